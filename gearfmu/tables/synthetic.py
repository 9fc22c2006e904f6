"""Synthetic tooth-pair tables from textbook shapes (SI units).

These builders make :class:`gearfmu.tables.mesh_tables.MeshTables` without any physics
module, for tests, hard cases and imports from other tools:

* :func:`tables_from_arrays` wraps raw per-slot arrays (stiffness k in N/m,
  meshing error e in m, half backlash b in m, against pinion angle, optionally
  against pinion torque) into a validated :class:`MeshTables`.  CSV import of
  TVMS / transmission error from FE or LTCA tools builds on it.
* :func:`rectangular_wave_tables` gives the classic rectangular-wave time
  varying mesh stiffness (TVMS): every tooth pair is engaged for
  ``contact_ratio`` mesh periods, the total stiffness alternates between the
  double-contact level and the single-contact level (Xu et al. 2022 section 2,
  Fig. 2: pairs j-1, j, j+1 with the meshing periods t_z and t_h; the
  rectangular-wave TVMS is the usual textbook idealisation, e.g. Kahraman &
  Blankenship 1997, the reference [14] of Xu et al. 2022).

Defaults of the gear data are the Kahraman & Blankenship test gears of Xu et al. 2022
Table 1 (50/50 teeth, base diameter 140.95 mm, inertia 0.0074 kg*m^2 per gear,
contact ratio 1.7547, backlash on the line of action 0.136 mm).

Conventions (see gearfmu/tables/mesh_tables.py): slot ``n % P`` holds the pair that starts
mesh number n at pinion angle n*mesh_period_rad (n counted from phi = 0); a
slot whose pair is outside the contact zone has k = 0.  A positive meshing
error is a material deficit: the pair touches when x > e + b (Xu et al. 2022 eq 6).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from dataclasses import fields as dataclass_fields
from typing import Callable, Optional

import numpy as np

from ..common.checks import finite_number
from .mesh_tables import MeshTables, TableError
from .zones import mean_total_stiffness_N_per_m

__all__ = [
    "SyntheticTableError",
    "KB_BASE_RADIUS_M",
    "KB_INERTIA_KGM2",
    "KB_TEETH",
    "KB_CONTACT_RATIO",
    "KB_BACKLASH_HALF_M",
    "GearData",
    "tables_from_arrays",
    "rectangular_wave_tables",
    "comprehensive_error_m",
]

#: Kahraman & Blankenship test gears, Xu et al. 2022 Table 1 (base diameter 140.95 mm)
KB_BASE_RADIUS_M = 0.5 * 140.95e-3
#: Xu et al. 2022 Table 1, inertia of each gear (kg*m^2)
KB_INERTIA_KGM2 = 0.0074
#: Xu et al. 2022 Table 1, teeth of pinion and gear
KB_TEETH = 50
#: Xu et al. 2022 Table 1, contact ratio
KB_CONTACT_RATIO = 1.7547
#: Xu et al. 2022 Table 1, backlash on the line of action 0.136 mm; b = half of it (Xu et al. 2022 eq 6)
KB_BACKLASH_HALF_M = 0.5 * 0.136e-3


#: gear scalars :func:`rectangular_wave_tables` hands on to :func:`tables_from_arrays`
_GEAR_DATA = frozenset(("teeth_pinion", "teeth_gear", "base_radius_pinion_m", "base_radius_gear_m",
                        "inertia_pinion_kgm2", "inertia_gear_kgm2"))


class SyntheticTableError(TableError):
    """Bad argument to a synthetic table builder (a ValueError subclass)."""


def _positive(name: str, value) -> float:
    """``value`` as a finite float > 0 (SyntheticTableError naming ``name`` otherwise)."""
    return finite_number(name, value, positive=True, error=SyntheticTableError)


def comprehensive_error_m(k_N_per_m: np.ndarray, e_m: np.ndarray) -> np.ndarray:
    """Comprehensive (envelope) meshing error of the traditional model, (NT, n_phi) in m.

    Xu et al. 2022 (text around eq 15 and Fig. 5) builds the comprehensive error as the
    envelope of the single-pair errors in the multi-contact zones: the pair
    that governs is the one that touches first.  With this project's sign
    convention (Xu et al. 2022 eq 6: a pair touches when x > e + b, positive e =
    material deficit) that is the *smallest* e among the pairs in the contact
    zone (k > 0).  Choice made here; where no slot has k > 0 the error is 0.
    """
    k = np.asarray(k_N_per_m, dtype=float)
    e = np.asarray(e_m, dtype=float)
    masked = np.where(k > 0.0, e, np.inf)
    env = masked.min(axis=1)
    return np.where(np.isfinite(env), env, 0.0)


@dataclass(frozen=True)
class GearData:
    """The gear pair's data that the per-slot arrays of :func:`tables_from_arrays` do not carry
    (SI): base radii (m), rotary inertias (kg m^2) and teeth of pinion and gear (defaults: the
    Kahraman & Blankenship gears of Xu et al. 2022 Table 1), the contact ratio (None: the mean number
    of slots with k > 0 over the grid, for a rectangular wave the contact ratio exactly) and the
    exact meshing-in and meshing-out pinion angles (rad) of every pair from the start of its mesh
    (both or neither; None: the lookup interpolates plainly across the zone edges, docs/tables.md
    "Contact-zone edges")."""

    base_radius_pinion_m: float = KB_BASE_RADIUS_M
    base_radius_gear_m: float = KB_BASE_RADIUS_M
    inertia_pinion_kgm2: float = KB_INERTIA_KGM2
    inertia_gear_kgm2: float = KB_INERTIA_KGM2
    teeth_pinion: int = KB_TEETH
    teeth_gear: int = KB_TEETH
    contact_ratio: Optional[float] = None
    engagement_in_rad: Optional[float] = None
    engagement_out_rad: Optional[float] = None


_GEAR_FIELDS = tuple(f.name for f in dataclass_fields(GearData))


def _gear_data(gear: Optional[GearData], positional, named: dict) -> GearData:
    """``gear`` (None: the defaults) with the gear scalars given positionally (in the order of
    :class:`GearData`, the first six) and by name applied."""
    if gear is None:
        gear = GearData()
    elif not isinstance(gear, GearData):
        raise SyntheticTableError(f"gear: must be a GearData, got {type(gear).__name__}")
    if len(positional) > 6:
        raise SyntheticTableError(f"tables_from_arrays: at most 11 positional arguments, got {5 + len(positional)}")
    unknown = sorted(set(named) - set(_GEAR_FIELDS))
    if unknown:
        raise SyntheticTableError(f"{unknown[0]}: not an argument of tables_from_arrays")
    given = dict(zip(_GEAR_FIELDS, positional))
    twice = sorted(set(given) & set(named))
    if twice:
        raise SyntheticTableError(f"{twice[0]}: given twice (by position and by name)")
    given.update(named)
    return replace(gear, **given) if given else gear


def tables_from_arrays(
    phi_period_rad: Optional[float] = None,
    mesh_period_rad: Optional[float] = None,
    k_N_per_m=None,
    e_m=None,
    backlash_half_m=0.0,
    *gear_scalars,
    gear: Optional[GearData] = None,
    torque_Nm=None,
    k_mean_N_per_m: Optional[float] = None,
    e_comprehensive_m=None,
    static_te_m=None,
    provenance: Optional[dict] = None,
    **gear_fields,
) -> MeshTables:
    """Build validated :class:`MeshTables` from raw per-slot arrays.

    Parameters (SI units)
    ---------------------
    phi_period_rad : period of the pinion-angle axis (rad); default
        ``P * mesh_period_rad``.
    mesh_period_rad : one mesh period of the pinion (rad); default 2*pi/teeth_pinion.
    k_N_per_m : pair stiffness (N/m), shape (P, n_phi) or (NT, P, n_phi); grid
        ``phi_i = i*phi_period_rad/n_phi``, periodic.
    e_m : meshing error (m), same shape as k (default zeros).
    backlash_half_m : half backlash b (m, Xu et al. 2022 eq 6): scalar, (n_phi,) or (P, n_phi).
    gear : :class:`GearData` -- base radii, inertias, teeth, contact ratio, engagement angles.
        Each of its fields may also be given by name (``teeth_pinion=23``,
        ``engagement_in_rad=0.0``), and the first six, the gear scalars
        base_radius_pinion_m, base_radius_gear_m, inertia_pinion_kgm2, inertia_gear_kgm2,
        teeth_pinion, teeth_gear, by position after ``backlash_half_m``.
    torque_Nm : torque axis (N*m), shape (NT,), strictly ascending; required when
        k has 3 axes with NT > 1, default [0.0] otherwise.
    k_mean_N_per_m : mean mesh stiffness k_m of Xu et al. 2022 eq 7 (N/m); default =
        mean of the total stiffness over the phi grid and all torque rows (the
        grid mean equals the mean of the periodic linear interpolant; with engagement
        angles the mean of the sub-cell lookup, gearfmu.tables.zones.mean_total_stiffness_N_per_m).
    e_comprehensive_m : (NT, n_phi) (m); default :func:`comprehensive_error_m`.
    static_te_m : (NT, n_phi) static transmission error (m), optional.
    provenance : dict stored with the tables (default: names this function).

    Raises :class:`SyntheticTableError` / :class:`TableError` (ValueError) naming the field.
    """
    g = _gear_data(gear, gear_scalars, gear_fields)
    k, e, b, tq = _table_arrays(k_N_per_m, e_m, backlash_half_m, torque_Nm)
    nt, p, nphi = k.shape
    z1 = int(g.teeth_pinion)
    z2 = int(g.teeth_gear)
    if z1 != g.teeth_pinion or z1 < 1:
        raise SyntheticTableError(f"teeth_pinion: must be a positive integer, got {g.teeth_pinion!r}")
    if z2 != g.teeth_gear or z2 < 1:
        raise SyntheticTableError(f"teeth_gear: must be a positive integer, got {g.teeth_gear!r}")
    mp = 2.0 * math.pi / z1 if mesh_period_rad is None else _positive("mesh_period_rad", mesh_period_rad)
    pp = p * mp if phi_period_rad is None else _positive("phi_period_rad", phi_period_rad)
    if not np.all(np.isfinite(k)):
        raise SyntheticTableError("k_N_per_m: contains NaN or infinite values")
    if np.any(k < 0):
        raise SyntheticTableError("k_N_per_m: negative stiffness")
    ktot = k.sum(axis=1)
    contact_ratio = g.contact_ratio
    if contact_ratio is None:
        contact_ratio = float((k > 0).sum(axis=1).mean())
    km = float(ktot.mean()) if k_mean_N_per_m is None else _positive("k_mean_N_per_m", k_mean_N_per_m)
    exact_mean = k_mean_N_per_m is None and g.engagement_in_rad is not None
    if e_comprehensive_m is None:
        ec = comprehensive_error_m(k, e)
    else:
        ec = np.array(e_comprehensive_m, dtype=float)
        if ec.ndim == 1:
            ec = ec[None, :]
    st = None if static_te_m is None else np.atleast_2d(np.array(static_te_m, dtype=float))
    t = MeshTables(
        torque_Nm=tq, k_N_per_m=np.ascontiguousarray(k), e_m=np.ascontiguousarray(e),
        backlash_half_m=np.ascontiguousarray(b),
        phi_period_rad=float(pp), mesh_period_rad=float(mp),
        base_radius_pinion_m=_positive("base_radius_pinion_m", g.base_radius_pinion_m),
        base_radius_gear_m=_positive("base_radius_gear_m", g.base_radius_gear_m),
        inertia_pinion_kgm2=_positive("inertia_pinion_kgm2", g.inertia_pinion_kgm2),
        inertia_gear_kgm2=_positive("inertia_gear_kgm2", g.inertia_gear_kgm2),
        teeth_pinion=z1, teeth_gear=z2,
        contact_ratio=_positive("contact_ratio", contact_ratio),
        k_mean_N_per_m=km,
        e_comprehensive_m=np.ascontiguousarray(ec),
        static_te_m=st,
        provenance=dict(provenance or {"source": "gearfmu.tables.synthetic.tables_from_arrays"}),
        engagement_in_rad=None if g.engagement_in_rad is None else float(g.engagement_in_rad),
        engagement_out_rad=None if g.engagement_out_rad is None else float(g.engagement_out_rad),
    )
    t.validate()
    if exact_mean:  # the mean of the sub-cell lookup over the rows (docs/tables.md "Contact-zone edges")
        t.k_mean_N_per_m = float(np.mean([mean_total_stiffness_N_per_m(t, t.k_N_per_m[r]) for r in range(nt)]))
    return t.validate()


def _table_arrays(k_N_per_m, e_m, backlash_half_m, torque_Nm):
    """(k (NT, P, n_phi), e of the same shape, b (P, n_phi), torque axis (NT,)) from the
    arguments of :func:`tables_from_arrays` (e default zeros and repeated over the torque rows
    when given for one; b broadcast from a scalar or (n_phi,); torque default [0.0])."""
    if k_N_per_m is None:
        raise SyntheticTableError("k_N_per_m: required")
    k = np.array(k_N_per_m, dtype=float)
    if k.ndim == 2:
        k = k[None, :, :]
    if k.ndim != 3:
        raise SyntheticTableError(f"k_N_per_m: expected shape (P, n_phi) or (NT, P, n_phi), got {k.shape}")
    nt, p, nphi = k.shape
    if e_m is None:
        e = np.zeros_like(k)
    else:
        e = np.array(e_m, dtype=float)
        if e.ndim == 2:
            e = e[None, :, :]
        if e.shape == (1, p, nphi) and nt > 1:
            e = np.repeat(e, nt, axis=0)
        if e.shape != k.shape:
            raise SyntheticTableError(f"e_m: shape {np.shape(e_m)} does not match k_N_per_m {k.shape}")
    b = np.array(backlash_half_m, dtype=float)
    if b.ndim == 0:
        b = np.full((p, nphi), float(b))
    elif b.ndim == 1:
        if b.shape != (nphi,):
            raise SyntheticTableError(f"backlash_half_m: 1-D shape must be ({nphi},), got {b.shape}")
        b = np.repeat(b[None, :], p, axis=0)
    if b.shape != (p, nphi):
        raise SyntheticTableError(f"backlash_half_m: expected scalar, ({nphi},) or ({p}, {nphi}), got {b.shape}")
    if torque_Nm is None:
        if nt > 1:
            raise SyntheticTableError(f"torque_Nm: required when k_N_per_m has {nt} torque rows")
        tq = np.zeros(1)
    else:
        tq = np.atleast_1d(np.array(torque_Nm, dtype=float))
        if tq.shape != (nt,):
            raise SyntheticTableError(f"torque_Nm: shape {tq.shape}, expected ({nt},)")
    return k, e, b, tq


def rectangular_wave_tables(
    k_single_N_per_m: float,
    k_double_N_per_m: Optional[float] = None,
    *,
    contact_ratio: float = KB_CONTACT_RATIO,
    points_per_mesh: int = 64,
    backlash_half_m: float = 0.0,
    pair_error_m: Optional[Callable[[int, np.ndarray], np.ndarray]] = None,
    slots: Optional[int] = None,
    mesh_periods: Optional[int] = None,
    zone_edges: bool = False,
    **gear_data,
) -> MeshTables:
    """Rectangular-wave TVMS tables (k in N/m, e in m, angles in rad).

    Pair n is engaged for pinion angles ``phi - n*T`` in ``[0, contact_ratio*T)``
    (T = mesh period = 2*pi/teeth_pinion, mod the table period).  With n(phi)
    pairs engaged the *total* stiffness is ``k_single_N_per_m`` for n = 1,
    ``k_double_N_per_m`` (default 2*k_single) for n = 2 and
    ``n*k_double/2`` for n >= 3; each engaged pair carries total/n, so the
    total TVMS is the classic rectangular wave of Xu et al. 2022 Fig. 2 / eq 4-5
    (double zone t_h - t_z, single zone 2 t_z - t_h per mesh period).

    ``pair_error_m(slot, u)`` (optional) gives the meshing error (m) of the pair
    in ``slot`` at engagement fraction ``u`` in [0, 1) (u = (phi - start)/(eps*T));
    it is only sampled where the pair is engaged (0 elsewhere).

    ``gear_data``: the gear scalars of :func:`tables_from_arrays` (``teeth_pinion``,
    ``teeth_gear``, ``base_radius_pinion_m``, ``base_radius_gear_m``, ``inertia_pinion_kgm2``,
    ``inertia_gear_kgm2``; defaults there, the Kahraman & Blankenship gears).

    Grid: ``points_per_mesh`` points per mesh period; the tables hold
    ``mesh_periods`` mesh periods (default = slots = ceil(contact_ratio)); the
    table value at a grid point is the engaged/not-engaged state *at* the point,
    so the stored wave is a trapezoid with ramps one grid step wide once it is
    linearly interpolated (docs/model.md table lookup).

    ``zone_edges``: also carry the engagement angles 0 and ``contact_ratio*T``, so that
    the kernels put each pair's own meshing-in and meshing-out steps exactly there
    (docs/model.md "Contact-zone edges").  Off by default (choice): a pair of the
    rectangular wave also steps *inside* its zone, wherever another pair enters or leaves
    (it carries total/count), and those steps stay one-cell ramps; the default keeps the
    textbook trapezoid that the dynamics validation against Xu et al. 2022 and the reference
    solvers of the tests are built on.
    """
    ks = _positive("k_single_N_per_m", k_single_N_per_m)
    kd = 2.0 * ks if k_double_N_per_m is None else _positive("k_double_N_per_m", k_double_N_per_m)
    eps = _positive("contact_ratio", contact_ratio)
    if eps < 1.0:
        raise SyntheticTableError(f"contact_ratio: must be >= 1 (continuous contact), got {eps!r}")
    npm = int(points_per_mesh)
    if npm != points_per_mesh or npm < 4:
        raise SyntheticTableError(f"points_per_mesh: must be an integer >= 4, got {points_per_mesh!r}")
    need = int(math.ceil(eps - 1e-12))
    p = need if slots is None else int(slots)
    if p < need:
        raise SyntheticTableError(f"slots: {slots!r} is fewer than ceil(contact_ratio) = {need}")
    nmesh = p if mesh_periods is None else int(mesh_periods)
    if nmesh < p or nmesh % p != 0:
        raise SyntheticTableError(f"mesh_periods: must be a positive multiple of slots={p}, got {mesh_periods!r}")
    unknown = sorted(set(gear_data) - _GEAR_DATA)
    if unknown:
        raise SyntheticTableError(f"{unknown[0]}: not an argument of rectangular_wave_tables")
    teeth_pinion = gear_data.pop("teeth_pinion", KB_TEETH)
    z1 = int(teeth_pinion)
    if z1 != teeth_pinion or z1 < 1:
        raise SyntheticTableError(f"teeth_pinion: must be a positive integer, got {teeth_pinion!r}")
    b_half = float(backlash_half_m)
    if not math.isfinite(b_half) or b_half < 0:
        raise SyntheticTableError(f"backlash_half_m: must be finite and >= 0, got {backlash_half_m!r}")
    mp = 2.0 * math.pi / z1
    nphi = nmesh * npm
    grid = np.arange(nphi)
    engaged = np.zeros((p, nphi), dtype=bool)
    frac = np.zeros((p, nphi))
    span = eps * npm  # engagement length in grid steps
    for n in range(nmesh):  # pair n starts at grid index n*npm, lives in slot n % P
        local = (grid - n * npm) % nphi
        on = local < span * (1.0 - 1e-12)
        if np.any(engaged[n % p] & on):
            raise SyntheticTableError("slots: two pairs overlap in one slot; increase slots")
        engaged[n % p] |= on
        frac[n % p] = np.where(on, local / span, frac[n % p])
    count = engaged.sum(axis=0)
    if np.any(count == 0):
        raise SyntheticTableError("contact_ratio: leaves angles with no pair engaged")
    total = np.where(count == 1, ks, np.where(count == 2, kd, count * kd / 2.0))
    k = np.where(engaged, (total / count)[None, :], 0.0)
    e = np.zeros((p, nphi))
    if pair_error_m is not None:
        for j in range(p):
            vals = np.asarray(pair_error_m(j, frac[j]), dtype=float)
            e[j] = np.where(engaged[j], np.broadcast_to(vals, (nphi,)), 0.0)
    return tables_from_arrays(
        phi_period_rad=nmesh * mp, mesh_period_rad=mp, k_N_per_m=k, e_m=e,
        backlash_half_m=b_half, teeth_pinion=z1, contact_ratio=eps, **gear_data,
        engagement_in_rad=0.0 if zone_edges else None, engagement_out_rad=eps * mp if zone_edges else None,
        provenance={"source": "gearfmu.tables.synthetic.rectangular_wave_tables",
                    "k_single_N_per_m": ks, "k_double_N_per_m": kd, "contact_ratio": eps,
                    "points_per_mesh": npm, "backlash_half_m": b_half},
    )
