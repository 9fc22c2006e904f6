"""A geometric planetary stage: its tables and lumped parameters from the gear geometry.

References (none produced by gearfmu.assembly.planetary):

* the second stage of the NREL 5 MW reference gearbox (Nejad, Guo, Gao & Moan 2016, Wind Energy 19,
  1089-1106, Table V, as in tests/unit/gear/test_internal_gear.py): 18/36/93 teeth, m = 21 mm, x = 0.389 /
  0.504 / 0.117, b = 550 mm, three planets at 584 mm;
* involute geometry written out here: base radii r_b = m z cos(alpha)/2, the operating pressure
  angles at the carrier radius, cos(alpha_w) = (r_bs + r_bp)/a and (r_br - r_bp)/a;
* solid discs and an annulus: m = rho pi b (r_o^2 - r_i^2), I = rho pi b (r_o^4 - r_i^4)/2;
* the mesh phases of gearfmu.gear.phasing (checked against a brute-force flank construction in
  tests/unit/gear/test_planetary_phasing.py) and the pin position deflections of Lin & Parker's mesh
  deflections (-e_r sin(alpha_s) - e_t cos(alpha_s), +e_r sin(alpha_r) - e_t cos(alpha_r));
* Lin & Parker's (1999) mode structure for equally spaced identical planets, and the statics of the
  stage: the planets share the sun torque equally.
"""
import math

import numpy as np
import pytest

from gearfmu.assembly.planetary import StageMechanics, planetary_stage
from gearfmu.gear.gearpair import GearDeviations, GearSpec, ToothDeviation
from gearfmu.gear.internal import RingRim
from gearfmu.gear.internal_stiffness import mean_internal_mesh_stiffness_N_per_m
from gearfmu.gear.phasing import mesh_phasing
from gearfmu.gear.planetary_set import PlanetarySet, PlanetErrors, planetary_geometry
from gearfmu.planetary.model import build_drivetrain
from gearfmu.planetary.modes import modes, multiplicities
from gearfmu.planetary.native import simulate
from gearfmu.tables.planetary import PlanetaryStageError

A20 = math.radians(20.0)
M, ZS, ZP, ZR, XS, XP, XR, B, AW = 21e-3, 18, 36, 93, 0.389, 0.504, 0.117, 0.550, 0.584
RIM = 0.1
MECH = StageMechanics(carrier_mass_kg=2000.0, carrier_inertia_kgm2=300.0,
                      bearing_N_per_m=dict(sun=0.0, ring=5e9, carrier=5e9, planet=5e9), support_Nm_per_rad=5e9)


def nrel2(**kw):
    return PlanetarySet(GearSpec(ZS, M, A20, B, XS), GearSpec(ZP, M, A20, B, XP), GearSpec(ZR, M, A20, B, XR), 3,
                        carrier_radius_m=AW, rim=RingRim(RIM, 12), backlash_sun_m=0.2e-3, backlash_ring_m=0.2e-3, **kw)


@pytest.fixture(scope="module")
def stage():
    return planetary_stage("s2", nrel2(), MECH, sun_torque_Nm=2.0e5, points_per_mesh=32)


def test_geometry_of_the_stage(stage):
    rbs, rbp, rbr = (0.5 * M * z * math.cos(A20) for z in (ZS, ZP, ZR))
    assert (stage.base_radius_sun_m, stage.base_radius_planet_m, stage.base_radius_ring_m) == pytest.approx(
        (rbs, rbp, rbr), rel=1e-12)
    assert stage.carrier_radius_m == AW
    assert math.cos(stage.pressure_angle_sun_rad) == pytest.approx((rbs + rbp) / AW, rel=1e-12)
    assert math.cos(stage.pressure_angle_ring_rad) == pytest.approx((rbr - rbp) / AW, rel=1e-12)
    assert stage.planet_angles_rad == pytest.approx((0.0, 2 * math.pi / 3, 4 * math.pi / 3))
    assert stage.ring_sun_phase_rad == mesh_phasing(planetary_geometry(nrel2())).ring_offset_rad[0]
    # identical planets share their tables
    assert stage.sun_tables[0] is stage.sun_tables[2] and stage.ring_tables[0] is stage.ring_tables[1]


def test_masses_and_inertias_of_the_stage(stage):
    rho = 7850.0
    for key, z in (("sun", ZS), ("planet", ZP)):
        r = 0.5 * M * z
        assert stage.mass_kg[key] == pytest.approx(rho * math.pi * B * r * r, rel=1e-12)
        assert stage.inertia_kgm2[key] == pytest.approx(0.5 * rho * math.pi * B * r ** 4, rel=1e-12)
    rf = planetary_geometry(nrel2()).ring_planet.rf2_m
    ro = rf + RIM
    assert stage.mass_kg["ring"] == pytest.approx(rho * math.pi * B * (ro ** 2 - rf ** 2), rel=1e-12)
    assert stage.inertia_kgm2["ring"] == pytest.approx(0.5 * rho * math.pi * B * (ro ** 4 - rf ** 4), rel=1e-12)
    assert stage.mass_kg["carrier"] == 2000.0 and stage.inertia_kgm2["carrier"] == 300.0


def test_ring_tables_carry_the_internal_mesh_stiffness(stage):
    ps = nrel2()
    rp = planetary_geometry(ps).ring_planet
    t = stage.ring_tables[0]
    k = mean_internal_mesh_stiffness_N_per_m(ps.planet, ps.ring, ps.rim, rp, n_per_mesh=512)
    # the tables' mean (their lookup on 32 points a mesh period, cut at the contact-zone edges) against
    # the fine mean of the stiffness model: measured -0.26 %
    assert t.k_mean_N_per_m == pytest.approx(k, rel=5e-3)
    assert t.teeth_pinion == ZP and t.teeth_gear == ZR
    assert t.base_radius_pinion_m == pytest.approx(stage.base_radius_planet_m, rel=1e-12)
    assert np.all(t.backlash_half_m == pytest.approx(0.1e-3))
    assert t.contact_ratio == pytest.approx(rp.contact_ratio)


def test_planet_errors_and_deviations_enter_per_planet():
    dev = GearDeviations(per_tooth=((0, ToothDeviation(pitch_m=8e-6)),))
    ps = nrel2(planet_errors=(PlanetErrors(10e-6, -20e-6), PlanetErrors(), PlanetErrors()),
               planet_deviations=(dev, GearDeviations(), GearDeviations()))
    st = planetary_stage("s2", ps, MECH, sun_torque_Nm=2.0e5, points_per_mesh=32)
    a_s, a_r = st.pressure_angle_sun_rad, st.pressure_angle_ring_rad
    d_s, d_r = st.position_deflections_m[0]
    assert d_s == pytest.approx(-10e-6 * math.sin(a_s) + 20e-6 * math.cos(a_s), rel=1e-12)
    assert d_r == pytest.approx(10e-6 * math.sin(a_r) + 20e-6 * math.cos(a_r), rel=1e-12)
    assert st.position_deflections_m[1] == (0.0, 0.0)
    assert st.sun_tables[0] is not st.sun_tables[1] and st.sun_tables[1] is st.sun_tables[2]
    assert np.ptp(st.sun_tables[0].e_m) > 1e-6 and np.ptp(st.sun_tables[1].e_m) == 0.0


def test_a_ring_without_mass_or_rim_is_refused():
    ps = PlanetarySet(GearSpec(ZS, M, A20, B, XS), GearSpec(ZP, M, A20, B, XP), GearSpec(ZR, M, A20, B, XR), 3,
                      carrier_radius_m=AW)
    with pytest.raises(PlanetaryStageError, match=r"s2\.ring: give the ring's mass and inertia, or its rim"):
        planetary_stage("s2", ps, MECH, sun_torque_Nm=2.0e5, points_per_mesh=32)
    with pytest.raises(PlanetaryStageError, match="sun torque must be > 0"):
        planetary_stage("s2", nrel2(), MECH, sun_torque_Nm=0.0, points_per_mesh=32)


def test_the_geometric_stage_has_lin_parkers_structure_and_shares_its_load(stage):
    m = build_drivetrain(planetaries=[stage], motor="s2.carrier", load="s2.sun")
    groups = multiplicities(modes(m, 1e6), "s2")
    assert {t for t, _, _ in groups} == {"rotational", "translational"}     # three planets: no planet modes
    assert all(k == (2 if t == "translational" else 1) for t, _, k in groups)
    # 1 MN m on the carrier: the sun mesh of every planet carries a third of the sun torque
    T_c = 1.0e6
    r = simulate(m, stop_time_s=1e-3, comm_step_s=1e-5, motor_torque_Nm=T_c, motor_speed_start_rad_s=1.5)
    T_s = T_c * stage.base_radius_sun_m / (stage.base_radius_sun_m + stage.base_radius_ring_m)
    for n in (1, 2, 3):
        assert r[f"s2.sun_planet[{n}].mesh_force"][0] == pytest.approx(T_s / 3 / stage.base_radius_sun_m, rel=1e-9)
        assert r[f"s2.load_sharing_factor[{n}]"][0] == pytest.approx(1.0, abs=1e-9)
    assert np.all(np.isfinite(r["s2.sun_planet[1].dte"]))
