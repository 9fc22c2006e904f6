"""Numba kernels of the gearbox solver (SI units; docs/gearbox.md "Model", "Integrators").

The data is flat, C-like, so that a C kernel can hold the same arrays (docs/gearbox.md
"Kernel data"):

* ``mi`` (int64, MI per mesh): pinion body, gear body, N, P, damping law, zoned, the data
  addresses of the mesh's k, e, b, node flags and contact-zone cuts, the torque row ``it`` of the
  current step, rows2, the addresses of its mode (int64, 4P + 2: reg, sub, kpos, zone side of
  every pair, then the held cell's nodes i0, i1) and work (float64, :data:`WK`: the Hermite
  data and held segment of gearfmu.dynamics.integrators, then the held cell nd), and the cell
  (nd, i0) that plain RK4 carries from one evaluation to the next;
* ``mf`` (float64, MF per mesh): Rb_p, Rb_q, the cell width dphi and N/Phi, the per-pair
  damping c, the torque-row weight wt of the current step, g_p;
* ``bf`` (float64, 2n): 1/I_i, then g_i;  ``si`` (int64, 2 per shaft): upstream and
  downstream body;  ``sf`` (float64, 2 per shaft): k, c.

The kernels read them through raw pointers (no numpy array crosses a call in the step loop:
docs/native.md "rk4_kink speed"), and each mesh's ``tab`` tuple -- the pair model's, built
from the addresses by :func:`_mtab` -- goes to the pair kernels (:mod:`gearfmu.gearbox._pair`),
so a stage is looked up exactly as the pair is.

State ``y`` (2n): psi, omega, then (u_i, du_i) of bodies 1..n-1 (gearfmu.gearbox.model).
The work array ``W`` holds y, the first stage f0, a trial end y1 and its f1, the RK4 stage
input, accumulator and slope, a predicted end yt and the torques tau, each at the offsets below.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, types
from numba.extending import intrinsic

from ._pair import (
    KINK_MAX_EVENTS, NODE_KINK_TOL, _CELL_NONE, _cell_nodes, _guard_at, _guard_root, _guard_seg, _held_tables, _kvals,
    _kvals_sel, _mesh_force, _mode_sync, _node_flags, _node_time, _pair_force, _pair_force_locked, _pair_guard,
    _pairs_hold, _phi_cell, _seg_cell, _seg_cross, _seg_flags, _seg_sel, _seg_start, _stop_flags, _switch_pair, _tab,
    _with_zones, _zone_sel,
)

#: ints per mesh in ``mi`` and their slots
MI = 20
(I_P, I_Q, I_N, I_NP, I_MODEL, I_ZONED, I_K, I_E, I_B, I_FLAGS, I_CUTS, I_IT, I_ROWS2, I_MD, I_WK,
 I_ND, I_I0, I_HI0, I_HI1) = range(19)
#: floats per mesh in ``mf`` and their slots
MF = 8
F_RBP, F_RBQ, F_DPHI, F_INV, F_C, F_WT, F_G = range(7)
#: floats per mesh of its work array: wk[0:16] Hermite data (y0, f0, y1, f1 of the mesh's local
#: state theta_p, omega_p, x, v), wk[16:18] the held segment, wk[22] the held cell nd
WK = 24
WK_ND = 22
#: offsets (in units of the state length 2n) of the vectors in the work array W
W_Y, W_F0, W_Y1, W_F1, W_TMP, W_ACC, W_KK, W_YT, W_TAU = range(9)
W_VECTORS = 9
#: the integrator code of 'rk4_seg' (gearfmu.common.vocabulary.INTEGRATORS)
ICODE_SEG = 3
#: how :func:`_rhs` reads the meshes: the plain lookup with the carried cell ('rk4'), the held mode
#: ('rk4_kink', 'rk4_node'), the held mode with every evaluation in its own cell of the held segment
#: ('rk4_seg'; gb_kernel.c and pl_kernel.c: the ``locked`` 0, 1 and 3 of their right-hand sides)
LOOKUP_PLAIN = 0
LOOKUP_HELD = 1
LOOKUP_SEG = 3


def stop_flags(k, e, b, cuts, zoned, icode):
    """The stop flags (uint8 per table node) of one mesh for integrator code ``icode``: rk4_node's
    (gearfmu.dynamics.model_rhs._node_flags), or for rk4_seg the pair's rk4_seg stops
    (_seg_flags: big kinks, contact_zone-flag changes, cells with a contact-zone edge) and every node
    where e bends at all (the NODE_KINK_TOL test on e alone): the multi-mesh kernels integrate the
    true velocities, so the damping term c*(de/dphi)*omega, which jumps where e bends, is not stepped
    over (docs/planetary.md "rk4_seg"; the arithmetic of gk_stops.c gki_node_flags, its bits 1 and 2)."""
    if icode != ICODE_SEG:
        return _node_flags(k, e, b)
    e_bends = _stop_flags(np.ones_like(k), e, np.zeros_like(b), cuts, False, NODE_KINK_TOL)
    return _seg_flags(k, e, b, cuts, zoned) | e_bends


def _ptr_intrinsic(dtype):
    @intrinsic
    def _p(typingctx, addr):
        if not isinstance(addr, types.Integer):
            return None
        sig = types.CPointer(dtype)(addr)

        def codegen(context, builder, signature, args):
            return builder.inttoptr(args[0], context.get_value_type(types.CPointer(dtype)))

        return sig, codegen
    return _p


#: the data pointer at an address (int64) held in ``mi`` (the arrays are owned by the caller)
_f64p = _ptr_intrinsic(types.float64)
_i64p = _ptr_intrinsic(types.int64)
_u8p = _ptr_intrinsic(types.uint8)


@intrinsic
def _addr(typingctx, arr):
    """The data address (int64) of a C-contiguous array."""
    if not isinstance(arr, types.Array):
        return None
    sig = types.int64(arr)

    def codegen(context, builder, signature, args):
        ary = context.make_array(signature.args[0])(context, builder, value=args[0])
        return builder.ptrtoint(ary.data, context.get_value_type(types.int64))

    return sig, codegen


@njit(cache=True, error_model="numpy", inline="always")
def _mtab(mi, mf, m):
    """The pair model's ``tab`` tuple of mesh m at the current step's torque row."""
    o = m * MI
    f = m * MF
    tab = _tab(_f64p(mi[o + I_K]), _f64p(mi[o + I_E]), _f64p(mi[o + I_B]), mi[o + I_IT], mi[o + I_ROWS2] != 0,
               mf[f + F_WT], mi[o + I_N], mi[o + I_NP], mf[f + F_DPHI], mf[f + F_C], mi[o + I_MODEL],
               mf[f + F_INV], _u8p(mi[o + I_FLAGS]))
    if mi[o + I_ZONED] != 0:
        tab = _with_zones(tab, _f64p(mi[o + I_CUTS]))
    return tab


@njit(cache=True, error_model="numpy", inline="always")
def _u(W, o, i):
    """u_i (or du_i with o + 1) of body i from the vector at offset o: 0 for body 0."""
    if i == 0:
        return 0.0
    return W[o + 2 * i]


@njit(cache=True, error_model="numpy", inline="always")
def _local(mi, mf, m, W, o):
    """The mesh's own (theta_p, omega_p, x, v) of the vector at offset o of W (a state, or its
    derivative: the map is linear): theta_p = g_p psi + u_p, omega_p = g_p omega + du_p,
    x = Rb_p u_p - Rb_q u_q, v = Rb_p du_p - Rb_q du_q."""
    p = mi[m * MI + I_P]
    q = mi[m * MI + I_Q]
    f = m * MF
    gp = mf[f + F_G]
    up = _u(W, o, p)
    dup = _u(W, o + 1, p)
    return (gp * W[o] + up, gp * W[o + 1] + dup, mf[f + F_RBP] * up - mf[f + F_RBQ] * _u(W, o, q),
            mf[f + F_RBP] * dup - mf[f + F_RBQ] * _u(W, o + 1, q))


@njit(cache=True, error_model="numpy")
def _mesh_locked(tab, md, th, om, x, v, nd, i0, i1):
    """Mesh force (N) with the mode held (cell nd, every pair's reg/sub/kpos and zone side):
    the force loop of gearfmu.dynamics.model_rhs._deriv_locked."""
    p = tab[8]
    w = (th - nd * tab[9]) * tab[12]
    f = 0.0
    for j in range(p):
        kv, ev, es, bv = _kvals_sel(tab, j, i0, i1, w, md[3 * p + j])
        f += _pair_force_locked(kv, ev, es, bv, x, v, om, tab[10], tab[11], md[j], md[p + j], md[2 * p + j])
    return f


@njit(cache=True, error_model="numpy", inline="always")
def _mesh_seg(tab, md, wk, th, om, x, v):
    """rk4_seg: the mesh force (N) with the mode held and the tables read in the cell of th clamped to
    the held segment (gearfmu.dynamics.seg_rhs._seg_cell, _seg_sel; docs/gearbox.md "rk4_seg")."""
    p = tab[8]
    nd = wk[WK_ND]
    lo = wk[16]
    hi = wk[17]
    cc, a0, a1, w = _seg_cell(tab, th, nd, md[4 * p], md[4 * p + 1], lo, hi)
    f = 0.0
    for j in range(p):
        kv, ev, es, bv = _kvals_sel(tab, j, a0, a1, w, _seg_sel(tab, md, j, cc, a0, nd, lo, hi))
        f += _pair_force_locked(kv, ev, es, bv, x, v, om, tab[10], tab[11], md[j], md[p + j], md[2 * p + j])
    return f


@njit(cache=True, error_model="numpy", inline="always")
def _pairs_hold_seg(tab, md, wk, th, om, x, v):
    """rk4_seg: True when no pair guard is negative at the mesh's state, the tables read as
    :func:`_mesh_seg` (gearfmu.dynamics.integrators._pairs_hold in the cell of th)."""
    p = tab[8]
    nd = wk[WK_ND]
    lo = wk[16]
    hi = wk[17]
    cc, a0, a1, w = _seg_cell(tab, th, nd, md[4 * p], md[4 * p + 1], lo, hi)
    for j in range(p):
        kv, ev, es, bv = _kvals_sel(tab, j, a0, a1, w, _seg_sel(tab, md, j, cc, a0, nd, lo, hi))
        for q in range(3):
            if _pair_guard(q, kv, ev, es, bv, x, v, om, tab[10], tab[11], md[j], md[p + j]) < 0.0:
                return False
    return True


@njit(cache=True, error_model="numpy")
def _rhs(gb, W, o, od, t_in, t_out, locked):
    """Derivative of the state at offset o of W into offset od (docs/gearbox.md "Model"):
    torques of the inputs, shafts and meshes on every body, a_i = tau_i/I_i, psi'' = a_0,
    u_i'' = a_i - g_i a_0.  ``locked``: LOOKUP_HELD every mesh with its held mode (rk4_kink,
    rk4_node), LOOKUP_SEG the held mode read in the cell of each evaluation (rk4_seg), LOOKUP_PLAIN
    the plain lookup with the carried cell (rk4)."""
    mi, mf, bf, si, sf, n, nm, ns, lb, n2 = gb
    ot = W_TAU * n2
    for i in range(n):
        W[ot + i] = 0.0
    W[ot] += t_in
    W[ot + lb] -= t_out
    for s in range(ns):
        a = si[2 * s]
        b = si[2 * s + 1]
        ts = sf[2 * s] * (_u(W, o, a) - _u(W, o, b)) + sf[2 * s + 1] * (_u(W, o + 1, a) - _u(W, o + 1, b))
        W[ot + a] -= ts
        W[ot + b] += ts
    for m in range(nm):
        th, om, x, v = _local(mi, mf, m, W, o)
        tab = _mtab(mi, mf, m)
        k = m * MI
        if locked == LOOKUP_SEG:
            fm = _mesh_seg(tab, _i64p(mi[k + I_MD]), _f64p(mi[k + I_WK]), th, om, x, v)
        elif locked == LOOKUP_HELD:
            md = _i64p(mi[k + I_MD])
            wk = _f64p(mi[k + I_WK])
            fm = _mesh_locked(tab, md, th, om, x, v, wk[WK_ND], md[4 * tab[8]], md[4 * tab[8] + 1])
        else:
            fm, nd, i0 = _mesh_force(tab, th, om, x, v, mi[k + I_ND], mi[k + I_I0])
            mi[k + I_ND] = nd
            mi[k + I_I0] = i0
        W[ot + mi[k + I_P]] -= mf[m * MF + F_RBP] * fm
        W[ot + mi[k + I_Q]] += mf[m * MF + F_RBQ] * fm
    a0 = W[ot] * bf[0]
    W[od] = W[o + 1]
    W[od + 1] = a0
    for i in range(1, n):
        W[od + 2 * i] = W[o + 2 * i + 1]
        W[od + 2 * i + 1] = W[ot + i] * bf[i] - bf[n + i] * a0


@njit(cache=True, error_model="numpy")
def _rk4(gb, W, oy, of0, h, oout, t_in, t_out, locked):
    """One classical RK4 step of length h from the state at oy with its first stage at of0 (given)
    into oout; the arithmetic of docs/model.md "Integration" component by component: stages at
    y + (h/2) k1, y + (h/2) k2, y + h k3, acc = ((k1 + 2 k2) + 2 k3) + k4, y + (h/6) acc."""
    n2 = gb[9]
    otmp = W_TMP * n2
    oacc = W_ACC * n2
    okk = W_KK * n2
    h2 = h / 2.0
    for i in range(n2):
        W[otmp + i] = W[oy + i] + h2 * W[of0 + i]
    _rhs(gb, W, otmp, okk, t_in, t_out, locked)
    for i in range(n2):
        W[oacc + i] = W[of0 + i] + 2.0 * W[okk + i]
        W[otmp + i] = W[oy + i] + h2 * W[okk + i]
    _rhs(gb, W, otmp, okk, t_in, t_out, locked)
    for i in range(n2):
        W[oacc + i] = W[oacc + i] + 2.0 * W[okk + i]
        W[otmp + i] = W[oy + i] + h * W[okk + i]
    _rhs(gb, W, otmp, okk, t_in, t_out, locked)
    h6 = h / 6.0
    for i in range(n2):
        W[oout + i] = W[oy + i] + h6 * (W[oacc + i] + W[okk + i])


@njit(cache=True, error_model="numpy")
def _mesh_start(gb, W, m, node):
    """A mesh's mode from the state (start of a communication step, or after the event cap):
    the held cell and segment of its pinion angle, the zone sides, every pair's contact
    region and sub-mode (gearfmu.dynamics.driver does the same for the pair)."""
    mi, mf = gb[0], gb[1]
    tab = _mtab(mi, mf, m)
    md = _i64p(mi[m * MI + I_MD])
    wk = _f64p(mi[m * MI + I_WK])
    th, om, x, v = _local(mi, mf, m, W, 0)
    nd = np.floor(th * tab[12])
    i0, i1 = _cell_nodes(nd, tab[7])
    _seg_start(tab, wk, nd, node, om, th)
    _zone_sel(tab, md, nd, i0, wk[16], wk[17])
    _mode_sync(tab, md, th, om, x, v, nd, i0, i1, True)
    _hold(tab, md, wk, nd, i0, i1)


@njit(cache=True, error_model="numpy", inline="always")
def _hold(tab, md, wk, nd, i0, i1):
    wk[WK_ND] = nd
    md[4 * tab[8]] = i0
    md[4 * tab[8] + 1] = i1


@njit(cache=True, error_model="numpy")
def _mesh_cross(gb, W, m, up, node):
    """Move mesh m's held segment across its end (up) or start, then the zone sides and the
    sub-modes at the state y (a located or predicted node event)."""
    mi, mf = gb[0], gb[1]
    tab = _mtab(mi, mf, m)
    md = _i64p(mi[m * MI + I_MD])
    wk = _f64p(mi[m * MI + I_WK])
    nd = _seg_cross(tab, wk, up, node)
    i0, i1 = _cell_nodes(nd, tab[7])
    _hold(tab, md, wk, nd, i0, i1)
    _zone_sel(tab, md, nd, i0, wk[16], wk[17])
    th, om, x, v = _local(mi, mf, m, W, 0)
    _mode_sync(tab, md, th, om, x, v, nd, i0, i1, False)


@njit(cache=True, error_model="numpy")
def _mesh_guards_hold(gb, W, o, m, segment, lk):
    """True when no pair guard of mesh m is negative at the state at offset o (and, with ``segment``,
    neither of its segment guards); the tables read as :func:`_rhs` with ``lk``."""
    mi, mf = gb[0], gb[1]
    tab = _mtab(mi, mf, m)
    md = _i64p(mi[m * MI + I_MD])
    wk = _f64p(mi[m * MI + I_WK])
    th, om, x, v = _local(mi, mf, m, W, o)
    if segment and (th - wk[16] * tab[9] < 0.0 or wk[17] * tab[9] - th < 0.0):
        return False
    if lk == LOOKUP_SEG:
        return _pairs_hold_seg(tab, md, wk, th, om, x, v)
    p = tab[8]
    return _pairs_hold(tab, md, th, om, x, v, wk[WK_ND], md[4 * p], md[4 * p + 1])


@njit(cache=True, error_model="numpy")
def _gb_substep(gb, W, h, node, lk, t_in, t_out):
    """One substep of length h of 'rk4_kink' (``node`` False), 'rk4_node' (True) or 'rk4_seg' (True
    and ``lk`` LOOKUP_SEG: every evaluation, guard and root search in the cell of its own angle
    clamped to the held segment, docs/gearbox.md "rk4_seg") for the whole
    gearbox (docs/gearbox.md "Integrators"): the pair's rk4_kink / rk4_node substep
    (gearfmu.dynamics.integrators._kink_substep) with every mesh holding its own cell, segment
    and pair modes.  A step ends at the earliest predicted node crossing of any mesh (rk4_node),
    else the trial step's guards of every mesh are located on the step's Hermite interpolant,
    mapped to each mesh's (theta_p, omega_p, x, v), and the earliest event wins.  Returns the
    number of events."""
    mi, mf, bf, si, sf, n, nm, ns, lb, n2 = gb
    oy, of0, oy1, of1, oyt = W_Y * n2, W_F0 * n2, W_Y1 * n2, W_F1 * n2, W_YT * n2
    seg = lk == LOOKUP_SEG
    rem = h
    nev = 0
    while True:
        if node:  # the held cell follows theta_p inside the held segment
            for m in range(nm):
                k = m * MI
                wk = _f64p(mi[k + I_WK])
                th, om, x, v = _local(mi, mf, m, W, oy)
                cn = np.floor(th * mf[m * MF + F_INV])
                if cn + 1.0 > wk[16] and cn < wk[17] and cn != wk[WK_ND]:
                    tab = _mtab(mi, mf, m)
                    md = _i64p(mi[k + I_MD])
                    i0, i1 = _cell_nodes(cn, tab[7])
                    _hold(tab, md, wk, cn, i0, i1)
                    _zone_sel(tab, md, cn, i0, wk[16], wk[17])
        _rhs(gb, W, oy, of0, t_in, t_out, lk)
        if node and nev < KINK_MAX_EVENTS:
            best_tau = -1.0
            best_m = -1
            for m in range(nm):
                wk = _f64p(mi[m * MI + I_WK])
                th, om, x, v = _local(mi, mf, m, W, oy)
                fa, fb, fc, fd = _local(mi, mf, m, W, of0)
                tau = _node_time(th, om, fb, rem, wk[16], wk[17], mf[m * MF + F_DPHI])
                if tau > 0.0 and (best_m < 0 or tau < best_tau):
                    best_tau = tau
                    best_m = m
            if best_m >= 0:
                _rk4(gb, W, oy, of0, best_tau, oyt, t_in, t_out, lk)
                ok = True
                for m in range(nm):
                    if not _mesh_guards_hold(gb, W, oyt, m, m != best_m, lk):
                        ok = False
                        break
                if ok:
                    up = _local(mi, mf, best_m, W, oy)[1] > 0.0
                    for i in range(n2):
                        W[oy + i] = W[oyt + i]
                    rem = rem - best_tau
                    nev += 1
                    _mesh_cross(gb, W, best_m, up, True)
                    if not rem > 0.0:
                        break
                    continue
        _rk4(gb, W, oy, of0, rem, oy1, t_in, t_out, lk)
        if nev >= KINK_MAX_EVENTS:
            for i in range(n2):
                W[oy + i] = W[oy1 + i]
            for m in range(nm):
                _mesh_start(gb, W, m, node)
            break
        any_neg = False
        for m in range(nm):
            if not _mesh_guards_hold(gb, W, oy1, m, True, lk):
                any_neg = True
                break
        if not any_neg:
            for i in range(n2):
                W[oy + i] = W[oy1 + i]
            break
        _rhs(gb, W, oy1, of1, t_in, t_out, lk)
        best = 2.0
        best_m = -1
        best_gi = -1
        for m in range(nm):
            k = m * MI
            tab = _mtab(mi, mf, m)
            md = _i64p(mi[k + I_MD])
            wk = _f64p(mi[k + I_WK])
            p = tab[8]
            nd, i0, i1 = wk[WK_ND], md[4 * p], md[4 * p + 1]
            ta, tb, tc, td = _local(mi, mf, m, W, oy1)
            have = False
            for gi in range(2 + 3 * p):
                if seg:
                    g = _guard_seg(tab, md, gi, ta, tb, tc, td, nd, i0, i1, wk[16], wk[17], 0.0, 0.0)
                else:
                    g = _guard_at(tab, md, gi, ta, tb, tc, td, nd, i0, i1, wk[16], wk[17])
                if g < 0.0:
                    if not have:  # the mesh's Hermite data: its local view of y, f0, y1, f1
                        wk[0], wk[1], wk[2], wk[3] = _local(mi, mf, m, W, oy)
                        wk[4], wk[5], wk[6], wk[7] = _local(mi, mf, m, W, of0)
                        wk[8], wk[9], wk[10], wk[11] = ta, tb, tc, td
                        wk[12], wk[13], wk[14], wk[15] = _local(mi, mf, m, W, of1)
                        have = True
                    s = _guard_root(tab, md, gi, g, wk, rem, nd, i0, i1, seg, 0.0, 0.0)
                    if s < best:
                        best = s
                        best_m = m
                        best_gi = gi
        if best_m < 0:
            for i in range(n2):
                W[oy + i] = W[oy1 + i]
            break
        if best >= 1.0:
            for i in range(n2):
                W[oy + i] = W[oy1 + i]
            rem = 0.0
        elif best > 0.0:
            tau = best * rem
            _rk4(gb, W, oy, of0, tau, oyt, t_in, t_out, lk)
            for i in range(n2):
                W[oy + i] = W[oyt + i]
            rem = rem - tau
        nev += 1
        if best_gi < 2:
            _mesh_cross(gb, W, best_m, best_gi == 1, node)
        else:
            k = best_m * MI
            tab = _mtab(mi, mf, best_m)
            md = _i64p(mi[k + I_MD])
            wk = _f64p(mi[k + I_WK])
            p = tab[8]
            j = (best_gi - 2) // 3
            th, om, x, v = _local(mi, mf, best_m, W, oy)
            kv = ev = es = bv = 0.0
            if md[j] == 0 and tab[11] == 0:   # the sub-mode decision of a contact onset reads the tables
                kv, ev, es, bv = _held_tables(tab, md, j, th, wk[WK_ND], md[4 * p], md[4 * p + 1], wk[16], wk[17],
                                              seg)
            _switch_pair(md, p, j, (best_gi - 2) - 3 * j, tab[11], kv, ev, es, bv, x, v, om, tab[10])
        if not rem > 0.0:
            break
    return nev


@njit(cache=True, error_model="numpy")
def _write_row(gb, W, row, out_body, out_mesh, out_pair, pair_off, out_shaft):
    """Output row ``row`` from the state y (docs/gearbox.md "Outputs"): every body's angle and
    speed, every mesh's x, v, force, stiffness in contact and pair forces (the lookup and force
    law of docs/model.md "Outputs" with the step's torque row), every shaft's torque."""
    mi, mf, bf, si, sf, n, nm, ns, lb, n2 = gb
    for i in range(n):
        gi = bf[n + i]
        out_body[row, 2 * i] = gi * W[0] + _u(W, 0, i)
        out_body[row, 2 * i + 1] = gi * W[1] + _u(W, 1, i)
    for m in range(nm):
        tab = _mtab(mi, mf, m)
        th, om, x, v = _local(mi, mf, m, W, 0)
        nd, i0, i1, w = _phi_cell(th, tab[12], tab[7], _CELL_NONE, 0)
        ftot = 0.0
        ks = 0.0
        for j in range(tab[8]):
            kv, ev, es, bv = _kvals(tab, j, i0, i1, w)
            fj, st = _pair_force(kv, ev, es, bv, x, v, om, tab[10], tab[11])
            out_pair[row, pair_off[m] + j] = fj
            ftot += fj
            if st != 0:
                ks += kv
        out_mesh[row, 4 * m] = x
        out_mesh[row, 4 * m + 1] = v
        out_mesh[row, 4 * m + 2] = ftot
        out_mesh[row, 4 * m + 3] = ks
    for s in range(ns):
        a = si[2 * s]
        b = si[2 * s + 1]
        out_shaft[row, s] = sf[2 * s] * (_u(W, 0, a) - _u(W, 0, b)) + sf[2 * s + 1] * (_u(W, 1, a) - _u(W, 1, b))


@njit(cache=True, error_model="numpy")
def run(icode, y, t_in, t_out, it_rows, wt_rows, step0, n_steps, H, n_sub, h, mi, mf, bf, si, sf, n, lb,
        out_body, out_mesh, out_pair, pair_off, out_shaft, out_events):
    """Communication steps step0 .. step0 + n_steps - 1 from the state ``y`` (2n, updated in place):
    row step0 + 1 + s of the outputs after step s (row 0 is written when step0 == 0).  Step s holds
    the motor torque t_in[s] and the load torque t_out[s] (N*m) and, per mesh m, the torque row
    it_rows[s, m] with weight wt_rows[s, m]; n_sub substeps of h (s).  ``icode``: 0 'rk4', 1
    'rk4_kink', 2 'rk4_node', 3 'rk4_seg' (the meshes' flags those of rk4_seg).  Returns the number of completed steps (fewer when the state turned
    non-finite).  ``mi``, ``mf`` are the per-mesh data of the module docstring (their
    addresses of k, e, b, flags, cuts, mode and work arrays must stay valid: the caller owns
    them)."""
    nm = mi.shape[0] // MI
    ns = si.shape[0] // 2
    n2 = 2 * n
    W = np.zeros(W_VECTORS * n2 + n)
    for i in range(n2):
        W[i] = y[i]
    gb = (_i64p(_addr(mi)), _f64p(_addr(mf)), _f64p(_addr(bf)), _i64p(_addr(si)),
          _f64p(_addr(sf)), n, nm, ns, lb, n2)
    wp = _f64p(_addr(W))
    mip = gb[0]
    mfp = gb[1]
    done = n_steps
    for s in range(n_steps):
        r = step0 + s
        for m in range(nm):
            mip[m * MI + I_IT] = it_rows[r, m]
            mfp[m * MF + F_WT] = wt_rows[r, m]
            mip[m * MI + I_ND] = _CELL_NONE
            mip[m * MI + I_I0] = 0
        if r == 0:
            _write_row(gb, wp, 0, out_body, out_mesh, out_pair, pair_off, out_shaft)
        nev = 0
        if icode >= 1:
            node = icode >= 2
            lk = LOOKUP_SEG if icode == ICODE_SEG else LOOKUP_HELD
            for m in range(nm):
                _mesh_start(gb, wp, m, node)
            for _ in range(n_sub):
                nev += _gb_substep(gb, wp, h, node, lk, t_in[r], t_out[r])
        else:
            for _ in range(n_sub):
                _rhs(gb, wp, 0, W_F0 * n2, t_in[r], t_out[r], LOOKUP_PLAIN)
                _rk4(gb, wp, 0, W_F0 * n2, h, W_YT * n2, t_in[r], t_out[r], LOOKUP_PLAIN)
                for i in range(n2):
                    W[i] = W[W_YT * n2 + i]
        out_events[r + 1] = nev
        _write_row(gb, wp, r + 1, out_body, out_mesh, out_pair, pair_off, out_shaft)
        finite = True
        for i in range(n2):
            if not math.isfinite(W[i]):
                finite = False
        if not finite:
            done = s + 1
            break
    for i in range(n2):
        y[i] = W[i]
    return done
