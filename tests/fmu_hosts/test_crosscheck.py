"""Reference results in the FMI Cross-Check layout and the check of an FMU against them
(gearfmu.fmu.crosscheck, docs/fmu_import.md "Reference results").

References (none produced by the code under test):
* the FMI Cross-Check rules, version 4.1, section 9.1.4 (files) and 10 (CSV rules), as fmpy's
  cross-check validator reads them (``fmpy.cross_check.validate_vendor_repo.validate_test_fmu``:
  the FMU's model description, ``_ref.opt``'s required elements, both CSVs against the FMU's
  variables, file sizes) on the set laid out in the cross-check tree
  fmus/2.0/cs/<platform>/<tool>/<version>/<model>;
* the reference solution is gearfmu's native numba solver, not the FMU: the FMU (both runtimes,
  stepped by fmpy's master with the set's inputs) must agree within RelTol of each range, and
  fmpy's own band test must find no outlier; an FMU of other tables must fail.
"""
import shutil

import fmpy
import pytest
from fmpy.cross_check.validate_vendor_repo import validate_test_fmu

from gearfmu.cli import main as cli_main
from gearfmu.fmu.crosscheck import REFERENCE_OUTPUTS, check_reference_results, write_reference_results
from gearfmu.fmu.pythonfmu_build import build_fmu
from gearfmu.fmu.standalone_build import build_standalone_fmu

from factories import make_tables

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

H = 1e-4


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    d = tmp_path_factory.mktemp("xc")
    t = make_tables(torque=(50.0, 150.0))
    kw = dict(stop_time_s=200 * H, output_interval_s=H, max_step_s=1e-5, pinion_torque_start_Nm=100.0,
              validation=False)
    other = make_tables(torque=(50.0, 150.0))
    other.k_N_per_m[:] *= 0.8
    return {"standalone": build_standalone_fmu(t, d / "sa.fmu", platforms=["x86_64-linux"], model_name="gearXC", **kw),
            "fmi3": build_standalone_fmu(t, d / "sa3.fmu", platforms=["x86_64-linux"], model_name="gearXC",
                                         fmi_version=3, **kw),
            "pythonfmu": build_fmu(t, d / "py.fmu", model_name="gearXC", **{k: v for k, v in kw.items()
                                                                               if k != "validation"}),
            "other": build_standalone_fmu(other, d / "other.fmu", platforms=["x86_64-linux"], model_name="gearXC",
                                          **kw)}


@pytest.fixture(scope="module")
def xc_set(fmus, tmp_path_factory):
    out = tmp_path_factory.mktemp("set") / "fmus" / "2.0" / "cs" / "linux64" / "gearfmu" / "0.1.0" / "gearXC"
    paths = write_reference_results(fmus["standalone"], out)
    return out, paths


def test_the_set_is_what_the_cross_check_rules_ask(xc_set, fmus):
    out, paths = xc_set
    assert sorted(p.name for p in out.iterdir()) == ["ReadMe.txt", "gearXC.fmu", "gearXC_in.csv", "gearXC_ref.csv",
                                                      "gearXC_ref.opt"]
    assert validate_test_fmu(str(out)) == []
    ref = paths["ref"].read_text().splitlines()
    assert ref[0] == ",".join(f'"{n}"' for n in ("time", *REFERENCE_OUTPUTS)) and len(ref) == 202
    opt = paths["opt"].read_text()
    assert "StartTime, 0.0" in opt and "StopTime, 0.02" in opt and "StepSize, 0.0001" in opt and "RelTol" in opt
    inputs = [ln.split(",") for ln in paths["in"].read_text().splitlines()]
    md = fmpy.read_model_description(str(fmus["standalone"]))
    assert inputs[0] == ["\"time\""] + [f'"{v.name}"' for v in md.modelVariables if v.causality == "input"]
    assert inputs[2][1] == inputs[1][1] != inputs[3][1] == inputs[4][1]  # the torque ramp, no discontinuity
    assert all(f.stat().st_size < 1_000_000 for f in out.iterdir() if f.suffix == ".csv")


@pytest.mark.parametrize("which", ["standalone", "fmi3", "pythonfmu"])
def test_gearfmu_fmus_pass_their_set(xc_set, fmus, which):
    out, _ = xc_set
    r = check_reference_results(fmus[which], out)
    assert r["passed"], r
    assert set(r["columns"]) == set(REFERENCE_OUTPUTS) and r["band_outliers"] == 0.0


def test_an_fmu_of_other_tables_fails(xc_set, fmus):
    out, _ = xc_set
    r = check_reference_results(fmus["other"], out)
    assert not r["passed"] and max(r["columns"].values()) > 1e-3


def test_cli_writes_and_checks_a_set(xc_set, fmus, tmp_path, capsys):
    out, _ = xc_set
    assert cli_main(["crosscheck", str(fmus["standalone"]), str(out)]) == 0
    assert capsys.readouterr().out.strip().endswith("passed")
    assert cli_main(["crosscheck", str(fmus["other"]), str(out)]) == 1
    assert capsys.readouterr().out.strip().endswith("FAILED")
    empty = tmp_path / "empty"
    empty.mkdir()
    assert cli_main(["crosscheck", str(fmus["standalone"]), str(empty)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("gearfmu crosscheck:") and "\n" not in err
    shutil.rmtree(empty)
