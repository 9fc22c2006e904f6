"""A planetary FMU against the native planetary solver (``gearfmu validate DRIVETRAIN.toml`` of a
drivetrain with planetary stages).

The FMU is stepped at exactly the communication step H from t_k = k*H (the native solver's steps,
:func:`gearfmu.fmu.gearbox_compare.step_fmu`) with its start values.  The FMU shows its kernel state
as locals, and the native solver starts from the FMU's initial state: the two agree to round-off
(measured: bit for bit).  An FMU without them (an older build) is run against the native solver from
its own quasi-static state (numpy's solve, within 1e-12 of the C kernel's): the round-off of the two
starts grows in the lightly damped modes that are zero by symmetry (a floating sun's translations), so
every output is then compared with the largest range of the outputs of its unit (``scale``).
"""
from __future__ import annotations

import dataclasses
import hashlib
import time
from pathlib import Path
from typing import Optional

import numpy as np

from ..common.progress import ticking
from ..planetary.model import PlanetaryModel
from ..planetary.native import simulate as simulate_planetary
from .compare import DEFAULT_TOLERANCE, FmuFile, FmuMismatchError, diff_report, open_fmu
from .gearbox_compare import check_gearbox_fmu_matches, step_fmu
from .planetary_build import native_run

__all__ = ["check_planetary_fmu_matches", "validate_planetary_fmu", "state_names"]


def state_names(model: PlanetaryModel):
    """The FMU's Model Exchange states (locals): psi, omega, every DOF's deviation and its rate."""
    out = ["reference_angle", "reference_speed"]
    for nm in model.dof_names[1:]:
        out += [f"{nm}_deviation", f"{nm}_deviation_rate"]
    return out


def check_planetary_fmu_matches(fmu: FmuFile, model: Optional[PlanetaryModel] = None, variables=None, *,
                                scene_text: Optional[str] = None, scene_label: str = "SCENE") -> None:
    """Refuse (FmuMismatchError, naming both) an FMU that is not a planetary FMU, was built from another
    drivetrain scene than ``scene_text``, carries other tables of a mesh than ``model``'s, or has other
    variables than ``variables``; checks only what is given.  Nothing is simulated."""
    rec = fmu.record or {}
    if rec and rec.get("model") != "planetary":
        raise FmuMismatchError(f"{fmu.path} is a {rec.get('model', 'gear-pair')} FMU, not a planetary FMU; "
                               f"{scene_label} is a drivetrain with planetary stages (gearfmu build makes its FMU)")
    check_gearbox_fmu_matches(fmu, None, variables, scene_text=scene_text, scene_label=scene_label)
    for nm, t in (zip(model.mesh_names, model.mesh_tables) if model is not None else ()):
        tsha = ((rec.get("meshes") or {}).get(nm) or {}).get("tables_bin_sha256")
        if tsha is not None and hashlib.sha256(t.to_bytes()[1]).hexdigest() != tsha:
            raise FmuMismatchError(f"{fmu.path} carries other tables of mesh {nm!r} than {scene_label} gives")


def validate_planetary_fmu(fmu_path, model: PlanetaryModel, settings, variables, *,
                           tolerance: float = DEFAULT_TOLERANCE, scene_text: Optional[str] = None,
                           stop_time_s: Optional[float] = None, comm_step_s: Optional[float] = None) -> dict:
    """The report of ``gearfmu validate`` for a planetary FMU, with the keys of
    :func:`gearfmu.fmu.gearbox_compare.validate_gearbox_fmu`'s and ``start`` ("FMU initial state" or
    "native quasi-static state", module docstring) and per output its ``scale`` (its range; without the
    FMU's states the largest range of its unit's outputs)."""
    from fmpy.validation import validate_fmu  # fmpy: heavy, only to validate an FMU

    if not (tolerance >= 0 and tolerance < float("inf")):
        raise FmuMismatchError(f"tolerance: must be finite and >= 0, got {tolerance!r}")
    check_planetary_fmu_matches(open_fmu(fmu_path), model, variables, scene_text=scene_text)
    stop = settings.stop_time_s if stop_time_s is None else stop_time_s
    H = settings.output_interval_s if comm_step_s is None else comm_step_s
    with ticking(f"checking {Path(fmu_path).name} with fmpy's validation"):
        problems = [str(p) for p in validate_fmu(str(fmu_path))]
    outs = [v for v in variables if v.causality == "output"]
    names = {v.name for v in variables}
    states = state_names(model) if all(n in names for n in state_names(model)) else []
    with ticking(f"{Path(fmu_path).name} over {stop:g} s"):
        fmu = step_fmu(fmu_path, [v.name for v in outs] + states, stop_time_s=stop, comm_step_s=H)
    y0 = np.array([fmu.columns[n][0] for n in states]) if states else None
    s = dataclasses.replace(settings, stop_time_s=stop, output_interval_s=H)

    def run(stop_s):
        return simulate_planetary(model, dataclasses.replace(s, stop_time_s=stop_s),
                                  motor_torque_Nm=s.motor_torque_start_Nm, load_torque_Nm=s.load_torque_start_Nm,
                                  initial_state=y0)

    run(min(stop, 10 * H))   # compile (or load), not timed
    with ticking(f"native planetary solver over {stop:g} s"):
        t0 = time.perf_counter()
        nat = run(stop) if y0 is not None else native_run(model, s)
        native_wall = time.perf_counter() - t0
    per = diff_report({v.name: np.asarray(nat[v.name]) for v in outs}, {v.name: fmu.columns[v.name] for v in outs})
    units = {v.name: v.unit or "1" for v in outs}
    if y0 is None:   # every output against the largest range of its unit
        big = {}
        for v in outs:
            big[units[v.name]] = max(big.get(units[v.name], 0.0), per[v.name]["range"])
        for v in outs:
            d = per[v.name]
            d["scale"] = max(d["range"], big[units[v.name]])
            d["rel_max_diff"] = d["max_abs_diff"] / d["scale"] if d["scale"] > 0 else d["rel_max_diff"]
    return {
        "fmu": str(fmu_path), "fmpy_problems": problems, "stop_time_s": stop, "comm_step_s": H,
        "max_step_s": settings.max_step_s, "samples": int(len(fmu.time_s)), "outputs": per, "units": units,
        "start": "FMU initial state" if y0 is not None else "native quasi-static state",
        "max_abs_diff": {k: v["max_abs_diff"] for k, v in per.items()},
        "rms_diff": {k: v["rms_diff"] for k, v in per.items()},
        "max_rel_diff": max((v["rel_max_diff"] for v in per.values()), default=0.0),
        "tolerance": tolerance,
        "failed": {k: v["rel_max_diff"] for k, v in per.items() if not v["rel_max_diff"] <= tolerance},
        "native_wall_s": native_wall, "fmu_wall_s": fmu.wall_s,
        "bitwise": all(np.array_equal(np.asarray(nat[v.name]), fmu.columns[v.name], equal_nan=True) for v in outs),
    }
