"""The native planetary solver against references no code of gearfmu.planetary produced.

* The event-located reference: gearfmu.planetary.reference.simulate_reference -- the same equations
  written again in plain Python over the pair reference's table pieces and force law, integrated by
  solve_ivp DOP853 at rtol 1e-10 with every table node and contact change of every mesh located as
  an event (no numba code shared).  Planetary hard cases of gearfmu.bench: contact loss in every
  mesh of a three-planet stage with backlash after a sudden unloading (sequential phases), four
  planets on a floating sun with a pin position error, and a carrier-driven stage (its meshes run
  their tables backwards) followed by a parallel stage.  The event-aware integrators (rk4_node, rk4_kink, rk4_seg) meet it within 5e-5 of each
  signal's range at the default step and within 5e-7 at a quarter of it (fourth order).
* The gearbox solver (gearfmu.gearbox.native): a drivetrain of parallel stages only is the
  gearbox's model; both solvers agree to 1e-9.
* Willis' equation (z_s (w_s - w_c) + z_r (w_r - w_c) = 0) from the tooth counts: the speeds of sun,
  carrier and ring, for each member held and either end driving, over 100 mesh periods of steady
  state with time-varying mesh stiffness, to 1e-12.
* Load sharing: equal among ideal, equally spaced planets (the mean over whole mesh periods with
  time-varying stiffness, sequential phases); with a planet's pin position error, the published
  result for a floating sun (A. Kahraman, *Load sharing characteristics of planetary transmissions*,
  Mech. Mach. Theory 29 (1994) 1151-1165; H. Ligata, A. Kahraman, A. Singh, *A closed-form planet load
  sharing formulation for planetary gear sets using a translational analogy*, J. Mech. Des. 131
  (2009) 021007): three planets share equally whatever the error (the floating sun's force balance
  leaves no other solution), four planets share in opposite pairs, L_1 = L_3, L_2 = L_4,
  L_1 + L_2 = 2; and the loads of every planet against the static solution of Lin & Parker's
  matrices (tests/unit/planetary/lin_parker.py) with the pin error as a pre-deflection of the planet bearing, to
  1e-9.
* Parker's phasing rule (R. G. Parker, *A physical explanation for the effectiveness of planet
  phasing to suppress planetary gear vibration*, J. Sound Vib. 236 (2000) 561-573): with N equally
  spaced planets the l-th mesh harmonic reaches the rotational response only when l z_s/N is an
  integer, the translational response (in the carrier frame) only when (l z_s +- 1)/N is; in the
  spectra of the outputs (steady state, 200 mesh periods sampled 40 times per period at the steady
  speed: 40 is a multiple of N, so that aliased harmonics keep their class) every harmonic the rule
  suppresses lies at least 60 dB below the largest one it lets through.
"""
import math

import numpy as np
import pytest

pytestmark = pytest.mark.slow  # builds or long runs: the full suite, not the quick subset

from gearfmu.gear.phasing import parker_harmonic_excitation
from gearfmu.gear.planetary_set import PlanetErrors
from gearfmu.gearbox.cases import gearbox_case
from gearfmu.gearbox.native import simulate as simulate_gearbox
from gearfmu.planetary.model import build_drivetrain
from gearfmu.planetary.native import output_units, simulate
from gearfmu.planetary.reference import simulate_reference
from gearfmu.bench import lp_stage, planetary_case, run_kwargs
from lin_parker import PUBLISHED, lin_parker_matrices, sun_mesh_vector

_REF = {}


def reference(case):
    if case not in _REF:
        model, kw = planetary_case(case, mesh_periods=10)
        _REF[case] = (model, kw, simulate_reference(model, **kw))
    return _REF[case]


def signals(model):
    return [f"{m}.{q}" for m in model.mesh_names for q in ("dte", "mesh_force")] + [
        f"{d}_speed" for d in ("lp.carrier", "lp.sun") if f"{d}_speed" in output_units(model)]


def worst(res, ref, names):
    return max(float(np.max(np.abs(res[n] - ref[n])) / np.ptp(ref[n])) for n in names)


@pytest.mark.parametrize("case", ["contact_loss", "position_error", "two_stage"])
def test_native_against_reference(case):
    model, kw, ref = reference(case)
    names = signals(model)
    for integrator in ("rk4_node", "rk4_kink", "rk4_seg"):
        r = simulate(model, **kw, integrator=integrator)
        assert worst(r, ref, names) <= 5e-5, integrator
        fine = simulate(model, **kw, integrator=integrator, max_step_s=r.step_s / 4)
        assert worst(fine, ref, names) <= 5e-7, integrator
    r4 = simulate(model, **kw, integrator="rk4", max_step_s=r.step_s / 4)
    assert worst(r4, ref, names) <= 5e-3


def test_the_cases_are_what_they_say():
    model, kw, ref = reference("contact_loss")
    for m in model.mesh_names:                        # every mesh loses contact now and then
        f = ref[f"{m}.mesh_force"]
        assert 1 <= np.sum(f == 0.0) < len(f) // 2, m
    model, kw, ref = reference("two_stage")           # the planetary meshes run their tables backwards
    stage_meshes = [i for i, m in enumerate(model.mesh_names) if m.startswith("lp.")]
    assert all(model.angle_ref[i] < 0 for i in stage_meshes)
    assert ref["lp.sun_planet[1].mesh_force"].min() > 0.0
    model, kw, ref = reference("position_error")      # planet 1, its pin behind, carries more
    lsf = [np.mean(ref[f"lp.load_sharing_factor[{n}]"]) for n in (1, 2, 3, 4)]
    assert lsf[0] > 1.2 and min(lsf) < 0.95


def test_a_drivetrain_of_parallel_stages_is_the_gearbox():
    gb, kw = gearbox_case("contact_loss", mesh_periods=12)
    motor = gb.inertia_kgm2[gb.part_body["motor"]] - 0.5 * gb.shafts[0].inertia_kgm2
    load = gb.inertia_kgm2[gb.part_body["load"]] - 0.5 * gb.shafts[-1].inertia_kgm2
    pm = build_drivetrain(gb.meshes, (), gb.shafts, {"motor": motor, "load": load})
    a = simulate_gearbox(gb, **kw)
    b = simulate(pm, **kw)
    for n in ("stage1.dte", "stage2.dte", "stage1.mesh_force", "stage2.mesh_force", "intermediate_shaft.force"):
        an = n.replace(".force", ".torque")
        assert float(np.max(np.abs(a[an] - b[n])) / np.ptp(a[an])) <= 1e-9, n
    assert float(np.max(np.abs(a["load_speed"] - b["load_speed"]))) <= 1e-9 * float(np.max(a["load_speed"]))


# ---------------------------------------------------------------- Willis
@pytest.mark.parametrize("held,motor,load", [("ring", "sun", "carrier"), ("ring", "carrier", "sun"),
                                             ("sun", "ring", "carrier"), ("sun", "carrier", "ring"),
                                             ("carrier", "sun", "ring"), ("carrier", "ring", "sun")])
def test_willis_speed_ratios_in_steady_state(held, motor, load):
    zs, zp, zr = 24, 36, 96
    st = lp_stage(4, contact_ratio_sun=1.6, contact_ratio_ring=1.7, held=held, bearing_damping_ratio=0.05)
    m = build_drivetrain(planetaries=[st], motor=f"lp.{motor}", load=f"lp.{load}")
    kw = run_kwargs(m, "lp.sun_planet[1]", 300.0, 50.0, 400, comm_per_mesh=8)
    r = simulate(m, **kw)
    last = slice(len(r.time_s) - 1 - 8 * 100, None)     # the last 100 mesh periods
    d = {p: r[f"lp.{p}_angle"][last][-1] - r[f"lp.{p}_angle"][last][0] for p in ("sun", "carrier", "ring")}
    scale = max(abs(d[p]) for p in d) * zr
    assert abs(zs * (d["sun"] - d["carrier"]) + zr * (d["ring"] - d["carrier"])) <= 1e-12 * scale
    assert abs(d[held]) <= 1e-12 * scale / zr


# ---------------------------------------------------------------- load sharing
def test_equal_load_sharing_of_ideal_equally_spaced_planets():
    """Five planets, sequential phases (24/5 not an integer), time-varying stiffness: each planet's
    mean sun-mesh force over whole mesh periods is the N-th of the sun torque over its base radius."""
    st = lp_stage(5, contact_ratio_sun=1.6, contact_ratio_ring=1.7, bearing_damping_ratio=0.05, gamma_rs=0.3)
    m = build_drivetrain(planetaries=[st], motor="lp.sun", load="lp.carrier")
    P = 40
    kw = steady_kwargs(m, 500.0, 100.0, P)
    r = simulate(m, **kw)
    last = slice(len(r.time_s) - P * 200, None)
    F = [np.mean(r[f"lp.sun_planet[{n}].mesh_force"][last]) for n in range(1, 6)]
    for n in range(1, 6):
        assert np.mean(r[f"lp.load_sharing_factor[{n}]"][last]) == pytest.approx(1.0, abs=1e-6)
        assert F[n - 1] == pytest.approx(F[0], rel=1e-6)
    # together they carry the sun torque (the mean of 40 samples a period of a force with steps: 1e-3)
    assert sum(F) * st.base_radius_sun_m == pytest.approx(100.0, rel=1e-3)
    # the instantaneous factors differ (the meshes are out of phase) ...
    assert np.ptp(r["lp.load_sharing_factor[1]"][last]) > 0.05


#: a run whose first row is the static state at (almost) no speed: no centripetal forces
STATIC = dict(stop_time_s=1e-5, comm_step_s=1e-5, motor_speed_start_rad_s=1e-9)


def pin_error_model(N, e_t, k_sun=0.0):
    errs = (PlanetErrors(0.0, e_t),) + (PlanetErrors(),) * (N - 1)
    st = lp_stage(N, planet_errors=errs, bearing_N_per_m=dict(sun=k_sun, ring=1e8, carrier=1e8, planet=1e8))
    return st, build_drivetrain(planetaries=[st], motor="lp.sun", load="lp.carrier")


def static_sun_mesh_forces(N, e_t, T, rs, k_sun=0.0):
    """Lin & Parker's static problem: K q = f, the carrier's rotation u_c held (it carries the load
    torque), the sun torque T as the force T/r_s on u_s, planet 1's pin error as its bearing's
    pre-deflection; returns k_sp delta_sn of every planet."""
    M, K, f = lin_parker_matrices(N, pin_errors=[(0.0, e_t)] + [(0.0, 0.0)] * (N - 1), k_bearing={"s": k_sun})
    f[8] += T / rs
    free = [i for i in range(K.shape[0]) if i != 2]
    q = np.zeros(K.shape[0])
    q[free] = np.linalg.solve(K[np.ix_(free, free)], f[free])
    return np.array([PUBLISHED["k_sp"] * sun_mesh_vector(N, n) @ q for n in range(N)])


@pytest.mark.parametrize("N,k_sun", [(3, 0.0), (4, 0.0), (4, 1e8), (5, 1e8)])
def test_load_sharing_with_a_pin_position_error_against_the_static_solution(N, k_sun):
    e_t, T = -20e-6, 100.0                     # planet 1's pin 20 um behind its place (clockwise), 100 N m on the sun
    st, m = pin_error_model(N, e_t, k_sun)
    r = simulate(m, **STATIC, motor_torque_Nm=T)
    F = static_sun_mesh_forces(N, e_t, T, st.base_radius_sun_m, k_sun)
    lsf = np.array([r[f"lp.load_sharing_factor[{n + 1}]"][0] for n in range(N)])    # the static state
    np.testing.assert_allclose(lsf, N * F / F.sum(), rtol=1e-9)
    np.testing.assert_allclose([r[f"lp.sun_planet[{n + 1}].mesh_force"][0] for n in range(N)], F, rtol=1e-9)
    if N == 3 and k_sun == 0.0:                # Kahraman 1994, Ligata et al. 2009: a floating sun shares
        np.testing.assert_allclose(lsf, 1.0, atol=1e-9)     # three planets' loads equally
    if N == 4 and k_sun == 0.0:                # ... four in opposite pairs
        assert lsf[0] == pytest.approx(lsf[2], abs=1e-9) and lsf[1] == pytest.approx(lsf[3], abs=1e-9)
        assert lsf[0] + lsf[1] == pytest.approx(2.0, abs=1e-9) and lsf[0] > 1.05
    if k_sun > 0.0:                            # a held sun cannot even the loads out: planet 1, nearer the
        assert lsf[0] > 1.1 and lsf[0] == max(lsf)     # sun it drives (counter-clockwise), carries more


def test_load_sharing_factor_with_a_floating_sun_grows_with_the_error_over_the_torque():
    """The closed form of Ligata et al. 2009 for four planets on a floating sun: L_1 = 1 - c e/T with
    c fixed by the stiffnesses (linear in the error, inverse in the torque; e < 0 behind its place)."""
    out = {}
    for e_t, T in ((-10e-6, 100.0), (-20e-6, 100.0), (-20e-6, 200.0)):
        st, m = pin_error_model(4, e_t)
        r = simulate(m, **STATIC, motor_torque_Nm=T)
        out[(e_t, T)] = 1.0 - r["lp.load_sharing_factor[1]"][0]
    assert out[(-20e-6, 100.0)] == pytest.approx(2.0 * out[(-10e-6, 100.0)], rel=1e-9)
    assert out[(-20e-6, 200.0)] == pytest.approx(out[(-10e-6, 100.0)], rel=1e-9)


# ---------------------------------------------------------------- Parker's phasing rule
def steady_kwargs(m, speed, torque, P, periods=600):
    """Run arguments whose communication step is 1/P of the mesh period at the steady speed (a first
    run finds it: the start transient changes the speed a little)."""
    kw = run_kwargs(m, "lp.sun_planet[1]", speed, torque, periods, comm_per_mesh=P)
    r = simulate(m, **kw)
    w = float(np.mean(r["lp.sun_speed"][-P * 200:]))
    return run_kwargs(m, "lp.sun_planet[1]", w, torque, periods, comm_per_mesh=P, motor_speed_start_rad_s=speed)


@pytest.mark.parametrize("N,teeth", [(5, (24, 36, 96)), (4, (25, 35, 95))])
def test_parker_phasing_rule_in_the_output_spectra(N, teeth):
    zs, zp, zr = teeth
    st = lp_stage(N, teeth_sun=zs, teeth_planet=zp, teeth_ring=zr, contact_ratio_sun=1.6, contact_ratio_ring=1.7,
                  bearing_damping_ratio=0.05, gamma_rs=0.3)
    m = build_drivetrain(planetaries=[st], motor="lp.sun", load="lp.carrier")
    P, K, H = 40, 200, 10
    r = simulate(m, **steady_kwargs(m, 500.0, 100.0, P))
    kind = [parker_harmonic_excitation(l, zs, N) for l in range(1, H + 1)]
    assert {"rotational", "translational", "planet"} <= set(kind)

    def harmonics(name):
        x = r[name][-K * P:]
        X = np.abs(np.fft.rfft(x - x.mean())) / len(x)
        return np.array([X[l * K] for l in range(1, H + 1)])

    for name, passes in (("lp.ring_support.force", "rotational"), ("lp.sun_speed", "rotational"),
                         ("lp.carrier_speed", "rotational"), ("lp.sun_x", "translational"),
                         ("lp.ring_y", "translational"), ("lp.carrier_x", "translational")):
        h = harmonics(name)
        through = max(h[i] for i in range(H) if kind[i] == passes)
        stopped = max(h[i] for i in range(H) if kind[i] != passes)
        assert 20 * math.log10(stopped / through) <= -60.0, (name, h)
    # a single mesh sees every harmonic
    h = harmonics("lp.sun_planet[1].dte")
    assert min(h[:4]) > 1e-3 * max(h)


@pytest.mark.parametrize("model", ["translational", "torsional"])
def test_the_static_state_with_backlash_presses_the_drive_flanks(model):
    """Backlash (40 um on each flank) much larger than the mesh deflection, a floating sun: the initial
    state still puts every mesh on its drive flank with the static load, T_s/(N r_s) on each sun mesh
    (statics)."""
    st = lp_stage(3, contact_ratio_sun=1.6, contact_ratio_ring=1.7, backlash_half_m=40e-6, model=model,
                  bearing_N_per_m=dict(sun=0.0, ring=1e8, carrier=1e8, planet=1e8))
    m = build_drivetrain(planetaries=[st], motor="lp.sun", load="lp.carrier")
    T = 100.0
    r = simulate(m, **STATIC, motor_torque_Nm=T)
    for n in (1, 2, 3):
        assert r[f"lp.sun_planet[{n}].mesh_force"][0] == pytest.approx(T / 3 / st.base_radius_sun_m, rel=1e-9)
        assert r[f"lp.sun_planet[{n}].dte"][0] > 40e-6 and r[f"lp.ring_planet[{n}].dte"][0] > 40e-6
