#!/usr/bin/env python3
"""Benchmark: wall time of each `gearfmu` subcommand on the default scene, cold and warm.

"Cold" is the first run with an empty numba cache (a fresh NUMBA_CACHE_DIR: the native solver
and the EHL kernels are compiled in that process); "warm" is the next run of the same command,
which loads the compiled code from that cache.  Every run is a fresh process, as a user's shell
command is.  The C compilers' own caches (zig's) are left as they are: a machine's first
cross-compilation of the Windows runtime is a one-off cost that this benchmark does not measure.

Prints one JSON object: per subcommand ``cold_s``, ``warm_s`` and ``cold_over_warm``, and the
goal of a warm build (``warm_build_goal_s``).  Ratios measured in one run; the machine may be
shared, so repeat (``--repeat``) and read the best.

    python benchmarks/bench_startup.py [--repeat 1] [--commands build,simulate,validate,ssp]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

WARM_BUILD_GOAL_S = 2.0


def _commands(out: Path):
    return {
        "build": ["build", "-q", "-o", str(out / "b.fmu"), "--no-estimate"],
        "simulate": ["simulate", "-o", str(out / "s.csv")],
        "validate": ["validate", "--fmu", str(out / "b.fmu")],
        "ssp": ["ssp", "-o", str(out / "p.ssp")],
    }


def _run(args, env) -> float:
    t = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "gearfmu.cli", *args], env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t
    if p.returncode != 0:
        raise SystemExit(f"gearfmu {' '.join(args)} failed ({p.returncode}):\n{p.stderr[-2000:]}")
    return wall


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--commands", default="build,simulate,validate,ssp")
    a = ap.parse_args(argv)
    names = [c.strip() for c in a.commands.split(",") if c.strip()]
    out = {"unit": "s (wall, fresh process per run)", "warm_build_goal_s": WARM_BUILD_GOAL_S, "commands": {}}
    with tempfile.TemporaryDirectory(prefix="gearfmu_startup_") as tmp:
        tmp = Path(tmp)
        cmds = _commands(tmp)
        if "validate" in names and "build" not in names:
            _run(cmds["build"], os.environ.copy())
        for name in names:
            cold, warm = [], []
            for r in range(a.repeat):
                env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp / f"numba_{name}_{r}")}
                cold.append(_run(cmds[name], env))
                warm.append(_run(cmds[name], env))
            out["commands"][name] = {"cold_s": min(cold), "warm_s": min(warm),
                                     "cold_over_warm": min(cold) / min(warm)}
    b = out["commands"].get("build")
    if b:
        out["warm_build_within_goal"] = b["warm_s"] <= WARM_BUILD_GOAL_S
    print(json.dumps(out, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
