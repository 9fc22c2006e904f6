"""Tooth-pair tables: the interface between the physics and the dynamics.

Imports the physics (:mod:`gearfmu.gear`, :mod:`gearfmu.contact`, :mod:`gearfmu.ehl`).

==============  ============================================================
Module          Contents
==============  ============================================================
mesh_tables     MeshTables: the format (JSON + binary), temperature axis
estimate        cost estimate of tables, FMU and build time; the size guard
precompute      precompute_tables: gear pair -> tables (torque and temperature rows)
contact_rows    torque rows with a load-dependent contact model (EHL films)
load_iteration  the load-sharing iteration with a load-dependent contact stiffness
direct_tvms     mesh stiffness evaluated directly at given positions (films)
table_import    tables from CSV files, and back
synthetic       tables from textbook shapes (rectangular wave, ...)
==============  ============================================================
"""
