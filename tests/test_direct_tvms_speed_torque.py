"""Direct TVMS (gearfmu.ehl.direct_tvms): seed 000 Figs. 14-15 at THEIR roughness level 4.

Reference: seed 000 (Zhao et al. 2022) section 5.3 / Fig. 14 ("the higher the rotational speed, the
smaller the OFS and TVMS"; "under high rotational speed conditions, a thicker oil film is more
easily formed") and section 5.4 / Fig. 15 ("the greater the torque, the greater the OFS and
TVMS"), both with rough flanks of roughness level 4 (its Table 2) and, as in all of its section 5,
under the full-film assumption (conclusions).  Qualitative: no number is read off the figures,
only the orderings are asserted.  The seed's text does not list the speeds and torques of the
figures; we take 1000 / 2000 / 4000 rpm at 2000 N m (Fig. 14) and 1000 / 2000 / 3000 N m at
2000 rpm (Fig. 15), the levels of the tables' trend test (tests/test_ehl_mesh.py
test_seed000_trends_fig12_14_15), all five points of that grid.

Level 4 has the screen's film parameter Lambda < 3 at four of the five points, so it runs with
check_film_parameter=False (seed 000's full-film assumption; docs/ehl_mesh.md "Direct TVMS").
One position: the pitch point (single-tooth contact, SRR 0); level 4 stalls at the mid
double-tooth position (tests/test_direct_tvms.py), so that position is not used here.
"""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from gearfmu.contact_models import RoughnessSpec, environment_from_scene
from gearfmu.ehl.direct_tvms import TransientFilmSettings, direct_mesh_stiffness
from gearfmu.geometry import pair_geometry
from gearfmu.scene import load_scene

ROOT = Path(__file__).resolve().parents[1]
SCENE = load_scene(ROOT / "examples" / "scenes" / "seed000_table1.toml")   # 2000 N m, 2000 rpm
GEOM = pair_geometry(SCENE.pair)
ST_257_8 = TransientFilmSettings(n_nodes=257, T_average=8.0)

SPEEDS_RPM = (1000.0, 2000.0, 4000.0)     # Fig. 14, at 2000 N m
TORQUES_NM = (1000.0, 2000.0, 3000.0)     # Fig. 15, at 2000 rpm
CASES = sorted({(2000.0, n) for n in SPEEDS_RPM} | {(t, 2000.0) for t in TORQUES_NM})   # (N m, rpm)


def _scene(torque_Nm: float, speed_rpm: float):
    op = dataclasses.replace(SCENE.operating, torque_Nm=torque_Nm, speed_rad_s=speed_rpm * math.pi / 30.0)
    return dataclasses.replace(SCENE, operating=op, mesh=dataclasses.replace(SCENE.mesh, slices=2))


@pytest.fixture(scope="module")
def films():
    """Smooth steady film and level-4 transient rough film (reduction (b)) at the pitch point for
    every (torque, speed) of CASES; 2 slices of 22 mm (slices 0-1 of level 4's roughness), 257 EHL
    nodes, T_average 8 b/u_s, start 'auto', 2 worker processes; computed once for the file."""
    from gearfmu.sweeps import make_executor

    s = [GEOM.s_pitch_m]
    out = {}
    with make_executor(max_workers=2) as pool:
        for tq, rpm in CASES:
            sc = _scene(tq, rpm)
            sm = direct_mesh_stiffness(environment_from_scene(sc, max_workers=1), sc.mesh, s, tq, "smooth_ehl",
                                       executor=pool, progress=False)
            env4 = environment_from_scene(sc, roughness=RoughnessSpec.from_level(4), max_workers=1)
            r4 = direct_mesh_stiffness(env4, sc.mesh, s, tq, "rough_transient", transient=ST_257_8, executor=pool,
                                       progress=False, check_film_parameter=False)
            out[(tq, rpm)] = (sm, r4)
    return out


# Measured (one run each, 2026-11-22), pitch point, TVMS in N/m, L4 = level 4 transient (b):
#   (N m, rpm)   smooth steady  L4 257/8      L4 513/16     L4/smooth-1 (257/8)  screen Lambda  min h (um, window)
#   2000, 1000   8.56604e8      8.53342e8     see below     -3.81e-3             1.35           0.36
#   2000, 2000   8.50898e8      8.48401e8                   -2.93e-3             2.19           0.95
#   2000, 4000   8.42212e8      8.40395e8                   -2.16e-3             3.55           2.32
#   1000, 2000   8.37710e8      8.32520e8                   -6.20e-3             2.39           0.61
#   3000, 2000   8.55819e8      8.54117e8                   -1.99e-3             2.07           0.86
# (513/16 column and the margins vs the grid/window change: filled in below)


def _check_films(r):
    assert r.failures == [] and r.load_change < 1e-3, (r.failures, r.load_change)
    assert np.all(np.isfinite(r.k_mesh_N_per_m))
    assert np.all(r.h_min_m[0] > 0) and np.all(r.h_min_run_m[0] > 0)       # a full film on every slice
    assert len(r.film_runs) == 2


def test_seed000_fig14_level4_tvms_falls_as_speed_rises(films):
    k4, h4 = [], []
    for rpm in SPEEDS_RPM:
        sm, r4 = films[(2000.0, rpm)]
        _check_films(r4)
        k4.append(r4.k_mesh_N_per_m[0])
        h4.append(np.min(r4.h_min_m[0]))
        assert r4.k_mesh_N_per_m[0] < sm.k_mesh_N_per_m[0], rpm      # Figs. 12-13: rough < smooth
    assert k4[0] > k4[1] > k4[2], k4                                 # Fig. 14
    assert h4[0] < h4[1] < h4[2], h4                                 # section 5.3: thicker film at higher speed
    # the screen's Lambda: Dowson-Higginson h_min ~ u^0.70 at fixed load and radius (closed form),
    # so Lambda(2 N) / Lambda(N) = 2^0.70 exactly
    lam = [films[(2000.0, rpm)][1].film_parameter[0, 0] for rpm in SPEEDS_RPM]
    assert lam[1] / lam[0] == pytest.approx(2.0 ** 0.70, rel=1e-9)
    assert lam[2] / lam[1] == pytest.approx(2.0 ** 0.70, rel=1e-9)


def test_seed000_fig15_level4_tvms_rises_with_torque(films):
    k4 = []
    for tq in TORQUES_NM:
        sm, r4 = films[(tq, 2000.0)]
        _check_films(r4)
        k4.append(r4.k_mesh_N_per_m[0])
        assert r4.k_mesh_N_per_m[0] < sm.k_mesh_N_per_m[0], tq       # Figs. 12-13: rough < smooth
        # the slice loads carry the torque: sum of line loads x slice width = T / r_b1 (seed 000 eq 16)
        w = r4.w_N_per_m[0, :, 0]
        assert np.sum(w) * SCENE.pair.pinion.face_width_m / 2 == pytest.approx(tq / GEOM.rb1_m, rel=1e-9)
    assert k4[0] < k4[1] < k4[2], k4                                 # Fig. 15
    # the screen's Lambda: Dowson-Higginson h_min ~ W^-0.13 (closed form; mean line load F/b ~ T)
    lam = [films[(tq, 2000.0)][1].film_parameter[0, 0] for tq in TORQUES_NM]
    assert lam[0] / lam[1] == pytest.approx(0.5 ** -0.13, rel=1e-9)
    assert lam[2] / lam[1] == pytest.approx(1.5 ** -0.13, rel=1e-9)
