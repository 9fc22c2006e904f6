"""Steady line-contact EHL solver, Zhao et al. 2022 eq 2-7 and Algorithm 1.

Public entry point: :func:`solve_line_contact`.  See :mod:`.multigrid` for the
equations and the numerical method, and docs/ehl.md for the choices made.

Definitions (SI; Moes 1992 / Venner & Lubrecht 2000 conventions):

* ``R_m``: reduced radius of curvature, 1/R = 1/R1 + 1/R2.
* ``E_Pa``: reduced modulus E' = 2 / ((1 - nu1^2)/E1 + (1 - nu2^2)/E2)
  (the E' of Moes and Venner-Lubrecht and the E of Zhao et al. 2022 eq 4).
* ``w_N_per_m``: load per unit length of contact.
* ``u_m_s``: entrainment (mean) speed u_m = (u1 + u2)/2 (Zhao et al. 2022 eq 2's u_s).
* Moes' parameters: W = w/(E'R), U = eta0 u_m/(E'R), G = alpha E',
  M = W (2U)^(-1/2), L = G (2U)^(1/4), H_Moes = (h/R)(2U)^(-1/2).
* Hertz: b = R sqrt(8W/pi), p_h = E' sqrt(W/(2 pi)); Venner-Lubrecht
  H = h R / b^2 = pi H_Moes / (8 M), lambda-bar = 3 pi^2/(8 M^2),
  alpha-bar = alpha p_h = L sqrt(M/(2 pi)).

Roughness: the steady equations are solved with the composite roughness
frozen in place (d(rho h)/dt = 0 in Zhao et al. 2022 eq 2, i.e. a quasi-static
snapshot of the rough film); the composite roughness is the sum of the
profiles of both surfaces and enters Zhao et al. 2022 eq 3 with a positive sign (a
positive height *opens* the gap).  Where the film collapses (h <= 0 at any
node) the full-film model of Zhao et al. 2022 does not apply and
:class:`~gearfmu.ehl.errors.FilmCollapseError` is raised with the position
and the film parameter lambda = h_min / sigma (no asperity load sharing).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from dataclasses import fields as dataclass_fields
from typing import Callable, Dict, List, Mapping, Optional, Sequence, Union

import numpy as np

from ..common.checks import finite_number
from .attempts import RELAXATION_SETTINGS, Attempt, SteadyWalk, retry_made_progress, walk_chain
from .errors import EHLConvergenceError, EHLInputError, FilmCollapseError, stalled_residual
from .fits import moes_central_film
from .grids import choose_grid, coarse_retry_grids, corner_rule_capped, effective_alpha, refined_grid_intervals
from .iterate import ROUGH_NEWTON_AFTER_CYCLES, CycleSettings
from .lubricant import ROELANDS_LN_ETA_INF, ROELANDS_P0_PA, DH_C1_PA
from .multigrid import EHLParams
from .roughness import _roughness_function, band_limit

#: the public names; RELAXATION_SETTINGS and retry_made_progress are those of :mod:`.attempts`
__all__ = ["solve_line_contact", "LineContactSettings", "LineContactResult", "LineContactProblem",
           "line_contact_problem", "REFERENCE_CASE", "DEFAULT_TOL_PRESSURE", "DEFAULT_TOL_LOAD",
           "DEFAULT_TOL_RESIDUAL", "RELAXATION_SETTINGS", "retry_made_progress"]

#: Reference dimensional case used when only Moes' M and L are given
#: (Venner & Lubrecht 2000's standard mineral oil on steel): E' = 2.2e11 Pa,
#: R = 0.02 m, eta0 = 0.04 Pa s, alpha = 2.2e-8 1/Pa, rho0 = 870 kg/m^3.
#: With L = 0 the lubricant is isoviscous (alpha = 0) and U = 1e-11.
REFERENCE_CASE = dict(E_Pa=2.2e11, R_m=0.02, eta0_Pas=0.04, alpha_Pa_inv=2.2e-8,
                      rho0_kg_m3=870.0, U_isoviscous=1e-11)

Roughness = Union[None, Callable[[np.ndarray], np.ndarray],
                  tuple, Sequence]

#: default stopping tolerances (relative pressure change per cycle, relative load
#: error, scaled Reynolds residual in units of p_h)
DEFAULT_TOL_PRESSURE = 1e-5
DEFAULT_TOL_LOAD = 1e-6
DEFAULT_TOL_RESIDUAL = 1e-6


@dataclass(frozen=True)
class LineContactSettings:
    """How :func:`solve_line_contact` solves: the laws of the equations, the grid, the stop, the
    iteration and the roughness handling.  Each field may also be given to the solver as a keyword
    of the same name (``solve_line_contact(M=20, L=10, n_nodes=513)``), which overrides the value
    of the ``settings`` passed; a keyword that is not a field is a relaxation option (``relaxation``).

    * Equations: ``viscosity`` "roelands" (Zhao et al. 2022 eq 5, default) or "barus" (exp(alpha p), the
      law behind Moes' fit; used by the validation tests); ``compressible``: Dowson-Higginson
      density (Zhao et al. 2022 eq 6, default on).
    * Grid: ``n_nodes`` = n_coarse * 2^k + 1 nodes on [``x_in``, ``x_out``] in units of the Hertz
      half-width b (None: chosen from the film, :func:`.grids.choose_grid`; so is ``n_coarse``, the
      coarsest grid's intervals).
    * Stop: relative pressure change per W-cycle below ``tol_pressure``, relative load error
      below ``tol_load`` and the scaled Reynolds residual (mean |r_i / (dL_i/dP_i)| over
      pressurised nodes, in units of p_h) below ``tol_residual``; ``None`` (the default for all
      three): :data:`DEFAULT_TOL_PRESSURE`, :data:`DEFAULT_TOL_LOAD`, :data:`DEFAULT_TOL_RESIDUAL`,
      and the fast path may stop earlier, at its estimated discretisation error (docs/ehl.md).
      ``tol_film``: also require the relative change per cycle of the central and minimum film
      below this (default 1: off).
    * Iteration: at most ``max_cycles`` and at least ``min_cycles`` cycles per setting.
      ``fmg_cycles`` > 0 (smooth solves without ``initial``): a full-multigrid start
      (:meth:`.multigrid.FlatMultigrid.fmg_start`: the coarse problem solved first on the
      coarsest grid with dX^2 <= H_c and the next finer one, cubic interpolation up,
      ``fmg_cycles`` cycles per level) instead of the Hertzian pressure
      (``residuals["fmg_cycles_per_level"]``).  ``stop_at_discretisation`` (with ``fmg_cycles``
      > 0; 0: off): stop the finest-grid cycles when the relative change per cycle of the central
      and minimum film and the load error are below this factor times the discretisation error
      of the central film estimated from the FMG levels (Richardson, second order:
      |H_l - H_(l-1)| / 3 on the last FMG level, a quarter of it on the finest grid; the
      tolerance is capped at :data:`.iterate.STOP_FILM_CHANGE_CAP`) -- or at the tolerances;
      ``residuals["stopped_at_discretisation"]`` = [estimate, tolerance]; only where the coarse
      grids resolve the solution (docs/ehl.md: low alpha_eff).  ``newton_after_cycles`` (rough
      films; None: :data:`.iterate.ROUGH_NEWTON_AFTER_CYCLES`, 0: off): the coupled Newton of
      the finest grid (:mod:`.film_newton`) after that many cycles with the roughness in place
      (docs/ehl.md "Rough films"; ``residuals["coupled_newton_steps"]``); where that fails, once
      more with the roughness in the amplitude steps :data:`.iterate.ROUGH_NEWTON_RAMP`
      (``residuals["roughness_ramp_retry"]``).  For a smooth film it enables the coupled Newton
      as the last resort of the chain of attempts (0: the settings' path alone).
    * Roughness: the smooth solution is computed first and continued through the amplitude
      steps ``roughness_ramp`` (last must be 1; default one step).  The roughness is sampled on
      the finest grid and low-pass filtered (FFT, ideal cut) to wavelengths of at least
      ``roughness_min_wavelength_dX`` grid spacings (default 8; 0: no filter), because shorter
      wavelengths are not resolved by the discretisation and make the relaxation limit-cycle;
      ``result.roughness_m`` is the filtered profile used.
    * ``solver``: "compiled" (the only multigrid core, :mod:`.multigrid`).
    * ``relaxation``: one option dict of :mod:`.multigrid` (e.g. ``multigrid.SPEED_SETTING``)
      run instead of the chain of attempts of :mod:`.attempts` (then no fast path, no fallback
      setting, no retry grid); None: the chain.
    """

    viscosity: str = "roelands"
    compressible: bool = True
    n_nodes: Optional[int] = None
    n_coarse: Optional[int] = None
    x_in: float = -4.5
    x_out: float = 1.5
    tol_pressure: Optional[float] = None
    tol_load: Optional[float] = None
    tol_residual: Optional[float] = None
    tol_film: float = 1.0
    max_cycles: int = 60
    min_cycles: int = 2
    fmg_cycles: int = 0
    stop_at_discretisation: float = 0.0
    newton_after_cycles: Optional[int] = None
    roughness_ramp: tuple = (1.0,)
    roughness_min_wavelength_dX: float = 8.0
    solver: str = "compiled"
    relaxation: Optional[Mapping] = None

    @property
    def default_tolerances(self) -> bool:
        """No tolerance given: the fast path may stop at the discretisation error."""
        return self.tol_pressure is None and self.tol_load is None and self.tol_residual is None


_SETTINGS_FIELDS = frozenset(f.name for f in dataclass_fields(LineContactSettings))


def _settings_from(settings: Optional[LineContactSettings], fields: dict) -> LineContactSettings:
    """``settings`` (None: the defaults) with the keyword form ``fields`` applied: settings
    fields replace the value, other keywords are relaxation options (added to ``relaxation``)."""
    if settings is None:
        settings = LineContactSettings()
    elif not isinstance(settings, LineContactSettings):
        raise EHLInputError(f"settings: must be a LineContactSettings, got {type(settings).__name__}")
    mine = {k: v for k, v in fields.items() if k in _SETTINGS_FIELDS}
    options = {k: v for k, v in fields.items() if k not in _SETTINGS_FIELDS}
    if options:
        mine["relaxation"] = dict(mine.get("relaxation", settings.relaxation) or {}, **options)
    return replace(settings, **mine) if mine else settings


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


@dataclass(frozen=True)
class LineContactProblem:
    """A steady line contact as solved: the dimensional inputs (SI), Moes' parameters M, L and
    U = eta0 u_m/(E'R), the Hertz half-width ``b_m`` and pressure ``ph_Pa``, and the kernel
    parameters ``prm`` (Venner & Lubrecht's scaling, module docstring).  ``moes``: given as M, L."""

    R_m: float
    E_Pa: float
    w_N_per_m: float
    u_m_s: float
    eta0_Pas: float
    alpha_Pa_inv: float
    rho0_kg_m3: float
    M: float
    L: float
    U: float
    b_m: float
    ph_Pa: float
    prm: EHLParams
    moes: bool

    @property
    def scale_H(self) -> float:
        """Film in Venner-Lubrecht units per film in m: R / b^2."""
        return self.R_m / self.b_m ** 2

    def inputs(self) -> Dict[str, float]:
        """The dimensional inputs (SI), ``LineContactResult.inputs``."""
        return dict(R_m=self.R_m, E_Pa=self.E_Pa, w_N_per_m=self.w_N_per_m, u_m_s=self.u_m_s,
                    eta0_Pas=self.eta0_Pas, alpha_Pa_inv=self.alpha_Pa_inv, rho0_kg_m3=self.rho0_kg_m3)

    def posed(self, s: LineContactSettings) -> dict:
        """The keyword arguments of :func:`solve_line_contact` that pose this problem again in full
        precision (inputs as given, laws, domain, a grid the caller gave; ``EHLConvergenceError.problem``)."""
        out = (dict(M=self.M, L=self.L, rho0_kg_m3=self.rho0_kg_m3) if self.moes else self.inputs())
        out.update(viscosity=s.viscosity, compressible=bool(s.compressible), x_in=float(s.x_in),
                   x_out=float(s.x_out))
        out.update({k: getattr(s, k) for k in ("n_nodes", "n_coarse") if getattr(s, k) is not None})
        return out


def _finite_positive(name, v, allow_zero=False):
    return finite_number(name, v, positive=not allow_zero, nonneg=allow_zero, error=EHLInputError)


def line_contact_problem(R_m, E_Pa, w_N_per_m, u_m_s, eta0_Pas, alpha_Pa_inv, rho0_kg_m3, M, L,
                         s: LineContactSettings) -> LineContactProblem:
    """The checked problem of :func:`solve_line_contact`: the dimensional inputs, or Moes' M and L
    on :data:`REFERENCE_CASE`; W = w/(E'R), U = eta0 u_m/(E'R), M = W (2U)^(-1/2),
    L = alpha E' (2U)^(1/4); Hertz b = R sqrt(8W/pi), p_h = E' sqrt(W/(2 pi)); the kernel's
    lambda-bar = 3 pi^2/(8 M^2), Roelands A = ln eta0 + 9.67 and z = alpha p0/A (Zhao et al. 2022 eq 5)
    or Barus (flagged z < 0, A = alpha p_h), Dowson-Higginson c1/p_h (eq 6)."""
    dimensional = [R_m, E_Pa, w_N_per_m, u_m_s, eta0_Pas, alpha_Pa_inv]
    moes = M is not None or L is not None
    if moes:
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
    x_in, x_out = s.x_in, s.x_out
    if not (x_in < -1.0 and x_out > 1.0):
        raise EHLInputError(f"x_in={x_in!r}, x_out={x_out!r}: the domain must contain [-1, 1]")
    b_m = R_m * math.sqrt(8.0 * W / math.pi)
    ph_Pa = E_Pa * math.sqrt(W / (2.0 * math.pi))
    lam = 3.0 * math.pi ** 2 / (8.0 * M ** 2)
    if s.viscosity == "roelands":
        z = alpha_Pa_inv * ROELANDS_P0_PA / A
        A_kernel = A
    elif s.viscosity == "barus":
        # Barus: eta = eta0 exp(alpha p); the kernel flags it with z < 0 and A = alpha p_h
        z = -1.0 if alpha_Pa_inv > 0 else 0.0
        A_kernel = alpha_Pa_inv * ph_Pa
    else:
        raise EHLInputError(f"viscosity={s.viscosity!r}: must be 'roelands' or 'barus'")
    prm = EHLParams(lam=lam, A=A_kernel, z=z, php0=ph_Pa / ROELANDS_P0_PA, c1=DH_C1_PA / ph_Pa,
                    compressible=bool(s.compressible), x_in=float(x_in), x_out=float(x_out))
    return LineContactProblem(R_m, E_Pa, w_N_per_m, u_m_s, eta0_Pas, alpha_Pa_inv, rho0_kg_m3, M, L, U,
                              b_m, ph_Pa, prm, moes)


def solve_line_contact(R_m: float = None, E_Pa: float = None, w_N_per_m: float = None,
                       u_m_s: float = None, eta0_Pas: float = None,
                       alpha_Pa_inv: float = None, rho0_kg_m3: float = 870.0, *,
                       M: float = None, L: float = None, roughness_m: Roughness = None,
                       initial: Optional[LineContactResult] = None,
                       settings: Optional[LineContactSettings] = None, **fields) -> LineContactResult:
    """Solve the steady isothermal line-contact EHL problem (Zhao et al. 2022 eq 2-7).

    Either the dimensional inputs ``R_m`` (m), ``E_Pa`` (reduced modulus E',
    Pa), ``w_N_per_m`` (N/m), ``u_m_s`` (mean entrainment speed, m/s),
    ``eta0_Pas`` (Pa s), ``alpha_Pa_inv`` (1/Pa), ``rho0_kg_m3`` (kg/m^3, only
    scales the density; the film does not depend on it) -- or Moes' ``M``
    and ``L`` (then the reference case :data:`REFERENCE_CASE` supplies the
    dimensional values).  ``roughness_m``: composite roughness (m) added to
    the gap (Zhao et al. 2022 eq 3): a function of x (m), an ``(x_m, z_m)`` pair of
    arrays, or a list of either (summed).  ``initial``: a :class:`LineContactResult`
    of a nearby problem (e.g. the neighbouring meshing position): its pressure P(x/b)
    and central film (converted to the new scaling) start the iteration and its
    relaxation setting is tried first; typically 2-4x fewer W-cycles.

    ``settings``: a :class:`LineContactSettings` (laws, grid, tolerances, iteration,
    roughness handling, relaxation); each of its fields may be given as a keyword
    instead (``solve_line_contact(M=100, L=10, viscosity="barus", n_nodes=1025)``),
    and a keyword that is no field is a relaxation option of :mod:`.multigrid`
    (``solve_line_contact(M=20, L=5, **multigrid.SPEED_SETTING)``).

    The solve walks the chain of attempts of :mod:`.attempts` until one converges
    (docs/ehl.md): the fast path (smooth films with the default options:
    :data:`.attempts.FAST_SETTING` then :data:`.attempts.FAST_ROBUST_SETTING`, F-cycles with
    Newton on the coarsest grid and at the pressure spike, from a full-multigrid start or
    ``initial``; ``residuals["fast_path"]``, ``residuals["fast_path_stage"]``; with no
    tolerance given it stops at the discretisation error), the plan of the strongly
    piezoviscous corner (:data:`.attempts.PIEZO_CORNER_PLAN`; ``residuals["corner_plan_pair"]``),
    the relaxation settings of :data:`RELAXATION_SETTINGS` in turn on the default grid
    and, failing fast, on the coarse-grid retries and a refined grid (each setting
    continued where it stalls by the switch freeze and the block-Newton polish, the
    stalled states polished; ``residuals["frozen_switch_from_cycle"]``,
    ``residuals["newton_polish_rounds"]``, ``residuals["coarse_grid_retry"]``,
    ``residuals["grid_refined"]``), and for smooth films the coupled Newton from the
    stalled states.  Every converged result meets the stated tolerances; otherwise
    :class:`EHLConvergenceError` names the stalled residual, the best residual reached,
    what was skipped and the problem posed again in full precision.  With roughness the
    steady equations are solved with the roughness frozen in place (module docstring);
    a film that reaches h <= 0 raises :class:`FilmCollapseError`.
    """
    t_start = time.perf_counter()
    s = _settings_from(settings, fields)
    problem = line_contact_problem(R_m, E_Pa, w_N_per_m, u_m_s, eta0_Pas, alpha_Pa_inv, rho0_kg_m3, M, L, s)
    walk = _steady_walk(problem, s, roughness_m, initial)
    found = walk_chain(walk)
    return _result(problem, s, walk, found if found is not None else walk.failure(), found is not None,
                   t_start)


def _steady_walk(problem: LineContactProblem, s: LineContactSettings, roughness_m,
                 initial: Optional[LineContactResult]) -> SteadyWalk:
    """The walk of a solve: the start film (Moes' fit, or ``initial``'s), the grids (the default
    grid of :func:`.grids.choose_grid`; for smooth films on a grid chosen here the coarse-grid
    retries and the refined grid), the roughness on the finest grid, the order of the
    relaxation settings (``initial``'s first) and how each is iterated."""
    prm = problem.prm
    Hc_guess = math.pi * moes_central_film(problem.M, problem.L) / (8.0 * problem.M)   # VL units
    length = s.x_out - s.x_in
    n_nodes, n_coarse, n_levels = choose_grid(Hc_guess, length, s.n_nodes, s.n_coarse, effective_alpha(prm))
    ramp = tuple(float(a) for a in s.roughness_ramp)
    if not ramp or ramp[-1] != 1.0:
        raise EHLInputError(f"roughness_ramp={s.roughness_ramp!r}: must end with 1.0")
    rough_fn = _sampled_roughness(roughness_m, problem, s, n_nodes)
    if s.solver != "compiled":
        raise EHLInputError(f"solver={s.solver!r}: must be 'compiled' (the only multigrid core)")
    fmg_cycles = int(s.fmg_cycles)
    if fmg_cycles < 0:
        raise EHLInputError(f"fmg_cycles={fmg_cycles!r}: must be >= 0")
    sad = float(s.stop_at_discretisation)
    if not math.isfinite(sad) or sad < 0.0 or (sad > 0.0 and fmg_cycles == 0):
        raise EHLInputError(f"stop_at_discretisation={s.stop_at_discretisation!r}: must be "
                            ">= 0 and needs fmg_cycles > 0 (the estimate comes from the FMG levels)")
    newton_after = ROUGH_NEWTON_AFTER_CYCLES if s.newton_after_cycles is None else int(s.newton_after_cycles)
    if newton_after < 0:
        raise EHLInputError(f"newton_after_cycles={s.newton_after_cycles!r}: must be >= 0")
    options = bool(s.relaxation)
    order = [dict(s.relaxation)] if options else [dict(a) for a in RELAXATION_SETTINGS]
    if initial is not None:
        if not isinstance(initial, LineContactResult):
            raise EHLInputError("initial: must be a LineContactResult of an earlier solve")
        Hc_guess = initial.h_central_m * problem.scale_H
        prev = initial.residuals.get("settings")
        if prev is not None and not options:
            order = [dict(prev)] + [a for a in order if a != prev]
    grids = [(n_nodes, n_coarse, n_levels)]
    if s.n_coarse is None and rough_fn is None:
        # same finest grid, finer coarsest grid (docs/ehl.md)
        grids += [choose_grid(Hc_guess, length, n_nodes, c) for c in coarse_retry_grids(n_nodes - 1, n_coarse)]
    n_default = len(grids)
    if s.n_nodes is None and rough_fn is None:
        # a finer grid from the effective pressure-viscosity coefficient (refined_grid_intervals)
        n_ref = refined_grid_intervals(prm, length, n_nodes - 1)
        if n_ref is not None:
            grids.append(choose_grid(Hc_guess, length, n_ref + 1, n_coarse))
    tol = (DEFAULT_TOL_PRESSURE if s.tol_pressure is None else float(s.tol_pressure),
           DEFAULT_TOL_LOAD if s.tol_load is None else float(s.tol_load),
           DEFAULT_TOL_RESIDUAL if s.tol_residual is None else float(s.tol_residual))
    cycles = CycleSettings(s.max_cycles, s.min_cycles, *tol, tol_film=s.tol_film, ramp=ramp,
                           fmg=fmg_cycles if rough_fn is None else 0, stop_at_discretisation=sad,
                           newton_after=newton_after)
    default_path = not options and rough_fn is None
    return SteadyWalk(
        prm, rough_fn, Hc_guess, grids, n_default, order, cycles, (s.x_in, s.x_out), initial,
        fast_path=default_path and fmg_cycles == 0 and sad == 0.0,
        # strongly piezoviscous corner: the piezoviscous coarsest-grid rule was capped
        corner_plan=(default_path and initial is None and s.n_coarse is None
                     and corner_rule_capped(effective_alpha(prm), length, n_coarse)),
        default_tolerances=s.default_tolerances)


def _sampled_roughness(roughness_m, problem: LineContactProblem, s: LineContactSettings, n_nodes: int):
    """The composite roughness as a function of X in film units (None: smooth): sampled on the
    finest grid's ``n_nodes`` nodes, band-limited to ``s.roughness_min_wavelength_dX`` grid
    spacings (:func:`.roughness.band_limit`), interpolated linearly between the nodes."""
    rfun = _roughness_function(roughness_m)
    lw = float(s.roughness_min_wavelength_dX)
    if not math.isfinite(lw) or lw < 0.0:
        raise EHLInputError(f"roughness_min_wavelength_dX={s.roughness_min_wavelength_dX!r}: "
                            "must be finite and >= 0")
    if rfun is None:
        return None
    Xf = np.linspace(s.x_in, s.x_out, n_nodes)
    zr = np.asarray(rfun(Xf * problem.b_m), float)
    if zr.shape != Xf.shape or not np.all(np.isfinite(zr)):
        raise EHLInputError("roughness_m: must return finite heights (m), one per x")
    if lw > 0.0:
        zr = band_limit(zr, lw)
    zr_H = zr * problem.scale_H

    def rough_fn(X):
        return np.interp(X, Xf, zr_H)
    return rough_fn


def _result(problem: LineContactProblem, s: LineContactSettings, walk: SteadyWalk, a: Attempt,
            converged: bool, t_start: float) -> LineContactResult:
    """The result of the attempt ``a`` the walk reports (its path marked in its history), or the
    error: :class:`FilmCollapseError` where the film is h <= 0 somewhere (a converged film, or
    a rough one that did not converge), :class:`EHLConvergenceError` where nothing converged."""
    walk.mark_path(a)
    solver = a.solver
    X = solver.X[solver.top]
    H = solver.level_H().copy()
    P_top = solver.level_P().copy()
    rough_top = solver.rough[solver._sl(solver.top)]
    load_top = solver.load()
    b_m, ph_Pa, R_m = problem.b_m, problem.ph_Pa, problem.R_m
    x_m = X * b_m
    h_m = H / problem.scale_H
    rough_m = rough_top / problem.scale_H
    imin = int(np.argmin(h_m))
    sigma_m = float(np.std(rough_m)) if walk.rough_fn is not None else 0.0
    # smooth surfaces: a film <= 0 left by a setting that did not converge is a
    # diverged iterate, not a collapse of the full film -> EHLConvergenceError below
    if np.all(np.isfinite(h_m)) and h_m[imin] <= 0.0 and (converged or walk.rough_fn is not None):
        lam_f = h_m[imin] / sigma_m if sigma_m > 0 else float("-inf")
        raise FilmCollapseError(
            f"film collapse: h = {h_m[imin]:.3e} m <= 0 at x = {x_m[imin]:.4e} m "
            f"(X = {X[imin]:.3f}); film parameter lambda = h_min/sigma = {lam_f:.3f} "
            f"(sigma = {sigma_m:.3e} m); the full-film model (seed 000) does not hold",
            x_m=float(x_m[imin]), film_parameter=float(lam_f), h_min_m=float(h_m[imin]))
    if not converged:
        raise _convergence_error(problem, s, walk, a, t_start)
    # central film: linear interpolation at X = 0
    h_c = float(np.interp(0.0, X, h_m))
    s2U = math.sqrt(2.0 * problem.U)
    return LineContactResult(
        x_m=x_m, X=X.copy(), p_Pa=P_top * ph_Pa, P=P_top.copy(), h_m=h_m, H=H.copy(),
        h_central_m=h_c, h_min_m=float(h_m[imin]), x_min_m=float(x_m[imin]),
        H_central_moes=h_c / R_m / s2U, H_min_moes=float(h_m[imin]) / R_m / s2U,
        M=problem.M, L=problem.L, b_m=b_m, ph_Pa=ph_Pa, load_N_per_m=float(load_top * ph_Pa * b_m),
        iterations=a.cycles, residuals=a.hist, converged=True, grid_levels=walk.grids[a.k_grid][2],
        inputs=problem.inputs(), roughness_m=rough_m, wall_time_s=time.perf_counter() - t_start)


def _convergence_error(problem: LineContactProblem, s: LineContactSettings, walk: SteadyWalk, a: Attempt,
                       t_start: float) -> EHLConvergenceError:
    """The error of a walk in which nothing converged: the residual that stalled in the attempt
    reported, the best stalled residual of all (attempt and grid), how many settings on how
    many grids were tried, what was skipped, and the problem posed again (the message's M and L
    in full precision: a rounded value names a neighbouring problem, which may converge)."""
    c = walk.cycles
    last, name, val, tol = stalled_residual(a.hist, c.tol_pressure, c.tol_residual, c.tol_load)
    fin = [t_ for t_ in walk.tried if math.isfinite(t_[3])]
    b_ = min(fin, key=lambda t_: t_[3]) if fin else None
    best_txt = (f"; best stalled scaled residual {b_[3]:.2e} (attempt {b_[2]}, "
                f"{b_[0]}/{b_[1]} intervals)" if b_ else "")
    return EHLConvergenceError(
        f"EHL multigrid did not converge in {a.cycles} W-cycles (M={problem.M!r}, L={problem.L!r}, "
        f"{s.viscosity}, {'compressible' if s.compressible else 'incompressible'}"
        f"{', rough' if walk.rough_fn is not None else ''}): "
        f"residual '{name}' stalled at {val:.3e} (tolerance {tol:.1e}); "
        f"reynolds_residual={last['reynolds_residual']:.3e}{best_txt}; "
        f"{len(walk.tried)} setting(s) on {len({t_[:2] for t_ in walk.tried})} grid(s) tried in "
        f"{time.perf_counter() - t_start:.2f} s"
        + "".join(f"; {x}" for x in walk.skipped),
        residual_name=name, value=val, history=a.hist,
        best_residual=b_[3] if b_ else float("nan"), attempts=walk.tried, skipped=walk.skipped,
        problem=problem.posed(s))
