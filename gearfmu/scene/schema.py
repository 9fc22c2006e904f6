"""The scene schema: every table of a scene file, its keys, their units, defaults and ranges.

One declarative table, :data:`SCHEMA` (table path -> :class:`Key` tuple), that
:class:`gearfmu.scene.validate.Reader` checks a parsed scene against and that
``docs/scene.md`` documents key by key.  Every dimensional key carries its unit in
its name; :attr:`Key.scale` converts it to SI.  Option strings come from
:mod:`gearfmu.common.vocabulary` (their one definition).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Dict, Optional, Tuple

from ..common.vocabulary import (CONTACT_MODELS, DAMPING_MODELS, DEFAULT_DAMPING_MODEL, DEFAULT_INTEGRATOR,
                                 DEFAULT_RUNTIME, FILM_FAILURE_POLICIES,
                                 FILM_TRANSIENT_MODES, FLANK_LAWS, HELIX_HANDS, INTEGRATORS, OIL_ALPHA_LAWS,
                                 RUNTIMES, THERMAL_AXIS_QUANTITIES)
from ..contact.base import DEFAULT_FILM_POSITION_NODES, FULL_FILM_PARAMETER
from .options import OUTPUT_SAMPLES_PER_MESH, RPM_TO_RAD_S

__all__ = ["Key", "SCHEMA", "SUBTABLES", "TOOTH_KEYS", "REQUIRED", "AUTO"]

REQUIRED = object()
AUTO = "auto"


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
        return self.default is REQUIRED

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
    _i("teeth", REQUIRED, "number of teeth z", 5, 1000),
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

TOOTH_KEYS = (
    _i("index", REQUIRED, "tooth index, 0-based, < teeth", 0, None),
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
        _f("module_mm", "mm", REQUIRED, "module m", 0.0, 100.0, lo_open=True, scale=1e-3),
        _f("pressure_angle_deg", "deg", 20.0, "pressure angle alpha of the basic rack", 10.0, 35.0,
           lo_open=True, hi_open=True, scale=math.pi / 180.0),
        _f("face_width_mm", "mm", REQUIRED, "face width b", 0.0, 5000.0, lo_open=True, scale=1e-3),
        _f("backlash_um", "um", 0.0, "total backlash (play) along the line of action; the dead zone "
           "of seed 003 eq 6 is half of it", 0.0, 5000.0, scale=1e-6),
        _f("center_distance_mm", "mm", None, "operating centre distance (none = zero-backlash distance "
           "from the profile shifts)", 0.0, None, lo_open=True, scale=1e-3),
        _f("helix_angle_deg", "deg", 0.0, "reference helix angle beta (0 = spur); with beta > 0 module, "
           "pressure angle, shifts and addendum/clearance coefficients are normal-section values "
           "(docs/helical.md)", 0.0, 45.0, scale=math.pi / 180.0),
        _e("hand", HELIX_HANDS, "right", "helix hand of the pinion (the gear has the opposite hand)"),
    ),
    "gears.pinion": _GEAR_KEYS,
    "gears.gear": _GEAR_KEYS,
    "material": _MATERIAL_KEYS,
    "deviations.pinion": _DEV_KEYS,
    "deviations.gear": _DEV_KEYS,
    "deviations.pinion.tooth": TOOTH_KEYS,
    "deviations.gear.tooth": TOOTH_KEYS,
    "mesh": (
        _e("contact_model", CONTACT_MODELS, "hertz", "contact stiffness model"),
        _i("slices", 1, "face-width slices of the sliced stiffness model", 1, 1000),
        Key("foundation", "bool", "-", True, "fillet-foundation stiffness (Sainsot et al. 2004)"),
        Key("shared_foundation_correction", "bool", "-", False,
            "shared-foundation correction (Ma et al. 2016, seed 000 eq 11)"),
    ),
    "operating": (
        _f("torque_Nm", "N*m", REQUIRED, "nominal pinion torque (positive drives)", 0.0, 1e7, lo_open=True),
        _f("speed_rpm", "rpm", REQUIRED, "nominal pinion speed", 0.0, 1e6, lo_open=True, scale=RPM_TO_RAD_S),
        _f("torque_range_Nm", "N*m", None, "[low, high] pinion torque envelope; the torque axis when "
           "tables.torque_points > 1", 0.0, 1e7, kind="float_pair"),
        _f("speed_range_rpm", "rpm", None, "[low, high] pinion speed envelope", 0.0, 1e6,
           scale=RPM_TO_RAD_S, kind="float_pair"),
    ),
    "tables": (
        _i("points_per_mesh", 64, "pinion-angle samples per mesh period", 8, 100000),
        _i("torque_points", 1, "samples of the torque axis (1 = no torque axis)", 1, 1000),
        _i("slots", AUTO, "tooth-pair slot count P or \"auto\" (from the contact ratio)", 1, 16,
           kind="int_or_auto"),
    ),
    "solver": (
        _e("integrator", INTEGRATORS, DEFAULT_INTEGRATOR, "internal integrator (docs/model.md)"),
        _f("max_step_s", "s", AUTO, "largest internal step, or \"auto\"", 0.0, 1.0, lo_open=True,
           kind="float_or_auto"),
        _e("damping_model", DAMPING_MODELS, DEFAULT_DAMPING_MODEL, "per-pair damping rule (docs/model.md)"),
    ),
    "fmu": (
        Key("model_name", "identifier", "-", None, "FMU model name / identifier (C identifier; none = "
            "from scene.name)"),
        _f("damping_ratio", "1", 0.05, "mesh damping ratio zeta (tunable FMU parameter)", 0.0, 1.0),
        _e("runtime", RUNTIMES, DEFAULT_RUNTIME, "FMU runtime"),
        _f("stop_time_s", "s", 0.05, "DefaultExperiment stop time", 0.0, 1e6, lo_open=True),
        _f("output_interval_s", "s", AUTO, "DefaultExperiment output (communication) interval, or \"auto\" "
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
        _f("pressure_viscosity_GPa_inv", "1/GPa", REQUIRED, "pressure-viscosity coefficient alpha", 0.0,
           100.0, lo_open=True, scale=1e-9),
        _f("density_kg_m3", "kg/m^3", REQUIRED, "density at ambient pressure", 0.0, 3000.0, lo_open=True),
        _f("temperature_C", "degC", REQUIRED, "oil (inlet / bulk) temperature", -60.0, 300.0),
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
        _e("flank_law", FLANK_LAWS, FLANK_LAWS[0],
           "free thermal deformation of a flank (docs/thermal.md)"),
        _e("axis_quantity", THERMAL_AXIS_QUANTITIES, THERMAL_AXIS_QUANTITIES[0], "what temperature_axis_C is: bulk temperature "
           "of both gears (FMU input bulk_temperature), oil temperature (eta0 of a lubricated contact model; "
           "input oil_temperature) or both at one temperature (input gearbox_temperature)"),
        _e("oil_alpha", OIL_ALPHA_LAWS, OIL_ALPHA_LAWS[0], "pressure-viscosity coefficient along an oil "
           "axis: Roelands (constant Z, alpha from eta0(T)) or the [lubricant] value at every temperature"),
    ),
    # operating envelope and accuracy target of the fidelity planner (gearfmu/scene/envelope.py, docs/plan.md)
    "envelope": (
        _f("torque_range_Nm", "N*m", None, "[low, high] pinion torque envelope (none = "
           "operating.torque_range_Nm, else the nominal torque)", 0.0, 1e7, kind="float_pair"),
        _f("speed_range_rpm", "rpm", None, "[low, high] pinion speed envelope (none = "
           "operating.speed_range_rpm, else the nominal speed)", 0.0, 1e6, scale=RPM_TO_RAD_S,
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
SUBTABLES = {
    "": ("scene", "gears", "material", "deviations", "mesh", "operating", "tables", "solver", "fmu",
         "lubricant", "thermal", "envelope", "accuracy", "roughness"),
    "gears": ("pinion", "gear"),
    "deviations": ("pinion", "gear"),
    "deviations.pinion": ("tooth",),
    "deviations.gear": ("tooth",),
}

# [roughness]: W-M flank roughness of the rough-EHL contact model (Zhao et al. 2022 eq 1, Table 2;
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
    _f("full_film_parameter", "1", FULL_FILM_PARAMETER, "film parameter Lambda = h_min/sigma (Dowson-Higginson h_min, "
       "composite W-M sigma) below which the full-film model is not used", 0.0, 100.0),
    _i("film_position_nodes", DEFAULT_FILM_POSITION_NODES, "contact positions along the path of contact at which the rough films "
       "are solved and interpolated (0 = every table position)", 0, 10000),
    _e("film_transient", FILM_TRANSIENT_MODES, "off", "off: steady films with the roughness frozen in "
       "the contact; correction: at every film-grid node transient films with the roughness moving with the flanks "
       "on 4 slices give c = <k_transient>/k_steady, which multiplies every slice's rough/smooth ratio "
       "(docs/ehl_transient.md section 3); film: the node's rough film is the transient film (start 'auto', no "
       "steady rough solve), ratio <k_transient>/k_smooth for every slice, no film-parameter screen "
       "(docs/ehl_mesh.md 'Transient films in the tables'); needs film_position_nodes >= 2"),
)
