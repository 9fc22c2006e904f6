"""The helical pair of seed 001 (Table 1) and ISO 6336-1's mean mesh stiffness, shared by the helical
geometry and contact tests (tests/unit/gear/test_helical.py, tests/unit/contact/test_helical_contact.py).

Reference: ISO 6336-1:2019 method B (clause 9): q' with the virtual tooth numbers
z_n = z/(cos^2 beta_b cos beta), c' = C_M C_R C_B cos(beta)/q', c_gamma_alpha = c'(0.75 eps_alpha + 0.25).
"""
import math
from pathlib import Path

from gearfmu.gear.gearpair import GearPairSpec, GearSpec, Material

ROOT = Path(__file__).resolve().parents[2]
SEED001 = ROOT / "examples" / "scenes" / "seed001_table1.toml"
STEEL = Material(206e9, 0.3)


def helical(beta_deg=36.0, b_m=0.060, z=(33, 28), mn=0.005, x=(0.0, 0.0), alpha_deg=20.0):
    """A steel helical pair (right-hand pinion, left-hand gear); the defaults are seed 001's Table 1 pair."""
    beta = math.radians(beta_deg)
    p = GearSpec(z[0], mn, math.radians(alpha_deg), b_m, profile_shift=x[0], material=STEEL,
                 helix_angle_rad=beta, helix_hand="right")
    g = GearSpec(z[1], mn, math.radians(alpha_deg), b_m, profile_shift=x[1], material=STEEL,
                 helix_angle_rad=beta, helix_hand="left")
    return GearPairSpec(p, g)


def iso_c_gamma_alpha(g, dedendum_coeff=1.25):
    """ISO 6336-1 method B c_gamma_alpha in N/(mm um) for x = 0 (ISO 6336-1:2019 clause 9), virtual z_n."""
    C = [0.04723, 0.15551, 0.25791]
    zf = math.cos(g.base_helix_angle_rad) ** 2 * math.cos(g.helix_angle_rad)
    q = C[0] + C[1] / (g.z1 / zf) + C[2] / (g.z2 / zf)
    cp = 0.8 * 1.0 * (1.0 + 0.5 * (1.2 - dedendum_coeff)) / q * math.cos(g.helix_angle_rad)
    return cp * (0.75 * g.contact_ratio + 0.25)
