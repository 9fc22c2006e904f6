"""Seed 001 (Xu, Shi & Fan, Lubricants 2023): fractal normal contact stiffness.

    python examples/seed001_fractal.py [--out DIR]

Writes to DIR (default examples/output/seed001_fractal):
  fig7a.png / fig7a.csv   K_s against the load in the validation setting of seed 001 Fig. 7a
                          (gray cast iron: E = 130 GPa, HB 231, D = 1.3504, G = 2.1504e-12 m,
                          lambda_c = 1), classical positive-contact model and the full model
                          (lateral contact, Gaussian weights, interaction); nominal area A0 = 1e-4 m^2
                          (our choice: the seed does not give the specimen's area)
  fig10.png / fig10.csv   K_s, K_l and K_n = K_s + K_l against A_r* (D = 1.45, G = 8e-9 m,
                          film 0.5 um; cf. seed 001 Fig. 10)
  fig8.png / fig8.csv     lambda_c against the curvature radius and the line load (cf. Fig. 8)
  slicing.csv             K_n, K_s, K_l per unit face width and A_r/A0 of the seed 000 Table 1 pair
                          at its pitch point (2000 N m, 2000 rpm, roughness levels 1-4) for 1, 2, 4,
                          11 and 44 face-width slices: the same for every slicing
  summary.json            the settings and a few numbers
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from gearfmu.contact import fractal as fc  # noqa: E402


def _write_csv(path, header, rows):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)


def fig7a(out: Path) -> dict:
    A0 = 1e-4
    E = 130e9
    surf = fc.FractalSurface(1.3504, 2.1504e-12)
    mat = fc.FractalMaterial(E, fc.brinell_to_hardness_Pa(231.0))
    loads = np.geomspace(10.0, 3000.0, 30)
    models = {"positive contact (MB + KE)": fc.FractalOptions(),
              "lateral + interaction (seed 001)": fc.SEED001_FULL}
    rows, curves = [], {}
    for i, P in enumerate(loads):
        row = [P, P / (A0 * E)]
        for name, o in models.items():
            r = fc.solid_contact_at_load(surf, mat, P, A0, o)
            row += [r.stiffness_N_per_m, r.real_area_m2 / A0]
            curves.setdefault(name, []).append(r.stiffness_N_per_m)
        rows.append(row)
        print(f"\rfig7a: {i + 1}/{loads.size}", end="", file=sys.stderr)
    print(file=sys.stderr)
    _write_csv(out / "fig7a.csv", ["load_N", "P_star", "Ks_positive_N_per_m", "Ar_star_positive",
                                   "Ks_full_N_per_m", "Ar_star_full"], rows)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4.2))
    for name, k in curves.items():
        ax.plot(loads, np.array(k) / 1e9, marker="o" if "positive" in name else "^", ms=3, label=name)
    ax.set_xlabel("normal load P (N)")
    ax.set_ylabel("K_s (GN/m)")
    ax.set_title("seed 001 Fig. 7a setting (D 1.3504, G 2.15e-12 m, lambda_c 1)", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "fig7a.png", dpi=130)
    plt.close(fig)
    return {"A0_m2": A0, "a_c_m2": fc.critical_area_m2(surf, mat),
            "Ks_at_1000N_positive": float(np.interp(1000.0, loads, curves["positive contact (MB + KE)"])),
            "Ks_at_1000N_full": float(np.interp(1000.0, loads, curves["lateral + interaction (seed 001)"]))}


def fig10(out: Path) -> dict:
    from scipy.optimize import brentq

    A0, E, h = 1e-6, 2.26e11, 0.5e-6
    surf = fc.FractalSurface(1.45, 8e-9)
    mat = fc.FractalMaterial(E, 6.4e9, friction=0.12)
    rows = []
    for As in np.linspace(0.002, 0.8, 40):
        u = brentq(lambda u: fc.solid_contact(surf, mat, math.exp(u), A0, fc.SEED001_FULL).real_area_m2 / A0 - As,
                   math.log(1e-30), math.log(10 * A0), xtol=1e-12)
        r = fc.solid_contact(surf, mat, math.exp(u), A0, fc.SEED001_FULL)
        kl = fc.oil_film_stiffness_N_per_m(A0, r.real_area_m2, h)
        rows.append([As, r.load_N, r.stiffness_N_per_m, kl, r.stiffness_N_per_m + kl])
    _write_csv(out / "fig10.csv", ["Ar_star", "load_N", "Ks_N_per_m", "Kl_N_per_m", "Kn_N_per_m"], rows)
    a = np.array(rows)
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4.2))
    for j, lab in ((2, "K_s"), (3, "K_l"), (4, "K_n = K_s + K_l")):
        ax.plot(a[:, 0], a[:, j] / 1e9, label=lab)
    ax.set_xlabel("A_r* = A_r / A0")
    ax.set_ylabel("stiffness (GN/m)")
    ax.set_title("cf. seed 001 Fig. 10: D 1.45, G 8e-9 m, h 0.5 um, A0 1 mm^2")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "fig10.png", dpi=130)
    plt.close(fig)
    cross = a[np.argmax(a[:, 2] > a[:, 3]), 0]
    return {"fig10_crossover_Ar_star": float(cross)}


def fig8(out: Path) -> dict:
    E, sig, ell = 2.26e11, 0.2e-6, 0.5e-3
    rhos = np.geomspace(1e-4, 10.0, 40)
    loads = np.linspace(0.0, 1e6, 41)
    lr = [fc.contact_correction_coefficient(r, 3e5, E, sig, ell) for r in rhos]
    lf = [fc.contact_correction_coefficient(0.02, w, E, sig, ell) for w in loads]
    _write_csv(out / "fig8.csv", ["rho_m", "lambda_c_at_3e5_N_per_m", "line_load_N_per_m", "lambda_c_at_rho_20mm"],
               [[rhos[i] if i < rhos.size else "", lr[i] if i < rhos.size else "", loads[i], lf[i]]
                for i in range(loads.size)])
    import matplotlib.pyplot as plt
    fig, axs = plt.subplots(1, 2, figsize=(9, 3.8))
    axs[0].semilogx(rhos, lr)
    axs[0].set_xlabel("combined curvature radius rho (m)")
    axs[0].set_ylabel("lambda_c")
    axs[1].plot(loads / 1e3, lf)
    axs[1].set_xlabel("line load (N/mm)")
    for ax in axs:
        ax.grid(alpha=0.3)
    fig.suptitle("lambda_c (our rebuild of seed 001 eq 19), sigma 0.2 um, footprint 0.5 mm")
    fig.tight_layout()
    fig.savefig(out / "fig8.png", dpi=130)
    plt.close(fig)
    return {"lambda_c_rho_20mm_300N_per_mm": float(fc.contact_correction_coefficient(0.02, 3e5, E, sig, ell))}


def slicing(out: Path) -> dict:
    """Seed 000 Table 1 pitch point: K per unit width for several face slicings."""
    from gearfmu.gear.hertz import reduced_modulus_Pa
    from gearfmu.contact.models import RoughnessSpec
    from gearfmu.scene.physics import environment_from_scene
    from gearfmu.ehl.mesh_film import contact_kinematics
    from gearfmu.gear.geometry import pair_geometry
    from gearfmu.scene.reader import load_scene

    sc = load_scene(ROOT / "examples" / "scenes" / "seed000_table1.toml")
    g = pair_geometry(sc.pair)
    env = environment_from_scene(sc, max_workers=1)
    R, u, _ = contact_kinematics(g, g.s_pitch_m, sc.operating.speed_rad_s)
    w = sc.operating.torque_Nm / g.rb1_m / sc.pair.pinion.face_width_m
    Es = reduced_modulus_Pa(sc.pair)
    face = sc.pair.pinion.face_width_m
    rows, spread = [], {}
    for level in (1, 2, 3, 4):
        sp = RoughnessSpec.from_level(level)
        kn = []
        for n in (1, 2, 4, 11, 44):
            r = fc.slice_contact_stiffness(sp.D, sp.G_m, float(R), float(u), w, face / n, Es, env.eta0_Pas,
                                           env.alpha_Pa_inv)
            W = face / n
            kn.append(r["K_n_N_per_m"] / W)
            rows.append([level, n, W, r["K_n_N_per_m"] / W, r["K_s_N_per_m"] / W, r["K_l_N_per_m"] / W,
                         r["real_area_ratio"], r["film_parameter"], r["lambda_c"]])
        spread[f"level{level}"] = {"K_n_per_width_N_per_m2": kn[0], "rel_spread": (max(kn) - min(kn)) / kn[0],
                                   "real_area_ratio": rows[-1][6], "film_parameter": rows[-1][7]}
    _write_csv(out / "slicing.csv", ["level", "slices", "width_m", "K_n_per_width_N_per_m2", "K_s_per_width_N_per_m2",
                                     "K_l_per_width_N_per_m2", "real_area_ratio", "film_parameter", "lambda_c"], rows)
    return {"slicing_seed000_pitch": spread}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(ROOT / "examples" / "output" / "seed001_fractal"))
    a = ap.parse_args(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    summary = {}
    summary.update(fig7a(out))
    summary.update(fig10(out))
    summary.update(fig8(out))
    summary.update(slicing(out))
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    print(json.dumps(summary, indent=2))


if __name__ == "__main__":
    main()
