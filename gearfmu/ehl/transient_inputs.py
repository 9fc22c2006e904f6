"""Input groups of :func:`.transient.solve_line_contact_transient`.

:class:`TransientOperating` (operating conditions), :class:`TransientLubricant`
(lubricant) and :class:`TransientNumerics` (grid, time stepping, iteration);
each field may also be passed to the solver as a keyword of the same name.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from dataclasses import fields as dataclass_fields
from typing import Optional, Tuple, Union

from .errors import EHLInputError
from .lubricant import B0_DEFAULT_PA, B0_PRIME_DEFAULT


@dataclass(frozen=True)
class TransientOperating:
    """Operating conditions of :func:`solve_line_contact_transient`: the
    dimensional ``R_m`` (m), ``E_Pa`` (reduced modulus, Pa), ``w_N_per_m``
    (N/m, constant in time), ``u_m_s`` (entrainment speed u_s, m/s) or Moes'
    ``M``, ``L``; surface speeds by ``srr`` = (u1 - u2)/u_s or
    ``speed_ratios`` = (U1, U2) = (u1/u_s, u2/u_s)."""

    R_m: Optional[float] = None
    E_Pa: Optional[float] = None
    w_N_per_m: Optional[float] = None
    u_m_s: Optional[float] = None
    M: Optional[float] = None
    L: Optional[float] = None
    srr: float = 0.0
    speed_ratios: Optional[Tuple[float, float]] = None


@dataclass(frozen=True)
class TransientLubricant:
    """Lubricant of :func:`solve_line_contact_transient`: ``eta0_Pas`` (Pa s),
    ``alpha_Pa_inv`` (1/Pa), ``rho0_kg_m3`` (kg/m^3), Dowson-Higginson density
    (``compressible``), ``viscosity`` "roelands" or "barus", and the Tait
    constants ``B0_Pa`` (Pa), ``B0_prime`` of the film stiffness (Zhao et al. 2022 eq 8-9)."""

    eta0_Pas: Optional[float] = None
    alpha_Pa_inv: Optional[float] = None
    rho0_kg_m3: float = 870.0
    compressible: bool = True
    viscosity: str = "roelands"
    B0_Pa: float = B0_DEFAULT_PA
    B0_prime: float = B0_PRIME_DEFAULT


@dataclass(frozen=True)
class TransientNumerics:
    """Grid, time stepping and iteration of :func:`solve_line_contact_transient`
    (meaning of each field: that function's docstring)."""

    n_steps: Optional[int] = None
    dT: Optional[float] = None
    scheme: Optional[str] = None
    n_nodes: Optional[int] = None
    n_coarse: Optional[int] = None
    x_in: float = -4.5
    x_out: float = 1.5
    tol_pressure: float = 1e-5
    tol_load: float = 1e-6
    tol_residual: float = 1e-6
    max_cycles_per_step: int = 40
    extrapolate: bool = True
    relaxation_settings: Optional[tuple] = None
    start: str = "frozen"
    ramp_T: float = 1.0
    steady_options: Optional[dict] = None
    substep_rescue: Union[bool, str] = True


_INPUT_GROUPS = (("operating", TransientOperating), ("lubricant", TransientLubricant),
                 ("numerics", TransientNumerics))


def _transient_inputs(groups, fields):
    """The three input groups with the single ``fields`` (keyword form) applied."""
    out = []
    left = dict(fields)
    for (name, cls), g in zip(_INPUT_GROUPS, groups):
        if g is None:
            g = cls()
        elif not isinstance(g, cls):
            raise EHLInputError(f"{name}: must be a {cls.__name__}, got {type(g).__name__}")
        names = {f.name for f in dataclass_fields(cls)}
        mine = {k: left.pop(k) for k in list(left) if k in names}
        out.append(replace(g, **mine) if mine else g)
    if left:
        raise EHLInputError(f"unknown argument(s) {sorted(left)!r} of "
                            "solve_line_contact_transient")
    return out
