"""Right-hand side of the multi-pair gear dynamic model (numba kernels, SI units).

The table lookup, the per-pair force laws and the quasi-static equilibrium of
docs/model.md, written operation by operation as gearfmu/fmu/kernel/gearkernel.c
so that the numba solver and the C kernel agree bit for bit (no fastmath: it
would reorder the arithmetic).  Model: Xu et al. 2022 eq (1)-(6), P tooth-pair slots
with stiffness k_j (N/m), meshing error e_j (m), half backlash b_j (m) and
damping c (N*s/m), indexed by the pinion angle theta1 (rad).

The kernels take the tables as raw data pointers packed with the scalars in one
tuple ``tab`` (:func:`_tab`): a numba call with an array argument increfs and
decrefs the array's memory block (atomic operations the refcount pruner cannot
remove across calls, loops and branches), and the integrators call these
kernels many times per substep.  ``tab`` = (kp, ep, bp, o0, o1, rows2, wt,
n_phi, P, dphi, c, model, inv_dphi, fp, zp, zoned): pointers of k, e (NT, P, N) and b (P, N),
the offsets of torque rows it and it+1, whether a second row is blended
(NT > 1), its weight, the node count N, the slot count P, the cell width
(rad), the damping (N*s/m), the damping law (0 elastobacklash, 1 contact_zone) and
the reciprocal cell width N/Phi (1/rad), and the pointer of the node kink
flags (N uint8, :func:`_node_flags`, or for rk4_seg :func:`_seg_flags`; rk4_node and rk4_seg stop
only at flagged nodes), the pointer
of the contact-zone cuts (2, P, N) and whether they are read (:func:`_with_zones`,
docs/model.md "Contact-zone edges"; off: plain linear interpolation, the arithmetic of
the C kernel's lookup without cuts, gk_lookup.h).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, types
from numba.extending import intrinsic

#: no carried cell (_phi_cell): more than one cell away from every global cell index
_CELL_NONE = -(1 << 62)
#: 2^52: below it the global cell index and s - nd are exact in doubles
_CELL_LIMIT = 4503599627370496.0
#: relative tolerance of the node kink test (:func:`_node_flags`; gearkernel.h GK_NODE_KINK_TOL,
#: docs/native.md "rk4_node"): a second difference above it times the sum of the three |values|
NODE_KINK_TOL = 1e-9
#: relative tolerance of rk4_seg's big-kink stops (:func:`_seg_flags`; gearkernel.h
#: GK_SEG_KINK_TOL): the test of NODE_KINK_TOL with this threshold.  Chosen from the default
#: scene's tables (docs/model.md "rk4_seg"): at 64 points per mesh the sampled smooth curves
#: bend by at most 0.0054 (e), the kinks at the ends of contact and error curves by 0.045 to 1
SEG_KINK_TOL = 1e-2
#: most table nodes that get kink flags (gearkernel.h GK_NODE_FLAGS_MAX); more: every node flagged
NODE_FLAGS_MAX = 8192


@intrinsic
def _ptr(typingctx, arr):
    """Data pointer (CPointer) of a C-contiguous array, no reference counting.
    Valid while the array is alive; the caller owns the arrays."""
    if not isinstance(arr, types.Array):
        return None
    sig = types.CPointer(arr.dtype)(arr)

    def codegen(context, builder, signature, args):
        ary = context.make_array(signature.args[0])(context, builder, value=args[0])
        return ary.data

    return sig, codegen


@njit(cache=True, error_model="numpy", inline="always")
def _phi_cell(theta1, inv_dphi, n_phi, nd_prev, i0_prev):
    """docs/model.md 'Table lookup': (nd, i0, i1, w) at pinion angle theta1 (rad),
    s = theta1*inv_dphi, global cell nd = floor(s), nodes i0 = nd mod N and i1,
    weight w = s - nd.  (nd_prev, i0_prev) is the cell of the previous evaluation
    (_CELL_NONE: none): when nd moved by 0 or +-1, i0 follows without an integer
    division.  The result does not depend on it (the arithmetic of gearkernel.c
    phi_cell)."""
    s = theta1 * inv_dphi
    if not (s > -_CELL_LIMIT and s < _CELL_LIMIT):
        # 2^52 cells or more: an integer number of cells (w = 0); non-finite:
        # node 0, w = nan (the state is non-finite); never out of bounds
        if math.isfinite(s):
            r = np.fmod(s, float(n_phi))
            if r < 0.0:
                r += float(n_phi)
            i0 = int(r)
            w = 0.0
        else:
            i0 = 0
            w = s - s
        i1 = i0 + 1
        if i1 == n_phi:
            i1 = 0
        return _CELL_NONE, i0, i1, w
    nd = int(s)             # toward zero ...
    if nd > s:              # ... so floor(s)
        nd -= 1
    dn = nd - nd_prev
    if dn == 0:
        i0 = i0_prev
    elif dn == 1:
        i0 = i0_prev + 1
        if i0 == n_phi:
            i0 = 0
    elif dn == -1:
        i0 = n_phi - 1 if i0_prev == 0 else i0_prev - 1
    else:
        i0 = nd % n_phi     # floor modulo: in [0, N)
    i1 = i0 + 1
    if i1 == n_phi:
        i1 = 0
    w = s - nd
    return nd, i0, i1, w


@njit(cache=True, error_model="numpy")
def _cell_nodes(nd, n_phi):
    """(i0, i1) of global cell nd (float holding an integer): i0 = nd mod N."""
    r = nd - n_phi * np.floor(nd / n_phi)
    i0 = int(r)
    if i0 < 0:
        i0 = 0
    if i0 >= n_phi:
        i0 = n_phi - 1
    i1 = i0 + 1
    if i1 == n_phi:
        i1 = 0
    return i0, i1


@njit(cache=True, error_model="numpy")
def _torque_index(t1, torque):
    """Bracketing torque row it and weight wt for Tq = clamp(T1, torque[0], torque[-1]).

    it is the largest index in [0, NT-2] with torque[it] <= Tq,
    wt = (Tq - torque[it])/(torque[it+1] - torque[it]).  NT == 1: (0, 0.0).
    """
    nt = torque.shape[0]
    if nt == 1:
        return 0, 0.0
    tq = t1
    if tq < torque[0]:
        tq = torque[0]
    if tq > torque[nt - 1]:
        tq = torque[nt - 1]
    it = 0
    while it < nt - 2 and torque[it + 1] <= tq:
        it += 1
    wt = (tq - torque[it]) / (torque[it + 1] - torque[it])
    return it, wt


@njit(cache=True, error_model="numpy", inline="always")
def _table_pointers(k, e, b):
    """(data pointers of k, e (NT, P, N) and b (P, N), P, N); the arrays must be
    C-contiguous and outlive the pointers' use."""
    return _ptr(k), _ptr(e), _ptr(b), k.shape[1], k.shape[2]


@njit(cache=True, error_model="numpy", inline="always")
def _tab(kp, ep, bp, it, rows2, wt, n_phi, p, dphi, c, model, inv_dphi, fp):
    """The ``tab`` tuple of :func:`_kvals` for torque row it (and it+1 if rows2), plain
    linear interpolation (no contact-zone cuts: the last two entries are a placeholder
    pointer and False; :func:`_with_zones` sets them)."""
    o0 = it * p * n_phi
    o1 = (it + 1) * p * n_phi if rows2 else o0
    return (kp, ep, bp, o0, o1, rows2, wt, n_phi, p, dphi, c, model, inv_dphi, fp, kp, False)


@njit(cache=True, error_model="numpy", inline="always")
def _with_zones(tab, zp):
    """``tab`` with the sub-cell lookup on: zp is the data pointer of the (2, P, N) cuts of
    gearfmu.tables.zones.zone_cuts (docs/model.md "Contact-zone edges")."""
    return (tab[0], tab[1], tab[2], tab[3], tab[4], tab[5], tab[6], tab[7], tab[8], tab[9], tab[10], tab[11],
            tab[12], tab[13], zp, True)


@njit(cache=True, error_model="numpy", inline="always")
def _bent(a0, a1, a2, tol):
    """True when |(a2 - a1) - (a1 - a0)| > tol*(|a0| + |a1| + |a2|) (or not finite)."""
    d = (a2 - a1) - (a1 - a0)
    s = (abs(a0) + abs(a1)) + abs(a2)
    return not abs(d) <= tol * s


@njit(cache=True, error_model="numpy")
def _stop_flags(k, e, b, cuts, zoned, tol):
    """Stop flag (uint8) of every table node: the loop of :func:`_node_flags` (``tol`` =
    NODE_KINK_TOL, no zone cuts) and :func:`_seg_flags` (``tol`` = SEG_KINK_TOL, the zone
    cuts when ``zoned``)."""
    nt, p, n = k.shape
    flags = np.ones(n, dtype=np.uint8)
    if n > NODE_FLAGS_MAX:
        return flags
    for i in range(n):
        im = n - 1 if i == 0 else i - 1
        ip = 0 if i == n - 1 else i + 1
        bent = False
        for j in range(p):
            if _bent(b[j, im], b[j, i], b[j, ip], tol):
                bent = True
            pos = False
            nonpos = False
            for r in range(nt):
                ka = k[r, j, im]
                kb = k[r, j, i]
                kc = k[r, j, ip]
                if _bent(ka, kb, kc, tol) or _bent(e[r, j, im], e[r, j, i], e[r, j, ip], tol):
                    bent = True
                ml = ka + 0.5 * (kb - ka)
                mr = kb + 0.5 * (kc - kb)
                if ml > 0.0 and mr > 0.0:
                    pos = True
                elif not ml > 0.0 and not mr > 0.0:
                    nonpos = True
                else:
                    pos = True
                    nonpos = True
            if pos and nonpos:
                bent = True
            if zoned and (cuts[0, j, im] >= 0.0 or cuts[0, j, i] >= 0.0):
                bent = True
        flags[i] = 1 if bent else 0
    return flags


@njit(cache=True, error_model="numpy")
def _node_flags(k, e, b):
    """Kink flag (uint8) of every table node i (docs/native.md "rk4_node"): 1 when in any
    torque row and slot the table k, e or b bends at node i (:func:`_bent` with NODE_KINK_TOL,
    periodic neighbours), or the contact_zone flag kpos (k at the cell midpoint > 0) can differ
    between the cells on either side (the midpoint values over every row and both cells
    are neither all > 0 nor all <= 0).  Every node is flagged when N > NODE_FLAGS_MAX.
    The arithmetic of gk_stops.c gki_node_flags."""
    return _stop_flags(k, e, b, k, False, NODE_KINK_TOL)   # no zone cuts: k is never read as cuts


@njit(cache=True, error_model="numpy")
def _seg_flags(k, e, b, cuts, zoned):
    """Stop flag (uint8) of every table node i for rk4_seg (docs/model.md "rk4_seg"): 1 where
    the contact_zone flag kpos (k at the cell midpoint > 0) can differ between the cells on
    either side (the second test of :func:`_node_flags`), where in some torque row and slot
    k, e or b has a big kink, |(a[i+1] - a[i]) - (a[i] - a[i-1])| > SEG_KINK_TOL*(|a[i-1]| +
    |a[i]| + |a[i+1]|) (:func:`_bent`, periodic neighbours; the small kinks of a smoothly
    curved table sampled at its nodes are not stops: rk4_seg reads every cell's own line),
    and, with the contact-zone cuts (``zoned``, ``cuts`` (2, P, N)), at both nodes of every
    cell that holds a zone edge (an edge may lie on the node itself, where k steps).  Every
    node is flagged when N > NODE_FLAGS_MAX.  The arithmetic of gk_stops.c gki_node_flags
    (its rk4_seg bit)."""
    return _stop_flags(k, e, b, cuts, zoned, SEG_KINK_TOL)


@njit(cache=True, error_model="numpy")
def _row_values(kp, ep, o, i0, i1, w, inv_dphi):
    """k (N/m), e (m) and de/dphi (m/rad) of the slot row starting at offset o of
    the k, e pointers, interpolated at nodes (i0, i1) with weight w."""
    ka = kp[o + i0]
    kb = kp[o + i1]
    kv = ka + w * (kb - ka)
    ea = ep[o + i0]
    eb = ep[o + i1]
    ev = ea + w * (eb - ea)
    es = (eb - ea) * inv_dphi
    return kv, ev, es


@njit(cache=True, error_model="numpy")
def _edge_line(ap, o, i0, i1, w, ws, lo, hi, n_phi, inv_dphi):
    """Value and phi-slope at cell weight w of the row at offset o of pointer ap in a cell
    holding a contact-zone edge (cuts lo, hi; docs/model.md "Contact-zone edges"), on the
    side of the cut that weight ws selects: ws < lo the line of the cell to the left
    extended, ws >= hi the line of the cell to the right extended back, else the plain
    interpolation (third result False: outside the zone)."""
    if ws < lo:
        im = n_phi - 1 if i0 == 0 else i0 - 1
        a = ap[o + im]
        b = ap[o + i0]
        return b + w * (b - a), (b - a) * inv_dphi, True
    if ws >= hi:
        i2 = 0 if i1 == n_phi - 1 else i1 + 1
        a = ap[o + i1]
        b = ap[o + i2]
        return a + (w - 1.0) * (b - a), (b - a) * inv_dphi, True
    a = ap[o + i0]
    b = ap[o + i1]
    return a + w * (b - a), (b - a) * inv_dphi, False


@njit(cache=True, error_model="numpy")
def _kvals_edge(tab, j, i0, i1, w, ws, lo, hi):
    """:func:`_kvals` in a cell that holds a contact-zone edge, on the side of the cut that
    ws selects: k = 0 outside the zone, the in-zone side's extended line inside (k, e, b
    alike; e and b outside as plain)."""
    kp, ep, bp, o0, o1, rows2, wt, n_phi, p, dphi, c, model, inv_dphi, fp, zp, zoned = tab
    r = j * n_phi
    kv, ks, inz = _edge_line(kp, o0 + r, i0, i1, w, ws, lo, hi, n_phi, inv_dphi)
    ev, es, inz = _edge_line(ep, o0 + r, i0, i1, w, ws, lo, hi, n_phi, inv_dphi)
    if rows2:
        kv2, ks2, inz = _edge_line(kp, o1 + r, i0, i1, w, ws, lo, hi, n_phi, inv_dphi)
        ev2, es2, inz = _edge_line(ep, o1 + r, i0, i1, w, ws, lo, hi, n_phi, inv_dphi)
        kv = kv + wt * (kv2 - kv)
        ev = ev + wt * (ev2 - ev)
        es = es + wt * (es2 - es)
    bv, bs, inz = _edge_line(bp, r, i0, i1, w, ws, lo, hi, n_phi, inv_dphi)
    if not inz:
        kv = 0.0
    elif kv < 0.0:   # an extended line never gives a negative stiffness
        kv = 0.0
    return kv, ev, es, bv


@njit(cache=True, error_model="numpy", inline="always")
def _kvals(tab, j, i0, i1, w):
    """k_j (N/m), e_j (m), de_j/dphi (m/rad), b_j (m) of slot j at cell nodes
    (i0, i1) and weight w (docs/model.md 'Table lookup'): phi interpolation in
    torque row it, and when rows2 (NT > 1) also in row it+1, then linear
    interpolation between the two rows with weight wt.  With the contact-zone cuts
    on (:func:`_with_zones`) a cell that holds a zone edge goes to :func:`_kvals_edge`."""
    return _kvals_sel(tab, j, i0, i1, w, -1)


@njit(cache=True, error_model="numpy", inline="always")
def _kvals_sel(tab, j, i0, i1, w, sel):
    """:func:`_kvals` with the side of a contact-zone cut held (the rk4_kink mode, see
    :func:`_zone_sel`): sel -1 the side of w, 0 the in-zone part left of the cut, 1 the
    part outside the zone, 2 the in-zone part right of the cut.  A cell without an
    edge ignores sel."""
    kp, ep, bp, o0, o1, rows2, wt, n_phi, p, dphi, c, model, inv_dphi, fp, zp, zoned = tab
    r = j * n_phi
    if zoned:
        lo = zp[r + i0]
        if lo >= 0.0:
            ws = w
            if sel == 0:
                ws = -1.0
            elif sel == 1:
                ws = lo
            elif sel == 2:
                ws = 2.0
            return _kvals_edge(tab, j, i0, i1, w, ws, lo, zp[p * n_phi + r + i0])
    kv, ev, es = _row_values(kp, ep, o0 + r, i0, i1, w, inv_dphi)
    if rows2:
        kv2, ev2, es2 = _row_values(kp, ep, o1 + r, i0, i1, w, inv_dphi)
        kv = kv + wt * (kv2 - kv)
        ev = ev + wt * (ev2 - ev)
        es = es + wt * (es2 - es)
    ba = bp[r + i0]
    bb = bp[r + i1]
    bv = ba + w * (bb - ba)
    return kv, ev, es, bv


@njit(cache=True, error_model="numpy")
def _zone_sel(tab, md, nd, i0, lo, hi):
    """Hold the side of every pair's contact-zone cut for cell nd inside the held segment
    [lo, hi) (global node units): md[3P + j] = 0 left in-zone part, 1 outside, 2 right
    in-zone part, by the segment's midpoint in the cell; -1 in a cell without an edge
    (and always without the cuts).  gk_stops.c gki_zone_sel."""
    p = tab[8]
    n_phi = tab[7]
    zp = tab[14]
    a = lo if lo > nd else nd
    b = hi if hi < nd + 1.0 else nd + 1.0
    wm = 0.5 * (a + b) - nd
    for j in range(p):
        sel = -1
        if tab[15]:
            r = j * n_phi + i0
            clo = zp[r]
            if clo >= 0.0:
                if wm < clo:
                    sel = 0
                elif wm >= zp[p * n_phi + r]:
                    sel = 2
                else:
                    sel = 1
        md[3 * p + j] = sel


@njit(cache=True, error_model="numpy")
def _cut_above(tab, i0, f, incl):
    """Smallest cut fraction of cell i0 over all slots above f (at or above with incl)
    and below 1 (2.0: none; always none without the cuts)."""
    best = 2.0
    if tab[15]:
        p = tab[8]
        n_phi = tab[7]
        zp = tab[14]
        for j in range(p):
            r = j * n_phi + i0
            clo = zp[r]
            if clo >= 0.0:
                chi = zp[p * n_phi + r]
                if (clo > f or (incl and clo == f)) and clo < 1.0 and clo < best:
                    best = clo
                if (chi > f or (incl and chi == f)) and chi < 1.0 and chi < best:
                    best = chi
    return best


@njit(cache=True, error_model="numpy")
def _cut_below(tab, i0, f, incl):
    """Largest cut fraction of cell i0 over all slots below f (at or below with incl)
    and above 0 (-1.0: none; always none without the cuts)."""
    best = -1.0
    if tab[15]:
        p = tab[8]
        n_phi = tab[7]
        zp = tab[14]
        for j in range(p):
            r = j * n_phi + i0
            clo = zp[r]
            if clo >= 0.0:
                chi = zp[p * n_phi + r]
                if (clo < f or (incl and clo == f)) and clo > 0.0 and clo > best:
                    best = clo
                if (chi < f or (incl and chi == f)) and chi > 0.0 and chi > best:
                    best = chi
    return best


@njit(cache=True, error_model="numpy", inline="always")
def _pair_force(kv, ev, es, bv, x, v, omega1, c, model):
    """Force of one pair (N) and its contact state (1 drive, -1 back, 0 separated)."""
    de = es * omega1
    d = x - ev
    if d > bv:
        fc = kv * (d - bv)
        state = 1
    elif d < -bv:
        fc = kv * (d + bv)
        state = -1
    else:
        fc = 0.0
        state = 0
    fd = c * (v - de)
    if model == 0:  # elastobacklash
        if state == 1:
            f = fc + min(fc, fd)
            if f < 0.0:
                f = 0.0
        elif state == -1:
            f = fc + max(fc, fd)
            if f > 0.0:
                f = 0.0
        else:
            f = 0.0
    else:  # contact_zone
        if kv > 0.0:
            f = fc + fd
        else:
            f = 0.0
    return f, state


@njit(cache=True, error_model="numpy", inline="always")
def _pair_force_locked(kv, ev, es, bv, x, v, omega1, c, model, reg, sub, kpos):
    """Force of one pair (N) with its contact mode held: reg 1 drive, -1 back, 0
    separated; sub 0 'two' (2 fc), 1 'sum' (fc + fd), 2 'zero' (clamped);
    kpos (contact_zone) the pair is in the contact zone in this cell."""
    de = es * omega1
    d = x - ev
    if reg == 1:
        fc = kv * (d - bv)
    elif reg == -1:
        fc = kv * (d + bv)
    else:
        fc = 0.0
    fd = c * (v - de)
    if model == 0:
        if reg == 0 or sub == 2:
            return 0.0
        if sub == 0:
            return fc + fc
        return fc + fd
    if kpos != 0:
        return fc + fd
    return 0.0


@njit(cache=True, error_model="numpy")
def _pair_guard(q, kv, ev, es, bv, x, v, omega1, c, model, reg, sub):
    """Guard q (0..2) of a pair in mode (reg, sub): >= 0 while the mode holds;
    1.0 when guard q does not exist for this mode (docs/model.md 'rk4_kink'), also the sub-mode
    guards of an elastobacklash pair in contact with k = 0 in its sub-modes 'two' and 'zero', which
    both give it no force (a sign change of its damping force is no event; the event integrators
    stop where k turns positive and decide the sub-mode anew there).  gk_pair.h pair_guard (Model
    Exchange's indicators keep those guards: pair_guard_me)."""
    d = x - ev
    if reg == 0:
        if q == 0:
            return bv - d
        if q == 1:
            return d + bv
        return 1.0
    if q == 0:
        if reg == 1:
            return d - bv
        return -(d + bv)
    if model != 0:
        return 1.0
    if kv == 0.0 and sub != 1:   # k = 0 (out of the contact zone): 'two' and 'zero' both carry no force
        return 1.0
    if reg == 1:
        fc = kv * (d - bv)
    else:
        fc = kv * (d + bv)
    fd = c * (v - es * omega1)
    if reg == 1:
        if sub == 0:
            return fd - fc if q == 1 else 1.0
        if sub == 1:
            return fc - fd if q == 1 else fc + fd
        return -(fc + fd) if q == 1 else 1.0
    if sub == 0:
        return fc - fd if q == 1 else 1.0
    if sub == 1:
        return fd - fc if q == 1 else -(fc + fd)
    return fc + fd if q == 1 else 1.0


@njit(cache=True, error_model="numpy")
def _decide_sub(reg, kv, ev, es, bv, x, v, omega1, c):
    """Sub-mode of the elastobacklash law at the state (docs/model.md 'Per-pair force')."""
    if reg == 0:
        return 0
    d = x - ev
    fd = c * (v - es * omega1)
    if reg == 1:
        fc = kv * (d - bv)
        if fc < fd:
            return 0
        if fc + fd < 0.0:
            return 2
        return 1
    fc = kv * (d + bv)
    if fc > fd:
        return 0
    if fc + fd > 0.0:
        return 2
    return 1


@njit(cache=True, error_model="numpy", inline="always")
def _mesh_force(tab, theta1, omega1, x, v, nd, i0):
    """Total dynamic mesh force F = sum_j F_j (N), summed j = 0..P-1, and the cell
    (nd, i0) of theta1 (carried in from the previous evaluation, see _phi_cell).
    ``tab``: the table tuple of the module docstring."""
    n_phi = tab[7]
    nd, i0, i1, w = _phi_cell(theta1, tab[12], n_phi, nd, i0)
    f = 0.0
    for j in range(tab[8]):
        kv, ev, es, bv = _kvals(tab, j, i0, i1, w)
        fj, st = _pair_force(kv, ev, es, bv, x, v, omega1, tab[10], tab[11])
        f += fj
    return f, nd, i0


@njit(cache=True, error_model="numpy", inline="always")
def _deriv_locked(tab, dyn, md, th, om, x, v, nd, i0, i1):
    """Right-hand side with the mode (cell nd, per-pair reg/sub/kpos) held.
    Two-inertia form (sdof = False) or time-indexed SDOF (theta1' = omega1,
    omega1' = 0, m_e v' = F_m - F)."""
    dphi = tab[9]
    c = tab[10]
    model = tab[11]
    p = tab[8]
    sdof, t1, t2, rb1, rb2, in1, in2, fm, me, ii1, ii2 = dyn
    w = (th - nd * dphi) * tab[12]
    f = 0.0
    for j in range(p):
        kv, ev, es, bv = _kvals_sel(tab, j, i0, i1, w, md[3 * p + j])
        f += _pair_force_locked(kv, ev, es, bv, x, v, om, c, model, md[j], md[p + j], md[2 * p + j])
    if sdof:
        return om, 0.0, v, (fm - f) / me
    return om, (t1 - rb1 * f) * ii1, v, rb1 * (t1 - rb1 * f) * ii1 - rb2 * (rb2 * f - t2) * ii2


@njit(cache=True, error_model="numpy")
def _outputs_row(tab, theta1, omega1, x, v, pair_out, row):
    """Write the pair forces F_j (N) of output row ``row``; return (mesh force
    F = sum_j F_j (N), mesh stiffness (N/m): the sum of k_j over the pairs in
    contact), docs/model.md 'Outputs'."""
    nd, i0, i1, w = _phi_cell(theta1, tab[12], tab[7], _CELL_NONE, 0)
    ftot = 0.0
    ks = 0.0
    for j in range(tab[8]):
        kv, ev, es, bv = _kvals(tab, j, i0, i1, w)
        fj, st = _pair_force(kv, ev, es, bv, x, v, omega1, tab[10], tab[11])
        pair_out[row, j] = fj
        ftot += fj
        if st != 0:
            ks += kv
    return ftot, ks


@njit(cache=True, error_model="numpy")
def _equilibrium(theta1, t1, rb1, k, e, b, torque, inv_dphi):
    """docs/model.md 'Initial state': x (m) of the quasi-static equilibrium at theta1
    under F_m = T1/Rb1, by exactly 200 bisections.  Returns nan if no slot has k > 0.
    k, e (NT, P, N) and b (P, N) must be C-contiguous."""
    it, wt = _torque_index(t1, torque)
    kp, ep, bp, p, n_phi = _table_pointers(k, e, b)
    no_flags = np.ones(1, dtype=np.uint8)   # the flags are not read here
    tab = _tab(kp, ep, bp, it, k.shape[0] > 1, wt, n_phi, p, np.nan, 0.0, 0, inv_dphi, _ptr(no_flags))
    return _equilibrium_tab(tab, theta1, t1 / rb1)


@njit(cache=True, error_model="numpy")
def _equilibrium_zoned(theta1, t1, rb1, k, e, b, torque, inv_dphi, cuts):
    """:func:`_equilibrium` with the sub-cell lookup at the contact-zone edges (``cuts``: the
    C-contiguous (2, P, N) array of gearfmu.tables.zones.zone_cuts)."""
    it, wt = _torque_index(t1, torque)
    kp, ep, bp, p, n_phi = _table_pointers(k, e, b)
    no_flags = np.ones(1, dtype=np.uint8)
    tab = _tab(kp, ep, bp, it, k.shape[0] > 1, wt, n_phi, p, np.nan, 0.0, 0, inv_dphi, _ptr(no_flags))
    return _equilibrium_tab(_with_zones(tab, _ptr(cuts)), theta1, t1 / rb1)


@njit(cache=True, error_model="numpy")
def _equilibrium_tab(tab, theta1, fm):
    """The bisection of :func:`_equilibrium` on the table tuple ``tab`` under F_m = fm (N)."""
    n_phi = tab[7]
    p = tab[8]
    nd, i0, i1, w = _phi_cell(theta1, tab[12], n_phi, _CELL_NONE, 0)
    kk = np.empty(p)
    ee = np.empty(p)
    bb = np.empty(p)
    s = 0.0
    lo_e = np.inf
    hi_e = -np.inf
    for j in range(p):
        kv, ev, es, bv = _kvals(tab, j, i0, i1, w)
        kk[j] = kv
        ee[j] = ev
        bb[j] = bv
        if kv > 0.0:
            s += kv
            if ev - bv < lo_e:
                lo_e = ev - bv
            if ev + bv > hi_e:
                hi_e = ev + bv
    if not s > 0.0:
        return np.nan
    lo = lo_e - abs(fm) / s - 1e-12
    hi = hi_e + abs(fm) / s + 1e-12
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        g = 0.0
        for j in range(p):
            if kk[j] > 0.0:
                d = mid - ee[j]
                if d > bb[j]:
                    g += kk[j] * (d - bb[j])
                elif d < -bb[j]:
                    g += kk[j] * (d + bb[j])
        g = g - fm
        if g < 0.0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)
