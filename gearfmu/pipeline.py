"""The public entry points of the main job on a scene: scene -> (plan) -> tables -> FMU, the native
run beside it, and a drivetrain scene's gearbox (its native run and its gearbox FMU).

The stages themselves -- a pair scene's tables, run settings, FMU and native run, a drivetrain
scene's stage tables, gearbox or planetary model, run, modes and gearbox FMU -- live in :mod:`gearfmu.stages` (re-exported
here) and never plan.  This module puts the planner in front: :func:`build` builds what
:func:`gearfmu.plan.resolve` says a scene needs (its fidelity plan when it has an
``[accuracy]`` section, else the scene as written).
"""
from __future__ import annotations

from typing import Optional

from .stages import (PAIR_MESH_NAME, BuildResult, DrivetrainBuild, build_drivetrain_fmu,  # noqa: F401
                     build_fmu_from_scene, check_fmu_supported, check_gearbox_fmu_runtime, compute_tables,
                     describe_model, drivetrain_model, fmu_builder, gear_torque_for, gearbox_fmu_settings,
                     gearbox_model, gearbox_run_settings, is_drivetrain_file, load, load_any, max_step_for,
                     modes_lines, modes_report, pair_model, planetary_stages, platform_kw, run_settings,
                     simulate_drivetrain, simulate_native, stage_tables)

__all__ = ["BuildResult", "build", "compute_tables", "gear_torque_for", "load", "max_step_for", "run_settings",
           "simulate_native", "load_any", "is_drivetrain_file", "stage_tables", "gearbox_model", "pair_model",
           "gearbox_run_settings", "simulate_drivetrain", "modes_report", "PAIR_MESH_NAME", "gearbox_fmu_settings",
           "build_drivetrain_fmu", "DrivetrainBuild", "check_gearbox_fmu_runtime", "drivetrain_model",
           "planetary_stages", "describe_model", "modes_lines", "check_fmu_supported"]


def build(scene, out_path, *, progress: bool = False, runtime: Optional[str] = None,
          tables=None, estimate_accuracy: bool = False, platforms=None, allow_large: bool = False,
          fmi_version: int = 2, fmi3_outputs: str = "array", interface: Optional[str] = None,
          me_node_events: Optional[str] = None) -> BuildResult:
    """Scene -> tables -> FMU at ``out_path``.  ``runtime``: "standalone" (FMI layer in C,
    docs/standalone.md) or "pythonfmu"; None: the scene's ``fmu.runtime``.
    ``tables``: MeshTables to use instead of the scene's physics (e.g. imported from CSV,
    gearfmu.tables.table_import); the scene then only gives the FMU and operating settings.
    Otherwise the scene is built as :func:`gearfmu.plan.resolve` says: a scene with
    ``[accuracy]`` as its fidelity plan says (a plan that is not within its target is refused
    with :class:`gearfmu.plan.PlanError`); without it, as written, and ``estimate_accuracy``
    adds a cheap estimate of its error against the full-fidelity model over the envelope
    (``BuildResult.verified_envelope``).
    ``platforms``: binaries of a standalone FMU (gearfmu.fmu.crossbuild keys; None: all available).
    ``fmi3_outputs``: an FMI 3 FMU's per-slot outputs as arrays ("array") or scalars ("scalar",
    pair_force_1 .. for hosts without array support; docs/standalone.md "FMI 3.0").
    ``allow_large``: build even when the estimate (gearfmu.assembly.estimate) exceeds the limits.
    ``interface``, ``me_node_events``: a standalone FMU's interfaces ("cs", "me", "both") and Model
    Exchange's node events (None: the builder's defaults; docs/standalone.md "Model Exchange").
    The FMU records and checks its envelope (:func:`gearfmu.fmu.envelope.fmu_envelope_record`: the verified
    envelope, else the tables' own range and the scene's speed range, "not verified"; docs/fmu.md)."""
    runtime = runtime or scene.fmu.runtime
    fmu_builder(runtime)  # an unknown runtime fails before anything is computed
    platform_kw(runtime, platforms, fmi_version, fmi3_outputs, interface, me_node_events)
    plan = verified = None
    if tables is None:
        from .plan import resolve  # the planner: loaded by a build, not by importing the command line
        scene, plan, verified = resolve(scene, progress=progress, estimate_accuracy=estimate_accuracy,
                                        allow_large=allow_large)
    return build_fmu_from_scene(scene, out_path, progress=progress, runtime=runtime, tables=tables, plan=plan,
                                verified_envelope=verified, platforms=platforms, allow_large=allow_large,
                                fmi_version=fmi_version, fmi3_outputs=fmi3_outputs,
                                model_exchange={"interface": interface, "me_node_events": me_node_events})
