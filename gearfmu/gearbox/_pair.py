"""The pair model's numba kernels that the gearbox applies to every mesh: the one place that names them.

A stage of a gearbox is looked up and loaded exactly as the single pair is (docs/model.md
"Table lookup", "Contact-zone edges", "Per-pair force", "rk4_kink"): the gearbox kernels
(:mod:`gearfmu.gearbox.kernels`) call these functions of :mod:`gearfmu.dynamics` with each
mesh's own ``tab`` tuple, mode pointer and work pointer.  They are imported here and nowhere
else in the gearbox package, so that a rename in gearfmu.dynamics is a one-line fix.
"""
from ..dynamics.integrators import (  # noqa: F401  (re-exported to gearbox.kernels)
    KINK_MAX_EVENTS, KINK_MAX_SLOTS, _guard_at, _guard_root, _held_tables, _mode_sync, _node_time, _pairs_hold,
    _seg_cross, _seg_start, _switch_pair,
)
from ..dynamics.model_rhs import (  # noqa: F401  (re-exported to gearbox.kernels)
    NODE_KINK_TOL, _CELL_NONE, _cell_nodes, _kvals, _kvals_sel, _mesh_force, _node_flags, _pair_force,
    _pair_force_locked, _pair_guard, _phi_cell, _seg_flags, _stop_flags, _tab, _with_zones, _zone_sel,
)
from ..dynamics.seg_rhs import _guard_seg, _seg_cell, _seg_sel  # noqa: F401  (re-exported to the multi-mesh kernels)
