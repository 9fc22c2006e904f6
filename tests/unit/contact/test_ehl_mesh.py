"""EHL film in the mesh: contact kinematics, contact-model registry, film-stiffness TVMS and the
seed 000 section 5 trends on its Table 1 pair (docs/ehl_mesh.md).

The trend tests use coarse tables (4 points per mesh period, 2 face-width slices,
in-process solves) -- the trends, not the converged values, are what seed 000 states.
"""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from gearfmu.gear.hertz import reduced_modulus_Pa
from gearfmu.contact.models import (CONTACT_MODELS, ContactModelError, RoughnessSpec, get_contact_model,
                                    sliced_mesh_stiffness, tooth_compliances)
from gearfmu.scene.physics import environment_from_scene
from gearfmu.ehl.fits import dowson_higginson_min_film
from gearfmu.ehl.mesh_film import contact_kinematics, solve_slice_film
from gearfmu.gear.geometry import pair_geometry
from gearfmu.assembly.precompute import precompute_tables
from gearfmu.scene.reader import SceneError, load_scene
from gearfmu.gear.stiffness import slot_stiffness

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[3]
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
    assert set(CONTACT_MODELS) >= {"hertz", "smooth_ehl", "rough_ehl", "fractal_mixed"}
    with pytest.raises(ContactModelError, match="fractal_mixed|not available"):
        get_contact_model("no_such_model")


def test_sliced_stiffness_with_hertz_equals_tvms_path():
    """The per-slice contact path with the Hertz value reproduces the existing TVMS
    (seed 000 eq 13 with k_l = k_h) of gearfmu.gear.stiffness.slot_stiffness."""
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
    kw = {"roughness": RoughnessSpec.from_level(level, position_nodes=5)} if model == "rough_ehl" else {}
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


def _pitch_request():
    s = [GEOM.s_pitch_m]
    w = [SCENE.operating.torque_Nm / GEOM.rb1_m / SCENE.pair.pinion.face_width_m]
    return s, w


def _hand_film_parameter(level: int, w: float) -> float:
    """Lambda = h_min/sigma at the pitch point by hand: R, u_s from the pitch-point closed forms
    (R = r_w1 r_w2 sin(alpha_w)/(r_w1 + r_w2), u_s = omega1 r_w1 sin(alpha_w)); h_min from the
    Dowson & Higginson (1966) formula h_min/R = 2.65 U^0.70 G^0.54 W^-0.13; sigma of each flank the
    RMS of the full W-M sum, G^(D-1) L_s^(2-D) sqrt(1/(2 (1 - gamma^(-2(2-D))))) (L_s = 0.5 mm,
    gamma = 1.5: the docs/ehl.md convention), composite sigma = sqrt(2) x that."""
    from gearfmu.contact.roughness import SEED000_LEVELS

    lv = SEED000_LEVELS[level]
    sa = math.sin(GEOM.alpha_w_rad)
    R = GEOM.rw1_m * GEOM.rw2_m * sa / (GEOM.rw1_m + GEOM.rw2_m)
    u = SCENE.operating.speed_rad_s * GEOM.rw1_m * sa
    E1 = 207e9 / (1 - 0.29 ** 2)
    Ep = 2.0 / (1 / E1 + 1 / E1)                                    # E' = 2 / sum (1 - nu^2)/E
    eta0, alpha = SCENE.lubricant.dynamic_viscosity_Pas, 20e-9
    h = R * 2.65 * (eta0 * u / (Ep * R)) ** 0.70 * (alpha * Ep) ** 0.54 * (w / (Ep * R)) ** -0.13
    sig1 = lv.G_m ** (lv.D - 1) * 0.5e-3 ** (2 - lv.D) * math.sqrt(0.5 / (1 - 1.5 ** (-2 * (2 - lv.D))))
    return h / (math.sqrt(2.0) * sig1)


def test_film_parameter_against_hand_value_and_the_switch():
    """Lambda = h_min/sigma (Dowson-Higginson, composite W-M sigma) equals the hand value at the
    pitch point; level 1 (Lambda ~ 22) keeps the film, level 4 (Lambda ~ 2.2 < 3, the mixed range
    of Tallian 1967) switches to the policy without a film solve, recorded with its Lambda."""
    from gearfmu.contact.models import film_parameter

    s, w = _pitch_request()
    for level in (1, 4):
        env = _env(roughness=RoughnessSpec.from_level(level))
        lam = film_parameter(env, s, w)[0]
        assert lam == pytest.approx(_hand_film_parameter(level, w[0]), rel=1e-9)
    assert _hand_film_parameter(1, w[0]) > 15 and 1.5 < _hand_film_parameter(4, w[0]) < 3.0
    env = dataclasses.replace(_env(roughness=RoughnessSpec.from_level(4, on_failure="hertz")), n_slices=2,
                              width_m=22e-3)
    res = get_contact_model("rough_ehl").fn(env, s, [1], w)
    kh = CONTACT_MODELS["hertz"].fn(env, s, [1], w).k_N_per_m
    assert res.solves == 0 and res.fallbacks == 1 and res.k_N_per_m[0] == kh[0]
    f = res.failures[0]
    assert (f["status"], f["slice"], f["used"]) == ("low_film_parameter", 1, "hertz")
    assert f["film_parameter"] == pytest.approx(_hand_film_parameter(4, w[0]), rel=1e-9)


def test_film_failure_error_names_position_slice_and_lambda():
    """on_film_failure = 'error': ContactModelError with the LOA position in mm, the slice and Lambda
    (hand value of the test above)."""
    s, w = _pitch_request()
    env = dataclasses.replace(_env(roughness=RoughnessSpec.from_level(4, on_failure="error")), n_slices=2,
                              width_m=22e-3)
    lam = _hand_film_parameter(4, w[0])
    with pytest.raises(ContactModelError) as ei:
        get_contact_model("rough_ehl").fn(env, s, [1], w)
    msg = str(ei.value)
    assert f"s = {s[0] * 1e3:.4f} mm" in msg and "slice 1," in msg and f"lambda = h_min/sigma = {lam:.3g}" in msg
    with pytest.raises(ContactModelError, match="on_failure='bogus'"):
        RoughnessSpec.from_level(4, on_failure="bogus")
    with pytest.raises(ContactModelError, match="position_nodes=1"):
        RoughnessSpec.from_level(1, position_nodes=1)


def test_mixed_stiffness_lies_between_solid_part_and_solid_plus_whole_band_film():
    """'fractal_mixed' where Lambda < 3 (level 4): K_n = K_s + K_l is finite, above the dry solid
    part K_s alone (seed 001 eq 16-25 at the same load, evaluated separately) and below K_s plus an
    oil film over the whole Hertz band, B(p_m) 2b width / h_c (seed 000 eq 8-9, B by hand with
    B0 = 1.83 GPa, B0' = 11, h_c Pan & Hamrock 1989): the asperity area only removes film."""
    from gearfmu.contact import fractal as fc
    from gearfmu.ehl.fits import pan_hamrock_films

    s, w = _pitch_request()
    env = _env(roughness=RoughnessSpec.from_level(4, position_nodes=0))     # 44 slices of 1 mm
    res = get_contact_model("rough_ehl").fn(env, s, [0], w)
    k = res.k_N_per_m[0]
    assert res.failures[0]["used"] == "fractal_mixed" and math.isfinite(k)
    R, u, _ = contact_kinematics(GEOM, s[0], env.omega1_rad_s)
    Es = reduced_modulus_Pa(SCENE.pair)
    b = math.sqrt(4 * w[0] * R / (math.pi * Es))                    # Hertz half-width (Johnson 1985)
    A0 = 2 * b * env.width_m
    lv = RoughnessSpec.from_level(4)
    mo = fc.FractalMeshOptions()
    from gearfmu.contact.roughness import wm_sigma_m
    lam_c = fc.contact_correction_coefficient(R, w[0], Es, wm_sigma_m(lv.D, lv.G_m, mo.L_s_m), mo.L_s_m)
    opts = fc.FractalOptions(lateral=mo.options.lateral, interaction=mo.options.interaction, lambda_c=lam_c)
    Ks = fc.solid_contact_at_load(fc.FractalSurface(lv.D, lv.G_m), fc.FractalMaterial(Es, mo.H_Pa,
                                  friction=mo.friction), w[0] * env.width_m, A0, opts).stiffness_N_per_m
    Ep = 2 * Es
    _, hc = pan_hamrock_films(w[0] / (Ep * R), env.eta0_Pas * u / (Ep * R), env.alpha_Pa_inv * Ep)
    pm = w[0] / (2 * b)
    a = 1 + 11.0
    B = (1 - math.log(1 + pm / 1.83e9 * a) / a) * (1.83e9 + pm * a)
    assert Ks < k <= Ks + B * A0 / (hc * R) * (1 + 1e-9)


def test_film_grid_against_every_position_solve():
    """The film grid (films at a few contact positions x load nodes, interpolated) against the direct
    rough solve at every requested position (an independent run of the solver at each point), level 1,
    2 slices, loads 0.6/1.1 x nominal: film stiffness within 3 % (measured RMS 0.6 %, docs/ehl_mesh.md)."""
    env0 = dataclasses.replace(_env(roughness=RoughnessSpec.from_level(1, position_nodes=0)), n_slices=2,
                               width_m=22e-3)
    s = np.linspace(GEOM.s_start_m + 1e-4, GEOM.s_end_m - 1e-4, 6)
    S = np.repeat(s, 2)
    N = np.tile([0, 1], s.size)
    W = env0.film_load_anchor_N_per_m * np.where(np.arange(S.size) % 3 == 0, 0.6, 1.1)
    ref = get_contact_model("rough_ehl").fn(env0, S, N, W)
    env = dataclasses.replace(env0, roughness=RoughnessSpec.from_level(1, position_nodes=9), _grid=None)
    res = get_contact_model("rough_ehl").fn(env, S, N, W)
    # a grid node whose rough solve stalls (the solver's limit, docs/ehl.md) takes its requests
    # to the failure policy; compare where both runs have a film
    bad = {(f["s_m"], f["slice"]) for f in ref.failures + res.failures}
    ok = np.array([(float(f"{a:.10g}"), int(b)) not in bad for a, b in zip(S, N)])
    assert ok.sum() >= 8
    assert np.max(np.abs(res.k_N_per_m[ok] / ref.k_N_per_m[ok] - 1)) < 0.03
    solves = res.solves
    res2 = get_contact_model("rough_ehl").fn(env, S, N, W * 1.01)        # next pass: the grid is reused
    assert res2.solves == 0 and solves == env._grid.solves


def test_tiny_rough_scene_mixes_film_and_mixed_model_and_the_fmu_runs(tmp_path):
    """A tiny rough-EHL scene (2 slices, 8 points per mesh, level 2 with full_film_parameter = 5 so
    that part of the path switches): the tables build, record the switch (count, Lambda range, one
    warning), and the FMU runs with a finite mesh force whose mean over whole mesh periods equals
    the applied load T1/Rb1 within 2 % (seed 003, below eq 2: balanced torques)."""
    from gearfmu.fmu.compare import output_names, run_fmu
    from gearfmu.pipeline import build

    base = (ROOT / "examples" / "scenes" / "seed000_table1.toml").read_text()
    text = (base.replace('contact_model = "hertz"', 'contact_model = "rough_ehl"')
            .replace("slices = 44 ", "slices = 2 ").replace("points_per_mesh = 64", "points_per_mesh = 8")
            + "\n[roughness]\nlevel = 2\nfull_film_parameter = 5.0\nfilm_position_nodes = 5\n")
    scene = load_scene(text)
    assert scene.mesh.slices == 2 and scene.roughness.position_nodes == 5
    with pytest.warns(UserWarning, match=r"film parameter below 5 .* fractal mixed"):
        tables = precompute_tables(scene.pair, scene.mesh, points_per_mesh=8, torque_axis_Nm=None,
                                   nominal_torque_Nm=scene.operating.torque_Nm,
                                   contact_env=environment_from_scene(scene, max_workers=1))   # in-process
    res = build(scene, tmp_path / "rough.fmu", tables=tables)
    c = res.tables.provenance["contact"]
    assert c["film_failures_by_status"].get("low_film_parameter", 0) > 0
    assert c["film_grid"]["position_nodes"] == 5 and c["solves"] > 0          # part of the path kept the film
    lam = [f["film_parameter"] for f in c["film_failures_first"] if f["status"] == "low_film_parameter"]
    assert lam and max(lam) < 5.0
    tab = res.tables
    period = tab.mesh_period_rad / scene.operating.speed_rad_s
    run = run_fmu(res.fmu_path, stop_time_s=20 * period, comm_step_s=period / 50, names=output_names(tab.slots))
    f = np.asarray(run.columns["mesh_force"])
    assert np.all(np.isfinite(f))
    F = scene.operating.torque_Nm / tab.base_radius_pinion_m
    assert np.mean(f[-500:]) == pytest.approx(F, rel=0.02)


def test_scene_roughness_keys():
    """[roughness] keys: Table 2 level or D and G (nm), seed, band limit, failure policy."""
    base = (ROOT / "examples" / "scenes" / "seed000_table1.toml").read_text()
    r = load_scene(base + "\n[roughness]\nlevel = 3\nseed = 5\n").roughness
    assert (r.level, r.D, r.G_m, r.seed, r.f_max_per_m) == (3, 1.565, pytest.approx(4.513e-9), 5, 1e4)
    assert (r.on_failure, r.full_film_parameter, r.position_nodes) == ("fractal_mixed", 3.0, 9)
    env = environment_from_scene(load_scene(base + "\n[roughness]\nlevel = 2\non_film_failure = \"hertz\"\n"
                                            "full_film_parameter = 2.5\nfilm_position_nodes = 0\n"))
    assert (env.roughness.on_failure, env.roughness.full_film_parameter, env.roughness.position_nodes) == \
        ("hertz", 2.5, 0)
    with pytest.raises(SceneError, match="roughness.film_position_nodes"):
        load_scene(base + "\n[roughness]\nfilm_position_nodes = 1\n")
    with pytest.raises(SceneError, match="roughness.on_film_failure"):
        load_scene(base + "\n[roughness]\non_film_failure = \"mixed\"\n")
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


def test_stalled_grid_node_takes_the_linear_trend_of_its_converged_neighbours():
    """Stall replacement rule of the film grid (fill_stalled_ratio, docs/ehl_mesh.md): reference
    = the ratio written down by hand on a tiny row.  Converged nodes follow r(s) = 1.02 - 3 s
    (s in m), so an interior stalled node with converged nodes on both sides within 3 spacings
    gets exactly 1.02 - 3 s_k; an end node the value of its converged neighbour; a run of
    stalled nodes wider than 3 spacings, a collapse (not a solver limit) and an end node whose
    neighbour also failed stay NaN (the policy's smooth film then applies)."""
    from gearfmu.contact.models import fill_stalled_ratio

    s = np.linspace(0.01, 0.02, 11)                       # spacing 1 mm
    r = 1.02 - 3.0 * s
    expected = r.copy()
    stall = np.zeros(11, bool)
    stall[[0, 3, 4, 7, 8, 9]] = True                       # 0: end; 3-4: gap of 3; 7-9: gap of 4
    collapse = 5
    r_in = r.copy()
    r_in[stall] = np.nan
    r_in[collapse] = np.nan
    # node 5 collapsed -> 3-4 now lie between converged 2 and 6 (4 spacings): not filled
    out, filled = fill_stalled_ratio(s, r_in, stall)
    assert list(np.nonzero(filled)[0]) == [0]
    assert out[0] == pytest.approx(expected[1], abs=1e-15)
    assert np.all(np.isnan(out[[3, 4, 5, 7, 8, 9]]))
    # without the collapse: 3 and 4 between converged 2 and 5 (3 spacings) -> the hand values
    r_in[collapse] = r[collapse]
    out, filled = fill_stalled_ratio(s, r_in, stall)
    assert list(np.nonzero(filled)[0]) == [0, 3, 4]
    assert out[3] == pytest.approx(1.02 - 3.0 * 0.013, abs=1e-12)
    assert out[4] == pytest.approx(1.02 - 3.0 * 0.014, abs=1e-12)
    assert np.all(np.isnan(out[[7, 8, 9]]))                # 6 and 10 are 4 spacings apart
    assert np.array_equal(out[~stall], r_in[~stall])      # converged nodes untouched
    # the last two nodes stalled: the end node's neighbour failed and node 9 has no converged
    # node on its right, so neither is filled
    r2 = r.copy()
    r2[[9, 10]] = np.nan
    st2 = np.zeros(11, bool)
    st2[[9, 10]] = True
    out2, filled2 = fill_stalled_ratio(s, r2, st2)
    assert not np.any(filled2) and np.all(np.isnan(out2[[9, 10]]))
    with pytest.raises(ContactModelError, match="shape"):
        fill_stalled_ratio(s, r[:5], stall)
