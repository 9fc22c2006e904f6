"""Speed against error of the integrators 'rk4' and 'rk4_kink' (docs/model.md), and
numba against the C kernel per step.  Prints JSON (stdout); progress on stderr.

Case: the impact case of tests/test_integrators.py (rectangular-wave TVMS, errors,
backlash, light load, impact start), 4 mesh periods, 8 communication steps per
mesh period.  Reference: rk4_kink at h = H/3200 (its error there is ~1e-11 of
the range, tests/test_integrators.py shows it agrees with an event-located
solve_ivp to the reference's own 1e-9 level).  Errors: RMS and maximum of
|dte - dte_ref| and |mesh_force - F_ref| over the communication points,
relative to the reference's range.  Times: best of `--repeat` runs of the
compiled loop (native ``wall_s``; the C kernel through ctypes, one call per
communication step).  ``event_cost``: where rk4_kink's time goes -- its events
(table nodes and contact-mode changes it steps to), the net table-node crossings
among them (cell changes of theta1 between communication points) and the cost
per substep and per event (least squares wall = a*substeps + b*events over the
rows of one integrator).
Usage: python benchmarks/bench_integrators.py [--repeat 3]
"""
import argparse
import ctypes
import json
import sys
import tempfile
import time

import numpy as np

from gearfmu.fmu.pythonfmu_build import compile_kernel
from gearfmu.dynamics.native import simulate
from gearfmu.tables.synthetic import rectangular_wave_tables


def case():
    tb = rectangular_wave_tables(2e8, contact_ratio=1.6, backlash_half_m=20e-6, points_per_mesh=16,
                                 pair_error_m=lambda j, u: 4e-6 * (1 + j) * np.sin(np.pi * u))
    T1, w0, zeta, x0 = 5.0, 200.0, 0.03, -35e-6
    return tb, T1, T1 * tb.base_radius_gear_m / tb.base_radius_pinion_m, w0, zeta, x0


def c_runner(tb, T1, T2, w0, zeta, x0, H, n, hmax, integrator, lib):
    k = np.ascontiguousarray(tb.k_N_per_m)
    e = np.ascontiguousarray(tb.e_m)
    b = np.ascontiguousarray(tb.backlash_half_m)
    tq = np.ascontiguousarray(tb.torque_Nm, dtype=float)
    m = np.zeros(lib.gk_sizeof_model() // 8 + 2)
    out = np.zeros(lib.gk_n_outputs(tb.slots))
    lib.gk_init(m.ctypes.data, tb.slots, tb.n_phi, len(tq), tq.ctypes.data, k.ctypes.data, e.ctypes.data,
                b.ctypes.data, tb.phi_period_rad, tb.base_radius_pinion_m, tb.base_radius_gear_m,
                tb.inertia_pinion_kgm2, tb.inertia_gear_kgm2, tb.k_mean_N_per_m)
    lib.gk_set_damping(m.ctypes.data, zeta, 0)
    lib.gk_set_integrator(m.ctypes.data, integrator)
    s = np.array([0.0, w0, x0, 0.0])
    pm, ps, po = m.ctypes.data, s.ctypes.data, out.ctypes.data
    t0 = time.perf_counter()
    for _ in range(n):
        lib.gk_do_step(pm, ps, T1, T2, H, hmax, po)
    return time.perf_counter() - t0, s.copy()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    tb, T1, T2, w0, zeta, x0 = case()
    H = tb.mesh_period_rad / w0 / 8
    n = 32
    sim_s = n * H

    def run(integ, div):
        best, r = None, None
        for _ in range(args.repeat):
            r = simulate(tb, stop_time_s=sim_s, comm_step_s=H, max_step_s=H / div, pinion_torque_Nm=T1,
                         gear_torque_Nm=T2, pinion_speed_start_rad_s=w0, damping_ratio=zeta, dte_start_m=x0,
                         integrator=integ)
            best = r.wall_s if best is None else min(best, r.wall_s)
        return r, best

    print("reference ...", file=sys.stderr)
    ref, _ = run("rk4_kink", 3200)
    rx, rf = np.ptp(ref.dte), np.ptp(ref.mesh_force[1:])
    rows = []
    for integ in ("rk4", "rk4_kink"):
        for div in (4, 8, 16, 32, 64, 128, 256, 512):
            print(f"{integ} h = H/{div} ...", file=sys.stderr)
            r, wall = run(integ, div)
            dx = (r.dte - ref.dte) / rx
            df = (r.mesh_force[1:] - ref.mesh_force[1:]) / rf
            rows.append({"method": integ, "setting": f"h=H/{div}", "step_s": r.step_s, "wall_s": wall,
                         "wall_s_per_simulated_s": wall / sim_s, "events": r.info["events"],
                         "dte_rel_rms_err": float(np.sqrt(np.mean(dx ** 2))),
                         "dte_rel_max_err": float(np.max(np.abs(dx))),
                         "force_rel_rms_err": float(np.sqrt(np.mean(df ** 2))),
                         "force_rel_max_err": float(np.max(np.abs(df)))})
    # Pareto front: no other row is both faster and more accurate (dte RMS)
    for a in rows:
        a["on_front"] = not any(b["wall_s"] < a["wall_s"] and b["dte_rel_rms_err"] < a["dte_rel_rms_err"]
                                for b in rows)
    # numba vs C per step (same loop of 32 communication steps, h = H/256)
    lib_dir = tempfile.mkdtemp(prefix="bench_gk_")
    lib = ctypes.CDLL(str(compile_kernel(lib_dir)))
    d, i, p = ctypes.c_double, ctypes.c_int, ctypes.c_void_p
    lib.gk_init.argtypes = [p, i, i, i, p, p, p, p, d, d, d, d, d, d]
    lib.gk_set_damping.argtypes = [p, d, i]
    lib.gk_set_integrator.argtypes = [p, i]
    lib.gk_do_step.argtypes = [p, p, d, d, d, d, p]
    per_step = []
    for integ, code in (("rk4", 0), ("rk4_kink", 1)):
        div = 256
        _, wn = run(integ, div)
        wc = min(c_runner(tb, T1, T2, w0, zeta, x0, H, n, H / div, code, lib)[0] for _ in range(args.repeat))
        steps = n * div
        per_step.append({"method": integ, "substeps": steps, "numba_ns_per_substep": wn / steps * 1e9,
                         "c_ns_per_substep": wc / steps * 1e9, "numba_over_c": wn / wc})
    dphi = tb.phi_period_rad / tb.n_phi
    nodes = int(np.sum(np.abs(np.diff(np.floor(ref.pinion_angle / dphi)))))
    # least squares wall = a*substeps + b*events over the rows of each integrator
    event_cost = {"events": [r["events"] for r in rows if r["method"] == "rk4_kink"],
                  "table_node_crossings": nodes}
    for integ in ("rk4", "rk4_kink"):
        sel = [r for r in rows if r["method"] == integ]
        a = np.array([[n * int(r["setting"].split("/")[1]), r["events"]] for r in sel], dtype=float)
        w = np.array([r["wall_s"] for r in sel])
        coef = np.linalg.lstsq(a if integ == "rk4_kink" else a[:, :1], w, rcond=None)[0]
        event_cost[f"{integ}_ns_per_substep"] = float(coef[0] * 1e9)
        if integ == "rk4_kink":
            event_cost["rk4_kink_ns_per_event"] = float(coef[1] * 1e9)
    front = [r for r in rows if r["on_front"]]
    print(json.dumps({"case": "impact case of tests/test_integrators.py, 4 mesh periods, H = mesh period/8",
                      "reference": "rk4_kink h=H/3200", "simulated_s": sim_s, "rows": rows,
                      "front": [(r["method"], r["setting"]) for r in front],
                      "per_step": per_step, "event_cost": event_cost}, indent=1))


if __name__ == "__main__":
    main()
