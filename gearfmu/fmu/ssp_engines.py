"""Run an SSP of stage FMUs in the engines it is made for, and measure what the coupling does.

* :func:`run_fmpy`: fmpy's SSP master (``fmpy.ssp.simulation.simulate_ssp``): fixed communication step,
  every component stepped from the values of the last communication point (Jacobi), the outputs read
  after the step.  It starts every connection at 0: in the first step each driven input is 0, not the
  neighbour's initial output (the FMUs' first_step_start_values holds their start values instead;
  docs/gearbox.md "The SSP of stage FMUs").
* :func:`run_libcosim`: the Open Simulation Platform's libcosim (libcosimpy), from the archive's
  ``SystemStructure.ssd`` at a fixed step, or with the energy-conserving algorithm ECCO (Sadjina &
  Pedersen 2020; libcosim's ``ecco_algorithm``), which changes the step to keep the power residual of
  the bonds within its tolerances: the archive's FMUs, connections and bonds (:func:`read_system`) set
  up in code, since libcosim refuses an OspSystemStructure.xml with more than one power bond.
  libcosim transfers the initial outputs during initialization.

Both return a :class:`SspRun`: the communication points (s), the outputs asked for by (component,
variable), the wall and process CPU time of the simulation (s; fmpy's includes unpacking the FMUs).
:func:`energy_residual` is the energy the coupling creates or destroys
at the power bonds, from the exchanged values (the residual libcosim's ECCO controls).
"""
from __future__ import annotations

import shutil
import tempfile
import time
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, Optional, Sequence, Tuple

import numpy as np

__all__ = ["SspRun", "run_fmpy", "run_libcosim", "energy_residual", "bond_outputs", "ECCO_DEFAULTS", "bonds_of",
           "read_system"]

#: libcosim's ECCO parameters (libcosimpy EccoParams) used unless given: libcosimpy's defaults for the
#: controller, the change rates of libcosim's own ECCO example; the step bounds and tolerances are set per run
ECCO_DEFAULTS = {"safety_factor": 0.8, "min_change_rate": 0.2, "max_change_rate": 1.5, "p_gain": 0.2, "i_gain": 0.15}
NS_PER_S = 1_000_000_000


@dataclass
class SspRun:
    """The outputs of a run at its communication points ``time_s`` (after each step; the steps' lengths
    ``step_s``), by (component, variable); the wall time and the process CPU time of the run (s)."""

    engine: str
    time_s: np.ndarray
    step_s: np.ndarray
    values: Dict[Tuple[str, str], np.ndarray]
    wall_s: float
    cpu_s: float = 0.0

    def __getitem__(self, key: Tuple[str, str]) -> np.ndarray:
        return self.values[key]


@dataclass
class _Parameter:
    name: str
    value: float


@dataclass
class _ParameterSet:
    parameters: list


def run_fmpy(ssp_path, *, stop_time_s: float, step_s: float, outputs: Sequence[Tuple[str, str]],
             start_values: Optional[Dict[Tuple[str, str], float]] = None) -> SspRun:
    """Run the SSP in fmpy's SSP master for ``stop_time_s`` at the communication step ``step_s``; the
    ``outputs`` (component, variable) at t_k = k H, k = 1 .. round(stop/H).  ``start_values``: values
    set before the initialization ({(component, parameter or unconnected input): value}; fmpy applies
    them as a parameter set)."""
    from fmpy.ssp.simulation import simulate_ssp  # fmpy's SSP master: heavy, only to run it

    n = int(round(stop_time_s / step_s))
    pset = None
    if start_values:
        pset = _ParameterSet([_Parameter(f"{c}.{v}", float(x)) for (c, v), x in start_values.items()])
    t0, c0 = time.perf_counter(), time.process_time()
    # fmpy's loop adds the step to the time; a little less than n steps' end keeps it from one step more
    res = simulate_ssp(str(ssp_path), stop_time=(n - 0.5) * step_s, step_size=step_s, parameter_set=pset)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    if len(res) != n:
        raise RuntimeError(f"fmpy: {len(res)} communication steps, expected {n}")
    values = {}
    for comp, var in outputs:
        values[(comp, var)] = np.asarray(res[f"{comp}.{var}"], dtype=float)
    return SspRun("fmpy", np.arange(1, n + 1) * step_s, np.full(n, step_s), values, wall, cpu)


def read_system(folder) -> dict:
    """The system of an extracted SSP of stage FMUs: {"links": [(source, output, target, input)],
    "bonds": {bond: {"torque_in": (component, torque, speed), "torque_out": (component, torque, speed)}},
    "fmus": {component: path}} from its SystemStructure.ssd, OspSystemStructure.xml and the components'
    OspModelDescription files (the AngularMechanicalPort groups)."""
    folder = Path(folder)
    ssd = ET.parse(folder / "SystemStructure.ssd").getroot()
    kinds, fmus, links = {}, {}, []
    for el in ssd.iter():
        tag = el.tag.rsplit("}", 1)[-1]
        if tag == "Component":
            fmus[el.get("name")] = folder / el.get("source")
            for cn in el.iter():
                if cn.tag.endswith("}Connector"):
                    kinds[(el.get("name"), cn.get("name"))] = cn.get("kind")
        elif tag == "Connection":
            links.append((el.get("startElement"), el.get("startConnector"), el.get("endElement"), el.get("endConnector")))
    osp = ET.parse(folder / "OspSystemStructure.xml").getroot()
    bonds: Dict[str, dict] = {}
    for gc in osp.iter():
        if not gc.tag.endswith("}VariableGroupConnection"):
            continue
        name = None
        for g in gc:
            comp, name = g.get("simulator"), g.get("name")
            md = ET.parse(folder / "resources" / f"{comp}_OspModelDescription.xml").getroot()
            port = next(e for e in md.iter() if e.tag.endswith("}AngularMechanicalPort") and e.get("name") == name)
            torque = next(v.get("ref") for e in port if e.tag.endswith("}Torque") for v in e)
            speed = next(v.get("ref") for e in port if e.tag.endswith("}AngularVelocity") for v in e)
            side = "torque_in" if kinds.get((comp, torque)) == "input" else "torque_out"
            bonds.setdefault(name, {})[side] = (comp, torque, speed)
    return {"links": links, "bonds": bonds, "fmus": fmus}


def bonds_of(ssp_path) -> Dict[str, dict]:
    """The power bonds of an SSP archive of stage FMUs (:func:`read_system`)."""
    with tempfile.TemporaryDirectory(prefix="gearfmu_ssp_read_") as tmp:
        with zipfile.ZipFile(ssp_path) as z:
            for n in z.namelist():
                if not n.endswith(".fmu"):
                    z.extract(n, tmp)
        return read_system(tmp)["bonds"]


def run_libcosim(ssp_path, *, stop_time_s: float, step_s: float, outputs: Sequence[Tuple[str, str]],
                 ecco: Optional[Dict[str, float]] = None,
                 start_values: Optional[Dict[Tuple[str, str], float]] = None) -> SspRun:
    """Run the SSP in libcosim (libcosimpy) for ``stop_time_s``: from ``SystemStructure.ssd`` at the fixed
    step ``step_s``, or with ``ecco`` (EccoParams fields of libcosimpy, at least rel_tolerance,
    abs_tolerance, min_step_size, max_step_size in s; the first step ``step_s``): libcosim's ECCO
    algorithm over the archive's FMUs, links and power bonds (:func:`read_system`).  The ``outputs`` at
    every communication point libcosim reaches.  ``start_values``: as :func:`run_fmpy`'s (libcosim's
    initial values)."""
    from libcosimpy.CosimAlgorithm import CosimAlgorithm, EccoParams  # libcosim: only to run it
    from libcosimpy.CosimEnums import CosimVariableType  # libcosim: loads its C library, only to run it
    from libcosimpy.CosimExecution import CosimExecution  # libcosim: only to run it
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level  # libcosim: only to run it
    from libcosimpy.CosimObserver import CosimObserver  # libcosim: only to run it
    from libcosimpy.CosimSlave import CosimLocalSlave  # libcosim: only to run it

    log_output_level(CosimLogLevel.ERROR)
    h_ns = int(round(step_s * NS_PER_S))
    if h_ns < 1:
        raise ValueError(f"step_s: {step_s!r} is below libcosim's 1 ns")
    stop_ns = int(round(stop_time_s / step_s)) * h_ns
    h_min = float((ecco or {}).get("min_step_size", step_s))
    n_max = int(stop_ns // max(1, int(h_min * NS_PER_S))) + 16
    tmp = tempfile.mkdtemp(prefix="gearfmu_cosim_")
    alg = None
    try:
        if ecco is None:
            ex = CosimExecution.from_ssp_file(str(ssp_path), step_size=h_ns)
        else:
            with zipfile.ZipFile(ssp_path) as z:
                z.extractall(tmp)
            system = read_system(tmp)
            alg = CosimAlgorithm.create_ecco_algorithm(EccoParams(**dict(ECCO_DEFAULTS, step_size=step_s, **ecco)))
            ex = CosimExecution.from_algorithm(alg)
            idx = {name: ex.add_local_slave(CosimLocalSlave(str(path), name)) for name, path in system["fmus"].items()}
            vrs = {name: {v.name.decode(): v.reference for v in ex.slave_variables(i)} for name, i in idx.items()}
            for src, out, dst, inp in system["links"]:
                ex.connect_real_variables(idx[src], vrs[src][out], idx[dst], vrs[dst][inp])
            for bond in system["bonds"].values():
                (ca, ta, sa), (cb, tb, sb) = bond["torque_in"], bond["torque_out"]
                if alg.add_power_bond(idx[ca], vrs[ca][sa], vrs[ca][ta], idx[cb], vrs[cb][tb], vrs[cb][sb]) != 0:
                    raise RuntimeError(f"libcosim: power bond {ca}.{ta} / {cb}.{tb} refused")
        for (comp, var), x in (start_values or {}).items():
            i = ex.slave_index_from_instance_name(comp)
            vr = {v.name.decode(): v.reference for v in ex.slave_variables(i)} if i is not None else {}
            if var not in vr:
                raise KeyError(f"libcosim: no variable {comp}.{var}")
            ex.real_initial_value(i, vr[var], float(x))
        obs = CosimObserver.create_time_series(buffer_size=n_max)
        ex.add_observer(obs)
        if ecco is not None:   # ECCO reads the bonds' inputs too: an observed variable is one libcosim can get
            for bond in system["bonds"].values():
                tin, tout = bond["torque_in"], bond["torque_out"]
                for comp, var in ((tin[0], tin[1]), (tout[0], tout[2])):
                    obs.start_time_series(idx[comp], vrs[comp][var], CosimVariableType.REAL)
        refs = []
        for comp, var in outputs:
            i = ex.slave_index_from_instance_name(comp)
            if i is None:
                raise KeyError(f"libcosim: no component {comp!r}")
            vr = {v.name.decode(): v.reference for v in ex.slave_variables(i)}
            if var not in vr:
                raise KeyError(f"libcosim: {comp} has no variable {var!r}")
            refs.append((i, vr[var]))
            obs.start_time_series(i, vr[var], CosimVariableType.REAL)
        t0, c0 = time.perf_counter(), time.process_time()
        if not ex.simulate_until(stop_ns):
            from libcosimpy._internal import get_last_error_message  # libcosim: its last error, only then
            raise RuntimeError(f"libcosim: the simulation stopped with an error ({get_last_error_message()})")
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        values, times = {}, None
        for (comp, var), (i, vr) in zip(outputs, refs):
            tp, steps, samples = obs.time_series_real_samples(i, vr, 1, n_max)
            values[(comp, var)] = np.asarray(samples, dtype=float)
            times = np.asarray(tp, dtype=np.int64)
        t = times / NS_PER_S
        return SspRun("libcosim" + ("-ecco" if ecco else ""), t, np.diff(np.concatenate([[0.0], t])), values, wall,
                      cpu)
    finally:
        del alg
        shutil.rmtree(tmp, ignore_errors=True)


def energy_residual(run: SspRun, bonds: Dict[str, dict]) -> Dict[str, dict]:
    """Per power bond (``bonds``: :func:`bonds_of`), from the exchanged values at the communication points:
    the energy residual sum_k H_k |T_k w_(k+1) - w_k T_(k+1)| (J) -- at each step's end the power the
    side that holds the torque computes (the torque it held times the speed it reached) minus the power
    the other side computes (the speed it held times the torque it returned): libcosim ECCO's power
    residual (Sadjina & Pedersen 2020) -- and the energy through the bond, sum_k H_k |T_k w_k| (J).  The
    run must hold the torque output and the speed output of every bond."""
    out = {}
    for name, bond in bonds.items():
        ca, _, sa = bond["torque_in"]
        cb, tb, _ = bond["torque_out"]
        for key in ((ca, sa), (cb, tb)):
            if key not in run.values:
                raise KeyError(f"energy_residual: the run lacks {key[0]}.{key[1]} of bond {name}")
        torque, speed = run.values[(cb, tb)], run.values[(ca, sa)]
        h = run.step_s[1:]
        res = float(np.sum(h * np.abs(torque[:-1] * speed[1:] - speed[:-1] * torque[1:])))
        through = float(np.sum(h * np.abs(torque[:-1] * speed[:-1])))
        out[name] = {"residual_J": res, "transmitted_J": through, "relative": res / through if through else 0.0}
    return out


def bond_outputs(bonds: Dict[str, dict]) -> list:
    """The (component, variable) outputs :func:`energy_residual` needs."""
    out = []
    for bond in bonds.values():
        out += [(bond["torque_in"][0], bond["torque_in"][2]), (bond["torque_out"][0], bond["torque_out"][1])]
    return sorted(set(out))
