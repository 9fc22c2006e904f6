"""Tooth-pair tables: the format, the interface between the physics and the dynamics.

Imports only :mod:`gearfmu.common`: the format knows nothing of the physics that fills it
(:mod:`gearfmu.assembly` builds the tables of a gear pair).

Exports (loaded with their module on first use): ``MeshTables``, ``load_tables``, ``TableError``,
``TemperatureRangeError``; ``load_tables_file``, ``load_tables_csv``, ``tables_to_csv``,
``TableImportError``; ``tables_from_arrays``, ``rectangular_wave_tables``;
``mean_total_stiffness_N_per_m``.

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
from ..common.exports import lazy_exports

_EXPORTS = {
    **dict.fromkeys(("MeshTables", "load_tables", "TableError", "TemperatureRangeError"), "mesh_tables"),
    **dict.fromkeys(("load_tables_file", "load_tables_csv", "tables_to_csv", "TableImportError"), "table_import"),
    "tables_from_arrays": "synthetic", "rectangular_wave_tables": "synthetic",
    "mean_total_stiffness_N_per_m": "zones",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
