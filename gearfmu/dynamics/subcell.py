"""Table values and quasi-static transmission error with or without the sub-cell lookup at the
contact-zone edges (docs/model.md "Contact-zone edges"; SI units).

The numba lookup of :mod:`gearfmu.dynamics.model_rhs` evaluated at given pinion angles, for
measurement and tests of the table interpolation: with ``zone_edges=True`` and tables that carry
their engagement angles (:attr:`gearfmu.tables.mesh_tables.MeshTables.engagement_in_rad`) each
pair's stiffness steps exactly at its meshing-in and meshing-out angles
(:func:`gearfmu.tables.zones.zone_cuts`); ``zone_edges=False`` is the plain linear interpolation
of both kernels.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ..tables.mesh_tables import MeshTables, TableError
from ..tables.zones import zone_cuts
from .model_rhs import (
    _CELL_NONE, _equilibrium, _equilibrium_zoned, _kvals, _phi_cell, _ptr, _tab, _table_pointers, _torque_index,
    _with_zones,
)

__all__ = ["table_values", "static_te_m"]


@njit(cache=True, error_model="numpy")
def _values(phi, t1, k, e, b, torque, inv_dphi, cuts, zoned, out):
    it, wt = _torque_index(t1, torque)
    kp, ep, bp, p, n_phi = _table_pointers(k, e, b)
    no_flags = np.ones(1, dtype=np.uint8)
    tab = _tab(kp, ep, bp, it, k.shape[0] > 1, wt, n_phi, p, np.nan, 0.0, 0, inv_dphi, _ptr(no_flags))
    tz = _with_zones(tab, _ptr(cuts))
    for q in range(phi.shape[0]):
        nd, i0, i1, w = _phi_cell(phi[q], inv_dphi, n_phi, _CELL_NONE, 0)
        for j in range(p):
            if zoned:
                kv, ev, es, bv = _kvals(tz, j, i0, i1, w)
            else:
                kv, ev, es, bv = _kvals(tab, j, i0, i1, w)
            out[0, q, j] = kv
            out[1, q, j] = ev
            out[2, q, j] = es
            out[3, q, j] = bv


def _prepare(tables: MeshTables, zone_edges: bool):
    if tables.has_temperature_axis:
        raise TableError("tables: give single-temperature tables (MeshTables.at_temperature)")
    k = np.ascontiguousarray(tables.k_N_per_m, dtype=np.float64)
    e = np.ascontiguousarray(tables.e_m, dtype=np.float64)
    b = np.ascontiguousarray(tables.backlash_half_m, dtype=np.float64)
    tq = np.ascontiguousarray(tables.torque_Nm, dtype=np.float64)
    cuts = zone_cuts(tables) if zone_edges else None
    return k, e, b, tq, tables.n_phi / float(tables.phi_period_rad), cuts


def table_values(tables: MeshTables, phi_rad, pinion_torque_Nm: float = 0.0, *, zone_edges: bool = True):
    """(k (N/m), e (m), de/dphi (m/rad), b (m)) of every slot at the pinion angles ``phi_rad``
    (rad), each of shape (len(phi_rad), P), as the kernels look them up at pinion torque
    ``pinion_torque_Nm`` (N*m, selects the torque row).  ``zone_edges``: the sub-cell lookup at
    the contact-zone edges (no effect on tables without engagement angles)."""
    k, e, b, tq, inv_dphi, cuts = _prepare(tables, zone_edges)
    phi = np.ascontiguousarray(np.atleast_1d(np.asarray(phi_rad, dtype=np.float64)))
    out = np.empty((4, phi.size, k.shape[1]))
    zoned = cuts is not None
    _values(phi, float(pinion_torque_Nm), k, e, b, tq, inv_dphi, cuts if zoned else np.full((2, 1, 1), -1.0),
            zoned, out)
    return out[0], out[1], out[2], out[3]


def static_te_m(tables: MeshTables, pinion_torque_Nm: float, phi_rad, *, zone_edges: bool = True) -> np.ndarray:
    """Quasi-static transmission error x (m) at the pinion angles ``phi_rad`` (rad) under the
    constant mesh force F_m = T1/Rb1: the 200-bisection equilibrium of docs/model.md 'Initial
    state' on the looked-up k, e, b (``zone_edges`` as in :func:`table_values`)."""
    k, e, b, tq, inv_dphi, cuts = _prepare(tables, zone_edges)
    rb1 = float(tables.base_radius_pinion_m)
    t1 = float(pinion_torque_Nm)
    phi = np.atleast_1d(np.asarray(phi_rad, dtype=np.float64))
    if cuts is None:
        return np.array([_equilibrium(float(p), t1, rb1, k, e, b, tq, inv_dphi) for p in phi])
    return np.array([_equilibrium_zoned(float(p), t1, rb1, k, e, b, tq, inv_dphi, cuts) for p in phi])
