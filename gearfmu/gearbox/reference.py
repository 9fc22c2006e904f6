"""Event-located reference of the gearbox model (tests and benchmarks only).

The equations of docs/gearbox.md "Model", written again in plain Python -- no numba kernel of
:mod:`gearfmu.gearbox.kernels` or :mod:`gearfmu.dynamics` is called -- and integrated with
scipy's ``solve_ivp`` (DOP853 by default, rtol 1e-10), so that no integrator setting of this
project is tuned against it.  Every mesh is the pair model of docs/model.md on its stage's tables,
represented by the pair reference's table pieces and per-pair force law
(:mod:`gearfmu.dynamics.reference`: ``TableRows`` for the table pieces, kink nodes and contact-zone
lines, ``TableSegment`` for one piece's linear tables, the per-pair contact and damping modes, their
force and their switching indicators).

Segments: inside one segment every mesh keeps its table piece (between two kink nodes of its
tables), every pair of every mesh its contact and elastobacklash mode, and the inputs are constant,
so the right-hand side is a polynomial in the state and DOP853 keeps its order.  Each segment
stops at the first event of any mesh (a node of its piece, or a pair's indicator), located as a
terminal ``solve_ivp`` event on the dense output; the next segment starts there with the new piece
or pair mode of that mesh.  The choices of the pair reference carry over: modes after a switch
read a little ahead along the field (all other indicators), ``atol`` per state from physical
scales, the largest step a fraction of the shortest natural period, and the motor angle
integrated relative to the segment start.

Initial state: the quasi-static equilibrium of :meth:`gearfmu.gearbox.model.GearboxModel.static_state`,
computed here with the exact leftmost root of each mesh's piecewise-linear static force
(``equilibrium_dte_exact_m``) instead of the kernels' bisection.

``simulate_reference(model, settings, ...)`` takes the settings and arguments of
:func:`gearfmu.gearbox.native.simulate` (without ``max_step_s`` and ``integrator``) plus its
accuracy (:class:`ReferenceAccuracy`, the pair reference's: ``rtol``, ``method``, ``steps_per_period``,
...) and returns a :class:`gearfmu.gearbox.native.GearboxResult` with the same columns.
"""
from __future__ import annotations

import math
import time as _time
from typing import Optional

import numpy as np
import scipy.linalg
from scipy.integrate import solve_ivp

from ..common.progress import progress_bar
from ..dynamics.reference import (ReferenceAccuracy, TableRows, TableSegment, equilibrium_dte_exact_m, pair_forces,
                                 reference_accuracy)
from .model import GearboxModel
from ..common.settings import GearboxRunSettings
from .native import GearboxInputError, GearboxResult, InputLike, checked_settings, columns, run_inputs

__all__ = ["simulate_reference", "ReferenceAccuracy"]


def _local(model: GearboxModel, m: int, y, psi_rel_index=True):
    """(theta_p - theta_base, omega_p, x, v) of mesh m from the state y (psi relative to its base)."""
    p, q = model.mesh_bodies[m]
    up = y[2 * p] if p > 0 else 0.0
    dup = y[2 * p + 1] if p > 0 else 0.0
    uq = y[2 * q] if q > 0 else 0.0
    duq = y[2 * q + 1] if q > 0 else 0.0
    gp = model.g[p]
    rb_p, rb_q = model.mesh_rb_m[m]
    return (gp * y[0] + up, gp * y[1] + dup, rb_p * up - rb_q * uq, rb_p * dup - rb_q * duq)


def _lookup_values(rows: TableRows, theta: float):
    """k, e, b of every slot at pinion angle theta by docs/model.md (plain, or the zone lines)."""
    s = theta / rows.dphi
    if rows.zones is not None:
        v = rows.values_at(s)
        return v[0], v[1], v[3]
    N = rows.N
    u = s - N * math.floor(s / N)
    i0 = min(max(int(math.floor(u)), 0), N - 1)
    w = u - i0
    i1 = 0 if i0 + 1 == N else i0 + 1
    lerp = lambda A: A[:, i0] + w * (A[:, i1] - A[:, i0])
    return lerp(rows.K), lerp(rows.E), lerp(rows.B)


def simulate_reference(model: GearboxModel, settings: Optional[GearboxRunSettings] = None, *,
                       stop_time_s: Optional[float] = None, comm_step_s: Optional[float] = None,
                       motor_torque_Nm: Optional[InputLike] = None, load_torque_Nm: Optional[InputLike] = None,
                       motor_speed_start_rad_s: Optional[float] = None, motor_angle_start_rad: Optional[float] = None,
                       initial_state=None, accuracy: Optional[ReferenceAccuracy] = None, progress: bool = False,
                       **accuracy_fields) -> GearboxResult:
    """Event-located solve_ivp reference of the gearbox model (module docstring); settings and
    arguments as :func:`gearfmu.gearbox.native.simulate` (its step bound and integrator unused),
    plus ``accuracy`` (:class:`ReferenceAccuracy`; each of its fields, ``rtol``, ``atol_scale``,
    ``method``, ``steps_per_period``, ``max_segments``, may be given as a keyword instead).
    Steps: the quasi-static initial state (:meth:`_Reference.initial_state`), the scales of the
    tolerances and steps (:meth:`_Reference.set_scales`), then per communication step the
    segments between events (:meth:`_Reference.step`).  ``wall_s`` is the whole run."""
    rs = checked_settings(model, settings, GearboxInputError, stop_time_s=stop_time_s, output_interval_s=comm_step_s,
                           motor_speed_start_rad_s=motor_speed_start_rad_s, motor_angle_start_rad=motor_angle_start_rad)
    n_steps, t_in, t_out, t_ref, y_given = run_inputs(model, rs, motor_torque_Nm, load_torque_Nm, initial_state)
    acc = reference_accuracy(accuracy, accuracy_fields, GearboxInputError)
    ref = _Reference(model, acc)
    y0 = ref.initial_state(rs, t_ref, y_given)
    ref.set_scales(t_ref, y0, rs.motor_speed_start_rad_s)
    out = _Outputs(model, n_steps)
    H = rs.output_interval_s
    ref.psi = float(y0[0])          # the motor angle at the segment start; the state holds psi - psi_base
    ref.y = y0.copy()
    ref.y[0] = 0.0
    out.row(ref, 0, t_ref[0])
    diverged = None
    t_wall = _time.perf_counter()
    for k in progress_bar(range(n_steps), "gearbox reference", progress, unit="step"):
        if not ref.step(k * H, (k + 1) * H, float(t_in[k]), float(t_out[k]), t_ref[k]):
            diverged = k
            break
        out.row(ref, k + 1, t_ref[k])
    wall = _time.perf_counter() - t_wall
    state = ref.y.copy()
    state[0] = ref.psi
    info = {"form": "gearbox (docs/gearbox.md), event-located solve_ivp reference", "method": acc.method,
            "rtol": acc.rtol, "max_step_s": ref.h_cap, "segments": ref.n_seg, "events": ref.n_ev,
            "rhs_calls": ref.nfev, "completed_steps": n_steps if diverged is None else diverged}
    if diverged is not None:
        info["diverged_at_step"] = int(diverged)
    cols = columns(model, out.pair_off, out.body, out.mesh, out.pair, out.shaft, t_in, t_out)
    return GearboxResult(time_s=np.arange(n_steps + 1) * H, columns=cols, step_s=0.0, substeps=ref.n_seg,
                         integrator=f"reference {acc.method}", wall_s=wall, state=state, info=info)


class _Outputs:
    """The output rows of a run (bodies, meshes, pairs, shafts), one per communication point."""

    def __init__(self, model: GearboxModel, n_steps: int):
        n, nm = model.n_bodies, len(model.meshes)
        self.body = np.full((n_steps + 1, 2 * n), np.nan)
        self.mesh = np.full((n_steps + 1, 4 * nm), np.nan)
        self.pair_off = np.zeros(nm + 1, dtype=np.int64)
        for m, mesh in enumerate(model.meshes):
            self.pair_off[m + 1] = self.pair_off[m] + mesh.tables.slots
        self.pair = np.full((n_steps + 1, int(self.pair_off[-1])), np.nan)
        self.shaft = np.full((n_steps + 1, len(model.shafts)), np.nan)

    def row(self, ref: "_Reference", i: int, tr) -> None:
        """Row ``i`` from the reference's state (motor angle ``ref.psi``, state ``ref.y``) with the
        table rows of the reference torque ``tr``: body angles and speeds, each mesh's DTE, its
        rate, force and stiffness in contact, each pair's force, each shaft's torque."""
        model, psi, y = ref.model, ref.psi, ref.y
        g = model.g
        for b in range(model.n_bodies):
            self.body[i, 2 * b] = g[b] * psi + (y[2 * b] if b > 0 else 0.0)
            self.body[i, 2 * b + 1] = g[b] * y[1] + (y[2 * b + 1] if b > 0 else 0.0)
        for m in range(len(model.meshes)):
            th, om, x, v = _local(model, m, y)
            th = g[model.mesh_bodies[m, 0]] * psi + (th - g[model.mesh_bodies[m, 0]] * y[0])
            F, st, kk = pair_forces(th, om, x, v, ref.rows_for(m, tr), ref.pars[m][4], ref.pars[m][5])
            self.pair[i, self.pair_off[m]:self.pair_off[m + 1]] = F
            self.mesh[i, 4 * m:4 * m + 4] = (x, v, F.sum(), kk[st != 0].sum())
        for s in range(len(model.shafts)):
            self.shaft[i, s] = _shaft_torque(model, s, y)


def _shaft_torque(model: GearboxModel, s: int, y) -> float:
    """Torque (N m) of shaft ``s``: k (u_a - u_b) + c (du_a - du_b) of its end bodies."""
    a_, b_ = model.shaft_bodies[s]
    ua, ub = (y[2 * a_] if a_ > 0 else 0.0), (y[2 * b_] if b_ > 0 else 0.0)
    dua, dub = (y[2 * a_ + 1] if a_ > 0 else 0.0), (y[2 * b_ + 1] if b_ > 0 else 0.0)
    return model.shaft_k_Nm_per_rad[s] * (ua - ub) + model.shaft_c_Nms_per_rad[s] * (dua - dub)


class _Reference:
    """The reference's integration of one run: the table rows per mesh and reference torque, the
    equations of motion (:meth:`deriv`), the tolerances and step limits (:meth:`set_scales`), and
    the state -- motor angle ``psi`` at the segment start, state ``y`` relative to it, each mesh's
    table piece -- carried through the segments of each communication step (:meth:`step`)."""

    def __init__(self, model: GearboxModel, acc: ReferenceAccuracy):
        self.model, self.acc = model, acc
        nm = len(model.meshes)
        self.on_path = [mesh.name in model.on_path for mesh in model.meshes]
        self.pars = [(model.mesh_rb_m[m, 0], model.mesh_rb_m[m, 1], 1.0, 1.0, float(model.mesh_c_Ns_per_m[m]),
                      model.meshes[m].damping_model) for m in range(nm)]
        self.cache = {}
        self.pieces = [None] * nm
        self.prev = [None] * nm
        self.n_seg = self.n_ev = self.nfev = 0
        self.first_step = None
        self.psi, self.y = 0.0, None

    def rows_for(self, m: int, tr) -> TableRows:
        """The table rows of mesh ``m`` at the motor-side reference torque ``tr`` (the mesh's own
        torque through the gear ratio on the power path; the rows are kept)."""
        model = self.model
        tq = float(tr / model.g[model.mesh_bodies[m, 0]]) if self.on_path[m] else 0.0
        key = (m, tq if model.meshes[m].tables.n_torque > 1 else 0.0)
        if key not in self.cache:
            self.cache[key] = TableRows(model.meshes[m].tables, key[1])
        return self.cache[key]

    def initial_state(self, rs: GearboxRunSettings, t_ref, y_given):
        """The given state, or the quasi-static one: walk the tree from the motor, each shaft at its
        static twist, each mesh at the exact leftmost root of its piecewise-linear static force."""
        if y_given is not None:
            return y_given.copy()
        model = self.model
        g, n = model.g, model.n_bodies
        y0 = np.zeros(2 * n)
        y0[0], y0[1] = rs.motor_angle_start_rad, rs.motor_speed_start_rad_s
        u = np.zeros(n)
        ts = model.shaft_static_torques_Nm(float(t_ref[0]))
        tm = model.stage_torques_Nm(float(t_ref[0]))
        for kind, e, up, down in model.tree_edges:
            if kind == "shaft":
                u[down] = u[up] - ts[e] / model.shaft_k_Nm_per_rad[e]
                continue
            p, q = model.mesh_bodies[e]
            K, E, B = _lookup_values(self.rows_for(e, t_ref[0]), g[p] * rs.motor_angle_start_rad + u[p])
            x = equilibrium_dte_exact_m(K, E, B, tm[e] / model.mesh_rb_m[e, 0])
            if not math.isfinite(x):
                raise GearboxInputError(f"motor_angle_start_rad: no pair of mesh {model.meshes[e].name!r} in contact")
            u[q] = (model.mesh_rb_m[e, 0] * u[p] - x) / model.mesh_rb_m[e, 1]
        y0[2::2] = u[1:]
        return y0

    def set_scales(self, t_ref, y0, speed_rad_s: float) -> None:
        """The largest step ``h_cap``, the look-ahead ``delta`` of the mode choice (both from the
        highest natural frequency of the linearisation at every mesh's largest stiffness) and the
        absolute tolerance per state from physical scales (angle: the shortest mesh period; speed;
        deflection: the largest of the static deflection, backlash and error range; its rate)."""
        model, acc = self.model, self.acc
        g, n = model.g, model.n_bodies
        kmax = [float(np.max(m.tables.k_N_per_m.sum(axis=1))) for m in model.meshes]
        Mm, Km, _ = model.linearisation(float(t_ref[0]), mesh_stiffness_N_per_m=kmax)
        w_max = math.sqrt(max(float(np.max(scipy.linalg.eigh(Km, Mm, eigvals_only=True))), 1e-300))
        self.h_cap = 2.0 * math.pi / w_max / float(acc.steps_per_period)
        self.delta = 1e-9 * 2.0 * math.pi / w_max
        xs = []
        for m, mesh in enumerate(model.meshes):
            t = mesh.tables
            fm = float(np.max(np.abs(t_ref))) / g[model.mesh_bodies[m, 0]] / model.mesh_rb_m[m, 0]
            xs.append(max(fm / float(t.k_mean_N_per_m), float(np.max(t.backlash_half_m)), float(np.ptp(t.e_m)), 1e-9)
                      / float(np.min(model.mesh_rb_m[m])))
        us = max(max(xs), float(np.max(np.abs(y0[2::2]))) if n > 1 else 0.0, 1e-12)
        psi_s = min(float(m.tables.mesh_period_rad) / g[model.mesh_bodies[i, 0]] for i, m in enumerate(model.meshes))
        scale = np.empty(2 * n)
        scale[0], scale[1] = psi_s, max(abs(speed_rad_s), 1.0)
        scale[2::2], scale[3::2] = us, us * w_max
        self.atol = acc.rtol * acc.atol_scale * scale

    def deriv(self, y, forces, T1, T2):
        """d/dt of the state (docs/gearbox.md "Model"): the motor and load torques, the shaft
        torques and the mesh forces ``forces`` on the bodies, relative accelerations."""
        model = self.model
        n, g = model.n_bodies, model.g
        tau = np.zeros(n)
        tau[0] += T1
        tau[model.load_body] -= T2
        for s in range(len(model.shafts)):
            a_, b_ = model.shaft_bodies[s]
            ts_ = _shaft_torque(model, s, y)
            tau[a_] -= ts_
            tau[b_] += ts_
        for m in range(len(model.meshes)):
            p, q = model.mesh_bodies[m]
            tau[p] -= model.mesh_rb_m[m, 0] * forces[m]
            tau[q] += model.mesh_rb_m[m, 1] * forces[m]
        acc = tau / model.inertia_kgm2
        dy = np.empty(2 * n)
        dy[0], dy[1] = y[1], acc[0]
        dy[2::2] = y[3::2]
        dy[3::2] = acc[1:] - g[1:] * acc[0]
        return dy

    def step(self, t: float, t_end: float, T1: float, T2: float, tr) -> bool:
        """One communication step [t, t_end] at motor torque T1 and load torque T2 (the table rows
        of ``tr``): each mesh's piece where its rows changed, then segments from event to event
        until t_end (:meth:`segment`).  False where the state diverged."""
        model = self.model
        nm = len(model.meshes)
        rows = [self.rows_for(m, tr) for m in range(nm)]
        for m in range(nm):
            if rows[m] is not self.prev[m] or self.pieces[m] is None:
                th, om, _, _ = _local(model, m, self.y)
                self.pieces[m] = rows[m].piece_of(model.g[model.mesh_bodies[m, 0]] * self.psi + th, om)
                self.prev[m] = rows[m]
        forced = None
        zero_len = 0
        while t < t_end:
            seg = self.segment(rows, (t, t_end), T1, T2, forced)
            if seg is None:
                return False
            t_new, forced, event = seg
            if event:
                zero_len = zero_len + 1 if t_new <= t else 0
                if zero_len > 50:
                    raise RuntimeError(f"gearbox reference: no progress at t = {t!r} s (mode chattering)")
            t = t_new
            if not (np.all(np.isfinite(self.y)) and math.isfinite(self.psi)):
                return False
            if self.n_seg > self.acc.max_segments:
                raise RuntimeError(f"gearbox reference: more than max_segments={self.acc.max_segments} segments")
        return True

    def segment(self, rows, span, T1, T2, forced):
        """One segment from ``span`` = (t, t_end): every mesh on its piece with the contact and
        damping modes read a little ahead along the field (``forced``: the mode of the pair whose
        indicator ended the last segment), integrated by solve_ivp to the first event of any mesh
        (a node of its piece, or a pair's indicator) or to t_end.  The state moves there (the motor
        angle kept relative to the segment start).  Returns (time reached, the pair mode to force
        next, an event ended it) or None where solve_ivp failed."""
        model, acc = self.model, self.acc
        nm, g, y = len(model.meshes), model.g, self.y
        t, t_end = span
        segs = [TableSegment(rows[m], self.pieces[m], g[model.mesh_bodies[m, 0]] * self.psi, T1, T2, self.pars[m])
                for m in range(nm)]
        gen = [segs[m].force_general(_local(model, m, y)) for m in range(nm)]
        ya = y + self.delta * self.deriv(y, gen, T1, T2)
        modes = [segs[m].mode_from(_local(model, m, ya), forced[1] if forced and forced[0] == m else None)
                 for m in range(nm)]
        evs = _events(model, segs, modes)
        calls = [0]

        def rhs(tt, yy):
            calls[0] += 1
            return self.deriv(yy, [segs[m].force(_local(model, m, yy), modes[m]) for m in range(nm)], T1, T2)

        cap = self.h_cap
        for m in range(nm):
            if segs[m].node_hi is not None:
                om = abs(_local(model, m, y)[1])
                if om > 0.0:
                    cap = min(cap, (segs[m].node_hi - segs[m].node_lo) / om * 16.0 / float(acc.steps_per_period))
        sol = solve_ivp(rhs, (t, t_end), y, method=acc.method, rtol=acc.rtol, atol=self.atol,
                        events=[e for e, _ in evs] or None, max_step=cap,
                        first_step=None if not self.first_step else min(self.first_step, t_end - t))
        self.n_seg += 1
        self.nfev += calls[0]
        if sol.status == -1:
            return None
        if len(sol.t) >= 3:
            self.first_step = float(sol.t[-2] - sol.t[-3])
        forced = None
        if sol.status == 1:
            self.n_ev += 1
            hit = [i for i, te in enumerate(sol.t_events) if len(te)]
            i = min(hit, key=lambda i: sol.t_events[i][0])
            tag = evs[i][1]
            t_new = float(sol.t_events[i][0])
            yn = np.array(sol.y_events[i][0], dtype=float)
            m = tag[0]
            if tag[1] == "node":
                r = rows[m]
                self.pieces[m] = ((self.pieces[m][1], r.next_kink(self.pieces[m][1])) if tag[2] > 0
                                  else (r.prev_kink(self.pieces[m][0]), self.pieces[m][0]))
            else:
                forced = (m, (tag[2], tag[3], tag[4]))
        else:
            yn = np.array(sol.y[:, -1], dtype=float)
            t_new = t_end
        self.psi += float(yn[0])
        yn[0] = 0.0
        self.y = yn
        if sol.status == 1:
            self._cross_together(rows, tag)
        return t_new, forced, sol.status == 1

    def _cross_together(self, rows, tag) -> None:
        """Every mesh standing on its piece end crosses with the located event
        (:func:`cross_piece_ends`)."""
        model = self.model
        at = []
        for mm in range(len(model.meshes)):
            th, om, _, _ = _local(model, mm, self.y)
            at.append(((model.g[model.mesh_bodies[mm, 0]] * self.psi + th) / rows[mm].dphi, om))
        cross_piece_ends(self.pieces, rows, at, tag[0] if tag[1] == "node" else None)


def cross_piece_ends(pieces, rows, at, located) -> None:
    """Meshes whose table nodes coincide (two meshes on one pinion body with tables of one angle
    grid, such as an accessory drive beside the power path; planets meshing in phase) reach their
    piece ends together, and solve_ivp reports one event and finds none at the start of the next
    segment: every mesh but ``located`` standing on the end of its piece (``pieces[m]`` = (lo, hi)
    in node units; ``at[m]`` = (position in node units, angular speed)), moving out of it, crosses
    to the next piece of its ``rows[m]``."""
    for mm, (u, om) in enumerate(at):
        if pieces[mm] is None or mm == located:
            continue
        lo, hi = pieces[mm]
        if om > 0.0 and u >= hi - 1e-9:
            pieces[mm] = (hi, rows[mm].next_kink(hi))
        elif om < 0.0 and u <= lo + 1e-9:
            pieces[mm] = (rows[mm].prev_kink(lo), lo)


def _events(model: GearboxModel, segs, modes):
    """The terminal solve_ivp events of a segment, each with its tag (mesh, kind, ...): every
    mesh's piece nodes and pair indicators in the modes ``modes``."""
    evs = []
    for m in range(len(model.meshes)):
        for fn, tag in segs[m].events(modes[m]):
            ev = (lambda fn_, m_: (lambda tt, yy: fn_(tt, _local(model, m_, yy))))(fn, m)
            ev.terminal = True
            ev.direction = fn.direction
            evs.append((ev, (m,) + tuple(tag)))
    return evs
