"""Planetary stages from published lumped parameters (SI units; docs/planetary.md "Lumped stages").

A lumped-parameter planetary model from the literature (Lin & Parker 1999, Kahraman 1994 and
the many papers that reuse their parameter tables) gives masses, I/r^2 of every member, mean mesh
stiffness, bearing and torsional support stiffness (N/m along u = r theta) and the pressure angle
-- no tooth geometry.  :func:`lumped_stage` enters such a table as published and builds the
:class:`gearfmu.tables.planetary.PlanetaryStage` of it:

* base radii: the sun's r_s is given; r_p = r_s z_p/z_s and r_r = r_s z_r/z_s (one base pitch, so
  both meshes have one mesh frequency); the carrier radius r_c = (r_s + r_p)/cos(alpha_s) and the
  ring mesh's pressure angle cos(alpha_r) = (r_r - r_p)/r_c follow (alpha_r = alpha_s when
  z_r = z_s + 2 z_p); a given alpha_r must agree;
* inertias I = (I/r^2) r^2 with the member's radius (the carrier's r_c), so that the model in
  angles is the published one in u = r theta (the eigenvalues do not depend on r);
* torsional supports k_u (N/m on u) become k_u r^2 (N m/rad);
* mesh tables: the rectangular-wave stiffness of gearfmu.tables.synthetic with the published mean
  stiffness k_m and a contact ratio eps (single-pair level k_m/eps, double 2 k_m/eps; eps = 1: a
  constant stiffness, the linear time-invariant model of the paper), no meshing error, the given
  backlash;
* mesh phases from the tooth counts and planet angles (gearfmu.gear.phasing.lumped_phasing), planet
  1's ring-against-sun phase given (default 0).

The tooth counts only set the kinematics and the mesh frequency; they are not part of most
published lumped tables and are chosen by the user (stated with the example).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional, Tuple

from ..common.checks import finite_number
from ..common.vocabulary import DEFAULT_DAMPING_MODEL
from ..gear.phasing import lumped_phasing
from ..gear.planetary_set import PlanetErrors, equally_spaced_angles_rad, position_error_deflections_m
from ..tables.synthetic import rectangular_wave_tables
from ..tables.planetary import PlanetaryStage, PlanetaryStageError

__all__ = ["LumpedPlanetary", "lumped_stage"]


@dataclass(frozen=True)
class LumpedPlanetary:
    """Published lumped parameters of a planetary stage (SI): masses (kg) and I/r^2 (kg) of sun, ring,
    carrier and one planet; mean mesh stiffness of the sun and ring meshes (N/m); translational support
    stiffness of sun, ring, carrier (x and y alike) and of the planet bearings (N/m); torsional support
    of the held member along u = r theta (N/m); operating pressure angle of the sun mesh (rad; the ring
    mesh's follows, or is checked when given); tooth counts; the sun's base radius (m); planet angles
    (rad, None = equally spaced); contact ratios of the two meshes' rectangular-wave tables (1 =
    constant stiffness); half backlash (m); planet 1's ring-against-sun phase (mesh cycles); pin
    position errors; table points per mesh period; the held member's torsional support in N m/rad
    instead of ``support_N_per_m`` (when given)."""

    planets: int
    mass_kg: dict
    inertia_over_r2_kg: dict
    mesh_stiffness_sun_N_per_m: float
    mesh_stiffness_ring_N_per_m: float
    bearing_N_per_m: dict
    support_N_per_m: float
    pressure_angle_sun_rad: float
    teeth_sun: int
    teeth_planet: int
    teeth_ring: int
    base_radius_sun_m: float
    pressure_angle_ring_rad: Optional[float] = None
    planet_angles_rad: Optional[Tuple[float, ...]] = None
    contact_ratio_sun: float = 1.0
    contact_ratio_ring: float = 1.0
    backlash_half_m: float = 0.0
    gamma_rs: float = 0.0
    planet_errors: Tuple[PlanetErrors, ...] = field(default=())
    points_per_mesh: int = 32
    support_Nm_per_rad: Optional[float] = None


def lumped_stage(name: str, p: LumpedPlanetary, *, held: str = "ring", model: str = "translational",
                 mesh_damping_ratio: float = 0.05, damping_model: str = DEFAULT_DAMPING_MODEL,
                 bearing_damping_ratio: float = 0.02, where: Optional[str] = None) -> PlanetaryStage:
    """The :class:`PlanetaryStage` of published lumped parameters (module docstring); ``where`` names
    the parameter set in messages (default the stage name)."""
    w = where or name
    err = PlanetaryStageError
    zs, zp, zr = (int(v) for v in (p.teeth_sun, p.teeth_planet, p.teeth_ring))
    if min(zs, zp, zr) < 1 or zr <= zp:
        raise err(f"{w}.teeth: sun, planet and ring need positive tooth counts, the ring more than the planet")
    rs = finite_number(f"{w}.base_radius_sun_m", p.base_radius_sun_m, positive=True, error=err)
    a_s = finite_number(f"{w}.pressure_angle_sun_rad", p.pressure_angle_sun_rad, positive=True, error=err)
    if not a_s < math.pi / 2:
        raise err(f"{w}.pressure_angle_sun_rad: must lie below 90 deg")
    rp, rr = rs * zp / zs, rs * zr / zs
    rc = (rs + rp) / math.cos(a_s)
    c_r = (rr - rp) / rc
    if not -1.0 < c_r < 1.0:
        raise err(f"{w}.teeth: the ring mesh has no pressure angle at the carrier radius (cos = {c_r:.6g})")
    a_r = math.acos(c_r)
    if p.pressure_angle_ring_rad is not None and abs(p.pressure_angle_ring_rad - a_r) > 1e-9:
        raise err(f"{w}.pressure_angle_ring_rad: {math.degrees(p.pressure_angle_ring_rad):.6g} deg disagrees with "
                  f"the tooth counts and the sun mesh ({math.degrees(a_r):.6g} deg: r_c cos(alpha_r) = r_r - r_p)")
    n = int(p.planets)
    if n < 1:
        raise err(f"{w}.planets: must be >= 1, got {p.planets!r}")
    angles = equally_spaced_angles_rad(n) if p.planet_angles_rad is None else tuple(p.planet_angles_rad)
    if len(angles) != n:
        raise err(f"{w}.planet_angles_deg: {len(angles)} angles for {n} planets")
    radius = {"sun": rs, "ring": rr, "carrier": rc, "planet": rp}
    inertia = {}
    for key in ("sun", "ring", "carrier", "planet"):
        ir2 = finite_number(f"{w}.inertia_over_r2_kg[{key}]", p.inertia_over_r2_kg.get(key), positive=True, error=err)
        inertia[key] = ir2 * radius[key] ** 2
    ks = finite_number(f"{w}.mesh_stiffness_sun_N_per_m", p.mesh_stiffness_sun_N_per_m, positive=True, error=err)
    kr = finite_number(f"{w}.mesh_stiffness_ring_N_per_m", p.mesh_stiffness_ring_N_per_m, positive=True, error=err)
    ph = lumped_phasing(zs, zp, zr, angles, p.gamma_rs)
    sun_t = rectangular_wave_tables(ks / p.contact_ratio_sun, contact_ratio=p.contact_ratio_sun,
                                    points_per_mesh=p.points_per_mesh, backlash_half_m=p.backlash_half_m,
                                    teeth_pinion=zs, teeth_gear=zp, base_radius_pinion_m=rs, base_radius_gear_m=rp,
                                    inertia_pinion_kgm2=inertia["sun"], inertia_gear_kgm2=inertia["planet"])
    ring_t = rectangular_wave_tables(kr / p.contact_ratio_ring, contact_ratio=p.contact_ratio_ring,
                                     points_per_mesh=p.points_per_mesh, backlash_half_m=p.backlash_half_m,
                                     teeth_pinion=zp, teeth_gear=zr, base_radius_pinion_m=rp, base_radius_gear_m=rr,
                                     inertia_pinion_kgm2=inertia["planet"], inertia_gear_kgm2=inertia["ring"])
    errs = tuple(p.planet_errors) or tuple(PlanetErrors() for _ in range(n))
    if len(errs) != n:
        raise err(f"{w}.planet_errors: {len(errs)} entries for {n} planets")
    defl = tuple(position_error_deflections_m(e, a_s, a_r) for e in errs)
    if p.support_Nm_per_rad is not None:
        k_held = finite_number(f"{w}.support_Nm_per_rad", p.support_Nm_per_rad, positive=True, error=err)
    else:
        k_held = finite_number(f"{w}.support_N_per_m", p.support_N_per_m, positive=True, error=err) * radius[held] ** 2
    return PlanetaryStage(
        name=name, teeth_sun=zs, teeth_planet=zp, teeth_ring=zr, base_radius_sun_m=rs, base_radius_planet_m=rp,
        base_radius_ring_m=rr, carrier_radius_m=rc, pressure_angle_sun_rad=a_s, pressure_angle_ring_rad=a_r,
        planet_angles_rad=angles, sun_tables=(sun_t,) * n, ring_tables=(ring_t,) * n,
        mass_kg=dict(p.mass_kg), inertia_kgm2=inertia, bearing_N_per_m=dict(p.bearing_N_per_m),
        support_Nm_per_rad=k_held, held=held, model=model,
        ring_sun_phase_rad=ph.ring_offset_rad[0], position_deflections_m=defl, mesh_damping_ratio=mesh_damping_ratio,
        damping_model=damping_model, bearing_damping_ratio=bearing_damping_ratio)
