#!/usr/bin/env python3
"""Sawtooth of the sliced helical TVMS against the slice count (prints JSON).

The computation of ``examples/helical_sawtooth.py`` (docs/helical.md, "Slice sawtooth") as JSON:
seed 001 Table 1 scene, for each slice count NS the largest deviation of the total mesh stiffness
(relative to its mean) and of the static transmission error (relative to its peak-to-peak) from the
continuous-face-width limit, with whole slices and with partly engaged slices (the default).  The
limit is the partial-slice rule at 4 × the largest NS; ``limit_change_rel`` is its change from half
that NS.  The reference of the comparison is the continuous face width itself (a closed-form engaged
width, tests/unit/gear/test_helical_sawtooth.py); 1/(NS ε_α) is the expected size of a whole-slice step.

    python benchmarks/bench_helical_sawtooth.py [--points-per-mesh 64] [--slices 15 30 60 120 240]
"""
from __future__ import annotations

import argparse
import importlib.util
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from gearfmu.gear.geometry import pair_geometry  # noqa: E402
from gearfmu.scene.reader import load_scene  # noqa: E402


def _example():
    spec = importlib.util.spec_from_file_location("helical_sawtooth", ROOT / "examples" / "helical_sawtooth.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--points-per-mesh", type=int, default=64)
    ap.add_argument("--slices", type=int, nargs="+", default=[15, 30, 60, 120, 240])
    a = ap.parse_args(argv)
    t0 = time.perf_counter()
    ex = _example()
    sc = load_scene(ex.SCENE)
    g = pair_geometry(sc.pair)
    ppm, fine = a.points_per_mesh, 4 * max(a.slices)
    k_ref = ex.k_total(sc, g, fine, ppm, True)
    te_ref = ex.static_te(sc, fine, ppm, True)
    rows = []
    for ns in a.slices:
        kd = [float(np.max(np.abs(ex.k_total(sc, g, ns, ppm, p) - k_ref)) / k_ref.mean()) for p in (False, True)]
        td = [float(np.max(np.abs(ex.static_te(sc, ns, ppm, p) - te_ref)) / np.ptp(te_ref)) for p in (False, True)]
        rows.append({"slices": ns, "one_over_ns_eps_alpha": 1.0 / (ns * g.contact_ratio),
                     "k_dev_whole": kd[0], "k_dev_partial": kd[1], "te_dev_whole": td[0], "te_dev_partial": td[1]})
    print(json.dumps({"scene": "examples/scenes/seed001_table1.toml", "points_per_mesh": ppm,
                      "eps_alpha": g.contact_ratio, "eps_beta": g.overlap_ratio, "limit_slices": fine,
                      "limit_change_rel": float(np.max(np.abs(k_ref - ex.k_total(sc, g, fine // 2, ppm, True)))
                                                / k_ref.mean()),
                      "limit_k_ptp_over_mean": float(np.ptp(k_ref) / k_ref.mean()),
                      "limit_static_te_ptp_m": float(np.ptp(te_ref)), "rows": rows,
                      "wall_s": time.perf_counter() - t0}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
