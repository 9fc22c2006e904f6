"""The gearbox kernel's Model Exchange functions (gbkernel.h gb_me_*: every mesh's mode held between
events, the derivatives, indicators and outputs with the modes held), driven by an independent host
written here: scipy's solve_ivp (DOP853) with event location on the kernel's indicators, the modes
decided anew by gb_me_update at every located event.

References (none produced by the gearbox code):
* the linear limit (constant mesh stiffness, no error, no backlash, contact_zone: F = k x + c v): the
  matrix exponential of the first-order system with M, K, C assembled element by element
  (tests/unit/gearbox/test_gearbox_native.py), from the static state under a motor-torque step, to 1e-6 of the range;
* a nonlinear case, ``contact_loss`` of gearfmu.gearbox.cases (stage 1 loses contact and impacts while
  stage 2 carries load): the native gearbox solver (rk4_node) at a fine step, to 1e-4 of the range.
"""
import ctypes

import numpy as np
import pytest
import scipy.integrate
import scipy.linalg

from gearfmu.common.vocabulary import DAMPING_MODELS
from gearfmu.gearbox.cases import gearbox_case
from gearfmu.gearbox.native import simulate
from gearfmu.tables.zones import zone_cuts

from support.gearbox_cases import (K_MID, S1, S2, c_mesh, hand_damping, hand_damping_of_mid, hand_matrices, kernel_library,
                                   linear_gearbox)

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

NODES_NONE, NODES_KINKS = 0, 1


class KernelGearbox:
    """A gearbox model of gearfmu.gearbox.model in the C kernel (as gearbox_model.c sets it up: per mesh
    gk_init, its contact-zone cuts and zones, its damping), with its Model Exchange mode."""

    def __init__(self, L, model, node_events):
        P, I = ctypes.c_void_p, ctypes.c_int
        for name, args in (("gb_sizeof_me", []), ("gb_me_n_indicators", [P, I]),
                           ("gb_me_init", [P, P, P, P, ctypes.c_double, ctypes.c_double, I]),
                           ("gb_me_update", [P, P, P, P, ctypes.c_double, ctypes.c_double, P]),
                           ("gb_me_derivatives", [P, P, P, P, ctypes.c_double, ctypes.c_double, P]),
                           ("gb_me_indicators", [P, P, P, P, ctypes.c_double, ctypes.c_double, P]),
                           ("gb_me_outputs", [P, P, P, P, ctypes.c_double, ctypes.c_double, P])):
            getattr(L, name).restype = I
            getattr(L, name).argtypes = args
        self.L, self.model, self.keep = L, model, []
        pairs = []
        for mesh in model.meshes:
            t = mesh.tables
            arrs = [np.ascontiguousarray(a, dtype=float) for a in (t.torque_Nm, t.k_N_per_m, t.e_m, t.backlash_half_m)]
            pm = np.zeros(L.gk_sizeof_model() // 8 + 1)
            self.keep += arrs + [pm]
            assert L.gk_init(pm.ctypes.data, t.slots, t.n_phi, t.n_torque, *(a.ctypes.data for a in arrs),
                             t.phi_period_rad, t.base_radius_pinion_m, t.base_radius_gear_m, t.inertia_pinion_kgm2,
                             t.inertia_gear_kgm2, t.k_mean_N_per_m) == 0
            cuts = zone_cuts(t)
            if cuts is not None:
                c = np.ascontiguousarray(cuts, dtype=float)
                self.keep.append(c)
                assert L.gk_set_zone_cuts(pm.ctypes.data, c.ctypes.data) == 0
                assert L.gk_set_zone_edges(pm.ctypes.data, t.mesh_period_rad, t.engagement_in_rad,
                                           t.engagement_out_rad) == 0
            assert L.gk_set_damping(pm.ctypes.data, mesh.damping_ratio, DAMPING_MODELS[mesh.damping_model]) == 0
            pairs.append(pm)
        self.gb = np.zeros(L.gb_sizeof_model() // 8 + 1)
        self.work = np.zeros(L.gb_sizeof_work() // 8 + 1)
        self.me = np.zeros(L.gb_sizeof_me() // 8 + 1)
        inv_i = np.ascontiguousarray(1.0 / model.inertia_kgm2)
        g = np.ascontiguousarray(model.g)
        self.keep += [inv_i, g, pairs]
        assert L.gb_init(self.gb.ctypes.data, model.n_bodies, inv_i.ctypes.data, g.ctypes.data,
                         int(model.load_body), 1, 1) == 0
        for m, pm in enumerate(pairs):
            p, q = model.mesh_bodies[m]
            assert L.gb_add_mesh(self.gb.ctypes.data, pm.ctypes.data, int(p), int(q), 1) == 0
        for s, (a, b) in enumerate(model.shaft_bodies):
            assert L.gb_add_shaft(self.gb.ctypes.data, int(a), int(b), model.shaft_k_Nm_per_rad[s],
                                  model.shaft_c_Nms_per_rad[s], 1) == 0
        self.node_events = node_events
        self.nz = L.gb_me_n_indicators(self.gb.ctypes.data, node_events)
        self.n_out = L.gb_n_outputs(self.gb.ctypes.data)

    def _args(self, y):
        y = np.ascontiguousarray(y, dtype=float)
        return y, (self.gb.ctypes.data, self.work.ctypes.data, self.me.ctypes.data, y.ctypes.data)

    def init(self, y, T_in, T_out):
        y, a = self._args(y)
        assert self.L.gb_me_init(*a, T_in, T_out, self.node_events) == 0

    def update(self, y, T_in, T_out):
        y, a = self._args(y)
        changed = ctypes.c_int(0)
        assert self.L.gb_me_update(*a, T_in, T_out, ctypes.addressof(changed)) == 0
        return changed.value

    def derivatives(self, y, T_in, T_out):
        y, a = self._args(y)
        dy = np.zeros(len(y))
        assert self.L.gb_me_derivatives(*a, T_in, T_out, dy.ctypes.data) == 0
        return dy

    def indicators(self, y, T_in, T_out):
        y, a = self._args(y)
        z = np.zeros(self.nz)
        assert self.L.gb_me_indicators(*a, T_in, T_out, z.ctypes.data) == 0
        return z

    def outputs(self, y, T_in, T_out):
        y, a = self._args(y)
        out = np.zeros(self.n_out)
        assert self.L.gb_me_outputs(*a, T_in, T_out, out.ctypes.data) == 0
        return out


def run_host(kg, y0, T_in, T_out, times, rtol):
    """solve_ivp (DOP853) over the kernel's derivatives with every indicator a terminal event; at each
    event the modes anew (gb_me_update) and the integration restarted there.  The outputs at ``times``
    (gb_me_outputs with the modes of the segment they fall in) and the number of events."""
    kg.init(y0, T_in, T_out)
    events = []
    for i in range(kg.nz):
        def ev(t, y, i=i):
            return kg.indicators(y, T_in, T_out)[i]
        ev.terminal = True
        ev.direction = -1     # >= 0 while the modes hold: only a fall through zero is an event
        events.append(ev)
    t, y, out, n_ev = times[0], np.asarray(y0, float), [], 0
    k = 0
    while k < len(times):
        sol = scipy.integrate.solve_ivp(lambda _t, yy: kg.derivatives(yy, T_in, T_out), (t, times[-1]), y,
                                        method="DOP853", rtol=rtol, atol=rtol * np.maximum(np.abs(y), 1e-6),
                                        events=events, dense_output=True, t_eval=None)
        assert sol.status >= 0, sol.message
        t_end = sol.t[-1]
        while k < len(times) and times[k] <= t_end:
            out.append(kg.outputs(sol.sol(times[k]), T_in, T_out))
            k += 1
        if sol.status == 1:      # an event: the modes anew at the located state
            t, y = t_end, sol.y[:, -1]
            kg.update(y, T_in, T_out)
            n_ev += 1
            assert n_ev < 20000
        else:
            break
    return np.array(out), n_ev


def test_me_derivatives_equal_the_plain_ones_where_the_mode_fits(tmp_path):
    """In the linear gearbox every mesh is always in contact: the derivatives with the modes held equal
    gb_derivatives (the plain lookup) bit for bit, and the indicators are >= 0 after gb_me_init."""
    L = kernel_library(tmp_path)
    kg = KernelGearbox(L, linear_gearbox(), NODES_NONE)
    rng = np.random.default_rng(7)
    n = kg.model.n_bodies
    y = np.zeros(2 * n)
    y[0], y[1] = 0.37, 280.0
    y[2::2] = rng.normal(0.0, 1e-4, n - 1)
    y[3::2] = rng.normal(0.0, 0.5, n - 1)
    kg.init(y, 230.0, 900.0)
    dy = np.zeros(2 * n)
    assert L.gb_derivatives(kg.gb.ctypes.data, kg.work.ctypes.data, 0.0, y.ctypes.data, 230.0, 900.0,
                            dy.ctypes.data) == 0
    assert np.array_equal(kg.derivatives(y, 230.0, 900.0), dy)
    assert kg.nz == 6 and np.min(kg.indicators(y, 230.0, 900.0)) >= 0.0


def test_linear_limit_against_matrix_exponential(tmp_path):
    """From the static state under 150 N*m at 300 rad/s the motor torque steps to 250 N*m against
    1000 N*m (as tests/unit/gearbox/test_gearbox_native.py): the host over gb_me_* (DOP853, rtol 1e-11) reproduces the
    matrix exponential to 1e-6 of the range (DTE of both stages, the intermediate shaft's torque, the
    stage-1 mesh force)."""
    L = kernel_library(tmp_path)
    model = linear_gearbox()
    kg = KernelGearbox(L, model, NODES_KINKS)
    M, K = hand_matrices()
    C = hand_damping()
    order = [model.part_body[p] for p in ("motor", "s1.pinion", "s1.gear", "s2.pinion", "s2.gear", "load")]
    y0 = model.static_state(150.0, 300.0)
    u = np.concatenate([[0.0], y0[2::2]])[order]
    du = np.concatenate([[0.0], y0[3::2]])[order]
    th0, w0 = model.g[order] * y0[0] + u, model.g[order] * y0[1] + du
    f = np.zeros(6)
    f[0], f[5] = 250.0, -1000.0
    A = np.zeros((13, 13))
    Mi = np.linalg.inv(M)
    A[:6, 6:12] = np.eye(6)
    A[6:12, :6] = -Mi @ K
    A[6:12, 6:12] = -Mi @ C
    A[6:12, 12] = Mi @ f
    H, n = 1e-4, 200
    times = np.arange(n + 1) * H
    Z = np.array([scipy.linalg.expm(A * t) @ np.concatenate([th0, w0, [1.0]]) for t in times])
    out, _ = run_host(kg, y0, 250.0, 1000.0, times, 1e-11)
    o1, o2 = L.gb_mesh_offset(kg.gb.ctypes.data, 0), L.gb_mesh_offset(kg.gb.ctypes.data, 1)
    so = L.gb_shaft_offset(kg.gb.ctypes.data)
    x1 = S1["rb1"] * Z[:, 1] - S1["rb2"] * Z[:, 2]
    x2 = S2["rb1"] * Z[:, 3] - S2["rb2"] * Z[:, 4]
    mid = [i for i, sh in enumerate(model.shafts) if sh.name == "intermediate_shaft"][0]
    for got, ref in ((out[:, o1], x1), (out[:, o2], x2),
                     (out[:, so + mid], K_MID * (Z[:, 2] - Z[:, 3]) + hand_damping_of_mid(Z)),
                     (out[:, o1 + 2], S1["k"] * x1 + c_mesh(S1) * (S1["rb1"] * Z[:, 7] - S1["rb2"] * Z[:, 8]))):
        assert np.max(np.abs(got - ref)) <= 1e-6 * np.ptp(ref), np.max(np.abs(got - ref)) / np.ptp(ref)


@pytest.mark.parametrize("node_events", [NODES_NONE, NODES_KINKS])
def test_contact_loss_against_the_native_gearbox_solver(tmp_path, node_events):
    """Stage 1 loses contact and impacts while stage 2 carries load: the host over gb_me_* (DOP853, every
    contact change an event; with the big table kinks as events too) and the native gearbox solver
    (rk4_node at 1/64 of the communication step) agree on both stages' DTE and mesh force to 1e-4 of the
    range.  The case has grazing contacts, where a tiny difference decides whether a pair touches: at rtol
    1e-10 or 1e-11 one grazing contact near the end can go the other way (measured: 6e-2 to 1e-1 from there
    on: with node events, and without them on another machine), at 1e-12 it
    does not."""
    L = kernel_library(tmp_path)
    model, kw = gearbox_case("contact_loss", 30)
    kg = KernelGearbox(L, model, node_events)
    T_in = float(kw["motor_torque_Nm"])
    T_out = model.balancing_load_torque_Nm(T_in)
    y0 = model.static_state(T_in, kw["motor_speed_start_rad_s"], kw["motor_angle_start_rad"])
    nat = simulate(model, stop_time_s=kw["stop_time_s"], comm_step_s=kw["comm_step_s"], motor_torque_Nm=T_in,
                   load_torque_Nm=T_out, motor_speed_start_rad_s=kw["motor_speed_start_rad_s"], initial_state=y0,
                   max_step_s=kw["comm_step_s"] / 64, integrator="rk4_node")
    times = np.asarray(nat.time_s)
    out, n_ev = run_host(kg, y0, T_in, T_out, times, 1e-12)
    worst = {}
    for m, name in enumerate(mesh.name for mesh in model.meshes):
        o = L.gb_mesh_offset(kg.gb.ctypes.data, m)
        for col, q in ((0, "dte"), (2, "mesh_force")):
            ref = np.asarray(nat[f"{name}.{q}"])
            worst[f"{name}.{q}"] = float(np.max(np.abs(out[:, o + col] - ref)) / np.ptp(ref))
    print("contact loss, host over gb_me_* against native:", worst, "events", n_ev)
    assert max(worst.values()) <= 1e-4, worst
    assert n_ev >= 10      # stage 1 loses and regains contact again and again
