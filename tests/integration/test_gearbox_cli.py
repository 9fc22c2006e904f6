"""`gearfmu modes` and `gearfmu simulate` on drivetrain and pair scenes.

References: the two-inertia closed form f = sqrt(kbar/m_e)/(2 pi) of a pair (m_e = I1 I2/(I1 Rb2^2 +
I2 Rb1^2) from the tables' inertias and base radii, kbar their mean mesh stiffness); the tooth
ratios of the example reducer (71/19 x 55/17); a mesh order h z_p n_p meeting a mode at the speed
f/(h z_p g_p) (the definition of the Campbell diagram's interference); strain energy fractions
summing to one.  Bad input: one line naming the key or option, exit status 2.
"""
import dataclasses
import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from gearfmu import pipeline, stages
from gearfmu.cli import main
from gearfmu.pipeline import compute_tables, load
from gearfmu.assembly.estimate import BuildTooLargeError

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "scenes" / "gearbox_two_stage.toml"


@pytest.mark.slow
def test_modes_of_the_example_gearbox(tmp_path, capsys):
    out = tmp_path / "m.json"
    assert main(["modes", str(EXAMPLE), "-o", str(out), "-q"]) == 0
    text = capsys.readouterr().out
    assert "intermediate_shaft" in text and "rigid" in text
    rep = json.loads(out.read_text())
    assert (tmp_path / "m.png").stat().st_size > 10_000
    assert rep["kind"] == "drivetrain" and len(rep["bodies"]) == 6 and rep["reference_torque_Nm"] == 143.0
    modes = rep["modes"]
    assert modes[0]["rigid"] and all(not m["rigid"] for m in modes[1:])
    for m in modes[1:]:
        assert sum(m["strain_energy_fraction"].values()) == pytest.approx(1.0, rel=1e-9)
        assert 0 < m["damped_frequency_Hz"] < m["frequency_Hz"]
    # the rigid mode turns the load at the total ratio
    shape = modes[0]["shape"]
    assert shape["load"] / shape["motor"] == pytest.approx((19 / 71) * (17 / 55), rel=1e-12)
    cb = rep["campbell"]
    assert cb["operating_speed_rpm"] == pytest.approx(1470.0)
    order = {o["name"]: o for o in cb["orders"]}
    assert order["stage2 mesh 1x"]["hz_per_rpm"] == pytest.approx(17 * (19 / 71) / 60, rel=1e-12)
    for p in cb["interferences"]:
        f = modes[p["mode"]]["frequency_Hz"]
        assert p["speed_rpm"] == pytest.approx(f / order[p["order"]]["hz_per_rpm"], rel=1e-12)


def test_modes_of_a_pair_scene_is_the_two_inertia_closed_form(tmp_path, capsys):
    out = tmp_path / "pair.json"
    assert main(["modes", "-o", str(out), "--json", "-q"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep == json.loads(out.read_text())
    t = compute_tables(load(None))
    me = t.inertia_pinion_kgm2 * t.inertia_gear_kgm2 / (
        t.inertia_pinion_kgm2 * t.base_radius_gear_m ** 2 + t.inertia_gear_kgm2 * t.base_radius_pinion_m ** 2)
    assert len(rep["modes"]) == 2 and rep["modes"][0]["rigid"]
    assert rep["modes"][1]["frequency_Hz"] == pytest.approx(math.sqrt(t.k_mean_N_per_m / me) / (2 * math.pi),
                                                            rel=1e-9)


@pytest.mark.slow
def test_simulate_the_example_gearbox(tmp_path, capsys):
    out = tmp_path / "run.csv"
    assert main(["simulate", str(EXAMPLE), "--stop-time", "0.01", "-o", str(out), "-q"]) == 0
    assert "simulated 0.01 s of gearbox_two_stage" in capsys.readouterr().out
    units, names = (line.split(",") for line in out.read_text().splitlines()[:2])
    assert names[:3] == ["time", "motor_angle", "motor_speed"] and units[:3] == ["# units: s", "rad", "rad/s"]
    assert "stage2.pair_force[1]" in names and units[names.index("intermediate_shaft.torque")] == "N*m"
    data = np.loadtxt(out, delimiter=",", skiprows=2)
    assert data.shape[0] == 101
    col = {h: data[:, i] for i, h in enumerate(names)}
    ratio = (71 / 19) * (55 / 17)
    assert np.mean(col["load_speed"]) * ratio == pytest.approx(np.mean(col["motor_speed"]), rel=1e-3)
    # the shafts carry the motor torque times the ratios (balanced start, small vibration about it)
    assert np.mean(col["input_shaft.torque"]) == pytest.approx(143.0, rel=1e-2)
    assert np.mean(col["output_shaft.torque"]) == pytest.approx(143.0 * ratio, rel=1e-2)
    assert (tmp_path / "run.png").stat().st_size > 10_000


def test_bad_drivetrain_input_is_one_line_and_status_2(tmp_path, capsys):
    for name in ("gearbox_two_stage.toml", "gearbox_stage1.toml", "gearbox_stage2.toml"):
        shutil.copy(EXAMPLE.parent / name, tmp_path / name)
    scene = tmp_path / "gearbox_two_stage.toml"
    scene.write_text(scene.read_text().replace("diameter_mm = 50.0", "diameter_mm = -50.0"))
    assert main(["modes", str(scene), "-o", str(tmp_path / "x.json")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "shaft[1].diameter_mm: must be a number in (0, 10000], got -50.0" in err
    (tmp_path / "gearbox_stage2.toml").unlink()
    assert main(["simulate", str(EXAMPLE), "--backend", "fmu", "--fmu", "x.fmu"]) == 2
    assert "--backend: a drivetrain scene runs with the native gearbox solver only" in capsys.readouterr().err
    scene.write_text(scene.read_text().replace("diameter_mm = -50.0", "diameter_mm = 50.0"))
    assert main(["simulate", str(scene), "-o", str(tmp_path / "x.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "stage[1].scene: scene file not found" in err
    assert main(["simulate", str(EXAMPLE), "--stop-time", "0.00015", "--output-interval", "1e-4",
                 "-o", str(tmp_path / "y.csv")]) == 2
    assert "stop_time_s" in capsys.readouterr().err



def test_every_stage_estimate_is_checked_before_any_table(monkeypatch):
    """A stage over the size limits (gearfmu.assembly.estimate) stops the work before the first
    stage's tables are computed, naming the stage and the keys to change."""
    kind, scene = pipeline.load_any(EXAMPLE)
    s2 = scene.stages[1]
    huge = dataclasses.replace(s2.scene, tables=dataclasses.replace(s2.scene.tables, points_per_mesh=100000),
                               mesh=dataclasses.replace(s2.scene.mesh, slices=1000))
    scene = dataclasses.replace(scene, stages=(scene.stages[0], dataclasses.replace(s2, scene=huge)))
    computed = []
    monkeypatch.setattr(stages, "compute_tables", lambda sc, **kw: computed.append(sc.name))
    with pytest.raises(BuildTooLargeError, match=r"stage 'stage2' \(.*gearbox_stage2.toml\): "
                                                 r"tables.points_per_mesh \(100000\)"):
        pipeline.stage_tables(scene)
    assert computed == []
