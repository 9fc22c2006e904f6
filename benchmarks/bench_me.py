"""Model Exchange: error against the host's tolerance and cost (docs/standalone.md "Model Exchange").

Prints JSON (stdout); progress on stderr.  Per case (the default scene's computed tables at its
operating point, and the hard case with contact loss and impacts on both flanks of
gearfmu.bench.HARD_CASES):

* the reference: gearfmu.dynamics.reference (event-located solve_ivp DOP853, rtol 1e-11) at 128
  steps per shortest natural period, and at its default 64 to show how far the reference itself is
  settled (``reference_self_err``: its steps are capped, so the cap rather than rtol sets its error);
* the standalone FMU as FMI 2 Model Exchange, run by fmpy's CVode (BDF, its absolute tolerance
  the relative one times the FMU's nominal state values) at rtol 1e-4, 1e-6, 1e-8, for each choice
  of table-node events (none, the big kinks, every bent node; ``gearfmu build --me-node-events``);
* the native solver (rk4_node) at the scene's internal step, for the cost of the same run in C
  inside numba;
* the same standalone FMU as FMI 2 Co-Simulation (its own rk4_node at the same internal step) run by
  fmpy at the communication step, for the cost of Model Exchange against Co-Simulation in one host.

Each row: the largest and the RMS difference of the DTE and of the mesh force over the
communication instants, relative to the reference's range; the number of events the host handled;
the wall time of the whole ``fmpy.simulate_fmu`` call (one run).  A row whose host stopped (CVode's
step limit per output interval) says so in ``failed``.

Usage: python benchmarks/bench_me.py [--cases default,double_sided_impacts] [--rtols 1e-4,1e-6,1e-8]
"""
import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from gearfmu.bench import hard_case
from gearfmu.common.vocabulary import ME_NODE_EVENTS
from gearfmu.dynamics.native import choose_max_step_s, simulate
from gearfmu.dynamics.reference import simulate_reference
from gearfmu.fmu.standalone_build import build_standalone_fmu
from gearfmu.stages import gear_torque_for

#: case name -> gearfmu.bench hard case
CASES = {"default": "computed_default_scene", "double_sided_impacts": "double_sided_impacts"}
RTOLS = (1e-4, 1e-6, 1e-8)


def say(msg):
    print(f"bench_me: {msg}", file=sys.stderr, flush=True)


def errors(dte, force, ref) -> dict:
    """Max and RMS |x - ref| of the DTE and mesh force over the instants, relative to the reference's range."""
    out = {}
    for key, x, r in (("dte", dte, ref.dte), ("force", force, ref.mesh_force)):
        x, r = np.asarray(x, float), np.asarray(r, float)
        n = min(len(x), len(r))
        d = np.abs(x[:n] - r[:n]) / max(float(np.ptp(r)), 1e-300)
        out[f"{key}_rel_max_err"] = float(np.max(d)) if n else float("nan")
        out[f"{key}_rel_rms_err"] = float(np.sqrt(np.mean(d ** 2))) if n else float("nan")
    return out


def quiet(*args):
    """fmpy's logger: the FMU's messages (the envelope warning of tables with one torque row) are not results."""


def on_grid(res, times):
    """The rows of an fmpy result (events recorded) at the communication instants ``times``."""
    t = res["time"]
    idx = [int(np.argmin(np.abs(t - tk))) for tk in times]
    return res[idx]


def run_case(name: str, rtols, tmp: Path) -> dict:
    tables, kw = hard_case(CASES[name])
    T1 = float(np.atleast_1d(kw["pinion_torque_Nm"])[0])
    T2 = gear_torque_for(tables, T1)
    kw = dict(kw, gear_torque_Nm=T2)
    H, stop = kw["comm_step_s"], kw["stop_time_s"]
    say(f"{name}: reference (DOP853, rtol 1e-11, 128 and 64 steps per natural period)")
    t0 = time.perf_counter()
    ref = simulate_reference(tables, rtol=1e-11, steps_per_period=128.0, **kw)
    ref_wall = time.perf_counter() - t0
    ref64 = simulate_reference(tables, rtol=1e-11, steps_per_period=64.0, **kw)
    times = np.asarray(ref.time_s)
    h = choose_max_step_s(tables, 1.5 * max(abs(kw["pinion_speed_start_rad_s"]), 1.0))
    simulate(tables, max_step_s=h, **kw)   # compiled first, then timed
    t0 = time.perf_counter()
    nat = simulate(tables, max_step_s=h, **kw)
    nat_wall = time.perf_counter() - t0
    rows = [dict(host="native rk4_node", setting=f"h={h:.3g} s", wall_s=nat_wall, events=None,
                 **errors(nat.dte, nat.mesh_force, ref))]
    import fmpy
    say(f"{name}: the Co-Simulation FMU (rk4_node inside, h = {h:.3g} s)")
    cs = build_standalone_fmu(tables, tmp / f"{name}_cs.fmu", pinion_speed_start_rad_s=kw["pinion_speed_start_rad_s"],
                              pinion_torque_start_Nm=T1, gear_torque_start_Nm=T2, damping_ratio=kw["damping_ratio"],
                              damping_model=kw.get("damping_model", "elastobacklash"),
                              pinion_angle_start_rad=kw.get("pinion_angle_start_rad", 0.0), max_step_s=h,
                              stop_time_s=stop, output_interval_s=H, platforms=["x86_64-linux"], validation=False,
                              interface="cs")
    fmpy.simulate_fmu(str(cs), fmi_type="CoSimulation", stop_time=stop, output_interval=H, output=["dte"],
                      logger=quiet)   # the files extracted and the library loaded once before the timed run
    t0 = time.perf_counter()
    res = fmpy.simulate_fmu(str(cs), fmi_type="CoSimulation", stop_time=stop, output_interval=H,
                            output=["dte", "mesh_force"], logger=quiet)
    rows.append(dict(host="fmpy Co-Simulation", setting=f"rk4_node h={h:.3g} s", wall_s=time.perf_counter() - t0,
                     events=None, **errors(res["dte"], res["mesh_force"], ref)))
    for ne in ME_NODE_EVENTS:
        say(f"{name}: FMU with node events {ne!r}")
        path = build_standalone_fmu(tables, tmp / f"{name}_{ne}.fmu", pinion_speed_start_rad_s=kw["pinion_speed_start_rad_s"],
                                    pinion_torque_start_Nm=T1, gear_torque_start_Nm=T2, damping_ratio=kw["damping_ratio"],
                                    damping_model=kw.get("damping_model", "elastobacklash"),
                                    pinion_angle_start_rad=kw.get("pinion_angle_start_rad", 0.0), max_step_s=h,
                                    stop_time_s=stop, output_interval_s=H, platforms=["x86_64-linux"], validation=False,
                                    interface="me", me_node_events=ne)
        for rtol in rtols:
            say(f"{name}: fmpy CVode rtol {rtol:g}, node events {ne!r}")
            row = dict(host="fmpy CVode", setting=f"rtol={rtol:g}", node_events=ne, rtol=rtol)
            t0 = time.perf_counter()
            try:
                res = fmpy.simulate_fmu(str(path), fmi_type="ModelExchange", solver="CVode", relative_tolerance=rtol,
                                        stop_time=stop, output_interval=H, output=["dte", "mesh_force"],
                                        record_events=True, logger=quiet)
            except Exception as exc:  # noqa: BLE001 -- the host's own failure is a result
                row.update(wall_s=time.perf_counter() - t0, failed=f"{type(exc).__name__}: {str(exc)[:160]}")
                rows.append(row)
                continue
            row["wall_s"] = time.perf_counter() - t0
            row["events"] = int(np.sum(np.diff(res["time"]) == 0.0))
            g = on_grid(res, times)
            row.update(errors(g["dte"], g["mesh_force"], ref))
            rows.append(row)
    return dict(case=name, hard_case=CASES[name], stop_time_s=stop, comm_step_s=H, reference_wall_s=ref_wall,
                reference_self_err=errors(ref64.dte, ref64.mesh_force, ref), rows=rows)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--rtols", default=",".join(f"{r:g}" for r in RTOLS))
    a = ap.parse_args(argv)
    cases = [c for c in a.cases.split(",") if c]
    bad = [c for c in cases if c not in CASES]
    if bad:
        print(f"bench_me: --cases: unknown {bad} (known: {', '.join(CASES)})", file=sys.stderr)
        return 2
    rtols = tuple(float(r) for r in a.rtols.split(","))
    with tempfile.TemporaryDirectory(prefix="bench_me_") as tmp:
        out = [run_case(c, rtols, Path(tmp)) for c in cases]
    print(json.dumps({"host": "fmpy CVode", "cases": out}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
