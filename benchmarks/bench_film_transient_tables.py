"""Benchmark: seed 000 Table 1 pair tables with ``[roughness] film_transient = "film"`` (the rough
film of every film-grid node is the transient film, docs/ehl_mesh.md "Transient films in the
tables") at roughness levels 1-4, against the steady tables (Hertz, smooth, rough 'off').
Prints one JSON object: mean TVMS per torque row (N/m), failed grid nodes and why, the slice
spread of the node ratios, build CPU (this process + children) and the ordering
Hertz < L4 < L3 < L2 < L1 < smooth per torque.

    python benchmarks/bench_film_transient_tables.py [--levels 1 2 3 4] [--points-per-mesh 4]
        [--slices 2] [--torques 1000 2000 3000] [--refine-nodes 17] [--workers 2]
        [--policies fractal_mixed load_sharing hertz] [--refine-level 4]

``--policies``: film-failure policies (``[roughness] on_film_failure``) of the 'film' tables, one
full build per policy (precompute_tables works on a copy of the environment, so the film grid is
not reused: each policy costs the level's full CPU; the transient runs are deterministic, so the
rows differ only at the collapsed / failed nodes).  Keys ``film_L<lv>`` (first
policy) and ``film_L<lv>_<policy>``.  Per level, ``collapsed_nodes``: position on the line of action,
load, film parameter Lambda (Dowson-Higginson, composite sigma) and the solver's message (step, time,
x where h reached 0).

``--refine-nodes K``: the level-1 'film' tables again with K film-grid positions (default grid 9;
the smooth tables solve every position, no grid): the change of the mean TVMS is the grid's interpolation error, to compare
with the level-to-level steps; ``--refine-level L`` does it at level L instead of level 1.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import resource
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def _cpu():
    ch = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + ch.ru_utime + ch.ru_stime


def _failed_nodes(env, grid_row) -> list:
    """Failed nodes of the film grid under film_transient = 'film' (provenance
    ``failed_nodes_first``): s (m, line of action from N1; and relative to the pitch point), load
    (N/m), status, film parameter Lambda there (Dowson-Higginson, composite sigma) and the
    solver's message (step, time and x where h reached 0)."""
    from gearfmu.contact.models import film_parameter

    rows = []
    for f in grid_row.get("failed_nodes_first") or []:
        s, w = float(f["s_m"]), float(f["w_N_per_m"])
        lam = float(film_parameter(env, np.array([s]), np.array([w]))[0])
        rows.append({**f, "s_from_pitch_m": s - float(env.geom.s_pitch_m),
                     "s_rel_loa": (s - float(env.geom.s_start_m)) / (float(env.geom.s_end_m) - float(env.geom.s_start_m)),
                     "film_parameter": lam})
    return rows


def main(argv=None) -> int:
    from gearfmu.contact.models import RoughnessSpec
    from gearfmu.scene.physics import environment_from_scene
    from gearfmu.assembly.precompute import precompute_tables
    from gearfmu.scene.reader import load_scene

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--levels", type=int, nargs="+", default=[1, 2, 3, 4])
    ap.add_argument("--points-per-mesh", type=int, default=4)
    ap.add_argument("--slices", type=int, default=2)
    ap.add_argument("--torques", type=float, nargs="+", default=[1000.0, 2000.0, 3000.0])
    ap.add_argument("--refine-nodes", type=int, default=0)
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--skip-steady", action="store_true", help="only the 'film' tables (and smooth/Hertz)")
    ap.add_argument("--policies", nargs="+", default=["fractal_mixed"],
                    help="on_film_failure policies of the 'film' tables (grid built once per level)")
    ap.add_argument("--refine-level", type=int, default=1)
    a = ap.parse_args(argv)
    log = (lambda *x: print(*x, file=sys.stderr, flush=True))
    base = load_scene(ROOT / "examples" / "scenes" / "seed000_table1.toml")
    T = [float(t) for t in a.torques]
    out = {"scene": "examples/scenes/seed000_table1.toml", "points_per_mesh": a.points_per_mesh,
           "slices": a.slices, "torques_Nm": T, "mean_tvms_N_per_m": {}, "cost": {}, "grid": {}}

    def tables(name, model, spec=None):
        opts = dataclasses.replace(base.mesh, contact_model=model, slices=a.slices)
        sc = dataclasses.replace(base, mesh=opts)
        kw = {"roughness": spec} if spec is not None else {}
        if a.workers:
            kw["max_workers"] = a.workers
        env = environment_from_scene(sc, **kw)
        c0, t0 = _cpu(), time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            tab = precompute_tables(sc.pair, opts, points_per_mesh=a.points_per_mesh, torque_axis_Nm=T,
                                    nominal_torque_Nm=2000.0, contact_env=env)
        tab._bench_env = env
        k = tab.k_N_per_m.sum(axis=1)
        out["mean_tvms_N_per_m"][name] = [float(v) for v in k.mean(axis=1)]
        out["cost"][name] = {"cpu_s": round(_cpu() - c0, 2), "wall_s": round(time.perf_counter() - t0, 2)}
        c = tab.provenance.get("contact", {})
        g = c.get("film_grid") or {}
        ft = g.get("film_transient") or {}
        out["grid"][name] = {"film_failures": c.get("film_failures", 0),
                             "film_failures_by_status": c.get("film_failures_by_status"),
                             "film_failures_by_use": c.get("film_failures_by_use"),
                             "failed_rough_nodes": g.get("failed_rough_nodes"),
                             "stalled_rough_nodes_interpolated": g.get("stalled_rough_nodes_interpolated"),
                             **{q: ft.get(q) for q in ("nodes", "transient_runs", "failed_nodes",
                                                       "failed_nodes_by_status", "runs_smooth_start",
                                                       "rescued_steps", "slice_spread_max",
                                                       "slice_spread_mean", "steps_per_run_mean",
                                                       "worker_cpu_s", "c_by_load_node",
                                                       "failed_nodes_first")}}
        log(f"{name}: {out['cost'][name]}, mean TVMS {out['mean_tvms_N_per_m'][name]}")
        json.dump(out, open("/tmp/bench_film_transient_partial.json", "w"))
        return tab

    tables("hertz", "hertz")
    tables("smooth", "smooth_ehl")
    out["collapsed_nodes"] = {}
    for lv in a.levels:
        for ip, pol in enumerate(a.policies):
            spec = RoughnessSpec.from_level(lv, film_transient="film", on_failure=pol)
            tab = tables(f"film_L{lv}" if ip == 0 else f"film_L{lv}_{pol}", "rough_ehl", spec)
            env = tab._bench_env
        out["collapsed_nodes"][f"L{lv}"] = _failed_nodes(env, out["grid"][f"film_L{lv}"])
        json.dump(out, open("/tmp/bench_film_transient_partial.json", "w"))
    if not a.skip_steady:
        for lv in a.levels:
            tables(f"steady_L{lv}", "rough_ehl", RoughnessSpec.from_level(lv))
    if a.refine_nodes:
        K, rl = int(a.refine_nodes), int(a.refine_level)
        tables(f"film_L{rl}_K{K}", "rough_ehl", RoughnessSpec.from_level(
            rl, film_transient="film", position_nodes=K, on_failure=a.policies[0]))
    m = out["mean_tvms_N_per_m"]
    out["ordering"] = {}
    for ip, pol in enumerate(a.policies):
        sfx = "" if ip == 0 else f"_{pol}"
        chain = ["hertz"] + [f"film_L{lv}{sfx}" for lv in sorted(a.levels, reverse=True)] + ["smooth"]
        out["ordering"][pol] = {"chain": " < ".join(chain), "holds_per_torque": [
            all(m[chain[i]][r] < m[chain[i + 1]][r] for i in range(len(chain) - 1)) for r in range(len(T))],
            "steps_rel_to_smooth": {n: [m[n][r] / m["smooth"][r] - 1.0 for r in range(len(T))] for n in chain}}
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
