#!/usr/bin/env python3
"""The fractal mixed-lubrication contact (seed 001) at the seed 000 pitch point (prints JSON).

Seed 000 Table 1 pair (``examples/scenes/seed000_table1.toml``) at its pitch point, 2000 N·m,
roughness levels 1-4 of seed 000 Table 2, the ``fractal_mixed`` slice model
(``gearfmu.contact.fractal.slice_contact_stiffness``, docs/fractal_contact.md):

* ``levels``: K_n, K_s, K_l per unit face width, A_r/A0, the film parameter Λ and λc of one slice
  of the whole face, and the relative spread of K_n per width over 1, 2, 4, 11 and 44 slices
  (the model is built so that the slicing does not matter: the spread should be round-off);
* ``element_size``: K_s per width and A_r/A0 with the reference element's side 0.25, 0.5 and 1 mm
  (the solid part of the slice on elements of that area, everything else as in the slice model):
  what the choice of the element (docs/fractal_contact.md "How the nominal area enters") changes;
* ``hertz_per_width``: the Hertz line-contact stiffness per width at the same point, for scale.

No outside reference: the numbers describe our rebuild of seed 001; its checks against closed
forms and quadrature are in tests/unit/contact/test_fractal_contact.py.

    python benchmarks/bench_fractal.py
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from gearfmu.contact import fractal as fc  # noqa: E402
from gearfmu.contact.models import RoughnessSpec  # noqa: E402
from gearfmu.scene.physics import environment_from_scene  # noqa: E402
from gearfmu.ehl.mesh_film import contact_kinematics  # noqa: E402
from gearfmu.gear.geometry import pair_geometry  # noqa: E402
from gearfmu.gear.hertz import hertz_stiffness_N_per_m, reduced_modulus_Pa  # noqa: E402
from gearfmu.scene.reader import load_scene  # noqa: E402

SLICINGS = (1, 2, 4, 11, 44)
ELEMENT_SIDES_M = (0.25e-3, 0.5e-3, 1e-3)


def main() -> int:
    t0 = time.perf_counter()
    sc = load_scene(ROOT / "examples" / "scenes" / "seed000_table1.toml")
    g = pair_geometry(sc.pair)
    env = environment_from_scene(sc, max_workers=1)
    R, u, _ = (float(v) for v in contact_kinematics(g, g.s_pitch_m, sc.operating.speed_rad_s))
    face = sc.pair.pinion.face_width_m
    w = sc.operating.torque_Nm / g.rb1_m / face
    Es = reduced_modulus_Pa(sc.pair)
    mo = fc.FractalMeshOptions()
    levels, sizes = [], []
    for level in (1, 2, 3, 4):
        sp = RoughnessSpec.from_level(level)
        per_n = {n: fc.slice_contact_stiffness(sp.D, sp.G_m, R, u, w, face / n, Es, env.eta0_Pas, env.alpha_Pa_inv)
                 for n in SLICINGS}
        kn = [per_n[n]["K_n_N_per_m"] / (face / n) for n in SLICINGS]
        r = per_n[1]
        levels.append({"level": level, "D": sp.D, "G_m": sp.G_m,
                       "K_n_per_width_N_per_m2": r["K_n_N_per_m"] / face,
                       "K_s_per_width_N_per_m2": r["K_s_N_per_m"] / face,
                       "K_l_per_width_N_per_m2": r["K_l_N_per_m"] / face,
                       "real_area_ratio": r["real_area_ratio"], "film_parameter": r["film_parameter"],
                       "lambda_c": r["lambda_c"], "slicings": list(SLICINGS),
                       "K_n_rel_spread_over_slicings": (max(kn) - min(kn)) / kn[0]})
        # the solid part on reference elements of other sizes (lambda_c, sigma as in the slice model)
        surf = fc.FractalSurface(sp.D, sp.G_m)
        mat = fc.FractalMaterial(Es, mo.H_Pa, friction=mo.friction)
        b = fc.hertz_half_width_m(R, w, Es)
        A0 = 2.0 * b * face
        opts = fc.FractalOptions(lateral=mo.options.lateral, interaction=mo.options.interaction,
                                 lambda_c=r["lambda_c"])
        for side in ELEMENT_SIDES_M:
            sol = fc.solid_contact_extensive(surf, mat, w / (2.0 * b), A0, side ** 2, opts)
            sizes.append({"level": level, "element_side_m": side,
                          "K_s_per_width_N_per_m2": sol.stiffness_N_per_m / face,
                          "real_area_ratio": sol.real_area_m2 / A0})
    hertz = hertz_stiffness_N_per_m(sc.pair, face) / face
    print(json.dumps({"case": "seed 000 Table 1 pair, pitch point", "torque_Nm": sc.operating.torque_Nm,
                      "w_N_per_m": w, "R_m": R, "u_m_s": u, "b_m": fc.hertz_half_width_m(R, w, Es),
                      "face_width_m": face, "L_s_m": mo.L_s_m, "levels": levels, "element_size": sizes,
                      "hertz_per_width_N_per_m2": hertz, "wall_s": time.perf_counter() - t0}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
