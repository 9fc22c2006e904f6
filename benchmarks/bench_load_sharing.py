#!/usr/bin/env python3
"""Film-asperity load sharing (Johnson, Greenwood & Poon 1972) at the seed 000 pitch point (prints JSON).

Seed 000 Table 1 pair (``examples/scenes/seed000_table1.toml``) at its pitch point, 2000 N·m,
its oil at the scene's temperature, a 1 mm slice, roughness levels 1-4 of seed 000 Table 2
(docs/load_sharing.md): the film parameters (Dowson-Higginson minimum film and Moes' central
film over the composite RMS), the Nayak/McCool summit parameters of the band-limited W-M
surface, the load share of the asperities, the JGP central film against the smooth one, the real
area ratio, the film and asperity springs of ``gearfmu.contact.load_sharing.load_sharing`` with
the EHL solver's smooth film stiffness as the film spring, and the Hertz stiffness for scale.

No outside reference for the numbers themselves (JGP's own load-share curve was not available);
the module's checks against closed forms and quadrature are in tests/unit/contact/test_load_sharing.py.

    python benchmarks/bench_load_sharing.py
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from gearfmu.contact.load_sharing import (LineContactState, asperity_parameters, load_sharing,  # noqa: E402
                                          wm_spectral_moments)
from gearfmu.contact.models import RoughnessSpec  # noqa: E402
from gearfmu.scene.physics import environment_from_scene  # noqa: E402
from gearfmu.contact.base import film_parameter  # noqa: E402
from gearfmu.ehl.mesh_film import contact_kinematics, solve_slice_film  # noqa: E402
from gearfmu.gear.geometry import pair_geometry  # noqa: E402
from gearfmu.gear.hertz import hertz_stiffness_N_per_m  # noqa: E402
from gearfmu.scene.reader import load_scene  # noqa: E402

WIDTH_M = 1e-3


def main() -> int:
    t0 = time.perf_counter()
    sc = load_scene(ROOT / "examples" / "scenes" / "seed000_table1.toml")
    g = pair_geometry(sc.pair)
    w = sc.operating.torque_Nm / g.rb1_m / sc.pair.pinion.face_width_m
    env = environment_from_scene(sc, max_workers=1)
    fenv = env.film_environment()
    R, u, _ = (float(v) for v in contact_kinematics(g, g.s_pitch_m, env.omega1_rad_s))
    film = solve_slice_film(fenv, R, u, w)
    if film.status != "ok":
        raise SystemExit(f"bench_load_sharing: the smooth film at the pitch point did not solve ({film.status})")
    k_smooth = float(film.k_N_per_m) / env.width_m * WIDTH_M
    st = LineContactState(R, u, w, fenv.E_prime_Pa, env.eta0_Pas, env.alpha_Pa_inv, WIDTH_M)
    rows = []
    for level in (1, 2, 3, 4):
        spec = RoughnessSpec.from_level(level, on_failure="load_sharing")
        env_l = environment_from_scene(sc, max_workers=1, roughness=spec)
        asp = asperity_parameters(wm_spectral_moments(spec.D, spec.G_m))
        r = load_sharing(st, asp, k_smooth_N_per_m=k_smooth)
        rows.append({"level": level, "film_parameter_dh": float(film_parameter(env_l, [g.s_pitch_m], [w])[0]),
                     "film_parameter_central": r.film_parameter, "eta_per_m2": asp.eta_per_m2,
                     "beta_m": asp.beta_m, "sigma_s_m": asp.sigma_s_m, "alpha": asp.alpha,
                     "asperity_share": r.asperity_share, "h_c_m": r.h_c_m, "h_c_smooth_m": r.h_c_smooth_m,
                     "area_ratio": r.area_ratio, "k_film_N_per_m": r.k_film_N_per_m,
                     "k_asp_N_per_m": r.k_asp_N_per_m, "k_N_per_m": r.k_N_per_m})
    print(json.dumps({"case": "seed 000 Table 1 pair, pitch point", "torque_Nm": sc.operating.torque_Nm,
                      "w_N_per_m": w, "R_m": R, "u_m_s": u, "oil_temperature_C": sc.lubricant.temperature_C,
                      "width_m": WIDTH_M, "k_smooth_N_per_m": k_smooth,
                      "k_hertz_N_per_m": hertz_stiffness_N_per_m(sc.pair, WIDTH_M), "rows": rows,
                      "wall_s": time.perf_counter() - t0}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
