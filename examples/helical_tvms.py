"""Helical vs spur TVMS of the seed 001 Table 1 pair, and its FMU with seed 001's fractal contact
(docs/helical.md).

    python examples/helical_tvms.py            # both parts
    python examples/helical_tvms.py --tvms     # TVMS / ISO part only (Hertz contact, seconds)
    python examples/helical_tvms.py --fmu      # FMU part only (about 1-2 min)

TVMS part: build/helical/tvms.csv + tvms.png (total mesh stiffness over two mesh periods: the
transverse-equivalent spur pair, the helical pair, and the helical pair with eps_beta = 2) and
build/helical/iso.json (mean mesh stiffness per face width against ISO 6336-1 c_gamma_alpha over beta).

FMU part: builds the FMU of examples/scenes/seed001_table1_fractal.toml (contact_model =
"fractal_mixed", 20 slices, 32 points per mesh), runs it with fmpy at the scene's operating point
and checks it against the native solver; writes examples/output/seed001_helical_fmu/run.png (TVMS
of the fractal and Hertz tables, DTE, mesh force and pair forces) and summary.json.
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from gearfmu.gear.gearpair import MeshModelOptions
from gearfmu.gear.geometry import pair_geometry, transverse_equivalent
from gearfmu.scene.reader import load_scene
from gearfmu.gear.stiffness import slot_stiffness

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "build" / "helical"
FMU_OUT = ROOT / "examples" / "output" / "seed001_helical_fmu"


def iso_c_gamma_alpha(g, dedendum_coeff=1.25):
    """ISO 6336-1 method B, x = 0, virtual z_n = z/(cos^2 beta_b cos beta), N/(mm um)."""
    zf = math.cos(g.base_helix_angle_rad) ** 2 * math.cos(g.helix_angle_rad)
    q = 0.04723 + 0.15551 / (g.z1 / zf) + 0.25791 / (g.z2 / zf)
    cp = 0.8 * (1.0 + 0.5 * (1.2 - dedendum_coeff)) / q * math.cos(g.helix_angle_rad)
    return cp * (0.75 * g.contact_ratio + 0.25)


def with_beta(pair, beta_rad, b_m=None):
    def f(gs):
        return replace(gs, helix_angle_rad=beta_rad, face_width_m=b_m or gs.face_width_m)
    return replace(pair, pinion=f(pair.pinion), gear=f(pair.gear))


def tvms_part():
    OUT.mkdir(parents=True, exist_ok=True)
    scene = load_scene(ROOT / "examples" / "scenes" / "seed001_table1.toml")
    pair, opts = scene.pair, scene.mesh
    g = pair_geometry(pair)
    n = 256
    spur = slot_stiffness(transverse_equivalent(pair), None, MeshModelOptions(), None, n)
    hel = slot_stiffness(pair, g, opts, None, n)
    b2 = 2.0 * math.pi * g.normal_module_m / math.sin(g.helix_angle_rad)
    p2 = with_beta(pair, g.helix_angle_rad, b2)
    hel2 = slot_stiffness(p2, None, opts, None, n)
    phi = hel.phi_rad[: 2 * n] / g.mesh_period_rad
    cols = {"mesh_periods": phi,
            "spur_transverse_equivalent_N_per_m": spur.k_total_N_per_m[: 2 * n],
            "helical_seed001_N_per_m": hel.k_total_N_per_m[: 2 * n],
            "helical_eps_beta_2_N_per_m": hel2.k_total_N_per_m[: 2 * n]}
    with open(OUT / "tvms.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        w.writerows(zip(*cols.values()))
    rows = []
    for deg in (5, 10, 15, 20, 25, 30, 36, 40):
        p = with_beta(pair, math.radians(deg))
        gg = pair_geometry(p)
        k = slot_stiffness(p, gg, opts, None, 128).k_total_N_per_m
        km = k.mean() / gg.face_width_m / 1e9
        iso = iso_c_gamma_alpha(gg)
        rows.append(dict(beta_deg=deg, eps_alpha=gg.contact_ratio, eps_beta=gg.overlap_ratio,
                         k_mean_N_per_mm_um=km, iso_c_gamma_alpha=iso, rel_diff=km / iso - 1,
                         ptp_over_mean=float((k.max() - k.min()) / k.mean())))
        print(f"beta {deg:4.1f} deg: eps_a {gg.contact_ratio:.3f} eps_b {gg.overlap_ratio:.3f} "
              f"k_mean/b {km:6.2f}, ISO c_ga {iso:6.2f} ({km / iso - 1:+.1%}), ptp/mean {rows[-1]['ptp_over_mean']:.3f}",
              flush=True)
    summary = {"fluctuation_ptp_over_mean": {k: float((v.max() - v.min()) / v.mean()) for k, v in cols.items()
                                             if k != "mesh_periods"},
               "iso_6336_sweep": rows}
    (OUT / "iso.json").write_text(json.dumps(summary, indent=1))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4))
    for k, v in cols.items():
        if k != "mesh_periods":
            ax.plot(phi, v / 1e9, label=k.replace("_N_per_m", ""))
    ax.set_xlabel("pinion angle / mesh period")
    ax.set_ylabel("total mesh stiffness (N/(mm um))")
    ax.set_title("Seed 001 Table 1 pair: spur vs helical TVMS")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(OUT / "tvms.png", dpi=120)
    print(json.dumps(summary["fluctuation_ptp_over_mean"], indent=1))
    print(f"wrote {OUT / 'tvms.csv'}, {OUT / 'tvms.png'}, {OUT / 'iso.json'}")


def fmu_part():
    """Seed 001 pair with fractal mixed contact per slice: tables, FMU, fmpy run, native check."""
    import fmpy

    from gearfmu.fmu.compare import validate_fmu_against_native
    from gearfmu.pipeline import build, compute_tables, gear_torque_for

    FMU_OUT.mkdir(parents=True, exist_ok=True)
    scene = load_scene(ROOT / "examples" / "scenes" / "seed001_table1_fractal.toml")
    g = pair_geometry(scene.pair)
    c0 = time.process_time()
    res = build(scene, FMU_OUT / "seed001_fractal.fmu")
    build_cpu = time.process_time() - c0
    t = res.tables
    hertz = compute_tables(load_scene(ROOT / "examples" / "scenes" / "seed001_table1.toml"))
    i_nom = int(np.argmin(np.abs(t.torque_Nm - scene.operating.torque_Nm)))
    k_f = t.k_N_per_m[i_nom].sum(axis=0)
    k_h = hertz.k_N_per_m[0].sum(axis=0)
    T1 = scene.operating.torque_Nm
    stop, dt = scene.fmu.stop_time_s, scene.fmu.output_interval_s
    w0 = time.perf_counter()
    out = fmpy.simulate_fmu(str(res.fmu_path), stop_time=stop, output_interval=dt,
                            start_values={"pinion_torque": T1, "gear_torque": gear_torque_for(t, T1)})
    fmu_wall = time.perf_counter() - w0
    tt = out["time"]
    late = tt >= 0.5 * stop                                        # after the start-up transient
    F_static = T1 / t.base_radius_pinion_m
    rep = validate_fmu_against_native(
        res.fmu_path, t,
        native_kwargs=dict(max_step_s=res.max_step_s, pinion_torque_Nm=T1, gear_torque_Nm=gear_torque_for(t, T1),
                           pinion_speed_start_rad_s=scene.operating.speed_rad_s,
                           damping_ratio=scene.fmu.damping_ratio, damping_model=scene.solver.damping_model),
        stop_time_s=0.01, comm_step_s=dt)
    c = t.provenance["contact"]
    summary = {
        "scene": "examples/scenes/seed001_table1_fractal.toml",
        "contact_model": c["model"], "slices": scene.mesh.slices, "points_per_mesh": scene.tables.points_per_mesh,
        "torque_axis_Nm": t.torque_Nm.tolist(), "slots": t.slots, "total_contact_ratio": t.contact_ratio,
        "tables_wall_s": res.tables_compute_s, "fmu_build_wall_s": res.build_wall_s, "build_cpu_s": build_cpu,
        "contact_solves": c["solves"], "load_iteration_rows": c["load_iteration"]["rows"],
        "full_film_points": [r["failures"] for r in c["load_iteration"]["rows"]],
        "k_mean_fractal_N_per_m": float(k_f.mean()), "k_mean_hertz_N_per_m": float(k_h.mean()),
        "fractal_over_hertz": float(k_f.mean() / k_h.mean()),
        "k_mean_per_b_fractal_N_per_mm_um": float(k_f.mean() / g.face_width_m / 1e9),
        "iso_c_gamma_alpha_N_per_mm_um": iso_c_gamma_alpha(g),
        "fractal_vs_iso": float(k_f.mean() / g.face_width_m / 1e9 / iso_c_gamma_alpha(g) - 1),
        "ptp_over_mean_fractal": float((k_f.max() - k_f.min()) / k_f.mean()),
        "ptp_over_mean_hertz_60_slices": float((k_h.max() - k_h.min()) / k_h.mean()),
        "k_mean_by_torque_N_per_m": t.k_N_per_m.sum(axis=1).mean(axis=1).tolist(),
        "fmpy_wall_s": fmu_wall, "stop_time_s": stop, "output_interval_s": dt,
        "mesh_force_mean_second_half_N": float(out["mesh_force"][late].mean()),
        "static_mesh_force_N": F_static,
        "mesh_force_ptp_second_half_N": float(np.ptp(out["mesh_force"][late])),
        "dte_mean_second_half_um": float(out["dte"][late].mean() * 1e6),
        "dte_ptp_second_half_um": float(np.ptp(out["dte"][late]) * 1e6),
        "static_deflection_um": float(F_static / k_f.mean() * 1e6),
        "fmu_vs_native_max_rel_diff": max(v["rel_max_diff"] for v in rep["outputs"].values()),
        "fmpy_problems": rep["fmpy_problems"],
    }
    (FMU_OUT / "summary.json").write_text(json.dumps(summary, indent=1))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(3, 1, figsize=(8, 9))
    ph = t.phi_rad / t.mesh_period_rad
    ax[0].plot(ph, k_f / 1e9, label=f"fractal_mixed, {scene.mesh.slices} slices, {T1:g} N m")
    ax[0].plot(hertz.phi_rad / hertz.mesh_period_rad, k_h / 1e9, label="hertz, 60 slices")
    ax[0].set_xlabel("pinion angle / mesh period")
    ax[0].set_ylabel("total mesh stiffness (N/(mm um))")
    ax[0].legend(fontsize=8)
    ax[1].plot(tt * 1e3, out["dte"] * 1e6)
    ax[1].set_ylabel("DTE (um)")
    ax[2].plot(tt * 1e3, out["mesh_force"] / 1e3, label="mesh force")
    for i in range(t.slots):
        ax[2].plot(tt * 1e3, out[f"pair_force[{i + 1}]"] / 1e3, lw=0.6, label=f"pair_force[{i + 1}]")
    ax[2].axhline(F_static / 1e3, color="k", ls=":", lw=0.8, label="T1 / r_b1")
    ax[2].set_xlabel("time (ms)")
    ax[2].set_ylabel("force (kN)")
    ax[2].legend(fontsize=7, ncol=3)
    fig.suptitle("Seed 001 Table 1 helical pair, fractal mixed contact: FMU run (fmpy)")
    fig.tight_layout()
    fig.savefig(FMU_OUT / "run.png", dpi=110)
    print(json.dumps({k: v for k, v in summary.items() if k != "load_iteration_rows"}, indent=1))
    print(f"wrote {FMU_OUT / 'run.png'}, {FMU_OUT / 'summary.json'}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tvms", action="store_true", help="only the TVMS / ISO part")
    ap.add_argument("--fmu", action="store_true", help="only the fractal FMU part")
    a = ap.parse_args(argv)
    both = not (a.tvms or a.fmu)
    if a.tvms or both:
        tvms_part()
    if a.fmu or both:
        fmu_part()


if __name__ == "__main__":
    main()
