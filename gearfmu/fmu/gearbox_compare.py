"""A gearbox FMU against the native gearbox solver (``gearfmu validate DRIVETRAIN.toml``).

The FMU is stepped through fmpy's FMI 2 or FMI 3 API at exactly the communication step H from
t_k = k*H (the native solver's steps; fmpy.simulate_fmu computes H as a difference of times, which
differs by ulps and, where impacts amplify it, by more than round-off), with its start values;
the native solver (:func:`gearfmu.fmu.gearbox_validation.native_run`) with the same inputs, step
bound and integrator.  Both take the same RK4 substeps, so they agree to round-off (measured: bit
for bit).
"""
from __future__ import annotations

import hashlib
import time
from pathlib import Path
from typing import Dict, Optional, Sequence

import numpy as np

from ..common.progress import ticking
from ..gearbox.model import GearboxModel
from .compare import DEFAULT_TOLERANCE, FmuFile, FmuMismatchError, FmuRun, FmuRunError, diff_report, open_fmu
from .gearbox_validation import native_outputs_by_vr, native_run

__all__ = ["step_fmu", "check_gearbox_fmu_matches", "validate_gearbox_fmu"]


def step_fmu(fmu_path, names: Sequence[str], *, stop_time_s: float, comm_step_s: float,
             start_values: Optional[Dict[str, float]] = None) -> FmuRun:
    """Run an FMU (FMI 2 or 3 Co-Simulation) with fmpy's low-level API at exactly ``comm_step_s`` and
    read the Real outputs ``names`` (FMI 2 names; an FMI 3 array ``x`` of n elements is read as
    ``x[1]`` .. ``x[n]``) at every communication point; FmuRunError naming the file when a call fails."""
    import fmpy  # fmpy: heavy, only to run an FMU
    from fmpy.fmi2 import FMU2Slave  # fmpy: heavy, only to run an FMU
    from fmpy.fmi3 import FMU3Slave  # fmpy: heavy, only to run an FMU

    md = fmpy.read_model_description(str(fmu_path))
    fmi3 = md.fmiVersion.startswith("3")
    by_name = {v.name: v for v in md.modelVariables}
    refs = []   # (value reference, element index or None) per name
    for n in names:
        if n in by_name:
            refs.append((by_name[n].valueReference, None))
        elif fmi3 and n.endswith("]") and n.rsplit("[", 1)[0] in by_name:
            refs.append((by_name[n.rsplit("[", 1)[0]].valueReference, int(n.rsplit("[", 1)[1][:-1]) - 1))
        else:
            raise FmuMismatchError(f"{fmu_path}: no output {n!r}")
    n_steps = max(1, int(round(stop_time_s / comm_step_s)))
    unzip = fmpy.extract(str(fmu_path))
    cls = FMU3Slave if fmi3 else FMU2Slave
    slave = cls(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                instanceName=Path(fmu_path).stem)
    vrs = sorted({r for r, _ in refs})
    sizes = {v.valueReference: (int(v.shape[0]) if getattr(v, "shape", None) else 1) for v in md.modelVariables}

    def read():
        if fmi3:
            flat = slave.getFloat64(vrs, nValues=sum(sizes[r] for r in vrs))
        else:
            flat = slave.getReal(vrs)
        at, o = {}, 0
        for r in vrs:
            at[r] = flat[o:o + sizes[r]] if fmi3 else [flat[o]]
            o += sizes[r] if fmi3 else 1
        return [at[r][0 if i is None else i] for r, i in refs]

    rows = []
    try:
        slave.instantiate()
        if fmi3:
            slave.enterInitializationMode(startTime=0.0)
        else:
            slave.setupExperiment(startTime=0.0)
            slave.enterInitializationMode()
        for name, value in (start_values or {}).items():
            v = by_name[name]
            if v.type in ("Real", "Float64"):
                (slave.setFloat64 if fmi3 else slave.setReal)([v.valueReference], [float(value)])
            else:
                (slave.setInt32 if fmi3 else slave.setInteger)([v.valueReference], [int(value)])
        slave.exitInitializationMode()
        rows.append(read())
        t0 = time.perf_counter()
        for k in range(n_steps):
            slave.doStep(k * comm_step_s, comm_step_s)
            rows.append(read())
        wall = time.perf_counter() - t0
        slave.terminate()
    except Exception as exc:  # noqa: BLE001 - fmpy raises FMICallException and plain exceptions
        raise FmuRunError(f"{fmu_path}: the FMU failed ({str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__})") from exc
    finally:
        try:
            slave.freeInstance()
        except Exception:  # noqa: BLE001 - already failed above
            pass
    a = np.array(rows, dtype=float)
    return FmuRun(np.arange(n_steps + 1) * comm_step_s, {n: a[:, i] for i, n in enumerate(names)}, wall)


def check_gearbox_fmu_matches(fmu: FmuFile, model: Optional[GearboxModel] = None, variables=None, *,
                              scene_text: Optional[str] = None, scene_label: str = "SCENE") -> None:
    """Refuse (FmuMismatchError, naming both) an FMU that is not a gearbox FMU, was built from another
    drivetrain scene than ``scene_text``, carries other tables of a stage than ``model``'s, or has other
    variables than ``variables``; checks only what is given (the kind and the scene need no tables).
    Nothing is simulated."""
    rec = fmu.record or {}
    if rec.get("model") != "gearbox" and not any(v.name.endswith(".dte") for v in fmu.model_description.modelVariables):
        raise FmuMismatchError(f"{fmu.path} is a gear-pair FMU, not a gearbox FMU; {scene_label} is a drivetrain "
                               "scene (build its FMU with gearfmu build DRIVETRAIN.toml)")
    want_sha = rec.get("scene_sha256")
    if scene_text is not None and want_sha is not None:
        have = hashlib.sha256(scene_text.encode()).hexdigest()
        if have != want_sha:
            raise FmuMismatchError(f"{fmu.path} was built from another drivetrain scene (sha256 {want_sha[:12]}) than "
                                   f"{scene_label} (sha256 {have[:12]}); give the scene the FMU was built from or "
                                   "build the FMU from this scene")
    for m in (model.meshes if model is not None else ()):
        tsha = ((rec.get("stages") or {}).get(m.name) or {}).get("tables_bin_sha256")
        if tsha is not None:
            have = hashlib.sha256(m.tables.to_bytes()[1]).hexdigest()
            if have != tsha:
                raise FmuMismatchError(f"{fmu.path} carries other tables of stage {m.name!r} (sha256 {tsha[:12]}) than "
                                       f"{scene_label} gives (sha256 {have[:12]})")
    if variables is None:
        return
    want = {v.name for v in variables}
    have = set(fmu.variable_names)
    if want != have:
        raise FmuMismatchError(f"{fmu.path} has other variables than {scene_label}'s gearbox: only in the FMU "
                               f"{sorted(have - want)[:6]}, missing from it {sorted(want - have)[:6]}")


def validate_gearbox_fmu(fmu_path, model: GearboxModel, settings, variables, *, tolerance: float = DEFAULT_TOLERANCE,
                         scene_text: Optional[str] = None, stop_time_s: Optional[float] = None,
                         comm_step_s: Optional[float] = None) -> dict:
    """The report of ``gearfmu validate`` for a gearbox FMU (the keys of the pair's,
    :func:`gearfmu.fmu.compare.validate_fmu_against_native`, and ``units``): fmpy validation problems,
    per output the largest and RMS difference FMU - native and the native signal's range, the outputs
    beyond ``tolerance`` of their range in ``failed``, and the wall times.  ``settings``: the FMU's
    start values (:class:`gearfmu.common.settings.GearboxRunSettings`, resolved)."""
    from fmpy.validation import validate_fmu  # fmpy: heavy, only to validate an FMU

    if not (tolerance >= 0 and tolerance < float("inf")):
        raise FmuMismatchError(f"tolerance: must be finite and >= 0, got {tolerance!r}")
    check_gearbox_fmu_matches(open_fmu(fmu_path), model, variables, scene_text=scene_text)
    stop = settings.stop_time_s if stop_time_s is None else stop_time_s
    H = settings.output_interval_s if comm_step_s is None else comm_step_s
    with ticking(f"checking {Path(fmu_path).name} with fmpy's validation"):
        problems = [str(p) for p in validate_fmu(str(fmu_path))]
    by_vr = native_outputs_by_vr(model, variables)
    outs = [v for v in variables if v.causality == "output"]
    with ticking(f"{Path(fmu_path).name} over {stop:g} s"):
        fmu = step_fmu(fmu_path, [v.name for v in outs], stop_time_s=stop, comm_step_s=H)
    native_run(model, settings, stop_time_s=min(stop, 10 * H), comm_step_s=H)   # compile (or load), not timed
    with ticking(f"native gearbox solver over {stop:g} s"):
        t0 = time.perf_counter()
        nat = native_run(model, settings, stop_time_s=stop, comm_step_s=H)
        native_wall = time.perf_counter() - t0
    per = diff_report({v.name: np.asarray(nat[by_vr[v.value_reference]]) for v in outs}, fmu.columns)
    units = {v.name: v.unit or "1" for v in outs}
    return {
        "fmu": str(fmu_path), "fmpy_problems": problems, "stop_time_s": stop, "comm_step_s": H,
        "max_step_s": settings.max_step_s, "samples": int(len(fmu.time_s)), "outputs": per, "units": units,
        "max_abs_diff": {k: v["max_abs_diff"] for k, v in per.items()},
        "rms_diff": {k: v["rms_diff"] for k, v in per.items()},
        "max_rel_diff": max((v["rel_max_diff"] for v in per.values()), default=0.0),
        "tolerance": tolerance,
        "failed": {k: v["rel_max_diff"] for k, v in per.items() if not v["rel_max_diff"] <= tolerance},
        "native_wall_s": native_wall, "fmu_wall_s": fmu.wall_s,
        "bitwise": all(np.array_equal(np.asarray(nat[by_vr[v.value_reference]]), fmu.columns[v.name]) for v in outs),
    }
