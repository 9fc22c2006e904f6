"""A plain user script (no ``if __name__ == "__main__":`` guard) can compute lubricated tables.

The local process pool (gearfmu.common.executors.make_executor, the one place a pool is made) must not
re-run the user's module in its workers.  Reference: the same tables computed from this (pytest)
process, whose main module is guarded, so its pool is the established 'spawn' pool.  Two runs in
one process already differ by a few 1e-16 of the largest stiffness (the order in which the pool
hands back film solves), so "identical" is 1e-12 of the largest value of each array.
"""
from __future__ import annotations

import subprocess
import sys

import numpy as np

from gearfmu.scene.reader import default_scene_path
from gearfmu.tables.mesh_tables import load_tables
import pytest

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

#: the cheapest lubricated scene: the default pair with smooth EHL, one slice, 8 points per mesh
SCENE = (default_scene_path().read_text()
         .replace('contact_model = "hertz"', 'contact_model = "smooth_ehl"')
         .replace("slices = 44 ", "slices = 1 ")
         .replace("points_per_mesh = 64", "points_per_mesh = 8"))

SCRIPT = """import gearfmu.pipeline as p
scene = p.load(open("scene.toml").read())
tables = p.compute_tables(scene)
tables.save("out.gtab")
print("done")
"""


def test_unguarded_script_computes_lubricated_tables(tmp_path):
    assert 'contact_model = "smooth_ehl"' in SCENE and "slices = 1 " in SCENE and "points_per_mesh = 8" in SCENE
    (tmp_path / "scene.toml").write_text(SCENE)
    (tmp_path / "user_script.py").write_text(SCRIPT)
    assert "__main__" not in SCRIPT and len(SCRIPT.strip().splitlines()) == 5
    r = subprocess.run([sys.executable, "user_script.py"], cwd=tmp_path, capture_output=True, text=True,
                       timeout=900)
    assert r.returncode == 0, r.stderr[-3000:]
    assert "guard" not in r.stderr  # the workers ran (no fallback to one process where 'fork' exists)
    assert r.stdout.count("done") == 1  # the module ran once, not again in each worker
    got = load_tables(tmp_path / "out.gtab")

    from gearfmu import pipeline
    ref = pipeline.compute_tables(pipeline.load(SCENE))
    assert got.provenance["contact"]["model"] == "smooth_ehl"
    for name in ("torque_Nm", "k_N_per_m", "e_m", "static_te_m", "backlash_half_m"):
        a, b = getattr(got, name), getattr(ref, name)
        assert a.shape == b.shape and np.max(np.abs(a - b)) <= 1e-12 * np.max(np.abs(b)), name


def test_progress_bars_start_no_thread(capsys):
    """A progress bar (shown or not) must not start a thread: the local pool forks for an unguarded
    script only while the process runs one Python thread (gearfmu.common.executors._start_method),
    and tqdm's own monitor thread would otherwise stay alive after the bar."""
    import threading

    from gearfmu.common.progress import progress_bar

    before = {t.ident for t in threading.enumerate()}
    for enabled in (False, True):
        assert sum(progress_bar(range(5), "test bar", enabled)) == 10
    assert {t.ident for t in threading.enumerate()} == before
    assert "test bar" in capsys.readouterr().err
