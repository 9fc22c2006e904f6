"""Fidelity planner: only what a scene needs (docs/plan.md).

Given a scene, its operating envelope and its accuracy target
(:mod:`gearfmu.scene.envelope`), :func:`plan_scene` estimates what every modelling
choice contributes to the TVMS and to the DTE and mesh force over the
envelope, keeps what the target needs, drops the rest and measures the cost
of the chosen model against the full one.  :func:`planned_scene` turns a plan
into the scene that ``gearfmu build`` builds.

Choices (``gearfmu.scene.envelope.PLAN_CHOICES``) and their levels, cheapest first,
the last one being the full-fidelity level:

* ``contact_model`` -- the scene's own (the full-fidelity reference keeps it); the
  other models :mod:`gearfmu.contact.models` offers are what-if rows
  (:func:`_what_if_contact`), measured only on request.
* ``thermal`` -- seed 004 temperature stiffness on/off (only with an envelope
  temperature range).  Kept, the FMU gets a temperature axis over the range;
  dropped, it gets none (no temperature input).
* ``tooth_specific_errors`` -- per-tooth deviations (table period = the
  hunting-tooth cycle) against every tooth carrying its gear's default
  deviation (table period = P mesh periods).
* ``slices`` -- 1, 2, 4, 8, ... up to the scene's slices.
* ``points_per_mesh`` -- 16, 32, 64, 128, 256 (the full level is max(256, scene)).
* ``torque_points`` -- 1 (nominal torque only), 2, 3, 5, 9 equally spaced over
  the envelope torque range (full: max(9, scene)).
* ``slots`` -- the pair's minimum (:func:`gearfmu.gear.stiffness.required_slots`: ceil of the
  total contact ratio), or the scene's larger count.
* ``integrator`` -- rk4, rk4_kink (full).
* ``max_step`` -- 4, 2, 1, 1/2, 1/4 times h0 = :func:`gearfmu.dynamics.native.choose_max_step_s`
  of the full tables at the top envelope speed (full: h0/4).

Error measure (docs/plan.md "Error measure", :data:`gearfmu.plan_verify.ERROR_DEFINITION`):
per comparison run (a steady point of ``run_mesh_periods`` mesh periods from the
quasi-static start, or a segment of a transient) rms(y - y_full)/rms(y_full) of the DTE
and of the total mesh force; max|y - y_full|/range(y_full) reported beside it.  The
per-choice estimates use the envelope points (torque low / nominal / high x speed low /
nominal / high x temperature corners); the TVMS measure is the relative RMS difference
of the total mesh stiffness over the table period at the envelope torques and
temperatures (thermal configurations read at each temperature with
``MeshTables.at_temperature``, the FMU kernel's rule).  The greedy budget rule picks the
choices; :func:`_verify_and_revise` then searches the envelope for the worst point of the
COMBINED choice (:class:`gearfmu.plan_verify.Search`), raises the responsible choice
while a point is above ``safety_factor`` x target, and refuses the plan when the budget of
native runs is spent first.  ``Plan.verified_envelope`` records what was verified.

Confirmation through the FMUs (:func:`verify_fmus`, ``gearfmu plan --fmu``):
the planned and the full-fidelity FMU are built and driven with fmpy through
the same cases -- steady point, run-up and run-down over the speed range, the
search's worst steady point, warm-up over the temperature range, the envelope's
duty cycle (:func:`verification_cases`;
speed profiles through the load torque by rigid-body inverse dynamics,
:func:`drive_case`) -- and the DTE / mesh-force errors and the gains are
reported per case.
"""
from __future__ import annotations

import math
import shutil
import sys
import tempfile
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Dict, List, Optional, Tuple

import numpy as np

from .common.vocabulary import INTEGRATORS, LUBRICATED_CONTACT_MODELS, TEMPERATURE_INPUTS
from .scene.envelope import PLAN_CHOICES, AccuracyTarget, Envelope, accuracy_of, envelope_of, VerifiedEnvelope
from .contact.models import CONTACT_MODELS, environment_from_scene, get_contact_model
from .dynamics.native import choose_max_step_s, simulate
from .gear.gearpair import GearDeviations
from .gear.geometry import pair_geometry
from .gear.meshing_errors import pair_table_mesh_count
from .scene.reader import ThermalOptions
from .plan_verify import DriveCase, drive_case, ERROR_DEFINITION, Search
from .stages import build_fmu_from_scene
from .tables.precompute import precompute_tables
from .tables.estimate import estimate_build, BuildEstimate
from .gear.stiffness import required_slots

__all__ = ["PlanError", "Plan", "plan_scene", "planned_scene", "full_scene", "format_report",
           "relative_rms", "CONTACT_ORDER", "DriveCase", "drive_case", "verification_cases", "run_fmu_drive",
           "verify_fmus", "estimate_as_written", "verified_envelope_of",
           "DEFAULT_BUDGET_RUNS"]

#: contact models from the cheapest to the most detailed
CONTACT_ORDER = ("hertz", "smooth_ehl", "rough_ehl")
_PPM_LEVELS = (16, 32, 64, 128, 256)
_TORQUE_LEVELS = (1, 2, 3, 5, 9)
_STEP_FACTORS = (4.0, 2.0, 1.0, 0.5, 0.25)
_THERMAL_AXIS_POINTS = 3  # temperature axis of a kept thermal choice without a scene axis (CHOICE)
DEFAULT_BUDGET_RUNS = 2000  # native runs the envelope search and its revisions may take (CHOICE, docs/plan.md)
_REBUILD_BELOW_S = 5.0    # cost: tables that took less than this are rebuilt for a clean timing (CHOICE)


class PlanError(ValueError):
    """The planner cannot plan a scene (names the field and the reason)."""


def relative_rms(y, y_ref) -> float:
    """rms(y - y_ref) / rms(y_ref) (dimensionless); 0 when both are identically 0,
    inf when only the reference is; NaN-safe inputs are required."""
    y, y_ref = np.asarray(y, dtype=float), np.asarray(y_ref, dtype=float)
    num = float(np.sqrt(np.mean((y - y_ref) ** 2)))
    den = float(np.sqrt(np.mean(y_ref ** 2)))
    if den == 0.0:
        return 0.0 if num == 0.0 else math.inf
    return num / den


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


def _p_min(scene) -> int:
    return required_slots(pair_geometry(scene.pair))


def _teeth_differ(scene, slots: int) -> bool:
    return pair_table_mesh_count(scene.pair, slots) > slots


def _scene_roughness(scene):
    """The scene's ``[roughness]`` options, or None (absent, or a scene object without them)."""
    try:
        return getattr(scene, "roughness", None)
    except Exception:  # noqa: BLE001 - a scene built in code may have no text to read it from
        return None


def _scene_has_thermal(scene) -> bool:
    return getattr(scene, "thermal", None) is not None


def _choices(scene, env: Envelope, acc: AccuracyTarget) -> Dict[str, Choice]:
    pin = set(acc.pin)
    ch: Dict[str, Choice] = {}

    def add(name, levels, scene_value, note=""):
        if name in pin:
            ch[name] = Choice(name, [scene_value], pinned=True, note="pinned by the scene")
        else:
            ch[name] = Choice(name, list(levels), note=note if len(levels) > 1 else (note or "no alternative"))

    # the full-fidelity reference keeps the scene's own contact model; the others are what-if rows
    # (_what_if_contact), never a reduction of the scene
    add("contact_model", [scene.mesh.contact_model], scene.mesh.contact_model,
        "the scene's own contact model (others: what-if rows)")
    if env.temperature_range_C is not None:
        add("thermal", [False, True], _scene_has_thermal(scene))
    else:  # no temperature variation to plan for: the scene's [thermal] as written
        ch["thermal"] = Choice("thermal", [_scene_has_thermal(scene)], pinned="thermal" in pin,
                               note="no temperature range in the envelope: as the scene says")
    pmin = _p_min(scene)
    full_slots = scene.tables.slots or pmin
    if _teeth_differ(scene, full_slots):
        add("tooth_specific_errors", [False, True], True)
    else:
        ch["tooth_specific_errors"] = Choice("tooth_specific_errors", [True], note="all teeth alike")
    ns = int(scene.mesh.slices)
    add("slices", sorted({n for n in (1, 2, 4, 8, 16, 32, 64, 128, 256, 512) if n < ns} | {ns}), ns)
    ppm = int(scene.tables.points_per_mesh)
    full_ppm = max(256, ppm)
    add("points_per_mesh", sorted({p for p in _PPM_LEVELS if p < full_ppm} | {full_ppm}), ppm)
    tlo, thi = env.torque_range_Nm
    if thi > tlo:
        ntq = max(9, int(scene.tables.torque_points))
        add("torque_points", sorted({n for n in _TORQUE_LEVELS if n < ntq} | {ntq}), int(scene.tables.torque_points))
    else:
        ch["torque_points"] = Choice("torque_points", [1], note="no torque range in the envelope")
    add("slots", [pmin] if full_slots == pmin else [pmin, full_slots], full_slots)
    add("integrator", list(INTEGRATORS), scene.solver.integrator)
    # levels: multiples of h0 (the automatic step at the top envelope speed); pinned: the scene's
    # max_step_s in s, or 1 x h0 when the scene says "auto" (_step_absolute tells which)
    add("max_step", list(_STEP_FACTORS), scene.solver.max_step_s if scene.solver.max_step_s else 1.0,
        "levels are multiples of h0")
    return ch


def _what_if_contact(scene) -> List[dict]:
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


def _thermal_options(scene, env: Envelope, contact_model: Optional[str] = None):
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
    th = getattr(scene, "thermal", None)
    th = th if th is not None else ThermalOptions()
    q = getattr(th, "axis_quantity", "bulk")
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
        if hi == lo:  # one temperature: the seed 004 state of both gears at it, no axis
            return replace(th, pinion_temperature_C=float(lo), gear_temperature_C=float(lo))
        return replace(th, temperature_axis_C=tuple(float(x) for x in np.linspace(lo, hi, _THERMAL_AXIS_POINTS)))
    ax = th.temperature_axis_C
    if ax[0] > lo or ax[-1] < hi:
        raise PlanError(f"thermal.temperature_axis_C: [{ax[0]:g}, {ax[-1]:g}] degC does not cover the envelope "
                        f"temperature range [{lo:g}, {hi:g}] degC (the FMU refuses temperatures outside its axis)")
    return th


def _step_absolute(scene, acc: AccuracyTarget) -> bool:
    """True when the max_step level is a step in s (pinned to the scene's max_step_s)."""
    return "max_step" in acc.pin and scene.solver.max_step_s is not None


# ============================================================== model evaluation
class _Evaluator:
    """Builds tables and runs the native solver for configurations (dicts choice -> level value)."""

    def __init__(self, scene, env: Envelope, acc: AccuracyTarget, progress: bool):
        self.scene, self.env, self.acc, self.progress = scene, env, acc, progress
        self._tables: Dict[tuple, tuple] = {}
        self._factors: Dict[tuple, object] = {}  # (table key, degC) -> tables at that temperature
        self._runs: Dict[tuple, dict] = {}
        self.native_runs = 0  # native solver runs made (cached runs not counted)
        self.h0: Optional[float] = None
        self.t0_C = scene.thermal.standard_temperature_C if getattr(scene, "thermal", None) else 30.0

    # -------------------------------------------------------- tables
    def table_key(self, cfg: dict) -> tuple:
        return (cfg["contact_model"], cfg["tooth_specific_errors"], cfg["slices"], cfg["points_per_mesh"],
                cfg["torque_points"], cfg["slots"], bool(cfg["thermal"]))

    def pair(self, tooth_specific: bool):
        p = self.scene.pair
        if tooth_specific:
            return p

        def uniform(g):
            d = g.deviations
            return replace(g, deviations=GearDeviations(default=d.default, per_tooth=(),
                                                        lead_crowning_m=d.lead_crowning_m))
        return replace(p, pinion=uniform(p.pinion), gear=uniform(p.gear))

    def torque_axis(self, n: int) -> Tuple[float, ...]:
        if n <= 1:
            return (float(self.env.nominal_torque_Nm),)
        lo, hi = self.env.torque_range_Nm
        return tuple(lo + (hi - lo) * i / (n - 1) for i in range(n))

    def tables(self, cfg: dict):
        """(MeshTables, build wall time in s) of a configuration (cached)."""
        key = self.table_key(cfg)
        if key not in self._tables:
            t0 = time.perf_counter()
            tb = precompute_tables(**self.table_args(cfg))
            self._tables[key] = (tb, time.perf_counter() - t0)
        return self._tables[key]

    def table_args(self, cfg: dict) -> dict:
        """Arguments of :func:`gearfmu.tables.precompute.precompute_tables` for a configuration."""
        opts = replace(self.scene.mesh, contact_model=cfg["contact_model"], slices=int(cfg["slices"]))
        pair = self.pair(cfg["tooth_specific_errors"])
        kw = dict(pair=pair, opts=opts, points_per_mesh=int(cfg["points_per_mesh"]),
                  torque_axis_Nm=self.torque_axis(int(cfg["torque_points"])),
                  nominal_torque_Nm=self.env.nominal_torque_Nm, slots=int(cfg["slots"]))
        if cfg["thermal"]:  # the table builder's own temperature axis (docs/plan.md "Thermal estimate")
            kw["thermal"] = _thermal_options(self.scene, self.env, cfg["contact_model"])
        if cfg["contact_model"] != "hertz":  # lubricated models need their environment (contact_models)

            kw["contact_env"] = environment_from_scene(replace(self.scene, pair=pair, mesh=opts))
        return kw

    def tables_at(self, cfg: dict, temperature_C: Optional[float]):
        """The configuration's tables at a bulk temperature (degC): the table builder's
        temperature axis interpolated by :meth:`gearfmu.tables.mesh_tables.MeshTables.at_temperature`
        (the rule of the FMU kernel, bitwise at the nodes); None = the tables' default
        temperature.  Tables without a temperature axis are returned as they are."""
        tb, _ = self.tables(cfg)
        if not tb.has_temperature_axis:
            return tb
        t = tb.default_temperature_C if temperature_C is None else float(temperature_C)
        key = self.table_key(cfg) + (t,)
        if key not in self._factors:
            self._factors[key] = tb.at_temperature(t)
        return self._factors[key]

    def table_bytes(self, cfg: dict) -> int:
        tb, _ = self.tables(cfg)
        n = sum(np.asarray(a).nbytes for a in (tb.k_N_per_m, tb.e_m, tb.backlash_half_m, tb.torque_Nm,
                                               tb.e_comprehensive_m, tb.static_te_m,
                                               getattr(tb, "temperature_C", None)) if a is not None)
        return int(n)

    # -------------------------------------------------------- TVMS measure
    def k_total(self, cfg: dict, torque_Nm: float, temperature_C: Optional[float]):
        """(phi grid (rad), total mesh stiffness (N/m)) at a torque (rows interpolated as the kernel does)."""
        tb = self.tables_at(cfg, temperature_C)
        kt = tb.k_N_per_m.sum(axis=1)
        tq = np.asarray(tb.torque_Nm, dtype=float)
        if tq.size == 1:
            row = kt[0]
        else:
            T = min(max(torque_Nm, tq[0]), tq[-1])
            i = int(min(np.searchsorted(tq, T, side="right") - 1, tq.size - 2))
            w = (T - tq[i]) / (tq[i + 1] - tq[i])
            row = kt[i] + w * (kt[i + 1] - kt[i])
        return tb.phi_rad, row, tb.phi_period_rad

    def tvms_error(self, cfg: dict, full: dict) -> float:
        worst = 0.0
        for T in self.env.torques_Nm():
            for temp in (self.env.temperatures_C() or (None,)):
                phi_f, k_f, per_f = self.k_total(full, T, temp)
                phi_r, k_r, per_r = self.k_total(cfg, T, temp)
                x = np.mod(phi_f, per_r)
                k_ri = np.interp(x, np.append(phi_r, per_r), np.append(k_r, k_r[0]))
                worst = max(worst, relative_rms(k_ri, k_f))
        return worst

    # -------------------------------------------------------- dynamics
    def points(self) -> List[Tuple[float, float, Optional[float]]]:
        """Envelope points (pinion torque N*m, pinion speed rad/s, temperature degC or None)."""
        return [(T, w, temp) for T in self.env.torques_Nm() for w in self.env.speeds_rad_s()
                for temp in (self.env.temperatures_C() or (None,))]

    def step(self, cfg: dict) -> float:
        v = float(cfg["max_step"])
        return v if _step_absolute(self.scene, self.acc) else v * self.h0

    def run(self, cfg: dict, point) -> dict:
        """Native run at one envelope point: dte, mesh_force (arrays), wall_s and simulated time."""
        key = self.table_key(cfg) + (cfg["thermal"], cfg["integrator"], self.step(cfg), point)
        if key in self._runs:
            return self._runs[key]
        T, w, temp = point
        tb = self.tables_at(cfg, temp)
        self.native_runs += 1
        mesh_s = tb.mesh_period_rad / w
        n = int(self.acc.run_mesh_periods)
        res = simulate(tb, stop_time_s=n * mesh_s, comm_step_s=mesh_s / 16, max_step_s=self.step(cfg),
                       pinion_torque_Nm=T, pinion_speed_start_rad_s=w,
                       damping_ratio=self.scene.fmu.damping_ratio, damping_model=self.scene.solver.damping_model,
                       integrator=cfg["integrator"])
        out = {"dte": res.dte, "mesh_force": res.mesh_force, "wall_s": res.wall_s, "sim_s": n * mesh_s}
        self._runs[key] = out
        return out

    def run_drive(self, cfg: dict, case) -> dict:
        """Native run of a transient drive (:class:`DriveCase`): dte and mesh_force per
        communication step (row 0 = the start), cached per configuration and case name."""
        key = self.table_key(cfg) + (cfg["integrator"], self.step(cfg), "drive", case.name)
        if key in self._runs:
            return self._runs[key]
        tb, _ = self.tables(cfg)
        temp = case.temperature_C if (tb.has_temperature_axis and case.temperature_C is not None) else None
        self.native_runs += 1
        res = simulate(tb, stop_time_s=case.stop_time_s, comm_step_s=case.comm_step_s, max_step_s=self.step(cfg),
                       pinion_torque_Nm=case.pinion_torque_Nm, gear_torque_Nm=case.gear_torque_Nm,
                       pinion_speed_start_rad_s=case.pinion_speed_start_rad_s,
                       damping_ratio=self.scene.fmu.damping_ratio, damping_model=self.scene.solver.damping_model,
                       integrator=cfg["integrator"], bulk_temperature_C=temp)
        out = {"dte": res.dte, "mesh_force": res.mesh_force, "wall_s": res.wall_s, "sim_s": case.stop_time_s}
        self._runs[key] = out
        return out

    def dynamic_error(self, cfg: dict, full: dict) -> dict:
        """Worst relative RMS DTE / mesh-force difference over the envelope points, and the
        native wall time per simulated second of ``cfg``."""
        dte = force = 0.0
        wall = sim = 0.0
        for pt in self.points():
            a, b = self.run(cfg, pt), self.run(full, pt)
            if not (np.all(np.isfinite(a["dte"])) and np.all(np.isfinite(b["dte"]))):
                dte = force = math.inf
                continue
            dte = max(dte, relative_rms(a["dte"], b["dte"]))
            force = max(force, relative_rms(a["mesh_force"], b["mesh_force"]))
            wall += a["wall_s"]
            sim += a["sim_s"]
        return {"dte_rel": dte, "mesh_force_rel": force, "wall_per_sim_s": wall / sim if sim else math.nan}

    def measure(self, cfg: dict, full: dict) -> dict:
        _, build_s = self.tables(cfg)
        m = {"tvms_rel": self.tvms_error(cfg, full)}
        m.update(self.dynamic_error(cfg, full))
        m["table_build_s"] = build_s
        m["table_bytes"] = self.table_bytes(cfg)
        return m


# ============================================================== the plan
@dataclass
class Plan:
    """Result of :func:`plan_scene`: the chosen and the full configuration, the
    per-choice measurements, the verification of the chosen model and the costs.
    :meth:`to_dict` is the JSON report (``gearfmu plan --json``)."""

    scene_name: str
    envelope: Envelope
    target: AccuracyTarget
    choices: Dict[str, Choice]
    full: dict
    chosen: dict
    h0_s: float
    step_absolute: bool
    verification: dict
    cost: dict
    log: List[str] = field(default_factory=list)
    fmu_verification: dict = field(default_factory=dict)  # verify_fmus() when measured (plan --fmu)
    what_if: List[dict] = field(default_factory=list)  # other contact models: measured or skipped, never "full"
    verified_envelope: dict = field(default_factory=dict)  # gearfmu.scene.envelope.VerifiedEnvelope.to_dict()

    @property
    def within_target(self) -> bool:
        """True only when the envelope search passed and, when it ran, the FMU confirmation too."""
        fv = self.fmu_verification or {}
        return bool(self.verification.get("within_target")) and (not fv.get("cases") or
                                                                 bool(fv.get("within_target")))
    estimate: dict = field(default_factory=dict)  # gearfmu.tables.estimate of the scene as written / chosen / full

    def max_step_s(self, which: str = "chosen") -> float:
        """Largest internal step (s) of the chosen or the full configuration."""
        cfg = self.chosen if which == "chosen" else self.full
        v = float(cfg["max_step"])
        return v if self.step_absolute else v * self.h0_s

    def status(self, name: str) -> str:
        ch = self.choices[name]
        if ch.pinned:
            return "pinned"
        if ch.fixed:
            return "fixed"
        v, full = self.chosen[name], ch.full
        if v == full:
            return "kept"
        if v is False or (name == "torque_points" and v == 1) or (name == "contact_model" and v == "hertz"):
            return "dropped"
        return "reduced"

    def to_dict(self) -> dict:
        def jv(v):
            if isinstance(v, float) and not math.isfinite(v):
                return None if math.isnan(v) else ("inf" if v > 0 else "-inf")
            return v

        rows = []
        for name, ch in self.choices.items():
            idx = ch.levels.index(self.chosen[name])
            m = ch.measured.get(idx, {})
            rows.append({
                "choice": name, "status": self.status(name), "full": ch.full, "chosen": self.chosen[name],
                "levels": ch.levels, "note": ch.note,
                "contribution": {k: jv(m.get(k, 0.0)) for k in ("tvms_rel", "dte_rel", "mesh_force_rel")},
                "measured": [{"level": ch.levels[i], **{k: jv(v) for k, v in mm.items()}}
                             for i, mm in sorted(ch.measured.items())],
            })
        env = self.envelope
        return {
            "scene": self.scene_name,
            "envelope": {"torque_range_Nm": list(env.torque_range_Nm),
                         "speed_range_rpm": [w * 60 / (2 * math.pi) for w in env.speed_range_rad_s],
                         "temperature_range_C": list(env.temperature_range_C) if env.temperature_range_C else None,
                         "duty_cycle": env.duty_cycle.source if env.duty_cycle is not None else None},
            "target": {"dte_rel": self.target.dte_rel, "mesh_force_rel": self.target.mesh_force_rel,
                       "safety_factor": self.target.safety_factor, "pin": list(self.target.pin)},
            "h0_s": self.h0_s,
            "choices": rows,
            "chosen": dict(self.chosen, max_step_s=self.max_step_s("chosen")),
            "full": dict(self.full, max_step_s=self.max_step_s("full")),
            "verification": _json_clean(self.verification),
            "within_target": self.within_target,
            "verified_envelope": _json_clean(self.verified_envelope),
            "what_if": _json_clean(self.what_if),
            "cost": self.cost,
            "fmu_verification": _json_clean(self.fmu_verification),
            "estimate": self.estimate,
            "log": self.log,
        }


def _json_clean(v):
    """JSON-ready copy: non-finite floats as None / "inf" / "-inf", numpy scalars as Python numbers."""
    if isinstance(v, dict):
        return {k: _json_clean(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_json_clean(x) for x in v]
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None if math.isnan(v) else ("inf" if v > 0 else "-inf")
    return v


def _say(progress: bool, msg: str, log: List[str]) -> None:
    """Log a step of the plan; with ``progress`` also one line on stderr (also in --json mode)."""
    log.append(msg)
    if progress:
        print(f"gearfmu plan: {msg}", file=sys.stderr, flush=True)


def _budget_use(m: dict, acc: AccuracyTarget) -> float:
    return max(m["dte_rel"] / acc.dte_rel, m["mesh_force_rel"] / acc.mesh_force_rel)


_COST_KEYS = ("table_build_s", "table_bytes", "wall_per_sim_s")


def _est_cost(levels: Dict[str, int], choices: Dict[str, Choice], base: dict) -> float:
    """Relative cost estimate of a configuration: sum over table build time, table
    size and time per simulated second of the product of the single-choice ratios
    to the full model (each choice taken as acting independently)."""
    total = 0.0
    for k in _COST_KEYS:
        r = 1.0
        for name, i in levels.items():
            m = choices[name].measured.get(i)
            if m is not None and base.get(k):
                r *= m[k] / base[k]
        total += r
    return total


def plan_scene(scene, *, progress: bool = False, measure_fmu: bool = False,
               fmu_dir: Optional[str] = None, fmu_runtime: Optional[str] = None,
               budget_runs: Optional[int] = None, what_if: bool = False) -> Plan:
    """Plan the fidelity of a scene (docs/plan.md).

    1. Levels of every choice (:func:`_choices`; pinned ones are fixed).
    2. Each non-full level is measured alone against the full model (all other
       choices full): TVMS, DTE and mesh-force relative RMS errors over the
       envelope points, table build time, table size and native time per
       simulated second.
    3. Greedy rule: starting from the full model, repeatedly take the level
       change that saves the most estimated cost per unit of added budget use
       (budget use of a level = max(DTE error / DTE target, force error / force
       target)) while the summed budget use of all choices stays <= the safety
       factor (by the triangle inequality the combined error is about at most
       the sum of the single-choice errors).
    4. Verification: the combined chosen model is run against the full one at
       every envelope point; while its error exceeds the target, the choice with
       the largest budget use goes back one level towards full.
    5. Costs of the chosen and the full model: table build time, table size and
       time per simulated second, and with ``measure_fmu`` both FMUs built (in
       ``fmu_dir`` or a temporary directory; ``fmu_runtime``: "pythonfmu" or
       "standalone", None = the scene's) and driven through the verification
       cases (:func:`verify_fmus`, stored in ``Plan.fmu_verification``).
    """
    budget_runs = DEFAULT_BUDGET_RUNS if budget_runs is None else int(budget_runs)
    if budget_runs < 1:
        raise PlanError(f"budget_runs: must be a positive number of native runs, got {budget_runs}")
    env, acc = envelope_of(scene), accuracy_of(scene)
    if env.temperature_range_C is not None:
        _thermal_options(scene, env)  # the scene's temperature axis must cover the envelope (PlanError)
    log: List[str] = []
    choices = _choices(scene, env, acc)
    for name in PLAN_CHOICES:
        if name not in choices:
            raise PlanError(f"{name}: no levels (planner bug)")  # pragma: no cover
    ev = _Evaluator(scene, env, acc, progress)
    full = {n: c.full for n, c in choices.items()}
    tb_full, _ = ev.tables(full)
    ev.h0 = _h0(ev, full, env)
    full = {n: c.full for n, c in choices.items()}
    npts = len(ev.points())
    _say(progress, f"{npts} envelope points, full tables {tb_full.slots} slots x {tb_full.n_phi} angles x "
                   f"{tb_full.n_torque} torques, h0 = {ev.h0:.3g} s", log)

    base = ev.measure(full, full)
    for c in choices.values():
        c.measured[len(c.levels) - 1] = dict(base)
    for name, c in choices.items():
        for i, lv in enumerate(c.levels[:-1]):
            cfg = dict(full, **{name: lv})
            try:
                c.measured[i] = ev.measure(cfg, full)
            except (ValueError, ArithmeticError) as exc:  # a level the physics rejects is not offered
                c.measured[i] = {"tvms_rel": math.inf, "dte_rel": math.inf, "mesh_force_rel": math.inf,
                                 "table_build_s": math.nan, "table_bytes": 0, "wall_per_sim_s": math.nan,
                                 "error": str(exc)}
            m = c.measured[i]
            _say(progress, f"{name} = {lv}: TVMS {m['tvms_rel']:.2e}, DTE {m['dte_rel']:.2e}, "
                           f"force {m['mesh_force_rel']:.2e}", log)

    what_if_rows = _what_if_contact(scene)
    for r in what_if_rows:
        if r["skipped"] is None and not what_if:
            r["skipped"] = (f"not measured: the scene asks for {scene.mesh.contact_model} "
                            f"(plan_scene(..., what_if=True) measures it; film tables take minutes)")
        if r["skipped"] is None:
            try:
                m = ev.measure(dict(full, contact_model=r["contact_model"]), full)
                r.update({k: m[k] for k in ("tvms_rel", "dte_rel", "mesh_force_rel", "table_build_s")})
            except (ValueError, ArithmeticError) as exc:
                r["skipped"] = f"tables failed: {exc}"
        _say(progress, f"what-if contact_model = {r['contact_model']}: " +
             (f"skipped ({r['skipped']})" if r["skipped"] else
              f"TVMS {r['tvms_rel']:.2e}, DTE {r['dte_rel']:.2e}, force {r['mesh_force_rel']:.2e}"), log)
    what_if = what_if_rows

    # ---------------------------------------------------------- greedy
    level = {n: len(c.levels) - 1 for n, c in choices.items()}
    use = {n: 0.0 for n in choices}

    def cost_of(lv):
        return _est_cost(lv, choices, base)

    history: List[str] = []
    while True:
        best = None
        cur_cost, total = cost_of(level), sum(use.values())
        for name, c in choices.items():
            # levels are ordered by cost by construction: the candidate is the cheapest one that fits
            for i in range(level[name]):
                u = _budget_use(c.measured[i], acc)
                if math.isfinite(u) and total - use[name] + u <= acc.safety_factor:
                    break
            else:
                continue
            saved = max(cur_cost - cost_of(dict(level, **{name: i})), 0.0)  # measured (noisy) saving
            score = (saved + 1e-6) / max(u - use[name], 1e-6)
            if best is None or score > best[0]:
                best = (score, name, i, u)
        if best is None:
            break
        _, name, i, u = best
        level[name], use[name] = i, u
        history.append(name)
        _say(progress, f"take {name} = {choices[name].levels[i]} (budget use {u:.3f}, "
                       f"total {sum(use.values()):.3f})", log)

    # ---------------------------------------------------------- verification
    def cfg_of(lv):
        return {n: choices[n].levels[i] for n, i in lv.items()}

    chosen, ver = _verify_and_revise(ev, choices, level, full, acc, budget_runs,
                                     lambda msg: _say(progress, msg, log), progress)
    ver["tvms_rel"] = ev.tvms_error(chosen, full)
    ver["points"] = ver["probes"]

    # ---------------------------------------------------------- costs
    cost = {"full": _cost_entry(ev, full), "chosen": _cost_entry(ev, chosen)}
    plan = Plan(scene_name=scene.name, envelope=env, target=acc, choices=choices, full=full, chosen=chosen,
                h0_s=ev.h0, step_absolute=_step_absolute(scene, acc), verification=ver, cost=cost, log=log,
                what_if=what_if)
    plan.verified_envelope = verified_envelope_of(plan, kind="plan verification")

    plan.estimate = {"scene": estimate_build(scene).to_dict(),
                     **{w: estimate_build(planned_scene(scene, plan, w)).to_dict() for w in ("chosen", "full")}}
    if measure_fmu:
        _measure_fmus(scene, plan, fmu_dir, progress, fmu_runtime)
        plan.verified_envelope = verified_envelope_of(plan, kind="plan verification")
    g = {}
    for k in ("table_build_s", "table_bytes", "wall_per_sim_s", "fmu_bytes"):
        a, b = cost["full"].get(k), cost["chosen"].get(k)
        if a and b:
            g[k] = a / b
    cost["gain_full_over_chosen"] = g
    return plan


def _verify_and_revise(ev: _Evaluator, choices: Dict[str, Choice], level: Dict[str, int], full: dict,
                       acc: AccuracyTarget, budget_runs: int, say, progress: bool = False) -> Tuple[dict, dict]:
    """Verify the combined configuration of ``level`` over the envelope
    (:class:`gearfmu.plan_verify.Search`); while the worst point found is above the
    target, find the responsible choice (each reduced choice restored to full alone at
    that point: the one whose restoration lowers the error most), raise it to its
    cheapest level that brings that point within ``safety_factor`` x target (else to
    full) and verify again.  Stops when a search passes, or refuses when the budget of
    native runs is spent.  Returns (chosen configuration, verification dict); a refused
    plan's chosen configuration is the best one reached."""
    def cfg_of(lv):
        return {n: choices[n].levels[i] for n, i in lv.items()}

    search = Search(ev, full, say=say, progress=progress)
    start = ev.native_runs
    attempts: List[dict] = []
    best = None
    refused = None
    while True:
        chosen = cfg_of(level)
        res = search.verify(chosen, budget_runs - (ev.native_runs - start), margin=acc.safety_factor)
        w = res["worst"]
        att = {"chosen": dict(chosen), "worst": {k: v for k, v in w.items()},
               "within_target": res["within_target"], "native_runs": res["native_runs"],
               "probes": len(res["probes"])}
        attempts.append(att)
        say(f"verify ({len(res['probes'])} probes, {res['native_runs']} native runs): worst {w['probe']}: "
            f"DTE {w['dte_rel']:.2e}, force {w['mesh_force_rel']:.2e} "
            f"({'within' if res['within_target'] else 'ABOVE'} target)")
        if not res["exhausted"] and (best is None or w["u"] < best[0]["worst"]["u"]):
            best = (att, res)
        if res["within_target"]:
            break
        if res["exhausted"]:
            refused = (f"the budget of {budget_runs} native runs was spent before a configuration passed the "
                       f"envelope search")
            break
        reduced = [n for n in choices if level[n] < len(choices[n].levels) - 1]
        if not reduced:  # pragma: no cover - the full model against itself has no error
            refused = "the full-fidelity configuration itself fails the search (planner bug)"
            break
        probe = res["worst_probe"]
        trial = {n: search.evaluate(dict(chosen, **{n: full[n]}), probe)["u"] for n in reduced}
        resp = min(trial, key=lambda n: trial[n])
        say("at the worst point, each choice restored to full alone: " +
            ", ".join(f"{n} -> u {trial[n]:.2f}" for n in reduced) + f"; refining {resp}")
        new = len(choices[resp].levels) - 1
        for i in range(level[resp] + 1, len(choices[resp].levels) - 1):
            if search.evaluate(dict(chosen, **{resp: choices[resp].levels[i]}), probe)["u"] <= acc.safety_factor:
                new = i
                break
        level[resp] = new
        say(f"revise: {resp} = {choices[resp].levels[new]}")
    att, res = best if (refused and best is not None) else (attempts[-1], res)
    w = att["worst"]
    ver = {"dte_rel": w["dte_rel"], "mesh_force_rel": w["mesh_force_rel"], "dte_max_rel": w["dte_max_rel"],
           "mesh_force_max_rel": w["mesh_force_max_rel"], "worst": w["probe"], "worst_at": w["where"],
           "within_target": bool(att["within_target"]) and refused is None, "refused": refused,
           "native_runs": ev.native_runs - start, "budget_runs": budget_runs, "probes": att["probes"],
           "attempts": attempts, "error_definition": ERROR_DEFINITION,
           "probe_errors": [{k: p[k] for k in ("probe", "dte_rel", "mesh_force_rel", "dte_max_rel",
                                                 "mesh_force_max_rel")} for p in res["probes"]]}
    return dict(att["chosen"]), ver


def verified_envelope_of(plan, kind: str) -> dict:
    """The verified envelope of a plan as plain data (:class:`gearfmu.scene.envelope.VerifiedEnvelope`
    as a dict) for an FMU's validation record and model description."""
    v, env, acc = plan.verification, plan.envelope, plan.target
    fv = plan.fmu_verification or {}
    ve = VerifiedEnvelope(
        kind=kind, torque_range_Nm=tuple(env.torque_range_Nm),
        speed_range_rpm=tuple(w * 30 / math.pi for w in env.speed_range_rad_s),
        temperature_range_C=None if env.temperature_range_C is None else tuple(env.temperature_range_C),
        dte_target_rel=acc.dte_rel, mesh_force_target_rel=acc.mesh_force_rel, error_definition=ERROR_DEFINITION,
        within_target=bool(v.get("within_target")),
        worst_dte_rel=float(v["dte_rel"]), worst_mesh_force_rel=float(v["mesh_force_rel"]),
        worst_dte_max_rel=float(v.get("dte_max_rel", math.nan)),
        worst_mesh_force_max_rel=float(v.get("mesh_force_max_rel", math.nan)),
        worst_at=dict(v.get("worst_at") or {}), native_runs=int(v.get("native_runs", 0)),
        probes=int(v.get("probes", 0)),
        fmu_confirmed=None if not fv.get("cases") else bool(fv.get("within_target")))
    return ve.to_dict()


ESTIMATE_BUDGET_RUNS = 80      # native runs of the as-written estimate of `gearfmu build` (CHOICE)
_ESTIMATE_RUN_MESH_PERIODS = 20  # its run length in mesh periods (CHOICE: a cheap estimate)


def estimate_as_written(scene, *, progress: bool = False, budget_runs: int = ESTIMATE_BUDGET_RUNS) -> dict:
    """Cheap estimate of the error of a scene AS WRITTEN against its full-fidelity model
    (the planner's full levels, the scene's own contact model) over the scene's envelope:
    one envelope search (:class:`gearfmu.plan_verify.Search`) with runs of
    ``_ESTIMATE_RUN_MESH_PERIODS`` mesh periods and at most ``budget_runs`` native runs.
    Returns :class:`gearfmu.scene.envelope.VerifiedEnvelope` as a dict with kind
    "as-written estimate" and the default (or the scene's) target."""
    env = envelope_of(scene)
    acc = replace(accuracy_of(scene), pin=(), run_mesh_periods=min(accuracy_of(scene).run_mesh_periods,
                                                                      _ESTIMATE_RUN_MESH_PERIODS))
    log: List[str] = []
    choices = _choices(scene, env, acc)
    full = {n: c.full for n, c in choices.items()}
    ev = _Evaluator(scene, env, acc, progress)
    ev.h0 = _h0(ev, full, env)
    written = {"contact_model": scene.mesh.contact_model, "thermal": _scene_has_thermal(scene),
               "tooth_specific_errors": True, "slices": int(scene.mesh.slices),
               "points_per_mesh": int(scene.tables.points_per_mesh),
               "torque_points": int(scene.tables.torque_points) if full["torque_points"] > 1 else 1,
               "slots": int(scene.tables.slots or _p_min(scene)), "integrator": scene.solver.integrator}
    if scene.solver.max_step_s is not None:
        step_s = float(scene.solver.max_step_s)
    else:
        tb, _ = ev.tables(dict(written, max_step=1.0))
        w_top = max(env.speed_range_rad_s[1], env.nominal_speed_rad_s)
        step_s = (min(choose_max_step_s(tb.at_temperature(float(t)), w_top) for t in tb.temperature_C)
                  if tb.has_temperature_axis else choose_max_step_s(tb, w_top))
    written["max_step"] = step_s / ev.h0
    _say(progress, f"as-written estimate: the scene as written against its full-fidelity model "
                   f"(budget {budget_runs} native runs of {acc.run_mesh_periods} mesh periods)", log)
    res = Search(ev, full, say=lambda m: _say(progress, m, log), progress=progress).verify(written, budget_runs)
    w = res["worst"]
    ve = VerifiedEnvelope(
        kind="as-written estimate", torque_range_Nm=tuple(env.torque_range_Nm),
        speed_range_rpm=tuple(x * 30 / math.pi for x in env.speed_range_rad_s),
        temperature_range_C=None if env.temperature_range_C is None else tuple(env.temperature_range_C),
        dte_target_rel=acc.dte_rel, mesh_force_target_rel=acc.mesh_force_rel, error_definition=ERROR_DEFINITION,
        within_target=bool(w["dte_rel"] <= acc.dte_rel and w["mesh_force_rel"] <= acc.mesh_force_rel),
        worst_dte_rel=float(w["dte_rel"]), worst_mesh_force_rel=float(w["mesh_force_rel"]),
        worst_dte_max_rel=float(w["dte_max_rel"]), worst_mesh_force_max_rel=float(w["mesh_force_max_rel"]),
        worst_at=dict(w["where"]), native_runs=int(res["native_runs"]), probes=len(res["probes"]))
    d = ve.to_dict()
    d["search_complete"] = not res["exhausted"]
    d["full_fidelity"] = dict(full, max_step_s=full["max_step"] * ev.h0)
    d["as_written"] = dict(written, max_step_s=step_s)
    return d


def _h0(ev: "_Evaluator", full: dict, env: Envelope) -> float:
    """h0: :func:`gearfmu.dynamics.native.choose_max_step_s` of the full tables at the top envelope
    speed (the smallest over a temperature axis's nodes)."""
    tb_full, _ = ev.tables(full)
    w_top = max(env.speed_range_rad_s[1], env.nominal_speed_rad_s)
    if tb_full.has_temperature_axis:
        return min(choose_max_step_s(tb_full.at_temperature(float(t)), w_top) for t in tb_full.temperature_C)
    return choose_max_step_s(tb_full, w_top)


def _cost_entry(ev: _Evaluator, cfg: dict) -> dict:
    """Fresh measurement of one configuration's costs (tables rebuilt, runs at every envelope point)."""
    tb, first_s = ev.tables(cfg)
    if first_s < _REBUILD_BELOW_S:  # cheap: rebuild for a timing free of first-call (compile, cache) costs
        t0 = time.perf_counter()
        precompute_tables(**ev.table_args(cfg))
        build_s = time.perf_counter() - t0
    else:  # expensive (EHL film solves): the first build's time stands
        build_s = first_s
    wall = sim = 0.0
    for pt in ev.points():
        r = ev.run(cfg, pt)
        wall += r["wall_s"]
        sim += r["sim_s"]
    return {"table_build_s": build_s, "table_bytes": ev.table_bytes(cfg), "wall_per_sim_s": wall / sim,
            "tables_shape": [int(tb.n_torque), int(tb.slots), int(tb.n_phi)]}


def _measure_fmus(scene, plan: Plan, fmu_dir, progress, runtime=None) -> None:
    """Build the full and the chosen FMU and drive both through the verification
    cases (:func:`verify_fmus`); sizes, build times and errors go into the plan."""
    plan.fmu_verification = verify_fmus(scene, plan, fmu_dir=fmu_dir, progress=progress, runtime=runtime)
    for which in ("full", "chosen"):
        f = plan.fmu_verification["fmus"][which]
        plan.cost[which].update(fmu_bytes=f["fmu_bytes"], fmu_path=f["fmu_path"], fmu_build_s=f["fmu_build_s"])


# ============================================================== verification through the FMUs
_SAMPLES_PER_MESH = 16      # communication steps per mesh period at the case's top speed (CHOICE)
_CASE_MESH_PERIODS = 3      # a case lasts 3 x accuracy.run_mesh_periods mesh periods (CHOICE)
_RUN_UP_LOAD_SHARE = 0.1    # run-up: acceleration torque <= 10 % of the nominal torque (CHOICE)


def verification_cases(scene, plan: Plan, tables) -> List[DriveCase]:
    """The confirmation drives of a plan's envelope (docs/plan.md "Confirmation through
    the FMUs"); ``tables``: the full tables (inertias, base radii, mesh period).

    * ``steady``: nominal torque and speed, balanced load, middle of the temperature range;
    * ``run_up``: pinion speed linear from the low to the high end of the speed range at the
      nominal pinion torque, the load torque lowered by the acceleration torque (only with a
      speed range);
    * ``warm_up``: bulk temperature linear from the low to the high end of the temperature
      range at the nominal torque and speed (only with a temperature range);
    * ``duty_cycle``: the envelope's duty cycle replayed on its own time axis (torque and
      temperature columns interpolated linearly, the speed column followed through the load
      torque; temperature: the column, else the middle of the range).

    Each of the first three lasts ``_CASE_MESH_PERIODS`` x ``accuracy.run_mesh_periods``
    mesh periods at its mean speed (CHOICE: a warm-up of a real gearbox takes minutes;
    the stiffness follows the temperature quasi-statically, so the ramp is compressed into
    a run the FMUs take in seconds); the communication step is a 1/16 mesh period at the
    case's top speed.
    """
    env, acc = plan.envelope, plan.target
    T_nom, w_nom = env.nominal_torque_Nm, env.nominal_speed_rad_s
    mesh_rad = float(tables.mesh_period_rad)
    n_mesh = _CASE_MESH_PERIODS * int(acc.run_mesh_periods)
    temp_rng = env.temperature_range_C
    t_mid = None if temp_rng is None else 0.5 * (temp_rng[0] + temp_rng[1])

    def const(v):
        return None if v is None else (lambda t: np.full(np.shape(t), float(v)))

    def comm(w_top):
        return mesh_rad / w_top / _SAMPLES_PER_MESH

    cases = [drive_case("steady", tables, stop_time_s=n_mesh * mesh_rad / w_nom, comm_step_s=comm(w_nom),
                        torque_Nm=const(T_nom), speed_rad_s=const(w_nom), temperature_C=const(t_mid),
                        note="nominal torque and speed, balanced load")]
    w0, w1 = env.speed_range_rad_s
    if w1 > w0:
        rb1, rb2 = float(tables.base_radius_pinion_m), float(tables.base_radius_gear_m)
        i_red = float(tables.inertia_pinion_kgm2) + float(tables.inertia_gear_kgm2) * (rb1 / rb2) ** 2
        t_run = max(n_mesh * mesh_rad / (0.5 * (w0 + w1)), i_red * (w1 - w0) / (_RUN_UP_LOAD_SHARE * T_nom))
        cases.append(drive_case("run_up", tables, stop_time_s=t_run, comm_step_s=comm(w1), torque_Nm=const(T_nom),
                                speed_rad_s=lambda t: w0 + (w1 - w0) * np.asarray(t) / t_run,
                                temperature_C=const(t_mid),
                                note=f"{w0 * 30 / math.pi:.6g} -> {w1 * 30 / math.pi:.6g} rpm in {t_run:.3g} s"))
        cases.append(drive_case("run_down", tables, stop_time_s=t_run, comm_step_s=comm(w1), torque_Nm=const(T_nom),
                                speed_rad_s=lambda t: w1 - (w1 - w0) * np.asarray(t) / t_run,
                                temperature_C=const(t_mid),
                                note=f"{w1 * 30 / math.pi:.6g} -> {w0 * 30 / math.pi:.6g} rpm in {t_run:.3g} s"))
    wa = (plan.verification or {}).get("worst_at") or {}
    if wa.get("case") == "steady":  # the envelope search's worst steady point, confirmed through the FMUs
        w_w = wa["speed_rpm"] * math.pi / 30
        cases.append(drive_case("worst_point", tables, stop_time_s=n_mesh * mesh_rad / w_w, comm_step_s=comm(w_w),
                                torque_Nm=const(wa["torque_Nm"]), speed_rad_s=const(w_w),
                                temperature_C=const(wa.get("temperature_C")),
                                note=f"search's worst: {wa['torque_Nm']:.5g} N*m, {wa['speed_rpm']:.5g} rpm" +
                                ("" if wa.get("temperature_C") is None else f", {wa['temperature_C']:.4g} degC")))
    if temp_rng is not None and temp_rng[1] > temp_rng[0]:
        lo, hi = temp_rng
        t_run = n_mesh * mesh_rad / w_nom
        cases.append(drive_case("warm_up", tables, stop_time_s=t_run, comm_step_s=comm(w_nom),
                                torque_Nm=const(T_nom), speed_rad_s=const(w_nom),
                                temperature_C=lambda t: lo + (hi - lo) * np.asarray(t) / t_run,
                                note=f"{lo:g} -> {hi:g} degC in {t_run:.3g} s"))
    dc = env.duty_cycle
    if dc is not None:
        t0 = float(dc.time_s[0])
        tt = dc.time_s - t0

        def col(y):
            return lambda t: np.interp(t, tt, y)

        temp_fn = col(dc.temperature_C) if dc.temperature_C is not None else const(t_mid)
        cases.append(drive_case("duty_cycle", tables, stop_time_s=float(tt[-1]),
                                comm_step_s=comm(float(dc.speed_rad_s.max())), torque_Nm=col(dc.torque_Nm),
                                speed_rad_s=col(dc.speed_rad_s), temperature_C=temp_fn,
                                note=f"{Path(dc.source).name}: {len(tt)} points over {tt[-1]:.3g} s"))
    return cases


def run_fmu_drive(fmu_path, case: DriveCase, names=("dte", "mesh_force", "pinion_speed", "pinion_angle")) -> dict:
    """Drive one FMU (fmpy, FMI 2.0 co-simulation, step by step) through a case.

    Returns the output arrays (one value per communication step, at its end), the wall
    time and the CPU time of this thread spent in the stepping loop (the FMU runs in this
    process: pythonfmu wrapper, its Python slave and the C kernel; both FMUs pay the same
    per-step host overhead), and whether the FMU had a temperature input."""
    from fmpy import extract, read_model_description  # fmpy: heavy, only to drive the FMUs
    from fmpy.fmi2 import FMU2Slave  # fmpy: heavy, only to drive the FMUs

    md = read_model_description(str(fmu_path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    tname = next((n for n in TEMPERATURE_INPUTS.values() if n in vr), None)
    unzip = extract(str(fmu_path))
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="plan_verify")
    use_temp = tname is not None and case.temperature_C is not None
    in_vr = [vr["pinion_torque"], vr["gear_torque"]] + ([vr[tname]] if use_temp else [])
    out_vr = [vr[n] for n in names]
    n = len(case.pinion_torque_Nm)
    out = np.empty((n, len(names)))
    h = case.comm_step_s
    try:
        fmu.instantiate()
        fmu.setReal([vr["pinion_speed_start"]], [case.pinion_speed_start_rad_s])

        def inputs(i):
            v = [float(case.pinion_torque_Nm[i]), float(case.gear_torque_Nm[i])]
            return v + ([float(case.temperature_C[i])] if use_temp else [])

        fmu.setReal(in_vr, inputs(0))
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        start = fmu.getReal(out_vr)
        c0, w0 = time.thread_time(), time.perf_counter()
        for i in range(n):
            fmu.setReal(in_vr, inputs(i))
            fmu.doStep(currentCommunicationPoint=i * h, communicationStepSize=h)
            out[i] = fmu.getReal(out_vr)
        cpu, wall = time.thread_time() - c0, time.perf_counter() - w0
        fmu.terminate()
    finally:
        fmu.freeInstance()
        shutil.rmtree(unzip, ignore_errors=True)
    res = {nm: out[:, j] for j, nm in enumerate(names)}
    res["start"] = dict(zip(names, start))
    res.update(wall_s=wall, cpu_s=cpu, temperature_input=tname if use_temp else None)
    return res


def verify_fmus(scene, plan: Plan, *, fmu_dir=None, progress: bool = False, cases=None,
                runtime: Optional[str] = None) -> dict:
    """The planned FMU against the full-fidelity FMU over the scene's envelope (issue 8).

    Builds both with :func:`gearfmu.stages.build_fmu_from_scene` from :func:`planned_scene` (chosen)
    and :func:`full_scene` (their tables computed from the scene, timed), drives both
    through the same cases (:func:`verification_cases`, or ``cases``) with
    :func:`run_fmu_drive` and returns, as JSON-ready data: per FMU its size, table build
    time, FMU build time and temperature input; per case the relative RMS error
    rms(y - y_full)/rms(y_full) of the DTE and of the mesh force (the planner's error
    measure), whether both are within the target, the FMUs' wall and CPU time per
    simulated second and their ratio, and how far the full FMU's pinion turned from the
    drive's rigid-body target (|angle - integral of w_target dt| / that integral)."""
    d = Path(fmu_dir) if fmu_dir else Path(tempfile.mkdtemp(prefix="gearfmu_plan_"))
    d.mkdir(parents=True, exist_ok=True)
    fmus, built = {}, {}
    for which in ("full", "chosen"):
        sc = planned_scene(scene, plan, which=which)
        _say(progress, f"building the {which} FMU", plan.log)
        res = build_fmu_from_scene(sc, d / f"{scene.fmu.model_name}_{which}.fmu", runtime=runtime)
        built[which] = res
        fmus[which] = {"fmu_path": str(res.fmu_path), "fmu_bytes": res.fmu_path.stat().st_size,
                       "table_build_s": res.tables_wall_s, "fmu_build_s": res.build_wall_s,
                       "tables_shape": [int(x) for x in np.shape(res.tables.k_N_per_m)],
                       "max_step_s": res.max_step_s, "integrator": sc.solver.integrator}
    if cases is None:
        cases = verification_cases(scene, plan, built["full"].tables)
    acc = plan.target
    out = {}
    for case in cases:
        _say(progress, f"FMU case {case.name}: {len(case.pinion_torque_Nm)} steps of {case.comm_step_s:.3g} s",
             plan.log)
        r = {w: run_fmu_drive(built[w].fmu_path, case) for w in ("full", "chosen")}
        for w in ("chosen", "full"):  # a second run in the other order: the smaller time counts (noise)
            again = run_fmu_drive(built[w].fmu_path, case)
            for k in ("wall_s", "cpu_s"):
                r[w][k] = min(r[w][k], again[k])
        a, b = r["chosen"], r["full"]
        e_d, e_f = relative_rms(a["dte"], b["dte"]), relative_rms(a["mesh_force"], b["mesh_force"])
        sim = case.stop_time_s
        # rigid-body closed form of the drive: the pinion turns through the integral of the
        # target speed (trapezoids: the speed is linear within each step); the change of the
        # mesh deflection over the run is the small rest
        w_all = np.concatenate(([case.pinion_speed_start_rad_s], case.speed_profile_rad_s))
        turn_ref = float(np.sum(0.5 * (w_all[1:] + w_all[:-1])) * case.comm_step_s)
        track = abs(float(b["pinion_angle"][-1] - b["start"]["pinion_angle"]) - turn_ref) / turn_ref
        out[case.name] = {
            "note": case.note, "stop_time_s": sim, "steps": len(case.pinion_torque_Nm),
            "comm_step_s": case.comm_step_s,
            "temperature_C": None if case.temperature_C is None else
            [float(case.temperature_C.min()), float(case.temperature_C.max())],
            "temperature_input": {w: r[w]["temperature_input"] for w in r},
            "dte_rel": e_d, "mesh_force_rel": e_f,
            "within_target": bool(e_d <= acc.dte_rel and e_f <= acc.mesh_force_rel),
            "wall_per_sim_s": {w: r[w]["wall_s"] / sim for w in r},
            "cpu_per_sim_s": {w: r[w]["cpu_s"] / sim for w in r},
            "cpu_gain_full_over_chosen": r["full"]["cpu_s"] / r["chosen"]["cpu_s"] if r["chosen"]["cpu_s"] else None,
            "angle_tracking_rel": track,
        }
        _say(progress, f"FMU case {case.name}: DTE {e_d:.2e}, force {e_f:.2e} "
                       f"({'within' if out[case.name]['within_target'] else 'above'} target)", plan.log)
    gains = {k: fmus["full"][k] / fmus["chosen"][k] for k in ("fmu_bytes", "table_build_s")
             if fmus["chosen"][k]}
    return {"fmus": fmus, "cases": out, "gain_full_over_chosen": gains,
            "within_target": all(c["within_target"] for c in out.values())}


# ============================================================== scene of a plan
def planned_scene(scene, plan: Plan, which: str = "chosen"):
    """The scene ``gearfmu build`` builds for a plan: the chosen (or, ``which="full"``,
    the full-fidelity) configuration written into the scene's mesh, table, solver,
    operating, deviation and thermal settings.  Its ``accuracy`` is None (a planned
    scene is not planned again); ``text`` stays the original scene source."""
    cfg = plan.chosen if which == "chosen" else plan.full
    env = plan.envelope
    mesh = replace(scene.mesh, contact_model=cfg["contact_model"], slices=int(cfg["slices"]))
    ntq = int(cfg["torque_points"])
    op = replace(scene.operating, torque_points=ntq,
                 torque_range_Nm=env.torque_range_Nm if ntq > 1 else scene.operating.torque_range_Nm)
    tables = replace(scene.tables, points_per_mesh=int(cfg["points_per_mesh"]), torque_points=ntq,
                     slots=int(cfg["slots"]))
    solver = replace(scene.solver, integrator=cfg["integrator"], max_step_s=plan.max_step_s(which))
    pair = scene.pair
    if not cfg["tooth_specific_errors"]:
        def uniform(g):
            d = g.deviations
            return replace(g, deviations=GearDeviations(default=d.default, per_tooth=(),
                                                        lead_crowning_m=d.lead_crowning_m))
        pair = replace(pair, pinion=uniform(pair.pinion), gear=uniform(pair.gear))
    # kept: the thermal options the planner measured (the builder's temperature axis); dropped: no
    # thermal correction and no temperature axis (so no temperature input)
    thermal = _thermal_options(scene, env, cfg["contact_model"]) if cfg["thermal"] else None
    return replace(scene, mesh=mesh, operating=op, tables=tables, solver=solver, pair=pair, thermal=thermal,
                   accuracy=None)


def full_scene(scene, plan: Plan):
    """The full-fidelity scene of a plan (``planned_scene(..., which="full")``)."""
    return planned_scene(scene, plan, which="full")


# ============================================================== report
def _fmt(v) -> str:
    if isinstance(v, float):
        if not math.isfinite(v):
            return str(v)
        return f"{v:.3g}"
    return str(v)


def format_report(plan: Plan) -> str:
    """The fidelity report as a text table."""
    d = plan.to_dict()
    t = d["target"]
    lines = [f"fidelity plan for scene {d['scene']}: target DTE {t['dte_rel']:g}, mesh force "
             f"{t['mesh_force_rel']:g} (relative RMS error vs full model; safety {t['safety_factor']:g})",
             f"envelope: torque {d['envelope']['torque_range_Nm']} N*m, speed "
             f"[{d['envelope']['speed_range_rpm'][0]:.6g}, {d['envelope']['speed_range_rpm'][1]:.6g}] rpm, "
             f"temperature {d['envelope']['temperature_range_C']} degC; "
             f"{d['verification']['points']} search probes", ""]
    lines.append(f"{'choice':<22}{'full':>12}{'chosen':>12}{'status':>9}{'TVMS':>10}{'DTE':>10}{'force':>10}")
    for r in d["choices"]:
        c = r["contribution"]
        full, chosen = r["full"], r["chosen"]
        if r["choice"] == "max_step":
            full, chosen = f"{d['full']['max_step_s']:.2g}s", f"{d['chosen']['max_step_s']:.2g}s"
        lines.append(f"{r['choice']:<22}{_fmt(full):>12}{_fmt(chosen):>12}{r['status']:>9}"
                     f"{_fmt(c['tvms_rel']):>10}{_fmt(c['dte_rel']):>10}{_fmt(c['mesh_force_rel']):>10}")
    for r in d.get("what_if") or []:
        lines.append(f"{'what-if contact_model':<22}{r['contact_model']:>12}  " +
                     (f"skipped: {r['skipped']}" if r.get("skipped") else
                      f"TVMS {_fmt(r['tvms_rel'])}, DTE {_fmt(r['dte_rel'])}, force {_fmt(r['mesh_force_rel'])}"))
    v = d["verification"]
    wa = v.get("worst_at") or {}
    lines += ["", f"envelope search of the combined chosen model against the full one ({v.get('probes')} probes, "
                  f"{v.get('native_runs')} native runs of a budget of {v.get('budget_runs')}, "
                  f"{len(v.get('attempts') or [])} configuration(s) tried):",
              f"  worst: {v.get('worst')}: DTE {_fmt(v['dte_rel'])} (max/range {_fmt(v.get('dte_max_rel'))}), "
              f"mesh force {_fmt(v['mesh_force_rel'])} (max/range {_fmt(v.get('mesh_force_max_rel'))})"
              + (f" at t {_fmt(wa['time_s'][0])}..{_fmt(wa['time_s'][1])} s, {_fmt(wa.get('speed_rpm'))} rpm"
                 if wa.get("time_s") else ""),
              f"  error = rms(diff)/rms(full) of DTE and mesh force per run (docs/plan.md 'Error measure'); "
              f"TVMS {_fmt(v.get('tvms_rel'))}"]
    fv0 = d.get("fmu_verification") or {}
    fmu_bad = bool(fv0.get("cases")) and not fv0.get("within_target")
    if d["within_target"]:
        lines.append(f"  -> within target over the envelope (a plan passes when the worst found is <= "
                     f"{t['safety_factor']:g} x target)" +
                     (" (FMU confirmation within target too)" if fv0.get("cases") else ""))
    elif v.get("refused"):
        lines.append(f"  -> NOT within target: plan refused ({v['refused']}); shown: the best configuration reached")
    elif fmu_bad:
        lines.append("  -> NOT within target: the FMU confirmation has a case ABOVE the target (table below)")
    else:
        lines.append("  -> NOT within target")
    lines.append("")
    lines.append(f"{'cost':<26}{'full':>14}{'chosen':>14}{'full/chosen':>13}")
    cf, cc, g = d["cost"]["full"], d["cost"]["chosen"], d["cost"]["gain_full_over_chosen"]
    for k, label in (("table_build_s", "table build time (s)"), ("table_bytes", "table size (bytes)"),
                     ("fmu_bytes", "FMU size (bytes)"), ("wall_per_sim_s", "s per simulated s")):
        if k in cf and k in cc:
            lines.append(f"{label:<26}{_fmt(cf[k]):>14}{_fmt(cc[k]):>14}{_fmt(g.get(k, math.nan)):>13}")
    if d.get("estimate"):  # gearfmu.tables.estimate (the model behind the build guard)

        lines += ["", "estimate before computing (gearfmu.tables.estimate):"]
        lines += [f"  {w:<7}{BuildEstimate(**e).summary()}" for w, e in d["estimate"].items()]
    fv = d.get("fmu_verification") or {}
    if fv.get("cases"):
        ff, fc = fv["fmus"]["full"], fv["fmus"]["chosen"]
        lines += ["", "planned FMU against the full FMU (fmpy; relative RMS error; CPU s per simulated s):",
                  f"  FMU size {ff['fmu_bytes']} -> {fc['fmu_bytes']} bytes, table build "
                  f"{_fmt(ff['table_build_s'])} -> {_fmt(fc['table_build_s'])} s, temperature input "
                  f"{next(iter(fv['cases'].values()))['temperature_input']['full']} -> "
                  f"{next(iter(fv['cases'].values()))['temperature_input']['chosen']}",
                  f"  {'case':<12}{'DTE':>10}{'force':>10}{'target':>8}{'full':>11}{'chosen':>11}{'gain':>7}  drive"]
        for name, c in fv["cases"].items():
            cps = c["cpu_per_sim_s"]
            lines.append(f"  {name:<12}{_fmt(c['dte_rel']):>10}{_fmt(c['mesh_force_rel']):>10}"
                         f"{'ok' if c['within_target'] else 'ABOVE':>8}{_fmt(cps['full']):>11}{_fmt(cps['chosen']):>11}"
                         f"{_fmt(c['cpu_gain_full_over_chosen']):>7}  {c['note']}")
    return "\n".join(lines)
