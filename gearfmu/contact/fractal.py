"""Fractal mixed-lubrication normal contact stiffness (Xu, Shi & Fan 2023).

Rebuilt equations with their sources: docs/fractal_contact.md.  In short:

* Asperity size distribution (Majumdar & Bhushan 1991, J. Tribol. 113, 1-11;
  Xu, Shi & Fan 2023 eq 15 with the correction coefficient lambda_c as a factor):
  n(a) = lambda_c (D/2) a_l^(D/2) a^-(D+2)/2, 0 < a <= a_l.
* One asperity of size a (MB 1991): interference delta(a) = G^(D-1) a^((2-D)/2),
  tip radius R(a) = a^(D/2) / (pi G^(D-1)) so that a = pi R delta (Hertz);
  elastic load (4/(3 sqrt pi)) E G^(D-1) a^((3-D)/2) (Xu, Shi & Fan 2023 below eq 7).
* Yield onset at the mean pressure p_c = 1.1 k_mu Y (Xu, Shi & Fan 2023 above eq 10),
  k_mu = 1 - 0.228 mu (mu <= 0.3); critical area
  a_c = [4 E G^(D-1) / (3.3 sqrt(pi) k_mu Y)]^(2/(D-1))   (Xu, Shi & Fan 2023 eq 10),
  omega = delta/delta_c = (a_c/a)^(D-1), a_epc = 6^(1/(1-D)) a_c,
  a_pc = 110^(1/(1-D)) a_c (Xu, Shi & Fan 2023 below eq 13).
* Elastic / first / second elastic-plastic / fully plastic stages: Hertz for
  omega <= 1; Kogut & Etsion (2002, J. Appl. Mech. 69, 657-662) FE fits
  P/Pc = 1.03 w^1.425, A/Ac = 0.93 w^1.136 (1 < w <= 6) and
  P/Pc = 1.40 w^1.263, A/Ac = 0.94 w^1.146 (6 < w <= 110), Pc = p_c Ac,
  Ac = pi R delta_c; fully plastic A = 2 pi R delta, P = H A.  Asperity
  stiffness k = dP/d(delta) at fixed R; fully plastic asperities add no
  stiffness (Xu, Shi & Fan 2023 eq 23 has no plastic term).
* Lateral (shoulder-to-shoulder) contact, Xu, Shi & Fan 2023 eq 1-3 after Sepehri &
  Farhang (2008): class i with s_i = 1 + r_a^2/R^2, cos(alpha_i) = s_i^-1/2,
  radius at the contact point R_y = R s^(3/2), interference along the contact
  normal delta_a = delta s^-1/2; normal load P_n = P_a cos(alpha) and normal
  stiffness k_n = k_a cos^2(alpha) (Xu, Shi & Fan 2023 eq 24-25); class weights
  A_i/A_r as in Xu, Shi & Fan 2023 section 3.3 (uniform or Gaussian, after Zhang et al. 2019).
* Asperity interaction (Xu, Shi & Fan 2023 eq 4 after Ciavarella, Greenwood & Paggi
  2008): the pressure of the neighbouring asperities lowers the base of each
  asperity by delta_int = 2 p_nom r (1/sqrt(A*) - 1) / E (half-space under the
  nominal pressure over the annulus r < rho < r/sqrt(A*), A* = A_r/A_0).  It
  acts in series with the asperity: K_s = K_asp / (1 + K_asp C_int),
  C_int = d delta_int/dP stiffness-weighted over the asperities (our choice,
  docs/fractal_contact.md).
* Solid part K_s in parallel with the oil-film part
  K_l = B(p) (A_0 - A_r) / h (Zhao et al. 2022 eq 8-9 on the non-contact area,
  Xu, Shi & Fan 2023 eq 26 after Xue et al. 2022): K_n = K_s + K_l.
* Contact-surface correction coefficient lambda_c for curved flanks: the
  seed's formula (eq 19) is dimensionally inconsistent as published; we
  rebuild it from its stated meaning and limits (contact_correction_coefficient).
* Nominal area: the MB model ties the largest spot a_l to the real
  area, so at equal nominal pressure A_r/A0 grows with A0 (P ~ A_r^((3-D)/2)):
  a result on the whole slice depends on the slice width.  The mesh evaluates
  one reference element of the W-M sample size L_s x L_s (the surface's longest
  wavelength; Yan & Komvopoulos 1998 define the 3-D W-M surface on an L x L
  sample) under the nominal pressure and scales load, area and stiffness by
  A0/L_s^2 (solid_contact_extensive), so K per unit face width does not depend
  on the slicing.  A_r >= A0 (complete contact) raises FullContactError.
* Film parameter: one definition, Lambda = h_min / sqrt(sigma1^2 + sigma2^2)
  (Tallian 1967; Johnson 1985; ISO/TR 15144-1), h_min Dowson & Higginson, sigma_i
  the W-M RMS of each flank (film_parameter; equal to gearfmu.contact.models').

All quantities SI.  Areas in m^2; E is the composite (reduced) modulus as in
the seed ("composite Young's modulus of the contact material").
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional, Tuple

import numpy as np

from ..common.checks import finite_number
from ..ehl.lubricant import B0_DEFAULT_PA, B0_PRIME_DEFAULT, bulk_modulus_Pa
from .roughness import wm_sigma_m
from ..ehl.fits import dowson_higginson_min_film, pan_hamrock_films

__all__ = [
    "FractalInputError", "FractalSurface", "FractalMaterial", "LateralContact",
    "POSITIVE_CONTACT", "UNIFORM_LATERAL", "GAUSSIAN_LATERAL", "FractalOptions",
    "FractalContactResult", "SEED001_FULL", "friction_factor", "critical_area_m2", "stage_areas_m2",
    "asperity_response", "solid_contact", "solid_contact_at_load", "oil_film_stiffness_N_per_m",
    "normal_contact_stiffness", "contact_correction_coefficient", "hertz_half_width_m",
    "line_contact_gap_m", "brinell_to_hardness_Pa", "dimensionless",
    "KE_STAGE1", "KE_STAGE2", "K_HY_DEFAULT", "film_regime", "FractalMeshOptions",
    "slice_contact_stiffness", "FULL_FILM_LAMBDA", "BOUNDARY_LAMBDA",
    "FullContactError", "solid_contact_extensive", "composite_sigma_m", "film_parameter",
]

#: Kogut & Etsion (2002) FE fits (load coefficient, load exponent, area coefficient, area exponent)
KE_STAGE1 = (1.03, 1.425, 0.93, 1.136)   # 1 < omega <= 6
KE_STAGE2 = (1.40, 1.263, 0.94, 1.146)   # 6 < omega <= 110
#: H = K Y (Tabor; MB 1991 and Xu, Shi & Fan 2023 use K ~ 2.8)
K_HY_DEFAULT = 2.8
_OMEGA_EP1 = 6.0
_OMEGA_P = 110.0
_GL_X, _GL_W = np.polynomial.legendre.leggauss(48)


class FractalInputError(ValueError):
    """Bad input to the fractal contact model; the message names the field and the reason."""


class FullContactError(FractalInputError):
    """The asperities would need a real contact area A_r >= A0 to carry the load: complete
    contact, outside the fractal (isolated-asperity) model.  ``max_load_N`` is the load the
    asperities carry at A_r = A0, ``load_N`` the requested one."""

    def __init__(self, message: str, load_N: float = math.nan, max_load_N: float = math.nan):
        super().__init__(message)
        self.load_N = load_N
        self.max_load_N = max_load_N


def _pos(name: str, v, allow_zero: bool = False) -> float:
    return finite_number(name, v, positive=not allow_zero, nonneg=allow_zero, error=FractalInputError)


@dataclass(frozen=True)
class FractalSurface:
    """W-M fractal parameters of the composite surface: ``D`` in (1, 2), ``G_m`` (m)."""

    D: float
    G_m: float

    def __post_init__(self):
        if not (isinstance(self.D, (int, float)) and 1.0 < float(self.D) < 2.0):
            raise FractalInputError(f"D={self.D!r}: the fractal dimension must lie in (1, 2)")
        _pos("G_m", self.G_m)


@dataclass(frozen=True)
class FractalMaterial:
    """Composite modulus ``E_Pa`` (Pa), hardness ``H_Pa`` (Pa) of the softer body,
    ``K_HY`` = H/Y (1), asperity friction coefficient ``friction`` (1, 0..0.9)."""

    E_Pa: float
    H_Pa: float
    K_HY: float = K_HY_DEFAULT
    friction: float = 0.0

    def __post_init__(self):
        _pos("E_Pa", self.E_Pa)
        _pos("H_Pa", self.H_Pa)
        _pos("K_HY", self.K_HY)
        f = _pos("friction", self.friction, allow_zero=True)
        if f > 0.9:
            raise FractalInputError(f"friction={f!r}: the k_mu law covers 0 <= mu <= 0.9")

    @property
    def Y_Pa(self) -> float:
        """Yield strength Y = H/K (Pa)."""
        return self.H_Pa / self.K_HY

    @property
    def p_c_Pa(self) -> float:
        """Mean contact pressure at yield inception, 1.1 k_mu Y (Pa)."""
        return 1.1 * friction_factor(self.friction) * self.Y_Pa


@dataclass(frozen=True)
class LateralContact:
    """Lateral-contact classes: ``s`` = 1 + r_a^2/R^2 per class, ``weights`` = A_i/A_r (sum 1)."""

    s: Tuple[float, ...]
    weights: Tuple[float, ...]

    def __post_init__(self):
        s = np.asarray(self.s, float)
        w = np.asarray(self.weights, float)
        if s.ndim != 1 or s.size == 0 or s.shape != w.shape:
            raise FractalInputError("LateralContact: s and weights need the same non-zero length")
        if not np.all(np.isfinite(s)) or np.any(s < 1.0):
            raise FractalInputError("LateralContact.s: each 1 + r_a^2/R^2 must be finite and >= 1")
        if not np.all(np.isfinite(w)) or np.any(w < 0) or abs(w.sum() - 1.0) > 1e-6:
            raise FractalInputError(f"LateralContact.weights: must be >= 0 and sum to 1 (sum {w.sum():.6g})")


#: positive (peak-to-peak) contact only: the classical fractal model
POSITIVE_CONTACT = LateralContact((1.0,), (1.0,))
#: Xu, Shi & Fan 2023 section 3.3: s = 1.0 ... 1.9, A_i/A_r = 0.1 each
UNIFORM_LATERAL = LateralContact(tuple(1.0 + 0.1 * i for i in range(10)), (0.1,) * 10)
#: Xu, Shi & Fan 2023 section 3.3: Gaussian weights (as printed; they sum to 1.0)
GAUSSIAN_LATERAL = LateralContact(tuple(1.0 + 0.1 * i for i in range(10)),
                                  (0.2, 0.18, 0.16, 0.14, 0.1, 0.08, 0.06, 0.035, 0.025, 0.02))


@dataclass(frozen=True)
class FractalOptions:
    """Model switches: lateral-contact classes, asperity interaction, lambda_c (1)."""

    lateral: LateralContact = POSITIVE_CONTACT
    interaction: bool = False
    lambda_c: float = 1.0

    def __post_init__(self):
        lc = _pos("lambda_c", self.lambda_c)
        if lc > 1.0:
            raise FractalInputError(f"lambda_c={lc!r}: the correction coefficient must lie in (0, 1]")
        if not isinstance(self.lateral, LateralContact):
            raise FractalInputError("lateral: must be a LateralContact")


#: Xu, Shi & Fan 2023 full model (lateral contact with Gaussian weights, interaction)
SEED001_FULL = FractalOptions(lateral=GAUSSIAN_LATERAL, interaction=True)


@dataclass(frozen=True)
class FractalContactResult:
    """Solid-part contact state of one nominal area ``A0_m2``.

    ``load_N`` normal load carried by the asperities, ``real_area_m2`` A_r,
    ``stiffness_N_per_m`` K_s (with interaction when switched on),
    ``asperity_stiffness_N_per_m`` sum of asperity stiffnesses (no interaction),
    ``a_l_m2`` largest asperity size, ``stage_load_N`` / ``stage_stiffness_N_per_m``
    (elastic, elastic-plastic 1, elastic-plastic 2, plastic), ``a_c_m2`` critical area
    of positive contact."""

    load_N: float
    real_area_m2: float
    stiffness_N_per_m: float
    asperity_stiffness_N_per_m: float
    a_l_m2: float
    A0_m2: float
    a_c_m2: float
    stage_load_N: Tuple[float, float, float, float]
    stage_stiffness_N_per_m: Tuple[float, float, float, float]
    stage_area_m2: Tuple[float, float, float, float]


def brinell_to_hardness_Pa(HB: float) -> float:
    """Brinell number (kgf/mm^2) to hardness in Pa: HB * 9.80665e6 (definition of HB)."""
    return _pos("HB", HB) * 9.80665e6


def friction_factor(mu: float) -> float:
    """Friction correction k_mu of the yield inception pressure (Xu, Shi & Fan 2023 above eq 10,
    after Liu et al. 2015 / Chang, Etsion & Bogy): 1 - 0.228 mu (mu <= 0.3),
    0.932 exp(-1.58 (mu - 0.3)) (0.3 < mu <= 0.9)."""
    mu = _pos("friction", mu, allow_zero=True)
    if mu <= 0.3:
        return 1.0 - 0.228 * mu
    if mu <= 0.9:
        return 0.932 * math.exp(-1.58 * (mu - 0.3))
    raise FractalInputError(f"friction={mu!r}: the k_mu law covers 0 <= mu <= 0.9")


def critical_area_m2(surface: FractalSurface, material: FractalMaterial) -> float:
    """Critical (yield inception) size a_c (m^2) of positive contact, Xu, Shi & Fan 2023 eq 10:
    a_c = [4 E G^(D-1) / (3 sqrt(pi) p_c)]^(2/(D-1)), p_c = 1.1 k_mu Y."""
    D, G = surface.D, surface.G_m
    return (4.0 * material.E_Pa * G ** (D - 1.0)
            / (3.0 * math.sqrt(math.pi) * material.p_c_Pa)) ** (2.0 / (D - 1.0))


def stage_areas_m2(surface: FractalSurface, material: FractalMaterial, s: float = 1.0):
    """(a_c, a_epc, a_pc) (m^2) of the lateral class ``s``: omega_a = (a_c/a)^(D-1)/s^2
    reaches 1, 6, 110 (s = 1: Xu, Shi & Fan 2023 below eq 13)."""
    D = surface.D
    ac = critical_area_m2(surface, material)
    return tuple(ac * (s * s * w) ** (-1.0 / (D - 1.0)) for w in (1.0, _OMEGA_EP1, _OMEGA_P))


def asperity_response(rho_m, w_m, E_Pa: float, p_c_Pa: float, H_Pa: float):
    """Sphere of radius ``rho_m`` on a flat at interference ``w_m`` (arrays, m):
    returns (load N, contact area m^2, stiffness dP/dw N/m, stage 0..3).

    Stage 0 Hertz (omega <= 1), 1 and 2 Kogut & Etsion (2002) fits, 3 fully
    plastic (A = 2 pi rho w, P = H A, stiffness 0 as in Xu, Shi & Fan 2023 eq 23).
    delta_c = beta rho with beta = (3 pi p_c / (4 E))^2 (Hertz mean pressure = p_c)."""
    rho = np.asarray(rho_m, float)
    w = np.asarray(w_m, float)
    beta = (3.0 * math.pi * p_c_Pa / (4.0 * E_Pa)) ** 2
    dc = beta * rho
    om = np.where(dc > 0, w / np.where(dc > 0, dc, 1.0), 0.0)
    Ac = math.pi * rho * dc
    Pc = p_c_Pa * Ac
    P = np.zeros_like(w)
    A = np.zeros_like(w)
    k = np.zeros_like(w)
    st = np.full(w.shape, -1, dtype=int)
    c0 = (w > 0) & (om <= 1.0)
    P = np.where(c0, 4.0 / 3.0 * E_Pa * np.sqrt(rho * np.maximum(w, 0)) * np.maximum(w, 0), P)
    A = np.where(c0, math.pi * rho * w, A)
    k = np.where(c0, 2.0 * E_Pa * np.sqrt(rho * np.maximum(w, 0)), k)
    st = np.where(c0, 0, st)
    for code, (lo, hi), (cp, ep, ca, ea) in ((1, (1.0, _OMEGA_EP1), KE_STAGE1),
                                             (2, (_OMEGA_EP1, _OMEGA_P), KE_STAGE2)):
        c = (om > lo) & (om <= hi)
        omc = np.where(c, om, 1.0)
        P = np.where(c, cp * Pc * omc ** ep, P)
        A = np.where(c, ca * Ac * omc ** ea, A)
        k = np.where(c, cp * ep * (Pc / np.where(dc > 0, dc, 1.0)) * omc ** (ep - 1.0), k)
        st = np.where(c, code, st)
    c3 = om > _OMEGA_P
    A = np.where(c3, 2.0 * math.pi * rho * w, A)
    P = np.where(c3, H_Pa * 2.0 * math.pi * rho * w, P)
    k = np.where(c3, 0.0, k)
    st = np.where(c3, 3, st)
    return P, A, k, st


def _segments(edges, a_l):
    """Clip ascending stage edges [0, a_pc, a_epc, a_c, inf] to (0, a_l]."""
    out = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        lo2, hi2 = min(lo, a_l), min(hi, a_l)
        out.append((lo2, hi2) if hi2 > lo2 else None)
    return out


def _nodes(lo, hi, D):
    """Quadrature nodes a and weights for integral_lo^hi f(a) n(a) da / (lambda_c (D/2) a_l^(D/2)).

    lo = 0 (plastic range): a = hi t^(2/(2-D)) makes a^(-D/2) da smooth in t ... we
    fold n(a) into the weights.  lo > 0: Gauss-Legendre in ln a."""
    if lo == 0.0:
        m = 2.0 / (2.0 - D)
        t = 0.5 * (_GL_X + 1.0)
        a = hi * t ** m
        # n(a) da / c = a^(-(D+2)/2) * hi m t^(m-1) dt
        wts = 0.5 * _GL_W * a ** (-(D + 2.0) / 2.0) * hi * m * t ** (m - 1.0)
        return a, wts
    u0, u1 = math.log(lo), math.log(hi)
    u = 0.5 * (u1 - u0) * _GL_X + 0.5 * (u1 + u0)
    a = np.exp(u)
    wts = 0.5 * (u1 - u0) * _GL_W * a * a ** (-(D + 2.0) / 2.0)
    return a, wts


def solid_contact(surface: FractalSurface, material: FractalMaterial, a_l_m2: float, A0_m2: float,
                  options: FractalOptions = FractalOptions()) -> FractalContactResult:
    """Solid part of the contact for a largest asperity size ``a_l_m2`` (m^2) on the
    nominal area ``A0_m2`` (m^2): load, real area and K_s (Xu, Shi & Fan 2023 eq 16-25)."""
    a_l = _pos("a_l_m2", a_l_m2)
    A0 = _pos("A0_m2", A0_m2)
    D, G, E = surface.D, surface.G_m, material.E_Pa
    pc, H = material.p_c_Pa, material.H_Pa
    lam = options.lambda_c
    cn = lam * 0.5 * D * a_l ** (D / 2.0)
    a_all, q_all, s_all = [], [], []
    for s, wgt in zip(options.lateral.s, options.lateral.weights):
        if wgt == 0.0:
            continue
        ac, aepc, apc = stage_areas_m2(surface, material, s)
        for seg in _segments([0.0, apc, aepc, ac, math.inf], a_l):
            if seg is None:
                continue
            a, q = _nodes(seg[0], seg[1], D)
            a_all.append(a)
            q_all.append(q * (wgt * cn))
            s_all.append(np.full(a.shape, float(s)))
    a = np.concatenate(a_all)
    q = np.concatenate(q_all)
    s = np.concatenate(s_all)
    cosa = s ** -0.5
    delta = G ** (D - 1.0) * a ** ((2.0 - D) / 2.0)
    R = a ** (D / 2.0) / (math.pi * G ** (D - 1.0))
    P, A, k, st = asperity_response(R * s ** 1.5, delta * cosa, E, pc, H)
    Pn, kn = P * cosa, k * cosa * cosa
    P_st = np.array([float(np.sum((q * Pn)[st == j])) for j in range(4)])
    K_st = np.array([float(np.sum((q * kn)[st == j])) for j in range(4)])
    A_st = np.array([float(np.sum((q * A)[st == j])) for j in range(4)])
    sqrt_a_k = float(np.sum(q * kn * np.sqrt(a / math.pi)))
    P_tot, K_asp, A_r = float(P_st.sum()), float(K_st.sum()), float(A_st.sum())
    K = K_asp
    if options.interaction and K_asp > 0:
        A_star = min(A_r / A0, 1.0)
        # d delta_int / dP for an asperity of radius r: 2 r (1/sqrt(A*) - 1) / (E A0);
        # stiffness-weighted mean over the asperities
        C = 2.0 * (1.0 / math.sqrt(A_star) - 1.0) / (E * A0) * (sqrt_a_k / K_asp)
        K = K_asp / (1.0 + K_asp * C)
    return FractalContactResult(P_tot, A_r, K, K_asp, a_l, A0, critical_area_m2(surface, material),
                                tuple(P_st), tuple(K_st), tuple(A_st))


def _full_area_log_a_l(surface, material, A0, options) -> float:
    """ln a_l at which the real area A_r of :func:`solid_contact` reaches the nominal area A0."""
    D = surface.D

    def g(u):
        return math.log(solid_contact(surface, material, math.exp(u), A0, options).real_area_m2 / A0)

    # elastic-only estimate A_r = lambda_c D/(2-D) a_l (MB 1991), then bracket (A_r grows with a_l)
    u0 = math.log(A0 * (2.0 - D) / (D * options.lambda_c))
    lo, hi = u0 - 2.0, u0 + 2.0
    while g(lo) > 0:
        lo -= 4.0
    while g(hi) < 0:
        hi += 4.0
    from scipy.optimize import brentq  # scipy.optimize: heavy import, only when a fractal contact is solved
    return brentq(g, lo, hi, xtol=1e-12, rtol=1e-12)


def solid_contact_at_load(surface: FractalSurface, material: FractalMaterial, load_N: float,
                          A0_m2: float, options: FractalOptions = FractalOptions()) -> FractalContactResult:
    """:func:`solid_contact` with a_l found so that the asperities carry ``load_N`` (N).

    The real contact area must stay below the nominal one: if the asperities of ``A0_m2``
    carry less than ``load_N`` at A_r = A0 (complete contact, outside the isolated-asperity
    model), :class:`FullContactError` is raised (it is a :class:`FractalInputError`)."""
    P = _pos("load_N", load_N)
    A0 = _pos("A0_m2", A0_m2)

    def f(u):
        return math.log(solid_contact(surface, material, math.exp(u), A0, options).load_N) - math.log(P)

    def full_contact():
        u_full = _full_area_log_a_l(surface, material, A0, options)
        P_max = solid_contact(surface, material, math.exp(u_full), A0, options).load_N
        return FullContactError(
            f"load_N={P!r}: the asperities of A0_m2={A0!r} carry at most {P_max:.6g} N before the real "
            f"contact area reaches the nominal area (real_area_ratio A_r/A0 >= 1: complete contact, "
            f"outside the fractal model)", P, P_max)

    # a_l bracket up to A_r ~ 2 A0 (elastic estimate A_r = lambda_c D/(2-D) a_l); the answer is
    # accepted only below A_r = A0 (A_r grows with a_l, so the load at A_r = A0 is the limit)
    hi = math.log(2.0 * A0 * (2.0 - surface.D) / (surface.D * options.lambda_c))
    if f(hi) < 0:
        raise full_contact()
    lo = hi - 10.0
    while f(lo) > 0:
        lo -= 10.0
        if lo < hi - 400:
            raise FractalInputError(f"load_N={P!r}: too small to resolve")
    from scipy.optimize import brentq  # scipy.optimize: heavy import, only when a fractal contact is solved
    u = brentq(f, lo, hi, xtol=1e-12, rtol=1e-12)
    r = solid_contact(surface, material, math.exp(u), A0, options)
    if r.real_area_m2 >= A0:
        raise full_contact()
    return r


def solid_contact_extensive(surface: FractalSurface, material: FractalMaterial, pressure_Pa: float,
                            A0_m2: float, element_m2: float,
                            options: FractalOptions = FractalOptions()) -> FractalContactResult:
    """Solid contact of the nominal area ``A0_m2`` under the nominal pressure ``pressure_Pa``,
    evaluated on one reference element of area ``element_m2`` and scaled extensively:
    load, real area and stiffness (all stages) = N x the element's, N = A0/element.

    Why: the MB (1991) model ties the largest spot a_l to the real area (A_r = lambda_c
    D/(2-D) a_l elastically) and gives P ~ A_r^((3-D)/2), so at equal nominal pressure
    A_r/A0 grows as A0^((D-1)/(3-D)): the answer depends on how the nominal area is cut.
    The W-M surface itself is defined on a sample of its longest wavelength L (lowest
    frequency 1/L; Majumdar & Bhushan 1990/1991, Yan & Komvopoulos 1998 J. Appl. Phys.
    84:3617 define the 3-D surface on an L x L sample), and a rough-contact result is
    representative, hence additive over area, once the nominal area holds the longest
    wavelength (Yastrebov, Anciaux & Molinari 2012).  CHOICE (docs/fractal_contact.md): the
    element is L x L with L the W-M sample length; elements act in parallel, so stiffness,
    load and area add and the result per unit nominal area depends on the pressure only.
    Raises :class:`FullContactError` where the element would be in complete contact."""
    p = _pos("pressure_Pa", pressure_Pa)
    A0 = _pos("A0_m2", A0_m2)
    Ae = _pos("element_m2", element_m2)
    e = solid_contact_at_load(surface, material, p * Ae, Ae, options)
    n = A0 / Ae
    return FractalContactResult(
        e.load_N * n, e.real_area_m2 * n, e.stiffness_N_per_m * n, e.asperity_stiffness_N_per_m * n,
        e.a_l_m2, A0, e.a_c_m2, tuple(v * n for v in e.stage_load_N),
        tuple(v * n for v in e.stage_stiffness_N_per_m), tuple(v * n for v in e.stage_area_m2))


def oil_film_stiffness_N_per_m(A0_m2: float, real_area_m2: float, h_m: float, p_Pa: float = 0.0,
                               B0_Pa: float = B0_DEFAULT_PA, B0_prime: float = B0_PRIME_DEFAULT) -> float:
    """Oil-film part K_l = B(p) (A0 - A_r) / h (N/m): Zhao et al. 2022 eq 8-9 on the
    lubricated (non-contact) area (Xu, Shi & Fan 2023 eq 26, after Xue et al. 2022)."""
    A0 = _pos("A0_m2", A0_m2)
    Ar = _pos("real_area_m2", real_area_m2, allow_zero=True)
    h = _pos("h_m", h_m)
    p = _pos("p_Pa", p_Pa, allow_zero=True)
    return float(bulk_modulus_Pa(p, B0_Pa, B0_prime)) * max(A0 - Ar, 0.0) / h


def normal_contact_stiffness(surface: FractalSurface, material: FractalMaterial, load_N: float,
                             A0_m2: float, h_m: Optional[float], *, options: FractalOptions = SEED001_FULL,
                             B0_Pa: float = B0_DEFAULT_PA, B0_prime: float = B0_PRIME_DEFAULT) -> dict:
    """K_n = K_s + K_l (N/m) for load ``load_N`` on ``A0_m2`` with film thickness
    ``h_m`` (None: dry, K_l = 0).  The film's bulk modulus is taken at the
    nominal pressure load/A0.  Returns a dict with K_n, K_s, K_l, A_r and the solid result."""
    sol = solid_contact_at_load(surface, material, load_N, A0_m2, options)
    Kl = 0.0 if h_m is None else oil_film_stiffness_N_per_m(A0_m2, sol.real_area_m2, h_m,
                                                            load_N / A0_m2, B0_Pa, B0_prime)
    return {"K_n_N_per_m": sol.stiffness_N_per_m + Kl, "K_s_N_per_m": sol.stiffness_N_per_m,
            "K_l_N_per_m": Kl, "real_area_m2": sol.real_area_m2, "solid": sol}


def dimensionless(load_N: float, real_area_m2: float, stiffness_N_per_m: float, A0_m2: float,
                  E_Pa: float) -> Tuple[float, float, float]:
    """(P*, A_r*, K*) = (P/(A0 E), A_r/A0, K/(E sqrt(A0))).  Xu, Shi & Fan 2023 write K/(E A0),
    which has the unit 1/m; sqrt(A0) makes it dimensionless (our choice)."""
    A0, E = _pos("A0_m2", A0_m2), _pos("E_Pa", E_Pa)
    return load_N / (A0 * E), real_area_m2 / A0, stiffness_N_per_m / (E * math.sqrt(A0))


# ------------------------------------------------------------------ lambda_c
def hertz_half_width_m(rho_m: float, line_load_N_per_m: float, E_Pa: float) -> float:
    """Hertz line-contact half-width b = sqrt(4 w rho / (pi E)) (Johnson 1985, ch. 4)."""
    return math.sqrt(4.0 * _pos("line_load_N_per_m", line_load_N_per_m, allow_zero=True)
                     * _pos("rho_m", rho_m) / (math.pi * _pos("E_Pa", E_Pa)))


def line_contact_gap_m(x_m, b_m: float, rho_m: float):
    """Gap between two loaded Hertzian cylinders outside the band |x| > b (m):
    g = (b^2/(2 rho)) [X sqrt(X^2-1) - ln(X + sqrt(X^2-1))], X = |x|/b (0 inside);
    b = 0 gives the unloaded gap x^2/(2 rho)."""
    x = np.abs(np.asarray(x_m, float))
    if b_m <= 0:
        return x * x / (2.0 * rho_m)
    X = np.maximum(x / b_m, 1.0)
    r = np.sqrt(X * X - 1.0)
    return b_m * b_m / (2.0 * rho_m) * (X * r - np.log(X + r))


def contact_correction_coefficient(rho_m: float, line_load_N_per_m: float, E_Pa: float,
                                   sigma_m: float, ell_m: float, n: int = 2001) -> float:
    """Contact-surface correction coefficient lambda_c in (0, 1) (our rebuild of Xu, Shi & Fan 2023 eq 19).

    The share of the flat-plane asperity population that curved flanks bring
    into reach: over the reference band |x| <= b + ell (Hertz half-width b
    plus the roughness footprint ``ell_m``, e.g. the W-M longest wavelength),
    points inside the Hertz band count fully and points outside with
    exp(-g(x)/sigma), g the loaded Hertz gap and ``sigma_m`` the roughness
    height.  It meets the seed's stated properties: < 1, -> 1 for flat
    surfaces (rho -> inf), -> 0 for rho -> 0, > 0 at zero load and rising
    with the load (docs/fractal_contact.md)."""
    rho = _pos("rho_m", rho_m)
    sig = _pos("sigma_m", sigma_m)
    ell = _pos("ell_m", ell_m)
    b = hertz_half_width_m(rho, line_load_N_per_m, E_Pa)
    xr = b + ell
    x = np.linspace(b, xr, n)
    wgt = np.exp(-line_contact_gap_m(x, b, rho) / sig)
    outside = float(np.trapezoid(wgt, x))
    return (b + outside) / xr


# ------------------------------------------------------------------ mesh adapter
#: film-parameter ranges (lambda = h_min / sigma): full film >= 3, mixed 1..3, boundary < 1
#: (Tallian 1967; Johnson, Greenwood & Poon 1972; as tabulated by Hamrock, Schmid &
#: Jacobson, *Fundamentals of Machine Elements*, lubrication regimes)
FULL_FILM_LAMBDA = 3.0
BOUNDARY_LAMBDA = 1.0
#: hardness of case-hardened gear steel (about 650 HV = 6.4 GPa; our default, Xu, Shi & Fan 2023 give none)
GEAR_STEEL_HARDNESS_PA = 6.4e9
#: asperity friction coefficient of Xu, Shi & Fan 2023 Table 1
SEED001_ASPERITY_FRICTION = 0.12


def composite_sigma_m(sigma1_m: float, sigma2_m: float) -> float:
    """Composite RMS roughness sqrt(sigma1^2 + sigma2^2) (m) of two flanks (Johnson 1985,
    ch. 13; ISO/TR 15144-1 uses the same composite in its specific film thickness)."""
    return math.hypot(_pos("sigma1_m", sigma1_m, allow_zero=True), _pos("sigma2_m", sigma2_m, allow_zero=True))


def film_parameter(h_min_m: float, sigma1_m: float, sigma2_m: float) -> float:
    """The project's one film-parameter definition (1):
    Lambda = h_min / sqrt(sigma1^2 + sigma2^2), h_min the minimum film thickness of the
    smooth contact, sigma1, sigma2 the RMS roughness of the two flanks (Tallian 1967;
    Johnson 1985 ch. 13; ISO/TR 15144-1 specific film thickness).  In the mesh h_min is the
    Dowson & Higginson (1966) line-contact minimum film and sigma_i the W-M RMS of each
    flank (:func:`gearfmu.contact.roughness.wm_sigma_m`), the same as
    :func:`gearfmu.contact.models.film_parameter`."""
    sc = composite_sigma_m(sigma1_m, sigma2_m)
    if sc <= 0:
        raise FractalInputError("sigma1_m, sigma2_m: the composite roughness must be > 0")
    return _pos("h_min_m", h_min_m, allow_zero=True) / sc


def film_regime(film_parameter: float) -> str:
    """'full_film' (lambda >= 3), 'mixed' (1 <= lambda < 3) or 'boundary' (lambda < 1)."""
    lam = float(film_parameter)
    if not math.isfinite(lam) or lam < 0:
        raise FractalInputError(f"film_parameter={film_parameter!r}: must be finite and >= 0")
    if lam >= FULL_FILM_LAMBDA:
        return "full_film"
    return "mixed" if lam >= BOUNDARY_LAMBDA else "boundary"


@dataclass(frozen=True)
class FractalMeshOptions:
    """Settings of the 'fractal_mixed' mesh model: hardness ``H_Pa`` (Pa), asperity
    ``friction`` (1), fractal ``options`` (lateral classes, interaction), ``L_s_m`` (m)
    the W-M longest wavelength used for sigma and the lambda_c footprint, lubricant
    bulk modulus ``B0_Pa`` and ``B0_prime``."""

    H_Pa: float = GEAR_STEEL_HARDNESS_PA
    friction: float = SEED001_ASPERITY_FRICTION
    options: FractalOptions = SEED001_FULL
    L_s_m: float = 0.5e-3
    B0_Pa: float = B0_DEFAULT_PA
    B0_prime: float = B0_PRIME_DEFAULT


def slice_contact_stiffness(D: float, G_m: float, rho_m: float, u_m_s: float, w_N_per_m: float,
                            width_m: float, E_star_Pa: float, eta0_Pas: Optional[float],
                            alpha_Pa_inv: Optional[float],
                            mesh_options: FractalMeshOptions = FractalMeshOptions()) -> dict:
    """K_n (N/m) of one face-width slice of width ``width_m`` at line load ``w_N_per_m``.

    Nominal area A0 = 2b x width (Hertz band), nominal pressure p = w/(2b); the solid part
    from :func:`solid_contact_extensive` on L_s x L_s elements (L_s = ``mesh_options.L_s_m``,
    the W-M sample length) scaled by A0/L_s^2, so K_n per unit width does not depend on how
    the face is sliced; the whole slice load on the asperities (Xu, Shi & Fan 2023 eq 24); lambda_c
    from the curvature ``rho_m``, the line load and the composite roughness; the oil film of
    thickness h_c (Pan & Hamrock 1989 central film at entrainment speed ``u_m_s``) on the
    non-contact area.  Film parameter: :func:`film_parameter` with the Dowson & Higginson
    h_min and both flanks' W-M sigma (the definition of gearfmu.contact.models).
    Returns K_n, K_s, K_l, lambda_c, film parameter and its regime, A_r/A0, A0.
    No lubricant (eta0 None): K_l = 0.  Raises :class:`FullContactError` where the
    asperities cannot carry the load below complete contact (A_r >= A0)."""
    mo = mesh_options
    surf = FractalSurface(D, G_m)
    mat = FractalMaterial(E_star_Pa, mo.H_Pa, friction=mo.friction)
    w = _pos("w_N_per_m", w_N_per_m)
    b = hertz_half_width_m(rho_m, w, E_star_Pa)
    A0 = 2.0 * b * _pos("width_m", width_m)
    p_nom = w / (2.0 * b)
    sig_flank = wm_sigma_m(D, G_m, mo.L_s_m)
    sigma = composite_sigma_m(sig_flank, sig_flank)
    lam_c = contact_correction_coefficient(rho_m, w, E_star_Pa, sigma, mo.L_s_m)
    opts = FractalOptions(lateral=mo.options.lateral, interaction=mo.options.interaction, lambda_c=lam_c)
    sol = solid_contact_extensive(surf, mat, p_nom, A0, mo.L_s_m ** 2, opts)
    h_c = h_min = None
    Kl = 0.0
    lam = float("inf")
    if eta0_Pas is not None:
        Ep = 2.0 * E_star_Pa
        W = w / (Ep * rho_m)
        U = eta0_Pas * u_m_s / (Ep * rho_m)
        Gd = max(float(alpha_Pa_inv or 0.0) * Ep, 1e-9)
        h_c = pan_hamrock_films(W, U, Gd)[1] * rho_m
        h_min = dowson_higginson_min_film(W, U, Gd) * rho_m
        lam = film_parameter(h_min, sig_flank, sig_flank)
        Kl = oil_film_stiffness_N_per_m(A0, sol.real_area_m2, h_c, p_nom, mo.B0_Pa, mo.B0_prime)
    return {"K_n_N_per_m": sol.stiffness_N_per_m + Kl, "K_s_N_per_m": sol.stiffness_N_per_m,
            "K_l_N_per_m": Kl, "lambda_c": lam_c, "film_parameter": lam,
            "regime": film_regime(lam) if math.isfinite(lam) else "dry", "h_c_m": h_c, "h_min_m": h_min,
            "real_area_ratio": sol.real_area_m2 / A0, "A0_m2": A0}
