"""Fidelity plans of full scenes (docs/plan.md): JSON report and PNG per scene.

For each study scene (shipped scenes with an envelope and a 2 % / 2 % accuracy target added, and
examples/scenes/plan_seed004_warmup.toml, which states its own temperature axis, warm-up range
and duty cycle) run the planner, build the planned and the full-fidelity FMU and drive both
through the verification cases (steady point, run-up over the speed range, warm-up in
temperature, duty-cycle replay, run-down and the envelope search's worst point;
gearfmu.plan.verify_fmus).  Writes
examples/output/plan_study.json (every plan's report with its FMU verification) and
plan_study.png (per scene: error contribution of each choice's chosen level; cost of the
chosen model against the full one; measured planned-vs-full FMU error per case).  ``--out DIR``
writes them (and the FMUs) to DIR instead; ``--json`` also prints the JSON on stdout (the text
reports go to stderr then), the form benchmarks/report.py reads.

    python examples/plan_study.py [--no-fmu] [--only NAME] [--runtime pythonfmu|standalone]
                                  [--json] [--out DIR]
"""
import argparse
import json
import sys
import time
import tomllib
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from gearfmu.plan import format_report, plan_scene  # noqa: E402
from gearfmu.scene.reader import dumps_toml, load_scene  # noqa: E402

HERE = Path(__file__).resolve().parent
OUT = HERE / "output"

#: scene file -> sections added for the study (envelope from the scene's own ranges where it has them)
STUDIES = {
    "seed000_table1.toml": {"envelope": {"torque_range_Nm": [500.0, 2500.0], "speed_range_rpm": [1000.0, 3000.0]},
                            "accuracy": {"dte_rel_error": 0.02, "mesh_force_rel_error": 0.02,
                                         "pin": ["contact_model"]}},
    # the scene's own speed range 500-5000 rpm (its [operating] range) is the envelope
    "seed003_table1.toml": {"accuracy": {"dte_rel_error": 0.02, "mesh_force_rel_error": 0.02}},
    # its own [thermal] axis, [envelope] (warm-up 20 -> 90 degC, duty cycle) and [accuracy]
    "plan_seed004_warmup.toml": {},
}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--no-fmu", action="store_true", help="skip building and driving the FMUs")
    ap.add_argument("--only", action="append", help="run only this study scene (repeatable)")
    ap.add_argument("--runtime", choices=("pythonfmu", "standalone"), help="FMU runtime (default: the scene's)")
    ap.add_argument("--json", action="store_true", help="print the JSON on stdout (text reports to stderr)")
    ap.add_argument("--out", type=Path, default=OUT, help=f"output directory (default {OUT})")
    args = ap.parse_args(argv)
    out_dir = args.out
    out_dir.mkdir(parents=True, exist_ok=True)
    text_out = sys.stderr if args.json else sys.stdout
    reports = {}
    for name, extra in STUDIES.items():
        if args.only and name not in args.only:
            continue
        path = HERE / "scenes" / name
        if extra:
            data = tomllib.loads(path.read_text(encoding="utf-8"))
            data.update(extra)
            scene = load_scene(dumps_toml(data))
        else:  # the scene file as it is (its duty-cycle CSV path is relative to it)
            scene = load_scene(path)
        print(f"== {name}", file=sys.stderr, flush=True)
        t0, c0 = time.perf_counter(), time.process_time()
        plan = plan_scene(scene, progress=True, measure_fmu=not args.no_fmu, fmu_dir=str(out_dir / "plan_fmus"),
                           fmu_runtime=args.runtime)
        print(format_report(plan), file=text_out, flush=True)
        reports[name] = plan.to_dict()
        reports[name]["study_wall_s"] = time.perf_counter() - t0
        reports[name]["study_cpu_s"] = time.process_time() - c0
    text = json.dumps(reports, indent=1)
    (out_dir / "plan_study.json").write_text(text, encoding="utf-8")
    if args.json:
        print(text, flush=True)

    fig, axes = plt.subplots(len(reports), 3, figsize=(18, 4 * len(reports)), squeeze=False)
    for row, (name, rep) in enumerate(reports.items()):
        rows = [r for r in rep["choices"] if r["status"] not in ("fixed", "pinned")]
        labels = [f"{r['choice']}\n{r['full']}→{r['chosen']}" for r in rows]
        ax = axes[row][0]
        x = range(len(rows))
        for j, (key, lab) in enumerate((("tvms_rel", "TVMS"), ("dte_rel", "DTE"), ("mesh_force_rel", "mesh force"))):
            vals = [max(float(r["contribution"][key] or 0.0), 1e-16) for r in rows]
            ax.bar([i + 0.27 * (j - 1) for i in x], vals, width=0.27, label=lab)
        ax.axhline(rep["target"]["dte_rel"], color="k", ls="--", lw=1, label="target")
        ax.set_yscale("log")
        ax.set_xticks(list(x))
        ax.set_xticklabels(labels, fontsize=7)
        ax.set_ylabel("relative RMS error vs full")
        ax.set_title(f"{rep['scene']}: contribution of each chosen level")
        ax.legend(fontsize=7)
        ax = axes[row][1]
        keys = [k for k in ("table_build_s", "table_bytes", "wall_per_sim_s", "fmu_bytes")
                if k in rep["cost"]["full"] and k in rep["cost"]["chosen"]]
        ratio = [rep["cost"]["chosen"][k] / rep["cost"]["full"][k] for k in keys]
        ax.bar(keys, ratio, color="tab:green")
        ax.axhline(1.0, color="k", lw=1)
        ax.set_ylabel("chosen / full")
        v = rep["verification"]
        ax.set_title(f"cost; search worst DTE {v['dte_rel']:.2g}, force {v['mesh_force_rel']:.2g}"
                     f" ({'within' if rep['within_target'] else 'NOT within'} target)")
        ax = axes[row][2]
        cases = (rep.get("fmu_verification") or {}).get("cases") or {}
        if cases:
            names = list(cases)
            xs = range(len(names))
            for j, (key, lab) in enumerate((("dte_rel", "DTE"), ("mesh_force_rel", "mesh force"))):
                ax.bar([i + 0.35 * (j - 0.5) for i in xs], [max(float(cases[n][key]), 1e-16) for n in names],
                       width=0.35, label=lab)
            ax.axhline(rep["target"]["dte_rel"], color="k", ls="--", lw=1, label="target")
            ax.set_yscale("log")
            ax.set_xticks(list(xs))
            ax.set_xticklabels([f"{n}\nCPU gain {cases[n]['cpu_gain_full_over_chosen']:.2g}" for n in names],
                               fontsize=7)
            ax.set_ylabel("planned FMU vs full FMU (relative RMS)")
            ax.legend(fontsize=7)
            ax.set_title("through the FMUs (fmpy)")
        else:
            ax.set_axis_off()
    fig.tight_layout()
    fig.savefig(out_dir / "plan_study.png", dpi=110)
    print(f"wrote {out_dir / 'plan_study.json'} and {out_dir / 'plan_study.png'}", file=text_out)


if __name__ == "__main__":
    main()
