"""Run an SSP of stage FMUs in the engines it is made for, and measure what the coupling does.

* :func:`run_fmpy`: fmpy's SSP master (``fmpy.ssp.simulation.simulate_ssp``): fixed communication step,
  every component stepped from the values of the last communication point (Jacobi), the outputs read
  after the step.  It starts every connection at 0: in the first step each driven input is 0, not the
  neighbour's initial output (docs/gearbox.md "The SSP of stage FMUs" says what that costs).
* :func:`run_libcosim`: the Open Simulation Platform's libcosim (libcosimpy), from the archive's
  ``SystemStructure.ssd`` at a fixed step, or from its ``OspSystemStructure.xml`` with the
  energy-conserving algorithm ECCO (Sadjina & Pedersen 2020; libcosim's ``ecco_algorithm``), which
  changes the step to keep the power residual of the bonds within its tolerances.  libcosim transfers
  the initial outputs during initialization.

Both return a :class:`SspRun`: the communication points (s), the outputs asked for by (component,
variable), the wall time (s).  :func:`energy_residual` is the energy the coupling creates or destroys
at the power bonds, from the exchanged values (the residual libcosim's ECCO controls).
"""
from __future__ import annotations

import os
import shutil
import tempfile
import time
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, Optional, Sequence, Tuple

import numpy as np

__all__ = ["SspRun", "run_fmpy", "run_libcosim", "energy_residual", "ECCO_DEFAULTS", "bonds_of"]

#: libcosim's ECCO parameters (OspSystemStructure EccoConfiguration) used unless given: the values of
#: libcosim's own example (tests/data/fmi2/quarter_truck) with the step bounds and tolerances set per run
ECCO_DEFAULTS = {"SafetyFactor": 0.8, "MinimumChangeRate": 0.2, "MaximumChangeRate": 1.5, "ProportionalGain": 0.2,
                 "IntegralGain": 0.15}
NS_PER_S = 1_000_000_000


@dataclass
class SspRun:
    """The outputs of a run at its communication points ``time_s`` (after each step; the steps' lengths
    ``step_s``), by (component, variable); the wall time of the run (s)."""

    engine: str
    time_s: np.ndarray
    step_s: np.ndarray
    values: Dict[Tuple[str, str], np.ndarray]
    wall_s: float

    def __getitem__(self, key: Tuple[str, str]) -> np.ndarray:
        return self.values[key]


def run_fmpy(ssp_path, *, stop_time_s: float, step_s: float, outputs: Sequence[Tuple[str, str]]) -> SspRun:
    """Run the SSP in fmpy's SSP master for ``stop_time_s`` at the communication step ``step_s``; the
    ``outputs`` (component, variable) at t_k = k H, k = 1 .. round(stop/H)."""
    from fmpy.ssp.simulation import simulate_ssp  # fmpy's SSP master: heavy, only to run it

    n = int(round(stop_time_s / step_s))
    t0 = time.perf_counter()
    # fmpy's loop adds the step to the time; a little less than n steps' end keeps it from one step more
    res = simulate_ssp(str(ssp_path), stop_time=(n - 0.5) * step_s, step_size=step_s)
    wall = time.perf_counter() - t0
    if len(res) != n:
        raise RuntimeError(f"fmpy: {len(res)} communication steps, expected {n}")
    values = {}
    for comp, var in outputs:
        values[(comp, var)] = np.asarray(res[f"{comp}.{var}"], dtype=float)
    return SspRun("fmpy", np.arange(1, n + 1) * step_s, np.full(n, step_s), values, wall)


def bonds_of(osp_system: Path):
    """The power bonds of an OspSystemStructure.xml: {bond: [(input simulator, input, output simulator,
    output)]}."""
    root = ET.parse(osp_system).getroot()
    out: Dict[str, list] = {}
    for vc in root.iter():
        if vc.tag.endswith("VariableConnection") and vc.get("powerBond"):
            ends = {v.get("causality"): (v.get("simulator"), v.get("name")) for v in vc if v.tag.endswith("Variable")}
            out.setdefault(vc.get("powerBond"), []).append((*ends["input"], *ends["output"]))
    return out


def run_libcosim(ssp_path, *, stop_time_s: float, step_s: float, outputs: Sequence[Tuple[str, str]],
                 ecco: Optional[Dict[str, float]] = None) -> SspRun:
    """Run the SSP in libcosim (libcosimpy) for ``stop_time_s``: from ``SystemStructure.ssd`` at the fixed
    step ``step_s``, or with ``ecco`` (EccoConfiguration values: at least RelativeTolerance,
    AbsoluteTolerance, MinimumStepSize, MaximumStepSize; the first step ``step_s``) from the
    archive's OspSystemStructure.xml with libcosim's ECCO algorithm.  The ``outputs`` at every
    communication point libcosim reaches."""
    from libcosimpy.CosimEnums import CosimVariableType  # libcosim: loads its C library, only to run it
    from libcosimpy.CosimExecution import CosimExecution  # libcosim: only to run it
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level  # libcosim: only to run it
    from libcosimpy.CosimObserver import CosimObserver  # libcosim: only to run it

    log_output_level(CosimLogLevel.ERROR)
    h_ns = int(round(step_s * NS_PER_S))
    if h_ns < 1:
        raise ValueError(f"step_s: {step_s!r} is below libcosim's 1 ns")
    stop_ns = int(round(stop_time_s / step_s)) * h_ns
    tmp = tempfile.mkdtemp(prefix="gearfmu_cosim_")
    try:
        if ecco is None:
            ex = CosimExecution.from_ssp_file(str(ssp_path), step_size=h_ns)
        else:
            with zipfile.ZipFile(ssp_path) as z:
                z.extractall(tmp)
            osp = Path(tmp) / "OspSystemStructure.xml"
            tree = ET.parse(osp)
            root = tree.getroot()
            ns = root.tag[:root.tag.index("}") + 1] if root.tag.startswith("{") else ""
            root.find(f"{ns}Algorithm").text = "ecco"
            ec = ET.SubElement(root, f"{ns}EccoConfiguration")
            params = dict(ECCO_DEFAULTS, StepSize=step_s, **ecco)
            for key in ("SafetyFactor", "StepSize", "MinimumStepSize", "MaximumStepSize", "MinimumChangeRate",
                        "MaximumChangeRate", "ProportionalGain", "IntegralGain", "RelativeTolerance",
                        "AbsoluteTolerance"):
                ET.SubElement(ec, f"{ns}{key}").text = repr(float(params[key]))
            ET.register_namespace("", ns[1:-1])
            tree.write(osp, xml_declaration=True, encoding="utf-8")
            ex = CosimExecution.from_osp_config_file(str(osp))
        obs = CosimObserver.create_time_series(buffer_size=int(stop_ns // max(1, int(
            (ecco or {}).get("MinimumStepSize", step_s) * NS_PER_S))) + 16)
        ex.add_observer(obs)
        refs = []
        for comp, var in outputs:
            idx = ex.slave_index_from_instance_name(comp)
            if idx is None:
                raise KeyError(f"libcosim: no component {comp!r}")
            vr = {v.name.decode(): v.reference for v in ex.slave_variables(idx)}
            if var not in vr:
                raise KeyError(f"libcosim: {comp} has no variable {var!r}")
            refs.append((idx, vr[var]))
            obs.start_time_series(idx, vr[var], CosimVariableType.REAL)
        t0 = time.perf_counter()
        if not ex.simulate_until(stop_ns):
            raise RuntimeError("libcosim: the simulation stopped with an error")
        wall = time.perf_counter() - t0
        values, times = {}, None
        n_max = obs_len = int(stop_ns // max(1, int((ecco or {}).get("MinimumStepSize", step_s) * NS_PER_S))) + 16
        for (comp, var), (idx, vr) in zip(outputs, refs):
            tp, steps, samples = obs.time_series_real_samples(idx, vr, 1, n_max)
            values[(comp, var)] = np.asarray(samples, dtype=float)
            times = np.asarray(tp, dtype=np.int64)
        del obs_len
        t = times / NS_PER_S
        return SspRun("libcosim" + ("-ecco" if ecco else ""), t, np.diff(np.concatenate([[0.0], t])), values, wall)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def energy_residual(run: SspRun, bonds: Dict[str, list]) -> Dict[str, dict]:
    """Per power bond (``bonds``: :func:`bonds_of`), from the exchanged values at the communication points:
    the energy residual sum_k H_k |T_k w_(k+1) - w_k T_(k+1)| (J) -- at each step's end the power the
    torque side computes (the torque it held times the speed it reached) minus the power the speed side
    computes (the speed it held times the torque it returned), libcosim ECCO's power residual -- and the
    energy through the bond, sum_k H_k |T_k w_k| (J).  The run must hold both variables of every bond."""
    out = {}
    for name, conns in bonds.items():
        torque = speed = None
        for in_sim, in_var, out_sim, out_var in conns:
            key = (out_sim, out_var)
            if key not in run.values:
                raise KeyError(f"energy_residual: the run lacks {out_sim}.{out_var} of bond {name}")
            if "torque" in out_var:
                torque = run.values[key]
            else:
                speed = run.values[key]
        if torque is None or speed is None:
            raise KeyError(f"energy_residual: bond {name} has no torque or no speed connection")
        h = run.step_s[1:]
        res = float(np.sum(h * np.abs(torque[:-1] * speed[1:] - speed[:-1] * torque[1:])))
        through = float(np.sum(h * np.abs(torque[:-1] * speed[:-1])))
        out[name] = {"residual_J": res, "transmitted_J": through, "relative": res / through if through else 0.0}
    return out
