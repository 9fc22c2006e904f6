"""The example two-stage reducer in its three forms, run and plotted against each other.

Builds, from ``examples/scenes/gearbox_two_stage.toml``:

1. one gearbox FMU offering Co-Simulation and Model Exchange (``gearfmu build DRIVETRAIN.toml
   --interface both``),
2. the SSP of stage FMUs (``gearfmu ssp DRIVETRAIN.toml``, flange coupling),

and runs the monolithic native gearbox solver (the reference), the gearbox FMU as Co-Simulation
and as Model Exchange (fmpy's CVode) and the SSP in fmpy's SSP master.  Writes every stage's DTE
and mesh force of every form as CSV, a PNG per stage, and prints (JSON) each form's largest
difference from the native solver relative to the output's range, with its wall time.
docs/gearbox.md says which form to use where.

    python examples/gearbox_forms.py [--stop-time 0.02] [--comm-step 2e-5] [--out build/gearbox_forms]
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "examples" / "scenes" / "gearbox_two_stage.toml"
QUANTITIES = ("dte", "mesh_force")


def _host_platform():
    from gearfmu.fmu.crossbuild import host_key

    return (host_key(),)


def _on_grid(t_ref, t, y):
    """``y`` sampled at ``t`` read at the reference's times (the forms return the same
    communication points; interpolation only absorbs round-off of the time values)."""
    return np.interp(t_ref, np.asarray(t, float), np.asarray(y, float))


def run(stop_time_s: float, comm_step_s: float, out_dir: Path) -> dict:
    import fmpy

    from gearfmu import pipeline
    from gearfmu.fmu.composition import compose
    from gearfmu.fmu.ssp_engines import run_fmpy
    from gearfmu.ssp import ssp_from_drivetrain

    out_dir.mkdir(parents=True, exist_ok=True)
    _, scene = pipeline.load_any(SCENE)
    model = pipeline.gearbox_model(scene, pipeline.stage_tables(scene, progress=True))
    stages = [s.name for s in scene.stages]
    names = [f"{s}.{q}" for s in stages for q in QUANTITIES]
    plat = _host_platform()

    # the reference: the native gearbox solver at the same communication points
    t0 = time.perf_counter()
    native = pipeline.simulate_drivetrain(scene, model, stop_time_s=stop_time_s, comm_step_s=comm_step_s)
    forms = {"native": (native.time_s, {n: native[n] for n in names}, time.perf_counter() - t0)}

    # one FMU of the whole gearbox, both interfaces
    fmu = pipeline.build_drivetrain_fmu(scene, out_dir / f"{scene.model_name}.fmu", platforms=plat,
                                        validation=False, model_exchange={"interface": "both"}).fmu_path
    for label, kw in (("gearbox FMU, Co-Simulation", dict(fmi_type="CoSimulation")),
                      ("gearbox FMU, Model Exchange (CVode)",
                       dict(fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-8))):
        t0 = time.perf_counter()
        res = fmpy.simulate_fmu(str(fmu), stop_time=stop_time_s, output_interval=comm_step_s, output=names, **kw)
        forms[label] = (res["time"], {n: res[n] for n in names}, time.perf_counter() - t0)

    # the SSP of stage FMUs
    s = pipeline.gearbox_fmu_settings(scene, model)
    ssp = ssp_from_drivetrain(scene, out_dir / f"{scene.model_name}.ssp", comm_step_s=comm_step_s, platforms=plat,
                              model=model)
    comp = compose(model, motor_torque_Nm=s.motor_torque_start_Nm, load_torque_Nm=s.load_torque_start_Nm,
                   motor_speed_rad_s=s.motor_speed_start_rad_s, max_step_s=s.max_step_s, integrator=s.integrator)
    t0 = time.perf_counter()
    r = run_fmpy(ssp, stop_time_s=stop_time_s, step_s=comm_step_s, outputs=[comp.outputs[n] for n in names])
    t_ssp = comm_step_s * np.arange(1, len(r[comp.outputs[names[0]]]) + 1)
    forms["SSP of stage FMUs (fmpy)"] = (t_ssp, {n: r[comp.outputs[n]] for n in names}, time.perf_counter() - t0)

    # differences from the native solver, relative to the range of each output
    t_ref, ref, _ = forms["native"]
    summary = {"scene": SCENE.name, "stop_time_s": stop_time_s, "comm_step_s": comm_step_s, "forms": {}}
    for label, (t, ys, wall) in forms.items():
        if label == "native":
            summary["forms"][label] = {"wall_s": wall}
            continue
        lo = t_ref >= (t[0] - 1e-12)          # the SSP's rows start at the first step
        err = {n: float(np.max(np.abs(_on_grid(t_ref[lo], t, ys[n]) - ref[n][lo])) / np.ptp(ref[n][lo]))
               for n in names}
        summary["forms"][label] = {"wall_s": wall, "max_error_over_range": err}

    # CSV and PNG
    header = ["time"] + [f"{label}: {n}" for label in forms for n in names]
    cols = [t_ref] + [_on_grid(t_ref, forms[label][0], forms[label][1][n]) for label in forms for n in names]
    np.savetxt(out_dir / "gearbox_forms.csv", np.column_stack(cols), delimiter=",", header=",".join(header),
               comments="# units: s, then m (dte) and N (mesh_force)\n")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    for stage in stages:
        fig, axes = plt.subplots(len(QUANTITIES), 1, figsize=(8, 6), sharex=True)
        for ax, q, unit in zip(axes, QUANTITIES, ("m", "N")):
            for label, (t, ys, _) in forms.items():
                ax.plot(np.asarray(t) * 1e3, ys[f"{stage}.{q}"], label=label,
                        lw=2.5 if label == "native" else 1.0, ls="-" if label == "native" else "--")
            ax.set_ylabel(f"{q} [{unit}]")
        axes[0].set_title(f"{scene.name}, {stage}: three forms against the native solver")
        axes[-1].set_xlabel("time [ms]")
        axes[0].legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(out_dir / f"gearbox_forms_{stage}.png", dpi=110)
        plt.close(fig)
    (out_dir / "gearbox_forms.json").write_text(json.dumps(summary, indent=1))
    return summary


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--stop-time", type=float, default=0.02, help="simulated time [s]")
    ap.add_argument("--comm-step", type=float, default=2e-5, help="communication step [s]")
    ap.add_argument("--out", type=Path, default=ROOT / "build" / "gearbox_forms", help="output folder")
    a = ap.parse_args(argv)
    summary = run(a.stop_time, a.comm_step, a.out)
    print(json.dumps(summary, indent=1))
    print(f"wrote {a.out}/gearbox_forms.csv, .json and a PNG per stage", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
