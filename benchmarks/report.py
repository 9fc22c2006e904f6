#!/usr/bin/env python3
"""Write the validation report docs/validation.md (and its plots) from benchmark JSON.

    python benchmarks/report.py                 # run every source (quick settings), then write
    python benchmarks/report.py --from DIR      # write from JSON saved by an earlier run
    python benchmarks/report.py --only NAME ... # run only these sources (others from --save-dir)
    python benchmarks/report.py --all           # also the slow sources (seed 000 trends, minutes)

Each *source* is one existing benchmark or example script that prints (or writes) JSON: the
report runs it with its quick settings in a fresh interpreter, saves the JSON as
``DIR/<name>.json`` (default DIR: ``benchmarks/output/report``, kept out of git) and records
the command and its wall time in ``DIR/runs.json``.  The page is rendered only from those
files, so every number in docs/validation.md (and the README's speed table, written between
its ``report:speed`` marker comments) comes from a benchmark's JSON, never from a copied log.
A source whose JSON is missing is listed as "not run" rather than stopping the report.

Options: ``--out`` (page, default docs/validation.md), ``--img-dir`` (plots, default
docs/img), ``--readme`` (README to update, ``none`` to leave it), ``--save-dir`` (where a run
saves the JSON), ``--timeout`` (seconds per source).
"""
from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_DIR = ROOT / "benchmarks" / "output" / "report"
PY = sys.executable
CLI = [PY, "-c", "import sys; from gearfmu.cli import main; sys.exit(main())"]
SPEED_BEGIN = "<!-- report:speed:begin -->"
SPEED_END = "<!-- report:speed:end -->"

# name -> (command, file the command writes instead of stdout or None, what it is)
SOURCES = {
    "seed004": ([PY, "examples/seed004_temperature.py", "--json"], None,
                "examples/seed004_temperature.py --json"),
    "helical_iso": ([PY, "examples/helical_tvms.py", "--tvms"], "build/helical/iso.json",
                    "examples/helical_tvms.py --tvms"),
    "ehl": ([PY, "benchmarks/bench_ehl.py", "--sizes", "256", "512", "1024", "--repeats", "1", "--no-fmg"],
            None, "benchmarks/bench_ehl.py --sizes 256 512 1024 --repeats 1 --no-fmg"),
    "accuracy": (CLI + ["bench", "accuracy", "--json"], None, "gearfmu bench accuracy --json"),
    "hard_cases": ([PY, "examples/hard_cases.py", "--json", "--no-fmu", "--out", "{tmp}"], None,
                   "examples/hard_cases.py --json --no-fmu"),
    "arms": ([PY, "examples/seed003_arms.py", "--json", "--quick", "--out", "{tmp}"], None,
             "examples/seed003_arms.py --json --quick"),
    "fmu_speed": ([PY, "benchmarks/bench_fmu.py", "--sim-time", "0.1", "--repeat", "3"], None,
                  "benchmarks/bench_fmu.py --sim-time 0.1 --repeat 3"),
    "kernels": ([PY, "benchmarks/bench_kernels.py", "--sim-time", "0.05", "--repeat", "3"], None,
                "benchmarks/bench_kernels.py --sim-time 0.05 --repeat 3"),
    "trends": ([PY, "examples/seed000_trends.py", "--json", "--out", "{tmp}"], None,
               "examples/seed000_trends.py --json"),
}
# sources that take several minutes: run only when named (--only) or with --all
SLOW = {"trends"}


# ------------------------------------------------------------------------------- running

def run_source(name: str, save_dir: Path, timeout_s: float) -> dict:
    """Run one source, save its JSON as save_dir/name.json; returns its run record."""
    cmd, written, label = SOURCES[name]
    with tempfile.TemporaryDirectory() as tmp:
        argv = [a.replace("{tmp}", tmp) for a in cmd]
        env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
        print(f"report: running {label}", file=sys.stderr, flush=True)
        t0 = time.perf_counter()
        try:
            proc = subprocess.run(argv, cwd=ROOT, env=env, capture_output=True, text=True, timeout=timeout_s)
        except subprocess.TimeoutExpired:
            return {"command": label, "ok": False, "reason": f"timed out after {timeout_s:g} s"}
        wall = time.perf_counter() - t0
        if proc.returncode != 0:
            tail = (proc.stderr.strip().splitlines() or ["(no message)"])[-1]
            return {"command": label, "ok": False, "wall_s": wall,
                    "reason": f"exit status {proc.returncode}: {tail[:200]}"}
        text = (ROOT / written).read_text() if written else proc.stdout
        try:
            data = json.loads(text[text.index("{") if text.lstrip()[:1] != "[" else text.index("["):])
        except (ValueError, json.JSONDecodeError) as exc:
            return {"command": label, "ok": False, "wall_s": wall, "reason": f"no JSON in the output: {exc}"}
    (save_dir / f"{name}.json").write_text(json.dumps(data, indent=1))
    return {"command": label, "ok": True, "wall_s": wall}


# ------------------------------------------------------------------------------- formatting

def pct(x, digits=1) -> str:
    return "n/a" if x is None or not math.isfinite(x) else f"{100 * x:+.{digits}f} %"


def sci(x, digits=2) -> str:
    return "n/a" if x is None or not math.isfinite(float(x)) else f"{float(x):.{digits}e}"


def num(x, digits=3) -> str:
    return "n/a" if x is None or not math.isfinite(float(x)) else f"{float(x):.{digits}g}"


def table(header, rows) -> str:
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


class Page:
    """Markdown being written plus the plots it references."""

    def __init__(self, data: dict, runs: dict, img_dir: Path, out: Path):
        self.data, self.runs, self.img_dir, self.out = data, runs, img_dir, out
        self.parts: list[str] = []
        self.summary: list[list[str]] = []

    def cost(self, name) -> str:
        r = self.runs.get(name, {})
        return f"{r['wall_s']:.0f} s" if isinstance(r.get("wall_s"), (int, float)) else "n/a"

    def missing(self, name, title) -> bool:
        if name in self.data:
            return False
        reason = self.runs.get(name, {}).get("reason", "no saved JSON")
        self.parts.append(f"## {title}\n\nNot run ({reason}). Produce it with "
                          f"`python benchmarks/report.py --only {name}`.\n")
        return True

    def plot(self, filename: str, draw) -> str:
        """Draw with ``draw(plt)`` into img_dir/filename; returns the Markdown image link."""
        import matplotlib  # matplotlib: only for the report's plots

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt  # matplotlib: only for the report's plots

        self.img_dir.mkdir(parents=True, exist_ok=True)
        fig = draw(plt)
        fig.tight_layout()
        fig.savefig(self.img_dir / filename, dpi=80)
        plt.close(fig)
        rel = os.path.relpath(self.img_dir / filename, self.out.parent)
        return f"![{filename}]({Path(rel).as_posix()})"


# ------------------------------------------------------------------------------- sections

def sec_stiffness(pg: Page):
    if pg.missing("seed004", "Geometry and mesh stiffness: seed 004 Tables 2-3"):
        return
    rows = [r for r in pg.data["seed004"] if r["state"] == "standard"]
    body, worst_mesh = [], {}
    for r in rows:
        d = r["ours"] / r["seed"] - 1.0
        if r["quantity"] == "mesh":
            worst_mesh[r["pair"]] = max(worst_mesh.get(r["pair"], 0.0), abs(d))
        body.append([r["pair"], r["quantity"], r["point"], num(r["seed"] / 1e8, 5), num(r["ours"] / 1e8, 5), pct(d)])
    pg.parts.append(
        "## Geometry and mesh stiffness\n\n"
        "### Tooth and pair stiffness against seed 004 Tables 2-3\n\n"
        "Reference: He & Yang (seed 004) Tables 2-3, single-tooth and pair stiffness of gear pairs I "
        "and II at meshing-in, the pitch point and meshing-out, standard state (30 °C).  Ours: the "
        "potential-energy tooth stiffness with Sainsot's fillet foundation and the Hertz contact "
        "(docs/physics_stiffness.md), E = 206 GPa, ν = 0.3 (the paper does not list them).  The "
        "seed's own standard-stiffness method is only cited, not given, so the difference is a "
        "modelling difference, not round-off.  Units 1e8 N/m.\n\n"
        + table(["pair", "stiffness", "point", "seed 004", "ours", "difference"], body)
        + f"\n\nSource: `{SOURCES['seed004'][2]}` ({pg.cost('seed004')} for both pairs and all states).\n")
    pg.summary.append(["pair stiffness at meshing-in, pitch, meshing-out", "seed 004 Tables 2-3",
                       ", ".join(f"pair {p}: ≤ {100 * w:.0f} %" for p, w in sorted(worst_mesh.items())),
                       pg.cost("seed004")])

    if pg.missing("helical_iso", "Mesh stiffness against ISO 6336-1"):
        return
    iso = pg.data["helical_iso"]
    rows = iso.get("iso_6336_sweep", [])
    body = [[num(r["beta_deg"], 3), f"{r['eps_alpha']:.3f}", f"{r['eps_beta']:.3f}", f"{r['k_mean_N_per_mm_um']:.2f}",
             f"{r['iso_c_gamma_alpha']:.2f}", pct(r["rel_diff"]), f"{r['ptp_over_mean']:.3f}"] for r in rows]
    worst = max((abs(r.get("rel_diff", 0.0)) for r in rows), default=math.nan)
    pg.parts.append(
        "### Mean mesh stiffness against ISO 6336-1 method B\n\n"
        "Reference: ISO 6336-1:2019 clause 9 (method B), c_γα = c′(0.75 ε_α + 0.25) in N/(mm·µm), an "
        "empirical band (±25 %) rather than an exact value.  Ours: mean total mesh stiffness over a "
        "mesh period per face width of the seed 001 Table 1 pair with the helix angle β varied "
        "(docs/helical.md).\n\n"
        + table(["β (deg)", "ε_α", "ε_β", "ours k̄/b", "ISO c_γα", "difference", "TVMS ptp/mean"], body)
        + f"\n\nSource: `{SOURCES['helical_iso'][2]}` ({pg.cost('helical_iso')}).\n")
    pg.summary.append(["mean mesh stiffness over β", "ISO 6336-1 method B", f"≤ {100 * worst:.0f} % (band ±25 %)",
                       pg.cost("helical_iso")])


def sec_thermal(pg: Page):
    if pg.missing("seed004", "Thermal stiffness: seed 004 temperature states"):
        return
    by = {(r["pair"], r["quantity"], r["point"], r["state"]): r for r in pg.data["seed004"]}
    body, worst = [], {}
    order = {"pinion": 0, "gear": 1, "mesh": 2, "meshing-in": 0, "pitch": 1, "meshing-out": 2}
    for (pair, q, point, state), r in sorted(by.items(), key=lambda kv: (kv[0][0], order.get(kv[0][1], 9),
                                                                         order.get(kv[0][2], 9), kv[0][3])):
        if state == "standard":
            continue
        std = by.get((pair, q, point, "standard"))
        if std is None:
            continue
        f_seed, f_ours = r["seed"] / std["seed"], r["ours"] / std["ours"]
        if q == "mesh":
            worst[pair] = max(worst.get(pair, 0.0), abs(f_ours - f_seed))
        body.append([pair, q, point, state, f"{f_seed:.4f}", f"{f_ours:.4f}", f"{f_ours - f_seed:+.4f}"])
    pg.parts.append(
        "## Thermal state\n\n"
        "Reference: seed 004 Tables 2-3, stiffness in the expansion (70 °C) and shrinkage (10 °C) "
        "states.  Compared here is the temperature factor k(state)/k(standard) of each stiffness, "
        "which isolates the temperature model (docs/thermal.md) from the standard stiffness compared "
        "above.\n\n"
        + table(["pair", "stiffness", "point", "state", "seed 004 factor", "ours factor", "difference"], body)
        + f"\n\nSource: `{SOURCES['seed004'][2]}`.\n")
    pg.summary.append(["temperature factor k(T)/k(30 °C) of the pair stiffness", "seed 004 Tables 2-3",
                       ", ".join(f"pair {p}: within {w:.3f}" for p, w in sorted(worst.items())),
                       pg.cost("seed004")])


def sec_ehl(pg: Page):
    if pg.missing("ehl", "EHL line-contact film"):
        return
    d = pg.data["ehl"]
    body, finest = [], {}
    cases = [c for c in d.get("cases", []) if not c.get("options", {}).get("fmg_cycles")]
    for c in cases:
        o = c.get("options", {})
        law = f"{o.get('viscosity', '?')}, {'compressible' if o.get('compressible') else 'incompressible'}"
        for r in c["rows"]:
            dev = r.get("rel_dev_from_moes")
            if o.get("viscosity") == "barus" and dev is not None:
                finest[(c["M"], c["L"])] = (r["n_intervals"], dev)
            body.append([num(c["M"], 4), num(c["L"], 3), law, r["n_intervals"], num(r["H_central_moes"], 4),
                         pct(dev), sci(r.get("discretisation_error_estimate")),
                         r["cycles"], num(r["cpu_time_ms"], 3)])

    def draw(plt):
        fig, ax = plt.subplots(figsize=(6, 3.6))
        for c in cases:
            o = c.get("options", {})
            ns = [r["n_intervals"] for r in c["rows"]]
            ax.loglog(ns, [r["cpu_time_ms"] for r in c["rows"]], "o-",
                      label=f"M={c['M']:g}, L={c['L']:g}, {o.get('viscosity')}")
        ax.set_xlabel("grid intervals")
        ax.set_ylabel("CPU ms per solve")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        return fig

    img = pg.plot("validation_ehl_cost.png", draw) if cases else ""
    pg.parts.append(
        "## EHL film\n\n"
        "Reference: Moes' (1992) fit of the central film thickness of the smooth isothermal line "
        "contact, in Moes' dimensionless groups (M, L).  The fit describes the Barus, incompressible "
        "cases; with Roelands viscosity and Dowson-Higginson density the film lies below the fit by "
        "physics (docs/ehl.md).  The discretisation error is the Richardson estimate from the "
        "next coarser grid.  Cost: CPU time per solve.\n\n"
        + table(["M", "L", "laws", "intervals", "H_c (Moes scaling)", "vs Moes' fit", "discretisation err.",
                 "cycles", "CPU ms"], body)
        + f"\n\n{img}\n\nSource: `{SOURCES['ehl'][2]}` ({pg.cost('ehl')}).\n")
    pg.summary.append(["smooth EHL central film (Barus, finest grid)", "Moes (1992) fit",
                       ", ".join(f"M={m:g}, L={l:g}: {pct(d)} ({n} intervals)" for (m, l), (n, d) in finest.items()),
                       pg.cost("ehl")])


def sec_trends(pg: Page):
    if pg.missing("trends", "Contact models in the mesh: seed 000 section 5 trends"):
        return
    d = pg.data["trends"]
    tv = d["mean_tvms_N_per_m"]
    torques = [str(int(t)) if float(t).is_integer() else str(t) for t in d["torques_Nm"]]
    smooth = tv.get("smooth", {})
    body = []
    for model, row in tv.items():
        cells = [f"{row[t] / 1e9:.5f}" + ("" if model == "smooth" or t not in smooth else
                                           f" ({pct(row[t] / smooth[t] - 1.0, 3)})") for t in torques]
        body.append([model.replace("_", " "), *cells])
    checks = []
    hertz = tv.get("hertz", {})
    if hertz and smooth:
        checks.append(["Fig. 12: lubricated TVMS above Hertz", "smooth > Hertz at every torque",
                       "yes" if all(smooth[t] > hertz[t] for t in torques) else "no"])
        checks.append(["Fig. 15: TVMS rises with torque", "smooth film",
                       "yes" if all(smooth[a] < smooth[b] for a, b in zip(torques, torques[1:])) else "no"])
    sp = d.get("speed_rpm", {}).get("smooth", {})
    if sp:
        keys = sorted(sp, key=float)
        checks.append(["Fig. 14: TVMS falls as speed rises", f"smooth film, {', '.join(keys)} rpm",
                       "yes" if all(sp[a] > sp[b] for a, b in zip(keys, keys[1:])) else "no"])
    for lv in (1, 2, 3, 4):
        row = tv.get(f"rough_level_{lv}")
        if row and smooth:
            below = [t for t in torques if row[t] < smooth[t]]
            checks.append([f"Fig. 13: rough level {lv} below smooth", "tables, every torque",
                           f"{len(below)} of {len(torques)} torques"])
    notes = "".join(f"\n* {k.replace('_', ' ')}: {v}" for k, v in d.get("notes", {}).items())
    pg.parts.append(
        "## Contact models in the mesh\n\n"
        "Reference: the trends seed 000 (Zhao et al. 2022) section 5 reports for its Table 1 pair "
        "(Figs. 12-15): the lubricated TVMS lies above the Hertz one, rises with torque, falls as speed "
        "rises and falls as the roughness level rises.  Ours: mean TVMS of the tables "
        f"({d.get('points_per_mesh')} points per mesh period, {d.get('slices')} slices) with each contact "
        "model (docs/ehl_mesh.md); in 1e9 N/m, in brackets against the smooth film.  Where the film "
        "parameter is below 3 the scene's film-failure policy applies (notes below), which is "
        "outside seed 000's full-film assumption.\n\n"
        + table(["model", *[f"{t} N·m" for t in torques]], body) + "\n\n"
        + table(["seed 000 statement", "compared on", "reproduced"], checks)
        + (f"\n\nNotes of the run:{notes}" if notes else "")
        + f"\n\nSource: `{SOURCES['trends'][2]}` ({pg.cost('trends')}; not in the quick regeneration: "
        "`python benchmarks/report.py --only trends`).\n")
    ok = sum(1 for c in checks if c[2] == "yes")
    pg.summary.append(["TVMS trends with contact model, torque, speed", "seed 000 Figs. 12-15 (statements)",
                       f"{ok} of {sum(1 for c in checks if c[2] in ('yes', 'no'))} directions reproduced; "
                       "roughness levels: see the section", pg.cost("trends")])


def sec_dynamics(pg: Page):
    if not pg.missing("accuracy", "Dynamics and integrators: speed against error"):
        d = pg.data["accuracy"]
        ref = d.get("reference", {})
        body = [[r["method"], r["setting"], num(r["wall_s"], 3), sci(r.get("dte_rel_rms_err")),
                 sci(r.get("dte_rel_max_err")), sci(r.get("force_rel_rms_err"))] for r in d["rows"]]

        def draw(plt):
            fig, ax = plt.subplots(figsize=(6.5, 4.2))
            methods = list(dict.fromkeys(r["method"] for r in d["rows"]))
            for m in methods:
                rs = [r for r in d["rows"] if r["method"] == m and r.get("dte_rel_rms_err", 0) > 0]
                if rs:
                    ax.loglog([r["dte_rel_rms_err"] for r in rs], [r["wall_s"] for r in rs], "o-", label=m)
            ax.set_xlabel("DTE RMS error / DTE range")
            ax.set_ylabel("wall time (s)")
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=7)
            return fig

        img = pg.plot("validation_integrators.png", draw)
        kink = [r for r in d["rows"] if r["method"].endswith("rk4_kink") and r["method"].startswith("native")]
        best = next((r for r in kink if r["setting"] == "h=H/64"), None) or (
            min(kink, key=lambda r: r.get("dte_rel_rms_err", math.inf)) if kink else None)
        rk4 = next((r for r in d["rows"] if r["method"] == "native-rk4" and best
                    and r["setting"] == best["setting"]), None)
        pg.parts.append(
            "## Dynamics and integrators\n\n"
            f"### Speed against error on the hard case `{d['case']}`\n\n"
            "Reference: an independent solver, scipy's DOP853 restarted at every table kink and contact "
            f"change (event location, `gearfmu/dynamics/reference.py`), rtol {ref.get('rtol', 'n/a')}.  "
            "Compared: the native solver's integrators at internal steps h = H/n (H the communication "
            "step), the FMU at communication steps of several mesh periods, and scipy's DOP853 and "
            "Radau at looser tolerances.  Errors are RMS and maximum over the communication instants, "
            "relative to the reference's range (docs/dynamics_validation.md).\n\n"
            + table(["method", "setting", "wall s", "DTE rel. RMS", "DTE rel. max", "force rel. RMS"], body)
            + f"\n\n{img}\n\nSource: `{SOURCES['accuracy'][2]}` ({pg.cost('accuracy')}).\n")
        if best:
            diff = f"DTE RMS error at {best['setting']}: rk4_kink {sci(best['dte_rel_rms_err'])}"
            if rk4:
                diff += f", rk4 {sci(rk4['dte_rel_rms_err'])} of the range"
            pg.summary.append(["dynamic response (DTE, mesh force)", "event-located DOP853 (scipy)", diff,
                               f"{num(best['wall_s'], 2)} s per run (rk4_kink)"])

    if not pg.missing("hard_cases", "Hard cases against the reference"):
        d = pg.data["hard_cases"]
        cases = d.get("cases", d)
        body = []
        for name, c in (cases.items() if isinstance(cases, dict) else []):
            if not isinstance(c, dict):
                continue
            for integ in ("rk4_kink", "rk4"):
                e = c.get(integ)
                if isinstance(e, dict):
                    body.append([c.get("title", name), integ, sci(e.get("dte_rel_rms_err", e.get("dte_rel_rms"))),
                                 sci(e.get("dte_rel_max_err", e.get("dte_rel_max"))),
                                 sci(e.get("force_rel_rms_err", e.get("force_rel_rms"))),
                                 num(e.get("wall_s"), 3)])
        pg.parts.append(
            "### Every hard case\n\n"
            f"Same reference; the native solver with both integrators at the same internal step "
            f"h = H/{d.get('substeps_per_comm_step', '?')}, H = {d.get('comm_step', 'the communication step')} (heavy load, impacts on one and both flanks, low damping near resonance, high contact "
            "ratio, Ω_h = 2, torque steps, the default scene's computed tables).\n\n"
            + (table(["case", "integrator", "DTE rel. RMS", "DTE rel. max", "force rel. RMS", "wall s"], body)
               if body else "(no per-case rows in the JSON)")
            + f"\n\nSource: `{SOURCES['hard_cases'][2]}` ({pg.cost('hard_cases')}).\n")


def sec_arms(pg: Page):
    if pg.missing("arms", "Dynamic response against experiment: seed 003 Fig. 3"):
        return
    d = pg.data["arms"]
    body = [[num(c["seed"], 3), num(c["ours"], 3) if c.get("ours") is not None else "not found",
             c.get("kind") or "", num(c["difference"], 2) if c.get("difference") is not None else ""]
            for c in d.get("comparison", [])]
    found = [c for c in d.get("comparison", []) if c.get("ours") is not None]

    def draw(plt):
        fig, ax = plt.subplots(figsize=(6.5, 3.8))
        ax.plot(d["omega"], d["arms_up"], "-", label="up-sweep")
        ax.plot(d["omega"], d["arms_down"], "--", label="down-sweep")
        for s in d.get("seed_jumps", []):
            ax.axvline(s, color="0.6", ls=":", lw=0.8)
        ax.plot([], [], color="0.6", ls=":", lw=0.8, label="seed 003 jumps")
        ax.set_xlabel("Ω_h (mesh frequency / natural frequency)")
        ax.set_ylabel("A_rms")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        return fig

    img = pg.plot("validation_seed003_arms.png", draw) if d.get("omega") else ""
    pg.parts.append(
        "## Dynamic response against experiment\n\n"
        "Reference: seed 003 Fig. 3, the RMS of the first three mesh harmonics of the DTE against "
        "Ω_h for the Kahraman & Blankenship (1997) test gears (ζ = 0.02, 340 N·m), whose jumps the "
        "paper compares with the measured response.  Ours: up- and down-sweeps of the time-indexed "
        "model on the seed 003 Table 1 tables (docs/seed003.md), quick sweep; the table gives, for "
        "each Ω_h where seed 003 shows a jump, the nearest feature (jump, inflection, shoulder) of "
        "ours within 0.06.\n\n"
        + table(["seed 003 Ω_h", "ours Ω_h", "kind", "difference"], body)
        + f"\n\n{img}\n\nSource: `{SOURCES['arms'][2]}` ({pg.cost('arms')}).\n")
    pg.summary.append(["A_rms jumps against Ω_h", "seed 003 Fig. 3 (Kahraman & Blankenship rig)",
                       f"{len(found)} of {len(body)} seed features matched within 0.06", pg.cost("arms")])


def sec_fmu(pg: Page):
    if not pg.missing("kernels", "FMU runtime: C kernel against the native solver"):
        d = pg.data["kernels"]
        rows = list(d.get("cases", {}).values())
        body = [[r["case"], r["integrator"], r["slots"], r["internal_steps"], r["events"],
                 num(r["c_ns_per_step"], 3), num(r["numba_ns_per_step"], 3), num(r["numba_over_c"], 3),
                 sci(r["final_dte_rel_diff"])] for r in rows]
        worst = max((r["final_dte_rel_diff"] for r in rows), default=math.nan)
        pg.parts.append(
            "## FMU runtime\n\n"
            "### C kernel against the native solver\n\n"
            "Reference: the two independent implementations of docs/model.md (the FMU's C kernel and "
            "the numba native solver) on the same tables and steps; they are specified to agree to "
            "round-off.  Cost: CPU ns per internal step (best of the repeats).\n\n"
            + table(["case", "integrator", "slots", "steps", "events", "C ns/step", "numba ns/step",
                     "numba/C", "final DTE difference / range"], body)
            + f"\n\nSource: `{SOURCES['kernels'][2]}` ({pg.cost('kernels')}).\n")
        pg.summary.append(["FMU kernel against native solver", "second implementation (numba)",
                           "final DTE identical (bit for bit)" if worst == 0 else
                           f"final DTE ≤ {sci(worst)} of the range", pg.cost("kernels")])

    if not pg.missing("fmu_speed", "FMU runtime: cost per simulated second"):
        pg.parts.append("### Cost of the FMU against the native solver\n\n" + speed_table(pg.data["fmu_speed"])
                        + f"\n\nSource: `{SOURCES['fmu_speed'][2]}` ({pg.cost('fmu_speed')}).\n")


def speed_table(d: dict) -> str:
    """The speed table (also written into README.md) from bench_fmu's JSON."""
    comm_us = 1e6 * d["comm_step_scene_s"]
    rows = [
        ["internal step, native (numba)", f"{d['native_ns_per_step']:.0f} ns"],
        ["internal step, FMU (C kernel, long communication steps)",
         f"{d['fmu_ns_per_step']:.0f} ns ({d['fmu_over_native_per_step']:.2f} × native)"],
        [f"wall per simulated second at a {comm_us:.3g} µs communication step: native / FMU low-level "
         "loop / `fmpy.simulate_fmu`",
         f"{d['native_wall_per_sim_s']:.3g} s / {d['fmu_lowlevel_wall_per_sim_s']:.3g} s / "
         f"{d['fmu_simulate_fmu_wall_per_sim_s']:.3g} s"],
        ["FMU instantiation", f"{1e3 * d['fmu_instantiate_s']:.3g} ms"],
    ]
    return (f"Scene `{d['scene']}`, {d['slots']} pair slots.\n\n" + table(["quantity", "value"], rows))


COVERED_BY_TESTS = [
    ("meshing errors and the loaded static mesh", "hand values of seed 003 eq 15 and of the pitch "
     "closure, seed 000 eq 16, scipy's brentq on the load balance", "tests/test_meshing_errors.py, "
     "tests/test_loaded_mesh.py"),
    ("contact models and roughness (fractal, load sharing, W-M)", "seed 001 Figs. 7-12 statements, "
     "quadrature of the asperity integrals, seed 000 Table 2 Ra, the W-M closed-form RMS",
     "tests/test_fractal_contact.py, tests/test_load_sharing.py, tests/test_roughness.py"),
    ("rough EHL in the mesh, transient films", "seed 000 Figs. 12-15 trends, Venner et al. waviness "
     "reduction", "tests/test_ehl_mesh.py, tests/test_ehl_transient.py"),
    ("helical geometry and slicing", "hand formulas for ε_α, ε_β and the centre distance; the "
     "continuous face-width limit", "tests/test_helical.py, tests/test_helical_sawtooth.py"),
]


def render(data: dict, runs: dict, out: Path, img_dir: Path) -> str:
    pg = Page(data, runs, img_dir, out)
    for sec in (sec_stiffness, sec_thermal, sec_ehl, sec_trends, sec_dynamics, sec_arms, sec_fmu):
        sec(pg)
    head = (
        "# Validation report\n\n"
        "<!-- Generated by benchmarks/report.py from benchmark JSON; do not edit by hand. -->\n\n"
        "What each physics area of gearfmu is compared against, outside gearfmu (closed forms, "
        "published tables, a standard, an independent solver), how large the difference is and "
        "what it costs.  Every number on this page comes from the JSON of the benchmark or example "
        "named under its table; regenerate the page (and the plots in `docs/img/`) with\n\n"
        "```bash\npython benchmarks/report.py              # runs the sources with quick settings, a few minutes\n"
        "python benchmarks/report.py --all        # also the slow sources (seed 000 trends)\n"
        "python benchmarks/report.py --from DIR   # from JSON saved earlier (DIR/<source>.json)\n```\n\n"
        "Costs are wall times of one run on the machine that generated the page: compare them with "
        "each other, not with another machine.  The equations and choices behind each area are in "
        "the model reference ([index](index.md)).\n\n"
        "## Summary\n\n"
        + table(["quantity", "reference", "difference", "cost"], pg.summary)
        + "\n\nChecked by the test suite against references, not re-run here:\n\n"
        + table(["area", "reference", "tests"], COVERED_BY_TESTS) + "\n")
    return head + "\n" + "\n".join(pg.parts)


def write_readme_speed(readme: Path, data: dict) -> bool:
    """Replace the block between the speed markers of README.md; False if markers are absent."""
    text = readme.read_text()
    if SPEED_BEGIN not in text or SPEED_END not in text or "fmu_speed" not in data:
        return False
    a, rest = text.split(SPEED_BEGIN, 1)
    _, b = rest.split(SPEED_END, 1)
    block = (f"{SPEED_BEGIN}\n<!-- written by benchmarks/report.py from `{SOURCES['fmu_speed'][2]}` -->\n"
             + speed_table(data["fmu_speed"]) + f"\n{SPEED_END}")
    readme.write_text(a + block + b)
    return True


def load_dir(d: Path):
    data = {}
    for name in SOURCES:
        p = d / f"{name}.json"
        if p.is_file():
            data[name] = json.loads(p.read_text())
    runs_p = d / "runs.json"
    runs = json.loads(runs_p.read_text()) if runs_p.is_file() else {}
    return data, runs


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--from", dest="from_dir", type=Path, help="read saved JSON from this directory, run nothing")
    ap.add_argument("--only", nargs="+", choices=sorted(SOURCES), help="run only these sources")
    ap.add_argument("--all", action="store_true", help=f"also run the slow sources ({', '.join(sorted(SLOW))})")
    ap.add_argument("--save-dir", type=Path, default=DEFAULT_DIR)
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "validation.md")
    ap.add_argument("--img-dir", type=Path, default=ROOT / "docs" / "img")
    ap.add_argument("--readme", default=str(ROOT / "README.md"), help="README to update ('none': leave it)")
    ap.add_argument("--timeout", type=float, default=900.0, help="seconds per source")
    a = ap.parse_args(argv)
    if a.from_dir is not None:
        if not a.from_dir.is_dir():
            print(f"report: --from {a.from_dir}: not a directory", file=sys.stderr)
            return 2
        src = a.from_dir
    else:
        a.save_dir.mkdir(parents=True, exist_ok=True)
        runs_p = a.save_dir / "runs.json"
        runs = json.loads(runs_p.read_text()) if runs_p.is_file() else {}
        for name in a.only or [n for n in SOURCES if a.all or n not in SLOW]:
            runs[name] = run_source(name, a.save_dir, a.timeout)
            if not runs[name]["ok"]:
                print(f"report: {name}: {runs[name]['reason']}", file=sys.stderr)
                (a.save_dir / f"{name}.json").unlink(missing_ok=True)
            runs_p.write_text(json.dumps(runs, indent=1))
        src = a.save_dir
    data, runs = load_dir(src)
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(render(data, runs, a.out, a.img_dir))
    print(f"report: wrote {a.out} from {len(data)} of {len(SOURCES)} sources", file=sys.stderr)
    if a.readme != "none" and write_readme_speed(Path(a.readme), data):
        print(f"report: wrote the speed table of {a.readme}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
