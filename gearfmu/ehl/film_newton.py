"""Coupled Newton-Raphson of the finest grid: pressure and H0 together (rough films).

Why (docs/ehl.md "Rough films"): a W-M roughness wave in the strongly
piezoviscous film of the gear contact (L ~ 20) makes a local pressure spike
of its own wherever the gap converges in the inlet or the Hertz zone -- a
micro-EHL contact a few grid spacings wide in which eps/dX^2 falls by five or
six orders of magnitude between neighbouring nodes.  There the point
relaxation (Gauss-Seidel / distributive Jacobi) and the load balance that
moves H0 after the pressures are two separate iterations coupled through a
spike that carries a large part of the load: the spike pressure and H0
oscillate against each other (pressure change 1e-2 .. 1e-1 per cycle, load
error up to 30 %, the largest scaled residual on the 3-5 nodes of the spike;
residual histories in docs/ehl.md), whatever the relaxation factors, cycle
type, coarsest grid or finest grid.  The discrete equations have a solution:
Newton's method on all of them at once finds it in a few steps.

The system: for every interior node i of the free set F (pressurised nodes,
and nodes at P = 0 whose Newton update would be positive) the discrete
Reynolds equation L_i(P, H0) = f_i of :mod:`.mgkernels` (central Poiseuille
term, second-order upstream wedge term, film through the exact deformation
kernel), and the load balance dX sum P = pi/2.  The Jacobian is dense
(deformation integral) and exact: dL_i/dP_j through the film H (kernel), the
density, eps = rho H^3/(eta lambda) (its viscosity, density and film
dependence) and the Poiseuille stencil, dL_i/dH0 through H.  This is the
coupled Newton-Raphson of Houpert & Hamrock (1986, J. Tribol. 108, 411-420:
"Fast approach for calculating film thicknesses and pressures in
elastohydrodynamically lubricated contacts at high loads"), started here from
a few multigrid cycles instead of from the Hertzian pressure.  Cavitation:
a node at P = 0 enters F when its point update would be positive; far from
the solution a node that the step sends below zero is clipped to P = 0,
near it (scaled residual below :data:`NEWTON_ACTIVE_SET_BELOW`) it is set to
zero inside the step and the system solved again (:func:`_active_set_step`).
Globalisation: backtracking (at most :data:`NEWTON_LINE_SEARCH` halvings) on
the mean square of the diagonally scaled residual plus the squared relative
load error -- over the free set near the solution (the Newton direction is a
descent direction of it), over the pressurised nodes far from it -- from a
first step limited to :data:`NEWTON_MAX_LN_EPS` in ln(eps) through the
viscosity.  Dense LU (:func:`.coarse_newton._lu_solve`, single-threaded).
"""
from __future__ import annotations

import math

import numpy as np

from .coarse_newton import _lu_solve
from .mgcycle import _scaled_residual
from .mgkernels import _coef, _residual

#: finest grids with at most this many nodes use the coupled Newton (dense LU, O(n^3))
NEWTON_MAX_NODES = 1025
#: Newton steps at most per call
NEWTON_MAX_STEPS = 30
#: step halvings of the line search at most
NEWTON_LINE_SEARCH = 12
#: active-set corrections per Newton step at most (:func:`_active_set_step`), used
#: below this mean scaled residual (far from the solution full steps overshoot and
#: would drop nodes that are pressurised at the solution: measured on the default
#: scene's level-3 films, before the trust region and the amplitude-step retry: 6 of
#: 297 failed with the correction always on, 2 with it only below this residual)
NEWTON_ACTIVE_SET_ROUNDS = 4
NEWTON_ACTIVE_SET_BELOW = 1e-4
#: trust region of a Newton step: at most this change of ln(eps) through the viscosity
#: and density at any free node (level-3 films failed before the amplitude-step retry:
#: 11 of 297 with 1, 2 with 3, 1 with 6)
NEWTON_MAX_LN_EPS = 6.0

HIST_KEYS = ("pressure_change", "load_balance", "reynolds_residual", "H_central", "H_min",
             "film_change")


def _terms(solver):
    """Film, coefficients and residual f - L(P, H) of the finest grid: (r, eps, dle, rho, drho)."""
    t = solver.top
    P, H, f, tauH, base, rho, eps, dle, drho, delta, wrk = solver.state()[:11]
    solver.update_film(t)
    _coef(t, P, H, rho, eps, dle, drho, solver.iarr, solver.prmv)
    _residual(t, P, H, f, rho, eps, wrk, solver.iarr, solver.dx, solver.optv[3] > 0, 0.0)
    sl = solver._sl(t)
    return wrk[sl].copy(), eps[sl].copy(), dle[sl].copy(), rho[sl].copy(), drho[sl].copy()


def jacobian(solver, eps, dle, rho, drho):
    """(J, a): the dense dL_i/dP_j of the interior nodes (i, j = 1 .. n-2 of the
    finest grid) and dL_i/dH0, for the current P and H (L = Poiseuille - wedge,
    discretised as :func:`.mgkernels._residual`)."""
    t = solver.top
    sl = solver._sl(t)
    P = solver.P[sl]
    H = solver.H[sl]
    n = P.size
    dX = float(solver.dx[t])
    h2 = dX * dX
    ko = int(solver.iarr[2, t])
    Kt = solver.K[ko:ko + n]
    idx = np.arange(n)
    dH = Kt[np.abs(idx[:, None] - idx[None, :])] * (-1.0 / math.pi)    # dH_k/dP_j
    I = np.arange(1, n - 1)
    rr = np.arange(n - 2)
    # wedge coefficients per row: second-order upstream, first order at the first interior node
    c = np.empty((n - 2, 3))
    if solver.optv[3] > 0:
        c[:] = (1.5, -2.0, 0.5)
        c[0] = (1.0, -1.0, 0.0)
    else:
        c[:] = (1.0, -1.0, 0.0)
    J = np.zeros((n - 2, n))
    a = np.zeros(n - 2)
    for m in range(3):
        k = I - m
        cm_ = c[:, m] / dX
        J -= (cm_ * rho[k])[:, None] * dH[k]
        J[rr, k] -= cm_ * H[k] * drho[k]
        a -= cm_ * rho[k]
    em = 0.5 * (eps[I - 1] + eps[I])
    ep = 0.5 * (eps[I] + eps[I + 1])
    J[rr, I - 1] += em / h2
    J[rr, I] -= (em + ep) / h2
    J[rr, I + 1] += ep / h2
    cmv = (P[I - 1] - P[I]) / (2.0 * h2)
    cpv = (P[I + 1] - P[I]) / (2.0 * h2)
    for off, cc in ((-1, cmv), (0, cmv + cpv), (1, cpv)):
        k = I + off
        g3 = 3.0 * eps[k] / np.maximum(H[k], 1e-300)
        g3 = np.where(H[k] > 0.0, g3, 0.0)
        J += (cc * g3)[:, None] * dH[k]
        J[rr, k] += cc * eps[k] * dle[k]
        a += cc * g3
    return J[:, 1:n - 1], a


def coupled_newton(solver, tol_pressure, tol_load, tol_residual, max_steps=NEWTON_MAX_STEPS):
    """Coupled Newton steps on the finest grid of ``solver`` (a
    :class:`.multigrid.FlatMultigrid`, steady) until the state meets the
    solver's convergence test: scaled Reynolds residual (mean over pressurised
    nodes, :func:`.mgcycle._scaled_residual`) below ``tol_residual``, relative
    load error below ``tol_load`` and relative L1 pressure change of the last
    step below ``tol_pressure`` (the test after a cycle, :func:`.mgcycle._iterate`).
    Returns (converged, steps,
    history with the keys of :data:`HIST_KEYS`, one entry per step); a step
    whose line search fails ends the call with the state of the last accepted
    step."""
    t = solver.top
    sl = solver._sl(t)
    dX = float(solver.dx[t])
    order2 = solver.optv[3] > 0
    n = solver.P[sl].size
    i0 = int(round(-solver.prm.x_in / dX))
    hist = {k: [] for k in HIST_KEYS}
    dp_last = math.inf
    prev = None
    for step in range(max_steps + 1):
        r, eps, dle, rho, drho = _terms(solver)
        P = solver.P[sl]
        H = solver.H[sl]
        J, a = jacobian(solver, eps, dle, rho, drho)
        ri = r[1:n - 1]
        Pi = P[1:n - 1]
        diag = np.diag(J).copy()
        diag[diag == 0.0] = -1.0
        upd = ri / diag                                   # point-Newton update per node
        res0 = float(_scaled_residual(t, solver.state(), order2, False))
        g = 0.5 * math.pi - dX * float(np.sum(P))
        w0 = abs(g) / (0.5 * math.pi)
        hc, hm = float(H[i0]), float(np.min(H))
        if step > 0:
            dh = 1.0 if prev is None else max(abs(hc - prev[0]) / max(abs(hc), 1e-300),
                                              abs(hm - prev[1]) / max(abs(hm), 1e-300))
            for k_, v in zip(HIST_KEYS, (dp_last, w0, res0, hc, hm, dh)):
                hist[k_].append(v)
        prev = (hc, hm)
        if not (math.isfinite(res0) and math.isfinite(w0)):
            return False, step, hist
        if res0 < tol_residual and w0 < tol_load and dp_last < tol_pressure:
            return True, step, hist
        if step == max_steps:
            break
        near = res0 < NEWTON_ACTIVE_SET_BELOW
        d, F, D = _active_set_step(J, a, ri, Pi, g, dX, (Pi > 0.0) | (upd > 0.0),
                                   NEWTON_ACTIVE_SET_ROUNDS if near else 1)
        if d is None:
            return False, step, hist
        m = F.size
        P0 = P.copy()
        H00 = float(solver.H0[t])
        sc = 1.0 / np.abs(diag)

        def merit(Pv, rv):
            # near the solution over the free set of this step (fixed during the line
            # search: the Newton direction is a descent direction of this sum), far
            # from it over the pressurised nodes (the full steps clip nodes at zero)
            on = (1 + F) if near else np.nonzero(Pv[1:n - 1] > 0.0)[0] + 1
            e = rv[on] * sc[on - 1]
            gl = (0.5 * math.pi - dX * float(np.sum(Pv))) / (0.5 * math.pi)
            return float(np.mean(e * e)) + gl * gl if e.size else math.inf

        m0 = merit(P0, r)
        # trust region: at most NEWTON_MAX_LN_EPS change of ln(eps) through the viscosity
        # and density at any free node (the exponential viscosity makes larger steps
        # leave the region where the linear model holds)
        big = float(np.max(np.abs(d[:m] * dle[1 + F]), initial=0.0))
        lam = min(1.0, NEWTON_MAX_LN_EPS / big) if big > 0.0 else 1.0
        accepted = False
        for _ in range(NEWTON_LINE_SEARCH):
            Pn = P0.copy()
            Pn[1 + F] = np.maximum(P0[1 + F] + lam * d[:m], 0.0)
            Pn[1 + D] = (1.0 - lam) * P0[1 + D]
            solver.P[sl] = Pn
            solver.H0[t] = H00 + lam * d[m]
            m1 = merit(Pn, _terms(solver)[0])
            if math.isfinite(m1) and m1 < (1.0 - 1e-4 * lam) * m0:
                accepted = True
                break
            lam *= 0.5
        if not accepted:
            solver.P[sl] = P0
            solver.H0[t] = H00
            solver.update_film(t)
            return False, step, hist
        dp_last = float(np.sum(np.abs(solver.P[sl] - P0)) / max(float(np.sum(np.abs(solver.P[sl]))),
                                                                  1e-300))
    return False, max_steps, hist


def _active_set_step(J, a, ri, Pi, g, dX, free, rounds=NEWTON_ACTIVE_SET_ROUNDS):
    """Newton step (dP of the free nodes, dH0) of the coupled system with the
    nodes whose full step would end below zero moved to P = 0 instead (their
    step -P_j enters the right-hand side) and the system solved again, at most
    ``rounds`` times: a node that the step clips at zero is not a Newton
    step, so the line search would shorten every later step (linear
    convergence at rate 1 - lambda).  Returns (d, F, D): d over F then dH0,
    F the free and D the dropped interior nodes (indices 0 .. n-3); d None
    where the system is singular."""
    F = np.nonzero(free)[0]
    D = np.zeros(0, dtype=np.int64)
    d = None
    for k in range(rounds):
        m = F.size
        if m == 0:
            return None, F, D
        A = np.empty((m + 1, m + 1))
        A[:m, :m] = J[np.ix_(F, F)]
        A[:m, m] = a[F]
        A[m, :m] = dX
        A[m, m] = 0.0
        b = np.concatenate([ri[F], [g]])
        if D.size:
            b[:m] += J[np.ix_(F, D)] @ Pi[D]
            b[m] += dX * float(np.sum(Pi[D]))
        d = _lu_solve(A, b)
        if not np.all(np.isfinite(d)):
            return None, F, D
        neg = Pi[F] + d[:m] < 0.0
        if not np.any(neg) or k == rounds - 1:
            break
        D = np.sort(np.concatenate([D, F[neg]]))
        F = F[~neg]
    return d, F, D
