"""What the benchmarks share: timing, JSON output, the FMU hosts (fmpy loops, the C host, the C kernel
through ctypes) and the per-step cost split.  Every benchmark imports shared code from here only,
never from another benchmark (tests/project/test_benchmarks.py).

Timing: :func:`best_of` (the best of ``repeat`` runs: the machines are shared and noisy, the best run
is the one nobody interrupted); JSON: :func:`emit` (one JSON object on stdout, progress goes to stderr).

Hosts of a standalone FMU, all on the same unzipped FMU and model description:

* :func:`fmu_loop` -- a timed fmpy loop (``FMPY_LOOPS``: ``lean`` FMU2Slave.doStep + fmi2GetReal on
  ctypes arrays built once, ``raw`` the FMU's own functions through fmpy's ctypes pointers,
  ``getreal_list`` FMU2Slave.getReal with a list); :func:`python_floor` the same loops around two C
  functions that do nothing (benchmarks/fmi2_noop.c): the ceiling of any FMU through that loop;
* :func:`compile_host` / :func:`host_run` -- benchmarks/fmu_rtf_host.c, a plain C FMI 2.0 host
  (dlopen, doStep + getReal per communication step);
* :func:`c_runner` -- the C kernel alone (gk_do_step through ctypes, one call per communication step);
* :func:`c_layers` -- benchmarks/fmu_layers.c: nanoseconds per call of each layer of the FMU;
* :func:`step_costs` -- where one communication step goes: the kernel, the FMU's fixed cost, the ctypes
  calls and fmpy's wrappers, and the rate through the C host and each fmpy loop.

Run a benchmark as a script (``python benchmarks/bench_x.py``): its folder is then first on
``sys.path`` and ``from harness import ...`` finds this module.
"""
from __future__ import annotations

import json
import math
import shutil
import subprocess
import tempfile
import time
import zipfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

#: the FMU's ``integrator`` parameter per integrator name (modeldescription/variables.toml)
INTEGRATOR_CODE = {"rk4": 0, "rk4_kink": 1, "rk4_node": 2, "rk4_seg": 3}

#: the Python loops of fmu_loop: one doStep and one getReal of the outputs per
#: communication step, the FMU instantiated once (what each number in the JSON came from)
FMPY_LOOPS = {
    "lean": "fmpy FMU2Slave.doStep + FMU2Slave.fmi2GetReal (fmpy's status-checked function) on ctypes "
            "arrays of value references and values built once",
    "raw": "the FMU library's own fmi2DoStep / fmi2GetReal through fmpy's ctypes pointers (FMU2Slave.dll, "
           "fmpy's argument types; no fmpy wrapper in the loop; the loop checks the status itself)",
    "getreal_list": "fmpy FMU2Slave.doStep + FMU2Slave.getReal(list of value references): a ctypes array of "
                    "references and of values built and a list returned on every call",
}


# ================================================================ timing and output
def best_of(repeat: int, run):
    """The smallest of ``repeat`` (at least 1) calls of ``run()`` (a time in s)."""
    return min(run() for _ in range(max(1, repeat)))


def emit(report) -> None:
    """The benchmark's result: one JSON object on stdout (indent 1)."""
    print(json.dumps(report, indent=1))


# ================================================================ fmpy loops
def open_fmu_slave(unzipdir, md, start_values):
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


def fmu_loop(fmu_path, unzipdir, md, stop_s, comm_s, start_values, record=None, loop="lean", rows=None,
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
    fmu = open_fmu_slave(unzipdir, md, start_values)
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

    lib = Path(tmp) / "libfmi2_noop.so"
    subprocess.run(["cc", "-O2", "-shared", "-fPIC", "-o", str(lib), str(HERE / "fmi2_noop.c")],
                   check=True, capture_output=True)
    noop = ctypes.CDLL(str(lib))
    out = {}
    for loop in FMPY_LOOPS:
        wall = cpu = math.inf
        for _ in range(max(repeat, 10)):  # short loops: the best of many is the one nobody interrupted
            _, w, n, _, c = fmu_loop(None, unzipdir, md, sim_s, comm_s, start_values, loop=loop, noop=noop)
            wall, cpu = min(wall, w), min(cpu, c)
        out[loop] = {"wall_s": wall, "cpu_s": cpu, "real_time_factor": sim_s / wall,
                     "ns_per_step": 1e9 * cpu / n}
    return out


def fmpy_call_ns(unzipdir, md, start_values, calls=20000, repeat=5):
    """Nanoseconds per call of fmi2GetReal with no value reference (the FMU's state check and
    nothing else) through each layer of fmpy: ``raw`` the ctypes pointer (the ctypes call
    itself), ``wrapped`` FMU2Slave.fmi2GetReal (fmpy's status check and logger hook on top)."""
    from fmpy.fmi2 import fmi2Real, fmi2ValueReference

    fmu = open_fmu_slave(unzipdir, md, start_values)
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


# ================================================================ C hosts
def compile_host(tmp: Path) -> Path:
    """benchmarks/fmu_rtf_host.c compiled with the system cc against fmpy's FMI 2 headers."""
    from gearfmu.fmu.build_steps import fmi2_header_dir

    exe = Path(tmp) / "fmu_rtf_host"
    subprocess.run(["cc", "-std=c99", "-O2", "-Wall", f"-I{fmi2_header_dir()}", "-o", str(exe),
                    str(HERE / "fmu_rtf_host.c"), "-ldl"], check=True)
    return exe


def host_run(exe, unz, md, vr=None, *, sim_s, comm_s, repeat, max_step_s, integrator, reals=None,
             outputs=("dte", "mesh_force"), timeout=None):
    """(best wall s, best CPU s, rows of the ``outputs``) of the C host (:func:`compile_host`) on the
    unzipped FMU ``unz``: ``repeat`` runs of ``sim_s`` simulated seconds at the communication step
    ``comm_s``, the FMU's ``max_step`` and ``integrator`` (a name of INTEGRATOR_CODE or its code)
    parameters and the ``reals`` (name: value) set in initialization mode.  ``vr``: the value
    references by name (None: read from ``md``)."""
    vr = vr or {v.name: v.valueReference for v in md.modelVariables}
    code = INTEGRATOR_CODE[integrator] if isinstance(integrator, str) else int(integrator)
    args = [str(exe), str(unz), md.coSimulation.modelIdentifier, md.guid, repr(sim_s), repr(comm_s), str(repeat),
            ",".join(str(vr[n]) for n in outputs), str(vr["max_step"]), repr(max_step_s), str(vr["integrator"]),
            str(code)] + [f"{vr[k]}={v!r}" for k, v in (reals or {}).items()]
    proc = subprocess.run(args, capture_output=True, text=True, timeout=timeout)
    if proc.returncode != 0:
        raise RuntimeError(f"fmu_rtf_host exit {proc.returncode}: {proc.stderr.strip()[-2000:]}")
    out = proc.stdout.splitlines()
    head = json.loads(out[0])
    return min(head["wall_s"]), min(head["cpu_s"]), np.array([[float(x) for x in r.split(",")] for r in out[1:]])


def c_runner(tb, T1, T2, w0, zeta, x0, H, n, hmax, integrator, lib, damping_model=0):
    """(wall s, final state) of ``n`` communication steps of ``H`` s through the C kernel alone
    (``lib``: gearfmu.fmu.runtime.kernel_api.load_kernel of a compiled kernel; gk_do_step per step,
    internal steps of at most ``hmax``); torques T1, T2 (N m), start speed w0 (rad/s), damping ratio
    ``zeta``, start DTE x0 (m), ``integrator`` and ``damping_model`` the kernel's codes."""
    k = np.ascontiguousarray(tb.k_N_per_m)
    e = np.ascontiguousarray(tb.e_m)
    b = np.ascontiguousarray(tb.backlash_half_m)
    tq = np.ascontiguousarray(tb.torque_Nm, dtype=float)
    m = np.zeros(lib.gk_sizeof_model() // 8 + 2)
    out = np.zeros(lib.gk_n_outputs(tb.slots))
    lib.gk_init(m.ctypes.data, tb.slots, tb.n_phi, len(tq), tq.ctypes.data, k.ctypes.data, e.ctypes.data,
                b.ctypes.data, tb.phi_period_rad, tb.base_radius_pinion_m, tb.base_radius_gear_m,
                tb.inertia_pinion_kgm2, tb.inertia_gear_kgm2, tb.k_mean_N_per_m)
    lib.gk_set_damping(m.ctypes.data, zeta, damping_model)
    lib.gk_set_integrator(m.ctypes.data, integrator)
    s = np.array([0.0, w0, x0, 0.0])
    pm, ps, po = m.ctypes.data, s.ctypes.data, out.ctypes.data
    t0 = time.perf_counter()
    for _ in range(n):
        lib.gk_do_step(pm, ps, T1, T2, H, hmax, po)
    return time.perf_counter() - t0, s.copy()


def c_layers(unzipdir, md, comm_s, n_steps, repeat, max_step_s, integrator_code, reals, tmp):
    """benchmarks/fmu_layers.c compiled with the FMU's own sources/ at its compile flags and run:
    nanoseconds per call of the kernel, the shared checks, fmi2DoStep, fmi2DoStep + fmi2GetReal
    and fmi2GetReal alone, over the same trajectory (its header comment)."""
    from gearfmu.fmu.standalone_build import STANDALONE_CFLAGS, file_sources, fmi2_header_dir

    unzipdir = Path(unzipdir).resolve()  # the resource URI is file://<absolute path>
    src = unzipdir / "sources"
    exe = Path(tmp) / "fmu_layers"
    flags = [f for f in STANDALONE_CFLAGS if f not in ("-fPIC", "-shared", "-fvisibility=hidden")]
    files = [str(src / f) for f in file_sources(2)]  # one by one: fmu_layers.c calls the kernel's functions
    subprocess.run(["cc", *flags, f"-I{src}", f"-I{fmi2_header_dir()}", "-o", str(exe),
                    str(HERE / "fmu_layers.c"), *files, "-lm"], check=True, capture_output=True)
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
                _, w, _, _, c = fmu_loop(None, unzipdir, md, sim_s, comm_s, start, loop=loop,
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


def unzip_fmu(fmu, d):
    """The FMU unzipped into folder d; its model description (fmpy)."""
    import fmpy

    d.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(fmu) as z:
        z.extractall(d)
    return fmpy.read_model_description(str(fmu))


def at_error(points, key, target):
    """(step s, CPU s) where the error ``key(point)`` of a sweep reaches ``target``: log-log interpolation
    between the two sweep points around it (error rising with the step); None outside the sweep."""
    pts = sorted(points, key=lambda p: p["max_step_s"])
    for a, b in zip(pts, pts[1:]):
        ea, eb = key(a), key(b)
        if ea <= target <= eb and eb > ea > 0:
            t = (math.log(target) - math.log(ea)) / (math.log(eb) - math.log(ea))
            h = math.exp(math.log(a["max_step_s"]) + t * (math.log(b["max_step_s"]) - math.log(a["max_step_s"])))
            c = math.exp(math.log(a["cpu_s"]) + t * (math.log(b["cpu_s"]) - math.log(a["cpu_s"])))
            return h, c
    return None


def front_at(rows, target, key="wall_s"):
    """The cost ``key`` (a row's wall_s or cpu_s) at relative RMS DTE error ``target`` along the rows' own
    front, the rows that lower the error at a higher cost (log-log interpolation between the front's points
    around it; the cheapest row's cost when it already beats the target; None when the front does not reach
    it)."""
    pts = sorted((r[key], r["dte_rel_rms_err"]) for r in rows if math.isfinite(r["dte_rel_rms_err"]))
    front, best = [], math.inf
    for w, e in pts:
        if e < best:
            front.append((w, e))
            best = e
    for (w0, e0), (w1, e1) in zip(front, front[1:]):
        if e1 <= target <= e0:
            f = (math.log(target) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(w0) + f * (math.log(w1) - math.log(w0)))
    if front and front[0][1] <= target:
        return front[0][0]
    return None


def worst_mesh_errors(res, ref, mesh_names) -> dict:
    """The worst mesh's RMS and max |res - ref| of the DTE and the mesh force over the communication
    instants, relative to the reference's range (nan when res has NaN): ``dte_rel_rms_err``,
    ``dte_rel_max_err``, ``force_rel_rms_err``, ``force_rel_max_err``."""
    out = {}
    for key, col in (("dte", "dte"), ("force", "mesh_force")):
        rms, mx = [], []
        for m in mesh_names:
            d = res[f"{m}.{col}"] - ref[f"{m}.{col}"]
            rng = float(np.ptp(ref[f"{m}.{col}"])) or 1.0
            rms.append(float(np.sqrt(np.mean(d ** 2)) / rng))
            mx.append(float(np.max(np.abs(d)) / rng))
        out[f"{key}_rel_rms_err"] = max(rms)
        out[f"{key}_rel_max_err"] = max(mx)
    return out
