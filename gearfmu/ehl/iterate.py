"""Iteration of one relaxation setting of the steady EHL solver on one grid.

:func:`iterate_setting` runs the compiled cycles of :class:`.multigrid.FlatMultigrid`
from a start (given pressure, full multigrid, Hertzian pressure), through the
roughness stages, and continues a stalled setting by the block-Newton polish
(:mod:`.polish`) and the frozen switch; for a rough film on a grid of at most
:data:`.film_newton.NEWTON_MAX_NODES` nodes the coupled Newton of
:mod:`.film_newton` follows the first :data:`ROUGH_NEWTON_AFTER_CYCLES` cycles
(docs/ehl.md "Rough films").  Used by the attempts of :mod:`.attempts`, settings in
:class:`CycleSettings`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

from .film_newton import NEWTON_MAX_NODES, coupled_newton
from .multigrid import FlatMultigrid
from .polish import POLISH_BELOW_RESIDUAL, POLISH_EARLY_BELOW_RESIDUAL, _HIST_KEYS, _polish

#: Stall test of the compiled solver: a setting stalls when neither the
#: pressure change nor the scaled residual fell 3x over the last
#: STALL_WINDOW cycles against all earlier ones (checked from 2 x
#: STALL_WINDOW cycles on).  12: a window of 8 failed the high-M corner
#: about 1/3 sooner but cut off slowly converging light-load films (M = 0.85,
#: L = 16 of tests/unit/contact/test_helical_contact.py, 3x per ~10 cycles).
STALL_WINDOW = 12
#: stall window of the frozen-switch continuation (slow but steady
#: convergence, e.g. Barus M = 10, L = 20: 83 cycles; 8 stopped it early)
FROZEN_STALL_WINDOW = 12

#: upper limit of the film-change tolerance of ``stop_at_discretisation``: the
#: FMG levels' error estimate is unreliable at high alpha_eff (3-50x too large
#: at M = 100, L = 10, docs/ehl.md); the cap bounds the algebraic error left
#: to a few 1e-4 whatever the estimate
STOP_FILM_CHANGE_CAP = 3e-4

#: A relaxation setting that stalls with a relative pressure change per cycle
#: below this value is continued with the switch frozen (``freeze`` option of
#: :mod:`.multigrid`): the stall is then a switching limit cycle of the
#: relaxation close to the solution (measured on rough films, docs/ehl.md).
FREEZE_BELOW_PRESSURE_CHANGE = 1e-3

#: Rough films (docs/ehl.md "Rough films"): after this many multigrid cycles
#: with the roughness in place the coupled Newton of :mod:`.film_newton` takes
#: over (finest grids of at most NEWTON_MAX_NODES nodes); the cycles remove the
#: smooth part of the error cheaply, the Newton steps the local pressure spikes
#: at the roughness crests that the relaxation does not converge.  0: off (the
#: cycles alone, as before).
ROUGH_NEWTON_AFTER_CYCLES = 8
#: amplitude steps of the roughness tried when the rough film does not converge
#: in one step (each step: cycles, then the coupled Newton); on the default
#: scene's level-3 films (297 nodes) the one that the single step leaves
#: (Lambda = 3.3, the cycles diverge at a pressure spike of 10 p_h) converges so
ROUGH_NEWTON_RAMP = (0.5, 1.0)


def flat_options(opts):
    """Option dict with ``load_on_coarse`` mapped to ``load_mode`` and ``order2`` to 0/1."""
    o = dict(opts)
    if "load_on_coarse" in o:
        o["load_mode"] = 1 if o.pop("load_on_coarse") else 0
    if "order2" in o:
        o["order2"] = 1 if o["order2"] else 0
    return o

@dataclass(frozen=True)
class CycleSettings:
    """How :func:`iterate_setting` runs one relaxation setting on one grid.

    Stop: ``max_cycles`` (at most; a setting stopped there has not stalled), ``min_cycles`` (at
    least), the relative pressure change per cycle below ``tol_pressure``, the relative load error
    below ``tol_load``, the scaled Reynolds residual (units of p_h) below ``tol_residual`` and, if
    ``tol_film`` < 1, the relative change of the central and minimum film below it; a setting
    stalls when neither the pressure change nor the residual fell 3x over ``stall_window`` cycles.
    ``ramp``: the amplitude steps of the roughness (last 1; ignored for a smooth film).  Start:
    ``fmg`` > 0 cycles per level of a full-multigrid start (at most ``fmg_coarse_cycles`` on its
    first sub-hierarchy) where no start pressure is given.  ``stop_at_discretisation`` > 0: stop
    also when the film change and the load error are below this factor times the discretisation
    error of the central film, estimated from the full-multigrid levels (Richardson) or given as
    ``disc_estimate``, with the scaled residual below ``stop_residual``.  ``continuation``: continue
    a stalled setting (early polish, frozen switch, polish; False: stop at the stall).
    ``newton_after`` > 0 (rough films): the coupled Newton after that many cycles of the last
    roughness stage."""

    max_cycles: int
    min_cycles: int
    tol_pressure: float
    tol_load: float
    tol_residual: float
    tol_film: float = 1.0
    ramp: tuple = (1.0,)
    fmg: int = 0
    stop_at_discretisation: float = 0.0
    continuation: bool = True
    stall_window: int = STALL_WINDOW
    stop_residual: float = math.inf
    fmg_coarse_cycles: int = 20
    disc_estimate: Optional[float] = None
    newton_after: int = 0


def iterate_setting(prm, grid, rough_fn, opts, Hc_guess, P_start, cycles: CycleSettings):
    """One relaxation setting ``opts`` (:mod:`.multigrid` options) on one grid, ``grid`` =
    (levels, coarsest-grid intervals), as ``cycles`` says: the compiled multigrid cycles of
    Venner & Lubrecht 2000 (:mod:`.multigrid`) from ``P_start`` (finest grid), a full-multigrid start or a
    Hertzian pressure; with roughness (``rough_fn``: X -> roughness in film units) through the
    amplitude steps of ``cycles.ramp``, each stage continued where it stalls
    (:func:`_continue_stalled_stage`).  Returns (solver, history, converged, cycles run)."""
    n_levels, n_coarse = grid
    solver = FlatMultigrid(prm, n_levels, n_coarse, rough_fn, **flat_options(opts))
    if rough_fn is not None:
        solver.base[:] = np.concatenate([0.5 * x ** 2 for x in solver.X])
    hist = {k_: [] for k_ in _HIST_KEYS}
    tol_disc = _start(solver, hist, Hc_guess, P_start, cycles)
    stages = list(cycles.ramp) if rough_fn is not None else [None]
    if rough_fn is not None and P_start is None:
        stages = [0.0] + stages
    it = 0
    converged = False
    for a in stages:
        if a is not None:
            solver.set_roughness_scale(a)
        if (cycles.newton_after > 0 and rough_fn is not None and a is not None and a > 0.0
                and solver.level_P().size <= NEWTON_MAX_NODES):
            converged, nc = _newton_stage(solver, hist, it, cycles.newton_after, cycles.min_cycles,
                                          cycles.tol_pressure, cycles.tol_load, cycles.tol_residual,
                                          cycles.tol_film, cycles.stall_window)
            it += nc
            if converged:
                continue
        converged, nc, h = solver.iterate(max_cycles=cycles.max_cycles, min_cycles=cycles.min_cycles,
                                          tol_pressure=cycles.tol_pressure, tol_load=cycles.tol_load,
                                          tol_residual=cycles.tol_residual, tol_film=cycles.tol_film,
                                          stall_window=cycles.stall_window,
                                          tol_discretisation=tol_disc,
                                          tol_discretisation_residual=cycles.stop_residual,
                                          tol_discretisation_load=(cycles.tol_load if cycles.stop_residual
                                                                   < math.inf else math.inf))
        it += nc
        extend_history(hist, h)
        if not converged and nc >= cycles.max_cycles:
            # stopped by the caller's cycle limit, not stalled: no polish either
            hist["hit_max_cycles"] = [float(nc)]
        if not cycles.continuation:
            break
        if not converged:
            converged, it = _continue_stalled_stage(solver, hist, h, it, cycles)
        if not converged:
            break
    return solver, hist, converged, it


def extend_history(hist, h):
    """Append the per-cycle histories ``h`` to ``hist``."""
    for k_ in _HIST_KEYS:
        hist[k_].extend(h[k_])


def _start(solver, hist, Hc_guess, P_start, cycles: CycleSettings) -> float:
    """Start state of ``solver``: ``P_start``, a full-multigrid start (``cycles.fmg`` > 0) or the
    Hertzian pressure.  Returns the film-change tolerance of the stop at the discretisation error
    (0: none; docs/ehl.md): ``cycles.stop_at_discretisation`` times the relative discretisation
    error of the central film, by Richardson extrapolation (second order) over the last two
    full-multigrid levels, |H_l - H_(l-1)| / 3 there and a quarter of that on the finest grid,
    or ``cycles.disc_estimate``; capped at
    :data:`STOP_FILM_CHANGE_CAP`."""
    fmg_counts = None
    tol_disc = 0.0
    sad = cycles.stop_at_discretisation
    if P_start is None and cycles.fmg > 0:
        fmg_counts = solver.fmg_start(Hc_guess, cycles_per_level=cycles.fmg,
                                      coarse_cycles=cycles.fmg_coarse_cycles)
    elif P_start is None:
        solver.hertz_start(Hc_guess)
    else:
        solver.start(P_start, Hc_guess)
    if fmg_counts is not None:
        hist["fmg_cycles_per_level"] = list(fmg_counts)
        hc = solver.fmg_hc
        if sad > 0.0 and len(hc) >= 2 and hc[-1] > 0.0:
            e_top = abs(hc[-1] - hc[-2]) / 3.0 / hc[-1] / 4.0
            tol_disc = min(max(sad * e_top, 1e-8), STOP_FILM_CHANGE_CAP)
            hist["stopped_at_discretisation"] = [e_top, tol_disc]
    elif sad > 0.0 and cycles.disc_estimate is not None and cycles.disc_estimate > 0.0:
        tol_disc = min(max(sad * cycles.disc_estimate, 1e-8), STOP_FILM_CHANGE_CAP)
        hist["stopped_at_discretisation"] = [cycles.disc_estimate, tol_disc]
    return tol_disc


def _polishable(solver, hist) -> bool:
    """The polish applies: not stopped by the cycle limit, a second-order, non-defect setting."""
    return ("hit_max_cycles" not in hist and solver.opts.get("order2", 1)
            and not solver.opts.get("defect", 0))


def _continue_stalled_stage(solver, hist, h, it, cycles: CycleSettings):
    """A stage that stalled (history ``h`` of its cycles, ``it`` cycles so far), continued in
    turn (docs/ehl.md "Robustness path"): stalled just above the tolerance, the block-Newton
    polish (:func:`.polish._polish`; on failure the state is restored and the path goes on as
    without it); a limit cycle close to the solution (pressure change below
    :data:`FREEZE_BELOW_PRESSURE_CHANGE`), cycles with the Gauss-Seidel / Jacobi choice of every
    finest-grid node frozen; still stalled close to the solution, the polish (if not tried).
    Returns (converged, cycles so far)."""
    tols = (cycles.tol_pressure, cycles.tol_load, cycles.tol_residual, cycles.tol_film)
    last_dp = h["pressure_change"][-1] if h["pressure_change"] else float("nan")
    last_res = h["reynolds_residual"][-1] if h["reynolds_residual"] else float("nan")
    converged = False
    if math.isfinite(last_res) and last_res < POLISH_EARLY_BELOW_RESIDUAL and _polishable(solver, hist):
        saved = (solver.P.copy(), solver.H.copy(), solver.H0.copy(), solver.mode.copy())
        ok, nr, ph = _polish(solver, *tols, cycles.max_cycles)
        hist["newton_polish_early_rounds"] = [nr]
        if ok:
            converged = True
            hist["newton_polish_from_cycle"] = [it]
            hist["newton_polish_rounds"] = [nr]
            it += nr
            extend_history(hist, ph)
        else:
            solver.P[:], solver.H[:], solver.H0[:], solver.mode[:] = saved
    if not converged and math.isfinite(last_dp) and last_dp < FREEZE_BELOW_PRESSURE_CHANGE:
        solver.opts["freeze"] = 1
        converged, nc, h = solver.iterate(max_cycles=cycles.max_cycles, min_cycles=1,
                                          tol_pressure=cycles.tol_pressure, tol_load=cycles.tol_load,
                                          tol_residual=cycles.tol_residual, tol_film=cycles.tol_film,
                                          stall_window=FROZEN_STALL_WINDOW)
        solver.opts["freeze"] = 0
        hist["frozen_switch_from_cycle"] = [it]
        it += nc
        extend_history(hist, h)
    last_res = hist["reynolds_residual"][-1] if hist["reynolds_residual"] else float("nan")
    if (not converged and math.isfinite(last_res) and last_res < POLISH_BELOW_RESIDUAL
            and "newton_polish_rounds" not in hist
            and "newton_polish_early_rounds" not in hist   # failed once on this setting
            and _polishable(solver, hist)):
        converged, nc, h = _polish(solver, *tols, cycles.max_cycles)
        hist["newton_polish_from_cycle"] = [it]
        hist["newton_polish_rounds"] = [nc]
        it += nc
        extend_history(hist, h)
    return converged, it


def _newton_stage(solver, hist, it, n_cycles, min_cycles, tol_pressure, tol_load, tol_residual,
                  tol_film, stall_window):
    """Up to ``n_cycles`` cycles, then (not converged) the coupled Newton of the
    finest grid; where it fails, the coupled Newton once more from the state
    before the cycles (the cycles can leave a state further from the solution
    than the start when they diverge at a pressure spike); where that fails
    too, the state after the cycles is restored.  Appends to ``hist``; returns
    (converged, cycles + accepted Newton steps)."""
    start = (solver.P.copy(), solver.H.copy(), solver.H0.copy())
    converged, nc, h = solver.iterate(max_cycles=n_cycles, min_cycles=min(min_cycles, n_cycles),
                                      tol_pressure=tol_pressure, tol_load=tol_load,
                                      tol_residual=tol_residual, tol_film=tol_film,
                                      stall_window=stall_window)
    for k_ in _HIST_KEYS:
        hist[k_].extend(h[k_])
    if converged:
        return converged, nc
    after = (solver.P.copy(), solver.H.copy(), solver.H0.copy())
    failed = 0
    for k, state in enumerate((None, start)):
        if state is not None:
            solver.P[:], solver.H[:], solver.H0[:] = state
        elif not all(math.isfinite(v) for v in h["reynolds_residual"][-1:]):
            continue
        ok, ns, nh = coupled_newton(solver, tol_pressure, tol_load, tol_residual)
        if ok and tol_film < 1.0 and not (nh["film_change"] and nh["film_change"][-1] < tol_film):
            ok = False
        if ok:
            for k_ in _HIST_KEYS:
                hist[k_].extend(nh[k_])
            hist["coupled_newton_from_cycle"] = [float(it + nc if k == 0 else it)]
            hist["coupled_newton_steps"] = [float(ns)]
            if failed:
                hist["coupled_newton_failed_steps"] = [float(failed)]
            return True, nc + ns
        failed += ns
    solver.P[:], solver.H[:], solver.H0[:] = after
    hist["coupled_newton_failed_steps"] = [float(failed)]
    return False, nc
