"""Temperature stiffness (seed 004) and the oil-temperature viscosity law.

References: seed 004 (He & Yang, Mechanika) Tables 2-3 and eq 8, 11, 14, 17-18, 21-27; its Table 4
load (80 kW at 2000 rpm); textbook involute geometry (tooth thickness s = pi m/2 on the reference
circle); an independent numerical scaling of the involute (numpy + scipy brentq); ASTM D341's
Walther equation solved here with numpy.linalg.solve.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from gearfmu.gear import thermal as th
from gearfmu.gear.geometry import pair_geometry
from gearfmu.scene.reader import SceneError, load_scene

ROOT = Path(__file__).resolve().parents[3]
SCENE = {"I": ROOT / "examples" / "scenes" / "seed004_pair1.toml",
         "II": ROOT / "examples" / "scenes" / "seed004_pair2.toml"}
# seed 004 Table 2 (1e8 N/m): pinion in/pitch/out, gear in/pitch/out; Table 3: pair in/pitch/out
T2 = {"I": {"std": [18.5940, 7.4045, 2.3619, 2.5141, 8.2403, 22.3810],
            "exp": [17.9410, 6.7564, 2.2383, 2.4759, 7.4968, 21.2100],
            "shr": [13.4620, 5.8402, 2.1143, 2.1869, 5.9959, 13.3090]},
      "II": {"std": [30.6230, 22.0610, 2.4278, 1.2675, 1.6713, 4.6155],
             "exp": [29.5070, 21.0500, 2.3929, 1.2213, 1.5947, 4.5493],
             "shr": [15.6580, 12.1930, 2.1293, 1.2093, 1.5807, 4.3053]}}
T3 = {"I": {"std": [2.2147, 3.9000, 2.1365], "exp": [2.1370, 3.5481, 2.0246], "shr": [1.8813, 2.9585, 1.8245]},
      "II": {"std": [1.2171, 1.5536, 1.5909], "exp": [1.1728, 1.4824, 1.5681], "shr": [1.1226, 1.3993, 1.4247]}}
STATE_T = {"std": 30.0, "exp": 70.0, "shr": 10.0}       # seed 004 section 4
TORQUE = 80e3 / (2000 * 2 * math.pi / 60)               # seed 004 Table 4: 381.97 N m


def _setup(name):
    sc = load_scene(SCENE[name])
    g = pair_geometry(sc.pair)
    s = np.array([g.s_start_m, g.s_pitch_m, g.s_end_m])
    return sc, g, s, TORQUE / g.rb1_m


def _with_seed_standard(name, state):
    sc, g, s, Fn = _setup(name)
    std = np.array(T2[name]["std"]) * 1e8
    r = th.key_point_stiffness(sc.pair, th.ThermalState(STATE_T[state], STATE_T[state], 30.0), Fn, s, g,
                               standard=(np.array(T3[name]["std"]) * 1e8, std[:3], std[3:]))
    ours = np.r_[r.k1_N_per_m, r.k2_N_per_m, r.k_N_per_m] / 1e8
    seed = np.r_[T2[name][state], T3[name][state]]
    return ours, seed


# ------------------------------------------------------------------ (a) the thermal model alone
@pytest.mark.parametrize("state", ["exp", "shr"])
def test_pair_I_tables_2_3_with_the_seed_standard_stiffness(state):
    """Seed 004 Tables 2-3, pair I: the seed's standard stiffness + its Table 4 load + the
    radial-tangential flank law reproduce all 9 expansion and 9 shrinkage values to 0.02 %,
    except two printed expansion values that violate the seed's own eq 17-18 (k_Ti/k_i = k_T/k):
    pinion pitch 6.7564 (eq 18 with the seed's mesh ratio gives 6.7364) and gear meshing-in 2.4759
    (gives 2.4259) -- one-digit misprints; ours match the eq-18 values."""
    ours, seed = _with_seed_standard("I", state)
    rel = ours / seed - 1
    if state == "exp":
        std = np.array(T2["I"]["std"])
        ratio = np.array(T3["I"]["exp"]) / np.array(T3["I"]["std"])     # seed's own k_T/k
        eq18 = np.r_[std[:3] * ratio, std[3:] * ratio]
        typos = [1, 3]
        assert abs(seed[1] / eq18[1] - 1) > 2.5e-3 and abs(seed[3] / eq18[3] - 1) > 1.5e-2
        np.testing.assert_allclose(ours[typos], eq18[typos], rtol=2e-4)
        rel = np.delete(rel, typos)
    assert np.max(np.abs(rel)) < 2e-4, rel


def test_pair_II_tables_2_3_with_the_seed_standard_stiffness():
    """Pair II (profile shifted): the pinion's shrinkage values to 0.15 %; every value within 2 %.
    The seed's gear column implies a gear flank deformation 0.71-0.75 x ours (not reproduced by
    any law tried, docs/thermal.md), which the 2 % covers."""
    ours, seed = _with_seed_standard("II", "shr")
    assert np.max(np.abs(ours[:3] / seed[:3] - 1)) < 1.5e-3
    assert np.max(np.abs(ours / seed - 1)) < 0.02
    ours, seed = _with_seed_standard("II", "exp")
    assert np.max(np.abs(ours / seed - 1)) < 0.005


# ------------------------------------------------------------------ closed forms of the model
def test_expansion_satisfies_energy_balance_and_eq8():
    """Seed eq 11 (energy: 1/2 sum k_i x_pi^2 = 1/2 (2 F_n + k dx_TS) dx_T) with eq 8
    (dx_T = 2 dx_TS), solved independently for dx_TS by brentq; eq 21 series form; eq 17-18."""
    k1, k2, F = 1.2e9, 3.4e8, 9000.0
    k = 1 / (1 / k1 + 1 / k2)
    p1, p2 = 6e-6, 3.1e-6
    r = th.temperature_stiffness(k, k1, k2, p1, p2, F)
    Q = 0.5 * (k1 * p1 ** 2 + k2 * p2 ** 2)
    dxts = brentq(lambda d: 0.5 * (2 * F + k * d) * (2 * d) - Q, 0.0, 1e-3, xtol=1e-20, rtol=1e-14)
    x = F / k
    assert float(r.k_N_per_m) == pytest.approx(F / (x + dxts), rel=1e-12)
    assert float(r.compliance_m_per_N) == pytest.approx(dxts / F, rel=1e-10)
    assert 1 / float(r.k_N_per_m) == pytest.approx(1 / k + dxts / F, rel=1e-12)          # eq 21
    assert float(r.k1_N_per_m) / k1 == pytest.approx(float(r.k_N_per_m) / k, rel=1e-12)  # eq 17-18
    assert float(r.k2_N_per_m) / k2 == pytest.approx(float(r.k_N_per_m) / k, rel=1e-12)


def test_shrinkage_is_a_series_spring_eq23_26():
    """Seed eq 23-26: x_S = x + dx_S1 + dx_S2; 1/k_Si = 1/k_i + dx_Si/F_n."""
    k1, k2, F = 2.0e9, 5.0e8, 12000.0
    k = 1 / (1 / k1 + 1 / k2)
    s1, s2 = 2.5e-6, 4.0e-6
    r = th.temperature_stiffness(k, k1, k2, -s1, -s2, F)
    assert float(r.k_N_per_m) == pytest.approx(F / (F / k + s1 + s2), rel=1e-13)
    assert 1 / float(r.k1_N_per_m) == pytest.approx(1 / k1 + s1 / F, rel=1e-13)
    assert 1 / float(r.k2_N_per_m) == pytest.approx(1 / k2 + s2 / F, rel=1e-13)


def test_mixed_states_reduce_to_the_seed_limits_and_are_continuous():
    """CHOICE 1 (pinion hot, gear cold): with the gear at t0 it is eq 14 with one expanding tooth;
    with the pinion at t0 it is eq 23 with one shrinking tooth; continuous across t0."""
    k1, k2, F = 1.5e9, 6e8, 8000.0
    k = 1 / (1 / k1 + 1 / k2)
    x = F / k
    r = th.temperature_stiffness(k, k1, k2, 5e-6, 0.0, F)
    assert float(r.k_N_per_m) == pytest.approx(F / math.sqrt(x * x + k1 * 25e-12 / (2 * k)), rel=1e-13)
    r = th.temperature_stiffness(k, k1, k2, 0.0, -3e-6, F)
    assert float(r.k_N_per_m) == pytest.approx(F / (x + 3e-6), rel=1e-13)
    r = th.temperature_stiffness(k, k1, k2, 5e-6, -3e-6, F)
    X = math.sqrt(x * x + k1 * 25e-12 / (2 * k))
    assert float(r.k_N_per_m) == pytest.approx(F / (X + 3e-6), rel=1e-13)
    assert float(r.k2_N_per_m) == pytest.approx(F / (k / k2 * X + 3e-6), rel=1e-13)
    eps = np.array([-1e-13, 0.0, 1e-13])
    ks = th.temperature_stiffness(k, k1, k2, eps, eps, F).k_N_per_m
    np.testing.assert_allclose(ks, k, rtol=2e-13 / x)        # |dk/k| <= shrinkage / x
    assert ks[1] == k


def test_bad_input_raises_named_errors():
    with pytest.raises(th.ThermalError, match="normal_load_N"):
        th.temperature_stiffness(1e8, 2e8, 2e8, 1e-6, 1e-6, 0.0)
    with pytest.raises(th.ThermalError, match="free1_m"):
        th.temperature_stiffness(1e8, 2e8, 2e8, float("nan"), 1e-6, 10.0)
    sc, g, s, Fn = _setup("I")
    with pytest.raises(th.ThermalError, match="law"):
        th.free_flank_deformation_m(g, 1, s, 10.0, 1e-5, law="magic")
    with pytest.raises(th.ThermalError, match="torque_Nm"):
        th.thermal_slot_stiffness(sc.pair, torque_Nm=-1.0, temperatures_C=[30.0])
    with pytest.raises(th.ThermalError, match="temperatures_C"):
        th.thermal_slot_stiffness(sc.pair, torque_Nm=10.0, temperatures_C=[50.0, 40.0])
    with pytest.raises(th.ThermalError, match="gamma"):
        th.TemperatureProfile((0.5, 0.1), (70.0, 80.0))
    assert issubclass(th.ThermalError, ValueError)


# ------------------------------------------------------------------ free flank deformation
def test_homogeneous_law_equals_a_numerically_scaled_involute():
    """Scale the pinion's involute flank by (1 + alpha dT) about the centre (numpy points), then
    find with brentq where the flank normal at K meets the scaled flank: the distance must be
    alpha dT r_b tan(a_K) (the 'homogeneous' law) to first order in alpha dT.  alpha dT = 1e-8 here
    keeps the second-order term (alpha dT r_b^2/rho^2 relative, 0.8 % at the pinion root for 40 K
    of steel) below 1e-6."""
    sc, g, s, _ = _setup("I")
    rb = g.rb1_m
    a, dT = 1e-9, 10.0
    lam = 1 + a * dT
    psi0 = g.half_tooth_angle(1, rb)                    # polar angle of the flank at the base circle

    def flank(u, scale=1.0):                            # involute point of roll angle u, tooth frame
        ang = psi0 - (u - math.atan(u))
        rho = rb * math.sqrt(1 + u * u)
        return scale * np.array([rho * math.cos(ang), rho * math.sin(ang)])

    for sK in s:
        uK = sK / rb
        P = flank(uK)
        # unit normal of the flank at P (outward from the tooth): numerical derivative, rotated
        d = (flank(uK + 1e-7) - flank(uK - 1e-7))
        t = d / np.linalg.norm(d)
        n = np.array([-t[1], t[0]])
        if n @ P < 0:
            n = -n
        # intersection of P + eta n with the scaled flank: solve cross((Q(u) - P), n) = 0
        def f(u):
            d_ = flank(u, lam) - P
            return d_[0] * n[1] - d_[1] * n[0]
        u_star = brentq(f, uK - 0.05, uK + 0.05, xtol=1e-15)
        eta = (flank(u_star, lam) - P) @ n
        ref = a * dT * rb * math.tan(math.atan(uK))
        got = float(th.free_flank_deformation_m(g, 1, sK, dT, a, law="homogeneous"))
        assert abs(eta) == pytest.approx(ref, rel=1e-5)
        assert got == pytest.approx(abs(eta), rel=1e-5)


def test_radial_tangential_law_at_the_pitch_point_by_hand():
    """Pair I (x = 0, a_w = a): at the pitch point the pinion tooth is s = pi m/2 thick on the
    reference circle r = 40.5 mm; half chord h = r sin(s/(2r)); law = alpha dT (r sin 20 deg + h cos 20 deg)."""
    sc, g, s, _ = _setup("I")
    r, m, al = 0.0405, 0.003, math.radians(20)
    h = r * math.sin(math.pi * m / 2 / (2 * r))
    ref = 1.13e-5 * 40 * (r * math.sin(al) + h * math.cos(al))
    got = float(th.free_flank_deformation_m(g, 1, g.s_pitch_m, 40.0, 1.13e-5))
    assert got == pytest.approx(ref, rel=1e-9)
    # gear: r = 52.5 mm, same tooth thickness
    r2 = 0.0525
    h2 = r2 * math.sin(math.pi * m / 2 / (2 * r2))
    ref2 = 1.13e-5 * 40 * (r2 * math.sin(al) + h2 * math.cos(al))
    assert float(th.free_flank_deformation_m(g, 2, g.s_pitch_m, 40.0, 1.13e-5)) == pytest.approx(ref2, rel=1e-9)


# ------------------------------------------------------------------ (b) end to end with our stiffness
@pytest.fixture(scope="module")
def end_to_end():
    out = {}
    for name in ("I", "II"):
        sc, g, s, Fn = _setup(name)
        out[name] = {st: th.key_point_stiffness(sc.pair, th.ThermalState(t, t, 30.0), Fn, s, g)
                     for st, t in STATE_T.items()}
    return out


def _rel(res, name, st):
    b, r = res[name]["std"], res[name][st]
    return {q: getattr(r, a) / getattr(b, a) - 1 for q, a in
            (("pinion", "k1_N_per_m"), ("gear", "k2_N_per_m"), ("mesh", "k_N_per_m"))}


def test_end_to_end_signs_and_orderings_match_seed(end_to_end):
    """Seed 004 Tables 2-3 and section 4: (1) every temperature stiffness is below the standard one;
    (2) the 10 degC shrinkage lowers every value more than the 70 degC expansion; (3) pair I: the
    mesh reduction at the pitch point exceeds those at meshing-in and -out (both states); pair II
    expansion: pitch > meshing-in > meshing-out as in Table 3."""
    for name in ("I", "II"):
        e, s = _rel(end_to_end, name, "exp"), _rel(end_to_end, name, "shr")
        seed_e = {q: np.array(T2[name]["exp"][i:i + 3] if q != "mesh" else T3[name]["exp"]) /
                  np.array(T2[name]["std"][i:i + 3] if q != "mesh" else T3[name]["std"]) - 1
                  for q, i in (("pinion", 0), ("gear", 3), ("mesh", 0))}
        seed_s = {q: np.array(T2[name]["shr"][i:i + 3] if q != "mesh" else T3[name]["shr"]) /
                  np.array(T2[name]["std"][i:i + 3] if q != "mesh" else T3[name]["std"]) - 1
                  for q, i in (("pinion", 0), ("gear", 3), ("mesh", 0))}
        for q in ("pinion", "gear", "mesh"):
            assert np.all(e[q] < 0) and np.all(s[q] < 0) and np.all(seed_e[q] < 0) and np.all(seed_s[q] < 0)
            assert np.all(s[q] < e[q]) and np.all(seed_s[q] < seed_e[q])
    for st in ("exp", "shr"):
        m = _rel(end_to_end, "I", st)["mesh"]
        assert m[1] < m[0] and m[1] < m[2]
    m = _rel(end_to_end, "II", "exp")["mesh"]
    assert m[1] < m[0] < m[2]


def test_end_to_end_relative_reductions_near_seed(end_to_end):
    """Relative mesh-stiffness reductions vs Table 3 (percentage points): expansion within 1 pp for
    both pairs; shrinkage within 2.5 pp for pair I and 5 pp for pair II (our standard stiffness
    differs from the seed's, docs/physics_stiffness.md, and pair II's gear column is not
    reproduced). Measured: pair I exp 3.95/8.59/4.57 % vs 3.51/9.02/5.24 %."""
    for name, tol_s in (("I", 0.025), ("II", 0.05)):
        for st, tol in (("exp", 0.01), ("shr", tol_s)):
            seed = np.array(T3[name][st]) / np.array(T3[name]["std"]) - 1
            ours = _rel(end_to_end, name, st)["mesh"]
            assert np.max(np.abs(ours - seed)) < tol, (name, st, ours, seed)


def test_low_high_low_trend():
    """Seed Fig. 5 / eq 27: k(T) rises strictly up to the standard temperature and falls after it."""
    sc, g, s, Fn = _setup("I")
    temps = np.linspace(-20, 100, 25)
    k = np.array([th.key_point_stiffness(sc.pair, th.ThermalState(t, t, 30.0), Fn, s, g).k_N_per_m
                  for t in temps])
    i0 = int(np.argmin(abs(temps - 30.0)))
    assert temps[i0] == 30.0
    assert np.all(np.diff(k[:i0 + 1], axis=0) > 0) and np.all(np.diff(k[i0:], axis=0) < 0)


# ------------------------------------------------------------------ distribution along the LOA
def test_profile_vs_mean_is_local():
    """A temperature profile acts pointwise: at each contact point the result equals the uniform
    closed form (eq 14 with alpha (T(s) - t0) L) at the local temperature; a uniform profile
    equals its mean; a non-uniform one differs from its mean where T(s) != mean."""
    sc, g, s, Fn = _setup("I")
    gA, gE = th.gamma_from_s(g, [g.s_start_m, g.s_end_m])
    pin = th.TemperatureProfile((float(gA), float(gE)), (76.48, 84.48))
    gear = th.TemperatureProfile((float(gA), float(gE)), (79.54, 71.54))
    assert pin.mean_C(g) == pytest.approx(80.48, abs=1e-9) and gear.mean_C(g) == pytest.approx(75.54, abs=1e-9)
    prof = th.key_point_stiffness(sc.pair, th.ThermalState(pin, gear, 30.0), Fn, s, g)
    for j, sj in enumerate(s):
        t1 = 76.48 + 8.0 * (sj - g.s_start_m) / (g.s_end_m - g.s_start_m)
        t2 = 79.54 - 8.0 * (sj - g.s_start_m) / (g.s_end_m - g.s_start_m)
        loc = th.key_point_stiffness(sc.pair, th.ThermalState(t1, t2, 30.0), Fn, sj, g)
        assert float(prof.k_N_per_m[j]) == pytest.approx(float(loc.k_N_per_m[0]), rel=1e-13)
    flat = th.TemperatureProfile((-1.0, 1.0), (80.48, 80.48))
    a = th.key_point_stiffness(sc.pair, th.ThermalState(flat, flat, 30.0), Fn, s, g).k_N_per_m
    b = th.key_point_stiffness(sc.pair, th.ThermalState(80.48, 80.48, 30.0), Fn, s, g).k_N_per_m
    np.testing.assert_array_equal(a, b)
    # linear profiles equal their means at the middle of A..E: same stiffness there, not at A and E
    sm = np.array([g.s_start_m, 0.5 * (g.s_start_m + g.s_end_m), g.s_end_m])
    prof = th.key_point_stiffness(sc.pair, th.ThermalState(pin, gear, 30.0), Fn, sm, g).k_N_per_m
    mean = th.key_point_stiffness(sc.pair, th.ThermalState(80.48, 75.54, 30.0), Fn, sm, g).k_N_per_m
    assert prof[1] == pytest.approx(mean[1], rel=1e-12)
    assert abs(prof[0] / mean[0] - 1) > 5e-4 and abs(prof[2] / mean[2] - 1) > 5e-4


# ------------------------------------------------------------------ tables: temperature axis
def test_thermal_slot_stiffness_axis():
    """At t0 the standard slot stiffness exactly; elsewhere below it in contact, 0 out of contact;
    a single pair in single contact carries the whole load T/r_b1 (closed form eq 14)."""
    sc, g, _, _ = _setup("I")
    r = th.thermal_slot_stiffness(sc.pair, sc.mesh, torque_Nm=TORQUE, temperatures_C=[10.0, 30.0, 70.0],
                                  n_per_mesh=32)
    assert r.k_N_per_m.shape == (3,) + r.k_standard_N_per_m.shape
    np.testing.assert_array_equal(r.k_N_per_m[1], r.k_standard_N_per_m)
    inc = r.k_standard_N_per_m > 0
    assert np.all(r.k_N_per_m[0][inc] < r.k_standard_N_per_m[inc])
    assert np.all(r.k_N_per_m[2][inc] < r.k_standard_N_per_m[inc])
    assert np.all(r.k_N_per_m[:, ~inc] == 0)
    single = np.flatnonzero(inc.sum(axis=0) == 1)
    j = int(single[len(single) // 2])
    slot = int(np.flatnonzero(inc[:, j])[0])
    from gearfmu.gear.stiffness import slot_stiffness
    ss = slot_stiffness(sc.pair, g, sc.mesh, None, 32)
    sK = ss.s_m[slot, j]
    k = r.k_standard_N_per_m[slot, j]
    k1 = th.single_tooth_stiffness_N_per_m(sc.pair, g, 1, sK)[0]
    k2 = th.single_tooth_stiffness_N_per_m(sc.pair, g, 2, sK)[0]
    p1 = float(th.free_flank_deformation_m(g, 1, sK, 40.0, 1.13e-5))
    p2 = float(th.free_flank_deformation_m(g, 2, sK, 40.0, 1.13e-5))
    F = TORQUE / g.rb1_m
    x = F / k
    assert r.k_N_per_m[2, slot, j] == pytest.approx(F / math.sqrt(x * x + (k1 * p1 ** 2 + k2 * p2 ** 2) / (2 * k)),
                                                    rel=1e-12)


# ------------------------------------------------------------------ scene and oil
def test_scene_thermal_section():
    text = SCENE["I"].read_text() + ("\n[thermal]\nstandard_temperature_C = 30\npinion_temperature_C = 70\n"
                                     "gear_profile_gamma = [-0.5, 0.5]\ngear_profile_C = [70, 80]\n")
    t = load_scene(text).thermal
    assert t.pinion_temperature_C == 70.0 and t.gear_temperature_C is None
    assert t.gear_profile_C == (70.0, 80.0) and t.axis_quantity == "bulk" and t.lubricant is None
    t = load_scene(SCENE["I"].read_text() + "\n[thermal]\ntemperature_axis_C = [10, 30, 70]\n").thermal
    assert t.temperature_axis_C == (10.0, 30.0, 70.0)
    assert load_scene(SCENE["I"]).thermal is None
    for bad, key in (("temperature_axis_C = [30, 10]", "thermal.temperature_axis_C"),
                     ("pinion_profile_gamma = [0.1]", "thermal.pinion_profile_C"),
                     ("flank_law = \"linear\"", "thermal.flank_law"),
                     ("axis_quantity = \"wall\"", "thermal.axis_quantity"),
                     # a bulk axis sets both gears' temperature: a fixed one contradicts it
                     ("temperature_axis_C = [10, 70]\npinion_temperature_C = 70", "thermal.pinion_temperature_C"),
                     # the oil axis needs a lubricated contact model (pair I is Hertz)
                     ("temperature_axis_C = [40, 80]\naxis_quantity = \"oil\"", "thermal.axis_quantity"),
                     ("axis_quantity = \"oil\"", "thermal.axis_quantity")):
        with pytest.raises(SceneError, match=key.replace(".", r"\.")):
            load_scene(SCENE["I"].read_text() + "\n[thermal]\n" + bad + "\n")


def test_oil_viscosity_walther_astm_d341():
    """ASTM D341: log10 log10(nu + 0.7) = A - B log10(T/K) through (313.15 K, 320 cSt) and
    (373.15 K, 38.5 cSt) solved here with numpy.linalg.solve; eta0 = rho nu (constant rho)."""
    M = np.array([[1.0, -math.log10(313.15)], [1.0, -math.log10(373.15)]])
    A, B = np.linalg.solve(M, [math.log10(math.log10(320.7)), math.log10(math.log10(39.2))])
    for t in (20.0, 40.0, 60.0, 75.54, 100.0, 120.0):
        nu = 10 ** (10 ** (A - B * math.log10(t + 273.15))) - 0.7
        got = float(th.oil_dynamic_viscosity_Pas(320e-6, 38.5e-6, 870.0, t))
        assert got == pytest.approx(870.0 * nu * 1e-6, rel=1e-10)
    eta = th.oil_dynamic_viscosity_Pas(320e-6, 38.5e-6, 870.0, [40.0, 60.0, 80.0])
    assert np.all(np.diff(eta) < 0)
    with pytest.raises(th.ThermalError, match="nu40"):
        th.oil_dynamic_viscosity_Pas(30e-6, 38.5e-6, 870.0, 40.0)


def test_scene_to_thermal_state():
    """[thermal] -> ThermalState: profile when given, else uniform, else the standard temperature."""
    text = SCENE["I"].read_text() + ("\n[thermal]\nstandard_temperature_C = 25\npinion_temperature_C = 70\n"
                                     "gear_profile_gamma = [-0.5, 0.5]\ngear_profile_C = [70, 80]\n")
    st = th.thermal_state_from_scene(load_scene(text).thermal)
    assert st.pinion == 70.0 and st.standard_temperature_C == 25.0
    assert st.gear == th.TemperatureProfile((-0.5, 0.5), (70.0, 80.0))
    st = th.thermal_state_from_scene(load_scene(SCENE["I"].read_text() + "\n[thermal]\n").thermal)
    assert st.pinion == 30.0 and st.gear == 30.0


# ------------------------------------------------- one temperature without an axis (scene -> tables)
def _slot_positions(scene, tables):
    """LOA position (m from N1) of every slot and table angle, NaN out of contact."""
    from gearfmu.gear.stiffness import slot_stiffness

    g = pair_geometry(scene.pair)
    ss = slot_stiffness(scene.pair, g, scene.mesh, tables.slots, scene.tables.points_per_mesh)
    return g, np.tile(ss.s_m, (1, tables.n_phi // ss.s_m.shape[1]))


def test_single_temperature_without_axis_changes_the_tables():
    """[thermal] pinion/gear temperature alone (no axis) gives the tables at that state.

    Reference: seed 004 eq 23-26 written out here for 10 degC (shrinkage, t0 = 30): the free
    shrinkage of both flanks adds in series to the elastic deformation of each pair,
    k_S = F_j / (F_j/k_j + |dx_1| + |dx_2|), with the load share F_j = F_n k_j / sum k
    (docs/thermal.md CHOICE 4), F_n = T/r_b1, k_j the standard table, dx_i of
    free_flank_deformation_m (checked against the scaled involute and by hand above).
    The table mean equals the mean of thermal_slot_stiffness at that state, and is below
    the standard one (seed 004: shrinkage lowers the stiffness)."""
    from gearfmu.pipeline import compute_tables

    base = SCENE["I"].read_text().replace("slices = 25", "slices = 5")
    plain_sc = load_scene(base)
    plain = compute_tables(plain_sc)
    cold_sc = load_scene(base + "\n[thermal]\nstandard_temperature_C = 30\npinion_temperature_C = 10\n"
                                "gear_temperature_C = 10\n")
    cold = compute_tables(cold_sc)
    assert not cold.has_temperature_axis and cold.k_N_per_m.shape == plain.k_N_per_m.shape
    g, s = _slot_positions(plain_sc, plain)
    k = plain.k_N_per_m[0]
    on = k > 0
    F = plain_sc.operating.torque_Nm / g.rb1_m
    Fj = F * k / k.sum(axis=0)[None, :]
    alpha = plain_sc.pair.pinion.material.thermal_expansion_per_K
    d1 = np.abs(th.free_flank_deformation_m(g, 1, s[on], -20.0, alpha))
    d2 = np.abs(th.free_flank_deformation_m(g, 2, s[on], -20.0, alpha))
    hand = Fj[on] / (Fj[on] / k[on] + d1 + d2)
    np.testing.assert_allclose(cold.k_N_per_m[0][on], hand, rtol=1e-12)
    assert np.all(cold.k_N_per_m[0][~on] == 0.0)
    assert np.array_equal(cold.e_m, plain.e_m)            # no thermal profile distortion in seed 004
    km_cold, km_std = cold.k_total_N_per_m()[0].mean(), plain.k_total_N_per_m()[0].mean()
    ts = th.thermal_slot_stiffness(cold_sc.pair, cold_sc.mesh, torque_Nm=cold_sc.operating.torque_Nm,
                                   states=[th.thermal_state_from_scene(cold_sc.thermal)],
                                   n_per_mesh=cold_sc.tables.points_per_mesh, slots=cold.slots)
    assert km_cold == pytest.approx(ts.k_N_per_m[0].sum(axis=0).mean(), rel=1e-12)
    assert km_cold < 0.95 * km_std
    assert cold.provenance["thermal"]["state"] == {"pinion_C": 10.0, "gear_C": 10.0}
    # the standard temperature written out is the standard table, bit for bit
    std = compute_tables(load_scene(base + "\n[thermal]\npinion_temperature_C = 30\n"))
    assert np.array_equal(std.k_N_per_m, plain.k_N_per_m)


def test_different_gear_temperatures_and_a_profile_without_axis():
    """Pinion on a profile along the LOA, gear uniform above t0 (seed 004 Fig. 6, CHOICE 1 and 5):
    the tables equal thermal_slot_stiffness at that ThermalState (each contact point at the
    local flank temperatures), and a profile differs from its mean (docs/thermal.md)."""
    from gearfmu.pipeline import compute_tables

    base = SCENE["I"].read_text().replace("slices = 25", "slices = 5")
    prof = compute_tables(load_scene(base + "\n[thermal]\npinion_profile_gamma = [-0.5, 0.5]\n"
                                            "pinion_profile_C = [60, 90]\ngear_temperature_C = 70\n"))
    sc = load_scene(base + "\n[thermal]\npinion_profile_gamma = [-0.5, 0.5]\npinion_profile_C = [60, 90]\n"
                           "gear_temperature_C = 70\n")
    st = th.thermal_state_from_scene(sc.thermal)
    ts = th.thermal_slot_stiffness(sc.pair, sc.mesh, torque_Nm=sc.operating.torque_Nm, states=[st],
                                   n_per_mesh=sc.tables.points_per_mesh, slots=prof.slots)
    reps = prof.n_phi // ts.k_N_per_m.shape[-1]
    np.testing.assert_allclose(prof.k_N_per_m[0], np.tile(ts.k_N_per_m[0], (1, reps)), rtol=1e-12, atol=0)
    mean_C = st.pinion.mean_C(pair_geometry(sc.pair))
    mean = compute_tables(load_scene(base + f"\n[thermal]\npinion_temperature_C = {mean_C!r}\n"
                                            "gear_temperature_C = 70\n"))
    d = prof.k_total_N_per_m()[0] / mean.k_total_N_per_m()[0] - 1.0
    assert np.max(np.abs(d)) > 1e-4                      # the distribution is not its mean
    assert prof.provenance["thermal"]["state"]["pinion_C"] == {"profile_gamma": [-0.5, 0.5],
                                                              "profile_C": [60.0, 90.0]}
