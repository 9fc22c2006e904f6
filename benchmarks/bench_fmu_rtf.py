#!/usr/bin/env python3
"""Benchmark: real-time factor of the standalone FMU against its error, per table resolution.

For each points-per-mesh level (the planner's levels, gearfmu.plan.choices: 16 .. 256 by
default, and 512 .. 2048) the scene's tables are built at that resolution and packed into a standalone
FMI 2.0 FMU (this machine's binary only).  Each (points per mesh, integrator, max_step)
is then run over ``--sim`` simulated seconds at the communication step ``--comm``:

* through ``benchmarks/fmu_rtf_host.c`` (compiled here with the system ``cc``): a plain C
  FMI 2.0 host, dlopen of the FMU binary, doStep + getReal(dte) per communication step;
* through fmpy's low-level API (the same calls, a Python loop; harness.FMPY_LOOPS): ``fmpy_*``
  FMU2Slave.doStep + fmi2GetReal on ctypes arrays built once, ``fmpy_raw_*`` the FMU's functions
  through fmpy's ctypes pointers with no fmpy wrapper.

Both hosts read ``dte`` and ``mesh_force`` after every doStep.

``max_step`` and ``integrator`` are the FMU's own parameters, set in initialization mode;
``max_step`` = comm / substeps.  Every run's outputs (recorded by the C host; the fmpy run's
are compared with them bit for bit) are compared with a fine run: native rk4_kink on tables at
``--fine-ppm`` points per mesh (finer than every level) and max_step comm / ``--fine-substeps``.
Two errors over all communication points: ``dte_rel_rms_err`` = RMS(dte - dte_fine) /
RMS(dte_fine), the planner's measure (gearfmu.plan.relative_rms; mesh_force the same
in ``mesh_force_rel_rms_err``), and ``dte_rel_ptp_err`` = RMS(dte - dte_fine) /
peak-to-peak(dte_fine), the measure of bench_fmu.py's ``rtf`` block (stricter: the mean
deflection is not in the denominator).  ``reference_check``: both errors of the fine run against
one on tables twice as fine (how far the reference itself is from table convergence).
``dte_rel_rms_err_same_table``: the planner's measure against the same fine run on the run's own
tables (the integration error alone, as in bench_fmu.py's ``rtf`` block).

real_time_factor = simulated s / best wall s of ``--repeat`` runs (the machine is shared:
best of N; run it under ``nice``); ``cpu`` the same on process CPU time (C host only).
``cheapest`` lists, per error measure, among the settings within ``--target``, the fastest
through each host; ``smallest_error`` the run closest to the fine run.  ``dostep_overhead``:
the C host's wall time per doStep beyond its internal steps (rk4 at max_step = comm, run at
comm and at 10 x comm: the same internal steps, ten times fewer doStep calls).  ``python_floor``:
each fmpy loop around two C functions that do nothing (benchmarks/fmi2_noop.c, harness.python_floor),
the real-time factor no FMU can exceed through that loop on this machine.

Prints one JSON object.  ``--table-front``: only the table error per points per mesh, with the
tables' engagement angles (the sub-cell lookup at the contact-zone edges, docs/model.md) and
without them (the plain lookup), each against its own fine run (:func:`table_front`).

    nice python benchmarks/bench_fmu_rtf.py [SCENE] [--ppm 16,32,64,128,256] [--repeat 5]
"""
import argparse
import json
import math
import shutil
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from harness import FMPY_LOOPS, INTEGRATOR_CODE, compile_host, emit, fmu_loop, host_run, python_floor

def fmpy_run(unz, md, vr, *, sim_s, comm_s, max_step_s, integrator, reals, loop="lean"):
    """(wall s, rows of (dte, mesh_force), CPU s of the loop's thread) of one fmpy loop
    (harness.FMPY_LOOPS[loop]: by default FMU2Slave.doStep + fmi2GetReal on ctypes arrays built once)."""
    rows = []
    start = dict(reals, max_step=max_step_s, integrator=INTEGRATOR_CODE[integrator])
    _, wall, _, _, cpu = fmu_loop(None, str(unz), md, sim_s, comm_s, start, loop=loop, rows=rows)
    return wall, np.array(rows), cpu


def fmpy_columns(unz, md, vr, kw, repeat, c_rows):
    """The fmpy columns of a run: the lean loop and the raw ctypes-pointer loop, best of
    ``repeat`` each (in turn; wall and the loop's CPU time, as the C host's), and whether the lean
    loop's outputs equal the C host's bit for bit."""
    walls, cpus, rows = {"lean": float("inf"), "raw": float("inf")}, {"lean": float("inf"), "raw": float("inf")}, None
    for _ in range(repeat):
        for loop in walls:
            w, r, c = fmpy_run(unz, md, vr, loop=loop, **kw)
            walls[loop], cpus[loop] = min(walls[loop], w), min(cpus[loop], c)
            rows = r if rows is None else rows
    sim = kw["sim_s"]
    return {"fmpy_wall_s": walls["lean"], "fmpy_real_time_factor": sim / walls["lean"],
            "fmpy_cpu_real_time_factor": sim / cpus["lean"],
            "fmpy_raw_wall_s": walls["raw"], "fmpy_raw_real_time_factor": sim / walls["raw"],
            "fmpy_raw_cpu_real_time_factor": sim / cpus["raw"],
            "fmpy_outputs_equal_c_host": bool(np.array_equal(rows, c_rows))}


def table_front(scene, ppms, *, fine_ppm, comm_s, sim_s, fine_substeps, integrator="rk4_kink"):
    """Table error against table resolution, before and after the sub-cell lookup at the
    contact-zone edges (docs/model.md "Contact-zone edges").  Native runs only (the FMU's C
    kernel gives the same numbers bit for bit): for each points-per-mesh level, the run on
    those tables with max_step comm / ``fine_substeps`` (the integration error far below
    the table error) against the same run on ``fine_ppm`` tables.  ``plain``: the tables
    without their engagement angles (linear interpolation across the edges, the lookup
    before, and ``k_mean_N_per_m`` the grid mean of the nodes as before); ``subcell``: with them
    (and the exact mean).  Each against its own fine reference, and the two references against
    each other."""
    from gearfmu.dynamics.native import simulate
    from gearfmu.pipeline import compute_tables, gear_torque_for
    from gearfmu.plan import relative_rms

    T1 = scene.operating.torque_Nm

    def tables_at(p, edges):
        t = compute_tables(replace(scene, tables=replace(scene.tables, points_per_mesh=p)))
        if edges:
            return t
        # before: no engagement angles, k_mean the grid mean of the nominal row
        row = np.flatnonzero(np.asarray(t.torque_Nm) == T1)
        k_grid = float(t.k_N_per_m[int(row[0]) if row.size else 0].sum(axis=0).mean())
        return replace(t, engagement_in_rad=None, engagement_out_rad=None, k_mean_N_per_m=k_grid)

    def run(t):
        r = simulate(t, max_step_s=comm_s / fine_substeps, integrator=integrator, stop_time_s=sim_s,
                     comm_step_s=comm_s, pinion_torque_Nm=T1, gear_torque_Nm=gear_torque_for(t, T1),
                     pinion_speed_start_rad_s=scene.operating.speed_rad_s, damping_ratio=scene.fmu.damping_ratio,
                     damping_model=scene.solver.damping_model)
        return r.dte, r.info.get("events", 0)

    ref = {k: run(tables_at(fine_ppm, k == "subcell"))[0] for k in ("plain", "subcell")}
    out = {"scene": scene.name, "integrator": integrator, "comm_step_s": comm_s, "simulated_s": sim_s,
           "max_step_s": comm_s / fine_substeps, "fine_points_per_mesh": fine_ppm,
           "error": "RMS(dte - dte_ref) / RMS(dte_ref), dte_ref the same lookup on the fine tables",
           "fine_plain_vs_fine_subcell": relative_rms(ref["plain"], ref["subcell"]), "rows": []}
    for p in ppms:
        row = {"points_per_mesh": p}
        for k in ("plain", "subcell"):
            dte, ev = run(tables_at(p, k == "subcell"))
            row[f"{k}_dte_rel_rms_err"] = relative_rms(dte, ref[k])
            row[f"{k}_vs_fine_subcell"] = relative_rms(dte, ref["subcell"])
        out["rows"].append(row)
        print(json.dumps(row), file=sys.stderr, flush=True)
    errs = [r["subcell_dte_rel_rms_err"] for r in out["rows"]]
    out["subcell_order"] = [math.log2(a / b) if a > 0 and b > 0 else None for a, b in zip(errs, errs[1:])]
    errs = [r["plain_dte_rel_rms_err"] for r in out["rows"]]
    out["plain_order"] = [math.log2(a / b) if a > 0 and b > 0 else None for a, b in zip(errs, errs[1:])]
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scene", nargs="?")
    ap.add_argument("--ppm", default="16,32,64,128,256,512,1024,2048", help="points per mesh of the FMUs")
    ap.add_argument("--fine-ppm", type=int, default=4096, help="points per mesh of the fine run")
    ap.add_argument("--integrators", default="rk4,rk4_kink,rk4_node,rk4_seg")
    ap.add_argument("--substeps", default="1,2,3,4,6,8", help="max_step = comm / substeps")
    ap.add_argument("--comm", type=float, default=1e-4, help="communication step (s)")
    ap.add_argument("--sim", type=float, default=0.1, help="simulated seconds per run (s)")
    ap.add_argument("--target", type=float, default=1e-4, help="relative RMS dte error target")
    ap.add_argument("--fine-substeps", type=int, default=512)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--no-fmpy", action="store_true", help="time the C host only")
    ap.add_argument("--table-front", action="store_true",
                    help="only the table error per points per mesh, plain lookup and sub-cell edges (table_front)")
    args = ap.parse_args(argv)
    if args.table_front:
        from gearfmu.pipeline import load

        emit({"table_front": table_front(
            load(args.scene), sorted(int(x) for x in args.ppm.split(",")), fine_ppm=args.fine_ppm, comm_s=args.comm,
            sim_s=args.sim, fine_substeps=args.fine_substeps)})
        return 0

    from fmpy import extract, read_model_description

    from gearfmu.dynamics.native import simulate
    from gearfmu.fmu.standalone_build import build_standalone_fmu
    from gearfmu.pipeline import compute_tables, gear_torque_for, load
    from gearfmu.plan import relative_rms

    scene = load(args.scene)
    ppms = sorted(int(x) for x in args.ppm.split(","))
    integrators = [s.strip() for s in args.integrators.split(",")]
    subs = [int(x) for x in args.substeps.split(",")]
    T1 = scene.operating.torque_Nm
    w0 = scene.operating.speed_rad_s
    zeta = scene.fmu.damping_ratio
    dmodel = scene.solver.damping_model

    def tables_at(p):
        return compute_tables(replace(scene, tables=replace(scene.tables, points_per_mesh=p)))

    def fine_run(tables):
        r = simulate(tables, max_step_s=args.comm / args.fine_substeps, integrator="rk4_kink",
                     stop_time_s=args.sim, comm_step_s=args.comm, pinion_torque_Nm=T1,
                     gear_torque_Nm=gear_torque_for(tables, T1), pinion_speed_start_rad_s=w0,
                     damping_ratio=zeta, damping_model=dmodel)
        return np.column_stack([r.dte, r.mesh_force])

    fine = fine_run(tables_at(args.fine_ppm))
    rng = float(np.ptp(fine[:, 0]))

    def errors(rows, ref=None):
        ref = fine if ref is None else ref
        rows = np.asarray(rows, float)
        n = min(len(rows), len(ref))
        a, b = rows[:n], ref[:n]
        if ref is not fine:
            return {"dte_rel_rms_err_same_table": relative_rms(a[:, 0], b[:, 0])}
        return {"dte_rel_rms_err": relative_rms(a[:, 0], b[:, 0]),
                "dte_rel_ptp_err": float(np.sqrt(np.mean((a[:, 0] - b[:, 0]) ** 2)) / rng),
                "mesh_force_rel_rms_err": relative_rms(a[:, 1], b[:, 1])}

    report = {"scene": scene.name, "comm_step_s": args.comm, "simulated_s": args.sim, "repeat": args.repeat,
              "target": args.target,
              "reference": {"kind": "native rk4_kink", "points_per_mesh": args.fine_ppm,
                            "max_step_s": args.comm / args.fine_substeps, "dte_peak_to_peak_m": rng,
                            "dte_rms_m": float(np.sqrt(np.mean(fine[:, 0] ** 2)))},
              "reference_check": dict(points_per_mesh=2 * args.fine_ppm, **errors(fine_run(tables_at(2 * args.fine_ppm)))),
              "errors": {"dte_rel_rms_err": "RMS(dte - dte_ref) / RMS(dte_ref) (the planner's measure)",
                         "dte_rel_ptp_err": "RMS(dte - dte_ref) / peak-to-peak(dte_ref) (bench_fmu.py rtf block)",
                         "mesh_force_rel_rms_err": "RMS(F - F_ref) / RMS(F_ref)"},
              "c_host": "benchmarks/fmu_rtf_host.c: dlopen, fmi2DoStep + fmi2GetReal(dte, mesh_force) per step",
              "fmpy_host": None if args.no_fmpy else {"fmpy": "lean loop: " + FMPY_LOOPS["lean"],
                                                      "fmpy_raw": "raw loop: " + FMPY_LOOPS["raw"]},
              "runs": []}
    tmp = Path(tempfile.mkdtemp(prefix="gearfmu_rtf_"))
    try:
        exe = compile_host(tmp)
        for p in ppms:
            tables = tables_at(p)
            same = fine_run(tables)
            T2 = gear_torque_for(tables, T1)
            t0 = time.perf_counter()
            path = build_standalone_fmu(tables, tmp / f"rtf{p}.fmu", damping_ratio=zeta, pinion_speed_start_rad_s=w0,
                                        pinion_torque_start_Nm=T1, gear_torque_start_Nm=T2,
                                        max_step_s=args.comm, damping_model=dmodel, stop_time_s=args.sim,
                                        output_interval_s=args.comm, integrator="rk4_kink", validation=False,
                                        platforms=("x86_64-linux",), model_name=f"GearRtf{p}")
            build_s = time.perf_counter() - t0
            md = read_model_description(str(path))
            vr = {v.name: v.valueReference for v in md.modelVariables}
            unz = Path(extract(str(path)))
            reals = {"pinion_torque": T1, "gear_torque": T2}
            if p == ppms[0]:  # what one doStep costs beyond its internal steps: rk4 at max_step = comm
                w = [host_run(exe, unz, md, vr, sim_s=args.sim, comm_s=c, repeat=args.repeat, max_step_s=args.comm,
                              integrator="rk4", reals=reals)[0] for c in (args.comm, 10 * args.comm)]
                n1, n10 = round(args.sim / args.comm), round(args.sim / (10 * args.comm))
                report["dostep_overhead"] = {
                    "points_per_mesh": p, "integrator": "rk4", "max_step_s": args.comm,
                    "c_host_wall_s_comm": w[0], "c_host_wall_s_10comm": w[1],
                    "s_per_dostep_beyond_internal_steps": (w[0] - w[1]) / (n1 - n10)}
                if not args.no_fmpy:
                    report["python_floor"] = python_floor(
                        unz, md, dict(reals, max_step=args.comm, integrator=INTEGRATOR_CODE["rk4"]), sim_s=10 * args.sim,
                        comm_s=args.comm, repeat=args.repeat, tmp=tmp)
            for integ in integrators:
                for n in subs:
                    h = args.comm / n
                    kw = dict(sim_s=args.sim, comm_s=args.comm, max_step_s=h, integrator=integ, reals=reals)
                    wall, cpu, rows = host_run(exe, unz, md, vr, repeat=args.repeat, **kw)
                    row = {"points_per_mesh": p, "integrator": integ, "substeps": n, "max_step_s": h,
                           **errors(rows), **errors(rows, same), "c_host_wall_s": wall, "c_host_real_time_factor": args.sim / wall,
                           "c_host_cpu_real_time_factor": args.sim / cpu, "fmu_build_s": build_s}
                    if not args.no_fmpy:
                        row.update(fmpy_columns(unz, md, vr, kw, args.repeat, rows))
                    report["runs"].append(row)
                    print(json.dumps(row), file=sys.stderr, flush=True)
            shutil.rmtree(unz, ignore_errors=True)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    keys = ["c_host_real_time_factor"] + ([] if args.no_fmpy else ["fmpy_real_time_factor", "fmpy_raw_real_time_factor"])
    report["cheapest"] = {}
    for m in ("dte_rel_rms_err", "dte_rel_ptp_err", "dte_rel_rms_err_same_table"):
        ok = [r for r in report["runs"] if np.isfinite(r[m]) and r[m] <= args.target]
        report["cheapest"][m] = {k: (max(ok, key=lambda r: r[k]) if ok else None) for k in keys}
    report["smallest_error"] = min(report["runs"], key=lambda r: r["dte_rel_rms_err"], default=None)
    emit(report)
    return 0


if __name__ == "__main__":
    sys.exit(main())
