"""The one loop over communication steps of the native solver (numba, SI units).

:func:`_loop` writes output row 0 (the initial state with the inputs of step 0)
and advances the state over every communication step with the chosen
integrator and form (compiled as two drivers, :func:`_run` and :func:`_run_seg`,
so that a run compiles only what it runs; :func:`driver_for` picks one); the integrator (``icode``: 0 'rk4', 1 'rk4_kink', 2 'rk4_node', 3 'rk4_seg',
gearfmu.common.vocabulary.INTEGRATORS) and the form (``sdof``: two-inertia,
Xu et al. 2022 eq 1-2, or time-indexed SDOF, Xu et al. 2022 eq 3-6) are the parts that
vary; the inputs held over the step, the table row blend and the outputs are
shared.  The per-step order of operations is that of gearkernel.c
(docs/model.md 'Integration', 'Outputs'), so the two agree bit for bit.
"""
from __future__ import annotations

import contextlib
import math

import numpy as np
from numba import njit

from ..common.jit import cache_is_cold
from ..common.progress import ticking
from .integrators import SEG_WORK_BASE, _kink_substep, _mode_sync, _rk4_step, _seg_start, _seg_substep
from .model_rhs import (
    _CELL_NONE, _cell_nodes, _equilibrium, _node_flags, _seg_flags, _outputs_row, _ptr, _tab, _table_pointers,
    _torque_index, _with_zones, _zone_sel,
)


@njit(cache=True, error_model="numpy")
def _write_row(tab, row, th, om, x, v, out_state, out_pair, out_force, out_stiff):
    """Output row ``row``: the state, the pair forces, the mesh force and stiffness."""
    out_state[row, 0] = th
    out_state[row, 1] = om
    out_state[row, 2] = x
    out_state[row, 3] = v
    ftot, ks = _outputs_row(tab, th, om, x, v, out_pair, row)
    out_force[row] = ftot
    out_stiff[row] = ks


@njit(cache=True, error_model="numpy", inline="always")
def _loop(seg, icode, sdof, th, om, x, v, t1s, t2s, H, n_sub, h, rb1, rb2, in1, in2, me, k, e, b, torque,
          inv_dphi, dphi, c, model, outs, cuts, zoned):
    """Rows 0..n of the outputs; returns the number of completed steps (fewer than
    n when the state turned non-finite).  ``seg`` (a constant of the caller, :func:`_run` or
    :func:`_run_seg`): the 'rk4_seg' loop; numba prunes the branch not taken, so each driver
    compiles only its own integrators.  ``outs`` = (out_state, out_pair, out_force,
    out_stiff, out_events), one argument (a call of more than 30 arguments reaches numba's
    inliner as a call with *args, which it cannot inline).

    Step s holds T1 = t1s[s], T2 = t2s[s] (N*m) and takes n_sub substeps of h (s).
    'rk4' carries the table cell across steps; in the SDOF form theta1 is
    th0 + omega1*t with t = s*H + i*h at substep i.  'rk4_kink' and 'rk4_node' set the contact
    mode from the state at the start of every step and counts the located events
    per step in out_events; in the SDOF form it integrates theta1 as a state
    with omega1' = 0.  'rk4_node' stops only at the table nodes flagged by
    _node_flags (computed once per run from k, e, b), 'rk4_seg' only at those of _seg_flags
    (from k, e, b and the cuts).  k, e (NT, P, N) and b (P, N) must be C-contiguous (the
    kernels read their data pointers, see gearfmu.dynamics.model_rhs).  ``zoned``: the sub-cell
    lookup at the contact-zone edges with the (2, P, N) ``cuts`` of gearfmu.tables.zones.zone_cuts
    (docs/model.md "Contact-zone edges"; rk4_kink and rk4_node stop at the cuts)."""
    out_state, out_pair, out_force, out_stiff, out_events = outs
    n_steps = out_state.shape[0] - 1
    kp, ep, bp, p, n_phi = _table_pointers(k, e, b)
    rows2 = k.shape[0] > 1
    mode = np.zeros(4 * p, dtype=np.int64)   # reg, sub, kpos and the held zone side per pair
    work = np.zeros(SEG_WORK_BASE + 4 * p)   # Hermite data, the held segment, rk4_seg's lookup
    if seg:
        flags = _seg_flags(k, e, b, cuts, zoned)
    else:
        flags = _node_flags(k, e, b)
    md = _ptr(mode)
    wk = _ptr(work)
    fp = _ptr(flags)
    zp = _ptr(cuts)
    th0 = th
    nd = _CELL_NONE
    i0 = 0
    for s in range(n_steps):
        t1 = t1s[s]
        t2 = t2s[s]
        fm = t1 / rb1
        it, wt = _torque_index(t1, torque)
        tab = _tab(kp, ep, bp, it, rows2, wt, n_phi, p, dphi, c, model, inv_dphi, fp)
        if zoned:
            tab = _with_zones(tab, zp)
        dyn = (sdof, t1, t2, rb1, rb2, in1, in2, fm, me, 1.0 / in1, 1.0 / in2)   # the last two: 1/I1, 1/I2
        if s == 0:
            _write_row(tab, 0, th, om, x, v, out_state, out_pair, out_force, out_stiff)
        if icode >= 1:
            ndk = np.floor(th * inv_dphi)
            ik0, ik1 = _cell_nodes(ndk, n_phi)
            _seg_start(tab, wk, ndk, icode >= 2, om, th)
            _zone_sel(tab, md, ndk, ik0, work[16], work[17])
            _mode_sync(tab, md, th, om, x, v, ndk, ik0, ik1, True)
            nev = 0
            if seg:
                work[18] = 0.0   # no reuse of a lookup across communication steps (tables, mode)
                for _ in range(n_sub):
                    th, om, x, v, ndk, ne = _seg_substep(tab, dyn, md, wk, th, om, x, v, h, ndk)
                    nev += ne
            else:
                for _ in range(n_sub):
                    th, om, x, v, ndk, ne = _kink_substep(tab, dyn, md, wk, th, om, x, v, h, ndk, icode == 2)
                    nev += ne
            out_events[s + 1] = nev
        else:
            t0 = s * H
            if sdof:
                for i in range(n_sub):
                    th, om, x, v, nd, i0 = _rk4_step(tab, dyn, True, th0, t0 + i * h, th, om, x, v, h, nd, i0)
                th = th0 + om * ((s + 1) * H)
            else:
                for i in range(n_sub):
                    th, om, x, v, nd, i0 = _rk4_step(tab, dyn, False, th0, t0, th, om, x, v, h, nd, i0)
        _write_row(tab, s + 1, th, om, x, v, out_state, out_pair, out_force, out_stiff)
        finite = math.isfinite(x) and math.isfinite(v)
        if icode >= 1 or not sdof:  # rk4 SDOF: theta1, omega1 follow from the time
            finite = finite and math.isfinite(th) and math.isfinite(om)
        if not finite:
            return s + 1
    return n_steps


@njit(cache=True, error_model="numpy")
def _run(icode, sdof, th, om, x, v, t1s, t2s, H, n_sub, h, rb1, rb2, in1, in2, me, k, e, b, torque,
         inv_dphi, dphi, c, model, out_state, out_pair, out_force, out_stiff, out_events, cuts, zoned):
    """:func:`_loop` of 'rk4', 'rk4_kink' and 'rk4_node' (``icode`` 0, 1, 2)."""
    return _loop(False, icode, sdof, th, om, x, v, t1s, t2s, H, n_sub, h, rb1, rb2, in1, in2, me, k, e, b, torque,
                 inv_dphi, dphi, c, model, (out_state, out_pair, out_force, out_stiff, out_events), cuts, zoned)


@njit(cache=True, error_model="numpy")
def _run_seg(icode, sdof, th, om, x, v, t1s, t2s, H, n_sub, h, rb1, rb2, in1, in2, me, k, e, b, torque,
             inv_dphi, dphi, c, model, out_state, out_pair, out_force, out_stiff, out_events, cuts, zoned):
    """:func:`_loop` of 'rk4_seg' (``icode`` 3), compiled only when a run asks for it."""
    return _loop(True, icode, sdof, th, om, x, v, t1s, t2s, H, n_sub, h, rb1, rb2, in1, in2, me, k, e, b, torque,
                 inv_dphi, dphi, c, model, (out_state, out_pair, out_force, out_stiff, out_events), cuts, zoned)


def driver_for(icode: int):
    """The compiled driver of integrator code ``icode``: :func:`_run_seg` for 'rk4_seg', else :func:`_run`."""
    return _run_seg if icode == 3 else _run


_COMPILED = set()
#: the cuts argument of :func:`_run` without the sub-cell lookup (never read)
NO_CUTS = np.full((2, 1, 1), -1.0)


_ANNOUNCING = []  # the open compiling() block, if any (one line for the whole compilation)


@contextlib.contextmanager
def compiling(icode: int = 0):
    """The block that first calls the native solver's compiled code of integrator code ``icode``
    (the table arrays, the equilibrium, the driver): one line with the elapsed time on stderr
    while it runs when numba's cache does not hold the driver yet (the first run after
    installing or updating gearfmu; :func:`gearfmu.common.progress.ticking`), nothing otherwise."""
    run = driver_for(icode)
    cold = not _ANNOUNCING and run not in _COMPILED and cache_is_cold([run])
    with ticking("compiling the native solver (first run after installing or updating gearfmu, about a minute; "
                 "kept for later runs)", enabled=None if cold else False):
        _ANNOUNCING.append(icode)
        try:
            yield
        finally:
            _ANNOUNCING.pop()


def _warmup(icode: int = 0) -> None:
    """Compile (or load from the cache) the driver of integrator code ``icode``
    (:func:`driver_for`) on a tiny problem, so that a run's ``wall_s`` excludes the
    compilation; argument types as simulate passes them."""
    run = driver_for(icode)
    if run in _COMPILED:
        return
    with compiling(icode):
        _warm(run, icode)
    _COMPILED.add(run)


def _warm(run, icode: int) -> None:
    k = np.ones((2, 1, 4)) * 1e8
    e = np.zeros((2, 1, 4))
    b = np.zeros((1, 4))
    tq = np.array([0.0, 1.0])
    x0 = _equilibrium(0.0, 1.0, 0.1, k, e, b, tq, 4.0)
    run(icode, False, 0.0, 1.0, x0, 0.0, np.ones(2), np.ones(2), 1e-6, 1, 1e-6, 0.1, 0.1, 1.0, 1.0, 1.0,
        k, e, b, tq, 4.0, 0.25, 1.0, 0, np.zeros((2, 4)), np.zeros((2, 1)), np.zeros(2), np.zeros(2),
        np.zeros(2, dtype=np.int64), NO_CUTS, False)
