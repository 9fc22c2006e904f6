"""Block-Newton polish, its dense solver, the refined-grid rule and the cached grid
constants of the compiled EHL solver (docs/ehl.md, "Newton polish of the spike region"
and "Speed").  References: the discretised equations re-evaluated independently in
numpy (tests/test_ehl.py), LAPACK's solve, the closed form of the grid rule, and a
grid hierarchy built without the cache."""
from __future__ import annotations

import math

import numpy as np
import pytest

from gearfmu.ehl import solve_line_contact
from gearfmu.ehl import mgcore
from gearfmu.ehl.multigrid import EHLParams
from gearfmu.ehl.solver import _dense_solve, effective_alpha, refined_grid_intervals

from test_ehl import _discrete_equations_check


def test_dense_solve_matches_lapack():
    # Reference: numpy.linalg.solve (LAPACK gesv) on a random nonsymmetric system
    # that needs pivoting (zero diagonal entries)
    rng = np.random.default_rng(3)
    for n in (1, 2, 7, 60, 250):
        A = rng.standard_normal((n, n))
        A[np.arange(n), np.arange(n)] = 0.0 if n > 1 else 1.0
        b = rng.standard_normal(n)
        x = _dense_solve(A.copy(), b.copy())
        ref = np.linalg.solve(A, b)
        assert np.allclose(x, ref, rtol=1e-9, atol=1e-9 * np.abs(ref).max())
    # singular: NaN, not an exception (the polish then drops the step)
    x = _dense_solve(np.zeros((3, 3)), np.ones(3))
    assert np.all(np.isnan(x))


@pytest.mark.parametrize("viscosity,compressible", [("roelands", True), ("barus", False)])
def test_corner_point_converges_with_the_newton_polish(viscosity, compressible):
    # M = 500, L = 15 stalled on every relaxation setting at scaled residual
    # floors of 2.5e-6 .. 3e-4 (docs/ehl.md), Roelands + Dowson-Higginson and
    # Barus incompressible alike; with the block-Newton polish both converge
    # (Roelands: polish on setting 5 in 1-4 rounds; Barus: setting 5's stalled
    # state, 20 rounds, after all settings failed).  Reference: the discretised
    # equations re-evaluated in numpy with a dense deformation sum (film
    # consistency 1e-9, load 1e-5, scaled residual 1e-5, as the other Roelands
    # tests).  Measured: Roelands 3e-15, 1.5e-7, 7.2e-7; Barus 3e-15, 1.2e-6,
    # 9.5e-7 (H_c +0.5 % from Moes' fit).
    r = solve_line_contact(M=500.0, L=15.0, viscosity=viscosity, compressible=compressible)
    assert r.converged
    assert r.residuals["newton_polish_rounds"][0] >= 1
    gap_spread, load_err, scaled = _discrete_equations_check(r, viscosity, compressible)
    assert gap_spread < 1e-9
    assert load_err < 1e-5
    assert scaled < 1e-5
    # the solver's own stopping test was met on the last cycle (tight tolerances)
    assert r.residuals["reynolds_residual"][-1] < 1e-6
    assert r.residuals["pressure_change"][-1] < 1e-5


def test_refined_grid_rule_closed_form():
    # Reference: the rule dX <= 0.15 / alpha_eff, alpha_eff = d ln(eta)/dP at P = 1:
    # Barus alpha p_h = L sqrt(M / (2 pi)); M = 50, L = 15: 42.31, so
    # 6 / dX >= 6 x 42.31 / 0.15 = 1692.6 -> 2048 intervals (at least twice 256)
    prm = EHLParams(lam=3 * math.pi ** 2 / (8 * 50.0 ** 2),
                    A=15.0 * math.sqrt(50.0 / (2 * math.pi)), z=-1.0, php0=1.0, c1=1.0,
                    compressible=False, x_in=-4.5, x_out=1.5)
    assert effective_alpha(prm) == pytest.approx(42.31, rel=1e-3)
    assert refined_grid_intervals(prm, 6.0, 256) == 2048
    assert refined_grid_intervals(prm, 6.0, 1024) == 2048
    assert refined_grid_intervals(prm, 6.0, 4096) is None      # above REFINE_MAX_INTERVALS


def test_cached_grid_constants_equal_a_fresh_build():
    # Reference: the constants of the same hierarchy computed without the cache
    prm = EHLParams(lam=0.1, A=2.0, z=-1.0, php0=1.0, c1=1.0, compressible=False,
                    x_in=-4.5, x_out=1.5)
    a = mgcore.FlatMultigrid(prm, 4, 32)
    b = mgcore.FlatMultigrid(prm, 4, 32)
    assert a.K is b.K and a.khr is b.khr                # shared, not rebuilt
    ns = [32 * 2 ** k + 1 for k in range(4)]
    off = np.concatenate(([0], np.cumsum(ns)))
    ms = [int(a.iarr[4, l]) for l in range(4)]
    moff = np.concatenate(([0], np.cumsum(ms)))
    toff = np.concatenate(([0], np.cumsum([m // 2 for m in ms])))
    fresh = mgcore._grid_constants(ns, ms, off, moff, toff, -4.5, 1.5)
    for x, y in zip((a.dx, a.K, a.khr, a.khi, a.twr, a.twi), fresh[1:]):
        assert np.array_equal(x, y)
    for x, y in zip(a.X, fresh[0]):
        assert np.array_equal(x, y)
