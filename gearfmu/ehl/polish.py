"""Block-Newton polish of the pressure-spike region of the steady EHL solver.

In the strongly piezoviscous corner (high M with high L) the point
relaxations stall at residual floors on the nodes of the pressure spike and
the outlet drop, where eps/dX^2 is tiny and the equation is the film balance
d(rho H)/dX = 0 coupled through the deformation integral: a local problem
with a dense Jacobian.  Venner & Lubrecht 2000 name line/block relaxation for
it; :func:`block_newton` is the simplest form (a dense Newton step on the
block), :func:`_polish` alternates it with multigrid cycles.
"""
from __future__ import annotations

import math

import numpy as np

from .coarse_newton import _lu_solve as _dense_solve   # dense Gaussian elimination
from .mgcycle import _scaled_residual
from .mgkernels import _coef, _residual


#: Block-Newton polish (docs/ehl.md): a
#: setting that stalls (after its frozen-switch continuation) with a scaled
#: Reynolds residual below this value is continued by rounds of
#: (block Newton on the finest grid, one multigrid cycle).  Chosen from the
#: stalls of the (M, L) corner: those that the polish converges ended at
#: 1.9e-6 .. 5e-6, those it does not at 2e-4 .. 7e-3.
POLISH_BELOW_RESIDUAL = 1e-5
#: a setting whose cycles stall (before its frozen-switch continuation) with a
#: scaled residual below this value is polished first (state restored if the
#: polish fails): Barus M = 100, L = 10 on 2048 intervals floats at 1e-5 ..
#: 2e-5 on its first setting (docs/ehl.md)
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
#: largest Newton block (nodes; dense solve ~ n^3 / 3)
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
    largest scaled Reynolds residual (Zhao et al. 2022 eq 2-6 discretised as in
    :mod:`.multigrid`; H0 and all other nodes fixed).

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
        # single-threaded compiled LU (the threaded LAPACK solves of numpy/scipy
        # compete for the cores with the worker processes)
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
