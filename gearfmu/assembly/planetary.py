"""The tables of a geometric planetary set and the stage built on them (SI units; docs/planetary.md).

Every planet has two meshes, each with its own :class:`gearfmu.tables.mesh_tables.MeshTables`:

* sun-planet (the sun the pinion): the external pair's tables of gearfmu.assembly.precompute at the
  carrier radius, with the planet's own deviations, the mesh options of the scene (contact model,
  foundation, slices), the sun torque share T_s/N as the nominal torque;
* planet-ring (the planet the pinion): per-pair stiffness of gearfmu.gear.internal_stiffness (the
  internal tooth, the planet's and ring's root terms, the rim), per-pair meshing errors from the
  planet's and ring's profile and pitch deviations (Xu et al. 2022 eq 15, gearfmu.gear.meshing_errors: the
  ring's roll length along the line of action is s + N1N2, its active profile runs from its root end
  at s_E + N1N2 to its tip at s_A + N1N2), the ring mesh's backlash; Hertz contact, one slice,
  load-independent stiffness, one torque row (CHOICE: the load-dependent contact models and lead
  crowning of the external pair are not carried over to internal meshes).

Identical planets share their tables.  Masses and inertias of the gears: solid discs between the hub
bore and the reference radius (gearfmu.assembly.precompute.disc_inertia_kgm2, and its mass); the ring:
an annulus between its root circle and root + rim thickness (or the given values); the carrier's are
given.  Pressure angles and radii: the operating values of each mesh at the carrier radius, so that
r_c cos(alpha_s) = r_s + r_p and r_c cos(alpha_r) = r_r - r_p hold exactly (involute geometry).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Dict, Optional

import numpy as np

from ..common.vocabulary import DEFAULT_DAMPING_MODEL
from ..gear.gearpair import GearPairSpec, GearSpec, MeshModelOptions
from ..gear.internal_stiffness import internal_slot_stiffness
from ..gear.meshing_errors import (EvaluationRanges, comprehensive_error_m, gear_teeth_differ, pair_error_m,
                                   slot_mesh_numbers, table_mesh_count)
from ..gear.phasing import mesh_phasing
from ..gear.planetary_set import PlanetarySet, PlanetarySetGeometry, planetary_geometry, position_error_deflections_m
from ..tables.mesh_tables import MeshTables
from ..tables.zones import mean_total_stiffness_N_per_m
from ..tables.planetary import PlanetaryStage, PlanetaryStageError
from .precompute import disc_inertia_kgm2, precompute_tables

__all__ = ["StageMechanics", "ring_planet_tables", "planetary_stage", "gear_mass_kg", "ring_mass_inertia"]


@dataclass(frozen=True)
class StageMechanics:
    """The parts of a geometric planetary stage that geometry does not give (SI): the carrier's mass
    and inertia, optional masses and inertias of the ring (None: the annulus of the rim), translational
    support stiffness of sun, ring and carrier and of the planet bearings (N/m), the held member's
    torsional support (N m/rad), the held port, the model, damping ratios and law."""

    carrier_mass_kg: float
    carrier_inertia_kgm2: float
    bearing_N_per_m: Dict[str, float]
    support_Nm_per_rad: float
    held: str = "ring"
    model: str = "translational"
    ring_mass_kg: Optional[float] = None
    ring_inertia_kgm2: Optional[float] = None
    mesh_damping_ratio: float = 0.05
    damping_model: str = DEFAULT_DAMPING_MODEL
    bearing_damping_ratio: float = 0.02


def gear_mass_kg(g: GearSpec) -> float:
    """Mass (kg) of a solid disc of the gear's material between the hub bore and the reference radius."""
    r = 0.5 * g.module_m * g.teeth
    rh = 0.0 if g.hub_radius_m is None else float(g.hub_radius_m)
    return g.material.density_kg_m3 * math.pi * g.face_width_m * (r * r - rh * rh)


def ring_mass_inertia(ring: GearSpec, rf2_m: float, rim_thickness_m: Optional[float]):
    """(mass kg, inertia kg m^2) of the ring's rim annulus between its root radius and root + rim
    thickness (teeth not counted); None when no rim thickness is given."""
    if rim_thickness_m is None:
        return None
    ro = rf2_m + float(rim_thickness_m)
    rho, b = ring.material.density_kg_m3, ring.face_width_m
    return rho * math.pi * b * (ro ** 2 - rf2_m ** 2), 0.5 * rho * math.pi * b * (ro ** 4 - rf2_m ** 4)


def ring_planet_tables(ps: PlanetarySet, geom: PlanetarySetGeometry, n: int, *, opts: MeshModelOptions,
                       points_per_mesh: int, nominal_planet_torque_Nm: float) -> MeshTables:
    """Tables of planet n's ring mesh (module docstring)."""
    rp = geom.ring_planet
    planet = ps.planet_spec(n)
    ring = ps.ring
    st = internal_slot_stiffness(planet, ring, ps.rim, rp, opts, None, points_per_mesh)
    P = st.k_N_per_m.shape[0]
    n_mesh = table_mesh_count(P, rp.z1, rp.z2, gear_teeth_differ(planet.deviations, rp.z1),
                              gear_teeth_differ(ring.deviations, rp.z2))
    reps = n_mesh // P
    k = np.tile(st.k_N_per_m, (1, reps))
    L = rp.loa_length_m
    ranges = EvaluationRanges(s_o_pinion_m=rp.s_start_m, s_f_pinion_m=rp.s_end_m, s_o_gear_m=-L - rp.s_end_m,
                              s_f_gear_m=-L - rp.s_start_m, n1n2_m=-L)
    mesh_no, local = slot_mesh_numbers(P, n_mesh, points_per_mesh)
    dphi = rp.mesh_period_rad / points_per_mesh
    s = np.clip(rp.s_start_m + rp.rb1_m * local * dphi, rp.s_start_m, rp.s_end_m)
    e = pair_error_m(GearPairSpec(planet, ring), ranges, mesh_no, s)
    ec = comprehensive_error_m(e[None], (k > 0)[None])
    mp_ = gear_mass_kg(planet)
    t = MeshTables(
        torque_Nm=np.array([float(nominal_planet_torque_Nm)]), k_N_per_m=np.ascontiguousarray(k[None]),
        e_m=np.ascontiguousarray(e[None]), backlash_half_m=np.full((P, n_mesh * points_per_mesh),
                                                                   0.5 * float(ps.backlash_ring_m)),
        phi_period_rad=n_mesh * rp.mesh_period_rad, mesh_period_rad=rp.mesh_period_rad, base_radius_pinion_m=rp.rb1_m,
        base_radius_gear_m=rp.rb2_m, inertia_pinion_kgm2=disc_inertia_kgm2(planet),
        inertia_gear_kgm2=_ring_inertia(ps, rp), teeth_pinion=rp.z1, teeth_gear=rp.z2,
        contact_ratio=rp.contact_ratio, k_mean_N_per_m=float(k.sum(axis=0).mean()),
        e_comprehensive_m=np.ascontiguousarray(ec), static_te_m=None,
        provenance={"planetary": {"mesh": "ring-planet", "planet": n + 1, "points_per_mesh": points_per_mesh,
                                  "slots": P, "table_mesh_periods": n_mesh, "planet_mass_kg": mp_,
                                  "rim_thickness_m": ps.rim.thickness_m, "rim_supports": ps.rim.supports,
                                  "model": "gearfmu.gear.internal_stiffness (potential energy, Sainsot root, "
                                           "curved-beam rim)"}},
        engagement_in_rad=0.0, engagement_out_rad=rp.contact_ratio * rp.mesh_period_rad)
    t.k_mean_N_per_m = mean_total_stiffness_N_per_m(t, t.k_N_per_m[0])
    return t.validate()


def _ring_inertia(ps: PlanetarySet, rp) -> float:
    mi = ring_mass_inertia(ps.ring, rp.rf2_m, ps.rim.thickness_m)
    if ps.ring.inertia_kgm2 is not None:
        return float(ps.ring.inertia_kgm2)
    if mi is None:   # only the mesh damping's m_e reads it: the ring's inertia barely enters it
        return 1e3 * disc_inertia_kgm2(ps.ring)
    return mi[1]


def planetary_stage(name: str, ps: PlanetarySet, mech: StageMechanics, *, opts: Optional[MeshModelOptions] = None,
                    points_per_mesh: int = 64, sun_torque_Nm: float, progress: bool = False,
                    where: Optional[str] = None) -> PlanetaryStage:
    """The :class:`gearfmu.tables.planetary.PlanetaryStage` of a geometric planetary set: its geometry and
    checks (gearfmu.gear.planetary_set), phases (gearfmu.gear.phasing), the tables of every planet's two
    meshes at the sun torque share ``sun_torque_Nm``/N (module docstring) and the mechanics ``mech``."""
    opts = MeshModelOptions() if opts is None else opts
    w = where or name
    geom = planetary_geometry(ps, where=w)
    sp, rp = geom.sun_planet, geom.ring_planet
    N = geom.planets
    if not (math.isfinite(sun_torque_Nm) and sun_torque_Nm > 0):
        raise PlanetaryStageError(f"{w}: the sun torque must be > 0 to build the tables, got {sun_torque_Nm!r}")
    ph = mesh_phasing(geom)
    sun_t, ring_t = [], []
    cache_s, cache_r = {}, {}
    for n in range(N):
        planet = ps.planet_spec(n)
        key = planet.deviations
        if key not in cache_s:
            pair = GearPairSpec(ps.sun, planet, backlash_m=ps.backlash_sun_m, center_distance_m=geom.carrier_radius_m)
            cache_s[key] = precompute_tables(pair, opts, points_per_mesh=points_per_mesh,
                                             nominal_torque_Nm=sun_torque_Nm / N, progress=progress)
            cache_r[key] = ring_planet_tables(ps, geom, n, opts=opts, points_per_mesh=points_per_mesh,
                                              nominal_planet_torque_Nm=sun_torque_Nm / N * rp.rb1_m / sp.rb1_m)
        sun_t.append(cache_s[key])
        ring_t.append(cache_r[key])
    ring_mi = ring_mass_inertia(ps.ring, rp.rf2_m, ps.rim.thickness_m)
    m_ring = mech.ring_mass_kg if mech.ring_mass_kg is not None else (ring_mi[0] if ring_mi else None)
    i_ring = mech.ring_inertia_kgm2 if mech.ring_inertia_kgm2 is not None else (ring_mi[1] if ring_mi else None)
    if m_ring is None or i_ring is None:
        raise PlanetaryStageError(f"{w}.ring: give the ring's mass and inertia, or its rim thickness (the rim annulus)")
    mass = {"sun": gear_mass_kg(ps.sun), "planet": gear_mass_kg(ps.planet), "ring": float(m_ring),
            "carrier": float(mech.carrier_mass_kg)}
    inertia = {"sun": disc_inertia_kgm2(ps.sun), "planet": disc_inertia_kgm2(ps.planet), "ring": float(i_ring),
               "carrier": float(mech.carrier_inertia_kgm2)}
    defl = tuple(position_error_deflections_m(ps.planet_error(n), sp.alpha_w_rad, rp.alpha_w_rad) for n in range(N))
    return PlanetaryStage(
        name=name, teeth_sun=sp.z1, teeth_planet=sp.z2, teeth_ring=rp.z2, base_radius_sun_m=sp.rb1_m,
        base_radius_planet_m=sp.rb2_m, base_radius_ring_m=rp.rb2_m, carrier_radius_m=geom.carrier_radius_m,
        pressure_angle_sun_rad=sp.alpha_w_rad, pressure_angle_ring_rad=rp.alpha_w_rad,
        planet_angles_rad=geom.planet_angles_rad, sun_tables=tuple(sun_t), ring_tables=tuple(ring_t), mass_kg=mass,
        inertia_kgm2=inertia, bearing_N_per_m=dict(mech.bearing_N_per_m), support_Nm_per_rad=mech.support_Nm_per_rad,
        held=mech.held, model=mech.model, ring_sun_phase_rad=ph.ring_offset_rad[0], position_deflections_m=defl,
        mesh_damping_ratio=mech.mesh_damping_ratio, damping_model=mech.damping_model,
        bearing_damping_ratio=mech.bearing_damping_ratio)
