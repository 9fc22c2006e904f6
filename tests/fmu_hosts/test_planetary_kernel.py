"""The planetary drivetrain kernel in C (gearfmu/fmu/kernel/plkernel.h, pl_kernel.c, pl_static.c) against
references its C code did not produce.

* The numba planetary solver (gearfmu.planetary.native.simulate; gearfmu/planetary/kernels.py), the same
  equations written in another language with the same order of floating-point operations: the kernel
  stepped by pl_do_step at the native communication step from the native initial state reproduces the
  native state after the run and every native output column (DOF coordinates and rates, every mesh's
  DTE, its rate, force, stiffness, pair forces and load sharings, every spring force, every planet's
  load-sharing factor) BIT FOR BIT (np.array_equal), for 'rk4', 'rk4_kink', 'rk4_node' and 'rk4_seg', on: the
  example reducer examples/scenes/planetary_reducer.toml (a translational planetary stage with a
  floating sun and a parallel stage), Lin & Parker's (1999) four-planet system of
  examples/scenes/planetary_lin_parker.toml (translational), a torsional stage (Kahraman 1994's purely
  torsional model), a stage with a planet position error (gearfmu.bench 'position_error'), the same
  stage driven by its load torque alone (the motor end no torque input) and a run with contact loss
  (gearfmu.bench 'contact_loss': the torque drops, the backlash opens).
* PlanetaryModel.static_state (numpy's LAPACK solve in Newton's method): pl_initialize within 1e-12 of
  the largest deviation of each kind (rotations, translations); 1e-10 with supports of 1e13 N/m, whose
  Newton residual is measured against the springs' k q too (the round-off of a solve 2e4 times worse
  conditioned).
* A mesh with no tooth pair in contact: static_state raises naming the mesh; pl_initialize returns
  GK_ERR_NOCONTACT with that mesh's index.
* gearkernel.h's status codes for bad arguments (never a crash, the state left unchanged).
* Model Exchange (pl_me_*): the derivatives with the modes pl_me_init decides equal pl_derivatives (the
  plain lookup) where those modes fit, bit for bit; scipy's solve_ivp (DOP853, events on the kernel's
  indicators, the modes decided anew at each) over pl_me_derivatives on a run that keeps every mesh in
  contact reproduces the native solver within 1e-6 of each output's range.
"""
import ctypes
import dataclasses
from pathlib import Path

import numpy as np
import pytest
import scipy.integrate

from gearfmu import stages
from gearfmu.bench import lp_stage, planetary_case, run_kwargs
from gearfmu.fmu.planetary_kernel import PlanetaryKernel, compile_planetary_kernel
from gearfmu.fmu.runtime.kernel_api import load_kernel
from gearfmu.gear.planetary_set import PlanetErrors
from gearfmu.planetary.model import PlanetaryModelError, build_drivetrain
from gearfmu.planetary.native import simulate
from gearfmu.scene.drivetrain import load_drivetrain

pytestmark = pytest.mark.slow  # compiles the kernel and runs the native solver: the full suite

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "examples" / "scenes"
INTEGRATORS = ("rk4", "rk4_kink", "rk4_node", "rk4_seg")
GK_OK, GK_ERR_MODEL, GK_ERR_INPUT, GK_ERR_STEP, GK_ERR_NONFINITE, GK_ERR_NOCONTACT, GK_ERR_PARAM = range(7)


@pytest.fixture(scope="module")
def lib_path(tmp_path_factory):
    return compile_planetary_kernel(tmp_path_factory.mktemp("plkernel"))


@pytest.fixture(scope="module")
def lib(lib_path):
    return load_kernel(lib_path, check=True, planetary=True)


def _scene_case(name, stop_periods):
    sc = load_drivetrain(SCENES / f"{name}.toml")
    model = stages.drivetrain_model(sc, stages.stage_tables(sc))
    s = stages.gearbox_run_settings(sc)
    m = next(i for i, n in enumerate(model.mesh_names) if "sun_planet[1]" in n)
    T = float(model.mesh_tables[m].mesh_period_rad) / (abs(float(model.angle_ref[m])) * s.motor_speed_start_rad_s)
    return model, dict(stop_time_s=stop_periods * T, comm_step_s=T / 8, motor_torque_Nm=s.motor_torque_start_Nm,
                       motor_speed_start_rad_s=s.motor_speed_start_rad_s, motor_angle_start_rad=0.013)


def _torsional(stop_periods):
    st = lp_stage(3, model="torsional", teeth_sun=21, teeth_planet=23, teeth_ring=67, contact_ratio_sun=1.6,
                  contact_ratio_ring=1.7)
    m = build_drivetrain(planetaries=[st], motor="lp.sun", load="lp.carrier")
    return m, run_kwargs(m, "lp.sun_planet[1]", 300.0, 60.0, stop_periods)


def _load_driven(stop_periods):
    """The pin-error stage with the load torque the only input (the motor end free: T_ref = T_load g_load)."""
    st = lp_stage(4, teeth_sun=21, teeth_planet=23, teeth_ring=67, contact_ratio_sun=1.6, contact_ratio_ring=1.7,
                  planet_errors=(PlanetErrors(0.0, -20e-6),) + (PlanetErrors(),) * 3)
    m = build_drivetrain(planetaries=[st], motor="lp.sun", load="lp.carrier", motor_torque_input=False)
    kw = run_kwargs(m, "lp.sun_planet[1]", 300.0, 0.0, stop_periods)
    kw["load_torque_Nm"] = 60.0 / m.load_ratio
    return m, kw


def _stiff_supports(stop_periods):
    """Pins, carrier and ring on supports of 1e13 N/m (a rigid part written as a stiff spring), a pin error."""
    st = lp_stage(4, teeth_sun=21, teeth_planet=23, teeth_ring=67, contact_ratio_sun=1.6, contact_ratio_ring=1.7,
                  planet_errors=(PlanetErrors(0.0, -20e-6),) + (PlanetErrors(),) * 3, support_N_per_m=1e13,
                  bearing_N_per_m=dict(sun=0.0, ring=1e13, carrier=1e13, planet=1e13))
    m = build_drivetrain(planetaries=[st], motor="lp.sun", load="lp.carrier")
    return m, run_kwargs(m, "lp.sun_planet[1]", 300.0, 60.0, stop_periods)


def _driven(stop_periods):
    """A superimposing stage: the sun on the motor, the ring driven through its support at a speed that
    changes every communication step (-40 rad/s and a ramp), the carrier on the load (torsional model)."""
    st = dataclasses.replace(lp_stage(3, model="torsional", teeth_sun=21, teeth_planet=23, teeth_ring=67,
                                      contact_ratio_sun=1.6, contact_ratio_ring=1.7), driven_speed_rad_s=-40.0)
    m = build_drivetrain(planetaries=[st], motor="lp.sun", load="lp.carrier")
    kw = run_kwargs(m, "lp.sun_planet[1]", 300.0, 60.0, stop_periods)
    kw["drive_speeds_rad_s"] = {"lp.ring": lambda t: -40.0 + 2e4 * t}
    return m, kw


def _driven_carrier(stop_periods):
    """Translational: the motor on the carrier, the ring driven (the carrier's speed is the motor's
    alone, so its frame is exact), the sun on the load."""
    st = dataclasses.replace(lp_stage(3, teeth_sun=21, teeth_planet=23, teeth_ring=67, contact_ratio_sun=1.6,
                                      contact_ratio_ring=1.7), driven_speed_rad_s=25.0)
    m = build_drivetrain(planetaries=[st], motor="lp.carrier", load="lp.sun")
    return m, run_kwargs(m, "lp.sun_planet[1]", 100.0, 60.0, stop_periods)


def _driven_translational(stop_periods):
    """Translational superimposing stage: the sun on the motor, the ring driven (its speed changing every
    step), the carrier on the load -- the drive turns the carrier, so its frame turns with the drive too."""
    st = dataclasses.replace(lp_stage(3, teeth_sun=21, teeth_planet=23, teeth_ring=67, contact_ratio_sun=1.6,
                                      contact_ratio_ring=1.7), driven_speed_rad_s=-40.0)
    m = build_drivetrain(planetaries=[st], motor="lp.sun", load="lp.carrier")
    kw = run_kwargs(m, "lp.sun_planet[1]", 300.0, 60.0, stop_periods)
    kw["drive_speeds_rad_s"] = {"lp.ring": lambda t: -40.0 + 2e4 * t}
    return m, kw


def _bench(name):
    return lambda stop_periods: planetary_case(name, mesh_periods=stop_periods)


CASES = {
    "reducer": lambda p: _scene_case("planetary_reducer", p),
    "lin_parker": lambda p: _scene_case("planetary_lin_parker", p),
    "torsional": _torsional,
    "position_error": _bench("position_error"),
    "contact_loss": _bench("contact_loss"),
    "load_driven": _load_driven,
    "driven_ring": _driven,
    "driven_ring_translational": _driven_carrier,
    "driven_ring_turning_frame": _driven_translational,
}
_MODELS = {}


def case(name):
    if name not in _MODELS:
        _MODELS[name] = CASES[name](4 if name != "contact_loss" else 6)
    return _MODELS[name]


def kernel_columns(K, model):
    """Native output name -> index in the kernel's output vector (plkernel.h "Output layout")."""
    cols = {}
    for i, nm in enumerate(model.dof_names):
        a, r = (f"{nm}_angle", f"{nm}_speed") if model.dof_kind[i] == "rot" else (nm, f"{nm}_rate")
        cols[a], cols[r] = 2 * i, 2 * i + 1
    for p in model.parts:
        d = model.part_dof[p]
        if model.dof_names[d] != p:
            cols[f"{p}_angle"], cols[f"{p}_speed"] = 2 * d, 2 * d + 1
    for m, nm in enumerate(model.mesh_names):
        o, P = K.mesh_offset(m), model.mesh_tables[m].slots
        cols[f"{nm}.dte"], cols[f"{nm}.dte_rate"] = o, o + 1
        cols[f"{nm}.mesh_force"], cols[f"{nm}.mesh_stiffness"] = o + 2, o + 3
        for j in range(P):
            cols[f"{nm}.pair_force[{j + 1}]"] = o + 4 + j
            cols[f"{nm}.load_sharing[{j + 1}]"] = o + 4 + P + j
    for s, nm in enumerate(model.spring_names):
        cols[f"{nm}.force"] = K.spring_offset() + s
    for g, st in enumerate(model.stages):
        for n in range(st["planets"]):
            cols[f"{st['name']}.load_sharing_factor[{n + 1}]"] = K.group_offset(g) + n
    return cols


def kernel_run(K, model, res):
    """The kernel stepped as the native run was: from its initial state, its inputs per step, its
    communication step and step bound.  The output rows (row 0: pl_outputs at the start)."""
    s = res.info["settings"]
    t_in, t_out = res["motor_torque"], res["load_torque"]
    w = res.info.get("drive_speeds_rad_s", np.zeros((len(t_in), 0)))   # a driven member's prescribed speed
    y0 = model.static_state(float(res.info["reference_torque_Nm"][0]), s.motor_speed_start_rad_s,
                            s.motor_angle_start_rad, drive_speeds_rad_s=w[0] if model.drives else None)
    K.set_state(y0)
    rows = [K.outputs(t_in[0], t_out[0])]
    for k in range(len(t_in) - 1):
        if model.drives:
            K.set_drive_speeds(w[k])
        rows.append(K.step(t_in[k], t_out[k], s.output_interval_s, s.max_step_s))
    return np.array(rows)


@pytest.mark.parametrize("integrator", INTEGRATORS)
@pytest.mark.parametrize("name", list(CASES))
def test_steps_equal_the_native_solver_bit_for_bit(lib, name, integrator):
    model, kw = case(name)
    res = simulate(model, integrator=integrator, **kw)
    assert res.info["completed_steps"] == len(res.time_s) - 1
    K = PlanetaryKernel(lib, model, integrator)
    rows = kernel_run(K, model, res)
    assert np.array_equal(K.y, res.state), np.max(np.abs(K.y - res.state))
    cols = kernel_columns(K, model)
    assert set(cols) == set(res.names()) - {"motor_torque", "load_torque"}
    assert len(set(cols.values())) == K.n_out      # every kernel output is a native column
    differ = [n for n, i in cols.items() if not np.array_equal(res[n], rows[:, i], equal_nan=True)]
    assert differ == [], differ[:5]
    if integrator == "rk4_kink" or (integrator == "rk4_node" and name != "lin_parker"):
        assert res.info["events"] > 0   # events located (Lin & Parker's constant mesh stiffness bends nowhere)
    if name == "contact_loss":  # the backlash opened: some pair force is 0 after the drop
        assert np.min(res["lp.sun_planet[1].mesh_force"]) < 0.5 * np.max(res["lp.sun_planet[1].mesh_force"])


@pytest.mark.parametrize("name", list(CASES) + ["stiff_supports"])
def test_static_state_equals_the_model_s(lib, name):
    model, kw = case(name) if name in CASES else _stiff_supports(4)
    K = PlanetaryKernel(lib, model)
    for T, w, a in ((kw["motor_torque_Nm"] if not callable(kw["motor_torque_Nm"]) else 60.0,
                     kw["motor_speed_start_rad_s"], 0.013), (35.0, 0.0, 1.1), (-20.0, 50.0, -0.4)):
        want = model.static_state(T, w, a)
        got = K.initialize(T, w, a)
        # q' = 0 but for a driven member's drive: its rigid motion at the drive's speed (pl_start_drives)
        assert got[0] == a and got[1] == w and np.array_equal(got[3::2], want[3::2])
        assert np.all(got[3::2] == 0.0) or model.drives
        kind = np.array(model.dof_kind[1:])
        for k in ("rot", "trans"):
            sel = np.flatnonzero(kind == k)
            if sel.size:
                q, qc = want[2::2][sel], got[2::2][sel]
                # the stiff supports are 2e4 times the meshes: the solve's round-off grows by that condition
                tol = 1e-10 if name == "stiff_supports" else 1e-12
                assert np.max(np.abs(qc - q)) <= tol * np.max(np.abs(q)), (name, k, T)


def test_drive_arguments_give_status_codes(lib):
    """The drives of driven members: 1/m = 0 only with g = 0 and not for the motor DOF; pl_add_drive's
    refusals; a non-finite drive speed refused with the state unchanged."""
    model, kw = case("driven_ring")
    L = load_kernel(lib._name, planetary=True)    # unchecked: the codes themselves
    K = PlanetaryKernel(lib, model, "rk4_node")
    P, S = K.pl.ctypes.data, K.state.ctypes.data
    y0 = K.initialize(60.0, 300.0)
    scratch = np.zeros(L.pl_sizeof_model() // 8 + 1)
    inv_m, g = np.array([1.0, 0.0, 1.0]), np.array([1.0, 0.5, 0.5])
    assert L.pl_init(scratch.ctypes.data, 3, inv_m.ctypes.data, g.ctypes.data, 2, 1, 1) == GK_ERR_MODEL  # g != 0
    g[1] = 0.0
    assert L.pl_init(scratch.ctypes.data, 3, inv_m.ctypes.data, g.ctypes.data, 2, 1, 1) == GK_OK
    inv_m[0], g[0] = 0.0, 1.0
    assert L.pl_init(scratch.ctypes.data, 3, inv_m.ctypes.data, g.ctypes.data, 2, 1, 1) == GK_ERR_MODEL  # motor
    d = model.drive_dofs[0]
    mode = np.array(model.drives[0]["mode"])
    assert L.pl_add_drive(P, d, mode.ctypes.data) == GK_ERR_MODEL                 # declared already
    assert L.pl_add_drive(P, model.part_dof["lp.sun"], mode.ctypes.data) == GK_ERR_MODEL   # 1/m > 0
    assert L.pl_add_drive(P, 0, mode.ctypes.data) == GK_ERR_MODEL
    assert L.pl_add_drive(P, d, None) == GK_ERR_MODEL
    bad = np.array([float("nan")])
    assert L.pl_set_drive_speeds(P, S, bad.ctypes.data) == GK_ERR_INPUT
    assert L.pl_start_drives(P, S, bad.ctypes.data) == GK_ERR_INPUT
    assert np.array_equal(K.y, y0)             # the refusals left the state unchanged
    ok = np.array([-12.5])
    assert L.pl_set_drive_speeds(P, S, ok.ctypes.data) == GK_OK and K.y[2 * d + 1] == -12.5


def test_a_mesh_without_contact_is_named(lib):
    model, kw = case("position_error")
    m = model.mesh_names.index("lp.ring_planet[2]")
    t = model.mesh_tables[m]
    dead = dataclasses.replace(t, k_N_per_m=np.zeros_like(np.asarray(t.k_N_per_m)))
    bad = dataclasses.replace(model, mesh_tables=model.mesh_tables[:m] + (dead,) + model.mesh_tables[m + 1:])
    with pytest.raises(PlanetaryModelError, match=rf"meshes\[{m}\] \(lp.ring_planet\[2\]\): no tooth pair"):
        bad.static_state(60.0, 300.0)
    plain = load_kernel(lib._name, planetary=True)
    K = PlanetaryKernel(lib, bad)
    where = ctypes.c_int(-7)
    st = plain.pl_initialize(K.pl.ctypes.data, K.work.ctypes.data, K.state.ctypes.data, 0.0, 300.0, 60.0,
                             ctypes.addressof(where))
    assert (st, where.value) == (GK_ERR_NOCONTACT, m)


def test_bad_arguments_give_status_codes(lib):
    model, kw = case("position_error")
    L = load_kernel(lib._name, planetary=True)    # unchecked: the codes themselves
    K = PlanetaryKernel(lib, model, "rk4_node")
    P, W, S, ME = K.pl.ctypes.data, K.work.ctypes.data, K.state.ctypes.data, K.me.ctypes.data
    y0 = K.initialize(60.0, 300.0)
    out = np.zeros(K.n_out)
    one, dof, cf = np.ones(4), np.array([1, 2, 3, 500], dtype=np.intc), np.ones(4)
    scratch = np.zeros(L.pl_sizeof_model() // 8 + 1)
    nan, inf = float("nan"), float("inf")
    assert L.pl_init(None, 3, one.ctypes.data, one.ctypes.data, 1, 1, 1) == GK_ERR_MODEL
    assert L.pl_init(scratch.ctypes.data, 1, one.ctypes.data, one.ctypes.data, 0, 1, 1) == GK_ERR_MODEL
    assert L.pl_init(scratch.ctypes.data, 500, one.ctypes.data, one.ctypes.data, 1, 1, 1) == GK_ERR_MODEL
    assert L.pl_init(scratch.ctypes.data, 3, one.ctypes.data, one.ctypes.data, 3, 1, 1) == GK_ERR_MODEL
    assert L.pl_init(scratch.ctypes.data, 3, one.ctypes.data, None, 1, 1, 1) == GK_ERR_MODEL
    assert L.pl_init(scratch.ctypes.data, 3, (-one).ctypes.data, one.ctypes.data, 1, 1, 1) == GK_ERR_MODEL
    assert L.pl_add_spring(P, 4, dof.ctypes.data, cf.ctypes.data, 1e6, 0.0) == GK_ERR_MODEL      # DOF 500
    assert L.pl_add_spring(P, 5, dof.ctypes.data, cf.ctypes.data, 1e6, 0.0) == GK_ERR_MODEL
    assert L.pl_add_spring(P, 2, dof.ctypes.data, cf.ctypes.data, -1e6, 0.0) == GK_ERR_MODEL
    assert L.pl_add_frame(P, 0, 2, 0.1, 1.0) == GK_ERR_MODEL
    assert L.pl_add_mesh(P, None, 1, dof.ctypes.data, cf.ctypes.data, 0, None, None, 1.0, 0.0, 1.0) == GK_ERR_MODEL
    assert L.pl_add_mesh(P, K.pairs[0].ctypes.data, 7, dof.ctypes.data, cf.ctypes.data, 0, None, None, 1.0, 0.0,
                         1.0) == GK_ERR_MODEL
    assert L.pl_add_group(P, 2, np.array([0, 99], dtype=np.intc).ctypes.data) == GK_ERR_MODEL
    assert L.pl_set_integrator(P, 4) == GK_ERR_PARAM and L.pl_set_integrator(None, 0) == GK_ERR_MODEL
    assert L.pl_n_outputs(P) == K.n_out        # the refusals left the model as it was
    assert L.pl_do_step(P, W, S, nan, 0.0, 1e-4, 1e-5, out.ctypes.data) == GK_ERR_INPUT
    assert L.pl_do_step(P, W, S, 60.0, inf, 1e-4, 1e-5, out.ctypes.data) == GK_ERR_INPUT
    assert L.pl_do_step(P, W, S, 60.0, 0.0, -1e-4, 1e-5, out.ctypes.data) == GK_ERR_STEP
    assert L.pl_do_step(P, W, S, 60.0, 0.0, 1e-4, 0.0, out.ctypes.data) == GK_ERR_STEP
    assert L.pl_do_step(None, W, S, 60.0, 0.0, 1e-4, 1e-5, out.ctypes.data) == GK_ERR_MODEL
    assert L.pl_do_step(P, W, S, 1e308, 0.0, 1e-2, 1e-2, out.ctypes.data) == GK_ERR_NONFINITE
    assert np.array_equal(K.y, y0)             # every refused step left the state unchanged
    assert L.pl_initialize(P, W, S, nan, 0.0, 60.0, None) == GK_ERR_INPUT
    assert L.pl_outputs(P, W, S, 60.0, 0.0, None) == GK_ERR_MODEL
    assert L.pl_derivatives(P, W, 0.0, None, 60.0, 0.0, out.ctypes.data) == GK_ERR_MODEL
    ybad = y0.copy()
    ybad[3] = nan
    dy = np.zeros(y0.size)
    assert L.pl_derivatives(P, W, 0.0, ybad.ctypes.data, 60.0, 0.0, dy.ctypes.data) == GK_ERR_INPUT
    assert L.pl_me_init(P, W, ME, y0.ctypes.data, 60.0, 0.0, 9) == GK_ERR_PARAM
    assert L.pl_me_init(P, W, ME, ybad.ctypes.data, 60.0, 0.0, 0) == GK_ERR_NONFINITE
    assert L.pl_me_derivatives(P, W, ME, y0.ctypes.data, nan, 0.0, dy.ctypes.data) == GK_ERR_INPUT
    assert L.pl_mesh_offset(P, 99) == -1 and L.pl_group_offset(None, 0) == -1 and L.pl_n_outputs(None) == 0
    assert L.pl_abi_version() == 2 and L.pl_events(None) == 0


# ---------------------------------------------------------------- Model Exchange
def test_me_derivatives_with_the_decided_modes_are_the_plain_ones(lib):
    """At states of a run (every mesh loaded, no zone edge or backlash at hand), the derivatives with the
    modes pl_me_init decides there equal pl_derivatives bit for bit; the indicators are >= 0."""
    for name in ("position_error", "reducer"):
        model, kw = case(name)
        res = simulate(model, integrator="rk4_node", **kw)
        K = PlanetaryKernel(lib, model)
        T_in, T_out = float(res["motor_torque"][0]), float(res["load_torque"][0])
        y = model.static_state(float(res.info["reference_torque_Nm"][0]), kw["motor_speed_start_rad_s"], 0.013)
        K.set_state(y)
        s = res.info["settings"]
        checked = 0
        for k in range(6):
            y = K.y
            K.me_init(y, T_in, T_out, 0)
            z = K.me_indicators(y, T_in, T_out, 0)
            if np.min(z) > 1e-12:       # a state away from every event: the modes are those of the state
                assert np.array_equal(K.me_derivatives(y, T_in, T_out), K.derivatives(y, T_in, T_out)), name
                checked += 1
            K.step(T_in, T_out, s.output_interval_s, s.max_step_s)
        assert checked >= 3, name


def _me_host(K, y0, T_in, T_out, times, rtol, node_events=0):
    """solve_ivp (DOP853) over pl_me_derivatives, every indicator a terminal event (falling through 0);
    at each event the modes anew (pl_me_update).  The outputs at ``times`` (pl_me_outputs in the modes of
    the segment they fall in) and the number of events."""
    K.me_init(y0, T_in, T_out, node_events)
    nz = K.n_indicators(node_events)
    events = []
    for i in range(nz):
        def ev(t, y, i=i):
            return K.me_indicators(y, T_in, T_out, node_events)[i]
        ev.terminal, ev.direction = True, -1
        events.append(ev)
    t, y, out, n_ev, k = times[0], np.asarray(y0, float), [], 0, 0
    while k < len(times):
        sol = scipy.integrate.solve_ivp(lambda _t, yy: K.me_derivatives(yy, T_in, T_out), (t, times[-1]), y,
                                        method="DOP853", rtol=rtol, atol=rtol * np.maximum(np.abs(y), 1e-9),
                                        events=events, dense_output=True)
        assert sol.status >= 0, sol.message
        while k < len(times) and times[k] <= sol.t[-1]:
            out.append(K.me_outputs(sol.sol(times[k]), T_in, T_out))
            k += 1
        if sol.status != 1:
            break
        t, y = sol.t[-1], sol.y[:, -1]
        K.me_update(y, T_in, T_out)
        n_ev += 1
        assert n_ev < 5000
    return np.array(out), n_ev


@pytest.mark.parametrize("node_events", [0, 2])
def test_me_host_over_the_kernel_matches_the_native_solver(lib, node_events):
    """Lin & Parker's system with a planet position error at load (every mesh keeps contact): the host
    over pl_me_* (DOP853, rtol 1e-10; without node events, and with an event at every node where the
    tables bend) against the native solver (rk4_node) at a step bound of a tenth of its own: every
    output within 1e-6 of its range."""
    model, kw = case("position_error")
    kw = dict(kw, stop_time_s=2 * kw["comm_step_s"] * 8)
    res = simulate(model, integrator="rk4_node", **kw)
    h = res.info["settings"].max_step_s / 10.0
    res = simulate(model, integrator="rk4_node", max_step_s=h, **kw)
    K = PlanetaryKernel(lib, model)
    T_in, T_out = float(res["motor_torque"][0]), float(res["load_torque"][0])
    assert np.all(res["motor_torque"] == T_in) and np.all(res["load_torque"] == T_out)
    for n in model.mesh_names:                  # contact kept: the mesh forces stay well above 0
        assert np.min(res[f"{n}.mesh_force"]) > 0.2 * np.mean(res[f"{n}.mesh_force"])
    y0 = model.static_state(T_in, kw["motor_speed_start_rad_s"], kw["motor_angle_start_rad"])
    out, n_ev = _me_host(K, y0, T_in, T_out, res.time_s, 1e-10, node_events)
    assert n_ev > 0
    cols = kernel_columns(K, model)
    worst = {}
    for name, i in cols.items():
        ref = res[name]
        rng = max(float(np.ptp(ref)), 1e-3 * float(np.max(np.abs(ref))), 1e-300)
        worst[name] = float(np.max(np.abs(out[:, i] - ref))) / rng
    bad = sorted(worst.items(), key=lambda kv: -kv[1])[:3]
    print("Model Exchange host against the native solver: worst |error| / range", bad[0], "events", n_ev)
    assert bad[0][1] <= 1e-6, bad
