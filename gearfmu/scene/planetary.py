"""The ``[[planetary]]`` stages of a drivetrain scene: a planetary set by its geometry or by published
lumped parameters (docs/scene.md "[[planetary]]", docs/planetary.md).

A row names the stage (its ports are the parts ``<name>.sun``, ``<name>.carrier`` and ``<name>.ring``;
the ``held`` one is grounded through its torsional support -- or, with ``driven_speed_rpm``, driven
through it by a speed-controlled drive --, the other two join the drivetrain by shafts), the dynamic model, the number of planets and their angles, damping, pin position errors,
and either

* ``[planetary.gears]``: module, pressure angle, face width, tooth counts, profile shifts, carrier
  radius, backlash and the ring's rim (gearfmu.gear.planetary_set, gearfmu.gear.internal), with
  ``[planetary.carrier]`` (mass, inertia) and optionally ``[planetary.ring]`` (mass, inertia; none:
  the rim annulus); the tables are built later from the geometry (gearfmu.assembly.planetary), or
* ``[planetary.lumped]``: masses, I/r^2, mean mesh stiffness, pressure angle, tooth counts and the
  sun's base radius, as a paper publishes them (gearfmu.assembly.planetary_lumped),

and ``[planetary.bearings]``: the translational support stiffness of sun, ring, carrier and the planet
bearings (the translational model).  An impossible set is refused at reading with its key and reason:
the assembly condition, planets that overlap, interference and pointed teeth of either mesh, the tip
clearance, both meshes at one carrier radius (the checks of gearfmu.gear.planetary_set).
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any, Dict, Optional, Tuple

from ..assembly.planetary import StageMechanics
from ..assembly.planetary_lumped import LumpedPlanetary, lumped_stage
from ..common.units import RPM_TO_RAD_S
from ..common.vocabulary import (DAMPING_MODELS, DEFAULT_DAMPING_MODEL, DEFAULT_PLANETARY_MODEL, PLANETARY_MODELS,
                                 PLANETARY_PORTS)
from ..gear.gearpair import GearSpec
from ..gear.internal import RingRim
from ..gear.planetary_set import PlanetarySet, PlanetErrors, planetary_geometry
from ..tables.planetary import PlanetaryStageError
from .schema import REQUIRED, Key
from .validate import Reader, sub

__all__ = ["PLANETARY_SCHEMA", "PLANETARY_SUBTABLES", "PlanetarySpec", "read_planetary"]


def _f(name, unit, default, doc, lo=None, hi=None, lo_open=False, hi_open=False, scale=1.0, kind="float"):
    return Key(name, kind, unit, default, doc, lo, hi, lo_open, hi_open, (), scale)


_BEARING = "translational support stiffness (x and y alike) of the "
#: the keys of a [[planetary]] row and its sub-tables (docs/scene.md "[[planetary]]")
PLANETARY_SCHEMA: Dict[str, Tuple[Key, ...]] = {
    "planetary": (
        Key("name", "str", "-", REQUIRED, "stage name (letters, digits, _); its ports are the parts <name>.sun, "
            "<name>.carrier and <name>.ring, its outputs <name>.sun_planet[n].dte, ..."),
        Key("held", "enum", "-", "ring", "the port grounded through its torsional support (the other two join the "
            "drivetrain); with driven_speed_rpm, the port driven through it", choices=PLANETARY_PORTS),
        _f("driven_speed_rpm", "rpm", None, "none: the held port is grounded; given: its support's outer end turns at "
           "this speed (a speed-controlled drive with the support's stiffness and damping; the FMU's input "
           "<name>.<held>_speed_input)", -1e6, 1e6, scale=RPM_TO_RAD_S),
        Key("model", "enum", "-", DEFAULT_PLANETARY_MODEL, "dynamic model: Lin & Parker's translational-rotational "
            "model or the purely torsional one", choices=PLANETARY_MODELS),
        Key("planets", "int", "-", REQUIRED, "number of planets", 1, 32),
        _f("planet_angles_deg", "deg", None, "carrier angle of every planet from planet 1, counter-clockwise (none = "
           "equally spaced)", 0.0, 360.0, hi_open=True, scale=math.pi / 180.0, kind="float_list"),
        _f("support_Nm_per_rad", "N*m/rad", None, "torsional support stiffness of the held port (or "
           "lumped.support_N_per_m)", 0.0, 1e14, lo_open=True),
        _f("damping_ratio", "1", 0.05, "mesh damping ratio zeta of every sun and ring mesh", 0.0, 1.0),
        Key("damping_model", "enum", "-", DEFAULT_DAMPING_MODEL, "per-pair damping law of the meshes "
            "(docs/model.md)", choices=tuple(DAMPING_MODELS)),
        _f("bearing_damping_ratio", "1", 0.02, "damping ratio of the supports and planet bearings: c = 2 zeta "
           "sqrt(k m) of the supported body", 0.0, 1.0),
        _f("pin_error_radial_um", "um", (), "radial position error of every planet's pin (outwards; one per planet, "
           "or none)", -1e4, 1e4, scale=1e-6, kind="float_list"),
        _f("pin_error_tangential_um", "um", (), "tangential position error of every planet's pin "
           "(counter-clockwise; one per planet, or none)", -1e4, 1e4, scale=1e-6, kind="float_list"),
        Key("points_per_mesh", "int", "-", 64, "table points per mesh period", 8, 1024),
        Key("source", "str", "-", "", "where the numbers come from (shown in reports)"),
    ),
    "planetary.bearings": (
        _f("sun_N_per_m", "N/m", 0.0, _BEARING + "sun (0 = a floating sun)", 0.0, 1e14),
        _f("ring_N_per_m", "N/m", REQUIRED, _BEARING + "ring", 0.0, 1e14),
        _f("carrier_N_per_m", "N/m", REQUIRED, _BEARING + "carrier", 0.0, 1e14),
        _f("planet_N_per_m", "N/m", REQUIRED, "radial and tangential stiffness of every planet bearing", 0.0, 1e14,
           lo_open=True),
    ),
    "planetary.gears": (
        _f("module_mm", "mm", REQUIRED, "module of sun, planets and ring", 0.0, 100.0, lo_open=True, scale=1e-3),
        _f("pressure_angle_deg", "deg", 20.0, "reference pressure angle", 10.0, 35.0, scale=math.pi / 180.0),
        _f("face_width_mm", "mm", REQUIRED, "face width", 0.0, 5000.0, lo_open=True, scale=1e-3),
        Key("teeth_sun", "int", "-", REQUIRED, "teeth of the sun", 6, 1000),
        Key("teeth_planet", "int", "-", REQUIRED, "teeth of every planet", 6, 1000),
        Key("teeth_ring", "int", "-", REQUIRED, "teeth of the ring (internal)", 12, 3000),
        _f("profile_shift_sun", "1", 0.0, "profile shift coefficient of the sun", -2.0, 3.0),
        _f("profile_shift_planet", "1", 0.0, "profile shift coefficient of the planets", -2.0, 3.0),
        _f("profile_shift_ring", "1", 0.0, "profile shift coefficient of the ring (ISO 21771 with z_r < 0: "
           "x_p + x_r > 0 shortens the ring mesh's centre distance)", -3.0, 3.0),
        _f("addendum_coefficient", "1", 1.0, "addendum coefficient h_a* of sun and planets", 0.5, 1.5),
        _f("addendum_coefficient_ring", "1", 1.0, "addendum coefficient h_a* of the ring (a shortened ring addendum "
           "avoids interference)", 0.3, 1.5),
        _f("tip_clearance_coefficient", "1", 0.25, "bottom clearance coefficient c* of sun, planets and ring", 0.0,
           0.6),
        _f("carrier_radius_mm", "mm", None, "planet centre radius (none = the sun mesh's zero-backlash centre "
           "distance)", 0.0, 1e5, lo_open=True, scale=1e-3),
        _f("backlash_sun_um", "um", 0.0, "total backlash of every sun-planet mesh along its line of action", 0.0,
           1e4, scale=1e-6),
        _f("backlash_ring_um", "um", 0.0, "total backlash of every planet-ring mesh along its line of action", 0.0,
           1e4, scale=1e-6),
        _f("rim_thickness_mm", "mm", None, "radial thickness of the ring's rim below its tooth roots (none = a "
           "rigid rim)", 0.0, 1e4, lo_open=True, scale=1e-3),
        Key("rim_supports", "int", "-", 6, "equally spaced supports that hold the ring's rim", 2, 360),
    ),
    "planetary.carrier": (
        _f("mass_kg", "kg", REQUIRED, "mass of the carrier (without the planets)", 0.0, 1e6, lo_open=True),
        _f("inertia_kgm2", "kg*m^2", REQUIRED, "inertia of the carrier (without the planets)", 0.0, 1e6,
           lo_open=True),
    ),
    "planetary.ring": (
        _f("mass_kg", "kg", None, "mass of the ring (none = the rim annulus of gears.rim_thickness_mm)", 0.0, 1e6,
           lo_open=True),
        _f("inertia_kgm2", "kg*m^2", None, "inertia of the ring (none = the rim annulus)", 0.0, 1e6, lo_open=True),
    ),
    "planetary.lumped": (
        _f("mass_sun_kg", "kg", REQUIRED, "mass of the sun", 0.0, 1e6, lo_open=True),
        _f("mass_ring_kg", "kg", REQUIRED, "mass of the ring", 0.0, 1e6, lo_open=True),
        _f("mass_carrier_kg", "kg", REQUIRED, "mass of the carrier", 0.0, 1e6, lo_open=True),
        _f("mass_planet_kg", "kg", REQUIRED, "mass of one planet", 0.0, 1e6, lo_open=True),
        _f("inertia_over_r2_sun_kg", "kg", REQUIRED, "I/r^2 of the sun (r its base radius)", 0.0, 1e6,
           lo_open=True),
        _f("inertia_over_r2_ring_kg", "kg", REQUIRED, "I/r^2 of the ring (base radius)", 0.0, 1e6, lo_open=True),
        _f("inertia_over_r2_carrier_kg", "kg", REQUIRED, "I/r^2 of the carrier (r the carrier radius)", 0.0, 1e6,
           lo_open=True),
        _f("inertia_over_r2_planet_kg", "kg", REQUIRED, "I/r^2 of one planet (base radius)", 0.0, 1e6,
           lo_open=True),
        _f("mesh_stiffness_sun_N_per_m", "N/m", REQUIRED, "mean stiffness of every sun-planet mesh", 0.0, 1e14,
           lo_open=True),
        _f("mesh_stiffness_ring_N_per_m", "N/m", REQUIRED, "mean stiffness of every planet-ring mesh", 0.0, 1e14,
           lo_open=True),
        _f("pressure_angle_deg", "deg", REQUIRED, "operating pressure angle of the sun meshes", 0.0, 60.0,
           lo_open=True, scale=math.pi / 180.0),
        _f("pressure_angle_ring_deg", "deg", None, "operating pressure angle of the ring meshes (none = from the "
           "tooth counts and the sun mesh; given: checked)", 0.0, 60.0, lo_open=True, scale=math.pi / 180.0),
        Key("teeth_sun", "int", "-", REQUIRED, "teeth of the sun (kinematics and mesh frequency)", 3, 1000),
        Key("teeth_planet", "int", "-", REQUIRED, "teeth of every planet", 3, 1000),
        Key("teeth_ring", "int", "-", REQUIRED, "teeth of the ring", 6, 3000),
        _f("base_radius_sun_mm", "mm", REQUIRED, "base radius of the sun (the others follow from the tooth counts)",
           0.0, 1e5, lo_open=True, scale=1e-3),
        _f("support_N_per_m", "N/m", None, "torsional support of the held port along u = r theta, as published "
           "(or support_Nm_per_rad)", 0.0, 1e14, lo_open=True),
        _f("contact_ratio_sun", "1", 1.0, "contact ratio of the sun meshes' rectangular-wave stiffness (1 = the "
           "constant published stiffness)", 1.0, 4.0),
        _f("contact_ratio_ring", "1", 1.0, "contact ratio of the ring meshes' rectangular-wave stiffness", 1.0, 4.0),
        _f("backlash_um", "um", 0.0, "total backlash of every mesh along its line of action", 0.0, 1e4, scale=1e-6),
        _f("ring_sun_phase", "1", 0.0, "planet 1's ring-mesh phase against its sun mesh (mesh cycles)", 0.0, 1.0,
           hi_open=True),
    ),
}
#: the sub-tables of a [[planetary]] row
PLANETARY_SUBTABLES = {"planetary": ("bearings", "gears", "carrier", "ring", "lumped")}


@dataclass(frozen=True)
class PlanetarySpec:
    """A [[planetary]] row (SI): name, held port, model, planets; either the geometric set with the
    mechanics geometry does not give (``planetary_set``, ``mechanics``) or the published lumped
    parameters (``lumped``); damping; table points; teeth (sun, planet, ring); the kinematic ratio of
    each free port (port speed / motor speed) and the sun's static torque at the drivetrain's motor
    torque (N*m, the tables' nominal torque) -- filled in by the drivetrain reader."""

    name: str
    held: str
    model: str
    planets: int
    teeth: Tuple[int, int, int]
    planetary_set: Optional[PlanetarySet]
    mechanics: Optional[StageMechanics]
    lumped: Optional[LumpedPlanetary]
    mesh_damping_ratio: float
    damping_model: str
    bearing_damping_ratio: float
    points_per_mesh: int
    source: str
    ratio: Dict[str, float]
    sun_torque_Nm: float = 0.0
    driven_speed_rad_s: Optional[float] = None

    @property
    def form(self) -> str:
        return "geometry" if self.planetary_set is not None else "lumped"

    def port(self, p: str) -> str:
        return f"{self.name}.{p}"

    @property
    def free_ports(self) -> Tuple[str, str]:
        return tuple(p for p in PLANETARY_PORTS if p != self.held)

    @property
    def sun_ring(self) -> Tuple[float, float]:
        """(z_s, z_r): the numbers Willis' equation takes."""
        return float(self.teeth[0]), float(self.teeth[2])


#: field names in the messages of gearfmu.gear.planetary_set / internal / geometry -> scene keys
_FIELDS = [
    (re.compile(r"^planets\b"), "planets"), (re.compile(r"^planet_angles_deg"), "planet_angles_deg"),
    (re.compile(r"^carrier_radius_mm"), "gears.carrier_radius_mm"),
    (re.compile(r"^(ring\.)?profile_shift"), "gears.profile_shift_ring"),
    (re.compile(r"^planet\.profile_shift"), "gears.profile_shift_planet"),
    (re.compile(r"^ring\.addendum_coefficient"), "gears.addendum_coefficient_ring"),
    (re.compile(r"^(planet\.)?addendum_coefficient"), "gears.addendum_coefficient"),
    (re.compile(r"^(ring\.)?teeth"), "gears.teeth_ring"),
    (re.compile(r"^planet_errors"), "pin_error_tangential_um"),
    (re.compile(r"^center_distance_m"), "gears.carrier_radius_mm"),
]


def _field_key(path: str, field: str, reason: str) -> Tuple[str, str]:
    for rx, key in _FIELDS:
        if rx.match(field):
            suffix = field[len("planet_angles_deg"):] if key == "planet_angles_deg" else ""
            return f"{path}.{key}{suffix}", reason
    return f"{path}.gears", f"{field}: {reason}"


def _geometry_key(path: str, exc: Exception) -> Tuple[str, str]:
    """(scene key, reason) of an error of the planetary-set checks raised with where=``path``."""
    msg = str(exc)
    rest = msg[len(path):] if msg.startswith(path) else msg
    m = re.match(r"^ \((sun-planet|planet-ring) mesh\): (.*)$", rest, re.S)
    mesh = ""
    if m:
        mesh, rest = f"{m.group(1)} mesh: ", m.group(2)
    m = re.match(r"^\.?([A-Za-z_][A-Za-z_.\[\]0-9]*): (.*)$", rest, re.S)
    if m:
        key, reason = _field_key(path, m.group(1), m.group(2))
        return key, mesh + reason
    return f"{path}.gears", mesh + rest.lstrip(": ")


def _pin_errors(r: Reader, path: str, v: Dict[str, Any], n: int) -> Tuple[PlanetErrors, ...]:
    er, et = v["pin_error_radial_um"] or (), v["pin_error_tangential_um"] or ()
    for key, vals in (("pin_error_radial_um", er), ("pin_error_tangential_um", et)):
        if vals and len(vals) != n:
            r.add(f"{path}.{key}", f"must have one value per planet ({n}) or be empty, got {len(vals)} values")
            return ()
    if not er and not et:
        return ()
    er = er or (0.0,) * n
    et = et or (0.0,) * n
    return tuple(PlanetErrors(a, b) for a, b in zip(er, et))


def read_planetary(r: Reader, path: str, raw: Dict[str, Any], v: Dict[str, Any]) -> Optional[PlanetarySpec]:
    """A [[planetary]] row (its keys ``v`` already read) with its sub-tables, checked; None when a
    problem was recorded.  ``ratio`` and ``sun_torque_Nm`` are left for the drivetrain reader."""
    n0 = len(r.problems)
    trans = v["model"] == "translational"
    bearings = (r.table(sub(raw, "bearings"), f"{path}.bearings", required=True)
                if trans or sub(raw, "bearings") is not None else {})
    has_g, has_l = sub(raw, "gears") is not None, sub(raw, "lumped") is not None
    if has_g == has_l:
        r.add(path, "give either [planetary.gears] (the geometry) or [planetary.lumped] (published lumped "
                    "parameters)" + ("" if not has_g else ", not both"))
        return None
    n = v["planets"]
    angles = v["planet_angles_deg"]
    if n is not None and angles is not None and len(angles) != n:
        r.add(f"{path}.planet_angles_deg", f"must have one angle per planet ({n}), got {len(angles)}")
    errs = _pin_errors(r, path, v, n) if n is not None else ()
    bear = {k: bearings.get(f"{k}_N_per_m") or 0.0 for k in ("sun", "ring", "carrier", "planet")}
    common = dict(mesh_damping_ratio=v["damping_ratio"], damping_model=v["damping_model"],
                  bearing_damping_ratio=v["bearing_damping_ratio"])
    if has_g:
        g = r.table(sub(raw, "gears"), f"{path}.gears")
        car = r.table(sub(raw, "carrier"), f"{path}.carrier", required=True)
        ring = r.table(sub(raw, "ring"), f"{path}.ring")
        if v["support_Nm_per_rad"] is None:
            r.add(f"{path}.support_Nm_per_rad", "missing: the held port's torsional support (N*m/rad)")
        if len(r.problems) > n0 or n is None:
            return None
        gs = [GearSpec(teeth=g[f"teeth_{k}"], module_m=g["module_mm"], pressure_angle_rad=g["pressure_angle_deg"],
                       face_width_m=g["face_width_mm"], profile_shift=g[f"profile_shift_{k}"],
                       addendum_coefficient=g["addendum_coefficient_ring" if k == "ring" else "addendum_coefficient"],
                       tip_clearance_coefficient=g["tip_clearance_coefficient"])
              for k in ("sun", "planet", "ring")]
        ps = PlanetarySet(gs[0], gs[1], gs[2], n, rim=RingRim(g["rim_thickness_mm"], g["rim_supports"]),
                          planet_angles_rad=angles, carrier_radius_m=g["carrier_radius_mm"],
                          backlash_sun_m=g["backlash_sun_um"], backlash_ring_m=g["backlash_ring_um"], planet_errors=errs)
        try:
            planetary_geometry(ps, where=path)
        except ValueError as exc:
            r.add(*_geometry_key(path, exc))
            return None
        if (ring["mass_kg"] is None) != (ring["inertia_kgm2"] is None):
            r.add(f"{path}.ring", "give both mass_kg and inertia_kgm2, or neither (the rim annulus)")
            return None
        if ring["mass_kg"] is None and g["rim_thickness_mm"] is None:
            r.add(f"{path}.ring", "missing: the ring's mass_kg and inertia_kgm2 (or gears.rim_thickness_mm: the rim "
                                  "annulus gives them)")
            return None
        mech = StageMechanics(carrier_mass_kg=car["mass_kg"], carrier_inertia_kgm2=car["inertia_kgm2"],
                              bearing_N_per_m=bear, support_Nm_per_rad=v["support_Nm_per_rad"], held=v["held"],
                              model=v["model"], ring_mass_kg=ring["mass_kg"], ring_inertia_kgm2=ring["inertia_kgm2"],
                              **common)
        teeth = (g["teeth_sun"], g["teeth_planet"], g["teeth_ring"])
        return PlanetarySpec(v["name"], v["held"], v["model"], n, teeth, ps, mech, None, points_per_mesh=
                             v["points_per_mesh"], source=v["source"], ratio={},
                             driven_speed_rad_s=v["driven_speed_rpm"], **common)
    lp = r.table(sub(raw, "lumped"), f"{path}.lumped")
    if (v["support_Nm_per_rad"] is None) == (lp["support_N_per_m"] is None):
        r.add(f"{path}.lumped.support_N_per_m", "give the held port's torsional support once: lumped.support_N_per_m "
                                                "(along u = r theta) or support_Nm_per_rad")
    if len(r.problems) > n0 or n is None:
        return None
    p = LumpedPlanetary(
        planets=n, mass_kg={k: lp[f"mass_{k}_kg"] for k in ("sun", "ring", "carrier", "planet")},
        inertia_over_r2_kg={k: lp[f"inertia_over_r2_{k}_kg"] for k in ("sun", "ring", "carrier", "planet")},
        mesh_stiffness_sun_N_per_m=lp["mesh_stiffness_sun_N_per_m"],
        mesh_stiffness_ring_N_per_m=lp["mesh_stiffness_ring_N_per_m"], bearing_N_per_m=bear,
        support_N_per_m=lp["support_N_per_m"] or 0.0, pressure_angle_sun_rad=lp["pressure_angle_deg"],
        teeth_sun=lp["teeth_sun"], teeth_planet=lp["teeth_planet"], teeth_ring=lp["teeth_ring"],
        base_radius_sun_m=lp["base_radius_sun_mm"], pressure_angle_ring_rad=lp["pressure_angle_ring_deg"],
        planet_angles_rad=angles, contact_ratio_sun=lp["contact_ratio_sun"], contact_ratio_ring=lp["contact_ratio_ring"],
        backlash_half_m=0.5 * lp["backlash_um"], gamma_rs=lp["ring_sun_phase"], planet_errors=errs,
        points_per_mesh=v["points_per_mesh"], support_Nm_per_rad=v["support_Nm_per_rad"])
    try:   # the lumped set's own checks (cheap: rectangular-wave tables)
        lumped_stage(v["name"], p, held=v["held"], model=v["model"], where=f"{path}.lumped", **common)
    except PlanetaryStageError as exc:
        msg = str(exc)
        key, _, reason = msg.partition(": ")
        r.add(key if key.startswith(path) else f"{path}.lumped", reason if key.startswith(path) else msg)
        return None
    teeth = (lp["teeth_sun"], lp["teeth_planet"], lp["teeth_ring"])
    return PlanetarySpec(v["name"], v["held"], v["model"], n, teeth, None, None, p, points_per_mesh=v["points_per_mesh"],
                         source=v["source"], ratio={}, driven_speed_rad_s=v["driven_speed_rpm"], **common)
