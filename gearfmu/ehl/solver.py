"""Steady line-contact EHL solver, seed 000 eq 2-7 and Algorithm 1.

Public entry point: :func:`solve_line_contact`.  See :mod:`.multigrid` for the
equations and the numerical method, and docs/ehl.md for the choices made.

Definitions (SI; Moes 1992 / Venner & Lubrecht 2000 conventions):

* ``R_m``: reduced radius of curvature, 1/R = 1/R1 + 1/R2.
* ``E_Pa``: reduced modulus E' = 2 / ((1 - nu1^2)/E1 + (1 - nu2^2)/E2)
  (the E' of Moes and Venner-Lubrecht and the E of seed 000 eq 4).
* ``w_N_per_m``: load per unit length of contact.
* ``u_m_s``: entrainment (mean) speed u_m = (u1 + u2)/2 (seed 000 eq 2's u_s).
* Moes' parameters: W = w/(E'R), U = eta0 u_m/(E'R), G = alpha E',
  M = W (2U)^(-1/2), L = G (2U)^(1/4), H_Moes = (h/R)(2U)^(-1/2).
* Hertz: b = R sqrt(8W/pi), p_h = E' sqrt(W/(2 pi)); Venner-Lubrecht
  H = h R / b^2 = pi H_Moes / (8 M), lambda-bar = 3 pi^2/(8 M^2),
  alpha-bar = alpha p_h = L sqrt(M/(2 pi)).

Roughness: the steady equations are solved with the composite roughness
frozen in place (d(rho h)/dt = 0 in seed 000 eq 2, i.e. a quasi-static
snapshot of the rough film); the composite roughness is the sum of the
profiles of both surfaces and enters seed 000 eq 3 with a positive sign (a
positive height *opens* the gap).  Where the film collapses (h <= 0 at any
node) the full-film model of seed 000 does not apply and
:class:`~gearfmu.ehl.errors.FilmCollapseError` is raised with the position
and the film parameter lambda = h_min / sigma (no asperity load sharing).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional, Sequence, Union

import numpy as np

from ..common.checks import finite_number
from .errors import EHLConvergenceError, EHLInputError, FilmCollapseError, stalled_residual
from .fits import moes_central_film
from .lubricant import ROELANDS_LN_ETA_INF, ROELANDS_P0_PA, DH_C1_PA
from .multigrid import EHLParams, MultigridSolver
from .mgcore import FlatMultigrid, OPT_KEYS, _coef, _residual, _scaled_residual
from .mgcore import _lu_solve as _dense_solve   # dense Gaussian elimination, partial pivoting

#: Reference dimensional case used when only Moes' M and L are given
#: (Venner & Lubrecht 2000's standard mineral oil on steel): E' = 2.2e11 Pa,
#: R = 0.02 m, eta0 = 0.04 Pa s, alpha = 2.2e-8 1/Pa, rho0 = 870 kg/m^3.
#: With L = 0 the lubricant is isoviscous (alpha = 0) and U = 1e-11.
REFERENCE_CASE = dict(E_Pa=2.2e11, R_m=0.02, eta0_Pas=0.04, alpha_Pa_inv=2.2e-8,
                      rho0_kg_m3=870.0, U_isoviscous=1e-11)

Roughness = Union[None, Callable[[np.ndarray], np.ndarray],
                  tuple, Sequence]


@dataclass
class LineContactResult:
    """Result of :func:`solve_line_contact` (SI unless the name says otherwise)."""

    x_m: np.ndarray            #: grid, m (x = b X, origin at the Hertz centre)
    X: np.ndarray              #: grid, dimensionless x/b
    p_Pa: np.ndarray           #: pressure, Pa
    P: np.ndarray              #: pressure / p_h
    h_m: np.ndarray            #: film thickness, m
    H: np.ndarray              #: film thickness in Venner-Lubrecht scaling h R / b^2
    h_central_m: float         #: film thickness at x = 0, m
    h_min_m: float             #: minimum film thickness, m
    x_min_m: float             #: position of the minimum film, m
    H_central_moes: float      #: (h_central/R)(2U)^(-1/2)
    H_min_moes: float          #: (h_min/R)(2U)^(-1/2)
    M: float                   #: Moes load parameter
    L: float                   #: Moes material parameter
    b_m: float                 #: Hertz half width, m
    ph_Pa: float               #: Hertz maximum pressure, Pa
    load_N_per_m: float        #: integral of p dx, N/m
    iterations: int            #: number of W-cycles on the finest grid
    residuals: Dict[str, List[float]]  #: per-cycle histories
    converged: bool
    inputs: Dict[str, float]   #: dimensional inputs actually used (SI)
    roughness_m: np.ndarray    #: composite roughness on the grid, m
    wall_time_s: float = 0.0
    grid_levels: int = 0       #: number of multigrid levels used

    @property
    def h_central(self) -> float:
        """Alias of ``h_central_m`` (m)."""
        return self.h_central_m

    @property
    def h_min(self) -> float:
        """Alias of ``h_min_m`` (m)."""
        return self.h_min_m


#: Relaxation settings tried in turn by the compiled solver (see docs/ehl.md):
#: (0) Venner & Lubrecht's arrangement (switch 0.3, GS/Jacobi under-relaxation
#: 0.6/0.5, load balance on the coarsest grid, switching hysteresis);
#: (1) the old default (s = 3, 0.8/0.6, load on the finest grid);
#: (2)-(5) as (0) with the trust region dmax = 3 (instead of 0.3: the
#: clipped updates at the pressure spike kept residual floors) and GS/Jacobi
#: 0.6/0.5, 0.4/0.2, 0.3/0.15, 0.3/0.1 -- the smaller Jacobi under-relaxation
#: of the nodes upstream of the spike made the high-M piezoviscous corner
#: converge (measured over the (M, L) tables); placed after (1) so that the
#: cases (1) converges (and warm-started sweeps from them) keep their path;
#: (6)-(8) older fallbacks found by numerical experiment.
RELAXATION_SETTINGS = (
    dict(switch=0.3, nu1=2, nu2=1, omega_gs=0.6, omega_j=0.5, load_mode=1, c_h0=0.1,
         stick=10.0),
    dict(switch=3.0, nu1=2, nu2=1, omega_gs=0.8, omega_j=0.6),
    dict(switch=0.3, nu1=2, nu2=1, omega_gs=0.6, omega_j=0.5, load_mode=1, c_h0=0.1,
         stick=10.0, dmax=3.0),
    dict(switch=0.3, nu1=2, nu2=1, omega_gs=0.4, omega_j=0.2, load_mode=1, c_h0=0.1,
         stick=10.0, dmax=3.0),
    dict(switch=0.3, nu1=2, nu2=1, omega_gs=0.3, omega_j=0.15, load_mode=1, c_h0=0.1,
         stick=10.0, dmax=3.0),
    dict(switch=0.3, nu1=2, nu2=1, omega_gs=0.3, omega_j=0.1, load_mode=1, c_h0=0.1,
         stick=10.0, dmax=3.0),
    dict(switch=0.3, nu1=2, nu2=1, omega_gs=0.6, omega_j=0.3, load_mode=1, c_h0=0.1,
         stick=10.0),
    dict(switch=3.0, nu1=2, nu2=1, omega_gs=0.8, omega_j=0.6, stick=10.0),
    dict(switch=0.3, nu1=2, nu2=3, omega_gs=0.6, omega_j=0.4),
)

#: Stall test of the compiled solver: a setting stalls when neither the
#: pressure change nor the scaled residual fell 3x over the last
#: STALL_WINDOW cycles against all earlier ones (checked from 2 x
#: STALL_WINDOW cycles on).  12: a window of 8 failed the high-M corner
#: about 1/3 sooner but cut off slowly converging light-load films (M = 0.85,
#: L = 16 of tests/test_helical_contact.py, 3x per ~10 cycles).
STALL_WINDOW = 12
#: stall window of the frozen-switch continuation (slow but steady
#: convergence, e.g. Barus M = 10, L = 20: 83 cycles; 8 stopped it early)
FROZEN_STALL_WINDOW = 12

#: upper limit of the film-change tolerance of ``stop_at_discretisation``: the
#: FMG levels' error estimate is unreliable at high alpha_eff (3-50x too large
#: at M = 100, L = 10, docs/ehl.md); the cap bounds the algebraic error left
#: to a few 1e-4 whatever the estimate
STOP_FILM_CHANGE_CAP = 3e-4

#: A relaxation setting that stalls with a relative pressure change per cycle
#: below this value is continued with the switch frozen (``freeze`` option of
#: :mod:`.mgcore`): the stall is then a switching limit cycle of the
#: relaxation close to the solution (measured on rough films, docs/ehl.md).
FREEZE_BELOW_PRESSURE_CHANGE = 1e-3

#: Settings of the previous (Python-driven) solver, kept for ``solver="python"``.
PYTHON_RELAXATION_SETTINGS = (
    dict(switch=3.0, nu1=2, nu2=1, omega_gs=0.8, omega_j=0.6),
    dict(switch=0.3, nu1=2, nu2=2, omega_gs=0.8, omega_j=0.6),
    dict(switch=1.0, nu1=2, nu2=2, omega_gs=0.8, omega_j=0.6),
    dict(switch=0.3, nu1=2, nu2=3, omega_gs=0.6, omega_j=0.4),
)


def _flat_opts(opts):
    """Map the options of the Python solver onto the compiled one."""
    o = dict(opts)
    if "load_on_coarse" in o:
        o["load_mode"] = 1 if o.pop("load_on_coarse") else 0
    if "order2" in o:
        o["order2"] = 1 if o["order2"] else 0
    return o


#: Block-Newton polish (docs/ehl.md "Newton polish of the spike region"): a
#: setting that stalls (after its frozen-switch continuation) with a scaled
#: Reynolds residual below this value is continued by rounds of
#: (block Newton on the finest grid, one multigrid cycle).  Chosen from the
#: stalls of the (M, L) corner: those that the polish converges ended at
#: 1.9e-6 .. 5e-6, those it does not at 2e-4 .. 7e-3.
POLISH_BELOW_RESIDUAL = 1e-5
#: a setting whose cycles stall (before its frozen-switch continuation) with a
#: scaled residual below this value is polished first (state restored if the
#: polish fails): Barus M = 100, L = 10 on 2048 intervals floats at 1e-5 ..
#: 2e-5 on its first setting (docs/ehl.md "Speed")
POLISH_EARLY_BELOW_RESIDUAL = 3e-5
#: at most this many polish rounds; stop early when the scaled residual has
#: not fallen 3x over the last POLISH_STALL_ROUNDS rounds (Barus M = 500,
#: L = 15 needs 20 rounds, falling about 1.3x per round with dips)
POLISH_MAX_ROUNDS = 30
POLISH_STALL_ROUNDS = 8
#: when every setting has failed on a grid, the stalled states with a scaled
#: residual below this value are polished, lowest first, until one converges
#: (Barus M = 500, L = 15: 2e-4 on setting 5 -> converges; the failures that remain
#: stall at 2.6e-4 with the residual spread over the whole Hertz zone
#: (Roelands M = 50, L = 20), or oscillate at 1e-4..3e-4 (Barus M = 500, L = 20))
POLISH_BEST_BELOW_RESIDUAL = 1e-3
#: largest Newton block (nodes; dense solve ~ n^3 / 3: 400 nodes ~ 5 ms)
POLISH_MAX_BLOCK = 400


def _finest_terms(solver):
    """Film, coefficients and residual f - L(P, H) of the finest grid (arrays of
    that grid: residual, eps, d ln(eps)/dP, rho, d rho/dP)."""
    S = solver.state()
    t = solver.top
    P, H, f, tauH, base, rho, eps, dle, drho, delta, wrk = S[:11]
    solver.update_film(t)
    _coef(t, P, H, rho, eps, dle, drho, solver.iarr, solver.prmv)
    _residual(t, P, H, f, rho, eps, wrk, solver.iarr, solver.dx, True, 0.0)
    sl = solver._sl(t)
    return wrk[sl].copy(), eps[sl].copy(), dle[sl].copy(), rho[sl].copy(), drho[sl].copy()


def block_newton(solver, steps: int = 2, frac: float = 0.05, margin: int = 8,
                 max_block: int = POLISH_MAX_BLOCK):
    """Newton steps for the finest-grid pressure on the block of nodes with the
    largest scaled Reynolds residual (seed 000 eq 2-6 discretised as in
    :mod:`.mgcore`; H0 and all other nodes fixed).

    The block is the contiguous pressurised run of nodes around the largest
    scaled residual |r_i / (dL_i/dP_i)| that covers every node whose scaled
    residual exceeds ``frac`` times the largest, plus ``margin`` nodes, at
    most ``max_block`` nodes.  The Jacobian dL_i/dP_j of the discrete operator
    L = Poiseuille - wedge is assembled densely: the wedge term (second-order
    upstream) through the film H_k = ... - (1/pi) sum_j K_|k-j| P_j and the
    density, the Poiseuille term directly and through eps_k = rho H^3/(eta
    lambda) (its pressure derivative via eta and rho, and H^3 via the
    deformation).  Each step is accepted only if it lowers the mean scaled
    residual of the finest grid (step halved up to 3 times, else dropped).

    Why (docs/ehl.md): in the strongly piezoviscous corner the point relaxations
    stall at residual floors on the ~10-100 nodes of the pressure spike and the
    outlet drop, where eps/dX^2 ~ 1e-8 .. 1e-4 and the equation is the film
    balance d(rho H)/dX = 0 coupled through the deformation integral -- a local
    problem with a dense Jacobian that point relaxation solves poorly and a
    dense Newton solve exactly (Venner & Lubrecht 2000 name line/block
    relaxation for this; the dense block is the simplest form).
    Returns the block (node indices of the finest grid) or None."""
    t = solver.top
    sl = solver._sl(t)
    dX = float(solver.dx[t])
    h2 = dX * dX
    Kt = solver.K[sl]
    order2 = solver.optv[3] > 0
    B = None
    for _ in range(steps):
        r, eps, dle, rho, drho = _finest_terms(solver)
        P = solver.P[sl]
        H = solver.H[sl]
        n = P.size
        em = np.zeros(n)
        ep = np.zeros(n)
        em[1:-1] = 0.5 * (eps[:-2] + eps[1:-1])
        ep[1:-1] = 0.5 * (eps[1:-1] + eps[2:])
        J0 = -(em + ep) / h2 + rho * (Kt[0] - Kt[1]) / (math.pi * dX)
        sr = np.where(P > 0.0, np.abs(r / np.where(J0 != 0.0, J0, 1.0)), 0.0)
        sr[:2] = 0.0
        sr[-1] = 0.0
        im = int(np.argmax(sr))
        if not (sr[im] > 0.0 and np.all(np.isfinite(sr))):
            break
        big = np.nonzero(sr > frac * sr[im])[0]
        lo = max(2, int(big.min()) - margin)
        hi = min(n - 2, int(big.max()) + margin)
        if hi - lo + 1 > max_block:
            lo = max(2, im - max_block // 2)
            hi = min(n - 2, lo + max_block - 1)
        a, b = im, im
        while a - 1 >= lo and P[a - 1] > 0.0:
            a -= 1
        while b + 1 <= hi and P[b + 1] > 0.0:
            b += 1
        B = np.arange(a, b + 1)
        nb = B.size
        rows = np.arange(a - 2, b + 2)
        dH = -Kt[np.abs(rows[:, None] - B[None, :])] / math.pi    # dH_k / dP_j
        R0 = B - (a - 2)                                           # row of node i in dH
        ia = np.arange(nb)
        J = -(1.5 * rho[B, None] * dH[R0] - 2.0 * rho[B - 1, None] * dH[R0 - 1]
              + 0.5 * rho[B - 2, None] * dH[R0 - 2]) / dX
        for off, c in ((0, 1.5), (1, -2.0), (2, 0.5)):
            m = ia - off >= 0
            J[ia[m], ia[m] - off] -= c * H[B[m] - off] * drho[B[m] - off] / dX
        for off, c in ((-1, em[B] / h2), (0, -(em[B] + ep[B]) / h2), (1, ep[B] / h2)):
            m = (ia + off >= 0) & (ia + off < nb)
            J[ia[m], ia[m] + off] += c[m]
        cm = (P[B - 1] - P[B]) / (2.0 * h2)
        cp = (P[B + 1] - P[B]) / (2.0 * h2)
        for off, c in ((-1, cm), (0, cm + cp), (1, cp)):
            k = B + off
            J += c[:, None] * (3.0 * eps[k] / np.maximum(H[k], 1e-300))[:, None] * dH[R0 + off]
            m = (ia + off >= 0) & (ia + off < nb)
            J[ia[m], ia[m] + off] += (c * eps[k] * dle[k])[m]
        # single-threaded compiled LU: the threaded LAPACK solves (numpy, scipy)
        # took 0.1-0.3 s for 186 nodes on this shared 2-core machine (0.3 ms idle)
        d = _dense_solve(np.ascontiguousarray(J), r[B].copy())
        if not np.all(np.isfinite(d)):
            break
        P0 = P.copy()
        r0 = _scaled_residual(t, solver.state(), order2, False)
        lam = 1.0
        accepted = False
        for _ls in range(4):
            Pn = P0.copy()
            Pn[B] = np.maximum(P0[B] + lam * d, 0.0)
            solver.P[sl] = Pn
            solver.update_film(t)
            r1 = _scaled_residual(t, solver.state(), order2, False)
            if math.isfinite(r1) and r1 < r0:
                accepted = True
                break
            lam *= 0.5
        if not accepted:
            solver.P[sl] = P0
            solver.update_film(t)
            break
    return B


def _polish(solver, tol_pressure, tol_load, tol_residual, tol_film,
            max_rounds=POLISH_MAX_ROUNDS):
    """Rounds of (one multigrid cycle, :func:`block_newton`) until the state
    after the Newton step meets the normal convergence test: pressure change
    over the round (relative L1) below ``tol_pressure``, load error below
    ``tol_load``, mean scaled Reynolds residual below ``tol_residual`` and, if
    ``tol_film`` < 1, the relative change of the central and minimum film over
    the round below it -- the same quantities and tolerances as after a cycle,
    evaluated on the state returned.  (Newton after the cycle: the cycle
    re-creates part of the spike residual that the Newton step removes; tested
    after the cycle, Barus M = 500, L = 15 did not converge in 20 rounds,
    after the Newton step it does in 20.)  Stops when the scaled residual has
    not fallen 3x over POLISH_STALL_ROUNDS rounds; at most
    min(POLISH_MAX_ROUNDS, ``max_rounds``) rounds (the caller's ``max_cycles``).
    Returns (converged, rounds, history)."""
    hist = {k_: [] for k_ in _HIST_KEYS}
    t = solver.top
    sl = solver._sl(t)
    order2 = solver.optv[3] > 0
    i0 = int(round(-solver.prm.x_in / solver.dx[t]))
    prev = None
    n_rounds = max(0, min(POLISH_MAX_ROUNDS, int(max_rounds)))
    for k in range(n_rounds):
        P_before = solver.P[sl].copy()
        solver.iterate(max_cycles=1, min_cycles=1, tol_pressure=0.0, tol_load=0.0,
                       tol_residual=0.0, stall_window=10 ** 6)
        block_newton(solver)
        P = solver.P[sl]
        H = solver.H[sl]
        dp = float(np.sum(np.abs(P - P_before)) / max(float(np.sum(np.abs(P))), 1e-300))
        dw = abs(solver.load() - 0.5 * math.pi) / (0.5 * math.pi)
        res = float(_scaled_residual(t, solver.state(), order2, False))
        hc, hm = float(H[i0]), float(np.min(H))
        dh = 1.0 if prev is None else max(abs(hc - prev[0]) / max(abs(hc), 1e-300),
                                          abs(hm - prev[1]) / max(abs(hm), 1e-300))
        prev = (hc, hm)
        for k_, v in zip(_HIST_KEYS, (dp, dw, res, hc, hm, dh)):
            hist[k_].append(v)
        if not (math.isfinite(dp) and math.isfinite(dw) and math.isfinite(res)):
            return False, k + 1, hist
        if dp < tol_pressure and dw < tol_load and res < tol_residual and (tol_film >= 1.0
                                                                            or dh < tol_film):
            return True, k + 1, hist
        rr = hist["reynolds_residual"]
        if len(rr) > POLISH_STALL_ROUNDS and min(rr[-POLISH_STALL_ROUNDS:]) > \
                min(rr[:-POLISH_STALL_ROUNDS]) / 3.0:
            return False, k + 1, hist
    return False, n_rounds, hist


_HIST_KEYS = ("pressure_change", "load_balance", "reynolds_residual", "H_central", "H_min",
              "film_change")


def _iterate_flat(prm, n_levels, n_coarse, rough_fn, opts, Hc_guess, P_start, max_cycles,
                  min_cycles, tol_pressure, tol_load, tol_residual, ramp=(1.0,), tol_film=1.0,
                  fmg=0, stop_at_discretisation=0.0):
    """Compiled W-cycles (:mod:`.mgcore`) from ``P_start`` (finest grid), a
    full-multigrid start (``fmg`` > 0 cycles per level) or a Hertzian
    pressure; with roughness the amplitude steps of ``ramp``."""
    solver = FlatMultigrid(prm, n_levels, n_coarse, rough_fn, **_flat_opts(opts))
    if rough_fn is not None:
        solver.base[:] = np.concatenate([0.5 * x ** 2 for x in solver.X])
    fmg_counts = None
    tol_disc = 0.0
    if P_start is None and fmg > 0:
        fmg_counts = solver.fmg_start(Hc_guess, cycles_per_level=fmg)
    elif P_start is None:
        solver.hertz_start(Hc_guess)
    else:
        solver.start(P_start, Hc_guess)
    hist = {k_: [] for k_ in _HIST_KEYS}
    if fmg_counts is not None:
        hist["fmg_cycles_per_level"] = list(fmg_counts)
        hc = solver.fmg_hc
        if stop_at_discretisation > 0.0 and len(hc) >= 2 and hc[-1] > 0.0:
            # Richardson (second order): error of the last FMG level
            # |H_l - H_(l-1)| / 3, of the finest grid a quarter of that; stop when
            # the film change per cycle and the load error are below
            # stop_at_discretisation times that estimate (docs/ehl.md)
            e_top = abs(hc[-1] - hc[-2]) / 3.0 / hc[-1] / 4.0
            tol_disc = min(max(stop_at_discretisation * e_top, 1e-8), STOP_FILM_CHANGE_CAP)
            hist["stopped_at_discretisation"] = [e_top, tol_disc]
    stages = list(ramp) if rough_fn is not None else [None]
    if rough_fn is not None and P_start is None:
        stages = [0.0] + stages
    it = 0
    converged = False
    for a in stages:
        if a is not None:
            solver.set_roughness_scale(a)
        converged, nc, h = solver.iterate(max_cycles=max_cycles, min_cycles=min_cycles,
                                          tol_pressure=tol_pressure, tol_load=tol_load,
                                          tol_residual=tol_residual, tol_film=tol_film,
                                          stall_window=STALL_WINDOW,
                                          tol_discretisation=tol_disc)
        it += nc
        for k_ in _HIST_KEYS:
            hist[k_].extend(h[k_])
        if not converged and nc >= max_cycles:
            # stopped by the caller's cycle limit, not stalled: no polish either
            hist["hit_max_cycles"] = [float(nc)]
        last_dp = h["pressure_change"][-1] if h["pressure_change"] else float("nan")
        last_res = h["reynolds_residual"][-1] if h["reynolds_residual"] else float("nan")
        if (not converged and math.isfinite(last_res) and last_res < POLISH_EARLY_BELOW_RESIDUAL
                and "hit_max_cycles" not in hist
                and solver.opts.get("order2", 1) and not solver.opts.get("defect", 0)):
            # stalled just above the tolerance: block-Newton polish first; if it
            # fails, the state is restored and the path continues exactly as
            # without it (frozen switch, docs/ehl.md)
            saved = (solver.P.copy(), solver.H.copy(), solver.H0.copy(), solver.mode.copy())
            ok, nr, ph = _polish(solver, tol_pressure, tol_load, tol_residual, tol_film,
                                 max_cycles)
            hist["newton_polish_early_rounds"] = [nr]
            if ok:
                converged = True
                hist["newton_polish_from_cycle"] = [it]
                hist["newton_polish_rounds"] = [nr]
                it += nr
                for k_ in _HIST_KEYS:
                    hist[k_].extend(ph[k_])
            else:
                solver.P[:], solver.H[:], solver.H0[:], solver.mode[:] = saved
        if not converged and math.isfinite(last_dp) and last_dp < FREEZE_BELOW_PRESSURE_CHANGE:
            # limit cycle close to the solution: continue with the Gauss-Seidel /
            # Jacobi choice of every finest-grid node frozen (docs/ehl.md)
            solver.opts["freeze"] = 1
            converged, nc, h = solver.iterate(max_cycles=max_cycles, min_cycles=1,
                                              tol_pressure=tol_pressure, tol_load=tol_load,
                                              tol_residual=tol_residual, tol_film=tol_film,
                                              stall_window=FROZEN_STALL_WINDOW)
            solver.opts["freeze"] = 0
            hist["frozen_switch_from_cycle"] = [it]
            it += nc
            for k_ in _HIST_KEYS:
                hist[k_].extend(h[k_])
        last_res = hist["reynolds_residual"][-1] if hist["reynolds_residual"] else float("nan")
        if (not converged and math.isfinite(last_res) and last_res < POLISH_BELOW_RESIDUAL
                and "hit_max_cycles" not in hist and "newton_polish_rounds" not in hist
                and "newton_polish_early_rounds" not in hist   # failed once on this setting
                and solver.opts.get("order2", 1) and not solver.opts.get("defect", 0)):
            # close to the solution but stalled on the spike region: block-Newton
            # polish (docs/ehl.md)
            converged, nc, h = _polish(solver, tol_pressure, tol_load, tol_residual, tol_film,
                                       max_cycles)
            hist["newton_polish_from_cycle"] = [it]
            hist["newton_polish_rounds"] = [nc]
            it += nc
            for k_ in _HIST_KEYS:
                hist[k_].extend(h[k_])
        if not converged:
            break
    return solver, hist, converged, it


def _iterate(prm, n_levels, n_coarse, rough_fn, opts, Hc_guess, fmg_cycles, max_cycles,
             min_cycles, tol_pressure, tol_load, tol_residual, ramp=(1.0,)):
    """W-cycles from a Hertzian (or FMG) start until convergence or stall.

    With roughness the amplitude is raised in the steps of ``ramp`` (each
    step converged before the next, the previous solution as its start)."""
    solver = MultigridSolver(prm, n_levels, n_coarse, rough_fn, **opts)
    if rough_fn is not None:
        solver.set_roughness_scale(0.0)
    if fmg_cycles > 0:
        solver.fmg_start(H0_guess=Hc_guess - 0.597, cycles_per_level=fmg_cycles)
    else:
        solver.hertz_start(Hc_guess)
    top = solver.levels[-1]
    hist = {"pressure_change": [], "load_balance": [], "reynolds_residual": []}
    converged = False
    it = 0
    stages = [0.0] + list(ramp) if rough_fn is not None else [None]
    for a in stages:
        if a is not None:
            solver.set_roughness_scale(a)
        converged = False
        first = len(hist["pressure_change"])
        for k in range(1, max_cycles + 1):
            it += 1
            P_old = top.P.copy()
            solver.solve_cycle(n_levels - 1)
            sP = float(np.sum(np.abs(top.P)))
            dP = float(np.sum(np.abs(top.P - P_old))) / max(sP, 1e-300)
            dW = abs(top.load() - 0.5 * math.pi) / (0.5 * math.pi)
            res = solver.scaled_residual(top)
            hist["pressure_change"].append(dP)
            hist["load_balance"].append(dW)
            hist["reynolds_residual"].append(res)
            if not (math.isfinite(dP) and math.isfinite(dW) and math.isfinite(res)):
                return solver, hist, False, it
            if k >= min_cycles and dP < tol_pressure and dW < tol_load and res < tol_residual:
                converged = True
                break
            # stall: neither the change nor the residual fell by 3x in 12 cycles
            if k >= 24:
                rr = hist["reynolds_residual"][first:]
                pp = hist["pressure_change"][first:]
                if min(rr[-12:]) > min(rr[:-12]) / 3.0 and min(pp[-12:]) > min(pp[:-12]) / 3.0:
                    break
        if not converged:
            break
    return solver, hist, converged, it


def band_limit(z: np.ndarray, min_wavelength_samples: float) -> np.ndarray:
    """Low-pass filter of a uniformly sampled profile ``z``: Fourier
    components with wavelength shorter than ``min_wavelength_samples``
    samples are removed (ideal cut of the FFT of the profile extended by its
    mirror image, so that no jump at the ends leaks into the band).  Units
    of ``z`` are kept."""
    z = np.asarray(z, float)
    n = z.size
    if n < 4 or min_wavelength_samples <= 2.0:
        return z.copy()
    ext = np.concatenate((z, z[-2:0:-1]))        # even extension, period 2n - 2
    m = ext.size
    Z = np.fft.rfft(ext)
    f = np.arange(Z.size) / m                     # cycles per sample
    Z[f > 1.0 / min_wavelength_samples] = 0.0
    return np.fft.irfft(Z, m)[:n]


def choose_grid(Hc_VL: float, length: float, n_nodes=None, n_coarse=None):
    """Grid sizes (n_nodes, n_coarse, n_levels) for a film of about ``Hc_VL``
    (Venner-Lubrecht units) on a domain ``length`` half-widths long.

    The coarsest grid must resolve the film (dX^2 <= Hc, found by experiment:
    coarser grids make the FAS correction diverge at high M); the default
    finest grid has dX^2 <= Hc/480, which gave a 1 % discretisation error
    of the central film at M = 100, L = 10 (see docs/ehl.md).
    Defaults are clipped to 256..16384 intervals.
    """
    def pow2_at_least(x):
        return 1 << max(0, int(math.ceil(math.log2(max(x, 1.0)))))
    if n_coarse is None:
        n_coarse = min(max(32, pow2_at_least(length / math.sqrt(Hc_VL))), 1024)
    if n_nodes is None:
        n_int = min(max(256, pow2_at_least(length * math.sqrt(480.0 / Hc_VL))), 16384)
        n_int = max(n_int, n_coarse)
        n_nodes = n_int + 1
    n_nodes = int(n_nodes)
    n_coarse = int(n_coarse)
    k = n_nodes - 1
    if n_coarse < 8 or k < n_coarse or k % n_coarse != 0:
        raise EHLInputError(f"n_nodes={n_nodes!r}: need n_nodes - 1 = n_coarse * 2^k with "
                            f"n_coarse={n_coarse!r} >= 8")
    q = k // n_coarse
    n_levels = 1
    while q > 1 and q % 2 == 0:
        q //= 2
        n_levels += 1
    if q != 1:
        raise EHLInputError(f"n_nodes={n_nodes!r}: n_nodes - 1 must be n_coarse={n_coarse} "
                            "times a power of 2")
    return n_nodes, n_coarse, n_levels


#: grid rule of the refined retry: dX <= REFINE_DX_ALPHA / alpha_eff (found
#: by experiment over the (M, L) table in docs/ehl.md: the pressure spike and
#: the outlet drop are then resolved by several nodes)
REFINE_DX_ALPHA = 0.15
#: largest retry grid (intervals): the failures measured on finer retry grids
#: (M >= 100 with L >= 15, M = 500 with L = 10) never converged there and cost
#: 3-11 s each
REFINE_MAX_INTERVALS = 4096


#: coarse-grid retry (docs/ehl.md "Coarse-grid retry"): a smooth solve whose
#: settings all fail on the default hierarchy is retried on the same finest
#: grid with the coarsest grid refined by these factors in turn (at least
#: COARSE_RETRY_MIN_LEVELS levels left).  Measured: the stalls of Barus
#: M = 500, L = 20 and Roelands M = 50, L = 20 are smooth errors over the whole
#: Hertz zone that the coarse-grid correction does not remove when the
#: coarsest grid is 128 (resp. 32) intervals; 512 (resp. 64) converge them.
COARSE_RETRY_FACTORS = (2, 4)
COARSE_RETRY_MIN_LEVELS = 3


#: Failing fast (docs/ehl.md "Failing fast"), rule 1: the retry grids
#: (coarse-grid retry, refined grid) are tried only when some setting on the
#: default grid stalled below this scaled Reynolds residual (the threshold of
#: the best-state polish).  Measured: every solve that converged on a retry grid
#: (the (M, L) tables, the margin points M = 2000-5000, L <= 30, M = 0.3-7.5,
#: L = 5-40) had stalled below 6e-4 on its default grid.
RETRY_BELOW_RESIDUAL = 1e-3
#: rule 2: a second or later retry grid is tried only when the previous retry
#: grid lowered the best stalled residual of the grids before it at least
#: RETRY_PROGRESS_FACTOR times or stalled below RETRY_CLOSE_RESIDUAL (measured
#: on the converging cases: 2.9x (Barus M = 5000, L = 30) to 200x, or 1.3x at
#: 5.9e-6 (Barus M = 20000, L = 10); on the failures Barus M = 200 and 1000,
#: L = 40: 1.0x at 9e-4 and 0.3x at 7e-4)
RETRY_PROGRESS_FACTOR = 2.0
RETRY_CLOSE_RESIDUAL = 1e-4


def coarse_retry_grids(n_int: int, n_coarse: int) -> List[int]:
    """Coarsest-grid sizes (intervals) of the coarse-grid retry of a solve on
    ``n_int`` finest intervals whose default coarsest grid has ``n_coarse``:
    ``n_coarse`` times each of :data:`COARSE_RETRY_FACTORS` that leaves at
    least :data:`COARSE_RETRY_MIN_LEVELS` levels."""
    out = []
    for f in COARSE_RETRY_FACTORS:
        c = int(n_coarse) * int(f)
        if c * 2 ** (COARSE_RETRY_MIN_LEVELS - 1) <= n_int:
            out.append(c)
    return out


def effective_alpha(prm) -> float:
    """alpha_eff = d ln(eta)/dP at P = 1 (dimensionless, Hertzian pressure
    units): alpha p_h for Barus; A z (p_h/p0) (1 + p_h/p0)^(z-1) for Roelands
    (seed 000 eq 5)."""
    if prm.z < 0.0:
        return float(prm.A)
    if prm.z > 0.0:
        return float(prm.A * prm.z * prm.php0 * (1.0 + prm.php0) ** (prm.z - 1.0))
    return 0.0


def refined_grid_intervals(prm, length: float, n_int: int) -> Optional[int]:
    """Number of intervals of the retry grid after a failed solve on
    ``n_int`` intervals (smooth solves whose grid was chosen automatically):
    the power of 2 with dX <= REFINE_DX_ALPHA / alpha_eff, at least 2 n_int;
    None when that exceeds REFINE_MAX_INTERVALS."""
    a = effective_alpha(prm)
    need = length * a / REFINE_DX_ALPHA if a > 0.0 else 0.0
    n = 2 * n_int
    while n < need:
        n *= 2
    return n if n <= REFINE_MAX_INTERVALS else None


def _finite_positive(name, v, allow_zero=False):
    return finite_number(name, v, positive=not allow_zero, nonneg=allow_zero, error=EHLInputError)


def _roughness_function(roughness) -> Optional[Callable[[np.ndarray], np.ndarray]]:
    """Normalise the roughness argument into one function of x (m) -> height (m)."""
    if roughness is None:
        return None
    if callable(roughness):
        return roughness
    if isinstance(roughness, tuple) and len(roughness) == 2 and not callable(roughness[0]) \
            and np.ndim(roughness[0]) == 1:
        xr = np.asarray(roughness[0], float)
        zr = np.asarray(roughness[1], float)
        if xr.shape != zr.shape or xr.size < 2:
            raise EHLInputError("roughness_m: (x_m, z_m) arrays must have the same length >= 2")
        if not (np.all(np.isfinite(xr)) and np.all(np.isfinite(zr))):
            raise EHLInputError("roughness_m: profile contains NaN or infinite values")
        if np.any(np.diff(xr) <= 0):
            raise EHLInputError("roughness_m: x_m must be strictly increasing")
        return lambda x: np.interp(x, xr, zr)
    parts = [_roughness_function(r) for r in roughness]
    return lambda x: sum(f(x) for f in parts)


def solve_line_contact(R_m: float = None, E_Pa: float = None, w_N_per_m: float = None,
                       u_m_s: float = None, eta0_Pas: float = None,
                       alpha_Pa_inv: float = None, rho0_kg_m3: float = 870.0, *,
                       M: float = None, L: float = None,
                       roughness_m: Roughness = None,
                       compressible: bool = True, viscosity: str = "roelands",
                       n_nodes: Optional[int] = None, n_coarse: Optional[int] = None,
                       x_in: float = -4.5, x_out: float = 1.5,
                       tol_pressure: float = 1e-5, tol_load: float = 1e-6,
                       tol_residual: float = 1e-6, tol_film: float = 1.0,
                       max_cycles: int = 60, min_cycles: int = 2,
                       fmg_cycles: int = 0, roughness_ramp=(1.0,),
                       initial: Optional["LineContactResult"] = None,
                       roughness_min_wavelength_dX: float = 8.0,
                       solver: str = "compiled", stop_at_discretisation: float = 0.0,
                       **multigrid_options) -> LineContactResult:
    """Solve the steady isothermal line-contact EHL problem (seed 000 eq 2-7).

    Either the dimensional inputs ``R_m`` (m), ``E_Pa`` (reduced modulus E',
    Pa), ``w_N_per_m`` (N/m), ``u_m_s`` (mean entrainment speed, m/s),
    ``eta0_Pas`` (Pa s), ``alpha_Pa_inv`` (1/Pa), ``rho0_kg_m3`` (kg/m^3, only
    scales the density; the film does not depend on it) -- or Moes' ``M``
    and ``L`` (then the reference case :data:`REFERENCE_CASE` supplies the
    dimensional values).  ``roughness_m``: composite roughness (m) added to
    the gap (seed 000 eq 3): a function of x (m), an ``(x_m, z_m)`` pair of
    arrays, or a list of either (summed, e.g. one per surface).
    ``compressible`` switches Dowson-Higginson density on (default).
    Grid: ``n_nodes`` = n_coarse * 2^k + 1 nodes on [x_in, x_out] in units of
    the Hertz half-width b (default: chosen from the film, see
    :func:`choose_grid`).  Convergence: relative pressure change per W-cycle
    below ``tol_pressure``, relative load error below ``tol_load`` and the
    scaled Reynolds residual (mean |r_i / (dL_i/dP_i)| over pressurised
    nodes, in units of p_h) below ``tol_residual``; otherwise
    :class:`EHLConvergenceError` names the stalled residual.
    With roughness the smooth solution is computed first and then continued
    through the amplitude steps ``roughness_ramp`` (last must be 1; default
    (1.0,): one step -- finer ramps did not help in the cases tried).
    ``viscosity``: "roelands" (seed 000 eq 5, default) or "barus"
    (exp(alpha p), the law behind Moes' fit; used by the validation tests).  Film collapse (h <= 0): :class:`FilmCollapseError`.

    Fast paths (added with the compiled solver, docs/ehl.md):

    * ``initial``: a :class:`LineContactResult` of a nearby problem (e.g. the
      neighbouring meshing position).  Its pressure P(x/b) and central film
      (converted to the new scaling) start the iteration and its relaxation
      settings are tried first; typically 2-4x fewer W-cycles.
    * ``roughness_min_wavelength_dX``: the roughness is sampled on the finest
      grid and low-pass filtered (FFT, ideal cut) to wavelengths of at least
      this many grid spacings (default 8; 0 switches filtering off), because
      shorter wavelengths are not resolved by the discretisation and make
      the relaxation limit-cycle.  ``result.roughness_m`` is the filtered
      profile actually used.
    * ``solver``: "compiled" (default; whole W-cycle in numba,
      :mod:`.mgcore`) or "python" (the previous driver, :mod:`.multigrid`).
    * ``tol_film``: also require the relative change per cycle of the
      central and minimum film below this (default 1: off; compiled solver).
    * ``fmg_cycles`` (compiled solver, smooth solves without ``initial``):
      > 0 starts with a full-multigrid pass (:meth:`.mgcore.FlatMultigrid.fmg_start`:
      coarse problem solved first on the coarsest grid with dX^2 <= H_c and the
      next finer one, cubic interpolation up, ``fmg_cycles`` cycles per level)
      instead of the Hertzian pressure; ``residuals["fmg_cycles_per_level"]``.
      The convergence test after it is the same.  With ``solver="python"`` the
      previous driver's FMG is used.
    * ``stop_at_discretisation`` (with ``fmg_cycles`` > 0; default 0: off): stop
      the finest-grid cycles when the relative change per cycle of the central
      and minimum film and the load error are below this factor times the
      discretisation error of the central film estimated from the FMG levels
      (Richardson, second order: |H_l - H_(l-1)| / 3 on the last FMG level, a
      quarter of it on the finest grid; the tolerance is capped at
      :data:`STOP_FILM_CHANGE_CAP`) -- or when the normal tolerances are met.
      ``residuals["stopped_at_discretisation"]`` = [estimate, tolerance].  Only
      where the coarse grids resolve the solution (docs/ehl.md: low alpha_eff).

    Robustness (compiled solver, docs/ehl.md): the relaxation settings of
    :data:`RELAXATION_SETTINGS` are tried in turn; a setting that stalls
    with a pressure change per cycle below
    :data:`FREEZE_BELOW_PRESSURE_CHANGE` continues with the finest-grid
    Gauss-Seidel/Jacobi switch frozen (``residuals["frozen_switch_from_cycle"]``);
    a smooth solve on an automatically chosen grid that fails on every
    setting is retried once on the grid of :func:`refined_grid_intervals`
    (``residuals["grid_refined"]``).  A setting that stalls close to a
    solution is continued by the block-Newton polish of the pressure-spike
    region (:func:`block_newton`, :func:`_polish`; ``residuals["newton_polish_rounds"]``,
    docs/ehl.md), and once every setting has failed on a grid the stalled
    states are polished, lowest residual first.  Every converged result meets
    the stated tolerances; otherwise :class:`EHLConvergenceError`.
    """
    t_start = time.perf_counter()
    dimensional = [R_m, E_Pa, w_N_per_m, u_m_s, eta0_Pas, alpha_Pa_inv]
    if M is not None or L is not None:
        if M is None or L is None:
            raise EHLInputError("M and L must be given together")
        if any(v is not None for v in dimensional):
            raise EHLInputError("give either the dimensional inputs or M and L, not both")
        M = _finite_positive("M", M)
        L = _finite_positive("L", L, allow_zero=True)
        ref = REFERENCE_CASE
        E_Pa, R_m, eta0_Pas = ref["E_Pa"], ref["R_m"], ref["eta0_Pas"]
        if L > 0.0:
            alpha_Pa_inv = ref["alpha_Pa_inv"]
            U = 0.5 * (L / (alpha_Pa_inv * E_Pa)) ** 4
        else:
            alpha_Pa_inv = 0.0
            U = ref["U_isoviscous"]
        W = M * math.sqrt(2.0 * U)
        w_N_per_m = W * E_Pa * R_m
        u_m_s = U * E_Pa * R_m / eta0_Pas
    else:
        names = ["R_m", "E_Pa", "w_N_per_m", "u_m_s", "eta0_Pas", "alpha_Pa_inv"]
        for n_, v in zip(names, dimensional):
            if v is None:
                raise EHLInputError(f"{n_} is required (or give M and L)")
        R_m = _finite_positive("R_m", R_m)
        E_Pa = _finite_positive("E_Pa", E_Pa)
        w_N_per_m = _finite_positive("w_N_per_m", w_N_per_m)
        u_m_s = _finite_positive("u_m_s", u_m_s)
        eta0_Pas = _finite_positive("eta0_Pas", eta0_Pas)
        alpha_Pa_inv = _finite_positive("alpha_Pa_inv", alpha_Pa_inv, allow_zero=True)
        W = w_N_per_m / (E_Pa * R_m)
        U = eta0_Pas * u_m_s / (E_Pa * R_m)
        M = W / math.sqrt(2.0 * U)
        L = alpha_Pa_inv * E_Pa * (2.0 * U) ** 0.25
    rho0_kg_m3 = _finite_positive("rho0_kg_m3", rho0_kg_m3)
    A = math.log(eta0_Pas) - ROELANDS_LN_ETA_INF
    if A <= 0.0:
        raise EHLInputError(f"eta0_Pas={eta0_Pas!r} is below the Roelands limit 6.31e-5 Pa s")
    if not (x_in < -1.0 and x_out > 1.0):
        raise EHLInputError(f"x_in={x_in!r}, x_out={x_out!r}: the domain must contain [-1, 1]")
    b_m = R_m * math.sqrt(8.0 * W / math.pi)
    ph_Pa = E_Pa * math.sqrt(W / (2.0 * math.pi))
    lam = 3.0 * math.pi ** 2 / (8.0 * M ** 2)
    if viscosity == "roelands":
        z = alpha_Pa_inv * ROELANDS_P0_PA / A
        A_kernel = A
    elif viscosity == "barus":
        # Barus: eta = eta0 exp(alpha p); the kernel flags it with z < 0 and A = alpha p_h
        z = -1.0 if alpha_Pa_inv > 0 else 0.0
        A_kernel = alpha_Pa_inv * ph_Pa
    else:
        raise EHLInputError(f"viscosity={viscosity!r}: must be 'roelands' or 'barus'")
    prm = EHLParams(lam=lam, A=A_kernel, z=z, php0=ph_Pa / ROELANDS_P0_PA, c1=DH_C1_PA / ph_Pa,
                    compressible=bool(compressible), x_in=float(x_in), x_out=float(x_out))

    Hc_guess = math.pi * moes_central_film(M, L) / (8.0 * M)   # VL units
    user_grid = n_nodes is not None
    user_coarse = n_coarse is not None
    n_nodes, n_coarse, n_levels = choose_grid(Hc_guess, x_out - x_in, n_nodes, n_coarse)
    roughness_ramp = tuple(float(a) for a in roughness_ramp)
    if not roughness_ramp or roughness_ramp[-1] != 1.0:
        raise EHLInputError(f"roughness_ramp={roughness_ramp!r}: must end with 1.0")
    rfun = _roughness_function(roughness_m)
    scale_H = R_m / b_m ** 2  # h -> H
    lw = float(roughness_min_wavelength_dX)
    if not math.isfinite(lw) or lw < 0.0:
        raise EHLInputError(f"roughness_min_wavelength_dX={roughness_min_wavelength_dX!r}: "
                            "must be finite and >= 0")
    rough_fn = None
    if rfun is not None:
        Xf = np.linspace(x_in, x_out, n_nodes)
        zr = np.asarray(rfun(Xf * b_m), float)
        if zr.shape != Xf.shape or not np.all(np.isfinite(zr)):
            raise EHLInputError("roughness_m: must return finite heights (m), one per x")
        if lw > 0.0:
            zr = band_limit(zr, lw)
        zr_H = zr * scale_H

        def rough_fn(X):
            return np.interp(X, Xf, zr_H)

    if solver not in ("compiled", "python"):
        raise EHLInputError(f"solver={solver!r}: must be 'compiled' or 'python'")
    fmg_cycles = int(fmg_cycles)
    if fmg_cycles < 0:
        raise EHLInputError(f"fmg_cycles={fmg_cycles!r}: must be >= 0")
    sad = float(stop_at_discretisation)
    if not math.isfinite(sad) or sad < 0.0 or (sad > 0.0 and fmg_cycles == 0):
        raise EHLInputError(f"stop_at_discretisation={stop_at_discretisation!r}: must be "
                            ">= 0 and needs fmg_cycles > 0 (the estimate comes from the FMG levels)")
    if solver == "python":
        table = PYTHON_RELAXATION_SETTINGS
    else:
        table = RELAXATION_SETTINGS
    if multigrid_options:
        attempts = [dict(multigrid_options)]
    else:
        attempts = [dict(a) for a in table]
    P_start = None
    if initial is not None:
        if not isinstance(initial, LineContactResult):
            raise EHLInputError("initial: must be a LineContactResult of an earlier solve")
        Hc_guess = initial.h_central_m * scale_H
        prev = initial.residuals.get("settings")
        if prev is not None and not multigrid_options and solver == "compiled":
            attempts = [dict(prev)] + [a for a in attempts if a != prev]
    # grids tried in turn: the default one and, for smooth solves on a grid
    # chosen here, one refined from the effective pressure-viscosity
    # coefficient (see refined_grid_intervals)
    grids = [(n_nodes, n_coarse, n_levels)]
    compiled = solver == "compiled"
    if compiled and not user_coarse and rfun is None:
        # same finest grid, finer coarsest grid (docs/ehl.md "Coarse-grid retry")
        grids += [choose_grid(Hc_guess, x_out - x_in, n_nodes, c)
                  for c in coarse_retry_grids(n_nodes - 1, n_coarse)]
    n_default = len(grids)
    if compiled and not user_grid and rfun is None:
        n_ref = refined_grid_intervals(prm, x_out - x_in, n_nodes - 1)
        if n_ref is not None:
            grids.append(choose_grid(Hc_guess, x_out - x_in, n_ref + 1, n_coarse))
    collapsed = None
    tried = []          # (grid intervals, coarsest intervals, setting, final scaled residual)
    skipped = []        # why settings or grids were skipped (fail fast)
    for k_grid, (n_nodes, n_coarse, n_levels) in enumerate(grids):
        if k_grid > 0:
            # fail fast (rules 1 and 2 above): best stalled residual per grid so far
            per_grid = [min((t_[3] for t_ in tried if t_[:2] == (g[0] - 1, g[1])),
                            default=math.inf) for g in grids[:k_grid]]
            if not per_grid[0] < RETRY_BELOW_RESIDUAL:
                skipped.append(f"retry grids not tried: best scaled residual on the default "
                               f"grid {per_grid[0]:.1e} >= {RETRY_BELOW_RESIDUAL:.0e}")
                break
            if k_grid > 1 and not (per_grid[-1] * RETRY_PROGRESS_FACTOR
                                   <= min(per_grid[:-1])
                                   or per_grid[-1] < RETRY_CLOSE_RESIDUAL):
                skipped.append(f"{len(grids) - k_grid} further retry grid(s) not tried: the "
                               f"last one ({grids[k_grid - 1][0] - 1}/{grids[k_grid - 1][1]}"
                               f" intervals) reached {per_grid[-1]:.1e}, neither "
                               f"{RETRY_PROGRESS_FACTOR:g}x below {min(per_grid[:-1]):.1e} "
                               f"nor below {RETRY_CLOSE_RESIDUAL:.0e}")
                break
        best = []
        if initial is not None:
            Xg = np.linspace(x_in, x_out, n_nodes)
            P_start = np.interp(Xg, initial.X, initial.P, left=0.0, right=0.0)
        for k_att, opts in enumerate(attempts):
            if not compiled:
                solver_obj, hist, converged, it = _iterate(
                    prm, n_levels, n_coarse, rough_fn, opts, Hc_guess, fmg_cycles, max_cycles,
                    min_cycles, tol_pressure, tol_load, tol_residual, tuple(roughness_ramp))
            else:
                solver_obj, hist, converged, it = _iterate_flat(
                    prm, n_levels, n_coarse, rough_fn, opts, Hc_guess,
                    P_start if k_att == 0 else None, max_cycles, min_cycles, tol_pressure,
                    tol_load, tol_residual, tuple(roughness_ramp), tol_film,
                    fmg=fmg_cycles if rough_fn is None else 0,
                    stop_at_discretisation=float(stop_at_discretisation))
            if converged:
                break
            rr = hist["reynolds_residual"]
            tried.append((n_nodes - 1, n_coarse, k_att,
                          float(rr[-1]) if rr and math.isfinite(rr[-1]) else math.inf))
            # remember the last attempt that ended with a collapsed film (h <= 0):
            # if no attempt converges, that is reported (FilmCollapseError) rather
            # than the stall of whichever setting happened to run last
            H_end = (solver_obj.level_H() if isinstance(solver_obj, FlatMultigrid)
                     else solver_obj.levels[-1].H)
            if rfun is not None and np.all(np.isfinite(H_end)) and float(np.min(H_end)) <= 0.0:
                collapsed = (solver_obj, hist, opts, k_att, k_grid, it)
            # stalled states close to a solution (final scaled residual below
            # POLISH_BEST_BELOW_RESIDUAL, not yet polished) for the polish below
            rr = hist["reynolds_residual"]
            if (compiled and rr and math.isfinite(rr[-1]) and "newton_polish_rounds" not in hist
                    and "newton_polish_early_rounds" not in hist and "hit_max_cycles" not in hist
                    and rr[-1] < POLISH_BEST_BELOW_RESIDUAL
                    and solver_obj.opts.get("order2", 1) and not solver_obj.opts.get("defect", 0)
                    ):
                best.append((rr[-1], k_att, solver_obj, hist, opts, it))
        # every setting failed on this grid: polish the stalled states, lowest
        # residual first, until one converges (docs/ehl.md "Newton polish of the
        # spike region": Barus M = 500, L = 15 converges only from setting 5's
        # state, whose residual is not the lowest)
        for _, b_att, b_obj, b_hist, b_opts, b_it in sorted(best, key=lambda t: t[:2]):
            if converged:
                break
            ok, nr, ph = _polish(b_obj, tol_pressure, tol_load, tol_residual, tol_film,
                                 max_cycles)
            if ok:
                b_hist["newton_polish_from_cycle"] = [b_it]
                b_hist["newton_polish_rounds"] = [nr]
                for k_ in _HIST_KEYS:
                    b_hist[k_].extend(ph[k_])
                solver_obj, hist, opts, k_att, it = b_obj, b_hist, b_opts, b_att, b_it + nr
                converged = True
        if converged:
            break
    if not converged and collapsed is not None:
        solver_obj, hist, opts, k_att, k_grid, it = collapsed
    if len(grids) > n_default:
        hist["grid_refined"] = [1.0 if k_grid >= n_default else 0.0]
    if 0 < k_grid < n_default:
        hist["coarse_grid_retry"] = [float(n_coarse)]
    hist["settings"] = opts
    hist["attempt"] = k_att
    if isinstance(solver_obj, FlatMultigrid):
        X = solver_obj.X[solver_obj.top]
        H = solver_obj.level_H().copy()
        P_top = solver_obj.level_P().copy()
        rough_top = solver_obj.rough[solver_obj._sl(solver_obj.top)]
        load_top = solver_obj.load()
    else:
        top = solver_obj.levels[-1]
        X, H, P_top, rough_top, load_top = top.X, top.H, top.P, top.rough, top.load()
    x_m = X * b_m
    h_m = H / scale_H
    rough_m = rough_top / scale_H
    imin = int(np.argmin(h_m))
    sigma_m = float(np.std(rough_m)) if rfun is not None else 0.0
    # smooth surfaces: a film <= 0 left by a setting that did not converge is a
    # diverged iterate, not a collapse of the full film -> EHLConvergenceError below
    if np.all(np.isfinite(h_m)) and h_m[imin] <= 0.0 and (converged or rfun is not None):
        lam_f = h_m[imin] / sigma_m if sigma_m > 0 else float("-inf")
        raise FilmCollapseError(
            f"film collapse: h = {h_m[imin]:.3e} m <= 0 at x = {x_m[imin]:.4e} m "
            f"(X = {X[imin]:.3f}); film parameter lambda = h_min/sigma = {lam_f:.3f} "
            f"(sigma = {sigma_m:.3e} m); the full-film model (seed 000) does not hold",
            x_m=float(x_m[imin]), film_parameter=float(lam_f), h_min_m=float(h_m[imin]))
    if not converged:
        last, name, val, tol = stalled_residual(hist, tol_pressure, tol_residual, tol_load)
        fin = [t_ for t_ in tried if math.isfinite(t_[3])]
        b_ = min(fin, key=lambda t_: t_[3]) if fin else None
        best_txt = (f"; best stalled scaled residual {b_[3]:.2e} (attempt {b_[2]}, "
                    f"{b_[0]}/{b_[1]} intervals)" if b_ else "")
        raise EHLConvergenceError(
            f"EHL multigrid did not converge in {it} W-cycles (M={M:.4g}, L={L:.4g}): "
            f"residual '{name}' stalled at {val:.3e} (tolerance {tol:.1e}); "
            f"reynolds_residual={last['reynolds_residual']:.3e}{best_txt}; "
            f"{len(tried)} setting(s) on {len({t_[:2] for t_ in tried})} grid(s) tried in "
            f"{time.perf_counter() - t_start:.2f} s"
            + "".join(f"; {x}" for x in skipped),
            residual_name=name, value=val, history=hist,
            best_residual=b_[3] if b_ else float("nan"), attempts=tried, skipped=skipped)

    # central film: linear interpolation at X = 0
    h_c = float(np.interp(0.0, X, h_m))
    s2U = math.sqrt(2.0 * U)
    p_Pa = P_top * ph_Pa
    return LineContactResult(
        x_m=x_m, X=X.copy(), p_Pa=p_Pa, P=P_top.copy(), h_m=h_m, H=H.copy(),
        h_central_m=h_c, h_min_m=float(h_m[imin]), x_min_m=float(x_m[imin]),
        H_central_moes=h_c / R_m / s2U, H_min_moes=float(h_m[imin]) / R_m / s2U,
        M=M, L=L, b_m=b_m, ph_Pa=ph_Pa, load_N_per_m=float(load_top * ph_Pa * b_m),
        iterations=it, residuals=hist, converged=True,
        grid_levels=n_levels,
        inputs=dict(R_m=R_m, E_Pa=E_Pa, w_N_per_m=w_N_per_m, u_m_s=u_m_s,
                    eta0_Pas=eta0_Pas, alpha_Pa_inv=alpha_Pa_inv, rho0_kg_m3=rho0_kg_m3),
        roughness_m=rough_m, wall_time_s=time.perf_counter() - t_start)
