"""The scenes of a plan and their confirmation through the FMUs (docs/plan.md
"Confirmation through the FMUs"): :func:`planned_scene` / :func:`full_scene` (the scenes
``gearfmu build`` builds), :func:`verification_cases` (the drives), :func:`run_fmu_drive`
(one FMU through one drive with fmpy) and :func:`verify_fmus` (planned against full FMU)."""
from __future__ import annotations

import math
import shutil
import tempfile
import time
from dataclasses import replace
from pathlib import Path
from typing import List, Optional

import numpy as np

from ..common.vocabulary import TEMPERATURE_INPUTS
from ..fmu.summary import fmu_summary
from ..gear.gearpair import GearDeviations
from .choices import thermal_options
from .report import Plan
from .verify import (MEASURES, DriveCase, budget_use, case_errors, constant, drive_case, limiting_measure, say,
                          speed_sweeps, target_of)
from ..stages import build_fmu_from_scene

def measure_fmus(scene, plan: Plan, fmu_dir, progress, runtime=None) -> None:
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

    const = constant

    def comm(w_top):
        return mesh_rad / w_top / _SAMPLES_PER_MESH

    cases = [drive_case("steady", tables, stop_time_s=n_mesh * mesh_rad / w_nom, comm_step_s=comm(w_nom),
                        torque_Nm=const(T_nom), speed_rad_s=const(w_nom), temperature_C=const(t_mid),
                        note="nominal torque and speed, balanced load")]
    w0, w1 = env.speed_range_rad_s
    if w1 > w0:
        cases += speed_sweeps(tables, speed_range_rad_s=(w0, w1), torque_Nm=T_nom, temperature_C=t_mid,
                              mesh_periods=n_mesh, comm_step_s=comm(w1), load_share=_RUN_UP_LOAD_SHARE)
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
    """The planned FMU against the full-fidelity FMU over the scene's envelope.

    Builds both with :func:`gearfmu.stages.build_fmu_from_scene` from :func:`planned_scene` (chosen)
    and :func:`full_scene` (their tables computed from the scene, timed), drives both
    through the same cases (:func:`verification_cases`, or ``cases``) with
    :func:`run_fmu_drive` and returns, as JSON-ready data: per FMU its size, table build
    time, FMU build time and temperature input; per case every error measure of the planner
    (:func:`gearfmu.plan.verify.case_errors`: a steady case on the whole mesh periods of its second
    half, a transient one by segments, the worst kept), the budget use, the limiting measure,
    the measures above their target and whether every one is within it, the FMUs' wall and CPU time per
    simulated second and their ratio, and how far the full FMU's pinion turned from the
    drive's rigid-body target (|angle - integral of w_target dt| / that integral)."""
    d = Path(fmu_dir) if fmu_dir else Path(tempfile.mkdtemp(prefix="gearfmu_plan_"))
    d.mkdir(parents=True, exist_ok=True)
    fmus, built = {}, {}
    for which in ("full", "chosen"):
        sc = planned_scene(scene, plan, which=which)
        say(progress, f"building the {which} FMU", plan.log)
        res = build_fmu_from_scene(sc, d / f"{scene.fmu.model_name}_{which}.fmu", runtime=runtime)
        built[which] = res
        fmus[which] = {"fmu_path": str(res.fmu_path), "fmu_bytes": res.fmu_path.stat().st_size,
                       "contents": fmu_summary(res.fmu_path),
                       "table_build_s": res.tables_compute_s, "fmu_build_s": res.build_wall_s,
                       "tables_shape": [int(x) for x in np.shape(res.tables.k_N_per_m)],
                       "max_step_s": res.max_step_s, "integrator": sc.solver.integrator}
    if cases is None:
        cases = verification_cases(scene, plan, built["full"].tables)
    acc = plan.target
    out = {}
    for case in cases:
        say(progress, f"FMU case {case.name}: {len(case.pinion_torque_Nm)} steps of {case.comm_step_s:.3g} s",
             plan.log)
        r = {w: run_fmu_drive(built[w].fmu_path, case) for w in ("full", "chosen")}
        for w in ("chosen", "full"):  # a second run in the other order: the smaller time counts (noise)
            again = run_fmu_drive(built[w].fmu_path, case)
            for k in ("wall_s", "cpu_s"):
                r[w][k] = min(r[w][k], again[k])
        a, b = r["chosen"], r["full"]
        e = case_errors(case, a, b, float(built["full"].tables.mesh_period_rad), int(acc.run_mesh_periods),
                        acc.dte_rel, acc.mesh_force_rel, with_start=False)
        e_d, e_f = e["dte_rel"], e["mesh_force_rel"]
        u = budget_use(e, acc.dte_rel, acc.mesh_force_rel)
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
            **{k: e[k] for k in MEASURES}, "dte_max_rel": e["dte_max_rel"],
            "mesh_force_max_rel": e["mesh_force_max_rel"], "window": e["window"],
            "u": u, "limit": limiting_measure(e, acc.dte_rel, acc.mesh_force_rel),
            "above": [k for k in MEASURES if e[k] > target_of(k, acc.dte_rel, acc.mesh_force_rel)],
            "within_target": bool(u <= 1.0),
            "wall_per_sim_s": {w: r[w]["wall_s"] / sim for w in r},
            "cpu_per_sim_s": {w: r[w]["cpu_s"] / sim for w in r},
            "cpu_gain_full_over_chosen": r["full"]["cpu_s"] / r["chosen"]["cpu_s"] if r["chosen"]["cpu_s"] else None,
            "angle_tracking_rel": track,
        }
        say(progress, f"FMU case {case.name}: DTE {e_d:.2e}, force {e_f:.2e}, budget use {u:.3g} limited by "
                       f"{out[case.name]['limit']} ({'within' if out[case.name]['within_target'] else 'above'} "
                       f"target)", plan.log)
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
    thermal = thermal_options(scene, env, cfg["contact_model"]) if cfg["thermal"] else None
    return replace(scene, mesh=mesh, operating=op, tables=tables, solver=solver, pair=pair, thermal=thermal,
                   accuracy=None)


def full_scene(scene, plan: Plan):
    """The full-fidelity scene of a plan (``planned_scene(..., which="full")``)."""
    return planned_scene(scene, plan, which="full")
