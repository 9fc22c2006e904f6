"""Block-Newton polish, its dense solver, the refined-grid rule and the cached grid
constants of the compiled EHL solver (docs/ehl.md, "Newton polish of the spike region"
and "Speed").  References: the discretised equations re-evaluated independently in
numpy (tests/unit/ehl/test_ehl.py), LAPACK's solve, the closed form of the grid rule, and a
grid hierarchy built without the cache."""
from __future__ import annotations

import math

import numpy as np
import pytest

from gearfmu.ehl import solve_line_contact
from gearfmu.ehl import coarse_newton, mgkernels, multigrid
from gearfmu.ehl.multigrid import EHLParams
from gearfmu.ehl.coarse_newton import _lu_solve as _dense_solve
from gearfmu.ehl.grids import effective_alpha, refined_grid_intervals

from support.ehl_checks import discrete_equations_check

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow


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
    # 9.5e-7 (H_c +0.5 % from Moes' fit).  Whether the polish is reached depends on the last bits
    # of the relaxation (the IEEE-exact deformation FFT lets Barus converge on a setting without
    # it), so the test asks for convergence to the discrete equations, not for the route taken.
    r = solve_line_contact(M=500.0, L=15.0, viscosity=viscosity, compressible=compressible)
    assert r.converged
    gap_spread, load_err, scaled = discrete_equations_check(r, viscosity, compressible)
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
    a = multigrid.FlatMultigrid(prm, 4, 32)
    b = multigrid.FlatMultigrid(prm, 4, 32)
    assert a.K is b.K and a.khr is b.khr                # shared, not rebuilt
    ns = [32 * 2 ** k + 1 for k in range(4)]
    off = np.concatenate(([0], np.cumsum(ns)))
    ms = [int(a.iarr[4, l]) for l in range(4)]
    moff = np.concatenate(([0], np.cumsum(ms)))
    toff = np.concatenate(([0], np.cumsum(ms)))     # base table + stage table per level
    fresh = multigrid._grid_constants(ns, ms, off, moff, toff, -4.5, 1.5)
    for x, y in zip((a.dx, a.K, a.khr, a.khi, a.twr, a.twi), fresh[1:]):
        assert np.array_equal(x, y)
    for x, y in zip(a.X, fresh[0]):
        assert np.array_equal(x, y)


@pytest.mark.parametrize("setting,gamma,fmg", [(0, 2, False), (1, 2, False), (0, "F", False),
                                               (0, 1, False), (0, 2, True)])
def test_lean_cycle_is_bitwise_the_full_cycle(setting, gamma, fmg):
    # The lean cycle (multigrid option lean=1, default; docs/ehl.md "Speed") only
    # skips work whose result is never read or is already there (coefficients
    # right after the restriction, the film after a post-sweep followed by a
    # prolongation, the finest coefficients of the convergence test).
    # Reference: the same cycles with every step computed (lean=0): P, H, H0
    # and the per-cycle histories must agree bit for bit (a skipped step that
    # was needed would change them at once).  Roelands + Dowson-Higginson,
    # M = 100, L = 10 on 513 nodes (5 levels) and Barus M = 20, L = 10.
    from gearfmu.ehl.solver import RELAXATION_SETTINGS
    for M, L, z in ((100.0, 10.0, 0.6), (20.0, 10.0, -1.0)):
        A = L * math.sqrt(M / (2.0 * math.pi)) if z < 0 else 8.0
        prm = EHLParams(lam=3.0 * math.pi ** 2 / (8.0 * M ** 2), A=A, z=z, php0=2.0, c1=0.3,
                        compressible=z > 0, x_in=-4.5, x_out=1.5)
        hc = 0.2 if M == 20.0 else 0.05
        out = []
        for lean in (1, 0):
            o = dict(RELAXATION_SETTINGS[setting], gamma=gamma, lean=lean)
            fm = multigrid.FlatMultigrid(prm, 5, 32, **o)
            if fmg:
                fm.fmg_start(hc)
            else:
                fm.hertz_start(hc)
            ok, k, h = fm.iterate(max_cycles=6, min_cycles=6, tol_pressure=0.0, tol_load=0.0,
                                  tol_residual=0.0)
            out.append((fm.level_P().copy(), fm.level_H().copy(), fm.H0.copy(), h))
        (Pa, Ha, H0a, ha), (Pb, Hb, H0b, hb) = out
        assert np.all(np.isfinite(Pa)) and np.max(Pa) > 0.5
        assert np.array_equal(Pa, Pb) and np.array_equal(Ha, Hb) and np.array_equal(H0a, H0b)
        for key in ha:
            assert np.array_equal(np.asarray(ha[key]), np.asarray(hb[key])), key


def test_lean_cycle_with_the_time_term_is_bitwise_the_full_cycle():
    # The transient solver's time term (c_t > 0, docs/ehl_transient.md) runs
    # through the same lean cycle; reference: lean=0 (every step computed).
    prm = EHLParams(lam=3.0 * math.pi ** 2 / (8.0 * 400.0), A=8.0, z=0.6, php0=2.0, c1=0.3,
                    compressible=True, x_in=-4.5, x_out=1.5)
    out = []
    for lean in (1, 0):
        fm = multigrid.FlatMultigrid(prm, 4, 32, dist=1, lean=lean)
        fm.hertz_start(0.2)
        fm.iterate(max_cycles=4, min_cycles=4, tol_pressure=0.0, tol_load=0.0,
                   tol_residual=0.0)
        dT = 6.0 / 256
        fm.set_time_term(1.5 / dT, -1.2 * fm.rho_H() / dT)
        fm.iterate(max_cycles=3, min_cycles=3, tol_pressure=0.0, tol_load=0.0,
                   tol_residual=0.0)
        out.append((fm.level_P().copy(), fm.level_H().copy()))
    assert np.all(np.isfinite(out[0][0]))
    assert np.array_equal(out[0][0], out[1][0]) and np.array_equal(out[0][1], out[1][1])


def test_stage_twiddle_fft_matches_the_direct_sum_and_numpy():
    # The film FFT with per-stage twiddle tables (deformation.stage_twiddles).
    # References: the O(N^2) direct sum of the deformation (1e-12 relative to
    # its largest value) and numpy's FFT of the same complex sequence (1e-12).
    from gearfmu.ehl.deformation import (DeformationOperator, deformation_direct, _cfft,
                                         stage_twiddles)
    rng = np.random.default_rng(7)
    for n in (65, 129, 1025, 2049):
        op = DeformationOperator(n, 6.0 / (n - 1))
        P = rng.random(n)
        ref = deformation_direct(P, op.K)
        assert np.max(np.abs(op(P) - ref)) < 1e-12 * np.max(np.abs(ref))
    for N in (2, 4, 16, 512):
        m = 2 * N
        ang = -2.0 * np.pi * np.arange(N) / m
        sr, si = stage_twiddles(np.cos(ang), np.sin(ang), m)
        z = rng.standard_normal(N) + 1j * rng.standard_normal(N)
        for sign, ref in ((1.0, np.fft.fft(z)), (-1.0, np.fft.ifft(z) * N)):
            re, im = z.real.copy(), z.imag.copy()
            _cfft(re, im, N, sr, si, sign)
            assert np.max(np.abs(re + 1j * im - ref)) < 1e-12 * np.max(np.abs(ref))


def _coarse_fas_state(M, L, z, compressible, order2=1):
    """A FAS coarse-grid problem (level 0 of a 3-level hierarchy, 33 nodes) as
    the cycle sets it up after a few cycles, with a generic right-hand side."""
    A = L * math.sqrt(M / (2.0 * math.pi)) if z < 0 else 0.8 * L
    prm = EHLParams(lam=3.0 * math.pi ** 2 / (8.0 * M ** 2), A=A, z=z, php0=2.0, c1=0.3,
                    compressible=compressible, x_in=-4.5, x_out=1.5)
    fm = multigrid.FlatMultigrid(prm, 3, 32, load_mode=1, switch=0.3, omega_gs=0.6, omega_j=0.5,
                              c_h0=0.1, stick=10.0, order2=order2)
    fm.hertz_start(0.15)
    fm.iterate(max_cycles=3, min_cycles=3, tol_pressure=0.0, tol_load=0.0, tol_residual=0.0,
               stall_window=10 ** 6)
    S = fm.state()
    mgkernels._down(2, S)
    mgkernels._down(1, S)
    o, n = int(fm.iarr[0, 0]), int(fm.iarr[1, 0])
    fm.f[o + 1:o + n - 1] += 1e-3 * np.random.default_rng(0).standard_normal(n - 2)
    return fm, S, o, n


@pytest.mark.parametrize("M,L,z,compressible,order2", [(20.0, 5.0, -1.0, False, 1),
                                                       (20.0, 5.0, 0.6, True, 1),
                                                       (100.0, 10.0, 0.6, True, 1),
                                                       (20.0, 5.0, 0.6, True, 0)])
def test_coarse_newton_jacobian_matches_finite_differences(M, L, z, compressible, order2):
    # The Newton system of the coarsest-grid solve (coarse_newton._coarse_jacobian, the
    # speed path's coarse solver).  Reference: central finite differences (step
    # 1e-7) of the coarse residual f - L(P, H(P, H0)) and of the load equation
    # g - dX sum P, evaluated by the cycle's own film/coefficient/residual
    # kernels.  Measured: 3e-12 (Barus), 1.1e-7..2.9e-7 (Roelands + D-H: the
    # finite difference straddles the P = 0 kink of the node next to the
    # cavitated region); a missing or wrong term gives 1e-3 .. 1.
    fm, S, o, n = _coarse_fas_state(M, L, z, compressible, order2)
    P = fm.P
    rho, eps, dle, drho, _, wrk = fm.work[:6]

    def resid():
        fm.update_film(0)
        mgkernels._coef(0, P, fm.H, rho, eps, dle, drho, fm.iarr, fm.prmv)
        mgkernels._residual(0, P, fm.H, fm.f, rho, eps, wrk, fm.iarr, fm.dx, order2 > 0, 0.0,
                         False)
        return wrk[o:o + n].copy(), fm.g[0] - fm.dx[0] * P[o:o + n].sum()

    r0, _ = resid()
    act = np.array([k for k in range(1, n - 1) if P[o + k] > 0 or P[o + k - 1] > 0
                    or P[o + k + 1] > 0], dtype=np.int64)
    buf = np.zeros(n, dtype=np.int64)
    buf[:act.size] = act
    J, b = coarse_newton._coarse_jacobian(S, buf, act.size, True)
    assert J.shape == (act.size + 1, act.size + 1)
    assert np.array_equal(b[:act.size], -r0[act])
    Jfd = np.zeros_like(J)
    step = 1e-7
    for c, k in enumerate(list(act) + [None]):
        if k is None:
            fm.H0[0] += step
            rp, lp = resid()
            fm.H0[0] -= 2 * step
            rm, lm = resid()
            fm.H0[0] += step
        else:
            P[o + k] += step
            rp, lp = resid()
            P[o + k] -= 2 * step
            rm, lm = resid()
            P[o + k] += step
        Jfd[:act.size, c] = (rp[act] - rm[act]) / (2 * step)
        Jfd[act.size, c] = (lp - lm) / (2 * step)
    assert np.max(np.abs(J - Jfd)) < 1e-5 * np.max(np.abs(Jfd))


@pytest.mark.parametrize("M,L,z,compressible", [(20.0, 5.0, -1.0, False),
                                                 (100.0, 10.0, 0.6, True)])
def test_spike_newton_jacobian_on_the_finest_grid_matches_finite_differences(M, L, z,
                                                                             compressible):
    # The spike block's Newton system (coarse_newton._spike_newton uses _coarse_jacobian on
    # the finest level of the hierarchy; its grid spacing, kernel and offsets are that
    # level's).  Reference: central finite differences (step 1e-7) of the finest-grid
    # residual f - L(P, H(P)) (forward differences at cavitated nodes) evaluated by the
    # cycle's own film/coefficient/residual kernels,
    # over the block of 2 x 6 + 1 nodes around the largest scaled residual (the width of
    # attempts.FAST_SETTING).  A wrong level (spacing or kernel of level 0) gives errors of
    # order 1.
    A = L * math.sqrt(M / (2.0 * math.pi)) if z < 0 else 0.8 * L
    prm = EHLParams(lam=3.0 * math.pi ** 2 / (8.0 * M ** 2), A=A, z=z, php0=2.0, c1=0.3,
                    compressible=compressible, x_in=-4.5, x_out=1.5)
    fm = multigrid.FlatMultigrid(prm, 3, 32, load_mode=1, switch=0.3, omega_gs=0.6,
                                 omega_j=0.5, c_h0=0.1, stick=10.0)
    fm.hertz_start(0.15)
    fm.iterate(max_cycles=4, min_cycles=4, tol_pressure=0.0, tol_load=0.0, tol_residual=0.0,
               stall_window=10 ** 6)
    S = fm.state()
    t = fm.top
    o, n = int(fm.iarr[0, t]), int(fm.iarr[1, t])
    P = fm.P
    rho, eps, dle, drho, _, wrk = fm.work[:6]

    def resid():
        fm.update_film(t)
        mgkernels._coef(t, P, fm.H, rho, eps, dle, drho, fm.iarr, fm.prmv)
        mgkernels._residual(t, P, fm.H, fm.f, rho, eps, wrk, fm.iarr, fm.dx, True, 0.0,
                            False)
        return wrk[o:o + n].copy()

    r0 = resid()
    kmax, big = coarse_newton._block_scaled_residual(t, S, 1, n - 1)
    assert kmax > 0 and big > 0.0
    act = np.array([k for k in range(max(1, kmax - 6), min(n - 1, kmax + 7))
                    if P[o + k] > 0 or P[o + k - 1] > 0 or P[o + k + 1] > 0], dtype=np.int64)
    J, b = coarse_newton._coarse_jacobian(S, act, act.size, False, t)
    assert np.array_equal(b, -r0[act])
    Jfd = np.zeros_like(J)
    step = 1e-7
    for c, k in enumerate(act):
        # a cavitated node (P = 0) can only rise: forward difference there (a
        # central one straddles the kink of max(P, 0) in the coefficients)
        lo = 0.0 if P[o + k] <= 0.0 else step
        P[o + k] += step
        rp = resid()
        P[o + k] -= step + lo
        rm = resid()
        P[o + k] += lo
        Jfd[:, c] = (rp[act] - rm[act]) / (step + lo)
    assert np.max(np.abs(J - Jfd)) < 1e-5 * np.max(np.abs(Jfd))


@pytest.mark.parametrize("M,L", [(20.0, 10.0), (100.0, 10.0)])
def test_speed_path_reaches_the_same_converged_film(M, L):
    # The speed path (multigrid.SPEED_SETTING: F-cycles, Newton on the coarsest
    # grid) against the default path, both converged far below the default
    # tolerances on 1024 intervals (Roelands + Dowson-Higginson).  References:
    # the default path's H_c and H_min (1e-6 relative) and the discretised
    # equations re-evaluated in numpy with a dense deformation sum (as the
    # other Roelands tests: film 1e-9, load 1e-5, scaled residual 1e-5).
    tight = dict(tol_pressure=1e-8, tol_load=1e-9, tol_residual=1e-9, max_cycles=200)
    fast = solve_line_contact(M=M, L=L, n_nodes=1025, **multigrid.SPEED_SETTING, **tight)
    ref = solve_line_contact(M=M, L=L, n_nodes=1025, **tight)
    assert fast.converged and ref.converged
    assert abs(fast.H_central_moes / ref.H_central_moes - 1.0) < 1e-6
    assert abs(fast.H_min_moes / ref.H_min_moes - 1.0) < 1e-6
    gap_spread, load_err, scaled = discrete_equations_check(fast, "roelands", True)
    assert gap_spread < 1e-9 and load_err < 1e-5 and scaled < 1e-5


@pytest.mark.parametrize("M,L", [(20.0, 10.0), (100.0, 10.0)])
def test_speed_path_stops_inside_the_discretisation_error(M, L):
    # The speed path stopped at multigrid.DISC_TOLERANCES leaves an algebraic error
    # of H_c (against the same grid converged to pressure change 1e-8) below 0.3
    # of the discretisation error.  Reference: Richardson's estimate of the
    # discretisation error from the converged 512- and 1024-interval solutions
    # (second order: |H(1024) - H(512)| / 3).  Measured: 0.01-0.1 of it.
    tight = dict(tol_pressure=1e-8, tol_load=1e-9, tol_residual=1e-9, max_cycles=200)
    h = {n: solve_line_contact(M=M, L=L, n_nodes=n + 1, **tight).H_central_moes
         for n in (512, 1024)}
    disc = abs(h[1024] - h[512]) / 3.0 / h[1024]
    r = solve_line_contact(M=M, L=L, n_nodes=1025, **multigrid.SPEED_SETTING,
                           **multigrid.DISC_TOLERANCES)
    assert r.converged and r.iterations <= 6
    assert abs(r.H_central_moes / h[1024] - 1.0) < 0.3 * disc


@pytest.mark.parametrize("M", [20.0, 100.0])
def test_default_solve_takes_the_fast_path_to_the_discrete_solution(M):
    # The default 1025-node solve (Roelands + Dowson-Higginson, L = 10) converges on the fast
    # path (F-cycles, Newton on the coarsest grid, full-multigrid start; docs/ehl.md) without
    # any option, and stops at its estimated discretisation error.  References: the
    # discretised equations re-evaluated in numpy with a dense deformation sum (as the other
    # tests: film 1e-9, load 1e-5, scaled residual 1e-5; the load error also below the default
    # load tolerance 1e-6 of the problem statement), and the films of the same equations
    # solved to tolerances 1000x tighter (W-cycles, no fast path since options are given) on
    # 1024 and 512 intervals: the central and minimum film of the default solve within a
    # tenth of the discretisation error of the 1024-interval grid, estimated by Richardson
    # (second order) from the two (measured: 9.2e-4 / 8.4e-4 at M = 20, 1.1e-2 / 1.2e-2 at
    # M = 100; the algebraic error left 0.005 / 0.04 and 0.01 / 0.013 of it).
    r = solve_line_contact(M=M, L=10.0, n_nodes=1025)
    assert r.residuals.get("fast_path") == [1.0]
    assert "stopped_at_discretisation" in r.residuals
    assert r.residuals["settings"]["switch"] == 0.3 and "gamma" not in r.residuals["settings"]
    gap_spread, load_err, scaled = discrete_equations_check(r)
    assert gap_spread < 1e-9 and load_err < 1e-5 and scaled < 1e-5
    assert abs(r.load_N_per_m / r.inputs["w_N_per_m"] - 1.0) < 1e-6
    tight = {n: solve_line_contact(M=M, L=10.0, n_nodes=n + 1, tol_pressure=1e-8,
                                   tol_load=1e-9, tol_residual=1e-9, max_cycles=300,
                                   switch=0.3, nu1=2, nu2=1, omega_gs=0.6, omega_j=0.5,
                                   load_mode=1, c_h0=0.1, stick=10.0) for n in (512, 1024)}
    assert "fast_path" not in tight[1024].residuals
    for key in ("H_central_moes", "H_min_moes"):
        h1, h2 = getattr(tight[1024], key), getattr(tight[512], key)
        disc = abs(h1 - h2) / 3.0 / h1
        assert abs(getattr(r, key) / h1 - 1.0) < 0.1 * disc


@pytest.mark.parametrize("M,L", [(1000.0, 15.0), (600.0, 18.0), (1000.0, 20.0)])
def test_piezoviscous_corner_converges_on_the_first_pairs_of_its_plan(M, L):
    # Barus, incompressible: the piezoviscous coarsest-grid rule is capped there, and the
    # (grid, setting) pairs of PIEZO_CORNER_PLAN run before the normal order (docs/ehl.md);
    # the first two points stalled on 6 resp. 3 settings before converging in the normal
    # order.
    # References: the discretised equations re-evaluated in numpy (as above) and Moes' fit
    # at the tolerance of the range test in tests/unit/ehl/test_ehl.py (6 %; measured -1.3 %, +0.6 %).
    from gearfmu.ehl.fits import moes_central_film
    r = solve_line_contact(M=M, L=L, viscosity="barus", compressible=False)
    assert r.residuals.get("corner_plan_pair") is not None
    if M == 1000.0 and L == 20.0:
        # converges with setting 9 (Venner & Lubrecht's listing factors 0.4/0.2, F-cycles,
        # coarsest-grid Newton), the second pair; without it the plan ran through three
        # failing pairs first
        assert r.residuals["corner_plan_pair"] == [0.0, 9.0]
    gap_spread, load_err, scaled = discrete_equations_check(r, "barus", compressible=False)
    assert gap_spread < 1e-9 and load_err < 1e-5 and scaled < 1e-5
    assert abs(r.H_central_moes / moes_central_film(M, L) - 1.0) < 0.06


def test_spike_step_film_update_matches_the_direct_deformation_sum():
    # The spike Newton step updates the film by kernel columns of the changed nodes
    # (coarse_newton._add_deformation) instead of an FFT.  Reference: the film
    # H0 + X^2/2 + V(P) with V the O(N^2) direct sum (deformation.deformation_direct)
    # of the changed pressure.
    from gearfmu.ehl.deformation import deformation_direct
    prm = EHLParams(lam=0.17, A=7.5, z=0.52, php0=4.7, c1=0.64, compressible=True,
                    x_in=-4.5, x_out=1.5)
    fm = multigrid.FlatMultigrid(prm, 5, 32)            # finest level 513 nodes
    fm.hertz_start(0.78)
    t = fm.top
    S = fm.state()
    o = int(fm.iarr[0, t])
    rng = np.random.default_rng(11)
    for k in (1, 7, 200, 256, 500, 511):
        dp = float(rng.uniform(-0.05, 0.05))
        fm.P[o + k] += dp
        coarse_newton._add_deformation(t, S, k, dp)
    P = fm.level_P()
    ref = fm.H0[t] + 0.5 * fm.X[t] ** 2 + deformation_direct(P.copy(), fm.K[o:o + P.size])
    assert np.max(np.abs(fm.level_H() - ref)) < 1e-12 * np.max(np.abs(ref))


def test_fmg_prolongation_is_exact_for_cubic_pressures():
    # The compiled full-multigrid prolongation (mgkernels._fmg_prolong) interpolates
    # with the 4-point cubic rule (Venner & Lubrecht 2000).  Reference: a cubic
    # polynomial, which that rule reproduces exactly at every fine node with two
    # coarse nodes on each side; linear rule next to the ends; P = 0 at the ends.
    prm = EHLParams(lam=0.17, A=7.5, z=0.52, php0=4.7, c1=0.64, compressible=True,
                    x_in=-4.5, x_out=1.5)
    fm = multigrid.FlatMultigrid(prm, 3, 32)
    cubic = lambda x: 3.0 + 0.2 * x + 0.1 * x ** 2 + 0.02 * x ** 3     # > 0 on the grid
    Xc, Xf = fm.X[1], fm.X[2]
    fm.P[fm._sl(1)] = cubic(Xc)
    fm.H0[1] = 0.37
    fm._prolong_solution(2)
    Pf = fm.level_P(2)
    assert Pf[0] == 0.0 and Pf[-1] == 0.0
    assert np.max(np.abs(Pf[2:-2] - cubic(Xf[2:-2]))) < 1e-12
    lin = 0.5 * (cubic(Xc[:2]).sum()), 0.5 * (cubic(Xc[-2:]).sum())
    assert abs(Pf[1] - lin[0]) < 1e-12 and abs(Pf[-2] - lin[1]) < 1e-12
    assert fm.H0[2] == 0.37
