#!/usr/bin/env python3
"""Benchmark: the table cache (gearfmu.assembly.table_cache) -- the second command on a scene.

Runs, each in a fresh process and with an empty gearfmu cache folder at the start:
``gearfmu tables SCENE`` (computes the tables and keeps them), ``gearfmu tables SCENE`` again and
``gearfmu build SCENE --no-estimate`` (both read them back), then ``gearfmu tables SCENE
--no-cache`` (computes again).  The table time of each is the one the command prints
("tables ... s"); the ratio second / first is the goal (< 5 %).  Default scene: the fractal
example (examples/scenes/seed001_table1_fractal.toml), whose tables take about half a minute of
CPU.  The machine may be shared: the table times are wall times of the table step only, each
command's CPU time (process and children) is printed beside them.

Prints one JSON object: ``runs`` (per command: table_s, wall_s, cpu_s, from_cache), ``ratio``
(the table time of each command that reads the tables back over the first one's),
``no_cache_ratio`` (the same for ``--no-cache``), ``goal`` and ``within_goal``.

    python benchmarks/bench_cache.py [--scene PATH]
"""
from __future__ import annotations

import argparse
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "examples" / "scenes" / "seed001_table1_fractal.toml"
GOAL = 0.05


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run(args, env, cwd) -> dict:
    c0, t0 = _cpu(), time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "gearfmu.cli", *args], env=env, cwd=cwd, capture_output=True, text=True)
    wall, cpu = time.perf_counter() - t0, _cpu() - c0
    if p.returncode != 0:
        raise SystemExit(f"gearfmu {' '.join(args)} failed ({p.returncode}):\n{p.stderr[-2000:]}")
    m = re.search(r"tables? [^\n]*?(\d+\.\d+) s\b", p.stdout)
    if m is None:
        raise SystemExit(f"gearfmu {' '.join(args)}: no table time in its output:\n{p.stdout}")
    return {"command": "gearfmu " + " ".join(a if not a.startswith("/") else Path(a).name for a in args),
            "table_s": float(m.group(1)), "wall_s": round(wall, 2), "cpu_s": round(cpu, 2),
            "from_cache": "tables read from the cache" in p.stderr}


def summarise(scene: str, runs: list) -> dict:
    """The JSON of the benchmark from its four runs: ``ratio`` of the two commands that read the
    tables back, ``no_cache_ratio`` of the one that computes them again."""
    first = runs[0]["table_s"]
    cached = runs[1:3]
    return {"scene": scene, "runs": runs, "ratio": {r["command"]: r["table_s"] / first for r in cached},
            "no_cache_ratio": runs[3]["table_s"] / first, "goal": GOAL,
            "within_goal": all(r["from_cache"] and r["table_s"] / first < GOAL for r in cached)
            and not runs[0]["from_cache"] and not runs[3]["from_cache"]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", type=Path, default=SCENE)
    a = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        env = dict(os.environ, GEARFMU_CACHE_DIR=str(tmp / "cache"))
        env.pop("GEARFMU_NO_TABLE_CACHE", None)
        scene = str(a.scene.resolve())
        runs = []
        for args in (["tables", scene, "-o", str(tmp / "a.gtab")],
                     ["tables", scene, "-o", str(tmp / "b.gtab")],
                     ["build", scene, "--no-estimate", "-o", str(tmp / "c.fmu")],
                     ["tables", scene, "--no-cache", "-o", str(tmp / "d.gtab")]):
            print(f"bench_cache: gearfmu {' '.join(args)}", file=sys.stderr, flush=True)
            runs.append(run(args, env, tmp))
            print(f"  {runs[-1]}", file=sys.stderr, flush=True)
    out = summarise(a.scene.name, runs)
    print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
