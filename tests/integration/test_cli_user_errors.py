"""What a new user hits first: helical scenes plan, validate can fail, bad files answer in one line.

References (no numbers here come from gearfmu itself):
* Overlap ratio eps_beta = b sin(beta) / (pi m_n) (ISO 6336-1; docs/helical.md): seed 001 Table 1
  (b = 60 mm, beta = 36 deg, m_n = 5 mm) gives 2.245, so with eps_alpha >= 1 the total contact
  ratio exceeds 3.2 and a slot count must be at least 4 (one tooth pair per slot at any time).
* FMU against native: two implementations of docs/model.md (the FMU's C kernel, the numba
  solver) agree to round-off (1e-13 of each range measured), not bitwise: a tolerance of 1e-15
  must fail, the default 1e-9 must pass.
* The CLI contract of gearfmu/cli.py: bad input -> one line on stderr naming the file, status 2.
"""
import contextlib
import io
import json
import math
import re
import zipfile
from pathlib import Path

import pytest

from gearfmu.cli import main, make_parser
from gearfmu.fmu.compare import FmuFile, FmuMismatchError, check_fmu_matches, diff_report, open_fmu
from gearfmu.pipeline import compute_tables, load
from gearfmu.scene.reader import default_scene_path

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

REPO = Path(__file__).resolve().parents[2]
SEED001 = REPO / "examples" / "scenes" / "seed001_table1.toml"


def _cli(*args):
    """``gearfmu ARGS`` in this process (an uncaught exception fails the test): (status, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main([str(a) for a in args])
        except SystemExit as exc:  # argparse
            rc = exc.code
    return rc, out.getvalue(), err.getvalue()


def _one_line_error(rc, err, *words):
    assert rc == 2, err
    assert "Traceback" not in err, err
    lines = [ln for ln in err.splitlines() if ln.startswith("gearfmu")]
    assert len(lines) == 1, err
    for w in words:
        assert str(w) in lines[0], (w, lines[0])
    return lines[0]


# ------------------------------------------------------------------ 1. helical scenes plan
def test_helical_scene_plans_with_slots_from_the_total_contact_ratio(capsys):
    eps_beta = 60.0 * math.sin(math.radians(36.0)) / (math.pi * 5.0)
    assert eps_beta == pytest.approx(2.245, abs=1e-3)
    need = math.ceil(1.0 + eps_beta)  # eps_alpha >= 1
    rc = main(["plan", "-q", "--json", str(SEED001)])
    out = capsys.readouterr().out
    assert rc == 0
    slots = next(c for c in json.loads(out)["choices"] if c["choice"] == "slots")
    assert min(slots["levels"]) >= need and slots["chosen"] >= need, slots


# ------------------------------------------------------------------ one FMU for the module
@pytest.fixture(scope="module")
def csv_fmu(tmp_path_factory):
    """`gearfmu tables` on the default scene, then `gearfmu build --tables T.csv` with no
    --tables-meta: the sidecar written beside the CSV is found by name."""
    d = tmp_path_factory.mktemp("cli")
    rc, out, err = _cli("tables", "-q", "-o", d / "T.gtab")
    assert rc == 0, err
    assert (d / "T.csv").is_file() and (d / "T.meta.toml").is_file()
    rc, out, err = _cli("build", "-q", "--tables", d / "T.csv", "-o", d / "default.fmu")
    assert rc == 0, err
    return d, d / "default.fmu"


# ------------------------------------------------------------------ 5. CSV tables and sidecar
def test_tables_csv_builds_without_tables_meta(csv_fmu):
    d, fmu = csv_fmu
    assert fmu.is_file()
    from gearfmu.tables.table_import import load_tables_file

    import numpy as np

    back = load_tables_file(d / "T.csv", d / "T.meta.toml")
    ref = compute_tables(load(None))
    assert np.array_equal(back.k_N_per_m, ref.k_N_per_m) and np.array_equal(back.e_m, ref.e_m)


def test_csv_without_sidecar_says_tables_meta_is_needed(csv_fmu, tmp_path):
    d, _ = csv_fmu
    lone = tmp_path / "lone.csv"
    lone.write_bytes((d / "T.csv").read_bytes())
    rc, _, err = _cli("build", "--tables", lone, "-o", tmp_path / "x.fmu")
    _one_line_error(rc, err, "lone.csv", "--tables-meta", "teeth_pinion", "inertia_gear_kgm2")


# ------------------------------------------------------------------ 2. validate can fail
def test_validate_passes_on_its_own_scene_and_fails_beyond_the_tolerance(csv_fmu):
    _, fmu = csv_fmu
    rc, out, err = _cli("validate", "--fmu", fmu, "--stop-time", "0.005")
    assert rc == 0, out + err
    assert "PASSED" in out
    rc, out, err = _cli("validate", "--fmu", fmu, "--stop-time", "0.005", "--tolerance", "1e-15")
    assert rc == 1, out + err
    assert "FAILED" in out
    assert re.search(r"validate: mesh_force differs by \S+ = \S+ of its range", err), err


def test_validate_refuses_an_fmu_of_another_scene_before_running(csv_fmu, tmp_path):
    _, fmu = csv_fmu
    text = default_scene_path().read_text(encoding="utf-8")
    other = re.sub(r'(?m)^name = "([^"]+)"', r'name = "other_pair"', text, count=1)
    other = re.sub(r"(?m)^torque_Nm = .*$", "torque_Nm = 123.0", other, count=1)
    assert other != text
    (tmp_path / "other.toml").write_text(other, encoding="utf-8")
    rc, out, err = _cli("validate", tmp_path / "other.toml", "--fmu", fmu)
    _one_line_error(rc, err, fmu.name, "'other_pair'", "'seed000_table1'")
    assert "samples" not in out  # nothing simulated


def test_validate_refuses_other_tables_and_another_slot_count(csv_fmu):
    _, fmu = csv_fmu
    f = open_fmu(fmu)
    scene = load(None)
    t2 = compute_tables(scene)
    assert t2.slots == 2
    from dataclasses import replace

    t4 = compute_tables(replace(scene, tables=replace(scene.tables, slots=4)))
    with pytest.raises(FmuMismatchError, match="other tables"):
        check_fmu_matches(f, tables=t4)
    # without a validation record only the variables can tell: 2 slots against 4, refused
    bare = FmuFile(f.path, f.model_description, None, None)
    check_fmu_matches(bare, tables=t2)
    with pytest.raises(FmuMismatchError, match=r"has 2 pair slots .*\(4 slots\)"):
        check_fmu_matches(bare, tables=t4)


def test_diff_report_never_compares_part_of_the_outputs():
    import numpy as np

    a = {"x": np.arange(5.0), "y": np.ones(5)}
    with pytest.raises(FmuMismatchError, match="only in the reference"):
        diff_report(a, {"x": np.arange(5.0)})
    with pytest.raises(FmuMismatchError, match="5 samples in the reference, 4"):
        diff_report(a, {"x": np.arange(4.0), "y": np.ones(5)})


# ------------------------------------------------------------------ 3. bad files, one line
@pytest.fixture
def bad_files(tmp_path):
    (tmp_path / "nomd.fmu").write_bytes(b"")
    with zipfile.ZipFile(tmp_path / "nomd.fmu", "w") as z:
        z.writestr("a.txt", "x")
    (tmp_path / "empty.toml").write_text("", encoding="utf-8")
    (tmp_path / "adir").mkdir()
    (tmp_path / "afile").write_text("x", encoding="utf-8")
    (tmp_path / "cols.csv").write_text("pinion_angle_deg,foo\n0,1\n1,2\n", encoding="utf-8")
    (tmp_path / "cols.meta.toml").write_text(
        "teeth_pinion = 20\nteeth_gear = 30\nbase_radius_pinion_m = 0.05\nbase_radius_gear_m = 0.07\n"
        "inertia_pinion_kgm2 = 0.01\ninertia_gear_kgm2 = 0.02\n", encoding="utf-8")
    return tmp_path


@pytest.mark.parametrize("cmd", [["validate"], ["simulate", "--backend", "fmu"]])
def test_a_file_that_is_not_an_fmu_gets_one_line(bad_files, cmd):
    readme = REPO / "README.md"
    _one_line_error(*_cli(*cmd, "--fmu", readme)[::2], "README.md", "not a zip archive")
    _one_line_error(*_cli(*cmd, "--fmu", bad_files / "nomd.fmu")[::2], "nomd.fmu", "no modelDescription.xml")
    _one_line_error(*_cli(*cmd, "--fmu", bad_files / "adir")[::2], "adir", "directory")


def test_other_bad_inputs_get_one_line(bad_files):
    d = bad_files
    cases = [
        (["plan", d / "empty.toml"], ["empty.toml", "empty"]),
        (["build", d / "adir"], ["adir", "directory"]),
        (["build", "--tables", d / "cols.csv", "-o", d / "x.fmu"], ["cols.csv", "k_slot1_N_per_m"]),
        (["build", "--tables", d / "cols.csv", "--tables-meta", d / "adir", "-o", d / "x.fmu"],
         ["--tables-meta", "adir", "directory"]),
        (["simulate", "-q", "--stop-time", "0.001", "-o", d / "adir"], ["adir", "directory"]),
        (["simulate", "-q", "--stop-time", "0.001", "-o", d / "afile" / "x.csv"], ["afile", "not a folder"]),
        (["tables", "-q", "-o", d / "afile" / "sub" / "x.gtab"], ["afile", "not a folder"]),
        # a folder nobody may write into (sysfs refuses new files even to root)
        (["tables", "-q", "-o", "/sys/gearfmu_test.gtab"], ["/sys/gearfmu_test.gtab", "Permission denied"]),
        (["ssp", "-q", "-o", "/sys/gearfmu_test.ssp"], ["/sys/gearfmu_test.ssp", "Permission denied"]),
        (["bench", "accuracy", "--png", "/sys/gearfmu_test.png"], ["--png", "Permission denied"]),
        (["plan", "-q", "--fmu", "-o", d / "afile"], ["afile", "folder"]),
    ]
    for args, words in cases:
        rc, _, err = _cli(*args)
        _one_line_error(rc, err, *words)


def test_an_output_folder_that_does_not_exist_is_created(tmp_path):
    out = tmp_path / "new" / "deeper" / "t.gtab"
    rc, _, err = _cli("tables", "-q", "-o", out)
    assert rc == 0, err
    assert out.is_file() and out.with_suffix(".csv").is_file() and (out.parent / "t.meta.toml").is_file()


# ------------------------------------------------------------------ 6. wording
def test_option_errors_name_the_option_once(capsys):
    with pytest.raises(SystemExit) as exc:
        make_parser().parse_args(["simulate", "--stop-time", "abc"])
    assert exc.value.code == 2
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert last.endswith("error: argument --stop-time: not a number: 'abc'") and last.count("--stop-time") == 1, last


def test_help_shows_no_restructuredtext_markup(capsys):
    for argv in (["--help"], ["bench", "--help"], ["validate", "--help"]):
        with pytest.raises(SystemExit):
            make_parser().parse_args(argv)
        out = capsys.readouterr().out
        assert "`" not in out, out
    with pytest.raises(SystemExit):
        make_parser().parse_args(["--help"])
    out = capsys.readouterr().out
    assert "  gearfmu plan     [SCENE]" in out  # the command summary keeps its layout


def test_readme_command_summary_lists_every_option():
    """Every option of every subcommand appears in the README's command block on that command's
    lines, and SCENE is optional everywhere (it defaults to the default scene)."""
    text = (REPO / "README.md").read_text(encoding="utf-8")
    block = text.split("## Command line", 1)[1].split("```", 2)[1]
    p = make_parser()
    sub = next(a for a in p._actions if a.__class__.__name__ == "_SubParsersAction")
    for name, sp in sub.choices.items():
        lines = block.split(f"gearfmu {name}", 1)[1].split("\ngearfmu ", 1)[0]
        for act in sp._actions:
            opts = [o for o in act.option_strings if o not in ("-h", "--help")]
            if opts:
                assert any(re.search(re.escape(o) + r"\b", lines) for o in opts), (name, opts)
        if any(a.dest == "scene" for a in sp._actions):
            assert lines.lstrip().startswith("[SCENE]"), (name, lines[:40])
    assert make_parser().parse_args(["plan"]).scene is None


def test_spur_wording_is_gone_and_integrator_is_documented(csv_fmu):
    _, fmu = csv_fmu
    desc = open_fmu(fmu).model_description.description
    assert "helical" in desc.lower(), desc
    py = (REPO / "pyproject.toml").read_text(encoding="utf-8")
    assert "helical" in re.search(r'(?m)^description = "(.*)"', py).group(1).lower()
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    assert "spur gear pair into" not in readme
    assert re.search(r"(?m)^\| `integrator` \| parameter", readme)
    assert re.search(r"(?m)^\| integrator \| parameter", (REPO / "docs" / "fmu.md").read_text(encoding="utf-8"))


def test_tables_with_a_temperature_axis_plot_and_export_the_standard_temperature(tmp_path, monkeypatch):
    """The plot and the CSV form have no temperature axis: `gearfmu tables` writes them at the
    standard temperature, a node of the axis, where the tables are the stored slice bit for bit
    (docs/model.md "Temperature axis"); the reference is that slice as it went into the stack."""
    import numpy as np

    import gearfmu.pipeline as pipeline
    from gearfmu.tables.table_import import load_tables_csv
    from factories import AXIS, temp_tables

    stacked, slices = temp_tables()
    monkeypatch.setattr(pipeline, "compute_tables", lambda scene, progress=False, allow_large=False: stacked)
    rc, out, err = _cli("tables", "-q", "-o", tmp_path / "t.gtab")
    assert rc == 0, err
    assert (tmp_path / "t.png").stat().st_size > 0
    back = load_tables_csv(tmp_path / "t.csv", tmp_path / "t.meta.toml")
    ref = slices[list(AXIS).index(stacked.default_temperature_C)]
    assert np.array_equal(back.k_N_per_m, ref.k_N_per_m) and np.array_equal(back.e_m, ref.e_m)


def test_validate_of_a_planned_scene_compares_like_with_like(tmp_path, monkeypatch):
    """A scene with [accuracy] builds its FMU from the plan (tables, step bound, integrator);
    validate runs the native solver with the same plan, so the two agree to round-off (the
    reference of the module docstring), within the default tolerance."""
    from support.plan_scenes import SMALL

    (tmp_path / "small.toml").write_text(SMALL, encoding="utf-8")
    monkeypatch.chdir(tmp_path)  # validate builds into build/ of the working folder
    rc, out, err = _cli("validate", tmp_path / "small.toml", "--stop-time", "0.005")
    assert rc == 0, out + err
    assert "PASSED" in out
