#!/usr/bin/env python3
"""Mean mesh stiffness of the seed spur pairs against ISO 6336-1 method B (prints JSON).

For the example scenes of the seed pairs (seed 000 Table 1, seed 004 pairs I and II, seed 003
Table 1; geometry, material and hub radii as in ``examples/scenes/*.toml``) it computes, per face
width in N/(mm·µm): the largest single-pair stiffness, and the mean total mesh stiffness over a mesh
period with the shared-foundation correction (λ = 1), with independent foundations (the default)
and without the foundation term (docs/physics_stiffness.md).

Reference: ISO 6336-1:2019 clause 9 (method B), written out below: the single stiffness
c' = C_M C_R C_B / q' with q' = C1 + C2/z_n1 + C3/z_n2 + C4 x1 + C5 x1/z_n1 + C6 x2 + C7 x2/z_n2
+ C8 x1² + C9 x2² (ISO 6336-1 Table 9), C_M = 0.8, C_R = 1 (solid blank),
C_B = 1 + 0.5 (1.2 − h_fP/m) for α = 20°, and the mesh stiffness c_γα = c' (0.75 ε_α + 0.25).
ISO calls method B an approximation: compare against a ±25 % band, not an exact value.

    python benchmarks/bench_stiffness_iso.py
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from gearfmu.gear.gearpair import MeshModelOptions  # noqa: E402
from gearfmu.gear.geometry import pair_geometry  # noqa: E402
from gearfmu.gear.stiffness import mean_mesh_stiffness_N_per_m, slot_stiffness  # noqa: E402
from gearfmu.scene.reader import load_scene  # noqa: E402

#: ISO 6336-1:2019 Table 9, C1 .. C9 of q' (mm·µm/N)
ISO_C = (0.04723, 0.15551, 0.25791, -0.00635, -0.11654, -0.00193, -0.24188, 0.00529, 0.00182)
PAIRS = {"seed 000 Table 1": "seed000_table1", "seed 004 pair I": "seed004_pair1",
         "seed 004 pair II": "seed004_pair2", "seed 003 Table 1": "seed003_table1"}
UNIT = 1e9   # N/(mm·µm) = 1e9 N/m²


def iso_6336_method_b(z1, z2, x1, x2, eps_alpha, dedendum_coeff):
    """(c', c_γα) of ISO 6336-1:2019 method B in N/(mm·µm) (spur gears, solid blanks, α = 20°)."""
    c = ISO_C
    q = (c[0] + c[1] / z1 + c[2] / z2 + c[3] * x1 + c[4] * x1 / z1 + c[5] * x2 + c[6] * x2 / z2
         + c[7] * x1 ** 2 + c[8] * x2 ** 2)
    cb = 1.0 + 0.5 * (1.2 - dedendum_coeff)
    cp = 0.8 * 1.0 * cb / q
    return cp, cp * (0.75 * eps_alpha + 0.25)


def pair_row(label: str, scene: str) -> dict:
    sc = load_scene(ROOT / "examples" / "scenes" / f"{scene}.toml")
    pair = sc.pair
    g = pair_geometry(pair)
    b = pair.pinion.face_width_m
    dedendum = 1.0 + pair.pinion.tip_clearance_coefficient   # h_fP / m = ha* + c* with ha* = 1
    cp, cga = iso_6336_method_b(g.z1, g.z2, g.x1, g.x2, g.contact_ratio, dedendum)

    def mean(**kw):
        return mean_mesh_stiffness_N_per_m(pair, g, MeshModelOptions(**kw)) / b / UNIT

    return {"pair": label, "scene": f"examples/scenes/{scene}.toml", "z1": g.z1, "z2": g.z2, "x1": g.x1,
            "x2": g.x2, "eps_alpha": g.contact_ratio, "dedendum_coeff": dedendum, "hub_radius_m":
            [pair.pinion.hub_radius_m, pair.gear.hub_radius_m],
            "iso_c_prime": cp, "iso_c_gamma_alpha": cga,
            "ours_max_single_pair": float(slot_stiffness(pair, g, MeshModelOptions()).k_N_per_m.max()) / b / UNIT,
            "ours_mean_shared_correction": mean(shared_foundation_correction=True),
            "ours_mean_independent_foundations": mean(shared_foundation_correction=False),
            "ours_mean_no_foundation": mean(foundation=False)}


def main() -> int:
    t0 = time.perf_counter()
    rows = [pair_row(label, scene) for label, scene in PAIRS.items()]
    print(json.dumps({"unit": "N/(mm um)", "reference": "ISO 6336-1:2019 clause 9, method B",
                      "band_rel": 0.25, "rows": rows, "wall_s": time.perf_counter() - t0}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
