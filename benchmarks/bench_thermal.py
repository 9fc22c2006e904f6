#!/usr/bin/env python3
"""Temperature stiffness of seed 004 (He & Yang) and the oil-temperature film (prints JSON).

Sections of the JSON (docs/thermal.md; seed values and the load from
``examples/seed004_temperature.py``, which holds the seed's Tables 2-3):

* ``tables23``: every Table 2-3 entry (pinion, gear, mesh; meshing-in, pitch, meshing-out;
  standard 30 °C, expansion 70 °C, shrinkage 10 °C) of pairs I and II: the seed's value, ours with
  the seed's own standard stiffness (``ours_with_seed_standard``: isolates the thermal model) and
  ours end to end (``ours``: our standard stiffness too).  Reference: seed 004 Tables 2-3.
* ``implied_load``: for each free-flank-deformation law of ``gearfmu.gear.thermal`` the normal load
  that the seed's Table 2 implies at each key point, F_n = |Δx_S,i| / (1/k_S,i − 1/k_i) with the
  shrinkage (−20 K) compliance of each tooth from Table 2; a law consistent with the seed gives one
  load at all six points.  Reference: the seed's Table 4 load, F_n = T_1/r_b1 (80 kW at 2000 rpm).
* ``oil``: η0(T) of the seed 004 oil (ASTM D341) and the film at pair I's pitch point: Moes'
  (1992) central and Dowson-Higginson's minimum film (closed-form fits) against the multigrid
  solver's slice film of the ``smooth_ehl`` contact model, and its film stiffness.
* ``profile_vs_mean``: the illustrative bulk-temperature profile of seed Figs. 6-7 (means ± 4 K)
  against its uniform mean, at the key points and as TVMS over a mesh period (no outside reference).

    python benchmarks/bench_thermal.py
"""
from __future__ import annotations

import importlib.util
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from gearfmu.common.vocabulary import FLANK_LAWS  # noqa: E402
from gearfmu.gear import thermal as th  # noqa: E402


def _example():
    spec = importlib.util.spec_from_file_location("seed004_temperature", ROOT / "examples" / "seed004_temperature.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def implied_loads(ex) -> dict:
    """Load (N) implied by the seed's Table 2 shrinkage compliances under each flank law."""
    out = {}
    for name in ("I", "II"):
        sc, geom, s, Fn = ex.pair_setup(name)
        std, shr = (np.array(ex.SEED_TABLE2[name][k]) * 1e8 for k in ("standard", "shrinkage"))
        dT = ex.STATES["shrinkage"] - ex.T_STANDARD_C
        laws = {}
        for law in FLANK_LAWS:
            loads = {}
            for which, gear in ((1, "pinion"), (2, "gear")):
                sl = slice(0, 3) if which == 1 else slice(3, 6)
                d = 1.0 / shr[sl] - 1.0 / std[sl]
                alpha = (sc.pair.pinion if which == 1 else sc.pair.gear).material.thermal_expansion_per_K
                free = np.abs(th.free_flank_deformation_m(geom, which, s, dT, alpha, law))
                loads[gear] = [float(v) for v in free / d]
            laws[law] = loads
        out[name] = {"table4_load_N": float(Fn), "laws": laws}
    return out


def main() -> int:
    t0 = time.perf_counter()
    ex = _example()
    rows = ex.table_rows()
    res = {"points": list(ex.POINTS), "states_C": ex.STATES, "torque_Nm": ex.TORQUE_NM, "tables23": rows,
           "implied_load": implied_loads(ex)}
    plt = ex._plt()
    with tempfile.TemporaryDirectory() as tmp:
        ex.oil(Path(tmp), plt, True)
        res["oil"] = json.loads((Path(tmp) / "oil_temperature.json").read_text())
        ex.fig7(Path(tmp), plt)
        res["profile_vs_mean"] = json.loads((Path(tmp) / "fig7.json").read_text())
    res["wall_s"] = time.perf_counter() - t0
    print(json.dumps(res, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
