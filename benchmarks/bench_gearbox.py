"""Speed against error of the native gearbox solver against the scipy reference (docs/gearbox.md).

Prints JSON (stdout); progress on stderr.  Per hard case of gearfmu.gearbox.cases (a two-stage
reducer: contact loss in stage 1, the intermediate-shaft resonance, a torque step):

* the reference: gearfmu.gearbox.reference (event-located solve_ivp DOP853) at rtol 1e-12 and
  128 steps per shortest natural period;
* the native solver with 'rk4', 'rk4_kink' and 'rk4_node' at 2 .. 256 substeps per
  communication step (the whole ``simulate`` call timed, best of ``--repeat``; ``loop_wall_s``
  its compiled loop alone);
* the same scipy reference with DOP853 at rtol 1e-4 .. 1e-10 and 16 .. 64 steps per shortest
  natural period (its largest step; fewer than about 24 let the sign-change event detection miss
  contact changes), one run each (its time is long and steady);

each row's error against the tight reference: the RMS over the communication instants of the
difference of each stage's DTE (and mesh force), relative to the reference's range, the worse
stage.  ``wall_at`` gives each method's wall time at relative DTE errors 1e-4 and 1e-6 (log-log
interpolation along its own front) and ``speedup_vs_DOP853`` DOP853's time over each native
integrator's at those errors; ``summary`` the smallest speedup over the cases (the goal: the
native gearbox solver >= 300 x the scipy reference at 1e-6).  ``example``: the example
two-stage reducer (examples/scenes/gearbox_two_stage.toml) at its default settings, wall time
per simulated second and per internal step.

Usage: python benchmarks/bench_gearbox.py [--repeat 3] [--mesh-periods 60] [--cases a,b]
"""
import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from gearfmu.common.vocabulary import GEARBOX_INTEGRATORS
from gearfmu.pipeline import gearbox_model, load_any, simulate_drivetrain, stage_tables
from gearfmu.gearbox.cases import GEARBOX_CASES, gearbox_case
from gearfmu.gearbox.native import simulate
from gearfmu.gearbox.reference import simulate_reference
from harness import front_at, worst_mesh_errors

ROOT = Path(__file__).resolve().parents[1]
#: the relative RMS DTE errors at which the methods' wall times are compared (JSON key -> value)
TARGETS = {"1e-04": 1e-4, "1e-06": 1e-6}
SUBSTEPS = (2, 4, 8, 16, 32, 64, 128, 256)
#: (rtol, steps per shortest natural period) of the DOP853 rows: below ~24 steps per period the sign-change
#: event detection misses contact changes and the solution leaves the reference (measured on the cases)
DOP853_SETTINGS = ((1e-4, 16), (1e-6, 16), (1e-6, 24), (1e-6, 32), (1e-8, 32), (1e-10, 64))


def say(msg):
    print(f"bench_gearbox: {msg}", file=sys.stderr, flush=True)


def timed(fn, repeat):
    """(best wall time of ``repeat`` calls, the result of that call)."""
    best, res = math.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        r = fn()
        wall = time.perf_counter() - t0
        if wall < best:
            best, res = wall, r
    return best, res


def case_front(name, repeat, mesh_periods):
    model, kw = gearbox_case(name, mesh_periods=mesh_periods)
    mesh_names = [m.name for m in model.meshes]
    H = kw["comm_step_s"]
    say(f"{name}: reference (rtol 1e-12) ...")
    t0 = time.perf_counter()
    ref = simulate_reference(model, rtol=1e-12, steps_per_period=128, **kw)
    ref_wall = time.perf_counter() - t0
    rows = []
    t0_Nm = float(np.atleast_1d(kw["motor_torque_Nm"])[0])
    simulate(model, **dict(kw, stop_time_s=H, max_step_s=H, motor_torque_Nm=t0_Nm))   # compile (or load) first
    for integ in GEARBOX_INTEGRATORS:
        for n in SUBSTEPS:
            wall, r = timed(lambda: simulate(model, max_step_s=H / n, integrator=integ, **kw), repeat)
            rows.append(dict(method=integ, setting=f"h=H/{n}", step_s=H / n, wall_s=wall, loop_wall_s=r.wall_s,
                             events=int(r.info["events"]), **worst_mesh_errors(r, ref, mesh_names)))
        say(f"{name}: {integ} done")
    for rt, spp in DOP853_SETTINGS:
        say(f"{name}: DOP853 rtol {rt:g}, {spp} steps per period ...")
        wall, r = timed(lambda: simulate_reference(model, rtol=rt, steps_per_period=spp, **kw), 1)
        rows.append(dict(method="solve_ivp-DOP853", setting=f"rtol={rt:g}, {spp}/period", wall_s=wall,
                         **worst_mesh_errors(r, ref, mesh_names)))
    methods = list(GEARBOX_INTEGRATORS) + ["solve_ivp-DOP853"]
    at = {m: {key: front_at([r for r in rows if r["method"] == m], tg) for key, tg in TARGETS.items()} for m in methods}
    speedup = {m: {tg: (at["solve_ivp-DOP853"][tg] / at[m][tg] if at[m][tg] and at["solve_ivp-DOP853"][tg]
                        else None) for tg in at[m]} for m in GEARBOX_INTEGRATORS}
    return {"case": name, "bodies": model.n_bodies, "meshes": len(model.meshes), "comm_step_s": H,
            "stop_time_s": kw["stop_time_s"], "reference": "event-located DOP853 rtol 1e-12, 128 steps per period "
            "(gearfmu.gearbox.reference)", "reference_wall_s": ref_wall, "reference_segments": ref.info["segments"],
            "rows": rows, "wall_at": at, "speedup_vs_DOP853": speedup}


def example(repeat):
    """The example reducer at its own settings: wall time per simulated second and per internal step."""
    kind, scene = load_any(ROOT / "examples" / "scenes" / "gearbox_two_stage.toml")
    model = gearbox_model(scene, stage_tables(scene))
    simulate_drivetrain(scene, model, stop_time_s=scene.output_interval_s)   # compile (or load)
    wall, r = timed(lambda: simulate_drivetrain(scene, model), repeat)
    steps = r.substeps * (len(r.time_s) - 1)
    return {"scene": scene.name, "stages": len(model.meshes), "bodies": model.n_bodies, "integrator": r.integrator,
            "step_s": r.step_s, "stop_time_s": scene.stop_time_s, "wall_s": wall, "loop_wall_s": r.wall_s,
            "wall_per_simulated_s": wall / scene.stop_time_s, "ns_per_internal_step": 1e9 * r.wall_s / steps,
            "events": int(r.info["events"])}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--mesh-periods", type=int, default=60, help="stage-1 mesh periods of every case")
    ap.add_argument("--cases", default=",".join(GEARBOX_CASES))
    a = ap.parse_args(argv)
    fronts = [case_front(c, a.repeat, a.mesh_periods) for c in a.cases.split(",")]
    summary = {}
    for integ in GEARBOX_INTEGRATORS:
        for key in TARGETS:
            vals = [f["speedup_vs_DOP853"][integ][key] for f in fronts]
            summary.setdefault(integ, {})[key] = (None if any(v is None for v in vals) else min(vals))
    out = {"fronts": fronts, "summary_min_speedup_vs_DOP853": summary, "example": example(a.repeat),
           "goal": "native gearbox solver >= 300 x the scipy reference (DOP853) at 1e-6 relative DTE error"}
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
