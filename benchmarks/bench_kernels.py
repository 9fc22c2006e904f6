#!/usr/bin/env python3
"""Benchmark: per-internal-step cost of the C kernel (gearkernel.c, the FMUs'
kernel) against the numba native kernel (gearfmu.dynamics.native), measured in one run.

Both integrate the same tables with the same substeps, once per integrator
('rk4' and 'rk4_kink', docs/model.md; the integrator code is set in the C model
with ``gk_set_integrator``): a communication step spans ``--substeps`` internal
steps, so per-call overhead (ctypes for C, the Python wrapper for numba) is
spread thin.  For 'rk4_kink' a "step" is a nominal substep, events included.  C: ``gk_do_step`` called via
ctypes on the kernel compiled exactly as the FMUs compile it; numba:
``gearfmu.dynamics.native.simulate`` (its ``wall_s`` excludes JIT compilation).  Two
cases: the default scene's tables and a hard case with contact loss and
impacts (rectangular-wave tables with backlash, light load).

Prints one JSON object: per case and integrator (key ``case/integrator``)
``c_ns_per_step``, ``numba_ns_per_step``, ``numba_over_c`` and ``events``, and
``max_numba_over_c`` over all (the goal: numba within 1.3x of C per step).

``--proxy PATH`` (optional) names the C source of a plain-C speed reference: a
program that takes a step count as its argument and prints one JSON object
with ``ns_per_step`` (e.g. a hand-written RK4 loop of a simplified multi-pair
model).  It is compiled with the FMU kernel's own flags
(``gearfmu.fmu.pythonfmu_build.CFLAGS`` without ``-shared``), run for as many steps as the
kernel takes, and every row then also carries ``proxy_ns_per_step``,
``c_over_proxy`` and ``numba_over_proxy`` (the goal: the kernel within 1.5x
of the proxy on the default scene's 'rk4').  Without it no proxy columns.

C, numba (and proxy) runs alternate, so all see the same machine load.
Each timing is the best of ``--repeat`` runs (shared, noisy machines: compare
ratios, not absolute times).  ``--clock cpu`` (default) counts CPU time, which
time slices lost to other processes do not inflate: the C loop's thread time;
numba's as the thread time of ``simulate`` minus that of a one-step
``simulate`` (its set-up); the proxy's as the CPU time of the child for the
steps minus that for one step (process start).  ``--clock wall``: wall time
(numba's ``wall_s``, the proxy's own report).

    python benchmarks/bench_kernels.py [--sim-time 0.2] [--substeps 100] [--repeat 5]
        [--integrators rk4,rk4_kink] [--proxy PATH] [--clock cpu|wall]
"""
import argparse
import hashlib
import json
import math
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))


def _c_kernel(tmp):
    from gearfmu.fmu.pythonfmu_build import compile_kernel
    from gearfmu.fmu.runtime.kernel_api import load_kernel

    return load_kernel(compile_kernel(tmp))


def _proxy_binary(source, tmp):
    """Compile the proxy's C source with the kernel's flags; return (binary, command)."""
    from gearfmu.fmu.pythonfmu_build import CFLAGS, find_c_compiler

    src = Path(source)
    if not src.is_file():
        sys.exit(f"--proxy: {source}: no such file")
    exe = Path(tmp) / "proxy"
    cmd = [find_c_compiler(), *[f for f in CFLAGS if f != "-shared"], "-o", str(exe), str(src), "-lm"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit(f"--proxy: {source}: compilation failed ({' '.join(cmd)}):\n{proc.stderr}")
    return exe, cmd


def _child_cpu_s(cmd):
    """CPU time (s) of one child process running cmd, and its stdout."""
    import resource

    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run(cmd, capture_output=True, text=True, check=True)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime), proc.stdout


def _run_proxy(exe, n_steps, clock):
    """ns per step of the proxy over n_steps steps: its own report (wall), or
    the CPU time of the run minus that of a one-step run (cpu)."""
    if clock == "wall":
        proc = subprocess.run([str(exe), str(n_steps)], capture_output=True, text=True, check=True)
        return float(json.loads(proc.stdout)["ns_per_step"])
    full, _ = _child_cpu_s([str(exe), str(n_steps)])
    one, _ = _child_cpu_s([str(exe), "1"])
    return (full - one) / (n_steps - 1) * 1e9


def _run_c(lib, t, case, n_comm, H, hmax, icode):
    arrs = [np.ascontiguousarray(a, dtype=np.float64) for a in (t.torque_Nm, t.k_N_per_m, t.e_m, t.backlash_half_m)]
    model = np.zeros(lib.gk_sizeof_model() // 8 + 2)
    state = np.zeros(lib.gk_sizeof_state() // 8 + 1)
    out = np.zeros(lib.gk_n_outputs(t.slots))
    pm, ps, po = model.ctypes.data, state.ctypes.data, out.ctypes.data
    assert lib.gk_init(pm, t.slots, t.n_phi, t.n_torque, *[a.ctypes.data for a in arrs], t.phi_period_rad,
                       t.base_radius_pinion_m, t.base_radius_gear_m, t.inertia_pinion_kgm2, t.inertia_gear_kgm2,
                       t.k_mean_N_per_m) == 0
    assert lib.gk_set_damping(pm, case["zeta"], 0) == 0
    assert lib.gk_set_integrator(pm, icode) == 0
    assert lib.gk_initialize(pm, ps, 0.0, case["w0"], case["T1"]) == 0
    step = lib.gk_do_step
    T1, T2 = case["T1"], case["T2"]
    t0, c0 = time.perf_counter(), time.thread_time()
    for _ in range(n_comm):
        if step(pm, ps, T1, T2, H, hmax, po) != 0:
            raise RuntimeError("C kernel step failed")
    return time.perf_counter() - t0, time.thread_time() - c0, float(out[4])


def _cases():
    from gearfmu.dynamics.native import choose_max_step_s
    from gearfmu.pipeline import compute_tables, gear_torque_for, load
    from gearfmu.tables.synthetic import rectangular_wave_tables

    scene = load(None)
    td = compute_tables(scene)
    ti = rectangular_wave_tables(1e8, contact_ratio=1.6, backlash_half_m=20e-6,
                                 pair_error_m=lambda j, u: 10e-6 * np.sin(np.pi * u) * (1 + 0.5 * j))
    wi = math.sqrt(ti.k_mean_N_per_m / ti.equivalent_mass_kg) * ti.mesh_period_rad / (2 * math.pi)
    T1 = scene.operating.torque_Nm
    return {
        "default_scene": dict(tables=td, T1=T1, T2=gear_torque_for(td, T1), w0=scene.operating.speed_rad_s,
                              zeta=scene.fmu.damping_ratio,
                              hmax=choose_max_step_s(td, 1.5 * scene.operating.speed_rad_s)),
        "impacts": dict(tables=ti, T1=10.0, T2=gear_torque_for(ti, 10.0), w0=wi, zeta=0.02, hmax=4.5e-6),
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sim-time", type=float, default=0.2, help="simulated time per run, s")
    ap.add_argument("--substeps", type=int, default=100, help="internal steps per communication step")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--integrators", default="rk4,rk4_kink", help="comma-separated integrator names")
    ap.add_argument("--proxy", metavar="PATH", help="C source of a plain-C speed reference (see above); "
                    "adds proxy_ns_per_step, c_over_proxy, numba_over_proxy")
    ap.add_argument("--clock", choices=("cpu", "wall"), default="cpu", help="what is timed (see above)")
    a = ap.parse_args(argv)
    from gearfmu.dynamics.native import INTEGRATORS, simulate

    report = {"benchmark": "bench_kernels", "python": sys.version.split()[0], "machine": platform.machine(),
              "sim_time_s": a.sim_time, "substeps_per_comm_step": a.substeps, "repeat": a.repeat,
              "clock": a.clock, "cases": {}}
    with tempfile.TemporaryDirectory() as tmp:
        lib = _c_kernel(tmp)
        proxy = None
        if a.proxy:
            proxy, cmd = _proxy_binary(a.proxy, tmp)
            report["proxy"] = {"source": Path(a.proxy).name,
                               "sha256": hashlib.sha256(Path(a.proxy).read_bytes()).hexdigest(),
                               "flags": cmd[1:-4]}
        for name, c in _cases().items():
            t = c["tables"]
            hmax = c["hmax"]
            H = a.substeps * hmax * (1 - 1e-9)  # exactly `substeps` internal steps of <= hmax
            n_comm = max(2, int(a.sim_time / H))
            n_steps = n_comm * a.substeps
            for integ in a.integrators.split(","):
                kw = dict(stop_time_s=n_comm * H, comm_step_s=H, max_step_s=hmax, pinion_torque_Nm=c["T1"],
                          gear_torque_Nm=c["T2"], pinion_speed_start_rad_s=c["w0"], damping_ratio=c["zeta"],
                          integrator=integ)
                one = dict(kw, stop_time_s=H)
                simulate(t, **one)  # JIT warm-up
                nb, cc, px = [], [], []
                # interleaved, best of `repeat`: all see the same machine load
                for _ in range(a.repeat):
                    c0 = time.thread_time()
                    r = simulate(t, **kw)
                    c1 = time.thread_time()
                    simulate(t, **one)
                    c2 = time.thread_time()
                    # ns per internal step
                    nb.append(r.wall_s / n_steps * 1e9 if a.clock == "wall"
                              else ((c1 - c0) - (c2 - c1)) / (n_steps - a.substeps) * 1e9)
                    w, cpu, dte_c = _run_c(lib, t, c, n_comm, H, hmax, INTEGRATORS[integ])
                    cc.append((w if a.clock == "wall" else cpu) / n_steps * 1e9)
                    if proxy is not None:
                        px.append(_run_proxy(proxy, n_steps, a.clock))
                rel = abs(float(r.dte[-1]) - dte_c) / max(float(np.ptp(r.dte)), 1e-300)
                row = {
                    "case": name, "integrator": integ, "slots": t.slots, "internal_steps": n_steps,
                    "max_step_s": hmax, "events": int(r.info.get("events", 0)),
                    "c_ns_per_step": min(cc), "numba_ns_per_step": min(nb),
                    "numba_over_c": min(nb) / min(cc), "final_dte_rel_diff": rel,
                }
                if px:
                    row["proxy_ns_per_step"] = min(px)
                    row["c_over_proxy"] = row["c_ns_per_step"] / min(px)
                    row["numba_over_proxy"] = row["numba_ns_per_step"] / min(px)
                report["cases"][f"{name}/{integ}"] = row
                extra = (f", proxy {row['proxy_ns_per_step']:.0f} ns/step, C/proxy {row['c_over_proxy']:.2f}"
                         if px else "")
                print(f"{name} {integ}: C {row['c_ns_per_step']:.0f} ns/step, numba "
                      f"{row['numba_ns_per_step']:.0f} ns/step, ratio {row['numba_over_c']:.2f}, "
                      f"events {row['events']}{extra}", file=sys.stderr, flush=True)
    report["goal"] = "numba_over_c <= 1.3 for every case"
    report["max_numba_over_c"] = max(r["numba_over_c"] for r in report["cases"].values())
    if a.proxy:
        report["proxy_goal"] = "c_over_proxy <= 1.5 for default_scene/rk4 (same compile flags)"
    print(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
