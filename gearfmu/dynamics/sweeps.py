"""Steady-state sweeps of the dynamic model (speed, load, damping, deviations) through an executor.

A *sweep job* (:class:`SweepJob`) is one sequence of operating points on one
set of tables: dimensionless mesh frequencies Omega_h (Xu et al. 2022 eq 7) at one
pinion torque and damping ratio.  Each point runs the time-indexed SDOF form
of Xu et al. 2022 eq 3-6 (:func:`gearfmu.dynamics.native.simulate_sdof`, constant pinion
speed), drops ``settle_meshes`` mesh periods of transient, records
``record_meshes`` more (rounded up to whole table periods), and reduces the
record to the mesh-harmonic amplitudes A_r / A_rms of Xu et al. 2022 eq 10-11
(:mod:`gearfmu.dynamics.harmonics`) of the dimensionless DTE q = x/l.

* ``continuation=True`` (speed sweeps, Xu et al. 2022 Fig. 3 and Figs. 30-32): each
  point starts from the final state (x, dx/dt, pinion angle) of the previous
  one, so an up-sweep and a down-sweep follow their branches through jumps.
  Such a job is sequential by nature.
* ``continuation=False``: every point starts from the quasi-static
  equilibrium at rest relative motion (independent points).

Independent jobs -- an up- and a down-sweep, several loads, damping ratios or
deviation levels -- run through :func:`run_jobs` on a ``concurrent.futures``
style executor: a local process pool by default (``spawn`` start method, so it
is safe in threaded hosts; every worker compiles the numba kernels once; ``fork`` for
a main script without a ``__main__`` guard, see :func:`make_executor`), a
Dask distributed cluster when a scheduler address is given (``scheduler=
"tcp://host:8786"``; needs the ``cluster`` extra), or any executor passed in.
Jobs and results are dataclasses of numpy arrays; they cross processes in
memory only (the executor's own transport).  Nothing is written to files here.

Dimensionless form (Xu et al. 2022 eq 7-9): omega_n = sqrt(k_m/m_e) with
k_m = ``tables.k_mean_N_per_m``; Omega_h = omega_mesh/omega_n, so the pinion
speed of a point is omega1 = Omega_h * omega_n * mesh_period_rad / (2 pi).
q = x/l with the nominal length l = ``length_scale_m`` (default 1 um: Xu et al. 2022
does not state l; with 1 um, q and A_rms read directly in micrometres).
"""
from __future__ import annotations

import math
import os
import time
from concurrent.futures import as_completed
from dataclasses import dataclass, field
from typing import List, Optional, Sequence

import numpy as np
from scipy.signal import find_peaks

from ..common.executors import SweepInputError, ManagedExecutor, make_executor
from ..common.progress import progress_bar
from ..common.vocabulary import DAMPING_MODELS, current_spelling
from .harmonics import DEFAULT_BANDWIDTH_ORDERS, mesh_harmonics
from ..tables.mesh_tables import MeshTables
from .native import choose_max_step_s, simulate_sdof
from .subcell import table_values

__all__ = [
    "SweepInputError",
    "PointSettings",
    "SweepJob",
    "PointHistory",
    "PointResult",
    "SweepResult",
    "pinion_speed_for_omega_h",
    "pair_values_at",
    "run_sweep",
    "run_jobs",
    "make_executor",
    "find_jumps",
]

#: default nominal length l of Xu et al. 2022 eq 7 (m): q = x/l in micrometres (choice, docs/seed003.md)
DEFAULT_LENGTH_SCALE_M = 1e-6


@dataclass(frozen=True)
class PointSettings:
    """How each operating point is run and analysed.

    settle_meshes : mesh periods dropped as transient before recording.
    record_meshes : mesh periods recorded (rounded up to whole table periods).
    samples_per_mesh : output samples per mesh period (the spectrum's Nyquist
        order is samples_per_mesh*z1/2 shaft orders).
    points_per_period : internal integrator steps (native default integrator) per min(natural period, mesh period)
        (:func:`gearfmu.dynamics.native.choose_max_step_s`).
    length_scale_m : nominal length l of Xu et al. 2022 eq 7 (m).
    bandwidth_orders : BW of Xu et al. 2022 eq 11 (shaft orders).
    harmonics : mesh harmonics in A_rms (Xu et al. 2022: 3).
    keep_history : keep the recorded time histories in the result.
    """

    settle_meshes: int = 300
    record_meshes: int = 100
    samples_per_mesh: int = 64
    points_per_period: int = 64
    length_scale_m: float = DEFAULT_LENGTH_SCALE_M
    bandwidth_orders: float = DEFAULT_BANDWIDTH_ORDERS
    harmonics: int = 3
    keep_history: bool = False

    def validate(self) -> "PointSettings":
        for name in ("settle_meshes", "record_meshes", "samples_per_mesh", "points_per_period", "harmonics"):
            v = getattr(self, name)
            lo = 0 if name == "settle_meshes" else 1
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < lo:
                raise SweepInputError(f"{name}: must be an integer >= {lo}, got {v!r}")
        for name in ("length_scale_m",):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise SweepInputError(f"{name}: must be finite and > 0, got {v!r}")
        v = self.bandwidth_orders
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
            raise SweepInputError(f"bandwidth_orders: must be finite and >= 0, got {v!r}")
        return self


@dataclass
class SweepJob:
    """One sequence of operating points on one set of tables (SI units).

    omega_h : dimensionless mesh frequencies Omega_h (Xu et al. 2022 eq 7), in run order.
    pinion_torque_Nm : T1 (N*m); the load is F_m = T1/Rb1.
    damping_ratio : per-pair damping ratio zeta bar (Xu et al. 2022 eq 8).
    damping_model : ``"contact_zone"`` (eq 8-9: constant damping on every pair in
        its contact zone, rho = 2 in the double zone) or ``"elastobacklash"``.
    continuation : start each point from the previous point's final state.
    start_state : optional (x_m, v_m_s, theta1_rad) for the first point.
    label : free text carried into the result.
    """

    tables: MeshTables
    omega_h: np.ndarray
    pinion_torque_Nm: float
    damping_ratio: float
    damping_model: str = "contact_zone"
    continuation: bool = True
    settings: PointSettings = field(default_factory=PointSettings)
    start_state: Optional[tuple] = None
    label: str = ""

    def validate(self) -> "SweepJob":
        if not isinstance(self.tables, MeshTables):
            raise SweepInputError(f"tables: expected MeshTables, got {type(self.tables).__name__}")
        self.tables.validate()
        om = np.atleast_1d(np.asarray(self.omega_h, dtype=float))
        if om.ndim != 1 or om.size < 1:
            raise SweepInputError(f"omega_h: expected a non-empty 1-D sequence, got shape {om.shape}")
        if not np.all(np.isfinite(om)) or np.any(om <= 0):
            raise SweepInputError("omega_h: every Omega_h must be finite and > 0")
        for name in ("pinion_torque_Nm", "damping_ratio"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float, np.floating)) and math.isfinite(v)):
                raise SweepInputError(f"{name}: must be a finite number, got {v!r}")
        if self.damping_ratio < 0:
            raise SweepInputError(f"damping_ratio: must be >= 0, got {self.damping_ratio!r}")
        self.damping_model = current_spelling("damping_model", self.damping_model)
        if self.damping_model not in DAMPING_MODELS:
            raise SweepInputError(f"damping_model: {self.damping_model!r} unknown; choose one of {list(DAMPING_MODELS)}")
        if self.start_state is not None:
            s = tuple(float(v) for v in self.start_state)
            if len(s) != 3 or not all(math.isfinite(v) for v in s):
                raise SweepInputError("start_state: expected three finite numbers (x_m, v_m_s, theta1_rad)")
        self.settings.validate()
        self.omega_h = om
        return self


@dataclass
class PointHistory:
    """Recorded steady-state history of one point (SI unless said).

    time_s, theta1_rad (pinion angle), mesh_cycle (pinion angle / mesh period:
    tau/tau_z of the figures of Xu et al. 2022, counted from the start of the run), dte_m,
    q (= dte/l), pair_force_N (n, P) (eq 14: spring plus damping part),
    contact_force_N (n, P) (spring part k_j f(x - e_j) only), k_N_per_m and
    e_m (n, P) (pair tables at each sample), mesh_force_N (eq 13),
    load_sharing (n, P).
    """

    time_s: np.ndarray
    theta1_rad: np.ndarray
    mesh_cycle: np.ndarray
    dte_m: np.ndarray
    q: np.ndarray
    pair_force_N: np.ndarray
    contact_force_N: np.ndarray
    k_N_per_m: np.ndarray
    e_m: np.ndarray
    mesh_force_N: np.ndarray
    load_sharing: np.ndarray


@dataclass
class PointResult:
    """Steady-state summary of one operating point.

    A_r : (harmonics,) mesh-harmonic RMS amplitudes of q (eq 11, dimensionless,
        i.e. in units of l); A_rms : eq 10.  q_mean, q_min, q_max : of the record.
    contact_loss : some pair inside its contact zone (k > 0) had no contact
        (|x - e_j| <= b_j) at a recorded sample; back_contact : some pair touched
        the back flank.  settled_rel : |A_rms(first half) - A_rms(second half)| /
        A_rms over the record (halves of whole table periods; 0 = periodic).
    end_state : (x_m, v_m_s, theta1_rad) after the point.  diverged : the
    solver produced non-finite values (then the amplitudes are NaN).
    """

    omega_h: float
    omega1_rad_s: float
    A_r: np.ndarray
    A_rms: float
    q_mean: float
    q_min: float
    q_max: float
    contact_loss: bool
    back_contact: bool
    settled_rel: float
    end_state: tuple
    diverged: bool
    wall_s: float
    history: Optional[PointHistory] = None


@dataclass
class SweepResult:
    """All points of one job, in run order, plus the arrays of the curve."""

    label: str
    omega_h: np.ndarray
    A_r: np.ndarray          # (n, harmonics)
    A_rms: np.ndarray        # (n,)
    q_mean: np.ndarray
    q_min: np.ndarray
    q_max: np.ndarray
    contact_loss: np.ndarray  # bool (n,)
    settled_rel: np.ndarray
    points: List[PointResult]
    pinion_torque_Nm: float
    damping_ratio: float
    damping_model: str
    omega_n_rad_s: float
    length_scale_m: float
    wall_s: float


# ------------------------------------------------------------------ helpers
def _omega_n(tables: MeshTables) -> float:
    return math.sqrt(tables.k_mean_N_per_m / tables.equivalent_mass_kg)


def pinion_speed_for_omega_h(tables: MeshTables, omega_h: float) -> float:
    """Pinion speed (rad/s) at which the mesh frequency is Omega_h * omega_n (Xu et al. 2022 eq 7):
    omega1 = Omega_h * sqrt(k_m/m_e) * mesh_period_rad / (2 pi)."""
    return float(omega_h) * _omega_n(tables) * tables.mesh_period_rad / (2.0 * math.pi)


def pair_values_at(tables: MeshTables, theta1_rad, pinion_torque_Nm: float):
    """k_j (N/m), e_j (m), b_j (m) of every slot at pinion angles theta1 (arrays (n, P)).

    The table lookup of docs/model.md (periodic linear interpolation in phi,
    linear in clamped torque) in vectorised numpy, for post-processing; tables with
    engagement angles through the kernels' own lookup (docs/model.md "Contact-zone edges").
    """
    if tables.engagement_in_rad is not None and not tables.has_temperature_axis:
        k, e, _, b = table_values(tables, np.ravel(np.asarray(theta1_rad, dtype=float)), pinion_torque_Nm)
        return k, e, b
    th = np.asarray(theta1_rad, dtype=float)
    Phi = tables.phi_period_rad
    N = tables.n_phi
    dphi = Phi / N
    phim = th - Phi * np.floor(th / Phi)
    s = phim / dphi
    i0 = np.clip(np.floor(s).astype(int), 0, N - 1)
    w = s - i0
    i1 = np.where(i0 + 1 == N, 0, i0 + 1)

    def interp(A):  # A: (P, N) -> (n, P)
        return (A[:, i0] + w * (A[:, i1] - A[:, i0])).T

    tq = tables.torque_Nm
    if tables.n_torque > 1:
        T = min(max(float(pinion_torque_Nm), tq[0]), tq[-1])
        it = int(min(max(np.searchsorted(tq, T, side="right") - 1, 0), tables.n_torque - 2))
        wt = (T - tq[it]) / (tq[it + 1] - tq[it])
        k = interp(tables.k_N_per_m[it]) + wt * (interp(tables.k_N_per_m[it + 1]) - interp(tables.k_N_per_m[it]))
        e = interp(tables.e_m[it]) + wt * (interp(tables.e_m[it + 1]) - interp(tables.e_m[it]))
    else:
        k = interp(tables.k_N_per_m[0])
        e = interp(tables.e_m[0])
    b = interp(tables.backlash_half_m)
    return k, e, b


def _run_point(job: SweepJob, omega_h: float, state, rec_meshes: int):
    t = job.tables
    st = job.settings
    om1 = pinion_speed_for_omega_h(t, omega_h)
    t_mesh = t.mesh_period_rad / om1
    H = t_mesh / st.samples_per_mesh
    n_mesh = st.settle_meshes + rec_meshes
    hmax = choose_max_step_s(t, om1, points_per_period=st.points_per_period)
    kw = {}
    if state is not None:
        kw = dict(dte_start_m=state[0], dte_rate_start_m_s=state[1], pinion_angle_start_rad=state[2])
    t0 = time.perf_counter()
    res = simulate_sdof(t, omega1_rad_s=om1, stop_time_s=n_mesh * t_mesh, comm_step_s=H, max_step_s=hmax,
                        pinion_torque_Nm=job.pinion_torque_Nm, damping_ratio=job.damping_ratio,
                        damping_model=job.damping_model, **kw)
    wall = time.perf_counter() - t0
    n_rec = rec_meshes * st.samples_per_mesh
    sl = slice(res.dte.size - n_rec - 1, res.dte.size - 1)   # n_rec samples, whole periods
    l = st.length_scale_m
    end = (float(res.dte[-1]), float(res.dte_rate[-1]), float(res.pinion_angle[-1]))
    nh = st.harmonics
    if not (np.all(np.isfinite(res.dte)) and np.all(np.isfinite(res.dte_rate))):
        nan = float("nan")
        return PointResult(omega_h=float(omega_h), omega1_rad_s=om1, A_r=np.full(nh, nan), A_rms=nan,
                           q_mean=nan, q_min=nan, q_max=nan, contact_loss=False, back_contact=False,
                           settled_rel=nan, end_state=end, diverged=True, wall_s=wall), None
    q = res.dte[sl] / l
    spr = st.samples_per_mesh * t.teeth_pinion
    kw_h = dict(samples_per_revolution=spr, teeth=t.teeth_pinion, harmonics=nh,
                bandwidth_orders=st.bandwidth_orders)
    hm = mesh_harmonics(q, **kw_h)
    half = n_rec // 2
    per = int(round(t.phi_period_rad / t.mesh_period_rad)) * st.samples_per_mesh
    if half % per == 0 and half > 0:
        a1 = mesh_harmonics(q[:half], **kw_h).A_rms
        a2 = mesh_harmonics(q[half:], **kw_h).A_rms
        settled = abs(a1 - a2) / max(hm.A_rms, 1e-300)
    else:
        settled = float("nan")
    th = res.pinion_angle[sl]
    k, e, b = pair_values_at(t, th, job.pinion_torque_Nm)
    d = res.dte[sl][:, None] - e
    inzone = k > 0.0
    contact_loss = bool(np.any(inzone & (np.abs(d) <= b)))
    back = bool(np.any(inzone & (d < -b)))
    hist = None
    if st.keep_history:
        fc = np.where(d > b, k * (d - b), np.where(d < -b, k * (d + b), 0.0))
        hist = PointHistory(
            time_s=res.time_s[sl].copy(), theta1_rad=th.copy(), mesh_cycle=th / t.mesh_period_rad,
            dte_m=res.dte[sl].copy(), q=q.copy(), pair_force_N=res.pair_force[sl].copy(),
            contact_force_N=fc, k_N_per_m=k, e_m=e, mesh_force_N=res.mesh_force[sl].copy(),
            load_sharing=res.load_sharing[sl].copy())
    pr = PointResult(omega_h=float(omega_h), omega1_rad_s=om1, A_r=hm.A_r, A_rms=hm.A_rms,
                     q_mean=float(q.mean()), q_min=float(q.min()), q_max=float(q.max()),
                     contact_loss=contact_loss, back_contact=back, settled_rel=float(settled),
                     end_state=end, diverged=False, wall_s=wall, history=hist)
    return pr, end


def run_sweep(job: SweepJob) -> SweepResult:
    """Run one job's points in order (continuation or independent), in this process."""
    job = job.validate()
    t = job.tables
    per = int(round(t.phi_period_rad / t.mesh_period_rad))
    rec = int(math.ceil(job.settings.record_meshes / per)) * per
    first = None if job.start_state is None else tuple(float(v) for v in job.start_state)
    state = first
    t0 = time.perf_counter()
    points = []
    for om in job.omega_h:
        pr, end = _run_point(job, float(om), state, rec)
        points.append(pr)
        # continuation: the next point starts where this one ended (from equilibrium after a divergence)
        state = (None if pr.diverged else end) if job.continuation else first
    wall = time.perf_counter() - t0

    def arr(name):
        return np.array([getattr(p, name) for p in points])

    return SweepResult(
        label=job.label, omega_h=arr("omega_h"), A_r=np.vstack([p.A_r for p in points]), A_rms=arr("A_rms"),
        q_mean=arr("q_mean"), q_min=arr("q_min"), q_max=arr("q_max"),
        contact_loss=arr("contact_loss").astype(bool), settled_rel=arr("settled_rel"), points=points,
        pinion_torque_Nm=float(job.pinion_torque_Nm), damping_ratio=float(job.damping_ratio),
        damping_model=job.damping_model, omega_n_rad_s=_omega_n(t),
        length_scale_m=job.settings.length_scale_m, wall_s=wall)


def run_jobs(jobs: Sequence[SweepJob], *, executor=None, scheduler: Optional[str] = None,
             client=None, max_workers: Optional[int] = None, progress: bool = False) -> List[SweepResult]:
    """Run independent sweep jobs concurrently; results in the order of ``jobs``.

    ``executor``: any object with ``submit(fn, *args) -> future`` (left open);
    else :func:`make_executor` (``client``, ``scheduler``, ``max_workers``;
    default a local process pool with min(len(jobs), CPU count) workers).
    ``progress``: a progress bar of the finished jobs on stderr.
    """
    jobs = [j.validate() for j in jobs]
    if not jobs:
        return []
    if executor is not None:
        ctx = ManagedExecutor(executor, None, own=False)
    else:
        if max_workers is None and scheduler is None and client is None:
            max_workers = min(len(jobs), os.cpu_count() or 1)
        ctx = make_executor(scheduler=scheduler, max_workers=max_workers, client=client)
    out: List[Optional[SweepResult]] = [None] * len(jobs)
    with ctx as ex:
        futs = {ex.submit(run_sweep, j): i for i, j in enumerate(jobs)}
        for f in progress_bar(as_completed(futs), "gearfmu sweeps", progress, total=len(jobs), unit="job"):
            i = futs[f]
            out[i] = f.result()
    return out  # type: ignore[return-value]


# --------------------------------------------------------------- jump finder
def find_jumps(omega_h, curves: Sequence, *, jump_ratio: float = 1.25, min_prominence: float = 0.15,
               shoulder_prominence: float = 1.0, merge_within: float = 0.015) -> dict:
    """Jumps, inflections, shoulders and peaks of A_rms(Omega_h) curves (Xu et al. 2022 Fig. 3 reading).

    omega_h : ascending common grid; curves : A_rms arrays on it (e.g. the
    up- and the down-sweep, reordered to ascending Omega_h).  Everything is
    read on L = log A_rms (relative changes).

    * ``jump_down`` / ``jump_up``: a step between neighbouring points whose
      ratio exceeds ``jump_ratio`` and is at least twice the steps on either
      side (a discontinuity, not a steep flank); located at the midpoint;
    * ``inflection``: a local minimum of L with prominence >= ``min_prominence``
      -- the "inflection point" of Xu et al. 2022, where A_rms turns from "decreases
      sharply" to "increases slowly";
    * ``shoulder``: a local minimum of the slope dL/dOmega_h with prominence >=
      ``shoulder_prominence`` (per unit Omega_h) that is not an inflection: a
      weak resonance riding on a rising flank (a superharmonic too weak to make
      a minimum);
    * ``peak``: a local maximum of L with prominence >= ``min_prominence``
      (resonances; reported, not counted as jumps);
    * ``hysteresis``: intervals where two curves differ by more than 10 %.

    Returns {"features": [{"omega_h", "kind", "curve", "size"}], "jumps": sorted
    Omega_h of the jumps, inflections and shoulders (merged within
    ``merge_within``), "peaks": [...], "hysteresis": [[lo, hi], ...]}.
    """
    om = np.asarray(omega_h, dtype=float)
    if om.ndim != 1 or om.size < 3 or not np.all(np.diff(om) > 0):
        raise SweepInputError("omega_h: expected an ascending 1-D grid of at least 3 points")
    feats = []
    logs = []
    for ci, a in enumerate(curves):
        a = np.asarray(a, dtype=float)
        if a.shape != om.shape:
            raise SweepInputError(f"curves[{ci}]: shape {a.shape} differs from omega_h {om.shape}")
        if not np.all(np.isfinite(a)) or np.any(a <= 0):
            raise SweepInputError(f"curves[{ci}]: every value must be finite and > 0")
        la = np.log(a)
        logs.append(la)
        d = np.diff(la)
        ad = np.abs(d)
        for i in range(d.size):
            nb = [ad[j] for j in (i - 1, i + 1) if 0 <= j < d.size]
            if ad[i] > math.log(jump_ratio) and all(ad[i] >= 2.0 * x for x in nb):
                feats.append({"omega_h": float(0.5 * (om[i] + om[i + 1])),
                              "kind": "jump_down" if d[i] < 0 else "jump_up", "curve": ci,
                              "size": float(d[i])})
        mins, pm = find_peaks(-la, prominence=min_prominence)
        for i, p in zip(mins, pm["prominences"]):
            feats.append({"omega_h": float(om[i]), "kind": "inflection", "curve": ci, "size": float(p)})
        maxs, px = find_peaks(la, prominence=min_prominence)
        for i, p in zip(maxs, px["prominences"]):
            feats.append({"omega_h": float(om[i]), "kind": "peak", "curve": ci, "size": float(p)})
        slope = d / np.diff(om)
        sh, ps = find_peaks(-slope, prominence=shoulder_prominence)
        for i, p in zip(sh, ps["prominences"]):
            o = float(0.5 * (om[i] + om[i + 1]))
            near_other = any(abs(o - om[j]) <= merge_within for j in list(mins) + list(maxs))
            if not near_other and slope[i] > 0:
                feats.append({"omega_h": o, "kind": "shoulder", "curve": ci, "size": float(p)})
    hyst = []
    if len(logs) >= 2:
        diff = np.abs(logs[0] - logs[1]) > math.log(1.1)
        i = 0
        while i < diff.size:
            if diff[i]:
                j = i
                while j + 1 < diff.size and diff[j + 1]:
                    j += 1
                hyst.append([float(om[i]), float(om[j])])
                i = j + 1
            else:
                i += 1
    feats.sort(key=lambda f: (f["omega_h"], f["kind"], f["curve"]))

    def merged(kinds):
        out: List[float] = []
        for f in feats:
            if f["kind"] not in kinds:
                continue
            if out and f["omega_h"] - out[-1] <= merge_within:
                continue
            out.append(f["omega_h"])
        return out

    return {"features": feats, "jumps": merged({"jump_down", "jump_up", "inflection", "shoulder"}),
            "peaks": merged({"peak"}), "hysteresis": hyst}
