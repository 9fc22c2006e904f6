"""Tests of the line-contact EHL solver gearfmu.ehl (seed 000 eq 2-7).

Every reference below comes from outside this code base:
* the exact Hertzian deformation identity (Johnson, Contact Mechanics, 1985, ch. 5):
  int_{-1}^{1} ln|x - t| sqrt(1 - t^2) dt = (pi/2)(x^2 - 1/2 - ln 2), |x| <= 1;
* Moes' (1992) central film fit (as quoted by Venner & Lubrecht 2000), whose
  groups M, L contain only alpha: it describes the Barus viscosity law and an
  incompressible lubricant, so the comparison uses exactly those laws (the fit's own
  accuracy, about 5 %, against a closed form and an independent discretisation:
  tests/unit/ehl/test_ehl_moes.py);
* Dowson & Higginson's minimum film formula (compressible, exponential
  viscosity -- their assumptions), a looser fit to 1960s solutions;
* hand calculations of the Roelands and Dowson-Higginson laws;
* Richardson's observed order of convergence (grid refinement).
"""
import math

import numpy as np
import pytest

from gearfmu.ehl import (EHLConvergenceError, EHLInputError, FilmCollapseError,
                         solve_line_contact)
from gearfmu.ehl.deformation import DeformationOperator, deformation_direct
from gearfmu.ehl.fits import dowson_higginson_min_film, moes_central_film
from gearfmu.ehl.lubricant import (dowson_higginson_density_kg_m3, roelands_viscosity_Pas,
                                   roelands_z)

from support.ehl_checks import discrete_equations_check

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow


# --------------------------------------------------------------------------- kernel
@pytest.mark.parametrize("n", [257, 1025, 4097])
def test_deformation_of_hertz_pressure_is_exact_parabola(n):
    # Reference: exact identity above => V(X) = -(1/pi)(pi/2)(X^2 - 1/2 - ln 2)
    # for P = sqrt(1 - X^2), so H = X^2/2 + V is flat inside |X| <= 1.
    # Measured max error: 4.6e-5 (257), 5.9e-6 (1025), 6.6e-7 (4097) -- order 1.5
    # (the sqrt edge of the Hertz pressure limits it).
    X = np.linspace(-4.5, 1.5, n)
    dX = X[1] - X[0]
    P = np.sqrt(np.clip(1.0 - X ** 2, 0.0, None))
    op = DeformationOperator(n, dX)
    V = op(P)
    exact = -0.5 * (X ** 2 - 0.5 - math.log(2.0))
    inside = np.abs(X) <= 1.0
    err = np.abs(V - exact)[inside].max()
    assert err < 3.0 * dX ** 1.5
    gap = 0.5 * X[inside] ** 2 + V[inside]
    assert np.ptp(gap) < 6.0 * dX ** 1.5          # flat gap inside the contact
    # FFT evaluation equals the O(N^2) sum to round-off
    np.testing.assert_allclose(V, deformation_direct(P, op.K), rtol=0, atol=1e-12)


# --------------------------------------------------------------------------- lubricant
def test_roelands_and_dowson_higginson_hand_values():
    eta0, alpha = 0.04, 2.2e-8
    # z = alpha p0 / (ln eta0 + 9.67) = 2.2e-8 * 1.96e8 / (ln 0.04 + 9.67)
    z_hand = 2.2e-8 * 1.96e8 / (math.log(0.04) + 9.67)
    assert roelands_z(eta0, alpha) == pytest.approx(z_hand, rel=1e-12)
    assert roelands_viscosity_Pas(0.0, eta0, alpha) == pytest.approx(eta0, rel=1e-14)
    # initial slope d ln(eta)/dp = alpha (the reason for the choice of z)
    dp = 1.0e3
    slope = math.log(roelands_viscosity_Pas(dp, eta0, alpha) / eta0) / dp
    assert slope == pytest.approx(alpha, rel=1e-4)
    # 1 GPa by hand: eta0 exp{(ln eta0 + 9.67)[(1 + 1e9/1.96e8)^z - 1]}
    hand = eta0 * math.exp((math.log(eta0) + 9.67) * ((1 + 1e9 / 1.96e8) ** z_hand - 1))
    assert roelands_viscosity_Pas(1e9, eta0, alpha) == pytest.approx(hand, rel=1e-12)
    # Dowson-Higginson: rho/rho0 = (0.59e9 + 1.34 p)/(0.59e9 + p): 1.17 at 0.59 GPa
    assert dowson_higginson_density_kg_m3(0.59e9) == pytest.approx(1.17, rel=1e-12)
    assert dowson_higginson_density_kg_m3(1e15) == pytest.approx(1.34, rel=1e-5)


# --------------------------------------------------------------------------- Moes
# (M, L, measured relative deviation from Moes' fit) -- see docs/ehl.md
MOES_POINTS = [
    (5.0, 0.0, +0.037),
    (20.0, 0.0, -0.017),
    (10.0, 10.0, +0.032),
    (100.0, 10.0, +0.007),
    (200.0, 10.0, +0.003),
    (500.0, 5.0, -0.025),
    (1000.0, 2.0, -0.042),
    (5.0, 20.0, +0.032),
    (20.0, 20.0, +0.051),
]


@pytest.mark.parametrize("M,L,measured", MOES_POINTS)
def test_smooth_central_film_against_moes(M, L, measured):
    # Reference: Moes' fit.  Tolerance 6 %: the largest deviation measured
    # over the points above is 5.1 % (M = 20, L = 20); the mean |deviation| is
    # 2.7 %.  The fit itself is off by up to about 5 % from converged solutions
    # (closed form, independent discretisation: tests/unit/ehl/test_ehl_moes.py), which
    # bounds what the comparison can show; deviations below 3 % at 6 of 9.
    r = solve_line_contact(M=M, L=L, viscosity="barus", compressible=False)
    ref = moes_central_film(M, L)
    dev = r.H_central_moes / ref - 1.0
    assert r.converged
    assert abs(dev) < 0.06
    assert dev == pytest.approx(measured, abs=0.01)   # documents the measured value
    # Moes scaling of the film: H = (h/R)(2U)^(-1/2), by definition
    U = r.inputs["eta0_Pas"] * r.inputs["u_m_s"] / (r.inputs["E_Pa"] * r.inputs["R_m"])
    assert r.h_central_m == pytest.approx(r.H_central_moes * r.inputs["R_m"] * math.sqrt(2 * U),
                                          rel=1e-12)


# Every (M, L) of the grid M = 5..1000 x L = 0..20 (docs/ehl.md, "Convergence over
# (M, L)"): all 48 converge since the coarse-grid retry ((500, 20) was the last
# failure: every setting stalled on the default 128-interval coarsest grid; it
# converges on the same 2048-interval finest grid with a 512-interval coarsest grid).
MOES_RANGE = [(M, L) for M in (5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0)
              for L in (0.0, 2.0, 5.0, 10.0, 15.0, 20.0)]


def test_smooth_central_film_against_moes_over_the_M_L_range():
    # Reference: Moes' fit (Barus, incompressible -- its assumptions) over
    # M = 5..1000, L = 0..20 on the default grids.  Tolerances: every point
    # within 6 % and the mean |deviation| below 3 % (the aim).
    # Measured: max 5.5 % (M = 1000, L = 0: the fit's isoviscous-elastic asymptote
    # sits about 5 % above grid-converged solutions, tests/unit/ehl/test_ehl_moes.py; the
    # default grid adds 0.6 % there),
    # mean 2.4 % over these 48 points; the last point added, (500, 20), is
    # -0.45 % (its neighbours (500, 15) +0.5 %, (1000, 20) -0.3 %, (200, 20) +2.3 %).
    devs = []
    for M, L in MOES_RANGE:
        r = solve_line_contact(M=M, L=L, viscosity="barus", compressible=False)
        assert r.converged
        devs.append(r.H_central_moes / moes_central_film(M, L) - 1.0)
        if (M, L) == (50.0, 15.0):
            # converges on the default 1024 intervals (no refined retry grid)
            assert r.X.size - 1 == 1024
    devs = np.abs(np.array(devs))
    worst = MOES_RANGE[int(np.argmax(devs))]
    assert devs.max() < 0.06, f"worst {worst}: {devs.max():.3f}"
    assert devs.mean() < 0.03


@pytest.mark.parametrize("M,L,viscosity,n_coarse", [(500.0, 20.0, "barus", 512),
                                                    (50.0, 20.0, "roelands", 128)])
def test_last_M_L_failures_converge_on_a_finer_coarsest_grid(M, L, viscosity, n_coarse):
    # Barus (500, 20) and Roelands (50, 20) stalled on every relaxation setting on
    # the film-rule hierarchy (coarsest grid 128 resp. 32 intervals): the residual
    # left is smooth over the Hertz zone (docs/ehl.md "Coarse-grid retry").  They
    # converge on the same finest grid with a finer coarsest grid (Roelands (50, 20)
    # directly on the default one of the piezoviscous rule of grids.choose_grid,
    # Barus (500, 20) on the coarse-grid retry).  References:
    # the discretised equations re-evaluated in numpy (dense deformation sum) and,
    # for Barus, Moes' fit at the tolerance of the range test (6 %; measured
    # -0.45 %); Roelands + Dowson-Higginson sits below the fit (measured -20.2 %,
    # its neighbours (50, 15) -19.5 %, (100, 20) -22.3 %, docs/ehl.md).
    comp = viscosity == "roelands"
    r = solve_line_contact(M=M, L=L, viscosity=viscosity, compressible=comp)
    assert r.converged and (r.X.size - 1) // 2 ** (r.grid_levels - 1) == n_coarse
    gap_spread, load_err, scaled = discrete_equations_check(r, viscosity, compressible=comp)
    assert gap_spread < 1e-9 and load_err < 1e-5 and scaled < 1e-5
    dev = r.H_central_moes / moes_central_film(M, L) - 1.0
    if comp:
        assert -0.30 < dev < 0.05
    else:
        assert abs(dev) < 0.06


@pytest.mark.parametrize("M,L", [(5.5, 22.0), (5.55, 22.4)])
def test_stalled_smooth_film_converges_by_the_coupled_newton(M, L):
    # Barus, L just beyond Moes' range at light load (the gear oil's L, Barus law): all ten
    # relaxation settings stalled at pressure changes of 1e-2 on every grid tried (13 of 77
    # points of M 5.5-6, L 22-22.6 failed; their neighbours converge on a fragile path).  The
    # coupled Newton of the finest grid (film_newton.py) from the stalled states converges them
    # (and the default grid's (10, 40) of the failing-fast test, far beyond the range).
    # References: the discretised equations re-evaluated in numpy (dense deformation sum), and
    # on 512 intervals the independent discretisation of benchmarks/ehl_reference.py (measured
    # solver - reference -0.065 % at (5.5, 22)).
    import importlib.util
    import pathlib
    r = solve_line_contact(M=M, L=L, viscosity="barus", compressible=False)
    assert r.converged and r.residuals.get("coupled_newton_steps")
    gap_spread, load_err, scaled = discrete_equations_check(r, "barus", compressible=False)
    assert gap_spread < 1e-9 and load_err < 1e-5 and scaled < 1e-5
    r2 = solve_line_contact(M=M, L=L, viscosity="barus", compressible=False, n_nodes=513)
    path = pathlib.Path(__file__).resolve().parents[3] / "benchmarks" / "ehl_reference.py"
    spec = importlib.util.spec_from_file_location("ehl_reference", path)
    ref = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(ref)
    H_ref, _, ok, _ = ref.reference_central_film(M, L, 512, r2.X, r2.P, r2.H_central_moes)
    assert ok and r2.H_central_moes == pytest.approx(H_ref, rel=2e-3)
    assert r.H_central_moes == pytest.approx(r2.H_central_moes, rel=5e-3)   # 256 vs 512 intervals


def test_minimum_film_against_dowson_higginson():
    # Reference: Dowson & Higginson h_min/R = 2.65 U^0.70 G^0.54 W^-0.13 with
    # their assumptions (compressible, exponential viscosity), steel/mineral
    # oil in their validity range (G = 5000, W ~ 8e-5, U ~ 2e-11).  Looser
    # tolerance (10 %) because the formula is a power-law fit to early coarse
    # solutions; measured: +2.2 %.
    E, R, w, u, eta0, alpha = 2.26e11, 0.02, 3.58e5, 9.66, 0.01, 2.2e-8
    r = solve_line_contact(R_m=R, E_Pa=E, w_N_per_m=w, u_m_s=u, eta0_Pas=eta0,
                           alpha_Pa_inv=alpha, viscosity="barus", compressible=True)
    W, U, G = w / (E * R), eta0 * u / (E * R), alpha * E
    ref = dowson_higginson_min_film(W, U, G) * R
    assert r.h_min_m == pytest.approx(ref, rel=0.10)
    # the minimum film sits in the outlet constriction, downstream of the centre
    assert 0.0 < r.x_min_m < 1.5 * r.b_m


# --------------------------------------------------------------------------- grid
def test_grid_convergence_observed_order():
    # Reference: Richardson -- with a second-order scheme the central film
    # converges like dX^2.  Fixed coarse grid, three nested fine grids.
    # Measured at M = 20, L = 5: order ~2, last change < 1 %.
    H = []
    for n in (257, 513, 1025):
        r = solve_line_contact(M=20.0, L=5.0, viscosity="barus", compressible=False,
                               n_nodes=n, n_coarse=64)
        H.append(r.H_central_moes)
    d1, d2 = abs(H[1] - H[0]), abs(H[2] - H[1])
    order = math.log2(d1 / d2)
    assert 1.5 < order < 2.6
    assert d2 / H[2] < 0.01


def test_dimensional_and_moes_inputs_agree():
    # Similarity (Moes 1992): with Barus viscosity and no compressibility the
    # film in Moes' scaling depends on M and L only.
    E, R, w, u, eta0, alpha = 2.3e11, 0.015, 2.0e5, 3.0, 0.05, 1.8e-8
    r1 = solve_line_contact(R_m=R, E_Pa=E, w_N_per_m=w, u_m_s=u, eta0_Pas=eta0,
                            alpha_Pa_inv=alpha, viscosity="barus", compressible=False)
    W, U = w / (E * R), eta0 * u / (E * R)
    assert r1.M == pytest.approx(W / math.sqrt(2 * U), rel=1e-12)
    assert r1.L == pytest.approx(alpha * E * (2 * U) ** 0.25, rel=1e-12)
    r2 = solve_line_contact(M=r1.M, L=r1.L, viscosity="barus", compressible=False)
    assert r2.H_central_moes == pytest.approx(r1.H_central_moes, rel=1e-5)
    # Hertz half width and load: b = sqrt(8 w R / (pi E')), integral p dx = w
    assert r1.b_m == pytest.approx(math.sqrt(8 * w * R / (math.pi * E)), rel=1e-12)
    assert r1.load_N_per_m == pytest.approx(w, rel=1e-6)


# --------------------------------------------------------------------------- errors
def test_bad_inputs_name_the_field():
    with pytest.raises(EHLInputError, match="R_m"):
        solve_line_contact(R_m=-1.0, E_Pa=2e11, w_N_per_m=1e5, u_m_s=1.0, eta0_Pas=0.04,
                           alpha_Pa_inv=2e-8)
    with pytest.raises(EHLInputError, match="M and L"):
        solve_line_contact(M=10.0)
    with pytest.raises(EHLInputError, match="eta0_Pas"):
        solve_line_contact(R_m=0.01, E_Pa=2e11, w_N_per_m=1e5, u_m_s=1.0, eta0_Pas=1e-6,
                           alpha_Pa_inv=2e-8)
    with pytest.raises(EHLInputError, match="n_nodes"):
        solve_line_contact(M=10.0, L=5.0, n_nodes=1000)


def test_non_convergence_names_the_residual():
    with pytest.raises(EHLConvergenceError) as ei:
        solve_line_contact(M=100.0, L=10.0, max_cycles=2, switch=3.0)
    assert ei.value.residual_name in ("pressure_change", "load_balance", "reynolds_residual")
    assert ei.value.residual_name in str(ei.value)
    assert ei.value.value > 0


def test_film_collapse_reports_position_and_film_parameter():
    # A 1.5 um waviness (wavelength 0.1 mm) in a contact whose smooth film is
    # ~0.3 um: the full film cannot survive -> FilmCollapseError with x, lambda.
    def rough(x):
        return 1.5e-6 * np.cos(2 * np.pi * x / 1e-4)
    with pytest.raises(FilmCollapseError) as ei:
        solve_line_contact(R_m=0.02, E_Pa=2.26e11, w_N_per_m=3.0e5, u_m_s=2.0, eta0_Pas=0.01,
                           alpha_Pa_inv=2.2e-8, roughness_m=rough, max_cycles=30)
    e = ei.value
    assert "lambda" in str(e) and "x =" in str(e)
    assert e.film_parameter <= 0.0
    assert math.isfinite(e.x_m)


def test_small_roughness_converges_and_zero_roughness_is_smooth():
    kw = dict(R_m=0.02, E_Pa=2.26e11, w_N_per_m=3.0e5, u_m_s=5.0, eta0_Pas=0.04,
              alpha_Pa_inv=2.2e-8)
    r0 = solve_line_contact(**kw)
    rz = solve_line_contact(**kw, roughness_m=lambda x: 0.0 * x)
    # same problem, different iteration path: equal within the convergence tolerance
    assert rz.h_central_m == pytest.approx(r0.h_central_m, rel=1e-4)
    rr = solve_line_contact(**kw, roughness_m=lambda x: 0.02e-6 * np.cos(2 * np.pi * x / 1e-4))
    assert rr.converged and rr.h_min_m > 0
    assert np.ptp(rr.h_m[np.abs(rr.X) < 0.5]) > np.ptp(r0.h_m[np.abs(r0.X) < 0.5])


def test_hopeless_stall_fails_fast_and_reports_the_best_residual():
    # Failing fast (docs/ehl.md "Failing fast"), Barus outside Moes' range.
    # Reference: the two rules' definitions (counts of grids tried, thresholds),
    # not timings.
    from gearfmu.ehl.grids import (RETRY_BELOW_RESIDUAL, RETRY_CLOSE_RESIDUAL,
                                   RETRY_PROGRESS_FACTOR)
    from gearfmu.ehl.solver import RELAXATION_SETTINGS, retry_made_progress
    # The settings' path alone (newton_after_cycles=0: no coupled Newton as the last resort,
    # which converges both cases below, test_stalled_smooth_film_converges_by_the_coupled_newton).
    # M = 10, L = 40: no setting on the default grid stalls below 1e-3 (best
    # measured 2.1e-2) -> no retry grid (rule 1); every setting was tried there
    with pytest.raises(EHLConvergenceError) as ei:
        solve_line_contact(M=10.0, L=40.0, viscosity="barus", compressible=False, newton_after_cycles=0)
    e = ei.value
    assert len({a[:2] for a in e.attempts}) == 1
    assert len(e.attempts) == len(RELAXATION_SETTINGS)
    assert e.best_residual == min(a[3] for a in e.attempts) >= RETRY_BELOW_RESIDUAL
    assert any("retry grids not tried" in x for x in e.skipped)
    assert "best stalled scaled residual" in str(e) and e.residual_name in str(e)
    # M = 200, L = 40: the default grid reaches 8e-4 < 1e-3 -> retry grids are
    # tried (rule 1); a retry grid after the first only when its predecessor made
    # progress (rule 2)
    with pytest.raises(EHLConvergenceError) as ei:
        solve_line_contact(M=200.0, L=40.0, viscosity="barus", compressible=False, newton_after_cycles=0)
    e = ei.value
    grids = []
    for a in e.attempts:
        if a[:2] not in grids:
            grids.append(a[:2])
    assert len(grids) >= 2 and grids[1][1] == 2 * grids[0][1]
    best = [min(a[3] for a in e.attempts if a[:2] == g) for g in grids]
    assert best[0] < RETRY_BELOW_RESIDUAL
    for k in range(2, len(grids)):
        assert retry_made_progress(best[:k])
    # Rule 2 itself, on residual histories (reference: the rule's definition, factor 2 and
    # the 1e-4 threshold): no progress and not close -> stop; halved, or below 1e-4 -> go on.
    assert RETRY_PROGRESS_FACTOR == 2.0 and RETRY_CLOSE_RESIDUAL == 1e-4
    assert not retry_made_progress([8e-4, 5e-4])
    assert not retry_made_progress([8e-4, 2e-4, 1.5e-4])
    assert retry_made_progress([8e-4, 4e-4])
    assert retry_made_progress([8e-4, 9e-4, 9e-5])


def test_convergence_error_poses_the_failed_problem_again():
    # A failure seen in a long run must be repeatable on its own: the message gives M and L in
    # full precision (rounded to 4 digits it names a neighbouring problem, which may converge:
    # Barus L = 22.0 fails at M = 5.5 and converges at M = 5.75) and the error carries
    # ``problem``, the keyword arguments that pose the same problem again.  Reference: the
    # solver's determinism -- the same problem stalls with the same residual history.
    M, L, kw = 20.000000001, 10.0, dict(max_cycles=2, tol_residual=1e-12)
    with pytest.raises(EHLConvergenceError) as e1:
        solve_line_contact(M=M, L=L, viscosity="barus", compressible=False, n_nodes=513, **kw)
    assert f"M={M!r}, L={L!r}, barus, incompressible" in str(e1.value)
    assert e1.value.problem == dict(M=M, L=L, rho0_kg_m3=870.0, viscosity="barus", compressible=False,
                                    x_in=-4.5, x_out=1.5, n_nodes=513)
    with pytest.raises(EHLConvergenceError) as e2:
        solve_line_contact(**e1.value.problem, **kw)
    assert e2.value.history == e1.value.history
    dim = dict(R_m=0.02, E_Pa=2.26e11, w_N_per_m=2e5, u_m_s=5.0, eta0_Pas=0.04, alpha_Pa_inv=2.2e-8)
    with pytest.raises(EHLConvergenceError) as e3:
        solve_line_contact(**dim, **kw)
    assert e3.value.problem == dict(dim, rho0_kg_m3=870.0, viscosity="roelands", compressible=True,
                                    x_in=-4.5, x_out=1.5)


# --------------------------------------------------------------------------- film stiffness
def test_bulk_modulus_is_tait_tangent_modulus_with_right_limits():
    # Reference: isothermal Tait equation V/V0 = 1 - ln(1 + p (1+B0')/B0)/(1+B0')
    # (Bair 2007); its tangent modulus -V dp/dV is seed 000 eq 9.  Limits:
    # B(0) = B0 and dB/dp(0) = B0' (definition of B0').
    from gearfmu.ehl.film_stiffness import bulk_modulus_Pa
    B0, B1 = 1.9e9, 10.5
    V = lambda p: 1.0 - math.log(1.0 + p * (1 + B1) / B0) / (1 + B1)
    for p in (0.0, 0.2e9, 0.5e9, 1.5e9):
        dp = 1e3
        tangent = -V(p) * 2 * dp / (V(p + dp) - V(p - dp)) if p > 0 else None
        if tangent is not None:
            assert float(bulk_modulus_Pa(p, B0, B1)) == pytest.approx(tangent, rel=1e-6)
    assert float(bulk_modulus_Pa(0.0, B0, B1)) == pytest.approx(B0, rel=1e-15)
    slope = (float(bulk_modulus_Pa(1e3, B0, B1)) - B0) / 1e3
    assert slope == pytest.approx(B1, rel=1e-4)


def test_film_stiffness_limits_and_trend_with_load():
    from gearfmu.ehl.film_stiffness import (film_stiffness_N_per_m, slice_film_stiffness_N_per_m,
                                            total_film_stiffness_N_per_m, B0_DEFAULT_PA)
    # eq 8 limits: p_m -> 0 gives A B0 / h; k ~ 1/h.
    k1 = film_stiffness_N_per_m(1e-6, 1e-6, 0.0)
    assert k1 == pytest.approx(1e-6 * B0_DEFAULT_PA / 1e-6, rel=1e-15)
    assert film_stiffness_N_per_m(1e-6, 0.5e-6, 0.0) == pytest.approx(2 * k1, rel=1e-15)
    # eq 10: slices in parallel add.
    assert total_film_stiffness_N_per_m([1.0, 2.0, 3.5]) == 6.5
    # More load -> thinner film and higher pressure -> stiffer film (seed 000
    # Fig. 15 trend: film stiffness rises with torque).
    kw = dict(R_m=0.02, E_Pa=2.26e11, u_m_s=5.0, eta0_Pas=0.04, alpha_Pa_inv=2.2e-8)
    ks = [slice_film_stiffness_N_per_m(solve_line_contact(w_N_per_m=w, **kw), 1e-3)
          for w in (1.5e5, 4.5e5)]
    assert ks[1] > ks[0]
    # Higher entrainment speed -> thicker film -> softer film (seed 000 Fig. 14).
    kw.pop("u_m_s")
    kv = [slice_film_stiffness_N_per_m(solve_line_contact(w_N_per_m=3e5, u_m_s=u, **kw), 1e-3)
          for u in (2.0, 10.0)]
    assert kv[1] < kv[0]


# --------------------------------------------------------------------------- compiled solver
# Roelands + Dowson-Higginson (the model used for gears) over a grid of (M, L),
# including the cases the previous driver could not solve (M = 1000, L = 10;
# M = 7.5, L = 24.9 from the thermal teammate; seed 000's pitch point M = 6.1,
# L = 18).  Measured cycles/attempt are in docs/ehl.md.
ROELANDS_GRID = [(5.0, 0.0), (5.0, 10.0), (10.0, 20.0), (20.0, 5.0), (20.0, 25.0),
                 (50.0, 10.0), (100.0, 20.0), (7.5, 24.9), (6.1, 18.0), (1000.0, 10.0)]


@pytest.mark.parametrize("M,L", ROELANDS_GRID)
def test_roelands_compressible_converges_and_satisfies_discrete_equations(M, L):
    # Reference: the discretised equations themselves, re-evaluated here in
    # numpy with a dense O(N^2) deformation sum (independent of the solver's
    # FFT and relaxation code).  Tolerances: film-equation consistency 1e-9
    # (round-off of the FFT), load 1e-6 and scaled residual 1e-5 (the
    # solver's stopping tolerances are 1e-6 each).
    r = solve_line_contact(M=M, L=L)
    assert r.converged
    gap_spread, load_err, scaled = discrete_equations_check(r)
    assert gap_spread < 1e-9
    assert load_err < 1e-5
    assert scaled < 1e-5
    # compressible + Roelands gives a thinner film than Moes' Barus/incompressible
    # fit for L > 0 (docs/ehl.md: about -10 % to -27 % over this grid); never thicker
    # by more than the fit's few per cent.
    assert r.H_central_moes < 1.05 * moes_central_film(M, L)


def test_warm_start_from_neighbouring_solution():
    # Reference: the cold solve of the same problem.  A warm start from the
    # neighbouring load (5 % lower) reaches the same film within the
    # convergence tolerance and needs no more W-cycles.  Both stop at the same
    # (the default) tolerances, given explicitly: without them the cold solve may
    # stop at its estimated discretisation error instead (docs/ehl.md), which a
    # warm start can use only when ``initial`` carries such an estimate.
    kw = dict(R_m=0.02, E_Pa=2.26e11, u_m_s=5.0, eta0_Pas=0.04, alpha_Pa_inv=2.2e-8,
              tol_pressure=1e-5, tol_load=1e-6, tol_residual=1e-6)
    prev = solve_line_contact(w_N_per_m=2.0e5, **kw)
    cold = solve_line_contact(w_N_per_m=2.1e5, **kw)
    warm = solve_line_contact(w_N_per_m=2.1e5, initial=prev, **kw)
    assert warm.h_central_m == pytest.approx(cold.h_central_m, rel=1e-4)
    assert warm.h_min_m == pytest.approx(cold.h_min_m, rel=1e-3)
    assert warm.iterations <= cold.iterations
    with pytest.raises(EHLInputError, match="initial"):
        solve_line_contact(w_N_per_m=2.1e5, initial="previous", **kw)


def test_roughness_band_limit_removes_only_unresolved_wavelengths():
    # Reference: closed-form cosines with a whole number of half periods over
    # the profile (so the even extension is exactly periodic): a component of
    # wavelength 64 samples passes unchanged, one of 4 samples is removed.
    from gearfmu.ehl.roughness import band_limit
    n = 513
    j = np.arange(n)
    keep = np.cos(np.pi * 16 * j / (n - 1))          # wavelength 2(n-1)/16 = 64 samples
    drop = 0.3 * np.cos(np.pi * 256 * j / (n - 1))   # wavelength 4 samples
    out = band_limit(keep + drop, 8.0)
    np.testing.assert_allclose(out, keep, atol=1e-12)
    # a solve keeps the filtered profile it used
    kw = dict(R_m=0.02, E_Pa=2.26e11, w_N_per_m=3.0e5, u_m_s=5.0, eta0_Pas=0.04,
              alpha_Pa_inv=2.2e-8, n_nodes=513)
    r = solve_line_contact(**kw, roughness_m=lambda x: 0.01e-6 * np.cos(2 * np.pi * x / 2e-6))
    # (the wave is not periodic on the grid: the cut leaves a small leak)
    assert np.max(np.abs(r.roughness_m)) < 0.01 * 0.01e-6
    with pytest.raises(EHLInputError, match="roughness_min_wavelength_dX"):
        solve_line_contact(**kw, roughness_m=lambda x: 0 * x, roughness_min_wavelength_dX=-1)


# --------------------------------------------------------------------------- speed-up pieces
@pytest.mark.parametrize("n", [3, 4, 5, 9, 17, 33, 100, 513])
def test_packed_real_fft_convolution_equals_direct_sum(n):
    # Reference: the O(N^2) Toeplitz sum (deformation_direct) on random
    # pressures, including the smallest embeddings (n = 3: period 4, a
    # complex FFT of length 2) and sizes that are not 2^k + 1.
    rng = np.random.default_rng(n)
    P = rng.random(n)
    op = DeformationOperator(n, 6.0 / (n - 1))
    np.testing.assert_allclose(op(P), deformation_direct(P, op.K), rtol=0, atol=1e-12)


def test_cycle_schedules_visit_the_coarsest_grid_as_defined():
    # Reference: the cycle definitions (Trottenberg, Oosterlee & Schueller
    # 2001, sec. 2.4): with l levels a V-cycle visits the coarsest grid once,
    # a W-cycle 2^(l-2) times (one visit from level 1), an F-cycle l - 1 times;
    # every descent from level k is matched by an ascent to k.
    from gearfmu.ehl.mgcycle import w_schedule
    for nl in (2, 3, 5, 7):
        for gamma, visits in ((1, 1), (2, 2 ** (nl - 2)), ("F", nl - 1)):
            s = w_schedule(nl, gamma)
            assert int(np.sum(s == 0)) == visits
            for k in range(1, nl):
                assert np.sum(s == k) == np.sum(s == -k)
            assert s[0] == nl - 1 and s[-1] == -(nl - 1)
    with pytest.raises(EHLInputError, match="gamma"):
        w_schedule(4, 3)


def test_f_cycle_solution_satisfies_the_discrete_equations():
    # Reference: the discretised equations re-evaluated in numpy (as above);
    # the F-cycle is a different iteration towards the same discrete solution.
    r = solve_line_contact(M=20.0, L=5.0, gamma="F", switch=0.3, nu1=2, nu2=1, omega_gs=0.6,
                           omega_j=0.5, load_mode=1, c_h0=0.1, stick=10.0)
    gap_spread, load_err, scaled = discrete_equations_check(r)
    assert gap_spread < 1e-9 and load_err < 1e-5 and scaled < 1e-5


def test_frozen_switch_result_satisfies_the_discrete_equations():
    # Barus M = 10, L = 15 (256 intervals): relaxation setting 1 stalls in a
    # switching limit cycle close to the solution and finishes with the
    # Gauss-Seidel/Jacobi switch frozen (docs/ehl.md; the default path now
    # converges this point on its fast path, so the setting is given).  Reference: the
    # discretised equations re-evaluated in numpy -- freezing the switch only
    # changes the iteration, so the result must satisfy them as tightly as any.
    from gearfmu.ehl.solver import RELAXATION_SETTINGS
    r = solve_line_contact(M=10.0, L=15.0, viscosity="barus", compressible=False,
                           **RELAXATION_SETTINGS[1])
    assert "frozen_switch_from_cycle" in r.residuals
    gap_spread, load_err, scaled = discrete_equations_check(r, "barus", compressible=False)
    assert gap_spread < 1e-9 and load_err < 1e-5 and scaled < 1e-5


def test_fmg_start_solution_satisfies_the_discrete_equations_and_is_at_discretisation_accuracy():
    # Full-multigrid start (fmg_cycles=1), Barus M = 20, L = 5.  References:
    # (1) the discretised equations re-evaluated in numpy (as above); (2) the
    # discretisation error of the central film from Richardson extrapolation of
    # the 512/1024-interval solutions (second order, measured order 2.01 in
    # test_grid_convergence_observed_order): after the FMG pass and ONE cycle on
    # the finest grid the central film must already be well within that error
    # of the converged film: measured 1.3e-4 against the estimate 1.1e-3 of the
    # 1024-interval discretisation error (ratio 0.12; bound 0.25).
    kw = dict(M=20.0, L=5.0, viscosity="barus", compressible=False)
    r = solve_line_contact(n_nodes=1025, fmg_cycles=1, **kw)
    assert r.residuals["fmg_cycles_per_level"][1:] == [1, 1, 1]
    gap_spread, load_err, scaled = discrete_equations_check(r, "barus", compressible=False)
    assert gap_spread < 1e-9 and load_err < 1e-5 and scaled < 1e-5
    h512 = solve_line_contact(n_nodes=513, **kw).H_central_moes
    # Richardson: error of the 1024-interval film = (H_1024 - H_512) / (2^2 - 1)
    disc_err = abs(h512 - r.H_central_moes) / 3.0 / r.H_central_moes
    hc = r.residuals["H_central"]
    assert abs(hc[0] / hc[-1] - 1.0) < 0.25 * disc_err
    # stop at the estimated discretisation error (FMG levels, Richardson): at most
    # 3 finest cycles and a central film within a tenth of the discretisation
    # error of the fully converged one (measured: 3 cycles, 2.4e-5 vs 1.1e-3)
    rs = solve_line_contact(n_nodes=1025, fmg_cycles=1, stop_at_discretisation=0.1, **kw)
    assert rs.iterations <= 3 and "stopped_at_discretisation" in rs.residuals
    assert abs(rs.H_central_moes / r.H_central_moes - 1.0) < 0.1 * disc_err
    with pytest.raises(EHLInputError, match="stop_at_discretisation"):
        solve_line_contact(n_nodes=1025, stop_at_discretisation=0.1, **kw)


@pytest.mark.parametrize("M,L,viscosity", [(500.0, 10.0, "barus"), (200.0, 20.0, "barus"),
                                           (200.0, 20.0, "roelands"), (500.0, 20.0, "roelands")])
def test_high_M_piezoviscous_corner_converges(M, L, viscosity):
    # Cases of the (M, L) tables that raised EHLConvergenceError before the
    # under-relaxed settings and the piezoviscous coarsest-grid rule (docs/ehl.md).
    # Reference: the discretised equations re-evaluated in numpy.
    comp = viscosity == "roelands"
    r = solve_line_contact(M=M, L=L, viscosity=viscosity, compressible=comp)
    assert r.converged
    gap_spread, load_err, scaled = discrete_equations_check(r, viscosity, compressible=comp)
    assert gap_spread < 1e-9 and load_err < 1e-5 and scaled < 1e-5
