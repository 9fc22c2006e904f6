"""Quasi-static invariants and free vibration of the native gearbox solver.

References (none produced by gearfmu.gearbox):

* Free vibration: an undamped linear gearbox started in one of its modes (from the eigenproblem
  of the hand-assembled M, K of tests/unit/gearbox/test_gearbox_modes.py) vibrates at that natural frequency,
  x_m(t) = eps (r_m . phi) cos(omega t) for every mesh (RK4 at 256 steps per period of the mode:
  its phase error, (omega h)^5/120 per step, stays far below 1e-6 over three periods).
* Statics: with time-invariant meshes (constant stiffness and meshing error, with backlash) a
  damped gearbox under balanced torques settles where every element carries its static torque:
  each mesh force T_p/Rb_p, each shaft torque T_motor/g, each DTE the single pair's static
  deflection F/k + e + b, and the load turns at the product of the tooth ratios times the motor
  speed.  Exact: asserted to 1e-9.
* Periodic steady state with time-varying meshes (smooth stiffness and error tables, two stages
  whose table periods are commensurate): the referred angular momentum fixes the mean speed at
  the start speed, so the motion is periodic in time with the common period of the tables.
  Over one period the load turns exactly the product of the tooth ratios times the motor angle
  (exact: 1e-9).  The mean mesh force over the period is exactly the transmitted torque over the
  base radius; the mean of N samples of it is a quadrature of a force with kinks (the tables are
  piecewise linear), asserted to 1e-5 at 256 samples.  A stage's mean DTE equals its single-pair
  model's at the same torque only where the mesh is time-invariant (above): with a time-varying
  mesh the stiffness correlates with the force and with the speed fluctuation, and both depend on
  the inertias and shafts the stage is coupled to; at 20 rad/s (mesh frequency well below every
  coupled mode) the two differ by about 1.5e-5 of the mean, asserted to 5e-5.
"""
import math

import numpy as np
import pytest
import scipy.linalg

from gearfmu.dynamics.native import simulate as simulate_pair
from gearfmu.gearbox.model import Mesh, Shaft, build_gearbox
from gearfmu.gearbox.native import simulate
from gearfmu.tables.synthetic import tables_from_arrays

from support.gearbox_cases import I_LOAD, I_MOTOR, K_IN, K_MID, K_OUT, S1, S2, const_tables, hand_matrices


def test_free_vibration_in_each_mode_at_its_natural_frequency():
    meshes = [Mesh("s1", const_tables(**S1), 0.0, "contact_zone"), Mesh("s2", const_tables(**S2), 0.0, "contact_zone")]
    model = build_gearbox(meshes, [Shaft("input_shaft", "motor", "s1.pinion", K_IN),
                                   Shaft("intermediate_shaft", "s1.gear", "s2.pinion", K_MID),
                                   Shaft("output_shaft", "s2.gear", "load", K_OUT)], {"motor": I_MOTOR, "load": I_LOAD})
    M, K = hand_matrices()
    w2, phi = scipy.linalg.eigh(K, M)
    order = [model.part_body[p] for p in ("motor", "s1.pinion", "s1.gear", "s2.pinion", "s2.gear", "load")]
    g = model.g[order]
    r1 = np.array([0, S1["rb1"], -S1["rb2"], 0, 0, 0])
    r2 = np.array([0, 0, 0, S2["rb1"], -S2["rb2"], 0])
    for k in range(1, 6):
        w = math.sqrt(w2[k])
        v = phi[:, k] * (1e-4 / np.max(np.abs(phi[:, k])))     # angles of the hand chain, rad
        y0 = np.zeros(12)
        y0[0], y0[1] = v[0], 50.0
        u = v - g * v[0]
        for i, b in enumerate(order):
            if b:
                y0[2 * b] = u[i]
        T = 2 * math.pi / w
        n = 200
        r = simulate(model, stop_time_s=3 * T, comm_step_s=3 * T / n, motor_torque_Nm=0.0, load_torque_Nm=0.0,
                     motor_speed_start_rad_s=50.0, initial_state=y0, integrator="rk4", max_step_s=T / 256)
        c = np.cos(w * r.time_s)
        for name, rm in (("s1.dte", r1), ("s2.dte", r2)):
            ref = (rm @ v) * c
            assert np.max(np.abs(r[name] - ref)) <= 1e-6 * max(np.ptp(ref), 1e-3 * (abs(r1 @ v) + abs(r2 @ v))), (k, name)


def _time_invariant_gearbox():
    def tab(k, e, b, s):
        return tables_from_arrays(k_N_per_m=np.full((1, 8), k), e_m=np.full((1, 8), e), backlash_half_m=b,
                                  base_radius_pinion_m=s["rb1"], base_radius_gear_m=s["rb2"],
                                  inertia_pinion_kgm2=s["i1"], inertia_gear_kgm2=s["i2"], teeth_pinion=s["z1"],
                                  teeth_gear=s["z2"])
    t1, t2 = tab(S1["k"], 3e-6, 10e-6, S1), tab(S2["k"], -2e-6, 15e-6, S2)
    model = build_gearbox([Mesh("s1", t1, 0.1), Mesh("s2", t2, 0.1)],
                          [Shaft("input_shaft", "motor", "s1.pinion", K_IN, 0.3),
                           Shaft("intermediate_shaft", "s1.gear", "s2.pinion", K_MID, 0.3),
                           Shaft("output_shaft", "s2.gear", "load", K_OUT, 0.3)], {"motor": I_MOTOR, "load": 0.1})
    return model, t1, t2


def test_time_invariant_meshes_settle_at_the_static_torques_exactly():
    model, t1, t2 = _time_invariant_gearbox()
    T = 150.0
    y0 = model.static_state(60.0, 200.0)     # the static state of another torque: it must settle
    r = simulate(model, stop_time_s=0.6, comm_step_s=1e-3, motor_torque_Nm=T, motor_speed_start_rad_s=200.0,
                 initial_state=y0)
    i2 = S1["rb2"] / S1["rb1"]
    F1, F2 = T / S1["rb1"], T * i2 / S2["rb1"]
    assert np.ptp(r["s1.mesh_force"]) > 0.5 * F1   # it did move
    last = lambda name: r[name][-1]
    assert last("s1.mesh_force") == pytest.approx(F1, rel=1e-9)
    assert last("s2.mesh_force") == pytest.approx(F2, rel=1e-9)
    assert last("input_shaft.torque") == pytest.approx(T, rel=1e-9)
    assert last("intermediate_shaft.torque") == pytest.approx(T * i2, rel=1e-9)
    assert last("output_shaft.torque") == pytest.approx(T * i2 * S2["rb2"] / S2["rb1"], rel=1e-9)
    assert last("s1.dte") == pytest.approx(F1 / S1["k"] + 3e-6 + 10e-6, rel=1e-9)
    assert last("s2.dte") == pytest.approx(F2 / S2["k"] - 2e-6 + 15e-6, rel=1e-9)
    # the single pair's own static DTE at the stage torque (its equilibrium under T_p)
    p = simulate_pair(t2, stop_time_s=1e-4, comm_step_s=1e-4, pinion_torque_Nm=T * i2, pinion_speed_start_rad_s=10.0,
                      damping_ratio=0.1)
    assert last("s2.dte") == pytest.approx(p.dte[0], rel=1e-9)
    assert last("load_speed") / last("motor_speed") == pytest.approx((23 / 67) * (19 / 73), rel=1e-9)


def _smooth_tables(k0, e0, z1, z2, rb, i1, i2, n=64):
    ph = np.arange(n) / n * 2 * math.pi
    return tables_from_arrays(k_N_per_m=(k0 * (1 + 0.2 * np.cos(ph)))[None], e_m=(e0 * np.sin(ph))[None],
                              backlash_half_m=10e-6, teeth_pinion=z1, teeth_gear=z2, base_radius_pinion_m=rb,
                              base_radius_gear_m=rb * z2 / z1, inertia_pinion_kgm2=i1, inertia_gear_kgm2=i2)


def test_periodic_steady_state_invariants():
    # stage 1 20/40, stage 2 20/60: table periods 2 pi/20 of each pinion, common period 4 pi/20 of the motor
    t1 = _smooth_tables(5e8, 3e-6, 20, 40, 0.03, 3e-4, 5e-3)
    t2 = _smooth_tables(8e8, 2e-6, 20, 60, 0.035, 6e-4, 4e-2)
    model = build_gearbox([Mesh("s1", t1, 0.1), Mesh("s2", t2, 0.1)],
                          [Shaft("a", "motor", "s1.pinion", 5e4, 0.2), Shaft("b", "s1.gear", "s2.pinion", 1e5, 0.2),
                           Shaft("c", "s2.gear", "load", 3e5, 0.2)], {"motor": 0.01, "load": 0.2})
    T, w0, N = 100.0, 20.0, 256
    period = 4 * math.pi / 20 / w0
    r = simulate(model, stop_time_s=12 * period, comm_step_s=period / N, motor_torque_Nm=T, motor_speed_start_rad_s=w0)
    i1 = len(r.time_s) - 1
    i0 = i1 - N
    d_motor = r["motor_angle"][i1] - r["motor_angle"][i0]
    d_load = r["load_angle"][i1] - r["load_angle"][i0]
    assert d_motor == pytest.approx(4 * math.pi / 20, rel=1e-9)
    assert d_load / d_motor == pytest.approx((20 / 40) * (20 / 60), rel=1e-9)
    assert np.mean(r["s1.mesh_force"][i0:i1]) == pytest.approx(T / 0.03, rel=1e-5)
    assert np.mean(r["s2.mesh_force"][i0:i1]) == pytest.approx(2 * T / 0.035, rel=1e-5)
    y0 = model.static_state(T, w0)
    for tab, name, part, tp, per in ((t1, "s1", "s1.pinion", T, 2), (t2, "s2", "s2.pinion", 2 * T, 1)):
        b = model.part_body[part]
        wp = w0 * model.g[b]
        pp = 2 * math.pi / 20 / wp
        n = N // per
        p = simulate_pair(tab, stop_time_s=math.ceil(12 * period / pp) * pp, comm_step_s=pp / n, pinion_torque_Nm=tp,
                          pinion_speed_start_rad_s=wp, damping_ratio=0.1,
                          pinion_angle_start_rad=model.g[b] * y0[0] + y0[2 * b])
        x_pair = np.mean(p.dte[-n - 1:-1])
        assert np.mean(r[f"{name}.dte"][i0:i1]) == pytest.approx(x_pair, rel=5e-5)
