"""Integrators of the dynamic model: 'rk4', 'rk4_kink' and 'rk4_node', the default
(docs/model.md "Integration", docs/native.md "rk4_node").

References (none produced by gearfmu code):
* scipy.integrate.solve_ivp (DOP853, rtol 1e-10) restarted at every table node
  and every contact-mode change, the events located by scipy's own event
  finder on its dense output; the right-hand side, the per-cell table
  interpolation and the switching functions are written here in plain numpy
  from docs/model.md and seed 003 eq 1-6, and the mode after an event is found
  by a short look-ahead (not by the transition table the kernels use);
* the order of a one-step method: global error C h^p, p read off a
  least-squares fit of log(error) against log(h) (Hairer, Norsett & Wanner,
  Solving ODEs I, sec. II.3); p = 4 for classical RK4 on a smooth right-hand
  side, and RK4 falls to first order when the right-hand side jumps inside
  steps (ibid. sec. II.6, discontinuous equations);
* the C kernel (gearfmu/fmu/kernel/gearkernel.c) through ctypes, a second,
  independent implementation of docs/model.md.
"""
import dataclasses
import math

import numpy as np
import pytest

from gearfmu.fmu.pythonfmu_build import FmuBuildError, build_fmu, compile_kernel
from gearfmu.fmu.runtime.kernel_api import load_kernel
from gearfmu.common.vocabulary import DEFAULT_INTEGRATOR, INTEGRATORS
from gearfmu.dynamics.native import NativeInputError, choose_max_step_s, simulate, simulate_sdof
from gearfmu.tables.synthetic import rectangular_wave_tables

from support.integrator_cases import impact_case, order_fit, reference, run_c, tent_case

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow


# ----------------------------------------------------------------- cases
def hcr_case():
    """High contact ratio eps = 2.4 with five slots (seed 003 section 3), errors,
    backlash, near-zero load and an impact start."""
    tb = rectangular_wave_tables(1.5e8, contact_ratio=2.4, slots=5, backlash_half_m=10e-6,
                                 points_per_mesh=16,
                                 pair_error_m=lambda j, u: 3e-6 * (1 + 0.5 * j) * np.sin(np.pi * u))
    T1, w0, zeta, x0 = 1.0, 300.0, 0.02, 30e-6
    return tb, T1, T1 * tb.base_radius_gear_m / tb.base_radius_pinion_m, w0, zeta, x0


# ----------------------------------------------------------------- tests
def test_convergence_order_rk4_first_rk4_kink_fourth():
    """Impact case over four mesh periods (128 table-node and contact events).
    Error = max over the 33 communication points of |dte - dte_ref| / range(dte_ref).
    Measured: rk4 1.1e-4, 3.0e-5, 1.9e-5, 2.7e-6 at h = H/25..H/200,
    fitted order 1.7 (erratic: the error depends on where nodes fall in a step);
    rk4_kink 3.7e-7, 3.1e-8, 1.2e-9 at H/25..H/100, fitted order 4.1 (1.6e-9 at
    H/200 is the reference's own level, so the fit stops at H/100).
    Asserted: rk4 order < 2.2 and rk4_kink order > 3.5 with every rk4_kink
    error at least 30x below rk4's at the same h."""
    tb, T1, T2, w0, zeta, x0 = impact_case()
    H = tb.mesh_period_rad / w0 / 8
    n = 32
    t_eval = np.arange(n + 1) * H
    ref, segs = reference(tb, T1, T2, zeta, [0.0, w0, x0, 0.0], t_eval)
    assert segs > 100       # the reference really restarted at every event
    rng = np.ptp(ref[2])
    divs = np.array([25, 50, 100, 200])
    errs = {}
    for integ in ("rk4", "rk4_kink"):
        errs[integ] = []
        for div in divs:
            r = simulate(tb, stop_time_s=n * H, comm_step_s=H, max_step_s=H / div, pinion_torque_Nm=T1,
                         gear_torque_Nm=T2, pinion_speed_start_rad_s=w0, damping_ratio=zeta,
                         dte_start_m=x0, integrator=integ)
            errs[integ].append(np.max(np.abs(r.dte - ref[2])) / rng)
    p_rk4 = order_fit(H / divs, errs["rk4"])
    p_kink = order_fit(H / divs[:3], errs["rk4_kink"][:3])   # the last is at the reference's own level
    print("errors", errs, "orders", p_rk4, p_kink)
    assert p_rk4 < 2.2, (p_rk4, errs)
    assert p_kink > 3.5, (p_kink, errs)
    assert all(a > 30 * b for a, b in zip(errs["rk4"], errs["rk4_kink"])), errs
    # the hard case happened: separation and back-flank contact
    assert np.sum(r.mesh_force == 0.0) > 3 and np.sum(r.mesh_force < 0.0) > 3


def test_rk4_kink_matches_reference_on_hcr_five_slots_and_seed003():
    """eps = 2.4 with five slots (elastobacklash) and the impact case under the
    contact_zone damping law: rk4_kink at h = H/50 within 1e-7 of each signal's range
    of the event-located reference (measured: 4e-9 .. 3e-8); all values finite."""
    for case, model in ((hcr_case, "elastobacklash"), (impact_case, "contact_zone")):
        tb, T1, T2, w0, zeta, x0 = case()
        H = tb.mesh_period_rad / w0 / 8
        t_eval = np.arange(17) * H
        ref, _ = reference(tb, T1, T2, zeta, [0.0, w0, x0, 0.0], t_eval, model=model)
        r = simulate(tb, stop_time_s=16 * H, comm_step_s=H, max_step_s=H / 50, pinion_torque_Nm=T1,
                     gear_torque_Nm=T2, pinion_speed_start_rad_s=w0, damping_ratio=zeta, dte_start_m=x0,
                     integrator="rk4_kink", damping_model=model)
        ours = np.vstack([r.pinion_angle, r.pinion_speed, r.dte, r.dte_rate])
        assert np.all(np.isfinite(ours))
        for q in range(4):
            err = np.max(np.abs(ours[q] - ref[q])) / np.ptp(ref[q])
            assert err < 1e-7, (case.__name__, model, q, err)


def test_sdof_rk4_kink_fourth_order_vs_reference():
    """Time-indexed SDOF (seed 003 eq 3-6, constant omega1) on the impact case:
    rk4_kink error vs the event-located reference falls with order > 3.5
    (measured 3.7e-6, 1.9e-7, 1.7e-8 at h = H/12, H/25, H/50: order 3.9) and is
    at least 100x below rk4's at H/50 (measured 1.5e-5; at these coarse steps
    rk4's smooth-part error still dominates its node errors)."""
    tb, T1, T2, w0, zeta, x0 = impact_case()
    H = tb.mesh_period_rad / w0 / 8
    t_eval = np.arange(25) * H
    ref, _ = reference(tb, T1, T2, zeta, [0.0, w0, x0, 0.0], t_eval, sdof=True)
    rng = np.ptp(ref[2])
    divs = np.array([12, 25, 50])
    out = {}
    for integ in ("rk4", "rk4_kink"):
        out[integ] = []
        for div in divs:
            r = simulate_sdof(tb, omega1_rad_s=w0, stop_time_s=24 * H, comm_step_s=H, max_step_s=H / div,
                              pinion_torque_Nm=T1, damping_ratio=zeta, dte_start_m=x0, integrator=integ)
            out[integ].append(np.max(np.abs(r.dte - ref[2])) / rng)
    print(out)
    assert order_fit(H / divs, out["rk4_kink"]) > 3.5, out
    assert out["rk4"][-1] > 100 * out["rk4_kink"][-1], out


# ------------------------------------------------------------ C kernel
@pytest.fixture(scope="module")
def clib(tmp_path_factory):
    return load_kernel(compile_kernel(tmp_path_factory.mktemp("kernel")))


@pytest.mark.parametrize("case", [impact_case, hcr_case])
@pytest.mark.parametrize("model", ["elastobacklash", "contact_zone"])
@pytest.mark.parametrize("div", [2, 40])
@pytest.mark.parametrize("integrator", ["rk4_kink", "rk4_node", "rk4_seg"])
def test_native_and_c_kernel_agree_rk4_kink(clib, case, model, div, integrator):
    """Same tables, inputs and steps: numba and C rk4_kink (and rk4_node, rk4_seg) agree to <= 1e-9
    of each signal's range over 48 communication steps (measured: bit for bit)."""
    tb, T1, T2, w0, zeta, x0 = case()
    H = tb.mesh_period_rad / w0 / 8
    r = simulate(tb, stop_time_s=48 * H, comm_step_s=H, max_step_s=H / div, pinion_torque_Nm=T1,
                 gear_torque_Nm=T2, pinion_speed_start_rad_s=w0, damping_ratio=zeta, dte_start_m=x0,
                 integrator=integrator, damping_model=model)
    c, fc = run_c(clib, tb, T1, T2, w0, zeta, {"elastobacklash": 0, "contact_zone": 1}[model], x0, H, 48, H / div,
              {"rk4_kink": 1, "rk4_node": 2, "rk4_seg": 3}[integrator])
    nat = np.vstack([r.pinion_angle, r.pinion_speed, r.dte, r.dte_rate])
    assert r.info["events"] > (10 if integrator == "rk4_seg" else 48)   # rk4_seg: no table-node stops
    for q in range(4):
        assert np.max(np.abs(nat[q] - c[q])) <= 1e-9 * np.ptp(nat[q]), q
    assert np.max(np.abs(r.mesh_force[1:] - fc[1:])) <= 1e-9 * np.ptp(r.mesh_force)


def torque_axis_case():
    """The HCR case with a torque axis: a second row at 3x the torque with
    1.3x the stiffness and 0.7x the errors, T1 between the rows."""
    tb, T1, T2, w0, zeta, x0 = hcr_case()
    tb = dataclasses.replace(tb, torque_Nm=np.array([0.5, 1.5]),
                             k_N_per_m=np.concatenate([tb.k_N_per_m, 1.3 * tb.k_N_per_m]),
                             e_m=np.concatenate([tb.e_m, 0.7 * tb.e_m]),
                             e_comprehensive_m=np.concatenate([tb.e_comprehensive_m, 0.7 * tb.e_comprehensive_m]),
                             static_te_m=None)
    return tb, T1, T2, w0, zeta, x0


def backward_case():
    """The impact case turning backwards: negative angles, cells crossed downwards."""
    tb, T1, T2, w0, zeta, x0 = impact_case()
    return tb, -T1, -T2, -w0, zeta, -x0


def backward_tent_case():
    """tent_case turning backwards: segments between flagged nodes crossed downwards."""
    tb, T1, T2, w0, zeta, x0 = tent_case()
    return tb, -T1, -T2, -w0, zeta, -x0


@pytest.mark.parametrize("case", [impact_case, torque_axis_case, backward_case, tent_case, backward_tent_case])
@pytest.mark.parametrize("integrator", ["rk4", "rk4_kink", "rk4_node", "rk4_seg"])
def test_native_and_c_kernel_agree_bit_for_bit(clib, case, integrator):
    """docs/model.md pins every floating-point operation (table lookup with the
    reciprocal cell width, force law, RK4 and rk4_kink arithmetic), so the two
    independent implementations must give identical doubles: every state and the
    mesh force after each of 96 communication steps over two or more table periods.
    On the tent tables rk4_node runs segments between flagged nodes (fewer events
    than rk4_kink's node crossings), so the node flags of both agree too (the
    sine errors of the other cases bend the tables at every node)."""
    tb, T1, T2, w0, zeta, x0 = case()
    H = tb.mesh_period_rad / abs(w0) / 8
    code = {"rk4": 0, "rk4_kink": 1, "rk4_node": 2, "rk4_seg": 3}[integrator]
    r = simulate(tb, stop_time_s=96 * H, comm_step_s=H, max_step_s=H / 7, pinion_torque_Nm=T1,
                 gear_torque_Nm=T2, pinion_speed_start_rad_s=w0, damping_ratio=zeta, dte_start_m=x0,
                 integrator=integrator)
    c, fc = run_c(clib, tb, T1, T2, w0, zeta, 0, x0, H, 96, H / 7, code)
    nat = np.vstack([r.pinion_angle, r.pinion_speed, r.dte, r.dte_rate])
    assert abs(nat[0, -1] - nat[0, 0]) > 2 * tb.phi_period_rad
    if integrator == "rk4_node" and case in (tent_case, backward_tent_case):
        rk = simulate(tb, stop_time_s=96 * H, comm_step_s=H, max_step_s=H / 7, pinion_torque_Nm=T1,
                      gear_torque_Nm=T2, pinion_speed_start_rad_s=w0, damping_ratio=zeta, dte_start_m=x0,
                      integrator="rk4_kink")
        assert r.info["events"] < 0.5 * rk.info["events"]
    assert np.array_equal(nat, c)
    assert np.array_equal(r.mesh_force[1:], fc[1:])


def test_c_kernel_rejects_unknown_integrator(clib):
    tb = impact_case()[0]
    k, e, b = tb.k_N_per_m, tb.e_m, tb.backlash_half_m
    tq = np.array([0.0])
    m = np.zeros(clib.gk_sizeof_model() // 8 + 2)
    assert clib.gk_init(m.ctypes.data, tb.slots, tb.n_phi, 1, tq.ctypes.data, k.ctypes.data, e.ctypes.data,
                        b.ctypes.data, tb.phi_period_rad, 0.07, 0.07, 0.0074, 0.0074, 1e8) == 0
    assert clib.gk_set_integrator(m.ctypes.data, 4) == 6      # GK_ERR_PARAM
    assert clib.gk_set_integrator(m.ctypes.data, -1) == 6
    assert clib.gk_set_integrator(m.ctypes.data, 1) == 0


@pytest.mark.parametrize("runtime", ["pythonfmu", "standalone"])
@pytest.mark.parametrize("integrator", ["rk4_kink", "rk4_node", "rk4_seg"])
def test_fmu_with_rk4_kink_agrees_with_native(tmp_path, integrator, runtime):
    """FMU (pythonfmu and standalone runtimes) built with integrator='rk4_kink', 'rk4_node' or
    'rk4_seg' (FMU parameter integrator = 1, 2, 3), run by
    fmpy with communication steps of a quarter mesh period: every output within
    1e-9 of its range of the native run with the same integrator (the FMU starts from the
    quasi-static equilibrium, so the native run does too)."""
    from fmpy import simulate_fmu
    tb, T1, T2, w0, zeta, _ = hcr_case()
    T1, T2 = 20.0, 20.0 * tb.base_radius_gear_m / tb.base_radius_pinion_m
    H = tb.mesh_period_rad / w0 / 4
    hmax = H / 7
    from gearfmu.fmu.standalone_build import build_standalone_fmu
    builder = build_fmu if runtime == "pythonfmu" else build_standalone_fmu
    path = builder(tb, tmp_path / "kink.fmu", damping_ratio=zeta, pinion_speed_start_rad_s=w0,
                     pinion_torque_start_Nm=T1, gear_torque_start_Nm=T2, max_step_s=hmax,
                     integrator=integrator, stop_time_s=40 * H, output_interval_s=H)
    res = simulate_fmu(str(path), stop_time=40 * H, output_interval=H,
                       output=["dte", "pinion_speed", "mesh_force", "pinion_angle"])
    r = simulate(tb, stop_time_s=40 * H, comm_step_s=H, max_step_s=hmax, pinion_torque_Nm=T1,
                 gear_torque_Nm=T2, pinion_speed_start_rad_s=w0, damping_ratio=zeta, integrator=integrator)
    assert r.info["events"] > (10 if integrator == "rk4_seg" else 40)   # rk4_seg: no table-node stops
    for name in ("dte", "pinion_speed", "mesh_force", "pinion_angle"):
        ours = getattr(r, name)
        assert len(res[name]) == len(ours)
        assert np.max(np.abs(res[name] - ours)) <= 1e-9 * np.ptp(ours), name


def test_bad_integrator_names_the_field(tmp_path):
    tb = impact_case()[0]
    with pytest.raises(NativeInputError, match="integrator"):
        simulate(tb, stop_time_s=1e-3, comm_step_s=1e-3, pinion_torque_Nm=1.0, pinion_speed_start_rad_s=10.0,
                 damping_ratio=0.02, integrator="euler")
    with pytest.raises(NativeInputError, match="integrator"):
        simulate_sdof(tb, omega1_rad_s=10.0, stop_time_s=1e-3, comm_step_s=1e-3, pinion_torque_Nm=1.0,
                      damping_ratio=0.02, integrator="rk45")
    with pytest.raises(FmuBuildError, match="integrator"):
        build_fmu(tb, tmp_path / "x.fmu", integrator="dopri")
    assert not (tmp_path / "x.fmu").exists()


# ------------------------------------------------- hard cases and the default
#: hard case (gearfmu.bench.HARD_CASES) -> tolerance on the max relative error of dte and
#: mesh force of rk4_kink at 64 substeps per communication step (H = mesh period/4), about
#: 3x the error measured against gearfmu.dynamics.reference (event-located DOP853,
#: rtol 1e-10, closed-form checks in tests/unit/dynamics/test_reference.py).  tests/unit/dynamics/test_hard_cases.py
#: holds rk4 to 3e-5 .. 1.2e-3 at 1024 substeps on the same cases.
KINK_HARD = {
    "heavy_load": 3e-7,               # measured 7.2e-8 / 6.6e-8 (dte / force)
    "single_sided_impacts": 4e-7,     # measured 8.2e-8 / 1.1e-7
    "double_sided_impacts": 3e-6,     # measured 5.5e-7 / 7.2e-7
    "low_damping_resonance": 4e-7,    # measured 6.4e-8 / 1.0e-7
    "high_contact_ratio": 2e-7,       # measured 2.7e-8 / 4.7e-8
    "omega_h_2": 2e-7,                # measured 2.5e-8 / 4.5e-8
    "torque_steps": 5e-5,             # measured 1.4e-5 / 1.6e-5 (340 -> 60 -> 900 N m)
    "computed_default_scene": 6e-7,   # measured 1.2e-7 / 1.7e-7
}


@pytest.mark.parametrize("name", sorted(KINK_HARD))
def test_hard_cases_against_reference_rk4_node_and_rk4_kink(name):
    """The hard cases with the default integrator rk4_node and with rk4_kink against the
    event-located reference: at 64 substeps per communication step both within the
    tolerance above.  At the automatic step (choose_max_step_s at the start speed, what
    max_step_s = "auto" gives) rk4_node's RMS dte and mesh-force errors are at most 2x
    rk4_kink's (measured: up to 1.8x on the rectangular-wave tables, whose linear pieces
    it crosses without a stop; equal to 1 % on the computed default scene, whose tables
    bend at every node) with at most rk4_kink's events (1 % on the computed tables, where
    every node is an event of both); every output finite."""
    from gearfmu.bench import hard_case, rel_errors
    from gearfmu.dynamics.reference import simulate_reference

    tables, kw = hard_case(name)
    ref = simulate_reference(tables, **kw)
    H = kw["comm_step_s"]
    h_auto = choose_max_step_s(tables, abs(kw["pinion_speed_start_rad_s"]))
    for h in (H / 64, h_auto):
        err, events = {}, {}
        for integ in ("rk4_node", "rk4_kink"):
            r = simulate(tables, max_step_s=h, integrator=integ, **kw)
            for a in (r.dte, r.mesh_force, r.pair_force, r.pinion_speed):
                assert np.all(np.isfinite(a))
            err[integ], events[integ] = rel_errors(r, ref), r.info["events"]
            assert events[integ] > 0
            if h == H / 64:
                e = err[integ]
                assert e["dte_rel_max_err"] < KINK_HARD[name] and e["force_rel_max_err"] < KINK_HARD[name], (integ, e)
        if h == h_auto:
            for key in ("dte_rel_rms_err", "force_rel_rms_err"):
                assert err["rk4_node"][key] <= 2.0 * err["rk4_kink"][key], (key, err)
            assert events["rk4_node"] <= 1.01 * events["rk4_kink"], events


@pytest.mark.parametrize("name", ["single_sided_impacts", "computed_default_scene"])
def test_rk4_node_matches_event_located_dop853_like_rk4_kink(name):
    """rk4_node (flagged table nodes reached by one RK4 step to the predicted crossing
    time) against an outside reference: scipy solve_ivp DOP853 with event location at
    rtol 1e-12 (gearfmu.dynamics.reference).  At 64 substeps per communication step
    the dte and mesh-force errors are within rk4_kink's bound (KINK_HARD).  The
    computed default scene's tables bend at every node, so nothing is skipped there:
    at 8 and 64 substeps the RMS errors are within a factor 1.1 of rk4_kink's
    (measured: equal to 1 %) with the event count within 1 %.  The impact case's
    rectangular-wave tables are linear across most nodes: fewer than half of
    rk4_kink's events, RMS errors within 1.2x of rk4_kink's at 64 substeps (measured
    1.08x; at 8 substeps the longer steps cost accuracy, measured 7x).  The states
    differ from rk4_kink's, so the prediction really ran."""
    from gearfmu.bench import hard_case, rel_errors
    from gearfmu.dynamics.reference import simulate_reference

    tables, kw = hard_case(name)
    ref = simulate_reference(tables, rtol=1e-12, steps_per_period=128, **kw)
    H = kw["comm_step_s"]
    for n in (8, 64):
        rn = simulate(tables, max_step_s=H / n, integrator="rk4_node", **kw)
        rk = simulate(tables, max_step_s=H / n, integrator="rk4_kink", **kw)
        en, ek = rel_errors(rn, ref), rel_errors(rk, ref)
        assert np.all(np.isfinite(rn.dte)) and np.all(np.isfinite(rn.mesh_force))
        assert not np.array_equal(rn.dte, rk.dte)
        if name == "computed_default_scene":
            assert abs(rn.info["events"] - rk.info["events"]) <= 0.01 * rk.info["events"]
            for key in ("dte_rel_rms_err", "force_rel_rms_err"):
                assert ek[key] / 1.1 <= en[key] <= 1.1 * ek[key], (n, key, en, ek)
        else:
            assert rn.info["events"] < 0.5 * rk.info["events"]
            if n == 64:
                for key in ("dte_rel_rms_err", "force_rel_rms_err"):
                    assert en[key] <= 1.2 * ek[key], (n, key, en, ek)
        if n == 64:
            assert en["dte_rel_max_err"] < KINK_HARD[name] and en["force_rel_max_err"] < KINK_HARD[name], en


def test_default_integrator_is_rk4_node_everywhere(tmp_path):
    """The default is rk4_node, the same in the native solver, the scene, both FMU builders
    and the FMU parameter start value of an FMU built with defaults (docs/native.md
    "Integrators" justifies it); a scene may still choose 'rk4_kink' or 'rk4'.  The solvers and
    the builders take the run settings' default (the builders' ``integrator`` None: RunSettings'; the
    solvers take it as one of their settings keywords, absent: RunSettings')."""
    import xml.etree.ElementTree as ET
    import zipfile

    from gearfmu.common.settings import RunSettings
    from gearfmu.dynamics import native
    from gearfmu.scene.reader import default_scene_path, load_scene
    from gearfmu.fmu.standalone_build import build_standalone_fmu

    assert DEFAULT_INTEGRATOR == native.DEFAULT_INTEGRATOR == RunSettings().integrator == "rk4_node"
    tb0 = hcr_case()[0]
    run = dict(stop_time_s=1e-3, comm_step_s=1e-4, pinion_torque_Nm=1.0, damping_ratio=0.02)
    assert simulate(tb0, pinion_speed_start_rad_s=10.0, **run).info["integrator"] == "rk4_node"
    assert simulate_sdof(tb0, omega1_rad_s=10.0, **run).info["integrator"] == "rk4_node"
    assert load_scene(None).solver.integrator == "rk4_node"
    text = default_scene_path().read_text(encoding="utf-8")
    assert 'integrator = "rk4_node"' in text
    assert load_scene(text.replace('integrator = "rk4_node"', 'integrator = "rk4_kink"')).solver.integrator == "rk4_kink"
    tb = hcr_case()[0]
    # both builders, given no integrator, build FMUs whose integrator parameter starts at rk4_node
    from gearfmu.fmu.crossbuild import host_key
    for path in (build_fmu(tb, tmp_path / "d.fmu"),
                 build_standalone_fmu(tb, tmp_path / "s.fmu", platforms=(host_key(),), validation=False)):
        with zipfile.ZipFile(path) as z:
            root = ET.fromstring(z.read("modelDescription.xml"))
        var = [v for v in root.iter("ScalarVariable") if v.get("name") == "integrator"]
        assert len(var) == 1 and var[0].find("Integer").get("start") == str(INTEGRATORS["rk4_node"]), path


def test_fmu_default_long_communication_steps_match_native_default(tmp_path):
    """Hard case 8 with the default integrator: an FMU built with defaults (rk4_node),
    run by fmpy with communication steps of 1/4, 1, 5 and 10 mesh periods, gives the
    native answer of the default integrator with the same internal steps to 1e-9 of each range
    (measured <= 7.3e-13: the mode is rebuilt from the state at every communication
    step in both; fmpy's step sizes differ from H in the last bits), and meets the
    reference to 5e-7 (measured 9.3e-8) at h = Tm/256."""
    from gearfmu.bench import hard_case
    from gearfmu.fmu.compare import output_names, run_fmu
    from gearfmu.dynamics.reference import simulate_reference

    tables, kw = hard_case("single_sided_impacts")
    Tm = 4 * kw["comm_step_s"]
    hmax = Tm / 256
    kw = dict(kw, pinion_angle_start_rad=0.0, stop_time_s=20 * Tm)
    fmu = build_fmu(tables, tmp_path / "k.fmu", model_name="k", damping_ratio=kw["damping_ratio"],
                    pinion_speed_start_rad_s=kw["pinion_speed_start_rad_s"],
                    pinion_torque_start_Nm=kw["pinion_torque_Nm"], max_step_s=hmax,
                    stop_time_s=kw["stop_time_s"], output_interval_s=Tm)
    ref = simulate_reference(tables, **kw)
    for m in (0.25, 1, 5, 10):
        H = m * Tm
        run = run_fmu(fmu, stop_time_s=kw["stop_time_s"], comm_step_s=H, names=output_names(tables.slots))
        nat = simulate(tables, **dict(kw, comm_step_s=H, max_step_s=hmax))
        assert nat.info["integrator"] == DEFAULT_INTEGRATOR and nat.info["events"] > 0
        for name in ("dte", "mesh_force", "pinion_speed"):
            a, b = run.columns[name], getattr(nat, name)
            assert len(a) == len(b) and np.all(np.isfinite(a))
            assert np.max(np.abs(a - b)) <= 1e-9 * np.ptp(b), (m, name)
        stride = int(round(H / kw["comm_step_s"]))
        d = np.abs(run.columns["dte"] - ref.dte[::stride])
        assert d.max() / np.ptp(ref.dte) < 5e-7, (m, d.max() / np.ptp(ref.dte))


def test_rk4_node_skips_nodes_of_a_linear_table_closed_form():
    """Tables constant across every node (both slots k = 1e8 N/m, no error, no
    backlash, contact_zone): no node is flagged, rk4_node crosses nodes only at the
    artificial segment end one table period ahead (events <= periods crossed + 1,
    while rk4_kink stops at every node), and its dte equals the closed form of
    m_e x'' + 2c x' + k x = F_m (two pairs, each c*(v - 0); damped oscillator,
    x(0) = x0, x'(0) = 0) to 1e-6 of the range (RK4 at omega_n h = 0.05: phase error
    omega_n t (omega_n h)^4/120 = 6.5e-7 over the two periods in which the transient lives)."""
    from gearfmu.dynamics.model_rhs import _node_flags

    tb = tent_case()[0]
    P, N = tb.slots, tb.n_phi
    tb = dataclasses.replace(tb, e_m=np.zeros((1, P, N)), e_comprehensive_m=np.zeros((1, N)))
    assert not np.any(_node_flags(tb.k_N_per_m, tb.e_m, tb.backlash_half_m))
    T1, zeta, w0, x0 = 40e-6 * 1e8 * tb.base_radius_pinion_m, 0.05, 200.0, 10e-6
    me = tb.equivalent_mass_kg
    K, Fm = 2e8, T1 / tb.base_radius_pinion_m
    C = 2 * (2 * zeta * math.sqrt(tb.k_mean_N_per_m * me))
    wn = math.sqrt(K / me)
    H = 2 * math.pi / wn / 8
    h = 0.05 / wn
    n = 200
    kw = dict(stop_time_s=n * H, comm_step_s=H, pinion_torque_Nm=T1, pinion_speed_start_rad_s=w0,
              damping_ratio=zeta, dte_start_m=x0, damping_model="contact_zone")
    r = simulate(tb, max_step_s=h, integrator="rk4_node", **kw)
    rk = simulate(tb, max_step_s=h, integrator="rk4_kink", **kw)
    t = np.arange(n + 1) * H
    xs, g = Fm / K, C / (2 * me)
    wd = math.sqrt(wn ** 2 - g ** 2)
    exact = xs + (x0 - xs) * np.exp(-g * t) * (np.cos(wd * t) + g / wd * np.sin(wd * t))
    periods = (r.pinion_angle[-1] - r.pinion_angle[0]) / tb.phi_period_rad
    assert rk.info["events"] > 10 * (periods + 1)
    assert r.info["events"] <= periods + 1
    assert np.max(np.abs(r.dte - exact)) <= 1e-6 * np.ptp(exact), np.max(np.abs(r.dte - exact)) / np.ptp(exact)


def test_rk4_node_keeps_the_event_at_a_kinked_node():
    """Tables linear between nodes 0, 8, 16 (mod 32) and bent there (tent_case): exactly
    those nodes are flagged, rk4_node stops at each flagged node it crosses and nowhere
    else (events = flagged crossings), and its dte meets the event-located DOP853
    reference of this module (rtol 1e-10) to 2e-5 of the range at 8 substeps per
    communication step (measured 5e-6, as rk4_kink with every node).  Classical RK4
    at the same steps, which crosses the kinks inside steps (what a wrongly cleared
    flag would do), misses it by more than 1e-3 (measured 2.3e-3)."""
    from gearfmu.dynamics.model_rhs import _node_flags

    tb, T1, T2, w0, zeta, x0 = tent_case()
    assert list(np.flatnonzero(_node_flags(tb.k_N_per_m, tb.e_m, tb.backlash_half_m))) == [0, 8, 16]
    H = tb.mesh_period_rad / w0 / 8
    n = 96
    ref, _ = reference(tb, T1, T2, zeta, [0.0, w0, x0, 0.0], np.arange(n + 1) * H, model="contact_zone")
    err = {}
    for integ in ("rk4", "rk4_node"):
        r = simulate(tb, stop_time_s=n * H, comm_step_s=H, max_step_s=H / 8, pinion_torque_Nm=T1,
                     gear_torque_Nm=T2, pinion_speed_start_rad_s=w0, damping_ratio=zeta, dte_start_m=x0,
                     integrator=integ, damping_model="contact_zone")
        err[integ] = np.max(np.abs(r.dte - ref[2])) / np.ptp(ref[2])
        if integ == "rk4_node":
            dphi = tb.phi_period_rad / tb.n_phi
            cells = np.floor(r.pinion_angle / dphi)
            crossed = [m for m in range(int(cells[0]) + 1, int(cells[-1]) + 1) if m % 32 in (0, 8, 16)]
            assert np.all(np.diff(r.pinion_angle) > 0)
            assert r.info["events"] == len(crossed)
    assert err["rk4_node"] <= 2e-5, err
    assert err["rk4"] > 1e-3, err
