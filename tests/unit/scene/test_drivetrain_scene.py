"""The drivetrain scene: reading, SI conversion, ratios, operating points, and one line per problem.

References: the kinematic ratio of an involute spur stage is z_pinion/z_gear exactly (base radii
r_b = m z cos(alpha)/2); a uniform round shaft in torsion has k = G pi (D^4 - d^4)/(32 L) with
G = E/(2(1 + nu)) and polar inertia rho pi (D^4 - d^4) L/32; the balancing load torque is the motor
torque times the total ratio (power balance).  The expected key paths are written out here.
"""
import math
import pathlib
import textwrap

import pytest

from gearfmu.scene.drivetrain import DRIVETRAIN_SCHEMA, SHAFT_DAMPING_RATIO_DEFAULT, load_drivetrain
from gearfmu.scene.options import SceneError
from gearfmu.scene.reader import default_scene_path

PAIR = """
[stage.pair.gears]
module_mm = {m}
face_width_mm = {b}
[stage.pair.gears.pinion]
teeth = {z1}
[stage.pair.gears.gear]
teeth = {z2}
"""

BASE = textwrap.dedent("""
[drivetrain]
name = "two stage"
[motor]
inertia_kgm2 = 0.03
torque_Nm = 150.0
speed_rpm = 3000.0
[load]
inertia_kgm2 = 2.0
[[stage]]
name = "s1"
""") + PAIR.format(m=2.5, b=25.0, z1=23, z2=67) + textwrap.dedent("""
[[stage]]
name = "s2"
""") + PAIR.format(m=3.5, b=40.0, z1=19, z2=73) + textwrap.dedent("""
[[shaft]]
name = "input_shaft"
from = "motor"
to = "s1.pinion"
diameter_mm = 30.0
bore_mm = 10.0
length_mm = 150.0
[[shaft]]
name = "intermediate_shaft"
from = "s2.pinion"
to = "s1.gear"
stiffness_Nm_per_rad = 1.6e5
damping_Nms_per_rad = 3.0
[[shaft]]
name = "output_shaft"
from = "s2.gear"
to = "load"
rigid = true
""")


def test_two_stage_reads_ratios_operating_points_and_shafts():
    d = load_drivetrain(BASE)
    g1, g2 = 23 / 67, 19 / 73
    assert d.ratio["s1.gear"] == pytest.approx(g1, rel=1e-13)
    assert d.ratio["s2.pinion"] == pytest.approx(g1, rel=1e-13)
    assert d.ratio["load"] == pytest.approx(g1 * g2, rel=1e-13)
    assert d.total_ratio == pytest.approx(67 / 23 * 73 / 19, rel=1e-13)
    assert d.load_torque_Nm == pytest.approx(150.0 * 67 / 23 * 73 / 19, rel=1e-13)
    s1, s2 = d.stages
    assert s1.pinion_torque_Nm == pytest.approx(150.0, rel=1e-13)
    assert s2.pinion_torque_Nm == pytest.approx(150.0 * 67 / 23, rel=1e-13)
    assert s2.scene.operating.speed_rad_s == pytest.approx(3000 * 2 * math.pi / 60 * g1, rel=1e-13)
    assert s1.damping_ratio == 0.05 and s1.damping_model == "elastobacklash"   # the pair scene's defaults
    inp, mid, out = d.shafts
    G = 206e9 / (2 * 1.3)
    J = math.pi * (0.030 ** 4 - 0.010 ** 4) / 32
    assert inp.stiffness_Nm_per_rad == pytest.approx(G * J / 0.150, rel=1e-13)
    assert inp.inertia_kgm2 == pytest.approx(7850 * J * 0.150, rel=1e-13)
    assert inp.damping_ratio == SHAFT_DAMPING_RATIO_DEFAULT and inp.stiffness_from == "dimensions"
    assert (mid.stiffness_Nm_per_rad, mid.damping_Nms_per_rad, mid.damping_ratio) == (1.6e5, 3.0, None)
    assert out.rigid and out.stiffness_Nm_per_rad is None
    assert d.integrator == "rk4_node" and d.max_step_s is None
    # auto output interval: >= 20 samples per mesh period of the fastest stage (23 teeth at 50 rev/s)
    assert d.output_interval_s <= 1 / (23 * 50.0) / 20 and d.output_interval_auto


def test_stage_by_path_replaces_its_operating_point_and_says_so(tmp_path):
    pair = default_scene_path()
    text = BASE.replace('[[stage]]\nname = "s1"\n' + PAIR.format(m=2.5, b=25.0, z1=23, z2=67),
                        f'[[stage]]\nname = "s1"\nscene = "{pair.name}"\n')
    (tmp_path / pair.name).write_text(pair.read_text())
    f = tmp_path / "gearbox.toml"
    f.write_text(text.replace('from = "s2.pinion"', 'from = "s2.pinion"'))
    d = load_drivetrain(f)
    s1 = d.stages[0]
    assert s1.scene.pair.pinion.teeth == 45 and s1.source == str(tmp_path / pair.name)
    assert s1.pinion_torque_Nm == 150.0
    assert any(n.startswith("s1: operating point 2000 N*m, 2000 rpm of") and "replaced" in n for n in d.notes)
    assert d.ratio["s1.gear"] == pytest.approx(45 / 34, rel=1e-13)


def test_torque_outside_the_stage_torque_axis_is_a_warning():
    text = BASE.replace('[[stage]]\nname = "s2"\n', '[[stage]]\nname = "s2"\n[stage.pair.operating]\n'
                        'torque_range_Nm = [10.0, 200.0]\n[stage.pair.tables]\ntorque_points = 3\n')
    d = load_drivetrain(text)
    assert any(n.startswith("WARNING s2: pinion torque 436.957 N*m outside") for n in d.notes)


@pytest.mark.parametrize("edit, problems", [
    (lambda t: t.replace("stiffness_Nm_per_rad = 1.6e5", "stiffness_Nm_per_rad = -3"),
     [("shaft[1].stiffness_Nm_per_rad", "must be a number in (0, 1e+12], got -3")]),
    (lambda t: t.replace('to = "s1.gear"', 'to = "s3.gear"').replace("teeth = 73", "teeth = 3"),
     [("stage[1].pair.gears.gear.teeth", "must be an integer in [5, 1000], got 3"),
      ("shaft[1].to", "'s3.gear' is not a part; parts are motor, load, s1.pinion, s1.gear, s2.pinion, s2.gear")]),
    (lambda t: t.replace("speed_rpm = 3000.0", "speed_rpm = 3000.0\nspeed_rad_s = 3.0"),
     [("motor.speed_rad_s", "unknown key; did you mean 'speed_rpm'? (this key is in rpm)")]),
    (lambda t: t.replace('from = "s2.pinion"\nto = "s1.gear"', 'from = "s2.gear"\nto = "s1.gear"'),
     [("stage[1]", "the gear 's2.gear' lies on the motor side of the pinion 's2.pinion': the pinion is the driving "
                   "member of its stage (swap the stage's gears, or check the shafts)")]),
    (lambda t: t.replace('to = "load"\nrigid = true', 'to = "load"\nrigid = true\n[[shaft]]\nname = "extra"\n'
                         'from = "s1.pinion"\nto = "load"\nstiffness_Nm_per_rad = 1e4'),
     [("shaft[3]", "closes a loop between 's1.pinion' and 'load': the drivetrain must be a tree (one kinematic "
                   "degree of freedom)")]),
    (lambda t: t.replace("diameter_mm = 30.0\n", "").replace('name = "s2"', 'name = "s1"'),
     [("stage[1].name", "'s1' is already the name of stage[0]"),
      ("shaft[0].diameter_mm", "missing: a shaft's dimensions need diameter_mm and length_mm")]),
    (lambda t: t.replace("rigid = true", "rigid = true\ndamping_ratio = 0.1"),
     [("shaft[2].damping_ratio", "a rigid shaft has no stiffness or damping (remove the key or rigid = true)")]),
    (lambda t: t + "[[planetary]]\nname = 'p'\n",
     [("planetary[0].planets", "missing (required)"), ("planetary[0].bearings", "missing table (required)"),
      ("planetary[0]", "give either [planetary.gears] (the geometry) or [planetary.lumped] (published lumped "
                       "parameters)")]),
])
def test_every_problem_is_named_with_its_key_path(edit, problems):
    with pytest.raises(SceneError) as exc:
        load_drivetrain(edit(BASE))
    assert sorted(exc.value.problems) == sorted(problems)


def test_pinion_must_be_the_driving_member():
    text = BASE.replace('from = "motor"\nto = "s1.pinion"', 'from = "motor"\nto = "s1.gear"').replace(
        'from = "s2.pinion"\nto = "s1.gear"', 'from = "s2.pinion"\nto = "s1.pinion"')
    with pytest.raises(SceneError) as exc:
        load_drivetrain(text)
    assert exc.value.problems == [("stage[0]", "the gear 's1.gear' lies on the motor side of the pinion 's1.pinion': "
                                   "the pinion is the driving member of its stage (swap the stage's gears, or check "
                                   "the shafts)")]


def test_schema_has_every_key_a_unit_and_a_meaning():
    for table, keys in DRIVETRAIN_SCHEMA.items():
        for k in keys:
            assert k.doc and k.unit, (table, k.name)


def test_docs_document_every_drivetrain_key():
    doc = (pathlib.Path(__file__).resolve().parents[3] / "docs" / "scene.md").read_text(encoding="utf-8")
    section = doc.split("## Drivetrain scenes", 1)[1].split("\n## ", 1)[0]
    for table, keys in DRIVETRAIN_SCHEMA.items():
        assert f"[{table}]" in section or f"[[{table}]]" in section, table
        for k in keys:
            assert f"`{k.name}`" in section, f"{table}.{k.name}"
