"""The scene file: the single user input of gearfmu (TOML, engineering units).

A scene names a spur gear pair (geometry, materials, tooth deviations), the
mesh model (contact model, slices, foundation), the operating envelope, the
table resolution, the solver and the FMU options, and optionally the
lubricant.  Every dimensional key carries its unit in its name
(``module_mm``, ``speed_rpm``, ``profile_form_um`` ...).  :func:`load_scene`
parses and validates a scene and converts it to SI into the dataclasses of
:mod:`gearfmu.gear.gearpair` plus the small option dataclasses defined here.

The format, every key (unit, default, range, meaning) and the choices made
for the shipped scenes are documented in ``docs/scene.md``.

Validation
----------
Unknown keys (with the closest valid key as a hint, so ``module_m`` suggests
``module_mm``), wrong types, out-of-range values and inconsistent
combinations are all collected and raised together as one
:class:`SceneError` (a :class:`ValueError`) whose message names the full key
path of every problem, e.g. ``gears.pinion.teeth: must be an integer >= 5,
got 3.5``.  Physically impossible gears (contact ratio < 1, pointed tip,
undercut, interference) are detected by :func:`gearfmu.gear.geometry.pair_geometry`
and re-raised as :class:`SceneError` with the scene key path.

No pickle, no code execution: a scene is plain TOML data.
"""
from __future__ import annotations

import difflib
import hashlib
import math
import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

try:  # Python >= 3.11
    import tomllib as _toml
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as _toml  # type: ignore[no-redef]

from ..common.vocabulary import (CONTACT_MODELS, DAMPING_MODELS, FILM_FAILURE_POLICIES, FILM_TRANSIENT_MODES,
                                 DEFAULT_RUNTIME, FLANK_LAWS, INTEGRATORS, LUBRICATED_CONTACT_MODELS, RUNTIMES,
                                 THERMAL_AXIS_QUANTITIES)
from ..ehl.lubricant import walther_kinematic_viscosity_cSt
from ..gear.gearpair import (GearDeviations, GearPairSpec, GearSpec, Material,
                       MeshModelOptions, ToothDeviation)
from .envelope import read_envelope_sections
from ..contact.roughness import SEED000_LEVELS
from ..gear import geometry

__all__ = [
    "SceneError", "Scene", "OperatingPoint", "TableOptions", "SolverOptions",
    "FmuOptions", "Lubricant", "ThermalOptions", "load_scene", "default_scene_path",
    "dumps_toml", "walther_kinematic_viscosity_cSt", "SCHEMA", "CONTACT_MODELS",
    "DAMPING_MODELS", "INTEGRATORS", "RUNTIMES", "DEFAULT_RUNTIME", "default_output_interval_s",
    "OUTPUT_SAMPLES_PER_MESH",
]


_RPM_TO_RAD_S = 2.0 * math.pi / 60.0


# ============================================================== errors
class SceneError(ValueError):
    """A scene is invalid.  ``problems`` lists ``(key_path, reason)`` pairs;
    the message names every key path and reason, one per line."""

    def __init__(self, problems: Sequence[Tuple[str, str]], source: str = ""):
        self.problems: List[Tuple[str, str]] = list(problems)
        self.source = source
        lines = [f"{path}: {reason}" for path, reason in self.problems]
        where = f" in scene {source!r}" if source else ""
        if len(lines) == 1:
            msg = lines[0] + (f" ({where.strip()})" if where else "")
        else:
            msg = f"{len(lines)} problems{where}:\n" + "\n".join("  - " + s for s in lines)
        super().__init__(msg)


# ============================================================== result dataclasses
@dataclass(frozen=True)
class OperatingPoint:
    """Operating envelope (SI).

    ``torque_Nm`` is the nominal pinion torque (N*m, positive drives),
    ``speed_rad_s`` the nominal pinion speed (rad/s).  The optional ranges
    (N*m and rad/s, ``(low, high)``) span the torque axis of the tables
    (see :meth:`torque_axis_Nm`) and the envelope the FMU accepts.
    """

    torque_Nm: float
    speed_rad_s: float
    torque_range_Nm: Optional[Tuple[float, float]] = None
    speed_range_rad_s: Optional[Tuple[float, float]] = None
    torque_points: int = 1

    @property
    def speed_rpm(self) -> float:
        """Nominal pinion speed in rev/min."""
        return self.speed_rad_s / _RPM_TO_RAD_S

    def torque_axis_Nm(self, points: Optional[int] = None) -> Tuple[float, ...]:
        """Torque axis of the tables (N*m): the nominal torque alone when
        ``points == 1`` or no range is given, else ``points`` equally spaced
        values over ``torque_range_Nm`` (both ends included).  ``points``
        None = ``torque_points`` (the scene's ``tables.torque_points``)."""
        if points is None:
            points = self.torque_points
        if points <= 1 or self.torque_range_Nm is None:
            return (float(self.torque_Nm),)
        lo, hi = self.torque_range_Nm
        return tuple(lo + (hi - lo) * i / (points - 1) for i in range(points))


@dataclass(frozen=True)
class TableOptions:
    """Resolution of the tooth-pair tables.

    ``points_per_mesh``: pinion-angle samples per mesh period 2*pi/z1;
    ``torque_points``: samples of the torque axis (1 = no torque axis);
    ``slots``: tooth-pair slot count P, ``None`` = automatic (from the contact ratio).
    """

    points_per_mesh: int = 64
    torque_points: int = 1
    slots: Optional[int] = None


@dataclass(frozen=True)
class SolverOptions:
    """Dynamic solver settings (docs/model.md).

    ``integrator``: 'rk4_kink' (default: the setting on the speed-against-error
    front, docs/dynamics_validation.md) or 'rk4'; ``max_step_s``: largest internal step in s
    (``None`` = automatic, chosen by the builder from the mesh frequency and
    the contact natural frequency); ``damping_model``: 'elastobacklash' or
    'seed003' (docs/model.md, "Per-pair force").
    """

    integrator: str = "rk4_kink"
    max_step_s: Optional[float] = None
    damping_model: str = "elastobacklash"


@dataclass(frozen=True)
class FmuOptions:
    """FMU options.

    ``model_name``: the FMU's model name / identifier (a C identifier);
    ``damping_ratio``: mesh damping ratio zeta (dimensionless, default 0.05,
    see docs/scene.md for why); ``runtime``: 'standalone' (default, all-C) or 'pythonfmu';
    ``stop_time_s`` and ``output_interval_s``: the DefaultExperiment (s);
    ``output_interval_auto``: True when the scene left ``output_interval_s`` unset (or
    "auto") and it was resolved by :func:`default_output_interval_s`.
    """

    model_name: str
    damping_ratio: float = 0.05
    runtime: str = DEFAULT_RUNTIME
    stop_time_s: float = 0.05
    output_interval_s: float = 1e-4
    output_interval_auto: bool = False


@dataclass(frozen=True)
class Lubricant:
    """Lubricant properties (SI).

    ``dynamic_viscosity_Pas`` is eta0, the ambient-pressure dynamic viscosity
    at ``temperature_C`` (either given directly or from the kinematic
    viscosities at 40 and 100 degC by the Walther / ASTM D341 law times
    ``density_kg_m3``); ``pressure_viscosity_Pa_inv`` is the
    pressure-viscosity coefficient alpha (1/Pa).  Kinematic viscosities are
    kept (m^2/s) when given.
    """

    name: str
    dynamic_viscosity_Pas: float
    pressure_viscosity_Pa_inv: float
    density_kg_m3: float
    temperature_C: float
    kinematic_viscosity_40C_m2_s: Optional[float] = None
    kinematic_viscosity_100C_m2_s: Optional[float] = None

    def kinematic_viscosity_m2_s(self, temperature_C: float) -> float:
        """Kinematic viscosity (m^2/s) at ``temperature_C`` (degC): Walther /
        ASTM D341 through the 40 and 100 degC values when given, otherwise
        the constant eta0/rho (no temperature law known)."""
        if self.kinematic_viscosity_40C_m2_s is None or self.kinematic_viscosity_100C_m2_s is None:
            return self.dynamic_viscosity_Pas / self.density_kg_m3
        return 1e-6 * walther_kinematic_viscosity_cSt(
            self.kinematic_viscosity_40C_m2_s * 1e6, self.kinematic_viscosity_100C_m2_s * 1e6,
            temperature_C)


@dataclass(frozen=True)
class ThermalOptions:
    """The ``[thermal]`` section (seed 004; docs/thermal.md), degC.

    ``pinion_temperature_C`` / ``gear_temperature_C``: uniform bulk temperature
    (None = the standard temperature); ``*_profile_gamma`` / ``*_profile_C``:
    a bulk temperature along the line of action over seed 004's normalised
    coordinate Gamma_K (overrides the uniform value when given);
    ``temperature_axis_C``: temperatures of the tables' temperature axis
    (empty = no axis); ``flank_law``: free flank deformation law of
    :func:`gearfmu.gear.thermal.free_flank_deformation_m`; ``axis_quantity``: what
    the axis is (:data:`THERMAL_AXIS_QUANTITIES`): "bulk" the bulk temperature of
    both gears (seed 004 stiffness, FMU input ``bulk_temperature``), "oil" the
    oil temperature (eta0 of a lubricated contact model, input
    ``oil_temperature``), "bulk_and_oil" both at one temperature (input
    ``gearbox_temperature``); ``lubricant``: the scene's ``[lubricant]`` (its
    viscosity-temperature law), attached by the scene reader when the axis
    involves the oil.  Without an axis, ``pinion_temperature_C`` /
    ``gear_temperature_C`` / the profiles change the tables (seed 004 eq 27-28
    at that state); with a "bulk" or "bulk_and_oil" axis the axis sets the gear
    temperatures and these keys must be absent; with an "oil" axis they give
    the gears' state at every oil temperature (docs/thermal.md).
    ``oil_alpha``: the pressure-viscosity coefficient along an oil axis:
    "roelands" (Roelands 1966, constant Z: alpha(T) from eta0(T),
    :func:`gearfmu.ehl.lubricant.roelands_alpha_at_viscosity_Pa_inv`) or
    "constant" (the ``[lubricant]`` value at every temperature).
    """

    standard_temperature_C: float = 30.0
    pinion_temperature_C: Optional[float] = None
    gear_temperature_C: Optional[float] = None
    pinion_profile_gamma: Tuple[float, ...] = ()
    pinion_profile_C: Tuple[float, ...] = ()
    gear_profile_gamma: Tuple[float, ...] = ()
    gear_profile_C: Tuple[float, ...] = ()
    temperature_axis_C: Tuple[float, ...] = ()
    flank_law: str = "radial_tangential"
    axis_quantity: str = "bulk"
    oil_alpha: str = "roelands"
    lubricant: Optional["Lubricant"] = None


@dataclass(frozen=True)
class Scene:
    """A validated scene, in SI.

    ``text`` is the TOML source (provenance; hash it with :attr:`sha256`),
    ``source_path`` the file it came from (``None`` for text).
    """

    name: str
    description: str
    text: str
    pair: GearPairSpec
    mesh: MeshModelOptions
    operating: OperatingPoint
    tables: TableOptions
    solver: SolverOptions
    fmu: FmuOptions
    lubricant: Optional[Lubricant] = None
    source_path: Optional[str] = None
    thermal: Optional[ThermalOptions] = None
    envelope: Optional[Any] = None  # gearfmu.scene.envelope.Envelope ([envelope], docs/plan.md)
    accuracy: Optional[Any] = None  # gearfmu.scene.envelope.AccuracyTarget ([accuracy], docs/plan.md)

    @property
    def sha256(self) -> str:
        """SHA-256 of the TOML source (hex)."""
        return hashlib.sha256(self.text.encode("utf-8")).hexdigest()

    @property
    def torque_axis_Nm(self) -> Tuple[float, ...]:
        """The tables' torque axis (N*m), see :meth:`OperatingPoint.torque_axis_Nm`."""
        return self.operating.torque_axis_Nm(self.tables.torque_points)

    @property
    def roughness(self) -> Optional["RoughnessOptions"]:
        """The ``[roughness]`` table (:class:`RoughnessOptions`, SI) or None when absent
        (read from :attr:`text`, validated by :func:`load_scene`)."""
        return _roughness_from_text(self.text)


# ============================================================== defaults that depend on the scene
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


# ============================================================== schema
_REQUIRED = object()
_AUTO = "auto"


@dataclass(frozen=True)
class Key:
    """One scene key: type, unit, default, allowed range, SI scale and meaning.

    ``kind``: 'float', 'int', 'bool', 'str', 'enum', 'float_list' (list of
    numbers), 'float_pair' ([low, high]), 'int_or_auto', 'float_or_auto',
    'identifier'.  Ranges: ``lo``/``hi`` with ``lo_open``/``hi_open``.
    ``scale`` converts the scene unit to SI.
    """

    name: str
    kind: str
    unit: str
    default: Any = None
    doc: str = ""
    lo: Optional[float] = None
    hi: Optional[float] = None
    lo_open: bool = False
    hi_open: bool = False
    choices: Tuple[str, ...] = ()
    scale: float = 1.0

    @property
    def required(self) -> bool:
        return self.default is _REQUIRED

    def range_text(self) -> str:
        lo, hi = self.lo, self.hi
        if lo is not None and hi is not None:
            return f"in {'(' if self.lo_open else '['}{lo:g}, {hi:g}{')' if self.hi_open else ']'}"
        if lo is not None:
            return f"{'>' if self.lo_open else '>='} {lo:g}"
        if hi is not None:
            return f"{'<' if self.hi_open else '<='} {hi:g}"
        return ""


def _f(name, unit, default, doc, lo=None, hi=None, lo_open=False, hi_open=False, scale=1.0, kind="float"):
    return Key(name, kind, unit, default, doc, lo, hi, lo_open, hi_open, (), scale)


def _i(name, default, doc, lo=None, hi=None, kind="int"):
    return Key(name, kind, "1", default, doc, lo, hi)


def _e(name, choices, default, doc):
    return Key(name, "enum", "-", default, doc, choices=tuple(choices))


_MATERIAL_KEYS = (
    _f("youngs_modulus_GPa", "GPa", 206.0, "Young's modulus E", 0.0, 1000.0, lo_open=True, scale=1e9),
    _f("poisson_ratio", "1", 0.3, "Poisson's ratio nu", 0.0, 0.5, hi_open=True),
    _f("density_kg_m3", "kg/m^3", 7850.0, "density rho (gear-body inertia when inertia_kgm2 is not given)",
       0.0, 30000.0, lo_open=True),
    _f("thermal_expansion_per_K", "1/K", 1.13e-5, "linear thermal expansion coefficient (seed 004: 1.13e-5)",
       0.0, 1e-3),
)

_GEAR_KEYS = (
    _i("teeth", _REQUIRED, "number of teeth z", 5, 1000),
    _f("profile_shift", "1", 0.0, "profile shift (addendum modification) coefficient x", -2.0, 3.0),
    _f("addendum_coefficient", "1", 1.0, "addendum coefficient h_a*", 0.0, 2.0, lo_open=True),
    _f("tip_clearance_coefficient", "1", 0.25, "tip (bottom) clearance coefficient c*", 0.0, 1.0),
    _f("hub_radius_mm", "mm", None, "radius of the gear-body bore r_int (Sainsot foundation; "
       "none = left to the stiffness module)", 0.0, None, lo_open=True, scale=1e-3),
    _f("inertia_kgm2", "kg*m^2", None, "polar moment of inertia (none = solid disc between hub and "
       "root radius)", 0.0, None, lo_open=True),
) + tuple(replace(k, default=None, doc=k.doc + " (overrides [material])") for k in _MATERIAL_KEYS)

_DEV_KEYS = (
    _f("profile_form_um", "um", 0.0, "profile form deviation f_fa (seed 003 eq 15), every tooth", -1000.0, 1000.0,
       scale=1e-6),
    _f("profile_slope_um", "um", 0.0, "profile slope deviation f_Ha (seed 003 eq 15), every tooth", -1000.0,
       1000.0, scale=1e-6),
    _f("form_periods", "1", 2.0, "f_r: sine periods of the form deviation over the profile evaluation range",
       0.0, 100.0, lo_open=True),
    _f("pitch_um", "um", (), "single pitch deviation per tooth along the line of action, one per tooth "
       "(length = teeth) or empty", -1000.0, 1000.0, scale=1e-6, kind="float_list"),
    _f("lead_crowning_um", "um", 0.0, "lead crowning C_b (seed 000 eq 16 E_pc)", 0.0, 1000.0, scale=1e-6),
)

_TOOTH_KEYS = (
    _i("index", _REQUIRED, "tooth index, 0-based, < teeth", 0, None),
    _f("profile_form_um", "um", None, "f_fa of this tooth", -1000.0, 1000.0, scale=1e-6),
    _f("profile_slope_um", "um", None, "f_Ha of this tooth", -1000.0, 1000.0, scale=1e-6),
    _f("form_periods", "1", None, "f_r of this tooth", 0.0, 100.0, lo_open=True),
    _f("pitch_um", "um", None, "single pitch deviation of this tooth (not together with a pitch_um list)",
       -1000.0, 1000.0, scale=1e-6),
)

#: every table of the scene and its keys (docs/scene.md documents each one)
SCHEMA: Dict[str, Tuple[Key, ...]] = {
    "scene": (
        Key("name", "str", "-", "scene", "short name (also the default FMU model name)"),
        Key("description", "str", "-", "", "free text"),
    ),
    "gears": (
        _f("module_mm", "mm", _REQUIRED, "module m", 0.0, 100.0, lo_open=True, scale=1e-3),
        _f("pressure_angle_deg", "deg", 20.0, "pressure angle alpha of the basic rack", 10.0, 35.0,
           lo_open=True, hi_open=True, scale=math.pi / 180.0),
        _f("face_width_mm", "mm", _REQUIRED, "face width b", 0.0, 5000.0, lo_open=True, scale=1e-3),
        _f("backlash_um", "um", 0.0, "total backlash (play) along the line of action; the dead zone "
           "of seed 003 eq 6 is half of it", 0.0, 5000.0, scale=1e-6),
        _f("center_distance_mm", "mm", None, "operating centre distance (none = zero-backlash distance "
           "from the profile shifts)", 0.0, None, lo_open=True, scale=1e-3),
        _f("helix_angle_deg", "deg", 0.0, "reference helix angle beta (0 = spur); with beta > 0 module, "
           "pressure angle, shifts and addendum/clearance coefficients are normal-section values "
           "(docs/helical.md)", 0.0, 45.0, scale=math.pi / 180.0),
        _e("hand", ("right", "left"), "right", "helix hand of the pinion (the gear has the opposite hand)"),
    ),
    "gears.pinion": _GEAR_KEYS,
    "gears.gear": _GEAR_KEYS,
    "material": _MATERIAL_KEYS,
    "deviations.pinion": _DEV_KEYS,
    "deviations.gear": _DEV_KEYS,
    "deviations.pinion.tooth": _TOOTH_KEYS,
    "deviations.gear.tooth": _TOOTH_KEYS,
    "mesh": (
        _e("contact_model", CONTACT_MODELS, "hertz", "contact stiffness model"),
        _i("slices", 1, "face-width slices of the sliced stiffness model", 1, 1000),
        Key("foundation", "bool", "-", True, "fillet-foundation stiffness (Sainsot et al. 2004)"),
        Key("shared_foundation_correction", "bool", "-", False,
            "shared-foundation correction (Ma et al. 2016, seed 000 eq 11)"),
    ),
    "operating": (
        _f("torque_Nm", "N*m", _REQUIRED, "nominal pinion torque (positive drives)", 0.0, 1e7, lo_open=True),
        _f("speed_rpm", "rpm", _REQUIRED, "nominal pinion speed", 0.0, 1e6, lo_open=True, scale=_RPM_TO_RAD_S),
        _f("torque_range_Nm", "N*m", None, "[low, high] pinion torque envelope; the torque axis when "
           "tables.torque_points > 1", 0.0, 1e7, kind="float_pair"),
        _f("speed_range_rpm", "rpm", None, "[low, high] pinion speed envelope", 0.0, 1e6,
           scale=_RPM_TO_RAD_S, kind="float_pair"),
    ),
    "tables": (
        _i("points_per_mesh", 64, "pinion-angle samples per mesh period", 8, 100000),
        _i("torque_points", 1, "samples of the torque axis (1 = no torque axis)", 1, 1000),
        _i("slots", _AUTO, "tooth-pair slot count P or \"auto\" (from the contact ratio)", 1, 16,
           kind="int_or_auto"),
    ),
    "solver": (
        _e("integrator", INTEGRATORS, "rk4_kink", "internal integrator (docs/model.md)"),
        _f("max_step_s", "s", _AUTO, "largest internal step, or \"auto\"", 0.0, 1.0, lo_open=True,
           kind="float_or_auto"),
        _e("damping_model", DAMPING_MODELS, "elastobacklash", "per-pair damping rule (docs/model.md)"),
    ),
    "fmu": (
        Key("model_name", "identifier", "-", None, "FMU model name / identifier (C identifier; none = "
            "from scene.name)"),
        _f("damping_ratio", "1", 0.05, "mesh damping ratio zeta (tunable FMU parameter)", 0.0, 1.0),
        _e("runtime", RUNTIMES, DEFAULT_RUNTIME, "FMU runtime"),
        _f("stop_time_s", "s", 0.05, "DefaultExperiment stop time", 0.0, 1e6, lo_open=True),
        _f("output_interval_s", "s", _AUTO, "DefaultExperiment output (communication) interval, or \"auto\" "
           f"(>= {OUTPUT_SAMPLES_PER_MESH} samples per mesh period at the nominal speed)", 0.0, 1e3,
           lo_open=True, kind="float_or_auto"),
    ),
    "lubricant": (
        Key("name", "str", "-", "oil", "lubricant name"),
        _f("eta0_Pas", "Pa*s", None, "dynamic viscosity at temperature_C and ambient pressure", 0.0, 1e3,
           lo_open=True),
        _f("kinematic_viscosity_40C_cSt", "cSt", None, "kinematic viscosity at 40 degC (mm^2/s)", 2.0, 1e6,
           scale=1e-6),
        _f("kinematic_viscosity_100C_cSt", "cSt", None, "kinematic viscosity at 100 degC (mm^2/s)", 2.0, 1e6,
           scale=1e-6),
        _f("pressure_viscosity_GPa_inv", "1/GPa", _REQUIRED, "pressure-viscosity coefficient alpha", 0.0,
           100.0, lo_open=True, scale=1e-9),
        _f("density_kg_m3", "kg/m^3", _REQUIRED, "density at ambient pressure", 0.0, 3000.0, lo_open=True),
        _f("temperature_C", "degC", _REQUIRED, "oil (inlet / bulk) temperature", -60.0, 300.0),
    ),
    "thermal": (
        _f("standard_temperature_C", "degC", 30.0, "standard temperature t0 of the gear geometry "
           "(seed 004: 30)", -200.0, 500.0),
        _f("pinion_temperature_C", "degC", None, "uniform pinion bulk temperature (none = standard)",
           -200.0, 500.0),
        _f("gear_temperature_C", "degC", None, "uniform gear bulk temperature (none = standard)", -200.0, 500.0),
        _f("pinion_profile_gamma", "1", (), "pinion bulk temperature profile: seed 004 normalised LOA "
           "coordinates Gamma_K, ascending", -1.0, 10.0, kind="float_list"),
        _f("pinion_profile_C", "degC", (), "pinion bulk temperatures at pinion_profile_gamma", -200.0, 500.0,
           kind="float_list"),
        _f("gear_profile_gamma", "1", (), "gear bulk temperature profile: Gamma_K, ascending", -1.0, 10.0,
           kind="float_list"),
        _f("gear_profile_C", "degC", (), "gear bulk temperatures at gear_profile_gamma", -200.0, 500.0,
           kind="float_list"),
        _f("temperature_axis_C", "degC", (), "tables' temperature axis (uniform bulk temperature of both "
           "gears), ascending; empty = none", -200.0, 500.0, kind="float_list"),
        _e("flank_law", FLANK_LAWS, "radial_tangential",
           "free thermal deformation of a flank (docs/thermal.md)"),
        _e("axis_quantity", THERMAL_AXIS_QUANTITIES, "bulk", "what temperature_axis_C is: bulk temperature "
           "of both gears (FMU input bulk_temperature), oil temperature (eta0 of a lubricated contact model; "
           "input oil_temperature) or both at one temperature (input gearbox_temperature)"),
        _e("oil_alpha", ("roelands", "constant"), "roelands", "pressure-viscosity coefficient along an oil "
           "axis: Roelands (constant Z, alpha from eta0(T)) or the [lubricant] value at every temperature"),
    ),
    # operating envelope and accuracy target of the fidelity planner (gearfmu/scene/envelope.py, docs/plan.md)
    "envelope": (
        _f("torque_range_Nm", "N*m", None, "[low, high] pinion torque envelope (none = "
           "operating.torque_range_Nm, else the nominal torque)", 0.0, 1e7, kind="float_pair"),
        _f("speed_range_rpm", "rpm", None, "[low, high] pinion speed envelope (none = "
           "operating.speed_range_rpm, else the nominal speed)", 0.0, 1e6, scale=_RPM_TO_RAD_S,
           kind="float_pair"),
        _f("temperature_range_C", "degC", None, "[low, high] bulk temperature envelope (none = no "
           "temperature variation)", -200.0, 500.0, kind="float_pair"),
        Key("duty_cycle_csv", "str", "-", None, "duty-cycle CSV (time_s, torque_Nm, speed_rpm[, "
            "temperature_C]) relative to the scene file; its extremes widen the ranges"),
    ),
    "accuracy": (
        _f("dte_rel_error", "1", 0.02, "largest acceptable relative RMS error of the DTE", 0.0, 1.0,
           lo_open=True),
        _f("mesh_force_rel_error", "1", 0.02, "largest acceptable relative RMS error of the mesh force",
           0.0, 1.0, lo_open=True),
        _f("safety_factor", "1", 0.8, "share of the target the summed single-choice estimates, and the "
           "envelope search's worst point, may use",
           0.0, 1.0, lo_open=True),
        _i("run_mesh_periods", 40, "mesh periods of each dynamic comparison run", 5, 100000),
        Key("pin", "str_list", "-", (), "choices taken from the scene as written, not planned"),
    ),
}

#: sub-tables that may appear inside a table (besides its keys)
_SUBTABLES = {
    "": ("scene", "gears", "material", "deviations", "mesh", "operating", "tables", "solver", "fmu",
         "lubricant", "thermal", "envelope", "accuracy"),
    "gears": ("pinion", "gear"),
    "deviations": ("pinion", "gear"),
    "deviations.pinion": ("tooth",),
    "deviations.gear": ("tooth",),
}
_REQUIRED_TABLES = ("gears", "gears.pinion", "gears.gear", "operating")

# [roughness]: W-M flank roughness of the rough-EHL contact model (seed 000 eq 1, Table 2;
# gearfmu/contact/models.py, docs/ehl_mesh.md)
SCHEMA["roughness"] = (
    _i("level", 1, "seed 000 Table 2 roughness level 1-4 (D and G from the table), or 0 = use "
       "fractal_dimension and G_nm", 0, 4),
    _f("fractal_dimension", "1", None, "W-M fractal dimension D (level = 0 only)", 1.0, 2.0,
       lo_open=True, hi_open=True),
    _f("G_nm", "nm", None, "W-M characteristic scale G (level = 0 only); seed 000 Table 2's G "
       "read in mm, so G_nm = 1e6 x the table value (level 4: 5.229 nm)", 0.0, 1e6, lo_open=True, scale=1e-9),
    _i("seed", 2022, "seed of the random phases (per flank and slice; reproducible)", 0, 2 ** 63 - 1),
    _f("max_frequency_per_mm", "1/mm", 10.0, "band limit of the roughness (highest W-M frequency)",
       0.0, 1e4, lo_open=True, scale=1e3),
    _e("on_film_failure", FILM_FAILURE_POLICIES, "fractal_mixed", "where the film "
       "parameter h_min/sigma is below full_film_parameter or the rough film collapses or does not converge: seed 001 "
       "fractal mixed-lubrication stiffness, Hertz stiffness (both recorded), stop with an error, or film-asperity "
       "load sharing (Johnson, Greenwood & Poon 1972; docs/load_sharing.md)"),
    _f("full_film_parameter", "1", 3.0, "film parameter Lambda = h_min/sigma (Dowson-Higginson h_min, "
       "composite W-M sigma) below which the full-film model is not used", 0.0, 100.0),
    _i("film_position_nodes", 9, "contact positions along the path of contact at which the rough films "
       "are solved and interpolated (0 = every table position)", 0, 10000),
    _e("film_transient", FILM_TRANSIENT_MODES, "off", "off: steady films with the roughness frozen in "
       "the contact; correction: at every film-grid node transient films with the roughness moving with the flanks "
       "on 4 slices give c = <k_transient>/k_steady, which multiplies every slice's rough/smooth ratio "
       "(docs/ehl_transient.md section 3); film: the node's rough film is the transient film (start 'auto', no "
       "steady rough solve), ratio <k_transient>/k_smooth for every slice, no film-parameter screen "
       "(docs/ehl_mesh.md 'Transient films in the tables'); needs film_position_nodes >= 2"),
)
_SUBTABLES[""] = _SUBTABLES[""] + ("roughness",)


@dataclass(frozen=True)
class RoughnessOptions:
    """The ``[roughness]`` table in SI: ``D``, ``G_m`` (m), ``seed``,
    ``f_max_per_m`` (1/m), ``level`` (0 = custom), ``on_failure``,
    ``full_film_parameter``, ``film_position_nodes`` (docs/ehl_mesh.md)."""

    D: float
    G_m: float
    seed: int = 2022
    f_max_per_m: float = 1e4
    level: int = 1
    on_failure: str = "fractal_mixed"
    full_film_parameter: float = 3.0
    film_position_nodes: int = 9
    film_transient: str = "off"


def _roughness(r: "_Reader", data: Any) -> Optional[RoughnessOptions]:
    """Read ``[roughness]`` (None when absent)."""
    raw = _sub(data, "roughness")
    if raw is None:
        return None
    n0 = len(r.problems)
    ro = r.table(raw, "roughness")
    if len(r.problems) > n0:
        return None
    level = ro["level"]
    if level == 0:
        for k in ("fractal_dimension", "G_nm"):
            if ro[k] is None:
                r.add(f"roughness.{k}", "required when roughness.level = 0")
        if len(r.problems) > n0:
            return None
        D, G = ro["fractal_dimension"], ro["G_nm"]
    else:
        for k in ("fractal_dimension", "G_nm"):
            if isinstance(raw, dict) and k in raw:
                r.add(f"roughness.{k}", f"only with roughness.level = 0 (level {level} takes D and G "
                                        "from seed 000 Table 2)")
        if len(r.problems) > n0:
            return None
        D, G = SEED000_LEVELS[level].D, SEED000_LEVELS[level].G_m
    if ro["film_position_nodes"] == 1:
        r.add("roughness.film_position_nodes", "must be 0 (every table position) or >= 2 (interpolation nodes)")
        return None
    if ro["film_transient"] != "off" and ro["film_position_nodes"] == 0:
        r.add("roughness.film_transient", f"{ro['film_transient']!r} is stored on the film grid; needs "
                                          "film_position_nodes >= 2 (got 0)")
        return None
    return RoughnessOptions(D=D, G_m=G, seed=ro["seed"], f_max_per_m=ro["max_frequency_per_mm"],
                            level=level, on_failure=ro["on_film_failure"],
                            full_film_parameter=ro["full_film_parameter"],
                            film_position_nodes=ro["film_position_nodes"],
                            film_transient=ro["film_transient"])


def _roughness_from_text(text: str) -> Optional[RoughnessOptions]:
    r = _Reader()
    out = _roughness(r, _toml.loads(text))
    if r.problems:
        raise SceneError(r.problems)
    return out


# ============================================================== helpers
_UNIT_SUFFIX = re.compile(r"_(mm|m|um|deg|rad|GPa|Pa|Nm|rpm|rad_s|s|kg_m3|kgm2|C|cSt|Pas|GPa_inv|"
                          r"Pa_inv|per_K)$")


def _suggest(key: str, valid: Sequence[str], units: Optional[Mapping[str, str]] = None) -> str:
    """Hint for an unknown key: a valid key with the same stem and another
    unit (``module_m`` -> ``module_mm``), else the closest spelling."""
    if not valid:
        return ""
    k = key.lower()
    best = None
    for v in valid:
        m = _UNIT_SUFFIX.search(v)
        if not m:
            continue
        stem = v[:m.start()].lower()
        if (k.startswith(stem + "_") or k == stem) and (best is None or len(stem) > best[1]):
            best = (v, len(stem), m.group(1))
    if best is not None:
        unit = (units or {}).get(best[0], best[2])
        return f"; did you mean {best[0]!r}? (this key is in {unit})"
    close = difflib.get_close_matches(key, list(valid), n=1, cutoff=0.6)
    if not close:
        low = difflib.get_close_matches(k, [v.lower() for v in valid], n=1, cutoff=0.6)
        close = [v for v in valid if low and v.lower() == low[0]]
    return f"; did you mean {close[0]!r}?" if close else ""


def _describe(value: Any) -> str:
    if isinstance(value, bool):
        return f"the boolean {str(value).lower()}"
    if isinstance(value, str):
        return f"the string {value!r}"
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, list):
        return "an array"
    if isinstance(value, (int, float)):
        return repr(value)
    return f"a {type(value).__name__}"


def _to_si(v: float, scale: float) -> float:
    """v * scale, computed as a division when scale is 1/integer so that
    decimal inputs give the nearest double (6 mm -> 0.006 m exactly as typed)."""
    if scale != 1.0 and scale < 1.0:
        inv = round(1.0 / scale)
        if abs(1.0 / scale - inv) <= 1e-9 * inv:
            return v / inv
    return v * scale


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


class _Reader:
    """Collects problems while reading tables of a parsed scene."""

    def __init__(self) -> None:
        self.problems: List[Tuple[str, str]] = []

    def add(self, path: str, reason: str) -> None:
        self.problems.append((path, reason))

    # ---------------------------------------------------------- values
    def _num(self, path: str, key: Key, v: Any, integer: bool, allow_auto: bool = False):
        """Validate one number against ``key``'s range; return it in SI or None."""
        what = "an integer" if integer else "a number"
        rng = key.range_text()
        expect = f"{what} {rng}".strip() + (' or "auto"' if allow_auto else "")
        if integer:
            ok = isinstance(v, int) and not isinstance(v, bool)
        else:
            ok = _is_number(v)
        if not ok:
            self.add(path, f"must be {expect}, got {_describe(v)}")
            return None
        if not integer and not math.isfinite(v):
            self.add(path, f"must be a finite number {rng}".rstrip() + f", got {v!r}")
            return None
        bad = ((key.lo is not None and (v < key.lo or (key.lo_open and v == key.lo)))
               or (key.hi is not None and (v > key.hi or (key.hi_open and v == key.hi))))
        if bad:
            self.add(path, f"must be {expect}, got {v!r}")
            return None
        return int(v) if integer else _to_si(float(v), key.scale)

    def value(self, path: str, key: Key, v: Any):
        """Validate ``v`` for ``key``; return the SI value or None (problem recorded)."""
        k = key.kind
        if k == "float":
            return self._num(path, key, v, integer=False)
        if k == "int":
            return self._num(path, key, v, integer=True)
        if k == "int_or_auto":
            if v == _AUTO:
                return None
            return self._num(path, key, v, integer=True, allow_auto=True)
        if k == "float_or_auto":
            if v == _AUTO:
                return None
            return self._num(path, key, v, integer=False, allow_auto=True)
        if k == "bool":
            if not isinstance(v, bool):
                self.add(path, f"must be true or false, got {_describe(v)}")
                return None
            return v
        if k == "str":
            if not isinstance(v, str):
                self.add(path, f"must be a string, got {_describe(v)}")
                return None
            return v
        if k == "identifier":
            if not isinstance(v, str) or not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]{0,63}", v):
                self.add(path, "must be a C identifier (letters, digits, _; not starting with a digit; "
                               f"at most 64 characters), got {_describe(v)}")
                return None
            return v
        if k == "enum":
            if not isinstance(v, str) or v not in key.choices:
                hint = ""
                if isinstance(v, str):
                    close = difflib.get_close_matches(v.lower(), key.choices, n=1, cutoff=0.5)
                    hint = f"; did you mean {close[0]!r}?" if close else ""
                self.add(path, f"must be one of {', '.join(repr(c) for c in key.choices)}, "
                               f"got {_describe(v)}{hint}")
                return None
            return v
        if k == "str_list":
            if not isinstance(v, list) or not all(isinstance(x, str) for x in v):
                self.add(path, f"must be an array of strings, got {_describe(v)}")
                return None
            return tuple(v)
        if k in ("float_list", "float_pair"):
            if not isinstance(v, list):
                self.add(path, f"must be an array of numbers, got {_describe(v)}")
                return None
            out, ok = [], True
            for i, item in enumerate(v):
                x = self._num(f"{path}[{i}]", key, item, integer=False)
                ok = ok and x is not None
                out.append(x)
            if not ok:
                return None
            if k == "float_pair":
                if len(out) != 2 or not out[0] < out[1]:
                    self.add(path, f"must be [low, high] with low < high, got {v!r}")
                    return None
                return (out[0], out[1])
            return tuple(out)
        raise AssertionError(f"unknown key kind {k}")  # pragma: no cover - schema bug

    # ---------------------------------------------------------- tables
    def table(self, data: Any, path: str, *, required: bool = False) -> Dict[str, Any]:
        """Read the table at ``path`` (schema ``SCHEMA[path]``): returns key ->
        SI value (defaults filled in, None where invalid or absent)."""
        keys = SCHEMA.get(path, ())
        subs = _SUBTABLES.get(path, ())
        out: Dict[str, Any] = {k.name: None for k in keys}
        if data is None:
            if required:
                self.add(path, "missing table (required)")
                return out
            data = {}
        if not isinstance(data, dict):
            self.add(path, f"must be a table, got {_describe(data)}")
            return out
        valid = [k.name for k in keys] + list(subs)
        units = {k.name: k.unit for k in keys}
        for name in data:
            if name not in valid:
                where = f"{path}.{name}" if path else name
                self.add(where, "unknown key" + _suggest(name, valid, units))
        for k in keys:
            p = f"{path}.{k.name}"
            if k.name in data:
                out[k.name] = self.value(p, k, data[k.name])
            elif k.required:
                self.add(p, "missing (required)")
            elif k.default is None or k.default is _AUTO:
                out[k.name] = None
            elif k.kind == "float":
                out[k.name] = _to_si(float(k.default), k.scale)
            elif k.kind == "float_list":
                out[k.name] = tuple(_to_si(x, k.scale) for x in k.default)
            else:
                out[k.name] = k.default
        return out


def _sub(data: Any, name: str) -> Any:
    return data.get(name) if isinstance(data, dict) else None


# ============================================================== TOML writer
_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def _toml_str(s: str) -> str:
    out = ['"']
    for ch in s:
        o = ord(ch)
        if ch == '"':
            out.append('\\"')
        elif ch == "\\":
            out.append("\\\\")
        elif ch == "\n":
            out.append("\\n")
        elif ch == "\t":
            out.append("\\t")
        elif o < 0x20 or o == 0x7F:
            out.append(f"\\u{o:04X}")
        elif 0xD800 <= o <= 0xDFFF:
            raise ValueError("dumps_toml: lone surrogate characters cannot be written to TOML")
        else:
            out.append(ch)
    out.append('"')
    return "".join(out)


def _toml_key(k: str) -> str:
    return k if _BARE_KEY.fullmatch(k) else _toml_str(k)


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return _toml_str(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, Mapping):
        return "{" + ", ".join(f"{_toml_key(str(k))} = {_toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"dumps_toml: cannot write a {type(v).__name__}")


def _is_table_array(v: Any) -> bool:
    return isinstance(v, (list, tuple)) and len(v) > 0 and all(isinstance(x, Mapping) for x in v)


def _dump_table(data: Mapping, prefix: List[str], lines: List[str]) -> None:
    scalars = [(k, v) for k, v in data.items() if not isinstance(v, Mapping) and not _is_table_array(v)]
    tables = [(k, v) for k, v in data.items() if isinstance(v, Mapping)]
    arrays = [(k, v) for k, v in data.items() if _is_table_array(v)]
    for k, v in scalars:
        lines.append(f"{_toml_key(str(k))} = {_toml_value(v)}")
    for k, v in tables:
        path = prefix + [str(k)]
        lines.append("")
        lines.append("[" + ".".join(_toml_key(p) for p in path) + "]")
        _dump_table(v, path, lines)
    for k, v in arrays:
        path = prefix + [str(k)]
        for item in v:
            lines.append("")
            lines.append("[[" + ".".join(_toml_key(p) for p in path) + "]]")
            _dump_table(item, path, lines)


def dumps_toml(data: Mapping) -> str:
    """Write a nested mapping (tables, arrays of tables, strings, numbers,
    booleans, arrays) as TOML text that :mod:`tomllib` reads back to the same
    data.  Used for scenes built in code (:func:`load_scene` with a mapping)
    so that every scene has a TOML source for provenance."""
    if not isinstance(data, Mapping):
        raise TypeError("dumps_toml: expected a mapping")
    lines: List[str] = []
    _dump_table(data, [], lines)
    return "\n".join(lines).lstrip("\n") + "\n"


# ============================================================== building
def _gear_spec(r: _Reader, data: Any, role: str, shared: Dict[str, Any], mat: Dict[str, Any],
               dev: Optional[GearDeviations]) -> Optional[GearSpec]:
    g = r.table(_sub(_sub(data, "gears"), role), f"gears.{role}", required=True)
    vals = {k: g[k] if g.get(k) is not None else mat[k] for k in
            ("youngs_modulus_GPa", "poisson_ratio", "density_kg_m3", "thermal_expansion_per_K")}
    if any(v is None for v in vals.values()) or g["teeth"] is None:
        return None
    needed = ("profile_shift", "addendum_coefficient", "tip_clearance_coefficient")
    if any(g[k] is None for k in needed) or any(shared[k] is None for k in
                                                 ("module_mm", "pressure_angle_deg", "face_width_mm")):
        return None
    material = Material(youngs_modulus_Pa=vals["youngs_modulus_GPa"], poisson_ratio=vals["poisson_ratio"],
                        density_kg_m3=vals["density_kg_m3"], thermal_expansion_per_K=vals["thermal_expansion_per_K"])
    m = shared["module_mm"]
    hub = g["hub_radius_mm"]
    beta = shared.get("helix_angle_deg") or 0.0
    hand = shared.get("hand") or "right"
    if role == "gear" and beta != 0.0:
        hand = "left" if hand == "right" else "right"
    if hub is not None:
        root = m * (g["teeth"] / (2.0 * math.cos(beta)) - g["addendum_coefficient"] - g["tip_clearance_coefficient"]
                    + g["profile_shift"])
        if hub >= root:
            r.add(f"gears.{role}.hub_radius_mm",
                  f"must be smaller than the root radius {root * 1e3:.4g} mm, got {hub * 1e3:g}")
            return None
    return GearSpec(teeth=g["teeth"], module_m=m, pressure_angle_rad=shared["pressure_angle_deg"],
                    face_width_m=shared["face_width_mm"], profile_shift=g["profile_shift"],
                    addendum_coefficient=g["addendum_coefficient"],
                    tip_clearance_coefficient=g["tip_clearance_coefficient"], hub_radius_m=hub,
                    material=material, inertia_kgm2=g["inertia_kgm2"],
                    deviations=dev if dev is not None else GearDeviations(),
                    helix_angle_rad=beta, helix_hand=hand)


def _deviations(r: _Reader, data: Any, role: str, teeth: Optional[int]) -> Optional[GearDeviations]:
    """Read [deviations.<role>] and its [[deviations.<role>.tooth]] rows into
    a :class:`GearDeviations` (SI); ``teeth`` None = tooth count invalid
    (then only the per-key checks run)."""
    path = f"deviations.{role}"
    raw = _sub(_sub(data, "deviations"), role)
    n_before = len(r.problems)
    d = r.table(raw, path)
    rows: List[Tuple[str, Dict[str, Any]]] = []
    traw = _sub(raw, "tooth")
    if traw is not None:
        if not isinstance(traw, list) or not all(isinstance(t, dict) for t in traw):
            r.add(f"{path}.tooth", f"must be an array of tables [[{path}.tooth]], got {_describe(traw)}")
            traw = []
        valid = [k.name for k in _TOOTH_KEYS]
        units = {k.name: k.unit for k in _TOOTH_KEYS}
        for i, t in enumerate(traw):
            p = f"{path}.tooth[{i}]"
            for name in t:
                if name not in valid:
                    r.add(f"{p}.{name}", "unknown key" + _suggest(name, valid, units))
            vals: Dict[str, Any] = {}
            for k in _TOOTH_KEYS:
                if k.name in t:
                    vals[k.name] = r.value(f"{p}.{k.name}", k, t[k.name])
                elif k.required:
                    r.add(f"{p}.{k.name}", "missing (required)")
                    vals[k.name] = None
            rows.append((p, vals))
    pitch = d.get("pitch_um")
    if teeth is not None and pitch is not None and len(pitch) not in (0, teeth):
        r.add(f"{path}.pitch_um", f"must have one value per tooth ({teeth}) or be empty, got {len(pitch)} values")
    seen: Dict[int, str] = {}
    for p, vals in rows:
        idx = vals["index"]
        if idx is not None and teeth is not None:
            if idx >= teeth:
                r.add(f"{p}.index", f"must be an integer in [0, {teeth - 1}] (the gear has {teeth} teeth), got {idx}")
            elif idx in seen:
                r.add(f"{p}.index", f"tooth {idx} is already given by {seen[idx]}")
            else:
                seen[idx] = p
        if "pitch_um" in vals and pitch:
            r.add(f"{p}.pitch_um", f"tooth pitch given twice: {path}.pitch_um already lists every tooth")
    if len(r.problems) > n_before or teeth is None:
        return None
    default = ToothDeviation(profile_form_m=d["profile_form_um"], profile_slope_m=d["profile_slope_um"],
                             form_periods=d["form_periods"], pitch_m=0.0)
    overrides = {vals["index"]: vals for _, vals in rows}
    fields = (("profile_form_m", "profile_form_um"), ("profile_slope_m", "profile_slope_um"),
              ("form_periods", "form_periods"), ("pitch_m", "pitch_um"))
    per_tooth = []
    for i in range(teeth):
        dev = replace(default, pitch_m=pitch[i]) if pitch else default
        o = overrides.get(i)
        if o:
            dev = replace(dev, **{f: o[key] for f, key in fields if key in o})
        if dev != default:
            per_tooth.append((i, dev))
    return GearDeviations(default=default, per_tooth=tuple(per_tooth), lead_crowning_m=d["lead_crowning_um"])


def _lubricant(r: _Reader, data: Any) -> Optional[Lubricant]:
    raw = _sub(data, "lubricant")
    if raw is None:
        return None
    n0 = len(r.problems)
    lu = r.table(raw, "lubricant")
    if len(r.problems) > n0 or not isinstance(raw, dict):
        return None
    has_eta = "eta0_Pas" in raw
    has_nu = ("kinematic_viscosity_40C_cSt" in raw, "kinematic_viscosity_100C_cSt" in raw)
    if has_eta and any(has_nu):
        r.add("lubricant", "give either eta0_Pas or the kinematic viscosities "
                           "(kinematic_viscosity_40C_cSt and kinematic_viscosity_100C_cSt), not both")
        return None
    if not has_eta and not all(has_nu):
        r.add("lubricant", "needs eta0_Pas, or both kinematic_viscosity_40C_cSt and "
                           "kinematic_viscosity_100C_cSt")
        return None
    nu40 = nu100 = None
    if has_eta:
        eta = lu["eta0_Pas"]
    else:
        nu40, nu100 = lu["kinematic_viscosity_40C_cSt"], lu["kinematic_viscosity_100C_cSt"]
        if not nu100 < nu40:
            r.add("lubricant.kinematic_viscosity_100C_cSt",
                  f"must be smaller than kinematic_viscosity_40C_cSt ({nu40 * 1e6:g}), got {nu100 * 1e6:g}")
            return None
        try:
            eta = 1e-6 * walther_kinematic_viscosity_cSt(nu40 * 1e6, nu100 * 1e6, lu["temperature_C"]) \
                * lu["density_kg_m3"]
        except (OverflowError, ValueError):
            eta = float("nan")
        if not (math.isfinite(eta) and eta > 0):
            r.add("lubricant.temperature_C", f"the viscosity law gives no usable viscosity at {lu['temperature_C']:g} degC")
            return None
    return Lubricant(name=lu["name"], dynamic_viscosity_Pas=eta,
                     pressure_viscosity_Pa_inv=lu["pressure_viscosity_GPa_inv"],
                     density_kg_m3=lu["density_kg_m3"], temperature_C=lu["temperature_C"],
                     kinematic_viscosity_40C_m2_s=nu40, kinematic_viscosity_100C_m2_s=nu100)


def _thermal(r: _Reader, data: Any) -> Optional[ThermalOptions]:
    """Read ``[thermal]`` (None when absent); cross-checks profile lengths and order."""
    raw = _sub(data, "thermal")
    if raw is None:
        return None
    n0 = len(r.problems)
    th = r.table(raw, "thermal")
    if len(r.problems) > n0:
        return None
    for role in ("pinion", "gear"):
        g, t = th[f"{role}_profile_gamma"], th[f"{role}_profile_C"]
        if len(g) != len(t):
            r.add(f"thermal.{role}_profile_C", f"needs one temperature per {role}_profile_gamma point "
                                               f"({len(g)}), got {len(t)}")
        elif any(b <= a for a, b in zip(g, g[1:])):
            r.add(f"thermal.{role}_profile_gamma", f"must be strictly ascending, got {list(g)!r}")
    ax = th["temperature_axis_C"]
    if any(b <= a for a, b in zip(ax, ax[1:])):
        r.add("thermal.temperature_axis_C", f"must be strictly ascending, got {list(ax)!r}")
    if len(r.problems) > n0:
        return None
    return ThermalOptions(**th)


def _thermal_cross_checks(r: _Reader, th: Optional[ThermalOptions], contact_model: Optional[str],
                          lub: Optional[Lubricant]) -> Optional[ThermalOptions]:
    """[thermal] against [mesh] and [lubricant] (docs/thermal.md "Oil temperature axis"):
    an axis_quantity other than "bulk" needs an axis, a contact model that uses
    the lubricant and a viscosity-temperature law usable at every axis
    temperature; a bulk temperature axis excludes fixed gear temperatures.
    Returns the options with the lubricant attached when the axis involves the oil."""
    if th is None:
        return None
    q = th.axis_quantity
    fixed = [k for k in ("pinion_temperature_C", "gear_temperature_C") if getattr(th, k) is not None] + \
        [k for k in ("pinion_profile_C", "gear_profile_C") if len(getattr(th, k))]
    if len(th.temperature_axis_C) and q in ("bulk", "bulk_and_oil") and fixed:
        r.add(f"thermal.{fixed[0]}", f"the {q!r} temperature axis sets the temperature of both gears; remove "
                                     f"{', '.join(fixed)} or use axis_quantity = \"oil\"")
    if q == "bulk":
        return th
    if not len(th.temperature_axis_C):
        r.add("thermal.axis_quantity", f"{q!r} needs thermal.temperature_axis_C (the oil temperatures of the "
                                       "tables' axis)")
        return th
    if contact_model not in LUBRICATED_CONTACT_MODELS:
        r.add("thermal.axis_quantity", f"{q!r}: the oil temperature acts through eta0 of a lubricated contact "
                                       f"model, but mesh.contact_model = {contact_model!r} uses no lubricant "
                                       f"(use one of {list(LUBRICATED_CONTACT_MODELS)}, or axis_quantity = \"bulk\")")
        return th
    if lub is None:
        return th  # the missing [lubricant] is reported above
    if lub.kinematic_viscosity_40C_m2_s is None or lub.kinematic_viscosity_100C_m2_s is None:
        r.add("lubricant.eta0_Pas", f"thermal.axis_quantity = {q!r} needs a viscosity-temperature law: give "
                                    "kinematic_viscosity_40C_cSt and kinematic_viscosity_100C_cSt instead")
        return th
    for t in th.temperature_axis_C:
        try:
            eta = lub.density_kg_m3 * lub.kinematic_viscosity_m2_s(float(t))
        except (OverflowError, ValueError):
            eta = float("nan")
        if not (math.isfinite(eta) and eta > 0):
            r.add("thermal.temperature_axis_C", f"the lubricant's viscosity law gives no usable viscosity at "
                                                f"{t:g} degC")
            return th
    return replace(th, lubricant=lub)


#: GearPairSpec / GearSpec field names -> scene key names (for GeometryError)
_FIELD_TO_KEY = {
    "teeth": "teeth", "module_m": "module_mm", "pressure_angle_rad": "pressure_angle_deg",
    "face_width_m": "face_width_mm", "profile_shift": "profile_shift",
    "addendum_coefficient": "addendum_coefficient", "tip_clearance_coefficient": "tip_clearance_coefficient",
    "hub_radius_m": "hub_radius_mm", "inertia_kgm2": "inertia_kgm2", "backlash_m": "backlash_um",
    "center_distance_m": "center_distance_mm", "youngs_modulus_Pa": "youngs_modulus_GPa",
    "poisson_ratio": "poisson_ratio", "density_kg_m3": "density_kg_m3",
    "thermal_expansion_per_K": "thermal_expansion_per_K",
    "helix_angle_rad": "helix_angle_deg", "helix_hand": "hand",
}
_SHARED = ("module_m", "pressure_angle_rad", "face_width_m", "backlash_m", "center_distance_m",
           "helix_angle_rad", "helix_hand")


def _geometry_key_path(field: str) -> str:
    """Map a GeometryError field ('pinion.profile_shift', 'center_distance_m',
    'pair', ...) to the scene key path ('gears.pinion.profile_shift', ...)."""
    parts = [p for p in re.split(r"[.\[\]]+", field.strip()) if p]
    if parts and parts[0] in ("pair", "gears", "spec"):
        parts = parts[1:]
    role = None
    if parts and parts[0] in ("pinion", "gear"):
        role, parts = parts[0], parts[1:]
    if not parts:
        return f"gears.{role}" if role else "gears"
    name = parts[-1]
    key = _FIELD_TO_KEY.get(name)
    if key is None:
        return f"gears.{role}" if role else "gears"
    if name in _SHARED:
        return f"gears.{key}"
    return f"gears.{role}.{key}" if role else f"gears.{key}"


def _geometry_problem(exc: BaseException) -> Tuple[str, str]:
    msg = str(exc)
    field = None
    for attr in ("key", "field", "path", "field_name"):
        val = getattr(exc, attr, None)
        if isinstance(val, str) and val:
            field = val
            break
    if field is None:
        m = re.match(r"\s*([A-Za-z_][\w.\[\]]*)((?:\s*\+\s*[A-Za-z_][\w.\[\]]*)*)\s*:\s*(.*)", msg, re.S)
        if m:
            field, msg = m.group(1), (m.group(1) + m.group(2) + ": " if m.group(2) else "") + m.group(3)
    path = _geometry_key_path(field) if field else "gears"
    return path, f"impossible gear pair: {msg}"


def _check_geometry(pair: GearPairSpec) -> Optional[Tuple[str, str]]:
    """Run the geometry module's checks (contact ratio, pointed tip, undercut,
    interference); return ``(key_path, reason)`` or None."""
    try:
        geometry.pair_geometry(pair)
    except (ValueError, ArithmeticError) as exc:  # GeometryError is a ValueError
        return _geometry_problem(exc)
    return None


def _model_name(name: str) -> str:
    s = re.sub(r"[^A-Za-z0-9_]+", "_", name).strip("_") or "gearfmu_scene"
    if s[0].isdigit():
        s = "scene_" + s
    return s[:64]


def _build(data: Dict[str, Any], text: str, source_path: Optional[str]) -> Scene:
    r = _Reader()
    top = r.table(data, "")
    del top
    sc = r.table(_sub(data, "scene"), "scene")
    name = sc["name"] if isinstance(sc["name"], str) else "scene"
    shared = r.table(_sub(data, "gears"), "gears", required=True)
    mat = r.table(_sub(data, "material"), "material")
    _ = r.table(_sub(data, "deviations"), "deviations")
    teeth = {}
    for role in ("pinion", "gear"):
        raw = _sub(_sub(data, "gears"), role)
        t = raw.get("teeth") if isinstance(raw, dict) else None
        teeth[role] = t if isinstance(t, int) and not isinstance(t, bool) and 5 <= t <= 1000 else None
    devs = {role: _deviations(r, data, role, teeth[role]) for role in ("pinion", "gear")}
    gears = {role: _gear_spec(r, data, role, shared, mat, devs[role]) for role in ("pinion", "gear")}
    mesh_d = r.table(_sub(data, "mesh"), "mesh")
    op = r.table(_sub(data, "operating"), "operating", required=True)
    tab = r.table(_sub(data, "tables"), "tables")
    sol = r.table(_sub(data, "solver"), "solver")
    fmu = r.table(_sub(data, "fmu"), "fmu")
    _roughness(r, data)  # validated here; Scene.roughness reads it
    lub = _lubricant(r, data)
    thermal = _thermal(r, data)
    envelope, accuracy = read_envelope_sections(r, data, op, source_path)

    # ---------------- cross-key checks (only on values that passed their own checks)
    for k, rk in (("torque_Nm", "torque_range_Nm"), ("speed_rpm", "speed_range_rpm")):
        v, rng = op[k], op[rk]
        if v is not None and rng is not None and not (rng[0] - 1e-12 * abs(rng[1]) <= v <= rng[1] * (1 + 1e-12)):
            scale = SCHEMA["operating"][0].scale if k == "torque_Nm" else _RPM_TO_RAD_S
            r.add(f"operating.{k}", f"{v / scale:g} lies outside operating.{rk} "
                                    f"[{rng[0] / scale:g}, {rng[1] / scale:g}]")
    if tab["torque_points"] is not None and tab["torque_points"] > 1 and op["torque_range_Nm"] is None \
            and isinstance(_sub(data, "operating"), dict) and "torque_range_Nm" not in data["operating"]:
        r.add("tables.torque_points", f"{tab['torque_points']} torque points need operating.torque_range_Nm")
    if fmu["stop_time_s"] is not None and fmu["output_interval_s"] is not None \
            and fmu["output_interval_s"] > fmu["stop_time_s"]:
        r.add("fmu.output_interval_s", f"must not exceed fmu.stop_time_s ({fmu['stop_time_s']:g} s), "
                                       f"got {fmu['output_interval_s']:g}")
    if mesh_d["contact_model"] in LUBRICATED_CONTACT_MODELS and _sub(data, "lubricant") is None:
        r.add("lubricant", f"missing table (required by mesh.contact_model = {mesh_d['contact_model']!r})")
    thermal = _thermal_cross_checks(r, thermal, mesh_d["contact_model"], lub)

    pair = None
    if gears["pinion"] is not None and gears["gear"] is not None and shared["backlash_um"] is not None \
            and not ("center_distance_mm" in (_sub(data, "gears") or {}) and shared["center_distance_mm"] is None):
        pair = GearPairSpec(pinion=gears["pinion"], gear=gears["gear"], backlash_m=shared["backlash_um"],
                            center_distance_m=shared["center_distance_mm"])
        if not r.problems:
            problem = _check_geometry(pair)
            if problem is not None:
                r.add(*problem)
    if r.problems:
        raise SceneError(r.problems, source=source_path or name)

    assert pair is not None
    mesh = MeshModelOptions(contact_model=mesh_d["contact_model"], slices=mesh_d["slices"],
                            foundation=mesh_d["foundation"],
                            shared_foundation_correction=mesh_d["shared_foundation_correction"])
    operating = OperatingPoint(torque_Nm=op["torque_Nm"], speed_rad_s=op["speed_rpm"],
                               torque_range_Nm=op["torque_range_Nm"], speed_range_rad_s=op["speed_range_rpm"],
                               torque_points=tab["torque_points"])
    tables = TableOptions(points_per_mesh=tab["points_per_mesh"], torque_points=tab["torque_points"],
                          slots=tab["slots"])
    solver = SolverOptions(integrator=sol["integrator"], max_step_s=sol["max_step_s"],
                           damping_model=sol["damping_model"])
    dt_auto = fmu["output_interval_s"] is None
    dt = (min(default_output_interval_s(operating.speed_rad_s, pair.pinion.teeth), fmu["stop_time_s"])
          if dt_auto else fmu["output_interval_s"])
    fmu_o = FmuOptions(model_name=fmu["model_name"] or _model_name(name), damping_ratio=fmu["damping_ratio"],
                       runtime=fmu["runtime"], stop_time_s=fmu["stop_time_s"],
                       output_interval_s=dt, output_interval_auto=dt_auto)
    return Scene(name=name, description=sc["description"], text=text, pair=pair, mesh=mesh,
                 operating=operating, tables=tables, solver=solver, fmu=fmu_o, lubricant=lub,
                 source_path=source_path, thermal=thermal, envelope=envelope, accuracy=accuracy)


# ============================================================== public entry points
def default_scene_path() -> Path:
    """Path of the package's default scene (``gearfmu/scene/data/default_scene.toml``:
    the gear pair of seed 000 Table 1)."""
    return Path(__file__).resolve().parent / "data" / "default_scene.toml"


def load_scene(source: Union[str, Path, Mapping, None] = None) -> Scene:
    """Parse and validate a scene.

    ``source`` is a path (``str`` or :class:`~pathlib.Path`) to a TOML file,
    TOML text (a ``str`` containing a newline or ``=``), a mapping with the
    same structure (written to TOML first, so the scene keeps a TOML source),
    or None for :func:`default_scene_path`.  Returns a :class:`Scene` in SI;
    raises :class:`SceneError` listing every problem with its key path.
    """
    source_path: Optional[str] = None
    if source is None:
        source = default_scene_path()
    if isinstance(source, Mapping):
        try:
            text = dumps_toml(source)
        except (TypeError, ValueError) as exc:
            raise SceneError([("<scene>", f"cannot be written as TOML: {exc}")]) from None
    elif isinstance(source, Path) or (isinstance(source, str) and "\n" not in source and "=" not in source):
        path = Path(source)
        try:
            text = path.read_text(encoding="utf-8")
        except FileNotFoundError:
            raise SceneError([("<file>", f"scene file not found: {path}")]) from None
        except (OSError, UnicodeDecodeError) as exc:
            raise SceneError([("<file>", f"cannot read scene file {path}: {exc}")]) from None
        source_path = str(path)
    elif isinstance(source, str):
        text = source
    else:
        raise SceneError([("<scene>", f"expected a path, TOML text or a mapping, got {type(source).__name__}")])
    try:
        data = _toml.loads(text)
    except _toml.TOMLDecodeError as exc:
        raise SceneError([("<toml>", f"not valid TOML: {exc}")], source=source_path or "") from None
    return _build(data, text, source_path)
