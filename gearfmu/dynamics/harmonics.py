"""Mesh-harmonic amplitudes of the dynamic transmission error (Xu et al. 2022 eq 10-11).

Xu et al. 2022 (section 2.2), after Kahraman & Blankenship (1997,
1999; its references [14], [15]):

    A_rms = sqrt( sum_{r=1..3} A_r^2 )                                   (eq 10)
    A_r   = sqrt( sum_{s = r N - BW/2}^{r N + BW/2} W(s) )                (eq 11)

W is the one-sided discrete autopower spectrum of the DTE against shaft order
s, N the number of teeth of the gear whose shaft orders are used, BW the
analysis bandwidth in shaft orders.  (Eq 11 as printed sums W(r s_i) over
s_i = N - BW/2 ... N + BW/2; read with the band centred on the r-th mesh
order r N, which is what "r-th mesh harmonic" means.)

Choices (written here and in docs/seed003.md)
---------------------------------------------
* **Normalisation: RMS.**  W is scaled so that its sum over all non-zero
  orders is the mean square of the fluctuating part of the signal (Parseval):
  W_0 = |X_0|^2, W_k = 2 |X_k|^2 (0 < k < n/2), W_{n/2} = |X_{n/2}|^2 for even
  n, with X = DFT(x)/n.  This is ``scipy.signal.periodogram(x,
  scaling='spectrum', window='boxcar', detrend=False)`` (its "power
  spectrum" in V^2).  A sinusoid of amplitude a at a mesh order then gives
  A_r = a/sqrt(2), its RMS value: Kahraman & Blankenship report *RMS*
  amplitudes ("equivalent root-mean-square amplitude"), and A_rms is then the
  RMS of the DTE band-passed around the first three mesh harmonics.
  ``normalization="amplitude"`` multiplies every A_r (and A_rms) by sqrt(2)
  (peak amplitude of a sinusoid), for comparison with amplitude spectra such
  as Xu et al. 2022 Figs. 10b-26b.
* **Bandwidth** BW = 2 shaft orders by default (the bins at r N - 1, r N,
  r N + 1 for a record of whole revolutions): Xu et al. 2022 do not give BW;
  Kahraman & Blankenship analyse the DTE in shaft orders with a narrow band
  around each mesh order to collect the mesh harmonic and its first shaft-order
  sidebands.  Any BW >= 0 may be given; bins whose order lies in
  [r N - BW/2, r N + BW/2] (inclusive, with a 1e-9 order tolerance) are summed.
* **Record**: the signal must span a whole number of mesh periods so that
  every mesh harmonic falls exactly on a DFT bin (no leakage).  When the
  response has other periodic content (tables periodic over several mesh
  periods: deviations that differ per tooth, hunting-tooth cycles) the record
  should span whole table periods (``MeshTables.phi_period_rad``), which the
  sweeps in :mod:`gearfmu.dynamics.sweeps` do.  No window is applied (a boxcar window is
  exact for whole periods).

:func:`mesh_order_amplitudes` is the order-tracking companion the fidelity planner's error
measure uses (docs/plan.md "Error measure"): peak amplitudes of mesh orders 1..k over the last
whole mesh periods of a record, resampled uniformly in the rigid-body mesh angle when the speed
varies.

All functions are pure; inputs are numpy arrays in any unit (the amplitudes
come out in the unit of the signal).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = [
    "HarmonicsInputError",
    "MeshHarmonics",
    "autopower_one_sided",
    "mesh_harmonics",
    "NORMALIZATIONS",
    "DEFAULT_BANDWIDTH_ORDERS",
    "OrderAmplitudes",
    "mesh_order_amplitudes",
]

#: accepted values of ``normalization`` -> factor applied to the RMS amplitudes
NORMALIZATIONS = {"rms": 1.0, "amplitude": math.sqrt(2.0)}
#: default analysis bandwidth BW of Xu et al. 2022 eq 11, in shaft orders (choice, see module doc)
DEFAULT_BANDWIDTH_ORDERS = 2.0


class HarmonicsInputError(ValueError):
    """Bad argument to the harmonic analysis; the message names the argument."""


@dataclass
class MeshHarmonics:
    """Result of :func:`mesh_harmonics` (amplitudes in the unit of the signal).

    ``A_r[r-1]`` is the r-th mesh harmonic amplitude (eq 11), ``A_rms`` eq 10;
    ``orders`` (shaft orders) and ``W`` the one-sided autopower spectrum
    (signal unit squared, RMS-normalised whatever ``normalization`` says);
    ``revolutions`` the record length in shaft revolutions, ``mean`` the mean
    of the signal.
    """

    A_r: np.ndarray
    A_rms: float
    orders: np.ndarray
    W: np.ndarray
    revolutions: float
    teeth: int
    bandwidth_orders: float
    normalization: str
    mean: float


def autopower_one_sided(signal) -> np.ndarray:
    """One-sided discrete autopower spectrum W of a real signal (RMS normalisation).

    W[0] = mean^2, W[k] = 2|X_k|^2 for 0 < k < n/2, W[n/2] = |X_{n/2}|^2 (n even),
    X = rfft(signal)/n; sum(W[1:]) equals the variance of the signal (Parseval).
    """
    x = np.asarray(signal, dtype=float)
    if x.ndim != 1 or x.size < 2:
        raise HarmonicsInputError(f"signal: expected a 1-D array of at least 2 samples, got shape {x.shape}")
    if not np.all(np.isfinite(x)):
        raise HarmonicsInputError("signal: contains NaN or infinite values")
    n = x.size
    X = np.fft.rfft(x) / n
    W = np.abs(X) ** 2
    if n % 2 == 0:
        W[1:-1] *= 2.0
    else:
        W[1:] *= 2.0
    return W


def mesh_harmonics(signal, *, samples_per_revolution: float, teeth: int, harmonics: int = 3,
                   bandwidth_orders: float = DEFAULT_BANDWIDTH_ORDERS,
                   normalization: str = "rms") -> MeshHarmonics:
    """A_r (Xu et al. 2022 eq 11) and A_rms (eq 10) of a signal sampled uniformly in shaft angle.

    Parameters
    ----------
    signal : 1-D array, equally spaced samples of the DTE (any unit) over a
        whole number of mesh periods, steady state (transients dropped).
    samples_per_revolution : samples per shaft revolution of the gear with
        ``teeth`` teeth (a float; at constant speed = revolution time / sample step).
    teeth : N of eq 11 (teeth of that gear); the r-th mesh order is r*N.
    harmonics : how many mesh harmonics enter A_rms (Xu et al. 2022: 3).
    bandwidth_orders : BW of eq 11 in shaft orders (>= 0).
    normalization : ``"rms"`` (default, Kahraman & Blankenship's RMS
        amplitudes) or ``"amplitude"`` (x sqrt(2), peak amplitude of a sinusoid).
    """
    if normalization not in NORMALIZATIONS:
        raise HarmonicsInputError(
            f"normalization: {normalization!r} unknown; choose one of {sorted(NORMALIZATIONS)}")
    try:
        spr = float(samples_per_revolution)
    except (TypeError, ValueError):
        raise HarmonicsInputError(f"samples_per_revolution: expected a number, got {samples_per_revolution!r}") from None
    if not math.isfinite(spr) or spr <= 0:
        raise HarmonicsInputError(f"samples_per_revolution: must be finite and > 0, got {samples_per_revolution!r}")
    if isinstance(teeth, bool) or int(teeth) != teeth or int(teeth) < 1:
        raise HarmonicsInputError(f"teeth: must be a positive integer, got {teeth!r}")
    teeth = int(teeth)
    if isinstance(harmonics, bool) or int(harmonics) != harmonics or int(harmonics) < 1:
        raise HarmonicsInputError(f"harmonics: must be a positive integer, got {harmonics!r}")
    harmonics = int(harmonics)
    try:
        bw = float(bandwidth_orders)
    except (TypeError, ValueError):
        raise HarmonicsInputError(f"bandwidth_orders: expected a number, got {bandwidth_orders!r}") from None
    if not math.isfinite(bw) or bw < 0:
        raise HarmonicsInputError(f"bandwidth_orders: must be finite and >= 0, got {bandwidth_orders!r}")
    W = autopower_one_sided(signal)
    n = np.asarray(signal).size
    revs = n / spr
    meshes = revs * teeth
    if abs(meshes - round(meshes)) > 1e-6 * max(1.0, meshes) or round(meshes) < 1:
        raise HarmonicsInputError(
            f"signal: the record spans {meshes:.9g} mesh periods; it must span a whole number "
            f"(n = {n} samples, samples_per_revolution = {spr!r}, teeth = {teeth})")
    top = harmonics * teeth + 0.5 * bw
    if top > 0.5 * spr * (1.0 - 1e-12):
        raise HarmonicsInputError(
            f"samples_per_revolution: {spr!r} puts the Nyquist order at {0.5 * spr:.6g}, below the "
            f"highest analysed order {top:.6g} ({harmonics} harmonics of {teeth} teeth, BW {bw:g})")
    orders = np.arange(W.size) / revs
    tol = 1e-9 * max(1.0, top)
    A = np.empty(harmonics)
    for r in range(1, harmonics + 1):
        c = r * teeth
        band = (orders >= c - 0.5 * bw - tol) & (orders <= c + 0.5 * bw + tol)
        A[r - 1] = math.sqrt(float(W[band].sum()))
    f = NORMALIZATIONS[normalization]
    A *= f
    return MeshHarmonics(A_r=A, A_rms=float(math.sqrt(float(np.sum(A ** 2)))), orders=orders, W=W,
                         revolutions=float(revs), teeth=teeth, bandwidth_orders=bw,
                         normalization=normalization, mean=float(np.mean(signal)))


@dataclass
class OrderAmplitudes:
    """Result of :func:`mesh_order_amplitudes` (in the unit of the signal).

    ``amplitudes[k-1]``: peak amplitude of mesh order k (a x cos(2 pi k phi + p) gives a);
    ``mean``: of the resampled window (its DFT bin 0); ``peak_to_peak``: max - min of the
    samples inside the window; ``periods``: whole mesh
    periods in the window; ``samples_per_period``: of the uniform resampling in mesh angle;
    ``window``: (first, last) mesh phase of the window (mesh periods)."""

    amplitudes: np.ndarray
    mean: float
    peak_to_peak: float
    periods: int
    samples_per_period: int
    window: tuple


def mesh_order_amplitudes(signal, mesh_phase, *, orders: int = 3, periods=None) -> OrderAmplitudes:
    """Peak amplitudes of mesh orders 1..``orders`` over the last whole mesh periods of a record
    (order tracking: the record resampled uniformly in mesh angle, then one DFT).

    ``mesh_phase``: the rigid-body mesh angle of every sample in mesh periods (pinion angle /
    mesh period angle; strictly increasing; at constant speed the sample times in mesh
    periods).  The window is the largest whole number of mesh periods that ends at the last
    sample (at most ``periods``).  Where the samples do not fall on a uniform grid of the mesh
    angle (the speed varies), the signal is resampled at M points per mesh period by a cubic
    spline through the samples (M: the record's mean density rounded, at least 2 x orders + 2);
    on a uniform grid the samples are used as they are.  Then, with x_j the N M resampled
    values, A_k = 2 |sum_j x_j exp(-2 pi i k j / M)| / (N M), exact for a signal whose
    content lies at whole mesh orders below M / 2 (no leakage: whole periods, no window)."""
    x = np.asarray(signal, dtype=float)
    p = np.asarray(mesh_phase, dtype=float)
    if x.ndim != 1 or x.shape != p.shape or x.size < 4:
        raise HarmonicsInputError(f"signal, mesh_phase: expected two 1-D arrays of the same length >= 4, "
                                  f"got shapes {x.shape} and {p.shape}")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(p))):
        raise HarmonicsInputError("signal, mesh_phase: contain NaN or infinite values")
    if np.any(np.diff(p) <= 0):
        raise HarmonicsInputError("mesh_phase: must be strictly increasing")
    if isinstance(orders, bool) or int(orders) != orders or int(orders) < 1:
        raise HarmonicsInputError(f"orders: must be a positive integer, got {orders!r}")
    orders = int(orders)
    span = float(p[-1] - p[0])
    n_per = int(math.floor(span + 1e-9))
    if periods is not None:
        n_per = min(n_per, int(periods))
    if n_per < 1:
        raise HarmonicsInputError(f"mesh_phase: the record spans {span:.6g} mesh periods; at least one is needed")
    m = max(int(round((x.size - 1) / span)), 2 * orders + 2)
    p0 = float(p[-1]) - n_per
    q = p0 + np.arange(n_per * m) / m  # the periodic grid: the window's end (= its start) not repeated
    i0 = max(int(np.searchsorted(p, p0, side="left")) - 3, 0)
    j0 = x.size - 1 - n_per * m
    if j0 >= 0 and np.allclose(p[j0:x.size - 1], q, rtol=0.0, atol=1e-9):  # already uniform in mesh angle
        xq = x[j0:x.size - 1]
    else:
        from scipy.interpolate import CubicSpline  # only where the speed varies
        xq = CubicSpline(p[i0:], x[i0:])(q)
    spec = np.fft.rfft(xq) / xq.size
    amp = np.array([2.0 * abs(spec[k * n_per]) for k in range(1, orders + 1)])  # k n_per < N M / 2
    inside = x[p >= p0 - 1e-9]
    return OrderAmplitudes(amplitudes=amp, mean=float(np.mean(xq)), peak_to_peak=float(np.ptp(inside)),
                           periods=n_per, samples_per_period=m, window=(p0, float(p[-1])))
