"""The documentation page of a gearbox FMU (``documentation/index.html``; FMI 2 also ``_main.html``).

As the pair FMU's page (:mod:`gearfmu.fmu.fmudoc`: self-contained, every text from the build
HTML-escaped, no path of the build machine): the variables with units and meaning, the model in
brief with its equations (docs/gearbox.md), the bodies, stages and shafts of this gearbox, the
parameters, the validation record, the scene and the platforms.
"""
from __future__ import annotations

import json
from typing import List, Optional, Sequence

from ..gearbox.model import GearboxModel
from .fmudoc import _STYLE, _e, _num, _rows
from .modeldesc import FMI3_TYPES, fmi3_variables

__all__ = ["gearbox_documentation_html", "GEARBOX_EQUATIONS"]

#: the equations of docs/gearbox.md "Model", by anchor: (title, lines)
GEARBOX_EQUATIONS = {
    "eq-state": ("State: kinematic reference and deviations (docs/gearbox.md \"Model\")",
                 ["y = [psi, omega, u_1, du_1, ..., u_{n-1}, du_{n-1}],   u_i = theta_i - g_i*psi",
                  "g_0 = 1; a shaft keeps the ratio (g_b = g_a); a mesh multiplies it by Rb_p/Rb_q",
                  "angle_i = g_i*psi + u_i,   speed_i = g_i*omega + du_i"]),
    "eq-mesh": ("Mesh of a stage (its pair model, seed 003 eq 1-6)",
                ["x = Rb_p*u_p - Rb_q*u_q   (dte),   v = Rb_p*du_p - Rb_q*du_q   (dte_rate)",
                 "theta_p = g_p*psi + u_p,  omega_p = g_p*omega + du_p   (the table angle and speed)",
                 "F = sum_j F_j(theta_p, omega_p, x, v)   (per-pair stiffness, meshing error, backlash, damping)",
                 "torque on the pinion body -Rb_p*F, on the gear body +Rb_q*F",
                 "c = 2*zeta*sqrt(k_mean*m_e),  m_e = I1*I2/(I1*Rb2^2 + I2*Rb1^2) of the stage's two gears"]),
    "eq-shaft": ("Shaft (upstream body a, downstream body b)",
                 ["T = k*(u_a - u_b) + c*(du_a - du_b)   (torque, positive driving away from the motor)",
                  "torque on a: -T, on b: +T"]),
    "eq-motion": ("Equations of motion",
                  ["a_i = tau_i/I_i   (tau_i: motor torque on body 0, -load torque on the load body, shafts, meshes)",
                   "psi'' = a_0,   u_i'' = a_i - g_i*a_0"]),
    "eq-outputs": ("Outputs of a stage", ["mesh_force = F,  mesh_stiffness = sum of k_j over the pairs in contact",
                                          "pair_force[j] = F_j,  load_sharing[j] = F_j/F (0 where F = 0)"]),
    "eq-integration": ("Integration",
                       ["n = max(1, ceil(H/max_step*(1 - 1e-12))) RK4 substeps of h = H/n per communication step "
                        "H; rk4_kink and rk4_node also stop at the table nodes and contact changes of every mesh"]),
}
#: the equation of each variable, by its base name (the part, stage or shaft removed)
_EQ_OF = {"speed": "eq-state", "angle": "eq-state", "dte": "eq-mesh", "dte_rate": "eq-mesh", "mesh_force": "eq-mesh",
          "mesh_stiffness": "eq-outputs", "pair_force": "eq-outputs", "load_sharing": "eq-outputs",
          "torque": "eq-shaft", "motor_torque": "eq-motion", "load_torque": "eq-motion", "damping_ratio": "eq-mesh",
          "damping_model": "eq-mesh", "max_step": "eq-integration", "integrator": "eq-integration",
          "motor_speed_start": "eq-state", "motor_angle_start": "eq-state"}


def _eq(name: str) -> Optional[str]:
    base = name.split("[")[0].rsplit(".", 1)[-1]
    for key in (base, base.rsplit("_", 1)[-1] if base.endswith(("_speed", "_angle")) else base):
        if key in _EQ_OF:
            return _EQ_OF[key]
    if base.startswith(("pair_force_", "load_sharing_")):
        return "eq-outputs"
    return None


def gearbox_documentation_html(*, model: GearboxModel, model_name: str, model_identifier: str, fmi_version: int,
                               generation_tool: str, variables: Sequence, description: str, parameters: dict,
                               scene_text: Optional[str], validation_record: Optional[dict], platforms_text: str,
                               experiment: dict) -> bytes:
    """The page (UTF-8 bytes) of a gearbox FMU of ``model`` with ``variables`` (expanded)."""
    out: List[str] = []
    w = out.append
    w("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">")
    w(f"<title>{_e(model_name)}: gearfmu gearbox FMU</title><style>{_STYLE}</style></head><body>")
    w(f"<h1>{_e(model_name)}</h1><p>{_e(description)}</p>")
    w("<p>Contents: <a href=\"#variables\">Variables</a> &middot; <a href=\"#model\">Model</a> &middot; "
      "<a href=\"#gearbox\">Bodies, stages and shafts</a> &middot; <a href=\"#validation\">Validation record</a> "
      "&middot; <a href=\"#scene\">Scene</a> &middot; <a href=\"#platforms\">Platforms and sources</a></p>")
    # the interfaces as the model description's text names them (gearfmu.fmu.modeldesc)
    kinds = next(k for k in ("Co-Simulation and Model Exchange", "Model Exchange", "Co-Simulation")
                 if k in description or k == "Co-Simulation")
    w("<table>" + _rows([("FMI version", f"{fmi_version}.0 {kinds}"), ("modelIdentifier", model_identifier),
                         ("runtime", "standalone (C, no Python)"), ("generated by", generation_tool),
                         ("default experiment", f"start {_num(experiment.get('start'))} s, stop "
                                                f"{_num(experiment.get('stop'))} s, step {_num(experiment.get('step'))} s")])
      + "</table>")
    w("<h2 id=\"variables\">Variables</h2><table><tr><th>name</th><th>value reference</th><th>causality</th>"
      "<th>variability</th><th>type</th><th>unit</th><th>start</th><th>min</th><th>max</th><th>meaning</th>"
      "<th>equation</th></tr>")
    if fmi_version == 3:
        rows = [(v3.name + (f" [{v3.size}]" if v3.size else ""), v3.value_reference, v3.first,
                 v3.first.description.replace("slot 1", "slot i") if v3.size else v3.first.description,
                 FMI3_TYPES[v3.first.type]) for v3 in fmi3_variables(variables)]
    else:
        rows = [(v.name, v.value_reference, v, v.description, v.type) for v in variables]
    for name, vr, v, meaning, typ in rows:
        eq = _eq(v.name)
        link = f"<a href=\"#{eq}\">{_e(GEARBOX_EQUATIONS[eq][0].split(' (')[0])}</a>" if eq else ""
        w(f"<tr><td><code>{_e(name)}</code></td><td>{vr}</td><td>{_e(v.causality)}</td><td>{_e(v.variability)}</td>"
          f"<td>{_e(typ)}</td><td>{_e(v.unit or '')}</td><td>{_e(_num(v.start))}</td><td>{_e(_num(v.min))}</td>"
          f"<td>{_e(_num(v.max))}</td><td>{_e(meaning)}</td><td>{link}</td></tr>")
    if fmi_version == 3:
        w(f"<tr><td><code>time</code></td><td>{len(variables)}</td><td>independent</td><td>continuous</td>"
          "<td>Float64</td><td>s</td><td></td><td></td><td></td><td>Simulation time</td><td></td></tr>")
    w("</table>")

    w("<h2 id=\"model\">Model</h2><p>Rigid bodies (rotors, gears, merged by rigid couplings) joined by elastic "
      "shafts and gear meshes, one torsional system: every mesh is the multi-pair model of its stage (per-pair "
      "stiffness, meshing error and backlash from the stage's tables over its pinion angle, the pair FMU's force "
      "law), the state holds every body's deviation from its kinematic position.  The inputs are held over a "
      "communication step; the state is integrated in C (gearfmu's docs/gearbox.md is the full model).</p>")
    for anchor, (title, lines) in GEARBOX_EQUATIONS.items():
        w(f"<h3 id=\"{anchor}\">{_e(title)}</h3><pre>{_e(chr(10).join(lines))}</pre>")
    w("<h3>Parameters of this build</h3><table>" + _rows(sorted(
        (k, json.dumps(v, sort_keys=True) if isinstance(v, dict) else _num(v)) for k, v in parameters.items()))
      + "</table>")

    w("<h2 id=\"gearbox\">Bodies, stages and shafts</h2><h3>Bodies</h3><table><tr><th>body</th><th>parts</th>"
      "<th>inertia (kg*m^2)</th><th>kinematic ratio g (speed / motor speed)</th></tr>")
    for i in range(model.n_bodies):
        w(f"<tr><td>{i}</td><td>{_e(', '.join(model.bodies[i]))}</td><td>{_e(_num(float(model.inertia_kgm2[i])))}"
          f"</td><td>{_e(_num(float(model.g[i])))}</td></tr>")
    w("</table><p>The motor torque acts on body 0" + (" (an input)" if model.motor_torque_input else " (no input: "
      "a free end)") + f", the load torque on body {model.load_body}" + (" (an input)." if model.load_torque_input
                                                                          else " (no input: a free end)."))
    w("</p><h3>Stages</h3><table><tr><th>stage</th><th>teeth</th><th>slots</th><th>angle points</th>"
      "<th>torque axis (N*m)</th><th>base radii (m)</th><th>gear inertias (kg*m^2)</th><th>mean stiffness (N/m)</th>"
      "<th>bodies (pinion, gear)</th><th>damping ratio, law</th><th>tables</th></tr>")
    for m, mesh in enumerate(model.meshes):
        t = mesh.tables
        p, q = model.mesh_bodies[m]
        w(f"<tr><td><code>{_e(mesh.name)}</code></td><td>{t.teeth_pinion} / {_e(getattr(t, 'teeth_gear', ''))}</td>"
          f"<td>{t.slots}</td><td>{t.n_phi}</td><td>{_e(' '.join(_num(float(x)) for x in t.torque_Nm))}</td>"
          f"<td>{_e(_num(float(t.base_radius_pinion_m)))}, {_e(_num(float(t.base_radius_gear_m)))}</td>"
          f"<td>{_e(_num(float(t.inertia_pinion_kgm2)))}, {_e(_num(float(t.inertia_gear_kgm2)))}</td>"
          f"<td>{_e(_num(float(t.k_mean_N_per_m)))}</td><td>{p}, {q}</td>"
          f"<td>{_e(_num(mesh.damping_ratio))}, {_e(mesh.damping_model)}</td>"
          f"<td>resources/{_e(mesh.name)}/tables.bin</td></tr>")
    w("</table><h3>Elastic shafts</h3>")
    if model.shafts:
        w("<table><tr><th>shaft</th><th>ends (parts)</th><th>bodies (upstream, downstream)</th>"
          "<th>stiffness (N*m/rad)</th><th>damping (N*m*s/rad)</th></tr>")
        for s, sh in enumerate(model.shafts):
            a, b = model.shaft_bodies[s]
            w(f"<tr><td><code>{_e(sh.name)}</code></td><td>{_e(sh.a)}, {_e(sh.b)}</td><td>{a}, {b}</td>"
              f"<td>{_e(_num(float(model.shaft_k_Nm_per_rad[s])))}</td>"
              f"<td>{_e(_num(float(model.shaft_c_Nms_per_rad[s])))}</td></tr>")
        w("</table>")
    else:
        w("<p>None (the stages' gears sit on the motor and load bodies, or rigid couplings join them).</p>")

    w("<h2 id=\"validation\">Validation record</h2>")
    if validation_record:
        ref = validation_record.get("reference", {})
        w("<p>The FMU carries <code>resources/validation/</code>: a reference result of gearfmu's native gearbox "
          "solver (numba, independent of the C kernel) over the default experiment, with the versions and "
          "checksums of this build.</p><table>" + _rows([
              ("reference file", "resources/validation/" + str(ref.get("file"))), ("solver", ref.get("solver")),
              ("criterion", ref.get("criterion")), ("rows", ref.get("rows")),
              ("versions", json.dumps(validation_record.get("versions"), sort_keys=True))]) + "</table>")
    else:
        w("<p>This FMU was built without a validation record.</p>")
    w("<h2 id=\"scene\">Scene</h2>")
    w(f"<pre>{_e(scene_text)}</pre><p>Every stage's pair scene: <code>resources/&lt;stage&gt;/scene.toml</code>.</p>"
      if scene_text else "<p>Built from a gearbox in code, without a scene file.</p>")
    w("<h2 id=\"platforms\">Platforms and sources</h2>" f"<pre>{_e(platforms_text)}</pre>")
    w(f"<p>Source code: <code>sources/fmi{fmi_version}_gearbox_all.c</code> is the one file to compile (it includes "
      f"the others; every function but the fmi{fmi_version}* ones is static).  Static linking: define "
      f"<code>FMI{fmi_version}_FUNCTION_PREFIX={_e(model_identifier)}_</code> and use the FMI standard's headers "
      "(the importer's own; sources/BUILD.txt).</p>")
    w("</body></html>\n")
    return "".join(out).encode("utf-8")
