"""Rough EHL films converge where the film is full (docs/ehl.md "Rough films").

The cases are film-grid nodes of the default scene's rough-EHL tables (seed 000 Table 1 pair,
its oil at 60 degC, 2000 rpm; the lowest rough load column of the default tables, 8.958e4 N/m)
whose rough films stalled in the multigrid cycles although the film parameter Lambda =
h_min/sigma (Dowson-Higginson h_min, seed 000 Table 2 sigma) is in the full-film range
(Lambda >= 3): level 2, position node 1, slices 0, 12, 28 (Lambda = 5.75) and level 3,
position node 6, slice 8 (Lambda = 3.33, the one that needs the roughness in amplitude steps).

Reference: the discretised equations themselves, re-evaluated in numpy (dense deformation sum
of the exact cell integrals of ln|x|, second-order upstream wedge term, Roelands and
Dowson-Higginson laws written out here), as tests/unit/ehl/test_ehl.py does for smooth films; and the
coupled Newton's Jacobian against finite differences of the solver's own residual kernel.
"""

import numpy as np
import pytest

from gearfmu.contact.models import RoughnessSpec, rough_profile, film_parameter
from gearfmu.scene.physics import environment_from_scene
from gearfmu.contact.rough_ehl import RoughFilmGrid
from gearfmu.ehl.film_newton import _terms, jacobian
from gearfmu.ehl.mesh_film import contact_kinematics, solve_node_films, solve_slice_film
from gearfmu.ehl.solver import solve_line_contact
from gearfmu.scene.reader import load_scene
from gearfmu.assembly.contact_rows import film_failure_kinds, film_failure_line

from support.ehl_checks import discrete_equations_check

W_NODE = 89577.25357541349     # N/m: the lowest rough load column of the default tables


def _env(level):
    import dataclasses
    sc = load_scene(None)
    sc = dataclasses.replace(sc, mesh=dataclasses.replace(sc.mesh, contact_model="rough_ehl", slices=44))
    return environment_from_scene(sc, roughness=RoughnessSpec.from_level(level), max_workers=1)


def _node(env, k, slices):
    s = float(RoughFilmGrid(env, 9).s_nodes[k])
    fenv, fl = env.film_environment(), env.flanks()
    R, u, _ = (float(np.ravel(v)[0]) for v in contact_kinematics(env.geom, np.array([s]), env.omega1_rad_s))
    profs = [rough_profile(env, fenv, fl, s, n, W_NODE, R) for n in slices]
    lam = float(film_parameter(env, np.array([s]), np.array([W_NODE]))[0])
    return fenv, R, u, profs, lam


def _rough_equations_check(r):
    """support.ehl_checks.discrete_equations_check of a rough film (Roelands, compressible): the
    roughness in the gap."""
    return discrete_equations_check(r, roughness=r.roughness_m * r.inputs["R_m"] / r.b_m ** 2)


@pytest.mark.parametrize("level,k,slices", [(2, 1, (0, 12, 28)), (3, 6, (8,))])
def test_full_film_rough_nodes_that_stalled_converge(level, k, slices):
    """Film-grid nodes with Lambda >= 3 whose rough film stalled in the multigrid cycles
    (pressure spikes of 5-10 p_h at roughness crests in the inlet, L = 22): converged now,
    and the result satisfies the discrete equations (tolerances as tests/unit/ehl/test_ehl.py)."""
    env = _env(level)
    fenv, R, u, profs, lam = _node(env, k, slices)
    assert lam >= 3.0
    sm, outs = solve_node_films(fenv, R, u, W_NODE, profs)
    assert sm.status == "ok"
    assert [o.status for o in outs] == ["ok"] * len(slices)
    for prof in profs:
        out, r = solve_slice_film(fenv, R, u, W_NODE, prof, return_result=True)
        assert out.status == "ok" and r.converged
        gap_spread, load_err, scaled = _rough_equations_check(r)
        assert gap_spread < 1e-9
        assert load_err < 1e-5
        assert scaled < 1e-5
        assert out.film_parameter > 0.0 and r.h_min_m > 0.0


def test_coupled_newton_jacobian_equals_finite_differences():
    """dL_i/dP_j and dL_i/dH0 of :func:`gearfmu.ehl.film_newton.jacobian` against central
    differences of the solver's residual kernel at a rough film (level 2, pitch-side node)."""
    env = _env(2)
    fenv, R, u, profs, _ = _node(env, 4, (0,))
    import gearfmu.ehl.iterate as it
    seen = []
    orig = it.coupled_newton

    def spy(solver, *a, **kw):
        seen.append(solver)
        return orig(solver, *a, **kw)
    it.coupled_newton = spy
    try:
        sm = solve_line_contact(R, fenv.E_prime_Pa, W_NODE, u, fenv.eta0_Pas, fenv.alpha_Pa_inv, fenv.rho0_kg_m3)
        solve_line_contact(R, fenv.E_prime_Pa, W_NODE, u, fenv.eta0_Pas, fenv.alpha_Pa_inv, fenv.rho0_kg_m3,
                           roughness_m=profs[0], initial=sm)
    finally:
        it.coupled_newton = orig
    solver = seen[0]
    t, sl = solver.top, solver._sl(solver.top)
    r, eps, dle, rho, drho = _terms(solver)
    J, a = jacobian(solver, eps, dle, rho, drho)
    P = solver.P[sl]
    n = P.size
    cols = [j for j in range(1, n - 1) if P[j] > 1e-3][::9]
    for j in cols:
        h = 1e-6 * P[j]
        solver.P[sl.start + j] += h
        rp = _terms(solver)[0]
        solver.P[sl.start + j] -= 2 * h
        rm = _terms(solver)[0]
        solver.P[sl.start + j] += h
        fd = -(rp - rm)[1:n - 1] / (2 * h)
        np.testing.assert_allclose(J[:, j - 1], fd, rtol=0, atol=1e-6 * np.abs(fd).max())
    h = 1e-7
    solver.H0[t] += h
    rp = _terms(solver)[0]
    solver.H0[t] -= 2 * h
    rm = _terms(solver)[0]
    solver.H0[t] += h
    np.testing.assert_allclose(a, -(rp - rm)[1:n - 1] / (2 * h), rtol=0, atol=1e-6 * np.abs(a).max())


def test_points_without_rough_film_are_counted_by_kind():
    """Mixed lubrication by Lambda (expected) and solver failures at a full-film Lambda
    (defect) are counted apart, each with what replaced it, and the build line names both."""
    spec = RoughnessSpec.from_level(3)
    fails = ([dict(status="low_film_parameter", film_parameter=2.5 + 0.1 * i, used="fractal_mixed")
              for i in range(4)]
             + [dict(status="stall", film_parameter=4.2, used="smooth_ehl"),
                dict(status="collapse", film_parameter=3.1, used="smooth_ehl")])
    c = film_failure_kinds(fails, spec, grid_nodes_interpolated=2)
    m, b = c["film_mixed_lubrication"], c["film_solver_failures"]
    assert m["points"] == 4 and m["used"] == {"fractal_mixed": 4}
    assert m["lambda_range"] == pytest.approx([2.5, 2.8])
    assert b["points"] == 2 and b["by_status"] == {"collapse": 1, "stall": 1}
    assert b["used"] == {"smooth_ehl": 2} and b["grid_nodes_interpolated"] == 2
    line = film_failure_line(c, spec)
    assert "mixed lubrication, expected) at 4 " in line and "solver failure) at 2 points" in line
    assert "2 film-grid nodes stalled" in line
    clean = film_failure_kinds(fails[:4], spec)
    assert clean["film_solver_failures"]["points"] == 0
    assert "solver failure" not in film_failure_line(clean, spec)
    assert film_failure_line(film_failure_kinds([], spec), spec) == ""
