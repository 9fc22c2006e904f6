"""Iteration of one relaxation setting of the steady EHL solver on one grid.

:func:`_iterate_flat` runs the compiled cycles of :class:`.multigrid.FlatMultigrid`
from a start (given pressure, full multigrid, Hertzian pressure), through the
roughness stages, and continues a stalled setting by the block-Newton polish
(:mod:`.polish`) and the frozen switch; for a rough film on a grid of at most
:data:`.film_newton.NEWTON_MAX_NODES` nodes the coupled Newton of
:mod:`.film_newton` follows the first :data:`ROUGH_NEWTON_AFTER_CYCLES` cycles
(docs/ehl.md "Rough films").  Used by :func:`.solver.solve_line_contact`.
"""
from __future__ import annotations

import math

import numpy as np

from .film_newton import NEWTON_MAX_NODES, coupled_newton
from .multigrid import FlatMultigrid
from .polish import POLISH_BELOW_RESIDUAL, POLISH_EARLY_BELOW_RESIDUAL, _HIST_KEYS, _polish

#: Stall test of the compiled solver: a setting stalls when neither the
#: pressure change nor the scaled residual fell 3x over the last
#: STALL_WINDOW cycles against all earlier ones (checked from 2 x
#: STALL_WINDOW cycles on).  12: a window of 8 failed the high-M corner
#: about 1/3 sooner but cut off slowly converging light-load films (M = 0.85,
#: L = 16 of tests/test_helical_contact.py, 3x per ~10 cycles).
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


def _flat_opts(opts):
    """Option dict with ``load_on_coarse`` mapped to ``load_mode`` and ``order2`` to 0/1."""
    o = dict(opts)
    if "load_on_coarse" in o:
        o["load_mode"] = 1 if o.pop("load_on_coarse") else 0
    if "order2" in o:
        o["order2"] = 1 if o["order2"] else 0
    return o

def _iterate_flat(prm, n_levels, n_coarse, rough_fn, opts, Hc_guess, P_start, max_cycles,
                  min_cycles, tol_pressure, tol_load, tol_residual, ramp=(1.0,), tol_film=1.0,
                  fmg=0, stop_at_discretisation=0.0, continuation=True,
                  stall_window=STALL_WINDOW, stop_residual=math.inf, fmg_coarse_cycles=20,
                  disc_estimate=None, newton_after=0):
    """Compiled W-cycles (:mod:`.multigrid`) from ``P_start`` (finest grid), a
    full-multigrid start (``fmg`` > 0 cycles per level, at most
    ``fmg_coarse_cycles`` on its first sub-hierarchy) or a Hertzian pressure;
    with roughness the amplitude steps of ``ramp``.  ``stop_residual``: the
    stop at the discretisation error (``stop_at_discretisation``) also needs the
    scaled residual below it and the load error below ``tol_load``;
    ``disc_estimate``: the relative discretisation error of the central film
    to use without a full-multigrid start (a warm start's from its ``initial``).
    ``newton_after`` > 0 (rough films): in the last roughness stage, the
    coupled Newton (:func:`.film_newton.coupled_newton`) after that many cycles
    if they have not converged; where it fails the state is restored and the
    cycles go on (``hist["coupled_newton_failed_steps"]``)."""
    solver = FlatMultigrid(prm, n_levels, n_coarse, rough_fn, **_flat_opts(opts))
    if rough_fn is not None:
        solver.base[:] = np.concatenate([0.5 * x ** 2 for x in solver.X])
    fmg_counts = None
    tol_disc = 0.0
    if P_start is None and fmg > 0:
        fmg_counts = solver.fmg_start(Hc_guess, cycles_per_level=fmg,
                                      coarse_cycles=fmg_coarse_cycles)
    elif P_start is None:
        solver.hertz_start(Hc_guess)
    else:
        solver.start(P_start, Hc_guess)
    hist = {k_: [] for k_ in _HIST_KEYS}
    if fmg_counts is not None:
        hist["fmg_cycles_per_level"] = list(fmg_counts)
        hc = solver.fmg_hc
        if stop_at_discretisation > 0.0 and len(hc) >= 2 and hc[-1] > 0.0:
            # Richardson (second order): error of the last FMG level
            # |H_l - H_(l-1)| / 3, of the finest grid a quarter of that; stop when
            # the film change per cycle and the load error are below
            # stop_at_discretisation times that estimate (docs/ehl.md)
            e_top = abs(hc[-1] - hc[-2]) / 3.0 / hc[-1] / 4.0
            tol_disc = min(max(stop_at_discretisation * e_top, 1e-8), STOP_FILM_CHANGE_CAP)
            hist["stopped_at_discretisation"] = [e_top, tol_disc]
    elif stop_at_discretisation > 0.0 and disc_estimate is not None and disc_estimate > 0.0:
        tol_disc = min(max(stop_at_discretisation * disc_estimate, 1e-8), STOP_FILM_CHANGE_CAP)
        hist["stopped_at_discretisation"] = [disc_estimate, tol_disc]
    stages = list(ramp) if rough_fn is not None else [None]
    if rough_fn is not None and P_start is None:
        stages = [0.0] + stages
    it = 0
    converged = False
    for a in stages:
        if a is not None:
            solver.set_roughness_scale(a)
        if (newton_after > 0 and rough_fn is not None and a is not None and a > 0.0
                and solver.level_P().size <= NEWTON_MAX_NODES):
            converged, nc = _newton_stage(solver, hist, it, newton_after, min_cycles, tol_pressure,
                                          tol_load, tol_residual, tol_film, stall_window)
            it += nc
            if converged:
                continue
        converged, nc, h = solver.iterate(max_cycles=max_cycles, min_cycles=min_cycles,
                                          tol_pressure=tol_pressure, tol_load=tol_load,
                                          tol_residual=tol_residual, tol_film=tol_film,
                                          stall_window=stall_window,
                                          tol_discretisation=tol_disc,
                                          tol_discretisation_residual=stop_residual,
                                          tol_discretisation_load=(tol_load if stop_residual
                                                                   < math.inf else math.inf))
        it += nc
        for k_ in _HIST_KEYS:
            hist[k_].extend(h[k_])
        if not converged and nc >= max_cycles:
            # stopped by the caller's cycle limit, not stalled: no polish either
            hist["hit_max_cycles"] = [float(nc)]
        if not continuation:
            break
        last_dp = h["pressure_change"][-1] if h["pressure_change"] else float("nan")
        last_res = h["reynolds_residual"][-1] if h["reynolds_residual"] else float("nan")
        if (not converged and math.isfinite(last_res) and last_res < POLISH_EARLY_BELOW_RESIDUAL
                and "hit_max_cycles" not in hist
                and solver.opts.get("order2", 1) and not solver.opts.get("defect", 0)):
            # stalled just above the tolerance: block-Newton polish first; if it
            # fails, the state is restored and the path continues exactly as
            # without it (frozen switch, docs/ehl.md)
            saved = (solver.P.copy(), solver.H.copy(), solver.H0.copy(), solver.mode.copy())
            ok, nr, ph = _polish(solver, tol_pressure, tol_load, tol_residual, tol_film,
                                 max_cycles)
            hist["newton_polish_early_rounds"] = [nr]
            if ok:
                converged = True
                hist["newton_polish_from_cycle"] = [it]
                hist["newton_polish_rounds"] = [nr]
                it += nr
                for k_ in _HIST_KEYS:
                    hist[k_].extend(ph[k_])
            else:
                solver.P[:], solver.H[:], solver.H0[:], solver.mode[:] = saved
        if not converged and math.isfinite(last_dp) and last_dp < FREEZE_BELOW_PRESSURE_CHANGE:
            # limit cycle close to the solution: continue with the Gauss-Seidel /
            # Jacobi choice of every finest-grid node frozen (docs/ehl.md)
            solver.opts["freeze"] = 1
            converged, nc, h = solver.iterate(max_cycles=max_cycles, min_cycles=1,
                                              tol_pressure=tol_pressure, tol_load=tol_load,
                                              tol_residual=tol_residual, tol_film=tol_film,
                                              stall_window=FROZEN_STALL_WINDOW)
            solver.opts["freeze"] = 0
            hist["frozen_switch_from_cycle"] = [it]
            it += nc
            for k_ in _HIST_KEYS:
                hist[k_].extend(h[k_])
        last_res = hist["reynolds_residual"][-1] if hist["reynolds_residual"] else float("nan")
        if (not converged and math.isfinite(last_res) and last_res < POLISH_BELOW_RESIDUAL
                and "hit_max_cycles" not in hist and "newton_polish_rounds" not in hist
                and "newton_polish_early_rounds" not in hist   # failed once on this setting
                and solver.opts.get("order2", 1) and not solver.opts.get("defect", 0)):
            # close to the solution but stalled on the spike region: block-Newton
            # polish (docs/ehl.md)
            converged, nc, h = _polish(solver, tol_pressure, tol_load, tol_residual, tol_film,
                                       max_cycles)
            hist["newton_polish_from_cycle"] = [it]
            hist["newton_polish_rounds"] = [nc]
            it += nc
            for k_ in _HIST_KEYS:
                hist[k_].extend(h[k_])
        if not converged:
            break
    return solver, hist, converged, it




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
