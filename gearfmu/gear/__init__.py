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
================  =====================================================================
"""
