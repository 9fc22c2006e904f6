"""The 'rk4_seg' integrator (docs/model.md "rk4_seg"): rk4_node's held segments and event
location, the segments running from contact-zone edge to edge, every evaluation reading the
tables in its own cell, RK4 in the shifted velocities.

References (none produced by gearfmu code):
* the closed-form damped oscillator m_e x'' + 2c x' + K (x - e_bar) = F_m (two slots of constant
  stiffness k and constant errors e_j, K = 2k, e_bar = mean of the e_j; seed 003 eq 1-6 with
  kpos = 1, contact_zone);
* the event-located DOP853 solution of tests/support/integrator_cases.py (``reference``: scipy, restarted
  at every table node and contact change, right-hand side written there in plain numpy);
* rk4_kink at a small step on tables with contact-zone edges, which that module checks against the
  same DOP853 reference (the reference itself has no zone edges);
* the C kernel (gearfmu/fmu/kernel/gearkernel.c), bit for bit: tests/unit/dynamics/test_integrators.py and
  tests/unit/dynamics/test_subcell.py run rk4_seg in their numba-against-C comparisons.
"""
import dataclasses
import math

import numpy as np
import pytest

from gearfmu.dynamics.model_rhs import _seg_flags
from gearfmu.dynamics.native import simulate
from support.integrator_cases import impact_case, order_fit, reference, tent_case
from support.subcell_tables import dyn_tables


def test_rk4_seg_constant_tables_closed_form_without_node_stops():
    """Both slots k = 1e8 N/m with constant errors 3 and -1 um (contact_zone): the shifted
    velocities carry C = c*(e_0 + e_1) != 0, and rk4_seg crosses nodes only at the artificial
    segment end one table period ahead (events <= periods crossed + 1); its dte equals the
    closed form x_s + (x0 - x_s) e^{-g t}(cos w_d t + g/w_d sin w_d t), x_s = F_m/K + e_bar, to
    1e-6 of the range (RK4 at omega_n h = 0.05)."""
    tb = tent_case()[0]
    P, N = tb.slots, tb.n_phi
    e = np.zeros((1, P, N))
    e[0, 0] = 3e-6
    e[0, 1] = -1e-6
    tb = dataclasses.replace(tb, e_m=e, e_comprehensive_m=e[:, 0].copy())
    assert not np.any(_seg_flags(tb.k_N_per_m, tb.e_m, tb.backlash_half_m, np.full((2, P, N), -1.0), False))
    T1, zeta, w0, x0 = 40e-6 * 1e8 * tb.base_radius_pinion_m, 0.05, 200.0, 10e-6
    me = tb.equivalent_mass_kg
    K, Fm = 2e8, T1 / tb.base_radius_pinion_m
    C = 2 * (2 * zeta * math.sqrt(tb.k_mean_N_per_m * me))
    wn = math.sqrt(K / me)
    H = 2 * math.pi / wn / 8
    n = 200
    r = simulate(tb, max_step_s=0.05 / wn, stop_time_s=n * H, comm_step_s=H, pinion_torque_Nm=T1,
                 pinion_speed_start_rad_s=w0, damping_ratio=zeta, dte_start_m=x0, damping_model="contact_zone",
                 integrator="rk4_seg")
    t = np.arange(n + 1) * H
    xs, g = Fm / K + 1e-6, C / (2 * me)
    wd = math.sqrt(wn ** 2 - g ** 2)
    exact = xs + (x0 - xs) * np.exp(-g * t) * (np.cos(wd * t) + g / wd * np.sin(wd * t))
    periods = (r.pinion_angle[-1] - r.pinion_angle[0]) / tb.phi_period_rad
    assert r.info["events"] <= periods + 1
    err = np.max(np.abs(r.dte - exact)) / np.ptp(exact)
    assert err <= 1e-6, err


def _errors(case, model, divs, integrator="rk4_seg", n=32):
    """Max |dte - dte_ref| / range(dte_ref) over n communication steps H = mesh period / 8 at
    max step H/div, against the event-located DOP853 reference; and each run's result."""
    tb, T1, T2, w0, zeta, x0 = case()
    H = tb.mesh_period_rad / w0 / 8
    ref, segs = reference(tb, T1, T2, zeta, [0.0, w0, x0, 0.0], np.arange(n + 1) * H, model=model)
    assert segs > 50   # the reference restarted at the table nodes and contact changes
    errs, runs = [], []
    for div in divs:
        r = simulate(tb, stop_time_s=n * H, comm_step_s=H, max_step_s=H / div, pinion_torque_Nm=T1,
                     gear_torque_Nm=T2, pinion_speed_start_rad_s=w0, damping_ratio=zeta, dte_start_m=x0,
                     integrator=integrator, damping_model=model)
        errs.append(np.max(np.abs(r.dte - ref[2])) / np.ptp(ref[2]))
        runs.append(r)
    return errs, runs


def test_rk4_seg_stops_at_big_kinks_fourth_order_to_reference():
    """Tent tables (kinks of e at nodes 0, 8, 16 of 32, where c*(de/dphi)*omega1 jumps; second
    differences 1, 0.09 and 1 of the sum of the three |values|, above SEG_KINK_TOL): rk4_seg stops
    at exactly these nodes (events = the 5 kinked nodes crossed) and converges at fourth order to
    the event-located reference; measured 5.3e-6, 3.3e-7, 2.0e-8, 2.0e-9 at H/8 .. H/64, both
    damping laws (without the stops, the rule before SEG_KINK_TOL: 3.5e-6, 1.4e-6 at H/8, H/32).
    Asserted: <= 5e-8 at H/32, <= 5e-9 at H/64 and a fitted order > 3.5 over H/8 .. H/32."""
    tb = tent_case()[0]
    P, N = tb.slots, tb.n_phi
    flags = _seg_flags(tb.k_N_per_m, tb.e_m, tb.backlash_half_m, np.full((2, P, N), -1.0), False)
    assert list(np.flatnonzero(flags)) == [0, 8, 16]
    divs = np.array([8, 16, 32, 64])
    for model in ("contact_zone", "elastobacklash"):
        errs, runs = _errors(tent_case, model, divs)
        assert all(r.info["events"] >= 3 for r in runs)
        assert errs[2] <= 5e-8 and errs[3] <= 5e-9, (model, errs)
        assert order_fit(1.0 / divs[:3], errs[:3]) > 3.5, (model, errs)


def _k_tent_case(amp):
    """tent_case without errors, slot 0's stiffness k = 1e8*(1 + amp*tent) N/m with the tent
    0..1..0 over nodes 0..8..16 (kinks at nodes 0, 8, 16 of relative size about amp/18)."""
    def case():
        tb, T1, T2, w0, zeta, x0 = tent_case()
        P, N = tb.slots, tb.n_phi
        i = np.arange(N) % 32
        k = np.full((1, P, N), 1e8)
        k[0, 0] *= 1.0 + amp * np.where(i <= 8, i / 8.0, np.where(i <= 16, (16 - i) / 8.0, 0.0))
        e = np.zeros_like(tb.e_m)
        return dataclasses.replace(tb, k_N_per_m=k, e_m=e, e_comprehensive_m=e[:, 0].copy()), T1, T2, w0, zeta, x0
    return case


@pytest.mark.slow
def test_rk4_seg_kink_threshold_flags_big_stiffness_kinks_only():
    """Stiffness tents (:func:`_k_tent_case`): amplitude 0.5 bends k at nodes 0, 8, 16 by 0.020,
    0.028, 0.020 of the sum of the three |values| (above SEG_KINK_TOL = 1e-2), amplitude 0.05 by
    0.0021, 0.0040, 0.0021 (below it; rk4_node's NODE_KINK_TOL flags both).  The big tent: stops
    there, fourth order to the event-located reference (measured 3.3e-6, 2.0e-7, 1.2e-8, 6.7e-10
    at H/8 .. H/64); the small tent: no flag, no event, and RK4 over the kinks converges at about
    second order (Hairer, Norsett & Wanner, sec. II.6; measured 5.6e-6, 4.4e-7, 8.7e-8 at H/8,
    H/32, H/128).  Asserted: big <= 5e-8 at H/32, <= 3e-9 at H/64; small <= 1e-6 at H/32,
    <= 3e-7 at H/128 and a tenfold fall from H/8 to H/128."""
    from gearfmu.dynamics.model_rhs import _node_flags

    for amp, want in ((0.5, [0, 8, 16]), (0.05, [])):
        tb = _k_tent_case(amp)()[0]
        P, N = tb.slots, tb.n_phi
        flags = _seg_flags(tb.k_N_per_m, tb.e_m, tb.backlash_half_m, np.full((2, P, N), -1.0), False)
        assert list(np.flatnonzero(flags)) == want, amp
        assert list(np.flatnonzero(_node_flags(tb.k_N_per_m, tb.e_m, tb.backlash_half_m))) == [0, 8, 16]
    for model in ("contact_zone", "elastobacklash"):
        errs, runs = _errors(_k_tent_case(0.5), model, (8, 16, 32, 64))
        assert all(r.info["events"] >= 3 for r in runs)
        assert errs[2] <= 5e-8 and errs[3] <= 3e-9, (model, errs)
        errs, runs = _errors(_k_tent_case(0.05), model, (8, 32, 128))
        assert all(r.info["events"] == 0 for r in runs)
        assert errs[1] <= 1e-6 and errs[2] <= 3e-7, (model, errs)
        assert errs[2] <= errs[0] / 10, (model, errs)


def test_rk4_seg_impacts_and_contact_loss_match_reference():
    """Impact case (teeth separate and hit both flanks): rk4_seg locates every contact change
    like rk4_node and stays stable; against the event-located reference, measured: elastobacklash
    2.7e-7 at H/32 and 7.1e-8 at H/64, contact_zone 2.0e-5 at H/32 and 5.9e-6 at H/64 (its
    damping term changes the force while separated, so more kinked nodes matter).  Asserted:
    <= 1e-6 and <= 3e-7 (elastobacklash), <= 5e-5 and <= 1.5e-5 (contact_zone), separation and
    back-flank contact happened, and fewer events than rk4_node (no table-node stops)."""
    for model, bounds in (("elastobacklash", (1e-6, 3e-7)), ("contact_zone", (5e-5, 1.5e-5))):
        errs, runs = _errors(impact_case, model, (32, 64))
        assert errs[0] <= bounds[0] and errs[1] <= bounds[1], (model, errs)
        f = runs[1].mesh_force
        assert np.all(np.isfinite(f))
        if model == "elastobacklash":
            assert np.sum(f == 0.0) > 3 and np.sum(f < 0.0) > 3
        tb, T1, T2, w0, zeta, x0 = impact_case()
        H = tb.mesh_period_rad / w0 / 8
        rn = simulate(tb, stop_time_s=32 * H, comm_step_s=H, max_step_s=H / 64, pinion_torque_Nm=T1, gear_torque_Nm=T2,
                      pinion_speed_start_rad_s=w0, damping_ratio=zeta, dte_start_m=x0, integrator="rk4_node",
                      damping_model=model)
        assert runs[1].info["events"] < rn.info["events"], (runs[1].info["events"], rn.info["events"])


def test_rk4_seg_stops_where_a_contact_zone_edge_lies_on_a_node():
    """Tables with contact-zone edges (docs/model.md "Contact-zone edges"), one of them on a
    table node (the stiffness steps there): rk4_seg stops at both nodes of every cell with an
    edge, so the step of k is never inside an RK4 step; against rk4_kink at H/512 (rk4_kink
    is checked against the event-located DOP853 in tests/unit/dynamics/test_integrators.py) the error falls
    with order > 3.5: measured 1.0e-3, 6.5e-5, 4.1e-6, 2.9e-7 at H/8 .. H/64, both damping laws
    (without the stops at the edge cells: first order, 5.6e-3 at H/32, and 1.0 of the range
    with contact_zone)."""
    t = dyn_tables(False)
    w0, T1 = 300.0, 50.0
    T2 = T1 * t.base_radius_gear_m / t.base_radius_pinion_m
    H = t.mesh_period_rad / w0 / 8
    divs = np.array([8, 16, 32, 64])
    for model in ("elastobacklash", "contact_zone"):
        kw = dict(stop_time_s=64 * H, comm_step_s=H, pinion_torque_Nm=T1, gear_torque_Nm=T2,
                  pinion_speed_start_rad_s=w0, damping_ratio=0.05, damping_model=model)
        ref = simulate(t, max_step_s=H / 512, integrator="rk4_kink", **kw).dte
        errs = [np.max(np.abs(simulate(t, max_step_s=H / d, integrator="rk4_seg", **kw).dte - ref)) / np.ptp(ref)
                for d in divs]
        assert errs[2] <= 1e-5, (model, errs)
        assert order_fit(H / divs, errs) > 3.5, (model, errs)


def test_rk4_seg_time_indexed_sdof_matches_reference():
    """Time-indexed SDOF (seed 003 eq 3-6, omega1 constant, g_w = 0 and g_v = 1/m_e in the
    shifted velocity) on the impact case: against the event-located reference (sdof form)
    rk4_seg at H/64 is within 1e-7 of the range (measured against rk4_kink at H/400:
    1.5e-6 at H/16, 1.3e-8 at H/64), with fewer events than rk4_node."""
    from gearfmu.dynamics.native import simulate_sdof

    tb, T1, T2, w0, zeta, x0 = impact_case()
    H = tb.mesh_period_rad / w0 / 8
    ref, _ = reference(tb, T1, T2, zeta, [0.0, w0, x0, 0.0], np.arange(33) * H, sdof=True)
    kw = dict(stop_time_s=32 * H, comm_step_s=H, max_step_s=H / 64, pinion_torque_Nm=T1, omega1_rad_s=w0,
              damping_ratio=zeta, dte_start_m=x0)
    r = simulate_sdof(tb, integrator="rk4_seg", **kw)
    err = np.max(np.abs(r.dte - ref[2])) / np.ptp(ref[2])
    assert err <= 1e-7, err
    assert r.info["events"] < simulate_sdof(tb, integrator="rk4_node", **kw).info["events"]
