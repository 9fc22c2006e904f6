"""Planetary stages in a drivetrain scene: reading, refusals, the example scenes, `gearfmu modes`.

References (none produced by gearfmu.planetary or gearfmu.scene.planetary):

* Lin & Parker's (1999) Table 1 system in examples/scenes/planetary_lin_parker.toml: its frequencies
  against their matrices assembled in tests/unit/planetary/lin_parker.py (the example's motor and load of 1e-9 kg*m^2
  on rigid shafts move them by less than 1e-5), its mode structure, and Parker's (2000) rule for the
  interference points of its Campbell diagram (four planets, 24 sun teeth: every harmonic reaches
  rotational modes only);
* the tooth ratios of the planetary reducer example: Willis' (1 + 81/21) times 61/19;
* statics: in the initial state every sun mesh of the reducer's floating sun carries T_s/(N r_s), every
  ring mesh the same force (the planet's torque balance), stage 2 the carrier torque over its base radius;
* the assembly condition ((z_s + z_r)/N an integer), neighbouring planets' tip circles apart, and
  the internal-mesh checks of gearfmu.gear.internal (tests/unit/gear/test_internal_gear.py), each refused with
  its scene key.  Bad input: one line, exit status 2.
"""
import json
import math
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.slow  # builds or long runs: the full suite, not the quick subset

from gearfmu import pipeline
from gearfmu.cli import main
from gearfmu.planetary.native import simulate as simulate_planetary
from gearfmu.scene.drivetrain import load_drivetrain
from gearfmu.scene.options import SceneError
from lin_parker import hz, lin_parker_matrices

ROOT = Path(__file__).resolve().parents[3]
LP = ROOT / "examples" / "scenes" / "planetary_lin_parker.toml"
REDUCER = ROOT / "examples" / "scenes" / "planetary_reducer.toml"


def test_lin_parker_example_scene_has_the_published_frequencies_and_structure():
    sc = load_drivetrain(LP)
    assert sc.planetaries[0].form == "lumped" and sc.total_ratio == pytest.approx(5.0, rel=1e-15)
    model = pipeline.drivetrain_model(sc, pipeline.stage_tables(sc))
    res, cb = pipeline.modes_report("drivetrain", sc, model)
    got = np.array([m.frequency_Hz for m in res.modes])
    np.testing.assert_allclose(got, hz(*lin_parker_matrices(4)), rtol=1e-5, atol=1e-3)
    kinds = {}
    for m in res.modes[1:]:
        kinds.setdefault(m.types["lp"], []).append(m.frequency_Hz)
    assert sorted(kinds) == ["planet", "rotational", "translational"]
    assert len(kinds["rotational"]) == 5 and len(kinds["translational"]) == 12 and len(kinds["planet"]) == 3
    # Parker 2000: 24/4 is an integer, every mesh harmonic excites rotational modes only
    lp_points = [p for p in cb["interferences"] if p["order"].startswith("lp mesh")]
    assert lp_points and all(p["excited"] == (res.modes[p["mode"]].types["lp"] == "rotational") for p in lp_points)


def test_planetary_reducer_example():
    sc = load_drivetrain(REDUCER)
    assert sc.total_ratio == pytest.approx((1 + 81 / 21) * 61 / 19, rel=1e-12)
    ps = sc.planetaries[0]
    assert ps.form == "geometry" and ps.sun_torque_Nm == pytest.approx(195.0, rel=1e-12)
    assert ps.ratio == {"sun": 1.0, "carrier": pytest.approx(21 / 102, rel=1e-12), "ring": 0.0}
    assert any(n.startswith("ps: planetary stage (geometry, translational, 3 planets, ring held)") for n in sc.notes)
    model = pipeline.drivetrain_model(sc, pipeline.stage_tables(sc))
    r = pipeline.simulate_drivetrain(sc, model, stop_time_s=2e-3)
    st = model.stages[0]
    rb_s = next(t for n, t in zip(model.mesh_names, model.mesh_tables) if n == "ps.sun_planet[1]").base_radius_pinion_m
    assert st["planets"] == 3 and np.all(np.isfinite(r["load_speed"]))
    assert np.min(r["ps.sun_planet[1].mesh_force"]) > 0.0       # no contact loss at full load
    # the initial state at (almost) no speed -- no centripetal preload of the planet bearings -- is the
    # statics (docs/planetary.md "Initial state"): backlash 40 um on either flank, every mesh pressed
    s = simulate_planetary(model, stop_time_s=1e-5, comm_step_s=1e-5, motor_torque_Nm=195.0,
                           motor_speed_start_rad_s=1e-9)
    for n in (1, 2, 3):
        assert s[f"ps.sun_planet[{n}].mesh_force"][0] == pytest.approx(195.0 / 3 / rb_s, rel=1e-9)
        assert s[f"ps.ring_planet[{n}].mesh_force"][0] == pytest.approx(195.0 / 3 / rb_s, rel=1e-9)
    rb_p2 = model.mesh_tables[0].base_radius_pinion_m
    assert s["stage2.mesh_force"][0] == pytest.approx(195.0 * 102 / 21 / rb_p2, rel=1e-9)
    # at speed the sun meshes carry within 1e-4 of it (the planets' centripetal preload)
    assert r["ps.sun_planet[1].mesh_force"][0] == pytest.approx(195.0 / 3 / rb_s, rel=1e-4)


def test_gearfmu_modes_of_a_planetary_scene(tmp_path, capsys):
    out = tmp_path / "m.json"
    assert main(["modes", str(LP), "-o", str(out), "-q"]) == 0
    text = capsys.readouterr().out
    assert "planet  lp." in text and "cancelled by the planets' mesh phasing" in text
    assert "lp: translational 727.27 Hz x2, translational 1091.2 Hz x2, rotational 1536.5 Hz, planet 1808.2 Hz" in text
    rep = json.loads(out.read_text())
    assert (tmp_path / "m.png").stat().st_size > 10_000
    assert rep["kind"] == "drivetrain" and len(rep["dofs"]) == 21
    assert {m["type"]["lp"] for m in rep["modes"]} == {"rigid", "rotational", "translational", "planet"}
    orders = {o["name"]: o for o in rep["campbell"]["orders"]}
    assert orders["lp mesh 1x"]["phasing"] == "rotational"
    # sun mesh frequency per motor rpm: z_s (1 - g_c) / 60 with g_c = 24/120 (Willis)
    assert orders["lp mesh 1x"]["hz_per_rpm"] == pytest.approx(24 * (1 - 24 / 120) / 60, rel=1e-12)


def test_gearfmu_simulate_of_a_planetary_scene(tmp_path, capsys):
    out = tmp_path / "run.csv"
    assert main(["simulate", str(LP), "-o", str(out), "--stop-time", "0.002", "-q"]) == 0
    assert "simulated 0.002 s of planetary_lin_parker (21 DOFs, 8 meshes" in capsys.readouterr().out
    lines = out.read_text().splitlines()
    names = lines[1].split(",")
    units = dict(zip(names, lines[0].removeprefix("# units:").strip().split(",")))
    assert units["lp.load_sharing_factor[1]"] == "1" and units["lp.sun_planet[1].dte"] == "m"
    assert units["lp.ring_support.force"] == "N*m" and units["lp.sun_x"] == "m"
    first, row = (dict(zip(names, map(float, lines[i].split(",")))) for i in (2, -1))
    # four in-phase planets (24/4): equal shares; Willis: the carrier turns at 24/120 of the sun's speed
    # (the angles' increments: the static twist between them cancels; their vibration is below 1e-5)
    for n in (1, 2, 3, 4):
        assert row[f"lp.load_sharing_factor[{n}]"] == pytest.approx(1.0, abs=1e-9)
    turned = {p: row[f"lp.{p}_angle"] - first[f"lp.{p}_angle"] for p in ("sun", "carrier")}
    assert turned["carrier"] / turned["sun"] == pytest.approx(24 / 120, rel=1e-5)
    assert (tmp_path / "run.png").stat().st_size > 10_000


def test_a_planetary_drivetrain_is_no_ssp_of_stage_fmus(tmp_path, capsys):
    """A drivetrain with planetary stages is one system (its planetary FMU, tests/fmu_hosts/test_planetary_fmu.py),
    not a gearbox of stages: `gearfmu ssp` refuses it with one line, exit status 2, nothing written."""
    assert main(["ssp", str(LP), "-o", str(tmp_path / "x.ssp"), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == ("gearfmu: planetary[0] (lp): a drivetrain with planetary stages is one system, not a "
                       "gearbox of stages; `gearfmu build` makes its planetary FMU (docs/planetary.md)")
    assert not (tmp_path / "x.ssp").exists()


def _edit(text, old, new):
    assert old in text, old
    return text.replace(old, new)


@pytest.mark.parametrize("old,new,key,reason", [
    ("teeth_ring = 81 ", "teeth_ring = 82 ", "planetary[0].planets",
     "(z_s + z_r)/N = 103/3 = 34.3333 is not an integer: 3 equally spaced planets cannot be assembled"),
    ("planets = 3\n", "planets = 6\n", "planetary[0].planets", "planets 1 and 2 overlap"),
    ("profile_shift_ring = -0.45", "profile_shift_ring = 0.0", "planetary[0].gears.carrier_radius_mm",
     "planet-ring mesh: 77.3645 mm exceeds the zero-backlash centre distance 76.1954 mm of the planet-ring mesh"),
    ("rim_supports = 6\n", "rim_supports = 6\ncarrier_radius_mm = 78.5\n", "planetary[0].gears.carrier_radius_mm",
     "planet-ring mesh: 78.5 mm exceeds the zero-backlash centre distance 77.5025 mm of the planet-ring mesh"),
    ("profile_shift_planet = 0.1\n", "profile_shift_planet = 0.1\naddendum_coefficient_ring = 0.5\n"
     "tip_clearance_coefficient = 0.1\n", "planetary[0].gears.addendum_coefficient",
     "planet-ring mesh: the planet tip reaches beyond the ring's root circle"),
    ("profile_shift_ring = -0.45", "profile_shift_ring = -0.4", "planetary[0].gears.addendum_coefficient_ring",
     "planet-ring mesh: root interference"),
    ("planets = 3\n", "planets = 3\npin_error_tangential_um = [20.0, 0.0]\n", "planetary[0].pin_error_tangential_um",
     "must have one value per planet (3) or be empty, got 2 values"),
    ("planets = 3\n", "planets = 3\nplanet_angles_deg = [0.0, 121.0, 240.0]\n", "planetary[0].planet_angles_deg[1]",
     "planet 2 at 121 deg cannot be assembled"),
    ("to = \"ps.sun\"", "to = \"ps.ring\"", "shaft[0].to", "'ps.ring' is the held port of planetary stage 'ps'"),
    ("module_mm = 3.0", "module_m = 3.0", "planetary[0].gears.module_m", "unknown key; did you mean 'module_mm'?"),
    ("[planetary.carrier]", "[planetary.lumped]\nteeth_sun = 21\n[planetary.carrier]", "planetary[0]",
     "give either [planetary.gears] (the geometry) or [planetary.lumped] (published lumped parameters), not both"),
    ("ring_N_per_m = 5e8\n", "", "planetary[0].bearings.ring_N_per_m", "missing (required)"),
])
def test_impossible_or_bad_planetary_sets_are_refused_with_their_key(old, new, key, reason):
    text = _edit(REDUCER.read_text(), old, new)
    with pytest.raises(SceneError) as exc:
        load_drivetrain(text.replace('scene = "planetary_reducer_stage2.toml"',
                                     f'scene = "{REDUCER.parent / "planetary_reducer_stage2.toml"}"'))
    probs = dict(exc.value.problems)
    assert key in probs, exc.value.problems
    assert reason in probs[key], probs[key]


def test_the_bearings_table_is_required_by_the_translational_model_only():
    text = REDUCER.read_text().replace('scene = "planetary_reducer_stage2.toml"',
                                       f'scene = "{REDUCER.parent / "planetary_reducer_stage2.toml"}"')
    start = text.index("[planetary.bearings]")
    end = text.index("[[stage]]")
    no_bearings = text[:start] + text[end:]
    with pytest.raises(SceneError) as exc:
        load_drivetrain(no_bearings)
    assert ("planetary[0].bearings", "missing table (required)") in exc.value.problems
    sc = load_drivetrain(no_bearings.replace('model = "translational"', 'model = "torsional"'))
    assert sc.planetaries[0].model == "torsional"
