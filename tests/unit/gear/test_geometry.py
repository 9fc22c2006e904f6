"""Involute pair geometry against hand calculations and published tables.

References (none produced by this code):
* textbook involute formulas (ISO 21771; Niemann/Winter) evaluated by hand
  below with ``math`` only;
* seed 004 (He & Yang, Mechanika) Table 1: radii and centre distance of gear
  pairs I and II, published to 0.01 mm;
* seed 003 (Xu et al. 2022) Table 1: base / outer diameter and contact ratio
  1.7547 of the Kahraman & Blankenship 50/50 pair.
"""
import math

import numpy as np
import pytest

from gearfmu.gear.gearpair import GearPairSpec, GearSpec
from gearfmu.gear.geometry import (GeometryError, inverse_involute, involute, pair_geometry,
                              undercut_limit_radius)

DEG20 = math.radians(20.0)


def spur_pair(z1, z2, m, x1=0.0, x2=0.0, b=0.02, cd=None, ha=1.0, c=0.25, hub1=None, hub2=None):
    return GearPairSpec(
        pinion=GearSpec(z1, m, DEG20, b, x1, ha, c, hub1),
        gear=GearSpec(z2, m, DEG20, b, x2, ha, c, hub2),
        center_distance_m=cd)


def test_standard_pair_hand_calculation():
    # Hand calculation, 20/40 teeth, m = 5 mm, alpha = 20 deg, x = 0:
    #   r1 = 5*20/2 = 50 mm, r2 = 100 mm; rb = r cos 20 = 46.98463 / 93.96926 mm
    #   ra = r + m = 55 / 105 mm; rf = r - 1.25 m = 43.75 / 93.75 mm; a = 150 mm
    #   x1 + x2 = 0  ->  alpha_w = alpha, a_w = a
    #   p_b = pi * 5 * cos 20 = 14.76066 mm
    #   eps = (sqrt(55^2 - 46.98463^2) + sqrt(105^2 - 93.96926^2) - 150 sin 20) / p_b
    #       = (28.59098 + 46.84846 - 51.30302) / 14.76066 = 1.63519
    g = pair_geometry(spur_pair(20, 40, 5e-3))
    mm = 1e-3
    assert g.r1_m == pytest.approx(50 * mm, rel=1e-12)
    assert g.r2_m == pytest.approx(100 * mm, rel=1e-12)
    assert g.rb1_m == pytest.approx(46.98463 * mm, abs=1e-8)
    assert g.rb2_m == pytest.approx(93.96926 * mm, abs=1e-8)
    assert g.ra1_m == pytest.approx(55 * mm, rel=1e-12)
    assert g.ra2_m == pytest.approx(105 * mm, rel=1e-12)
    assert g.rf1_m == pytest.approx(43.75 * mm, rel=1e-12)
    assert g.rf2_m == pytest.approx(93.75 * mm, rel=1e-12)
    assert g.center_distance_m == pytest.approx(150 * mm, rel=1e-12)
    assert g.alpha_w_rad == pytest.approx(DEG20, abs=1e-12)
    assert g.base_pitch_m == pytest.approx(14.76066 * mm, abs=1e-8)
    assert g.contact_ratio == pytest.approx(1.63519, abs=2e-5)
    # LOA: N1N2 = a sin 20 = 51.30302; E = 28.59098; A = 51.30302 - 46.84846 = 4.45456;
    # C = rb1 tan 20 = r1 sin 20 = 17.10101 mm
    assert g.loa_length_m == pytest.approx(51.30302 * mm, abs=1e-8)
    assert g.s_end_m == pytest.approx(28.59098 * mm, abs=1e-8)
    assert g.s_start_m == pytest.approx(4.45456 * mm, abs=1e-8)
    assert g.s_pitch_m == pytest.approx(17.10101 * mm, abs=1e-8)
    assert g.mesh_period_rad == pytest.approx(2 * math.pi / 20)
    # helpers: the pinion radius at E is its tip radius, the gear radius at A is its tip radius
    assert g.pinion_radius_at(g.s_end_m) == pytest.approx(g.ra1_m, rel=1e-12)
    assert g.gear_radius_at(g.s_start_m) == pytest.approx(g.ra2_m, rel=1e-12)
    assert g.pinion_radius_at(g.s_pitch_m) == pytest.approx(g.rw1_m, rel=1e-12)
    assert g.pinion_pressure_angle_at(g.s_pitch_m) == pytest.approx(DEG20, abs=1e-12)
    # one base pitch of LOA travel = one mesh period of pinion rotation
    assert g.pinion_angle_from_s(g.s_start_m + g.base_pitch_m) == pytest.approx(g.mesh_period_rad)
    assert g.active_length_m == pytest.approx(g.contact_ratio * g.base_pitch_m, rel=1e-12)
    lo2, hi2 = g.active_roll2_m
    assert hi2 == pytest.approx(math.sqrt(g.ra2_m ** 2 - g.rb2_m ** 2), rel=1e-12)


def test_inverse_involute_roundtrip():
    # inv(20 deg) = tan(20 deg) - 20 pi/180 = 0.0149044 (involute function tables)
    assert float(involute(DEG20)) == pytest.approx(0.0149044, abs=1e-7)
    for a in np.linspace(0.05, 1.2, 25):
        assert inverse_involute(float(involute(a))) == pytest.approx(a, abs=1e-12)


def test_seed004_pair_I_table1():
    # seed 004 Table 1, pair I: m = 3, z = 27/35, x = 0: r 40.5/52.5, ra 43.5/55.5,
    # rb 38.06/49.33 mm, a = 93 mm (published to 0.01 mm -> tolerance 0.006 mm)
    g = pair_geometry(spur_pair(27, 35, 3e-3, b=0.025))
    tol = 0.006e-3
    assert g.r1_m == pytest.approx(40.5e-3, abs=tol)
    assert g.r2_m == pytest.approx(52.5e-3, abs=tol)
    assert g.ra1_m == pytest.approx(43.5e-3, abs=tol)
    assert g.ra2_m == pytest.approx(55.5e-3, abs=tol)
    assert g.rb1_m == pytest.approx(38.06e-3, abs=tol)
    assert g.rb2_m == pytest.approx(49.33e-3, abs=tol)
    assert g.center_distance_m == pytest.approx(93e-3, abs=tol)


def test_seed004_pair_II_table1_profile_shifted():
    # seed 004 Table 1, pair II: m = 4.5, z = 16/24, x = 0.8532/-0.5, a = 91.5 mm.
    # Its "pitch radius" 36.60/54.90 mm is the OPERATING pitch radius a_w z/(z1+z2)
    # (reference radii would be 36.0/54.0); its tip radii 44.25/56.16 mm include the tip
    # shortening k m with k = (x1+x2) - (a_w - a)/m = 0.3532 - 1.5/4.5 = 0.01987:
    #   ra1 = 36 + 4.5 (1 + 0.8532 - 0.01987) = 44.2500, ra2 = 54 + 4.5 (1 - 0.5 - 0.01987) = 56.1606
    # (without shortening: 44.339 / 56.250 mm, which the table does not list).
    g = pair_geometry(spur_pair(16, 24, 4.5e-3, 0.8532, -0.5, cd=91.5e-3))
    tol = 0.006e-3
    assert g.rw1_m == pytest.approx(36.60e-3, abs=tol)
    assert g.rw2_m == pytest.approx(54.90e-3, abs=tol)
    assert g.ra1_m == pytest.approx(44.25e-3, abs=tol)
    assert g.ra2_m == pytest.approx(56.16e-3, abs=tol)
    assert g.rb1_m == pytest.approx(33.83e-3, abs=tol)
    assert g.rb2_m == pytest.approx(50.74e-3, abs=tol)
    assert g.center_distance_m == pytest.approx(91.5e-3, abs=tol)
    # the zero-backlash meshing equation gives the same centre distance (x1 was chosen for it)
    g0 = pair_geometry(spur_pair(16, 24, 4.5e-3, 0.8532, -0.5))
    assert g0.center_distance_m == pytest.approx(91.5e-3, abs=0.001e-3)
    # without shortening the tips are r + m (ha* + x)
    gn = pair_geometry(spur_pair(16, 24, 4.5e-3, 0.8532, -0.5, cd=91.5e-3), tip_shortening=False)
    assert gn.ra1_m == pytest.approx(36e-3 + 4.5e-3 * 1.8532, rel=1e-12)
    # gear z = 24, x = -0.5 is below x_min = 1 - 24 sin^2(20)/2 = -0.4038 (slight undercut),
    # accepted because the undercut stays below the start of its active profile
    r_u = undercut_limit_radius(24, 4.5e-3, DEG20, -0.5, 1.0)
    assert g.rb2_m < r_u < g.gear_radius_at(g.s_end_m)


def test_seed003_kahraman_pair():
    # seed 003 Table 1: 50/50, m = 3 mm, base diameter 140.95 mm, outer 156 mm,
    # centre distance 150 mm, contact ratio 1.7547
    g = pair_geometry(spur_pair(50, 50, 3e-3, b=0.02))
    assert 2 * g.rb1_m == pytest.approx(140.95e-3, abs=0.006e-3)
    assert 2 * g.ra1_m == pytest.approx(156e-3, abs=1e-9)
    assert g.center_distance_m == pytest.approx(150e-3, rel=1e-12)
    assert g.contact_ratio == pytest.approx(1.7547, abs=6e-5)


def test_operating_pressure_angle_from_given_center_distance():
    # hand: cos(alpha_w) = a cos(alpha)/a_w = 150 cos 20 / 152 -> alpha_w = 21.9528 deg
    g = pair_geometry(spur_pair(20, 40, 5e-3, 0.2, 0.2, cd=152e-3))
    assert math.degrees(g.alpha_w_rad) == pytest.approx(
        math.degrees(math.acos(150 * math.cos(DEG20) / 152)), abs=1e-10)
    assert g.rw1_m == pytest.approx(152e-3 / 3, rel=1e-12)


def test_undercut_rejected():
    # z = 8, x = 0: x_min = 1 - 8 sin^2(20)/2 = 0.532 > 0 -> undercut (textbook limit z_min = 17)
    with pytest.raises(GeometryError, match=r"pinion\.profile_shift: undercut"):
        pair_geometry(spur_pair(8, 40, 2e-3))
    # 17 teeth (z_min = 2/sin^2 20 = 17.1) is fine against a rack-like mate
    pair_geometry(spur_pair(17, 40, 2e-3))
    # no undercut at or above x_min
    assert undercut_limit_radius(20, 1e-3, DEG20, 0.0, 1.0) == 0.0
    assert undercut_limit_radius(12, 1e-3, DEG20, 0.0, 1.0) > 6e-3 * math.cos(DEG20)


def test_contact_ratio_below_one_rejected():
    # ha* = 0.5, 20/40 m 5: eps = (sqrt(52.5^2-46.985^2) + sqrt(102.5^2-93.969^2) - 51.303)/14.761
    #   = (23.424 + 40.937 - 51.303)/14.761 = 0.885 < 1
    with pytest.raises(GeometryError, match="contact ratio"):
        pair_geometry(spur_pair(20, 40, 5e-3, ha=0.5))


def test_pointed_tip_rejected():
    # z = 10, x = 1.0: tip r_a = 5 + 2 = 7 m-units, alpha_a = acos(4.6985/7) = 47.84 deg,
    # half tip angle = pi/20 + 2 tan20/10 + inv20 - inv(47.84) = 0.15708 + 0.07279 + 0.01490 - 0.2696 < 0
    with pytest.raises(GeometryError, match="pointed"):
        pair_geometry(spur_pair(10, 40, 2e-3, 1.0, 0.0))


def test_interference_rejected():
    # 14 / 60 teeth, m = 2, pinion x = 0.2 (no rack undercut: x_min = 1 - 14 sin^2 20/2 = 0.181),
    # gear addendum 1.4 m. Hand calc: inv(alpha_w) = inv 20 + 2 tan 20 * 0.2/74 = 0.016872
    # -> alpha_w = 20.814 deg, a_w = 74 cos 20/cos 20.814 = 74.392 mm, N1N2 = a_w sin(alpha_w)
    # = 26.43 mm; tip shortening k = 0.2 - 0.392/2 = 0.004, ra2 = 60 + 2 (1.4 - 0.004) = 62.79 mm,
    # rb2 = 56.382 mm, sqrt(ra2^2 - rb2^2) = 27.64 mm > N1N2: the gear tip reaches past N1.
    def pair(ha2):
        return GearPairSpec(GearSpec(14, 2e-3, DEG20, 0.02, 0.2, 1.0, 0.25),
                            GearSpec(60, 2e-3, DEG20, 0.02, 0.0, ha2, 0.25))
    with pytest.raises(GeometryError, match=r"gear\.addendum_coefficient: involute interference"):
        pair_geometry(pair(1.4))
    # ha2 = 1.13: ra2 = 62.252 mm, sqrt(ra2^2 - rb2^2) = 26.39 mm, s_A = 0.05 mm > 0 (not past N1)
    # but below the pinion's form circle: s_form = 14 sin 20 - 0.8*2/sin 20 = 4.788 - 4.678 = 0.110 mm
    with pytest.raises(GeometryError, match=r"pinion\.profile_shift: root interference"):
        pair_geometry(pair(1.13))
    pair_geometry(pair(1.0))


@pytest.mark.parametrize("field,kwargs,match", [
    ("teeth", dict(z1=0), r"pinion\.teeth"),
    ("teeth", dict(z1=20.5), r"pinion\.teeth"),
    ("module", dict(m=-1e-3), r"pinion\.module_m"),
    ("face", dict(b=0.0), r"pinion\.face_width_m"),
])
def test_bad_input_names_field(field, kwargs, match):
    args = dict(z1=20, z2=40, m=2e-3, b=0.02)
    args.update(kwargs)
    with pytest.raises(GeometryError, match=match):
        pair_geometry(spur_pair(args["z1"], args["z2"], args["m"], b=args["b"]))


def test_hub_radius_must_be_below_root():
    # rf1 = 20 - 1.25*2 = 17.5 mm for z = 20, m = 2
    with pytest.raises(GeometryError, match=r"pinion\.hub_radius_m"):
        pair_geometry(spur_pair(20, 40, 2e-3, hub1=17.5e-3))
    pair_geometry(spur_pair(20, 40, 2e-3, hub1=17.0e-3))
    assert issubclass(GeometryError, ValueError)


def _brute_force_undercut_ratio(z, x, alpha=DEG20):
    """Independent check of the trochoid: envelope of the rack's straight flank, brute force.

    The gear (module 1) is generated by a rack whose straight flank (pressure angle alpha)
    ends ha* m = 1 below the datum line, shifted by x.  For many rolling positions phi the
    flank polyline is placed in the gear frame; at each radius the cut flank is the smallest
    polar angle reached by any position.  Where that lies inside the involute, the involute
    is undercut.  Returns the largest such radius / r (0 if none).
    """
    from gearfmu.gear.geometry import half_tooth_angle_at_base
    r = z / 2.0
    rb = r * math.cos(alpha)
    d = 1.0 - x
    psi_b = half_tooth_angle_at_base(z, x, alpha)
    xc = r * (psi_b - float(involute(alpha)))
    yv = np.linspace(r - d, r + 1.0, 300)
    xv = xc + (r - yv) * math.tan(alpha)
    rhos = np.linspace(rb * 1.0001, r, 400)
    best = np.full(rhos.shape, np.inf)
    for phi in np.linspace(-1.2, 1.2, 4001):
        X = xv - r * phi
        Xg = X * math.cos(phi) + yv * math.sin(phi)
        Yg = -X * math.sin(phi) + yv * math.cos(phi)
        rho, th = np.hypot(Xg, Yg), np.arctan2(Xg, Yg)
        k = int(np.argmin(rho))                      # split into two monotonic branches
        for rr, tt in ((rho[k:], th[k:]), (rho[:k + 1][::-1], th[:k + 1][::-1])):
            if rr.size < 2:
                continue
            inside = (rhos >= rr[0]) & (rhos <= rr[-1])
            best[inside] = np.minimum(best[inside], np.interp(rhos[inside], rr, tt))
    inv = psi_b - involute(np.arccos(rb / rhos))
    bad = best < inv - 1e-7
    return float(rhos[bad].max() / r) if bad.any() else 0.0


@pytest.mark.parametrize("z", [8, 12])
def test_undercut_height_matches_brute_force_envelope(z):
    # grid spacing of the brute force: (r - rb)/400 ~ 1.5e-4 r -> tolerance 1e-3 r
    ratio = undercut_limit_radius(z, 1.0, DEG20, 0.0, 1.0) / (z / 2.0)
    assert ratio == pytest.approx(_brute_force_undercut_ratio(z, 0.0), abs=1e-3)
    assert ratio > math.cos(DEG20)
