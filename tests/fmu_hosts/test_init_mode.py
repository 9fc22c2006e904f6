"""Initialization Mode and the FMI call order, both runtimes, through fmpy's
low-level API (fmpy.fmi2.FMU2Slave, an independent FMI master).

References:
* FMI 2.0 standard, sections 2.2.8 and 4.2.4: from fmi2EnterInitializationMode
  on, the InitialUnknowns (here every output) can be read and are computed
  from the start values, parameters and inputs set so far; the
  InitialUnknowns' ``dependencies`` name the knowns they depend on.  So an
  output read in Initialization Mode must equal the first value read after
  fmi2ExitInitializationMode, and change with exactly the knowns it declares.
* Closed form (docs/model.md, initial state): with constant total stiffness
  k_total and no meshing error, the initial static balance gives
  mesh_force = T1/Rb1 and dte = F/k_total.
* A two-FMU chain (gear A's mesh force drives gear B): a master that passes
  A's output to B during initialization must get what a master that
  initializes A completely first and then B gets.
* FMI 2.0 section 4.2.4 table of allowed calls: a call out of order is
  fmi2Error; a setup without an initial state makes fmi2ExitInitializationMode
  return fmi2Error; section 2.2.7 (causality, variability): an output, and a fixed
  parameter after initialization, cannot be set; section 2.1.5: fmi2Error and fmi2Discard
  are reported through the logger "whether or not logging is on" ... is the FMU's choice,
  here: a message with a status other than fmi2OK always reaches the host.  Both runtimes
  share one FMI layer (docs/fmu.md "The binary"), so every test of the call order runs on
  both with the same expectations, words included.
"""
from dataclasses import replace

import fmpy
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave

from gearfmu.fmu.pythonfmu_build import build_fmu
from gearfmu.fmu.standalone_build import build_standalone_fmu
from gearfmu.tables.synthetic import rectangular_wave_tables

from factories import make_tables
from support.fmpy_host import callbacks  # fmpy logger proxy: formats the C layer's printf-style messages

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

RUNTIMES = ("standalone", "pythonfmu")
H = 1e-4


def _tables():
    """Meshing errors (so the damping term of the initial mesh force is not 0) and a
    two-row torque axis whose rows differ in stiffness (so mesh_stiffness depends on torque)."""
    t = make_tables(torque=(50.0, 150.0))
    k = t.k_N_per_m.copy()
    k[1] *= 1.25
    return replace(t, k_N_per_m=k)


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    d = tmp_path_factory.mktemp("init")
    kw = dict(max_step_s=1e-5, pinion_torque_start_Nm=100.0, pinion_speed_start_rad_s=150.0, damping_ratio=0.05,
              stop_time_s=0.01, output_interval_s=H)
    # Co-Simulation only: this module checks the Co-Simulation Initialization Mode and its InitialUnknowns
    # (Model Exchange adds states and derivatives to them; tests/fmu_hosts/test_model_exchange.py)
    return {"standalone": build_standalone_fmu(_tables(), d / "sa.fmu", model_name="initSA", validation=False,
                                               interface="cs", **kw),
            "pythonfmu": build_fmu(_tables(), d / "py.fmu", model_name="initPY", **kw)}


class Inst:
    """One instance through fmpy's FMU2Slave, recording (status, message) of every log call."""

    def __init__(self, path, name, logging_on=True):
        self.md = fmpy.read_model_description(str(path))
        self.log = []
        self._cb = cb = callbacks(self.log)
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=fmpy.extract(str(path)),
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.outputs = [v.name for v in self.md.modelVariables if v.causality == "output"]
        self.fmu.instantiate(callbacks=cb, loggingOn=logging_on)
        self.fmu.setupExperiment(startTime=0.0)

    def set(self, **kw):
        reals = {k: v for k, v in kw.items() if not isinstance(v, int)}
        ints = {k: v for k, v in kw.items() if isinstance(v, int)}
        if reals:
            self.fmu.setReal([self.vr[k] for k in reals], list(reals.values()))
        if ints:
            self.fmu.setInteger([self.vr[k] for k in ints], list(ints.values()))

    def get(self, names=None):
        names = self.outputs if names is None else names
        return np.array(self.fmu.getReal([self.vr[n] for n in names]))

    def close(self):
        self.fmu.freeInstance()


@pytest.mark.parametrize("runtime", RUNTIMES)
def test_outputs_in_init_mode_equal_first_after_exit(fmus, runtime):
    """Every output read in Initialization Mode equals the first value after exit,
    right after enter (start values) and after inputs/parameters were set in the mode."""
    s = Inst(fmus[runtime], "a")
    s.fmu.enterInitializationMode()
    at_start = s.get()
    s.set(pinion_torque=130.0, pinion_speed_start=90.0, damping_ratio=0.08, pinion_angle_start=0.013)
    in_init = s.get()
    s.fmu.exitInitializationMode()
    after = s.get()
    assert np.array_equal(in_init, after), dict(zip(s.outputs, in_init - after))
    # the set values were used: the static force of 130 N.m differs from the start torque's
    i = s.outputs.index("mesh_force")
    assert abs(at_start[i] - after[i]) > 300.0 and after[i] > 0  # 30 N.m more at Rb1 = 0.05 m: ~600 N
    assert after[s.outputs.index("pinion_speed")] == 90.0 and after[s.outputs.index("pinion_angle")] == 0.013
    s.fmu.terminate()
    s.close()


@pytest.mark.parametrize("runtime", RUNTIMES)
def test_init_mode_static_balance_closed_form(runtime, tmp_path):
    """Constant total stiffness, no meshing error: in Initialization Mode mesh_force = T1/Rb1
    and dte = F/k_total (closed form), mesh_stiffness = k_total, speeds = the start speed."""
    t = rectangular_wave_tables(2e8, contact_ratio=2.0)  # two pairs engaged everywhere: k_total = 4e8 N/m
    T1 = 40.0
    b = build_standalone_fmu if runtime == "standalone" else build_fmu
    extra = {"validation": False} if runtime == "standalone" else {}
    p = b(t, tmp_path / "bal.fmu", model_name="bal", pinion_speed_start_rad_s=50.0, pinion_torque_start_Nm=T1,
          max_step_s=1e-5, stop_time_s=0.001, output_interval_s=1e-4, **extra)
    s = Inst(p, "bal")
    s.fmu.enterInitializationMode()
    F, x, k, w = s.get(["mesh_force", "dte", "mesh_stiffness", "pinion_speed"])
    assert F == pytest.approx(T1 / t.base_radius_pinion_m, rel=1e-9)
    assert x == pytest.approx(F / 4e8, rel=1e-9)
    assert k == pytest.approx(4e8, rel=1e-12) and w == 50.0
    s.fmu.exitInitializationMode()
    s.fmu.terminate()
    s.close()


def test_initial_unknowns_dependencies_are_true(fmus):
    """Each InitialUnknown changes when a known it lists changes, and does not change
    when any other input or parameter changes (perturbed one at a time in Initialization Mode)."""
    md = fmpy.read_model_description(str(fmus["standalone"]))
    knowns = [v for v in md.modelVariables if v.causality in ("input", "parameter")]
    declared = {u.variable.name: {d.name for d in u.dependencies} for u in md.initialUnknowns}
    assert set(declared) == {v.name for v in md.modelVariables if v.causality == "output"}
    perturbed = {"pinion_torque": 120.0, "gear_torque": 300.0, "damping_ratio": 0.2, "pinion_speed_start": 60.0,
                 "pinion_angle_start": 0.2, "max_step": 2e-6, "damping_model": 1, "integrator": 0}
    assert set(perturbed) == {v.name for v in knowns}
    s = Inst(fmus["standalone"], "dep")
    s.fmu.enterInitializationMode()
    starts = {v.name: (int(v.start) if v.type == "Integer" else float(v.start)) for v in knowns}
    observed = {n: set() for n in s.outputs}
    # three operating points, since a dependency may be invisible at one: the start torque (both
    # pairs loaded), and a light load below the torque axis (clamped to its first row) at two angles,
    # where pair 2, then pair 1, is in its contact zone but inside the backlash, so that only contact_zone
    # damping (damping_model 1) acts on it; the angle perturbation (0.2 rad, mesh period 0.314 rad)
    # moves into the single-contact zone
    for t1, angle in ((starts["pinion_torque"], 0.0), (5.0, 0.0), (5.0, 0.1)):
        s.set(pinion_torque=t1, pinion_angle_start=angle)
        base = dict(zip(s.outputs, s.get()))
        values = dict(starts, pinion_torque=t1, pinion_angle_start=angle)
        for name, val in perturbed.items():
            s.set(**{name: val})
            for n, y in zip(s.outputs, s.get()):
                if y != base[n]:
                    observed[n].add(name)
            s.set(**{name: values[name]})
        assert np.array_equal(s.get(), [base[n] for n in s.outputs])  # back to the base values
    assert observed == declared
    s.close()


def _chain(path, scale, n, pass_in_init):
    """Gear A's mesh force times ``scale`` (m) is gear B's pinion torque.  pass_in_init: the
    master reads A in Initialization Mode and sets B before both exit; otherwise it
    initializes A completely, then sets B's input and initializes B.  Returns B's outputs."""
    a, b = Inst(path, "A"), Inst(path, "B")
    if pass_in_init:
        a.fmu.enterInitializationMode()
        b.fmu.enterInitializationMode()
        b.set(pinion_torque=scale * a.get(["mesh_force"])[0])
        a.fmu.exitInitializationMode()
        b.fmu.exitInitializationMode()
    else:
        a.fmu.enterInitializationMode()
        a.fmu.exitInitializationMode()
        b.set(pinion_torque=scale * a.get(["mesh_force"])[0])
        b.fmu.enterInitializationMode()
        b.fmu.exitInitializationMode()
    rows = [b.get()]
    for k in range(n):
        force = a.get(["mesh_force"])[0]
        b.set(pinion_torque=scale * force)
        a.fmu.doStep(k * H, H)
        b.fmu.doStep(k * H, H)
        rows.append(b.get())
    for x in (a, b):
        x.fmu.terminate()
        x.close()
    return np.array(rows)


@pytest.mark.parametrize("runtime", RUNTIMES)
def test_two_fmu_chain_same_with_or_without_passing_in_init(fmus, runtime):
    scale = 0.75 * _tables().base_radius_pinion_m  # B runs at 3/4 of A's torque
    with_init = _chain(fmus[runtime], scale, 100, True)
    without = _chain(fmus[runtime], scale, 100, False)
    assert np.array_equal(with_init, without), float(np.max(np.abs(with_init - without)))
    assert with_init[0, 5] > 0  # B starts loaded (mesh_force), not from a zero torque


# ------------------------------------- the FMI state machine: both runtimes, one expectation
def _status(call, *args):
    try:
        call(*args)
        return 0
    except FMICallException as exc:
        return exc.status


@pytest.mark.parametrize("runtime", RUNTIMES)
def test_exit_fails_on_a_bad_setup(fmus, runtime):
    """A NaN pinion torque at exit: fmi2ExitInitializationMode returns fmi2Error with the
    reason logged; the instance is then in the error state (doStep refused, outputs not served
    as if initialized, reset works)."""
    s = Inst(fmus[runtime], "bad")
    s.fmu.enterInitializationMode()
    s.set(pinion_torque=float("nan"))
    assert _status(s.fmu.exitInitializationMode) == 3
    text = " ".join(m for _, m in s.log)
    assert "pinion_torque = nan" in text and "fmi2ExitInitializationMode" in text
    assert _status(s.fmu.doStep, 0.0, H) == 3
    assert "fmi2DoStep: illegal call sequence: not allowed in state error" in s.log[-1][1]
    s.fmu.reset()
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    s.fmu.exitInitializationMode()
    s.fmu.doStep(0.0, H)
    s.fmu.terminate()
    s.close()


@pytest.mark.parametrize("runtime", RUNTIMES)
@pytest.mark.parametrize("call, state, before", [
    (lambda f: f.doStep(0.0, H), "instantiated", ()),
    (lambda f: f.exitInitializationMode(), "instantiated", ()),
    (lambda f: f.getReal([2]), "instantiated", ()),
    (lambda f: f.terminate(), "instantiated", ()),
    (lambda f: f.enterInitializationMode(), "initializationMode", ("enter",)),
    (lambda f: f.setupExperiment(startTime=0.0), "initializationMode", ("enter",)),
    (lambda f: f.doStep(0.0, H), "initializationMode", ("enter",)),
    (lambda f: f.exitInitializationMode(), "stepComplete", ("enter", "exit")),
    (lambda f: f.enterInitializationMode(), "stepComplete", ("enter", "exit")),
], ids=["step-before-init", "exit-before-enter", "get-before-enter", "terminate-before-init", "enter-twice",
        "setup-in-init", "step-in-init", "exit-twice", "enter-after-exit"])
def test_out_of_order_call_refused_and_logged(fmus, runtime, call, state, before):
    s = Inst(fmus[runtime], "order")
    for step in before:
        getattr(s.fmu, step + "InitializationMode")()
    n = len(s.log)
    assert _status(call, s.fmu) == 3
    assert len(s.log) == n + 1 and s.log[-1][0] == 3
    assert "illegal call sequence" in s.log[-1][1] and f"state {state}" in s.log[-1][1]
    # the instance is unharmed: the normal sequence still works
    if "enter" not in before:
        s.fmu.enterInitializationMode()
    if "exit" not in before:
        s.fmu.exitInitializationMode()
    s.fmu.doStep(0.0, H)
    s.fmu.terminate()
    assert _status(s.fmu.setReal, [0], [1.0]) == 3 and "state terminated" in s.log[-1][1]
    assert _status(s.fmu.doStep, H, H) == 3 and "state terminated" in s.log[-1][1]
    s.close()


@pytest.mark.parametrize("runtime", RUNTIMES)
def test_refused_sets_and_gets_are_errors_with_the_same_words(fmus, runtime):
    """An output, a fixed parameter after initialization, an unknown value reference, a value of
    the wrong type: each refused with fmi2Error, one logged line naming the function and the
    variable, nothing changed; a tunable parameter and an input may be set between steps."""
    s = Inst(fmus[runtime], "refuse")
    vr = s.vr
    s.fmu.enterInitializationMode()
    s.fmu.setReal([vr["max_step"]], [2e-5])  # fixed: settable until the end of initialization
    s.fmu.exitInitializationMode()
    before = s.get()
    cases = [
        (s.fmu.setReal, [vr["max_step"]], [1e-3], "fmi2SetReal: max_step cannot be set now "
                                                 "(causality/variability forbid it)"),
        (s.fmu.setInteger, [vr["damping_model"]], [1], "fmi2SetInteger: damping_model cannot be set now "
                                                      "(causality/variability forbid it)"),
        (s.fmu.setReal, [vr["mesh_force"]], [1.0], "fmi2SetReal: mesh_force cannot be set now "
                                                  "(causality/variability forbid it)"),
        (s.fmu.setReal, [999], [1.0], "fmi2SetReal: no variable with value reference 999"),
        (s.fmu.getReal, [999], None, "fmi2GetReal: no variable with value reference 999"),
        (s.fmu.getInteger, [vr["mesh_force"]], None, "fmi2GetInteger: mesh_force is not of type Integer"),
        (s.fmu.setReal, [vr["integrator"]], [1.0], "fmi2SetReal: integrator is not of type Real"),
    ]
    for fn, refs, values, words in cases:
        n = len(s.log)
        args = (refs,) if values is None else (refs, values)
        assert _status(fn, *args) == 3, words
        assert s.log[n:] == [(3, words)]
    assert np.array_equal(s.get(), before)
    assert s.fmu.getReal([vr["max_step"]]) == [2e-5]
    n = len(s.log)
    s.set(damping_ratio=0.1, pinion_torque=120.0)  # tunable and input: accepted
    s.fmu.doStep(0.0, H)
    assert s.fmu.getReal([vr["damping_ratio"], vr["pinion_torque"]]) == [0.1, 120.0]
    assert not any(st >= 2 for st, _ in s.log[n:]), s.log[n:]
    s.fmu.terminate()
    s.close()


@pytest.mark.parametrize("runtime", RUNTIMES)
@pytest.mark.parametrize("logging_on", [True, False], ids=["logging-on", "logging-off"])
def test_refusals_and_warnings_reach_the_host_whatever_the_logging(fmus, runtime, logging_on):
    """With logging off (fmi2Instantiate loggingOn = false) a discarded step, a refused call and a
    warning still log their line; only fmi2OK messages follow the switch."""
    s = Inst(fmus[runtime], "quiet", logging_on=logging_on)
    s.fmu.enterInitializationMode()
    s.fmu.exitInitializationMode()
    s.set(pinion_torque=float("inf"))
    assert _status(s.fmu.doStep, 0.0, H) == 2
    assert s.log[-1] == (2, "pinion_torque = inf at t = 0.0 s: not finite; step rejected, state unchanged")
    assert _status(s.fmu.getReal, [999]) == 3 and s.log[-1][0] == 3
    s.set(pinion_torque=400.0)  # beyond the torque axis [50, 150] N.m: clamped, and outside the envelope
    n = len(s.log)
    assert _status(s.fmu.doStep, 0.0, H) == 0
    assert {st for st, _ in s.log[n:]} == {1}
    text = " ".join(m for _, m in s.log[n:])
    assert "outside the tables' torque axis" in text and "outside the range this FMU was built for" in text
    s.fmu.terminate()
    s.close()
    # fmi2OK messages (instantiation) only with logging on
    assert {st for st, _ in s.log} - {0} == {1, 2, 3} and (0 in {st for st, _ in s.log}) == logging_on
