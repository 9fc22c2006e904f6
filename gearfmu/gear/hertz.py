"""Hertzian (dry, smooth) line-contact stiffness of a tooth pair.

CHOICE: the load-independent formula of Yang & Sun (1985), "A rotary model
for spur gear dynamics", J. Mech. Trans. Autom. Des. 107: 529-535, used by
most potential-energy TVMS papers (e.g. Tian 2004; Chen & Shao 2011; seed
000 eq 13 with k_l = k_h for the Hertz case):

    k_h = pi E L / (4 (1 - nu^2))        (same material)

written for two materials with the reduced modulus
1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2 as k_h = pi E* L / 2, which reduces
to the line above when both materials are equal.  It is independent of the
load and of the contact position (the exact Hertz line-contact approach is
logarithmic in the load and depends on the body depth; Yang & Sun's value is
the linearised form those papers use).
"""
from __future__ import annotations

import math

from .gearpair import GearPairSpec


class ContactError(ValueError):
    """Bad input to the contact-stiffness formula (message names the argument)."""


def reduced_modulus_Pa(pair: GearPairSpec) -> float:
    """E* = 1 / ((1 - nu1^2)/E1 + (1 - nu2^2)/E2) in Pa."""
    m1, m2 = pair.pinion.material, pair.gear.material
    for name, m in (("pinion", m1), ("gear", m2)):
        if not (m.youngs_modulus_Pa > 0):
            raise ContactError(f"{name}.material.youngs_modulus_Pa: must be > 0")
        if not (-1.0 < m.poisson_ratio < 0.5):
            raise ContactError(f"{name}.material.poisson_ratio: must lie in (-1, 0.5)")
    return 1.0 / ((1 - m1.poisson_ratio ** 2) / m1.youngs_modulus_Pa
                  + (1 - m2.poisson_ratio ** 2) / m2.youngs_modulus_Pa)


def hertz_stiffness_N_per_m(pair: GearPairSpec, width_m: float) -> float:
    """Hertz contact stiffness k_h (N/m) of one tooth pair over a contact length ``width_m`` (m)."""
    if not (isinstance(width_m, (int, float)) and math.isfinite(width_m) and width_m > 0):
        raise ContactError(f"width_m: must be a finite positive length, got {width_m!r}")
    return math.pi * reduced_modulus_Pa(pair) * width_m / 2.0
