"""Tooth-pair tables: the format, the interface between the physics and the dynamics.

Imports only :mod:`gearfmu.common`: the format knows nothing of the physics that fills it
(:mod:`gearfmu.assembly` builds the tables of a gear pair).

==============  ============================================================
Module          Contents
==============  ============================================================
mesh_tables     MeshTables: the format (JSON + binary, .gtab), temperature axis
zones           contact-zone edges, mean total stiffness
table_import    tables from CSV files, and back
synthetic       tables from textbook shapes (rectangular wave, ...)
planetary       PlanetaryStage: a planetary stage's mesh tables and lumped parameters
==============  ============================================================
"""
