"""The documentation every gearfmu FMU carries: one self-contained HTML page.

FMI 3.0 (section 2.5.1.1) and FMI 2.0.1 and later (section 2.3) name ``documentation/index.html``
the entry point of an FMU's documentation; FMI 2.0 (2014) named it ``documentation/_main.html``.
An FMI 2 FMU carries both (the same page), an FMI 3 FMU ``index.html``.

The page is generated at build time from the interface spec (modeldescription/variables.toml, as
expanded for the FMU) and the build's own data: the variables with units and meaning, the model in
brief with its equations (each output links to the equation that defines it), the scene, the
tables and their provenance, the verified envelope and accuracy, the validation record and the
platforms.  Self-contained: no script, no style sheet, image or font from elsewhere, no link out of
the page; every text taken from the build is HTML-escaped.  No path of the build machine appears
(the builder checks every file of the FMU for one, :func:`build_machine_paths`).
"""
from __future__ import annotations

import html
import json
import os
import re
import sys
import tempfile
from pathlib import Path
from typing import Iterable, List, Optional, Sequence

from .modeldesc import FMI3_TYPES, fmi3_variables

__all__ = ["DOC_FILES", "documentation_html", "build_machine_paths"]


def DOC_FILES(fmi_version: int) -> tuple:
    """The documentation entry points of an FMU of ``fmi_version``."""
    return ("documentation/index.html",) if fmi_version == 3 else ("documentation/index.html",
                                                                   "documentation/_main.html")


#: the equations of docs/model.md, by anchor: (title, lines)
EQUATIONS = {
    "eq-state": ("State and derived angles (docs/model.md \"Model\")",
                 ["y = [theta1, omega1, x, v]",
                  "x = theta1*Rb1 - theta2*Rb2        dynamic transmission error (m)",
                  "theta2 = (theta1*Rb1 - x)/Rb2,  omega2 = (omega1*Rb1 - v)/Rb2"]),
    "eq-motion": ("Equations of motion (seed 003 eq. 1-2)",
                  ["dtheta1/dt = omega1",
                   "domega1/dt = (T1 - Rb1*F)/I1",
                   "dx/dt = v",
                   "dv/dt = Rb1*(T1 - Rb1*F)/I1 - Rb2*(Rb2*F - T2)/I2",
                   "F = sum over the P slots of F_j        mesh force (N)"]),
    "eq-pair": ("Force of tooth pair j (seed 003 eq. 3-6)",
                ["d = x - e_j(theta1)        deflection against the meshing error",
                 "fc = k_j(theta1)*(d - b_j) if d > b_j (drive flank), k_j*(d + b_j) if d < -b_j (back flank), else 0",
                 "fd = c*(v - de_j/dt),  c = 2*zeta*sqrt(k_mean*m_e),  m_e = I1*I2/(I1*Rb2^2 + I2*Rb1^2)",
                 "elastobacklash: F_j = max(0, fc + min(fc, fd)) on the drive flank, min(0, fc + max(fc, fd)) "
                 "on the back flank",
                 "contact_zone:   F_j = fc + fd where k_j > 0, else 0"]),
    "eq-outputs": ("Outputs", ["mesh_force = F,  mesh_stiffness = sum of k_j over the pairs in contact",
                               "pair_force[j] = F_j,  load_sharing[j] = F_j/F (0 where F = 0)"]),
    "eq-integration": ("Integration",
                       ["n = max(1, ceil(H/max_step*(1 - 1e-12))) RK4 substeps of h = H/n per communication "
                        "step H; the event integrators (rk4_kink, rk4_node, rk4_seg) also stop at table "
                        "nodes and contact changes"]),
}
#: the equation that defines each variable (the others are inputs or parameters of eq-motion/eq-pair)
VARIABLE_EQUATION = {"pinion_speed": "eq-motion", "gear_speed": "eq-state", "pinion_angle": "eq-motion",
                     "gear_angle": "eq-state", "dte": "eq-state", "mesh_force": "eq-motion",
                     "mesh_stiffness": "eq-outputs", "pair_force": "eq-pair", "load_sharing": "eq-outputs",
                     "pinion_torque": "eq-motion", "gear_torque": "eq-motion", "damping_ratio": "eq-pair",
                     "damping_model": "eq-pair", "max_step": "eq-integration", "integrator": "eq-integration",
                     "pinion_speed_start": "eq-state", "pinion_angle_start": "eq-state"}

_STYLE = ("body{font-family:sans-serif;max-width:72em;margin:1em auto;padding:0 1em;line-height:1.4}"
          "table{border-collapse:collapse}td,th{border:1px solid #bbb;padding:2px 6px;text-align:left;"
          "vertical-align:top}th{background:#eee}pre{background:#f6f6f6;padding:6px;overflow-x:auto}"
          "code{background:#f6f6f6}")


def _e(x) -> str:
    return html.escape("" if x is None else str(x), quote=True)


def _num(x) -> str:
    if x is None:
        return ""
    if isinstance(x, float):
        return repr(x)
    return str(x)


def _rows(pairs) -> str:
    return "".join(f"<tr><th>{_e(k)}</th><td>{_e(v)}</td></tr>" for k, v in pairs)


def _base(name: str) -> str:
    return re.sub(r"(\[\d+\]|_\d+)$", "", name)


def documentation_html(*, model_name: str, model_identifier: str, fmi_version: int, runtime: str,
                       generation_tool: str, variables: Sequence, description: str, tables,
                       parameters: dict, envelope: Optional[dict], scene_text: Optional[str],
                       validation_record: Optional[dict], platforms_text: str,
                       experiment: dict, interfaces: Sequence[str] = ("cs",)) -> bytes:
    """The page (UTF-8 bytes).  ``variables``: the FMU's variables (gearfmu.fmu.modeldesc.Variable,
    after expansion, per-slot elements included), ``tables``: its MeshTables, ``parameters``: the
    build's parameters (SI units), ``envelope``: the envelope record, ``validation_record``: the
    parsed resources/validation/record.json (None: the FMU has none), ``experiment``: start/stop
    time and step (s), ``interfaces``: "cs" and/or "me" (Co-Simulation, Model Exchange)."""
    kinds = " and ".join(n for k, n in (("cs", "Co-Simulation"), ("me", "Model Exchange")) if k in interfaces)
    out: List[str] = []
    w = out.append
    w("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">")
    w(f"<title>{_e(model_name)}: gearfmu gear-pair FMU</title><style>{_STYLE}</style></head><body>")
    w(f"<h1>{_e(model_name)}</h1>")
    w(f"<p>{_e(description)}</p>")
    w("<p>Contents: <a href=\"#variables\">Variables</a> &middot; <a href=\"#model\">Model</a> &middot; "
      "<a href=\"#tables\">Tables</a> &middot; <a href=\"#envelope\">Verified envelope and accuracy</a> &middot; "
      "<a href=\"#validation\">Validation record</a> &middot; <a href=\"#scene\">Scene</a> &middot; "
      "<a href=\"#platforms\">Platforms and sources</a></p>")
    w("<table>" + _rows([("FMI version", f"{fmi_version}.0 {kinds}"), ("modelIdentifier", model_identifier),
                         ("runtime", runtime), ("generated by", generation_tool),
                         ("default experiment", f"start {_num(experiment.get('start'))} s, stop "
                                                f"{_num(experiment.get('stop'))} s, step {_num(experiment.get('step'))} s")])
      + "</table>")

    w("<h2 id=\"variables\">Variables</h2><table><tr><th>name</th><th>value reference</th><th>causality</th>"
      "<th>variability</th><th>type</th><th>unit</th><th>start</th><th>min</th><th>max</th><th>meaning</th>"
      "<th>equation</th></tr>")
    if fmi_version == 3:  # the FMI 3 variables: arrays of the per-slot elements (modeldesc.fmi3_variables)
        rows = [(f"{v3.name}" + (f" [{v3.size}]" if v3.size else ""), v3.value_reference, v3.first,
                 v3.first.description.replace("slot 1", "slot i") if v3.size else v3.first.description,
                 FMI3_TYPES[v3.first.type]) for v3 in fmi3_variables(variables)]
    else:
        rows = [(v.name, v.value_reference, v, v.description, v.type) for v in variables]
    for name, vr, v, meaning, typ in rows:
        eq = VARIABLE_EQUATION.get(_base(v.name))
        link = f"<a href=\"#{eq}\">{_e(EQUATIONS[eq][0].split(' (')[0])}</a>" if eq else ""
        w(f"<tr><td><code>{_e(name)}</code></td><td>{vr}</td><td>{_e(v.causality)}</td>"
          f"<td>{_e(v.variability)}</td><td>{_e(typ)}</td><td>{_e(v.unit or '')}</td><td>{_e(_num(v.start))}</td>"
          f"<td>{_e(_num(v.min))}</td><td>{_e(_num(v.max))}</td><td>{_e(meaning)}</td><td>{link}</td></tr>")
    if fmi_version == 3:
        w(f"<tr><td><code>time</code></td><td>{len(variables)}</td><td>independent</td><td>continuous</td>"
          "<td>Float64</td><td>s</td><td></td><td></td><td></td><td>Simulation time</td><td></td></tr>")
    w("</table>")
    if fmi_version == 3:
        w("<p>FMI 3: the per-slot elements are " + ("the arrays <code>pair_force</code> and <code>load_sharing</code> "
          "(value reference of element 1, one get brings all P values)" if any(v.name.endswith("[1]") for v in variables)
          else "scalars <code>pair_force_i</code>, <code>load_sharing_i</code>") +
          "; the independent variable <code>time</code> has value reference " + str(len(variables)) + ".</p>")

    w("<h2 id=\"model\">Model</h2><p>A two-inertia torsional spur or helical gear pair: pinion and gear on the "
      "line of action, coupled by P tooth-pair slots whose mesh stiffness k_j, meshing error e_j and half "
      "backlash b_j come from precomputed tables over the pinion angle (and the pinion torque, and the "
      "temperature where the tables have those axes).  The inputs are the two torques; the state is integrated "
      "with fixed-step RK4 in C (gearfmu's docs/model.md is the full contract; the tables' physics is in "
      "docs/references.md).</p>")
    for anchor, (title, lines) in EQUATIONS.items():
        w(f"<h3 id=\"{anchor}\">{_e(title)}</h3><pre>{_e(chr(10).join(lines))}</pre>")
    w("<h3>Parameters of this build</h3><table>" + _rows(sorted((k, _num(v)) for k, v in parameters.items()))
      + "</table>")

    w("<h2 id=\"tables\">Tables</h2><table>" + _rows([
        ("tooth-pair slots P", tables.slots), ("angle points", tables.n_phi), ("torque rows", tables.n_torque),
        ("torque axis (N*m)", " ".join(_num(float(x)) for x in tables.torque_Nm)),
        ("temperature axis (degC)", " ".join(_num(float(x)) for x in tables.temperature_C)
         if tables.has_temperature_axis else "none"),
        ("base radii Rb1, Rb2 (m)", f"{_num(tables.base_radius_pinion_m)}, {_num(tables.base_radius_gear_m)}"),
        ("inertias I1, I2 (kg*m^2)", f"{_num(tables.inertia_pinion_kgm2)}, {_num(tables.inertia_gear_kgm2)}"),
        ("mean mesh stiffness (N/m)", _num(tables.k_mean_N_per_m)),
        ("teeth", f"{tables.teeth_pinion} / {getattr(tables, 'teeth_gear', '')}")]) + "</table>")
    w("<p>Provenance of the tables (how they were computed):</p>"
      f"<pre>{_e(json.dumps(tables.provenance, indent=1, sort_keys=True, default=str))}</pre>")

    w("<h2 id=\"envelope\">Verified envelope and accuracy</h2>")
    if envelope:
        keys = ("status", "source", "pinion_torque_range_Nm", "pinion_speed_range_rad_s", "pinion_speed_range_rpm",
                "temperature_range_C", "speed_margin_rel", "dte_target_rel", "mesh_force_target_rel",
                "within_target", "worst_dte_rel", "worst_mesh_force_rel", "worst_at", "error_definition", "outside")
        w("<table>" + _rows([(k, json.dumps(envelope[k], default=str)) for k in keys if k in envelope]) + "</table>")
    else:
        w("<p>No envelope record.</p>")

    w("<h2 id=\"validation\">Validation record</h2>")
    if validation_record:
        ref = validation_record.get("reference", {})
        w("<p>The FMU carries <code>resources/validation/</code>: a reference result of gearfmu's native solver "
          "(independent of the C kernel) over the default experiment, the versions and checksums of this "
          "build.</p><table>" + _rows([
              ("reference file", "resources/validation/" + str(ref.get("file"))),
              ("solver", ref.get("solver")), ("criterion", ref.get("criterion")),
              ("rows", ref.get("rows")), ("tables.bin SHA-256", validation_record.get("tables", {}).get("tables_bin_sha256")),
              ("versions", json.dumps(validation_record.get("versions"), sort_keys=True))]) + "</table>")
    else:
        w("<p>This FMU was built without a validation record.</p>")

    w("<h2 id=\"scene\">Scene</h2>")
    w(f"<pre>{_e(scene_text)}</pre>" if scene_text else "<p>Built from tables without a scene file.</p>")

    w("<h2 id=\"platforms\">Platforms and sources</h2>" f"<pre>{_e(platforms_text)}</pre>")
    if runtime == "standalone":
        w(f"<p>Source code: <code>sources/fmi{fmi_version}_all.c</code> is the one file to compile (it includes the "
          f"others; every function but the fmi{fmi_version}* ones is static).  Static linking: define "
          f"<code>FMI{fmi_version}_FUNCTION_PREFIX={_e(model_identifier)}_</code> and use the FMI standard's "
          "headers (the importer's own; sources/BUILD.txt).</p>")
    w("</body></html>\n")
    return "".join(out).encode("utf-8")


def build_machine_paths(root: Path, extra: Iterable[str] = ()) -> List[str]:
    """Every file under ``root`` (an FMU being assembled) that holds a path of the build machine:
    the home folder, the temporary folder, the Python installation, the current folder, the
    package's own folder and ``extra``; returns "file: path" lines (empty: none)."""
    marks = {os.path.expanduser("~"), tempfile.gettempdir(), sys.prefix, sys.base_prefix, os.getcwd(),
             str(Path(__file__).resolve().parents[2]), *extra}
    marks = sorted({m for m in marks if m and len(m) > 4 and m != os.sep}, key=len, reverse=True)
    found = []
    for p in sorted(Path(root).rglob("*")):
        if not p.is_file():
            continue
        data = p.read_bytes()
        for m in marks:
            if m.encode() in data:
                found.append(f"{p.relative_to(root).as_posix()}: {m}")
                break
    return found
