"""The planetary FMU of a stage with a DRIVEN member (docs/planetary.md "Driven members"), built by
``gearfmu build`` from examples/scenes/planetary_driven_ring.toml (the ring driven through its support
by a speed-controlled drive, the sun on the motor, the carrier on the load), against references its C
code did not produce.

* The native planetary solver (numba, gearfmu/planetary/kernels.py), the same equations in another
  language: fmpy steps the FMU at the native communication step while the drive's speed input
  ``ps.ring_speed_input`` changes every step; the native solver, started from the FMU's initial state
  with the same speed per step, gives every output within 1e-12 of its range (bit for bit).
* Willis' equation (z_s (w_s - w_c) + z_r (w_r - w_c) = 0) for the FMU's initial speeds, and the
  driven ring at exactly the prescribed speed after every step.
* fmpy's validate_fmu: no problems; Co-Simulation and Model Exchange, the input in rad/s starting at
  the scene's speed.
* Model Exchange: fmpy's CVode (rtol 1e-8) with the drive's speed input set to another speed than the
  scene's, then stepping to its opposite halfway, against the native solver with the same speeds over
  0.01 s: within 1e-4 of each output's range (the tolerance of the held stage's Model Exchange test,
  tests/fmu_hosts/test_planetary_fmu.py).
* Bad input: a non-finite speed input discards the step (Co-Simulation) or the evaluation (Model
  Exchange) with a message naming the input and leaves the state unchanged.
"""
import ctypes
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from gearfmu import stages
from gearfmu.fmu.planetary_build import native_run, planetary_settings, variables_of_fmu
from gearfmu.planetary.native import simulate
from gearfmu.scene.drivetrain import load_drivetrain

from support.fmpy_host import quiet, slave, status

pytestmark = pytest.mark.slow

SCENE = Path(__file__).resolve().parents[2] / "examples" / "scenes" / "planetary_driven_ring.toml"
TOL = 1e-12   # of each output's range
INPUT = "ps.ring_speed_input"


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    d = tmp_path_factory.mktemp("drivenfmu")
    fmu = d / "driven.fmu"
    gearfmu_cli = Path(sys.executable).with_name("gearfmu")
    subprocess.run([str(gearfmu_cli), "build", str(SCENE), "-o", str(fmu), "--platforms", "x86_64-linux", "-q"],
                   check=True)
    sc = load_drivetrain(SCENE)
    model = stages.drivetrain_model(sc, stages.stage_tables(sc))
    return {"fmu": fmu, "dir": d, "model": model, "settings": planetary_settings(model, stages.gearbox_run_settings(sc))}


def _states(model):
    out = ["reference_angle", "reference_speed"]
    for nm in model.dof_names[1:]:
        out += [f"{nm}_deviation", f"{nm}_deviation_rate"]
    return out


def test_the_fmu_follows_the_drive_speed_as_the_native_solver(built):
    model, s = built["model"], built["settings"]
    outs = [v.name for v in variables_of_fmu(model, s, interface="cs") if v.causality == "output"]
    assert INPUT in {v.name for v in variables_of_fmu(model, s, interface="cs") if v.causality == "input"}
    H, n = s.output_interval_s, 200
    w_ring = -100.0 * np.pi / 30.0 + 4.0 * np.sin(np.arange(n + 1) * H * 2e3)    # rad/s, a new value every step
    fmu, vr, msgs = slave(built["fmu"], built["dir"], "run")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setReal([vr[INPUT]], [float(w_ring[0])])
    fmu.exitInitializationMode()
    names = outs + _states(model)
    refs = [vr[nm] for nm in names]
    rows = [fmu.getReal(refs)]
    for k in range(n):
        fmu.setReal([vr[INPUT]], [float(w_ring[k])])
        fmu.doStep(k * H, H)
        rows.append(fmu.getReal(refs))
    fmu.terminate()
    fmu.freeInstance()
    got = dict(zip(names, np.array(rows).T))
    y0 = np.array([got[nm][0] for nm in _states(model)])
    zs, _, zr = model.stages[0]["teeth"]
    ws, wc, wr = (got[f"ps.{p}_speed"][0] for p in ("sun", "carrier", "ring"))
    assert wr == w_ring[0]
    assert abs(zs * (ws - wc) + zr * (wr - wc)) <= 1e-12 * zr * abs(ws)    # Willis at the start
    assert np.array_equal(got["ps.ring_drive_speed"][1:], w_ring[:n])      # the drive at the prescribed speed
    nat = simulate(model, s, stop_time_s=n * H, comm_step_s=H, motor_torque_Nm=s.motor_torque_start_Nm,
                   load_torque_Nm=s.load_torque_start_Nm, initial_state=y0, drive_speeds_rad_s={"ps.ring": w_ring})
    worst = {}
    for nm in outs:
        a, b = nat[nm], got[nm]
        rng = max(float(np.ptp(a)), float(np.max(np.abs(a))) * 1e-300, 1e-300)
        worst[nm] = 0.0 if np.array_equal(a, b) else float(np.max(np.abs(a - b))) / rng
    assert max(worst.values()) <= TOL, sorted(worst.items(), key=lambda kv: -kv[1])[:3]
    assert np.ptp(got["ps.ring_support.force"]) > 1.0


def test_a_non_finite_speed_input_discards_the_step(built):
    from fmpy.fmi2 import fmi2Discard
    fmu, vr, msgs = slave(built["fmu"], built["dir"], "bad")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    H = built["settings"].output_interval_s
    fmu.doStep(0.0, H)
    before = fmu.getReal([vr["ps.ring_drive_speed"], vr["ps.sun_speed"]])
    fmu.setReal([vr[INPUT]], [float("nan")])
    assert status(fmu.doStep, H, H) == fmi2Discard
    assert any(INPUT in m and "not finite" in m for _, m in msgs), msgs
    assert fmu.getReal([vr["ps.ring_drive_speed"], vr["ps.sun_speed"]]) == before    # state unchanged
    fmu.setReal([vr[INPUT]], [-5.0])
    fmu.doStep(H, H)
    assert fmu.getReal([vr["ps.ring_drive_speed"]])[0] == -5.0
    fmu.terminate()
    fmu.freeInstance()


def test_the_built_fmu_is_valid_and_offers_both_interfaces(built):
    import fmpy
    import fmpy.validation
    assert fmpy.validation.validate_fmu(str(built["fmu"])) == []
    md = fmpy.read_model_description(str(built["fmu"]))
    assert md.coSimulation is not None and md.modelExchange is not None
    v = {x.name: x for x in md.modelVariables}[INPUT]
    assert v.causality == "input" and v.unit == "rad/s" and float(v.start) == pytest.approx(-100.0 * np.pi / 30.0,
                                                                                          rel=1e-15)


ME_NAMES = ["ps.sun_planet[1].mesh_force", "ps.ring_planet[2].mesh_force", "ps.ring_support.force", "load_speed",
            "ps.carrier_speed"]


def test_model_exchange_in_fmpy_cvode_follows_the_speed_input(built):
    import dataclasses

    import fmpy
    model, s = built["model"], dataclasses.replace(built["settings"], stop_time_s=0.01)
    w = -5.0   # rad/s, not the scene's -100 rpm
    nat = native_run(model, s, drive_speeds_rad_s={"ps.ring": w})
    got = fmpy.simulate_fmu(str(built["fmu"]), fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-8,
                            stop_time=s.stop_time_s, output_interval=s.output_interval_s, start_values={INPUT: w},
                            output=ME_NAMES + ["ps.ring_drive_speed"], record_events=False, logger=quiet)
    n = min(len(got), len(nat.time_s))
    assert n == len(nat.time_s)
    assert np.all(got["ps.ring_drive_speed"] == w)
    errs = {k: float(np.max(np.abs(got[k][:n] - nat[k][:n])) / np.ptp(nat[k][:n])) for k in ME_NAMES}
    print("CVode against native:", errs)
    assert max(errs.values()) <= 1e-4, errs
    # the input stepping from -5 to +5 rad/s halfway (a time event of fmpy's input): the drive follows it
    t_step = 0.5 * s.stop_time_s
    sig = np.array([(0.0, w), (t_step, w), (t_step, -w), (s.stop_time_s, -w)], dtype=[("time", float), (INPUT, float)])
    got = fmpy.simulate_fmu(str(built["fmu"]), fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-8,
                            stop_time=s.stop_time_s, output_interval=s.output_interval_s, start_values={INPUT: w},
                            input=sig, output=ME_NAMES + ["ps.ring_drive_speed"], record_events=False, logger=quiet)
    steps = np.arange(len(nat.time_s)) * s.output_interval_s
    nat = native_run(model, s, drive_speeds_rad_s={"ps.ring": np.where(steps < t_step * (1 - 1e-12), w, -w)})
    assert got["ps.ring_drive_speed"][-1] == -w
    # the row at the step itself: fmpy samples after the event (the new speed in the support's damping), the
    # native row is the end of the step before it (the old speed); every other row compares
    rows = np.flatnonzero(np.abs(steps - t_step) > 0.5 * s.output_interval_s)
    errs = {k: float(np.max(np.abs(got[k][rows] - nat[k][rows])) / np.ptp(nat[k])) for k in ME_NAMES}
    print("CVode against native, input step:", errs)
    assert max(errs.values()) <= 1e-4, errs


def test_a_non_finite_speed_input_stops_a_model_exchange_evaluation(built):
    from fmpy.fmi2 import FMU2Model, fmi2Discard
    import fmpy
    md = fmpy.read_model_description(str(built["fmu"]))
    from support.fmpy_host import callbacks
    msgs = []
    d = fmpy.extract(str(built["fmu"]), unzipdir=str(built["dir"] / "me"))
    fmu = FMU2Model(guid=md.guid, unzipDirectory=d, modelIdentifier=md.modelExchange.modelIdentifier,
                    instanceName="me")
    cb = callbacks(msgs)
    fmu.instantiate(callbacks=cb, loggingOn=True)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.enterContinuousTimeMode()
    nx = md.numberOfContinuousStates
    x, dx = (ctypes.c_double * nx)(), (ctypes.c_double * nx)()
    fmu.getContinuousStates(x, nx)
    before = np.array(x[:])
    fmu.setReal([vr[INPUT]], [float("inf")])
    assert status(fmu.getDerivatives, dx, nx) == fmi2Discard
    assert any(INPUT in m and "not finite" in m for _, m in msgs), msgs
    fmu.getContinuousStates(x, nx)
    assert np.array_equal(np.array(x[:]), before)
    fmu.terminate()
    fmu.freeInstance()
