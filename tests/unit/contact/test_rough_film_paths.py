"""The two steady rough-film paths agree on the same slice (docs/ehl_mesh.md
"Steady rough film: table path vs direct sampling").

* Table path: ``contact_models.rough_profile`` (composite roughness resampled on 2801 points
  over [-5b, 2b]) solved by ``mesh_film.solve_node_films`` (smooth film first, rough film
  warm-started from it, the steady solver's 8 dX band filter) -- what ``RoughFilmGrid`` stores
  at a grid node; between nodes the grid interpolates the rough/smooth ratio linearly in s.
* Direct path (the reference, sampled independently): the steady frozen-roughness start of
  ``transient.solve_line_contact_transient`` (``flank_slice_case``: each flank's profile read
  per surface at its own material coordinate on the solver grid, no band filter, no
  resampling, cold start), i.e. docs/ehl_transient.md 6.5's "frozen steady film at T = 0".

Seed 000 Table 1 pair (examples/scenes/seed000_table1.toml), roughness level 1, nominal line
load, 256 intervals (the solver's own choice there).  Measured: the two paths
differ by <= 6e-6 in the ratio at level 1 (slices 0, 7) and <= 9.3e-5 at level 2 (slices 0, 2,
4, 6, 7; the 8 dX filter); a composite with the wrong sign convention of wm
(z1(a1 + x) + z2(a2 - x)) moves the level-1 ratio by 0.028-0.029, so the tolerance 1e-4
separates them.
"""
from pathlib import Path

import numpy as np
import pytest

from gearfmu.contact.models import RoughnessSpec, rough_profile, _smooth_film_k, film_grid, rough_ehl_model
from gearfmu.scene.physics import environment_from_scene
from gearfmu.ehl.film_stiffness import slice_film_stiffness_N_per_m
from gearfmu.ehl.mesh_film import contact_kinematics, involute_arc_length_m, solve_node_films
from gearfmu.ehl.solver import solve_line_contact
from gearfmu.ehl.transient import flank_slice_case, solve_line_contact_transient
from gearfmu.gear.geometry import pair_geometry
from gearfmu.scene.reader import load_scene

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

SCENE = Path(__file__).resolve().parents[3] / "examples" / "scenes" / "seed000_table1.toml"
N_NODES = 257
TOL = 1e-4


@pytest.fixture(scope="module")
def case():
    sc = load_scene(SCENE)
    g = pair_geometry(sc.pair)
    w = sc.operating.torque_Nm / g.rb1_m / sc.pair.pinion.face_width_m
    return sc, g, w


def _direct_ratio(env, s, w, j):
    """Reference: the transient solver's steady frozen-roughness start (T = 0) over the smooth
    steady film on the same grid (both eq 8 "seed" on |x| <= b)."""
    kw = flank_slice_case(env, s, w, j)
    r = solve_line_contact_transient(n_nodes=N_NODES, n_steps=1, start="frozen", **kw)
    assert r.start == "frozen"
    sm = solve_line_contact(*(kw[k] for k in ("R_m", "E_Pa", "w_N_per_m", "u_m_s", "eta0_Pas",
                                              "alpha_Pa_inv", "rho0_kg_m3")), n_nodes=N_NODES)
    k_s = slice_film_stiffness_N_per_m(sm, kw["width_m"], "seed", kw["B0_Pa"], kw["B0_prime"])
    return float(r.k_film_N_per_m[0]) / k_s


def _table_node_ratio(env, s, w, slices, flip_sign=False):
    fenv = env.film_environment()
    fl = env.flanks()
    R, u, _ = (float(np.ravel(v)[0]) for v in contact_kinematics(env.geom, np.array([s]), env.omega1_rad_s))
    profs = []
    for j in slices:
        x, z = rough_profile(env, fenv, fl, s, j, w, R)
        if flip_sign:  # negative control: wm(x) = z1(a1 + x) + z2(a2 - x)
            a1 = float(involute_arc_length_m(env.geom.roll_length_at(1, s), env.geom.rb1_m))
            a2 = float(involute_arc_length_m(env.geom.roll_length_at(2, s), env.geom.rb2_m))
            z = fl.composite_m(j, a1, a2, -x)
        profs.append((x, z))
    sm, outs = solve_node_films(fenv, R, u, w, profs)
    assert sm.status == "ok" and all(o.status == "ok" for o in outs)
    return np.array([o.k_N_per_m / sm.k_N_per_m for o in outs])


def test_table_node_film_equals_direct_sampling_on_the_same_slice(case):
    """Pitch point, level 1, slices 0 and 7 (measured 0.98343 / 1.01402 on both paths): the table
    path's node film equals the transient start's frozen film within 1e-4 (reference: the other
    path, sampled independently); the wrong sign convention of wm does not."""
    sc, g, w = case
    env = environment_from_scene(sc, roughness=RoughnessSpec.from_level(1), max_workers=1, ehl_nodes=N_NODES)
    s = g.s_pitch_m
    table = _table_node_ratio(env, s, w, [0, 7])
    direct = np.array([_direct_ratio(env, s, w, j) for j in (0, 7)])
    np.testing.assert_allclose(table, direct, rtol=0, atol=TOL)
    flipped = _table_node_ratio(env, s, w, [0, 7], flip_sign=True)
    assert np.all(np.abs(flipped - direct) > 10 * TOL), (flipped, direct)


def test_table_grid_between_nodes_blends_the_direct_node_films(case):
    """The film grid's per-slice rough/smooth ratio at the pitch point (between position nodes 4
    and 5 of 9, f = 0.064) is (1 - f) r(s_4) + f r(s_5) of the direct films at the nodes
    (reference: the transient start at each node) -- not the direct film at the pitch point,
    which is a different draw of the roughness (docs/ehl_mesh.md)."""
    sc, g, w = case
    env = environment_from_scene(sc, roughness=RoughnessSpec.from_level(1), max_workers=1,
                                 ehl_nodes=N_NODES, n_slices=2, width_m=sc.pair.pinion.face_width_m / 2)
    s = g.s_pitch_m
    table = rough_ehl_model(env, [s, s], [0, 1], [w, w]).k_N_per_m
    grid = film_grid(env)
    k_s = _smooth_film_k(env, env.film_environment(), np.array([s, s]), np.array([w, w]))
    ratio = table / k_s
    k = int(np.searchsorted(grid.s_nodes, s)) - 1
    f = (s - grid.s_nodes[k]) / (grid.s_nodes[k + 1] - grid.s_nodes[k])
    assert 0.0 < f < 1.0
    ref = np.array([(1 - f) * _direct_ratio(env, float(grid.s_nodes[k]), w, j)
                    + f * _direct_ratio(env, float(grid.s_nodes[k + 1]), w, j) for j in (0, 1)])
    np.testing.assert_allclose(ratio, ref, rtol=0, atol=TOL)
