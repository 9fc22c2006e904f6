"""Tests of the native (numba) solver and the synthetic tables.

References (none produced by code of this package):
* closed form of the damped linear oscillator m x'' + c x' + k x = F
  (any vibrations textbook, e.g. Rao, Mechanical Vibrations, sec. 2.6/4.x);
* the exact discrete propagator of classical RK4 on a linear system,
  y_n - y_s = R(hA)^n (y_0 - y_s), R(Z) = I + Z + Z^2/2 + Z^3/6 + Z^4/24
  (Hairer, Norsett & Wanner, Solving ODEs I, sec. II.1 / IV.2: stability function);
* scipy.integrate.solve_ivp (DOP853, rtol 1e-10) on right-hand sides written
  here in plain Python from docs/model.md and seed 003 eq 6 and 12;
* momentum balance m_e (v_b - v_a) = int (F_m - F) dt (Newton's second law);
* hand calculations of the rectangular-wave TVMS (contact ratio = mean number
  of pairs in contact) and of springs in parallel for the static equilibrium.
"""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gearfmu.dynamics.native import (
    NativeInputError, choose_max_step_s, dimensionless, equilibrium_dte_m, simulate,
    simulate_sdof, substeps,
)
from gearfmu.tables.synthetic import (
    SyntheticTableError, rectangular_wave_tables, tables_from_arrays,
)

RB = 0.07          # base radius (m)
INERTIA = 0.0074   # kg m^2 (seed 003 Table 1)
K_CONST = 3.0e8    # N/m


def const_tables(k=K_CONST, rb1=RB, rb2=RB, i1=INERTIA, i2=INERTIA):
    """One slot of constant stiffness, no error, no backlash."""
    return tables_from_arrays(k_N_per_m=np.full((1, 8), k), base_radius_pinion_m=rb1,
                              base_radius_gear_m=rb2, inertia_pinion_kgm2=i1, inertia_gear_kgm2=i2,
                              teeth_pinion=50, teeth_gear=50)


def me_of(rb1, rb2, i1, i2):
    # seed 003, below eq 2
    return i1 * i2 / (i1 * rb2 ** 2 + i2 * rb1 ** 2)


def oscillator(t, m, c, k, f, x0, v0):
    """Closed-form response of m x'' + c x' + k x = f (underdamped): x(t), v(t)."""
    wn = math.sqrt(k / m)
    z = c / (2.0 * math.sqrt(k * m))
    wd = wn * math.sqrt(1.0 - z * z)
    xs = f / k
    a = x0 - xs
    bcoef = (v0 + z * wn * a) / wd
    env = np.exp(-z * wn * t)
    x = xs + env * (a * np.cos(wd * t) + bcoef * np.sin(wd * t))
    v = env * ((-z * wn) * (a * np.cos(wd * t) + bcoef * np.sin(wd * t))
               + (-a * wd * np.sin(wd * t) + bcoef * wd * np.cos(wd * t)))
    return x, v


# --------------------------------------------------------------- linear limit
def test_sdof_linear_step_response_closed_form_and_rk4_order():
    """Constant k, no errors/backlash, contact_zone damping (F = k x + c v exactly):
    closed-form step response from x = 0.  RK4 global phase error estimate
    omega_n t (omega_n h)^4/120 (Hairer et al. sec. II.1); tolerance 2x that.
    Halving h must cut the error by 2^4 (fourth order): ratio in [12, 20]."""
    tb = const_tables()
    zeta, T1, w1 = 0.05, 300.0, 100.0
    me = me_of(RB, RB, INERTIA, INERTIA)
    wn = math.sqrt(K_CONST / me)
    period = 2 * math.pi / wn
    errs = []
    for ppp in (100, 200):
        H = period / 20
        r = simulate_sdof(tb, omega1_rad_s=w1, stop_time_s=200 * H, comm_step_s=H,
                          max_step_s=period / ppp, pinion_torque_Nm=T1, damping_ratio=zeta,
                          damping_model="contact_zone", dte_start_m=0.0, integrator="rk4")
        assert r.substeps == ppp // 20
        c = 2 * zeta * math.sqrt(K_CONST * me)
        x_ref, v_ref = oscillator(r.time_s, me, c, K_CONST, T1 / RB, 0.0, 0.0)
        xs = T1 / RB / K_CONST
        err = np.max(np.abs(r.dte - x_ref)) / xs
        est = wn * r.time_s[-1] * (wn * r.step_s) ** 4 / 120.0
        assert err < 2.0 * est, (ppp, err, est)
        assert np.max(np.abs(r.dte_rate - v_ref)) / (xs * wn) < 2.0 * est
        errs.append(err)
        # outputs at row 0 and later: mesh force = k x + c v (linear force law)
        np.testing.assert_allclose(r.mesh_force, K_CONST * r.dte + c * r.dte_rate, rtol=1e-12,
                                   atol=1e-9 * T1 / RB)
    assert 12.0 < errs[0] / errs[1] < 20.0, errs


def test_two_inertia_matches_rk4_propagator_and_closed_form():
    """Two-inertia model, unbalanced torques, elastobacklash with teeth never
    separating and |c v| < k x (checked): the state [x, v] follows
    (a) the exact RK4 propagator R(hA)^n of the linear relative equation
        m_e x'' + c x' + k x = m_e (Rb1 T1/I1 + Rb2 T2/I2) to round-off (1e-9),
    (b) its closed form within the RK4 error estimate, and the pinion speed
        follows I1 omega1' = T1 - Rb1 F integrated exactly (F linear in x, v)."""
    rb1, rb2, i1, i2 = 0.05, 0.09, 0.004, 0.02
    tb = const_tables(rb1=rb1, rb2=rb2, i1=i1, i2=i2)
    zeta, T1, T2, w0 = 0.03, 200.0, 250.0, 150.0
    me = me_of(rb1, rb2, i1, i2)
    wn = math.sqrt(K_CONST / me)
    c = 2 * zeta * math.sqrt(K_CONST * me)
    feff = me * (rb1 * T1 / i1 + rb2 * T2 / i2)
    xs = feff / K_CONST
    x0 = 0.6 * xs
    period = 2 * math.pi / wn
    H = period / 16
    r = simulate(tb, stop_time_s=160 * H, comm_step_s=H, max_step_s=period / 128,
                 pinion_torque_Nm=T1, gear_torque_Nm=T2, pinion_speed_start_rad_s=w0,
                 damping_ratio=zeta, dte_start_m=x0, integrator="rk4")
    assert np.all(r.dte > 0) and np.all(np.abs(c * r.dte_rate) < K_CONST * r.dte)
    h = r.step_s
    A = np.array([[0.0, 1.0], [-K_CONST / me, -c / me]])
    Z = h * A
    R = np.eye(2) + Z + Z @ Z / 2 + Z @ Z @ Z / 6 + Z @ Z @ Z @ Z / 24
    Rn = np.linalg.matrix_power(R, r.substeps)
    z = np.array([x0 - xs, 0.0])
    xs_prop, vs_prop = [], []
    for _ in range(len(r.time_s)):
        xs_prop.append(z[0] + xs)
        vs_prop.append(z[1])
        z = Rn @ z
    np.testing.assert_allclose(r.dte, xs_prop, rtol=0, atol=1e-9 * abs(xs - x0))
    np.testing.assert_allclose(r.dte_rate, vs_prop, rtol=0, atol=1e-9 * abs(xs - x0) * wn)
    x_ref, v_ref = oscillator(r.time_s, me, c, K_CONST, feff, x0, 0.0)
    est = wn * r.time_s[-1] * (wn * h) ** 4 / 120.0
    assert np.max(np.abs(r.dte - x_ref)) < 2 * est * abs(xs - x0)
    # I1 omega1' = T1 - Rb1 (k x + c v): integrate with x = x_ref, v = v_ref analytically:
    # int (k x + c v) dt = k int x dt + c (x - x0), int x dt = (feff t - me (v - 0) - c (x - x0))/k
    t = r.time_s
    int_x = (feff * t - me * v_ref - c * (x_ref - x0)) / K_CONST
    om_ref = w0 + (T1 * t - rb1 * (K_CONST * int_x + c * (x_ref - x0))) / i1
    assert np.max(np.abs(r.pinion_speed - om_ref)) < 1e-6 * np.ptp(om_ref)
    # derived gear speed and angle (docs/model.md outputs)
    np.testing.assert_allclose(r.gear_speed, (r.pinion_speed * rb1 - r.dte_rate) / rb2, rtol=1e-14)


# ---------------------------------------------- time-varying stiffness + backlash
def _table_rhs(tb, T1, T2, zeta, model):
    """docs/model.md right-hand side, written independently in plain Python."""
    Phi, N = tb.phi_period_rad, tb.n_phi
    dphi = Phi / N
    K, E, B = tb.k_N_per_m[0], tb.e_m[0], tb.backlash_half_m
    rb1, rb2 = tb.base_radius_pinion_m, tb.base_radius_gear_m
    I1, I2 = tb.inertia_pinion_kgm2, tb.inertia_gear_kgm2
    c = 2 * zeta * math.sqrt(tb.k_mean_N_per_m * me_of(rb1, rb2, I1, I2))

    def force(th, om, x, v):
        phim = th - Phi * math.floor(th / Phi)
        s = phim / dphi
        i0 = min(max(int(math.floor(s)), 0), N - 1)
        w = s - i0
        i1 = (i0 + 1) % N
        F = 0.0
        for j in range(K.shape[0]):
            k = K[j, i0] + w * (K[j, i1] - K[j, i0])
            e = E[j, i0] + w * (E[j, i1] - E[j, i0])
            de = (E[j, i1] - E[j, i0]) / dphi * om
            b = B[j, i0] + w * (B[j, i1] - B[j, i0])
            d = x - e
            fd = c * (v - de)
            fc = k * (d - b) if d > b else (k * (d + b) if d < -b else 0.0)
            if model == "contact_zone":
                F += fc + fd if k > 0 else 0.0
            elif d > b:
                F += max(0.0, fc + min(fc, fd))
            elif d < -b:
                F += min(0.0, fc + max(fc, fd))
        return F

    def rhs(t, y):
        th, om, x, v = y
        F = force(th, om, x, v)
        return [om, (T1 - rb1 * F) / I1, v, rb1 * (T1 - rb1 * F) / I1 - rb2 * (rb2 * F - T2) / I2]

    return rhs, force


@pytest.mark.parametrize("model", ["elastobacklash", "contact_zone"])
def test_rectangular_wave_with_backlash_vs_scipy(model):
    """Rectangular-wave TVMS, per-pair sine errors, backlash 2b = 40 um, light
    load and an impact start so the teeth separate and hit the back flank.
    Reference: solve_ivp DOP853 rtol 1e-10 on the plain-Python RHS above.
    The table slopes of e jump at grid nodes (and contact_zone switches damping on
    where k becomes > 0), so RK4 is locally O(h^2) there: with h = mesh
    period/51200 the measured difference is <= 6e-7 of each signal's range
    (contact_zone: 6e-6 at h 4x larger, i.e. ~h^2; elastobacklash: flat at ~4e-7,
    the reference's own level: rtol 1e-12 moves it by 1e-7); tolerance 2e-6."""
    A = 4e-6
    tb = rectangular_wave_tables(2e8, contact_ratio=1.6, backlash_half_m=20e-6, points_per_mesh=16,
                                 pair_error_m=lambda j, u: A * (1 + j) * np.sin(np.pi * u))
    T1, w0, zeta, x0 = 5.0, 200.0, 0.03, -35e-6
    T2 = T1 * tb.base_radius_gear_m / tb.base_radius_pinion_m
    mp = tb.mesh_period_rad / w0
    H = mp / 32
    r = simulate(tb, stop_time_s=4 * 32 * H, comm_step_s=H, max_step_s=H / 1600, pinion_torque_Nm=T1,
                 pinion_speed_start_rad_s=w0, damping_ratio=zeta, dte_start_m=x0, damping_model=model,
                 integrator="rk4")
    rhs, force = _table_rhs(tb, T1, T2, zeta, model)
    sol = solve_ivp(rhs, (0.0, r.time_s[-1]), [0.0, w0, x0, 0.0], method="DOP853", rtol=1e-10,
                    atol=[1e-14, 1e-10, 1e-17, 1e-12], t_eval=r.time_s)
    assert sol.status == 0
    for name, ours, ref in (("pinion_angle", r.pinion_angle, sol.y[0]), ("pinion_speed", r.pinion_speed, sol.y[1]),
                            ("dte", r.dte, sol.y[2]), ("dte_rate", r.dte_rate, sol.y[3])):
        assert np.max(np.abs(ours - ref)) < 2e-6 * np.ptp(ref), name
    F_ref = np.array([force(*sol.y[:, i]) for i in range(len(r.time_s))])
    assert np.max(np.abs(r.mesh_force - F_ref)) < 3e-5 * np.ptp(F_ref)
    if model == "elastobacklash":
        # the hard case really happened: separation (F = 0) and back-flank contact (F < 0)
        assert np.sum(r.mesh_force == 0.0) > 10 and np.sum(r.mesh_force < 0.0) > 10


# ------------------------------------------------------------ force balance
def test_mean_mesh_force_equals_load_in_steady_state():
    """Constant speed (time-indexed SDOF), no errors, rectangular-wave TVMS:
    Newton, m_e (v_b - v_a) = int (F_m - F) dt over whole mesh periods, so in
    steady state (60 mesh periods, zeta = 0.07: transient decayed by e^-50) the
    mean F = T1/Rb1.  512 samples per mesh period; the sample mean of a periodic
    signal with kinks has a quadrature error ~ (1/512)^2: measured 1.8e-6
    (SDOF) and 3e-6 (two-inertia), tolerance 1e-5."""
    tb = rectangular_wave_tables(2e8, contact_ratio=1.7547, points_per_mesh=64)
    T1, w1, npp = 340.0, 250.0, 512
    mp = tb.mesh_period_rad / w1
    H = mp / npp
    fm = T1 / tb.base_radius_pinion_m
    r = simulate_sdof(tb, omega1_rad_s=w1, stop_time_s=60 * npp * H, comm_step_s=H, max_step_s=H,
                      pinion_torque_Nm=T1, damping_ratio=0.07)
    assert np.ptp(r.mesh_force[-npp:]) > 0.5 * fm  # a truly dynamic steady state
    assert abs(r.mesh_force[-20 * npp:].mean() - fm) < 1e-5 * fm
    # the two-inertia model at the balancing load T2 = T1 Rb2/Rb1
    r2 = simulate(tb, stop_time_s=60 * npp * H, comm_step_s=H, max_step_s=H, pinion_torque_Nm=T1,
                  pinion_speed_start_rad_s=w1, damping_ratio=0.07)
    assert abs(r2.mesh_force[-20 * npp:].mean() - fm) < 1e-5 * fm


def smooth_two_slot_tables(k0=2e8, amp=0.3, backlash_half_m=0.0):
    """Two slots whose stiffness varies smoothly but never reaches 0 (no meshing-in ramp)."""
    phi = np.arange(64) / 64
    k = np.stack([k0 * (1 + amp * np.sin(2 * np.pi * phi)), k0 * (1 + amp * np.cos(2 * np.pi * phi))])
    return tables_from_arrays(k_N_per_m=k, backlash_half_m=backlash_half_m)


def test_damping_models_identical_while_in_contact_and_differ_after_separation():
    """docs/model.md: elastobacklash gives fc + fd while the pair is on the drive
    flank and |fd| < fc; contact_zone gives fc + fd for k > 0.  Every slot always
    loaded (k > 0 everywhere, no errors, heavy load): identical to the last bit.
    (Rectangular-wave tables do not qualify: a pair meshing in has k -> 0 but the
    full damping c, so elastobacklash clips its force; see docs/native.md.)
    Light load with an impact start and backlash: the models must differ."""
    tb = smooth_two_slot_tables()
    kw = dict(stop_time_s=0.02, comm_step_s=1e-4, pinion_torque_Nm=400.0, pinion_speed_start_rad_s=300.0,
              damping_ratio=0.05)
    a = simulate(tb, damping_model="elastobacklash", **kw)
    b = simulate(tb, damping_model="contact_zone", **kw)
    assert np.all(a.pair_force > 0) and np.ptp(a.mesh_force) > 0.1 * a.mesh_force.mean()
    for name in ("dte", "pinion_speed", "mesh_force", "pair_force", "mesh_stiffness"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    tbl = smooth_two_slot_tables(backlash_half_m=10e-6)
    kw.update(pinion_torque_Nm=2.0, dte_start_m=-25e-6)
    a = simulate(tbl, damping_model="elastobacklash", **kw)
    b = simulate(tbl, damping_model="contact_zone", **kw)
    assert np.sum(a.mesh_force == 0.0) > 5
    assert np.max(np.abs(a.dte - b.dte)) > 1e-7


# --------------------------------------------------------- traditional model
def test_traditional_model_vs_scipy_eq12():
    """Traditional single-pair model = simulate_sdof(tables.traditional()): total
    TVMS, comprehensive error (here the envelope min of the two pair errors),
    seed 003 eq 12 with eq 6, written here as an SDOF RHS in plain Python and
    solved by DOP853 rtol 1e-10 (itself within 3e-8 of a segment-wise solve
    restarted at every table node).  de/dt jumps at every table node, so RK4
    converges only O(h) here.  The steps are commensurate with the table: a node
    falls exactly on every second communication point, and whether the rounded
    stage angle there lands in the left or the right cell decides each of these
    ~160 local errors of h/6 times the jump.  So the level depends on the lookup's
    last bit: measured 2.0e-5, 3.2e-6, 7.0e-7 of the range of x at h = H/400,
    H/1600, H/6400 with the angle reduced modulo the period and divided by dphi,
    7.5e-5, 9.1e-6, 2.1e-6 with theta1*inv_dphi (docs/model.md "Table lookup");
    with a start angle off the nodes both give 2e-5 to 4e-5 at H/6400.
    Tolerance 5e-6 at H/6400."""
    tb = rectangular_wave_tables(2e8, contact_ratio=1.6, points_per_mesh=16, backlash_half_m=5e-6,
                                 pair_error_m=lambda j, u: 3e-6 * np.sin(np.pi * u) * (1 + 0.5 * j))
    tr = tb.traditional()
    assert tr.slots == 1
    np.testing.assert_allclose(tr.k_N_per_m[0, 0], tb.k_N_per_m[0].sum(axis=0))
    # envelope min of the engaged pairs' errors (hand rule, seed 003 Fig. 5 text)
    env = np.where(tb.k_N_per_m[0] > 0, tb.e_m[0], np.inf).min(axis=0)
    np.testing.assert_array_equal(tr.e_m[0, 0], env)
    T1, w1, zeta = 20.0, 300.0, 0.04
    rb = tb.base_radius_pinion_m
    me = tb.equivalent_mass_kg
    c = 2 * zeta * math.sqrt(tb.k_mean_N_per_m * me)
    mp = tb.mesh_period_rad / w1
    H = mp / 32
    r = simulate_sdof(tr, omega1_rad_s=w1, stop_time_s=5 * 32 * H, comm_step_s=H, max_step_s=H / 6400,
                      pinion_torque_Nm=T1, damping_ratio=zeta, damping_model="contact_zone", dte_start_m=0.0,
                      integrator="rk4")
    Phi, N = tr.phi_period_rad, tr.n_phi
    dphi = Phi / N
    K, E, B = tr.k_N_per_m[0, 0], tr.e_m[0, 0], tr.backlash_half_m[0]

    def rhs(t, y):
        x, v = y
        th = w1 * t
        phim = th - Phi * math.floor(th / Phi)
        s = phim / dphi
        i0 = min(int(s), N - 1)
        w = s - i0
        i1 = (i0 + 1) % N
        k = K[i0] + w * (K[i1] - K[i0])
        e = E[i0] + w * (E[i1] - E[i0])
        b = B[i0] + w * (B[i1] - B[i0])
        d = x - e
        f = d - b if d > b else (d + b if d < -b else 0.0)   # seed 003 eq 6
        F = k * f + c * (v - (E[i1] - E[i0]) / dphi * w1)    # seed 003 eq 12
        return [v, (T1 / rb - F) / me]

    sol = solve_ivp(rhs, (0, r.time_s[-1]), [0.0, 0.0], method="DOP853", rtol=1e-10,
                    atol=[1e-17, 1e-12], t_eval=r.time_s)
    assert np.max(np.abs(r.dte - sol.y[0])) < 5e-6 * np.ptp(sol.y[0])


def test_traditional_equals_multipair_without_damping_errors_or_separation():
    """With zeta = 0, no errors and no backlash all pairs share one contact state
    and sum_j k_j f(x) = (sum_j k_j) f(x): the two models are the same ODE (agree
    to round-off, 1e-9 of the range)."""
    tb = rectangular_wave_tables(2e8, contact_ratio=1.7547, points_per_mesh=32)
    kw = dict(omega1_rad_s=300.0, stop_time_s=0.01, comm_step_s=1e-4, pinion_torque_Nm=300.0, damping_ratio=0.0)
    a = simulate_sdof(tb, **kw)
    b = simulate_sdof(tb.traditional(), **kw)
    np.testing.assert_allclose(a.dte, b.dte, rtol=0, atol=1e-9 * np.ptp(a.dte))
    np.testing.assert_allclose(a.mesh_force, b.mesh_force, rtol=0, atol=1e-9 * np.ptp(a.mesh_force))


# ------------------------------------------------------------- dimensionless
def test_dimensionless_form_closed_form():
    """Seed 003 eq 7: q'' + 2 zeta q' + q = F_m/(k_m l) for constant k; closed form
    in tau; Omega_h = z1 omega1/omega_n by hand."""
    tb = const_tables()
    w1, T1, zeta, l = 120.0, 250.0, 0.05, 1e-6
    me = me_of(RB, RB, INERTIA, INERTIA)
    wn = math.sqrt(K_CONST / me)
    r = simulate_sdof(tb, omega1_rad_s=w1, stop_time_s=0.002, comm_step_s=2e-5, max_step_s=2e-7,
                      pinion_torque_Nm=T1, damping_ratio=zeta, damping_model="contact_zone", dte_start_m=0.0)
    d = dimensionless(r, tb, l)
    assert d.Omega_h == pytest.approx(50 * w1 / wn, rel=1e-12)
    assert d.zeta == pytest.approx(zeta, rel=1e-12)
    assert d.load == pytest.approx(T1 / RB / (K_CONST * l), rel=1e-12)
    q_ref, _ = oscillator(d.tau, 1.0, 2 * zeta, 1.0, d.load, 0.0, 0.0)
    assert np.max(np.abs(d.q - q_ref)) < 1e-7 * d.load


# ------------------------------------------------------- tables and helpers
def test_rectangular_wave_levels_match_hand_calculation():
    """Per mesh period: double contact over (eps - 1) T, single over (2 - eps) T;
    k_mean = k_s + (eps - 1)(k_d - k_s) (textbook rectangular wave)."""
    ks, kd, eps, npm = 2.0e8, 3.4e8, 1.625, 64  # eps*npm integer: exact on the grid
    tb = rectangular_wave_tables(ks, kd, contact_ratio=eps, points_per_mesh=npm)
    ktot = tb.k_total_N_per_m()[0]
    assert set(np.unique(ktot)) == {ks, kd}
    assert np.mean(ktot == kd) == pytest.approx(eps - 1.0, abs=1e-12)
    assert tb.k_mean_N_per_m == pytest.approx(ks + (eps - 1) * (kd - ks), rel=1e-12)
    assert tb.slots == 2 and tb.n_phi == 2 * npm
    # pair n occupies slot n % P from meshing-in for eps mesh periods
    on = tb.k_N_per_m[0, 0] > 0
    assert on[0] and on[int(eps * npm) - 1] and not on[int(eps * npm)] and not on[-1]
    hcr = rectangular_wave_tables(1e8, contact_ratio=2.4, points_per_mesh=20)
    assert hcr.slots == 3
    assert np.mean((hcr.k_N_per_m[0] > 0).sum(axis=0)) == pytest.approx(2.4, abs=1e-12)


def test_initial_equilibrium_springs_in_parallel():
    """Two engaged pairs with errors e1, e2 and half backlash b, both loaded:
    k1 (x - e1 - b) + k2 (x - e2 - b) = F  ->  x = (F + k1 (e1 + b) + k2 (e2 + b))/(k1 + k2)."""
    k1, k2, e1, e2, b, T1 = 1.5e8, 2.5e8, 2e-6, -1e-6, 3e-6, 200.0
    k = np.array([[k1] * 8, [k2] * 8])
    e = np.array([[e1] * 8, [e2] * 8])
    tb = tables_from_arrays(k_N_per_m=k, e_m=e, backlash_half_m=b, base_radius_pinion_m=RB)
    x = equilibrium_dte_m(tb, T1, 0.3)
    x_ref = (T1 / RB + k1 * (e1 + b) + k2 * (e2 + b)) / (k1 + k2)
    assert x == pytest.approx(x_ref, rel=1e-14)
    r = simulate(tb, stop_time_s=1e-4, comm_step_s=1e-4, pinion_torque_Nm=T1, pinion_speed_start_rad_s=0.0,
                 damping_ratio=0.0, pinion_angle_start_rad=0.3)
    assert r.dte[0] == x and r.mesh_force[0] == pytest.approx(T1 / RB, rel=1e-12)
    f_ref = np.array([k1 * (x_ref - e1 - b), k2 * (x_ref - e2 - b)])
    np.testing.assert_allclose(r.load_sharing[0], f_ref / f_ref.sum(), rtol=1e-10)


def test_torque_axis_interpolation_by_hand():
    """NT = 2 tables at T1 between the rows equal a single-row table whose values
    are interpolated by hand (docs/model.md torque axis); clamped outside."""
    kA, kB = np.full((1, 8), 2e8), np.full((1, 8), 3e8)
    tb = tables_from_arrays(k_N_per_m=np.stack([kA, kB]), torque_Nm=[100.0, 300.0])
    kw = dict(stop_time_s=1e-3, comm_step_s=1e-4, pinion_speed_start_rad_s=100.0, damping_ratio=0.05)
    for T1, kh in ((150.0, 2.25e8), (50.0, 2e8), (900.0, 3e8)):
        ref = tables_from_arrays(k_N_per_m=np.full((1, 8), kh))
        a, b = simulate(tb, pinion_torque_Nm=T1, **kw), simulate(ref, pinion_torque_Nm=T1,
                                                                  **dict(kw, damping_ratio=0.05 * math.sqrt(
                                                                      tb.k_mean_N_per_m / kh)))
        np.testing.assert_allclose(a.mesh_stiffness, kh, rtol=1e-14)
        np.testing.assert_allclose(a.dte, b.dte, rtol=1e-12)


def test_choose_max_step_hand_calculation():
    tb = const_tables()
    wn = math.sqrt(K_CONST / me_of(RB, RB, INERTIA, INERTIA))
    assert choose_max_step_s(tb, 10.0) == pytest.approx(2 * math.pi / wn / 64, rel=1e-14)
    # fast: mesh period 2 pi/(50 * 1000) s is shorter than 2 pi/omega_n
    assert choose_max_step_s(tb, 1000.0, 32) == pytest.approx(2 * math.pi / 50 / 1000 / 32, rel=1e-14)
    assert substeps(1e-3, 1e-4) == 10 and substeps(1e-3, 3e-4) == 4 and substeps(1e-5, 1e-3) == 1


def test_inputs_csv_and_errors(tmp_path):
    tb = rectangular_wave_tables(2e8, contact_ratio=1.5, points_per_mesh=16)
    kw = dict(stop_time_s=1e-3, comm_step_s=1e-4, pinion_speed_start_rad_s=100.0, damping_ratio=0.05)
    a = simulate(tb, pinion_torque_Nm=100.0, **kw)
    b = simulate(tb, pinion_torque_Nm=np.full(10, 100.0), **kw)
    c = simulate(tb, pinion_torque_Nm=lambda t: 100.0, **kw)
    np.testing.assert_array_equal(a.dte, b.dte)
    np.testing.assert_array_equal(a.dte, c.dte)
    assert a.time_s.shape == (11,) and a.pair_force.shape == (11, 2)
    p = tmp_path / "r.csv"
    a.to_csv(p)
    lines = p.read_text().splitlines()
    assert lines[0].startswith("# units: s,rad/s") and lines[1].split(",")[7] == "pair_force[1]"
    data = np.loadtxt(p, delimiter=",", skiprows=2)
    np.testing.assert_array_equal(data[:, 5], a.dte)
    with pytest.raises(NativeInputError, match="pinion_torque_Nm"):
        simulate(tb, pinion_torque_Nm=float("nan"), **kw)
    with pytest.raises(NativeInputError, match="damping_model"):
        simulate(tb, pinion_torque_Nm=1.0, damping_model="bogus", **kw)
    with pytest.raises(NativeInputError, match="stop_time_s"):
        simulate(tb, pinion_torque_Nm=1.0, **dict(kw, stop_time_s=1.05e-3))
    with pytest.raises(NativeInputError, match="damping_ratio"):
        simulate(tb, pinion_torque_Nm=1.0, **dict(kw, damping_ratio=-1.0))
    with pytest.raises(SyntheticTableError, match="contact_ratio"):
        rectangular_wave_tables(2e8, contact_ratio=0.9)
    with pytest.raises(SyntheticTableError, match="e_m"):
        tables_from_arrays(k_N_per_m=np.ones((2, 8)), e_m=np.ones((3, 8)))
    with pytest.raises(ValueError, match="k_N_per_m"):
        tables_from_arrays(k_N_per_m=-np.ones((2, 8)))



def test_settings_keywords_are_the_settings_fields_and_nothing_else():
    """The run-settings keywords of simulate / simulate_sdof (stop_time_s, comm_step_s, ...) are
    the RunSettings fields they name, bit for bit the same run as the settings object; a keyword
    that is none of them is the TypeError Python raises for an unknown keyword argument (the
    message of a module-level function), and simulate_sdof takes its speed as
    omega1_rad_s only."""
    import dataclasses

    from gearfmu.common.settings import RunSettings

    tb = rectangular_wave_tables(2e8, contact_ratio=1.5, points_per_mesh=16, backlash_half_m=2e-6)
    kw = dict(stop_time_s=1e-3, comm_step_s=1e-4, max_step_s=2.5e-5, pinion_speed_start_rad_s=100.0,
              damping_ratio=0.05, damping_model="elastobacklash", pinion_angle_start_rad=0.01, integrator="rk4_kink")
    s = RunSettings(stop_time_s=1e-3, output_interval_s=1e-4, max_step_s=2.5e-5, pinion_speed_start_rad_s=100.0,
                    damping_ratio=0.05, damping_model="elastobacklash", pinion_angle_start_rad=0.01,
                    integrator="rk4_kink", pinion_torque_start_Nm=30.0)
    a = simulate(tb, pinion_torque_Nm=30.0, **kw)
    b = simulate(tb, s)
    c = simulate(tb, dataclasses.replace(s, damping_ratio=0.5), pinion_torque_Nm=30.0, damping_ratio=0.05)
    for r in (b, c):
        for name in ("dte", "pinion_speed", "pair_force", "mesh_stiffness"):
            np.testing.assert_array_equal(getattr(a, name), getattr(r, name))
    sd = simulate_sdof(tb, omega1_rad_s=100.0, pinion_torque_Nm=30.0,
                       **{k: v for k, v in kw.items() if k != "pinion_speed_start_rad_s"})
    np.testing.assert_array_equal(sd.dte, simulate_sdof(tb, s).dte)

    for solver, word in ((simulate, "comm_step"), (simulate_sdof, "rtol"), (simulate_sdof, "pinion_speed_start_rad_s")):
        with pytest.raises(TypeError) as got:
            solver(tb, **{word: 1e-4})
        assert str(got.value) == f"{solver.__name__}() got an unexpected keyword argument {word!r}", got.value

def test_tables_changed_in_place_between_runs_are_checked_and_used_again():
    """simulate skips MeshTables.validate for the same tables object only while nothing validate
    reads has changed: a value made invalid in place (array element, optional array, scalar,
    replaced array) after a good run is still refused, and a valid in-place change is used --
    the run equals, bit for bit, one on freshly built tables with the new values."""
    from gearfmu.tables.mesh_tables import TableError

    kw = dict(stop_time_s=2e-3, comm_step_s=1e-4, pinion_torque_Nm=50.0, pinion_speed_start_rad_s=100.0,
              damping_ratio=0.05)
    tb = rectangular_wave_tables(2e8, contact_ratio=1.6, backlash_half_m=20e-6, points_per_mesh=16)
    assert tb.e_comprehensive_m is not None
    simulate(tb, **kw)

    def refused(change, match):
        t = rectangular_wave_tables(2e8, contact_ratio=1.6, backlash_half_m=20e-6, points_per_mesh=16)
        simulate(t, **kw)
        change(t)
        with pytest.raises(TableError, match=match):
            simulate(t, **kw)

    refused(lambda t: t.k_N_per_m.__setitem__((0, 0, 3), np.nan), "k_N_per_m")
    refused(lambda t: t.backlash_half_m.__setitem__((0, 2), -1e-6), "backlash_half_m")
    refused(lambda t: t.e_comprehensive_m.__setitem__((0, 1), np.inf), "e_comprehensive_m")
    refused(lambda t: setattr(t, "inertia_gear_kgm2", -1.0), "inertia_gear_kgm2")
    refused(lambda t: setattr(t, "e_m", np.zeros((1, 1, 4))), "e_m")

    fresh = rectangular_wave_tables(2e8, contact_ratio=1.6, backlash_half_m=20e-6, points_per_mesh=16)
    fresh.k_N_per_m = fresh.k_N_per_m * 1.5
    tb.k_N_per_m *= 1.5          # in place: same array object, new values
    a, b = simulate(tb, **kw), simulate(fresh, **kw)
    for name in ("dte", "mesh_force", "pair_force", "mesh_stiffness"):
        assert getattr(a, name).tobytes() == getattr(b, name).tobytes(), name
    assert not np.array_equal(a.mesh_stiffness, simulate(rectangular_wave_tables(
        2e8, contact_ratio=1.6, backlash_half_m=20e-6, points_per_mesh=16), **kw).mesh_stiffness)
