"""gearfmu: spur and helical gear mesh physics packaged as FMI 2.0 and 3.0 Co-Simulation FMUs.

``import gearfmu`` gives the user's entry points, each the Python face of a ``gearfmu`` command
(docs/cli.md).  They load lazily: importing gearfmu reads no numerics (numpy, numba, scipy, fmpy
load with the first entry point used), so a script or a tool that only looks is not slowed.

==========================  =========================  ===================================================
Entry point                 command                    what it does (SI units in, SI units out)
==========================  =========================  ===================================================
load, load_any              every command's SCENE      read and check a scene file (None: the default
                                                       scene); load_any also a drivetrain scene, as
                                                       ("pair" | "drivetrain", scene)
compute_tables              gearfmu tables             a pair scene's tooth-pair tables (MeshTables:
                                                       stiffness N/m, error m per slot and mesh position)
stage_tables                gearfmu tables             a drivetrain scene's tables, one per stage
load_tables_file            build --tables             tables from a .gtab file or CSV (docs/tables.md)
run_settings                                           a pair scene's RunSettings on its tables (the
                                                       FMU's start values and the native run's)
simulate_native             gearfmu simulate           the native (numba) solver on a scene's tables:
                                                       DTE (m), mesh and per-pair force (N), speeds
gearbox_model               gearfmu simulate           a drivetrain scene's GearboxModel on its tables
simulate_drivetrain         gearfmu simulate           the native gearbox solver on that model
build                       gearfmu build              scene -> (plan) -> tables -> FMU file
build_drivetrain_fmu        gearfmu build              drivetrain scene -> one gearbox FMU
validate                    gearfmu validate           an FMU (given or built) against the native solver:
                                                       per-output differences, fmpy's problems
validate_drivetrain         gearfmu validate           a gearbox FMU against the native gearbox solver
plan_scene, format_report   gearfmu plan               the fidelity plan of a scene with [accuracy]
                                                       (docs/plan.md) and its text report
resolve                     (build, validate)          the scene a build builds, its plan, its verified
                                                       envelope
modes_report                gearfmu modes              natural frequencies, strain energy, Campbell data
                                                       of a pair (pair_model) or drivetrain scene
ssp_from_scene              gearfmu ssp                an SSP package of the FMU with parameter variants
==========================  =========================  ===================================================

The types they hand back or take are here too: Scene, DrivetrainScene, MeshTables, RunSettings,
GearboxRunSettings, BuildResult, DrivetrainBuild, Plan; and the errors a user meets most:
SceneError, PlanError, BuildTooLargeError (every error bad input causes is a ValueError whose
message names the field or file and the reason).

>>> import gearfmu
>>> scene = gearfmu.load()                   # the default scene: the Zhao et al. 2022 Table 1 pair
>>> scene.name
'seed000_table1'
>>> tables = gearfmu.compute_tables(scene)   # stiffness and errors of every tooth-pair slot
>>> tables.slots
2
>>> run = gearfmu.simulate_native(scene, tables, stop_time_s=0.01)
>>> import numpy as np                       # the mean mesh force carries the pinion torque, F Rb1 = T1
>>> bool(abs(np.mean(run.mesh_force) * tables.base_radius_pinion_m / scene.operating.torque_Nm - 1) < 0.02)
True

Data flows one way: scene -> physics (geometry, stiffness, errors, loaded mesh, contact
models, EHL) -> tables -> native solver / FMU (README "Architecture").  Layers, top to
bottom; each imports only the layers below it (tests/project/test_architecture.py):

===================  ================================================================
Module / package     Contents
===================  ================================================================
cli                  the ``gearfmu`` command line
ssp, bench, plots    SSP packages; hard cases and benchmarks; PNG plots
pipeline             the public entry points: load, compute_tables, build (the
                     planner in front of the stages), validate, the drivetrain's
plan/                fidelity planner ([accuracy]): resolve, the budget rule, the
                     envelope search, the report, the confirmation through FMUs
stages               the stages of a pair or a drivetrain scene, without the
                     planner: tables, run settings, FMU, native and gearbox runs
fmu/                 model description, FMU builders, envelope record, runtime, C
gearbox/             gearbox model, modes, native gearbox solver
planetary/           planetary stages: Lin & Parker model, classified modes, solver
dynamics/            native solver, reference integrator, sweeps, harmonics
scene/               the scene reader; the physics options read off a scene
assembly/            the physics of a pair turned into tables; the table cache
tables/              the table format (MeshTables, .gtab, CSV import)
contact/             contact-model registry, fractal, load sharing, roughness
gear/                gear pair: geometry, stiffness, errors, loaded mesh, thermal
ehl/                 line-contact EHL numerics
common/              option vocabulary, run settings, input checks, executors
===================  ================================================================

The subpackages and modules of this table are attributes of gearfmu too, loaded when first used
(``gearfmu.plan.resolve``).  The terms, and which paper each seed label is: docs/glossary.md.
"""
from .common.exports import lazy_exports

__version__ = "0.1.0"

#: entry point -> the module (below gearfmu) that defines it
_ENTRY_POINTS = {
    **dict.fromkeys(("load", "load_any", "compute_tables", "stage_tables", "run_settings", "simulate_native",
                     "gearbox_model", "pair_model", "simulate_drivetrain", "build", "build_drivetrain_fmu",
                     "validate", "validate_drivetrain", "modes_report", "BuildResult", "DrivetrainBuild"),
                    "pipeline"),
    **dict.fromkeys(("plan_scene", "format_report", "resolve", "Plan", "PlanError"), "plan"),
    "load_tables_file": "tables.table_import",
    "ssp_from_scene": "ssp",
    "Scene": "scene.options",
    "SceneError": "scene.options",
    "DrivetrainScene": "scene.drivetrain",
    "MeshTables": "tables.mesh_tables",
    "RunSettings": "common.settings",
    "GearboxRunSettings": "common.settings",
    "BuildTooLargeError": "assembly.estimate",
}

#: the modules and subpackages of the layer table above, attributes of gearfmu once used
_SUBMODULES = ("cli", "ssp", "bench", "plots", "pipeline", "plan", "stages", "fmu", "gearbox", "planetary",
               "dynamics", "scene", "assembly", "tables", "contact", "gear", "ehl", "common")

__all__ = sorted(_ENTRY_POINTS)
__getattr__, __dir__ = lazy_exports(__name__, _ENTRY_POINTS, _SUBMODULES)
