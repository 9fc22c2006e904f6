"""benchmarks/report.py writes the validation report from benchmark JSON, and only from it.

Reference: the JSON files written here by hand (a small fixture of each source's output format,
with round numbers chosen for this test); the page and the README speed table must show exactly
those numbers, formatted, and name the benchmark that produced them.  A source without JSON is
listed as not run.  (Not timed: speed lives in the benchmarks.)
"""
import importlib.util
import json
import pathlib

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _report():
    spec = importlib.util.spec_from_file_location("gearfmu_report", ROOT / "benchmarks" / "report.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _fixture(d: pathlib.Path):
    seed004 = [
        {"pair": "I", "point": "pitch", "quantity": "mesh", "state": "standard", "seed": 3.9e8, "ours": 3.51e8},
        {"pair": "I", "point": "pitch", "quantity": "mesh", "state": "shrinkage", "seed": 2.9585e8, "ours": 2.6325e8},
    ]
    accuracy = {"case": "single_sided_impacts", "comm_step_s": 7e-5, "stop_time_s": 8.4e-3,
                "reference": {"rtol": 1e-11},
                "rows": [{"method": "native-rk4", "setting": "h=H/4", "wall_s": 0.0002, "dte_rel_rms_err": 9.6e-3,
                          "dte_rel_max_err": 4.1e-2, "force_rel_rms_err": 1.1e-2},
                         {"method": "native-rk4_kink", "setting": "h=H/64", "wall_s": 0.0018,
                          "dte_rel_rms_err": 1.6e-8, "dte_rel_max_err": 8.2e-8, "force_rel_rms_err": 1.8e-8}]}
    fmu_speed = {"scene": "scene", "slots": 2, "comm_step_scene_s": 2e-5, "native_ns_per_step": 251.0,
                 "fmu_ns_per_step": 240.0, "fmu_over_native_per_step": 0.956, "native_wall_per_sim_s": 0.056,
                 "fmu_lowlevel_wall_per_sim_s": 0.45, "fmu_simulate_fmu_wall_per_sim_s": 0.8,
                 "fmu_instantiate_s": 0.006}
    ehl = {"cases": [{"M": 20.0, "L": 5.0, "options": {"viscosity": "barus", "compressible": False},
                      "rows": [{"n_intervals": 512, "H_central_moes": 3.487, "rel_dev_from_moes": 0.0061,
                                "discretisation_error_estimate": 4.3e-3, "cycles": 12, "cpu_time_ms": 10.5}]}]}
    trends = {"points_per_mesh": 4, "slices": 2, "torques_Nm": [1000.0, 2000.0],
              "mean_tvms_N_per_m": {"hertz": {"1000": 1.0e9, "2000": 1.0e9},
                                    "smooth": {"1000": 1.2e9, "2000": 1.25e9},
                                    "rough_level_4": {"1000": 1.26e9, "2000": 1.2e9}},
              "speed_rpm": {"smooth": {"1000": 1.3e9, "2000": 1.25e9, "4000": 1.28e9}}}
    for name, data in (("seed004", seed004), ("accuracy", accuracy), ("fmu_speed", fmu_speed), ("ehl", ehl),
                       ("trends", trends)):
        (d / f"{name}.json").write_text(json.dumps(data))
    (d / "runs.json").write_text(json.dumps({"seed004": {"ok": True, "wall_s": 4.0, "command": "x"}}))


def test_report_from_saved_json(tmp_path):
    rep = _report()
    src = tmp_path / "json"
    src.mkdir()
    _fixture(src)
    readme = tmp_path / "README.md"
    readme.write_text(f"# x\n\n{rep.SPEED_BEGIN}\nold table\n{rep.SPEED_END}\n\ntail\n")
    out = tmp_path / "docs" / "validation.md"
    assert rep.main(["--from", str(src), "--out", str(out), "--img-dir", str(tmp_path / "docs" / "img"),
                     "--readme", str(readme)]) == 0
    page = out.read_text()
    # seed 004: 3.51e8 against 3.9e8 is -10.0 %; the shrinkage factor 0.75 against 0.7586
    assert "| I | mesh | pitch | 3.9 | 3.51 | -10.0 % |" in page
    assert "| I | mesh | pitch | shrinkage | 0.7586 | 0.7500 | -0.0086 |" in page
    assert "(4 s for both pairs and all states)" in page          # cost from runs.json
    # integrators: the rows as given, and the summary picks rk4_kink's smallest error
    assert "| native-rk4_kink | h=H/64 | 0.0018 | 1.60e-08 | 8.20e-08 | 1.80e-08 |" in page
    assert "DTE RMS error at h=H/64: rk4_kink 1.60e-08" in page
    assert "pair I: within 0.009" in page                           # |0.75 - 0.7586|
    # EHL: the finest Barus grid against Moes' fit in the summary
    assert "M=20, L=5: +0.6 % (512 intervals)" in page
    # seed 000 trends: values against smooth, and each stated direction judged on the numbers
    assert "| rough level 4 | 1.26000 (+5.000 %) | 1.20000 (-4.000 %) |" in page
    assert "| Fig. 15: TVMS rises with torque | smooth film | yes |" in page
    assert "| Fig. 14: TVMS falls as speed rises | smooth film, 1000, 2000, 4000 rpm | no |" in page
    assert "| Fig. 13: rough level 4 below smooth | tables, every torque | 1 of 2 torques |" in page
    # FMU speed, in the page and between the README markers (old content replaced)
    assert "| internal step, native (numba) | 251 ns |" in page
    text = readme.read_text()
    assert "| internal step, FMU (C kernel, long communication steps) | 240 ns (0.96 × native) |" in text
    assert "old table" not in text and text.endswith("\n\ntail\n")
    assert "benchmarks/bench_fmu.py" in text
    # sources without JSON are named, not silently dropped; plots are written and linked
    assert "## Dynamic response against experiment: seed 003 Fig. 3\n\nNot run" in page
    assert (tmp_path / "docs" / "img" / "validation_integrators.png").is_file()
    assert "](img/validation_integrators.png)" in page


def test_report_refuses_a_missing_directory(tmp_path, capsys):
    rep = _report()
    assert rep.main(["--from", str(tmp_path / "nope"), "--out", str(tmp_path / "v.md"), "--readme", "none"]) == 2
    assert "not a directory" in capsys.readouterr().err
