"""Both runtimes of one FMU driven through the same input schedule, and the envelope records an FMU
carries (tests/fmu_hosts/test_envelope_fmu.py, tests/unit/plan/test_plan.py; docs/fmu.md "Verified
envelope")."""
import json
import zipfile

import fmpy
from fmpy.fmi2 import FMU2Slave

from support.fmpy_host import callbacks

#: the communication step the FMUs are built with and driven at (s)
H = 1e-4


def drive(path, schedule):
    """Step the FMU at H through ``schedule`` (dicts of inputs per step); return (warnings, statuses)."""
    md = fmpy.read_model_description(str(path))
    log = []
    cb = callbacks(log)
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=fmpy.extract(str(path)),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="env")
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu.instantiate(callbacks=cb, loggingOn=True)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    statuses = []
    for i, inputs in enumerate(schedule):
        fmu.setReal([vr[k] for k in inputs], list(inputs.values()))
        statuses.append(fmu.fmi2DoStep(fmu.component, i * H, H, 1))  # the status (fmpy raises above warning)
    fmu.terminate()
    fmu.freeInstance()
    return [m for st, m in log if st == 1], statuses


def both_runtimes_warn(fmus, schedule):
    """Envelope warnings of both runtimes for one schedule; they must be the same messages
    (the tables' own torque-axis warning, worded by each runtime, is not one of them)."""
    got = {k: drive(p, schedule) for k, p in fmus.items()}
    env = {k: [w for w in g[0] if w.endswith("(one warning per input; resources/envelope.json)")]
           for k, g in got.items()}
    assert env["standalone"] == env["pythonfmu"], got
    for _, statuses in got.values():
        assert statuses == [0] * len(schedule)  # fmi2OK: the FMU keeps running
    return env["standalone"]


def record(path):
    """(resources/envelope.json, resources/validation/record.json, the model description's description) of an FMU."""
    with zipfile.ZipFile(path) as z:
        env = json.loads(z.read("resources/envelope.json"))
        rec = json.loads(z.read("resources/validation/record.json"))
    return env, rec, fmpy.read_model_description(str(path)).description
