"""Elastic deformation of a line contact (Zhao et al. 2022 eq 4), dimensionless form.

Zhao et al. 2022 eq 4 (the half-space line-contact solution, Johnson 1985 ch. 2):

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
The FFT (:func:`conv_real`) packs the real pressure into a complex sequence
of half length and uses that the symmetric embedding has a real spectrum.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit


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


def stage_twiddles(twr: np.ndarray, twi: np.ndarray, m: int):
    """Per-stage contiguous twiddle table of the length-m/2 complex FFT of
    :func:`conv_real`: entry h + k (k < h, h = 1, 2, 4, .., m/4) is
    exp(-2 pi i k / (2 h)), copied from the base table twr/twi[j] =
    exp(-2 pi i j / m) at j = k m / (2 h) (same values bit for bit, so the FFT
    result is unchanged; the butterfly loop then reads its twiddles
    contiguously, docs/ehl.md "Speed").  Entry 0 is unused."""
    N = m // 2
    sr = np.zeros(N)
    si = np.zeros(N)
    h = 1
    while h < N:
        j = np.arange(h) * (m // (2 * h))
        sr[h:2 * h] = twr[j]
        si[h:2 * h] = twi[j]
        h *= 2
    return sr, si


#: bit reversal of a byte (:func:`_bitrev`)
_REV8 = np.array([int(f"{i:08b}"[::-1], 2) for i in range(256)], dtype=np.int64)


@njit(cache=True, error_model="numpy", inline="always")
def _bitrev(k, bits):
    """k (< 2^32) with its lowest ``bits`` bits in reverse order (byte table)."""
    r = ((_REV8[k & 255] << 24) | (_REV8[(k >> 8) & 255] << 16)
         | (_REV8[(k >> 16) & 255] << 8) | _REV8[(k >> 24) & 255])
    return r >> (32 - bits)


@njit(cache=True, error_model="numpy", inline="always")
def _butterfly(re, im, i, half, wr, wi):
    """Radix-2 butterfly of entries i and i + half with the twiddle wr + i wi."""
    i2 = i + half
    vr = re[i2] * wr - im[i2] * wi
    vi = re[i2] * wi + im[i2] * wr
    re[i2] = re[i] - vr
    im[i2] = im[i] - vi
    re[i] += vr
    im[i] += vi


@njit(cache=True, error_model="numpy")
def _cfft_stages(re, im, N, sr, si, sign, skip_first=False):
    """Butterfly stages of :func:`_cfft` on input already in bit-reversed
    order (natural-order output).  Stages with >= 8 twiddles run block by
    block on slices of the two halves (separate views: the compiler proves
    them apart and vectorises the twiddle loop; the same operations on the
    same numbers as the scalar loop, so the same bits), shorter ones twiddle
    by twiddle.  ``skip_first``: the caller has done the length-2 stage."""
    if not skip_first:
        for i in range(0, N - 1, 2):          # length-2 stage: twiddle 1
            ar = re[i]
            ai = im[i]
            br = re[i + 1]
            bi = im[i + 1]
            re[i] = ar + br
            im[i] = ai + bi
            re[i + 1] = ar - br
            im[i + 1] = ai - bi
    length = 4
    while length <= N:
        half = length >> 1
        if half >= 8:
            wr = sr[half:length]
            wi = si[half:length]
            for s in range(0, N, length):
                xr = re[s:s + half]
                xi = im[s:s + half]
                yr = re[s + half:s + length]
                yi = im[s + half:s + length]
                for k in range(half):
                    twi = sign * wi[k]
                    vr = yr[k] * wr[k] - yi[k] * twi
                    vi = yr[k] * twi + yi[k] * wr[k]
                    ar = xr[k]
                    ai = xi[k]
                    yr[k] = ar - vr
                    yi[k] = ai - vi
                    xr[k] = ar + vr
                    xi[k] = ai + vi
        else:
            for k in range(half):
                wr_ = sr[half + k]
                wi_ = sign * si[half + k]
                for s in range(0, N, length):
                    _butterfly(re, im, s + k, half, wr_, wi_)
        length <<= 1


@njit(cache=True, error_model="numpy")
def _cfft(re, im, N, sr, si, sign):
    """Iterative radix-2 complex FFT of re[0:N] + i im[0:N] in place (N a
    power of 2, no 1/N scaling); twiddles of the stage of half length h at
    sr/si[h:2h] (:func:`stage_twiddles`); ``sign`` = +1 forward, -1 inverse.
    Bit-reversal permutation, then :func:`_cfft_stages` (:func:`conv_real`
    writes its input in bit-reversed order instead)."""
    bits = 0
    while (1 << bits) < N:
        bits += 1
    for i in range(1, N):
        j = _bitrev(i, bits)
        if i < j:
            t = re[i]
            re[i] = re[j]
            re[j] = t
            t = im[i]
            im[i] = im[j]
            im[j] = t
    _cfft_stages(re, im, N, sr, si, sign)


@njit(cache=True, error_model="numpy", inline="always")
def _spectrum_times(re, im, kk, jj, wr, wi, kh, yr, yi, k):
    """Entry k of the length-m spectrum of the packed real sequence (entries kk
    and jj = N - kk of its half-length FFT, twiddle wr + i wi) times kh, into
    yr/yi[k] (:func:`conv_real`)."""
    zr = re[kk]
    zi = im[kk]
    cr = re[jj]
    ci = -im[jj]
    er = 0.5 * (zr + cr)
    ei = 0.5 * (zi + ci)
    orr = 0.5 * (zi - ci)
    oi = -0.5 * (zr - cr)
    yr[k] = (er + wr * orr - wi * oi) * kh
    yi[k] = (ei + wr * oi + wi * orr) * kh


@njit(cache=True, error_model="numpy")
def conv_real(P, o, n, khr, mo, m, twr, twi, to, K, ko, re, im, yr, yi, V):
    """V_i = -(1/pi) sum_j K_|i-j| P_{o+j} (i, j < n) by FFT.

    Circulant embedding of period m >= 2n - 3 (exact for the interior nodes;
    the end nodes are added by direct sums); ``khr[mo:mo+m]`` is the
    spectrum of -(1/pi) times the embedded kernel, which is *real* because
    the embedding is symmetric.  The real input is packed into a complex
    sequence of length m/2 (even samples real, odd samples imaginary), so
    one complex FFT of length m/2 forward and one back replace two of length
    m (standard real-FFT packing, e.g. Press et al., Numerical Recipes
    sec. 12.3).  Twiddles ``twr/twi[to:to+m/2]`` = exp(-2 pi i k/m), followed
    by the FFT's stage table (:func:`stage_twiddles`) at ``[to+m/2:to+m]``.
    Work buffers re, im, yr, yi need m/2 + 1 entries."""
    N = m // 2
    bits = 0
    while (1 << bits) < N:
        bits += 1
    # packed input written in bit-reversed order (the FFT stages need no
    # permutation); its second half is zero (N >= n - 1), i.e. the odd
    # bit-reversed positions, so the length-2 stage copies each even entry
    # into the odd one after it (x + 0 = x - 0 = x) and is done here
    for k in range(N // 2):
        a = 2 * k
        j = _bitrev(k, bits)
        vr = P[o + a] if (a >= 1 and a <= n - 2) else 0.0
        vi = P[o + a + 1] if a + 1 <= n - 2 else 0.0
        re[j] = vr
        re[j + 1] = vr
        im[j] = vi
        im[j + 1] = vi
    _cfft_stages(re, im, N, twr[to + N:], twi[to + N:], 1.0, True)
    # spectrum of the real input (k = 0 and N: the pair (0, 0); else (k, N - k)) times
    # the kernel spectrum
    _spectrum_times(re, im, 0, 0, twr[to], twi[to], khr[mo], yr, yi, 0)
    for k in range(1, N):
        _spectrum_times(re, im, k, N - k, twr[to + k], twi[to + k], khr[mo + k], yr, yi, k)
    _spectrum_times(re, im, 0, 0, -1.0, 0.0, khr[mo + N], yr, yi, N)
    for k in range(N):
        j = N - k
        ar = yr[k]
        ai = yi[k]
        cr = yr[j]
        ci = -yi[j]
        dr = 0.5 * (ar - cr)
        di = 0.5 * (ai - ci)
        wr = twr[to + k]
        wi = -twi[to + k]
        j = _bitrev(k, bits)
        re[j] = 0.5 * (ar + cr) - (dr * wi + di * wr)
        im[j] = 0.5 * (ai + ci) + (dr * wr - di * wi)
    _cfft_stages(re, im, N, twr[to + N:], twi[to + N:], -1.0)
    inv = 1.0 / N
    p0 = P[o]
    p1 = P[o + n - 1]
    for i in range(0, n, 2):
        V[i] = re[i >> 1] * inv - (K[ko + i] * p0 + K[ko + n - 1 - i] * p1) / math.pi
    for i in range(1, n, 2):
        V[i] = im[i >> 1] * inv - (K[ko + i] * p0 + K[ko + n - 1 - i] * p1) / math.pi


@njit(cache=True, error_model="numpy")
def fft_deformation(P, khr, khi, twr, twi, K):
    """V = -(1/pi) K * P by zero-padded circular convolution (numba FFT,
    :func:`conv_real`); (khr, khi) is the FFT of the circulant embedding of
    -(1/pi) K with a period m >= 2n - 3 (khi is zero up to round-off: the
    embedding is symmetric); exact for the interior nodes 1..n-2, the two
    end nodes are added by direct sums."""
    n = P.size
    m = khr.size
    buf = np.zeros((4, m // 2 + 2))
    out = np.empty(n)
    conv_real(P, 0, n, khr, 0, m, twr, twi, 0, K, 0, buf[0], buf[1], buf[2], buf[3], out)
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
        import scipy.fft as _fft  # scipy.fft: heavy import, only when a kernel is set up
        khat = _fft.fft(c) * (-1.0 / np.pi)
        self.khr = np.ascontiguousarray(khat.real)
        self.khi = np.ascontiguousarray(khat.imag)
        ang = -2.0 * np.pi * np.arange(m // 2) / m
        twr, twi = np.cos(ang), np.sin(ang)
        sr, si = stage_twiddles(twr, twi, m)
        # base table, then the FFT's stage table (conv_real's layout)
        self.twr = np.concatenate((twr, sr))
        self.twi = np.concatenate((twi, si))

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
