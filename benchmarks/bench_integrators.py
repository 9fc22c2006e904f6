"""Speed against error of the integrators 'rk4', 'rk4_kink' and 'rk4_node' (docs/model.md,
docs/native.md), and numba against the C kernel per step.  Prints JSON (stdout); progress
on stderr.

``fronts`` (``--fronts``, default on): per case -- the default scene's computed tables
(gearfmu.bench hard case computed_default_scene), an impact case (single_sided_impacts)
and a 3-slot case (the seed 003 gears at contact ratio 2.4, tent errors) -- every native
integrator at 1..256 substeps per communication step and solve_ivp DOP853 at rtol 1e-3..1e-10
(gearfmu.dynamics.reference, event-located), each row's relative RMS dte and force error
against the event-located DOP853 reference at rtol 1e-12 and its wall time (best of
``--repeat`` for every method; native: the whole ``simulate`` call, ``loop_wall_s`` its
compiled loop alone); ``wall_at`` gives each method's wall time at relative RMS dte errors 1e-4 and
1e-6 (log-log interpolation along its own front) and ``speedup_vs_DOP853`` the ratio of
DOP853's to each integrator's.  ``fmu_rtf``: the standalone FMU of the default scene built
with 'rk4_node' at the internal step where the native rk4_node front crosses 1e-4, run by
fmpy's low-level FMU2Slave loop at a communication step of 1e-4 s for 0.1 s simulated
(real-time factor = simulated / wall); its own error from an fmpy run on the case's grid.

Case: the impact case of tests/unit/dynamics/test_integrators.py (rectangular-wave TVMS, errors,
backlash, light load, impact start), 4 mesh periods, 8 communication steps per
mesh period.  Reference: rk4_kink at h = H/3200 (its error there is ~1e-11 of
the range, tests/unit/dynamics/test_integrators.py shows it agrees with an event-located
solve_ivp to the reference's own 1e-9 level).  Errors: RMS and maximum of
|dte - dte_ref| and |mesh_force - F_ref| over the communication points,
relative to the reference's range.  Times: best of `--repeat` runs of the
compiled loop (native ``wall_s``; the C kernel through ctypes, one call per
communication step).  ``event_cost``: where rk4_kink's time goes -- its events
(table nodes and contact-mode changes it steps to), the net table-node crossings
among them (cell changes of theta1 between communication points) and the cost
per substep and per event (least squares wall = a*substeps + b*events over the
rows of one integrator).
Usage: python benchmarks/bench_integrators.py [--repeat 3] [--fronts-only]
"""
import argparse
import math
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from harness import best_of, c_runner, emit, front_at, step_costs
from gearfmu.fmu.pythonfmu_build import compile_kernel
from gearfmu.fmu.runtime.kernel_api import load_kernel
from gearfmu.bench import _kb, _kw, hard_case, rel_errors, tent_error
from gearfmu.common.vocabulary import INTEGRATORS
from gearfmu.dynamics.native import simulate
from gearfmu.dynamics.reference import simulate_reference
from gearfmu.tables.synthetic import rectangular_wave_tables


def case():
    tb = rectangular_wave_tables(2e8, contact_ratio=1.6, backlash_half_m=20e-6, points_per_mesh=16,
                                 pair_error_m=lambda j, u: 4e-6 * (1 + j) * np.sin(np.pi * u))
    T1, w0, zeta, x0 = 5.0, 200.0, 0.03, -35e-6
    return tb, T1, T1 * tb.base_radius_gear_m / tb.base_radius_pinion_m, w0, zeta, x0


def three_slot_case():
    """The seed 003 gears (gearfmu.bench) at contact ratio 2.4 on 3 slots, tent errors 3 um."""
    t = _kb(contact_ratio=2.4, slots=3, pair_error_m=tent_error(3e-6))
    return t, _kw(t, 0.7, 340.0, 0.02, 30)


FRONT_CASES = ("computed_default_scene", "single_sided_impacts", "three_slot")
FRONT_SUBSTEPS = (1, 2, 4, 8, 16, 32, 64, 128, 256)
DOP853_RTOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)


def _case(name):
    return three_slot_case() if name == "three_slot" else hard_case(name)


def case_front(name, repeat):
    """Rows of the speed-against-error front of one case (module docstring)."""
    tables, kw = _case(name)
    H = kw["comm_step_s"]
    print(f"front {name}: reference ...", file=sys.stderr)
    ref = simulate_reference(tables, rtol=1e-12, steps_per_period=128, **kw)
    rows = []
    simulate(tables, **dict(kw, stop_time_s=H, max_step_s=H, integrator="rk4_node"))  # compile
    for integ in INTEGRATORS:
        for n in FRONT_SUBSTEPS:
            best, r = math.inf, None
            for _ in range(repeat):   # the whole call, as gearfmu bench accuracy times it
                t0 = time.perf_counter()
                r = simulate(tables, max_step_s=H / n, integrator=integ, **kw)
                best = min(best, time.perf_counter() - t0)
            rows.append(dict(method=integ, setting=f"h=H/{n}", step_s=H / n, wall_s=best, loop_wall_s=r.wall_s,
                             events=int(r.info.get("events", 0)), **rel_errors(r, ref)))
    for rt in DOP853_RTOLS:
        print(f"front {name}: DOP853 rtol {rt:g} ...", file=sys.stderr)
        best, r = math.inf, None
        for _ in range(repeat):   # best of --repeat, as the native rows
            t0 = time.perf_counter()
            r = simulate_reference(tables, rtol=rt, method="DOP853", steps_per_period=8, **kw)
            best = min(best, time.perf_counter() - t0)
        rows.append(dict(method="solve_ivp-DOP853", setting=f"rtol={rt:g}", wall_s=best, **rel_errors(r, ref)))
    methods = list(INTEGRATORS) + ["solve_ivp-DOP853"]
    at = {m: {f"{tg:g}": front_at([r for r in rows if r["method"] == m], tg) for tg in (1e-4, 1e-6)}
          for m in methods}
    speedup = {m: {tg: (at["solve_ivp-DOP853"][tg] / at[m][tg]
                        if at[m][tg] and at["solve_ivp-DOP853"][tg] else None) for tg in at[m]}
               for m in INTEGRATORS}
    return {"case": name, "slots": tables.slots, "comm_step_s": H, "stop_time_s": kw["stop_time_s"],
            "reference": "event-located DOP853 rtol 1e-12 (gearfmu.dynamics.reference)", "rows": rows,
            "wall_at": at, "speedup_vs_DOP853": speedup}


def fmu_rtf(front, repeat, lib, comm_s=1e-4, sim_s=0.1):
    """Real-time factor of the standalone FMU (rk4_node) of the front's case at the internal
    step where the native rk4_node rows cross 1e-4 relative RMS dte error; and that of the
    C kernel alone (gk_do_step through ctypes, same steps) to show what the FMI layer adds."""
    from fmpy import extract, read_model_description
    from gearfmu.fmu.compare import run_fmu
    from gearfmu.fmu.standalone_build import build_standalone_fmu

    tables, kw = _case(front["case"])
    ok = [r for r in front["rows"] if r["method"] == "rk4_node" and r["dte_rel_rms_err"] <= 1e-4]
    h = max(r["step_s"] for r in ok)
    with tempfile.TemporaryDirectory() as wd:
        path = build_standalone_fmu(tables, Path(wd) / "rtf.fmu", damping_ratio=kw["damping_ratio"],
                                    pinion_speed_start_rad_s=kw["pinion_speed_start_rad_s"],
                                    pinion_torque_start_Nm=float(kw["pinion_torque_Nm"]), max_step_s=h,
                                    damping_model=kw.get("damping_model", "elastobacklash"),
                                    stop_time_s=max(sim_s, kw["stop_time_s"]), output_interval_s=comm_s,
                                    integrator="rk4_node", validation=False)
        md = read_model_description(str(path))
        unz = extract(str(path))
        hosts = step_costs(unz, md, sim_s=sim_s, comm_s=comm_s, max_step_s=h, integrator="rk4_node", reals={},
                           repeat=repeat)  # C host, fmpy loops, per-step layer costs (harness.step_costs)
        walls = [hosts["fmpy_lean_wall_s"]]
        print("fmu: error run on the case's grid ...", file=sys.stderr)
        ref = simulate_reference(tables, rtol=1e-12, steps_per_period=128, **kw)
        run = run_fmu(path, stop_time_s=kw["stop_time_s"], comm_step_s=kw["comm_step_s"],
                      names=["dte", "mesh_force"])
        err = rel_errors({"dte": run.columns["dte"], "mesh_force": run.columns["mesh_force"]}, ref)
        shutil.rmtree(unz, ignore_errors=True)
    T1 = float(kw["pinion_torque_Nm"])
    T2 = T1 * tables.base_radius_gear_m / tables.base_radius_pinion_m
    x0 = float(simulate(tables, **dict(kw, stop_time_s=kw["comm_step_s"])).dte[0])
    kwall = best_of(repeat, lambda: c_runner(tables, T1, T2, kw["pinion_speed_start_rad_s"], kw["damping_ratio"], x0,
                                             comm_s, int(round(sim_s / comm_s)), h, 2, lib)[0])
    return {"kernel_wall_s": kwall, "kernel_real_time_factor": sim_s / kwall,
            "case": front["case"], "integrator": "rk4_node", "max_step_s": h, "comm_step_s": comm_s,
            "simulated_s": sim_s, "wall_s": min(walls), "real_time_factor": sim_s / min(walls),
            "error_on_case_grid": err, "hosts": hosts}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--fronts", action=argparse.BooleanOptionalAction, default=True)
    ap.add_argument("--fronts-only", action="store_true", help="the fronts and fmu_rtf only")
    args = ap.parse_args()
    if args.fronts_only:
        lib = load_kernel(compile_kernel(tempfile.mkdtemp(prefix="bench_gk_")))
        fronts = [case_front(name, args.repeat) for name in FRONT_CASES]
        emit({"fronts": fronts, "fmu_rtf": fmu_rtf(fronts[0], args.repeat, lib)})
        return
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
    integrators = ("rk4", "rk4_kink", "rk4_node")
    rx, rf = np.ptp(ref.dte), np.ptp(ref.mesh_force[1:])
    rows = []
    for integ in integrators:
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
    lib = load_kernel(compile_kernel(lib_dir))
    per_step = []
    for integ, code in (("rk4", 0), ("rk4_kink", 1), ("rk4_node", 2)):
        div = 256
        _, wn = run(integ, div)
        wc = best_of(args.repeat, lambda: c_runner(tb, T1, T2, w0, zeta, x0, H, n, H / div, code, lib)[0])
        steps = n * div
        per_step.append({"method": integ, "substeps": steps, "numba_ns_per_substep": wn / steps * 1e9,
                         "c_ns_per_substep": wc / steps * 1e9, "numba_over_c": wn / wc})
    dphi = tb.phi_period_rad / tb.n_phi
    nodes = int(np.sum(np.abs(np.diff(np.floor(ref.pinion_angle / dphi)))))
    # least squares wall = a*substeps + b*events over the rows of each integrator
    event_cost = {"events": [r["events"] for r in rows if r["method"] == "rk4_kink"],
                  "table_node_crossings": nodes}
    for integ in integrators:
        sel = [r for r in rows if r["method"] == integ]
        a = np.array([[n * int(r["setting"].split("/")[1]), r["events"]] for r in sel], dtype=float)
        w = np.array([r["wall_s"] for r in sel])
        coef = np.linalg.lstsq(a if integ != "rk4" else a[:, :1], w, rcond=None)[0]
        event_cost[f"{integ}_ns_per_substep"] = float(coef[0] * 1e9)
        if integ != "rk4":
            event_cost[f"{integ}_ns_per_event"] = float(coef[1] * 1e9)
    front = [r for r in rows if r["on_front"]]
    extra = {}
    if args.fronts:
        extra["fronts"] = [case_front(name, args.repeat) for name in FRONT_CASES]
        extra["fmu_rtf"] = fmu_rtf(extra["fronts"][0], args.repeat, lib)
    emit({"case": "impact case of tests/unit/dynamics/test_integrators.py, 4 mesh periods, H = mesh period/8",
          "reference": "rk4_kink h=H/3200", "simulated_s": sim_s, "rows": rows,
          "front": [(r["method"], r["setting"]) for r in front],
          "per_step": per_step, "event_cost": event_cost, **extra})


if __name__ == "__main__":
    main()
