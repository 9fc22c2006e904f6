"""Involute spur- and helical-gear pair geometry (SI units: m, rad).

Helical pairs are reduced to their transverse section (:func:`transverse_equivalent`,
docs/helical.md); everything below then holds in the transverse plane.

Everything the stiffness, error and loaded-mesh modules need about the shape
of an external involute spur gear pair cut by a standard rack (ISO 53 basic
rack with addendum ``ha*`` m, dedendum ``(ha* + c*)`` m):

* radii per gear (suffix 1 = pinion, 2 = gear): pitch ``r``, base ``rb``,
  tip ``ra``, root ``rf``, operating pitch ``rw``;
* operating pressure angle ``alpha_w_rad`` and centre distance;
* the line of action (LOA) measured from the pinion's base-circle tangent
  point N1: meshing-in point A (``s_start_m``), pitch point C
  (``s_pitch_m``), meshing-out point E (``s_end_m``), N1N2 = ``loa_length_m``;
* the contact ratio and the roll lengths of each gear's active profile.

Formulas (textbook involute geometry, e.g. ISO 21771:2007 sections 4-5,
Niemann/Winter "Maschinenelemente II" ch. 21, Litvin & Fuentes "Gear Geometry
and Applied Theory" ch. 10):

* r = m z / 2, rb = r cos(alpha), p_b = pi m cos(alpha)
* inv(alpha_w) = inv(alpha) + 2 tan(alpha) (x1 + x2)/(z1 + z2)
  (zero-backlash meshing equation); a_w = a cos(alpha)/cos(alpha_w), with
  a = m (z1 + z2)/2.  If ``GearPairSpec.center_distance_m`` is given, a_w is
  that value and alpha_w = arccos(a cos(alpha)/a_w).
* rf = r - m (ha* + c* - x)
* ra = r + m (ha* + x - k), k = max(0, (x1 + x2) - (a_w - a)/m) the *tip
  shortening* (ISO 21771 eq. 4.3.2 style "addendum reduction") that keeps the
  standard bottom clearance c* m at the operating centre distance.  CHOICE:
  applied by default (``tip_shortening=True``); He & Yang 2023 Table 1 pair II
  reports tip radii 44.25 / 56.16 mm which are exactly r + m(ha*+x-k) with
  a_w = 91.5 mm (without shortening they would be 44.34 / 56.25 mm).
* LOA: N1N2 = a_w sin(alpha_w); s_E = sqrt(ra1^2 - rb1^2);
  s_A = N1N2 - sqrt(ra2^2 - rb2^2); s_C = rb1 tan(alpha_w);
  contact ratio eps_alpha = (s_E - s_A)/p_b.
* Half tooth angle at radius rho (polar angle between the tooth centre line
  and the flank): psi(rho) = pi/(2z) + 2 x tan(alpha)/z + inv(alpha) -
  inv(alpha_rho), cos(alpha_rho) = rb/rho (no backlash thinning).

Validation raises :class:`GeometryError` (a ``ValueError``) naming the field.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Tuple

import numpy as np

from ..common.vocabulary import HELIX_HANDS
from .gearpair import GearPairSpec, GearSpec


class GeometryError(ValueError):
    """The gear pair is impossible or badly specified (message names the field)."""


def involute(alpha_rad):
    """inv(alpha) = tan(alpha) - alpha (rad -> rad); works on arrays."""
    return np.tan(alpha_rad) - alpha_rad


def inverse_involute(inv_value: float) -> float:
    """alpha (rad) with tan(alpha) - alpha = inv_value (Newton, |err| < 1e-15)."""
    if not (inv_value >= 0.0) or not math.isfinite(inv_value):
        raise GeometryError(f"inverse_involute: involute value {inv_value!r} must be >= 0")
    # Cheng (1992)-style start: alpha ~ (3 inv)^(1/3) for small angles
    a = (3.0 * inv_value) ** (1.0 / 3.0) if inv_value > 0 else 0.0
    a = min(a, 1.5)
    for _ in range(60):
        t = math.tan(a)
        f = t - a - inv_value
        fp = t * t
        if fp == 0.0:
            break
        step = f / fp
        a -= step
        if abs(step) < 1e-16:
            break
    return a


@dataclass(frozen=True)
class PairGeometry:
    """Geometry of a spur gear pair (lengths in m, angles in rad).

    Suffix 1 = pinion, 2 = gear.  LOA positions ``s`` are measured along the
    line of action from the pinion's base-circle tangent point N1 towards N2.
    """

    z1: int
    z2: int
    module_m: float
    alpha_rad: float            # tool (generating) pressure angle
    x1: float
    x2: float
    r1_m: float                 # reference pitch radius m z / 2
    r2_m: float
    rb1_m: float                # base radius
    rb2_m: float
    ra1_m: float                # tip radius (after tip shortening)
    ra2_m: float
    rf1_m: float                # root radius
    rf2_m: float
    rw1_m: float                # operating pitch radius
    rw2_m: float
    alpha_w_rad: float          # operating pressure angle
    center_distance_m: float    # operating centre distance a_w
    reference_center_distance_m: float  # a = m (z1 + z2)/2
    tip_shortening_m: float     # k m, subtracted from both tip radii
    base_pitch_m: float         # p_b = pi m cos(alpha)
    contact_ratio: float        # eps_alpha
    loa_length_m: float         # N1N2
    s_start_m: float            # A, meshing-in (gear tip)
    s_pitch_m: float            # C
    s_end_m: float              # E, meshing-out (pinion tip)
    tip_thickness1_m: float     # normal tooth thickness (chordal arc) at the tip circle
    tip_thickness2_m: float
    mesh_period_rad: float      # 2 pi / z1, pinion angle per mesh
    # ---- helical pairs (docs/helical.md); spur: beta = beta_b = 0, eps_beta = 0.
    # With beta != 0 every field above is of the TRANSVERSE section: module_m = m_t,
    # alpha_rad = alpha_t, x1/x2 = x_n cos(beta) (shift in units of m_t), base_pitch_m = p_bt,
    # contact_ratio = eps_alpha.
    helix_angle_rad: float = 0.0        # reference helix angle beta
    base_helix_angle_rad: float = 0.0   # beta_b, tan(beta_b) = tan(beta) cos(alpha_t)
    normal_module_m: float = 0.0        # m_n (spur: = module_m)
    normal_pressure_angle_rad: float = 0.0  # alpha_n (spur: = alpha_rad)
    face_width_m: float = 0.0           # common face width b = min(b1, b2)
    overlap_ratio: float = 0.0          # eps_beta = b sin(beta)/(pi m_n) = b tan(beta_b)/p_bt

    @property
    def total_contact_ratio(self) -> float:
        """eps_gamma = eps_alpha + eps_beta (spur: the contact ratio)."""
        return self.contact_ratio + self.overlap_ratio

    @property
    def is_helical(self) -> bool:
        return self.helix_angle_rad != 0.0

    # ----------------------------------------------------------- helpers
    @property
    def active_length_m(self) -> float:
        """Length of the path of contact A..E (m) = contact_ratio * p_b."""
        return self.s_end_m - self.s_start_m

    def pinion_radius_at(self, s_m):
        """Pinion radius (m) of the contact point at LOA position s (m from N1)."""
        s = np.asarray(s_m, dtype=float)
        return np.sqrt(self.rb1_m ** 2 + s ** 2)

    def gear_radius_at(self, s_m):
        """Gear radius (m) of the contact point at LOA position s (m from N1)."""
        s = np.asarray(s_m, dtype=float)
        return np.sqrt(self.rb2_m ** 2 + (self.loa_length_m - s) ** 2)

    def pinion_pressure_angle_at(self, s_m):
        """Transverse pressure angle (rad) of the pinion flank at LOA position s."""
        return np.arctan2(np.asarray(s_m, dtype=float), self.rb1_m)

    def gear_pressure_angle_at(self, s_m):
        """Transverse pressure angle (rad) of the gear flank at LOA position s."""
        return np.arctan2(self.loa_length_m - np.asarray(s_m, dtype=float), self.rb2_m)

    def roll_length_at(self, which: int, s_m):
        """Roll length (m) of the contact point on gear ``which`` (1|2).

        The roll length of a flank point is its distance from that gear's
        base-circle tangent point along the LOA: s for the pinion, N1N2 - s for
        the gear.
        """
        s = np.asarray(s_m, dtype=float)
        if which == 1:
            return s
        if which == 2:
            return self.loa_length_m - s
        raise GeometryError(f"which: must be 1 (pinion) or 2 (gear), got {which!r}")

    @property
    def active_roll1_m(self) -> Tuple[float, float]:
        """(start, end) roll length (m) of the pinion's active profile (root -> tip).

        Also the profile evaluation range s_o..s_f of Xu et al. 2022 eq (15) for the
        pinion (CHOICE: evaluation range = active profile, start of active
        profile to tip).
        """
        return (self.s_start_m, self.s_end_m)

    @property
    def active_roll2_m(self) -> Tuple[float, float]:
        """(start, end) roll length (m) of the gear's active profile (root -> tip)."""
        return (self.loa_length_m - self.s_end_m, self.loa_length_m - self.s_start_m)

    def s_from_pinion_angle(self, phi_rad, s0_m: float | None = None):
        """LOA position (m) of a pair that was at ``s0_m`` (default A) at phi = 0.

        A pair's contact point advances rb1 * d(theta1) along the LOA.
        """
        s0 = self.s_start_m if s0_m is None else s0_m
        return s0 + self.rb1_m * np.asarray(phi_rad, dtype=float)

    def pinion_angle_from_s(self, s_m, s0_m: float | None = None):
        """Pinion angle (rad) since the pair passed ``s0_m`` (default A)."""
        s0 = self.s_start_m if s0_m is None else s0_m
        return (np.asarray(s_m, dtype=float) - s0) / self.rb1_m

    def half_tooth_angle(self, which: int, radius_m):
        """psi(rho) (rad): polar half-angle of the tooth of gear ``which`` at radius rho >= rb."""
        z, x, rb = (self.z1, self.x1, self.rb1_m) if which == 1 else (self.z2, self.x2, self.rb2_m)
        rho = np.asarray(radius_m, dtype=float)
        a_r = np.arccos(np.clip(rb / rho, -1.0, 1.0))
        return half_tooth_angle_at_base(z, x, self.alpha_rad) - involute(a_r)

    def gear_values(self, which: int) -> dict:
        """Radii of gear ``which`` as a dict: r, rb, ra, rf, rw, z, x (SI)."""
        if which == 1:
            return dict(r=self.r1_m, rb=self.rb1_m, ra=self.ra1_m, rf=self.rf1_m,
                        rw=self.rw1_m, z=self.z1, x=self.x1)
        if which == 2:
            return dict(r=self.r2_m, rb=self.rb2_m, ra=self.ra2_m, rf=self.rf2_m,
                        rw=self.rw2_m, z=self.z2, x=self.x2)
        raise GeometryError(f"which: must be 1 (pinion) or 2 (gear), got {which!r}")


def half_tooth_angle_at_base(z: int, x: float, alpha_rad: float) -> float:
    """Polar half-angle (rad) of the tooth at the base circle: pi/(2z) + 2 x tan(a)/z + inv(a)."""
    return math.pi / (2.0 * z) + 2.0 * x * math.tan(alpha_rad) / z + float(involute(alpha_rad))


# ---------------------------------------------------------------- validation
def _check_gear(g: GearSpec, name: str) -> None:
    if isinstance(g.teeth, bool) or not isinstance(g.teeth, (int, np.integer)):
        if not (isinstance(g.teeth, float) and g.teeth.is_integer()):
            raise GeometryError(f"{name}.teeth: must be an integer, got {g.teeth!r}")
    if g.teeth <= 0:
        raise GeometryError(f"{name}.teeth: must be positive, got {g.teeth!r}")
    for field, val in (("module_m", g.module_m), ("face_width_m", g.face_width_m)):
        if not (isinstance(val, (int, float, np.floating)) and math.isfinite(val) and val > 0):
            raise GeometryError(f"{name}.{field}: must be a finite positive number, got {val!r}")
    if not (math.isfinite(g.pressure_angle_rad) and 0.0 < g.pressure_angle_rad < math.pi / 3):
        raise GeometryError(f"{name}.pressure_angle_rad: must lie in (0, pi/3), got {g.pressure_angle_rad!r}")
    if not math.isfinite(g.profile_shift):
        raise GeometryError(f"{name}.profile_shift: must be finite, got {g.profile_shift!r}")
    if not (math.isfinite(g.addendum_coefficient) and g.addendum_coefficient > 0):
        raise GeometryError(f"{name}.addendum_coefficient: must be > 0, got {g.addendum_coefficient!r}")
    if not (math.isfinite(g.tip_clearance_coefficient) and g.tip_clearance_coefficient >= 0):
        raise GeometryError(
            f"{name}.tip_clearance_coefficient: must be >= 0, got {g.tip_clearance_coefficient!r}")
    E = g.material.youngs_modulus_Pa
    nu = g.material.poisson_ratio
    if not (math.isfinite(E) and E > 0):
        raise GeometryError(f"{name}.material.youngs_modulus_Pa: must be > 0, got {E!r}")
    if not (math.isfinite(nu) and -1.0 < nu < 0.5):
        raise GeometryError(f"{name}.material.poisson_ratio: must lie in (-1, 0.5), got {nu!r}")


def undercut_limit_radius(z: int, module_m: float, alpha_rad: float, x: float,
                          addendum_coefficient: float) -> float:
    """Radius (m) up to which rack generation removes involute (0 if no undercut).

    The gear is generated by a rack whose straight flank ends ``ha* m`` below
    its datum line (the tool tip radius lies below that).  Undercut exists when
    x < x_min = ha* - z sin^2(alpha)/2 (ISO 21771); the trochoid traced by the
    end point Q of the tool's straight flank then cuts into the involute.
    This function traces that trochoid in the gear frame (exact kinematics of
    rack generation: the rack translates r*phi while the gear turns phi) and
    returns the largest radius at which it lies inside the involute tooth, so
    that a pair may be accepted when its active profile starts above the
    undercut zone ("slight undercut", e.g. He & Yang 2023 pair II's gear, z = 24,
    x = -0.5 < x_min = -0.404).
    """
    r = module_m * z / 2.0
    rb = r * math.cos(alpha_rad)
    d = (addendum_coefficient - x) * module_m      # depth of Q below the rolling line
    if d <= r * math.sin(alpha_rad) ** 2:
        return 0.0
    psi_b = half_tooth_angle_at_base(z, x, alpha_rad)
    psi_r = psi_b - float(involute(alpha_rad))      # half tooth angle at the pitch circle
    xq0 = r * psi_r + d * math.tan(alpha_rad)       # Q at phi = 0 (rolling-line arc ~ r psi_r)
    qy = r - d
    # t = horizontal position of Q relative to the gear centre (rack frame)
    t_max = math.sqrt(max(r * r - qy * qy, 0.0)) + 1e-12
    t = np.linspace(-t_max, t_max, 20001)
    phi = (xq0 - t) / r
    rho = np.sqrt(t * t + qy * qy)
    theta_q = np.arctan2(t, qy) + phi
    ok = rho > rb
    if not np.any(ok):
        return 0.0
    a_rho = np.arccos(np.clip(rb / rho[ok], -1.0, 1.0))
    theta_inv = psi_b - involute(a_rho)
    inside = theta_q[ok] < theta_inv - 1e-12
    if not np.any(inside):
        return 0.0
    return float(np.max(rho[ok][inside]))


def _operating(pair: GearPairSpec):
    p, g = pair.pinion, pair.gear
    alpha = p.pressure_angle_rad
    m = p.module_m
    z1, z2 = int(p.teeth), int(g.teeth)
    a = m * (z1 + z2) / 2.0
    if pair.center_distance_m is None:
        inv_w = float(involute(alpha)) + 2.0 * math.tan(alpha) * (p.profile_shift + g.profile_shift) / (z1 + z2)
        if inv_w <= 0.0:
            raise GeometryError(
                "pinion.profile_shift + gear.profile_shift: too negative, no operating pressure angle "
                f"(inv(alpha_w) = {inv_w:.4g} <= 0)")
        alpha_w = inverse_involute(inv_w)
        a_w = a * math.cos(alpha) / math.cos(alpha_w)
    else:
        a_w = float(pair.center_distance_m)
        if not (math.isfinite(a_w) and a_w > 0):
            raise GeometryError(f"center_distance_m: must be a finite positive number, got {a_w!r}")
        c = a * math.cos(alpha) / a_w
        if c >= 1.0:
            raise GeometryError(
                f"center_distance_m: {a_w:.6g} m is below the base-circle sum a*cos(alpha) = "
                f"{a * math.cos(alpha):.6g} m")
        alpha_w = math.acos(c)
        # operating centre distance must not be below the zero-backlash one
        # (tolerance 1e-3 m: published centre distances are rounded, e.g. He & Yang 2023
        # pair II: 91.5 mm given, 91.50010 mm from the meshing equation)
        inv_w0 = float(involute(alpha)) + 2.0 * math.tan(alpha) * (p.profile_shift + g.profile_shift) / (z1 + z2)
        if inv_w0 > 0:
            a_w0 = a * math.cos(alpha) / math.cos(inverse_involute(inv_w0))
            if a_w < a_w0 - 1e-3 * m:
                raise GeometryError(
                    f"center_distance_m: {a_w:.6g} m is below the zero-backlash centre distance "
                    f"{a_w0:.6g} m for the given profile shifts (teeth would interpenetrate)")
    return a, a_w, alpha_w


#: largest accepted helix angle (ISO 6336-1 method B and the slicing model are meant for beta <= 45 deg)
MAX_HELIX_ANGLE_RAD = math.pi / 4.0


def _check_helix(pair: GearPairSpec) -> float:
    """Validated helix angle beta (rad) of the pair (0 for spur pairs)."""
    p, g = pair.pinion, pair.gear
    for name, gs in (("pinion", p), ("gear", g)):
        b = gs.helix_angle_rad
        if not (isinstance(b, (int, float, np.floating)) and math.isfinite(b)
                and 0.0 <= b <= MAX_HELIX_ANGLE_RAD):
            raise GeometryError(f"{name}.helix_angle_rad: must lie in [0, pi/4] (0 = spur), got {b!r}")
        if gs.helix_hand not in HELIX_HANDS:
            raise GeometryError(f"{name}.helix_hand: must be one of {HELIX_HANDS}, got {gs.helix_hand!r}")
    if abs(p.helix_angle_rad - g.helix_angle_rad) > 1e-12:
        raise GeometryError("gear.helix_angle_rad: must equal pinion.helix_angle_rad "
                            f"({p.helix_angle_rad!r} != {g.helix_angle_rad!r})")
    beta = float(p.helix_angle_rad)
    if beta != 0.0 and p.helix_hand == g.helix_hand:
        raise GeometryError(f"gear.helix_hand: an external helical pair needs opposite hands, both are "
                            f"{p.helix_hand!r}")
    return beta


def transverse_alpha_rad(normal_alpha_rad: float, helix_angle_rad: float) -> float:
    """Transverse pressure angle alpha_t = atan(tan(alpha_n)/cos(beta)) (rad; ISO 21771)."""
    return math.atan(math.tan(normal_alpha_rad) / math.cos(helix_angle_rad))


def base_helix_angle_rad(helix_angle_rad: float, normal_alpha_rad: float) -> float:
    """Base helix angle beta_b (rad): tan(beta_b) = tan(beta) cos(alpha_t) (ISO 21771)."""
    at = transverse_alpha_rad(normal_alpha_rad, helix_angle_rad)
    return math.atan(math.tan(helix_angle_rad) * math.cos(at))


def transverse_equivalent(pair: GearPairSpec) -> GearPairSpec:
    """The spur pair whose tooth is the TRANSVERSE section of the helical pair.

    A helical gear's transverse section is an involute spur profile generated by
    the transverse section of the basic rack: module m_t = m_n/cos(beta),
    pressure angle alpha_t = atan(tan(alpha_n)/cos(beta)); the rack's normal
    heights (h_a* m_n, (h_a* + c*) m_n, shift x m_n) are the same in the
    transverse section (ISO 21771 section 4).  In units of m_t the coefficients
    are therefore h_a* cos(beta), c* cos(beta), x cos(beta) (note x_t tan(alpha_t)
    = x tan(alpha_n), so tooth thickness and inv(alpha_wt) come out exactly as
    in ISO 21771).  A spur pair (beta = 0) is returned unchanged.
    """
    beta = _check_helix(pair)
    if beta == 0.0:
        return pair
    cb = math.cos(beta)

    def tr(gs: GearSpec) -> GearSpec:
        return replace(gs, module_m=gs.module_m / cb,
                       pressure_angle_rad=transverse_alpha_rad(gs.pressure_angle_rad, beta),
                       profile_shift=gs.profile_shift * cb,
                       addendum_coefficient=gs.addendum_coefficient * cb,
                       tip_clearance_coefficient=gs.tip_clearance_coefficient * cb,
                       helix_angle_rad=0.0, helix_hand="right")

    return replace(pair, pinion=tr(pair.pinion), gear=tr(pair.gear))


def pair_geometry(pair: GearPairSpec, *, tip_shortening: bool = True) -> PairGeometry:
    """Geometry of a spur or helical gear pair (see module docstring for the formulas).

    Helical pairs (``GearSpec.helix_angle_rad`` != 0, normal-section input, see
    :class:`gearfmu.gear.gearpair.GearSpec`): the transverse section is the spur pair
    of :func:`transverse_equivalent`; the result adds beta, beta_b, m_n, alpha_n,
    the face width and the overlap ratio eps_beta = b sin(beta)/(pi m_n)
    (ISO 21771; Niemann/Winter ch. 21).  CHOICE: the transverse contact ratio
    must still be >= 1 (the check of the spur pair), which is stricter than
    eps_gamma >= 1.

    Raises :class:`GeometryError` naming the field for bad input and for
    impossible gears: non-positive / non-integer teeth, non-positive module or
    face width, different module or pressure angle on the two gears,
    undercut reaching into the active profile, pointed tip (tip thickness
    <= 0), involute interference (A before N1 or E beyond N2), contact ratio
    < 1, hub radius >= root radius.
    """
    beta = _check_helix(pair)
    if beta != 0.0:
        _check_gear(pair.pinion, "pinion")
        _check_gear(pair.gear, "gear")
        tg = pair_geometry(transverse_equivalent(pair), tip_shortening=tip_shortening)
        b = float(min(pair.pinion.face_width_m, pair.gear.face_width_m))
        mn = float(pair.pinion.module_m)
        return replace(tg, helix_angle_rad=beta,
                       base_helix_angle_rad=base_helix_angle_rad(beta, float(pair.pinion.pressure_angle_rad)),
                       normal_module_m=mn, normal_pressure_angle_rad=float(pair.pinion.pressure_angle_rad),
                       face_width_m=b, overlap_ratio=b * math.sin(beta) / (math.pi * mn))
    p, g = pair.pinion, pair.gear
    _check_gear(p, "pinion")
    _check_gear(g, "gear")
    if abs(p.module_m - g.module_m) > 1e-12 * p.module_m:
        raise GeometryError(f"gear.module_m: must equal pinion.module_m ({p.module_m} != {g.module_m})")
    if abs(p.pressure_angle_rad - g.pressure_angle_rad) > 1e-12:
        raise GeometryError("gear.pressure_angle_rad: must equal pinion.pressure_angle_rad")
    if not (math.isfinite(pair.backlash_m) and pair.backlash_m >= 0):
        raise GeometryError(f"backlash_m: must be finite and >= 0, got {pair.backlash_m!r}")

    m = float(p.module_m)
    alpha = float(p.pressure_angle_rad)
    z1, z2 = int(p.teeth), int(g.teeth)
    x1, x2 = float(p.profile_shift), float(g.profile_shift)
    a, a_w, alpha_w = _operating(pair)

    r1, r2 = m * z1 / 2.0, m * z2 / 2.0
    rb1, rb2 = r1 * math.cos(alpha), r2 * math.cos(alpha)
    y = (a_w - a) / m
    k = max(0.0, (x1 + x2) - y) if tip_shortening else 0.0
    ra1 = r1 + m * (p.addendum_coefficient + x1 - k)
    ra2 = r2 + m * (g.addendum_coefficient + x2 - k)
    rf1 = r1 - m * (p.addendum_coefficient + p.tip_clearance_coefficient - x1)
    rf2 = r2 - m * (g.addendum_coefficient + g.tip_clearance_coefficient - x2)
    rw1 = a_w * z1 / (z1 + z2)
    rw2 = a_w * z2 / (z1 + z2)
    pb = math.pi * m * math.cos(alpha)

    for name, gs, rf in (("pinion", p, rf1), ("gear", g, rf2)):
        if rf <= 0:
            raise GeometryError(f"{name}.profile_shift: root radius {rf:.4g} m <= 0")
        if gs.hub_radius_m is not None:
            h = gs.hub_radius_m
            if not (math.isfinite(h) and h > 0):
                raise GeometryError(f"{name}.hub_radius_m: must be a finite positive number, got {h!r}")
            if h >= rf:
                raise GeometryError(
                    f"{name}.hub_radius_m: {h:.6g} m must be below the root radius {rf:.6g} m")

    # pointed tip: tooth thickness at the tip circle
    def tip_thickness(z, x, rb, ra):
        a_a = math.acos(rb / ra)
        return 2.0 * ra * (half_tooth_angle_at_base(z, x, alpha) - float(involute(a_a)))

    sa1 = tip_thickness(z1, x1, rb1, ra1)
    sa2 = tip_thickness(z2, x2, rb2, ra2)
    for name, sa in (("pinion", sa1), ("gear", sa2)):
        if sa <= 0:
            raise GeometryError(
                f"{name}.profile_shift: pointed tooth, tip thickness {sa * 1e3:.4g} mm <= 0 "
                "(reduce the profile shift or the addendum coefficient)")

    L = a_w * math.sin(alpha_w)
    sE = math.sqrt(ra1 ** 2 - rb1 ** 2)
    sA = L - math.sqrt(ra2 ** 2 - rb2 ** 2)
    sC = rb1 * math.tan(alpha_w)
    # undercut by the generating rack: must not reach the active profile
    for name, gs, z, x, s_act_start, rb in (
            ("pinion", p, z1, x1, sA, rb1), ("gear", g, z2, x2, L - sE, rb2)):
        x_min = gs.addendum_coefficient - z * math.sin(alpha) ** 2 / 2.0
        if x < x_min:
            r_u = undercut_limit_radius(z, m, alpha, x, gs.addendum_coefficient)
            r_act = math.sqrt(rb ** 2 + s_act_start ** 2)
            if s_act_start < 0 or r_u >= r_act:
                raise GeometryError(
                    f"{name}.profile_shift: undercut, x = {x:.4g} < x_min = {x_min:.4g} "
                    f"(ha* - z sin^2(alpha)/2) and the undercut reaches radius {r_u * 1e3:.4g} mm, "
                    f"above the start of the active profile at {r_act * 1e3:.4g} mm")
    if sA < 0:
        raise GeometryError(
            f"gear.addendum_coefficient: involute interference, the gear tip passes the pinion's base tangent point N1 "
            f"(meshing-in s_A = {sA * 1e3:.4g} mm < 0); the pinion root would be cut (undercut by the mate)")
    if sE > L:
        raise GeometryError(
            f"pinion.addendum_coefficient: involute interference, the pinion tip passes the gear's base tangent point N2 "
            f"(meshing-out s_E = {sE * 1e3:.4g} mm > N1N2 = {L * 1e3:.4g} mm)")
    # root (form-circle) interference: a rack-cut involute exists only above the roll length
    # s_form = r sin(alpha) - (ha* - x) m / sin(alpha) (where the tool's straight flank ends);
    # the mate's tip must not push contact below it (ISO 21771 "form diameter" check).
    for name, gs, r, x, s_act_start in (
            ("pinion", p, r1, x1, sA), ("gear", g, r2, x2, L - sE)):
        s_form = r * math.sin(alpha) - (gs.addendum_coefficient - x) * m / math.sin(alpha)
        if s_form > 0 and s_act_start < s_form * (1.0 - 1e-9):
            raise GeometryError(
                f"{name}.profile_shift: root interference, contact starts at roll length "
                f"{s_act_start * 1e3:.4g} mm below the generated involute (form circle roll length "
                f"{s_form * 1e3:.4g} mm); increase the shift or shorten the mating tip")
    eps = (sE - sA) / pb
    if eps < 1.0:
        raise GeometryError(f"pinion.addendum_coefficient: contact ratio {eps:.4f} < 1 "
                            "(the mesh would lose contact between tooth pairs)")

    return PairGeometry(
        z1=z1, z2=z2, module_m=m, alpha_rad=alpha, x1=x1, x2=x2,
        r1_m=r1, r2_m=r2, rb1_m=rb1, rb2_m=rb2, ra1_m=ra1, ra2_m=ra2, rf1_m=rf1, rf2_m=rf2,
        rw1_m=rw1, rw2_m=rw2, alpha_w_rad=alpha_w, center_distance_m=a_w,
        reference_center_distance_m=a, tip_shortening_m=k * m, base_pitch_m=pb,
        contact_ratio=eps, loa_length_m=L, s_start_m=sA, s_pitch_m=sC, s_end_m=sE,
        tip_thickness1_m=sa1, tip_thickness2_m=sa2, mesh_period_rad=2.0 * math.pi / z1,
        normal_module_m=m, normal_pressure_angle_rad=alpha,
        face_width_m=float(min(p.face_width_m, g.face_width_m)),
    )
