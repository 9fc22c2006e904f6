"""The gear-pair dynamics on the tables.

Imports :mod:`gearfmu.tables` and :mod:`gearfmu.common`.

===========  =========================================================
Module       Contents
===========  =========================================================
native       the numba solver (simulate, simulate_sdof), step choice
reference    event-located reference integrator (tests and benchmarks)
sweeps       steady-state sweeps through an executor
harmonics    mesh-harmonic amplitudes of the DTE (seed 003 eq 10-11)
===========  =========================================================
"""
