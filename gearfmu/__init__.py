"""gearfmu: spur and helical gear mesh physics packaged as FMI 2.0 Co-Simulation FMUs.

Data flows one way: scene -> physics (geometry, stiffness, errors, loaded mesh, contact
models, EHL) -> tables -> native solver / FMU (README "Architecture").  Layers, top to
bottom; each imports only the layers below it (tests/test_architecture.py):

===================  ================================================================
Module / package     Contents
===================  ================================================================
cli                  the ``gearfmu`` command line
ssp, bench, plots    SSP packages; hard cases and benchmarks; PNG plots
pipeline             the public entry points: load, compute_tables, build (the
                     planner in front of the stages), the drivetrain's
plan/                fidelity planner ([accuracy]): resolve, the budget rule, the
                     envelope search, the report, the confirmation through FMUs
stages               the stages of a pair or a drivetrain scene, without the
                     planner: tables, run settings, FMU, native and gearbox runs
fmu/                 model description, FMU builders, envelope record, runtime, C
gearbox/             gearbox model, modes, native gearbox solver
dynamics/            native solver, reference integrator, sweeps, harmonics
tables/, scene/      tooth-pair tables and their precompute; the scene reader
contact/             contact-model registry, fractal, load sharing, roughness
gear/                gear pair: geometry, stiffness, errors, loaded mesh, thermal
ehl/                 line-contact EHL numerics
common/              option vocabulary, run settings, input checks, executors
===================  ================================================================
"""
__version__ = "0.1.0"
