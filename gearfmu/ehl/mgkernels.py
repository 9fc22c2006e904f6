"""Compiled grid operators of the line-contact EHL multigrid solver (numba).

Equations (Zhao et al. 2022 eq 2-7 in the Hertzian scaling of Venner & Lubrecht 2000,
*Multilevel Methods in Lubrication*, Elsevier; docs/ehl.md):

    d/dX( eps dP/dX ) - d(rho H)/dX = 0,   eps = rho H^3 / (eta lambda)    (Reynolds, eq 2)
    H = H0 + X^2/2 - (1/pi) int P ln|X - X'| dX' + R(X)                     (film, eq 3-4)
    eta = exp{A [ (1 + P ph/p0)^z - 1 ]}  (Roelands, eq 5) or exp(alpha p_h P) (Barus)
    rho = (c1 + 1.34 P) / (c1 + P),  c1 = 0.59e9 Pa / ph                    (Dowson-Higginson, eq 6)
    dX sum P = pi/2                                                         (load balance, eq 7)
    P = 0 at the inlet and outlet, P >= 0 (cavitation by P = max(P, 0)).

Discretisation: central differences for the Poiseuille term with eps at the
half nodes as the mean of the node values, second-order upstream differences
for the wedge term (first order at the first interior node), deformation with
piecewise-constant pressure (:mod:`.deformation`).  Transient term
(docs/ehl_transient.md): option ``c_t`` adds c_t (rho H)_i to the wedge term
(``c_char``: replaces it, the characteristic scheme) and its derivative to the
point Jacobians; the old time levels are the finest-grid right-hand side f.

All levels live in flat arrays (level l at offset ``iarr[0, l]`` with
``iarr[1, l]`` nodes); the state tuple ``S`` is built by
:meth:`.multigrid.FlatMultigrid.state`.  Levels with at most :data:`N_DIRECT`
nodes evaluate the deformation by the direct O(n^2) sum, finer ones by FFT
(:func:`.deformation.conv_real`).

Relaxation (Venner & Lubrecht 2000): point Newton, Gauss-Seidel where
eps_i/dX^2 >= ``switch`` or next to cavitation, distributive Jacobi
elsewhere.  Two distribution patterns: ``dist = 1`` the symmetric pattern of
Venner & Lubrecht (P_i += d_i - (d_{i-1} + d_{i+1})/4; ``dist = 2`` with 1/2),
``dist = 0`` the dipole of Zhao et al. 2022 (+d_i at i, -d_i at i-1).  The Jacobians
include the deformation kernel and the density derivative of the wedge term;
a trust region limits the change of ln(eps) per sweep to ``dmax``.  Coarse
grid: FAS, injection of P, full weighting of the residual, the coarse film
starting equal to the injected fine film (FAS on the film equation), linear
interpolation of the correction where the fine pressure is positive.
"""
from __future__ import annotations

import math

from numba import njit

from .deformation import conv_real

#: levels with at most this many nodes use the direct O(n^2) deformation sum
N_DIRECT = 64


@njit(cache=True, error_model="numpy")
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


@njit(cache=True, error_model="numpy")
def _film(l, P, H, base, tauH, H0, iarr, K, khr, khi, twr, twi, re, im, V):
    o = iarr[0, l]
    n = iarr[1, l]
    _deform(l, P, V, iarr, K, khr, khi, twr, twi, re, im)
    for i in range(n):
        H[o + i] = H0[l] + base[o + i] + V[i] + tauH[o + i]


@njit(cache=True, error_model="numpy")
def _coef(l, P, H, rho, eps, dle, drho, iarr, prm):
    """rho, eps = rho H^3/(eta lambda), d ln(eps)/dP and d rho/dP on level l."""
    o = iarr[0, l]
    _coef_span(o, o + iarr[1, l], P, H, rho, eps, dle, drho, prm)


@njit(cache=True, error_model="numpy")
def _coef_span(i0, i1, P, H, rho, eps, dle, drho, prm):
    """:func:`_coef` of the flat indices i0 <= i < i1."""
    lam, A, z, php0, c1, comp = prm[0], prm[1], prm[2], prm[3], prm[4], prm[5]
    for i in range(i0, i1):
        p = P[i] if P[i] > 0.0 else 0.0
        dl = 0.0
        r = 1.0
        dr = 0.0
        if comp > 0.0:
            r = (c1 + 1.34 * p) / (c1 + p)
            dl += 1.34 / (c1 + 1.34 * p) - 1.0 / (c1 + p)
            dr = 0.34 * c1 / ((c1 + p) * (c1 + p))
        if z > 0.0:
            x = 1.0 + p * php0
            q = math.exp(z * math.log(x))       # x^z (exp/log: cheaper than pow)
            eta = math.exp(A * (q - 1.0))
            dl -= A * z * php0 * q / x
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


@njit(cache=True, error_model="numpy", inline="always")
def _reynolds_terms(P, H, rho, eps, i, sec, idX, ih2, ct, char):
    """Terms of the discrete Reynolds equation at node i: eps at the half nodes
    (em, ep), the Poiseuille term and the wedge term (second-order upstream if
    ``sec``, else first order), with the implicit time term ct rho_i H_i added
    to the wedge term (``char``: replacing it); ``idX`` = 1/dX, ``ih2`` =
    1/dX^2 (products instead of divisions in the sweeps)."""
    em = 0.5 * (eps[i - 1] + eps[i])
    ep = 0.5 * (eps[i] + eps[i + 1])
    poi = (em * (P[i - 1] - P[i]) + ep * (P[i + 1] - P[i])) * ih2
    if sec:
        wedge = (1.5 * rho[i] * H[i] - 2.0 * rho[i - 1] * H[i - 1]
                 + 0.5 * rho[i - 2] * H[i - 2]) * idX
    else:
        wedge = (rho[i] * H[i] - rho[i - 1] * H[i - 1]) * idX
    if ct != 0.0:
        if char:
            wedge = ct * rho[i] * H[i]
        else:
            wedge += ct * rho[i] * H[i]
    return em, ep, poi, wedge


@njit(cache=True, error_model="numpy")
def _residual(l, P, H, f, rho, eps, out, iarr, dx, order2, ct=0.0, char=False):
    """out_i = f_i - L_i(P, H) (interior nodes; 0 at the ends).

    ``ct`` > 0: transient operator (Zhao et al. 2022 eq 2 with d(rho H)/dT, BDF1/BDF2,
    docs/ehl_transient.md): the implicit part ct (rho H)_i is added to the
    wedge term; the old time levels are in f (finest grid).  ct = 0 takes
    the steady code path unchanged (bitwise).  ``char``: characteristic
    scheme (Courant 1): the implicit time term ct (rho H)_i *replaces* the
    wedge term, the shifted old levels are in f."""
    o = iarr[0, l]
    n = iarr[1, l]
    dX = dx[l]
    idX = 1.0 / dX
    ih2 = idX * idX
    out[o] = 0.0
    out[o + n - 1] = 0.0
    for k in range(1, n - 1):
        i = o + k
        em, ep, poi, wedge = _reynolds_terms(P, H, rho, eps, i, k >= 2 and order2, idX, ih2,
                                             ct, char)
        out[i] = f[i] - (poi - wedge)


@njit(cache=True, error_model="numpy")
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
    idX = 1.0 / dX
    ih2 = idX * idX
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
        sec = k >= 2 and order2
        em, ep, poi, wedge = _reynolds_terms(P, H, rho, eps, i, sec, idX, ih2, ct, char)
        r = f[i] - (poi - wedge)
        xtra = -abs(0.5 * eps[i] * dle[i] * (P[i - 1] - 2.0 * P[i] + P[i + 1]) * ih2)
        # hysteresis (``stick`` >= 1): a node relaxed by Jacobi stays Jacobi
        # until eps/dX^2 exceeds stick * switch (prevents switching limit cycles)
        thr = switch * stick if mode[i] == 1 else switch
        gs = eps[i] * ih2 >= thr or P[i - 1] <= 0.0 or P[i + 1] <= 0.0 or P[i] <= 0.0
        if freeze and l == top_level:
            # frozen switch (finest grid): keep the relaxation type of each node
            gs = mode[i] == 0
        mode[i] = 0 if gs else 1
        if gs:
            if sec:
                w = (1.5 * rho[i] * K0 - 2.0 * rho[i - 1] * K1 + 0.5 * rho[i - 2] * K2) * ipi
                w = (w - 1.5 * H[i] * drho[i]) * idX
            else:
                w = ((rho[i] * K0 - rho[i - 1] * K1) * ipi - H[i] * drho[i]) * idX
            if ct != 0.0:
                # d[ct rho_i H_i]/dP_i with dH_i/dP_i = -K0/pi (time term)
                if char:
                    w = 0.0
                w += ct * (rho[i] * K0 * ipi - H[i] * drho[i])
            J = -(em + ep) * ih2 + w + xtra
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
            w *= idX
            if ct != 0.0:
                # time term: film change -c0/pi and density change at i per unit d
                if char:
                    w = 0.0
                w += ct * (rho[i] * c0 * ipi - H[i] * drho[i])
            if dist > 0.5:
                Jp = -poifac * (em + ep) * ih2
            else:
                Jp = -(2.0 * em + ep) * ih2
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


@njit(cache=True, error_model="numpy")
def _relax(l, sweeps, load_here, S, coef_valid=False, last_film=True):
    """``sweeps`` relaxation sweeps on level l, each followed by a film update.
    ``coef_valid``: rho, eps, dle, drho of level l already belong to the current
    P and H (the first sweep does not recompute them); ``last_film`` = False:
    the film after the last sweep is not computed (the caller never reads it).
    Both only skip work whose result is not used or already there, so the
    iterates are bitwise the same (``lean`` option, docs/ehl.md)."""
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


@njit(cache=True, error_model="numpy")
def _load(l, P, iarr, dx):
    o = iarr[0, l]
    n = iarr[1, l]
    s = 0.0
    for k in range(n):
        s += P[o + k]
    return dx[l] * s


@njit(cache=True, error_model="numpy")
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


@njit(cache=True, error_model="numpy")
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


@njit(cache=True, error_model="numpy")
def _fmg_prolong(l, S):
    """Start level l from the solution on level l-1 (full multigrid): P
    injected at the even nodes and cubic (4-point) interpolation at the odd
    ones (linear next to the ends), clipped to P >= 0, zero right-hand sides,
    H0 carried over, film updated (:meth:`.multigrid.FlatMultigrid._prolong_solution`)."""
    (P, H, f, tauH, base, rho, eps, dle, drho, delta, wrk, Pold, H0, g, iarr, dx, K, khr, khi,
     twr, twi, re, im, V, prm, opt, H0old, mode) = S
    oc = iarr[0, l - 1]
    nc = iarr[1, l - 1]
    of = iarr[0, l]
    nf = iarr[1, l]
    for I in range(nc):
        P[of + 2 * I] = P[oc + I]
    for I in range(nc - 1):
        a = P[oc + I]
        b = P[oc + I + 1]
        if nc >= 4 and 1 <= I <= nc - 3:
            v = (9.0 * (a + b) - (P[oc + I - 1] + P[oc + I + 2])) / 16.0
        else:
            v = 0.5 * (a + b)
        P[of + 2 * I + 1] = v
    for k in range(nf):
        if P[of + k] < 0.0:
            P[of + k] = 0.0
        f[of + k] = 0.0
        tauH[of + k] = 0.0
    P[of] = 0.0
    P[of + nf - 1] = 0.0
    H0[l] = H0[l - 1]
    _film(l, P, H, base, tauH, H0, iarr, K, khr, khi, twr, twi, re, im, V)
