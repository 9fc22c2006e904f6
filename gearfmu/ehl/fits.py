"""Closed-form film-thickness fits for smooth line contacts (references for tests).

All take Moes / Hamrock-Dowson dimensionless groups (mean entrainment speed,
reduced modulus E' = 2/((1-nu1^2)/E1 + (1-nu2^2)/E2), reduced radius R):
W = w/(E'R), U = eta0 u_m/(E'R), G = alpha E', M = W (2U)^(-1/2),
L = G (2U)^(1/4).
"""
from __future__ import annotations

import math

from .errors import EHLInputError


def _pos(name, v, zero=False):
    v = float(v)
    if not math.isfinite(v) or v < 0 or (v == 0 and not zero):
        raise EHLInputError(f"{name} must be finite and {'>=' if zero else '>'} 0, got {v!r}")
    return v


def moes_central_film(M: float, L: float) -> float:
    """Moes' (1992) central film thickness H_c = (h_c/R)(2U)^(-1/2), dimensionless.

    Moes, H., "Optimum similarity analysis with applications to
    elastohydrodynamic lubrication", Wear 159 (1992) 57-66; the form quoted by
    Venner & Lubrecht (2000):
    H_RI = 3/M, H_EI = 2.621 M^(-1/5), H_RP = 1.287 L^(2/3),
    H_EP = 1.311 M^(-1/8) L^(3/4), s = (7 + 8 exp(-2 H_EI/H_RI))/5,
    H_c = [(H_RI^(7/3) + H_EI^(7/3))^(3s/7) + (H_RP^(-7/2) + H_EP^(-7/2))^(-2s/7)]^(1/s).
    """
    M = _pos("M", M)
    L = _pos("L", L, zero=True)
    h_ri = 3.0 / M
    h_ei = 2.621 * M ** (-0.2)
    s = (7.0 + 8.0 * math.exp(-2.0 * h_ei / h_ri)) / 5.0
    term1 = (h_ri ** (7.0 / 3.0) + h_ei ** (7.0 / 3.0)) ** (3.0 * s / 7.0)
    if L > 0.0:
        h_rp = 1.287 * L ** (2.0 / 3.0)
        h_ep = 1.311 * M ** (-1.0 / 8.0) * L ** 0.75
        term2 = (h_rp ** (-3.5) + h_ep ** (-3.5)) ** (-2.0 * s / 7.0)
    else:
        term2 = 0.0
    return (term1 + term2) ** (1.0 / s)


def martin_rigid_isoviscous(xi_in: float = -math.inf):
    """Rigid cylinder on a plane, isoviscous lubricant, Reynolds (Swift-Stieber) outlet condition:
    the load coefficient c = h0 w / (eta0 u_m R) and the outlet position xi_out, xi = x/sqrt(2 R h0).

    Martin, H.M., "Lubrication of gear teeth", Engineering 102 (1916) 119-121; with the Reynolds
    outlet condition p = dp/dx = 0 (Hamrock, Schmid & Jacobson, *Fundamentals of Fluid Film
    Lubrication*, 2004, ch. 8 and 19: h_min/R = 4.9 U/W, U on the mean speed u_m).  With
    x = sqrt(2 R h0) tan(g), h = h0 sec^2(g), the Reynolds equation h^3 p' = 12 eta0 u_m (h - h*)
    integrates in closed form: the outlet angle g* solves
    F(g*) - F(g_in) = 0, F(g) = g/2 + sin(2g)/4 - k (3g/8 + sin(2g)/4 + sin(4g)/32), k = sec^2(g*),
    and the load is w = 24 (eta0 u_m R / h0) I with
    I = [sin^2(g)/2 + k cos^4(g)/4] at g_in minus the same at g* (by parts, p(g_in) = p(g*) = 0).
    ``xi_in``: the inlet (pressure zero) in units of sqrt(2 R h0); -inf is Martin's fully flooded
    case, c = 6 cos^2(g*) = 4.8950, xi_out = 0.4751.  The central film in Moes' scaling is then
    H = (h0/R)(2U)^(-1/2) = c / (2 M) (Moes' fit has 3/M as its rigid-isoviscous asymptote).
    """
    xi_in = float(xi_in)
    if math.isnan(xi_in) or xi_in >= -1.0:
        raise EHLInputError(f"xi_in must be < -1 (upstream of the gap minimum), got {xi_in!r}")
    g_in = -0.5 * math.pi if math.isinf(xi_in) else math.atan(xi_in)

    def F(g, k):
        return 0.5 * g + 0.25 * math.sin(2 * g) - k * (0.375 * g + 0.25 * math.sin(2 * g)
                                                       + math.sin(4 * g) / 32.0)

    def gap(gs):   # flow balance between the inlet and the outlet angle gs
        k = 1.0 / math.cos(gs) ** 2
        return F(gs, k) - F(g_in, k)

    lo, hi = 1e-9, 0.5 * math.pi - 1e-9   # gap > 0 at lo (pressure still rising), < 0 at hi
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if gap(mid) > 0.0:
            lo = mid
        else:
            hi = mid
    gs = 0.5 * (lo + hi)
    k = 1.0 / math.cos(gs) ** 2
    I = (0.5 * math.sin(g_in) ** 2 + 0.25 * k * math.cos(g_in) ** 4
         - 0.5 * math.sin(gs) ** 2 - 0.25 * k * math.cos(gs) ** 4)
    return 24.0 * I, math.tan(gs)


def dowson_higginson_min_film(W: float, U: float, G: float) -> float:
    """Dowson & Higginson minimum film h_min/R = 2.65 U^0.70 G^0.54 W^-0.13.

    Dowson, D. & Higginson, G.R., *Elasto-hydrodynamic Lubrication*, Pergamon
    1966/1977 (U on the mean speed).  Fitted to early numerical solutions for
    moderate loads of steel/mineral-oil contacts (roughly G ~ 2500-5000 and
    W ~ 1e-5..1e-4); expect 10-20 % against modern solutions.
    """
    return 2.65 * _pos("U", U) ** 0.70 * _pos("G", G) ** 0.54 * _pos("W", W) ** -0.13


def dowson_toyoda_central_film(W: float, U: float, G: float) -> float:
    """Dowson & Toyoda (1979) central film h_c/R = 3.06 U^0.69 G^0.56 W^-0.10."""
    return 3.06 * _pos("U", U) ** 0.69 * _pos("G", G) ** 0.56 * _pos("W", W) ** -0.10


def pan_hamrock_films(W: float, U: float, G: float):
    """Pan & Hamrock (1989) line-contact fits, returns (h_min/R, h_c/R).

    Pan, P. & Hamrock, B.J., "Simple formulas for performance parameters used
    in elastohydrodynamically lubricated line contacts", J. Tribol. 111 (1989)
    246-251: H_min = 1.714 W^-0.128 U^0.694 G^0.568,
    H_c = 2.922 W^-0.166 U^0.692 G^0.470.
    """
    W, U, G = _pos("W", W), _pos("U", U), _pos("G", G)
    return (1.714 * W ** -0.128 * U ** 0.694 * G ** 0.568,
            2.922 * W ** -0.166 * U ** 0.692 * G ** 0.470)


def moes_parameters(W: float, U: float, G: float):
    """(M, L) from (W, U, G) with U on the mean speed (Moes 1992)."""
    W, U, G = _pos("W", W), _pos("U", U), _pos("G", G, zero=True)
    return W * (2 * U) ** -0.5, G * (2 * U) ** 0.25
