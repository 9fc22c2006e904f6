"""Benchmark: rough-EHL tables of the default scene (seed 000 Table 1 pair, 44 slices) through the
local process pool.  Prints one JSON object: wall time, film solves, solves per second, passes.

    python benchmarks/bench_ehl_tables.py [--points-per-mesh 64] [--slices 44] [--level 1]
        [--torques 2000] [--workers N]

The issue's goal is >= 64 points per mesh period and 44 slices in under a minute on a 2-core
machine; docs/ehl_mesh.md records what this script measured.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--points-per-mesh", type=int, default=64)
    ap.add_argument("--slices", type=int, default=44)
    ap.add_argument("--level", type=int, default=1)
    ap.add_argument("--torques", type=float, nargs="+", default=[1000.0, 2000.0, 3000.0])
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--progress", action="store_true")
    a = ap.parse_args(argv)

    from gearfmu.contact_models import RoughnessSpec, environment_from_scene
    from gearfmu.precompute import precompute_tables
    from gearfmu.scene import load_scene

    sc = load_scene(None)
    opts = dataclasses.replace(sc.mesh, contact_model="rough_ehl", slices=a.slices)
    sc = dataclasses.replace(sc, mesh=opts)
    env = environment_from_scene(sc, roughness=RoughnessSpec.from_level(a.level), max_workers=a.workers,
                                 progress=a.progress)
    t0 = time.perf_counter()
    c0 = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tab = precompute_tables(sc.pair, opts, points_per_mesh=a.points_per_mesh, torque_axis_Nm=a.torques,
                                nominal_torque_Nm=sc.operating.torque_Nm, contact_env=env)
    wall = time.perf_counter() - t0
    c = tab.provenance["contact"]
    out = {
        "benchmark": "rough-EHL tables, default scene", "points_per_mesh": a.points_per_mesh,
        "slices": a.slices, "roughness_level": a.level, "torques_Nm": a.torques,
        "workers": a.workers or os.cpu_count(), "cpu_count": os.cpu_count(), "wall_s": round(wall, 2),
        "parent_cpu_s": round(time.process_time() - c0, 2), "film_solves": c["solves"],
        "solves_per_s": round(c["solves"] / wall, 2), "film_failures": c.get("film_failures", 0),
        "passes_per_torque": [r["passes"] for r in c["load_iteration"]["rows"]],
        "mean_tvms_N_per_m": [float(v) for v in tab.k_N_per_m.sum(axis=1).mean(axis=1)],
        "load_average_1min": os.getloadavg()[0],
    }
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
