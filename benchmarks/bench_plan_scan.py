#!/usr/bin/env python3
"""Benchmark: the fidelity planner's verdict checked on a seeded random scan of gear pairs.

For each of ``--n`` scenes drawn from a seeded generator (normal module 1.5-5 mm, pinion teeth
17-35, ratio 1-2.5, helix angle 0-40 deg, face width 8-40 mm, a line load 50-400 N/mm at the
pinion's base circle, pinion speed 500-4000 rpm, profile form deviation 0-8 um, in a share of
the scenes one tooth with its own deviation and lead crowning; 2-8 slices, 32 points per mesh,
runs of 12 mesh periods: each plan stays cheap) the planner (``gearfmu.plan.plan_scene``,
default target 2 % / 2 %, one-point envelope: the scene's operating point) chooses a
configuration.  Then the chosen and the full-fidelity configuration (``planned_scene``, tables
built from the scene by ``gearfmu.pipeline.compute_tables``, each with its own integrator and
step) are run by the native solver at check points of this benchmark's own -- the operating
point with a run three times the planner's (as the FMU confirmation's steady case) and a seeded
random speed inside the band the one-point envelope's FMU accepts without a warning -- and every
error measure of docs/plan.md "Error measure" (``gearfmu.plan.verify.run_errors``: RMS, DTE
peak-to-peak and mean, mesh orders 1-3 of DTE and force) is compared with its target.

A scene passes when its plan says "within target" and every measure at every check point is
within the target, or when its plan says it is not within target.  Prints one JSON object (and
writes it to ``-o``): per scene the drawn parameters, the chosen configuration, the plan's
verdict, budget use and limiting measure, and per check point every measure; the summary counts
the plans within target, refused, and the violations (a plan within target with a check point
above the target), and the largest check budget use among the plans within target.  The exit
status is 0 whatever the verdicts (benchmarks/report.py shows the violations).

    python benchmarks/bench_plan_scan.py [--n 50] [--seed 2024] [-o build/bench_plan_scan.json]
"""
import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from gearfmu.dynamics.native import simulate  # noqa: E402
from gearfmu.pipeline import compute_tables  # noqa: E402
from gearfmu.plan import plan_scene, planned_scene  # noqa: E402
from gearfmu.plan.verify import (MEASURES, POINT_SPEED_MARGIN_REL, budget_use, limiting_measure,  # noqa: E402
                                 run_errors, steady_phase)
from gearfmu.scene.reader import SceneError, load_scene  # noqa: E402

RUN_MESH_PERIODS = 12     # the planner's comparison runs (CHOICE: cheap; the check runs 3 x longer)
CHECK_LENGTH = 3          # a check run lasts CHECK_LENGTH x RUN_MESH_PERIODS mesh periods (as the FMU steady case)
SAMPLES_PER_MESH = 16


def draw(rng, i: int) -> dict:
    """The drawn parameters of scene ``i`` (in the units their names carry)."""
    helical = rng.random() < 0.75
    return {
        "name": f"scan_{i:03d}",
        "module_mm": float(np.round(rng.uniform(1.5, 5.0), 2)),
        "z1": int(rng.integers(17, 36)),
        "ratio": float(rng.uniform(1.0, 2.5)),
        "helix_angle_deg": float(np.round(rng.uniform(5.0, 40.0), 1)) if helical else 0.0,
        "face_width_mm": float(np.round(rng.uniform(8.0, 40.0), 1)),
        "line_load_N_per_mm": float(rng.uniform(50.0, 400.0)),
        "speed_rpm": float(np.round(rng.uniform(500.0, 4000.0))),
        "profile_form_um": float(np.round(rng.uniform(0.0, 8.0), 2)),
        "tooth_form_um": float(np.round(rng.uniform(2.0, 15.0), 2)) if rng.random() < 0.3 else None,
        "lead_crowning_um": float(np.round(rng.uniform(2.0, 10.0), 2)) if rng.random() < 0.3 else None,
        "slices": int(rng.choice([2, 4, 8])) if helical else int(rng.choice([1, 2, 4])),
        "check_speed_share": float(rng.uniform(-1.0, 1.0)),
    }


def scene_text(p: dict) -> str:
    z2 = max(int(round(p["z1"] * p["ratio"])), p["z1"])
    m, z1, beta = p["module_mm"], p["z1"], math.radians(p["helix_angle_deg"])
    alpha_t = math.atan(math.tan(math.radians(20.0)) / math.cos(beta))
    rb1_m = 0.5 * m * z1 / math.cos(beta) * math.cos(alpha_t) * 1e-3
    torque = p["line_load_N_per_mm"] * p["face_width_mm"] * rb1_m
    dev = f"\n[deviations.pinion]\nprofile_form_um = {p['profile_form_um']}\n"
    if p["lead_crowning_um"] is not None:
        dev += f"lead_crowning_um = {p['lead_crowning_um']}\n"
    if p["tooth_form_um"] is not None:
        dev += f"\n[[deviations.pinion.tooth]]\nindex = 2\nprofile_form_um = {p['tooth_form_um']}\n"
    p["z2"], p["torque_Nm"] = z2, torque
    return f"""
[scene]
name = "{p['name']}"

[gears]
module_mm = {m}
face_width_mm = {p['face_width_mm']}
helix_angle_deg = {p['helix_angle_deg']}
backlash_um = 100.0

[gears.pinion]
teeth = {z1}

[gears.gear]
teeth = {z2}
{dev}
[mesh]
slices = {p['slices']}

[operating]
torque_Nm = {torque:.6g}
speed_rpm = {p['speed_rpm']}

[tables]
points_per_mesh = 32

[accuracy]
run_mesh_periods = {RUN_MESH_PERIODS}
"""


def check(scene, plan, speeds_rad_s) -> list:
    """Every measure of the chosen configuration against the full one at this benchmark's check
    points (steady runs of CHECK_LENGTH x RUN_MESH_PERIODS mesh periods, window: their second half)."""
    sc = {w: planned_scene(scene, plan, which=w) for w in ("chosen", "full")}
    tb = {w: compute_tables(sc[w]) for w in sc}
    out = []
    for w_rad in speeds_rad_s:
        mesh_s = tb["full"].mesh_period_rad / w_rad
        runs = {w: simulate(tb[w], stop_time_s=CHECK_LENGTH * RUN_MESH_PERIODS * mesh_s,
                            comm_step_s=mesh_s / SAMPLES_PER_MESH, max_step_s=plan.max_step_s(w),
                            pinion_torque_Nm=scene.operating.torque_Nm, pinion_speed_start_rad_s=w_rad,
                            damping_ratio=scene.fmu.damping_ratio, damping_model=scene.solver.damping_model,
                            integrator=sc[w].solver.integrator) for w in sc}
        a, b = runs["chosen"], runs["full"]
        n = len(b.dte)
        e = run_errors(a.dte, a.mesh_force, b.dte, b.mesh_force, steady_phase(n, SAMPLES_PER_MESH), n // 2)
        acc = plan.target
        out.append({"speed_rpm": w_rad * 30 / math.pi, **{k: e[k] for k in MEASURES},
                    "u": budget_use(e, acc.dte_rel, acc.mesh_force_rel),
                    "limit": limiting_measure(e, acc.dte_rel, acc.mesh_force_rel)})
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=50, help="scenes in the scan")
    ap.add_argument("--seed", type=int, default=2024)
    ap.add_argument("-o", "--output", default=None, help="also write the JSON here")
    a = ap.parse_args(argv)
    rng = np.random.default_rng(a.seed)
    t_all = time.perf_counter()
    rows = []
    for i in range(a.n):
        p = draw(rng, i)
        text = scene_text(p)
        t0 = time.perf_counter()
        try:
            scene = load_scene(text)
        except SceneError as exc:
            rows.append({"params": p, "skipped": str(exc)})
            print(f"bench_plan_scan: {p['name']}: skipped ({exc})", file=sys.stderr, flush=True)
            continue
        plan = plan_scene(scene)
        v = plan.verification
        w = scene.operating.speed_rad_s
        checks = check(scene, plan, [w, w * (1.0 + POINT_SPEED_MARGIN_REL * p["check_speed_share"])])
        worst = max(c["u"] for c in checks)
        ok = (not plan.within_target) or worst <= 1.0
        rows.append({"params": p, "chosen": dict(plan.chosen), "full": dict(plan.full),
                     "max_step_s": plan.max_step_s(), "within_target": plan.within_target,
                     "plan_u": v["u"], "plan_limit": v["limit"], "probes": v["probes"],
                     "native_runs": v["native_runs"], "checks": checks, "check_u": worst,
                     "check_limit": max(checks, key=lambda c: c["u"])["limit"], "pass": ok,
                     "wall_s": time.perf_counter() - t0})
        print(f"bench_plan_scan: {p['name']} beta {p['helix_angle_deg']:g} deg: "
              f"{'within' if plan.within_target else 'NOT within'} target (u {v['u']:.3g}, {v['limit']}); "
              f"check u {worst:.3g} -> {'ok' if ok else 'VIOLATION'} ({time.perf_counter() - t0:.1f} s)",
              file=sys.stderr, flush=True)
    done = [r for r in rows if "pass" in r]
    inside = [r for r in done if r["within_target"]]
    res = {
        "unit": "budget use u = largest error measure / its target (1 = on target), dimensionless",
        "seed": a.seed, "scenes": len(rows), "planned": len(done),
        "skipped": len(rows) - len(done), "helical": sum(1 for r in done if r["params"]["helix_angle_deg"] > 0),
        "within_target": len(inside), "not_within_target": len(done) - len(inside),
        "violations": sum(1 for r in done if not r["pass"]),
        "worst_check_u_within_target": max((r["check_u"] for r in inside), default=None),
        "reduced_any": sum(1 for r in inside if any(r["chosen"][n] != r["full"][n] for n in r["full"])),
        "wall_s": time.perf_counter() - t_all, "cpu_count": os.cpu_count(),
        "rows": rows,
    }
    text = json.dumps(res, indent=1)
    print(text)
    if a.output:
        Path(a.output).parent.mkdir(parents=True, exist_ok=True)
        Path(a.output).write_text(text + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
