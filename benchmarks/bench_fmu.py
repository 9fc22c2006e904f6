#!/usr/bin/env python3
"""Benchmark: FMU (C kernel behind pythonfmu) against the native numba solver.

Measured in one run, on the same tables, inputs and internal steps:

* ``native_ns_per_step`` / ``fmu_ns_per_step``: cost of one internal RK4 step
  when a communication step spans many internal steps (FMU: fmpy low-level
  ``doStep`` loop with a communication step of ten mesh periods);
* ``*_wall_per_sim_s``: wall time per simulated second at the scene's own
  communication step (FMU through fmpy's low-level API and through
  ``fmpy.simulate_fmu``), and their ratio to native; ``fmpy_floor_wall_per_sim_s`` the same
  fmpy loops around two C functions that do nothing (:func:`python_floor`) and
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

Every fmpy loop here is one of ``FMPY_LOOPS`` (by default ``lean``: FMU2Slave.doStep and
fmi2GetReal on ctypes arrays built once).  ``step_costs`` (used by bench_integrators.py's
``fmu_rtf``) splits one communication step into the kernel, the FMU's fixed cost, the ctypes
calls and fmpy's wrappers, and gives the rate through the C host and each fmpy loop.

Prints one JSON object.  Ratios, not absolute times, are the comparable
numbers (these machines are shared and noisy): each timing is the best of
``--repeat`` runs, the native and the FMU runs taken in turn.

    python benchmarks/bench_fmu.py [SCENE] [--sim-time 0.2] [--repeat 3]
"""
import argparse
import json
import math
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


#: the Python loops of _fmu_loop: one doStep and one getReal of the outputs per
#: communication step, the FMU instantiated once (what each number in the JSON came from)
FMPY_LOOPS = {
    "lean": "fmpy FMU2Slave.doStep + FMU2Slave.fmi2GetReal (fmpy's status-checked function) on ctypes "
            "arrays of value references and values built once",
    "raw": "the FMU library's own fmi2DoStep / fmi2GetReal through fmpy's ctypes pointers (FMU2Slave.dll, "
           "fmpy's argument types; no fmpy wrapper in the loop; the loop checks the status itself)",
    "getreal_list": "fmpy FMU2Slave.doStep + FMU2Slave.getReal(list of value references): a ctypes array of "
                    "references and of values built and a list returned on every call",
}


def _open_fmu(unzipdir, md, start_values):
    """An fmpy FMU2Slave instantiated and initialised with start_values (name: value, set as the
    variable's declared type)."""
    from fmpy.fmi2 import FMU2Slave

    var = {v.name: v for v in md.modelVariables}
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir,
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bench")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    for name, value in start_values.items():
        if var[name].type == "Integer":
            fmu.setInteger([var[name].valueReference], [int(value)])
        else:
            fmu.setReal([var[name].valueReference], [float(value)])
    fmu.exitInitializationMode()
    return fmu


def _fmu_loop(fmu_path, unzipdir, md, stop_s, comm_s, start_values, record=None, loop="lean", rows=None,
              outputs=("dte", "mesh_force"), noop=None):
    """Timed fmpy doStep/getReal loop (``loop``: a key of FMPY_LOOPS) over round(stop_s / comm_s)
    communication steps; returns (instantiate + initialise s, loop wall s, steps, last outputs, loop CPU s
    of this thread: the wall time without the time the thread waited for a core on a shared machine).
    ``record`` (a list): the first output at every communication point is appended (row 0 the
    initial one); ``rows`` (a list): every output.  ``noop`` (a ctypes library of
    benchmarks/fmi2_noop.c): the loop calls its fmi2DoStep and fmi2GetReal, with fmpy's argument
    types and through fmpy's own wrappers, instead of the FMU's (:func:`python_floor`)."""
    from fmpy.fmi2 import fmi2Real, fmi2ValueReference

    vrs = [next(v.valueReference for v in md.modelVariables if v.name == o) for o in outputs]
    t0 = time.perf_counter()
    fmu = _open_fmu(unzipdir, md, start_values)
    t_init = time.perf_counter() - t0
    real_functions = dict(fmu._functions)
    if noop is not None:
        for name in ("fmi2DoStep", "fmi2GetReal"):
            f = getattr(noop, name)
            f.argtypes, f.restype = real_functions[name].argtypes, real_functions[name].restype
            fmu._functions[name] = f
    n = int(round(stop_s / comm_s))
    nv = len(vrs)
    vr_arr = (fmi2ValueReference * nv)(*vrs)
    vals = (fmi2Real * nv)()
    comp = fmu.component
    do_step, get_real = fmu.doStep, fmu.fmi2GetReal
    if loop == "raw":
        do_step, get_real = fmu._functions["fmi2DoStep"], fmu._functions["fmi2GetReal"]
    elif loop not in FMPY_LOOPS:
        raise ValueError(f"loop: {loop!r} unknown; choose one of {sorted(FMPY_LOOPS)}")
    get_real(comp, vr_arr, nv, vals)

    def keep(v):
        if record is not None:
            record.append(v[0])
        if rows is not None:
            rows.append(list(v))
    keep(vals)
    kept = record is not None or rows is not None
    t = 0.0
    c1 = time.thread_time()
    t1 = time.perf_counter()
    if loop == "lean":
        for _ in range(n):
            do_step(t, comm_s)
            get_real(comp, vr_arr, nv, vals)
            if kept:
                keep(vals)
            t += comm_s
    elif loop == "raw":
        for _ in range(n):
            if do_step(comp, t, comm_s, 1) or get_real(comp, vr_arr, nv, vals):
                raise RuntimeError(f"fmi2DoStep / fmi2GetReal at t = {t!r} s: status not OK")
            if kept:
                keep(vals)
            t += comm_s
    else:
        for _ in range(n):
            do_step(t, comm_s)
            v = fmu.getReal(vrs)
            if kept:
                keep(v)
            t += comm_s
    wall = time.perf_counter() - t1
    cpu = time.thread_time() - c1
    last = list(vals) if loop != "getreal_list" else fmu.getReal(vrs)
    fmu._functions.update(real_functions)
    fmu.terminate()
    fmu.freeInstance()
    return t_init, wall, n, last, cpu


def python_floor(unzipdir, md, start_values, *, sim_s, comm_s, repeat, tmp):
    """The fmpy loops of FMPY_LOOPS around benchmarks/fmi2_noop.c's fmi2DoStep and fmi2GetReal
    (compiled here with the system cc): per loop the wall s, the loop's CPU s, the real-time
    factor (simulated s / wall s, best of ``repeat``, at least 10) and the nanoseconds per communication step
    when the FMU costs nothing -- the ceiling of every FMU driven through that loop on this
    machine and interpreter."""
    import ctypes
    import subprocess

    lib = Path(tmp) / "libfmi2_noop.so"
    subprocess.run(["cc", "-O2", "-shared", "-fPIC", "-o", str(lib), str(Path(__file__).with_name("fmi2_noop.c"))],
                   check=True, capture_output=True)
    noop = ctypes.CDLL(str(lib))
    out = {}
    for loop in FMPY_LOOPS:
        wall = cpu = math.inf
        for _ in range(max(repeat, 10)):  # short loops: the best of many is the one nobody interrupted
            _, w, n, _, c = _fmu_loop(None, unzipdir, md, sim_s, comm_s, start_values, loop=loop, noop=noop)
            wall, cpu = min(wall, w), min(cpu, c)
        out[loop] = {"wall_s": wall, "cpu_s": cpu, "real_time_factor": sim_s / wall,
                     "ns_per_step": 1e9 * cpu / n}
    return out


def fmpy_call_ns(unzipdir, md, start_values, calls=20000, repeat=5):
    """Nanoseconds per call of fmi2GetReal with no value reference (the FMU's state check and
    nothing else) through each layer of fmpy: ``raw`` the ctypes pointer (the ctypes call
    itself), ``wrapped`` FMU2Slave.fmi2GetReal (fmpy's status check and logger hook on top)."""
    from fmpy.fmi2 import fmi2Real, fmi2ValueReference

    fmu = _open_fmu(unzipdir, md, start_values)
    comp, vr_arr, vals = fmu.component, (fmi2ValueReference * 1)(0), (fmi2Real * 1)()
    raw, wrapped = fmu.dll.fmi2GetReal, fmu.fmi2GetReal

    def per_call(fn):
        best = float("inf")
        for _ in range(repeat):
            t0 = time.thread_time()
            for _ in range(calls):
                fn(comp, vr_arr, 0, vals)
            best = min(best, time.thread_time() - t0)
        return 1e9 * best / calls
    out = {"raw": per_call(raw), "wrapped": per_call(wrapped)}
    fmu.terminate()
    fmu.freeInstance()
    return out


def c_layers(unzipdir, md, comm_s, n_steps, repeat, max_step_s, integrator_code, reals, tmp):
    """benchmarks/fmu_layers.c compiled with the FMU's own sources/ at its compile flags and run:
    nanoseconds per call of the kernel, the shared checks, fmi2DoStep, fmi2DoStep + fmi2GetReal
    and fmi2GetReal alone, over the same trajectory (its header comment)."""
    import subprocess

    from gearfmu.fmu.standalone_build import STANDALONE_CFLAGS, binary_sources

    unzipdir = Path(unzipdir).resolve()  # the resource URI is file://<absolute path>
    src = unzipdir / "sources"
    exe = Path(tmp) / "fmu_layers"
    flags = [f for f in STANDALONE_CFLAGS if f not in ("-fPIC", "-shared", "-fvisibility=hidden")]
    files = [str(src / f) for f in binary_sources(2)]
    subprocess.run(["cc", *flags, f"-I{src}", "-o", str(exe), str(Path(__file__).with_name("fmu_layers.c")),
                    *files, "-lm"], check=True, capture_output=True)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    args = [str(exe), str(unzipdir), md.guid, repr(comm_s), str(n_steps), str(repeat),
            f"{vr['dte']},{vr['mesh_force']}", str(vr["max_step"]), repr(max_step_s), str(vr["integrator"]),
            str(integrator_code)] + [f"{vr[k]}={v!r}" for k, v in reals.items()]
    proc = subprocess.run(args, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"fmu_layers exit {proc.returncode}: {proc.stderr.strip()}")
    return json.loads(proc.stdout)


def step_costs(unzipdir, md, *, sim_s, comm_s, max_step_s, integrator, reals, repeat):
    """Where one communication step goes, measured in one run on one FMU (same tables, integrator,
    max_step and inputs for every host): the real-time factor (simulated s / loop wall s, and
    the same on the loop's CPU time) through the C host (benchmarks/fmu_rtf_host.c) and each fmpy
    loop (FMPY_LOOPS), the hosts in turn, best of ``repeat`` (at least 10) each; ``c_layers`` (c_layers) and
    ``per_step_ns``: nanoseconds per communication step of each layer -- the kernel, the FMU's
    fixed cost (fmi2DoStep + fmi2GetReal beyond the kernel; its shared checks, its FMI 2
    plumbing, its fmi2GetReal), and from the hosts' CPU times: the Python loop with its two
    ctypes calls (fmpy raw - C host), fmpy's wrappers (lean - raw) and FMU2Slave.getReal's
    list building (getreal_list - lean).  ``per_call_ns_fmi2GetReal_no_refs``: fmpy_call_ns."""
    sys.path.insert(0, str(Path(__file__).parent))
    from bench_fmu_rtf import INTEGRATOR_CODE, compile_host, host_run

    code = INTEGRATOR_CODE[integrator]
    vr = {v.name: v.valueReference for v in md.modelVariables}
    start = dict(reals, max_step=max_step_s, integrator=code)
    n = int(round(sim_s / comm_s))
    repeat = max(repeat, 10)  # short loops: more of them, the best one is the one nobody interrupted
    tmp = Path(tempfile.mkdtemp(prefix="gearfmu_steps_"))
    walls = {"c_host": math.inf, **{k: math.inf for k in FMPY_LOOPS}}
    cpus = dict(walls)
    rows = {k: [] for k in FMPY_LOOPS}
    try:
        exe = compile_host(tmp)
        layers = c_layers(unzipdir, md, comm_s, n, 4 * repeat, max_step_s, code, reals, tmp)
        for r in range(repeat):  # the hosts in turn, best of `repeat` each (a shared machine)
            w, c, c_rows = host_run(exe, unzipdir, md, vr, sim_s=sim_s, comm_s=comm_s, repeat=1,
                                    max_step_s=max_step_s, integrator=integrator, reals=reals)
            walls["c_host"], cpus["c_host"] = min(walls["c_host"], w), min(cpus["c_host"], c)
            for loop in FMPY_LOOPS:
                _, w, _, _, c = _fmu_loop(None, unzipdir, md, sim_s, comm_s, start, loop=loop,
                                          rows=rows[loop] if r == 0 else None)
                walls[loop], cpus[loop] = min(walls[loop], w), min(cpus[loop], c)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    c_wall, c_cpu = walls.pop("c_host"), cpus.pop("c_host")
    calls = fmpy_call_ns(unzipdir, md, start, repeat=repeat)
    ns = {k: 1e9 * w / n for k, w in cpus.items()}
    c_ns = 1e9 * c_cpu / n
    per_step = {
        "kernel": layers["kernel_ns"],
        "fmu_fixed": layers["step_get_ns"] - layers["kernel_ns"],
        "fmu_shared_checks": layers["shared_ns"] - layers["kernel_ns"],
        "fmu_fmi2_dostep_plumbing": layers["dostep_ns"] - layers["shared_ns"],
        "fmu_fmi2_getreal": layers["getreal_ns"],
        "c_host_step": c_ns,
        "fmpy_raw_step": ns["raw"],
        "fmpy_lean_step": ns["lean"],
        "fmpy_getreal_list_step": ns["getreal_list"],
        "python_loop_and_two_ctypes_calls": ns["raw"] - c_ns,
        "fmpy_wrappers": ns["lean"] - ns["raw"],
        "getreal_list_building": ns["getreal_list"] - ns["lean"],
    }
    return {
        "loops": {"c_host": "benchmarks/fmu_rtf_host.c: dlopen, fmi2DoStep + fmi2GetReal(dte, mesh_force) per step",
                  **{f"fmpy_{k}": v for k, v in FMPY_LOOPS.items()}},
        "c_host_wall_s": c_wall, "c_host_real_time_factor": sim_s / c_wall,
        "c_host_cpu_s": c_cpu, "c_host_cpu_real_time_factor": sim_s / c_cpu,
        **{f"fmpy_{k}_wall_s": w for k, w in walls.items()},
        **{f"fmpy_{k}_real_time_factor": sim_s / w for k, w in walls.items()},
        **{f"fmpy_{k}_cpu_s": c for k, c in cpus.items()},
        **{f"fmpy_{k}_cpu_real_time_factor": sim_s / c for k, c in cpus.items()},
        "fmpy_loops_same_outputs": all(rows[k] == rows["lean"] for k in rows),
        "fmpy_outputs_equal_c_host": bool(np.array_equal(np.array(rows["lean"]), c_rows)),
        "c_layers": layers,
        "per_call_ns_fmi2GetReal_no_refs": calls,
        "per_step_ns": per_step,
    }


def rtf_at_error(tables, *, T1, T2, w0, zeta, damping_model, integrator, target, comm_s, sim_s, repeat):
    """The ``rtf`` block of the report (module docstring)."""
    from fmpy import extract, read_model_description

    from gearfmu.dynamics.native import simulate
    from gearfmu.fmu.standalone_build import build_standalone_fmu
    from gearfmu.fmu.pythonfmu_build import compile_kernel
    from gearfmu.fmu.runtime.kernel_api import load_kernel
    sys.path.insert(0, str(Path(__file__).parent))
    from bench_integrators import c_runner

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
            walls.append(_fmu_loop(path, unz, md, sim_s, comm_s, {"pinion_torque": T1, "gear_torque": T2},
                                   record=rec)[1])
        shutil.rmtree(unz, ignore_errors=True)
        lib = load_kernel(compile_kernel(tmp))
        code = {"rk4": 0, "rk4_kink": 1, "rk4_node": 2}[integrator]
        dm = {"elastobacklash": 0, "contact_zone": 1}[damping_model]
        nsteps = int(round(sim_s / comm_s))
        kwall = min(c_runner(tables, T1, T2, w0, zeta, float(fine.dte[0]), comm_s, nsteps, h, code, lib,
                             damping_model=dm)[0] for _ in range(repeat))
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
        print(json.dumps({"scene": scene.name, "rtf": rep}, indent=1))
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
            ti, wb, _, _, _ = _fmu_loop(res.fmu_path, unz, md, sim, big, sv)
            inits.append(ti)
            fmu_big.append(wb)
            _, ws, _, _, _ = _fmu_loop(res.fmu_path, unz, md, sim, small, sv)
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
        print(json.dumps(report, indent=1))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
