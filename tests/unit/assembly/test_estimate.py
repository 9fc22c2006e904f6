"""The cost estimate and the guard before expensive work (gearfmu.assembly.estimate, read off a scene by
gearfmu.scene.physics).

A scene inside every documented key range (points_per_mesh = 100000, torque_points = 1000) asks
for tables of several GB; it must be refused before anything is computed, with a message that
names the keys, unless the user overrides.  The precompute is replaced by a stub here, so no
test computes anything big.  Reference for the size estimate: the byte size of the saved
default tables (written by gearfmu.tables, not by the estimate).
"""
from __future__ import annotations

import pytest

from gearfmu.assembly import estimate
from gearfmu.scene import physics
from gearfmu import pipeline
from gearfmu.cli import main
from gearfmu.scene.reader import default_scene_path

HUGE = (default_scene_path().read_text()
        .replace("points_per_mesh = 64", "points_per_mesh = 100000")
        .replace("torque_points = 1", "torque_points = 1000")
        .replace("speed_rpm = 2000.0 ", "speed_rpm = 2000.0\ntorque_range_Nm = [500.0, 3000.0] "))


class _Computed(Exception):
    pass


@pytest.fixture
def no_precompute(monkeypatch):
    """Any table computation raises _Computed instead of running."""
    import gearfmu.assembly.precompute as pc

    def stub(*a, **k):
        raise _Computed()

    monkeypatch.setattr(pc, "precompute_tables", stub)


def test_huge_scene_is_refused_before_computing(no_precompute):
    scene = pipeline.load(HUGE)
    assert scene.tables.points_per_mesh == 100000 and scene.tables.torque_points == 1000
    with pytest.raises(estimate.BuildTooLargeError) as ei:
        pipeline.compute_tables(scene)
    msg = str(ei.value)
    assert "tables.points_per_mesh" in msg and "tables.torque_points" in msg and "--allow-large" in msg
    assert "\n" not in msg
    # 1000 rows x 2 slots x 200000 angles of float64 k and e alone are 6.4 GB
    est = physics.estimate_build(scene)
    assert est.table_bytes >= 8 * 2 * 1000 * 2 * 200000 and est.fmu_bytes > estimate.FMU_LIMIT_BYTES


def test_cli_refuses_the_huge_scene_with_one_line(tmp_path, capsys, no_precompute):
    p = tmp_path / "huge.toml"
    p.write_text(HUGE)
    assert main(["tables", str(p), "-q", "-o", str(tmp_path / "t.gtab")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("gearfmu: ") and "tables.points_per_mesh" in err and err.count("\n") == 0


def test_override_lets_it_through(tmp_path, no_precompute):
    scene = pipeline.load(HUGE)
    with pytest.raises(_Computed):  # the guard passed: the (stubbed) computation was reached
        pipeline.compute_tables(scene, allow_large=True)
    p = tmp_path / "huge.toml"
    p.write_text(HUGE)
    with pytest.raises(_Computed):
        main(["tables", str(p), "-q", "--allow-large", "-o", str(tmp_path / "t.gtab")])


def test_default_scene_is_not_refused_and_its_size_estimate_holds(tmp_path):
    """Estimated table bytes within a factor 1.25 of the saved default tables."""
    scene = pipeline.load(None)
    est = physics.check_build_cost(scene)
    assert est.build_s < estimate.BUILD_TIME_LIMIT_S
    tables = pipeline.compute_tables(scene)
    size = tables.save(tmp_path / "d.gtab").stat().st_size
    assert (est.n_phi, est.slots, est.torque_rows) == (tables.n_phi, tables.slots, tables.n_torque)
    assert 1 / 1.25 <= est.table_bytes / size <= 1.25
