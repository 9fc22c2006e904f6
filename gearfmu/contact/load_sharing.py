"""Film-asperity load sharing in a rough EHL line contact (mixed lubrication).

Johnson, Greenwood & Poon (JGP) 1972, "A simple theory of asperity contact in
elastohydrodynamic lubrication", Wear 19, 91-108, in the form used for line contacts by
Gelinck & Schipper (2000, Tribol. Int. 33, 175-181) and the "load-sharing concept" papers
after them.  Full derivation, sources and every CHOICE: docs/load_sharing.md.  SI units.

* Load split (JGP): w = w_film + w_asp with w_film = w/gamma1, w_asp = w/gamma2,
  1/gamma1 + 1/gamma2 = 1.  Both parts keep the Hertz half-width b of the total load
  (b = sqrt(8 w R/(pi E'))); the film part therefore behaves as a *smooth* EHL contact
  under the load w/gamma1 with the modulus E'/gamma1 (JGP; Gelinck & Schipper 2000 write
  the same scaling as F -> F/gamma1, E -> E/gamma1 in Moes' film formula).  In Moes'
  groups (U on the mean speed, gearfmu.ehl.fits): W unchanged, U -> gamma1 U,
  G -> G/gamma1, so M -> M gamma1^-1/2, L -> L gamma1^-3/4 and
  h_c = R (2 gamma1 U)^1/2 H_c(M gamma1^-1/2, L gamma1^-3/4) (Moes 1992 central film,
  :func:`jgp_central_film_m`).
* Asperities: Greenwood & Williamson (1966, Proc. R. Soc. A 295, 300-319) for the
  equivalent rough surface (both flanks' spectral moments added, McCool 1986) against a
  flat: nominal pressure p_a = (4/3) eta E* beta^1/2 sigma_s^3/2 F_3/2(d/sigma_s),
  real-area ratio pi eta beta sigma_s F_1, contact density eta F_0, with d the separation
  of the flat from the mean summit plane and F_n(t) = int_t^inf (s - t)^n phi(s) ds
  (:func:`gw_integral`; Gaussian or exponential summit heights).
* Summit parameters from the profile spectral moments m0, m2, m4 (Nayak 1971, J. Lubr.
  Technol. 93, 398; McCool 1986, Wear 107, 37-60): eta = m4/(6 pi sqrt(3) m2),
  beta = 3 sqrt(pi)/(8 sqrt(m4)), sigma_s = sqrt(1 - 0.8968/alpha) sqrt(m0),
  mean summit height y_s = 4 sqrt(m0)/sqrt(pi alpha), alpha = m0 m4/m2^2
  (:func:`asperity_parameters`).  The W-M moments are analytic sums over its lines
  (:func:`wm_spectral_moments`), band [1/L_s, f_max] with f_max = 1e6 1/m by default,
  the Nyquist frequency of the 0.5 um sampling of gearfmu.contact.roughness' Ra convention
  (CHOICE; GW needs a band limit, m2 and m4 of the full W-M sum diverge).
* Shared separation (CHOICE, as in the load-sharing-concept papers): the central film
  h_c is the separation of the two surfaces' mean planes; the asperities carry a uniform
  nominal pressure p_a(h_c - y_s) over the Hertz band: w_asp = 2 b p_a.  gamma1 solves
  w (1 - 1/gamma1) = 2 b p_a(h_c(gamma1) - y_s) (one root: the left side rises with
  gamma1, h_c rises and p_a falls).
* Stiffness (CHOICE): film and asperity springs in parallel at the shared separation,
  k = k_film + k_asp.  k_asp = -dw_asp/dh at fixed band = 2 b width 2 eta E* beta^1/2
  sigma_s^1/2 F_1/2(d/sigma_s).  k_film is Zhao et al. 2022 eq 8-9 at the film's share:
  A B(p_f)/h with A = 2 b width, p_f = w_film/(2 b) and h the JGP film h_c; given the
  smooth film's stiffness k_smooth at the total load (e.g. from the EHL solver), the
  film spring is k_smooth x [B(p_f)/h_c] / [B(w/(2b))/h_c,smooth] so that the full-film
  limit (gamma1 -> 1) returns k_smooth exactly and the fits only give the change.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..common.checks import finite_number
from ..ehl.fits import moes_central_film
from ..ehl.lubricant import B0_DEFAULT_PA, B0_PRIME_DEFAULT, bulk_modulus_Pa
from .roughness import (SEED000_GAMMA, SEED000_SAMPLE_LENGTH_M, SEED000_SAMPLING_M, RoughnessInputError,
                        wm_frequencies_per_m)

__all__ = [
    "LoadSharingInputError", "ASPERITY_F_MAX_PER_M", "NAYAK_SIGMA_S_COEFF", "SpectralMoments",
    "wm_spectral_moments", "profile_spectral_moments", "AsperityParameters", "asperity_parameters",
    "gw_integral", "GWContact", "gw_contact", "LineContactState", "LoadShareResult",
    "jgp_central_film_m", "hertz_half_width_m", "load_sharing", "SUMMIT_DISTRIBUTIONS",
]

#: upper band limit (1/m) of the asperity (summit) statistics: the Nyquist frequency of the
#: 0.5 um sampling at which gearfmu.contact.roughness evaluates Ra (SEED000_SAMPLING_M) -- CHOICE
ASPERITY_F_MAX_PER_M = 0.5 / SEED000_SAMPLING_M
#: sigma_s^2 = (1 - 0.8968/alpha) m0 (Nayak 1971; McCool 1986)
NAYAK_SIGMA_S_COEFF = 0.8968
SUMMIT_DISTRIBUTIONS = ("gaussian", "exponential")
#: F_n(t) = 0 (double underflow) above _T_HIGH; below -_T_LOW Gauss-Hermite instead of D_v
_T_HIGH = 38.0
_T_LOW = 20.0


class LoadSharingInputError(ValueError):
    """Bad input to the load-sharing model; the message names the field and the reason."""


def _pos(name, v, zero=False) -> float:
    return finite_number(name, v, positive=not zero, nonneg=zero, error=LoadSharingInputError)


# ------------------------------------------------------------------ spectral moments
@dataclass(frozen=True)
class SpectralMoments:
    """Profile spectral moments of a (composite) surface: ``m0_m2`` = sigma^2 (m^2),
    ``m2`` = mean square slope (1), ``m4_per_m2`` = mean square curvature (1/m^2)."""

    m0_m2: float
    m2: float
    m4_per_m2: float

    @property
    def alpha(self) -> float:
        """Nayak's bandwidth parameter alpha = m0 m4 / m2^2 (1)."""
        return self.m0_m2 * self.m4_per_m2 / self.m2 ** 2


def wm_spectral_moments(D: float, G_m: float, f_max_per_m: float = ASPERITY_F_MAX_PER_M,
                        L_s_m: float = SEED000_SAMPLE_LENGTH_M, gamma: float = SEED000_GAMMA,
                        flanks: int = 2) -> SpectralMoments:
    """Analytic spectral moments of the W-M profile of Zhao et al. 2022 eq 1 (SI form of
    gearfmu.contact.roughness): lines f_n = gamma^n/L_s <= f_max with amplitude
    a_n = G^(D-1) f_n^(D-2); a line a cos(2 pi f x + phi) contributes a^2/2 (2 pi f)^k to
    m_k.  ``flanks`` independent flanks with the same (D, G) add their moments (the
    equivalent surface of two rough surfaces, McCool 1986)."""
    if int(flanks) != flanks or flanks < 1:
        raise LoadSharingInputError(f"flanks={flanks!r}: must be an integer >= 1")
    try:
        f = wm_frequencies_per_m(L_s_m, f_max_per_m, gamma)
    except RoughnessInputError as e:
        raise LoadSharingInputError(f"f_max_per_m: {e}") from None
    if not (1.0 < float(D) < 2.0):
        raise LoadSharingInputError(f"D={D!r}: the fractal dimension must lie in (1, 2)")
    _pos("G_m", G_m)
    e = 0.5 * (G_m ** (D - 1.0) * f ** (D - 2.0)) ** 2
    k = 2.0 * math.pi * f
    n = float(flanks)
    return SpectralMoments(n * float(e.sum()), n * float((e * k ** 2).sum()), n * float((e * k ** 4).sum()))


def profile_spectral_moments(x_m, z_m) -> SpectralMoments:
    """Spectral moments of a sampled periodic profile by FFT: m_k = sum over the one-sided
    spectrum of |Z(f)|^2 (2 pi f)^k (the profile is taken as one period; the mean is
    removed).  m0 = variance, m2 = mean square slope, m4 = mean square curvature."""
    x = np.asarray(x_m, float)
    z = np.asarray(z_m, float)
    if x.ndim != 1 or x.shape != z.shape or x.size < 8:
        raise LoadSharingInputError("x_m, z_m: 1-D arrays of equal length >= 8 are required")
    dx = np.diff(x)
    if np.any(dx <= 0) or (dx.max() - dx.min()) > 1e-9 * dx.mean():
        raise LoadSharingInputError("x_m: must be uniformly spaced and increasing")
    n = x.size
    Z = np.fft.rfft(z - z.mean()) / n
    P = np.abs(Z) ** 2
    P[1:] *= 2.0
    if n % 2 == 0:
        P[-1] *= 0.5
    k = 2.0 * math.pi * np.fft.rfftfreq(n, float(dx.mean()))
    return SpectralMoments(float(P.sum()), float((P * k ** 2).sum()), float((P * k ** 4).sum()))


# ------------------------------------------------------------------ summit parameters
@dataclass(frozen=True)
class AsperityParameters:
    """Greenwood-Williamson summit parameters of the equivalent surface: summit density
    ``eta_per_m2``, summit radius ``beta_m``, RMS summit height ``sigma_s_m``, mean summit
    height above the surface mean plane ``y_s_m``, surface RMS ``sigma_m``, Nayak's
    ``alpha``."""

    eta_per_m2: float
    beta_m: float
    sigma_s_m: float
    y_s_m: float
    sigma_m: float
    alpha: float

    def __post_init__(self):
        for name in ("eta_per_m2", "beta_m", "sigma_s_m", "sigma_m", "alpha"):
            _pos(name, getattr(self, name))
        _pos("y_s_m", self.y_s_m, zero=True)


def asperity_parameters(mom: SpectralMoments) -> AsperityParameters:
    """Nayak (1971) / McCool (1986) summit statistics of an isotropic Gaussian surface
    from its profile moments: eta = m4/(6 pi sqrt(3) m2), beta = 3 sqrt(pi)/(8 sqrt(m4)),
    sigma_s = sqrt(1 - 0.8968/alpha) sqrt(m0), y_s = 4 sqrt(m0)/sqrt(pi alpha).
    Needs alpha > 0.8968 (a broad-band surface; Nayak's formulas are for alpha >> 1)."""
    m0, m2, m4 = _pos("m0_m2", mom.m0_m2), _pos("m2", mom.m2), _pos("m4_per_m2", mom.m4_per_m2)
    a = mom.alpha
    if a <= NAYAK_SIGMA_S_COEFF:
        raise LoadSharingInputError(f"alpha={a:.4g}: the bandwidth parameter m0 m4/m2^2 must exceed "
                                    f"{NAYAK_SIGMA_S_COEFF} for the Nayak summit statistics (raise f_max)")
    s = math.sqrt(m0)
    return AsperityParameters(eta_per_m2=m4 / (6.0 * math.pi * math.sqrt(3.0) * m2),
                              beta_m=3.0 * math.sqrt(math.pi) / (8.0 * math.sqrt(m4)),
                              sigma_s_m=math.sqrt(1.0 - NAYAK_SIGMA_S_COEFF / a) * s,
                              y_s_m=4.0 * s / math.sqrt(math.pi * a), sigma_m=s, alpha=a)


# ------------------------------------------------------------------ GW integrals and contact
def gw_integral(n: float, t, distribution: str = "gaussian"):
    """F_n(t) = int_t^inf (s - t)^n phi(s) ds for the standardised summit-height density phi
    (Greenwood & Williamson 1966; Greenwood & Tripp 1970), n >= 0.

    Gaussian phi = exp(-s^2/2)/sqrt(2 pi): F_n(t) = Gamma(n+1) exp(-t^2/4) D_{-n-1}(t)/sqrt(2 pi)
    with D the parabolic cylinder function (DLMF 12.5.1, U(a, z) = D_{-a-1/2}(z)); exact,
    e.g. F_0 = erfc(t/sqrt 2)/2.  Exponential phi = exp(-s) (s >= 0, GW 1966):
    F_n(t) = Gamma(n+1) exp(-t) for t >= 0 (and int_0^inf (s - t)^n e^-s ds for t < 0)."""
    n = _pos("n", n, zero=True)
    t = np.asarray(t, float)
    from scipy.special import gamma as _gamma_fn, pbdv  # scipy.special: heavy import, only for a rough contact
    if distribution == "gaussian":
        tc = np.clip(t, -_T_LOW, _T_HIGH)
        with np.errstate(over="ignore", invalid="ignore", under="ignore"):
            d, _ = pbdv(-n - 1.0, tc)
            out = _gamma_fn(n + 1.0) * np.exp(-0.25 * tc * tc) * d / math.sqrt(2.0 * math.pi)
        out = np.where(t >= _T_HIGH, 0.0, np.where(np.isfinite(out), np.maximum(out, 0.0), 0.0))
        if np.any(t <= -_T_LOW):   # all summits above t: E[(s - t)^n] by Gauss-Hermite (80 nodes)
            xs, ws = np.polynomial.hermite_e.hermegauss(80)
            out = np.array(out, dtype=float)
            low = np.nonzero(np.atleast_1d(t <= -_T_LOW))
            flat = np.atleast_1d(out)
            flat[low] = [float(np.sum(ws * (xs - tt) ** n)) / math.sqrt(2.0 * math.pi)
                         for tt in np.atleast_1d(t)[low]]
            out = flat.reshape(out.shape)
        return out[()] if out.ndim else float(out)
    if distribution == "exponential":
        if np.any(t < 0):
            from scipy.integrate import quad  # scipy.integrate: heavy import, only for t < 0
            f = np.vectorize(lambda tt: _gamma_fn(n + 1.0) * math.exp(-tt) if tt >= 0 else
                             quad(lambda s: (s - tt) ** n * math.exp(-s), 0.0, np.inf)[0])
            return f(t)[()]
        return (_gamma_fn(n + 1.0) * np.exp(-t))[()]
    raise LoadSharingInputError(f"distribution={distribution!r}: must be one of {', '.join(SUMMIT_DISTRIBUTIONS)}")


@dataclass(frozen=True)
class GWContact:
    """GW contact of the equivalent rough surface against a flat at one separation:
    ``pressure_Pa`` nominal pressure, ``area_ratio`` A_r/A0, ``contacts_per_m2``,
    ``stiffness_Pa_per_m`` = -dp/dd (per unit nominal area)."""

    pressure_Pa: float
    area_ratio: float
    contacts_per_m2: float
    stiffness_Pa_per_m: float


def gw_contact(asp: AsperityParameters, d_m: float, E_star_Pa: float,
               distribution: str = "gaussian") -> GWContact:
    """Greenwood & Williamson (1966) at separation ``d_m`` of the flat from the mean summit
    plane: p = (4/3) eta E* beta^1/2 sigma_s^3/2 F_3/2, A_r/A0 = pi eta beta sigma_s F_1,
    N/A0 = eta F_0, -dp/dd = 2 eta E* beta^1/2 sigma_s^1/2 F_1/2 (dF_n/dt = -n F_(n-1)).
    E* = 1/((1-nu1^2)/E1 + (1-nu2^2)/E2) (Hertz sphere P = (4/3) E* beta^1/2 delta^3/2)."""
    E = _pos("E_star_Pa", E_star_Pa)
    if not math.isfinite(float(d_m)):
        raise LoadSharingInputError(f"d_m={d_m!r}: must be finite")
    t = float(d_m) / asp.sigma_s_m
    c = asp.eta_per_m2 * E * math.sqrt(asp.beta_m)
    return GWContact(pressure_Pa=4.0 / 3.0 * c * asp.sigma_s_m ** 1.5 * float(gw_integral(1.5, t, distribution)),
                     area_ratio=math.pi * asp.eta_per_m2 * asp.beta_m * asp.sigma_s_m
                     * float(gw_integral(1.0, t, distribution)),
                     contacts_per_m2=asp.eta_per_m2 * float(gw_integral(0.0, t, distribution)),
                     stiffness_Pa_per_m=2.0 * c * math.sqrt(asp.sigma_s_m) * float(gw_integral(0.5, t, distribution)))


# ------------------------------------------------------------------ JGP load sharing
@dataclass(frozen=True)
class LineContactState:
    """One line-contact request (SI): reduced radius ``R_m``, mean entrainment speed
    ``u_m_per_s``, load per unit length ``w_N_per_m``, E' = 2 E* ``E_prime_Pa``, oil
    ``eta0_Pas`` and ``alpha_Pa_inv``, slice ``width_m``."""

    R_m: float
    u_m_per_s: float
    w_N_per_m: float
    E_prime_Pa: float
    eta0_Pas: float
    alpha_Pa_inv: float
    width_m: float

    def __post_init__(self):
        for name in ("R_m", "u_m_per_s", "w_N_per_m", "E_prime_Pa", "eta0_Pas", "width_m"):
            _pos(name, getattr(self, name))
        _pos("alpha_Pa_inv", self.alpha_Pa_inv, zero=True)


def hertz_half_width_m(st: LineContactState) -> float:
    """b = sqrt(8 w R/(pi E')) (Hertz line contact)."""
    return math.sqrt(8.0 * st.w_N_per_m * st.R_m / (math.pi * st.E_prime_Pa))


def jgp_central_film_m(st: LineContactState, gamma1: float = 1.0) -> float:
    """Central film (m) of the film part of JGP: the smooth contact under w/gamma1 with the
    modulus E'/gamma1, by Moes' (1992) fit (:func:`gearfmu.ehl.fits.moes_central_film`):
    h_c = R (2 U1)^1/2 H_c(M1, L1), U1 = gamma1 U, M1 = M gamma1^-1/2, L1 = L gamma1^-3/4."""
    g = _pos("gamma1", gamma1)
    if g < 1.0:
        raise LoadSharingInputError(f"gamma1={gamma1!r}: must be >= 1 (film share <= 1)")
    U = st.eta0_Pas * st.u_m_per_s / (st.E_prime_Pa * st.R_m)
    W = st.w_N_per_m / (st.E_prime_Pa * st.R_m)
    G = st.alpha_Pa_inv * st.E_prime_Pa
    M = W * (2.0 * U) ** -0.5
    L = G * (2.0 * U) ** 0.25
    return st.R_m * math.sqrt(2.0 * g * U) * moes_central_film(M / math.sqrt(g), L / g ** 0.75)


@dataclass(frozen=True)
class LoadShareResult:
    """Result of :func:`load_sharing` (SI).  ``film_share`` = 1/gamma1 = w_film/w,
    ``asperity_share`` = 1/gamma2; ``h_c_m`` shared separation of the mean planes (JGP
    central film), ``h_c_smooth_m`` the smooth film at the total load, ``d_m`` = h_c - y_s
    (flat to mean summit plane), ``b_m`` Hertz half-width, ``p_film_Pa`` = w_film/(2b),
    ``p_asp_Pa`` the GW nominal pressure, ``area_ratio`` A_r/A0; stiffnesses per slice
    (N/m): ``k_asp_N_per_m``, ``k_film_N_per_m``, ``k_N_per_m`` = their sum;
    ``film_ratio`` = k_film / k_film,smooth (Zhao et al. 2022 eq 8 at the film's share over eq 8
    at the total load); ``film_parameter`` Lambda = h_c,smooth / sigma (central film)."""

    gamma1: float
    film_share: float
    asperity_share: float
    h_c_m: float
    h_c_smooth_m: float
    d_m: float
    b_m: float
    p_film_Pa: float
    p_asp_Pa: float
    area_ratio: float
    k_asp_N_per_m: float
    k_film_N_per_m: float
    k_N_per_m: float
    film_ratio: float
    film_parameter: float


def load_sharing(st: LineContactState, asp: AsperityParameters, *, distribution: str = "gaussian",
                 k_smooth_N_per_m: Optional[float] = None, B0_Pa: float = B0_DEFAULT_PA,
                 B0_prime: float = B0_PRIME_DEFAULT, min_film_share: float = 1e-9) -> LoadShareResult:
    """JGP film-asperity load sharing of one rough line-contact slice (module doc).

    Solves w (1 - s) = 2 b p_asp(h_c(1/s) - y_s) for the film share s = 1/gamma1 in
    [``min_film_share``, 1] (brentq in ln s, rtol 1e-12); s = 1 when the asperities carry
    nothing at the smooth film (p_asp underflows).  ``k_smooth_N_per_m``: the smooth film's
    stiffness at the total load (e.g. the EHL solver's Zhao et al. 2022 eq 8); None: the film spring
    is eq 8 itself with the Moes film, A B(p_f)/h_c."""
    if distribution not in SUMMIT_DISTRIBUTIONS:
        raise LoadSharingInputError(f"distribution={distribution!r}: must be one of {', '.join(SUMMIT_DISTRIBUTIONS)}")
    if k_smooth_N_per_m is not None:
        _pos("k_smooth_N_per_m", k_smooth_N_per_m)
    s_min = _pos("min_film_share", min_film_share)
    if s_min >= 1.0:
        raise LoadSharingInputError(f"min_film_share={min_film_share!r}: must be < 1")
    w = st.w_N_per_m
    Es = 0.5 * st.E_prime_Pa
    b = hertz_half_width_m(st)
    A = 2.0 * b * st.width_m

    def asp_load(s):
        with np.errstate(over="ignore", invalid="ignore"):
            h = jgp_central_film_m(st, 1.0 / s)
        if not math.isfinite(h):   # Moes' fit overflows far in the rigid-isoviscous range
            return 0.0, h
        return 2.0 * b * gw_contact(asp, h - asp.y_s_m, Es, distribution).pressure_Pa, h

    def resid(ln_s):
        s = math.exp(ln_s)
        return (1.0 - s) * w - asp_load(s)[0]

    h_smooth = jgp_central_film_m(st, 1.0)
    r1 = resid(0.0)
    if r1 >= 0.0:   # no asperity load at the smooth film
        s = 1.0
    else:
        lo = math.log(s_min)
        if resid(lo) <= 0.0:
            raise LoadSharingInputError(
                f"w_N_per_m={w!r}: the asperities carry the load only with a film share below "
                f"min_film_share={s_min:g} (film thickness out of the fit's range)")
        from scipy.optimize import brentq  # scipy.optimize: heavy import, only for a rough contact
        s = math.exp(brentq(resid, lo, 0.0, xtol=1e-14, rtol=1e-12, maxiter=200))
    h = jgp_central_film_m(st, 1.0 / s)
    gc = gw_contact(asp, h - asp.y_s_m, Es, distribution)
    p_f = s * w / (2.0 * b)
    k_film_eq8 = A * float(bulk_modulus_Pa(p_f, B0_Pa, B0_prime)) / h
    k_smooth_eq8 = A * float(bulk_modulus_Pa(w / (2.0 * b), B0_Pa, B0_prime)) / h_smooth
    ratio = k_film_eq8 / k_smooth_eq8
    k_film = k_film_eq8 if k_smooth_N_per_m is None else float(k_smooth_N_per_m) * ratio
    k_asp = A * gc.stiffness_Pa_per_m
    return LoadShareResult(gamma1=1.0 / s, film_share=s, asperity_share=1.0 - s, h_c_m=h, h_c_smooth_m=h_smooth,
                           d_m=h - asp.y_s_m, b_m=b, p_film_Pa=p_f, p_asp_Pa=gc.pressure_Pa,
                           area_ratio=gc.area_ratio, k_asp_N_per_m=k_asp, k_film_N_per_m=k_film,
                           k_N_per_m=k_film + k_asp, film_ratio=ratio, film_parameter=h_smooth / asp.sigma_m)
