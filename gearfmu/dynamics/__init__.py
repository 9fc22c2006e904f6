"""The gear-pair dynamics on the tables.

Imports :mod:`gearfmu.tables` and :mod:`gearfmu.common`.

Exports (loaded with their module on first use): the native solver ``simulate``,
``simulate_sdof``, ``SimResult``, ``NativeInputError``, ``choose_max_step_s``,
``write_columns_csv``; the reference ``simulate_reference``, ``ReferenceInputError``; the sweeps
``run_sweep``, ``run_jobs``, ``SweepJob``, ``PointSettings``, ``find_jumps``; the harmonics
``mesh_harmonics``, ``MeshHarmonics``, ``autopower_one_sided``.

===========  =========================================================
Module       Contents
===========  =========================================================
native       public API of the numba solver (simulate, simulate_sdof,
             SimResult), argument checks, step choice
driver       the one compiled loop over communication steps (all
             integrators and forms), output rows
integrators  RK4 step ('rk4'), the event-locating 'rk4_kink' substep and
             its 'rk4_node' and 'rk4_seg' variants
model_rhs    table lookup, per-pair force laws, contact-mode guards,
             quasi-static equilibrium (numba, the C kernel's arithmetic)
seg_rhs      'rk4_seg' right-hand side and guards: per-evaluation cell in
             the held segment, shifted velocities
subcell      table values and quasi-static TE with or without the
             sub-cell lookup at the contact-zone edges (measurement)
reference    event-located reference integrator (tests and benchmarks)
sweeps       steady-state sweeps through an executor
harmonics    mesh-harmonic amplitudes of the DTE (Xu et al. 2022 eq 10-11)
===========  =========================================================
"""
from ..common.exports import lazy_exports

_EXPORTS = {
    **dict.fromkeys(("simulate", "simulate_sdof", "SimResult", "NativeInputError", "choose_max_step_s",
                     "write_columns_csv"), "native"),
    "simulate_reference": "reference", "ReferenceInputError": "reference",
    **dict.fromkeys(("run_sweep", "run_jobs", "SweepJob", "PointSettings", "find_jumps"), "sweeps"),
    **dict.fromkeys(("mesh_harmonics", "MeshHarmonics", "autopower_one_sided"), "harmonics"),
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
