"""Operating envelope and accuracy target of a scene (``[envelope]``, ``[accuracy]``).

The fidelity planner (:mod:`gearfmu.plan`, docs/plan.md) chooses the model a
scene needs from two statements of the scene:

* the **operating envelope** -- the pinion torque, pinion speed and bulk
  temperature ranges the FMU will see, given as ranges or as a duty cycle
  (a CSV time series, whose extremes then widen the ranges), and
* the **accuracy target** -- the largest acceptable relative error of the
  dynamic transmission error (DTE) and of the dynamic mesh force, as a
  relative RMS difference from the full-fidelity model over the envelope.

:func:`read_envelope_sections` is called by :func:`gearfmu.scene.reader.load_scene`
and fills :attr:`gearfmu.scene.reader.Scene.envelope` / ``.accuracy`` (SI); bad
input is reported with the key path like every scene problem.  Every key is
documented in docs/scene.md.

Choices (docs/plan.md):

* Missing ranges fall back to ``[operating]``'s ``torque_range_Nm`` /
  ``speed_range_rpm`` and then to the nominal point; a missing temperature
  range means "no temperature variation" (thermal effects get no budget).
* The duty-cycle CSV has a header row naming its columns; ``time_s``,
  ``torque_Nm`` and ``speed_rpm`` are required, ``temperature_C`` is
  optional (the same unit-in-the-name rule as the scene keys).  Its path is
  relative to the scene file.
"""
from __future__ import annotations

import csv
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Optional, Tuple

import numpy as np

from ..common.user_files import read_text
from .options import RPM_TO_RAD_S

__all__ = ["EnvelopeError", "DutyCycle", "Envelope", "AccuracyTarget", "load_duty_cycle_csv",
           "read_envelope_sections", "envelope_of", "accuracy_of", "check_target", "PLAN_CHOICES",
           "VerifiedEnvelope"]


#: names of the modelling choices a scene may pin (``accuracy.pin``), docs/plan.md
PLAN_CHOICES = ("contact_model", "thermal", "tooth_specific_errors", "slices", "points_per_mesh",
                "torque_points", "slots", "integrator", "max_step")


class EnvelopeError(ValueError):
    """Bad envelope / accuracy input; the message names the field and the reason."""


@dataclass(frozen=True)
class DutyCycle:
    """A duty cycle: ``time_s`` (s, strictly ascending), pinion ``torque_Nm`` (N*m),
    pinion ``speed_rad_s`` (rad/s) and optional bulk ``temperature_C`` (degC), one
    value per time point (piecewise linear in between)."""

    time_s: np.ndarray
    torque_Nm: np.ndarray
    speed_rad_s: np.ndarray
    temperature_C: Optional[np.ndarray] = None
    source: str = ""


@dataclass(frozen=True)
class Envelope:
    """Operating envelope (SI): ``(low, high)`` pinion torque (N*m), pinion speed
    (rad/s) and bulk temperature (degC, None = no variation), the nominal point,
    and the duty cycle when one was given."""

    torque_range_Nm: Tuple[float, float]
    speed_range_rad_s: Tuple[float, float]
    nominal_torque_Nm: float
    nominal_speed_rad_s: float
    temperature_range_C: Optional[Tuple[float, float]] = None
    duty_cycle: Optional[DutyCycle] = None

    def torques_Nm(self) -> Tuple[float, ...]:
        """Torque levels of the planner's envelope points: low, nominal, high (distinct, > 0)."""
        return _levels(self.torque_range_Nm, self.nominal_torque_Nm, positive=True)

    def speeds_rad_s(self) -> Tuple[float, ...]:
        """Speed levels of the planner's envelope points: low, nominal, high (distinct, > 0)."""
        return _levels(self.speed_range_rad_s, self.nominal_speed_rad_s, positive=True)

    def temperatures_C(self) -> Tuple[float, ...]:
        """Temperature corners (empty when the envelope has no temperature range)."""
        if self.temperature_range_C is None:
            return ()
        lo, hi = self.temperature_range_C
        return (lo,) if hi == lo else (lo, hi)


@dataclass(frozen=True)
class AccuracyTarget:
    """Accuracy target (dimensionless relative RMS errors, docs/plan.md "Error measure").

    ``dte_rel`` / ``mesh_force_rel``: largest acceptable rms(reduced - full) /
    rms(full) of the DTE and of the total mesh force over the envelope points;
    ``safety_factor``: share of the target the summed single-choice estimates
    may use; ``run_mesh_periods``: length of each dynamic comparison run (mesh
    periods); ``pin``: choices taken from the scene as written (``PLAN_CHOICES``).
    """

    dte_rel: float = 0.02
    mesh_force_rel: float = 0.02
    safety_factor: float = 0.8
    run_mesh_periods: int = 40
    pin: Tuple[str, ...] = ()


@dataclass(frozen=True)
class VerifiedEnvelope:
    """What was verified about a model over its envelope, as plain data (docs/plan.md
    "Verified envelope"), for an FMU's validation record and model description (the FMU's
    envelope record, :func:`gearfmu.fmu.envelope.fmu_envelope_record`, reads this dict).

    ``kind``: "plan verification" (the planner's envelope search of the planned model) or
    "as-written estimate" (``gearfmu build`` of a scene without ``[accuracy]``: a cheap
    search of the scene as written).  Ranges: pinion torque (N*m), pinion speed (rpm),
    bulk temperature (degC, None = no variation).  Targets and worst errors are
    dimensionless, measured as ``error_definition`` says (relative RMS; ``*_max_rel`` =
    max|diff| / range of the full-fidelity signal) against the full-fidelity model;
    ``worst_at``: where the worst error was found (case; torque, speed, temperature; the
    time window of a transient).  ``within_target``: the search found no point above the
    target; ``fmu_confirmed``: None when the FMUs were not run, else whether the FMU
    cases stayed within the target.  ``native_runs`` / ``probes``: the search's size."""

    kind: str
    torque_range_Nm: Tuple[float, float]
    speed_range_rpm: Tuple[float, float]
    temperature_range_C: Optional[Tuple[float, float]]
    dte_target_rel: float
    mesh_force_target_rel: float
    error_definition: str
    within_target: bool
    worst_dte_rel: float
    worst_mesh_force_rel: float
    worst_dte_max_rel: float
    worst_mesh_force_max_rel: float
    worst_at: dict = field(default_factory=dict)
    native_runs: int = 0
    probes: int = 0
    fmu_confirmed: Optional[bool] = None

    def to_dict(self) -> dict:
        """JSON-ready dict (tuples as lists, non-finite numbers as None)."""
        def clean(v):
            if isinstance(v, dict):
                return {k: clean(x) for k, x in v.items()}
            if isinstance(v, (list, tuple)):
                return [clean(x) for x in v]
            if isinstance(v, float) and not math.isfinite(v):
                return None
            return v
        return clean(asdict(self))


def _levels(rng, nominal, positive):
    vals = sorted({float(rng[0]), float(nominal), float(rng[1])})
    if positive:
        vals = [v for v in vals if v > 0] or [float(nominal)]
    return tuple(vals)


# ------------------------------------------------------------------ duty cycle
def load_duty_cycle_csv(path) -> DutyCycle:
    """Read a duty-cycle CSV: a header row with ``time_s``, ``torque_Nm``,
    ``speed_rpm`` and optionally ``temperature_C`` (any order, extra columns
    rejected), then one row per time point.  Raises :class:`EnvelopeError`
    naming the column / row and the reason."""
    p = Path(path)
    try:
        text = read_text(p, "a duty-cycle CSV", EnvelopeError)
    except FileNotFoundError:
        raise EnvelopeError(f"duty_cycle_csv: file not found: {p}") from None
    except OSError as exc:
        raise EnvelopeError(f"duty_cycle_csv: cannot read {p}: {exc.strerror or exc}") from None
    except EnvelopeError as exc:  # not text: a zip archive, a binary file, not UTF-8
        raise EnvelopeError(f"duty_cycle_csv: {exc}") from None
    rows = [r for r in csv.reader(line for line in text.splitlines() if line.strip() and
                                  not line.lstrip().startswith("#"))]
    if not rows:
        raise EnvelopeError(f"duty_cycle_csv: {p} is empty")
    head = [h.strip() for h in rows[0]]
    allowed = ("time_s", "torque_Nm", "speed_rpm", "temperature_C")
    for h in head:
        if h not in allowed:
            raise EnvelopeError(f"duty_cycle_csv: unknown column {h!r} in {p} (allowed: {', '.join(allowed)})")
    for need in allowed[:3]:
        if need not in head:
            raise EnvelopeError(f"duty_cycle_csv: missing column {need!r} in {p}")
    if len(set(head)) != len(head):
        raise EnvelopeError(f"duty_cycle_csv: repeated column in {p}")
    data = []
    for i, r in enumerate(rows[1:], start=2):
        if len(r) != len(head):
            raise EnvelopeError(f"duty_cycle_csv: row {i} of {p} has {len(r)} values, expected {len(head)}")
        try:
            vals = [float(x) for x in r]
        except ValueError:
            raise EnvelopeError(f"duty_cycle_csv: row {i} of {p} holds a non-number: {r!r}") from None
        if not all(math.isfinite(v) for v in vals):
            raise EnvelopeError(f"duty_cycle_csv: row {i} of {p} holds a non-finite value: {r!r}")
        data.append(vals)
    if len(data) < 2:
        raise EnvelopeError(f"duty_cycle_csv: {p} needs at least 2 rows of data, got {len(data)}")
    a = np.array(data)
    col = {h: a[:, j] for j, h in enumerate(head)}
    t = col["time_s"]
    if np.any(np.diff(t) <= 0):
        raise EnvelopeError(f"duty_cycle_csv: time_s must be strictly ascending in {p}")
    if np.any(col["torque_Nm"] < 0) or np.any(col["speed_rpm"] <= 0):
        raise EnvelopeError(f"duty_cycle_csv: torque_Nm must be >= 0 and speed_rpm > 0 in {p}")
    temp = col.get("temperature_C")
    if temp is not None and (np.any(temp < -200) or np.any(temp > 500)):
        raise EnvelopeError(f"duty_cycle_csv: temperature_C must lie in [-200, 500] in {p}")
    return DutyCycle(time_s=t, torque_Nm=col["torque_Nm"], speed_rad_s=col["speed_rpm"] * RPM_TO_RAD_S,
                     temperature_C=temp, source=str(p))


# ------------------------------------------------------------------ scene sections
def read_envelope_sections(reader, data: Any, operating: dict, source_path: Optional[str]):
    """Read ``[envelope]`` and ``[accuracy]`` of a parsed scene with the scene
    reader (:class:`gearfmu.scene.validate.Reader`; problems are added to it with their key
    paths).  ``operating``: the SI values of ``[operating]``.  Returns
    ``(Envelope or None, AccuracyTarget or None)``: None for a section that is
    absent or invalid (then a problem was recorded)."""
    envelope = accuracy = None
    got = reader.section(data, "envelope")
    if got is not None:
        envelope = _envelope(reader, got[1], operating, source_path)
    got = reader.section(data, "accuracy")
    if got is not None:
        a = got[1]
        bad = [p for p in a["pin"] if p not in PLAN_CHOICES]
        if bad:
            reader.add("accuracy.pin", f"unknown choice {bad[0]!r}; choices: {', '.join(PLAN_CHOICES)}")
        else:
            accuracy = AccuracyTarget(dte_rel=a["dte_rel_error"], mesh_force_rel=a["mesh_force_rel_error"],
                                      safety_factor=a["safety_factor"], run_mesh_periods=a["run_mesh_periods"],
                                      pin=tuple(a["pin"]))
    return envelope, accuracy


def _envelope(reader, e: dict, op: dict, source_path: Optional[str]) -> Optional[Envelope]:
    t_nom, w_nom = op.get("torque_Nm"), op.get("speed_rpm")
    if t_nom is None or w_nom is None:
        return None
    tr = e["torque_range_Nm"] or op.get("torque_range_Nm") or (t_nom, t_nom)
    wr = e["speed_range_rpm"] or op.get("speed_range_rpm") or (w_nom, w_nom)
    temp = e["temperature_range_C"]
    duty = None
    if e["duty_cycle_csv"]:
        p = Path(e["duty_cycle_csv"])
        if not p.is_absolute() and source_path:
            p = Path(source_path).resolve().parent / p
        try:
            duty = load_duty_cycle_csv(p)
        except EnvelopeError as exc:
            reader.add("envelope.duty_cycle_csv", str(exc).split(": ", 1)[1])
            return None
        tr = (min(tr[0], float(duty.torque_Nm.min())), max(tr[1], float(duty.torque_Nm.max())))
        wr = (min(wr[0], float(duty.speed_rad_s.min())), max(wr[1], float(duty.speed_rad_s.max())))
        if duty.temperature_C is not None:
            lo, hi = float(duty.temperature_C.min()), float(duty.temperature_C.max())
            temp = (lo, hi) if temp is None else (min(temp[0], lo), max(temp[1], hi))
    if wr[0] <= 0:
        reader.add("envelope.speed_range_rpm", f"low end must be > 0, got {wr[0] / RPM_TO_RAD_S:g}")
        return None
    return Envelope(torque_range_Nm=(float(tr[0]), float(tr[1])), speed_range_rad_s=(float(wr[0]), float(wr[1])),
                    nominal_torque_Nm=float(t_nom), nominal_speed_rad_s=float(w_nom),
                    temperature_range_C=None if temp is None else (float(temp[0]), float(temp[1])),
                    duty_cycle=duty)


# ------------------------------------------------------------------ defaults for a scene
def envelope_of(scene) -> Envelope:
    """The scene's envelope: its ``[envelope]`` section, else built from
    ``[operating]`` (ranges or the nominal point) and ``[thermal]``'s
    temperature axis (its first and last value) when it has one."""
    env = scene.envelope
    if env is not None:
        return env
    op = scene.operating
    tr = op.torque_range_Nm or (op.torque_Nm, op.torque_Nm)
    wr = op.speed_range_rad_s or (op.speed_rad_s, op.speed_rad_s)
    temp = None
    th = scene.thermal
    if th is not None and len(th.temperature_axis_C) > 1:
        temp = (float(th.temperature_axis_C[0]), float(th.temperature_axis_C[-1]))
    return Envelope(torque_range_Nm=(float(tr[0]), float(tr[1])), speed_range_rad_s=(float(wr[0]), float(wr[1])),
                    nominal_torque_Nm=float(op.torque_Nm), nominal_speed_rad_s=float(op.speed_rad_s),
                    temperature_range_C=temp)


def accuracy_of(scene) -> AccuracyTarget:
    """The scene's ``[accuracy]`` target, else the defaults of :class:`AccuracyTarget`."""
    acc = scene.accuracy
    return acc if acc is not None else AccuracyTarget()


def check_target(dte_rel: float, mesh_force_rel: float) -> None:
    """Raise :class:`EnvelopeError` unless both targets are finite and in (0, 1]."""
    for name, v in (("dte_rel", dte_rel), ("mesh_force_rel", mesh_force_rel)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and 0 < v <= 1):
            raise EnvelopeError(f"{name}: must be a number in (0, 1], got {v!r}")
