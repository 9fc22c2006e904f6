"""Speed against error of the native planetary solver against the scipy reference (docs/planetary.md).

Prints JSON (stdout); progress on stderr.  Per planetary hard case of gearfmu.bench (contact loss
in every mesh of a three-planet stage with backlash after a sudden unloading, four planets on a
floating sun with a pin position error, a carrier-driven planetary stage followed by a parallel
stage):

* the reference: gearfmu.planetary.reference (event-located solve_ivp DOP853) at rtol 1e-12 and
  128 steps per shortest natural period;
* the native solver with 'rk4', 'rk4_kink' and 'rk4_node' at 2 .. 256 substeps per
  communication step (the whole ``simulate`` call timed, best of ``--repeat``; ``loop_wall_s``
  its compiled loop alone);
* the same scipy reference with DOP853 at rtol 1e-4 .. 1e-10 and 16 .. 64 steps per shortest
  natural period (its largest step), one run each (its time is long and steady);

each row's error against the tight reference: the RMS over the communication instants of the
difference of each mesh's DTE (and mesh force), relative to the reference's range, the worst
mesh.  Every row has the call's wall time and its CPU time (``time.process_time``: the machine is
shared, and the CPU time of these single-threaded solvers depends less on the other load); ``cpu_at``
(and ``wall_at``) gives each method's CPU (wall) time at relative DTE errors 1e-4 and 1e-6 (log-log
interpolation along its own front) and ``speedup_vs_DOP853`` DOP853's time over each native
integrator's at those errors; ``summary`` the smallest speedup over the cases (the goal: the
native planetary solver >= 300 x the scipy reference at 1e-6).  ``example``: the planetary +
parallel reducer (examples/scenes/planetary_reducer.toml) at its default settings, wall and CPU
time per simulated second and per internal step.  ``c_kernel``: the planetary kernel in C
(gearfmu/fmu/kernel/plkernel.h, stepped by pl_do_step through ctypes as an FMU steps it) against the
numba solver's compiled loop on the same run (every hard case and the example, 'rk4_node' and 'rk4'):
the time per internal step of each, their ratio (numba over C) measured in the same run, and whether
the C run's state equals the numba run's bit for bit.

``fmu``: the planetary FMU of examples/scenes/planetary_stage.toml (three planets) in the C host
benchmarks/fmu_rtf_host.c, its real-time factor (simulated seconds per CPU second) at the internal step
that gives 1e-4 relative RMS DTE error against a fine native run (goal >= 10; :func:`fmu_rtf`).

Usage: python benchmarks/bench_planetary.py [--repeat 3] [--mesh-periods 20] [--cases a,b] [--fmu-sim 0.05]
[--fmu-only] [--c-kernel-only]
"""
import argparse
import dataclasses
import json
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from gearfmu.common.vocabulary import GEARBOX_INTEGRATORS
from gearfmu.pipeline import drivetrain_model, load_any, simulate_drivetrain, stage_tables
from gearfmu.planetary.native import simulate
from gearfmu.planetary.reference import simulate_reference
from gearfmu.bench import PLANETARY_CASES, planetary_case
from gearfmu.stages import build_planetary_drivetrain_fmu
from harness import at_error, compile_host, front_at, host_run, unzip_fmu, worst_mesh_errors

ROOT = Path(__file__).resolve().parents[1]
#: the relative RMS DTE errors at which the methods' wall times are compared (JSON key -> value)
TARGETS = {"1e-04": 1e-4, "1e-06": 1e-6}
SUBSTEPS = (2, 4, 8, 16, 32, 64, 128, 256)
#: (rtol, steps per shortest natural period) of the DOP853 rows (as benchmarks/bench_gearbox.py)
DOP853_SETTINGS = ((1e-4, 16), (1e-6, 24), (1e-8, 32), (1e-10, 64))


def say(msg):
    print(f"bench_planetary: {msg}", file=sys.stderr, flush=True)


def timed(fn, repeat):
    """(best wall time, best CPU time of ``repeat`` calls, the result of the call with the best CPU time)."""
    best, best_cpu, res = math.inf, math.inf, None
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        r = fn()
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        best = min(best, wall)
        if cpu < best_cpu:
            best_cpu, res = cpu, r
    return best, best_cpu, res


def case_front(name, repeat, mesh_periods):
    model, kw = planetary_case(name, mesh_periods=mesh_periods)
    H = kw["comm_step_s"]
    say(f"{name}: reference (rtol 1e-12) ...")
    t0 = time.perf_counter()
    ref = simulate_reference(model, rtol=1e-12, steps_per_period=128, **kw)
    ref_wall = time.perf_counter() - t0
    rows = []
    simulate(model, **dict(kw, stop_time_s=H, max_step_s=H))   # compile (or load) first
    for integ in GEARBOX_INTEGRATORS:
        for n in SUBSTEPS:
            wall, cpu, r = timed(lambda: simulate(model, max_step_s=H / n, integrator=integ, **kw), repeat)
            rows.append(dict(method=integ, setting=f"h=H/{n}", step_s=H / n, wall_s=wall, cpu_s=cpu,
                             loop_wall_s=r.wall_s,
                             events=int(r.info["events"]), **worst_mesh_errors(r, ref, model.mesh_names)))
        say(f"{name}: {integ} done")
    for rt, spp in DOP853_SETTINGS:
        say(f"{name}: DOP853 rtol {rt:g}, {spp} steps per period ...")
        wall, cpu, r = timed(lambda: simulate_reference(model, rtol=rt, steps_per_period=spp, **kw), 1)
        rows.append(dict(method="solve_ivp-DOP853", setting=f"rtol={rt:g}, {spp}/period", wall_s=wall, cpu_s=cpu,
                         **worst_mesh_errors(r, ref, model.mesh_names)))
    methods = list(GEARBOX_INTEGRATORS) + ["solve_ivp-DOP853"]
    at = {m: {key: front_at([r for r in rows if r["method"] == m], tg) for key, tg in TARGETS.items()} for m in methods}
    cpu_at = {m: {key: front_at([r for r in rows if r["method"] == m], tg, "cpu_s") for key, tg in TARGETS.items()}
              for m in methods}
    speedup = {m: {tg: (cpu_at["solve_ivp-DOP853"][tg] / cpu_at[m][tg]
                        if cpu_at[m][tg] and cpu_at["solve_ivp-DOP853"][tg] else None) for tg in cpu_at[m]}
               for m in GEARBOX_INTEGRATORS}
    return {"case": name, "dofs": model.n_dof, "meshes": len(model.mesh_names), "comm_step_s": H,
            "stop_time_s": kw["stop_time_s"], "reference": "event-located DOP853 rtol 1e-12, 128 steps per period "
            "(gearfmu.planetary.reference)", "reference_wall_s": ref_wall, "reference_segments": ref.info["segments"],
            "rows": rows, "wall_at": at, "cpu_at": cpu_at, "speedup_vs_DOP853": speedup,
            "clock": "speedups from CPU time (time.process_time) of the whole call"}


def example(repeat):
    """The example reducer at its own settings: wall time per simulated second and per internal step."""
    kind, scene = load_any(ROOT / "examples" / "scenes" / "planetary_reducer.toml")
    model = drivetrain_model(scene, stage_tables(scene))
    simulate_drivetrain(scene, model, stop_time_s=scene.output_interval_s)   # compile (or load)
    wall, cpu, r = timed(lambda: simulate_drivetrain(scene, model), repeat)
    steps = r.substeps * (len(r.time_s) - 1)
    return {"scene": scene.name, "meshes": len(model.mesh_names), "dofs": model.n_dof, "integrator": r.integrator,
            "step_s": r.step_s, "stop_time_s": scene.stop_time_s, "wall_s": wall, "cpu_s": cpu, "loop_wall_s": r.wall_s,
            "wall_per_simulated_s": wall / scene.stop_time_s, "cpu_per_simulated_s": cpu / scene.stop_time_s, "ns_per_internal_step": 1e9 * r.wall_s / steps,
            "events": int(r.info["events"])}


FMU_FACTORS = (0.5, 1.0, 2.0, 4.0, 8.0, 16.0)
FMU_TARGET = 1e-4


def fmu_rtf(repeat, sim_s, scene_name="planetary_stage", integrators=("rk4_node", "rk4_seg", "rk4")):
    """The planetary FMU (``gearfmu build`` of the scene, this machine's binary) in the C host
    benchmarks/fmu_rtf_host.c: ``sim_s`` simulated seconds at the scene's communication step, its
    max_step swept over FMU_FACTORS x the default for each of ``integrators``; each run's error the worst mesh's RMS DTE difference
    against a fine native run (rk4_node at an eighth of the default step) over its range; the CPU time and
    real-time factor (simulated / CPU seconds) at the step where that error is FMU_TARGET (log-log
    interpolation along the sweep; goal >= 10)."""
    kind, scene = load_any(ROOT / "examples" / "scenes" / f"{scene_name}.toml")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        res = build_planetary_drivetrain_fmu(scene, tmp / "p.fmu", platforms=("x86_64-linux",), validation=False,
                                             model_exchange={"interface": "cs"})
        model, s = res.model, res.settings
        md = unzip_fmu(res.fmu_path, tmp / "unz")
        exe = compile_host(tmp)
        outs = [f"{m}.dte" for m in model.mesh_names]
        fine = simulate(model, dataclasses.replace(s, stop_time_s=sim_s, max_step_s=s.max_step_s / 8),
                        motor_torque_Nm=s.motor_torque_start_Nm, load_torque_Nm=s.load_torque_start_Nm)
        by_integrator = {}
        for integ in integrators:
            points = []
            for f in FMU_FACTORS:
                say(f"planetary FMU in the C host, {integ}, max_step {f:g} x default")
                try:
                    wall, cpu, rows = host_run(exe, tmp / "unz", md, sim_s=sim_s, comm_s=s.output_interval_s,
                                               repeat=repeat, outputs=outs, max_step_s=f * s.max_step_s,
                                               integrator=integ, timeout=3600)
                except RuntimeError as exc:   # beyond the integrator's stability: the FMU discards the step
                    points.append({"factor": f, "max_step_s": f * s.max_step_s, "failed": str(exc)[-300:]})
                    continue
                n = min(rows.shape[0], len(fine.time_s))
                err = max(float(np.sqrt(np.mean((rows[:n, j] - fine[o][:n]) ** 2)) / np.ptp(fine[o][:n]))
                          for j, o in enumerate(outs))
                points.append({"factor": f, "max_step_s": f * s.max_step_s, "cpu_s": cpu, "wall_s": wall,
                               "dte_rel_rms_err": err, "rtf_cpu": sim_s / cpu})
            hit = at_error([p for p in points if "failed" not in p], lambda p: p["dte_rel_rms_err"], FMU_TARGET)
            by_integrator[integ] = {
                "sweep": points,
                "at_target": None if hit is None else {"max_step_s": hit[0], "cpu_s": hit[1], "rtf_cpu": sim_s / hit[1]}}
    return {"scene": scene.name, "planets": model.stages[0]["planets"], "dofs": model.n_dof,
            "meshes": len(model.mesh_names), "integrator": s.integrator, "comm_step_s": s.output_interval_s,
            "default_max_step_s": s.max_step_s, "sim_s": sim_s, "host": "benchmarks/fmu_rtf_host.c (C, FMI 2.0)",
            "reference": "native planetary solver, rk4_node at default max_step / 8", "integrators": by_integrator,
            "target_dte_rel_rms_err": FMU_TARGET, "goal": "the planetary FMU >= 10 x real time at 1e-4 relative DTE error"}


def c_kernel(repeat, mesh_periods, cases):
    """The C kernel per internal step against the numba loop, on each case's run (module docstring)."""
    from gearfmu.fmu.planetary_kernel import PlanetaryKernel, compile_planetary_kernel

    lib = compile_planetary_kernel(tempfile.mkdtemp(prefix="bench_planetary_"))
    runs = [(c, *planetary_case(c, mesh_periods=mesh_periods)) for c in cases]
    kind, scene = load_any(ROOT / "examples" / "scenes" / "planetary_reducer.toml")
    model = drivetrain_model(scene, stage_tables(scene))
    s = simulate_drivetrain(scene, model, stop_time_s=scene.output_interval_s).info["settings"]
    runs.append((scene.name, model, dict(stop_time_s=scene.stop_time_s, comm_step_s=s.output_interval_s,
                                         motor_torque_Nm=s.motor_torque_start_Nm,
                                         motor_speed_start_rad_s=s.motor_speed_start_rad_s)))
    rows = []
    for name, model, kw in runs:
        for integ in ("rk4_node", "rk4"):
            simulate(model, **dict(kw, stop_time_s=kw["comm_step_s"], integrator=integ))   # compile (or load)
            loop = math.inf
            for _ in range(repeat):
                r = simulate(model, integrator=integ, **kw)
                loop = min(loop, r.wall_s)
            st = r.info["settings"]
            t_in, t_out = r["motor_torque"], r["load_torque"]
            y0 = model.static_state(float(r.info["reference_torque_Nm"][0]), st.motor_speed_start_rad_s,
                                    st.motor_angle_start_rad)
            K = PlanetaryKernel(lib, model, integ)
            c_wall = math.inf
            for _ in range(repeat):
                K.set_state(y0)
                t0 = time.perf_counter()
                for k in range(len(t_in) - 1):
                    K.step(t_in[k], t_out[k], st.output_interval_s, st.max_step_s)
                c_wall = min(c_wall, time.perf_counter() - t0)
            steps = r.substeps * (len(r.time_s) - 1)
            rows.append({"run": name, "integrator": integ, "dofs": model.n_dof, "meshes": len(model.mesh_names),
                         "internal_steps": steps, "numba_loop_wall_s": loop, "c_wall_s": c_wall,
                         "numba_ns_per_step": 1e9 * loop / steps, "c_ns_per_step": 1e9 * c_wall / steps,
                         "numba_over_c": loop / c_wall, "bit_for_bit": bool(np.array_equal(K.y, r.state))})
            say(f"c_kernel: {name} {integ} done")
    return {"rows": rows, "clock": "best wall time of --repeat runs; C through ctypes, one call per "
            "communication step (the call's cost included); numba: its compiled loop (PlanetaryResult.wall_s)"}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--mesh-periods", type=int, default=20, help="sun mesh periods of every case")
    ap.add_argument("--cases", default=",".join(PLANETARY_CASES))
    ap.add_argument("--fmu-sim", type=float, default=0.05, help="simulated seconds of each planetary FMU run")
    ap.add_argument("--fmu-only", action="store_true", help="only the planetary FMU's real-time factor")
    ap.add_argument("--c-kernel-only", action="store_true", help="only the C kernel against the numba loop")
    a = ap.parse_args(argv)
    if a.fmu_only:
        print(json.dumps({"fmu": fmu_rtf(a.repeat, a.fmu_sim)}, indent=1))
        return
    if a.c_kernel_only:
        print(json.dumps({"c_kernel": c_kernel(a.repeat, a.mesh_periods, a.cases.split(","))}, indent=1))
        return
    fronts = [case_front(c, a.repeat, a.mesh_periods) for c in a.cases.split(",")]
    summary = {}
    for integ in GEARBOX_INTEGRATORS:
        for key in TARGETS:
            vals = [f["speedup_vs_DOP853"][integ][key] for f in fronts]
            summary.setdefault(integ, {})[key] = (None if any(v is None for v in vals) else min(vals))
    out = {"fronts": fronts, "summary_min_speedup_vs_DOP853": summary, "example": example(a.repeat),
           "fmu": fmu_rtf(a.repeat, a.fmu_sim),
           "c_kernel": c_kernel(a.repeat, a.mesh_periods, a.cases.split(",")),
           "goal": "native planetary solver >= 300 x the scipy reference (DOP853) at 1e-6 relative DTE error"}
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
