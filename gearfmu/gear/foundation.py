"""Fillet-foundation (gear body) compliance of Sainsot, Velex & Duverger (2004).

Sainsot P., Velex P., Duverger O., "Contribution of gear body to tooth
deflections - a new bidimensional analytical formula", J. Mech. Des. 126
(2004) 748-752; used as Zhao et al. 2022 eq (12):

    1/k_f = cos^2(alpha_m)/(E W) * { L* (u_f/S_f)^2 + M* (u_f/S_f) + P* (1 + Q* tan^2(alpha_m)) }

with each coefficient X* = A/theta_f^2 + B h_f^2 + C h_f/theta_f + D/theta_f + E h_f + F
(table below, Sainsot et al. 2004 Table 1), where

* h_f = r_f / r_int: root radius over bore (hub) radius;
* theta_f: half angle, seen from the gear centre, of the tooth root on the
  root circle (the arc between the two points where the fillets meet the
  root circle); S_f = 2 r_f theta_f is that arc length (root thickness);
* u_f: distance along the tooth centre line from the root circle to the
  point where the line of the load crosses the centre line; for an involute
  load tangent to the base circle that point lies at r_b / cos(alpha_m)
  from the gear centre, so u_f = r_b / cos(alpha_m) - r_f (CHOICE: measured
  from the root circle on the centre line, not from the root chord; the two
  differ by r_f (1 - cos theta_f), about 0.5 % of r_f);
* alpha_m: angle between the load and the normal to the tooth centre line
  (the alpha_1 of the potential-energy integrals, beta in Zhao et al. 2022 eq 12/15);
* W: face width of the slice.  E: Young's modulus (plane stress, as in the seed).
"""
from __future__ import annotations

import numpy as np

#: Sainsot et al. (2004) coefficients: rows L*, M*, P*, Q*; columns A..F
SAINSOT_COEFFICIENTS = np.array([
    [-5.574e-5, -1.9986e-3, -2.3015e-4, 4.7702e-3, 0.0271, 6.8045],   # L*
    [60.111e-5, 28.100e-3, -83.431e-4, -9.9256e-3, 0.1624, 0.9086],   # M*
    [-50.952e-5, 185.50e-3, 0.0538e-4, 53.300e-3, 0.2895, 0.9236],    # P*
    [-6.2042e-5, 9.0889e-3, -4.0964e-4, 7.8297e-3, -0.1472, 0.6904],  # Q*
])


class FoundationError(ValueError):
    """Bad input to the fillet-foundation formula (message names the argument)."""


def sainsot_coefficients(theta_f_rad: float, h_f: float) -> tuple:
    """(L*, M*, P*, Q*) of Sainsot et al. (2004) for theta_f (rad) and h_f = r_f/r_int (1)."""
    if not (theta_f_rad > 0):
        raise FoundationError(f"theta_f_rad: must be > 0, got {theta_f_rad!r}")
    if not (h_f > 1):
        raise FoundationError(f"h_f: r_f/r_int must exceed 1, got {h_f!r}")
    t = theta_f_rad
    basis = np.array([1.0 / t ** 2, h_f ** 2, h_f / t, 1.0 / t, h_f, 1.0])
    L, M, P, Q = SAINSOT_COEFFICIENTS @ basis
    return float(L), float(M), float(P), float(Q)


def sainsot_compliance_m_per_N(u_f_m, S_f_m: float, theta_f_rad: float, h_f: float,
                               alpha_m_rad, youngs_modulus_Pa: float, width_m: float):
    """Fillet-foundation compliance 1/k_f (m/N) of one tooth (Zhao et al. 2022 eq 12, Sainsot 2004).

    ``u_f_m`` and ``alpha_m_rad`` may be arrays (one value per load position).
    """
    if not (youngs_modulus_Pa > 0):
        raise FoundationError(f"youngs_modulus_Pa: must be > 0, got {youngs_modulus_Pa!r}")
    if not (width_m > 0):
        raise FoundationError(f"width_m: must be > 0, got {width_m!r}")
    if not (S_f_m > 0):
        raise FoundationError(f"S_f_m: must be > 0, got {S_f_m!r}")
    L, M, P, Q = sainsot_coefficients(theta_f_rad, h_f)
    u = np.asarray(u_f_m, dtype=float) / S_f_m
    am = np.asarray(alpha_m_rad, dtype=float)
    return (np.cos(am) ** 2 / (youngs_modulus_Pa * width_m)
            * (L * u ** 2 + M * u + P * (1.0 + Q * np.tan(am) ** 2)))
