"""Fill gearfmu's compile caches once, before the test workers start (tests/conftest.py).

On a fresh clone (CI) numba's disk cache (``cache=True``: the native pair, gearbox and planetary
solvers, one driver per integrator; the EHL film kernels) and the object cache of the cross-compiled
C runtime (gearfmu.fmu.crossbuild: five platforms, FMI 2 and 3, the pair, gearbox and planetary units) are
empty.  Without this step every process that meets a cold cache compiles on its own: both test
workers and the command-line, pool and fresh-process runs the tests start, several of them the same
code at the same time.  Each family below runs a tiny problem through the code the tests use, in
its own process, the families side by side; warm caches make each a load of a few seconds.

    PYTHONPATH=.:tests python tests/support/warm_caches.py FAMILY      # native, films or objects
"""
import sys
import tempfile
from pathlib import Path

FAMILIES = ("native", "films", "objects")


def _native():
    import numpy as np

    from gearfmu.bench import planetary_case
    from gearfmu.common.vocabulary import GEARBOX_INTEGRATORS, INTEGRATORS
    from gearfmu.dynamics.native import simulate, simulate_sdof
    from gearfmu.dynamics.subcell import static_te_m, table_values
    from gearfmu.gearbox.cases import gearbox_case
    from gearfmu.gearbox.native import simulate as simulate_gearbox
    from gearfmu.planetary.native import simulate as simulate_planetary
    from gearfmu.tables.synthetic import rectangular_wave_tables
    from support.subcell_tables import dyn_tables

    tb = rectangular_wave_tables(2e8, contact_ratio=1.6, backlash_half_m=20e-6, points_per_mesh=16,
                                 pair_error_m=lambda j, u: 4e-6 * (1 + j) * np.sin(np.pi * u))
    for integrator in INTEGRATORS:
        for model in ("elastobacklash", "contact_zone"):
            simulate(tb, stop_time_s=1e-4, comm_step_s=1e-5, pinion_torque_Nm=5.0, pinion_speed_start_rad_s=200.0,
                     damping_ratio=0.03, damping_model=model, integrator=integrator)
        simulate_sdof(tb, omega1_rad_s=200.0, stop_time_s=1e-4, comm_step_s=1e-5, pinion_torque_Nm=5.0,
                      damping_ratio=0.03, integrator=integrator)
    # tables with contact-zone edges between the nodes: the sub-cell lookup and its equilibrium
    zoned = dyn_tables(False)
    static_te_m(zoned, 5.0, np.linspace(0.0, zoned.mesh_period_rad, 5))
    table_values(zoned, np.linspace(0.0, zoned.mesh_period_rad, 5), 5.0)
    simulate(zoned, stop_time_s=1e-4, comm_step_s=1e-5, pinion_torque_Nm=5.0, pinion_speed_start_rad_s=200.0,
             damping_ratio=0.03)
    model, kw = gearbox_case("contact_loss", mesh_periods=2)
    for integrator in GEARBOX_INTEGRATORS:
        simulate_gearbox(model, **dict(kw, integrator=integrator))
    model, kw = planetary_case("contact_loss", mesh_periods=2)
    for integrator in GEARBOX_INTEGRATORS:
        simulate_planetary(model, **dict(kw, integrator=integrator))


def _films():
    import numpy as np

    from gearfmu.ehl import solve_line_contact
    from gearfmu.ehl.deformation import DeformationOperator
    from gearfmu.ehl.transient import HarmonicWaviness, solve_line_contact_transient

    s = solve_line_contact(M=20.0, L=10.0, n_nodes=257)
    solve_line_contact(M=20.0, L=10.0, n_nodes=257, viscosity="barus", compressible=False)
    wav = HarmonicWaviness(0.1 * s.h_central_m, 0.5 * s.b_m)
    solve_line_contact_transient(M=20.0, L=10.0, n_nodes=257, roughness=wav, dT=0.05, n_steps=8)
    DeformationOperator(257, 0.01)(np.ones(257))


def _objects():
    from gearfmu.bench import planetary_case
    from gearfmu.fmu.gearbox_build import build_gearbox_fmu, gearbox_settings
    from gearfmu.fmu.planetary_build import build_planetary_fmu, planetary_settings
    from gearfmu.fmu.standalone_build import build_standalone_fmu
    from gearfmu.gearbox.cases import gearbox_case
    from gearfmu.tables.synthetic import rectangular_wave_tables

    tb = rectangular_wave_tables(1e8, contact_ratio=1.6, points_per_mesh=16)
    model, _ = gearbox_case("contact_loss", mesh_periods=2)
    planetary, _ = planetary_case("position_error", mesh_periods=2)
    with tempfile.TemporaryDirectory() as d:
        for v in (2, 3):
            build_standalone_fmu(tb, Path(d) / f"pair{v}.fmu", max_step_s=1e-5, fmi_version=v, validation=False)
            build_gearbox_fmu(model, Path(d) / f"gearbox{v}.fmu", fmi_version=v, validation=False,
                              settings=gearbox_settings(model, max_step_s=1e-5))
            build_planetary_fmu(planetary, Path(d) / f"planetary{v}.fmu", fmi_version=v, validation=False,
                                settings=planetary_settings(planetary, max_step_s=1e-5))


def main(family: str) -> int:
    {"native": _native, "films": _films, "objects": _objects}[family]()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
