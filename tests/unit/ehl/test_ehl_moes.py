"""The smooth line-contact film against Moes' fit, and against references of the fit's own accuracy.

References (none of them produced by gearfmu.ehl):

* Martin (1916): rigid cylinder, isoviscous lubricant, Reynolds outlet condition, in closed form
  (:func:`gearfmu.ehl.fits.martin_rigid_isoviscous`; the classical h_min/R = 4.9 U/W with the
  outlet at x = 0.475 sqrt(2 R h0), Hamrock, Schmid & Jacobson, *Fundamentals of Fluid Film
  Lubrication*, 2004) -- the limit M -> 0 at L = 0;
* an independent discretisation of the same equations, written separately from the multigrid
  solver (benchmarks/ehl_reference.py: pressure piecewise linear with the logarithmic kernel
  integrated in closed form, eps at the half nodes from the half-node pressure and film, all
  unknowns by Newton's method with the dense Jacobian and an active set for cavitation);
* Moes' (1992) central-film fit as quoted by Venner & Lubrecht (2000), Barus viscosity and an
  incompressible lubricant (its assumptions).

What they show (benchmarks/bench_ehl_moes.py; docs/ehl.md "Validation"; docs/validation.md
"Smooth EHL film against Moes' fit"): the solver reproduces Martin's closed form as M -> 0
(+0.30 % at M = 0.1) and agrees with the independent discretisation to 0.07 % on average (0.32 %
at most) on the same grid, and both converge to the same films under grid refinement (within
0.06 %); the fit differs from these converged films by up to 4.85 % (mean 2.13 % over 61 random
points; within 3 % at only 39 of them): 3.1-4.9 % below them at 17 points of moderate M with
high L (M 9-113, L 10-18) and 3.6 % at M = 5, L = 0, 3.2-4.2 % above them at 5 points of high M
with L < 2 (its isoviscous-elastic asymptote 2.621 M^-1/5 against 2.50 M^-1/5 at M = 300 and
1000), and its rigid-isoviscous asymptote 3/M is 23 % above Martin's exact 2.4475/M.  So the solver is held to the fit within the fit's own accuracy, and to
the independent solution and the closed form closely.
"""
import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

from gearfmu.ehl import solve_line_contact
from gearfmu.ehl.fits import martin_rigid_isoviscous, moes_central_film

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[3]
BARUS = dict(viscosity="barus", compressible=False)


def _reference_module():
    spec = importlib.util.spec_from_file_location("ehl_reference", ROOT / "benchmarks" / "ehl_reference.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_martin_closed_form_is_the_textbook_solution():
    # Reference: h_min/R = 4.9 U/W (U on the mean speed) and the outlet (Reynolds condition) at
    # x = 0.475 sqrt(2 R h0) (Hamrock et al. 2004, Martin 1916); and, for a finite inlet, the
    # Reynolds equation integrated numerically (scipy quad, independent of the closed form).
    from scipy.integrate import quad
    c, xi_out = martin_rigid_isoviscous()
    assert c == pytest.approx(4.9, abs=0.01) and xi_out == pytest.approx(0.475, abs=0.001)
    xi_in = -5.0
    c5, xo5 = martin_rigid_isoviscous(xi_in)
    g_in, gs = math.atan(xi_in), math.atan(xo5)
    k = 1.0 / math.cos(gs) ** 2

    def dp(g):          # dp/dg in units of 12 eta0 u_m sqrt(2 R h0) / h0^2
        return math.cos(g) ** 2 - k * math.cos(g) ** 4
    assert quad(dp, g_in, gs)[0] == pytest.approx(0.0, abs=1e-12)      # p = 0 at both ends
    load = quad(lambda g: quad(dp, g_in, g)[0] / math.cos(g) ** 2, g_in, gs, limit=200)[0]
    assert c5 == pytest.approx(24.0 * load, rel=1e-8)
    assert c5 < c                                                     # a shorter inlet carries less


def test_rigid_isoviscous_limit_against_martin():
    # Reference: Martin's closed form with the solver's inlet (30 sqrt(2 R h0) upstream, in the
    # film found) -- the limit M -> 0 of the elastic solution at L = 0.  Tolerance 1 %: measured
    # +0.30 % at M = 0.1 (the deformation's remaining effect; +1.2 % at M = 0.2, +8 % at M = 0.5).
    # Moes' fit has 3/M as its rigid-isoviscous asymptote: 23 % above the closed form here.
    M, xi_in, n = 0.1, -30.0, 4096
    c_inf, _ = martin_rigid_isoviscous()
    s = math.sqrt(2.0 * math.pi * (c_inf / (2.0 * M)) / (8.0 * M))   # sqrt(2 R h0)/b expected
    r = solve_line_contact(M=M, L=0.0, x_in=xi_in * s, x_out=2.0 * s, n_nodes=n + 1, **BARUS)
    s_found = math.sqrt(2.0 * math.pi * r.H_central_moes / (8.0 * M))
    c, xi_out = martin_rigid_isoviscous(xi_in * s / s_found)
    assert r.H_central_moes * M == pytest.approx(c / 2.0, rel=0.01)
    # the pressure ends (Reynolds condition) where Martin's does, within two grid spacings
    last = r.X[np.nonzero(r.P > 0.0)[0][-1]]
    assert abs(last - xi_out * s_found) < 2.0 * (r.X[1] - r.X[0])
    assert moes_central_film(M, 0.0) * M / (c_inf / 2.0) - 1.0 > 0.2


@pytest.mark.parametrize("M,L,fit_below", [(20.0, 15.0, 0.04), (5.0, 0.0, 0.03)])
def test_independent_discretisation_agrees_where_the_fit_is_off(M, L, fit_below):
    # Reference: the independent discretisation (module doc) on the same 1024 intervals,
    # Newton started from the solver's pressure (the start selects the branch; the converged
    # state solves the reference's own equations).  Measured: solver - reference -0.07 %
    # (20, 15) and -0.002 % (5, 0); both converge to the same film on 2048 intervals (-0.02 %).
    # Moes' fit lies 4.4 % resp. 3.6 % below the reference: more than the 3 % of the issue,
    # where two discretisations agree to 0.1 %.
    ref = _reference_module()
    r = solve_line_contact(M=M, L=L, n_nodes=1025, **BARUS)
    H_ref, _, ok, _ = ref.reference_central_film(M, L, 1024, r.X, r.P, r.H_central_moes)
    assert ok
    assert r.H_central_moes == pytest.approx(H_ref, rel=2e-3)
    assert moes_central_film(M, L) < (1.0 - fit_below) * H_ref


def test_smooth_central_film_against_moes_on_a_seeded_random_grid():
    # Reference: Moes' fit (Barus, incompressible) on the seeded random grid of
    # benchmarks/bench_ehl_moes.py (64 points, seed 2024: M log-uniform on 5..1000, L uniform on
    # 0..20).  Tolerances from the fit's own accuracy: against the grid-converged films of the
    # benchmark (Richardson extrapolation of the solver on 2x/4x finer grids, which the
    # independent discretisation matches within 0.07 % at the 36 points it was run) the fit is
    # off by up to 4.85 % (M = 21.6, L = 18.1), mean 2.13 % (61 points); the default grid's
    # film is low by up to 2.0 % at high M with moderate L (mean 0.48 %), where the fit is high,
    # so there the two add (M = 743, L = 4.1: fit +2.15 %, default grid -1.99 %, together
    # -4.05 %).  Every point within 5.5 %, mean |deviation| below 2.5 %.  Measured (default
    # solve against the fit): max 4.76 % (M = 21.6, L = 18.1), mean 2.13 %, 43 of 64 within 3 %.
    rng = np.random.default_rng(2024)
    Ms = 10 ** rng.uniform(math.log10(5.0), 3.0, 64)
    Ls = rng.uniform(0.0, 20.0, 64)
    devs = np.array([solve_line_contact(M=float(M), L=float(L), **BARUS).H_central_moes
                     / moes_central_film(M, L) - 1.0 for M, L in zip(Ms, Ls)])
    worst = int(np.argmax(np.abs(devs)))
    assert np.abs(devs).max() < 0.055, f"M={Ms[worst]:.4g}, L={Ls[worst]:.3g}: {devs[worst]:+.3%}"
    assert np.abs(devs).mean() < 0.025
