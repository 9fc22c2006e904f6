"""The main job on a scene: scene -> (plan) -> tables -> FMU, and the native run beside it.

The public entry points.  The stages themselves are wired in :mod:`gearfmu.stages`
(re-exported here); :func:`build` adds the planner (:mod:`gearfmu.plan`) in front when
the scene has an ``[accuracy]`` section.
"""
from __future__ import annotations

from typing import Optional

from .plan import plan_scene, planned_scene
from .stages import (BuildResult, build_fmu_from_scene, compute_tables, fmu_builder, gear_torque_for, load,
                     max_step_for, simulate_native)

__all__ = ["BuildResult", "build", "compute_tables", "gear_torque_for", "load", "max_step_for",
           "simulate_native"]


def build(scene, out_path, *, progress: bool = False, runtime: Optional[str] = None,
          tables=None) -> BuildResult:
    """Scene -> tables -> FMU at ``out_path``.  ``runtime``: "pythonfmu" or
    "standalone" (FMI layer in C, docs/standalone.md); None: the scene's ``fmu.runtime``.
    ``tables``: MeshTables to use instead of the scene's physics (e.g. imported from CSV,
    gearfmu.tables.table_import); the scene then only gives the FMU and operating settings.
    A scene with ``[accuracy]`` (and no ``tables``) is planned first (docs/plan.md) and the
    planned scene is built; the plan is in the result."""
    runtime = runtime or getattr(scene.fmu, "runtime", "pythonfmu")
    fmu_builder(runtime)  # an unknown runtime fails before any planning
    plan = None
    if tables is None and getattr(scene, "accuracy", None) is not None:  # follow the plan (docs/plan.md)
        plan = plan_scene(scene, progress=progress)
        scene = planned_scene(scene, plan)
    return build_fmu_from_scene(scene, out_path, progress=progress, runtime=runtime, tables=tables, plan=plan)
