"""An independent numpy re-evaluation of the EHL line-contact solver's discretised equations
(docs/ehl.md), shared by tests/unit/ehl/test_ehl.py, test_ehl_speedpath.py and test_rough_film_convergence.py."""
import math

import numpy as np


def discrete_equations_check(r, viscosity="roelands", compressible=True, roughness=None):
    """Independent numpy re-evaluation of the discretised equations (docs/ehl.md):
    film from P by a dense sum of the exact cell integrals of ln|x| (closed form
    f(x) = x(ln|x| - 1)), load dX sum P = pi/2, and the Reynolds residual with
    the second-order upstream wedge term, scaled by the point Jacobian.  ``roughness``:
    the dimensionless roughness in the gap of a rough film (None: smooth).  Returns the
    spread of the gap minus X^2/2, the deformation and the roughness (0 for a constant H0),
    the load error and the mean scaled residual over pressurised nodes (units of p_h)."""
    X, P, H = r.X, r.P, r.H
    n, dX = X.size, X[1] - X[0]
    def f(x):
        ax = np.abs(x)
        return np.where(ax > 0, x * (np.log(np.where(ax > 0, ax, 1.0)) - 1.0), 0.0)
    t = np.arange(n)
    K = f((t + 0.5) * dX) - f((t - 0.5) * dX)
    V = -(K[np.abs(t[:, None] - t[None, :])] @ P) / np.pi
    gap = H - 0.5 * X ** 2 - V                      # must be the constant H0
    if roughness is not None:
        gap = gap - roughness
    load_err = abs(dX * P.sum() - 0.5 * np.pi)
    inp = r.inputs
    p = P * r.ph_Pa
    A = math.log(inp["eta0_Pas"]) + 9.67
    z = inp["alpha_Pa_inv"] * 1.96e8 / A
    if viscosity == "roelands":
        eta = np.exp(A * ((1 + p / 1.96e8) ** z - 1))    # Roelands (seed 000 eq 5)
    else:
        eta = np.exp(inp["alpha_Pa_inv"] * p)            # Barus
    if compressible:
        rho = (0.59e9 + 1.34 * p) / (0.59e9 + p)         # Dowson-Higginson (eq 6)
    else:
        rho = np.ones_like(p)
    lam = 3 * math.pi ** 2 / (8 * r.M ** 2)
    eps = rho * H ** 3 / (eta * lam)
    em, ep = 0.5 * (eps[:-2] + eps[1:-1]), 0.5 * (eps[1:-1] + eps[2:])
    poi = (em * (P[:-2] - P[1:-1]) + ep * (P[2:] - P[1:-1])) / dX ** 2
    rH = rho * H
    wedge = np.empty(n - 2)
    wedge[0] = (rH[1] - rH[0]) / dX
    wedge[1:] = (1.5 * rH[2:-1] - 2 * rH[1:-2] + 0.5 * rH[:-3]) / dX
    res = (poi - wedge)
    J = -(em + ep) / dX ** 2 + rho[1:-1] * (K[0] - K[1]) / (math.pi * dX)
    pos = P[1:-1] > 0
    scaled = np.mean(np.abs(res[pos] / J[pos]))
    return np.ptp(gap), load_err, float(scaled)
