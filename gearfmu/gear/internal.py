"""Internal (ring) gears and the planet-ring mesh: involute geometry and its checks (SI: m, rad).

A ring gear is described by a :class:`gearfmu.gear.gearpair.GearSpec` (teeth, module, pressure
angle, face width, profile shift, addendum and tip-clearance coefficients, material) and a
:class:`RingRim` (rim thickness below the tooth roots and the number of supports that hold it).
Its mate is an external planet (pinion).  Index 1 is the planet, index 2 the ring, as in
:class:`gearfmu.gear.geometry.PairGeometry`, whose interface :class:`InternalPairGeometry`
repeats where the tooth-compliance and meshing-error functions read it.

Sign convention of the ring's profile shift (ISO 21771:2007 with a negative tooth number, the
internal gear written as z2 < 0): a positive shift x2 moves the ring's profile towards the gear
axis, so that

* tooth thickness at the reference circle s2 = m (pi/2 + 2 x2 tan(alpha)), as for external gears;
* tip (inner) radius  ra2 = r2 - m (ha* + x2);  root (outer) radius  rf2 = r2 + m (ha* + c* - x2);
* half tooth angle at radius rho >= rb2 (the internal tooth widens outwards):
  psi2(rho) = pi/(2 z2) + 2 x2 tan(alpha)/z2 - inv(alpha) + inv(alpha_rho), cos(alpha_rho) = rb2/rho.

Operating mesh (ISO 21771 with z2 < 0; Niemann/Winter "Maschinenelemente II" ch. 21.6):

* reference centre distance a = m (z2 - z1)/2;
* inv(alpha_w) = inv(alpha) - 2 tan(alpha) (x1 + x2)/(z2 - z1) (both shifts positive pull the
  planet towards the ring axis); a_w = a cos(alpha)/cos(alpha_w); a given centre distance must
  not exceed the zero-backlash one (an internal mesh tightens as the planet moves outwards);
* the line of action is tangent to both base circles on the same side; N1 (planet) and N2 (ring)
  lie N1N2 = a_w sin(alpha_w) apart and the contact point P lies beyond N1: its planet roll
  length is s = |P N1| and its ring roll length s + N1N2.  LOA positions ``s`` are measured from
  N1 away from N2, so that a pair runs from s_A to s_E as the planet (driving) turns forward:
  s_A = sqrt(ra2^2 - rb2^2) - N1N2 (the ring tip), s_E = sqrt(ra1^2 - rb1^2) (the planet tip);
* contact ratio eps = (s_E - s_A)/p_b.

Checks (each a :class:`InternalGearError` naming the field and the reason):

* the ring's tip circle must lie outside its base circle (an involute exists only there);
* pointed teeth (tip thickness <= 0) of planet and ring, and a ring tooth space that closes at
  the root circle;
* involute interference: s_A >= 0, written as KHK's z1/z2 >= 1 - tan(alpha_a2)/tan(alpha_w)
  (the ring tip would dig into the planet's root below its base circle), and contact must start
  above the planet's generated involute (form circle of the rack-cut planet);
* the planet tip must not reach the ring's root circle along the line of action (s_E + N1N2 <=
  sqrt(rf2^2 - rb2^2): the ring's involute ends at its root, CHOICE: no fillet below it);
* trochoid (tip) interference of internal gears, the tips meeting outside the path of contact
  as the planet tooth leaves the ring space (KHK Co. Ltd., *Gear Technical Reference*, "Internal
  gears", the condition theta1 z1/z2 + inv(alpha_w) - inv(alpha_a2) - theta2 >= 0 with
  theta1 = acos((ra2^2 - ra1^2 - a_w^2)/(2 a_w ra1)) + inv(alpha_a1) - inv(alpha_w),
  theta2 = acos((a_w^2 + ra2^2 - ra1^2)/(2 a_w ra2)));
* tip clearance: ring root to planet tip rf2 - (a_w + ra1) > 0 and ring tip to planet root
  ra2 - (a_w + rf1) > 0 on the line of centres;
* contact ratio >= 1.

CHOICE: no tip shortening on internal pairs (the external pair's k of gearfmu.gear.geometry
keeps the bottom clearance of profile-shifted external pairs; the clearances above are checked
instead).  Spur gears only (a helical planetary needs axial degrees of freedom the planar
planetary model does not have).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional, Tuple

import numpy as np

from .gearpair import GearSpec
from .geometry import GeometryError, half_tooth_angle_at_base, inverse_involute, involute, _check_gear

__all__ = ["InternalGearError", "RingRim", "InternalPairGeometry", "internal_pair_geometry",
           "ring_half_tooth_angle_rad", "trochoid_interference_margin_rad"]


class InternalGearError(GeometryError):
    """An impossible or badly specified internal gear pair (message names the field)."""


@dataclass(frozen=True)
class RingRim:
    """The ring gear's rim below its tooth roots: radial thickness (m; None = a rigid rim, no rim
    compliance) and the number of equally spaced supports (pins, bolts or splines) that hold it
    against the housing (gearfmu.gear.internal_stiffness models the rim between two supports as a
    clamped curved beam)."""

    thickness_m: Optional[float] = None
    supports: int = 6


def ring_half_tooth_angle_rad(z: int, x: float, alpha_rad: float, radius_m, rb_m: float):
    """Half tooth angle psi2(rho) (rad) of an internal gear at radius rho >= rb (module docstring):
    pi/(2z) + 2 x tan(alpha)/z - inv(alpha) + inv(alpha_rho)."""
    rho = np.asarray(radius_m, dtype=float)
    a_r = np.arccos(np.clip(rb_m / rho, -1.0, 1.0))
    return math.pi / (2.0 * z) + 2.0 * x * math.tan(alpha_rad) / z - float(involute(alpha_rad)) + involute(a_r)


@dataclass(frozen=True)
class InternalPairGeometry:
    """Geometry of a planet (1) in mesh with a ring (2), lengths in m, angles in rad.  Field names
    follow :class:`gearfmu.gear.geometry.PairGeometry`; LOA positions ``s`` are measured from N1
    away from N2 (module docstring)."""

    z1: int
    z2: int
    module_m: float
    alpha_rad: float
    x1: float
    x2: float
    r1_m: float
    r2_m: float
    rb1_m: float
    rb2_m: float
    ra1_m: float
    ra2_m: float
    rf1_m: float
    rf2_m: float
    rw1_m: float
    rw2_m: float
    alpha_w_rad: float
    center_distance_m: float
    reference_center_distance_m: float
    base_pitch_m: float
    contact_ratio: float
    loa_length_m: float          # N1N2
    s_start_m: float             # A: the ring tip
    s_pitch_m: float             # C: rb1 tan(alpha_w)
    s_end_m: float               # E: the planet tip
    tip_thickness1_m: float
    tip_thickness2_m: float
    mesh_period_rad: float       # 2 pi / z1 (planet angle per mesh)
    face_width_m: float
    tip_clearance_root2_m: float     # rf2 - (a_w + ra1)
    tip_clearance_root1_m: float     # ra2 - (a_w + rf1)
    trochoid_margin_rad: float       # >= 0: no tip interference (KHK)
    helix_angle_rad: float = 0.0
    base_helix_angle_rad: float = 0.0
    overlap_ratio: float = 0.0

    internal = True

    @property
    def total_contact_ratio(self) -> float:
        return self.contact_ratio

    @property
    def is_helical(self) -> bool:
        return False

    @property
    def normal_module_m(self) -> float:
        return self.module_m

    @property
    def active_length_m(self) -> float:
        return self.s_end_m - self.s_start_m

    def roll_length_at(self, which: int, s_m):
        """Roll length (m) of the contact point at LOA position s on gear ``which``: s on the planet
        (1), s + N1N2 on the ring (2)."""
        s = np.asarray(s_m, dtype=float)
        if which == 1:
            return s
        if which == 2:
            return s + self.loa_length_m
        raise InternalGearError(f"which: must be 1 (planet) or 2 (ring), got {which!r}")

    def pinion_radius_at(self, s_m):
        return np.sqrt(self.rb1_m ** 2 + np.asarray(s_m, dtype=float) ** 2)

    def gear_radius_at(self, s_m):
        return np.sqrt(self.rb2_m ** 2 + (np.asarray(s_m, dtype=float) + self.loa_length_m) ** 2)

    def gear_values(self, which: int) -> dict:
        """Radii of gear ``which`` as a dict: r, rb, ra, rf, rw, z, x (SI); the ring's ra is its
        inner (tip) radius, rf its outer (root) radius."""
        if which == 1:
            return dict(r=self.r1_m, rb=self.rb1_m, ra=self.ra1_m, rf=self.rf1_m, rw=self.rw1_m, z=self.z1, x=self.x1)
        if which == 2:
            return dict(r=self.r2_m, rb=self.rb2_m, ra=self.ra2_m, rf=self.rf2_m, rw=self.rw2_m, z=self.z2, x=self.x2)
        raise InternalGearError(f"which: must be 1 (planet) or 2 (ring), got {which!r}")

    def half_tooth_angle(self, which: int, radius_m):
        """Half tooth angle (rad) of gear ``which`` at radius rho >= rb (the ring's widens outwards)."""
        if which == 1:
            rho = np.asarray(radius_m, dtype=float)
            a_r = np.arccos(np.clip(self.rb1_m / rho, -1.0, 1.0))
            return half_tooth_angle_at_base(self.z1, self.x1, self.alpha_rad) - involute(a_r)
        return ring_half_tooth_angle_rad(self.z2, self.x2, self.alpha_rad, radius_m, self.rb2_m)


def trochoid_interference_margin_rad(z1: int, z2: int, ra1: float, ra2: float, a_w: float, alpha_w: float,
                                     rb2: float) -> float:
    """theta1 z1/z2 + inv(alpha_w) - inv(alpha_a2) - theta2 (rad) of KHK's trochoid-interference
    condition for internal gears (module docstring); >= 0: the tips clear.  When the tip circles do
    not intersect (the planet tip never reaches the ring tip circle) the margin is +inf.  ``rb2``:
    the ring's base radius; the planet's base radius follows from the operating pitch radii,
    rb1 = rb2 z1/z2."""
    c1 = (ra2 ** 2 - ra1 ** 2 - a_w ** 2) / (2.0 * a_w * ra1)
    c2 = (a_w ** 2 + ra2 ** 2 - ra1 ** 2) / (2.0 * a_w * ra2)
    if not (-1.0 <= c1 <= 1.0 and -1.0 <= c2 <= 1.0):
        return math.inf
    rb1 = rb2 * z1 / z2
    a_a1 = math.acos(min(rb1 / ra1, 1.0))
    th1 = math.acos(c1) + float(involute(a_a1)) - float(involute(alpha_w))
    th2 = math.acos(c2)
    a_a2 = math.acos(min(rb2 / ra2, 1.0))
    return th1 * z1 / z2 + float(involute(alpha_w)) - float(involute(a_a2)) - th2


#: a given centre distance may exceed the zero-backlash one of the internal mesh by this many modules (published
#: shifts and centre distances are rounded; the external pair accepts 1e-3 modules the other way)
CENTER_DISTANCE_TOLERANCE_MODULES = 0.01


def _operating(planet: GearSpec, ring: GearSpec, center_distance_m: Optional[float]) -> Tuple[float, float, float]:
    m, alpha = float(planet.module_m), float(planet.pressure_angle_rad)
    z1, z2 = int(planet.teeth), int(ring.teeth)
    a = m * (z2 - z1) / 2.0
    inv_w = float(involute(alpha)) - 2.0 * math.tan(alpha) * (planet.profile_shift + ring.profile_shift) / (z2 - z1)
    if inv_w <= 0.0:
        raise InternalGearError(
            "planet.profile_shift + ring.profile_shift: too large, no operating pressure angle of the internal "
            f"mesh (inv(alpha_w) = {inv_w:.4g} <= 0)")
    alpha_w0 = inverse_involute(inv_w)
    a_w0 = a * math.cos(alpha) / math.cos(alpha_w0)
    if center_distance_m is None:
        return a, a_w0, alpha_w0
    a_w = float(center_distance_m)
    if not (math.isfinite(a_w) and a_w > 0):
        raise InternalGearError(f"center_distance_m: must be a finite positive length, got {a_w!r}")
    c = a * math.cos(alpha) / a_w
    if not c < 1.0:
        raise InternalGearError(f"center_distance_m: {a_w:.6g} m is below the base-radius difference "
                                f"{a * math.cos(alpha):.6g} m of the internal mesh")
    if a_w > a_w0 + CENTER_DISTANCE_TOLERANCE_MODULES * m:
        raise InternalGearError(
            f"center_distance_m: {a_w * 1e3:.6g} mm exceeds the zero-backlash centre distance {a_w0 * 1e3:.6g} mm "
            "of the planet-ring mesh for these profile shifts (the planet teeth would cut into the ring teeth)")
    return a, a_w, math.acos(c)


def internal_pair_geometry(planet: GearSpec, ring: GearSpec, center_distance_m: Optional[float] = None,
                           *, planet_tip_radius_m: Optional[float] = None, where: str = "ring") -> InternalPairGeometry:
    """Geometry of a planet in mesh with a ring (module docstring for the formulas and the checks).
    ``center_distance_m`` None: the zero-backlash operating centre distance (a given one may exceed it
    by :data:`CENTER_DISTANCE_TOLERANCE_MODULES` modules: rounded published data; it is then used as
    given).  ``planet_tip_radius_m``: the planet's tip radius when it is set elsewhere (the tip
    shortening of its sun mesh, gearfmu.gear.geometry); None: r1 + m (ha* + x1).  ``where`` prefixes
    the ring's field names in messages (e.g. ``planetary[0].ring``)."""
    _check_gear(planet, "planet")
    _check_gear(ring, where)
    for name, g in (("planet", planet), (where, ring)):
        if g.helix_angle_rad != 0.0:
            raise InternalGearError(f"{name}.helix_angle_rad: planetary stages are spur only (got "
                                    f"{math.degrees(g.helix_angle_rad):.4g} deg)")
    if not int(ring.teeth) > int(planet.teeth):
        raise InternalGearError(f"{where}.teeth: the ring needs more teeth than the planet ({int(ring.teeth)} <= "
                                f"{int(planet.teeth)})")
    if abs(planet.module_m - ring.module_m) > 1e-12 * planet.module_m:
        raise InternalGearError(f"{where}.module_m: must equal the planet's module ({ring.module_m!r} != "
                                f"{planet.module_m!r})")
    if abs(planet.pressure_angle_rad - ring.pressure_angle_rad) > 1e-12:
        raise InternalGearError(f"{where}.pressure_angle_rad: must equal the planet's pressure angle")
    m, alpha = float(planet.module_m), float(planet.pressure_angle_rad)
    z1, z2 = int(planet.teeth), int(ring.teeth)
    x1, x2 = float(planet.profile_shift), float(ring.profile_shift)
    a, a_w, alpha_w = _operating(planet, ring, center_distance_m)
    r1, r2 = m * z1 / 2.0, m * z2 / 2.0
    rb1, rb2 = r1 * math.cos(alpha), r2 * math.cos(alpha)
    ra1 = r1 + m * (planet.addendum_coefficient + x1) if planet_tip_radius_m is None else float(planet_tip_radius_m)
    rf1 = r1 - m * (planet.addendum_coefficient + planet.tip_clearance_coefficient - x1)
    ra2 = r2 - m * (ring.addendum_coefficient + x2)
    rf2 = r2 + m * (ring.addendum_coefficient + ring.tip_clearance_coefficient - x2)
    pb = math.pi * m * math.cos(alpha)
    if rf1 <= 0:
        raise InternalGearError(f"planet.profile_shift: root radius {rf1:.4g} m <= 0")
    if not ra2 > rb2:
        raise InternalGearError(
            f"{where}.addendum_coefficient: the ring's tip circle ({ra2 * 1e3:.6g} mm) lies inside its base circle "
            f"({rb2 * 1e3:.6g} mm): an internal involute exists only outside the base circle (reduce the addendum "
            "or the profile shift of the ring)")
    # pointed teeth and the ring's tooth space at its root
    sa1 = 2.0 * ra1 * (half_tooth_angle_at_base(z1, x1, alpha) - float(involute(math.acos(rb1 / ra1))))
    psi_a2 = float(ring_half_tooth_angle_rad(z2, x2, alpha, ra2, rb2))
    psi_f2 = float(ring_half_tooth_angle_rad(z2, x2, alpha, rf2, rb2))
    sa2 = 2.0 * ra2 * psi_a2
    if sa1 <= 0:
        raise InternalGearError(f"planet.profile_shift: pointed tooth, tip thickness {sa1 * 1e3:.4g} mm <= 0")
    if sa2 <= 0:
        raise InternalGearError(f"{where}.profile_shift: pointed ring tooth, tip thickness {sa2 * 1e3:.4g} mm <= 0 "
                                "(reduce the ring's profile shift or addendum)")
    if not psi_f2 < math.pi / z2:
        raise InternalGearError(f"{where}.profile_shift: the ring's teeth meet at its root circle (no tooth space "
                                "left): reduce the profile shift or the dedendum of the ring")
    L = a_w * math.sin(alpha_w)
    sA = math.sqrt(ra2 ** 2 - rb2 ** 2) - L
    sE = math.sqrt(ra1 ** 2 - rb1 ** 2)
    sC = rb1 * math.tan(alpha_w)
    a_a2 = math.acos(rb2 / ra2)
    if sA < 0:
        raise InternalGearError(
            f"{where}.addendum_coefficient: involute interference of the internal mesh, z1/z2 = {z1 / z2:.4g} < "
            f"1 - tan(alpha_a2)/tan(alpha_w) = {1.0 - math.tan(a_a2) / math.tan(alpha_w):.4g}: the ring tip "
            f"reaches below the planet's base circle (s_A = {sA * 1e3:.4g} mm < 0)")
    s_form = r1 * math.sin(alpha) - (planet.addendum_coefficient - x1) * m / math.sin(alpha)
    if s_form > 0 and sA < s_form * (1.0 - 1e-9):
        raise InternalGearError(
            f"{where}.addendum_coefficient: root interference, the ring tip meets the planet at roll length "
            f"{sA * 1e3:.4g} mm, below its generated involute (form circle roll length {s_form * 1e3:.4g} mm); "
            "shorten the ring's addendum or shift the planet")
    u_root2 = math.sqrt(rf2 ** 2 - rb2 ** 2)
    if sE + L > u_root2 * (1.0 + 1e-12):
        raise InternalGearError(
            f"planet.addendum_coefficient: the planet tip reaches beyond the ring's root circle along the line of "
            f"action (ring roll {(sE + L) * 1e3:.4g} mm > {u_root2 * 1e3:.4g} mm)")
    c_root2 = rf2 - (a_w + ra1)
    c_root1 = ra2 - (a_w + rf1)
    if c_root2 <= 0:
        raise InternalGearError(f"planet.addendum_coefficient: no tip clearance between the planet tip and the ring "
                                f"root ({c_root2 * 1e3:.4g} mm)")
    if c_root1 <= 0:
        raise InternalGearError(f"{where}.addendum_coefficient: no tip clearance between the ring tip and the planet "
                                f"root ({c_root1 * 1e3:.4g} mm)")
    margin = trochoid_interference_margin_rad(z1, z2, ra1, ra2, a_w, alpha_w, rb2)
    if margin < 0:
        raise InternalGearError(
            f"{where}.teeth: trochoid (tip) interference of the internal mesh, theta1 z1/z2 + inv(alpha_w) - "
            f"inv(alpha_a2) - theta2 = {margin:.4g} rad < 0: the planet tip hits the ring tip as it leaves the ring "
            f"space (z2 - z1 = {z2 - z1} is too small for these addenda; more ring teeth, a shorter ring addendum "
            "or a positive shift of the ring help)")
    eps = (sE - sA) / pb
    if eps < 1.0:
        raise InternalGearError(f"{where}.addendum_coefficient: contact ratio {eps:.4f} < 1 of the planet-ring mesh")
    return InternalPairGeometry(
        z1=z1, z2=z2, module_m=m, alpha_rad=alpha, x1=x1, x2=x2, r1_m=r1, r2_m=r2, rb1_m=rb1, rb2_m=rb2,
        ra1_m=ra1, ra2_m=ra2, rf1_m=rf1, rf2_m=rf2, rw1_m=a_w * z1 / (z2 - z1), rw2_m=a_w * z2 / (z2 - z1),
        alpha_w_rad=alpha_w, center_distance_m=a_w, reference_center_distance_m=a, base_pitch_m=pb,
        contact_ratio=eps, loa_length_m=L, s_start_m=sA, s_pitch_m=sC, s_end_m=sE, tip_thickness1_m=sa1,
        tip_thickness2_m=sa2, mesh_period_rad=2.0 * math.pi / z1,
        face_width_m=float(min(planet.face_width_m, ring.face_width_m)), tip_clearance_root2_m=c_root2,
        tip_clearance_root1_m=c_root1, trochoid_margin_rad=margin)
