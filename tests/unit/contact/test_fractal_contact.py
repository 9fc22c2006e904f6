"""Fractal mixed-lubrication contact stiffness (seed 001), gearfmu/contact/fractal.py.

References: closed forms of Majumdar & Bhushan (1991) and Jiang et al. (2010,
J. Tribol. 132, 011401) for the elastic stage; Kogut & Etsion (2002) stage fits
integrated here with scipy.integrate.quad (independent of the model's
Gauss-Legendre sums); Hertz sphere and line-contact closed forms (Johnson,
Contact Mechanics, 1985); and the trends stated in seed 001 section 4.
"""
import math

import numpy as np
import pytest
from scipy.integrate import quad

from gearfmu.contact import fractal as fc

E = 2.26e11          # seed 001 Table 1 effective modulus (Pa)
H = 6.4e9            # Pa
MAT = fc.FractalMaterial(E, H, friction=0.12)
A0 = 1e-6            # m^2


def _n(a, lam, D, al):
    """Majumdar-Bhushan size distribution with seed 001's lambda_c factor."""
    return lam * 0.5 * D * al ** (D / 2) * a ** (-(D + 2) / 2)


def _quad_log(f, lo, hi):
    """integral_lo^hi f(a) da in ln a (scipy quad, tight tolerance)."""
    v, _ = quad(lambda u: f(math.exp(u)) * math.exp(u), math.log(lo), math.log(hi),
                epsabs=0.0, epsrel=1e-11, limit=200)
    return v


# ------------------------------------------------------------ closed forms
def test_elastic_stage_matches_majumdar_bhushan_and_jiang_closed_forms():
    """Elastic stage, positive contact, no interaction: load by quad of MB 1991's
    F_e = 4 E G^(D-1) a^((3-D)/2) / (3 sqrt(pi)) and stiffness against Jiang et al.'s
    closed form K_e = 2 lam E D/((D-1) sqrt(pi)) a_l^(D/2) (a_c^((1-D)/2) - a_l^((1-D)/2))."""
    D, G, lam = 1.45, 3e-9, 0.7
    surf = fc.FractalSurface(D, G)
    ac = fc.critical_area_m2(surf, MAT)
    al = 200.0 * ac
    r = fc.solid_contact(surf, MAT, al, A0, fc.FractalOptions(lambda_c=lam))
    Fe = lambda a: 4 * E * G ** (D - 1) * a ** ((3 - D) / 2) / (3 * math.sqrt(math.pi))
    P_ref = _quad_log(lambda a: Fe(a) * _n(a, lam, D, al), ac, al)
    K_ref = 2 * lam * E * D / ((D - 1) * math.sqrt(math.pi)) * al ** (D / 2) * (
        ac ** ((1 - D) / 2) - al ** ((1 - D) / 2))
    A_ref = _quad_log(lambda a: a * _n(a, lam, D, al), ac, al)
    assert r.stage_load_N[0] == pytest.approx(P_ref, rel=1e-9)
    assert r.stage_stiffness_N_per_m[0] == pytest.approx(K_ref, rel=1e-9)
    assert r.stage_area_m2[0] == pytest.approx(A_ref, rel=1e-9)


def test_critical_area_is_where_hertz_mean_pressure_reaches_1p1_kmu_Y():
    """At a_c the MB elastic mean pressure F_e/a equals 1.1 k_mu Y (seed 001 eq 10),
    k_mu = 1 - 0.228 mu; the ep/plastic limits are 6^(1/(1-D)) and 110^(1/(1-D)) a_c."""
    D, G = 1.38, 5e-9
    surf = fc.FractalSurface(D, G)
    ac, aepc, apc = fc.stage_areas_m2(surf, MAT)
    p = 4 * E * G ** (D - 1) * ac ** ((1 - D) / 2) / (3 * math.sqrt(math.pi))
    assert p == pytest.approx(1.1 * (1 - 0.228 * 0.12) * H / 2.8, rel=1e-12)
    assert aepc == pytest.approx(6 ** (1 / (1 - D)) * ac, rel=1e-12)
    assert apc == pytest.approx(110 ** (1 / (1 - D)) * ac, rel=1e-12)


def test_all_four_stages_against_kogut_etsion_by_quadrature():
    """Positive contact, no interaction: each stage's load, stiffness and area
    against scipy quad of the Kogut-Etsion fits written out here (omega =
    (a_c/a)^(D-1), Ac = a/omega, Pc = p_c Ac, delta = G^(D-1) a^((2-D)/2)) and
    the plastic stage against the closed form 2 H lam D/(2-D) a_l^(D/2) a_pc^((2-D)/2)."""
    D, G, lam = 1.42, 6e-9, 0.9
    surf = fc.FractalSurface(D, G)
    ac, aepc, apc = fc.stage_areas_m2(surf, MAT)
    al = 3.0 * ac
    pc = 1.1 * (1 - 0.228 * 0.12) * H / 2.8
    r = fc.solid_contact(surf, MAT, al, A0, fc.FractalOptions(lambda_c=lam))
    n = lambda a: _n(a, lam, D, al)
    om = lambda a: (ac / a) ** (D - 1)
    dl = lambda a: G ** (D - 1) * a ** ((2 - D) / 2)
    for j, (c, e, ca, ea, lo, hi) in ((1, (1.03, 1.425, 0.93, 1.136, aepc, ac)),
                                      (2, (1.40, 1.263, 0.94, 1.146, apc, aepc))):
        P = _quad_log(lambda a: c * pc * a / om(a) * om(a) ** e * n(a), lo, hi)
        K = _quad_log(lambda a: c * e * pc * (a / om(a)) / (dl(a) / om(a)) * om(a) ** (e - 1) * n(a), lo, hi)
        A = _quad_log(lambda a: ca * a / om(a) * om(a) ** ea * n(a), lo, hi)
        assert r.stage_load_N[j] == pytest.approx(P, rel=1e-9)
        assert r.stage_stiffness_N_per_m[j] == pytest.approx(K, rel=1e-9)
        assert r.stage_area_m2[j] == pytest.approx(A, rel=1e-9)
    Pp = 2 * H * lam * D / (2 - D) * al ** (D / 2) * apc ** ((2 - D) / 2)
    assert r.stage_load_N[3] == pytest.approx(Pp, rel=1e-10)
    assert r.stage_stiffness_N_per_m[3] == 0.0


def test_asperity_response_hertz_and_kogut_etsion_values():
    """Hertz sphere (Johnson 1985): P = 4/3 E R^1/2 w^3/2, A = pi R w, k = 2 E sqrt(R w);
    at omega = 3 and 50 the KE fits 1.03 w^1.425 and 1.40 w^1.263 times Pc."""
    R, pc = 1e-5, 2e9
    beta = (3 * math.pi * pc / (4 * E)) ** 2
    wc = beta * R
    P, A, k, st = fc.asperity_response(np.array([R] * 4), np.array([0.5 * wc, 3 * wc, 50 * wc, 200 * wc]),
                                       E, pc, H)
    assert P[0] == pytest.approx(4 / 3 * E * math.sqrt(R) * (0.5 * wc) ** 1.5, rel=1e-12)
    assert k[0] == pytest.approx(2 * E * math.sqrt(R * 0.5 * wc), rel=1e-12)
    # Hertz mean pressure at w_c is p_c by construction of beta
    assert (4 / 3 * E * math.sqrt(R) * wc ** 1.5) / (math.pi * R * wc) == pytest.approx(pc, rel=1e-12)
    Pc = pc * math.pi * R * wc
    assert P[1] == pytest.approx(1.03 * Pc * 3 ** 1.425, rel=1e-12)
    assert P[2] == pytest.approx(1.40 * Pc * 50 ** 1.263, rel=1e-12)
    assert P[3] == pytest.approx(H * 2 * math.pi * R * 200 * wc, rel=1e-12)
    assert list(st) == [0, 1, 2, 3]
    # stiffness = dP/dw inside each stage (central differences)
    for w in (0.5 * wc, 3 * wc, 50 * wc):
        h = 1e-6 * w
        Pp = fc.asperity_response(np.array([R]), np.array([w + h]), E, pc, H)[0][0]
        Pm = fc.asperity_response(np.array([R]), np.array([w - h]), E, pc, H)[0][0]
        kk = fc.asperity_response(np.array([R]), np.array([w]), E, pc, H)[2][0]
        assert kk == pytest.approx((Pp - Pm) / (2 * h), rel=1e-6)


def test_load_inversion_reproduces_the_load():
    surf = fc.FractalSurface(1.45, 8e-9)
    r = fc.solid_contact_at_load(surf, MAT, 25.0, A0, fc.SEED001_FULL)
    assert r.load_N == pytest.approx(25.0, rel=1e-9)


# ------------------------------------------------------------ seed 001 trends
def _K_at_area(surf, opts, Astar):
    from scipy.optimize import brentq

    f = lambda u: fc.solid_contact(surf, MAT, math.exp(u), A0, opts).real_area_m2 / A0 - Astar
    u = brentq(f, math.log(1e-30), math.log(10 * A0), xtol=1e-12)
    return fc.solid_contact(surf, MAT, math.exp(u), A0, opts).stiffness_N_per_m


@pytest.mark.parametrize("Astar", [0.01, 0.1, 0.3])
def test_fig9_Ks_grows_with_D_and_falls_with_G(Astar):
    """Seed 001 Fig. 9 / section 4.3: at a given real contact area K_s is larger for
    larger D (G fixed) and smaller for larger G (D fixed)."""
    opts = fc.SEED001_FULL
    kD = [_K_at_area(fc.FractalSurface(D, 8e-9), opts, Astar) for D in (1.40, 1.45, 1.50)]
    kG = [_K_at_area(fc.FractalSurface(1.45, G), opts, Astar) for G in (2e-9, 8e-9, 3e-8)]
    assert kD[0] < kD[1] < kD[2]
    assert kG[0] > kG[1] > kG[2]


def test_fig12_lateral_contact_and_interaction():
    """Seed 001 Fig. 12 / section 4.5 / abstract: with lateral contact and interaction K_s
    is lower (here at a given real contact area), and their influence on K_s at a given
    load decreases with D and increases with G (|K_full/K_positive - 1|)."""
    for D, G in ((1.40, 2e-9), (1.48, 2e-9), (1.40, 8e-9)):
        s = fc.FractalSurface(D, G)
        for Astar in (0.1, 0.3):
            assert _K_at_area(s, fc.SEED001_FULL, Astar) < _K_at_area(s, fc.FractalOptions(), Astar)

    def influence(D, G, P):
        s = fc.FractalSurface(D, G)
        k1 = fc.solid_contact_at_load(s, MAT, P, A0, fc.SEED001_FULL).stiffness_N_per_m
        k0 = fc.solid_contact_at_load(s, MAT, P, A0, fc.FractalOptions()).stiffness_N_per_m
        return abs(k1 / k0 - 1.0)

    for P in (1.0, 10.0):
        assert influence(1.40, 2e-9, P) > influence(1.48, 2e-9, P)    # Fig. 12a: D 1.40 vs 1.48
        assert influence(1.40, 8e-9, P) > influence(1.40, 2e-9, P)    # Fig. 12b: G 8 vs 2 (x1e-9 m)


def test_interaction_alone_lowers_Ks_and_leaves_load_and_area():
    s = fc.FractalSurface(1.45, 5e-9)
    al = 1e-3 * A0
    r0 = fc.solid_contact(s, MAT, al, A0, fc.FractalOptions())
    r1 = fc.solid_contact(s, MAT, al, A0, fc.FractalOptions(interaction=True))
    assert r1.load_N == r0.load_N and r1.real_area_m2 == r0.real_area_m2
    assert r1.stiffness_N_per_m < r0.stiffness_N_per_m


def test_fig8_lambda_c_properties():
    """Seed 001 Fig. 8 / section 4.2: lambda_c < 1, rising with the curvature radius
    (-> 1 for flat surfaces, -> 0 for rho -> 0), > 0 at zero load and rising with load."""
    sig, ell = 0.2e-6, 0.5e-3
    rhos = [1e-5, 1e-3, 1e-2, 5e-2, 1.0, 1e3]
    lr = [fc.contact_correction_coefficient(r, 3e5, E, sig, ell) for r in rhos]
    assert all(0 < v < 1 for v in lr)
    assert all(b > a for a, b in zip(lr, lr[1:]))
    assert lr[0] < 0.02 and lr[-1] > 0.99
    loads = [0.0, 1e4, 1e5, 3e5, 1e6, 3e6]
    lf = [fc.contact_correction_coefficient(0.02, w, E, sig, ell) for w in loads]
    assert lf[0] > 0 and all(b > a for a, b in zip(lf, lf[1:])) and lf[-1] < 1


def test_hertz_gap_closed_form():
    """Gap outside a Hertz line contact (Johnson 1985): zero at the band edge, slope
    (b/rho) sqrt(X^2-1), and x^2/(2 rho) - (b^2/(2 rho))(1/2 + ln 2X) far away."""
    b, rho = 2e-4, 0.02
    assert fc.line_contact_gap_m(b, b, rho) == pytest.approx(0.0, abs=1e-30)
    x = 3.7 * b
    h = 1e-9
    slope = (fc.line_contact_gap_m(x + h, b, rho) - fc.line_contact_gap_m(x - h, b, rho)) / (2 * h)
    assert slope == pytest.approx(b / rho * math.sqrt(3.7 ** 2 - 1), rel=1e-6)
    X = 400.0
    far = X * X * b * b / (2 * rho) - b * b / (2 * rho) * (0.5 + math.log(2 * X))
    assert fc.line_contact_gap_m(X * b, b, rho) == pytest.approx(far, rel=1e-9)
    assert fc.hertz_half_width_m(rho, 3e5, E) == pytest.approx(math.sqrt(4 * 3e5 * rho / (math.pi * E)))


def test_fig10_oil_film_dominates_small_area_solid_dominates_large():
    """Seed 001 Fig. 10 (D = 1.45): K_l dominates K_n at small A_r*, K_s at large A_r*;
    K_l falls as A_r* grows.  K_l = B (A0 - A_r)/h with the Tait bulk modulus (seed 000 eq 8-9)."""
    s = fc.FractalSurface(1.45, 8e-9)
    h = 0.5e-6
    ks, kl = [], []
    for Astar in (0.001, 0.01, 0.3, 0.6):
        ks.append(_K_at_area(s, fc.SEED001_FULL, Astar))
        kl.append(fc.oil_film_stiffness_N_per_m(A0, Astar * A0, h))
    assert kl[0] > 10 * ks[0]
    assert ks[-1] > kl[-1]
    assert all(b < a for a, b in zip(kl, kl[1:]))
    assert kl[0] == pytest.approx(870.0 * 1450.0 ** 2 * 0.999 * A0 / h, rel=1e-12)  # B0 = rho c^2 at p = 0


# ------------------------------------------------------------ input checks, mesh model
@pytest.mark.parametrize("make, field", [
    (lambda: fc.FractalSurface(2.0, 1e-9), "D="),
    (lambda: fc.FractalSurface(1.5, -1.0), "G_m"),
    (lambda: fc.FractalMaterial(-1.0, 1e9), "E_Pa"),
    (lambda: fc.FractalMaterial(1e11, 1e9, friction=1.5), "friction"),
    (lambda: fc.FractalOptions(lambda_c=1.5), "lambda_c"),
    (lambda: fc.LateralContact((1.0, 0.5), (0.5, 0.5)), "LateralContact.s"),
    (lambda: fc.LateralContact((1.0, 1.1), (0.5, 0.6)), "weights"),
    (lambda: fc.oil_film_stiffness_N_per_m(1e-6, 0.0, 0.0), "h_m"),
    (lambda: fc.film_regime(float("nan")), "film_parameter"),
])
def test_bad_input_names_the_field(make, field):
    with pytest.raises(fc.FractalInputError, match=field):
        make()


def test_too_large_load_is_a_clear_error():
    with pytest.raises(fc.FractalInputError, match="load_N"):
        fc.solid_contact_at_load(fc.FractalSurface(1.45, 8e-9), MAT, 1e9, A0)


def test_film_regime_thresholds():
    """lambda >= 3 full film, 1..3 mixed, < 1 boundary (Tallian 1967; Johnson, Greenwood & Poon 1972)."""
    assert fc.film_regime(3.0) == "full_film"
    assert fc.film_regime(2.99) == "mixed" and fc.film_regime(1.0) == "mixed"
    assert fc.film_regime(0.99) == "boundary"


def test_fractal_mixed_is_registered_and_load_dependent():
    from gearfmu.contact.models import CONTACT_MODELS

    m = CONTACT_MODELS["fractal_mixed"]
    assert m.load_dependent and m.needs_lubricant
    geom, env = _seed000_env(2)
    s_mid = 0.5 * (geom.s_start_m + geom.s_end_m)
    s = np.array([s_mid, s_mid, s_mid])
    res = m.fn(env, s, np.array([0, 1, 0]), np.array([1e5, 1e5, 4e5]))
    k = res.k_N_per_m
    assert np.all(np.isfinite(k)) and np.all(k > 0)
    assert k[0] == k[1]            # slices share D and G
    assert k[2] > k[0]             # stiffer at the higher slice load


# ------------------------------------------------------------ slicing, complete contact, film parameter
def _seed000_pitch():
    """Seed 000 Table 1 pair at its pitch point and nominal line load w = T/(r_b1 b)."""
    from pathlib import Path

    from gearfmu.gear.hertz import reduced_modulus_Pa
    from gearfmu.ehl.mesh_film import contact_kinematics
    from gearfmu.gear.geometry import pair_geometry
    from gearfmu.scene.reader import load_scene

    sc = load_scene(Path(__file__).resolve().parents[3] / "examples" / "scenes" / "seed000_table1.toml")
    g = pair_geometry(sc.pair)
    R, u, _ = contact_kinematics(g, g.s_pitch_m, sc.operating.speed_rad_s)
    w = sc.operating.torque_Nm / g.rb1_m / sc.pair.pinion.face_width_m
    return sc, g, float(R), float(u), w, reduced_modulus_Pa(sc.pair)


def _eta_alpha(sc):
    from gearfmu.scene.physics import environment_from_scene

    env = environment_from_scene(sc, max_workers=1)
    return env.eta0_Pas, env.alpha_Pa_inv


@pytest.mark.parametrize("level", [1, 4])
def test_slice_stiffness_per_unit_width_does_not_depend_on_the_slicing(level):
    """The 44 mm face of the seed 000 pair at its pitch point and nominal line load, cut
    into 1, 2, 4, 11 or 44 slices: K_n, K_s, K_l per unit width and A_r/A0 are the same.  Reference:
    slices are springs in parallel under the same line load, so stiffness per unit width of a uniform
    face is a property of the face (and the 1 mm + 43 mm cut adds up to the whole face).  The old
    per-slice nominal area gave A_r/A0 = 0.68 (1 mm) against 1.44 (22 mm) at level 4.  Tolerance
    rel 1e-9: only the root finder's (1e-12) and rounding errors may differ."""
    from gearfmu.contact.models import RoughnessSpec

    sc, _, R, u, w, Es = _seed000_pitch()
    sp = RoughnessSpec.from_level(level)
    eta, alpha = _eta_alpha(sc)
    face = 44e-3

    def k(width):
        return fc.slice_contact_stiffness(sp.D, sp.G_m, R, u, w, width, Es, eta, alpha)

    ref = k(face)
    assert 0.0 < ref["real_area_ratio"] < 1.0 and ref["K_l_N_per_m"] > 0
    for n in (2, 4, 11, 44):
        r = k(face / n)
        for key in ("K_n_N_per_m", "K_s_N_per_m", "K_l_N_per_m"):
            assert r[key] * n == pytest.approx(ref[key], rel=1e-9), (n, key)
        assert r["real_area_ratio"] == pytest.approx(ref["real_area_ratio"], rel=1e-9)
    assert k(1e-3)["K_n_N_per_m"] + k(43e-3)["K_n_N_per_m"] == pytest.approx(ref["K_n_N_per_m"], rel=1e-9)
    # the solid part is N = A0/L_s^2 reference elements in parallel (docs/fractal_contact.md)
    mo = fc.FractalMeshOptions()
    b = math.sqrt(4 * w * R / (math.pi * Es))                          # Hertz half-width (Johnson 1985)
    opts = fc.FractalOptions(lateral=mo.options.lateral, interaction=mo.options.interaction,
                             lambda_c=ref["lambda_c"])
    e = fc.solid_contact_at_load(fc.FractalSurface(sp.D, sp.G_m), fc.FractalMaterial(Es, mo.H_Pa, friction=mo.friction),
                                 w / (2 * b) * mo.L_s_m ** 2, mo.L_s_m ** 2, opts)
    assert ref["K_s_N_per_m"] == pytest.approx(e.stiffness_N_per_m * 2 * b * face / mo.L_s_m ** 2, rel=1e-9)


def test_raw_mb_area_ratio_grows_with_nominal_area_extensive_does_not():
    """Why the mesh scales a reference element: in the MB (1991) model at equal nominal pressure
    A_r/A0 grows with A0 (P ~ A_r^((3-D)/2) elastically), the element-scaled result does not."""
    s = fc.FractalSurface(1.45, 1e-10)
    p = 1e6
    raw = [fc.solid_contact_at_load(s, MAT, p * a, a).real_area_m2 / a for a in (1e-8, 1e-6, 1e-4)]
    ext = [fc.solid_contact_extensive(s, MAT, p, a, 1e-8).real_area_m2 / a for a in (1e-8, 1e-6, 1e-4)]
    assert raw[0] < raw[1] < raw[2] and raw[2] > 2 * raw[0]
    assert ext == pytest.approx([raw[0]] * 3, rel=1e-12)


def test_real_area_reaching_the_nominal_area_raises():
    """A_r >= A0 (complete contact) is outside the model: the load the asperities carry at
    A_r = A0 is the limit; just below it the real area stays below A0, just above it
    FullContactError (a FractalInputError) names load_N and real_area_ratio."""
    s = fc.FractalSurface(1.45, 8e-9)
    with pytest.raises(fc.FullContactError, match="load_N=.*real_area_ratio") as ei:
        fc.solid_contact_at_load(s, MAT, 1e9, A0, fc.SEED001_FULL)
    P_max = ei.value.max_load_N
    assert isinstance(ei.value, fc.FractalInputError) and 0 < P_max < 1e9
    r = fc.solid_contact_at_load(s, MAT, 0.999 * P_max, A0, fc.SEED001_FULL)
    assert 0.99 < r.real_area_m2 / A0 < 1.0
    with pytest.raises(fc.FullContactError):
        fc.solid_contact_at_load(s, MAT, 1.001 * P_max, A0, fc.SEED001_FULL)


def test_film_parameter_one_definition():
    """Lambda = h_min / sqrt(sigma1^2 + sigma2^2) (Tallian 1967; Johnson 1985; ISO/TR 15144-1), with
    h_min of Dowson & Higginson (h_min/R = 2.65 U^0.70 G^0.54 W^-0.13, written out here) and both
    flanks' W-M sigma: the mixed model's Lambda equals the rough-EHL switch's
    (gearfmu.contact.models.film_parameter) at the seed 000 pitch point, levels 1-4."""
    from gearfmu.contact.models import RoughnessSpec
    from gearfmu.scene.physics import environment_from_scene
    from gearfmu.contact.models import film_parameter as switch_lambda
    from gearfmu.contact.roughness import wm_sigma_m

    assert fc.film_parameter(5e-7, 3e-7, 4e-7) == pytest.approx(1.0, rel=1e-15)
    sc, g, R, u, w, Es = _seed000_pitch()
    eta, alpha = _eta_alpha(sc)
    Ep = 2 * Es
    for level in (1, 2, 3, 4):
        sp = RoughnessSpec.from_level(level)
        r = fc.slice_contact_stiffness(sp.D, sp.G_m, R, u, w, 11e-3, Es, eta, alpha)
        h = R * 2.65 * (eta * u / (Ep * R)) ** 0.70 * (alpha * Ep) ** 0.54 * (w / (Ep * R)) ** -0.13
        lam = h / (math.sqrt(2) * wm_sigma_m(sp.D, sp.G_m, 0.5e-3))
        assert r["film_parameter"] == pytest.approx(lam, rel=1e-12)
        env = environment_from_scene(sc, roughness=sp, max_workers=1)
        assert switch_lambda(env, [g.s_pitch_m], [w])[0] == pytest.approx(lam, rel=1e-12)


def test_fractal_mixed_model_complete_contact_uses_hertz_and_says_so():
    """A slice load whose asperities would reach complete contact (level 4, 4 MN/m) takes the Hertz
    stiffness of the slice, recorded as 'complete_contact' (the rough-EHL policy's choice)."""
    from gearfmu.contact.models import CONTACT_MODELS, hertz_stiffness_N_per_m

    geom, env = _seed000_env(4)
    s = np.full(2, geom.s_pitch_m)
    res = CONTACT_MODELS["fractal_mixed"].fn(env, s, np.array([0, 1]), np.array([3e5, 4e6]))
    assert res.k_N_per_m[1] == hertz_stiffness_N_per_m(env.pair, 11e-3)
    assert res.k_N_per_m[0] != res.k_N_per_m[1] and res.fallbacks == 1
    f = [x for x in res.failures if x["status"] == "complete_contact"]
    assert len(f) == 1 and f[0]["w_N_per_m"] == pytest.approx(4e6) and "real_area_ratio" in f[0]["message"]


def _seed000_env(level):
    """Seed 000 Table 1 pair (45/34 teeth, m = 6 mm, 20 deg, 44 mm face) in 4 slices of 11 mm at
    2000 rpm with the given Table 2 roughness level: (pair geometry, ContactEnvironment)."""
    from gearfmu.contact.models import ContactEnvironment, RoughnessSpec
    from gearfmu.gear.gearpair import GearPairSpec, GearSpec
    from gearfmu.gear.geometry import pair_geometry

    g = lambda z: GearSpec(teeth=z, module_m=6e-3, pressure_angle_rad=math.radians(20), face_width_m=44e-3)
    pair = GearPairSpec(pinion=g(45), gear=g(34))
    geom = pair_geometry(pair)
    return geom, ContactEnvironment(pair=pair, geom=geom, omega1_rad_s=209.4, n_slices=4, width_m=11e-3,
                                    eta0_Pas=0.1, alpha_Pa_inv=2e-8, rho0_kg_m3=870.0,
                                    roughness=RoughnessSpec.from_level(level))
