"""The gear-pair dynamics on the tables.

Imports :mod:`gearfmu.tables` and :mod:`gearfmu.common`.

===========  =========================================================
Module       Contents
===========  =========================================================
native       public API of the numba solver (simulate, simulate_sdof,
             SimResult), argument checks, step choice
driver       the one compiled loop over communication steps (all
             integrators and forms), output rows
integrators  RK4 step ('rk4') and the event-locating 'rk4_kink' substep
model_rhs    table lookup, per-pair force laws, contact-mode guards,
             quasi-static equilibrium (numba, the C kernel's arithmetic)
reference    event-located reference integrator (tests and benchmarks)
sweeps       steady-state sweeps through an executor
harmonics    mesh-harmonic amplitudes of the DTE (seed 003 eq 10-11)
===========  =========================================================
"""
