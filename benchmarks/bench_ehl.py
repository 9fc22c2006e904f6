"""Benchmark of the line-contact EHL solver (prints JSON; not a test).

For each operating point and grid size (256 ... 4096 intervals): CPU and wall
time per smooth solve (median of ``--repeats``; numba compilation excluded),
the number of multigrid cycles, the time per cycle, the central film in
Moes' scaling and its deviation from Moes' fit (the Barus/incompressible
cases are the ones Moes' fit describes; the Roelands/compressible case sits
about 20 % below it by physics, docs/ehl.md).  Per case, the fitted exponent
p of cost ~ N^p (least squares on log CPU time against log N, over the sizes)
for the whole solve and per cycle (an N log N cost per cycle gives p of
about 1.1 over 256..4096).  The machine's load average is recorded because
other jobs inflate wall time; CPU time is the fairer number on a shared
machine.

    python benchmarks/bench_ehl.py [--repeats 3] [--sizes 256 512 1024 2048 4096]
                                   [--no-fmg]
    python benchmarks/bench_ehl.py --ml-table barus|roelands   # convergence over (M, L)
    python benchmarks/bench_ehl.py --speed [--repeats 7]       # speed vs error

``--speed`` (time per smooth solve over >= 4 grid sizes and
its growth): for Roelands + Dowson-Higginson at M = 20, L = 10 and M = 100, L = 10
(the team's target cases) and sizes 256 .. 4096 intervals, each solve timed with
the default tolerances and stopped at about the discretisation accuracy
(``tol_pressure=1e-3, tol_load=1e-4, tol_residual=1e-4``): CPU ms per solve
(median and minimum of ``--repeats``), per cycle, cycles, and the central film's
error against the finest-grid answer (8192 intervals, converged to pressure
change 1e-9) and against the same grid converged (the algebraic error the stop
leaves); the discretisation error is the difference of the two converged
answers.  Fitted exponents of CPU per solve and per cycle against N (an N log N
cost gives about 1.1 over 256..4096).  Modes: ``default`` (default path and
tolerances), ``discretisation`` (default path, the stop above),
``speed_path`` (``gearfmu.ehl.multigrid.SPEED_SETTING``: F-cycles with a Newton
solve of the coarsest grid, with the stop above) and
``speed_path_default_tolerances``.

Each case is timed with the default Hertzian start, with the full-multigrid
start (``fmg_cycles=1``) and with the FMG start plus the stop at the estimated
discretisation error (``stop_at_discretisation=0.1``) in the same run;
``hc_rel_diff_vs_default`` is the central film's distance from the default row.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import time

import numpy as np

from gearfmu.ehl import solve_line_contact
from gearfmu.ehl.fits import moes_central_film


def bench(M, L, sizes, repeats, **kw):
    rows = []
    for n in sizes:
        times, cpu = [], []
        r = None
        for _ in range(repeats):
            t = time.perf_counter()
            c = time.process_time()
            r = solve_line_contact(M=M, L=L, n_nodes=n + 1, **kw)
            times.append(time.perf_counter() - t)
            cpu.append(time.process_time() - c)
        t_med = float(np.median(times))
        c_med = float(np.median(cpu))
        hc = r.residuals["H_central"]
        # the same grid converged far below the default tolerances: the algebraic
        # error the row's stopping rule left in H_c and H_min
        conv = _converged(M, L, n, **kw)
        rows.append(dict(n_intervals=n, solver=kw.get("solver", "compiled"),
                         fmg_cycles=kw.get("fmg_cycles", 0),
                         stop_at_discretisation=kw.get("stop_at_discretisation", 0.0),
                         discretisation_stop=r.residuals.get("stopped_at_discretisation"),
                         fmg_cycles_per_level=r.residuals.get("fmg_cycles_per_level"),
                         levels=r.grid_levels, cycles=r.iterations,
                         attempt=r.residuals["attempt"],
                         frozen_switch="frozen_switch_from_cycle" in r.residuals,
                         wall_time_ms=1e3 * t_med, cpu_time_ms=1e3 * c_med,
                         cpu_ms_per_cycle=1e3 * c_med / r.iterations,
                         H_central_moes=r.H_central_moes,
                         rel_dev_from_moes=r.H_central_moes / moes_central_film(M, L) - 1.0,
                         # |H_c after cycle k / H_c at convergence - 1|, k = 1, 2, 3 (cycles
                         # of the last setting tried; central node film)
                         hc_rel_diff_after_cycle=[abs(h / hc[-1] - 1.0) for h in hc[:3]],
                         hc_rel_err_vs_converged=(
                             None if conv is None else
                             abs(r.H_central_moes / conv.H_central_moes - 1.0)),
                         hmin_rel_err_vs_converged=(None if conv is None else
                                                    abs(r.H_min_moes / conv.H_min_moes - 1.0))))
    return rows


_CONVERGED = {}


def _converged(M, L, n, **kw):
    """Solve of (M, L) on n intervals to pressure change 1e-9, load 1e-10, scaled
    residual 1e-10 (cached per case): the reference of ``*_rel_err_vs_converged``."""
    from gearfmu.ehl.errors import EHLConvergenceError
    key = (M, L, n, kw.get("viscosity"), kw.get("compressible"))
    if key not in _CONVERGED:
        _CONVERGED[key] = None
        for tp, tr in ((1e-9, 1e-10), (1e-8, 1e-9)):     # the second where the first stalls
            try:
                _CONVERGED[key] = solve_line_contact(
                    M=M, L=L, n_nodes=n + 1, viscosity=kw.get("viscosity", "roelands"),
                    compressible=kw.get("compressible", True), tol_pressure=tp, tol_load=tr,
                    tol_residual=tr, max_cycles=400)
                break
            except EHLConvergenceError:
                pass
    return _CONVERGED[key]


def discretisation_error(rows):
    """Richardson estimate (second order) of the relative discretisation error
    of H_c on each size n: |H(n) - H(n/2)| / 3 / H(n); None for the coarsest."""
    by_n = {r["n_intervals"]: r["H_central_moes"] for r in rows}
    for r in rows:
        h = by_n.get(r["n_intervals"] // 2)
        hn = r["H_central_moes"]
        r["discretisation_error_estimate"] = (None if h is None else abs(hn - h) / 3.0 / hn)


def fitted_exponent(ns, costs):
    """p in cost ~ N^p by least squares on the logarithms."""
    return float(np.polyfit(np.log(np.asarray(ns, float)), np.log(np.asarray(costs, float)), 1)[0])


ML_TABLE_M = (5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0)
ML_TABLE_L = (0.0, 2.0, 5.0, 10.0, 15.0, 20.0)


def ml_table(viscosity, compressible, Ms=ML_TABLE_M, Ls=ML_TABLE_L):
    """Convergence over Moes' (M, L) with the default grid and settings: per point
    converged or not, relaxation attempt, cycles, frozen switch, refined grid,
    Newton-polish rounds, CPU time (also of a failure) and H_c against Moes' fit."""
    from gearfmu.ehl.errors import EHLConvergenceError
    rows = []
    for M in Ms:
        for L in Ls:
            c = time.process_time()
            row = dict(M=M, L=L)
            try:
                r = solve_line_contact(M=M, L=L, viscosity=viscosity, compressible=compressible)
                h = r.residuals
                row.update(converged=True, attempt=h["attempt"], cycles=r.iterations,
                           n_intervals=r.X.size - 1,
                           frozen="frozen_switch_from_cycle" in h,
                           refined=bool(h.get("grid_refined", [0.0])[0]),
                           polish_rounds=(h.get("newton_polish_rounds") or [0])[-1],
                           rel_dev_from_moes=r.H_central_moes / moes_central_film(M, L) - 1.0)
            except EHLConvergenceError as e:
                row.update(converged=False, residual=e.residual_name, value=e.value)
            row["cpu_s"] = time.process_time() - c
            rows.append(row)
            print(json.dumps(row), file=sys.stderr, flush=True)
    return rows


#: stopping at about the discretisation accuracy (docs/ehl.md "Speed"; the same
#: values as gearfmu.ehl.multigrid.DISC_TOLERANCES, repeated so that the benchmark
#: also runs against code versions without them)
DISC_TOLERANCES = dict(tol_pressure=1e-3, tol_load=1e-4, tol_residual=1e-4)
SPEED_CASES = ((20.0, 10.0), (100.0, 10.0))
try:        # the opt-in speed path (F-cycles, Newton on the coarsest grid)
    from gearfmu.ehl.multigrid import SPEED_SETTING
except ImportError:     # older code versions (before/after comparisons)
    SPEED_SETTING = None


from gearfmu.ehl.errors import EHLConvergenceError


def _tight(M, L, n, **kw):
    for tp, tr in ((1e-9, 1e-10), (1e-8, 1e-9), (1e-7, 1e-8)):
        try:
            return solve_line_contact(M=M, L=L, n_nodes=n + 1, tol_pressure=tp, tol_load=tr,
                                      tol_residual=tr, max_cycles=400, **kw)
        except EHLConvergenceError:     # stalled below these tolerances: looser
            pass
    return solve_line_contact(M=M, L=L, n_nodes=n + 1, **kw)


def speed_table(sizes, repeats, finest=8192, cases=SPEED_CASES):
    """Speed vs error (see the module doc, ``--speed``); returns a dict."""
    out = dict(load_average_1min=os.getloadavg()[0], cpu_count=os.cpu_count(),
               finest_reference_intervals=finest, disc_tolerances=DISC_TOLERANCES, cases=[])
    for M, L in cases:
        ref = _tight(M, L, finest)
        hc_ref = ref.H_central_moes
        case = dict(M=M, L=L, viscosity="roelands", compressible=True,
                    H_central_moes_finest=hc_ref, modes={})
        conv = {n: _tight(M, L, n).H_central_moes for n in sizes}
        modes = [("default", {}), ("discretisation", DISC_TOLERANCES)]
        if SPEED_SETTING is not None:
            modes += [("speed_path", dict(SPEED_SETTING, **DISC_TOLERANCES)),
                      ("speed_path_default_tolerances", dict(SPEED_SETTING))]
        for mode, kw in modes:
            rows = []
            for n in sizes:
                cpu = []
                try:
                    for _ in range(repeats):
                        c = time.process_time()
                        r = solve_line_contact(M=M, L=L, n_nodes=n + 1, **kw)
                        cpu.append(time.process_time() - c)
                except EHLConvergenceError as e:
                    rows.append(dict(n_intervals=n, converged=False, error=str(e)[:200]))
                    continue
                hc = r.H_central_moes
                rows.append(dict(
                    n_intervals=n, levels=r.grid_levels, cycles=r.iterations,
                    attempt=r.residuals["attempt"],
                    cpu_ms_median=1e3 * float(np.median(cpu)), cpu_ms_min=1e3 * min(cpu),
                    cpu_ms_per_cycle=1e3 * float(np.median(cpu)) / r.iterations,
                    hc_rel_err_vs_finest=abs(hc / hc_ref - 1.0),
                    hc_rel_err_vs_same_grid_converged=abs(hc / conv[n] - 1.0),
                    discretisation_error_vs_finest=abs(conv[n] / hc_ref - 1.0)))
            ok = [r_ for r_ in rows if "cycles" in r_]
            ns = [r_["n_intervals"] for r_ in ok]
            case["modes"][mode] = dict(
                rows=rows,
                cost_exponent_per_solve=fitted_exponent(ns, [r_["cpu_ms_min"] for r_ in ok]),
                cost_exponent_per_cycle=fitted_exponent(ns, [r_["cpu_ms_per_cycle"]
                                                             for r_ in ok]),
                n_log_n_exponent_reference=fitted_exponent(ns, [n * math.log2(n) for n in ns]))
        out["cases"].append(case)
    out["load_average_1min_end"] = os.getloadavg()[0]
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--sizes", type=int, nargs="+", default=[256, 512, 1024, 2048, 4096])
    ap.add_argument("--no-fmg", action="store_true",
                    help="skip the rows with the full-multigrid start (fmg_cycles=1)")
    ap.add_argument("--ml-table", choices=["barus", "roelands"],
                    help="only the convergence table over M 5-1000 x L 0-20 (Barus: "
                         "incompressible, Roelands: compressible), one JSON line per point")
    ap.add_argument("--speed", action="store_true",
                    help="only the speed-vs-error table (Roelands, M = 20 / 100, L = 10)")
    args = ap.parse_args(argv)
    if args.speed:
        solve_line_contact(M=20.0, L=5.0, n_nodes=257)  # numba compilation
        print(json.dumps(speed_table(args.sizes, args.repeats), indent=1))
        return
    if args.ml_table:
        solve_line_contact(M=20.0, L=5.0, n_nodes=257)  # numba compilation
        rows = ml_table(args.ml_table, args.ml_table == "roelands")
        ok = [r for r in rows if r["converged"]]
        print(json.dumps(dict(viscosity=args.ml_table, load_average_1min=os.getloadavg()[0],
                              converged=len(ok), points=len(rows),
                              failure_cpu_s=[round(r["cpu_s"], 3) for r in rows
                                             if not r["converged"]],
                              total_cpu_s=sum(r["cpu_s"] for r in rows), rows=rows), indent=1))
        return
    solve_line_contact(M=20.0, L=5.0, n_nodes=257)  # numba compilation
    solve_line_contact(M=20.0, L=5.0, n_nodes=257, fmg_cycles=1)
    out = dict(python=platform.python_version(), machine=platform.machine(),
               load_average_1min=os.getloadavg()[0], cpu_count=os.cpu_count(),
               note="CPU time per solve; the machine is shared (see load average)", cases=[])
    cases = [(20.0, 5.0, dict(viscosity="barus", compressible=False)),
             (100.0, 10.0, dict(viscosity="barus", compressible=False)),
             (100.0, 10.0, dict(viscosity="roelands", compressible=True))]
    if not args.no_fmg:
        cases = [c for case in cases for c in
                 (case, (case[0], case[1], dict(case[2], fmg_cycles=1)),
                  (case[0], case[1], dict(case[2], fmg_cycles=1, stop_at_discretisation=0.1)))]
    for M, L, kw in cases:
        rows = bench(M, L, args.sizes, args.repeats, **kw)
        discretisation_error(rows)
        ns = [r["n_intervals"] for r in rows]
        out["cases"].append(dict(
            M=M, L=L, options=dict(kw), rows=rows,
            cost_exponent_per_solve=fitted_exponent(ns, [r["cpu_time_ms"] for r in rows]),
            cost_exponent_per_cycle=fitted_exponent(ns, [r["cpu_ms_per_cycle"] for r in rows]),
            n_log_n_exponent_reference=fitted_exponent(ns, [n * math.log2(n) for n in ns])))
    # H_c of every row against the default (Hertzian start, tight tolerances)
    # row of the same case and size: the algebraic error left by the FMG rows
    ref = {}
    for c in out["cases"]:
        if not c["options"].get("fmg_cycles"):
            ref[(c["M"], c["L"], c["options"].get("viscosity"))] = {
                r["n_intervals"]: r["H_central_moes"] for r in c["rows"]}
    for c in out["cases"]:
        base = ref.get((c["M"], c["L"], c["options"].get("viscosity")), {})
        for r in c["rows"]:
            h = base.get(r["n_intervals"])
            r["hc_rel_diff_vs_default"] = None if h is None else abs(r["H_central_moes"] / h - 1)
    out["load_average_1min_end"] = os.getloadavg()[0]
    # warm start along 8 neighbouring loads (a meshing-position sweep)
    kw = dict(R_m=0.02, E_Pa=2.26e11, u_m_s=5.0, eta0_Pas=0.04, alpha_Pa_inv=2.2e-8)
    loads = np.linspace(3.0e5, 3.35e5, 8)
    t = time.process_time()
    cold = [solve_line_contact(w_N_per_m=w, **kw) for w in loads]
    t_cold = time.process_time() - t
    t = time.process_time()
    prev, warm = None, []
    for w in loads:
        prev = solve_line_contact(w_N_per_m=w, initial=prev, **kw)
        warm.append(prev)
    t_warm = time.process_time() - t
    out["warm_start"] = dict(n_solves=len(loads), cold_cpu_s=t_cold, warm_cpu_s=t_warm,
                             n_intervals=cold[0].X.size - 1,
                             cold_cycles=[r.iterations for r in cold],
                             warm_cycles=[r.iterations for r in warm],
                             max_rel_diff_h_central=max(abs(a.h_central_m / b.h_central_m - 1)
                                                        for a, b in zip(warm, cold)))
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
