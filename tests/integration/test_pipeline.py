"""End to end on the default scene: scene -> tables -> FMU, FMU against native, CLI.

References:
* FMU vs native: two independent implementations of docs/model.md (C kernel
  driven by fmpy, numba solver) must agree to round-off, relative difference
  <= 1e-9 of each signal's range, when their internal steps match.
* Mean mesh force: in a periodic steady state with balanced torques
  (T2 = T1*Rb2/Rb1) the shaft accelerations average to zero, so the mean
  dynamic mesh force equals F_m = T1/Rb1 (seed 003, below eq 2).
"""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from gearfmu.fmu.compare import output_names, run_fmu, validate_fmu_against_native
from gearfmu.pipeline import build, gear_torque_for, load

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def default_build(tmp_path_factory):
    scene = load(None)
    res = build(scene, tmp_path_factory.mktemp("fmu") / "default.fmu")
    return scene, res


def test_default_scene_fmu_agrees_with_native_to_roundoff(default_build):
    scene, res = default_build
    t1 = scene.operating.torque_Nm
    rep = validate_fmu_against_native(
        res.fmu_path, res.tables,
        native_kwargs=dict(max_step_s=res.max_step_s, pinion_torque_Nm=t1,
                           gear_torque_Nm=gear_torque_for(res.tables, t1),
                           pinion_speed_start_rad_s=scene.operating.speed_rad_s,
                           damping_ratio=scene.fmu.damping_ratio,
                           damping_model=scene.solver.damping_model),
        stop_time_s=0.02, comm_step_s=scene.fmu.output_interval_s)
    assert rep["fmpy_problems"] == []
    assert set(rep["outputs"]) == set(output_names(res.tables.slots))
    worst = {k: v["rel_max_diff"] for k, v in rep["outputs"].items()}
    assert max(worst.values()) <= 1e-9, worst
    # the comparison is not vacuous: the signals really vary
    assert rep["outputs"]["mesh_force"]["range"] > 0.1 * t1 / res.tables.base_radius_pinion_m
    assert rep["outputs"]["pair_force[1]"]["range"] > 0


def test_default_scene_mean_mesh_force_equals_applied_load(default_build):
    scene, res = default_build
    tables = res.tables
    mesh_period_s = tables.mesh_period_rad / scene.operating.speed_rad_s
    n_mesh, per = 100, 200
    step = mesh_period_s / per  # 200 samples per mesh period, a whole number of periods averaged
    run = run_fmu(res.fmu_path, stop_time_s=n_mesh * mesh_period_s, comm_step_s=step,
                  names=output_names(tables.slots))
    f = run.columns["mesh_force"]
    w = run.columns["pinion_speed"]
    m = 40 * per
    last = f[-m - 1:-1]  # the last 40 whole mesh periods
    fm = scene.operating.torque_Nm / tables.base_radius_pinion_m
    # Newton on the pinion over the window: I1*(w_end - w_start) = (T1 - Rb1*mean F)*T_window, so
    # mean F = F_m - I1*dw/(Rb1*T_window); the sampled mean (rectangle rule on a force with
    # jumps at meshing-in/out) must match it, and F_m itself within the residual speed drift
    f_newton = fm - tables.inertia_pinion_kgm2 * (w[-1] - w[-m - 1]) / (
        tables.base_radius_pinion_m * m * step)
    assert abs(last.mean() - f_newton) / fm < 2e-3
    assert abs(last.mean() - fm) / fm < 5e-3
    assert np.all(np.isfinite(f))
    # pair forces add up to the mesh force and never pull (elastobacklash)
    pf = np.column_stack([run.columns[f"pair_force[{i + 1}]"] for i in range(tables.slots)])
    assert np.allclose(pf.sum(axis=1), f, rtol=1e-12, atol=1e-9)
    assert pf.min() >= 0.0


def _run(args, cwd):
    return subprocess.run([sys.executable, *args], cwd=cwd, capture_output=True, text=True, timeout=300)


def test_cli_tables_simulate_validate(tmp_path):
    r = _run(["-m", "gearfmu.cli", "tables", "-o", "t/default.gtab", "-q"], tmp_path)
    assert r.returncode == 0, r.stderr
    for suffix in (".gtab", ".png", ".csv"):
        assert (tmp_path / "t" / f"default{suffix}").stat().st_size > 0
    r = _run(["-m", "gearfmu.cli", "simulate", "--stop-time", "0.005", "-o", "s/native.csv", "-q"], tmp_path)
    assert r.returncode == 0, r.stderr
    units, head = (tmp_path / "s" / "native.csv").read_text().splitlines()[:2]  # docs/cli.md "simulate"
    assert units.startswith("# units: s,rad/s") and head.startswith("time,pinion_speed") and "pair_force[2]" in head
    assert (tmp_path / "s" / "native.png").stat().st_size > 0
    r = _run(["-m", "gearfmu.cli", "build", "-o", "b/g.fmu", "-q"], tmp_path)
    assert r.returncode == 0, r.stderr
    r = _run(["-m", "gearfmu.cli", "simulate", "--backend", "fmu", "--fmu", "b/g.fmu", "--stop-time", "0.005",
              "-o", "s/fmu.csv"], tmp_path)
    assert r.returncode == 0, r.stderr
    a = np.loadtxt(tmp_path / "s" / "native.csv", delimiter=",", skiprows=2)
    b = np.loadtxt(tmp_path / "s" / "fmu.csv", delimiter=",", skiprows=2)
    assert a.shape == b.shape
    col = head.split(",").index("mesh_force")
    assert np.max(np.abs(a[:, col] - b[:, col])) <= 1e-9 * np.ptp(a[:, col])
    r = _run(["-m", "gearfmu.cli", "validate", "--fmu", "b/g.fmu", "--stop-time", "0.005", "--json"], tmp_path)
    assert r.returncode == 0, r.stderr
    rep = json.loads(r.stdout)
    for key in ("fmpy_problems", "max_abs_diff", "rms_diff", "native_wall_s", "fmu_wall_s"):
        assert key in rep
    assert rep["fmpy_problems"] == []
    assert set(rep["max_abs_diff"]) == set(output_names(2))


def test_build_fmu_script_reports(tmp_path):
    r = _run([str(REPO / "build_fmu.py"), "--json", "-o", "x.fmu"], tmp_path)
    assert r.returncode == 0, r.stderr
    rep = json.loads(r.stdout)
    assert rep["fmpy_problems"] == [] and rep["max_rel_diff"] <= 1e-9
    assert (tmp_path / "x.fmu").stat().st_size > 0
    # the README's first command: the standalone FMU with the five binaries (FMI 2: darwin64 holds both Mac
    # CPUs, and the arm64 one is also in aarch64-darwin, the folder FMI 2.0.4 takes from FMI 3)
    c = rep["fmu_contents"]
    assert (c["runtime"], c["fmi_version"], c["needs_execution_tool"], c["not_built"]) == ("standalone", "2.0", False, {})
    assert sorted(c["platforms"]) == ["aarch64-darwin", "aarch64-linux", "darwin64", "linux64", "win64"]
    r = _run([str(REPO / "build_fmu.py"), "-o", "y.fmu"], tmp_path)
    assert r.returncode == 0, r.stderr
    assert ("runtime standalone (all C, needs no Python), FMI 2.0 Co-Simulation and Model Exchange, platforms: linux64, "
            "aarch64-linux, win64, darwin64 (x86_64 + arm64; arm64 also as aarch64-darwin)") in r.stdout.splitlines()


def test_cli_bad_scene_names_the_key(tmp_path):
    bad = (REPO / "gearfmu" / "scene" / "data" / "default_scene.toml").read_text().replace("teeth = 45", "teeth = 3")
    (tmp_path / "bad.toml").write_text(bad)
    r = _run(["-m", "gearfmu.cli", "build", "bad.toml", "-o", "bad.fmu"], tmp_path)
    assert r.returncode == 2
    assert "gears.pinion.teeth" in r.stderr
    assert not (tmp_path / "bad.fmu").exists()
    r = _run(["-m", "gearfmu.cli", "build", "missing.toml"], tmp_path)
    assert r.returncode == 2 and "not found" in r.stderr
