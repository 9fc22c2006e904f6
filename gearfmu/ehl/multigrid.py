"""Multilevel solver object of the line-contact EHL problem (the one multigrid core).

:class:`FlatMultigrid` holds a hierarchy of uniform grids in flat arrays and
drives the compiled kernels (:mod:`.mgkernels` grid operators, :mod:`.mgcycle`
cycles and convergence loop, :mod:`.coarse_newton` coarsest-grid solve):
starts (Hertzian pressure, a given pressure, full multigrid), the transient
time term, and the iteration.  :class:`EHLParams` are the dimensionless
parameters of one problem.  Every solver of :mod:`gearfmu.ehl` (steady,
transient, mesh films) uses this class.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .deformation import kernel_coefficients, stage_twiddles
from .errors import EHLInputError
from .mgcycle import OPT_DEFAULTS, OPT_KEYS, _iterate, cached_schedule
from .mgkernels import N_DIRECT, _coef, _film, _fmg_prolong


@dataclass
class EHLParams:
    """Dimensionless parameters of one line-contact problem (Venner-Lubrecht scaling)."""

    lam: float          # lambda-bar = 12 eta0 u_m R^2 / (b^3 ph)
    A: float            # ln(eta0) + 9.67 (eta0 in Pa s)
    z: float            # Roelands index
    php0: float         # ph / p0
    c1: float           # 0.59e9 Pa / ph (Dowson-Higginson)
    compressible: bool
    x_in: float
    x_out: float


#: Speed path (docs/ehl.md; opt-in, pass as multigrid options:
#: ``solve_line_contact(..., **SPEED_SETTING)``): the first relaxation setting of
#: :data:`.attempts.RELAXATION_SETTINGS` with F-cycles and the coarsest grid solved
#: by one Newton step (:func:`_coarse_newton`) instead of 10 point sweeps.
#: Fewer and cheaper cycles than the default W-cycles (benchmarks/bench_ehl.py
#: --speed), but without the fallback settings of the default path (passing
#: options disables them); the default path tries similar cycles first
#: (:data:`.attempts.FAST_SETTING`, :data:`.attempts.FAST_ROBUST_SETTING`, with an FMG start).
SPEED_SETTING = dict(switch=0.3, nu1=2, nu2=1, omega_gs=0.6, omega_j=0.5, load_mode=1,
                     c_h0=0.1, stick=10.0, gamma="F", coarse_newton=1)

#: stopping at about the discretisation accuracy of the default grids (docs/ehl.md):
#: with :data:`SPEED_SETTING` the algebraic error of H_c left stays below the
#: discretisation error (benchmarks/bench_ehl.py --speed)
DISC_TOLERANCES = dict(tol_pressure=1e-3, tol_load=1e-4, tol_residual=1e-4)


#: grid constants (node positions, kernel coefficients, kernel spectra, FFT
#: twiddles) per grid hierarchy, shared by every :class:`FlatMultigrid` on the
#: same grid (building them is a noticeable part of a small solve);
#: read-only arrays (numpy flag), so that no solve can change them for the solves after it
_GRID_CACHE: dict = {}
_GRID_CACHE_SIZE = 64


def _grid_constants(ns, ms, off, moff, toff, x_in, x_out):
    """(X per level, dX per level, kernel coefficients, kernel spectrum real/imag,
    twiddles cos/sin) of the level hierarchy with ``ns`` nodes per level."""
    X = [np.linspace(x_in, x_out, n) for n in ns]
    dx = np.array([x[1] - x[0] for x in X])
    K = np.concatenate([kernel_coefficients(n, d) for n, d in zip(ns, dx)])
    khr = np.zeros(max(int(moff[-1]), 1))
    khi = np.zeros_like(khr)
    twr = np.zeros(max(int(toff[-1]), 1))
    twi = np.zeros_like(twr)
    for l, (n, m) in enumerate(zip(ns, ms)):
        if m == 0:
            continue
        Kl = K[off[l]:off[l] + n]
        c = np.zeros(m)
        c[:n] = Kl
        c[m - n + 1:] = Kl[1:][::-1]
        import scipy.fft as _fft  # scipy.fft: heavy import, only when a kernel is set up
        kh = _fft.fft(c) * (-1.0 / np.pi)
        khr[moff[l]:moff[l] + m] = kh.real
        khi[moff[l]:moff[l] + m] = kh.imag
        ang = -2.0 * np.pi * np.arange(m // 2) / m
        cw, sw = np.cos(ang), np.sin(ang)
        twr[toff[l]:toff[l] + m // 2] = cw
        twi[toff[l]:toff[l] + m // 2] = sw
        # the FFT's per-stage table follows the base table (conv_real)
        sr, si = stage_twiddles(cw, sw, m)
        twr[toff[l] + m // 2:toff[l] + m] = sr
        twi[toff[l] + m // 2:toff[l] + m] = si
    return X, dx, K, khr, khi, twr, twi


#: per (levels, coarsest intervals, domain): node counts, total nodes, longest
#: FFT, the level index table, the grid constants and 0.5 X^2 of every level
_LAYOUT_CACHE: dict = {}


def _layout(n_levels, n_coarse, x_in, x_out):
    key = (n_levels, n_coarse, x_in, x_out)
    lay = _LAYOUT_CACHE.get(key)
    if lay is not None:
        return lay
    ns = [n_coarse * 2 ** k + 1 for k in range(n_levels)]
    off = np.concatenate(([0], np.cumsum(ns)))
    ms = []
    for n in ns:
        m = 1
        while m < 2 * n - 3:
            m *= 2
        ms.append(m if n > N_DIRECT else 0)
    moff = np.concatenate(([0], np.cumsum(ms)))
    # per level: m/2 twiddles exp(-2 pi i k/m), then the FFT's stage table
    toff = np.concatenate(([0], np.cumsum(ms)))
    iarr = np.zeros((6, n_levels), dtype=np.int64)
    iarr[0] = off[:-1]
    iarr[1] = ns
    iarr[2] = off[:-1]          # kernel coefficients share the level offsets
    iarr[3] = moff[:-1]
    iarr[4] = ms
    iarr[5] = toff[:-1]
    gkey = (tuple(ns), x_in, x_out)
    cached = _GRID_CACHE.get(gkey)
    if cached is None:
        cached = _grid_constants(ns, ms, off, moff, toff, x_in, x_out)
        for a in (*cached[0], *cached[1:]):
            a.flags.writeable = False    # shared by every solver on this grid: never written
        if len(_GRID_CACHE) >= _GRID_CACHE_SIZE:
            _GRID_CACHE.pop(next(iter(_GRID_CACHE)))
        _GRID_CACHE[gkey] = cached
    base0 = np.concatenate([0.5 * x ** 2 for x in cached[0]])
    base0.flags.writeable = False
    iarr.flags.writeable = False
    lay = (ns, int(off[-1]), max(max(ms), 1), iarr, cached, base0)
    if len(_LAYOUT_CACHE) >= _GRID_CACHE_SIZE:
        _LAYOUT_CACHE.pop(next(iter(_LAYOUT_CACHE)))
    _LAYOUT_CACHE[key] = lay
    return lay


class FlatMultigrid:
    """Level hierarchy in flat arrays for the compiled W-cycle (see module doc).

    ``prm`` is an :class:`.multigrid.EHLParams`; level 0 is the coarsest
    (``n_coarse`` intervals), level ``n_levels - 1`` the finest.  ``rough_fn``
    maps X (Hertz units) to the roughness in film units (h R / b^2)."""

    def __init__(self, prm, n_levels: int, n_coarse: int, rough_fn=None, **opts):
        bad = set(opts) - set(OPT_KEYS) - {"gamma"}
        if bad:
            raise EHLInputError(f"unknown multigrid option(s) {sorted(bad)!r}; "
                                f"known: {list(OPT_KEYS) + ['gamma']}")
        self.prm = prm
        self.n_levels = int(n_levels)
        o = dict(OPT_DEFAULTS)
        o.update({k: v for k, v in opts.items() if k != "gamma"})
        self.opts = o
        self.gamma = opts.get("gamma", 2)
        lay = _layout(self.n_levels, int(n_coarse), float(prm.x_in), float(prm.x_out))
        ns, ntot, mmax, iarr, cached, base0 = lay
        self.iarr = iarr.copy()
        # shared between solvers on the same grid (never written after construction)
        self.X, self.dx, self.K, self.khr, self.khi, self.twr, self.twi = cached
        z = lambda: np.zeros(ntot)
        self.P, self.H, self.f, self.tauH = z(), z(), z(), z()
        if rough_fn is None:
            self.rough = np.zeros(ntot)
            self.base = base0.copy()
        else:
            self.rough = np.concatenate([np.asarray(rough_fn(x), float) for x in self.X])
            self.base = base0 + self.rough
        self.work = [z() for _ in range(7)]   # rho eps dle drho delta wrk Pold
        self.H0 = np.zeros(n_levels)
        self.H0old = np.zeros(n_levels)
        self.mode = np.zeros(ntot, dtype=np.int8)
        self.g = np.full(n_levels, 0.5 * np.pi)
        self.re = np.zeros(mmax + 4)
        self.im = np.zeros(mmax + 4)
        self.V = np.zeros(max(ns))
        self.prmv = np.array([prm.lam, prm.A, prm.z, prm.php0, prm.c1,
                              1.0 if prm.compressible else 0.0, prm.x_in, prm.x_out, 1.0])
        self.optv = np.array([float(o[k]) for k in OPT_KEYS])
        self.sched = cached_schedule(n_levels, self.gamma)

    # -- access ---------------------------------------------------------------
    def _sl(self, l):
        o, n = self.iarr[0, l], self.iarr[1, l]
        return slice(int(o), int(o + n))

    @property
    def top(self):
        return self.n_levels - 1

    def level_P(self, l=None):
        return self.P[self._sl(self.top if l is None else l)]

    def level_H(self, l=None):
        return self.H[self._sl(self.top if l is None else l)]

    def state(self):
        S = (self.P, self.H, self.f, self.tauH, self.base, *self.work, self.H0, self.g,
             self.iarr, self.dx, self.K, self.khr, self.khi, self.twr, self.twi, self.re,
             self.im, self.V, self.prmv, self.optv, self.H0old, self.mode)
        return S

    def set_roughness_scale(self, a: float):
        self.base[:] = np.concatenate([0.5 * x ** 2 for x in self.X]) + a * self.rough
        self.update_film(self.top)

    def update_film(self, l):
        _film(l, self.P, self.H, self.base, self.tauH, self.H0, self.iarr, self.K, self.khr,
              self.khi, self.twr, self.twi, self.re, self.im, self.V)

    def load(self, l=None) -> float:
        l = self.top if l is None else l
        return float(self.dx[l] * np.sum(self.P[self._sl(l)]))

    # -- transient term (docs/ehl_transient.md; default off) -------------------
    def rho_H(self, l=None) -> np.ndarray:
        """rho_i H_i on level l (finest by default; Dowson-Higginson rho of
        the current P), the quantity whose time derivative Zhao et al. 2022 eq 2 keeps."""
        l = self.top if l is None else l
        rho, eps, dle, drho = self.work[0], self.work[1], self.work[2], self.work[3]
        _coef(l, self.P, self.H, rho, eps, dle, drho, self.iarr, self.prmv)
        sl = self._sl(l)
        return rho[sl] * self.H[sl]

    def set_time_term(self, c_t: float, f_top=None, characteristic: bool = False):
        """Implicit time coefficient ``c_t`` (1/dT for BDF1, 1.5/dT for BDF2, 0:
        steady) on every level and the old-time right-hand side ``f_top`` of the
        finest grid (BDF1: -(rho H)^(n-1)/dT; BDF2: (-2 (rho H)^(n-1) +
        0.5 (rho H)^(n-2))/dT; None: zero).  The coarse levels receive it through
        the restricted residual (FAS).  Not combined with ``defect``.
        ``characteristic``: the time term replaces the wedge term (Venner &
        Lubrecht's discretisation along the characteristic at Courant 1, dT = dX:
        c_t = 1.5/dX, f = (-2 (rho H)^(n-1)_(i-1) + 0.5 (rho H)^(n-2)_(i-2))/dX)."""
        c_t = float(c_t)
        if not math.isfinite(c_t) or c_t < 0.0:
            raise EHLInputError(f"c_t={c_t!r}: must be finite and >= 0")
        self.opts["c_t"] = c_t
        self.optv[OPT_KEYS.index("c_t")] = c_t
        self.opts["c_char"] = 1 if characteristic else 0
        self.optv[OPT_KEYS.index("c_char")] = self.opts["c_char"]
        sl = self._sl(self.top)
        if f_top is None:
            self.f[sl] = 0.0
        else:
            f_top = np.asarray(f_top, float)
            if f_top.shape != (sl.stop - sl.start,):
                raise EHLInputError(f"f_top: need {sl.stop - sl.start} finest-grid values, "
                                    f"got shape {f_top.shape}")
            self.f[sl] = f_top
            self.f[sl.start] = self.f[sl.stop - 1] = 0.0

    # -- starts ---------------------------------------------------------------
    def start(self, P_top: np.ndarray, Hc: float):
        """Finest-grid pressure ``P_top`` and H0 such that the central film
        is ``Hc`` (Venner-Lubrecht units)."""
        t = self.top
        sl = self._sl(t)
        self.prmv[8] = Hc
        P = np.clip(np.asarray(P_top, float), 0.0, None)
        P[0] = P[-1] = 0.0
        self.P[sl] = P
        self.f[:] = 0.0
        self.tauH[:] = 0.0
        self.H0[t] = 0.0
        self.update_film(t)
        self.H0[t] = Hc - float(np.interp(0.0, self.X[t], self.H[sl]))
        self.update_film(t)

    def hertz_start(self, Hc: float):
        X = self.X[self.top]
        self.start(np.sqrt(np.clip(1.0 - X ** 2, 0.0, None)), Hc)

    def _substate(self, lo: int, hi: int):
        """State tuple of the sub-hierarchy of levels lo..hi (level lo is its
        coarsest, hi its finest); per-level arrays are views, so the compiled
        kernels update this object's arrays."""
        S = list(self.state())
        sl = slice(lo, hi + 1)
        S[12] = self.H0[sl]
        S[13] = self.g[sl]
        S[14] = np.ascontiguousarray(self.iarr[:, sl])
        S[15] = self.dx[sl]
        S[26] = self.H0old[sl]
        return tuple(S)

    def _prolong_solution(self, l: int):
        """Start level l from the solution on level l-1: cubic (4-point,
        Venner & Lubrecht 2000 sec. 3.x "FMG interpolation of higher order
        than the discretisation": 2nd-order discretisation -> order >= 3)
        interpolation of P, clipped to P >= 0; H0 carried over."""
        _fmg_prolong(l, self.state())

    def fmg_start(self, Hc: float, cycles_per_level: int = 1, coarse_cycles: int = 20,
                  coarse_tol: float = 1e-4, alpha_dx: float = math.inf, alpha_eff: float = 0.0):
        """Full multigrid start (Venner & Lubrecht 2000 ch. 3 and their EHL
        chapters; Brandt 1984): solve on a coarse sub-hierarchy first, then
        interpolate the solution up (:meth:`_prolong_solution`, cubic) and do
        ``cycles_per_level`` cycles on each finer sub-hierarchy, up to (not
        including) the finest level, which is then started from the
        interpolated solution.  ``self.fmg_hc``: central film (Venner-Lubrecht
        units) on each FMG level after its cycles (for a Richardson estimate of
        the discretisation error).

        The FMG starts at the coarsest level with dX^2 <= Hc (Venner-Lubrecht
        units; ``Hc`` the expected central film): coarser grids cannot carry
        the film (the FAS corrections diverge at high M, docs/ehl.md).  The
        first sub-hierarchy is that level and the next finer one, started
        from the Hertzian pressure and iterated until the pressure change,
        load error and scaled residual fall below ``coarse_tol`` (at most
        ``coarse_cycles``).  Returns the number of cycles on each level."""
        t = self.top
        self.fmg_hc = []
        lo = 0
        while lo < t and self.dx[lo] ** 2 > Hc:
            lo += 1
        first = lo + 1
        while first < t and alpha_eff * self.dx[first] > alpha_dx:
            first += 1
        first = min(first, t)
        counts = []
        if first >= t:
            self.hertz_start(Hc)
            return counts
        X = self.X[first]
        sl = self._sl(first)
        self.prmv[8] = Hc
        self.f[:] = 0.0
        self.tauH[:] = 0.0
        self.P[sl] = np.sqrt(np.clip(1.0 - X ** 2, 0.0, None))
        self.P[sl.start] = self.P[sl.stop - 1] = 0.0
        self.H0[first] = 0.0
        self.update_film(first)
        self.H0[first] = Hc - float(np.interp(0.0, X, self.H[sl]))
        self.update_film(first)
        self.optv[:] = [float(self.opts[k]) for k in OPT_KEYS]
        # the spike Newton step belongs to the finest grid's iteration, not to
        # the coarse sub-hierarchies of the start
        self.optv[OPT_KEYS.index("spike_newton")] = 0.0
        for l in range(first, t):
            if l > first:
                self._prolong_solution(l)
            ncyc = coarse_cycles if l == first else cycles_per_level
            tol = coarse_tol if l == first else 0.0
            hist = np.full((6, ncyc), np.nan)
            k = _iterate(cached_schedule(l - lo + 1, self.gamma), self._substate(lo, l), hist,
                         int(ncyc), 1, tol, tol, tol, 1.0, 6 if l == first else 10 ** 6, 0.0)
            counts.append(abs(int(k)))
            Xl = self.X[l]
            self.fmg_hc.append(float(np.interp(0.0, Xl, self.level_H(l))))
            if not np.all(np.isfinite(self.level_P(l))):
                break
        self._prolong_solution(t)
        return counts

    # -- iteration ------------------------------------------------------------
    def iterate(self, max_cycles=60, min_cycles=2, tol_pressure=1e-5, tol_load=1e-6,
                tol_residual=1e-6, stall_window=12, tol_film=1.0, tol_discretisation=0.0,
                tol_discretisation_residual=math.inf, tol_discretisation_load=math.inf):
        """Compiled W-cycles; returns (converged, cycles, history dict).
        ``tol_discretisation`` > 0: also stop when the relative film change per
        cycle and the load error are below it, the scaled residual below
        ``tol_discretisation_residual`` and the load error below
        ``tol_discretisation_load`` (a finite value: the finest-grid pressure is
        scaled to the load when only the load is missing, :func:`.mgcycle._iterate`)."""
        hist = np.full((6, max_cycles), np.nan)
        self.optv[:] = [float(self.opts[k]) for k in OPT_KEYS]
        k = _iterate(self.sched, self.state(), hist, int(max_cycles), int(min_cycles),
                     float(tol_pressure), float(tol_load), float(tol_residual),
                     float(tol_film), int(stall_window), float(tol_discretisation),
                     float(tol_discretisation_residual), float(tol_discretisation_load))
        nc = abs(int(k))
        h = {"pressure_change": hist[0, :nc].tolist(), "load_balance": hist[1, :nc].tolist(),
             "reynolds_residual": hist[2, :nc].tolist(), "H_central": hist[3, :nc].tolist(),
             "H_min": hist[4, :nc].tolist(), "film_change": hist[5, :nc].tolist()}
        return k > 0, nc, h
