"""The gear pair: specs, geometry, stiffness, deviations, loaded mesh, thermal state.

Imports :mod:`gearfmu.ehl` (the Walther viscosity law) and :mod:`gearfmu.common`.

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
thermal           ThermalOptions; temperature stiffness, thermal deformation (seed 004)
internal          internal (ring) gears: the planet-ring mesh geometry and its checks
internal_stiffness  ring tooth, rim and planet-ring tooth-pair stiffness (potential energy)
planetary_set     planetary gear sets: both meshes at one carrier radius, assembly,
                  planet interference, planet position errors
phasing           mesh phases of every sun-planet and ring-planet mesh (Parker & Lin)
================  =====================================================================
"""
