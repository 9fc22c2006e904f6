"""examples/gearbox_forms.py: the example reducer as one gearbox FMU (Co-Simulation and Model
Exchange) and as an SSP of stage FMUs, each against the monolithic native gearbox solver.

References: the native gearbox solver at the same communication points.  The Co-Simulation FMU
runs the same integrator on the same tables (the gearbox FMU's contract: within 1e-9 of the
range); the Model Exchange FMU is integrated by fmpy's CVode at rtol 1e-8 (docs/gearbox.md "Model
Exchange": about 1e-4 of the range); the SSP carries the flange coupling's error, about 0.1 % of
the range at a 2e-5 s communication step (docs/gearbox.md "The SSP of stage FMUs", measured by
benchmarks/bench_composition.py).
"""
import json
import runpy
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow  # builds two FMUs and an SSP

ROOT = Path(__file__).resolve().parents[2]


def test_three_forms_against_the_native_solver(tmp_path):
    mod = runpy.run_path(str(ROOT / "examples" / "gearbox_forms.py"), run_name="gearbox_forms")
    assert mod["main"](["--stop-time", "0.005", "--comm-step", "2e-5", "--out", str(tmp_path)]) == 0
    summary = json.loads((tmp_path / "gearbox_forms.json").read_text())
    forms = summary["forms"]
    bounds = {"gearbox FMU, Co-Simulation": 1e-9, "gearbox FMU, Model Exchange (CVode)": 1e-3,
              "SSP of stage FMUs (fmpy)": 1e-2}
    assert set(forms) == {"native", *bounds}
    for label, bound in bounds.items():
        err = forms[label]["max_error_over_range"]
        assert set(err) == {"stage1.dte", "stage1.mesh_force", "stage2.dte", "stage2.mesh_force"}
        assert max(err.values()) < bound, (label, err)
    for name in ("gearbox_forms.csv", "gearbox_forms_stage1.png", "gearbox_forms_stage2.png"):
        assert (tmp_path / name).stat().st_size > 0, name
