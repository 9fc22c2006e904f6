"""Loaded static mesh: load sharing among tooth pairs and face-width slices
(Zhao et al. 2022 eq 16), SI units.  See docs/physics_errors.md.

Model
-----
At one pinion angle the pairs j = 1..P in the contact zone are split into
face-width slices n = 1..NS, each a linear spring k_jn (N/m) that closes when
the static transmission error x_s (m, along the line of action) exceeds its
gap g_jn = e_j + E_pc,n (e_j the pair's meshing error, E_pc,n the lead
crowning of slice n, Zhao et al. 2022 eq 16).  The static balance is

    g(x_s) = sum_j sum_n k_jn * max(0, x_s - e_j - E_pc,n) = F,   F = T1 / rb1.

g is continuous, piecewise linear and non-decreasing, so the root is found
exactly by an active-set walk over the sorted gaps (a monotone bracketing root
find that ends on the exact linear segment: x_s = (F + sum_active k g) /
sum_active k).  This is the load balance of Zhao et al. 2022 eq 16 without its
assumption that every slice is in contact.

Per-pair stiffness for the dynamic model (docs/model.md)
-------------------------------------------------------
The dynamic model uses one spring per pair, F_j = k_j (x - e_j).  With lead
crowning a pair's force-deflection law is piecewise linear, so we give each
pair, at each torque,
  * the effective error e_eff,j = e_j + min_n E_pc,n (the deflection at which
    the pair's first slice touches), torque-independent, and
  * the secant stiffness k_j = F_j / (x_s - e_eff,j) of its static load,
which is Zhao et al. 2022 eq 16, K = F sum k_n / (F + sum k_n E_pc), for a single pair
with all slices in contact.  Then sum_j k_j max(0, x_s - e_eff,j) = F exactly:
the tables reproduce the loaded static TE at every torque row.  A pair in the
contact zone that carries no static load gets the secant stiffness at the
deflection of the most deflected pair at that angle (delta_ref = x_s -
min_j e_eff,j), i.e. the stiffness it would show if it were loaded like its
neighbour; at zero load (delta_ref = 0) its tangent stiffness at first touch.
Without crowning (all E_pc equal) k_j = sum_n k_jn exactly and is
load-independent.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


class LoadedMeshInputError(ValueError):
    """Bad input to the loaded-mesh solver (names the field and the reason)."""


def static_deflection_m(k_N_per_m, gap_m, force_N) -> np.ndarray:
    """Exact root x of sum_m k_m max(0, x - gap_m) = F for each row (m).

    ``k_N_per_m``, ``gap_m``: shape (..., M) (M springs per row); ``force_N``:
    scalar or shape (...), >= 0.  Springs with k = 0 are ignored.  Raises
    :class:`LoadedMeshInputError` when a row has no spring with k > 0, or on
    negative / non-finite input.
    """
    k = np.asarray(k_N_per_m, dtype=float)
    g = np.asarray(gap_m, dtype=float)
    if k.shape != g.shape or k.ndim < 1:
        raise LoadedMeshInputError(f"gap_m: shape {g.shape} must equal k_N_per_m shape {k.shape} (>= 1 axis)")
    if not np.all(np.isfinite(k)) or np.any(k < 0):
        raise LoadedMeshInputError("k_N_per_m: must be finite and >= 0")
    if not np.all(np.isfinite(g)):
        raise LoadedMeshInputError("gap_m: must be finite")
    f = np.broadcast_to(np.asarray(force_N, dtype=float), k.shape[:-1])
    if not np.all(np.isfinite(f)) or np.any(f < 0):
        raise LoadedMeshInputError("force_N: must be finite and >= 0 (drive-flank load)")
    if np.any(k.sum(axis=-1) <= 0):
        raise LoadedMeshInputError("k_N_per_m: some angle has no spring in contact (all k = 0)")
    order = np.argsort(g, axis=-1, kind="stable")
    c = np.take_along_axis(g, order, axis=-1)
    w = np.take_along_axis(k, order, axis=-1)
    K = np.cumsum(w, axis=-1)
    S = np.cumsum(w * c, axis=-1)
    G = np.empty_like(K)  # g evaluated at the next breakpoint with springs 0..i active
    G[..., :-1] = K[..., :-1] * c[..., 1:] - S[..., :-1]
    G[..., -1] = np.inf
    ok = (G >= f[..., None]) & (K > 0)
    i = np.argmax(ok, axis=-1)[..., None]
    Ki = np.take_along_axis(K, i, axis=-1)[..., 0]
    Si = np.take_along_axis(S, i, axis=-1)[..., 0]
    return (f + Si) / Ki


def pair_force_N(k_slice_N_per_m, crowning_m, deflection_m) -> np.ndarray:
    """Force of one pair (N) at deflection delta measured from its error e_j:
    sum_n k_n max(0, delta - E_pc,n).  ``k_slice_N_per_m`` (..., NS),
    ``crowning_m`` (NS,), ``deflection_m`` broadcast against (...)."""
    k = np.asarray(k_slice_N_per_m, dtype=float)
    d = np.asarray(deflection_m, dtype=float)[..., None]
    return (k * np.maximum(0.0, d - np.asarray(crowning_m, dtype=float))).sum(axis=-1)


@dataclass
class LoadedMesh:
    """Static loaded mesh at one load over an angle grid (SI).

    Shapes: pairs (P, N), totals (N,).
    """

    force_N: float
    static_te_m: np.ndarray          # (N,) loaded static transmission error x_s
    pair_load_N: np.ndarray          # (P, N)
    load_sharing: np.ndarray         # (P, N) pair_load / F (0 when F = 0)
    k_secant_N_per_m: np.ndarray     # (P, N) per-pair secant stiffness (0 outside contact zone)
    e_effective_m: np.ndarray        # (P, N) e_j + min E_pc (onset of contact)

    def total_stiffness_N_per_m(self) -> np.ndarray:
        """Sum of the per-pair secant stiffnesses over pairs, (N,)."""
        return self.k_secant_N_per_m.sum(axis=0)


def loaded_static_mesh(k_slice_N_per_m, e_pair_m, crowning_m, force_N: float) -> LoadedMesh:
    """Load sharing among pairs and slices at one load (Zhao et al. 2022 eq 16).

    ``k_slice_N_per_m``: (P, NS, N) stiffness of slice n of the pair in slot j
    at angle i (0 outside the contact zone); ``e_pair_m``: (P, N) meshing error
    of each pair; ``crowning_m``: (NS,) E_pc per slice (>= 0);
    ``force_N``: F = T1/rb1 >= 0.  See the module docstring for the secant
    stiffness and effective error given to the dynamic model.
    """
    k = np.asarray(k_slice_N_per_m, dtype=float)
    e = np.asarray(e_pair_m, dtype=float)
    E = np.asarray(crowning_m, dtype=float)
    if k.ndim != 3:
        raise LoadedMeshInputError(f"k_slice_N_per_m: expected shape (P, NS, N), got {k.shape}")
    P, NS, N = k.shape
    if e.shape != (P, N):
        raise LoadedMeshInputError(f"e_pair_m: expected shape {(P, N)}, got {e.shape}")
    if E.shape != (NS,):
        raise LoadedMeshInputError(f"crowning_m: expected shape {(NS,)}, got {E.shape}")
    if not np.all(np.isfinite(E)) or np.any(E < 0):
        raise LoadedMeshInputError("crowning_m: must be finite and >= 0")
    if not math.isfinite(force_N) or force_N < 0:
        raise LoadedMeshInputError(f"force_N: must be finite and >= 0, got {force_N!r}")
    gap = e[:, None, :] + E[None, :, None]                                  # (P, NS, N)
    kk = np.moveaxis(k, 2, 0).reshape(N, P * NS)
    gg = np.moveaxis(gap, 2, 0).reshape(N, P * NS)
    x = static_deflection_m(kk, gg, force_N)                                 # (N,)
    Fj = (k * np.maximum(0.0, x[None, None, :] - gap)).sum(axis=1)          # (P, N)
    lsr = Fj / force_N if force_N > 0 else np.zeros_like(Fj)
    ksum = k.sum(axis=1)                                                     # (P, N)
    in_zone = ksum > 0
    emin = float(E.min())
    e_eff = e + emin
    if np.all(E == E[0]):
        ksec = ksum.copy()
    else:
        dE = E - emin
        delta = x[None, :] - e_eff                                           # (P, N)
        delta_ref = x - np.where(in_zone, e_eff, np.inf).min(axis=0)         # (N,)
        loaded = in_zone & (delta > 0)
        d_use = np.where(loaded, delta, delta_ref[None, :])
        f_use = np.where(loaded, Fj, pair_force_N(np.moveaxis(k, 1, 2), dE, d_use))
        with np.errstate(divide="ignore", invalid="ignore"):
            ksec = np.where(d_use > 0, f_use / d_use, 0.0)
        tangent0 = (k * (dE == 0)[None, :, None]).sum(axis=1)                # first-touch tangent
        ksec = np.where(in_zone & ~(d_use > 0), tangent0, ksec)
        ksec = np.where(in_zone, ksec, 0.0)
    return LoadedMesh(force_N=float(force_N), static_te_m=x, pair_load_N=Fj, load_sharing=lsr,
                      k_secant_N_per_m=ksec, e_effective_m=e_eff)
