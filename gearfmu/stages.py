"""The stages of the main job on a scene: scene -> tables -> FMU, and the native run beside it.

Only wiring; each stage lives in its own package (scene, tables, fmu, dynamics).  The
planner (:mod:`gearfmu.plan`) builds its planned scenes with :func:`build_fmu_from_scene`;
:func:`gearfmu.pipeline.build` runs the planner first when a scene asks for it.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

import numpy as np

from . import __version__
from .common.progress import notice
from .common.vocabulary import DEFAULT_FMI3_OUTPUTS, FMI3_OUTPUTS, RUNTIMES
from .scene.physics import environment_from_scene
from .dynamics.native import choose_max_step_s, simulate
from .fmu.pythonfmu_build import build_fmu
from .fmu.standalone_build import build_standalone_fmu
from .scene.envelope import fmu_envelope_record
from .scene.reader import default_scene_path, load_scene
from .scene.physics import check_build_cost, estimate_build
from .assembly import precompute, table_cache


def load(scene_path: Optional[str] = None):
    """Load a scene file (None: the default scene)."""
    return load_scene(scene_path if scene_path is not None else default_scene_path())


def gear_torque_for(tables, pinion_torque_Nm: float) -> float:
    """Load torque on the gear that balances a pinion torque in steady state,
    T2 = T1 * Rb2 / Rb1 (seed 003: F_m = T1/Rb1 = T2/Rb2)."""
    return pinion_torque_Nm * tables.base_radius_gear_m / tables.base_radius_pinion_m


def compute_tables(scene, *, progress: bool = False, allow_large: bool = False, cache: Optional[bool] = None):
    """Precompute the tooth-pair tables of a scene (timed).  Refuses with a
    :class:`gearfmu.tables.estimate.BuildTooLargeError` naming the scene keys when the estimated
    tables, FMU or build time exceed the limits of :mod:`gearfmu.tables.estimate`, unless
    ``allow_large``.  The tables are kept in gearfmu's table cache and read back when the same
    physics is asked again (:mod:`gearfmu.tables.table_cache`); ``cache`` False computes without
    it, None follows ``--no-cache`` / ``GEARFMU_NO_TABLE_CACHE``."""
    check_build_cost(scene, allow_large=allow_large)
    torque_axis = scene.operating.torque_axis_Nm() if hasattr(scene.operating, "torque_axis_Nm") else None
    prov = {
        "scene_name": scene.name,
        "scene_toml": scene.text,
        "gearfmu_version": __version__,
        "numpy_version": np.__version__,
        "created_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "contact_model": scene.mesh.contact_model,
    }
    args = dict(pair=scene.pair, opts=scene.mesh, points_per_mesh=scene.tables.points_per_mesh,
                torque_axis_Nm=torque_axis, nominal_torque_Nm=scene.operating.torque_Nm,
                slots=scene.tables.slots, **_contact_kw(scene, progress), thermal=scene.thermal)
    # looked up at call time, so a substitute set on the module is used
    return table_cache.cached_tables(precompute.precompute_tables, args, prov, progress=progress, use_cache=cache)


def _contact_kw(scene, progress: bool) -> dict:
    """``contact_env`` for the EHL contact models (gearfmu/contact/models.py); {} for Hertz."""
    if scene.mesh.contact_model == "hertz":
        return {}
    return {"contact_env": environment_from_scene(scene, progress=progress)}


def max_step_for(scene, tables) -> float:
    """The internal step bound: the scene's ``solver.max_step_s`` or the automatic choice."""
    if scene.solver.max_step_s is not None:
        return float(scene.solver.max_step_s)
    vmax = scene.operating.speed_rad_s
    rng = scene.operating.speed_range_rad_s
    if rng:
        vmax = max(abs(v) for v in rng)
    if tables.has_temperature_axis:  # the bound of the stiffest temperature slice
        return min(choose_max_step_s(tables.at_temperature(float(t)), abs(vmax)) for t in tables.temperature_C)
    return choose_max_step_s(tables, abs(vmax))


@dataclass
class BuildResult:
    fmu_path: Path
    tables: object
    tables_wall_s: float
    build_wall_s: float
    max_step_s: float
    plan: object = None  # gearfmu.plan.Plan when the scene's [accuracy] made build follow a plan
    #: gearfmu.scene.envelope.VerifiedEnvelope as a dict: the plan's verified envelope, or the as-written
    #: estimate (estimate_accuracy=True, no [accuracy]); None otherwise (docs/plan.md "Verified envelope")
    verified_envelope: Optional[dict] = None
    estimate: object = None  # gearfmu.tables.estimate.BuildEstimate of the scene that was built
    #: s, the time the tables' computation took: ``tables_wall_s`` when they were computed here, the
    #: original computation's when they were read from the table cache (gearfmu.tables.table_cache)
    tables_compute_s: Optional[float] = None


def fmu_builder(runtime: str):
    """The FMU builder of a runtime: "standalone" (FMI layer in C, docs/standalone.md) or
    "pythonfmu"; both take the same arguments."""
    if runtime == "standalone":
        return build_standalone_fmu
    if runtime != "pythonfmu":
        raise ValueError(f"runtime: {runtime!r} not one of {RUNTIMES}")
    return build_fmu


def platform_kw(runtime: str, platforms, fmi_version: int = 2,
                fmi3_outputs: str = DEFAULT_FMI3_OUTPUTS) -> dict:
    """``platforms`` for the builder: binaries of a standalone FMU (gearfmu.fmu.crossbuild keys;
    None: all available); ``fmi_version`` 3: the standalone FMI 3.0 FMU, with ``fmi3_outputs``
    "array" or "scalar" (:data:`gearfmu.common.vocabulary.FMI3_OUTPUTS`)."""
    if fmi_version not in (2, 3) or (fmi_version == 3 and runtime != "standalone"):
        raise ValueError(f"--fmi-version: {fmi_version} needs 2, or 3 with the standalone runtime")
    if fmi3_outputs not in FMI3_OUTPUTS:
        raise ValueError(f"--fmi3-outputs: {fmi3_outputs!r} not one of {', '.join(FMI3_OUTPUTS)}")
    if fmi3_outputs != DEFAULT_FMI3_OUTPUTS and fmi_version != 3:
        raise ValueError(f"--fmi3-outputs: {fmi3_outputs} needs --fmi-version 3 (an FMI 2 FMU has scalars only)")
    version = {"fmi_version": 3, "fmi3_outputs": fmi3_outputs} if fmi_version == 3 else {}
    if platforms is None:
        return version
    if runtime != "standalone":
        raise ValueError("--platforms: only the standalone runtime builds binaries for other platforms "
                         "(use --runtime standalone)")
    return {"platforms": tuple(platforms), **version}


def build_fmu_from_scene(scene, out_path, *, progress: bool = False, runtime: Optional[str] = None,
                         tables=None, plan=None, verified_envelope: Optional[dict] = None, platforms=None,
                         allow_large: bool = False, fmi_version: int = 2,
                         fmi3_outputs: str = DEFAULT_FMI3_OUTPUTS) -> BuildResult:
    """Scene -> tables -> FMU at ``out_path``, the scene as it is (no planning: see
    :func:`gearfmu.pipeline.build`).  ``runtime``: "standalone" or "pythonfmu"; None: the
    scene's ``fmu.runtime``.  ``tables``: MeshTables to use instead of the scene's physics
    (e.g. imported from CSV, gearfmu.tables.table_import); the scene then only gives the FMU
    and operating settings.  ``plan``, ``verified_envelope``: kept in the result.
    ``platforms``: binaries of a standalone FMU.  ``allow_large``: build even when the
    estimate (gearfmu.tables.estimate) exceeds the limits."""
    runtime = runtime or scene.fmu.runtime
    builder = fmu_builder(runtime)
    extra = platform_kw(runtime, platforms, fmi_version, fmi3_outputs)
    est = estimate_build(scene) if tables is None else None
    t0 = time.perf_counter()
    if tables is None:
        tables = compute_tables(scene, progress=progress, allow_large=allow_large)
    t1 = time.perf_counter()
    h_max = max_step_for(scene, tables)
    t1_Nm = scene.operating.torque_Nm
    notice(f"building the FMU {out_path} ({runtime} runtime, FMI {fmi_version})", enabled=progress or None)
    path = builder(
        tables, out_path,
        model_name=scene.fmu.model_name,
        damping_ratio=scene.fmu.damping_ratio,
        pinion_speed_start_rad_s=scene.operating.speed_rad_s,
        pinion_torque_start_Nm=t1_Nm,
        gear_torque_start_Nm=gear_torque_for(tables, t1_Nm),
        max_step_s=h_max,
        damping_model=scene.solver.damping_model,
        stop_time_s=scene.fmu.stop_time_s,
        output_interval_s=scene.fmu.output_interval_s,
        scene_text=scene.text,
        envelope=fmu_envelope_record(tables, verified_envelope,
                                     speed_range_rad_s=scene.operating.speed_range_rad_s),
        integrator=scene.solver.integrator, **extra,
    )
    t2 = time.perf_counter()
    computed = t1 - t0
    if isinstance(tables.provenance, dict) and "table_cache" in tables.provenance:
        computed = float((tables.provenance.get("precompute") or {}).get("wall_s", computed))
    return BuildResult(Path(path), tables, t1 - t0, t2 - t1, h_max, plan, verified_envelope, est, computed)


def simulate_native(scene, tables, *, stop_time_s=None, comm_step_s=None, max_step_s=None,
                    damping_ratio=None, pinion_torque_Nm=None, gear_torque_Nm=None):
    """Run the native (numba) solver on a scene's tables with the scene's settings."""
    t1_Nm = scene.operating.torque_Nm if pinion_torque_Nm is None else pinion_torque_Nm
    return simulate(
        tables,
        stop_time_s=scene.fmu.stop_time_s if stop_time_s is None else stop_time_s,
        comm_step_s=scene.fmu.output_interval_s if comm_step_s is None else comm_step_s,
        max_step_s=max_step_for(scene, tables) if max_step_s is None else max_step_s,
        pinion_torque_Nm=t1_Nm,
        gear_torque_Nm=gear_torque_for(tables, t1_Nm) if gear_torque_Nm is None else gear_torque_Nm,
        pinion_speed_start_rad_s=scene.operating.speed_rad_s,
        damping_ratio=scene.fmu.damping_ratio if damping_ratio is None else damping_ratio,
        damping_model=scene.solver.damping_model,
        integrator=scene.solver.integrator,
    )
