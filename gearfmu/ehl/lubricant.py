"""Lubricant property laws used by the line-contact EHL solver (SI units).

* Roelands-type pressure-viscosity law, Zhao et al. 2022 eq 5 (Roelands 1966, in the
  form used by Venner & Lubrecht 2000, *Multilevel Methods in Lubrication*,
  Elsevier):

      eta(p) = eta0 * exp{ (ln(eta0) + 9.67) * [ -1 + (1 + p/p0)^z ] }

  with p0 = 1.96e8 Pa (the "pressure coefficient" of Zhao et al. 2022) and the
  viscosity-pressure index z chosen so that the initial slope
  d ln(eta)/dp at p = 0 equals the Barus pressure-viscosity coefficient
  alpha:  z = alpha * p0 / (ln(eta0) + 9.67)   (eta0 in Pa s).
* Dowson-Higginson density, Zhao et al. 2022 eq 6 (Dowson & Higginson 1966):

      rho(p) = rho0 * (0.59e9 + 1.34 p) / (0.59e9 + p)

* Bulk modulus of the lubricant against pressure, Zhao et al. 2022 eq 9 (tangent
  modulus of the isothermal Tait equation; Dwyer-Joyce, Reddyhoff & Zhu 2011),
  :func:`bulk_modulus_Pa`, and the equation of state it is the tangent modulus
  of, :func:`tait_volume_ratio` / :func:`tait_density_ratio`; the choice of
  B0, B0' is explained in :mod:`gearfmu.ehl.film_stiffness`.
* Temperature AND pressure: Roelands' (1966) viscosity-temperature-pressure
  correlation, :func:`roelands_viscosity_pT_Pas` (SI form of Houpert 1985),
  its temperature-viscosity index S0 from two viscosities
  (:func:`roelands_S0_from_viscosities`) and the pressure-viscosity coefficient
  it implies at any oil temperature, :func:`roelands_alpha_Pa_inv` /
  :func:`roelands_alpha_at_viscosity_Pa_inv` (Z constant over temperature,
  Roelands' own assumption).  Not wired into the tables' oil axis yet
  (docs/thermal.md).

Negative pressures are not physical in the cavitated film; every law here
treats ``p < 0`` as an error.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

from .errors import EHLInputError

#: Roelands reference pressure p0 in Pa (Zhao et al. 2022 eq 5; Venner & Lubrecht 2000).
ROELANDS_P0_PA = 1.96e8
#: Roelands constant ln(eta_inf) = -9.67 with eta in Pa s (Roelands 1966).
ROELANDS_LN_ETA_INF = -9.67
#: Dowson-Higginson constants (Zhao et al. 2022 eq 6), Pa and dimensionless.
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
    """Viscosity in Pa s at gauge pressure ``p_Pa`` (Pa), Zhao et al. 2022 eq 5."""
    p = np.asarray(p_Pa, dtype=float)
    if np.any(p < 0.0) or not np.all(np.isfinite(p)):
        raise EHLInputError("p_Pa must be finite and >= 0")
    z = roelands_z(eta0_Pas, alpha_Pa_inv, p0_Pa)
    a = math.log(eta0_Pas) - ROELANDS_LN_ETA_INF
    return eta0_Pas * np.exp(a * (-1.0 + (1.0 + p / p0_Pa) ** z))


def dowson_higginson_density_kg_m3(p_Pa, rho0_kg_m3: float = 1.0):
    """Density in kg/m^3 at gauge pressure ``p_Pa`` (Pa), Zhao et al. 2022 eq 6.

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


def _tait_inputs(p_Pa, B0_Pa: float, B0_prime: float):
    """Checked pressure array (Pa) and 1 + B0' of the Tait law (EHLInputError naming the field)."""
    p = np.asarray(p_Pa, dtype=float)
    if not np.all(np.isfinite(p)) or np.any(p < 0.0):
        raise EHLInputError("p_Pa must be finite and >= 0")
    if not (math.isfinite(B0_Pa) and B0_Pa > 0):
        raise EHLInputError(f"B0_Pa={B0_Pa!r}: must be finite and > 0")
    if not (math.isfinite(B0_prime) and B0_prime > -1.0):
        raise EHLInputError(f"B0_prime={B0_prime!r}: must be finite and > -1")
    return p, 1.0 + B0_prime


def bulk_modulus_Pa(p_Pa, B0_Pa: float = B0_DEFAULT_PA, B0_prime: float = B0_PRIME_DEFAULT):
    """Bulk modulus B_l (Pa) of the lubricant at pressure ``p_Pa`` (Pa), Zhao et al. 2022 eq 9."""
    p, a = _tait_inputs(p_Pa, B0_Pa, B0_prime)
    return (1.0 - np.log1p(p / B0_Pa * a) / a) * (B0_Pa + p * a)


def tait_volume_ratio(p_Pa, B0_Pa: float = B0_DEFAULT_PA, B0_prime: float = B0_PRIME_DEFAULT):
    """V/V0 (dimensionless) at pressure ``p_Pa`` (Pa) of the isothermal Tait
    equation of state whose tangent modulus -V dp/dV is Zhao et al. 2022 eq 9:

        V/V0 = 1 - ln[1 + p (1 + B0')/B0] / (1 + B0')

    (the equation usually called Tait's -- Hayward 1967, Br. J. Appl. Phys. 18,
    965, shows it to be a later misquotation of Tait's original, equivalent to
    it near p = 0 -- in the form Bair 2007 uses with K0 = B0, K0' = B0';
    :func:`bulk_modulus_Pa` is -V dp/dV of this, which the tests check by
    differentiating it numerically).
    """
    p, a = _tait_inputs(p_Pa, B0_Pa, B0_prime)
    return 1.0 - np.log1p(p / B0_Pa * a) / a


def tait_density_ratio(p_Pa, B0_Pa: float = B0_DEFAULT_PA, B0_prime: float = B0_PRIME_DEFAULT):
    """rho/rho0 = V0/V (dimensionless) of :func:`tait_volume_ratio`."""
    return 1.0 / tait_volume_ratio(p_Pa, B0_Pa, B0_prime)


#: Roelands' temperature constant in K: his (1 + t/135 degC) is (T - 138 K)/135 K
#: (Houpert 1985 writes the SI form with 138; 273.15 - 135 = 138.15).
ROELANDS_T_INF_K = 138.0


def _check_temperature_K(name: str, T_K) -> np.ndarray:
    T = np.asarray(T_K, dtype=float)
    if not np.all(np.isfinite(T)) or np.any(T <= ROELANDS_T_INF_K):
        raise EHLInputError(f"{name} must be finite and > {ROELANDS_T_INF_K} K (Roelands' temperature "
                            f"origin -135 degC), got {T_K!r}")
    return T


def roelands_viscosity_pT_Pas(p_Pa, T_K, eta_ref_Pas: float, T_ref_K: float, Z: float, S0: float,
                              p0_Pa: float = ROELANDS_P0_PA):
    """Viscosity in Pa s at gauge pressure ``p_Pa`` (Pa) and temperature ``T_K`` (K):
    Roelands' (1966) viscosity-temperature-pressure correlation.

    Roelands, *Correlational aspects of the viscosity-temperature-pressure
    relationship of lubricating oils*, thesis, TH Delft 1966 (also Roelands,
    Vlugter & Waterman, J. Basic Eng. 85 (1963) 601), in his units
    (eta in cP, t in degC, p in kgf/cm^2):

        log10 eta + 1.200 = (log10 eta_R + 1.200) (1 + t/135)^(-S0) (1 + p/2000)^Z

    which in SI units (Houpert 1985, J. Tribol. 107, 241; eta in Pa s, T in K,
    p in Pa) is

        eta = eta_R exp{ (ln eta_R + 9.67) [ ((T - 138)/(T_R - 138))^(-S0)
                                             (1 + p/p0)^Z - 1 ] },  p0 = 1.96e8 Pa

    (9.67 = 1.2 ln 10 + ln 1000; p0 = 2000 kgf/cm^2).  ``eta_ref_Pas`` is the
    viscosity at ambient pressure and ``T_ref_K``; Z (viscosity-pressure index)
    and S0 (viscosity-temperature index) are constants of the oil, independent of
    T and p (Roelands).  At T = T_R this is Zhao et al. 2022 eq 5 with z = Z.
    """
    p = np.asarray(p_Pa, dtype=float)
    if np.any(p < 0.0) or not np.all(np.isfinite(p)):
        raise EHLInputError("p_Pa must be finite and >= 0")
    T = _check_temperature_K("T_K", T_K)
    T_ref = float(_check_temperature_K("T_ref_K", T_ref_K))
    eta_ref = _check_positive("eta_ref_Pas", eta_ref_Pas)
    a = math.log(eta_ref) - ROELANDS_LN_ETA_INF
    if a <= 0.0:
        raise EHLInputError(f"eta_ref_Pas={eta_ref!r} is below the Roelands limit viscosity 6.31e-5 Pa s")
    Z = float(Z)
    if not math.isfinite(Z) or Z < 0.0:
        raise EHLInputError(f"Z must be finite and >= 0, got {Z!r}")
    S0 = float(S0)
    if not math.isfinite(S0) or S0 < 0.0:
        raise EHLInputError(f"S0 must be finite and >= 0, got {S0!r}")
    p0 = _check_positive("p0_Pa", p0_Pa)
    theta = ((T - ROELANDS_T_INF_K) / (T_ref - ROELANDS_T_INF_K)) ** (-S0)
    return eta_ref * np.exp(a * (theta * (1.0 + p / p0) ** Z - 1.0))


def roelands_S0_from_viscosities(eta_ref_Pas: float, T_ref_K: float, eta_Pas: float, T_K: float) -> float:
    """Roelands' viscosity-temperature index S0 (dimensionless) through two
    ambient-pressure viscosities (Pa s) at two temperatures (K):

        S0 = -ln[(ln eta + 9.67)/(ln eta_R + 9.67)] / ln[(T - 138)/(T_R - 138)]

    (:func:`roelands_viscosity_pT_Pas` at p = 0 solved for S0)."""
    e1, e2 = _check_positive("eta_ref_Pas", eta_ref_Pas), _check_positive("eta_Pas", eta_Pas)
    T1 = float(_check_temperature_K("T_ref_K", T_ref_K))
    T2 = float(_check_temperature_K("T_K", T_K))
    if T1 == T2:
        raise EHLInputError(f"T_K={T_K!r}: must differ from T_ref_K")
    a1, a2 = math.log(e1) - ROELANDS_LN_ETA_INF, math.log(e2) - ROELANDS_LN_ETA_INF
    if a1 <= 0.0 or a2 <= 0.0:
        raise EHLInputError("eta_ref_Pas, eta_Pas: must be above the Roelands limit viscosity 6.31e-5 Pa s")
    return float(-math.log(a2 / a1) / math.log((T2 - ROELANDS_T_INF_K) / (T1 - ROELANDS_T_INF_K)))


def roelands_alpha_Pa_inv(eta0_Pas, Z: float, p0_Pa: float = ROELANDS_P0_PA):
    """Pressure-viscosity coefficient (1/Pa) of the Roelands law at the
    temperature where the ambient viscosity is ``eta0_Pas`` (Pa s): the initial
    slope d ln(eta)/dp at p = 0 of :func:`roelands_viscosity_pT_Pas`,

        alpha = Z (ln eta0 + 9.67) / p0

    (the inverse of :func:`roelands_z`; Houpert 1985).  With Z constant (Roelands)
    alpha falls with temperature as ln eta0 + 9.67 does."""
    eta0 = np.asarray(eta0_Pas, dtype=float)
    if not np.all(np.isfinite(eta0)) or np.any(eta0 <= 0.0):
        raise EHLInputError(f"eta0_Pas must be finite and > 0, got {eta0_Pas!r}")
    a = np.log(eta0) - ROELANDS_LN_ETA_INF
    if np.any(a <= 0.0):
        raise EHLInputError("eta0_Pas: below the Roelands limit viscosity 6.31e-5 Pa s")
    Z = float(Z)
    if not math.isfinite(Z) or Z < 0.0:
        raise EHLInputError(f"Z must be finite and >= 0, got {Z!r}")
    return Z * a / _check_positive("p0_Pa", p0_Pa)


def roelands_alpha_at_viscosity_Pa_inv(alpha_ref_Pa_inv: float, eta0_ref_Pas: float, eta0_Pas):
    """Pressure-viscosity coefficient (1/Pa) at another oil temperature, from
    the one at a reference temperature, with Roelands' Z held constant:

        alpha(T) = alpha_ref (ln eta0(T) + 9.67) / (ln eta0_ref + 9.67)

    ``eta0_Pas`` (scalar or array, Pa s) is the ambient viscosity at the new
    temperature(s) (e.g. from the Walther / ASTM D341 law of the oil axis),
    ``eta0_ref_Pas`` the one at which ``alpha_ref_Pa_inv`` holds.  The form
    the oil temperature axis would use (docs/thermal.md, "What is left")."""
    z = roelands_z(eta0_ref_Pas, alpha_ref_Pa_inv)
    return roelands_alpha_Pa_inv(eta0_Pas, z)


def walther_kinematic_viscosity_cSt(nu40_cSt: float, nu100_cSt: float, temperature_C: float) -> float:
    """Kinematic viscosity (cSt = mm^2/s) at ``temperature_C`` (degC) from the
    values at 40 and 100 degC by the Walther equation of ASTM D341:
    ``log10(log10(nu + 0.7)) = A - B*log10(T)`` with T in K.  The 0.7 constant
    is the D341 form valid for nu >= 2 cSt (the later D341 editions add
    correction terms below that, not needed for gear oils)."""
    if not (nu40_cSt > nu100_cSt > 0.3):
        raise ValueError("walther: need nu40_cSt > nu100_cSt > 0.3 cSt")
    t40, t100, t = 313.15, 373.15, temperature_C + 273.15
    y40 = math.log10(math.log10(nu40_cSt + 0.7))
    y100 = math.log10(math.log10(nu100_cSt + 0.7))
    b = (y40 - y100) / (math.log10(t100) - math.log10(t40))
    a = y40 + b * math.log10(t40)
    return 10.0 ** (10.0 ** (a - b * math.log10(t))) - 0.7


@dataclass(frozen=True)
class Lubricant:
    """Lubricant properties (SI); a scene's ``[lubricant]`` (:mod:`gearfmu.scene.sections`).

    ``dynamic_viscosity_Pas`` is eta0, the ambient-pressure dynamic viscosity
    at ``temperature_C`` (either given directly or from the kinematic
    viscosities at 40 and 100 degC by the Walther / ASTM D341 law times
    ``density_kg_m3``); ``pressure_viscosity_Pa_inv`` is the
    pressure-viscosity coefficient alpha (1/Pa).  Kinematic viscosities are
    kept (m^2/s) when given.
    """

    name: str
    dynamic_viscosity_Pas: float
    pressure_viscosity_Pa_inv: float
    density_kg_m3: float
    temperature_C: float
    kinematic_viscosity_40C_m2_s: Optional[float] = None
    kinematic_viscosity_100C_m2_s: Optional[float] = None

    def kinematic_viscosity_m2_s(self, temperature_C: float) -> float:
        """Kinematic viscosity (m^2/s) at ``temperature_C`` (degC): Walther /
        ASTM D341 through the 40 and 100 degC values when given, otherwise
        the constant eta0/rho (no temperature law known)."""
        if self.kinematic_viscosity_40C_m2_s is None or self.kinematic_viscosity_100C_m2_s is None:
            return self.dynamic_viscosity_Pas / self.density_kg_m3
        return 1e-6 * walther_kinematic_viscosity_cSt(
            self.kinematic_viscosity_40C_m2_s * 1e6, self.kinematic_viscosity_100C_m2_s * 1e6,
            temperature_C)
