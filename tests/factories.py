"""Tables that test files of several layers build: the shared factories (tests/README.md).

Importable by name from every test file (pyproject.toml's ``pythonpath`` puts tests/ and its folders
on the path): ``from factories import make_tables``.

* :func:`make_tables`: small rectangular-wave tables in the table format (gearfmu.tables), each tooth
  pair engaged for eps mesh periods with a half-sine meshing error -- the FMUs of the host tests are
  built on them;
* :func:`temp_tables`: the same with a temperature axis (:data:`AXIS`) whose three slices differ in
  stiffness and error.
"""
import numpy as np

from gearfmu.tables.mesh_tables import MeshTables, stack_temperatures

#: base radii (m) of the pinion and the gear of make_tables
RB1, RB2 = 0.05, 0.075
#: the temperature axis of temp_tables (degC)
AXIS = (10.0, 30.0, 70.0)


def make_tables(P=2, n_phi=64, z1=20, eps=1.5, k_pair=2e8, e_amp=2e-6, b=1e-5, torque=(100.0,)):
    """Small rectangular-wave tables: pair n engaged for phi - n*T in [0, eps*T)."""
    T = 2 * np.pi / z1
    phi = np.arange(n_phi) * P * T / n_phi
    nt = len(torque)
    k = np.zeros((nt, P, n_phi))
    e = np.zeros((nt, P, n_phi))
    for j in range(P):
        for n in range(-P, 2 * P):
            if n % P == j:
                on = (phi >= n * T) & (phi < n * T + eps * T)
                k[:, j, on] = k_pair
                e[:, j, on] = e_amp * np.sin(np.pi * (phi[on] - n * T) / (eps * T))
    return MeshTables(torque_Nm=np.array(torque, float), k_N_per_m=k, e_m=e,
                      backlash_half_m=np.full((P, n_phi), b), phi_period_rad=P * T, mesh_period_rad=T,
                      base_radius_pinion_m=RB1, base_radius_gear_m=RB2, inertia_pinion_kgm2=0.002,
                      inertia_gear_kgm2=0.006, teeth_pinion=z1, teeth_gear=30, contact_ratio=eps,
                      k_mean_N_per_m=k_pair * eps, provenance={"source": "tests/factories.py"})


def temp_tables():
    """P = 2, torque axis [50, 150] N.m, three temperature slices that differ in k and e."""
    slices = []
    for f, g in ((0.8, 1.3), (1.0, 1.0), (0.9, 0.7)):
        t = make_tables(torque=(50.0, 150.0))
        t.k_N_per_m[:] *= f
        t.k_N_per_m[1] *= 1.15
        t.e_m[:] *= g
        slices.append(t)
    return stack_temperatures(slices, AXIS, temperature_reference_C=30.0), slices
