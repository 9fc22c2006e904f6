"""Run settings: how one run of the model goes (SI units), checked in one place.

A run of the pair model is configured by one :class:`RunSettings`: the native solver
(:func:`gearfmu.dynamics.native.simulate`, ``simulate_sdof``, the reference integrator), both
FMU builders (the DefaultExperiment and the start values, :mod:`gearfmu.fmu`), the planner and
the benchmarks take it.  :func:`gearfmu.stages.run_settings` builds it once from a scene and its
tables; a caller that runs a variant changes fields (:func:`checked`, ``dataclasses.replace``),
and every new value is checked again by the same rule.

A gearbox run (:func:`gearfmu.gearbox.native.simulate`) takes :class:`GearboxRunSettings`, the
extension of the same experiment and integration fields (names, units, defaults and check shared
through :class:`RunBase`) with the gearbox's two ends -- motor and load -- in place of the pair's
pinion and gear (a pair is the two-body gearbox with the pinion at the motor end).

Every setting is checked once in Python, when a settings object is made
(:class:`RunSettingsError` naming the field; :func:`checked` re-raises it as the caller's own
error class), and once more in C by the FMU at run time (``gkfmu.c``).  The defaults live here:
the field defaults and :func:`default_output_interval_s`.  The automatic values that need the
tables -- the step bound and the balancing gear torque -- are resolved on them by
:func:`gearfmu.dynamics.native.resolve_settings` (the gearbox's by
:func:`gearfmu.gearbox.native.resolve_settings`).
"""
from __future__ import annotations

import dataclasses
import math
import numbers
from dataclasses import dataclass
from typing import Optional, Tuple

from .checks import finite_number
from .vocabulary import (DAMPING_MODELS, DEFAULT_DAMPING_MODEL, DEFAULT_INTEGRATOR, GEARBOX_INTEGRATORS, INTEGRATORS,
                         current_spelling)

__all__ = ["RunSettingsError", "RunBase", "RunSettings", "GearboxRunSettings", "checked", "field_names",
           "default_output_interval_s", "OUTPUT_SAMPLES_PER_MESH", "SOLVER_ARGUMENTS"]

#: samples per mesh period of a defaulted output (communication) interval
OUTPUT_SAMPLES_PER_MESH = 20


def default_output_interval_s(pinion_speed_rad_s: float, pinion_teeth: int,
                              samples_per_mesh: int = OUTPUT_SAMPLES_PER_MESH) -> float:
    """The output (communication) interval, s, used wherever the user gives none.

    At least ``samples_per_mesh`` samples per mesh period 2*pi / (z1 |omega1|) at the
    pinion speed ``pinion_speed_rad_s`` (rad/s), rounded down to 1, 2 or 5 x 10^n s so
    that the DefaultExperiment reads well (so 20 to 50 samples per mesh period).  A fixed
    interval aliases the mesh frequency: 1e-4 s is 6 samples per mesh period at 1667 Hz.
    A zero speed falls back to the mesh period at 1 rad/s.
    """
    w = abs(float(pinion_speed_rad_s)) or 1.0
    h = 2.0 * math.pi / (int(pinion_teeth) * w) / int(samples_per_mesh)
    e = math.floor(math.log10(h))
    m = h / 10.0 ** e
    return float(max(c for c in (1.0, 2.0, 5.0, 10.0) if c <= m * (1 + 1e-12)) * 10.0 ** e)


class RunSettingsError(ValueError):
    """A run setting is invalid; the message names the field and the reason."""


def _number(name: str, value, *, positive: bool = False, nonneg: bool = False, optional: bool = False):
    if optional and value is None:
        return None
    return finite_number(name, value, positive=positive, nonneg=nonneg, error=RunSettingsError)


def _code_name(name: str, value, codes: dict, allowed, where: str = "") -> str:
    """``value`` (a name of ``codes`` or its integer code) as the name; RunSettingsError otherwise
    (``where``: what the names are offered for, e.g. " for gearboxes")."""
    if isinstance(value, str):
        value = current_spelling(name, value)
        if value in codes and value in allowed:
            return value
        raise RunSettingsError(f"{name}: {value!r} unknown{where}; choose one of {sorted(allowed)}")
    if not isinstance(value, bool) and isinstance(value, numbers.Integral):
        names = [n for n, c in codes.items() if c == value and n in allowed]
        if names:
            return names[0]
    raise RunSettingsError(f"{name}: {value!r} must be one of {sorted(allowed)} or its code "
                           f"({', '.join(f'{codes[n]} = {n}' for n in sorted(allowed, key=codes.get))})")


@dataclass(frozen=True)
class RunBase:
    """The experiment and the integration, shared by every run (SI units).

    ``stop_time_s``: the run's length (s, > 0; the FMU's DefaultExperiment stopTime);
    ``output_interval_s``: the output (communication) interval H (s, > 0; the FMU's
    DefaultExperiment stepSize; None: :func:`default_output_interval_s` at the start speed, at
    most the stop time); ``max_step_s``: the largest internal step (s, > 0; None: the automatic
    step on the tables, ``resolve_settings``); ``integrator``: one of
    :data:`gearfmu.common.vocabulary.INTEGRATORS` (its integer code is accepted and stored as
    the name)."""

    stop_time_s: float = 0.1
    output_interval_s: Optional[float] = None
    max_step_s: Optional[float] = None
    integrator: str = DEFAULT_INTEGRATOR

    #: the integrators this kind of run offers, and for what (the error message)
    INTEGRATOR_NAMES = tuple(INTEGRATORS)
    INTEGRATORS_FOR = ""

    def __post_init__(self):
        for name, value in self._checked_fields():
            object.__setattr__(self, name, value)

    def _checked_fields(self):
        """(field, checked value) of every field: the one check of the run settings."""
        yield "stop_time_s", _number("stop_time_s", self.stop_time_s, positive=True)
        yield "output_interval_s", _number("output_interval_s", self.output_interval_s, positive=True, optional=True)
        yield "max_step_s", _number("max_step_s", self.max_step_s, positive=True, optional=True)
        yield "integrator", _code_name("integrator", self.integrator, INTEGRATORS, self.INTEGRATOR_NAMES,
                                       self.INTEGRATORS_FOR)

    @property
    def integrator_code(self) -> int:
        """The integrator's code (:data:`gearfmu.common.vocabulary.INTEGRATORS`, the FMU parameter)."""
        return INTEGRATORS[self.integrator]

    def output_interval_for(self, pinion_speed_rad_s: float, pinion_teeth: int) -> float:
        """``output_interval_s``, or when None :func:`default_output_interval_s` at the pinion
        speed (rad/s) and teeth, at most the stop time."""
        if self.output_interval_s is not None:
            return self.output_interval_s
        return min(default_output_interval_s(pinion_speed_rad_s, pinion_teeth), self.stop_time_s)


@dataclass(frozen=True)
class RunSettings(RunBase):
    """The settings of one run of the gear-pair model (SI units), checked when made.

    The experiment and integration fields of :class:`RunBase`, then: ``damping_ratio`` the mesh
    damping ratio zeta (>= 0); ``damping_model`` one of
    :data:`gearfmu.common.vocabulary.DAMPING_MODELS` (name or code, an older spelling with a
    warning; stored as the name); the pinion's start speed (rad/s) and angle (rad); the start
    torques (N*m) of the pinion and of the gear (``gear_torque_start_Nm`` None: the static
    balance T1 Rb2/Rb1 on the tables).  The FMU's start values and its DefaultExperiment are
    these numbers; the native solver's inputs default to the start torques held constant."""

    damping_ratio: float = 0.02
    damping_model: str = DEFAULT_DAMPING_MODEL
    pinion_speed_start_rad_s: float = 100.0
    pinion_angle_start_rad: float = 0.0
    pinion_torque_start_Nm: float = 100.0
    gear_torque_start_Nm: Optional[float] = None

    def _checked_fields(self):
        yield from super()._checked_fields()
        yield "damping_ratio", _number("damping_ratio", self.damping_ratio, nonneg=True)
        yield "damping_model", _code_name("damping_model", self.damping_model, DAMPING_MODELS, tuple(DAMPING_MODELS))
        yield "pinion_speed_start_rad_s", _number("pinion_speed_start_rad_s", self.pinion_speed_start_rad_s)
        yield "pinion_angle_start_rad", _number("pinion_angle_start_rad", self.pinion_angle_start_rad)
        yield "pinion_torque_start_Nm", _number("pinion_torque_start_Nm", self.pinion_torque_start_Nm)
        yield "gear_torque_start_Nm", _number("gear_torque_start_Nm", self.gear_torque_start_Nm, optional=True)

    @property
    def damping_model_code(self) -> int:
        """The damping model's code (:data:`gearfmu.common.vocabulary.DAMPING_MODELS`, the FMU parameter)."""
        return DAMPING_MODELS[self.damping_model]


@dataclass(frozen=True)
class GearboxRunSettings(RunBase):
    """The settings of one run of a gearbox (docs/gearbox.md; SI units), checked when made.

    The experiment and integration fields of :class:`RunBase` (the integrator one of
    :data:`gearfmu.common.vocabulary.GEARBOX_INTEGRATORS`), then the gearbox's ends: the motor's
    start speed (rad/s) and angle (rad), the start torques (N*m) of the motor and of the load
    (``load_torque_start_Nm`` None: the torque that balances the motor's through the gearbox).
    The mesh damping is each stage's (the gearbox model's meshes)."""

    motor_speed_start_rad_s: float = 100.0
    motor_angle_start_rad: float = 0.0
    motor_torque_start_Nm: float = 100.0
    load_torque_start_Nm: Optional[float] = None

    INTEGRATOR_NAMES = tuple(GEARBOX_INTEGRATORS)
    INTEGRATORS_FOR = " for gearboxes"

    def _checked_fields(self):
        yield from super()._checked_fields()
        yield "motor_speed_start_rad_s", _number("motor_speed_start_rad_s", self.motor_speed_start_rad_s)
        yield "motor_angle_start_rad", _number("motor_angle_start_rad", self.motor_angle_start_rad)
        yield "motor_torque_start_Nm", _number("motor_torque_start_Nm", self.motor_torque_start_Nm)
        yield "load_torque_start_Nm", _number("load_torque_start_Nm", self.load_torque_start_Nm, optional=True)


#: the keyword arguments of the solvers that set a field under another name (field -> argument)
SOLVER_ARGUMENTS = {"output_interval_s": "comm_step_s"}


def checked(settings: Optional[RunBase], error=RunSettingsError, kind=RunSettings, names: Optional[dict] = None,
            **changes) -> RunBase:
    """``settings`` (None: the defaults of ``kind``) with the fields of ``changes`` whose value is
    not None, as a checked settings object; a bad value raises ``error`` (a ValueError subclass,
    the caller's own) naming the field -- by the caller's argument name when ``names`` (field ->
    argument) gives one and the value came from that argument.  Unchanged settings are returned
    as they are."""
    if settings is None:
        settings = kind()
    elif not isinstance(settings, kind):
        raise error(f"settings: expected {kind.__name__}, got {type(settings).__name__}")
    given = {k: v for k, v in changes.items() if v is not None}
    if not given:
        return settings
    try:
        return dataclasses.replace(settings, **given)
    except RunSettingsError as exc:
        msg = str(exc)
        field = msg.split(":", 1)[0]
        if names and field in names and field in given:
            msg = names[field] + msg[len(field):]
        if error is RunSettingsError and msg == str(exc):
            raise
        raise error(msg) from None


def field_names(kind=RunSettings) -> Tuple[str, ...]:
    """The field names of a settings class (in order)."""
    return tuple(f.name for f in dataclasses.fields(kind))
