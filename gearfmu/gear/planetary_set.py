"""A planetary gear set: sun, N planets on a carrier, ring -- its geometry, the checks of the set, and
the meshing errors its planets' positions add (SI units: m, rad).

Every planet meshes with the sun (an external pair, gearfmu.gear.geometry, the sun as pinion) and
with the ring (an internal pair, gearfmu.gear.internal, the planet as pinion) at one centre
distance, the carrier radius a_c.  :func:`planetary_geometry` builds both pairs and rejects
impossible sets with the reason (each a :class:`PlanetarySetError` naming the field):

* every pair check of the sun-planet and planet-ring meshes (interference, pointed teeth, contact
  ratio, tip clearance; the planet's tip radius is the one its sun mesh sets, with that mesh's tip
  shortening);
* coaxiality: both meshes at the carrier radius (a given a_c may lie up to 1e-3 modules below the
  sun mesh's zero-backlash centre distance and up to 0.01 modules above the ring mesh's, for rounded
  published data);
* the assembly condition (e.g. H. W. Müller, *Epicyclic Drive Trains*, Wayne State University Press
  1982, ch. 2; R. G. Parker, J. Lin, *Mesh phasing relationships in planetary and epicyclic gears*,
  J. Mech. Des. 126 (2004) 365-370): a planet fits at carrier angle psi_n (measured from planet 1,
  counter-clockwise) only when (z_s + z_r) psi_n/(2 pi) is an integer; for N equally spaced planets
  (z_s + z_r)/N must be an integer;
* planet interference: the tip circles of neighbouring planets must not overlap,
  2 a_c sin(dpsi/2) > 2 ra_p.

Planet position errors (:class:`PlanetErrors`): the pin of planet n displaced by e_r (radially
outwards) and e_t (tangentially, counter-clockwise) moves the planet as its translations zeta,
eta of the translational model do (gearfmu.planetary.model): it changes the sun-mesh deflection by
-e_r sin(alpha_s) - e_t cos(alpha_s) and the ring-mesh deflection by +e_r sin(alpha_r) -
e_t cos(alpha_r) (Lin & Parker 1999's mesh deflections).  :func:`position_error_deflections_m`
returns them; the tables take them as per-mesh meshing errors (docs/planetary.md).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Optional, Tuple

from .gearpair import GearDeviations, GearPairSpec, GearSpec
from .geometry import GeometryError, PairGeometry, pair_geometry
from .internal import InternalGearError, InternalPairGeometry, RingRim, internal_pair_geometry

__all__ = ["PlanetarySetError", "PlanetErrors", "PlanetarySet", "PlanetarySetGeometry", "planetary_geometry",
           "equally_spaced_angles_rad", "position_error_deflections_m"]


class PlanetarySetError(GeometryError):
    """An impossible or badly specified planetary set (message names the field)."""


@dataclass(frozen=True)
class PlanetErrors:
    """Position error of one planet's pin (m): radial (outwards) and tangential (counter-clockwise)."""

    radial_m: float = 0.0
    tangential_m: float = 0.0


@dataclass(frozen=True)
class PlanetarySet:
    """A planetary gear set (SI): sun, planet and ring gears (the planet spec holds the deviations of
    every planet unless ``planet_deviations`` gives one per planet), the ring's rim, the number of
    planets and their carrier angles (rad from planet 1, counter-clockwise; None = equally spaced),
    the carrier radius (m; None = the sun mesh's zero-backlash centre distance), the total backlash
    of the sun and ring meshes along their lines of action (m) and the planets' position errors."""

    sun: GearSpec
    planet: GearSpec
    ring: GearSpec
    planets: int
    rim: RingRim = RingRim()
    planet_angles_rad: Optional[Tuple[float, ...]] = None
    carrier_radius_m: Optional[float] = None
    backlash_sun_m: float = 0.0
    backlash_ring_m: float = 0.0
    planet_deviations: Optional[Tuple[GearDeviations, ...]] = None
    planet_errors: Tuple[PlanetErrors, ...] = field(default=())

    def planet_spec(self, n: int) -> GearSpec:
        """The GearSpec of planet n (0-based) with its own deviations."""
        if self.planet_deviations is None:
            return self.planet
        return replace(self.planet, deviations=self.planet_deviations[n])

    def planet_error(self, n: int) -> PlanetErrors:
        return self.planet_errors[n] if self.planet_errors else PlanetErrors()


@dataclass(frozen=True)
class PlanetarySetGeometry:
    """The checked geometry of a planetary set: the sun-planet pair (sun = pinion), the planet-ring
    pair (planet = pinion), the carrier radius (m), the planet angles (rad) and the smallest gap
    between neighbouring planets' tip circles (m)."""

    sun_planet: PairGeometry
    ring_planet: InternalPairGeometry
    carrier_radius_m: float
    planet_angles_rad: Tuple[float, ...]
    planet_gap_m: float

    @property
    def planets(self) -> int:
        return len(self.planet_angles_rad)

    @property
    def equally_spaced(self) -> bool:
        n = self.planets
        return all(abs(a - 2.0 * math.pi * i / n) < 1e-12 for i, a in enumerate(self.planet_angles_rad))


def equally_spaced_angles_rad(n: int) -> Tuple[float, ...]:
    """Carrier angles 2 pi k/N of N equally spaced planets (rad)."""
    return tuple(2.0 * math.pi * k / n for k in range(n))


def _check_count(n) -> int:
    if isinstance(n, bool) or int(n) != n or n < 1:
        raise PlanetarySetError(f"planets: must be a positive integer, got {n!r}")
    return int(n)


def planetary_geometry(ps: PlanetarySet, *, where: str = "planetary") -> PlanetarySetGeometry:
    """Build and check the geometry of a planetary set (module docstring); ``where`` prefixes the
    field names in messages."""
    n = _check_count(ps.planets)
    zs, zr = int(ps.sun.teeth), int(ps.ring.teeth)
    m = float(ps.sun.module_m)
    angles = equally_spaced_angles_rad(n) if ps.planet_angles_rad is None else tuple(float(a) for a in ps.planet_angles_rad)
    if len(angles) != n:
        raise PlanetarySetError(f"{where}.planet_angles_deg: {len(angles)} angles for {n} planets")
    if any(not math.isfinite(a) for a in angles) or abs(angles[0]) > 1e-12:
        raise PlanetarySetError(f"{where}.planet_angles_deg: finite angles from planet 1 at 0 deg, got "
                                f"{[math.degrees(a) for a in angles]}")
    if any(not (0.0 <= a < 2.0 * math.pi) for a in angles) or any(b <= a for a, b in zip(angles, angles[1:])):
        raise PlanetarySetError(f"{where}.planet_angles_deg: must increase from 0 and stay below 360 deg")
    for name, g in (("sun", ps.sun), ("ring", ps.ring)):
        if abs(g.module_m - m) > 1e-12 * m or abs(g.pressure_angle_rad - ps.planet.pressure_angle_rad) > 1e-12:
            raise PlanetarySetError(f"{where}.{name}: module and pressure angle must equal the planet's")
    if abs(ps.planet.module_m - m) > 1e-12 * m:
        raise PlanetarySetError(f"{where}.planet.module_mm: must equal the sun's")
    # assembly condition
    if ps.planet_angles_rad is None:
        if (zs + zr) % n:
            raise PlanetarySetError(
                f"{where}.planets: (z_s + z_r)/N = {zs + zr}/{n} = {(zs + zr) / n:.6g} is not an integer: {n} equally "
                "spaced planets cannot be assembled (assembly condition; change a tooth count or space the planets "
                "unequally)")
    else:
        for k, a in enumerate(angles):
            q = (zs + zr) * a / (2.0 * math.pi)
            if abs(q - round(q)) > 1e-6:
                raise PlanetarySetError(
                    f"{where}.planet_angles_deg[{k}]: planet {k + 1} at {math.degrees(a):.8g} deg cannot be assembled: "
                    f"(z_s + z_r) psi/360 = {q:.6g} must be an integer (planet positions are multiples of "
                    f"360/(z_s + z_r) = {360.0 / (zs + zr):.6g} deg)")
    # the two meshes at one centre distance
    try:
        sp0 = pair_geometry(GearPairSpec(ps.sun, ps.planet))
    except GeometryError as exc:
        raise PlanetarySetError(f"{where} (sun-planet mesh): {exc}") from None
    a_c = sp0.center_distance_m if ps.carrier_radius_m is None else float(ps.carrier_radius_m)
    try:
        sp = pair_geometry(GearPairSpec(ps.sun, ps.planet, backlash_m=ps.backlash_sun_m, center_distance_m=a_c))
    except GeometryError as exc:
        raise PlanetarySetError(f"{where} (sun-planet mesh): {exc}") from None
    try:
        rp = internal_pair_geometry(ps.planet, ps.ring, a_c, planet_tip_radius_m=sp.ra2_m, where="ring")
    except InternalGearError as exc:
        if "exceeds the zero-backlash centre distance" in str(exc):
            try:
                rp0 = internal_pair_geometry(ps.planet, ps.ring, planet_tip_radius_m=sp.ra2_m, where="ring")
            except InternalGearError:
                raise PlanetarySetError(f"{where} (planet-ring mesh): {exc}") from None
            raise PlanetarySetError(
                f"{where}.carrier_radius_mm: the planets cannot mesh with sun and ring at one centre distance: "
                f"{a_c * 1e3:.6g} mm for the sun mesh, at most {rp0.center_distance_m * 1e3:.6g} mm for the ring mesh "
                "(profile shifts: x_s + x_p sets the first, x_p + x_r the second)") from None
        raise PlanetarySetError(f"{where} (planet-ring mesh): {exc}") from None
    # planet interference
    gap = math.inf
    if n > 1:
        ra_p = sp.ra2_m
        for k in range(n):
            d = (angles[(k + 1) % n] - angles[k]) % (2.0 * math.pi)
            g = 2.0 * a_c * math.sin(0.5 * d) - 2.0 * ra_p
            if g < gap:
                gap = g
            if g <= 0.0:
                raise PlanetarySetError(
                    f"{where}.planets: planets {k + 1} and {(k + 1) % n + 1} overlap: their centres are "
                    f"{2.0 * a_c * math.sin(0.5 * d) * 1e3:.6g} mm apart, their tip circles need "
                    f"{2.0 * ra_p * 1e3:.6g} mm (fewer planets, or smaller planets)")
    if ps.planet_deviations is not None and len(ps.planet_deviations) != n:
        raise PlanetarySetError(f"{where}.planet_deviations: {len(ps.planet_deviations)} entries for {n} planets")
    if ps.planet_errors and len(ps.planet_errors) != n:
        raise PlanetarySetError(f"{where}.planet_errors: {len(ps.planet_errors)} entries for {n} planets")
    for k, e in enumerate(ps.planet_errors):
        for nm in ("radial_m", "tangential_m"):
            v = getattr(e, nm)
            if not math.isfinite(v) or abs(v) > m:
                raise PlanetarySetError(f"{where}.planet_errors[{k}].{nm}: must be finite and within one module "
                                        f"({m * 1e3:g} mm), got {v!r}")
    return PlanetarySetGeometry(sun_planet=sp, ring_planet=rp, carrier_radius_m=a_c, planet_angles_rad=angles,
                                planet_gap_m=gap)


def position_error_deflections_m(err: PlanetErrors, alpha_sun_rad: float, alpha_ring_rad: float) -> Tuple[float, float]:
    """(sun-mesh, ring-mesh) deflection (m, Lin & Parker's delta_sn, delta_rn sign) that a pin
    position error adds (module docstring)."""
    d_s = -err.radial_m * math.sin(alpha_sun_rad) - err.tangential_m * math.cos(alpha_sun_rad)
    d_r = err.radial_m * math.sin(alpha_ring_rad) - err.tangential_m * math.cos(alpha_ring_rad)
    return d_s, d_r
