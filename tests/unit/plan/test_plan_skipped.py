"""What the planner skips and how it shows progress (gearfmu.plan, docs/plan.md "Skipped").

References:
* The scene as written: a spur pair without [thermal], [lubricant] or [roughness], one torque
  (no envelope torque range), every tooth alike and slots = ceil(contact ratio) -- so the
  thermal choice, the torque axis, the tooth-specific errors, extra slots and every lubricated
  contact model cannot matter over its envelope; the reasons are the scene's own facts.
* The table builder itself (gearfmu.assembly.precompute.precompute_tables) at the coarser
  resolution is the reference for tables the planner takes from a finer grid.
* gearfmu.assembly.estimate.estimate_build is the cost model the plan-time table budget uses.
"""
import json
import sys
from pathlib import Path

import numpy as np
import pytest

import gearfmu.plan.verify as plan_verify
from gearfmu.cli import main
from gearfmu.plan import format_report, plan_scene
from gearfmu.plan.choices import PLAN_TABLE_BUILD_S, choices_of, reference_points_per_mesh, skipped_choices
from gearfmu.plan.evaluator import Evaluator
from gearfmu.scene.envelope import accuracy_of, envelope_of
from gearfmu.scene.reader import load_scene
from gearfmu.scene.physics import estimate_build
from gearfmu.assembly.precompute import precompute_tables

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[3]

HERTZ_ONE_TORQUE = """
[scene]
name = "plan_hertz_one_torque"

[gears]
module_mm = 3.0
face_width_mm = 20.0
backlash_um = 100.0

[gears.pinion]
teeth = 20

[gears.gear]
teeth = 31

[deviations.pinion]
profile_form_um = 5.0

[mesh]
contact_model = "hertz"
slices = 2

[operating]
torque_Nm = 200.0
speed_rpm = 1000.0

[tables]
points_per_mesh = 32

[accuracy]
run_mesh_periods = 10
pin = ["integrator", "max_step"]
"""


@pytest.fixture(scope="module")
def hertz(tmp_path_factory):
    p = tmp_path_factory.mktemp("skip") / "hertz.toml"
    p.write_text(HERTZ_ONE_TORQUE, encoding="utf-8")
    return p, load_scene(p)


def test_hertz_scene_lists_what_its_envelope_cannot_need(hertz, capsys):
    """The JSON and the text report list the skipped choices with the scene's reasons; the
    chosen plan is still verified within its target against the full-fidelity reference."""
    path, scene = hertz
    assert main(["plan", str(path), "--json", "-q"]) == 0
    d = json.loads(capsys.readouterr().out)
    reasons = {(r["choice"], None if r["levels"] is None else tuple(r["levels"])): r["reason"] for r in d["skipped"]}
    assert "no temperature range" in reasons[("thermal", None)]
    assert "one torque" in reasons[("torque_points", None)]
    assert "all teeth alike" in reasons[("tooth_specific_errors", None)]
    assert "minimum" in reasons[("slots", None)]
    assert "no [lubricant]" in reasons[("contact_model", ("smooth_ehl",))]
    assert "no [lubricant]" in reasons[("contact_model", ("rough_ehl",))]
    # nothing planned is listed as skipped: slices and points per mesh are measured
    assert not any(r["choice"] in ("slices", "points_per_mesh") and r["levels"] is None for r in d["skipped"])
    assert d["within_target"] and d["verification"]["dte_rel"] <= d["target"]["dte_rel"]
    plan = plan_scene(scene)
    text = format_report(plan)
    assert "skipped" in text and "torque_points: one torque in the envelope" in text


def test_progress_on_stderr_also_with_json(hertz, capsys):
    """The planner's progress goes to stderr, also with --json (stdout stays the JSON alone)."""
    path, _ = hertz
    assert main(["plan", str(path), "--json"]) == 0
    cap = capsys.readouterr()
    json.loads(cap.out)
    assert "gearfmu plan: verify" in cap.err
    assert "gearfmu plan" not in cap.out


def test_progress_bar_is_tqdm_on_stderr_when_installed(hertz, monkeypatch):
    """With tqdm the level measurements show one bar on stderr, advanced to its total, and the
    step lines are written above it (tqdm.write), not through print."""
    _, scene = hertz
    made = []

    class FakeBar:
        def __init__(self, iterable, desc, total=None, leave=True):
            self.total, self.desc, self.file, self.n, self.closed = total, desc, sys.stderr, 0, False
            made.append(self)

        def update(self, n=1):
            self.n += n

        def set_postfix_str(self, s, refresh=True):
            pass

        def write(self, s, file=None):
            assert file is sys.stderr
            self.written = getattr(self, "written", 0) + 1

        def close(self):
            self.closed = True

    monkeypatch.setattr(plan_verify, "progress_bar", FakeBar)
    plan_scene(scene, progress=True)
    bars = [b for b in made if b.desc == "gearfmu plan: levels"]
    assert len(bars) == 1 and bars[0].file is sys.stderr and bars[0].closed
    assert bars[0].n == bars[0].total and bars[0].written > 0


def test_coarser_points_per_mesh_taken_from_the_finer_grid_equal_a_build(hertz):
    """The planner takes the 64- and 32-point tables from the 256-point reference (every 4th /
    8th angle); they equal the table builder's own tables at that resolution bit for bit."""
    _, scene = hertz
    env, acc = envelope_of(scene), accuracy_of(scene)
    ch = choices_of(scene, env, acc)
    full = {n: c.full for n, c in ch.items()}
    ev = Evaluator(scene, env, acc, False)
    ev.tables(full)
    for ppm in (32, 64):
        cfg = dict(full, points_per_mesh=ppm)
        tb, _ = ev.tables(cfg)
        assert ev.table_key(cfg) in ev.derived
        ref = precompute_tables(**ev.table_args(cfg))
        for name in ("k_N_per_m", "e_m", "backlash_half_m", "e_comprehensive_m", "static_te_m", "torque_Nm"):
            assert np.array_equal(getattr(tb, name), getattr(ref, name)), name
        assert tb.k_mean_N_per_m == ref.k_mean_N_per_m


def test_expensive_contact_reference_capped_and_listed():
    """The fractal example scene: 256 points per mesh of fractal tables are far above the
    plan-time budget per reference build, so the reference stays at the scene's 32 points and
    the finer levels are listed as skipped with that reason (no table is built here)."""
    from dataclasses import replace
    scene = load_scene(ROOT / "examples" / "scenes" / "seed001_table1_fractal.toml")
    for p in (64, 128, 256):
        assert estimate_build(replace(scene, tables=replace(scene.tables, points_per_mesh=p))).build_s \
            > PLAN_TABLE_BUILD_S, p
    ppm, why = reference_points_per_mesh(scene)
    assert ppm == 32 and "plan-time budget" in why
    ch = choices_of(scene, envelope_of(scene), accuracy_of(scene))
    assert ch["points_per_mesh"].levels == [16, 32]
    rows = [r for r in skipped_choices(ch, []) if r["choice"] == "points_per_mesh"]
    assert rows == [{"choice": "points_per_mesh", "levels": [64, 128, 256], "reason": why}]
    # a Hertz scene keeps the 256-point reference
    hertz = load_scene(ROOT / "examples" / "scenes" / "seed003_table1.toml")
    assert reference_points_per_mesh(hertz) == (256, "")
