"""Time levels of the transient line-contact solver (:func:`.transient.solve_line_contact_transient`).

:class:`MovingSurfaces`: the composite roughness W(x, t) = z1(x - u1 t) + z2(x - u2 t) of two
surfaces whose height patterns move with them (Zhao et al. 2022 eq 3; docs/ehl_transient.md section 1).
:class:`TimeStepper`: the time levels on one :class:`.multigrid.FlatMultigrid` -- the rigid gap
X^2/2 + W at the level's time (ramped in for a smooth start), the time-derivative terms of the
scheme (characteristic, BDF2, BDF1), the warm start extrapolated from the last levels, the
relaxation settings in turn (the one that converged last first, each with its frozen-switch
continuation) and the sub-step rescue of a step that stalls on every setting.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional, Sequence, Union

import numpy as np

from .iterate import FREEZE_BELOW_PRESSURE_CHANGE, FROZEN_STALL_WINDOW, STALL_WINDOW, flat_options
from .mgcycle import OPT_DEFAULTS

#: sub-step rescue of a step that stalled on every relaxation setting: the step
#: is re-solved as this many BDF2 sub-steps, in turn (docs/ehl_transient.md)
SUBSTEP_SPLITS = (2, 4)


@dataclass(frozen=True)
class MovingSurfaces:
    """The roughness ``model`` (``surface_height_m(surface, xi_m)`` of each surface's material
    coordinate xi, m; None: smooth) of two surfaces moving at U1 = u1/u_s and U2 = u2/u_s."""

    model: Optional[object]
    U1: float
    U2: float

    def height_m(self, x_m, t_s, u_s):
        """Composite roughness (m) at positions ``x_m`` (m) and time ``t_s`` (s), entrainment speed
        ``u_s`` (m/s): the material point of surface i at x at time t was at x - U_i u_s t."""
        return (self.model.surface_height_m(1, x_m - self.U1 * u_s * t_s)
                + self.model.surface_height_m(2, x_m - self.U2 * u_s * t_s))


@dataclass(frozen=True)
class StepSettings:
    """How each time level is solved: the relaxation settings ``order`` tried in turn, at most
    ``max_cycles`` W-cycles per setting, the steady tolerances, the time step ``dT`` (b/u_s), the
    ``scheme`` ("characteristic", "bdf2" or "bdf1"), the warm start (``extrapolate``: linear
    from the last two levels) and ``substep_rescue`` (True, False or "always")."""

    order: Sequence[dict]
    max_cycles: int
    tol_pressure: float
    tol_load: float
    tol_residual: float
    dT: float
    scheme: str
    extrapolate: bool = True
    substep_rescue: Union[bool, str] = True


class TimeStepper:
    """The time levels of one transient solve on ``solver`` (module docstring).  ``b_m``,
    ``u_s``, ``scale_H``: Hertz half-width (m), entrainment speed (m/s), film units per m;
    ``ramp_T`` > 0: the roughness amplitude ramped from 0 to 1 over that time (smooth start)."""

    def __init__(self, solver, surfaces: MovingSurfaces, b_m: float, u_s: float, scale_H: float,
                 ramp_T: float, steps: StepSettings):
        self.solver, self.top = solver, solver.top
        self.surfaces, self.b_m, self.u_s, self.scale_H, self.ramp = surfaces, b_m, u_s, scale_H, ramp_T
        self.steps = steps
        self.cur = 0            # the relaxation setting that converged last (tried first)
        self.P_hist = self.H0_hist = self.rH = None

    def set_time(self, T: float) -> None:
        """The rigid gap X^2/2 + W(X, T) of every level at the dimensionless time T (Zhao et al. 2022 eq 3)."""
        solver, model = self.solver, self.surfaces.model
        b_m, u_s, ramp = self.b_m, self.u_s, self.ramp
        for l in range(solver.n_levels):
            Xl = solver.X[l]
            amp = 1.0 if ramp <= 0.0 else min(1.0, T / ramp)
            w = 0.0 if model is None or amp == 0.0 else \
                amp * self.surfaces.height_m(Xl * b_m, T * b_m / u_s, u_s) * self.scale_H
            solver.base[solver._sl(l)] = 0.5 * Xl ** 2 + w

    def keep_level(self) -> None:
        """The solver's state becomes the newest time level (the last two are kept)."""
        P, H0, rH = self.solver.level_P().copy(), float(self.solver.H0[self.top]), self.solver.rho_H()
        if self.P_hist is None:
            self.P_hist, self.H0_hist, self.rH = [P], [H0], [rH]
        else:
            self.P_hist, self.H0_hist, self.rH = [self.P_hist[-1], P], [self.H0_hist[-1], H0], [self.rH[-1], rH]

    def time_terms(self, n: int):
        """(c_t, old-level right-hand side, characteristic) of step ``n`` (docs/ehl_transient.md):
        the characteristic scheme's [1.5 (rho H)^n_i - 2 (rho H)^(n-1)_(i-1) + 0.5 (rho H)^(n-2)_(i-2)]/dX
        (old levels shifted one / two nodes upstream, Courant 1; node -1 of level n-2 by linear
        extrapolation; at the first step the start state also stands for level -1, so that a
        stationary start stays stationary), BDF2 [3 (rho H)^n - 4 (rho H)^(n-1) + (rho H)^(n-2)]/(2 dT)
        from the second step, else BDF1."""
        rH, dT = self.rH, self.steps.dT
        if self.steps.scheme == "characteristic":
            r2 = rH[-2] if n >= 2 else rH[-1]
            a1 = np.empty_like(rH[-1])
            a1[1:] = rH[-1][:-1]
            a1[0] = 0.0
            a2 = np.empty_like(r2)
            a2[2:] = r2[:-2]
            a2[1] = 2.0 * r2[0] - r2[1]
            a2[0] = 0.0
            return 1.5 / dT, (-2.0 * a1 + 0.5 * a2) / dT, True
        if self.steps.scheme == "bdf2" and n >= 2:
            return 1.5 / dT, (-2.0 * rH[-1] + 0.5 * rH[-2]) / dT, False
        return 1.0 / dT, -rH[-1] / dT, False

    def warm_start(self, n: int):
        """(P, H0) to start step ``n`` from: linearly extrapolated from the last two levels (P
        clipped at 0), or the last level."""
        if self.steps.extrapolate and n >= 2:
            return (np.clip(2.0 * self.P_hist[-1] - self.P_hist[-2], 0.0, None),
                    2.0 * self.H0_hist[-1] - self.H0_hist[-2])
        return self.P_hist[-1], self.H0_hist[-1]

    def solve_level(self, ct, f_old, characteristic, P_start, H0_start):
        """One implicit time level: the relaxation settings in turn (the last converged first),
        each from the warm start with its frozen-switch continuation.  Returns (converged,
        W-cycles, history of the last attempt)."""
        solver, top, st = self.solver, self.top, self.steps
        ok = False
        ncyc = 0
        tried = [self.cur] + [k for k in range(len(st.order)) if k != self.cur]
        for k in tried:
            o = dict(OPT_DEFAULTS)
            o.update(flat_options(st.order[k]))
            solver.opts.clear()
            solver.opts.update(o)
            sl = solver._sl(top)
            solver.P[sl] = P_start
            solver.P[sl.start] = solver.P[sl.stop - 1] = 0.0
            solver.tauH[:] = 0.0
            solver.H0[top] = H0_start
            solver.mode[:] = 0
            solver.update_film(top)
            solver.set_time_term(ct, f_old, characteristic=characteristic)
            ok, nc, h = solver.iterate(max_cycles=st.max_cycles, min_cycles=1, tol_pressure=st.tol_pressure,
                                       tol_load=st.tol_load, tol_residual=st.tol_residual,
                                       stall_window=STALL_WINDOW)
            ncyc += nc
            dp = h["pressure_change"][-1] if h["pressure_change"] else float("nan")
            if not ok and math.isfinite(dp) and dp < FREEZE_BELOW_PRESSURE_CHANGE:
                solver.opts["freeze"] = 1
                ok, nc, h2 = solver.iterate(max_cycles=st.max_cycles, min_cycles=1,
                                            tol_pressure=st.tol_pressure, tol_load=st.tol_load,
                                            tol_residual=st.tol_residual, stall_window=FROZEN_STALL_WINDOW)
                solver.opts["freeze"] = 0
                ncyc += nc
                if h2["pressure_change"]:
                    h = h2
            if ok:
                self.cur = k
                break
        return ok, ncyc, h

    def rescue(self, T: float):
        """Sub-step rescue of a stalled step (docs/ehl_transient.md): the interval [T - dT, T]
        in m = 2, then 4 equal BDF2 sub-steps (steady wedge + time derivative, roughness at each
        sub-step time; the first sub-step variable-step BDF2 on the levels T - dT, T - 2 dT,
        omega = 1/m, or BDF1 at the first step), each solved by :meth:`solve_level`.  Returns
        (converged, W-cycles, history, m)."""
        solver, top, dT = self.solver, self.top, self.steps.dT
        P_hist, H0_hist, rH = self.P_hist, self.H0_hist, self.rH
        total = 0
        h = {"pressure_change": [], "load_balance": [], "reynolds_residual": []}
        for m in SUBSTEP_SPLITS:
            hs = dT / m
            P_a, H0_a, r_a = P_hist[-1], H0_hist[-1], rH[-1]      # level T - dT
            ok = False
            for q in range(1, m + 1):
                self.set_time(T - dT + q * hs)
                if q == 1:
                    if len(rH) >= 2:
                        w = 1.0 / m
                        ct = (1.0 + 2.0 * w) / (1.0 + w) / hs
                        f_old = (-(1.0 + w) * rH[-1] + w * w / (1.0 + w) * rH[-2]) / hs
                        P_s = np.clip(P_hist[-1] + w * (P_hist[-1] - P_hist[-2]), 0.0, None)
                        H0_s = H0_hist[-1] + w * (H0_hist[-1] - H0_hist[-2])
                    else:
                        ct, f_old = 1.0 / hs, -rH[-1] / hs
                        P_s, H0_s = P_hist[-1], H0_hist[-1]
                    r_b, P_b, H0_b = None, None, None
                else:
                    ct = 1.5 / hs
                    f_old = (-2.0 * r_a + 0.5 * r_b) / hs
                    P_s = np.clip(2.0 * P_a - P_b, 0.0, None)
                    H0_s = 2.0 * H0_a - H0_b
                ok, nc, h = self.solve_level(ct, f_old, False, P_s, H0_s)
                total += nc
                if not ok:
                    break
                r_b, P_b, H0_b = r_a, P_a, H0_a
                r_a, P_a, H0_a = solver.rho_H(), solver.level_P().copy(), float(solver.H0[top])
            if ok:
                return True, total, h, m
        self.set_time(T)
        return False, total, h, 0

    def step(self, n: int):
        """Step ``n`` (to T = n dT): the time levels' terms, the warm start, :meth:`solve_level`
        and, where that stalls, :meth:`rescue` (every step as sub-steps with
        ``substep_rescue="always"``).  Returns (converged, W-cycles, history, sub-steps of a
        rescue or 0)."""
        T = n * self.steps.dT
        self.set_time(T)
        ct, f_old, characteristic = self.time_terms(n)
        P_start, H0_start = self.warm_start(n)
        if self.steps.substep_rescue == "always":
            ok, ncyc, h = False, 0, {}
        else:
            ok, ncyc, h = self.solve_level(ct, f_old, characteristic, P_start, H0_start)
        m_used = 0
        if not ok and self.steps.substep_rescue:
            ok, nc, h, m = self.rescue(T)
            ncyc += nc
            if ok:
                m_used = m
        return ok, ncyc, h, m_used
