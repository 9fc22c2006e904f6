#!/usr/bin/env python
"""The hard cases of the dynamic model: native solver against the event-located reference, as PNGs.

For every case of gearfmu.bench.HARD_CASES (1 heavy load, 2 single-sided impacts,
3 double-sided impacts, 4 zeta = 0.01 near resonance, 5 HCR eps 2.4 with five slots,
6 Omega_h = 2, 7 torque steps, and the default scene's computed tables) this runs
the reference (gearfmu.dynamics.reference: scipy DOP853, rtol 1e-10, restarted at every
table kink and contact change), the native solver with 'rk4_node' (the default),
'rk4_kink' and 'rk4' at the same internal step (``--substeps`` per communication step,
H = mesh period/4), and plots DTE and total mesh force against time with the
errors of the integrators below.  Case 8 (the FMU with communication steps up to
ten mesh periods) runs the FMU built with defaults through fmpy on the
single-sided impact case with communication steps of 1/4, 1, 5 and 10 mesh periods
against the native run (default integrator) with the same internal steps (skip with --no-fmu).

    python examples/hard_cases.py [--out DIR] [--substeps 16] [--json] [--no-fmu]

Writes DIR/hard_case_<name>.png and .csv (time, reference and both native runs),
DIR/hard_cases.json (errors: max and RMS of |native - reference| over the
communication instants relative to the reference's range, wall times) and
DIR/hard_case_8_fmu.png.  Default DIR = examples/output/hard_cases.  --json
prints the summary on stdout; progress goes to stderr.  See
docs/dynamics_validation.md.
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from gearfmu.common.vocabulary import DEFAULT_INTEGRATOR  # noqa: E402

TITLES = {
    "heavy_load": "1 heavy load, contact never lost",
    "single_sided_impacts": "2 single-sided impacts",
    "double_sided_impacts": "3 double-sided impacts",
    "low_damping_resonance": "4 zeta = 0.01 near resonance",
    "high_contact_ratio": "5 HCR eps = 2.4, five slots",
    "omega_h_2": "6 Omega_h = 2",
    "torque_steps": "7 torque steps 340 -> 60 -> 900 N m",
    "computed_default_scene": "computed tables (default scene)",
}


def _log(msg: str) -> None:
    print(f"[hard_cases] {msg}", file=sys.stderr, flush=True)


def _plot_case(path, name, ref, runs, substeps):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t_ms = ref.time_s * 1e3
    fig, ax = plt.subplots(2, 2, figsize=(12, 6.5), sharex=True)
    for col, (attr, scale, unit) in enumerate((("dte", 1e6, "DTE (um)"), ("mesh_force", 1e-3, "mesh force (kN)"))):
        a = ax[0, col]
        a.plot(t_ms, getattr(ref, attr) * scale, "k-", lw=2.5, alpha=0.35, label="reference (DOP853, events)")
        for integ, (r, _) in runs.items():
            a.plot(t_ms, getattr(r, attr) * scale, lw=0.9, ls="-" if integ == DEFAULT_INTEGRATOR else "--",
                   label=f"native {integ}, H/{substeps}")
        a.set_ylabel(unit)
        a.grid(alpha=0.3)
        rng = float(np.ptp(getattr(ref, attr))) or 1.0
        e = ax[1, col]
        for integ, (r, _) in runs.items():
            d = np.abs(getattr(r, attr) - getattr(ref, attr)) / rng
            e.semilogy(t_ms, np.maximum(d, 1e-16), lw=0.9, label=f"{integ}")
        e.set_ylabel(f"|error| / range ({attr})")
        e.set_xlabel("time (ms)")
        e.grid(alpha=0.3, which="both")
    ax[0, 0].legend(fontsize=8)
    ax[1, 0].legend(fontsize=8)
    fig.suptitle(f"hard case {TITLES.get(name, name)}")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _write_csv(path, ref, runs):
    cols = {"time_s": ref.time_s, "dte_ref_m": ref.dte, "mesh_force_ref_N": ref.mesh_force}
    for integ, (r, _) in runs.items():
        cols[f"dte_{integ}_m"] = r.dte
        cols[f"mesh_force_{integ}_N"] = r.mesh_force
    np.savetxt(path, np.column_stack(list(cols.values())), delimiter=",", header=",".join(cols), comments="",
               fmt="%.17g")


def _case8(out: Path, summary: dict) -> None:
    """FMU (defaults: the default integrator) with long communication steps against native."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from gearfmu.bench import hard_case
    from gearfmu.fmu.compare import output_names, run_fmu
    from gearfmu.fmu.pythonfmu_build import build_fmu
    from gearfmu.dynamics.native import simulate
    from gearfmu.dynamics.reference import simulate_reference

    tables, kw = hard_case("single_sided_impacts")
    Tm = 4 * kw["comm_step_s"]
    hmax = Tm / 256
    kw = dict(kw, pinion_angle_start_rad=0.0, stop_time_s=20 * Tm)
    ref = simulate_reference(tables, **kw)
    rows = []
    fig, ax = plt.subplots(figsize=(10, 4.5))
    ax.plot(ref.time_s * 1e3, ref.dte * 1e6, "k-", lw=2.5, alpha=0.3, label="reference")
    with tempfile.TemporaryDirectory() as tmp:
        fmu = build_fmu(tables, Path(tmp) / "hc8.fmu", model_name="hc8", damping_ratio=kw["damping_ratio"],
                        pinion_speed_start_rad_s=kw["pinion_speed_start_rad_s"],
                        pinion_torque_start_Nm=kw["pinion_torque_Nm"], max_step_s=hmax,
                        stop_time_s=kw["stop_time_s"], output_interval_s=Tm)
        for m in (0.25, 1, 5, 10):
            H = m * Tm
            _log(f"case 8: FMU with communication step {m} mesh periods")
            run = run_fmu(fmu, stop_time_s=kw["stop_time_s"], comm_step_s=H, names=output_names(tables.slots))
            nat = simulate(tables, **dict(kw, comm_step_s=H, max_step_s=hmax))
            stride = int(round(H / kw["comm_step_s"]))
            rng = float(np.ptp(ref.dte))
            rows.append({"comm_step_mesh_periods": m,
                         "fmu_vs_native_rel_max": float(np.max(np.abs(run.columns["dte"] - nat.dte)) / rng),
                         "fmu_vs_reference_rel_max": float(np.max(np.abs(run.columns["dte"] - ref.dte[::stride])) / rng),
                         "fmu_wall_s": run.wall_s})
            ax.plot(run.time_s * 1e3, run.columns["dte"] * 1e6, "o-", ms=3, lw=0.8,
                    label=f"FMU ({DEFAULT_INTEGRATOR}), H = {m} Tm")
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("DTE (um)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("hard case 8: FMU with long communication steps (h = Tm/256) vs reference")
    fig.tight_layout()
    fig.savefig(out / "hard_case_8_fmu.png", dpi=110)
    plt.close(fig)
    summary["fmu_long_steps"] = rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=str(HERE / "output" / "hard_cases"))
    ap.add_argument("--substeps", type=int, default=16, help="internal steps per communication step")
    ap.add_argument("--json", action="store_true", help="print the summary JSON on stdout")
    ap.add_argument("--no-fmu", action="store_true", help="skip case 8 (FMU build and fmpy runs)")
    a = ap.parse_args(argv)
    if a.substeps < 1:
        ap.error("--substeps: must be >= 1")
    from gearfmu.bench import HARD_CASES, hard_case, rel_errors
    from gearfmu.dynamics.native import simulate
    from gearfmu.dynamics.reference import simulate_reference

    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    summary = {"substeps_per_comm_step": a.substeps, "comm_step": "mesh period/4", "cases": {}}
    for i, name in enumerate(HARD_CASES):
        _log(f"{i + 1}/{len(HARD_CASES)} {name}: reference ...")
        tables, kw = hard_case(name)
        t0 = time.perf_counter()
        ref = simulate_reference(tables, **kw)
        ref_wall = time.perf_counter() - t0
        runs = {}
        for integ in ("rk4_node", "rk4_kink", "rk4"):  # wall_s excludes JIT (native.simulate warms up itself)
            r = simulate(tables, max_step_s=kw["comm_step_s"] / a.substeps, integrator=integ, **kw)
            runs[integ] = (r, rel_errors(r, ref))
        summary["cases"][name] = {
            "title": TITLES.get(name, name), "reference_wall_s": ref_wall,
            **{integ: dict(err, wall_s=r.wall_s, events=int(r.info.get("events", 0)),
                           finite=bool(np.all(np.isfinite(r.dte)) and np.all(np.isfinite(r.mesh_force))))
               for integ, (r, err) in runs.items()}}
        _plot_case(out / f"hard_case_{name}.png", name, ref, runs, a.substeps)
        _write_csv(out / f"hard_case_{name}.csv", ref, runs)
        _log("   dte err " + ", ".join(f"{ig} {e['dte_rel_max_err']:.2e}" for ig, (_, e) in runs.items()))
    if not a.no_fmu:
        _case8(out, summary)
    (out / "hard_cases.json").write_text(json.dumps(summary, indent=1))
    _log(f"wrote {out}")
    if a.json:
        print(json.dumps(summary, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
