"""Build an FMI 2.0 Co-Simulation FMU from tooth-pair tables.

The FMU is a pythonfmu FMU whose Python slave (``gearfmu/fmu/runtime/gearfmu_slave.py``,
a template) is a thin FMI layer over the C kernel ``gearfmu/fmu/kernel/gearkernel.c``
(docs/model.md), compiled here with the system C compiler and shipped in the
FMU's ``resources/`` together with its sources.  The model description is
produced from ``modeldescription/variables.toml`` (:mod:`gearfmu.fmu.modeldesc`),
checked against what the slave registers, and replaces pythonfmu's.

FMU layout (docs/fmu.md)::

    modelDescription.xml                 from the spec
    binaries/linux64/<id>.so             the loader (gearfmu/fmu/runtime/pyshim.c) in front of
    binaries/linux64/<id>.pythonfmu.so   pythonfmu's FMI wrapper
    resources/<id>.py                    the slave (unique module and class name)
    resources/pythonfmu/                 pythonfmu's Python side
    resources/tables.json, tables.bin    the tables (gearfmu/tables/mesh_tables.py format)
    resources/gearkernel.so              the compiled kernel
    resources/kernel_src/gearkernel.c|h  its sources and the compile command
    resources/gearfmu_runtime.json       variables, kernel name, SHA-256 sums
    resources/gearfmu_pyshim.txt         the Python the loader starts (recorded at build time)
    resources/pyshim_src/                the loader's source and its compile command
    resources/provenance.json            who/what/when built this FMU
    resources/scene.toml                 the scene (when given)
"""
from __future__ import annotations

import datetime
import hashlib
import json
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import uuid
import zipfile
from pathlib import Path
from typing import Optional, Union
from dataclasses import replace
import sysconfig

from .. import __version__
from .modeldesc import (apply_start_values, check_model_description, check_registered,
                        expand_variables, features_of, load_spec, model_description_xml,
                        runtime_variable_table)
from ..common.vocabulary import DAMPING_MODELS, INTEGRATORS, current_spelling
from ..tables.mesh_tables import MeshTables
from .validation import validation_record
from ..scene.reader import default_output_interval_s
from ..scene.envelope import ENVELOPE_FILE, envelope_note, fmu_envelope_record, runtime_envelope

HERE = Path(__file__).resolve().parent
KERNEL_SOURCE = HERE / "kernel" / "gearkernel.c"
KERNEL_HEADER = HERE / "kernel" / "gearkernel.h"
SLAVE_TEMPLATE = HERE / "runtime" / "gearfmu_slave.py"
PYSHIM_SOURCE = HERE / "runtime" / "pyshim.c"
PYSHIM_CONFIG = "gearfmu_pyshim.txt"
#: the loader's compile flags (docs/fmu.md "The binary"); it links no Python
PYSHIM_CFLAGS = ("-O2", "-fPIC", "-shared", "-std=c99", "-fvisibility=hidden")
TEMPLATE_CLASS = "GearFmuSlave"
#: compile flags (no FMA contraction, so the kernel's arithmetic is the written one)
CFLAGS = ("-O2", "-fPIC", "-shared", "-ffp-contract=off", "-std=c99")
KERNEL_ABI_VERSION = 3  # gearkernel.h GK_ABI_VERSION (2: temperature axis, 3: verified envelope check)
#: gearkernel.h GK_KINK_MAX_SLOTS
KINK_MAX_SLOTS = 32


class FmuBuildError(ValueError):
    """The FMU cannot be built from these arguments; the message names the field."""


#: the FMI 2.0 standard headers the C layers are compiled against
FMI2_HEADERS = ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")


def fmi2_header_dir() -> Path:
    """fmpy's copy of the FMI 2.0 standard headers (``fmpy/c-code``)."""
    import fmpy  # fmpy: only for its FMI 2 headers

    d = Path(fmpy.__file__).resolve().parent / "c-code"
    missing = [h for h in FMI2_HEADERS if not (d / h).is_file()]
    if missing:
        raise FmuBuildError(f"FMI headers: {missing} not found in {d} (fmpy installation incomplete)")
    return d


class CompilerNotFoundError(FmuBuildError):
    """No C compiler to build the kernel."""


def _kernel_filename() -> str:
    ext = {"Linux": ".so", "Darwin": ".dylib", "Windows": ".dll"}.get(platform.system(), ".so")
    return "gearkernel" + ext


def find_c_compiler() -> str:
    """The C compiler: ``$CC``, else gcc, else cc.  Raises :class:`CompilerNotFoundError`."""
    for cand in (os.environ.get("CC"), "gcc", "cc"):
        if cand and shutil.which(cand):
            return shutil.which(cand)
    raise CompilerNotFoundError("C compiler: none found (tried $CC, gcc, cc); the FMU's kernel is compiled "
                                "at build time -- install gcc or set CC")


def compile_kernel(dest_dir, *, cc: Optional[str] = None) -> Path:
    """Compile gearkernel.c into a shared library in ``dest_dir``; return its path.

    Command: ``<cc> -O2 -fPIC -shared -ffp-contract=off -std=c99 -o <lib> gearkernel.c -lm``.
    """
    cc = cc or find_c_compiler()
    dest = Path(dest_dir)
    dest.mkdir(parents=True, exist_ok=True)
    lib = dest / _kernel_filename()
    cmd = [cc, *CFLAGS, "-o", str(lib), str(KERNEL_SOURCE), "-lm"]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    except OSError as exc:
        raise CompilerNotFoundError(f"C compiler {cc!r}: cannot run ({exc})") from None
    if proc.returncode != 0:
        raise FmuBuildError(f"kernel: compilation failed ({' '.join(cmd)}):\n{proc.stderr}")
    return lib


def _compiler_version(cc: str) -> str:
    try:
        return subprocess.run([cc, "--version"], capture_output=True, text=True, timeout=30).stdout.splitlines()[0]
    except (OSError, IndexError, subprocess.SubprocessError):
        return "unknown"


def _sha256_file(p: Path) -> str:
    return hashlib.sha256(Path(p).read_bytes()).hexdigest()


def _check_positive(name: str, value, allow_zero: bool = False) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise FmuBuildError(f"{name}: expected a number, got {value!r}") from None
    if not (v == v and abs(v) != float("inf")):
        raise FmuBuildError(f"{name}: must be finite, got {value!r}")
    if v < 0 or (v == 0 and not allow_zero):
        raise FmuBuildError(f"{name}: must be {'>= 0' if allow_zero else '> 0'}, got {value!r}")
    return v


def _check_finite(name: str, value) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise FmuBuildError(f"{name}: expected a number, got {value!r}") from None
    if not (v == v and abs(v) != float("inf")):
        raise FmuBuildError(f"{name}: must be finite, got {value!r}")
    return v


def _damping_model_code(damping_model) -> int:
    if isinstance(damping_model, str):
        damping_model = current_spelling("damping_model", damping_model)
        if damping_model not in DAMPING_MODELS:
            raise FmuBuildError(f"damping_model: {damping_model!r} not one of {sorted(DAMPING_MODELS)}")
        return DAMPING_MODELS[damping_model]
    if isinstance(damping_model, bool) or damping_model not in (0, 1):
        raise FmuBuildError(f"damping_model: {damping_model!r} must be 0 (elastobacklash) or 1 (contact_zone)")
    return int(damping_model)


def _replace_class_name(template: str, class_name: str) -> str:
    text, n = re.subn(rf"\b{TEMPLATE_CLASS}\b", class_name, template)
    if n == 0 or f"class {class_name}(Fmi2Slave):" not in text:
        raise FmuBuildError(f"{SLAVE_TEMPLATE}: template lacks 'class {TEMPLATE_CLASS}(Fmi2Slave):'")
    return text


def _integrator_code(integrator, slots: int) -> int:
    """0/'rk4', 1/'rk4_kink' or 2/'rk4_node' (gearfmu.dynamics.native.INTEGRATORS) -> the kernel code."""
    if isinstance(integrator, str):
        if integrator not in INTEGRATORS:
            raise FmuBuildError(f"integrator: {integrator!r} not one of {sorted(INTEGRATORS)}")
        code = INTEGRATORS[integrator]
    elif isinstance(integrator, bool) or integrator not in INTEGRATORS.values():
        raise FmuBuildError(f"integrator: {integrator!r} must be 0 (rk4), 1 (rk4_kink) or 2 (rk4_node)")
    else:
        code = int(integrator)
    if code != 0 and slots > KINK_MAX_SLOTS:
        raise FmuBuildError(f"integrator: rk4_kink/rk4_node handle at most {KINK_MAX_SLOTS} slots, the tables have {slots}")
    return code


def temperature_input(variables, tables: MeshTables):
    """The temperature input (:attr:`MeshTables.temperature_input`: ``bulk_temperature``,
    ``oil_temperature`` or ``gearbox_temperature``) for tables with a temperature
    axis: start = :attr:`MeshTables.default_temperature_C`, min/max = the axis
    ends (degC).  Returns (variables, start or None)."""
    if not tables.has_temperature_axis:
        return list(variables), None

    name = tables.temperature_input
    lo, hi = tables.temperature_range_C
    start = tables.default_temperature_C
    out = [replace(v, start=start, min=lo, max=hi) if v.name == name else v for v in variables]
    if not any(v.name == name for v in out):
        raise FmuBuildError(f"{name}: the tables have a temperature axis but the interface spec "
                            f"has no {name!r} input (a 'requires' entry for it)")
    return out, start


def check_output_arguments(out_path, scene_text) -> Path:
    """``out_path`` as a Path ending in .fmu and ``scene_text`` a str or None (FmuBuildError
    naming the field otherwise); shared by both FMU builders."""
    if scene_text is not None and not isinstance(scene_text, str):
        raise FmuBuildError(f"scene_text: expected str or None, got {type(scene_text).__name__}")
    out_path = Path(out_path)
    if out_path.suffix != ".fmu":
        raise FmuBuildError(f"out_path: must end in .fmu, got {str(out_path)!r}")
    return out_path


def check_build_arguments(tables, *, model_name, damping_ratio, pinion_speed_start_rad_s,
                          pinion_angle_start_rad, pinion_torque_start_Nm, gear_torque_start_Nm,
                          max_step_s, stop_time_s, output_interval_s, damping_model):
    """Check the arguments both FMU builders share (pythonfmu and standalone runtimes).

    Returns (damping ratio, pinion speed rad/s, pinion angle rad, pinion torque N*m,
    gear torque N*m, max step s, stop time s, output interval s, damping model code);
    raises :class:`FmuBuildError` naming the field.  ``gear_torque_start_Nm`` None
    means the static balance ``pinion_torque_start_Nm * Rb2/Rb1``.
    """
    if not isinstance(tables, MeshTables):
        raise FmuBuildError(f"tables: expected a MeshTables, got {type(tables).__name__}")
    tables.validate()
    if not isinstance(model_name, str) or not model_name.strip():
        raise FmuBuildError(f"model_name: must be a non-empty string, got {model_name!r}")
    zeta = _check_positive("damping_ratio", damping_ratio, allow_zero=True)
    w0 = _check_finite("pinion_speed_start_rad_s", pinion_speed_start_rad_s)
    th0 = _check_finite("pinion_angle_start_rad", pinion_angle_start_rad)
    T1 = _check_finite("pinion_torque_start_Nm", pinion_torque_start_Nm)
    if gear_torque_start_Nm is None:
        gear_torque_start_Nm = T1 * tables.base_radius_gear_m / tables.base_radius_pinion_m
    T2 = _check_finite("gear_torque_start_Nm", gear_torque_start_Nm)
    hmax = _check_positive("max_step_s", max_step_s)
    tstop = _check_positive("stop_time_s", stop_time_s)
    if output_interval_s is None:  # the scene's rule (gearfmu.scene.reader.default_output_interval_s)

        output_interval_s = min(default_output_interval_s(w0, tables.teeth_pinion), tstop)
    dt = _check_positive("output_interval_s", output_interval_s)
    return zeta, w0, th0, T1, T2, hmax, tstop, dt, _damping_model_code(damping_model)


def build_fmu(tables: MeshTables, out_path, *, model_name: str = "gearpair", damping_ratio: float = 0.02,
              pinion_speed_start_rad_s: float = 100.0, pinion_torque_start_Nm: float = 100.0,
              gear_torque_start_Nm: Optional[float] = None, max_step_s: float = 1e-5,
              damping_model: Union[int, str] = 0, stop_time_s: float = 0.1,
              output_interval_s: Optional[float] = None, scene_text: Optional[str] = None, pinion_angle_start_rad: float = 0.0,
              spec_path=None, cc: Optional[str] = None, integrator: Union[int, str] = 1,
              envelope: Optional[dict] = None) -> Path:
    """Build an FMI 2.0 CS FMU of the gear pair described by ``tables``; return its path.

    Units: damping_ratio (1), speeds rad/s, torques N*m, times s, angles rad.
    ``gear_torque_start_Nm`` None means the static balance
    ``pinion_torque_start_Nm * Rb2/Rb1``.  ``damping_model``: 0 or
    "elastobacklash", 1 or "contact_zone" (docs/model.md).  ``integrator``: 0 or
    "rk4", 1 or "rk4_kink" (default; docs/model.md "Integration", docs/dynamics_validation.md;
    FMU parameter ``integrator``).  ``stop_time_s`` and
    ``output_interval_s`` go to the DefaultExperiment (stopTime, stepSize); ``output_interval_s``
    None = :func:`gearfmu.scene.reader.default_output_interval_s` at the start speed.
    ``envelope``: :func:`gearfmu.scene.envelope.fmu_envelope_record` (None: the tables' own range,
    "not verified"), checked at run time and recorded (docs/fmu.md "Verified envelope").
    The FMU is written to a temporary name beside ``out_path`` and renamed
    at the end, so a failed build never leaves a half-written FMU under the
    final name.
    """
    zeta, w0, th0, T1, T2, hmax, tstop, dt, dm = check_build_arguments(
        tables, model_name=model_name, damping_ratio=damping_ratio,
        pinion_speed_start_rad_s=pinion_speed_start_rad_s, pinion_angle_start_rad=pinion_angle_start_rad,
        pinion_torque_start_Nm=pinion_torque_start_Nm, gear_torque_start_Nm=gear_torque_start_Nm,
        max_step_s=max_step_s, stop_time_s=stop_time_s, output_interval_s=output_interval_s,
        damping_model=damping_model)
    ig = _integrator_code(integrator, tables.slots)
    out_path = check_output_arguments(out_path, scene_text)

    spec = load_spec(spec_path)
    variables = expand_variables(spec, tables.slots, features_of(tables))
    variables = apply_start_values(variables, {
        "pinion_torque": T1, "gear_torque": T2, "damping_ratio": zeta, "pinion_speed_start": w0,
        "pinion_angle_start": th0, "max_step": hmax, "damping_model": dm, "integrator": ig})
    variables, temp0 = temperature_input(variables, tables)


    env_rec = envelope if envelope is not None else fmu_envelope_record(tables)
    meta_bytes, bin_bytes = tables.to_bytes()
    digest = hashlib.sha256(meta_bytes + bin_bytes + repr((model_name, zeta, w0, th0, T1, T2, hmax, dm, ig)).encode())
    suffix = f"{digest.hexdigest()[:12]}_{uuid.uuid4().hex[:8]}"
    identifier = f"gearfmu_{suffix}"       # module name and modelIdentifier
    class_name = f"GearFmu_{suffix}"
    guid = "{" + str(uuid.uuid4()) + "}"
    cc = cc or find_c_compiler()

    with tempfile.TemporaryDirectory(prefix="gearfmu_build_") as tmpd:
        tmp = Path(tmpd)
        stage = tmp / "stage"
        stage.mkdir()
        (stage / "tables.json").write_bytes(meta_bytes)
        (stage / "tables.bin").write_bytes(bin_bytes)
        lib = compile_kernel(stage, cc=cc)
        src_dir = stage / "kernel_src"
        src_dir.mkdir()
        shutil.copy2(KERNEL_SOURCE, src_dir / KERNEL_SOURCE.name)
        shutil.copy2(KERNEL_HEADER, src_dir / KERNEL_HEADER.name)
        (src_dir / "BUILD.txt").write_text(
            f"{Path(cc).name} {' '.join(CFLAGS)} -o {lib.name} gearkernel.c -lm\n", encoding="utf-8")
        sha = {name: _sha256_file(stage / name) for name in ("tables.json", "tables.bin", lib.name)}
        runtime = {
            "format": "gearfmu-runtime", "version": 1, "model_identifier": identifier,
            "kernel_file": lib.name, "kernel_abi_version": KERNEL_ABI_VERSION, "slots": tables.slots,
            "sha256": sha, "variables": runtime_variable_table(variables),
            "envelope": runtime_envelope(env_rec),
        }
        (stage / "gearfmu_runtime.json").write_text(json.dumps(runtime, indent=1), encoding="utf-8")
        now = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
        shim = compile_pyshim(tmp / "shim", identifier, cc=cc)
        (stage / PYSHIM_CONFIG).write_text(pyshim_config(f"{identifier}.pythonfmu.so"), encoding="utf-8")
        shim_src = stage / "pyshim_src"
        shim_src.mkdir()
        shutil.copy2(PYSHIM_SOURCE, shim_src / PYSHIM_SOURCE.name)
        (shim_src / "BUILD.txt").write_text(
            f"{Path(cc).name} {' '.join(PYSHIM_CFLAGS)} -I<FMI 2.0 headers> -o <modelIdentifier>.so "
            f"pyshim.c -ldl -lpthread\n", encoding="utf-8")
        files = [stage / n for n in ("tables.json", "tables.bin", lib.name, "gearfmu_runtime.json",
                                     PYSHIM_CONFIG)]
        if scene_text is not None:
            (stage / "scene.toml").write_text(scene_text, encoding="utf-8")
            files.append(stage / "scene.toml")
        provenance = {
            "gearfmu_version": __version__, "built_utc": now, "model_name": model_name,
            "model_identifier": identifier, "guid": guid,
            "parameters": {"damping_ratio": zeta, "pinion_speed_start_rad_s": w0, "pinion_angle_start_rad": th0,
                           "pinion_torque_start_Nm": T1, "gear_torque_start_Nm": T2, "max_step_s": hmax,
                           "damping_model": dm, "integrator": ig, "stop_time_s": tstop,
                           "output_interval_s": dt,
                           **({} if temp0 is None else {"bulk_temperature_start_C": temp0})},
            "tables_sha256": hashlib.sha256(bin_bytes).hexdigest(),
            "tables_provenance": tables.provenance,
            "kernel": {"file": lib.name, "sha256": sha[lib.name], "compiler": _compiler_version(cc),
                       "flags": list(CFLAGS), "source_sha256": _sha256_file(KERNEL_SOURCE)},
            "scene_sha256": None if scene_text is None else hashlib.sha256(scene_text.encode()).hexdigest(),
            "python": sys.version.split()[0], "platform": platform.platform(),
            "spec": str(Path(spec.path).name),
        }
        (stage / "provenance.json").write_text(json.dumps(provenance, indent=1, default=str), encoding="utf-8")
        files.append(stage / "provenance.json")

        script_dir = tmp / "script"
        script_dir.mkdir()
        script = script_dir / f"{identifier}.py"
        script.write_text(_replace_class_name(SLAVE_TEMPLATE.read_text(encoding="utf-8"), class_name),
                          encoding="utf-8")
        raw_fmu = tmp / "raw" / f"{identifier}.fmu"
        raw_fmu.parent.mkdir()
        _pythonfmu_build(script, raw_fmu, [*files, src_dir, shim_src])

        record = validation_record(
            tables, runtime="pythonfmu", model_identifier=identifier, stop_time_s=tstop, output_interval_s=dt,
            parameters={k: v for k, v in provenance["parameters"].items() if k not in ("stop_time_s", "output_interval_s")},
            scene_text=scene_text, compiler=provenance["kernel"]["compiler"], envelope=env_rec)
        record[ENVELOPE_FILE] = json.dumps(env_rec, indent=1).encode("utf-8")

        with zipfile.ZipFile(raw_fmu) as zin:
            registered = zin.read("modelDescription.xml")
            check_registered(registered, variables)
            xml = model_description_xml(spec, variables, model_name=model_name, model_identifier=identifier,
                                        guid=guid, stop_time_s=tstop, step_size_s=dt,
                                        generation_tool=f"gearfmu {__version__}", generation_date=now,
                                        version=__version__, description_note=envelope_note(env_rec))
            check_model_description(xml, variables)
            out_path.parent.mkdir(parents=True, exist_ok=True)
            part = out_path.with_name(out_path.name + f".part-{uuid.uuid4().hex[:8]}")
            plat = _platform_dir()
            try:
                with zipfile.ZipFile(part, "w", compression=zipfile.ZIP_DEFLATED) as zout:
                    zout.writestr("modelDescription.xml", xml)
                    for info in zin.infolist():
                        n = info.filename
                        if n == "modelDescription.xml":
                            continue
                        if n.startswith("binaries/") and not n.startswith(f"binaries/{plat}/"):
                            continue  # the kernel is compiled for this platform only
                        if shim is not None and n == f"binaries/{plat}/{identifier}.so":  # behind the loader
                            zout.writestr(f"binaries/{plat}/{identifier}.pythonfmu.so", zin.read(n))
                            zout.write(shim, n)
                            continue
                        zout.writestr(info, zin.read(n))
                    for rel, data in record.items():  # resources/validation/ (docs/standalone.md), envelope.json
                        zout.writestr(rel, data)
                os.replace(part, out_path)
            finally:
                if part.exists():
                    part.unlink()
    return out_path


def compile_pyshim(dest_dir, identifier: str, *, cc: Optional[str] = None) -> Optional[Path]:
    """Compile the loader ``gearfmu/fmu/runtime/pyshim.c`` as ``<identifier>.so`` in ``dest_dir``.

    It becomes the FMU's binary and loads libpython and pythonfmu's wrapper on
    the first ``fmi2Instantiate`` (docs/fmu.md "The binary").  Linux only: on
    other systems returns None and the FMU keeps pythonfmu's wrapper as its binary.
    """
    if platform.system() != "Linux":
        return None  # elsewhere pythonfmu's wrapper stays the FMU's binary
    cc = cc or find_c_compiler()
    dest = Path(dest_dir)
    dest.mkdir(parents=True, exist_ok=True)
    lib = dest / f"{identifier}.so"
    cmd = [cc, *PYSHIM_CFLAGS, f"-I{fmi2_header_dir()}", "-o", str(lib), str(PYSHIM_SOURCE), "-ldl", "-lpthread"]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    except OSError as exc:
        raise CompilerNotFoundError(f"C compiler {cc!r}: cannot run ({exc})") from None
    if proc.returncode != 0:
        raise FmuBuildError(f"pyshim: compilation failed ({' '.join(cmd)}):\n{proc.stderr}")
    return lib


def pyshim_config(wrapper_name: str) -> str:
    """``resources/gearfmu_pyshim.txt``: the Python of this build (version, shared
    library, executable, whose environment provides numpy) and the wrapper's
    file name, one ``key=value`` a line."""
    ver = f"{sys.version_info.major}.{sys.version_info.minor}"
    soname = sysconfig.get_config_var("INSTSONAME") or f"libpython{ver}.so.1.0"
    libdir = sysconfig.get_config_var("LIBDIR") or ""
    path = os.path.join(libdir, soname) if sysconfig.get_config_var("Py_ENABLE_SHARED") else ""
    if path and not os.path.isfile(path):
        path = ""
    if not soname.endswith(".so") and ".so." not in soname:  # a static libpython: ask the loader by name
        soname = f"libpython{ver}.so.1.0"
    return (f"python_version={ver}\nlibpython={path}\nlibpython_soname={soname}\n"
            f"python_executable={sys.executable}\nwrapper={wrapper_name}\n")


def _platform_dir() -> str:
    bits = "64" if sys.maxsize > 2 ** 32 else "32"
    return {"Windows": "win", "Linux": "linux", "Darwin": "darwin"}.get(platform.system(), "unknown") + bits


def _pythonfmu_build(script: Path, dest: Path, project_files) -> None:
    """Run pythonfmu's FmuBuilder and undo its side effects on this process
    (it imports the script as a module and puts its folder on sys.path)."""
    from pythonfmu import FmuBuilder  # pythonfmu: heavy, only while building

    module = script.stem
    path_before = list(sys.path)
    try:
        FmuBuilder.build_FMU(script, dest=dest, project_files=[str(p) for p in project_files])
    finally:
        sys.path[:] = path_before
        sys.modules.pop(module, None)
    if not dest.is_file():
        raise FmuBuildError(f"out_path: pythonfmu produced no FMU at {dest}")
