"""Event-located reference of the planetary drivetrain model (tests and benchmarks only).

The equations of docs/planetary.md "Model", written again in plain Python -- no numba kernel of
:mod:`gearfmu.planetary.kernels` or :mod:`gearfmu.dynamics` is called -- and integrated with scipy's
``solve_ivp`` (DOP853 by default, rtol 1e-10), every mesh the pair reference's table pieces and
per-pair force law (:mod:`gearfmu.dynamics.reference`: ``TableRows``, ``TableSegment``,
``pair_forces``), as the gearbox reference does (gearfmu.gearbox.reference, whose choices carry over: segments inside which every
mesh keeps its table piece and pair modes, each ended by the first event of any mesh located as a
terminal ``solve_ivp`` event; modes after a switch read a little ahead along the field; ``atol`` per
state from physical scales; the largest step a fraction of the shortest natural period; the motor
angle integrated relative to the segment start).  The initial state is the model's quasi-static
state (:meth:`gearfmu.planetary.model.PlanetaryModel.static_state`).

``simulate_reference(model, ...)`` takes the settings and arguments of
:func:`gearfmu.planetary.native.simulate` (its step bound and integrator unused) plus the accuracy
of gearfmu.gearbox.reference.ReferenceAccuracy (``rtol``, ``method``, ``steps_per_period``, ...) and
returns a :class:`gearfmu.planetary.native.PlanetaryResult` with the same columns.
"""
from __future__ import annotations

import math
import time as _time
from dataclasses import fields as dataclass_fields, replace
from typing import Optional

import numpy as np
import scipy.linalg
from scipy.integrate import solve_ivp

from ..common.progress import progress_bar
from ..common.settings import GearboxRunSettings
from ..dynamics.native import InputLike
from ..dynamics.reference import TableRows, TableSegment, pair_forces
from ..gearbox.reference import ReferenceAccuracy, cross_piece_ends
from .model import PlanetaryModel
from .native import PlanetaryInputError, PlanetaryResult, checked_settings, columns, run_inputs

__all__ = ["simulate_reference"]


class _Maps:
    """The model's sparse maps as plain Python lists."""

    def __init__(self, model: PlanetaryModel):
        self.x = [[(int(d), float(c)) for d, c in zip(model.mesh_idx[m], model.mesh_coef[m]) if d >= 0]
                  for m in range(len(model.mesh_names))]
        self.a = [[(int(d), float(c)) for d, c in zip(model.angle_idx[m], model.angle_coef[m]) if d >= 0]
                  for m in range(len(model.mesh_names))]
        self.s = [[(int(d), float(c)) for d, c in zip(model.spring_idx[s], model.spring_coef[s]) if d >= 0]
                  for s in range(len(model.spring_names))]
        self.aref = [float(v) for v in model.angle_ref]
        self.phase = [float(v) for v in model.angle_phase]


def _q(y, d):
    return y[2 * d] if d > 0 else 0.0


def _qd(y, d):
    return y[2 * d + 1] if d > 0 else 0.0


def _local(mp: _Maps, m: int, y):
    """(theta - theta_base, omega, x, v) of mesh m from the state y (psi relative to its base)."""
    th = mp.aref[m] * y[0] + sum(c * _q(y, d) for d, c in mp.a[m])
    om = mp.aref[m] * y[1] + sum(c * _qd(y, d) for d, c in mp.a[m])
    x = sum(c * _q(y, d) for d, c in mp.x[m])
    v = sum(c * _qd(y, d) for d, c in mp.x[m])
    return th, om, x, v


def simulate_reference(model: PlanetaryModel, settings: Optional[GearboxRunSettings] = None, *,
                       stop_time_s: Optional[float] = None, comm_step_s: Optional[float] = None,
                       motor_torque_Nm: Optional[InputLike] = None, load_torque_Nm: Optional[InputLike] = None,
                       motor_speed_start_rad_s: Optional[float] = None, motor_angle_start_rad: Optional[float] = None,
                       initial_state=None, accuracy: Optional[ReferenceAccuracy] = None, progress: bool = False,
                       **accuracy_fields) -> PlanetaryResult:
    """Event-located solve_ivp reference (module docstring); settings and arguments as
    :func:`gearfmu.planetary.native.simulate` (its step bound and integrator unused), plus
    ``accuracy`` (gearfmu.gearbox.reference.ReferenceAccuracy; each of its fields, ``rtol``,
    ``atol_scale``, ``method``, ``steps_per_period`` -- the largest step: the shortest natural period
    of the linearisation with every mesh at its largest total stiffness, over this number --,
    ``max_segments``, may be given as a keyword instead).  Steps: the quasi-static initial state,
    the scales of the tolerances and steps (:meth:`_Reference.set_scales`), then per communication
    step the segments between events (:meth:`_Reference.step`).  ``wall_s`` is the whole run.  A model
    with a driven member is refused (docs/planetary.md "Driven members")."""
    if isinstance(model, PlanetaryModel) and model.drives:
        raise PlanetaryInputError(f"model: the reference does not take driven members ({model.drives[0]['port']}); "
                                  "gearfmu.planetary.native.simulate does")
    rs = checked_settings(model, settings, stop_time_s=stop_time_s, output_interval_s=comm_step_s,
                          motor_speed_start_rad_s=motor_speed_start_rad_s, motor_angle_start_rad=motor_angle_start_rad)
    n_steps, t_in, t_out, t_ref, y_given = run_inputs(model, rs, motor_torque_Nm, load_torque_Nm, initial_state)
    acc = _accuracy(accuracy, accuracy_fields)
    H = rs.output_interval_s
    ref = _Reference(model, acc)
    y0 = model.static_state(float(t_ref[0]), rs.motor_speed_start_rad_s, rs.motor_angle_start_rad) \
        if y_given is None else y_given.copy()
    ref.set_scales(t_ref, y0, rs.motor_speed_start_rad_s)
    out = _Outputs(model, n_steps)
    ref.psi = float(y0[0])          # the motor angle at the segment start; the state holds psi - psi_base
    ref.y = y0.copy()
    ref.y[0] = 0.0
    out.row(ref, 0, t_ref[0])
    diverged = None
    t_wall = _time.perf_counter()
    for k in progress_bar(range(n_steps), "planetary reference", progress, unit="step"):
        if not ref.step(k * H, (k + 1) * H, float(t_in[k]), float(t_out[k]), t_ref[k]):
            diverged = k
            break
        out.row(ref, k + 1, t_ref[k])
    wall = _time.perf_counter() - t_wall
    state = ref.y.copy()
    state[0] = ref.psi
    info = {"form": "planetary drivetrain (docs/planetary.md), event-located solve_ivp reference",
            "method": acc.method, "rtol": acc.rtol, "max_step_s": ref.h_cap, "segments": ref.n_seg,
            "events": ref.n_ev, "rhs_calls": ref.nfev, "completed_steps": n_steps if diverged is None else diverged}
    if diverged is not None:
        info["diverged_at_step"] = int(diverged)
    cols = columns(model, out.pair_off, out.dof, out.mesh, out.pair, out.spring, t_in, t_out)
    return PlanetaryResult(time_s=np.arange(n_steps + 1) * H, columns=cols, step_s=0.0, substeps=ref.n_seg,
                           integrator=f"reference {acc.method}", wall_s=wall, state=state, info=info)


def _accuracy(accuracy: Optional[ReferenceAccuracy], fields: dict) -> ReferenceAccuracy:
    """``accuracy`` (None: the defaults) with the keyword form applied, checked."""
    if accuracy is None:
        accuracy = ReferenceAccuracy()
    elif not isinstance(accuracy, ReferenceAccuracy):
        raise PlanetaryInputError(f"accuracy: expected ReferenceAccuracy, got {type(accuracy).__name__}")
    unknown = sorted(set(fields) - {f.name for f in dataclass_fields(ReferenceAccuracy)})
    if unknown:
        raise PlanetaryInputError(f"{unknown[0]}: not an argument of simulate_reference")
    acc = replace(accuracy, **fields) if fields else accuracy
    if not (acc.rtol > 0 and math.isfinite(acc.rtol)):
        raise PlanetaryInputError(f"rtol: must be a positive number, got {acc.rtol!r}")
    return acc


class _Outputs:
    """The output rows of a run (DOFs, meshes, pairs, springs), one per communication point."""

    def __init__(self, model: PlanetaryModel, n_steps: int):
        n, nm = model.n_dof, len(model.mesh_names)
        self.pair_off = np.zeros(nm + 1, dtype=np.int64)
        for m, t in enumerate(model.mesh_tables):
            self.pair_off[m + 1] = self.pair_off[m] + t.slots
        self.dof = np.full((n_steps + 1, 2 * n), np.nan)
        self.mesh = np.full((n_steps + 1, 4 * nm), np.nan)
        self.pair = np.full((n_steps + 1, int(self.pair_off[-1])), np.nan)
        self.spring = np.full((n_steps + 1, len(model.spring_names)), np.nan)

    def row(self, ref: "_Reference", i: int, tr) -> None:
        """Row ``i`` from the reference's state (motor angle ``ref.psi``, state ``ref.y``) with the
        table rows of the reference torque ``tr``."""
        model, mp, psi, y = ref.model, ref.mp, ref.psi, ref.y
        g = model.g
        for d in range(model.n_dof):
            self.dof[i, 2 * d] = g[d] * psi + _q(y, d)
            self.dof[i, 2 * d + 1] = g[d] * y[1] + _qd(y, d)
        for m in range(len(model.mesh_names)):
            th, om, x, v = _local(mp, m, y)
            th = mp.aref[m] * psi + mp.phase[m] + (th - mp.aref[m] * y[0])
            F, st, kk = pair_forces(th, om, x, v, ref.rows_for(m, tr), ref.pars[m][4], ref.pars[m][5])
            self.pair[i, self.pair_off[m]:self.pair_off[m + 1]] = F
            self.mesh[i, 4 * m:4 * m + 4] = (x, v, F.sum(), kk[st != 0].sum())
        self.spring[i] = ref.spring_forces(y)


class _Reference:
    """The reference's integration of one run: the table rows per mesh and reference torque, the
    equations of motion (:meth:`deriv`), the tolerances and step limits (:meth:`set_scales`), and the
    state -- motor angle ``psi`` at the segment start, state ``y`` relative to it, each mesh's table
    piece -- carried through the segments of each communication step (:meth:`step`)."""

    def __init__(self, model: PlanetaryModel, acc: ReferenceAccuracy):
        self.model, self.acc = model, acc
        nm = len(model.mesh_names)
        self.mp = _Maps(model)
        self.pars = [(1.0, 1.0, 1.0, 1.0, float(model.mesh_c[m]), model.mesh_damping_model[m]) for m in range(nm)]
        self.frames = [(int(ia), int(ib), float(R0), float(gf))
                       for (ia, ib), (R0, gf) in zip(model.frame_idx, model.frame_par)]
        self.cache = {}
        self.pieces = [None] * nm
        self.prev = [None] * nm
        self.n_seg = self.n_ev = self.nfev = 0
        self.first_step = None
        self.psi, self.y = 0.0, None

    def rows_for(self, m: int, tr) -> TableRows:
        """The table rows of mesh ``m`` at the motor-side reference torque ``tr`` (kept)."""
        t = self.model.mesh_tables[m]
        tq = abs(float(tr) * float(self.model.mesh_torque_per_ref[m]))
        key = (m, tq if t.n_torque > 1 else 0.0)
        if key not in self.cache:
            self.cache[key] = TableRows(t, key[1])
        return self.cache[key]

    def set_scales(self, t_ref, y0, speed_rad_s: float) -> None:
        """The largest step ``h_cap``, the look-ahead ``delta`` of the mode choice (from the highest
        natural frequency of the linearisation at every mesh's largest stiffness) and the absolute
        tolerance per state from physical scales (angle: the shortest mesh period; speed; deflection:
        the largest of the static deflection, backlash and error range, over the DOF's lever arm)."""
        model, acc, mp = self.model, self.acc, self.mp
        n, nm = model.n_dof, len(model.mesh_names)
        kmax = [float(np.max(t.k_N_per_m.sum(axis=1))) for t in model.mesh_tables]
        Mm, Km, _ = model.linearisation(float(t_ref[0]), mesh_stiffness_N_per_m=kmax)
        w_max = math.sqrt(max(float(np.max(scipy.linalg.eigh(Km, Mm, eigvals_only=True))), 1e-300))
        self.h_cap = 2.0 * math.pi / w_max / float(acc.steps_per_period)
        self.delta = 1e-9 * 2.0 * math.pi / w_max
        xs = []
        for m, t in enumerate(model.mesh_tables):
            fm = float(np.max(np.abs(t_ref))) * abs(float(model.mesh_torque_per_ref[m])) / float(t.base_radius_pinion_m)
            xs.append(max(fm / float(t.k_mean_N_per_m), float(np.max(t.backlash_half_m)), float(np.ptp(t.e_m)), 1e-9))
        xscale = max(xs)
        scale = np.empty(2 * n)
        psi_s = min(float(t.mesh_period_rad) / max(abs(mp.aref[m]), 1e-12) for m, t in enumerate(model.mesh_tables))
        scale[0], scale[1] = psi_s, max(abs(speed_rad_s), 1.0)
        for d in range(1, n):
            arms = [abs(c) for m_ in range(nm) for dd, c in mp.x[m_] if dd == d]
            r = min(arms) if (arms and model.dof_kind[d] == "rot") else 1.0
            qs = max(xscale / max(r, 1e-12), abs(float(y0[2 * d])), 1e-15)
            scale[2 * d], scale[2 * d + 1] = qs, qs * w_max
        self.atol = acc.rtol * acc.atol_scale * scale

    def spring_forces(self, y):
        model = self.model
        return [model.spring_k[s] * sum(c * _q(y, d) for d, c in ent)
                + model.spring_c[s] * sum(c * _qd(y, d) for d, c in ent) for s, ent in enumerate(self.mp.s)]

    def deriv(self, y, forces, T1, T2):
        """d/dt of the state (docs/planetary.md "Model"): springs and mesh forces ``forces`` as
        generalised forces, the reference's acceleration from the balance of the generalised
        momentum, the turning frames' inertial terms."""
        model, mp = self.model, self.mp
        n, g, mass, lb = model.n_dof, model.g, model.mass, model.load_dof
        Q = np.zeros(n)
        for s, f in enumerate(self.spring_forces(y)):
            for d, c in mp.s[s]:
                Q[d] -= c * f
        for m in range(len(model.mesh_names)):
            for d, c in mp.x[m]:
                Q[d] -= c * forces[m]
        sg = float(np.dot(g[1:], Q[1:]))
        for ia, ib, R0, gf in self.frames:
            sg += gf * ((R0 + y[2 * ia]) * Q[ib] - y[2 * ib] * Q[ia])
        ext0 = T1 - (T2 if lb == 0 else 0.0)
        if lb != 0:
            Q[lb] -= T2
        a0 = (ext0 - sg) / mass[0]
        dy = np.empty(2 * n)
        dy[0], dy[1] = y[1], a0
        dy[2::2] = y[3::2]
        dy[3::2] = Q[1:] / mass[1:] - g[1:] * a0
        for ia, ib, R0, gf in self.frames:
            Om, Od = gf * y[1], gf * a0
            qa, qb, va, vb = y[2 * ia], y[2 * ib], y[2 * ia + 1], y[2 * ib + 1]
            dy[2 * ia + 1] += 2.0 * Om * vb + Od * qb + Om * Om * (R0 + qa)
            dy[2 * ib + 1] += -2.0 * Om * va - Od * (R0 + qa) + Om * Om * qb
        return dy

    def step(self, t: float, t_end: float, T1: float, T2: float, tr) -> bool:
        """One communication step [t, t_end] at motor torque T1 and load torque T2 (the table rows of
        ``tr``): each mesh's piece where its rows changed, then segments from event to event until
        t_end (:meth:`segment`).  False where the state diverged."""
        mp, nm = self.mp, len(self.model.mesh_names)
        rows = [self.rows_for(m, tr) for m in range(nm)]
        for m in range(nm):
            if rows[m] is not self.prev[m] or self.pieces[m] is None:
                th, om, _, _ = _local(mp, m, self.y)
                self.pieces[m] = rows[m].piece_of(mp.aref[m] * self.psi + mp.phase[m] + th, om)
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
                    raise RuntimeError(f"planetary reference: no progress at t = {t!r} s (mode chattering)")
            t = t_new
            if not (np.all(np.isfinite(self.y)) and math.isfinite(self.psi)):
                return False
            if self.n_seg > self.acc.max_segments:
                raise RuntimeError(f"planetary reference: more than max_segments={self.acc.max_segments} segments")
        return True

    def segment(self, rows, span, T1, T2, forced):
        """One segment from ``span`` = (t, t_end): every mesh on its piece with the contact and damping
        modes read a little ahead along the field (``forced``: the mode of the pair whose indicator
        ended the last segment), integrated by solve_ivp to the first event of any mesh or to t_end.
        Returns (time reached, the pair mode to force next, an event ended it) or None where solve_ivp
        failed."""
        model, acc, mp = self.model, self.acc, self.mp
        nm, y = len(model.mesh_names), self.y
        t, t_end = span
        segs = [TableSegment(rows[m], self.pieces[m], mp.aref[m] * self.psi + mp.phase[m], T1, T2, self.pars[m])
                for m in range(nm)]
        gen = [segs[m].force_general(_local(mp, m, y)) for m in range(nm)]
        ya = y + self.delta * self.deriv(y, gen, T1, T2)
        modes = [segs[m].mode_from(_local(mp, m, ya), forced[1] if forced and forced[0] == m else None)
                 for m in range(nm)]
        evs = _events(mp, segs, modes)
        calls = [0]

        def rhs(tt, yy):
            calls[0] += 1
            return self.deriv(yy, [segs[m].force(_local(mp, m, yy), modes[m]) for m in range(nm)], T1, T2)

        cap = self.h_cap
        for m in range(nm):
            if segs[m].node_hi is not None:
                om = abs(_local(mp, m, y)[1])
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
        forced, tag = None, None
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
        if tag is not None:
            self._cross_together(rows, tag)
        return t_new, forced, sol.status == 1

    def _cross_together(self, rows, tag) -> None:
        """Planets meshing in phase reach their piece ends together: every mesh standing on its
        piece end crosses with the located event (gearfmu.gearbox.reference.cross_piece_ends)."""
        mp = self.mp
        at = []
        for mm in range(len(self.model.mesh_names)):
            th, om, _, _ = _local(mp, mm, self.y)
            at.append(((mp.aref[mm] * self.psi + mp.phase[mm] + th) / rows[mm].dphi, om))
        cross_piece_ends(self.pieces, rows, at, tag[0] if tag[1] == "node" else None)


def _events(mp: _Maps, segs, modes):
    """The terminal solve_ivp events of a segment, each with its tag (mesh, kind, ...): every mesh's
    piece nodes and pair indicators in the modes ``modes``."""
    evs = []
    for m, seg in enumerate(segs):
        for fn, tag in seg.events(modes[m]):
            ev = (lambda fn_, m_: (lambda tt, yy: fn_(tt, _local(mp, m_, yy))))(fn, m)
            ev.terminal = True
            ev.direction = fn.direction
            evs.append((ev, (m,) + tuple(tag)))
    return evs
