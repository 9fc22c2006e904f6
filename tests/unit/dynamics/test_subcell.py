"""Sub-cell lookup at the contact-zone edges (docs/model.md "Contact-zone edges",
gearfmu.tables.zones, gearfmu.dynamics.subcell).

References no code here produced: synthetic tooth pairs whose stiffness is a closed form
K(u) = k0 (1 + a u/eps + c u (eps - u)/eps^2) over their engagement u in [0, eps) mesh periods
and 0 outside.  The time-averaged mesh stiffness is then the polynomial integral
(1/T) int K = k0 (eps + a eps/2 + c eps/6); the mean quasi-static transmission error under a
constant mesh force F (springs in parallel with meshing errors, x = (F + sum k_j e_j)/sum k_j)
is the integral of that closed form, evaluated by scipy.integrate.quad split at the closed-form
engagement edges.  The model's means are integrated exactly for a piecewise-smooth function:
Gauss-Legendre on every piece between table nodes and the closed-form edge angles.
"""
import math

import numpy as np
import pytest
from scipy.integrate import quad

from gearfmu.dynamics.subcell import static_te_m, table_values
from gearfmu.tables.mesh_tables import MeshTables, TableError, load_tables
from gearfmu.tables.synthetic import rectangular_wave_tables, tables_from_arrays
from gearfmu.tables.zones import PLAIN, zone_cuts

from support.integrator_cases import run_c
from support.subcell_tables import (A_LIN, C_PAR, K0, P, T, Z1, dyn_tables, pair_error, pair_stiffness,
                                    zone_tables)

F_MESH = 2000.0              # N


def _mean_over_mesh(f, t, eps):
    """(1/T) int_0^T f(phi) dphi for a function smooth between the table nodes and the
    closed-form edges 0 and (eps - 1) T: 6-point Gauss-Legendre on every piece."""
    ppm = t.n_phi // P
    brk = np.unique(np.concatenate([np.arange(ppm + 1) * T / ppm, [(eps - 1.0) * T]]))
    g, wg = np.polynomial.legendre.leggauss(6)
    a, b = brk[:-1, None], brk[1:, None]
    x = (0.5 * (a + b) + 0.5 * (b - a) * g[None, :]).ravel()
    w = (0.5 * (b - a) * wg[None, :]).ravel()
    return float(np.dot(w, f(x))) / T


def _kbar_exact(eps):
    return K0 * (eps + A_LIN * eps / 2.0 + C_PAR * eps / 6.0)


def _te_exact(eps, error):
    def x(u):
        pairs = [(u, 0)] + ([(u + 1.0, 1)] if u + 1.0 < eps else [])
        ks = sum(pair_stiffness(v, eps) for v, _ in pairs)
        ke = sum(pair_stiffness(v, eps) * (pair_error(v, eps) if error else 0.0) for v, _ in pairs)
        return (F_MESH + ke) / ks
    return quad(x, 0.0, eps - 1.0, limit=200)[0] + quad(x, eps - 1.0, 1.0, limit=200)[0]


def _kbar_model(t, eps, zone_edges):
    return _mean_over_mesh(lambda ph: table_values(t, ph, zone_edges=zone_edges)[0].sum(axis=1), t, eps)


def _te_model(t, eps, zone_edges):
    rb1 = t.base_radius_pinion_m
    return _mean_over_mesh(lambda ph: static_te_m(t, F_MESH * rb1, ph, zone_edges=zone_edges), t, eps)


def test_plain_lookup_error_is_first_order_and_is_the_edge_ramps():
    """The diagnosis: with the edges on table nodes (eps = 1.5, even ppm) the plain linear
    interpolation turns each step into a one-cell ramp.  The ramp before meshing-in adds
    K(0) h/2, the one before meshing-out misses K(eps) h/2 (h the cell width), so the mean
    stiffness is off by (K(0) - K(eps)) h/(2T) = -A k0 h/(2T): first order, and exactly the
    two edge cells (the smooth part adds only O(h^2))."""
    eps = 1.5
    errs = []
    for ppm in (16, 32, 64, 128):
        t = zone_tables(ppm, eps)
        err = _kbar_model(t, eps, False) - _kbar_exact(eps)
        ramp = -A_LIN * K0 / (2.0 * ppm)
        assert err == pytest.approx(ramp, rel=4.0 / ppm)
        errs.append(abs(err))
    assert errs[-1] / errs[0] == pytest.approx(1.0 / 8.0, rel=0.05)   # halves with every doubling


@pytest.mark.parametrize("eps", [1.5, 1.0 + 1.0 / math.sqrt(3.0)])
def test_subcell_lookup_mean_stiffness_second_order(eps):
    """Edges on nodes (1.5) and off nodes (1 + 1/sqrt 3, irrational: never on a node)."""
    errs = [abs(_kbar_model(zone_tables(ppm, eps), eps, True) / _kbar_exact(eps) - 1.0) for ppm in (16, 32, 64, 128)]
    for a, b in zip(errs, errs[1:]):
        assert b < a / 3.0            # second order: a quarter per doubling (first order: a half)
    assert errs[-1] < 2e-5
    # and far better than the plain lookup at the same resolution
    t = zone_tables(64, eps)
    plain = abs(_kbar_model(t, eps, False) / _kbar_exact(eps) - 1.0)
    assert errs[2] < plain / 10.0


def test_subcell_lookup_static_te_second_order_with_error_jump():
    """Mean static TE under constant force, meshing error nonzero at both edges (e jumps
    too), edges off the nodes."""
    eps = 1.0 + 1.0 / math.sqrt(3.0)
    ref = _te_exact(eps, True)
    errs = [abs(_te_model(zone_tables(ppm, eps, error=True), eps, True) / ref - 1.0) for ppm in (16, 32, 64, 128)]
    for a, b in zip(errs, errs[1:]):
        assert b < a / 3.0
    plain = [abs(_te_model(zone_tables(ppm, eps, error=True), eps, False) / ref - 1.0) for ppm in (32, 128)]
    assert plain[1] > plain[0] / 8.0    # the plain lookup is not second order (1/16 per two doublings)
    assert errs[3] < plain[1] / 20.0


def test_k_mean_is_the_exact_mean_of_the_lookup():
    """k_mean_N_per_m (the damping's mean stiffness) of tables with engagement angles converges at
    second order to the closed-form mean; the grid mean of tables without them is first order
    (modulated by where the edge falls in its cell) and far off at every level."""
    eps = 1.0 + 1.0 / math.sqrt(3.0)
    ref = _kbar_exact(eps)
    errs = [abs(zone_tables(p, eps).k_mean_N_per_m / ref - 1.0) for p in (16, 32, 64, 128)]
    for a, b in zip(errs, errs[1:]):
        assert b < a / 3.0
    grid = [abs(zone_tables(p, eps, engagement=False).k_mean_N_per_m / ref - 1.0) for p in (16, 32, 64, 128)]
    assert all(e < g / 20.0 for e, g in zip(errs, grid))


def test_values_at_the_edges():
    """Just outside an edge k = 0; just inside it the closed form K within O(h^2)."""
    eps = 1.0 + 1.0 / math.sqrt(3.0)
    t = zone_tables(32, eps)
    h = T / 32
    d = 1e-9
    k = table_values(t, [eps * T - d, eps * T + d, T - d, T + d, 2 * T - d])[0]
    # slot 0 leaves at eps T; slot 1's pair enters at T; slot 0's next pair enters at 2 T
    assert k[0, 0] == pytest.approx(pair_stiffness(eps, eps), rel=2 * (h / T) ** 2 * 10)
    assert k[1, 0] == 0.0
    assert k[2, 1] == 0.0 and k[3, 1] == pytest.approx(pair_stiffness(0.0, eps), rel=1e-6)
    assert k[4, 0] == 0.0
    kp = table_values(t, [eps * T - d, T - d], zone_edges=False)[0]   # plain: the ramps
    assert 0.0 < kp[0, 0] < pair_stiffness(eps, eps) and kp[1, 1] > 0.0


def test_zone_cuts_layout():
    t = zone_tables(16, 1.5)   # exit at node 24 of slot 0 (period 32 nodes), entry at node 0
    cuts = zone_cuts(t)
    lo, hi = cuts
    assert lo[0, 31] == 0.0 and hi[0, 31] == 1.0     # the cell before the entry node: all outside
    assert lo[0, 23] == 1.0                         # the cell before the exit node: all inside
    assert lo[0, 24] == 0.0 and hi[0, 24] == 1.0     # the cell after it: all outside
    assert lo[0, 5] == PLAIN
    assert zone_cuts(zone_tables(16, 1.5, engagement=False)) is None


def test_engagement_round_trip_and_older_files(tmp_path):
    assert rectangular_wave_tables(2e8, contact_ratio=1.6, points_per_mesh=16).engagement_in_rad is None
    t = rectangular_wave_tables(2e8, contact_ratio=1.6, points_per_mesh=16, zone_edges=True)
    assert t.engagement_in_rad == 0.0 and t.engagement_out_rad == pytest.approx(1.6 * t.mesh_period_rad)
    back = load_tables(t.save(tmp_path / "a.gtab"))
    assert back.engagement_in_rad == t.engagement_in_rad and back.engagement_out_rad == t.engagement_out_rad
    # without the angles (imported tables, files written before the field) the JSON has no
    # 'engagement' key and reads back as None: plain interpolation
    plain = zone_tables(16, 1.5, engagement=False)
    meta, binary = plain.to_bytes()
    assert b'"engagement"' not in meta
    assert MeshTables.from_bytes(meta, binary).engagement_in_rad is None
    k0 = table_values(plain, [1.5 * T - 1e-9])[0]
    assert k0[0, 0] == table_values(plain, [1.5 * T - 1e-9], zone_edges=False)[0][0, 0]


def test_engagement_checks():
    t = zone_tables(16, 1.5, engagement=False)
    k = t.k_N_per_m.copy()
    with pytest.raises(TableError, match="k_N_per_m: slot 0 has k != 0 at node 20 "):
        tables_from_arrays(phi_period_rad=P * T, mesh_period_rad=T, k_N_per_m=k, teeth_pinion=Z1,
                           engagement_in_rad=0.0, engagement_out_rad=1.2 * T)
    with pytest.raises(TableError, match="give both or neither"):
        tables_from_arrays(phi_period_rad=P * T, mesh_period_rad=T, k_N_per_m=k, teeth_pinion=Z1,
                           engagement_in_rad=0.0)
    with pytest.raises(TableError, match="longer than P = 2 mesh periods"):
        tables_from_arrays(phi_period_rad=P * T, mesh_period_rad=T, k_N_per_m=k, teeth_pinion=Z1,
                           engagement_in_rad=0.0, engagement_out_rad=2.5 * T)


# ---------------------------------------------------------------- the C kernel, bit for bit
@pytest.fixture(scope="module")
def clib(tmp_path_factory):
    from gearfmu.fmu.pythonfmu_build import compile_kernel
    from gearfmu.fmu.runtime.kernel_api import load_kernel

    return load_kernel(compile_kernel(tmp_path_factory.mktemp("kernel")))


def _c_cuts(L, t):
    cuts = np.zeros(2 * t.slots * t.n_phi)
    st = L.gk_zone_cuts(t.slots, t.n_phi, t.phi_period_rad, t.mesh_period_rad, t.engagement_in_rad,
                        t.engagement_out_rad, cuts.ctypes.data)
    return st, cuts


@pytest.mark.parametrize("ppm,eps", [(16, 1.5), (16, 1.0 + 1.0 / math.sqrt(3.0)), (7, 1.9), (64, 1.3)])
def test_c_zone_cuts_equal_python(clib, ppm, eps):
    t = zone_tables(ppm, eps)
    st, cuts = _c_cuts(clib, t)
    assert st == 0
    assert np.array_equal(cuts.reshape(2, t.slots, t.n_phi), zone_cuts(t))
    # a zone of fewer than 3 cells: no cuts (the plain lookup) in both
    assert clib.gk_zone_cuts(P, 2 * P, P * T, T, 0.0, 1.2 * T, np.zeros(2 * P * 2 * P).ctypes.data) == 6


def replace_engagement(t, a, b):
    import dataclasses
    return dataclasses.replace(t, engagement_in_rad=a, engagement_out_rad=b)


def _run_c(L, t, T1, T2, w0, zeta, model, H, n, hmax, integrator, edges=True):
    st, cuts = _c_cuts(L, t)
    assert st == 0 or not edges
    return run_c(L, t, T1, T2, w0, zeta, model, None, H, n, hmax, integrator, cuts=cuts if edges else None)


@pytest.mark.parametrize("backward", [False, True])
@pytest.mark.parametrize("two_rows", [False, True])
@pytest.mark.parametrize("model", [0, 1])
@pytest.mark.parametrize("integrator", ["rk4", "rk4_kink", "rk4_node", "rk4_seg"])
def test_native_and_c_kernel_agree_bit_for_bit_with_zone_edges(clib, backward, two_rows, model, integrator):
    """The sub-cell lookup and the stops at the cuts pin every operation: numba and C give
    identical doubles (states and mesh force after each of 64 communication steps over more
    than two table periods, forwards and backwards, one and two torque rows, both damping laws)."""
    from gearfmu.dynamics.native import simulate

    t = dyn_tables(two_rows)
    sg = -1.0 if backward else 1.0
    w0 = sg * 300.0
    T1 = sg * 50.0
    T2 = T1 * t.base_radius_gear_m / t.base_radius_pinion_m
    H = t.mesh_period_rad / 300.0 / 8
    code = {"rk4": 0, "rk4_kink": 1, "rk4_node": 2, "rk4_seg": 3}[integrator]
    r = simulate(t, stop_time_s=64 * H, comm_step_s=H, max_step_s=H / 5, pinion_torque_Nm=T1, gear_torque_Nm=T2,
                 pinion_speed_start_rad_s=w0, damping_ratio=0.05, integrator=integrator,
                 damping_model=["elastobacklash", "contact_zone"][model])
    c, fc = _run_c(clib, t, T1, T2, w0, 0.05, model, H, 64, H / 5, code)
    nat = np.vstack([r.pinion_angle, r.pinion_speed, r.dte, r.dte_rate])
    assert abs(nat[0, -1] - nat[0, 0]) > 2 * t.phi_period_rad
    assert np.array_equal(nat, c)
    assert np.array_equal(r.mesh_force[1:], fc[1:])
    # and the edges change the run (the plain lookup is a different model)
    c0, _ = _run_c(clib, t, T1, T2, w0, 0.05, model, H, 64, H / 5, code, edges=False)
    assert not np.array_equal(c0, c)


@pytest.mark.parametrize("runtime", [pytest.param("pythonfmu", marks=pytest.mark.slow), "standalone"])
def test_fmu_with_zone_edges_agrees_with_native(tmp_path, runtime):
    """Both FMU runtimes pass the tables' engagement angles to the kernel (gk_zone_cuts,
    gk_set_zone_cuts): run by fmpy, every output equals the native run's (which reads the
    same angles), and differs from the run on the same tables without them."""
    import dataclasses

    from fmpy import simulate_fmu

    from gearfmu.dynamics.native import simulate
    from gearfmu.fmu.pythonfmu_build import build_fmu
    from gearfmu.fmu.standalone_build import build_standalone_fmu

    t = dyn_tables(False)
    w0, T1 = 300.0, 50.0
    T2 = T1 * t.base_radius_gear_m / t.base_radius_pinion_m
    H = t.mesh_period_rad / w0 / 4
    builder = build_fmu if runtime == "pythonfmu" else build_standalone_fmu
    path = builder(t, tmp_path / "zones.fmu", damping_ratio=0.05, pinion_speed_start_rad_s=w0,
                   pinion_torque_start_Nm=T1, gear_torque_start_Nm=T2, max_step_s=H / 5, integrator="rk4_node",
                   stop_time_s=40 * H, output_interval_s=H)
    res = simulate_fmu(str(path), stop_time=40 * H, output_interval=H, output=["dte", "mesh_force"])
    kw = dict(stop_time_s=40 * H, comm_step_s=H, max_step_s=H / 5, pinion_torque_Nm=T1, gear_torque_Nm=T2,
              pinion_speed_start_rad_s=w0, damping_ratio=0.05, integrator="rk4_node")
    r = simulate(t, **kw)
    plain = simulate(dataclasses.replace(t, engagement_in_rad=None, engagement_out_rad=None), **kw)
    for name in ("dte", "mesh_force"):
        assert np.max(np.abs(res[name] - getattr(r, name))) <= 1e-12 * np.ptp(getattr(r, name)), name
    assert np.max(np.abs(plain.dte - r.dte)) > 1e-4 * np.ptp(r.dte)
