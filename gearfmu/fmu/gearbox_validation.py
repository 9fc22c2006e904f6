"""The validation record of a gearbox FMU (``resources/validation/``) and the native run it holds.

As every gearfmu FMU (docs/standalone.md "Validation record"): ``record.json`` (runtime, versions,
parameters, every stage's table checksums, the experiment, the reference file's SHA-256 and the
agreement criterion), ``reference_result.csv`` (the native gearbox solver,
:func:`gearfmu.gearbox.native.simulate`, over the FMU's DefaultExperiment with its start values; columns
``time`` and every output in value-reference order, under the FMU's names) and ``scene.toml``.  The
reference result is kept in gearfmu's file cache (folder ``validation``) under a key of everything
it depends on, as the pair's is (:mod:`gearfmu.fmu.validation`).
"""
from __future__ import annotations

import csv
import datetime
import hashlib
import io
import json
import platform
from typing import Dict, Optional, Sequence

from ..common.cache import cache_dir, load_entry, store_entry
from ..common.progress import ticking
from ..gearbox.model import GearboxModel
from ..gearbox.native import GearboxResult, simulate as simulate_gearbox
from .gearbox_interface import gearbox_variables, load_gearbox_spec
from .validation import REFERENCE_CACHE, VALIDATION_DIR, _SOLVER_PACKAGES, _sources_sha256, _versions

__all__ = ["native_run", "native_outputs_by_vr", "gearbox_validation_record", "reference_csv", "record_files"]


def native_run(model: GearboxModel, settings, *, stop_time_s: Optional[float] = None,
               comm_step_s: Optional[float] = None) -> GearboxResult:
    """The native gearbox solver with an FMU's start values (``settings``: the FMU's
    :class:`gearfmu.common.settings.GearboxRunSettings`, resolved by
    :func:`gearfmu.fmu.gearbox_build.gearbox_settings`): the same inputs held over each
    communication step, the same internal step bound and integrator, the same start."""
    return simulate_gearbox(model, settings, stop_time_s=stop_time_s, comm_step_s=comm_step_s,
                            motor_torque_Nm=settings.motor_torque_start_Nm,
                            load_torque_Nm=settings.load_torque_start_Nm)


def native_outputs_by_vr(model: GearboxModel, variables: Sequence) -> Dict[int, str]:
    """Value reference of every output of the FMU -> its native column (the FMU's names before an FMI 3
    build made its per-slot outputs scalars, which are the native solver's column names)."""
    plain = gearbox_variables(load_gearbox_spec(), model)
    outs = {v.value_reference for v in variables if v.causality == "output"}
    return {v.value_reference: v.name for v in plain if v.value_reference in outs}


def reference_csv(result: GearboxResult, model: GearboxModel, variables: Sequence) -> bytes:
    """``time`` and every output (value-reference order, the FMU's names) of a native run, one row per
    communication point, every number as Python writes it (17 significant digits, exact)."""
    by_vr = native_outputs_by_vr(model, variables)
    names = {v.value_reference: v.name for v in variables}
    order = sorted(by_vr)
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["time", *(names[r] for r in order)])
    cols = [result[by_vr[r]] for r in order]
    for i in range(len(result.time_s)):
        w.writerow([repr(float(result.time_s[i]))] + [repr(float(c[i])) for c in cols])
    return buf.getvalue().encode("utf-8")


def _reference(model: GearboxModel, variables, settings):
    """(reference_result.csv bytes, {substeps, rows, native_wall_s}), from the cache when the same key
    was computed before (:mod:`gearfmu.fmu.validation` explains the key)."""
    versions = _versions()
    stages = []
    for m in model.meshes:
        meta = json.loads(m.tables.to_bytes()[0].decode("utf-8"))
        content = {k: v for k, v in meta.items() if k != "provenance"}
        stages.append([m.name, hashlib.sha256(json.dumps(content, sort_keys=True).encode()).hexdigest(),
                       m.damping_ratio, m.damping_model])
    key = {"what": "gearfmu native gearbox reference result",
           "stages": stages, "inertia": [float(x).hex() for x in model.inertia_kgm2],
           "g": [float(x).hex() for x in model.g], "parts": list(model.parts), "load_body": int(model.load_body),
           "shafts": [[s.name, int(a), int(b), float(k).hex(), float(c).hex()] for s, (a, b), k, c in
                      zip(model.shafts, model.shaft_bodies, model.shaft_k_Nm_per_rad, model.shaft_c_Nms_per_rad)],
           "ends": [bool(model.motor_torque_input), bool(model.load_torque_input)],
           "settings": {k: repr(v) for k, v in sorted(vars(settings).items())},
           "columns": [v.name for v in variables if v.causality == "output"],
           "versions": {k: versions[k] for k in ("gearfmu", "python", *_SOLVER_PACKAGES)},
           "gearfmu_sources_sha256": _sources_sha256(), "machine": platform.machine()}
    folder = cache_dir(REFERENCE_CACHE)
    hit = load_entry(folder, key, ".csv", fields={"substeps": int, "rows": int, "native_wall_s": float})
    if hit is not None:
        return hit[1], hit[0]
    with ticking(f"validation record: native gearbox reference run over {settings.stop_time_s:g} s "
                 "(kept for later builds)"):
        res = native_run(model, settings)
    ref = reference_csv(res, model, variables)
    meta = {"substeps": int(res.substeps), "rows": int(len(res.time_s)), "native_wall_s": float(res.wall_s)}
    store_entry(folder, key, meta, ref, ".csv")
    return ref, meta


def gearbox_validation_record(model: GearboxModel, variables, settings, *, runtime: str, model_identifier: str,
                              parameters: dict, scene_text: Optional[str] = None,
                              compiler: Optional[str] = None) -> Dict[str, bytes]:
    """The validation record of a gearbox FMU as ``{path inside the FMU: bytes}`` (module docstring)."""
    ref, ref_meta = _reference(model, variables, settings)
    return record_files("gearbox", {m.name: m.tables for m in model.meshes}, ref, ref_meta, settings,
                        solver="gearfmu.gearbox.native.simulate (numba gearbox solver, docs/gearbox.md)",
                        runtime=runtime, model_identifier=model_identifier, parameters=parameters,
                        scene_text=scene_text, compiler=compiler)


def record_files(kind: str, tables_by_name, ref: bytes, ref_meta: dict, settings, *, solver: str, runtime: str,
                 model_identifier: str, parameters: dict, scene_text: Optional[str], compiler: Optional[str],
                 criterion: Optional[str] = None) -> Dict[str, bytes]:
    """The files of a multi-mesh FMU's validation record (``kind`` "gearbox" or "planetary"): record.json
    with every mesh's table checksums (``tables_by_name``: name -> MeshTables), the reference result
    ``ref`` of ``solver`` and scene.toml."""
    tables = {}
    for name, t in tables_by_name.items():
        meta_bytes, bin_bytes = t.to_bytes()
        meta = json.loads(meta_bytes.decode("utf-8"))
        tables[name] = {"tables_bin_sha256": hashlib.sha256(bin_bytes).hexdigest(),
                        "tables_json_sha256": hashlib.sha256(meta_bytes).hexdigest(),
                        "arrays_sha256": {k: v["sha256"] for k, v in meta["arrays"].items()},
                        "slots": t.slots, "n_phi": t.n_phi, "n_torque": t.n_torque}
    record = {
        "format": "gearfmu-validation-record", "version": 1, "model": kind,
        "runtime": runtime, "model_identifier": model_identifier,
        "created_utc": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "versions": _versions(), "platform": platform.platform(), "machine": platform.machine(),
        "compiler": compiler, "parameters": parameters, "stages" if kind == "gearbox" else "meshes": tables,
        "scene_sha256": None if scene_text is None else hashlib.sha256(scene_text.encode()).hexdigest(),
        "reference": {
            "file": "reference_result.csv", "sha256": hashlib.sha256(ref).hexdigest(),
            "solver": solver,
            "start_time_s": 0.0, "stop_time_s": settings.stop_time_s,
            "output_interval_s": settings.output_interval_s,
            "substeps_per_interval": ref_meta["substeps"], "rows": ref_meta["rows"],
            "criterion": criterion or ("every output within 1e-9 of its range in this file when a master steps the FMU "
                                       "with communication step = output_interval_s and the start values above "
                                       "(measured: bit for bit)"),
            "native_wall_s": ref_meta["native_wall_s"],
        },
    }
    out = {f"{VALIDATION_DIR}/record.json": json.dumps(record, indent=1, default=str).encode("utf-8"),
           f"{VALIDATION_DIR}/reference_result.csv": ref}
    if scene_text is not None:
        out[f"{VALIDATION_DIR}/scene.toml"] = scene_text.encode("utf-8")
    return out
