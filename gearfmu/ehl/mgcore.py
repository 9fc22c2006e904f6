"""Compiled FAS multigrid core of the line-contact EHL solver (whole W-cycle in numba).

Same equations and discretisation as :mod:`.multigrid` (seed 000 eq 2-7 in the
Hertzian scaling of Venner & Lubrecht 2000, *Multilevel Methods in
Lubrication*, Elsevier): Reynolds with eps at half nodes, wedge term first- or
second-order upstream, deformation with piecewise-constant pressure
(:mod:`.deformation`), P = max(P, 0) cavitation, load balance dX sum P = pi/2.

What differs from the Python-driven :class:`.multigrid.MultigridSolver` is the
organisation: all levels live in flat arrays (level l at offset ``off[l]``),
a W-cycle is a precomputed *schedule* of integer codes (+k: relax and restrict
from level k; 0: solve on the coarsest grid; -k: prolong the correction to
level k and relax), and the cycle loop with its convergence test runs in one
compiled call.  Coarse levels with at most ``N_DIRECT`` nodes evaluate the
deformation by the direct O(n^2) sum, finer ones by FFT
(:func:`.deformation.conv_real`).  Cycle types: W (default), V and F
(:func:`w_schedule`).

Relaxation (Venner & Lubrecht 2000): point Newton, Gauss-Seidel where
eps_i/dX^2 >= ``switch`` or next to cavitation, distributive Jacobi
elsewhere.  Two distribution patterns are available: ``dist = 1`` the
symmetric pattern of Venner & Lubrecht (P_i += d_i - (d_{i-1} + d_{i+1})/4),
``dist = 0`` the dipole of seed 000 (+d_i at i, -d_i at i-1).  The Jacobians
include the deformation kernel and the density derivative of the wedge term.
Transient term (docs/ehl_transient.md, seed 000 eq 2 with d(rho H)/dT):
option ``c_t`` (default 0) adds c_t (rho H)_i to the wedge term of every
level and its derivative to the point Jacobians; the old time levels enter
as the finest-grid right-hand side f (:meth:`FlatMultigrid.set_time_term`).
With c_t = 0 every branch of the steady code runs unchanged (bitwise).
Load balance: ``load_mode = 0`` moves H0 on the finest grid after every cycle
(adaptive gain), ``load_mode = 1`` moves H0 on the coarsest grid inside the
cycle with the FAS load right-hand side (Venner & Lubrecht's arrangement).

Speed (docs/ehl.md "Lean cycle, faster film FFT and the speed path"): option
``lean`` (default 1) skips work whose result is never read (bitwise the same
iterates); option ``coarse_newton`` = k > 0 solves the coarsest grid by k dense
Newton steps (:func:`_coarse_newton`) instead of ``nu0`` sweeps;
:data:`SPEED_SETTING` (F-cycles + one coarse Newton step) with
:data:`DISC_TOLERANCES` is the opt-in speed path.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit
from scipy import fft as _fft

from .deformation import conv_real, kernel_coefficients, stage_twiddles
from .errors import EHLInputError

#: levels with at most this many nodes use the direct O(n^2) deformation sum
N_DIRECT = 64
#: the coarsest-grid Newton solve (option ``coarse_newton``) is used only up to
#: this many coarsest nodes (dense LU, O(n^3): 65 nodes ~0.1 ms per step);
#: larger coarsest grids keep the point sweeps
COARSE_NEWTON_MAX_NODES = 129


@njit(cache=True)
def _deform(l, P, V, iarr, K, khr, khi, twr, twi, re, im):
    """V = -(1/pi) sum_j K_|i-j| P_j on level l (direct sum or FFT)."""
    o = iarr[0, l]
    n = iarr[1, l]
    ko = iarr[2, l]
    if n <= N_DIRECT:
        for i in range(n):
            s = 0.0
            for j in range(n):
                d = i - j
                if d < 0:
                    d = -d
                s += K[ko + d] * P[o + j]
            V[i] = -s / math.pi
        return
    mo = iarr[3, l]
    m = iarr[4, l]
    to = iarr[5, l]
    h = m // 2 + 1
    # re/im hold 2 (m/2 + 1) entries: packed sequence and product spectrum
    conv_real(P, o, n, khr, mo, m, twr, twi, to, K, ko, re[:h], im[:h], re[h:2 * h],
              im[h:2 * h], V)


@njit(cache=True)
def _film(l, P, H, base, tauH, H0, iarr, K, khr, khi, twr, twi, re, im, V):
    o = iarr[0, l]
    n = iarr[1, l]
    _deform(l, P, V, iarr, K, khr, khi, twr, twi, re, im)
    for i in range(n):
        H[o + i] = H0[l] + base[o + i] + V[i] + tauH[o + i]


@njit(cache=True)
def _coef(l, P, H, rho, eps, dle, drho, iarr, prm):
    """rho, eps = rho H^3/(eta lambda), d ln(eps)/dP and d rho/dP on level l."""
    lam, A, z, php0, c1, comp = prm[0], prm[1], prm[2], prm[3], prm[4], prm[5]
    o = iarr[0, l]
    n = iarr[1, l]
    for i in range(o, o + n):
        p = P[i] if P[i] > 0.0 else 0.0
        dl = 0.0
        r = 1.0
        dr = 0.0
        if comp > 0.0:
            r = (c1 + 1.34 * p) / (c1 + p)
            dl += 1.34 / (c1 + 1.34 * p) - 1.0 / (c1 + p)
            dr = 0.34 * c1 / ((c1 + p) * (c1 + p))
        if z > 0.0:
            q = (1.0 + p * php0) ** z
            eta = math.exp(A * (q - 1.0))
            dl -= A * z * php0 * q / (1.0 + p * php0)
        elif z < 0.0:
            eta = math.exp(A * p)
            dl -= A
        else:
            eta = 1.0
        hh = H[i] if H[i] > 0.0 else 0.0
        rho[i] = r
        drho[i] = dr
        eps[i] = r * hh * hh * hh / (eta * lam)
        dle[i] = dl


@njit(cache=True)
def _residual(l, P, H, f, rho, eps, out, iarr, dx, order2, ct=0.0, char=False):
    """out_i = f_i - L_i(P, H) (interior nodes; 0 at the ends).

    ``ct`` > 0: transient operator (seed 000 eq 2 with d(rho H)/dT, BDF1/BDF2,
    docs/ehl_transient.md): the implicit part ct (rho H)_i is added to the
    wedge term; the old time levels are in f (finest grid).  ct = 0 takes
    the steady code path unchanged (bitwise).  ``char``: characteristic
    scheme (Courant 1): the implicit time term ct (rho H)_i *replaces* the
    wedge term, the shifted old levels are in f."""
    o = iarr[0, l]
    n = iarr[1, l]
    dX = dx[l]
    h2 = dX * dX
    out[o] = 0.0
    out[o + n - 1] = 0.0
    for k in range(1, n - 1):
        i = o + k
        em = 0.5 * (eps[i - 1] + eps[i])
        ep = 0.5 * (eps[i] + eps[i + 1])
        poi = (em * (P[i - 1] - P[i]) + ep * (P[i + 1] - P[i])) / h2
        if k >= 2 and order2:
            wedge = (1.5 * rho[i] * H[i] - 2.0 * rho[i - 1] * H[i - 1]
                     + 0.5 * rho[i - 2] * H[i - 2]) / dX
        else:
            wedge = (rho[i] * H[i] - rho[i - 1] * H[i - 1]) / dX
        if ct != 0.0:
            if char:
                wedge = ct * rho[i] * H[i]
            else:
                wedge += ct * rho[i] * H[i]
        out[i] = f[i] - (poi - wedge)


@njit(cache=True)
def _relax_once(l, P, H, f, rho, eps, dle, drho, delta, iarr, dx, K, opt, mode):
    """One relaxation sweep on level l (P in place; H stale afterwards)."""
    omega_gs, omega_j, switch, order2, dmax, dist = opt[0], opt[1], opt[2], opt[3] > 0, \
        opt[4], opt[5]
    stick = opt[13]
    freeze = opt[14] > 0.5
    ct = opt[15]
    char = opt[16] > 0.5
    top_level = iarr.shape[1] - 1
    o = iarr[0, l]
    n = iarr[1, l]
    ko = iarr[2, l]
    dX = dx[l]
    h2 = dX * dX
    ipi = 1.0 / math.pi
    K0 = K[ko]
    K1 = K[ko + 1]
    K2 = K[ko + 2]
    K3 = K[ko + 3]
    # film change per unit distributed change, c(m) for m = 0, -1, -2
    # symmetric distribution d at i, -q d at i - 1 and i + 1: q = 1/4 (dist = 1,
    # the point-contact weights of Venner & Lubrecht), q = 1/2 (dist = 2: zero
    # net weight in 1-D, so that a change leaves the far film unchanged)
    q = 0.5 if dist > 1.5 else 0.25
    if dist > 0.5:
        c0 = K0 - 2.0 * q * K1
        cm1 = K1 - q * (K0 + K2)
        cm2 = K2 - q * (K1 + K3)
        pm1 = -q
        poifac = 1.0 + 2.0 * q
    else:
        c0 = K0 - K1
        cm1 = K1 - K0
        cm2 = K2 - K1
        pm1 = -1.0
        poifac = 0.0
    for k in range(n):
        delta[o + k] = 0.0
    for k in range(1, n - 1):
        i = o + k
        em = 0.5 * (eps[i - 1] + eps[i])
        ep = 0.5 * (eps[i] + eps[i + 1])
        poi = (em * (P[i - 1] - P[i]) + ep * (P[i + 1] - P[i])) / h2
        sec = k >= 2 and order2
        if sec:
            wedge = (1.5 * rho[i] * H[i] - 2.0 * rho[i - 1] * H[i - 1]
                     + 0.5 * rho[i - 2] * H[i - 2]) / dX
        else:
            wedge = (rho[i] * H[i] - rho[i - 1] * H[i - 1]) / dX
        if ct != 0.0:
            if char:
                wedge = ct * rho[i] * H[i]
            else:
                wedge += ct * rho[i] * H[i]
        r = f[i] - (poi - wedge)
        xtra = -abs(0.5 * eps[i] * dle[i] * (P[i - 1] - 2.0 * P[i] + P[i + 1]) / h2)
        # hysteresis (``stick`` >= 1): a node relaxed by Jacobi stays Jacobi
        # until eps/dX^2 exceeds stick * switch (prevents switching limit cycles)
        thr = switch * stick if mode[i] == 1 else switch
        gs = eps[i] / h2 >= thr or P[i - 1] <= 0.0 or P[i + 1] <= 0.0 or P[i] <= 0.0
        if freeze and l == top_level:
            # frozen switch (finest grid): keep the relaxation type of each node
            gs = mode[i] == 0
        mode[i] = 0 if gs else 1
        if gs:
            if sec:
                w = (1.5 * rho[i] * K0 - 2.0 * rho[i - 1] * K1 + 0.5 * rho[i - 2] * K2) * ipi
                w = (w - 1.5 * H[i] * drho[i]) / dX
            else:
                w = ((rho[i] * K0 - rho[i - 1] * K1) * ipi - H[i] * drho[i]) / dX
            if ct != 0.0:
                # d[ct rho_i H_i]/dP_i with dH_i/dP_i = -K0/pi (time term)
                if char:
                    w = 0.0
                w += ct * (rho[i] * K0 * ipi - H[i] * drho[i])
            J = -(em + ep) / h2 + w + xtra
            d = omega_gs * r / J
            if abs(d * dle[i]) > dmax:
                d = math.copysign(dmax / abs(dle[i]), d)
            newp = P[i] + d
            if newp < 0.0:
                newp = 0.0
            P[i] = newp
        else:
            if sec:
                w = (1.5 * rho[i] * c0 - 2.0 * rho[i - 1] * cm1 + 0.5 * rho[i - 2] * cm2) * ipi
                w -= 1.5 * H[i] * drho[i] - 2.0 * H[i - 1] * drho[i - 1] * pm1
            else:
                w = (rho[i] * c0 - rho[i - 1] * cm1) * ipi
                w -= H[i] * drho[i] - H[i - 1] * drho[i - 1] * pm1
            w /= dX
            if ct != 0.0:
                # time term: film change -c0/pi and density change at i per unit d
                if char:
                    w = 0.0
                w += ct * (rho[i] * c0 * ipi - H[i] * drho[i])
            if dist > 0.5:
                Jp = -poifac * (em + ep) / h2
            else:
                Jp = -(2.0 * em + ep) / h2
            J = Jp + w + xtra
            d = omega_j * r / J
            if abs(d * dle[i]) > dmax:
                d = math.copysign(dmax / abs(dle[i]), d)
            delta[i] = d
    if dist > 0.5:
        for k in range(1, n - 1):
            i = o + k
            d = delta[i] - q * (delta[i - 1] + delta[i + 1])
            if d != 0.0 and P[i] > 0.0:
                P[i] += d
    else:
        for k in range(1, n - 1):
            i = o + k
            d = delta[i]
            if d != 0.0:
                P[i] += d
                P[i - 1] -= d
    P[o] = 0.0
    P[o + n - 1] = 0.0
    for k in range(n):
        if P[o + k] < 0.0:
            P[o + k] = 0.0


@njit(cache=True)
def _relax(l, sweeps, load_here, S, coef_valid=False, last_film=True):
    """``sweeps`` relaxation sweeps on level l, each followed by a film update.
    ``coef_valid``: rho, eps, dle, drho of level l already belong to the current
    P and H (the first sweep does not recompute them); ``last_film`` = False:
    the film after the last sweep is not computed (the caller never reads it).
    Both only skip work whose result is not used or already there, so the
    iterates are bitwise the same (``lean`` option, docs/ehl.md "Speed")."""
    (P, H, f, tauH, base, rho, eps, dle, drho, delta, wrk, Pold, H0, g, iarr, dx, K, khr, khi,
     twr, twi, re, im, V, prm, opt, H0old, mode) = S
    o = iarr[0, l]
    n = iarr[1, l]
    for s_ in range(sweeps):
        if s_ > 0 or not coef_valid:
            _coef(l, P, H, rho, eps, dle, drho, iarr, prm)
        _relax_once(l, P, H, f, rho, eps, dle, drho, delta, iarr, dx, K, opt, mode)
        if load_here:
            # load balance on this (coarsest) grid: H0 against the load error
            s = 0.0
            for k in range(n):
                s += P[o + k]
            err = g[l] - dx[l] * s
            i0 = int(round(-prm[6] / dx[l]))
            Hc = H[o + i0]
            scale = max(Hc, 0.2 * prm[8])
            dH0 = -opt[6] * err
            lim = opt[7] * scale
            if dH0 > lim:
                dH0 = lim
            elif dH0 < -lim:
                dH0 = -lim
            H0[l] += dH0
        if s_ < sweeps - 1 or last_film:
            _film(l, P, H, base, tauH, H0, iarr, K, khr, khi, twr, twi, re, im, V)


@njit(cache=True)
def _load(l, P, iarr, dx):
    o = iarr[0, l]
    n = iarr[1, l]
    s = 0.0
    for k in range(n):
        s += P[o + k]
    return dx[l] * s


@njit(cache=True)
def _down(k, S, coef_valid=False):
    """Pre-relax on level k and set up the FAS problem on level k-1 (whose
    coefficients are left valid for the current P and H on return)."""
    (P, H, f, tauH, base, rho, eps, dle, drho, delta, wrk, Pold, H0, g, iarr, dx, K, khr, khi,
     twr, twi, re, im, V, prm, opt, H0old, mode) = S
    nu1 = int(opt[8])
    _relax(k, nu1, False, S, coef_valid)
    of = iarr[0, k]
    nf = iarr[1, k]
    oc = iarr[0, k - 1]
    nc = iarr[1, k - 1]
    order2 = opt[3] > 0
    _coef(k, P, H, rho, eps, dle, drho, iarr, prm)
    _residual(k, P, H, f, rho, eps, wrk, iarr, dx, order2, opt[15], opt[16] > 0.5)
    for i in range(nf):
        if P[of + i] <= 0.0:
            wrk[of + i] = 0.0
    for I in range(nc):
        P[oc + I] = P[of + 2 * I]
        Pold[oc + I] = P[oc + I]
        tauH[oc + I] = 0.0
    H0[k - 1] = H0[k]
    _film(k - 1, P, H, base, tauH, H0, iarr, K, khr, khi, twr, twi, re, im, V)
    for I in range(nc):
        tauH[oc + I] = H[of + 2 * I] - H[oc + I]
        H[oc + I] = H[of + 2 * I]
    if opt[17] > 0.5:
        # lean: P and H of level k-1 are now the fine values at the even nodes,
        # whose coefficients _coef(k) computed just above -- inject them (the
        # coefficients are pointwise functions of P_i, H_i: bitwise the same)
        for I in range(nc):
            rho[oc + I] = rho[of + 2 * I]
            eps[oc + I] = eps[of + 2 * I]
            dle[oc + I] = dle[of + 2 * I]
            drho[oc + I] = drho[of + 2 * I]
    else:
        _coef(k - 1, P, H, rho, eps, dle, drho, iarr, prm)
    # f_c = L_c(P_c) + restricted residual  (wrk on level k-1 receives f_c - L_c = -(-r))
    for I in range(nc):
        f[oc + I] = 0.0
    _residual(k - 1, P, H, f, rho, eps, wrk, iarr, dx, order2, opt[15], opt[16] > 0.5)   # wrk_c = -L_c
    for I in range(1, nc - 1):
        i = of + 2 * I
        rr = 0.25 * wrk[i - 1] + 0.5 * wrk[i] + 0.25 * wrk[i + 1]
        f[oc + I] = -wrk[oc + I] + rr
    f[oc] = 0.0
    f[oc + nc - 1] = 0.0
    g[k - 1] = g[k] + _load(k - 1, P, iarr, dx) - _load(k, P, iarr, dx)
    H0old[k - 1] = H0[k - 1]


@njit(cache=True)
def _up(k, S, last_film=True):
    """Prolong the level k-1 correction to level k and post-relax
    (``last_film`` = False: no film update after the last sweep)."""
    (P, H, f, tauH, base, rho, eps, dle, drho, delta, wrk, Pold, H0, g, iarr, dx, K, khr, khi,
     twr, twi, re, im, V, prm, opt, H0old, mode) = S
    of = iarr[0, k]
    nf = iarr[1, k]
    oc = iarr[0, k - 1]
    for i in range(1, nf - 1):
        if i % 2 == 0:
            c = P[oc + i // 2] - Pold[oc + i // 2]
        else:
            j = i // 2
            c = 0.5 * (P[oc + j] - Pold[oc + j] + P[oc + j + 1] - Pold[oc + j + 1])
        if P[of + i] > 0.0:
            P[of + i] += c
            if P[of + i] < 0.0:
                P[of + i] = 0.0
    H0[k] += H0[k - 1] - H0old[k - 1]
    _film(k, P, H, base, tauH, H0, iarr, K, khr, khi, twr, twi, re, im, V)
    _relax(k, int(opt[9]), False, S, False, last_film)


@njit(cache=True)
def _lu_solve(A, b):
    """x with A x = b, Gaussian elimination with partial pivoting (A, b
    overwritten); NaN where A is singular."""
    n = b.size
    for k in range(n):
        p = k
        amax = abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > amax:
                amax = abs(A[i, k])
                p = i
        if amax == 0.0:
            b[:] = np.nan
            return b
        if p != k:
            for j in range(n):
                t = A[k, j]
                A[k, j] = A[p, j]
                A[p, j] = t
            t = b[k]
            b[k] = b[p]
            b[p] = t
        inv = 1.0 / A[k, k]
        for i in range(k + 1, n):
            m = A[i, k] * inv
            if m != 0.0:
                for j in range(k + 1, n):
                    A[i, j] -= m * A[k, j]
                b[i] -= m * b[k]
    for k in range(n - 1, -1, -1):
        s = b[k]
        for j in range(k + 1, n):
            s -= A[k, j] * b[j]
        b[k] = s / A[k, k]
    return b


@njit(cache=True)
def _coarse_jacobian(S, act, na, load_here):
    """Newton system of :func:`_coarse_newton` on level 0: J (dense, unknowns
    P of the nodes ``act[:na]`` then H0 if ``load_here``) and b = -residual,
    with the coefficients (``_coef``) and the residual r = f - L (``wrk``,
    ``_residual``) of the current state already computed."""
    (P, H, f, tauH, base, rho, eps, dle, drho, delta, wrk, Pold, H0, g, iarr, dx, K, khr, khi,
     twr, twi, re, im, V, prm, opt, H0old, mode) = S
    o = iarr[0, 0]
    n = iarr[1, 0]
    ko = iarr[2, 0]
    dX = dx[0]
    h2 = dX * dX
    order2 = opt[3] > 0
    ipi = 1.0 / math.pi
    m = na + 1 if load_here else na
    J = np.empty((m, m))
    b = np.empty(m)
    col = np.full(n, -1, dtype=np.int64)        # node -> column of the system
    for c in range(na):
        col[act[c]] = c
    for a in range(na):
        k = act[a]
        i = o + k
        em = 0.5 * (eps[i - 1] + eps[i])
        ep = 0.5 * (eps[i] + eps[i + 1])
        cm = 0.5 * (P[i - 1] - P[i]) / h2
        cp = 0.5 * (P[i + 1] - P[i]) / h2
        if order2 and k >= 2:
            w0, w1, w2 = 1.5 / dX, -2.0 / dX, 0.5 / dX
        else:
            w0, w1, w2 = 1.0 / dX, -1.0 / dX, 0.0
        b[a] = -wrk[i]
        # 3 eps_j / H_j for j = i-1, i, i+1 (0 where the film is closed)
        e3m = 3.0 * eps[i - 1] / H[i - 1] if H[i - 1] > 0.0 else 0.0
        e3 = 3.0 * eps[i] / H[i] if H[i] > 0.0 else 0.0
        e3p = 3.0 * eps[i + 1] / H[i + 1] if H[i + 1] > 0.0 else 0.0
        # film part: dr_i/dP_kk = sum_j A_j dH_j/dP_kk, dH_j/dP_kk = -K_|j-kk|/pi
        # (Poiseuille through eps_j ~ H_j^3 for j = i-1..i+1, wedge through
        # rho_j H_j for j = i-2..i)
        A0 = (-(cm + cp) * e3 + w0 * rho[i]) * ipi
        A1 = (-cm * e3m + w1 * rho[i - 1]) * ipi
        A2 = (w2 * rho[i - 2]) * ipi if k >= 2 else 0.0
        Ap = (-cp * e3p) * ipi
        for c in range(na):
            kk = act[c]
            J[a, c] = -(A2 * K[ko + abs(k - 2 - kk)] + A1 * K[ko + abs(k - 1 - kk)]
                        + A0 * K[ko + abs(k - kk)] + Ap * K[ko + abs(k + 1 - kk)])
        # local part: Poiseuille coefficients, d eps/dP and d rho/dP of the node
        c = col[k]
        J[a, c] += -(cm + cp) * eps[i] * dle[i] + (em + ep) / h2 + w0 * drho[i] * H[i]
        if k - 1 >= 0 and col[k - 1] >= 0:
            J[a, col[k - 1]] += -cm * eps[i - 1] * dle[i - 1] - em / h2 \
                + w1 * drho[i - 1] * H[i - 1]
        if k + 1 < n and col[k + 1] >= 0:
            J[a, col[k + 1]] += -cp * eps[i + 1] * dle[i + 1] - ep / h2
        if k - 2 >= 0 and col[k - 2] >= 0:
            J[a, col[k - 2]] += w2 * drho[i - 2] * H[i - 2]
        if load_here:
            J[a, na] = -(cm * (e3m + e3) + cp * (e3 + e3p)) + w0 * rho[i] + w1 * rho[i - 1] \
                + (w2 * rho[i - 2] if k >= 2 else 0.0)
    if load_here:
        s = 0.0
        for k in range(n):
            s += P[o + k]
        b[na] = -(g[0] - dX * s)
        for c in range(na):
            J[na, c] = -dX
        J[na, na] = 0.0
    return J, b


@njit(cache=True)
def _coarse_newton(steps, load_here, S, coef_valid=False):
    """Coarsest-grid solve by Newton steps on the whole (FAS) coarse problem
    instead of point sweeps (option ``coarse_newton`` = steps; steady only).

    Unknowns: the pressure of every interior node that is pressurised or next
    to a pressurised node, and H0 when the load balance is done on this grid
    (``load_here``; equation g - dX sum P = 0).  Dense Jacobian of
    r_i = f_i - (Poiseuille_i - wedge_i) exactly as :func:`_residual`
    discretises it: the film through the deformation kernel
    (dH_j/dP_k = -K_|j-k|/pi, dH_j/dH0 = 1), eps = rho H^3/(eta lambda) through
    P (d ln eps/dP) and H, the wedge term through rho and H.  Each step is
    scaled so that no pressure changes ln(eps) by more than 1 (trust region,
    as the sweeps' ``dmax``), P is clipped at 0 (cavitation), and the film is
    updated.  A singular or non-finite system leaves the state unchanged.
    Venner & Lubrecht 2000 solve the coarsest grid "exactly" with many
    relaxations; a Newton solve of 33-65 unknowns is the direct form of it
    (docs/ehl.md "Speed")."""
    (P, H, f, tauH, base, rho, eps, dle, drho, delta, wrk, Pold, H0, g, iarr, dx, K, khr, khi,
     twr, twi, re, im, V, prm, opt, H0old, mode) = S
    o = iarr[0, 0]
    n = iarr[1, 0]
    order2 = opt[3] > 0
    act = np.empty(n, dtype=np.int64)
    for st in range(steps):
        if st > 0 or not coef_valid:
            _coef(0, P, H, rho, eps, dle, drho, iarr, prm)
        _residual(0, P, H, f, rho, eps, wrk, iarr, dx, order2, 0.0, False)
        na = 0
        for k in range(1, n - 1):
            i = o + k
            if P[i] > 0.0 or P[i - 1] > 0.0 or P[i + 1] > 0.0:
                act[na] = k
                na += 1
        if na == 0:
            return
        J, b = _coarse_jacobian(S, act, na, load_here)
        d = _lu_solve(J, b)
        ok = True
        big = 0.0
        for a in range(d.size):
            if not math.isfinite(d[a]):
                ok = False
        if not ok:
            return
        for a in range(na):
            v = abs(d[a] * dle[o + act[a]])
            if v > big:
                big = v
        sc = 1.0 if big <= 1.0 else 1.0 / big
        for a in range(na):
            i = o + act[a]
            v = P[i] + sc * d[a]
            P[i] = v if v > 0.0 else 0.0
        if load_here:
            H0[0] += sc * d[na]
        _film(0, P, H, base, tauH, H0, iarr, K, khr, khi, twr, twi, re, im, V)


@njit(cache=True)
def _run_schedule(sched, S, top_coef_valid=False):
    """One cycle.  With option ``lean`` (default 1) work whose result is never
    read is skipped: (i) the coefficients of a level at its first sweep right
    after the restriction to it (``_down`` computed them from the same P and
    H; also the finest level's when ``top_coef_valid``: the convergence test
    computed them), (ii) the film after the post-sweep of level k when the
    next step prolongs to level k+1 (only P of level k is read there; the next
    restriction to level k recomputes its film).  Bitwise the same iterates
    (tested); ~10 % less CPU per cycle (docs/ehl.md "Speed")."""
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


@njit(cache=True)
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


@njit(cache=True)
def _iterate(sched, S, hist, max_cycles, min_cycles, tol_p, tol_w, tol_r, tol_f,
             stall_window, tol_d):
    """Cycles until converged (returns +cycles) or stalled/failed (-cycles).

    hist[:, k] = (pressure change, load error, scaled residual, central film,
    minimum film, relative film change) of cycle k (films in Venner-Lubrecht
    units, central = node at X = 0); converged when the first three and the
    relative change of the central and minimum films are below tol_p, tol_w,
    tol_r, tol_f -- or, with ``tol_d`` > 0, when the relative film change and
    the load error are both below tol_d (stop at the discretisation error)."""
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
        if not (math.isfinite(dP) and math.isfinite(dW) and math.isfinite(res)):
            return -(cyc + 1)
        if cyc + 1 >= min_cycles and ((dP < tol_p and dW < tol_w and res < tol_r and dh < tol_f)
                                      or (dh < tol_d and dW < tol_d)):
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


#: option vector layout of the compiled core
OPT_KEYS = ("omega_gs", "omega_j", "switch", "order2", "dmax", "dist", "c_h0", "h0_step",
            "nu1", "nu2", "nu0", "load_mode", "defect", "stick", "freeze", "c_t", "c_char",
            "lean", "coarse_newton")
OPT_DEFAULTS = dict(omega_gs=0.8, omega_j=0.6, switch=3.0, order2=1, dmax=0.3, dist=0,
                    c_h0=0.5, h0_step=0.5, nu1=2, nu2=1, nu0=10, load_mode=0,
                    defect=0, stick=1.0, freeze=0, c_t=0.0, c_char=0, lean=1,
                    coarse_newton=0)


#: Speed path (docs/ehl.md "Speed"; opt-in, pass as multigrid options:
#: ``solve_line_contact(..., **SPEED_SETTING)``): the first relaxation setting of
#: :data:`.solver.RELAXATION_SETTINGS` with F-cycles and the coarsest grid solved
#: by one Newton step (:func:`_coarse_newton`) instead of 10 point sweeps.
#: Measured at 1024 intervals (Roelands, M = 20 / 100, L = 10): 3 cycles to
#: 0.1 of the discretisation error of H_c instead of 4-6 W-cycles, ~1.2 ms per
#: cycle instead of ~1.6-1.9.  Without the fallback settings of the default
#: path (passing options disables them), so not the default.
SPEED_SETTING = dict(switch=0.3, nu1=2, nu2=1, omega_gs=0.6, omega_j=0.5, load_mode=1,
                     c_h0=0.1, stick=10.0, gamma="F", coarse_newton=1)

#: stopping at about the discretisation accuracy of the default grids (docs/ehl.md
#: "Speed"): with :data:`SPEED_SETTING` the algebraic error of H_c left is below
#: ~0.3 of the discretisation error at 256-4096 intervals (measured)
DISC_TOLERANCES = dict(tol_pressure=1e-3, tol_load=1e-4, tol_residual=1e-4)


#: grid constants (node positions, kernel coefficients, kernel spectra, FFT
#: twiddles) per grid hierarchy, shared by every :class:`FlatMultigrid` on the
#: same grid: building them cost 0.6 ms per solve at 1025 nodes / 6 levels
#: (measured, docs/ehl.md "Speed"); read-only after construction
_GRID_CACHE: dict = {}
_GRID_CACHE_SIZE = 64


def _grid_constants(ns, ms, off, moff, toff, x_in, x_out):
    """(X per level, dX per level, kernel coefficients, kernel spectrum real/imag,
    twiddles cos/sin) of the level hierarchy with ``ns`` nodes per level."""
    X = [np.linspace(x_in, x_out, n) for n in ns]
    dx = np.array([x[1] - x[0] for x in X])
    K = np.concatenate([kernel_coefficients(n, d) for n, d in zip(ns, dx)])
    khr = np.zeros(max(int(moff[-1]), 1))
    khi = np.zeros_like(khr)
    twr = np.zeros(max(int(toff[-1]), 1))
    twi = np.zeros_like(twr)
    for l, (n, m) in enumerate(zip(ns, ms)):
        if m == 0:
            continue
        Kl = K[off[l]:off[l] + n]
        c = np.zeros(m)
        c[:n] = Kl
        c[m - n + 1:] = Kl[1:][::-1]
        kh = _fft.fft(c) * (-1.0 / np.pi)
        khr[moff[l]:moff[l] + m] = kh.real
        khi[moff[l]:moff[l] + m] = kh.imag
        ang = -2.0 * np.pi * np.arange(m // 2) / m
        cw, sw = np.cos(ang), np.sin(ang)
        twr[toff[l]:toff[l] + m // 2] = cw
        twi[toff[l]:toff[l] + m // 2] = sw
        # the FFT's per-stage table follows the base table (conv_real)
        sr, si = stage_twiddles(cw, sw, m)
        twr[toff[l] + m // 2:toff[l] + m] = sr
        twi[toff[l] + m // 2:toff[l] + m] = si
    return X, dx, K, khr, khi, twr, twi


class FlatMultigrid:
    """Level hierarchy in flat arrays for the compiled W-cycle (see module doc).

    ``prm`` is an :class:`.multigrid.EHLParams`; level 0 is the coarsest
    (``n_coarse`` intervals), level ``n_levels - 1`` the finest.  ``rough_fn``
    maps X (Hertz units) to the roughness in film units (h R / b^2)."""

    def __init__(self, prm, n_levels: int, n_coarse: int, rough_fn=None, **opts):
        bad = set(opts) - set(OPT_KEYS) - {"gamma"}
        if bad:
            raise EHLInputError(f"unknown multigrid option(s) {sorted(bad)!r}; "
                                f"known: {list(OPT_KEYS) + ['gamma']}")
        self.prm = prm
        self.n_levels = int(n_levels)
        o = dict(OPT_DEFAULTS)
        o.update({k: v for k, v in opts.items() if k != "gamma"})
        self.opts = o
        self.gamma = opts.get("gamma", 2)
        ns = [n_coarse * 2 ** k + 1 for k in range(n_levels)]
        off = np.concatenate(([0], np.cumsum(ns)))
        ms = []
        for n in ns:
            m = 1
            while m < 2 * n - 3:
                m *= 2
            ms.append(m if n > N_DIRECT else 0)
        moff = np.concatenate(([0], np.cumsum(ms)))
        # per level: m/2 twiddles exp(-2 pi i k/m), then the FFT's stage table
        toff = np.concatenate(([0], np.cumsum(ms)))
        self.iarr = np.zeros((6, n_levels), dtype=np.int64)
        self.iarr[0] = off[:-1]
        self.iarr[1] = ns
        self.iarr[2] = off[:-1]          # kernel coefficients share the level offsets
        self.iarr[3] = moff[:-1]
        self.iarr[4] = ms
        self.iarr[5] = toff[:-1]
        ntot = int(off[-1])
        key = (tuple(ns), float(prm.x_in), float(prm.x_out))
        cached = _GRID_CACHE.get(key)
        if cached is None:
            cached = _grid_constants(ns, ms, off, moff, toff, prm.x_in, prm.x_out)
            if len(_GRID_CACHE) >= _GRID_CACHE_SIZE:
                _GRID_CACHE.pop(next(iter(_GRID_CACHE)))
            _GRID_CACHE[key] = cached
        # shared between solvers on the same grid (never written after construction)
        self.X, self.dx, self.K, self.khr, self.khi, self.twr, self.twi = cached
        mmax = max(max(ms), 1)
        z = lambda: np.zeros(ntot)
        self.P, self.H, self.f, self.tauH = z(), z(), z(), z()
        self.rough = np.concatenate([np.zeros(n) if rough_fn is None else
                                     np.asarray(rough_fn(x), float) for n, x in
                                     zip(ns, self.X)])
        self.base = np.concatenate([0.5 * x ** 2 for x in self.X]) + self.rough
        self.work = [z() for _ in range(7)]   # rho eps dle drho delta wrk Pold
        self.H0 = np.zeros(n_levels)
        self.H0old = np.zeros(n_levels)
        self.mode = np.zeros(ntot, dtype=np.int8)
        self.g = np.full(n_levels, 0.5 * np.pi)
        self.re = np.zeros(mmax + 4)
        self.im = np.zeros(mmax + 4)
        self.V = np.zeros(max(ns))
        self.prmv = np.array([prm.lam, prm.A, prm.z, prm.php0, prm.c1,
                              1.0 if prm.compressible else 0.0, prm.x_in, prm.x_out, 1.0])
        self.optv = np.array([float(o[k]) for k in OPT_KEYS])
        self.sched = w_schedule(n_levels, self.gamma)

    # -- access ---------------------------------------------------------------
    def _sl(self, l):
        o, n = self.iarr[0, l], self.iarr[1, l]
        return slice(int(o), int(o + n))

    @property
    def top(self):
        return self.n_levels - 1

    def level_P(self, l=None):
        return self.P[self._sl(self.top if l is None else l)]

    def level_H(self, l=None):
        return self.H[self._sl(self.top if l is None else l)]

    def state(self):
        S = (self.P, self.H, self.f, self.tauH, self.base, *self.work, self.H0, self.g,
             self.iarr, self.dx, self.K, self.khr, self.khi, self.twr, self.twi, self.re,
             self.im, self.V, self.prmv, self.optv, self.H0old, self.mode)
        return S

    def set_roughness_scale(self, a: float):
        self.base[:] = np.concatenate([0.5 * x ** 2 for x in self.X]) + a * self.rough
        self.update_film(self.top)

    def update_film(self, l):
        _film(l, self.P, self.H, self.base, self.tauH, self.H0, self.iarr, self.K, self.khr,
              self.khi, self.twr, self.twi, self.re, self.im, self.V)

    def load(self, l=None) -> float:
        l = self.top if l is None else l
        return float(self.dx[l] * np.sum(self.P[self._sl(l)]))

    # -- transient term (docs/ehl_transient.md; default off) -------------------
    def rho_H(self, l=None) -> np.ndarray:
        """rho_i H_i on level l (finest by default; Dowson-Higginson rho of
        the current P), the quantity whose time derivative seed 000 eq 2 keeps."""
        l = self.top if l is None else l
        rho, eps, dle, drho = self.work[0], self.work[1], self.work[2], self.work[3]
        _coef(l, self.P, self.H, rho, eps, dle, drho, self.iarr, self.prmv)
        sl = self._sl(l)
        return rho[sl] * self.H[sl]

    def set_time_term(self, c_t: float, f_top=None, characteristic: bool = False):
        """Implicit time coefficient ``c_t`` (1/dT for BDF1, 1.5/dT for BDF2, 0:
        steady) on every level and the old-time right-hand side ``f_top`` of the
        finest grid (BDF1: -(rho H)^(n-1)/dT; BDF2: (-2 (rho H)^(n-1) +
        0.5 (rho H)^(n-2))/dT; None: zero).  The coarse levels receive it through
        the restricted residual (FAS).  Not combined with ``defect``.
        ``characteristic``: the time term replaces the wedge term (Venner &
        Lubrecht's discretisation along the characteristic at Courant 1, dT = dX:
        c_t = 1.5/dX, f = (-2 (rho H)^(n-1)_(i-1) + 0.5 (rho H)^(n-2)_(i-2))/dX)."""
        c_t = float(c_t)
        if not math.isfinite(c_t) or c_t < 0.0:
            raise EHLInputError(f"c_t={c_t!r}: must be finite and >= 0")
        self.opts["c_t"] = c_t
        self.optv[OPT_KEYS.index("c_t")] = c_t
        self.opts["c_char"] = 1 if characteristic else 0
        self.optv[OPT_KEYS.index("c_char")] = self.opts["c_char"]
        sl = self._sl(self.top)
        if f_top is None:
            self.f[sl] = 0.0
        else:
            f_top = np.asarray(f_top, float)
            if f_top.shape != (sl.stop - sl.start,):
                raise EHLInputError(f"f_top: need {sl.stop - sl.start} finest-grid values, "
                                    f"got shape {f_top.shape}")
            self.f[sl] = f_top
            self.f[sl.start] = self.f[sl.stop - 1] = 0.0

    # -- starts ---------------------------------------------------------------
    def start(self, P_top: np.ndarray, Hc: float):
        """Finest-grid pressure ``P_top`` and H0 such that the central film
        is ``Hc`` (Venner-Lubrecht units)."""
        t = self.top
        sl = self._sl(t)
        self.prmv[8] = Hc
        P = np.clip(np.asarray(P_top, float), 0.0, None)
        P[0] = P[-1] = 0.0
        self.P[sl] = P
        self.f[:] = 0.0
        self.tauH[:] = 0.0
        self.H0[t] = 0.0
        self.update_film(t)
        self.H0[t] = Hc - float(np.interp(0.0, self.X[t], self.H[sl]))
        self.update_film(t)

    def hertz_start(self, Hc: float):
        X = self.X[self.top]
        self.start(np.sqrt(np.clip(1.0 - X ** 2, 0.0, None)), Hc)

    def _substate(self, lo: int, hi: int):
        """State tuple of the sub-hierarchy of levels lo..hi (level lo is its
        coarsest, hi its finest); per-level arrays are views, so the compiled
        kernels update this object's arrays."""
        S = list(self.state())
        sl = slice(lo, hi + 1)
        S[12] = self.H0[sl]
        S[13] = self.g[sl]
        S[14] = np.ascontiguousarray(self.iarr[:, sl])
        S[15] = self.dx[sl]
        S[26] = self.H0old[sl]
        return tuple(S)

    def _prolong_solution(self, l: int):
        """Start level l from the solution on level l-1: cubic (4-point,
        Venner & Lubrecht 2000 sec. 3.x "FMG interpolation of higher order
        than the discretisation": 2nd-order discretisation -> order >= 3)
        interpolation of P, clipped to P >= 0; H0 carried over."""
        Pc = self.level_P(l - 1)
        nc = Pc.size
        Pf = np.empty(2 * nc - 1)
        Pf[0::2] = Pc
        mid = 0.5 * (Pc[:-1] + Pc[1:])
        if nc >= 4:
            mid[1:-1] = (9.0 * (Pc[1:-2] + Pc[2:-1]) - (Pc[:-3] + Pc[3:])) / 16.0
        Pf[1::2] = mid
        np.clip(Pf, 0.0, None, out=Pf)
        Pf[0] = Pf[-1] = 0.0
        sl = self._sl(l)
        self.P[sl] = Pf
        self.f[sl] = 0.0
        self.tauH[sl] = 0.0
        self.H0[l] = self.H0[l - 1]
        self.update_film(l)

    def fmg_start(self, Hc: float, cycles_per_level: int = 1, coarse_cycles: int = 20,
                  coarse_tol: float = 1e-4, alpha_dx: float = math.inf, alpha_eff: float = 0.0):
        """Full multigrid start (Venner & Lubrecht 2000 ch. 3 and their EHL
        chapters; Brandt 1984): solve on a coarse sub-hierarchy first, then
        interpolate the solution up (:meth:`_prolong_solution`, cubic) and do
        ``cycles_per_level`` cycles on each finer sub-hierarchy, up to (not
        including) the finest level, which is then started from the
        interpolated solution.  ``self.fmg_hc``: central film (Venner-Lubrecht
        units) on each FMG level after its cycles (for a Richardson estimate of
        the discretisation error).

        The FMG starts at the coarsest level with dX^2 <= Hc (Venner-Lubrecht
        units; ``Hc`` the expected central film): coarser grids cannot carry
        the film (the FAS corrections diverge at high M, docs/ehl.md).  The
        first sub-hierarchy is that level and the next finer one, started
        from the Hertzian pressure and iterated until the pressure change,
        load error and scaled residual fall below ``coarse_tol`` (at most
        ``coarse_cycles``).  Returns the number of cycles on each level."""
        t = self.top
        self.fmg_hc = []
        lo = 0
        while lo < t and self.dx[lo] ** 2 > Hc:
            lo += 1
        first = lo + 1
        while first < t and alpha_eff * self.dx[first] > alpha_dx:
            first += 1
        first = min(first, t)
        counts = []
        if first >= t:
            self.hertz_start(Hc)
            return counts
        X = self.X[first]
        sl = self._sl(first)
        self.prmv[8] = Hc
        self.f[:] = 0.0
        self.tauH[:] = 0.0
        self.P[sl] = np.sqrt(np.clip(1.0 - X ** 2, 0.0, None))
        self.P[sl.start] = self.P[sl.stop - 1] = 0.0
        self.H0[first] = 0.0
        self.update_film(first)
        self.H0[first] = Hc - float(np.interp(0.0, X, self.H[sl]))
        self.update_film(first)
        self.optv[:] = [float(self.opts[k]) for k in OPT_KEYS]
        for l in range(first, t):
            if l > first:
                self._prolong_solution(l)
            ncyc = coarse_cycles if l == first else cycles_per_level
            tol = coarse_tol if l == first else 0.0
            hist = np.full((6, ncyc), np.nan)
            k = _iterate(w_schedule(l - lo + 1, self.gamma), self._substate(lo, l), hist,
                         int(ncyc), 1, tol, tol, tol, 1.0, 6 if l == first else 10 ** 6, 0.0)
            counts.append(abs(int(k)))
            Xl = self.X[l]
            self.fmg_hc.append(float(np.interp(0.0, Xl, self.level_H(l))))
            if not np.all(np.isfinite(self.level_P(l))):
                break
        self._prolong_solution(t)
        return counts

    # -- iteration ------------------------------------------------------------
    def iterate(self, max_cycles=60, min_cycles=2, tol_pressure=1e-5, tol_load=1e-6,
                tol_residual=1e-6, stall_window=12, tol_film=1.0, tol_discretisation=0.0):
        """Compiled W-cycles; returns (converged, cycles, history dict).
        ``tol_discretisation`` > 0: also stop when the relative film change per
        cycle and the load error are below it."""
        hist = np.full((6, max_cycles), np.nan)
        self.optv[:] = [float(self.opts[k]) for k in OPT_KEYS]
        k = _iterate(self.sched, self.state(), hist, int(max_cycles), int(min_cycles),
                     float(tol_pressure), float(tol_load), float(tol_residual),
                     float(tol_film), int(stall_window), float(tol_discretisation))
        nc = abs(int(k))
        h = {"pressure_change": hist[0, :nc].tolist(), "load_balance": hist[1, :nc].tolist(),
             "reynolds_residual": hist[2, :nc].tolist(), "H_central": hist[3, :nc].tolist(),
             "H_min": hist[4, :nc].tolist(), "film_change": hist[5, :nc].tolist()}
        return k > 0, nc, h
