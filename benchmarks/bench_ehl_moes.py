"""The smooth line-contact film against Moes' fit and against references of its own accuracy (prints JSON).

Barus viscosity and an incompressible lubricant throughout (the assumptions of Moes' fit).

* ``grid``: a seeded random grid (default 64 points, seed 2024: M log-uniform on 5..1000, L
  uniform on 0..20).  Per point: the default solve and its deviation from Moes' (1992) fit
  (:func:`gearfmu.ehl.fits.moes_central_film`); the grid-converged central film H_ref, Richardson
  extrapolation (second order) of the solver on 2x and 4x the default grid with tight tolerances
  (1x and 2x where 4x would exceed 16384 intervals; the default tolerances where the tight ones
  stall); the independent discretisation of
  ``benchmarks/ehl_reference.py`` (dense Newton, piecewise-linear pressure kernel, midpoint eps)
  on the 2x grid where that has at most 2048 intervals.  Reported: the fit against H_ref (the
  fit's own accuracy), the default solve against H_ref (the solver's), the independent
  discretisation against the solver on the same grid and against H_ref.
* ``rigid``: the rigid-isoviscous limit M -> 0 at L = 0 against Martin's (1916) closed form with
  the Reynolds outlet condition (:func:`gearfmu.ehl.fits.martin_rigid_isoviscous`), the inlet at
  30 sqrt(2 R h0) upstream in both.
* ``inlet``: the central film with the inlet at -4.5 b (default), -8 b and -16 b.
* ``isoviscous_elastic``: L = 0 at high M on 8192 and 16384 intervals (tight tolerances) and
  the Richardson value against the fit's isoviscous-elastic asymptote 2.621 M^(-1/5).

    python benchmarks/bench_ehl_moes.py [--points 64] [--seed 2024] [--sections grid rigid inlet isoviscous_elastic]
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from ehl_reference import reference_central_film  # noqa: E402

from gearfmu.ehl import EHLError, solve_line_contact  # noqa: E402
from gearfmu.ehl.fits import martin_rigid_isoviscous, moes_central_film  # noqa: E402

LAWS = dict(viscosity="barus", compressible=False)
TIGHT = dict(tol_pressure=1e-7, tol_load=1e-8, tol_residual=1e-7)
DEFAULT_TOLERANCES = dict(tol_pressure=1e-5, tol_load=1e-6, tol_residual=1e-6)
MAX_INTERVALS = 16384
REFERENCE_MAX_INTERVALS = 2048


def random_grid(points: int, seed: int):
    """The seeded random (M, L) grid of tests/unit/ehl/test_ehl.py."""
    rng = np.random.default_rng(seed)
    Ms = 10 ** rng.uniform(math.log10(5.0), 3.0, points)
    Ls = rng.uniform(0.0, 20.0, points)
    return [(float(M), float(L)) for M, L in zip(Ms, Ls)]


def _solve(M, L, **kw):
    try:
        return solve_line_contact(M=M, L=L, **LAWS, **kw)
    except EHLError as exc:
        return exc


def _refined(M, L, n):
    """Solve on n intervals at the tight tolerances, else at the default ones (given, so
    that the solve stops at them and not at its discretisation-error estimate)."""
    for name, tol in (("tight", TIGHT), ("default", DEFAULT_TOLERANCES)):
        r = _solve(M, L, n_nodes=n + 1, **tol)
        if not isinstance(r, Exception):
            r.tolerances = name
            return r
    return r


def grid_point(M, L):
    fit = moes_central_film(M, L)
    t0 = time.process_time()
    r = _solve(M, L)
    row = dict(M=M, L=L, fit=fit, cpu_s=time.process_time() - t0)
    if isinstance(r, Exception):
        row["error"] = str(r)[:200]
        return row
    n = r.X.size - 1
    row.update(n_intervals=n, H_default=r.H_central_moes, dev_default_vs_fit=r.H_central_moes / fit - 1.0)
    na, nb = (2 * n, 4 * n) if 4 * n <= MAX_INTERVALS else (n, 2 * n)
    ra, rb = _refined(M, L, na), _refined(M, L, nb)
    if isinstance(ra, Exception) or isinstance(rb, Exception):
        row["error_refined"] = str(ra if isinstance(ra, Exception) else rb)[:200]
        return row
    row["refined_tolerances"] = [ra.tolerances, rb.tolerances]
    ha, hb = ra.H_central_moes, rb.H_central_moes
    ref = hb + (hb - ha) / 3.0
    row.update(refined_intervals=[na, nb], H_refined=[ha, hb], H_ref=ref,
               dev_fit_vs_ref=fit / ref - 1.0, dev_default_vs_ref=r.H_central_moes / ref - 1.0,
               richardson_correction=(hb - ha) / 3.0 / ref)
    if na <= REFERENCE_MAX_INTERVALS:
        t1 = time.process_time()
        hi, hmin, ok, steps = reference_central_film(M, L, na, ra.X, ra.P, ha)
        row.update(reference_intervals=na, reference_converged=ok, reference_newton_steps=steps,
                   reference_cpu_s=time.process_time() - t1)
        if ok:
            row.update(H_reference=hi, dev_reference_vs_solver_same_grid=hi / ha - 1.0,
                       dev_reference_vs_ref=hi / ref - 1.0, dev_fit_vs_reference=fit / hi - 1.0)
    return row


def section_grid(points, seed, log):
    rows = []
    for k, (M, L) in enumerate(random_grid(points, seed)):
        row = grid_point(M, L)
        rows.append(row)
        log(f"grid {k + 1}/{points} M={M:.4g} L={L:.3g}: default vs fit {row.get('dev_default_vs_fit')}, "
            f"fit vs ref {row.get('dev_fit_vs_ref')}, independent vs solver "
            f"{row.get('dev_reference_vs_solver_same_grid')}")

    def stat(key):
        v = [abs(r[key]) for r in rows if r.get(key) is not None]
        return dict(n=len(v), max=max(v) if v else None, mean=float(np.mean(v)) if v else None)

    return {"seed": seed, "points": points, "rows": rows,
            "failed": sum(1 for r in rows if "H_default" not in r),
            "within_3pct_default_vs_fit": sum(1 for r in rows if abs(r.get("dev_default_vs_fit", 1.0)) <= 0.03),
            "within_5pct_default_vs_fit": sum(1 for r in rows if abs(r.get("dev_default_vs_fit", 1.0)) <= 0.05),
            "default_vs_fit": stat("dev_default_vs_fit"), "fit_vs_ref": stat("dev_fit_vs_ref"),
            "default_vs_ref": stat("dev_default_vs_ref"),
            "reference_vs_solver_same_grid": stat("dev_reference_vs_solver_same_grid"),
            "reference_vs_ref": stat("dev_reference_vs_ref")}


def section_rigid(log, Ms=(1.0, 0.5, 0.2, 0.1), xi_in=-30.0, xi_out=2.0, n=4096):
    rows = []
    c_inf, _ = martin_rigid_isoviscous()
    c, _ = martin_rigid_isoviscous(xi_in)
    for M in Ms:
        Hvl = math.pi * (c_inf / (2.0 * M)) / (8.0 * M)      # expected central film, Venner-Lubrecht units
        s = math.sqrt(2.0 * Hvl)                               # sqrt(2 R h0) in units of b
        r = _solve(M, 0.0, x_in=xi_in * s, x_out=xi_out * s, n_nodes=n + 1)
        if isinstance(r, Exception):
            rows.append(dict(M=M, error=str(r)[:200]))
            continue
        # the inlet in units of sqrt(2 R h0) of the film found (close to xi_in)
        xi_found = xi_in * s / math.sqrt(2.0 * math.pi * r.H_central_moes / (8.0 * M))
        c_found, _ = martin_rigid_isoviscous(xi_found)
        rows.append(dict(M=M, x_in_b=xi_in * s, xi_in=xi_found, n_intervals=n,
                         HM_solver=r.H_central_moes * M, HM_martin=c_found / 2.0, HM_martin_flooded=c_inf / 2.0,
                         HM_fit=moes_central_film(M, 0.0) * M,
                         dev_solver_vs_martin=r.H_central_moes * M / (c_found / 2.0) - 1.0,
                         dev_fit_vs_martin_flooded=moes_central_film(M, 0.0) * M / (c_inf / 2.0) - 1.0))
        log(f"rigid M={M}: {rows[-1]['dev_solver_vs_martin']}")
    return {"xi_in": xi_in, "martin_c_flooded": c_inf, "martin_c_at_xi_in": c,
            "moes_rigid_asymptote_HM": 3.0, "martin_HM_flooded": c_inf / 2.0, "rows": rows}


def section_inlet(log, pts=((5.0, 0.0), (20.0, 15.0), (40.0, 18.0), (600.0, 0.5))):
    rows = []
    for M, L in pts:
        row = dict(M=M, L=L, fit=moes_central_film(M, L))
        for x_in in (-4.5, -8.0, -16.0):
            r = _solve(M, L, x_in=x_in)
            row[f"H_x_in_{-x_in:g}"] = None if isinstance(r, Exception) else r.H_central_moes
        rows.append(row)
        log(f"inlet M={M} L={L}: {row}")
    return {"rows": rows}


def section_isoviscous_elastic(log, Ms=(300.0, 1000.0)):
    rows = []
    for M in Ms:
        ra, rb = _refined(M, 0.0, 8192), _refined(M, 0.0, 16384)
        if isinstance(ra, Exception) or isinstance(rb, Exception):
            rows.append(dict(M=M, error=str(ra if isinstance(ra, Exception) else rb)[:200]))
            continue
        ref = rb.H_central_moes + (rb.H_central_moes - ra.H_central_moes) / 3.0
        rows.append(dict(M=M, H=[ra.H_central_moes, rb.H_central_moes], H_ref=ref,
                         coefficient=ref * M ** 0.2, fit=moes_central_film(M, 0.0),
                         fit_coefficient=moes_central_film(M, 0.0) * M ** 0.2,
                         dev_fit_vs_ref=moes_central_film(M, 0.0) / ref - 1.0))
        log(f"isoviscous-elastic M={M}: {rows[-1]}")
    return {"moes_asymptote_coefficient": 2.621, "rows": rows}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--points", type=int, default=64)
    ap.add_argument("--seed", type=int, default=2024)
    ap.add_argument("--sections", nargs="+", default=["grid", "rigid", "inlet", "isoviscous_elastic"],
                    choices=["grid", "rigid", "inlet", "isoviscous_elastic"])
    a = ap.parse_args(argv)

    def log(msg):
        print(msg, file=sys.stderr, flush=True)

    solve_line_contact(M=20.0, L=10.0, **LAWS)      # compile / load the compiled kernels first
    out = {}
    if "rigid" in a.sections:
        out["rigid"] = section_rigid(log)
    if "inlet" in a.sections:
        out["inlet"] = section_inlet(log)
    if "isoviscous_elastic" in a.sections:
        out["isoviscous_elastic"] = section_isoviscous_elastic(log)
    if "grid" in a.sections:
        out["grid"] = section_grid(a.points, a.seed, log)
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
