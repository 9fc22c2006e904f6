"""gearfmu: spur and helical gear mesh physics packaged as FMI 2.0 Co-Simulation FMUs.

Data flows one way: scene -> physics (geometry, stiffness, errors, loaded mesh, contact
models, EHL) -> tables -> native solver / FMU (README "Architecture").  Layers, top to
bottom; each imports only the layers below it (tests/test_architecture.py):

===================  ================================================================
Module / package     Contents
===================  ================================================================
cli                  the ``gearfmu`` command line
ssp, bench, plots    SSP packages; hard cases and benchmarks; PNG plots
pipeline             the public entry points: load, compute_tables, build (with plan)
plan                 fidelity planner ([accuracy]): the budget rule, revisions, estimate
plan_fmu             the planned / full scenes and their confirmation through the FMUs
plan_report,         the plan and its report;
plan_evaluator       tables and native runs of configurations
plan_verify,         the planner's envelope search and verification drives;
plan_choices         the choices, their levels and what is skipped
stages               the stages wired without the planner
fmu/                 model description, FMU builders, runtime, C sources
dynamics/            native solver, reference integrator, sweeps, harmonics
tables/, scene/      tooth-pair tables and their precompute; the scene reader
contact/             contact-model registry, fractal, load sharing, roughness
gear/                gear pair: geometry, stiffness, errors, loaded mesh, thermal
ehl/                 line-contact EHL numerics
common/              option vocabulary, input checks, executors
===================  ================================================================
"""
__version__ = "0.1.0"
