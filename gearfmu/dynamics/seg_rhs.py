"""Right-hand side and contact guards of the 'rk4_seg' integrator (numba kernels, SI units;
docs/model.md "rk4_seg").

Inside a held segment (between two stops of :func:`gearfmu.dynamics.model_rhs._seg_flags`)
every evaluation looks the tables up in its own cell (:func:`_seg_cell`), and the state is
integrated in the shifted velocities Omega = omega1 - (Rb1/I1)*C and V = v - C/m_e with
C = c*sum_j e_j over the damped pairs, so that the jump of de_j/dphi at a table node does not
enter the right-hand side.  Operation by operation the arithmetic of the rk4_seg part of
gearfmu/fmu/kernel/gearkernel.c (bitwise agreement); ``tab``, ``dyn`` and the mode ``md`` as in
:mod:`gearfmu.dynamics.model_rhs` and :mod:`gearfmu.dynamics.integrators`.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .model_rhs import _cell_nodes, _kvals_sel, _pair_guard


@njit(cache=True, error_model="numpy", inline="always")
def _seg_cell(tab, th, nd, i0, i1, lo, hi):
    """rk4_seg: (cell, i0, i1, weight) of theta1 th, the cell clamped to the held segment
    [lo, hi) (global node units; floor(lo) .. ceil(hi) - 1, a non-finite th gives floor(lo));
    (nd, i0, i1) the held cell, whose nodes are reused when the cell is it or a neighbour."""
    n_phi = tab[7]
    cl = np.floor(lo)
    ch = np.ceil(hi) - 1.0
    c = np.floor(th * tab[12])
    if not c > cl:
        c = cl
    if c > ch:
        c = ch
    if c == nd:
        a0, a1 = i0, i1
    elif c == nd + 1.0:
        a0 = i1
        a1 = 0 if i1 == n_phi - 1 else i1 + 1
    elif c == nd - 1.0:
        a1 = i0
        a0 = n_phi - 1 if i0 == 0 else i0 - 1
    else:
        a0, a1 = _cell_nodes(c, n_phi)
    return c, a0, a1, (th - c * tab[9]) * tab[12]


@njit(cache=True, error_model="numpy", inline="always")
def _seg_sel(tab, md, j, c, a0, nd, lo, hi):
    """rk4_seg: the held side of pair j's contact-zone cut in cell c of the held segment
    [lo, hi): md[3P + j] in the held cell nd, else as :func:`_zone_sel` for cell c."""
    p = tab[8]
    if c == nd or not tab[15]:
        return md[3 * p + j]
    n_phi = tab[7]
    zp = tab[14]
    r = j * n_phi + a0
    clo = zp[r]
    if not clo >= 0.0:
        return -1
    a = lo if lo > c else c
    b = hi if hi < c + 1.0 else c + 1.0
    wm = 0.5 * (a + b) - c
    if wm < clo:
        return 0
    if wm >= zp[p * n_phi + r]:
        return 2
    return 1


@njit(cache=True, error_model="numpy", inline="always")
def _seg_gains(dyn):
    """rk4_seg (docs/model.md "rk4_seg"): the gains (g_w, g_v) of the shifted velocities
    Omega = omega1 - g_w*C, V = v - g_v*C with C = c*sum of e_j over the damped pairs:
    two-inertia g_w = Rb1/I1, g_v = Rb1*(Rb1/I1) + Rb2*(Rb2/I2) (1/kg); SDOF 0 and 1/m_e."""
    sdof, t1, t2, rb1, rb2, in1, in2, fm, me, ii1, ii2 = dyn
    if sdof:
        return 0.0, 1.0 / me
    return rb1 / in1, rb1 * (rb1 / in1) + rb2 * (rb2 / in2)


@njit(cache=True, error_model="numpy", inline="always")
def _seg_damped(tab, md, j):
    """True when pair j's force holds the viscous term c*(v - de_j/dphi*omega1) in its held
    mode: elastobacklash in contact (reg != 0) with sub-mode 'sum', contact_zone with kpos."""
    p = tab[8]
    if tab[11] == 0:
        return md[j] != 0 and md[p + j] == 1
    return md[2 * p + j] != 0


@njit(cache=True, error_model="numpy", inline="always")
def _seg_ce(tab, md, th, nd, i0, i1, lo, hi):
    """rk4_seg: C = c*sum_j e_j(theta1) (N*s/m * m) over the damped pairs (:func:`_seg_damped`),
    the tables read in the cell of th clamped to the held segment [lo, hi)."""
    p = tab[8]
    cc, a0, a1, w = _seg_cell(tab, th, nd, i0, i1, lo, hi)
    ea = 0.0
    for j in range(p):
        if _seg_damped(tab, md, j):
            kv, ev, es, bv = _kvals_sel(tab, j, a0, a1, w, _seg_sel(tab, md, j, cc, a0, nd, lo, hi))
            ea += ev
    return tab[10] * ea


@njit(cache=True, error_model="numpy", inline="always")
def _pair_terms(tab, md, j, kv, ev, es, bv, x, fs, ea, sa, na):
    """Pair j's terms of :func:`_seg_rhs` added to the sums (fs, ea, sa, na) and returned: its
    spring force F_j = k_j*(x - e_j -+ b_j) in its held regime (twice in the elastobacklash
    sub-mode 0), and when the pair is damped in its held mode its e_j, de_j/dphi and one
    viscous term (docs/model.md "rk4_seg")."""
    p = tab[8]
    reg = md[j]
    if reg == 1:
        fc = kv * ((x - ev) - bv)
    elif reg == -1:
        fc = kv * ((x - ev) + bv)
    else:
        fc = 0.0
    if tab[11] == 0:
        if reg != 0:
            sub = md[p + j]
            if sub == 0:
                fs += fc + fc
            elif sub == 1:
                fs += fc
                ea += ev
                sa += es
                na += 1.0
    elif md[2 * p + j] != 0:
        fs += fc
        ea += ev
        sa += es
        na += 1.0
    return fs, ea, sa, na


@njit(cache=True, error_model="numpy", inline="always")
def _seg_accel(tab, dyn, wo, wv, fs, ea, sa, na):
    """(omega1, Omega', v, V', S) of :func:`_seg_rhs` from the shifted velocities (wo, wv) and
    the sums of :func:`_pair_terms` over the pairs; the accelerations multiply by 1/I1 and 1/I2
    (kg^-1 m^-2) rather than divide (a division per evaluation is slow)."""
    c = tab[10]
    sdof, t1, t2, rb1, rb2, in1, in2, fm, me, ii1, ii2 = dyn
    gw, gv = _seg_gains(dyn)
    ce = c * ea
    om = wo + gw * ce
    v = wv + gv * ce
    f = fs + na * (c * v)
    if sdof:
        return om, 0.0, v, (fm - f) / me, c * sa
    return om, (t1 - rb1 * f) * ii1, v, rb1 * (t1 - rb1 * f) * ii1 - rb2 * (rb2 * f - t2) * ii2, c * sa


@njit(cache=True, error_model="numpy", inline="always")
def _seg_rhs(tab, dyn, md, th, wo, x, wv, nd, i0, i1, lo, hi):
    """rk4_seg right-hand side in the shifted state (theta1, Omega, x, V) (docs/model.md
    "rk4_seg"), the mode held and the tables read in the cell of theta1 clamped to the held
    segment [lo, hi) (:func:`_seg_cell`): C = c*sum e_j over the damped pairs,
    omega1 = Omega + g_w*C, v = V + g_v*C (:func:`_seg_gains`), and the mesh force without
    the e-slope term, F_r = sum_j F_j + c*(de_j/dphi)*omega1 (the damped pairs) = the
    spring terms + n_d*c*v.  Returns (omega1, (T1 - Rb1*F_r)/I1, v, V') with
    V' = Rb1*(T1 - Rb1*F_r)/I1 - Rb2*(Rb2*F_r - T2)/I2 (SDOF: 0 and (F_m - F_r)/m_e), and
    S = c*sum de_j/dphi over the damped pairs (omega1' = Omega' + g_w*S*omega1)."""
    p = tab[8]
    cc, a0, a1, w = _seg_cell(tab, th, nd, i0, i1, lo, hi)
    fs = 0.0
    ea = 0.0
    sa = 0.0
    na = 0.0
    for j in range(p):
        kv, ev, es, bv = _kvals_sel(tab, j, a0, a1, w, _seg_sel(tab, md, j, cc, a0, nd, lo, hi))
        fs, ea, sa, na = _pair_terms(tab, md, j, kv, ev, es, bv, x, fs, ea, sa, na)
    return _seg_accel(tab, dyn, wo, wv, fs, ea, sa, na)


@njit(cache=True, error_model="numpy")
def _guard_seg(tab, md, gi, th, wo, x, wv, nd, i0, i1, lo, hi, gw, gv):
    """rk4_seg: guard gi (as :func:`gearfmu.dynamics.integrators._guard_at`) at the shifted state (theta1, Omega, x, V):
    omega1 = Omega + g_w*C, v = V + g_v*C (:func:`_seg_rhs`), C as :func:`_seg_ce` and the pair's
    guard, the tables read once per pair for both, in the cell of theta1 clamped to the held
    segment [lo, hi).  gearkernel.c guard_seg."""
    dphi = tab[9]
    if gi == 0:
        return th - lo * dphi
    if gi == 1:
        return hi * dphi - th
    p = tab[8]
    jg = (gi - 2) // 3
    q = (gi - 2) - 3 * jg
    cc, a0, a1, w = _seg_cell(tab, th, nd, i0, i1, lo, hi)
    ea = 0.0
    kj = 0.0
    ej = 0.0
    sj = 0.0
    bj = 0.0
    for j in range(p):
        damped = _seg_damped(tab, md, j)
        if damped or j == jg:
            kv, ev, es, bv = _kvals_sel(tab, j, a0, a1, w, _seg_sel(tab, md, j, cc, a0, nd, lo, hi))
            if damped:
                ea += ev
            if j == jg:
                kj = kv
                ej = ev
                sj = es
                bj = bv
    ce = tab[10] * ea
    return _pair_guard(q, kj, ej, sj, bj, x, wv + gv * ce, wo + gw * ce, tab[10], tab[11], md[jg], md[p + jg])
