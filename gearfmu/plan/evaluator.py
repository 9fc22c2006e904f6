"""Model evaluation for the planner: tables and native runs of configurations.

A configuration is a dict choice -> level value (:mod:`gearfmu.plan.choices`).
:class:`Evaluator` builds and caches the tables of configurations and the native runs at
envelope points, and measures a configuration against the full one (TVMS and the error
measures of :func:`gearfmu.plan.verify.run_errors`; costs: the deterministic table work, table
size and solver work per simulated second the budget rule ranks by, and the table build time and
native time per simulated second, reported only).
"""
from __future__ import annotations

import math
import time
from dataclasses import replace
from typing import Dict, List, Optional, Tuple

import numpy as np

from ..scene.physics import environment_from_scene
from ..dynamics.native import choose_max_step_s, simulate
from ..gear.gearpair import GearDeviations
from .choices import step_absolute, thermal_options, table_work
from .verify import MEASURES, run_errors, steady_phase
from ..tables.zones import mean_total_stiffness_N_per_m
from ..scene.envelope import AccuracyTarget, Envelope
from ..stages import run_settings
from ..assembly import table_cache
from ..assembly.precompute import precompute_tables

_REBUILD_BELOW_S = 5.0    # cost: tables that took less than this are rebuilt for a clean timing (CHOICE)
#: RK4 steps that one event of the native solver costs, by integrator (CHOICE, docs/plan.md "Cost model"):
#: rk4_seg and rk4_node end a step at a predicted crossing (one more step); rk4_kink locates the event by
#: a trial step and a root search before the step to it
EVENT_STEPS = {"rk4": 0.0, "rk4_seg": 1.0, "rk4_node": 1.0, "rk4_kink": 2.0}


def run_work(res, integrator: str) -> float:
    """Deterministic work of a native run (:class:`gearfmu.dynamics.native.SimResult`): right-hand-side
    evaluations x pair slots, 4 per RK4 step, the steps being the substeps of the completed
    communication steps plus :data:`EVENT_STEPS` per located event.  The budget rule ranks costs
    by it (a count, the same on every machine and at every load; wall times are reported only)."""
    steps = (int(res.info.get("completed_steps", len(res.dte) - 1)) * int(res.substeps)
             + EVENT_STEPS.get(integrator, 1.0) * int(res.info.get("events", 0)))
    return 4.0 * float(res.slots) * steps


def relative_rms(y, y_ref) -> float:
    """rms(y - y_ref) / rms(y_ref) (dimensionless); 0 when both are identically 0,
    inf when only the reference is; NaN-safe inputs are required."""
    y, y_ref = np.asarray(y, dtype=float), np.asarray(y_ref, dtype=float)
    num = float(np.sqrt(np.mean((y - y_ref) ** 2)))
    den = float(np.sqrt(np.mean(y_ref ** 2)))
    if den == 0.0:
        return 0.0 if num == 0.0 else math.inf
    return num / den



# ============================================================== model evaluation
class Evaluator:
    """Builds tables and runs the native solver for configurations (dicts choice -> level value)."""

    def __init__(self, scene, env: Envelope, acc: AccuracyTarget, progress: bool):
        self.scene, self.env, self.acc, self.progress = scene, env, acc, progress
        #: the scene's run settings (its damping); every run sets its own experiment, inputs and integration
        self.settings = run_settings(scene)
        self._tables: Dict[tuple, tuple] = {}
        self._factors: Dict[tuple, object] = {}  # (table key, degC) -> tables at that temperature
        self._runs: Dict[tuple, dict] = {}
        self.native_runs = 0  # native solver runs made (cached runs not counted)
        self.h0: Optional[float] = None
        self.t0_C = scene.thermal.standard_temperature_C if scene.thermal is not None else 30.0
        self.table_wall_s = 0.0  # wall time spent building tables (derived tables cost nothing)
        self.derived: set = set()  # table keys whose tables were taken from a finer grid

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

    def tables(self, cfg: dict, progress: Optional[bool] = None):
        """(MeshTables, build wall time in s) of a configuration (cached).  Taken from the
        tables of a finer nesting grid when one is cached (:meth:`_from_finer`; its time is
        the finer build's time scaled by the angle count), else built or read from gearfmu's
        table cache (:mod:`gearfmu.assembly.table_cache`; the time is then that of the build that
        computed them) (``progress``: the table builder's progress on stderr; None: the planner's)."""
        key = self.table_key(cfg)
        if not self.tables_ready(cfg):
            t0 = time.perf_counter()
            tb = table_cache.cached_tables(precompute_tables, self.table_args(cfg), {},
                                           progress=self.progress if progress is None else progress)
            dt = time.perf_counter() - t0
            self.table_wall_s += dt
            if "table_cache" in tb.provenance:  # read back: the cost is the computation's
                dt = float(tb.provenance.get("precompute", {}).get("wall_s", dt))
            self._tables[key] = (tb, dt)
        return self._tables[key]

    def tables_ready(self, cfg: dict) -> bool:
        """True when the configuration's tables are cached or can be taken from cached finer
        tables (then they are, at no build cost)."""
        key = self.table_key(cfg)
        if key in self._tables:
            return True
        sub = self._from_finer(key)
        if sub is None:
            return False
        self._tables[key] = sub
        self.derived.add(key)
        return True

    def _from_finer(self, key: tuple):
        """The tables of ``key`` from cached tables that differ only in points per mesh, by a
        whole factor s: every s-th angle (the grids nest: phi_j = j x period / n_phi from 0),
        ``k_mean_N_per_m`` recomputed over those angles at the nominal torque row.  Only for
        tables without a temperature axis whose torque axis holds the nominal torque (so that
        ``k_mean_N_per_m`` is that of a build at this resolution).  For the Hertz contact every
        array equals a build at this resolution bit for bit; for the load-iterated contact
        models within the load iteration's tolerance.  None when no such tables are cached."""
        ppm = int(key[3])
        best = None
        for k2, (tb, dt) in self._tables.items():
            p2 = int(k2[3])
            if (k2[:3] + k2[4:] == key[:3] + key[4:] and p2 > ppm and p2 % ppm == 0 and k2 not in self.derived
                    and not tb.has_temperature_axis and (best is None or p2 < int(best[0][3]))):
                best = (k2, tb, dt)
        if best is None:
            return None
        k2, tb, dt = best
        tq = np.asarray(tb.torque_Nm, dtype=float)
        nominal = np.flatnonzero(tq == float(self.env.nominal_torque_Nm))
        if nominal.size == 0:
            return None
        s = int(k2[3]) // ppm

        def sub(a):
            return None if a is None else np.ascontiguousarray(np.asarray(a)[..., ::s])
        k = sub(tb.k_N_per_m)
        prov = dict(tb.provenance)
        if isinstance(prov.get("precompute"), dict):
            prov["precompute"] = dict(prov["precompute"], points_per_mesh=ppm,
                                      derived_from_points_per_mesh=int(k2[3]))
        out = replace(tb, k_N_per_m=k, e_m=sub(tb.e_m), backlash_half_m=sub(tb.backlash_half_m),
                      e_comprehensive_m=sub(tb.e_comprehensive_m), static_te_m=sub(tb.static_te_m), provenance=prov)
        out = replace(out, k_mean_N_per_m=mean_total_stiffness_N_per_m(out, k[int(nominal[0])]))
        return out.validate(), dt / s

    def table_args(self, cfg: dict) -> dict:
        """Arguments of :func:`gearfmu.assembly.precompute.precompute_tables` for a configuration."""
        opts = replace(self.scene.mesh, contact_model=cfg["contact_model"], slices=int(cfg["slices"]))
        pair = self.pair(cfg["tooth_specific_errors"])
        kw = dict(pair=pair, opts=opts, points_per_mesh=int(cfg["points_per_mesh"]),
                  torque_axis_Nm=self.torque_axis(int(cfg["torque_points"])),
                  nominal_torque_Nm=self.env.nominal_torque_Nm, slots=int(cfg["slots"]))
        if cfg["thermal"]:  # the table builder's own temperature axis (docs/plan.md "Thermal estimate")
            kw["thermal"] = thermal_options(self.scene, self.env, cfg["contact_model"])
        if cfg["contact_model"] != "hertz":  # lubricated models need their environment (contact_models)

            kw["contact_env"] = environment_from_scene(replace(self.scene, pair=pair, mesh=opts),
                                                       progress=self.progress)
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
                                               tb.temperature_C) if a is not None)
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
        return v if step_absolute(self.scene, self.acc) else v * self.h0

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
        res = simulate(tb, self.settings, stop_time_s=n * mesh_s, comm_step_s=mesh_s / 16, max_step_s=self.step(cfg),
                       pinion_torque_Nm=T, pinion_speed_start_rad_s=w, integrator=cfg["integrator"])
        out = {"dte": res.dte, "mesh_force": res.mesh_force, "wall_s": res.wall_s, "sim_s": n * mesh_s,
               "work": run_work(res, cfg["integrator"])}
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
        res = simulate(tb, self.settings, stop_time_s=case.stop_time_s, comm_step_s=case.comm_step_s,
                       max_step_s=self.step(cfg), pinion_torque_Nm=case.pinion_torque_Nm,
                       gear_torque_Nm=case.gear_torque_Nm, pinion_speed_start_rad_s=case.pinion_speed_start_rad_s,
                       integrator=cfg["integrator"], bulk_temperature_C=temp)
        out = {"dte": res.dte, "mesh_force": res.mesh_force, "wall_s": res.wall_s, "sim_s": case.stop_time_s,
               "work": run_work(res, cfg["integrator"])}
        self._runs[key] = out
        return out

    def dynamic_error(self, cfg: dict, full: dict) -> dict:
        """Worst over the envelope points of every error measure of ``cfg`` against ``full``
        (:func:`gearfmu.plan.verify.run_errors` on the steady window of each run); the native
        wall time per simulated second of ``cfg`` (reported) and its solver work per simulated
        second (:func:`run_work`, the deterministic cost the budget rule ranks by)."""
        worst: Dict[str, float] = {k: 0.0 for k in MEASURES}
        wall = sim = work = 0.0
        for pt in self.points():
            a, b = self.run(cfg, pt), self.run(full, pt)
            n = len(b["dte"])
            e = run_errors(a["dte"], a["mesh_force"], b["dte"], b["mesh_force"], steady_phase(n), n // 2)
            for k in MEASURES:
                worst[k] = max(worst[k], e[k])
            wall += a["wall_s"]
            work += a["work"]
            sim += a["sim_s"]
        return dict(worst, wall_per_sim_s=wall / sim if sim else math.nan,
                    work_per_sim_s=work / sim if sim else math.nan)

    def measure(self, cfg: dict, full: dict) -> dict:
        _, build_s = self.tables(cfg)
        m = {"tvms_rel": self.tvms_error(cfg, full)}
        m.update(self.dynamic_error(cfg, full))
        m["table_build_s"] = build_s
        m["table_work"] = table_work(cfg)
        m["table_bytes"] = self.table_bytes(cfg)
        return m



def h0_of(ev: "Evaluator", full: dict, env: Envelope) -> float:
    """h0: :func:`gearfmu.dynamics.native.choose_max_step_s` of the full tables at the top envelope
    speed (the smallest over a temperature axis's nodes)."""
    tb_full, _ = ev.tables(full)
    w_top = max(env.speed_range_rad_s[1], env.nominal_speed_rad_s)
    if tb_full.has_temperature_axis:
        return min(choose_max_step_s(tb_full.at_temperature(float(t)), w_top) for t in tb_full.temperature_C)
    return choose_max_step_s(tb_full, w_top)


def cost_entry(ev: Evaluator, cfg: dict) -> dict:
    """Fresh measurement of one configuration's costs (tables rebuilt, runs at every envelope point)."""
    tb, first_s = ev.tables(cfg)
    if first_s < _REBUILD_BELOW_S:  # cheap: rebuild for a timing free of first-call (compile, cache) costs
        t0 = time.perf_counter()
        precompute_tables(**ev.table_args(cfg))
        build_s = time.perf_counter() - t0
    else:  # expensive (EHL film solves): the first build's time stands
        build_s = first_s
    wall = sim = work = 0.0
    for pt in ev.points():
        r = ev.run(cfg, pt)
        wall += r["wall_s"]
        work += r["work"]
        sim += r["sim_s"]
    return {"table_build_s": build_s, "table_work": table_work(cfg), "table_bytes": ev.table_bytes(cfg),
            "wall_per_sim_s": wall / sim, "work_per_sim_s": work / sim,
            "tables_shape": [int(tb.n_torque), int(tb.slots), int(tb.n_phi)]}
