"""Elastic deformation of a line contact (seed 000 eq 4), dimensionless form.

Seed 000 eq 4 (the half-space line-contact solution, Johnson 1985 ch. 2):

    v(x) = -(2 / (pi E')) * integral p(x') ln (x - x')^2 dx'
         = -(4 / (pi E')) * integral p(x') ln|x - x'| dx'     (+ a constant)

with the reduced modulus E' = 2 / ((1 - nu1^2)/E1 + (1 - nu2^2)/E2).  In the
Hertzian scaling x = b X, p = p_h P, h = (b^2 / R) H (b = sqrt(8 w R / (pi E')),
p_h = b E' / (4 R)) this is

    V(X) = -(1/pi) * integral P(X') ln|X - X'| dX'            (+ a constant)

which is absorbed into the rigid-body approach H0.

Discretisation (Venner & Lubrecht 2000): P piecewise constant on
cells of width dX around each node, integrated exactly, giving the Toeplitz
coefficients

    K_t = f((t + 1/2) dX) - f((t - 1/2) dX),   f(x) = x (ln|x| - 1),

so V_i = -(1/pi) * sum_j K_|i-j| P_j.  The product of the Toeplitz matrix
with P is evaluated by FFT (zero-padded circulant embedding) in
O(N log N); :func:`deformation_direct` is the O(N^2) sum used to check it.
"""
from __future__ import annotations

import numpy as np
from numba import njit
from scipy import fft as _fft


def kernel_coefficients(n_nodes: int, dX: float) -> np.ndarray:
    """Toeplitz coefficients K_t, t = 0..n_nodes-1 (dimensionless, spacing dX)."""
    t = np.arange(n_nodes, dtype=float)
    a = (t + 0.5) * dX
    b = (t - 0.5) * dX

    def f(x):
        ax = np.abs(x)
        out = np.zeros_like(x)
        nz = ax > 0
        out[nz] = x[nz] * (np.log(ax[nz]) - 1.0)
        return out

    return f(a) - f(b)


@njit(cache=False, fastmath=False)
def _fft_inplace(re, im, twr, twi, sign):
    """Iterative radix-2 FFT of (re, im) in place (length a power of 2);
    twiddles exp(-2 pi i k/n) = twr + i twi for k < n/2; ``sign`` = +1 forward,
    -1 inverse (no 1/n scaling)."""
    n = re.size
    j = 0
    for i in range(1, n):
        bit = n >> 1
        while j & bit:
            j ^= bit
            bit >>= 1
        j ^= bit
        if i < j:
            t = re[i]
            re[i] = re[j]
            re[j] = t
            t = im[i]
            im[i] = im[j]
            im[j] = t
    length = 2
    while length <= n:
        half = length // 2
        step = n // length
        for k in range(half):
            wr = twr[k * step]
            wi = sign * twi[k * step]
            for i in range(k, n, length):
                i2 = i + half
                vr = re[i2] * wr - im[i2] * wi
                vi = re[i2] * wi + im[i2] * wr
                re[i2] = re[i] - vr
                im[i2] = im[i] - vi
                re[i] += vr
                im[i] += vi
        length <<= 1


@njit(cache=False)
def fft_deformation(P, khr, khi, twr, twi, K):
    """V = -(1/pi) K * P by zero-padded circular convolution (numba FFT);
    (khr, khi) is the FFT of the circulant embedding of -(1/pi) K with a
    period m >= 2n - 3: exact for the interior nodes 1..n-2; the two end
    nodes (zero in the EHL problem) are added by direct sums."""
    n = P.size
    m = khr.size
    re = np.zeros(m)
    im = np.zeros(m)
    for i in range(1, n - 1):
        re[i] = P[i]
    _fft_inplace(re, im, twr, twi, 1.0)
    for i in range(m):
        a = re[i] * khr[i] - im[i] * khi[i]
        b = re[i] * khi[i] + im[i] * khr[i]
        re[i] = a
        im[i] = b
    _fft_inplace(re, im, twr, twi, -1.0)
    out = np.empty(n)
    p0 = P[0]
    p1 = P[n - 1]
    for i in range(n):
        out[i] = re[i] / m - (K[i] * p0 + K[n - 1 - i] * p1) / np.pi
    return out


class DeformationOperator:
    """Fast evaluation of V = -(1/pi) K P on one uniform grid (FFT convolution,
    radix-2 FFT compiled with numba so that relaxation loops stay in numba)."""

    def __init__(self, n_nodes: int, dX: float):
        self.n = int(n_nodes)
        self.dX = float(dX)
        self.K = kernel_coefficients(self.n, self.dX)
        m = 1
        while m < 2 * self.n - 3:
            m *= 2
        c = np.zeros(m)
        c[: self.n] = self.K
        c[m - self.n + 1:] = self.K[1:][::-1]
        self._m = m
        khat = _fft.fft(c) * (-1.0 / np.pi)
        self.khr = np.ascontiguousarray(khat.real)
        self.khi = np.ascontiguousarray(khat.imag)
        ang = -2.0 * np.pi * np.arange(m // 2) / m
        self.twr = np.cos(ang)
        self.twi = np.sin(ang)

    def __call__(self, P: np.ndarray) -> np.ndarray:
        """Return V_i = -(1/pi) sum_j K_|i-j| P_j for P on this grid."""
        return fft_deformation(np.ascontiguousarray(P, dtype=np.float64),
                               self.khr, self.khi, self.twr, self.twi, self.K)


@njit(cache=False)
def deformation_direct(P, K):
    """O(N^2) reference sum V_i = -(1/pi) sum_j K_|i-j| P_j."""
    n = P.size
    out = np.zeros(n)
    for i in range(n):
        s = 0.0
        for j in range(n):
            s += K[abs(i - j)] * P[j]
        out[i] = -s / np.pi
    return out
