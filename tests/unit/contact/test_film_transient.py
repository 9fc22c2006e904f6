"""[roughness] film_transient: the transient film correction of the rough-EHL film grid
(docs/ehl_transient.md section 3 "last row", gearfmu/contact/models.py RoughFilmGrid).

References:
* "off": the grid's rough/smooth ratios equal, bit for bit, direct steady solves of the same
  nodes (gearfmu.ehl.mesh_film.solve_node_films with the flank profile built here from the
  involute arc lengths, seed 000 eq 3) -- the steady pipeline is untouched;
* smooth surfaces: the transient of a smooth film is the steady film (no time dependence
  without roughness, docs/ehl_transient.md T1: the BDF term of a stationary state is 0), so
  c = 1 up to the per-step iteration tolerance (tol_pressure = 1e-5);
* "correction": a node's stored c equals an independent direct call of
  solve_line_contact_transient at that node (position, load, slices spread over the face),
  and every slice's ratio is its steady ratio times c;
* bad values: a clear error naming the key.
Small grids (2-3 positions, one load column, 129 EHL nodes) keep this file short.
"""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from gearfmu.contact.models import (ContactModelError, RoughFilmGrid, RoughnessSpec, transient_node_correction,
                                    transient_slices)
from gearfmu.scene.physics import environment_from_scene
from gearfmu.scene.reader import SceneError, load_scene

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[3]
SCENE = ROOT / "examples" / "scenes" / "seed000_table1.toml"
EHL_NODES = 129


def _env(slices, mode, nodes=2, level=1):
    base = load_scene(SCENE)
    sc = dataclasses.replace(base, mesh=dataclasses.replace(base.mesh, contact_model="rough_ehl",
                                                           slices=slices))
    spec = RoughnessSpec.from_level(level, position_nodes=nodes, film_transient=mode)
    return environment_from_scene(sc, roughness=spec, max_workers=1, ehl_nodes=EHL_NODES)


def _grid(env, nodes=2):
    g = RoughFilmGrid(env, nodes)
    g.ensure(env, env.film_environment(), [0], [0])
    return g


@pytest.fixture(scope="module")
def grids():
    """The same 2 positions x 1 load x 5 slices grid, 'off' and 'correction'."""
    off_env, cor_env = _env(5, "off"), _env(5, "correction")
    return off_env, _grid(off_env), cor_env, _grid(cor_env)


def test_slice_choice():
    # CHOICE (docs/ehl_transient.md section 3): 4 slices, round(linspace(0, NS - 1, 4))
    assert list(transient_slices(44)) == [0, 14, 29, 43]    # 43/3 = 14.33, 86/3 = 28.67
    assert list(transient_slices(5)) == [0, 1, 3, 4]        # 4/3 = 1.33, 8/3 = 2.67
    assert list(transient_slices(2)) == [0, 1]


def test_off_is_the_steady_grid_bitwise(grids):
    from gearfmu.ehl.mesh_film import contact_kinematics, involute_arc_length_m, solve_node_films

    off_env, g_off, _, _ = grids
    assert RoughnessSpec.from_level(1) == RoughnessSpec.from_level(1, film_transient="off")
    assert "film_transient" not in g_off.summary() and not g_off.transient
    fenv, geom, fl = off_env.film_environment(), off_env.geom, off_env.flanks()
    w = float(g_off.w_node(0))
    for k, s in enumerate(g_off.s_nodes):
        R, u, _ = (float(np.ravel(v)[0]) for v in contact_kinematics(geom, np.array([s]), off_env.omega1_rad_s))
        b = math.sqrt(8.0 * w * R / (math.pi * fenv.E_prime_Pa))     # Hertz half-width
        x = np.linspace(-5.0 * b, 2.0 * b, 2801)
        a1 = float(involute_arc_length_m(geom.roll_length_at(1, s), geom.rb1_m))
        a2 = float(involute_arc_length_m(geom.roll_length_at(2, s), geom.rb2_m))
        sm, outs = solve_node_films(fenv, R, u, w, [(x, fl.composite_m(n, a1, a2, x)) for n in range(5)])
        for n, o in enumerate(outs):
            assert o.status == "ok"
            assert g_off.ratio[0][n, k] == o.k_N_per_m / sm.k_N_per_m       # bitwise


def test_correction_equals_direct_transient_calls(grids):
    from gearfmu.ehl.transient import flank_slice_case, solve_line_contact_transient

    _, g_off, cor_env, g = grids
    t = g.transient[0]
    assert t["status"] == ["ok", "ok"]
    # the steady part is the "off" grid, bit for bit
    np.testing.assert_array_equal(g.ratio_steady[0], g_off.ratio[0])
    w = float(g.w_node(0))
    for k, s in enumerate(g.s_nodes):
        ca, cb = [], []
        for n in (0, 1, 3, 4):
            r = solve_line_contact_transient(**flank_slice_case(cor_env, float(s), w, n), n_nodes=EHL_NODES)
            red = r.film_stiffness_reductions()
            k0 = r.k_film_N_per_m[0]                 # steady frozen-roughness start of the run
            cb.append(red["k_of_means_N_per_m"] / k0)
            ca.append(red["k_mean_of_k_N_per_m"] / k0)
        assert t["k_of_means"][k] == pytest.approx(np.mean(cb), rel=1e-12, abs=0)
        assert t["mean_of_k"][k] == pytest.approx(np.mean(ca), rel=1e-12, abs=0)
        # every slice (also 2, not run in time) gets its steady ratio x c
        np.testing.assert_array_equal(g.ratio[0][:, k], g_off.ratio[0][:, k] * t["k_of_means"][k])
    # a moving level-1 roughness changes the film: c != 1 beyond the iteration tolerance
    assert np.all(np.abs(t["k_of_means"] - 1.0) > 1e-4)
    summ = g.summary()["film_transient"]
    assert summ["failed_nodes"] == 0 and summ["transient_runs"] == 8 and summ["slices"] == [0, 1, 3, 4]
    # reduction (a) on request, without new solves
    g.set_transient_reduction("mean_of_k")
    np.testing.assert_array_equal(g.ratio[0], g_off.ratio[0] * t["mean_of_k"][None, :])
    g.set_transient_reduction("k_of_means")
    with pytest.raises(ContactModelError, match="reduction"):
        g.set_transient_reduction("median")


def test_smooth_surfaces_give_c_one():
    env = _env(1, "correction")
    fl = env.flanks()
    env._flanks = dataclasses.replace(fl, z1_m=np.zeros_like(fl.z1_m), z2_m=np.zeros_like(fl.z2_m))
    g = _grid(env)
    for red in ("k_of_means", "mean_of_k", "h_central_ratio", "h_mean_ratio"):
        # T1: stationary state, the time term vanishes; per-step tolerance tol_pressure = 1e-5
        np.testing.assert_allclose(g.transient[0][red], 1.0, rtol=0, atol=1e-5)


def test_failed_transient_is_a_failed_node(monkeypatch):
    """A transient stall fails the node: the stall fill rule gives it the linear interpolation
    of its corrected neighbours (fill_stalled_ratio), and the provenance counts it."""
    import gearfmu.ehl.transient as tr
    from gearfmu.ehl.errors import EHLConvergenceError

    env = _env(1, "correction", nodes=3)
    mid = float(np.linspace(env.geom.s_start_m, env.geom.s_end_m, 3)[1])
    real = tr.solve_line_contact_transient

    def fake(**kw):
        if abs(kw["R_m"] - _R(env, mid)) < 1e-15:
            raise EHLConvergenceError("transient step 3 stalled (test)", "pressure_change", 1.0)
        return real(**kw)

    monkeypatch.setattr(tr, "solve_line_contact_transient", fake)
    g = _grid(env, nodes=3)
    t = g.transient[0]
    assert t["status"] == ["ok", "stall", "ok"] and math.isnan(t["k_of_means"][1])
    assert g.status[0][0, 1] == "stall_interpolated"
    assert g.ratio[0][0, 1] == pytest.approx(0.5 * (g.ratio[0][0, 0] + g.ratio[0][0, 2]), rel=1e-14)
    summ = g.summary()
    assert summ["film_transient"]["failed_nodes"] == 1
    assert summ["film_transient"]["failed_nodes_by_status"] == {"stall": 1}
    assert summ["stalled_rough_nodes_interpolated"] == 1
    # a failed run fails the node whatever the other slices gave
    c = transient_node_correction([{"status": "ok", "message": "", "k_steady_N_per_m": 1.0,
                                    "k_of_means": 1.1, "mean_of_k": 1.2},
                                   {"status": "collapse", "message": "h <= 0"}])
    assert c["status"] == "collapse" and math.isnan(c["k_of_means"])


def _R(env, s):
    from gearfmu.ehl.mesh_film import contact_kinematics

    return float(np.ravel(contact_kinematics(env.geom, np.array([s]), env.omega1_rad_s)[0])[0])


def test_bad_values_rejected():
    with pytest.raises(ContactModelError, match="film_transient='on'"):
        RoughnessSpec.from_level(1, film_transient="on")
    with pytest.raises(ContactModelError, match="film_transient_reduction='median'"):
        RoughnessSpec.from_level(1, film_transient="correction", film_transient_reduction="median")
    with pytest.raises(ContactModelError, match="film_transient.*position_nodes >= 2"):
        RoughnessSpec.from_level(1, film_transient="correction", position_nodes=0)
    text = SCENE.read_text(encoding="utf-8")
    for extra, msg in (('film_transient = "full"', "roughness.film_transient"),
                       ('film_transient = 1', "roughness.film_transient"),
                       ('film_transient = "correction"\nfilm_position_nodes = 0',
                        "roughness.film_transient")):
        with pytest.raises(SceneError) as ei:
            load_scene(text + f"\n[roughness]\nlevel = 1\n{extra}\n")
        assert msg in str(ei.value)
    sc = load_scene(text + '\n[roughness]\nlevel = 2\nfilm_transient = "correction"\n')
    assert sc.roughness.film_transient == "correction"
    assert environment_from_scene(sc).roughness.film_transient == "correction"
    assert load_scene(text + "\n[roughness]\nlevel = 2\n").roughness.film_transient == "off"
