"""An independent solution of the smooth line-contact EHL equations (reference for the multigrid solver).

Same continuous problem as :func:`gearfmu.ehl.solve_line_contact` with Barus viscosity and an
incompressible lubricant (the assumptions of Moes' fit), Venner-Lubrecht scaling (docs/ehl.md):

    d/dX(eps dP/dX) - dH/dX = 0,  eps = H^3 exp(-alpha_bar P) / lambda_bar,  P >= 0 (Reynolds condition),
    H = H0 + X^2/2 - (1/pi) int P(X') ln|X - X'| dX',   int P dX = pi/2,
    lambda_bar = 3 pi^2 / (8 M^2),  alpha_bar = L sqrt(M / (2 pi)),  H_Moes = 8 M H / pi,

but a different discretisation and a different method, written separately from gearfmu.ehl:

* deformation: pressure piecewise *linear* between the nodes (hat functions), each hat's
  logarithmic integral in closed form (the solver: piecewise constant on cells);
* Reynolds equation in flux form with eps at the half node taken from the half-node pressure and
  film, eps(P_(i+1/2), H_(i+1/2)) (the solver: the mean of the two node values of eps); wedge
  flux second-order upwind, (3 H_i - H_(i-1))/2 at i + 1/2 (first order at the first cell);
* all unknowns (the pressures of the free set and H0) by Newton's method with the exact dense
  Jacobian and a backtracking line search; cavitation by an active set (a cavitated node joins
  when its point update is positive; a node whose full step ends below zero leaves it near the
  solution); the load by the trapezoidal rule (the same sum: P = 0 at both ends).

Newton needs a start close to the solution: the multigrid solution on the same grid is used;
the converged result is the solution of *these* discrete equations (the start only selects the
branch), so its difference from the multigrid value is the difference of two second-order
discretisations, which vanishes as dX^2 under grid refinement.  Dense LU: O(n^3) per step,
about 1 s at 1024 and 10 s at 2048 intervals.
"""
from __future__ import annotations

import math

import numpy as np
import scipy.linalg as sla


def _xlog(u):
    """u ln|u| - u (antiderivative of ln|u|), 0 at u = 0."""
    a = np.abs(u)
    out = np.zeros_like(u)
    nz = a > 0
    out[nz] = u[nz] * np.log(a[nz]) - u[nz]
    return out


def _x2log(u):
    """u^2/2 ln|u| - u^2/4 (antiderivative of u ln|u|), 0 at u = 0."""
    a = np.abs(u)
    out = np.zeros_like(u)
    nz = a > 0
    out[nz] = 0.5 * u[nz] ** 2 * np.log(a[nz]) - 0.25 * u[nz] ** 2
    return out


def hat_kernel(n: int, d: float) -> np.ndarray:
    """C_k = int hat(s) ln|k d - s| ds, k = 0..n-1, for the hat of half-width d centred at 0."""
    t = np.arange(n) * d

    def seg(s0, s1, a, b):   # int_s0^s1 (a + b s) ln|t - s| ds, with u = t - s
        u0, u1 = t - s1, t - s0
        return (a + b * t) * (_xlog(u1) - _xlog(u0)) - b * (_x2log(u1) - _x2log(u0))

    return seg(-d, 0.0, 1.0, 1.0 / d) + seg(0.0, d, 1.0, -1.0 / d)


class ReferenceProblem:
    """The discrete equations above for Moes' (M, L) on ``n_intervals`` uniform intervals of
    [x_in, x_out] (Hertz units)."""

    def __init__(self, M: float, L: float, n_intervals: int, x_in: float = -4.5, x_out: float = 1.5):
        self.M, self.L = float(M), float(L)
        self.lam = 3.0 * math.pi ** 2 / (8.0 * self.M ** 2)
        self.abar = self.L * math.sqrt(self.M / (2.0 * math.pi))
        self.X = np.linspace(x_in, x_out, int(n_intervals) + 1)
        self.d = float(self.X[1] - self.X[0])
        self.n = self.X.size
        C = hat_kernel(self.n, self.d)
        k = np.abs(np.arange(self.n)[:, None] - np.arange(self.n)[None, :])
        self.D = -C[k] / math.pi             # H = H0 + X^2/2 + D @ P

    def film(self, P, H0):
        return H0 + 0.5 * self.X ** 2 + self.D @ P

    def residual(self, P, H0):
        """(R, load error, H, eps at the half nodes); R_i = 0 at pressurised interior nodes."""
        d = self.d
        H = self.film(P, H0)
        e = (0.5 * (H[1:] + H[:-1])) ** 3 * np.exp(-self.abar * 0.5 * (P[1:] + P[:-1])) / self.lam
        q = e * (P[1:] - P[:-1]) / d                      # Poiseuille flux at i + 1/2
        c = np.empty(self.n - 1)                          # wedge flux at i + 1/2
        c[0] = H[0]
        c[1:] = 0.5 * (3.0 * H[1:-1] - H[:-2])
        R = np.zeros(self.n)
        R[1:-1] = (q[1:] - q[:-1]) / d - (c[1:] - c[:-1]) / d
        return R, d * float(P.sum()) - 0.5 * math.pi, H, e

    def jacobian(self, P, H, e):
        """dR/dP (dense, through the film and eps) and dR/dH0."""
        d, n = self.d, self.n
        Hm = 0.5 * (H[1:] + H[:-1])
        g = (P[1:] - P[:-1]) / d
        q_p = -self.abar * 0.5 * e * g         # d q_m / d P_m (and / d P_(m+1)) through eps
        q_h = 3.0 * 0.5 * e / Hm * g           # d q_m / d H_m (and / d H_(m+1)) through eps
        JP = np.zeros((n, n))
        JH = np.zeros((n, n))
        i = np.arange(1, n - 1)
        for m, s in ((i, 1.0), (i - 1, -1.0)):   # + q_(i+1/2)/d, - q_(i-1/2)/d
            JP[i, m + 1] += s * (e[m] / d + q_p[m]) / d
            JP[i, m] += s * (-e[m] / d + q_p[m]) / d
            JH[i, m + 1] += s * q_h[m] / d
            JH[i, m] += s * q_h[m] / d
        JH[i, i] -= 1.5 / d                      # - c_(i+1/2)/d
        JH[i, i - 1] += 0.5 / d
        j = i[i >= 2]                            # + c_(i-1/2)/d
        JH[j, j - 1] += 1.5 / d
        JH[j, j - 2] -= 0.5 / d
        JH[1, 0] += 1.0 / d
        return JP + JH @ self.D, JH.sum(axis=1)


def newton_solve(prob: ReferenceProblem, P_start, H0_start, tol=1e-10, max_steps=60):
    """Newton on the free pressures and H0 from (P_start, H0_start).  Returns
    (P, H0, converged, steps); converged: the mean square of the diagonally scaled residual
    over the free set plus the squared relative load error below tol^2 and a relative pressure
    change below 1e-10."""
    P = np.clip(np.asarray(P_start, float).copy(), 0.0, None)
    P[0] = P[-1] = 0.0
    H0 = float(H0_start)
    n, d = prob.n, prob.d
    scale = np.ones(n)

    def merit(P_, H0_):
        R_, g_, H_, e_ = prob.residual(P_, H0_)
        if not np.all(np.isfinite(R_)) or float(np.min(H_)) <= 0.0:
            return math.inf, None
        fr = P_ > 0.0
        return float(np.sum((R_[fr] * scale[fr]) ** 2) + (g_ / (0.5 * math.pi)) ** 2), (R_, g_, H_, e_)

    f0, st = merit(P, H0)
    if st is None:
        return P, H0, False, 0
    for step in range(max_steps):
        R, g, H, e = st
        J, JH0 = prob.jacobian(P, H, e)
        diag = np.diag(J).copy()
        scale = 1.0 / np.maximum(np.abs(diag), 1e-300)
        f0, st = merit(P, H0)
        free = P > 0.0
        with np.errstate(divide="ignore", invalid="ignore"):
            free |= (-R / diag) > 0.0
        free[0] = free[-1] = False
        for _ in range(20):
            F = np.nonzero(free)[0]
            m = F.size
            A = np.empty((m + 1, m + 1))
            A[:m, :m] = J[np.ix_(F, F)]
            A[:m, m] = JH0[F]
            A[m, :m] = d
            A[m, m] = 0.0
            s = np.concatenate([scale[F], [1.0]])
            x = sla.solve(A * s[:, None], np.concatenate([-R[F], [-g]]) * s)
            below = F[P[F] + x[:m] < 0.0]
            if below.size and f0 < 1e-6:
                free[below] = False      # near the solution: these stay at zero, solve again
                continue
            break
        dP = np.zeros(n)
        dP[F] = x[:m]
        t = 1.0
        for _ in range(40):
            Pt = np.clip(P + t * dP, 0.0, None)
            Pt[~free] = 0.0
            ft, stt = merit(Pt, H0 + t * x[m])
            if ft < f0 * (1.0 - 1e-4 * t) or ft < 1e-28:
                break
            t *= 0.5
        else:
            return P, H0, False, step
        change = float(np.sum(np.abs(Pt - P)) / max(float(np.sum(np.abs(Pt))), 1e-300))
        P, H0, f0, st = Pt, H0 + t * x[m], ft, stt
        if f0 < tol ** 2 and change < 1e-10:
            return P, H0, True, step + 1
    return P, H0, False, max_steps


def reference_central_film(M, L, n_intervals, start_X, start_P, start_Hc_moes, x_in=-4.5, x_out=1.5):
    """Central film (Moes scaling) of the reference discretisation on ``n_intervals`` intervals,
    Newton started from a pressure ``start_P`` on ``start_X`` with central film ``start_Hc_moes``.
    Returns (H_central_moes, H_min_moes, converged, steps)."""
    prob = ReferenceProblem(M, L, n_intervals, x_in, x_out)
    P0 = np.interp(prob.X, start_X, start_P, left=0.0, right=0.0)
    Hc = start_Hc_moes * math.pi / (8.0 * M)
    H0 = Hc - float(np.interp(0.0, prob.X, prob.film(P0, 0.0)))
    P, H0, ok, steps = newton_solve(prob, P0, H0)
    H = prob.film(P, H0)
    to_moes = 8.0 * M / math.pi
    return float(np.interp(0.0, prob.X, H)) * to_moes, float(H.min()) * to_moes, ok, steps
