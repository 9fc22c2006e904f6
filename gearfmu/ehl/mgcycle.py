"""Compiled multigrid cycles of the EHL solver: schedules, convergence loop, options.

A cycle is a precomputed *schedule* of integer codes (:func:`w_schedule`:
+k relax on level k and restrict, 0 solve on the coarsest grid, -k prolong
the correction to level k and relax); :func:`_iterate` runs cycles with the
finest-grid load balance and the convergence test in one compiled call.
Load balance: ``load_mode = 0`` moves H0 on the finest grid after every
cycle (adaptive gain), ``load_mode = 1`` moves H0 on the coarsest grid
inside the cycle with the FAS load right-hand side (Venner & Lubrecht 2000).
``spike_newton`` > 0: after every cycle that many Newton steps on the
finest-grid block of 2 ``spike_width`` + 1 nodes around the largest scaled
residual (:func:`.coarse_newton._spike_newton`; steady only).
The options are passed as one float vector in the order of :data:`OPT_KEYS`.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .coarse_newton import COARSE_NEWTON_MAX_NODES, _coarse_newton, _spike_newton
from .errors import EHLInputError
from .mgkernels import _coef, _down, _film, _load, _relax, _residual, _up


@njit(cache=True, error_model="numpy")
def _run_schedule(sched, S, top_coef_valid=False):
    """One cycle.  With option ``lean`` (default 1) work whose result is never
    read is skipped: (i) the coefficients of a level at its first sweep right
    after the restriction to it (``_down`` computed them from the same P and
    H; also the finest level's when ``top_coef_valid``: the convergence test
    computed them), (ii) the film after the post-sweep of level k when the
    next step prolongs to level k+1 (only P of level k is read there; the next
    restriction to level k recomputes its film).  Bitwise the same iterates
    (tested); ~10 % less CPU per cycle (docs/ehl.md)."""
    opt = S[25]
    lean = opt[17] > 0.5
    ns = sched.shape[0]
    for idx in range(ns):
        code = sched[idx]
        prev = sched[idx - 1] if idx > 0 else -1
        if code > 0:
            valid = lean and ((idx > 0 and prev == code + 1) or (idx == 0 and top_coef_valid))
            _down(code, S, valid)
        elif code == 0:
            cv = lean and idx > 0 and prev == 1
            if opt[18] > 0.5 and opt[15] == 0.0 and S[14][1, 0] <= COARSE_NEWTON_MAX_NODES:
                _coarse_newton(int(opt[18]), opt[11] > 0.5, S, cv)
            else:
                _relax(0, int(opt[10]), opt[11] > 0.5, S, cv)
        else:
            nxt = sched[idx + 1] if idx + 1 < ns else 0
            _up(-code, S, not (lean and nxt == code - 1))


@njit(cache=True, error_model="numpy")
def _scaled_residual(l, S, order2, zero_f):
    """Mean over pressurised nodes of |r_i / (dL_i/dP_i)| (units of p_h);
    ``zero_f``: residual of the undisturbed equation (f = 0)."""
    (P, H, f, tauH, base, rho, eps, dle, drho, delta, wrk, Pold, H0, g, iarr, dx, K, khr, khi,
     twr, twi, re, im, V, prm, opt, H0old, mode) = S
    o = iarr[0, l]
    n = iarr[1, l]
    ko = iarr[2, l]
    _coef(l, P, H, rho, eps, dle, drho, iarr, prm)
    if zero_f:
        o2 = iarr[0, l]
        for k in range(iarr[1, l]):
            delta[o2 + k] = 0.0
        _residual(l, P, H, delta, rho, eps, wrk, iarr, dx, order2, opt[15], opt[16] > 0.5)
    else:
        _residual(l, P, H, f, rho, eps, wrk, iarr, dx, order2, opt[15], opt[16] > 0.5)
    dX = dx[l]
    h2 = dX * dX
    s = 0.0
    cnt = 0
    for k in range(1, n - 1):
        i = o + k
        if P[i] <= 0.0:
            continue
        em = 0.5 * (eps[i - 1] + eps[i])
        ep = 0.5 * (eps[i] + eps[i + 1])
        J = -(em + ep) / h2 + rho[i] * (K[ko] - K[ko + 1]) / (math.pi * dX)
        if opt[15] != 0.0:
            J += opt[15] * rho[i] * K[ko] / math.pi
        s += abs(wrk[i] / J)
        cnt += 1
    return s / max(cnt, 1)


@njit(cache=True, error_model="numpy")
def _iterate(sched, S, hist, max_cycles, min_cycles, tol_p, tol_w, tol_r, tol_f,
             stall_window, tol_d, tol_dr=math.inf, tol_dw=math.inf):
    """Cycles until converged (returns +cycles) or stalled/failed (-cycles).

    hist[:, k] = (pressure change, load error, scaled residual, central film,
    minimum film, relative film change) of cycle k (films in Venner-Lubrecht
    units, central = node at X = 0); converged when the first three and the
    relative change of the central and minimum films are below tol_p, tol_w,
    tol_r, tol_f -- or, with ``tol_d`` > 0, when the relative film change and
    the load error are both below tol_d, the scaled residual below ``tol_dr``
    and the load error below ``tol_dw`` (stop at the discretisation error).
    With a finite ``tol_dw``, a state at that stop but for a load error
    between tol_dw and tol_d has its finest-grid pressure scaled to the load
    and is evaluated again (load projection)."""
    (P, H, f, tauH, base, rho, eps, dle, drho, delta, wrk, Pold, H0, g, iarr, dx, K, khr, khi,
     twr, twi, re, im, V, prm, opt, H0old, mode) = S
    nl = iarr.shape[1]
    top = nl - 1
    o = iarr[0, top]
    n = iarr[1, top]
    Pprev = np.empty(n)
    c_cur = opt[6]
    dprev = 0.0
    load_mode = opt[11] > 0.5
    defect = opt[12] > 0.5
    i0 = int(round(-prm[6] / dx[top]))
    for cyc in range(max_cycles):
        for k in range(n):
            Pprev[k] = P[o + k]
        g[top] = 0.5 * math.pi
        if defect:
            # defect correction (Venner & Lubrecht 2000): the cycles relax the
            # first-order upstream operator L1 with f = L1(P) - L2(P), so that
            # a fixed point solves the second-order equation L2(P) = 0
            for k in range(n):
                f[o + k] = 0.0
            _coef(top, P, H, rho, eps, dle, drho, iarr, prm)
            _residual(top, P, H, f, rho, eps, wrk, iarr, dx, True)      # -L2
            _residual(top, P, H, f, rho, eps, delta, iarr, dx, False)   # -L1
            for k in range(1, n - 1):
                f[o + k] = wrk[o + k] - delta[o + k]
        # after the first cycle the convergence test below left the finest
        # level's coefficients valid for the current P, H (lean option)
        _run_schedule(sched, S, cyc > 0)
        if not load_mode or nl == 1:
            err = 0.5 * math.pi - _load(top, P, iarr, dx)
            dH0 = -c_cur * err
            scale = max(H[o + i0], 0.2 * prm[8])
            lim = opt[7] * scale
            if dH0 > lim:
                dH0 = lim
            elif dH0 < -lim:
                dH0 = -lim
            if dH0 * dprev < 0.0 and abs(dH0) > 0.5 * abs(dprev):
                c_cur *= 0.5
            elif dH0 * dprev > 0.0:
                c_cur = min(c_cur * 1.5, opt[6])
            dprev = dH0
            H0[top] += dH0
            _film(top, P, H, base, tauH, H0, iarr, K, khr, khi, twr, twi, re, im, V)
        if opt[19] > 0.5 and opt[15] == 0.0:
            _spike_newton(int(opt[19]), int(opt[20]), S)
        for ev in range(2):
            sp = 0.0
            dp = 0.0
            for k in range(n):
                sp += abs(P[o + k])
                dp += abs(P[o + k] - Pprev[k])
            dP = dp / max(sp, 1e-300)
            dW = abs(_load(top, P, iarr, dx) - 0.5 * math.pi) / (0.5 * math.pi)
            if defect:
                res = _scaled_residual(top, S, True, True)
            else:
                res = _scaled_residual(top, S, opt[3] > 0, False)
            hist[0, cyc] = dP
            hist[1, cyc] = dW
            hist[2, cyc] = res
            hc = H[o + i0]
            hm = H[o]
            for k in range(1, n):
                if H[o + k] < hm:
                    hm = H[o + k]
            hist[3, cyc] = hc
            hist[4, cyc] = hm
            if cyc > 0:
                dh = max(abs(hc - hist[3, cyc - 1]) / max(abs(hc), 1e-300),
                         abs(hm - hist[4, cyc - 1]) / max(abs(hm), 1e-300))
            else:
                dh = 1.0
            hist[5, cyc] = dh
            if (ev == 0 and cyc + 1 >= min_cycles and dh < tol_d and res < tol_dr
                    and tol_dw <= dW < tol_d):
                # at the discretisation stop but for the load: scale the finest
                # pressure to the load (the film changes by about dW times the
                # deformation, far below tol_d) and evaluate the state again
                c = 0.5 * math.pi / _load(top, P, iarr, dx)
                for k in range(n):
                    P[o + k] *= c
                _film(top, P, H, base, tauH, H0, iarr, K, khr, khi, twr, twi, re, im, V)
                continue
            break
        if not (math.isfinite(dP) and math.isfinite(dW) and math.isfinite(res)):
            return -(cyc + 1)
        if cyc + 1 >= min_cycles and ((dP < tol_p and dW < tol_w and res < tol_r and dh < tol_f)
                                      or (dh < tol_d and dW < tol_d and dW < tol_dw
                                          and res < tol_dr)):
            return cyc + 1
        if cyc + 1 >= 2 * stall_window:
            # stall: neither the change nor the residual fell 3x in the last window
            mr_old = 1e300
            mp_old = 1e300
            for j in range(cyc + 1 - stall_window):
                mr_old = min(mr_old, hist[2, j])
                mp_old = min(mp_old, hist[0, j])
            mr_new = 1e300
            mp_new = 1e300
            for j in range(cyc + 1 - stall_window, cyc + 1):
                mr_new = min(mr_new, hist[2, j])
                mp_new = min(mp_new, hist[0, j])
            if mr_new > mr_old / 3.0 and mp_new > mp_old / 3.0:
                return -(cyc + 1)
    return -max_cycles


def w_schedule(n_levels: int, gamma=2) -> np.ndarray:
    """Integer codes of one multigrid cycle whose finest level is
    n_levels - 1: +k relax on k and go down, 0 coarsest solve, -k come up to
    k and relax.  ``gamma`` = 2: W-cycle, 1: V-cycle, "F": F-cycle (on each
    level an F-cycle then a V-cycle on the next coarser level; Trottenberg,
    Oosterlee & Schueller 2001, *Multigrid*, sec. 2.4: W-cycle-like
    convergence with the coarsest grid visited n_levels - 1 times instead of
    2^(n_levels - 2))."""
    ops = []

    def cyc(k, g):
        if k == 0:
            ops.append(0)
            return
        ops.append(k)
        if k == 1:
            cyc(0, g)
        elif g == "F":
            cyc(k - 1, "F")
            cyc(k - 1, 1)
        else:
            for _ in range(int(g)):
                cyc(k - 1, g)
        ops.append(-k)

    if gamma not in (1, 2, "F"):
        raise EHLInputError(f"gamma={gamma!r}: must be 1 (V-cycle), 2 (W-cycle) or 'F'")
    cyc(n_levels - 1, gamma)
    return np.array(ops, dtype=np.int64)


_SCHEDULES: dict = {}


def cached_schedule(n_levels: int, gamma=2) -> np.ndarray:
    """:func:`w_schedule`, built once per (n_levels, gamma) and read-only (the compiled
    cycles only read it; a write would change every later solve)."""
    key = (int(n_levels), gamma)
    s = _SCHEDULES.get(key)
    if s is None:
        s = w_schedule(n_levels, gamma)
        s.flags.writeable = False     # shared by every solve with these levels
        _SCHEDULES[key] = s
    return s


#: option vector layout of the compiled core
OPT_KEYS = ("omega_gs", "omega_j", "switch", "order2", "dmax", "dist", "c_h0", "h0_step",
            "nu1", "nu2", "nu0", "load_mode", "defect", "stick", "freeze", "c_t", "c_char",
            "lean", "coarse_newton", "spike_newton", "spike_width")
OPT_DEFAULTS = dict(omega_gs=0.8, omega_j=0.6, switch=3.0, order2=1, dmax=0.3, dist=0,
                    c_h0=0.5, h0_step=0.5, nu1=2, nu2=1, nu0=10, load_mode=0,
                    defect=0, stick=1.0, freeze=0, c_t=0.0, c_char=0, lean=1,
                    coarse_newton=0, spike_newton=0, spike_width=6)
