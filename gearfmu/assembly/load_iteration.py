"""The loaded mesh with a load-dependent contact stiffness: how the load splits among the
tooth pairs and face-width slices in contact when each slice's contact stiffness depends on
that slice's own load (docs/ehl_mesh.md "Load sharing").

One iteration, used by the table builder (:mod:`gearfmu.assembly.precompute`) and the direct
TVMS (:mod:`gearfmu.assembly.direct_tvms`): from given slice loads, every slice in contact gets
its contact stiffness at its line load (at least a load floor), the slices are combined into
the slice mesh stiffness, and the loaded static mesh (Zhao et al. 2022 eq 16,
:func:`gearfmu.gear.loaded_mesh.loaded_static_mesh`) gives the next slice loads.  A request is
re-solved only when its line load moved by more than ``0.1 * LOAD_ITERATION_TOL`` of itself
(a film is expensive); the iteration stops when no slice load changes by more than
``LOAD_ITERATION_TOL`` x F/NS between passes, or after ``LOAD_ITERATION_MAX`` passes (with a
warning).  SI units.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Optional, Tuple
import warnings

import numpy as np

from ..gear.loaded_mesh import loaded_static_mesh

#: largest change of a slice load between passes, relative to the mean slice load F/NS
LOAD_ITERATION_TOL = 1e-3
#: pass limit of the load-sharing iteration
LOAD_ITERATION_MAX = 8
#: load floor of every slice in the contact zone (light or no static load), a share of the
#: mean line load F/b: its film is evaluated there (docs/ehl_mesh.md)
UNLOADED_SLICE_LOAD_SHARE = 0.5


def slice_loads_N(k_slice, e_pair, crowning, force_N):
    """(P, NS, N) static slice loads F_jn = k_jn max(0, x_s - e_j - E_n) (Zhao et al. 2022 eq 16) of
    slice stiffness ``k_slice`` (P, NS, N; N/m), pair errors ``e_pair`` (P, N; m), lead
    crowning ``crowning`` (NS,; m) under the mesh force ``force_N`` (N)."""
    lm = loaded_static_mesh(k_slice, e_pair, crowning, force_N)
    gap = e_pair[:, None, :] + crowning[None, :, None]
    return k_slice * np.maximum(0.0, lm.static_te_m[None, None, :] - gap)


@dataclass
class LoadSharing:
    """Result of :func:`iterate_load_sharing`: ``k_slice_N_per_m`` (P, NS, N) slice mesh
    stiffness of the last pass, ``k_contact_N_per_m`` (P, NS, N) the contact stiffness behind
    it (0 out of the zone), ``loads_N`` (P, NS, N) static slice loads with that stiffness,
    ``passes`` and ``load_change`` (max slice-load change of the last pass over F/NS)."""

    k_slice_N_per_m: np.ndarray
    k_contact_N_per_m: np.ndarray
    loads_N: np.ndarray
    passes: int
    load_change: float


#: ``solve(w, redo, pass_no) -> (k, frozen)``: the contact stiffness (N/m) of the zone
#: entries ``redo`` (bool mask over the zone) at line loads ``w[redo]`` (N/m), and a bool mask
#: over the zone of entries to keep from now on (failed films), or None
ContactSolve = Callable[[np.ndarray, np.ndarray, int], Tuple[np.ndarray, Optional[np.ndarray]]]


def iterate_load_sharing(loads_N: np.ndarray, e_pair_m: np.ndarray, crowning_m: np.ndarray, force_N: float,
                         zone, line_width_m, floor_N_per_m: float, solve: ContactSolve,
                         mesh_stiffness: Callable[[np.ndarray], np.ndarray], *, what: str) -> LoadSharing:
    """Iterate the slice loads with a load-dependent contact stiffness (module doc).

    ``loads_N`` (P, NS, N): the starting slice loads (e.g. with the Hertz stiffness);
    ``e_pair_m`` (P, N), ``crowning_m`` (NS,), ``force_N``: the loaded mesh (Zhao et al. 2022 eq 16);
    ``zone``: the (j, n, i) index arrays of the (pair, slice, position) entries in contact;
    ``line_width_m``: the contact length a slice load is spread over (scalar, or one per zone
    entry); ``floor_N_per_m``: the smallest line load a film is solved at; ``solve``: see
    :data:`ContactSolve`; ``mesh_stiffness(k_contact)`` -> (P, NS, N) slice mesh stiffness
    from the contact stiffness (the tooth and foundation compliances of the caller);
    ``what`` names the computation in the warning when the iteration does not converge.
    A (position, slice) whose film failed keeps its fallback stiffness in later passes
    (re-trying it at a slightly different load would let the sharing oscillate)."""
    j, n, i = zone
    loads = loads_N
    kc = np.zeros(loads.shape)
    w_prev = np.full(j.shape, np.nan)
    frozen = np.zeros(j.shape, dtype=bool)
    NS = loads.shape[1]
    F = float(force_N)
    change = float("nan")
    k = None
    for it in range(1, LOAD_ITERATION_MAX + 1):
        w = np.maximum(loads[zone] / line_width_m, floor_N_per_m)
        redo = ~(np.abs(w - w_prev) <= 0.1 * LOAD_ITERATION_TOL * w_prev) & ~frozen
        if np.any(redo):
            vals, failed = solve(w, redo, it)
            kc[j[redo], n[redo], i[redo]] = vals
            w_prev = np.where(redo, w, w_prev)
            if failed is not None:
                frozen |= failed
        k = mesh_stiffness(kc)
        new = slice_loads_N(k, e_pair_m, crowning_m, F)
        change = float(np.max(np.abs(new - loads)) / max(F / NS, 1e-300)) if F > 0 else 0.0
        loads = new
        if change < LOAD_ITERATION_TOL:
            break
    else:
        warnings.warn(f"{what}: load sharing not converged after {LOAD_ITERATION_MAX} passes "
                      f"(max slice-load change {change:.2e} of F/NS)")
    return LoadSharing(k, kc, loads, it, change)
