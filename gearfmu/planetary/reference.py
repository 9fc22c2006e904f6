"""Event-located reference of the planetary drivetrain model (tests and benchmarks only).

The equations of docs/planetary.md "Model", written again in plain Python -- no numba kernel of
:mod:`gearfmu.planetary.kernels` or :mod:`gearfmu.dynamics` is called -- and integrated with scipy's
``solve_ivp`` (DOP853 by default, rtol 1e-10), every mesh the pair reference's table pieces and
per-pair force law (:mod:`gearfmu.dynamics.reference`: ``TableRows``, ``TableSegment``, ``pair_forces``), as the gearbox
reference does (gearfmu.gearbox.reference, whose choices carry over: segments inside which every
mesh keeps its table piece and pair modes, each ended by the first event of any mesh located as a
terminal ``solve_ivp`` event; modes after a switch read a little ahead along the field; ``atol`` per
state from physical scales; the largest step a fraction of the shortest natural period; the motor
angle integrated relative to the segment start).  The initial state is the model's quasi-static
state (:meth:`gearfmu.planetary.model.PlanetaryModel.static_state`).

``simulate_reference(model, ...)`` takes the arguments of :func:`gearfmu.planetary.native.simulate`
(without ``max_step_s`` and ``integrator``) plus ``rtol``, ``method``, ``steps_per_period`` and returns a
:class:`gearfmu.planetary.native.PlanetaryResult` with the same columns.
"""
from __future__ import annotations

import math
import time as _time
from typing import Optional

import numpy as np
import scipy.linalg
from scipy.integrate import solve_ivp

from ..common.progress import progress_bar
from ..common.settings import GearboxRunSettings
from ..dynamics.native import InputLike
from ..dynamics.reference import TableRows, TableSegment, pair_forces
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
                       initial_state=None, rtol: float = 1e-10, atol_scale: float = 1.0, method: str = "DOP853",
                       steps_per_period: float = 64.0, max_segments: int = 5_000_000,
                       progress: bool = False) -> PlanetaryResult:
    """Event-located solve_ivp reference (module docstring); settings and arguments as
    :func:`gearfmu.planetary.native.simulate` (its step bound and integrator unused), plus ``rtol``,
    ``atol_scale``, ``method`` and ``steps_per_period`` (the largest step: the shortest natural period
    of the linearisation with every mesh at its largest total stiffness, over this number).  ``wall_s``
    is the whole run."""
    rs = checked_settings(model, settings, stop_time_s=stop_time_s, output_interval_s=comm_step_s,
                          motor_speed_start_rad_s=motor_speed_start_rad_s, motor_angle_start_rad=motor_angle_start_rad)
    n_steps, t_in, t_out, t_ref, y_given = run_inputs(model, rs, motor_torque_Nm, load_torque_Nm, initial_state)
    if not (rtol > 0 and math.isfinite(rtol)):
        raise PlanetaryInputError(f"rtol: must be a positive number, got {rtol!r}")
    H = rs.output_interval_s
    n, nm = model.n_dof, len(model.mesh_names)
    mass, g = model.mass, model.g
    lb = model.load_dof
    mp = _Maps(model)
    pars = [(1.0, 1.0, 1.0, 1.0, float(model.mesh_c[m]), model.mesh_damping_model[m]) for m in range(nm)]
    frames = [(int(ia), int(ib), float(R0), float(gf)) for (ia, ib), (R0, gf) in zip(model.frame_idx,
                                                                                      model.frame_par)]
    cache = {}

    def rows_for(m, tr):
        t = model.mesh_tables[m]
        tq = abs(float(tr) * float(model.mesh_torque_per_ref[m]))
        key = (m, tq if t.n_torque > 1 else 0.0)
        if key not in cache:
            cache[key] = TableRows(t, key[1])
        return cache[key]

    y0 = model.static_state(float(t_ref[0]), rs.motor_speed_start_rad_s, rs.motor_angle_start_rad) \
        if y_given is None else y_given.copy()

    # ---- scales: tolerances, largest step, the look-ahead of the mode choice
    kmax = [float(np.max(t.k_N_per_m.sum(axis=1))) for t in model.mesh_tables]
    Mm, Km, _ = model.linearisation(float(t_ref[0]), mesh_stiffness_N_per_m=kmax)
    w_max = math.sqrt(max(float(np.max(scipy.linalg.eigh(Km, Mm, eigvals_only=True))), 1e-300))
    h_cap = 2.0 * math.pi / w_max / float(steps_per_period)
    delta = 1e-9 * 2.0 * math.pi / w_max
    xs = []
    for m, t in enumerate(model.mesh_tables):
        fm = float(np.max(np.abs(t_ref))) * abs(float(model.mesh_torque_per_ref[m])) / float(t.base_radius_pinion_m)
        xs.append(max(fm / float(t.k_mean_N_per_m), float(np.max(t.backlash_half_m)), float(np.ptp(t.e_m)), 1e-9))
    xscale = max(xs)
    scale = np.empty(2 * n)
    psi_s = min(float(t.mesh_period_rad) / max(abs(mp.aref[m]), 1e-12) for m, t in enumerate(model.mesh_tables))
    scale[0], scale[1] = psi_s, max(abs(rs.motor_speed_start_rad_s), 1.0)
    for d in range(1, n):
        if model.dof_kind[d] == "rot":
            r = min(abs(c) for m_ in range(nm) for dd, c in mp.x[m_] if dd == d) if any(
                dd == d for m_ in range(nm) for dd, _ in mp.x[m_]) else 1.0
            qs = max(xscale / max(r, 1e-12), abs(float(y0[2 * d])), 1e-15)
        else:
            qs = max(xscale, abs(float(y0[2 * d])), 1e-15)
        scale[2 * d], scale[2 * d + 1] = qs, qs * w_max
    atol = rtol * atol_scale * scale

    pair_off = np.zeros(nm + 1, dtype=np.int64)
    for m, t in enumerate(model.mesh_tables):
        pair_off[m + 1] = pair_off[m] + t.slots
    out_dof = np.full((n_steps + 1, 2 * n), np.nan)
    out_mesh = np.full((n_steps + 1, 4 * nm), np.nan)
    out_pair = np.full((n_steps + 1, int(pair_off[-1])), np.nan)
    out_spring = np.full((n_steps + 1, len(model.spring_names)), np.nan)

    def spring_forces(y):
        return [model.spring_k[s] * sum(c * _q(y, d) for d, c in ent)
                + model.spring_c[s] * sum(c * _qd(y, d) for d, c in ent) for s, ent in enumerate(mp.s)]

    def out_row(i, psi, y, tr):
        for d in range(n):
            out_dof[i, 2 * d] = g[d] * psi + _q(y, d)
            out_dof[i, 2 * d + 1] = g[d] * y[1] + _qd(y, d)
        for m in range(nm):
            th, om, x, v = _local(mp, m, y)
            th = mp.aref[m] * psi + mp.phase[m] + (th - mp.aref[m] * y[0])
            F, st, kk = pair_forces(th, om, x, v, rows_for(m, tr), pars[m][4], pars[m][5])
            out_pair[i, pair_off[m]:pair_off[m + 1]] = F
            out_mesh[i, 4 * m:4 * m + 4] = (x, v, F.sum(), kk[st != 0].sum())
        out_spring[i] = spring_forces(y)

    def deriv(y, forces, T1, T2):
        Q = np.zeros(n)
        for s, f in enumerate(spring_forces(y)):
            for d, c in mp.s[s]:
                Q[d] -= c * f
        for m in range(nm):
            for d, c in mp.x[m]:
                Q[d] -= c * forces[m]
        # the reference's acceleration from the balance of the generalised momentum
        sg = float(np.dot(g[1:], Q[1:]))
        for ia, ib, R0, gf in frames:
            sg += gf * ((R0 + y[2 * ia]) * Q[ib] - y[2 * ib] * Q[ia])
        ext0 = T1 - (T2 if lb == 0 else 0.0)
        if lb != 0:
            Q[lb] -= T2
        a0 = (ext0 - sg) / mass[0]
        dy = np.empty(2 * n)
        dy[0], dy[1] = y[1], a0
        dy[2::2] = y[3::2]
        dy[3::2] = Q[1:] / mass[1:] - g[1:] * a0
        for ia, ib, R0, gf in frames:
            Om, Od = gf * y[1], gf * a0
            qa, qb, va, vb = y[2 * ia], y[2 * ib], y[2 * ia + 1], y[2 * ib + 1]
            dy[2 * ia + 1] += 2.0 * Om * vb + Od * qb + Om * Om * (R0 + qa)
            dy[2 * ib + 1] += -2.0 * Om * va - Od * (R0 + qa) + Om * Om * qb
        return dy

    psi = float(y0[0])
    y = y0.copy()
    y[0] = 0.0
    out_row(0, psi, y, t_ref[0])
    pieces = [None] * nm
    prev = [None] * nm
    n_seg = n_ev = nfev = 0
    first_step = None
    diverged = None
    t_wall = _time.perf_counter()
    for k in progress_bar(range(n_steps), "planetary reference", progress, unit="step"):
        T1, T2 = float(t_in[k]), float(t_out[k])
        rows = [rows_for(m, t_ref[k]) for m in range(nm)]
        for m in range(nm):
            if rows[m] is not prev[m] or pieces[m] is None:
                th, om, _, _ = _local(mp, m, y)
                pieces[m] = rows[m].piece_of(mp.aref[m] * psi + mp.phase[m] + th, om)
                prev[m] = rows[m]
        t, t_end = k * H, (k + 1) * H
        forced = None
        zero_len = 0
        while t < t_end:
            segs = [TableSegment(rows[m], pieces[m], mp.aref[m] * psi + mp.phase[m], T1, T2, pars[m]) for m in range(nm)]
            gen = [segs[m].force_general(_local(mp, m, y)) for m in range(nm)]
            ya = y + delta * deriv(y, gen, T1, T2)
            modes = [segs[m].mode_from(_local(mp, m, ya), forced[1] if forced and forced[0] == m else None)
                     for m in range(nm)]
            evs = []
            for m in range(nm):
                for fn, tag in segs[m].events(modes[m]):
                    ev = (lambda fn_, m_: (lambda tt, yy: fn_(tt, _local(mp, m_, yy))))(fn, m)
                    ev.terminal = True
                    ev.direction = fn.direction
                    evs.append((ev, (m,) + tuple(tag)))
            calls = [0]

            def rhs(tt, yy):
                calls[0] += 1
                return deriv(yy, [segs[m].force(_local(mp, m, yy), modes[m]) for m in range(nm)], T1, T2)

            cap = h_cap
            for m in range(nm):
                if segs[m].node_hi is not None:
                    om = abs(_local(mp, m, y)[1])
                    if om > 0.0:
                        cap = min(cap, (segs[m].node_hi - segs[m].node_lo) / om * 16.0 / float(steps_per_period))
            sol = solve_ivp(rhs, (t, t_end), y, method=method, rtol=rtol, atol=atol,
                            events=[e for e, _ in evs] or None, max_step=cap,
                            first_step=None if not first_step else min(first_step, t_end - t))
            n_seg += 1
            nfev += calls[0]
            if sol.status == -1:
                diverged = k
                break
            if len(sol.t) >= 3:
                first_step = float(sol.t[-2] - sol.t[-3])
            forced = None
            if sol.status == 1:
                n_ev += 1
                hit = [i for i, te in enumerate(sol.t_events) if len(te)]
                i = min(hit, key=lambda i: sol.t_events[i][0])
                tag = evs[i][1]
                t_new = float(sol.t_events[i][0])
                yn = np.array(sol.y_events[i][0], dtype=float)
                m = tag[0]
                if tag[1] == "node":
                    r = rows[m]
                    pieces[m] = ((pieces[m][1], r.next_kink(pieces[m][1])) if tag[2] > 0
                                 else (r.prev_kink(pieces[m][0]), pieces[m][0]))
                else:
                    forced = (m, (tag[2], tag[3], tag[4]))
                zero_len = zero_len + 1 if t_new <= t else 0
                if zero_len > 50:
                    raise RuntimeError(f"planetary reference: no progress at t = {t!r} s (mode chattering)")
                t = t_new
            else:
                yn = np.array(sol.y[:, -1], dtype=float)
                t = t_end
            psi += float(yn[0])
            yn[0] = 0.0
            y = yn
            if not (np.all(np.isfinite(y)) and math.isfinite(psi)):
                diverged = k
                break
            if sol.status == 1:
                # meshes in phase reach their piece ends together; solve_ivp reports one event and
                # finds none at the start of the next segment: every mesh standing on the end of its
                # piece, moving out of it, crosses with the located one
                for mm in range(nm):
                    if pieces[mm] is None or (tag[1] == "node" and mm == tag[0]):
                        continue
                    th, om, _, _ = _local(mp, mm, y)
                    u = (mp.aref[mm] * psi + mp.phase[mm] + th) / rows[mm].dphi
                    lo, hi = pieces[mm]
                    if om > 0.0 and u >= hi - 1e-9:
                        pieces[mm] = (hi, rows[mm].next_kink(hi))
                    elif om < 0.0 and u <= lo + 1e-9:
                        pieces[mm] = (rows[mm].prev_kink(lo), lo)
            if n_seg > max_segments:
                raise RuntimeError(f"planetary reference: more than max_segments={max_segments} segments")
        if diverged is not None:
            break
        out_row(k + 1, psi, y, t_ref[k])
    wall = _time.perf_counter() - t_wall
    state = y.copy()
    state[0] = psi
    info = {"form": "planetary drivetrain (docs/planetary.md), event-located solve_ivp reference", "method": method,
            "rtol": rtol, "max_step_s": h_cap, "segments": n_seg, "events": n_ev, "rhs_calls": nfev,
            "completed_steps": n_steps if diverged is None else diverged}
    if diverged is not None:
        info["diverged_at_step"] = int(diverged)
    cols = columns(model, pair_off, out_dof, out_mesh, out_pair, out_spring, t_in, t_out)
    return PlanetaryResult(time_s=np.arange(n_steps + 1) * H, columns=cols, step_s=0.0, substeps=n_seg,
                           integrator=f"reference {method}", wall_s=wall, state=state, info=info)
