"""The documentation page of a planetary FMU (``documentation/index.html``; FMI 2 also ``_main.html``).

As the gearbox FMU's page (:mod:`gearfmu.fmu.gearbox_doc`, whose head, variables table, equations and
tail it uses): the variables with units and meaning, the model in brief with its equations
(docs/planetary.md), the degrees of freedom, meshes, springs and planetary stages of this drivetrain,
the parameters, the validation record, the scene and the platforms.
"""
from __future__ import annotations

from typing import List, Optional, Sequence

from ..planetary.model import PlanetaryModel
from .fmudoc import _e, _num
from .gearbox_doc import doc_equations, doc_head, doc_tail, doc_variables
from .planetary_interface import tables_folders

__all__ = ["planetary_documentation_html", "PLANETARY_EQUATIONS"]

#: the equations of docs/planetary.md "Model", by anchor: (title, lines)
PLANETARY_EQUATIONS = {
    "eq-state": ("State: kinematic reference and deviations (docs/planetary.md \"Model\")",
                 ["y = [psi, omega, q_1, dq_1, ..., q_{n-1}, dq_{n-1}]",
                  "rotation i: angle = g_i*psi + q_i, speed = g_i*omega + dq_i (g by the Willis equation)",
                  "translation i: position q_i, rate dq_i (in the frame turning with the carrier)"]),
    "eq-mesh": ("Mesh (Lin & Parker 1999 eq 1-2; its pair model, seed 003 eq 1-6)",
                ["x = sum_j a_j*q_j   (dte: the mesh deflection along the line of action)",
                 "theta = a_ref*psi + sum_j b_j*q_j + phase   (the table angle)",
                 "F = sum_k F_k(theta, omega, x, v)   (per-pair stiffness, meshing error, backlash, damping)",
                 "force on DOF j: -a_j*F;  c = 2*zeta*sqrt(k_mean*m_e) per pair"]),
    "eq-spring": ("Spring (shaft, bearing, support)", ["f = k*(r.q) + c*(r.dq),  force on DOF j: -r_j*f"]),
    "eq-frame": ("Rotating frame (translations on the carrier, Omega = g_c*omega)",
                 ["q_a'' += 2*Omega*q_b' + Omega'*q_b + Omega^2*(R0 + q_a)",
                  "q_b'' += -2*Omega*q_a' - Omega'*(R0 + q_a) + Omega^2*q_b"]),
    "eq-motion": ("Equations of motion", ["psi'' = Q_0/m_0,   q_i'' = Q_i/m_i - g_i*psi''"]),
    "eq-outputs": ("Outputs of a mesh and a stage",
                   ["mesh_force = F,  mesh_stiffness = sum of k over the pairs in contact",
                    "pair_force[k] = F_k,  load_sharing[k] = F_k/F (0 where F = 0)",
                    "load_sharing_factor[n] = N*F_sn/sum_m F_sm   (Kahraman 1994)"]),
    "eq-integration": ("Integration",
                       ["n = max(1, ceil(H/max_step*(1 - 1e-12))) RK4 substeps of h = H/n per communication step "
                        "H; rk4_kink and rk4_node also stop at the table nodes and contact changes of every mesh"]),
}
_EQ_OF = {"angle": "eq-state", "speed": "eq-state", "rate": "eq-state", "dte": "eq-mesh", "dte_rate": "eq-mesh",
          "mesh_force": "eq-outputs", "mesh_stiffness": "eq-outputs", "pair_force": "eq-outputs",
          "load_sharing": "eq-outputs", "load_sharing_factor": "eq-outputs", "force": "eq-spring",
          "motor_torque": "eq-motion", "load_torque": "eq-motion", "damping_ratio": "eq-mesh",
          "damping_model": "eq-mesh", "max_step": "eq-integration", "integrator": "eq-integration",
          "motor_speed_start": "eq-state", "motor_angle_start": "eq-state"}


def _eq(name: str) -> Optional[str]:
    base = name.rsplit(".", 1)[-1].split("[")[0]
    for key in (base, base.rsplit("_", 1)[-1]):
        if key in _EQ_OF:
            return _EQ_OF[key]
    return None


def planetary_documentation_html(*, model: PlanetaryModel, model_name: str, model_identifier: str, fmi_version: int,
                                 generation_tool: str, variables: Sequence, description: str, parameters: dict,
                                 scene_text: Optional[str], validation_record: Optional[dict], platforms_text: str,
                                 experiment: dict) -> bytes:
    """The page (UTF-8 bytes) of a planetary FMU of ``model`` with ``variables`` (expanded)."""
    out: List[str] = []
    w = out.append
    folders = tables_folders(model)
    doc_head(w, model_name=model_name, what="planetary", description=description, fmi_version=fmi_version,
             model_identifier=model_identifier, generation_tool=generation_tool, experiment=experiment,
             contents=[("variables", "Variables"), ("model", "Model"), ("drivetrain", "DOFs, meshes and springs"),
                       ("validation", "Validation record"), ("scene", "Scene"), ("platforms", "Platforms and sources")])
    doc_variables(w, variables, fmi_version, PLANETARY_EQUATIONS, _eq)
    w("<h2 id=\"model\">Model</h2><p>A drivetrain with planetary stages as one system of generalised degrees of "
      "freedom: the rotations of the shafts' bodies, of every planet and held member, and (translational "
      "stages) the translations of sun, ring, carrier and planets in the frame turning with the carrier.  Every "
      "mesh -- parallel stages, every sun-planet and ring-planet mesh -- is the multi-pair model on its own "
      "tables; shafts, bearings and supports are springs.  The inputs are held over a communication step; the "
      "state is integrated in C (gearfmu's docs/planetary.md is the full model).</p>")
    doc_equations(w, PLANETARY_EQUATIONS, parameters)
    w(f"<h2 id=\"drivetrain\">DOFs, meshes and springs</h2><p>Motor torque on <code>{_e(model.motor)}</code>"
      + (" (an input)" if model.motor_torque_input else " (no input)") + f", load torque on <code>{_e(model.load)}"
      "</code>" + (" (an input)." if model.load_torque_input else " (no input).") + "</p>")
    w("<table><tr><th>DOF</th><th>name</th><th>kind</th><th>mass or inertia</th><th>kinematic ratio g</th></tr>")
    for i, nm in enumerate(model.dof_names):
        w(f"<tr><td>{i}</td><td>{_e(nm)}</td><td>{_e(model.dof_kind[i])}</td><td>{_e(_num(float(model.mass[i])))}</td>"
          f"<td>{_e(_num(float(model.g[i])))}</td></tr>")
    w("</table><h3>Meshes</h3><table><tr><th>mesh</th><th>slots</th><th>angle points</th><th>torque per reference "
      "torque</th><th>damping (N*s/m), law</th><th>tables</th></tr>")
    for m, nm in enumerate(model.mesh_names):
        t = model.mesh_tables[m]
        w(f"<tr><td><code>{_e(nm)}</code></td><td>{t.slots}</td><td>{t.n_phi}</td>"
          f"<td>{_e(_num(float(model.mesh_torque_per_ref[m])))}</td><td>{_e(_num(float(model.mesh_c[m])))}, "
          f"{_e(model.mesh_damping_model[m])}</td><td>resources/{_e(folders[m])}/tables.bin</td></tr>")
    w("</table><h3>Springs</h3><table><tr><th>spring</th><th>kind</th><th>k</th><th>c</th></tr>")
    for s, nm in enumerate(model.spring_names):
        w(f"<tr><td><code>{_e(nm)}</code></td><td>{_e(model.spring_kind[s])}</td>"
          f"<td>{_e(_num(float(model.spring_k[s])))}</td><td>{_e(_num(float(model.spring_c[s])))}</td></tr>")
    w("</table><h3>Planetary stages</h3><table><tr><th>stage</th><th>model</th><th>planets</th><th>held</th>"
      "<th>teeth (sun, planet, ring)</th></tr>")
    for st in model.stages:
        w(f"<tr><td><code>{_e(st['name'])}</code></td><td>{_e(st['model'])}</td><td>{st['planets']}</td>"
          f"<td>{_e(st['held'])}</td><td>{_e(', '.join(str(z) for z in st.get('teeth', ())))}</td></tr>")
    w("</table>")
    doc_tail(w, solver_text="gearfmu's native planetary solver (numba, independent of the C kernel)",
             validation_record=validation_record, scene_text=scene_text,
             scene_note="Every parallel stage's pair scene: <code>resources/&lt;stage&gt;/scene.toml</code>.",
             platforms_text=platforms_text, fmi_version=fmi_version, unit_name=f"fmi{fmi_version}_planetary_all.c",
             model_identifier=model_identifier, what="planetary drivetrain")
    return "".join(out).encode("utf-8")
