"""Line-contact EHL (Zhao et al. 2022 eq 2-7): lubricant laws, deformation, multigrid solver.

Public API: :func:`solve_line_contact` with its :class:`LineContactSettings`,
:class:`LineContactResult`, the transient
solver :func:`solve_line_contact_transient` (docs/ehl_transient.md) and the
errors :class:`EHLInputError`, :class:`EHLConvergenceError`,
:class:`FilmCollapseError` (all ValueError subclasses).

Self-contained numerics: imports nothing from gearfmu but :mod:`gearfmu.common`.

================  =================================================================
Module            Contents
================  =================================================================
solver            steady line-contact solver (Zhao et al. 2022 eq 2-7): inputs, settings, result
attempts          the chain of attempts of a steady solve: fast path, corner plan,
                  settings per grid with polish, coupled Newton from stalled states
transient         transient solver, roughness moving with the surfaces
transient_inputs  input groups of the transient solver (operating, lubricant, numerics)
transient_steps   time levels of the transient solver: moving roughness, schemes, settings
                  in turn, sub-step rescue
mesh_film         films along the line of action: kinematics, node solves
multigrid         the multigrid core: EHLParams, FlatMultigrid (levels, starts, iteration)
mgcycle           compiled cycles: schedules, convergence loop, option vector
mgkernels         compiled grid operators: film, coefficients, residual, relaxation, transfers
iterate           one relaxation setting on one grid (CycleSettings): cycles, rough-film
                  Newton, polish, freeze
coarse_newton     coarsest-grid Newton solve, dense LU
film_newton       coupled Newton of the finest grid (pressure and H0; rough films)
polish            block-Newton polish of the pressure-spike region
grids             grid choice: default grid, coarse-grid and refined retries
roughness         roughness input: normalisation, band limit
deformation       elastic deformation (Zhao et al. 2022 eq 4), FFT convolution
lubricant         Lubricant; viscosity/density laws: Roelands, D-H, Tait, Walther
film_stiffness    oil-film normal stiffness (Zhao et al. 2022 eq 8-10)
fits              closed-form film-thickness fits
errors            EHLInputError, EHLConvergenceError, FilmCollapseError
================  =================================================================
"""
from .errors import EHLConvergenceError, EHLError, EHLInputError, FilmCollapseError
from .solver import LineContactResult, LineContactSettings, solve_line_contact, REFERENCE_CASE
from .transient import (FlankSliceRoughness, HarmonicWaviness, TransientLineContactResult,
                        solve_line_contact_transient)
from .transient_inputs import TransientLubricant, TransientNumerics, TransientOperating

__all__ = ["solve_line_contact", "LineContactSettings", "LineContactResult", "REFERENCE_CASE", "EHLError",
           "EHLInputError", "EHLConvergenceError", "FilmCollapseError",
           "solve_line_contact_transient", "TransientLineContactResult", "HarmonicWaviness",
           "FlankSliceRoughness", "TransientOperating", "TransientLubricant",
           "TransientNumerics"]
