"""Elastic deformation of a line contact (seed 000 eq 4), dimensionless form.

Seed 000 eq 4 (the half-space line-contact solution, Johnson 1985 ch. 2):

    v(x) = -(2 / (pi E')) * integral p(x') ln (x - x')^2 dx'
         = -(4 / (pi E')) * integral p(x') ln|x - x'| dx'     (+ a constant)

with the reduced modulus E' = 2 / ((1 - nu1^2)/E1 + (1 - nu2^2)/E2).  In the
Hertzian scaling x = b X, p = p_h P, h = (b^2 / R) H (b = sqrt(8 w R / (pi E')),
p_h = b E' / (4 R)) this is

    V(X) = -(1/pi) * integral P(X') ln|X - X'| dX'            (+ a constant)

which is absorbed into the rigid-body approach H0.

Discretisation (Venner & Lubrecht 2000, section 2.4): P piecewise constant on
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


class DeformationOperator:
    """Fast evaluation of V = -(1/pi) K P on one uniform grid (FFT convolution)."""

    def __init__(self, n_nodes: int, dX: float):
        self.n = int(n_nodes)
        self.dX = float(dX)
        self.K = kernel_coefficients(self.n, self.dX)
        m = _fft.next_fast_len(2 * self.n, real=True)
        c = np.zeros(m)
        c[: self.n] = self.K
        c[m - self.n + 1:] = self.K[1:][::-1]
        self._m = m
        self._kh = _fft.rfft(c) * (-1.0 / np.pi)

    def __call__(self, P: np.ndarray) -> np.ndarray:
        """Return V_i = -(1/pi) sum_j K_|i-j| P_j for P on this grid."""
        return _fft.irfft(_fft.rfft(P, self._m) * self._kh, self._m)[: self.n]


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
