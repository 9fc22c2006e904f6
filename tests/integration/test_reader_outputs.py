"""What a reader sees on screen, in files and in the guide says what it means.

References (none produced by the code under test):
* SI prefixes: 1 N/um = 1e6 N/m, 1 kN/um = 1e9 N/m -- the unit an axis label names fixes the
  factor between the plotted numbers and the tables' N/m;
* the FMU interface spec modeldescription/variables.toml, read here with tomllib: the unit of
  every output;
* docs/native.md and docs/cli.md: the CSV layout they state is the layout the command writes;
* the default scene's mesh frequency z1 n1 / 60 = 45 * 2000 / 60 = 1500 Hz and docs/scene.md's
  rule of at least 20 samples per mesh period for an output interval;
* matplotlib's own layout (window extents after a draw): a legend beside the axes covers no curve.
"""
import contextlib
import io
import re
import types
from pathlib import Path

import numpy as np
import pytest

from gearfmu.cli import _print_contact, main, print_report
from gearfmu.fmu.compare import output_names

from factories import make_tables

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

REPO = Path(__file__).resolve().parents[2]
#: N/m per unit of the stiffness units an axis may name (SI prefixes; u = micro)
SI_STIFFNESS = {"N/m": 1.0, "N/mm": 1e3, "N/um": 1e6, "N/µm": 1e6, "kN/mm": 1e6, "kN/um": 1e9, "kN/µm": 1e9,
                "MN/m": 1e6, "GN/m": 1e9}


def _spec_units():
    spec = tomllib.loads((REPO / "modeldescription" / "variables.toml").read_text())
    return {v["name"]: v.get("unit", "1") for v in spec["variable"]}


def _stdout(fn, *a):
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        fn(*a)
    return out.getvalue()


# ----------------------------------------------------------------- tables plot
def test_stiffness_axis_label_states_the_scale_of_the_plotted_values():
    from gearfmu.plots import tables_figure

    t = make_tables(P=2)
    ax = tables_figure(t).axes[0]
    unit = re.fullmatch(r"stiffness \[([^\]]+)\]", ax.get_ylabel())
    assert unit and unit.group(1) in SI_STIFFNESS, ax.get_ylabel()
    total = next(ln for ln in ax.get_lines() if ln.get_label() == "total (TVMS)")
    n = len(total.get_ydata())
    np.testing.assert_allclose(np.asarray(total.get_ydata()) * SI_STIFFNESS[unit.group(1)],
                               t.k_N_per_m[0].sum(axis=0)[:n], rtol=1e-12)


def test_legend_of_a_four_slot_pair_covers_no_curve():
    """Seed 001's helical pair has four slots; the legends sit beside the axes, inside the figure."""
    from gearfmu.plots import tables_figure

    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig = tables_figure(make_tables(P=4, eps=3.4))
    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw(renderer)                      # the layout as saved
    page = fig.bbox
    for ax in fig.axes:
        leg = ax.get_legend()
        if leg is None:
            continue
        lb, ab = leg.get_window_extent(renderer), ax.get_window_extent(renderer)
        assert lb.x0 >= ab.x1, (ax.get_ylabel(), lb, ab)            # beside the data area, not on it
        assert lb.x1 <= page.x1 + 0.5 and lb.y0 >= page.y0 - 0.5    # and not cut off


# --------------------------------------------------------------- simulate CSV
def test_simulate_csv_has_the_layout_the_docs_state(tmp_path):
    native_md = (REPO / "docs" / "native.md").read_text()
    cli_md = (REPO / "docs" / "cli.md").read_text()
    assert "`# units:` line, a row of FMU names" in native_md and "`gearfmu simulate` writes the\nsame layout" in native_md
    assert "a `# units:` comment line with one unit per\ncolumn, a row of names" in cli_md

    scene = tmp_path / "s.toml"
    scene.write_text((REPO / "gearfmu" / "scene" / "data" / "default_scene.toml").read_text()
                     .replace("slices = 44 ", "slices = 4 ").replace("points_per_mesh = 64", "points_per_mesh = 32"))
    out = tmp_path / "run.csv"
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        rc = main(["simulate", str(scene), "--stop-time", "0.001", "--output-interval", "2e-5", "-o", str(out), "-q"])
    assert rc == 0, err.getvalue()
    lines = out.read_text().splitlines()
    assert lines[0].startswith("# units: ")
    units = lines[0][len("# units: "):].split(",")
    names = lines[1].split(",")
    slots = sum(1 for n in names if n.startswith("pair_force["))
    assert names == ["time", *output_names(slots)]                 # FMU names, the FMU's order
    spec = _spec_units()
    want = ["s"] + [spec[re.sub(r"\[\d+\]$", "", n)] for n in names[1:]]
    assert units == want
    data = np.loadtxt(out, delimiter=",", skiprows=2)
    assert data.shape == (51, len(names))                          # row 0 = the initial state
    np.testing.assert_allclose(data[:, 0], np.arange(51) * 2e-5, rtol=0, atol=1e-15)
    # 17 significant digits: every number reads back to the float64 it was written from
    assert all(x == format(float(x), ".17g") for x in lines[3].split(","))


# ------------------------------------------------------------- validate table
def test_validate_table_names_units_and_says_what_range_is():
    names = output_names(1)
    rep = {"fmu": "x.fmu", "scene": "s", "fmpy_problems": [], "samples": 3, "comm_step_s": 1e-4, "max_step_s": 1e-5,
           "stop_time_s": 2e-4, "native_wall_s": 0.1, "fmu_wall_s": 0.1, "tolerance": 1e-9, "failed": {},
           "outputs": {n: {"max_abs_diff": 1e-12, "rms_diff": 1e-13, "range": 2.0, "rel_max_diff": 5e-13}
                       for n in names}}
    text = _stdout(print_report, rep)
    head = next(ln for ln in text.splitlines() if ln.startswith("output"))
    assert "unit" in head.split()
    spec = _spec_units()
    for n in names:
        row = next(ln for ln in text.splitlines() if ln.startswith(n + " "))
        assert row.split()[1] == spec[re.sub(r"\[\d+\]$", "", n)], row
    assert "range = max - min of the native solver's output over the run" in text


# ------------------------------------------------------------- flagged points
def test_flagged_points_are_explained_where_they_are_printed():
    prov = {"contact": {"model": "fractal_mixed", "eta0_Pas": 0.2, "speed_rad_s": 100.0, "solves": 50,
                        "load_iteration": {"rows": [
                            {"torque_Nm": 600.0, "failures": 3, "failures_by_status": {"full_film": 3}},
                            {"torque_Nm": 1200.0, "failures": 2,
                             "failures_by_status": {"full_film": 1, "complete_contact": 1}}]}}}
    text = _stdout(_print_contact, types.SimpleNamespace(provenance=prov))
    assert "5 flagged points (flagged = (position, slice load) requests" in text
    assert "4 full_film: film parameter h_min/sigma >= 3" in text
    assert "1 complete_contact: asperities would touch over the whole nominal area: Hertz stiffness used" in text


# ---------------------------------------------------------------- plan report
def _plan_dict():
    from gearfmu.plan.verify import MEASURES

    contrib = {"tvms_rel": 0.0, **{k: 0.0 for k in MEASURES}, "budget_use": 0.0, "limit": "dte_rel"}
    return {"scene": "fr", "target": {"dte_rel": 0.02, "mesh_force_rel": 0.02, "safety_factor": 1.0,
                                      "measures": {k: 0.02 for k in MEASURES}},
            "envelope": {"torque_range_Nm": [600.0, 1200.0], "speed_range_rpm": [1000.0, 1000.0],
                         "temperature_range_C": None},
            "verification": {"points": 1, "probes": 1, "native_runs": 1, "budget_runs": 80, "attempts": [],
                             "worst": "steady", "dte_rel": 1e-3, "mesh_force_rel": 1e-3, "u": 0.05, "limit": "dte_rel",
                             "worst_by_measure": {}},
            "choices": [{"choice": "contact_model", "full": "fractal_mixed", "chosen": "fractal_mixed",
                         "status": "pinned", "contribution": contrib},
                        {"choice": "points_per_mesh", "full": 32, "chosen": 32, "status": "kept",
                         "contribution": contrib}],
            "what_if": [], "skipped": [], "within_target": True,
            "full": {"max_step_s": 1e-6}, "chosen": {"max_step_s": 1e-6},
            "cost": {"full": {}, "chosen": {}, "gain_full_over_chosen": {}}, "estimate": {}, "fmu_verification": {}}


def test_plan_report_columns_never_run_together():
    from gearfmu.plan import format_report

    text = format_report(types.SimpleNamespace(to_dict=_plan_dict))
    row = next(ln for ln in text.splitlines() if ln.startswith("contact_model"))
    assert row.split() == ["contact_model", "fractal_mixed", "fractal_mixed", "pinned", "0", "0", "0"], row
    head = next(ln for ln in text.splitlines() if ln.startswith("choice"))
    assert head.index("status") > row.index("fractal_mixed", row.index("fractal_mixed") + 1)


def test_plan_fmu_report_says_what_each_fmu_is():
    """`gearfmu plan --fmu`: the report names the runtime, FMI version and platforms of both FMUs."""
    from gearfmu.plan import format_report

    line = "runtime standalone (all C, needs no Python), FMI 2.0 Co-Simulation, platforms: linux64"
    fmus = {w: {"fmu_path": f"/x/{w}.fmu", "fmu_bytes": 10, "table_build_s": 1.0, "fmu_build_s": 1.0,
                "contents": line} for w in ("full", "chosen")}
    case = {"note": "steady", "dte_rel": 1e-3, "mesh_force_rel": 1e-3, "within_target": True,
            "temperature_input": {"full": None, "chosen": None}, "cpu_per_sim_s": {"full": 1.0, "chosen": 0.5},
            "cpu_gain_full_over_chosen": 2.0}
    d = dict(_plan_dict(), fmu_verification={"fmus": fmus, "cases": {"steady": case}, "within_target": True})
    text = format_report(types.SimpleNamespace(to_dict=lambda: d))
    assert f"  full FMU /x/full.fmu: {line}" in text.splitlines()
    assert f"  chosen FMU /x/chosen.fmu: {line}" in text.splitlines()


# --------------------------------------------------------------- bench accuracy
def test_bench_accuracy_says_its_errors_are_relative_and_to_what():
    from gearfmu.bench import accuracy_table

    rep = {"case": "c", "comm_step_s": 1e-4, "stop_time_s": 0.01,
           "reference": {"method": "DOP853 event-located", "rtol": 1e-11},
           "rows": [{"method": "native-rk4", "setting": "h=H/4", "wall_s": 0.01, "dte_rel_rms_err": 1e-3,
                     "dte_rel_max_err": 2e-3, "force_rel_rms_err": 1e-3}]}
    text = "\n".join(accuracy_table(rep))
    assert "errors are RELATIVE" in text and "divided by the reference's range (max - min over the run)" in text
    assert "reference: DOP853 event-located, rtol 1e-11" in text


# ------------------------------------------------------- the guide's fmpy examples
@pytest.mark.parametrize("page", ["getting_started.md", "fmu_import.md"])
def test_guide_fmpy_output_interval_samples_the_mesh(page):
    """docs/scene.md: an output interval needs >= 20 samples per mesh period (a fixed 1e-4 s
    aliases).  The guide's fmpy calls on the default FMU must follow it."""
    scene = tomllib.loads((REPO / "gearfmu" / "scene" / "data" / "default_scene.toml").read_text())
    f_mesh = scene["gears"]["pinion"]["teeth"] * scene["operating"]["speed_rpm"] / 60.0
    assert f_mesh == 1500.0
    text = (REPO / "docs" / page).read_text()
    calls = re.findall(r'simulate_fmu\("build/GearPairSeed000\.fmu".*?output_interval=([0-9.eE+-]+)', text, re.S)
    assert calls, page
    for dt in calls:
        assert 1.0 / (float(dt) * f_mesh) >= 20, (page, dt)
    assert "A fixed 1e-4 s is 6 samples per mesh period" in (REPO / "docs" / "scene.md").read_text()
