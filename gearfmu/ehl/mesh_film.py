"""The EHL oil film along the line of action: contact kinematics, flank
roughness at the contact, and the film stiffness of each face-width slice of
each tooth pair at each meshing position (Zhao et al. 2022 eq 3, 8-10), solved
through a ``concurrent.futures``-style executor.  SI units throughout.

Kinematics of an involute contact (textbook: e.g. Johnson, *Contact
Mechanics*, 1985, ch. 13 on gears; ISO/TS 6336-22 uses the same sums):
the contact point at LOA position s (m from N1, the pinion's base-circle
tangent point) has the roll lengths s1 = s (pinion) and s2 = N1N2 - s (gear).
The radius of curvature of an involute at a point equals its roll length,
so the reduced radius of the two cylinders in contact is

    R = s1 s2 / (s1 + s2)                                     (1/R = 1/s1 + 1/s2).

Rolling (tangential) velocities: the pinion surface point at the contact has
velocity omega1 x r; its component along the common tangent (normal to the
LOA) is omega1 * s1, and likewise omega2 * s2 for the gear (the component
along the LOA, omega rb, is equal for both and is the motion of the contact
point itself).  With omega2 = omega1 z1/z2:

    u1 = omega1 s1,  u2 = omega1 (z1/z2) s2,
    u_s = (u1 + u2)/2   (Zhao et al. 2022 eq 2's entrainment velocity),
    sliding u1 - u2 = 0 at the pitch point, where u_s = omega1 r_w1 sin(alpha_w).

Roughness at the contact (Zhao et al. 2022 eq 3's wm; a CHOICE where the seed is
silent): every flank carries, on each slice, its own W-M profile along the
flank arc length a measured from the base circle, a = rho^2/(2 r_b) for roll
length rho (arc length of an involute).  Relative to the moving contact point
the pinion material flows towards its root and the gear material towards its
tip (both in the entrainment direction +x), so at local coordinate x the gap
holds the composite roughness

    wm(x) = z1_n(a1(s1) - x) + z2_n(a2(s2) + x).

The same realisation is used on every tooth of a gear (the tables then stay
periodic in the mesh period); slices and the two flanks are independent
(``numpy.random.SeedSequence(seed)``: child 0 pinion, child 1 gear, each
spawned per slice).  The roughness is band-limited to ``f_max_per_m`` (default
1e4 1/m: wavelengths >= 100 um, about 14 grid spacings of the default 256
interval EHL grid at the Zhao et al. 2022 operating point; finer roughness does not
converge, docs/ehl.md) -- the band limit keeps 63-77 % of the roughness
variance of the Table 2 levels.

Film stiffness per slice: Zhao et al. 2022 eq 8-9 with A = 2 b width and the means of
p and h over the Hertz band (:func:`gearfmu.ehl.film_stiffness.slice_film_stiffness_N_per_m`,
``method="seed"``).
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import List, Optional, Sequence, Tuple

import numpy as np

from . import mgcycle
from .errors import EHLConvergenceError, EHLInputError, FilmCollapseError
from .film_stiffness import slice_film_stiffness_N_per_m
from .lubricant import B0_DEFAULT_PA, B0_PRIME_DEFAULT
from .solver import solve_line_contact
from ..common.executors import make_executor, ManagedExecutor
from ..common.jit import module_cache_is_cold
from ..common.progress import notice, progress_bar, wait_refreshing


class MeshFilmInputError(EHLInputError):
    """Bad input to the mesh-film functions (names the field and the reason)."""


# ---------------------------------------------------------------- kinematics
def contact_kinematics(geom, s_m, omega1_rad_s: float) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(R_m, u_m_s, sliding_m_s) at LOA positions ``s_m`` (m from N1).

    R = s1 s2/(s1 + s2) (m), entrainment u_s = (omega1 s1 + omega2 s2)/2 (m/s),
    sliding u1 - u2 (m/s), omega2 = omega1 z1/z2 (module docstring)."""
    if not (math.isfinite(omega1_rad_s) and omega1_rad_s > 0):
        raise MeshFilmInputError(f"omega1_rad_s={omega1_rad_s!r}: must be finite and > 0 (rad/s)")
    s = np.asarray(s_m, dtype=float)
    s1 = geom.roll_length_at(1, s)
    s2 = geom.roll_length_at(2, s)
    if np.any(~np.isfinite(s)) or np.any(s1 <= 0) or np.any(s2 <= 0):
        raise MeshFilmInputError("s_m: contact positions must lie strictly between N1 and N2")
    omega2 = omega1_rad_s * geom.z1 / geom.z2
    u1 = omega1_rad_s * s1
    u2 = omega2 * s2
    return s1 * s2 / (s1 + s2), 0.5 * (u1 + u2), u1 - u2


def involute_arc_length_m(roll_m, base_radius_m: float):
    """Arc length (m) of an involute from the base circle to roll length ``roll_m``:
    a = rho^2 / (2 r_b) (integral of rho d(rho)/r_b)."""
    r = np.asarray(roll_m, dtype=float)
    return r * r / (2.0 * base_radius_m)


# ---------------------------------------------------------------- roughness
@dataclass
class FlankRoughness:
    """Sampled W-M roughness of both flanks, per slice (m).

    ``a1_m``/``a2_m``: arc-length grids of the pinion / gear flank; ``z1_m``,
    ``z2_m``: (n_slices, len(a)) heights."""

    a1_m: np.ndarray
    z1_m: np.ndarray
    a2_m: np.ndarray
    z2_m: np.ndarray
    D: float
    G_m: float
    seed: int
    f_max_per_m: float

    @property
    def n_slices(self) -> int:
        return int(self.z1_m.shape[0])

    def composite_m(self, slice_index: int, a1_m: float, a2_m: float, x_m) -> np.ndarray:
        """wm(x) = z1(a1 - x) + z2(a2 + x) of slice ``slice_index`` (m)."""
        x = np.asarray(x_m, dtype=float)
        return (np.interp(a1_m - x, self.a1_m, self.z1_m[slice_index])
                + np.interp(a2_m + x, self.a2_m, self.z2_m[slice_index]))


# ---------------------------------------------------------------- one solve
@dataclass(frozen=True)
class FilmEnvironment:
    """Everything a film solve needs besides position, load and roughness (SI).

    ``E_prime_Pa`` = 2 / ((1 - nu1^2)/E1 + (1 - nu2^2)/E2); lubricant eta0 (Pa s)
    at the oil temperature, alpha (1/Pa), rho0 (kg/m^3); bulk-modulus law
    B0 (Pa), B0' (Zhao et al. 2022 eq 9); ``n_nodes`` of the EHL grid (None: solver's
    choice)."""

    E_prime_Pa: float
    eta0_Pas: float
    alpha_Pa_inv: float
    rho0_kg_m3: float
    width_m: float
    B0_Pa: float = B0_DEFAULT_PA
    B0_prime: float = B0_PRIME_DEFAULT
    n_nodes: Optional[int] = None


@dataclass
class FilmOutcome:
    """Result of one slice solve.  ``status``: 'ok', 'collapse' (FilmCollapseError)
    or 'stall' (EHLConvergenceError); ``k_N_per_m`` NaN unless ok."""

    k_N_per_m: float
    h_central_m: float
    h_min_m: float
    p_mean_Pa: float
    sigma_m: float
    status: str
    film_parameter: float = float("nan")
    message: str = ""


#: Relaxation setting tried first by a rough solve warm-started from the smooth film
#: (:func:`solve_node_films`; the solver's keyword options, docs/ehl.md): Gauss-Seidel /
#: Jacobi switch 0.3, nu1 = 2, nu2 = 3, under-relaxation 0.6 / 0.4.  On the default scene
#: (3 grid positions x 44 slices at the nominal load, warm starts) most level-2 rough films
#: that converge with the solver's own order (the smooth film's setting first, then every
#: setting in turn, the later ones from a Hertz start) do so only on this setting, after the
#: others fail; tried first it converges them with the film stiffness unchanged to 1.2e-5 and
#: without the failed attempts' cost.
ROUGH_WARM_SETTINGS = dict(switch=0.3, nu1=2, nu2=3, omega_gs=0.6, omega_j=0.4)


def solve_slice_film(env: FilmEnvironment, R_m: float, u_m_s: float, w_N_per_m: float,
                     roughness=None, return_result: bool = False, initial=None,
                     relaxation: Optional[Sequence[dict]] = None):
    """Film of one slice: solve Zhao et al. 2022 eq 2-7 and eq 8-9 (see module doc).

    ``roughness``: None (smooth) or an ``(x_m, z_m)`` composite profile.
    ``initial``: a LineContactResult to start from (warm start, e.g. the smooth
    film at the same position and load: about 3x fewer W-cycles for a rough solve).
    ``relaxation``: None (the solver's own sequence of relaxation settings, a
    stall costing all of them) or a list of option dicts, each tried once in
    turn as explicit keyword options of ``solve_line_contact`` (every one
    warm-started from ``initial``); the film stalls when all stall.
    Returns a :class:`FilmOutcome` (and the LineContactResult when
    ``return_result``; None when the solve failed)."""
    res = None
    sigma = 0.0 if roughness is None else float(np.std(roughness[1]))
    try:
        try:
            args = (R_m, env.E_prime_Pa, w_N_per_m, u_m_s, env.eta0_Pas, env.alpha_Pa_inv, env.rho0_kg_m3)
            if relaxation:
                for i_opt, opts in enumerate(relaxation):
                    try:
                        res = solve_line_contact(*args, roughness_m=roughness, n_nodes=env.n_nodes,
                                                 initial=initial, **opts)
                        break
                    except EHLConvergenceError:
                        if i_opt == len(relaxation) - 1:
                            raise
            else:
                res = solve_line_contact(*args, roughness_m=roughness, n_nodes=env.n_nodes, initial=initial)
        except EHLConvergenceError:
            if roughness is not None:
                raise
            # smooth films at low M (light loads, M < 1) sometimes need more W-cycles: one retry
            res = solve_line_contact(R_m, env.E_prime_Pa, w_N_per_m, u_m_s, env.eta0_Pas, env.alpha_Pa_inv,
                                     env.rho0_kg_m3, n_nodes=env.n_nodes, max_cycles=200)
        band = np.abs(res.x_m) <= res.b_m
        k = slice_film_stiffness_N_per_m(res, env.width_m, "seed", env.B0_Pa, env.B0_prime)
        sig = float(np.std(res.roughness_m[band])) if roughness is not None else 0.0
        out = FilmOutcome(k, res.h_central_m, res.h_min_m, float(np.mean(res.p_Pa[band])), sig, "ok",
                          res.h_min_m / sig if sig > 0 else float("inf"))
    except FilmCollapseError as exc:
        out = FilmOutcome(float("nan"), float("nan"), exc.h_min_m, float("nan"), sigma, "collapse",
                          exc.film_parameter, str(exc)[:300])
    except EHLConvergenceError as exc:
        out = FilmOutcome(float("nan"), float("nan"), float("nan"), float("nan"), sigma, "stall",
                          float("nan"), str(exc)[:300])
    if return_result:
        return out, res
    return out


def _solve_chunk(env: FilmEnvironment, items):
    """Worker: solve a list of (R, u, w, roughness-or-None) requests."""
    return [solve_slice_film(env, R, u, w, rough) for (R, u, w, rough) in items]


def solve_node_films(env: FilmEnvironment, R_m: float, u_m_s: float, w_N_per_m: float,
                     roughness_list: Sequence) -> Tuple[FilmOutcome, List[FilmOutcome]]:
    """Smooth film at one (position, load) node, then the rough film of every
    profile in ``roughness_list`` (one per slice) warm-started from it
    (``initial=``, about 3x fewer cycles than a cold start; stalled warm starts are
    not retried cold: that rarely recovers them and doubles the cost of a stall).  Each rough solve tries two relaxation settings, both warm: first
    :data:`ROUGH_WARM_SETTINGS`, then the smooth film's own setting (``relaxation=`` of
    :func:`solve_slice_film`; a stall then costs two settings, not the solver's whole
    sequence with cold restarts).  Where the smooth film fails the rough films are not
    solved (status 'smooth <status>'; the grid needs the smooth film for the ratio).
    Returns (smooth outcome, rough outcomes)."""
    sm, res = solve_slice_film(env, R_m, u_m_s, w_N_per_m, None, return_result=True)
    if sm.status != "ok":  # no smooth film: the grid cannot use a rough one (ratio to smooth)
        return sm, [FilmOutcome(float("nan"), float("nan"), float("nan"), float("nan"), 0.0,
                                f"smooth {sm.status}", message="smooth film failed; rough not solved")
                    for _ in roughness_list]
    relax = None
    if res is not None:
        relax = [dict(ROUGH_WARM_SETTINGS)]
        prev = res.residuals.get("settings")
        if isinstance(prev, dict) and prev != ROUGH_WARM_SETTINGS:
            relax.append(dict(prev))
    outs = [solve_slice_film(env, R_m, u_m_s, w_N_per_m, r, initial=res, relaxation=relax)
            for r in roughness_list]
    return sm, outs


def _solve_node_chunk(env: FilmEnvironment, items):
    """Worker: :func:`solve_node_films` for a list of (R, u, w, [profiles]) items."""
    return [solve_node_films(env, R, u, w, rl) for (R, u, w, rl) in items]


# ---------------------------------------------------------------- batches
def solve_films(env: FilmEnvironment, requests: Sequence[tuple], *, executor=None,
                max_workers: Optional[int] = None, chunk_size: Optional[int] = None,
                progress: bool = False, label: str = "EHL films") -> List[FilmOutcome]:
    """Solve independent slice films ``requests`` = [(R_m, u_m_s, w_N_per_m, roughness|None), ...].

    ``executor``: any ``concurrent.futures``-style object with ``submit`` (e.g.
    ``distributed.Client(...).get_executor()``; left open); None: a local
    process pool (``gearfmu.common.executors.make_executor``, min(CPU count, chunks) workers; in-process for a
    single chunk or ``max_workers`` = 1).  Results in request order."""
    reqs = list(requests)
    if not reqs:
        return []
    n_cpu = os.cpu_count() or 1
    if chunk_size is None:
        chunk_size = max(1, min(32, math.ceil(len(reqs) / (4 * n_cpu))))
    chunks = [reqs[i:i + chunk_size] for i in range(0, len(reqs), chunk_size)]
    res = map_chunks(_solve_chunk, env, chunks, [len(c) for c in chunks], executor=executor,
                     max_workers=max_workers, progress=progress, label=label)
    return [o for r in res for o in r]


def _film_solver_cold() -> bool:
    """True when numba's cache lacks the compiled multigrid cycle of the film solver."""
    return module_cache_is_cold(mgcycle)


def map_chunks(worker, env, chunks: Sequence[list], counts: Sequence[int], *, executor=None,
               max_workers: Optional[int] = None, progress: bool = False,
               label: str = "EHL films") -> List[list]:
    """Run ``worker(env, chunk)`` for every chunk through an executor (see
    :func:`solve_films`); ``counts``: film solves per chunk for the progress bar.
    Returns the workers' results in chunk order."""

    if not chunks:
        return []
    n_cpu = os.cpu_count() or 1
    if progress and _film_solver_cold():
        notice("compiling the EHL film solver (first use after installing or updating gearfmu; every worker "
               "process compiles it, a few minutes; kept for later runs)", enabled=True)
    bar = progress_bar(desc=label, enabled=progress, total=int(sum(counts)), unit="film", leave=False)
    out: List[Optional[list]] = [None] * len(chunks)
    if executor is None:
        nw = min(n_cpu if max_workers is None else int(max_workers), len(chunks))
        ctx = make_executor(max_workers=nw)
    else:
        ctx = ManagedExecutor(executor, None, own=False)
    try:
        with ctx as ex:
            futs = {ex.submit(worker, env, c): i for i, c in enumerate(chunks)}
            for f in wait_refreshing(futs, bar):
                i = futs[f]
                out[i] = f.result()
                bar.update(int(counts[i]))
    finally:
        bar.close()
    return out  # type: ignore[return-value]
