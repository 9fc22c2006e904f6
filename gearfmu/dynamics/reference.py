"""Event-located reference integrator of the dynamic model (tests and benchmarks only).

What it solves
--------------
The two-inertia multi-pair model of docs/model.md (Xu et al. 2022 eq 1-6, the
contract of the native solver and the FMU kernel), written here again in plain
Python from that page -- it does not call :mod:`gearfmu.dynamics.native`'s kernel --
and integrated with scipy's ``solve_ivp`` (DOP853 by default, rtol 1e-10) so
that no integrator setting of this project is tuned against it.

Why it is tight
---------------
The right-hand side of docs/model.md is smooth only piecewise:

* every tooth pair j switches between back flank, separated and drive flank
  where its deflection ``d_j = x - e_j`` crosses ``-b_j`` and ``+b_j``
  (Xu et al. 2022 eq 6, the dead-zone kinks);
* the ``elastobacklash`` damping law switches branch where the damping force
  ``fd`` crosses ``+fc`` and ``-fc`` (the clamp of docs/model.md);
* the tables are piecewise-linear in the pinion angle: k, e, b have kinks at
  grid nodes and the meshing-error rate ``de/dt = (de/dphi) omega1`` jumps there;
* the inputs change at communication-step boundaries.

Inside one *segment* (fixed table piece between two kink nodes, fixed contact
state and damping branch of every pair, fixed inputs) the right-hand side is a
polynomial in the state, so DOP853 keeps its order.  Each segment integrates
that smooth field and stops at the first switch, located as a terminal
``solve_ivp`` event (scipy's ``brentq`` on the dense output, xtol 4 eps); the
next segment starts there with the new state of the switching pair.  Table
nodes where the interpolant has no kink (collinear neighbours, e.g. the flat
parts of a rectangular wave) are not restarts.

Choices (not in the papers)
---------------------------
* Mode after a switch: the indicator that fired takes the side it crossed to;
  all other indicators are read at ``y + delta*f(y)`` (delta = 1e-9 of the
  shortest natural period), so simultaneous switches are all taken at once and
  a pair starting exactly on a boundary gets the side it is moving to.
* A kink node is a node whose second difference of k, e or b exceeds 1e-13 of
  that array's largest magnitude (any slot); collinear nodes are merged.
* Initial ``x(0)``: the *leftmost* root of the monotone piecewise-linear
  ``g(x) = sum_j fc_j(x) - F_m`` (the point docs/model.md's 200 bisections
  converge to), found exactly from the breakpoints ``e_j +- b_j``.
* ``atol`` per state: rtol times a scale -- pinion angle: one mesh period;
  pinion speed: |start speed| (at least 1 rad/s); x: the largest of the static
  deflection F_m/k_mean, the backlash and the error range (at least 1e-9 m);
  v: that times omega_n = sqrt(k_mean/m_e).
* The pinion angle is integrated relative to the segment start (its base is a
  Python float), so its absolute precision does not decay with the angle turned.

Public API
----------
``simulate_reference(tables, settings, *, pinion_torque_Nm, ..., accuracy)``
takes the settings and arguments of :func:`gearfmu.dynamics.native.simulate` (its step bound and
integrator unused; checked by the same :class:`gearfmu.common.settings.RunSettings` and
:func:`gearfmu.dynamics.native.run_inputs`) plus its accuracy, a :class:`ReferenceAccuracy`
(``rtol``, ``atol_scale``, ``method``, ``steps_per_period``, ``max_segments``; each also a
keyword; the gearbox reference takes the same type) (tables with a temperature axis: one constant
``bulk_temperature_C``, the slice ``tables.at_temperature`` gives), and returns a
:class:`gearfmu.dynamics.native.SimResult` (same arrays at the communication instants, the
derived outputs by the same rule;
``step_s`` is 0, ``substeps`` the number of segments, ``info`` counts segments,
events and right-hand-side calls).  The gearbox reference (:mod:`gearfmu.gearbox.reference`)
takes its per-mesh pieces from here: :class:`TableRows` (the tables at one torque, kink nodes,
zone lines), :class:`TableSegment` (one piece, its modes, right-hand side and events) and
:func:`pair_forces` (the per-pair forces of a state).
"""
from __future__ import annotations

import bisect
import math
import time as _time
from dataclasses import dataclass, replace
from dataclasses import fields as dataclass_fields
from typing import Optional

import numpy as np

from ..common.progress import progress_bar
from ..tables.mesh_tables import MeshTables
from ..common.settings import SOLVER_ARGUMENTS, RunSettings, checked
from .native import (InputLike, NativeInputError, SimResult, _at_temperature, _finite, derived_outputs,
                     resolve_settings, run_inputs, settings_changes, start_state)

__all__ = ["ReferenceInputError", "ReferenceAccuracy", "ACCURACY_FIELDS", "reference_accuracy", "simulate_reference",
           "equilibrium_dte_exact_m", "kink_nodes", "TableRows", "TableSegment", "pair_forces"]

KINK_REL_TOL = 1e-13


class ReferenceInputError(ValueError):
    """Bad argument to the reference integrator; the message names the argument."""


class TableRows:
    """Tables at one pinion torque: K, E, B (P, N) on the phi grid, and the kink nodes."""

    def __init__(self, tables: MeshTables, t1: float):
        tq = np.asarray(tables.torque_Nm, dtype=float)
        k = np.asarray(tables.k_N_per_m, dtype=float)
        e = np.asarray(tables.e_m, dtype=float)
        if len(tq) == 1:
            self.K, self.E = k[0].copy(), e[0].copy()
        else:  # docs/model.md: Tq = clamp(T1), linear between bracketing rows
            q = min(max(t1, tq[0]), tq[-1])
            i = int(np.searchsorted(tq, q, side="right") - 1)
            i = min(max(i, 0), len(tq) - 2)
            w = (q - tq[i]) / (tq[i + 1] - tq[i])
            self.K = k[i] + w * (k[i + 1] - k[i])
            self.E = e[i] + w * (e[i + 1] - e[i])
        self.B = np.asarray(tables.backlash_half_m, dtype=float).copy()
        self.P, self.N = self.K.shape
        self.dphi = float(tables.phi_period_rad) / self.N
        self.zones = _zones(tables)
        kinks = kink_nodes(self.K, self.E, self.B)
        if self.zones is not None:
            kinks = [float(i) for i in kinks]  # the contact-zone edges are piece ends too (docs/model.md)
            span = self.zones[1]
            for starts in self.zones[0]:
                for s0 in starts:
                    for q in (s0, math.fmod(s0 + span, self.N)):
                        near = round(q)
                        kinks.append(float(near) % self.N if abs(q - near) < 1e-9 else q)
            kinks = sorted(set(kinks))
        self.kinks = kinks
        self.key = (float(self.K.sum()), float(self.E.sum()))

    def coeffs(self, j: int, u: float):
        """The straight line of slot j's k, e, b at position u (node units, unwrapped) by the
        rule of docs/model.md "Contact-zone edges": ((kA, kB), (eA, eB), (bA, bB), base, inz),
        value(u') = A + (u' - base)(B - A); inz False: outside the contact zone, k = 0.  Without
        zone edges the line of the cell holding u."""
        N = self.N
        c = math.floor(u)
        base = c
        inz = True
        if self.zones is not None:
            starts, span = self.zones
            r = u - N * math.floor(u / N)
            inz = False
            for s0 in starts[j]:
                d = (r - s0) % N
                if d < span:
                    inz = True
                    start = u - d
                    end = start + span
                    if c < end <= c + 1:      # the zone ends in this cell: the line of the cell before
                        base = c - 1
                    elif c < start < c + 1:   # it starts in this cell: the line of the cell after
                        base = c + 1
                    break
        i0 = int(base - N * math.floor(base / N))
        i1 = 0 if i0 + 1 == N else i0 + 1
        return ((self.K[j, i0], self.K[j, i1]), (self.E[j, i0], self.E[j, i1]), (self.B[j, i0], self.B[j, i1]),
                base, inz)

    def values_at(self, u: float):
        """k, e, de/dphi (per node unit), b of every slot at position u (node units)."""
        out = np.zeros((4, self.P))
        for j in range(self.P):
            (ka, kb), (ea, eb), (ba, bb), base, inz = self.coeffs(j, u)
            w = u - base
            k = ka + w * (kb - ka)
            out[0, j] = max(k, 0.0) if inz else 0.0
            out[1, j] = ea + w * (eb - ea)
            out[2, j] = eb - ea
            out[3, j] = ba + w * (bb - ba)
        return out

    def piece_of(self, theta: float, omega: float):
        """(m_lo, m_hi) unwrapped kink nodes (and zone edges) bracketing theta (None if none)."""
        ks = self.kinks
        if len(ks) == 0:
            return None
        N = self.N
        u = theta / self.dphi
        m = math.floor(u)
        if self.zones is not None:  # pieces end at nodes and zone edges (floats)
            m = float(round(u)) if abs(u - round(u)) < 1e-9 else u
            q0, r0 = divmod(m, N)
            i = bisect.bisect_right(ks, r0 + 1e-9) - 1
            if i >= 0 and abs(ks[i] - r0) <= 1e-9:  # on a piece end: take the side we move to
                m = q0 * N + ks[i] if omega >= 0 else q0 * N + ks[i] - 1e-6
        elif abs(u - round(u)) < 1e-9:  # on a node: take the side we move to
            m = int(round(u)) if omega >= 0 else int(round(u)) - 1
        q, r = divmod(m, N)
        i = bisect.bisect_right(ks, r) - 1
        if i < 0:
            lo = (q - 1) * N + ks[-1]
        else:
            lo = q * N + ks[i]
        return lo, self.next_kink(lo)

    def next_kink(self, m: int) -> int:
        ks, N = self.kinks, self.N
        q, r = divmod(m, N)
        i = bisect.bisect_right(ks, r + 1e-9) if self.zones is not None else bisect.bisect_right(ks, r)
        return q * N + ks[i] if i < len(ks) else (q + 1) * N + ks[0]

    def prev_kink(self, m: int) -> int:
        ks, N = self.kinks, self.N
        q, r = divmod(m, N)
        i = (bisect.bisect_left(ks, r - 1e-9) if self.zones is not None else bisect.bisect_left(ks, r)) - 1
        return q * N + ks[i] if i >= 0 else (q - 1) * N + ks[-1]


def _zones(tables: MeshTables):
    """(starts, span): per slot the meshing-in positions of its pairs in node units (in
    [0, N)) and the zone length in node units, from the tables' engagement angles (pair n,
    slot n % P, is in its zone for n T + in <= phi < n T + out); None without the angles or
    for a zone shorter than 3 cells (the plain lookup, docs/model.md "Contact-zone edges")."""
    if tables.engagement_in_rad is None:
        return None
    N = tables.n_phi
    inv = N / float(tables.phi_period_rad)
    span = (float(tables.engagement_out_rad) - float(tables.engagement_in_rad)) * inv
    if span < 3.0:
        return None
    n_mesh = int(round(float(tables.phi_period_rad) / float(tables.mesh_period_rad)))
    starts = [[] for _ in range(tables.slots)]
    for m in range(n_mesh):
        starts[m % tables.slots].append(math.fmod(m * (N / n_mesh) + float(tables.engagement_in_rad) * inv, N) % N)
    return starts, span


def kink_nodes(K, E, B) -> list:
    """Grid nodes where the periodic piecewise-linear interpolant of any of
    k, e, b (arrays (P, N)) changes slope, as a sorted list of node indices.

    A node is a kink when the second difference of an array at that node
    exceeds 1e-13 of the array's largest magnitude (choice; collinear nodes
    are merged into one linear piece)."""
    mask = np.zeros(np.shape(K)[1], dtype=bool)
    for A in (K, E, B):
        A = np.asarray(A, dtype=float)
        scale = float(np.max(np.abs(A))) if A.size else 0.0
        if scale == 0.0:
            continue
        d2 = np.roll(A, -1, axis=1) - 2.0 * A + np.roll(A, 1, axis=1)
        mask |= np.any(np.abs(d2) > KINK_REL_TOL * scale, axis=0)
    return [int(i) for i in np.nonzero(mask)[0]]


def equilibrium_dte_exact_m(K, E, B, fm: float) -> float:
    """Leftmost root of g(x) = sum_{k_j>0} fc_j(x) - F_m for one angle (arrays (P,)).

    g is piecewise linear and non-decreasing with breakpoints e_j +- b_j; the
    root is found exactly from the breakpoints (no iteration).  Returns nan when
    no slot has k > 0."""
    K = np.asarray(K, float)
    sel = K > 0
    if not np.any(sel):
        return float("nan")
    k, e, b = K[sel], np.asarray(E, float)[sel], np.asarray(B, float)[sel]

    def g(x):
        d = x - e
        fc = np.where(d > b, k * (d - b), np.where(d < -b, k * (d + b), 0.0))
        return float(fc.sum()) - fm

    S = float(k.sum())
    pts = np.unique(np.concatenate([e - b, e + b]))
    gv = [g(p) for p in pts]
    if gv[0] >= 0.0:
        return float(pts[0] - gv[0] / S)  # left ray: every pair on the back flank, slope S
    for i in range(1, len(pts)):
        if gv[i] >= 0.0:
            g0, g1 = gv[i - 1], gv[i]
            return float(pts[i - 1] + (0.0 - g0) * (pts[i] - pts[i - 1]) / (g1 - g0))
    return float(pts[-1] - gv[-1] / S)  # right ray: every pair on the drive flank


def _pair_force(k, d, b, fd, model):
    """The per-pair force law of docs/model.md at stiffness ``k``, deflection ``d = x - e``,
    half backlash ``b`` and damping force ``fd = c (v - de/dt)``: (F_j in N, contact side
    +1 drive flank, -1 back flank, 0 separated)."""
    if d > b:
        fc, side = k * (d - b), 1
    elif d < -b:
        fc, side = k * (d + b), -1
    else:
        fc, side = 0.0, 0
    if model == "elastobacklash":
        if side == 1:
            return max(0.0, fc + min(fc, fd)), side
        if side == -1:
            return min(0.0, fc + max(fc, fd)), side
        return 0.0, side
    return (fc + fd if k > 0.0 else 0.0), side


def pair_forces(theta, omega, x, v, rows: TableRows, c, model):
    """Per-pair forces (N), contact states and stiffnesses at one state, by the
    literal formulas of docs/model.md (lookup, force law): used for outputs."""
    N, dphi = rows.N, rows.dphi
    Phi = N * dphi
    phim = theta - Phi * math.floor(theta / Phi)
    s = phim / dphi
    i0 = int(math.floor(s))
    i0 = min(max(i0, 0), N - 1)
    w = s - i0
    i1 = 0 if i0 + 1 == N else i0 + 1
    F = np.zeros(rows.P)
    st = np.zeros(rows.P, dtype=int)
    kk = np.zeros(rows.P)
    if rows.zones is not None:  # docs/model.md "Contact-zone edges"
        vals = rows.values_at(s)
        for j in range(rows.P):
            k, e, de, b = vals[0, j], vals[1, j], vals[2, j] / dphi * omega, vals[3, j]
            f, s_ = _pair_force(k, x - e, b, c * (v - de), model)
            F[j], st[j], kk[j] = f, s_, k
        return F, st, kk
    for j in range(rows.P):
        k = rows.K[j, i0] + w * (rows.K[j, i1] - rows.K[j, i0])
        e = rows.E[j, i0] + w * (rows.E[j, i1] - rows.E[j, i0])
        b = rows.B[j, i0] + w * (rows.B[j, i1] - rows.B[j, i0])
        de = (rows.E[j, i1] - rows.E[j, i0]) / dphi * omega
        f, s_ = _pair_force(k, x - e, b, c * (v - de), model)
        F[j], st[j], kk[j] = f, s_, k
    return F, st, kk


# -------------------------------------------------------------- segments
class TableSegment:
    """One table piece: linear k, e, b per active pair in theta (relative to the
    piece start), the mode of every active pair, the smooth RHS and the events."""

    def __init__(self, rows: TableRows, piece, theta_base, T1, T2, par):
        self.rows, self.piece, self.theta_base = rows, piece, theta_base
        self.T1, self.T2 = T1, T2
        self.rb1, self.rb2, self.i1, self.i2, self.c, self.model = par
        if piece is None:
            ia, ib, theta_a = 0, 0, 0.0
            slope_ok = False
        else:
            ia, ib = piece[0] % rows.N, piece[1] % rows.N
            theta_a = piece[0] * rows.dphi
            slope_ok = True
        self.off = theta_base - theta_a  # theta - theta_a = off + theta_rel
        ia1 = (ia + 1) % rows.N
        pairs = []
        if piece is not None and rows.zones is not None:
            ia = ia1 = None  # the lines of docs/model.md "Contact-zone edges" (TableRows.coeffs)
            umid = 0.5 * (piece[0] + piece[1])
            for j in range(rows.P):
                (ka, kb), (ea, eb), (ba, bb), base, inz = rows.coeffs(j, umid)
                w0, w1 = piece[0] - base, piece[1] - base
                if not inz or max(ka + w0 * (kb - ka), ka + w1 * (kb - ka)) <= 0.0:
                    continue
                pairs.append((j, ka + w0 * (kb - ka), (kb - ka) / rows.dphi, ea + w0 * (eb - ea),
                              (eb - ea) / rows.dphi, ba + w0 * (bb - ba), (bb - ba) / rows.dphi))
        for j in range(rows.P if ia is not None else 0):
            k0, e0, b0 = rows.K[j, ia], rows.E[j, ia], rows.B[j, ia]
            if slope_ok:
                ks = (rows.K[j, ia1] - k0) / rows.dphi
                es = (rows.E[j, ia1] - e0) / rows.dphi
                bs = (rows.B[j, ia1] - b0) / rows.dphi
            else:
                ks = es = bs = 0.0
            if max(k0, rows.K[j, ib]) > 0.0:  # k = 0 over the whole piece: no force at all
                pairs.append((j, k0, ks, e0, es, b0, bs))
        self.pairs = pairs
        if piece is None:
            self.node_lo = self.node_hi = None
        else:
            self.node_lo = piece[0] * rows.dphi - theta_base
            self.node_hi = piece[1] * rows.dphi - theta_base
        self.nfev = 0

    # state of pair p at (theta_rel, omega, x, v)
    def _pair(self, p, th, om, x, v):
        j, k0, ks, e0, es, b0, bs = p
        u = self.off + th
        k = k0 + ks * u
        e = e0 + es * u
        b = b0 + bs * u
        d = x - e
        fd = self.c * (v - es * om)
        return k, d, b, fd

    def indicators(self, p, th, om, x, v, side):
        """h_hi = d - b, h_lo = d + b, u1 = fd - fc, u2 = fd + fc (fc on `side`)."""
        k, d, b, fd = self._pair(p, th, om, x, v)
        fc = k * (d - b) if side > 0 else (k * (d + b) if side < 0 else 0.0)
        return d - b, d + b, fd - fc, fd + fc

    def mode_from(self, y, forced=None):
        """Per active pair (side, alpha, beta): F_j = alpha*fc_j + beta*fd_j.

        ``forced`` = (pair position, indicator index, sign) overrides one sign."""
        th, om, x, v = y
        modes = []
        for ip, p in enumerate(self.pairs):
            hh, hl, _, _ = self.indicators(p, th, om, x, v, 0)
            sg = [hh, hl]
            if forced is not None and forced[0] == ip and forced[1] < 2:
                sg[forced[1]] = forced[2]
            side = 1 if sg[0] > 0 else (-1 if sg[1] < 0 else 0)
            if self.model == "contact_zone":
                modes.append((side, 1 if side != 0 else 0, 1))
                continue
            if side == 0:
                modes.append((0, 0, 0))
                continue
            _, _, u1, u2 = self.indicators(p, th, om, x, v, side)
            if forced is not None and forced[0] == ip and forced[1] >= 2:
                if forced[1] == 2:
                    u1 = forced[2]
                else:
                    u2 = forced[2]
            if side > 0:
                a = (side, 2, 0) if u1 >= 0 else ((side, 1, 1) if u2 >= 0 else (side, 0, 0))
            else:
                a = (side, 2, 0) if u1 <= 0 else ((side, 1, 1) if u2 <= 0 else (side, 0, 0))
            modes.append(a)
        return modes

    def force(self, y, modes):
        th, om, x, v = y
        F = 0.0
        for p, (side, al, be) in zip(self.pairs, modes):
            if al == 0 and be == 0:
                continue
            k, d, b, fd = self._pair(p, th, om, x, v)
            fc = k * (d - side * b) if side != 0 else 0.0
            F += al * fc + be * fd
        return F

    def force_general(self, y):
        """docs/model.md force law on this piece's linear tables (mode found on the fly)."""
        th, om, x, v = y
        F = 0.0
        for p in self.pairs:
            k, d, b, fd = self._pair(p, th, om, x, v)
            F += _pair_force(k, d, b, fd, self.model)[0]
        return F

    def deriv(self, y, F):
        T1, T2 = self.T1, self.T2
        acc1 = (T1 - self.rb1 * F) / self.i1
        return np.array([y[1], acc1, y[3], self.rb1 * acc1 - self.rb2 * (self.rb2 * F - T2) / self.i2])

    def rhs_factory(self, modes):
        def rhs(t, y):
            self.nfev += 1
            return self.deriv(y, self.force(y, modes))
        return rhs

    def events(self, modes):
        """Terminal events leaving the current mode: (callable, tag) list."""
        evs = []

        def make(fn, direction, tag):
            fn.terminal = True
            fn.direction = direction
            evs.append((fn, tag))

        if self.node_hi is not None:
            nh, nl = self.node_hi, self.node_lo
            make(lambda t, y: y[0] - nh, 1.0, ("node", +1))
            make(lambda t, y: y[0] - nl, -1.0, ("node", -1))
        for ip, (p, (side, al, be)) in enumerate(zip(self.pairs, modes)):
            def ind(idx, p=p, side=side):
                return lambda t, y: self.indicators(p, y[0], y[1], y[2], y[3], side)[idx]
            if side == 0:
                make(ind(0), 1.0, ("pair", ip, 0, +1))
                make(ind(1), -1.0, ("pair", ip, 1, -1))
                continue
            if side > 0:
                make(ind(0), -1.0, ("pair", ip, 0, -1))
            else:
                make(ind(1), 1.0, ("pair", ip, 1, +1))
            if self.model == "contact_zone":
                continue
            if (al, be) == (2, 0):
                d = -1.0 if side > 0 else 1.0
                make(ind(2), d, ("pair", ip, 2, int(d)))
            elif (al, be) == (1, 1):
                d = 1.0 if side > 0 else -1.0
                make(ind(2), d, ("pair", ip, 2, int(d)))
                make(ind(3), -d, ("pair", ip, 3, int(-d)))
            else:
                d = 1.0 if side > 0 else -1.0
                make(ind(3), d, ("pair", ip, 3, int(d)))
        return evs


# --------------------------------------------------------------- accuracy
@dataclass(frozen=True)
class ReferenceAccuracy:
    """How a reference integrates (this pair reference and :mod:`gearfmu.gearbox.reference`):
    solve_ivp's ``method`` and relative tolerance ``rtol`` (> 0), the absolute tolerance of each
    state rtol * ``atol_scale`` * its physical scale, the largest step the shortest natural period
    (the pair's at its largest total stiffness; the gearbox's linearisation with every mesh at its
    largest) over ``steps_per_period``, and at most ``max_segments`` segments.  Checked when made
    (ReferenceInputError naming the field)."""

    rtol: float = 1e-10
    atol_scale: float = 1.0
    method: str = "DOP853"
    steps_per_period: float = 64.0
    max_segments: int = 5_000_000

    def __post_init__(self):
        object.__setattr__(self, "rtol", _finite("rtol", self.rtol, positive=True, error=ReferenceInputError))


#: the field names of :class:`ReferenceAccuracy` (each also a keyword of the references)
ACCURACY_FIELDS = tuple(f.name for f in dataclass_fields(ReferenceAccuracy))


def reference_accuracy(accuracy: Optional[ReferenceAccuracy], fields: dict, error=ReferenceInputError,
                       function: str = "simulate_reference") -> ReferenceAccuracy:
    """``accuracy`` (None: the defaults) with the fields given as keywords (``fields``) in place,
    checked; ``error`` (the caller's ValueError class) names the field, or a keyword that is no
    field (not an argument of ``function``)."""
    if accuracy is None:
        accuracy = ReferenceAccuracy()
    elif not isinstance(accuracy, ReferenceAccuracy):
        raise error(f"accuracy: expected ReferenceAccuracy, got {type(accuracy).__name__}")
    unknown = sorted(set(fields) - set(ACCURACY_FIELDS))
    if unknown:
        raise error(f"{unknown[0]}: not an argument of {function}")
    try:
        return replace(accuracy, **fields) if fields else accuracy
    except ReferenceInputError as exc:
        if error is ReferenceInputError:
            raise
        raise error(str(exc)) from None


# ------------------------------------------------------------------- main
def _temperature_slice(tables: MeshTables, bulk_temperature_C) -> MeshTables:
    """The single-temperature tables the reference runs on (docs/model.md "Temperature axis")."""
    if not tables.has_temperature_axis:
        if bulk_temperature_C is not None:
            raise ReferenceInputError("bulk_temperature_C: the tables have no temperature axis")
        return tables
    try:
        return _at_temperature(tables, tables.default_temperature_C if bulk_temperature_C is None
                               else bulk_temperature_C)
    except NativeInputError as exc:
        raise ReferenceInputError(str(exc)) from None


class _Rows:
    """The output rows of a run, one per communication instant: the state [theta1, omega1, x, v],
    the pair forces, the mesh force and the stiffness of the pairs in contact (NaN where the run
    did not reach)."""

    def __init__(self, n: int, slots: int):
        self.state = np.full((n, 4), np.nan)
        self.pair = np.full((n, slots), np.nan)
        self.force = np.full(n, np.nan)
        self.stiff = np.full(n, np.nan)

    def write(self, i: int, y, rows: TableRows, c: float, model: str) -> None:
        """Row ``i`` of the state ``y``, its forces by the literal formulas (:func:`pair_forces`)."""
        F, st, kk = pair_forces(y[0], y[1], y[2], y[3], rows, c, model)
        self.state[i] = y
        self.pair[i] = F
        self.force[i] = F.sum()
        self.stiff[i] = kk[st != 0].sum()


class _PairReference:
    """The reference's integration of one run (module docstring): the table rows per torque, the
    damping, the tolerances and step limits (:meth:`set_scales`), and the state -- the pinion angle
    ``theta`` at the segment start, (omega1, x, v) ``y_rest``, the table ``piece`` -- carried through
    the segments of each communication step (:meth:`step`)."""

    def __init__(self, tables: MeshTables, s: RunSettings, acc: ReferenceAccuracy):
        self.tables, self.acc = tables, acc
        rb1, rb2 = float(tables.base_radius_pinion_m), float(tables.base_radius_gear_m)
        I1, I2 = float(tables.inertia_pinion_kgm2), float(tables.inertia_gear_kgm2)
        self.me = I1 * I2 / (I1 * rb2 ** 2 + I2 * rb1 ** 2)  # Xu et al. 2022 below eq 2
        self.km = float(tables.k_mean_N_per_m)
        self.c = 2.0 * s.damping_ratio * math.sqrt(self.km * self.me)  # docs/model.md, Xu et al. 2022 eq 7-9
        self.wn = math.sqrt(self.km / self.me)
        self.model = s.damping_model
        self.par = (rb1, rb2, I1, I2, self.c, self.model)
        self.rows_cache = {}
        self.piece = self.prev_rows = self.first_step = None
        self.n_seg = self.n_ev = self.nfev = 0
        self.theta, self.y_rest = 0.0, None

    def rows_for(self, t1) -> TableRows:
        """The table rows at pinion torque ``t1`` (kept)."""
        key = float(t1) if self.tables.n_torque > 1 else 0.0
        if key not in self.rows_cache:
            self.rows_cache[key] = TableRows(self.tables, key)
        return self.rows_cache[key]

    def initial_x(self, th0: float, t1: float, x_start) -> float:
        """``x_start``, or when None the exact leftmost root of the static force at the pinion angle
        ``th0`` under ``t1`` (module docstring; docs/model.md "Contact-zone edges" for the lines)."""
        if x_start is not None:
            return x_start
        r0 = self.rows_for(t1)
        rb1 = self.par[0]
        Phi = r0.N * r0.dphi
        phim = th0 - Phi * math.floor(th0 / Phi)
        u = phim / r0.dphi
        i0 = min(max(int(math.floor(u)), 0), r0.N - 1)
        w = u - i0
        i1 = (i0 + 1) % r0.N
        lerp = lambda A: A[:, i0] + w * (A[:, i1] - A[:, i0])
        if r0.zones is None:
            x0 = equilibrium_dte_exact_m(lerp(r0.K), lerp(r0.E), lerp(r0.B), t1 / rb1)
        else:
            vals = r0.values_at(u)
            x0 = equilibrium_dte_exact_m(vals[0], vals[1], vals[3], t1 / rb1)
        if not math.isfinite(x0):
            raise ReferenceInputError(f"pinion_angle_start_rad: no pair in contact at {th0!r}; give dte_start_m")
        return x0

    def set_scales(self, t1s, x0: float, w0: float) -> None:
        """The absolute tolerance per state (module docstring), the look-ahead ``delta`` of the mode
        choice and the largest step ``h_cap``: 1/steps_per_period of the shortest natural period
        (stiffest mesh), so an indicator cannot cross a boundary and come back inside one step
        unseen (events are detected by sign changes between steps)."""
        t, acc, wn = self.tables, self.acc, self.wn
        xs = max(abs(t1s).max() / self.par[0] / self.km, float(np.max(t.backlash_half_m)), float(np.ptp(t.e_m)),
                 abs(x0), 1e-9)
        scale = np.array([t.mesh_period_rad, max(abs(w0), 1.0), xs, xs * wn])
        self.atol = acc.rtol * acc.atol_scale * scale
        self.delta = 1e-9 * min(2 * math.pi / wn, t.mesh_period_rad / max(abs(w0), 1.0))
        wmax = math.sqrt(float(np.max(t.k_N_per_m.sum(axis=1))) / self.me)
        self.h_cap = 2.0 * math.pi / max(wmax, wn) / float(acc.steps_per_period)

    def seg_cap(self, seg: TableSegment, omega: float) -> float:
        """The largest step in ``seg``: ``h_cap``, and at most 16/steps_per_period of the time to
        cross the table piece, so short pieces (one-node ramps of k and e, where de/dt is large) are
        resolved too."""
        if seg.node_hi is None or omega == 0.0:
            return self.h_cap
        dur = (seg.node_hi - seg.node_lo) / abs(omega)
        return min(self.h_cap, dur * 16.0 / float(self.acc.steps_per_period))

    def step(self, span, T1: float, T2: float, rows: TableRows) -> bool:
        """One communication step ``span`` = (t, t_end) at torques T1, T2 on the table ``rows``: the
        piece where the rows changed, then segments from event to event until t_end
        (:meth:`segment`).  False where solve_ivp failed or the state turned non-finite."""
        t, t_end = span
        if rows is not self.prev_rows or self.piece is None:
            self.piece = rows.piece_of(self.theta, self.y_rest[0])
            self.prev_rows = rows
        forced = None
        zero_len = 0
        while t < t_end:
            done = self.segment(rows, (t, t_end), T1, T2, forced)
            if done is None:
                return False
            t_new, forced, event = done
            if event:
                zero_len = zero_len + 1 if t_new <= t else 0
                if zero_len > 50:
                    raise RuntimeError(f"reference: no progress at t = {t!r} s (mode chattering)")
            t = t_new if event else t_end
            if not np.all(np.isfinite(self.y_rest)) or not math.isfinite(self.theta):
                return False
            if self.n_seg > self.acc.max_segments:
                raise RuntimeError(f"reference: more than max_segments={self.acc.max_segments} segments")
        return True

    def segment(self, rows: TableRows, span, T1: float, T2: float, forced):
        """One segment from ``span`` = (t, t_end) on the current piece, the modes read a little
        ahead along the true field (``forced``: the mode of the pair whose indicator ended the last
        segment), integrated by solve_ivp to the first event or to t_end; the state moves there (on
        a node event the angle snaps onto the node and the piece moves on).  Returns (time reached,
        the pair mode to force next, an event ended it), None where solve_ivp failed."""
        t, t_end = span
        acc, y_rest = self.acc, self.y_rest
        seg = TableSegment(rows, self.piece, self.theta, T1, T2, self.par)
        y = np.array([0.0, y_rest[0], y_rest[1], y_rest[2]])
        ya = y + self.delta * seg.deriv(y, seg.force_general(y))
        modes = seg.mode_from(ya, forced)
        evs = seg.events(modes)
        from scipy.integrate import solve_ivp  # scipy.integrate: heavy, only where the reference runs

        sol = solve_ivp(seg.rhs_factory(modes), (t, t_end), y, method=acc.method, rtol=acc.rtol, atol=self.atol,
                        events=[e for e, _ in evs] or None, max_step=self.seg_cap(seg, y_rest[0]),
                        first_step=None if not self.first_step else min(self.first_step, t_end - t))
        self.n_seg += 1
        self.nfev += seg.nfev
        if sol.status == -1:
            return None
        if len(sol.t) >= 3:
            self.first_step = float(sol.t[-2] - sol.t[-3])
        t_new = float(sol.t[-1])
        yn = sol.y[:, -1]
        forced = None
        if sol.status == 1:  # an event: which one fired first
            self.n_ev += 1
            hit = [i for i, te in enumerate(sol.t_events) if len(te)]
            i = min(hit, key=lambda i: sol.t_events[i][0])
            tag = evs[i][1]
            t_new = float(sol.t_events[i][0])
            yn = sol.y_events[i][0]
            if tag[0] == "node":
                piece = self.piece
                if tag[1] > 0:
                    node, self.piece = piece[1], (piece[1], rows.next_kink(piece[1]))
                else:
                    node, self.piece = piece[0], (rows.prev_kink(piece[0]), piece[0])
                self.theta = node * rows.dphi  # snap onto the node
            else:
                self.theta = self.theta + float(yn[0])
                forced = (tag[1], tag[2], tag[3])
        else:
            self.theta = self.theta + float(yn[0])
        self.y_rest = np.array(yn[1:4], dtype=float)
        return t_new, forced, sol.status == 1


def simulate_reference(
    tables: MeshTables,
    settings: Optional[RunSettings] = None,
    *,
    pinion_torque_Nm: Optional[InputLike] = None,
    gear_torque_Nm: Optional[InputLike] = None,
    dte_start_m: Optional[float] = None,
    dte_rate_start_m_s: float = 0.0,
    bulk_temperature_C: Optional[float] = None,
    accuracy: Optional[ReferenceAccuracy] = None,
    progress: bool = False,
    **fields,
) -> SimResult:
    """Event-located solve_ivp reference of docs/model.md (two-inertia form).

    Same settings, arguments and input convention as :func:`gearfmu.dynamics.native.simulate`
    (its run-settings keywords :data:`gearfmu.dynamics.native.SETTINGS_KEYWORDS`; torques in N*m
    held over each communication step; ``gear_torque_Nm`` None = T1*Rb2/Rb1); ``max_step_s`` and
    ``integrator`` (and the settings' fields of the same names) are accepted and ignored (the
    reference chooses its steps).  ``accuracy``: a :class:`ReferenceAccuracy` (None: its
    defaults); each of its fields may be given as a keyword instead: ``rtol`` (solve_ivp rtol),
    ``atol_scale`` (multiplies the per-state absolute tolerances rtol*scale, see module
    docstring), ``method`` ("DOP853" or "Radau", "RK45", ...), ``steps_per_period`` (the largest
    step is the shortest natural period 2 pi/sqrt(max k_total/m_e) over this number, so that no
    contact or clamp indicator crosses and returns inside one step unseen), ``max_segments``.
    ``bulk_temperature_C`` (degC, one constant value; tables with a temperature axis
    only): the run uses ``tables.at_temperature`` (None: ``default_temperature_C``),
    the slice :func:`gearfmu.dynamics.native.simulate` runs on at that temperature.
    Steps: the checks, the initial state (:meth:`_PairReference.initial_x`), the scales of the
    tolerances and steps (:meth:`_PairReference.set_scales`), then per communication step the
    segments between events (:meth:`_PairReference.step`).
    Returns a :class:`gearfmu.dynamics.native.SimResult`; ``wall_s`` is the whole run.
    """
    acc_fields = {k: fields.pop(k) for k in ACCURACY_FIELDS if k in fields}
    changes = settings_changes("simulate_reference", fields)
    changes.pop("max_step_s", None)
    changes.pop("integrator", None)
    s = checked(settings, ReferenceInputError, RunSettings, SOLVER_ARGUMENTS, **changes)
    if not isinstance(tables, MeshTables):
        raise ReferenceInputError(f"tables: expected MeshTables, got {type(tables).__name__}")
    tables = _temperature_slice(tables, bulk_temperature_C)
    tables.validate()
    s = resolve_settings(tables, s)
    n_steps, t1s, t2s = run_inputs(tables, s, pinion_torque_Nm, gear_torque_Nm, error=ReferenceInputError)
    x_start, v0 = start_state(dte_start_m, dte_rate_start_m_s, error=ReferenceInputError)
    acc = reference_accuracy(accuracy, acc_fields)
    H, w0, th0 = s.output_interval_s, s.pinion_speed_start_rad_s, s.pinion_angle_start_rad
    ref = _PairReference(tables, s, acc)
    x0 = ref.initial_x(th0, t1s[0], x_start)
    ref.set_scales(t1s, x0, w0)
    out = _Rows(n_steps + 1, tables.slots)
    out.write(0, (th0, w0, x0, v0), ref.rows_for(t1s[0]), ref.c, ref.model)
    ref.theta, ref.y_rest = th0, np.array([w0, x0, v0])
    t_wall = _time.perf_counter()
    diverged = None
    for k in progress_bar(range(n_steps), "reference", progress, unit="step"):
        rows = ref.rows_for(t1s[k])
        if not ref.step((k * H, (k + 1) * H), t1s[k], t2s[k], rows):
            diverged = k
            break
        out.write(k + 1, (ref.theta, ref.y_rest[0], ref.y_rest[1], ref.y_rest[2]), rows, ref.c, ref.model)
    wall = _time.perf_counter() - t_wall
    info = {"form": "two-inertia (docs/model.md), event-located solve_ivp reference", "method": acc.method,
            "rtol": acc.rtol, "max_step_s": ref.h_cap, "atol": ref.atol.tolist(), "segments": ref.n_seg,
            "events": ref.n_ev, "rhs_calls": ref.nfev, "equivalent_mass_kg": ref.me}
    if diverged is not None:
        info["diverged_at_step"] = int(diverged)
    return SimResult(time_s=np.arange(n_steps + 1) * H, **derived_outputs(tables, out.state, out.pair, out.force),
                     mesh_force=out.force, pair_force=out.pair, mesh_stiffness=out.stiff, pinion_torque=t1s,
                     gear_torque=t2s, step_s=0.0, substeps=ref.n_seg, damping_Ns_per_m=ref.c, damping_model=ref.model,
                     wall_s=wall, info=info)
