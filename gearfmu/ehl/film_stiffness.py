"""Oil-film (lubricant layer) normal stiffness, Zhao et al. 2022 eq 8-10.

Spring model of a liquid layer (Zhao et al. 2022 ref [43]; Dwyer-Joyce, Reddyhoff &
Zhu 2011, J. Tribol. 133, 031501): a layer of thickness h and bulk modulus B
has a normal stiffness per unit area B/h, so a contact patch of area A has

    k_l = A * B_l / h_l                                              (eq 8)

with the bulk modulus at the mean film pressure p_m (eq 9, the tangent bulk
modulus of the isothermal Tait equation of state; ln = natural log):

    B_l = {1 - ln[1 + (p_m/B0)(1 + B0')] / (1 + B0')} * [B0 + p_m (1 + B0')]

B0 is the bulk modulus at ambient pressure and B0' its pressure derivative
(dB/dp at p = 0 equals B0', which the tests check).  The slice stiffnesses
add (eq 10): K_l = sum_n k_ln.

Values of B0, B0' (a gap of Zhao et al. 2022: eq 9 refers the reader to its ref [44],
a misnumbering -- [44] is Ma et al. 2016 on tip relief; the law is that of
ref [43], Dwyer-Joyce, Reddyhoff & Zhu 2011).  What that paper says about
them (its abstract, J. Tribol. 133 (3) 031501, and the White Rose eprint
43103): "the liquid film stiffness was calculated by using a predicted film
thickness and a bulk modulus estimated from published rheological models of
lubricants under high pressure" -- B0, B0' are not measured there but taken
from the high-pressure rheology literature, i.e. the Tait parameters K0, K0'
of the lubricant.  Its table of constants could not be read here (only the
abstract and reference list are in the corpora searched; queries listed in
docs/ehl.md), so the defaults are the literature values of that kind:

* B0 = rho c^2 = 870 kg/m^3 x (1450 m/s)^2 = 1.83 GPa, the ambient bulk
  modulus of a mineral oil (the isentropic one, as ultrasound sees it; the
  isothermal one is lower by the factor Cp/Cv);
* B0' = 11, the typical Tait K0' of liquid lubricants (Bair, *High Pressure
  Rheology for Quantitative Elastohydrodynamics*, Elsevier 2007).

Checked (tests/unit/ehl/test_lubricant_laws.py): the equation of state whose tangent
modulus eq 9 is (:func:`~gearfmu.ehl.lubricant.tait_density_ratio`) with
these defaults stays within 1.7 % of the Dowson-Higginson density (Zhao et al. 2022
eq 6, Dowson & Higginson 1966) from 0 to 2 GPa, and D-H's own ambient
modulus 0.59 GPa/0.34 = 1.74 GPa is 5 % below B0; B0' = 5 would leave that
band.  Both remain parameters.

Contact patch of one slice (a choice, Zhao et al. 2022 does not define A and h_l):
A = 2 b * width (the Hertz contact band |x| <= b), p_m and h_l the means of
p and h over |x| <= b.  ``method="local"`` instead sums springs in parallel,
k = width * integral_{|x|<=b} B(p(x)) / h(x) dx.
"""
from __future__ import annotations

import math

import numpy as np

from .errors import EHLInputError

from .lubricant import B0_DEFAULT_PA, B0_PRIME_DEFAULT, bulk_modulus_Pa  # noqa: F401  (eq 9)


def film_stiffness_N_per_m(area_m2: float, h_m: float, p_mean_Pa: float,
                           B0_Pa: float = B0_DEFAULT_PA,
                           B0_prime: float = B0_PRIME_DEFAULT) -> float:
    """k_l = A B_l(p_m) / h_l (N/m), Zhao et al. 2022 eq 8."""
    if not (math.isfinite(area_m2) and area_m2 > 0):
        raise EHLInputError(f"area_m2={area_m2!r}: must be finite and > 0")
    if not (math.isfinite(h_m) and h_m > 0):
        raise EHLInputError(f"h_m={h_m!r}: the film thickness must be finite and > 0")
    return float(area_m2 * bulk_modulus_Pa(p_mean_Pa, B0_Pa, B0_prime) / h_m)


def slice_film_stiffness_N_per_m(result, width_m: float, method: str = "seed",
                                 B0_Pa: float = B0_DEFAULT_PA,
                                 B0_prime: float = B0_PRIME_DEFAULT) -> float:
    """Film stiffness (N/m) of one face-width slice of width ``width_m`` (m)
    from a :class:`~gearfmu.ehl.LineContactResult` (see module doc for A, p_m, h)."""
    if not (math.isfinite(width_m) and width_m > 0):
        raise EHLInputError(f"width_m={width_m!r}: must be finite and > 0")
    x, p, h, b = result.x_m, result.p_Pa, result.h_m, result.b_m
    band = np.abs(x) <= b
    if band.sum() < 3:
        raise EHLInputError("the grid has fewer than 3 nodes in the Hertz band |x| <= b")
    if np.any(h[band] <= 0):
        raise EHLInputError("film thickness <= 0 in the contact band")
    if method == "seed":
        return film_stiffness_N_per_m(2.0 * b * width_m, float(np.mean(h[band])),
                                      float(np.mean(p[band])), B0_Pa, B0_prime)
    if method == "local":
        dx = x[1] - x[0]
        return float(width_m * dx * np.sum(bulk_modulus_Pa(p[band], B0_Pa, B0_prime) / h[band]))
    raise EHLInputError(f"method={method!r}: must be 'seed' or 'local'")


def total_film_stiffness_N_per_m(slice_stiffnesses_N_per_m) -> float:
    """K_l = sum of the slice stiffnesses (N/m), Zhao et al. 2022 eq 10 (slices in parallel)."""
    k = np.asarray(slice_stiffnesses_N_per_m, dtype=float)
    if k.ndim != 1 or k.size == 0 or not np.all(np.isfinite(k)) or np.any(k < 0):
        raise EHLInputError("slice_stiffnesses_N_per_m: need a non-empty 1-D array of finite values >= 0")
    return float(k.sum())
