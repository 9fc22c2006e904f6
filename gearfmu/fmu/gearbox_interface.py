"""The interface of a gearbox FMU from the spec ``modeldescription/gearbox.toml`` (docs/gearbox.md
"The gearbox FMU").

The spec is the single source of the variable names, causality, variability, units, start values
and descriptions; this module

* reads and checks it (:func:`load_gearbox_spec`; the same :class:`gearfmu.fmu.modeldesc.Spec` the
  pair's spec gives, so the model description writers of :mod:`gearfmu.fmu.modeldesc` serve both),
* expands it for a :class:`gearfmu.gearbox.model.GearboxModel` (:func:`gearbox_variables`):
  ``per = "part"`` entries for every part (``motor_speed``, ``stage1.pinion_angle``),
  ``per = "stage"`` for every stage (``stage1.dte``, ``stage1.pair_force[2]``), ``per = "shaft"`` for
  every elastic shaft (``input_shaft.torque``), with the absolute position of each output in the
  gearbox kernel's output vector (gbkernel.h: :func:`mesh_offset`, :func:`shaft_offset`),
* sets the start values of a build (:func:`apply_starts`).

The FMU's output names are the native gearbox solver's columns (gearfmu.gearbox.native.output_units).
"""
from __future__ import annotations

import math
import re
import tomllib
from dataclasses import replace
from pathlib import Path
from typing import Dict, List, Sequence

from ..gearbox.model import GearboxModel
from ..tables.zones import zone_cuts
from .modeldesc import (BASE_UNITS, CAUSALITIES, INITIALS, TYPES, UNIT_SCALING, VARIABILITIES, Spec, SpecError,
                        Variable)

__all__ = ["GEARBOX_SPEC_FORMAT", "FEATURES", "DEFAULT_GEARBOX_SPEC_PATH", "load_gearbox_spec", "features_of",
           "gearbox_variables", "mesh_offset", "shaft_offset", "n_outputs", "output_names", "stage_parameter",
           "apply_starts"]

GEARBOX_SPEC_FORMAT = "gearfmu-gearbox-variables"
SPEC_VERSIONS = (1,)
#: what `per` repeats an entry for, and how the name is made from the item's name
PER = {"part": "{item}_{name}", "stage": "{item}.{name}", "shaft": "{item}.{name}", "body": "{item}_{name}"}
#: conditions an entry may name in ``requires``: the motor (load) end is a torque input; Model Exchange
#: (its states, derivatives and contact indicators; a stage's zone indicators, checked per stage; the
#: table-node indicators)
FEATURES = ("motor_torque_input", "load_torque_input", "model_exchange", "zone_events", "node_events")
#: the gearbox kernel's output block of a mesh before its pair forces (gbkernel.h GB_OUT_PAIR_FORCE)
MESH_SCALARS = 4


def _default_spec_path() -> Path:
    """The spec in the source tree (``<repo>/modeldescription``) or, installed, ``gearfmu/modeldescription``."""
    here = Path(__file__).resolve().parent.parent
    for cand in (here.parent / "modeldescription" / "gearbox.toml", here / "modeldescription" / "gearbox.toml"):
        if cand.is_file():
            return cand
    return here.parent / "modeldescription" / "gearbox.toml"


DEFAULT_GEARBOX_SPEC_PATH = _default_spec_path()


def load_gearbox_spec(path=None, *, spec_format: str = GEARBOX_SPEC_FORMAT, per=None, features=FEATURES) -> Spec:
    """Read and check the gearbox spec (default ``modeldescription/gearbox.toml``); SpecError naming
    the entry and field.  ``spec_format``, ``per`` (the item kinds an entry may be repeated for,
    default :data:`PER`) and ``features``: another spec of the same form (the planetary FMU's,
    :mod:`gearfmu.fmu.planetary_interface`)."""
    per = PER if per is None else per
    p = Path(path) if path is not None else DEFAULT_GEARBOX_SPEC_PATH
    try:
        data = tomllib.loads(p.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise SpecError(f"{p}: gearbox interface spec not found") from None
    except tomllib.TOMLDecodeError as exc:
        raise SpecError(f"{p}: not valid TOML ({exc})") from None
    if data.get("format") != spec_format:
        raise SpecError(f"{p}: format is {data.get('format')!r}, expected {spec_format!r}")
    if data.get("version") not in SPEC_VERSIONS:
        raise SpecError(f"{p}: spec version {data.get('version')!r} unsupported (know {list(SPEC_VERSIONS)})")
    units = data.get("units", {})
    for uname, exps in units.items():
        for b, e in exps.items():
            if b in UNIT_SCALING:
                if isinstance(e, bool) or not isinstance(e, (int, float)) or not math.isfinite(e):
                    raise SpecError(f"{p}: units.{uname}: {b} = {e!r} must be a finite number")
            elif b not in BASE_UNITS or not isinstance(e, int):
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
            raise SpecError(f"{where}: derivative_of: a derivative is named der(<its state>)")
        if name in names:
            raise SpecError(f"{where}: name duplicated")
        names.add(name)
        for key, allowed in (("type", TYPES), ("causality", CAUSALITIES), ("variability", VARIABILITIES)):
            if ent.get(key) not in allowed:
                raise SpecError(f"{where}: {key} {ent.get(key)!r} not in {allowed}")
        if ent.get("initial") is not None and ent["initial"] not in INITIALS:
            raise SpecError(f"{where}: initial {ent['initial']!r} not in {INITIALS}")
        if ent.get("per") is not None and ent["per"] not in per:
            raise SpecError(f"{where}: per {ent['per']!r} not one of {sorted(per)}")
        if ent.get("per_slot") and ent.get("per") not in ("stage", "mesh"):
            raise SpecError(f"{where}: per_slot needs per = \"stage\" (the slots are a stage's)")
        unit = ent.get("unit")
        if unit is not None and unit not in units:
            raise SpecError(f"{where}: unit {unit!r} has no entry in [units]")
        if ent["type"] == "Integer" and unit is not None:
            raise SpecError(f"{where}: unit: FMI 2.0 Integer variables carry no unit")
        if ent["causality"] in ("input", "parameter") and "start" not in ent:
            raise SpecError(f"{where}: start: inputs and parameters need a start value")
        if ent["causality"] == "output" and ("output_index" not in ent or ent.get("per") is None):
            raise SpecError(f"{where}: output_index and per: every output is a part's, stage's or shaft's and "
                            "needs its position in the item's block of the kernel's output vector")
        if "requires" in ent and ent["requires"] not in features:
            raise SpecError(f"{where}: requires {ent['requires']!r} not one of {features}")
    knowns = {e["name"] for e in entries if e["causality"] in ("input", "parameter")}
    for i, ent in enumerate(entries):
        deps = ent.get("initial_dependencies")
        if deps is None:
            continue
        where = f"{p}: variable #{i + 1} ({ent['name']!r})"
        if ent["causality"] != "output" or ent.get("initial") not in ("approx", "calculated"):
            raise SpecError(f"{where}: initial_dependencies: only for outputs with initial = calculated/approx")
        if not isinstance(deps, list) or any(d not in knowns for d in deps) or len(set(deps)) != len(deps):
            raise SpecError(f"{where}: initial_dependencies must list distinct input/parameter names of the spec, "
                            f"got {deps!r}")
    return Spec(path=str(p), model=data.get("model", {}), default_experiment=data.get("default_experiment", {}),
                units=units, entries=entries)


def _derivative_name(name: str):
    """The state of a derivative's name ``der(<state>)``, else None."""
    m = re.fullmatch(r"der\(([A-Za-z_]\w*)\)", name)
    return m.group(1) if m else None


def features_of(model: GearboxModel, model_exchange: bool = False, node_events: bool = False) -> tuple:
    """The spec features (:data:`FEATURES`) of a gearbox: which ends are torque inputs; with
    ``model_exchange`` its states and indicators (``node_events``: the table-node indicators too;
    the zone indicators are decided per stage, :func:`gearbox_variables`)."""
    out = tuple(f for f, on in zip(FEATURES, (model.motor_torque_input, model.load_torque_input)) if on)
    if model_exchange:
        out += ("model_exchange", "zone_events") + (("node_events",) if node_events else ())
    return out


def me_stage_indicators(model: GearboxModel, node_events: bool) -> List[int]:
    """The number of event indicators of every stage (gk_me_n_indicators): 3 P, P more when its tables
    have contact-zone edges, 2 more with table-node events."""
    return [3 * m.tables.slots + (m.tables.slots if zone_cuts(m.tables) is not None else 0) + (2 if node_events else 0)
            for m in model.meshes]


# ------------------------------------------------------------ output layout
def mesh_offset(model: GearboxModel, m: int) -> int:
    """Position of mesh m's block in the gearbox kernel's output vector (gbkernel.h gb_mesh_offset):
    after the 2 values of every body and the 4 + 2 P of every mesh before it."""
    return 2 * model.n_bodies + sum(MESH_SCALARS + 2 * mm.tables.slots for mm in model.meshes[:m])


def shaft_offset(model: GearboxModel) -> int:
    """Position of the shaft torques in the output vector (gbkernel.h gb_shaft_offset)."""
    return mesh_offset(model, len(model.meshes))


def n_outputs(model: GearboxModel) -> int:
    """Length of the gearbox kernel's output vector (gbkernel.h gb_n_outputs)."""
    return shaft_offset(model) + len(model.shafts)


def _relative_index(raw, slots: int, where: str) -> int:
    if isinstance(raw, int) and not isinstance(raw, bool):
        return raw
    if isinstance(raw, str) and raw.replace(" ", "").endswith("+P"):
        return int(raw.replace(" ", "")[:-2]) + slots
    raise SpecError(f"{where}: output_index {raw!r} must be an integer or '<n>+P'")


def _blocks(entries):
    """Consecutive entries with the same ``per`` as (per, [entries])."""
    out = []
    for ent in entries:
        per = ent.get("per")
        if out and out[-1][0] == per and per is not None:
            out[-1][1].append(ent)
        else:
            out.append((per, [ent]))
    return out


def _me_index(raw, slots: int, where: str) -> int:
    """``me_state`` / ``me_indicator``: an integer, or "<n>P" / "<n>P+<k>" (n times the stage's slots, plus k)."""
    if isinstance(raw, int) and not isinstance(raw, bool):
        return raw
    m = re.fullmatch(r"(\d*)P(?:\+(\d+))?", raw.replace(" ", "")) if isinstance(raw, str) else None
    if m is None:
        raise SpecError(f"{where}: {raw!r} must be an integer, '<n>P' or '<n>P+<k>'")
    return int(m.group(1) or 1) * slots + int(m.group(2) or 0)


def me_block(model: GearboxModel) -> int:
    """Where the Model Exchange block starts in the output vector of gearbox_model.c: after the kernel's
    outputs; then the 2 n states, their 2 n derivatives and the event indicators."""
    return n_outputs(model)


def _me_output_index(ent, per, k, item_body, model, node_events, slots, where) -> int:
    """The absolute output index of a Model Exchange entry (item k of its ``per``)."""
    n2 = 2 * model.n_bodies
    if "me_state" in ent or "derivative_of" in ent:
        rel = _me_index(ent.get("me_state", 0), 0, where)
        pos = rel if per is None else 2 * item_body + rel
        return me_block(model) + pos
    ind = me_stage_indicators(model, node_events)
    rel = _me_index(ent["me_indicator"], slots, where)
    if ent.get("requires") == "node_events" and ind[k] - 2 - 3 * slots > 0:
        rel += slots   # after the zone indicators of a stage that has them
    return me_block(model) + 2 * n2 + sum(ind[:k]) + rel


def gearbox_variables(spec: Spec, model: GearboxModel, *, model_exchange: bool = False,
                      node_events: bool = False) -> List[Variable]:
    """The spec expanded for ``model`` (module docstring), numbered in order (value reference =
    position), with every output's absolute index in the kernel's output vector; with
    ``model_exchange`` the states, derivatives and event indicators too (``node_events``: the
    table-node indicators), their indices in the Model Exchange block (:func:`me_block`)."""
    feats = features_of(model, model_exchange, node_events)
    entries = [e for e in spec.entries if "requires" not in e or e["requires"] in feats]
    present = {e["name"] for e in entries}
    stages = [m.name for m in model.meshes]
    zones = [zone_cuts(m.tables) is not None for m in model.meshes]
    bodies = [model.bodies[b][0] for b in range(1, model.n_bodies)]
    items = {"part": list(model.parts), "stage": stages, "shaft": [s.name for s in model.shafts], "body": bodies,
             None: [None]}
    per_of = {e["name"]: e.get("per") for e in entries}
    out: List[Variable] = []
    for per, ents in _blocks(entries):
        for k, item in enumerate(items[per]):
            for ent in ents:
                if per == "stage" and ent.get("requires") == "zone_events" and not zones[k]:
                    continue   # a stage whose tables have no contact-zone edges has no zone indicators
                der = _derivative_name(ent["name"])
                name = ent["name"] if per is None else PER[per].format(item=item, name=ent["name"])
                derivative_of = ent.get("derivative_of")
                if der is not None and per is not None:
                    derivative_of = PER[per].format(item=item, name=der)
                    name = f"der({derivative_of})"
                slots = model.meshes[k].tables.slots if per == "stage" else 0
                deps = None
                if ent.get("initial_dependencies") is not None:
                    deps = []
                    for d in ent["initial_dependencies"]:
                        if d not in present:
                            continue   # a conditional variable this FMU does not carry
                        if per_of[d] == "stage":
                            deps += [f"{item}.{d}"] if per == "stage" else [f"{s}.{d}" for s in stages]
                        else:
                            deps.append(d)
                    deps = tuple(deps)
                base = None
                if "me_state" in ent or "derivative_of" in ent or "me_indicator" in ent:
                    base = _me_output_index(ent, per, k, k + 1, model, node_events, slots, f"{spec.path}: {name}")
                    if "derivative_of" in ent:
                        state = next(e for e in entries if e["name"] == ent["derivative_of"])
                        base += 2 * model.n_bodies + _me_index(state["me_state"], 0, name) - \
                            _me_index(ent.get("me_state", 0), 0, name)
                elif "output_index" in ent:
                    rel = _relative_index(ent["output_index"], slots, f"{spec.path}: {name}")
                    base = (2 * model.part_body[item] if per == "part" else mesh_offset(model, k) if per == "stage"
                            else shaft_offset(model) + k) + rel
                start = ent.get("start")
                if start is not None:
                    start = int(start) if ent["type"] == "Integer" else float(start)
                n_el = slots if ent.get("per_slot") else 1
                for i in range(n_el):
                    desc = ent.get("description", "")
                    vname = name
                    if ent.get("per_slot"):
                        vname = f"{name}[{i + 1}]"
                        desc = desc.replace("slot i", f"slot {i + 1}")
                    if per is not None:
                        desc = f"{desc} ({per} {item})"
                    out.append(Variable(
                        name=vname, value_reference=len(out), type=ent["type"], causality=ent["causality"],
                        variability=ent["variability"], initial=ent.get("initial"), unit=ent.get("unit"),
                        description=desc, start=start, min=ent.get("min"), max=ent.get("max"),
                        output_index=None if base is None else base + i,
                        build_override=bool(ent.get("build_override", False)), initial_dependencies=deps,
                        derivative_of=derivative_of, event_indicator=bool(ent.get("event_indicator", False))))
    return out


def stage_parameter(stage: str, name: str) -> str:
    """The FMU name of a per-stage parameter (``stage1.damping_ratio``)."""
    return PER["stage"].format(item=stage, name=name)


def output_names(variables: Sequence[Variable]) -> List[str]:
    """The output variables' names in value-reference order."""
    return [v.name for v in variables if v.causality == "output"]


def apply_starts(variables: Sequence[Variable], starts: Dict[str, float]) -> List[Variable]:
    """Start values of the build (``starts``: name -> value; SpecError for a name that is not a
    variable with a start value, or a value outside its min/max)."""
    by_name = {v.name: v for v in variables}
    for n in starts:
        if n not in by_name or by_name[n].start is None:
            raise SpecError(f"{n}: no variable with a start value of that name in the gearbox interface")
    out = []
    for v in variables:
        if v.name in starts:
            val = starts[v.name]
            val = int(val) if v.type == "Integer" else float(val)
            if v.type == "Real" and not math.isfinite(val):
                raise SpecError(f"{v.name}: start value must be finite, got {val!r}")
            if (v.min is not None and val < v.min) or (v.max is not None and val > v.max):
                raise SpecError(f"{v.name}: start value {val!r} outside [{v.min}, {v.max}]")
            v = replace(v, start=val)
        out.append(v)
    return out
