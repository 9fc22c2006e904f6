"""Seed 000 section 5 trends on its Table 1 pair: TVMS with Hertz, smooth-EHL and rough-EHL
(levels 1-4) contact, against torque and speed; film profiles (Figs. 7-8), film stiffness along
the line of action and across the face (Fig. 9), TVMS curves (Figs. 12-15).

    python examples/seed000_trends.py [--json] [--points-per-mesh 4] [--slices 2] [--out DIR]
                                      [--also-policy load_sharing] [--transient-levels 1 2]
                                      [--direct | --only-direct] [--direct-slices 2]
                                      [--direct-nodes 257] [--direct-T-average 8]
                                      [--direct-speed-torque | --only-direct-speed-torque]

--json prints one JSON object (mean TVMS in N/m per contact model, speed and torque); PNG, CSV and
JSON files go to examples/output/seed000_trends/.  Coarse defaults (4 points per mesh period,
2 slices) keep the run to minutes; where the film parameter is below 3 (levels 3-4) or a rough
film fails, the scene's policy (default: seed 001 fractal mixed lubrication) applies, recorded
in the notes (docs/ehl_mesh.md).  --transient-levels adds, per level, the tables with
[roughness] film_transient = "correction" (transient film correction, docs/ehl_transient.md
section 3) under both time reductions, (b) k_of_means (the table's) and (a) mean_of_k, as the
JSON key "film_transient" (mean TVMS, build wall/CPU time, the correction's provenance).
--direct adds (--only-direct: only) the TVMS evaluated directly, without tables, at the pitch point
(single-tooth contact) and the middle of the double-tooth zone, 2000 N m, 2000 rpm, perfect gears
(gearfmu.assembly.direct_tvms: Hertz, smooth steady film, smooth transient, rough levels 1-2 steady
and transient with reduction (b); levels 3-4 transient under seed 000's full-film assumption:
their screen Lambda = h_min/sigma is below 3, so they run with check_film_parameter=False, one call
per position, flagged in the JSON key "full_film_assumption" with the screen's Lambda, the solved
films' minimum h and h/sigma, smooth starts and rescued steps; a film that stalls leaves that
position null) as the JSON key "direct_tvms" (N/m per model and position, relative to smooth, CPU,
"films": minimum film of every transient rough case) and the figure direct_tvms.png (about
2.5 min CPU with 2 slices and 257 nodes, most of it levels 3-4).
--direct-speed-torque adds (--only-direct-speed-torque: only) seed 000 Figs. 14-15 at their roughness
level 4: TVMS at the pitch point with the smooth steady film and the level-4 transient film (full
film assumed, check_film_parameter=False) at 1000 / 2000 / 4000 rpm (2000 N m) and 1000 / 2000 /
3000 N m (2000 rpm), JSON key "direct_tvms_speed_torque" (N/m, relative to smooth, the screen's
Lambda and the solved films' minimum h per point) and direct_tvms_speed_torque.png (about 45 s CPU;
the level-4 point at 1000 rpm is not grid-resolved -- it collapses / stalls at 513 nodes --,
docs/ehl_mesh.md "Direct TVMS").
"""
from __future__ import annotations

import argparse
import csv
import dataclasses
import json
import math
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

TORQUES = (1000.0, 2000.0, 3000.0)   # N m (seed 000 Fig. 15 uses several torques around 2000)
SPEEDS = (1000.0, 2000.0, 4000.0)    # rpm (Fig. 14)


def run(ppm: int, slices: int, out: Path, log=print, policies=(), transient_levels=()) -> dict:
    from gearfmu.contact.models import RoughnessSpec
    from gearfmu.scene.physics import environment_from_scene
    from gearfmu.assembly.precompute import precompute_tables
    from gearfmu.scene.reader import load_scene

    base = load_scene(ROOT / "examples" / "scenes" / "seed000_table1.toml")
    result = {"scene": "examples/scenes/seed000_table1.toml", "points_per_mesh": ppm, "slices": slices,
              "torques_Nm": list(TORQUES), "mean_tvms_N_per_m": {}, "speed_rpm": {}, "notes": {}}
    curves = {}

    costs = {}

    def tables(model, level=None, speed_rpm=2000.0, torques=TORQUES, policy=None, transient=None):
        sc = dataclasses.replace(base, operating=dataclasses.replace(base.operating,
                                                                     speed_rad_s=speed_rpm * math.pi / 30))
        opts = dataclasses.replace(sc.mesh, contact_model=model, slices=slices)
        sc = dataclasses.replace(sc, mesh=opts)
        kw = {"roughness": RoughnessSpec.from_level(level, **({"on_failure": policy} if policy else {}))} \
            if level else {}
        if transient:   # time reduction of the transient film correction
            kw["roughness"] = dataclasses.replace(kw["roughness"], film_transient="correction",
                                                  film_transient_reduction=transient)
        import resource
        ch0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        c0 = time.process_time()
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            tab = precompute_tables(sc.pair, opts, points_per_mesh=ppm, torque_axis_Nm=list(torques),
                                    nominal_torque_Nm=2000.0, contact_env=environment_from_scene(sc, **kw))
        ch1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        costs[(model, level, speed_rpm, policy, transient)] = {
            "wall_s": round(time.perf_counter() - t0, 2),
            "cpu_s": round(time.process_time() - c0 + (ch1.ru_utime + ch1.ru_stime) - (ch0.ru_utime + ch0.ru_stime), 2)}
        c = tab.provenance.get("contact", {})
        log(f"{model} level={level} {speed_rpm:g} rpm{' transient ' + transient if transient else ''}: "
            f"{time.perf_counter() - t0:.1f} s, "
            f"{c.get('solves', 0)} solves, {c.get('film_failures', 0)} film failures")
        return tab

    for name, model, level in (("hertz", "hertz", None), ("smooth", "smooth_ehl", None),
                               ("rough_level_1", "rough_ehl", 1), ("rough_level_2", "rough_ehl", 2),
                               ("rough_level_3", "rough_ehl", 3), ("rough_level_4", "rough_ehl", 4)) + tuple(
            (f"rough_level_{lv}+{pol}", "rough_ehl", lv) for pol in policies for lv in (3, 4)):
        tab = tables(model, level, policy=name.split("+")[1] if "+" in name else None)
        k = tab.k_N_per_m.sum(axis=1)                       # (torques, N) total TVMS
        result["mean_tvms_N_per_m"][name] = {f"{t:g}": float(v) for t, v in zip(TORQUES, k.mean(axis=1))}
        c = tab.provenance.get("contact", {})
        if c.get("film_failures"):
            fl = c["film_failures_first"]
            result["notes"][name] = (f"{c['film_failures']} (position, slice, torque) points without a rough film "
                                     f"(by status {c.get('film_failures_by_status')}; lambda = h_min/sigma "
                                     f"{min(f['film_parameter'] for f in fl):.2f}..{max(f['film_parameter'] for f in fl):.2f}"
                                     f" in the first 20); used there: {c.get('film_failures_by_use')} "
                                     f"(on_film_failure = {c['roughness']['on_failure']!r})")
        curves[name] = k
    if transient_levels:
        ft = result["film_transient"] = {"reductions": {"k_of_means": "(b) A B(<p_m>)/<h_m>, the table's",
                                                        "mean_of_k": "(a) <A B(p_m)/h_m>"}, "levels": {}}
        for lv in transient_levels:
            row = ft["levels"][str(lv)] = {"off": result["mean_tvms_N_per_m"].get(f"rough_level_{lv}"),
                                           "cost_off": costs.get(("rough_ehl", lv, 2000.0, None, None))}
            for red in ("k_of_means", "mean_of_k"):
                tab = tables("rough_ehl", lv, transient=red)
                k = tab.k_N_per_m.sum(axis=1)
                row[red] = {f"{t:g}": float(v) for t, v in zip(TORQUES, k.mean(axis=1))}
                row[f"cost_{red}"] = costs[("rough_ehl", lv, 2000.0, None, red)]
                c = tab.provenance.get("contact", {})
                g = (c.get("film_grid") or {}).get("film_transient") or {}
                row[f"correction_{red}"] = {q: g.get(q) for q in (
                    "nodes", "transient_runs", "failed_nodes", "failed_nodes_by_status", "c_by_load_node",
                    "worker_cpu_s", "steps_per_run_mean", "cycles_per_step_mean")}
                row[f"film_failures_{red}"] = c.get("film_failures", 0)
                curves[f"rough_level_{lv}+transient_{red}"] = k
            if row["off"] is None:
                del row["off"]
    for name, model, level in (("smooth", "smooth_ehl", None), ("rough_level_1", "rough_ehl", 1)):
        result["speed_rpm"][name] = {}
        for n in SPEEDS:
            tab = tables(model, level, speed_rpm=n, torques=(2000.0, 3000.0))
            result["speed_rpm"][name][f"{n:g}"] = float(tab.k_N_per_m.sum(axis=1)[0].mean())
            curves[f"{name}@{n:g}rpm"] = tab.k_N_per_m.sum(axis=1)[:1]
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "mean_tvms.json", "w") as fh:
        json.dump(result, fh, indent=1)
    with open(out / "tvms_curves.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["case", "torque_row", "angle_index", "tvms_N_per_m"])
        for name, k in curves.items():
            for r, row in enumerate(k):
                for i, v in enumerate(row):
                    w.writerow([name, r, i, f"{v:.6e}"])
    _figures(base, curves, out, slices)
    return result


#: (label, model, roughness level) of the direct TVMS (--direct)
DIRECT_CASES = (("hertz", "hertz", None), ("smooth", "smooth_ehl", None),
                ("smooth_transient", "smooth_transient", None),
                ("rough_level_1_steady", "rough_steady", 1), ("rough_level_1", "rough_transient", 1),
                ("rough_level_2_steady", "rough_steady", 2), ("rough_level_2", "rough_transient", 2),
                ("rough_level_3", "rough_transient", 3), ("rough_level_4", "rough_transient", 4))
#: levels whose screen Lambda (Dowson-Higginson h_min / undeformed composite sigma) is below 3: evaluated
#: under seed 000's full-film assumption (check_film_parameter=False), one call per position, flagged in
#: the JSON key "full_film_assumption"
DIRECT_FULL_FILM_ASSUMED = (3, 4)


def run_direct(out: Path, slices: int = 2, n_nodes: int = 257, T_average: float = 8.0,
               max_workers=None, log=print, torque_Nm: float = 2000.0) -> dict:
    """Seed 000 Figs. 12-13 read at the TVMS level, without tables: TVMS (N/m) of every model of
    DIRECT_CASES at the pitch point and the middle of the double-tooth zone
    (gearfmu.assembly.direct_tvms.direct_mesh_stiffness); writes direct_tvms.json and direct_tvms.png."""
    from gearfmu.contact.models import RoughnessSpec, film_parameter
    from gearfmu.scene.physics import environment_from_scene
    from gearfmu.assembly.direct_tvms import (DirectTVMSError, TransientFilmSettings, direct_mesh_stiffness,
                                         pair_positions_m)
    from gearfmu.ehl.mesh_film import contact_kinematics
    from gearfmu.gear.geometry import pair_geometry
    from gearfmu.scene.reader import load_scene

    base = load_scene(ROOT / "examples" / "scenes" / "seed000_table1.toml")
    sc = dataclasses.replace(base, mesh=dataclasses.replace(base.mesh, slices=slices))
    g = pair_geometry(sc.pair)
    s = np.array([g.s_pitch_m, g.s_start_m + 0.5 * (g.contact_ratio - 1.0) * g.base_pitch_m])
    labels = ("pitch point (single-tooth contact)", "middle of the double-tooth zone")
    sp = pair_positions_m(g, s)
    env0 = environment_from_scene(sc, max_workers=1)
    pos = []
    for i, lab in enumerate(labels):
        q = sp[np.isfinite(sp[:, i]), i]
        R, u, sl = contact_kinematics(g, q, env0.omega1_rad_s)
        pos.append({"label": lab, "s_m": float(s[i]), "pairs_from_A_mm": [float(x) for x in (q - g.s_start_m) * 1e3],
                    "srr": [float(x) for x in sl / u]})
    st = TransientFilmSettings(n_nodes=n_nodes, T_average=T_average)
    res = {"scene": "examples/scenes/seed000_table1.toml", "torque_Nm": torque_Nm, "speed_rpm": 2000.0,
           "slices": slices, "n_nodes": n_nodes, "T_average_b_per_u_s": T_average,
           "reduction": st.reduction, "errors": "perfect gears (no deviations, no crowning)",
           "positions": pos, "tvms_N_per_m": {}, "relative_to_smooth": {}, "cost": {}, "not_evaluated": {}}
    from gearfmu.dynamics.sweeps import make_executor

    res["full_film_assumption"] = {}
    res["films"] = {}
    with make_executor(max_workers=max_workers) as ex:
        for name, model, level in DIRECT_CASES:
            env = environment_from_scene(sc, roughness=RoughnessSpec.from_level(level) if level else None,
                                         max_workers=1)
            if level in DIRECT_FULL_FILM_ASSUMED:
                res["tvms_N_per_m"][name], res["full_film_assumption"][name] = _direct_full_film(
                    env, sc, s, torque_Nm, model, st, ex, log, name)
                continue
            try:
                r = direct_mesh_stiffness(env, sc.mesh, s, torque_Nm, model, transient=st, executor=ex,
                                          progress=False)
            except DirectTVMSError as exc:      # e.g. a steady rough film that stalls
                res["not_evaluated"][name] = {"reason": str(exc)}
                log(f"direct {name}: not evaluated: {exc}")
                continue
            res["tvms_N_per_m"][name] = [float(x) for x in r.k_mesh_N_per_m]
            res["cost"][name] = {"cpu_s": round(r.cpu_s, 2), "wall_s": round(r.wall_s, 2),
                                 "film_evaluations": r.film_evaluations, "passes": r.passes,
                                 "load_change_over_F_per_NS": r.load_change, "failures": r.failures}
            if level:
                res["cost"][name]["film_parameter_min"] = float(np.nanmin(r.film_parameter))
            if model == "rough_transient":
                res["films"][name] = _film_summary(r)
            log(f"direct {name}: {r.k_mesh_N_per_m} N/m, {r.cpu_s:.1f} s CPU")
    for level in DIRECT_FULL_FILM_ASSUMED:   # the default screen's verdict, kept for the record
        env = environment_from_scene(sc, roughness=RoughnessSpec.from_level(level), max_workers=1)
        q = sp[np.isfinite(sp)]
        lam = film_parameter(env, q, np.full(q.shape, torque_Nm / g.rb1_m / (env.width_m * slices)))
        try:
            direct_mesh_stiffness(env, sc.mesh, s, torque_Nm, "rough_transient", transient=st, max_workers=1)
            why = "evaluated"
        except DirectTVMSError as exc:
            why = str(exc)
        res["full_film_assumption"].setdefault(f"rough_level_{level}", {})["default_screen"] = {
            "film_parameter_min": float(lam.min()), "film_parameter_max": float(lam.max()), "verdict": why}
    sm = np.array(res["tvms_N_per_m"]["smooth"])
    res["relative_to_smooth"] = {k: [None if x is None else float(x / sm[i] - 1.0) for i, x in enumerate(v)]
                                 for k, v in res["tvms_N_per_m"].items()}
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "direct_tvms.json", "w") as fh:
        json.dump(res, fh, indent=1)
    _direct_figure(res, out / "direct_tvms.png")
    return res


def run_direct_speed_torque(out: Path, slices: int = 2, n_nodes: int = 257, T_average: float = 8.0,
                            max_workers=None, log=print) -> dict:
    """Seed 000 Figs. 14-15 at THEIR roughness level 4, without tables: TVMS (N/m) at the pitch point
    with the smooth steady film and the level-4 transient rough film (reduction (b)) at
    SPEEDS (rpm) x 2000 N m (Fig. 14) and TORQUES (N m) x 2000 rpm (Fig. 15), level 4 under seed 000's
    full-film assumption (check_film_parameter=False; the screen's Lambda is recorded); writes
    direct_tvms_speed_torque.json and direct_tvms_speed_torque.png.  A film that fails leaves
    that point null with the reason (tests/unit/assembly/test_direct_tvms_speed_torque.py asserts the orderings)."""
    from gearfmu.contact.models import RoughnessSpec
    from gearfmu.scene.physics import environment_from_scene
    from gearfmu.assembly.direct_tvms import DirectTVMSError, TransientFilmSettings, direct_mesh_stiffness
    from gearfmu.gear.geometry import pair_geometry
    from gearfmu.scene.reader import load_scene
    from gearfmu.dynamics.sweeps import make_executor

    base = load_scene(ROOT / "examples" / "scenes" / "seed000_table1.toml")
    g = pair_geometry(base.pair)
    st = TransientFilmSettings(n_nodes=n_nodes, T_average=T_average)
    res = {"scene": "examples/scenes/seed000_table1.toml", "position": "pitch point (single-tooth contact, SRR 0)",
           "s_m": float(g.s_pitch_m), "roughness_level": 4, "slices": slices, "n_nodes": n_nodes,
           "T_average_b_per_u_s": T_average, "reduction": st.reduction, "check_film_parameter": False,
           "errors": "perfect gears (no deviations, no crowning)", "points": []}
    cases = [("fig14_speed", 2000.0, n) for n in SPEEDS] + [("fig15_torque", t, 2000.0) for t in TORQUES]
    done = {}
    with make_executor(max_workers=max_workers) as ex:
        for fig, tq, rpm in cases:
            if (tq, rpm) in done:
                res["points"].append(dict(done[(tq, rpm)], figure=fig))
                continue
            op = dataclasses.replace(base.operating, torque_Nm=tq, speed_rad_s=rpm * math.pi / 30.0)
            sc = dataclasses.replace(base, operating=op, mesh=dataclasses.replace(base.mesh, slices=slices))
            p = {"figure": fig, "torque_Nm": tq, "speed_rpm": rpm}
            sm = direct_mesh_stiffness(environment_from_scene(sc, max_workers=1), sc.mesh, [g.s_pitch_m], tq,
                                       "smooth_ehl", executor=ex, progress=False)
            p["smooth_N_per_m"] = float(sm.k_mesh_N_per_m[0])
            env4 = environment_from_scene(sc, roughness=RoughnessSpec.from_level(4), max_workers=1)
            try:
                r = direct_mesh_stiffness(env4, sc.mesh, [g.s_pitch_m], tq, "rough_transient", transient=st,
                                          executor=ex, progress=False, check_film_parameter=False)
            except DirectTVMSError as exc:
                p.update(rough_level_4_N_per_m=None, relative_to_smooth=None, status="failed", reason=str(exc)[:400])
                log(f"direct L4 {tq:g} N m, {rpm:g} rpm: failed: {exc}")
            else:
                k4 = float(r.k_mesh_N_per_m[0])
                p.update(rough_level_4_N_per_m=k4, relative_to_smooth=k4 / p["smooth_N_per_m"] - 1.0, status="ok",
                         failures=r.failures, films=_film_summary(r))
                p["films"] = {kk: (v[0] if isinstance(v, list) else v) for kk, v in p["films"].items()}
                log(f"direct L4 {tq:g} N m, {rpm:g} rpm: {k4:.6e} N/m ({p['relative_to_smooth']:+.3e} of smooth), "
                    f"screen Lambda {p['films']['film_parameter_screen']:.3f}, h_min {p['films']['h_min_m']:.3e} m, "
                    f"{r.cpu_s:.1f} s CPU")
            done[(tq, rpm)] = {k: v for k, v in p.items() if k != "figure"}
            res["points"].append(p)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "direct_tvms_speed_torque.json", "w") as fh:
        json.dump(res, fh, indent=1)
    _speed_torque_figure(res, out / "direct_tvms_speed_torque.png")
    return res


def _speed_torque_figure(res: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    for a, (key, xname, xlab) in zip(ax, (("fig14_speed", "speed_rpm", "pinion speed (rpm), 2000 N m"),
                                          ("fig15_torque", "torque_Nm", "pinion torque (N m), 2000 rpm"))):
        pts = [p for p in res["points"] if p["figure"] == key]
        x = [p[xname] for p in pts]
        a.plot(x, [p["smooth_N_per_m"] / 1e9 for p in pts], "k-o", label="smooth (steady film)")
        ok = [p for p in pts if p["rough_level_4_N_per_m"] is not None]
        a.plot([p[xname] for p in ok], [p["rough_level_4_N_per_m"] / 1e9 for p in ok], "-s", color="tab:purple",
               label="rough level 4 (transient, full film assumed)")
        for p in ok:
            a.annotate(f"{p['relative_to_smooth']:+.1e}\nh_min {p['films']['h_min_m'] * 1e6:.2f} um",
                       (p[xname], p["rough_level_4_N_per_m"] / 1e9), fontsize=7, ha="center", va="top",
                       textcoords="offset points", xytext=(0, -4))
        a.set_xlabel(xlab)
        a.set_ylabel("TVMS at the pitch point (GN/m)")
        a.legend(fontsize=8)
    fig.suptitle(f"Seed 000 Figs. 14-15 (roughness level 4), direct TVMS at the pitch point: {res['slices']} slices, "
                 f"{res['n_nodes']} EHL nodes, T_average {res['T_average_b_per_u_s']:g}, reduction (b); "
                 "check_film_parameter=False", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _film_summary(r) -> dict:
    """Per position: the solved transient films' minimum h (m) over the averaging window and x, the
    minimum over the whole run, h_min / composite sigma, starts and rescued steps (DirectTVMS fields)."""
    N = r.k_mesh_N_per_m.size
    def per_pos(a, f):
        return [None if not np.any(np.isfinite(a[..., i])) else float(f(a[..., i])) for i in range(N)]
    return {"sigma_composite_m": r.sigma_composite_m,
            "film_parameter_screen": per_pos(r.film_parameter, np.nanmin),
            "h_min_m": per_pos(r.h_min_m, np.nanmin), "h_min_run_m": per_pos(r.h_min_run_m, np.nanmin),
            "h_min_over_sigma": per_pos(r.h_min_over_sigma, np.nanmin),
            "smooth_starts": sum(1 for q in r.film_runs if q["start"] == "smooth"),
            "rescued_steps": sum(q["rescued_steps"] for q in r.film_runs), "runs": len(r.film_runs),
            "cpu_s": round(r.cpu_s, 2), "passes": r.passes, "film_evaluations": r.film_evaluations}


def _direct_full_film(env, sc, s, torque_Nm, model, st, ex, log, name):
    """Levels of DIRECT_FULL_FILM_ASSUMED: one direct_mesh_stiffness call per position with
    check_film_parameter=False (seed 000's full-film assumption), so that a film that stalls at one
    position does not hide the other.  Returns (TVMS per position, None where the film failed;
    the flagged record)."""
    from gearfmu.assembly.direct_tvms import DirectTVMSError, direct_mesh_stiffness

    k, rec = [], {"check_film_parameter": False,
                  "assumption": "seed 000 section 5: full film at every roughness level of its Table 2; the default "
                                "screen (Lambda = h_min/sigma < 3, Dowson-Higginson h_min, undeformed composite sigma) "
                                "refuses this level", "positions": []}
    for si in s:
        try:
            r = direct_mesh_stiffness(env, sc.mesh, [si], torque_Nm, model, transient=st, executor=ex,
                                      progress=False, check_film_parameter=False)
        except DirectTVMSError as exc:
            k.append(None)
            rec["positions"].append({"s_m": float(si), "status": "failed", "reason": str(exc)[:400]})
            log(f"direct {name} at s = {si * 1e3:.4f} mm: failed: {exc}")
            continue
        k.append(float(r.k_mesh_N_per_m[0]))
        q = {"s_m": float(si), "status": "ok", "failures": r.failures}
        q.update({kk: (v[0] if isinstance(v, list) else v) for kk, v in _film_summary(r).items()})
        rec["positions"].append(q)
        log(f"direct {name} at s = {si * 1e3:.4f} mm: {k[-1]:.6e} N/m, h_min {q['h_min_m']:.3e} m "
            f"(h_min/sigma {q['h_min_over_sigma']:.3f}, screen Lambda {q['film_parameter_screen']:.3f}), "
            f"{r.cpu_s:.1f} s CPU")
    return k, rec


def _direct_figure(res: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = [n for n in ("hertz", "smooth", "rough_level_1", "rough_level_2", "rough_level_3", "rough_level_4")
             if n in res["relative_to_smooth"]]
    tick = {"hertz": "Hertz", "smooth": "smooth", "rough_level_1": "rough 1", "rough_level_2": "rough 2",
            "rough_level_3": "rough 3*", "rough_level_4": "rough 4*"}
    color = {"hertz": "0.5", "smooth": "k", "rough_level_1": "tab:blue", "rough_level_2": "tab:red",
             "rough_level_3": "tab:orange", "rough_level_4": "tab:purple"}
    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    for i, p in enumerate(res["positions"]):
        rel = [res["relative_to_smooth"][n][i] for n in names]
        a = ax[i]
        a.bar(range(len(names)), [0.0 if r is None else r * 1e3 for r in rel], color=[color[n] for n in names],
              hatch=None)
        for x, n in enumerate(names):
            if rel[x] is None:
                a.annotate("film\nfailed\n(stall)", (x, 0.0), ha="center", va="top", fontsize=7)
        a.set_xticks(range(len(names)))
        a.set_xticklabels([tick[n] for n in names])
        a.set_ylabel("TVMS / smooth - 1 (per mille)")
        a.set_yscale("symlog", linthresh=0.01)
        a.set_title(f"{p['label']}\nsmooth {res['tvms_N_per_m']['smooth'][i] / 1e9:.5f} GN/m, SRR "
                    + ", ".join(f"{x:+.2f}" for x in p["srr"]), fontsize=9)
        for x, r in enumerate(rel):
            if names[x] == "smooth" or r is None:
                continue
            a.annotate(f"{r:+.2e}", (x, r * 1e3), ha="center", va="bottom" if r >= 0 else "top", fontsize=7)
    fig.suptitle(f"Seed 000 Figs. 12-13, direct TVMS: {res['torque_Nm']:g} N m, 2000 rpm, {res['slices']} slices, "
                 f"{res['n_nodes']} EHL nodes, transient reduction (b)\n* levels 3-4 under seed 000's full-film "
                 "assumption (screen Lambda = h_min/sigma < 3, check_film_parameter=False)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _figures(base, curves, out: Path, slices: int) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from gearfmu.contact.models import RoughnessSpec
    from gearfmu.scene.physics import environment_from_scene
    from gearfmu.ehl.mesh_film import contact_kinematics, involute_arc_length_m, solve_slice_film
    from gearfmu.gear.geometry import pair_geometry

    g = pair_geometry(base.pair)
    # Figs. 7-8: pressure and film on several slices at the pitch point (smooth, level 1, level 2)
    env = environment_from_scene(dataclasses.replace(base, mesh=dataclasses.replace(base.mesh, slices=44)),
                                 roughness=RoughnessSpec.from_level(2), max_workers=1)
    fenv = env.film_environment()
    s = g.s_pitch_m
    R, u, _ = contact_kinematics(g, s, env.omega1_rad_s)
    w = base.operating.torque_Nm / g.rb1_m / base.pair.pinion.face_width_m
    fig, ax = plt.subplots(2, 2, figsize=(10, 6), sharex=True)
    for col, level in enumerate((1, 2)):
        e = dataclasses.replace(env, roughness=RoughnessSpec.from_level(level), _flanks=None)
        fl = e.flanks()
        a1 = float(involute_arc_length_m(g.roll_length_at(1, s), g.rb1_m))
        a2 = float(involute_arc_length_m(g.roll_length_at(2, s), g.rb2_m))
        o, r = solve_slice_film(fenv, float(R), float(u), w, return_result=True)
        ax[0, col].plot(r.X, r.p_Pa / 1e9, "k", lw=2, label="smooth")
        ax[1, col].plot(r.X, r.h_m * 1e6, "k", lw=2, label="smooth")
        b = r.b_m
        for n in (0, 10, 20, 30):
            x = np.linspace(-5 * b, 2 * b, 2801)
            o, rr = solve_slice_film(fenv, float(R), float(u), w, (x, fl.composite_m(n, a1, a2, x)), True)
            if rr is None:
                continue
            ax[0, col].plot(rr.X, rr.p_Pa / 1e9, lw=0.8, label=f"slice {n}")
            ax[1, col].plot(rr.X, rr.h_m * 1e6, lw=0.8, label=f"slice {n}")
        ax[0, col].set_title(f"pitch point, 2000 N m, roughness level {level}")
        ax[0, col].set_ylabel("pressure (GPa)")
        ax[1, col].set_ylabel("film thickness (um)")
        ax[1, col].set_xlabel("X = x/b")
        ax[0, col].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "fig7_8_pressure_film.png", dpi=120)
    plt.close(fig)

    # Fig. 9: film stiffness along the LOA and across the face (level 1, nominal line load)
    e = dataclasses.replace(env, roughness=RoughnessSpec.from_level(1), _flanks=None,
                            n_slices=slices * 4, width_m=base.pair.pinion.face_width_m / (slices * 4))
    sp = np.linspace(g.s_start_m, g.s_end_m, 9)
    from gearfmu.contact.models import rough_ehl_model, smooth_ehl_model
    S, N = np.meshgrid(sp, np.arange(e.n_slices), indexing="ij")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        kr = rough_ehl_model(e, S.ravel(), N.ravel(), np.full(S.size, w)).k_N_per_m.reshape(S.shape)
        ks = smooth_ehl_model(e, sp, np.zeros(sp.size, int), np.full(sp.size, w)).k_N_per_m
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    ax[0].plot((sp - g.s_start_m) * 1e3, ks / 1e9, "k", lw=2, label="smooth")
    for n in range(0, e.n_slices, max(1, e.n_slices // 4)):
        ax[0].plot((sp - g.s_start_m) * 1e3, kr[:, n] / 1e9, lw=0.8, label=f"level 1, slice {n}")
    ax[0].set_xlabel("position along the LOA from A (mm)")
    ax[0].set_ylabel("film stiffness per slice (GN/m)")
    ax[0].legend(fontsize=7)
    im = ax[1].imshow(kr.T / 1e9, aspect="auto", origin="lower",
                      extent=[0, (g.s_end_m - g.s_start_m) * 1e3, 0, e.n_slices])
    ax[1].set_xlabel("position along the LOA from A (mm)")
    ax[1].set_ylabel("slice")
    fig.colorbar(im, ax=ax[1], label="film stiffness (GN/m)")
    fig.tight_layout()
    fig.savefig(out / "fig9_film_stiffness.png", dpi=120)
    plt.close(fig)

    # Figs. 12-15: TVMS curves over one table period
    fig, ax = plt.subplots(1, 3, figsize=(14, 4))
    for name in ("hertz", "smooth", "rough_level_1", "rough_level_4"):
        ax[0].plot(curves[name][1] / 1e9, label=name)
    for name in curves:
        if name.startswith("rough_level") and "@" not in name:
            ax[1].plot(curves[name][1] / 1e9, label=name)
    for r, t in enumerate(TORQUES):
        ax[2].plot(curves["smooth"][r] / 1e9, label=f"smooth {t:g} N m")
    for a_, title in zip(ax, ("Fig. 12: contact models (2000 N m)", "Fig. 13: roughness levels",
                              "Fig. 15: torque")):
        a_.set_title(title)
        a_.set_xlabel("angle index")
        a_.set_ylabel("TVMS (GN/m)")
        a_.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "fig12_15_tvms.png", dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print one JSON object to stdout")
    ap.add_argument("--points-per-mesh", type=int, default=4)
    ap.add_argument("--slices", type=int, default=2)
    ap.add_argument("--out", default=str(ROOT / "examples" / "output" / "seed000_trends"))
    ap.add_argument("--also-policy", action="append", default=[], metavar="POLICY",
                    help="add levels 3-4 with this [roughness] on_film_failure (e.g. load_sharing) as "
                         "rows 'rough_level_N+POLICY'")
    ap.add_argument("--transient-levels", type=int, nargs="+", default=[], metavar="LEVEL",
                    help="add the tables with [roughness] film_transient = 'correction' of these levels, "
                         "reductions (b) and (a), as the JSON key 'film_transient'")
    ap.add_argument("--direct", action="store_true",
                    help="add the TVMS evaluated directly at two meshing positions (JSON key 'direct_tvms')")
    ap.add_argument("--only-direct", action="store_true", help="only the direct TVMS (no tables)")
    ap.add_argument("--direct-slices", type=int, default=2)
    ap.add_argument("--direct-nodes", type=int, default=257, help="EHL grid nodes of the direct films")
    ap.add_argument("--direct-T-average", type=float, default=8.0,
                    help="transient averaging window after the wash-out (b/u_s)")
    ap.add_argument("--workers", type=int, default=None, help="worker processes of the direct TVMS")
    ap.add_argument("--direct-speed-torque", action="store_true",
                    help="add seed 000 Figs. 14-15 at roughness level 4, direct TVMS at the pitch point "
                         "(JSON key 'direct_tvms_speed_torque', about 45 s CPU more)")
    ap.add_argument("--only-direct-speed-torque", action="store_true",
                    help="only the level-4 speed/torque points of --direct-speed-torque (no tables)")
    a = ap.parse_args(argv)
    log = (lambda *x: print(*x, file=sys.stderr, flush=True))
    if a.only_direct_speed_torque:
        a.only_direct, a.direct = True, False
    res = {} if a.only_direct else run(a.points_per_mesh, a.slices, Path(a.out), log,
                                       policies=tuple(a.also_policy), transient_levels=tuple(a.transient_levels))
    if a.direct or (a.only_direct and not a.only_direct_speed_torque):
        res["direct_tvms"] = run_direct(Path(a.out), a.direct_slices, a.direct_nodes, a.direct_T_average,
                                        a.workers, log)
    if a.direct_speed_torque or a.only_direct_speed_torque:
        res["direct_tvms_speed_torque"] = run_direct_speed_torque(Path(a.out), a.direct_slices, a.direct_nodes,
                                                                  a.direct_T_average, a.workers, log)
    if a.json:
        print(json.dumps(res))
    else:
        print(json.dumps(res, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
