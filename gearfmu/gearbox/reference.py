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
:func:`gearfmu.gearbox.native.simulate` (without ``max_step_s`` and ``integrator``) plus ``rtol``, ``method``, ``steps_per_period`` and
returns a :class:`gearfmu.gearbox.native.GearboxResult` with the same columns.
"""
from __future__ import annotations

import math
import time as _time
from typing import Optional

import numpy as np
import scipy.linalg
from scipy.integrate import solve_ivp

from ..common.progress import progress_bar
from ..dynamics.reference import TableRows, TableSegment, equilibrium_dte_exact_m, pair_forces
from .model import GearboxModel
from ..common.settings import GearboxRunSettings
from .native import GearboxInputError, GearboxResult, InputLike, checked_settings, columns, run_inputs

__all__ = ["simulate_reference"]


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
                       initial_state=None, rtol: float = 1e-10, atol_scale: float = 1.0, method: str = "DOP853",
                       steps_per_period: float = 64.0, max_segments: int = 5_000_000,
                       progress: bool = False) -> GearboxResult:
    """Event-located solve_ivp reference of the gearbox model (module docstring); settings and
    arguments as :func:`gearfmu.gearbox.native.simulate` (its step bound and integrator unused),
    plus ``rtol`` (solve_ivp), ``atol_scale`` (times the per-state absolute tolerances rtol*scale),
    ``method`` and ``steps_per_period`` (the largest step is the shortest natural period of the
    linearisation with every mesh at its largest total stiffness, over this number).  ``wall_s`` is
    the whole run."""
    rs = checked_settings(model, settings, GearboxInputError, stop_time_s=stop_time_s, output_interval_s=comm_step_s,
                           motor_speed_start_rad_s=motor_speed_start_rad_s, motor_angle_start_rad=motor_angle_start_rad)
    n_steps, t_in, t_out, t_ref, y_given = run_inputs(model, rs, motor_torque_Nm, load_torque_Nm, initial_state)
    if not (rtol > 0 and math.isfinite(rtol)):
        raise GearboxInputError(f"rtol: must be a positive number, got {rtol!r}")
    H = rs.output_interval_s
    n, nm = model.n_bodies, len(model.meshes)
    I, g = model.inertia_kgm2, model.g
    lb = model.load_body
    on_path = [mesh.name in model.on_path for mesh in model.meshes]
    pars = [(model.mesh_rb_m[m, 0], model.mesh_rb_m[m, 1], 1.0, 1.0, float(model.mesh_c_Ns_per_m[m]),
             model.meshes[m].damping_model) for m in range(nm)]

    cache = {}

    def rows_for(m, tr):
        tq = float(tr / g[model.mesh_bodies[m, 0]]) if on_path[m] else 0.0
        key = (m, tq if model.meshes[m].tables.n_torque > 1 else 0.0)
        if key not in cache:
            cache[key] = TableRows(model.meshes[m].tables, key[1])
        return cache[key]

    # ---- initial state: walk the tree, each mesh at its exact static root
    if y_given is None:
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
            K, E, B = _lookup_values(rows_for(e, t_ref[0]), g[p] * rs.motor_angle_start_rad + u[p])
            x = equilibrium_dte_exact_m(K, E, B, tm[e] / model.mesh_rb_m[e, 0])
            if not math.isfinite(x):
                raise GearboxInputError(f"motor_angle_start_rad: no pair of mesh {model.meshes[e].name!r} in contact")
            u[q] = (model.mesh_rb_m[e, 0] * u[p] - x) / model.mesh_rb_m[e, 1]
        y0[2::2] = u[1:]
    else:
        y0 = y_given.copy()

    # ---- scales: tolerances, largest step, the look-ahead of the mode choice
    kmax = [float(np.max(m.tables.k_N_per_m.sum(axis=1))) for m in model.meshes]
    Mm, Km, _ = model.linearisation(float(t_ref[0]), mesh_stiffness_N_per_m=kmax)
    w_max = math.sqrt(max(float(np.max(scipy.linalg.eigh(Km, Mm, eigvals_only=True))), 1e-300))
    h_cap = 2.0 * math.pi / w_max / float(steps_per_period)
    delta = 1e-9 * 2.0 * math.pi / w_max
    xs = []
    for m, mesh in enumerate(model.meshes):
        t = mesh.tables
        fm = float(np.max(np.abs(t_ref))) / g[model.mesh_bodies[m, 0]] / model.mesh_rb_m[m, 0]
        xs.append(max(fm / float(t.k_mean_N_per_m), float(np.max(t.backlash_half_m)), float(np.ptp(t.e_m)), 1e-9)
                  / float(np.min(model.mesh_rb_m[m])))
    us = max(max(xs), float(np.max(np.abs(y0[2::2]))) if n > 1 else 0.0, 1e-12)
    psi_s = min(float(m.tables.mesh_period_rad) / g[model.mesh_bodies[i, 0]] for i, m in enumerate(model.meshes))
    scale = np.empty(2 * n)
    scale[0], scale[1] = psi_s, max(abs(rs.motor_speed_start_rad_s), 1.0)
    scale[2::2], scale[3::2] = us, us * w_max
    atol = rtol * atol_scale * scale

    # ---- outputs
    out_body = np.full((n_steps + 1, 2 * n), np.nan)
    out_mesh = np.full((n_steps + 1, 4 * nm), np.nan)
    pair_off = np.zeros(nm + 1, dtype=np.int64)
    for m, mesh in enumerate(model.meshes):
        pair_off[m + 1] = pair_off[m] + mesh.tables.slots
    out_pair = np.full((n_steps + 1, int(pair_off[-1])), np.nan)
    out_shaft = np.full((n_steps + 1, len(model.shafts)), np.nan)

    def out_row(i, psi, y, tr):
        for b in range(n):
            out_body[i, 2 * b] = g[b] * psi + (y[2 * b] if b > 0 else 0.0)
            out_body[i, 2 * b + 1] = g[b] * y[1] + (y[2 * b + 1] if b > 0 else 0.0)
        for m in range(nm):
            th, om, x, v = _local(model, m, y)
            th = g[model.mesh_bodies[m, 0]] * psi + (th - g[model.mesh_bodies[m, 0]] * y[0])
            F, st, kk = pair_forces(th, om, x, v, rows_for(m, tr), pars[m][4], pars[m][5])
            out_pair[i, pair_off[m]:pair_off[m + 1]] = F
            out_mesh[i, 4 * m:4 * m + 4] = (x, v, F.sum(), kk[st != 0].sum())
        for s in range(len(model.shafts)):
            a_, b_ = model.shaft_bodies[s]
            ua, ub = (y[2 * a_] if a_ > 0 else 0.0), (y[2 * b_] if b_ > 0 else 0.0)
            dua, dub = (y[2 * a_ + 1] if a_ > 0 else 0.0), (y[2 * b_ + 1] if b_ > 0 else 0.0)
            out_shaft[i, s] = model.shaft_k_Nm_per_rad[s] * (ua - ub) + model.shaft_c_Nms_per_rad[s] * (dua - dub)

    def deriv(y, forces, T1, T2):
        tau = np.zeros(n)
        tau[0] += T1
        tau[lb] -= T2
        for s in range(len(model.shafts)):
            a_, b_ = model.shaft_bodies[s]
            ua, ub = (y[2 * a_] if a_ > 0 else 0.0), (y[2 * b_] if b_ > 0 else 0.0)
            dua, dub = (y[2 * a_ + 1] if a_ > 0 else 0.0), (y[2 * b_ + 1] if b_ > 0 else 0.0)
            ts_ = model.shaft_k_Nm_per_rad[s] * (ua - ub) + model.shaft_c_Nms_per_rad[s] * (dua - dub)
            tau[a_] -= ts_
            tau[b_] += ts_
        for m in range(nm):
            p, q = model.mesh_bodies[m]
            tau[p] -= model.mesh_rb_m[m, 0] * forces[m]
            tau[q] += model.mesh_rb_m[m, 1] * forces[m]
        acc = tau / I
        dy = np.empty(2 * n)
        dy[0], dy[1] = y[1], acc[0]
        dy[2::2] = y[3::2]
        dy[3::2] = acc[1:] - g[1:] * acc[0]
        return dy

    psi = float(y0[0])          # the motor angle at the segment start; the state holds psi - psi_base
    y = y0.copy()
    y[0] = 0.0
    out_row(0, psi, y, t_ref[0])
    pieces = [None] * nm
    prev = [None] * nm
    n_seg = n_ev = nfev = 0
    first_step = None
    diverged = None
    t_wall = _time.perf_counter()
    for k in progress_bar(range(n_steps), "gearbox reference", progress, unit="step"):
        T1, T2 = float(t_in[k]), float(t_out[k])
        rows = [rows_for(m, t_ref[k]) for m in range(nm)]
        for m in range(nm):
            if rows[m] is not prev[m] or pieces[m] is None:
                th, om, _, _ = _local(model, m, y)
                pieces[m] = rows[m].piece_of(g[model.mesh_bodies[m, 0]] * psi + th, om)
                prev[m] = rows[m]
        t, t_end = k * H, (k + 1) * H
        forced = None
        zero_len = 0
        while t < t_end:
            segs = [TableSegment(rows[m], pieces[m], g[model.mesh_bodies[m, 0]] * psi, T1, T2, pars[m])
                    for m in range(nm)]
            gen = [segs[m].force_general(_local(model, m, y)) for m in range(nm)]
            ya = y + delta * deriv(y, gen, T1, T2)
            modes = [segs[m].mode_from(_local(model, m, ya), forced[1] if forced and forced[0] == m else None)
                     for m in range(nm)]
            evs = []
            for m in range(nm):
                for fn, tag in segs[m].events(modes[m]):
                    ev = (lambda fn_, m_: (lambda tt, yy: fn_(tt, _local(model, m_, yy))))(fn, m)
                    ev.terminal = True
                    ev.direction = fn.direction
                    evs.append((ev, (m,) + tuple(tag)))
            calls = [0]

            def rhs(tt, yy):
                calls[0] += 1
                return deriv(yy, [segs[m].force(_local(model, m, yy), modes[m]) for m in range(nm)], T1, T2)

            cap = h_cap
            for m in range(nm):
                if segs[m].node_hi is not None:
                    om = abs(_local(model, m, y)[1])
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
                    raise RuntimeError(f"gearbox reference: no progress at t = {t!r} s (mode chattering)")
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
            if n_seg > max_segments:
                raise RuntimeError(f"gearbox reference: more than max_segments={max_segments} segments")
        if diverged is not None:
            break
        out_row(k + 1, psi, y, t_ref[k])
    wall = _time.perf_counter() - t_wall
    state = y.copy()
    state[0] = psi
    info = {"form": "gearbox (docs/gearbox.md), event-located solve_ivp reference", "method": method, "rtol": rtol,
            "max_step_s": h_cap, "segments": n_seg, "events": n_ev, "rhs_calls": nfev,
            "completed_steps": n_steps if diverged is None else diverged}
    if diverged is not None:
        info["diverged_at_step"] = int(diverged)
    cols = columns(model, pair_off, out_body, out_mesh, out_pair, out_shaft, t_in, t_out)
    return GearboxResult(time_s=np.arange(n_steps + 1) * H, columns=cols, step_s=0.0, substeps=n_seg,
                         integrator=f"reference {method}", wall_s=wall, state=state, info=info)
