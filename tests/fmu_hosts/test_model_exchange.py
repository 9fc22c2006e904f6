"""Model Exchange of the standalone FMU (docs/standalone.md "Model Exchange", docs/model.md "Model
Exchange"): a host's own solver integrates the gear pair.

References (none produced by the FMU's code): the event-located scipy solution of the same equations
(gearfmu.dynamics.reference, DOP853 at 128 steps per natural period), which two independent Model
Exchange hosts must reproduce: fmpy's CVode (SUNDIALS, BDF) and PathSim's adaptive Dormand-Prince
(pathsim-fmi, its own zero-crossing detection); FMPy's validator for the model descriptions; the FMI
2.0 / 3.0 tables of allowed calls for the refusals.
"""
import ctypes
import zipfile

import fmpy
import numpy as np
import pytest
from fmpy.fmi2 import FMU2Model
from fmpy.fmi3 import FMU3Model
from fmpy.validation import validate_fmu

from gearfmu.bench import hard_case
from gearfmu.dynamics.reference import simulate_reference
from gearfmu.fmu.standalone_build import build_standalone_fmu
from gearfmu.stages import gear_torque_for
from support.fmpy_host import callbacks, keep_fmpy_logger_alive, quiet, status

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

CASES = ("computed_default_scene", "double_sided_impacts")


def _case(name):
    tables, kw = hard_case(name)
    T1 = float(kw["pinion_torque_Nm"])
    kw = dict(kw, gear_torque_Nm=gear_torque_for(tables, T1))
    return tables, kw


def _build(tables, kw, path, **extra):
    return build_standalone_fmu(tables, path, pinion_speed_start_rad_s=kw["pinion_speed_start_rad_s"],
                                pinion_torque_start_Nm=kw["pinion_torque_Nm"], gear_torque_start_Nm=kw["gear_torque_Nm"],
                                damping_ratio=kw["damping_ratio"], damping_model=kw.get("damping_model", "elastobacklash"),
                                pinion_angle_start_rad=kw.get("pinion_angle_start_rad", 0.0), max_step_s=4e-6,
                                stop_time_s=kw["stop_time_s"], output_interval_s=kw["comm_step_s"],
                                platforms=["x86_64-linux"], validation=False, **extra)


@pytest.fixture(scope="module")
def cases(tmp_path_factory):
    d = tmp_path_factory.mktemp("me")
    out = {}
    for name in CASES:
        tables, kw = _case(name)
        ref = simulate_reference(tables, rtol=1e-11, steps_per_period=128.0, **kw)
        out[name] = dict(tables=tables, kw=kw, ref=ref,
                         fmu2=_build(tables, kw, d / f"{name}_2.fmu"),
                         fmu3=_build(tables, kw, d / f"{name}_3.fmu", fmi_version=3))
    out["dir"] = d
    return out


def _rel_max(x, ref):
    return float(np.max(np.abs(np.asarray(x)[:len(ref)] - ref)) / np.ptp(ref))


def _fmpy_me(path, kw, rtol):
    res = fmpy.simulate_fmu(str(path), fmi_type="ModelExchange", solver="CVode", relative_tolerance=rtol,
                            stop_time=kw["stop_time_s"], output_interval=kw["comm_step_s"],
                            output=["dte", "mesh_force"], record_events=False, logger=quiet)
    return res


@pytest.mark.parametrize("name", CASES)
@pytest.mark.parametrize("v", [2, 3])
def test_fmpy_cvode_reproduces_the_reference(cases, name, v):
    """fmpy's CVode on the FMU's own equations converges to the event-located reference: at rtol 1e-8
    within 1e-4 of the range over 10 (default scene) and 30 (impacts on both flanks) mesh periods, and
    the error falls with the tolerance (measured: benchmarks/bench_me.py)."""
    c = cases[name]
    fine = _fmpy_me(c[f"fmu{v}"], c["kw"], 1e-8)
    coarse = _fmpy_me(c[f"fmu{v}"], c["kw"], 1e-5)
    ref = c["ref"]
    e_fine = max(_rel_max(fine["dte"], ref.dte), _rel_max(fine["mesh_force"], ref.mesh_force))
    e_coarse = max(_rel_max(coarse["dte"], ref.dte), _rel_max(coarse["mesh_force"], ref.mesh_force))
    assert e_fine < 1e-4, (name, e_fine)
    assert e_fine < e_coarse / 10.0, (e_fine, e_coarse)


def test_pathsim_host_reproduces_the_reference(cases):
    """A second Model Exchange host from the package index: PathSim (pathsim-fmi) integrates the FMU
    with its own adaptive Dormand-Prince 5(4) and its own zero-crossing location of the event
    indicators; sampled at the communication instants it reproduces the reference within 1e-4 on the
    case with contact loss and impacts on both flanks.  (Not run on the default scene: there
    pathsim-fmi 0.1.1 stalls in the location of a contact event, because its zero-crossing events read
    the indicators of the state the FMU was last given, which after a rejected step is that step's,
    not the state at the time they are buffered for.)"""
    name = "double_sided_impacts"
    from pathsim import Connection, Simulation
    from pathsim.blocks import Constant, Scope
    from pathsim.solvers import RKDP54
    from pathsim_fmi import ModelExchangeFMU

    c = cases[name]
    kw = c["kw"]
    keep_fmpy_logger_alive()
    fmu = ModelExchangeFMU(str(c["fmu2"]), instance_name="gear", tolerance=1e-13)
    t1, t2 = Constant(kw["pinion_torque_Nm"]), Constant(kw["gear_torque_Nm"])
    scope = Scope(sampling_period=kw["comm_step_s"])
    sim = Simulation([t1, t2, fmu, scope],
                     [Connection(t1, fmu["pinion_torque"]), Connection(t2, fmu["gear_torque"]),
                      Connection(fmu["dte"], scope[0]), Connection(fmu["mesh_force"], scope[1])],
                     dt=kw["comm_step_s"] / 50, Solver=RKDP54, tolerance_lte_rel=1e-9, tolerance_lte_abs=1e-15,
                     log=False)
    sim.run(kw["stop_time_s"])
    t, (dte, force) = scope.read()
    ref = c["ref"]
    n = min(len(t), len(ref.time_s))
    assert np.allclose(t[:n], ref.time_s[:n], rtol=0, atol=1e-12)
    assert n >= len(ref.time_s) - 1
    assert _rel_max(dte[:n], ref.dte[:n]) < 1e-4
    assert _rel_max(force[:n], ref.mesh_force[:n]) < 1e-4


# --------------------------------------------------------------------- the linear limit
#: one slot of constant stiffness, no error, no backlash, the contact_zone force law (F = k x + c v): the
#: pair is a linear two-inertia system (the stage-1 data of tests/unit/gearbox/test_gearbox_modes.py)
LIN = dict(k=4.0e8, rb1=0.0270, rb2=0.0270 * 67 / 23, i1=2.0e-4, i2=1.2e-2, zeta=0.05, T1=150.0, T2=900.0, w0=300.0)


def linear_reference(times):
    """The matrix exponential of the first-order system of M = diag(I1, I2), K = k r r^T, C = c r r^T on
    the absolute angles (r = [Rb1, -Rb2], c = 2 zeta sqrt(k m_e), m_e = I1 I2/(I1 Rb2^2 + I2 Rb1^2)), assembled
    here, from the quasi-static state under T1 (x = T1/(Rb1 k), both gears at w0 on the kinematic ratio)
    with the gear torque T2 against it (not in equilibrium: a torque step at t = 0).  Rows: dte, mesh force,
    pinion speed."""
    import math

    import scipy.linalg

    L = LIN
    r = np.array([L["rb1"], -L["rb2"]])
    me = L["i1"] * L["i2"] / (L["i1"] * L["rb2"] ** 2 + L["i2"] * L["rb1"] ** 2)
    c = 2 * L["zeta"] * math.sqrt(L["k"] * me)
    Mi = np.diag([1 / L["i1"], 1 / L["i2"]])
    A = np.zeros((5, 5))
    A[:2, 2:4] = np.eye(2)
    A[2:4, :2] = -Mi @ (L["k"] * np.outer(r, r))
    A[2:4, 2:4] = -Mi @ (c * np.outer(r, r))
    A[2:4, 4] = Mi @ np.array([L["T1"], -L["T2"]])
    x0 = L["T1"] / (L["rb1"] * L["k"])
    z0 = np.array([0.0, -x0 / L["rb2"], L["w0"], L["w0"] * L["rb1"] / L["rb2"], 1.0])
    Z = np.array([scipy.linalg.expm(A * t) @ z0 for t in times])
    x, v = Z[:, :2] @ r, Z[:, 2:4] @ r
    return x, L["k"] * x + c * v, Z[:, 2]


@pytest.fixture(scope="module")
def linear_fmus(tmp_path_factory):
    from gearfmu.tables.synthetic import tables_from_arrays

    L = LIN
    t = tables_from_arrays(k_N_per_m=np.full((1, 16), L["k"]), base_radius_pinion_m=L["rb1"],
                           base_radius_gear_m=L["rb2"], inertia_pinion_kgm2=L["i1"], inertia_gear_kgm2=L["i2"],
                           teeth_pinion=23, teeth_gear=67)
    kw = dict(pinion_speed_start_rad_s=L["w0"], pinion_torque_Nm=L["T1"], gear_torque_Nm=L["T2"],
              damping_ratio=L["zeta"], damping_model="contact_zone", stop_time_s=3e-3, comm_step_s=1e-5)
    d = tmp_path_factory.mktemp("me_linear")
    return kw, {v: _build(t, kw, d / f"linear_{v}.fmu", fmi_version=v, interface="me") for v in (2, 3)}


@pytest.mark.parametrize("v", [2, 3])
def test_linear_limit_against_matrix_exponential_fmpy_cvode(linear_fmus, v):
    """The linear limit (about 20 periods of the mesh's natural frequency, 6.6 kHz) under fmpy's CVode at
    rtol 1e-10: the DTE, the mesh force and the pinion speed within 1e-6 of their range of the matrix
    exponential (linear_reference); the initial state is the quasi-static one (x = T1/(Rb1 k), 1e-9)."""
    kw, fmus = linear_fmus
    res = fmpy.simulate_fmu(str(fmus[v]), fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-10,
                            stop_time=kw["stop_time_s"], output_interval=kw["comm_step_s"],
                            output=["dte", "mesh_force", "pinion_speed"], record_events=False, logger=quiet)
    x, F, w = linear_reference(res["time"])
    assert abs(res["dte"][0] - x[0]) <= 1e-9 * x[0]
    for got, ref in ((res["dte"], x), (res["mesh_force"], F), (res["pinion_speed"], w)):
        assert np.max(np.abs(got - ref)) <= 1e-6 * np.ptp(ref), np.max(np.abs(got - ref)) / np.ptp(ref)


def test_linear_limit_against_matrix_exponential_pathsim(linear_fmus):
    """The same linear limit in the second host, PathSim's adaptive Dormand-Prince 5(4), within 1e-6."""
    from pathsim import Connection, Simulation
    from pathsim.blocks import Constant, Scope
    from pathsim.solvers import RKDP54
    from pathsim_fmi import ModelExchangeFMU

    kw, fmus = linear_fmus
    keep_fmpy_logger_alive()
    fmu = ModelExchangeFMU(str(fmus[2]), instance_name="linear", tolerance=1e-13)
    t1, t2 = Constant(kw["pinion_torque_Nm"]), Constant(kw["gear_torque_Nm"])
    scope = Scope(sampling_period=kw["comm_step_s"])
    sim = Simulation([t1, t2, fmu, scope],
                     [Connection(t1, fmu["pinion_torque"]), Connection(t2, fmu["gear_torque"]),
                      Connection(fmu["dte"], scope[0]), Connection(fmu["mesh_force"], scope[1])],
                     dt=kw["comm_step_s"] / 20, Solver=RKDP54, tolerance_lte_rel=1e-10, tolerance_lte_abs=1e-16,
                     log=False)
    sim.run(kw["stop_time_s"])
    t, (dte, force) = scope.read()
    x, F, _ = linear_reference(t)
    assert len(t) >= round(kw["stop_time_s"] / kw["comm_step_s"])
    assert np.max(np.abs(dte - x)) <= 1e-6 * np.ptp(x), np.max(np.abs(dte - x)) / np.ptp(x)
    assert np.max(np.abs(force - F)) <= 1e-6 * np.ptp(F), np.max(np.abs(force - F)) / np.ptp(F)


@pytest.mark.parametrize("v", [2, 3])
def test_model_descriptions_validate_and_declare_model_exchange(cases, tmp_path, v):
    """fmpy's validator finds nothing in the CS+ME (default), the ME-only and the CS-only FMU; the
    state derivatives are in the order of the state vector and the event indicators number 3 per
    pair, 1 per pair with contact-zone edges and 2 with node events (the default: the big kinks)."""
    c = cases["computed_default_scene"]
    both = c[f"fmu{v}"]
    me = _build(c["tables"], c["kw"], tmp_path / "me.fmu", fmi_version=v, interface="me", me_node_events="none")
    cs = _build(c["tables"], c["kw"], tmp_path / "cs.fmu", fmi_version=v, interface="cs")
    for path in (both, me, cs):
        assert validate_fmu(str(path)) == [], path
    P = c["tables"].slots
    md = fmpy.read_model_description(str(both))
    assert md.modelExchange is not None and md.coSimulation is not None
    assert [d.variable.name for d in md.derivatives] == ["der(pinion_angle)", "der(pinion_speed)", "der(dte)",
                                                       "der(dte_rate)"]
    assert [d.variable.derivative.name for d in md.derivatives] == ["pinion_angle", "pinion_speed", "dte", "dte_rate"]
    assert md.numberOfEventIndicators == 4 * P + 2   # the default scene's tables carry contact-zone edges
    mdm = fmpy.read_model_description(str(me))
    assert mdm.coSimulation is None and mdm.numberOfEventIndicators == 4 * P
    mdc = fmpy.read_model_description(str(cs))
    assert mdc.modelExchange is None and mdc.numberOfEventIndicators == 0 and not mdc.derivatives
    cfg = zipfile.ZipFile(me).read("resources/gearfmu_standalone.txt").decode()
    assert "interfaces=me\n" in cfg and "me.node_events=0\n" in cfg


def _model(path, tmp, name="m"):
    md = fmpy.read_model_description(str(path))
    d = fmpy.extract(str(path), str(tmp / name))
    return md, FMU2Model(guid=md.guid, unzipDirectory=d, modelIdentifier=md.modelExchange.modelIdentifier,
                         instanceName=name)


def _vr(md, name):
    return next(v.valueReference for v in md.modelVariables if v.name == name)


def test_call_order_inputs_and_fmu_state(cases, tmp_path):
    """The FMI 2.0 table of allowed calls for Model Exchange (section 3.2.3): states set only in
    continuous-time mode, a tunable parameter only in event mode; a NaN input makes the derivatives
    fmi2Discard with a message naming it; the FMU state restores the mode too (the continuation is
    the same bit for bit); the indicators are >= 0 after every event."""
    c = cases["double_sided_impacts"]
    md, m = _model(c["fmu2"], tmp_path)
    msgs = []
    m._test_callbacks = callbacks(msgs)
    m.instantiate(callbacks=m._test_callbacks, loggingOn=True)
    n, nz = md.numberOfContinuousStates, md.numberOfEventIndicators
    x = (ctypes.c_double * n)()
    dx = (ctypes.c_double * n)()
    z = (ctypes.c_double * nz)()
    m.setupExperiment(startTime=0.0)
    m.enterInitializationMode()
    m.getContinuousStates(x, n)
    x0 = np.array(x)
    m.exitInitializationMode()
    # event mode: states cannot be set, a tunable parameter can
    assert status(m.setContinuousStates, x, n) == 3
    assert "not allowed in state eventMode" in msgs[-1][1]
    m.setReal([_vr(md, "damping_ratio")], [c["kw"]["damping_ratio"]])
    m.newDiscreteStates()
    m.enterContinuousTimeMode()
    assert status(m.setReal, [_vr(md, "damping_ratio")], [0.1]) == 3
    assert "event mode, not in continuous-time mode" in msgs[-1][1]
    m.getContinuousStates(x, n)
    assert np.array_equal(x0, np.array(x))
    m.getEventIndicators(z, nz)
    assert min(z) >= 0.0
    # a plain explicit Euler run through contact changes, with event handling at sign changes
    h = 1e-7
    states = []
    t = 0.0
    for k in range(3000):
        m.getDerivatives(dx, n)
        for i in range(n):
            x[i] += h * dx[i]
        t += h
        m.setTime(t)
        m.setContinuousStates(x, n)
        z_prev = list(z)
        m.getEventIndicators(z, nz)
        if any(a * b <= 0 and a != b for a, b in zip(z_prev, z)) or min(z) < 0:
            m.enterEventMode()
            m.newDiscreteStates()
            m.enterContinuousTimeMode()
            m.getEventIndicators(z, nz)
            assert min(z) > -1e-12, list(z)
        m.completedIntegratorStep()
        if k == 1000:
            saved = m.getFMUstate()
            x_saved, t_saved = list(x), t
        if k > 1000:
            states.append(list(x))
    # restore and continue: the same states bit for bit
    m.setFMUstate(saved)
    x[:] = x_saved
    t = t_saved
    again = []
    for k in range(1001, 3000):
        m.getDerivatives(dx, n)
        for i in range(n):
            x[i] += h * dx[i]
        t += h
        m.setTime(t)
        m.setContinuousStates(x, n)
        z_prev = list(z)
        m.getEventIndicators(z, nz)
        if any(a * b <= 0 and a != b for a, b in zip(z_prev, z)) or min(z) < 0:
            m.enterEventMode()
            m.newDiscreteStates()
            m.enterContinuousTimeMode()
            m.getEventIndicators(z, nz)
        m.completedIntegratorStep()
        again.append(list(x))
    assert np.array_equal(np.array(states), np.array(again))
    # a NaN input: fmi2Discard, the message names it
    m.setReal([_vr(md, "pinion_torque")], [float("nan")])
    assert status(m.getDerivatives, dx, n) == 2
    assert "pinion_torque = nan" in msgs[-1][1] and "not evaluated" in msgs[-1][1]
    m.terminate()
    m.freeInstance()


def test_refusals(cases, tmp_path):
    """An FMU without Model Exchange (--interface cs) refuses to instantiate for it, one without
    Co-Simulation refuses that, each with a message naming the interface."""
    c = cases["double_sided_impacts"]
    cs = _build(c["tables"], c["kw"], tmp_path / "cs.fmu", interface="cs")
    me = _build(c["tables"], c["kw"], tmp_path / "me.fmu", interface="me")
    for path, typ, want in ((cs, 0, "offers Co-Simulation only"), (me, 1, "offers Model Exchange only")):
        md = fmpy.read_model_description(str(path))
        d = fmpy.extract(str(path), str(tmp_path / f"x{typ}"))
        lib = ctypes.CDLL(str(next((tmp_path / f"x{typ}" / "binaries" / "linux64").glob("*.so"))))
        msgs = []
        cb = callbacks(msgs)
        lib.fmi2Instantiate.restype = ctypes.c_void_p
        lib.fmi2Instantiate.argtypes = [ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_char_p,
                                        ctypes.c_void_p, ctypes.c_int, ctypes.c_int]
        uri = (tmp_path / f"x{typ}" / "resources").as_uri().encode()
        inst = lib.fmi2Instantiate(b"x", typ, md.guid.encode(), uri, ctypes.addressof(cb), 0, 1)
        assert inst is None
        assert any(want in m for _, m in msgs), msgs
        assert d


def test_fmi3_counts_and_states(cases, tmp_path):
    """FMI 3: the counts of states and event indicators, the initial states in initialization mode
    equal the ones after it, and the derivatives match the FMI 2 FMU's at the same state."""
    c = cases["computed_default_scene"]
    md = fmpy.read_model_description(str(c["fmu3"]))
    d = fmpy.extract(str(c["fmu3"]), str(tmp_path / "m3"))
    m = FMU3Model(guid=md.guid, unzipDirectory=d, modelIdentifier=md.modelExchange.modelIdentifier, instanceName="m3")
    m.instantiate()
    m.enterInitializationMode(startTime=0.0)
    x_init = (ctypes.c_double * 4)()
    m.getContinuousStates(x_init, 4)
    m.exitInitializationMode()
    m.updateDiscreteStates()
    m.enterContinuousTimeMode()
    assert m.getNumberOfContinuousStates() == 4
    assert m.getNumberOfEventIndicators() == md.numberOfEventIndicators == 4 * c["tables"].slots + 2
    x = (ctypes.c_double * 4)()
    m.getContinuousStates(x, 4)
    assert np.array_equal(np.array(x_init), np.array(x))
    dx3 = (ctypes.c_double * 4)()
    m.getContinuousStateDerivatives(dx3, 4)
    dx3 = np.array(dx3)
    md2, m2 = _model(c["fmu2"], tmp_path, "m2")
    m2.instantiate()
    m2.setupExperiment(startTime=0.0)
    m2.enterInitializationMode()
    m2.exitInitializationMode()
    m2.newDiscreteStates()
    m2.enterContinuousTimeMode()
    buf = (ctypes.c_double * 4)()
    m2.getDerivatives(buf, 4)
    assert np.array_equal(dx3, np.array(buf))
    m.terminate()
    m.freeInstance()
    m2.terminate()
    m2.freeInstance()
