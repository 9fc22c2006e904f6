"""Multilevel solution of the dimensionless line-contact EHL problem.

Equations (seed 000 eq 2-7 in the Hertzian scaling of Venner & Lubrecht 2000,
*Multilevel Methods in Lubrication*):

    d/dX( eps dP/dX ) - d(rho H)/dX = 0,   eps = rho H^3 / (eta lambda)    (Reynolds, eq 2)
    H = H0 + X^2/2 - (1/pi) int P ln|X - X'| dX' + R(X)                     (film, eq 3-4)
    eta = exp{A [ (1 + P ph/p0)^z - 1 ]},  A = ln(eta0) + 9.67             (Roelands, eq 5)
    rho = (c1 + 1.34 P) / (c1 + P),  c1 = 0.59e9 Pa / ph                    (Dowson-Higginson, eq 6)
    dX sum P = pi/2                                                         (load balance, eq 7)
    P = 0 at the inlet and outlet, P >= 0 (cavitation by P = max(P, 0)).

Discretisation: central differences for the Poiseuille term with eps at the
half nodes as the mean of the node values, second-order upstream differences
for the wedge term (first order at the first interior node).

Solver (Venner & Lubrecht 2000; Algorithm 1 of seed 000): FAS
multigrid with W-cycles (nu1 pre-, nu2 post-relaxations), injection of P and
full weighting of the residual to the coarse grid, FAS also on the film
equation (the coarse film starts equal to the injected fine film and changes
with the coarse-grid kernel), linear interpolation of the correction (only
where the fine pressure is positive), the load balance (eq 7) enforced on
the finest grid after every W-cycle by moving H0 against the load error,
full multigrid (FMG) start from a Hertzian pressure with cubic
interpolation of the solution between levels.  Relaxation: line by line,
Gauss-Seidel where eps/dX^2 is large (low-pressure inlet/outlet) and
Jacobi "dipole" relaxation (seed 000: changes delta_i applied as
+delta_i at i and -delta_i at i-1) where eps/dX^2 is small (Hertzian zone); the switch is
eps/dX^2 >= ``switch`` (3.0; found by numerical experiment here: 1.0 and
10 fail to converge at M = 100, L = 10).  The deformation
is recomputed by FFT (see :mod:`.deformation`) after each sweep.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from .deformation import DeformationOperator, fft_deformation


@njit(cache=False)
def _coefficients(P, H, lam, A, z, php0, c1, compressible):
    n = P.size
    rho = np.ones(n)
    eps = np.zeros(n)
    dle = np.zeros(n)   # d ln(eps) / dP at fixed H
    drho = np.zeros(n)  # d rho / dP
    for i in range(n):
        p = P[i] if P[i] > 0.0 else 0.0
        dl = 0.0
        if compressible:
            rho[i] = (c1 + 1.34 * p) / (c1 + p)
            dl += 1.34 / (c1 + 1.34 * p) - 1.0 / (c1 + p)
            drho[i] = 0.34 * c1 / ((c1 + p) * (c1 + p))
        if z > 0.0:
            eta = math.exp(A * ((1.0 + p * php0) ** z - 1.0))
            dl -= A * z * php0 * (1.0 + p * php0) ** (z - 1.0)
        elif z < 0.0:
            # Barus law exp(alpha p) with A = alpha-bar = alpha p_h (z < 0 flags it)
            eta = math.exp(A * p)
            dl -= A
        else:
            eta = 1.0
        hh = H[i] if H[i] > 0.0 else 0.0
        eps[i] = rho[i] * hh * hh * hh / (eta * lam)
        dle[i] = dl
    return rho, eps, dle, drho


@njit(cache=False)
def _operator(P, H, rho, eps, dX, order2):
    n = P.size
    L = np.zeros(n)
    h2 = dX * dX
    for i in range(1, n - 1):
        em = 0.5 * (eps[i - 1] + eps[i])
        ep = 0.5 * (eps[i] + eps[i + 1])
        poi = (em * (P[i - 1] - P[i]) + ep * (P[i + 1] - P[i])) / h2
        if i >= 2 and order2:
            wedge = (1.5 * rho[i] * H[i] - 2.0 * rho[i - 1] * H[i - 1]
                     + 0.5 * rho[i - 2] * H[i - 2]) / dX
        else:
            wedge = (rho[i] * H[i] - rho[i - 1] * H[i - 1]) / dX
        L[i] = poi - wedge
    return L


@njit(cache=False)
def _relax(P, H, f, rho, eps, dle, drho, dX, K, omega_gs, omega_j, switch, order2, dmax):
    """One relaxation sweep; P changed in place, H left stale (caller updates).

    Returns the sum of |changes| and the L1 norm of the residual at the
    start of the sweep (both dimensionless)."""
    n = P.size
    h2 = dX * dX
    ipi = 1.0 / math.pi
    # Jacobian pieces: dH_j/dP_i = -(1/pi) K_|i-j|; dipole change (+delta at i,
    # -delta at i-1) changes H_m by -(1/pi) (K_|m-i| - K_|m-i+1|) delta
    K0 = K[0]
    K1 = K[1]
    K2 = K[2]
    Dd0 = K0 - K1      # m = i
    Dd1 = K1 - K0      # m = i-1
    Dd2 = K2 - K1      # m = i-2
    delta = np.zeros(n)
    jac = np.zeros(n, dtype=np.bool_)
    change = 0.0
    resn = 0.0
    for i in range(1, n - 1):
        em = 0.5 * (eps[i - 1] + eps[i])
        ep = 0.5 * (eps[i] + eps[i + 1])
        poi = (em * (P[i - 1] - P[i]) + ep * (P[i + 1] - P[i])) / h2
        if i >= 2 and order2:
            wedge = (1.5 * rho[i] * H[i] - 2.0 * rho[i - 1] * H[i - 1]
                     + 0.5 * rho[i - 2] * H[i - 2]) / dX
        else:
            wedge = (rho[i] * H[i] - rho[i - 1] * H[i - 1]) / dX
        r = f[i] - (poi - wedge)
        resn += abs(r)
        # dependence of eps_i on P_i (viscosity, density), taken into the
        # Jacobian by its magnitude (never shrinks |J|; continuous in P)
        xtra = -abs(0.5 * eps[i] * dle[i] * (P[i - 1] - 2.0 * P[i] + P[i + 1]) / h2)
        use_gs = eps[i] / h2 >= switch or P[i - 1] <= 0.0 or P[i + 1] <= 0.0 or P[i] <= 0.0
        if use_gs:
            if i >= 2 and order2:
                w = (1.5 * rho[i] * K0 - 2.0 * rho[i - 1] * K1 + 0.5 * rho[i - 2] * K2) * ipi / dX
                w -= 1.5 * H[i] * drho[i] / dX
            else:
                w = (rho[i] * K0 - rho[i - 1] * K1) * ipi / dX
                w -= H[i] * drho[i] / dX
            J = -(em + ep) / h2 + w + xtra
            d = omega_gs * r / J
            # trust region: eps (viscosity) may change by at most exp(dmax) per sweep
            if abs(d * dle[i]) > dmax:
                d = math.copysign(dmax / abs(dle[i]), d)
            old = P[i]
            newp = old + d
            if newp < 0.0:
                newp = 0.0
            P[i] = newp
            change += abs(newp - old)
        else:
            if i >= 2 and order2:
                w = (1.5 * rho[i] * Dd0 - 2.0 * rho[i - 1] * Dd1 + 0.5 * rho[i - 2] * Dd2) * ipi / dX
                w -= (1.5 * H[i] * drho[i] + 2.0 * H[i - 1] * drho[i - 1]) / dX
            else:
                w = (rho[i] * Dd0 - rho[i - 1] * Dd1) * ipi / dX
                w -= (H[i] * drho[i] + H[i - 1] * drho[i - 1]) / dX
            J = -(2.0 * em + ep) / h2 + w + xtra
            d = omega_j * r / J
            if abs(d * dle[i]) > dmax:
                d = math.copysign(dmax / abs(dle[i]), d)
            delta[i] = d
            jac[i] = True
    for i in range(1, n - 1):
        if jac[i]:
            d = delta[i]
            P[i] += d
            P[i - 1] -= d
            change += 2.0 * abs(d)
    P[0] = 0.0
    P[n - 1] = 0.0
    for i in range(n):
        if P[i] < 0.0:
            P[i] = 0.0
    return change, resn


@njit(cache=False)
def _scaled_residual(P, H, f, rho, eps, dX, K, order2):
    """Mean over pressurised nodes of |r_i / (dL_i/dP_i)|: the size of the
    pressure change (in units of p_h) a point-Newton step would make."""
    n = P.size
    L = _operator(P, H, rho, eps, dX, order2)
    h2 = dX * dX
    s = 0.0
    cnt = 0
    for i in range(1, n - 1):
        if P[i] <= 0.0:
            continue
        em = 0.5 * (eps[i - 1] + eps[i])
        ep = 0.5 * (eps[i] + eps[i + 1])
        w = (rho[i] * (K[0] - K[1])) / (math.pi * dX)
        J = -(em + ep) / h2 + w
        s += abs((f[i] - L[i]) / J)
        cnt += 1
    return s / max(cnt, 1)


@njit(cache=False)
def _relax_sweeps(P, H, f, base, tauH, H0, khr, khi, twr, twi, dX, K, lam, A, z, php0, c1,
                  compressible, omega_gs, omega_j, switch, order2, dmax, sweeps):
    """``sweeps`` relaxation sweeps, each followed by the film update
    H = H0 + base + V(P) + tauH (FFT); P and H changed in place."""
    change = 0.0
    for _ in range(sweeps):
        rho, eps, dle, drho = _coefficients(P, H, lam, A, z, php0, c1, compressible)
        change, _r = _relax(P, H, f, rho, eps, dle, drho, dX, K, omega_gs, omega_j, switch,
                            order2, dmax)
        V = fft_deformation(P, khr, khi, twr, twi, K)
        for i in range(P.size):
            H[i] = H0 + base[i] + V[i] + tauH[i]
    return change


@njit(cache=False)
def _operator_full(P, H, dX, lam, A, z, php0, c1, compressible, order2):
    rho, eps, _d, _r = _coefficients(P, H, lam, A, z, php0, c1, compressible)
    return _operator(P, H, rho, eps, dX, order2)


@njit(cache=False)
def _restrict_fw(r):
    nc = (r.size - 1) // 2 + 1
    out = np.zeros(nc)
    for I in range(1, nc - 1):
        i = 2 * I
        out[I] = 0.25 * r[i - 1] + 0.5 * r[i] + 0.25 * r[i + 1]
    return out


@njit(cache=False)
def _prolong_correction(Pf, dPc):
    nf = Pf.size
    for i in range(1, nf - 1):
        if i % 2 == 0:
            c = dPc[i // 2]
        else:
            c = 0.5 * (dPc[i // 2] + dPc[i // 2 + 1])
        if Pf[i] > 0.0:
            Pf[i] += c
        if Pf[i] < 0.0:
            Pf[i] = 0.0


def _interp_cubic(Pc: np.ndarray) -> np.ndarray:
    """Cubic (4-point) interpolation of a coarse solution to the fine grid."""
    nc = Pc.size
    nf = 2 * (nc - 1) + 1
    Pf = np.zeros(nf)
    Pf[::2] = Pc
    ext = np.concatenate(([Pc[0]], Pc, [Pc[-1]]))
    # midpoint between coarse j and j+1 uses ext[j], ext[j+1], ext[j+2], ext[j+3]
    Pf[1::2] = (-ext[:-3] + 9.0 * ext[1:-2] + 9.0 * ext[2:-1] - ext[3:]) / 16.0
    Pf[Pf < 0.0] = 0.0
    Pf[0] = Pf[-1] = 0.0
    return Pf


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


class Level:
    def __init__(self, n_intervals: int, prm: EHLParams, rough_fn=None):
        self.n = n_intervals + 1
        self.X = np.linspace(prm.x_in, prm.x_out, self.n)
        self.dX = self.X[1] - self.X[0]
        self.defo = DeformationOperator(self.n, self.dX)
        self.K = self.defo.K
        self.rough = np.zeros(self.n) if rough_fn is None else rough_fn(self.X)
        self.base = 0.5 * self.X ** 2 + self.rough
        self.P = np.zeros(self.n)
        self.H = np.zeros(self.n)
        self.f = np.zeros(self.n)
        self.g = 0.5 * np.pi
        self.H0 = 0.0
        self.tauH = np.zeros(self.n)   # FAS right-hand side of the film equation

    def update_H(self):
        self.H = self.H0 + self.base + self.defo(self.P) + self.tauH

    def load(self) -> float:
        return self.dX * float(np.sum(self.P))


class MultigridSolver:
    """FAS W-cycle solver on a hierarchy of uniform grids (see module doc)."""

    def __init__(self, prm: EHLParams, n_levels: int, n_coarse: int, rough_fn=None,
                 nu1: int = 2, nu2: int = 1, nu0: int = 10,
                 omega_gs: float = 0.8, omega_j: float = 0.6, switch: float = 3.0,
                 c_h0: float = 0.5, order2: bool = True, h0_step: float = 0.5,
                 load_on_coarse: bool = False, dmax: float = 0.3):
        self.prm = prm
        self.levels = [Level(n_coarse * 2 ** k, prm, rough_fn) for k in range(n_levels)]
        self.nu1, self.nu2, self.nu0 = nu1, nu2, nu0
        self.omega_gs, self.omega_j, self.switch = omega_gs, omega_j, switch
        self.c_h0 = c_h0
        self.order2 = order2
        self.h0_step = h0_step
        self.load_on_coarse = load_on_coarse
        self.c_cur = c_h0
        self._dH0_prev = 0.0
        self.dmax = dmax
        self.H_scale = 1.0   # typical film (VL units), set by the starts

    # -- elementary operations ------------------------------------------------
    def set_roughness_scale(self, a: float):
        """Scale the roughness of every level by ``a`` (continuation from the
        smooth solution)."""
        for lv in self.levels:
            lv.base = 0.5 * lv.X ** 2 + a * lv.rough
            lv.update_H()

    def _coef(self, lv: Level):
        p = self.prm
        return _coefficients(lv.P, lv.H, p.lam, p.A, p.z, p.php0, p.c1, p.compressible)

    def relax(self, lv: Level, sweeps: int):
        p = self.prm
        d = lv.defo
        return _relax_sweeps(lv.P, lv.H, lv.f, lv.base, lv.tauH, lv.H0, d.khr, d.khi, d.twr,
                             d.twi, lv.dX, lv.K, p.lam, p.A, p.z, p.php0, p.c1, p.compressible,
                             self.omega_gs, self.omega_j, self.switch, self.order2, self.dmax,
                             sweeps)

    def residual(self, lv: Level) -> np.ndarray:
        return lv.f - self.operator(lv)

    def scaled_residual(self, lv: Level) -> float:
        rho, eps, _, _ = self._coef(lv)
        return _scaled_residual(lv.P, lv.H, lv.f, rho, eps, lv.dX, lv.K, self.order2)

    def operator(self, lv: Level) -> np.ndarray:
        p = self.prm
        return _operator_full(lv.P, lv.H, lv.dX, p.lam, p.A, p.z, p.php0, p.c1,
                              p.compressible, self.order2)

    def relax_coarsest(self, lv: Level):
        if self.load_on_coarse:
            for _ in range(self.nu0):
                self.relax(lv, 1)
                self._h0_step(lv, lv.g)
        else:
            self.relax(lv, self.nu0)

    def _h0_step(self, lv: Level, g: float):
        dH0 = -self.c_h0 * (g - lv.load())
        scale = max(float(np.interp(0.0, lv.X, lv.H)), 0.2 * self.H_scale)
        lim = self.h0_step * scale
        lv.H0 += min(max(dH0, -lim), lim)
        lv.update_H()

    def update_H0(self, lv: Level):
        """Load balance (seed 000 eq 7) on the current finest grid: H0 moves
        against the load error, H0 <- H0 - c (pi/2 - dX sum P).  The gain c
        is halved whenever the step changes sign without shrinking (an
        over-correction) and recovers (x1.5) while it keeps its sign."""
        dH0 = -self.c_cur * (0.5 * np.pi - lv.load())
        # never move H0 by more than a fraction of the film itself: for thin
        # films (high M) the load is very sensitive to H0
        scale = max(float(np.interp(0.0, lv.X, lv.H)), 0.2 * self.H_scale)
        lim = self.h0_step * scale
        dH0 = min(max(dH0, -lim), lim)
        if dH0 * self._dH0_prev < 0.0 and abs(dH0) > 0.5 * abs(self._dH0_prev):
            self.c_cur *= 0.5
        elif dH0 * self._dH0_prev > 0.0:
            self.c_cur = min(self.c_cur * 1.5, self.c_h0)
        self._dH0_prev = dH0
        lv.H0 += dH0
        lv.update_H()

    def solve_cycle(self, k: int):
        """One W-cycle with level k as the finest grid, then the H0 update."""
        self.levels[k].g = 0.5 * np.pi
        self.cycle(k)
        if not self.load_on_coarse or k == 0:
            self.update_H0(self.levels[k])

    # -- cycles -------------------------------------------------------------
    def cycle(self, k: int, gamma: int = 2):
        lv = self.levels[k]
        if k == 0:
            self.relax_coarsest(lv)
            return
        self.relax(lv, self.nu1)
        r = self.residual(lv)
        # cavitated points carry no residual to the coarse grid
        r[lv.P <= 0.0] = 0.0
        cv = self.levels[k - 1]
        cv.P = lv.P[::2].copy()
        cv.H0 = lv.H0
        # FAS for the film equation as well: the coarse film starts equal to the
        # (injected) fine film, and changes with the coarse-grid kernel
        cv.tauH = np.zeros(cv.n)
        cv.update_H()
        cv.tauH = lv.H[::2] - cv.H
        cv.H = lv.H[::2].copy()
        cv.f = self.operator(cv) + _restrict_fw(r)
        cv.f[0] = cv.f[-1] = 0.0
        cv.g = lv.g + cv.load() - lv.load()
        H0_old = cv.H0
        P_old = cv.P.copy()
        for _ in range(gamma if k > 1 else 1):
            self.cycle(k - 1, gamma)
        _prolong_correction(lv.P, cv.P - P_old)
        lv.H0 += cv.H0 - H0_old
        lv.update_H()
        self.relax(lv, self.nu2)

    def hertz_start(self, Hc_guess: float):
        """Initialise the finest grid with the Hertzian pressure sqrt(1 - X^2)
        and H0 such that the central film equals ``Hc_guess`` (VL units)."""
        self.H_scale = Hc_guess
        lv = self.levels[-1]
        X = lv.X
        lv.P = np.where(np.abs(X) < 1.0, np.sqrt(np.clip(1.0 - X ** 2, 0.0, None)), 0.0)
        lv.f = np.zeros(lv.n)
        lv.tauH = np.zeros(lv.n)
        lv.H0 = 0.0
        lv.update_H()
        lv.H0 = Hc_guess - float(np.interp(0.0, X, lv.H))
        lv.update_H()

    def fmg_start(self, H0_guess: float, cycles_per_level: int = 1):
        lv = self.levels[0]
        X = lv.X
        self.H_scale = H0_guess + 0.597
        lv.P = np.where(np.abs(X) < 1.0, np.sqrt(np.clip(1.0 - X ** 2, 0.0, None)), 0.0)
        lv.H0 = H0_guess
        lv.f[:] = 0.0
        lv.tauH = np.zeros(lv.n)
        lv.g = 0.5 * np.pi
        lv.update_H()
        # bring the coarsest grid close to its own solution
        for _ in range(20):
            self.relax_coarsest(lv)
            self.update_H0(lv)
        for k in range(1, len(self.levels)):
            fine = self.levels[k]
            fine.P = _interp_cubic(self.levels[k - 1].P)
            fine.H0 = self.levels[k - 1].H0
            fine.f = np.zeros(fine.n)
            fine.tauH = np.zeros(fine.n)
            fine.g = 0.5 * np.pi
            fine.update_H()
            for _ in range(cycles_per_level):
                self.solve_cycle(k)
