"""Weierstrass-Mandelbrot (W-M) fractal flank roughness (Zhao et al. 2022 eq 1, Table 2).

Zhao et al. 2022 eq 1 with a random phase per frequency:

    wm(x) = G^(D-1) * sum_n cos(2 pi gamma^n x + phi_n) / gamma^((2-D) n),
    1 < D < 2, gamma = 1.5, 0 <= phi_n <= 2 pi.

The seed gives D and G for four roughness levels (Table 2) but not the units
of G and x, nor the frequency range nor the evaluation length.  Convention
chosen here (documented in docs/ehl.md):

* Dimensionally consistent SI form (Majumdar & Bhushan 1990, Wear 136, eq 1
  with a random phase per term as in Yan & Komvopoulos 1998, J. Appl. Phys.
  84):  wm(x) = G^(D-1) * sum_{n=0}^{n_max} f_n^(D-2) cos(2 pi f_n x + phi_n),
  f_n = gamma^n / L_s, lengths in m.  With L_s = 1 length unit this is
  exactly Zhao et al. 2022 eq 1.
* Table 2's G is read in **mm** (G_SI = 1e-3 * G_table m, i.e. 1.669 nm to
  5.229 nm, the order of magnitude of the G values of Majumdar & Bhushan's
  measured surfaces) and the lowest frequency is f_0 = 1/L_s with
  L_s = 0.5 mm (``SEED000_SAMPLE_LENGTH_M``).  This is a calibration choice:
  no (unit, L_s) pair reproduces all four Ra values better than about
  +-3 % (the best fit is a unit of 1.58 mm), and with mm and integer n_min
  = 2 level 1 comes out 12 % low; L_s = 0.5 mm puts every level within
  about +-9 % (tests/unit/contact/test_roughness.py measures it).
* Ra is evaluated on the unfiltered profile (least-squares mean line) over
  ``SEED000_EVALUATION_LENGTH_M`` = 4 mm, the ISO 4288 evaluation length for
  0.1 um < Ra <= 2 um, sampled at 0.5 um, averaged over the face-width
  slices of one flank.

The highest frequency is the Nyquist frequency of the sampling unless given.
Identification of D and G from a measured profile uses the band-averaged
power spectrum (Majumdar & Bhushan 1990, J. Tribol. 112, 205-216: the W-M spectrum is
S(f) = G^(2(D-1)) / (2 ln gamma) * f^-(5-2D)), see :func:`identify_fractal`.
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from typing import Dict, Optional, Tuple

import numpy as np

from ..ehl.mesh_film import FlankRoughness, MeshFilmInputError, involute_arc_length_m

#: W-M frequency ratio gamma of Zhao et al. 2022 eq 1.
SEED000_GAMMA = 1.5
#: Lowest-frequency wavelength L_s of the convention above (m).
SEED000_SAMPLE_LENGTH_M = 0.5e-3
#: Ra evaluation length (m): ISO 4288 for 0.1 um < Ra <= 2 um.
SEED000_EVALUATION_LENGTH_M = 4.0e-3
#: Sampling step used for Ra evaluation (m).
SEED000_SAMPLING_M = 0.5e-6


@dataclass(frozen=True)
class RoughnessLevel:
    """One roughness level of Zhao et al. 2022 Table 2 (Ra in m, D, G in m)."""

    level: int
    Ra_m: float
    D: float
    G_m: float


#: Zhao et al. 2022 Table 2 with G converted by the convention above (table value in mm).
#: (The table prints level 3's D as "1565"; read as 1.565.)
SEED000_LEVELS: Dict[int, RoughnessLevel] = {
    1: RoughnessLevel(1, 0.107e-6, 1.692, 1.669e-6 * 1e-3),
    2: RoughnessLevel(2, 0.425e-6, 1.596, 3.528e-6 * 1e-3),
    3: RoughnessLevel(3, 0.681e-6, 1.565, 4.513e-6 * 1e-3),
    4: RoughnessLevel(4, 0.907e-6, 1.546, 5.229e-6 * 1e-3),
}


class RoughnessInputError(ValueError):
    """Bad roughness input; the message names the field and the reason."""


def _check(D: float, G_m: float, gamma: float, L_s_m: float):
    if not (1.0 < float(D) < 2.0):
        raise RoughnessInputError(f"D={D!r}: the fractal dimension must lie in (1, 2)")
    if not (math.isfinite(G_m) and G_m > 0):
        raise RoughnessInputError(f"G_m={G_m!r}: must be finite and > 0 (m)")
    if not (math.isfinite(gamma) and gamma > 1):
        raise RoughnessInputError(f"gamma={gamma!r}: must be > 1")
    if not (math.isfinite(L_s_m) and L_s_m > 0):
        raise RoughnessInputError(f"L_s_m={L_s_m!r}: must be finite and > 0 (m)")


def wm_frequencies_per_m(L_s_m: float = SEED000_SAMPLE_LENGTH_M, f_max_per_m: float = 1e6,
                         gamma: float = SEED000_GAMMA) -> np.ndarray:
    """Frequencies f_n = gamma^n / L_s (1/m), n = 0 .. while f_n <= f_max."""
    if not (f_max_per_m > 1.0 / L_s_m):
        raise RoughnessInputError(
            f"f_max_per_m={f_max_per_m!r} must exceed the lowest frequency 1/L_s = {1 / L_s_m!r}")
    n_max = int(math.floor(math.log(f_max_per_m * L_s_m) / math.log(gamma) + 1e-12))
    return gamma ** np.arange(n_max + 1) / L_s_m


def wm_profile_m(x_m, D: float, G_m: float, phases_rad=None, *,
                 L_s_m: float = SEED000_SAMPLE_LENGTH_M, f_max_per_m: Optional[float] = None,
                 gamma: float = SEED000_GAMMA, rng=None) -> np.ndarray:
    """W-M profile height (m) at positions ``x_m`` (m), Zhao et al. 2022 eq 1 (SI form).

    ``phases_rad``: one phase per frequency (random uniform in [0, 2 pi) from
    ``rng`` -- a numpy Generator or an int seed -- when None).  ``f_max_per_m``
    defaults to the Nyquist frequency of ``x_m`` (uniform spacing assumed).
    """
    x = np.asarray(x_m, dtype=float)
    if x.ndim != 1 or x.size < 2 or not np.all(np.isfinite(x)):
        raise RoughnessInputError("x_m must be a finite 1-D array with >= 2 points")
    _check(D, G_m, gamma, L_s_m)
    if f_max_per_m is None:
        dx = float(np.min(np.diff(x)))
        if dx <= 0:
            raise RoughnessInputError("x_m must be strictly increasing")
        f_max_per_m = 0.5 / dx
    f = wm_frequencies_per_m(L_s_m, f_max_per_m, gamma)
    if phases_rad is None:
        g = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
        phases_rad = g.uniform(0.0, 2.0 * np.pi, f.size)
    phases = np.asarray(phases_rad, dtype=float)
    if phases.shape != f.shape:
        raise RoughnessInputError(f"phases_rad: need {f.size} phases (one per frequency), "
                                  f"got {phases.shape}")
    amp = G_m ** (D - 1.0) * f ** (D - 2.0)
    z = np.zeros_like(x)
    for a, fn, ph in zip(amp, f, phases):
        z += a * np.cos(2.0 * np.pi * fn * x + ph)
    return z


def flank_roughness_m(x_m, D: float, G_m: float, n_slices: int, seed: int, *,
                      L_s_m: float = SEED000_SAMPLE_LENGTH_M,
                      f_max_per_m: Optional[float] = None,
                      gamma: float = SEED000_GAMMA) -> np.ndarray:
    """Roughness of one flank, shape (n_slices, len(x_m)), m.

    Zhao et al. 2022 section 2.2: the same (D, G) on every face-width slice but an
    independent random phase per frequency and per slice.  Reproducible: the
    phases of slice k come from ``numpy.random.SeedSequence(seed).spawn``.
    """
    if int(n_slices) < 1:
        raise RoughnessInputError(f"n_slices={n_slices!r}: must be >= 1")
    children = np.random.SeedSequence(int(seed)).spawn(int(n_slices))
    return np.stack([
        wm_profile_m(x_m, D, G_m, rng=np.random.default_rng(c), L_s_m=L_s_m,
                     f_max_per_m=f_max_per_m, gamma=gamma) for c in children])


def _detrend(x, z):
    A = np.vstack([x - x.mean(), np.ones_like(x)]).T
    coef, *_ = np.linalg.lstsq(A, z, rcond=None)
    return z - A @ coef


def ra_m(x_m, z_m) -> float:
    """Arithmetic mean roughness Ra (m) about the least-squares mean line."""
    x = np.asarray(x_m, float)
    z = np.asarray(z_m, float)
    if x.shape != z.shape or x.size < 3:
        raise RoughnessInputError("x_m and z_m must have the same shape with >= 3 points")
    return float(np.mean(np.abs(_detrend(x, z))))


def rq_m(x_m, z_m) -> float:
    """RMS roughness sigma = Rq (m) about the least-squares mean line."""
    x = np.asarray(x_m, float)
    z = np.asarray(z_m, float)
    return float(np.sqrt(np.mean(_detrend(x, z) ** 2)))


def wm_sigma_m(D: float, G_m: float, L_s_m: float = SEED000_SAMPLE_LENGTH_M,
               f_max_per_m: float = np.inf, gamma: float = SEED000_GAMMA) -> float:
    """Expected RMS height (m) of the discrete W-M sum: sum of a_n^2/2."""
    _check(D, G_m, gamma, L_s_m)
    q = gamma ** (-2.0 * (2.0 - D))
    if np.isinf(f_max_per_m):
        s = 1.0 / (1.0 - q)
    else:
        n = wm_frequencies_per_m(L_s_m, f_max_per_m, gamma).size
        s = (1.0 - q ** n) / (1.0 - q)
    return float(G_m ** (D - 1.0) * L_s_m ** (2.0 - D) * math.sqrt(0.5 * s))


def level_Ra_m(level: int, n_slices: int = 44, seed: int = 0,
               evaluation_length_m: float = SEED000_EVALUATION_LENGTH_M,
               sampling_m: float = SEED000_SAMPLING_M) -> float:
    """Mean Ra (m) over ``n_slices`` generated slices of a Zhao et al. 2022 Table 2 level."""
    lv = SEED000_LEVELS[int(level)]
    x = np.arange(0.0, evaluation_length_m, sampling_m)
    z = flank_roughness_m(x, lv.D, lv.G_m, n_slices, seed)
    return float(np.mean([ra_m(x, zk) for zk in z]))


@dataclass(frozen=True)
class FractalFit:
    """Result of :func:`identify_fractal`."""

    D: float                 #: fractal dimension
    G_m: float               #: characteristic scale (m), W-M convention above
    slope: float             #: slope of log band power vs log frequency
    band_f_per_m: np.ndarray  #: lower band edges used (1/m)
    band_power_m2: np.ndarray  #: band powers (m^2)


def identify_fractal(x_m, z_m, gamma: float = SEED000_GAMMA, band_ratio: float = 1.5,
                     f_lo_per_m: Optional[float] = None,
                     f_hi_per_m: Optional[float] = None) -> FractalFit:
    """Identify D and G of a profile from its band-averaged power spectrum.

    The W-M spectrum S(f) = G^(2(D-1)) / (2 ln gamma) f^-(5-2D) (Majumdar &
    Bhushan 1990, J. Tribol. 112, 205-216) integrates over a band [f, r f] to
    P_b = G^(2(D-1)) f^-(4-2D) (1 - r^-(4-2D)) / (2 ln gamma (4-2D)), so the
    slope s of log P_b against log f gives D = 2 + s/2 and the intercept
    gives G.  Bands of ratio ``band_ratio`` (one W-M line per band when it
    equals gamma) from the band of largest power at or above ``f_lo``
    (default 8/L, L the profile length) up to ``f_hi`` (default Nyquist/4); the profile is detrended and Hann-windowed
    (power corrected by the window's mean square).
    """
    x = np.asarray(x_m, float)
    z = np.asarray(z_m, float)
    if x.ndim != 1 or x.shape != z.shape or x.size < 64:
        raise RoughnessInputError("x_m, z_m: 1-D arrays of equal length >= 64 are required")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(z))):
        raise RoughnessInputError("x_m, z_m: NaN or infinite values")
    dx = np.diff(x)
    if np.any(dx <= 0) or (dx.max() - dx.min()) > 1e-6 * dx.mean():
        raise RoughnessInputError("x_m must be uniformly spaced and increasing")
    dx = float(dx.mean())
    n = x.size
    length = n * dx
    zz = _detrend(x, z)
    w = np.hanning(n)
    Z = np.fft.rfft(zz * w)
    f = np.fft.rfftfreq(n, dx)
    # one-sided power per bin such that sum(power) ~ mean square of the profile
    power = (np.abs(Z) ** 2) / (n * n * np.mean(w ** 2))
    power[1:] *= 2.0
    if n % 2 == 0:
        power[-1] *= 0.5
    f_lo = 8.0 / length if f_lo_per_m is None else float(f_lo_per_m)
    f_hi = 0.25 / dx if f_hi_per_m is None else float(f_hi_per_m)
    edges = [f_lo]
    while edges[-1] * band_ratio <= f_hi:
        edges.append(edges[-1] * band_ratio)
    if len(edges) < 4:
        raise RoughnessInputError("profile too short for a band-averaged spectrum "
                                  f"(only {len(edges) - 1} bands between {f_lo:.3g} and {f_hi:.3g} 1/m)")
    lo = np.array(edges[:-1])
    pb = np.array([power[(f >= a) & (f < a * band_ratio)].sum() for a in lo])
    # the fractal range starts at the band of largest power (below it the
    # profile has no content, e.g. W-M frequencies start at 1/L_s)
    i0 = int(np.argmax(pb))
    lo, pb = lo[i0:], pb[i0:]
    keep = pb > 0
    lo, pb = lo[keep], pb[keep]
    if lo.size < 4:
        raise RoughnessInputError(f"only {lo.size} usable spectral bands: profile too short")
    slope, icpt = np.polyfit(np.log(lo), np.log(pb), 1)
    D = 2.0 + 0.5 * slope
    if not (1.0 < D < 2.0):
        raise RoughnessInputError(f"identified D = {D:.3f} is outside (1, 2): "
                                  "the profile is not fractal in the fitted band")
    k = 4.0 - 2.0 * D
    c = (1.0 - band_ratio ** (-k)) / (2.0 * math.log(gamma) * k)
    # P_b = G^(2(D-1)) c f^-k  ->  ln G = (ln P_b + k ln f - ln c) / (2(D-1)), averaged
    lnG = np.mean((np.log(pb) + k * np.log(lo) - math.log(c)) / (2.0 * (D - 1.0)))
    return FractalFit(D=float(D), G_m=float(math.exp(lnG)), slope=float(slope),
                      band_f_per_m=lo, band_power_m2=pb)


def load_profile_csv(path, x_unit_m: float = 1.0, z_unit_m: float = 1.0
                     ) -> Tuple[np.ndarray, np.ndarray]:
    """Read a measured profile: CSV with two columns, position and height.

    A header line is skipped when its first field is not a number.  Values are
    multiplied by ``x_unit_m`` and ``z_unit_m`` (e.g. 1e-3 and 1e-6 for mm and
    um) and returned in m.
    """
    xs, zs = [], []
    with open(path, newline="") as fh:
        for k, row in enumerate(csv.reader(fh)):
            if not row or not row[0].strip():
                continue
            try:
                xv, zv = float(row[0]), float(row[1])
            except (ValueError, IndexError):
                if k == 0:
                    continue
                raise RoughnessInputError(f"{path}: line {k + 1}: expected two numbers, got {row!r}")
            xs.append(xv)
            zs.append(zv)
    return np.asarray(xs) * x_unit_m, np.asarray(zs) * z_unit_m


# ---------------------------------------------------------------- flank roughness for the film solves
def make_flank_roughness(geom, D: float, G_m: float, n_slices: int, seed: int, *,
                         f_max_per_m: float = 1e4, margin_m: float = 3e-3,
                         step_m: Optional[float] = None) -> FlankRoughness:
    """W-M roughness of the active pinion and gear flanks (Zhao et al. 2022 eq 1, per slice).

    ``G_m`` in m (Zhao et al. 2022 Table 2 G read in mm: :data:`gearfmu.contact.roughness.SEED000_LEVELS`);
    the profiles cover the active flank arc length plus ``margin_m`` on both
    sides, sampled at ``step_m`` (default a tenth of the shortest wavelength)."""
    if int(n_slices) != n_slices or n_slices < 1:
        raise MeshFilmInputError(f"n_slices={n_slices!r}: must be an integer >= 1")
    if not (math.isfinite(f_max_per_m) and f_max_per_m > 0):
        raise MeshFilmInputError(f"f_max_per_m={f_max_per_m!r}: must be finite and > 0 (1/m)")
    step = 0.1 / f_max_per_m if step_m is None else float(step_m)
    children = np.random.SeedSequence(int(seed)).spawn(2)
    grids, heights = [], []
    for which, ch in ((1, children[0]), (2, children[1])):
        lo_roll, hi_roll = geom.active_roll1_m if which == 1 else geom.active_roll2_m
        rb = geom.rb1_m if which == 1 else geom.rb2_m
        a_lo = float(involute_arc_length_m(max(lo_roll, 0.0), rb)) - margin_m
        a_hi = float(involute_arc_length_m(hi_roll, rb)) + margin_m
        a = np.arange(a_lo, a_hi + step, step)
        try:
            z = np.stack([wm_profile_m(a, D, G_m, rng=np.random.default_rng(c), f_max_per_m=f_max_per_m)
                          for c in ch.spawn(int(n_slices))])
        except RoughnessInputError as exc:
            raise MeshFilmInputError(f"roughness: {exc}") from None
        grids.append(a)
        heights.append(z)
    return FlankRoughness(grids[0], heights[0], grids[1], heights[1], float(D), float(G_m), int(seed),
                          float(f_max_per_m))
