#!/usr/bin/env python
"""Seed 003 Figs. 5-30: meshing errors, traditional vs new model, and the effects of
f_fa, f_Ha, speed, load and damping on the DTE, the dynamic mesh force and load sharing.

Gear pair: seed 003 Table 1 (examples/scenes/seed003_table1.toml) with a profile
deviation of eq 15 on every pinion tooth (f_r = 2); the contact-ratio variants
of Fig. 5 change the addendum coefficient of both gears (h_a* = 0.7, 1.0, 1.1
give epsilon = 1.27, 1.75, 1.91; seed 003 uses 1.28, 1.75, 1.92).  Figs. 6-9 use
the epsilon = 1.91 pair (seed 003 takes Fig. 5c/d), Figs. 10-30 the Table 1
pair (epsilon = 1.75, the pair the paper specifies).  Dynamics: time-indexed
SDOF of eq 3-6 in the dimensionless form of eq 7-9 (q = x / 1 um), damping
model 'contact_zone' (eq 8-9), defaults zeta = 0.04, T1 = 500 N*m, Omega_h = 0.6 as in
seed 003 section 3-4.  Independent cases run in parallel through
gearfmu.dynamics.sweeps.run_jobs (local processes, or Dask with --scheduler).

    python examples/seed003_figures.py [--quick] [--out DIR] [--scheduler ADDR] [--json]

Writes DIR/seed003_fig*.png, DIR/seed003_figures.json (summary with the
paper's statements and whether ours reproduce them) and
DIR/seed003_figures_cases.csv.  See docs/seed003.md.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SCENE = HERE / "scenes" / "seed003_table1.toml"
HA_FOR_EPS = {"1.28": 0.7, "1.75": 1.0, "1.92": 1.1}


def _log(msg):
    print(f"[seed003_figures] {msg}", file=sys.stderr, flush=True)


# ------------------------------------------------------------------ tables
def seed003_tables(ffa_um=0.0, fha_um=0.0, torque_Nm=500.0, addendum=1.0, form_periods=2.0):
    """Tables of the seed 003 Table 1 pair with eq 15 deviations on every pinion tooth."""
    from gearfmu import pipeline
    from gearfmu.scene.reader import load_scene

    d = tomllib.loads(SCENE.read_text())
    d["deviations"]["pinion"] = {"profile_form_um": float(ffa_um), "profile_slope_um": float(fha_um),
                                 "form_periods": float(form_periods)}
    d["operating"]["torque_Nm"] = float(torque_Nm)
    for g in ("pinion", "gear"):
        d["gears"][g]["addendum_coefficient"] = float(addendum)
    return pipeline.compute_tables(load_scene(d))


def adjusted_tables(tables, bump_m=5e-6):
    """Seed 003 Fig. 5d: change the single-pair error of the pair that does *not* govern
    the comprehensive error in the double-tooth zone (it gets a half-sine bump of
    +bump_m over each stretch where it lies above the envelope), so the comprehensive
    error -- and the traditional model -- stay the same while the pairs differ."""
    from gearfmu.tables.synthetic import tables_from_arrays

    k = tables.k_N_per_m.copy()
    e = tables.e_m.copy()
    env = tables.e_comprehensive_m
    for it in range(k.shape[0]):
        for j in range(k.shape[1]):
            above = (k[it, j] > 0) & (e[it, j] > env[it] + 1e-15)
            idx = np.flatnonzero(above)
            if idx.size == 0:
                continue
            runs = np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1)
            for r in runs:
                e[it, j, r] += bump_m * np.sin(np.pi * (np.arange(r.size) + 0.5) / r.size)
    return tables_from_arrays(
        tables.phi_period_rad, tables.mesh_period_rad, k, e, tables.backlash_half_m,
        tables.base_radius_pinion_m, tables.base_radius_gear_m, tables.inertia_pinion_kgm2,
        tables.inertia_gear_kgm2, tables.teeth_pinion, tables.teeth_gear, torque_Nm=tables.torque_Nm,
        contact_ratio=tables.contact_ratio, k_mean_N_per_m=tables.k_mean_N_per_m,
        e_comprehensive_m=env, provenance=dict(tables.provenance, variant="seed 003 Fig. 5d adjusted"))


# --------------------------------------------------------------- analysis
def engagement_position(theta1_rad, tables, slot):
    """Position of slot's pair in its engagement, in mesh periods from meshing-in (0 .. P)."""
    mp = tables.mesh_period_rad
    per = tables.slots * mp
    return (((np.asarray(theta1_rad) % per) - slot * mp) % per) / mp


def zone_of(pos, eps):
    """'front' double zone [0, eps-1), 'single' [eps-1, 1), 'rear' double [1, eps), 'out'."""
    return np.where(pos < eps - 1, "front", np.where(pos < 1, "single", np.where(pos < eps, "rear", "out")))


def summarize(tables, res):
    """Numbers of one steady-state case (SweepResult of one point with history)."""
    p = res.points[0]
    h = p.history
    eps = tables.contact_ratio
    out = {"omega_h": p.omega_h, "A_r": p.A_r.tolist(), "A_rms": p.A_rms,
           "q_p2p": p.q_max - p.q_min, "q_mean": p.q_mean,
           "mesh_force_mean_N": float(h.mesh_force_N.mean()),
           "mesh_force_p2p_N": float(np.ptp(h.mesh_force_N)),
           "pair_force_max_N": float(h.pair_force_N.max()),
           "contact_loss": p.contact_loss, "settled_rel": p.settled_rel}
    zones = set()
    ls_p2p = []
    for j in range(tables.slots):
        pos = engagement_position(h.theta1_rad, tables, j)
        lost = (h.k_N_per_m[:, j] > 0) & (h.contact_force_N[:, j] == 0)
        zones.update(zone_of(pos[lost], eps).tolist())
        inz = h.k_N_per_m[:, j] > 0
        ls_p2p.append(float(np.ptp(h.load_sharing[inz, j])) if inz.any() else 0.0)
    out["contact_loss_zones"] = sorted(zones)
    out["load_sharing_p2p"] = max(ls_p2p)
    # load-sharing fluctuation inside the double zones only (seed 003 Figs. 13, 25, 29)
    j = 0
    pos = engagement_position(h.theta1_rad, tables, j)
    z = zone_of(pos, eps)
    dbl = (z == "front") | (z == "rear")
    ideal = np.where(z == "front", (pos / max(eps - 1, 1e-9)), np.where(z == "rear", 1 - (pos - 1) / max(eps - 1, 1e-9), 1.0))
    out["load_sharing_dev_double"] = float(np.sqrt(np.mean((h.load_sharing[dbl, j] - ideal[dbl]) ** 2))) if dbl.any() else 0.0
    return out


# ------------------------------------------------------------------ cases
def build_cases(quick):
    """All independent cases: (group, name, tables, omega_h, torque, zeta, tag)."""
    cases = []
    t175 = {}

    def tab(ffa=15.0, fha=0.0, T=500.0):
        key = (ffa, fha, T)
        if key not in t175:
            t175[key] = seed003_tables(ffa, fha, T)
        return t175[key]

    t192 = seed003_tables(15.0, 0.0, 500.0, addendum=HA_FOR_EPS["1.92"])
    t192d = adjusted_tables(t192)
    for name, t in (("5c", t192), ("5d", t192d)):
        cases.append(("fig6-9", f"new {name}", t, 0.6, 500.0, 0.04))
        cases.append(("fig6-9", f"traditional {name}", t.traditional(), 0.6, 500.0, 0.04))
    ffas = [0.0, 5.0, 15.0, 25.0] + ([] if quick else [50.0, 75.0, 100.0])
    for f in ffas:
        cases.append(("fig10-13", f"f_fa={f:g} um", tab(f), 0.6, 500.0, 0.04))
    for f in (-10.0, 0.0, 10.0, 20.0):
        cases.append(("fig14-17", f"f_Ha={f:g} um", tab(15.0, f), 0.6, 500.0, 0.04))
    for om in (0.3, 0.6, 0.9):
        cases.append(("fig18-21", f"Omega_h={om:g}", tab(), om, 500.0, 0.04))
    for T in (200.0, 500.0, 800.0):
        cases.append(("fig22-25", f"T1={T:g} N m", tab(15.0, 0.0, T), 0.6, T, 0.04))
        cases.append(("fig22-25 reference", f"T1={T:g} N m", tab(0.0, 0.0, T), 0.6, T, 0.04))
    for z in (0.01, 0.04, 0.07):
        cases.append(("fig26-29", f"zeta={z:g}", tab(), 0.6, 500.0, z))
    return cases, t192, t192d


def fig5_tables():
    return {eps: seed003_tables(15.0, 0.0, 500.0, addendum=ha) for eps, ha in HA_FOR_EPS.items()}


# ------------------------------------------------------------------ plots
def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_fig5(tabs, t192d, path):
    plt = _plt()
    fig, axs = plt.subplots(1, 4, figsize=(16, 3.8))
    items = [(f"(a) eps = {tabs['1.28'].contact_ratio:.2f}", tabs["1.28"]),
             (f"(b) eps = {tabs['1.75'].contact_ratio:.2f}", tabs["1.75"]),
             (f"(c) eps = {tabs['1.92'].contact_ratio:.2f}", tabs["1.92"]),
             (f"(d) eps = {t192d.contact_ratio:.2f}, adjusted", t192d)]
    for ax, (title, t) in zip(axs, items):
        phi = t.phi_rad / t.mesh_period_rad
        for j in range(t.slots):
            e = np.where(t.k_N_per_m[0, j] > 0, t.e_m[0, j], np.nan) * 1e6
            ax.plot(phi, e, lw=1.0, label=f"pair in slot {j + 1}")
        ax.plot(phi, t.e_comprehensive_m[0] * 1e6, "k--", lw=1.3, label="comprehensive")
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("pinion angle / mesh period")
        ax.grid(alpha=0.3)
    axs[0].set_ylabel("meshing error (um)")
    axs[0].legend(fontsize=7)
    fig.suptitle("Seed 003 Fig. 5: single-pair and comprehensive meshing error, f_fa = 15 um, f_r = 2")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_group(group, items, path, title):
    """items: list of (name, tables, SweepResult)."""
    plt = _plt()
    fig, axs = plt.subplots(2, 3, figsize=(16, 8))
    for name, t, r in items:
        h = r.points[0].history
        mc = h.mesh_cycle
        n_last = 4 * r.points[0].history.q.size // max(1, int(round(mc[-1] - mc[0] + 1e-9)))
        sl = slice(-n_last - 1, None)
        axs[0, 0].plot(mc[sl] - mc[sl][0], h.q[sl], lw=1.0, label=name)
        W = r.points[0].history.q  # amplitude spectrum in mesh orders
        X = np.abs(np.fft.rfft(W - W.mean())) * 2 / W.size
        nm = int(round(mc[-1] - mc[0] + (mc[1] - mc[0])))
        orders = np.arange(X.size) / nm
        keep = orders <= 5.2
        axs[0, 1].plot(orders[keep], X[keep], lw=1.0, label=name)
        axs[0, 2].plot(mc[sl] - mc[sl][0], h.mesh_force_N[sl] / 1e3, lw=1.0, label=name)
        for j in range(t.slots):
            pos = engagement_position(h.theta1_rad, t, j)
            inz = h.k_N_per_m[:, j] > 0
            o = np.argsort(pos[inz])
            if j == 0:
                axs[1, 0].plot(pos[inz][o], h.pair_force_N[inz, j][o] / 1e3, ".", ms=1.5, label=name)
                axs[1, 1].plot(pos[inz][o], h.load_sharing[inz, j][o], ".", ms=1.5, label=name)
                axs[1, 2].plot(pos[inz][o], h.contact_force_N[inz, j][o] / 1e3, ".", ms=1.5, label=name)
    axs[0, 0].set(xlabel="tau / tau_z (last 4 mesh periods)", ylabel="q = x / 1 um", title="(a) DTE")
    axs[0, 1].set(xlabel="mesh order", ylabel="amplitude of q", title="(b) spectrum (amplitude)")
    axs[0, 2].set(xlabel="tau / tau_z", ylabel="kN", title="total dynamic mesh force (eq 12/13)")
    axs[1, 0].set(xlabel="engagement position (mesh periods from meshing-in)", ylabel="kN",
                  title="dynamic mesh force of one pair (eq 14)")
    axs[1, 1].set(xlabel="engagement position", ylabel="1", title="load sharing ratio of one pair")
    axs[1, 2].set(xlabel="engagement position", ylabel="kN", title="contact (spring) force of one pair")
    for ax in axs.flat:
        ax.grid(alpha=0.3)
    axs[0, 0].legend(fontsize=7)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def plot_fig30(omega, curves, path):
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8, 4.8))
    for i, (z, up, dn) in enumerate(curves):
        ax.plot(omega, up, "-", color=f"C{i}", lw=1.2, label=f"zeta = {z:g} up")
        ax.plot(omega, dn, "--", color=f"C{i}", lw=1.0, label=f"zeta = {z:g} down")
    ax.set(xlabel="Omega_h", ylabel="A_rms (q = x / 1 um, RMS)", yscale="log",
           title="Seed 003 Fig. 30: A_rms vs Omega_h, f_fa = 15 um, T1 = 500 N m")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# ------------------------------------------------------------------- main
def statements(summary):
    """The paper's qualitative statements, with our numbers and whether they hold."""
    g = summary["groups"]
    out = []

    def add(text, holds, numbers):
        out.append({"statement": text, "holds": bool(holds), "numbers": numbers})

    f69 = g["fig6-9"]
    d = summary["fig7"]
    add("Fig. 7: the traditional model's total force differs from the new model's in the double-tooth zone "
        "(by more than 1 % of the mean force)",
        d["diff_double_N"] > 0.01 * f69["new 5c"]["mesh_force_mean_N"], d)
    add("Fig. 7: ... most in the double-tooth zone (largest difference there rather than in the single zone)",
        d["diff_double_N"] > d["diff_single_N"], d)
    add("Fig. 6: the traditional model gives the same response for Fig. 5c and 5d errors, the new model does not",
        summary["fig6"]["traditional_identical"] and summary["fig6"]["new_q_rms_diff"] > 0, summary["fig6"])
    ff = g["fig10-13"]
    a = [ff[k]["A_rms"] for k in ("f_fa=0 um", "f_fa=5 um", "f_fa=15 um", "f_fa=25 um")]
    add("Fig. 10: growing f_fa (0, 5, 15, 25 um) raises the DTE amplitude", all(np.diff(a) > 0), {"A_rms": a})
    add("Fig. 12: with f_fa = 25 um a pair loses contact in the rear double-tooth zone (Omega_h 0.6, zeta 0.04, T1 500 N m)",
        "rear" in ff["f_fa=25 um"]["contact_loss_zones"],
        {k: v["contact_loss_zones"] for k, v in ff.items()})
    sp = g["fig18-21"]
    add("Fig. 18: at Omega_h = 0.9 the first harmonic dominates",
        sp["Omega_h=0.9"]["A_r"][0] > max(sp["Omega_h=0.9"]["A_r"][1:]), {k: v["A_r"] for k, v in sp.items()})
    ld = g["fig22-25"]
    add("Fig. 23: with T1 rising (200, 500, 800 N m) the mean total mesh force rises",
        ld["T1=200 N m"]["mesh_force_mean_N"] < ld["T1=500 N m"]["mesh_force_mean_N"] < ld["T1=800 N m"]["mesh_force_mean_N"],
        {k: v["mesh_force_mean_N"] for k, v in ld.items()})
    add("Fig. 22: with T1 rising the second harmonic grows relative to the first",
        ld["T1=200 N m"]["A_r"][1] / ld["T1=200 N m"]["A_r"][0] < ld["T1=800 N m"]["A_r"][1] / ld["T1=800 N m"]["A_r"][0],
        {k: v["A_r"] for k, v in ld.items()})
    lsd = summary["fig25_load_sharing_deviation"]
    add("Fig. 25: with T1 rising the influence of the profile deviation on load sharing decreases "
        "(RMS difference of the load sharing ratio with and without f_fa falls)",
        lsd["T1=200 N m"] > lsd["T1=500 N m"] > lsd["T1=800 N m"], lsd)
    dz = g["fig26-29"]
    add("Fig. 26b: with zeta rising (0.01, 0.04, 0.07) the second harmonic falls and the first rises slightly",
        dz["zeta=0.01"]["A_r"][1] > dz["zeta=0.04"]["A_r"][1] > dz["zeta=0.07"]["A_r"][1]
        and dz["zeta=0.01"]["A_r"][0] < dz["zeta=0.07"]["A_r"][0],
        {k: v["A_r"] for k, v in dz.items()})
    add("Fig. 26a-27: with zeta rising the DTE and total force fluctuations (peak to peak) decrease",
        dz["zeta=0.01"]["q_p2p"] >= dz["zeta=0.04"]["q_p2p"] >= dz["zeta=0.07"]["q_p2p"]
        and dz["zeta=0.01"]["mesh_force_p2p_N"] >= dz["zeta=0.07"]["mesh_force_p2p_N"],
        {k: [v["q_p2p"], v["mesh_force_p2p_N"]] for k, v in dz.items()})
    if "fig30" in summary:
        f30 = summary["fig30"]
        add("Fig. 30: at zeta = 0.01 up- and down-sweeps land on different branches (jumps), "
            "at 0.04 and 0.07 they coincide (within 5 %)",
            f30["zeta=0.01"]["max_up_down_rel_diff"] > 0.1 and f30["zeta=0.04"]["max_up_down_rel_diff"] < 0.05
            and f30["zeta=0.07"]["max_up_down_rel_diff"] < 0.05,
            {k: v["max_up_down_rel_diff"] for k, v in f30.items() if k.startswith("zeta")})
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", default="build/seed003")
    from gearfmu.common.executors import add_scheduler_option  # the one --scheduler option
    add_scheduler_option(ap)
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--json", action="store_true", help="print the summary JSON on stdout")
    ap.add_argument("--no-fig30", action="store_true", help="skip the A_rms sweeps of Fig. 30")
    args = ap.parse_args(argv)

    from gearfmu.dynamics.sweeps import PointSettings, SweepJob, run_jobs

    t0 = time.perf_counter()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    _log("computing tables")
    cases, t192, t192d = build_cases(args.quick)
    tabs5 = fig5_tables()
    plot_fig5(tabs5, t192d, out / "seed003_fig5_errors.png")
    st = PointSettings(settle_meshes=150 if args.quick else 400, record_meshes=20 if args.quick else 40,
                       keep_history=True)
    jobs = [SweepJob(t, [om], T, z, settings=st, continuation=False, label=f"{g}: {n}")
            for g, n, t, om, T, z in cases]
    fig30_om = np.round(np.arange(0.3, 1.2001, 0.02 if args.quick else 0.01), 6)
    st30 = PointSettings(settle_meshes=100 if args.quick else 200, record_meshes=20 if args.quick else 40)
    zetas30 = (0.01, 0.04, 0.07)
    if not args.no_fig30:
        t15 = next(c[2] for c in cases if c[1] == "f_fa=15 um")
        for z in zetas30:
            jobs.append(SweepJob(t15, fig30_om, 500.0, z, settings=st30, label=f"fig30 up zeta={z}"))
            jobs.append(SweepJob(t15, fig30_om[::-1].copy(), 500.0, z, settings=st30, label=f"fig30 down zeta={z}"))
    _log(f"{len(jobs)} jobs")
    results = run_jobs(jobs, scheduler=args.scheduler, max_workers=args.workers, progress=True)
    summary = {"groups": {}, "contact_ratio_fig6_9": t192.contact_ratio,
               "contact_ratios_fig5": {k: v.contact_ratio for k, v in tabs5.items()},
               "settings": {"settle_meshes": st.settle_meshes, "record_meshes": st.record_meshes,
                            "length_scale_m": st.length_scale_m, "damping_model": "contact_zone"}}
    by_group = {}
    for (g, n, t, om, T, z), r in zip(cases, results):
        summary["groups"].setdefault(g, {})[n] = dict(summarize(t, r), zeta=z, torque_Nm=T)
        by_group.setdefault(g, []).append((n, t, r))
    # Fig. 6/7 comparisons
    res = {n: r for (g, n, t, om, T, z), r in zip(cases, results) if g == "fig6-9"}
    hn, ht = res["new 5c"].points[0].history, res["traditional 5c"].points[0].history
    pos = engagement_position(hn.theta1_rad, t192, 0) % 1.0
    dbl = pos < (t192.contact_ratio - 1)
    diff = np.abs(hn.mesh_force_N - ht.mesh_force_N)
    summary["fig7"] = {"diff_double_N": float(diff[dbl].max()), "diff_single_N": float(diff[~dbl].max())}
    qa, qb = res["traditional 5c"].points[0].history.q, res["traditional 5d"].points[0].history.q
    na, nb = res["new 5c"].points[0].history.q, res["new 5d"].points[0].history.q
    summary["fig6"] = {"traditional_identical": bool(np.array_equal(qa, qb)),
                       "new_q_rms_diff": float(np.sqrt(np.mean((na - nb) ** 2)))}
    ls = {}
    ref = {n: r for (g, n, t, om, T, z), r in zip(cases, results) if g == "fig22-25 reference"}
    for (g, n, t, om, T, z), r in zip(cases, results):
        if g == "fig22-25":
            a, b = r.points[0].history, ref[n].points[0].history
            inz = a.k_N_per_m > 0
            ls[n] = float(np.sqrt(np.mean((a.load_sharing[inz] - b.load_sharing[inz]) ** 2)))
    summary["fig25_load_sharing_deviation"] = ls
    by_group.pop("fig22-25 reference", None)
    titles = {"fig6-9": "Seed 003 Figs. 6-9: new vs traditional model, eps = %.2f, Omega_h 0.6, zeta 0.04, T1 500 N m" % t192.contact_ratio,
              "fig10-13": "Seed 003 Figs. 10-13: profile form deviation f_fa", "fig14-17": "Seed 003 Figs. 14-17: profile slope deviation f_Ha (f_fa = 15 um)",
              "fig18-21": "Seed 003 Figs. 18-21: speed Omega_h", "fig22-25": "Seed 003 Figs. 22-25: load T1",
              "fig26-29": "Seed 003 Figs. 26-29: damping ratio zeta"}
    for g, items in by_group.items():
        plot_group(g, items, out / f"seed003_{g.replace('-', '_')}.png", titles[g])
    if not args.no_fig30:
        rr = results[len(cases):]
        curves = [(z, rr[2 * i].A_rms, rr[2 * i + 1].A_rms[::-1]) for i, z in enumerate(zetas30)]
        plot_fig30(fig30_om, curves, out / "seed003_fig30_arms.png")
        summary["fig30"] = {"omega": fig30_om.tolist(),
                            **{f"zeta={z:g}": {"arms_up": u.tolist(), "arms_down": d.tolist(),
                                               "max_up_down_rel_diff": float(np.max(np.abs(u - d) / d))}
                               for z, u, d in curves}}
    summary["statements"] = statements(summary)
    summary["wall_s"] = time.perf_counter() - t0
    (out / "seed003_figures.json").write_text(json.dumps(summary, indent=1))
    rows = []
    for g, d in summary["groups"].items():
        for n, v in d.items():
            rows.append(f'{g},{n},{v["omega_h"]},{v["torque_Nm"]},{v["zeta"]},{v["A_r"][0]:.6g},{v["A_r"][1]:.6g},'
                        f'{v["A_r"][2]:.6g},{v["A_rms"]:.6g},{v["q_p2p"]:.6g},{v["mesh_force_mean_N"]:.6g},'
                        f'{v["mesh_force_p2p_N"]:.6g},{int(v["contact_loss"])},{"|".join(v["contact_loss_zones"])}')
    (out / "seed003_figures_cases.csv").write_text(
        "group,case,omega_h,torque_Nm,zeta,A1,A2,A3,A_rms,q_p2p,mesh_force_mean_N,mesh_force_p2p_N,contact_loss,loss_zones\n"
        + "\n".join(rows) + "\n")
    for s in summary["statements"]:
        _log(f"{'HOLDS ' if s['holds'] else 'DIFFERS'}: {s['statement']}")
    _log(f"done in {summary['wall_s']:.1f} s; wrote {out}/seed003_*.png, seed003_figures.json, seed003_figures_cases.csv")
    if args.json:
        print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
