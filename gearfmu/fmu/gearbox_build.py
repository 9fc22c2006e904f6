"""Build the gearbox FMU: one FMI 2.0 (or 3.0) Co-Simulation FMU in C for a whole gearbox.

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
import platform
import shutil
import sys
import tempfile
import uuid
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Dict, Optional, Sequence

from .. import __version__
from ..common.settings import GearboxRunSettings, checked
from ..common.vocabulary import DEFAULT_FMI3_OUTPUTS, FMI3_OUTPUTS
from ..gearbox.model import GearboxModel
from ..gearbox.native import resolve_settings
from . import crossbuild
from .build_steps import (KERNEL_DIR, KERNEL_HEADERS, KERNEL_SOURCES, FmuBuildError, check_model_description,
                          check_output_arguments, compiler_version, find_c_compiler, fmi_header_dir, fmu_zip,
                          model_description, variable_table_lines, zip_folder)
from .gearbox_doc import gearbox_documentation_html
from .gearbox_interface import apply_starts, gearbox_variables, load_gearbox_spec, stage_parameter
from .gearbox_validation import gearbox_validation_record
from .modeldesc import SpecError
from .fmudoc import DOC_FILES
from .standalone_build import (FMI_VERSIONS, STANDALONE_CFLAGS, build_recipe_files, compile_standalone,
                               platforms_text, scalar_names, standalone_model_description)

__all__ = ["build_gearbox_fmu", "gearbox_settings", "fmu_parameters", "start_values", "variables_of_fmu",
           "config_text", "EVENT_MAX_SLOTS", "GEARBOX_UNITS", "gearbox_file_sources", "copy_gearbox_sources", "CONFIG_FILE"]

HERE = Path(__file__).resolve().parent
STANDALONE_DIR = HERE / "standalone"
#: the one file a build of the gearbox FMU of FMI 2 / FMI 3 compiles
GEARBOX_UNITS = {2: STANDALONE_DIR / "fmi2_gearbox_all.c", 3: STANDALONE_DIR / "fmi3_gearbox_all.c"}
#: the FMI layers (the pair FMU's, unchanged)
LAYERS = {2: STANDALONE_DIR / "fmi2_gear.c", 3: STANDALONE_DIR / "fmi3_gear.c"}
#: the plumbing, the gearbox model, the reading of resources and the gearbox kernel, in compile order
GEARBOX_SOURCES = (STANDALONE_DIR / "fmi_common.c", STANDALONE_DIR / "gearbox_model.c",
                   STANDALONE_DIR / "gf_resources.c", KERNEL_DIR / "gb_kernel.c")
GEARBOX_HEADERS = (STANDALONE_DIR / "gf_model.h", STANDALONE_DIR / "fmi_common.h", STANDALONE_DIR / "gearbox_model.h",
                   STANDALONE_DIR / "gf_resources.h", KERNEL_DIR / "gbkernel.h")
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


def config_text(model: GearboxModel, variables, stage_bytes, *, guid: str, model_identifier: str) -> str:
    """The ``gearfmu_gearbox.txt`` gearbox_model.c reads (format gearfmu-gearbox, version 1): the bodies
    (1/I and the kinematic ratio as C99 hexadecimal floats, exact), every stage (its tables file, size,
    SHA-256, dimensions, byte offsets, scalars, bodies, whether it is on the power path, the value
    references of its damping parameters), the elastic shafts, the tree walked from the motor, the value
    references the model drives, and the variable table.  ``stage_bytes``: (tables.json, tables.bin)
    bytes of every stage."""
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
def build_gearbox_fmu(model: GearboxModel, out_path, *, settings: Optional[GearboxRunSettings] = None,
                      model_name: str = "gearbox", scene_text: Optional[str] = None,
                      stage_scene_texts: Optional[Dict[str, str]] = None, platforms: Optional[Sequence[str]] = None,
                      fmi_version: int = 2, fmi3_outputs: str = DEFAULT_FMI3_OUTPUTS, validation: bool = True,
                      cc: Optional[str] = None, spec_path=None) -> Path:
    """Build the gearbox FMU of ``model`` at ``out_path`` (FMI ``fmi_version`` 2 or 3 Co-Simulation, the
    standalone C runtime); return its path.

    ``settings``: the run's :class:`gearfmu.common.settings.GearboxRunSettings` (the FMU's start values
    and DefaultExperiment; None: its defaults; automatic values resolved by :func:`gearbox_settings`);
    ``scene_text`` the drivetrain scene and ``stage_scene_texts`` every stage's pair scene (stage
    name -> TOML), carried in resources/; ``platforms``: keys of :data:`gearfmu.fmu.crossbuild.TARGETS` (default all; without
    zig the build machine's only, the FMU says what it lacks); ``fmi3_outputs`` "scalar": the per-slot
    outputs of an FMI 3 FMU as scalars ``stage1.pair_force_1`` ..; ``validation`` False: no validation
    record (no native run); ``cc``: the build machine's compiler.  Written under a temporary name
    beside ``out_path`` and renamed at the end."""
    if fmi_version not in FMI_VERSIONS:
        raise FmuBuildError(f"fmi_version: {fmi_version!r} not one of {FMI_VERSIONS}")
    if fmi3_outputs not in FMI3_OUTPUTS or (fmi3_outputs != DEFAULT_FMI3_OUTPUTS and fmi_version != 3):
        raise FmuBuildError(f"fmi3_outputs: {fmi3_outputs!r} must be one of {FMI3_OUTPUTS}, and other than "
                            f"{DEFAULT_FMI3_OUTPUTS!r} only with fmi_version 3")
    settings = gearbox_settings(model, settings)
    if not isinstance(model_name, str) or not model_name.strip():
        raise FmuBuildError(f"model_name: must be a non-empty string, got {model_name!r}")
    out_path = check_output_arguments(out_path, scene_text)
    keys = crossbuild.parse_platforms(None) if platforms is None else tuple(platforms)
    unknown = [k for k in keys if k not in crossbuild.TARGETS]
    if unknown or not keys:
        raise FmuBuildError(f"platforms: unknown {unknown} (known: {', '.join(crossbuild.TARGETS)})")
    spec = load_gearbox_spec(spec_path)
    try:
        variables = apply_starts(gearbox_variables(spec, model), start_values(model, settings))
    except SpecError as exc:
        raise FmuBuildError(str(exc)) from None
    if fmi3_outputs == "scalar":
        variables = scalar_names(variables)
    stage_bytes = [m.tables.to_bytes() for m in model.meshes]
    identifier = f"gearfmu_gb_{_digest(model, stage_bytes, model_name, settings)[:12]}_{uuid.uuid4().hex[:8]}"
    guid = "{" + str(uuid.uuid4()) + "}"
    now = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    params = fmu_parameters(model, settings)
    unit = GEARBOX_UNITS[fmi_version].name
    stage_scene_texts = dict(stage_scene_texts or {})

    with tempfile.TemporaryDirectory(prefix="gearfmu_gb_build_") as tmpd:
        root = Path(tmpd) / "fmu"
        src = copy_gearbox_sources(root / "sources", fmi_version)

        def host_compile(out_lib):
            host = cc or find_c_compiler()
            return compile_standalone(src, out_lib, cc=host, fmi_version=fmi_version, sources=(unit,)), \
                compiler_version(host)

        try:
            binaries = crossbuild.build_binaries(keys, src, root / "binaries", identifier, cflags=STANDALONE_CFLAGS,
                                                 sources=(unit,), host_compile=host_compile,
                                                 host_cc_first=cc is not None, fmi_version=fmi_version,
                                                 header_dir=fmi_header_dir(fmi_version))
        except crossbuild.CrossBuildError as exc:
            raise FmuBuildError(str(exc)) from None
        for name, text in build_recipe_files(identifier, fmi_version, (unit,)).items():
            (src / name).write_text(text, encoding="utf-8")
        plat_text = platforms_text(binaries, fmi_version)
        (root / "documentation").mkdir()
        (root / "documentation" / "platforms.txt").write_text(plat_text, encoding="utf-8")
        built = {k: r for k, r in binaries.items() if "missing" not in r}
        for r in built.values():
            r["sha256"] = hashlib.sha256((root / "binaries" / r["folder"] / r["file"]).read_bytes()).hexdigest()
        res = root / "resources"
        res.mkdir()
        files = {}
        for mesh, (meta_bytes, bin_bytes) in zip(model.meshes, stage_bytes):
            d = res / stage_folder(mesh.name)
            d.mkdir()
            (d / "tables.json").write_bytes(meta_bytes)
            (d / "tables.bin").write_bytes(bin_bytes)
            if mesh.name in stage_scene_texts:
                (d / "scene.toml").write_text(stage_scene_texts[mesh.name], encoding="utf-8")
        (res / CONFIG_FILE).write_text(config_text(model, variables, stage_bytes, guid=guid,
                                                   model_identifier=identifier), encoding="utf-8")
        if scene_text is not None:
            (res / "scene.toml").write_text(scene_text, encoding="utf-8")
        for p in sorted(res.rglob("*")):
            if p.is_file():
                files[p.relative_to(root).as_posix()] = hashlib.sha256(p.read_bytes()).hexdigest()
        compiler = "; ".join(sorted({r["compiler"] for r in built.values()})) or None
        provenance = {
            "gearfmu_version": __version__, "built_utc": now, "runtime": "standalone", "model": "gearbox",
            "fmi_version": fmi_version, "model_name": model_name, "model_identifier": identifier, "guid": guid,
            "parameters": dict(params, stop_time_s=settings.stop_time_s,
                               output_interval_s=settings.output_interval_s),
            "stages": {m.name: {"tables": f"resources/{stage_folder(m.name)}/tables.bin",
                                "tables_sha256": hashlib.sha256(b).hexdigest(), "tables_provenance":
                                m.tables.provenance} for m, (_, b) in zip(model.meshes, stage_bytes)},
            "files_sha256": files,
            "binary": {"compiler": compiler, "flags": list(STANDALONE_CFLAGS),
                       "command": "; ".join(sorted({r["command"] for r in built.values()})), "platforms": binaries,
                       "sources_sha256": {p.name: hashlib.sha256(p.read_bytes()).hexdigest()
                                          for p in sorted(src.iterdir())}},
            "scene_sha256": None if scene_text is None else hashlib.sha256(scene_text.encode()).hexdigest(),
            "python": sys.version.split()[0], "platform": platform.platform(), "spec": Path(spec.path).name,
        }
        (res / "provenance.json").write_text(json.dumps(provenance, indent=1, default=str), encoding="utf-8")
        record = None
        if validation:
            rec_files = gearbox_validation_record(model, variables, settings, runtime="standalone",
                                                  model_identifier=identifier, parameters=params,
                                                  scene_text=scene_text, compiler=compiler)
            for rel, data in rec_files.items():
                p = root / rel
                p.parent.mkdir(parents=True, exist_ok=True)
                p.write_bytes(data)
            record = json.loads(rec_files["resources/validation/record.json"])
        md_args = dict(model_name=model_name, model_identifier=identifier, guid=guid,
                       stop_time_s=settings.stop_time_s, step_size_s=settings.output_interval_s,
                       generation_tool=f"gearfmu {__version__} (standalone runtime, gearbox)", generation_date=now,
                       version=__version__)
        note = crossbuild.platform_summary(binaries)
        if fmi_version == 3:
            xml = model_description(spec, variables, 3, platforms_note=note, **md_args)
        else:
            xml = standalone_model_description(model_description(spec, variables, 2, **md_args), (unit,),
                                               platforms_note=note)
            check_model_description(xml, variables)
        (root / "modelDescription.xml").write_bytes(xml)
        page = gearbox_documentation_html(
            model=model, model_name=model_name, model_identifier=identifier, fmi_version=fmi_version,
            generation_tool=md_args["generation_tool"], variables=variables,
            description=ET.fromstring(xml).get("description", ""), parameters=params, scene_text=scene_text,
            validation_record=record, platforms_text=plat_text,
            experiment={"start": 0.0, "stop": settings.stop_time_s, "step": settings.output_interval_s})
        for rel in DOC_FILES(fmi_version):
            (root / rel).write_bytes(page)
        with fmu_zip(out_path) as zout:
            zip_folder(zout, root)
    return out_path


def variables_of_fmu(model: GearboxModel, settings: GearboxRunSettings, fmi3_outputs: str = DEFAULT_FMI3_OUTPUTS,
                     spec_path=None):
    """The variables a gearbox FMU of ``model`` built with ``settings`` has (for hosts and tests)."""
    variables = apply_starts(gearbox_variables(load_gearbox_spec(spec_path), model),
                             start_values(model, gearbox_settings(model, settings)))
    return scalar_names(variables) if fmi3_outputs == "scalar" else variables
