"""The chain of attempts of the steady line-contact solver (docs/ehl.md "Robustness path").

A steady solve (:func:`.solver.solve_line_contact`) walks :data:`ATTEMPT_CHAIN` in order until an
attempt converges; each step knows when it applies:

1. :func:`fast_path` -- smooth solves with the default options: Venner & Lubrecht's relaxation
   with F-cycles, the coarsest grid solved by Newton steps and Newton steps on the pressure spike
   after each cycle, from a full-multigrid start or the caller's ``initial``.  The cheapest way to
   the film over most of Moes' range; stops at the discretisation error when no tolerance is given.
2. :func:`piezoviscous_corner_plan` -- where the piezoviscous coarsest-grid rule of
   :func:`.grids.choose_grid` is capped, the (grid, setting) pairs of :data:`PIEZO_CORNER_PLAN`
   measured to converge that corner, before the order below would stall on most settings first.
3. :func:`relaxation_settings_on_each_grid` -- the relaxation settings of
   :data:`RELAXATION_SETTINGS` in turn, each continued where it stalls (switch freeze, block-Newton
   polish: :func:`.iterate.iterate_setting`), then the stalled states of the grid polished, lowest
   residual first; on the default grid and, where that came close (the fail-fast rules), on the
   coarse-grid retries and the refined grid of :mod:`.grids`.
4. :func:`coupled_newton_from_stalled_states` -- last resort of smooth films: the coupled Newton of
   the finest grid (:func:`.film_newton.coupled_newton`) from the states every setting left stalled.

Every step records what it ran in the :class:`SteadyWalk` (stalled attempts, their residuals,
skipped retry grids); later steps and the error report of a walk in which nothing converged read it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Callable, Dict, List, Optional, Tuple

import numpy as np

from .coarse_newton import COARSE_NEWTON_MAX_NODES
from .film_newton import NEWTON_MAX_NODES, coupled_newton
from .grids import RETRY_BELOW_RESIDUAL, RETRY_CLOSE_RESIDUAL, RETRY_PROGRESS_FACTOR
from .iterate import ROUGH_NEWTON_RAMP, CycleSettings, extend_history, iterate_setting
from .multigrid import EHLParams, FlatMultigrid
from .polish import POLISH_BEST_BELOW_RESIDUAL, _polish

#: Relaxation settings tried in turn by the compiled solver (see docs/ehl.md):
#: (0) Venner & Lubrecht's arrangement (switch 0.3, GS/Jacobi under-relaxation
#: 0.6/0.5, load balance on the coarsest grid, switching hysteresis);
#: (1) the old default (s = 3, 0.8/0.6, load on the finest grid);
#: (2)-(5) as (0) with the trust region dmax = 3 (instead of 0.3: the
#: clipped updates at the pressure spike kept residual floors) and GS/Jacobi
#: 0.6/0.5, 0.4/0.2, 0.3/0.15, 0.3/0.1 -- the smaller Jacobi under-relaxation
#: of the nodes upstream of the spike made the high-M piezoviscous corner
#: converge (measured over the (M, L) tables); placed after (1) so that the
#: cases (1) converges (and warm-started sweeps from them) keep their path;
#: (6)-(8) older fallbacks found by numerical experiment; (9) the under-relaxation
#: of Venner & Lubrecht's EHL program (listing EHL2d.c: switch xi_l = 0.3,
#: Gauss-Seidel 0.4, distributive Jacobi 0.2) with F-cycles and the coarsest-grid
#: Newton solve, used by the piezoviscous corner plan (converges Barus M = 1000,
#: L = 18 and 20, where setting 6 stalls).
RELAXATION_SETTINGS = (
    dict(switch=0.3, nu1=2, nu2=1, omega_gs=0.6, omega_j=0.5, load_mode=1, c_h0=0.1,
         stick=10.0),
    dict(switch=3.0, nu1=2, nu2=1, omega_gs=0.8, omega_j=0.6),
    dict(switch=0.3, nu1=2, nu2=1, omega_gs=0.6, omega_j=0.5, load_mode=1, c_h0=0.1,
         stick=10.0, dmax=3.0),
    dict(switch=0.3, nu1=2, nu2=1, omega_gs=0.4, omega_j=0.2, load_mode=1, c_h0=0.1,
         stick=10.0, dmax=3.0),
    dict(switch=0.3, nu1=2, nu2=1, omega_gs=0.3, omega_j=0.15, load_mode=1, c_h0=0.1,
         stick=10.0, dmax=3.0),
    dict(switch=0.3, nu1=2, nu2=1, omega_gs=0.3, omega_j=0.1, load_mode=1, c_h0=0.1,
         stick=10.0, dmax=3.0),
    dict(switch=0.3, nu1=2, nu2=1, omega_gs=0.6, omega_j=0.3, load_mode=1, c_h0=0.1,
         stick=10.0),
    dict(switch=3.0, nu1=2, nu2=1, omega_gs=0.8, omega_j=0.6, stick=10.0),
    dict(switch=0.3, nu1=2, nu2=3, omega_gs=0.6, omega_j=0.4),
    dict(switch=0.3, nu1=2, nu2=1, omega_gs=0.4, omega_j=0.2, load_mode=1, c_h0=0.1,
         stick=10.0, gamma="F", coarse_newton=1),
)

#: Fast path of the default smooth solve (docs/ehl.md), two stages tried in
#: turn where the coarsest grid has at most COARSE_NEWTON_MAX_NODES nodes, each
#: from a fresh full-multigrid start (one cycle per level, at most the stage's
#: number of cycles on the first sub-hierarchy): both relax as setting 0 of
#: :data:`RELAXATION_SETTINGS` with F-cycles and the coarsest grid solved by
#: Newton steps (:mod:`.coarse_newton`), and after each cycle do Newton steps on
#: the finest-grid block around the largest scaled residual
#: (:func:`.coarse_newton._spike_newton`).  The first stage, FAST_SETTING, is
#: the cheaper cycle (one pre-sweep instead of two, two spike steps on
#: 2 x 8 + 1 nodes, two start cycles on the first FMG sub-hierarchy); where it
#: does not converge within FAST_MAX_CYCLES cycles (or stalls over
#: FAST_STALL_WINDOW cycles) FAST_ROBUST_SETTING follows (two pre-sweeps, one
#: spike step on 2 x 6 + 1 nodes, up to 20 start cycles); a warm start (given
#: ``initial``) runs only FAST_ROBUST_SETTING, from ``initial``.  When neither
#: converges the settings of :data:`RELAXATION_SETTINGS` follow from a fresh
#: start, as without the fast path.
FAST_SETTING = dict(RELAXATION_SETTINGS[0], nu1=1, gamma="F", coarse_newton=1, spike_newton=2,
                    spike_width=8)
FAST_FMG_COARSE_CYCLES = 2
FAST_ROBUST_SETTING = dict(RELAXATION_SETTINGS[0], gamma="F", coarse_newton=1, spike_newton=1,
                           spike_width=6)
FAST_ROBUST_FMG_COARSE_CYCLES = 20
FAST_FMG_CYCLES = 1
FAST_MAX_CYCLES = 20
FAST_STALL_WINDOW = 6
#: Stop of the fast path at the discretisation error (docs/ehl.md; only when no
#: tolerance is given): after a cycle whose relative change of the central and
#: the minimum film is below FAST_STOP_FRACTION times the discretisation error
#: of the central film estimated from the full-multigrid levels (Richardson, as
#: ``stop_at_discretisation``; capped at :data:`.iterate.STOP_FILM_CHANGE_CAP`), with the
#: scaled Reynolds residual below FAST_STOP_RESIDUAL (units of p_h) and the
#: relative load error below ``tol_load`` (the load balance has no
#: discretisation error; the finest pressure is scaled to the load when only
#: that is missing, :func:`.mgcycle._iterate`) -- or at the normal tolerances,
#: whichever comes first.  The algebraic film error left is then about a tenth
#: of the discretisation error or less (measured on 1025 nodes, Roelands,
#: L = 10: 0.005-0.04 of it at M = 20 and 100).
FAST_STOP_FRACTION = 0.25
FAST_STOP_RESIDUAL = 5e-6

#: Strongly piezoviscous corner (the piezoviscous coarsest-grid rule of
#: :func:`.grids.choose_grid` capped, alpha_eff dX_coarse > COARSE_DX_ALPHA):
#: (grid, setting) pairs tried before the normal order -- grid 0 the default
#: hierarchy, 1 the first coarse-grid retry (only under fail-fast rule 1);
#: indices into :data:`RELAXATION_SETTINGS`.  Measured over the Barus (M, L)
#: table (docs/ehl.md): setting 6 converges most of these points on the first
#: or the 2x finer coarsest grid, setting 9 Barus M = 1000, L = 18 and 20 on the
#: first (which made the pairs (1, 0) and (0, 3) of the plan before it
#: unnecessary).
PIEZO_CORNER_PLAN = ((0, 6), (0, 9), (1, 6))
#: a pair of the plan that stalls below this scaled residual is polished at
#: once (measured over the corner: the plan's polishes that converged started
#: from 3.5e-5, those from 2e-4 .. 1e-3 failed)
PLAN_POLISH_BELOW_RESIDUAL = 1e-4

#: Smooth films that stall on every setting and grid: the coupled Newton
#: (:func:`.film_newton.coupled_newton`) from at most this many stalled states (lowest
#: scaled residual first) on finest grids of at most NEWTON_MAX_NODES nodes, before
#: :class:`.errors.EHLConvergenceError` (docs/ehl.md "Robustness path").
SMOOTH_NEWTON_STATES = 4

#: one grid of a walk: (finest-grid nodes, coarsest-grid intervals, levels)
Grid = Tuple[int, int, int]


def retry_made_progress(per_grid) -> bool:
    """Fail-fast rule 2: is a further retry grid worth trying?

    ``per_grid`` holds the best stalled scaled residual of each grid tried so far, in order.
    The next grid is tried only when the last one lowered the best residual of the grids
    before it ``RETRY_PROGRESS_FACTOR`` times, or stalled below ``RETRY_CLOSE_RESIDUAL``
    (close enough to convergence that a finer coarsest grid may finish it).
    """
    last = per_grid[-1]
    return last * RETRY_PROGRESS_FACTOR <= min(per_grid[:-1]) or last < RETRY_CLOSE_RESIDUAL


@dataclass
class Attempt:
    """One relaxation setting run on one grid, and what became of it (a polish or the coupled
    Newton may finish a stalled attempt later: they continue its solver and history)."""

    converged: bool
    solver: FlatMultigrid         #: the state at the end
    hist: dict                    #: per-cycle histories and path markers (LineContactResult.residuals)
    cycles: int                   #: W-cycles, polish rounds and Newton steps
    setting: dict                 #: relaxation options of :mod:`.multigrid`
    k_setting: int                #: index into the walk's order of settings
    k_grid: int                   #: index into the walk's grids
    residual: float = math.inf    #: final scaled Reynolds residual of a stalled attempt (inf: none)


@dataclass
class SteadyWalk:
    """A steady solve walking :data:`ATTEMPT_CHAIN`: the problem, how to iterate, and the record
    of what was run so far."""

    prm: EHLParams
    rough_fn: Optional[Callable]  #: X -> composite roughness in film units; None: smooth
    Hc_guess: float               #: central film of the start (Venner-Lubrecht units)
    grids: List[Grid]             #: default grid first, then the coarse-grid retries, the refined grid
    n_default: int                #: grids[:n_default]: the default grid and its coarse-grid retries
    order: List[dict]             #: relaxation settings in the order tried
    cycles: CycleSettings         #: how one setting is iterated
    domain: Tuple[float, float]   #: (x_in, x_out) in units of the Hertz half-width
    initial: Optional[object] = None   #: LineContactResult of the warm start
    fast_path: bool = False
    corner_plan: bool = False
    default_tolerances: bool = True    #: no tolerance given: the fast path may stop at the discretisation error
    # -- the record
    tried: List[tuple] = field(default_factory=list)   #: (intervals, coarsest intervals, setting, residual)
    skipped: List[str] = field(default_factory=list)   #: why retry grids were not tried
    ran: Dict[Tuple[int, int], Optional[Attempt]] = field(default_factory=dict)  #: -> stalled state to polish
    stalled: List[Attempt] = field(default_factory=list)  #: smooth stalled states for the coupled Newton
    collapsed: Optional[Attempt] = None   #: the last attempt that ended with a film h <= 0
    last: Optional[Attempt] = None        #: the last attempt run
    grid_reached: int = 0                 #: the last grid the settings were walked on
    fast_failed_cycles: int = 0

    def start_pressure(self, k_grid: int, k_setting: int) -> Optional[np.ndarray]:
        """Start pressure of a setting: the first setting of a warm start starts from
        ``initial``'s pressure interpolated to the grid, every other one from scratch."""
        if k_setting != 0 or self.initial is None:
            return None
        X = np.linspace(self.domain[0], self.domain[1], self.grids[k_grid][0])
        return np.interp(X, self.initial.X, self.initial.P, left=0.0, right=0.0)

    def best_residual_on(self, k_grid: int) -> float:
        """The lowest final scaled residual of the settings that stalled on grid ``k_grid``."""
        g = (self.grids[k_grid][0] - 1, self.grids[k_grid][1])
        return min((t[3] for t in self.tried if t[:2] == g), default=math.inf)

    def run_setting(self, k_grid: int, k_setting: int) -> Attempt:
        """Setting ``k_setting`` on grid ``k_grid`` (:func:`.iterate.iterate_setting`); a rough film
        that does not converge in one roughness step with the coupled Newton on is solved again in
        the steps :data:`.iterate.ROUGH_NEWTON_RAMP` (docs/ehl.md "Rough films").  A stall is
        recorded (:meth:`_record_stall`)."""
        n_nodes, n_coarse, n_levels = self.grids[k_grid]
        setting = self.order[k_setting]
        P_start = self.start_pressure(k_grid, k_setting)
        solver, hist, conv, it = iterate_setting(self.prm, (n_levels, n_coarse), self.rough_fn, setting,
                                                 self.Hc_guess, P_start, self.cycles)
        if (not conv and self.rough_fn is not None and self.cycles.newton_after > 0
                and len(self.cycles.ramp) == 1):
            ramp = replace(self.cycles, ramp=ROUGH_NEWTON_RAMP, fmg=0, stop_at_discretisation=0.0)
            s2, h2, conv, it2 = iterate_setting(self.prm, (n_levels, n_coarse), self.rough_fn, setting,
                                                self.Hc_guess, P_start, ramp)
            if conv:
                solver, hist, it = s2, h2, it + it2
                hist["roughness_ramp_retry"] = list(ROUGH_NEWTON_RAMP)
        a = Attempt(conv, solver, hist, it, setting, k_setting, k_grid)
        self.last = a
        if not conv:
            self._record_stall(a)
        return a

    def _record_stall(self, a: Attempt) -> None:
        """Record a stalled attempt: its residual (``tried``); a smooth state the coupled Newton
        may take; a collapsed rough film (if nothing converges that is reported, rather than the
        stall of whichever setting ran last); a state close to a solution for the polish."""
        n_nodes, n_coarse, _ = self.grids[a.k_grid]
        hist, solver = a.hist, a.solver
        rr = hist["reynolds_residual"]
        finite = bool(rr) and math.isfinite(rr[-1])
        a.residual = float(rr[-1]) if finite else math.inf
        self.tried.append((n_nodes - 1, n_coarse, a.k_setting, a.residual))
        if (self.rough_fn is None and self.cycles.newton_after > 0 and finite
                and n_nodes <= NEWTON_MAX_NODES and "hit_max_cycles" not in hist):
            # (a setting stopped by the caller's cycle limit has not stalled: no Newton either)
            self.stalled.append(a)
        H_end = solver.level_H()
        if self.rough_fn is not None and np.all(np.isfinite(H_end)) and float(np.min(H_end)) <= 0.0:
            self.collapsed = a
        polish = (finite and "newton_polish_rounds" not in hist and "newton_polish_early_rounds" not in hist
                  and "hit_max_cycles" not in hist and rr[-1] < POLISH_BEST_BELOW_RESIDUAL
                  and solver.opts.get("order2", 1) and not solver.opts.get("defect", 0))
        self.ran[(a.k_grid, a.k_setting)] = a if polish else None

    def polish(self, a: Attempt) -> bool:
        """The block-Newton polish (:func:`.polish._polish`) of a stalled attempt; on success the
        attempt is converged with the polish rounds added to its history and cycles."""
        c = self.cycles
        ok, nr, ph = _polish(a.solver, c.tol_pressure, c.tol_load, c.tol_residual, c.tol_film, c.max_cycles)
        if ok:
            a.hist["newton_polish_from_cycle"] = [a.cycles]
            a.hist["newton_polish_rounds"] = [nr]
            extend_history(a.hist, ph)
            a.cycles += nr
            a.converged = True
        return ok

    def failure(self) -> Attempt:
        """What a walk in which nothing converged reports: the last attempt that left a collapsed
        film, else the last attempt run, at the grid the walk reached and the last setting of the
        order (where the walk stopped)."""
        if self.collapsed is not None:
            return self.collapsed
        last = self.last
        return Attempt(False, last.solver, last.hist, last.cycles, self.order[-1], len(self.order) - 1,
                       self.grid_reached, last.residual)

    def mark_path(self, a: Attempt) -> None:
        """Path markers of the attempt reported in its history (docs/ehl.md): ``grid_refined``,
        ``coarse_grid_retry``, the relaxation ``settings`` and ``attempt`` (index), the cycles of
        a failed fast path."""
        if len(self.grids) > self.n_default:
            a.hist["grid_refined"] = [1.0 if a.k_grid >= self.n_default else 0.0]
        if 0 < a.k_grid < self.n_default:
            a.hist["coarse_grid_retry"] = [float(self.grids[a.k_grid][1])]
        a.hist["settings"] = a.setting
        a.hist["attempt"] = a.k_setting
        if self.fast_failed_cycles:
            a.hist["fast_path_failed_cycles"] = [float(self.fast_failed_cycles)]


# --------------------------------------------------------------------------- the chain
def fast_path(walk: SteadyWalk) -> Optional[Attempt]:
    """Smooth solves with the default options where the coarsest grid is small enough for its
    Newton solve: :data:`FAST_SETTING`, then :data:`FAST_ROBUST_SETTING` (a warm start only the
    latter, from ``initial``) -- Venner & Lubrecht's relaxation with F-cycles, the coarsest grid
    solved by Newton steps and, after each cycle, Newton steps on the block around the largest
    scaled residual (local relaxation at the pressure spike, after Brandt 1984) -- each from a
    fresh start on the default grid, without continuation
    (a stall falls through to the next step); with no tolerance given they stop at the
    discretisation error (:data:`FAST_STOP_FRACTION`; a warm start on the same grid uses the
    estimate of ``initial``).  Marks ``fast_path`` and ``fast_path_stage``; the relaxation
    reported is setting 0's, which the transient and mesh-film solvers reuse."""
    n_nodes, n_coarse, n_levels = walk.grids[0]
    if not (walk.fast_path and n_coarse + 1 <= COARSE_NEWTON_MAX_NODES):
        return None
    initial, c = walk.initial, walk.cycles
    P_fast, disc_prev = None, None
    stages = ((FAST_SETTING, FAST_FMG_COARSE_CYCLES), (FAST_ROBUST_SETTING, FAST_ROBUST_FMG_COARSE_CYCLES))
    if initial is not None:
        P_fast = np.interp(np.linspace(walk.domain[0], walk.domain[1], n_nodes), initial.X, initial.P,
                           left=0.0, right=0.0)
        stages = stages[1:]
        # the discretisation error estimated by the solve of ``initial`` on the same grid
        if initial.X.size == n_nodes and "stopped_at_discretisation" in initial.residuals:
            disc_prev = initial.residuals["stopped_at_discretisation"][0]
    for k_fast, (setting, coarse_cycles) in enumerate(stages):
        cycles = CycleSettings(
            min(c.max_cycles, FAST_MAX_CYCLES), c.min_cycles, c.tol_pressure, c.tol_load, c.tol_residual,
            tol_film=c.tol_film, fmg=0 if initial is not None else FAST_FMG_CYCLES, continuation=False,
            stall_window=FAST_STALL_WINDOW,
            stop_at_discretisation=FAST_STOP_FRACTION if walk.default_tolerances and c.tol_film >= 1.0 else 0.0,
            stop_residual=FAST_STOP_RESIDUAL, fmg_coarse_cycles=coarse_cycles, disc_estimate=disc_prev)
        solver, hist, converged, it = iterate_setting(walk.prm, (n_levels, n_coarse), None, setting,
                                                      walk.Hc_guess, P_fast, cycles)
        if converged:
            hist["fast_path"] = [1.0]
            # 0: FAST_SETTING, 1: FAST_ROBUST_SETTING
            hist["fast_path_stage"] = [float(k_fast + 2 - len(stages))]
            return Attempt(True, solver, hist, it, dict(RELAXATION_SETTINGS[0]), 0, 0)
        walk.fast_failed_cycles += it
    return None


def piezoviscous_corner_plan(walk: SteadyWalk) -> Optional[Attempt]:
    """The strongly piezoviscous corner (docs/ehl.md): the (grid, setting) pairs of
    :data:`PIEZO_CORNER_PLAN` first, the coarse-grid retry only under fail-fast rule 1 (the
    default grid stalled below :data:`.grids.RETRY_BELOW_RESIDUAL`); a pair that stalls below
    :data:`PLAN_POLISH_BELOW_RESIDUAL` is polished at once (a state further from the solution
    waits for the polish of its grid).  Marks ``corner_plan_pair``."""
    if not walk.corner_plan:
        return None
    for kg, ka in PIEZO_CORNER_PLAN:
        if kg >= walk.n_default or ka >= len(walk.order):
            continue
        if kg > 0 and not walk.best_residual_on(0) < RETRY_BELOW_RESIDUAL:
            break
        a = walk.run_setting(kg, ka)
        stalled = walk.ran.get((kg, ka))
        if not a.converged and stalled is not None and stalled.residual < PLAN_POLISH_BELOW_RESIDUAL:
            walk.polish(stalled)
            walk.ran[(kg, ka)] = None
        if a.converged:
            a.hist["corner_plan_pair"] = [float(kg), float(ka)]
            return a
    return None


def relaxation_settings_on_each_grid(walk: SteadyWalk) -> Optional[Attempt]:
    """The settings of the walk's order in turn on each grid (a pair the corner plan ran is not
    run again); when every setting stalled on a grid, its stalled states are polished, lowest
    residual first, until one converges (Barus M = 500, L = 15 converges only from setting 5's
    state, whose residual is not the lowest).  A retry grid is tried only where the fail-fast
    rules (:func:`retry_grid_worth_trying`) allow."""
    for k_grid in range(len(walk.grids)):
        walk.grid_reached = k_grid
        if k_grid > 0 and not retry_grid_worth_trying(walk, k_grid):
            break
        for k_setting in range(len(walk.order)):
            if (k_grid, k_setting) in walk.ran:
                continue
            a = walk.run_setting(k_grid, k_setting)
            if a.converged:
                return a
        stalled = [a for (g, _), a in walk.ran.items() if g == k_grid and a is not None]
        for a in sorted(stalled, key=lambda a: (a.residual, a.k_setting)):
            if walk.polish(a):
                return a
    return None


def retry_grid_worth_trying(walk: SteadyWalk, k_grid: int) -> bool:
    """Fail fast (docs/ehl.md): retry grids only where the default grid stalled below
    :data:`.grids.RETRY_BELOW_RESIDUAL` (rule 1), a further one only where the last one made
    progress (rule 2, :func:`retry_made_progress`); a grid not tried is named in ``skipped``."""
    per_grid = [walk.best_residual_on(g) for g in range(k_grid)]
    if not per_grid[0] < RETRY_BELOW_RESIDUAL:
        walk.skipped.append(f"retry grids not tried: best scaled residual on the default "
                            f"grid {per_grid[0]:.1e} >= {RETRY_BELOW_RESIDUAL:.0e}")
        return False
    if k_grid > 1 and not retry_made_progress(per_grid):
        prev = walk.grids[k_grid - 1]
        walk.skipped.append(f"{len(walk.grids) - k_grid} further retry grid(s) not tried: the "
                            f"last one ({prev[0] - 1}/{prev[1]} intervals) reached {per_grid[-1]:.1e}, neither "
                            f"{RETRY_PROGRESS_FACTOR:g}x below {min(per_grid[:-1]):.1e} "
                            f"nor below {RETRY_CLOSE_RESIDUAL:.0e}")
        return False
    return True


def coupled_newton_from_stalled_states(walk: SteadyWalk) -> Optional[Attempt]:
    """Last resort for a smooth film that every setting, polish and grid left stalled: the
    coupled Newton of the finest grid (:func:`.film_newton.coupled_newton`) from at most
    :data:`SMOOTH_NEWTON_STATES` stalled states, lowest residual first (Barus M = 5.5, L = 22: all
    ten settings stall at pressure changes of 1e-2, the Newton converges from eight of their
    states to the same film).  Marks ``coupled_newton_from_cycle`` and ``coupled_newton_steps``."""
    c = walk.cycles
    for a in sorted(walk.stalled, key=lambda a: (a.residual, a.k_grid, a.k_setting))[:SMOOTH_NEWTON_STATES]:
        ok, ns, nh = coupled_newton(a.solver, c.tol_pressure, c.tol_load, c.tol_residual)
        if ok and c.tol_film < 1.0 and not (nh["film_change"] and nh["film_change"][-1] < c.tol_film):
            ok = False
        if ok:
            extend_history(a.hist, nh)
            a.hist["coupled_newton_from_cycle"] = [float(a.cycles)]
            a.hist["coupled_newton_steps"] = [float(ns)]
            a.cycles += ns
            a.converged = True
            return a
    return None


#: The chain of attempts of a steady solve, walked in this order until one converges (module
#: docstring): the cheap fast path where it applies, the measured plan of the piezoviscous corner,
#: the relaxation settings on the default and the retry grids with their polish, and the coupled
#: Newton from the stalled states as the last resort.
ATTEMPT_CHAIN: Tuple[Callable[[SteadyWalk], Optional[Attempt]], ...] = (
    fast_path,
    piezoviscous_corner_plan,
    relaxation_settings_on_each_grid,
    coupled_newton_from_stalled_states,
)


def walk_chain(walk: SteadyWalk) -> Optional[Attempt]:
    """The first attempt of :data:`ATTEMPT_CHAIN` that converges (None: none did)."""
    for step in ATTEMPT_CHAIN:
        found = step(walk)
        if found is not None:
            return found
    return None
