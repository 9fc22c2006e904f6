"""Roughness input of the steady EHL solver: normalisation and band limit."""
from __future__ import annotations

from typing import Callable, Optional

import numpy as np

from .errors import EHLInputError


def band_limit(z: np.ndarray, min_wavelength_samples: float) -> np.ndarray:
    """Low-pass filter of a uniformly sampled profile ``z``: Fourier
    components with wavelength shorter than ``min_wavelength_samples``
    samples are removed (ideal cut of the FFT of the profile extended by its
    mirror image, so that no jump at the ends leaks into the band).  Units
    of ``z`` are kept."""
    z = np.asarray(z, float)
    n = z.size
    if n < 4 or min_wavelength_samples <= 2.0:
        return z.copy()
    ext = np.concatenate((z, z[-2:0:-1]))        # even extension, period 2n - 2
    m = ext.size
    Z = np.fft.rfft(ext)
    f = np.arange(Z.size) / m                     # cycles per sample
    Z[f > 1.0 / min_wavelength_samples] = 0.0
    return np.fft.irfft(Z, m)[:n]


def _roughness_function(roughness) -> Optional[Callable[[np.ndarray], np.ndarray]]:
    """Normalise the roughness argument into one function of x (m) -> height (m)."""
    if roughness is None:
        return None
    if callable(roughness):
        return roughness
    if isinstance(roughness, tuple) and len(roughness) == 2 and not callable(roughness[0]) \
            and np.ndim(roughness[0]) == 1:
        xr = np.asarray(roughness[0], float)
        zr = np.asarray(roughness[1], float)
        if xr.shape != zr.shape or xr.size < 2:
            raise EHLInputError("roughness_m: (x_m, z_m) arrays must have the same length >= 2")
        if not (np.all(np.isfinite(xr)) and np.all(np.isfinite(zr))):
            raise EHLInputError("roughness_m: profile contains NaN or infinite values")
        if np.any(np.diff(xr) <= 0):
            raise EHLInputError("roughness_m: x_m must be strictly increasing")
        return lambda x: np.interp(x, xr, zr)
    parts = [_roughness_function(r) for r in roughness]
    return lambda x: sum(f(x) for f in parts)
