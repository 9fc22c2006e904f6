"""Integrators of the gear dynamic model (numba kernels, SI units; docs/model.md 'Integration').

* :func:`_rk4_step` -- one classical RK4 step ('rk4'), two-inertia form
  (Xu et al. 2022 eq 1-2) or time-indexed SDOF (Xu et al. 2022 eq 3-6).
* :func:`_kink_substep` -- one substep of 'rk4_kink': RK4 with the contact mode
  and the table cell held, stepping exactly to every table node and contact
  mode change located on the step's cubic Hermite interpolant; and of
  'rk4_node': the same, but only at table nodes where the tables bend (the node
  kink flags of :func:`gearfmu.dynamics.model_rhs._node_flags`), each reached by
  one RK4 step to its crossing time predicted from theta1' = omega1 (no trial
  step, no root finder); between them the steps are full substeps.
* :func:`_seg_substep` -- one substep of 'rk4_seg': rk4_node's segments running
  only between contact-zone edges, every evaluation in its own table cell, RK4 in
  the shifted velocities (docs/model.md "rk4_seg").
* :func:`_event_substep` -- the event-location loop of the three, written once
  (gearkernel.c event_substep); each of them compiles it with its own right-hand side.

Operation by operation the arithmetic of gearfmu/fmu/kernel/gearkernel.c
(bitwise agreement).  The kernels take the tables as the ``tab`` tuple of
:mod:`gearfmu.dynamics.model_rhs` and the inputs as the tuple
``dyn`` = (sdof, T1 (N*m), T2 (N*m), Rb1 (m), Rb2 (m), I1 (kg*m^2),
I2 (kg*m^2), F_m = T1/Rb1 (N), m_e (kg), 1/I1, 1/I2 (1/(kg*m^2))); the accelerations
multiply by 1/I1 and 1/I2, as gearkernel.c does with the values of gk_init.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .model_rhs import (
    _CELL_LIMIT, _cell_nodes, _decide_sub, _deriv_locked, _kvals_sel, _cut_above, _cut_below, _zone_sel,
    _mesh_force, _pair_guard,
)
from .seg_rhs import (
    _guard_seg, _pair_terms, _seg_accel, _seg_ce, _seg_cell, _seg_damped, _seg_gains, _seg_rhs, _seg_sel,
)


@njit(cache=True, error_model="numpy")
def _rk4_accumulate(stage, sa, sb, sc, sd, ka, kb, kc, kd):
    """RK4 increment sum after stage ``stage`` (0..3) with stage slope k: k1 at
    stage 0, then + 2*k2, + 2*k3, + k4, left to right."""
    if stage == 0:
        return ka, kb, kc, kd
    if stage == 3:
        return sa + ka, sb + kb, sc + kc, sd + kd
    return sa + 2.0 * ka, sb + 2.0 * kb, sc + 2.0 * kc, sd + 2.0 * kd


@njit(cache=True, error_model="numpy", inline="always")
def _rk4_step(tab, dyn, sdof, th0, t, th, om, x, v, h, nd, i0):
    """One classical RK4 step of length h (docs/model.md 'Integration').

    Two-inertia form (sdof False): state (theta1, omega1, x, v).  Time-indexed
    SDOF (sdof True, Xu et al. 2022 eq 3-6): theta1 = th0 + omega1*t_s prescribed at
    the stage times t_s = t, t + h/2, t + h/2, t + h, omega1 constant, states
    (x, v) with m_e v' = F_m - F; theta1 and omega1 are returned unchanged.
    Stage s evaluates f at y + a_s*h*k_{s-1} (a = 0, 1/2, 1/2, 1; h/2 computed
    as h/2.0); the increments are accumulated left to right,
    acc = ((k1 + 2*k2) + 2*k3) + k4, and y_new = y + (h/6.0)*acc.  The table
    cell (nd, i0) is carried from stage to stage and returned.  The caller passes
    ``sdof`` as a constant, so that the inlined step has no branch on it."""
    _, t1, t2, rb1, rb2, in1, in2, fm, me, ii1, ii2 = dyn
    h2 = h / 2.0
    ka, kb, kc, kd = 0.0, 0.0, 0.0, 0.0
    sa, sb, sc, sd = 0.0, 0.0, 0.0, 0.0
    for stage in range(4):
        if stage == 0:
            ts = t
            ya = th
            yb = om
            yc = x
            yd = v
        elif stage == 3:
            ts = t + h
            ya = th + h * ka
            yb = om + h * kb
            yc = x + h * kc
            yd = v + h * kd
        else:
            ts = t + h2
            ya = th + h2 * ka
            yb = om + h2 * kb
            yc = x + h2 * kc
            yd = v + h2 * kd
        if sdof:
            ya = th0 + om * ts
            yb = om
        f, nd, i0 = _mesh_force(tab, ya, yb, yc, yd, nd, i0)
        kc = yd
        if sdof:
            kd = (fm - f) / me
        else:
            ka = yb
            kb = (t1 - rb1 * f) * ii1
            kd = rb1 * (t1 - rb1 * f) * ii1 - rb2 * (rb2 * f - t2) * ii2
        sa, sb, sc, sd = _rk4_accumulate(stage, sa, sb, sc, sd, ka, kb, kc, kd)
    h6 = h / 6.0
    if sdof:
        return th, om, x + h6 * sc, v + h6 * sd, nd, i0
    return th + h6 * sa, om + h6 * sb, x + h6 * sc, v + h6 * sd, nd, i0


#: events (mode switches) located per substep before the rest of the substep is
#: taken without detection (guards a grazing ping-pong); docs/model.md "rk4_kink"
KINK_MAX_EVENTS = 1000
#: largest slot count the rk4_kink integrator accepts (fixed arrays in the C kernel)
KINK_MAX_SLOTS = 32
_KINK_TOL_S = 1e-12     # root bracket width in the unit substep fraction s
_KINK_MAX_IT = 60       # Illinois iterations per root

# Speed (docs/native.md "rk4_kink speed"): the rk4_kink kernels below never take
# a numpy array (see gearfmu.dynamics.model_rhs on reference counting): the
# locked right-hand side, the guards and the root finder call each other many
# times per substep.  The driver hands them the tables as ``tab``, the inputs as
# ``dyn``, the mode as an int64 pointer ``md`` (reg[j] = md[j], sub[j] = md[P + j],
# kpos[j] = md[2P + j]) and the Hermite data as a float64 pointer ``wk``
# (y0 = wk[0:4], f0 = wk[4:8], y1 = wk[8:12], f1 = wk[12:16]; the held segment's
# end nodes lo = wk[16], hi = wk[17], global node indices).  LLVM then
# inlines the whole substep; no allocation or slicing happens in the loop.


@njit(cache=True, error_model="numpy")
def _rk4_locked(tab, dyn, md, th, om, x, v, fa, fb, fc, fd, h, nd, i0, i1):
    """One classical RK4 step of length h, first stage (fa..fd) given, mode held;
    the arithmetic of :func:`_rk4_step`: stages at y + (h/2)*k1, y + (h/2)*k2,
    y + h*k3, acc = ((k1 + 2*k2) + 2*k3) + k4."""
    h2 = h / 2.0
    ka, kb, kc, kd = _deriv_locked(tab, dyn, md, th + h2 * fa, om + h2 * fb, x + h2 * fc, v + h2 * fd,
                                   nd, i0, i1)
    sa, sb, sc, sd = _rk4_accumulate(1, fa, fb, fc, fd, ka, kb, kc, kd)
    ka, kb, kc, kd = _deriv_locked(tab, dyn, md, th + h2 * ka, om + h2 * kb, x + h2 * kc, v + h2 * kd,
                                   nd, i0, i1)
    sa, sb, sc, sd = _rk4_accumulate(2, sa, sb, sc, sd, ka, kb, kc, kd)
    ka, kb, kc, kd = _deriv_locked(tab, dyn, md, th + h * ka, om + h * kb, x + h * kc, v + h * kd,
                                   nd, i0, i1)
    sa, sb, sc, sd = _rk4_accumulate(3, sa, sb, sc, sd, ka, kb, kc, kd)
    h6 = h / 6.0
    return th + h6 * sa, om + h6 * sb, x + h6 * sc, v + h6 * sd


@njit(cache=True, error_model="numpy")
def _guard_at(tab, md, gi, th, om, x, v, nd, i0, i1, lo, hi):
    """Guard gi at a state: 0 segment start theta1 - lo*dphi, 1 segment end hi*dphi - theta1
    (rk4_kink: lo = nd, hi = nd + 1, the cell), 2 + 3*j + q guard q of pair j; the
    tables are interpolated in the held cell nd."""
    dphi = tab[9]
    if gi == 0:
        return th - lo * dphi
    if gi == 1:
        return hi * dphi - th
    p = tab[8]
    j = (gi - 2) // 3
    q = (gi - 2) - 3 * j
    w = (th - nd * dphi) * tab[12]
    kv, ev, es, bv = _kvals_sel(tab, j, i0, i1, w, md[3 * p + j])
    return _pair_guard(q, kv, ev, es, bv, x, v, om, tab[10], tab[11], md[j], md[p + j])


@njit(cache=True, error_model="numpy")
def _rk4_seg(tab, dyn, md, th, wo, x, wv, fa, fb, fc, fd, h, nd, i0, i1, lo, hi):
    """One classical RK4 step of length h of the shifted state (theta1, Omega, x, V) with
    :func:`gearfmu.dynamics.seg_rhs._seg_rhs` (rk4_seg), first stage (fa..fd) given, mode
    held; the arithmetic of :func:`_rk4_locked`."""
    h2 = h / 2.0
    ka, kb, kc, kd, sk = _seg_rhs(tab, dyn, md, th + h2 * fa, wo + h2 * fb, x + h2 * fc, wv + h2 * fd,
                                  nd, i0, i1, lo, hi)
    sa, sb, sc, sd = _rk4_accumulate(1, fa, fb, fc, fd, ka, kb, kc, kd)
    ka, kb, kc, kd, sk = _seg_rhs(tab, dyn, md, th + h2 * ka, wo + h2 * kb, x + h2 * kc, wv + h2 * kd,
                                  nd, i0, i1, lo, hi)
    sa, sb, sc, sd = _rk4_accumulate(2, sa, sb, sc, sd, ka, kb, kc, kd)
    ka, kb, kc, kd, sk = _seg_rhs(tab, dyn, md, th + h * ka, wo + h * kb, x + h * kc, wv + h * kd,
                                  nd, i0, i1, lo, hi)
    sa, sb, sc, sd = _rk4_accumulate(3, sa, sb, sc, sd, ka, kb, kc, kd)
    h6 = h / 6.0
    return th + h6 * sa, wo + h6 * sb, x + h6 * sc, wv + h6 * sd


@njit(cache=True, error_model="numpy")
def _hermite_guard(tab, md, gi, s, wk, tau, nd, i0, i1, seg=False, gw=0.0, gv=0.0):
    """Guard gi on the cubic Hermite interpolant of the step (wk: y0, f0, y1, f1)
    at fraction s in [0, 1]."""
    u = 1.0 - s
    h00 = (1.0 + 2.0 * s) * u * u
    h10 = s * u * u
    h01 = s * s * (3.0 - 2.0 * s)
    h11 = s * s * (s - 1.0)
    ya = ((h00 * wk[0] + h10 * (tau * wk[4])) + h01 * wk[8]) + h11 * (tau * wk[12])
    yb = ((h00 * wk[1] + h10 * (tau * wk[5])) + h01 * wk[9]) + h11 * (tau * wk[13])
    yc = ((h00 * wk[2] + h10 * (tau * wk[6])) + h01 * wk[10]) + h11 * (tau * wk[14])
    yd = ((h00 * wk[3] + h10 * (tau * wk[7])) + h01 * wk[11]) + h11 * (tau * wk[15])
    if seg:
        return _guard_seg(tab, md, gi, ya, yb, yc, yd, nd, i0, i1, wk[16], wk[17], gw, gv)
    return _guard_at(tab, md, gi, ya, yb, yc, yd, nd, i0, i1, wk[16], wk[17])


@njit(cache=True, error_model="numpy")
def _guard_root(tab, md, gi, g_end, wk, tau, nd, i0, i1, seg=False, gw=0.0, gv=0.0):
    """Fraction s in [0, 1] where guard gi crosses zero on the Hermite interpolant
    (Illinois regula falsi; returns the end of the bracket where the guard < 0)."""
    if seg:
        ga = _guard_seg(tab, md, gi, wk[0], wk[1], wk[2], wk[3], nd, i0, i1, wk[16], wk[17], gw, gv)
    else:
        ga = _guard_at(tab, md, gi, wk[0], wk[1], wk[2], wk[3], nd, i0, i1, wk[16], wk[17])
    if not ga > 0.0:
        return 0.0
    a = 0.0
    bb = 1.0
    gb = g_end
    side = 0
    for _ in range(_KINK_MAX_IT):
        s = (a * gb - bb * ga) / (gb - ga)
        if not (s > a and s < bb):
            s = 0.5 * (a + bb)
        gs = _hermite_guard(tab, md, gi, s, wk, tau, nd, i0, i1, seg, gw, gv)
        if gs < 0.0:
            bb = s
            gb = gs
            if side == -1:
                ga = 0.5 * ga
            side = -1
        elif gs == 0.0:
            bb = s
            break
        else:
            a = s
            ga = gs
            if side == 1:
                gb = 0.5 * gb
            side = 1
        if bb - a <= _KINK_TOL_S:
            break
    return bb


@njit(cache=True, error_model="numpy")
def _mode_sync(tab, md, th, om, x, v, nd, i0, i1, from_state):
    """Set kpos of every pair for cell nd and the sub-modes of pairs in contact;
    with from_state also the regions (the start of a communication step)."""
    dphi = tab[9]
    c = tab[10]
    model = tab[11]
    p = tab[8]
    w = (th - nd * dphi) * tab[12]
    for j in range(p):
        km, em, esm, bm = _kvals_sel(tab, j, i0, i1, 0.5, md[3 * p + j])
        md[2 * p + j] = 1 if km > 0.0 else 0
        kv, ev, es, bv = _kvals_sel(tab, j, i0, i1, w, md[3 * p + j])
        if from_state:
            d = x - ev
            if d > bv:
                md[j] = 1
            elif d < -bv:
                md[j] = -1
            else:
                md[j] = 0
        if model == 0:
            md[p + j] = _decide_sub(md[j], kv, ev, es, bv, x, v, om, c)
        else:
            md[p + j] = 0


@njit(cache=True, error_model="numpy")
def _put4(wk, o, a, b, c, d):
    """wk[o:o+4] = (a, b, c, d) (one 4-vector of the Hermite data)."""
    wk[o] = a
    wk[o + 1] = b
    wk[o + 2] = c
    wk[o + 3] = d


@njit(cache=True, error_model="numpy")
def _node_time(th, om, fb, rem, lo, hi, dphi):
    """Time to the flagged table node ahead of theta1 predicted from the step's first
    stage (rk4_node): theta1(tau) = th + tau*(om + 0.5*fb*tau) with fb = omega1',
    the node hi*dphi for om > 0, lo*dphi for om < 0 (the held segment's ends);
    linear start tau = (node - th)/om, then two Newton iterations.  Returns tau when
    0 < tau < rem and the slope keeps the sign of om, else -1 (no prediction)."""
    if om > 0.0:
        dist = hi * dphi - th
    elif om < 0.0:
        dist = lo * dphi - th
    else:
        return -1.0
    tau = dist / om
    for _ in range(2):
        d = om + fb * tau
        if not d * om > 0.0:
            return -1.0
        tau = tau - (tau * (om + 0.5 * fb * tau) - dist) / d
    if tau > 0.0 and tau < rem:
        return tau
    return -1.0


@njit(cache=True, error_model="numpy")
def _node_flagged(tab, n):
    """Kink flag of global table node n (float holding an integer), node n mod N."""
    i0, i1 = _cell_nodes(n, tab[7])
    return tab[13][i0] != 0


@njit(cache=True, error_model="numpy")
def _seg_up(tab, n, node=True):
    """First stop above position n (global node units, rk4_kink/rk4_node segment ends):
    a contact-zone cut (docs/model.md "Contact-zone edges") or the next node (rk4_kink) or
    flagged node (rk4_node), at most floor(n) + N (n + 1 beyond 2^52 cells, where doubles no
    longer count single nodes, and for a non-finite n).  Without the cuts: the next node
    (rk4_kink), the first flagged node above n (rk4_node)."""
    if not abs(n) < _CELL_LIMIT:
        return n + 1.0
    n_phi = tab[7]
    c = np.floor(n)
    if tab[15]:
        i0, i1 = _cell_nodes(c, n_phi)
        f = _cut_above(tab, i0, n - c, False)
        while f < 1.0 and not c + f > n:   # n - c rounds: the stop must lie above n
            f = _cut_above(tab, i0, f, False)
        if f < 1.0:
            return c + f
    if not node:
        return c + 1.0
    top = c + n_phi
    m = c + 1.0
    while m < top:
        if _node_flagged(tab, m):
            return m
        if tab[15]:
            i0, i1 = _cell_nodes(m, n_phi)
            f = _cut_above(tab, i0, 0.0, False)
            if f < 1.0:
                return m + f
        m += 1.0
    return m


@njit(cache=True, error_model="numpy")
def _seg_down(tab, n, node=True):
    """Last stop below position n (as :func:`_seg_up`, downwards), at least ceil(n) - N
    (n - 1 beyond 2^52 cells)."""
    if not abs(n) < _CELL_LIMIT:
        return n - 1.0
    n_phi = tab[7]
    c = np.ceil(n) - 1.0
    if tab[15]:
        i0, i1 = _cell_nodes(c, n_phi)
        f = _cut_below(tab, i0, n - c, False)
        while f > 0.0 and not c + f < n:   # the stop must lie below n
            f = _cut_below(tab, i0, f, False)
        if f > 0.0:
            return c + f
    if not node:
        return c
    bottom = c + 1.0 - n_phi
    m = c
    while m > bottom:
        if _node_flagged(tab, m):
            return m
        if tab[15]:
            i0, i1 = _cell_nodes(m - 1.0, n_phi)
            f = _cut_below(tab, i0, 1.0, False)
            if f > 0.0:
                return m - 1.0 + f
        m -= 1.0
    return m


@njit(cache=True, error_model="numpy")
def _seg_start(tab, wk, nd, node, om, th):
    """Held segment for cell nd at a step start (theta1 = th): [nd, nd + 1] (rk4_kink);
    rk4_node: from nd to the first flagged node above it when om >= 0, from the last
    flagged node below nd + 1 to nd + 1 when om < 0 (the scan runs ahead of the motion).
    A contact-zone cut in cell nd splits it: the segment starts at the last cut at or below
    theta1 (om >= 0 or rk4_kink), or ends at the first cut at or above it (rk4_node, om < 0)."""
    lo = nd
    hi = nd + 1.0
    if tab[15]:
        i0, i1 = _cell_nodes(nd, tab[7])
        f = th * tab[12] - nd
        fb = _cut_below(tab, i0, f, True)
        if fb > 0.0:
            lo = nd + fb
        fa = _cut_above(tab, i0, f, True)
        if fa < 1.0:
            hi = nd + fa
    if node and om < 0.0:
        wk[17] = hi
        wk[16] = _seg_down(tab, hi, True)
    else:
        wk[16] = lo
        wk[17] = _seg_up(tab, lo, node)


@njit(cache=True, error_model="numpy")
def _seg_cross(tab, wk, up, node):
    """Move the held segment across its end (up) or start; returns the new held cell."""
    if up:
        lo = wk[17]
        wk[16] = lo
        wk[17] = _seg_up(tab, lo, node)
        return np.floor(lo)
    hi = wk[16]
    wk[17] = hi
    wk[16] = _seg_down(tab, hi, node)
    return np.ceil(hi) - 1.0


@njit(cache=True, error_model="numpy")
def _pairs_hold(tab, md, th, om, x, v, nd, i0, i1):
    """True when no pair guard is negative at the state (cell nd held)."""
    p = tab[8]
    w = (th - nd * tab[9]) * tab[12]
    for j in range(p):
        kv, ev, es, bv = _kvals_sel(tab, j, i0, i1, w, md[3 * p + j])
        rj = md[j]
        sj = md[p + j]
        for q in range(3):
            if _pair_guard(q, kv, ev, es, bv, x, v, om, tab[10], tab[11], rj, sj) < 0.0:
                return False
    return True


@njit(cache=True, error_model="numpy", inline="always")
def _switch_pair(md, p, j, q, model, kv, ev, es, bv, x, v, om, c):
    """The mode change of pair j when its guard q reached zero (rk4_kink, rk4_node and rk4_seg;
    gearkernel.c switch_pair): a pair out of contact enters contact on the side of the guard
    (the elastobacklash sub-mode decided from the state and the pair's table values kv, ev, es,
    bv there, which are read only then); a pair in contact leaves it at guard 0, and otherwise
    moves between the elastobacklash sub-modes (1 -> 0 at guard 1, 1 -> 2 at guard 2, back to 1)."""
    if md[j] == 0:
        md[j] = 1 if q == 0 else -1
        if model == 0:
            md[p + j] = _decide_sub(md[j], kv, ev, es, bv, x, v, om, c)
    elif q == 0:
        md[j] = 0
        md[p + j] = 0
    elif md[p + j] == 1:
        md[p + j] = 0 if q == 1 else 2
    else:
        md[p + j] = 1


@njit(cache=True, error_model="numpy")
def _seg_true(tab, dyn, md, th, wo, x, wv, nd, i0, i1, lo, hi):
    """(omega1, v) of the shifted state (theta1, Omega, x, V) (rk4_seg)."""
    gw, gv = _seg_gains(dyn)
    ce = _seg_ce(tab, md, th, nd, i0, i1, lo, hi)
    return wo + gw * ce, wv + gv * ce


#: rk4_seg's reuse of the step end's lookup (:func:`_seg_end`, :func:`_seg_first`) in the work
#: array: wk[18] 1 when valid, wk[19] theta1, wk[20:22] the segment, wk[22 + 4j .. 25 + 4j] pair
#: j's (k, e, de/dphi, b); the work array holds SEG_WORK_BASE + 4*P values
SEG_WORK_BASE = 22


@njit(cache=True, error_model="numpy")
def _seg_lookup(tab, md, wk, th, nd, i0, i1, lo, hi):
    """rk4_seg: (k, e, de/dphi, b) of every pair at theta1 th (:func:`_seg_cell`) into the
    work array (wk[22 + 4j ..]); returns C = c*sum e_j over the damped pairs."""
    p = tab[8]
    cc, a0, a1, w = _seg_cell(tab, th, nd, i0, i1, lo, hi)
    ea = 0.0
    for j in range(p):
        kv, ev, es, bv = _kvals_sel(tab, j, a0, a1, w, _seg_sel(tab, md, j, cc, a0, nd, lo, hi))
        o = SEG_WORK_BASE + 4 * j
        wk[o] = kv
        wk[o + 1] = ev
        wk[o + 2] = es
        wk[o + 3] = bv
        if _seg_damped(tab, md, j):
            ea += ev
    return tab[10] * ea


@njit(cache=True, error_model="numpy")
def _seg_first(tab, dyn, md, wk, th, om, x, v, nd, i0, i1, lo, hi):
    """rk4_seg's first stage at the state (theta1, omega1, x, v) with one lookup per pair:
    (Omega, V, f0 (4), S) with the shifted state and f0, S as :func:`_seg_rhs` there (the
    values and operations of :func:`_seg_ce`, then :func:`_seg_rhs`); the lookup of the last
    :func:`_seg_end` when the substep ended at th in the same segment (wk[18]: the same cell
    and mode, so the same values).  gearkernel.c seg_first."""
    p = tab[8]
    c = tab[10]
    gw, gv = _seg_gains(dyn)
    if wk[18] != 0.0 and th == wk[19] and lo == wk[20] and hi == wk[21]:
        ea = 0.0
        for j in range(p):
            if _seg_damped(tab, md, j):
                ea += wk[SEG_WORK_BASE + 4 * j + 1]
        ce = c * ea
    else:
        ce = _seg_lookup(tab, md, wk, th, nd, i0, i1, lo, hi)
    wk[18] = 0.0
    wo = om - gw * ce
    wv = v - gv * ce
    fs = 0.0
    ea = 0.0
    sa = 0.0
    na = 0.0
    for j in range(p):
        o = SEG_WORK_BASE + 4 * j
        fs, ea, sa, na = _pair_terms(tab, md, j, wk[o], wk[o + 1], wk[o + 2], wk[o + 3], x, fs, ea, sa, na)
    omr, ob, vr, vb, sk = _seg_accel(tab, dyn, wo, wv, fs, ea, sa, na)
    return wo, wv, omr, ob, vr, vb, sk


@njit(cache=True, error_model="numpy")
def _seg_end(tab, md, wk, gw, gv, ya, yb, yc, yd, nd, i0, i1, lo, hi):
    """rk4_seg at the end (ya..yd) of a step in the shifted state: (omega1, v) (:func:`_seg_true`)
    and True when no pair guard is negative there (as :func:`_pairs_hold`), with one lookup
    per pair for both, kept in the work array with theta1 and the segment (wk[19:22]) for
    :func:`_seg_first`.  gearkernel.c seg_end."""
    p = tab[8]
    ce = _seg_lookup(tab, md, wk, ya, nd, i0, i1, lo, hi)
    wk[19] = ya
    wk[20] = lo
    wk[21] = hi
    om = yb + gw * ce
    v = yd + gv * ce
    for j in range(p):
        o = SEG_WORK_BASE + 4 * j
        for q in range(3):
            if _pair_guard(q, wk[o], wk[o + 1], wk[o + 2], wk[o + 3], yc, v, om, tab[10], tab[11],
                           md[j], md[p + j]) < 0.0:
                return om, v, False
    return om, v, True


# ------------------------------------------------------------------ event location
# One substep of rk4_kink, rk4_node and rk4_seg, the loop written once (gearkernel.c
# event_substep): the helpers below pick the right-hand side, step, state and guards of the
# integrator by ``seg``, a constant of each caller (_kink_substep, _seg_substep), so numba
# compiles each caller with its own branch only.

@njit(cache=True, error_model="numpy", inline="always")
def _first_stage(tab, dyn, md, wk, th, om, x, v, nd, i0, i1, lo, hi, gw, seg):
    """The first RK4 stage at the state: (omega, v of the integrated state -- rk4_seg: the shifted
    Omega, V --, the stage f (4), omega1' for the node prediction)."""
    if seg:
        wo, wv, fa, fb, fc, fd, sk = _seg_first(tab, dyn, md, wk, th, om, x, v, nd, i0, i1, lo, hi)
        return wo, wv, fa, fb, fc, fd, fb + gw * (sk * om)
    fa, fb, fc, fd = _deriv_locked(tab, dyn, md, th, om, x, v, nd, i0, i1)
    return om, v, fa, fb, fc, fd, fb


@njit(cache=True, error_model="numpy", inline="always")
def _held_step(tab, dyn, md, th, wo, x, wv, fa, fb, fc, fd, h, nd, i0, i1, lo, hi, seg):
    """An RK4 step of length h, first stage given, mode held (rk4_seg: of the shifted state)."""
    if seg:
        return _rk4_seg(tab, dyn, md, th, wo, x, wv, fa, fb, fc, fd, h, nd, i0, i1, lo, hi)
    return _rk4_locked(tab, dyn, md, th, wo, x, wv, fa, fb, fc, fd, h, nd, i0, i1)


@njit(cache=True, error_model="numpy", inline="always")
def _held_rhs(tab, dyn, md, th, wo, x, wv, nd, i0, i1, lo, hi, seg):
    """The right-hand side, mode held (rk4_seg: in the shifted state)."""
    if seg:
        fa, fb, fc, fd, sk = _seg_rhs(tab, dyn, md, th, wo, x, wv, nd, i0, i1, lo, hi)
        return fa, fb, fc, fd
    return _deriv_locked(tab, dyn, md, th, wo, x, wv, nd, i0, i1)


@njit(cache=True, error_model="numpy", inline="always")
def _step_end(tab, md, wk, gw, gv, ya, yb, yc, yd, nd, i0, i1, lo, hi, seg):
    """The state at the end (ya..yd) of a step and, for rk4_seg, whether no pair guard is negative
    there (:func:`_seg_end`, one lookup for both); rk4_kink and rk4_node test the pair guards
    apart (:func:`_pairs_hold`), only when the segment's guards hold."""
    if seg:
        tb, td, hold = _seg_end(tab, md, wk, gw, gv, ya, yb, yc, yd, nd, i0, i1, lo, hi)
        return ya, tb, yc, td, hold
    return ya, yb, yc, yd, True


@njit(cache=True, error_model="numpy", inline="always")
def _end_guard(tab, md, wk, gi, ya, yb, yc, yd, tb, td, nd, i0, i1, lo, hi, gw, gv, seg):
    """Guard gi at the end (ya..yd) of a trial step (rk4_seg: the shifted state, with the state's
    omega1, v = tb, td and the pair values of :func:`_seg_end`'s lookup there)."""
    if not seg:
        return _guard_at(tab, md, gi, ya, yb, yc, yd, nd, i0, i1, lo, hi)
    if gi < 2:
        return _guard_seg(tab, md, gi, ya, yb, yc, yd, nd, i0, i1, lo, hi, gw, gv)
    p = tab[8]
    j = (gi - 2) // 3
    o = SEG_WORK_BASE + 4 * j
    return _pair_guard((gi - 2) - 3 * j, wk[o], wk[o + 1], wk[o + 2], wk[o + 3], yc, td, tb, tab[10], tab[11],
                       md[j], md[p + j])


@njit(cache=True, error_model="numpy", inline="always")
def _held_tables(tab, md, j, th, nd, i0, i1, lo, hi, seg):
    """(k, e, de/dphi, b) of pair j at theta1 = th, mode held (rk4_seg: in th's own cell of the segment)."""
    if seg:
        cc, a0, a1, w = _seg_cell(tab, th, nd, i0, i1, lo, hi)
        return _kvals_sel(tab, j, a0, a1, w, _seg_sel(tab, md, j, cc, a0, nd, lo, hi))
    w = (th - nd * tab[9]) * tab[12]
    return _kvals_sel(tab, j, i0, i1, w, md[3 * tab[8] + j])


@njit(cache=True, error_model="numpy", inline="always")
def _event_substep(tab, dyn, md, wk, th, om, x, v, h, nd, node, seg):
    """One substep of length h of rk4_kink, rk4_node (``node``) or rk4_seg (``seg``, which runs as
    rk4_node); returns (theta1, omega1, x, v, nd, events), the mode md updated in place.

    Per pass: the held cell follows theta1 inside the held segment [lo, hi) (wk[16], wk[17]; not
    for rk4_kink, whose segment is the cell), the first RK4 stage is taken at the state; rk4_node
    and rk4_seg predict the crossing of the segment's end ahead (:func:`_node_time`) and take one
    step to it, which crosses into the next segment when no pair guard is negative at its end;
    otherwise a trial step to the end of the substep follows, and when a guard is negative at its
    end, the earliest zero is located on the step's cubic Hermite interpolant
    (:func:`_guard_root`), the step retaken exactly to it and the mode switched there.  After
    KINK_MAX_EVENTS events the rest of the substep is taken without detection.  rk4_seg
    integrates the shifted state (theta1, Omega, x, V) of :func:`gearfmu.dynamics.seg_rhs._seg_rhs`
    and carries the step end's lookup into the next substep (wk[18])."""
    n_phi = tab[7]
    p = tab[8]
    dphi = tab[9]
    c = tab[10]
    model = tab[11]
    n_guard = 2 + 3 * p
    gw, gv = _seg_gains(dyn)
    i0, i1 = _cell_nodes(nd, n_phi)
    rem = h
    nev = 0
    while True:
        lo = wk[16]
        hi = wk[17]
        if node:   # the held cell follows theta1 inside the segment
            cn = np.floor(th * tab[12])
            if cn + 1.0 > lo and cn < hi and cn != nd:
                nd = cn
                i0, i1 = _cell_nodes(nd, n_phi)
                _zone_sel(tab, md, nd, i0, lo, hi)
        wo, wv, fa, fb, fc, fd, fbn = _first_stage(tab, dyn, md, wk, th, om, x, v, nd, i0, i1, lo, hi, gw, seg)
        if node and nev < KINK_MAX_EVENTS:   # the segment's end ahead: one step to it
            tau = _node_time(th, om, fbn, rem, lo, hi, dphi)
            if tau > 0.0:
                ya, yb, yc, yd = _held_step(tab, dyn, md, th, wo, x, wv, fa, fb, fc, fd, tau, nd, i0, i1, lo, hi, seg)
                ta, tb, tc, td, hold = _step_end(tab, md, wk, gw, gv, ya, yb, yc, yd, nd, i0, i1, lo, hi, seg)
                if hold if seg else _pairs_hold(tab, md, ta, tb, tc, td, nd, i0, i1):
                    nd = _seg_cross(tab, wk, om > 0.0, True)
                    th, om, x, v = ta, tb, tc, td
                    rem = rem - tau
                    nev += 1
                    i0, i1 = _cell_nodes(nd, n_phi)
                    _zone_sel(tab, md, nd, i0, wk[16], wk[17])
                    _mode_sync(tab, md, th, om, x, v, nd, i0, i1, False)
                    if not rem > 0.0:
                        break
                    continue
        ya, yb, yc, yd = _held_step(tab, dyn, md, th, wo, x, wv, fa, fb, fc, fd, rem, nd, i0, i1, lo, hi, seg)
        ta, tb, tc, td, hold = _step_end(tab, md, wk, gw, gv, ya, yb, yc, yd, nd, i0, i1, lo, hi, seg)
        if nev >= KINK_MAX_EVENTS:
            th, om, x, v = ta, tb, tc, td
            nd = np.floor(th * tab[12])
            i0, i1 = _cell_nodes(nd, n_phi)
            _seg_start(tab, wk, nd, node, om, th)
            _zone_sel(tab, md, nd, i0, wk[16], wk[17])
            _mode_sync(tab, md, th, om, x, v, nd, i0, i1, True)
            break
        # the guards at the trial end: the segment's first, then the pairs' (one lookup per pair)
        any_neg = ((ta - lo * dphi < 0.0) or (hi * dphi - ta < 0.0)
                   or not (hold if seg else _pairs_hold(tab, md, ta, tb, tc, td, nd, i0, i1)))
        if not any_neg:
            th, om, x, v = ta, tb, tc, td
            if seg:
                wk[18] = 1.0   # the next substep starts at the end of _seg_end's lookup
            break
        best = 2.0
        best_gi = -1
        have_f1 = False
        for gi in range(n_guard):
            g = _end_guard(tab, md, wk, gi, ya, yb, yc, yd, tb, td, nd, i0, i1, lo, hi, gw, gv, seg)
            if g < 0.0:
                if not have_f1:
                    _put4(wk, 0, th, wo, x, wv)
                    _put4(wk, 4, fa, fb, fc, fd)
                    _put4(wk, 8, ya, yb, yc, yd)
                    ga_, gb_, gc_, gd_ = _held_rhs(tab, dyn, md, ya, yb, yc, yd, nd, i0, i1, lo, hi, seg)
                    _put4(wk, 12, ga_, gb_, gc_, gd_)
                    have_f1 = True
                s = _guard_root(tab, md, gi, g, wk, rem, nd, i0, i1, seg, gw, gv)
                if s < best:
                    best = s
                    best_gi = gi
        if best_gi < 0:
            th, om, x, v = ta, tb, tc, td
            break
        # step exactly to the event, then switch the mode
        if best >= 1.0:
            th, om, x, v = ta, tb, tc, td
            rem = 0.0
        elif best > 0.0:
            tau = best * rem
            ya, yb, yc, yd = _held_step(tab, dyn, md, th, wo, x, wv, fa, fb, fc, fd, tau, nd, i0, i1, lo, hi, seg)
            if seg:
                yb, yd = _seg_true(tab, dyn, md, ya, yb, yc, yd, nd, i0, i1, lo, hi)
            th, om, x, v = ya, yb, yc, yd
            rem = rem - tau
        nev += 1
        if best_gi < 2:
            nd = _seg_cross(tab, wk, best_gi == 1, node)
            i0, i1 = _cell_nodes(nd, n_phi)
            _zone_sel(tab, md, nd, i0, wk[16], wk[17])
            _mode_sync(tab, md, th, om, x, v, nd, i0, i1, False)
        else:
            j = (best_gi - 2) // 3
            kv = ev = es = bv = 0.0
            if md[j] == 0 and model == 0:   # _switch_pair's sub-mode decision reads the tables
                kv, ev, es, bv = _held_tables(tab, md, j, th, nd, i0, i1, wk[16], wk[17], seg)
            _switch_pair(md, p, j, (best_gi - 2) - 3 * j, model, kv, ev, es, bv, x, v, om, c)
        if not rem > 0.0:
            break
    return th, om, x, v, nd, nev


@njit(cache=True, error_model="numpy")
def _kink_substep(tab, dyn, md, wk, th, om, x, v, h, nd, node=False):
    """Advance one substep of length h with the rk4_kink integrator (docs/model.md), or with
    ``node`` the 'rk4_node' integrator; :func:`_event_substep`.  Returns (theta1, omega1, x, v,
    nd, events); the mode md is updated in place.

    The held segment [lo, hi) (wk[16], wk[17], global node indices) is the cell nd for
    rk4_kink.  With ``node`` it runs from flagged node to flagged node
    (:func:`gearfmu.dynamics.model_rhs._node_flags`; the tables are linear across the nodes
    inside, so the held cell's interpolant is theirs): the flagged node ahead within the
    remaining substep is not located by a trial step and the root finder: its crossing time is
    predicted from theta1' = omega1 (:func:`_node_time`), the RK4 step ends there, and when no
    pair guard is negative at that end the segment switches to the next one as at a located
    node event; when a pair guard is negative the prediction is dropped and the rk4_kink trial
    and location follow.  Without ``node`` the arithmetic is that of rk4_kink exactly."""
    return _event_substep(tab, dyn, md, wk, th, om, x, v, h, nd, node, False)


@njit(cache=True, error_model="numpy")
def _seg_substep(tab, dyn, md, wk, th, om, x, v, h, nd):
    """Advance one substep of length h with the rk4_seg integrator (docs/model.md "rk4_seg");
    :func:`_event_substep`.  Returns (theta1, omega1, x, v, nd, events); the mode md is updated
    in place.

    rk4_node's held segments, stops and event location, with two changes: the segments run
    from contact-zone cut to contact-zone cut (and the nodes where the contact_zone flag kpos
    can change, :func:`gearfmu.dynamics.model_rhs._seg_flags`), and every evaluation reads
    the tables in the cell of its own theta1 clamped to the segment, so the tables' piecewise
    linear interpolant is integrated exactly; the RK4 steps integrate the shifted state
    (theta1, Omega, x, V) of :func:`gearfmu.dynamics.seg_rhs._seg_rhs`, whose right-hand
    side has no jump at the table nodes (the e-slope damping term is moved into the state)."""
    return _event_substep(tab, dyn, md, wk, th, om, x, v, h, nd, True, True)
