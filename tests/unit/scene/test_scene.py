"""Tests of the scene file format (gearfmu.scene.reader).

References (no number below was produced by gearfmu):
* seed 000 Table 1, seed 003 Table 1, seed 004 Tables 1, 4 and 5 (cited in full in docs/references.md);
* textbook involute relations (ISO 21771: r = m z/2, rb = r cos(alpha),
  ra = r + m (ha* + x - k), rf = r - m (ha* + c* - x), inv(alpha_w) equation,
  contact ratio from the tip radii), solved here with scipy.optimize.brentq;
* ISO/TR 10064-2 minimum normal backlash (2/3)(0.06 + 0.0005 a + 0.03 m) mm;
* hand arithmetic (2000 rpm = 2000 * 2 pi / 60 rad/s; 80 kW / 2000 rpm);
* the Walther equation of ASTM D341 with hand-computed constants;
* tomllib (the standard-library TOML reader) for the TOML writer round trip.
"""
from __future__ import annotations

import math
import re
import tomllib
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from gearfmu.gear.gearpair import GearDeviations, ToothDeviation
from gearfmu.scene.drivetrain import is_drivetrain_file
from gearfmu.scene.reader import (SCHEMA, Scene, SceneError, default_scene_path, dumps_toml, load_scene,
                           walther_kinematic_viscosity_cSt)

ROOT = Path(__file__).resolve().parents[3]
#: the example pair scenes (a drivetrain scene, with a top-level [drivetrain] table, is read by
#: gearfmu.scene.drivetrain: tests/unit/scene/test_drivetrain_scene.py)
SCENES = sorted(p for p in (ROOT / "examples" / "scenes").glob("*.toml") if not is_drivetrain_file(p))
DEFAULT_TEXT = default_scene_path().read_text(encoding="utf-8")
DEG = math.pi / 180.0


def inv(a):
    return math.tan(a) - a


def operating_center_distance(m, z1, z2, x1, x2, alpha=20 * DEG):
    """Zero-backlash centre distance from inv(alpha_w) = inv(alpha) + 2 tan(alpha)(x1+x2)/(z1+z2) (ISO 21771)."""
    target = inv(alpha) + 2 * math.tan(alpha) * (x1 + x2) / (z1 + z2)
    alpha_w = brentq(lambda a: inv(a) - target, 1e-3, 1.2, xtol=1e-15)
    return m * (z1 + z2) / 2 * math.cos(alpha) / math.cos(alpha_w)


def problems_of(text) -> SceneError:
    with pytest.raises(SceneError) as info:
        load_scene(text)
    return info.value


# ------------------------------------------------------------------ shipped scenes
def test_examples_present():
    names = {p.name for p in SCENES}
    assert {"seed000_table1.toml", "seed003_table1.toml", "seed004_pair1.toml", "seed004_pair2.toml"} <= names


@pytest.mark.parametrize("path", SCENES + [default_scene_path()], ids=lambda p: p.name)
def test_every_shipped_scene_loads(path):
    scene = load_scene(path)
    assert isinstance(scene, Scene)
    assert scene.text == path.read_text(encoding="utf-8")
    assert scene.source_path == str(path)
    assert re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", scene.fmu.model_name)
    assert len(scene.sha256) == 64


def test_default_scene_is_seed000_table1():
    """Seed 000 Table 1: z 45/34, m 6 mm, b 44 mm, r_int 81.5/80 mm, alpha 20 deg, x 0.37/0.34,
    ha* 1, c* 0.25, E 207 GPa, nu 0.29, 2000 N*m, 2000 rpm; the task's f_fa 15 um, f_r 2 on the pinion."""
    s = load_scene(None)
    p, g = s.pair.pinion, s.pair.gear
    assert (p.teeth, g.teeth) == (45, 34)
    assert p.module_m == 0.006 and g.module_m == 0.006
    assert p.face_width_m == 0.044
    assert (p.hub_radius_m, g.hub_radius_m) == (0.0815, 0.080)
    assert p.pressure_angle_rad == pytest.approx(math.pi / 9, rel=1e-15)
    assert (p.profile_shift, g.profile_shift) == (0.37, 0.34)
    assert (p.addendum_coefficient, p.tip_clearance_coefficient) == (1.0, 0.25)
    assert p.material.youngs_modulus_Pa == 207e9 and g.material.poisson_ratio == 0.29
    assert s.operating.torque_Nm == 2000.0
    assert s.operating.speed_rad_s == pytest.approx(2000 * 2 * math.pi / 60, rel=1e-15)
    assert s.mesh.contact_model == "hertz" and s.mesh.slices == 44  # 1 mm slices
    assert p.deviations.default == ToothDeviation(profile_form_m=15e-6, form_periods=2.0)
    assert p.deviations.per_tooth == ()
    assert g.deviations.is_zero
    assert s.fmu.damping_ratio == 0.05
    assert 0.04 <= s.fmu.stop_time_s <= 0.06 and s.fmu.output_interval_s == pytest.approx(2e-5)
    # the shipped example is the same scene
    assert load_scene(ROOT / "examples/scenes/seed000_table1.toml").pair == s.pair


def test_default_backlash_follows_iso_tr_10064_2():
    """j_bn,min = (2/3)(0.06 + 0.0005 a + 0.03 m) mm with a the operating centre distance."""
    s = load_scene(None)
    a_mm = operating_center_distance(6.0, 45, 34, 0.37, 0.34)
    assert a_mm == pytest.approx(241.02, abs=0.01)
    jn_mm = 2 / 3 * (0.06 + 0.0005 * a_mm + 0.03 * 6.0)
    assert s.pair.backlash_m * 1e3 == pytest.approx(jn_mm, abs=0.001)


def test_seed003_scene_reproduces_table1():
    """Seed 003 Table 1: outer diameter 156 mm, root diameter 140.68 mm, base diameter 140.95 mm,
    centre distance 150 mm, contact ratio 1.7547, backlash 0.145 mm (transverse) = 0.136 mm on the LOA."""
    s = load_scene(ROOT / "examples/scenes/seed003_table1.toml")
    p = s.pair.pinion
    m, z, x = p.module_m * 1e3, p.teeth, p.profile_shift
    alpha = p.pressure_angle_rad
    d_tip = m * (z + 2 * p.addendum_coefficient + 2 * x)
    d_root = m * (z - 2 * p.addendum_coefficient - 2 * p.tip_clearance_coefficient + 2 * x)
    d_base = m * z * math.cos(alpha)
    assert d_tip == pytest.approx(156.0, abs=1e-9)
    assert d_root == pytest.approx(140.68, abs=0.005)
    assert d_base == pytest.approx(140.95, abs=0.005)
    a = s.pair.center_distance_m * 1e3
    assert a == 150.0
    # textbook transverse contact ratio of two equal gears at a = 150 mm
    ra, rb = d_tip / 2, d_base / 2
    eps = (2 * math.sqrt(ra ** 2 - rb ** 2) - a * math.sin(alpha)) / (math.pi * m * math.cos(alpha))
    assert eps == pytest.approx(1.7547, abs=1e-4)
    # 0.145 mm circumferential backlash times cos(alpha) is the LOA backlash 0.136 mm (total play)
    assert s.pair.backlash_m * 1e3 == pytest.approx(0.145 * math.cos(alpha), abs=0.001)
    assert s.pair.backlash_m == pytest.approx(136e-6, rel=1e-12)
    assert (p.inertia_kgm2, s.pair.gear.inertia_kgm2) == (0.0074, 0.0074)
    assert p.material.youngs_modulus_Pa == 206e9 and p.material.poisson_ratio == 0.3
    assert s.operating.torque_Nm == 340.0 and s.fmu.damping_ratio == 0.02
    assert s.pair.pinion.deviations.is_zero and s.pair.gear.deviations.is_zero


def test_seed004_pair1_reproduces_table1_and_table4_load():
    """Seed 004 Table 1 pair I: a 93 mm, r 40.5/52.5, ra 43.5/55.5, rb 38.06/49.33 mm, h 6.75 mm;
    Table 4: 80 kW at 2000 rpm -> T1 = 80e3 / (2000 * 2 pi / 60) = 381.97 N*m."""
    s = load_scene(ROOT / "examples/scenes/seed004_pair1.toml")
    p, g = s.pair.pinion, s.pair.gear
    m = p.module_m * 1e3
    assert (p.teeth, g.teeth, m, s.pair.pinion.face_width_m) == (27, 35, 3.0, 0.025)
    assert operating_center_distance(m, 27, 35, p.profile_shift, g.profile_shift) == pytest.approx(93.0, abs=1e-9)
    for gs, r_tab, ra_tab, rb_tab in ((p, 40.5, 43.5, 38.06), (g, 52.5, 55.5, 49.33)):
        r = m * gs.teeth / 2
        assert r == pytest.approx(r_tab, abs=1e-12)
        assert r + m * (gs.addendum_coefficient + gs.profile_shift) == pytest.approx(ra_tab, abs=1e-9)
        assert r * math.cos(gs.pressure_angle_rad) == pytest.approx(rb_tab, abs=0.005)
        assert m * (2 * gs.addendum_coefficient + gs.tip_clearance_coefficient) == pytest.approx(6.75, abs=1e-9)
    assert s.operating.torque_Nm == pytest.approx(80e3 / (2000 * 2 * math.pi / 60), abs=0.005)
    assert s.operating.speed_rad_s == pytest.approx(2000 * 2 * math.pi / 60, rel=1e-15)
    assert p.material.thermal_expansion_per_K == 1.13e-5  # seed 004 section 4
    lub = s.lubricant
    assert lub is not None and lub.density_kg_m3 == 870.0 and lub.temperature_C == 60.0  # Table 4


def test_seed004_pair2_reproduces_table1():
    """Seed 004 Table 1 pair II: m 4.5, z 16/24, x 0.8532/-0.5, b 20, a 91.5 mm, operating pitch
    radii 36.60/54.90, tip radii 44.25/56.16, base radii 33.83/50.74, tooth height 10.04 mm."""
    s = load_scene(ROOT / "examples/scenes/seed004_pair2.toml")
    p, g = s.pair.pinion, s.pair.gear
    m = p.module_m * 1e3
    assert (p.teeth, g.teeth, m, p.face_width_m) == (16, 24, 4.5, 0.020)
    assert (p.profile_shift, g.profile_shift) == (0.8532, -0.5)
    a_w = operating_center_distance(m, 16, 24, p.profile_shift, g.profile_shift)
    assert a_w == pytest.approx(91.5, abs=0.001)
    assert a_w * 16 / 40 == pytest.approx(36.60, abs=0.005) and a_w * 24 / 40 == pytest.approx(54.90, abs=0.005)
    k = (p.profile_shift + g.profile_shift) - (a_w - m * 20) / m  # tip shortening (ISO 21771)
    for gs, ra_tab, rb_tab in ((p, 44.25, 33.83), (g, 56.16, 50.74)):
        r = m * gs.teeth / 2
        ra = r + m * (gs.addendum_coefficient + gs.profile_shift - k)
        rf = r - m * (gs.addendum_coefficient + gs.tip_clearance_coefficient - gs.profile_shift)
        assert ra == pytest.approx(ra_tab, abs=0.005)
        assert r * math.cos(20 * DEG) == pytest.approx(rb_tab, abs=0.005)
        if gs is p:
            assert ra - rf == pytest.approx(10.04, abs=0.005)
    assert s.operating.torque_Nm == 138.0 and s.operating.speed_rpm == pytest.approx(900.0, rel=1e-14)
    assert s.operating.torque_range_Nm == (14.0, 138.0)  # Table 5 load levels


# ------------------------------------------------------------------ unit conversion
def test_unit_conversions_spot_checks():
    s = load_scene(DEFAULT_TEXT)
    assert s.pair.pinion.module_m == 0.006  # 6 mm
    assert s.operating.speed_rad_s == pytest.approx(209.4395102, abs=1e-7)  # 2000 * 2 pi / 60
    assert s.pair.pinion.deviations.default.profile_form_m == 15e-6  # 15 um
    assert s.pair.backlash_m == 240e-6
    assert s.pair.pinion.material.youngs_modulus_Pa == 207e9  # GPa
    assert s.pair.pinion.pressure_angle_rad == pytest.approx(0.3490658504, abs=1e-10)  # 20 deg
    assert s.lubricant.pressure_viscosity_Pa_inv == pytest.approx(2e-8, rel=1e-15)  # 20 1/GPa
    assert s.lubricant.kinematic_viscosity_40C_m2_s == pytest.approx(320e-6, rel=1e-15)  # cSt = mm^2/s


def test_walther_viscosity_law():
    """ASTM D341 Walther: log10 log10(nu + 0.7) = A - B log10(T/K); for 320 / 38.5 cSt at 40 / 100 degC
    by hand: A = 6.84743, B = 2.58376, so at 60 degC nu = 10^10^(A - B log10 333.15) - 0.7 = 135.96 cSt."""
    assert walther_kinematic_viscosity_cSt(320.0, 38.5, 40.0) == pytest.approx(320.0, rel=1e-12)
    assert walther_kinematic_viscosity_cSt(320.0, 38.5, 100.0) == pytest.approx(38.5, rel=1e-12)
    assert walther_kinematic_viscosity_cSt(320.0, 38.5, 60.0) == pytest.approx(135.96, abs=0.02)
    lub = load_scene(None).lubricant
    assert lub.dynamic_viscosity_Pas == pytest.approx(135.96e-6 * 870.0, rel=2e-4)
    with pytest.raises(ValueError):
        walther_kinematic_viscosity_cSt(38.5, 320.0, 60.0)


# ------------------------------------------------------------------ deviations
def test_per_tooth_overrides_and_pitch_lists_land_in_gear_deviations():
    pitch = [((i * 7) % 5 - 2) * 1.5 for i in range(34)]  # um, one per gear tooth
    text = DEFAULT_TEXT.replace("[deviations.gear]", """
[[deviations.pinion.tooth]]
index = 3
profile_form_um = 25.0
[[deviations.pinion.tooth]]
index = 44
profile_slope_um = -4.0
form_periods = 3.0
pitch_um = 6.0

[deviations.gear]
lead_crowning_um = 8.0
pitch_um = [""" + ", ".join(repr(v) for v in pitch) + "]\n")
    s = load_scene(text)
    dp: GearDeviations = s.pair.pinion.deviations
    assert dp.tooth(3) == ToothDeviation(profile_form_m=25e-6, form_periods=2.0)
    assert dp.tooth(44) == ToothDeviation(profile_form_m=15e-6, profile_slope_m=-4e-6, form_periods=3.0,
                                          pitch_m=6e-6)
    assert dp.tooth(10) == dp.default == ToothDeviation(profile_form_m=15e-6, form_periods=2.0)
    assert [i for i, _ in dp.per_tooth] == [3, 44] and dp.teeth_differ
    dg = s.pair.gear.deviations
    assert dg.lead_crowning_m == 8e-6
    for i in range(34):
        assert dg.tooth(i).pitch_m == pytest.approx(pitch[i] * 1e-6, rel=1e-15, abs=0)
    assert sorted(i for i, _ in dg.per_tooth) == [i for i in range(34) if pitch[i] != 0.0]


def test_deviation_errors_name_the_row():
    text = DEFAULT_TEXT.replace("[deviations.gear]", """
pitch_um = [1.0, 2.0]
[[deviations.pinion.tooth]]
index = 45
[[deviations.pinion.tooth]]
index = 2
profile_frm_um = 3.0
[[deviations.pinion.tooth]]
index = 2
[deviations.gear]
""")
    e = problems_of(text)
    paths = [p for p, _ in e.problems]
    assert "deviations.pinion.pitch_um" in paths  # 2 values for 45 teeth
    assert "deviations.pinion.tooth[0].index" in paths  # 45 is not in [0, 44]
    assert "deviations.pinion.tooth[1].profile_frm_um" in paths
    assert "deviations.pinion.tooth[2].index" in paths  # duplicate
    assert "did you mean 'profile_form_um'" in str(e)
    assert "one value per tooth (45)" in str(e)


# ------------------------------------------------------------------ errors
def test_unknown_key_with_unit_hint():
    e = problems_of(DEFAULT_TEXT.replace("module_mm = 6.0", "module_m = 0.006"))
    assert "gears.module_m: unknown key; did you mean 'module_mm'? (this key is in mm)" in str(e)
    assert ("gears.module_mm", "missing (required)") in e.problems
    e = problems_of(DEFAULT_TEXT.replace("speed_rpm = 2000.0", "speed_rad_s = 209.4"))
    assert "operating.speed_rad_s: unknown key; did you mean 'speed_rpm'?" in str(e)
    e = problems_of(DEFAULT_TEXT.replace("slices = 44", "slics = 44"))
    assert "mesh.slics: unknown key; did you mean 'slices'?" in str(e)
    e = problems_of(DEFAULT_TEXT + "\n[roughnes]\nlevel = 1\n")
    assert e.problems == [("roughnes", "unknown key; did you mean 'roughness'?")]  # [roughness] exists (docs/ehl_mesh.md)


def test_wrong_type_and_out_of_range_name_the_key_path():
    e = problems_of(DEFAULT_TEXT.replace("teeth = 45", "teeth = 3.5"))
    assert str(e).startswith("gears.pinion.teeth: must be an integer in [5, 1000], got 3.5")
    e = problems_of(DEFAULT_TEXT.replace("teeth = 45", 'teeth = "45"'))
    assert e.problems == [("gears.pinion.teeth", "must be an integer in [5, 1000], got the string '45'")]
    e = problems_of(DEFAULT_TEXT.replace("teeth = 45", "teeth = 4"))
    assert e.problems[0][0] == "gears.pinion.teeth"
    e = problems_of(DEFAULT_TEXT.replace("pressure_angle_deg = 20.0", "pressure_angle_deg = 35.0"))
    assert e.problems == [("gears.pressure_angle_deg", "must be a number in (10, 35), got 35.0")]
    e = problems_of(DEFAULT_TEXT.replace("face_width_mm = 44.0", "face_width_mm = -44.0"))
    assert e.problems[0][0] == "gears.face_width_mm" and "got -44.0" in e.problems[0][1]
    e = problems_of(DEFAULT_TEXT.replace("foundation = true", 'foundation = "yes"'))
    assert e.problems[0] == ("mesh.foundation", "must be true or false, got the string 'yes'")
    e = problems_of(DEFAULT_TEXT.replace('contact_model = "hertz"', 'contact_model = "hertzian"'))
    assert e.problems[0][0] == "mesh.contact_model" and "did you mean 'hertz'" in e.problems[0][1]
    e = problems_of(DEFAULT_TEXT.replace("torque_Nm = 2000.0", "torque_Nm = nan"))
    assert e.problems[0][0] == "operating.torque_Nm" and "finite" in e.problems[0][1]
    e = problems_of(DEFAULT_TEXT.replace('model_name = "GearPairSeed000"', 'model_name = "9 lives"'))
    assert e.problems[0][0] == "fmu.model_name"
    e = problems_of(DEFAULT_TEXT.replace("[gears.gear]", "[gears.unused]\na = 1\n\n[gears.gear]")
                    .replace("hub_radius_mm = 80.0", "hub_radius_mm = 0.0"))
    assert {p for p, _ in e.problems} == {"gears.gear.hub_radius_mm", "gears.unused"}


def test_hub_radius_must_be_inside_the_root_circle():
    # gear root radius by hand: 6 (34/2 - 1 - 0.25 + 0.34) = 96.54 mm
    e = problems_of(DEFAULT_TEXT.replace("hub_radius_mm = 80.0", "hub_radius_mm = 96.6"))
    assert e.problems == [("gears.gear.hub_radius_mm", "must be smaller than the root radius 96.54 mm, got 96.6")]
    load_scene(DEFAULT_TEXT.replace("hub_radius_mm = 80.0", "hub_radius_mm = 96.5"))


def test_several_problems_are_all_listed():
    text = (DEFAULT_TEXT.replace("teeth = 45", 'teeth = "45"')
            .replace("pressure_angle_deg = 20.0", "pressure_angle_deg = 40.0")
            .replace("slices = 44", "slics = 44")
            .replace("damping_ratio = 0.05", "damping_ratio = -0.1")
            .replace("output_interval_s = 2e-5", "output_interval_s = 1.0"))
    e = problems_of(text)
    paths = {p for p, _ in e.problems}
    assert paths == {"gears.pinion.teeth", "gears.pressure_angle_deg", "mesh.slics", "fmu.damping_ratio",
                     "fmu.output_interval_s"}
    msg = str(e)
    assert msg.startswith("5 problems in scene 'seed000_table1':")
    for p in paths:
        assert f"  - {p}: " in msg


def test_missing_tables_and_required_keys():
    e = problems_of(re.sub(r"\[operating\][^\[]*", "", DEFAULT_TEXT))
    assert ("operating", "missing table (required)") in e.problems
    e = problems_of(DEFAULT_TEXT.replace("teeth = 34\n", ""))
    assert ("gears.gear.teeth", "missing (required)") in e.problems


def test_impossible_gears_are_reported_with_the_key_path():
    # contact ratio < 1: ha* = 0.3 on both gears.  Hand check (textbook, ra = r + m (ha* + x - k)):
    text = DEFAULT_TEXT.replace("addendum_coefficient = 1.0", "addendum_coefficient = 0.3")
    a_w = operating_center_distance(6.0, 45, 34, 0.37, 0.34)
    k = 0.71 - (a_w - 237.0) / 6.0
    ra1, ra2 = 135.0 + 6 * (0.3 + 0.37 - k), 102.0 + 6 * (0.3 + 0.34 - k)
    rb1, rb2 = 135.0 * math.cos(20 * DEG), 102.0 * math.cos(20 * DEG)
    alpha_w = math.acos((rb1 + rb2) / a_w)
    eps = (math.sqrt(ra1 ** 2 - rb1 ** 2) + math.sqrt(ra2 ** 2 - rb2 ** 2) - a_w * math.sin(alpha_w)) / (
        math.pi * 6 * math.cos(20 * DEG))
    assert eps < 1.0
    e = problems_of(text)
    assert len(e.problems) == 1
    path, reason = e.problems[0]
    assert path.startswith("gears") and "contact ratio" in reason

    # undercut: z = 12, x = 0 < x_min = 1 - 12 sin^2(20 deg)/2 = 0.298 (textbook: z_min = 17 at 20 deg)
    text = (DEFAULT_TEXT.replace("teeth = 45", "teeth = 12").replace("profile_shift = 0.37", "profile_shift = 0.0")
            .replace("profile_shift = 0.34", "profile_shift = 0.0").replace("hub_radius_mm = 81.5", "hub_radius_mm = 10.0"))
    e = problems_of(text)
    assert e.problems[0][0] == "gears.pinion.profile_shift" and "undercut" in e.problems[0][1]

    # pointed tip: z = 12, x = 1.5 (mate x = -1.0).  Hand check of the tip thickness
    # s_a = 2 ra (pi/(2z) + 2 x tan(alpha)/z + inv(alpha) - inv(alpha_a)) with the tip shortening k.
    text = (DEFAULT_TEXT.replace("teeth = 45", "teeth = 12").replace("profile_shift = 0.37", "profile_shift = 1.5")
            .replace("profile_shift = 0.34", "profile_shift = -1.0").replace("hub_radius_mm = 81.5", "hub_radius_mm = 10.0"))
    a_w = operating_center_distance(6.0, 12, 34, 1.5, -1.0)
    k = max(0.0, 0.5 - (a_w - 138.0) / 6.0)
    ra = 36.0 + 6 * (1.0 + 1.5 - k)
    rb = 36.0 * math.cos(20 * DEG)
    s_a = 2 * ra * (math.pi / 24 + 2 * 1.5 * math.tan(20 * DEG) / 12 + inv(20 * DEG) - inv(math.acos(rb / ra)))
    assert s_a < 0
    e = problems_of(text)
    assert e.problems[0][0] == "gears.pinion.profile_shift" and "pointed" in e.problems[0][1]

    # centre distance below the base-circle sum 237 cos(20 deg) = 222.7 mm
    e = problems_of(DEFAULT_TEXT.replace("backlash_um = 240.0", "backlash_um = 240.0\ncenter_distance_mm = 200.0"))
    assert e.problems[0][0] == "gears.center_distance_mm"


def test_contact_models_and_lubricant_rules():
    for model in ("smooth_ehl", "rough_ehl", "fractal_mixed"):
        s = load_scene(DEFAULT_TEXT.replace('contact_model = "hertz"', f'contact_model = "{model}"'))
        assert s.mesh.contact_model == model
    no_lub = DEFAULT_TEXT[:DEFAULT_TEXT.index("[lubricant]")]
    assert load_scene(no_lub).lubricant is None
    e = problems_of(no_lub.replace('contact_model = "hertz"', 'contact_model = "rough_ehl"'))
    assert e.problems[0][0] == "lubricant" and "rough_ehl" in e.problems[0][1]
    e = problems_of(DEFAULT_TEXT + "eta0_Pas = 0.1\n")
    assert e.problems[0][0] == "lubricant" and "not both" in e.problems[0][1]
    s = load_scene(DEFAULT_TEXT.replace("kinematic_viscosity_40C_cSt = 320.0\nkinematic_viscosity_100C_cSt = 38.5",
                                        "eta0_Pas = 0.1"))
    assert s.lubricant.dynamic_viscosity_Pas == 0.1
    e = problems_of(DEFAULT_TEXT.replace("kinematic_viscosity_100C_cSt = 38.5", "kinematic_viscosity_100C_cSt = 400.0"))
    assert e.problems[0][0] == "lubricant.kinematic_viscosity_100C_cSt"


def test_operating_ranges_and_torque_axis():
    text = DEFAULT_TEXT.replace("speed_rpm = 2000.0", "speed_rpm = 2000.0\ntorque_range_Nm = [500.0, 2500.0]")
    s = load_scene(text.replace("torque_points = 1", "torque_points = 5"))
    assert s.torque_axis_Nm == (500.0, 1000.0, 1500.0, 2000.0, 2500.0)  # hand: 500 + 500 i
    assert s.operating.torque_axis_Nm() == s.torque_axis_Nm
    assert s.operating.torque_axis_Nm(3) == (500.0, 1500.0, 2500.0)
    assert load_scene(text).torque_axis_Nm == (2000.0,)
    e = problems_of(DEFAULT_TEXT.replace("torque_points = 1", "torque_points = 5"))
    assert e.problems[0][0] == "tables.torque_points"
    e = problems_of(DEFAULT_TEXT.replace("speed_rpm = 2000.0", "speed_rpm = 2000.0\nspeed_range_rpm = [3000.0, 4000.0]"))
    assert e.problems[0][0] == "operating.speed_rpm" and "outside" in e.problems[0][1]
    e = problems_of(DEFAULT_TEXT.replace("speed_rpm = 2000.0", "speed_rpm = 2000.0\nspeed_range_rpm = [4000.0, 3000.0]"))
    assert e.problems[0][0] == "operating.speed_range_rpm"
    s = load_scene(DEFAULT_TEXT.replace('slots = "auto"', "slots = 3").replace('max_step_s = "auto"', "max_step_s = 1e-6"))
    assert s.tables.slots == 3 and s.solver.max_step_s == 1e-6
    s = load_scene(DEFAULT_TEXT)
    assert s.tables.slots is None and s.solver.max_step_s is None and s.tables.points_per_mesh == 64


def test_bad_sources():
    e = problems_of("gears = [1, 2\n")
    assert e.problems[0][0] == "<toml>"
    with pytest.raises(SceneError, match="not found"):
        load_scene(ROOT / "examples/scenes/no_such_scene.toml")


def test_mapping_source_and_toml_writer_round_trip():
    """dumps_toml output read back by tomllib gives the same data."""
    data = tomllib.loads(DEFAULT_TEXT)
    data["deviations"]["pinion"]["tooth"] = [{"index": 1, "profile_form_um": 2.5}]
    data["scene"]["description"] = 'quote " backslash \\ tab \t newline \n del \x7f unicode \u00e9'
    text = dumps_toml(data)
    assert tomllib.loads(text) == data
    s = load_scene(data)
    assert s.text == text and s.pair.pinion.deviations.tooth(1).profile_form_m == 2.5e-6


def test_default_runtime_is_the_all_c_one_defined_once():
    """The default FMU runtime is the standalone (all-C) one; the default scene leaves it to
    the one definition (gearfmu.common.vocabulary.DEFAULT_RUNTIME), which FmuOptions and the [fmu] key share."""
    from gearfmu.scene.reader import DEFAULT_RUNTIME, FmuOptions

    assert DEFAULT_RUNTIME == "standalone"
    assert "runtime" not in tomllib.loads(DEFAULT_TEXT)["fmu"]
    assert load_scene(DEFAULT_TEXT).fmu.runtime == DEFAULT_RUNTIME == FmuOptions(model_name="x").runtime
    assert next(k for k in SCHEMA["fmu"] if k.name == "runtime").default == DEFAULT_RUNTIME
    data = tomllib.loads(DEFAULT_TEXT)
    data["fmu"]["runtime"] = "pythonfmu"
    assert load_scene(dumps_toml(data)).fmu.runtime == "pythonfmu"


def test_docs_document_every_key():
    doc = (ROOT / "docs" / "scene.md").read_text(encoding="utf-8")
    for table, keys in SCHEMA.items():
        assert f"[{table}]" in doc or f"[[{table}]]" in doc, table
        for k in keys:
            assert f"`{k.name}`" in doc, f"{table}.{k.name}"


# ------------------------------------------------------------------ property test
_BASE = tomllib.loads(DEFAULT_TEXT)
_KEY_NAME = st.text(alphabet="abcdefghijklmnopqrstuvwxyz_0123456789ABCmu", min_size=1, max_size=20)
_SCALAR = st.one_of(
    st.integers(min_value=-(2 ** 63), max_value=2 ** 63 - 1),
    st.floats(allow_nan=True, allow_infinity=True),
    st.booleans(),
    st.text(alphabet=st.characters(blacklist_categories=("Cs",)), max_size=12),
    st.sampled_from(["auto", "hertz", "rough_ehl", "rk4", "contact_zone", "seed003", "pythonfmu"]),
)
_VALUE = st.one_of(
    _SCALAR,
    st.lists(_SCALAR, max_size=4),
    st.lists(st.floats(min_value=-100, max_value=100), min_size=0, max_size=50),
    st.dictionaries(_KEY_NAME, _SCALAR, max_size=3),
    st.lists(st.dictionaries(st.sampled_from(["index", "profile_form_um", "pitch_um", "x"]), _SCALAR,
                             max_size=3), min_size=1, max_size=3),
)


def _paths(node, prefix=()):
    out = []
    if isinstance(node, dict):
        for k, v in node.items():
            out.append(prefix + (k,))
            out.extend(_paths(v, prefix + (k,)))
    return out


_PATHS = [()] + _paths(_BASE)


def _mutate(data, path, op, value, new_key):
    import copy
    d = copy.deepcopy(data)
    parent = d
    for k in path[:-1]:
        parent = parent[k]
    if op == "delete" and path:
        del parent[path[-1]]
    elif op == "set" and path:
        parent[path[-1]] = value
    else:  # add an extra key into the table at path (or at the top)
        target = parent[path[-1]] if path else d
        if isinstance(target, dict):
            target[new_key] = value
        elif path:
            parent[path[-1]] = value
    return d


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.sampled_from(_PATHS), st.sampled_from(["set", "delete", "add"]), _VALUE,
                          _KEY_NAME), min_size=1, max_size=3))
def test_random_mutations_are_accepted_or_rejected_with_a_key_path(mutations):
    data = _BASE
    for path, op, value, new_key in mutations:
        try:
            data = _mutate(data, path, op, value, new_key)
        except (KeyError, TypeError):  # an earlier mutation removed or replaced the parent
            continue
    text = dumps_toml(data)
    try:
        scene = load_scene(text)
    except SceneError as exc:
        assert exc.problems
        msg = str(exc)
        for key_path, reason in exc.problems:
            assert key_path and reason
            assert f"{key_path}: " in msg
            head = re.split(r"[.\[]", key_path)[0]
            assert head in SCHEMA or head in data, key_path
    else:
        assert isinstance(scene, Scene)
        assert scene.pair.pinion.teeth >= 5 and scene.pair.pinion.module_m > 0


def test_docs_example_loads():
    """The full example in docs/scene.md is a valid scene and gives what its comments say."""
    doc = (ROOT / "docs" / "scene.md").read_text(encoding="utf-8")
    block = re.search(r"## Example \(every section\)\s*```toml\n(.*?)```", doc, re.S).group(1)
    s = load_scene(block)
    assert s.torque_axis_Nm == (500.0, 1000.0, 1500.0, 2000.0, 2500.0)
    assert s.pair.gear.material.youngs_modulus_Pa == 210e9 and s.pair.pinion.material.youngs_modulus_Pa == 207e9
    assert s.pair.pinion.deviations.tooth(7) == ToothDeviation(25e-6, 0.0, 2.0, 4e-6)
    assert s.pair.gear.deviations.tooth(2).pitch_m == 2e-6


# ------------------------------------------------------------------ option vocabulary, renamed values
def _with_damping(value: str) -> str:
    data = tomllib.loads(DEFAULT_TEXT)
    data.setdefault("solver", {})["damping_model"] = value
    return dumps_toml(data)


def test_old_damping_spelling_warns_naming_the_new_one_and_reads_as_it():
    """damping_model = "seed003" (the paper's label) is the rule now spelled "contact_zone": the old
    spelling loads with a FutureWarning naming the key path and the new spelling, and gives the
    same scene; the new spelling loads without a warning."""
    with pytest.warns(FutureWarning, match=r"solver\.damping_model = 'seed003' is deprecated.*use 'contact_zone'"):
        old = load_scene(_with_damping("seed003"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        new = load_scene(_with_damping("contact_zone"))
    assert old.solver.damping_model == new.solver.damping_model == "contact_zone"
    assert old.solver == new.solver and old.pair == new.pair and old.fmu == new.fmu


def test_old_damping_spelling_runs_the_same_rule_in_the_solvers():
    """The native solver and the sweeps take the old spelling with the warning and give arrays
    identical to the new spelling's; the rule is the one that differs from elastobacklash inside
    the backlash (seed 003 eq 3-5: a pair in its contact zone is damped even while separated),
    on rectangular-wave tables with backlash (seed 003 Fig. 2 / eq 4-5)."""
    from gearfmu.dynamics.native import simulate
    from gearfmu.dynamics.sweeps import SweepJob
    from gearfmu.tables.synthetic import rectangular_wave_tables

    tb = rectangular_wave_tables(4e8, backlash_half_m=20e-6)
    kw = dict(stop_time_s=2e-3, comm_step_s=2e-5, max_step_s=2e-6, pinion_torque_Nm=50.0,
              pinion_speed_start_rad_s=150.0, damping_ratio=0.05, dte_start_m=0.0, dte_rate_start_m_s=0.02)
    with pytest.warns(FutureWarning, match="use 'contact_zone'"):
        old = simulate(tb, damping_model="seed003", **kw)
    new = simulate(tb, damping_model="contact_zone", **kw)
    other = simulate(tb, damping_model="elastobacklash", **kw)
    for name in ("dte", "mesh_force", "pair_force", "pinion_speed"):
        assert np.array_equal(getattr(old, name), getattr(new, name)), name
    assert not np.array_equal(new.dte, other.dte)  # the two rules are told apart by this case
    with pytest.warns(FutureWarning, match="use 'contact_zone'"):
        job = SweepJob(tb, omega_h=[0.5], pinion_torque_Nm=50.0, damping_ratio=0.05,
                       damping_model="seed003").validate()
    assert job.damping_model == "contact_zone"


@pytest.mark.parametrize("key,value", [("solver.damping_model", "seed004"), ("solver.integrator", "euler"),
                                       ("mesh.contact_model", "elastic"), ("thermal.oil_alpha", "walther")])
def test_unknown_option_value_is_one_line_naming_the_key_and_the_choices(key, value):
    """An unknown option value is one line: the key path, every allowed value (the vocabulary's,
    not the deprecated spellings), what was given."""
    from gearfmu.common import vocabulary

    table, name = key.split(".")
    data = tomllib.loads(DEFAULT_TEXT)
    data.setdefault(table, {})[name] = value
    with pytest.raises(SceneError) as exc:
        load_scene(dumps_toml(data))
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith(f"{key}: must be one of ") and repr(value) in msg, msg
    choices = {"damping_model": vocabulary.DAMPING_MODELS, "integrator": vocabulary.INTEGRATORS,
               "contact_model": vocabulary.CONTACT_MODELS, "oil_alpha": vocabulary.OIL_ALPHA_LAWS}[name]
    for c in choices:
        assert repr(c) in msg, (c, msg)
    assert "seed003" not in msg


def test_every_deprecated_spelling_names_a_current_value_of_its_field():
    """The alias table holds old spellings only: each maps to a value the field accepts now and is
    not itself a current value; every scene key that takes such a field knows the new value."""
    from gearfmu.common import vocabulary

    fields = {"damping_model": vocabulary.DAMPING_MODELS}
    assert set(vocabulary.DEPRECATED_SPELLINGS) <= set(fields)
    for field, table in vocabulary.DEPRECATED_SPELLINGS.items():
        for old, new in table.items():
            assert new in fields[field] and old not in fields[field], (field, old, new)
            assert vocabulary.current_spelling(field, new) == new


def test_fmu_runtime_copy_of_the_temperature_inputs_matches_the_vocabulary():
    """The FMU runtime template imports nothing from gearfmu, so it keeps its own list of the
    inputs that select a temperature axis; it must be the vocabulary's."""
    from gearfmu.common.vocabulary import TEMPERATURE_INPUTS
    from gearfmu.fmu.runtime import gearfmu_slave

    assert gearfmu_slave.TEMPERATURE_INPUT_NAMES == tuple(TEMPERATURE_INPUTS.values())
