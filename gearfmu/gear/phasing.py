"""Mesh phasing of a planetary set: where every sun-planet and ring-planet mesh stands in its mesh
cycle when the set is at its reference position (SI: rad; phases in mesh cycles).

R. G. Parker, J. Lin, *Mesh phasing relationships in planetary and epicyclic gears*, J. Mech.
Des. 126 (2004) 365-370; R. G. Parker, *A physical explanation for the effectiveness of planet
phasing to suppress planetary gear vibration*, J. Sound Vib. 236 (2000) 561-573.

Table angles (gearfmu.tables.mesh_tables: a pair enters its contact zone at table angle 0 in
slot 0 and the table angle advances with the pinion's forward rotation): the sun mesh of planet
n reads its tables at sigma (theta_s - theta_c) + phi_sn, the ring mesh at sigma' (theta_pn -
theta_c) + phi_rn (the planet as the ring mesh's pinion), with sigma = +1 when the sun turns
counter-clockwise relative to the carrier in the tables' forward sense (sigma' = -sigma: the
planet then spins clockwise).  At the reference (all angles 0):

* sun meshes: planet n sees the sun turned by -psi_n, so phi_sn = -sigma psi_n (sun angle); in
  mesh cycles gamma_sn = -sigma z_s psi_n/(2 pi) (mod 1) -- Parker & Lin's sun-planet phase;
* ring meshes: planet n sees the ring turned by -psi_n; the ring's relative angle and the planet's
  spin are tied by rb_p theta_p = rb_r theta_r, so phi_rn = phi_r1 + sigma (z_r/z_p) psi_n (planet
  angle), gamma_rn = sigma z_r psi_n/(2 pi) (mod 1), equal to gamma_sn whenever the assembly
  condition holds ((z_s + z_r) psi_n/(2 pi) an integer);
* the ring mesh of a planet against its own sun mesh, gamma_rs = phi_r1 z_p/(2 pi) (mod 1), from
  the planet's tooth geometry: with the planet at the origin, the sun on its -x side (planet frame
  x along the carrier radius), the sun mesh's line of action runs through the pitch point along
  d = (sin alpha_s, cos alpha_s), its planet tangent point at polar angle pi - alpha_s, and meets the
  planet's counter-clockwise flanks (involutes unwinding clockwise, starting on the base circle at
  beta_j + psi_b); the ring mesh's runs along (sin alpha_r, -cos alpha_r), its planet tangent point
  at polar angle alpha_r, and meets the clockwise flanks (starting at beta_j - psi_b); psi_b =
  pi/(2 z_p) + 2 x_p tan(alpha)/z_p + inv(alpha), beta_j = beta_0 + 2 pi j/z_p the tooth centre lines.
  The sun mesh at table angle 0 puts a planet flank at s_A (planet roll N1N2 - s_A), which fixes
  beta_0 = pi - alpha_s - psi_b + (N1N2 - s_A)/rb_p; the ring mesh's flank nearest ahead of its entry
  point s_A' then stands at
      phi_r1 = alpha_r + psi_b - beta_0 - s_A'/rb_p    (mod 2 pi/z_p).
  (alpha_s, alpha_r: the operating pressure angles of the two meshes.)

"In phase" meshing: every gamma_sn = 0 (e.g. z_s/N an integer for N equally spaced planets);
otherwise "sequential" (Parker & Lin).  Planet position and tooth errors are per-mesh meshing
errors (gearfmu.gear.planetary_set, gearfmu.planetary.tables), not phases.

:func:`parker_harmonic_excitation` states Parker's (2000) rule for equally spaced planets: the
l-th mesh harmonic excites only rotational modes when l z_s/N is an integer, only translational
modes when (l z_s +- 1)/N is, and neither otherwise (only planet modes).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence, Tuple

from .geometry import half_tooth_angle_at_base
from .planetary_set import PlanetarySetGeometry

__all__ = ["MeshPhasing", "mesh_phasing", "lumped_phasing", "ring_sun_phase_rad", "parker_harmonic_excitation"]


@dataclass(frozen=True)
class MeshPhasing:
    """Phases of a planetary set's meshes (module docstring): the tables' forward sense ``sigma``
    (+1: the sun turns counter-clockwise relative to the carrier), per planet the table angle of its
    sun mesh (sun angle, rad) and of its ring mesh (planet angle, rad) at the reference, the phases
    in mesh cycles relative to planet 1's sun mesh ([0, 1)), planet 1's ring-against-sun phase, and
    whether the sun meshes are in phase."""

    sigma: int
    sun_offset_rad: Tuple[float, ...]
    ring_offset_rad: Tuple[float, ...]
    gamma_sun: Tuple[float, ...]
    gamma_ring: Tuple[float, ...]
    gamma_rs: float
    in_phase: bool

    def to_dict(self) -> dict:
        return {"sigma": self.sigma, "gamma_sun": list(self.gamma_sun), "gamma_ring": list(self.gamma_ring),
                "gamma_rs": self.gamma_rs, "in_phase": self.in_phase,
                "sun_offset_rad": list(self.sun_offset_rad), "ring_offset_rad": list(self.ring_offset_rad)}


def _frac(v: float) -> float:
    f = v - math.floor(v)
    return 0.0 if abs(f) < 1e-12 or abs(f - 1.0) < 1e-12 else f


def ring_sun_phase_rad(geom: PlanetarySetGeometry) -> float:
    """phi_r1 (planet angle, rad, in [0, 2 pi/z_p)): planet 1's ring-mesh table angle when its sun
    mesh stands at table angle 0 (module docstring)."""
    sp, rp = geom.sun_planet, geom.ring_planet
    zp, xp = rp.z1, rp.x1
    rb = rp.rb1_m
    psi_b = half_tooth_angle_at_base(zp, xp, rp.alpha_rad)
    beta0 = math.pi - sp.alpha_w_rad - psi_b + (sp.loa_length_m - sp.s_start_m) / rb
    phi = rp.alpha_w_rad + psi_b - beta0 - rp.s_start_m / rb
    T = 2.0 * math.pi / zp
    return phi - T * math.floor(phi / T)


def _phases(zs: int, zp: int, zr: int, angles: Sequence[float], phi_r1: float, sigma: int) -> MeshPhasing:
    s_off = tuple(-sigma * a for a in angles)
    r_off = tuple(phi_r1 + sigma * (zr / zp) * a for a in angles)
    g_s = tuple(_frac(-sigma * zs * a / (2.0 * math.pi)) for a in angles)
    g_r = tuple(_frac(sigma * zr * a / (2.0 * math.pi)) for a in angles)
    return MeshPhasing(sigma=int(sigma), sun_offset_rad=s_off, ring_offset_rad=r_off, gamma_sun=g_s, gamma_ring=g_r,
                       gamma_rs=_frac(phi_r1 * zp / (2.0 * math.pi)), in_phase=all(g == 0.0 for g in g_s))


def mesh_phasing(geom: PlanetarySetGeometry, sigma: int = 1) -> MeshPhasing:
    """Phases of every mesh of a planetary set from its tooth counts, planet angles and tooth geometry
    (module docstring); ``sigma`` the tables' forward sense of the sun (+1 counter-clockwise relative
    to the carrier, -1 clockwise: the mirror image, same phases with the planet angles mirrored)."""
    if sigma not in (1, -1):
        raise ValueError(f"sigma: must be +1 or -1, got {sigma!r}")
    sp, rp = geom.sun_planet, geom.ring_planet
    return _phases(sp.z1, sp.z2, rp.z2, geom.planet_angles_rad, ring_sun_phase_rad(geom), sigma)


def lumped_phasing(teeth_sun: int, teeth_planet: int, teeth_ring: int, planet_angles_rad: Sequence[float],
                   gamma_rs: float = 0.0, sigma: int = 1) -> MeshPhasing:
    """Phases of a lumped planetary (no tooth geometry): from the tooth counts and planet angles, with
    planet 1's ring-against-sun phase ``gamma_rs`` (mesh cycles) given."""
    if not (math.isfinite(gamma_rs)):
        raise ValueError(f"gamma_rs: must be finite, got {gamma_rs!r}")
    phi_r1 = _frac(gamma_rs) * 2.0 * math.pi / teeth_planet
    return _phases(int(teeth_sun), int(teeth_planet), int(teeth_ring), planet_angles_rad, phi_r1, sigma)


def parker_harmonic_excitation(harmonic: int, teeth_sun: int, planets: int) -> str:
    """Parker (2000): which modes the ``harmonic``-th mesh harmonic excites in a planetary set with
    ``planets`` equally spaced planets: 'rotational' (l z_s/N an integer), 'translational'
    ((l z_s +- 1)/N an integer) or 'planet' (neither: the net forces and torques on the central
    members cancel, only planet modes respond)."""
    q = harmonic * teeth_sun
    if q % planets == 0:
        return "rotational"
    if (q + 1) % planets == 0 or (q - 1) % planets == 0:
        return "translational"
    return "planet"
