"""The two FMU runtimes refuse the same bad inputs with the same words.

The pythonfmu slave (gearfmu/fmu/runtime/gearfmu_slave.py) and the standalone C runtime
(gearfmu/fmu/standalone/gear_model.c) both call the kernel's FMU layer
(gearfmu/fmu/kernel/gkfmu.c) for their parameter and input checks, the damping and
temperature they apply and the communication step.  Reference: the policy of docs/fmu.md
("Bad input"): a bad parameter -> no initial state (fmi2Error at fmi2ExitInitializationMode), a
bad input or step size -> fmi2Discard with the state unchanged, a torque outside the torque axis
-> one warning.  Each case below drives one instance of each runtime through the same calls and
compares the statuses and the messages of that layer (status and text) one for one; a check or a
message changed in one runtime only makes them differ.
"""
from __future__ import annotations

import fmpy
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
import pytest

from gearfmu.fmu.pythonfmu_build import build_fmu
from gearfmu.fmu.standalone_build import build_standalone_fmu
from gearfmu.tables.mesh_tables import stack_temperatures

from factories import make_tables
from support.fmpy_host import callbacks

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

H = 1e-4
AXIS = (10.0, 30.0, 70.0)
NAN, INF = float("nan"), float("inf")


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    """P = 2, torque axis [50, 150] N.m, a temperature axis 10..70 degC; both runtimes."""
    d = tmp_path_factory.mktemp("shared_checks")
    slices = []
    for f in (0.8, 1.0, 0.9):
        t = make_tables(torque=(50.0, 150.0))
        t.k_N_per_m[:] *= f
        slices.append(t)
    tt = stack_temperatures(slices, AXIS, temperature_reference_C=30.0)
    kw = dict(max_step_s=1e-5, pinion_torque_start_Nm=100.0, pinion_speed_start_rad_s=100.0,
              stop_time_s=20 * H, output_interval_s=H)
    return {"pythonfmu": build_fmu(tt, d / "py.fmu", model_name="chkPy", **kw),
            "standalone": build_standalone_fmu(tt, d / "sa.fmu", model_name="chkSa", validation=False,
                                               platforms=["x86_64-linux"], **kw)}


def _set(fmu, vr, values):
    for name, x in values.items():
        if name in ("damping_model", "integrator"):   # the Integer parameters
            fmu.setInteger([vr[name]], [int(x)])
        else:
            fmu.setReal([vr[name]], [float(x)])


def _call(fn, *args):
    """The status of an FMI call (fmpy raises above warning)."""
    try:
        fn(*args)
        return 0
    except FMICallException as exc:
        return exc.status


def run_case(path, name, at_init, at_step, step_size=H):
    """Instantiate, set ``at_init`` in initialization mode, exit, one step, set ``at_step``, one step
    of ``step_size``, stopping at the first call refused; return the statuses and every message
    with a status other than fmi2OK [(status, text)]: those of the kernel's FMU layer and of the
    FMI layer the two runtimes share (docs/fmu.md "The binary")."""
    md = fmpy.read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    log = []
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=fmpy.extract(str(path)),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
    fmu.instantiate(callbacks=callbacks(log), loggingOn=True)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    _set(fmu, vr, at_init)
    statuses = [_call(fmu.exitInitializationMode)]
    if statuses[-1] < 2:
        statuses.append(_call(fmu.doStep, 0.0, H))
    if statuses[-1] < 2:
        _set(fmu, vr, at_step)
        statuses.append(_call(fmu.doStep, H, step_size))
    _call(fmu.terminate)  # refused in the error state
    fmu.freeInstance()
    return statuses, [(st, m) for st, m in log if st > 0]


CASES = {
    "pinion_torque NaN at init": ({"pinion_torque": NAN}, {}),
    "max_step zero": ({"max_step": 0.0}, {}),
    "temperature outside the axis at init": ({"bulk_temperature": 80.0}, {}),
    "torques not finite": ({}, {"pinion_torque": INF, "gear_torque": NAN}),
    "temperature outside the axis": ({}, {"bulk_temperature": 75.0}),
    "temperature NaN": ({}, {"bulk_temperature": NAN}),
    "torque beyond the axis": ({}, {"pinion_torque": 400.0, "gear_torque": 400.0}),
}
#: parameters outside the min/max of the model description: the standalone runtime discards them when
#: set (FMI 2.0.5 section 2.2.7; tests/fmu_hosts/test_fmu_strict.py), so its kernel layer never sees them
PARAMETER_RANGE_CASES = {
    "damping_ratio below min": ({"damping_ratio": -0.5}, {}),
    "damping_model 3": ({"damping_model": 3}, {}),
    "integrator 4": ({"integrator": 4}, {}),
    "damping_ratio negative in a step": ({}, {"damping_ratio": -1.0}),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_both_runtimes_refuse_bad_input_with_the_same_message(fmus, case):
    at_init, at_step = CASES[case]
    (st_py, msg_py), (st_sa, msg_sa) = (run_case(fmus[k], k, at_init, at_step) for k in ("pythonfmu", "standalone"))
    assert msg_py == msg_sa
    assert msg_py, "the case gives no message"
    assert st_py == st_sa
    if at_init:  # refused without an initial state at fmi2ExitInitializationMode (fmi2Error)
        assert st_sa == [3]
        assert {st for st, _ in msg_py} == {3}


@pytest.mark.parametrize("runtime", ["standalone", "pythonfmu"])
@pytest.mark.parametrize("case", sorted(PARAMETER_RANGE_CASES))
def test_both_runtimes_discard_a_parameter_outside_its_range_when_set(fmus, case, runtime):
    """FMI 2.0.5 sec. 2.2.7: a value outside min/max is refused when it is set (fmi2Discard; the
    FMU keeps the old value) -- the same check of the shared FMI layer in both runtimes."""
    at_init, at_step = PARAMETER_RANGE_CASES[case]
    md = fmpy.read_model_description(str(fmus[runtime]))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    log = []
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=fmpy.extract(str(fmus[runtime])),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="sa")
    fmu.instantiate(callbacks=callbacks(log), loggingOn=True)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    values = at_init or at_step
    if not at_init:
        fmu.exitInitializationMode()
    name, x = next(iter(values.items()))
    setter = fmu.setInteger if name in ("damping_model", "integrator") else fmu.setReal
    assert _call(setter, [vr[name]], [x]) == 2  # fmi2Discard at the set
    assert [m for st, m in log if st == 2] == [
        f"fmi2Set{'Integer' if setter == fmu.setInteger else 'Real'}: {name} = {x:g} is outside its range "
        f"[{'0' if name != 'damping_ratio' else '0'}, {'1' if name == 'damping_model' else '3' if name == 'integrator' else 'inf'}]"
        " (min/max of the model description); not set, the call sets nothing"]
    if at_init:
        assert _call(fmu.exitInitializationMode) == 0
    assert _call(fmu.doStep, 0.0, H) == 0  # the old value stays
    fmu.freeInstance()


@pytest.mark.parametrize("step_size", [0.0, -0.0, -H, -1e-05, -123.5, -2.5e16, -1 / 3, NAN, INF, -INF])
def test_both_runtimes_discard_a_bad_step_size_with_the_same_message(fmus, step_size):
    py = run_case(fmus["pythonfmu"], "pythonfmu", {}, {}, step_size)
    sa = run_case(fmus["standalone"], "standalone", {}, {}, step_size)
    assert py == sa
    assert py[0][-1] == 2  # fmi2Discard
    # the numbers as Python's repr writes them (docs/fmu.md)
    assert [m for _, m in py[1]] == [f"communication step size {step_size!r} at t = 0.0001 s: must be "
                                     "finite and > 0; step rejected, state unchanged"]
