"""Tests of the transient line-contact EHL extension (docs/ehl_transient.md).

References (none produced by this code):
* T0: the steady solver's own path is unchanged when the time coefficient is
  0 -- the bitwise reference is the steady iteration without the option
  (the old-vs-new module comparison is in docs/ehl_transient.md "Status");
* the discretised transient Reynolds operator written out by hand in numpy
  from seed 000 eq 2 (BDF1/BDF2 formulas of any numerical analysis text,
  e.g. Hairer & Wanner, *Solving ODEs II*, sec. V.1);
* T1, T2: a stationary state has d(rho H)/dT = 0 exactly (BDF1 and BDF2 of a
  constant are 0), so the steady solution solves the transient equations
  (smooth at any SRR; rough with the roughness frozen, U1 = U2 = 0);
* T3: a harmonic waviness under pure rolling gives a time-periodic film
  (period lambda/u_s): two successive periods agree;
* T4-T6: Venner, Couhier, Lubrecht & Greenwood (1997), "Amplitude reduction of
  waviness in transient EHL line contacts", Tribology Series 32, 103-112: the
  deformed amplitude A_d/A_i is independent of A_i and a single function of
  nabla = (lambda/b) M^(3/4)/L^(1/2); short waves (small nabla) pass almost
  undeformed, long ones nearly vanish (thresholds are CHOICES of
  docs/ehl_transient.md section 4 turning the abstract's words into numbers).
"""
import math

import numpy as np
import pytest

from gearfmu.ehl import solve_line_contact
from gearfmu.ehl.mgkernels import _coef, _residual
from gearfmu.ehl.multigrid import FlatMultigrid
from gearfmu.ehl.iterate import flat_options

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow


def _flat_from_result(res, prm_from):
    """FlatMultigrid on the grid of ``res`` started from its converged pressure."""
    prm, n_levels, n_coarse = prm_from
    opts = flat_options(res.residuals["settings"])
    fm = FlatMultigrid(prm, n_levels, n_coarse, None, **opts)
    Hc = float(np.interp(0.0, res.X, res.H))
    fm.start(res.P, Hc)
    return fm


def _params(res):
    """EHLParams of a steady result (the formulas of solve_line_contact, Roelands)."""
    from gearfmu.ehl.lubricant import DH_C1_PA, ROELANDS_LN_ETA_INF, ROELANDS_P0_PA
    from gearfmu.ehl.multigrid import EHLParams
    A = math.log(res.inputs["eta0_Pas"]) - ROELANDS_LN_ETA_INF
    return EHLParams(lam=3.0 * math.pi ** 2 / (8.0 * res.M ** 2), A=A,
                     z=res.inputs["alpha_Pa_inv"] * ROELANDS_P0_PA / A,
                     php0=res.ph_Pa / ROELANDS_P0_PA, c1=DH_C1_PA / res.ph_Pa,
                     compressible=True, x_in=float(res.X[0]), x_out=float(res.X[-1]))


def _steady_problem(M=20.0, L=10.0, n_nodes=257):
    res = solve_line_contact(M=M, L=L, n_nodes=n_nodes, tol_pressure=1e-9, tol_residual=1e-9,
                             tol_load=1e-10, max_cycles=200)
    n_levels = res.grid_levels
    n_coarse = (n_nodes - 1) // 2 ** (n_levels - 1)
    return res, (_params(res), n_levels, n_coarse)


_WAVES = {}


def _wave(*args, **kw):
    """:func:`gearfmu.ehl.transient.waviness_amplitude_ratio`, run once per argument set in this
    file (a copy of its result each time): it is deterministic, and T3, T6 and the scheme test
    ask for the same lambda = 0.5 b wave, T6 and the sub-step test for the same lambda = b wave."""
    import inspect
    from gearfmu.ehl.transient import waviness_amplitude_ratio
    bound = inspect.signature(waviness_amplitude_ratio).bind(*args, **kw)
    bound.apply_defaults()
    key = repr(sorted(bound.arguments.items()))
    if key not in _WAVES:
        _WAVES[key] = waviness_amplitude_ratio(*args, **kw)
    return dict(_WAVES[key])


# ------------------------------------------------------------------------- T0
def test_T0_time_term_zero_is_bitwise_the_steady_iteration():
    # Reference: the steady compiled W-cycles with the default options (c_t
    # absent) -- setting the time coefficient to 0 explicitly, with a zero
    # old-time right-hand side, must take exactly the same floating-point path.
    res = solve_line_contact(M=20.0, L=10.0, n_nodes=257)
    _res, pf = _steady_problem()
    a = _flat_from_result(res, pf)
    b = _flat_from_result(res, pf)
    b.set_time_term(0.0, np.zeros(a.level_P().size))
    # perturb both identically so that the cycles have work to do
    for s in (a, b):
        s.P[s._sl(s.top)] *= 1.01
        s.update_film(s.top)
    ka = a.iterate(max_cycles=6, min_cycles=6)
    kb = b.iterate(max_cycles=6, min_cycles=6)
    assert ka[1] == kb[1] == 6
    assert np.array_equal(a.level_P(), b.level_P())
    assert np.array_equal(a.level_H(), b.level_H())
    assert ka[2]["reynolds_residual"] == kb[2]["reynolds_residual"]


# ------------------------------------------------------------------------- operator
@pytest.mark.parametrize("order2,char", [(0, False), (1, False), (1, True)])
def test_transient_residual_equals_hand_written_operator(order2, char):
    # Reference: seed 000 eq 2 discretised by hand (numpy, not the kernel):
    # L_i = [e_{i-1/2}(P_{i-1}-P_i) + e_{i+1/2}(P_{i+1}-P_i)]/dX^2
    #       - D_X(rho H)_i - c_t (rho H)_i,   residual f_i - L_i
    # (characteristic scheme: without D_X(rho H)_i, the shifted old levels in f).
    res, pf = _steady_problem()
    fm = _flat_from_result(res, pf)
    rng = np.random.default_rng(3)
    sl = fm._sl(fm.top)
    fm.P[sl] *= 1.0 + 0.05 * rng.standard_normal(sl.stop - sl.start)
    fm.P[sl] = np.clip(fm.P[sl], 0, None)
    fm.update_film(fm.top)
    ct = 1.5 / fm.dx[fm.top]
    f_top = rng.standard_normal(sl.stop - sl.start)
    fm.set_time_term(ct, f_top)
    rho, eps, dle, drho, delta, wrk = fm.work[:6]
    _coef(fm.top, fm.P, fm.H, rho, eps, dle, drho, fm.iarr, fm.prmv)
    _residual(fm.top, fm.P, fm.H, fm.f, rho, eps, wrk, fm.iarr, fm.dx, bool(order2), ct, char)
    P, H, r, e = fm.P[sl], fm.H[sl], rho[sl], eps[sl]
    dX = fm.dx[fm.top]
    rH = r * H
    ref = np.zeros_like(P)
    for i in range(1, P.size - 1):
        em, ep = 0.5 * (e[i - 1] + e[i]), 0.5 * (e[i] + e[i + 1])
        poi = (em * (P[i - 1] - P[i]) + ep * (P[i + 1] - P[i])) / dX ** 2
        if order2 and i >= 2:
            wedge = (1.5 * rH[i] - 2 * rH[i - 1] + 0.5 * rH[i - 2]) / dX
        else:
            wedge = (rH[i] - rH[i - 1]) / dX
        if char:        # characteristic scheme: the time term replaces the wedge
            wedge = 0.0
        ref[i] = fm.f[sl][i] - (poi - wedge - ct * rH[i])
    np.testing.assert_allclose(wrk[sl], ref, rtol=1e-12, atol=1e-9 * np.abs(ref).max())


# ------------------------------------------------------------------------- T1 (kernel)
@pytest.mark.parametrize("scheme", ["bdf1", "bdf2"])
def test_T1_kernel_stationary_state_is_a_transient_solution(scheme):
    # Reference: d(rho H)/dT of a constant state is 0 for BDF1 and BDF2, so the
    # converged steady solution must stay put (within the iteration
    # tolerance) when the time term is switched on with old levels = it.
    res, pf = _steady_problem()
    fm = _flat_from_result(res, pf)
    dT = fm.dx[fm.top]
    rH = fm.rho_H()
    if scheme == "bdf1":
        fm.set_time_term(1.0 / dT, -rH / dT)
    else:
        fm.set_time_term(1.5 / dT, (-2.0 * rH + 0.5 * rH) / dT)
    P0, H0 = fm.level_P().copy(), fm.level_H().copy()
    ok, nc, h = fm.iterate(max_cycles=20, min_cycles=3, tol_pressure=1e-9, tol_load=1e-10,
                           tol_residual=1e-9)
    assert ok, h
    hc0 = float(np.interp(0.0, res.X, H0))
    hc1 = float(np.interp(0.0, res.X, fm.level_H()))
    assert abs(hc1 - hc0) / hc0 < 1e-6
    assert abs(fm.level_H().min() - H0.min()) / H0.min() < 1e-6
    assert np.max(np.abs(fm.level_P() - P0)) < 1e-6
    # the time term is active: with a zero old-time right-hand side (an
    # empty gap at T = -dT) the same state is no longer a solution
    fm.set_time_term(1.0 / dT, None)
    fm.iterate(max_cycles=3, min_cycles=3)
    assert np.max(np.abs(fm.level_P() - P0)) > 1e-3


# ------------------------------------------------------------------------- T1
@pytest.mark.parametrize("scheme", ["characteristic", "bdf2"])
@pytest.mark.parametrize("srr", [0.0, 0.5, -0.5])
def test_T1_smooth_transient_stays_on_the_steady_solution(srr, scheme):
    # Reference: smooth surfaces -> nothing depends on T; BDF of a constant is 0
    # (and the characteristic scheme of a stationary film is the steady wedge).
    from gearfmu.ehl.transient import solve_line_contact_transient
    tight = dict(tol_pressure=1e-9, tol_load=1e-10, tol_residual=1e-9)
    r = solve_line_contact_transient(M=20.0, L=10.0, n_nodes=257, srr=srr, n_steps=50,
                                     scheme=scheme, steady_options=dict(max_cycles=200), **tight)
    s = r.steady
    assert r.T.size == 51 and r.T[-1] == pytest.approx(50 * r.dT)
    assert r.dT == pytest.approx(6.0 / 256)                    # default dT = dX
    assert (r.U1, r.U2) == pytest.approx((1 + srr / 2, 1 - srr / 2))
    assert np.max(np.abs(r.h_central_m / s.h_central_m - 1)) < 1e-6
    assert np.max(np.abs(r.h_min_m / s.h_min_m - 1)) < 1e-6
    assert np.max(np.abs(r.p_Pa - s.p_Pa)) / s.ph_Pa < 1e-6
    red = r.film_stiffness_reductions(T_start=0.0)
    assert red["k_mean_of_k_N_per_m"] == pytest.approx(red["k_of_means_N_per_m"], rel=1e-6)


# ------------------------------------------------------------------------- T2
def _seed000_pitch():
    from pathlib import Path
    from gearfmu.contact.models import RoughnessSpec
    from gearfmu.scene.physics import environment_from_scene
    from gearfmu.gear.geometry import pair_geometry
    from gearfmu.scene.reader import load_scene
    sc = load_scene(Path(__file__).resolve().parents[3] / "examples" / "scenes" /
                    "seed000_table1.toml")
    g = pair_geometry(sc.pair)
    env = environment_from_scene(sc, roughness=RoughnessSpec.from_level(1), max_workers=1)
    w = sc.operating.torque_Nm / g.rb1_m / sc.pair.pinion.face_width_m
    return env, g.s_pitch_m, w


def test_T2_frozen_level1_roughness_equals_the_steady_rough_solve():
    # Reference: with U1 = U2 = 0 the rough gap does not move, so the steady
    # frozen-roughness film (seed 000 Table 1 pair, pitch point, level 1,
    # slice 0) is a stationary state of the transient equations.
    from gearfmu.ehl.film_stiffness import slice_film_stiffness_N_per_m
    from gearfmu.ehl.transient import flank_slice_case, solve_line_contact_transient
    env, s, w = _seed000_pitch()
    kw = flank_slice_case(env, s, w, 0)
    assert kw["srr"] == pytest.approx(0.0, abs=1e-12)           # pitch point: pure rolling
    kw.pop("srr")
    tight = dict(tol_pressure=1e-9, tol_load=1e-10, tol_residual=1e-9)
    r = solve_line_contact_transient(n_nodes=257, n_steps=20, speed_ratios=(0.0, 0.0),
                                     steady_options=dict(max_cycles=200), **tight, **kw)
    st = r.steady
    k_st = slice_film_stiffness_N_per_m(st, env.width_m, "seed")
    assert np.std(st.roughness_m) > 0.02 * st.h_central_m       # rough: sigma/h_c = 0.037
    assert np.max(np.abs(r.h_central_m / st.h_central_m - 1)) < 1e-5
    assert np.max(np.abs(r.k_film_N_per_m / k_st - 1)) < 1e-5
    # moving roughness (U1 = U2 = 1) is not stationary: the film changes
    kw2 = dict(kw, srr=0.0)
    r2 = solve_line_contact_transient(n_nodes=257, n_steps=20, **kw2)
    assert np.max(np.abs(r2.h_central_m / st.h_central_m - 1)) > 1e-3


# ------------------------------------------------------------------------- T3
def test_T3_pure_rolling_waviness_reaches_a_periodic_state():
    # Reference: periodic forcing of period lambda/(b U) in T -> periodic film.
    # Characteristic scheme, lambda = 21 dX = 0.492 b; measured defect 1.1e-6 H_c.
    d = _wave(20.0, 10.0, 0.5, 0.1, n_nodes=257)
    assert d["scheme"] == "characteristic"
    assert d["wavelength_b"] == pytest.approx(21 * 6.0 / 256)
    assert d["periodicity_defect"] < 1e-4
    assert d["cycles_per_step"] < 10                            # measured 5.1


def test_T3b_smooth_start_with_ramp_reaches_the_same_periodic_state():
    # Reference: the periodic state does not depend on the start (start-up error
    # leaves the domain with the surfaces): frozen start vs smooth start with the
    # waviness ramped in over T = 1; last period compared point by point.
    from gearfmu.ehl.transient import HarmonicWaviness, solve_line_contact_transient
    s = solve_line_contact(M=20.0, L=10.0, n_nodes=257)
    wav = HarmonicWaviness(0.1 * s.h_central_m, 0.5 * s.b_m)
    k = 24
    dT = 0.5 / k
    n = int(math.ceil((1.0 + 6.0) / dT)) + k
    a = solve_line_contact_transient(M=20.0, L=10.0, n_nodes=257, roughness=wav, dT=dT, n_steps=n)
    b = solve_line_contact_transient(M=20.0, L=10.0, n_nodes=257, roughness=wav, dT=dT, n_steps=n,
                                     start="smooth", ramp_T=1.0)
    assert a.start == "frozen" and b.start == "smooth" and b.T_settled == pytest.approx(7.0)
    assert b.h_central_m[0] == pytest.approx(s.h_central_m, rel=1e-4)    # smooth at T = 0
    assert np.max(np.abs(a.h_central_m[-k:] - b.h_central_m[-k:])) < 1e-4 * s.h_central_m


# ------------------------------------------------------------------------- T4-T6
# Default (characteristic) scheme on 257 nodes; wavelengths are rounded to whole
# steps per period by waviness_amplitude_ratio (the nabla used is returned).
def test_T4_amplitude_ratio_does_not_depend_on_the_amplitude():
    # Reference: Venner et al. 1997 -- A_d/A_i independent of A_i.
    # Measured: 0.6122 (A_i = 0.05 H_c), 0.6127 (0.2 H_c), lambda = 1.008 b.
    a = _wave(20.0, 10.0, 1.0, 0.05)["ratio"]
    b = _wave(20.0, 10.0, 1.0, 0.2)["ratio"]
    assert abs(a - b) < 0.02
    assert 0.2 < a < 0.95                                       # a real reduction


def test_T5_amplitude_ratio_collapses_on_nabla():
    # Reference: Venner et al. 1997 -- A_d/A_i = F(nabla) for all (M, L), nabla =
    # (lambda/b) M^(3/4)/L^(1/2).  Two loads at nabla ~ 2.93-2.94 (42 and 21 grid
    # steps per wavelength).  Measured: 0.623 (M = 20, nabla 2.944), 0.635 (M = 50, nabla 2.927).
    a = _wave(20.0, 10.0, 42 * 6.0 / 256, 0.1)
    b = _wave(50.0, 10.0, 21 * 6.0 / 256, 0.1)
    assert a["nabla"] == pytest.approx(b["nabla"], rel=0.01)
    assert abs(a["ratio"] - b["ratio"]) < 0.05


def test_T6_amplitude_ratio_limits_and_monotone():
    # Reference: Venner et al. 1997 -- short waves hardly deformed, long waves
    # nearly vanish.  CHOICE thresholds (docs/ehl_transient.md section 4): > 0.9 at
    # lambda = 0.25 b, < 0.2 at nabla >= 20, monotone in between (M = 20, L = 10).
    # Measured: 0.967, 0.896, 0.612, 0.325, 0.072 at
    # nabla 0.77, 1.47, 3.0, 6.0, 20.0.
    scan = [_wave(20.0, 10.0, lam, 0.1) for lam in (0.25, 0.5, 1.0, 2.0, 6.7)]
    rat = [d["ratio"] for d in scan]
    assert scan[0]["wavelength_b"] == pytest.approx(11 * 6.0 / 256) and rat[0] > 0.9
    assert scan[-1]["nabla"] >= 20.0 and rat[-1] < 0.2
    assert all(x > y for x, y in zip(rat[:-1], rat[1:])), rat


def test_characteristic_scheme_removes_the_numerical_damping_of_bdf2():
    # Reference: grid convergence -- the same wave (lambda = 21 dX on 257 nodes =
    # 42 dX on 513 nodes = 0.492 b, M = 20, L = 10).  The characteristic scheme
    # shifts the film wave exactly at Courant 1: 257 and 513 nodes agree within
    # 0.01; BDF2 with the upwind wedge damps it numerically on 257 nodes
    # (docs/ehl_transient.md 6.3; measured 0.8957 (257), 0.8919
    # (513), BDF2 0.7735 on 257).
    c257 = _wave(20.0, 10.0, 0.5, 0.1)
    c513 = _wave(20.0, 10.0, c257["wavelength_b"], 0.1, n_nodes=513)
    b257 = _wave(20.0, 10.0, c257["wavelength_b"], 0.1, scheme="bdf2")
    assert c513["wavelength_b"] == pytest.approx(c257["wavelength_b"], rel=1e-12)
    assert abs(c257["ratio"] - c513["ratio"]) < 0.01
    assert c513["ratio"] - b257["ratio"] > 0.05


# ------------------------------------------------------------------------- errors
def test_bad_inputs_name_the_field():
    from gearfmu.ehl import EHLInputError
    from gearfmu.ehl.transient import HarmonicWaviness, solve_line_contact_transient
    with pytest.raises(EHLInputError, match="wavelength_m"):
        HarmonicWaviness(1e-7, 0.0)
    with pytest.raises(EHLInputError, match="surfaces"):
        HarmonicWaviness(1e-7, 1e-4, surfaces=(3,))
    with pytest.raises(EHLInputError, match="srr"):
        solve_line_contact_transient(M=20.0, L=10.0, srr=3.0)
    with pytest.raises(EHLInputError, match="scheme"):
        solve_line_contact_transient(M=20.0, L=10.0, scheme="cn")
    with pytest.raises(EHLInputError, match="roughness"):
        solve_line_contact_transient(M=20.0, L=10.0, roughness=42)
    with pytest.raises(EHLInputError, match="dT"):
        solve_line_contact_transient(M=20.0, L=10.0, n_nodes=257, dT=0.01, scheme="characteristic")
    with pytest.raises(EHLInputError, match="start"):
        solve_line_contact_transient(M=20.0, L=10.0, start="cold")
    with pytest.raises(EHLInputError, match="n_steps"):
        solve_line_contact_transient(M=20.0, L=10.0, n_nodes=257, n_steps=0)


def test_stalled_step_names_step_time_and_residual():
    from gearfmu.ehl import EHLConvergenceError
    from gearfmu.ehl.transient import HarmonicWaviness, solve_line_contact_transient
    s = solve_line_contact(M=20.0, L=10.0, n_nodes=257)
    wav = HarmonicWaviness(0.1 * s.h_central_m, 0.5 * s.b_m)
    with pytest.raises(EHLConvergenceError, match=r"transient step 1 of 5 \(T = 0.02344.*residual"):
        solve_line_contact_transient(M=20.0, L=10.0, n_nodes=257, roughness=wav, n_steps=5,
                                     max_cycles_per_step=1,
                                     relaxation_settings=[dict(switch=0.3, dist=1)])


# ------------------------------------------------------------------------- sub-step rescue
def test_substep_rescue_path_keeps_a_stationary_film():
    # Reference: as T1 -- a stationary film has d(rho H)/dT = 0, and the
    # rescue's variable-step BDF2 (coefficients (1 + 2w)/(1 + w), -(1 + w),
    # w^2/(1 + w), w = 1/2, summing to 0: Hairer, Norsett & Wanner, *Solving
    # ODEs I*, sec. III.5) and uniform BDF2 sub-steps of a constant are 0.
    # substep_rescue="always" solves every step as 2 sub-steps (the path a
    # stalled step takes, docs/ehl_transient.md 6.7); measured 1.5e-9 p_h.
    from gearfmu.ehl.transient import solve_line_contact_transient
    tight = dict(tol_pressure=1e-9, tol_load=1e-10, tol_residual=1e-9)
    r = solve_line_contact_transient(M=20.0, L=10.0, n_nodes=257, srr=0.5, n_steps=20,
                                     substep_rescue="always",
                                     steady_options=dict(max_cycles=200), **tight)
    s = r.steady
    assert np.all(r.rescued[1:] == 2) and r.rescued[0] == 0
    assert np.max(np.abs(r.h_central_m / s.h_central_m - 1)) < 1e-6
    assert np.max(np.abs(r.h_min_m / s.h_min_m - 1)) < 1e-6
    assert np.max(np.abs(r.p_Pa - s.p_Pa)) / s.ph_Pa < 1e-6


def test_substep_rescue_path_gives_the_same_amplitude_reduction():
    # Reference: Venner et al. 1997's A_d/A_i is a property of the continuous
    # equations, not of the time discretisation: the rescue path (2 BDF2
    # sub-steps per step, dT/2 = dX/2) and the characteristic scheme must agree
    # at lambda = b (43 nodes per wavelength, where BDF2 is grid-converged,
    # docs/ehl_transient.md 6.3).  Measured: 0.6131 (sub-steps) vs 0.6122
    # (characteristic); tolerance 0.005 (the 257-vs-513 spread of 6.3 is 0.004).
    c = _wave(20.0, 10.0, 1.0, 0.1)
    s = _wave(20.0, 10.0, 1.0, 0.1, substep_rescue="always")
    assert s["wavelength_b"] == c["wavelength_b"]
    assert abs(s["ratio"] - c["ratio"]) < 0.005


def test_substep_rescue_bad_value_names_the_field():
    from gearfmu.ehl import EHLInputError
    from gearfmu.ehl.transient import solve_line_contact_transient
    with pytest.raises(EHLInputError, match="substep_rescue"):
        solve_line_contact_transient(M=20.0, L=10.0, n_nodes=257, substep_rescue="sometimes")


# ------------------------------------------------------------------------- seed 000 Fig. 13
def test_seed000_fig13_film_stiffness_falls_with_the_roughness_level_at_the_pitch_point():
    # Reference: seed 000 Fig. 13 and its text (qualitative): the film (and mesh)
    # stiffness of rough flanks is below the smooth one and falls with the
    # roughness level.  No number is taken from the figure; only the ordering is
    # asserted.  Seed 000 Table 1 pair at the pitch point (SRR = 0), nominal load,
    # slices 0 and 1 of the level's flank roughness, 256 intervals, transient from
    # T = 0 (start 'auto') to T_settled + 8, reduction (b) = seed 000 eq 8 on the
    # window means <h_m>, <p_m>, as a ratio to the smooth steady film on the same grid
    # (smooth transient = 1 by T1).
    # Measured (one run; mean of slices 0-1):
    #   256 intervals: smooth 1.0000025, level 1 0.998684, level 2 0.964667
    #   512 intervals: smooth 1.0000081, level 1 0.998693, level 2 0.965233
    # Margins at 256: smooth - level 1 = 1.3e-3, level 1 - level 2 = 0.034; the
    # discretisation error (256 vs 512) is 5.6e-6 / 9e-6 / 5.7e-4 -- the margins are
    # 150x and 60x larger, so the ordering is resolved (docs/ehl_transient.md 6.8).
    from pathlib import Path
    from gearfmu.contact.models import RoughnessSpec
    from gearfmu.scene.physics import environment_from_scene
    from gearfmu.ehl.film_stiffness import slice_film_stiffness_N_per_m
    from gearfmu.ehl.transient import flank_slice_case, solve_line_contact_transient
    from gearfmu.gear.geometry import pair_geometry
    from gearfmu.scene.reader import load_scene
    sc = load_scene(Path(__file__).resolve().parents[3] / "examples" / "scenes" /
                    "seed000_table1.toml")
    g = pair_geometry(sc.pair)
    w = sc.operating.torque_Nm / g.rb1_m / sc.pair.pinion.face_width_m
    n_nodes, T_avg = 257, 8.0

    def k_b(env, j):
        kw = flank_slice_case(env, g.s_pitch_m, w, j)
        T_wash = 6.0 / min(1 + kw["srr"] / 2, 1 - kw["srr"] / 2)
        n_steps = int(math.ceil((1.0 + T_wash + T_avg) / (6.0 / (n_nodes - 1))))
        r = solve_line_contact_transient(n_nodes=n_nodes, n_steps=n_steps, start="auto",
                                         ramp_T=1.0, **kw)
        return r.film_stiffness_reductions(r.T_settled, r.T_settled + T_avg)["k_of_means_N_per_m"]

    env = {lv: environment_from_scene(sc, roughness=RoughnessSpec.from_level(lv), max_workers=1)
           for lv in (1, 2)}
    kw0 = flank_slice_case(env[1], g.s_pitch_m, w, None)
    sm = solve_line_contact(*(kw0[k] for k in ("R_m", "E_Pa", "w_N_per_m", "u_m_s", "eta0_Pas",
                                               "alpha_Pa_inv", "rho0_kg_m3")), n_nodes=n_nodes)
    k_s = slice_film_stiffness_N_per_m(sm, kw0["width_m"], "seed", kw0["B0_Pa"], kw0["B0_prime"])
    k_smooth = k_b(env[1], None) / k_s
    k1 = np.mean([k_b(env[1], j) for j in (0, 1)]) / k_s
    k2 = np.mean([k_b(env[2], j) for j in (0, 1)]) / k_s
    assert k_smooth == pytest.approx(1.0, abs=1e-5)          # T1
    assert k2 < k1 < k_smooth, (k_smooth, k1, k2)
