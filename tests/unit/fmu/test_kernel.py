"""The C kernel (gearfmu/fmu/kernel/gearkernel.c) called directly through ctypes.

References (none produced by gearfmu code):
* the linear oscillator m_e x'' + c x' + k x = m_e a0 in closed form
  (any vibration textbook, e.g. Rao, Mechanical Vibrations, sec. 2.6: damped
  free vibration x(t) = x_s + e^{-zeta w t}[A cos w_d t + B sin w_d t]),
* the linear invariant of the two-inertia model (torque balance):
  d/dt (I1 w1/Rb1 + I2 w2/Rb2) = T1/Rb1 - T2/Rb2, preserved exactly by RK4,
* hand-solved static balances of parallel springs with gaps,
* numpy.interp (independent periodic linear interpolation).
"""
import math

import numpy as np
import pytest

from gearfmu.fmu.pythonfmu_build import compile_kernel
from gearfmu.fmu.runtime.kernel_api import load_kernel

RB1, RB2, I1, I2 = 0.05, 0.075, 0.002, 0.006
ME = I1 * I2 / (I1 * RB2 ** 2 + I2 * RB1 ** 2)  # seed 003: equivalent mass
PHI = 2 * 2 * math.pi / 20  # two mesh periods of a 20-tooth pinion


@pytest.fixture(scope="module")
def lib(tmp_path_factory):
    return load_kernel(compile_kernel(tmp_path_factory.mktemp("kernel")))


class Kernel:
    """Own the model/state buffers and the tables the kernel borrows."""

    def __init__(self, L, k, e, b, torque=(100.0,), k_mean=None, zeta=0.0, model=0):
        self.L = L
        self.k = np.ascontiguousarray(k, dtype=float)
        self.e = np.ascontiguousarray(e, dtype=float)
        self.b = np.ascontiguousarray(b, dtype=float)
        self.tq = np.ascontiguousarray(torque, dtype=float)
        nt, P, n = self.k.shape
        self.P = P
        self.m = np.zeros(L.gk_sizeof_model() // 8 + 2)
        self.s = np.zeros(4)
        self.out = np.zeros(L.gk_n_outputs(P))
        st = L.gk_init(self.m.ctypes.data, P, n, nt, self.tq.ctypes.data, self.k.ctypes.data,
                       self.e.ctypes.data, self.b.ctypes.data, PHI, RB1, RB2, I1, I2,
                       k_mean if k_mean is not None else float(self.k.max()))
        assert st == 0
        assert L.gk_set_damping(self.m.ctypes.data, zeta, model) == 0

    def initialize(self, theta0, omega0, T1):
        return self.L.gk_initialize(self.m.ctypes.data, self.s.ctypes.data, theta0, omega0, T1)

    def step(self, T1, T2, H, hmax):
        return self.L.gk_do_step(self.m.ctypes.data, self.s.ctypes.data, T1, T2, H, hmax, self.out.ctypes.data)

    def outputs(self, T1):
        assert self.L.gk_outputs(self.m.ctypes.data, self.s.ctypes.data, T1, self.out.ctypes.data) == 0
        return self.out.copy()


def const_tables(kval, P=1, n=16, b=0.0):
    return np.full((1, P, n), kval), np.zeros((1, P, n)), np.full((P, n), b)


def oscillator(x0, xs, zeta, wn, t):
    """x(t) of m x'' + c x' + k x = k xs from rest at x0 (closed form)."""
    wd = wn * math.sqrt(1 - zeta ** 2)
    a = x0 - xs
    env = np.exp(-zeta * wn * t)
    x = xs + a * env * (np.cos(wd * t) + zeta * wn / wd * np.sin(wd * t))
    v = -a * env * (wn ** 2 / wd) * np.sin(wd * t)
    return x, v


@pytest.mark.parametrize("zeta,model", [(0.0, 0), (0.05, 1), (0.05, 0)])
def test_linear_oscillator_closed_form(lib, zeta, model):
    """Constant stiffness, no errors, no backlash: x obeys the linear oscillator.
    With zeta = 0.05 and a 20 % load step the elastobacklash limits never act
    (damping force < 2 % of the spring force), so both damping models are linear."""
    kv = 1e8
    K = Kernel(lib, *const_tables(kv), k_mean=kv, zeta=zeta, model=model)
    T1, T2 = 100.0, 0.8 * 100.0 * RB2 / RB1
    assert K.initialize(0.0, 100.0, T1) == 0
    x0 = K.s[2]
    assert x0 == pytest.approx(T1 / RB1 / kv, rel=1e-12)  # static balance F_m = k x
    a0 = RB1 * T1 / I1 + RB2 * T2 / I2
    xs = a0 * ME / kv
    wn = math.sqrt(kv / ME)
    H, hmax, nsteps = 1e-5, 1e-6, 200
    xs_num, vs_num = [], []
    L0 = I1 * K.s[1] / RB1 + I2 * (K.s[1] * RB1 - K.s[3]) / RB2 / RB2
    for _ in range(nsteps):
        assert K.step(T1, T2, H, hmax) == 0
        xs_num.append(K.s[2])
        vs_num.append(K.s[3])
    t = H * np.arange(1, nsteps + 1)
    x_ref, v_ref = oscillator(x0, xs, zeta, wn, t)
    amp = abs(xs - x0)
    assert np.max(np.abs(np.array(xs_num) - x_ref)) < 1e-6 * amp
    assert np.max(np.abs(np.array(vs_num) - v_ref)) < 1e-6 * amp * wn
    # torque-balance invariant, exact for RK4 up to round-off
    Lend = I1 * K.out[1] / RB1 + I2 * K.out[3] / RB2
    assert Lend == pytest.approx(L0 + (T1 / RB1 - T2 / RB2) * t[-1], rel=1e-12)
    # outputs: mesh force = k x + c v (linear case), gear kinematics from x
    c = 2 * zeta * math.sqrt(kv * ME)
    assert K.out[5] == pytest.approx(kv * K.s[2] + c * K.s[3], rel=1e-12)
    assert K.out[2] == pytest.approx((K.s[0] * RB1 - K.s[2]) / RB2, rel=1e-14)
    assert K.out[6] == kv
    assert K.out[7 + 1] == pytest.approx(1.0)  # single slot carries everything


def test_equilibrium_bisection_hand_calc(lib):
    """Two slots, k1 = 1e8, k2 = 2e8, errors 0 and delta, half backlash b.
    Hand calc: 0 < F < k1*delta -> x = b + F/k1; F > k1*delta -> x = b + (F + k2*delta)/(k1+k2);
    -k2*delta < F < 0 -> only slot 2's back flank touches: x = delta - b + F/k2."""
    n = 8
    k = np.zeros((1, 2, n))
    k[0, 0], k[0, 1] = 1e8, 2e8
    e = np.zeros((1, 2, n))
    delta, b = 5e-6, 2e-6
    e[0, 1] = delta
    K = Kernel(lib, k, e, np.full((2, n), b), k_mean=3e8)
    for T1 in (10.0, 100.0, -20.0):
        F = T1 / RB1
        assert K.initialize(0.3, 50.0, T1) == 0
        if T1 < 0:
            want = delta - b + F / 2e8
        elif F < 1e8 * delta:
            want = b + F / 1e8
        else:
            want = b + (F + 2e8 * delta) / 3e8
        assert K.s[2] == pytest.approx(want, rel=1e-12, abs=1e-20)
        assert (K.s[0], K.s[1], K.s[3]) == (0.3, 50.0, 0.0)
        out = K.outputs(T1)
        assert out[5] == pytest.approx(F, rel=1e-9)  # static force balance
        assert out[7 + 2] + out[7 + 3] == pytest.approx(1.0)


def test_table_lookup_against_numpy_interp(lib):
    """k(phi) and the torque axis: compare mesh_stiffness with numpy.interp
    (periodic in phi, clamped linear in torque)."""
    n = 24
    rng = np.random.default_rng(1)
    rows = rng.uniform(1e8, 3e8, size=(2, 1, n))
    torque = np.array([50.0, 250.0])
    K = Kernel(lib, rows, np.zeros((2, 1, n)), np.zeros((1, n)), torque=torque, k_mean=2e8)
    grid = np.arange(n) * PHI / n
    for theta in (-1.234, 0.0, 0.07, 0.5 * PHI, 3.0 * PHI + 0.011, PHI - 1e-13, -1e-300, -PHI,
                  -3.0 * PHI - 0.011):
        for T1 in (0.0, 50.0, 120.0, 250.0, 400.0):
            K.s[:] = (theta, 0.0, 1e-3, 0.0)  # deep in contact
            got = K.outputs(T1)[6]
            ka = np.interp(theta % PHI, grid, rows[0, 0], period=PHI)
            kb = np.interp(theta % PHI, grid, rows[1, 0], period=PHI)
            w = np.clip((T1 - 50.0) / 200.0, 0.0, 1.0)
            assert got == pytest.approx(ka + w * (kb - ka), rel=1e-12)


def test_separation_is_free_flight(lib):
    """Inside the backlash dead zone with no torque the pair is free: x = x0 + v0 t,
    theta1 = theta0 + w0 t exactly (kinematics)."""
    K = Kernel(lib, *const_tables(1e8, b=1e-3), zeta=0.05, model=0)
    K.s[:] = (0.1, 20.0, 0.0, 1e-3)
    for _ in range(10):
        assert K.step(0.0, 0.0, 0.05, 0.01) == 0
    assert K.s[2] == pytest.approx(5e-4, rel=1e-12)
    assert K.s[0] == pytest.approx(0.1 + 20.0 * 0.5, rel=1e-12)
    assert K.out[5] == 0.0 and K.out[6] == 0.0


def test_invalid_inputs_return_codes_and_keep_state(lib):
    K = Kernel(lib, *const_tables(1e8))
    assert K.initialize(0.0, 10.0, 100.0) == 0
    before = K.s.copy()
    assert K.step(float("nan"), 0.0, 1e-4, 1e-5) == 2
    assert K.step(float("inf"), 0.0, 1e-4, 1e-5) == 2
    assert K.step(100.0, float("-inf"), 1e-4, 1e-5) == 2
    assert K.step(100.0, 150.0, 0.0, 1e-5) == 3
    assert K.step(100.0, 150.0, -1e-4, 1e-5) == 3
    assert K.step(100.0, 150.0, 1e-4, float("nan")) == 3
    assert K.step(100.0, 150.0, 1.0, 1e-12) == 3  # 1e12 substeps refused, no hang
    assert np.array_equal(K.s, before)
    assert K.initialize(0.0, 10.0, float("nan")) == 2
    assert lib.gk_set_damping(K.m.ctypes.data, -0.1, 0) == 6
    assert lib.gk_set_damping(K.m.ctypes.data, 0.1, 7) == 6
    # no slot in contact -> no equilibrium
    Z = Kernel(lib, np.zeros((1, 1, 8)), np.zeros((1, 1, 8)), np.zeros((1, 8)), k_mean=1.0)
    assert Z.initialize(0.0, 0.0, 10.0) == 5
    # substep count of docs/model.md: ceil(H/h_max*(1 - 1e-12)), at least 1
    assert lib.gk_substeps(1e-4, 1e-5) == 10.0
    assert lib.gk_substeps(1e-4, 3e-5) == 4.0
    assert lib.gk_substeps(1e-6, 1e-5) == 1.0


def test_lookup_at_huge_and_non_finite_angles_stays_on_the_table(lib):
    """Beyond 2^52 table cells an angle is an integer number of cells, so the
    lookup must return a stored node value (docs/model.md "Table lookup"), never
    an extrapolation; a non-finite angle must not crash (the lookup reads node 0
    with weight NaN).  Reference: the set of stored values."""
    n = 24
    rows = np.random.default_rng(7).uniform(1e8, 3e8, size=(1, 1, n))
    K = Kernel(lib, rows, np.zeros((1, 1, n)), np.zeros((1, n)), k_mean=2e8)
    for theta in (1e300, -1e300, 3.0e17, -7.7e15 * PHI):
        K.s[:] = (theta, 0.0, 1e-3, 0.0)
        got = K.outputs(100.0)[6]
        assert got in set(rows.ravel()), theta
    for theta in (float("nan"), float("inf"), -float("inf")):
        K.s[:] = (theta, 0.0, 1e-3, 0.0)
        assert lib.gk_outputs(K.m.ctypes.data, K.s.ctypes.data, 100.0, K.out.ctypes.data) == 0
