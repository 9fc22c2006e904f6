"""EHL film in the mesh: contact kinematics, contact-model registry, film-stiffness TVMS and the
seed 000 section 5 trends on its Table 1 pair (docs/ehl_mesh.md).

Runtime: the trend tests use coarse tables (4 points per mesh period, 2 face-width slices,
in-process solves) -- the trends, not the converged values, are what seed 000 states.
"""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from gearfmu.contact import reduced_modulus_Pa
from gearfmu.contact_models import (CONTACT_MODELS, ContactModelError, RoughnessSpec, environment_from_scene,
                                    get_contact_model, sliced_mesh_stiffness, tooth_compliances)
from gearfmu.ehl.fits import dowson_higginson_min_film
from gearfmu.ehl.mesh_film import contact_kinematics, solve_slice_film
from gearfmu.geometry import pair_geometry
from gearfmu.precompute import precompute_tables
from gearfmu.scene import SceneError, load_scene
from gearfmu.stiffness import slot_stiffness

ROOT = Path(__file__).resolve().parents[1]
SCENE = load_scene(ROOT / "examples" / "scenes" / "seed000_table1.toml")
GEOM = pair_geometry(SCENE.pair)


def _env(scene=SCENE, **kw):
    kw.setdefault("max_workers", 1)
    return environment_from_scene(scene, **kw)


def test_pitch_point_kinematics_closed_form():
    """At the pitch point the roll lengths are r_w sin(alpha_w) (textbook involute geometry), so
    R = r_w1 r_w2 sin(alpha_w)/(r_w1 + r_w2), u_s = omega1 r_w1 sin(alpha_w), no sliding."""
    w1 = SCENE.operating.speed_rad_s
    R, u, slide = contact_kinematics(GEOM, GEOM.s_pitch_m, w1)
    sa = math.sin(GEOM.alpha_w_rad)
    assert R == pytest.approx(GEOM.rw1_m * GEOM.rw2_m * sa / (GEOM.rw1_m + GEOM.rw2_m), rel=1e-9)
    assert u == pytest.approx(w1 * GEOM.rw1_m * sa, rel=1e-9)
    assert abs(slide) < 1e-9 * u


def test_rolling_speeds_from_rigid_body_velocities():
    """Independent check: velocity omega x r of each gear's material point at the contact,
    projected on the common tangent (normal to the line of action), at A, C and E."""
    w1 = SCENE.operating.speed_rad_s
    w2 = w1 * GEOM.z1 / GEOM.z2
    aw, rb1, rb2 = GEOM.center_distance_m, GEOM.rb1_m, GEOM.rb2_m
    # pinion centre (0,0), gear centre (aw,0); LOA tangent to both base circles
    aa = GEOM.alpha_w_rad
    n_loa = np.array([math.sin(aa), math.cos(aa)])              # unit vector along the LOA, N1 -> N2
    N1 = rb1 * np.array([math.cos(aa), -math.sin(aa)])
    t_hat = np.array([n_loa[1], -n_loa[0]])                     # common tangent
    N2 = N1 + GEOM.loa_length_m * n_loa
    assert np.hypot(N2[0] - aw, N2[1]) == pytest.approx(rb2, rel=1e-9)   # LOA tangent to the gear base circle
    for s in (GEOM.s_start_m, GEOM.s_pitch_m, GEOM.s_end_m):
        Pt = N1 + s * n_loa
        v1 = w1 * np.array([-Pt[1], Pt[0]])                     # pinion turns +omega1
        r2 = Pt - np.array([aw, 0.0])
        v2 = -w2 * np.array([-r2[1], r2[0]])                    # gear turns the other way
        assert abs(v1 @ n_loa - v2 @ n_loa) < 1e-9 * abs(v1 @ n_loa)   # same speed along the LOA
        _, u, slide = contact_kinematics(GEOM, s, w1)
        u1, u2 = abs(v1 @ t_hat), abs(v2 @ t_hat)
        assert u == pytest.approx(0.5 * (u1 + u2), rel=1e-9)
        assert abs(slide) == pytest.approx(abs(u1 - u2), rel=1e-9, abs=1e-9)


def test_hertz_model_is_yang_sun():
    """'hertz': k = pi E* w / 2 with 1/E* = sum (1 - nu^2)/E (Yang & Sun 1985), any load."""
    env = _env()
    res = get_contact_model("hertz").fn(env, [GEOM.s_pitch_m] * 2, [0, 1], [1e5, 3e5])
    Es = 1.0 / (2 * (1 - 0.29 ** 2) / 207e9)
    assert np.allclose(res.k_N_per_m, math.pi * Es * env.width_m / 2.0, rtol=1e-12)
    assert set(CONTACT_MODELS) >= {"hertz", "smooth_ehl", "rough_ehl"}
    with pytest.raises(ContactModelError, match="fractal_mixed|not available"):
        get_contact_model("no_such_model")


def test_sliced_stiffness_with_hertz_equals_tvms_path():
    """The per-slice contact path with the Hertz value reproduces the existing TVMS
    (seed 000 eq 13 with k_l = k_h) of gearfmu.stiffness.slot_stiffness."""
    opts = dataclasses.replace(SCENE.mesh, slices=3)
    ss = slot_stiffness(SCENE.pair, GEOM, opts, None, 16)
    ct, fp, fg = tooth_compliances(SCENE.pair, GEOM, ss.s_m, ss.slice_width_m)
    kh = math.pi * reduced_modulus_Pa(SCENE.pair) * ss.slice_width_m / 2.0
    kc = np.where(np.isfinite(ss.s_m), kh, 0.0)[:, None, :].repeat(3, axis=1)
    k = sliced_mesh_stiffness(ct, fp, fg, kc, opts)
    assert np.allclose(k, ss.k_per_slice_N_per_m[:, None, :], rtol=1e-12, atol=0)


def test_smooth_film_at_pitch_point_against_dowson_higginson():
    """Smooth slice film at the pitch point of the Table 1 pair at 2000 N m: h_min against the
    Dowson-Higginson (1966) formula (independent closed-form fit) within 15 %, and the film
    stiffness equals A B(p_m)/h_m of seed 000 eq 8-9 evaluated by hand from the profiles."""
    env = _env()
    fenv = env.film_environment()
    R, u, _ = contact_kinematics(GEOM, GEOM.s_pitch_m, env.omega1_rad_s)
    w = SCENE.operating.torque_Nm / GEOM.rb1_m / SCENE.pair.pinion.face_width_m
    out, res = solve_slice_film(fenv, float(R), float(u), w, return_result=True)
    assert out.status == "ok"
    E = fenv.E_prime_Pa
    hmin_dh = R * dowson_higginson_min_film(w / (E * R), fenv.eta0_Pas * u / (E * R), fenv.alpha_Pa_inv * E)
    assert out.h_min_m == pytest.approx(hmin_dh, rel=0.15)
    band = np.abs(res.x_m) <= res.b_m
    pm, hm = res.p_Pa[band].mean(), res.h_m[band].mean()
    a = 1 + 11.0
    B = (1 - math.log(1 + pm / 1.83e9 * a) / a) * (1.83e9 + pm * a)      # seed 000 eq 9, B0 = 1.83 GPa, B0' = 11
    assert out.k_N_per_m == pytest.approx(2 * res.b_m * env.width_m * B / hm, rel=2e-3)


def _mean_tvms(model, *, speed_rpm=None, torques=(1000.0, 3000.0), level=1, ppm=4, slices=2):
    sc = SCENE
    if speed_rpm is not None:
        sc = dataclasses.replace(sc, operating=dataclasses.replace(sc.operating,
                                                                   speed_rad_s=speed_rpm * math.pi / 30))
    opts = dataclasses.replace(sc.mesh, contact_model=model, slices=slices)
    sc = dataclasses.replace(sc, mesh=opts)
    kw = {"roughness": RoughnessSpec.from_level(level)} if model == "rough_ehl" else {}
    tab = precompute_tables(sc.pair, opts, points_per_mesh=ppm, torque_axis_Nm=list(torques),
                            nominal_torque_Nm=torques[-1], contact_env=_env(sc, **kw))
    return tab.k_N_per_m.sum(axis=1).mean(axis=1), tab


def test_seed000_trends_fig12_14_15():
    """Seed 000 section 5 on its Table 1 pair (coarse tables):
    Fig. 12: TVMS with the oil film (smooth and rough level 1) above Hertz;
    Fig. 15: TVMS rises with torque (1000 -> 3000 N m);
    Fig. 14: TVMS falls as speed rises (1000 -> 4000 rpm)."""
    kh, _ = _mean_tvms("hertz")
    ks, tab = _mean_tvms("smooth_ehl")
    kr, tab_r = _mean_tvms("rough_ehl", level=1)
    assert np.all(ks > kh * 1.02) and np.all(kr > kh * 1.02)                 # Fig. 12 (Hertz lowest)
    assert ks[1] > ks[0] and kr[1] > kr[0]                                   # Fig. 15
    assert abs(kh[1] - kh[0]) < 1e-9 * kh[0]                                 # Hertz: load-independent
    k_slow, _ = _mean_tvms("smooth_ehl", speed_rpm=1000.0, torques=(3000.0,) * 1)
    k_fast, _ = _mean_tvms("smooth_ehl", speed_rpm=4000.0, torques=(3000.0,) * 1)
    assert k_fast[-1] < k_slow[-1]                                           # Fig. 14
    c = tab.provenance["contact"]
    assert c["model"] == "smooth_ehl" and all(r["load_change"] < 1e-3 for r in c["load_iteration"]["rows"])
    assert tab_r.provenance["contact"]["film_failures"] == 0


def test_rough_film_failure_is_reported_with_position_and_lambda():
    """Level 4 (seed 000 Table 2) at the Table 1 operating point: the full film does not hold
    (docs/ehl.md); with on_failure='error' the error names the position, slice and lambda,
    with 'hertz' the Hertz value is used and the failure recorded."""
    s = [GEOM.s_pitch_m]
    w = [SCENE.operating.torque_Nm / GEOM.rb1_m / SCENE.pair.pinion.face_width_m]
    env = _env(roughness=RoughnessSpec.from_level(4, on_failure="error"))
    env = dataclasses.replace(env, n_slices=2, width_m=22e-3)
    with pytest.raises(ContactModelError, match=r"s = .* mm .*slice 1, film parameter lambda"):
        get_contact_model("rough_ehl").fn(env, s, [1], w)
    env2 = dataclasses.replace(env, roughness=RoughnessSpec.from_level(4), _flanks=env.flanks())
    res = get_contact_model("rough_ehl").fn(env2, s, [1], w)
    kh = CONTACT_MODELS["hertz"].fn(env2, s, [1], w).k_N_per_m
    assert res.fallbacks == 1 and res.k_N_per_m[0] == kh[0]
    f = res.failures[0]
    assert f["slice"] == 1 and f["s_m"] == pytest.approx(s[0]) and 0 < f["film_parameter"] < 10


def test_scene_roughness_keys():
    """[roughness] keys: Table 2 level or D and G (nm), seed, band limit, failure policy."""
    base = (ROOT / "examples" / "scenes" / "seed000_table1.toml").read_text()
    r = load_scene(base + "\n[roughness]\nlevel = 3\nseed = 5\n").roughness
    assert (r.level, r.D, r.G_m, r.seed, r.f_max_per_m) == (3, 1.565, pytest.approx(4.513e-9), 5, 1e4)
    r = load_scene(base + "\n[roughness]\nlevel = 0\nfractal_dimension = 1.5\nG_nm = 2.0\n"
                          "max_frequency_per_mm = 20.0\non_film_failure = \"error\"\n").roughness
    assert (r.D, r.G_m, r.f_max_per_m, r.on_failure) == (1.5, pytest.approx(2e-9), pytest.approx(2e4), "error")
    with pytest.raises(SceneError, match="roughness.G_nm: required"):
        load_scene(base + "\n[roughness]\nlevel = 0\nfractal_dimension = 1.5\n")
    with pytest.raises(SceneError, match="roughness.fractal_dimension: only with"):
        load_scene(base + "\n[roughness]\nlevel = 2\nfractal_dimension = 1.5\n")
    with pytest.raises(SceneError, match="roughness.level"):
        load_scene(base + "\n[roughness]\nlevel = 5\n")
    assert load_scene(base).roughness is None
