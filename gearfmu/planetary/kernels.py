"""Numba kernels of the planetary drivetrain solver (SI units; docs/planetary.md "Model", "Integrators").

The gearbox kernels (gearfmu.gearbox.kernels) generalised from torsional bodies to any DOFs: every
element is a sparse linear map of the DOFs.  The data is flat, C-like, so that a C kernel can hold
the same arrays:

* ``mi`` (int64, MI per mesh): the count and DOF indices of the mesh's x map (up to MX), of its
  table-angle map (up to 2), then as the gearbox: N, P, damping law, zoned, the data addresses of
  its k, e, b, node flags and contact-zone cuts, the torque row of the step, rows2, the addresses
  of its mode and work arrays, the cell carried by plain RK4;
* ``mf`` (float64, MF per mesh): the x coefficients (MX), the table-angle coefficients (2), the
  angle's psi coefficient and phase, the cell width dphi and N/Phi, the per-pair damping c, the
  torque-row weight of the step;
* ``bf`` (float64, 2n): 1/m_i, then g_i;  ``si`` (int64, SI per spring: count, SP DOF indices),
  ``sf`` (float64, SF per spring: SP coefficients, k, c);  ``fi`` (int64, FI per frame: the DOFs a, b,
  the drive DOF d that turns the frame or -1), ``ff`` (float64, FF per frame: R0, frame ratio g_f, its
  drive ratio h_f: the frame turns at g_f omega + h_f q_d').

A mesh's own state (theta, omega, x, v) -- the pair model's table angle and speed, DTE and its
rate -- is the linear map of y (plus the phase for theta), so the pair kernels of
gearfmu.gearbox._pair see every mesh exactly as the pair model sees its one mesh.  State ``y``
(2n): psi, omega, then (q_i, q_i') of DOFs 1..n-1.  The work array ``W`` holds y, the first stage
f0, a trial end y1 and its f1, the RK4 stage input, accumulator and slope, a predicted end yt and
the generalised forces, each at the offsets below (those of gearfmu.gearbox.kernels).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..gearbox._pair import (
    KINK_MAX_EVENTS, _CELL_NONE, _cell_nodes, _guard_at, _guard_root, _guard_seg, _held_tables, _kvals, _mesh_force,
    _mode_sync, _node_time, _pair_force, _pairs_hold, _phi_cell, _seg_cross, _seg_start, _switch_pair, _tab,
    _with_zones, _zone_sel,
)
from .model import MESH_MAP_DOFS as MX, SPRING_DOFS as SP
from ..gearbox.kernels import (ICODE_SEG, LOOKUP_HELD, LOOKUP_PLAIN, LOOKUP_SEG, W_ACC, W_F0, W_F1, W_KK, W_TAU, W_TMP,
                               W_VECTORS, W_Y, W_Y1, W_YT, WK, WK_ND, _addr, _f64p, _hold, _i64p, _mesh_locked,
                               _mesh_seg, _pairs_hold_seg, _u8p)

#: ints per mesh in ``mi`` and their slots
MI = 26
I_NX = 0
I_X0 = 1                 # 7 DOF indices of the x map: 1..7
I_NA = 8
I_A0 = 9                 # 2 DOF indices of the angle map: 9, 10
(I_N, I_NP, I_MODEL, I_ZONED, I_K, I_E, I_B, I_FLAGS, I_CUTS, I_IT, I_ROWS2, I_MD, I_WK, I_ND, I_I0) = range(11, 26)
#: floats per mesh in ``mf`` and their slots
MF = 15
F_X0 = 0                 # 7 coefficients of the x map: 0..6
F_A0 = 7                 # 2 coefficients of the angle map: 7, 8
F_AREF, F_PHI0, F_DPHI, F_INV, F_C, F_WT = range(9, 15)
#: per spring: ints (count + SP indices) and floats (SP coefficients, k, c)
SI = SP + 1
SF = SP + 2
#: per rotating frame: ints (its radial and tangential DOF, the drive DOF that turns it or -1) and floats
#: (R0, its speed per omega, per drive speed)
FI = 3
FF = 3


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
    """q_i (or q_i' with o + 1) of DOF i from the vector at offset o: 0 for DOF 0."""
    if i == 0:
        return 0.0
    return W[o + 2 * i]


@njit(cache=True, error_model="numpy", inline="always")
def _angle(mi, mf, m, W, o, off):
    """The mesh's own (theta, omega) of the vector at offset o of W (a state with ``off`` 1.0, or its
    derivative with ``off`` 0.0: the map is linear but for the phase)."""
    k = m * MI
    f = m * MF
    th = mf[f + F_AREF] * W[o] + off * mf[f + F_PHI0]
    om = mf[f + F_AREF] * W[o + 1]
    for j in range(mi[k + I_NA]):
        d = mi[k + I_A0 + j]
        c = mf[f + F_A0 + j]
        th += c * _u(W, o, d)
        om += c * _u(W, o + 1, d)
    return th, om


@njit(cache=True, error_model="numpy", inline="always")
def _local(mi, mf, m, W, o, off):
    """The mesh's own (theta, omega, x, v) of the vector at offset o of W: (theta, omega) of
    :func:`_angle`, then the x map."""
    k = m * MI
    f = m * MF
    th, om = _angle(mi, mf, m, W, o, off)
    x = 0.0
    v = 0.0
    for j in range(mi[k + I_NX]):
        d = mi[k + I_X0 + j]
        c = mf[f + F_X0 + j]
        x += c * _u(W, o, d)
        v += c * _u(W, o + 1, d)
    return th, om, x, v


@njit(cache=True, error_model="numpy")
def _rhs(gb, W, o, od, t_in, t_out, locked):
    """Derivative of the state at offset o of W into offset od (docs/planetary.md "Model"):
    generalised forces Q_i of the springs and meshes; the reference's acceleration from the balance
    of the generalised momentum, psi'' = (T_in - sum_i>0 g_i Q_i - sum_frames g_f ((R0 + q_a) Q_b -
    q_b Q_a))/m_0 (the internal forces cancel exactly, also where the linearised translations of a
    turning stage carry moments); q_i'' = (Q_i + external)/m_i - g_i psi'' plus the inertial terms of
    the rotating frames.  ``locked``: LOOKUP_HELD every mesh with its held mode (rk4_kink, rk4_node),
    LOOKUP_SEG the held mode read in the cell of each evaluation (rk4_seg), LOOKUP_PLAIN the plain
    lookup with the carried cell (rk4)."""
    mi, mf, bf, si, sf, fi, ff, n, nm, ns, nf, lb, n2 = gb
    ot = W_TAU * n2
    for i in range(n):
        W[ot + i] = 0.0
    for s in range(ns):
        v = 0.0
        vd = 0.0
        cnt = si[s * SI]
        for j in range(cnt):
            d = si[s * SI + 1 + j]
            c = sf[s * SF + j]
            v += c * _u(W, o, d)
            vd += c * _u(W, o + 1, d)
        fs = sf[s * SF + SP] * v + sf[s * SF + SP + 1] * vd
        for j in range(cnt):
            W[ot + si[s * SI + 1 + j]] -= sf[s * SF + j] * fs
    for m in range(nm):
        th, om, x, v = _local(mi, mf, m, W, o, 1.0)
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
        for j in range(mi[k + I_NX]):
            W[ot + mi[k + I_X0 + j]] -= mf[m * MF + F_X0 + j] * fm
    sg = 0.0
    for i in range(1, n):
        sg += bf[n + i] * W[ot + i]
    for r in range(nf):
        ia = fi[FI * r]
        ib = fi[FI * r + 1]
        sg += ff[FF * r + 1] * ((ff[FF * r] + W[o + 2 * ia]) * W[ot + ib] - W[o + 2 * ib] * W[ot + ia])
    ext0 = t_in
    if lb == 0:
        ext0 -= t_out
    else:
        W[ot + lb] -= t_out
    a0 = (ext0 - sg) * bf[0]
    W[od] = W[o + 1]
    W[od + 1] = a0
    for i in range(1, n):
        W[od + 2 * i] = W[o + 2 * i + 1]
        W[od + 2 * i + 1] = W[ot + i] * bf[i] - bf[n + i] * a0
    for r in range(nf):
        ia = fi[FI * r]
        ib = fi[FI * r + 1]
        R0 = ff[FF * r]
        gfr = ff[FF * r + 1]
        Om = gfr * W[o + 1]
        if fi[FI * r + 2] >= 0:   # a drive turns the frame too (its speed constant over a step)
            Om += ff[FF * r + 2] * W[o + 2 * fi[FI * r + 2] + 1]
        Od = gfr * a0
        qa = W[o + 2 * ia]
        qb = W[o + 2 * ib]
        va = W[o + 2 * ia + 1]
        vb = W[o + 2 * ib + 1]
        W[od + 2 * ia + 1] += 2.0 * Om * vb + Od * qb + Om * Om * (R0 + qa)
        W[od + 2 * ib + 1] += -2.0 * Om * va - Od * (R0 + qa) + Om * Om * qb


@njit(cache=True, error_model="numpy")
def _rk4(gb, W, oy, of0, h, oout, t_in, t_out, locked):
    """One classical RK4 step of length h from the state at oy with its first stage at of0 (given)
    into oout (the arithmetic of gearfmu.gearbox.kernels._rk4)."""
    n2 = gb[12]
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
    """A mesh's mode from the state (gearfmu.gearbox.kernels._mesh_start)."""
    mi, mf = gb[0], gb[1]
    tab = _mtab(mi, mf, m)
    md = _i64p(mi[m * MI + I_MD])
    wk = _f64p(mi[m * MI + I_WK])
    th, om, x, v = _local(mi, mf, m, W, 0, 1.0)
    nd = np.floor(th * tab[12])
    i0, i1 = _cell_nodes(nd, tab[7])
    _seg_start(tab, wk, nd, node, om, th)
    _zone_sel(tab, md, nd, i0, wk[16], wk[17])
    _mode_sync(tab, md, th, om, x, v, nd, i0, i1, True)
    _hold(tab, md, wk, nd, i0, i1)


@njit(cache=True, error_model="numpy")
def _mesh_cross(gb, W, m, up, node):
    """Move mesh m's held segment across its end (up) or start, then the zone sides and sub-modes."""
    mi, mf = gb[0], gb[1]
    tab = _mtab(mi, mf, m)
    md = _i64p(mi[m * MI + I_MD])
    wk = _f64p(mi[m * MI + I_WK])
    nd = _seg_cross(tab, wk, up, node)
    i0, i1 = _cell_nodes(nd, tab[7])
    _hold(tab, md, wk, nd, i0, i1)
    _zone_sel(tab, md, nd, i0, wk[16], wk[17])
    th, om, x, v = _local(mi, mf, m, W, 0, 1.0)
    _mode_sync(tab, md, th, om, x, v, nd, i0, i1, False)


@njit(cache=True, error_model="numpy")
def _mesh_guards_hold(gb, W, o, m, segment, lk):
    """True when no pair guard of mesh m is negative at the state at offset o (with ``segment``
    neither of its segment guards); the tables read as :func:`_rhs` with ``lk``."""
    mi, mf = gb[0], gb[1]
    tab = _mtab(mi, mf, m)
    md = _i64p(mi[m * MI + I_MD])
    wk = _f64p(mi[m * MI + I_WK])
    th, om, x, v = _local(mi, mf, m, W, o, 1.0)
    if segment and (th - wk[16] * tab[9] < 0.0 or wk[17] * tab[9] - th < 0.0):
        return False
    if lk == LOOKUP_SEG:
        return _pairs_hold_seg(tab, md, wk, th, om, x, v)
    p = tab[8]
    return _pairs_hold(tab, md, th, om, x, v, wk[WK_ND], md[4 * p], md[4 * p + 1])


@njit(cache=True, error_model="numpy")
def _substep(gb, W, h, node, lk, t_in, t_out):
    """One substep of 'rk4_kink' (``node`` False), 'rk4_node' (True) or 'rk4_seg' (True and ``lk``
    LOOKUP_SEG): the gearbox's substep (gearfmu.gearbox.kernels._gb_substep) over the generalised
    meshes.  rk4_seg runs as rk4_node between the stops of its flags (docs/planetary.md "rk4_seg"),
    every evaluation, guard and root search reading the tables in the cell of its own angle clamped
    to the held segment.  Returns the number of events."""
    mi, mf = gb[0], gb[1]
    nm = gb[8]
    n2 = gb[12]
    oy, of0, oy1, of1, oyt = W_Y * n2, W_F0 * n2, W_Y1 * n2, W_F1 * n2, W_YT * n2
    seg = lk == LOOKUP_SEG
    rem = h
    nev = 0
    while True:
        if node:  # the held cell follows theta inside the held segment
            for m in range(nm):
                k = m * MI
                wk = _f64p(mi[k + I_WK])
                th, om = _angle(mi, mf, m, W, oy, 1.0)
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
                th, om = _angle(mi, mf, m, W, oy, 1.0)
                fa, fb = _angle(mi, mf, m, W, of0, 0.0)
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
                    up = _angle(mi, mf, best_m, W, oy, 1.0)[1] > 0.0
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
            ta, tb, tc, td = _local(mi, mf, m, W, oy1, 1.0)
            have = False
            for gi in range(2 + 3 * p):
                if seg:
                    g = _guard_seg(tab, md, gi, ta, tb, tc, td, nd, i0, i1, wk[16], wk[17], 0.0, 0.0)
                else:
                    g = _guard_at(tab, md, gi, ta, tb, tc, td, nd, i0, i1, wk[16], wk[17])
                if g < 0.0:
                    if not have:  # the mesh's Hermite data: its local view of y, f0, y1, f1
                        wk[0], wk[1], wk[2], wk[3] = _local(mi, mf, m, W, oy, 1.0)
                        wk[4], wk[5], wk[6], wk[7] = _local(mi, mf, m, W, of0, 0.0)
                        wk[8], wk[9], wk[10], wk[11] = ta, tb, tc, td
                        wk[12], wk[13], wk[14], wk[15] = _local(mi, mf, m, W, of1, 0.0)
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
            th, om, x, v = _local(mi, mf, best_m, W, oy, 1.0)
            kv = ev = es = bv = 0.0
            if md[j] == 0 and tab[11] == 0:   # the sub-mode decision of a contact onset reads the tables
                kv, ev, es, bv = _held_tables(tab, md, j, th, wk[WK_ND], md[4 * p], md[4 * p + 1], wk[16], wk[17],
                                              seg)
            _switch_pair(md, p, j, (best_gi - 2) - 3 * j, tab[11], kv, ev, es, bv, x, v, om, tab[10])
        if not rem > 0.0:
            break
    return nev


@njit(cache=True, error_model="numpy")
def _write_row(gb, W, row, out_dof, out_mesh, out_pair, pair_off, out_spring):
    """Output row ``row`` from the state: every DOF's absolute coordinate and rate (g psi + q), every
    mesh's x, v, force, stiffness in contact and pair forces (the pair model's output rule with the
    step's torque row), every spring's force."""
    mi, mf, bf, si, sf, fi, ff, n, nm, ns, nf, lb, n2 = gb
    for i in range(n):
        gi = bf[n + i]
        out_dof[row, 2 * i] = gi * W[0] + _u(W, 0, i)
        out_dof[row, 2 * i + 1] = gi * W[1] + _u(W, 1, i)
    for m in range(nm):
        tab = _mtab(mi, mf, m)
        th, om, x, v = _local(mi, mf, m, W, 0, 1.0)
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
        v = 0.0
        vd = 0.0
        for j in range(si[s * SI]):
            d = si[s * SI + 1 + j]
            v += sf[s * SF + j] * _u(W, 0, d)
            vd += sf[s * SF + j] * _u(W, 1, d)
        out_spring[row, s] = sf[s * SF + SP] * v + sf[s * SF + SP + 1] * vd


@njit(cache=True, error_model="numpy")
def run(icode, y, t_in, t_out, it_rows, wt_rows, step0, n_steps, H, n_sub, h, mi, mf, bf, si, sf, fi, ff, n, lb,
        out_dof, out_mesh, out_pair, pair_off, out_spring, out_events, drv_dof, drv_w):
    """Communication steps step0 .. step0 + n_steps - 1 from the state ``y`` (2n, updated in place),
    as gearfmu.gearbox.kernels.run: row step0 + 1 + s after step s; step s holds t_in[s], t_out[s] and
    per mesh the torque row it_rows[s, m] with weight wt_rows[s, m]; n_sub substeps of h.  ``icode``:
    0 'rk4', 1 'rk4_kink', 2 'rk4_node', 3 'rk4_seg' (the meshes' flags those of rk4_seg).  ``drv_dof``: the
    drive DOFs of the driven members (infinite inertia, g = 0), whose speed q' is set to drv_w[s, j] at
    the start of step s (docs/planetary.md "Driven members").  Returns the number of completed steps."""
    nm = mi.shape[0] // MI
    ns = si.shape[0] // SI
    nf = fi.shape[0] // FI
    n2 = 2 * n
    W = np.zeros(W_VECTORS * n2 + n)
    for i in range(n2):
        W[i] = y[i]
    gb = (_i64p(_addr(mi)), _f64p(_addr(mf)), _f64p(_addr(bf)), _i64p(_addr(si)), _f64p(_addr(sf)),
          _i64p(_addr(fi)), _f64p(_addr(ff)), n, nm, ns, nf, lb, n2)
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
        for j in range(drv_dof.shape[0]):
            W[2 * drv_dof[j] + 1] = drv_w[r, j]
        if r == 0:
            _write_row(gb, wp, 0, out_dof, out_mesh, out_pair, pair_off, out_spring)
        nev = 0
        if icode >= 1:
            node = icode >= 2
            lk = LOOKUP_SEG if icode == ICODE_SEG else LOOKUP_HELD
            for m in range(nm):
                _mesh_start(gb, wp, m, node)
            for _ in range(n_sub):
                nev += _substep(gb, wp, h, node, lk, t_in[r], t_out[r])
        else:
            for _ in range(n_sub):
                _rhs(gb, wp, 0, W_F0 * n2, t_in[r], t_out[r], LOOKUP_PLAIN)
                _rk4(gb, wp, 0, W_F0 * n2, h, W_YT * n2, t_in[r], t_out[r], LOOKUP_PLAIN)
                for i in range(n2):
                    W[i] = W[W_YT * n2 + i]
        out_events[r + 1] = nev
        _write_row(gb, wp, r + 1, out_dof, out_mesh, out_pair, pair_off, out_spring)
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
