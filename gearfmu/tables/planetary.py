"""A planetary stage as the solvers read it (SI units): per planet the tables of its sun-planet and
planet-ring meshes, and the stage's lumped parameters (docs/planetary.md "The stage").

The physics fills it -- :mod:`gearfmu.assembly.planetary` from the geometry of a planetary set,
:mod:`gearfmu.assembly.planetary_lumped` from published lumped parameters -- and the planetary
solvers (:mod:`gearfmu.planetary`) check it and build their model from it, as a gear pair's
:class:`gearfmu.tables.mesh_tables.MeshTables` sits between its physics and its solver.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Dict, Optional, Tuple

import numpy as np

from ..common.vocabulary import DEFAULT_DAMPING_MODEL, DEFAULT_PLANETARY_MODEL, PLANETARY_PORTS
from .mesh_tables import MeshTables

__all__ = ["PlanetaryStageError", "PlanetaryStage", "shift_meshing_error"]


class PlanetaryStageError(ValueError):
    """A planetary stage that cannot be built or is inconsistent; the message names the field."""


@dataclass(frozen=True)
class PlanetaryStage:
    """A planetary stage (SI).  Geometry: tooth counts, base radii (m), carrier radius r_c (m,
    planet centres), operating pressure angles of the sun and ring meshes (rad), planet angles psi_n
    (rad from planet 1, counter-clockwise).  Tables per planet: ``sun_tables[n]`` (sun the pinion,
    planet the gear) and ``ring_tables[n]`` (planet the pinion, ring the gear);
    ``ring_sun_phase_rad``: planet 1's ring-mesh table angle when its sun mesh is at 0
    (gearfmu.gear.phasing); ``position_deflections_m``: per planet the (sun, ring) mesh deflections
    (m, Lin & Parker's sign) its pin position error adds.  Masses (kg) and inertias (kg m^2) of sun,
    ring, carrier and one planet; translational support stiffness of sun, ring and carrier and the
    planet bearings (N/m); torsional support of the held member (N m/rad); ``held``: the grounded
    port; ``model``: 'translational' or 'torsional' (gearfmu.common.vocabulary.PLANETARY_MODELS);
    mesh damping ratio and law; bearing damping ratio (c = 2 zeta sqrt(k m) of the supported
    body).  ``source``: where the numbers come from (shown in reports).  ``driven_speed_rad_s``: None
    (the ``held`` port is grounded through its support), or the speed (rad/s) at which the support's
    outer end turns: the ``held`` port is then *driven* by a speed-controlled drive through its support
    (docs/planetary.md "Driven members")."""

    name: str
    teeth_sun: int
    teeth_planet: int
    teeth_ring: int
    base_radius_sun_m: float
    base_radius_planet_m: float
    base_radius_ring_m: float
    carrier_radius_m: float
    pressure_angle_sun_rad: float
    pressure_angle_ring_rad: float
    planet_angles_rad: Tuple[float, ...]
    sun_tables: Tuple[MeshTables, ...]
    ring_tables: Tuple[MeshTables, ...]
    mass_kg: Dict[str, float]
    inertia_kgm2: Dict[str, float]
    bearing_N_per_m: Dict[str, float]
    support_Nm_per_rad: float
    held: str = "ring"
    model: str = DEFAULT_PLANETARY_MODEL
    ring_sun_phase_rad: float = 0.0
    position_deflections_m: Tuple[Tuple[float, float], ...] = ()
    mesh_damping_ratio: float = 0.05
    damping_model: str = DEFAULT_DAMPING_MODEL
    bearing_damping_ratio: float = 0.02
    source: str = ""
    driven_speed_rad_s: Optional[float] = None

    @property
    def planets(self) -> int:
        return len(self.planet_angles_rad)

    def port(self, p: str) -> str:
        """The part name of port ``p`` ('sun', 'carrier' or 'ring')."""
        return f"{self.name}.{p}"

    @property
    def free_ports(self) -> Tuple[str, str]:
        """The two ports that are not held."""
        return tuple(p for p in PLANETARY_PORTS if p != self.held)


def shift_meshing_error(t: MeshTables, x0_m: float) -> MeshTables:
    """Tables whose meshing errors (and comprehensive error and static TE) are lowered by ``x0_m``
    (m): the same as adding ``x0_m`` to the mesh's deflection x (a constant deflection such as a
    planet's pin position error, docs/planetary.md "Planet position errors")."""
    if x0_m == 0.0:
        return t
    e = np.asarray(t.e_m, dtype=float) - x0_m
    ec = None if t.e_comprehensive_m is None else np.asarray(t.e_comprehensive_m, dtype=float) - x0_m
    st = None if t.static_te_m is None else np.asarray(t.static_te_m, dtype=float) - x0_m
    prov = dict(t.provenance, position_error_shift_m=float(x0_m))
    return replace(t, e_m=np.ascontiguousarray(e), e_comprehensive_m=ec, static_te_m=st, provenance=prov)
