"""Build the planetary FMU: one FMI 2.0 (or 3.0) Co-Simulation and/or Model Exchange FMU in C for a
drivetrain with planetary stages (docs/planetary.md "The planetary FMU").

The same FMI layers and plumbing as the pair and gearbox FMUs (``fmi2_gear.c`` / ``fmi3_gear.c``,
``fmi_common.c``) over the planetary model (``standalone/planetary_model.c``, on the multi-mesh
behaviour ``standalone/gf_meshes.c`` it shares with the gearbox model) and the planetary kernel
(``kernel/pl_kernel.c``, ``kernel/pl_static.c``: the C port of gearfmu.planetary.kernels, every mesh on
the pair kernel's own pieces), compiled from one translation unit (``fmi2_planetary_all.c`` /
``fmi3_planetary_all.c``) for the platforms of :mod:`gearfmu.fmu.crossbuild` and packaged as the
gearbox FMU is (:mod:`gearfmu.fmu.multimesh_build`).  The interface comes from
``modeldescription/planetary.toml`` (:mod:`gearfmu.fmu.planetary_interface`): the outputs are the native
planetary solver's columns.

FMU layout::

    modelDescription.xml                   needsExecutionTool=false, FMU state, SourceFiles
    binaries/<folder>/<id>.<so|dll|dylib>    linux64, aarch64-linux, win64, darwin64 (+ aarch64-darwin)
    sources/                               fmi2_planetary_all.c (the file to compile) and the files it includes
    documentation/index.html, platforms.txt
    resources/<tables>/tables.json, .bin    the meshes' tables (the pair FMU's format, docs/tables.md): one
                                           folder per distinct tables file (the sun-planet meshes of a stage
                                           with identical tables share one)
    resources/<stage>/scene.toml           every parallel stage's pair scene (from a drivetrain scene)
    resources/gearfmu_planetary.txt        what planetary_model.c reads (:func:`config_text`)
    resources/provenance.json, scene.toml
    resources/validation/                  record.json and reference_result.csv of the native planetary solver
"""
from __future__ import annotations

import csv
import dataclasses
import datetime
import hashlib
import io
import json
import math
import platform
import shutil
import uuid
from pathlib import Path
from typing import Dict, Optional, Sequence

import numpy as np

from ..common.cache import cache_dir, load_entry, store_entry
from ..common.progress import ticking
from ..common.settings import GearboxRunSettings, checked
from ..common.vocabulary import (DEFAULT_FMI3_OUTPUTS, DEFAULT_FMU_INTERFACE, DEFAULT_ME_NODE_EVENTS, FMI3_OUTPUTS,
                                  FMU_INTERFACES, ME_NODE_EVENTS)
from ..planetary.model import SPRING_DOFS, PlanetaryModel
from ..planetary.native import resolve_settings, simulate as simulate_planetary
from .build_steps import KERNEL_DIR, KERNEL_HEADERS, KERNEL_SOURCES, FmuBuildError, check_output_arguments, \
    variable_table_lines
from .gearbox_build import EVENT_MAX_SLOTS, GEARBOX_HEADERS, LAYERS, STANDALONE_DIR
from .gearbox_interface import apply_starts
from .gearbox_validation import record_files
from .modeldesc import SpecError
from .multimesh_build import FmuPackage, assemble_fmu, check_platforms, interface_options
from .planetary_doc import planetary_documentation_html
from .planetary_interface import damping_items, load_planetary_spec, planetary_variables, tables_folders
from .planetary_kernel import kernel_data
from .standalone_build import FMI_VERSIONS, INTERFACE_ELEMENTS, scalar_names
from .validation import REFERENCE_CACHE, _SOLVER_PACKAGES, _sources_sha256, _versions

__all__ = ["build_planetary_fmu", "planetary_settings", "start_values", "config_text", "variables_of_fmu",
           "planetary_file_sources", "copy_planetary_sources", "native_run", "CONFIG_FILE", "PLANETARY_UNITS"]

#: the one file a build of the planetary FMU of FMI 2 / FMI 3 compiles
PLANETARY_UNITS = {2: STANDALONE_DIR / "fmi2_planetary_all.c", 3: STANDALONE_DIR / "fmi3_planetary_all.c"}
#: the plumbing, the planetary model, the reading of resources, the multi-mesh behaviour and the planetary
#: kernel, in compile order
PLANETARY_SOURCES = (STANDALONE_DIR / "fmi_common.c", STANDALONE_DIR / "planetary_model.c",
                     STANDALONE_DIR / "gf_resources.c", STANDALONE_DIR / "gf_meshes.c", KERNEL_DIR / "pl_kernel.c",
                     KERNEL_DIR / "pl_static.c")
PLANETARY_HEADERS = (*(h for h in GEARBOX_HEADERS if h.name not in ("gearbox_model.h", "gbkernel.h")),
                     STANDALONE_DIR / "planetary_model.h", KERNEL_DIR / "plkernel.h", KERNEL_DIR / "pl_internal.h")
CONFIG_FILE = "gearfmu_planetary.txt"
CONFIG_FORMAT = "gearfmu-planetary"
CONFIG_VERSION = 1
DAMPING_CODES = {"elastobacklash": 0, "contact_zone": 1}


def planetary_file_sources(fmi_version: int = 2) -> tuple:
    """Every C file of the planetary binary in compile order (the unit includes them so)."""
    return (LAYERS[fmi_version].name, *(p.name for p in PLANETARY_SOURCES), *(p.name for p in KERNEL_SOURCES))


def copy_planetary_sources(dest_dir, fmi_version: int = 2) -> Path:
    """The unit of ``fmi_version``, the files it includes and their headers into ``dest_dir`` (not the
    FMI headers: the importer's, as the standard says)."""
    dest = Path(dest_dir)
    dest.mkdir(parents=True, exist_ok=True)
    for src in (PLANETARY_UNITS[fmi_version], LAYERS[fmi_version], *PLANETARY_SOURCES, *PLANETARY_HEADERS,
                *KERNEL_SOURCES, *KERNEL_HEADERS):
        shutil.copy2(src, dest / src.name)
    return dest


# ----------------------------------------------------------------- arguments
def planetary_settings(model: PlanetaryModel, settings: Optional[GearboxRunSettings] = None,
                       **changes) -> GearboxRunSettings:
    """The run settings of a planetary FMU, as :func:`gearfmu.fmu.gearbox_build.gearbox_settings` for a
    gearbox: ``settings`` with ``changes`` (checked; FmuBuildError naming the field), the load's start
    torque (None: the balancing T_motor/g_load), the output interval and the largest internal step
    resolved (:func:`gearfmu.planetary.native.resolve_settings`).  An integrator other than rk4 handles at
    most :data:`gearfmu.fmu.gearbox_build.EVENT_MAX_SLOTS` slots per mesh."""
    if not isinstance(model, PlanetaryModel):
        raise FmuBuildError(f"model: expected gearfmu.planetary.model.PlanetaryModel, got {type(model).__name__}")
    s = checked(settings, FmuBuildError, GearboxRunSettings, **changes)
    if s.load_torque_start_Nm is None:
        s = dataclasses.replace(s, load_torque_start_Nm=s.motor_torque_start_Nm / model.load_ratio)
    s = resolve_settings(model, s, reference_torque_Nm=model.reference_torque_Nm(s.motor_torque_start_Nm,
                                                                                 s.load_torque_start_Nm))
    for nm, t in zip(model.mesh_names, model.mesh_tables):
        if s.integrator != "rk4" and t.slots > EVENT_MAX_SLOTS:
            raise FmuBuildError(f"integrator: {s.integrator!r} handles at most {EVENT_MAX_SLOTS} slots, mesh "
                                    f"{nm!r} has {t.slots}")
    return s


def fmu_parameters(model: PlanetaryModel, s: GearboxRunSettings) -> dict:
    """The parameters the provenance and the validation record name (the integrator by its code)."""
    return {"motor_torque_start_Nm": s.motor_torque_start_Nm, "load_torque_start_Nm": s.load_torque_start_Nm,
            "motor_speed_start_rad_s": s.motor_speed_start_rad_s, "motor_angle_start_rad": s.motor_angle_start_rad,
            "max_step_s": s.max_step_s, "integrator": s.integrator_code,
            "stages": {nm: {"damping_ratio": z, "damping_model": law} for nm, _, z, law in damping_items(model)}}


def start_values(model: PlanetaryModel, s: GearboxRunSettings) -> Dict[str, float]:
    """The start value of every parameter and input of the interface (by its FMU name)."""
    starts = {"motor_speed_start": s.motor_speed_start_rad_s, "motor_angle_start": s.motor_angle_start_rad,
              "max_step": s.max_step_s, "integrator": s.integrator_code}
    if model.motor_torque_input:
        starts["motor_torque"] = s.motor_torque_start_Nm
    if model.load_torque_input:
        starts["load_torque"] = s.load_torque_start_Nm
    for nm, _, z, law in damping_items(model):
        starts[f"{nm}.damping_ratio"] = z
        starts[f"{nm}.damping_model"] = DAMPING_CODES[law]
    for d in model.drives:   # a driven member: the model's drive speed (the scene's driven_speed_rpm)
        starts[f"{d['port']}_speed_input"] = d["speed_rad_s"]
    return starts


# ---------------------------------------------------------------- resources
def _hexf(v) -> str:
    return float(v).hex()


def me_nominals(model: PlanetaryModel, settings: GearboxRunSettings) -> list:
    """Nominal values of the Model Exchange states [psi, omega, q_1, q_1', ...]: psi 1 rad, omega the start
    speed (at least 1 rad/s); a translation the smallest mesh scale (the largest of its static deflection,
    backlash and meshing-error range, at least 1e-9 m), a rotation that over the largest base radius; every
    rate that times the highest mesh frequency sqrt(k_mean/m_e)."""
    t_ref = model.reference_torque_Nm(settings.motor_torque_start_Nm, settings.load_torque_start_Nm)
    x, rb, wn = math.inf, 0.0, 0.0
    for m, t in enumerate(model.mesh_tables):
        tq = abs(float(model.mesh_torque_per_ref[m]) * t_ref)
        e = np.asarray(t.e_m, float)
        x = min(x, max(tq / (t.base_radius_pinion_m * t.k_mean_N_per_m), float(np.max(np.abs(t.backlash_half_m))),
                       float(np.max(e) - np.min(e)), 1e-9))
        rb = max(rb, t.base_radius_pinion_m, t.base_radius_gear_m)
        wn = max(wn, math.sqrt(t.k_mean_N_per_m / float(model.mesh_me[m])))
    out = [1.0, max(abs(settings.motor_speed_start_rad_s), 1.0)]
    for i in range(1, model.n_dof):
        q = x / rb if model.dof_kind[i] == "rot" else x
        out += [q, q * wn]
    return out


def config_text(model: PlanetaryModel, variables, mesh_bytes, *, guid: str, model_identifier: str,
                interface: str = "cs", node_events: str = "none", nominals: Optional[Sequence[float]] = None) -> str:
    """The ``gearfmu_planetary.txt`` planetary_model.c reads (format gearfmu-planetary, version 1): the
    degrees of freedom (1/m and the kinematic ratio as C99 hexadecimal floats, exact), the springs, the
    rotating frames, every mesh (its tables file, size, SHA-256, dimensions, byte offsets and scalars as the
    gearbox's stages; its x map, table-angle map with psi coefficient and phase, static torque per reference
    torque, the value references of its stage's damping parameters), the load-sharing groups, the value
    references the model drives, Model Exchange and the variable table.  ``mesh_bytes``: (tables.json,
    tables.bin) bytes of every mesh."""
    vr = {v.name: v.value_reference for v in variables}
    kd = kernel_data(model)   # the numba solver's own arrays (gearfmu.fmu.planetary_kernel)
    lines = [
        "# gearfmu planetary FMU configuration (written by gearfmu.fmu.planetary_build; read by planetary_model.c)",
        f"# floats are C99 hexadecimal literals (exact); dof = index|1/m|g|name; spring = index|count|{SPRING_DOFS} DOFs|"
        f"{SPRING_DOFS} coefs|k|c|name; frame = index|radial DOF|tangential DOF|R0|frame ratio; frame_drive = frame|"
        "drive DOF|drive ratio; mesh.<i>.x = n|DOFs|coefs; mesh.<i>.angle = "
        "n|DOFs|coefs|psi coefficient|phase; group = index|count|sun-planet meshes; drive = index|DOF|value "
        "reference of its speed input|n|rigid motion of the n DOFs",
        f"format={CONFIG_FORMAT}", f"version={CONFIG_VERSION}", f"model_identifier={model_identifier}",
        f"guid={guid}", f"dofs={kd.n_dof}", f"load_dof={kd.load_dof}",
        f"motor_torque_input={int(kd.motor_input)}", f"load_torque_input={int(kd.load_input)}",
    ]
    lines += [f"dof={i}|{_hexf(kd.inv_m[i])}|{_hexf(kd.g[i])}|{model.dof_names[i]}" for i in range(kd.n_dof)]
    lines.append(f"springs={len(kd.springs)}")
    for s, (dofs, coefs, k, c) in enumerate(kd.springs):
        pad = SPRING_DOFS - len(dofs)
        lines.append(f"spring={s}|{len(dofs)}|" + "|".join(str(d) for d in (*dofs, *[-1] * pad)) + "|"
                     + "|".join(_hexf(x) for x in (*coefs, *[0.0] * pad)) + f"|{_hexf(k)}|{_hexf(c)}|"
                     + model.spring_names[s])
    lines.append(f"frames={len(kd.frames)}")
    lines += [f"frame={f}|{a}|{b}|{_hexf(r0)}|{_hexf(ratio)}" for f, (a, b, r0, ratio) in enumerate(kd.frames)]
    lines += [f"frame_drive={f}|{d}|{_hexf(h)}" for f, d, h in kd.frame_drives]
    stage_of = {m: nm for nm, ms, _, _ in damping_items(model) for m in ms}
    folders = tables_folders(model)
    lines.append(f"meshes={len(kd.meshes)}")
    for m, md in enumerate(kd.meshes):
        t = md.tables
        meta_bytes, bin_bytes = mesh_bytes[m]
        meta = json.loads(meta_bytes.decode("utf-8"))
        sc = meta["scalars"]
        st = f"mesh.{m}."
        lines += [f"{st}name={md.name}", f"{st}tables={folders[m]}/tables.bin", f"{st}tables_bytes={len(bin_bytes)}",
                  f"{st}tables_sha256={hashlib.sha256(bin_bytes).hexdigest()}", f"{st}slots={t.slots}",
                  f"{st}n_phi={t.n_phi}", f"{st}n_torque={t.n_torque}"]
        lines += [f"{st}offset.{k}={int(meta['arrays'][k]['offset'])}"
                  for k in ("torque_Nm", "k_N_per_m", "e_m", "backlash_half_m")]
        lines += [f"{st}{k}={_hexf(sc[k])}" for k in ("phi_period_rad", "base_radius_pinion_m", "base_radius_gear_m",
                                                      "inertia_pinion_kgm2", "inertia_gear_kgm2", "k_mean_N_per_m")]
        if meta.get("engagement") is not None:
            lines += [f"{st}mesh_period_rad={_hexf(sc['mesh_period_rad'])}",
                      f"{st}engagement_in_rad={_hexf(meta['engagement']['in_rad'])}",
                      f"{st}engagement_out_rad={_hexf(meta['engagement']['out_rad'])}"]
        lines.append(f"{st}x={len(md.x_dof)}|" + "|".join([str(d) for d in md.x_dof] + [_hexf(c) for c in md.x_coef]))
        lines.append(f"{st}angle={len(md.a_dof)}|" + "|".join([str(d) for d in md.a_dof] + [_hexf(c) for c in md.a_coef]
                                                             + [_hexf(md.a_ref), _hexf(md.phase_rad)]))
        lines.append(f"{st}torque_per_ref={_hexf(md.torque_per_ref)}")
        lines += [f"{st}vr.damping_ratio={vr[f'{stage_of[m]}.damping_ratio']}",
                  f"{st}vr.damping_model={vr[f'{stage_of[m]}.damping_model']}"]
    lines.append(f"groups={len(kd.groups)}")
    lines += [f"group={g}|{len(ms)}|" + "|".join(str(m) for m in ms) for g, ms in enumerate(kd.groups)]
    lines.append(f"drives={len(kd.drives)}")
    lines += [f"drive={j}|{dof}|{vr[model.drives[j]['port'] + '_speed_input']}|{len(mode)}|"
              + "|".join(_hexf(x) for x in mode) for j, (dof, mode) in enumerate(kd.drives)]
    for key in ("motor_torque", "load_torque", "motor_speed_start", "motor_angle_start", "max_step", "integrator"):
        lines.append(f"vr.{key}={vr.get(key, -1)}")
    elements = INTERFACE_ELEMENTS[interface]
    lines.append("state_outputs=1")   # the kernel state as locals after the outputs, Model Exchange or not
    lines.append("interfaces=" + ",".join(e for e in ("cs", "me") if e in elements))
    if "me" in elements:
        lines.append(f"me.node_events={ME_NODE_EVENTS.index(node_events)}")
        lines.append(f"me.event_indicators={sum(v.event_indicator for v in variables)}")
        lines.append("me.nominals=" + "|".join(_hexf(v) for v in nominals))
    lines += variable_table_lines(variables)
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------- validation
def native_run(model: PlanetaryModel, settings: GearboxRunSettings, *, stop_time_s: Optional[float] = None,
               comm_step_s: Optional[float] = None, drive_speeds_rad_s=None):
    """The native planetary solver with an FMU's start values (``settings`` resolved by
    :func:`planetary_settings`): the inputs held, the same step bound, integrator and start;
    ``drive_speeds_rad_s``: the driven members' speeds (None: the model's, the inputs' start values)."""
    return simulate_planetary(model, settings, stop_time_s=stop_time_s, comm_step_s=comm_step_s,
                              motor_torque_Nm=settings.motor_torque_start_Nm,
                              load_torque_Nm=settings.load_torque_start_Nm, drive_speeds_rad_s=drive_speeds_rad_s)


def _reference(model: PlanetaryModel, variables, settings):
    """(reference_result.csv bytes, {substeps, rows, native_wall_s}) of the native planetary solver, from
    gearfmu's file cache when the same key was computed before (:mod:`gearfmu.fmu.validation`)."""
    versions = _versions()
    meshes = []
    for m, t in enumerate(model.mesh_tables):
        meta = json.loads(t.to_bytes()[0].decode("utf-8"))
        content = {k: v for k, v in meta.items() if k != "provenance"}
        meshes.append([model.mesh_names[m], hashlib.sha256(json.dumps(content, sort_keys=True).encode()).hexdigest()])
    arrays = [model.mass, model.g, model.spring_idx, model.spring_coef, model.spring_k, model.spring_c, model.mesh_idx,
              model.mesh_coef, model.angle_idx, model.angle_coef, model.angle_ref, model.angle_phase, model.mesh_c,
              model.mesh_torque_per_ref, model.frame_idx, model.frame_par]
    key = {"what": "gearfmu native planetary reference result", "meshes": meshes,
           "arrays": hashlib.sha256(b"".join(np.ascontiguousarray(a).tobytes() for a in arrays)).hexdigest(),
           "names": [list(model.dof_names), list(model.mesh_names), list(model.spring_names)],
           "damping": list(model.mesh_damping_model), "load_dof": int(model.load_dof),
           "ends": [bool(model.motor_torque_input), bool(model.load_torque_input)],
           "settings": {k: repr(v) for k, v in sorted(vars(settings).items())},
           "columns": [v.name for v in variables if v.causality == "output"],
           "versions": {k: versions[k] for k in ("gearfmu", "python", *_SOLVER_PACKAGES)},
           "gearfmu_sources_sha256": _sources_sha256(), "machine": platform.machine()}
    folder = cache_dir(REFERENCE_CACHE)
    hit = load_entry(folder, key, ".csv", fields={"substeps": int, "rows": int, "native_wall_s": float})
    if hit is not None:
        return hit[1], hit[0]
    with ticking(f"validation record: native planetary reference run over {settings.stop_time_s:g} s "
                 "(kept for later builds)"):
        res = native_run(model, settings)
    outs = sorted((v.value_reference, v.name) for v in variables if v.causality == "output")
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["time", *(nm for _, nm in outs)])
    cols = [res[nm] for _, nm in outs]
    for i in range(len(res.time_s)):
        w.writerow([repr(float(res.time_s[i]))] + [repr(float(c[i])) for c in cols])
    ref = buf.getvalue().encode("utf-8")
    meta = {"substeps": int(res.substeps), "rows": int(len(res.time_s)), "native_wall_s": float(res.wall_s)}
    store_entry(folder, key, meta, ref, ".csv")
    return ref, meta


# --------------------------------------------------------------------- build
def _digest(model: PlanetaryModel, mesh_bytes, model_name: str, s: GearboxRunSettings) -> str:
    h = hashlib.sha256()
    for meta, data in mesh_bytes:
        h.update(meta)
        h.update(data)
    h.update(repr((model_name, s, model.mass.tolist(), model.g.tolist(), model.spring_k.tolist(),
                   model.mesh_c.tolist(), model.dof_names)).encode())
    return h.hexdigest()


def build_planetary_fmu(model: PlanetaryModel, out_path, *, settings: Optional[GearboxRunSettings] = None,
                        model_name: str = "planetary", scene_text: Optional[str] = None,
                        stage_scene_texts: Optional[Dict[str, str]] = None, platforms: Optional[Sequence[str]] = None,
                        fmi_version: int = 2, fmi3_outputs: str = DEFAULT_FMI3_OUTPUTS, validation: bool = True,
                        cc: Optional[str] = None, model_exchange: Optional[dict] = None) -> Path:
    """Build the planetary FMU of ``model`` at ``out_path`` (FMI ``fmi_version`` 2 or 3, the standalone C
    runtime); return its path.  The arguments as :func:`gearfmu.fmu.gearbox_build.build_gearbox_fmu`'s
    (``stage_scene_texts``: the parallel stages' pair scenes)."""
    interface, me_node_events = interface_options(model_exchange, FMU_INTERFACES, ME_NODE_EVENTS,
                                                  DEFAULT_ME_NODE_EVENTS)
    me = "me" in INTERFACE_ELEMENTS[interface]
    if me:
        for nm, t in zip(model.mesh_names, model.mesh_tables):
            if t.slots > EVENT_MAX_SLOTS:
                raise FmuBuildError(f"interface {interface}: mesh {nm} has {t.slots} tooth-pair slots; Model "
                                    f"Exchange handles at most {EVENT_MAX_SLOTS}")
    if fmi_version not in FMI_VERSIONS:
        raise FmuBuildError(f"fmi_version: {fmi_version!r} not one of {FMI_VERSIONS}")
    if fmi3_outputs not in FMI3_OUTPUTS or (fmi3_outputs != DEFAULT_FMI3_OUTPUTS and fmi_version != 3):
        raise FmuBuildError(f"fmi3_outputs: {fmi3_outputs!r} must be one of {FMI3_OUTPUTS}, and other than "
                            f"{DEFAULT_FMI3_OUTPUTS!r} only with fmi_version 3")
    settings = planetary_settings(model, settings)
    if not isinstance(model_name, str) or not model_name.strip():
        raise FmuBuildError(f"model_name: must be a non-empty string, got {model_name!r}")
    out_path = check_output_arguments(out_path, scene_text)
    keys = check_platforms(platforms)
    spec = load_planetary_spec()
    try:
        variables = variables_of_fmu(model, settings, fmi3_outputs, interface=interface, me_node_events=me_node_events)
    except SpecError as exc:
        raise FmuBuildError(str(exc)) from None
    mesh_bytes = [t.to_bytes() for t in model.mesh_tables]
    identifier = f"gearfmu_pl_{_digest(model, mesh_bytes, model_name, settings)[:12]}_{uuid.uuid4().hex[:8]}"
    guid = "{" + str(uuid.uuid4()) + "}"
    now = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    params = fmu_parameters(model, settings)
    resources = {}
    for folder, (meta_bytes, bin_bytes) in zip(tables_folders(model), mesh_bytes):
        resources.setdefault(f"{folder}/tables.json", meta_bytes)
        resources.setdefault(f"{folder}/tables.bin", bin_bytes)
    for nm, text in (stage_scene_texts or {}).items():
        resources[f"{nm}/scene.toml"] = text.encode("utf-8")
    resources[CONFIG_FILE] = config_text(model, variables, mesh_bytes, guid=guid, model_identifier=identifier,
                                         interface=interface, node_events=me_node_events,
                                         nominals=me_nominals(model, settings) if me else None).encode("utf-8")
    if scene_text is not None:
        resources["scene.toml"] = scene_text.encode("utf-8")
    folders = tables_folders(model)
    provenance = {
        "parameters": dict(params, stop_time_s=settings.stop_time_s, output_interval_s=settings.output_interval_s),
        "meshes": {nm: {"tables": f"resources/{folders[m]}/tables.bin",
                        "tables_sha256": hashlib.sha256(mesh_bytes[m][1]).hexdigest(),
                        "tables_provenance": model.mesh_tables[m].provenance} for m, nm in enumerate(model.mesh_names)},
        "scene_sha256": None if scene_text is None else hashlib.sha256(scene_text.encode()).hexdigest()}

    def record(compiler):
        ref, meta = _reference(model, variables, settings)
        return record_files("planetary", dict(zip(model.mesh_names, model.mesh_tables)), ref, meta, settings,
                            solver="gearfmu.planetary.native.simulate (numba planetary solver, docs/planetary.md)",
                            runtime="standalone", model_identifier=identifier, parameters=params,
                            scene_text=scene_text, compiler=compiler,
                            criterion="every output within 1e-7 of the largest range of the outputs of its unit in "
                                      "this file when a master steps the FMU with communication step = "
                                      "output_interval_s and the start values above (the FMU's initial state is the "
                                      "C kernel's quasi-static solve, within 1e-12 of numpy's; from the same initial "
                                      "state: bit for bit)")

    def page(description, rec, plat_text, tool):
        return planetary_documentation_html(
            model=model, model_name=model_name, model_identifier=identifier, fmi_version=fmi_version,
            generation_tool=tool, variables=variables, description=description, parameters=params,
            scene_text=scene_text, validation_record=rec, platforms_text=plat_text,
            experiment={"start": 0.0, "stop": settings.stop_time_s, "step": settings.output_interval_s})

    return assemble_fmu(FmuPackage(
        kind="planetary", out_path=out_path, fmi_version=fmi_version, unit=PLANETARY_UNITS[fmi_version],
        copy_sources=lambda dest: copy_planetary_sources(dest, fmi_version), platforms=keys, cc=cc,
        identifier=identifier, guid=guid, now=now, spec=spec, variables=variables, model_name=model_name,
        stop_time_s=settings.stop_time_s, step_size_s=settings.output_interval_s, interface=interface,
        resources=resources, provenance=provenance, record=record if validation else None, page=page,
        naming_convention="flat"))


def variables_of_fmu(model: PlanetaryModel, settings: GearboxRunSettings, fmi3_outputs: str = DEFAULT_FMI3_OUTPUTS,
                     spec_path=None, interface: str = DEFAULT_FMU_INTERFACE, me_node_events: str = DEFAULT_ME_NODE_EVENTS):
    """The variables a planetary FMU of ``model`` built with ``settings`` (and ``interface``,
    ``me_node_events``) has (for hosts and tests)."""
    variables = apply_starts(planetary_variables(load_planetary_spec(spec_path), model,
                                                 model_exchange="me" in INTERFACE_ELEMENTS[interface],
                                                 node_events=me_node_events != "none"),
                             start_values(model, planetary_settings(model, settings)))
    return scalar_names(variables) if fmi3_outputs == "scalar" else variables
