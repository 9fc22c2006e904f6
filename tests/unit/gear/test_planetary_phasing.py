"""Mesh phasing of planetary sets (gearfmu.gear.phasing).

References (none produced by this code):
* Parker & Lin (2004), J. Mech. Des. 126, 365-370: the sun-planet phases gamma_sn = z_s psi_n/(2 pi)
  and ring-planet phases gamma_rn = z_r psi_n/(2 pi) (mod 1, sign by the rotation sense), written
  out by hand below for the NREL 5 MW stage-1 set (19/17/56, three planets);
* a brute-force construction of planet 1's ring-against-sun phase: the planet's involute flanks
  drawn from their polar description (half tooth angle psi(rho)), intersected with the two lines of
  action, the contacting flank family picked by the flank normal lying along the line of action, the
  planet turned until a sun-mesh contact sits at the sun mesh's entry point s_A;
* Parker (2000), J. Sound Vib. 236, 561-573: which harmonics excite which mode types, evaluated by
  hand for z_s = 21, N = 4 (the spectra of the native solver are in tests/test_planetary_dynamics.py).
"""
import math

import numpy as np
import pytest

from gearfmu.gear.gearpair import GearSpec
from gearfmu.gear.geometry import half_tooth_angle_at_base, involute
from gearfmu.gear.phasing import lumped_phasing, mesh_phasing, parker_harmonic_excitation, ring_sun_phase_rad
from gearfmu.gear.planetary_set import PlanetarySet, planetary_geometry

A20 = math.radians(20.0)


def nrel(m, zs, zp, zr, xs, xp, xr, b, aw, ha_r=1.0, n=3, angles=None):
    return planetary_geometry(PlanetarySet(GearSpec(zs, m, A20, b, xs), GearSpec(zp, m, A20, b, xp),
                                           GearSpec(zr, m, A20, b, xr, ha_r), n, planet_angles_rad=angles,
                                           carrier_radius_m=aw))


SETS = {
    "nrel stage 1 (odd z_p)": (45e-3, 19, 17, 56, 0.617, 0.802, -0.501, 0.491, 0.863),
    "nrel stage 2 (even z_p)": (21e-3, 18, 36, 93, 0.389, 0.504, 0.117, 0.550, 0.584),
    "x = -0.5/0.5/-0.5, ring addendum 0.9": (2e-3, 25, 29, 83, -0.5, 0.5, -0.5, 0.02, None, 0.9),
}


def test_equally_spaced_phases_by_hand():
    g = nrel(*SETS["nrel stage 1 (odd z_p)"])
    ph = mesh_phasing(g)
    # gamma_sn = frac(-z_s psi_n/2pi) = frac(-19 n/3): 0, 2/3, 1/3; gamma_rn = frac(56 n/3): 0, 2/3, 1/3
    assert ph.gamma_sun == pytest.approx((0.0, 2 / 3, 1 / 3), abs=1e-12)
    assert ph.gamma_ring == pytest.approx((0.0, 2 / 3, 1 / 3), abs=1e-12)
    assert not ph.in_phase
    # sun offsets are the planet angles (sun angle units), ring offsets shift by z_r/z_p psi_n
    assert ph.sun_offset_rad == pytest.approx((0.0, -2 * math.pi / 3, -4 * math.pi / 3), abs=1e-12)
    d = np.subtract(ph.ring_offset_rad, ph.ring_offset_rad[0])
    assert d == pytest.approx([0.0, 56 / 17 * 2 * math.pi / 3, 56 / 17 * 4 * math.pi / 3], abs=1e-12)
    # the mirror (sun turning clockwise in the tables' forward sense): phases 1 - gamma
    mir = mesh_phasing(g, sigma=-1)
    assert mir.gamma_sun == pytest.approx((0.0, 1 / 3, 2 / 3), abs=1e-12)


def test_in_phase_and_unequal_spacing():
    # z_s = 18 with three planets: z_s/N an integer, all sun meshes in phase
    g = nrel(*SETS["nrel stage 2 (even z_p)"])
    assert mesh_phasing(g).in_phase
    # unequally spaced planets at multiples of 360/(z_s + z_r) = 360/111 deg: phases by the same rule
    ang = tuple(2 * math.pi * k / 111 for k in (0, 36, 75))
    ph = lumped_phasing(18, 36, 93, ang)
    assert ph.gamma_sun == pytest.approx([(-18 * k / 111) % 1 for k in (0, 36, 75)], abs=1e-12)
    assert ph.gamma_ring == pytest.approx(ph.gamma_sun, abs=1e-12)     # assembly: (z_s + z_r) psi/2pi integer


def _flank_contacts(geom, beta0, mesh):
    """LOA positions (m, from each mesh's N1) where a planet flank touches the mesh's line of action,
    found point by point from the planet's polar flank description."""
    sp, rp = geom.sun_planet, geom.ring_planet
    zp, xp, rb = rp.z1, rp.x1, rp.rb1_m
    ra, rf = sp.ra2_m, rp.rf1_m
    psi_b = half_tooth_angle_at_base(zp, xp, A20)
    if mesh == "sun":
        C, d, s_c = np.array([-sp.rw2_m, 0.0]), np.array([math.sin(sp.alpha_w_rad), math.cos(sp.alpha_w_rad)]), \
            sp.s_pitch_m
    else:
        C, d, s_c = np.array([rp.rw1_m, 0.0]), np.array([math.sin(rp.alpha_w_rad), -math.cos(rp.alpha_w_rad)]), \
            rp.s_pitch_m
    rho = np.linspace(max(rb, rf) * (1 + 1e-9), ra, 4001)
    psi = psi_b - involute(np.arccos(rb / rho))
    out = []
    for j in range(zp):
        for side in (1, -1):
            ang = beta0 + 2 * math.pi * j / zp + side * psi
            P = np.stack([rho * np.cos(ang), rho * np.sin(ang)], axis=1)
            f = (P[:, 0] - C[0]) * d[1] - (P[:, 1] - C[1]) * d[0]
            for i in np.nonzero(np.sign(f[:-1]) != np.sign(f[1:]))[0]:
                w = f[i] / (f[i] - f[i + 1])
                p = P[i] + w * (P[i + 1] - P[i])
                tang = P[i + 1] - P[i]
                normal = np.array([tang[1], -tang[0]]) / np.hypot(*tang)
                if abs(abs(normal @ d) - 1.0) < 1e-4:           # the flank's normal lies along the line of action
                    out.append(s_c + (p - C) @ d)
    out = np.sort(out)
    # beyond the planet's tangent point the line meets the other flank family (its normals touch the base
    # circle there too): keep the side where the mesh works, between N1 and N2 (sun), beyond N1 (ring)
    if mesh == "sun":
        return out[(out > 0.0) & (out < sp.loa_length_m)]
    return out[out > 0.0]


@pytest.mark.parametrize("name", list(SETS))
def test_ring_sun_phase_against_flank_construction(name):
    g = nrel(*SETS[name])
    sp, rp = g.sun_planet, g.ring_planet
    rb, pb = rp.rb1_m, rp.base_pitch_m
    s0 = _flank_contacts(g, 0.0, "sun")
    ds = (_flank_contacts(g, 1e-6, "sun")[0] - s0[0]) / 1e-6
    assert ds == pytest.approx(-rb, rel=1e-3)          # the planet turning clockwise advances the sun-mesh contacts
    beta0 = (s0[0] - sp.s_start_m) / rb                 # a contact at s_A: the sun mesh at table angle 0
    # (the pair at s_A itself sits on the planet's tip circle, the end of the drawn flank: check modulo p_b)
    off = (_flank_contacts(g, beta0, "sun") - sp.s_start_m + 0.5 * pb) % pb - 0.5 * pb
    assert np.min(np.abs(off)) < 1e-6 * pb
    sr = _flank_contacts(g, beta0, "ring")
    ahead = (sr - rp.s_start_m) % pb                    # the ring pair nearest ahead of the entry point
    phi_brute = float(np.min(ahead)) / rb
    T = 2 * math.pi / rp.z1
    diff = (ring_sun_phase_rad(g) - phi_brute + 0.5 * T) % T - 0.5 * T
    assert abs(diff) < 1e-5 * T, (ring_sun_phase_rad(g), phi_brute)


def test_parker_rule_by_hand():
    # z_s = 21, N = 4: l z_s mod 4 = 1, 2, 3, 0 for l = 1..4
    assert [parker_harmonic_excitation(l, 21, 4) for l in (1, 2, 3, 4)] == \
        ["translational", "planet", "translational", "rotational"]
    # z_s = 19, N = 3: 19 mod 3 = 1 -> translational; 38 mod 3 = 2 -> translational (38 + 1 = 39); 57 -> rotational
    assert [parker_harmonic_excitation(l, 19, 3) for l in (1, 2, 3)] == ["translational", "translational", "rotational"]
