"""Benchmark: rough-EHL tables of the default scene (seed 000 Table 1 pair, 44 slices, 64 points
per mesh period, the scene's torque axis) through the local process pool, and the error of the
film grid (films solved at a few contact positions x load nodes and interpolated) against
solving every position.  Prints one JSON object.

    python benchmarks/bench_ehl_tables.py                      # default scene, grid (timing)
    python benchmarks/bench_ehl_tables.py --accuracy           # + reduced-case interpolation error
    python benchmarks/bench_ehl_tables.py --position-nodes 0 --torques 2000   # old path (every position)
    options: [--points-per-mesh 64] [--slices 44] [--level 1] [--torques T ...] [--workers 2]
             [--position-nodes K] [--progress] [--accuracy-nodes 5 9 17 33] [--compare-tvms FILE.json]
             [--levels 1 2 3 4]   # + build time, solves, stalls of each level (--save-tvms: one file each)
             [--models hertz smooth_ehl]   # + mean TVMS of these contact models' tables
    python benchmarks/bench_ehl_tables.py --transient [--levels 1 2]   # film_transient off vs correction

Timing: wall and CPU of the parent, film solves, passes.  Old-path estimate: the distinct
(position, slice) requests of the tables x passes x rows times the measured time of one cold
rough solve (in-process sample), divided by the workers.  Accuracy (``--accuracy``): on a
reduced case (4 slices, 16 points per mesh, 1000/2000/3000 N m) (a) the film stiffness of the
grid against the direct solve at every table position with loads 0.5/0.8/1.2 x nominal,
(b) the mean and largest TVMS difference of the whole tables against the all-positions tables.
docs/ehl_mesh.md records what this script measured.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def _scene(slices, model="rough_ehl"):
    from gearfmu.scene.reader import load_scene

    sc = load_scene(None)
    opts = dataclasses.replace(sc.mesh, contact_model=model, slices=slices)
    return dataclasses.replace(sc, mesh=opts)


def _tables(sc, level, K, ppm, torques, workers, progress=False, transient="off"):
    from gearfmu.contact.models import RoughnessSpec
    from gearfmu.scene.physics import environment_from_scene
    from gearfmu.assembly.precompute import precompute_tables

    env = environment_from_scene(sc, roughness=RoughnessSpec.from_level(level, position_nodes=K,
                                                                        film_transient=transient),
                                 max_workers=workers, progress=progress)
    import resource

    ch0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0, c0 = time.perf_counter(), time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tab = precompute_tables(sc.pair, sc.mesh, points_per_mesh=ppm, torque_axis_Nm=torques,
                                nominal_torque_Nm=sc.operating.torque_Nm, contact_env=env)
    ch1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (time.process_time() - c0, (ch1.ru_utime + ch1.ru_stime) - (ch0.ru_utime + ch0.ru_stime))
    return tab, time.perf_counter() - t0, cpu


def _cold_solve_time(sc, level, n=12):
    """Mean CPU time (s) of one cold rough solve (old path) at table positions, in-process."""
    from gearfmu.contact.models import RoughnessSpec, rough_profile
    from gearfmu.scene.physics import environment_from_scene
    from gearfmu.ehl.mesh_film import contact_kinematics, solve_slice_film

    env = environment_from_scene(sc, roughness=RoughnessSpec.from_level(level))
    fenv, fl, g = env.film_environment(), env.flanks(), env.geom
    s = np.linspace(g.s_start_m, g.s_end_m, n + 2)[1:-1]
    R, u, _ = contact_kinematics(g, s, env.omega1_rad_s)
    w = env.film_load_anchor_N_per_m
    solve_slice_film(fenv, float(R[0]), float(u[0]), w)            # compile
    c0 = time.process_time()
    for i in range(n):
        solve_slice_film(fenv, float(R[i]), float(u[i]), w,
                         rough_profile(env, fenv, fl, float(s[i]), i % env.n_slices, w, float(R[i])))
    return (time.process_time() - c0) / n


def _film_error(level, K_list, slices=4, ppm=16):
    """Grid against direct rough solves at every table position (loads 0.5/0.8/1.2 x nominal)."""
    from gearfmu.contact.models import RoughnessSpec, get_contact_model
    from gearfmu.scene.physics import environment_from_scene
    from gearfmu.gear.stiffness import slot_stiffness

    sc = _scene(slices)
    env0 = environment_from_scene(sc, roughness=RoughnessSpec.from_level(level, position_nodes=0,
                                                                         full_film_parameter=0.0,
                                                                         on_failure="hertz"), max_workers=2)
    ss = slot_stiffness(sc.pair, env0.geom, sc.mesh, None, ppm)
    s = np.unique(np.round(ss.s_m[np.isfinite(ss.s_m)], 12))
    S, N = np.meshgrid(s, np.arange(slices), indexing="ij")
    S, N = S.ravel(), N.ravel()
    f = np.array([0.5, 0.8, 1.2])[np.arange(S.size) % 3]
    W = env0.film_load_anchor_N_per_m * f
    model = get_contact_model("rough_ehl").fn
    t0 = time.perf_counter()
    ref = model(env0, S, N, W)
    t_ref = time.perf_counter() - t0
    bad_ref = {(x["s_m"], x["slice"], x["w_N_per_m"]) for x in ref.failures}
    from gearfmu.contact.models import _key
    ok_ref = np.array([(_key(a), int(b), _key(c)) not in bad_ref for a, b, c in zip(S, N, W)])
    out = {"level": level, "slices": slices, "positions": int(s.size), "requests": int(S.size),
           "direct_solves": ref.solves, "direct_failures": len(ref.failures), "direct_wall_s": round(t_ref, 2),
           "grid": []}
    for K in K_list:
        env = dataclasses.replace(env0, roughness=dataclasses.replace(env0.roughness, position_nodes=K),
                                  _grid=None)
        t0 = time.perf_counter()
        res = model(env, S, N, W)
        t = time.perf_counter() - t0
        bad = {(x["s_m"], x["slice"], x["w_N_per_m"]) for x in res.failures}
        ok = ok_ref & np.array([(_key(a), int(b), _key(c)) not in bad for a, b, c in zip(S, N, W)])
        e = res.k_N_per_m[ok] / ref.k_N_per_m[ok] - 1.0
        out["grid"].append({"position_nodes": K, "film_solves": res.solves, "wall_s": round(t, 2),
                            "failures": len(res.failures), "compared": int(ok.sum()),
                            "film_k_rel_err_rms": float(np.sqrt(np.mean(e ** 2))),
                            "film_k_rel_err_max": float(np.max(np.abs(e))),
                            "film_k_rel_err_mean": float(np.mean(e))})
    return out


def _tvms_error(level, K_list, slices=4, ppm=16, torques=(1000.0, 2000.0, 3000.0), workers=2):
    sc = _scene(slices)
    ref, t_ref, _ = _tables(sc, level, 0, ppm, list(torques), workers)
    kr = ref.k_N_per_m.sum(axis=1)
    out = {"level": level, "slices": slices, "points_per_mesh": ppm, "torques_Nm": list(torques),
           "all_positions": {"wall_s": round(t_ref, 2), "film_solves": ref.provenance["contact"]["solves"],
                             "film_failures": ref.provenance["contact"].get("film_failures", 0),
                             "mean_tvms_N_per_m": [float(v) for v in kr.mean(axis=1)]},
           "grid": []}
    for K in K_list:
        tab, t, _ = _tables(sc, level, K, ppm, list(torques), workers)
        k = tab.k_N_per_m.sum(axis=1)
        d = (k - kr) / kr.mean(axis=1, keepdims=True)
        out["grid"].append({"position_nodes": K, "wall_s": round(t, 2),
                            "film_solves": tab.provenance["contact"]["solves"],
                            "film_failures": tab.provenance["contact"].get("film_failures", 0),
                            "tvms_rel_diff_max": float(np.max(np.abs(d))),
                            "mean_tvms_rel_diff": [float(v) for v in (k.mean(axis=1) / kr.mean(axis=1) - 1.0)]})
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--points-per-mesh", type=int, default=64)
    ap.add_argument("--slices", type=int, default=44)
    ap.add_argument("--level", type=int, default=1)
    ap.add_argument("--torques", type=float, nargs="+", default=None,
                    help="table torques (N m); default: the scene's axis (load-dependent: 0.5/1/1.5 x nominal)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--position-nodes", type=int, default=None, help="film grid positions (0 = every position)")
    ap.add_argument("--progress", action="store_true")
    ap.add_argument("--accuracy", action="store_true")
    ap.add_argument("--accuracy-only", action="store_true")
    ap.add_argument("--accuracy-nodes", type=int, nargs="+", default=[5, 9, 17, 33])
    ap.add_argument("--levels", type=int, nargs="+", default=None,
                    help="also build the tables of these roughness levels (1-4): time, solves, stalls per level")
    ap.add_argument("--models", nargs="+", default=None, choices=["hertz", "smooth_ehl"],
                    help="also build the tables of these contact models (same options): mean TVMS per torque row")
    ap.add_argument("--save-tvms", default=None, help="write the TVMS (P, N) of the first row to this .json")
    ap.add_argument("--compare-tvms", default=None, help="TVMS .json of another run: report the difference")
    ap.add_argument("--transient", action="store_true",
                    help="only: build the tables of --level (or each of --levels) with [roughness] film_transient "
                         "'off' and 'correction' (docs/ehl_transient.md section 3): build time (CPU), mean TVMS, "
                         "the correction's provenance")
    a = ap.parse_args(argv)

    from gearfmu.contact.models import DEFAULT_FILM_POSITION_NODES

    K = DEFAULT_FILM_POSITION_NODES if a.position_nodes is None else a.position_nodes
    out = {"benchmark": "rough-EHL tables, default scene", "cpu_count": os.cpu_count()}
    if a.transient:
        out["film_transient"] = [_transient_row(lv, K, a) for lv in (a.levels or [a.level])]
        print(json.dumps(out))
        return 0
    if not a.accuracy_only:
        sc = _scene(a.slices)
        tab, wall, cpu = _tables(sc, a.level, K, a.points_per_mesh, a.torques, a.workers, a.progress)
        c = tab.provenance["contact"]
        rows = c["load_iteration"]["rows"]
        from gearfmu.gear.stiffness import slot_stiffness
        ss = slot_stiffness(sc.pair, tab_geom(sc), sc.mesh, None, a.points_per_mesh)
        n_pos = int(np.unique(np.round(ss.s_m[np.isfinite(ss.s_m)], 12)).size)
        t_solve = _cold_solve_time(sc, a.level)
        passes = sum(r["passes"] for r in rows)
        old_solves = n_pos * a.slices * passes
        out.update({
            "points_per_mesh": a.points_per_mesh, "slices": a.slices, "roughness_level": a.level,
            "torques_Nm": [float(t) for t in tab.torque_Nm], "workers": a.workers, "position_nodes": K,
            "wall_s": round(wall, 2), "parent_cpu_s": round(cpu[0], 2), "workers_cpu_s": round(cpu[1], 2),
            "ideal_wall_s_on_idle_cores": round(cpu[0] + cpu[1] / max(a.workers, 1), 1),
            "film_solves": c["solves"],
            "film_grid": c.get("film_grid"), "film_failures": c.get("film_failures", 0),
            "film_failures_by_status": c.get("film_failures_by_status"),
            "passes_per_torque": [r["passes"] for r in rows],
            "mean_tvms_N_per_m": [float(v) for v in tab.k_N_per_m.sum(axis=1).mean(axis=1)],
            "old_path_estimate": {"distinct_positions": n_pos, "solves": old_solves,
                                  "cold_rough_solve_cpu_s": round(t_solve, 4),
                                  "wall_s": round(old_solves * t_solve / max(a.workers, 1), 1)},
            "load_average_1min": os.getloadavg()[0],
        })
        ktot = tab.k_N_per_m.sum(axis=1)
        if a.save_tvms:
            Path(a.save_tvms).write_text(json.dumps({"torques_Nm": [float(t) for t in tab.torque_Nm],
                                                     "tvms_N_per_m": ktot.tolist()}))
        if a.compare_tvms:
            other = json.loads(Path(a.compare_tvms).read_text())
            ko = np.asarray(other["tvms_N_per_m"], float)
            if ko.shape == ktot.shape:
                d = (ktot - ko) / ko.mean(axis=1, keepdims=True)
                out["tvms_vs_other"] = {"file": a.compare_tvms, "rel_diff_max": float(np.max(np.abs(d))),
                                        "mean_rel_diff": [float(v) for v in ktot.mean(axis=1) / ko.mean(axis=1) - 1]}
            else:
                out["tvms_vs_other"] = {"file": a.compare_tvms, "error": f"shape {ko.shape} != {ktot.shape}"}
    if a.levels:
        out["levels"] = [_level_row(lv, K, a) for lv in a.levels]
    if a.models:
        out["models"] = [_model_row(m, a) for m in a.models]
        out["load_average_1min_end"] = os.getloadavg()[0]
    if a.accuracy or a.accuracy_only:
        out["accuracy_film"] = [_film_error(lv, a.accuracy_nodes) for lv in (1, 2)]
        out["accuracy_tvms"] = _tvms_error(1, [n for n in a.accuracy_nodes if n >= 9])
    print(json.dumps(out))
    return 0


def _level_row(level, K, a):
    """Build time and film-grid counts of one roughness level (default scene, same options)."""
    sc = _scene(a.slices)
    tab, wall, cpu = _tables(sc, level, K, a.points_per_mesh, a.torques, a.workers, a.progress)
    c = tab.provenance["contact"]
    g = c.get("film_grid") or {}
    row = {"roughness_level": level, "wall_s": round(wall, 2), "parent_cpu_s": round(cpu[0], 2),
           "workers_cpu_s": round(cpu[1], 2),
           "ideal_wall_s_on_idle_cores": round(cpu[0] + cpu[1] / max(a.workers, 1), 1),
           "film_solves": c["solves"], "rough_film_solves": g.get("rough_film_solves"),
           "failed_rough_nodes": g.get("failed_rough_nodes"),
           "stalled_rough_nodes_interpolated": g.get("stalled_rough_nodes_interpolated"),
           "film_failures": c.get("film_failures", 0), "film_failures_by_status": c.get("film_failures_by_status"),
           "film_failures_by_use": c.get("film_failures_by_use"),
           "film_mixed_lubrication": c.get("film_mixed_lubrication"),
           "film_solver_failures": c.get("film_solver_failures"), "build_line": c.get("warning", ""),
           "mean_tvms_N_per_m": [float(v) for v in tab.k_N_per_m.sum(axis=1).mean(axis=1)],
           "load_average_1min": os.getloadavg()[0]}
    if a.save_tvms:
        p = Path(a.save_tvms)
        p.with_name(f"{p.stem}_level{level}{p.suffix}").write_text(json.dumps(
            {"torques_Nm": [float(t) for t in tab.torque_Nm], "tvms_N_per_m": tab.k_N_per_m.sum(axis=1).tolist()}))
    return row


def _model_row(model, a):
    """Mean TVMS per torque row of another contact model's tables (default scene, same options)."""
    import resource

    from gearfmu.scene.physics import environment_from_scene
    from gearfmu.assembly.precompute import precompute_tables

    sc = _scene(a.slices, model)
    env = environment_from_scene(sc, max_workers=a.workers)
    ch0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0, c0 = time.perf_counter(), time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tab = precompute_tables(sc.pair, sc.mesh, points_per_mesh=a.points_per_mesh, torque_axis_Nm=a.torques,
                                nominal_torque_Nm=sc.operating.torque_Nm, contact_env=env)
    ch1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return {"model": model, "wall_s": round(time.perf_counter() - t0, 2),
            "cpu_s": round(time.process_time() - c0 + (ch1.ru_utime + ch1.ru_stime) - (ch0.ru_utime + ch0.ru_stime), 2),
            "torques_Nm": [float(t) for t in tab.torque_Nm],
            "mean_tvms_N_per_m": [float(v) for v in tab.k_N_per_m.sum(axis=1).mean(axis=1)]}


def _transient_row(level, K, a):
    """film_transient 'off' against 'correction' on the same scene and options (one run each)."""
    sc = _scene(a.slices)
    row = {"roughness_level": level, "points_per_mesh": a.points_per_mesh, "slices": a.slices,
           "position_nodes": K, "workers": a.workers}
    for mode in ("off", "correction"):
        tab, wall, cpu = _tables(sc, level, K, a.points_per_mesh, a.torques, a.workers, a.progress, mode)
        c = tab.provenance["contact"]
        g = c.get("film_grid") or {}
        row[mode] = {"wall_s": round(wall, 2), "parent_cpu_s": round(cpu[0], 2), "workers_cpu_s": round(cpu[1], 2),
                     "total_cpu_s": round(cpu[0] + cpu[1], 2), "film_solves": c["solves"],
                     "failed_rough_nodes": g.get("failed_rough_nodes"),
                     "stalled_rough_nodes_interpolated": g.get("stalled_rough_nodes_interpolated"),
                     "film_failures": c.get("film_failures", 0),
                     "torques_Nm": [float(t) for t in tab.torque_Nm],
                     "mean_tvms_N_per_m": [float(v) for v in tab.k_N_per_m.sum(axis=1).mean(axis=1)],
                     "load_average_1min": os.getloadavg()[0]}
        if mode != "off":
            row[mode]["film_transient"] = g.get("film_transient")
    row["cpu_ratio_correction_to_off"] = round(row["correction"]["total_cpu_s"] / max(row["off"]["total_cpu_s"], 1e-9), 2)
    row["mean_tvms_rel_change"] = [b / a_ - 1.0 for a_, b in zip(row["off"]["mean_tvms_N_per_m"],
                                                                 row["correction"]["mean_tvms_N_per_m"])]
    return row


def tab_geom(sc):
    from gearfmu.gear.geometry import pair_geometry

    return pair_geometry(sc.pair)


if __name__ == "__main__":
    raise SystemExit(main())
