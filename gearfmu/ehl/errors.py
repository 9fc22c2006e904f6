"""Exceptions raised by :mod:`gearfmu.ehl` (all are ValueError subclasses)."""
from __future__ import annotations


class EHLError(ValueError):
    """Base class of the EHL solver's errors."""


class EHLInputError(EHLError):
    """An input is out of range; the message names the field and the reason."""


class EHLConvergenceError(EHLError):
    """The multigrid iteration stalled.

    ``residual_name`` is the residual that stalled ("pressure_change",
    "load_balance" or "reynolds_residual") and ``value`` its last value.
    From the steady solver also: ``best_residual``, the lowest final scaled
    Reynolds residual of any setting tried; ``attempts``, one
    (finest-grid intervals, coarsest-grid intervals, attempt index -- the index
    into the relaxation settings in the order tried --, final scaled residual) per
    setting tried; ``skipped``, why settings or retry grids were
    not tried (fail fast, docs/ehl.md); ``problem``, the keyword arguments of
    :func:`gearfmu.ehl.solve_line_contact` that pose the same problem again in
    full precision (dimensional inputs, laws, domain, a grid given by the caller;
    not the roughness or the solver options), so that a failure seen in a long
    run can be repeated on its own (the message's M and L are in full precision too).
    """

    def __init__(self, message: str, residual_name: str = "", value: float = float("nan"),
                 history=None, best_residual: float = float("nan"), attempts=None,
                 skipped=None, problem=None):
        super().__init__(message)
        self.residual_name = residual_name
        self.value = value
        self.history = history
        self.best_residual = best_residual
        self.attempts = list(attempts or [])
        self.skipped = list(skipped or [])
        self.problem = dict(problem or {})


class FilmCollapseError(EHLError):
    """The film thickness reached zero (h <= 0) somewhere: the full-film model
    of Zhao et al. 2022 does not hold there.  ``x_m`` is the position, ``film_parameter``
    lambda = h_min / sigma (composite RMS roughness); ``h_min_m`` the film."""

    def __init__(self, message: str, x_m: float = float("nan"),
                 film_parameter: float = float("nan"), h_min_m: float = float("nan")):
        super().__init__(message)
        self.x_m = x_m
        self.film_parameter = film_parameter
        self.h_min_m = h_min_m


RESIDUAL_NAMES = ("pressure_change", "load_balance", "reynolds_residual")


def stalled_residual(history, tol_pressure: float, tol_residual: float, tol_load: float):
    """Which residual stalled, for :class:`EHLConvergenceError`: from a history dict of
    residual lists return (last values by name, name, its last value, its tolerance).
    The pressure change is named first, then the scaled Reynolds residual, then the load
    balance (a NaN counts as not converged)."""
    last = {q: (history[q][-1] if history.get(q) else float("nan")) for q in RESIDUAL_NAMES}
    if not last["pressure_change"] < tol_pressure:
        return last, "pressure_change", last["pressure_change"], tol_pressure
    if not last["reynolds_residual"] < tol_residual:
        return last, "reynolds_residual", last["reynolds_residual"], tol_residual
    return last, "load_balance", last["load_balance"], tol_load
