"""The main job on a scene: scene -> (plan) -> tables -> FMU, and the native run beside it.

The public entry points.  The stages themselves are wired in :mod:`gearfmu.stages`
(re-exported here); :func:`build` adds the planner (:mod:`gearfmu.plan`) in front when
the scene has an ``[accuracy]`` section.
"""
from __future__ import annotations

from typing import Optional

from .stages import (BuildResult, build_fmu_from_scene, compute_tables, fmu_builder, gear_torque_for, load,
                     max_step_for, platform_kw, simulate_native)
from .scene.physics import check_build_cost

__all__ = ["BuildResult", "build", "compute_tables", "gear_torque_for", "load", "max_step_for",
           "simulate_native"]


def build(scene, out_path, *, progress: bool = False, runtime: Optional[str] = None,
          tables=None, estimate_accuracy: bool = False, platforms=None, allow_large: bool = False,
          fmi_version: int = 2, fmi3_outputs: str = "array") -> BuildResult:
    """Scene -> tables -> FMU at ``out_path``.  ``runtime``: "standalone" (FMI layer in C,
    docs/standalone.md) or "pythonfmu"; None: the scene's ``fmu.runtime``.
    ``tables``: MeshTables to use instead of the scene's physics (e.g. imported from CSV,
    gearfmu.tables.table_import); the scene then only gives the FMU and operating settings.
    A scene with ``[accuracy]`` is built as its fidelity plan says (gearfmu.plan; a plan that is
    not within its target is refused with :class:`gearfmu.plan.PlanError`); without it, the scene
    is built as written and ``estimate_accuracy`` adds a cheap estimate of its error against the
    full-fidelity model over the envelope (``BuildResult.verified_envelope``).
    ``platforms``: binaries of a standalone FMU (gearfmu.fmu.crossbuild keys; None: all available).
    ``fmi3_outputs``: an FMI 3 FMU's per-slot outputs as arrays ("array") or scalars ("scalar",
    pair_force_1 .. for hosts without array support; docs/standalone.md "FMI 3.0").
    ``allow_large``: build even when the estimate (gearfmu.tables.estimate) exceeds the limits.
    The FMU records and checks its envelope (:func:`gearfmu.scene.envelope.fmu_envelope_record`: the verified
    envelope, else the tables' own range and the scene's speed range, "not verified"; docs/fmu.md)."""
    runtime = runtime or scene.fmu.runtime
    fmu_builder(runtime)  # an unknown runtime fails before anything is computed
    platform_kw(runtime, platforms, fmi_version, fmi3_outputs)
    if tables is None:  # refuse an oversized scene before planning or estimating anything
        check_build_cost(scene, allow_large=allow_large)
    plan = None
    if tables is None and scene.accuracy is not None:  # follow the plan (docs/plan.md)
        from .plan import PlanError, plan_scene, planned_scene  # the planner: loaded only for scenes with [accuracy]
        plan = plan_scene(scene, progress=progress)
        if not plan.within_target:
            v = plan.verification
            raise PlanError(f"accuracy: the fidelity plan of scene {scene.name!r} is not within its target over "
                            f"the envelope ({v.get('refused') or 'worst: ' + str(v.get('worst'))}); "
                            f"see `gearfmu plan`")
        verified = plan.verified_envelope
        scene = planned_scene(scene, plan)
    elif tables is None and estimate_accuracy:
        from .plan import estimate_as_written  # the planner: loaded only for the as-written estimate
        try:
            verified = estimate_as_written(scene, progress=progress)
        except (ValueError, ArithmeticError) as exc:  # the estimate never stops a build; it says why it is missing
            verified = {"kind": "as-written estimate", "error": f"{type(exc).__name__}: {exc}"}
    else:
        verified = None
    return build_fmu_from_scene(scene, out_path, progress=progress, runtime=runtime, tables=tables, plan=plan,
                                verified_envelope=verified, platforms=platforms, allow_large=allow_large,
                                fmi_version=fmi_version, fmi3_outputs=fmi3_outputs)
