"""Steady line-contact EHL solver, seed 000 eq 2-7 and Algorithm 1.

Public entry point: :func:`solve_line_contact`.  See :mod:`.multigrid` for the
equations and the numerical method, and docs/ehl.md for the choices made.

Definitions (SI; Moes 1992 / Venner & Lubrecht 2000 conventions):

* ``R_m``: reduced radius of curvature, 1/R = 1/R1 + 1/R2.
* ``E_Pa``: reduced modulus E' = 2 / ((1 - nu1^2)/E1 + (1 - nu2^2)/E2)
  (the E' of Moes and Venner-Lubrecht and the E of seed 000 eq 4).
* ``w_N_per_m``: load per unit length of contact.
* ``u_m_s``: entrainment (mean) speed u_m = (u1 + u2)/2 (seed 000 eq 2's u_s).
* Moes' parameters: W = w/(E'R), U = eta0 u_m/(E'R), G = alpha E',
  M = W (2U)^(-1/2), L = G (2U)^(1/4), H_Moes = (h/R)(2U)^(-1/2).
* Hertz: b = R sqrt(8W/pi), p_h = E' sqrt(W/(2 pi)); Venner-Lubrecht
  H = h R / b^2 = pi H_Moes / (8 M), lambda-bar = 3 pi^2/(8 M^2),
  alpha-bar = alpha p_h = L sqrt(M/(2 pi)).

Roughness: the steady equations are solved with the composite roughness
frozen in place (d(rho h)/dt = 0 in seed 000 eq 2, i.e. a quasi-static
snapshot of the rough film); the composite roughness is the sum of the
profiles of both surfaces and enters seed 000 eq 3 with a positive sign (a
positive height *opens* the gap).  Where the film collapses (h <= 0 at any
node) the full-film model of seed 000 does not apply and
:class:`~gearfmu.ehl.errors.FilmCollapseError` is raised with the position
and the film parameter lambda = h_min / sigma (no asperity load sharing).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Callable, Dict, List, Optional, Sequence, Union

import numpy as np

from ..common.checks import finite_number
from .errors import EHLConvergenceError, EHLInputError, FilmCollapseError, stalled_residual
from .fits import moes_central_film
from .grids import (RETRY_BELOW_RESIDUAL, RETRY_CLOSE_RESIDUAL, RETRY_PROGRESS_FACTOR,
                    choose_grid, coarse_retry_grids, corner_rule_capped, effective_alpha,
                    refined_grid_intervals)
from .lubricant import ROELANDS_LN_ETA_INF, ROELANDS_P0_PA, DH_C1_PA
from .coarse_newton import COARSE_NEWTON_MAX_NODES
from .multigrid import EHLParams
from .film_newton import NEWTON_MAX_NODES, coupled_newton
from .iterate import (FREEZE_BELOW_PRESSURE_CHANGE, FROZEN_STALL_WINDOW, ROUGH_NEWTON_AFTER_CYCLES,
                      ROUGH_NEWTON_RAMP,
                      STALL_WINDOW, STOP_FILM_CHANGE_CAP, _flat_opts, _iterate_flat)
from .polish import POLISH_BEST_BELOW_RESIDUAL, _HIST_KEYS, _polish
from .roughness import _roughness_function, band_limit

#: Reference dimensional case used when only Moes' M and L are given
#: (Venner & Lubrecht 2000's standard mineral oil on steel): E' = 2.2e11 Pa,
#: R = 0.02 m, eta0 = 0.04 Pa s, alpha = 2.2e-8 1/Pa, rho0 = 870 kg/m^3.
#: With L = 0 the lubricant is isoviscous (alpha = 0) and U = 1e-11.
REFERENCE_CASE = dict(E_Pa=2.2e11, R_m=0.02, eta0_Pas=0.04, alpha_Pa_inv=2.2e-8,
                      rho0_kg_m3=870.0, U_isoviscous=1e-11)

Roughness = Union[None, Callable[[np.ndarray], np.ndarray],
                  tuple, Sequence]


@dataclass
class LineContactResult:
    """Result of :func:`solve_line_contact` (SI unless the name says otherwise)."""

    x_m: np.ndarray            #: grid, m (x = b X, origin at the Hertz centre)
    X: np.ndarray              #: grid, dimensionless x/b
    p_Pa: np.ndarray           #: pressure, Pa
    P: np.ndarray              #: pressure / p_h
    h_m: np.ndarray            #: film thickness, m
    H: np.ndarray              #: film thickness in Venner-Lubrecht scaling h R / b^2
    h_central_m: float         #: film thickness at x = 0, m
    h_min_m: float             #: minimum film thickness, m
    x_min_m: float             #: position of the minimum film, m
    H_central_moes: float      #: (h_central/R)(2U)^(-1/2)
    H_min_moes: float          #: (h_min/R)(2U)^(-1/2)
    M: float                   #: Moes load parameter
    L: float                   #: Moes material parameter
    b_m: float                 #: Hertz half width, m
    ph_Pa: float               #: Hertz maximum pressure, Pa
    load_N_per_m: float        #: integral of p dx, N/m
    iterations: int            #: number of W-cycles on the finest grid
    residuals: Dict[str, List[float]]  #: per-cycle histories
    converged: bool
    inputs: Dict[str, float]   #: dimensional inputs actually used (SI)
    roughness_m: np.ndarray    #: composite roughness on the grid, m
    wall_time_s: float = 0.0
    grid_levels: int = 0       #: number of multigrid levels used

    @property
    def h_central(self) -> float:
        """Alias of ``h_central_m`` (m)."""
        return self.h_central_m

    @property
    def h_min(self) -> float:
        """Alias of ``h_min_m`` (m)."""
        return self.h_min_m


#: Smooth films that stall on every setting and grid: the coupled Newton
#: (:func:`.film_newton.coupled_newton`) from at most this many stalled states (lowest
#: scaled residual first) on finest grids of at most NEWTON_MAX_NODES nodes, before
#: :class:`EHLConvergenceError` (docs/ehl.md "Robustness path").
SMOOTH_NEWTON_STATES = 4

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
#: ``stop_at_discretisation``; capped at :data:`STOP_FILM_CHANGE_CAP`), with the
#: scaled Reynolds residual below FAST_STOP_RESIDUAL (units of p_h) and the
#: relative load error below ``tol_load`` (the load balance has no
#: discretisation error; the finest pressure is scaled to the load when only
#: that is missing, :func:`.mgcycle._iterate`) -- or at the normal tolerances,
#: whichever comes first.  The algebraic film error left is then about a tenth
#: of the discretisation error or less (measured on 1025 nodes, Roelands,
#: L = 10: 0.005-0.04 of it at M = 20 and 100).
FAST_STOP_FRACTION = 0.25
FAST_STOP_RESIDUAL = 5e-6

#: default stopping tolerances (relative pressure change per cycle, relative load
#: error, scaled Reynolds residual in units of p_h)
DEFAULT_TOL_PRESSURE = 1e-5
DEFAULT_TOL_LOAD = 1e-6
DEFAULT_TOL_RESIDUAL = 1e-6

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


def _finite_positive(name, v, allow_zero=False):
    return finite_number(name, v, positive=not allow_zero, nonneg=allow_zero, error=EHLInputError)

def retry_made_progress(per_grid) -> bool:
    """Fail-fast rule 2: is a further retry grid worth trying?

    ``per_grid`` holds the best stalled scaled residual of each grid tried so far, in order.
    The next grid is tried only when the last one lowered the best residual of the grids
    before it ``RETRY_PROGRESS_FACTOR`` times, or stalled below ``RETRY_CLOSE_RESIDUAL``
    (close enough to convergence that a finer coarsest grid may finish it).
    """
    last = per_grid[-1]
    return last * RETRY_PROGRESS_FACTOR <= min(per_grid[:-1]) or last < RETRY_CLOSE_RESIDUAL


def solve_line_contact(R_m: float = None, E_Pa: float = None, w_N_per_m: float = None,
                       u_m_s: float = None, eta0_Pas: float = None,
                       alpha_Pa_inv: float = None, rho0_kg_m3: float = 870.0, *,
                       M: float = None, L: float = None,
                       roughness_m: Roughness = None,
                       compressible: bool = True, viscosity: str = "roelands",
                       n_nodes: Optional[int] = None, n_coarse: Optional[int] = None,
                       x_in: float = -4.5, x_out: float = 1.5,
                       tol_pressure: Optional[float] = None, tol_load: Optional[float] = None,
                       tol_residual: Optional[float] = None, tol_film: float = 1.0,
                       max_cycles: int = 60, min_cycles: int = 2,
                       fmg_cycles: int = 0, roughness_ramp=(1.0,),
                       initial: Optional["LineContactResult"] = None,
                       roughness_min_wavelength_dX: float = 8.0,
                       solver: str = "compiled", stop_at_discretisation: float = 0.0,
                       newton_after_cycles: Optional[int] = None,
                       **multigrid_options) -> LineContactResult:
    """Solve the steady isothermal line-contact EHL problem (seed 000 eq 2-7).

    Either the dimensional inputs ``R_m`` (m), ``E_Pa`` (reduced modulus E',
    Pa), ``w_N_per_m`` (N/m), ``u_m_s`` (mean entrainment speed, m/s),
    ``eta0_Pas`` (Pa s), ``alpha_Pa_inv`` (1/Pa), ``rho0_kg_m3`` (kg/m^3, only
    scales the density; the film does not depend on it) -- or Moes' ``M``
    and ``L`` (then the reference case :data:`REFERENCE_CASE` supplies the
    dimensional values).  ``roughness_m``: composite roughness (m) added to
    the gap (seed 000 eq 3): a function of x (m), an ``(x_m, z_m)`` pair of
    arrays, or a list of either (summed, e.g. one per surface).
    ``compressible`` switches Dowson-Higginson density on (default).
    Grid: ``n_nodes`` = n_coarse * 2^k + 1 nodes on [x_in, x_out] in units of
    the Hertz half-width b (default: chosen from the film, see
    :func:`choose_grid`).  Convergence: relative pressure change per W-cycle
    below ``tol_pressure``, relative load error below ``tol_load`` and the
    scaled Reynolds residual (mean |r_i / (dL_i/dP_i)| over pressurised
    nodes, in units of p_h) below ``tol_residual``; otherwise
    :class:`EHLConvergenceError` names the stalled residual.  ``None`` (the
    default for all three): 1e-5, 1e-6 and 1e-6, and the fast path may stop
    earlier, at its estimated discretisation error (below).
    With roughness the smooth solution is computed first and then continued
    through the amplitude steps ``roughness_ramp`` (last must be 1; default
    (1.0,): one step; a rough film that does not converge in one step is
    solved again in the steps :data:`.iterate.ROUGH_NEWTON_RAMP`, see ``newton_after_cycles``).
    ``viscosity``: "roelands" (seed 000 eq 5, default) or "barus"
    (exp(alpha p), the law behind Moes' fit; used by the validation tests).  Film collapse (h <= 0): :class:`FilmCollapseError`.

    Fast paths (added with the compiled solver, docs/ehl.md):

    * ``initial``: a :class:`LineContactResult` of a nearby problem (e.g. the
      neighbouring meshing position).  Its pressure P(x/b) and central film
      (converted to the new scaling) start the iteration and its relaxation
      settings are tried first; typically 2-4x fewer W-cycles.
    * ``roughness_min_wavelength_dX``: the roughness is sampled on the finest
      grid and low-pass filtered (FFT, ideal cut) to wavelengths of at least
      this many grid spacings (default 8; 0 switches filtering off), because
      shorter wavelengths are not resolved by the discretisation and make
      the relaxation limit-cycle.  ``result.roughness_m`` is the filtered
      profile actually used.
    * ``solver``: "compiled" (the only value; :mod:`.multigrid`).
    * ``newton_after_cycles`` (rough films; None: :data:`.iterate.ROUGH_NEWTON_AFTER_CYCLES`,
      0: off): the coupled Newton of the finest grid (:mod:`.film_newton`) after
      that many cycles with the roughness in place (docs/ehl.md "Rough films";
      ``residuals["coupled_newton_steps"]``); where that fails, once more with the
      roughness in the amplitude steps :data:`.iterate.ROUGH_NEWTON_RAMP`
      (``residuals["roughness_ramp_retry"]``).
    * ``tol_film``: also require the relative change per cycle of the
      central and minimum film below this (default 1: off; compiled solver).
    * ``fmg_cycles`` (compiled solver, smooth solves without ``initial``):
      > 0 starts with a full-multigrid pass (:meth:`.multigrid.FlatMultigrid.fmg_start`:
      coarse problem solved first on the coarsest grid with dX^2 <= H_c and the
      next finer one, cubic interpolation up, ``fmg_cycles`` cycles per level)
      instead of the Hertzian pressure; ``residuals["fmg_cycles_per_level"]``.
      The convergence test after it is the same.
    * ``stop_at_discretisation`` (with ``fmg_cycles`` > 0; default 0: off): stop
      the finest-grid cycles when the relative change per cycle of the central
      and minimum film and the load error are below this factor times the
      discretisation error of the central film estimated from the FMG levels
      (Richardson, second order: |H_l - H_(l-1)| / 3 on the last FMG level, a
      quarter of it on the finest grid; the tolerance is capped at
      :data:`STOP_FILM_CHANGE_CAP`) -- or when the normal tolerances are met.
      ``residuals["stopped_at_discretisation"]`` = [estimate, tolerance].  Only
      where the coarse grids resolve the solution (docs/ehl.md: low alpha_eff).

    Default path (docs/ehl.md): a smooth solve with default options first
    tries the fast path, :data:`FAST_SETTING` then :data:`FAST_ROBUST_SETTING`
    (F-cycles, Newton on the coarsest grid, full-multigrid start or
    ``initial``; ``residuals["fast_path"]``, ``residuals["fast_path_stage"]``); in the
    strongly piezoviscous corner the pairs of :data:`PIEZO_CORNER_PLAN` come first
    (``residuals["corner_plan_pair"]``).  Given no tolerance, the fast path
    stops at the discretisation error: when the relative change of the central
    and minimum film over a cycle is below :data:`FAST_STOP_FRACTION` times the
    FMG levels' Richardson estimate of the discretisation error of the central
    film (as ``stop_at_discretisation``, capped at :data:`STOP_FILM_CHANGE_CAP`;
    a warm start uses the estimate of ``initial`` on the same grid), with the
    scaled residual below :data:`FAST_STOP_RESIDUAL` and the load error below
    ``tol_load`` (the finest pressure scaled to the load when only that is
    missing) -- or at the tolerances.  Measured on 1025 nodes (Roelands, L = 10,
    M = 20 and 100): 3 cycles after the start, the central and minimum film
    within 0.005-0.04 of the discretisation error (about 1e-3 and 1e-2) of the
    same equations converged 1000x tighter.

    Robustness (compiled solver, docs/ehl.md): the relaxation settings of
    :data:`RELAXATION_SETTINGS` are tried in turn; a setting that stalls
    with a pressure change per cycle below
    :data:`FREEZE_BELOW_PRESSURE_CHANGE` continues with the finest-grid
    Gauss-Seidel/Jacobi switch frozen (``residuals["frozen_switch_from_cycle"]``);
    a smooth solve on an automatically chosen grid that fails on every
    setting is retried once on the grid of :func:`refined_grid_intervals`
    (``residuals["grid_refined"]``).  A setting that stalls close to a
    solution is continued by the block-Newton polish of the pressure-spike
    region (:func:`block_newton`, :func:`_polish`; ``residuals["newton_polish_rounds"]``,
    docs/ehl.md), and once every setting has failed on a grid the stalled
    states are polished, lowest residual first.  Every converged result meets
    the stated tolerances; otherwise :class:`EHLConvergenceError`.
    """
    t_start = time.perf_counter()
    # as given (EHLConvergenceError.problem)
    grid_given = dict(n_nodes=n_nodes, n_coarse=n_coarse, moes=M is not None or L is not None)
    # no tolerance given: the fast path may stop at the discretisation error (docs/ehl.md)
    default_tolerances = tol_pressure is None and tol_load is None and tol_residual is None
    tol_pressure = DEFAULT_TOL_PRESSURE if tol_pressure is None else float(tol_pressure)
    tol_load = DEFAULT_TOL_LOAD if tol_load is None else float(tol_load)
    tol_residual = DEFAULT_TOL_RESIDUAL if tol_residual is None else float(tol_residual)
    dimensional = [R_m, E_Pa, w_N_per_m, u_m_s, eta0_Pas, alpha_Pa_inv]
    if M is not None or L is not None:
        if M is None or L is None:
            raise EHLInputError("M and L must be given together")
        if any(v is not None for v in dimensional):
            raise EHLInputError("give either the dimensional inputs or M and L, not both")
        M = _finite_positive("M", M)
        L = _finite_positive("L", L, allow_zero=True)
        ref = REFERENCE_CASE
        E_Pa, R_m, eta0_Pas = ref["E_Pa"], ref["R_m"], ref["eta0_Pas"]
        if L > 0.0:
            alpha_Pa_inv = ref["alpha_Pa_inv"]
            U = 0.5 * (L / (alpha_Pa_inv * E_Pa)) ** 4
        else:
            alpha_Pa_inv = 0.0
            U = ref["U_isoviscous"]
        W = M * math.sqrt(2.0 * U)
        w_N_per_m = W * E_Pa * R_m
        u_m_s = U * E_Pa * R_m / eta0_Pas
    else:
        names = ["R_m", "E_Pa", "w_N_per_m", "u_m_s", "eta0_Pas", "alpha_Pa_inv"]
        for n_, v in zip(names, dimensional):
            if v is None:
                raise EHLInputError(f"{n_} is required (or give M and L)")
        R_m = _finite_positive("R_m", R_m)
        E_Pa = _finite_positive("E_Pa", E_Pa)
        w_N_per_m = _finite_positive("w_N_per_m", w_N_per_m)
        u_m_s = _finite_positive("u_m_s", u_m_s)
        eta0_Pas = _finite_positive("eta0_Pas", eta0_Pas)
        alpha_Pa_inv = _finite_positive("alpha_Pa_inv", alpha_Pa_inv, allow_zero=True)
        W = w_N_per_m / (E_Pa * R_m)
        U = eta0_Pas * u_m_s / (E_Pa * R_m)
        M = W / math.sqrt(2.0 * U)
        L = alpha_Pa_inv * E_Pa * (2.0 * U) ** 0.25
    rho0_kg_m3 = _finite_positive("rho0_kg_m3", rho0_kg_m3)
    A = math.log(eta0_Pas) - ROELANDS_LN_ETA_INF
    if A <= 0.0:
        raise EHLInputError(f"eta0_Pas={eta0_Pas!r} is below the Roelands limit 6.31e-5 Pa s")
    if not (x_in < -1.0 and x_out > 1.0):
        raise EHLInputError(f"x_in={x_in!r}, x_out={x_out!r}: the domain must contain [-1, 1]")
    b_m = R_m * math.sqrt(8.0 * W / math.pi)
    ph_Pa = E_Pa * math.sqrt(W / (2.0 * math.pi))
    lam = 3.0 * math.pi ** 2 / (8.0 * M ** 2)
    if viscosity == "roelands":
        z = alpha_Pa_inv * ROELANDS_P0_PA / A
        A_kernel = A
    elif viscosity == "barus":
        # Barus: eta = eta0 exp(alpha p); the kernel flags it with z < 0 and A = alpha p_h
        z = -1.0 if alpha_Pa_inv > 0 else 0.0
        A_kernel = alpha_Pa_inv * ph_Pa
    else:
        raise EHLInputError(f"viscosity={viscosity!r}: must be 'roelands' or 'barus'")
    prm = EHLParams(lam=lam, A=A_kernel, z=z, php0=ph_Pa / ROELANDS_P0_PA, c1=DH_C1_PA / ph_Pa,
                    compressible=bool(compressible), x_in=float(x_in), x_out=float(x_out))

    Hc_guess = math.pi * moes_central_film(M, L) / (8.0 * M)   # VL units
    user_grid = n_nodes is not None
    user_coarse = n_coarse is not None
    n_nodes, n_coarse, n_levels = choose_grid(Hc_guess, x_out - x_in, n_nodes, n_coarse,
                                              effective_alpha(prm))
    roughness_ramp = tuple(float(a) for a in roughness_ramp)
    if not roughness_ramp or roughness_ramp[-1] != 1.0:
        raise EHLInputError(f"roughness_ramp={roughness_ramp!r}: must end with 1.0")
    rfun = _roughness_function(roughness_m)
    scale_H = R_m / b_m ** 2  # h -> H
    lw = float(roughness_min_wavelength_dX)
    if not math.isfinite(lw) or lw < 0.0:
        raise EHLInputError(f"roughness_min_wavelength_dX={roughness_min_wavelength_dX!r}: "
                            "must be finite and >= 0")
    rough_fn = None
    if rfun is not None:
        Xf = np.linspace(x_in, x_out, n_nodes)
        zr = np.asarray(rfun(Xf * b_m), float)
        if zr.shape != Xf.shape or not np.all(np.isfinite(zr)):
            raise EHLInputError("roughness_m: must return finite heights (m), one per x")
        if lw > 0.0:
            zr = band_limit(zr, lw)
        zr_H = zr * scale_H

        def rough_fn(X):
            return np.interp(X, Xf, zr_H)

    if solver != "compiled":
        raise EHLInputError(f"solver={solver!r}: must be 'compiled' (the only multigrid core)")
    fmg_cycles = int(fmg_cycles)
    if fmg_cycles < 0:
        raise EHLInputError(f"fmg_cycles={fmg_cycles!r}: must be >= 0")
    sad = float(stop_at_discretisation)
    if not math.isfinite(sad) or sad < 0.0 or (sad > 0.0 and fmg_cycles == 0):
        raise EHLInputError(f"stop_at_discretisation={stop_at_discretisation!r}: must be "
                            ">= 0 and needs fmg_cycles > 0 (the estimate comes from the FMG levels)")
    newton_after = (ROUGH_NEWTON_AFTER_CYCLES if newton_after_cycles is None
                    else int(newton_after_cycles))
    if newton_after < 0:
        raise EHLInputError(f"newton_after_cycles={newton_after_cycles!r}: must be >= 0")
    if multigrid_options:
        attempts = [dict(multigrid_options)]
    else:
        attempts = [dict(a) for a in RELAXATION_SETTINGS]
    P_start = None
    if initial is not None:
        if not isinstance(initial, LineContactResult):
            raise EHLInputError("initial: must be a LineContactResult of an earlier solve")
        Hc_guess = initial.h_central_m * scale_H
        prev = initial.residuals.get("settings")
        if prev is not None and not multigrid_options:
            attempts = [dict(prev)] + [a for a in attempts if a != prev]
    # grids tried in turn: the default one and, for smooth solves on a grid
    # chosen here, one refined from the effective pressure-viscosity
    # coefficient (see refined_grid_intervals)
    grids = [(n_nodes, n_coarse, n_levels)]
    if not user_coarse and rfun is None:
        # same finest grid, finer coarsest grid (docs/ehl.md)
        grids += [choose_grid(Hc_guess, x_out - x_in, n_nodes, c)
                  for c in coarse_retry_grids(n_nodes - 1, n_coarse)]
    n_default = len(grids)
    if not user_grid and rfun is None:
        n_ref = refined_grid_intervals(prm, x_out - x_in, n_nodes - 1)
        if n_ref is not None:
            grids.append(choose_grid(Hc_guess, x_out - x_in, n_ref + 1, n_coarse))
    # fast path first (FAST_SETTING): default options, smooth
    fast_path = (not multigrid_options and rfun is None and fmg_cycles == 0 and sad == 0.0)
    fast_failed_cycles = 0
    # strongly piezoviscous corner: the piezoviscous coarsest-grid rule was capped
    plan_corner = (not multigrid_options and rfun is None and initial is None
                   and not user_coarse
                   and corner_rule_capped(effective_alpha(prm), x_out - x_in, n_coarse))
    collapsed = None
    tried = []          # (grid intervals, coarsest intervals, setting, final scaled residual)
    skipped = []        # why settings or grids were skipped (fail fast)
    done = {}           # (grid, setting) tried -> its stalled state for the polish, or None
    stalled = []        # smooth stalled states on grids the coupled Newton takes (last resort)

    def run(k_grid, k_att):
        """One relaxation setting on one grid; records a failure in ``tried``."""
        nonlocal collapsed
        n_nodes_, n_coarse_, n_levels_ = grids[k_grid]
        opts_ = attempts[k_att]
        s_obj, h_, conv, it_ = _iterate_flat(
            prm, n_levels_, n_coarse_, rough_fn, opts_, Hc_guess,
            P_start if k_att == 0 else None, max_cycles, min_cycles, tol_pressure,
            tol_load, tol_residual, tuple(roughness_ramp), tol_film,
            fmg=fmg_cycles if rough_fn is None else 0,
            stop_at_discretisation=float(stop_at_discretisation), newton_after=newton_after)
        if not conv and rough_fn is not None and newton_after > 0 and len(roughness_ramp) == 1:
            # the roughness in steps, coupled Newton on each (docs/ehl.md "Rough films")
            s2, h2, conv, it2 = _iterate_flat(
                prm, n_levels_, n_coarse_, rough_fn, opts_, Hc_guess,
                P_start if k_att == 0 else None, max_cycles, min_cycles, tol_pressure,
                tol_load, tol_residual, ROUGH_NEWTON_RAMP, tol_film, newton_after=newton_after)
            if conv:
                s_obj, h_, it_ = s2, h2, it_ + it2
                h_["roughness_ramp_retry"] = list(ROUGH_NEWTON_RAMP)
        if conv:
            return True, s_obj, h_, it_
        rr = h_["reynolds_residual"]
        tried.append((n_nodes_ - 1, n_coarse_, k_att,
                      float(rr[-1]) if rr and math.isfinite(rr[-1]) else math.inf))
        if (rfun is None and newton_after > 0 and rr and math.isfinite(rr[-1])
                and n_nodes_ <= NEWTON_MAX_NODES and "hit_max_cycles" not in h_):
            # (a setting stopped by the caller's cycle limit has not stalled: no Newton either)
            stalled.append((float(rr[-1]), k_grid, k_att, s_obj, h_, opts_, it_))
        # remember the last attempt that ended with a collapsed film (h <= 0):
        # if no attempt converges, that is reported (FilmCollapseError) rather
        # than the stall of whichever setting happened to run last
        H_end = s_obj.level_H()
        if rfun is not None and np.all(np.isfinite(H_end)) and float(np.min(H_end)) <= 0.0:
            collapsed = (s_obj, h_, opts_, k_att, k_grid, it_)
        # stalled states close to a solution (final scaled residual below
        # POLISH_BEST_BELOW_RESIDUAL, not yet polished) for the polish below
        entry = None
        if (rr and math.isfinite(rr[-1]) and "newton_polish_rounds" not in h_
                and "newton_polish_early_rounds" not in h_ and "hit_max_cycles" not in h_
                and rr[-1] < POLISH_BEST_BELOW_RESIDUAL
                and s_obj.opts.get("order2", 1) and not s_obj.opts.get("defect", 0)):
            entry = (rr[-1], k_att, s_obj, h_, opts_, it_)
        done[(k_grid, k_att)] = entry
        return False, s_obj, h_, it_

    converged = False
    k_grid, k_att, opts = 0, 0, attempts[0]
    n_nodes, n_coarse, n_levels = grids[0]
    if fast_path and n_coarse + 1 <= COARSE_NEWTON_MAX_NODES:
        # from the given solution (warm start) or a full-multigrid start
        P_fast = None
        disc_prev = None
        stages = ((FAST_SETTING, FAST_FMG_COARSE_CYCLES),
                  (FAST_ROBUST_SETTING, FAST_ROBUST_FMG_COARSE_CYCLES))
        if initial is not None:
            P_fast = np.interp(np.linspace(x_in, x_out, n_nodes), initial.X, initial.P,
                               left=0.0, right=0.0)
            stages = stages[1:]
            # the discretisation error estimated by the solve of ``initial`` on the same grid
            if initial.X.size == n_nodes and "stopped_at_discretisation" in initial.residuals:
                disc_prev = initial.residuals["stopped_at_discretisation"][0]
        for k_fast, (setting, coarse_cycles) in enumerate(stages):
            solver_obj, hist, converged, it = _iterate_flat(
                prm, n_levels, n_coarse, None, setting, Hc_guess, P_fast,
                min(max_cycles, FAST_MAX_CYCLES), min_cycles, tol_pressure, tol_load,
                tol_residual, (1.0,), tol_film, fmg=0 if initial is not None else FAST_FMG_CYCLES,
                continuation=False, stall_window=FAST_STALL_WINDOW,
                stop_at_discretisation=(FAST_STOP_FRACTION if default_tolerances
                                        and tol_film >= 1.0 else 0.0),
                stop_residual=FAST_STOP_RESIDUAL, fmg_coarse_cycles=coarse_cycles,
                disc_estimate=disc_prev)
            if converged:
                hist["fast_path"] = [1.0]
                # 0: FAST_SETTING, 1: FAST_ROBUST_SETTING
                hist["fast_path_stage"] = [float(k_fast + 2 - len(stages))]
                opts = dict(RELAXATION_SETTINGS[0])     # the relaxation it used
                break
            fast_failed_cycles += it
    if not converged and plan_corner:
        # strongly piezoviscous corner (docs/ehl.md): the pairs of PIEZO_CORNER_PLAN
        # first; the coarse-grid retry only under fail-fast rule 1
        for kg, ka in PIEZO_CORNER_PLAN:
            if kg >= n_default or ka >= len(attempts):
                continue
            g0 = (grids[0][0] - 1, grids[0][1])
            if kg > 0 and not min((t_[3] for t_ in tried if t_[:2] == g0),
                                  default=math.inf) < RETRY_BELOW_RESIDUAL:
                break
            converged, solver_obj, hist, it = run(kg, ka)
            entry = done.get((kg, ka))
            if not converged and entry is not None and entry[0] < PLAN_POLISH_BELOW_RESIDUAL:
                # its stalled state polished at once (as after all settings below;
                # a state further from the solution waits for that polish)
                ok, nr, ph = _polish(entry[2], tol_pressure, tol_load, tol_residual, tol_film,
                                     max_cycles)
                done[(kg, ka)] = None
                if ok:
                    hist["newton_polish_from_cycle"] = [it]
                    hist["newton_polish_rounds"] = [nr]
                    for k_ in _HIST_KEYS:
                        hist[k_].extend(ph[k_])
                    it += nr
                    converged = True
            if converged:
                k_grid, k_att, opts = kg, ka, attempts[ka]
                n_nodes, n_coarse, n_levels = grids[kg]
                hist["corner_plan_pair"] = [float(kg), float(ka)]
                break
    for k_grid, (n_nodes, n_coarse, n_levels) in enumerate(grids if not converged else []):
        if k_grid > 0:
            # fail fast (rules 1 and 2 above): best stalled residual per grid so far
            per_grid = [min((t_[3] for t_ in tried if t_[:2] == (g[0] - 1, g[1])),
                            default=math.inf) for g in grids[:k_grid]]
            if not per_grid[0] < RETRY_BELOW_RESIDUAL:
                skipped.append(f"retry grids not tried: best scaled residual on the default "
                               f"grid {per_grid[0]:.1e} >= {RETRY_BELOW_RESIDUAL:.0e}")
                break
            if k_grid > 1 and not retry_made_progress(per_grid):
                skipped.append(f"{len(grids) - k_grid} further retry grid(s) not tried: the "
                               f"last one ({grids[k_grid - 1][0] - 1}/{grids[k_grid - 1][1]}"
                               f" intervals) reached {per_grid[-1]:.1e}, neither "
                               f"{RETRY_PROGRESS_FACTOR:g}x below {min(per_grid[:-1]):.1e} "
                               f"nor below {RETRY_CLOSE_RESIDUAL:.0e}")
                break
        if initial is not None:
            Xg = np.linspace(x_in, x_out, n_nodes)
            P_start = np.interp(Xg, initial.X, initial.P, left=0.0, right=0.0)
        for k_att, opts in enumerate(attempts):
            if (k_grid, k_att) in done:
                continue
            converged, solver_obj, hist, it = run(k_grid, k_att)
            if converged:
                break
        # every setting failed on this grid: polish the stalled states, lowest
        # residual first, until one converges (docs/ehl.md: Barus M = 500, L = 15 converges only from setting 5's
        # state, whose residual is not the lowest)
        best = [e for (g, _), e in done.items() if g == k_grid and e is not None]
        for _, b_att, b_obj, b_hist, b_opts, b_it in sorted(best, key=lambda t: t[:2]):
            if converged:
                break
            ok, nr, ph = _polish(b_obj, tol_pressure, tol_load, tol_residual, tol_film,
                                 max_cycles)
            if ok:
                b_hist["newton_polish_from_cycle"] = [b_it]
                b_hist["newton_polish_rounds"] = [nr]
                for k_ in _HIST_KEYS:
                    b_hist[k_].extend(ph[k_])
                solver_obj, hist, opts, k_att, it = b_obj, b_hist, b_opts, b_att, b_it + nr
                converged = True
        if converged:
            break
    if not converged and stalled:
        # last resort for a smooth film that every setting, polish and grid left stalled: the
        # coupled Newton of the finest grid (film_newton.py) from the stalled states, lowest
        # residual first (Barus M = 5.5, L = 22: all ten settings stall at pressure changes of
        # 1e-2, the Newton converges from eight of their states to the same film)
        for _, b_grid, b_att, b_obj, b_hist, b_opts, b_it in sorted(
                stalled, key=lambda t_: t_[:3])[:SMOOTH_NEWTON_STATES]:
            ok, ns, nh = coupled_newton(b_obj, tol_pressure, tol_load, tol_residual)
            if ok and tol_film < 1.0 and not (nh["film_change"] and nh["film_change"][-1] < tol_film):
                ok = False
            if ok:
                for k_ in _HIST_KEYS:
                    b_hist[k_].extend(nh[k_])
                b_hist["coupled_newton_from_cycle"] = [float(b_it)]
                b_hist["coupled_newton_steps"] = [float(ns)]
                solver_obj, hist, opts, k_att, k_grid, it = b_obj, b_hist, b_opts, b_att, b_grid, b_it + ns
                n_nodes, n_coarse, n_levels = grids[k_grid]
                converged = True
                break
    if not converged and collapsed is not None:
        solver_obj, hist, opts, k_att, k_grid, it = collapsed
    if len(grids) > n_default:
        hist["grid_refined"] = [1.0 if k_grid >= n_default else 0.0]
    if 0 < k_grid < n_default:
        hist["coarse_grid_retry"] = [float(n_coarse)]
    hist["settings"] = opts
    hist["attempt"] = k_att
    if fast_failed_cycles:
        hist["fast_path_failed_cycles"] = [float(fast_failed_cycles)]
    X = solver_obj.X[solver_obj.top]
    H = solver_obj.level_H().copy()
    P_top = solver_obj.level_P().copy()
    rough_top = solver_obj.rough[solver_obj._sl(solver_obj.top)]
    load_top = solver_obj.load()
    x_m = X * b_m
    h_m = H / scale_H
    rough_m = rough_top / scale_H
    imin = int(np.argmin(h_m))
    sigma_m = float(np.std(rough_m)) if rfun is not None else 0.0
    # smooth surfaces: a film <= 0 left by a setting that did not converge is a
    # diverged iterate, not a collapse of the full film -> EHLConvergenceError below
    if np.all(np.isfinite(h_m)) and h_m[imin] <= 0.0 and (converged or rfun is not None):
        lam_f = h_m[imin] / sigma_m if sigma_m > 0 else float("-inf")
        raise FilmCollapseError(
            f"film collapse: h = {h_m[imin]:.3e} m <= 0 at x = {x_m[imin]:.4e} m "
            f"(X = {X[imin]:.3f}); film parameter lambda = h_min/sigma = {lam_f:.3f} "
            f"(sigma = {sigma_m:.3e} m); the full-film model (seed 000) does not hold",
            x_m=float(x_m[imin]), film_parameter=float(lam_f), h_min_m=float(h_m[imin]))
    if not converged:
        last, name, val, tol = stalled_residual(hist, tol_pressure, tol_residual, tol_load)
        fin = [t_ for t_ in tried if math.isfinite(t_[3])]
        b_ = min(fin, key=lambda t_: t_[3]) if fin else None
        best_txt = (f"; best stalled scaled residual {b_[3]:.2e} (attempt {b_[2]}, "
                    f"{b_[0]}/{b_[1]} intervals)" if b_ else "")
        # the problem exactly as solved (full precision: a rounded M or L names a
        # neighbouring problem, which may well converge)
        problem = (dict(M=M, L=L, rho0_kg_m3=rho0_kg_m3) if grid_given["moes"] else
                   dict(R_m=R_m, E_Pa=E_Pa, w_N_per_m=w_N_per_m, u_m_s=u_m_s, eta0_Pas=eta0_Pas,
                        alpha_Pa_inv=alpha_Pa_inv, rho0_kg_m3=rho0_kg_m3))
        problem.update(viscosity=viscosity, compressible=bool(compressible), x_in=float(x_in),
                       x_out=float(x_out))
        problem.update({k_: grid_given[k_] for k_ in ("n_nodes", "n_coarse") if grid_given[k_] is not None})
        raise EHLConvergenceError(
            f"EHL multigrid did not converge in {it} W-cycles (M={M!r}, L={L!r}, "
            f"{viscosity}, {'compressible' if compressible else 'incompressible'}"
            f"{', rough' if rfun is not None else ''}): "
            f"residual '{name}' stalled at {val:.3e} (tolerance {tol:.1e}); "
            f"reynolds_residual={last['reynolds_residual']:.3e}{best_txt}; "
            f"{len(tried)} setting(s) on {len({t_[:2] for t_ in tried})} grid(s) tried in "
            f"{time.perf_counter() - t_start:.2f} s"
            + "".join(f"; {x}" for x in skipped),
            residual_name=name, value=val, history=hist,
            best_residual=b_[3] if b_ else float("nan"), attempts=tried, skipped=skipped,
            problem=problem)

    # central film: linear interpolation at X = 0
    h_c = float(np.interp(0.0, X, h_m))
    s2U = math.sqrt(2.0 * U)
    p_Pa = P_top * ph_Pa
    return LineContactResult(
        x_m=x_m, X=X.copy(), p_Pa=p_Pa, P=P_top.copy(), h_m=h_m, H=H.copy(),
        h_central_m=h_c, h_min_m=float(h_m[imin]), x_min_m=float(x_m[imin]),
        H_central_moes=h_c / R_m / s2U, H_min_moes=float(h_m[imin]) / R_m / s2U,
        M=M, L=L, b_m=b_m, ph_Pa=ph_Pa, load_N_per_m=float(load_top * ph_Pa * b_m),
        iterations=it, residuals=hist, converged=True,
        grid_levels=n_levels,
        inputs=dict(R_m=R_m, E_Pa=E_Pa, w_N_per_m=w_N_per_m, u_m_s=u_m_s,
                    eta0_Pas=eta0_Pas, alpha_Pa_inv=alpha_Pa_inv, rho0_kg_m3=rho0_kg_m3),
        roughness_m=rough_m, wall_time_s=time.perf_counter() - t_start)
