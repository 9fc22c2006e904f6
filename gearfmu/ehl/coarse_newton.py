"""Coarsest-grid Newton solve of the EHL multigrid (option ``coarse_newton``).

Venner & Lubrecht 2000 solve the coarsest grid "exactly" by many relaxation
sweeps; a dense Newton solve of the 33-129 coarsest-grid unknowns is the
direct form of it.  :func:`_lu_solve` is the dense Gaussian elimination also
used by the block-Newton polish (:mod:`.polish`).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .mgkernels import _coef, _coef_span, _film, _residual, _reynolds_terms

#: the coarsest-grid Newton solve (option ``coarse_newton``) is used only up to
#: this many coarsest nodes (dense LU, O(n^3));
#: larger coarsest grids keep the point sweeps
COARSE_NEWTON_MAX_NODES = 129


@njit(cache=True, error_model="numpy")
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
        rowk = A[k, k + 1:]
        for i in range(k + 1, n):
            m = A[i, k] * inv
            if m != 0.0:
                # on row views: the compiler sees two separate rows and vectorises
                rowi = A[i, k + 1:]
                for j in range(rowi.size):
                    rowi[j] -= m * rowk[j]
                b[i] -= m * b[k]
    for k in range(n - 1, -1, -1):
        s = b[k]
        for j in range(k + 1, n):
            s -= A[k, j] * b[j]
        b[k] = s / A[k, k]
    return b


@njit(cache=True, error_model="numpy")
def _coarse_jacobian(S, act, na, load_here, l=0):
    """Newton system of :func:`_coarse_newton` on level l (default the
    coarsest; :func:`_spike_newton` uses it on the finest): J (dense, unknowns
    P of the nodes ``act[:na]`` then H0 if ``load_here``) and b = -residual,
    with the coefficients (``_coef``) and the residual r = f - L (``wrk``,
    ``_residual``) of the current state already computed."""
    (P, H, f, tauH, base, rho, eps, dle, drho, delta, wrk, Pold, H0, g, iarr, dx, K, khr, khi,
     twr, twi, re, im, V, prm, opt, H0old, mode) = S
    o = iarr[0, l]
    n = iarr[1, l]
    ko = iarr[2, l]
    dX = dx[l]
    h2 = dX * dX
    order2 = opt[3] > 0
    ipi = 1.0 / math.pi
    m = na + 1 if load_here else na
    J = np.empty((m, m))
    b = np.empty(m)
    col = np.full(n, -1, dtype=np.int64)        # node -> column of the system
    for c in range(na):
        col[act[c]] = c
    # the kernel extended symmetrically, Ks[n + t] = K_|t| (no abs per entry), and
    # whether the unknowns are consecutive nodes (then each row reads Ks in one
    # forward run, mirrored: Ks[m] = Ks[2n - m], which the compiler vectorises)
    Ks = np.empty(2 * n + 1)
    for t in range(n):
        Ks[n + t] = K[ko + t]
        Ks[n - t] = K[ko + t]
    Ks[0] = 0.0                                  # t = -n: never read
    Ks[2 * n] = 0.0                              # t = n: never read
    consecutive = na > 0 and act[na - 1] - act[0] == na - 1
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
        if consecutive:
            row = J[a, :na]
            q = n - k + act[0]
            for c in range(na):
                row[c] = -(A2 * Ks[q + 2 + c] + A1 * Ks[q + 1 + c]
                           + A0 * Ks[q + c] + Ap * Ks[q - 1 + c])
        else:
            for c in range(na):
                t = n + k - act[c]
                J[a, c] = -(A2 * Ks[t - 2] + A1 * Ks[t - 1] + A0 * Ks[t] + Ap * Ks[t + 1])
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
        b[na] = -(g[l] - dX * s)
        for c in range(na):
            J[na, c] = -dX
        J[na, na] = 0.0
    return J, b


@njit(cache=True, error_model="numpy")
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
    (docs/ehl.md)."""
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


@njit(cache=True, error_model="numpy")
def _block_scaled_residual(l, S, k0, k1):
    """Coefficients and residual of level l for the current state, and the
    largest |r_i / (dL_i/dP_i)| over the pressurised nodes k0 <= k < k1 (the
    node, and that value)."""
    (P, H, f, tauH, base, rho, eps, dle, drho, delta, wrk, Pold, H0, g, iarr, dx, K, khr, khi,
     twr, twi, re, im, V, prm, opt, H0old, mode) = S
    o = iarr[0, l]
    ko = iarr[2, l]
    dX = dx[l]
    h2 = dX * dX
    _coef(l, P, H, rho, eps, dle, drho, iarr, prm)
    _residual(l, P, H, f, rho, eps, wrk, iarr, dx, opt[3] > 0, 0.0, False)
    kmax = -1
    big = 0.0
    for k in range(k0, k1):
        i = o + k
        if P[i] <= 0.0:
            continue
        em = 0.5 * (eps[i - 1] + eps[i])
        ep = 0.5 * (eps[i] + eps[i + 1])
        J0 = -(em + ep) / h2 + rho[i] * (K[ko] - K[ko + 1]) / (math.pi * dX)
        v = abs(wrk[i] / J0)
        if v > big:
            big = v
            kmax = k
    return kmax, big


@njit(cache=True, error_model="numpy")
def _block_scaled_residual_local(l, S, k0, k1):
    """As :func:`_block_scaled_residual` (steady operator), but the
    coefficients only of the nodes k0 - 2 .. k1 that the residual of the
    nodes k0 <= k < k1 reads and the residual only of those nodes (the
    acceptance test of :func:`_spike_newton`; the other nodes' coefficients
    are left as they were)."""
    (P, H, f, tauH, base, rho, eps, dle, drho, delta, wrk, Pold, H0, g, iarr, dx, K, khr, khi,
     twr, twi, re, im, V, prm, opt, H0old, mode) = S
    o = iarr[0, l]
    n = iarr[1, l]
    ko = iarr[2, l]
    dX = dx[l]
    h2 = dX * dX
    idX = 1.0 / dX
    ih2 = idX * idX
    order2 = opt[3] > 0
    _coef_span(o + max(k0 - 2, 0), o + min(k1 + 1, n), P, H, rho, eps, dle, drho, prm)
    kmax = -1
    big = 0.0
    for k in range(k0, k1):
        i = o + k
        em, ep, poi, wedge = _reynolds_terms(P, H, rho, eps, i, k >= 2 and order2, idX, ih2,
                                             0.0, False)
        wrk[i] = f[i] - (poi - wedge)
        if P[i] <= 0.0:
            continue
        J0 = -(em + ep) / h2 + rho[i] * (K[ko] - K[ko + 1]) / (math.pi * dX)
        v = abs(wrk[i] / J0)
        if v > big:
            big = v
            kmax = k
    return kmax, big


@njit(cache=True, error_model="numpy")
def _stale_scaled_residual_argmax(l, S):
    """Node of level l with the largest |r_i / (dL_i/dP_i)| over the pressurised
    nodes from the residual (``wrk``) and coefficients as they are (nothing
    recomputed); -1 if there is none."""
    (P, H, f, tauH, base, rho, eps, dle, drho, delta, wrk, Pold, H0, g, iarr, dx, K, khr, khi,
     twr, twi, re, im, V, prm, opt, H0old, mode) = S
    o = iarr[0, l]
    n = iarr[1, l]
    ko = iarr[2, l]
    dX = dx[l]
    ih2 = 1.0 / (dX * dX)
    w = (K[ko] - K[ko + 1]) / (math.pi * dX)
    kmax = -1
    big = 0.0
    for k in range(1, n - 1):
        i = o + k
        if P[i] <= 0.0:
            continue
        J0 = -0.5 * (eps[i - 1] + 2.0 * eps[i] + eps[i + 1]) * ih2 + rho[i] * w
        v = abs(wrk[i] / J0)
        if v > big:
            big = v
            kmax = k
    return kmax


@njit(cache=True, error_model="numpy")
def _add_deformation(l, S, k, dp):
    """H of level l += the film change of a pressure change ``dp`` at node k
    (-dp K_|j-k| / pi at every node j: the direct form of one column of the
    deformation, instead of a full FFT film update after a local change)."""
    H = S[1]
    iarr = S[14]
    K = S[16]
    o = iarr[0, l]
    n = iarr[1, l]
    ko = iarr[2, l]
    c = -dp / math.pi
    for j in range(k):
        H[o + j] += c * K[ko + k - j]
    for j in range(k, n):
        H[o + j] += c * K[ko + j - k]


@njit(cache=True, error_model="numpy")
def _spike_newton(steps, width, S):
    """Newton steps on the block of the finest grid around the node with the
    largest scaled Reynolds residual (option ``spike_newton`` = steps,
    ``spike_width`` = nodes each side; steady only, H0 and the other nodes
    fixed).

    After the multigrid cycles have smoothed the error, almost all of the
    scaled residual left sits on a handful of nodes at the pressure spike
    and the outlet drop (measured at Roelands M = 20 and 100, L = 10, 1025
    nodes: 94-98 % at 0.8 < X < 1, 87-97 % on the 8 largest nodes), where
    eps/dX^2 changes by orders of
    magnitude over a few nodes and the point relaxation switches between
    Gauss-Seidel and distributive Jacobi; each cycle lowers it only 2-3x.
    Local relaxation at such a singularity (Brandt 1984, *Multigrid
    Techniques: 1984 Guide*, local relaxation near singularities; Venner &
    Lubrecht 2000 solve this zone by line relaxation) done as a dense Newton
    step of the block (the Jacobian of :func:`_coarse_jacobian`: deformation
    kernel, eps through P and H, the wedge term through rho and H) removes
    it.  Trust region and clipping as in :func:`_coarse_newton`; the step is
    undone unless the largest scaled residual of the block falls; a singular
    or non-finite system leaves the state unchanged.  The film follows the
    step column by column (:func:`_add_deformation`, a few nodes changed)
    and the acceptance test reads only the block
    (:func:`_block_scaled_residual_local`); the caller's convergence test
    recomputes the coefficients of the whole level."""
    (P, H, f, tauH, base, rho, eps, dle, drho, delta, wrk, Pold, H0, g, iarr, dx, K, khr, khi,
     twr, twi, re, im, V, prm, opt, H0old, mode) = S
    l = iarr.shape[1] - 1
    o = iarr[0, l]
    n = iarr[1, l]
    ko = iarr[2, l]
    dX = dx[l]
    h2 = dX * dX
    order2 = opt[3] > 0
    act = np.empty(2 * width + 1, dtype=np.int64)
    old = np.empty(2 * width + 1)
    Hs = np.empty(n)
    for st in range(steps):
        if st == 0:
            kmax, big0 = _block_scaled_residual(l, S, 1, n - 1)
        else:
            # a further step: the largest scaled residual from the coefficients
            # and residuals at hand (current on the last block; elsewhere from
            # before the last step, which moved the film there only by the
            # deformation of a few changed nodes), then both recomputed on the
            # new block
            kmax = _stale_scaled_residual_argmax(l, S)
            if kmax < 0:
                return
            kmax, big0 = _block_scaled_residual_local(
                l, S, max(1, kmax - width), min(n - 1, kmax + width + 1))
        if kmax < 0:
            return
        na = 0
        for k in range(max(1, kmax - width), min(n - 1, kmax + width + 1)):
            i = o + k
            if P[i] > 0.0 or P[i - 1] > 0.0 or P[i + 1] > 0.0:
                act[na] = k
                na += 1
        J, b = _coarse_jacobian(S, act, na, False, l)
        d = _lu_solve(J, b)
        for a in range(d.size):
            if not math.isfinite(d[a]):
                return
        big = 0.0
        for a in range(na):
            v = abs(d[a] * dle[o + act[a]])
            if v > big:
                big = v
        sc = 1.0 if big <= 1.0 else 1.0 / big
        for k in range(n):
            Hs[k] = H[o + k]
        for a in range(na):
            i = o + act[a]
            old[a] = P[i]
            v = P[i] + sc * d[a]
            P[i] = v if v > 0.0 else 0.0
            if P[i] != old[a]:
                _add_deformation(l, S, act[a], P[i] - old[a])
        # accepted only if the largest scaled residual of the block fell
        k_, big1 = _block_scaled_residual_local(l, S, act[0], act[na - 1] + 1)
        if not big1 < big0:
            for a in range(na):
                P[o + act[a]] = old[a]
            for k in range(n):
                H[o + k] = Hs[k]
            return
