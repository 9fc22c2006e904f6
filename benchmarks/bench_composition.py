#!/usr/bin/env python3
"""Composition accuracy: the SSP of stage FMUs against the monolithic gearbox, over the communication step (JSON).

    python benchmarks/bench_composition.py [--scene DRIVETRAIN.toml] [--sim 0.02] [--steps 1e-6,...,1e-4]
                                           [--repeat 3]

For the example two-stage reducer (docs/gearbox.md "The SSP of stage FMUs"), every form runs ``--sim``
simulated seconds from the quasi-static state (the meshing errors and the mesh stiffness excite both stages)
and is compared with the native gearbox solver at a 1e-6 s communication step (the same internal step rule
and integrator; read at each run's communication points):

* ``flange`` (the default coupling: every shaft inside the stage FMU of the light body it drives, the
  flange moving on the parabola of the last two speeds received) in fmpy's SSP master and in libcosim,
  at every communication step of ``--steps``;
* ``flange_linear`` (the flange at the speed received over the step; flange_order 1) in libcosim;
* ``shaft`` (the stages take torques at their pinion and gear; shaft FMUs integrate the exchanged speeds
  and return the predicted torque) in libcosim;
* ``flange`` under libcosim's energy-conserving algorithm ECCO (Sadjina & Pedersen 2020) at tolerances
  1e-2 .. 1e-5 (steps 1e-6 .. 1e-4 s; the "step" of such a run is its mean step);
* the monolithic gearbox FMU (``gearfmu build``) in fmpy (its low-level API, a Python loop) and in
  libcosim, at every step (its error is the integrator's alone: it does every stage in one FMU).

Per run: RMS(x - x_native) / peak-to-peak(x_native) of each stage's DTE and mesh force, the energy residual
at the power bonds (libcosim ECCO's, relative to the energy through the bond; gearfmu.fmu.ssp_engines),
the wall time and the process CPU time (each the best of ``--repeat``; the machine is shared, CPU time
is the steadier) per simulated second; a run that stops with an
error or leaves the range by more than 10x is "diverged".  Derived: per form, the communication step
and cost where the worse stage's DTE and mesh-force error reach 1 % and 0.1 % (log-log interpolation
between the two steps around it), and the monolithic FMU's cost at the scene's communication step beside.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
STEPS = (1e-6, 2e-6, 5e-6, 1e-5, 2e-5, 5e-5, 1e-4)
#: CVode's relative tolerance for the Model Exchange runs of the gearbox FMU
ME_RTOL = 1e-8
TOLERANCES = (1e-2, 1e-3, 1e-4, 1e-5)
TARGETS = (1e-2, 1e-3)


def _err(x, ref) -> float:
    return float(np.sqrt(np.mean((np.asarray(x) - ref) ** 2)) / np.ptp(ref))


def _errors(time_s, values, ref, cols, outputs):
    """{column: RMS error / range} against the native run ``ref``, read at ``time_s``."""
    out = {}
    for c in cols:
        y = np.interp(time_s, ref.time_s, ref[c])
        out[c] = _err(values[outputs[c]], y)
    return out


def _gearbox_fmu_libcosim(path, names, *, stop_s, step_s):
    """(wall s, communication points s, {name: values}, CPU s) of one FMU alone in libcosim at a fixed step."""
    from libcosimpy.CosimEnums import CosimVariableType  # libcosim: only to run it
    from libcosimpy.CosimExecution import CosimExecution  # libcosim: only to run it
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level  # libcosim: only to run it
    from libcosimpy.CosimObserver import CosimObserver  # libcosim: only to run it
    from libcosimpy.CosimSlave import CosimLocalSlave  # libcosim: only to run it

    log_output_level(CosimLogLevel.ERROR)
    h_ns = int(round(step_s * 1e9))
    n = int(round(stop_s / step_s))
    ex = CosimExecution.from_step_size(h_ns)
    i = ex.add_local_slave(CosimLocalSlave(str(path), "gearbox"))
    vr = {v.name.decode(): v.reference for v in ex.slave_variables(i)}
    obs = CosimObserver.create_time_series(buffer_size=n + 16)
    ex.add_observer(obs)
    for nm in names:
        obs.start_time_series(i, vr[nm], CosimVariableType.REAL)
    t0, c0 = time.perf_counter(), time.process_time()
    if not ex.simulate_until(n * h_ns):
        raise RuntimeError("libcosim stopped with an error")
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    out = {}
    for nm in names:
        tp, _, samples = obs.time_series_real_samples(i, vr[nm], 1, n + 16)
        out[nm] = np.asarray(samples)
    return wall, np.asarray(tp) / 1e9, out, cpu


def at_error(points, key, target):
    """(step s, wall and CPU per simulated s) where ``key(point)`` reaches ``target`` with the error rising
    with the step: log-log interpolation between the last step below and the first above; None outside
    the sweep."""
    pts = sorted((p for p in points if not p.get("diverged")), key=lambda p: p["step_s"])

    def lerp(a, b, t, k):
        return math.exp(math.log(a[k]) + t * (math.log(b[k]) - math.log(a[k])))

    if pts and key(pts[-1]) <= target:
        bad = [p["step_s"] for p in points if p.get("diverged") and p["step_s"] > pts[-1]["step_s"]]
        return {"step_s": None, "below_at_largest_step": pts[-1]["step_s"], "wall_per_sim_s": pts[-1]["wall_per_sim_s"],
                "cpu_per_sim_s": pts[-1]["cpu_per_sim_s"], "diverged_from_s": min(bad) if bad else None}
    for a, b in zip(pts, pts[1:]):
        ea, eb = key(a), key(b)
        if ea <= target <= eb and eb > ea > 0:
            t = (math.log(target) - math.log(ea)) / (math.log(eb) - math.log(ea))
            return {"step_s": lerp(a, b, t, "step_s"), "wall_per_sim_s": lerp(a, b, t, "wall_per_sim_s"),
                    "cpu_per_sim_s": lerp(a, b, t, "cpu_per_sim_s")}
    return None


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default=str(ROOT / "examples" / "scenes" / "gearbox_two_stage.toml"))
    ap.add_argument("--sim", type=float, default=0.02, help="simulated seconds per run")
    ap.add_argument("--steps", default=",".join(repr(h) for h in STEPS), help="communication steps (s)")
    ap.add_argument("--repeat", type=int, default=5, help="runs per setting (best wall and CPU time)")
    args = ap.parse_args(argv)
    steps = [float(x) for x in args.steps.split(",")]

    from gearfmu import pipeline
    from gearfmu.fmu.composition import compose
    from gearfmu.fmu.crossbuild import host_key
    from gearfmu.fmu.gearbox_build import build_gearbox_fmu
    from gearfmu.fmu.gearbox_compare import step_fmu
    from gearfmu.fmu.ssp_engines import bond_outputs, bonds_of, energy_residual, run_fmpy, run_libcosim
    from gearfmu.ssp import gearbox_ssp

    _, scene = pipeline.load_any(args.scene)
    model = pipeline.gearbox_model(scene, pipeline.stage_tables(scene))
    s = pipeline.gearbox_fmu_settings(scene, model)
    sim = args.sim
    stages = [m.name for m in model.meshes]
    cols = [f"{m}.{q}" for m in stages for q in ("dte", "mesh_force")]
    kw = dict(motor_torque_Nm=s.motor_torque_start_Nm, load_torque_Nm=s.load_torque_start_Nm,
              motor_speed_rad_s=s.motor_speed_start_rad_s, max_step_s=s.max_step_s, integrator=s.integrator)
    print(f"bench_composition: {scene.name}, {sim:g} s simulated, steps {steps}", file=sys.stderr)
    ref = pipeline.simulate_drivetrain(scene, model, stop_time_s=sim, comm_step_s=1e-6)
    out = {"scene": scene.name, "sim_s": sim, "steps_s": steps, "repeat": args.repeat, "max_step_s": s.max_step_s,
           "integrator": s.integrator, "scene_comm_step_s": s.output_interval_s,
           "reference": "native gearbox solver at a 1e-6 s communication step",
           "error": "RMS(x - x_native) / peak-to-peak(x_native) at the run's communication points",
           "cost": "wall time and process CPU time per simulated second, each the best of the runs", "forms": {}}

    def record(form, step, run_fn, comp=None, bonds=None):
        best, best_cpu, run, diverged = None, None, None, None
        for _ in range(args.repeat):
            try:
                r = run_fn()
            except (RuntimeError, KeyError, ValueError) as exc:
                diverged = str(exc).splitlines()[0][:200]
                break
            best = r.wall_s if best is None else min(best, r.wall_s)
            best_cpu = r.cpu_s if best_cpu is None else min(best_cpu, r.cpu_s)
            run = r
        row = {"step_s": step}
        if run is None:
            row.update(diverged=diverged)
        else:
            errs = _errors(run.time_s, run.values, ref, cols, comp.outputs)
            if not all(math.isfinite(e) and e < 10.0 for e in errs.values()):
                row.update(diverged="the outputs left the native range by more than 10x", errors=errs)
            else:
                row.update(errors=errs, dte_worst=max(errs[f"{m}.dte"] for m in stages),
                           force_worst=max(errs[f"{m}.mesh_force"] for m in stages),
                           wall_per_sim_s=best / sim, cpu_per_sim_s=best_cpu / sim, comm_points=len(run.time_s),
                           mean_step_s=float(run.time_s[-1] / len(run.time_s)))
                if bonds:
                    er = energy_residual(run, bonds)
                    row["energy_residual"] = {b: v["relative"] for b, v in er.items()}
                    row["energy_residual_worst"] = max(v["relative"] for v in er.values())
        out["forms"].setdefault(form, []).append(row)
        print(f"  {form} H={step:g}: " + ("diverged" if row.get("diverged") else
              f"DTE {row['dte_worst']:.2e}, force {row['force_worst']:.2e}, {row['wall_per_sim_s']:.3g} s/s"),
              file=sys.stderr)

    with tempfile.TemporaryDirectory(prefix="gearfmu_bench_comp_") as tmpd:
        tmp = Path(tmpd)
        plat = (host_key(),)
        ssps, comps = {}, {}
        for form, coupling, order in (("flange", "flange", 2), ("flange_linear", "flange", 1), ("shaft", "shaft", 2)):
            comps[form] = compose(model, coupling=coupling, flange_order=order, **kw)
            ssps[form] = gearbox_ssp(comps[form], tmp / f"{form}.ssp", stop_time_s=sim,
                                     comm_step_s=s.output_interval_s, platforms=plat)
        bonds = {f: bonds_of(p) for f, p in ssps.items()}
        outs = {f: [c.outputs[col] for col in cols] + bond_outputs(bonds[f]) for f, c in comps.items()}
        for h in steps:
            record("flange/fmpy", h, lambda: run_fmpy(ssps["flange"], stop_time_s=sim, step_s=h, outputs=outs["flange"]),
                   comps["flange"], bonds["flange"])
            for form in ("flange", "flange_linear", "shaft"):
                record(f"{form}/libcosim", h, lambda: run_libcosim(ssps[form], stop_time_s=sim, step_s=h,
                                                                   outputs=outs[form]), comps[form], bonds[form])
        for tol in TOLERANCES:
            ecco = {"rel_tolerance": tol, "abs_tolerance": tol, "min_step_size": 1e-6, "max_step_size": 1e-4}
            record("flange/libcosim-ecco", tol, lambda: run_libcosim(ssps["flange"], stop_time_s=sim, step_s=1e-5,
                                                                     outputs=outs["flange"], ecco=ecco),
                   comps["flange"], bonds["flange"])
            out["forms"]["flange/libcosim-ecco"][-1]["tolerance"] = tol
            if "mean_step_s" in out["forms"]["flange/libcosim-ecco"][-1]:
                out["forms"]["flange/libcosim-ecco"][-1]["step_s"] = out["forms"]["flange/libcosim-ecco"][-1]["mean_step_s"]
        # ---------------------------------------------------------------- the monolithic gearbox FMU
        gb = build_gearbox_fmu(model, tmp / "gearbox.fmu", settings=dataclasses.replace(s, stop_time_s=sim),
                               model_name="bench_gearbox", platforms=plat, validation=False,
                               model_exchange={"interface": "both"})
        names = cols

        class _Run:
            def __init__(self, wall, t, values, cpu):
                self.wall_s, self.time_s, self.values, self.cpu_s = wall, t, values, cpu

        mono = type("M", (), {"outputs": {c: c for c in cols}})()
        for h in steps:
            def fmpy_run():
                c0 = time.process_time()   # with the FMU's unpacking and instantiation, as fmpy's SSP runs
                r = step_fmu(gb, names, stop_time_s=sim, comm_step_s=h)
                return _Run(r.wall_s, r.time_s[1:], {c: np.asarray(r.columns[c][1:]) for c in names},
                            time.process_time() - c0)
            record("gearbox_fmu/fmpy", h, fmpy_run, mono)
            record("gearbox_fmu/libcosim", h, lambda: _Run(*_gearbox_fmu_libcosim(gb, names, stop_s=sim, step_s=h)), mono)

            def me_run():
                # Model Exchange: fmpy's CVode integrates the gearbox's own equations and events; the
                # communication step is only where the outputs are read
                import fmpy
                c0, t0 = time.process_time(), time.perf_counter()
                r = fmpy.simulate_fmu(str(gb), fmi_type="ModelExchange", solver="CVode", relative_tolerance=ME_RTOL,
                                      stop_time=sim, output_interval=h, output=names)
                return _Run(time.perf_counter() - t0, r["time"][1:], {c: np.asarray(r[c][1:]) for c in names},
                            time.process_time() - c0)
            record("gearbox_fmu_me/fmpy-cvode", h, me_run, mono)
    for form, rows in out["forms"].items():
        for key, what in (("dte_worst", "dte"), ("force_worst", "mesh_force")):
            for target in TARGETS:
                out.setdefault("at_error", {}).setdefault(form, {})[f"{what}_{target:g}"] = at_error(
                    rows, lambda p, k=key: p[k], target)
    mono_rows = {r["step_s"]: r for r in out["forms"]["gearbox_fmu/libcosim"] if not r.get("diverged")}
    at_scene = mono_rows.get(s.output_interval_s)
    out["gearbox_fmu_at_scene_step"] = at_scene
    print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
