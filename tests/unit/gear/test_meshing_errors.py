"""Tests of gearfmu.gear.meshing_errors against hand calculations of seed 003 eq (15),
ISO 1328-1 cumulative pitch deviation, the lcm hunting-tooth rule and seed 000
eq (16) lead crowning.  Every expected number below is worked out by hand in the
comment next to it (no number was produced by the code under test)."""
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from gearfmu.gear.gearpair import GearDeviations, GearPairSpec, GearSpec, ToothDeviation
from gearfmu.gear.meshing_errors import (EvaluationRanges, MeshingErrorInputError, comprehensive_error_m,
                                    gear_teeth_differ, lead_crowning_m, pair_error_m,
                                    pair_lead_crowning_m, pitch_position_errors_m,
                                    profile_deviation_m, slot_mesh_numbers, table_mesh_count,
                                    tooth_indices)

UM = 1e-6


# ----------------------------------------------------------------- eq 15
def test_profile_deviation_hand_values():
    # seed 003 eq 15 with f_fa = 15 um, f_Ha = 4 um, f_r = 2 on s in [2 mm, 10 mm]:
    # xi = (s - s_o)/(s_f - s_o); e = 7.5 um sin(4 pi xi) + 4 um xi
    dev = ToothDeviation(profile_form_m=15 * UM, profile_slope_m=4 * UM, form_periods=2.0)
    s = np.array([2e-3, 3e-3, 4e-3, 6e-3, 7e-3, 10e-3])
    # xi = 0, 1/8, 1/4, 1/2, 5/8, 1 ->
    # 0; 7.5*sin(pi/2)+0.5 = 8.0; 7.5*sin(pi)+1 = 1; 0+2 = 2; 7.5*sin(5pi/2)+2.5 = 10; 0 + 4 = 4
    expected = np.array([0.0, 8.0, 1.0, 2.0, 10.0, 4.0]) * UM
    np.testing.assert_allclose(profile_deviation_m(s, dev, 2e-3, 10e-3), expected, rtol=0, atol=1e-15)


def test_profile_deviation_clamped_outside_range():
    # outside [s_o, s_f] the value is held at the end values: slope only -> 0 and f_Ha
    dev = ToothDeviation(profile_slope_m=-3 * UM)
    out = profile_deviation_m(np.array([0.0, 20e-3]), dev, 2e-3, 10e-3)
    np.testing.assert_allclose(out, [0.0, -3 * UM], atol=1e-18)


@settings(max_examples=60, deadline=None)
@given(ffa=st.floats(-50e-6, 50e-6), fha=st.floats(-50e-6, 50e-6), fr=st.floats(0, 6),
       xi=st.floats(0, 1))
def test_profile_deviation_bounded(ffa, fha, fr, xi):
    # |e| <= |f_fa|/2 + |f_Ha| xi follows from |sin| <= 1 in eq 15
    dev = ToothDeviation(profile_form_m=ffa, profile_slope_m=fha, form_periods=fr)
    e = float(profile_deviation_m(1e-3 + 5e-3 * xi, dev, 1e-3, 6e-3))
    assert abs(e) <= abs(ffa) / 2 + abs(fha) * xi + 1e-18


def test_profile_deviation_bad_range_and_values():
    with pytest.raises(MeshingErrorInputError, match="s_f_m"):
        profile_deviation_m(1.0, ToothDeviation(), 2.0, 1.0)
    with pytest.raises(MeshingErrorInputError, match="profile_form_m"):
        profile_deviation_m(1.0, ToothDeviation(profile_form_m=float("nan")), 0.0, 2.0)
    with pytest.raises(MeshingErrorInputError, match="form_periods"):
        profile_deviation_m(1.0, ToothDeviation(form_periods=-1.0), 0.0, 2.0)


# ----------------------------------------------------------------- pitch
def test_pitch_positions_single_long_pitch():
    # z = 4, f_pt = [0, 0, 4, 0] um. Closure: mean 1 um -> f' = [-1, -1, 3, -1].
    # cumulative from tooth 0: p = [0, -1, 2, 1]; mean 0.5 -> [-0.5, -1.5, 1.5, 0.5] um
    devs = GearDeviations(per_tooth=((2, ToothDeviation(pitch_m=4 * UM)),))
    np.testing.assert_allclose(pitch_position_errors_m(devs, 4), np.array([-0.5, -1.5, 1.5, 0.5]) * UM,
                               atol=1e-18)


def test_pitch_positions_equal_pitches_close_to_zero():
    # every pitch 3 um too long cannot close a circle: after closure all positions are 0
    devs = GearDeviations(default=ToothDeviation(pitch_m=3 * UM))
    assert np.all(pitch_position_errors_m(devs, 17) == 0.0)
    assert not gear_teeth_differ(devs, 17)


def test_pitch_index_out_of_range():
    devs = GearDeviations(per_tooth=((9, ToothDeviation(pitch_m=1e-6)),))
    with pytest.raises(MeshingErrorInputError, match="per_tooth"):
        pitch_position_errors_m(devs, 5)


# ------------------------------------------------------------ periods/indices
def test_table_mesh_count_lcm_rule():
    # hand lcm: lcm(2,45) = 90, lcm(2,34) = 34, lcm(2,45,34) = 2*45*17 = 1530
    assert table_mesh_count(2, 45, 34, False, False) == 2
    assert table_mesh_count(2, 45, 34, True, False) == 90
    assert table_mesh_count(2, 45, 34, False, True) == 34
    assert table_mesh_count(2, 45, 34, True, True) == 1530
    assert table_mesh_count(3, 50, 50, True, True) == 150
    with pytest.raises(MeshingErrorInputError, match="slots"):
        table_mesh_count(0, 45, 34, False, False)


def test_tooth_indices():
    # mesh 7 with z1 = 5, z2 = 3: pinion tooth 7 mod 5 = 2, gear tooth 7 mod 3 = 1
    i1, i2 = tooth_indices(7, 5, 3)
    assert (int(i1), int(i2)) == (2, 1)


def test_slot_mesh_numbers_hand_grid():
    # P = 2, 4 meshes per table, 2 points per mesh: grid i = 0..7, latest mesh started = i // 2.
    # slot 0 holds even meshes: [0,0,0,0,2,2,2,2]; slot 1 odd ones, the one at i = 0,1 entered
    # one period before phi = 0 (mesh -1 = mesh 3 of the periodic table): [3,3,1,1,1,1,3,3]
    n, local = slot_mesh_numbers(2, 4, 2)
    np.testing.assert_array_equal(n[0], [0, 0, 0, 0, 2, 2, 2, 2])
    np.testing.assert_array_equal(n[1], [3, 3, 1, 1, 1, 1, 3, 3])
    np.testing.assert_array_equal(local[0], [0, 1, 2, 3, 0, 1, 2, 3])
    np.testing.assert_array_equal(local[1], [2, 3, 0, 1, 2, 3, 0, 1])


# -------------------------------------------------------------- pair error
def _pair(pin_devs=GearDeviations(), gear_devs=GearDeviations(), z1=5, z2=3):
    g = lambda z, d: GearSpec(teeth=z, module_m=3e-3, pressure_angle_rad=math.radians(20),
                              face_width_m=20e-3, deviations=d)
    return GearPairSpec(pinion=g(z1, pin_devs), gear=g(z2, gear_devs))


def test_pair_error_sums_flanks_and_uses_tooth_indices():
    # ranges: pinion s in [10, 20] mm from N1, N1N2 = 40 mm -> gear u = 40 - s in [20, 30] mm.
    rng = EvaluationRanges(s_o_pinion_m=10e-3, s_f_pinion_m=20e-3, s_o_gear_m=20e-3, s_f_gear_m=30e-3,
                           n1n2_m=40e-3)
    pin = GearDeviations(per_tooth=((2, ToothDeviation(profile_slope_m=10 * UM)),))
    gear = GearDeviations(per_tooth=((1, ToothDeviation(profile_slope_m=6 * UM)),))
    pair = _pair(pin, gear)
    s = np.array([10e-3, 15e-3, 20e-3])
    # mesh 7: pinion tooth 2 (slope 10 um), gear tooth 1 (slope 6 um).
    # s = 10 mm: pinion xi 0 -> 0; gear u = 30 mm, xi 1 -> 6 um; total 6
    # s = 15 mm: 5 + 3 = 8 um; s = 20 mm: 10 + 0 = 10 um
    np.testing.assert_allclose(pair_error_m(pair, rng, 7, s), np.array([6.0, 8.0, 10.0]) * UM, atol=1e-18)
    # mesh 0: pinion tooth 0, gear tooth 0 -> no profile deviation, no pitch -> exactly 0
    assert np.all(pair_error_m(pair, rng, 0, s) == 0.0)
    # mesh 12: pinion tooth 2 (12 mod 5), gear tooth 0 -> pinion only: 0, 5, 10 um
    np.testing.assert_allclose(pair_error_m(pair, rng, 12, s), np.array([0.0, 5.0, 10.0]) * UM, atol=1e-18)


def test_pair_error_pitch_term():
    # pinion z = 4 with a 4 um long pitch ending at tooth 2: positions [-0.5,-1.5,1.5,0.5] um
    # (hand, see test above); mesh 6 -> pinion tooth 2 -> +1.5 um at any s
    rng = EvaluationRanges(10e-3, 20e-3, 20e-3, 30e-3, 40e-3)
    pair = _pair(GearDeviations(per_tooth=((2, ToothDeviation(pitch_m=4 * UM)),)), z1=4)
    np.testing.assert_allclose(pair_error_m(pair, rng, 6, [12e-3, 18e-3]), [1.5 * UM, 1.5 * UM], atol=1e-18)


# --------------------------------------------------------- comprehensive
def test_comprehensive_is_min_over_pairs_in_contact():
    e = np.array([[1.0, 2.0, 3.0, 9.0], [5.0, 0.5, 4.0, -7.0]]) * UM
    inc = np.array([[True, True, True, True], [False, True, True, False]])
    # angle 0: only pair 0 -> 1; angle 1: min(2, .5) = .5; angle 2: min(3, 4) = 3; angle 3: 9
    np.testing.assert_allclose(comprehensive_error_m(e, inc), np.array([1.0, 0.5, 3.0, 9.0]) * UM)


# -------------------------------------------------------------- crowning
def test_lead_crowning_parabola_hand_values():
    # b = 20 mm, 4 slices: centres -7.5, -2.5, 2.5, 7.5 mm; (2y/b)^2 = 0.5625, 0.0625
    # C_b = 10 um -> 5.625, 0.625, 0.625, 5.625 um
    np.testing.assert_allclose(lead_crowning_m(10 * UM, 20e-3, 4), np.array([5.625, 0.625, 0.625, 5.625]) * UM,
                               rtol=1e-14)
    # odd count: centre slice exactly 0; 5 slices: (2y/b)^2 = 0.64, 0.16, 0, 0.16, 0.64
    np.testing.assert_allclose(lead_crowning_m(10 * UM, 20e-3, 5), np.array([6.4, 1.6, 0, 1.6, 6.4]) * UM,
                               rtol=1e-14, atol=1e-20)


def test_pair_crowning_adds_both_gears():
    # pinion 3 um + gear 5 um = 8 um over 3 slices: (2y/b)^2 = (2/3)^2 = 4/9, 0, 4/9
    pair = _pair(GearDeviations(lead_crowning_m=3 * UM), GearDeviations(lead_crowning_m=5 * UM))
    np.testing.assert_allclose(pair_lead_crowning_m(pair, 3), np.array([32 / 9, 0, 32 / 9]) * UM, rtol=1e-14,
                               atol=1e-20)


def test_lead_crowning_bad_input():
    with pytest.raises(MeshingErrorInputError, match="lead_crowning_m"):
        lead_crowning_m(-1e-6, 0.02, 3)
    with pytest.raises(MeshingErrorInputError, match="slices"):
        lead_crowning_m(1e-6, 0.02, 0)
    with pytest.raises(MeshingErrorInputError, match="face_width_m"):
        lead_crowning_m(1e-6, 0.0, 3)


def test_evaluation_ranges_seed003_table1_geometry():
    # seed 003 Table 1: z = 50/50, m = 3 mm, 20 deg, outer diameter 156 mm, centre distance 150 mm.
    # hand: rb = 75 cos 20 = 70.4769 mm; N1N2 = 150 sin 20 = 51.3030 mm;
    # tip roll length sqrt(78^2 - 70.4769^2) = 33.4215 mm; s_A = 51.3030 - 33.4215 = 17.8815 mm
    from gearfmu.gear.geometry import pair_geometry
    from gearfmu.gear.meshing_errors import evaluation_ranges
    g = GearSpec(teeth=50, module_m=3e-3, pressure_angle_rad=math.radians(20), face_width_m=20e-3)
    r = evaluation_ranges(pair_geometry(GearPairSpec(pinion=g, gear=g)))
    assert abs(r.n1n2_m - 51.3030e-3) < 1e-7
    assert abs(r.s_o_pinion_m - 17.8815e-3) < 1e-7 and abs(r.s_f_pinion_m - 33.4215e-3) < 1e-7
    assert abs(r.s_o_gear_m - 17.8815e-3) < 1e-7 and abs(r.s_f_gear_m - 33.4215e-3) < 1e-7
