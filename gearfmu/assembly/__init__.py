"""Table assembly: the physics of a gear pair turned into tooth-pair tables (SI units).

Takes specs and settings (gear-pair spec, mesh options, contact environment, thermal options;
never a Scene: the scene layer, :mod:`gearfmu.scene.physics`, reads them off a scene), calls
the physics (:mod:`gearfmu.gear`, :mod:`gearfmu.contact`, :mod:`gearfmu.ehl`) with arrays and
writes the result in the table format of :mod:`gearfmu.tables`.  Imports those packages and
:mod:`gearfmu.common`; nothing above them.

Exports (loaded with their module on first use): ``precompute_tables``;
``direct_mesh_stiffness``, ``TransientFilmSettings``; the cost model ``estimate_cost``,
``BuildEstimate``, ``BuildTooLargeError``.  The table cache is used as its module
(``gearfmu.assembly.table_cache``).

==============  ============================================================
Module          Contents
==============  ============================================================
precompute      precompute_tables: gear pair -> tables (torque and temperature rows)
contact_rows    torque rows with a load-dependent contact model (EHL films, helical
                normal section)
load_iteration  the load-sharing iteration with a load-dependent contact stiffness
direct_tvms     mesh stiffness evaluated directly at given positions (films)
estimate        cost model of a table build and its FMU; the size limits
table_cache     the table cache, keyed on precompute_tables' arguments
planetary       a geometric planetary set -> its stage: every planet's sun-planet and
                planet-ring tables, masses, inertias, phases, pin position errors
planetary_lumped  a planetary stage from published lumped parameters (Lin & Parker style)
==============  ============================================================
"""
from ..common.exports import lazy_exports

_EXPORTS = {
    "precompute_tables": "precompute",
    "direct_mesh_stiffness": "direct_tvms", "TransientFilmSettings": "direct_tvms",
    **dict.fromkeys(("estimate_cost", "BuildEstimate", "BuildTooLargeError"), "estimate"),
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
