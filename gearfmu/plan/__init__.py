"""The fidelity planner: only what a scene needs (docs/plan.md).

Given a scene, its operating envelope and its accuracy target (``[envelope]``, ``[accuracy]``;
:mod:`gearfmu.scene.envelope`), the planner estimates what every modelling choice contributes to
the DTE and the mesh force over the envelope, keeps what the target needs, drops the rest,
verifies the combined choice by a worst-case search of the envelope and measures the cost of
the chosen model against the full one.  It builds its tables, native runs and FMUs with the
stages below it (:mod:`gearfmu.stages`); :func:`resolve` is what a build asks of it.

Exports: :func:`resolve` (the scene a build builds, its plan, its verified envelope),
:func:`plan_scene`, :class:`Plan`, :class:`PlanError`, :func:`format_report`,
:func:`planned_scene`, :func:`full_scene`, :func:`estimate_as_written`,
:func:`verified_envelope_of`, the confirmation through the FMUs (:func:`verify_fmus`,
:func:`verification_cases`, :func:`run_fmu_drive`, :class:`DriveCase`, :func:`drive_case`),
:func:`relative_rms`, :func:`skipped_choices`, ``CONTACT_ORDER``, ``DEFAULT_BUDGET_RUNS``.
The modules' other names are the planner's own.

==========  =======================================================================
Module      Contents
==========  =======================================================================
planner     plan_scene: the budget rule and the revisions; estimate_as_written;
            resolve: what ``gearfmu build`` and ``gearfmu validate`` build
confirm     the planned and full scenes, their confirmation through the FMUs
report      Plan, its JSON and text report, the verified envelope
evaluator   tables and native runs of configurations, per-choice measurements, costs
choices     the choices and their levels (cheapest first, the last the full one),
            what is skipped and why, the what-if contact models
verify      the error measure, the envelope search, the verification drives, the
            progress display
==========  =======================================================================
"""
from .choices import CONTACT_ORDER, PlanError, skipped_choices
from .confirm import full_scene, planned_scene, run_fmu_drive, verification_cases, verify_fmus
from .evaluator import relative_rms
from .planner import DEFAULT_BUDGET_RUNS, estimate_as_written, plan_scene, resolve
from .report import Plan, format_report, verified_envelope_of
from .verify import DriveCase, drive_case

__all__ = ["resolve", "plan_scene", "Plan", "PlanError", "format_report", "planned_scene", "full_scene",
           "estimate_as_written", "verified_envelope_of", "verify_fmus", "verification_cases", "run_fmu_drive",
           "DriveCase", "drive_case", "relative_rms", "skipped_choices", "CONTACT_ORDER", "DEFAULT_BUDGET_RUNS"]
