#!/usr/bin/env python3
"""Benchmark: FMU (C kernel behind pythonfmu) against the native numba solver.

Measured in one run, on the same tables, inputs and internal steps:

* ``native_ns_per_step`` / ``fmu_ns_per_step``: cost of one internal RK4 step
  when a communication step spans many internal steps (FMU: fmpy low-level
  ``doStep`` loop with a communication step of ten mesh periods);
* ``*_wall_per_sim_s``: wall time per simulated second at the scene's own
  communication step (FMU through fmpy's low-level API and through
  ``fmpy.simulate_fmu``), and their ratio to native; ``fmpy_floor_wall_per_sim_s`` the same
  fmpy loops around two C functions that do nothing (``harness.python_floor``) and
  ``fmu_over_native_per_sim_s_bound`` = (that loop's wall + native's) / native's: the lowest
  ratio any FMU doing the native solver's work can reach through that loop on this machine;
* ``fmu_instantiate_s``: extract + instantiate + initialise of the FMU;
* ``rtf``: real-time factor (simulated s / wall s) of the standalone FMU built with
  ``--rtf-integrator`` (default rk4_node) at a stated error (``--rtf-error``, relative
  RMS dte error, default 1e-4) and communication step (``--rtf-comm``, default 1e-4 s),
  over ``--rtf-sim`` simulated seconds: the largest internal step H/n whose native run
  (bitwise the FMU's kernel) meets the error against a fine run (native rk4_kink at
  H/512) is built into the FMU; the FMU's own outputs, recorded in the timed fmpy
  low-level loop, are compared with the fine run again (``fmu_dte_rel_rms_err``); the
  same steps through the C kernel alone (gk_do_step via ctypes) give
  ``kernel_real_time_factor`` (what the FMI layer and the Python host loop add).

Every fmpy loop here is one of ``harness.FMPY_LOOPS`` (by default ``lean``: FMU2Slave.doStep and
fmi2GetReal on ctypes arrays built once; benchmarks/harness.py holds the hosts every benchmark
shares).

Prints one JSON object.  Ratios, not absolute times, are the comparable
numbers (these machines are shared and noisy): each timing is the best of
``--repeat`` runs, the native and the FMU runs taken in turn.

    python benchmarks/bench_fmu.py [SCENE] [--sim-time 0.2] [--repeat 3]
"""
import argparse
import math
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from harness import best_of, c_runner, emit, fmu_loop, python_floor


def rtf_at_error(tables, *, T1, T2, w0, zeta, damping_model, integrator, target, comm_s, sim_s, repeat):
    """The ``rtf`` block of the report (module docstring)."""
    from fmpy import extract, read_model_description

    from gearfmu.dynamics.native import simulate
    from gearfmu.fmu.standalone_build import build_standalone_fmu
    from gearfmu.fmu.pythonfmu_build import compile_kernel
    from gearfmu.fmu.runtime.kernel_api import load_kernel

    kw = dict(stop_time_s=sim_s, comm_step_s=comm_s, pinion_torque_Nm=T1, gear_torque_Nm=T2,
              pinion_speed_start_rad_s=w0, damping_ratio=zeta, damping_model=damping_model)
    fine = simulate(tables, max_step_s=comm_s / 512, integrator="rk4_kink", **kw)
    rng = float(np.ptp(fine.dte))

    def err(dte):
        d = np.asarray(dte, float)[:len(fine.dte)] - fine.dte[:len(dte)]
        return float(np.sqrt(np.mean(d ** 2)) / rng)

    tried, n_ok = [], None
    for n in (1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64):
        e = err(simulate(tables, max_step_s=comm_s / n, integrator=integrator, **kw).dte)
        tried.append({"substeps": n, "dte_rel_rms_err": e})
        if e <= target:
            n_ok = n
            break
    if n_ok is None:
        return {"error": f"no internal step down to H/64 meets {target:g}", "tried": tried}
    h = comm_s / n_ok
    tmp = Path(tempfile.mkdtemp(prefix="gearfmu_rtf_"))
    try:
        path = build_standalone_fmu(tables, tmp / "rtf.fmu", damping_ratio=zeta, pinion_speed_start_rad_s=w0,
                                    pinion_torque_start_Nm=T1, gear_torque_start_Nm=T2, max_step_s=h,
                                    damping_model=damping_model, stop_time_s=sim_s, output_interval_s=comm_s,
                                    integrator=integrator, validation=False)
        md = read_model_description(str(path))
        unz = extract(str(path))
        walls, rec = [], []
        for _ in range(repeat):
            rec = []
            walls.append(fmu_loop(path, unz, md, sim_s, comm_s, {"pinion_torque": T1, "gear_torque": T2},
                                  record=rec)[1])
        shutil.rmtree(unz, ignore_errors=True)
        lib = load_kernel(compile_kernel(tmp))
        code = {"rk4": 0, "rk4_kink": 1, "rk4_node": 2}[integrator]
        dm = {"elastobacklash": 0, "contact_zone": 1}[damping_model]
        nsteps = int(round(sim_s / comm_s))
        kwall = best_of(repeat, lambda: c_runner(tables, T1, T2, w0, zeta, float(fine.dte[0]), comm_s, nsteps, h,
                                                 code, lib, damping_model=dm)[0])
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return {"integrator": integrator, "target_dte_rel_rms_err": target, "comm_step_s": comm_s,
            "simulated_s": sim_s, "max_step_s": h, "substeps": n_ok, "tried": tried,
            "reference": "native rk4_kink at H/512 (fine run)",
            "fmu_dte_rel_rms_err": err(rec), "fmu_wall_s": min(walls), "real_time_factor": sim_s / min(walls),
            "fmu_host": "fmpy FMU2Slave doStep + getReal per communication step (Python loop)",
            "kernel_wall_s": kwall, "kernel_real_time_factor": sim_s / kwall}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scene", nargs="?")
    ap.add_argument("--sim-time", type=float, default=0.2, help="simulated seconds per timing (s)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--rtf-error", type=float, default=1e-4, help="relative RMS dte error of the rtf block")
    ap.add_argument("--rtf-comm", type=float, default=1e-4, help="communication step of the rtf block (s)")
    ap.add_argument("--rtf-sim", type=float, default=0.1, help="simulated seconds of the rtf block (s)")
    ap.add_argument("--rtf-integrator", default="rk4_node")
    ap.add_argument("--only-rtf", action="store_true", help="report the rtf block only")
    args = ap.parse_args(argv)

    import fmpy
    from fmpy import extract, read_model_description

    from gearfmu.dynamics.native import simulate, substeps
    from gearfmu.pipeline import build, gear_torque_for, load

    scene = load(args.scene)
    if args.only_rtf:
        from gearfmu.pipeline import compute_tables
        tables = compute_tables(scene)
        T1 = scene.operating.torque_Nm
        rep = rtf_at_error(tables, T1=T1, T2=gear_torque_for(tables, T1), w0=scene.operating.speed_rad_s,
                           zeta=scene.fmu.damping_ratio, damping_model=scene.solver.damping_model,
                           integrator=args.rtf_integrator, target=args.rtf_error, comm_s=args.rtf_comm,
                           sim_s=args.rtf_sim, repeat=args.repeat)
        emit({"scene": scene.name, "rtf": rep})
        return 0
    tmp = Path(tempfile.mkdtemp(prefix="gearfmu_bench_"))
    try:
        t0 = time.perf_counter()
        res = build(scene, tmp / "bench.fmu")
        build_s = time.perf_counter() - t0
        tables, h_max = res.tables, res.max_step_s
        T1 = scene.operating.torque_Nm
        T2 = gear_torque_for(tables, T1)
        w0 = scene.operating.speed_rad_s
        zeta = scene.fmu.damping_ratio
        mesh_period_s = tables.mesh_period_rad / abs(w0)
        big = 10 * mesh_period_s          # a communication step of ten mesh periods
        small = scene.fmu.output_interval_s
        sim = args.sim_time
        kw = dict(max_step_s=h_max, pinion_torque_Nm=T1, gear_torque_Nm=T2, pinion_speed_start_rad_s=w0,
                  damping_ratio=zeta, damping_model=scene.solver.damping_model)
        simulate(tables, stop_time_s=10 * small, comm_step_s=small, **kw)  # JIT warm-up

        def native_wall(comm):
            r = simulate(tables, stop_time_s=sim, comm_step_s=comm, **kw)
            return r.wall_s
        n_big = int(round(sim / big)) * substeps(big, h_max)

        md = read_model_description(str(res.fmu_path))
        unz = extract(str(res.fmu_path))
        sv = {"pinion_torque": T1, "gear_torque": T2}
        inits, fmu_big, fmu_small, nat_bigs, nat_smalls = [], [], [], [], []
        floor = {}
        for _ in range(args.repeat):  # native, FMU and the empty loops in turn: a slow spell hits all
            nat_bigs.append(native_wall(big))
            nat_smalls.append(native_wall(small))
            ti, wb, _, _, _ = fmu_loop(res.fmu_path, unz, md, sim, big, sv)
            inits.append(ti)
            fmu_big.append(wb)
            _, ws, _, _, _ = fmu_loop(res.fmu_path, unz, md, sim, small, sv)
            fmu_small.append(ws)
            # the same loops around functions that do nothing: the part of fmu_small that is the host's
            for k, v in python_floor(unz, md, sv, sim_s=sim, comm_s=small, repeat=1, tmp=tmp).items():
                floor[k] = min(floor.get(k, math.inf), v["wall_s"])
        nat_big, nat_small = min(nat_bigs), min(nat_smalls)
        t0 = time.perf_counter()
        fmpy.simulate_fmu(str(res.fmu_path), stop_time=sim, output_interval=small)
        simfmu_wall = time.perf_counter() - t0
        t0 = time.perf_counter()
        inst = fmpy.instantiate_fmu(unz, md)
        inst_s = time.perf_counter() - t0
        inst.freeInstance()

        report = {
            "scene": scene.name,
            "slots": tables.slots,
            "max_step_s": h_max,
            "sim_time_s": sim,
            "comm_step_large_s": big,
            "comm_step_scene_s": small,
            "native_ns_per_step": 1e9 * nat_big / n_big,
            "fmu_ns_per_step": 1e9 * min(fmu_big) / n_big,
            "fmu_over_native_per_step": min(fmu_big) / nat_big,
            "native_wall_per_sim_s": nat_small / sim,
            "fmu_lowlevel_wall_per_sim_s": min(fmu_small) / sim,
            "fmu_simulate_fmu_wall_per_sim_s": simfmu_wall / sim,
            "fmu_over_native_per_sim_s_lowlevel": min(fmu_small) / nat_small,
            "fmu_over_native_per_sim_s_simulate_fmu": simfmu_wall / nat_small,
            "fmpy_floor_wall_per_sim_s": {k: w / sim for k, w in floor.items()},
            "fmu_over_native_per_sim_s_bound": {k: (w + nat_small) / nat_small for k, w in floor.items()},
            "internal_steps_per_comm_step_scene": substeps(small, h_max),
            "fmu_instantiate_s": inst_s,
            "fmu_instantiate_and_initialize_s": min(inits),
            "fmu_build_s": build_s,
            "tables_s": res.tables_compute_s,  # the computation, also when read from the table cache
            "rtf": rtf_at_error(tables, T1=T1, T2=T2, w0=w0, zeta=zeta, damping_model=scene.solver.damping_model,
                                integrator=args.rtf_integrator, target=args.rtf_error, comm_s=args.rtf_comm,
                                sim_s=args.rtf_sim, repeat=args.repeat),
        }
        emit(report)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
