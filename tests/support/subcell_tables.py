"""Synthetic tooth pairs whose stiffness is a closed form over their engagement, with contact-zone
edges between table nodes (tests/unit/dynamics/test_subcell.py, test_rk4_seg.py; docs/model.md
"Contact-zone edges")."""
import math

import numpy as np

from gearfmu.tables.synthetic import tables_from_arrays


Z1 = 25
T = 2.0 * math.pi / Z1       # mesh period (rad)


K0 = 4.0e8                   # N/m
A_LIN = 0.5                  # K(eps) = 1.5 K(0): the two edges' ramps do not cancel
C_PAR = 0.8
E_AMP = 2.0e-6               # m, meshing error amplitude
P = 2


def pair_stiffness(u, eps):
    """K(u) = k0 (1 + a u/eps + c u (eps - u)/eps^2) (N/m) at engagement u in [0, eps) mesh periods."""
    return K0 * (1.0 + A_LIN * u / eps + C_PAR * u * (eps - u) / eps ** 2)


def pair_error(u, eps):
    """The meshing error (m) at engagement u: a cosine, nonzero at both zone edges."""
    return E_AMP * math.cos(2.0 * math.pi * u / (1.3 * eps))  # nonzero at both edges: e jumps too


def zone_tables(ppm, eps, *, engagement=True, error=False):
    """P pairs with the closed-form K (and E with error=True) over their engagement, ppm table nodes per
    mesh period; engagement=True states the zone edges 0 and eps T."""
    n = P * ppm
    phi = np.arange(n) * (P * T) / n
    k = np.zeros((P, n))
    e = np.zeros((P, n))
    for m in range(P):
        u = ((phi - m * T) % (P * T)) / T
        on = u < eps
        k[m] = np.where(on, pair_stiffness(u, eps), 0.0)
        if error:
            e[m] = np.where(on, [pair_error(x, eps) for x in u], 0.0)
    kw = dict(engagement_in_rad=0.0, engagement_out_rad=eps * T) if engagement else {}
    return tables_from_arrays(phi_period_rad=P * T, mesh_period_rad=T, k_N_per_m=k, e_m=e, teeth_pinion=Z1, **kw)


def dyn_tables(two_rows):
    """zone_tables with errors at eps = 1 + 1/sqrt(3) (one torque row, or two with 1.3 k and 0.7 e)."""
    t = zone_tables(16, 1.0 + 1.0 / math.sqrt(3.0), error=True)
    if two_rows:
        import dataclasses
        t = dataclasses.replace(t, torque_Nm=np.array([20.0, 80.0]),
                                k_N_per_m=np.concatenate([t.k_N_per_m, 1.3 * t.k_N_per_m]),
                                e_m=np.concatenate([t.e_m, 0.7 * t.e_m]), e_comprehensive_m=None, static_te_m=None)
    return t.validate()
