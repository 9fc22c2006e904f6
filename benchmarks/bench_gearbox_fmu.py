#!/usr/bin/env python3
"""The gearbox FMU against its stages' pair FMUs: cost per simulated second through a C host (JSON).

    python benchmarks/bench_gearbox_fmu.py [--scene DRIVETRAIN.toml] [--sim 0.1] [--repeat 5]

Goal (docs/gearbox.md "The gearbox FMU"): the gearbox FMU costs at most 1.3 x the sum of its stages'
pair FMUs per simulated second, at the same accuracy.  Built here for this machine only:

* the gearbox FMU of the drivetrain scene (``gearfmu build DRIVETRAIN.toml``'s FMU: its integrator and
  internal step rule, 64 points per shortest period of every stage and of the gearbox's modes);
* each stage's pair FMU (the standalone runtime) on the same tables at the stage's operating point in
  the gearbox (pinion speed g_p x the motor speed, pinion torque T_motor/g_p, the balancing gear
  torque) with the same integrator and damping; its own step rule is the pair's (64 points per
  shortest period of the stage alone, gearfmu.dynamics.native.choose_max_step_s at 1.5 x its speed).

Every FMU runs ``--sim`` simulated seconds at the scene's communication step through
``benchmarks/fmu_rtf_host.c`` (a plain C FMI 2.0 host: doStep + getReal of every stage's DTE and mesh
force per communication step), its ``max_step`` parameter swept over factors of its default step;
cost = the best process CPU time of ``--repeat`` runs (the machine is shared; wall time beside it).
Error of a run: RMS(dte - dte_fine) / peak-to-peak(dte_fine) per stage, against a fine run of the same
model (the native gearbox solver, resp. the native pair solver, at an eighth of the default step).

Ratios (gearbox cost / sum of the pair FMUs' costs):

* ``ratio_same_accuracy``: every stage's pair FMU at the step where its DTE error equals that stage's
  error in the gearbox FMU at its default step (log-log interpolation along the sweep) -- the goal's;
* ``ratio_matching_pairs``: the gearbox FMU at the step where no stage's error exceeds its pair FMU's at
  the pair's default step, against the pair FMUs at their defaults;
* ``ratio_step_rule``: every FMU at its default step; ``ratio_same_step``: the pair FMUs at the gearbox's
  default step (the cost of the same number of internal steps, the bookkeeping of bodies and shafts).
"""
from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
from pathlib import Path

import numpy as np

from harness import ROOT, at_error, compile_host, emit, host_run, unzip_fmu as _unzip

GOAL = 1.3
GEARBOX_FACTORS = (0.8, 1.0, 1.15, 1.3, 1.5, 1.75)
PAIR_FACTORS = (0.5, 0.65, 0.8, 1.0, 1.25, 1.6, 2.0)


def _host(exe, unz, md, *, sim_s, comm_s, repeat, outs, max_step_s, integrator):
    """(best CPU s, best wall s, output rows) of fmu_rtf_host.c on the unzipped FMU (harness.host_run)."""
    wall, cpu, rows = host_run(exe, unz, md, sim_s=sim_s, comm_s=comm_s, repeat=repeat, outputs=outs,
                               max_step_s=max_step_s, integrator=integrator, timeout=3600)
    return cpu, wall, rows


def _err(x, ref) -> float:
    n = min(len(x), len(ref))
    return float(np.sqrt(np.mean((x[:n] - ref[:n]) ** 2)) / np.ptp(ref[:n]))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default=str(ROOT / "examples" / "scenes" / "gearbox_two_stage.toml"))
    ap.add_argument("--sim", type=float, default=0.1, help="simulated seconds per run")
    ap.add_argument("--repeat", type=int, default=5, help="runs per setting (best CPU time)")
    args = ap.parse_args(argv)

    from gearfmu import pipeline
    from gearfmu.dynamics.native import choose_max_step_s as pair_max_step_s, simulate as simulate_pair
    from gearfmu.fmu.crossbuild import host_key
    from gearfmu.fmu.gearbox_build import build_gearbox_fmu
    from gearfmu.fmu.gearbox_validation import native_run
    from gearfmu.fmu.standalone_build import build_standalone_fmu
    from gearfmu.scene.drivetrain import load_drivetrain

    scene = load_drivetrain(args.scene)
    model = pipeline.gearbox_model(scene, pipeline.stage_tables(scene))
    s0 = pipeline.gearbox_fmu_settings(scene, model)
    s = dataclasses.replace(s0, stop_time_s=args.sim)
    comm, sim, h0 = s.output_interval_s, args.sim, s.max_step_s
    plat = (host_key(),)
    t_ref = model.reference_torque_Nm(s.motor_torque_start_Nm, s.load_torque_start_Nm)
    stages = [m.name for m in model.meshes]
    out = {"scene": scene.name, "sim_s": sim, "comm_step_s": comm, "repeat": args.repeat,
           "integrator": s.integrator, "host": "benchmarks/fmu_rtf_host.c (C, FMI 2.0, dlopen)",
           "cost": "best process CPU time of the runs", "goal": GOAL}
    print(f"bench_gearbox_fmu: {scene.name}, {sim:g} s simulated at {comm:g} s, best of {args.repeat}",
          file=sys.stderr)
    with tempfile.TemporaryDirectory(prefix="gearfmu_bench_gb_") as tmpd:
        tmp = Path(tmpd)
        exe = compile_host(tmp)
        # ---------------------------------------------------------------- gearbox
        gb = build_gearbox_fmu(model, tmp / "gearbox.fmu", settings=s, model_name="bench_gearbox", platforms=plat,
                               validation=False)
        md = _unzip(gb, tmp / "gb")
        outs = [f"{m}.{q}" for m in stages for q in ("dte", "mesh_force")]
        fine = native_run(model, dataclasses.replace(s, max_step_s=h0 / 8))
        nat = native_run(model, s)
        sweep = []
        for f in GEARBOX_FACTORS:
            cpu, wall, rows = _host(exe, tmp / "gb", md, sim_s=sim, comm_s=comm, repeat=args.repeat, outs=outs,
                                    max_step_s=h0 * f, integrator=s.integrator_code)
            sweep.append({"factor": f, "max_step_s": h0 * f, "cpu_s": cpu, "wall_s": wall,
                          "dte_rel_rms_err": {m: _err(rows[:, 2 * k], fine[f"{m}.dte"]) for k, m in enumerate(stages)}})
            if f == 1.0:
                same = all(np.array_equal(rows[:, i], nat[n]) for i, n in enumerate(outs))
        default = next(p for p in sweep if p["factor"] == 1.0)
        out["gearbox"] = {"max_step_s": h0, "events": int(nat.info["events"]), "substeps": int(nat.substeps),
                          "equals_native_solver": bool(same), "default": default, "sweep": sweep}
        print(f"  gearbox: {default['cpu_s'] / sim:.4g} s CPU per simulated s (step {h0:.3g} s)", file=sys.stderr)
        # ---------------------------------------------------------------- stages
        out["stages"] = []
        for k, m in enumerate(model.meshes):
            t = m.tables
            gp = float(model.g[model.mesh_bodies[k, 0]])
            w = gp * s.motor_speed_start_rad_s
            t1 = t_ref / gp if m.name in model.on_path else 0.0
            t2 = t1 * t.base_radius_gear_m / t.base_radius_pinion_m
            own = pair_max_step_s(t, 1.5 * abs(w))
            pf = build_standalone_fmu(t, tmp / f"{m.name}.fmu", model_name=f"bench_{m.name}",
                                      damping_ratio=m.damping_ratio, pinion_speed_start_rad_s=w,
                                      pinion_torque_start_Nm=t1, gear_torque_start_Nm=t2, max_step_s=own,
                                      damping_model=m.damping_model, integrator=s.integrator, stop_time_s=sim,
                                      output_interval_s=comm, validation=False, platforms=plat)
            pmd = _unzip(pf, tmp / m.name)
            pfine = simulate_pair(t, stop_time_s=sim, comm_step_s=comm, max_step_s=min(own, h0) / 8,
                                  pinion_torque_Nm=t1, gear_torque_Nm=t2, pinion_speed_start_rad_s=w,
                                  damping_ratio=m.damping_ratio, damping_model=m.damping_model,
                                  integrator=s.integrator)
            psweep = []
            for f, h in [(f, own * f) for f in PAIR_FACTORS] + [(None, h0)]:
                cpu, wall, rows = _host(exe, tmp / m.name, pmd, sim_s=sim, comm_s=comm, repeat=args.repeat,
                                        outs=["dte", "mesh_force"], max_step_s=h,
                                        integrator=s.integrator_code)
                psweep.append({"factor": f, "max_step_s": h, "cpu_s": cpu, "wall_s": wall,
                               "dte_rel_rms_err": _err(rows[:, 0], pfine.dte)})
            row = {"stage": m.name, "pinion_speed_rad_s": w, "pinion_torque_Nm": t1, "max_step_s": own,
                   "default": next(p for p in psweep if p["factor"] == 1.0),
                   "at_gearbox_step": next(p for p in psweep if p["factor"] is None),
                   "sweep": [p for p in psweep if p["factor"] is not None]}
            hit = at_error(row["sweep"], lambda p: p["dte_rel_rms_err"], default["dte_rel_rms_err"][m.name])
            row["at_gearbox_accuracy"] = None if hit is None else {"max_step_s": hit[0], "cpu_s": hit[1]}
            print(f"  {m.name}: {row['default']['cpu_s'] / sim:.4g} s CPU per simulated s (own step {own:.3g} s)",
                  file=sys.stderr)
            out["stages"].append(row)
    gbc = out["gearbox"]["default"]["cpu_s"]
    out["ratio_step_rule"] = gbc / sum(r["default"]["cpu_s"] for r in out["stages"])
    out["ratio_same_step"] = gbc / sum(r["at_gearbox_step"]["cpu_s"] for r in out["stages"])
    matched = [r["at_gearbox_accuracy"] for r in out["stages"]]
    out["ratio_same_accuracy"] = None if None in matched else gbc / sum(x["cpu_s"] for x in matched)
    worst = {m: r["default"]["dte_rel_rms_err"] for m, r in zip(stages, out["stages"])}
    hit = at_error(out["gearbox"]["sweep"], lambda p: max(p["dte_rel_rms_err"][m] / worst[m] for m in stages), 1.0)
    out["gearbox_matching_pairs"] = None if hit is None else {"max_step_s": hit[0], "cpu_s": hit[1]}
    out["ratio_matching_pairs"] = None if hit is None else hit[1] / sum(r["default"]["cpu_s"] for r in out["stages"])
    out["within_goal"] = out["ratio_same_accuracy"] is not None and out["ratio_same_accuracy"] <= GOAL
    emit(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
