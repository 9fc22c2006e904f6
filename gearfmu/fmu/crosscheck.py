"""Reference results of a gearfmu FMU in the layout of the FMI Cross-Check, and a check of any FMU
against such a set (docs/fmu_import.md "Reference results").

The layout is the one the Modelica Association's FMI Cross-Check rules prescribe for an exported
FMU ("FMI Cross-Check: How to Improve FMI Compliance", version 4.1, section 9.1.4 "Files to
submit" and section 10 "CSV Rules"), which fmpy's cross-check tools read
(``fmpy.cross_check.validate_vendor_repo.validate_test_fmu``, ``fmpy.util.read_ref_opt_file``)::

    <model>.fmu        the FMU
    <model>_ref.csv    reference solution: "time" + at most 10 outputs, names quoted, C float literals,
                       time increasing, at most 1 MB
    <model>_in.csv     the input signals (every input of the model description; linear between
                       rows, a repeated time a step)
    <model>_ref.opt    StartTime, StopTime, StepSize, RelTol (+ OutputIntervalLength when the
                       reference is thinned to stay under 1 MB)
    ReadMe.txt         what the set is and how it was computed

The successor layout, the Reference-FMUs' ``extra/org.fmi-standard.fmi-ls-ref/`` (a manifest and a
``<model>_out.csv`` inside the FMU, layered standard fmi-ls-ref 1.0.0-alpha), is not final; every
gearfmu FMU already carries its reference result inside (``resources/validation/``).

The reference solution is not the FMU's own output: it is the native numba solver
(:func:`gearfmu.dynamics.native.simulate`, an implementation of docs/model.md independent of the C
kernel) on the tables and parameters the FMU carries, stepped with the same communication step
and the same inputs.  The inputs hold the start values, except a ramp of the pinion torque by
:data:`TORQUE_STEP` over the middle half of the run (linear between the rows, as the rules
prescribe; no discontinuity, so a master needs no extra communication point and every master that
samples the inputs at its communication points applies the same values).

:func:`check_reference_results` runs an FMU (any FMU: fmpy's master, the set's inputs and
experiment) and compares it with ``<model>_ref.csv``: each column within ``RelTol`` of its range,
and fmpy's cross-check band test (:func:`fmpy.util.validate_result`) without an outlier.
"""
from __future__ import annotations

import argparse
import json
import shutil
import sys
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Optional

import numpy as np

from ..common.settings import RunSettings
from ..dynamics.native import simulate
from ..tables.mesh_tables import MeshTables

__all__ = ["REFERENCE_OUTPUTS", "REL_TOL", "write_reference_results", "check_reference_results", "main"]

#: the outputs of ``<model>_ref.csv`` (the rules recommend at most 10 important variables)
REFERENCE_OUTPUTS = ("pinion_speed", "gear_speed", "pinion_angle", "gear_angle", "dte", "mesh_force",
                     "mesh_stiffness")
#: agreement required of each column, as a fraction of the column's range: a master that steps the
#: FMU with the set's StepSize reproduces the native solver to round-off (docs/standalone.md
#: "Agreement and masters": 1e-9 at an exact step; fmpy's step sizes differ by ulps, which impacts
#: amplify to 3.5e-7 of range)
REL_TOL = 1e-6
#: the rules' size limit of one CSV file (bytes)
MAX_CSV_BYTES = 1_000_000
#: relative change of the pinion torque over the ramp of ``<model>_in.csv``
TORQUE_STEP = 0.1


@dataclass
class FmuData:
    """What the set is computed from, read from the FMU itself."""
    model_name: str
    inputs: List[str]
    parameters: dict
    tables: MeshTables


def _read_fmu(fmu_path: Path) -> FmuData:
    from fmpy import read_model_description  # fmpy: only to read the FMU

    md = read_model_description(str(fmu_path))
    with zipfile.ZipFile(fmu_path) as z:
        names = set(z.namelist())
        if "resources/provenance.json" not in names or "resources/tables.bin" not in names:
            raise ValueError(f"{fmu_path}: not a gearfmu FMU (no resources/provenance.json or tables.bin)")
        prov = json.loads(z.read("resources/provenance.json"))
        tables = MeshTables.from_bytes(z.read("resources/tables.json"), z.read("resources/tables.bin"),
                                       source=f"{fmu_path.name}:resources")
    inputs = [v.name for v in md.modelVariables if v.causality == "input"]
    return FmuData(md.modelName, inputs, prov["parameters"], tables)


def _csv(path: Path, names, rows) -> None:
    """A CSV by the rules: quoted names, then C float literals (repr: shortest round-trip)."""
    with open(path, "w", encoding="utf-8", newline="\n") as f:
        f.write(",".join(f'"{n}"' for n in names) + "\n")
        for r in rows:
            f.write(",".join(repr(float(x)) for x in r) + "\n")


def write_reference_results(fmu_path, out_dir, *, model_name: Optional[str] = None) -> Dict[str, Path]:
    """Write the cross-check set of the gearfmu FMU ``fmu_path`` into ``out_dir``; return the paths
    by role ("fmu", "ref", "in", "opt", "readme").  ``model_name`` (default: the FMU's modelName)
    names the files.  SI units: times s, torques N*m, outputs as the FMU's."""
    fmu_path = Path(fmu_path)
    d = _read_fmu(fmu_path)
    name = model_name or d.model_name
    p, t = d.parameters, d.tables
    stop, H = float(p["stop_time_s"]), float(p["output_interval_s"])
    T1, T2 = float(p["pinion_torque_start_Nm"]), float(p["gear_torque_start_Nm"])
    axis = np.asarray(t.torque_Nm, dtype=float)
    T1b = T1 * (1.0 + TORQUE_STEP)
    if axis.size > 1 and not axis[0] <= T1b <= axis[-1]:  # stay inside the torque axis (no clamp)
        T1b = T1 * (1.0 - TORQUE_STEP)
    ramp_t, ramp_T = [0.0, 0.25 * stop, 0.75 * stop, stop], [T1, T1, T1b, T1b]  # the rows of _in.csv
    # the FMU's settings as its record states them (damping model and integrator as their codes)
    settings = RunSettings(stop_time_s=stop, output_interval_s=H, max_step_s=float(p["max_step_s"]),
                           integrator=int(p.get("integrator", 0)), damping_ratio=float(p["damping_ratio"]),
                           damping_model=int(p["damping_model"]),
                           pinion_speed_start_rad_s=float(p["pinion_speed_start_rad_s"]),
                           pinion_angle_start_rad=float(p.get("pinion_angle_start_rad", 0.0)),
                           pinion_torque_start_Nm=T1, gear_torque_start_Nm=T2)
    temp = p.get("bulk_temperature_start_C")
    res = simulate(t, settings, pinion_torque_Nm=lambda t_s: float(np.interp(t_s, ramp_t, ramp_T)), gear_torque_Nm=T2,
                   bulk_temperature_C=None if temp is None else float(temp))

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {"fmu": out / f"{name}.fmu", "ref": out / f"{name}_ref.csv", "in": out / f"{name}_in.csv",
             "opt": out / f"{name}_ref.opt", "readme": out / "ReadMe.txt"}
    if fmu_path.resolve() != paths["fmu"].resolve():
        shutil.copyfile(fmu_path, paths["fmu"])
    cols = [np.asarray(res.time_s)] + [np.asarray(getattr(res, c)) for c in REFERENCE_OUTPUTS]
    rows = np.column_stack(cols)
    stride = 1
    while len(rows[::stride]) * (len(cols) * 24 + 2) > MAX_CSV_BYTES:  # 24 characters a value at most
        stride += 1
    keep = rows[::stride]
    if keep[-1, 0] != rows[-1, 0]:  # the reference ends at StopTime
        keep = np.vstack([keep, rows[-1:]])
    _csv(paths["ref"], ["time", *REFERENCE_OUTPUTS], keep)
    start_value = {"pinion_torque": (T1, T1b), "gear_torque": (T2, T2)}
    if temp is not None:
        start_value.update({k: (float(temp), float(temp)) for k in d.inputs if k not in start_value})
    in_rows = [[time_s] + [start_value[k][which] for k in d.inputs] for time_s, which in zip(ramp_t, (0, 0, 1, 1))]
    _csv(paths["in"], ["time", *d.inputs], in_rows)
    opt = [f"StartTime, {0.0!r}", f"StopTime, {stop!r}", f"StepSize, {H!r}", f"RelTol, {REL_TOL!r}"]
    if stride > 1:
        opt.append(f"OutputIntervalLength, {stride * H!r}")
    paths["opt"].write_text("\n".join(opt) + "\n", encoding="utf-8")
    paths["readme"].write_text(
        f"{name}: FMI Cross-Check set (rules version 4.1, section 9.1.4) of a gearfmu gear-pair FMU.\n"
        f"Reference ({name}_ref.csv): gearfmu's native solver (an implementation of the model independent of\n"
        f"the FMU's C kernel) on the tables and parameters inside the FMU, communication step {H!r} s.\n"
        f"Inputs ({name}_in.csv): the start values; pinion_torque ramps from {T1!r} to {T1b!r} N*m between\n"
        f"t = {ramp_t[1]!r} s and {ramp_t[2]!r} s (linear between rows). A master steps the FMU with StepSize and\n"
        f"applies the inputs at its communication points; every column then agrees within RelTol of its\n"
        "range. Check any FMU against this set: gearfmu crosscheck <FMU> <this folder>.\n", encoding="utf-8")
    return paths


def _opt(path: Path) -> Dict[str, float]:
    from fmpy.util import read_ref_opt_file  # the rules' reader (checks the required elements)

    return read_ref_opt_file(str(path))


def check_reference_results(fmu_path, set_dir, *, model_name: Optional[str] = None,
                            rel_tol: Optional[float] = None) -> dict:
    """Run ``fmu_path`` (any FMI 2/3 Co-Simulation FMU, through fmpy) over the experiment and inputs
    of the cross-check set in ``set_dir`` and compare with its ``_ref.csv``.  ``model_name``: the
    set's file prefix (default: the one ``*_ref.csv`` in the folder).  Returns ``{"passed",
    "columns": {name: deviation / range}, "rel_tol", "band_outliers"}``; ``passed`` when every
    column is within ``rel_tol`` (default: the set's RelTol) and fmpy's cross-check band test
    (:func:`fmpy.util.validate_result`) finds no outlier."""
    import fmpy  # fmpy: heavy, only to run an FMU
    from fmpy.util import read_csv, validate_result  # fmpy: the cross-check's CSV reader and band test

    set_dir = Path(set_dir)
    if model_name is None:
        refs = sorted(set_dir.glob("*_ref.csv"))
        if len(refs) != 1:
            raise ValueError(f"{set_dir}: {len(refs)} *_ref.csv files; name the model (--model)")
        model_name = refs[0].name[:-len("_ref.csv")]
    opt = _opt(set_dir / f"{model_name}_ref.opt")
    ref = read_csv(set_dir / f"{model_name}_ref.csv")
    in_path = set_dir / f"{model_name}_in.csv"
    inputs = read_csv(in_path) if in_path.is_file() else None
    names = list(ref.dtype.names[1:])
    step = opt["StepSize"] or None
    res = fmpy.simulate_fmu(str(fmu_path), start_time=opt["StartTime"], stop_time=opt["StopTime"],
                            output_interval=step, step_size=step, input=inputs, output=names)
    tol = float(opt["RelTol"]) if rel_tol is None else float(rel_tol)
    t_ref, t_res = ref["time"], res["time"]
    columns = {}
    for n in names:
        y = np.interp(t_ref, t_res, np.asarray(res[n], dtype=float))
        span = float(np.ptp(ref[n])) or max(float(np.max(np.abs(ref[n]))), 1.0)
        columns[n] = float(np.max(np.abs(y - ref[n])) / span)
    band = float(validate_result(result=res[["time", *names]], reference=ref))
    reached = t_res[-1] >= opt["StopTime"] * (1 - 1e-12)
    return {"passed": reached and band == 0.0 and all(v <= tol for v in columns.values()),
            "columns": columns, "rel_tol": tol, "band_outliers": band, "model": model_name}


def main(argv=None) -> int:
    """``python -m gearfmu.fmu.crosscheck FMU SET_DIR [--model NAME] [--rel-tol X]``: one line per
    column, then "passed" or "FAILED"; exit status 0 when passed, 1 when not, 2 on bad input."""
    ap = argparse.ArgumentParser(prog="gearfmu crosscheck", description=check_reference_results.__doc__)
    ap.add_argument("fmu")
    ap.add_argument("set_dir")
    ap.add_argument("--model", default=None)
    ap.add_argument("--rel-tol", type=float, default=None)
    a = ap.parse_args(argv)
    try:
        r = check_reference_results(a.fmu, a.set_dir, model_name=a.model, rel_tol=a.rel_tol)
    except (OSError, ValueError, KeyError) as exc:
        print(f"gearfmu crosscheck: {exc}", file=sys.stderr)
        return 2
    for n, v in r["columns"].items():
        print(f"{n:16s} max |FMU - reference| / range = {v:.3g} (RelTol {r['rel_tol']:g})")
    print(f"cross-check band test: {r['band_outliers']:.3g} of the samples outside")
    print("passed" if r["passed"] else "FAILED")
    return 0 if r["passed"] else 1


if __name__ == "__main__":
    sys.exit(main())
