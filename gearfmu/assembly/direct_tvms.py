"""Mesh stiffness of a spur pair evaluated DIRECTLY at given meshing positions.

No table, no film grid, no interpolation: at every requested meshing position every tooth
pair in contact and every face-width slice gets its own contact stiffness k_l from the chosen
model, solved at that pair's contact position and that slice's load, and the slices are
combined with the tooth and foundation compliances exactly as the tables combine them:

    k_tooth^i = 1 / (1/k_l + 1/k_tp + 1/k_tg)           (Zhao et al. 2022 eq 13; bending, shear,
                                                          axial of both teeth eq 14-15)
    foundation per pair (Sainsot; eq 12, or eq 11 with the shared-foundation correction)
    slice loads F_jn = k_jn max(0, x_s - e_j - E_n), sum F_jn = F = T1/r_b1   (eq 16)
    TVMS = sum over pairs j and slices n of k_jn                              (eq 10)

(:func:`gearfmu.contact.models.tooth_compliances`, :func:`gearfmu.contact.models.sliced_mesh_stiffness`,
:func:`gearfmu.gear.loaded_mesh.loaded_static_mesh`).  The load of each slice is iterated with the
load-dependent contact stiffness by the table builder's iteration
(:func:`gearfmu.assembly.load_iteration.iterate_load_sharing`: start from the Hertz slice loads,
load floor 0.5 F/b, a request is re-solved when its load moved by more than 1e-4 of itself,
stop when no slice load changes by more than ``LOAD_ITERATION_TOL`` = 1e-3 of F/NS, at most
``LOAD_ITERATION_MAX`` passes).

Contact models (:data:`DIRECT_MODELS`):

* ``hertz``: Yang & Sun line-contact stiffness pi E* w / 2 (load-independent; Zhao et al. 2022's
  reference case in Fig. 12);
* ``smooth_ehl``: steady smooth line-contact EHL (Zhao et al. 2022 eq 2-7), film stiffness Zhao et al. 2022
  eq 8-9 on the Hertz band (:func:`gearfmu.ehl.mesh_film.solve_slice_film`);
* ``rough_steady``: the same with the slice's frozen W-M flank roughness at the contact
  (Zhao et al. 2022 eq 1, 3; the steady rough film of the tables, sampled directly and solved as the
  film grid solves it, warm-started from the smooth film, :func:`gearfmu.ehl.mesh_film.solve_node_films`);
* ``smooth_transient`` / ``rough_transient``: the transient solver
  (:func:`gearfmu.ehl.transient.solve_line_contact_transient`, option A of docs/ehl_transient.md:
  R, u_s, SRR and w frozen at the request, the roughness of each flank moving with that flank at
  u1, u2, :func:`gearfmu.ehl.transient.flank_slice_case`), start 'auto', run through the wash-out
  and ``T_average`` more (b/u_s units); film stiffness by reduction (b) = Zhao et al. 2022 eq 8 on the
  window means A B(<p_m>)/<h_m> (default; (a) <A B(p_m)/h_m> selectable) -- the quantity of
  tests/unit/ehl/test_ehl_transient.py's Fig. 13 test and of the tables' transient correction.

CHOICES (also in docs/ehl_mesh.md "Direct TVMS"):

* Meshing position = LOA position ``s_m`` (m from N1) of one contact; the other pairs in contact
  are at s + k p_b inside [s_A, s_E] (:func:`pair_positions_m`).
* Errors: perfect gears by default (``e_pair_m`` = 0, no crowning), the case of Zhao et al. 2022
  section 5; the table's per-pair meshing errors and crowning can be passed (:class:`PairLoading`).
* Load iteration of the film models that need a film per slice (``rough_steady``,
  ``smooth_transient``, ``rough_transient``): the iteration starts from the slice loads
  converged with ``smooth_ehl`` (steady smooth films, cheap) instead of the Hertz loads --
  the same fixed point (same rule and tolerance), a better first guess, so that an expensive
  transient run is repeated only if the roughness itself moves a slice load by more than the
  tolerance.
* Film parameter: the rough models screen every request with Lambda = h_min/sigma
  (:func:`gearfmu.contact.models.film_parameter`); below ``RoughnessSpec.full_film_parameter``
  (3) Zhao et al. 2022's full film does not exist and :class:`DirectTVMSError` is raised (names the
  position, pair and Lambda) unless ``check_film_parameter=False``.  A film that fails
  (stall, collapse) raises too (``on_film_failure='error'``), or takes the steady smooth film
  (``'smooth'``; recorded in ``failures``).  The screen is a CHOICE, not a prediction of film
  collapse: under Zhao et al. 2022's full-film assumption (``check_film_parameter=False``) the transient films
  of the Table 1 pair at levels 3-4 (screen Lambda 2.1-2.9) exist with h > 0 everywhere, window
  minimum down to 0.55 sigma (the roughness is flattened inside the contact; a Newtonian,
  isothermal, elastic model result) -- recorded per request in ``h_min_m`` / ``h_min_over_sigma`` /
  ``film_runs`` (docs/ehl_mesh.md "Direct TVMS").

Work goes through a ``concurrent.futures``-style executor (``executor`` or a local pool of
``max_workers``; in-process for ``max_workers=1``), one film evaluation per task chunk, with a
progress bar when asked for (:func:`gearfmu.ehl.mesh_film.map_chunks`).  SI units throughout.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import List, Optional
import dataclasses
import os

import numpy as np

from ..ehl.errors import EHLConvergenceError, EHLInputError, FilmCollapseError
from .load_iteration import UNLOADED_SLICE_LOAD_SHARE, iterate_load_sharing, slice_loads_N
from ..contact.models import film_parameter, sliced_mesh_stiffness, tooth_compliances, composite_sigma_m
from ..contact.rough_ehl import rough_profile
from ..ehl.mesh_film import solve_node_films, solve_slice_film, contact_kinematics, map_chunks
from ..ehl import transient as ehl_transient
from ..ehl.transient import flank_slice_case
from ..gear.hertz import hertz_stiffness_N_per_m

#: contact models of :func:`direct_mesh_stiffness`
DIRECT_MODELS = ("hertz", "smooth_ehl", "rough_steady", "smooth_transient", "rough_transient")
_ROUGH = ("rough_steady", "rough_transient")
_TRANSIENT = ("smooth_transient", "rough_transient")
#: film-failure handling of :func:`direct_mesh_stiffness`
DIRECT_FAILURE_POLICIES = ("error", "smooth")


class DirectTVMSError(EHLInputError):
    """Bad input to :func:`direct_mesh_stiffness`, a request outside the full film, or a failed
    film under ``on_film_failure='error'`` (names the field or the request and the reason)."""


@dataclass(frozen=True)
class TransientFilmSettings:
    """Settings of the transient film runs (models ``*_transient``).

    ``n_nodes``: EHL grid nodes (257 = 256 intervals, as the tables' transient correction);
    ``T_average``: averaging window after the wash-out, in b/u_s (CHOICE: 8, the Fig. 13 test's
    window; the solver's default 4 is the tables'); ``reduction``: 'k_of_means' (b, default) or
    'mean_of_k' (a) (docs/ehl_transient.md section 3); ``start``, ``ramp_T``: the solver's start
    ('auto': frozen steady start, smooth start with a roughness ramp of ``ramp_T`` if that
    stalls); ``substep_rescue``: the solver's stalled-step rescue."""

    n_nodes: int = 257
    T_average: float = 8.0
    reduction: str = "k_of_means"
    start: str = "auto"
    ramp_T: float = 1.0
    substep_rescue: bool = True

    def check(self) -> "TransientFilmSettings":
        if int(self.n_nodes) != self.n_nodes or self.n_nodes < 33 or (self.n_nodes - 1) & (self.n_nodes - 2):
            raise DirectTVMSError(f"transient.n_nodes={self.n_nodes!r}: must be 2^k + 1 >= 33")
        if not (isinstance(self.T_average, (int, float)) and math.isfinite(self.T_average) and self.T_average > 0):
            raise DirectTVMSError(f"transient.T_average={self.T_average!r}: must be finite and > 0 (b/u_s)")
        if self.reduction not in ("k_of_means", "mean_of_k"):
            raise DirectTVMSError(f"transient.reduction={self.reduction!r}: must be 'k_of_means' or 'mean_of_k'")
        return self


@dataclass
class DirectTVMS:
    """Result of :func:`direct_mesh_stiffness` (SI).

    ``s_m`` (N,) requested positions; ``s_pair_m`` (P, N) contact position of each pair (NaN: not
    in contact); ``k_mesh_N_per_m`` (N,) the TVMS; ``k_pair_N_per_m`` (P, N); ``k_slice_N_per_m``
    and ``k_contact_N_per_m`` (P, NS, N) slice mesh stiffness and the model's contact stiffness
    k_l; ``w_N_per_m`` (P, NS, N) static slice line loads (N/m) with the final stiffness (0 out of
    contact; the films were solved at loads within the iteration tolerance of these); ``film_parameter`` (P, N)
    Lambda = h_min/sigma of the screen (Dowson-Higginson h_min of the smooth contact at the mean line load
    F/b, undeformed composite sigma; NaN for smooth/Hertz); ``passes`` and ``load_change`` (max slice-load change of the
    last pass over F/NS) of the load iteration; ``film_evaluations``: film solves / runs done;
    ``failures``: dicts (s_m, pair, slice, w_N_per_m, status, message); ``cpu_s``: process CPU of
    this process plus ``worker_cpu_s`` (film CPU spent in other processes); ``wall_s``.

    Transient models only (NaN / empty otherwise), at the final slice loads: ``h_min_m`` (P, NS, N)
    the minimum film of the run over the averaging window and over x (the solver's h_min per time
    level, on the whole grid x_in..x_out); ``h_min_run_m`` (P, NS, N) the same over the whole run
    from T = 0 (start, roughness ramp, wash-out included); ``h_min_over_sigma`` (P, NS, N)
    ``h_min_m`` / ``sigma_composite_m`` (rough_transient; the film parameter of the SOLVED, deformed
    rough film, to compare with the screen's ``film_parameter``); ``film_runs``: one dict per
    evaluated request (s_m, pair, slice, w_N_per_m, start 'frozen' or 'smooth' (smooth start with
    the roughness ramp), ramp_T, steps, rescued_steps (steps rescued by sub-steps), h_min_m,
    h_min_run_m, h_min_over_sigma, h_central_ratio).  A transient film with h <= 0 anywhere at
    any time level raises FilmCollapseError in the solver (a failure, never a k)."""

    model: str
    s_m: np.ndarray
    s_pair_m: np.ndarray
    k_mesh_N_per_m: np.ndarray
    k_pair_N_per_m: np.ndarray
    k_slice_N_per_m: np.ndarray
    k_contact_N_per_m: np.ndarray
    w_N_per_m: np.ndarray
    film_parameter: np.ndarray
    passes: int
    load_change: float
    film_evaluations: int
    failures: List[dict] = field(default_factory=list)
    cpu_s: float = 0.0
    wall_s: float = 0.0
    torque_Nm: float = float("nan")
    worker_cpu_s: float = 0.0
    h_min_m: Optional[np.ndarray] = None
    h_min_run_m: Optional[np.ndarray] = None
    h_min_over_sigma: Optional[np.ndarray] = None
    sigma_composite_m: float = float("nan")
    film_runs: List[dict] = field(default_factory=list)


def pair_positions_m(geom, s_m) -> np.ndarray:
    """(P, N) LOA positions (m from N1) of every pair in contact when one contact is at ``s_m``
    (N,): s + k p_b (k integer) inside [s_A, s_E], sorted along the LOA; NaN for the slots not in
    contact (P = ceil(contact ratio)).  Involute kinematics: consecutive pairs are one base pitch
    apart on the line of action."""
    s = np.atleast_1d(np.asarray(s_m, dtype=float))
    if s.ndim != 1 or s.size == 0 or not np.all(np.isfinite(s)):
        raise DirectTVMSError("s_m: meshing positions must be a non-empty 1-D array of finite LOA positions (m)")
    lo, hi, pb = float(geom.s_start_m), float(geom.s_end_m), float(geom.base_pitch_m)
    tol = 1e-12 * max(hi, 1.0)
    if np.any(s < lo - tol) or np.any(s > hi + tol):
        raise DirectTVMSError(f"s_m: positions must lie on the path of contact [{lo * 1e3:.4f}, {hi * 1e3:.4f}] mm "
                              "(LOA from N1)")
    P = int(math.ceil(float(geom.contact_ratio) - 1e-12))
    out = np.full((P, s.size), np.nan)
    for i, si in enumerate(s):
        pos = sorted(p for p in (si + k * pb for k in range(-P - 1, P + 2)) if lo - tol <= p <= hi + tol)
        for j, p in enumerate(pos[:P]):
            out[j, i] = min(max(p, lo), hi)
    return out


# ------------------------------------------------------------------------------ workers
def _film_chunk(_env, items):
    """Worker: film evaluations.  Item ('steady', fenv, R, u, w, profile|None) or ('transient',
    kwargs, T_average, reduction).  Returns dicts with k_N_per_m, status, message, cpu_s (and for
    transient runs the window means and steps)."""

    out = []
    for it in items:
        c0 = time.process_time()
        if it[0] == "steady":
            _, fenv, R, u, w, prof = it
            if prof is None:
                o = solve_slice_film(fenv, R, u, w, None)
            else:   # the tables' rough solve: warm start from the smooth film, two relaxation settings
                o = solve_node_films(fenv, R, u, w, [prof])[1][0]
            out.append(dict(k_N_per_m=float(o.k_N_per_m), status=o.status, message=o.message,
                            cpu_s=time.process_time() - c0, pid=os.getpid()))
            continue
        _, kw, T_avg, red = it
        try:
            # looked up at call time, so a substitute set on the module is used
            r = ehl_transient.solve_line_contact_transient(**kw)
            T0 = r.T_settled
            q = r.film_stiffness_reductions(T0, T0 + T_avg)
            k = q["k_of_means_N_per_m"] if red == "k_of_means" else q["k_mean_of_k_N_per_m"]
            m = r.window(T0, T0 + T_avg)
            out.append(dict(k_N_per_m=float(k), status="ok", message="", cpu_s=time.process_time() - c0,
                            steps=int(r.T.size - 1), start=r.start, ramp_T=float(r.ramp_T),
                            h_central_ratio=q["h_central_mean_m"] / float(r.h_central_m[0]),
                            h_min_window_m=float(np.min(r.h_min_m[m])), h_min_run_m=float(np.min(r.h_min_m)),
                            h_mean_window_m=float(q["h_mean_m"]),
                            rescued=int(np.count_nonzero(r.rescued)) if r.rescued is not None else 0,
                            pid=os.getpid()))
        except (FilmCollapseError, EHLConvergenceError) as exc:
            out.append(dict(k_N_per_m=float("nan"), status="collapse" if isinstance(exc, FilmCollapseError)
                            else "stall", message=str(exc)[:300], cpu_s=time.process_time() - c0,
                            pid=os.getpid()))
    return out


def _transient_kwargs(env, s: float, w: float, slice_index, st: TransientFilmSettings) -> dict:
    kw = flank_slice_case(env, s, w, slice_index)
    srr = float(kw["srr"])
    dX = 6.0 / (st.n_nodes - 1)              # x_in = -4.5, x_out = 1.5 (the solver's defaults)
    T_wash = 6.0 / min(1.0 + 0.5 * srr, 1.0 - 0.5 * srr)
    kw.update(n_nodes=int(st.n_nodes), start=st.start, ramp_T=float(st.ramp_T),
              substep_rescue=st.substep_rescue,
              n_steps=int(math.ceil((float(st.ramp_T) + T_wash + float(st.T_average)) / dX)))
    return kw


def _refuse_low_film(model, env, s, lam, where) -> None:
    """DirectTVMSError for the first request with Lambda below the full-film limit."""
    bad = np.asarray(lam) < env.roughness.full_film_parameter
    if not np.any(bad):
        return
    q = int(np.argmax(bad))
    at = "" if where is None else f", pair {int(where[0][q])}, slice {int(where[1][q])}"
    raise DirectTVMSError(
        f"{model}: no full film at s = {float(s[q]) * 1e3:.4f} mm (LOA from N1){at}: film parameter "
        f"lambda = h_min/sigma = {float(lam[q]):.3g} below the full-film limit "
        f"{env.roughness.full_film_parameter:g} (roughness level {env.roughness.level}); seed 000 assumes "
        "a full film; pass check_film_parameter=False to run the film anyway")


def _key(x: float) -> float:
    return float(f"{x:.10g}")


@dataclass(frozen=True)
class PairLoading:
    """How the pair is loaded in :func:`direct_mesh_stiffness` (SI; None: the default):
    ``e_pair_m`` (P, N) meshing error per pair and position (default 0: perfect gears, Zhao et al. 2022
    section 5), ``crowning_m`` (NS,) lead crowning per slice (default 0) -- the loaded static mesh
    of Zhao et al. 2022 eq 16 -- and ``initial_loads_N`` (P, NS, N) slice loads to start the load iteration
    from (default: the Hertz loads, or for the per-slice film models the loads converged with
    ``smooth_ehl``)."""

    e_pair_m: Optional[np.ndarray] = None
    crowning_m: Optional[np.ndarray] = None
    initial_loads_N: Optional[np.ndarray] = None


@dataclass
class _DirectPair:
    """The pair at the requested positions (SI): contact position of each pair ``sp`` (P, N), the
    errors ``e`` (P, N) and crowning ``E`` (NS,), the torque ``T`` and mesh force ``F`` = T/r_b1,
    the slice width, the tooth and foundation compliances (Zhao et al. 2022 eq 11-15), the zone entries
    in contact (mask (P, NS, N) and its index arrays) and the film environment (None: Hertz)."""

    env: object
    opts: object
    model: str
    st: TransientFilmSettings
    sp: np.ndarray
    e: np.ndarray
    E: np.ndarray
    T: float
    width: float
    compliances: tuple
    zone: np.ndarray
    fenv: object = None

    @property
    def F(self) -> float:
        return self.T / float(self.env.geom.rb1_m)

    @property
    def idx(self):
        return np.nonzero(self.zone)

    def hertz_contact(self) -> np.ndarray:
        """(P, NS, N) Hertz contact stiffness in the zone (Yang & Sun, pi E* w / 2), 0 outside."""
        return np.where(self.zone, hertz_stiffness_N_per_m(self.env.pair, self.width), 0.0)

    def mesh_stiffness(self, kc) -> np.ndarray:
        """(P, NS, N) slice mesh stiffness from the contact stiffness ``kc`` (Zhao et al. 2022 eq 10-13)."""
        ct, fp, fg = self.compliances
        return sliced_mesh_stiffness(ct, fp, fg, kc, self.opts)


# ------------------------------------------------------------------------------ main
def direct_mesh_stiffness(env, opts, s_m, torque_Nm: float, model: str, *, loading: Optional[PairLoading] = None,
                          transient: Optional[TransientFilmSettings] = None, executor=None,
                          max_workers: Optional[int] = None, progress: bool = False,
                          check_film_parameter: bool = True, on_film_failure: str = "error") -> DirectTVMS:
    """TVMS (N/m) of the pair at the meshing positions ``s_m`` (m from N1), evaluated directly
    (Zhao et al. 2022 eq 10-16 with the contact stiffness of ``model``; module doc).

    ``env``: :class:`gearfmu.contact.models.ContactEnvironment` (pair, geometry, pinion speed,
    lubricant, ``n_slices`` and slice ``width_m``, ``roughness`` for the rough models; its
    ``ehl_nodes`` set the steady films' grid, default ``transient.n_nodes``); ``opts``:
    :class:`gearfmu.gear.gearpair.MeshModelOptions` (foundation choices; ``opts.slices`` must equal
    ``env.n_slices``); ``torque_Nm`` (> 0): pinion torque, F = T/r_b1; ``model``: one of
    :data:`DIRECT_MODELS`; ``loading``: :class:`PairLoading` (meshing errors, crowning, start
    loads; default perfect gears from the Hertz loads); ``transient``: :class:`TransientFilmSettings`;
    ``executor`` / ``max_workers`` / ``progress``: as :func:`gearfmu.ehl.mesh_film.solve_films`;
    ``check_film_parameter``, ``on_film_failure``: the film-parameter screen and what a failed
    film does (module doc).

    Steps: the pair at the positions (:func:`_direct_pair`: pairs in contact, compliances); Hertz
    contact directly; otherwise the film-parameter screen of the rough models, the start loads
    (:func:`_start_loads`), the load-sharing iteration with one film per distinct request
    (:class:`_FilmRequests`, :func:`gearfmu.assembly.load_iteration.iterate_load_sharing`) and,
    for the transient models, the minimum films of the runs (:func:`_transient_film_minima`)."""
    t_wall, c_parent = time.perf_counter(), time.process_time()
    loading = loading or PairLoading()
    dp = _direct_pair(env, opts, s_m, torque_Nm, model, loading, transient, on_film_failure)
    P, NS, N = dp.zone.shape
    lam = np.full((P, N), np.nan)
    if model == "hertz":
        kc_h = dp.hertz_contact()
        k = dp.mesh_stiffness(kc_h)
        loads = slice_loads_N(k, dp.e, dp.E, dp.F)
        res = DirectTVMS(model, np.atleast_1d(np.asarray(s_m, float)), dp.sp, k.sum(axis=(0, 1)), k.sum(axis=1), k,
                         kc_h, loads / dp.width, lam, 1, 0.0, 0, [], 0.0, 0.0, dp.T)
        res.cpu_s, res.wall_s = time.process_time() - c_parent, time.perf_counter() - t_wall
        return res
    face = dp.width * NS
    if model in _ROUGH:
        pos = dp.sp[np.isfinite(dp.sp)]
        lam_f = film_parameter(env, pos, np.full(pos.shape, dp.F / face))
        lam[np.isfinite(dp.sp)] = lam_f
        if check_film_parameter:      # screen at the mean line load F/b first (before any solve)
            _refuse_low_film(model, env, pos, lam_f, None)
    run = dict(executor=executor, max_workers=max_workers, progress=progress)
    loads, pre_cpu, pre_evaluations = _start_loads(dp, s_m, loading, run, on_film_failure)
    films = _FilmRequests(dp, check_film_parameter, on_film_failure, run)
    films.worker_cpu += pre_cpu
    films.evaluations += pre_evaluations
    ls = iterate_load_sharing(loads, dp.e, dp.E, dp.F, dp.idx, dp.width, UNLOADED_SLICE_LOAD_SHARE * dp.F / face,
                              films.solve, dp.mesh_stiffness, what=f"direct TVMS {model}")
    k, kc, loads, it, change = ls.k_slice_N_per_m, ls.k_contact_N_per_m, ls.loads_N, ls.passes, ls.load_change
    wl = np.where(dp.zone, loads / dp.width, 0.0)
    if model not in _ROUGH:
        lam[:] = np.nan
    hmin, hrun, hsig, sigma, runs = _transient_film_minima(dp, films)
    worker_cpu = films.worker_cpu
    return DirectTVMS(model, np.atleast_1d(np.asarray(s_m, float)), dp.sp, k.sum(axis=(0, 1)), k.sum(axis=1), k, kc,
                      wl, lam, it, change, films.evaluations, films.failures,
                      cpu_s=time.process_time() - c_parent + worker_cpu, wall_s=time.perf_counter() - t_wall,
                      torque_Nm=dp.T, worker_cpu_s=worker_cpu, h_min_m=hmin, h_min_run_m=hrun, h_min_over_sigma=hsig,
                      sigma_composite_m=sigma, film_runs=runs)


def _direct_pair(env, opts, s_m, torque_Nm, model: str, loading: PairLoading, transient, on_film_failure) -> _DirectPair:
    """The inputs checked (DirectTVMSError naming the field) and the pair at the positions: the
    pairs in contact (:func:`pair_positions_m`), the tooth and foundation compliances
    (:func:`gearfmu.contact.models.tooth_compliances`), the film environment of a film model."""
    if model not in DIRECT_MODELS:
        raise DirectTVMSError(f"model={model!r}: must be one of {', '.join(DIRECT_MODELS)}")
    if on_film_failure not in DIRECT_FAILURE_POLICIES:
        raise DirectTVMSError(f"on_film_failure={on_film_failure!r}: must be one of "
                              f"{', '.join(DIRECT_FAILURE_POLICIES)}")
    try:
        T = float(torque_Nm)
    except (TypeError, ValueError):
        raise DirectTVMSError(f"torque_Nm={torque_Nm!r}: must be a number (N m)") from None
    if not (math.isfinite(T) and T > 0):
        raise DirectTVMSError(f"torque_Nm={torque_Nm!r}: must be finite and > 0 (N m)")
    NS = int(env.n_slices)
    if int(opts.slices) != NS:
        raise DirectTVMSError(f"opts.slices={opts.slices!r}: must equal env.n_slices={NS} (one slice width)")
    if getattr(env.geom, "helix_angle_rad", 0.0) != 0.0:
        raise DirectTVMSError("env.geom: the direct TVMS is for spur pairs (helix angle 0)")
    if model in _ROUGH and env.roughness is None:
        raise DirectTVMSError(f"env.roughness: model {model!r} needs a RoughnessSpec")
    st = (transient or TransientFilmSettings()).check()
    geom, pair = env.geom, env.pair
    sp = pair_positions_m(geom, s_m)                                    # (P, N)
    P, N = sp.shape
    e = np.zeros((P, N)) if loading.e_pair_m is None else np.asarray(loading.e_pair_m, dtype=float)
    E = np.zeros(NS) if loading.crowning_m is None else np.asarray(loading.crowning_m, dtype=float)
    if e.shape != (P, N) or not np.all(np.isfinite(e)):
        raise DirectTVMSError(f"e_pair_m: must be a finite array of shape {(P, N)} (m)")
    if E.shape != (NS,) or not np.all(np.isfinite(E)) or np.any(E < 0):
        raise DirectTVMSError(f"crowning_m: must be a finite array >= 0 of shape {(NS,)} (m)")
    width = float(env.width_m)
    compliances = tooth_compliances(pair, geom, sp, width)
    zone = np.broadcast_to(np.isfinite(sp)[:, None, :], (P, NS, N))
    fenv = None
    if model != "hertz":
        fenv = env.film_environment()
        if fenv.n_nodes is None:
            fenv = dataclasses.replace(fenv, n_nodes=int(st.n_nodes))
    return _DirectPair(env, opts, model, st, sp, e, E, T, width, compliances, zone, fenv)


def _start_loads(dp: _DirectPair, s_m, loading: PairLoading, run: dict, on_film_failure: str):
    """Slice loads (P, NS, N) the load iteration starts from: the given ones; for the per-slice
    film models the loads converged with ``smooth_ehl`` (steady smooth films, cheap: the same
    fixed point from a better first guess, module doc); else the Hertz loads.  Returns (loads,
    film CPU of other processes, film evaluations) of the smooth pre-solve."""
    P, NS, N = dp.zone.shape
    if loading.initial_loads_N is not None:
        loads = np.asarray(loading.initial_loads_N, dtype=float)
        if loads.shape != (P, NS, N):
            raise DirectTVMSError(f"initial_loads_N: expected shape {(P, NS, N)}, got {loads.shape}")
        return loads, 0.0, 0
    if dp.model in ("rough_steady",) + _TRANSIENT:
        pre = direct_mesh_stiffness(dp.env, dp.opts, s_m, dp.T, "smooth_ehl", loading=PairLoading(dp.e, dp.E),
                                    transient=dp.st, on_film_failure=on_film_failure, **run)
        return pre.w_N_per_m * dp.width, pre.worker_cpu_s, pre.film_evaluations
    return slice_loads_N(dp.mesh_stiffness(dp.hertz_contact()), dp.e, dp.E, dp.F), 0.0, 0


class _FilmRequests:
    """The film evaluations of the load iteration (:meth:`solve`, the ``solve`` of
    :func:`gearfmu.assembly.load_iteration.iterate_load_sharing`): one per distinct (position,
    slice for the rough films, load), kept for later passes; the rough models screen every
    request's film parameter first; a failed film raises (``on_film_failure='error'``) or takes
    the steady smooth film (``'smooth'``, recorded in ``failures``)."""

    def __init__(self, dp: _DirectPair, check_film_parameter: bool, on_film_failure: str, run: dict):
        self.dp, self.check, self.on_failure, self.run = dp, check_film_parameter, on_film_failure, run
        geom = dp.env.geom
        self.R_all, self.u_all, _ = contact_kinematics(
            geom, np.where(np.isfinite(dp.sp), dp.sp, float(geom.s_pitch_m)), dp.env.omega1_rad_s)
        self.zone = dp.idx
        self.last_key = [None] * len(self.zone[0])   # cache key of the film behind kc[j, n, i] (per zone entry)
        self.cache = {}
        self.smooth_cache = {}
        self.worker_cpu = 0.0
        self.evaluations = 0
        self.failures: List[dict] = []

    def _item(self, s_k, sl, w_k, jj, ii):
        """The work item of one request (:func:`_film_chunk`)."""
        dp = self.dp
        env, st, fenv = dp.env, dp.st, dp.fenv
        R, u = float(self.R_all[jj, ii]), float(self.u_all[jj, ii])
        if dp.model in _TRANSIENT:
            kw = _transient_kwargs(env, float(dp.sp[jj, ii]), w_k, None if sl < 0 else sl, st)
            return ("transient", kw, float(st.T_average), st.reduction)
        if dp.model == "rough_steady":
            prof = rough_profile(env, fenv, env.flanks(), float(dp.sp[jj, ii]), sl, w_k, R)
            return ("steady", fenv, R, u, w_k, prof)
        return ("steady", fenv, R, u, w_k, None)

    def solve(self, w, redo, it):
        """Contact stiffness (N/m) of the zone entries ``redo`` at the line loads ``w`` (pass ``it``)."""
        dp, (j, n, i) = self.dp, self.zone
        model, sp = dp.model, dp.sp
        ridx = np.nonzero(redo)[0]
        if model in _ROUGH and self.check:
            lam_r = film_parameter(dp.env, sp[j[ridx], i[ridx]], w[ridx])
            _refuse_low_film(model, dp.env, sp[j[ridx], i[ridx]], lam_r, (j[ridx], n[ridx]))
        # one evaluation per distinct (position, slice for rough films, load)
        keys = []
        for q in ridx:
            sl = int(n[q]) if model in _ROUGH else -1
            keys.append((_key(sp[j[q], i[q]]), sl, _key(w[q]), int(j[q]), int(i[q])))
        uniq = {}
        for kk in keys:
            uniq.setdefault(kk[:3], kk)
        todo = [kk for kk in uniq.values() if kk[:3] not in self.cache]
        items = [self._item(*kk) for kk in todo]
        if items:
            res_chunks = map_chunks(_film_chunk, None, [[x] for x in items], [1] * len(items),
                                    label=f"direct TVMS {model} pass {it}", **self.run)
            for kk, r in zip(todo, res_chunks):
                r = r[0]
                if r["pid"] != os.getpid():      # run in another process: its CPU is not ours
                    self.worker_cpu += r["cpu_s"]
                self.evaluations += 1
                self.cache[kk[:3]] = r
        vals = np.empty(len(ridx))
        for m, (q, kk) in enumerate(zip(ridx, keys)):
            r = self.cache[kk[:3]]
            self.last_key[q] = kk
            vals[m] = r["k_N_per_m"] if r["status"] == "ok" else self._failed(q, kk, r)
        return vals, None

    def _failed(self, q, kk, r) -> float:
        """A failed film: DirectTVMSError, or the steady smooth film's stiffness (recorded)."""
        n = self.zone[1]
        f = dict(s_m=kk[0], pair=kk[3], slice=int(n[q]), w_N_per_m=kk[2], status=r["status"],
                 message=r["message"])
        if self.on_failure == "error":
            raise DirectTVMSError(f"{self.dp.model}: film {r['status']} at s = {kk[0] * 1e3:.4f} mm (LOA from N1), "
                                  f"pair {kk[3]}, slice {int(n[q])}, w = {kk[2]:.4g} N/m: {r['message']}")
        sk = (kk[0], kk[2])
        if sk not in self.smooth_cache:
            o = _film_chunk(None, [("steady", self.dp.fenv, float(self.R_all[kk[3], kk[4]]),
                                    float(self.u_all[kk[3], kk[4]]), kk[2], None)])[0]
            self.evaluations += 1
            self.smooth_cache[sk] = o
        f["used"] = "smooth_ehl"
        self.failures.append(f)
        return self.smooth_cache[sk]["k_N_per_m"]


def _transient_film_minima(dp: _DirectPair, films: _FilmRequests):
    """Of the transient models (NaN / empty otherwise), at the final slice loads: the minimum
    film over the averaging window and over the whole run per zone entry, the window minimum
    over the composite sigma (rough films) and one record per evaluated request.  Returns
    (h_min_m, h_min_run_m, h_min_over_sigma, sigma, runs)."""
    j, n, i = films.zone
    hmin, hrun, hsig = (np.full(dp.zone.shape, np.nan) for _ in range(3))
    sigma = float("nan")
    runs: List[dict] = []
    if dp.model not in _TRANSIENT:
        return hmin, hrun, hsig, sigma, runs
    if dp.model in _ROUGH:
        sigma = float(composite_sigma_m(dp.env.roughness))
    for q, kk in enumerate(films.last_key):
        r = films.cache.get(kk[:3]) if kk is not None else None
        if r is None or r["status"] != "ok":
            continue
        hmin[j[q], n[q], i[q]] = r["h_min_window_m"]
        hrun[j[q], n[q], i[q]] = r["h_min_run_m"]
        hsig[j[q], n[q], i[q]] = r["h_min_window_m"] / sigma
        runs.append(dict(s_m=kk[0], pair=kk[3], slice=int(n[q]), w_N_per_m=kk[2], start=r["start"],
                         ramp_T=r["ramp_T"], steps=r["steps"], rescued_steps=r["rescued"],
                         h_min_m=r["h_min_window_m"], h_min_run_m=r["h_min_run_m"],
                         h_min_over_sigma=r["h_min_window_m"] / sigma, h_central_ratio=r["h_central_ratio"]))
    return hmin, hrun, hsig, sigma, runs
