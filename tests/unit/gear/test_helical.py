"""Helical gear pairs through staggered face-width slices (docs/helical.md).

References (none produced by gearfmu):
* textbook helical geometry (ISO 21771; Niemann/Winter, Maschinenelemente II, ch. 21):
  m_t = m_n/cos(beta), tan(alpha_t) = tan(alpha_n)/cos(beta), tan(beta_b) = tan(beta) cos(alpha_t)
  and independently sin(beta_b) = sin(beta) cos(alpha_n), eps_beta = b sin(beta)/(pi m_n),
  eps_alpha from the tip radii r + m_n, p_bn = p_bt cos(beta_b), the inv(alpha_wt) meshing equation;
* ISO 6336-1:2019 method B (clause 9): q' with the virtual tooth numbers z_n = z/(cos^2 beta_b cos beta),
  c' = C_M C_R C_B cos(beta)/q', c_gamma_alpha = c'(0.75 eps_alpha + 0.25);
* the classical result that the total contact-line length of a helical pair, hence (slices in
  parallel) its mesh stiffness, is constant when eps_beta is an integer, and that the overlap
  smooths the mesh stiffness (Niemann/Winter ch. 21; Smith, Gear Noise and Vibration, ch. 3);
* the slice kinematics: slice n is y_n tan(beta_b) behind the leading face end along the line of
  action, so its contact spends exactly eps_alpha mesh periods in the zone;
* FMU vs native solver: two independent implementations agree to round-off (docs/fmu.md).
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from gearfmu.gear.gearpair import MeshModelOptions
from gearfmu.gear.geometry import GeometryError, involute, pair_geometry, transverse_equivalent
from gearfmu.gear.meshing_errors import slot_errors_m, slot_slice_errors_m, stiffness_weighted_pair_error_m
from gearfmu.scene.reader import SceneError, load_scene
from gearfmu.gear.stiffness import (StiffnessError, helical_slot_stiffness, required_slots,
                               slice_lag_mesh_periods, slot_stiffness)

from support.helical_cases import SEED001, helical, iso_c_gamma_alpha

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow


# ------------------------------------------------------------------ geometry
def test_seed001_geometry_against_hand_values():
    g = pair_geometry(helical())
    # hand values (calculator): m_t = 5/cos 36 = 6.18034 mm, alpha_t = atan(tan 20/cos 36) = 24.2226 deg,
    # beta_b = atan(tan 36 cos 24.2226) = 33.5275 deg, eps_beta = 60 sin 36/(5 pi) = 2.24517
    assert g.module_m == pytest.approx(6.18034e-3, rel=1e-5)
    assert math.degrees(g.alpha_rad) == pytest.approx(24.2226, abs=1e-4)
    assert math.degrees(g.base_helix_angle_rad) == pytest.approx(33.5275, abs=1e-4)
    assert g.overlap_ratio == pytest.approx(2.24517, abs=1e-5)
    # independent identity sin(beta_b) = sin(beta) cos(alpha_n)
    assert math.sin(g.base_helix_angle_rad) == pytest.approx(math.sin(math.radians(36)) * math.cos(math.radians(20)),
                                                              rel=1e-12)
    # normal base pitch p_bn = pi m_n cos(alpha_n) = p_bt cos(beta_b)
    assert g.base_pitch_m * math.cos(g.base_helix_angle_rad) == pytest.approx(math.pi * 5e-3 * math.cos(math.radians(20)),
                                                                            rel=1e-12)
    # transverse contact ratio from the textbook formula, tip radii r + m_n (x = 0, no shortening)
    mt, at = 5e-3 / math.cos(math.radians(36)), math.atan(math.tan(math.radians(20)) / math.cos(math.radians(36)))
    r1, r2 = 33 * mt / 2, 28 * mt / 2
    rb1, rb2 = r1 * math.cos(at), r2 * math.cos(at)
    ea = (math.sqrt((r1 + 5e-3) ** 2 - rb1 ** 2) + math.sqrt((r2 + 5e-3) ** 2 - rb2 ** 2)
          - (r1 + r2) * math.sin(at)) / (math.pi * mt * math.cos(at))
    assert g.contact_ratio == pytest.approx(ea, rel=1e-9)
    assert g.contact_ratio == pytest.approx(1.2371, abs=1e-4)
    assert g.total_contact_ratio == pytest.approx(ea + 2.24517, abs=1e-5)
    assert g.center_distance_m == pytest.approx(0.0061803399 * 61 / 2, rel=1e-8)   # 188.50 mm
    assert g.normal_module_m == 5e-3 and g.face_width_m == 0.060
    assert required_slots(g) == 4


def test_shifted_helical_meshing_equation():
    # ISO 21771: inv(alpha_wt) = inv(alpha_t) + 2 tan(alpha_n)(x1 + x2)/(z1 + z2); a_w = a cos(alpha_t)/cos(alpha_wt);
    # root radius r - m_n (h_a* + c* - x) and tip r + m_n (h_a* + x - k)
    pair = helical(beta_deg=20.0, z=(21, 40), mn=0.004, x=(0.3, 0.1))
    g = pair_geometry(pair)
    b, an = math.radians(20), math.radians(20)
    at = math.atan(math.tan(an) / math.cos(b))
    inv_w = math.tan(at) - at + 2 * math.tan(an) * 0.4 / 61
    assert float(involute(g.alpha_w_rad)) == pytest.approx(inv_w, rel=1e-12)
    a = 0.004 * 61 / (2 * math.cos(b))
    assert g.center_distance_m == pytest.approx(a * math.cos(at) / math.cos(g.alpha_w_rad), rel=1e-12)
    r1 = 0.004 * 21 / (2 * math.cos(b))
    assert g.rf1_m == pytest.approx(r1 - 0.004 * (1.25 - 0.3), rel=1e-12)
    k = 0.4 - (g.center_distance_m - a) / 0.004
    assert g.ra1_m == pytest.approx(r1 + 0.004 * (1.0 + 0.3 - k), rel=1e-12)
    # spur is left unchanged by the transverse reduction
    spur = replace(pair, pinion=replace(pair.pinion, helix_angle_rad=0.0), gear=replace(pair.gear, helix_angle_rad=0.0))
    assert transverse_equivalent(spur) is spur
    assert pair_geometry(spur).overlap_ratio == 0.0 and not pair_geometry(spur).is_helical


def test_bad_helical_input_names_the_field():
    p = helical()
    with pytest.raises(GeometryError, match="gear.helix_hand"):
        pair_geometry(replace(p, gear=replace(p.gear, helix_hand="right")))
    with pytest.raises(GeometryError, match="gear.helix_angle_rad"):
        pair_geometry(replace(p, gear=replace(p.gear, helix_angle_rad=0.5)))
    with pytest.raises(GeometryError, match="pinion.helix_angle_rad"):
        pair_geometry(replace(p, pinion=replace(p.pinion, helix_angle_rad=float("nan"))))
    with pytest.raises(GeometryError, match="pinion.helix_hand"):
        pair_geometry(replace(p, pinion=replace(p.pinion, helix_hand="up")))
    text = SEED001.read_text().replace("helix_angle_deg = 36.0", "helix_angle_deg = 50.0")
    with pytest.raises(SceneError) as ei:
        load_scene(text)
    assert any(path == "gears.helix_angle_deg" for path, _ in ei.value.problems)


# ------------------------------------------------------------------ stiffness
@pytest.mark.parametrize("beta_deg", [20.0, 30.0, 36.0])
def test_mean_mesh_stiffness_against_iso_6336(beta_deg):
    # ISO's c_gamma_alpha (mean transverse mesh stiffness per unit face width; c_gamma_beta = 0.85 c_gamma_alpha
    # is ISO's value for the face load factor, not a mean mesh stiffness) is an empirical band: +-25 % as for
    # spur pairs (docs/physics_stiffness.md).  Measured: 20 deg +9.9 %, 30 deg +5.4 %, 36 deg (seed 001) +1.6 %.
    pair = helical(beta_deg)
    g = pair_geometry(pair)
    st = slot_stiffness(pair, g, MeshModelOptions(slices=20), None, 64)
    km = st.k_total_N_per_m.mean() / g.face_width_m / 1e9
    assert km == pytest.approx(iso_c_gamma_alpha(g), rel=0.25), (km, iso_c_gamma_alpha(g))
    if beta_deg == 36.0:
        # the transverse-section beam (oblique cut, ~1/cos^3 beta too thick) misses ISO by ~+54 %: why the
        # slice stiffness is taken on the normal section (docs/helical.md)
        tr = helical_slot_stiffness(pair, g, MeshModelOptions(slices=20), None, 64, section="transverse")
        assert tr.k_total_N_per_m.mean() / g.face_width_m / 1e9 > 1.4 * iso_c_gamma_alpha(g)


def test_helical_fluctuates_far_less_than_spur_of_same_transverse_geometry():
    pair = helical()
    g = pair_geometry(pair)
    spur = transverse_equivalent(pair)        # the same transverse section, straight teeth
    ks = slot_stiffness(spur, None, MeshModelOptions(), None, 128).k_total_N_per_m
    kh = slot_stiffness(pair, g, MeshModelOptions(slices=60), None, 128).k_total_N_per_m
    f_spur = (ks.max() - ks.min()) / ks.mean()
    f_hel = (kh.max() - kh.min()) / kh.mean()
    # measured: spur 0.676 (single/double contact jumps, eps_alpha = 1.237), helical (60 slices) 0.060
    assert f_spur > 0.3
    assert f_hel < 0.2 * f_spur, (f_spur, f_hel)


def test_integer_overlap_ratio_nearly_removes_the_fluctuation():
    beta = math.radians(36.0)
    fl = {}
    for eb in (2.0, 2.5):
        pair = helical(b_m=eb * math.pi * 0.005 / math.sin(beta))
        g = pair_geometry(pair)
        assert g.overlap_ratio == pytest.approx(eb, rel=1e-12)
        for ns in (20, 40):
            k = slot_stiffness(pair, g, MeshModelOptions(slices=ns), None, 128).k_total_N_per_m
            fl[eb, ns] = (k.max() - k.min()) / k.mean()
    # eps_beta = 2: constant in the continuum limit; partly engaged slices (docs/helical.md "Slice
    # sawtooth") leave a residue of second order or better in the slice width (measured 1.2e-5 at
    # 20 slices, 9.6e-7 at 40; whole slices entering and leaving left 0.0625 and 0.0314)
    assert fl[2.0, 40] < 1e-4
    assert fl[2.0, 20] / fl[2.0, 40] >= 3.5
    # eps_beta = 2.5: a real fluctuation that does not vanish with finer slices (measured 0.049 at 40)
    assert fl[2.5, 40] > 100.0 * fl[2.0, 40]
    assert fl[2.5, 20] == pytest.approx(fl[2.5, 40], rel=0.01)


def test_slice_stagger_and_time_in_contact():
    pair = helical()
    g = pair_geometry(pair)
    ns, n = 12, 256
    st = helical_slot_stiffness(pair, g, MeshModelOptions(slices=ns), None, n)
    s = st.s_slice_m
    w = g.face_width_m / ns
    # adjacent slices of one pair, both wholly in contact: w tan(beta_b) apart along the line of action
    f = st.slice_contact_fraction
    both = (f[:, :-1, :] == 1.0) & (f[:, 1:, :] == 1.0)
    d = (s[:, :-1, :] - s[:, 1:, :])[both]
    np.testing.assert_allclose(d, w * math.tan(g.base_helix_angle_rad), rtol=1e-9)
    # every slice is engaged eps_alpha mesh periods per mesh period on average (partly engaged
    # slices count with their engaged share)
    engaged = f.sum(axis=(0, 2)) / s.shape[2]
    np.testing.assert_allclose(engaged, g.contact_ratio, atol=2.0 / n)
    assert np.all((st.k_per_slice_N_per_m > 0) == np.isfinite(s))
    np.testing.assert_allclose(st.k_N_per_m, st.k_per_slice_N_per_m.sum(axis=1), rtol=1e-12)
    # lags: y_n tan(beta_b)/p_bt with y_n at the slice centres
    np.testing.assert_allclose(slice_lag_mesh_periods(g, ns),
                               (np.arange(ns) + 0.5) * w * math.tan(g.base_helix_angle_rad) / g.base_pitch_m)


def test_slots_from_total_contact_ratio():
    pair = helical()
    g0 = pair_geometry(pair)
    # face width making eps_gamma exactly 3: ceil gives 3, the integer rule one more
    b3 = (3.0 - g0.contact_ratio) * math.pi * 0.005 / math.sin(math.radians(36))
    g3 = pair_geometry(helical(b_m=b3))
    assert g3.total_contact_ratio == pytest.approx(3.0, abs=1e-12)
    assert required_slots(g3) == 4
    with pytest.raises(StiffnessError, match="slots"):
        helical_slot_stiffness(pair, g0, MeshModelOptions(slices=4), 3, 32)
    with pytest.raises(StiffnessError, match="section"):
        helical_slot_stiffness(pair, g0, MeshModelOptions(slices=4), None, 32, section="oblique")


# ------------------------------------------------------------------ errors
def test_slices_see_their_own_roll_position_in_the_pair_error():
    # pinion profile slope deviation f_Ha = 10 um (seed 003 eq 15, linear in roll length over s_A..s_E)
    from gearfmu.gear.gearpair import GearDeviations, ToothDeviation
    pair = helical()
    pair = replace(pair, pinion=replace(pair.pinion, deviations=GearDeviations(ToothDeviation(profile_slope_m=10e-6))))
    g = pair_geometry(pair)
    ns, n = 8, 64
    st = helical_slot_stiffness(pair, g, MeshModelOptions(slices=ns), None, n)
    e_sl = slot_slice_errors_m(pair, g, 4, 4, n, ns)
    # eq 15 by hand at each slice's contact position
    want = 10e-6 * (st.s_slice_m - g.s_start_m) / (g.s_end_m - g.s_start_m)
    on = np.isfinite(st.s_slice_m)
    np.testing.assert_allclose(e_sl[on], want[on], rtol=1e-9, atol=1e-15)
    e_pair = stiffness_weighted_pair_error_m(e_sl, st.k_per_slice_N_per_m)
    k = st.k_per_slice_N_per_m
    j = np.argmax(on.sum(axis=1).ravel())          # a (slot, angle) with many slices engaged
    p, i = np.unravel_index(j, on.sum(axis=1).shape)
    wk = np.where(on, want, 0.0)
    assert e_pair[p, i] == pytest.approx(np.sum(k[p, :, i] * wk[p, :, i]) / np.sum(k[p, :, i]), rel=1e-12)
    # spur: every slice sees the pair's position
    spur = transverse_equivalent(pair)
    gs = pair_geometry(spur)
    np.testing.assert_array_equal(slot_slice_errors_m(spur, gs, 2, 2, n, 3)[:, 1, :], slot_errors_m(spur, gs, 2, 2, n))


# ------------------------------------------------------------------ tables and FMU
def test_seed001_scene_tables_and_fmu_agree_with_native(tmp_path):
    from gearfmu.fmu.compare import output_names, validate_fmu_against_native
    from gearfmu.pipeline import build, gear_torque_for

    scene = load_scene(SEED001)
    assert scene.pair.pinion.helix_angle_rad == pytest.approx(math.radians(36))
    assert scene.pair.gear.helix_hand == "left" and scene.pair.pinion.helix_hand == "right"
    res = build(scene, tmp_path / "seed001.fmu")
    t = res.tables
    g = pair_geometry(scene.pair)
    assert t.slots == 4 and t.contact_ratio == pytest.approx(g.total_contact_ratio)
    # mean of the tables' total stiffness (whole table period) against k_mean, the exact mean of the
    # lookup with the contact-zone edges (docs/tables.md): the two differ only in the edge cells, by
    # a second-order term, and a helical pair's stiffness rises from nearly zero at its edges (the
    # contact line enters over the face width), so they agree far inside 5e-5 (measured 4.5e-6)
    ks = t.k_N_per_m[0].sum(axis=0)
    assert t.k_mean_N_per_m == pytest.approx(ks.mean(), rel=5e-5)
    assert (ks.max() - ks.min()) / ks.mean() < 0.15
    t1 = scene.operating.torque_Nm
    rep = validate_fmu_against_native(
        res.fmu_path, t,
        native_kwargs=dict(max_step_s=res.max_step_s, pinion_torque_Nm=t1,
                           gear_torque_Nm=gear_torque_for(t, t1),
                           pinion_speed_start_rad_s=scene.operating.speed_rad_s,
                           damping_ratio=scene.fmu.damping_ratio, damping_model=scene.solver.damping_model),
        stop_time_s=0.01, comm_step_s=scene.fmu.output_interval_s)
    assert rep["fmpy_problems"] == []
    assert set(rep["outputs"]) == set(output_names(4))
    worst = {k: v["rel_max_diff"] for k, v in rep["outputs"].items()}
    assert max(worst.values()) <= 1e-9, worst
    assert rep["outputs"]["pair_force[1]"]["range"] > 0
