"""[roughness] film_transient = "film" with on_film_failure = "load_sharing": a film-grid node
whose transient film collapses (h <= 0, FilmCollapseError) takes the Johnson-Greenwood-Poon
load-sharing stiffness (gearfmu/contact/load_sharing.py, docs/load_sharing.md), not the smooth film and
not seed 001's fractal K_n (docs/ehl_mesh.md "Transient films in the tables").

The collapse is forced (every transient run raises FilmCollapseError, as
tests/unit/assembly/test_film_transient_tables.py does for one node), so no transient film is solved: the grid
solves only its smooth columns (129 EHL nodes).

References (none produced by the code under test):
* the smooth film at the node: an independent solve_line_contact + seed 000 eq 8 on |x| <= b
  (slice_film_stiffness_N_per_m), to 1e-9 (the grid's log-cubic interpolation is exact at a node);
* JGP limit (docs/load_sharing.md, "k_film ... gamma1 -> 1 returns the solver's film exactly"):
  where the film parameter is large (seed 000 level 1, Lambda ~ 20) the asperity share is 0 and the
  load-sharing stiffness is the smooth film itself (1e-9);
* continuity (docs/load_sharing.md): at seed 000 level 4 (Lambda ~ 2) the film still carries most of
  the load, so Hertz (Yang & Sun, the dry limit) < k < k_smooth and k/k_smooth > 0.9 (the
  measured table of docs/load_sharing.md: 0.981 at the pitch point, 2000 N m); the asperity
  share is > 0 and the value equals gearfmu.contact.load_sharing.load_sharing evaluated here on the
  independent smooth film (1e-9);
* 'hertz' policy at the same collapsed node: the Hertz stiffness exactly.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from gearfmu.contact.models import RoughnessSpec, film_grid, rough_ehl_model
from gearfmu.scene.physics import environment_from_scene

ROOT = Path(__file__).resolve().parents[3]
SCENE = ROOT / "examples" / "scenes" / "seed000_table1.toml"
EHL_NODES = 129


def _env(level, on_failure):
    base = load_scene_cached()
    sc = dataclasses.replace(base, mesh=dataclasses.replace(base.mesh, contact_model="rough_ehl", slices=1))
    spec = RoughnessSpec.from_level(level, position_nodes=3, film_transient="film", on_failure=on_failure)
    return environment_from_scene(sc, roughness=spec, max_workers=1, ehl_nodes=EHL_NODES)


_SCENE = []


def load_scene_cached():
    from gearfmu.scene.reader import load_scene

    if not _SCENE:
        _SCENE.append(load_scene(SCENE))
    return _SCENE[0]


@pytest.fixture
def collapse_everywhere(monkeypatch):
    import gearfmu.ehl.transient as tr
    from gearfmu.ehl.errors import FilmCollapseError

    calls = []

    def fake(**kw):
        calls.append(kw["R_m"])
        raise FilmCollapseError("film collapse at transient step 7 (test): h <= 0", x_m=0.0, h_min_m=-1e-9)

    monkeypatch.setattr(tr, "solve_line_contact_transient", fake)
    return calls


def _independent_smooth_k(env, s, w):
    from gearfmu.ehl.film_stiffness import slice_film_stiffness_N_per_m
    from gearfmu.ehl.mesh_film import contact_kinematics
    from gearfmu.ehl.solver import solve_line_contact

    R, u, _ = [float(np.ravel(v)[0]) for v in contact_kinematics(env.geom, np.array([s]), env.omega1_rad_s)]
    fenv = env.film_environment()
    sm = solve_line_contact(R, fenv.E_prime_Pa, w, u, fenv.eta0_Pas, fenv.alpha_Pa_inv, fenv.rho0_kg_m3,
                            n_nodes=EHL_NODES)
    return slice_film_stiffness_N_per_m(sm, fenv.width_m, "seed", fenv.B0_Pa, fenv.B0_prime), R, u


def _collapsed_request(level, on_failure):
    """The middle node of a 3-position grid at one of its load nodes; every transient run collapses."""
    env = _env(level, on_failure)
    g = film_grid(env)
    s = float(g.s_nodes[1])
    j = int(np.floor(g._jpos(2000.0 / float(env.geom.rb1_m) / 0.044)))   # the column of ~2000 N m
    w = float(g.w_node(j))
    out = rough_ehl_model(env, [s], [0], [w])
    return env, g, s, w, out


def test_collapsed_node_takes_load_sharing_between_hertz_and_smooth(collapse_everywhere):
    from gearfmu.gear.hertz import hertz_stiffness_N_per_m
    from gearfmu.contact.models import film_parameter
    from gearfmu.contact.load_sharing import LineContactState, asperity_parameters, load_sharing, wm_spectral_moments

    env, g, s, w, out = _collapsed_request(4, "load_sharing")
    assert collapse_everywhere, "the forced collapse must have been reached through the transient runs"
    assert [f["status"] for f in out.failures] == ["collapse"]
    assert out.failures[0]["used"] == "load_sharing"
    ft = g.summary()["film_transient"]
    assert ft["failed_nodes_by_status"] == {"collapse": ft["failed_nodes"]} and ft["failed_nodes"] >= 3
    k = float(out.k_N_per_m[0])
    k_smooth, R, u = _independent_smooth_k(env, s, w)
    fenv = env.film_environment()
    st = LineContactState(R_m=R, u_m_per_s=u, w_N_per_m=w, E_prime_Pa=fenv.E_prime_Pa,
                          eta0_Pas=float(env.eta0_Pas), alpha_Pa_inv=float(env.alpha_Pa_inv),
                          width_m=float(env.width_m))
    ref = load_sharing(st, asperity_parameters(wm_spectral_moments(env.roughness.D, env.roughness.G_m)),
                       k_smooth_N_per_m=k_smooth)
    assert k == pytest.approx(ref.k_N_per_m, rel=1e-9)
    k_hertz = hertz_stiffness_N_per_m(env.pair, env.width_m)
    lam = float(film_parameter(env, np.array([s]), np.array([w]))[0])
    assert lam < 3.0                                   # level 4: below Tallian's full-film limit
    assert k_hertz < k < k_smooth                      # between the dry limit and the smooth film
    assert k / k_smooth > 0.9                          # continuity: the film carries most of the load
    # and not the default policy's value (seed 001 K_n ~ 7x the film, docs/load_sharing.md)
    env.roughness = dataclasses.replace(env.roughness, on_failure="fractal_mixed")
    k_fm = float(rough_ehl_model(env, [s], [0], [w]).k_N_per_m[0])
    assert k_fm > 2.0 * k_smooth
    # 'hertz' at the same collapsed node: Hertz exactly
    env.roughness = dataclasses.replace(env.roughness, on_failure="hertz")
    assert float(rough_ehl_model(env, [s], [0], [w]).k_N_per_m[0]) == k_hertz


def test_collapsed_node_at_large_film_parameter_is_the_smooth_film(collapse_everywhere):
    from gearfmu.contact.models import film_parameter

    # JGP limit: asperity share -> 0 as Lambda grows; level 1 (Lambda ~ 20) -> the smooth film itself
    env, g, s, w, out = _collapsed_request(1, "load_sharing")
    assert [f["status"] for f in out.failures] == ["collapse"]
    assert float(film_parameter(env, np.array([s]), np.array([w]))[0]) > 10.0
    k_smooth, _, _ = _independent_smooth_k(env, s, w)
    assert float(out.k_N_per_m[0]) == pytest.approx(k_smooth, rel=1e-9)
