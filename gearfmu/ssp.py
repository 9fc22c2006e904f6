"""SSP package of a gear FMU: system structure, FMU and named parameter sets.

An SSP (System Structure and Parameterization, Modelica Association,
*SSP 1.0*, 2019) archive is a zip holding ``SystemStructure.ssd`` (the default
variant), further ``.ssd`` files (other variants, SSP 1.0 section 3), and
``resources/`` (the FMU and ``.ssv`` parameter value sets, SSP 1.0 sections
5 and 6).  :func:`build_ssp` writes

```
SystemStructure.ssd            the system, the first parameter set (e.g. nominal) in force
<variant>.ssd                  the same system with the variant's parameter set alone
resources/<model>.fmu          the gear FMU
resources/<variant>.ssv        one ParameterSet per variant (named after it), the FMU's variable names
```

The system ``drivetrain`` holds one component ``gear`` (the FMU) whose connectors
are the FMU's outputs, by their full names (SI units from the FMU's UnitDefinitions);
its inputs are not connectors, so they keep the start values the parameter set
gives them, and its parameters are set by the parameter sets (a parameter binding
reaches every variable of the FMU by name).  Nothing connects to the system itself,
which is the one form every SSP engine tried opens as is: fmpy, libcosim and ecos
(ecos and libcosim refuse a connection to a system connector; fmpy writes 0 into a
component input that nothing drives, and reports a parameter connector as 0).  Each parameter set is bound on the component: a ``<variant>.ssd``
binds its own set; ``SystemStructure.ssd`` binds every set, the first one first
and again last, so that an engine that applies all bindings in order (SSP 1.0)
ends with the first set, an engine that takes the component's first binding
(libcosim) gets it too, and an engine that chooses a set by its name (ecos)
finds them all.  Every set names the same variables, so that applying one set
over another gives that set.  How each engine selects a variant:
docs/fmu_import.md "SSP packages".  Every XML file is checked against the SSP
1.0 XSD shipped with pyssp-standard before the archive is written; a package
that fails the check is never written.

Variants are named sets of parameter values and input start values of the FMU
(for example two damping ratios).  Choices (docs/robustness.md "SSP"): with no
explicit variants, :func:`ssp_from_scene` makes ``nominal`` (the scene's damping
ratio), ``damping_low`` (half of it) and ``damping_high`` (twice it, at most 1);
when the FMU has a temperature input (tables with a temperature axis) also
``temperature_low`` / ``temperature_high`` at the ends of the axis.  Values are
checked against the FMU's modelDescription (name, causality parameter or input,
min/max, Integer) and the error names the variant and the parameter.
"""
from __future__ import annotations

import math
import re
import shutil
import tempfile
import uuid
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path
from typing import Dict, Mapping, Optional

from . import stages as st
from .common.checks import finite_number
from .common.progress import ticking
from .common.vocabulary import DEFAULT_INTEGRATOR, DEFAULT_SSP_COUPLING
from .fmu.composition import compose
from .fmu.gearbox_ssp import write_composition
from .pipeline import build

NS = {
    "ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
    "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
    "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
}
for _p, _u in NS.items():
    ET.register_namespace(_p, _u)

_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,63}$")


#: names of the system and of its one component (the gear FMU) in every .ssd
SYSTEM, COMPONENT = "drivetrain", "gear"

#: the temperature inputs (their start value is a variant's, like a parameter's; any FMU input may be)
VARIANT_INPUTS = ("bulk_temperature", "oil_temperature", "gearbox_temperature")


class SspError(ValueError):
    """Bad SSP input (variant name, parameter name or value); the message names it."""


def _is_integer(var) -> bool:
    """An FMI 2 Integer or an FMI 3 Int32 (an SSP 1.0 ``Integer`` connector); every other is ``Real``.
    An FMI 3 array variable (``pair_force``) is one connector of its name: SSP 1.0 has no array type."""
    return var.type in ("Integer", "Int32")


def _q(prefix: str, tag: str) -> str:
    return f"{{{NS[prefix]}}}{tag}"


def _fmu_interface(fmu_path: Path):
    """(model description, units {name: base exponents}) of an FMU."""
    import fmpy  # fmpy: heavy, only to read the FMU

    md = fmpy.read_model_description(str(fmu_path))
    units = {}
    for u in md.unitDefinitions:
        bu = u.baseUnit
        units[u.name] = {} if bu is None else {k: getattr(bu, k) for k in ("kg", "m", "s", "A", "K", "mol", "cd", "rad")
                                                 if getattr(bu, k, 0)}
    return md, units


def check_variants(md, variants: Mapping[str, Mapping[str, float]]) -> Dict[str, Dict[str, float]]:
    """Check variant names and parameter values against the FMU's model description."""
    if not variants:
        raise SspError("variants: at least one named parameter set is needed")
    # parameters, and the start values of inputs (the system does not drive them: docs/fmu_import.md)
    params = {v.name: v for v in md.modelVariables if v.causality in ("parameter", "input")}
    out = {}
    for name, values in variants.items():
        if not isinstance(name, str) or not _NAME.match(name) or name == "SystemStructure":
            raise SspError(f"variants: name {name!r} must be a letter then letters, digits or _ (max 64), "
                           f"not 'SystemStructure'")
        if not values:
            raise SspError(f"variants.{name}: no parameter values")
        checked = {}
        for p, val in values.items():
            if p not in params:
                raise SspError(f"variants.{name}.{p}: not a parameter or input of the FMU "
                               f"(parameters and inputs: {sorted(params)})")
            var = params[p]
            x = finite_number(f"variants.{name}.{p}", val, error=SspError)
            if var.min is not None and x < float(var.min) or var.max is not None and x > float(var.max):
                raise SspError(f"variants.{name}.{p} = {x!r}: outside the FMU's range [{var.min}, {var.max}]")
            if _is_integer(var):
                if x != int(x):
                    raise SspError(f"variants.{name}.{p}: Integer parameter, got {x!r}")
                x = int(x)
            checked[p] = x
        out[name] = checked
    return out


def _value_element(parent, prefix: str, var, x) -> None:
    """``<prefix:Real value unit>`` / ``<prefix:Integer value>`` of a parameter value."""
    if _is_integer(var):
        ET.SubElement(parent, _q(prefix, "Integer"), {"value": str(int(x))})
    else:
        attrs = {"value": repr(float(x))}
        if var.unit:
            attrs["unit"] = var.unit
        ET.SubElement(parent, _q(prefix, "Real"), attrs)


def complete_variants(md, variants: Mapping[str, Mapping[str, float]]) -> Dict[str, Dict[str, float]]:
    """Every variant with a value for every variable that any variant names: the first variant's
    value, else the FMU's start value.  Then applying one set over another gives that set."""
    var = {v.name: v for v in md.modelVariables}
    first = next(iter(variants.values()))
    names = list(dict.fromkeys(p for values in variants.values() for p in values))

    def default(p):
        if p in first:
            return first[p]
        start = var[p].start
        if start is None:
            raise SspError(f"variants: {p} has no start value in the FMU; give it in every variant")
        return int(start) if _is_integer(var[p]) else float(start)

    return {name: {p: values[p] if p in values else default(p) for p in names} for name, values in variants.items()}


def _ssv_xml(name: str, values: Mapping[str, float], md) -> bytes:
    """The variant's .ssv: a ParameterSet named after the variant with the FMU's variable names
    (a parameter set of the component, bound on it: SSP 1.0 ParameterBinding)."""
    root = ET.Element(_q("ssv", "ParameterSet"), {"version": "1.0", "name": name})
    params = ET.SubElement(root, _q("ssv", "Parameters"))
    var = {v.name: v for v in md.modelVariables}
    for p, x in values.items():
        _value_element(ET.SubElement(params, _q("ssv", "Parameter"), {"name": p}), "ssv", var[p], x)
    return ET.tostring(root, encoding="utf-8", xml_declaration=True)


def _connector(parent, var, kind: str, used_units: set) -> None:
    c = ET.SubElement(parent, _q("ssd", "Connector"), {"name": var.name, "kind": kind})
    if _is_integer(var):
        ET.SubElement(c, _q("ssc", "Integer"))
    else:
        ET.SubElement(c, _q("ssc", "Real"), {"unit": var.unit} if var.unit else {})
        if var.unit:
            used_units.add(var.unit)


def _ssd_xml(ssd_name: str, sources, fmu_rel: str, md, units, stop_time_s: float, description: str) -> bytes:
    """One .ssd of the package: the system ``drivetrain`` with the component ``gear`` (the FMU),
    whose connectors are the FMU's outputs, and one ParameterBinding on the
    component per .ssv of ``sources`` (archive paths, in order).  No system connectors and no
    connections: the form fmpy, libcosim and ecos all open (module docstring)."""
    root = ET.Element(_q("ssd", "SystemStructureDescription"),
                      {"version": "1.0", "name": ssd_name, "generationTool": "gearfmu",
                       "description": description})
    system = ET.SubElement(root, _q("ssd", "System"), {"name": SYSTEM})
    used_units: set = set()
    elements = ET.SubElement(system, _q("ssd", "Elements"))
    comp = ET.SubElement(elements, _q("ssd", "Component"),
                         {"name": COMPONENT, "type": "application/x-fmu-sharedlibrary", "source": fmu_rel})
    conns = ET.SubElement(comp, _q("ssd", "Connectors"))
    for v in md.modelVariables:
        if v.causality == "output":
            _connector(conns, v, v.causality, used_units)
    binds = ET.SubElement(comp, _q("ssd", "ParameterBindings"))
    for src in sources:
        ET.SubElement(binds, _q("ssd", "ParameterBinding"), {"source": src})
    if used_units:
        ue = ET.SubElement(root, _q("ssd", "Units"))
        for u in sorted(used_units):
            un = ET.SubElement(ue, _q("ssc", "Unit"), {"name": u})
            ET.SubElement(un, _q("ssc", "BaseUnit"), {k: str(e) for k, e in units.get(u, {}).items()})
    ET.SubElement(root, _q("ssd", "DefaultExperiment"), {"startTime": "0.0", "stopTime": repr(float(stop_time_s))})
    return ET.tostring(root, encoding="utf-8", xml_declaration=True)


def validate_ssp_dir(directory) -> None:
    """Schema-validate every .ssd and .ssv under ``directory`` with pyssp-standard
    (SSP 1.0 XSD); raise SspError naming the file on the first failure."""
    from pyssp_standard import SSD, SSV  # pyssp-standard: heavy schema validation, only when asked
    import xmlschema  # pyssp-standard's schema validator: heavy, only when asked

    d = Path(directory)
    files = sorted(d.glob("*.ssd")) + sorted((d / "resources").glob("*.ssv"))
    if not (d / "SystemStructure.ssd").is_file():
        raise SspError(f"{d}: SystemStructure.ssd missing")
    schemas = {}  # pyssp-standard's check_compliance, with each XSD parsed once instead of once per file
    for f in files:
        try:
            doc = (SSD if f.suffix == ".ssd" else SSV)(f, mode="r")
            xsd = doc.schemas[doc.identifier]
            if xsd not in schemas:  # XSD 1.1 when the schema's name says so, as pyssp-standard decides
                schemas[xsd] = (xmlschema.XMLSchema11 if "11" in str(xsd) else xmlschema.XMLSchema10)(xsd)
            xmlschema.validate(f, schemas[xsd], namespaces=doc.namespaces)
        except Exception as exc:  # noqa: BLE001 - xmlschema raises several types
            raise SspError(f"{f.relative_to(d)}: not valid SSP 1.0 ({str(exc).splitlines()[0]})") from None


def build_ssp(fmu_path, out_path, variants: Mapping[str, Mapping[str, float]], *,
              stop_time_s: Optional[float] = None, system_name: str = "gearpair") -> Path:
    """Write an SSP archive with the FMU at ``fmu_path`` and one variant per
    entry of ``variants`` ({variant name: {parameter name: value}}); the first
    variant is the default (``SystemStructure.ssd``).  Units of the values: the
    FMU parameter's unit (SI).  Returns ``out_path``."""
    fmu_path = Path(fmu_path)
    out_path = Path(out_path)
    if not fmu_path.is_file():
        raise SspError(f"fmu_path: not a file: {fmu_path}")
    if out_path.suffix != ".ssp":
        raise SspError(f"out_path: must end in .ssp, got {str(out_path)!r}")
    md, units = _fmu_interface(fmu_path)
    checked = check_variants(md, variants)
    if stop_time_s is None:
        de = md.defaultExperiment
        stop_time_s = float(de.stopTime) if de is not None and de.stopTime is not None else 0.1
    if not (math.isfinite(stop_time_s) and stop_time_s > 0):
        raise SspError(f"stop_time_s: must be finite and > 0, got {stop_time_s!r}")
    fmu_rel = f"resources/{fmu_path.stem}.fmu"
    complete = complete_variants(md, checked)
    names = list(complete)
    ssv = {name: f"resources/{name}.ssv" for name in names}
    with tempfile.TemporaryDirectory(prefix="gearfmu_ssp_") as tmpd:
        stage = Path(tmpd)
        (stage / "resources").mkdir()
        shutil.copy2(fmu_path, stage / fmu_rel)
        for name, values in complete.items():
            (stage / ssv[name]).write_bytes(_ssv_xml(name, values, md))
            desc = (f"gear pair {md.modelName}, parameter set {name!r}: "
                    + ", ".join(f"{k} = {v!r}" for k, v in checked[name].items()))
            (stage / f"{name}.ssd").write_bytes(
                _ssd_xml(f"{system_name}_{name}", [ssv[name]], fmu_rel, md, units, stop_time_s, desc))
        # the first set first (libcosim's default) and last (in force where all bindings apply in order),
        # the others between (ecos selects a set by name)
        order = [names[0], *names[1:], names[0]] if len(names) > 1 else names
        desc = (f"gear pair {md.modelName}, parameter set {names[0]!r} in force; parameter sets "
                + ", ".join(repr(n) for n in names) + " (one .ssd each)")
        (stage / "SystemStructure.ssd").write_bytes(
            _ssd_xml(system_name, [ssv[n] for n in order], fmu_rel, md, units, stop_time_s, desc))
        validate_ssp_dir(stage)
        _zip_folder(stage, out_path)
    return out_path


def _zip_folder(stage: Path, out_path: Path) -> None:
    """Every file under ``stage`` into the archive ``out_path`` (written under a temporary name beside
    it and renamed at the end: a failed write never leaves a half-written package)."""
    out_path.parent.mkdir(parents=True, exist_ok=True)
    part = out_path.with_name(out_path.name + f".part-{uuid.uuid4().hex[:8]}")
    try:
        with zipfile.ZipFile(part, "w", compression=zipfile.ZIP_DEFLATED) as z:
            for f in sorted(stage.rglob("*")):
                if f.is_file():
                    z.write(f, f.relative_to(stage).as_posix())
        part.replace(out_path)
    finally:
        if part.exists():
            part.unlink()


def fmpy_parameter_set(ssp_path, variant: str):
    """The variant's parameter set for fmpy's SSP master
    (``fmpy.ssp.simulation.simulate_ssp(ssp, parameter_set=...)``): ``resources/<variant>.ssv``
    with its names made the system's hierarchical names ``gear.<variable>`` (SSP 1.0), which
    that master expects; it applies no binding of the .ssd itself."""
    from fmpy.ssp.ssd import read_ssv  # fmpy: heavy, only for fmpy's master

    with zipfile.ZipFile(ssp_path) as z:
        if f"resources/{variant}.ssv" not in z.namelist():
            raise SspError(f"variant: {variant!r} is not a parameter set of {ssp_path}")
    ps = read_ssv(str(ssp_path), resource=f"resources/{variant}.ssv")
    for par in ps.parameters:
        par.name = f"{COMPONENT}.{par.name}"
    return ps


def default_variants(damping_ratio: float, temperature_range_C=None,
                     temperature_input: str = "bulk_temperature") -> Dict[str, Dict[str, float]]:
    """nominal / damping_low (half) / damping_high (twice, at most 1) damping ratios;
    with ``temperature_range_C`` = (lowest, highest) of the tables' temperature axis
    (degC, FMUs with a temperature input: ``temperature_input``, one of
    :data:`VARIANT_INPUTS`) also ``temperature_low`` / ``temperature_high`` at the
    nominal damping and the two ends of the axis."""
    z = float(damping_ratio)
    out = {"nominal": {"damping_ratio": z}, "damping_low": {"damping_ratio": 0.5 * z},
           "damping_high": {"damping_ratio": min(1.0, 2.0 * z)}}
    if temperature_range_C is not None:
        lo, hi = (float(x) for x in temperature_range_C)
        if temperature_input not in VARIANT_INPUTS:
            raise SspError(f"temperature_input: {temperature_input!r} not one of {VARIANT_INPUTS}")
        out["temperature_low"] = {"damping_ratio": z, temperature_input: lo}
        out["temperature_high"] = {"damping_ratio": z, temperature_input: hi}
    return out


def parse_variant(text: str):
    """``NAME:PARAM=VALUE[,PARAM=VALUE...]`` -> (name, {param: value})."""
    name, sep, rest = text.partition(":")
    if not sep or not rest:
        raise SspError(f"--variant {text!r}: expected NAME:PARAM=VALUE[,PARAM=VALUE...]")
    values = {}
    for item in rest.split(","):
        p, eq, v = item.partition("=")
        if not eq:
            raise SspError(f"--variant {text!r}: {item!r} is not PARAM=VALUE")
        try:
            values[p.strip()] = float(v)
        except ValueError:
            raise SspError(f"--variant {text!r}: {p.strip()} value {v!r} is not a number") from None
    return name.strip(), values


def ssp_from_scene(scene, out_path, *, variants: Optional[Mapping[str, Mapping[str, float]]] = None,
                   progress: bool = False, tables=None, fmi_version: int = 2, runtime: Optional[str] = None,
                   platforms=None) -> Path:
    """Scene -> tables -> FMU -> SSP archive at ``out_path``.  ``runtime``: the FMU's runtime
    ("standalone" or "pythonfmu"; None: the scene's ``fmu.runtime``); ``platforms``: binaries of a
    standalone FMU (gearfmu.fmu.crossbuild keys; None: all); ``tables``: MeshTables to use instead
    of the scene's physics (as :func:`gearfmu.pipeline.build`); ``fmi_version`` 3: an FMI 3.0 FMU
    (standalone runtime)."""
    out_path = Path(out_path)
    if out_path.suffix != ".ssp":
        raise SspError(f"out_path: must end in .ssp, got {str(out_path)!r}")
    with tempfile.TemporaryDirectory(prefix="gearfmu_ssp_fmu_") as d:
        res = build(scene, Path(d) / f"{scene.fmu.model_name}.fmu", progress=progress, tables=tables,
                    fmi_version=fmi_version, runtime=runtime, platforms=platforms)
        trange = res.tables.temperature_range_C
        tin = res.tables.temperature_input or "bulk_temperature"
        with ticking(f"writing the SSP package {out_path} (every .ssd and .ssv checked against its SSP 1.0 schema)",
                     enabled=progress or None):
            return build_ssp(res.fmu_path, out_path, variants or default_variants(res.settings.damping_ratio, trange,
                                                                                   tin),
                             stop_time_s=res.settings.stop_time_s, system_name=scene.fmu.model_name)


def ssp_fmu_name(ssp_path) -> str:
    """The archive name of the FMU inside an SSP package (``resources/<model>.fmu``)."""
    with zipfile.ZipFile(ssp_path) as z:
        names = [n for n in z.namelist() if n.startswith("resources/") and n.endswith(".fmu")]
    if not names:
        raise SspError(f"{ssp_path}: no resources/*.fmu in the package")
    return names[0]


def ssp_fmu_bytes(ssp_path) -> bytes:
    """The FMU inside an SSP package, as bytes."""
    with zipfile.ZipFile(ssp_path) as z:
        return z.read(ssp_fmu_name(ssp_path))


# ------------------------------------------------------------------ gearboxes
def gearbox_ssp(comp, out_path, *, stop_time_s: float, comm_step_s: float, name: str = "gearbox",
                description: str = "", fmi_version: int = 2, platforms=None, progress: bool = False) -> Path:
    """The SSP of stage FMUs of the composition ``comp`` (:func:`gearfmu.fmu.composition.compose`: the
    gearbox cut into its stage and element components for a coupling, with their start values) at
    ``out_path``: one FMU per stage and per end body (and per shaft with the "shaft" coupling), joined at
    the elastic shafts through OSP angular mechanical ports (docs/gearbox.md "The SSP of stage FMUs");
    every .ssd checked against the SSP 1.0 schema before the archive is written.  ``stop_time_s`` and
    ``comm_step_s`` (s): the run and the communication step the system is annotated with."""
    out_path = Path(out_path)
    if out_path.suffix != ".ssp":
        raise SspError(f"out_path: must end in .ssp, got {str(out_path)!r}")
    for key, v in (("stop_time_s", stop_time_s), ("comm_step_s", comm_step_s)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise SspError(f"{key}: must be finite and > 0, got {v!r}")
    with tempfile.TemporaryDirectory(prefix="gearfmu_gbssp_") as tmpd:
        stage = Path(tmpd)
        with ticking(f"building {len(comp.components)} FMUs ({', '.join(c.name for c in comp.components)})",
                     enabled=progress or None):
            write_composition(comp, stage, stop_time_s=stop_time_s, step_size_s=comm_step_s, name=name,
                              description=description or f"{name}: SSP of stage FMUs, {comp.coupling} coupling",
                              fmi_version=fmi_version, platforms=platforms)
        validate_ssp_dir(stage)
        _zip_folder(stage, out_path)
    return out_path


def ssp_from_drivetrain(scene, out_path, *, coupling: Optional[str] = None, comm_step_s: Optional[float] = None,
                        fmi_version: int = 2, platforms=None, progress: bool = False, allow_large: bool = False,
                        model=None) -> Path:
    """Drivetrain scene -> every stage's tables -> gearbox model -> the SSP of stage FMUs at ``out_path``
    (:func:`gearbox_ssp` with the gearbox FMU's run settings of the scene: start values, integrator,
    internal step and run; ``comm_step_s`` None: the scene's output interval; ``model``: the GearboxModel
    when already built)."""
    if model is None:
        model = st.gearbox_model(scene, st.stage_tables(scene, progress=progress, allow_large=allow_large))
    s = st.gearbox_fmu_settings(scene, model)
    comp = compose(model, coupling=coupling or DEFAULT_SSP_COUPLING, motor_torque_Nm=s.motor_torque_start_Nm,
                   load_torque_Nm=s.load_torque_start_Nm, motor_speed_rad_s=s.motor_speed_start_rad_s,
                   max_step_s=s.max_step_s, integrator=s.integrator or DEFAULT_INTEGRATOR)
    return gearbox_ssp(comp, out_path, stop_time_s=s.stop_time_s,
                       comm_step_s=s.output_interval_s if comm_step_s is None else comm_step_s,
                       name=scene.model_name, description=f"{scene.name}: SSP of stage FMUs",
                       fmi_version=fmi_version, platforms=platforms, progress=progress)
