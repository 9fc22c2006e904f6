"""Build an FMI 2.0 Co-Simulation FMU from tooth-pair tables.

The FMU is a pythonfmu FMU whose Python slave (``gearfmu/fmu/runtime/gearfmu_slave.py``,
a template) is a thin FMI layer over the C kernel ``gearfmu/fmu/kernel/`` (``gearkernel.c`` and
the files beside it, docs/model.md) and the FMU behaviour the standalone runtime shares (``gkfmu.c``:
input checks, steps, messages), compiled here with the system C compiler and shipped in the
FMU's ``resources/`` together with its sources; the slave binds the library's functions with
the declarative table ``gearfmu/fmu/runtime/kernel_api.py``, shipped beside it.  The model description is
produced from ``modeldescription/variables.toml`` (:mod:`gearfmu.fmu.modeldesc`),
checked against what the slave registers, and replaces pythonfmu's.

FMU layout (docs/fmu.md)::

    modelDescription.xml                 from the spec
    binaries/linux64/<id>.so             the loader (gearfmu/fmu/runtime/pyshim.c) in front of
    binaries/linux64/<id>.pythonfmu.so   pythonfmu's FMI wrapper
    resources/<id>.py                    the slave (unique module and class name)
    resources/<id>_kernel_api.py         the kernel's function table (runtime/kernel_api.py)
    resources/pythonfmu/                 pythonfmu's Python side
    resources/tables.json, tables.bin    the tables (gearfmu/tables/mesh_tables.py format)
    resources/gearkernel.so              the compiled kernel with the FMU layer (gkfmu.c) over it
    resources/kernel_src/                the kernel's sources (gearkernel.c|h, gk_*.c|h, gkfmu.c|h) and
                                         the compile command
    resources/gearfmu_runtime.json       variables, kernel name, SHA-256 sums
    resources/gearfmu_pyshim.txt         the Python version, the id of the build's Python record,
                                         the wrapper's name, the variable table (no path)
    resources/pyshim_src/                the loader's source and its compile command
    resources/provenance.json            who/what/when built this FMU
    resources/scene.toml                 the scene (when given)

The paths of the build's Python (its executable and shared library) are not in the FMU: they go
to a record outside it, ``<gearfmu cache>/pythons/<id>.txt`` (:func:`record_build_python`), which
the loader reads on this machine; elsewhere ``$GEARFMU_PYTHON`` names the Python to use
(docs/fmu.md "The binary").
"""
from __future__ import annotations

import datetime
import hashlib
import json
import os
import platform
import re
import shutil
import sys
import tempfile
import uuid
import zipfile
import xml.etree.ElementTree as ET
from importlib.metadata import version
from pathlib import Path
from typing import Optional, Union
import sysconfig

from .. import __version__
from ..common.cache import cache_dir
from ..common.progress import ticking
from ..common.settings import RunSettings
from .build_steps import (CFLAGS, FMI2_HEADERS, FMU_LAYER_ABI_VERSION, FMU_LAYER_HEADER,  # noqa: F401
                          FMU_LAYER_SOURCE, KERNEL_ABI_VERSION, KERNEL_DIR, KERNEL_LIBRARY_HEADERS,
                          KERNEL_LIBRARY_SOURCES, CompilerNotFoundError, FmuBuildError, check_arguments,
                          check_output_arguments, compiler_version,
                          find_c_compiler, fmi2_header_dir, fmu_digest, fmu_zip, interface_variables,
                          model_description, record_parameters, run_compiler, scene_sha256, sha256_file,
                          start_values, temperature_input, variable_table_lines, write_scene, write_tables)
from .modeldesc import check_registered, load_spec, runtime_variable_table
from ..tables.mesh_tables import MeshTables
from .fmudoc import DOC_FILES, documentation_html
from .validation import VALIDATION_DIR, validation_record
from .envelope import ENVELOPE_FILE, envelope_json, envelope_note, fmu_envelope_record, runtime_envelope

HERE = Path(__file__).resolve().parent
SLAVE_TEMPLATE = HERE / "runtime" / "gearfmu_slave.py"
#: the kernel's function table the slave imports, and the name its template imports it by inside
#: the FMU (replaced by ``<identifier>_kernel_api``: modules of FMUs in one process must differ)
KERNEL_API = HERE / "runtime" / "kernel_api.py"
TEMPLATE_KERNEL_API = "gearfmu_kernel_api"
PYSHIM_SOURCE = HERE / "runtime" / "pyshim.c"
#: the binary's C files: the loader and model of the Python slave (pyshim.c) under the standalone
#: runtime's FMI 2.0 layer and plumbing (docs/fmu.md "The binary"), and the headers they include
PYSHIM_SOURCES = (PYSHIM_SOURCE, HERE / "standalone" / "fmi2_gear.c", HERE / "standalone" / "fmi_common.c")
PYSHIM_HEADERS = (HERE / "standalone" / "fmi_common.h", HERE / "standalone" / "gf_model.h")
PYSHIM_CONFIG = "gearfmu_pyshim.txt"
#: the folder of gearfmu's cache (:func:`gearfmu.common.cache.cache_dir`) holding the records of
#: the Pythons pythonfmu FMUs were built with, and the first line of a record (pyshim.c reads both)
PYTHON_RECORDS = "pythons"
PYTHON_RECORD_FORMAT = "format=gearfmu-python-record 1"
#: the environment variable naming the Python executable the loader starts instead (pyshim.c)
PYTHON_OVERRIDE_VARIABLE = "GEARFMU_PYTHON"
#: the binary's compile flags (docs/fmu.md "The binary"); it links no Python
PYSHIM_CFLAGS = ("-O2", "-fPIC", "-shared", "-std=c99", "-fvisibility=hidden")
TEMPLATE_CLASS = "GearFmuSlave"


def _kernel_filename() -> str:
    ext = {"Linux": ".so", "Darwin": ".dylib", "Windows": ".dll"}.get(platform.system(), ".so")
    return "gearkernel" + ext


def _kernel_key(cc: str) -> Optional[str]:
    """SHA-256 of everything the kernel compilation reads: the compiler file (resolved path, size,
    modification time), :data:`CFLAGS`, the library's name, the C files it compiles (in order) and
    the bytes of every C source and header of the kernel folder; None when the compiler is not a
    file (then nothing is kept)."""
    p = Path(shutil.which(cc) or cc)
    if not p.is_file():
        return None
    st = p.stat()
    h = hashlib.sha256()
    for part in (str(p.resolve()), str(st.st_size), str(st.st_mtime_ns), " ".join(CFLAGS), _kernel_filename(),
                 " ".join(f.name for f in KERNEL_LIBRARY_SOURCES)):
        h.update(part.encode() + b"\0")
    for f in sorted({*KERNEL_DIR.glob("*.c"), *KERNEL_DIR.glob("*.h"), *KERNEL_LIBRARY_SOURCES,
                     *KERNEL_LIBRARY_HEADERS}):
        h.update(f.name.encode() + b"\0" + f.read_bytes())
    return h.hexdigest()


def compile_kernel(dest_dir, *, cc: Optional[str] = None) -> Path:
    """Compile the kernel (:data:`~gearfmu.fmu.build_steps.KERNEL_SOURCES`) and the FMU layer over it
    (gkfmu.c) into a shared library in ``dest_dir``; return its path.

    Command: ``<cc> -O2 -fPIC -shared -ffp-contract=off -std=c99 -o <lib> gearkernel.c gk_model.c ...
    gkfmu.c -lm``.
    The library is kept in gearfmu's file cache (:func:`gearfmu.common.cache.cache_dir`, folder
    ``kernels``) under :func:`_kernel_key`; a later build with the same compiler, flags and
    sources copies it instead of compiling again (the compiler gives the same bytes for the same
    inputs).  A cache folder that cannot be written only costs the next build a compilation.
    """
    cc = cc or find_c_compiler()
    dest = Path(dest_dir)
    dest.mkdir(parents=True, exist_ok=True)
    lib = dest / _kernel_filename()
    key = _kernel_key(cc)
    kept = cache_dir("kernels") / f"{key[:32]}-{lib.name}" if key else None
    if kept is not None and kept.is_file():
        shutil.copy2(kept, lib)
        return lib
    with ticking(f"compiling the FMU's C kernel ({Path(cc).name}; kept for later builds)"):
        run_compiler([cc, *CFLAGS, "-o", str(lib), *(str(f) for f in KERNEL_LIBRARY_SOURCES), "-lm"], "kernel")
    if kept is not None:
        try:  # atomic publish: a concurrent build sees either no file or the whole library
            kept.parent.mkdir(parents=True, exist_ok=True)
            part = kept.with_name(kept.name + f".{os.getpid()}.part")
            shutil.copy2(lib, part)
            os.replace(part, kept)
        except OSError:
            pass
    return lib


def _slave_text(template: str, class_name: str, kernel_api: str) -> str:
    """The slave of one FMU: the template with its class named ``class_name`` and the kernel's
    function table imported as the module ``kernel_api`` (the FMU's copy of kernel_api.py)."""
    text, n = re.subn(rf"\b{TEMPLATE_CLASS}\b", class_name, template)
    if n == 0 or f"class {class_name}(Fmi2Slave):" not in text:
        raise FmuBuildError(f"{SLAVE_TEMPLATE}: template lacks 'class {TEMPLATE_CLASS}(Fmi2Slave):'")
    text, n = re.subn(rf"\b{TEMPLATE_KERNEL_API}\b", kernel_api, text)
    if n == 0:
        raise FmuBuildError(f"{SLAVE_TEMPLATE}: template lacks the import of {TEMPLATE_KERNEL_API}")
    return text


def build_fmu(tables: MeshTables, out_path, settings: Optional[RunSettings] = None, *, model_name: str = "gearpair",
              scene_text: Optional[str] = None, spec_path=None, cc: Optional[str] = None,
              envelope: Optional[dict] = None,
              damping_ratio: Optional[float] = None, pinion_speed_start_rad_s: Optional[float] = None,
              pinion_torque_start_Nm: Optional[float] = None, gear_torque_start_Nm: Optional[float] = None,
              max_step_s: Optional[float] = None, damping_model: Union[int, str, None] = None,
              stop_time_s: Optional[float] = None, output_interval_s: Optional[float] = None,
              pinion_angle_start_rad: Optional[float] = None, integrator: Union[int, str, None] = None) -> Path:
    """Build an FMI 2.0 CS FMU of the gear pair described by ``tables``; return its path.

    ``settings``: the run settings (:class:`gearfmu.common.settings.RunSettings`; None: its
    defaults): the start values of the FMU's parameters and inputs and its DefaultExperiment
    (``stop_time_s``, ``output_interval_s``: stopTime, stepSize).  The keyword arguments of the
    same names, when given, replace its fields.  Units: damping_ratio (1), speeds rad/s, torques
    N*m, times s, angles rad.  Automatic values are resolved on the tables as the native solver
    resolves them (:func:`gearfmu.dynamics.native.resolve_settings`): ``gear_torque_start_Nm``
    None means the static balance ``pinion_torque_start_Nm * Rb2/Rb1``, ``max_step_s`` None the
    automatic step at 1.5 x the start speed, ``output_interval_s`` None
    :func:`gearfmu.common.settings.default_output_interval_s` at the start speed.
    ``damping_model``: "elastobacklash" (0) or "contact_zone" (1) (docs/model.md).
    ``integrator``: "rk4" (0), "rk4_kink" (1), "rk4_node" (2, the default,
    :data:`~gearfmu.common.vocabulary.DEFAULT_INTEGRATOR`; docs/model.md "Integration",
    docs/native.md "rk4_node") or "rk4_seg" (3, docs/model.md "rk4_seg"; FMU parameter ``integrator``).
    ``envelope``: :func:`gearfmu.fmu.envelope.fmu_envelope_record` (None: the tables' own range,
    "not verified"), checked at run time and recorded (docs/fmu.md "Verified envelope").
    The FMU is written to a temporary name beside ``out_path`` and renamed
    at the end, so a failed build never leaves a half-written FMU under the
    final name.
    """
    s, out_path = check_arguments(tables, out_path, settings, scene_text=scene_text, model_name=model_name,
                                  damping_ratio=damping_ratio, pinion_speed_start_rad_s=pinion_speed_start_rad_s,
                                  pinion_angle_start_rad=pinion_angle_start_rad,
                                  pinion_torque_start_Nm=pinion_torque_start_Nm, gear_torque_start_Nm=gear_torque_start_Nm,
                                  max_step_s=max_step_s, stop_time_s=stop_time_s, output_interval_s=output_interval_s,
                                  damping_model=damping_model, integrator=integrator)
    tstop, dt = s.stop_time_s, s.output_interval_s
    spec = load_spec(spec_path)
    variables, temp0 = interface_variables(spec, tables, start_values(s))
    env_rec = envelope if envelope is not None else fmu_envelope_record(tables)
    meta_bytes, bin_bytes = tables.to_bytes()
    suffix = f"{fmu_digest(meta_bytes, bin_bytes, model_name, s)[:12]}_{uuid.uuid4().hex[:8]}"
    identifier = f"gearfmu_{suffix}"       # module name and modelIdentifier
    class_name = f"GearFmu_{suffix}"
    guid = "{" + str(uuid.uuid4()) + "}"
    cc = cc or find_c_compiler()

    with tempfile.TemporaryDirectory(prefix="gearfmu_build_") as tmpd:
        tmp = Path(tmpd)
        stage = tmp / "stage"
        stage.mkdir()
        write_tables(stage, meta_bytes, bin_bytes)
        lib = compile_kernel(stage, cc=cc)
        src_dir = stage / "kernel_src"
        src_dir.mkdir()
        for f in (*KERNEL_LIBRARY_SOURCES, *KERNEL_LIBRARY_HEADERS):
            shutil.copy2(f, src_dir / f.name)
        (src_dir / "BUILD.txt").write_text(
            f"{Path(cc).name} {' '.join(CFLAGS)} -o {lib.name} {' '.join(f.name for f in KERNEL_LIBRARY_SOURCES)} -lm\n",
            encoding="utf-8")
        sha = {name: sha256_file(stage / name) for name in ("tables.json", "tables.bin", lib.name)}
        runtime = {
            "format": "gearfmu-runtime", "version": 1, "model_identifier": identifier,
            "kernel_file": lib.name, "kernel_abi_version": KERNEL_ABI_VERSION,
            "fmu_layer_abi_version": FMU_LAYER_ABI_VERSION, "slots": tables.slots,
            "sha256": sha, "variables": runtime_variable_table(variables),
            "envelope": runtime_envelope(env_rec),
        }
        (stage / "gearfmu_runtime.json").write_text(json.dumps(runtime, indent=1), encoding="utf-8")
        now = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
        shim = compile_pyshim(tmp / "shim", identifier, cc=cc)
        if shim is not None:  # the loader's record of this build's Python, outside the FMU
            record_build_python()
        (stage / PYSHIM_CONFIG).write_text(pyshim_config(f"{identifier}.pythonfmu.so", guid=guid,
                                                         variables=variables), encoding="utf-8")
        shim_src = stage / "pyshim_src"
        shim_src.mkdir()
        for f in (*PYSHIM_SOURCES, *PYSHIM_HEADERS):
            shutil.copy2(f, shim_src / f.name)
        (shim_src / "BUILD.txt").write_text(
            f"{Path(cc).name} {' '.join(PYSHIM_CFLAGS)} -I. -I<FMI 2.0 headers> -o <modelIdentifier>.so "
            f"{' '.join(f.name for f in PYSHIM_SOURCES)} -ldl -lpthread\n", encoding="utf-8")
        files = [stage / n for n in ("tables.json", "tables.bin", lib.name, "gearfmu_runtime.json",
                                     PYSHIM_CONFIG)]
        scene_file = write_scene(stage, scene_text)
        if scene_file is not None:
            files.append(scene_file)
        parameters = dict(record_parameters(s), stop_time_s=tstop, output_interval_s=dt)
        if temp0 is not None:  # after the experiment times (the record's key order)
            parameters["bulk_temperature_start_C"] = temp0
        provenance = {
            "gearfmu_version": __version__, "built_utc": now, "model_name": model_name,
            "model_identifier": identifier, "guid": guid, "parameters": parameters,
            "tables_sha256": hashlib.sha256(bin_bytes).hexdigest(),
            "tables_provenance": tables.provenance,
            "kernel": {"file": lib.name, "sha256": sha[lib.name], "compiler": compiler_version(cc),
                       "flags": list(CFLAGS),
                       "sources_sha256": {f.name: sha256_file(f) for f in (*KERNEL_LIBRARY_SOURCES,
                                                                           *KERNEL_LIBRARY_HEADERS)}},
            "scene_sha256": scene_sha256(scene_text),
            "python": sys.version.split()[0], "platform": platform.platform(),
            "spec": str(Path(spec.path).name),
        }
        (stage / "provenance.json").write_text(json.dumps(provenance, indent=1, default=str), encoding="utf-8")
        files.append(stage / "provenance.json")

        script_dir = tmp / "script"
        script_dir.mkdir()
        script = script_dir / f"{identifier}.py"
        api = script_dir / f"{identifier}_kernel_api.py"
        script.write_text(_slave_text(SLAVE_TEMPLATE.read_text(encoding="utf-8"), class_name, api.stem),
                          encoding="utf-8")
        shutil.copy2(KERNEL_API, api)
        raw_fmu = tmp / "raw" / f"{identifier}.fmu"
        raw_fmu.parent.mkdir()
        _pythonfmu_build(script, raw_fmu, [*files, api, src_dir, shim_src])

        record = validation_record(
            tables, s, runtime="pythonfmu", model_identifier=identifier, temperature_start_C=temp0,
            scene_text=scene_text, compiler=provenance["kernel"]["compiler"], envelope=env_rec)
        record[ENVELOPE_FILE] = envelope_json(env_rec).encode("utf-8")

        with zipfile.ZipFile(raw_fmu) as zin:
            check_registered(zin.read("modelDescription.xml"), variables)
            xml = model_description(spec, variables, 2, model_name=model_name, model_identifier=identifier,
                                    guid=guid, stop_time_s=tstop, step_size_s=dt,
                                    generation_tool=f"gearfmu {__version__}", generation_date=now,
                                    version=__version__, description_note=envelope_note(env_rec))
            plat = _platform_dir()
            with fmu_zip(out_path) as zout:
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
                page = documentation_html(  # documentation/index.html and _main.html (gearfmu.fmu.fmudoc)
                    model_name=model_name, model_identifier=identifier, fmi_version=2, runtime="pythonfmu",
                    generation_tool=f"gearfmu {__version__}", variables=variables,
                    description=ET.fromstring(xml).get("description", ""), tables=tables,
                    parameters=record_parameters(s, temp0), envelope=env_rec, scene_text=scene_text,
                    validation_record=json.loads(record[f"{VALIDATION_DIR}/record.json"]),
                    platforms_text=f"binaries/{plat}: gearfmu's loader and pythonfmu's wrapper; the kernel "
                                   "(resources/) compiled on the build machine (docs/fmu.md)",
                    experiment={"start": 0.0, "stop": tstop, "step": dt})
                for rel in DOC_FILES(2):
                    zout.writestr(rel, page)
    return out_path


def compile_pyshim(dest_dir, identifier: str, *, cc: Optional[str] = None) -> Optional[Path]:
    """Compile the FMU's binary ``<identifier>.so`` in ``dest_dir``: the standalone runtime's FMI
    2.0 layer and plumbing over the model of ``gearfmu/fmu/runtime/pyshim.c``, which loads
    libpython and pythonfmu's wrapper on the first ``fmi2Instantiate`` and runs the Python slave
    through it (docs/fmu.md "The binary").  Linux only: on other systems returns None and the
    FMU keeps pythonfmu's wrapper as its binary.
    """
    if platform.system() != "Linux":
        return None  # elsewhere pythonfmu's wrapper stays the FMU's binary
    cc = cc or find_c_compiler()
    dest = Path(dest_dir)
    dest.mkdir(parents=True, exist_ok=True)
    lib = dest / f"{identifier}.so"
    run_compiler([cc, *PYSHIM_CFLAGS, f"-I{PYSHIM_HEADERS[0].parent}", f"-I{fmi2_header_dir()}", "-o", str(lib),
                  *(str(f) for f in PYSHIM_SOURCES), "-ldl", "-lpthread"], "pyshim")
    return lib


def python_environment() -> str:
    """What the Python environment of this build is, without a path: the interpreter's version,
    whether it is a virtual environment, and the versions of the modules the FMU needs."""
    kind = "a virtual environment of Python" if sys.prefix != sys.base_prefix else "Python"
    return f"{kind} {sys.version.split()[0]} with numpy {version('numpy')} and pythonfmu {version('pythonfmu')}"


def _libpython() -> tuple:
    """(version "3.X", path of this Python's shared library or "" when it has none, the soname the
    dynamic loader is asked for)."""
    ver = f"{sys.version_info.major}.{sys.version_info.minor}"
    soname = sysconfig.get_config_var("INSTSONAME") or f"libpython{ver}.so.1.0"
    libdir = sysconfig.get_config_var("LIBDIR") or ""
    path = os.path.join(libdir, soname) if sysconfig.get_config_var("Py_ENABLE_SHARED") else ""
    if path and not os.path.isfile(path):
        path = ""
    if not soname.endswith(".so") and ".so." not in soname:  # a static libpython: ask the loader by name
        soname = f"libpython{ver}.so.1.0"
    return ver, path, soname


def python_record() -> tuple:
    """(id, text) of the record of this build's Python that the loader reads outside the FMU:
    ``format=gearfmu-python-record 1``, then ``python_version``, ``python_executable``,
    ``libpython`` (absolute paths; empty when there is no shared library) and ``environment``
    (:func:`python_environment`), one ``key=value`` a line.  The id is the first 16 hex digits of
    the SHA-256 of the version and the two paths: one record per Python environment, shared by
    every FMU built in it, and a new one when the environment at a path changes its Python."""
    ver, path, _ = _libpython()
    rid = hashlib.sha256(f"{ver}\0{sys.executable}\0{path}".encode("utf-8", "surrogateescape")).hexdigest()[:16]
    return rid, (f"{PYTHON_RECORD_FORMAT}\npython_version={ver}\npython_executable={sys.executable}\n"
                 f"libpython={path}\nenvironment={python_environment()}\n")


_UNWRITABLE_SAID = False


def record_build_python() -> Optional[Path]:
    """Write :func:`python_record` to ``<gearfmu cache>/pythons/<id>.txt`` (written beside, then
    renamed: a reader sees the old record or the new one, never a part); return its path.  A
    folder that cannot be written (or a Python without an executable's path) is no failure of the
    build: None, and one line on stderr (once per process) saying that the FMU then runs in Python hosts, and in a C host with
    ``$GEARFMU_PYTHON`` set."""
    global _UNWRITABLE_SAID
    rid, text = python_record()
    path = cache_dir(PYTHON_RECORDS) / f"{rid}.txt"
    part = path.with_name(f"{path.name}.{os.getpid()}.{uuid.uuid4().hex[:8]}.part")
    try:
        if not sys.executable or any(c in p for p in (sys.executable, _libpython()[1]) for c in "\r\n"):
            raise OSError("this Python names no executable (sys.executable), or its path holds a line break")
        path.parent.mkdir(parents=True, exist_ok=True)
        part.write_bytes(text.encode("utf-8", "surrogateescape"))
        os.replace(part, path)
        return path
    except OSError as exc:
        if not _UNWRITABLE_SAID:
            _UNWRITABLE_SAID = True
            print(f"gearfmu: cannot write the record of this build's Python ({path}: "
                  f"{exc.strerror or exc}); the pythonfmu FMU runs in Python hosts, and in a C host with "
                  f"{PYTHON_OVERRIDE_VARIABLE} set to this Python's executable (docs/fmu.md)", file=sys.stderr)
        return None
    finally:
        try:
            part.unlink()
        except OSError:
            pass


def pyshim_config(wrapper_name: str, *, guid: str, variables) -> str:
    """``resources/gearfmu_pyshim.txt``: the Python version of this build, the soname of its shared
    library, the id of its record (:func:`python_record`), a description of its environment, the
    wrapper's file name, the GUID and the variable table the FMI layer serves
    (:func:`~gearfmu.fmu.build_steps.variable_table_lines`), one ``key=value`` a line.  No path:
    where the build's Python is lives in the record, outside the FMU."""
    ver, _, soname = _libpython()
    rid, _ = python_record()
    return (f"python_version={ver}\nlibpython_soname={soname}\npython_record={rid}\nwrapper={wrapper_name}\n"
            f"environment={python_environment()}\nguid={guid}\n" + "\n".join(variable_table_lines(variables)) + "\n")


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
