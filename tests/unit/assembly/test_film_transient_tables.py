"""[roughness] film_transient = "film": the rough film of every film-grid node is the transient
film (gearfmu/contact/models.py RoughFilmGrid, docs/ehl_mesh.md "Transient films in the tables").

References (none produced by the code under test):
* a node's ratio equals an independent evaluation: the smooth film by solve_line_contact +
  slice_film_stiffness_N_per_m (seed 000 eq 8 on |x| <= b), the transient films by
  solve_line_contact_transient (start 'auto') and seed 000 eq 8 applied here to the window
  means of h_m and p_m (window from ramp + T_wash = ramp + (x_out - x_in)/min(U1, U2), computed
  here from the slide-to-roll ratio) -- to 1e-10;
* smooth flanks: the transient of a smooth film is the stationary steady film (docs/ehl_transient.md
  T1: the time term of a stationary state is 0), so the ratio is 1 up to the per-step iteration
  tolerance tol_pressure = 1e-5;
* failures: a stall takes the linear interpolation of the neighbours' ratios (the grid's stall
  rule, computed here), a collapse (h <= 0: no full film) goes to the film-failure policy;
* bad values: a clear error naming the field.
Small grids (2-3 positions, one load column, 129 EHL nodes) keep this file short.
"""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from gearfmu.contact.models import (ContactModelError, RoughFilmGrid, RoughnessSpec, rough_ehl_model,
                                    transient_node_film)
from gearfmu.scene.physics import environment_from_scene
from gearfmu.scene.reader import SceneError, load_scene

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[3]
SCENE = ROOT / "examples" / "scenes" / "seed000_table1.toml"
EHL_NODES = 129


def _env(slices, level=1, nodes=2, **kw):
    base = load_scene(SCENE)
    sc = dataclasses.replace(base, mesh=dataclasses.replace(base.mesh, contact_model="rough_ehl", slices=slices))
    spec = RoughnessSpec.from_level(level, position_nodes=nodes, film_transient="film", **kw)
    return environment_from_scene(sc, roughness=spec, max_workers=1, ehl_nodes=EHL_NODES)


def _grid(env, nodes=2):
    g = RoughFilmGrid(env, nodes)
    g.ensure(env, env.film_environment(), [0], [0])
    return g


def _kin(env, s):
    from gearfmu.ehl.mesh_film import contact_kinematics

    return [float(np.ravel(v)[0]) for v in contact_kinematics(env.geom, np.array([s]), env.omega1_rad_s)]


def test_node_ratio_equals_direct_transient_calls():
    from gearfmu.ehl.film_stiffness import film_stiffness_N_per_m, slice_film_stiffness_N_per_m
    from gearfmu.ehl.solver import solve_line_contact
    from gearfmu.ehl.transient import flank_slice_case, solve_line_contact_transient

    env = _env(2)
    g = _grid(env)
    t = g.transient[0]
    assert t["status"] == ["ok", "ok"]
    fenv = env.film_environment()
    w = float(g.w_node(0))
    for k, s in enumerate(g.s_nodes):
        R, u, slide = _kin(env, float(s))
        sm = solve_line_contact(R, fenv.E_prime_Pa, w, u, fenv.eta0_Pas, fenv.alpha_Pa_inv, fenv.rho0_kg_m3,
                                n_nodes=EHL_NODES)
        k_smooth = slice_film_stiffness_N_per_m(sm, fenv.width_m, "seed", fenv.B0_Pa, fenv.B0_prime)
        rb, ra = [], []
        for n in (0, 1):
            r = solve_line_contact_transient(**flank_slice_case(env, float(s), w, n), n_nodes=EHL_NODES,
                                             start="auto")
            srr = slide / u
            T0 = (r.ramp_T if r.start == "smooth" else 0.0) + 6.0 / min(1 + srr / 2, 1 - srr / 2)
            m = r.T >= T0 - 1e-12
            kb = film_stiffness_N_per_m(2.0 * r.b_m * fenv.width_m, float(np.mean(r.h_mean_m[m])),
                                        float(np.mean(r.p_mean_Pa[m])), fenv.B0_Pa, fenv.B0_prime)
            rb.append(kb / k_smooth)
            ra.append(float(np.mean(r.k_film_N_per_m[m])) / k_smooth)
        assert t["k_of_means"][k] == pytest.approx(np.mean(rb), rel=1e-10, abs=0)
        assert t["mean_of_k"][k] == pytest.approx(np.mean(ra), rel=1e-10, abs=0)
        # every slice of the node gets the same ratio (CHOICE), the per-slice values are kept
        np.testing.assert_array_equal(g.ratio[0][:, k], t["k_of_means"][k])
        np.testing.assert_allclose(t["slice_ratios"]["k_of_means"][:, k], rb, rtol=1e-10)
    # a moving level-1 roughness changes the film beyond the iteration tolerance
    assert np.all(np.abs(t["k_of_means"] - 1.0) > 1e-4)
    summ = g.summary()
    assert summ["rough_film_solves"] == 0                       # no steady rough solve
    ft = summ["film_transient"]
    assert ft["mode"] == "film" and ft["failed_nodes"] == 0 and ft["transient_runs"] == 4
    assert ft["film_parameter_screen"] is False
    spread = [np.ptp(t["slice_ratios"]["k_of_means"][:, k]) / np.mean(t["slice_ratios"]["k_of_means"][:, k])
              for k in range(2)]
    assert ft["slice_spread_max"] == pytest.approx(max(spread), rel=1e-12)
    g.set_transient_reduction("mean_of_k")                      # reduction (a) without new solves
    np.testing.assert_array_equal(g.ratio[0], np.broadcast_to(t["mean_of_k"], (2, 2)))


def test_smooth_flanks_give_ratio_one():
    env = _env(1)
    fl = env.flanks()
    env._flanks = dataclasses.replace(fl, z1_m=np.zeros_like(fl.z1_m), z2_m=np.zeros_like(fl.z2_m))
    g = _grid(env)
    for red in ("k_of_means", "mean_of_k"):
        # T1: the steady smooth film is the stationary solution; per-step tolerance 1e-5
        np.testing.assert_allclose(g.transient[0][red], 1.0, rtol=0, atol=1e-5)
    assert g.transient_summary()["runs_smooth_start"] == 0


def test_failed_nodes_stall_fill_and_collapse_policy(monkeypatch):
    import gearfmu.ehl.transient as tr
    from gearfmu.ehl.errors import EHLConvergenceError, FilmCollapseError

    env = _env(1, nodes=3)
    s3 = np.linspace(env.geom.s_start_m, env.geom.s_end_m, 3)
    R_mid, R_end = _kin(env, float(s3[1]))[0], _kin(env, float(s3[2]))[0]
    real = tr.solve_line_contact_transient

    def fake(**kw):
        if abs(kw["R_m"] - R_mid) < 1e-15:
            raise EHLConvergenceError("transient step 3 stalled (test)", "pressure_change", 1.0)
        if abs(kw["R_m"] - R_end) < 1e-15 and kw["w_N_per_m"] > 0:
            raise FilmCollapseError("h <= 0 (test)", h_min_m=-1e-9, film_parameter=0.5)
        return real(**kw)

    monkeypatch.setattr(tr, "solve_line_contact_transient", fake)
    g = _grid(env, nodes=3)
    t = g.transient[0]
    assert t["status"] == ["ok", "stall", "collapse"]
    # stall: no converged right neighbour -> not filled (fill rule needs both sides for an interior node)
    assert g.status[0][0, 1] == "stall" and not np.isfinite(g.ratio[0][0, 1])
    ft = g.summary()["film_transient"]
    assert ft["failed_nodes"] == 2 and ft["failed_nodes_by_status"] == {"collapse": 1, "stall": 1}
    # through the model: a request at the collapsed end node goes to the policy (no smooth stand-in)
    env.roughness = dataclasses.replace(env.roughness, on_failure="hertz")
    env._grid = g
    w0 = float(g.w_node(0))
    out = rough_ehl_model(env, [float(s3[0]), float(s3[2])], [0, 0], [w0, w0])
    from gearfmu.gear.hertz import hertz_stiffness_N_per_m

    assert out.k_N_per_m[1] == hertz_stiffness_N_per_m(env.pair, env.width_m)
    assert [f["status"] for f in out.failures] == ["collapse"]
    assert np.isfinite(out.k_N_per_m[0]) and out.k_N_per_m[0] != out.k_N_per_m[1]
    # node rule: any failed slice fails the node
    c = transient_node_film([{"status": "ok", "message": "", "k_of_means": 1.0, "mean_of_k": 1.0},
                             {"status": "collapse", "message": "h <= 0"}], 1.0)
    assert c["status"] == "collapse" and math.isnan(c["k_of_means"])


def test_stall_between_converged_nodes_is_interpolated(monkeypatch):
    import gearfmu.ehl.transient as tr
    from gearfmu.ehl.errors import EHLConvergenceError

    env = _env(1, nodes=3)
    R_mid = _kin(env, float(np.linspace(env.geom.s_start_m, env.geom.s_end_m, 3)[1]))[0]
    real = tr.solve_line_contact_transient

    def fake(**kw):
        if abs(kw["R_m"] - R_mid) < 1e-15:
            raise EHLConvergenceError("transient step 3 stalled (test)", "pressure_change", 1.0)
        return real(**kw)

    monkeypatch.setattr(tr, "solve_line_contact_transient", fake)
    g = _grid(env, nodes=3)
    assert g.status[0][0, 1] == "stall_interpolated"
    assert g.ratio[0][0, 1] == pytest.approx(0.5 * (g.ratio[0][0, 0] + g.ratio[0][0, 2]), rel=1e-14)
    assert g.summary()["stalled_rough_nodes_interpolated"] == 1


def test_film_parameter_screen():
    # CHOICE (docs/ehl_mesh.md): no Lambda screen in 'film' mode by default; on for 'off'/'correction'
    assert not RoughnessSpec.from_level(4, film_transient="film").screens_film_parameter
    assert RoughnessSpec.from_level(4, film_transient="correction").screens_film_parameter
    assert RoughnessSpec.from_level(4).screens_film_parameter
    assert RoughnessSpec.from_level(4, film_transient="film", film_parameter_screen=True).screens_film_parameter
    # screen on: level 4 requests (Lambda ~2 < 3 at the nominal load, Dowson-Higginson) go to the
    # policy before any solve
    env = _env(1, level=4, film_parameter_screen=True, on_failure="hertz")
    s = np.array([float(env.geom.s_pitch_m)])
    out = rough_ehl_model(env, s, [0], [2000.0 / float(env.geom.rb1_m) / 0.044])
    assert out.solves == 0 and out.failures[0]["status"] == "low_film_parameter"
    assert out.failures[0]["film_parameter"] < 3.0


def test_bad_values_name_the_field():
    with pytest.raises(ContactModelError, match="film_parameter_screen='yes'"):
        RoughnessSpec.from_level(1, film_transient="film", film_parameter_screen="yes")
    with pytest.raises(ContactModelError, match="film_transient='films'"):
        RoughnessSpec.from_level(1, film_transient="films")
    with pytest.raises(ContactModelError, match="film_transient='film'.*position_nodes >= 2"):
        RoughnessSpec.from_level(1, film_transient="film", position_nodes=0)
    text = SCENE.read_text(encoding="utf-8")
    for extra in ('film_transient = "films"', 'film_transient = "film"\nfilm_position_nodes = 0'):
        with pytest.raises(SceneError) as ei:
            load_scene(text + f"\n[roughness]\nlevel = 3\n{extra}\n")
        assert "roughness.film_transient" in str(ei.value)
    sc = load_scene(text + '\n[roughness]\nlevel = 3\nfilm_transient = "film"\n')
    assert environment_from_scene(sc).roughness.film_transient == "film"
