#!/usr/bin/env python3
"""Helical pair with load-dependent contact models per slice (prints JSON).

Seed 001 Table 1 helical pair (``examples/scenes/seed001_table1.toml``: 33/28 teeth, m_n 5 mm,
β 36°, b 60 mm), SCH632 at 60 °C (η0 0.118 Pa·s, α 20 /GPa), 1000 rpm, EHL grid of 129 nodes, tables
at 600 and 1200 N·m (docs/helical.md "Load-dependent contact models").  Per contact model and slicing
(``fractal_mixed`` 8 slices × 16 points per mesh, ``smooth_ehl`` 4 × 8): the mean total mesh stiffness
per face width at 1200 N·m against ISO 6336-1 method B c_γα (the reference; virtual numbers of teeth,
``examples/helical_tvms.py``), against the Hertz tables of the same slicing, its fluctuation
(peak-to-peak / mean) against that of the Hertz tables and of the spur pair of the same transverse
section with the same contact model (one slice: the classical overlap smoothing).

    python benchmarks/bench_helical_contact.py
"""
from __future__ import annotations

import importlib.util
import json
import math
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from gearfmu.contact.models import ContactEnvironment  # noqa: E402
from gearfmu.gear.gearpair import MeshModelOptions  # noqa: E402
from gearfmu.gear.geometry import pair_geometry, transverse_equivalent  # noqa: E402
from gearfmu.gear.stiffness import slot_stiffness  # noqa: E402
from gearfmu.scene.reader import load_scene  # noqa: E402
from gearfmu.assembly.precompute import precompute_tables  # noqa: E402

TORQUES = (600.0, 1200.0)
CASES = (("fractal_mixed", 8, 16), ("smooth_ehl", 4, 8))


def _iso():
    spec = importlib.util.spec_from_file_location("helical_tvms", ROOT / "examples" / "helical_tvms.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.iso_c_gamma_alpha


def contact_k_total(pair, model, slices, ppm):
    """Total mesh stiffness (N/m) over the angle grid at the nominal (largest) torque row."""
    g = pair_geometry(pair)
    b = min(pair.pinion.face_width_m, pair.gear.face_width_m)
    env = ContactEnvironment(pair=pair, geom=g, omega1_rad_s=1000.0 * math.pi / 30.0, n_slices=slices,
                             width_m=b / slices, eta0_Pas=0.118, alpha_Pa_inv=2e-8, rho0_kg_m3=870.0,
                             max_workers=1, ehl_nodes=129)
    t = precompute_tables(pair, MeshModelOptions(slices=slices, contact_model=model), points_per_mesh=ppm,
                          torque_axis_Nm=list(TORQUES), nominal_torque_Nm=TORQUES[-1], contact_env=env)
    return t.k_N_per_m[-1].sum(axis=0)


def _fluct(k) -> float:
    return float((k.max() - k.min()) / k.mean())


def main() -> int:
    t0 = time.perf_counter()
    pair = load_scene(ROOT / "examples" / "scenes" / "seed001_table1.toml").pair
    g = pair_geometry(pair)
    iso = _iso()(g)
    rows = []
    for model, slices, ppm in CASES:
        k = contact_k_total(pair, model, slices, ppm)
        kh = slot_stiffness(pair, g, MeshModelOptions(slices=slices), None, ppm).k_total_N_per_m
        ks = contact_k_total(transverse_equivalent(pair), model, 1, ppm)
        kbar = float(k.mean()) / g.face_width_m / 1e9
        rows.append({"model": model, "slices": slices, "points_per_mesh": ppm, "k_mean_N_per_mm_um": kbar,
                     "rel_diff_iso": kbar / iso - 1.0, "over_hertz": float(k.mean() / kh.mean()),
                     "ptp_over_mean": _fluct(k), "hertz_ptp_over_mean": _fluct(kh),
                     "spur_ptp_over_mean": _fluct(ks)})
        print(f"{model}: {kbar:.3f} N/(mm um)", file=sys.stderr, flush=True)
    print(json.dumps({"scene": "examples/scenes/seed001_table1.toml", "torque_Nm": TORQUES[-1],
                      "iso_c_gamma_alpha": iso, "rows": rows, "wall_s": time.perf_counter() - t0}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
