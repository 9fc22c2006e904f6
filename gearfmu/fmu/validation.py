"""The validation record every gearfmu FMU carries (both runtimes): ``resources/validation/``.

Shared by the pythonfmu builder (:mod:`gearfmu.fmu.pythonfmu_build`) and the standalone
builder (:mod:`gearfmu.fmu.standalone_build`): the native solver's reference result over the
FMU's DefaultExperiment, table checksums, versions and the agreement criterion.
"""
from __future__ import annotations

import csv
import datetime
import hashlib
import dataclasses
import importlib.metadata
import io
import json
import platform
import sys
from typing import Dict, Optional

from .. import __version__
from ..common.cache import cache_dir, load_entry, package_sources_sha256, sources_sha256, store_entry  # noqa: F401
from ..common.progress import ticking
from ..common.settings import RunSettings
from ..dynamics.native import simulate
from ..tables.mesh_tables import MeshTables
from .build_steps import record_parameters
from .compare import native_columns, output_names

__all__ = ["validation_record", "VALIDATION_DIR", "RECORD_PACKAGES", "REFERENCE_CACHE"]

VALIDATION_DIR = "resources/validation"
#: packages whose versions the validation record names
RECORD_PACKAGES = ("numpy", "scipy", "numba", "fmpy", "pythonfmu", "libcosimpy")
#: folder of gearfmu's file cache (:mod:`gearfmu.common.cache`) holding the native reference results
REFERENCE_CACHE = "validation"
#: packages whose versions are part of a cached reference result's key (the numbers depend on them)
_SOLVER_PACKAGES = ("numpy", "numba")


def _sources_sha256() -> str:
    return sources_sha256()


def _versions() -> Dict[str, Optional[str]]:
    out = {"gearfmu": __version__, "python": sys.version.split()[0]}
    for pkg in RECORD_PACKAGES:
        try:
            out[pkg] = importlib.metadata.version(pkg)
        except importlib.metadata.PackageNotFoundError:
            out[pkg] = None
    return out


def validation_record(tables: MeshTables, settings: RunSettings, *, runtime: str, model_identifier: str,
                      temperature_start_C: Optional[float] = None, scene_text: Optional[str] = None,
                      compiler: Optional[str] = None, envelope: Optional[dict] = None) -> Dict[str, bytes]:
    """The validation record every gearfmu FMU carries (both runtimes), as
    ``{path inside the FMU: bytes}`` under ``resources/validation/``.

    Files: ``record.json`` (runtime, package and dependency versions, platform,
    compiler, parameters, table checksums -- tables.bin and every array --,
    the experiment, the reference file's SHA-256 and the agreement criterion),
    ``reference_result.csv`` (the native numba solver, :func:`gearfmu.dynamics.native.simulate`,
    over the FMU's DefaultExperiment with the FMU's start values: ``settings``, the build's
    resolved :class:`gearfmu.common.settings.RunSettings` -- communication step = stepSize, same
    max_step --, at the temperature input's start value ``temperature_start_C`` (degC) when the
    tables have a temperature axis, so the FMU reproduces it to round-off when a master steps it at
    stepSize) and ``scene.toml`` when a scene was given; ``envelope``
    (:func:`gearfmu.fmu.envelope.fmu_envelope_record`, the FMU's ``resources/envelope.json``)
    goes into record.json as ``envelope``.  ``parameters`` in record.json:
    :func:`gearfmu.fmu.build_steps.record_parameters`.  The pattern follows the Modelica
    Reference-FMUs, which carry their reference result CSV inside the FMU.
    """
    p = record_parameters(settings, temperature_start_C)
    stop_time_s, output_interval_s = settings.stop_time_s, settings.output_interval_s
    sim_kw = {} if temperature_start_C is None else {"bulk_temperature_C": float(temperature_start_C)}
    meta_bytes, bin_bytes = tables.to_bytes()
    meta = json.loads(meta_bytes.decode("utf-8"))
    ref, ref_meta = _reference(tables, settings, sim_kw, meta)
    record = {
        "format": "gearfmu-validation-record", "version": 1,
        "runtime": runtime, "model_identifier": model_identifier,
        "created_utc": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "versions": _versions(), "platform": platform.platform(), "machine": platform.machine(),
        "compiler": compiler,
        "parameters": p,
        "tables": {"tables_bin_sha256": hashlib.sha256(bin_bytes).hexdigest(),
                   "tables_json_sha256": hashlib.sha256(meta_bytes).hexdigest(),
                   "arrays_sha256": {k: v["sha256"] for k, v in meta["arrays"].items()},
                   "slots": tables.slots, "n_phi": tables.n_phi, "n_torque": tables.n_torque},
        "scene_sha256": None if scene_text is None else hashlib.sha256(scene_text.encode()).hexdigest(),
        "envelope": envelope,
        "reference": {
            "file": "reference_result.csv", "sha256": hashlib.sha256(ref).hexdigest(),
            "solver": "gearfmu.dynamics.native.simulate (numba, docs/model.md RK4)",
            "start_time_s": 0.0, "stop_time_s": stop_time_s, "output_interval_s": output_interval_s,
            "substeps_per_interval": ref_meta["substeps"], "rows": ref_meta["rows"],
            "criterion": "every output within 1e-9 of its range in this file when a master steps the FMU "
                         "with communication step = output_interval_s and the start values above",
            "native_wall_s": ref_meta["native_wall_s"],
        },
    }
    out = {f"{VALIDATION_DIR}/record.json": json.dumps(record, indent=1, default=str).encode("utf-8"),
           f"{VALIDATION_DIR}/reference_result.csv": ref}
    if scene_text is not None:
        out[f"{VALIDATION_DIR}/scene.toml"] = scene_text.encode("utf-8")
    return out


def _reference(tables: MeshTables, settings: RunSettings, sim_kw: dict, tables_meta: dict):
    """(reference_result.csv bytes, {substeps, rows, native_wall_s}) of the native solver on
    ``tables`` with ``settings`` and the keyword arguments ``sim_kw``.  Kept in gearfmu's file cache
    (:mod:`gearfmu.common.cache`, folder :data:`REFERENCE_CACHE`) under the key: the tables' content
    checksum (every array's SHA-256, shapes, scalars and axes: ``tables.json`` without its provenance,
    which the solver does not read), every setting and argument of the run, the gearfmu, Python and
    solver package versions, the checksum of gearfmu's own source files (:func:`package_sources_sha256`)
    and the machine type.  A later build with the same key reads the file instead of running the solver
    (the same bytes: the solver is deterministic); any change in the key runs it again.
    ``native_wall_s`` is the wall time of the run that computed the file."""
    content = {k: v for k, v in tables_meta.items() if k != "provenance"}
    versions = _versions()
    run = dict(dataclasses.asdict(settings), **sim_kw)
    key = {"what": "gearfmu native reference result",
           "tables_content_sha256": hashlib.sha256(json.dumps(content, sort_keys=True).encode()).hexdigest(),
           "simulate": {k: repr(v) for k, v in sorted(run.items())},
           "versions": {k: versions[k] for k in ("gearfmu", "python", *_SOLVER_PACKAGES)},
           "gearfmu_sources_sha256": _sources_sha256(),
           "machine": platform.machine()}
    folder = cache_dir(REFERENCE_CACHE)
    hit = load_entry(folder, key, ".csv", fields={"substeps": int, "rows": int, "native_wall_s": float})
    if hit is not None:
        return hit[1], hit[0]
    with ticking(f"validation record: native reference run over {settings.stop_time_s:g} s "
                 "(kept for later builds)"):
        res = simulate(tables, settings, **sim_kw)
    cols = native_columns(res, tables.slots)
    names = output_names(tables.slots)
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["time", *names])
    for i in range(len(res.time_s)):
        w.writerow([repr(float(res.time_s[i]))] + [repr(float(cols[n][i])) for n in names])
    ref = buf.getvalue().encode("utf-8")
    meta = {"substeps": int(res.substeps), "rows": int(len(res.time_s)), "native_wall_s": float(res.wall_s)}
    store_entry(folder, key, meta, ref, ".csv")
    return ref, meta
