#!/usr/bin/env python3
"""Wall time of the test suite as a user runs it (prints JSON).

Runs ``python -m pytest -q`` (the README's test command; pytest's own options from
pyproject.toml) in a fresh process from the repository root and prints one JSON object:
``wall_s``, ``exit_code`` and ``summary`` (pytest's last line, e.g. "512 passed in 250.1s").
Extra arguments are passed to pytest: ``-m "not slow" -n 2`` times the quick subset
(tests/README.md), a single test file tries this script quickly.

    python benchmarks/bench_tests.py [PYTEST_ARGS ...]
"""
from __future__ import annotations

import json
import os
import shlex
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main(argv=None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *args]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    lines = [ln.strip() for ln in proc.stdout.splitlines() if ln.strip()]
    summary = next((ln.strip("= ") for ln in reversed(lines) if " in " in ln and ("passed" in ln or "failed" in ln
                                                                                  or "error" in ln)), "")
    print(json.dumps({"command": shlex.join(["python", "-m", "pytest", "-q", *args]), "wall_s": wall,
                      "exit_code": proc.returncode, "summary": summary, "cpu_count": os.cpu_count()}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
