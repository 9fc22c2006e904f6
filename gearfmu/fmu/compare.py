"""FMU against the native solver: run both on the same inputs and steps, compare.

The FMU is driven by fmpy (``simulate_fmu`` with ``output_interval`` equal to
the communication step); the native solver by :func:`gearfmu.dynamics.native.simulate`
with the same communication step and the same internal step bound, so both
take identical RK4 substeps and should agree to round-off.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Dict, List

import numpy as np

from ..common.vocabulary import INTEGRATORS
from ..dynamics.native import simulate

SCALAR_OUTPUTS = ("pinion_speed", "gear_speed", "pinion_angle", "gear_angle", "dte",
                  "mesh_force", "mesh_stiffness")


def output_names(slots: int) -> List[str]:
    """The FMU's output variable names for P slots (the naming contract)."""
    names = list(SCALAR_OUTPUTS)
    names += [f"pair_force[{i + 1}]" for i in range(slots)]
    names += [f"load_sharing[{i + 1}]" for i in range(slots)]
    return names


def native_columns(result, slots: int) -> Dict[str, np.ndarray]:
    """Native SimResult arrays keyed by FMU output names."""
    cols = {n: np.asarray(getattr(result, n)) for n in SCALAR_OUTPUTS}
    pf = np.asarray(result.pair_force)
    ls = np.asarray(result.load_sharing)
    for i in range(slots):
        cols[f"pair_force[{i + 1}]"] = pf[:, i]
        cols[f"load_sharing[{i + 1}]"] = ls[:, i]
    return cols


@dataclass
class FmuRun:
    time_s: np.ndarray
    columns: Dict[str, np.ndarray]
    wall_s: float


def run_fmu(fmu_path, *, stop_time_s: float, comm_step_s: float, start_values=None,
            names=None) -> FmuRun:
    """Simulate an FMU with fmpy at a fixed communication step."""
    import fmpy  # fmpy: heavy, only to run an FMU

    t0 = time.perf_counter()
    res = fmpy.simulate_fmu(str(fmu_path), stop_time=stop_time_s, output_interval=comm_step_s,
                            start_values=dict(start_values or {}), output=names)
    wall = time.perf_counter() - t0
    cols = {n: np.asarray(res[n], dtype=float) for n in res.dtype.names if n != "time"}
    return FmuRun(np.asarray(res["time"], dtype=float), cols, wall)


def diff_report(ref: Dict[str, np.ndarray], other: Dict[str, np.ndarray]) -> Dict[str, dict]:
    """Per output: largest and RMS absolute difference, the reference's range,
    and the largest difference relative to that range."""
    out = {}
    for name, a in ref.items():
        if name not in other:
            continue
        b = other[name]
        n = min(len(a), len(b))
        d = np.abs(a[:n] - b[:n])
        rng = float(np.ptp(a[:n])) if n else 0.0
        scale = rng if rng > 0 else max(float(np.max(np.abs(a[:n]))) if n else 0.0, 1e-300)
        out[name] = {
            "max_abs_diff": float(d.max()) if n else 0.0,
            "rms_diff": float(np.sqrt(np.mean(d ** 2))) if n else 0.0,
            "range": rng,
            "rel_max_diff": float(d.max() / scale) if n else 0.0,
        }
    return out


def fmu_integrator(fmu_path, start_values=None):
    """Name of the integrator an FMU runs with ('rk4', 'rk4_kink'): its parameter
    ``integrator`` (docs/model.md; code 0/1) from ``start_values`` or else the start
    value in its modelDescription.xml; None if the FMU has no such parameter."""
    from fmpy import read_model_description  # fmpy: heavy, only to read an FMU


    if start_values and "integrator" in start_values:
        code = int(start_values["integrator"])
    else:
        md = read_model_description(str(fmu_path))
        var = next((v for v in md.modelVariables if v.name == "integrator"), None)
        if var is None or var.start is None:
            return None
        code = int(var.start)
    return {v: k for k, v in INTEGRATORS.items()}.get(code)


def validate_fmu_against_native(fmu_path, tables, *, native_kwargs: dict, stop_time_s: float,
                                comm_step_s: float, start_values=None) -> dict:
    """The report of ``gearfmu validate``: fmpy validation problems, per-output
    differences (FMU minus native), wall time of each.  Without ``integrator`` in
    ``native_kwargs`` the native run uses the FMU's own (:func:`fmu_integrator`)."""
    from fmpy.validation import validate_fmu  # fmpy: heavy, only to validate an FMU


    problems = [str(p) for p in validate_fmu(str(fmu_path))]
    if "integrator" not in native_kwargs:
        integ = fmu_integrator(fmu_path, start_values)
        if integ is not None:
            native_kwargs = dict(native_kwargs, integrator=integ)
    names = output_names(tables.slots)
    fmu = run_fmu(fmu_path, stop_time_s=stop_time_s, comm_step_s=comm_step_s,
                  start_values=start_values, names=names)
    simulate(tables, **dict(native_kwargs, stop_time_s=min(stop_time_s, 10 * comm_step_s),
                            comm_step_s=comm_step_s))  # JIT warm-up, not timed
    t0 = time.perf_counter()
    nat = simulate(tables, **dict(native_kwargs, stop_time_s=stop_time_s, comm_step_s=comm_step_s))
    native_wall = time.perf_counter() - t0
    per = diff_report(native_columns(nat, tables.slots), fmu.columns)
    return {
        "fmu": str(fmu_path),
        "fmpy_problems": problems,
        "stop_time_s": stop_time_s,
        "comm_step_s": comm_step_s,
        "max_step_s": native_kwargs.get("max_step_s"),
        "samples": int(len(fmu.time_s)),
        "outputs": per,
        "max_abs_diff": {k: v["max_abs_diff"] for k, v in per.items()},
        "rms_diff": {k: v["rms_diff"] for k, v in per.items()},
        "max_rel_diff": max((v["rel_max_diff"] for v in per.values()), default=0.0),
        "native_wall_s": native_wall,
        "fmu_wall_s": fmu.wall_s,
    }
