"""The gear pair: specs, geometry, stiffness, deviations, loaded mesh, thermal state.

Imports :mod:`gearfmu.ehl` (the Walther viscosity law) and :mod:`gearfmu.common`.

Exports (loaded with their module on first use): the specs ``GearSpec``, ``GearPairSpec``,
``GearDeviations``, ``ToothDeviation``, ``Material``, ``MeshModelOptions``; ``pair_geometry``,
``PairGeometry``, ``GeometryError``; ``slot_stiffness``, ``mean_mesh_stiffness_N_per_m``;
``hertz_stiffness_N_per_m``, ``reduced_modulus_Pa``; ``loaded_static_mesh``; ``ThermalOptions``.

================  =====================================================================
Module            Contents
================  =====================================================================
gearpair          GearSpec, GearPairSpec, GearDeviations, MeshModelOptions (plain data)
geometry          involute spur/helical pair geometry, contact ratio, checks
hertz             Hertzian line-contact stiffness, reduced modulus
foundation        fillet-foundation compliance (Sainsot, Velex & Duverger 2004)
stiffness         tooth, foundation and tooth-pair mesh stiffness (TVMS)
meshing_errors    per-tooth-pair meshing errors, lead crowning
loaded_mesh       loaded static mesh: load sharing among pairs and slices
thermal           ThermalOptions; temperature stiffness, thermal deformation (He & Yang 2023)
internal          internal (ring) gears: the planet-ring mesh geometry and its checks
internal_stiffness  ring tooth, rim and planet-ring tooth-pair stiffness (potential energy)
planetary_set     planetary gear sets: both meshes at one carrier radius, assembly,
                  planet interference, planet position errors
phasing           mesh phases of every sun-planet and ring-planet mesh (Parker & Lin)
================  =====================================================================
"""
from ..common.exports import lazy_exports

_EXPORTS = {
    **dict.fromkeys(("GearSpec", "GearPairSpec", "GearDeviations", "ToothDeviation", "Material",
                     "MeshModelOptions"), "gearpair"),
    "pair_geometry": "geometry", "PairGeometry": "geometry", "GeometryError": "geometry",
    "slot_stiffness": "stiffness", "mean_mesh_stiffness_N_per_m": "stiffness",
    "hertz_stiffness_N_per_m": "hertz", "reduced_modulus_Pa": "hertz",
    "loaded_static_mesh": "loaded_mesh",
    "ThermalOptions": "thermal",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
