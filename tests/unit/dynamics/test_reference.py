"""The event-located reference integrator (gearfmu.dynamics.reference) against closed forms.

References: the damped linear oscillator m x'' + c x' + k x = 0 (textbook closed
form, e.g. Meirovitch, Elements of Vibration Analysis, ch. 1); the undamped
impact (backlash) oscillator, solved by hand piecewise: contact arcs of a
harmonic oscillator joined by free flights across the gap 2b at constant speed,
period 2 pi/omega + 4 b/(A omega); the static balance of two springs in parallel
with offsets (hand calculation); and refinement of the reference's own
tolerance (an answer that stops changing) and a second scipy method (Radau).
"""
import math

import numpy as np
import pytest

from gearfmu.bench import hard_case
from gearfmu.dynamics.reference import ReferenceInputError, equilibrium_dte_exact_m, simulate_reference
from gearfmu.tables.synthetic import tables_from_arrays

RB1, RB2, I1, I2 = 0.05, 0.08, 0.002, 0.009
ME = I1 * I2 / (I1 * RB2 ** 2 + I2 * RB1 ** 2)  # seed 003 below eq 2


def constant_tables(k, b=0.0):
    return tables_from_arrays(k_N_per_m=np.full((1, 8), k), backlash_half_m=b, base_radius_pinion_m=RB1,
                              base_radius_gear_m=RB2, inertia_pinion_kgm2=I1, inertia_gear_kgm2=I2,
                              teeth_pinion=20, teeth_gear=32)


def test_damped_oscillator_closed_form():
    """Constant k, no error, no backlash, no torque, contact_zone damping: x obeys
    m_e x'' + c x' + k x = 0 exactly (docs/model.md with T1 = T2 = 0)."""
    k, zeta, x0 = 3e8, 0.05, 1e-5
    t = constant_tables(k)
    wn = math.sqrt(k / ME)
    H = 2 * math.pi / wn / 10
    r = simulate_reference(t, stop_time_s=60 * H, comm_step_s=H, pinion_torque_Nm=0.0, gear_torque_Nm=0.0,
                           pinion_speed_start_rad_s=50.0, damping_ratio=zeta, damping_model="contact_zone",
                           dte_start_m=x0)
    wd = wn * math.sqrt(1 - zeta ** 2)
    ts = r.time_s
    x = x0 * np.exp(-zeta * wn * ts) * (np.cos(wd * ts) + zeta / math.sqrt(1 - zeta ** 2) * np.sin(wd * ts))
    err = np.max(np.abs(r.dte - x)) / x0
    assert err < 1e-9, err  # measured 2e-11
    # mesh force F = k x + c v with c = 2 zeta sqrt(k m_e)
    assert np.max(np.abs(r.mesh_force - (k * r.dte + 2 * zeta * math.sqrt(k * ME) * r.dte_rate))) < 1e-6 * k * x0


def impact_closed_form(ts, k, b, A):
    """x(t) of the undamped backlash oscillator from x = b + A, v = 0 (module docstring)."""
    w = math.sqrt(k / ME)
    tq, tf = math.pi / (2 * w), 2 * b / (A * w)
    period = 4 * tq + 2 * tf
    out = []
    for t in np.mod(ts, period):
        if t <= tq:
            out.append(b + A * math.cos(w * t))
        elif t <= tq + tf:
            out.append(b - A * w * (t - tq))
        elif t <= 3 * tq + tf:
            out.append(-b - A * math.sin(w * (t - tq - tf)))
        elif t <= 3 * tq + 2 * tf:
            out.append(-b + A * w * (t - 3 * tq - tf))
        else:
            out.append(b + A * math.sin(w * (t - 3 * tq - 2 * tf)))
    return np.array(out), period


def test_impact_oscillator_closed_form():
    """Drive-flank contact, separation, back-flank impact and back: every switch is an
    event; the reference follows the piecewise closed form to 1e-9 of the amplitude."""
    k, b, A = 2e8, 20e-6, 5e-6
    t = constant_tables(k, b)
    w = math.sqrt(k / ME)
    H = 2 * math.pi / w / 7.3
    r = simulate_reference(t, stop_time_s=80 * H, comm_step_s=H, pinion_torque_Nm=0.0, gear_torque_Nm=0.0,
                           pinion_speed_start_rad_s=30.0, damping_ratio=0.0, dte_start_m=b + A)
    x, period = impact_closed_form(r.time_s, k, b, A)
    assert r.time_s[-1] > 3 * period  # several impacts on both flanks
    assert np.any(r.pair_force[:, 0] < 0) and np.any(r.pair_force[:, 0] > 0) and np.any(r.mesh_force == 0)
    err = np.max(np.abs(r.dte - x)) / A
    assert err < 1e-9, err  # measured 4e-12
    assert r.info["events"] >= 4 * 3


@pytest.fixture(scope="module")
def impacts():
    tables, kw = hard_case("double_sided_impacts")
    kw = dict(kw, stop_time_s=kw["comm_step_s"] * 48)
    return tables, kw, simulate_reference(tables, **kw)


@pytest.mark.slow
def test_refining_the_tolerance_does_not_change_the_answer(impacts):
    """rtol 1e-10 -> 1e-12 and max step halved: the reference moves by less than 1e-8 of the
    DTE range on a case with impacts on both flanks and meshing errors (measured 4e-11)."""
    tables, kw, r = impacts
    assert np.any(r.pair_force < 0) and np.any(r.mesh_force == 0)
    r2 = simulate_reference(tables, rtol=1e-12, steps_per_period=128, **kw)
    for name in ("dte", "mesh_force"):
        a, b = getattr(r, name), getattr(r2, name)
        assert np.max(np.abs(a - b)) / np.ptp(b) < 1e-8, name


@pytest.mark.slow
def test_radau_agrees_with_dop853(impacts):
    """A second scipy method (implicit Radau IIA) with the same event location."""
    tables, kw, r = impacts
    r2 = simulate_reference(tables, method="Radau", rtol=1e-10, **kw)
    assert np.max(np.abs(r.dte - r2.dte)) / np.ptp(r.dte) < 1e-7  # measured ~1e-9


def test_equilibrium_two_springs_by_hand():
    """k = [1e8, 2e8] N/m, e = [0, 1 um], b = 0, F = 300 N: both in contact,
    x = (F + k1 e1 + k2 e2)/(k1 + k2) = 500/3e8 m; with F = 50 N, x < e2 and b = 0 put pair 2
    on its back flank (seed 003 eq 6), so the same line holds: x = 250/3e8 m.  With F = 0 and
    b = 2 um the dead zones are [-2, 2] and [-1, 3] um; the leftmost root is e2 - b = -1 um."""
    K, E = np.array([1e8, 2e8]), np.array([0.0, 1e-6])
    assert equilibrium_dte_exact_m(K, E, [0, 0], 300.0) == pytest.approx(500 / 3e8, rel=1e-14)
    assert equilibrium_dte_exact_m(K, E, [0, 0], 50.0) == pytest.approx(250 / 3e8, rel=1e-14)
    assert equilibrium_dte_exact_m(K, E, [2e-6, 2e-6], 0.0) == pytest.approx(-1e-6, rel=1e-14)
    assert math.isnan(equilibrium_dte_exact_m([0.0, 0.0], E, [0, 0], 1.0))


def test_bad_input_names_the_argument():
    t = constant_tables(1e8)
    base = dict(stop_time_s=1e-3, comm_step_s=1e-4, pinion_torque_Nm=1.0, pinion_speed_start_rad_s=1.0,
                damping_ratio=0.01)
    for key, val, word in (("comm_step_s", -1.0, "comm_step_s"), ("damping_model", "x", "damping_model"),
                           ("stop_time_s", 1.05e-3, "stop_time_s"), ("pinion_torque_Nm", np.ones(3), "pinion_torque_Nm"),
                           ("damping_ratio", float("nan"), "damping_ratio")):
        with pytest.raises(ReferenceInputError, match=word):
            simulate_reference(t, **dict(base, **{key: val}))
    with pytest.raises(ReferenceInputError, match="tables"):
        simulate_reference("nope", **base)



def test_accuracy_object_is_the_keywords_and_the_gearbox_one():
    """The accuracy of the reference is one ReferenceAccuracy, the gearbox reference's too: given
    as an object or field by field as keywords, the same run bit for bit; a bad field is one line
    naming it (the pair's error class, the gearbox's GearboxInputError), an unknown keyword the
    TypeError Python raises for one."""
    from gearfmu.dynamics.reference import ReferenceAccuracy
    from gearfmu.gearbox.cases import gearbox_case
    from gearfmu.gearbox.native import GearboxInputError
    from gearfmu.gearbox.reference import ReferenceAccuracy as GearboxAccuracy, simulate_reference as gearbox_reference

    assert GearboxAccuracy is ReferenceAccuracy
    t = constant_tables(1e8, b=1e-6)
    base = dict(stop_time_s=1e-3, comm_step_s=1e-4, pinion_torque_Nm=1.0, pinion_speed_start_rad_s=1.0,
                damping_ratio=0.01)
    a = simulate_reference(t, rtol=1e-8, atol_scale=10.0, method="RK45", steps_per_period=16.0, **base)
    b = simulate_reference(t, accuracy=ReferenceAccuracy(rtol=1e-8, atol_scale=10.0, method="RK45",
                                                         steps_per_period=16.0), **base)
    c = simulate_reference(t, accuracy=ReferenceAccuracy(rtol=1e-3, method="RK45", steps_per_period=16.0),
                           rtol=1e-8, atol_scale=10.0, **base)
    for r in (b, c):
        np.testing.assert_array_equal(a.dte, r.dte)
        assert r.info["method"] == "RK45" and r.info["rtol"] == 1e-8
    for bad in (dict(rtol=0.0), dict(rtol=float("nan")), dict(accuracy="tight")):
        with pytest.raises(ReferenceInputError, match=next(iter(bad))) as info:
            simulate_reference(t, **bad, **base)
        assert "\n" not in str(info.value)
    with pytest.raises(ReferenceInputError, match="rtol: must be > 0"):
        ReferenceAccuracy(rtol=-1e-6)
    with pytest.raises(TypeError, match="simulate_reference\\(\\) got an unexpected keyword argument 'tol'"):
        simulate_reference(t, tol=1e-6, **base)
    model, kw = gearbox_case("torque_step", mesh_periods=1)
    with pytest.raises(GearboxInputError, match="rtol: must be > 0"):
        gearbox_reference(model, rtol=0.0, **kw)

def test_temperature_axis_selects_the_slice_as_the_native_solver_does():
    """Tables with a temperature axis (two constant-k slices, 3e8 N/m at 30 degC and
    2e8 N/m at 70 degC): the reference runs at ``bulk_temperature_C`` (default: the
    tables' default_temperature_C, as gearfmu.dynamics.native.simulate) on the node-wise
    blend, so at 50 degC k = 2.5e8 N/m and x follows the damped oscillator
    m_e x'' + c x' + k x = 0 in closed form (c = 2 zeta sqrt(k_mean m_e) with the
    tables' k_mean, docs/model.md).  Bad temperatures give a one-line error naming
    bulk_temperature_C."""
    from gearfmu.tables.mesh_tables import stack_temperatures

    tt = stack_temperatures([constant_tables(3e8), constant_tables(2e8)], [30.0, 70.0],
                            temperature_reference_C=30.0)
    zeta, x0 = 0.02, 1e-5
    c = 2 * zeta * math.sqrt(tt.k_mean_N_per_m * ME)
    for T, k in ((None, 3e8), (50.0, 2.5e8), (70.0, 2e8)):
        wn = math.sqrt(k / ME)
        H = 2 * math.pi / wn / 10
        r = simulate_reference(tt, stop_time_s=40 * H, comm_step_s=H, pinion_torque_Nm=0.0, gear_torque_Nm=0.0,
                               pinion_speed_start_rad_s=50.0, damping_ratio=zeta, damping_model="contact_zone",
                               dte_start_m=x0, bulk_temperature_C=T)
        g = c / (2 * ME)
        wd = math.sqrt(wn ** 2 - g ** 2)
        ts = r.time_s
        x = x0 * np.exp(-g * ts) * (np.cos(wd * ts) + g / wd * np.sin(wd * ts))
        assert np.max(np.abs(r.dte - x)) / x0 < 1e-9, (T, np.max(np.abs(r.dte - x)) / x0)
    base = dict(stop_time_s=1e-3, comm_step_s=1e-4, pinion_torque_Nm=1.0, pinion_speed_start_rad_s=1.0,
                damping_ratio=0.01)
    for bad in (80.0, float("nan"), "warm", [30.0, 40.0]):
        with pytest.raises(ReferenceInputError, match="bulk_temperature_C") as info:
            simulate_reference(tt, bulk_temperature_C=bad, **base)
        assert "\n" not in str(info.value)
    with pytest.raises(ReferenceInputError, match="bulk_temperature_C: the tables have no temperature axis"):
        simulate_reference(constant_tables(1e8), bulk_temperature_C=30.0, **base)
