"""The defaulted output (communication) interval resolves the mesh frequency.

Reference: the mesh period in closed form, T_mesh = 60 / (n1 z1) s for a pinion of z1 teeth at
n1 rpm (hand arithmetic, not gearfmu), and the static mesh force F = T1 / Rb1 (torque balance;
Rb1 = m z1 cos(alpha) / 2 from seed 003 Table 1's m = 3 mm, z1 = 50, alpha = 20 deg).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from gearfmu.scene.reader import load_scene

ROOT = Path(__file__).resolve().parents[3]
SEED003 = ROOT / "examples" / "scenes" / "seed003_table1.toml"


def _mesh_period_s(rpm: float, z1: int) -> float:
    return 60.0 / (rpm * z1)


def _without_interval(text: str) -> str:
    return "\n".join(ln for ln in text.splitlines() if not ln.startswith("output_interval_s"))


def test_seed003_example_resolves_the_mesh_period():
    """2000 rpm x 50 teeth: T_mesh = 0.6 ms; the example's interval gives >= 20 samples per period."""
    s = load_scene(SEED003)
    T = _mesh_period_s(2000.0, 50)
    assert T == pytest.approx(6e-4)
    assert s.fmu.output_interval_auto
    assert T / s.fmu.output_interval_s >= 20


@pytest.mark.parametrize("rpm,z1", [(2000.0, 45), (137.0, 60), (30000.0, 45), (7.5, 45)])
def test_default_interval_from_speed_and_teeth(rpm, z1):
    """The default scene with its interval removed, at other speeds and pinion teeth:
    20 <= samples per mesh period <= 50 (a 1-2-5 rounding of T_mesh / 20)."""
    text = _without_interval(default_scene_path_text()).replace("speed_rpm = 2000.0", f"speed_rpm = {rpm}") \
        .replace("teeth = 45", f"teeth = {z1}", 1)
    s = load_scene(text)
    assert s.pair.pinion.teeth == z1 and s.operating.speed_rpm == pytest.approx(rpm)
    n = _mesh_period_s(rpm, z1) / s.fmu.output_interval_s
    assert 20 - 1e-9 <= n <= 50 + 1e-9
    mant = s.fmu.output_interval_s / 10 ** math.floor(math.log10(s.fmu.output_interval_s) + 1e-12)
    assert min(abs(mant - c) for c in (1, 2, 5)) < 1e-9


def test_explicit_interval_is_kept():
    text = SEED003.read_text().replace('output_interval_s = "auto"', "output_interval_s = 1e-4")
    s = load_scene(text)
    assert s.fmu.output_interval_s == 1e-4 and not s.fmu.output_interval_auto


def default_scene_path_text() -> str:
    from gearfmu.scene.reader import default_scene_path

    return default_scene_path().read_text()


def test_seed003_simulated_mean_force_matches_the_static_load():
    """The native run of the seed 003 example at its default output interval: the sampled mean
    mesh force over whole mesh periods after the start transient equals T1 / Rb1 to 1 %
    (a 1e-4 s interval, 6 samples per mesh period, gave 5.31 kN against 4.82 kN)."""
    from gearfmu.pipeline import compute_tables, simulate_native

    s = load_scene(SEED003)
    tables = compute_tables(s)
    res = simulate_native(s, tables)
    rb1 = 0.5 * 3e-3 * 50 * math.cos(math.radians(20.0))
    F_ref = 340.0 / rb1
    T = _mesh_period_s(2000.0, 50)
    t = np.asarray(res.time_s)
    n_per = int(round(T / s.fmu.output_interval_s * 10))  # ten mesh periods at a time
    tail = np.asarray(res.mesh_force)[t >= 0.02][: (np.count_nonzero(t >= 0.02) // n_per) * n_per]
    assert tail.size >= n_per
    # 2 %: the mesh force steps where a pair meshes in or out (docs/model.md "Contact-zone
    # edges"), and 30 samples locked to the mesh phase carry up to a step / 30 of bias
    # (measured 1.4 %; the ramps of the plain lookup gave < 1 %)
    assert float(np.mean(tail)) == pytest.approx(F_ref, rel=0.02)
