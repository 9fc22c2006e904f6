"""The native gearbox solver against references no gearbox code produced.

* The linear limit: with constant mesh stiffness, no errors, no backlash and the contact_zone
  force law (F = k x + c v), the gearbox is a linear torsional system; its forced response from
  a static state under a torque step is the matrix exponential of the first-order system with
  M, K, C assembled here element by element (scipy.linalg.expm of the augmented matrix).
* One stage without shafts is the pair model: the gearbox solver on the single mesh reproduces
  gearfmu.dynamics.native.simulate (an independent implementation of the same equations in
  other state variables: x against the gear deviation u) on the hard cases of gearfmu.bench.
* Conservation: with balanced torques the angular momentum referred to the motor,
  sum_i I_i g_i omega_i, is constant (every internal torque cancels in it: g_a = g_b across a
  shaft, g_p Rb_p = g_q Rb_q across a mesh), and every Runge-Kutta step keeps a linear
  invariant of the equations to round-off.
"""
import numpy as np
import pytest
import scipy.linalg

from gearfmu.bench import hard_case
from gearfmu.dynamics.native import simulate as simulate_pair
from gearfmu.gearbox.model import Mesh, Shaft, build_gearbox
from gearfmu.gearbox.native import GearboxInputError, simulate
from gearfmu.tables.synthetic import rectangular_wave_tables

from support.gearbox_cases import (I_LOAD, I_MOTOR, K_IN, K_MID, K_OUT, S1, S2, c_mesh, hand_damping,
                                   hand_damping_of_mid, hand_matrices, linear_gearbox)


@pytest.mark.parametrize("integrator", ["rk4", "rk4_kink", "rk4_node"])
def test_linear_limit_forced_response_against_matrix_exponential(integrator):
    model = linear_gearbox()
    M, K = hand_matrices()
    C = hand_damping()
    order = [model.part_body[p] for p in ("motor", "s1.pinion", "s1.gear", "s2.pinion", "s2.gear", "load")]
    # start: the static state under 150 N*m at 300 rad/s; then a motor torque step to 250 N*m against 1000 N*m
    y0 = model.static_state(150.0, 300.0)
    u = np.concatenate([[0.0], y0[2::2]])[order]
    du = np.concatenate([[0.0], y0[3::2]])[order]
    g = np.array([1.0, 1.0, S1["rb1"] / S1["rb2"], S1["rb1"] / S1["rb2"],
                  S1["rb1"] / S1["rb2"] * S2["rb1"] / S2["rb2"], S1["rb1"] / S1["rb2"] * S2["rb1"] / S2["rb2"]])
    th0, w0 = g * y0[0] + u, g * y0[1] + du
    f = np.zeros(6); f[0] = 250.0; f[5] = -1000.0
    A = np.zeros((13, 13))
    Mi = np.linalg.inv(M)
    A[:6, 6:12] = np.eye(6)
    A[6:12, :6] = -Mi @ K
    A[6:12, 6:12] = -Mi @ C
    A[6:12, 12] = Mi @ f
    H, n = 1e-4, 200
    Z = np.array([scipy.linalg.expm(A * (i * H)) @ np.concatenate([th0, w0, [1.0]]) for i in range(n + 1)])
    x1 = S1["rb1"] * Z[:, 1] - S1["rb2"] * Z[:, 2]
    x2 = S2["rb1"] * Z[:, 3] - S2["rb2"] * Z[:, 4]
    r = simulate(model, stop_time_s=n * H, comm_step_s=H, motor_torque_Nm=250.0, load_torque_Nm=1000.0,
                 motor_speed_start_rad_s=300.0, initial_state=y0, integrator=integrator)
    for got, ref in ((r["s1.dte"], x1), (r["s2.dte"], x2), (r["load_speed"], Z[:, 11]),
                     (r["intermediate_shaft.torque"], K_MID * (Z[:, 2] - Z[:, 3]) + hand_damping_of_mid(Z)),
                     (r["s1.mesh_force"], S1["k"] * x1 + c_mesh(S1) * (S1["rb1"] * Z[:, 7] - S1["rb2"] * Z[:, 8]))):
        assert np.max(np.abs(got - ref)) <= 1e-6 * np.ptp(ref)


@pytest.mark.parametrize("case", ["single_sided_impacts", "double_sided_impacts", "high_contact_ratio",
                                  "torque_steps"])
@pytest.mark.parametrize("integrator", ["rk4", "rk4_kink", "rk4_node"])
def test_one_stage_is_the_pair_model(case, integrator):
    t, kw = hard_case(case)
    model = build_gearbox([Mesh("s", t, kw["damping_ratio"])], motor="s.pinion", load="s.gear")
    h = kw["comm_step_s"] / 32
    p = simulate_pair(t, **kw, max_step_s=h, integrator=integrator)
    g = simulate(model, stop_time_s=kw["stop_time_s"], comm_step_s=kw["comm_step_s"],
                 motor_torque_Nm=kw["pinion_torque_Nm"], motor_speed_start_rad_s=kw["pinion_speed_start_rad_s"],
                 motor_angle_start_rad=kw["pinion_angle_start_rad"], max_step_s=h, integrator=integrator)
    for name, ref in (("s.dte", p.dte), ("s.mesh_force", p.mesh_force), ("s.gear_speed", p.gear_speed),
                      ("s.pinion_speed", p.pinion_speed), ("s.pair_force[2]", p.pair_force[:, 1]),
                      ("s.mesh_stiffness", p.mesh_stiffness)):
        assert np.max(np.abs(g[name] - ref)) <= 1e-9 * np.ptp(ref), name
    assert g.info["events"] == p.info["events"]


def nonlinear_gearbox():
    """Two rectangular-wave stages with backlash and tent errors, elastic shafts."""
    err = lambda a: (lambda slot, u: a * (1.0 - np.abs(2.0 * u - 1.0)))
    t1 = rectangular_wave_tables(3e8, backlash_half_m=20e-6, pair_error_m=err(5e-6), teeth_pinion=23, teeth_gear=67,
                                 base_radius_pinion_m=0.027, base_radius_gear_m=0.0787, inertia_pinion_kgm2=2e-4,
                                 inertia_gear_kgm2=1.2e-2)
    t2 = rectangular_wave_tables(5e8, backlash_half_m=30e-6, pair_error_m=err(8e-6), teeth_pinion=19, teeth_gear=73,
                                 base_radius_pinion_m=0.0312, base_radius_gear_m=0.1199, inertia_pinion_kgm2=8e-4,
                                 inertia_gear_kgm2=8e-2)
    return build_gearbox([Mesh("s1", t1, 0.05), Mesh("s2", t2, 0.05)],
                         [Shaft("input_shaft", "motor", "s1.pinion", K_IN, 0.02),
                          Shaft("intermediate_shaft", "s1.gear", "s2.pinion", K_MID, 0.02),
                          Shaft("output_shaft", "s2.gear", "load", K_OUT, 0.02)], {"motor": I_MOTOR, "load": I_LOAD})


@pytest.mark.parametrize("integrator", ["rk4", "rk4_node"])
def test_angular_momentum_is_conserved_under_balanced_torques(integrator):
    model = nonlinear_gearbox()
    r = simulate(model, stop_time_s=0.02, comm_step_s=1e-4, motor_torque_Nm=60.0, motor_speed_start_rad_s=300.0,
                 integrator=integrator)
    L = sum(model.inertia_kgm2[b] * model.g[b] * r[f"{model.bodies[b][0]}_speed"] for b in range(model.n_bodies))
    assert np.ptp(r["s2.dte"]) > 1e-6   # the meshes do vibrate
    assert np.max(np.abs(L - L[0])) <= 1e-12 * abs(L[0])


def test_bad_arguments_name_the_field():
    model = linear_gearbox()
    kw = dict(stop_time_s=1e-3, comm_step_s=1e-4, motor_torque_Nm=10.0, motor_speed_start_rad_s=1.0)
    with pytest.raises(GearboxInputError, match="integrator: 'euler' unknown for gearboxes"):
        simulate(model, **kw, integrator="euler")
    with pytest.raises(GearboxInputError, match="stop_time_s"):
        simulate(model, **dict(kw, stop_time_s=1.5e-4))
    with pytest.raises(GearboxInputError, match="motor_torque_Nm: contains NaN"):
        simulate(model, **dict(kw, motor_torque_Nm=float("nan")))
    with pytest.raises(GearboxInputError, match="initial_state"):
        simulate(model, **kw, initial_state=[0.0, 1.0])
