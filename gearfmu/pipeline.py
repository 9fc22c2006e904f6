"""The public entry points of the main job on a scene: scene -> (plan) -> tables -> FMU, the native
run beside it, the FMU checked against it, and a drivetrain scene's gearbox (its native run, its
gearbox FMU and that FMU's check).  ``import gearfmu`` gives these names lazily (the table of
:mod:`gearfmu`).

The stages themselves -- a pair scene's tables, run settings, FMU and native run, a drivetrain
scene's stage tables, gearbox or planetary model, run, modes and gearbox FMU -- live in :mod:`gearfmu.stages` (re-exported
here) and never plan.  This module puts the planner in front: :func:`build` builds what
:func:`gearfmu.plan.resolve` says a scene needs (its fidelity plan when it has an
``[accuracy]`` section, else the scene as written).
"""
from __future__ import annotations

from pathlib import Path
from typing import Optional

from .fmu.compare import DEFAULT_TOLERANCE, FmuFile, check_fmu_matches, open_fmu, validate_fmu_against_native
from .fmu.gearbox_build import variables_of_fmu
from .fmu.gearbox_compare import check_gearbox_fmu_matches, validate_gearbox_fmu
from .fmu.planetary_build import variables_of_fmu as planetary_variables_of_fmu
from .fmu.planetary_compare import check_planetary_fmu_matches, validate_planetary_fmu
from .common.vocabulary import DEFAULT_FMI3_OUTPUTS
from .stages import (PAIR_MESH_NAME, BuildResult, DrivetrainBuild, build_drivetrain_fmu,  # noqa: F401
                     build_fmu_from_scene, check_fmu_supported, check_gearbox_fmu_runtime, compute_tables,
                     describe_model, drivetrain_model, fmu_builder, gear_torque_for, gearbox_fmu_settings,
                     gearbox_model, gearbox_run_settings, is_drivetrain_file, load, load_any, max_step_for,
                     modes_lines, modes_report, pair_model, planetary_fmu_settings, planetary_stages, platform_kw,
                     run_settings,
                     simulate_drivetrain, simulate_native, stage_tables)

__all__ = ["BuildResult", "build", "compute_tables", "gear_torque_for", "load", "max_step_for", "run_settings",
           "simulate_native", "load_any", "is_drivetrain_file", "stage_tables", "gearbox_model", "pair_model",
           "gearbox_run_settings", "simulate_drivetrain", "modes_report", "PAIR_MESH_NAME", "gearbox_fmu_settings",
           "build_drivetrain_fmu", "DrivetrainBuild", "check_gearbox_fmu_runtime", "drivetrain_model",
           "planetary_stages", "describe_model", "modes_lines", "check_fmu_supported", "validate", "validate_drivetrain"]


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


def _opened(fmu) -> FmuFile:
    """``fmu`` (a path, or an FmuFile already opened) opened: FmuMismatchError naming the file otherwise."""
    return fmu if isinstance(fmu, FmuFile) else open_fmu(fmu)


def validate(scene, fmu=None, *, out_path=None, tolerance: float = DEFAULT_TOLERANCE,
             stop_time_s: Optional[float] = None, comm_step_s: Optional[float] = None, progress: bool = False,
             allow_large: bool = False) -> dict:
    """``gearfmu validate`` of a pair scene: an FMU against the native solver on the same tables and run
    settings; the report of :func:`gearfmu.fmu.compare.validate_fmu_against_native` (fmpy's validation
    problems, per output the largest and RMS difference FMU - native and the native range, ``failed``: the
    outputs beyond ``tolerance`` (1) of their range, the wall times (s)) with ``scene``: the scene's name.
    ``fmu``: the FMU to check (a path or an opened :class:`gearfmu.fmu.compare.FmuFile`; refused with
    FmuMismatchError before any table is computed when it was built from another scene); None: the scene's
    FMU is built at ``out_path`` (None: ``build/<model_name>.fmu``, as the command line) the way
    :func:`build` builds it (its fidelity plan when the scene has ``[accuracy]``).  ``stop_time_s``,
    ``comm_step_s`` (s): None takes the scene's ``[fmu]`` values."""
    text = scene.text
    if fmu is not None:
        fmu = _opened(fmu)
        check_fmu_matches(fmu, scene_text=text)  # before the tables are computed
    from .plan import resolve  # the planner: loaded by the commands that build, not at startup
    # the scene the FMU is built from: its plan's when it has [accuracy] (as build)
    scene, plan, verified = resolve(scene, progress=progress, allow_large=allow_large)
    if fmu is not None:
        fmu_path = fmu.path
        tables = compute_tables(scene, progress=progress, allow_large=allow_large)
        settings = run_settings(scene, tables)
    else:
        out = Path(out_path) if out_path is not None else Path("build") / f"{scene.fmu.model_name}.fmu"
        res = build_fmu_from_scene(scene, out, progress=progress, plan=plan, verified_envelope=verified,
                                   allow_large=allow_large)
        fmu_path, tables, settings = res.fmu_path, res.tables, res.settings
    rep = validate_fmu_against_native(fmu_path, tables, settings, stop_time_s=stop_time_s or scene.fmu.stop_time_s,
                                      comm_step_s=comm_step_s or scene.fmu.output_interval_s, tolerance=tolerance,
                                      scene_text=text)
    rep["scene"] = scene.name
    return rep


def _scalar_fmi3(fmu_path) -> bool:
    """An FMI 3 gearbox FMU built with scalar per-slot outputs (stage1.pair_force_1, ...)."""
    import fmpy  # fmpy: only to read the FMU

    md = fmpy.read_model_description(str(fmu_path))
    return md.fmiVersion.startswith("3") and any(v.name.endswith(".pair_force_1") for v in md.modelVariables)


def _interface(fmu_path) -> str:
    """The interfaces of an FMU: "cs", "me" or "both"."""
    import fmpy  # fmpy: only to read the FMU

    md = fmpy.read_model_description(str(fmu_path))
    return {(True, True): "both", (True, False): "cs", (False, True): "me"}[(md.coSimulation is not None,
                                                                             md.modelExchange is not None)]


def validate_drivetrain(scene, fmu=None, *, out_path=None, tolerance: float = DEFAULT_TOLERANCE,
                        stop_time_s: Optional[float] = None, comm_step_s: Optional[float] = None,
                        progress: bool = False, allow_large: bool = False) -> dict:
    """``gearfmu validate`` of a drivetrain scene: its gearbox FMU against the native gearbox solver; the
    report of :func:`gearfmu.fmu.gearbox_compare.validate_gearbox_fmu` (the keys of :func:`validate`'s, and
    ``units``) with ``scene``; a drivetrain with planetary stages: its planetary FMU against the native
    planetary solver (:func:`gearfmu.fmu.planetary_compare.validate_planetary_fmu`).  ``fmu``: the gearbox FMU to check (a path or an opened FmuFile; refused
    before the tables are computed when it is not a gearbox FMU of this scene); None: built at ``out_path``
    (None: ``build/<model_name>.fmu``).  ``stop_time_s``, ``comm_step_s`` (s): None takes the scene's."""
    planetary = bool(scene.planetaries)
    if fmu is not None:
        fmu = _opened(fmu)
        (check_planetary_fmu_matches if planetary else check_gearbox_fmu_matches)(fmu, scene_text=scene.text)
        fmu_path = fmu.path
        tables = stage_tables(scene, progress=progress, allow_large=allow_large)
        if planetary:
            model = drivetrain_model(scene, tables)
            settings = planetary_fmu_settings(scene, model)
        else:
            model = gearbox_model(scene, tables)
            settings = gearbox_fmu_settings(scene, model)
    else:
        out = Path(out_path) if out_path is not None else Path("build") / f"{scene.model_name}.fmu"
        res = build_drivetrain_fmu(scene, out, progress=progress, allow_large=allow_large)
        fmu_path, model, settings = res.fmu_path, res.model, res.settings
    if planetary:
        fmi3_outputs = "scalar" if _scalar_fmi3(fmu_path) else DEFAULT_FMI3_OUTPUTS
        variables = planetary_variables_of_fmu(model, settings, fmi3_outputs, interface=_interface(fmu_path))
        rep = validate_planetary_fmu(fmu_path, model, settings, variables, tolerance=tolerance, scene_text=scene.text,
                                     stop_time_s=stop_time_s, comm_step_s=comm_step_s)
        rep["scene"] = scene.name
        return rep
    variables = variables_of_fmu(model, settings, "scalar" if _scalar_fmi3(fmu_path) else DEFAULT_FMI3_OUTPUTS)
    rep = validate_gearbox_fmu(fmu_path, model, settings, variables, tolerance=tolerance, scene_text=scene.text,
                               stop_time_s=stop_time_s, comm_step_s=comm_step_s)
    rep["scene"] = scene.name
    return rep
