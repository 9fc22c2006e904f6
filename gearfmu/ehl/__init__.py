"""Line-contact EHL (seed 000 eq 2-7): lubricant laws, deformation, multigrid solver.

Public API: :func:`solve_line_contact`, :class:`LineContactResult`, the transient
solver :func:`solve_line_contact_transient` (docs/ehl_transient.md) and the
errors :class:`EHLInputError`, :class:`EHLConvergenceError`,
:class:`FilmCollapseError` (all ValueError subclasses).
"""
from .errors import EHLConvergenceError, EHLError, EHLInputError, FilmCollapseError
from .solver import LineContactResult, solve_line_contact, REFERENCE_CASE
from .transient import (FlankSliceRoughness, HarmonicWaviness, TransientLineContactResult,
                        solve_line_contact_transient)

__all__ = ["solve_line_contact", "LineContactResult", "REFERENCE_CASE", "EHLError",
           "EHLInputError", "EHLConvergenceError", "FilmCollapseError",
           "solve_line_contact_transient", "TransientLineContactResult", "HarmonicWaviness",
           "FlankSliceRoughness"]
