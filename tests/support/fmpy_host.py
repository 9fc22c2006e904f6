"""FMUs driven through fmpy's low-level FMI 2 API: callbacks that record the FMU's messages, a
Co-Simulation slave, an instance stepped at a fixed communication step (:class:`Inst`), and the
process-wide logger fmpy's default callbacks need."""
import numpy as np
import fmpy
from fmpy.fmi2 import FMU2Slave

#: the communication step of :meth:`Inst.steps` (s)
H = 1e-4
#: the outputs :meth:`Inst.out` reads (those the FMU has)
OUTS = ["dte", "mesh_force", "pinion_speed", "gear_speed", "pinion_angle", "gear_angle", "mesh_stiffness",
        "pair_force[1]", "pair_force[2]", "load_sharing[1]"]

#: every callback struct :func:`callbacks` registered: fmpy's logger proxy keeps the last registered
#: logger in one process-wide slot (s_logger in fmpy/logging), which fmpy's default callbacks
#: (fmpy.simulate_fmu without a logger) also call -- a freed one there crashes the process the
#: first time a later FMU logs anything (a warning, docs/fmu.md "Verified envelope").  The slot
#: holds the logger registered last, so every instance's messages reach it: each set of callbacks
#: carries its own componentEnvironment, by which the messages go to their list (_LOGS)
KEPT_CALLBACKS = []
_LOGS = {}


def callbacks(msgs):
    """fmpy callbacks whose logger appends (status, formatted message) to msgs (kept alive for the
    whole process, see KEPT_CALLBACKS)."""
    from fmpy.fmi2 import (fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                           fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)
    from fmpy.fmi1 import calloc, free
    from fmpy.logging import addLoggerProxy
    from ctypes import byref

    def logger(env, inst, status, cat, msg):
        if env in _LOGS:  # (another host's callbacks, e.g. fmpy.simulate_fmu's defaults, have none)
            _LOGS[env].append((status, msg.decode() if isinstance(msg, bytes) else str(msg)))

    key = len(KEPT_CALLBACKS) + 1
    _LOGS[key] = msgs
    cb = fmi2CallbackFunctions()
    cb.logger = fmi2CallbackLoggerTYPE(logger)
    cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    cb.componentEnvironment = key
    addLoggerProxy(byref(cb))
    KEPT_CALLBACKS.append(cb)
    return cb


def slave(path, tmp, name="s", instantiate=True):
    """(an FMU2Slave of the FMU at path unzipped under tmp/name, its value references by name, the
    list its messages go to)."""
    md = fmpy.read_model_description(str(path))
    d = fmpy.extract(str(path), unzipdir=str(tmp / name))
    msgs = []
    s = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName=name)
    s._test_callbacks = callbacks(msgs)  # keep alive as long as the slave
    if instantiate:
        s.instantiate(loggingOn=True, callbacks=s._test_callbacks)
    vrs = {v.name: v.valueReference for v in md.modelVariables}
    return s, vrs, msgs


def status(call, *args):
    """call(*args), or the FMI status it raised."""
    from fmpy.fmi1 import FMICallException
    try:
        return call(*args)
    except FMICallException as exc:
        return exc.status


def quiet(*args):
    """fmpy's logger for runs whose messages are not under test."""


_LIVE_CALLBACKS = []


def keep_fmpy_logger_alive():
    """fmpy (0.3.32) formats an FMU's messages in a native proxy that forwards them to the Python logger
    registered last, process-wide; ``simulate_fmu(logger=...)`` registers its own and frees it when it
    returns, so the next FMU on fmpy's default callbacks (PathSim's) that logs a message calls freed
    memory and the host dies.  Registered here: a logger that lives as long as the process."""
    from ctypes import byref

    from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
    from fmpy.logging import addLoggerProxy

    cb = fmi2CallbackFunctions()
    cb.logger = fmi2CallbackLoggerTYPE(quiet)
    _LIVE_CALLBACKS.append(cb)
    addLoggerProxy(byref(cb))


class Inst:
    """One FMU instance driven through fmpy's low-level API, recording log messages."""

    def __init__(self, path, name):
        self.md = fmpy.read_model_description(str(path))
        self.log = []
        self._cb = cb = callbacks(self.log)  # formats the FMU's printf-style messages
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=fmpy.extract(str(path)),
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.fmu.instantiate(callbacks=cb, loggingOn=True)
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()

    def set(self, **kw):
        self.fmu.setReal([self.vr[k] for k in kw], list(kw.values()))

    def out(self):
        names = [n for n in OUTS if n in self.vr]
        return self.fmu.getReal([self.vr[n] for n in names])

    def steps(self, i0, n, torque_schedule=None):
        rows = []
        for i in range(i0, i0 + n):
            if torque_schedule is not None:
                self.set(pinion_torque=torque_schedule(i))
            self.fmu.doStep(currentCommunicationPoint=i * H, communicationStepSize=H)
            rows.append(self.out())
        return np.array(rows)

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()
