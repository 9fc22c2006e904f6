"""modelDescription.xml from the interface spec ``modeldescription/variables.toml``.

The spec is the single source of the FMU's variable names, causality,
variability, units, descriptions, start values and DefaultExperiment.  This
module

* reads and checks the spec (:func:`load_spec`),
* expands per-slot entries to ``name[1] .. name[P]`` and numbers the
  variables (value reference = 0-based position, the numbering pythonfmu uses
  for registered variables) (:func:`expand_variables`),
* writes the FMI 2.0 Co-Simulation model description
  (:func:`model_description_xml`) following the FMI 2.0.x standard
  (Modelica Association, *FMI 2.0 for Model Exchange and Co-Simulation*,
  section 2.2: UnitDefinitions 2.2.2, ModelVariables 2.2.7, ModelStructure
  2.2.8 -- Outputs lists every output, InitialUnknowns every output with
  initial = approx/calculated and every calculated parameter),
* checks a model description that pythonfmu produced from what the slave
  registered against the spec (:func:`check_registered`) and checks our own
  XML for internal consistency (:func:`check_model_description`),
* produces the variable table the FMU runtime reads
  (:func:`runtime_variable_table`).

Units: start values in the spec are SI in the unit the entry names.
"""
from __future__ import annotations

import math
import re
import tomllib
import xml.etree.ElementTree as ET
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

SPEC_FORMAT = "gearfmu-variables"
SPEC_VERSIONS = (1,)
def _default_spec_path() -> Path:
    """The spec in the source tree (``<repo>/modeldescription``) or, in an
    installed package, the same file that pyproject.toml maps into
    ``gearfmu/modeldescription``."""
    here = Path(__file__).resolve().parent.parent
    for cand in (here.parent / "modeldescription" / "variables.toml",
                 here / "modeldescription" / "variables.toml"):
        if cand.is_file():
            return cand
    return here.parent / "modeldescription" / "variables.toml"


DEFAULT_SPEC_PATH = _default_spec_path()

CAUSALITIES = ("parameter", "calculatedParameter", "input", "output", "local")
VARIABILITIES = ("constant", "fixed", "tunable", "discrete", "continuous")
INITIALS = ("exact", "approx", "calculated")
TYPES = ("Real", "Integer")
BASE_UNITS = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")
UNIT_SCALING = ("factor", "offset")
#: conditions an entry may name in ``requires`` (the FMU carries a variable only
#: when its tables need it): "temperature_axis" = the tables have a bulk
#: temperature axis (input bulk_temperature), "oil_temperature_axis" an oil
#: temperature axis (input oil_temperature), "gearbox_temperature_axis" a
#: gears-and-oil axis (input gearbox_temperature) (docs/tables.md "Operating
#: axes", docs/thermal.md)
FEATURES = ("temperature_axis", "oil_temperature_axis", "gearbox_temperature_axis",
            "model_exchange", "zone_events", "node_events")
#: the features of Model Exchange (the standalone runtime, docs/standalone.md "Model Exchange"):
#: the states, derivatives and contact indicators; the zone indicators (tables with contact-zone
#: edges); the segment indicators (node events asked for at build time)
ME_FEATURES = ("model_exchange", "zone_events", "node_events")
#: the interfaces an FMU may offer (modelDescription elements ModelExchange, CoSimulation)
INTERFACES = ("me", "cs")
#: FMU input selecting the temperature axis -> the feature that declares it
TEMPERATURE_INPUT_FEATURES = {"bulk_temperature": "temperature_axis", "oil_temperature": "oil_temperature_axis",
                              "gearbox_temperature": "gearbox_temperature_axis"}

#: log categories (the ones pythonfmu's wrapper logs with; the names FMI 2.0 and FMI 3.0 section
#: 2.4.5 define, plus logAll), each described with the status of the FMU's FMI version (fmi{v}Warning, ...)
LOG_CATEGORIES = {
    "logStatusWarning": "Log messages with fmi{v}Warning status.",
    "logStatusDiscard": "Log messages with fmi{v}Discard status.",
    "logStatusError": "Log messages with fmi{v}Error status.",
    "logStatusFatal": "Log messages with fmi{v}Fatal status.",
    "logAll": "Log all messages.",
}


def log_categories(fmi_version: int = 2) -> Dict[str, str]:
    """:data:`LOG_CATEGORIES` with the status names of FMI ``fmi_version`` (2 or 3)."""
    return {name: text.format(v=fmi_version) for name, text in LOG_CATEGORIES.items()}


class SpecError(ValueError):
    """The interface spec (variables.toml) is malformed; the message names the entry and field."""


class ModelDescriptionError(ValueError):
    """A model description disagrees with the spec or with itself."""


@dataclass(frozen=True)
class Spec:
    """The parsed interface spec."""

    path: str
    model: Mapping[str, str]
    default_experiment: Mapping[str, float]
    units: Mapping[str, Mapping[str, int]]
    entries: Sequence[Mapping[str, object]]


@dataclass(frozen=True)
class Variable:
    """One scalar variable of the FMU (after per-slot expansion)."""

    name: str
    value_reference: int
    type: str
    causality: str
    variability: str
    initial: Optional[str]
    unit: Optional[str]
    description: str
    start: Optional[Union[float, int]]
    min: Optional[Union[float, int]]
    max: Optional[Union[float, int]]
    output_index: Optional[int]  # position in the C kernel's output vector
    build_override: bool = False
    #: names of the inputs/parameters its Initialization-Mode value depends on (None: not declared)
    initial_dependencies: Optional[Tuple[str, ...]] = None
    #: Model Exchange: the state this variable is the derivative of (None: not a derivative)
    derivative_of: Optional[str] = None
    #: Model Exchange: an event indicator (FMI 3 ModelStructure/EventIndicator; FMI 2 counts them)
    event_indicator: bool = False


# ------------------------------------------------------------------ the spec
def load_spec(path=None) -> Spec:
    """Read and check the spec TOML (default: ``modeldescription/variables.toml``)."""
    p = Path(path) if path is not None else DEFAULT_SPEC_PATH
    try:
        data = tomllib.loads(p.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise SpecError(f"{p}: interface spec not found") from None
    except tomllib.TOMLDecodeError as exc:
        raise SpecError(f"{p}: not valid TOML ({exc})") from None
    if data.get("format") != SPEC_FORMAT:
        raise SpecError(f"{p}: format is {data.get('format')!r}, expected {SPEC_FORMAT!r}")
    if data.get("version") not in SPEC_VERSIONS:
        raise SpecError(f"{p}: spec version {data.get('version')!r} unsupported (know {list(SPEC_VERSIONS)})")
    units = data.get("units", {})
    for uname, exps in units.items():
        for b, e in exps.items():
            if b in UNIT_SCALING:  # FMI 2.0 BaseUnit factor / offset (e.g. degC: K = 1, offset = 273.15)
                if isinstance(e, bool) or not isinstance(e, (int, float)) or not math.isfinite(e):
                    raise SpecError(f"{p}: units.{uname}: {b} = {e!r} must be a finite number")
                continue
            if b not in BASE_UNITS or not isinstance(e, int):
                raise SpecError(f"{p}: units.{uname}: base unit {b!r} = {e!r} (need one of {BASE_UNITS}, integer exponent)")
    entries = data.get("variable", [])
    if not entries:
        raise SpecError(f"{p}: no [[variable]] entries")
    names = set()
    for i, ent in enumerate(entries):
        where = f"{p}: variable #{i + 1} ({ent.get('name', '?')!r})"
        name = ent.get("name")
        if not isinstance(name, str) or not (name.isidentifier() or _derivative_name(name)):
            raise SpecError(f"{where}: name must be an identifier (or der(<identifier>) of a derivative)")
        if "derivative_of" in ent and _derivative_name(name) != ent["derivative_of"]:
            raise SpecError(f"{where}: derivative_of: a derivative is named der(<its state>), "
                            f"got derivative_of = {ent['derivative_of']!r}")
        if not isinstance(ent.get("event_indicator", False), bool):
            raise SpecError(f"{where}: event_indicator must be true or false")
        if name in names:
            raise SpecError(f"{where}: name duplicated")
        names.add(name)
        if ent.get("type") not in TYPES:
            raise SpecError(f"{where}: type {ent.get('type')!r} not in {TYPES}")
        if ent.get("causality") not in CAUSALITIES:
            raise SpecError(f"{where}: causality {ent.get('causality')!r} not in {CAUSALITIES}")
        if ent.get("variability") not in VARIABILITIES:
            raise SpecError(f"{where}: variability {ent.get('variability')!r} not in {VARIABILITIES}")
        if ent.get("initial") is not None and ent["initial"] not in INITIALS:
            raise SpecError(f"{where}: initial {ent['initial']!r} not in {INITIALS}")
        unit = ent.get("unit")
        if unit is not None and unit not in units:
            raise SpecError(f"{where}: unit {unit!r} has no entry in [units]")
        if ent["type"] == "Integer" and unit is not None:
            raise SpecError(f"{where}: unit: FMI 2.0 Integer variables carry no unit")
        if ent["causality"] in ("input", "parameter") and "start" not in ent:
            raise SpecError(f"{where}: start: inputs and parameters need a start value")
        if ent["causality"] == "output" and "output_index" not in ent:
            raise SpecError(f"{where}: output_index: every output needs its kernel output position")
        if not isinstance(ent.get("description", ""), str):
            raise SpecError(f"{where}: description must be a string")
        if "requires" in ent and ent["requires"] not in FEATURES:
            raise SpecError(f"{where}: requires {ent['requires']!r} not one of {FEATURES}")
    for i, ent in enumerate(entries):
        if "derivative_of" in ent and ent["derivative_of"] not in names:
            raise SpecError(f"{p}: variable #{i + 1} ({ent['name']!r}): derivative_of {ent['derivative_of']!r} "
                            "is not a variable of the spec")
    knowns = {e["name"] for e in entries if e["causality"] in ("input", "parameter")}
    for i, ent in enumerate(entries):
        if "initial_dependencies" not in ent:
            continue
        where = f"{p}: variable #{i + 1} ({ent['name']!r})"
        deps = ent["initial_dependencies"]
        if ent["causality"] != "output" or ent.get("initial") not in ("approx", "calculated"):
            raise SpecError(f"{where}: initial_dependencies: only for outputs with initial = calculated/approx")
        if not isinstance(deps, list) or any(d not in knowns for d in deps) or len(set(deps)) != len(deps):
            raise SpecError(f"{where}: initial_dependencies must list distinct input/parameter names "
                            f"of the spec, got {deps!r}")
    de = data.get("default_experiment", {})
    for k in ("start_time_s", "stop_time_s", "step_size_s"):
        if k in de and not (isinstance(de[k], (int, float)) and math.isfinite(de[k])):
            raise SpecError(f"{p}: default_experiment.{k} must be a finite number")
    return Spec(path=str(p), model=data.get("model", {}), default_experiment=de, units=units, entries=entries)


def _derivative_name(name: str) -> Optional[str]:
    """The state of a derivative's name ``der(<state>)``, else None."""
    m = re.fullmatch(r"der\(([A-Za-z_]\w*)\)", name)
    return m.group(1) if m else None


def _output_index(raw, slots: int, slot: int, where: str) -> int:
    m = re.fullmatch(r"(\d+)\+(\d*)P", raw.replace(" ", "")) if isinstance(raw, str) else None
    if isinstance(raw, int) and not isinstance(raw, bool):
        base = raw
    elif m:
        base = int(m.group(1)) + int(m.group(2) or 1) * slots
    else:
        raise SpecError(f"{where}: output_index {raw!r} must be an integer or '<n>+P', '<n>+<k>P'")
    return base + slot


def features_of(tables) -> tuple:
    """The spec features (:data:`FEATURES`) a table set needs."""
    if not getattr(tables, "has_temperature_axis", False):
        return ()
    name = getattr(tables, "temperature_input", None) or "bulk_temperature"
    if name not in TEMPERATURE_INPUT_FEATURES:
        raise SpecError(f"tables: temperature input {name!r} not one of {sorted(TEMPERATURE_INPUT_FEATURES)}")
    return (TEMPERATURE_INPUT_FEATURES[name],)


def expand_variables(spec: Spec, slots: int, features: Iterable[str] = ()) -> List[Variable]:
    """Expand per-slot entries for ``slots`` tooth-pair slots and number all
    variables.  An entry with ``requires = "<feature>"`` is kept only when the
    feature is in ``features`` (the FMU carries only what its tables need); the
    spec lists such entries last so that the value references of the others do
    not depend on them."""
    if not isinstance(slots, int) or slots < 1:
        raise SpecError(f"slots: need an integer >= 1, got {slots!r}")
    features = tuple(features)
    for f in features:
        if f not in FEATURES:
            raise SpecError(f"features: {f!r} not one of {FEATURES}")
    out: List[Variable] = []
    present = {e["name"] for e in spec.entries if "requires" not in e or e["requires"] in features}
    for ent in spec.entries:
        if "requires" in ent and ent["requires"] not in features:
            continue
        deps = ent.get("initial_dependencies")
        if deps is not None:  # conditional variables this FMU does not carry drop out
            deps = tuple(d for d in deps if d in present)
        per_slot = bool(ent.get("per_slot", False))
        for i in range(slots if per_slot else 1):
            name = f"{ent['name']}[{i + 1}]" if per_slot else ent["name"]
            oi = None
            if "output_index" in ent:
                oi = _output_index(ent["output_index"], slots, i, f"{spec.path}: {name}")
            start = ent.get("start")
            if start is not None:
                start = int(start) if ent["type"] == "Integer" else float(start)
            initial = ent.get("initial")
            if initial is None and ent["causality"] in ("input", "parameter"):
                initial = None  # FMI default (exact for parameters; none for inputs)
            desc = ent.get("description", "")
            if per_slot:
                desc = desc.replace("slot i", f"slot {i + 1}")
            out.append(Variable(
                name=name, value_reference=len(out), type=ent["type"], causality=ent["causality"],
                variability=ent["variability"], initial=initial, unit=ent.get("unit"),
                description=desc, start=start, min=ent.get("min"), max=ent.get("max"),
                output_index=oi, build_override=bool(ent.get("build_override", False)),
                initial_dependencies=deps, derivative_of=ent.get("derivative_of"),
                event_indicator=bool(ent.get("event_indicator", False)),
            ))
    return out


def apply_start_values(variables: Sequence[Variable], starts: Mapping[str, Union[float, int]]) -> List[Variable]:
    """Replace start values (build-time choices).  Unknown names and variables
    without a start value raise :class:`SpecError`; values are range-checked
    against the spec's min/max."""
    by_name = {v.name: v for v in variables}
    for n in starts:
        if n not in by_name:
            raise SpecError(f"{n}: no such variable in the spec")
        if by_name[n].start is None:
            raise SpecError(f"{n}: has no start value (causality {by_name[n].causality})")
    out = []
    for v in variables:
        if v.name in starts:
            val = starts[v.name]
            if v.type == "Integer":
                if isinstance(val, bool) or int(val) != val:
                    raise SpecError(f"{v.name}: Integer start value expected, got {val!r}")
                val = int(val)
            else:
                val = float(val)
                if not math.isfinite(val):
                    raise SpecError(f"{v.name}: start value must be finite, got {val!r}")
            if v.min is not None and val < v.min:
                raise SpecError(f"{v.name}: start value {val!r} below min {v.min!r}")
            if v.max is not None and val > v.max:
                raise SpecError(f"{v.name}: start value {val!r} above max {v.max!r}")
            v = replace(v, start=val)
        out.append(v)
    return out


# --------------------------------------------------------------------- XML
def _num(v, typ: str) -> str:
    return str(int(v)) if typ == "Integer" else repr(float(v))


def _with_note(text: str, note: Optional[str]) -> str:
    """``text`` with the sentence ``note`` appended (a full stop between them)."""
    text = text.strip()
    if not note:
        return text
    if text and not text.endswith((".", "!", "?")):
        text += "."
    return f"{text} {note}".strip()


def _root_element(spec: Spec, attrib: dict, version: Optional[str], generation_date: Optional[str]):
    """``<fmiModelDescription>`` with ``attrib`` plus the spec's author/license, version and date."""
    attrib = dict(attrib)
    for key in ("author", "license"):
        if spec.model.get(key):
            attrib[key] = str(spec.model[key])
    if version:
        attrib["version"] = version
    if generation_date:
        attrib["generationDateAndTime"] = generation_date
    return ET.Element("fmiModelDescription", attrib)


def _units_logs_experiment(root, spec: Spec, units, stop_time_s, step_size_s, fmi_version: int = 2) -> None:
    """UnitDefinitions (``units``), LogCategories and DefaultExperiment: the same elements in FMI 2.0
    and FMI 3.0 model descriptions."""
    if units:
        ud = ET.SubElement(root, "UnitDefinitions")
        for u in sorted(units):
            ue = ET.SubElement(ud, "Unit", {"name": u})
            exps = spec.units[u]
            if exps:
                ET.SubElement(ue, "BaseUnit", {b: (repr(float(e)) if b in UNIT_SCALING else str(e))
                                               for b, e in exps.items()})
    cats = ET.SubElement(root, "LogCategories")
    for c, d in log_categories(fmi_version).items():
        ET.SubElement(cats, "Category", {"name": c, "description": d})
    de = dict(spec.default_experiment)
    if stop_time_s is not None:
        de["stop_time_s"] = stop_time_s
    if step_size_s is not None:
        de["step_size_s"] = step_size_s
    dea = {xml_key: repr(float(de[key])) for key, xml_key in
           (("start_time_s", "startTime"), ("stop_time_s", "stopTime"), ("step_size_s", "stepSize")) if key in de}
    if dea:
        ET.SubElement(root, "DefaultExperiment", dea)


def state_names(variables: Sequence[Variable]) -> List[str]:
    """The continuous states (Model Exchange) in the order of the state vector: the variables the
    derivatives name, in the order of the derivatives."""
    return [v.derivative_of for v in variables if v.derivative_of is not None]


def is_initial_unknown(v: Variable, states: Iterable[str]) -> bool:
    """In ModelStructure/InitialUnknowns (FMI 2.0 section 2.2.8, FMI 3.0 section 2.4.8): the outputs
    and the continuous states with initial approx/calculated, every state derivative, and the
    calculated parameters."""
    calculated = v.initial in ("approx", "calculated")
    return ((v.causality == "output" and calculated) or v.causality == "calculatedParameter"
            or (v.causality == "local" and calculated and (v.derivative_of is not None or v.name in states)))


def _check_interfaces(interfaces: Sequence[str]) -> Tuple[str, ...]:
    out = tuple(i for i in INTERFACES if i in interfaces)
    if not out or len(out) != len(tuple(interfaces)):
        raise ModelDescriptionError(f"interfaces: {tuple(interfaces)!r} must name one or both of {INTERFACES}")
    return out


def _interfaces_text(desc: str, interfaces: Sequence[str]) -> str:
    """The spec's description with its "Co-Simulation" naming the interfaces the FMU offers."""
    names = {("cs",): "Co-Simulation", ("me",): "Model Exchange", ("me", "cs"): "Co-Simulation and Model Exchange"}
    return desc.replace("Co-Simulation", names[tuple(interfaces)])


#: FMI 2.0 ModelExchange attributes of an FMU that offers it (the standalone runtime)
_ME2 = {"needsExecutionTool": "false", "completedIntegratorStepNotNeeded": "false",
        "canBeInstantiatedOnlyOncePerProcess": "false", "canNotUseMemoryManagementFunctions": "true",
        "canGetAndSetFMUstate": "true", "canSerializeFMUstate": "true"}


def model_description_xml(spec: Spec, variables: Sequence[Variable], *, model_name: str,
                          model_identifier: str, guid: str, stop_time_s: Optional[float] = None,
                          step_size_s: Optional[float] = None, generation_tool: str = "gearfmu",
                          generation_date: Optional[str] = None, version: Optional[str] = None,
                          description_note: Optional[str] = None, interfaces: Sequence[str] = ("cs",)) -> bytes:
    """The FMI 2.0 ``modelDescription.xml`` (UTF-8 bytes) for ``variables``, with the elements of
    ``interfaces`` ("me": ModelExchange, "cs": CoSimulation); ``description_note`` is appended to
    the spec's description (the verified envelope)."""
    interfaces = _check_interfaces(interfaces)
    attrib = {
        "fmiVersion": "2.0", "modelName": model_name, "guid": guid,
        "description": _with_note(_interfaces_text(str(spec.model.get("description", "")), interfaces),
                                  description_note),
        "generationTool": generation_tool, "variableNamingConvention": "structured",
        "numberOfEventIndicators": str(sum(v.event_indicator for v in variables)),
    }
    root = _root_element(spec, attrib, version, generation_date)
    if "me" in interfaces:
        ET.SubElement(root, "ModelExchange", dict(modelIdentifier=model_identifier, **_ME2))
    if "cs" not in interfaces:
        return _fmi2_rest(root, spec, variables, stop_time_s, step_size_s)
    ET.SubElement(root, "CoSimulation", {
        "modelIdentifier": model_identifier,
        "needsExecutionTool": "true",  # the pythonfmu runtime needs a Python interpreter
        "canHandleVariableCommunicationStepSize": "true",
        "canInterpolateInputs": "false",
        "canBeInstantiatedOnlyOncePerProcess": "false",
        "canNotUseMemoryManagementFunctions": "true",
        # the runtime saves its whole internal state (docs/robustness.md "FMU state")
        "canGetAndSetFMUstate": "true",
        "canSerializeFMUstate": "true",
    })
    return _fmi2_rest(root, spec, variables, stop_time_s, step_size_s)


def _fmi2_rest(root, spec: Spec, variables: Sequence[Variable], stop_time_s, step_size_s) -> bytes:
    """The FMI 2.0 model description after its interface elements: units, log categories, default
    experiment, ModelVariables and ModelStructure."""
    _units_logs_experiment(root, spec, {v.unit for v in variables if v.unit is not None}, stop_time_s, step_size_s)
    index = {v.name: i + 1 for i, v in enumerate(variables)}
    states = state_names(variables)
    mv = ET.SubElement(root, "ModelVariables")
    for i, v in enumerate(variables):
        if v.value_reference != i:
            raise ModelDescriptionError(f"{v.name}: value reference {v.value_reference} but position {i}")
        va = {"name": v.name, "valueReference": str(v.value_reference), "description": v.description,
              "causality": v.causality, "variability": v.variability}
        if v.initial is not None:
            va["initial"] = v.initial
        sv = ET.SubElement(mv, "ScalarVariable", va)
        ta = {}
        if v.unit is not None:
            ta["unit"] = v.unit
        if v.min is not None:
            ta["min"] = _num(v.min, v.type)
        if v.max is not None:
            ta["max"] = _num(v.max, v.type)
        if v.start is not None:
            ta["start"] = _num(v.start, v.type)
        if v.derivative_of is not None:
            ta["derivative"] = str(index[v.derivative_of])
        ET.SubElement(sv, v.type, ta)
    ms = ET.SubElement(root, "ModelStructure")
    outs = [i + 1 for i, v in enumerate(variables) if v.causality == "output"]
    if outs:
        oe = ET.SubElement(ms, "Outputs")
        for idx in outs:
            ET.SubElement(oe, "Unknown", {"index": str(idx)})
    ders = [i + 1 for i, v in enumerate(variables) if v.derivative_of is not None]
    if ders:  # in the order of the state vector (FMI 2.0 section 2.2.8)
        de = ET.SubElement(ms, "Derivatives")
        for idx in ders:
            ET.SubElement(de, "Unknown", {"index": str(idx)})
    iu = [i + 1 for i, v in enumerate(variables) if is_initial_unknown(v, states)]
    if iu:
        ie = ET.SubElement(ms, "InitialUnknowns")
        for idx in iu:
            ua = {"index": str(idx)}
            deps = initial_dependency_indices(variables, variables[idx - 1])
            if deps is not None:  # FMI 2.0 section 2.2.8: absent = depends on all knowns
                ua["dependencies"] = " ".join(str(d) for d in deps)
            ET.SubElement(ie, "Unknown", ua)
    ET.indent(root, space="  ")
    return b'<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="utf-8") + b"\n"


# ------------------------------------------------------------- FMI 3.0 XML
#: FMI 3.0 type of each spec type
FMI3_TYPES = {"Real": "Float64", "Integer": "Int32"}


@dataclass(frozen=True)
class Variable3:
    """One FMI 3 variable: a scalar of the spec, or the array ``name`` of the per-slot
    elements ``name[1] .. name[n]`` (value reference = that of ``name[1]``)."""
    name: str
    value_reference: int
    size: Optional[int]          # None: a scalar; else the array length (<Dimension start=...>)
    first: Variable              # the (first) element: type, causality, unit, start, ...


def fmi3_variables(variables: Sequence[Variable]) -> List[Variable3]:
    """Group the expanded variables into FMI 3 variables: ``name[1] .. name[P]`` (consecutive value
    references, the per-slot entries of the spec) become one array ``name`` -- the same grouping the
    C layer makes (gf_resources.c gfr_mark_arrays)."""
    out: List[Variable3] = []
    i = 0
    while i < len(variables):
        v = variables[i]
        if v.name.endswith("[1]"):
            base, n = v.name[:-3], 1
            while i + n < len(variables) and variables[i + n].name == f"{base}[{n + 1}]":
                n += 1
            out.append(Variable3(base, v.value_reference, n, v))
            i += n
        else:
            out.append(Variable3(v.name, v.value_reference, None, v))
            i += 1
    return out


def fmi3_time_vr(variables: Sequence[Variable]) -> int:
    """Value reference of the FMI 3 independent variable ``time``: after every spec variable
    (the C layer: n_vars)."""
    return len(variables)


def model_description_xml3(spec: Spec, variables: Sequence[Variable], *, model_name: str,
                           model_identifier: str, guid: str, stop_time_s: Optional[float] = None,
                           step_size_s: Optional[float] = None, generation_tool: str = "gearfmu",
                           generation_date: Optional[str] = None, version: Optional[str] = None,
                           description_note: Optional[str] = None, interfaces: Sequence[str] = ("cs",)) -> bytes:
    """The FMI 3.0 Co-Simulation ``modelDescription.xml`` of the standalone runtime (FMI 3.0
    standard section 2.4: ModelVariables 2.4.7 with arrays (``<Dimension start=P>``, the slot
    count fixed at build), ModelStructure 2.4.8 by value reference).  The same variables, names and
    value references as the FMI 2 FMU (:func:`model_description_xml`) except that the per-slot
    elements ``name[i]`` are the array ``name`` (:func:`fmi3_variables`), plus the independent
    variable ``time`` (:func:`fmi3_time_vr`)."""
    interfaces = _check_interfaces(interfaces)
    desc = _with_note(_interfaces_text(str(spec.model.get("description", "")).replace("FMI 2.0", "FMI 3.0"),
                                       interfaces), description_note)
    attrib = {"fmiVersion": "3.0", "modelName": model_name, "instantiationToken": guid, "description": desc,
              "generationTool": generation_tool, "variableNamingConvention": "structured"}
    root = _root_element(spec, attrib, version, generation_date)
    common = {"modelIdentifier": model_identifier, "needsExecutionTool": "false",
              "canBeInstantiatedOnlyOncePerProcess": "false", "canGetAndSetFMUState": "true",
              "canSerializeFMUState": "true"}
    if "me" in interfaces:
        ET.SubElement(root, "ModelExchange", dict(common, needsCompletedIntegratorStep="true",
                                                  providesEvaluateDiscreteStates="false"))
    if "cs" in interfaces:
        ET.SubElement(root, "CoSimulation", dict(common, canHandleVariableCommunicationStepSize="true",
                                                 hasEventMode="false", providesIntermediateUpdate="false"))
    _units_logs_experiment(root, spec, {v.unit for v in variables if v.unit is not None} | {"s"}, stop_time_s,
                           step_size_s, fmi_version=3)
    mv = ET.SubElement(root, "ModelVariables")
    ET.SubElement(mv, "Float64", {"name": "time", "valueReference": str(fmi3_time_vr(variables)),
                                  "causality": "independent", "variability": "continuous", "unit": "s",
                                  "description": "Simulation time"})
    vars3 = fmi3_variables(variables)
    vr_of = {}
    for v3 in vars3:
        for k in range(v3.size or 1):
            vr_of[variables[v3.first.value_reference + k].name] = v3.value_reference
    for v3 in vars3:
        v = v3.first
        desc = v.description.replace("slot 1", "slot i") if v3.size else v.description
        va = {"name": v3.name, "valueReference": str(v3.value_reference), "description": desc,
              "causality": v.causality, "variability": v.variability}
        if v.initial is not None:
            va["initial"] = v.initial
        if v.unit is not None:
            va["unit"] = v.unit
        for key in ("min", "max", "start"):
            val = getattr(v, key)
            if val is not None:
                va[key] = " ".join([_num(val, v.type)] * (v3.size or 1))
        if v.derivative_of is not None:
            va["derivative"] = str(vr_of[v.derivative_of])
        el = ET.SubElement(mv, FMI3_TYPES[v.type], va)
        if v3.size:
            ET.SubElement(el, "Dimension", {"start": str(v3.size)})
    states = state_names(variables)
    ms = ET.SubElement(root, "ModelStructure")  # Output, ContinuousStateDerivative, InitialUnknown, EventIndicator
    for v3 in vars3:
        if v3.first.causality == "output":
            ET.SubElement(ms, "Output", {"valueReference": str(v3.value_reference)})
    for v3 in vars3:
        if v3.first.derivative_of is not None:
            ET.SubElement(ms, "ContinuousStateDerivative", {"valueReference": str(v3.value_reference)})
    for v3 in vars3:
        v = v3.first
        if is_initial_unknown(v, states):
            ua = {"valueReference": str(v3.value_reference)}
            if v.initial_dependencies is not None:
                ua["dependencies"] = " ".join(str(r) for r in sorted({vr_of[n] for n in v.initial_dependencies}))
            ET.SubElement(ms, "InitialUnknown", ua)
    for v3 in vars3:
        if v3.first.event_indicator:
            ET.SubElement(ms, "EventIndicator", {"valueReference": str(v3.value_reference)})
    ET.indent(root, space="  ")
    return b'<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="utf-8") + b"\n"


def check_model_description3(xml_bytes: bytes, variables: Sequence[Variable]) -> None:
    """Check an FMI 3 model description against ``variables``: every spec variable is there under its
    FMI 3 name (arrays with their length) with its value reference, type and causality, plus ``time``."""
    root = ET.fromstring(xml_bytes)
    got = {}
    for el in root.find("ModelVariables"):
        dim = el.find("Dimension")
        got[el.get("name")] = (el.tag, int(el.get("valueReference")), el.get("causality"),
                               None if dim is None else int(dim.get("start")))
    want = {v3.name: (FMI3_TYPES[v3.first.type], v3.value_reference, v3.first.causality, v3.size)
            for v3 in fmi3_variables(variables)}
    want["time"] = ("Float64", fmi3_time_vr(variables), "independent", None)
    if got != want:
        diff = sorted(set(got.items()) ^ set(want.items()))
        raise ModelDescriptionError(f"FMI 3 model description and spec disagree: {diff}")


def initial_dependency_indices(variables: Sequence[Variable], v: Variable) -> Optional[List[int]]:
    """The 1-based, ascending ScalarVariable indices of ``v.initial_dependencies`` (None: undeclared)."""
    if v.initial_dependencies is None:
        return None
    index = {x.name: i + 1 for i, x in enumerate(variables)}
    return sorted(index[n] for n in v.initial_dependencies)


# ------------------------------------------------------------------ checks
def _xml_variables(xml_bytes: bytes) -> List[dict]:
    try:
        root = ET.fromstring(xml_bytes)
    except ET.ParseError as exc:
        raise ModelDescriptionError(f"modelDescription.xml: not well-formed XML ({exc})") from None
    out = []
    for sv in root.iter("ScalarVariable"):
        typ = next((c.tag for c in sv if c.tag in ("Real", "Integer", "Boolean", "String", "Enumeration")), None)
        out.append({"name": sv.get("name"), "valueReference": int(sv.get("valueReference")),
                    "causality": sv.get("causality", "local"), "variability": sv.get("variability", "continuous"),
                    "type": typ})
    return out


def check_registered(registered_xml: bytes, variables: Sequence[Variable]) -> None:
    """Check that the variables a slave registered (pythonfmu's generated model
    description) match the spec: same names in the same order, same value
    references, causality, variability and type.  Raises
    :class:`ModelDescriptionError` listing every difference."""
    reg = _xml_variables(registered_xml)
    problems = []
    if len(reg) != len(variables):
        problems.append(f"slave registers {len(reg)} variables, spec has {len(variables)}")
    for r, v in zip(reg, variables):
        want = {"name": v.name, "valueReference": v.value_reference, "causality": v.causality,
                "variability": v.variability, "type": v.type}
        for key, val in want.items():
            if r[key] != val:
                problems.append(f"{v.name}: {key} is {r[key]!r} in the slave, {val!r} in the spec")
    if problems:
        raise ModelDescriptionError("slave and spec disagree: " + "; ".join(problems))


def check_model_description(xml_bytes: bytes, variables: Sequence[Variable]) -> None:
    """Check a produced model description against ``variables``: names, value
    references, start values, units defined, Outputs and InitialUnknowns sets."""
    root = ET.fromstring(xml_bytes)
    check_registered(xml_bytes, variables)
    defined = {u.get("name") for u in root.iter("Unit")}
    problems = []
    svs = list(root.iter("ScalarVariable"))
    for sv, v in zip(svs, variables):
        te = sv.find(v.type)
        if v.unit is not None and te.get("unit") not in defined:
            problems.append(f"{v.name}: unit {te.get('unit')!r} not in UnitDefinitions")
        if v.start is not None:
            got = te.get("start")
            if got is None or float(got) != float(v.start):
                problems.append(f"{v.name}: start {got!r}, expected {v.start!r}")
    ms = root.find("ModelStructure")
    outs = [int(u.get("index")) for u in ms.find("Outputs")] if ms.find("Outputs") is not None else []
    want_outs = [i + 1 for i, v in enumerate(variables) if v.causality == "output"]
    if outs != want_outs:
        problems.append(f"ModelStructure/Outputs {outs} != {want_outs}")
    iu_el = ms.find("InitialUnknowns")
    iu = [int(u.get("index")) for u in iu_el] if iu_el is not None else []
    states = state_names(variables)
    want_iu = [i + 1 for i, v in enumerate(variables) if is_initial_unknown(v, states)]
    if iu != want_iu:
        problems.append(f"ModelStructure/InitialUnknowns {iu} != {want_iu}")
    for u in (iu_el if iu_el is not None else []):
        v = variables[int(u.get("index")) - 1]
        want = initial_dependency_indices(variables, v)
        got = None if u.get("dependencies") is None else [int(x) for x in u.get("dependencies").split()]
        if got != want:
            problems.append(f"ModelStructure/InitialUnknowns {v.name}: dependencies {got} != {want}")
    if problems:
        raise ModelDescriptionError("; ".join(problems))


def runtime_variable_table(variables: Iterable[Variable]) -> List[dict]:
    """The list the FMU runtime registers, in value-reference order (JSON-ready)."""
    return [{"name": v.name, "vr": v.value_reference, "type": v.type, "causality": v.causality,
             "variability": v.variability, "initial": v.initial, "start": v.start,
             "min": v.min, "max": v.max, "output_index": v.output_index, "description": v.description}
            for v in variables]
