"""The planner's modelling choices and their levels (docs/plan.md "Choices and levels").

:func:`choices_of` lists, for a scene, its envelope and its accuracy target, every choice of
``gearfmu.scene.envelope.PLAN_CHOICES`` with its levels (cheapest first, the last one the
full-fidelity level); a choice the envelope cannot need gets one level and a reason
(:func:`skipped_choices`).  :func:`what_if_contact` lists the other contact models,
:func:`thermal_options` the ``[thermal]`` options of a kept thermal level.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Dict, List, Optional, Tuple

import numpy as np

from ..common.vocabulary import INTEGRATORS, LUBRICATED_CONTACT_MODELS
from ..contact.models import CONTACT_MODELS, get_contact_model
from ..gear.geometry import pair_geometry
from ..gear.meshing_errors import pair_table_mesh_count
from ..gear.stiffness import required_slots
from ..scene.envelope import AccuracyTarget, Envelope
from ..scene.reader import ThermalOptions
from ..scene.physics import estimate_build

#: the integrator levels the planner measures, the last the full model's: rk4 (cheapest),
#: rk4_seg (stops only at contact-zone edges, big kinks and contact events: cheaper than rk4_node
#: when a step spans several table cells, dearer per step below that), rk4_node (the default:
#: contact events and the table nodes where the tables bend, their crossings predicted), then
#: rk4_kink (every table node and contact event located; at one step the most accurate, so the
#: full-fidelity reference).  rk4_seg and rk4_node trade places in cost with the step, so the
#: greedy rule compares the levels' measured costs (gearfmu.plan.planner, not the order).
PLAN_INTEGRATOR_LEVELS = ("rk4", "rk4_seg", "rk4_node", "rk4_kink")
assert set(PLAN_INTEGRATOR_LEVELS) <= set(INTEGRATORS)
#: choices whose levels are not in cost order at every step: all their levels are measured (a
#: negligible budget use of one level does not skip the next ones, which may be cheaper)
LEVELS_NOT_COST_ORDERED = ("integrator",)

#: contact models from the cheapest to the most detailed
CONTACT_ORDER = ("hertz", "smooth_ehl", "rough_ehl")
_PPM_LEVELS = (16, 32, 64, 128, 256)
_TORQUE_LEVELS = (1, 2, 3, 5, 9)
_STEP_FACTORS = (4.0, 2.0, 1.0, 0.5, 0.25)
_THERMAL_AXIS_POINTS = 3  # temperature axis of a kept thermal choice without a scene axis (CHOICE)
#: plan-time budget of one reference table build, in s of gearfmu.assembly.estimate's model (CHOICE):
#: the full-fidelity points per mesh are the finest level whose estimate fits, never below the scene's
PLAN_TABLE_BUILD_S = 60.0
#: when the reference build is above PLAN_TABLE_BUILD_S: the table work (slices x angles x torque rows x
#: slots x temperatures) that the per-choice levels may build, as a share of the reference build's (CHOICE);
#: a level whose tables would exceed it is not measured and is listed with this reason
PLAN_LEVEL_TABLE_WORK = 0.5


class PlanError(ValueError):
    """The planner cannot plan a scene (names the field and the reason)."""


# ============================================================== choices
@dataclass
class Choice:
    """One modelling choice: its levels (cheapest first, last = full), whether the
    scene pins it, and the measurements of each level against the full model."""

    name: str
    levels: list
    pinned: bool = False
    note: str = ""
    measured: Dict[int, dict] = field(default_factory=dict)  # level index -> measures
    skipped: str = ""  # why the choice has one level although the scene does not pin it
    skipped_levels: Dict[int, str] = field(default_factory=dict)  # level index -> why it was not measured

    @property
    def full(self):
        return self.levels[-1]

    @property
    def fixed(self) -> bool:
        return len(self.levels) <= 1


def _available_contact_models() -> Tuple[str, ...]:
    """Contact models the table builder offers: the registry
    ``gearfmu.contact.models.CONTACT_MODELS``."""
    return tuple(n for n in CONTACT_MODELS if isinstance(n, str))


def min_slots(scene) -> int:
    return required_slots(pair_geometry(scene.pair))


def _teeth_differ(scene, slots: int) -> bool:
    return pair_table_mesh_count(scene.pair, slots) > slots


def _scene_roughness(scene):
    """The scene's ``[roughness]`` options, or None (absent, or a scene built in code without
    a TOML text to read them from)."""
    try:
        return scene.roughness
    except Exception:  # noqa: BLE001 - a scene built in code may have no text to read it from
        return None


def scene_has_thermal(scene) -> bool:
    return scene.thermal is not None


def choices_of(scene, env: Envelope, acc: AccuracyTarget) -> Dict[str, Choice]:
    pin = set(acc.pin)
    ch: Dict[str, Choice] = {}

    def add(name, levels, scene_value, note=""):
        if name in pin:
            ch[name] = Choice(name, [scene_value], pinned=True, note="pinned by the scene")
        else:
            ch[name] = Choice(name, list(levels), note=note if len(levels) > 1 else (note or "no alternative"))

    def skip(name, value, why):
        ch[name] = Choice(name, [value], pinned=name in pin, note=why, skipped="" if name in pin else why)

    # the full-fidelity reference keeps the scene's own contact model; the others are what-if rows
    # (what_if_contact), never a reduction of the scene
    add("contact_model", [scene.mesh.contact_model], scene.mesh.contact_model,
        "the scene's own contact model (others: what-if rows)")
    if env.temperature_range_C is not None:
        add("thermal", [False, True], scene_has_thermal(scene))
    else:  # no temperature variation to plan for: the scene's [thermal] as written
        skip("thermal", scene_has_thermal(scene), "no temperature range in the envelope: as the scene says")
    pmin = min_slots(scene)
    full_slots = scene.tables.slots or pmin
    if _teeth_differ(scene, full_slots):
        add("tooth_specific_errors", [False, True], True)
    else:
        skip("tooth_specific_errors", True, "all teeth alike")
    ns = int(scene.mesh.slices)
    add("slices", sorted({n for n in (1, 2, 4, 8, 16, 32, 64, 128, 256, 512) if n < ns} | {ns}), ns)
    ppm = int(scene.tables.points_per_mesh)
    full_ppm, capped = reference_points_per_mesh(scene)
    add("points_per_mesh", sorted({p for p in _PPM_LEVELS if p < full_ppm} | {full_ppm}), ppm)
    if capped and "points_per_mesh" not in pin:
        ch["points_per_mesh"].note = capped
    tlo, thi = env.torque_range_Nm
    if thi > tlo:
        ntq = max(9, int(scene.tables.torque_points))
        add("torque_points", sorted({n for n in _TORQUE_LEVELS if n < ntq} | {ntq}), int(scene.tables.torque_points))
    else:
        skip("torque_points", 1, "one torque in the envelope")
    if full_slots == pmin:
        skip("slots", pmin, "the scene's slots are the pair's minimum ceil(contact ratio)")
    else:
        add("slots", [pmin, full_slots], full_slots)
    add("integrator", list(PLAN_INTEGRATOR_LEVELS), scene.solver.integrator)
    # levels: multiples of h0 (the automatic step at the top envelope speed); pinned: the scene's
    # max_step_s in s, or 1 x h0 when the scene says "auto" (step_absolute tells which)
    add("max_step", list(_STEP_FACTORS), scene.solver.max_step_s if scene.solver.max_step_s else 1.0,
        "levels are multiples of h0")
    return ch


def reference_points_per_mesh(scene) -> Tuple[int, str]:
    """(points per mesh of the full-fidelity reference, "" or why it is below 256).  The
    finest of the levels from the scene's own up to max(256, scene's) whose table build the
    cost model of :func:`gearfmu.scene.physics.estimate_build` puts within
    :data:`PLAN_TABLE_BUILD_S` (the scene's own when none does): the film and fractal contact
    models solve per angle and torque row, so their fine tables take minutes to hours."""
    ppm = int(scene.tables.points_per_mesh)
    top = max(256, ppm)

    def est(p):
        return estimate_build(replace(scene, tables=replace(scene.tables, points_per_mesh=p))).build_s
    for p in sorted({p for p in _PPM_LEVELS if ppm < p < top} | {ppm, top}, reverse=True):
        if est(p) <= PLAN_TABLE_BUILD_S or p == ppm:
            if p == top:
                return p, ""
            return p, (f"full-fidelity reference at {p} points per mesh, not {top}: the {scene.mesh.contact_model} "
                       f"tables at {top} are estimated at {est(top):.3g} s, above the plan-time budget of "
                       f"{PLAN_TABLE_BUILD_S:g} s per table build")
    return ppm, ""  # pragma: no cover - the scene's own level always ends the loop


def table_work(cfg: dict) -> float:
    """Relative work of building a configuration's tables: slices x points per mesh x torque
    rows x slots x temperatures (3 with thermal), the cells the sliced stiffness and the
    load-iterated contact models compute (the mesh periods of the table are left out: they
    only shrink for uniform teeth, so the work is not under-estimated)."""
    return (float(cfg["slices"]) * float(cfg["points_per_mesh"]) * max(float(cfg["torque_points"]), 1.0)
            * float(cfg["slots"]) * (_THERMAL_AXIS_POINTS if cfg["thermal"] else 1.0))


def reference_is_expensive(scene, full: dict) -> bool:
    """True when the full-fidelity reference tables are estimated above :data:`PLAN_TABLE_BUILD_S`
    (:func:`gearfmu.scene.physics.estimate_build`): then the per-choice levels get a table budget."""
    sc = replace(scene, mesh=replace(scene.mesh, slices=int(full["slices"])),
                 tables=replace(scene.tables, points_per_mesh=int(full["points_per_mesh"])))
    return estimate_build(sc).build_s > PLAN_TABLE_BUILD_S


def skipped_choices(choices: Dict[str, Choice], what_if_rows: List[dict]) -> List[dict]:
    """What the planner did not measure and why, as JSON-ready rows: choices the envelope
    cannot need (``choice``, ``reason``), levels left out (``choice``, ``levels``,
    ``reason``: the plan-time table budget, a full-fidelity reference below 256 points per
    mesh) and the what-if contact models not measured (``choice`` "contact_model",
    ``levels``, ``reason``)."""
    rows = []
    for c in choices.values():
        if c.skipped:
            rows.append({"choice": c.name, "levels": None, "reason": c.skipped})
        by_reason: Dict[str, list] = {}
        for i, why in sorted(c.skipped_levels.items()):
            by_reason.setdefault(why, []).append(c.levels[i])
        rows += [{"choice": c.name, "levels": lv, "reason": why} for why, lv in by_reason.items()]
        if c.name == "points_per_mesh" and c.note.startswith("full-fidelity reference at"):
            rows.append({"choice": c.name, "levels": [p for p in _PPM_LEVELS if p > c.full], "reason": c.note})
    rows += [{"choice": "contact_model", "levels": [r["contact_model"]], "reason": r["skipped"]}
             for r in what_if_rows if r.get("skipped")]
    return rows


def what_if_contact(scene) -> List[dict]:
    """The contact models other than the scene's: each a what-if row with the reason it is
    skipped (not offered, no ``[lubricant]``, no ``[roughness]``) or None when it can be
    measured (``plan_scene(..., what_if=True)``)."""
    avail = _available_contact_models()
    # CHOICE: rough_ehl only when the scene describes its roughness ([roughness]): the planner does
    # not invent a flank surface the scene does not state
    rows = []
    for m in CONTACT_ORDER:
        if m == scene.mesh.contact_model:
            continue
        why = None
        if m not in avail:
            why = "not offered by the table builder"
        elif m in LUBRICATED_CONTACT_MODELS and scene.lubricant is None:
            why = "the scene has no [lubricant]"
        elif m == "rough_ehl" and _scene_roughness(scene) is None:
            why = "the scene has no [roughness]"
        rows.append({"contact_model": m, "skipped": why})
    return rows


def thermal_options(scene, env: Envelope, contact_model: Optional[str] = None):
    """The ``[thermal]`` options of the kept thermal level: the scene's section (a
    default :class:`gearfmu.scene.reader.ThermalOptions` when it has none) whose temperature
    axis is the scene's ``temperature_axis_C`` or, when that is empty and the envelope
    has a temperature range, ``_THERMAL_AXIS_POINTS`` equally spaced points over the
    range (CHOICE, docs/plan.md).  Raises :class:`PlanError` when the scene's axis does
    not cover the envelope's temperature range (the FMU would refuse those inputs).

    ``contact_model``: the planned contact model.  An oil-temperature axis
    (``axis_quantity`` "oil" / "bulk_and_oil", docs/thermal.md) acts through eta0 of a
    lubricated model; when the plan chooses a model without a lubricant (hertz) the oil
    part has nothing to act on, so "oil" loses its axis and "bulk_and_oil" becomes "bulk"."""
    th = scene.thermal if scene.thermal is not None else ThermalOptions()
    q = th.axis_quantity
    if contact_model is not None and q != "bulk":
        if not get_contact_model(contact_model).needs_lubricant:
            th = (replace(th, temperature_axis_C=(), axis_quantity="bulk") if q == "oil"
                  else replace(th, axis_quantity="bulk"))
            if q == "oil":
                return th
    rng = env.temperature_range_C
    if rng is None:
        return th
    lo, hi = rng
    if not len(th.temperature_axis_C):
        if hi == lo:  # one temperature: the He & Yang 2023 state of both gears at it, no axis
            return replace(th, pinion_temperature_C=float(lo), gear_temperature_C=float(lo))
        return replace(th, temperature_axis_C=tuple(float(x) for x in np.linspace(lo, hi, _THERMAL_AXIS_POINTS)))
    ax = th.temperature_axis_C
    if ax[0] > lo or ax[-1] < hi:
        raise PlanError(f"thermal.temperature_axis_C: [{ax[0]:g}, {ax[-1]:g}] degC does not cover the envelope "
                        f"temperature range [{lo:g}, {hi:g}] degC (the FMU refuses temperatures outside its axis)")
    return th


def step_absolute(scene, acc: AccuracyTarget) -> bool:
    """True when the max_step level is a step in s (pinned to the scene's max_step_s)."""
    return "max_step" in acc.pin and scene.solver.max_step_s is not None
