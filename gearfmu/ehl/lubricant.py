"""Lubricant property laws used by the line-contact EHL solver (SI units).

* Roelands-type pressure-viscosity law, seed 000 eq 5 (Roelands 1966, in the
  form used by Venner & Lubrecht 2000, *Multilevel Methods in Lubrication*,
  Elsevier):

      eta(p) = eta0 * exp{ (ln(eta0) + 9.67) * [ -1 + (1 + p/p0)^z ] }

  with p0 = 1.96e8 Pa (the "pressure coefficient" of seed 000) and the
  viscosity-pressure index z chosen so that the initial slope
  d ln(eta)/dp at p = 0 equals the Barus pressure-viscosity coefficient
  alpha:  z = alpha * p0 / (ln(eta0) + 9.67)   (eta0 in Pa s).
* Dowson-Higginson density, seed 000 eq 6 (Dowson & Higginson 1966):

      rho(p) = rho0 * (0.59e9 + 1.34 p) / (0.59e9 + p)

* Bulk modulus of the lubricant against pressure, seed 000 eq 9 (tangent
  modulus of the isothermal Tait equation; Dwyer-Joyce, Reddyhoff & Zhu 2011),
  :func:`bulk_modulus_Pa`; the choice of B0, B0' is explained in
  :mod:`gearfmu.ehl.film_stiffness`.

Negative pressures are not physical in the cavitated film; every law here
treats ``p < 0`` as an error.
"""
from __future__ import annotations

import math

import numpy as np

from .errors import EHLInputError

#: Roelands reference pressure p0 in Pa (seed 000 eq 5; Venner & Lubrecht 2000).
ROELANDS_P0_PA = 1.96e8
#: Roelands constant ln(eta_inf) = -9.67 with eta in Pa s (Roelands 1966).
ROELANDS_LN_ETA_INF = -9.67
#: Dowson-Higginson constants (seed 000 eq 6), Pa and dimensionless.
DH_C1_PA = 0.59e9
DH_C2 = 1.34


def _check_positive(name: str, value: float) -> float:
    value = float(value)
    if not math.isfinite(value) or value <= 0.0:
        raise EHLInputError(f"{name} must be finite and > 0, got {value!r}")
    return value


def roelands_z(eta0_Pas: float, alpha_Pa_inv: float, p0_Pa: float = ROELANDS_P0_PA) -> float:
    """Roelands viscosity-pressure index z (dimensionless).

    z = alpha * p0 / (ln(eta0) + 9.67), eta0 in Pa s, alpha in 1/Pa, p0 in Pa
    (Venner & Lubrecht 2000): the Roelands law then has the same
    initial pressure-viscosity slope as Barus' law with coefficient alpha.
    """
    eta0 = _check_positive("eta0_Pas", eta0_Pas)
    alpha = float(alpha_Pa_inv)
    if not math.isfinite(alpha) or alpha < 0.0:
        raise EHLInputError(f"alpha_Pa_inv must be finite and >= 0, got {alpha_Pa_inv!r}")
    a = math.log(eta0) - ROELANDS_LN_ETA_INF
    if a <= 0.0:
        raise EHLInputError(
            f"eta0_Pas={eta0!r} is below the Roelands limit viscosity 6.31e-5 Pa s "
            "(ln(eta0) + 9.67 must be > 0)")
    return alpha * _check_positive("p0_Pa", p0_Pa) / a


def roelands_viscosity_Pas(p_Pa, eta0_Pas: float, alpha_Pa_inv: float,
                           p0_Pa: float = ROELANDS_P0_PA):
    """Viscosity in Pa s at gauge pressure ``p_Pa`` (Pa), seed 000 eq 5."""
    p = np.asarray(p_Pa, dtype=float)
    if np.any(p < 0.0) or not np.all(np.isfinite(p)):
        raise EHLInputError("p_Pa must be finite and >= 0")
    z = roelands_z(eta0_Pas, alpha_Pa_inv, p0_Pa)
    a = math.log(eta0_Pas) - ROELANDS_LN_ETA_INF
    return eta0_Pas * np.exp(a * (-1.0 + (1.0 + p / p0_Pa) ** z))


def dowson_higginson_density_kg_m3(p_Pa, rho0_kg_m3: float = 1.0):
    """Density in kg/m^3 at gauge pressure ``p_Pa`` (Pa), seed 000 eq 6.

    With the default ``rho0_kg_m3 = 1`` this is the density ratio rho/rho0
    (tends to 1.34 as p -> infinity).
    """
    p = np.asarray(p_Pa, dtype=float)
    if np.any(p < 0.0) or not np.all(np.isfinite(p)):
        raise EHLInputError("p_Pa must be finite and >= 0")
    rho0 = _check_positive("rho0_kg_m3", rho0_kg_m3)
    return rho0 * (DH_C1_PA + DH_C2 * p) / (DH_C1_PA + p)


#: Default bulk modulus at ambient pressure (Pa): rho c^2 = 870 * 1450^2.
B0_DEFAULT_PA = 870.0 * 1450.0 ** 2
#: Default pressure derivative of the bulk modulus (Tait K0').
B0_PRIME_DEFAULT = 11.0


def bulk_modulus_Pa(p_Pa, B0_Pa: float = B0_DEFAULT_PA, B0_prime: float = B0_PRIME_DEFAULT):
    """Bulk modulus B_l (Pa) of the lubricant at pressure ``p_Pa`` (Pa), seed 000 eq 9."""
    p = np.asarray(p_Pa, dtype=float)
    if not np.all(np.isfinite(p)) or np.any(p < 0.0):
        raise EHLInputError("p_Pa must be finite and >= 0")
    if not (math.isfinite(B0_Pa) and B0_Pa > 0):
        raise EHLInputError(f"B0_Pa={B0_Pa!r}: must be finite and > 0")
    if not (math.isfinite(B0_prime) and B0_prime > -1.0):
        raise EHLInputError(f"B0_prime={B0_prime!r}: must be finite and > -1")
    a = 1.0 + B0_prime
    return (1.0 - np.log1p(p / B0_Pa * a) / a) * (B0_Pa + p * a)
