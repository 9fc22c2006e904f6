"""The planner's result and its report: :class:`Plan` (JSON with :meth:`Plan.to_dict`),
:func:`format_report` (the text table of ``gearfmu plan``) and :func:`verified_envelope_of`
(the verified-envelope record an FMU carries)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Dict, List

import numpy as np

from .choices import Choice
from .verify import ERROR_DEFINITION, MEASURE_LABELS, MEASURES, budget_use, limiting_measure, target_of
from ..scene.envelope import AccuracyTarget, Envelope, VerifiedEnvelope
from ..assembly.estimate import BuildEstimate

# ============================================================== the plan
@dataclass
class Plan:
    """Result of :func:`plan_scene`: the chosen and the full configuration, the
    per-choice measurements, the verification of the chosen model and the costs.
    :meth:`to_dict` is the JSON report (``gearfmu plan --json``)."""

    scene_name: str
    envelope: Envelope
    target: AccuracyTarget
    choices: Dict[str, Choice]
    full: dict
    chosen: dict
    h0_s: float
    step_absolute: bool
    verification: dict
    cost: dict
    log: List[str] = field(default_factory=list)
    fmu_verification: dict = field(default_factory=dict)  # verify_fmus() when measured (plan --fmu)
    what_if: List[dict] = field(default_factory=list)  # other contact models: measured or skipped, never "full"
    verified_envelope: dict = field(default_factory=dict)  # gearfmu.scene.envelope.VerifiedEnvelope.to_dict()
    skipped: List[dict] = field(default_factory=list)  # gearfmu.plan.choices.skipped_choices: not measured, and why

    @property
    def within_target(self) -> bool:
        """True only when the envelope search passed and, when it ran, the FMU confirmation too."""
        fv = self.fmu_verification or {}
        return bool(self.verification.get("within_target")) and (not fv.get("cases") or
                                                                 bool(fv.get("within_target")))
    estimate: dict = field(default_factory=dict)  # gearfmu.assembly.estimate of the scene as written / chosen / full

    def max_step_s(self, which: str = "chosen") -> float:
        """Largest internal step (s) of the chosen or the full configuration."""
        cfg = self.chosen if which == "chosen" else self.full
        v = float(cfg["max_step"])
        return v if self.step_absolute else v * self.h0_s

    def status(self, name: str) -> str:
        ch = self.choices[name]
        if ch.pinned:
            return "pinned"
        if ch.fixed:
            return "fixed"
        v, full = self.chosen[name], ch.full
        if v == full:
            return "kept"
        if v is False or (name == "torque_points" and v == 1) or (name == "contact_model" and v == "hertz"):
            return "dropped"
        return "reduced"

    def to_dict(self) -> dict:
        def jv(v):
            if isinstance(v, float) and not math.isfinite(v):
                return None if math.isnan(v) else ("inf" if v > 0 else "-inf")
            return v

        rows = []
        acc = self.target
        for name, ch in self.choices.items():
            idx = ch.levels.index(self.chosen[name])
            m = ch.measured.get(idx, {})
            contrib = {k: m.get(k, 0.0) for k in ("tvms_rel",) + MEASURES}
            rows.append({
                "choice": name, "status": self.status(name), "full": ch.full, "chosen": self.chosen[name],
                "levels": ch.levels, "note": ch.note,
                "contribution": dict({k: jv(v) for k, v in contrib.items()},
                                     budget_use=jv(budget_use(contrib, acc.dte_rel, acc.mesh_force_rel)),
                                     limit=limiting_measure(contrib, acc.dte_rel, acc.mesh_force_rel)),
                "measured": [{"level": ch.levels[i], **{k: jv(v) for k, v in mm.items()}}
                             for i, mm in sorted(ch.measured.items())],
            })
        env = self.envelope
        return {
            "scene": self.scene_name,
            "envelope": {"torque_range_Nm": list(env.torque_range_Nm),
                         "speed_range_rpm": [w * 60 / (2 * math.pi) for w in env.speed_range_rad_s],
                         "temperature_range_C": list(env.temperature_range_C) if env.temperature_range_C else None,
                         "duty_cycle": env.duty_cycle.source if env.duty_cycle is not None else None},
            "target": {"dte_rel": self.target.dte_rel, "mesh_force_rel": self.target.mesh_force_rel,
                       "safety_factor": self.target.safety_factor, "pin": list(self.target.pin),
                       "measures": {k: target_of(k, acc.dte_rel, acc.mesh_force_rel) for k in MEASURES}},
            "h0_s": self.h0_s,
            "choices": rows,
            "chosen": dict(self.chosen, max_step_s=self.max_step_s("chosen")),
            "full": dict(self.full, max_step_s=self.max_step_s("full")),
            "verification": _json_clean(self.verification),
            "within_target": self.within_target,
            "verified_envelope": _json_clean(self.verified_envelope),
            "what_if": _json_clean(self.what_if),
            "skipped": _json_clean(self.skipped),
            "cost": self.cost,
            "fmu_verification": _json_clean(self.fmu_verification),
            "estimate": self.estimate,
            "log": self.log,
        }


def _json_clean(v):
    """JSON-ready copy: non-finite floats as None / "inf" / "-inf", numpy scalars as Python numbers."""
    if isinstance(v, dict):
        return {k: _json_clean(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_json_clean(x) for x in v]
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None if math.isnan(v) else ("inf" if v > 0 else "-inf")
    return v


def verified_envelope_of(plan, kind: str) -> dict:
    """The verified envelope of a plan as plain data (:class:`gearfmu.scene.envelope.VerifiedEnvelope`
    as a dict) for an FMU's validation record and model description."""
    v, env, acc = plan.verification, plan.envelope, plan.target
    fv = plan.fmu_verification or {}
    ve = VerifiedEnvelope(
        kind=kind, torque_range_Nm=tuple(env.torque_range_Nm),
        speed_range_rpm=tuple(w * 30 / math.pi for w in env.speed_range_rad_s),
        temperature_range_C=None if env.temperature_range_C is None else tuple(env.temperature_range_C),
        dte_target_rel=acc.dte_rel, mesh_force_target_rel=acc.mesh_force_rel, error_definition=ERROR_DEFINITION,
        within_target=bool(v.get("within_target")),
        worst_dte_rel=float(v["dte_rel"]), worst_mesh_force_rel=float(v["mesh_force_rel"]),
        worst_dte_max_rel=float(v.get("dte_max_rel", math.nan)),
        worst_mesh_force_max_rel=float(v.get("mesh_force_max_rel", math.nan)),
        worst_at=dict(v.get("worst_at") or {}), native_runs=int(v.get("native_runs", 0)),
        probes=int(v.get("probes", 0)),
        fmu_confirmed=None if not fv.get("cases") else bool(fv.get("within_target")))
    return ve.to_dict()



# ============================================================== report
def _fmt(v) -> str:
    if isinstance(v, float):
        if not math.isfinite(v):
            return str(v)
        return f"{v:.3g}"
    return str(v)


def _table(head, rows, widths) -> List[str]:
    """A text table: the first column left-aligned, the others right-aligned; every column at
    least its width in ``widths`` and at least two spaces wider than its longest entry (a
    long value such as ``fractal_mixed`` never runs into its neighbour)."""
    w = [max(wd, *(len(str(r[i])) + 2 for r in (head, *rows))) for i, wd in enumerate(widths)]
    return ["".join(f"{str(v):<{w[i]}}" if i == 0 else f"{str(v):>{w[i]}}" for i, v in enumerate(r))
            for r in (head, *rows)]


def format_report(plan: Plan) -> str:
    """The fidelity report as a text table."""
    d = plan.to_dict()
    t = d["target"]
    v = d["verification"]
    sr = v.get("searched_speed_range_rpm")
    er = d['envelope']['speed_range_rpm']
    lines = [f"fidelity plan for scene {d['scene']}: target DTE {t['dte_rel']:g}, mesh force "
             f"{t['mesh_force_rel']:g} (every measure of docs/plan.md 'Error measure' against the full model: "
             f"RMS, DTE peak-to-peak and mean, mesh orders 1-3 of DTE and force; safety {t['safety_factor']:g})",
             f"envelope: torque {d['envelope']['torque_range_Nm']} N*m, speed "
             f"[{er[0]:.6g}, {er[1]:.6g}] rpm, temperature {d['envelope']['temperature_range_C']} degC; "
             f"{v['points']} search probes" +
             (f" over [{sr[0]:.6g}, {sr[1]:.6g}] rpm (a one-speed envelope: the band its FMU accepts "
              f"without a warning)" if sr and er[1] <= er[0] else ""), ""]
    rows = []
    for r in d["choices"]:
        c = r["contribution"]
        full, chosen = r["full"], r["chosen"]
        if r["choice"] == "max_step":
            full, chosen = f"{d['full']['max_step_s']:.2g}s", f"{d['chosen']['max_step_s']:.2g}s"
        reduced = r["status"] in ("reduced", "dropped")
        rows.append((r["choice"], _fmt(full), _fmt(chosen), r["status"], _fmt(c["tvms_rel"]), _fmt(c["dte_rel"]),
                     _fmt(c["mesh_force_rel"]), _fmt(c["budget_use"]) if reduced else "",
                     MEASURE_LABELS[c["limit"]] if reduced else ""))
    lines += _table(("choice", "full", "chosen", "status", "TVMS", "DTE", "force", "use", "limited by"), rows,
                    (22, 12, 12, 9, 10, 10, 10, 10, 12))
    for r in d.get("what_if") or []:
        lines.append(f"{'what-if contact_model':<22}{r['contact_model']:>12}  " +
                     (f"skipped: {r['skipped']}" if r.get("skipped") else
                      f"TVMS {_fmt(r['tvms_rel'])}, DTE {_fmt(r['dte_rel'])}, force {_fmt(r['mesh_force_rel'])}"))
    if any(r["choice"] != "contact_model" for r in d["skipped"]):
        lines += ["", "skipped (not measured; the scene and its envelope cannot need them, or the plan-time budget):"]
        lines += [f"  {r['choice']}" + (f" {', '.join(_fmt(x) for x in r['levels'])}" if r["levels"] else "") +
                  f": {r['reason']}" for r in d["skipped"] if r["choice"] != "contact_model"]
    lines += _measure_table(d)
    wa = v.get("worst_at") or {}
    lines += ["", f"envelope search of the combined chosen model against the full one ({v.get('probes')} probes, "
                  f"{v.get('native_runs')} native runs of a budget of {v.get('budget_runs')}, "
                  f"{len(v.get('attempts') or [])} configuration(s) tried):",
              f"  worst: {v.get('worst')}: DTE {_fmt(v['dte_rel'])} (max/range {_fmt(v.get('dte_max_rel'))}), "
              f"mesh force {_fmt(v['mesh_force_rel'])} (max/range {_fmt(v.get('mesh_force_max_rel'))})"
              + (f" at t {_fmt(wa['time_s'][0])}..{_fmt(wa['time_s'][1])} s, {_fmt(wa.get('speed_rpm'))} rpm"
                 if wa.get("time_s") else ""),
              f"  budget use {_fmt(v.get('u'))} (largest measure / its target), limited by "
              f"{MEASURE_LABELS.get(v.get('limit'), v.get('limit'))}; TVMS {_fmt(v.get('tvms_rel'))}"]
    fv0 = d.get("fmu_verification") or {}
    fmu_bad = bool(fv0.get("cases")) and not fv0.get("within_target")
    lim = v.get("limit")
    worst_lim = (f"{MEASURE_LABELS.get(lim, lim)} {_fmt(v.get(lim))} against {_fmt(t['safety_factor'])} x target "
                 f"{_fmt(t['measures'][lim])} at {v.get('worst')}") if lim in MEASURE_LABELS else ""
    if d["within_target"]:
        lines.append(f"  -> within target over the envelope: every measure <= {t['safety_factor']:g} x its target "
                     f"(largest share: {worst_lim})" +
                     (" (FMU confirmation within target too)" if fv0.get("cases") else ""))
    elif v.get("refused"):
        lines.append(f"  -> NOT within target: plan refused ({v['refused']}); shown: the best configuration "
                     f"reached, failing on {worst_lim}")
    elif fmu_bad:
        bad = [f"{n}: {', '.join(MEASURE_LABELS[k] for k in c.get('above', []))}"
               for n, c in fv0["cases"].items() if not c.get("within_target")]
        lines.append("  -> NOT within target: the FMU confirmation has a case ABOVE the target (" + "; ".join(bad)
                     + "; table below)")
    else:
        lines.append(f"  -> NOT within target: {worst_lim}")
    lines.append("")
    lines.append(f"{'cost':<26}{'full':>14}{'chosen':>14}{'full/chosen':>13}")
    cf, cc, g = d["cost"]["full"], d["cost"]["chosen"], d["cost"]["gain_full_over_chosen"]
    for k, label in (("table_build_s", "table build time (s)"), ("table_bytes", "table size (bytes)"),
                     ("fmu_bytes", "FMU size (bytes)"), ("wall_per_sim_s", "s per simulated s")):
        if k in cf and k in cc:
            lines.append(f"{label:<26}{_fmt(cf[k]):>14}{_fmt(cc[k]):>14}{_fmt(g.get(k, math.nan)):>13}")
    if d.get("estimate"):  # gearfmu.assembly.estimate (the model behind the build guard)

        lines += ["", "estimate before computing (gearfmu.assembly.estimate):"]
        lines += [f"  {w:<7}{BuildEstimate(**e).summary()}" for w, e in d["estimate"].items()]
    fv = d.get("fmu_verification") or {}
    if fv.get("cases"):
        ff, fc = fv["fmus"]["full"], fv["fmus"]["chosen"]
        lines += ["", "planned FMU against the full FMU (fmpy; relative RMS error, budget use = largest measure / "
                      "its target, the measure; CPU s per simulated s):",
                  f"  FMU size {ff['fmu_bytes']} -> {fc['fmu_bytes']} bytes, table build "
                  f"{_fmt(ff['table_build_s'])} -> {_fmt(fc['table_build_s'])} s, temperature input "
                  f"{next(iter(fv['cases'].values()))['temperature_input']['full']} -> "
                  f"{next(iter(fv['cases'].values()))['temperature_input']['chosen']}",
                  *(f"  {w} FMU {fv['fmus'][w]['fmu_path']}: {fv['fmus'][w]['contents']}"
                    for w in ("full", "chosen") if fv["fmus"][w].get("contents")),
                  f"  {'case':<12}{'DTE':>10}{'force':>10}{'use':>7}{'limited by':>11}{'target':>8}{'full':>11}"
                  f"{'chosen':>11}{'gain':>7}  drive"]
        for name, c in fv["cases"].items():
            cps = c["cpu_per_sim_s"]
            lines.append(f"  {name:<12}{_fmt(c['dte_rel']):>10}{_fmt(c['mesh_force_rel']):>10}"
                         f"{_fmt(c.get('u')):>7}{MEASURE_LABELS.get(c.get('limit'), '-'):>11}"
                         f"{'ok' if c['within_target'] else 'ABOVE':>8}{_fmt(cps['full']):>11}{_fmt(cps['chosen']):>11}"
                         f"{_fmt(c['cpu_gain_full_over_chosen']):>7}  {c['note']}")
    return "\n".join(lines)


def _measure_table(d: dict) -> List[str]:
    """Every error measure (docs/plan.md 'Error measure') of each reduced choice's chosen level alone
    against the full model, the worst of each over the envelope search and its target."""
    keys = MEASURES
    w = 10
    head = f"  {'':<22}" + "".join(f"{MEASURE_LABELS[k]:>{w}}" for k in keys)
    rows = [f"  {r['choice']:<22}" + "".join(f"{_fmt(r['contribution'].get(k)):>{w}}" for k in keys)
            for r in d["choices"] if r["status"] in ("reduced", "dropped")]
    wb = d["verification"].get("worst_by_measure") or {}
    rows.append(f"  {'search: worst':<22}" + "".join(f"{_fmt((wb.get(k) or {}).get('value')):>{w}}" for k in keys))
    rows.append(f"  {'target':<22}" + "".join(f"{_fmt(d['target']['measures'][k]):>{w}}" for k in keys))
    return ["", "error measures against the full model (each reduced choice alone at the envelope points; the worst "
                "of each over the envelope search; the target):", head] + rows
