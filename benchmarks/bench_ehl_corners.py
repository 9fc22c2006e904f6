"""Time and accuracy of one smooth EHL solve per point of Moes' (M, L) range (prints JSON).

For every (M, L) of the grid below (Barus viscosity, incompressible: the
assumptions of Moes' fit) one default ``solve_line_contact(M=M, L=L)`` is
timed (CPU time of the process, best of ``--point-repeats`` solves so that numba's
compilation on first use is excluded) and its central
film compared with Moes' (1992) fit as quoted by Venner & Lubrecht 2000
(:func:`gearfmu.ehl.fits.moes_central_film`), the reference of
tests/unit/ehl/test_ehl.py.  Output: ``{"rows": [...], "worst": {...}, "summary": {...}}``,
one flat row per point with ``M``, ``L``, ``cpu_s``, ``cycles``,
``n_intervals``, ``coarse_intervals``, ``attempt``, ``path`` ("fast",
"corner_plan" or "settings", docs/ehl.md), ``fast_stage`` (the fast path's
stage that converged, 0 or 1, else None), ``H_central_moes``,
``H_central_fit``, ``dev_vs_moes`` (relative); ``worst`` is the slowest row,
``summary`` the median, maximum and total CPU time, the number of points
above 1 s (``points_over_1s``) and the mean and maximum
|dev_vs_moes|.  The rows with ``case`` = "default_1025" time the default
1025-node solve of the Roelands / Dowson-Higginson reference oil at M = 20
and 100, L = 10 (minimum of ``--repeats``: half of them before the grid, half after it).

    python benchmarks/bench_ehl_corners.py [--M 5 10 ...] [--L 0 2 ...] [--repeats 5]
"""
from __future__ import annotations

import argparse
import json
import statistics
import sys
import time

from gearfmu.ehl import EHLError, solve_line_contact
from gearfmu.ehl.fits import moes_central_film

M_GRID = (5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 600.0, 1000.0)
L_GRID = (0.0, 2.0, 5.0, 10.0, 15.0, 18.0, 20.0)


def _path(r):
    """Which part of the default path converged (docs/ehl.md)."""
    if "fast_path" in r.residuals:
        return "fast"
    if "corner_plan_pair" in r.residuals:
        return "corner_plan"
    return "settings"


def _fast_stage(r):
    st = r.residuals.get("fast_path_stage")
    return int(st[0]) if st else None


def point(M, L, repeats=2):
    """One grid point, timed as the best of ``repeats`` solves: the first one of a point also
    compiles whatever path it is the first to take (numba compiles on first use), which the
    one warm-up solve in :func:`main` does not reach for every point."""
    cpu = float("inf")
    for _ in range(repeats):
        t = time.process_time()
        try:
            r = solve_line_contact(M=M, L=L, viscosity="barus", compressible=False)
        except EHLError as e:
            return dict(case="moes_range", M=M, L=L, cpu_s=time.process_time() - t, converged=False,
                        error=str(e).split(":")[0])
        cpu = min(cpu, time.process_time() - t)
    fit = moes_central_film(M, L)
    n = r.X.size - 1
    return dict(case="moes_range", M=M, L=L, cpu_s=round(cpu, 4), converged=True,
                cycles=r.iterations, n_intervals=n,
                coarse_intervals=n // 2 ** (r.grid_levels - 1),
                attempt=int(r.residuals["attempt"]), path=_path(r), fast_stage=_fast_stage(r),
                H_central_moes=r.H_central_moes,
                H_central_fit=fit, dev_vs_moes=r.H_central_moes / fit - 1.0)


def default_1025(M, L, repeats, best=float("inf")):
    """The default 1025-node solve at (M, L), best of ``repeats`` and of ``best`` (CPU s)."""
    for _ in range(repeats):
        t = time.process_time()
        r = solve_line_contact(M=M, L=L, n_nodes=1025)
        best = min(best, time.process_time() - t)
    return dict(case="default_1025", M=M, L=L, cpu_s=round(best, 5), converged=True,
                cycles=r.iterations, n_intervals=1024, path=_path(r), fast_stage=_fast_stage(r),
                H_central_moes=r.H_central_moes)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--M", type=float, nargs="+", default=list(M_GRID))
    ap.add_argument("--L", type=float, nargs="+", default=list(L_GRID))
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--point-repeats", type=int, default=2, help="solves per grid point (the best is kept)")
    a = ap.parse_args(argv)
    solve_line_contact(M=20.0, L=5.0, viscosity="barus", compressible=False)   # compile
    solve_line_contact(M=20.0, L=10.0, n_nodes=1025)
    # the default solves: half the repeats before the grid, half after it, so that a slow spell
    # of a shared machine (seconds long) cannot spoil every repeat
    first = (a.repeats + 1) // 2
    rows = [default_1025(M, 10.0, first) for M in (20.0, 100.0)]
    grid = [point(M, L, a.point_repeats) for M in a.M for L in a.L]
    if a.repeats > first:
        rows = [default_1025(r["M"], 10.0, a.repeats - first, r["cpu_s"]) for r in rows]
    rows += grid
    cpu = [r["cpu_s"] for r in grid]
    devs = [abs(r["dev_vs_moes"]) for r in grid if r["converged"]]
    out = dict(rows=rows, worst=max(grid, key=lambda r: r["cpu_s"]),
               summary=dict(points=len(grid), converged=len(devs),
                            median_cpu_s=statistics.median(cpu), max_cpu_s=max(cpu),
                            total_cpu_s=sum(cpu), points_over_1s=sum(c > 1.0 for c in cpu),
                            mean_abs_dev_vs_moes=sum(devs) / max(len(devs), 1),
                            max_abs_dev_vs_moes=max(devs, default=float("nan"))))
    json.dump(out, sys.stdout, indent=1)
    print()


if __name__ == "__main__":
    main()
