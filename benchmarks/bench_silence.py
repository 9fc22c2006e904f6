#!/usr/bin/env python3
"""Benchmark: the longest silence on stderr of every `gearfmu` command (the progress promise).

Every command shows what it is doing on stderr at least every couple of seconds (bars, one-line
notices before each long phase).  This runs each command in a fresh process with stderr on a
pipe that a reader thread drains, stamps every chunk written, and reports the longest gap
between two writes after the first one (the exit counts as a write), with the text just before
the gap (what the user was looking at) and after it, and the start-up: the time from the process
start to its first write (Python loading gearfmu and its libraries).  The table cache is empty for
each scene's first command and kept for the rest (as a user's second command finds it); numba's
cache is the user's.

Prints one JSON object: per scene and command ``longest_silence_s``, ``before`` / ``after``
(the last and next line around it), ``startup_s``, ``wall_s``, ``cpu_s`` (the process and its
children) and ``exit``; ``worst_s`` and ``worst_startup_s`` over all of them.  The machine may be shared: a long gap in a loaded run can be the scheduler's; read
``before`` to see which phase it was.

    python benchmarks/bench_silence.py [--scenes default,fractal] [--commands tables,build,...]
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
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENES = {"default": None, "fractal": ROOT / "examples" / "scenes" / "seed001_table1_fractal.toml",
          "seed000": ROOT / "examples" / "scenes" / "seed000_table1.toml",
          "seed004_pair1": ROOT / "examples" / "scenes" / "seed004_pair1.toml"}
#: the threshold of the promise, s
SILENCE_GOAL_S = 2.0


#: the commands, run in a work folder of each scene (output names relative to it)
COMMANDS = {
    "tables": ["tables", "-o", "t.gtab"],
    "build": ["build", "-o", "b.fmu"],
    "simulate": ["simulate", "-o", "s.csv"],
    "validate": ["validate"],
    "validate_json": ["validate", "--json"],
    "validate_fmu": ["validate", "--fmu", "b.fmu"],
    "ssp": ["ssp", "-o", "p.ssp"],
    "plan_json": ["plan", "--json"],
}
_ESCAPE = re.compile(r"\x1b\[[0-9;]*[A-Za-z]")


def watch(argv, env, cwd=None, timeout_s: float = 3600.0) -> dict:
    """Run ``argv``; stderr chunks with their times (s since the start), exit status, wall and CPU s."""
    chunks = []
    c0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.Popen(argv, env=env, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)

    def read():
        fd = p.stderr.fileno()
        while True:
            b = os.read(fd, 65536)
            if not b:
                return
            chunks.append((time.perf_counter() - t0, b))

    def drain():
        p.stdout.read()

    th = [threading.Thread(target=read, daemon=True), threading.Thread(target=drain, daemon=True)]
    for t in th:
        t.start()
    try:
        rc = p.wait(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        p.kill()
        rc = p.wait()
    for t in th:
        t.join(5)
    wall = time.perf_counter() - t0
    c1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return {"chunks": chunks, "exit": rc, "wall_s": wall,
            "cpu_s": (c1.ru_utime + c1.ru_stime) - (c0.ru_utime + c0.ru_stime)}


def _screen_lines(chunks) -> list:
    """The line on the screen after each chunk: its last non-empty line, else the one before."""
    out, cur = [], "(start)"
    for b in chunks:
        text = _ESCAPE.sub("", b.decode("utf-8", "replace")).replace("\r", "\n")
        lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
        cur = lines[-1][:160] if lines else cur
        out.append(cur)
    return out


def longest_silence(run: dict) -> dict:
    """The longest gap between stderr writes after the first one (the exit counts as a write) and
    its neighbours; ``startup_s``: from the process start to its first write (Python's imports)."""
    times = [t for t, _ in run["chunks"]] + [run["wall_s"]]
    texts = _screen_lines([b for _, b in run["chunks"]]) + ["(exit)"]
    out = {"startup_s": round(times[0], 3), "stderr_writes": len(run["chunks"])}
    if len(times) < 2:
        return dict(out, longest_silence_s=0.0, at_s=0.0, before="(start)", after=texts[0])
    best = max(range(1, len(times)), key=lambda i: times[i] - times[i - 1])
    return dict(out, longest_silence_s=round(times[best] - times[best - 1], 3), at_s=round(times[best - 1], 3),
                before=texts[best - 1], after=texts[best])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", default="default,fractal")
    ap.add_argument("--commands", default=",".join(COMMANDS))
    ap.add_argument("--timeout", type=float, default=3600.0, help="seconds per command")
    a = ap.parse_args(argv)
    out = {"goal_s": SILENCE_GOAL_S, "scenes": {}}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for name in a.scenes.split(","):
            scene = SCENES[name]
            env = dict(os.environ, GEARFMU_CACHE_DIR=str(tmp / f"cache_{name}"))
            env.pop("GEARFMU_NO_TABLE_CACHE", None)
            work = tmp / name
            work.mkdir()
            res = {}
            for cmd in a.commands.split(","):
                args = COMMANDS[cmd] + ([str(scene)] if scene is not None else [])
                print(f"bench_silence: {name}: gearfmu {' '.join(args)}", file=sys.stderr, flush=True)
                run = watch([sys.executable, "-m", "gearfmu.cli", *args], env, cwd=work, timeout_s=a.timeout)
                res[cmd] = dict(longest_silence(run), wall_s=round(run["wall_s"], 2), cpu_s=round(run["cpu_s"], 2),
                                exit=run["exit"])
                print(f"  {res[cmd]}", file=sys.stderr, flush=True)
            out["scenes"][name] = res
    out["worst_s"] = max(r["longest_silence_s"] for s in out["scenes"].values() for r in s.values())
    out["worst_startup_s"] = max(r["startup_s"] for s in out["scenes"].values() for r in s.values())
    print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
