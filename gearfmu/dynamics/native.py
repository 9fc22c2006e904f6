"""Native (numba) solver of the multi-pair gear dynamic model (SI units).

Implements docs/model.md to the letter -- the contract shared with the FMU's C
kernel (gearfmu/fmu/kernel/gearkernel.c): the same table lookup, per-pair force
law, RK4 arithmetic order and initial-state bisection, so that the two
independent implementations agree to round-off on the same tables, inputs and
steps.  No fastmath (it would reorder the arithmetic).

Model: seed 003 eq (1)-(6) (two-inertia torsional pair, P tooth-pair slots,
per-pair stiffness k_j, damping c, meshing error e_j and half backlash b_j),
indexed by the pinion angle; state y = [theta1 (rad), omega1 (rad/s),
x (m), v (m/s)], x = theta1*Rb1 - theta2*Rb2 the dynamic transmission error.

Public API
----------
* :func:`simulate` -- the FMU model, outputs named as the FMU outputs.
* :func:`simulate_sdof` -- time-indexed SDOF form (seed 003 eq 3-6) at a
  prescribed constant pinion speed.
* :func:`dimensionless` -- seed 003 eq 7-9 rescaling of a result.
* :func:`choose_max_step_s` -- default internal step.
* :class:`SimResult` -- result arrays, ``to_csv``, ``wall_s``.

Details and choices: docs/native.md.
"""
from __future__ import annotations

import math
import time as _time
from dataclasses import dataclass, field
from typing import Callable, Optional, Union

import numpy as np
from numba import njit, types
from numba.extending import intrinsic

from ..common.vocabulary import DAMPING_MODELS, DEFAULT_INTEGRATOR, INTEGRATORS, current_spelling
from ..tables.mesh_tables import MeshTables, TemperatureRangeError
from ..common.checks import finite_number

__all__ = [
    "NativeInputError",
    "SimResult",
    "DimensionlessResult",
    "DAMPING_MODELS",
    "INTEGRATORS",
    "DEFAULT_INTEGRATOR",
    "simulate",
    "simulate_sdof",
    "dimensionless",
    "choose_max_step_s",
    "equilibrium_dte_m",
    "substeps",
]


InputLike = Union[float, np.ndarray, Callable[[float], float]]


class NativeInputError(ValueError):
    """Bad argument to the native solver; the message names the argument."""


# ---------------------------------------------------------------- kernels
#: no carried cell (_phi_cell): more than one cell away from every global cell index
_CELL_NONE = -(1 << 62)
#: 2^52: below it the global cell index and s - nd are exact in doubles
_CELL_LIMIT = 4503599627370496.0


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


@njit(cache=True, error_model="numpy")
def _rows(k, e, it):
    """Views of the torque rows it and it+1 (it again when NT == 1)."""
    if k.shape[0] > 1:
        return k[it], e[it], k[it + 1], e[it + 1], True
    return k[it], e[it], k[it], e[it], False


@njit(cache=True, error_model="numpy", inline="always")
def _pair_values(k0, e0, k1, e1, rows2, wt, b, j, i0, i1, w, inv_dphi):
    """k_j (N/m), e_j (m), de_j/dphi (m/rad), b_j (m) of slot j.

    k0, e0 are the (P, n_phi) rows of torque index it, k1, e1 those of it+1
    (used only when rows2, i.e. NT > 1): phi interpolation per torque row,
    then linear interpolation between the two rows with weight wt."""
    ka = k0[j, i0]
    kb = k0[j, i1]
    kv = ka + w * (kb - ka)
    ea = e0[j, i0]
    eb = e0[j, i1]
    ev = ea + w * (eb - ea)
    es = (eb - ea) * inv_dphi
    if rows2:
        ka2 = k1[j, i0]
        kb2 = k1[j, i1]
        kv2 = ka2 + w * (kb2 - ka2)
        ea2 = e1[j, i0]
        eb2 = e1[j, i1]
        ev2 = ea2 + w * (eb2 - ea2)
        es2 = (eb2 - ea2) * inv_dphi
        kv = kv + wt * (kv2 - kv)
        ev = ev + wt * (ev2 - ev)
        es = es + wt * (es2 - es)
    ba = b[j, i0]
    bb = b[j, i1]
    bv = ba + w * (bb - ba)
    return kv, ev, es, bv


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
def _mesh_force(tab, theta1, omega1, x, v, nd, i0):
    """Total dynamic mesh force F = sum_j F_j (N), summed j = 0..P-1, and the cell
    (nd, i0) of theta1 (carried in from the previous evaluation, see _phi_cell).
    ``tab``: the table pointers and scalars of :func:`_kvals` (no array argument
    in the step loop, see the rk4_kink section)."""
    n_phi = tab[7]
    nd, i0, i1, w = _phi_cell(theta1, tab[12], n_phi, nd, i0)
    f = 0.0
    for j in range(tab[8]):
        kv, ev, es, bv = _kvals(tab, j, i0, i1, w)
        fj, st = _pair_force(kv, ev, es, bv, x, v, omega1, tab[10], tab[11])
        f += fj
    return f, nd, i0


@njit(cache=True, error_model="numpy")
def _outputs_row(theta1, omega1, x, v, k0, e0, k1, e1, rows2, wt, b, inv_dphi, c, model,
                 pair_out, row):
    """Write pair forces of one output row; return (mesh_force, mesh_stiffness)."""
    n_phi = k0.shape[1]
    nd, i0, i1, w = _phi_cell(theta1, inv_dphi, n_phi, _CELL_NONE, 0)
    ftot = 0.0
    ks = 0.0
    for j in range(k0.shape[0]):
        kv, ev, es, bv = _pair_values(k0, e0, k1, e1, rows2, wt, b, j, i0, i1, w, inv_dphi)
        fj, st = _pair_force(kv, ev, es, bv, x, v, omega1, c, model)
        pair_out[row, j] = fj
        ftot += fj
        if st != 0:
            ks += kv
    return ftot, ks


@njit(cache=True, error_model="numpy")
def _equilibrium(theta1, t1, rb1, k, e, b, torque, inv_dphi):
    """docs/model.md 'Initial state': x (m) of the quasi-static equilibrium at theta1
    under F_m = T1/Rb1, by exactly 200 bisections.  Returns nan if no slot has k > 0."""
    it, wt = _torque_index(t1, torque)
    k0, e0, k1, e1, rows2 = _rows(k, e, it)
    n_phi = k.shape[2]
    p = k.shape[1]
    nd, i0, i1, w = _phi_cell(theta1, inv_dphi, n_phi, _CELL_NONE, 0)
    fm = t1 / rb1
    kk = np.empty(p)
    ee = np.empty(p)
    bb = np.empty(p)
    s = 0.0
    lo_e = np.inf
    hi_e = -np.inf
    for j in range(p):
        kv, ev, es, bv = _pair_values(k0, e0, k1, e1, rows2, wt, b, j, i0, i1, w, inv_dphi)
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


@njit(cache=True, error_model="numpy", inline="always")
def _rk4_step(th, om, x, v, h, t1, t2, rb1, rb2, i1, i2, tab, nd, i0):
    """One classical RK4 step of the two-inertia model (docs/model.md).

    Stage s evaluates f at y + a_s*h*k_{s-1} (a = 0, 1/2, 1/2, 1; h/2 computed
    as h/2.0); the increments are accumulated left to right,
    acc = ((k1 + 2*k2) + 2*k3) + k4, and y_new = y + (h/6.0)*acc.  The table
    cell (nd, i0) is carried from stage to stage and returned."""
    h2 = h / 2.0
    ka = 0.0
    kb = 0.0
    kc = 0.0
    kd = 0.0
    sa = 0.0
    sb = 0.0
    sc = 0.0
    sd = 0.0
    for stage in range(4):
        if stage == 0:
            ya = th
            yb = om
            yc = x
            yd = v
        elif stage == 3:
            ya = th + h * ka
            yb = om + h * kb
            yc = x + h * kc
            yd = v + h * kd
        else:
            ya = th + h2 * ka
            yb = om + h2 * kb
            yc = x + h2 * kc
            yd = v + h2 * kd
        f, nd, i0 = _mesh_force(tab, ya, yb, yc, yd, nd, i0)
        ka = yb
        kb = (t1 - rb1 * f) / i1
        kc = yd
        kd = rb1 * (t1 - rb1 * f) / i1 - rb2 * (rb2 * f - t2) / i2
        if stage == 0:
            sa = ka
            sb = kb
            sc = kc
            sd = kd
        elif stage == 3:
            sa = sa + ka
            sb = sb + kb
            sc = sc + kc
            sd = sd + kd
        else:
            sa = sa + 2.0 * ka
            sb = sb + 2.0 * kb
            sc = sc + 2.0 * kc
            sd = sd + 2.0 * kd
    h6 = h / 6.0
    return th + h6 * sa, om + h6 * sb, x + h6 * sc, v + h6 * sd, nd, i0


@njit(cache=True, error_model="numpy")
def _run_2dof(th, om, x, v, t1s, t2s, n_sub, h, rb1, rb2, i1, i2, k, e, b, torque,
              inv_dphi, c, model, out_state, out_pair, out_force, out_stiff):
    """Loop over communication steps (rows 1..n of the outputs; row 0 by caller).
    k, e (NT, P, N) and b (P, N) must be C-contiguous (the step reads their data
    pointers)."""
    n_steps = out_state.shape[0] - 1
    kp, ep, bp, p, n_phi = _table_pointers(k, e, b)
    nd = _CELL_NONE
    i0 = 0
    for s in range(n_steps):
        t1 = t1s[s]
        t2 = t2s[s]
        it, wt = _torque_index(t1, torque)
        k0, e0, k1, e1, rows2 = _rows(k, e, it)
        tab = _tab(kp, ep, bp, it, rows2, wt, n_phi, p, np.nan, c, model, inv_dphi)  # dphi: rk4_kink only
        for _ in range(n_sub):
            th, om, x, v, nd, i0 = _rk4_step(th, om, x, v, h, t1, t2, rb1, rb2, i1, i2, tab, nd, i0)
        out_state[s + 1, 0] = th
        out_state[s + 1, 1] = om
        out_state[s + 1, 2] = x
        out_state[s + 1, 3] = v
        ftot, ks = _outputs_row(th, om, x, v, k0, e0, k1, e1, rows2, wt, b, inv_dphi, c, model,
                                out_pair, s + 1)
        out_force[s + 1] = ftot
        out_stiff[s + 1] = ks
        if not (math.isfinite(th) and math.isfinite(om) and math.isfinite(x) and math.isfinite(v)):
            return s + 1
    return n_steps


@njit(cache=True, error_model="numpy")
def _rk4_step_sdof(t, x, v, h, th0, om, fm, me, tab, nd, i0):
    """One RK4 step of the time-indexed SDOF (theta1 = th0 + om*t prescribed),
    same stage and accumulation order as :func:`_rk4_step`; stage times t,
    t + h/2, t + h/2, t + h; the table cell (nd, i0) carried as there."""
    h2 = h / 2.0
    kc = 0.0
    kd = 0.0
    sc = 0.0
    sd = 0.0
    for stage in range(4):
        if stage == 0:
            ts = t
            yc = x
            yd = v
        elif stage == 3:
            ts = t + h
            yc = x + h * kc
            yd = v + h * kd
        else:
            ts = t + h2
            yc = x + h2 * kc
            yd = v + h2 * kd
        f, nd, i0 = _mesh_force(tab, th0 + om * ts, om, yc, yd, nd, i0)
        kc = yd
        kd = (fm - f) / me
        if stage == 0:
            sc = kc
            sd = kd
        elif stage == 3:
            sc = sc + kc
            sd = sd + kd
        else:
            sc = sc + 2.0 * kc
            sd = sd + 2.0 * kd
    h6 = h / 6.0
    return x + h6 * sc, v + h6 * sd, nd, i0


@njit(cache=True, error_model="numpy")
def _run_sdof(th0, om, x, v, t1s, H, n_sub, h, rb1, me, k, e, b, torque,
              inv_dphi, c, model, out_state, out_pair, out_force, out_stiff):
    n_steps = out_state.shape[0] - 1
    kp, ep, bp, p, n_phi = _table_pointers(k, e, b)
    nd = _CELL_NONE
    i0 = 0
    for s in range(n_steps):
        t1 = t1s[s]
        fm = t1 / rb1
        it, wt = _torque_index(t1, torque)
        k0, e0, k1, e1, rows2 = _rows(k, e, it)
        tab = _tab(kp, ep, bp, it, rows2, wt, n_phi, p, np.nan, c, model, inv_dphi)  # dphi: rk4_kink only
        t0 = s * H
        for i in range(n_sub):
            x, v, nd, i0 = _rk4_step_sdof(t0 + i * h, x, v, h, th0, om, fm, me, tab, nd, i0)
        th = th0 + om * ((s + 1) * H)
        out_state[s + 1, 0] = th
        out_state[s + 1, 1] = om
        out_state[s + 1, 2] = x
        out_state[s + 1, 3] = v
        ftot, ks = _outputs_row(th, om, x, v, k0, e0, k1, e1, rows2, wt, b, inv_dphi, c, model,
                                out_pair, s + 1)
        out_force[s + 1] = ftot
        out_stiff[s + 1] = ks
        if not (math.isfinite(x) and math.isfinite(v)):
            return s + 1
    return n_steps


# ------------------------------------------------------ rk4_kink (docs/model.md)
#: events (mode switches) located per substep before the rest of the substep is
#: taken without detection (guards a grazing ping-pong); docs/model.md "rk4_kink"
KINK_MAX_EVENTS = 1000
#: largest slot count the rk4_kink integrator accepts (fixed arrays in the C kernel)
KINK_MAX_SLOTS = 32
_KINK_TOL_S = 1e-12     # root bracket width in the unit substep fraction s
_KINK_MAX_IT = 60       # Illinois iterations per root

# Speed (docs/native.md "rk4_kink speed"): the rk4_kink helpers below never take
# a numpy array.  Every numba call with an array argument increfs/decrefs the
# array's memory block (atomic operations the refcount pruner cannot remove
# across calls, loops and branches), and the locked right-hand side, the guards
# and the root finder call each other ~20 times per substep.  So _run_kink
# takes raw data pointers once (_ptr) and hands the helpers one struct-like
# tuple ``tab`` of pointers and scalars, the inputs as a tuple ``dyn``, the
# mode as an int64 pointer ``md`` (reg[j] = md[j], sub[j] = md[P + j],
# kpos[j] = md[2P + j]) and the Hermite data as a float64 pointer ``wk``
# (y0 = wk[0:4], f0 = wk[4:8], y1 = wk[8:12], f1 = wk[12:16]).  LLVM then
# inlines the whole substep; no allocation or slicing happens in the loop.
# The arithmetic is unchanged operation by operation (bitwise agreement with
# gearkernel.c).


@intrinsic
def _ptr(typingctx, arr):
    """Data pointer (CPointer) of a C-contiguous array, no reference counting.
    Valid while the array is alive; the caller (_run_kink) owns the arrays."""
    if not isinstance(arr, types.Array):
        return None
    sig = types.CPointer(arr.dtype)(arr)

    def codegen(context, builder, signature, args):
        ary = context.make_array(signature.args[0])(context, builder, value=args[0])
        return ary.data

    return sig, codegen


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
    1.0 when guard q does not exist for this mode (docs/model.md 'rk4_kink')."""
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
def _kvals(tab, j, i0, i1, w):
    """k_j, e_j, de_j/dphi, b_j of slot j at cell nodes (i0, i1) and weight w; the
    arithmetic of :func:`_pair_values` on the pointers of ``tab``."""
    kp, ep, bp, o0, o1, rows2, wt, n_phi, p, dphi, c, model, inv_dphi = tab
    r = j * n_phi
    ka = kp[o0 + r + i0]
    kb = kp[o0 + r + i1]
    kv = ka + w * (kb - ka)
    ea = ep[o0 + r + i0]
    eb = ep[o0 + r + i1]
    ev = ea + w * (eb - ea)
    es = (eb - ea) * inv_dphi
    if rows2:
        ka2 = kp[o1 + r + i0]
        kb2 = kp[o1 + r + i1]
        kv2 = ka2 + w * (kb2 - ka2)
        ea2 = ep[o1 + r + i0]
        eb2 = ep[o1 + r + i1]
        ev2 = ea2 + w * (eb2 - ea2)
        es2 = (eb2 - ea2) * inv_dphi
        kv = kv + wt * (kv2 - kv)
        ev = ev + wt * (ev2 - ev)
        es = es + wt * (es2 - es)
    ba = bp[r + i0]
    bb = bp[r + i1]
    bv = ba + w * (bb - ba)
    return kv, ev, es, bv


@njit(cache=True, error_model="numpy", inline="always")
def _table_pointers(k, e, b):
    """(data pointers of k, e (NT, P, N) and b (P, N), P, N); the arrays must be
    C-contiguous and outlive the pointers' use."""
    return _ptr(k), _ptr(e), _ptr(b), k.shape[1], k.shape[2]


@njit(cache=True, error_model="numpy", inline="always")
def _tab(kp, ep, bp, it, rows2, wt, n_phi, p, dphi, c, model, inv_dphi):
    """The ``tab`` tuple of :func:`_kvals` for torque row it (and it+1 if rows2)."""
    o0 = it * p * n_phi
    o1 = (it + 1) * p * n_phi if rows2 else o0
    return (kp, ep, bp, o0, o1, rows2, wt, n_phi, p, dphi, c, model, inv_dphi)


@njit(cache=True, error_model="numpy", inline="always")
def _deriv_locked(tab, dyn, md, th, om, x, v, nd, i0, i1):
    """Right-hand side with the mode (cell nd, per-pair reg/sub/kpos) held.
    Two-inertia form (sdof = False) or time-indexed SDOF (theta1' = omega1,
    omega1' = 0, m_e v' = F_m - F)."""
    dphi = tab[9]
    c = tab[10]
    model = tab[11]
    p = tab[8]
    sdof, t1, t2, rb1, rb2, in1, in2, fm, me = dyn
    w = (th - nd * dphi) * tab[12]
    f = 0.0
    for j in range(p):
        kv, ev, es, bv = _kvals(tab, j, i0, i1, w)
        f += _pair_force_locked(kv, ev, es, bv, x, v, om, c, model, md[j], md[p + j], md[2 * p + j])
    if sdof:
        return om, 0.0, v, (fm - f) / me
    return om, (t1 - rb1 * f) / in1, v, rb1 * (t1 - rb1 * f) / in1 - rb2 * (rb2 * f - t2) / in2


@njit(cache=True, error_model="numpy")
def _rk4_locked(tab, dyn, md, th, om, x, v, fa, fb, fc, fd, h, nd, i0, i1):
    """One classical RK4 step of length h, first stage (fa..fd) given, mode held;
    the arithmetic of :func:`_rk4_step` (stages unrolled)."""
    h2 = h / 2.0
    ka, kb, kc, kd = _deriv_locked(tab, dyn, md, th + h2 * fa, om + h2 * fb, x + h2 * fc, v + h2 * fd,
                                   nd, i0, i1)
    sa = fa + 2.0 * ka
    sb = fb + 2.0 * kb
    sc = fc + 2.0 * kc
    sd = fd + 2.0 * kd
    ka, kb, kc, kd = _deriv_locked(tab, dyn, md, th + h2 * ka, om + h2 * kb, x + h2 * kc, v + h2 * kd,
                                   nd, i0, i1)
    sa = sa + 2.0 * ka
    sb = sb + 2.0 * kb
    sc = sc + 2.0 * kc
    sd = sd + 2.0 * kd
    ka, kb, kc, kd = _deriv_locked(tab, dyn, md, th + h * ka, om + h * kb, x + h * kc, v + h * kd,
                                   nd, i0, i1)
    sa = sa + ka
    sb = sb + kb
    sc = sc + kc
    sd = sd + kd
    h6 = h / 6.0
    return th + h6 * sa, om + h6 * sb, x + h6 * sc, v + h6 * sd


@njit(cache=True, error_model="numpy")
def _guard_at(tab, md, gi, th, om, x, v, nd, i0, i1):
    """Guard gi at a state: 0 cell start theta1 - nd*dphi, 1 cell end (nd+1)*dphi - theta1,
    2 + 3*j + q guard q of pair j."""
    dphi = tab[9]
    if gi == 0:
        return th - nd * dphi
    if gi == 1:
        return (nd + 1.0) * dphi - th
    p = tab[8]
    j = (gi - 2) // 3
    q = (gi - 2) - 3 * j
    w = (th - nd * dphi) * tab[12]
    kv, ev, es, bv = _kvals(tab, j, i0, i1, w)
    return _pair_guard(q, kv, ev, es, bv, x, v, om, tab[10], tab[11], md[j], md[p + j])


@njit(cache=True, error_model="numpy")
def _hermite_guard(tab, md, gi, s, wk, tau, nd, i0, i1):
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
    return _guard_at(tab, md, gi, ya, yb, yc, yd, nd, i0, i1)


@njit(cache=True, error_model="numpy")
def _guard_root(tab, md, gi, g_end, wk, tau, nd, i0, i1):
    """Fraction s in [0, 1] where guard gi crosses zero on the Hermite interpolant
    (Illinois regula falsi; returns the end of the bracket where the guard < 0)."""
    ga = _guard_at(tab, md, gi, wk[0], wk[1], wk[2], wk[3], nd, i0, i1)
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
        gs = _hermite_guard(tab, md, gi, s, wk, tau, nd, i0, i1)
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
        km, em, esm, bm = _kvals(tab, j, i0, i1, 0.5)
        md[2 * p + j] = 1 if km > 0.0 else 0
        kv, ev, es, bv = _kvals(tab, j, i0, i1, w)
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
def _kink_substep(tab, dyn, md, wk, th, om, x, v, h, nd):
    """Advance one substep of length h with the rk4_kink integrator (docs/model.md).
    Returns (theta1, omega1, x, v, nd, events); the mode md is updated in place."""
    n_phi = tab[7]
    p = tab[8]
    dphi = tab[9]
    c = tab[10]
    model = tab[11]
    n_guard = 2 + 3 * p
    i0, i1 = _cell_nodes(nd, n_phi)
    rem = h
    nev = 0
    while True:
        fa, fb, fc, fd = _deriv_locked(tab, dyn, md, th, om, x, v, nd, i0, i1)
        ta, tb, tc, td = _rk4_locked(tab, dyn, md, th, om, x, v, fa, fb, fc, fd, rem, nd, i0, i1)
        if nev >= KINK_MAX_EVENTS:
            th, om, x, v = ta, tb, tc, td
            nd = np.floor(th * tab[12])
            i0, i1 = _cell_nodes(nd, n_phi)
            _mode_sync(tab, md, th, om, x, v, nd, i0, i1, True)
            break
        # scan the guards at the trial end: cheap test first (one lookup per pair)
        any_neg = (ta - nd * dphi < 0.0) or ((nd + 1.0) * dphi - ta < 0.0)
        if not any_neg:
            w = (ta - nd * dphi) * tab[12]
            for j in range(p):
                kv, ev, es, bv = _kvals(tab, j, i0, i1, w)
                rj = md[j]
                sj = md[p + j]
                if (_pair_guard(0, kv, ev, es, bv, tc, td, tb, c, model, rj, sj) < 0.0
                        or _pair_guard(1, kv, ev, es, bv, tc, td, tb, c, model, rj, sj) < 0.0
                        or _pair_guard(2, kv, ev, es, bv, tc, td, tb, c, model, rj, sj) < 0.0):
                    any_neg = True
                    break
        if not any_neg:
            th, om, x, v = ta, tb, tc, td
            break
        best = 2.0
        best_gi = -1
        have_f1 = False
        for gi in range(n_guard):
            g = _guard_at(tab, md, gi, ta, tb, tc, td, nd, i0, i1)
            if g < 0.0:
                if not have_f1:
                    wk[0] = th
                    wk[1] = om
                    wk[2] = x
                    wk[3] = v
                    wk[4] = fa
                    wk[5] = fb
                    wk[6] = fc
                    wk[7] = fd
                    wk[8] = ta
                    wk[9] = tb
                    wk[10] = tc
                    wk[11] = td
                    ga_, gb_, gc_, gd_ = _deriv_locked(tab, dyn, md, ta, tb, tc, td, nd, i0, i1)
                    wk[12] = ga_
                    wk[13] = gb_
                    wk[14] = gc_
                    wk[15] = gd_
                    have_f1 = True
                s = _guard_root(tab, md, gi, g, wk, rem, nd, i0, i1)
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
            th, om, x, v = _rk4_locked(tab, dyn, md, th, om, x, v, fa, fb, fc, fd, tau, nd, i0, i1)
            rem = rem - tau
        nev += 1
        if best_gi < 2:
            nd = nd - 1.0 if best_gi == 0 else nd + 1.0
            i0, i1 = _cell_nodes(nd, n_phi)
            _mode_sync(tab, md, th, om, x, v, nd, i0, i1, False)
        else:
            j = (best_gi - 2) // 3
            q = (best_gi - 2) - 3 * j
            if md[j] == 0:
                md[j] = 1 if q == 0 else -1
                if model == 0:
                    w = (th - nd * dphi) * tab[12]
                    kv, ev, es, bv = _kvals(tab, j, i0, i1, w)
                    md[p + j] = _decide_sub(md[j], kv, ev, es, bv, x, v, om, c)
            elif q == 0:
                md[j] = 0
                md[p + j] = 0
            elif md[p + j] == 1:
                md[p + j] = 0 if q == 1 else 2
            else:
                md[p + j] = 1
        if not rem > 0.0:
            break
    return th, om, x, v, nd, nev


@njit(cache=True, error_model="numpy")
def _run_kink(th, om, x, v, t1s, t2s, n_sub, h, rb1, rb2, in1, in2, me, sdof, k, e, b, torque,
              inv_dphi, dphi, c, model, out_state, out_pair, out_force, out_stiff, out_events):
    """rk4_kink loop over communication steps (two-inertia or, with sdof, the
    time-indexed SDOF at constant omega1); the mode is set from the state at the
    start of every communication step.  k, e (NT, P, N) and b (P, N) must be
    C-contiguous (the helpers index their data pointers)."""
    n_steps = out_state.shape[0] - 1
    p = k.shape[1]
    n_phi = k.shape[2]
    mode = np.zeros(3 * p, dtype=np.int64)
    work = np.zeros(16)
    md = _ptr(mode)
    wk = _ptr(work)
    kp = _ptr(k)
    ep = _ptr(e)
    bp = _ptr(b)
    for s in range(n_steps):
        t1 = t1s[s]
        t2 = t2s[s]
        fm = t1 / rb1
        it, wt = _torque_index(t1, torque)
        k0, e0, k1, e1, rows2 = _rows(k, e, it)
        o0 = it * p * n_phi
        o1 = (it + 1) * p * n_phi if rows2 else o0
        tab = (kp, ep, bp, o0, o1, rows2, wt, n_phi, p, dphi, c, model, inv_dphi)
        dyn = (sdof, t1, t2, rb1, rb2, in1, in2, fm, me)
        nd = np.floor(th * inv_dphi)
        i0, i1 = _cell_nodes(nd, n_phi)
        _mode_sync(tab, md, th, om, x, v, nd, i0, i1, True)
        nev = 0
        for _ in range(n_sub):
            th, om, x, v, nd, ne = _kink_substep(tab, dyn, md, wk, th, om, x, v, h, nd)
            nev += ne
        out_events[s + 1] = nev
        out_state[s + 1, 0] = th
        out_state[s + 1, 1] = om
        out_state[s + 1, 2] = x
        out_state[s + 1, 3] = v
        ftot, ks = _outputs_row(th, om, x, v, k0, e0, k1, e1, rows2, wt, b, inv_dphi, c, model,
                                out_pair, s + 1)
        out_force[s + 1] = ftot
        out_stiff[s + 1] = ks
        if not (math.isfinite(th) and math.isfinite(om) and math.isfinite(x) and math.isfinite(v)):
            return s + 1
    return n_steps


@njit(cache=True, error_model="numpy")
def _row0(th, om, x, v, t1, k, e, b, torque, inv_dphi, c, model,
          out_state, out_pair, out_force, out_stiff):
    it, wt = _torque_index(t1, torque)
    k0, e0, k1, e1, rows2 = _rows(k, e, it)
    out_state[0, 0] = th
    out_state[0, 1] = om
    out_state[0, 2] = x
    out_state[0, 3] = v
    ftot, ks = _outputs_row(th, om, x, v, k0, e0, k1, e1, rows2, wt, b, inv_dphi, c, model, out_pair, 0)
    out_force[0] = ftot
    out_stiff[0] = ks


# ------------------------------------------------------------ python layer
@dataclass
class SimResult:
    """Result of :func:`simulate` / :func:`simulate_sdof` (SI units).

    Row 0 is the initial state (outputs at t = 0 with the initial inputs), then
    one row per communication step.  Arrays carry the FMU output names
    (docs/model.md "Outputs"): pinion_speed, gear_speed (rad/s), pinion_angle,
    gear_angle (rad), dte (m), mesh_force (N), pair_force (n_out, P) in N,
    load_sharing (n_out, P) dimensionless, mesh_stiffness (N/m).  Also the
    inputs used per row (pinion_torque, gear_torque in N*m), the relative
    velocity ``dte_rate`` (m/s), the internal step ``step_s`` and substeps per
    communication step, and ``wall_s`` (wall time of the compiled loop, s).
    """

    time_s: np.ndarray
    pinion_speed: np.ndarray
    gear_speed: np.ndarray
    pinion_angle: np.ndarray
    gear_angle: np.ndarray
    dte: np.ndarray
    dte_rate: np.ndarray
    mesh_force: np.ndarray
    pair_force: np.ndarray
    load_sharing: np.ndarray
    mesh_stiffness: np.ndarray
    pinion_torque: np.ndarray
    gear_torque: np.ndarray
    step_s: float
    substeps: int
    damping_Ns_per_m: float
    damping_model: str
    wall_s: float
    info: dict = field(default_factory=dict)

    OUTPUT_UNITS = {
        "pinion_speed": "rad/s", "gear_speed": "rad/s", "pinion_angle": "rad",
        "gear_angle": "rad", "dte": "m", "mesh_force": "N", "mesh_stiffness": "N/m",
    }

    @property
    def slots(self) -> int:
        return int(self.pair_force.shape[1])

    def columns(self) -> dict:
        """Ordered {name: (unit, 1-D array)} with FMU names; pair_force[i], i = 1..P."""
        cols = {"time": ("s", self.time_s)}
        for n in ("pinion_speed", "gear_speed", "pinion_angle", "gear_angle", "dte", "mesh_force"):
            cols[n] = (self.OUTPUT_UNITS[n], getattr(self, n))
        for i in range(self.slots):
            cols[f"pair_force[{i + 1}]"] = ("N", self.pair_force[:, i])
        for i in range(self.slots):
            cols[f"load_sharing[{i + 1}]"] = ("1", self.load_sharing[:, i])
        cols["mesh_stiffness"] = ("N/m", self.mesh_stiffness)
        cols["pinion_torque"] = ("N*m", self.pinion_torque)
        cols["gear_torque"] = ("N*m", self.gear_torque)
        return cols

    def to_csv(self, path) -> None:
        """Write a CSV: a '# units:' comment line, a row of FMU variable names, data
        with 17 significant digits (round-trips float64)."""
        cols = self.columns()
        data = np.column_stack([a for _, a in cols.values()])
        with open(path, "w", encoding="utf-8") as fh:
            fh.write("# units: " + ",".join(u for u, _ in cols.values()) + "\n")
            fh.write(",".join(cols) + "\n")
            np.savetxt(fh, data, delimiter=",", fmt="%.17g")


@dataclass
class DimensionlessResult:
    """Seed 003 eq 7-9 quantities: q = x/l, tau = omega_n t, Omega_h = omega_mesh/omega_n,
    zeta, and the dimensionless load F_m/(k_m l) (all dimensionless)."""

    tau: np.ndarray
    q: np.ndarray
    q_rate: np.ndarray
    Omega_h: float
    omega_n_rad_s: float
    zeta: float
    load: float
    length_scale_m: float


def _check_tables(tables) -> MeshTables:
    if not isinstance(tables, MeshTables):
        raise NativeInputError(f"tables: expected MeshTables, got {type(tables).__name__}")
    if tables.has_temperature_axis:
        raise NativeInputError("tables: have a temperature axis; pass bulk_temperature_C to simulate / "
                               "simulate_sdof, or select one with tables.at_temperature(T)")
    return tables.validate()


def _finite(name, value, *, positive=False, nonneg=False, error=None) -> float:
    """``value`` as a finite float (> 0 with ``positive``, >= 0 with ``nonneg``);
    otherwise ``error`` (default NativeInputError) naming ``name`` and the reason."""
    return finite_number(name, value, positive=positive, nonneg=nonneg,
                         error=NativeInputError if error is None else error)


def _n_steps(stop_time_s, comm_step_s) -> int:
    n = stop_time_s / comm_step_s
    nr = int(round(n))
    if nr < 1 or abs(n - nr) > 1e-6 * max(1.0, n):
        raise NativeInputError(
            f"stop_time_s: {stop_time_s!r} is not a whole number of communication steps "
            f"comm_step_s={comm_step_s!r} ({n:.9g})")
    return nr


def _input_series(name, value: InputLike, n_steps: int, comm_step_s: float) -> np.ndarray:
    """Input sampled at t_k = k*comm_step_s, k = 0..n_steps (the value held over step k)."""
    if callable(value):
        arr = np.array([float(value(k * comm_step_s)) for k in range(n_steps + 1)])
    else:
        a = np.asarray(value, dtype=float)
        if a.ndim == 0:
            arr = np.full(n_steps + 1, float(a))
        elif a.ndim == 1 and a.shape[0] in (n_steps, n_steps + 1):
            arr = np.empty(n_steps + 1)
            arr[: a.shape[0]] = a
            if a.shape[0] == n_steps:
                arr[n_steps] = a[-1]
        else:
            raise NativeInputError(
                f"{name}: expected a number, a callable of time, or an array of {n_steps} "
                f"or {n_steps + 1} values (one per communication step), got shape {a.shape}")
    if not np.all(np.isfinite(arr)):
        raise NativeInputError(f"{name}: contains NaN or infinite values")
    return np.ascontiguousarray(arr)


def substeps(comm_step_s: float, max_step_s: float) -> int:
    """n = max(1, ceil(H/h_max*(1 - 1e-12))) (docs/model.md 'Integration')."""
    return max(1, int(math.ceil(comm_step_s / max_step_s * (1.0 - 1e-12))))


def _arrays(tables: MeshTables):
    k = np.ascontiguousarray(tables.k_N_per_m, dtype=np.float64)
    e = np.ascontiguousarray(tables.e_m, dtype=np.float64)
    b = np.ascontiguousarray(tables.backlash_half_m, dtype=np.float64)
    tq = np.ascontiguousarray(tables.torque_Nm, dtype=np.float64)
    phi_period = float(tables.phi_period_rad)
    dphi = phi_period / tables.n_phi
    inv_dphi = tables.n_phi / phi_period  # docs/model.md 'Table lookup': N/Phi, one rounding
    return k, e, b, tq, inv_dphi, dphi


def _damping(tables: MeshTables, damping_ratio) -> float:
    """c = 2*zeta*sqrt(k_mean*m_e), m_e = I1*I2/(I1*Rb2^2 + I2*Rb1^2) (docs/model.md,
    seed 003 below eq 2), evaluated as I1*I2/(I1*Rb2*Rb2 + I2*Rb1*Rb1) left to right."""
    i1, i2 = float(tables.inertia_pinion_kgm2), float(tables.inertia_gear_kgm2)
    r1, r2 = float(tables.base_radius_pinion_m), float(tables.base_radius_gear_m)
    # left to right, I1*Rb2*Rb2 = (I1*Rb2)*Rb2: the order of the C kernel (bitwise agreement)
    me = i1 * i2 / (i1 * r2 * r2 + i2 * r1 * r1)
    return 2.0 * damping_ratio * math.sqrt(float(tables.k_mean_N_per_m) * me), me


def equilibrium_dte_m(tables: MeshTables, pinion_torque_Nm: float, pinion_angle_rad: float = 0.0) -> float:
    """Quasi-static equilibrium x (m) at the pinion angle under F_m = T1/Rb1, by the
    200-step bisection of docs/model.md 'Initial state'."""
    t = _check_tables(tables)
    k, e, b, tq, inv_dphi, dphi = _arrays(t)
    x = _equilibrium(_finite("pinion_angle_rad", pinion_angle_rad),
                     _finite("pinion_torque_Nm", pinion_torque_Nm),
                     float(t.base_radius_pinion_m), k, e, b, tq, inv_dphi)
    if not math.isfinite(x):
        raise NativeInputError(
            f"pinion_angle_rad: no tooth pair in the contact zone (all k = 0) at {pinion_angle_rad!r}; "
            "give dte_start_m")
    return float(x)


def choose_max_step_s(tables: MeshTables, max_speed_rad_s: float, points_per_period: int = 64) -> float:
    """Default maximum internal step (s).

    h_max = min(2*pi/omega_n, mesh period at max speed) / points_per_period with
    omega_n = sqrt(k_mean/m_e) (seed 003 eq 7) and the mesh period in time
    mesh_period_rad/|max_speed_rad_s|.  RK4's global error then scales as
    (omega_n h)^4: with 64 points per period the phase error of a free
    oscillation is about (2 pi/64)^5/120 = 8e-8 per step (docs/native.md).
    """
    t = _check_tables(tables)
    ppp = int(points_per_period)
    if ppp != points_per_period or ppp < 1:
        raise NativeInputError(f"points_per_period: must be a positive integer, got {points_per_period!r}")
    w = abs(_finite("max_speed_rad_s", max_speed_rad_s))
    wn = math.sqrt(t.k_mean_N_per_m / t.equivalent_mass_kg)
    period = 2.0 * math.pi / wn
    if w > 0.0:
        period = min(period, t.mesh_period_rad / w)
    return period / ppp


_COMPILED = False
_COMPILED_KINK = False


def _warmup(kink: bool = False) -> None:
    """Compile the kernels on a tiny problem so wall_s excludes JIT time
    (the rk4_kink kernels only when first used)."""
    global _COMPILED, _COMPILED_KINK
    if kink and not _COMPILED_KINK:
        k = np.ones((2, 1, 4)) * 1e8
        e = np.zeros((2, 1, 4))
        b = np.zeros((1, 4))
        tq = np.array([0.0, 1.0])
        for model in (0, 1):
            st = np.zeros((2, 4))
            pf = np.zeros((2, 1))
            fo = np.zeros(2)
            ks = np.zeros(2)
            ev = np.zeros(2, dtype=np.int64)
            for sdof in (False, True):
                _run_kink(0.0, 1.0, 0.0, 0.0, np.ones(2), np.ones(2), 1, 1e-6, 0.1, 0.1, 1.0, 1.0, 1.0, sdof,
                          k, e, b, tq, 4.0, 0.25, 1.0, model, st, pf, fo, ks, ev)
        _COMPILED_KINK = True
    if _COMPILED:
        return
    k = np.ones((2, 1, 4)) * 1e8
    e = np.zeros((2, 1, 4))
    b = np.zeros((1, 4))
    tq = np.array([0.0, 1.0])
    for model in (0, 1):
        st = np.zeros((2, 4))
        pf = np.zeros((2, 1))
        fo = np.zeros(2)
        ks = np.zeros(2)
        x0 = _equilibrium(0.0, 1.0, 0.1, k, e, b, tq, 4.0)
        _row0(0.0, 1.0, x0, 0.0, 1.0, k, e, b, tq, 4.0, 1.0, model, st, pf, fo, ks)
        _run_2dof(0.0, 1.0, x0, 0.0, np.ones(2), np.ones(2), 1, 1e-6, 0.1, 0.1, 1.0, 1.0,
                  k, e, b, tq, 4.0, 1.0, model, st, pf, fo, ks)
        _run_sdof(0.0, 1.0, x0, 0.0, np.ones(2), 1e-6, 1, 1e-6, 0.1, 1.0, k, e, b, tq,
                  4.0, 1.0, model, st, pf, fo, ks)
    _COMPILED = True


def _integrator_code(integrator, slots) -> int:
    if integrator not in INTEGRATORS:
        raise NativeInputError(f"integrator: {integrator!r} unknown; choose one of {sorted(INTEGRATORS)}")
    if integrator == "rk4_kink" and slots > KINK_MAX_SLOTS:
        raise NativeInputError(f"integrator: 'rk4_kink' handles at most {KINK_MAX_SLOTS} slots, "
                               f"the tables have {slots}")
    return INTEGRATORS[integrator]


def _common(tables, stop_time_s, comm_step_s, max_step_s, damping_ratio, damping_model):
    t = _check_tables(tables)
    stop = _finite("stop_time_s", stop_time_s, positive=True)
    H = _finite("comm_step_s", comm_step_s, positive=True)
    hmax = _finite("max_step_s", max_step_s, positive=True)
    zeta = _finite("damping_ratio", damping_ratio, nonneg=True)
    damping_model = current_spelling("damping_model", damping_model)
    if damping_model not in DAMPING_MODELS:
        raise NativeInputError(f"damping_model: {damping_model!r} unknown; choose one of {sorted(DAMPING_MODELS)}")
    n_steps = _n_steps(stop, H)
    n_sub = substeps(H, hmax)
    h = H / n_sub
    c, me = _damping(t, zeta)
    return t, stop, H, n_steps, n_sub, h, c, me, DAMPING_MODELS[damping_model]


def _initial_x(t, k, e, b, tq, inv_dphi, theta1, t1, dte_start_m):
    if dte_start_m is not None:
        return _finite("dte_start_m", dte_start_m)
    x0 = _equilibrium(theta1, t1, float(t.base_radius_pinion_m), k, e, b, tq, inv_dphi)
    if not math.isfinite(x0):
        raise NativeInputError(
            f"pinion_angle_start_rad: no tooth pair in the contact zone (all k = 0) at {theta1!r}; "
            "give dte_start_m")
    return x0


def _finish(t, time_s, state, pair, force, stiff, t1s, t2s, h, n_sub, c, damping_model, wall, done, info):
    rb1, rb2 = float(t.base_radius_pinion_m), float(t.base_radius_gear_m)
    th, om, x, v = state[:, 0], state[:, 1], state[:, 2], state[:, 3]
    with np.errstate(invalid="ignore", divide="ignore"):
        ls = np.where(force[:, None] != 0.0, pair / np.where(force[:, None] != 0.0, force[:, None], 1.0), 0.0)
    info = dict(info, completed_steps=int(done))
    if done < state.shape[0] - 1:
        info["diverged_at_step"] = int(done)
    return SimResult(
        time_s=time_s, pinion_speed=om.copy(), gear_speed=(om * rb1 - v) / rb2,
        pinion_angle=th.copy(), gear_angle=(th * rb1 - x) / rb2, dte=x.copy(), dte_rate=v.copy(),
        mesh_force=force, pair_force=pair, load_sharing=ls, mesh_stiffness=stiff,
        pinion_torque=t1s, gear_torque=t2s, step_s=h, substeps=n_sub, damping_Ns_per_m=c,
        damping_model=damping_model, wall_s=wall, info=info)


def simulate(
    tables: MeshTables,
    *,
    stop_time_s: float,
    comm_step_s: float,
    max_step_s: Optional[float] = None,
    pinion_torque_Nm: InputLike,
    gear_torque_Nm: Optional[InputLike] = None,
    pinion_speed_start_rad_s: float,
    damping_ratio: float,
    damping_model: str = "elastobacklash",
    pinion_angle_start_rad: float = 0.0,
    dte_start_m: Optional[float] = None,
    dte_rate_start_m_s: float = 0.0,
    integrator: str = DEFAULT_INTEGRATOR,
    bulk_temperature_C: Optional[InputLike] = None,
) -> SimResult:
    """Run the two-inertia multi-pair model of docs/model.md (seed 003 eq 1-6).

    Inputs (N*m) are a float, an array with one value per communication step
    (n or n+1 values; value k is held over [t_k, t_k+H)), or a callable of
    time t_k (s).  ``gear_torque_Nm`` None means the balancing load
    T2 = T1*Rb2/Rb1 (seed 003: F_m = T1/Rb1 = T2/Rb2).  ``max_step_s`` None
    means :func:`choose_max_step_s` at 1.5 x the start speed (at least 1 rad/s).
    ``dte_start_m`` / ``dte_rate_start_m_s`` (m, m/s) start from a given state
    instead of the quasi-static equilibrium at rest relative motion, e.g. the
    last state of a previous run (continuation in a speed sweep).
    If the state turns non-finite the run stops there; the remaining rows are
    NaN and ``info['diverged_at_step']`` says where.
    ``integrator``: 'rk4_kink' (default, :data:`DEFAULT_INTEGRATOR`: RK4 that
    steps exactly to every table node and contact-mode change, docs/model.md
    "rk4_kink"; ``info['events']`` counts the located events; at most
    KINK_MAX_SLOTS slots) or 'rk4' (fixed-step classical RK4).
    ``bulk_temperature_C`` (degC; tables with a temperature axis only): the FMU
    input ``bulk_temperature``, an input like the torques (None: the tables'
    ``default_temperature_C``); docs/model.md "Temperature axis".
    """
    if isinstance(tables, MeshTables) and tables.has_temperature_axis:
        return _simulate_temperature_axis(
            tables, bulk_temperature_C, stop_time_s=stop_time_s, comm_step_s=comm_step_s, max_step_s=max_step_s,
            pinion_torque_Nm=pinion_torque_Nm, gear_torque_Nm=gear_torque_Nm,
            pinion_speed_start_rad_s=pinion_speed_start_rad_s, damping_ratio=damping_ratio,
            damping_model=damping_model, pinion_angle_start_rad=pinion_angle_start_rad, dte_start_m=dte_start_m,
            dte_rate_start_m_s=dte_rate_start_m_s, integrator=integrator)
    if bulk_temperature_C is not None:
        raise NativeInputError("bulk_temperature_C: the tables have no temperature axis")
    t = _check_tables(tables)
    icode = _integrator_code(integrator, t.slots)
    w0 = _finite("pinion_speed_start_rad_s", pinion_speed_start_rad_s)
    if max_step_s is None:
        max_step_s = choose_max_step_s(t, max(1.5 * abs(w0), 1.0))
    t, stop, H, n_steps, n_sub, h, c, me, model = _common(
        t, stop_time_s, comm_step_s, max_step_s, damping_ratio, damping_model)
    rb1, rb2 = float(t.base_radius_pinion_m), float(t.base_radius_gear_m)
    t1s = _input_series("pinion_torque_Nm", pinion_torque_Nm, n_steps, H)
    if gear_torque_Nm is None:
        t2s = t1s * rb2 / rb1
    else:
        t2s = _input_series("gear_torque_Nm", gear_torque_Nm, n_steps, H)
    th0 = _finite("pinion_angle_start_rad", pinion_angle_start_rad)
    k, e, b, tq, inv_dphi, dphi = _arrays(t)
    x0 = _initial_x(t, k, e, b, tq, inv_dphi, th0, t1s[0], dte_start_m)
    state = np.full((n_steps + 1, 4), np.nan)
    pair = np.full((n_steps + 1, t.slots), np.nan)
    force = np.full(n_steps + 1, np.nan)
    stiff = np.full(n_steps + 1, np.nan)
    _warmup(kink=icode == 1)
    v0 = _finite("dte_rate_start_m_s", dte_rate_start_m_s)
    _row0(th0, w0, x0, v0, t1s[0], k, e, b, tq, inv_dphi, c, model, state, pair, force, stiff)
    events = np.zeros(n_steps + 1, dtype=np.int64)
    t_start = _time.perf_counter()
    if icode == 0:
        done = _run_2dof(th0, w0, x0, v0, t1s, t2s, n_sub, h, rb1, rb2,
                         float(t.inertia_pinion_kgm2), float(t.inertia_gear_kgm2),
                         k, e, b, tq, inv_dphi, c, model, state, pair, force, stiff)
    else:
        done = _run_kink(th0, w0, x0, v0, t1s, t2s, n_sub, h, rb1, rb2,
                         float(t.inertia_pinion_kgm2), float(t.inertia_gear_kgm2), me, False,
                         k, e, b, tq, inv_dphi, dphi, c, model, state, pair, force, stiff, events)
    wall = _time.perf_counter() - t_start
    time_s = np.arange(n_steps + 1) * H
    return _finish(t, time_s, state, pair, force, stiff, t1s, t2s, h, n_sub, c, damping_model, wall,
                   done, {"form": "two-inertia (docs/model.md)", "equivalent_mass_kg": me,
                          "integrator": integrator, "events": int(events.sum())})


def simulate_sdof(
    tables: MeshTables,
    *,
    omega1_rad_s: float,
    stop_time_s: float,
    comm_step_s: float,
    max_step_s: Optional[float] = None,
    pinion_torque_Nm: InputLike,
    damping_ratio: float,
    damping_model: str = "elastobacklash",
    pinion_angle_start_rad: float = 0.0,
    dte_start_m: Optional[float] = None,
    dte_rate_start_m_s: float = 0.0,
    integrator: str = DEFAULT_INTEGRATOR,
    bulk_temperature_C: Optional[float] = None,
) -> SimResult:
    """Time-indexed SDOF form of seed 003 eq 3-6 (SI units).

    The pinion turns at the prescribed constant speed: theta1 = theta1_0 +
    omega1*t; states [x (m), v (m/s)]; m_e dv/dt + F = F_m with F_m = T1/Rb1 and
    F the same per-pair force sum as :func:`simulate` (de_j = slope*omega1).
    Same RK4 arithmetic and substeps; stage times t, t+h/2, t+h/2, t+h with
    t = k*H + i*h.  The gear outputs are the derived ones of docs/model.md.
    ``integrator`` 'rk4_kink' integrates theta1 as a state with omega1' = 0
    and steps to every table node and contact-mode change (docs/model.md).
    ``bulk_temperature_C`` (degC, constant; tables with a temperature axis):
    the run uses ``tables.at_temperature`` (None: ``default_temperature_C``).
    """
    if isinstance(tables, MeshTables) and tables.has_temperature_axis:
        tables = _at_temperature(tables, tables.default_temperature_C if bulk_temperature_C is None
                                 else bulk_temperature_C)
    elif bulk_temperature_C is not None:
        raise NativeInputError("bulk_temperature_C: the tables have no temperature axis")
    t = _check_tables(tables)
    icode = _integrator_code(integrator, t.slots)
    om = _finite("omega1_rad_s", omega1_rad_s)
    if max_step_s is None:
        max_step_s = choose_max_step_s(t, max(abs(om), 1.0))
    t, stop, H, n_steps, n_sub, h, c, me, model = _common(
        t, stop_time_s, comm_step_s, max_step_s, damping_ratio, damping_model)
    rb1 = float(t.base_radius_pinion_m)
    t1s = _input_series("pinion_torque_Nm", pinion_torque_Nm, n_steps, H)
    t2s = t1s * float(t.base_radius_gear_m) / rb1
    th0 = _finite("pinion_angle_start_rad", pinion_angle_start_rad)
    k, e, b, tq, inv_dphi, dphi = _arrays(t)
    x0 = _initial_x(t, k, e, b, tq, inv_dphi, th0, t1s[0], dte_start_m)
    state = np.full((n_steps + 1, 4), np.nan)
    pair = np.full((n_steps + 1, t.slots), np.nan)
    force = np.full(n_steps + 1, np.nan)
    stiff = np.full(n_steps + 1, np.nan)
    _warmup(kink=icode == 1)
    v0 = _finite("dte_rate_start_m_s", dte_rate_start_m_s)
    _row0(th0, om, x0, v0, t1s[0], k, e, b, tq, inv_dphi, c, model, state, pair, force, stiff)
    events = np.zeros(n_steps + 1, dtype=np.int64)
    t_start = _time.perf_counter()
    if icode == 0:
        done = _run_sdof(th0, om, x0, v0, t1s, H, n_sub, h, rb1, me, k, e, b, tq,
                         inv_dphi, c, model, state, pair, force, stiff)
    else:
        done = _run_kink(th0, om, x0, v0, t1s, t2s, n_sub, h, rb1, float(t.base_radius_gear_m),
                         float(t.inertia_pinion_kgm2), float(t.inertia_gear_kgm2), me, True,
                         k, e, b, tq, inv_dphi, dphi, c, model, state, pair, force, stiff, events)
    wall = _time.perf_counter() - t_start
    time_s = np.arange(n_steps + 1) * H
    return _finish(t, time_s, state, pair, force, stiff, t1s, t2s, h, n_sub, c, damping_model, wall,
                   done, {"form": "time-indexed SDOF (seed 003 eq 3-6)", "equivalent_mass_kg": me,
                          "omega1_rad_s": om, "integrator": integrator, "events": int(events.sum())})


def dimensionless(result: SimResult, tables: MeshTables, length_scale_m: float) -> DimensionlessResult:
    """Seed 003 eq 7-9: q = x/l, tau = omega_n t, Omega_h = omega_mesh/omega_n.

    omega_n = sqrt(k_m/m_e) (rad/s) with k_m = tables.k_mean_N_per_m; the mesh
    frequency omega_mesh = 2*pi*omega1/mesh_period_rad (rad/s) uses the mean
    pinion speed of the result; q_rate = dq/dtau = v/(l omega_n); zeta is the
    per-pair damping ratio c/(2 m_e omega_n) (seed 003 eq 8, zeta bar); load =
    F_m/(k_m l) with F_m = T1/Rb1 of the first row.
    """
    t = _check_tables(tables)
    l = _finite("length_scale_m", length_scale_m, positive=True)
    me = t.equivalent_mass_kg
    wn = math.sqrt(t.k_mean_N_per_m / me)
    om = float(np.mean(result.pinion_speed))
    return DimensionlessResult(
        tau=wn * result.time_s, q=result.dte / l, q_rate=result.dte_rate / (l * wn),
        Omega_h=2.0 * math.pi * om / t.mesh_period_rad / wn, omega_n_rad_s=wn,
        zeta=result.damping_Ns_per_m / (2.0 * me * wn),
        load=float(result.pinion_torque[0]) / t.base_radius_pinion_m / (t.k_mean_N_per_m * l),
        length_scale_m=l)


# ------------------------------------------------- temperature axis (docs/model.md)
def _at_temperature(tables: MeshTables, temperature_C) -> MeshTables:
    try:
        return tables.at_temperature(float(temperature_C))
    except (TypeError, ValueError) as exc:
        if isinstance(exc, TemperatureRangeError):
            raise NativeInputError(f"bulk_temperature_C: {exc}") from None
        raise NativeInputError(f"bulk_temperature_C: expected a number, got {temperature_C!r}") from None


def _simulate_temperature_axis(tables: MeshTables, bulk_temperature_C, *, stop_time_s, comm_step_s, max_step_s,
                               pinion_torque_Nm, gear_torque_Nm, pinion_speed_start_rad_s, damping_ratio,
                               damping_model, pinion_angle_start_rad, dte_start_m, dte_rate_start_m_s,
                               integrator) -> SimResult:
    """:func:`simulate` on tables with a temperature axis.  The temperature is held
    over each communication step like the torques; every run of steps with one
    temperature is simulated on ``tables.at_temperature(T)`` (the node-wise blend of
    docs/model.md "Temperature axis", the arithmetic of the C kernel), continuing
    from the state [theta1, omega1, x, v] of the previous run -- the same
    per-step computation as an FMU whose input changes at those steps."""
    t = tables.validate()
    H = _finite("comm_step_s", comm_step_s, positive=True)
    n_steps = _n_steps(_finite("stop_time_s", stop_time_s, positive=True), H)
    temps = _input_series("bulk_temperature_C", t.default_temperature_C if bulk_temperature_C is None
                          else bulk_temperature_C, n_steps, H)
    slices = {}
    for T in np.unique(temps[:n_steps + 1]):
        slices[float(T)] = _at_temperature(t, T)
    t1s = _input_series("pinion_torque_Nm", pinion_torque_Nm, n_steps, H)
    rb1, rb2 = float(t.base_radius_pinion_m), float(t.base_radius_gear_m)
    t2s = t1s * rb2 / rb1 if gear_torque_Nm is None else _input_series("gear_torque_Nm", gear_torque_Nm, n_steps, H)
    w0 = _finite("pinion_speed_start_rad_s", pinion_speed_start_rad_s)
    if max_step_s is None:  # k_mean does not depend on temperature: one step bound for all runs
        max_step_s = choose_max_step_s(slices[float(temps[0])], max(1.5 * abs(w0), 1.0))
    parts = []
    th, om, x, v = _finite("pinion_angle_start_rad", pinion_angle_start_rad), w0, dte_start_m, dte_rate_start_m_s
    i = 0
    while i < n_steps:
        j = i + 1
        while j < n_steps and temps[j] == temps[i]:
            j += 1
        r = simulate(slices[float(temps[i])], stop_time_s=(j - i) * H, comm_step_s=H, max_step_s=max_step_s,
                     pinion_torque_Nm=t1s[i:j], gear_torque_Nm=t2s[i:j], pinion_speed_start_rad_s=om,
                     damping_ratio=damping_ratio, damping_model=damping_model, pinion_angle_start_rad=th,
                     dte_start_m=x, dte_rate_start_m_s=v, integrator=integrator)
        parts.append((i, r))
        if "diverged_at_step" in r.info:
            break
        th, om, x, v = (float(r.pinion_angle[-1]), float(r.pinion_speed[-1]), float(r.dte[-1]),
                        float(r.dte_rate[-1]))
        i = j
    first = parts[0][1]
    names = ("pinion_speed", "gear_speed", "pinion_angle", "gear_angle", "dte", "dte_rate", "mesh_force",
             "pair_force", "load_sharing", "mesh_stiffness")
    out = {}
    for n in names:
        a0 = getattr(first, n)
        arr = np.full((n_steps + 1,) + a0.shape[1:], np.nan)
        arr[0] = a0[0]
        for i0, r in parts:
            seg = getattr(r, n)[1:]
            arr[i0 + 1: i0 + 1 + seg.shape[0]] = seg
        out[n] = arr
    done = sum(int(r.info["completed_steps"]) for _, r in parts)
    info = dict(first.info, completed_steps=done, events=int(sum(r.info.get("events", 0) for _, r in parts)),
                bulk_temperature_C=temps, temperature_runs=len(parts))
    info.pop("diverged_at_step", None)
    if done < n_steps:
        info["diverged_at_step"] = done
    return SimResult(time_s=np.arange(n_steps + 1) * H, **out, pinion_torque=t1s, gear_torque=t2s,
                     step_s=first.step_s, substeps=first.substeps, damping_Ns_per_m=first.damping_Ns_per_m,
                     damping_model=first.damping_model, wall_s=float(sum(r.wall_s for _, r in parts)), info=info)
