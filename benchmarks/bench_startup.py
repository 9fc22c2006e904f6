#!/usr/bin/env python3
"""Benchmark: wall and CPU time of each `gearfmu` subcommand on the default scene, cold and warm.

"Cold" is the first run with empty caches: a fresh NUMBA_CACHE_DIR (the native solver and the
EHL kernels are compiled in that process) and a fresh GEARFMU_CACHE_DIR (no cached native
reference result of the validation record, gearfmu.fmu.validation).  "Warm" is the next run of
the same command, which loads the compiled code and the cached results.  Every run is a fresh
process, as a user's shell command is.  The compiled C objects (GEARFMU_CACHE_DIR/objects) and
the C compilers' own caches (zig's) are the user's, left as they are: a machine's first
cross-compilation is a one-off cost that this benchmark does not measure.  Python's bytecode
cache is on (PYTHONDONTWRITEBYTECODE is dropped from the environment), as it is for an installed
package: the first run writes the .pyc files that the next runs read.

Prints one JSON object: per subcommand ``cold_s`` and ``warm_s`` (wall, best of ``--repeat``),
``warm_cpu_s`` (user + system CPU seconds of the best warm run, its child processes included:
less sensitive to other load on a shared machine than wall time), ``cold_over_warm`` and
``warm_within_goal`` (warm wall time <= ``warm_goal_s``).  The machine may be shared: repeat
(``--repeat``) and read the best.

    python benchmarks/bench_startup.py [--repeat 1] [--commands build,simulate,validate,ssp]
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

from gearfmu.fmu.crossbuild import object_cache_dir

#: the goal of every subcommand's warm wall time on the default scene, s
WARM_GOAL_S = 2.0


def _commands(out: Path):
    return {
        "build": ["build", "-q", "-o", str(out / "b.fmu"), "--no-estimate"],
        "simulate": ["simulate", "-o", str(out / "s.csv")],
        "validate": ["validate", "--fmu", str(out / "b.fmu")],
        "ssp": ["ssp", "-o", str(out / "p.ssp")],
    }


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _run(args, env):
    """(wall s, user + system CPU s) of one ``gearfmu`` process and its children."""
    c0, t = _children_cpu(), time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "gearfmu.cli", *args], env=env, capture_output=True, text=True)
    wall, cpu = time.perf_counter() - t, _children_cpu() - c0
    if p.returncode != 0:
        raise SystemExit(f"gearfmu {' '.join(args)} failed ({p.returncode}):\n{p.stderr[-2000:]}")
    return wall, cpu


def _base_env() -> dict:
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


def _fresh_env(tmp: Path, tag: str) -> dict:
    """Empty numba and gearfmu caches, but the user's compiled C objects."""
    cache = tmp / f"gearfmu_cache_{tag}"
    cache.mkdir()
    env = {**_base_env(), "NUMBA_CACHE_DIR": str(tmp / f"numba_{tag}"), "GEARFMU_CACHE_DIR": str(cache)}
    objects = object_cache_dir()
    objects.mkdir(parents=True, exist_ok=True)
    (cache / "objects").symlink_to(objects, target_is_directory=True)
    return env


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--commands", default="build,simulate,validate,ssp")
    a = ap.parse_args(argv)
    names = [c.strip() for c in a.commands.split(",") if c.strip()]
    out = {"unit": "s (wall; cpu = user + system of the process and its children; fresh process per run)",
           "warm_goal_s": WARM_GOAL_S, "repeat": a.repeat, "commands": {}}
    with tempfile.TemporaryDirectory(prefix="gearfmu_startup_") as tmp:
        tmp = Path(tmp)
        cmds = _commands(tmp)
        if "validate" in names and "build" not in names:
            _run(cmds["build"], _base_env())
        for name in names:
            cold, warm = [], []
            for r in range(a.repeat):
                env = _fresh_env(tmp, f"{name}_{r}")
                cold.append(_run(cmds[name], env))
                warm.append(_run(cmds[name], env))
            best_cold, best_warm = min(cold), min(warm)
            out["commands"][name] = {"cold_s": best_cold[0], "warm_s": best_warm[0], "warm_cpu_s": best_warm[1],
                                     "cold_over_warm": best_cold[0] / best_warm[0],
                                     "warm_within_goal": best_warm[0] <= WARM_GOAL_S}
    out["all_warm_within_goal"] = all(c["warm_within_goal"] for c in out["commands"].values())
    print(json.dumps(out, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
