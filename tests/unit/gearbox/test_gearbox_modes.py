"""Gearbox model and modes: the linear limit against references assembled here, not by the model.

References (none produced by gearfmu.gearbox):

* a single pair, free-free: one rigid mode and one mesh mode with the closed-form frequency
  f = sqrt(k/m_e)/(2 pi), m_e = I1 I2/(I1 Rb2^2 + I2 Rb1^2) (the two-inertia torsional pair);
* a two-stage chain motor - shaft - stage 1 - shaft - stage 2 - shaft - load with constant mesh
  stiffness: the mass and stiffness matrices written out element by element below from the
  inertias, base radii, mesh and shaft stiffnesses, solved with scipy.linalg.eigh; the strain
  energy of every element of every mode from the same hand-made shapes;
* shaft stiffness and inertia from dimensions: k = G pi (D^4 - d^4)/(32 L), G = E/(2(1 + nu)),
  I = rho pi (D^4 - d^4) L/32 (a uniform round shaft in torsion; a hollow cylinder's polar inertia).
"""
import math

import numpy as np
import pytest
import scipy.linalg

from gearfmu.gearbox.model import GearboxModelError, Mesh, Shaft, build_gearbox
from gearfmu.gearbox.modes import campbell, modes

from support.gearbox_cases import I_LOAD, I_MOTOR, K_IN, K_MID, K_OUT, S1, S2, const_tables, hand_matrices


def two_stage(mid_rigid=False, **shaft_kw):
    shafts = [Shaft("input_shaft", "motor", "s1.pinion", K_IN, **shaft_kw),
              Shaft("intermediate_shaft", "s2.pinion", "s1.gear", None if mid_rigid else K_MID, **shaft_kw),
              Shaft("output_shaft", "s2.gear", "load", K_OUT, **shaft_kw)]
    return build_gearbox([Mesh("s1", const_tables(**S1)), Mesh("s2", const_tables(**S2))], shafts,
                         {"motor": I_MOTOR, "load": I_LOAD})


def test_single_pair_closed_form():
    t = const_tables(**S1)
    model = build_gearbox([Mesh("s1", t)], motor="s1.pinion", load="s1.gear")
    res = modes(model, 100.0)
    me = S1["i1"] * S1["i2"] / (S1["i1"] * S1["rb2"] ** 2 + S1["i2"] * S1["rb1"] ** 2)
    f = math.sqrt(S1["k"] / me) / (2 * math.pi)
    assert res.modes[0].rigid and res.modes[0].frequency_Hz == 0.0
    assert abs(res.modes[1].frequency_Hz - f) <= 1e-10 * f
    assert res.modes[1].energy == pytest.approx({"s1": 1.0}, rel=1e-12)
    # the rigid mode's shape is the kinematic ratio (pinion 1, gear Rb1/Rb2)
    assert res.modes[0].shape == pytest.approx([1.0, S1["rb1"] / S1["rb2"]], rel=1e-9)


def test_two_stage_frequencies_and_energies_against_hand_assembled_eigenproblem():
    model = two_stage()
    res = modes(model, 150.0)
    M, K = hand_matrices()
    w2, phi = scipy.linalg.eigh(K, M)
    f_ref = np.sqrt(np.maximum(w2, 0.0)) / (2 * math.pi)
    f = np.array([m.frequency_Hz for m in res.modes])
    assert f[0] == 0.0 and res.modes[0].rigid
    np.testing.assert_allclose(f[1:], f_ref[1:], rtol=1e-9)
    # strain energy per element of every mode, from the hand shapes
    order = [model.part_body[p] for p in ("motor", "s1.pinion", "s1.gear", "s2.pinion", "s2.gear", "load")]
    for i in range(1, 6):
        v = phi[:, i]
        e = {"input_shaft": K_IN * (v[0] - v[1]) ** 2, "s1": S1["k"] * (S1["rb1"] * v[1] - S1["rb2"] * v[2]) ** 2,
             "intermediate_shaft": K_MID * (v[2] - v[3]) ** 2,
             "s2": S2["k"] * (S2["rb1"] * v[3] - S2["rb2"] * v[4]) ** 2, "output_shaft": K_OUT * (v[4] - v[5]) ** 2}
        tot = sum(e.values())
        got = res.modes[i].energy
        for name, val in e.items():
            assert abs(got[name] - val / tot) <= 1e-8, (i, name)
        # the same shape up to scale (model bodies in its own order)
        s = res.modes[i].shape[order]
        np.testing.assert_allclose(s / s[np.argmax(abs(s))], v / v[np.argmax(abs(v))], atol=1e-8)


def test_rigid_intermediate_shaft_merges_the_bodies():
    model = two_stage(mid_rigid=True)
    assert model.n_bodies == 5
    merged = model.part_body["s1.gear"]
    assert model.part_body["s2.pinion"] == merged
    assert model.inertia_kgm2[merged] == pytest.approx(S1["i2"] + S2["i1"], rel=1e-15)
    # hand: the chain [motor, p1, g1+p2, g2, load]
    M, K6 = hand_matrices()
    T = np.zeros((6, 5))
    T[0, 0] = T[1, 1] = T[2, 2] = T[3, 2] = T[4, 3] = T[5, 4] = 1.0   # theta6 = T theta5
    K6[2, 2] -= K_MID; K6[3, 3] -= K_MID; K6[2, 3] += K_MID; K6[3, 2] += K_MID   # no elastic shaft there
    w2 = scipy.linalg.eigh(T.T @ K6 @ T, T.T @ M @ T, eigvals_only=True)
    f = np.array([m.frequency_Hz for m in modes(model, 150.0).modes])
    np.testing.assert_allclose(f[1:], np.sqrt(w2[1:]) / (2 * math.pi), rtol=1e-9)


def test_kinematic_ratios_and_static_torques():
    model = two_stage()
    g_load = (S1["rb1"] / S1["rb2"]) * (S2["rb1"] / S2["rb2"])
    assert model.load_ratio == pytest.approx(g_load, rel=1e-15)
    assert model.balancing_load_torque_Nm(150.0) == pytest.approx(150.0 / g_load, rel=1e-15)
    tq = model.stage_torques_Nm(150.0)
    assert tq == pytest.approx([150.0, 150.0 * S1["rb2"] / S1["rb1"]], rel=1e-15)
    # the static state: every shaft twisted T/k, every mesh x = F/k (constant stiffness, no error)
    y = model.static_state(150.0, 300.0)
    u = np.zeros(model.n_bodies)
    u[1:] = y[2::2]
    b = model.part_body
    assert u[b["motor"]] - u[b["s1.pinion"]] == pytest.approx(150.0 / K_IN, rel=1e-12)
    x1 = S1["rb1"] * u[b["s1.pinion"]] - S1["rb2"] * u[b["s1.gear"]]
    assert x1 == pytest.approx(150.0 / S1["rb1"] / S1["k"], rel=1e-9)
    assert u[b["s1.gear"]] - u[b["s2.pinion"]] == pytest.approx(tq[1] / K_MID, rel=1e-12)
    assert np.all(y[3::2] == 0.0) and y[1] == 300.0


def test_shaft_damping_ratio_uses_the_reduced_inertia_of_its_end_bodies():
    model = two_stage(damping_ratio=0.03)
    s = [sh.name for sh in model.shafts].index("input_shaft")
    a, b = model.shaft_bodies[s]
    ia, ib = model.inertia_kgm2[a], model.inertia_kgm2[b]
    assert {ia, ib} == {I_MOTOR, S1["i1"]}
    assert model.shaft_c_Nms_per_rad[s] == pytest.approx(2 * 0.03 * math.sqrt(K_IN * ia * ib / (ia + ib)), rel=1e-14)


def test_damped_modes_and_campbell():
    model = two_stage(damping_ratio=0.02)
    res = modes(model, 150.0)
    M, K, C = res.M, res.K, res.C
    for m in res.modes[1:]:
        # the damped eigenvalue: det(lambda^2 M + lambda C + K) = 0 at lambda = -zeta w + i w_d
        w = 2 * math.pi * m.damped_frequency_Hz / math.sqrt(1 - m.damping_ratio ** 2)
        lam = complex(-m.damping_ratio * w, 2 * math.pi * m.damped_frequency_Hz)
        smin = np.linalg.svd(lam * lam * M + lam * C + K, compute_uv=False)[-1]
        smax = np.linalg.svd(lam * lam * M + lam * C + K, compute_uv=False)[0]
        assert smin <= 1e-9 * smax
        assert 0.0 < m.damping_ratio < 0.2
    cb = campbell(model, res, 4000.0, operating_speed_rpm=3000.0)
    # every interference lies on its order line and its mode
    orders = {o["name"]: o["hz_per_rpm"] for o in cb["orders"]}
    assert orders["s1 mesh 1x"] == pytest.approx(23 / 60.0)
    assert orders["s2 mesh 2x"] == pytest.approx(2 * 19 * S1["rb1"] / S1["rb2"] / 60.0)
    assert cb["interferences"]
    for p in cb["interferences"]:
        assert p["speed_rpm"] * orders[p["order"]] == pytest.approx(p["frequency_Hz"], rel=1e-12)
        assert 0 < p["speed_rpm"] <= 4000.0


def test_bad_models_name_the_field():
    t = const_tables(**S1)
    with pytest.raises(GearboxModelError, match=r"shafts\[0\] \(a\): 'nowhere' is not a part"):
        build_gearbox([Mesh("s1", t)], [Shaft("a", "motor", "nowhere", 1e4)], {"motor": 1.0, "load": 1.0})
    with pytest.raises(GearboxModelError, match="not connected"):
        build_gearbox([Mesh("s1", t)], [Shaft("a", "motor", "s1.pinion", 1e4)], {"motor": 1.0, "load": 1.0})
    with pytest.raises(GearboxModelError, match="motor side of the pinion"):
        build_gearbox([Mesh("s1", t)], [Shaft("a", "motor", "s1.gear", 1e4), Shaft("b", "s1.pinion", "load", 1e4)],
                      {"motor": 1.0, "load": 1.0})
    with pytest.raises(GearboxModelError, match="closes a loop"):
        build_gearbox([Mesh("s1", t)], [Shaft("a", "motor", "s1.pinion", 1e4), Shaft("b", "s1.gear", "load", 1e4),
                                        Shaft("c", "motor", "load", 1e4)], {"motor": 1.0, "load": 1.0})
