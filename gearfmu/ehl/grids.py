"""Grid choice of the steady EHL solver: default grid, coarse-grid and refined retries."""
from __future__ import annotations

import math
from typing import List, Optional

from .errors import EHLInputError


#: piezoviscous coarsest-grid rule of :func:`choose_grid`: dX_coarse <=
#: COARSE_DX_ALPHA / alpha_eff, at most a coarsest grid 8 times coarser than
#: the finest.  Where the film rule dX^2 <= Hc leaves alpha_eff dX_coarse well
#: above 1 (high M with high L) the coarse-grid correction misses the smooth
#: error over the Hertz zone and every relaxation setting stalls on the
#: default hierarchy (benchmarks/bench_ehl_corners.py).
COARSE_DX_ALPHA = 2.0


def choose_grid(Hc_VL: float, length: float, n_nodes=None, n_coarse=None,
                alpha_eff: float = 0.0):
    """Grid sizes (n_nodes, n_coarse, n_levels) for a film of about ``Hc_VL``
    (Venner-Lubrecht units) on a domain ``length`` half-widths long.

    The coarsest grid must resolve the film (dX^2 <= Hc: coarser grids make
    the FAS correction diverge at high M) and, for a piezoviscous lubricant
    with ``alpha_eff`` = d ln(eta)/dP at P = 1 (:func:`effective_alpha`), the
    viscosity change across one coarse cell (dX <= :data:`COARSE_DX_ALPHA` /
    alpha_eff, but at least 3 levels); the default finest grid has
    dX^2 <= Hc/480, which gives about 1 % discretisation error of the central
    film at M = 100, L = 10 (docs/ehl.md).  Defaults are clipped to
    256..16384 intervals.
    """
    def pow2_at_least(x):
        return 1 << max(0, int(math.ceil(math.log2(max(x, 1.0)))))
    auto_coarse = n_coarse is None
    if auto_coarse:
        n_coarse = min(max(32, pow2_at_least(length / math.sqrt(Hc_VL))), 1024)
    if n_nodes is None:
        n_int = min(max(256, pow2_at_least(length * math.sqrt(480.0 / Hc_VL))), 16384)
        n_int = max(n_int, n_coarse)
        n_nodes = n_int + 1
    if auto_coarse and alpha_eff > 0.0:
        c_alpha = pow2_at_least(length * alpha_eff / COARSE_DX_ALPHA)
        n_coarse = max(n_coarse, min(c_alpha, (int(n_nodes) - 1) // 8))
    n_nodes = int(n_nodes)
    n_coarse = int(n_coarse)
    k = n_nodes - 1
    if n_coarse < 8 or k < n_coarse or k % n_coarse != 0:
        raise EHLInputError(f"n_nodes={n_nodes!r}: need n_nodes - 1 = n_coarse * 2^k with "
                            f"n_coarse={n_coarse!r} >= 8")
    q = k // n_coarse
    n_levels = 1
    while q > 1 and q % 2 == 0:
        q //= 2
        n_levels += 1
    if q != 1:
        raise EHLInputError(f"n_nodes={n_nodes!r}: n_nodes - 1 must be n_coarse={n_coarse} "
                            "times a power of 2")
    return n_nodes, n_coarse, n_levels


def corner_rule_capped(alpha_eff: float, length: float, n_coarse: int) -> bool:
    """True where the coarsest grid of ``n_coarse`` intervals misses the
    piezoviscous rule dX <= :data:`COARSE_DX_ALPHA` / alpha_eff of
    :func:`choose_grid` (capped there by the minimum number of levels): the
    strongly piezoviscous corner (high M with high L)."""
    return alpha_eff > 0.0 and alpha_eff * length / n_coarse > COARSE_DX_ALPHA


#: grid rule of the refined retry: dX <= REFINE_DX_ALPHA / alpha_eff (found
#: by experiment over the (M, L) table in docs/ehl.md: the pressure spike and
#: the outlet drop are then resolved by several nodes)
REFINE_DX_ALPHA = 0.15
#: largest retry grid (intervals): the failures measured on finer retry grids
#: (M >= 100 with L >= 15, M = 500 with L = 10) never converged there and cost
#: 3-11 s each
REFINE_MAX_INTERVALS = 4096


#: coarse-grid retry (docs/ehl.md): a smooth solve whose
#: settings all fail on the default hierarchy is retried on the same finest
#: grid with the coarsest grid refined by these factors in turn (at least
#: COARSE_RETRY_MIN_LEVELS levels left).  Measured: the stalls of Barus
#: M = 500, L = 20 and Roelands M = 50, L = 20 are smooth errors over the whole
#: Hertz zone that the coarse-grid correction does not remove when the
#: coarsest grid is 128 (resp. 32) intervals; 512 (resp. 64) converge them.
COARSE_RETRY_FACTORS = (2, 4)
COARSE_RETRY_MIN_LEVELS = 3


#: Failing fast (docs/ehl.md), rule 1: the retry grids
#: (coarse-grid retry, refined grid) are tried only when some setting on the
#: default grid stalled below this scaled Reynolds residual (the threshold of
#: the best-state polish).  Measured: every solve that converged on a retry grid
#: (the (M, L) tables, the margin points M = 2000-5000, L <= 30, M = 0.3-7.5,
#: L = 5-40) had stalled below 6e-4 on its default grid.
RETRY_BELOW_RESIDUAL = 1e-3
#: rule 2: a second or later retry grid is tried only when the previous retry
#: grid lowered the best stalled residual of the grids before it at least
#: RETRY_PROGRESS_FACTOR times or stalled below RETRY_CLOSE_RESIDUAL (measured
#: on the converging cases: 2.9x (Barus M = 5000, L = 30) to 200x, or 1.3x at
#: 5.9e-6 (Barus M = 20000, L = 10); on the failures Barus M = 200 and 1000,
#: L = 40: 1.0x at 9e-4 and 0.3x at 7e-4)
RETRY_PROGRESS_FACTOR = 2.0
RETRY_CLOSE_RESIDUAL = 1e-4


def coarse_retry_grids(n_int: int, n_coarse: int) -> List[int]:
    """Coarsest-grid sizes (intervals) of the coarse-grid retry of a solve on
    ``n_int`` finest intervals whose default coarsest grid has ``n_coarse``:
    ``n_coarse`` times each of :data:`COARSE_RETRY_FACTORS` that leaves at
    least :data:`COARSE_RETRY_MIN_LEVELS` levels."""
    out = []
    for f in COARSE_RETRY_FACTORS:
        c = int(n_coarse) * int(f)
        if c * 2 ** (COARSE_RETRY_MIN_LEVELS - 1) <= n_int:
            out.append(c)
    return out


def effective_alpha(prm) -> float:
    """alpha_eff = d ln(eta)/dP at P = 1 (dimensionless, Hertzian pressure
    units): alpha p_h for Barus; A z (p_h/p0) (1 + p_h/p0)^(z-1) for Roelands
    (Zhao et al. 2022 eq 5)."""
    if prm.z < 0.0:
        return float(prm.A)
    if prm.z > 0.0:
        return float(prm.A * prm.z * prm.php0 * (1.0 + prm.php0) ** (prm.z - 1.0))
    return 0.0


def refined_grid_intervals(prm, length: float, n_int: int) -> Optional[int]:
    """Number of intervals of the retry grid after a failed solve on
    ``n_int`` intervals (smooth solves whose grid was chosen automatically):
    the power of 2 with dX <= REFINE_DX_ALPHA / alpha_eff, at least 2 n_int;
    None when that exceeds REFINE_MAX_INTERVALS."""
    a = effective_alpha(prm)
    need = length * a / REFINE_DX_ALPHA if a > 0.0 else 0.0
    n = 2 * n_int
    while n < need:
        n *= 2
    return n if n <= REFINE_MAX_INTERVALS else None
