"""A [[planetary]] row with a driven member (``driven_speed_rpm``; docs/scene.md "[[planetary]]",
docs/planetary.md "Driven members"): the example scene examples/scenes/planetary_driven_ring.toml read
and run, its refusals.

References: Willis' equation for the speeds the example's comment gives (the carrier at
(21 x 1470 + 81 x (-100))/102 = 223.235 rpm with the ring at -100 rpm); the lossless torque balance
(the servo holds the ring against 81/21 x 195 N*m; within 1e-4, the translational model's centripetal
preload at speed).  Bad input: one line naming the key, exit status 2.
"""
from pathlib import Path

import numpy as np
import pytest

from gearfmu import pipeline
from gearfmu.cli import main
from gearfmu.scene.drivetrain import load_drivetrain
from gearfmu.scene.options import RPM_TO_RAD_S, SceneError

pytestmark = pytest.mark.slow   # builds the example's tables

ROOT = Path(__file__).resolve().parents[3]
DRIVEN = ROOT / "examples" / "scenes" / "planetary_driven_ring.toml"


def test_the_driven_ring_example():
    sc = load_drivetrain(DRIVEN)
    ps = sc.planetaries[0]
    assert ps.held == "ring" and ps.driven_speed_rad_s == pytest.approx(-100.0 * RPM_TO_RAD_S, rel=1e-15)
    assert any(n.startswith("ps: planetary stage (geometry, translational, 3 planets, ring driven at -100 rpm)")
               for n in sc.notes)
    # the sun mesh frequency z_s |n_s - n_c| with the carrier's speed by Willis from the sun's and the ring's
    n_c = (21 * 1470.0 + 81 * -100.0) / 102
    assert any(f"sun mesh frequency {21 * (1470.0 - n_c) / 60:.6g} Hz" in n for n in sc.notes), sc.notes
    model = pipeline.drivetrain_model(sc, pipeline.stage_tables(sc))
    assert model.drives[0]["port"] == "ps.ring"
    r = pipeline.simulate_drivetrain(sc, model, stop_time_s=2e-3)
    rpm = {p: r[f"ps.{p}_speed"][0] / RPM_TO_RAD_S for p in ("sun", "carrier", "ring")}
    assert rpm["ring"] == pytest.approx(-100.0, rel=1e-14) and rpm["sun"] == pytest.approx(1470.0, rel=1e-14)
    assert rpm["carrier"] == pytest.approx((21 * 1470.0 + 81 * -100.0) / 102, rel=1e-12)
    # the lossless torque balance; translational model at speed: within 1e-4 (the planets' centripetal
    # preload, docs/planetary.md "Initial state"; measured 2.7e-5)
    assert -r["ps.ring_support.force"][0] == pytest.approx(81 / 21 * 195.0, rel=1e-4)
    assert np.all(r["ps.ring_drive_speed"] == r["ps.ring_drive_speed"][0])


def test_gearfmu_simulate_of_the_driven_example(tmp_path, capsys):
    out = tmp_path / "run.csv"
    assert main(["simulate", str(DRIVEN), "-o", str(out), "--stop-time", "0.001", "-q"]) == 0
    names = out.read_text().splitlines()[1].split(",")
    assert "ps.ring_drive_speed" in names and "ps.ring_support.force" in names


@pytest.mark.parametrize("old,new,key,reason", [
    ("driven_speed_rpm = -100.0", 'driven_speed_rpm = "fast"', "planetary[0].driven_speed_rpm", "number"),
    ("driven_speed_rpm = -100.0", "driven_speed_rpm = 2e6", "planetary[0].driven_speed_rpm", "1e+06"),
    ('to = "ps.sun"', 'to = "ps.ring"', "shaft[0].to", "'ps.ring' is the held port of planetary stage 'ps' (driven "
     "through its torsional support by its drive): no shaft may join it"),
])
def test_bad_driven_rows_are_refused_with_their_key(old, new, key, reason):
    text = DRIVEN.read_text()
    assert old in text
    with pytest.raises(SceneError) as exc:
        load_drivetrain(text.replace(old, new))
    probs = dict(exc.value.problems)
    assert key in probs, exc.value.problems
    assert reason in probs[key], probs[key]


def test_the_cli_refuses_a_bad_drive_speed_with_one_line(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(DRIVEN.read_text().replace("driven_speed_rpm = -100.0", "driven_speed_rpm = nan"))
    assert main(["simulate", str(bad), "-o", str(tmp_path / "x.csv"), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "planetary[0].driven_speed_rpm" in err[0], err
    assert not (tmp_path / "x.csv").exists()
