#!/usr/bin/env python
"""Seed 003 Fig. 3: A_rms of the first three mesh harmonics of the DTE against Omega_h.

The seed 003 Table 1 pair (Kahraman & Blankenship test gears,
examples/scenes/seed003_table1.toml), tables from gearfmu.pipeline.compute_tables,
zeta = 0.02, T = 340 N*m, no meshing error (e = 0), damping model 'contact_zone'
(eq 8-9: constant damping per pair, rho = 2 in the double-tooth zone), the
dimensionless form of eq 7-9 with q = x/l, l = 1 um.  An up-sweep and a
down-sweep in Omega_h, each point continuing from the previous point's state,
transients dropped; A_r and A_rms from eq 10-11 (gearfmu.dynamics.harmonics, RMS
normalisation, BW = 2 shaft orders).  The two sweeps run in parallel through
gearfmu.dynamics.sweeps (local process pool, or a Dask cluster with --scheduler).

    python examples/seed003_arms.py [--json] [--quick] [--out DIR] [--scheduler tcp://HOST:PORT]

Writes DIR/seed003_fig3_arms.png, .csv and .json (default DIR = build/seed003);
--json prints the JSON object on stdout: {"omega", "arms_up", "arms_down",
"jumps", "features", "peaks", "hysteresis", "seed_jumps", "comparison", ...}.
Progress goes to stderr.  See docs/seed003.md.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SCENE = HERE / "scenes" / "seed003_table1.toml"
#: seed 003 section 2.2: "the frequency of each inflection point (near Omega_h = 0.28, 0.38 and 0.6)"
SEED_JUMPS = (0.28, 0.38, 0.6)


def _log(msg: str) -> None:
    print(f"[seed003_arms] {msg}", file=sys.stderr, flush=True)


def parse_args(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--json", action="store_true", help="print the result as JSON on stdout")
    ap.add_argument("--quick", action="store_true", help="coarse, short sweep (seconds)")
    ap.add_argument("--out", default="build/seed003", help="output directory (PNG, CSV, JSON)")
    from gearfmu.common.executors import add_scheduler_option  # the one --scheduler option
    add_scheduler_option(ap)
    ap.add_argument("--workers", type=int, default=None, help="local worker processes (default 2)")
    ap.add_argument("--omega-min", type=float, default=0.15)
    ap.add_argument("--omega-max", type=float, default=1.0)
    ap.add_argument("--step", type=float, default=None, help="Omega_h step (default 0.0025, quick 0.01)")
    ap.add_argument("--zeta", type=float, default=0.02, help="damping ratio (seed 003: 0.02)")
    ap.add_argument("--torque", type=float, default=340.0, help="pinion torque N*m (seed 003: 340)")
    return ap.parse_args(argv)


def compare_with_seed(jumps, features, seed=SEED_JUMPS, max_distance=0.06):
    """Nearest of our features to each Omega_h of seed 003 (None beyond max_distance)."""
    out = []
    for s in seed:
        best = None
        for f in features:
            if f["kind"] == "peak":
                continue
            d = f["omega_h"] - s
            if abs(d) <= max_distance and (best is None or abs(d) < abs(best["difference"])):
                best = {"seed": s, "ours": f["omega_h"], "kind": f["kind"], "difference": round(d, 6)}
        out.append(best if best is not None else {"seed": s, "ours": None, "kind": None, "difference": None})
    return out


def run(args) -> dict:
    from gearfmu import pipeline
    from gearfmu.dynamics.sweeps import PointSettings, SweepJob, find_jumps, run_jobs

    t0 = time.perf_counter()
    scene = pipeline.load(str(SCENE))
    tables = pipeline.compute_tables(scene)
    step = args.step if args.step is not None else (0.01 if args.quick else 0.0025)
    n = int(math.floor((args.omega_max - args.omega_min) / step + 1e-9)) + 1
    omega = np.round(args.omega_min + step * np.arange(n), 10)
    settings = (PointSettings(settle_meshes=150, record_meshes=40) if args.quick
                else PointSettings(settle_meshes=300, record_meshes=100))
    common = dict(tables=tables, pinion_torque_Nm=args.torque, damping_ratio=args.zeta,
                  damping_model="contact_zone", continuation=True, settings=settings)
    jobs = [SweepJob(omega_h=omega, label="up", **common),
            SweepJob(omega_h=omega[::-1].copy(), label="down", **common)]
    _log(f"{n} points x 2 sweeps, Omega_h {omega[0]:g}..{omega[-1]:g} step {step:g}, "
         f"settle {settings.settle_meshes} + record {settings.record_meshes} mesh periods per point")
    up, down = run_jobs(jobs, scheduler=args.scheduler, max_workers=args.workers if args.workers else None,
                        progress=True)
    arms_up = up.A_rms
    arms_down = down.A_rms[::-1]
    feat = find_jumps(omega, [arms_up, arms_down])
    cmp = compare_with_seed(feat["jumps"], feat["features"])
    wn = up.omega_n_rad_s
    res = {
        "figure": "seed 003 Fig. 3",
        "omega": omega.tolist(),
        "arms_up": arms_up.tolist(),
        "arms_down": arms_down.tolist(),
        "A_r_up": up.A_r.tolist(),
        "A_r_down": down.A_r[::-1].tolist(),
        "contact_loss_up": up.contact_loss.tolist(),
        "contact_loss_down": down.contact_loss[::-1].tolist(),
        "settled_rel_max": float(np.nanmax(np.concatenate([up.settled_rel, down.settled_rel]))),
        "jumps": feat["jumps"],
        "features": feat["features"],
        "peaks": feat["peaks"],
        "hysteresis": feat["hysteresis"],
        "seed_jumps": list(SEED_JUMPS),
        "comparison": cmp,
        "zeta": args.zeta, "torque_Nm": args.torque, "damping_model": "contact_zone",
        "length_scale_m": settings.length_scale_m, "bandwidth_orders": settings.bandwidth_orders,
        "normalization": "rms",
        "settle_meshes": settings.settle_meshes, "record_meshes": settings.record_meshes,
        "k_mean_N_per_m": tables.k_mean_N_per_m, "equivalent_mass_kg": tables.equivalent_mass_kg,
        "omega_n_rad_s": wn, "natural_frequency_Hz": wn / (2 * math.pi),
        "contact_ratio": tables.contact_ratio,
        "quick": bool(args.quick), "scheduler": args.scheduler,
        "wall_s": time.perf_counter() - t0,
    }
    return res


def write_outputs(res: dict, out_dir: Path) -> dict:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir.mkdir(parents=True, exist_ok=True)
    om = np.array(res["omega"])
    up = np.array(res["arms_up"])
    dn = np.array(res["arms_down"])
    fig, ax = plt.subplots(figsize=(8, 4.8))
    ax.plot(om, up, "-", color="C0", lw=1.4, label="up-sweep")
    ax.plot(om, dn, "--", color="C3", lw=1.2, label="down-sweep")
    for f in res["features"]:
        if f["kind"] in ("inflection", "shoulder") or f["kind"].startswith("jump"):
            ax.axvline(f["omega_h"], color="0.6", lw=0.7, ls=":")
    for s in res["seed_jumps"]:
        ax.axvline(s, color="C2", lw=0.9, ls="-.", alpha=0.7)
    ax.plot([], [], color="0.6", ls=":", label="features found (jumps/inflections/shoulders)")
    ax.plot([], [], color="C2", ls="-.", label="seed 003: 0.28, 0.38, 0.6")
    ax.set_xlabel(r"$\Omega_h$ = mesh frequency / $\omega_n$")
    ax.set_ylabel(r"$A_{rms}$ (q = x / 1 $\mu$m, RMS)")
    ax.set_title(f"Seed 003 Fig. 3: Table 1 pair, $\\zeta$ = {res['zeta']}, T = {res['torque_Nm']:g} N·m, e = 0")
    ax.set_yscale("log")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    png = out_dir / "seed003_fig3_arms.png"
    fig.savefig(png, dpi=130)
    plt.close(fig)
    csv = out_dir / "seed003_fig3_arms.csv"
    aru = np.array(res["A_r_up"])
    ard = np.array(res["A_r_down"])
    data = np.column_stack([om, up, dn, aru, ard])
    hdr = "omega_h,arms_up,arms_down,A1_up,A2_up,A3_up,A1_down,A2_down,A3_down"
    np.savetxt(csv, data, delimiter=",", header=hdr, comments="", fmt="%.10g")
    js = out_dir / "seed003_fig3_arms.json"
    res = dict(res, png=str(png), csv=str(csv), json=str(js))
    js.write_text(json.dumps(res, indent=1))
    return res


def main(argv=None) -> int:
    args = parse_args(argv)
    res = run(args)
    res = write_outputs(res, Path(args.out))
    _log(f"done in {res['wall_s']:.1f} s; features at Omega_h {res['jumps']}; peaks {res['peaks']}")
    for c in res["comparison"]:
        _log(f"seed {c['seed']}: ours {c['ours']} ({c['kind']}), difference {c['difference']}")
    _log(f"wrote {res['png']}, {res['csv']}, {res['json']}")
    if args.json:
        print(json.dumps(res))
    return 0


if __name__ == "__main__":
    sys.exit(main())
