"""Transient line-contact EHL with roughness moving with the surfaces.

Equations (Zhao et al. 2022 eq 2-3 keeping the squeeze term; docs/ehl_transient.md
section 1), Venner & Lubrecht 2000 scaling X = x/b, P = p/p_h, H = h R/b^2
and **T = t u_s/b** (u_s the entrainment speed):

    d/dX( eps dP/dX ) - d(rho H)/dX - d(rho H)/dT = 0                 (eq 2)
    H(X, T) = H0(T) + X^2/2 + V(P)(X) + W(X, T)                         (eq 3-4)
    W(X, T) = (R/b^2) [ z1(xi1) + z2(xi2) ],  xi_i = b (X - U_i T)      (eq 3, wm)
    dX sum P = pi/2 at every T                                          (eq 7)

A material point of surface i moves through the contact at u_i, so its
height pattern is advected at U_i = u_i/u_s: U1 = 1 + SRR/2, U2 = 1 - SRR/2
(SRR = (u1 - u2)/u_s, the definition of :func:`.mesh_film.contact_kinematics`).
For a gear flank slice (:class:`FlankSliceRoughness`) this is wm(x, t) =
z1(a1(t) - x) + z2(a2(t) + x) with da1/dt = u1, da2/dt = -u2 (involute arc
length a = rho^2/(2 r_b), docs/ehl_transient.md).

Time discretisation (choice, docs/ehl_transient.md): dT = dX
by default (Courant number 1 on u_s) with the convective and time derivatives
taken together along the characteristic,
d(rho H)/dX + d(rho H)/dT ~ [1.5 (rho H)^n_i - 2 (rho H)^(n-1)_(i-1)
+ 0.5 (rho H)^(n-2)_(i-2)]/dX (our reading of Venner & Lubrecht 2000's transient
scheme; a film wave moving at u_s is shifted without numerical damping); or
BDF2, d(rho H)/dT ~ [3 (rho H)^n - 4 (rho H)^(n-1) + (rho H)^(n-2)]/(2 dT), after a
BDF1 (implicit Euler) first step, with the steady wedge term (the design note's
first choice; it damps waves with fewer than ~40 nodes per wavelength, measured).
The implicit part c_t (rho H)^n is in the compiled multigrid operator
(:mod:`.mgkernels`, options ``c_t``, ``c_char``), the old levels are its
finest-grid right-hand side.  Each step: warm start from the previous step (P and H0 linearly
extrapolated from the last two levels, P clipped at 0), W-cycles until the
steady tolerances are met (load balance inside the cycles, so eq 7 holds per
step), the settings of :data:`TRANSIENT_RELAXATION_SETTINGS` then those of
:data:`.attempts.RELAXATION_SETTINGS` if it stalls; a step that stalls on every
setting is re-solved as 2, then 4 BDF2 sub-steps (roughness at the sub-step
times; rough flanks stall on limit cycles / residual floors at asperity
pressure spikes, docs/ehl_transient.md), and only if that fails too raises
:class:`.errors.EHLConvergenceError` naming the step and time.

Roughness is evaluated from the surfaces' own profiles at every step (no
band limit, unlike the steady solver's default 8 dX filter: choice, the
flank profiles' W-M band limit f_max = 1e4 1/m is 14 dX on the default
256-interval seed grid, docs/ehl_transient.md).  Cavitation stays P = max(P, 0)
(not mass conserving at internal cavities: risk R2 of the design note).

Outputs per step on the Hertz band |x| <= b: central and minimum film, mean
film and mean pressure, and the film stiffness k(t) = A B(p_m)/h_m of Zhao et al. 2022
eq 8 (:func:`.film_stiffness.film_stiffness_N_per_m`, ``method="seed"``:
A = 2 b width); the two time reductions of docs/ehl_transient.md
are :meth:`TransientLineContactResult.film_stiffness_reductions`.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable, Dict, Optional, Tuple, Union

import numpy as np

from .errors import EHLConvergenceError, EHLInputError, FilmCollapseError, stalled_residual
from .film_stiffness import film_stiffness_N_per_m
from .lubricant import (B0_DEFAULT_PA, B0_PRIME_DEFAULT, DH_C1_PA, ROELANDS_LN_ETA_INF,
                        ROELANDS_P0_PA)
from .transient_inputs import (TransientLubricant, TransientNumerics, TransientOperating,
                               _transient_inputs)
from .multigrid import EHLParams, FlatMultigrid
from .attempts import RELAXATION_SETTINGS
from .iterate import flat_options
from .solver import LineContactResult, solve_line_contact, solve_line_contact as _steady
from .mesh_film import contact_kinematics, involute_arc_length_m
from .transient_steps import SUBSTEP_SPLITS, MovingSurfaces, StepSettings, TimeStepper

#: Relaxation settings of the time steps, tried in this order (the one that
#: converged last is tried first at the next step), then the steady
#: :data:`.attempts.RELAXATION_SETTINGS`.  At M = 20, L = 10, 256 intervals,
#: waviness 0.1 H_c, lambda = 0.5 b (docs/ehl_transient.md):
#: the steady default (dipole distribution ``dist=0``) diverges within 2-5
#: steps once c_t > 0 (the time term sees the dipole's 1/r far field) and the
#: fallback omega_j = 0.1 needs ~14 cycles/step; the symmetric distribution
#: ``dist=1`` (-d/4 at the neighbours) needs 3.8 (omega_j 0.6), ``dist=2`` 4.8.
TRANSIENT_RELAXATION_SETTINGS = (
    dict(switch=0.3, nu1=2, nu2=1, omega_gs=0.6, omega_j=0.6, load_mode=1, c_h0=0.1,
         stick=10.0, dist=1),
    dict(switch=0.3, nu1=2, nu2=1, omega_gs=0.6, omega_j=0.5, load_mode=1, c_h0=0.1,
         stick=10.0, dist=2),
    dict(switch=0.3, nu1=2, nu2=2, omega_gs=0.4, omega_j=0.3, load_mode=1, c_h0=0.1,
         stick=10.0, dist=1, dmax=3.0),
    dict(switch=0.3, nu1=2, nu2=1, omega_gs=0.6, omega_j=0.1, load_mode=1, c_h0=0.1,
         stick=10.0),
)

#: averaging window after the wash-out (dimensionless time, CHOICE of
#: docs/ehl_transient.md: two contact widths at u_s)
T_AVERAGE = 4.0


# --------------------------------------------------------------------------- roughness inputs
@dataclass(frozen=True)
class HarmonicWaviness:
    """Harmonic waviness z(xi) = amplitude_m cos(2 pi xi / wavelength_m + phase_rad)
    on the surfaces listed in ``surfaces`` (1, 2 or both); xi (m) is the
    material coordinate of the surface (its position at t = 0).  A positive
    height opens the gap (Zhao et al. 2022 eq 3 sign of :mod:`.solver`)."""

    amplitude_m: float
    wavelength_m: float
    surfaces: Tuple[int, ...] = (1,)
    phase_rad: float = 0.0

    def __post_init__(self):
        if not (math.isfinite(self.amplitude_m) and self.amplitude_m >= 0.0):
            raise EHLInputError(f"amplitude_m={self.amplitude_m!r}: must be finite and >= 0 (m)")
        if not (math.isfinite(self.wavelength_m) and self.wavelength_m > 0.0):
            raise EHLInputError(f"wavelength_m={self.wavelength_m!r}: must be finite and > 0 (m)")
        s = tuple(self.surfaces)
        if not s or any(k not in (1, 2) for k in s) or len(set(s)) != len(s):
            raise EHLInputError(f"surfaces={self.surfaces!r}: must be (1,), (2,) or (1, 2)")
        if not math.isfinite(self.phase_rad):
            raise EHLInputError(f"phase_rad={self.phase_rad!r}: must be finite")

    def surface_height_m(self, surface: int, xi_m: np.ndarray) -> np.ndarray:
        if surface not in self.surfaces:
            return np.zeros_like(xi_m)
        return self.amplitude_m * np.cos(2.0 * math.pi * xi_m / self.wavelength_m
                                         + self.phase_rad)


@dataclass(frozen=True)
class FlankSliceRoughness:
    """The roughness of one face-width slice of a :class:`.mesh_film.FlankRoughness`
    at contact arc lengths ``a1_m``, ``a2_m`` (pinion / gear flank, m) at t = 0:
    wm(x, t) = z1(a1 + u1 t - x) + z2(a2 - u2 t + x) (Zhao et al. 2022 eq 3,
    ``FlankRoughness.composite_m`` with the flanks moving)."""

    flank: object
    slice_index: int
    a1_m: float
    a2_m: float

    def __post_init__(self):
        n = getattr(self.flank, "n_slices", None)
        if n is None:
            raise EHLInputError("flank: must be a gearfmu.ehl.mesh_film.FlankRoughness")
        if int(self.slice_index) != self.slice_index or not 0 <= self.slice_index < n:
            raise EHLInputError(f"slice_index={self.slice_index!r}: must be in 0..{n - 1}")
        for k in ("a1_m", "a2_m"):
            if not math.isfinite(getattr(self, k)):
                raise EHLInputError(f"{k}={getattr(self, k)!r}: must be finite (m)")

    def surface_height_m(self, surface: int, xi_m: np.ndarray) -> np.ndarray:
        fr, j = self.flank, int(self.slice_index)
        if surface == 1:
            return np.interp(self.a1_m - xi_m, fr.a1_m, fr.z1_m[j])
        return np.interp(self.a2_m + xi_m, fr.a2_m, fr.z2_m[j])


class _Profiles:
    """Two callables of the material coordinate xi (m) -> height (m)."""

    def __init__(self, f1, f2):
        self.f = (f1, f2)

    def surface_height_m(self, surface, xi_m):
        fn = self.f[surface - 1]
        if fn is None:
            return np.zeros_like(xi_m)
        z = np.asarray(fn(xi_m), float)
        if z.shape != xi_m.shape or not np.all(np.isfinite(z)):
            raise EHLInputError(f"roughness[{surface - 1}]: must return finite heights (m), "
                                "one per position")
        return z


RoughnessInput = Union[None, HarmonicWaviness, FlankSliceRoughness,
                       Tuple[Optional[Callable], Optional[Callable]]]


def _roughness_model(roughness):
    if roughness is None or isinstance(roughness, (HarmonicWaviness, FlankSliceRoughness)):
        return roughness
    if isinstance(roughness, tuple) and len(roughness) == 2 and \
            all(r is None or callable(r) for r in roughness):
        return _Profiles(*roughness)
    raise EHLInputError("roughness: must be None, HarmonicWaviness, FlankSliceRoughness or a "
                        "pair (z1, z2) of functions of the surface coordinate (m) or None")


# --------------------------------------------------------------------------- parameters
def dimensionless_params(res: LineContactResult, viscosity: str = "roelands",
                         compressible: bool = True) -> EHLParams:
    """The :class:`.multigrid.EHLParams` of a steady result (the formulas of
    :func:`.solver.solve_line_contact`: lambda-bar = 3 pi^2/(8 M^2), Roelands
    A = ln eta0 + 9.67, z = alpha p0/A (Zhao et al. 2022 eq 5) or Barus, D-H c1, eq 6)."""
    eta0, alpha = res.inputs["eta0_Pas"], res.inputs["alpha_Pa_inv"]
    A = math.log(eta0) - ROELANDS_LN_ETA_INF
    if viscosity == "roelands":
        z, A_k = alpha * ROELANDS_P0_PA / A, A
    elif viscosity == "barus":
        z, A_k = (-1.0 if alpha > 0 else 0.0), alpha * res.ph_Pa
    else:
        raise EHLInputError(f"viscosity={viscosity!r}: must be 'roelands' or 'barus'")
    return EHLParams(lam=3.0 * math.pi ** 2 / (8.0 * res.M ** 2), A=A_k, z=z,
                     php0=res.ph_Pa / ROELANDS_P0_PA, c1=DH_C1_PA / res.ph_Pa,
                     compressible=bool(compressible), x_in=float(res.X[0]),
                     x_out=float(res.X[-1]))


# --------------------------------------------------------------------------- result
@dataclass
class TransientLineContactResult:
    """Time series of :func:`solve_line_contact_transient` (SI unless named
    dimensionless).  Index 0 is the steady frozen-roughness start (T = 0)."""

    T: np.ndarray                  #: dimensionless time t u_s / b
    t_s: np.ndarray                #: time, s
    h_central_m: np.ndarray        #: film at x = 0, m
    h_min_m: np.ndarray            #: minimum film, m
    h_mean_m: np.ndarray           #: mean film on |x| <= b, m
    p_mean_Pa: np.ndarray          #: mean pressure on |x| <= b, Pa
    k_film_N_per_m: np.ndarray     #: Zhao et al. 2022 eq 8 film stiffness of a width_m slice, N/m
    cycles: np.ndarray             #: W-cycles per step (0 at T = 0)
    attempts: np.ndarray           #: index of the relaxation setting that converged per step
    dT: float                      #: time step, dimensionless (b/u_s units)
    dt_s: float                    #: time step, s
    scheme: str
    U1: float                      #: u1/u_s
    U2: float                      #: u2/u_s
    width_m: float                 #: slice width used for k, m
    x_m: np.ndarray                #: grid, m
    X: np.ndarray                  #: grid, x/b
    p_Pa: np.ndarray               #: pressure at the last step, Pa
    h_m: np.ndarray                #: film at the last step, m
    b_m: float
    ph_Pa: float
    M: float
    L: float
    steady: LineContactResult      #: the steady start (T = 0)
    cpu_time_s: float              #: process time of the time loop, s
    wall_time_s: float             #: wall time of the time loop, s
    settings: Dict = field(default_factory=dict)   #: relaxation setting of the last step
    start: str = "frozen"              #: "frozen" or "smooth" (roughness ramped in)
    ramp_T: float = 0.0                #: ramp duration of the smooth start (dimensionless)
    B0_Pa: float = B0_DEFAULT_PA       #: Tait B0 used for k, Pa (Zhao et al. 2022 eq 9)
    B0_prime: float = B0_PRIME_DEFAULT  #: Tait B0' used for k
    #: per step: 0, or the number of BDF2 sub-steps that rescued a stalled step
    rescued: Optional[np.ndarray] = None

    @property
    def srr(self) -> float:
        """Slide-to-roll ratio (u1 - u2)/u_s."""
        return self.U1 - self.U2

    @property
    def T_wash(self) -> float:
        """Dimensionless time for the start-up error to leave the domain with
        the slower moving surface: (x_out - x_in)/min(U1, U2) (0 if a surface is at rest)."""
        u = min(self.U1, self.U2)
        return 0.0 if u <= 0.0 else float(self.X[-1] - self.X[0]) / u

    @property
    def T_settled(self) -> float:
        """Start of the default averaging window: ramp_T + T_wash."""
        return self.ramp_T + self.T_wash

    def window(self, T_start: Optional[float] = None, T_end: Optional[float] = None) -> np.ndarray:
        """Boolean mask of the time levels with T_start <= T <= T_end (defaults:
        :attr:`T_settled` and the end of the run)."""
        a = self.T_settled if T_start is None else float(T_start)
        b = self.T[-1] if T_end is None else float(T_end)
        m = (self.T >= a - 1e-12) & (self.T <= b + 1e-12)
        if m.sum() < 2:
            raise EHLInputError(f"T_start={a!r}, T_end={b!r}: fewer than 2 time levels in the "
                                f"window (run ends at T = {self.T[-1]:.4g}); run more n_steps")
        return m

    def film_stiffness_reductions(self, T_start=None, T_end=None) -> Dict[str, float]:
        """docs/ehl_transient.md: (a) ``k_mean_of_k_N_per_m`` = <A B(p_m)/h_m>,
        (b) ``k_of_means_N_per_m`` = A B(<p_m>)/<h_m> (Zhao et al. 2022 eq 8 on time means),
        plus the window means of h_m, p_m and h_central."""
        m = self.window(T_start, T_end)
        kb = film_stiffness_N_per_m(2.0 * self.b_m * self.width_m, float(self.h_mean_m[m].mean()),
                                    float(self.p_mean_Pa[m].mean()), self.B0_Pa,
                                    self.B0_prime)
        return dict(k_mean_of_k_N_per_m=float(self.k_film_N_per_m[m].mean()),
                    k_of_means_N_per_m=float(kb), h_mean_m=float(self.h_mean_m[m].mean()),
                    p_mean_Pa=float(self.p_mean_Pa[m].mean()),
                    h_central_mean_m=float(self.h_central_m[m].mean()), n_samples=int(m.sum()))

    def central_amplitude_m(self, T_start=None, T_end=None) -> float:
        """Half the peak-to-peak of h_central over the window, m (the deformed
        amplitude A_d of Venner et al. 1997 for a harmonic waviness)."""
        m = self.window(T_start, T_end)
        return 0.5 * float(np.ptp(self.h_central_m[m]))


# --------------------------------------------------------------------------- solver
def _finite(name, v, lo=None, lo_open=False):
    try:
        v = float(v)
    except (TypeError, ValueError):
        raise EHLInputError(f"{name} must be a number, got {v!r}") from None
    if not math.isfinite(v) or (lo is not None and (v < lo or (lo_open and v == lo))):
        raise EHLInputError(f"{name}={v!r}: must be finite and {'>' if lo_open else '>='} {lo}")
    return v


def solve_line_contact_transient(operating: Optional[TransientOperating] = None,
                                 lubricant: Optional[TransientLubricant] = None,
                                 numerics: Optional[TransientNumerics] = None, *,
                                 roughness: RoughnessInput = None, width_m: float = 1.0,
                                 **fields) -> TransientLineContactResult:
    """Transient line-contact EHL (Zhao et al. 2022 eq 2-7 with d(rho h)/dt; module doc).

    Inputs in three groups, :class:`TransientOperating`, :class:`TransientLubricant`
    and :class:`TransientNumerics`; each of their fields may also be given as a
    keyword (``solve_line_contact_transient(M=20, L=10, n_steps=50)``), which
    overrides the group's value.  Fields as :func:`.solver.solve_line_contact`: the dimensional ``R_m``,
    ``E_Pa``, ``w_N_per_m``, ``u_m_s`` (entrainment speed u_s), ``eta0_Pas``,
    ``alpha_Pa_inv`` or Moes' ``M``, ``L``; the load is constant in time.
    ``roughness``: None (smooth), :class:`HarmonicWaviness`,
    :class:`FlankSliceRoughness` or a pair (z1, z2) of functions of each
    surface's material coordinate (m, its position at t = 0; None = smooth).
    Surface speeds: ``srr`` = (u1 - u2)/u_s (U1 = 1 + srr/2, U2 = 1 - srr/2)
    or ``speed_ratios`` = (U1, U2) directly (e.g. (0, 0): frozen roughness).
    ``dT``: time step in units of b/u_s (default dX, Courant 1); ``n_steps``:
    default (T_wash + T_AVERAGE)/dT with T_wash = (x_out - x_in)/min(U1, U2).
    ``scheme``: None (default: "characteristic" when dT = dX, else "bdf2"),
    "bdf2" (BDF1 first step), "bdf1" or "characteristic" (the
    convective and time derivatives together along the characteristic X - T at
    Courant 1, second order after a first-order step: [1.5 (rho H)^n_i -
    2 (rho H)^(n-1)_(i-1) + 0.5 (rho H)^(n-2)_(i-2)]/dX, after Venner & Lubrecht 2000's
    transient chapters; needs dT = dX; a wave of the film moving at u_s is
    shifted without numerical damping, docs/ehl_transient.md).  Per step: W-cycles until
    the relative pressure change < ``tol_pressure``, load error < ``tol_load``,
    scaled residual < ``tol_residual`` (the steady defaults).  ``width_m``,
    ``B0_Pa``, ``B0_prime``: slice width and Tait constants of k (Zhao et al. 2022 eq 8-9).
    ``steady_options``: extra keyword arguments of the steady start solve.
    ``extrapolate``: linear extrapolation of P, H0 from the last two steps as
    the warm start (False: the last step's P, H0).
    ``start``: "frozen" (default; T = 0 is the steady frozen-roughness film,
    docs/ehl_transient.md), "smooth" (T = 0 is the smooth steady film
    and the roughness amplitude is ramped linearly from 0 to 1 over ``ramp_T``;
    CHOICE for rough films whose steady frozen solve stalls, e.g. level 2) or
    "auto" ("frozen", and "smooth" if the frozen steady solve raises
    :class:`.errors.EHLConvergenceError`).  The averaging window then starts at
    ``ramp_T`` + T_wash (:attr:`TransientLineContactResult.T_settled`).
    ``relaxation_settings``: option dicts of :mod:`.multigrid` tried in turn per step
    (default :data:`TRANSIENT_RELAXATION_SETTINGS` then the steady ones).
    ``substep_rescue`` (default True): a step that stalls on every setting is
    re-solved as 2, then 4 BDF2 sub-steps with the roughness at the sub-step
    times (:data:`.transient_steps.SUBSTEP_SPLITS`, docs/ehl_transient.md; only stalled
    steps, so converging runs are unchanged); the steps rescued are
    :attr:`TransientLineContactResult.rescued`; "always": every step is solved
    as sub-steps (a verification mode of the rescue path)."""
    t_wall0 = time.perf_counter()
    op, lub, num = _transient_inputs((operating, lubricant, numerics), fields)
    ch = _checked_inputs(op, lub, num, roughness, width_m)
    steady, ramp = _steady_start(op, lub, num, ch)
    prm = dimensionless_params(steady, lub.viscosity, lub.compressible)
    n_nodes = steady.X.size
    n_levels = steady.grid_levels
    n_coarse = (n_nodes - 1) // 2 ** (n_levels - 1)
    b_m, ph_Pa, R = steady.b_m, steady.ph_Pa, steady.inputs["R_m"]
    u_s = steady.inputs["u_m_s"]
    scale_H = R / b_m ** 2
    first = dict(steady.residuals["settings"])
    solver = FlatMultigrid(prm, n_levels, n_coarse, None, **flat_options(first))
    dT, scheme, n_steps = _time_steps(num, ch.surfaces, float(solver.dx[solver.top]), ramp)
    dt_s = dT * b_m / u_s
    order = _settings_order(num.relaxation_settings)
    stepper = TimeStepper(solver, ch.surfaces, b_m, u_s, scale_H, ramp, StepSettings(
        order, ch.max_cycles, num.tol_pressure, num.tol_load, num.tol_residual, dT, scheme,
        num.extrapolate, ch.substep_rescue))
    stepper.set_time(0.0)
    solver.start(steady.P, float(np.interp(0.0, steady.X, steady.H)))
    rec = _Recorder(solver, n_steps, b_m, ph_Pa, scale_H, (dT, dt_s), 2.0 * b_m * ch.width_m,
                    (float(lub.B0_Pa), float(lub.B0_prime)))
    rec.record(0)
    stepper.keep_level()
    t_cpu0 = time.process_time()
    for n in range(1, n_steps + 1):
        ok, ncyc, h, m_used = stepper.step(n)
        rec.cycles[n] += ncyc
        rec.rescued[n] = m_used
        if not ok:
            raise _step_error(n, n_steps, stepper, h, (b_m, u_s))
        rec.attempts[n] = stepper.cur
        rec.record(n)
        stepper.keep_level()
    cpu = time.process_time() - t_cpu0
    Tv = np.arange(n_steps + 1) * dT
    Xt = rec.Xt
    return TransientLineContactResult(
        T=Tv, t_s=Tv * b_m / u_s, h_central_m=rec.out["hc"], h_min_m=rec.out["hmin"],
        h_mean_m=rec.out["hm"], p_mean_Pa=rec.out["pm"], k_film_N_per_m=rec.out["k"], cycles=rec.cycles,
        attempts=rec.attempts, dT=float(dT), dt_s=float(dt_s), scheme=scheme, U1=float(ch.surfaces.U1),
        U2=float(ch.surfaces.U2), width_m=ch.width_m, x_m=Xt * b_m, X=Xt.copy(),
        p_Pa=solver.level_P() * ph_Pa, h_m=solver.level_H() / scale_H, b_m=b_m, ph_Pa=ph_Pa,
        M=steady.M, L=steady.L, steady=steady, cpu_time_s=cpu,
        wall_time_s=time.perf_counter() - t_wall0,
        settings=dict(order[stepper.cur]), B0_Pa=rec.Bc[0], B0_prime=rec.Bc[1],
        start="smooth" if ramp > 0.0 else "frozen", ramp_T=float(ramp), rescued=rec.rescued)


@dataclass(frozen=True)
class _Checked:
    """The checked inputs of a transient solve that are not passed on as given."""

    surfaces: MovingSurfaces
    start: str
    ramp_T: float
    width_m: float
    max_cycles: int
    substep_rescue: Union[bool, str]
    steady_kw: dict


def _checked_inputs(op: TransientOperating, lub: TransientLubricant, num: TransientNumerics, roughness,
                    width_m) -> _Checked:
    """The roughness model and the surface speeds U1 = 1 + srr/2, U2 = 1 - srr/2 (or the given
    ``speed_ratios``), the start, the slice width, the cycle limit, the rescue and the steady
    start's options, each checked (EHLInputError naming the field)."""
    model = _roughness_model(roughness)
    if op.speed_ratios is not None:
        speed_ratios = op.speed_ratios
        if np.ndim(speed_ratios) != 1 or len(speed_ratios) != 2:
            raise EHLInputError(f"speed_ratios={speed_ratios!r}: must be a pair (U1, U2)")
        U1 = _finite("speed_ratios[0]", speed_ratios[0], 0.0)
        U2 = _finite("speed_ratios[1]", speed_ratios[1], 0.0)
    else:
        srr = _finite("srr", op.srr)
        if not -2.0 <= srr <= 2.0:
            raise EHLInputError(f"srr={srr!r}: must be in [-2, 2] (both surfaces moving in +x)")
        U1, U2 = 1.0 + 0.5 * srr, 1.0 - 0.5 * srr
    if num.start not in ("frozen", "smooth", "auto"):
        raise EHLInputError(f"start={num.start!r}: must be 'frozen', 'smooth' or 'auto'")
    ramp_T = _finite("ramp_T", num.ramp_T, 0.0, True)
    if num.scheme not in (None, "bdf1", "bdf2", "characteristic"):
        raise EHLInputError(f"scheme={num.scheme!r}: must be 'bdf1', 'bdf2' or 'characteristic'")
    width_m = _finite("width_m", width_m, 0.0, True)
    mc = int(num.max_cycles_per_step)
    if mc < 1:
        raise EHLInputError(f"max_cycles_per_step={num.max_cycles_per_step!r}: must be >= 1")
    if num.substep_rescue not in (True, False, "always"):
        raise EHLInputError(f"substep_rescue={num.substep_rescue!r}: must be True, False or 'always'")
    steady_kw = dict(num.steady_options or {})
    for k in ("roughness_m", "M", "L", "n_nodes", "n_coarse", "x_in", "x_out", "compressible",
              "viscosity"):
        if k in steady_kw:
            raise EHLInputError(f"steady_options: {k!r} is an argument of the transient solver")
    return _Checked(MovingSurfaces(model, U1, U2), num.start, ramp_T, width_m, mc, num.substep_rescue, steady_kw)


def _steady_start(op: TransientOperating, lub: TransientLubricant, num: TransientNumerics, ch: _Checked):
    """The state at T = 0 (docs/ehl_transient.md): the steady film with the roughness frozen in
    place (start "frozen"), or the smooth steady film with the roughness then ramped in over
    ``ramp_T`` ("smooth"; "auto": where the frozen steady solve stalls).  The steady solve has
    no band filter (the transient roughness is not filtered either).  Returns (steady result,
    ramp duration; 0 for the frozen start)."""
    surfaces = ch.surfaces

    def frozen(x_m):
        return surfaces.height_m(np.asarray(x_m, float), 0.0, 1.0)
    rough0 = frozen if surfaces.model is not None else None

    def steady_solve(rough):
        return solve_line_contact(op.R_m, op.E_Pa, op.w_N_per_m, op.u_m_s, lub.eta0_Pas, lub.alpha_Pa_inv,
                                  lub.rho0_kg_m3, M=op.M, L=op.L, roughness_m=rough,
                                  compressible=lub.compressible, viscosity=lub.viscosity,
                                  n_nodes=num.n_nodes, n_coarse=num.n_coarse, x_in=num.x_in, x_out=num.x_out,
                                  tol_pressure=num.tol_pressure, tol_load=num.tol_load,
                                  tol_residual=num.tol_residual, roughness_min_wavelength_dX=0.0,
                                  **ch.steady_kw)

    if ch.start == "smooth" and surfaces.model is not None:
        return steady_solve(None), ch.ramp_T
    try:
        return steady_solve(rough0), 0.0
    except EHLConvergenceError:
        if ch.start != "auto" or surfaces.model is None:
            raise
        return steady_solve(None), ch.ramp_T


def _time_steps(num: TransientNumerics, surfaces: MovingSurfaces, dX: float, ramp: float):
    """(dT, scheme, number of steps): dT = dX by default (Courant 1 on u_s); the scheme
    "characteristic" where dT = dX (which it needs), else "bdf2"; by default the steps of
    ramp + T_wash + :data:`T_AVERAGE`, T_wash = (x_out - x_in)/min(U1, U2)."""
    dT = dX if num.dT is None else _finite("dT", num.dT, 0.0, True)
    scheme = num.scheme
    if scheme is None:
        scheme = "characteristic" if abs(dT / dX - 1.0) <= 1e-9 else "bdf2"
    if scheme == "characteristic" and abs(dT / dX - 1.0) > 1e-9:
        raise EHLInputError(f"dT={dT!r}: scheme 'characteristic' needs dT = dX = {dX!r}")
    U_min = min(surfaces.U1, surfaces.U2)
    T_wash = 0.0 if U_min <= 0 else (num.x_out - num.x_in) / U_min
    n_steps = num.n_steps
    if n_steps is None:
        n_steps = int(math.ceil((ramp + T_wash + T_AVERAGE) / dT))
    if int(n_steps) != n_steps or n_steps < 1:
        raise EHLInputError(f"n_steps={n_steps!r}: must be an integer >= 1")
    return dT, scheme, int(n_steps)


def _settings_order(relaxation_settings):
    """The relaxation settings of the time steps in the order first tried: the given ones, or
    :data:`TRANSIENT_RELAXATION_SETTINGS` then the steady ones not among them."""
    if relaxation_settings is None:
        order = [dict(s) for s in TRANSIENT_RELAXATION_SETTINGS]
        order += [dict(s) for s in RELAXATION_SETTINGS if dict(s) not in order]
        return order
    order = [dict(s) for s in relaxation_settings]
    if not order:
        raise EHLInputError("relaxation_settings: need at least one settings dict")
    return order


class _Recorder:
    """The outputs per time level on the Hertz band |x| <= b (module docstring): central and
    minimum film, mean film and mean pressure, and the film stiffness k = A B(p_m)/h_m of seed
    000 eq 8 of the slice area ``area`` (m^2) with the Tait constants ``Bc`` = (B0, B0')."""

    def __init__(self, solver, n_steps, b_m, ph_Pa, scale_H, steps, area, Bc):
        self.solver, self.b_m, self.ph_Pa, self.scale_H = solver, b_m, ph_Pa, scale_H
        self.dT, self.dt_s = steps
        self.area, self.Bc = area, Bc
        self.Xt = solver.X[solver.top]
        self.band = np.abs(self.Xt) <= 1.0
        nT = n_steps + 1
        self.out = {k: np.empty(nT) for k in ("hc", "hmin", "hm", "pm", "k")}
        self.cycles = np.zeros(nT, dtype=np.int64)
        self.attempts = np.zeros(nT, dtype=np.int64)
        self.rescued = np.zeros(nT, dtype=np.int64)

    def record(self, n: int) -> None:
        """The outputs of time level ``n``; a film not finite or h <= 0 anywhere raises."""
        H = self.solver.level_H()
        P = self.solver.level_P()
        h = H / self.scale_H
        Xt, b_m, dT, out = self.Xt, self.b_m, self.dT, self.out
        if not np.all(np.isfinite(h)):
            raise EHLConvergenceError(f"transient step {n} (T = {n * dT:.4g}): film not finite",
                                      "pressure_change", float("nan"))
        imin = int(np.argmin(h))
        if h[imin] <= 0.0:
            raise FilmCollapseError(
                f"film collapse at transient step {n} (T = {n * dT:.4g}, t = {n * self.dt_s:.4g} s): "
                f"h = {h[imin]:.3e} m <= 0 at x = {Xt[imin] * b_m:.4e} m; the full-film model "
                "(seed 000) does not hold", x_m=float(Xt[imin] * b_m), h_min_m=float(h[imin]))
        out["hc"][n] = float(np.interp(0.0, Xt, h))
        out["hmin"][n] = float(h[imin])
        out["hm"][n] = float(np.mean(h[self.band]))
        out["pm"][n] = float(np.mean(P[self.band])) * self.ph_Pa
        out["k"][n] = film_stiffness_N_per_m(self.area, out["hm"][n], out["pm"][n], *self.Bc)


def _step_error(n: int, n_steps: int, stepper: TimeStepper, h, scales) -> EHLConvergenceError:
    """The error of a step that converged on no setting (nor as sub-steps): the step, its time
    and the residual that stalled; ``scales`` = (b (m), u_s (m/s))."""
    st = stepper.steps
    b_m, u_s = scales
    T = n * st.dT
    last, name, val, tol = stalled_residual(h, st.tol_pressure, st.tol_residual, st.tol_load)
    return EHLConvergenceError(
        f"transient step {n} of {n_steps} (T = {T:.4g}, t = {T * b_m / u_s:.4g} s) did "
        f"not converge on any of {len(st.order)} relaxation settings"
        f"{' (nor as ' + '/'.join(map(str, SUBSTEP_SPLITS)) + ' BDF2 sub-steps)' if st.substep_rescue else ''}"
        f": residual '{name}' "
        f"stalled at {val:.3e} (tolerance {tol:.1e}); reynolds_residual="
        f"{last['reynolds_residual']:.3e}", residual_name=name, value=val, history=h)


# --------------------------------------------------------------------------- amplitude reduction
def waviness_nabla(wavelength_b: float, M: float, L: float) -> float:
    """Venner, Couhier, Lubrecht & Greenwood (1997) line-contact wavelength
    parameter nabla = (lambda/b) M^(3/4) / L^(1/2) (docs/ehl_transient.md)."""
    return float(wavelength_b) * float(M) ** 0.75 / math.sqrt(float(L))


def waviness_amplitude_ratio(M: float, L: float, wavelength_b: float,
                             amplitude_Hc: float = 0.1, *, surfaces=(1,), srr: float = 0.0,
                             n_nodes: int = 257, periods_averaged: int = 1,
                             steps_per_period: Optional[int] = None,
                             scheme: str = "characteristic", **kw) -> Dict[str, float]:
    """Amplitude reduction A_d/A_i of a harmonic waviness (Venner et al. 1997).

    Waviness of amplitude A_i = ``amplitude_Hc`` x the smooth steady central
    film on ``surfaces`` with wavelength ``wavelength_b`` x b, run from the
    steady frozen start through the wash-out T_wash = (x_out - x_in)/min(U1, U2)
    plus ``periods_averaged`` + 1 periods of the slowest wave pattern (period
    lambda/(b U) in T).  ``scheme`` "characteristic" (default): dT = dX and the
    wavelength is rounded to a whole number of steps per period (lambda = k U dX
    b, the returned ``wavelength_b`` and ``nabla`` are the ones used); other
    schemes: dT = period/k with k = ``steps_per_period`` or ceil(period/dX).  A_d = half the peak-to-peak of h(x = 0) over the last
    ``periods_averaged`` periods (the deformed amplitude at the contact centre,
    CHOICE: Venner et al.'s "amplitude at X = 0").  Returns A_d/A_i, nabla,
    the periodicity defect (max |h_c(T) - h_c(T - period)| / h_c over the last
    period), the mean cycles per step and the CPU time of the time loop."""
    M = _finite("M", M, 0.0, True)
    L = _finite("L", L, 0.0, True)
    wavelength_b = _finite("wavelength_b", wavelength_b, 0.0, True)
    amplitude_Hc = _finite("amplitude_Hc", amplitude_Hc, 0.0, True)
    smooth = _steady(M=M, L=L, n_nodes=n_nodes)
    U = [1.0 + 0.5 * srr, 1.0 - 0.5 * srr]
    Umin = min(U[s - 1] for s in surfaces)
    if Umin <= 0.0:
        raise EHLInputError(f"srr={srr!r}: the wavy surface must move (U > 0)")
    period = wavelength_b / Umin
    dX = float(smooth.X[1] - smooth.X[0])
    if scheme == "characteristic":
        if steps_per_period:
            raise EHLInputError("steps_per_period: the characteristic scheme fixes dT = dX "
                                "(the wavelength is rounded instead)")
        k = max(2, int(round(period / dX)))
        dT = dX
        wavelength_b = k * dX * Umin
    else:
        k = int(steps_per_period) if steps_per_period else int(math.ceil(period / dX))
        dT = period / k
    T_wash = float(smooth.X[-1] - smooth.X[0]) / min(U)
    n_steps = int(math.ceil(T_wash / dT)) + (int(periods_averaged) + 1) * k
    A_i = amplitude_Hc * smooth.h_central_m
    wav = HarmonicWaviness(A_i, wavelength_b * smooth.b_m, tuple(surfaces))
    r = solve_line_contact_transient(M=M, L=L, n_nodes=n_nodes, roughness=wav, srr=srr,
                                     dT=dT, n_steps=n_steps, scheme=scheme, **kw)
    hc = r.h_central_m
    last = hc[-k:]
    prev = hc[-2 * k:-k]
    A_d = 0.5 * float(np.ptp(hc[-int(periods_averaged) * k:]))
    return dict(M=M, L=L, wavelength_b=wavelength_b, nabla=waviness_nabla(wavelength_b, M, L),
                amplitude_Hc=amplitude_Hc, A_i_m=A_i, A_d_m=A_d, ratio=A_d / A_i,
                periodicity_defect=float(np.max(np.abs(last - prev)) / smooth.h_central_m),
                h_central_smooth_m=smooth.h_central_m, n_steps=n_steps, dT=dT,
                cycles_per_step=float(r.cycles[1:].mean()),
                cycles_per_step_max=int(r.cycles.max()), cpu_time_s=r.cpu_time_s, scheme=scheme,
                cpu_per_step_ms=1e3 * r.cpu_time_s / n_steps)


# --------------------------------------------------------------------------- gear contact
def flank_slice_case(env, s_m: float, w_N_per_m: float, slice_index: Optional[int] = None
                     ) -> Dict[str, object]:
    """Keyword arguments of :func:`solve_line_contact_transient` for one slice of
    a gear contact at LOA position ``s_m`` (m from N1) and line load
    ``w_N_per_m`` (option A of docs/ehl_transient.md: R, u_s, SRR and w frozen
    at the node, only the roughness moves).  ``env`` is a
    :class:`gearfmu.contact.models.ContactEnvironment`; R, u_s and the sliding
    speed from :func:`.mesh_film.contact_kinematics`, srr = (u1 - u2)/u_s, the
    flank arc lengths a_i = rho_i^2/(2 r_bi) at the contact (t = 0);
    ``slice_index`` None: smooth."""
    fenv = env.film_environment()
    R, u_s, slide = (float(np.asarray(v).ravel()[0]) for v in
                     contact_kinematics(env.geom, np.array([s_m], float), env.omega1_rad_s))
    kw = dict(R_m=R, E_Pa=fenv.E_prime_Pa, w_N_per_m=float(w_N_per_m), u_m_s=u_s,
              eta0_Pas=fenv.eta0_Pas, alpha_Pa_inv=fenv.alpha_Pa_inv, rho0_kg_m3=fenv.rho0_kg_m3,
              srr=slide / u_s, width_m=fenv.width_m, B0_Pa=fenv.B0_Pa, B0_prime=fenv.B0_prime)
    if slice_index is not None:
        a1 = float(involute_arc_length_m(env.geom.roll_length_at(1, s_m), env.geom.rb1_m))
        a2 = float(involute_arc_length_m(env.geom.roll_length_at(2, s_m), env.geom.rb2_m))
        kw["roughness"] = FlankSliceRoughness(env.flanks(), int(slice_index), a1, a2)
    return kw
