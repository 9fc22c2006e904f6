"""Native (numba) solver of the multi-pair gear dynamic model (SI units).

Implements docs/model.md to the letter -- the contract shared with the FMU's C
kernel (gearfmu/fmu/kernel/gearkernel.c): the same table lookup, per-pair force
law, RK4 arithmetic order and initial-state bisection, so that the two
independent implementations agree to round-off on the same tables, inputs and
steps.  No fastmath (it would reorder the arithmetic).

Model: Xu et al. 2022 eq (1)-(6) (two-inertia torsional pair, P tooth-pair slots,
per-pair stiffness k_j, damping c, meshing error e_j and half backlash b_j),
indexed by the pinion angle; state y = [theta1 (rad), omega1 (rad/s),
x (m), v (m/s)], x = theta1*Rb1 - theta2*Rb2 the dynamic transmission error.

The compiled parts live in gearfmu.dynamics.model_rhs (table lookup, force
laws, equilibrium), gearfmu.dynamics.integrators ('rk4', 'rk4_kink', 'rk4_node', 'rk4_seg') and
gearfmu.dynamics.driver (the one loop over communication steps); this module
checks the inputs (the settings are checked by :class:`gearfmu.common.settings.RunSettings`),
prepares the tables and inputs and wraps the results.

Public API
----------
* :func:`simulate` -- the FMU model, outputs named as the FMU outputs.
* :func:`simulate_sdof` -- time-indexed SDOF form (Xu et al. 2022 eq 3-6) at a
  prescribed constant pinion speed.
* :func:`dimensionless` -- Xu et al. 2022 eq 7-9 rescaling of a result.
* :func:`choose_max_step_s` -- default internal step.
* :func:`resolve_settings` -- a run's :class:`gearfmu.common.settings.RunSettings` with its
  automatic values (output interval, step bound, balancing gear torque) resolved on the tables,
  the rule the FMU builders share.
* :class:`SimResult` -- result arrays, ``to_csv``, ``wall_s``; :func:`derived_outputs` -- the
  outputs derived from a run's rows (gear speed and angle, load sharing), shared with the reference.
* :data:`SETTINGS_KEYWORDS`, :func:`settings_changes` -- the keyword arguments of the solvers that
  set a run setting (``comm_step_s`` sets ``output_interval_s``).

Details and choices: docs/native.md.
"""
from __future__ import annotations

import dataclasses
import math
import time as _time
import weakref
from dataclasses import dataclass, field
from typing import Callable, Optional, Union

import numpy as np

from ..common.checks import finite_number
from ..common.settings import SOLVER_ARGUMENTS, RunSettings, checked
from ..common.vocabulary import DAMPING_MODELS, DEFAULT_INTEGRATOR, INTEGRATORS
from ..tables.mesh_tables import MeshTables, TemperatureRangeError
from ..tables.zones import zone_cuts
from .driver import NO_CUTS, _warmup, compiling, driver_for
from .integrators import KINK_MAX_SLOTS
from .model_rhs import _equilibrium, _equilibrium_zoned

__all__ = [
    "NativeInputError",
    "SimResult",
    "DimensionlessResult",
    "DAMPING_MODELS",
    "INTEGRATORS",
    "DEFAULT_INTEGRATOR",
    "simulate",
    "simulate_sdof",
    "dimensionless",
    "choose_max_step_s",
    "resolve_settings",
    "integrator_code",
    "equilibrium_dte_m",
    "substeps",
    "whole_steps",
    "input_series",
    "write_columns_csv",
    "derived_outputs",
    "settings_changes",
    "SETTINGS_KEYWORDS",
    "SDOF_SETTINGS_KEYWORDS",
]


InputLike = Union[float, np.ndarray, Callable[[float], float]]


class NativeInputError(ValueError):
    """Bad argument to the native solver; the message names the argument."""


# ------------------------------------------------------------ python layer
@dataclass
class SimResult:
    """Result of :func:`simulate` / :func:`simulate_sdof` (SI units).

    Row 0 is the initial state (outputs at t = 0 with the initial inputs), then
    one row per communication step.  Arrays carry the FMU output names
    (docs/model.md "Outputs"): pinion_speed, gear_speed (rad/s), pinion_angle,
    gear_angle (rad), dte (m), mesh_force (N), pair_force (n_out, P) in N,
    load_sharing (n_out, P) dimensionless, mesh_stiffness (N/m).  Also the
    inputs used per row (pinion_torque, gear_torque in N*m), the relative
    velocity ``dte_rate`` (m/s), the internal step ``step_s`` and substeps per
    communication step, and ``wall_s`` (wall time of the compiled loop, s).
    """

    time_s: np.ndarray
    pinion_speed: np.ndarray
    gear_speed: np.ndarray
    pinion_angle: np.ndarray
    gear_angle: np.ndarray
    dte: np.ndarray
    dte_rate: np.ndarray
    mesh_force: np.ndarray
    pair_force: np.ndarray
    load_sharing: np.ndarray
    mesh_stiffness: np.ndarray
    pinion_torque: np.ndarray
    gear_torque: np.ndarray
    step_s: float
    substeps: int
    damping_Ns_per_m: float
    damping_model: str
    wall_s: float
    info: dict = field(default_factory=dict)

    OUTPUT_UNITS = {
        "pinion_speed": "rad/s", "gear_speed": "rad/s", "pinion_angle": "rad",
        "gear_angle": "rad", "dte": "m", "mesh_force": "N", "mesh_stiffness": "N/m",
    }

    @property
    def slots(self) -> int:
        return int(self.pair_force.shape[1])

    def columns(self) -> dict:
        """Ordered {name: (unit, 1-D array)} with FMU names; pair_force[i], i = 1..P."""
        cols = {"time": ("s", self.time_s)}
        for n in ("pinion_speed", "gear_speed", "pinion_angle", "gear_angle", "dte", "mesh_force"):
            cols[n] = (self.OUTPUT_UNITS[n], getattr(self, n))
        for i in range(self.slots):
            cols[f"pair_force[{i + 1}]"] = ("N", self.pair_force[:, i])
        for i in range(self.slots):
            cols[f"load_sharing[{i + 1}]"] = ("1", self.load_sharing[:, i])
        cols["mesh_stiffness"] = ("N/m", self.mesh_stiffness)
        cols["pinion_torque"] = ("N*m", self.pinion_torque)
        cols["gear_torque"] = ("N*m", self.gear_torque)
        return cols

    def to_csv(self, path) -> None:
        """Write :meth:`columns` as a CSV (:func:`write_columns_csv`)."""
        write_columns_csv(path, self.columns())


def write_columns_csv(path, cols) -> None:
    """The CSV of results (``SimResult.to_csv``, ``gearfmu simulate``): a ``# units:`` comment
    line (one unit per column), a row of names (the FMU's: ``pair_force[1]`` ...), then the data,
    comma-separated, 17 significant digits (round-trips float64).  ``cols``: ordered
    ``{name: (unit, 1-D array)}``."""
    data = np.column_stack([np.asarray(a, dtype=float) for _, a in cols.values()])
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("# units: " + ",".join(u for u, _ in cols.values()) + "\n")
        fh.write(",".join(cols) + "\n")
        np.savetxt(fh, data, delimiter=",", fmt="%.17g")


@dataclass
class DimensionlessResult:
    """Xu et al. 2022 eq 7-9 quantities: q = x/l, tau = omega_n t, Omega_h = omega_mesh/omega_n,
    zeta, and the dimensionless load F_m/(k_m l) (all dimensionless)."""

    tau: np.ndarray
    q: np.ndarray
    q_rate: np.ndarray
    Omega_h: float
    omega_n_rad_s: float
    zeta: float
    load: float
    length_scale_m: float


def _check_tables(tables) -> MeshTables:
    if not isinstance(tables, MeshTables):
        raise NativeInputError(f"tables: expected MeshTables, got {type(tables).__name__}")
    if tables.temperature_C is not None:
        raise NativeInputError("tables: have a temperature axis; pass bulk_temperature_C to simulate / "
                               "simulate_sdof, or select one with tables.at_temperature(T)")
    return _validated(tables)


#: id(tables) -> (weak reference, :func:`_fingerprint`) of tables that passed ``validate()``
_VALIDATED: dict = {}


def _fingerprint(t: MeshTables):
    """Everything ``MeshTables.validate`` reads -- every dataclass field but ``provenance``,
    arrays as (dtype, shape, bytes) -- or None when a field is neither an array, a number
    nor None (then nothing is cached)."""
    parts = [type(t)]
    for name in _fields_validated(type(t)):
        v = getattr(t, name)
        if isinstance(v, np.ndarray):
            parts.append((v.dtype.str, v.shape, v.tobytes()))
        elif v is None or isinstance(v, (float, int, np.floating, np.integer)):
            parts.append(v)
        else:
            return None
    return tuple(parts)


_FIELDS: dict = {}


def _fields_validated(cls) -> tuple:
    names = _FIELDS.get(cls)
    if names is None:
        names = _FIELDS[cls] = tuple(f.name for f in dataclasses.fields(cls) if f.name != "provenance")
    return names


def _validated(t: MeshTables) -> MeshTables:
    """``t.validate()``, skipped when ``t`` (the same object) passed it before and nothing
    validate reads has changed since, bit for bit (:func:`_fingerprint`); validate is a pure
    function of those fields, so the outcome is the same."""
    key = id(t)
    fp = _fingerprint(t)
    hit = _VALIDATED.get(key)
    if fp is not None and hit is not None and hit[0]() is t and hit[1] == fp:
        return t
    t.validate()
    if fp is not None:
        try:
            ref = weakref.ref(t, lambda _r, key=key: _VALIDATED.pop(key, None))
        except TypeError:  # no weak references (a subclass with __slots__): nothing cached
            return t
        _VALIDATED[key] = (ref, fp)
    return t


def _finite(name, value, *, positive=False, nonneg=False, error=None) -> float:
    """``value`` as a finite float (> 0 with ``positive``, >= 0 with ``nonneg``);
    otherwise ``error`` (default NativeInputError) naming ``name`` and the reason."""
    return finite_number(name, value, positive=positive, nonneg=nonneg,
                         error=NativeInputError if error is None else error)


def whole_steps(stop_time_s, comm_step_s, error=NativeInputError) -> int:
    """Number of communication steps in the run; ``error`` (naming stop_time_s)
    when the stop time is not a whole number of them."""
    n = stop_time_s / comm_step_s
    nr = int(round(n))
    if nr < 1 or abs(n - nr) > 1e-6 * max(1.0, n):
        raise error(
            f"stop_time_s: {stop_time_s!r} is not a whole number of communication steps "
            f"comm_step_s={comm_step_s!r} ({n:.9g})")
    return nr


def input_series(name, value: InputLike, n_steps: int, comm_step_s: float, error=NativeInputError) -> np.ndarray:
    """Input sampled at t_k = k*comm_step_s, k = 0..n_steps (the value held over step k);
    ``error`` naming ``name`` for a value of the wrong shape or not finite."""
    if isinstance(value, float) or type(value) is int:  # a number: one check, one fill
        v = float(value)
        if not math.isfinite(v):
            raise error(f"{name}: contains NaN or infinite values")
        arr = np.empty(n_steps + 1)
        arr.fill(v)
        return arr
    if callable(value):
        arr = np.array([float(value(k * comm_step_s)) for k in range(n_steps + 1)])
    else:
        a = np.asarray(value, dtype=float)
        if a.ndim == 0:
            arr = np.full(n_steps + 1, float(a))
        elif a.ndim == 1 and a.shape[0] in (n_steps, n_steps + 1):
            arr = np.empty(n_steps + 1)
            arr[: a.shape[0]] = a
            if a.shape[0] == n_steps:
                arr[n_steps] = a[-1]
        else:
            raise error(
                f"{name}: expected a number, a callable of time, or an array of {n_steps} "
                f"or {n_steps + 1} values (one per communication step), got shape {a.shape}")
    if not np.all(np.isfinite(arr)):
        raise error(f"{name}: contains NaN or infinite values")
    return np.ascontiguousarray(arr)


def substeps(comm_step_s: float, max_step_s: float) -> int:
    """n = max(1, ceil(H/h_max*(1 - 1e-12))) (docs/model.md 'Integration')."""
    return max(1, int(math.ceil(comm_step_s / max_step_s * (1.0 - 1e-12))))


def _arrays(tables: MeshTables):
    k = np.ascontiguousarray(tables.k_N_per_m, dtype=np.float64)
    e = np.ascontiguousarray(tables.e_m, dtype=np.float64)
    b = np.ascontiguousarray(tables.backlash_half_m, dtype=np.float64)
    tq = np.ascontiguousarray(tables.torque_Nm, dtype=np.float64)
    phi_period = float(tables.phi_period_rad)
    dphi = phi_period / tables.n_phi
    inv_dphi = tables.n_phi / phi_period  # docs/model.md 'Table lookup': N/Phi, one rounding
    return k, e, b, tq, inv_dphi, dphi, zone_cuts(tables)  # cuts: docs/model.md "Contact-zone edges"


def _damping(tables: MeshTables, damping_ratio) -> float:
    """c = 2*zeta*sqrt(k_mean*m_e), m_e = I1*I2/(I1*Rb2^2 + I2*Rb1^2) (docs/model.md,
    Xu et al. 2022 below eq 2), evaluated as I1*I2/(I1*Rb2*Rb2 + I2*Rb1*Rb1) left to right."""
    i1, i2 = float(tables.inertia_pinion_kgm2), float(tables.inertia_gear_kgm2)
    r1, r2 = float(tables.base_radius_pinion_m), float(tables.base_radius_gear_m)
    # left to right, I1*Rb2*Rb2 = (I1*Rb2)*Rb2: the order of the C kernel (bitwise agreement)
    me = i1 * i2 / (i1 * r2 * r2 + i2 * r1 * r1)
    return 2.0 * damping_ratio * math.sqrt(float(tables.k_mean_N_per_m) * me), me


def equilibrium_dte_m(tables: MeshTables, pinion_torque_Nm: float, pinion_angle_rad: float = 0.0) -> float:
    """Quasi-static equilibrium x (m) at the pinion angle under F_m = T1/Rb1, by the
    200-step bisection of docs/model.md 'Initial state'."""
    t = _check_tables(tables)
    x = _equilibrium_x(t, _arrays(t), _finite("pinion_angle_rad", pinion_angle_rad),
                       _finite("pinion_torque_Nm", pinion_torque_Nm))
    if not math.isfinite(x):
        raise NativeInputError(
            f"pinion_angle_rad: no tooth pair in the contact zone (all k = 0) at {pinion_angle_rad!r}; "
            "give dte_start_m")
    return float(x)


def choose_max_step_s(tables: MeshTables, max_speed_rad_s: float, points_per_period: int = 64) -> float:
    """Default maximum internal step (s).

    h_max = min(2*pi/omega_n, mesh period at max speed) / points_per_period with
    omega_n = sqrt(k_mean/m_e) (Xu et al. 2022 eq 7) and the mesh period in time
    mesh_period_rad/|max_speed_rad_s|.  RK4's global error then scales as
    (omega_n h)^4: with 64 points per period the phase error of a free
    oscillation is about (2 pi/64)^5/120 = 8e-8 per step (docs/native.md).
    """
    t = _check_tables(tables)
    ppp = int(points_per_period)
    if ppp != points_per_period or ppp < 1:
        raise NativeInputError(f"points_per_period: must be a positive integer, got {points_per_period!r}")
    return _max_step_s(t, abs(_finite("max_speed_rad_s", max_speed_rad_s)), ppp)


def _max_step_s(t: MeshTables, w: float, ppp: int) -> float:
    """:func:`choose_max_step_s` on checked tables at speed ``|w|`` (rad/s) and ``ppp`` points."""
    wn = math.sqrt(t.k_mean_N_per_m / t.equivalent_mass_kg)
    period = 2.0 * math.pi / wn
    if w > 0.0:
        period = min(period, t.mesh_period_rad / w)
    return period / ppp


def integrator_code(integrator: str, slots: int, error=NativeInputError) -> int:
    """The code of a (checked) integrator name on tables of ``slots`` slots: the event-locating
    integrators handle at most :data:`KINK_MAX_SLOTS` slots (``error`` naming ``integrator``
    otherwise; the FMU builders use this check too)."""
    if integrator != "rk4" and slots > KINK_MAX_SLOTS:
        raise error(f"integrator: {integrator!r} handles at most {KINK_MAX_SLOTS} slots, the tables have {slots}")
    return INTEGRATORS[integrator]


def resolve_settings(tables: MeshTables, settings: RunSettings, *,
                     step_speed_rad_s: Optional[float] = None) -> RunSettings:
    """``settings`` with its automatic values resolved on (checked) ``tables``: the output
    interval (:meth:`RunSettings.output_interval_for` at the start speed and the pinion's teeth),
    the step bound (:func:`choose_max_step_s`'s rule at ``step_speed_rad_s``, rad/s; None: 1.5 x
    the start speed, at least 1 rad/s) and the gear's start torque (the static balance
    T1 Rb2/Rb1, Xu et al. 2022: F_m = T1/Rb1 = T2/Rb2).  The native solver and both FMU builders
    resolve them by this one rule, so a run configured alike is the same run."""
    s = settings
    changes = {}
    if s.output_interval_s is None:
        changes["output_interval_s"] = s.output_interval_for(s.pinion_speed_start_rad_s, tables.teeth_pinion)
    if s.max_step_s is None:
        w = max(1.5 * abs(s.pinion_speed_start_rad_s), 1.0) if step_speed_rad_s is None else abs(step_speed_rad_s)
        changes["max_step_s"] = _max_step_s(tables, w, 64)
    if s.gear_torque_start_Nm is None:
        changes["gear_torque_start_Nm"] = (s.pinion_torque_start_Nm * float(tables.base_radius_gear_m)
                                           / float(tables.base_radius_pinion_m))
    return dataclasses.replace(s, **changes) if changes else s


def _settings(settings, error=NativeInputError, names=SOLVER_ARGUMENTS, **changes) -> RunSettings:
    """The run's settings: ``settings`` (None: the :class:`RunSettings` defaults) with the
    keyword arguments given (not None) in place of its fields, checked (``error`` naming the
    argument, ``names``: field -> argument name)."""
    return checked(settings, error, RunSettings, names, **changes)


def run_inputs(tables: MeshTables, s: RunSettings, pinion_torque_Nm, gear_torque_Nm, error=NativeInputError):
    """(number of communication steps, pinion torque, gear torque) of a run with resolved settings
    ``s`` (:func:`resolve_settings`): the torques one value per communication step (n_steps + 1,
    :func:`input_series`).  ``pinion_torque_Nm`` None: the start torque held; ``gear_torque_Nm``
    None: the balancing load T2 = T1*Rb2/Rb1 of the pinion input given, else the settings' start
    torque held.  ``error`` names the first bad one."""
    n_steps = whole_steps(s.stop_time_s, s.output_interval_s, error=error)
    H = s.output_interval_s
    t1s = input_series("pinion_torque_Nm", s.pinion_torque_start_Nm if pinion_torque_Nm is None else pinion_torque_Nm,
                       n_steps, H, error=error)
    if gear_torque_Nm is not None:
        t2s = input_series("gear_torque_Nm", gear_torque_Nm, n_steps, H, error=error)
    elif pinion_torque_Nm is None:
        t2s = input_series("gear_torque_Nm", s.gear_torque_start_Nm, n_steps, H, error=error)
    else:
        t2s = t1s * float(tables.base_radius_gear_m) / float(tables.base_radius_pinion_m)
    return n_steps, t1s, t2s


def start_state(dte_start_m, dte_rate_start_m_s, error=NativeInputError):
    """(x0 or None, v0): the given start deflection (m; None: the quasi-static equilibrium) and rate (m/s)."""
    x0 = None if dte_start_m is None else _finite("dte_start_m", dte_start_m, error=error)
    return x0, _finite("dte_rate_start_m_s", dte_rate_start_m_s, error=error)


def _equilibrium_x(t, arrays, theta1, t1):
    """docs/model.md 'Initial state' on the tables' ``arrays`` (:func:`_arrays`)."""
    k, e, b, tq, inv_dphi, dphi, cuts = arrays
    if cuts is None:
        return _equilibrium(theta1, t1, float(t.base_radius_pinion_m), k, e, b, tq, inv_dphi)
    return _equilibrium_zoned(theta1, t1, float(t.base_radius_pinion_m), k, e, b, tq, inv_dphi, cuts)


def _initial_x(t, arrays, theta1, t1, dte_start_m):
    if dte_start_m is not None:
        return dte_start_m
    x0 = _equilibrium_x(t, arrays, theta1, t1)
    if not math.isfinite(x0):
        raise NativeInputError(
            f"pinion_angle_start_rad: no tooth pair in the contact zone (all k = 0) at {theta1!r}; "
            "give dte_start_m")
    return x0


def derived_outputs(tables: MeshTables, state, pair, force) -> dict:
    """The outputs a run derives from its rows (docs/model.md "Outputs"), as :class:`SimResult`
    fields: of the state rows [theta1, omega1, x, v] (``state``, (n, 4)) the pinion angle and
    speed, the DTE and its rate, and the gear's angle and speed (theta1*Rb1 - x)/Rb2,
    (omega1*Rb1 - v)/Rb2; the load sharing ``pair``/``force`` of each pair where the mesh force is
    not 0 (else 0; NaN rows stay NaN).  Shared by the native solver and the reference
    (:mod:`gearfmu.dynamics.reference`)."""
    rb1, rb2 = float(tables.base_radius_pinion_m), float(tables.base_radius_gear_m)
    cols = state.T.copy()  # the four columns [theta1, omega1, x, v] as contiguous rows, one block
    th, om, x, v = cols
    gear_angle, gear_speed = (cols[:2] * rb1 - cols[2:]) / rb2  # (th*Rb1 - x)/Rb2, (om*Rb1 - v)/Rb2
    f = force[:, None]
    ls = np.zeros(pair.shape)  # pair / force where force != 0 (NaN rows stay NaN), else 0
    with np.errstate(invalid="ignore", divide="ignore"):
        np.divide(pair, f, out=ls, where=f != 0.0)
    return dict(pinion_speed=om, gear_speed=gear_speed, pinion_angle=th, gear_angle=gear_angle, dte=x, dte_rate=v,
                load_sharing=ls)


def _output_rows(n: int, p: int):
    """(state (n, 4), pair force (n, p), mesh force (n,), stiffness (n,)): the rows the driver
    writes, views of one block filled with NaN (rows left unwritten stay NaN)."""
    out = np.empty(n * (6 + p))
    out.fill(np.nan)
    return (out[:4 * n].reshape(n, 4), out[4 * n:(4 + p) * n].reshape(n, p), out[(4 + p) * n:(5 + p) * n],
            out[(5 + p) * n:])


def _integrate(t, arrays, s: RunSettings, icode, sdof, y0, t1s, t2s, info) -> SimResult:
    """The run on the compiled driver (gearfmu.dynamics.driver): on the tables ``t`` and their
    ``arrays`` (:func:`_arrays`) with resolved settings ``s``, integrator ``icode`` and form
    ``sdof``, from the start state ``y0`` = (theta1, omega1, x, v) under the torque inputs (one
    value per communication step).  The communication step H in substeps of at most
    ``s.max_step_s``, the damping coefficient, the output rows, the driver, then the result with
    the derived outputs; ``info`` gains the equivalent mass, the events located and the steps
    completed (and where the state diverged)."""
    H = s.output_interval_s
    n_sub = substeps(H, s.max_step_s)
    h = H / n_sub
    c, me = _damping(t, s.damping_ratio)
    n = t1s.shape[0]
    k, e, b, tq, inv_dphi, dphi, cuts = arrays
    state, pair, force, stiff = _output_rows(n, k.shape[1])
    events = np.zeros(n, dtype=np.int64)
    _warmup(icode)
    t_start = _time.perf_counter()
    done = driver_for(icode)(icode, sdof, *y0, t1s, t2s, H, n_sub, h, float(t.base_radius_pinion_m),
                             float(t.base_radius_gear_m), float(t.inertia_pinion_kgm2), float(t.inertia_gear_kgm2),
                             me, k, e, b, tq, inv_dphi, dphi, c, DAMPING_MODELS[s.damping_model], state, pair, force,
                             stiff, events, NO_CUTS if cuts is None else cuts, cuts is not None)
    wall = _time.perf_counter() - t_start
    info = {"form": info.pop("form"), "equivalent_mass_kg": me, **info, "events": int(events.sum()),
            "completed_steps": int(done)}
    if done < n - 1:
        info["diverged_at_step"] = int(done)
    return SimResult(time_s=np.arange(n) * H, **derived_outputs(t, state, pair, force), mesh_force=force,
                     pair_force=pair, mesh_stiffness=stiff, pinion_torque=t1s, gear_torque=t2s, step_s=h,
                     substeps=n_sub, damping_Ns_per_m=c, damping_model=s.damping_model, wall_s=wall, info=info)


def _solve(t, s: RunSettings, t1s, t2s, x0, v0, icode, sdof, info) -> SimResult:
    """The run of :func:`simulate` (``sdof`` False) or :func:`simulate_sdof` (True) on checked
    tables ``t``, resolved settings ``s`` (:func:`resolve_settings`), the torque inputs (one
    value per communication step, :func:`run_inputs`) and the start state (x0 None: the
    equilibrium, docs/model.md "Initial state"), then :func:`_integrate`; ``info`` starts with
    the form."""
    with compiling(icode):  # the first run after installing gearfmu compiles all of this: one line
        arrays = _arrays(t)
        th0 = s.pinion_angle_start_rad
        x0 = _initial_x(t, arrays, th0, t1s[0], x0)
        _warmup(icode)
    return _integrate(t, arrays, s, icode, sdof, (th0, s.pinion_speed_start_rad_s, x0, v0), t1s, t2s, dict(info))


#: the keyword arguments of :func:`simulate` that set a field of its run settings (argument -> field)
SETTINGS_KEYWORDS = {SOLVER_ARGUMENTS.get(f, f): f for f in (
    "stop_time_s", "output_interval_s", "max_step_s", "pinion_speed_start_rad_s", "damping_ratio", "damping_model",
    "pinion_angle_start_rad", "integrator")}
#: those of :func:`simulate_sdof` (the prescribed speed is its argument ``omega1_rad_s``)
SDOF_SETTINGS_KEYWORDS = {a: f for a, f in SETTINGS_KEYWORDS.items() if f != "pinion_speed_start_rad_s"}


def settings_changes(function: str, keywords: dict, allowed: dict = SETTINGS_KEYWORDS) -> dict:
    """{field: value} of the run-settings keyword arguments ``keywords`` of a call of ``function``
    (its name); a keyword that is none of ``allowed`` (argument -> field) is a TypeError, the one
    Python raises for an unknown keyword argument."""
    for name in keywords:
        if name not in allowed:
            raise TypeError(f"{function}() got an unexpected keyword argument {name!r}")
    return {allowed[name]: value for name, value in keywords.items()}


def simulate(
    tables: MeshTables,
    settings: Optional[RunSettings] = None,
    *,
    pinion_torque_Nm: Optional[InputLike] = None,
    gear_torque_Nm: Optional[InputLike] = None,
    dte_start_m: Optional[float] = None,
    dte_rate_start_m_s: float = 0.0,
    bulk_temperature_C: Optional[InputLike] = None,
    **settings_fields,
) -> SimResult:
    """Run the two-inertia multi-pair model of docs/model.md (Xu et al. 2022 eq 1-6).

    ``settings``: the run's :class:`gearfmu.common.settings.RunSettings` (None: its defaults);
    the keyword arguments of the same meaning (:data:`SETTINGS_KEYWORDS`), when given and not
    None, replace its fields: ``stop_time_s`` (s), ``comm_step_s`` (the communication step
    H = ``output_interval_s``, s; None: the default interval at the start speed), ``max_step_s``
    (s; None: :func:`choose_max_step_s` at 1.5 x the start speed, at least 1 rad/s),
    ``pinion_speed_start_rad_s`` (rad/s), ``damping_ratio``, ``damping_model``,
    ``pinion_angle_start_rad`` (rad), ``integrator``; any other keyword is a TypeError.
    Inputs (N*m) are a float, an array with one value per communication step
    (n or n+1 values; value k is held over [t_k, t_k+H)), or a callable of
    time t_k (s); ``pinion_torque_Nm`` None: the settings' start torque held.
    ``gear_torque_Nm`` None means the balancing load T2 = T1*Rb2/Rb1 of the pinion input
    (Xu et al. 2022: F_m = T1/Rb1 = T2/Rb2; without a pinion input: the settings' gear start torque).
    ``dte_start_m`` / ``dte_rate_start_m_s`` (m, m/s) start from a given state
    instead of the quasi-static equilibrium at rest relative motion, e.g. the
    last state of a previous run (continuation in a speed sweep).
    If the state turns non-finite the run stops there; the remaining rows are
    NaN and ``info['diverged_at_step']`` says where.
    ``integrator``: 'rk4_node' (default, :data:`DEFAULT_INTEGRATOR`: rk4_kink stopping
    only at the table nodes where the tables bend, each reached by one RK4 step to its
    crossing time predicted from theta1' = omega1, docs/native.md "rk4_node"; those
    crossings count as events), 'rk4_kink' (RK4 that steps exactly to every table node
    and contact-mode change, docs/model.md "rk4_kink"; ``info['events']`` counts the
    located events; both at most KINK_MAX_SLOTS slots), 'rk4_seg' (rk4_node stopping only at
    the contact-zone edges and contact changes, every evaluation in its own table cell,
    docs/model.md "rk4_seg") or 'rk4' (fixed-step classical RK4).
    ``bulk_temperature_C`` (degC; tables with a temperature axis only): the FMU
    input ``bulk_temperature``, an input like the torques (None: the tables'
    ``default_temperature_C``); docs/model.md "Temperature axis".
    """
    s = _settings(settings, **settings_changes("simulate", settings_fields))
    temperature_axis = isinstance(tables, MeshTables) and tables.has_temperature_axis
    if temperature_axis:
        t = _validated(tables)
    elif bulk_temperature_C is not None:
        raise NativeInputError("bulk_temperature_C: the tables have no temperature axis")
    else:
        t = _check_tables(tables)
        icode = integrator_code(s.integrator, t.slots)
    s = resolve_settings(t, s)
    n_steps, t1s, t2s = run_inputs(t, s, pinion_torque_Nm, gear_torque_Nm)
    x0, v0 = start_state(dte_start_m, dte_rate_start_m_s)
    if temperature_axis:
        return _simulate_temperature_axis(t, s, n_steps, t1s, t2s, x0, v0, bulk_temperature_C)
    return _solve(t, s, t1s, t2s, x0, v0, icode, False, {"form": "two-inertia (docs/model.md)",
                                                         "integrator": s.integrator})


def simulate_sdof(
    tables: MeshTables,
    settings: Optional[RunSettings] = None,
    *,
    omega1_rad_s: Optional[float] = None,
    pinion_torque_Nm: Optional[InputLike] = None,
    dte_start_m: Optional[float] = None,
    dte_rate_start_m_s: float = 0.0,
    bulk_temperature_C: Optional[float] = None,
    **settings_fields,
) -> SimResult:
    """Time-indexed SDOF form of Xu et al. 2022 eq 3-6 (SI units).

    The pinion turns at the prescribed constant speed ``omega1_rad_s`` (the settings'
    ``pinion_speed_start_rad_s``): theta1 = theta1_0 + omega1*t; states [x (m), v (m/s)];
    m_e dv/dt + F = F_m with F_m = T1/Rb1 and F the same per-pair force sum as
    :func:`simulate` (de_j = slope*omega1).  Settings and keyword arguments as :func:`simulate`
    (:data:`SDOF_SETTINGS_KEYWORDS`: the speed is ``omega1_rad_s``; ``max_step_s`` None:
    :func:`choose_max_step_s` at the speed, at least 1 rad/s).
    Same RK4 arithmetic and substeps; stage times t, t+h/2, t+h/2, t+h with
    t = k*H + i*h.  The gear outputs are the derived ones of docs/model.md.
    ``integrator`` 'rk4_kink' (and 'rk4_node', 'rk4_seg') integrates theta1 as a state with omega1' = 0
    and steps to every table node and contact-mode change (docs/model.md).
    ``bulk_temperature_C`` (degC, constant; tables with a temperature axis):
    the run uses ``tables.at_temperature`` (None: ``default_temperature_C``).
    """
    s = _settings(settings, names=dict(SOLVER_ARGUMENTS, pinion_speed_start_rad_s="omega1_rad_s"),
                  pinion_speed_start_rad_s=omega1_rad_s,
                  **settings_changes("simulate_sdof", settings_fields, SDOF_SETTINGS_KEYWORDS))
    if isinstance(tables, MeshTables) and tables.has_temperature_axis:
        tables = _at_temperature(tables, tables.default_temperature_C if bulk_temperature_C is None
                                 else bulk_temperature_C)
    elif bulk_temperature_C is not None:
        raise NativeInputError("bulk_temperature_C: the tables have no temperature axis")
    t = _check_tables(tables)
    icode = integrator_code(s.integrator, t.slots)
    w = s.pinion_speed_start_rad_s
    s = resolve_settings(t, s, step_speed_rad_s=max(abs(w), 1.0))
    # the gear torque: the balance of the pinion's (recorded; the prescribed speed makes it act on nothing)
    _, t1s, t2s = run_inputs(t, s, s.pinion_torque_start_Nm if pinion_torque_Nm is None else pinion_torque_Nm, None)
    x0, v0 = start_state(dte_start_m, dte_rate_start_m_s)
    return _solve(t, s, t1s, t2s, x0, v0, icode, True, {"form": "time-indexed SDOF (seed 003 eq 3-6)",
                                                        "omega1_rad_s": w, "integrator": s.integrator})


def dimensionless(result: SimResult, tables: MeshTables, length_scale_m: float) -> DimensionlessResult:
    """Xu et al. 2022 eq 7-9: q = x/l, tau = omega_n t, Omega_h = omega_mesh/omega_n.

    omega_n = sqrt(k_m/m_e) (rad/s) with k_m = tables.k_mean_N_per_m; the mesh
    frequency omega_mesh = 2*pi*omega1/mesh_period_rad (rad/s) uses the mean
    pinion speed of the result; q_rate = dq/dtau = v/(l omega_n); zeta is the
    per-pair damping ratio c/(2 m_e omega_n) (Xu et al. 2022 eq 8, zeta bar); load =
    F_m/(k_m l) with F_m = T1/Rb1 of the first row.
    """
    t = _check_tables(tables)
    l = _finite("length_scale_m", length_scale_m, positive=True)
    me = t.equivalent_mass_kg
    wn = math.sqrt(t.k_mean_N_per_m / me)
    om = float(np.mean(result.pinion_speed))
    return DimensionlessResult(
        tau=wn * result.time_s, q=result.dte / l, q_rate=result.dte_rate / (l * wn),
        Omega_h=2.0 * math.pi * om / t.mesh_period_rad / wn, omega_n_rad_s=wn,
        zeta=result.damping_Ns_per_m / (2.0 * me * wn),
        load=float(result.pinion_torque[0]) / t.base_radius_pinion_m / (t.k_mean_N_per_m * l),
        length_scale_m=l)


# ------------------------------------------------- temperature axis (docs/model.md)
def _at_temperature(tables: MeshTables, temperature_C) -> MeshTables:
    try:
        return tables.at_temperature(float(temperature_C))
    except (TypeError, ValueError) as exc:
        if isinstance(exc, TemperatureRangeError):
            raise NativeInputError(f"bulk_temperature_C: {exc}") from None
        raise NativeInputError(f"bulk_temperature_C: expected a number, got {temperature_C!r}") from None


def _simulate_temperature_axis(t: MeshTables, s: RunSettings, n_steps, t1s, t2s, x0, v0,
                               bulk_temperature_C) -> SimResult:
    """:func:`simulate` on tables ``t`` with a temperature axis (resolved settings ``s``, the
    torque inputs and the start state).  The temperature is held over each communication step
    like the torques; every run of steps with one temperature is simulated on
    ``t.at_temperature(T)`` (the node-wise blend of docs/model.md "Temperature axis", the
    arithmetic of the C kernel), continuing from the state [theta1, omega1, x, v] of the previous
    run -- the same per-step computation as an FMU whose input changes at those steps.  The step
    bound is the same for all runs (k_mean does not depend on temperature)."""
    H = s.output_interval_s
    temps = input_series("bulk_temperature_C", t.default_temperature_C if bulk_temperature_C is None
                         else bulk_temperature_C, n_steps, H)
    slices = {}
    for T in np.unique(temps[:n_steps + 1]):
        slices[float(T)] = _at_temperature(t, T)
    parts = []
    th, om, x, v = s.pinion_angle_start_rad, s.pinion_speed_start_rad_s, x0, v0
    i = 0
    while i < n_steps:
        j = i + 1
        while j < n_steps and temps[j] == temps[i]:
            j += 1
        r = simulate(slices[float(temps[i])], dataclasses.replace(s, stop_time_s=(j - i) * H,
                                                                  pinion_speed_start_rad_s=om,
                                                                  pinion_angle_start_rad=th),
                     pinion_torque_Nm=t1s[i:j], gear_torque_Nm=t2s[i:j], dte_start_m=x, dte_rate_start_m_s=v)
        parts.append((i, r))
        if "diverged_at_step" in r.info:
            break
        th, om, x, v = (float(r.pinion_angle[-1]), float(r.pinion_speed[-1]), float(r.dte[-1]),
                        float(r.dte_rate[-1]))
        i = j
    first = parts[0][1]
    names = ("pinion_speed", "gear_speed", "pinion_angle", "gear_angle", "dte", "dte_rate", "mesh_force",
             "pair_force", "load_sharing", "mesh_stiffness")
    out = {}
    for n in names:
        a0 = getattr(first, n)
        arr = np.full((n_steps + 1,) + a0.shape[1:], np.nan)
        arr[0] = a0[0]
        for i0, r in parts:
            seg = getattr(r, n)[1:]
            arr[i0 + 1: i0 + 1 + seg.shape[0]] = seg
        out[n] = arr
    done = sum(int(r.info["completed_steps"]) for _, r in parts)
    info = dict(first.info, completed_steps=done, events=int(sum(r.info.get("events", 0) for _, r in parts)),
                bulk_temperature_C=temps, temperature_runs=len(parts))
    info.pop("diverged_at_step", None)
    if done < n_steps:
        info["diverged_at_step"] = done
    return SimResult(time_s=np.arange(n_steps + 1) * H, **out, pinion_torque=t1s, gear_torque=t2s,
                     step_s=first.step_s, substeps=first.substeps, damping_Ns_per_m=first.damping_Ns_per_m,
                     damping_model=first.damping_model, wall_s=float(sum(r.wall_s for _, r in parts)), info=info)
