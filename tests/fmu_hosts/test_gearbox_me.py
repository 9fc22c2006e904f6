"""The gearbox FMU as FMI 2 and FMI 3 Model Exchange (gearfmu build DRIVETRAIN.toml --interface me|both):
fmpy's CVode integrates the FMU's own equations (its states, derivatives and event indicators).

References (none produced by the gearbox code under test):
* the linear limit (constant mesh stiffness, no error, no backlash, contact_zone: F = k x + c v): the
  matrix exponential of the first-order system with M, K, C assembled element by element in
  tests/test_gearbox_modes.py and tests/test_gearbox_native.py, from the FMU's static start state under
  the motor torque against a load torque that does not balance it, to 1e-6 of the range;
* a nonlinear case, ``contact_loss`` of gearfmu.gearbox.cases (stage 1 loses contact and impacts while
  stage 2 carries load): the native gearbox solver (rk4_node at 1/64 of the output interval), to 1e-4
  of the range (measured with CVode at rtol 1e-10: 4.8e-5 stage 1 mesh force, 2.8e-5 stage 1 DTE,
  6e-6 stage 2; the linear limit 6e-9);
* the same linear limit in PathSim (pathsim-fmi), a second Model Exchange host;
* fmpy's validation of the model description; the FMU state (get/set and serialized) restores the
  continuous states and every mesh's held contact mode.
"""
import ctypes
import subprocess
import sys
from pathlib import Path

import fmpy
import fmpy.validation
import numpy as np
import pytest

pytestmark = pytest.mark.slow  # builds or long runs: the full suite, not the quick subset
import scipy.linalg
from fmpy.fmi2 import FMU2Model
from fmpy.fmi3 import FMU3Model

from gearfmu.fmu.gearbox_build import build_gearbox_fmu, gearbox_settings
from gearfmu.gearbox.cases import gearbox_case
from gearfmu.gearbox.native import simulate

from support.fmpy_host import keep_fmpy_logger_alive
from support.gearbox_cases import K_MID, S1, S2, c_mesh, hand_damping, hand_damping_of_mid, hand_matrices, linear_gearbox

HOST = ["x86_64-linux"]
QUANTITIES = ("dte", "mesh_force")


def quiet(*args):
    """fmpy's logger for runs whose messages are not under test."""


def _build(model, settings, path, v, interface="both", node_events=None):
    return build_gearbox_fmu(model, path, settings=settings, model_name=path.stem, platforms=HOST, validation=False,
                             fmi_version=v, model_exchange={"interface": interface, "me_node_events": node_events})


@pytest.fixture(scope="module")
def contact_loss(tmp_path_factory):
    d = tmp_path_factory.mktemp("gbme")
    model, kw = gearbox_case("contact_loss", 30)
    T_in = float(kw["motor_torque_Nm"])
    s = gearbox_settings(model, motor_torque_start_Nm=T_in, motor_speed_start_rad_s=kw["motor_speed_start_rad_s"],
                         motor_angle_start_rad=kw["motor_angle_start_rad"], stop_time_s=kw["stop_time_s"],
                         output_interval_s=kw["comm_step_s"])
    y0 = model.static_state(T_in, kw["motor_speed_start_rad_s"], kw["motor_angle_start_rad"])
    nat = simulate(model, stop_time_s=kw["stop_time_s"], comm_step_s=kw["comm_step_s"], motor_torque_Nm=T_in,
                   load_torque_Nm=s.load_torque_start_Nm, motor_speed_start_rad_s=kw["motor_speed_start_rad_s"],
                   initial_state=y0, max_step_s=kw["comm_step_s"] / 64, integrator="rk4_node")
    return dict(model=model, kw=kw, settings=s, native=nat, y0=y0,
                fmu={v: _build(model, s, d / f"contact_loss_{v}.fmu", v) for v in (2, 3)})


@pytest.mark.parametrize("v", [2, 3])
def test_model_description_valid_and_model_exchange_declared(contact_loss, v):
    """fmpy validates the model description; it offers both interfaces, 2 n continuous states (n = 6
    bodies) whose derivatives are der(<state>), and the event indicators of both stages."""
    path = contact_loss["fmu"][v]
    assert fmpy.validation.validate_fmu(str(path)) == []
    md = fmpy.read_model_description(str(path))
    assert md.modelExchange is not None and md.coSimulation is not None
    model = contact_loss["model"]
    assert len(md.derivatives) == 2 * model.n_bodies
    assert all(d.variable.name == f"der({d.variable.derivative.name})" for d in md.derivatives)
    n_ind = sum(3 * m.tables.slots + 2 for m in model.meshes)   # contact guards, default node events "kinks"
    assert md.numberOfEventIndicators == n_ind


@pytest.mark.parametrize("v", [2, 3])
def test_fmpy_cvode_contact_loss_against_the_native_gearbox_solver(contact_loss, v):
    """Stage 1 loses contact and impacts while stage 2 carries load: fmpy's CVode (rtol 1e-10) on the
    Model Exchange FMU and the native gearbox solver agree on both stages' DTE and mesh force to 1e-4 of
    the range."""
    c = contact_loss
    kw, nat = c["kw"], c["native"]
    names = [f"{m.name}.{q}" for m in c["model"].meshes for q in QUANTITIES]
    res = fmpy.simulate_fmu(str(c["fmu"][v]), fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-10,
                            stop_time=kw["stop_time_s"], output_interval=kw["comm_step_s"], output=names,
                            record_events=False, logger=quiet)
    t = np.asarray(nat.time_s)
    worst = {n: float(np.max(np.abs(np.interp(t, res["time"], res[n]) - np.asarray(nat[n]))) / np.ptp(nat[n]))
             for n in names}
    print(f"FMI {v} ME, CVode 1e-10 against native:", worst)
    assert max(worst.values()) <= 1e-4, worst


LIN_H, LIN_N = 1e-4, 200
LIN_NAMES = ["s1.dte", "s2.dte", "s1.mesh_force", "intermediate_shaft.torque", "load_speed"]


@pytest.fixture(scope="module")
def linear(tmp_path_factory):
    """The linear gearbox's Model Exchange FMUs (FMI 2, 3) started at the static state under 250 N*m at
    300 rad/s against a 1000 N*m load (not the balancing torque: the drivetrain decelerates and rings),
    and the matrix exponential of M, K, C assembled by hand from that state: the references of
    LIN_NAMES at t = k*LIN_H."""
    d = tmp_path_factory.mktemp("gbme_linear")
    model = linear_gearbox()
    s = gearbox_settings(model, motor_torque_start_Nm=250.0, load_torque_start_Nm=1000.0,
                         motor_speed_start_rad_s=300.0, motor_angle_start_rad=0.0, stop_time_s=LIN_N * LIN_H,
                         output_interval_s=LIN_H)
    fmus = {v: _build(model, s, d / f"linear_{v}.fmu", v, interface="me", node_events="none") for v in (2, 3)}
    M, K = hand_matrices()
    C = hand_damping()
    order = [model.part_body[p] for p in ("motor", "s1.pinion", "s1.gear", "s2.pinion", "s2.gear", "load")]
    y0 = model.static_state(250.0, 300.0)
    u = np.concatenate([[0.0], y0[2::2]])[order]
    du = np.concatenate([[0.0], y0[3::2]])[order]
    th0, w0 = model.g[order] * y0[0] + u, model.g[order] * y0[1] + du
    f = np.zeros(6)
    f[0], f[5] = 250.0, -1000.0
    A = np.zeros((13, 13))
    Mi = np.linalg.inv(M)
    A[:6, 6:12] = np.eye(6)
    A[6:12, :6] = -Mi @ K
    A[6:12, 6:12] = -Mi @ C
    A[6:12, 12] = Mi @ f
    times = np.arange(LIN_N + 1) * LIN_H
    Z = np.array([scipy.linalg.expm(A * t) @ np.concatenate([th0, w0, [1.0]]) for t in times])
    x1 = S1["rb1"] * Z[:, 1] - S1["rb2"] * Z[:, 2]
    x2 = S2["rb1"] * Z[:, 3] - S2["rb2"] * Z[:, 4]
    refs = {"s1.dte": x1, "s2.dte": x2,
            "s1.mesh_force": S1["k"] * x1 + c_mesh(S1) * (S1["rb1"] * Z[:, 7] - S1["rb2"] * Z[:, 8]),
            "intermediate_shaft.torque": K_MID * (Z[:, 2] - Z[:, 3]) + hand_damping_of_mid(Z),
            "load_speed": Z[:, 11]}
    return fmus, times, refs


@pytest.mark.parametrize("v", [2, 3])
def test_linear_limit_against_the_matrix_exponential(linear, v):
    """fmpy's CVode (rtol 1e-11) on the linear gearbox's Model Exchange FMU reproduces the matrix
    exponential to 1e-6 of the range (both stages' DTE, the stage-1 mesh force, the intermediate
    shaft's torque, the load speed)."""
    fmus, times, refs = linear
    res = fmpy.simulate_fmu(str(fmus[v]), fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-11,
                            stop_time=times[-1], output_interval=LIN_H, output=LIN_NAMES, record_events=False,
                            logger=quiet)
    worst = {k: float(np.max(np.abs(np.interp(times, res["time"], res[k]) - ref)) / np.ptp(ref))
             for k, ref in refs.items()}
    print(f"FMI {v} ME linear limit, CVode 1e-11 against expm:", worst)
    assert max(worst.values()) <= 1e-6, worst


def test_linear_limit_in_pathsim(linear):
    """The same linear limit in a second Model Exchange host from the package index: PathSim
    (pathsim-fmi) with its own adaptive Dormand-Prince 5(4), the torques from two Constant blocks,
    sampled at the output instants, within 1e-6 of the range of the matrix exponential (measured 8e-11)."""
    from pathsim import Connection, Simulation
    from pathsim.blocks import Constant, Scope
    from pathsim.solvers import RKDP54
    from pathsim_fmi import ModelExchangeFMU

    fmus, times, refs = linear
    keep_fmpy_logger_alive()
    fmu = ModelExchangeFMU(str(fmus[2]), instance_name="gearbox", tolerance=1e-13)
    motor, load = Constant(250.0), Constant(1000.0)
    scope = Scope(sampling_period=LIN_H)
    sim = Simulation([motor, load, fmu, scope],
                     [Connection(motor, fmu["motor_torque"]), Connection(load, fmu["load_torque"])]
                     + [Connection(fmu[n], scope[i]) for i, n in enumerate(LIN_NAMES)],
                     dt=LIN_H / 20, Solver=RKDP54, tolerance_lte_rel=1e-10, tolerance_lte_abs=1e-16, log=False)
    sim.run(times[-1])
    t, ys = scope.read()
    assert len(t) == len(times) and np.allclose(t, times, rtol=0, atol=1e-12)
    worst = {n: float(np.max(np.abs(y - refs[n])) / np.ptp(refs[n])) for n, y in zip(LIN_NAMES, ys)}
    print("PathSim linear limit against expm:", worst)
    assert max(worst.values()) <= 1e-6, worst


def _me_instance(path, v):
    md = fmpy.read_model_description(str(path))
    d = fmpy.extract(str(path), unzipdir=str(path.parent / f"{path.stem}_unzipped"))   # removed with tmp_path
    cls = FMU3Model if v == 3 else FMU2Model
    m = cls(guid=md.guid, unzipDirectory=d, modelIdentifier=md.modelExchange.modelIdentifier, instanceName="m")
    m.instantiate()
    if v == 3:
        m.enterInitializationMode(startTime=0.0)
        m.exitInitializationMode()
        m.updateDiscreteStates()
    else:
        m.setupExperiment(startTime=0.0)
        m.enterInitializationMode()
        m.exitInitializationMode()
        m.newDiscreteStates()
    m.enterContinuousTimeMode()
    return m, md


def _event_update(m, v):
    m.enterEventMode()
    if v == 3:
        m.updateDiscreteStates()
    else:
        m.newDiscreteStates()
    m.enterContinuousTimeMode()


@pytest.mark.parametrize("v", [2, 3])
def test_fmu_state_restores_states_and_contact_modes(contact_loss, v):
    """Get, serialize and set the FMU state of a Model Exchange instance: after the states were moved to
    where stage 1 has lost contact and the modes were decided anew there, the restored state gives the
    derivatives and event indicators of the saved one bit for bit (the held modes are in the state), and
    the same explicit steps from it give the same states."""
    m, md = _me_instance(contact_loss["fmu"][v], v)
    nx, nz = len(md.derivatives), md.numberOfEventIndicators
    ptr = ctypes.POINTER(ctypes.c_double)

    def call(fn, n):
        a = np.zeros(n)
        fn(a.ctypes.data_as(ptr), n)
        return a

    def states():
        return call(m.getContinuousStates, nx)

    def set_states(x):
        x = np.ascontiguousarray(x, dtype=float)
        m.setContinuousStates(x.ctypes.data_as(ptr), nx)

    def der():
        return call(m.getContinuousStateDerivatives if v == 3 else m.getDerivatives, nx)

    def indicators():
        return call(m.getEventIndicators, nz)

    def euler(k, h=2e-8):
        t = m_time[0]
        for _ in range(k):
            x = states()
            t += h
            m.setTime(t)
            set_states(x + h * der())
            m.completedIntegratorStep()
        m_time[0] = t
        return states()

    m_time = [0.0]
    euler(200)
    t_saved = m_time[0]
    saved_x = states()
    saved_der, saved_z = der(), indicators()
    state = m.getFMUState()
    blob = m.serializeFMUState(state)
    x_then = euler(100)
    # stage 1 separated: its gear body moved ahead by far more than the backlash, modes decided there
    far = saved_x.copy()
    far[4] += 1e-2
    set_states(far)
    _event_update(m, v)
    set_states(saved_x)
    assert not np.array_equal(der(), saved_der)   # the modes of the far state differ at the saved one
    for restore in (lambda: m.setFMUState(state), lambda: m.setFMUState(m.deserializeFMUState(blob))):
        restore()
        m_time[0] = t_saved
        assert np.array_equal(states(), saved_x)
        assert np.array_equal(der(), saved_der)
        assert np.array_equal(indicators(), saved_z)
        assert np.array_equal(euler(100), x_then)
    m.freeFMUState(state)
    m.terminate()
    m.freeInstance()


def test_cli_builds_the_example_gearbox_as_model_exchange(tmp_path):
    """gearfmu build DRIVETRAIN.toml --interface me --fmi-version 3 builds the example two-stage reducer
    as an FMI 3.0 Model Exchange FMU (no Co-Simulation) that fmpy validates and its CVode runs;
    --me-node-events without Model Exchange is refused in one line with status 2."""
    repo = Path(__file__).resolve().parents[2]
    example = repo / "examples" / "scenes" / "gearbox_two_stage.toml"
    out = tmp_path / "gb_me.fmu"

    def gearfmu(*args):
        return subprocess.run([sys.executable, "-m", "gearfmu.cli", "build", str(example), *args], capture_output=True,
                              text=True, timeout=900, cwd=repo)

    p = gearfmu("-o", str(out), "--interface", "me", "--fmi-version", "3", "--platforms", "x86_64-linux", "-q")
    assert p.returncode == 0, p.stderr
    assert "Model Exchange" in p.stdout
    assert fmpy.validation.validate_fmu(str(out)) == []
    md = fmpy.read_model_description(str(out))
    assert md.modelExchange is not None and md.coSimulation is None
    res = fmpy.simulate_fmu(str(out), fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-8,
                            stop_time=2e-3, output_interval=1e-5, output=["stage1.dte", "stage2.dte"],
                            record_events=False, logger=quiet)
    assert np.all(np.isfinite(res["stage1.dte"])) and np.all(np.isfinite(res["stage2.dte"]))
    p = gearfmu("-o", str(tmp_path / "x.fmu"), "--interface", "cs", "--me-node-events", "all")
    assert p.returncode == 2 and "--me-node-events all: only with Model Exchange" in p.stderr
    assert len(p.stderr.strip().splitlines()) == 1, p.stderr


def test_c_fuzz_of_the_model_exchange_gearbox_fmu(contact_loss):
    """tests/fmi_fuzz.c's random call sequences (a quarter of them on a Model Exchange instance) on the
    gearbox FMU that offers both interfaces: no host crash, every refusal logged, out-of-order calls
    refused as such.  The fuzzer's state vectors have the gearbox's own state count (from the model
    description), so its Model Exchange calls reach the gearbox's derivatives, indicators and event
    updates with near-start, nasty and wrongly counted states."""
    import fuzz_fmu

    res = fuzz_fmu.run_c_fuzz(contact_loss["fmu"][2], 400, first_seed=20261207, batch=200, jobs=2)
    assert res["sequences"] == 400 and res["host_crashes"] == 0, res["crashes"]
    assert res["unlogged_refusals"] == 0, res["unlogged_examples"]
    assert res["bad_status"] == 0 and res["fatals"] == 0
    assert res["sequences_breaking_order"] == res["sequences"] - res["instantiate_refused"]
