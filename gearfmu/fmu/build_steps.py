"""The build steps both FMU builders share (the pythonfmu runtime, :mod:`gearfmu.fmu.pythonfmu_build`,
and the standalone C runtime, :mod:`gearfmu.fmu.standalone_build`).

* the arguments: :func:`check_arguments` (the tables, the model name, the run settings --
  :class:`gearfmu.common.settings.RunSettings`, resolved on the tables --, the output path;
  one-line :class:`FmuBuildError` naming the field), :func:`start_values` and
  :func:`record_parameters` of the settings;
* the C side: the kernel's sources and flags (with the FMU layer over it, gkfmu.c, that both
  runtimes call), :func:`find_c_compiler`, :func:`run_compiler`;
* the interface: :func:`interface_variables` (modeldescription/variables.toml expanded for
  these tables, start values applied, the temperature input), :func:`model_description`;
* the resources: :func:`write_tables`, :func:`write_scene`, the envelope record
  (:mod:`gearfmu.fmu.envelope`), the validation record (:func:`gearfmu.fmu.validation.validation_record`);
* the FMU file: :func:`fmu_digest` (the identifier's hash), :func:`fmu_zip` (written under a
  temporary name beside the target and renamed at the end), :func:`zip_folder`;
* what a build knows before it writes a file: :class:`BuildInputs` (the checked tables and
  settings, the interface, the envelope record, the tables' bytes, the identifier and GUID).
"""
from __future__ import annotations

import contextlib
import hashlib
import os
import shutil
import subprocess
import uuid
import zipfile
from dataclasses import dataclass, replace
from xml.sax.saxutils import escape as xml_escape
from pathlib import Path
from typing import Optional, Tuple

from ..common.settings import RunSettings, checked
from ..dynamics.native import integrator_code, resolve_settings
from ..tables.mesh_tables import MeshTables
from .modeldesc import (apply_start_values, check_model_description, check_model_description3, expand_variables,
                        features_of, model_description_xml, model_description_xml3)

HERE = Path(__file__).resolve().parent
KERNEL_DIR = HERE / "kernel"
#: the kernel's C files in compile order (kernel/gk_internal.h says which holds what): the hot path
#: (forces, RK4, the event integrators, the step functions), the model and its setters, the stops of
#: the event integrators, the contact-zone cuts, the temperature axis, the verified envelope
KERNEL_SOURCES = tuple(KERNEL_DIR / n for n in ("gearkernel.c", "gk_model.c", "gk_stops.c", "gk_zones.c",
                                                 "gk_temperature.c", "gk_envelope.c"))
#: the kernel's headers: the public contract (gearkernel.h), what its files share, the table lookup, the
#: pair model's per-mesh pieces (force law, guards, mode decisions, root finder)
KERNEL_HEADERS = tuple(KERNEL_DIR / n for n in ("gearkernel.h", "gk_internal.h", "gk_lookup.h", "gk_pair.h"))
#: the FMU behaviour over the kernel both runtimes call (input checks, steps, messages; docs/fmu.md)
FMU_LAYER_SOURCE = KERNEL_DIR / "gkfmu.c"
FMU_LAYER_HEADER = KERNEL_DIR / "gkfmu.h"
#: the C files of the library both runtimes build from kernel/: the kernel and the FMU layer over it
KERNEL_LIBRARY_SOURCES = (*KERNEL_SOURCES, FMU_LAYER_SOURCE)
KERNEL_LIBRARY_HEADERS = (*KERNEL_HEADERS, FMU_LAYER_HEADER)
#: compile flags (no FMA contraction, so the kernel's arithmetic is the written one)
CFLAGS = ("-O2", "-fPIC", "-shared", "-ffp-contract=off", "-std=c99")
#: the FMI 2.0 standard headers the C layers are compiled against
FMI2_HEADERS = ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")
#: the FMI 3.0 standard headers
FMI3_HEADERS = ("fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h")


class FmuBuildError(ValueError):
    """The FMU cannot be built from these arguments; the message names the field."""


class CompilerNotFoundError(FmuBuildError):
    """No C compiler to build the kernel."""


def fmi2_header_dir() -> Path:
    """The FMI 2.0 standard's headers, unmodified (FMI 2.0.5; ``gearfmu/fmu/standalone/fmi2_headers``,
    README.txt there).  fmpy's copy (``fmpy/c-code``) ignores ``FMI2_FUNCTION_PREFIX``, so the
    sources of two FMUs compiled against it cannot link into one program."""
    d = HERE / "standalone" / "fmi2_headers"
    missing = [h for h in FMI2_HEADERS if not (d / h).is_file()]
    if missing:
        raise FmuBuildError(f"FMI headers: {missing} not found in {d} (gearfmu installation incomplete)")
    return d


def fmi3_header_dir() -> Path:
    """The FMI 3.0 standard's headers: fmpy's copy (``fmpy/c-code``), the standard's FMI 3.0.1
    headers unmodified (tests/fmu_hosts/test_source_fmus.py checks their prefix macros)."""
    import fmpy  # fmpy: only for its FMI 3 headers

    d = Path(fmpy.__file__).resolve().parent / "c-code"
    missing = [h for h in FMI3_HEADERS if not (d / h).is_file()]
    if missing:
        raise FmuBuildError(f"FMI headers: {missing} not found in {d} (fmpy installation incomplete)")
    return d


def fmi_header_dir(fmi_version: int) -> Path:
    """The folder of the FMI ``fmi_version`` (2 or 3) standard headers the standalone FMU is compiled with."""
    return fmi3_header_dir() if fmi_version == 3 else fmi2_header_dir()


def find_c_compiler() -> str:
    """The C compiler: ``$CC``, else gcc, else cc.  Raises :class:`CompilerNotFoundError`."""
    for cand in (os.environ.get("CC"), "gcc", "cc"):
        if cand and shutil.which(cand):
            return shutil.which(cand)
    raise CompilerNotFoundError("C compiler: none found (tried $CC, gcc, cc); the FMU's kernel is compiled "
                                "at build time -- install gcc or set CC")


def run_compiler(cmd, what: str, *, timeout: float = 120) -> None:
    """Run the compile command ``cmd`` (``cmd[0]`` the compiler); :class:`CompilerNotFoundError`
    if it cannot start, :class:`FmuBuildError` naming ``what`` with the compiler's messages if it fails."""
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except OSError as exc:
        raise CompilerNotFoundError(f"C compiler {cmd[0]!r}: cannot run ({exc})") from None
    if proc.returncode != 0:
        raise FmuBuildError(f"{what}: compilation failed ({' '.join(cmd)}):\n{proc.stderr}")


def compiler_version(cc: str) -> str:
    """The first line of ``<cc> --version`` ("unknown" if it gives none)."""
    try:
        return subprocess.run([cc, "--version"], capture_output=True, text=True, timeout=30).stdout.splitlines()[0]
    except (OSError, IndexError, subprocess.SubprocessError):
        return "unknown"


def sha256_file(p: Path) -> str:
    return hashlib.sha256(Path(p).read_bytes()).hexdigest()


# ----------------------------------------------------------------- arguments
def check_output_arguments(out_path, scene_text) -> Path:
    """``out_path`` as a Path ending in .fmu and ``scene_text`` a str or None (FmuBuildError
    naming the field otherwise)."""
    if scene_text is not None and not isinstance(scene_text, str):
        raise FmuBuildError(f"scene_text: expected str or None, got {type(scene_text).__name__}")
    out_path = Path(out_path)
    if out_path.suffix != ".fmu":
        raise FmuBuildError(f"out_path: must end in .fmu, got {str(out_path)!r}")
    return out_path


def check_arguments(tables, out_path, settings: Optional[RunSettings], *, scene_text, model_name,
                    **changes) -> Tuple[RunSettings, Path]:
    """The arguments both FMU builders share, checked in this order: the tables, the model name,
    the run settings (``settings``, None: the :class:`gearfmu.common.settings.RunSettings`
    defaults, with the fields of ``changes`` given; the one check of every setting), the
    integrator against the tables' slots, the output path and the scene text.  Returns (the
    settings resolved on the tables -- default output interval, automatic step, balancing gear
    torque: :func:`gearfmu.dynamics.native.resolve_settings`, the native solver's rule --, the
    output path); raises :class:`FmuBuildError` naming the field."""
    if not isinstance(tables, MeshTables):
        raise FmuBuildError(f"tables: expected a MeshTables, got {type(tables).__name__}")
    tables.validate()
    if not isinstance(model_name, str) or not model_name.strip():
        raise FmuBuildError(f"model_name: must be a non-empty string, got {model_name!r}")
    s = checked(settings, FmuBuildError, RunSettings, **changes)
    integrator_code(s.integrator, tables.slots, error=FmuBuildError)
    out_path = check_output_arguments(out_path, scene_text)
    return resolve_settings(tables, s), out_path


def start_values(s: RunSettings) -> dict:
    """Start values of the interface variables (modeldescription/variables.toml names) from resolved
    settings (damping model and integrator as their codes)."""
    return {"pinion_torque": s.pinion_torque_start_Nm, "gear_torque": s.gear_torque_start_Nm,
            "damping_ratio": s.damping_ratio, "pinion_speed_start": s.pinion_speed_start_rad_s,
            "pinion_angle_start": s.pinion_angle_start_rad, "max_step": s.max_step_s,
            "damping_model": s.damping_model_code, "integrator": s.integrator_code}


def record_parameters(s: RunSettings, temperature_start_C: Optional[float] = None) -> dict:
    """The parameters the provenance and the validation record name (no experiment times; damping
    model and integrator as their codes)."""
    p = {"damping_ratio": s.damping_ratio, "pinion_speed_start_rad_s": s.pinion_speed_start_rad_s,
         "pinion_angle_start_rad": s.pinion_angle_start_rad, "pinion_torque_start_Nm": s.pinion_torque_start_Nm,
         "gear_torque_start_Nm": s.gear_torque_start_Nm, "max_step_s": s.max_step_s,
         "damping_model": s.damping_model_code, "integrator": s.integrator_code}
    if temperature_start_C is not None:
        p["bulk_temperature_start_C"] = temperature_start_C
    return p


# ----------------------------------------------------------------- interface
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


def interface_variables(spec, tables: MeshTables, starts: dict, *, integrator_optional: bool = False,
                        features: tuple = ()):
    """The spec's variables for these tables with ``starts`` applied and the temperature input
    (:func:`temperature_input`); returns (variables, temperature start degC or None).
    ``integrator_optional``: a spec without an ``integrator`` parameter is accepted when the
    integrator is rk4 (0), the one the runtime then uses.  ``features``: spec features besides the
    tables' own (Model Exchange's, gearfmu.fmu.modeldesc.ME_FEATURES)."""
    variables = expand_variables(spec, tables.slots, features_of(tables) + tuple(features))
    if integrator_optional and not any(v.name == "integrator" for v in variables):
        if starts.get("integrator", 0) != 0:
            raise FmuBuildError("integrator: the interface spec has no 'integrator' parameter; only rk4 (0) is possible")
        starts = {k: v for k, v in starts.items() if k != "integrator"}
    return temperature_input(apply_start_values(variables, starts), tables)


def variable_table_lines(variables) -> list:
    """The variable table the C FMI layer reads (both runtimes: ``gearfmu_standalone.txt`` and the
    pythonfmu loader's ``gearfmu_pyshim.txt``): ``n_vars=N``, then one
    ``var=vr|causality|variability|type|output_index|start|min|max|name`` line per variable in
    value-reference order; numbers of Real variables as C99 hexadecimal literals (exact), of
    Integer ones as integers, empty when absent."""
    def number(v, typ):
        if v is None:
            return ""
        return str(int(v)) if typ == "Integer" else float(v).hex()

    lines = [f"n_vars={len(variables)}"]
    for v in variables:
        if "|" in v.name:
            raise FmuBuildError(f"variable {v.name!r}: '|' not allowed in names")
        oi = "" if v.output_index is None else str(int(v.output_index))
        lines.append("var=" + "|".join([str(v.value_reference), v.causality, v.variability, v.type, oi,
                                        number(v.start, v.type), number(v.min, v.type), number(v.max, v.type),
                                        v.name]))
    return lines


def _with_platforms_note(xml: bytes, note: Optional[str]) -> bytes:
    """``xml`` with `` [note]`` appended to the root element's description (which binaries it carries)."""
    if not note:
        return xml
    start = xml.index(b"<fmiModelDescription")
    a = xml.index(b' description="', start) + len(b' description="')
    b = xml.index(b'"', a)
    text = xml_escape(note, {'"': "&quot;"}).encode("utf-8")
    return xml[:a] + (xml[a:b].rstrip() + b" [" + text + b"]").lstrip() + xml[b:]


def model_description(spec, variables, fmi_version: int, platforms_note: Optional[str] = None, **md_args) -> bytes:
    """The model description of FMI ``fmi_version`` (2 or 3) from the spec, checked against ``variables``;
    FMI 3: ``platforms_note`` appended to the description."""
    if fmi_version == 3:
        xml = _with_platforms_note(model_description_xml3(spec, variables, **md_args), platforms_note)
        check_model_description3(xml, variables)
    else:
        xml = model_description_xml(spec, variables, **md_args)
        check_model_description(xml, variables)
    return xml


# ----------------------------------------------------------------- resources
def fmu_digest(meta_bytes: bytes, bin_bytes: bytes, model_name: str, s: RunSettings) -> str:
    """SHA-256 (hex) of the tables and the model's (resolved) settings: the first 12 digits go into the identifier."""
    key = (model_name, s.damping_ratio, s.pinion_speed_start_rad_s, s.pinion_angle_start_rad,
           s.pinion_torque_start_Nm, s.gear_torque_start_Nm, s.max_step_s, s.damping_model_code, s.integrator_code)
    return hashlib.sha256(meta_bytes + bin_bytes + repr(key).encode()).hexdigest()


def write_tables(res_dir: Path, meta_bytes: bytes, bin_bytes: bytes) -> None:
    """``tables.json`` and ``tables.bin`` (gearfmu/tables/mesh_tables.py format) into ``res_dir``."""
    (res_dir / "tables.json").write_bytes(meta_bytes)
    (res_dir / "tables.bin").write_bytes(bin_bytes)


def write_scene(res_dir: Path, scene_text: Optional[str]) -> Optional[Path]:
    """``scene.toml`` into ``res_dir`` when a scene was given; its path (None without one)."""
    if scene_text is None:
        return None
    p = res_dir / "scene.toml"
    p.write_text(scene_text, encoding="utf-8")
    return p


def scene_sha256(scene_text: Optional[str]) -> Optional[str]:
    return None if scene_text is None else hashlib.sha256(scene_text.encode()).hexdigest()


# ----------------------------------------------------------------- the file
@contextlib.contextmanager
def fmu_zip(out_path: Path):
    """A :class:`zipfile.ZipFile` (deflated) to write the FMU into: written under a temporary name
    beside ``out_path`` and renamed to it when the block ends without an error, so a failed
    build never leaves a half-written FMU under the final name."""
    out_path.parent.mkdir(parents=True, exist_ok=True)
    part = out_path.with_name(out_path.name + f".part-{uuid.uuid4().hex[:8]}")
    try:
        with zipfile.ZipFile(part, "w", compression=zipfile.ZIP_DEFLATED) as zout:
            yield zout
        os.replace(part, out_path)
    finally:
        if part.exists():
            part.unlink()


def zip_folder(zout: zipfile.ZipFile, root: Path) -> None:
    """``root/modelDescription.xml`` first, then every other file under ``root`` in sorted order."""
    zout.write(root / "modelDescription.xml", "modelDescription.xml")
    for p in sorted(root.rglob("*")):
        rel = p.relative_to(root).as_posix()
        if p.is_file() and rel != "modelDescription.xml":
            zout.write(p, rel)


# ----------------------------------------------------------------- one build
@dataclass(frozen=True)
class BuildInputs:
    """What one FMU build knows before it writes a file, checked and resolved: the ``tables``,
    the run ``settings`` resolved on them (:func:`check_arguments`), the ``model_name``, the
    ``scene_text`` (None: no scene), the interface ``spec`` and its ``variables`` with the start
    values applied (:func:`interface_variables`), the ``temperature_start_C`` of the temperature
    input (degC; None without a temperature axis), the ``envelope`` record
    (:func:`gearfmu.fmu.envelope.fmu_envelope_record`), the tables' bytes (``meta_bytes``
    tables.json, ``bin_bytes`` tables.bin), the ``identifier`` (modelIdentifier) and the ``guid``."""

    tables: MeshTables
    settings: RunSettings
    model_name: str
    scene_text: Optional[str]
    spec: object
    variables: list
    temperature_start_C: Optional[float]
    envelope: dict
    meta_bytes: bytes
    bin_bytes: bytes
    identifier: str
    guid: str

    @property
    def experiment(self) -> dict:
        """The DefaultExperiment: start, stop time and step size (s)."""
        return {"start": 0.0, "stop": self.settings.stop_time_s, "step": self.settings.output_interval_s}


def new_identifier(prefix: str, meta_bytes: bytes, bin_bytes: bytes, model_name: str, s: RunSettings) -> str:
    """``<prefix>_<12 digits of fmu_digest>_<8 random hex digits>``: the FMU's modelIdentifier (and
    module name); the random part keeps two builds of the same model apart in one process."""
    return f"{prefix}_{fmu_digest(meta_bytes, bin_bytes, model_name, s)[:12]}_{uuid.uuid4().hex[:8]}"


def new_guid() -> str:
    """A new GUID in braces (the model description's guid / instantiationToken)."""
    return "{" + str(uuid.uuid4()) + "}"
