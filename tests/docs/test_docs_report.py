"""benchmarks/report.py writes the validation report from benchmark JSON, and only from it.

Reference: the JSON files written here by hand (a small fixture of each source's output format,
with round numbers chosen for this test); the page and the README speed table must show exactly
those numbers, formatted, and name the benchmark that produced them.  A source without JSON is
listed as not run.  (Not timed: speed lives in the benchmarks.)
"""
import importlib.util
import json
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


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
    fmu_speed.update(fmu_over_native_per_sim_s_lowlevel=2.5, fmu_over_native_per_sim_s_simulate_fmu=6.0)
    stiffness_iso = {"rows": [{"pair": "seed 004 pair I", "eps_alpha": 1.6, "iso_c_prime": 12.5,
                               "iso_c_gamma_alpha": 20.0, "ours_max_single_pair": 15.0,
                               "ours_mean_shared_correction": 18.0, "ours_mean_independent_foundations": 22.0,
                               "ours_mean_no_foundation": 40.0}]}
    pts = ["meshing-in", "pitch", "meshing-out"]
    thermal = {"points": pts, "tables23": [
        {"pair": "I", "quantity": "mesh", "state": "shrinkage", "point": p, "seed": 2e8, "ours": 2.2e8,
         "ours_with_seed_standard": 2.01e8} for p in pts],
        "implied_load": {"I": {"table4_load_N": 10000.0, "laws": {
            "radial_tangential": {"pinion": [10000.0, 10010.0, 9990.0], "gear": [10000.0, 10000.0, 10000.0]}}}},
        "oil": {"rows": [{"temperature_C": 40.0, "eta0_Pas": 0.25, "h_min_dowson_higginson_m": 2e-6,
                          "h_min_solver_m": 1.9e-6, "h_central_moes_m": 3e-6, "h_central_solver_m": 2.4e-6,
                          "k_film_solver_N_per_m_per_m": 2e12}]}}
    load_sharing = {"torque_Nm": 2000.0, "w_N_per_m": 3.5e5, "oil_temperature_C": 60.0, "width_m": 1e-3,
                    "k_smooth_N_per_m": 1.0e9, "k_hertz_N_per_m": 2e8,
                    "rows": [{"level": 4, "film_parameter_dh": 2.5, "film_parameter_central": 3.0, "eta_per_m2": 5e11,
                              "beta_m": 3e-7, "sigma_s_m": 1.5e-6, "alpha": 150.0, "asperity_share": 0.1,
                              "h_c_m": 5e-6, "h_c_smooth_m": 4.9e-6, "area_ratio": 1e-3, "k_film_N_per_m": 0.95e9,
                              "k_asp_N_per_m": 0.1e9, "k_N_per_m": 1.05e9}]}
    fractal = {"torque_Nm": 2000.0, "w_N_per_m": 3.5e5, "R_m": 0.02, "u_m_s": 10.0, "b_m": 3e-4, "L_s_m": 5e-4,
               "levels": [{"level": 4, "K_n_per_width_N_per_m2": 7.5e12, "K_s_per_width_N_per_m2": 7e12,
                           "K_l_per_width_N_per_m2": 5e11, "real_area_ratio": 0.5, "film_parameter": 2.2,
                           "lambda_c": 0.56, "slicings": [1, 2], "K_n_rel_spread_over_slicings": 0.0}],
               "element_size": [{"level": 4, "element_side_m": a, "K_s_per_width_N_per_m2": k, "real_area_ratio": r}
                                for a, k, r in ((5e-4, 7e12, 0.5), (1e-3, 8e12, 0.75))]}
    # speed goals: round numbers on either side of each goal; "plan" and "tests" have no JSON
    kernels = {"cases": {"default_scene/rk4": {"case": "default_scene", "integrator": "rk4", "slots": 2,
                                               "internal_steps": 100, "events": 0, "c_ns_per_step": 80.0,
                                               "numba_ns_per_step": 96.0, "numba_over_c": 1.2,
                                               "final_dte_rel_diff": 0.0}}}
    integrators = {"fronts": [{"case": "computed_default_scene",
                               "speedup_vs_DOP853": {"rk4": {"1e-06": 250.0}, "rk4_kink": {"1e-06": 400.0},
                                                     "rk4_node": {"1e-06": 500.0}}}]}
    rtf_row = {"points_per_mesh": 64, "integrator": "rk4_node", "substeps": 2, "dte_rel_rms_err": 9e-5,
               "dte_rel_rms_err_same_table": 6e-6, "c_host_real_time_factor": 60.0, "fmpy_real_time_factor": 40.0,
               "fmpy_raw_real_time_factor": 45.0}
    fmu_rtf = {"scene": "default", "comm_step_s": 1e-4, "simulated_s": 0.1, "target": 1e-4,
               "reference": {"kind": "native rk4_kink", "points_per_mesh": 4096, "max_step_s": 2e-7},
               "reference_check": {"dte_rel_rms_err": 2e-8}, "runs": [rtf_row],
               "python_floor": {"lean": {"real_time_factor": 44.0, "ns_per_step": 2272.0},
                                "raw": {"real_time_factor": 55.0, "ns_per_step": 1818.0}},
               "cheapest": {"dte_rel_rms_err": {k: rtf_row for k in ("c_host_real_time_factor", "fmpy_real_time_factor",
                                                                       "fmpy_raw_real_time_factor")}}}
    startup = {"commands": {"build": {"cold_s": 9.0, "warm_s": 1.5}}}
    ehl_corners = {"summary": {"points": 63, "max_cpu_s": 1.5, "median_cpu_s": 0.1},
                   "rows": [{"case": "default_1025", "M": 20.0, "cpu_s": 0.004}]}
    sawtooth = {"limit_slices": 960, "limit_change_rel": 1e-6, "eps_alpha": 1.5, "eps_beta": 2.0, "points_per_mesh": 64,
                "limit_static_te_ptp_m": 1e-6, "limit_k_ptp_over_mean": 0.06,
                "rows": [{"slices": 15, "one_over_ns_eps_alpha": 1 / 22.5, "k_dev_whole": 0.05, "k_dev_partial": 0.001,
                          "te_dev_whole": 0.9, "te_dev_partial": 0.025}]}
    seed003 = {"statements": [{"statement": "Fig. 10: growing f_fa raises the DTE amplitude", "holds": True,
                               "numbers": {"A_rms": [7.5, 8.25]}},
                              {"statement": "Fig. 12: a pair loses contact", "holds": False,
                               "numbers": {"f_fa=25 um": []}}]}
    helical_contact = {"iso_c_gamma_alpha": 13.5, "torque_Nm": 1200.0,
                       "rows": [{"model": "smooth_ehl", "slices": 4, "points_per_mesh": 8, "k_mean_N_per_mm_um": 14.85,
                                 "rel_diff_iso": 0.1, "over_hertz": 1.07, "ptp_over_mean": 0.057,
                                 "hertz_ptp_over_mean": 0.06, "spur_ptp_over_mean": 0.644}]}
    gb_rows = [{"method": "rk4_node", "setting": "h=H/64", "wall_s": 0.002, "dte_rel_rms_err": 2e-8},
               {"method": "solve_ivp-DOP853", "setting": "rtol=1e-06", "wall_s": 1.0, "dte_rel_rms_err": 1e-8}]
    gearbox = {"fronts": [{"case": "torque_step", "rows": gb_rows,
                           "wall_at": {"rk4_node": {"1e-04": 0.001, "1e-06": 0.002},
                                       "solve_ivp-DOP853": {"1e-04": 1.0, "1e-06": 1.0}},
                           "speedup_vs_DOP853": {"rk4_node": {"1e-04": 1000.0, "1e-06": 500.0}}}],
               "summary_min_speedup_vs_DOP853": {"rk4_node": {"1e-04": 1000.0, "1e-06": 500.0}},
               "example": {"scene": "gearbox_two_stage", "stages": 2, "bodies": 6, "integrator": "rk4_node",
                           "step_s": 2e-6, "stop_time_s": 0.1, "wall_per_simulated_s": 0.4,
                           "ns_per_internal_step": 600.0, "events": 4500}}
    pl_rows = [dict(r, cpu_s=r["wall_s"]) for r in gb_rows]
    planetary = {"fronts": [{"case": "position_error", "rows": pl_rows,
                             "cpu_at": {"rk4_node": {"1e-04": 0.02, "1e-06": 0.04},
                                        "solve_ivp-DOP853": {"1e-04": 16.0, "1e-06": 18.0}},
                             "speedup_vs_DOP853": {"rk4_node": {"1e-04": 800.0, "1e-06": 450.0}}}],
                 "summary_min_speedup_vs_DOP853": {"rk4_node": {"1e-04": 800.0, "1e-06": 450.0}},
                 "example": {"scene": "planetary_reducer", "meshes": 7, "dofs": 22, "integrator": "rk4_node",
                             "step_s": 1.35e-6, "stop_time_s": 0.05, "cpu_per_simulated_s": 3.4,
                             "ns_per_internal_step": 4300.0, "events": 11826}}
    pt = lambda h, c, e: {"factor": 1.0, "max_step_s": h, "cpu_s": c, "wall_s": c, "dte_rel_rms_err": e}
    gearbox_fmu = {"scene": "gearbox_two_stage", "sim_s": 0.5, "comm_step_s": 1e-4, "repeat": 5, "goal": 1.3,
                   "gearbox": {"max_step_s": 2e-6, "equals_native_solver": True,
                               "default": pt(2e-6, 0.08, {"s1": 4e-8, "s2": 1e-9})},
                   "stages": [{"stage": "s1", "default": pt(2e-6, 0.03, 8e-8), "at_gearbox_step": pt(2e-6, 0.03, 8e-8),
                               "at_gearbox_accuracy": {"max_step_s": 1.5e-6, "cpu_s": 0.04}},
                              {"stage": "s2", "default": pt(3e-6, 0.02, 5e-9), "at_gearbox_step": pt(2e-6, 0.03, 1e-9),
                               "at_gearbox_accuracy": {"max_step_s": 2e-6, "cpu_s": 0.03}}],
                   "gearbox_matching_pairs": {"max_step_s": 2.5e-6, "cpu_s": 0.065},
                   "ratio_same_accuracy": 8 / 7, "ratio_matching_pairs": 1.3, "ratio_step_rule": 1.6,
                   "ratio_same_step": 4 / 3}
    for name, data in (("gearbox_fmu", gearbox_fmu), ("gearbox", gearbox), ("planetary", planetary), ("helical_contact", helical_contact), ("seed003_statements", seed003), ("helical_sawtooth", sawtooth), ("seed004", seed004), ("accuracy", accuracy), ("fmu_speed", fmu_speed), ("ehl", ehl),
                       ("trends", trends), ("stiffness_iso", stiffness_iso), ("thermal", thermal),
                       ("load_sharing", load_sharing), ("fractal", fractal), ("kernels", kernels),
                       ("integrators", integrators), ("startup", startup), ("ehl_corners", ehl_corners),
                       ("fmu_rtf", fmu_rtf)):
        (d / f"{name}.json").write_text(json.dumps(data))
    (d / "runs.json").write_text(json.dumps({"seed004": {"ok": True, "wall_s": 4.0, "command": "x"}}))


@pytest.mark.slow
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
    # ISO 6336-1: 18 and 22 against c_ga = 20 are -10 % and +10 %, 40 is 2.0 x; 15 against c' = 12.5 is +20 %
    assert ("| seed 004 pair I | 1.6000 | 12.50 | 15.00 (+20 %) | 20.00 | 18.00 (-10 %) | 22.00 (+10 %) "
            "| 40.00 (2.0 ×) |") in page
    # thermal model alone: (a) 2.01 against 2 is +0.50 %, (b) 2.2 is +10 %; implied load within 0.10 %
    assert "| I | mesh | shrinkage | 2 / 2 / 2 | 2.01 / 2.01 / 2.01 | +0.50 / +0.50 / +0.50 % | 2.2 / 2.2 / 2.2 " in page
    assert "| I | `radial_tangential` | 10000 / 10010 / 9990 | 10000 / 10000 / 10000 | 10000.0 | -0.10 % … +0.10 % |" in page
    assert "| h_c solver (µm) | 2.4 |" in page and "h_c -20.0 % … -20.0 % against Moes" in page
    # load sharing: k/k_smooth 1.05; fractal: the element sizes side by side
    assert "| 4 | 2.50 | 3.00 | 5e+11 | 0.3 | 1.5 | 150 | 0.1 | 5.000 / 4.900 | 0.001 | 0.9500 | 0.1 | 1.0500 |" in page
    assert "| 4 | 7e+12 / 8e+12 | 0.50 / 0.75 |" in page
    assert "| `smooth_ehl` | 4 × 8 | 14.85 | +10.0 % | × 1.070 | 0.057 | 0.060 | 0.644 |" in page
    assert "| Fig. 10: growing f_fa raises the DTE amplitude | yes | A_rms: [7.5, 8.25] |" in page
    assert "| Fig. 12: a pair loses contact | **no** | f_fa=25 um: none |" in page
    assert "| 15 | 4.44e-02 | 5.00e-02 | 1.00e-03 | 9.00e-01 | 2.50e-02 |" in page      # helical sawtooth
    # speed goals beside the measured values, in the page and the README; no JSON: "not measured"
    for where in (page, readme.read_text()):
        assert "| warm `gearfmu build` of the default scene ≤ 2 s | 1.50 s warm, 9.0 s cold (empty numba cache) | yes |" in where
        assert "| numba native solver per step ≤ 1.3 × the C kernel | ≤ 1.20 × over 1 case/integrator rows" in where
        assert "| FMU ≤ 3 × native per simulated second | 2.50 × (low-level FMI loop), 6.00 × " in where
        assert "rk4 ≥ 250 ×, rk4_kink ≥ 400 ×, rk4_node ≥ 500 ×" in where
        assert ("| FMU ≥ 50 × real time at 1e-4 relative DTE error (fmpy low-level loop) | fmpy low-level loop "
                "40 ×, fmpy's raw ctypes pointers 45 ×, C host 60 ×; fastest within 1.00e-04: 64 points per mesh, "
                "rk4_node, max step = communication step / 2, total DTE error 9.00e-05; the fmpy loop around two "
                "no-op C functions: 44 × (raw pointers 55 ×)") in where
        assert "| EHL film ≤ 1 s per point | worst 1.5 s, median 100 ms CPU over 63 points" in where
        assert "| EHL film ≤ 5 ms per point at the default settings | ≤ 4 ms CPU" in where
        assert "| `gearfmu plan` of the default scene ≤ 60 s | not measured (no `plan` JSON" in where
        assert "| C kernel per RK4 step ≤ 1.5 × the plain-C proxy at equal flags | not measured (" in where
    goals = {r[0]: r[2] for r in rep.goal_rows(json.loads(json.dumps({n: json.loads((src / f"{n}.json").read_text())
                                                                      for n in ("startup", "integrators", "fmu_rtf")})))}
    assert goals["FMU ≥ 50 × real time at 1e-4 relative DTE error (fmpy low-level loop)"] == "no"
    assert goals["test suite ≤ 5 min"] == "n/a"
    # gearboxes: the wall times and speedups of the fixture, the example's cost, the goal row
    assert "| torque_step | rk4_node | 1.00e-03 | 2.00e-03 | 1000 × / 500 × |" in page
    assert "0.4 s of wall time per simulated second, 600 ns per internal step" in page
    for where in (page, readme.read_text()):
        assert ("| native gearbox solver ≥ 300 × the scipy reference at 1e-6 relative DTE error | rk4_node ≥ 500 × "
                "(smallest over the cases torque_step; met judged on the default integrator rk4_node) | yes |") in where
    # planetary stages: the fixture's wall times and speedups, the example's cost, the goal row
    assert "| position_error | rk4_node | 2.00e-02 | 4.00e-02 | 800 × / 450 × |" in page
    assert "3.4 s of CPU time per simulated second, 4300 ns per internal step (11826 events in 0.05 s)" in page
    for where in (page, readme.read_text()):
        assert ("| native planetary solver ≥ 300 × the scipy reference at 1e-6 relative DTE error | rk4_node ≥ 450 × "
                "(smallest over the cases position_error; met judged on the default integrator rk4_node) | yes |") in where
    # the gearbox FMU against its stages' pair FMUs: the fixture's costs per simulated second and ratios
    assert "| gearbox FMU | 2.00e-06 | 0.16 | s1 4.00e-08, s2 1.00e-09 |" in page
    assert "| pair FMU s2, the gearbox's accuracy | 2.00e-06 | 0.06 | 1.00e-09 (interpolated) |" in page
    assert "| pair FMUs at the gearbox's accuracy per stage (the goal's) | 1.14 |" in page
    for where in (page, readme.read_text()):
        assert ("| gearbox FMU ≤ 1.3 × its stages' pair FMUs per simulated second (C host, same accuracy) | 1.14 × "
                "(pair FMUs at the gearbox's accuracy per stage; 1.30 × with the gearbox at the pair FMUs' accuracy, "
                "1.60 × at every FMU's default step; CPU time, gearbox_two_stage, C host) | yes |") in where
    # sources without JSON are named, not silently dropped; plots are written and linked
    assert "reach 44 × real time (fmpy's low-level loop, 2272 ns per step) and 55 × (raw ctypes pointers" in page
    assert "## Dynamic response against experiment: seed 003 Fig. 3\n\nNot run" in page
    assert (tmp_path / "docs" / "img" / "validation_integrators.png").is_file()
    assert "](img/validation_integrators.png)" in page


def test_report_refuses_a_missing_directory(tmp_path, capsys):
    rep = _report()
    assert rep.main(["--from", str(tmp_path / "nope"), "--out", str(tmp_path / "v.md"), "--readme", "none"]) == 2
    assert "not a directory" in capsys.readouterr().err


def test_a_failing_source_or_section_does_not_stop_the_others(tmp_path, monkeypatch, capsys):
    """One source exits with an error, another prints JSON: the second is saved, the page is written,
    the failure is named on stderr and the exit status is 1.  A section whose JSON lacks its fields
    is named on the page instead of stopping it."""
    rep = _report()
    py = rep.PY
    monkeypatch.setattr(rep, "SOURCES", {
        "broken": ([py, "-c", "import sys; sys.exit('broken on purpose')"], None, "broken"),
        "fractal": ([py, "-c", "import json; print(json.dumps(dict(levels=1)))"], None, "fractal"),
        "seed004": ([py, "-c", "print('step {1}'); print('[]')"], None, "seed004")})
    out = tmp_path / "v.md"
    rc = rep.main(["--only", "broken", "fractal", "seed004", "--save-dir", str(tmp_path / "json"),
                   "--out", str(out), "--img-dir", str(tmp_path / "img"), "--readme", "none"])
    err = capsys.readouterr().err
    assert rc == 1
    assert "source broken: exit status 1: broken on purpose" in err and "section fractal" in err
    assert (tmp_path / "json" / "fractal.json").is_file() and not (tmp_path / "json" / "broken.json").exists()
    page = out.read_text()
    assert "## Fractal\n\nCould not be rendered from its JSON (TypeError" in page
    assert "### Tooth and pair stiffness against seed 004 Tables 2-3" in page   # the other sections are there
    # a saved file that is not JSON: named, its section "not run", the page still written
    (tmp_path / "json" / "seed004.json").write_text("{not json")
    assert rep.main(["--from", str(tmp_path / "json"), "--out", str(out), "--img-dir", str(tmp_path / "img"),
                     "--readme", "none"]) == 1
    assert "seed004.json is not JSON" in out.read_text() and "source seed004" in capsys.readouterr().err


def test_plan_section_from_saved_json(tmp_path):
    """The fidelity-plan table: per scene the target, the choices kept and reduced (the study's and
    bench_plan's choice rows; one-level choices left out), the worst error the envelope search found,
    the plan time and the worst FMU case, exactly as in the fixture JSON; a stopped plan is named."""
    rep = _report()
    src = tmp_path / "json"
    src.mkdir()
    plan = {"scenes": {
        "default": {"wall_s": 12.34, "cpu_s": 10.0, "exit_code": 0,
                    "target": {"dte_rel": 0.02, "mesh_force_rel": 0.05},
                    "choices": [{"choice": "slices", "status": "reduced", "full": 44, "chosen": 1},
                                {"choice": "points_per_mesh", "status": "kept", "full": 256, "chosen": 256},
                                {"choice": "thermal", "status": "fixed", "full": False, "chosen": False},
                                {"choice": "integrator", "status": "pinned", "full": "rk4_kink", "chosen": "rk4_kink"},
                                {"choice": "max_step", "status": "reduced", "full": 0.25, "chosen": 4.0},
                                {"choice": "tooth_specific_errors", "status": "dropped", "full": True, "chosen": False}],
                    "within_target": True, "dte_rel": 1e-3, "mesh_force_rel": 6e-3,
                    "worst": "steady 2000 N*m, 2000 rpm", "native_runs": 3},
        "examples/scenes/x.toml": {"wall_s": 600.0, "exit_code": None, "stopped_after_s": 600.0}}}
    study = {"s.toml": {"target": {"dte_rel": 0.02, "mesh_force_rel": 0.02},
                        "choices": [{"choice": "torque_points", "status": "reduced", "full": 9, "chosen": 5},
                                    {"choice": "thermal", "status": "kept", "full": True, "chosen": True}],
                        "verification": {"dte_rel": 2.4e-3, "mesh_force_rel": 1.13e-2, "worst": "steady 386 N*m",
                                         "native_runs": 872},
                        "within_target": False, "study_wall_s": 95.34, "study_cpu_s": 90.0,
                        "fmu_verification": {"cases": {"steady": {"dte_rel": 1e-3, "mesh_force_rel": 2e-3},
                                                       "warm_up": {"dte_rel": 3e-3, "mesh_force_rel": 1e-3}}}}}
    (src / "plan.json").write_text(json.dumps(plan))
    (src / "plan_study.json").write_text(json.dumps(study))
    (src / "runs.json").write_text(json.dumps({"plan": {"ok": True, "wall_s": 13.0, "command": "x"}}))
    out = tmp_path / "validation.md"
    assert rep.main(["--from", str(src), "--out", str(out), "--img-dir", str(tmp_path / "img"),
                     "--readme", "none"]) == 0
    page = out.read_text()
    assert ("| default scene | 2 % / 5 % | points_per_mesh, integrator (pinned) | slices 44 → 1, "
            "max_step h0/4 → 4 h0, tooth_specific_errors on → off | 1.00e-03 / 6.00e-03 "
            "(steady 2000 N*m, 2000 rpm) | yes | 3 | 12.3 s (10 s CPU) | not run |") in page
    assert "| `examples/scenes/x.toml` | n/a | stopped after 600 s |  | n/a | n/a | n/a | 600.0 s | not run |" in page
    assert ("| `s.toml` (study) | 2 % / 2 % | thermal | torque_points 9 → 5 | 2.40e-03 / 1.13e-02 "
            "(steady 386 N*m) | no | 872 | 95.3 s (90 s CPU), with the FMUs | 3.00e-03 / 2.00e-03 (2 cases) |") in page
    assert "Sources: `benchmarks/bench_plan.py --scenes default` (13 s), `examples/plan_study.py --json` (n/a)." in page
    # the same bench_plan JSON measures the planner's speed goal
    assert "| `gearfmu plan` of the default scene ≤ 60 s | 12.3 s wall, 10.0 s CPU (default scene) | yes |" in page
    # without the study's JSON the section says how to produce it
    (src / "plan_study.json").unlink()
    assert rep.main(["--from", str(src), "--out", str(out), "--img-dir", str(tmp_path / "img"),
                     "--readme", "none"]) == 0
    assert "; `plan_study` not run (`python benchmarks/report.py --only plan_study`)." in out.read_text()


def test_cache_estimate_and_silence_sections_from_saved_json(tmp_path):
    """The table cache, the cost estimate and the silence of the commands: the numbers of the
    fixture (ratios 0.02 and 0.03 of a 40 s table build, estimate ratios 1.5 and 0.6, a 1.2 s
    silence) on the page and in the goals."""
    rep = _report()
    src = tmp_path / "json"
    src.mkdir()
    cache = {"scene": "s.toml", "goal": 0.05, "within_goal": True, "ratio": {"gearfmu tables s.toml": 0.02,
                                                                            "gearfmu build s.toml": 0.03},
             "runs": [{"command": "gearfmu tables s.toml", "table_s": 40.0, "wall_s": 45.0, "cpu_s": 41.0,
                       "from_cache": False},
                      {"command": "gearfmu tables s.toml", "table_s": 0.8, "wall_s": 3.0, "cpu_s": 2.0,
                       "from_cache": True},
                      {"command": "gearfmu build s.toml", "table_s": 1.2, "wall_s": 9.0, "cpu_s": 8.0,
                       "from_cache": True}]}
    row = {"estimate": {"build_s": 3.0, "table_bytes": 2e5, "fmu_bytes": 1.2e6},
           "measured": {"build_cpu_s": 2.0, "build_wall_s": 2.5, "table_bytes": 2e5, "fmu_bytes": 2e6},
           "ratio": {"build_time": 1.5, "table_bytes": 1.0, "fmu_bytes": 0.6}, "counts": {"contact_model": "hertz"}}
    estimate = {"goal": 2.0, "cpu_count": 2, "worst_ratio": 1.67, "within_2x": True, "scenes": {"default": row}}
    silence = {"goal_s": 2.0, "worst_s": 1.2, "worst_startup_s": 0.9,
               "scenes": {"default": {"validate": {"longest_silence_s": 1.2, "before": "gearfmu: building | x",
                                                   "after": "(exit)", "startup_s": 0.9, "wall_s": 4.0,
                                                   "at_s": 1.0, "stderr_writes": 9, "cpu_s": 3.0, "exit": 0}}}}
    for name, data in (("table_cache", cache), ("estimate", estimate), ("silence", silence)):
        (src / f"{name}.json").write_text(json.dumps(data))
    out = tmp_path / "validation.md"
    assert rep.main(["--from", str(src), "--out", str(out), "--img-dir", str(tmp_path / "img"),
                     "--readme", "none"]) in (0, 1)
    page = out.read_text()
    assert "| `gearfmu tables s.toml` | yes | 0.8 | 2 % | 3.0 | 2.0 |" in page
    assert "| `default` | hertz | 3 | 2 | 1.50 | 1.2 / 2 | 0.60 | 1.00 |" in page
    assert "| `default` | `validate` | 1.20 | gearfmu: building / x | 0.90 | 4.0 |" in page
    goals = {r[0]: (r[1], r[2]) for r in rep.goal_rows({"table_cache": cache, "estimate": estimate,
                                                         "silence": silence})}
    assert goals["second command on a scene: table time < 5 % of the first (table cache)"] == (
        "3 % of the first command's table time (40.0 s, scene s.toml)", "yes")
    assert goals["cost estimate within 2 × of the measured table time and sizes"][1] == "yes"
    assert goals["no command silent on stderr for more than 2 s"][1] == "yes"
