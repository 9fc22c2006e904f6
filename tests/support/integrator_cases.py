"""The integrator tests' reference and cases (tests/unit/dynamics/test_integrators.py, test_rk4_seg.py,
test_subcell.py).

* :func:`reference`: scipy.integrate.solve_ivp (DOP853) restarted at every table node and every
  contact-mode change, the events located by scipy's own event finder on its dense output; the
  right-hand side, the per-cell table interpolation and the switching functions written here in
  plain numpy from docs/model.md and seed 003 eq 1-6 (not by gearfmu);
* :func:`order_fit`: the order of a one-step method read off log(error) against log(h) (Hairer,
  Norsett & Wanner, Solving ODEs I, sec. II.3);
* :func:`run_c`: the C kernel (gearfmu/fmu/kernel/gearkernel.c) stepped through ctypes;
* :func:`impact_case`, :func:`tent_case`: tables and inputs with impacts, and with kinks at nodes.
"""
import dataclasses
import math

import numpy as np
from scipy.integrate import solve_ivp

from gearfmu.tables.synthetic import rectangular_wave_tables

ATOL = [1e-14, 1e-10, 1e-17, 1e-12]   # theta1 rad, omega1 rad/s, x m, v m/s


def reference(tb, T1, T2, zeta, y0, t_eval, model="elastobacklash", sdof=False, rtol=1e-10):
    """Event-located DOP853 solution of docs/model.md at t_eval (rows: theta1, omega1, x, v).

    The mode (table cell n, per pair region and elastobacklash branch) is held on
    each segment; every switching function of the mode is a terminal event with
    direction -1 (leaving the mode); at an event the new mode is read from the
    state advanced by a look-ahead of 1e-7 of a table step along the old field."""
    k, e, b = tb.k_N_per_m[0], tb.e_m[0], tb.backlash_half_m
    P, N = k.shape
    dphi = tb.phi_period_rad / N
    rb1, rb2 = tb.base_radius_pinion_m, tb.base_radius_gear_m
    i1, i2 = tb.inertia_pinion_kgm2, tb.inertia_gear_kgm2
    me = i1 * i2 / (i1 * rb2 ** 2 + i2 * rb1 ** 2)          # seed 003, below eq 2
    c = 2.0 * zeta * math.sqrt(tb.k_mean_N_per_m * me)
    ebl = model == "elastobacklash"

    def cell(n, th):
        j0 = n % N
        j1 = (j0 + 1) % N
        w = th / dphi - n
        kk = k[:, j0] + w * (k[:, j1] - k[:, j0])
        ee = e[:, j0] + w * (e[:, j1] - e[:, j0])
        bb = b[:, j0] + w * (b[:, j1] - b[:, j0])
        es = (e[:, j1] - e[:, j0]) / dphi
        kpos = (k[:, j0] + k[:, j1]) > 0
        return kk, ee, es, bb, kpos

    def parts(y, n):
        kk, ee, es, bb, kpos = cell(n, y[0])
        d = y[2] - ee
        fd = c * (y[3] - es * y[1])
        fdrive = kk * (d - bb)
        fback = kk * (d + bb)
        return d, bb, fd, fdrive, fback, kpos

    def classify(y, n):
        """region (1, 0, -1) and branch ('two', 'sum', 'zero') per pair, docs/model.md rules."""
        d, bb, fd, fdr, fbk, _ = parts(y, n)
        mode = []
        for j in range(P):
            if d[j] > bb[j]:
                br = "two" if fdr[j] < fd[j] else ("zero" if fdr[j] + fd[j] < 0 else "sum")
                mode.append((1, br))
            elif d[j] < -bb[j]:
                br = "two" if fbk[j] > fd[j] else ("zero" if fbk[j] + fd[j] > 0 else "sum")
                mode.append((-1, br))
            else:
                mode.append((0, ""))
        return mode

    def force(y, n, mode):
        d, bb, fd, fdr, fbk, kpos = parts(y, n)
        F = 0.0
        for j, (r, br) in enumerate(mode):
            fc = fdr[j] if r == 1 else (fbk[j] if r == -1 else 0.0)
            if ebl:
                F += 0.0 if (r == 0 or br == "zero") else (2 * fc if br == "two" else fc + fd[j])
            elif kpos[j]:
                F += fc + fd[j]
        return F

    def rhs(n, mode):
        def f(t, y):
            F = force(y, n, mode)
            if sdof:
                return [y[1], 0.0, y[3], (T1 / rb1 - F) / me]
            a1 = (T1 - rb1 * F) / i1
            return [y[1], a1, y[3], rb1 * a1 - rb2 * (rb2 * F - T2) / i2]
        return f

    def events(n, mode):
        evs = [lambda t, y: y[0] - n * dphi, lambda t, y: (n + 1) * dphi - y[0]]
        for j, (r, br) in enumerate(mode):
            def g(t, y, j=j, r=r, br=br, which=0):
                d, bb, fd, fdr, fbk, _ = parts(y, n)
                return d[j] - bb[j] if r == 1 else (-(d[j] + bb[j]) if r == -1 else 0.0)
            if r == 0:
                evs += [lambda t, y, j=j: (lambda p: p[1][j] - p[0][j])(parts(y, n)),
                        lambda t, y, j=j: (lambda p: p[0][j] + p[1][j])(parts(y, n))]
                continue
            evs.append(g)
            if not ebl:
                continue
            s = 1.0 if r == 1 else -1.0
            fci = 3 if r == 1 else 4
            if br == "two":     # min/max picks fc: leave when fc passes fd
                evs.append(lambda t, y, j=j, s=s, fci=fci: (lambda p: s * (p[2][j] - p[fci][j]))(parts(y, n)))
            elif br == "sum":
                evs.append(lambda t, y, j=j, s=s, fci=fci: (lambda p: s * (p[fci][j] - p[2][j]))(parts(y, n)))
                evs.append(lambda t, y, j=j, s=s, fci=fci: (lambda p: s * (p[fci][j] + p[2][j]))(parts(y, n)))
            else:
                evs.append(lambda t, y, j=j, s=s, fci=fci: (lambda p: -s * (p[fci][j] + p[2][j]))(parts(y, n)))
        for ev in evs:
            ev.terminal = True
            ev.direction = -1
        return evs

    t_end = t_eval[-1]
    t, y = 0.0, np.array(y0, dtype=float)
    n = int(math.floor(y[0] / dphi))
    mode = classify(y, n)
    out = np.full((4, len(t_eval)), np.nan)
    segments = 0
    while True:
        sol = solve_ivp(rhs(n, mode), (t, t_end), y, method="DOP853", rtol=rtol, atol=ATOL,
                        events=events(n, mode), dense_output=True)
        assert sol.status in (0, 1), sol.message
        t_new = sol.t[-1]
        sel = (t_eval >= t) & (t_eval <= t_new)
        if np.any(sel):
            out[:, sel] = sol.sol(t_eval[sel])
        segments += 1
        if sol.status == 0:
            break
        f_old = np.array(rhs(n, mode)(t_new, sol.y[:, -1]))
        y = sol.y[:, -1].copy()
        t = t_new
        look = y + f_old * (1e-7 * dphi / max(abs(y[1]), 1e-9))
        n = int(math.floor(look[0] / dphi))
        mode = classify(look, n)
    return out, segments


def impact_case():
    """Rectangular-wave TVMS (seed 003 Fig. 2 idealisation), per-pair sine
    errors of 4 and 8 um, backlash 2b = 40 um, light load and an impact start
    on the back-flank side: teeth separate and hit both flanks."""
    tb = rectangular_wave_tables(2e8, contact_ratio=1.6, backlash_half_m=20e-6, points_per_mesh=16,
                                 pair_error_m=lambda j, u: 4e-6 * (1 + j) * np.sin(np.pi * u))
    T1, w0, zeta, x0 = 5.0, 200.0, 0.03, -35e-6
    return tb, T1, T1 * tb.base_radius_gear_m / tb.base_radius_pinion_m, w0, zeta, x0


def tent_case():
    """Tables linear between a few nodes (docs/native.md "rk4_node"): the impact case's
    grid (N = 32, P = 2), both slots k = 1e8 N/m, no backlash; slot 0 carries a tent
    error of 5 um over nodes 0..8..16 (kinks at nodes 0, 8, 16), zero over 16..32;
    slot 1 no error.  Load 20 um of mean deflection, damping ratio 0.1, start 1 um
    off it (contact_zone: the damping force c*(v - e'*omega1) jumps at the kinks)."""
    tb = impact_case()[0]
    P, N = tb.slots, tb.n_phi
    i = np.arange(N) % 32
    tent = np.where(i <= 8, i / 8.0, np.where(i <= 16, (16 - i) / 8.0, 0.0)) * 5e-6
    e = np.zeros((1, P, N))
    e[0, 0] = tent
    tb = dataclasses.replace(tb, k_N_per_m=np.full((1, P, N), 1e8), e_m=e, backlash_half_m=np.zeros((P, N)),
                             e_comprehensive_m=e[:, 0].copy(), static_te_m=None, k_mean_N_per_m=2e8)
    T1 = 2e8 * 20e-6 * tb.base_radius_pinion_m
    return tb, T1, T1 * tb.base_radius_gear_m / tb.base_radius_pinion_m, 200.0, 0.1, 21e-6


def order_fit(hs, errs):
    """The order p of a global error C h^p: the slope of a least-squares line through (log h, log error)."""
    return float(np.polyfit(np.log(hs), np.log(errs), 1)[0])


def run_c(L, tb, T1, T2, w0, zeta, model, x0, H, n, hmax, integrator, cuts=None):
    """n communication steps of the C kernel from theta1 = 0, omega1 = w0, x = x0, v = 0 (x0 None:
    gk_initialize's quasi-static start); ``cuts``: contact-zone cuts of gk_zone_cuts to read.
    Returns the states (4, n + 1) and the mesh force after every step."""
    k = np.ascontiguousarray(tb.k_N_per_m)
    e = np.ascontiguousarray(tb.e_m)
    b = np.ascontiguousarray(tb.backlash_half_m)
    tq = np.ascontiguousarray(tb.torque_Nm, dtype=float)
    m = np.zeros(L.gk_sizeof_model() // 8 + 2)
    s = np.array([0.0, w0, 0.0 if x0 is None else x0, 0.0])
    out = np.zeros(L.gk_n_outputs(tb.slots))
    assert L.gk_init(m.ctypes.data, tb.slots, tb.n_phi, len(tq), tq.ctypes.data, k.ctypes.data,
                     e.ctypes.data, b.ctypes.data, tb.phi_period_rad, tb.base_radius_pinion_m,
                     tb.base_radius_gear_m, tb.inertia_pinion_kgm2, tb.inertia_gear_kgm2,
                     tb.k_mean_N_per_m) == 0
    if cuts is not None:
        assert L.gk_set_zone_cuts(m.ctypes.data, cuts.ctypes.data) == 0
    assert L.gk_set_damping(m.ctypes.data, zeta, model) == 0
    assert L.gk_set_integrator(m.ctypes.data, integrator) == 0
    if x0 is None:
        assert L.gk_initialize(m.ctypes.data, s.ctypes.data, 0.0, w0, T1) == 0
    rows, forces = [s.copy()], [np.nan]
    for _ in range(n):
        assert L.gk_do_step(m.ctypes.data, s.ctypes.data, T1, T2, H, hmax, out.ctypes.data) == 0
        rows.append(s.copy())
        forces.append(out[5])
    return np.array(rows).T, np.array(forces)
