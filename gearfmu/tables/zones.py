"""Contact-zone edges of the tooth-pair tables and the sub-cell cuts of the lookup (SI units).

Every tooth pair's stiffness steps from 0 to a finite value where it enters mesh and back to 0
where it leaves (for a spur pair at the pinion angles 0 and eps_alpha*T from the start of its
mesh, T = 2*pi/z1).  A table stores k on a uniform angle grid; linear interpolation between the
last node outside the zone and the first node inside turns the step into a ramp one cell wide,
an O(h) error in the stiffness integral (h the cell width) that dominates the table error of the
dynamic response (docs/model.md "Contact-zone edges").

With the exact meshing-in and meshing-out angles (:attr:`MeshTables.engagement_in_rad`,
``engagement_out_rad``) the lookup treats k, e and b inside a cell that holds an edge as the
in-zone function times the zone indicator: the in-zone part of the cell takes the straight line
of the neighbouring cell on the in-zone side, extended (linear extrapolation, O(h^2)); the part
outside the zone has k = 0 (e and b there keep the plain interpolation; they act only with k > 0).

:func:`zone_cuts` gives the per-slot, per-cell description the kernels read: two arrays
(P, n_phi) of cell fractions, ``lo`` and ``hi``.  ``lo < 0`` (:data:`PLAIN`): the cell holds no
edge, plain linear interpolation.  Otherwise, at cell fraction w in [0, 1): w < lo is in the zone
of the pair that leaves inside this cell (extended line of the cell to the left), w >= hi in the
zone of the pair that enters inside this cell (extended line of the cell to the right), and
lo <= w < hi outside every zone (k = 0).  A cell without an exit has lo = 0, without an entry
hi = 1.
"""
from __future__ import annotations

import math
from typing import Optional

import numpy as np

from .mesh_tables import MeshTables, check_engagement, zone_edges_nodes  # noqa: F401 (re-exported)

#: ``lo`` of a cell that holds no zone edge (plain linear interpolation)
PLAIN = -1.0
#: fewest table cells a contact zone must span for the extrapolated lookup (each edge cell takes
#: the line of the next cell inside the zone, which must not hold an edge itself)
MIN_ZONE_CELLS = 3.0


#: an edge within this many cells of a node is put on the node (gearkernel.h GK_ZONE_SNAP): the
#: rounding of (n T + angle) N/Phi must not move an edge that lies on a node into the next cell
SNAP_CELLS = 1e-9


def _wrap(x: float, n: int) -> float:
    """x mod n for a float x, on the nearest node when within SNAP_CELLS of it (gk_zones.c
    zone_wrap: fmod, + n when negative, then the snap)."""
    r = math.fmod(x, float(n))
    if r < 0.0:
        r += float(n)
    rn = math.floor(r + 0.5)
    if abs(r - rn) <= SNAP_CELLS:
        r = rn
    return r


def zone_cuts(t: MeshTables) -> Optional[np.ndarray]:
    """(2, P, n_phi) float64 cuts (``lo``, ``hi`` of the module docstring) of the sub-cell
    lookup, C-contiguous; None when the tables carry no engagement angles or a zone spans
    fewer than :data:`MIN_ZONE_CELLS` cells (then the lookup stays plain linear interpolation).
    The arithmetic of gk_zones.c gk_zone_cuts (the FMU computes its cuts there), so the
    two give the same doubles."""
    if t.engagement_in_rad is None:
        return None
    p, n = t.slots, t.n_phi
    phi_period = float(t.phi_period_rad)
    inv = float(n) / phi_period
    a_in_rad, a_out_rad = float(t.engagement_in_rad), float(t.engagement_out_rad)
    if not (a_out_rad - a_in_rad) * inv >= MIN_ZONE_CELLS:
        return None
    n_mesh = int(math.floor(phi_period / float(t.mesh_period_rad) + 0.5))
    ppm = float(n) / float(n_mesh)
    a_in = a_in_rad * inv
    a_out = a_out_rad * inv
    lo = np.full((p, n), PLAIN)
    hi = np.ones((p, n))

    def mark(j, c):
        if lo[j, c] < 0.0:
            lo[j, c] = 0.0

    for m in range(n_mesh):
        j = m % p
        start = float(m) * ppm
        s = _wrap(start + a_in, n)          # meshing-in: the zone starts inside the cell
        fl = math.floor(s)
        f = s - fl
        c = (int(fl) - 1) % n if f == 0.0 else int(fl) % n   # on a node: the cell before is all outside
        mark(j, c)
        hi[j, c] = min(hi[j, c], 1.0 if f == 0.0 else f)
        s = _wrap(start + a_out, n)         # meshing-out: the zone ends inside the cell
        fl = math.floor(s)
        f = s - fl
        if f == 0.0:   # on a node: the cell before it all inside, the one after all outside
            c = (int(fl) - 1) % n
            mark(j, c)
            lo[j, c] = max(lo[j, c], 1.0)
            mark(j, int(fl) % n)
        else:
            c = int(fl) % n
            mark(j, c)
            lo[j, c] = max(lo[j, c], f)
    return np.ascontiguousarray(np.stack([lo, hi]))


def mean_total_stiffness_N_per_m(t: MeshTables, k_row) -> float:
    """Mean over the table period of the total stiffness sum_j k_j(phi) (N/m) of one operating
    row ``k_row`` (P, n_phi) as the kernels look it up: with the sub-cell rule at the
    contact-zone edges the exact integral of its pieces (the grid mean of the nodes is off by
    about a pair's stiffness times the fraction of a cell at every edge, a first-order error in
    the resolution that enters the damping through ``k_mean_N_per_m``); without engagement
    angles the grid mean (the mean of the periodic linear interpolant)."""
    k = np.asarray(k_row, dtype=float)
    cuts = zone_cuts(t)
    if cuts is None:
        return float(k.sum(axis=0).mean())
    lo, hi = cuts
    km = np.roll(k, 1, axis=1)       # node i0 - 1
    k1 = np.roll(k, -1, axis=1)      # node i1
    k2 = np.roll(k, -2, axis=1)      # node i1 + 1
    plain = 0.5 * (k + k1)
    left = lo * k + 0.5 * lo * lo * (k - km)                               # int_0^lo of the left line
    right = (1.0 - hi) * k1 - 0.5 * (1.0 - hi) ** 2 * (k2 - k1)            # int_hi^1 of the right line
    cell = np.where(lo < 0.0, plain, np.maximum(left, 0.0) + np.maximum(right, 0.0))
    return float(cell.sum(axis=0).mean())
