#!/usr/bin/env python3
"""Benchmark: wall time of `gearfmu plan --json` on the default scene and every example scene.

Every plan is a fresh process, as a user's shell command is (import, numba cache load, tables,
native runs, the envelope search).  With ``--cold`` the default scene is also planned with an
empty numba cache (a fresh NUMBA_CACHE_DIR: the native kernels are compiled in that run), the
time a user waits for the first plan after installing.  A plan that has not finished after
``--timeout`` seconds is stopped and reported as such.

Prints one JSON object (and writes it to ``-o``): per scene ``wall_s``, ``cpu_s`` (user + system
time of the plan's process and the processes it waited for: on a shared machine the wall time
follows the load, the CPU time much less), ``exit_code`` (0 within
target, 1 not within target, None when stopped), the accuracy target, each choice's status (kept, reduced, dropped,
pinned, fixed), the chosen levels, the verified worst errors
(``dte_rel``, ``mesh_force_rel``, relative RMS against the full-fidelity reference; ``measures``: every
measure of docs/plan.md "Error measure" at the worst point, ``u`` the budget use and ``limit`` the
measure that sets it), the native
runs, and the skipped choices with their reasons.  The machine may be shared: repeat and read
the best.

    python benchmarks/bench_plan.py [--scenes default,examples/scenes/seed003_table1.toml]
                                    [--timeout 1800] [--cold] [-o build/bench_plan.json]
"""
import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from gearfmu.plan.verify import MEASURES  # noqa: E402  (the measure names only; plans run in fresh processes)
#: the planner's time goal on the default scene (a warm numba cache), s of wall time
DEFAULT_SCENE_GOAL_S = 60.0


def _plan(scene: str, timeout_s: float, env: dict) -> dict:
    args = [sys.executable, "-m", "gearfmu.cli", "plan", "--json", "-q"] + ([] if scene == "default" else [scene])
    t, r0 = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
    try:
        p = subprocess.run(args, env=env, capture_output=True, text=True, timeout=timeout_s, cwd=ROOT)
    except subprocess.TimeoutExpired:
        return {"wall_s": time.perf_counter() - t, "exit_code": None, "stopped_after_s": timeout_s}
    wall, r1 = time.perf_counter() - t, resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    out = {"wall_s": wall, "cpu_s": cpu, "exit_code": p.returncode}
    if p.returncode not in (0, 1):
        out["stderr"] = p.stderr[-2000:]
        return out
    d = json.loads(p.stdout)
    v = d["verification"]
    out.update(chosen=d["chosen"], full=d["full"], within_target=d["within_target"], target=d["target"],
               choices=[{k: r[k] for k in ("choice", "status", "full", "chosen")} for r in d["choices"]],
               dte_rel=v["dte_rel"], mesh_force_rel=v["mesh_force_rel"], worst=v.get("worst"),
               u=v.get("u"), limit=v.get("limit"),
               measures={k: v.get(k) for k in MEASURES if k in v},
               native_runs=v.get("native_runs"), probes=v.get("probes"),
               skipped=[{"choice": r["choice"], "levels": r["levels"], "reason": r["reason"]} for r in d.get("skipped", [])])
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", default=None,
                    help="comma-separated scene files ('default' = gearfmu plan without a scene); "
                         "default: the default scene and examples/scenes/*.toml")
    ap.add_argument("--timeout", type=float, default=1800.0, help="stop a plan after this many s of wall time")
    ap.add_argument("--cold", action="store_true", help="also plan the default scene with an empty numba cache")
    ap.add_argument("-o", "--output", default=None, help="also write the JSON here")
    a = ap.parse_args(argv)
    scenes = ([s.strip() for s in a.scenes.split(",") if s.strip()] if a.scenes else
              ["default"] + [str(p.relative_to(ROOT)) for p in sorted((ROOT / "examples" / "scenes").glob("*.toml"))])
    res = {"unit": "s (wall and CPU, fresh process per plan)", "default_scene_goal_s": DEFAULT_SCENE_GOAL_S,
           "cpu_count": os.cpu_count(), "scenes": {}}
    if a.cold:
        with tempfile.TemporaryDirectory(prefix="gearfmu_bench_plan_numba_") as cache:
            res["default_cold_numba_cache"] = _plan("default", a.timeout, dict(os.environ, NUMBA_CACHE_DIR=cache))
    for sc in scenes:
        print(f"bench_plan: {sc}", file=sys.stderr, flush=True)
        res["scenes"][sc] = _plan(sc, a.timeout, os.environ.copy())
    text = json.dumps(res, indent=1)
    print(text)
    if a.output:
        Path(a.output).parent.mkdir(parents=True, exist_ok=True)
        Path(a.output).write_text(text + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
