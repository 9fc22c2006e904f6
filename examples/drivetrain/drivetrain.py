"""Drivetrain co-simulation: speed-controlled motor -> gear FMU -> load inertia with drag.

Three separate FMUs: the motor (PI speed control, torque out; motor_fmu.py)
and the load (inertia + drag behind a torsional shaft; load_fmu.py), both
small pythonfmu FMUs, and the gear pair FMU of the default scene built with
BOTH gearfmu runtimes (pythonfmu and standalone C).  Each combination runs
under two independent masters: an fmpy master loop (below) and libcosimpy
(Open Simulation Platform).  Scenario: run-up from standstill to full speed
(ramped set-point, 0.4 s), then a load step at 0.6 s -- the angle-indexed
tables are swept at varying speed, starting at omega = 0.

Coupling (Jacobi, communication step H; every FMU sees the others' outputs of
the previous communication point):
    motor.torque -> gear.pinion_torque        gear.pinion_speed -> motor.speed
    load.shaft_torque -> gear.gear_torque     gear.gear_angle/gear_speed -> load.shaft_angle/shaft_speed

Outputs (examples/output/drivetrain/): drivetrain_<master>_<runtime>.csv,
drivetrain.png (speeds, DTE, mesh force; both runtimes overlaid, both
masters), drivetrain.json (per-signal largest difference between the
runtimes and between the masters, wall times).

    python examples/drivetrain/drivetrain.py [--stop-time 0.9] [--step 1e-4]
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
OUT = HERE.parent / "output" / "drivetrain"
GEAR_OUT = ["pinion_speed", "gear_speed", "pinion_angle", "gear_angle", "dte", "mesh_force", "mesh_stiffness"]


def build_all(out: Path):
    """The motor and load FMUs (pythonfmu) and the gear FMU of the default scene in both runtimes."""
    from pythonfmu import FmuBuilder

    from gearfmu.fmu.pythonfmu_build import build_fmu
    from gearfmu.dynamics.native import choose_max_step_s
    from gearfmu.pipeline import compute_tables, load
    from gearfmu.fmu.standalone_build import build_standalone_fmu

    out.mkdir(parents=True, exist_ok=True)
    fmus = {}
    for script in ("motor_fmu.py", "load_fmu.py"):
        FmuBuilder.build_FMU(HERE / script, dest=out)
        fmus[script.split("_")[0]] = out / {"motor_fmu.py": "SpeedMotor.fmu", "load_fmu.py": "LoadInertia.fmu"}[script]
    scene = load(None)
    tables = compute_tables(scene)
    kw = dict(model_name="gear_drivetrain", damping_ratio=scene.fmu.damping_ratio, pinion_speed_start_rad_s=0.0,
              pinion_torque_start_Nm=0.0, gear_torque_start_Nm=0.0,
              max_step_s=choose_max_step_s(tables, 1.3 * scene.operating.speed_rad_s),
              stop_time_s=1.0, output_interval_s=1e-4, damping_model=scene.solver.damping_model)
    fmus["gear_pythonfmu"] = build_fmu(tables, out / "gear_pythonfmu.fmu", **kw)
    fmus["gear_standalone"] = build_standalone_fmu(tables, out / "gear_standalone.fmu", **kw)
    return fmus, scene


def run_fmpy(fmus, gear_key, stop, H, progress=True):
    """An fmpy master loop (FMU2Slave, Jacobi coupling)."""
    import fmpy
    from fmpy.fmi2 import FMU2Slave

    sl, vr = {}, {}
    for key in ("motor", gear_key, "load"):
        md = fmpy.read_model_description(str(fmus[key]))
        d = fmpy.extract(str(fmus[key]))
        s = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName=key)
        s.instantiate()
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        s.exitInitializationMode()
        sl[key] = s
        vr[key] = {v.name: v.valueReference for v in md.modelVariables}
    m, g, l = sl["motor"], sl[gear_key], sl["load"]
    vm, vg, vl = vr["motor"], vr[gear_key], vr["load"]
    gout = [vg[n] for n in GEAR_OUT]
    n = int(round(stop / H))
    rows = np.zeros((n + 1, 1 + len(GEAR_OUT) + 3))
    t0 = time.perf_counter()
    for k in range(n + 1):
        go = g.getReal(gout)
        tm, wref = m.getReal([vm["torque"], vm["speed_ref"]])
        ts, wl = l.getReal([vl["shaft_torque"], vl["load_speed"]])
        rows[k] = [k * H, *go, tm, ts, wl]
        if k == n:
            break
        m.setReal([vm["speed"]], [go[0]])
        g.setReal([vg["pinion_torque"], vg["gear_torque"]], [tm, ts])
        l.setReal([vl["shaft_angle"], vl["shaft_speed"]], [go[3], go[1]])
        for s in (m, g, l):
            s.doStep(k * H, H)
        if progress and k % 1000 == 0:
            print(f"  fmpy/{gear_key}: t = {k * H:.3f} s, pinion {go[0]:7.2f} rad/s", flush=True)
    wall = time.perf_counter() - t0
    for s in sl.values():
        s.terminate()
        s.freeInstance()
    return rows, wall


LIBCOSIM = r"""
import json, sys
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
from libcosimpy.CosimObserver import CosimObserver
from libcosimpy.CosimSlave import CosimLocalSlave
log_output_level(CosimLogLevel.ERROR)
motor, gear, load, step_ns, n = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5])
names = json.loads(sys.argv[6])
ex = CosimExecution.from_step_size(step_ns)
idx = {k: ex.add_local_slave(CosimLocalSlave(fmu_path=p, instance_name=k)) for k, p in
       (("motor", motor), ("gear", gear), ("load", load))}
vr = {k: {v.name.decode(): v.reference for v in ex.slave_variables(i)} for k, i in idx.items()}
def c(a, an, b, bn):
    ex.connect_real_variables(idx[a], vr[a][an], idx[b], vr[b][bn])
c("motor", "torque", "gear", "pinion_torque"); c("gear", "pinion_speed", "motor", "speed")
c("load", "shaft_torque", "gear", "gear_torque"); c("gear", "gear_angle", "load", "shaft_angle")
c("gear", "gear_speed", "load", "shaft_speed")
obs = CosimObserver.create_last_value()
ex.add_observer(obs)
rows = []
for k in range(n):
    assert ex.step()
    g = obs.last_real_values(idx["gear"], [vr["gear"][x] for x in names])
    m = obs.last_real_values(idx["motor"], [vr["motor"]["torque"]])
    l = obs.last_real_values(idx["load"], [vr["load"]["shaft_torque"], vr["load"]["load_speed"]])
    rows.append([(k + 1) * step_ns * 1e-9, *g, *m, *l])
print(json.dumps(rows))
"""


def run_libcosim(fmus, gear_key, stop, H):
    import subprocess

    n = int(round(stop / H))
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-c", LIBCOSIM, str(fmus["motor"]), str(fmus[gear_key]), str(fmus["load"]),
                        str(int(round(H * 1e9))), str(n), json.dumps(GEAR_OUT)],
                       capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(f"libcosimpy run failed (exit {p.returncode}):\n{p.stderr[-3000:]}")
    return np.array(json.loads(p.stdout.strip().splitlines()[-1])), time.perf_counter() - t0


COLUMNS = ["time", *GEAR_OUT, "motor_torque", "shaft_torque", "load_speed"]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--stop-time", type=float, default=0.9)
    ap.add_argument("--step", type=float, default=1e-4, help="communication step, s")
    a = ap.parse_args(argv)
    print("building FMUs ...", flush=True)
    fmus, scene = build_all(OUT)
    runs, walls = {}, {}
    for rt in ("pythonfmu", "standalone"):
        key = f"gear_{rt}"
        print(f"fmpy master, gear runtime {rt}", flush=True)
        runs[("fmpy", rt)], walls[f"fmpy_{rt}"] = run_fmpy(fmus, key, a.stop_time, a.step)
        print(f"libcosimpy master, gear runtime {rt}", flush=True)
        runs[("libcosim", rt)], walls[f"libcosim_{rt}"] = run_libcosim(fmus, key, a.stop_time, a.step)
    for (master, rt), rows in runs.items():
        np.savetxt(OUT / f"drivetrain_{master}_{rt}.csv", rows, delimiter=",", header=",".join(COLUMNS), comments="")
    summary = {"stop_time_s": a.stop_time, "step_s": a.step, "wall_s": walls, "runtime_difference": {},
               "master_difference": {}}
    for master in ("fmpy", "libcosim"):
        x, y = runs[(master, "pythonfmu")], runs[(master, "standalone")]
        summary["runtime_difference"][master] = {
            c: float(np.max(np.abs(x[:, i] - y[:, i])) / max(np.ptp(x[:, i]), 1e-300)) for i, c in enumerate(COLUMNS)}
    x, y = runs[("fmpy", "standalone")][1:], runs[("libcosim", "standalone")]
    summary["master_difference"]["standalone_fmpy_vs_libcosim"] = {
        c: float(np.max(np.abs(x[:, i] - y[:, i])) / max(np.ptp(x[:, i]), 1e-300)) for i, c in enumerate(COLUMNS)}
    (OUT / "drivetrain.json").write_text(json.dumps(summary, indent=1))
    plot(runs, OUT / "drivetrain.png", scene)
    print(json.dumps(summary["runtime_difference"]["fmpy"], indent=1))
    print(f"wrote {OUT / 'drivetrain.png'}, CSVs and drivetrain.json")


def plot(runs, path, scene):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    styles = {("fmpy", "pythonfmu"): dict(color="C0", lw=2.0, alpha=0.5),
              ("fmpy", "standalone"): dict(color="C1", lw=0.8, ls="--"),
              ("libcosim", "pythonfmu"): dict(color="C2", lw=2.0, alpha=0.4),
              ("libcosim", "standalone"): dict(color="C3", lw=0.8, ls=":")}
    for key, r in runs.items():
        lab = f"{key[0]} master, gear FMU {key[1]}"
        st = styles[key]
        ax[0].plot(r[:, 0], r[:, 1], label=f"pinion, {lab}", **st)
        ax[0].plot(r[:, 0], r[:, 2], **st)
        ax[0].plot(r[:, 0], r[:, 10], **st)
        ax[1].plot(r[:, 0], r[:, 5] * 1e6, **st, label=lab)
        ax[2].plot(r[:, 0], r[:, 6] / 1e3, **st, label=lab)
    ax[0].set_ylabel("speed (rad/s)\npinion, gear, load")
    ax[1].set_ylabel("DTE (um)")
    ax[2].set_ylabel("mesh force (kN)")
    ax[2].set_xlabel("time (s)")
    ax[0].set_title(f"Drivetrain run-up and load step: motor + gear ({scene.name}) + load inertia")
    ax[1].legend(fontsize=7)
    for a_ in ax:
        a_.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


if __name__ == "__main__":
    main()
