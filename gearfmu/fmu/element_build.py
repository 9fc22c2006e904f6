"""Build the torsional element FMUs of an SSP of stage FMUs: a rigid body and an elastic shaft, in C.

The same FMI layers and plumbing as the pair and the gearbox FMU (``fmi2_gear.c`` / ``fmi3_gear.c``,
``fmi_common.c``, docs/standalone.md) over the element model (``standalone/element_model.c``), compiled
from one translation unit (``fmi2_element_all.c`` / ``fmi3_element_all.c``) for the platforms of
:mod:`gearfmu.fmu.crossbuild`.  The interface comes from ``modeldescription/element.toml``.
docs/gearbox.md "The SSP of stage FMUs" says where the elements sit and why.

* :class:`BodyElement`: a rigid inertia (the motor or the load of a gearbox) with torque inputs, each
  driving or resisting; outputs angle and speed.
* :class:`ShaftElement`: an elastic shaft (k, c) between two ports that exchange torque and angular
  velocity; it integrates the twist from the exchanged speeds and returns the torque predicted for the
  next communication step.

:func:`build_unit_fmu` packs any standalone unit of the runtime (an element, a stage of
:mod:`gearfmu.fmu.stage_build`): sources, binaries, model description, documentation page, resources.
"""
from __future__ import annotations

import datetime
import hashlib
import html
import json
import math
import shutil
import tempfile
import tomllib
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple, Union

from .. import __version__
from . import crossbuild
from .build_steps import (FmuBuildError, check_model_description, compiler_version, find_c_compiler,
                          fmi_header_dir, fmu_zip, model_description, variable_table_lines, zip_folder)
from .fmudoc import DOC_FILES
from .modeldesc import Spec, SpecError, Variable
from .standalone_build import (FMI_VERSIONS, STANDALONE_CFLAGS, build_recipe_files, compile_standalone,
                               platforms_text, standalone_model_description)

__all__ = ["TorqueInput", "BodyElement", "ShaftElement", "load_element_spec", "element_variables",
           "element_config_text", "build_element_fmu", "build_unit_fmu", "ELEMENT_SOURCES", "CONFIG_FILE"]

HERE = Path(__file__).resolve().parent
STANDALONE_DIR = HERE / "standalone"
#: the one file a build of an element FMU of FMI 2 / FMI 3 compiles, and the files it includes
ELEMENT_UNITS = {2: STANDALONE_DIR / "fmi2_element_all.c", 3: STANDALONE_DIR / "fmi3_element_all.c"}
LAYERS = {2: STANDALONE_DIR / "fmi2_gear.c", 3: STANDALONE_DIR / "fmi3_gear.c"}
ELEMENT_SOURCES = (STANDALONE_DIR / "fmi_common.c", STANDALONE_DIR / "element_model.c",
                   STANDALONE_DIR / "gf_resources.c")
ELEMENT_HEADERS = (STANDALONE_DIR / "gf_model.h", STANDALONE_DIR / "fmi_common.h", STANDALONE_DIR / "element_model.h",
                   STANDALONE_DIR / "gf_resources.h")
CONFIG_FILE = "gearfmu_element.txt"
CONFIG_FORMAT = "gearfmu-element"
CONFIG_VERSION = 1
SPEC_FORMAT = "gearfmu-element-variables"
KINDS = ("body", "shaft")


def _default_spec_path() -> Path:
    here = HERE.parent
    for cand in (here.parent / "modeldescription" / "element.toml", here / "modeldescription" / "element.toml"):
        if cand.is_file():
            return cand
    return here.parent / "modeldescription" / "element.toml"


# ------------------------------------------------------------------ elements
@dataclass(frozen=True)
class TorqueInput:
    """A torque input of a body: its FMU name, sign (+1 drives the body, -1 resists), start value (N*m),
    what it is, and whether it comes from a neighbouring FMU (a port: its start value is the neighbour's
    initial output)."""

    name: str
    sign: int
    start_Nm: float
    description: str
    port: bool = False


@dataclass(frozen=True)
class BodyElement:
    """A rigid body: inertia (kg*m^2), start angle (rad) and speed (rad/s), its torque inputs."""

    name: str
    inertia_kgm2: float
    angle_start_rad: float
    speed_start_rad_s: float
    torques: Tuple[TorqueInput, ...]
    kind: str = "body"


@dataclass(frozen=True)
class ShaftElement:
    """An elastic shaft: stiffness (N*m/rad), damping (N*m*s/rad), start twist (rad; the static torque
    over k) and the start value of both speed inputs (rad/s)."""

    name: str
    stiffness_Nm_per_rad: float
    damping_Nms_per_rad: float
    twist_start_rad: float
    speed_start_rad_s: float
    kind: str = "shaft"


Element = Union[BodyElement, ShaftElement]


def _finite(name: str, v, *, positive=False, nonneg=False) -> float:
    try:
        x = float(v)
    except (TypeError, ValueError):
        raise FmuBuildError(f"{name}: expected a number, got {v!r}") from None
    if not math.isfinite(x) or (positive and not x > 0) or (nonneg and x < 0):
        raise FmuBuildError(f"{name}: must be finite{' and > 0' if positive else ' and >= 0' if nonneg else ''}, "
                            f"got {v!r}")
    return x


def check_element(e: Element) -> Element:
    """FmuBuildError naming the field of a bad element."""
    if isinstance(e, BodyElement):
        _finite(f"{e.name}.inertia_kgm2", e.inertia_kgm2, positive=True)
        _finite(f"{e.name}.angle_start_rad", e.angle_start_rad)
        _finite(f"{e.name}.speed_start_rad_s", e.speed_start_rad_s)
        if not e.torques:
            raise FmuBuildError(f"{e.name}.torques: a body needs at least one torque input")
        names = set()
        for t in e.torques:
            if t.sign not in (1, -1) or not t.name or "|" in t.name or t.name in names:
                raise FmuBuildError(f"{e.name}.torques: {t.name!r}: a unique name and sign +1 or -1")
            names.add(t.name)
            _finite(f"{e.name}.{t.name}.start_Nm", t.start_Nm)
    elif isinstance(e, ShaftElement):
        _finite(f"{e.name}.stiffness_Nm_per_rad", e.stiffness_Nm_per_rad, positive=True)
        _finite(f"{e.name}.damping_Nms_per_rad", e.damping_Nms_per_rad, nonneg=True)
        _finite(f"{e.name}.twist_start_rad", e.twist_start_rad)
        _finite(f"{e.name}.speed_start_rad_s", e.speed_start_rad_s)
    else:
        raise FmuBuildError(f"element: expected BodyElement or ShaftElement, got {type(e).__name__}")
    return e


# --------------------------------------------------------------------- spec
def load_element_spec(path=None) -> Spec:
    """Read and check ``modeldescription/element.toml`` (SpecError naming the entry and field)."""
    p = Path(path) if path is not None else _default_spec_path()
    try:
        data = tomllib.loads(p.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise SpecError(f"{p}: element interface spec not found") from None
    except tomllib.TOMLDecodeError as exc:
        raise SpecError(f"{p}: not valid TOML ({exc})") from None
    if data.get("format") != SPEC_FORMAT or data.get("version") != 1:
        raise SpecError(f"{p}: format/version {data.get('format')!r}/{data.get('version')!r}, expected "
                        f"{SPEC_FORMAT!r}/1")
    units = data.get("units", {})
    for i, ent in enumerate(data.get("variable", [])):
        where = f"{p}: variable #{i + 1} ({ent.get('name', '?')!r})"
        if ent.get("kind") not in KINDS:
            raise SpecError(f"{where}: kind {ent.get('kind')!r} not in {KINDS}")
        if ent.get("unit") is not None and ent["unit"] not in units:
            raise SpecError(f"{where}: unit {ent['unit']!r} has no entry in [units]")
        if ent.get("causality") == "output" and "output_index" not in ent:
            raise SpecError(f"{where}: an output needs output_index")
        if ent.get("causality") in ("input", "parameter") and "start" not in ent:
            raise SpecError(f"{where}: inputs and parameters need a start value")
        if ent.get("per") not in (None, "torque") or (ent.get("per") and ent["kind"] != "body"):
            raise SpecError(f"{where}: per must be \"torque\" (bodies) or absent")
    return Spec(path=str(p), model=data.get("model", {}), default_experiment=data.get("default_experiment", {}),
                units=units, entries=data.get("variable", []))


def _starts(e: Element) -> Dict[str, float]:
    if isinstance(e, BodyElement):
        return {"inertia": e.inertia_kgm2, "angle_start": e.angle_start_rad, "speed_start": e.speed_start_rad_s}
    return {"stiffness": e.stiffness_Nm_per_rad, "damping": e.damping_Nms_per_rad,
            "twist_start": e.twist_start_rad, "upstream_speed": e.speed_start_rad_s,
            "downstream_speed": e.speed_start_rad_s}


def element_variables(e: Element, spec: Optional[Spec] = None) -> List[Variable]:
    """The variables of element ``e``: the spec's entries of its kind, ``per = "torque"`` repeated for
    every torque input of a body, numbered in order, with the element's start values."""
    spec = spec or load_element_spec()
    starts = _starts(e)
    out: List[Variable] = []
    for ent in spec.entries:
        if ent["kind"] != e.kind:
            continue
        rows = ([(t.name, float(t.start_Nm), f"{t.description} ({'drives' if t.sign > 0 else 'resists'})")
                 for t in e.torques] if ent.get("per") == "torque"
                else [(ent["name"], starts.get(ent["name"], ent.get("start")), ent.get("description", ""))])
        for name, start, desc in rows:
            if start is not None:
                start = int(start) if ent["type"] == "Integer" else float(start)
            out.append(Variable(name=name, value_reference=len(out), type=ent["type"], causality=ent["causality"],
                                variability=ent["variability"], initial=ent.get("initial"), unit=ent.get("unit"),
                                description=desc, start=start, min=ent.get("min"), max=ent.get("max"),
                                output_index=ent.get("output_index"),
                                build_override=bool(ent.get("build_override", False)),
                                initial_dependencies=(None if ent.get("initial_dependencies") is None
                                                      else tuple(ent["initial_dependencies"]))))
    return out


def element_config_text(e: Element, variables: Sequence[Variable], *, guid: str) -> str:
    """The ``gearfmu_element.txt`` element_model.c reads (format gearfmu-element, version 1)."""
    vr = {v.name: v.value_reference for v in variables}
    lines = ["# gearfmu element FMU configuration (written by gearfmu.fmu.element_build; read by element_model.c)",
             f"format={CONFIG_FORMAT}", f"version={CONFIG_VERSION}", f"guid={guid}", f"kind={e.kind}"]
    if isinstance(e, BodyElement):
        lines += [f"vr.inertia={vr['inertia']}", f"vr.angle_start={vr['angle_start']}",
                  f"vr.speed_start={vr['speed_start']}",
                  f"vr.first_step_start_values={vr['first_step_start_values']}"]
        lines += [f"torque={vr[t.name]}|{t.sign}|{int(t.port)}" for t in e.torques]
    else:
        lines += [f"vr.{key}={vr[name]}" for key, name in (
            ("stiffness", "stiffness"), ("damping", "damping"), ("twist_start", "twist_start"),
            ("speed_a", "upstream_speed"), ("speed_b", "downstream_speed"))]
    lines += variable_table_lines(variables)
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------------ packing
def _doc_html(title: str, description: str, variables: Sequence[Variable], notes: Sequence[str]) -> bytes:
    """A self-contained page: what the FMU is and its variables (every text HTML-escaped)."""
    e = html.escape
    rows = "".join(f"<tr><td>{e(v.name)}</td><td>{e(v.causality)}</td><td>{e(v.unit or '')}</td>"
                   f"<td>{e('' if v.start is None else repr(v.start))}</td><td>{e(v.description)}</td></tr>"
                   for v in variables)
    text = (f"<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>{e(title)}</title></head><body>"
            f"<h1>{e(title)}</h1><p>{e(description)}</p>" + "".join(f"<p>{e(n)}</p>" for n in notes) +
            "<table border=\"1\"><tr><th>name</th><th>causality</th><th>unit</th><th>start</th><th>meaning</th></tr>"
            f"{rows}</table></body></html>\n")
    return text.encode("utf-8")


@dataclass(frozen=True)
class UnitFmu:
    """What a standalone FMU of one C translation unit holds: ``unit`` (the one C file to compile)
    and the ``files`` it includes (into sources/), the model description of ``variables`` (the
    ``spec``'s units and experiment, ``description``, ``model_name``, ``identifier``, ``guid``,
    ``generation_tool``), ``resources`` ({path under resources/: bytes}), the documentation
    page's ``notes`` and the ``provenance`` added to resources/provenance.json."""

    unit: Path
    files: Sequence[Path]
    spec: Spec
    variables: Sequence[Variable]
    description: str
    model_name: str
    identifier: str
    guid: str
    resources: Dict[str, bytes]
    generation_tool: str
    notes: Sequence[str] = ()
    provenance: Optional[dict] = None


def build_unit_fmu(out_path, fmu: UnitFmu, *, fmi_version: int, platforms: Optional[Sequence[str]],
                   stop_time_s: float, step_size_s: float, cc: Optional[str] = None) -> Path:
    """Pack the standalone FMU ``fmu`` (:class:`UnitFmu`) at ``out_path``: its sources, its binaries
    for ``platforms`` (crossbuild keys; None: all) compiled for FMI ``fmi_version``, its model
    description (default experiment ``stop_time_s``, ``step_size_s`` in s), a documentation page,
    its resources and resources/provenance.json; ``cc``: the host compiler (None: found)."""
    unit, files, variables, identifier, guid = fmu.unit, fmu.files, fmu.variables, fmu.identifier, fmu.guid
    description, model_name, resources = fmu.description, fmu.model_name, fmu.resources
    spec = fmu.spec
    if fmi_version not in FMI_VERSIONS:
        raise FmuBuildError(f"fmi_version: {fmi_version!r} not one of {FMI_VERSIONS}")
    out_path = Path(out_path)
    if out_path.suffix != ".fmu":
        raise FmuBuildError(f"out_path: must end in .fmu, got {str(out_path)!r}")
    keys = crossbuild.parse_platforms(None) if platforms is None else tuple(platforms)
    unknown = [k for k in keys if k not in crossbuild.TARGETS]
    if unknown or not keys:
        raise FmuBuildError(f"platforms: unknown {unknown} (known: {', '.join(crossbuild.TARGETS)})")
    now = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    spec = Spec(path=spec.path, model={**spec.model, "description": description},
                default_experiment=spec.default_experiment, units=spec.units, entries=spec.entries)
    with tempfile.TemporaryDirectory(prefix="gearfmu_unit_build_") as tmpd:
        root = Path(tmpd) / "fmu"
        src = root / "sources"
        src.mkdir(parents=True)
        for f in (unit, *files):
            shutil.copy2(f, src / Path(f).name)

        def host_compile(out_lib):
            host = cc or find_c_compiler()
            return compile_standalone(src, out_lib, cc=host, fmi_version=fmi_version, sources=(unit.name,)), \
                compiler_version(host)

        try:
            binaries = crossbuild.build_binaries(keys, src, root / "binaries", identifier, cflags=STANDALONE_CFLAGS,
                                                 sources=(unit.name,), host_compile=host_compile,
                                                 host_cc_first=cc is not None, fmi_version=fmi_version,
                                                 header_dir=fmi_header_dir(fmi_version))
        except crossbuild.CrossBuildError as exc:
            raise FmuBuildError(str(exc)) from None
        for name, text in build_recipe_files(identifier, fmi_version, (unit.name,)).items():
            (src / name).write_text(text, encoding="utf-8")
        plat_text = platforms_text(binaries, fmi_version)
        (root / "documentation").mkdir()
        (root / "documentation" / "platforms.txt").write_text(plat_text, encoding="utf-8")
        res = root / "resources"
        res.mkdir()
        for rel, data in resources.items():
            (res / rel).parent.mkdir(parents=True, exist_ok=True)
            (res / rel).write_bytes(data)
        built = {k: r for k, r in binaries.items() if "missing" not in r}
        prov = {"gearfmu_version": __version__, "built_utc": now, "runtime": "standalone", "fmi_version": fmi_version,
                "model_name": model_name, "model_identifier": identifier, "guid": guid,
                "files_sha256": {f"resources/{rel}": hashlib.sha256(d).hexdigest() for rel, d in resources.items()},
                "binary": {"flags": list(STANDALONE_CFLAGS), "platforms": binaries,
                           "compiler": "; ".join(sorted({r["compiler"] for r in built.values()})) or None},
                **(fmu.provenance or {})}
        (res / "provenance.json").write_text(json.dumps(prov, indent=1, default=str), encoding="utf-8")
        md_args = dict(model_name=model_name, model_identifier=identifier, guid=guid, stop_time_s=stop_time_s,
                       step_size_s=step_size_s, generation_tool=fmu.generation_tool, generation_date=now,
                       version=__version__)
        note = crossbuild.platform_summary(binaries)
        if fmi_version == 3:
            xml = model_description(spec, variables, 3, platforms_note=note, **md_args)
        else:
            xml = standalone_model_description(model_description(spec, variables, 2, **md_args), (unit.name,),
                                               platforms_note=note)
            check_model_description(xml, variables)
        (root / "modelDescription.xml").write_bytes(xml)
        page = _doc_html(model_name, description, variables, fmu.notes)
        for rel in DOC_FILES(fmi_version):
            (root / rel).write_bytes(page)
        with fmu_zip(out_path) as zout:
            zip_folder(zout, root)
    return out_path


def build_element_fmu(element: Element, out_path, *, fmi_version: int = 2, platforms: Optional[Sequence[str]] = None,
                      stop_time_s: float = 0.1, step_size_s: float = 1e-5, cc: Optional[str] = None,
                      spec_path=None) -> Path:
    """Build the FMU of ``element`` (a :class:`BodyElement` or :class:`ShaftElement`) at ``out_path``
    (FMI ``fmi_version`` 2 or 3 Co-Simulation, the standalone C runtime); return its path."""
    check_element(element)
    spec = load_element_spec(spec_path)
    variables = element_variables(element, spec)
    digest = hashlib.sha256(repr(element).encode()).hexdigest()[:12]
    identifier = f"gearfmu_el_{digest}_{uuid.uuid4().hex[:8]}"
    guid = "{" + str(uuid.uuid4()) + "}"
    unit = ELEMENT_UNITS[fmi_version] if fmi_version in ELEMENT_UNITS else ELEMENT_UNITS[2]
    files = (LAYERS.get(fmi_version, LAYERS[2]), *ELEMENT_SOURCES, *ELEMENT_HEADERS)
    config = element_config_text(element, variables, guid=guid)
    fmu = UnitFmu(
        unit=unit, files=files, spec=spec, variables=variables,
        description=str(spec.model.get(f"description_{element.kind}", "")), model_name=element.name,
        identifier=identifier, guid=guid, resources={CONFIG_FILE: config.encode("utf-8")},
        generation_tool=f"gearfmu {__version__} (standalone runtime, {element.kind} element)",
        provenance={"model": f"element:{element.kind}", "element": {k: v for k, v in vars(element).items()
                                                                    if k != "torques"}})
    return build_unit_fmu(out_path, fmu, fmi_version=fmi_version, platforms=platforms, stop_time_s=stop_time_s,
                          step_size_s=step_size_s, cc=cc)
