"""Worst-case verification of a fidelity plan over its envelope (docs/plan.md "Verification").

The combined configuration of a plan (never one choice at a time) is compared with
the full-fidelity configuration by the native solver over the whole envelope:

* transients: run-up and run-down over the speed range (compared point by point, so
  where a resonance has coexisting branches both are checked), a torque step
  low -> high -> low and a temperature sequence high -> low -> high;
* steady points: the corners, the points farthest from every table node (mid-way
  between the torque rows and between the temperature axis nodes of the compared
  configuration) and the resonance speeds the full model's sweeps show (peaks of the
  DTE fluctuation, largest run-up/run-down difference);
* an adaptive refinement around the worst steady point, coordinate by coordinate
  (torque, speed, temperature), halving the step towards the worse neighbour.

All within a budget of native runs.  :data:`ERROR_DEFINITION` is the one error
measure of the planner; :func:`run_errors` computes it.
"""
from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from typing import Dict, List, Optional, Tuple

import numpy as np

from ..common.progress import progress_bar
from ..dynamics.harmonics import mesh_order_amplitudes

__all__ = ["ERROR_DEFINITION", "MEASURES", "MEASURE_LABELS", "run_errors", "Probe", "Search", "budget_use",
           "limiting_measure", "target_of", "steady_phase", "drive_phase", "say", "ProgressBar", "DriveCase",
           "drive_case", "constant", "speed_sweeps"]

#: the planner's error measures, one key each (docs/plan.md "Error measure"): relative RMS of DTE and
#: mesh force, DTE peak-to-peak and mean, and mesh orders 1-3 of DTE and mesh force
MEASURES = ("dte_rel", "mesh_force_rel", "dte_p2p_rel", "dte_mean_rel", "dte_h1_rel", "dte_h2_rel", "dte_h3_rel",
            "mesh_force_h1_rel", "mesh_force_h2_rel", "mesh_force_h3_rel")
#: a short label of every measure (text report)
MEASURE_LABELS = {"dte_rel": "DTE rms", "mesh_force_rel": "force rms", "dte_p2p_rel": "DTE p2p",
                  "dte_mean_rel": "DTE mean", "dte_h1_rel": "DTE h1", "dte_h2_rel": "DTE h2", "dte_h3_rel": "DTE h3",
                  "mesh_force_h1_rel": "force h1", "mesh_force_h2_rel": "force h2", "mesh_force_h3_rel": "force h3"}
MESH_ORDERS = 3              # mesh-order harmonics measured (1, 2, 3)
#: floor of a harmonic's normalisation, as a share of the strongest of the full model's first
#: MESH_ORDERS harmonics of that signal (CHOICE, docs/plan.md: 20 dB below the strongest order)
HARMONIC_FLOOR = 0.1

#: the planner's error measure, word for word (docs/plan.md "Error measure")
ERROR_DEFINITION = (
    "per comparison run (a steady point of run_mesh_periods mesh periods from the quasi-static start, or "
    "one segment of 16 x run_mesh_periods communication steps of a transient) and for y = DTE and y = total "
    "mesh force, sampled 16 times per mesh period at the run's top speed, against the full-fidelity model's "
    "y_full driven identically: rms(y - y_full) / rms(y_full) over the run's samples; over the run's window "
    "(a steady point: the whole mesh periods of its second half; a transient segment: its last whole mesh "
    "periods) |p2p(DTE) - p2p(DTE_full)| / p2p(DTE_full), |mean(DTE) - mean(DTE_full)| / p2p(DTE_full) and, "
    "for mesh orders k = 1, 2, 3 of DTE and mesh force (peak amplitudes A_k, resampled at the rigid-body mesh "
    "angle), |A_k - A_k,full| / max(A_k,full, 0.1 x max_j A_j,full); the DTE measures against the DTE target, "
    "the mesh-force ones against the mesh-force target, each the worst over all runs, every one within its "
    "target; also reported: max|y - y_full| / (max y_full - min y_full)")

_SEGMENT_SAMPLES_PER_RUN_PERIOD = 16  # communication steps per mesh period at a case's top speed (CHOICE)
_SWEEP_RUN_LENGTHS = 12               # a sweep lasts 12 x run_mesh_periods mesh periods at its mean speed
_MAX_MIDS = 4                         # mid-way points per axis in the steady grid (CHOICE)
_RESONANCE_SPEEDS = 3                 # resonance speeds taken from the sweeps into the steady grid (CHOICE)


def _ratio(num: float, den: float) -> float:
    if den == 0.0:
        return 0.0 if num == 0.0 else math.inf
    return num / den


def target_of(key: str, dte_target: float, force_target: float) -> float:
    """The target a measure is held to: the DTE target for the DTE measures, else the mesh-force one."""
    return dte_target if key.startswith("dte") else force_target


def steady_phase(n_samples: int, samples_per_mesh: int = 16) -> np.ndarray:
    """Rigid-body mesh phase (mesh periods) of the samples of a constant-speed run sampled
    ``samples_per_mesh`` times per mesh period from phase 0."""
    return np.arange(int(n_samples)) / float(samples_per_mesh)


def drive_phase(case, mesh_period_rad: float, with_start: bool = True) -> np.ndarray:
    """Rigid-body mesh phase (mesh periods) of a drive's samples: the integral of its target
    speed (linear within each step), divided by the mesh period angle (rad); ``with_start``:
    a sample at the start (the native solver's row 0) comes first."""
    w = np.concatenate(([case.pinion_speed_start_rad_s], np.asarray(case.speed_profile_rad_s, dtype=float)))
    turn = np.concatenate(([0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * case.comm_step_s)))
    ph = turn / float(mesh_period_rad)
    return ph if with_start else ph[1:]


def run_errors(dte, force, dte_full, force_full, mesh_phase=None, window_from: int = 0) -> dict:
    """The error measures of one comparison run (:data:`ERROR_DEFINITION`, :data:`MEASURES`):
    relative RMS ``dte_rel`` / ``mesh_force_rel`` over every sample, and over the window --
    the whole mesh periods that end at the last sample, starting at or after sample
    ``window_from`` -- ``dte_p2p_rel``, ``dte_mean_rel`` and the harmonic measures
    ``dte_hK_rel`` / ``mesh_force_hK_rel`` (K = 1..3; :func:`gearfmu.dynamics.harmonics.mesh_order_amplitudes`
    at ``mesh_phase``, the rigid-body mesh phase of every sample in mesh periods; None: 16
    samples per mesh period at constant speed), all dimensionless; also ``dte_max_rel`` /
    ``mesh_force_max_rel`` (max|diff| / range of the full signal, reported).  Non-finite
    samples give inf."""
    out = {}
    arrs = {}
    for key, a, b in (("dte", dte, dte_full), ("mesh_force", force, force_full)):
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        arrs[key] = (a, b)
        if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
            out[f"{key}_rel"] = out[f"{key}_max_rel"] = math.inf
            continue
        d = a - b
        out[f"{key}_rel"] = _ratio(float(np.sqrt(np.mean(d ** 2))), float(np.sqrt(np.mean(b ** 2))))
        out[f"{key}_max_rel"] = _ratio(float(np.max(np.abs(d))), float(np.max(b) - np.min(b)))
    n = len(arrs["dte"][1])
    ph = steady_phase(n) if mesh_phase is None else np.asarray(mesh_phase, dtype=float)
    i0 = min(max(int(window_from), 0), n - 1)
    span = float(ph[-1] - ph[i0]) if n else 0.0
    for key in ("dte", "mesh_force"):
        a, b = arrs[key]
        hk = [f"{key}_h{k}_rel" for k in range(1, MESH_ORDERS + 1)]
        extra = hk + (["dte_p2p_rel", "dte_mean_rel"] if key == "dte" else [])
        if not (math.isfinite(out[f"{key}_rel"]) and math.isfinite(out[f"{key}_max_rel"])) or span < 1.0 - 1e-9:
            bad = not math.isfinite(out[f"{key}_rel"])
            for k in extra:  # no whole mesh period in the window: these measures say nothing
                out[k] = math.inf if bad else 0.0
            continue
        ra = mesh_order_amplitudes(a[i0:], ph[i0:], orders=MESH_ORDERS)
        rb = mesh_order_amplitudes(b[i0:], ph[i0:], orders=MESH_ORDERS)
        floor = HARMONIC_FLOOR * float(np.max(rb.amplitudes))
        for k, name in enumerate(hk):
            out[name] = _ratio(abs(float(ra.amplitudes[k] - rb.amplitudes[k])), max(float(rb.amplitudes[k]), floor))
        if key == "dte":
            out["dte_p2p_rel"] = _ratio(abs(ra.peak_to_peak - rb.peak_to_peak), rb.peak_to_peak)
            out["dte_mean_rel"] = _ratio(abs(ra.mean - rb.mean), rb.peak_to_peak)
    return out


def case_errors(case, a: dict, b: dict, mesh_period_rad: float, run_mesh_periods: int, dte_target: float = 1.0,
                force_target: float = 1.0, with_start: bool = True) -> dict:
    """:func:`run_errors` of a drive (:class:`DriveCase`) run by two models: ``a`` / ``b`` dicts with
    ``dte`` and ``mesh_force`` (``b`` the full model; ``with_start``: a first sample at the start,
    as the native solver gives, else one per communication step at its end, as an FMU gives).
    A steady drive (constant speed, torques and temperature) is one run whose window is the whole
    mesh periods of its second half; a transient is cut into segments of 16 x ``run_mesh_periods``
    steps and the segment of the largest budget use (``dte_target``, ``force_target``) is
    returned.  ``window``: the sample range the result is of."""
    ph = drive_phase(case, mesh_period_rad, with_start=with_start)
    n = len(b["dte"])
    steady = (np.ptp(case.speed_profile_rad_s) == 0.0 and np.ptp(case.pinion_torque_Nm) == 0.0
              and np.ptp(case.gear_torque_Nm) == 0.0 and (case.temperature_C is None or np.ptp(case.temperature_C) == 0.0)
              and case.speed_profile_rad_s[0] == case.pinion_speed_start_rad_s)
    if steady:
        e = run_errors(a["dte"], a["mesh_force"], b["dte"], b["mesh_force"], ph, n // 2)
        e["window"] = [0, n]
        return e
    seg = _SEGMENT_SAMPLES_PER_RUN_PERIOD * int(run_mesh_periods)
    best = None
    for i0 in range(0, max(n - seg // 2, 1), seg):
        sl = slice(i0, min(i0 + seg, n))
        e = run_errors(a["dte"][sl], a["mesh_force"][sl], b["dte"][sl], b["mesh_force"][sl], ph[sl])
        u = budget_use(e, dte_target, force_target)
        if best is None or u > best[0]:
            best = (u, e, [i0, sl.stop])
    best[1]["window"] = best[2]
    return best[1]


def budget_use(m: dict, dte_target: float, force_target: float) -> float:
    """max over the measures of :data:`MEASURES` present in ``m`` of measure / its target
    (:func:`target_of`; 1 = exactly on target)."""
    return max(m[k] / target_of(k, dte_target, force_target) for k in MEASURES if k in m)


def limiting_measure(m: dict, dte_target: float, force_target: float) -> str:
    """The measure of ``m`` with the largest share of its target (the one that limits the budget use)."""
    keys = [k for k in MEASURES if k in m]
    return max(keys, key=lambda k: m[k] / target_of(k, dte_target, force_target))


_BAR = None  # the progress bar on stderr while one is shown (say() writes above it)


def say(progress: bool, msg: str, log: List[str]) -> None:
    """Log a step of the plan; with ``progress`` also one line on stderr (also in --json
    mode), written above the progress bar while one is shown."""
    log.append(msg)
    if not progress:
        return
    line = f"gearfmu plan: {msg}"
    if _BAR is not None:
        _BAR.write(line, file=sys.stderr)
    else:
        print(line, file=sys.stderr, flush=True)


class ProgressBar:
    """Progress of ``total`` steps of the plan on stderr (a bar of
    :func:`gearfmu.common.progress.progress_bar`; one bar at a time, inner ones stay silent).
    A context manager; :meth:`update` advances it, ``note`` names the step that has just
    finished."""

    def __init__(self, progress: bool, total: int, what: str):
        self.progress, self.total, self.what = progress, max(int(total), 1), what
        self._bar = None

    def __enter__(self):
        global _BAR
        if _BAR is not None:  # inside another bar: that one shows the progress
            self.progress = False
        if self.progress:
            self._bar = progress_bar(None, f"gearfmu plan: {self.what}", total=self.total, leave=False)
            _BAR = self._bar
        return self

    def update(self, n: int = 1, note: str = "") -> None:
        if self._bar is not None:
            if note:
                self._bar.set_postfix_str(note, refresh=False)
            self._bar.update(n)

    def __exit__(self, *exc):
        global _BAR
        if self._bar is not None:
            self._bar.close()
            if _BAR is self._bar:
                _BAR = None
        return False


def _progress_iter(items, progress: bool, what: str):
    """``items`` with a progress display on stderr (:class:`ProgressBar`)."""
    if not progress or len(items) < 20:
        yield from items
        return
    with ProgressBar(progress, len(items), what) as bar:
        for x in items:
            yield x
            bar.update()


#: a one-speed envelope is searched over the band of pinion speeds around it that its FMU accepts
#: without a warning (docs/plan.md "Verification"; the FMU kernel's GK_ENV_SPEED_MARGIN, gearkernel.h)
POINT_SPEED_MARGIN_REL = 0.1


def search_speed_range(env) -> Tuple[float, float]:
    """The pinion speed range (rad/s) the envelope search covers: the envelope's speed range, or
    for a one-speed envelope w the band w (1 -/+ :data:`POINT_SPEED_MARGIN_REL`), which the FMU
    treats as inside its verified envelope (its speed margin for the torsional vibration)."""
    w0, w1 = env.speed_range_rad_s
    if w1 > w0:
        return (float(w0), float(w1))
    return (float(w0) * (1.0 - POINT_SPEED_MARGIN_REL), float(w1) * (1.0 + POINT_SPEED_MARGIN_REL))


@dataclass(frozen=True)
class Probe:
    """One comparison: a steady point (pinion torque N*m, pinion speed rad/s, bulk
    temperature degC or None) or a transient named by ``kind``."""

    kind: str
    torque_Nm: float = math.nan
    speed_rad_s: float = math.nan
    temperature_C: Optional[float] = None

    def point(self):
        return (self.torque_Nm, self.speed_rad_s, self.temperature_C)

    def describe(self) -> str:
        if self.kind != "steady":
            return self.kind
        t = "" if self.temperature_C is None else f", {self.temperature_C:.4g} degC"
        return f"steady {self.torque_Nm:.5g} N*m, {self.speed_rad_s * 30 / math.pi:.5g} rpm{t}"


class Search:
    """Adaptive worst-case search of one configuration against the full one.

    ``ev``: the planner's evaluator (``gearfmu.plan.evaluator.Evaluator``: tables, cached native
    runs, ``native_runs`` counter); ``budget_runs``: the largest number of native runs
    (both configurations counted; cached runs are free) one :meth:`verify` may add."""

    def __init__(self, ev, full: dict, say=None, progress: bool = False):
        self.ev, self.full, self.progress = ev, full, progress
        self.env, self.acc = ev.env, ev.acc
        self.say = say or (lambda msg: None)
        self._cases = None
        self._resonance: Optional[List[float]] = None

    # ---------------------------------------------------------------- probes
    def mesh_period_rad(self) -> float:
        """The pinion angle of one mesh period (rad), from the full tables."""
        return float(self.ev.tables(self.full)[0].mesh_period_rad)

    def speed_range_rad_s(self) -> Tuple[float, float]:
        """The pinion speeds the search covers (rad/s): :func:`search_speed_range` of the envelope."""
        return search_speed_range(self.env)

    def cases(self) -> Dict[str, object]:
        """The transient drives (:class:`DriveCase`) of the envelope, built once."""
        if self._cases is None:
            env, acc = self.env, self.acc
            tb, _ = self.ev.tables(self.full)
            mesh_rad = float(tb.mesh_period_rad)
            n_run = int(acc.run_mesh_periods)
            T_nom, w_nom = env.nominal_torque_Nm, env.nominal_speed_rad_s
            (T0, T1), (w0, w1) = env.torque_range_Nm, self.speed_range_rad_s()
            tr = env.temperature_range_C
            t_mid = None if tr is None else 0.5 * (tr[0] + tr[1])

            const = constant

            def comm(w_top):
                return mesh_rad / w_top / _SEGMENT_SAMPLES_PER_RUN_PERIOD

            cases = {}
            if w1 > w0:
                for c in speed_sweeps(tb, speed_range_rad_s=(w0, w1), torque_Nm=T_nom, temperature_C=t_mid,
                                      mesh_periods=_SWEEP_RUN_LENGTHS * n_run, comm_step_s=comm(w1)):
                    cases[c.name] = c
            if T1 > T0:
                t_run = 3 * n_run * mesh_rad / w_nom

                def step(t, t_run=t_run):
                    t = np.asarray(t)
                    return np.where((t >= t_run / 3) & (t < 2 * t_run / 3), T1, T0)
                cases["torque_step"] = drive_case("torque_step", tb, stop_time_s=t_run, comm_step_s=comm(w_nom),
                                                  torque_Nm=step, speed_rad_s=const(w_nom),
                                                  temperature_C=const(t_mid))
            if tr is not None and tr[1] > tr[0]:
                t_run = 3 * n_run * mesh_rad / w_nom
                lo, hi = tr

                def temp(t, t_run=t_run):
                    x = np.asarray(t) / t_run
                    return hi - (hi - lo) * (1.0 - np.abs(2.0 * x - 1.0))
                cases["temperature_sequence"] = drive_case(
                    "temperature_sequence", tb, stop_time_s=t_run, comm_step_s=comm(w_nom), torque_Nm=const(T_nom),
                    speed_rad_s=const(w_nom), temperature_C=temp)
            self._cases = cases
        return self._cases

    def resonance_speeds(self) -> List[float]:
        """Speeds (rad/s) where the full model's run-up / run-down show the largest DTE
        fluctuation, and where the two sweeps differ most (coexisting branches)."""
        if self._resonance is not None:
            return self._resonance
        cs = self.cases()
        out: List[float] = []
        if "run_up" in cs:
            seg = _SEGMENT_SAMPLES_PER_RUN_PERIOD * int(self.acc.run_mesh_periods) // 4
            curves = {}
            for name in ("run_up", "run_down"):
                c = cs[name]
                r = self.ev.run_drive(self.full, c)
                d = np.asarray(r["dte"][1:], dtype=float)
                w = np.asarray(c.speed_profile_rad_s, dtype=float)
                n = len(d) // seg
                if n < 3:
                    continue
                fl = np.array([np.std(d[i * seg:(i + 1) * seg]) for i in range(n)])
                ws = np.array([np.mean(w[i * seg:(i + 1) * seg]) for i in range(n)])
                order = np.argsort(ws)
                curves[name] = (ws[order], fl[order])
                peaks = [i for i in range(1, n - 1) if fl[i] >= fl[i - 1] and fl[i] >= fl[i + 1]]
                out += [float(ws[i]) for i in sorted(peaks, key=lambda i: -fl[i])[:_RESONANCE_SPEEDS - 1]]
            if len(curves) == 2:
                (wu, fu), (wd, fd) = curves["run_up"], curves["run_down"]
                diff = np.abs(fu - np.interp(wu, wd, fd))
                out.append(float(wu[int(np.argmax(diff))]))
        w0, w1 = self.speed_range_rad_s()
        uniq: List[float] = []
        for w in out:
            w = min(max(w, w0), w1)
            if all(abs(w - u) > 1e-3 * w1 for u in uniq):
                uniq.append(w)
        self._resonance = uniq[:_RESONANCE_SPEEDS]
        return self._resonance

    def _torques(self, cfg: dict) -> List[float]:
        lo, hi = self.env.torque_range_Nm
        vals = {lo, hi}
        n = int(cfg["torque_points"])
        if hi > lo and n >= 2:  # mid-way between the configuration's torque rows
            rows = [lo + (hi - lo) * i / (n - 1) for i in range(n)]
            mids = [0.5 * (a + b) for a, b in zip(rows[:-1], rows[1:])]
            if len(mids) > _MAX_MIDS:  # fine axes: a spread of their mid-way points (both ends kept)
                mids = [mids[int(round(i))] for i in np.linspace(0, len(mids) - 1, _MAX_MIDS)]
            vals |= set(mids)
        elif hi > lo:
            vals.add(0.5 * (lo + hi))
        return sorted(v for v in vals if v > 0) or [self.env.nominal_torque_Nm]

    def _temperatures(self, cfg: dict) -> List[Optional[float]]:
        tr = self.env.temperature_range_C
        if tr is None:
            return [None]
        lo, hi = tr
        vals = {lo, hi}
        nodes = list(self._axis(cfg))
        nodes = [x for x in nodes if lo <= x <= hi] or [lo, hi]
        nodes = sorted(set(nodes) | {lo, hi})
        mids = [0.5 * (a + b) for a, b in zip(nodes[:-1], nodes[1:])]
        if len(mids) > _MAX_MIDS:
            mids = [mids[int(round(i))] for i in np.linspace(0, len(mids) - 1, _MAX_MIDS)]
        return sorted(vals | set(mids))

    def _axis(self, cfg: dict) -> Tuple[float, ...]:
        if not cfg["thermal"]:
            return ()
        tb = self.ev.tables(cfg)[0]
        t = tb.temperature_C
        return () if t is None else tuple(float(x) for x in np.atleast_1d(t))

    def _speeds(self) -> List[float]:
        w0, w1 = self.speed_range_rad_s()
        vals = sorted({w0, w1, self.env.nominal_speed_rad_s} | set(self.resonance_speeds()))
        return [v for v in vals if v > 0]

    # ---------------------------------------------------------------- evaluation
    def evaluate(self, cfg: dict, probe: Probe) -> dict:
        """Error of ``cfg`` against full on one probe: the :func:`run_errors` entries, its
        budget use ``u`` and ``where`` (the worst segment of a transient: its time, pinion
        torque, speed and temperature)."""
        ev, acc = self.ev, self.acc
        if probe.kind == "steady":
            a, b = ev.run(cfg, probe.point()), ev.run(self.full, probe.point())
            n = len(b["dte"])  # the steady window: the whole mesh periods of the run's second half
            m = run_errors(a["dte"], a["mesh_force"], b["dte"], b["mesh_force"], steady_phase(n), n // 2)
            m["where"] = {"case": "steady", "torque_Nm": probe.torque_Nm,
                          "speed_rpm": probe.speed_rad_s * 30 / math.pi, "temperature_C": probe.temperature_C}
        else:
            case = self.cases()[probe.kind]
            a, b = ev.run_drive(cfg, case), ev.run_drive(self.full, case)
            m = case_errors(case, a, b, self.mesh_period_rad(), int(acc.run_mesh_periods), acc.dte_rel,
                            acc.mesh_force_rel)
            i0, i1 = m.pop("window")
            n = len(b["dte"])
            k = min(max((i0 + i1) // 2, 1), n - 1) - 1  # input row of the segment's middle step
            temp = None if case.temperature_C is None else float(case.temperature_C[k])
            m = dict(m)
            m["where"] = {"case": probe.kind, "time_s": [i0 * case.comm_step_s, i1 * case.comm_step_s],
                          "torque_Nm": float(case.pinion_torque_Nm[k]),
                          "speed_rpm": float(case.speed_profile_rad_s[k]) * 30 / math.pi, "temperature_C": temp}
        m["u"] = budget_use(m, acc.dte_rel, acc.mesh_force_rel)
        m["limit"] = limiting_measure(m, acc.dte_rel, acc.mesh_force_rel)
        return m

    def verify(self, cfg: dict, budget_runs: int, margin: float = 1.0) -> dict:
        """Search the envelope for the worst error of ``cfg`` against full.

        Returns ``worst`` (the :meth:`evaluate` entry of the worst probe, with ``probe``),
        ``probes`` (every probe evaluated: description and errors), ``native_runs`` (runs
        this search added), ``exhausted`` (True when the budget ran out before the search
        finished) and ``within_target``: the search finished and its worst budget use is
        <= ``margin`` (the search samples the envelope; a margin below 1 leaves room for an
        unsampled point a little worse than the worst found)."""
        ev = self.ev
        start = ev.native_runs
        seen: Dict[Probe, dict] = {}
        exhausted = False

        def left() -> int:
            return budget_runs - (ev.native_runs - start)

        def visit(p: Probe) -> Optional[dict]:
            nonlocal exhausted
            if p in seen:
                return seen[p]
            if left() <= 0:
                exhausted = True
                return None
            m = self.evaluate(cfg, p)
            seen[p] = m
            return m

        for name in self.cases():  # transients first: the sweeps also give the resonance speeds
            visit(Probe(name))
        Ts, ws, ths = self._torques(cfg), self._speeds(), self._temperatures(cfg)
        grid = [Probe("steady", T, w, th) for w in ws for T in Ts for th in ths]
        self.say(f"search: {len(self.cases())} transients, {len(grid)} grid points "
                 f"({len(Ts)} torques x {len(ws)} speeds x {len(ths)} temperatures)")
        for p in _progress_iter(grid, self.progress, "grid points"):
            if visit(p) is None:
                break
        # adaptive refinement around the worst steady point, coordinate by coordinate
        axes = [(0, Ts), (1, ws)] + ([(2, ths)] if ths != [None] else [])
        for rnd in range(2):  # the second round starts from the new worst with half the first steps
            steady = [(m["u"], p) for p, m in seen.items() if p.kind == "steady"]
            if not steady or exhausted:
                break
            u_best, best = max(steady, key=lambda x: x[0])
            for j, vals in axes:
                x = list(best.point())
                lo_b, hi_b = min(vals), max(vals)
                if hi_b <= lo_b:
                    continue
                others = sorted(v for v in vals if v != x[j])
                below = [v for v in others if v < x[j]]
                above = [v for v in others if v > x[j]]
                step = 0.25 * (hi_b - lo_b)
                if below and above:
                    step = 0.5 * min(x[j] - below[-1], above[0] - x[j])
                elif above:
                    step = 0.5 * (above[0] - x[j])
                elif below:
                    step = 0.5 * (x[j] - below[-1])
                step *= 0.5 ** rnd
                for _ in range(3):
                    cands = []
                    for s in (-step, step):
                        y = list(x)
                        y[j] = min(max(x[j] + s, lo_b), hi_b)
                        if y[j] == x[j]:
                            continue
                        p = Probe("steady", *y)
                        m = visit(p)
                        if m is not None:
                            cands.append((m["u"], p))
                    if cands:
                        u_c, p_c = max(cands, key=lambda c: c[0])
                        if u_c > u_best:
                            u_best, best, x = u_c, p_c, list(p_c.point())
                    step *= 0.5
                    if exhausted:
                        break
        worst_p = max(seen, key=lambda p: seen[p]["u"])
        worst = dict(seen[worst_p], probe=worst_p.describe())
        ok = (not exhausted) and worst["u"] <= margin
        return {"worst": worst, "worst_probe": worst_p, "native_runs": ev.native_runs - start,
                "exhausted": exhausted, "within_target": bool(ok),
                "worst_by_measure": worst_by_measure(seen.values(), [p.describe() for p in seen]),
                "probes": [dict(seen[p], probe=p.describe()) for p in seen]}


def worst_by_measure(rows, names) -> Dict[str, dict]:
    """Per measure of :data:`MEASURES`: its largest ``value`` over ``rows`` (dicts of measures)
    and the name (of ``names``) of the row where it is."""
    out: Dict[str, dict] = {}
    for m, name in zip(rows, names):
        for k in MEASURES:
            if k in m and (k not in out or m[k] > out[k]["value"]):
                out[k] = {"value": float(m[k]), "at": name}
    return out


# ============================================================== verification drives
@dataclass(frozen=True)
class DriveCase:
    """One verification drive, the same for both FMUs (docs/plan.md "Verification
    through the FMUs"): communication step ``comm_step_s`` (s); per step the held
    (zero-order hold) inputs ``pinion_torque_Nm`` and ``gear_torque_Nm`` (N*m) and the
    bulk temperature ``temperature_C`` (degC, None = the FMU's start value; an FMU
    without a temperature input gets none); ``pinion_speed_start_rad_s`` (rad/s); and
    ``speed_profile_rad_s``, the rigid-body pinion speed at the end of each step that the
    torques were computed for (the drive's target speed)."""

    name: str
    comm_step_s: float
    pinion_torque_Nm: np.ndarray
    gear_torque_Nm: np.ndarray
    temperature_C: Optional[np.ndarray]
    pinion_speed_start_rad_s: float
    speed_profile_rad_s: np.ndarray
    note: str = ""

    @property
    def stop_time_s(self) -> float:
        return self.comm_step_s * len(self.pinion_torque_Nm)


def drive_case(name: str, tables, *, stop_time_s: float, comm_step_s: float, torque_Nm, speed_rad_s,
               temperature_C=None, note: str = "") -> DriveCase:
    """A drive that makes the pinion follow a speed profile under a pinion torque profile.

    ``torque_Nm(t)``, ``speed_rad_s(t)``, ``temperature_C(t)`` (or None): callables of
    time arrays (s).  The communication step is shortened so that a whole number of
    steps fills ``stop_time_s``.  Per step [t_i, t_i+1] the pinion torque and the
    temperature are their values at the step's midpoint, and the gear (load) torque is
    the rigid-body inverse dynamics of the pinion-referred pair,
    T2 = (T1 - I_red * a) * Rb2 / Rb1 with I_red = I1 + I2 (Rb1/Rb2)^2 and
    a = (w(t_i+1) - w(t_i)) / H (the two-inertia model of Xu et al. 2022 with a rigid mesh), so a
    rigid pair under these held torques reaches w(t_i+1) exactly at every step end.
    """
    n = max(int(math.ceil(stop_time_s / comm_step_s - 1e-9)), 1)
    h = stop_time_s / n
    t = np.arange(n + 1) * h
    tm = t[:-1] + 0.5 * h
    w = np.asarray(speed_rad_s(t), dtype=float)
    T1 = np.asarray(torque_Nm(tm), dtype=float) * np.ones(n)
    rb1, rb2 = float(tables.base_radius_pinion_m), float(tables.base_radius_gear_m)
    i_red = float(tables.inertia_pinion_kgm2) + float(tables.inertia_gear_kgm2) * (rb1 / rb2) ** 2
    acc = np.diff(w) / h
    T2 = (T1 - i_red * acc) * rb2 / rb1
    temp = None if temperature_C is None else np.asarray(temperature_C(tm), dtype=float) * np.ones(n)
    return DriveCase(name=name, comm_step_s=h, pinion_torque_Nm=T1, gear_torque_Nm=T2, temperature_C=temp,
                     pinion_speed_start_rad_s=float(w[0]), speed_profile_rad_s=w[1:], note=note)


def constant(v):
    """A drive input held at ``v`` (a callable of time arrays), or None when ``v`` is None."""
    return None if v is None else (lambda t: np.full(np.shape(t), float(v)))


def speed_sweeps(tables, *, speed_range_rad_s, torque_Nm: float, temperature_C: Optional[float],
                 mesh_periods: float, comm_step_s: float, load_share: float = 0.1) -> List[DriveCase]:
    """Run-up and run-down drives (:func:`drive_case`) over ``speed_range_rad_s`` (rad/s) at a
    constant pinion torque (N*m) and temperature (degC or None): each lasts ``mesh_periods``
    mesh periods at the mean speed, and at least I_red (w1 - w0) / (``load_share`` x torque), so
    that the acceleration torque of the rigid pair stays within that share of the torque."""
    w0, w1 = speed_range_rad_s
    rb1, rb2 = float(tables.base_radius_pinion_m), float(tables.base_radius_gear_m)
    i_red = float(tables.inertia_pinion_kgm2) + float(tables.inertia_gear_kgm2) * (rb1 / rb2) ** 2
    t_run = max(mesh_periods * float(tables.mesh_period_rad) / (0.5 * (w0 + w1)),
                i_red * (w1 - w0) / (load_share * torque_Nm))
    out = []
    for name, a, b in (("run_up", w0, w1), ("run_down", w1, w0)):
        out.append(drive_case(name, tables, stop_time_s=t_run, comm_step_s=comm_step_s, torque_Nm=constant(torque_Nm),
                              speed_rad_s=lambda t, a=a, b=b: a + (b - a) * np.asarray(t) / t_run,
                              temperature_C=constant(temperature_C),
                              note=f"{a * 30 / math.pi:.6g} -> {b * 30 / math.pi:.6g} rpm in {t_run:.3g} s"))
    return out
