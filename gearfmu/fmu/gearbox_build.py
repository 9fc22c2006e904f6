"""Build the gearbox FMU: one FMI 2.0 (or 3.0) Co-Simulation and/or Model Exchange FMU in C for a whole gearbox.

The same FMI layers and plumbing as the pair's standalone FMU (``fmi2_gear.c`` / ``fmi3_gear.c``,
``fmi_common.c``, docs/standalone.md) over the gearbox model (``standalone/gearbox_model.c``) and
the gearbox kernel (``kernel/gb_kernel.c``, which computes every mesh with the pair kernel's own
pieces), compiled from one translation unit (``fmi2_gearbox_all.c`` / ``fmi3_gearbox_all.c``) for the
five platforms of :mod:`gearfmu.fmu.crossbuild`.  The interface comes from
``modeldescription/gearbox.toml`` (:mod:`gearfmu.fmu.gearbox_interface`).  docs/gearbox.md "The
gearbox FMU" describes it.

FMU layout::

    modelDescription.xml                 from the gearbox spec; needsExecutionTool=false, FMU state, SourceFiles
    binaries/<folder>/<id>.<so|dll|dylib>  linux64, aarch64-linux, win64, darwin64 (+ aarch64-darwin)
    sources/                             fmi2_gearbox_all.c (the file to compile) and the files it includes,
                                         BUILD.txt, buildflags.txt, CMakeLists.txt (FMI 3: buildDescription.xml)
    documentation/index.html             the FMU's page (gearfmu.fmu.gearbox_doc; FMI 2 also _main.html)
    documentation/platforms.txt          the binaries carried and the ones not built, with the reason
    resources/<stage>/tables.json, .bin  every stage's tables (the pair FMU's format, docs/tables.md)
    resources/<stage>/scene.toml         the stage's pair scene (when built from a drivetrain scene)
    resources/gearfmu_gearbox.txt        what gearbox_model.c reads (:func:`config_text`)
    resources/provenance.json            versions, parameters, every checksum, the compile commands
    resources/scene.toml                 the drivetrain scene (when given)
    resources/validation/                record.json and reference_result.csv of the native gearbox solver
"""
from __future__ import annotations

import dataclasses
import datetime
import hashlib
import json
import math
import shutil
import uuid
from pathlib import Path
from typing import Dict, Optional, Sequence

import numpy as np

from ..common.settings import GearboxRunSettings, checked
from ..common.vocabulary import (DEFAULT_FMI3_OUTPUTS, DEFAULT_FMU_INTERFACE, DEFAULT_ME_NODE_EVENTS, FMI3_OUTPUTS,
                                  FMU_INTERFACES, ME_NODE_EVENTS)
from ..gearbox.model import GearboxModel
from ..gearbox.native import resolve_settings
from .build_steps import (KERNEL_DIR, KERNEL_HEADERS, KERNEL_SOURCES, FmuBuildError, check_output_arguments,
                          variable_table_lines)
from .gearbox_doc import gearbox_documentation_html
from .gearbox_interface import apply_starts, gearbox_variables, load_gearbox_spec, stage_parameter
from .gearbox_validation import gearbox_validation_record
from .modeldesc import SpecError
from .multimesh_build import FmuPackage, assemble_fmu, check_platforms, interface_options
from .standalone_build import FMI_VERSIONS, INTERFACE_ELEMENTS, scalar_names

__all__ = ["build_gearbox_fmu", "gearbox_settings", "fmu_parameters", "start_values", "variables_of_fmu",
           "config_text", "me_nominals", "EVENT_MAX_SLOTS", "GEARBOX_UNITS", "gearbox_file_sources", "copy_gearbox_sources", "CONFIG_FILE"]

HERE = Path(__file__).resolve().parent
STANDALONE_DIR = HERE / "standalone"
#: the one file a build of the gearbox FMU of FMI 2 / FMI 3 compiles
GEARBOX_UNITS = {2: STANDALONE_DIR / "fmi2_gearbox_all.c", 3: STANDALONE_DIR / "fmi3_gearbox_all.c"}
#: the FMI layers (the pair FMU's, unchanged)
LAYERS = {2: STANDALONE_DIR / "fmi2_gear.c", 3: STANDALONE_DIR / "fmi3_gear.c"}
#: the plumbing, the gearbox model, the reading of resources and the gearbox kernel, in compile order
GEARBOX_SOURCES = (STANDALONE_DIR / "fmi_common.c", STANDALONE_DIR / "gearbox_model.c",
                   STANDALONE_DIR / "gf_resources.c", STANDALONE_DIR / "gf_meshes.c", KERNEL_DIR / "gb_kernel.c")
GEARBOX_HEADERS = (STANDALONE_DIR / "gf_model.h", STANDALONE_DIR / "fmi_common.h", STANDALONE_DIR / "gearbox_model.h",
                   STANDALONE_DIR / "gf_resources.h", STANDALONE_DIR / "gf_meshes.h", KERNEL_DIR / "gbkernel.h")
CONFIG_FILE = "gearfmu_gearbox.txt"
CONFIG_FORMAT = "gearfmu-gearbox"
CONFIG_VERSION = 1


def gearbox_file_sources(fmi_version: int = 2) -> tuple:
    """Every C file of the gearbox binary in compile order: the FMI layer, the plumbing, the model, the
    reading of resources, the gearbox kernel and the pair kernel's files (the unit includes them so)."""
    return (LAYERS[fmi_version].name, *(p.name for p in GEARBOX_SOURCES), *(p.name for p in KERNEL_SOURCES))


def copy_gearbox_sources(dest_dir, fmi_version: int = 2) -> Path:
    """The unit of ``fmi_version``, the files it includes and their headers into ``dest_dir`` (not the
    FMI headers: the importer's, as the standard says)."""
    dest = Path(dest_dir)
    dest.mkdir(parents=True, exist_ok=True)
    for src in (GEARBOX_UNITS[fmi_version], LAYERS[fmi_version], *GEARBOX_SOURCES, *GEARBOX_HEADERS, *KERNEL_SOURCES,
                *KERNEL_HEADERS):
        shutil.copy2(src, dest / src.name)
    return dest


# ----------------------------------------------------------------- arguments
#: the most tooth-pair slots per stage the event-locating integrators of the C kernel handle
EVENT_MAX_SLOTS = 32


def gearbox_settings(model: GearboxModel, settings: Optional[GearboxRunSettings] = None,
                     **changes) -> GearboxRunSettings:
    """The run settings of a gearbox FMU: ``settings`` (:class:`gearfmu.common.settings.GearboxRunSettings`;
    None: its defaults) with the fields given in ``changes`` (checked by its one rule; a bad value
    raises FmuBuildError naming the field), every automatic value resolved on ``model``, since an
    FMU's start values and DefaultExperiment are numbers: the load's start torque (None: the torque
    T_motor/g_load that balances the motor's start torque), the output interval and the largest
    internal step (:func:`gearfmu.gearbox.native.resolve_settings`; the step linearised at the start
    torques).  An integrator other than rk4 handles at most :data:`EVENT_MAX_SLOTS` slots per stage."""
    if not isinstance(model, GearboxModel):
        raise FmuBuildError(f"model: expected gearfmu.gearbox.model.GearboxModel, got {type(model).__name__}")
    s = checked(settings, FmuBuildError, GearboxRunSettings, **changes)
    if s.load_torque_start_Nm is None:
        s = dataclasses.replace(s, load_torque_start_Nm=model.balancing_load_torque_Nm(s.motor_torque_start_Nm))
    s = resolve_settings(model, s, reference_torque_Nm=model.reference_torque_Nm(s.motor_torque_start_Nm,
                                                                                 s.load_torque_start_Nm))
    if s.integrator != "rk4":
        for m in model.meshes:
            if m.tables.slots > EVENT_MAX_SLOTS:
                raise FmuBuildError(f"integrator: {s.integrator!r} handles at most {EVENT_MAX_SLOTS} slots, stage "
                                    f"{m.name!r} has {m.tables.slots}")
    return s


def fmu_parameters(model: GearboxModel, s: GearboxRunSettings) -> dict:
    """The parameters the provenance and the validation record name (the integrator by its code)."""
    return {"motor_torque_start_Nm": s.motor_torque_start_Nm, "load_torque_start_Nm": s.load_torque_start_Nm,
            "motor_speed_start_rad_s": s.motor_speed_start_rad_s, "motor_angle_start_rad": s.motor_angle_start_rad,
            "max_step_s": s.max_step_s, "integrator": s.integrator_code,
            "stages": {m.name: {"damping_ratio": m.damping_ratio, "damping_model": m.damping_model}
                       for m in model.meshes}}


def start_values(model: GearboxModel, s: GearboxRunSettings) -> Dict[str, float]:
    """The start value of every parameter and input of the interface (by its FMU name; ``s``
    resolved by :func:`gearbox_settings`)."""
    starts = {"motor_speed_start": s.motor_speed_start_rad_s, "motor_angle_start": s.motor_angle_start_rad,
              "max_step": s.max_step_s, "integrator": s.integrator_code}
    if model.motor_torque_input:
        starts["motor_torque"] = s.motor_torque_start_Nm
    if model.load_torque_input:
        starts["load_torque"] = s.load_torque_start_Nm
    for m in model.meshes:
        starts[stage_parameter(m.name, "damping_ratio")] = m.damping_ratio
        starts[stage_parameter(m.name, "damping_model")] = {"elastobacklash": 0, "contact_zone": 1}[m.damping_model]
    return starts


# ---------------------------------------------------------------- resources
def _hexf(v) -> str:
    return float(v).hex()


def stage_folder(name: str) -> str:
    """A stage's folder under resources/ (stage names are identifiers: letters, digits, _)."""
    return name


def me_nominals(model: GearboxModel, settings: GearboxRunSettings) -> list:
    """Nominal values of the Model Exchange states [psi, omega, u_1, du_1, ...] (rad, rad/s): psi 1 rad;
    the start speed (at least 1 rad/s); every deviation the smallest stage scale over its larger base
    radius (a stage's scale: the largest of its static deflection at the start torque, its backlash
    and its meshing error range, at least 1e-9 m), every deviation rate that times the largest mesh
    frequency sqrt(k_mean/m_e).  A host's absolute tolerance is its relative tolerance times these."""
    t_ref = model.reference_torque_Nm(settings.motor_torque_start_Nm, settings.load_torque_start_Nm)
    u, wn = math.inf, 0.0
    for m, mesh in enumerate(model.meshes):
        t = mesh.tables
        g_p = float(model.g[model.mesh_bodies[m][0]])
        e = np.asarray(t.e_m, float)
        x = max(abs(t_ref / g_p) / (t.base_radius_pinion_m * t.k_mean_N_per_m),
                float(np.max(np.abs(t.backlash_half_m))), float(np.max(e) - np.min(e)), 1e-9)
        u = min(u, x / max(t.base_radius_pinion_m, t.base_radius_gear_m))
        wn = max(wn, math.sqrt(t.k_mean_N_per_m / t.equivalent_mass_kg))
    return [1.0, max(abs(settings.motor_speed_start_rad_s), 1.0)] + [u, u * wn] * (model.n_bodies - 1)


def config_text(model: GearboxModel, variables, stage_bytes, *, guid: str, model_identifier: str,
                interface: str = "cs", node_events: str = "none", nominals: Optional[Sequence[float]] = None) -> str:
    """The ``gearfmu_gearbox.txt`` gearbox_model.c reads (format gearfmu-gearbox, version 1): the bodies
    (1/I and the kinematic ratio as C99 hexadecimal floats, exact), every stage (its tables file, size,
    SHA-256, dimensions, byte offsets, scalars, bodies, whether it is on the power path, the value
    references of its damping parameters), the elastic shafts, the tree walked from the motor, the value
    references the model drives, Model Exchange (``interface`` of :data:`FMU_INTERFACES`: the
    ``interfaces`` line; with Model Exchange the ``me.*`` lines: ``node_events``, the number of event
    indicators, the ``nominals`` of the states) and the variable table.  ``stage_bytes``: (tables.json,
    tables.bin) bytes of every stage."""
    vr = {v.name: v.value_reference for v in variables}
    inv_i = [1.0 / float(x) for x in model.inertia_kgm2]   # as the numba kernels' bf = 1.0/I
    lines = [
        "# gearfmu gearbox FMU configuration (written by gearfmu.fmu.gearbox_build; read by gearbox_model.c)",
        "# floats are C99 hexadecimal literals (exact); body = index|1/I|g|parts; shaft = index|a|b|k|c|on_path|name;",
        "# edge = kind (0 shaft, 1 mesh)|index|upstream body|downstream body, walking from the motor's body",
        f"format={CONFIG_FORMAT}", f"version={CONFIG_VERSION}", f"model_identifier={model_identifier}",
        f"guid={guid}", f"bodies={model.n_bodies}", f"load_body={model.load_body}",
        f"motor_torque_input={int(model.motor_torque_input)}", f"load_torque_input={int(model.load_torque_input)}",
    ]
    for i in range(model.n_bodies):
        lines.append(f"body={i}|{_hexf(inv_i[i])}|{_hexf(model.g[i])}|{model.body_name(i)}")
    lines.append(f"stages={len(model.meshes)}")
    for m, mesh in enumerate(model.meshes):
        t = mesh.tables
        meta_bytes, bin_bytes = stage_bytes[m]
        meta = json.loads(meta_bytes.decode("utf-8"))
        sc = meta["scalars"]
        p, q = model.mesh_bodies[m]
        st = f"stage.{m}."
        lines += [f"{st}name={mesh.name}", f"{st}tables={stage_folder(mesh.name)}/tables.bin",
                  f"{st}tables_bytes={len(bin_bytes)}", f"{st}tables_sha256={hashlib.sha256(bin_bytes).hexdigest()}",
                  f"{st}slots={t.slots}", f"{st}n_phi={t.n_phi}", f"{st}n_torque={t.n_torque}"]
        for name in ("torque_Nm", "k_N_per_m", "e_m", "backlash_half_m"):
            lines.append(f"{st}offset.{name}={int(meta['arrays'][name]['offset'])}")
        for name in ("phi_period_rad", "base_radius_pinion_m", "base_radius_gear_m", "inertia_pinion_kgm2",
                     "inertia_gear_kgm2", "k_mean_N_per_m"):
            lines.append(f"{st}{name}={_hexf(sc[name])}")
        if meta.get("engagement") is not None:
            lines += [f"{st}mesh_period_rad={_hexf(sc['mesh_period_rad'])}",
                      f"{st}engagement_in_rad={_hexf(meta['engagement']['in_rad'])}",
                      f"{st}engagement_out_rad={_hexf(meta['engagement']['out_rad'])}"]
        lines += [f"{st}bodies={p}|{q}", f"{st}on_path={int(mesh.name in model.on_path)}",
                  f"{st}vr.damping_ratio={vr[stage_parameter(mesh.name, 'damping_ratio')]}",
                  f"{st}vr.damping_model={vr[stage_parameter(mesh.name, 'damping_model')]}"]
    lines.append(f"shafts={len(model.shafts)}")
    for s, sh in enumerate(model.shafts):
        a, b = model.shaft_bodies[s]
        lines.append(f"shaft={s}|{a}|{b}|{_hexf(model.shaft_k_Nm_per_rad[s])}|{_hexf(model.shaft_c_Nms_per_rad[s])}|"
                     f"{int(sh.name in model.on_path)}|{sh.name}")
    for kind, e, up, down in model.tree_edges:
        lines.append(f"edge={0 if kind == 'shaft' else 1}|{e}|{up}|{down}")
    for key in ("motor_torque", "load_torque", "motor_speed_start", "motor_angle_start", "max_step", "integrator"):
        lines.append(f"vr.{key}={vr.get(key, -1)}")
    elements = INTERFACE_ELEMENTS[interface]
    lines.append("interfaces=" + ",".join(e for e in ("cs", "me") if e in elements))
    if "me" in elements:   # docs/gearbox.md "Model Exchange"
        lines.append(f"me.node_events={ME_NODE_EVENTS.index(node_events)}")
        lines.append(f"me.event_indicators={sum(v.event_indicator for v in variables)}")
        lines.append("me.nominals=" + "|".join(_hexf(v) for v in nominals))
    lines += variable_table_lines(variables)
    return "\n".join(lines) + "\n"


def _digest(model: GearboxModel, stage_bytes, model_name: str, s: GearboxRunSettings) -> str:
    h = hashlib.sha256()
    for meta, data in stage_bytes:
        h.update(meta)
        h.update(data)
    h.update(repr((model_name, s, model.inertia_kgm2.tolist(), model.g.tolist(), model.shaft_k_Nm_per_rad.tolist(),
                   model.shaft_c_Nms_per_rad.tolist(), [(m.name, m.damping_ratio, m.damping_model)
                                                        for m in model.meshes])).encode())
    return h.hexdigest()


# --------------------------------------------------------------------- build
def model_exchange_options(model: GearboxModel, model_exchange: Optional[dict]) -> tuple:
    """(interface, me_node_events) of :func:`build_gearbox_fmu`'s ``model_exchange`` mapping (None: {});
    FmuBuildError naming the key for a value that is not offered, or a stage with more tooth-pair slots
    than Model Exchange handles (:data:`EVENT_MAX_SLOTS`)."""
    interface, node_events = interface_options(model_exchange, FMU_INTERFACES, ME_NODE_EVENTS, DEFAULT_ME_NODE_EVENTS)
    if "me" in INTERFACE_ELEMENTS[interface]:
        for m in model.meshes:
            if m.tables.slots > EVENT_MAX_SLOTS:
                raise FmuBuildError(f"interface {interface}: stage {m.name} has {m.tables.slots} tooth-pair slots; "
                                    f"Model Exchange handles at most {EVENT_MAX_SLOTS}")
    return interface, node_events


def build_gearbox_fmu(model: GearboxModel, out_path, *, settings: Optional[GearboxRunSettings] = None,
                      model_name: str = "gearbox", scene_text: Optional[str] = None,
                      stage_scene_texts: Optional[Dict[str, str]] = None, platforms: Optional[Sequence[str]] = None,
                      fmi_version: int = 2, fmi3_outputs: str = DEFAULT_FMI3_OUTPUTS, validation: bool = True,
                      cc: Optional[str] = None, model_exchange: Optional[dict] = None) -> Path:
    """Build the gearbox FMU of ``model`` at ``out_path`` (FMI ``fmi_version`` 2 or 3, the
    standalone C runtime); return its path.

    ``settings``: the run's :class:`gearfmu.common.settings.GearboxRunSettings` (the FMU's start values
    and DefaultExperiment; None: its defaults; automatic values resolved by :func:`gearbox_settings`);
    ``scene_text`` the drivetrain scene and ``stage_scene_texts`` every stage's pair scene (stage
    name -> TOML), carried in resources/; ``platforms``: keys of :data:`gearfmu.fmu.crossbuild.TARGETS` (default all; without
    zig the build machine's only, the FMU says what it lacks); ``fmi3_outputs`` "scalar": the per-slot
    outputs of an FMI 3 FMU as scalars ``stage1.pair_force_1`` ..; ``validation`` False: no validation
    record (no native run); ``cc``: the build machine's compiler.  Written under a temporary name
    beside ``out_path`` and renamed at the end.  ``model_exchange``: {"interface": "both" (Co-Simulation and
    Model Exchange, the default), "cs" (Co-Simulation) or "me" (Model Exchange), "me_node_events": Model Exchange's table-node events, one
    of :data:`gearfmu.common.vocabulary.ME_NODE_EVENTS`} (docs/gearbox.md "Model Exchange")."""
    interface, me_node_events = model_exchange_options(model, model_exchange)
    if fmi_version not in FMI_VERSIONS:
        raise FmuBuildError(f"fmi_version: {fmi_version!r} not one of {FMI_VERSIONS}")
    if fmi3_outputs not in FMI3_OUTPUTS or (fmi3_outputs != DEFAULT_FMI3_OUTPUTS and fmi_version != 3):
        raise FmuBuildError(f"fmi3_outputs: {fmi3_outputs!r} must be one of {FMI3_OUTPUTS}, and other than "
                            f"{DEFAULT_FMI3_OUTPUTS!r} only with fmi_version 3")
    me = "me" in INTERFACE_ELEMENTS[interface]
    settings = gearbox_settings(model, settings)
    if not isinstance(model_name, str) or not model_name.strip():
        raise FmuBuildError(f"model_name: must be a non-empty string, got {model_name!r}")
    out_path = check_output_arguments(out_path, scene_text)
    keys = check_platforms(platforms)
    spec = load_gearbox_spec()
    try:
        variables = apply_starts(gearbox_variables(spec, model, model_exchange=me,
                                                   node_events=me_node_events != "none"),
                                 start_values(model, settings))
    except SpecError as exc:
        raise FmuBuildError(str(exc)) from None
    if fmi3_outputs == "scalar":
        variables = scalar_names(variables)
    stage_bytes = [m.tables.to_bytes() for m in model.meshes]
    identifier = f"gearfmu_gb_{_digest(model, stage_bytes, model_name, settings)[:12]}_{uuid.uuid4().hex[:8]}"
    guid = "{" + str(uuid.uuid4()) + "}"
    now = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    params = fmu_parameters(model, settings)
    stage_scene_texts = dict(stage_scene_texts or {})
    resources = {}
    for mesh, (meta_bytes, bin_bytes) in zip(model.meshes, stage_bytes):
        d = stage_folder(mesh.name)
        resources[f"{d}/tables.json"] = meta_bytes
        resources[f"{d}/tables.bin"] = bin_bytes
        if mesh.name in stage_scene_texts:
            resources[f"{d}/scene.toml"] = stage_scene_texts[mesh.name].encode("utf-8")
    resources[CONFIG_FILE] = config_text(model, variables, stage_bytes, guid=guid, model_identifier=identifier,
                                         interface=interface, node_events=me_node_events,
                                         nominals=me_nominals(model, settings) if me else None).encode("utf-8")
    if scene_text is not None:
        resources["scene.toml"] = scene_text.encode("utf-8")
    provenance = {
        "parameters": dict(params, stop_time_s=settings.stop_time_s, output_interval_s=settings.output_interval_s),
        "stages": {m.name: {"tables": f"resources/{stage_folder(m.name)}/tables.bin",
                            "tables_sha256": hashlib.sha256(b).hexdigest(), "tables_provenance": m.tables.provenance}
                   for m, (_, b) in zip(model.meshes, stage_bytes)},
        "scene_sha256": None if scene_text is None else hashlib.sha256(scene_text.encode()).hexdigest()}

    def record(compiler):
        return gearbox_validation_record(model, variables, settings, runtime="standalone", model_identifier=identifier,
                                         parameters=params, scene_text=scene_text, compiler=compiler)

    def page(description, rec, plat_text, tool):
        return gearbox_documentation_html(
            model=model, model_name=model_name, model_identifier=identifier, fmi_version=fmi_version,
            generation_tool=tool, variables=variables, description=description, parameters=params,
            scene_text=scene_text, validation_record=rec, platforms_text=plat_text,
            experiment={"start": 0.0, "stop": settings.stop_time_s, "step": settings.output_interval_s})

    return assemble_fmu(FmuPackage(
        kind="gearbox", out_path=out_path, fmi_version=fmi_version, unit=GEARBOX_UNITS[fmi_version],
        copy_sources=lambda dest: copy_gearbox_sources(dest, fmi_version), platforms=keys, cc=cc,
        identifier=identifier, guid=guid, now=now, spec=spec, variables=variables, model_name=model_name,
        stop_time_s=settings.stop_time_s, step_size_s=settings.output_interval_s, interface=interface,
        resources=resources, provenance=provenance, record=record if validation else None, page=page))


def variables_of_fmu(model: GearboxModel, settings: GearboxRunSettings, fmi3_outputs: str = DEFAULT_FMI3_OUTPUTS,
                     spec_path=None, interface: str = DEFAULT_FMU_INTERFACE, me_node_events: str = DEFAULT_ME_NODE_EVENTS):
    """The variables a gearbox FMU of ``model`` built with ``settings`` (and ``interface``,
    ``me_node_events``) has (for hosts and tests)."""
    variables = apply_starts(gearbox_variables(load_gearbox_spec(spec_path), model,
                                               model_exchange="me" in INTERFACE_ELEMENTS[interface],
                                               node_events=me_node_events != "none"),
                             start_values(model, gearbox_settings(model, settings)))
    return scalar_names(variables) if fmi3_outputs == "scalar" else variables
