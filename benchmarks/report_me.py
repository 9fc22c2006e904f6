"""Section "Model Exchange against the event-located reference" of the validation report
(benchmarks/report.py) from the JSON of ``benchmarks/bench_me.py`` (source ``me``)."""
from __future__ import annotations

import math


def _sci(x, digits=2):
    return "n/a" if x is None or not math.isfinite(float(x)) else f"{float(x):.{digits}e}"


def _num(x, digits=3):
    return "n/a" if x is None or not math.isfinite(float(x)) else f"{float(x):.{digits}g}"


def _cs_wall(case):
    return next((r["wall_s"] for r in case["rows"] if r["host"] == "fmpy Co-Simulation"), None)


def default_me_row(case, rtol=1e-8):
    """The Model Exchange row at ``rtol`` with the builder's default node events (None if it failed)."""
    from gearfmu.common.vocabulary import DEFAULT_ME_NODE_EVENTS

    return next((r for r in case["rows"] if r["host"] == "fmpy CVode" and r.get("rtol") == rtol
                 and r.get("node_events") == DEFAULT_ME_NODE_EVENTS and "failed" not in r), None)


def render(pg, table, command):
    """Append the section and its summary row to the report page ``pg``."""
    d = pg.data["me"]
    parts = []
    for case in d["cases"]:
        cs = _cs_wall(case)
        body = []
        for r in case["rows"]:
            body.append([r["host"], r["setting"], r.get("node_events", "-"),
                         "-" if r.get("events") is None else str(r["events"]), _num(r["wall_s"], 3),
                         _num(r["wall_s"] / cs, 3) if cs and "failed" not in r else "n/a",
                         r.get("failed") or _sci(r.get("dte_rel_max_err")),
                         "" if "failed" in r else _sci(r.get("force_rel_max_err"))])
        selfe = case["reference_self_err"]
        parts.append(
            f"### {case['case']} (`{case['hard_case']}`, {_num(case['stop_time_s'] * 1e3, 4)} ms at "
            f"{_num(case['comm_step_s'] * 1e6, 4)} µs)\n\n"
            + table(["host", "setting", "node events", "events", "wall s", "× Co-Simulation",
                     "DTE max err / range", "force max err / range"], body)
            + f"\n\nThe reference itself (128 against 64 steps per natural period): DTE "
            f"{_sci(selfe['dte_rel_max_err'])}, force {_sci(selfe['force_rel_max_err'])}; its cost "
            f"{_num(case['reference_wall_s'], 3)} s.\n")
    pg.parts.append(
        "## Model Exchange against the event-located reference\n\n"
        "The standalone pair FMU as FMI 2 Model Exchange (`gearfmu build --interface me`), integrated by fmpy's "
        "CVode (BDF; absolute tolerance the relative one times the FMU's nominal state values) with the "
        "event indicators of every contact change, for each choice of table-node events "
        "(`--me-node-events`), against the event-located scipy solution of the same equations "
        "(`gearfmu.dynamics.reference`, DOP853 at rtol 1e-11, 128 steps per shortest natural period).  Beside "
        "it, the native solver (rk4_node) and the same model as a Co-Simulation FMU in the same host at the "
        "scene's internal step.  Errors: the largest difference over the communication instants over the "
        "reference's range; wall time: one whole `fmpy.simulate_fmu` call (one run, extraction and loading "
        "included; the Co-Simulation run after a first one).\n\n"
        + "\n".join(parts)
        + f"\nSource: `{command}` ({pg.cost('me')}).\n")
    worst, ratio = 0.0, []
    for case in d["cases"]:
        r = default_me_row(case)
        if r is None:
            continue
        worst = max(worst, r["dte_rel_max_err"], r["force_rel_max_err"])
        cs = _cs_wall(case)
        if cs:
            ratio.append(r["wall_s"] / cs)
    pg.summary.append(["pair FMU as Model Exchange (fmpy CVode, rtol 1e-8, default node events)",
                       "event-located scipy DOP853 of the same equations", f"{_sci(worst)} of range (DTE, force)",
                       (f"{_num(min(ratio), 3)}–{_num(max(ratio), 3)} × the Co-Simulation FMU" if ratio else "n/a")])
