#!/usr/bin/env python3
"""Write the validation report docs/validation.md (and its plots) from benchmark JSON.

    python benchmarks/report.py                 # run every source (quick settings), then write
    python benchmarks/report.py --from DIR      # write from JSON saved by an earlier run
    python benchmarks/report.py --only NAME ... # run only these sources (others from --save-dir)
    python benchmarks/report.py --all           # also the slow sources (seed 000 trends, speed goals)

Each *source* is one existing benchmark or example script that prints (or writes) JSON: the
report runs it with its quick settings in a fresh interpreter, saves the JSON as
``DIR/<name>.json`` (default DIR: ``benchmarks/output/report``, kept out of git) and records
the command and its wall time in ``DIR/runs.json``.  The page is rendered only from those
files, so every number in docs/validation.md (and the README's speed table, written between
its ``report:speed`` marker comments) comes from a benchmark's JSON, never from a copied log.
A source whose JSON is missing is listed as "not run" rather than stopping the report; a
source that fails (non-zero exit, timeout, no JSON) or a section that cannot be rendered from its
JSON is named on stderr, the other sources and sections still run, and the exit status is 1.
The README block also holds the speed goals beside the measured values (``goal_rows``); a goal
whose benchmark JSON is missing reads "not measured".

Options: ``--out`` (page, default docs/validation.md), ``--img-dir`` (plots, default
docs/img), ``--readme`` (README to update, ``none`` to leave it), ``--save-dir`` (where a run
saves the JSON), ``--timeout`` (seconds per source; default 900, 3600 for the slow sources).
"""
from __future__ import annotations

import argparse
import json
import math
import os
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

#: C source of the plain-C speed reference of bench_kernels (--proxy): the file named by the
#: environment variable GEARFMU_RK4_PROXY (a reference kept outside the project), else
#: benchmarks/rk4_proxy.c where the project has one
PROXY = os.environ.get("GEARFMU_RK4_PROXY") or (
    "benchmarks/rk4_proxy.c" if (ROOT / "benchmarks" / "rk4_proxy.c").is_file() else None)
_PROXY_SHOWN = "$GEARFMU_RK4_PROXY" if os.environ.get("GEARFMU_RK4_PROXY") else PROXY
_KERNELS = ["benchmarks/bench_kernels.py", "--sim-time", "0.05", "--repeat", "3",
            "--integrators", "rk4,rk4_kink,rk4_node"]
_KERNELS_SHOWN = " ".join(_KERNELS + (["--proxy", _PROXY_SHOWN] if PROXY else []))
_KERNELS = _KERNELS + (["--proxy", PROXY] if PROXY else [])

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
    "fmu_speed": ([PY, "benchmarks/bench_fmu.py", "--sim-time", "0.1", "--repeat", "5"], None,
                  "benchmarks/bench_fmu.py --sim-time 0.1 --repeat 5"),
    "kernels": ([PY, *_KERNELS], None, _KERNELS_SHOWN),
    "stiffness_iso": ([PY, "benchmarks/bench_stiffness_iso.py"], None, "benchmarks/bench_stiffness_iso.py"),
    "helical_sawtooth": ([PY, "benchmarks/bench_helical_sawtooth.py"], None, "benchmarks/bench_helical_sawtooth.py"),
    "helical_contact": ([PY, "benchmarks/bench_helical_contact.py"], None, "benchmarks/bench_helical_contact.py"),
    "thermal": ([PY, "benchmarks/bench_thermal.py"], None, "benchmarks/bench_thermal.py"),
    "load_sharing": ([PY, "benchmarks/bench_load_sharing.py"], None, "benchmarks/bench_load_sharing.py"),
    "fractal": ([PY, "benchmarks/bench_fractal.py"], None, "benchmarks/bench_fractal.py"),
    "ehl_corners": ([PY, "benchmarks/bench_ehl_corners.py", "--repeats", "10"], None,
                    "benchmarks/bench_ehl_corners.py --repeats 10"),
    "ehl_rough": ([PY, "benchmarks/bench_ehl_rough.py"], None, "benchmarks/bench_ehl_rough.py"),
    "ehl_moes": ([PY, "benchmarks/bench_ehl_moes.py"], None, "benchmarks/bench_ehl_moes.py"),
    "ehl_rough_tables": ([PY, "benchmarks/bench_ehl_tables.py", "--levels", "1", "2", "3", "--models", "hertz",
                          "smooth_ehl"], None,
                         "benchmarks/bench_ehl_tables.py --levels 1 2 3 --models hertz smooth_ehl"),
    "seed003_statements": ([PY, "examples/seed003_figures.py", "--quick", "--json", "--out", "{tmp}"], None,
                           "examples/seed003_figures.py --quick --json"),
    "trends": ([PY, "examples/seed000_trends.py", "--json", "--also-policy", "load_sharing", "--out", "{tmp}"],
               None, "examples/seed000_trends.py --json --also-policy load_sharing"),
    "fmu_rtf": ([PY, "benchmarks/bench_fmu_rtf.py", "--ppm", "32,64,128", "--integrators", "rk4_node,rk4_seg,rk4_kink",
                 "--substeps", "2,3,4,6", "--repeat", "5"], None,
                "benchmarks/bench_fmu_rtf.py --ppm 32,64,128 --integrators rk4_node,rk4_seg,rk4_kink --substeps 2,3,4,6 "
                "--repeat 5"),
    "table_front": ([PY, "benchmarks/bench_fmu_rtf.py", "--table-front"], None,
                    "benchmarks/bench_fmu_rtf.py --table-front"),
    "integrators": ([PY, "benchmarks/bench_integrators.py", "--repeat", "3"], None,
                    "benchmarks/bench_integrators.py --repeat 3"),
    "startup": ([PY, "benchmarks/bench_startup.py", "--commands", "build"], None,
                "benchmarks/bench_startup.py --commands build"),
    "plan": ([PY, "benchmarks/bench_plan.py", "--scenes", "default", "--timeout", "600"], None,
             "benchmarks/bench_plan.py --scenes default"),
    "plan_scan": ([PY, "benchmarks/bench_plan_scan.py", "--n", "50"], None, "benchmarks/bench_plan_scan.py --n 50"),
    "plan_study": ([PY, "examples/plan_study.py", "--json", "--out", "{tmp}"], None,
                   "examples/plan_study.py --json"),
    "tests": ([PY, "benchmarks/bench_tests.py"], None, "benchmarks/bench_tests.py"),
    "gearbox": ([PY, "benchmarks/bench_gearbox.py", "--repeat", "3"], None, "benchmarks/bench_gearbox.py --repeat 3"),
    "planetary": ([PY, "benchmarks/bench_planetary.py", "--repeat", "3"], None,
                  "benchmarks/bench_planetary.py --repeat 3"),
    "gearbox_fmu": ([PY, "benchmarks/bench_gearbox_fmu.py", "--sim", "0.5"], None,
                    "benchmarks/bench_gearbox_fmu.py --sim 0.5"),
    "me": ([PY, "benchmarks/bench_me.py"], None, "benchmarks/bench_me.py"),
    "composition": ([PY, "benchmarks/bench_composition.py"], None, "benchmarks/bench_composition.py"),
    "table_cache": ([PY, "benchmarks/bench_cache.py"], None, "benchmarks/bench_cache.py"),
    "estimate": ([PY, "benchmarks/bench_estimate.py"], None, "benchmarks/bench_estimate.py"),
    "silence": ([PY, "benchmarks/bench_silence.py"], None, "benchmarks/bench_silence.py"),
    "tests_quick": ([PY, "benchmarks/bench_tests.py", "-m", "not slow", "-n", "2"], None,
                    'benchmarks/bench_tests.py -m "not slow" -n 2'),
}
# sources that take several minutes: run only when named (--only) or with --all
SLOW = {"me", "trends", "ehl_corners", "ehl_rough", "ehl_moes", "ehl_rough_tables", "integrators", "startup",
        "plan_study", "plan_scan", "tests", "tests_quick", "gearbox", "planetary", "silence"}


# ------------------------------------------------------------------------------- running

def json_in(text: str):
    """The JSON a benchmark printed: the whole text, or from the first line that starts a JSON
    object or array to the end (lines of progress before it are skipped)."""
    try:
        return json.loads(text)
    except ValueError:
        pass
    lines = text.splitlines()
    for i, line in enumerate(lines):
        if line.lstrip()[:1] in ("{", "["):
            try:
                return json.loads("\n".join(lines[i:]))
            except ValueError:
                continue
    raise ValueError("no JSON object or array in it")


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
        except OSError as exc:
            return {"command": label, "ok": False, "reason": f"could not start: {exc}"}
        wall = time.perf_counter() - t0
        if proc.returncode != 0:
            tail = (proc.stderr.strip().splitlines() or ["(no message)"])[-1]
            return {"command": label, "ok": False, "wall_s": wall,
                    "reason": f"exit status {proc.returncode}: {tail[:200]}"}
        try:
            text = (ROOT / written).read_text() if written else proc.stdout
            data = json_in(text)
        except (OSError, ValueError) as exc:
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
    if not pg.missing("seed004", "Geometry and mesh stiffness: seed 004 Tables 2-3"):
        sec_stiffness_seed004(pg)
    sec_stiffness_iso(pg)
    if not pg.missing("helical_sawtooth", "Helical slices: sawtooth against the slice count"):
        sec_helical_sawtooth(pg)
    if not pg.missing("helical_contact", "Helical pair with load-dependent contact models"):
        sec_helical_contact(pg)


def sec_stiffness_seed004(pg: Page):
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


def sec_stiffness_iso(pg: Page):
    if not pg.missing("stiffness_iso", "Mean mesh stiffness of the seed pairs against ISO 6336-1"):
        d = pg.data["stiffness_iso"]
        body = []
        for r in d["rows"]:
            cp, cga = r["iso_c_prime"], r["iso_c_gamma_alpha"]
            body.append([r["pair"], f"{r['eps_alpha']:.4f}", f"{cp:.2f}",
                         f"{r['ours_max_single_pair']:.2f} ({pct(r['ours_max_single_pair'] / cp - 1, 0)})",
                         f"{cga:.2f}",
                         f"{r['ours_mean_shared_correction']:.2f} ({pct(r['ours_mean_shared_correction'] / cga - 1, 0)})",
                         f"{r['ours_mean_independent_foundations']:.2f} "
                         f"({pct(r['ours_mean_independent_foundations'] / cga - 1, 0)})",
                         f"{r['ours_mean_no_foundation']:.2f} ({r['ours_mean_no_foundation'] / cga:.1f} ×)"])

        def span(key):
            v = [r[key] / r["iso_c_gamma_alpha"] - 1 for r in d["rows"]]
            return f"{pct(min(v), 0)} … {pct(max(v), 0)}" if v else "n/a"

        pg.parts.append(
            "### Mean mesh stiffness of the seed pairs against ISO 6336-1 method B\n\n"
            "Reference: ISO 6336-1:2019 clause 9 (method B): single stiffness c′ = C_M C_R C_B / q′ "
            "(q′ from C1..C9 of its Table 9, C_M 0.8, C_R 1, C_B = 1 + 0.5 (1.2 − h_fP/m)) and mesh "
            "stiffness c_γα = c′ (0.75 ε_α + 0.25), an empirical band (±25 %) rather than an exact value.  "
            "Ours: the largest single-pair stiffness and the mean total mesh stiffness over a mesh period, "
            "per face width, of the example scenes of the seed pairs (their hub radii as the foundation's "
            "r_int), with the shared-foundation correction (λ = 1), with independent foundations (the "
            "default) and without the foundation term (docs/physics_stiffness.md).  N/(mm·µm); in brackets "
            "against ISO.\n\n"
            + table(["pair", "ε_α", "ISO c′", "ours max single pair", "ISO c_γα", "ours mean, shared correction",
                     "ours mean, independent foundations (default)", "ours mean, no foundation"], body)
            + f"\n\nSource: `{SOURCES['stiffness_iso'][2]}` ({pg.cost('stiffness_iso')}).\n")
        pg.summary.append(["mean mesh stiffness of the seed spur pairs", "ISO 6336-1 method B",
                           f"default {span('ours_mean_independent_foundations')}, shared correction "
                           f"{span('ours_mean_shared_correction')} (band ±25 %)", pg.cost("stiffness_iso")])

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


def sec_helical_sawtooth(pg: Page):
    d = pg.data["helical_sawtooth"]
    body = [[r["slices"], sci(r["one_over_ns_eps_alpha"]), sci(r["k_dev_whole"]), sci(r["k_dev_partial"]),
             sci(r["te_dev_whole"]), sci(r["te_dev_partial"])] for r in d["rows"]]
    pg.parts.append(
        "### Helical slices: sawtooth against the slice count\n\n"
        "Reference: the continuous face width (the limit of partly engaged slices at "
        f"NS = {d['limit_slices']}, which changes by {sci(d['limit_change_rel'], 1)} of the mean from half "
        "that slice count; the engaged width itself is checked against its closed form in "
        "tests/unit/gear/test_helical_sawtooth.py).  Seed 001 Table 1 pair "
        f"(ε_α {d['eps_alpha']:.4f}, ε_β {d['eps_beta']:.4f}), {d['points_per_mesh']} points per mesh: largest "
        "deviation of the total mesh stiffness (relative to its mean) and of the static transmission error "
        "(relative to its peak-to-peak, "
        f"{d['limit_static_te_ptp_m'] * 1e6:.3g} µm in the limit; k ptp/mean {d['limit_k_ptp_over_mean']:.3g}) "
        "from the limit, with whole slices entering and leaving and with partly engaged slices (the default, "
        "docs/helical.md).  1/(NS ε_α) is the size of one whole-slice step.\n\n"
        + table(["NS", "1/(NS ε_α)", "k dev, whole slices", "k dev, partial slices", "TE dev, whole",
                 "TE dev, partial"], body)
        + f"\n\nSource: `{SOURCES['helical_sawtooth'][2]}` ({pg.cost('helical_sawtooth')}).\n")


def sec_helical_contact(pg: Page):
    d = pg.data["helical_contact"]
    iso = d["iso_c_gamma_alpha"]
    body = [[f"`{r['model']}`", f"{r['slices']} × {r['points_per_mesh']}", f"{r['k_mean_N_per_mm_um']:.2f}",
             pct(r["rel_diff_iso"]), f"× {r['over_hertz']:.3f}", f"{r['ptp_over_mean']:.3f}",
             f"{r['hertz_ptp_over_mean']:.3f}", f"{r['spur_ptp_over_mean']:.3f}"] for r in d["rows"]]
    pg.parts.append(
        "### Helical pair with load-dependent contact models\n\n"
        f"Reference: ISO 6336-1:2019 method B, c_γα = {iso:.2f} N/(mm·µm) for the seed 001 Table 1 helical pair "
        "(virtual numbers of teeth; ±25 % band), and the spur pair of the same transverse section with the "
        "same contact model (the classical overlap smoothing).  Ours: tables with the contact model per "
        "slice (SCH632 at 60 °C, 1000 rpm, EHL grid of 129 nodes; docs/helical.md), mean total mesh "
        f"stiffness per face width at {d['torque_Nm']:g} N·m, against the Hertz tables of the same slicing, "
        "and the fluctuation peak-to-peak / mean.\n\n"
        + table(["model", "slices × points/mesh", "k̄/b (N/(mm·µm))", "vs ISO c_γα", "vs Hertz, same slicing",
                 "ptp/mean", "ptp/mean, Hertz", "ptp/mean, spur same section"], body)
        + f"\n\nSource: `{SOURCES['helical_contact'][2]}` ({pg.cost('helical_contact')}).\n")


def sec_thermal(pg: Page):
    if not pg.missing("seed004", "Thermal stiffness: seed 004 temperature states"):
        sec_thermal_factor(pg)
    if not pg.missing("thermal", "Thermal model, flank law and oil temperature"):
        sec_thermal_model(pg)


def sec_thermal_factor(pg: Page):
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


def _three(vals, fmt) -> str:
    return " / ".join(fmt(v) for v in vals)


def sec_thermal_model(pg: Page):
    d = pg.data["thermal"]
    points = d.get("points", ["meshing-in", "pitch", "meshing-out"])
    by = {(r["pair"], r["quantity"], r["state"], r["point"]): r for r in d["tables23"]}
    body, worst = [], {}
    for pair in ("I", "II"):
        for state in ("expansion", "shrinkage"):
            for q in ("pinion", "gear", "mesh"):
                rs = [by.get((pair, q, state, p)) for p in points]
                if any(r is None for r in rs):
                    continue
                da = [r["ours_with_seed_standard"] / r["seed"] - 1 for r in rs]
                db = [r["ours"] / r["seed"] - 1 for r in rs]
                worst[pair] = max([worst.get(pair, 0.0)] + [abs(v) for v in da])
                body.append([pair, q, state, _three([r["seed"] / 1e8 for r in rs], lambda v: f"{v:.5g}"),
                             _three([r["ours_with_seed_standard"] / 1e8 for r in rs], lambda v: f"{v:.5g}"),
                             _three(da, lambda v: f"{100 * v:+.2f}") + " %",
                             _three([r["ours"] / 1e8 for r in rs], lambda v: f"{v:.5g}"),
                             _three(db, lambda v: f"{100 * v:+.0f}") + " %"])
    src = f"\n\nSource: `{SOURCES['thermal'][2]}` ({pg.cost('thermal')} for this section).\n"
    pg.parts.append(
        "### Thermal model alone: Tables 2-3 with the seed's standard stiffness\n\n"
        "Reference: seed 004 Tables 2-3 (He & Yang), expansion (70 °C) and shrinkage (10 °C) states, "
        "in/pitch/out = meshing-in, pitch point, meshing-out.  (a): our thermal model (seed 004 eq 5-28, "
        "the radial + tangential flank law, Table 4 load F_n = T_1/r_b1) applied to the seed's own "
        "standard-state stiffness, which isolates the thermal model; (b): ours end to end (our standard "
        "stiffness too, docs/physics_stiffness.md).  1e8 N/m.\n\n"
        + table(["pair", "stiffness", "state", "seed 004 in / pitch / out", "(a) ours, seed's standard",
                 "difference (a)", "(b) ours end to end", "difference (b)"], body) + src)
    pg.summary.append(["thermal model on the seed's standard stiffness", "seed 004 Tables 2-3",
                       ", ".join(f"pair {p}: ≤ {100 * w:.2f} %" for p, w in sorted(worst.items())),
                       pg.cost("thermal")])

    body = []
    for pair, v in sorted(d.get("implied_load", {}).items()):
        ref = v["table4_load_N"]
        for law, loads in v["laws"].items():
            allv = loads["pinion"] + loads["gear"]
            body.append([pair, f"`{law}`", _three(loads["pinion"], lambda x: f"{x:.0f}"),
                         _three(loads["gear"], lambda x: f"{x:.0f}"), f"{ref:.1f}",
                         f"{pct(min(allv) / ref - 1, 2)} … {pct(max(allv) / ref - 1, 2)}"])
    pg.parts.append(
        "### Free flank deformation: the load the seed's Table 2 implies\n\n"
        "Reference: seed 004 Table 4 load F_n = T_1/r_b1 (80 kW at 2000 rpm, the load that reproduces its "
        "Table 2).  For each flank law of `gearfmu.gear.thermal` the load implied at each key point by "
        "the seed's shrinkage (−20 K) compliance of each tooth, F_n = |Δx_S,i| / (1/k_S,i − 1/k_i) with "
        "k_i, k_S,i from Table 2 (docs/thermal.md): a law consistent with the seed gives the Table 4 load "
        "at all six points.  N.\n\n"
        + table(["pair", "law", "pinion in / pitch / out", "gear in / pitch / out", "Table 4 load",
                 "range against Table 4"], body) + src)

    oil = d.get("oil", {})
    rows = oil.get("rows", [])
    if rows:
        def col(key, scale=1e6, digits=3):
            return [num(r[key] * scale, digits) if r.get(key) is not None else "n/a" for r in rows]

        hmin = [r["h_min_solver_m"] / r["h_min_dowson_higginson_m"] - 1 for r in rows if r.get("h_min_solver_m")]
        hc = [r["h_central_solver_m"] / r["h_central_moes_m"] - 1 for r in rows if r.get("h_central_solver_m")]
        body = [["η0 (Pa·s)", *col("eta0_Pas", 1.0)],
                ["h_min Dowson-Higginson (µm)", *col("h_min_dowson_higginson_m")],
                ["h_min solver (µm)", *col("h_min_solver_m")],
                ["h_c Moes (µm)", *col("h_central_moes_m")],
                ["h_c solver (µm)", *col("h_central_solver_m")],
                ["film stiffness per length, solver (N/m per m)", *col("k_film_solver_N_per_m_per_m", 1.0, 2)]]
        pg.parts.append(
            "### Oil temperature: film against the closed-form fits\n\n"
            "Reference: Dowson & Higginson's minimum-film and Moes' (1992) central-film fits of the smooth "
            "line contact.  Ours: η0(T) of the seed 004 Table 4 oil (320 / 38.5 cSt, ASTM D341 Walther "
            "law) and the slice film of the `smooth_ehl` contact model (the multigrid solver, the solve "
            "the tables' oil axis makes) at pair I's pitch point, Table 4 load, 2000 rpm, the scene's α at every "
            "temperature.  The Moes fit "
            "describes the Barus, incompressible film; the solver's Roelands, compressible film lies "
            "below it by physics (docs/ehl.md).\n\n"
            + table(["T (°C)", *[f"{r['temperature_C']:g}" for r in rows]], body)
            + (f"\n\nSolver against the fits over the temperatures: h_min {pct(min(hmin))} … {pct(max(hmin))} "
               f"against Dowson-Higginson, h_c {pct(min(hc))} … {pct(max(hc))} against Moes." if hmin and hc else "")
            + src)
        if hmin and hc:
            pg.summary.append(["film at the seed 004 oil's temperatures", "Dowson-Higginson, Moes (1992) fits",
                               f"h_min {pct(min(hmin))} … {pct(max(hmin))}, h_c {pct(min(hc))} … {pct(max(hc))}",
                               pg.cost("thermal")])

    pm = d.get("profile_vs_mean")
    if pm:
        kp = pm.get("key_points_one_pair_whole_load", {})
        tv = pm.get("tvms", {})
        body = [[f"pair stiffness at {p}, one pair, whole load", f"{v['difference_percent']:+.3f} %"]
                for p, v in kp.items()]
        body += [["TVMS over a mesh period (load shared), mean", f"{tv.get('mean_difference_percent', math.nan):+.3f} %"],
                 ["TVMS over a mesh period, largest absolute difference", f"{tv.get('max_abs_difference_percent', math.nan):.3f} %"]]
        pg.parts.append(
            "### Temperature profile against its mean\n\n"
            "No outside reference (seed Fig. 6b's profile is not in its text): pair I with illustrative "
            f"linear bulk-temperature profiles along the line of action, the seed's Fig. 7 means "
            f"(pinion {pm.get('pinion_mean_C', math.nan):.2f} °C, gear {pm.get('gear_mean_C', math.nan):.2f} °C) "
            "± 4 K, against the uniform mean temperatures (docs/thermal.md).\n\n"
            + table(["quantity", "profile against uniform mean"], body) + src)


def sec_load_sharing(pg: Page):
    if pg.missing("load_sharing", "Film-asperity load sharing"):
        return
    d = pg.data["load_sharing"]
    ks, kh = d["k_smooth_N_per_m"], d["k_hertz_N_per_m"]
    body = [[r["level"], f"{r['film_parameter_dh']:.2f}", f"{r['film_parameter_central']:.2f}",
             f"{r['eta_per_m2']:.3g}", num(r["beta_m"] * 1e6, 3), num(r["sigma_s_m"] * 1e6, 3), f"{r['alpha']:.0f}",
             num(r["asperity_share"], 2), f"{r['h_c_m'] * 1e6:.3f} / {r['h_c_smooth_m'] * 1e6:.3f}",
             num(r["area_ratio"], 2), f"{r['k_film_N_per_m'] / 1e9:.4f}", num(r["k_asp_N_per_m"] / 1e9, 2),
             f"{r['k_N_per_m'] / ks:.4f}"] for r in d["rows"]]
    pg.parts.append(
        "## Film-asperity load sharing\n\n"
        "No outside reference for the numbers (Johnson, Greenwood & Poon's own load-share curve was not "
        "available; the module's checks against closed forms and quadrature are in "
        "tests/unit/contact/test_load_sharing.py).  Seed 000 Table 1 pair at its pitch point, "
        f"{d['torque_Nm']:g} N·m (w = {d['w_N_per_m'] / 1e3:.1f} kN/m), its oil at "
        f"{d.get('oil_temperature_C', math.nan):g} °C, a {d['width_m'] * 1e3:g} mm slice, roughness levels of "
        "seed 000 Table 2 (docs/load_sharing.md): film parameters on the Dowson-Higginson minimum film "
        "(the switch's Λ) and on the central film (Λ_c), the Nayak/McCool summit parameters, the "
        "asperities' load share, the JGP central film against the smooth one, the real area ratio, the "
        "film and asperity springs and the total against the smooth film's stiffness k_smooth = "
        f"{ks / 1e9:.4f} GN/m (the EHL solver; Hertz: {kh / 1e9:.4f} GN/m).  Stiffness in GN/m.\n\n"
        + table(["level", "Λ (DH h_min)", "Λ_c (central)", "η (1/m²)", "β (µm)", "σ_s (µm)", "α", "asperity share",
                 "h_c / smooth (µm)", "A_r/A0", "k_film", "k_asp", "k/k_smooth"], body)
        + "\n\nThe mean TVMS with this policy is in the seed 000 trends section below (rows "
        "`+load sharing`)."
        + f"\n\nSource: `{SOURCES['load_sharing'][2]}` ({pg.cost('load_sharing')}).\n")


def sec_fractal(pg: Page):
    if pg.missing("fractal", "Fractal mixed-lubrication contact (seed 001)"):
        return
    d = pg.data["fractal"]
    body = [[r["level"], f"{r['K_n_per_width_N_per_m2']:.4g}", f"{r['K_s_per_width_N_per_m2']:.4g}",
             f"{r['K_l_per_width_N_per_m2']:.3g}", f"{r['real_area_ratio']:.3f}", f"{r['film_parameter']:.3g}",
             f"{r['lambda_c']:.3f}", sci(r["K_n_rel_spread_over_slicings"], 1)] for r in d["levels"]]
    sides = sorted({e["element_side_m"] for e in d.get("element_size", [])})
    by = {(e["level"], e["element_side_m"]): e for e in d.get("element_size", [])}
    ebody = [[r["level"], _three([by[(r["level"], a)]["K_s_per_width_N_per_m2"] for a in sides], lambda v: f"{v:.3g}"),
              _three([by[(r["level"], a)]["real_area_ratio"] for a in sides], lambda v: f"{v:.2f}")]
             for r in d["levels"] if all((r["level"], a) in by for a in sides)]
    slicings = ", ".join(str(n) for n in d["levels"][0].get("slicings", [])) if d["levels"] else ""
    hz = d.get("hertz_per_width_N_per_m2")
    pg.parts.append(
        "## Fractal mixed-lubrication contact\n\n"
        "No outside reference for the numbers: they describe our rebuild of seed 001 (docs/fractal_contact.md; "
        "its checks against closed forms and quadrature are in tests/unit/contact/test_fractal_contact.py).  Seed 000 "
        f"Table 1 pair at its pitch point, {d['torque_Nm']:g} N·m (w = {d['w_N_per_m'] / 1e3:.1f} kN/m, "
        f"R = {d['R_m'] * 1e3:.2f} mm, u = {d['u_m_s']:.2f} m/s, b = {d['b_m'] * 1e3:.3f} mm), the "
        "`fractal_mixed` slice model, roughness levels of seed 000 Table 2, per unit face width (N/m²); "
        f"the last column is the relative spread of K_n per width over {slicings} slices of the face."
        + (f"  For scale, Hertz: {hz:.3g} N/m²." if hz else "") + "\n\n"
        + table(["level", "K_n / width", "K_s / width", "K_l / width", "A_r/A0", "Λ", "λc", "spread over slicings"],
                body)
        + "\n\nThe solid part on reference elements of side "
        + " / ".join(f"{a * 1e3:g}" for a in sides) + " mm (the model's choice is the W-M sample length "
        f"{d.get('L_s_m', math.nan) * 1e3:g} mm):\n\n"
        + table(["level", "K_s / width", "A_r/A0"], ebody)
        + f"\n\nSource: `{SOURCES['fractal'][2]}` ({pg.cost('fractal')}).\n")


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


def sec_ehl_rough(pg: Page):
    if "ehl_rough" not in pg.data and "ehl_rough_tables" not in pg.data:
        pg.missing("ehl_rough", "Rough EHL films")
        return
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from report_ehl_rough import render as render_rough  # the section's own module (report.py's size)

    render_rough(pg, table, SOURCES["ehl_rough"][2])


def sec_ehl_moes(pg: Page):
    if pg.missing("ehl_moes", "Smooth EHL film against Moes' fit"):
        return
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from report_ehl_moes import render as render_moes  # the section's own module (report.py's size)

    render_moes(pg, table, SOURCES["ehl_moes"][2])


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
    for lv in (3, 4):
        row = tv.get(f"rough_level_{lv}+load_sharing")
        if row and smooth and hertz:
            between = [t for t in torques if hertz[t] < row[t] <= smooth[t]]
            checks.append([f"Fig. 13: rough level {lv} between Hertz and smooth", "tables, policy `load_sharing`",
                           f"{len(between)} of {len(torques)} torques"])
    notes = "".join(f"\n* {k.replace('_', ' ')}: {v}" for k, v in d.get("notes", {}).items())
    pg.parts.append(
        "## Contact models in the mesh\n\n"
        "Reference: the trends seed 000 (Zhao et al. 2022) section 5 reports for its Table 1 pair "
        "(Figs. 12-15): the lubricated TVMS lies above the Hertz one, rises with torque, falls as speed "
        "rises and falls as the roughness level rises.  Ours: mean TVMS of the tables "
        f"({d.get('points_per_mesh')} points per mesh period, {d.get('slices')} slices) with each contact "
        "model (docs/ehl_mesh.md); in 1e9 N/m, in brackets against the smooth film.  Where the film "
        "parameter is below 3 the scene's film-failure policy applies (notes below; the default "
        "`fractal_mixed`, rows `+load sharing` with the policy `load_sharing`, docs/load_sharing.md), "
        "which is outside seed 000's full-film assumption.\n\n"
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
        others = [(m, next((r for r in d["rows"] if r["method"] == f"native-{m}" and best
                            and r["setting"] == best["setting"]), None)) for m in ("rk4_node", "rk4")]
        natives = sorted({r["method"][len("native-"):] for r in d["rows"] if r["method"].startswith("native-")})
        lacking = [m for m in ("rk4", "rk4_kink", "rk4_node") if m not in natives]
        pg.parts.append(
            "## Dynamics and integrators\n\n"
            f"### Speed against error on the hard case `{d['case']}`\n\n"
            "Reference: an independent solver, scipy's DOP853 restarted at every table kink and contact "
            f"change (event location, `gearfmu/dynamics/reference.py`), rtol {ref.get('rtol', 'n/a')}.  "
            f"Compared: the native solver's integrators ({', '.join(natives) or 'none'}) at internal steps "
            "h = H/n (H the communication step), the FMU at communication steps of several mesh periods, "
            "and scipy's DOP853 and Radau at looser tolerances.  Errors are RMS and maximum over the "
            "communication instants, relative to the reference's range (docs/dynamics_validation.md)."
            + (f"  This JSON has no rows of {', '.join(lacking)}: regenerate it with "
               "`python benchmarks/report.py --only accuracy`." if lacking else "") + "\n\n"
            + table(["method", "setting", "wall s", "DTE rel. RMS", "DTE rel. max", "force rel. RMS"], body)
            + f"\n\n{img}\n\nSource: `{SOURCES['accuracy'][2]}` ({pg.cost('accuracy')}).\n")
        if best:
            diff = f"DTE RMS error at {best['setting']}: rk4_kink {sci(best['dte_rel_rms_err'])}"
            diff += "".join(f", {m} {sci(r['dte_rel_rms_err'])}" for m, r in others if r) + " of the range"
            cost = ", ".join(f"{m} {num(r['wall_s'], 2)} s" for m, r in [("rk4_kink", best), *others] if r)
            pg.summary.append(["dynamic response (DTE, mesh force)", "event-located DOP853 (scipy)", diff,
                               f"per run: {cost}"])

    if not pg.missing("hard_cases", "Hard cases against the reference"):
        d = pg.data["hard_cases"]
        cases = d.get("cases", d)
        body = []
        for name, c in (cases.items() if isinstance(cases, dict) else []):
            if not isinstance(c, dict):
                continue
            for integ in ("rk4_kink", "rk4_node", "rk4"):
                e = c.get(integ)
                if isinstance(e, dict):
                    body.append([c.get("title", name), integ, sci(e.get("dte_rel_rms_err", e.get("dte_rel_rms"))),
                                 sci(e.get("dte_rel_max_err", e.get("dte_rel_max"))),
                                 sci(e.get("force_rel_rms_err", e.get("force_rel_rms"))),
                                 num(e.get("wall_s"), 3)])
        pg.parts.append(
            "### Every hard case\n\n"
            f"Same reference; the native solver with each integrator in the JSON at the same internal step "
            f"h = H/{d.get('substeps_per_comm_step', '?')}, H = {d.get('comm_step', 'the communication step')} (heavy load, impacts on one and both flanks, low damping near resonance, high contact "
            "ratio, Ω_h = 2, torque steps, the default scene's computed tables).\n\n"
            + (table(["case", "integrator", "DTE rel. RMS", "DTE rel. max", "force rel. RMS", "wall s"], body)
               if body else "(no per-case rows in the JSON)")
            + f"\n\nSource: `{SOURCES['hard_cases'][2]}` ({pg.cost('hard_cases')}).\n")


def _front_rows_and_plot(pg: Page, d: dict, png: str, clock: str = "wall"):
    """The table rows (case, method, wall (or CPU) s at 1e-4 and 1e-6, speedup over DOP853) and the
    plot of the time-against-error fronts of bench_gearbox.py / bench_planetary.py (``clock``
    "wall" or "cpu": the rows' ``wall_s`` / ``cpu_s`` and the fronts' ``wall_at`` / ``cpu_at``)."""
    body = []
    for f in d["fronts"]:
        for m, at in f[f"{clock}_at"].items():
            sp = f["speedup_vs_DOP853"].get(m, {})
            body.append([f["case"], m, sci(at.get("1e-04")), sci(at.get("1e-06")),
                         "" if m not in f["speedup_vs_DOP853"] else
                         " / ".join("n/a" if sp.get(k) is None else f"{sp[k]:.0f} ×" for k in ("1e-04", "1e-06"))])

    def draw(plt):
        fig, axes = plt.subplots(1, len(d["fronts"]), figsize=(4.2 * len(d["fronts"]), 3.8), squeeze=False)
        for ax, f in zip(axes[0], d["fronts"]):
            for m in dict.fromkeys(r["method"] for r in f["rows"]):
                rs = [r for r in f["rows"] if r["method"] == m and 0 < r.get("dte_rel_rms_err", 0) < 1]
                if rs:
                    ax.loglog([r["dte_rel_rms_err"] for r in rs], [r[f"{clock}_s"] for r in rs], "o-", ms=3,
                              label=m)
            ax.set_title(f["case"], fontsize=9)
            ax.set_xlabel("DTE RMS error / DTE range")
            ax.grid(True, which="both", alpha=0.3)
        axes[0][0].set_ylabel(f"{'CPU' if clock == 'cpu' else 'wall'} time (s)")
        axes[0][0].legend(fontsize=7)
        return fig

    return body, pg.plot(png, draw)


def _front_summary(d: dict, what: str, reference: str) -> list:
    sp = d.get("summary_min_speedup_vs_DOP853", {})
    cells = ", ".join(f"{m} ≥ {v['1e-06']:.0f} × DOP853" for m, v in sp.items() if v.get("1e-06"))
    errs = [r["dte_rel_rms_err"] for f in d["fronts"] for r in f["rows"]
            if r["method"] == "rk4_node" and r["setting"] == "h=H/64"]
    diff = (f"DTE RMS error of rk4_node at h=H/64: {sci(min(errs))} … {sci(max(errs))} of the range"
            if errs else "n/a")
    return [what, reference, diff, f"at 1e-6: {cells or 'n/a'}"]


def sec_gearbox(pg: Page):
    if pg.missing("gearbox", "Gearboxes: the native gearbox solver against the scipy reference"):
        return
    d = pg.data["gearbox"]
    body, img = _front_rows_and_plot(pg, d, "validation_gearbox.png")
    ex = d.get("example", {})
    example = (f"\n\nThe example reducer `{ex['scene']}` ({ex['stages']} stages, {ex['bodies']} bodies, {ex['integrator']}, "
               f"internal step {sci(ex['step_s'])} s): {num(ex['wall_per_simulated_s'], 3)} s of wall time per simulated "
               f"second, {ex['ns_per_internal_step']:.0f} ns per internal step ({ex['events']} events in "
               f"{ex['stop_time_s']:g} s).") if ex else ""
    pg.parts.append(
        "## Gearboxes\n\n"
        "The native gearbox solver (docs/gearbox.md) on the hard cases of `gearfmu/gearbox/cases.py` (a two-stage "
        "reducer: contact loss in stage 1, the stage-1 mesh frequency on the intermediate-shaft mode, a torque step), "
        "against its event-located scipy reference at rtol 1e-12 (`gearfmu/gearbox/reference.py`).  Every native "
        "integrator at 2 to 256 substeps per communication step and the same scipy reference at looser tolerances "
        "(DOP853 at rtol 1e-4 to 1e-10 and 16 to 64 steps per shortest natural period); wall time of the "
        "whole call at relative RMS DTE errors 1e-4 and 1e-6 of the worse stage (log-log interpolation along each "
        "method's front) and the speedup over DOP853 there.\n\n"
        + table(["case", "method", "wall s at 1e-4", "wall s at 1e-6", "× DOP853 at 1e-4 / 1e-6"], body)
        + f"\n\n{img}{example}\n\nSource: `{SOURCES['gearbox'][2]}` ({pg.cost('gearbox')}).\n")
    pg.summary.append(_front_summary(d, "gearbox dynamics (two stages, shafts)",
                                     "event-located DOP853 (scipy), same equations"))


def sec_planetary(pg: Page):
    if pg.missing("planetary", "Planetary stages: the native planetary solver against the scipy reference"):
        return
    d = pg.data["planetary"]
    body, img = _front_rows_and_plot(pg, d, "validation_planetary.png", clock="cpu")
    ex = d.get("example", {})
    example = (f"\n\nThe example `{ex['scene']}` ({ex['meshes']} meshes, {ex['dofs']} degrees of freedom, "
               f"{ex['integrator']}, internal step {sci(ex['step_s'])} s): {num(ex['cpu_per_simulated_s'], 3)} s of "
               f"CPU time per simulated second, {ex['ns_per_internal_step']:.0f} ns per internal step "
               f"({ex['events']} events in {ex['stop_time_s']:g} s).") if ex else ""
    ck = d.get("c_kernel", {}).get("rows", [])
    if ck:
        example += ("\n\nThe planetary kernel in C (`gearfmu/fmu/kernel/plkernel.h`, stepped by `pl_do_step` through "
                    "ctypes, one call per communication step) against the numba solver's compiled loop on the same "
                    "runs, time per internal step and their ratio from one run; *bit for bit*: the C run's final "
                    "state equals the numba run's exactly.\n\n"
                    + table(["run", "integrator", "numba ns/step", "C ns/step", "numba / C", "bit for bit"],
                            [[r["run"], r["integrator"], f"{r['numba_ns_per_step']:.0f}", f"{r['c_ns_per_step']:.0f}",
                              num(r["numba_over_c"], 3), "yes" if r["bit_for_bit"] else "**no**"] for r in ck]))
    example += _planetary_fmu_line(d.get("fmu"))
    pg.parts.append(
        "## Planetary stages\n\n"
        "The native planetary solver (docs/planetary.md) on the hard cases of `gearfmu/bench.py` "
        "(Lin & Parker's system: contact loss in every mesh of three planets with backlash after a sudden "
        "unloading; four planets on a floating sun with a pin position error; a carrier-driven stage followed by "
        "a parallel stage), against its event-located scipy reference at rtol 1e-12 (`gearfmu/planetary/reference.py`).  "
        "Every native integrator at 2 to 256 substeps per communication step and the same scipy reference at "
        "looser tolerances (DOP853 at rtol 1e-4 to 1e-10, 16 to 64 steps per shortest natural period); CPU time "
        "of the whole call (process time: the single-threaded solvers' cost, less sensitive to other load on "
        "the machine than wall time) at relative RMS DTE errors 1e-4 and 1e-6 of the worst mesh (log-log "
        "interpolation along each method's front) and the speedup over DOP853 there.\n\n"
        + table(["case", "method", "CPU s at 1e-4", "CPU s at 1e-6", "× DOP853 at 1e-4 / 1e-6"], body)
        + f"\n\n{img}{example}\n\nSource: `{SOURCES['planetary'][2]}` ({pg.cost('planetary')}).\n")
    pg.summary.append(_front_summary(d, "planetary dynamics (Lin & Parker model, every mesh multi-pair)",
                                     "event-located DOP853 (scipy), same equations"))


def _planetary_fmu_line(f) -> str:
    """The planetary FMU's real-time factor in the C host at 1e-4 relative DTE error (bench_planetary.py ``fmu``)."""
    if not f:
        return ""
    parts = []
    for integ, v in f["integrators"].items():
        at = v.get("at_target")
        parts.append(f"{integ} {num(at['rtf_cpu'], 3)} x real time (max_step {sci(at['max_step_s'])} s)" if at
                     else f"{integ} does not reach it in the sweep (its error at the smallest step "
                          f"{sci(min(p['dte_rel_rms_err'] for p in v['sweep'] if 'dte_rel_rms_err' in p))})")
    return (f"\n\nThe planetary FMU of `{f['scene']}` ({f['planets']} planets, {f['dofs']} degrees of freedom) in "
            f"the C host `{f['host']}`, at the internal step that gives {sci(f['target_dte_rel_rms_err'])} relative RMS "
            f"DTE error against {f['reference']}: " + "; ".join(parts) + " (simulated per CPU second; goal >= 10)."
            + _fmu_floor(f))


def _fmu_floor(f) -> str:
    """What bounds the FMU's speed: its real-time factor at the largest step of the default integrator's
    sweep, where the steps no longer cost much and the table-node and contact events remain."""
    pts = [p for p in f["integrators"].get(f["integrator"], {}).get("sweep", []) if "rtf_cpu" in p]
    if not pts:
        return ""
    big = max(pts, key=lambda p: p["factor"])
    text = (f"  At {num(big['factor'], 3)} x the default step (error {sci(big['dte_rel_rms_err'])}) {f['integrator']} "
            f"still runs {num(big['rtf_cpu'], 3)} x real time: its events (every table node where the tables bend and "
            "every contact change of every mesh, one substep each) set the cost, not the step.")
    seg = [p for p in f["integrators"].get("rk4_seg", {}).get("sweep", []) if "rtf_cpu" in p]
    if seg:
        sb = max(seg, key=lambda p: p["factor"])
        text += (f"  rk4_seg stops only at the contact-zone edges, the big kinks and the nodes where e bends: at the "
                 f"same step it runs {num(sb['rtf_cpu'], 3)} x real time (error {sci(sb['dte_rel_rms_err'])}), bounded "
                 "by the RK4 steps themselves.")
    return text


def sec_me(pg: Page):
    if pg.missing("me", "Model Exchange against the event-located reference"):
        return
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from report_me import render as render_me  # the section's own module (report.py's size)

    render_me(pg, table, SOURCES["me"][2])


def sec_gearbox_fmu(pg: Page):
    if pg.missing("gearbox_fmu", "Gearbox FMU against its stages' pair FMUs"):
        return
    d = pg.data["gearbox_fmu"]
    g = d["gearbox"]
    gd = g["default"]
    stages = [r["stage"] for r in d["stages"]]
    body = [["gearbox FMU", sci(g["max_step_s"]), num(gd["cpu_s"] / d["sim_s"], 3),
             ", ".join(f"{m} {sci(gd['dte_rel_rms_err'][m])}" for m in stages)]]
    for r in d["stages"]:
        for label, x in (("own step rule", r["default"]), ("the gearbox's step", r["at_gearbox_step"])):
            body.append([f"pair FMU {r['stage']}, {label}", sci(x["max_step_s"]), num(x["cpu_s"] / d["sim_s"], 3),
                         sci(x["dte_rel_rms_err"])])
        m = r.get("at_gearbox_accuracy")
        body.append([f"pair FMU {r['stage']}, the gearbox's accuracy", sci(m["max_step_s"]) if m else "n/a",
                     num(m["cpu_s"] / d["sim_s"], 3) if m else "n/a",
                     sci(gd["dte_rel_rms_err"][r["stage"]]) + " (interpolated)"])
    mp = d.get("gearbox_matching_pairs")
    if mp:
        body.append(["gearbox FMU, the pair FMUs' accuracy", sci(mp["max_step_s"]), num(mp["cpu_s"] / d["sim_s"], 3),
                     "no stage above its pair FMU's (interpolated)"])
    ratios = [["pair FMUs at the gearbox's accuracy per stage (the goal's)", num(d["ratio_same_accuracy"], 3)],
              ["gearbox at the pair FMUs' accuracy (their default steps)", num(d["ratio_matching_pairs"], 3)],
              ["every FMU at its default step rule", num(d["ratio_step_rule"], 3)],
              ["every FMU at the gearbox's internal step", num(d["ratio_same_step"], 3)]]
    pg.parts.append(
        "## Gearbox FMU against its stages' pair FMUs\n\n"
        f"The gearbox FMU of `{d['scene']}` and the standalone pair FMU of each stage (the same tables at the "
        "stage's operating point in the gearbox, the same integrator and damping), each run "
        f"{d['sim_s']:g} s simulated at the {d['comm_step_s'] * 1e6:g} µs communication step by the plain C host "
        "`benchmarks/fmu_rtf_host.c` (doStep and every stage's DTE and mesh force per step); cost: the best "
        f"process CPU time of {d['repeat']} runs.  Accuracy: RMS(DTE − DTE_fine) / peak-to-peak(DTE_fine) of each "
        "stage against a fine run of the same model (the native gearbox, resp. pair, solver at an eighth of the "
        "step).  The gearbox FMU equals the native gearbox solver bit for bit: "
        + ("yes" if g.get("equals_native_solver") else "no") + ".\n\n"
        + table(["FMU, internal step", "step s", "CPU s per simulated s", "DTE error / range"], body)
        + "\n\nGearbox FMU cost / sum of the pair FMUs' costs:\n\n" + table(["compared at", "ratio"], ratios)
        + "\n\nOne FMU integrates every stage at the step of the fastest dynamics in the gearbox; a slower stage's "
        "own pair FMU takes larger steps at a lower accuracy, which the step-rule ratio counts against the gearbox. "
        f"\n\nSource: `{SOURCES['gearbox_fmu'][2]}` ({pg.cost('gearbox_fmu')}).\n")
    pg.summary.append(["gearbox FMU (two stages, shafts)", "native gearbox solver (numba), same steps",
                       "bit for bit" if g.get("equals_native_solver") else "differs",
                       f"{num(d['ratio_same_accuracy'], 3)} × its stages' pair FMUs at equal accuracy"])


#: the forms of bench_composition, as the report names them
COMPOSITION_FORMS = {"flange/fmpy": "SSP, flange coupling, fmpy", "flange/libcosim": "SSP, flange coupling, libcosim",
                     "flange_linear/libcosim": "SSP, flange at the received speed, libcosim",
                     "shaft/libcosim": "SSP, shaft FMUs, libcosim", "flange/libcosim-ecco": "SSP, flange, libcosim ECCO",
                     "gearbox_fmu/fmpy": "gearbox FMU, fmpy", "gearbox_fmu/libcosim": "gearbox FMU, libcosim",
                     "gearbox_fmu_me/fmpy-cvode": "gearbox FMU, Model Exchange, fmpy CVode rtol 1e-8"}


def _at(hit) -> str:
    if hit is None:
        return "not reached"
    cost = f"{num(hit['wall_per_sim_s'], 3)} s/s, CPU {num(hit.get('cpu_per_sim_s'), 3)}"
    if hit.get("step_s") is None:
        tail = f"; diverged from {sci(hit['diverged_from_s'])} s" if hit.get("diverged_from_s") else ""
        return f"below at {sci(hit['below_at_largest_step'])} s ({cost}{tail})"
    return f"{sci(hit['step_s'])} s ({cost})"


def sec_composition(pg: Page):
    if pg.missing("composition", "Gearboxes: the SSP of stage FMUs against the monolithic gearbox"):
        return
    d = pg.data["composition"]
    forms = [f for f in COMPOSITION_FORMS if f in d["forms"] and f != "flange/libcosim-ecco"]

    def cell(r):
        if r is None:
            return ""
        if r.get("diverged"):
            return "diverged"
        return f"{sci(r['dte_worst'])} / {sci(r['force_worst'])}"

    rows = [[sci(h)] + [cell(next((r for r in d["forms"][f] if r["step_s"] == h), None)) for f in forms]
            for h in d["steps_s"]]
    ecco = [[sci(r.get("tolerance")), sci(r.get("mean_step_s")), cell(r), sci(r.get("energy_residual_worst")),
             num(r.get("wall_per_sim_s"), 3), num(r.get("cpu_per_sim_s"), 3)]
            for r in d["forms"].get("flange/libcosim-ecco", [])]
    at = d.get("at_error", {})
    targets = [("DTE 1 %", "dte_0.01"), ("DTE 0.1 %", "dte_0.001"), ("mesh force 1 %", "mesh_force_0.01"),
               ("mesh force 0.1 %", "mesh_force_0.001")]
    at_rows = [[COMPOSITION_FORMS[f]] + [_at(at.get(f, {}).get(k)) for _, k in targets]
               for f in forms + ["flange/libcosim-ecco"] if f in d["forms"]]
    res = [[sci(r["step_s"]), sci(r.get("energy_residual_worst"))] for r in d["forms"].get("flange/libcosim", [])
           if not r.get("diverged")]

    def draw(plt):
        fig, axes = plt.subplots(1, 2, figsize=(10.5, 4.0))
        for f in forms + ["flange/libcosim-ecco"]:
            rs = sorted((r for r in d["forms"].get(f, []) if not r.get("diverged") and r["dte_worst"] > 0
                         and r["force_worst"] > 0), key=lambda r: r["step_s"])   # 0: the same substeps as the reference
            if not rs:
                continue
            line, = axes[0].loglog([r["step_s"] for r in rs], [r["dte_worst"] for r in rs], "o-", ms=3,
                                   label=COMPOSITION_FORMS[f])
            axes[0].loglog([r["step_s"] for r in rs], [r["force_worst"] for r in rs], "s--", ms=3,
                           color=line.get_color())
            axes[1].loglog([r["wall_per_sim_s"] for r in rs], [r["dte_worst"] for r in rs], "o-", ms=3,
                           color=line.get_color())
            axes[1].loglog([r["wall_per_sim_s"] for r in rs], [r["force_worst"] for r in rs], "s--", ms=3,
                           color=line.get_color())
        for ax in axes:
            for y in (1e-2, 1e-3):
                ax.axhline(y, color="grey", lw=0.6, ls=":")
            ax.grid(True, which="both", alpha=0.3)
            ax.set_ylabel("RMS error / range (worse stage)")
            ax.set_ylim(1e-9, 1.0)
        axes[0].set_xlabel("communication step (s; ECCO: its mean step)")
        axes[1].set_xlabel("wall time per simulated second (s)")
        axes[0].set_title("o- DTE, s-- mesh force", fontsize=9)
        axes[0].legend(fontsize=6)
        return fig

    img = pg.plot("validation_composition.png", draw)
    mono = d.get("gearbox_fmu_at_scene_step") or {}
    one = at.get("flange/libcosim", {})
    mono_text = (f"The monolithic gearbox FMU in libcosim at the scene's communication step "
                 f"{sci(d['scene_comm_step_s'])} s: {num(mono.get('wall_per_sim_s'), 3)} s per simulated second "
                 f"(CPU {num(mono.get('cpu_per_sim_s'), 3)} s) at {sci(mono.get('dte_worst'))} DTE error.  "
                 if mono else "")
    pg.parts.append(
        "## Gearboxes: the SSP of stage FMUs against the monolithic gearbox\n\n"
        f"The example reducer `{d['scene']}` run {d['sim_s']:g} s from its quasi-static state (the meshing errors and "
        "the mesh stiffness excite both stages) as an SSP of stage FMUs (`gearfmu ssp`, docs/gearbox.md \"The SSP of "
        "stage FMUs\") in fmpy's SSP master and in libcosim, and as the monolithic gearbox FMU, against the native "
        f"gearbox solver at a 1e-6 s communication step (every form integrates each stage with {d['integrator']} at "
        f"the internal step {sci(d['max_step_s'])} s).  Error: RMS(x − x_native) / peak-to-peak(x_native) of the "
        "worse stage's DTE and mesh force, at the run's communication points; cost per simulated second: "
        f"wall and process CPU time, each the best of {d['repeat']} runs (the machine is shared: CPU time is the "
        "steadier).  Couplings: *flange* (the default: every shaft inside the stage FMU of the "
        "light body it drives, the flange on the parabola of the last two speeds received), *flange at the received "
        "speed* (flange_order 1), *shaft FMUs* (the stages take torques, shaft FMUs integrate the exchanged speeds); "
        "a diverged run stopped with an error or left the range.\n\n"
        "Worse stage's DTE error / mesh-force error at each communication step:\n\n"
        + table(["step s"] + [COMPOSITION_FORMS[f] for f in forms], rows)
        + "\n\nWhere the error reaches 1 % and 0.1 % (log-log interpolation; cost there):\n\n"
        + table(["form"] + [t for t, _ in targets], at_rows)
        + "\n\nlibcosim's energy-conserving algorithm (ECCO) on the flange coupling, steps 1e-6 … 1e-4 s:\n\n"
        + table(["tolerance", "mean step s", "DTE / mesh-force error", "energy residual", "wall s/s", "CPU s/s"], ecco)
        + "\n\nEnergy residual at the bonds (libcosim ECCO's: Σ H |T_k ω_k+1 − ω_k T_k+1| over the energy through "
        "the bond, worst bond), flange coupling in libcosim:\n\n" + table(["step s", "energy residual"], res)
        + f"\n\n{img}\n\n{mono_text}Source: `{SOURCES['composition'][2]}` ({pg.cost('composition')}).\n")
    pg.summary.append(["SSP of stage FMUs (flange coupling, libcosim)", "native gearbox solver",
                       f"DTE 1 %: {_at(one.get('dte_0.01'))}; mesh force 1 %: {_at(one.get('mesh_force_0.01'))}",
                       f"gearbox FMU {num(mono.get('wall_per_sim_s'), 3)} s/s (CPU {num(mono.get('cpu_per_sim_s'), 3)}) "
                       f"at {sci(d['scene_comm_step_s'])} s"])


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


def _compact(v) -> str:
    """A JSON value of a statement's numbers in one table cell."""
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, (int, float)):
        return num(v, 3)
    if isinstance(v, list):
        return "[" + ", ".join(_compact(x) for x in v) + "]" if v else "none"
    if isinstance(v, dict):
        return "; ".join(f"{k}: {_compact(x)}" for k, x in v.items())
    return str(v).replace("|", "/")


def sec_seed003_statements(pg: Page):
    if pg.missing("seed003_statements", "Seed 003 statements (Figs. 6-30)"):
        return
    st = pg.data["seed003_statements"].get("statements", [])
    body = [[s["statement"].replace("|", "/"), "yes" if s["holds"] else "**no**", _compact(s.get("numbers"))]
            for s in st]
    pg.parts.append(
        "### Seed 003's statements (Figs. 6-30)\n\n"
        "Reference: the qualitative statements seed 003 makes about its Figs. 6-30 (errors, speed, load, "
        "damping), each judged on our numbers (docs/seed003.md; quick settings, the default stiffness "
        "model with an independent foundation per pair; A_r, A_rms and q in µm, forces in N).\n\n"
        + table(["statement (seed 003)", "reproduced", "our numbers"], body)
        + f"\n\nSource: `{SOURCES['seed003_statements'][2]}` ({pg.cost('seed003_statements')}).\n")
    pg.summary.append(["dynamic response: seed 003's statements on errors, speed, load, damping",
                       "seed 003 Figs. 6-30 (statements)",
                       f"{sum(1 for s in st if s['holds'])} of {len(st)} reproduced", pg.cost("seed003_statements")])


def _level(name, v) -> str:
    if name == "max_step" and isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0:
        return f"h0/{1 / v:g}" if v < 1 else ("h0" if v == 1 else f"{v:g} h0")
    if isinstance(v, bool):
        return "on" if v else "off"
    return num(v) if isinstance(v, float) else str(v)


def _plan_choices(r) -> tuple:
    """(kept at full, reduced or dropped) of one plan: its choice rows, or for JSON without them
    the chosen and full configurations compared (then pinned and fixed choices count as kept)."""
    rows = r.get("choices") or [{"choice": n, "full": f, "chosen": r["chosen"].get(n),
                                 "status": "kept" if r["chosen"].get(n) == f else "reduced"}
                                for n, f in r["full"].items() if n != "max_step_s"]
    kept = [x["choice"] + (" (pinned)" if x["status"] == "pinned" else "")
            for x in rows if x["status"] in ("kept", "pinned")]
    changed = [f"{x['choice']} {_level(x['choice'], x['full'])} → {_level(x['choice'], x['chosen'])}"
               for x in rows if x["status"] in ("reduced", "dropped")]
    return ", ".join(kept) or "none", ", ".join(changed) or "none"


def _plan_target(t) -> str:
    return "n/a" if not t else f"{100 * t['dte_rel']:g} % / {100 * t['mesh_force_rel']:g} %"


def _plan_use(v) -> str:
    """"; budget use U limited by MEASURE" of a plan's verification (empty for JSON without them)."""
    return "" if v.get("u") is None else f"; budget use {num(v['u'])} ({v.get('limit')})"


def _plan_fmu(fv) -> str:
    cases = (fv or {}).get("cases") or {}
    if not cases:
        return "not run"
    return (f"{sci(max(c['dte_rel'] for c in cases.values()))} / "
            f"{sci(max(c['mesh_force_rel'] for c in cases.values()))} ({len(cases)} cases)")


def sec_plan(pg: Page):
    title = "Fidelity plans: the planned model against the full-fidelity model"
    if "plan" not in pg.data and "plan_study" not in pg.data:
        pg.missing("plan", title)
        return
    body = []
    for scene, r in pg.data.get("plan", {}).get("scenes", {}).items():
        label = "default scene" if scene == "default" else f"`{scene}`"
        if r.get("exit_code") not in (0, 1):
            why = (f"stopped after {r['stopped_after_s']:.0f} s" if r.get("exit_code") is None
                   else f"failed (exit status {r['exit_code']})")
            body.append([label, "n/a", why, "", "n/a", "n/a", "n/a", f"{r['wall_s']:.1f} s", "not run"])
            continue
        kept, changed = _plan_choices(r)
        body.append([label, _plan_target(r.get("target")), kept, changed,
                     f"{sci(r['dte_rel'])} / {sci(r['mesh_force_rel'])}{_plan_use(r)} ({r.get('worst') or 'n/a'})",
                     _yes(r.get("within_target")), str(r.get("native_runs", "n/a")),
                     f"{r['wall_s']:.1f} s ({num(r.get('cpu_s', math.nan))} s CPU)", "not run"])
    for scene, r in pg.data.get("plan_study", {}).items():
        kept, changed = _plan_choices(r)
        v = r["verification"]
        body.append([f"`{scene}` (study)", _plan_target(r.get("target")), kept, changed,
                     f"{sci(v['dte_rel'])} / {sci(v['mesh_force_rel'])}{_plan_use(v)} ({v.get('worst') or 'n/a'})",
                     _yes(r.get("within_target")), str(v.get("native_runs", "n/a")),
                     f"{r['study_wall_s']:.1f} s ({num(r['study_cpu_s'])} s CPU)"
                     + (", with the FMUs" if r.get("fmu_verification") else ""),
                     _plan_fmu(r.get("fmu_verification"))])
    srcs = [n for n in ("plan", "plan_study") if n in pg.data]
    absent = [n for n in ("plan", "plan_study") if n not in pg.data]
    scan = _plan_scan_part(pg)
    pg.parts.append(
        f"## {title}\n\n"
        "`gearfmu plan` (docs/plan.md) keeps or lowers each modelling choice of a scene and then searches "
        "its envelope for the worst point of the planned configuration against the scene's full-fidelity "
        "configuration (the finest level of every choice).  Reference: that full-fidelity model, run by the "
        "same native solver; the errors are the measures of docs/plan.md \"Error measure\" (relative RMS of the "
        "DTE and of the mesh force, DTE peak-to-peak and mean, mesh orders 1-3 of DTE and mesh force), each "
        "against the scene's accuracy target; the table gives the two RMS errors and the budget use (largest "
        "measure over its target, with the measure that sets it) at the worst point.  The study scenes "
        "(`examples/plan_study.py`: shipped scenes with an envelope and a target added) are also built as "
        "FMUs, planned and full, and driven through fmpy over its verification cases (steady point, run-up, "
        "run-down, warm-up, duty cycle, the worst point found); the last column is the worst of those "
        "cases.  Choices with one level only (nothing to plan, e.g. thermal on a scene without a temperature "
        "range) are not listed.\n\n"
        + table(["scene", "target (DTE / force)", "kept at full", "reduced or dropped (full → chosen)",
                 "worst found (DTE / force, where)", "within target", "native runs", "plan time",
                 "through the FMUs (DTE / force)"], body)
        + "\n\nSources: " + ", ".join(f"`{SOURCES[n][2]}` ({pg.cost(n)})" for n in srcs)
        + "".join(f"; `{n}` not run (`python benchmarks/report.py --only {n}`)" for n in absent) + ".\n"
        + scan)


def _plan_scan_part(pg: Page) -> str:
    """The planner's verdicts checked on a seeded random scan of pairs (benchmarks/bench_plan_scan.py)."""
    head = "### The verdict on a random scan of pairs\n\n"
    if "plan_scan" not in pg.data:
        reason = pg.runs.get("plan_scan", {}).get("reason", "no saved JSON")
        return f"\n{head}Not run ({reason}). Produce it with `python benchmarks/report.py --only plan_scan`.\n"
    d = pg.data["plan_scan"]
    rows = [r for r in d["rows"] if "pass" in r]
    limits: dict = {}
    for r in rows:
        limits[r["plan_limit"]] = limits.get(r["plan_limit"], 0) + 1
    body = [[str(d["planned"]), str(d["helical"]), str(d["within_target"]), str(d["not_within_target"]),
             str(d["violations"]), num(d["worst_check_u_within_target"] if d["worst_check_u_within_target"]
                                       is not None else math.nan),
             ", ".join(f"{k} ({v})" for k, v in sorted(limits.items(), key=lambda x: -x[1]))]]
    pg.summary.append(["planner verdict on a random scan of pairs", "full-fidelity model, own check points",
                       f"{d['violations']} of {d['planned']} plans within target but above it at a check point",
                       pg.cost("plan_scan")])
    return (
        f"\n{head}"
        "Each of the scan's seeded random pairs (module, teeth, helix angle 0-40 deg, face width, load, speed, "
        "deviations; one operating point) is planned with the default target 2 % / 2 % on every measure of "
        "docs/plan.md \"Error measure\" (RMS, DTE peak-to-peak and mean, mesh orders 1-3 of DTE and mesh "
        "force).  Reference: the scene's full-fidelity model, run by the native solver beside the chosen one "
        "at the benchmark's own check points (the operating point with a run three times the planner's, and "
        "a random speed inside the band the FMU accepts without a warning).  A violation is a plan that says "
        "\"within target\" with a check point above the target; the budget use is the largest measure over "
        "its target (1 = on target).\n\n"
        + table(["pairs planned", "helical", "within target", "not within target (says so)", "violations",
                 "largest check budget use (within target)", "limiting measure of the plans (count)"], body)
        + f"\n\nSource: `{SOURCES['plan_scan'][2]}` ({pg.cost('plan_scan')}).\n")


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
    rtf = rtf_section(pg)
    if rtf:
        pg.parts.append(rtf)


def rtf_section(pg: Page) -> str:
    """The table-resolution front (plain lookup against the sub-cell lookup at the contact-zone
    edges) and the standalone FMU's real-time factor against its total error."""
    out = []
    if not pg.missing("table_front", "FMU runtime: table error against table resolution"):
        d = pg.data["table_front"]
        d = d.get("table_front", d)
        body = [[r["points_per_mesh"], sci(r["plain_dte_rel_rms_err"]), sci(r["subcell_dte_rel_rms_err"])]
                for r in d["rows"]]
        order = [o for o in d.get("subcell_order", []) if o is not None]
        out.append(
            "### Table error against table resolution\n\n"
            f"Scene `{d['scene']}`, native {d['integrator']} at a {d['max_step_s']:.3g} s step (integration "
            f"error far below the table error), {d['simulated_s']:g} s simulated.  Error: RMS(dte − dte_ref) / "
            f"RMS(dte_ref), the reference the same lookup on tables at {d['fine_points_per_mesh']} points per "
            "mesh.  *plain*: linear interpolation across each pair's meshing-in and meshing-out steps (the "
            "tables without their engagement angles); *sub-cell*: the steps placed at the exact angles "
            "(docs/model.md \"Contact-zone edges\").  Observed order of the sub-cell error: "
            + (", ".join(f"{o:.2f}" for o in order) if order else "n/a") + ".\n\n"
            + table(["points per mesh", "plain", "sub-cell"], body)
            + f"\n\nSource: `{SOURCES['table_front'][2]}` ({pg.cost('table_front')}).\n")
    if not pg.missing("fmu_rtf", "FMU runtime: real-time factor against total error"):
        d = pg.data["fmu_rtf"]
        ref = d["reference"]
        body = [[r["points_per_mesh"], r["integrator"], r["substeps"], sci(r["dte_rel_rms_err"]),
                 sci(r["dte_rel_rms_err_same_table"]), f"{r['c_host_real_time_factor']:.0f}",
                 f"{r.get('fmpy_raw_real_time_factor', math.nan):.0f}", f"{r.get('fmpy_real_time_factor', math.nan):.0f}"]
                for r in d["runs"]]
        out.append(
            "### Standalone FMU: real-time factor against total error\n\n"
            f"Scene `{d['scene']}`, communication step {1e6 * d['comm_step_s']:.3g} µs, {d['simulated_s']:g} s "
            "simulated; the FMU's outputs read after every step.  Total error: RMS(dte − dte_ref) / RMS(dte_ref) "
            f"against {ref['kind']} on tables at {ref['points_per_mesh']} points per mesh with a "
            f"{ref['max_step_s']:.3g} s step (that reference is {sci(d['reference_check']['dte_rel_rms_err'])} "
            f"from one on tables twice as fine); integration error: the same against the fine-step run on "
            "the FMU's own tables.  Real-time factor = simulated s / best wall s of the repeats, through a "
            "C FMI host (`benchmarks/fmu_rtf_host.c`), fmpy's raw ctypes pointers, and fmpy's low-level "
            "loop (`FMU2Slave.doStep` and `fmi2GetReal`).\n\n"
            + table(["points per mesh", "integrator", "max step = comm /", "total error", "integration error",
                     "C host × RT", "fmpy raw × RT", "fmpy × RT"], body)
            + _floor_text(d)
            + f"\n\nSource: `{SOURCES['fmu_rtf'][2]}` ({pg.cost('fmu_rtf')}).\n")
    return "\n".join(out)


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
     "closure, seed 000 eq 16, scipy's brentq on the load balance", "tests/unit/gear/test_meshing_errors.py, "
     "tests/unit/gear/test_loaded_mesh.py"),
    ("contact models and roughness (fractal, load sharing, W-M)", "seed 001 Figs. 7-12 statements, "
     "quadrature of the asperity integrals, seed 000 Table 2 Ra, the W-M closed-form RMS",
     "tests/unit/contact/test_fractal_contact.py, tests/unit/contact/test_load_sharing.py, tests/unit/contact/test_roughness.py"),
    ("rough EHL in the mesh, transient films", "seed 000 Figs. 12-15 trends, Venner et al. waviness "
     "reduction", "tests/unit/contact/test_ehl_mesh.py, tests/unit/ehl/test_ehl_transient.py"),
    ("helical geometry and slicing", "hand formulas for ε_α, ε_β and the centre distance; the "
     "continuous face-width limit", "tests/unit/gear/test_helical.py, tests/unit/gear/test_helical_sawtooth.py"),
]


NOT_MEASURED = "not measured"


def _yes(ok) -> str:
    return "n/a" if ok is None else ("yes" if ok else "no")


class NotMeasured(Exception):
    """The source's JSON exists but does not measure this goal (the message says why)."""


def _goal(data, name, fn):
    """fn(JSON) -> (measured, met) for a goal; "not measured" without the source's JSON."""
    if name not in data:
        return [f"{NOT_MEASURED} (no `{name}` JSON: `python benchmarks/report.py --only {name}`)", "n/a"]
    try:
        measured, ok = fn(data[name])
    except NotMeasured as exc:
        return [f"{NOT_MEASURED} ({exc})", "n/a"]
    except (KeyError, TypeError, ValueError, IndexError) as exc:
        return [f"{NOT_MEASURED} (the `{name}` JSON has no {exc})", "n/a"]
    return [measured, _yes(ok)]


def _g_build(d):
    b = d["commands"]["build"]
    return f"{b['warm_s']:.2f} s warm, {b['cold_s']:.1f} s cold (empty numba cache)", b["warm_s"] <= 2.0


def _g_proxy(d):
    rows = [r for r in d["cases"].values() if r.get("c_over_proxy") is not None]
    if not rows:
        raise NotMeasured("the kernels benchmark ran without a plain-C proxy source (`--proxy`); "
                          + ("set GEARFMU_RK4_PROXY to the proxy's C source" if PROXY is None else
                             f"regenerate: `python benchmarks/report.py --only kernels` passes {PROXY}"))
    r = next((r for r in rows if r["case"] == "default_scene" and r["integrator"] == "rk4"), rows[0])
    return f"{r['c_over_proxy']:.2f} × ({r['case']}, {r['integrator']})", r["c_over_proxy"] <= 1.5


def _g_numba(d):
    rows = list(d["cases"].values())
    worst = max(rows, key=lambda r: r["numba_over_c"])
    return (f"≤ {worst['numba_over_c']:.2f} × over {len(rows)} case/integrator rows (worst "
            f"{worst['case']}, {worst['integrator']})", worst["numba_over_c"] <= 1.3)


def _default_integrator():
    try:
        from gearfmu.common.vocabulary import DEFAULT_INTEGRATOR
        return DEFAULT_INTEGRATOR
    except ImportError:
        return None


def _g_dop853(d):
    fronts = d["fronts"]
    speed = {}
    for f in fronts:
        for integ, at in f["speedup_vs_DOP853"].items():
            speed.setdefault(integ, []).append((f["case"], at.get("1e-06")))
    cells = []
    for m, vs in speed.items():
        ok = [v for _, v in vs if v is not None]
        miss = [c for c, v in vs if v is None]
        cells.append(f"{m} " + (f"≥ {min(ok):.0f} ×" if ok else "n/a")
                     + (f" (1e-6 not reached or no DOP853 time on {', '.join(miss)})" if miss else ""))
    speed = {m: [v for _, v in vs] for m, vs in speed.items()}
    default = _default_integrator()
    vs = speed.get(default, [None])
    ok = None if any(v is None for v in vs) else min(vs) >= 300.0
    return (", ".join(cells) + f" (smallest over the cases {', '.join(f['case'] for f in fronts)}; "
            f"met judged on the default integrator {default})", ok)


def _g_fmu_native(d):
    r, s = d["fmu_over_native_per_sim_s_lowlevel"], d["fmu_over_native_per_sim_s_simulate_fmu"]
    text = (f"{r:.2f} × (low-level FMI loop), {s:.2f} × (`fmpy.simulate_fmu`) at a "
            f"{1e6 * d['comm_step_scene_s']:.3g} µs communication step")
    b = d.get("fmu_over_native_per_sim_s_bound")
    if b:
        text += (f"; the same loop around two C functions that do nothing already takes {b['lean'] - 1:.2f} × the "
                 f"native solver's time, so an FMU whose steps cost what the native solver's do cannot be below "
                 f"{b['lean']:.2f} × through that loop on this machine ({b['raw']:.2f} × through fmpy's raw "
                 "ctypes pointers)")
    return text, r <= 3.0


_RTF_HOSTS = (("fmpy_real_time_factor", "fmpy low-level loop"),
              ("fmpy_raw_real_time_factor", "fmpy's raw ctypes pointers"),
              ("c_host_real_time_factor", "C host"))


def _floor_text(d) -> str:
    """The fmpy loops' ceiling on this machine: the same loops around two C functions that do nothing."""
    fl = d.get("python_floor")
    if not fl:
        return ""
    return ("\n\nThe same Python loops around two C functions that do nothing (`benchmarks/fmi2_noop.c`, "
            "called with fmpy's argument types and through fmpy's own wrappers) reach "
            f"{fl['lean']['real_time_factor']:.0f} × real time (fmpy's low-level loop, "
            f"{fl['lean']['ns_per_step']:.0f} ns per step) and {fl['raw']['real_time_factor']:.0f} × (raw ctypes "
            f"pointers, {fl['raw']['ns_per_step']:.0f} ns per step): no FMU, however cheap, runs faster than "
            "that through these loops on this machine.")


def _rtf_setting(r) -> str:
    return (f"{r['points_per_mesh']} points per mesh, {r['integrator']}, max step = communication step / "
            f"{r['substeps']}, total DTE error {sci(r['dte_rel_rms_err'])}")


def _g_rtf(d):
    """Fastest run within the target on the total error (tables and steps against the fine run)."""
    best = d["cheapest"]["dte_rel_rms_err"]
    rows = [(label, best.get(k), k) for k, label in _RTF_HOSTS]
    if rows[0][1] is None:
        return f"no run within {sci(d['target'])} total DTE error", False
    settings = {_rtf_setting(r) for _, r, _ in rows if r}
    cells = ", ".join(f"{label} {r[k]:.0f} ×" + ("" if len(settings) == 1 else f" ({_rtf_setting(r)})")
                      for label, r, k in rows if r)
    where = f"; fastest within {sci(d['target'])}: {settings.pop()}" if len(settings) == 1 else ""
    fl = d.get("python_floor")
    ceiling = (f"; the fmpy loop around two no-op C functions: {fl['lean']['real_time_factor']:.0f} × "
               f"(raw pointers {fl['raw']['real_time_factor']:.0f} ×)") if fl else ""
    return (f"{cells}{where}{ceiling} (scene {d['scene']}, communication step {1e6 * d['comm_step_s']:.3g} µs)",
            rows[0][1]["fmpy_real_time_factor"] >= 50.0)


def _g_ehl_point(d):
    s = d["summary"]
    return (f"worst {s['max_cpu_s']:.3g} s, median {1e3 * s['median_cpu_s']:.3g} ms CPU over {s['points']} "
            "points of Moes' (M, L) range (default solve)", s["max_cpu_s"] <= 1.0)


def _g_ehl_default(d):
    rows = [r for r in d["rows"] if r.get("case") == "default_1025"]
    if not rows:
        raise NotMeasured("no default 1025-node rows in the `ehl_corners` JSON")
    worst = max(r["cpu_s"] for r in rows)
    return (f"≤ {1e3 * worst:.3g} ms CPU (default 1025-node solve, Roelands, M = "
            + "/".join(f"{r['M']:g}" for r in rows) + ", L = 10)", worst <= 5e-3)


def _g_plan(d):
    r = d["scenes"]["default"]
    if r.get("exit_code") is None:
        return f"stopped after {r.get('stopped_after_s', math.nan):.0f} s", False
    return f"{r['wall_s']:.1f} s wall, {r.get('cpu_s', math.nan):.1f} s CPU (default scene)", r["wall_s"] <= 60.0


def _g_tests(d):
    extra = "" if d.get("exit_code") == 0 else f"; the suite did not pass: {d.get('summary', '?')}"
    return f"{d['wall_s']:.0f} s ({d.get('summary', '')}){extra}", d["wall_s"] <= 300.0


def _g_tests_quick(d):
    extra = "" if d.get("exit_code") == 0 else f"; the subset did not pass: {d.get('summary', '?')}"
    return (f"{d['wall_s']:.0f} s ({d.get('summary', '')}, {d.get('cpu_count', '?')} cores){extra}",
            d["wall_s"] <= 60.0 and d.get("exit_code") == 0)


def _g_gearbox(d):
    sp = d["summary_min_speedup_vs_DOP853"]
    cells = ", ".join(f"{m} " + ("n/a" if v.get("1e-06") is None else f"≥ {v['1e-06']:.0f} ×") for m, v in sp.items())
    default = _default_integrator()
    v = sp.get(default, {}).get("1e-06")
    return (f"{cells} (smallest over the cases {', '.join(f['case'] for f in d['fronts'])}; met judged on the "
            f"default integrator {default})", None if v is None else v >= 300.0)


def _g_planetary_fmu(d):
    """The fastest integrator of the sweep at the target error (the FMU's ``integrator`` parameter picks it)."""
    f = d["fmu"]
    hits = {k: v["at_target"] for k, v in f["integrators"].items() if v.get("at_target")}
    if not hits:
        raise NotMeasured(f"no integrator reaches {f['target_dte_rel_rms_err']:g} in the sweep")
    integ, hit = max(hits.items(), key=lambda kv: kv[1]["rtf_cpu"])
    return (f"{hit['rtf_cpu']:.1f} × ({integ}, {f['scene']}: {f['planets']} planets, {f['meshes']} meshes; "
            f"max_step {hit['max_step_s']:.3g} s; CPU time, C host)", hit["rtf_cpu"] >= 10.0)


def _g_gearbox_fmu(d):
    r = d["ratio_same_accuracy"]
    if r is None:
        raise NotMeasured("the pair FMUs' sweep does not reach the gearbox's accuracy")
    return (f"{r:.2f} × (pair FMUs at the gearbox's accuracy per stage; {d['ratio_matching_pairs']:.2f} × with the "
            f"gearbox at the pair FMUs' accuracy, {d['ratio_step_rule']:.2f} × at every FMU's default step; CPU time, "
            f"{d['scene']}, C host)", r <= d.get("goal", 1.3))


def _g_cache(d):
    worst = max(d["ratio"].values())
    return (f"{100 * worst:.2g} % of the first command's table time ({d['runs'][0]['table_s']:.1f} s, scene "
            f"{d['scene']})", bool(d["within_goal"]))


def _g_estimate(d):
    n = sum(1 for r in d["scenes"].values() if "ratio" in r)
    return f"worst {d['worst_ratio']:.2f} × over {n} scenes (time, table and FMU size)", bool(d["within_2x"])


def _g_silence(d):
    return (f"longest {d['worst_s']:.1f} s between two lines; start-up (Python imports) up to "
            f"{d['worst_startup_s']:.1f} s", d["worst_s"] <= d["goal_s"])


def goal_rows(data: dict) -> list:
    """[goal, measured, met] for each speed goal, from whatever benchmark JSON exists."""
    goals = [
        ("warm `gearfmu build` of the default scene ≤ 2 s", "startup", _g_build),
        ("C kernel per RK4 step ≤ 1.5 × the plain-C proxy at equal flags", "kernels", _g_proxy),
        ("numba native solver per step ≤ 1.3 × the C kernel", "kernels", _g_numba),
        ("rk4 integrators ≥ 300 × faster than DOP853 at 1e-6 relative DTE error", "integrators", _g_dop853),
        ("native gearbox solver ≥ 300 × the scipy reference at 1e-6 relative DTE error", "gearbox", _g_gearbox),
        ("native planetary solver ≥ 300 × the scipy reference at 1e-6 relative DTE error", "planetary", _g_gearbox),
        ("planetary stage FMU ≥ 10 × real time at 1e-4 relative DTE error (C host)", "planetary", _g_planetary_fmu),
        ("gearbox FMU ≤ 1.3 × its stages' pair FMUs per simulated second (C host, same accuracy)", "gearbox_fmu",
         _g_gearbox_fmu),
        ("FMU ≤ 3 × native per simulated second", "fmu_speed", _g_fmu_native),
        ("FMU ≥ 50 × real time at 1e-4 relative DTE error (fmpy low-level loop)", "fmu_rtf", _g_rtf),
        ("EHL film ≤ 1 s per point", "ehl_corners", _g_ehl_point),
        ("EHL film ≤ 5 ms per point at the default settings", "ehl_corners", _g_ehl_default),
        ("`gearfmu plan` of the default scene ≤ 60 s", "plan", _g_plan),
        ("test suite ≤ 5 min", "tests", _g_tests),
        ("quick test subset (`pytest -m \"not slow\" -n 2`) ≤ 60 s", "tests_quick", _g_tests_quick),
        ("second command on a scene: table time < 5 % of the first (table cache)", "table_cache", _g_cache),
        ("cost estimate within 2 × of the measured table time and sizes", "estimate", _g_estimate),
        ("no command silent on stderr for more than 2 s", "silence", _g_silence),
    ]
    return [[g, *_goal(data, name, fn)] for g, name, fn in goals]


def goals_table(data: dict) -> str:
    return table(["goal", "measured", "met"], goal_rows(data))


def sec_goals(pg: Page):
    srcs = ["startup", "kernels", "integrators", "gearbox", "planetary", "gearbox_fmu", "fmu_speed", "fmu_rtf", "ehl_corners", "plan", "tests",
            "tests_quick", "table_cache", "estimate", "silence"]
    pg.parts.append(
        "## Speed goals\n\n"
        "Each goal beside the value measured by its benchmark (wall or CPU time of one run on the machine "
        "that generated the page); a goal whose benchmark JSON is missing reads \"not measured\".  The "
        "same table is in the README.\n\n" + goals_table(pg.data)
        + "\n\nSources: " + ", ".join(f"`{SOURCES[n][2]}` ({pg.cost(n)})" for n in srcs) + ".\n")


def _mb(b) -> str:
    return f"{b / 1e6:.3g}"


def sec_costs(pg: Page):
    """The table cache, the cost estimate and the silence of the commands."""
    pg.parts.append("## Table cache, cost estimate and progress\n")
    if not pg.missing("table_cache", "Table cache: the second command on a scene"):
        d = pg.data["table_cache"]
        first = d["runs"][0]["table_s"]
        body = [[f"`{r['command']}`", "yes" if r["from_cache"] else "no", f"{r['table_s']:.3g}",
                 f"{100 * r['table_s'] / first:.3g} %", f"{r['wall_s']:.1f}", f"{r['cpu_s']:.1f}"] for r in d["runs"]]
        pg.parts.append(
            "### Table cache: the second command on a scene\n\n"
            f"Scene `{d['scene']}`; every command a fresh process, the gearfmu cache empty before the first.  "
            "Table time: the table step as the command prints it (wall); the command's wall and CPU time "
            "(process and children) beside it.  Reference: the first command, which computes the tables "
            "(docs/cli.md \"Table cache\").\n\n"
            + table(["command", "tables from the cache", "table s", "of the first", "command wall s",
                     "command CPU s"], body)
            + f"\n\nSource: `{SOURCES['table_cache'][2]}` ({pg.cost('table_cache')}).\n")
        pg.summary.append(["table cache (second command)", "the first command's table time",
                           f"{100 * max(d['ratio'].values()):.2g} % of it", pg.cost("table_cache")])
    if not pg.missing("estimate", "Cost estimate against the measured cost"):
        d = pg.data["estimate"]
        body = []
        for name, r in d["scenes"].items():
            if "ratio" not in r:
                body.append([f"`{name}`", r.get("error", "failed"), "", "", "", "", "", ""])
                continue
            e, m, q = r["estimate"], r["measured"], r["ratio"]
            body.append([f"`{name}`", r["counts"]["contact_model"], f"{e['build_s']:.3g}", f"{m['build_cpu_s']:.3g}",
                         f"{q['build_time']:.2f}", f"{_mb(e['fmu_bytes'])} / {_mb(m['fmu_bytes'])}",
                         f"{q['fmu_bytes']:.2f}", f"{q['table_bytes']:.2f}"])
        pg.parts.append(
            "### Cost estimate against the measured cost\n\n"
            "Every example scene, the default scene and the scenes of `benchmarks/scenes/` (a small rough-EHL "
            "pair, a large helical table over the hunting-tooth cycle, an oil-temperature axis): the estimate "
            "of `gearfmu.assembly.estimate` before anything is computed, against one table build in a fresh process "
            "(CPU time of the process and its film workers, less sensitive to other load than wall time) and the "
            "FMU built from those tables.  Goal: every ratio within [0.5, 2] (docs/tables.md \"Cost estimate\").\n\n"
            + table(["scene", "contact model", "estimated CPU s", "measured CPU s", "time est./meas.",
                     "FMU MB est. / meas.", "FMU est./meas.", "tables est./meas."], body)
            + f"\n\nWorst ratio {d['worst_ratio']:.2f} ({'within' if d['within_2x'] else 'NOT within'} 2 ×); "
            f"{d.get('cpu_count')} CPUs.  Source: `{SOURCES['estimate'][2]}` ({pg.cost('estimate')}).\n")
        pg.summary.append(["cost estimate (time, sizes)", "measured table build and FMU",
                           f"within {d['worst_ratio']:.2f} ×", pg.cost("estimate")])
    if not pg.missing("silence", "Progress: the longest silence of each command"):
        d = pg.data["silence"]
        body = [[f"`{sc}`", f"`{cmd}`", f"{r['longest_silence_s']:.2f}", r["before"].replace("|", "/")[:70],
                 f"{r['startup_s']:.2f}", f"{r['wall_s']:.1f}"]
                for sc, cmds in d["scenes"].items() for cmd, r in cmds.items()]
        pg.parts.append(
            "### Progress: the longest silence of each command\n\n"
            "Each command in a fresh process, stderr stamped on every write (the table cache empty for each "
            "scene's first command).  Longest silence: the largest gap between two writes after the first "
            "(the exit counts), with the line shown during it; start-up: from the process start to its "
            f"first line.  Goal: ≤ {d['goal_s']:g} s.\n\n"
            + table(["scene", "command", "longest silence s", "during", "start-up s", "wall s"], body)
            + f"\n\nSource: `{SOURCES['silence'][2]}` ({pg.cost('silence')}).\n")


SECTIONS = ("sec_stiffness", "sec_thermal", "sec_ehl", "sec_ehl_moes", "sec_ehl_rough", "sec_load_sharing",
            "sec_fractal", "sec_trends", "sec_dynamics", "sec_gearbox", "sec_gearbox_fmu", "sec_planetary",
            "sec_composition", "sec_me", "sec_arms",
            "sec_seed003_statements", "sec_plan", "sec_fmu", "sec_costs", "sec_goals")


def render(data: dict, runs: dict, out: Path, img_dir: Path, failed: list = None) -> str:
    """The page; a section that cannot be rendered from its JSON is named on the page and in
    ``failed`` (when given) and the others are still written."""
    pg = Page(data, runs, img_dir, out)
    for name in SECTIONS:
        n_parts = len(pg.parts)
        try:
            globals()[name](pg)
        except Exception as exc:  # noqa: BLE001 -- one section's JSON must not stop the page
            del pg.parts[n_parts:]
            msg = f"{type(exc).__name__}: {exc}"
            pg.parts.append(f"## {name[4:].replace('_', ' ').capitalize()}\n\nCould not be rendered from its "
                            f"JSON ({msg}).\n")
            if failed is not None:
                failed.append(f"section {name[4:]}: {msg}")
    head = (
        "# Validation report\n\n"
        "<!-- Generated by benchmarks/report.py from benchmark JSON; do not edit by hand. -->\n\n"
        "What each physics area of gearfmu is compared against, outside gearfmu (closed forms, "
        "published tables, a standard, an independent solver), how large the difference is and "
        "what it costs.  Every number on this page comes from the JSON of the benchmark or example "
        "named under its table; regenerate the page (and the plots in `docs/img/`) with\n\n"
        "```bash\npython benchmarks/report.py              # runs the sources with quick settings, a few minutes\n"
        f"python benchmarks/report.py --all        # also the slow sources ({', '.join(sorted(SLOW))})\n"
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
    """Replace the block between the speed markers of README.md (the speed table and the goals
    table); False if the markers are absent."""
    text = readme.read_text()
    if SPEED_BEGIN not in text or SPEED_END not in text:
        return False
    a, rest = text.split(SPEED_BEGIN, 1)
    _, b = rest.split(SPEED_END, 1)
    speed = (speed_table(data["fmu_speed"]) if "fmu_speed" in data else
             f"{NOT_MEASURED.capitalize()} (no `fmu_speed` JSON: `python benchmarks/report.py --only fmu_speed`).")
    block = (f"{SPEED_BEGIN}\n<!-- written by benchmarks/report.py from `{SOURCES['fmu_speed'][2]}` and the "
             "benchmarks named in docs/validation.md \"Speed goals\" -->\n"
             + speed + "\n\nGoals beside the measured values:\n\n" + goals_table(data) + f"\n{SPEED_END}")
    readme.write_text(a + block + b)
    return True


def load_dir(d: Path, failed: list = None):
    """The saved JSON of every source in ``d`` and the run records; a file that is not JSON is
    left out (its section reads "not run") and named in ``failed``."""
    data, runs = {}, {}
    for name in SOURCES:
        p = d / f"{name}.json"
        if p.is_file():
            try:
                data[name] = json.loads(p.read_text())
            except ValueError as exc:
                runs[name] = {"ok": False, "reason": f"{p.name} is not JSON ({exc})"}
                if failed is not None:
                    failed.append(f"source {name}: {p} is not JSON ({exc})")
    runs_p = d / "runs.json"
    try:
        saved = json.loads(runs_p.read_text()) if runs_p.is_file() else {}
    except ValueError:
        saved = {}
    return data, {**saved, **runs}


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
    ap.add_argument("--timeout", type=float, default=None,
                    help="seconds per source (default 900, 3600 for the slow sources)")
    a = ap.parse_args(argv)
    failed: list[str] = []
    if a.from_dir is not None:
        if not a.from_dir.is_dir():
            print(f"report: --from {a.from_dir}: not a directory", file=sys.stderr)
            return 2
        src = a.from_dir
    else:
        a.save_dir.mkdir(parents=True, exist_ok=True)
        runs_p = a.save_dir / "runs.json"
        try:
            runs = json.loads(runs_p.read_text()) if runs_p.is_file() else {}
        except ValueError:
            runs = {}
        for name in a.only or [n for n in SOURCES if a.all or n not in SLOW]:
            timeout = a.timeout if a.timeout is not None else (3600.0 if name in SLOW else 900.0)
            try:
                runs[name] = run_source(name, a.save_dir, timeout)
            except Exception as exc:  # noqa: BLE001 -- one failing source must not stop the others
                runs[name] = {"command": SOURCES[name][2], "ok": False, "reason": f"{type(exc).__name__}: {exc}"}
            if not runs[name]["ok"]:
                print(f"report: {name}: {runs[name]['reason']}", file=sys.stderr)
                failed.append(f"source {name}: {runs[name]['reason']}")
                (a.save_dir / f"{name}.json").unlink(missing_ok=True)
            runs_p.write_text(json.dumps(runs, indent=1))
        src = a.save_dir
    data, runs = load_dir(src, failed)
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(render(data, runs, a.out, a.img_dir, failed))
    print(f"report: wrote {a.out} from {len(data)} of {len(SOURCES)} sources", file=sys.stderr)
    if a.readme != "none":
        if not Path(a.readme).is_file():
            failed.append(f"--readme {a.readme}: no such file")
        elif write_readme_speed(Path(a.readme), data):
            print(f"report: wrote the speed and goals tables of {a.readme}", file=sys.stderr)
        else:
            failed.append(f"--readme {a.readme}: no {SPEED_BEGIN} ... {SPEED_END} markers")
    if failed:
        print("report: FAILED (the page names them; the rest was written):\n  " + "\n  ".join(failed),
              file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
