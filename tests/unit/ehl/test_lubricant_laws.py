"""Lubricant laws of gearfmu.ehl.lubricant against references no code here produced.

* Seed 000 eq 9 (bulk modulus) against the equation of state it is the tangent
  modulus of (numerical differentiation) and, with the default B0 = 1.83 GPa,
  B0' = 11, against the published Dowson-Higginson density law (Dowson &
  Higginson 1966, constants 0.59 GPa and 1.34 written out here).
* Roelands' (1966) viscosity-temperature-pressure correlation in SI form against
  Roelands' own form in his units (cP, degC, kgf/cm^2), its temperature part
  against ASTM D341 (Walther) for the seed 004 Table 4 oil, and the
  pressure-viscosity coefficient against the numerical initial slope.
"""
import math

import numpy as np
import pytest

from gearfmu.ehl.errors import EHLInputError
from gearfmu.ehl.lubricant import (
    B0_DEFAULT_PA, B0_PRIME_DEFAULT, bulk_modulus_Pa, roelands_alpha_at_viscosity_Pa_inv,
    roelands_alpha_Pa_inv, roelands_S0_from_viscosities, roelands_viscosity_Pas,
    roelands_viscosity_pT_Pas, tait_density_ratio, tait_volume_ratio,
)


@pytest.mark.parametrize("B0_Pa,B0_prime", [(B0_DEFAULT_PA, B0_PRIME_DEFAULT), (1.2e9, 7.0), (2.5e9, 14.0)])
def test_eq9_is_the_tangent_modulus_of_the_tait_equation(B0_Pa, B0_prime):
    # Reference: B = -V dp/dV = -dp/d(ln V), by central differences of V/V0 (Richardson
    # extrapolated), independent of the closed form of eq 9.
    for p in (1e7, 2e8, 6e8, 1.5e9, 3e9):
        def dlnV(dp):
            return (np.log(tait_volume_ratio(p + dp, B0_Pa, B0_prime))
                    - np.log(tait_volume_ratio(p - dp, B0_Pa, B0_prime))) / (2 * dp)
        h = 1e6
        d = (4 * dlnV(h / 2) - dlnV(h)) / 3
        assert bulk_modulus_Pa(p, B0_Pa, B0_prime) == pytest.approx(-1.0 / d, rel=1e-7)


def test_default_tait_density_matches_dowson_higginson():
    # Reference: Dowson & Higginson (1966) rho/rho0 = (0.59e9 + 1.34 p)/(0.59e9 + p), the
    # density law of seed 000 eq 6, an independent published fit for mineral oils.
    # The default B0, B0' (rho c^2 of a mineral oil and Bair's typical K0') integrate to a
    # density within 1.7 % of it from 0 to 2 GPa (measured: -1.6 % at 0.5 GPa, +1.6 % at 2 GPa),
    # and D-H's own ambient tangent modulus 0.59 GPa / 0.34 = 1.735 GPa is within 6 % of B0.
    p = np.linspace(0.0, 2e9, 201)
    dh = (0.59e9 + 1.34 * p) / (0.59e9 + p)
    tait = tait_density_ratio(p)
    assert np.max(np.abs(tait / dh - 1.0)) < 0.017
    assert abs(0.59e9 / 0.34 / B0_DEFAULT_PA - 1.0) < 0.06
    # the check can fail: a B0' far from 11 leaves the band
    assert np.max(np.abs(tait_density_ratio(p, B0_DEFAULT_PA, 5.0) / dh - 1.0)) > 0.03


def _roelands_original_cP(t_C, p_kgf_cm2, eta_ref_cP, t_ref_C, Z, S0):
    """Roelands (1966) in his units: log10 eta + 1.2 = G0 (1 + t/135)^-S0 (1 + p/2000)^Z."""
    G0 = (math.log10(eta_ref_cP) + 1.2) * (1.0 + t_ref_C / 135.0) ** S0
    return 10.0 ** (G0 * (1.0 + t_C / 135.0) ** (-S0) * (1.0 + p_kgf_cm2 / 2000.0) ** Z - 1.2)


@pytest.mark.parametrize("t_C", [20.0, 40.0, 80.0, 120.0])
@pytest.mark.parametrize("p_Pa", [0.0, 1e8, 5e8, 1e9])
def test_roelands_SI_form_equals_roelands_original_units(t_C, p_Pa):
    # Reference: Roelands' correlation in cP / degC / kgf/cm^2 (1 kgf/cm^2 = 98066.5 Pa).
    # The SI constants (9.67, 1.96e8 Pa, 138 K) are rounded conversions of 1.2, 2000 kgf/cm^2
    # and 135 degC, so ln(eta) + 9.67 agrees to 1e-3 relative, not to round-off.
    eta_ref, t_ref, Z, S0 = 0.278, 40.0, 0.6, 1.1
    ours = roelands_viscosity_pT_Pas(p_Pa, t_C + 273.15, eta_ref, t_ref + 273.15, Z, S0)
    ref = _roelands_original_cP(t_C, p_Pa / 98066.5, eta_ref * 1e3, t_ref, Z, S0) * 1e-3
    assert math.log(ours) + 9.67 == pytest.approx(math.log(ref) + 9.67, rel=1e-3)


def test_roelands_at_reference_temperature_is_seed000_eq5():
    # Consistency: at T = T_ref the law is seed 000 eq 5 with z = Z, i.e. the isothermal
    # Roelands law with alpha = Z (ln eta0 + 9.67)/p0.
    p = np.linspace(0.0, 2e9, 11)
    eta_ref, T_ref, Z = 0.118, 333.15, 0.65
    alpha = roelands_alpha_Pa_inv(eta_ref, Z)
    np.testing.assert_allclose(roelands_viscosity_pT_Pas(p, T_ref, eta_ref, T_ref, Z, 1.2),
                               roelands_viscosity_Pas(p, eta_ref, alpha), rtol=1e-12)


@pytest.mark.parametrize("t_C", [40.0, 70.0, 100.0])
def test_alpha_is_the_initial_pressure_slope_at_each_temperature(t_C):
    # Reference: d ln(eta)/dp at p = 0 by one-sided differences (Richardson, second order).
    eta_ref, T_ref, Z, S0 = 0.278, 313.15, 0.6, 1.0
    T = t_C + 273.15

    def slope(h):
        e = roelands_viscosity_pT_Pas(np.array([0.0, h]), T, eta_ref, T_ref, Z, S0)
        return (math.log(e[1]) - math.log(e[0])) / h

    numeric = 2 * slope(5e4) - slope(1e5)
    eta0_T = float(roelands_viscosity_pT_Pas(0.0, T, eta_ref, T_ref, Z, S0))
    assert roelands_alpha_Pa_inv(eta0_T, Z) == pytest.approx(numeric, rel=1e-6)
    # and the constant-Z transfer from the reference temperature gives the same value
    alpha_ref = roelands_alpha_Pa_inv(eta_ref, Z)
    assert roelands_alpha_at_viscosity_Pa_inv(alpha_ref, eta_ref, eta0_T) == pytest.approx(numeric, rel=1e-6)


def _walther_cSt(nu40, nu100, T_K):
    """ASTM D341: log10 log10(nu + 0.7) = A - B log10 T, through (40 degC, nu40), (100 degC, nu100)."""
    y1, y2 = math.log10(math.log10(nu40 + 0.7)), math.log10(math.log10(nu100 + 0.7))
    B = (y1 - y2) / (math.log10(373.15) - math.log10(313.15))
    A = y1 + B * math.log10(313.15)
    return 10 ** (10 ** (A - B * math.log10(T_K))) - 0.7


def test_roelands_temperature_law_follows_astm_d341_for_seed004_oil():
    # Reference: ASTM D341 (Walther) through the seed 004 Table 4 oil, 320 cSt at 40 degC and
    # 38.5 cSt at 100 degC, density 870 kg/m^3. Roelands' S0 through the same two points
    # (measured S0 = 0.987) reproduces D341 within 0.7 % at 60 and 80 degC and within 1.2 % at
    # 20 and 120 degC (two independent standard laws, asserted at 1.5 %).
    rho = 870.0
    eta40, eta100 = 320e-6 * rho, 38.5e-6 * rho
    S0 = roelands_S0_from_viscosities(eta40, 313.15, eta100, 373.15)
    assert 0.9 < S0 < 1.1
    for t in (20.0, 60.0, 80.0, 120.0):
        T = t + 273.15
        ref = _walther_cSt(320.0, 38.5, T) * 1e-6 * rho
        ours = float(roelands_viscosity_pT_Pas(0.0, T, eta40, 313.15, 0.6, S0))
        assert ours == pytest.approx(ref, rel=0.015), t
    assert float(roelands_viscosity_pT_Pas(0.0, 373.15, eta40, 313.15, 0.6, S0)) == pytest.approx(eta100, rel=1e-12)


def test_bad_inputs_name_the_field():
    with pytest.raises(EHLInputError, match="T_K"):
        roelands_viscosity_pT_Pas(0.0, 100.0, 0.1, 313.15, 0.6, 1.0)
    with pytest.raises(EHLInputError, match="S0"):
        roelands_viscosity_pT_Pas(0.0, 330.0, 0.1, 313.15, 0.6, -1.0)
    with pytest.raises(EHLInputError, match="Z"):
        roelands_viscosity_pT_Pas(0.0, 330.0, 0.1, 313.15, float("nan"), 1.0)
    with pytest.raises(EHLInputError, match="p_Pa"):
        roelands_viscosity_pT_Pas(-1.0, 330.0, 0.1, 313.15, 0.6, 1.0)
    with pytest.raises(EHLInputError, match="eta_ref_Pas"):
        roelands_viscosity_pT_Pas(0.0, 330.0, 1e-5, 313.15, 0.6, 1.0)
    with pytest.raises(EHLInputError, match="T_K"):
        roelands_S0_from_viscosities(0.2, 313.15, 0.03, 313.15)
    with pytest.raises(EHLInputError, match="eta0_Pas"):
        roelands_alpha_Pa_inv(-0.1, 0.6)
    with pytest.raises(EHLInputError, match="B0_prime"):
        tait_volume_ratio(1e8, 1.8e9, -2.0)
    with pytest.raises(EHLInputError, match="p_Pa"):
        tait_density_ratio(-1.0)
