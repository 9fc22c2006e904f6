"""The two cases the standalone FMU's host tests build (tests/fmu_hosts/test_standalone.py,
test_platforms.py, test_fmi3.py): the default scene, and an impact case with contact loss and
back-flank impacts; and the deviation measure they compare outputs by."""
import numpy as np

from gearfmu.pipeline import compute_tables, gear_torque_for, load, max_step_for
from gearfmu.tables.synthetic import rectangular_wave_tables


def impact_tables():
    """Rectangular-wave TVMS (seed 003 Fig. 2 form), 20 um half backlash,
    10 um sinusoidal pair errors: at 10 N.m the pairs separate and hit the back flank."""
    return rectangular_wave_tables(1e8, contact_ratio=1.6, backlash_half_m=20e-6,
                                   pair_error_m=lambda j, u: 10e-6 * np.sin(np.pi * u) * (1 + 0.5 * j))


def cases():
    """{"default": ..., "impacts": ...}: per case the tables, communication step H (s), number of
    steps n, internal step bound hmax (s), torques T1, T2 (N.m), start speed w0 (rad/s), damping
    ratio zeta and damping model."""
    scene = load(None)
    t_def = compute_tables(scene)
    T1 = scene.operating.torque_Nm
    default = dict(tables=t_def, H=scene.fmu.output_interval_s, n=500, hmax=max_step_for(scene, t_def),
                   T1=T1, T2=gear_torque_for(t_def, T1), w0=scene.operating.speed_rad_s,
                   zeta=scene.fmu.damping_ratio, model=scene.solver.damping_model)
    t_imp = impact_tables()
    wn = np.sqrt(t_imp.k_mean_N_per_m / t_imp.equivalent_mass_kg)
    w0 = wn * t_imp.mesh_period_rad / (2 * np.pi)  # mesh frequency = natural frequency
    impacts = dict(tables=t_imp, H=1e-4, n=200, hmax=4.5e-6, T1=10.0, T2=gear_torque_for(t_imp, 10.0), w0=w0,
                   zeta=0.02, model="elastobacklash")
    return {"default": default, "impacts": impacts}


def max_rel(ref, other, names):
    """{name: max |ref - other| / range(ref)} per output (the range, or the largest magnitude of a
    constant signal)."""
    worst = {}
    for n in names:
        a, b = np.asarray(ref[n]), np.asarray(other[n])
        assert a.shape == b.shape, n
        rng = np.ptp(a) if np.ptp(a) > 0 else max(np.max(np.abs(a)), 1e-300)
        worst[n] = float(np.max(np.abs(a - b)) / rng)
    return worst
