"""The planner's decisions (docs/plan.md): the budget rule, the revisions, the as-written
estimate, and what a build builds.

:func:`plan_scene` estimates what every modelling choice contributes to the DTE and mesh force
over the scene's envelope (:mod:`gearfmu.scene.envelope`), keeps what the accuracy target
needs, drops the rest, verifies the combined choice by a worst-case search of the envelope
(:func:`verify_and_revise`) and measures the cost of the chosen model against the full one.
:func:`estimate_as_written` is the cheap error estimate of a scene built as written.
:func:`resolve` says what ``gearfmu build`` and ``gearfmu validate`` build for a scene: the
planned scene when it asks for a plan, else the scene as written.
"""
from __future__ import annotations

import math
from dataclasses import replace
from typing import Dict, List, Optional, Tuple

from ..dynamics.native import choose_max_step_s
from ..scene.envelope import PLAN_CHOICES, AccuracyTarget, VerifiedEnvelope, accuracy_of, envelope_of
from ..scene.physics import check_build_cost, estimate_build
from .choices import (LEVELS_NOT_COST_ORDERED, PLAN_LEVEL_TABLE_WORK, Choice, PlanError, choices_of, min_slots,
                      reference_is_expensive, scene_has_thermal, skipped_choices, step_absolute, table_work,
                      thermal_options, what_if_contact)
from .confirm import measure_fmus, planned_scene
from .evaluator import Evaluator, cost_entry, h0_of
from .report import Plan, verified_envelope_of
from .verify import ERROR_DEFINITION, MEASURES, ProgressBar, Search, budget_use, limiting_measure, say

__all__ = ["plan_scene", "estimate_as_written", "resolve", "verify_and_revise", "cheapest_fit", "DEFAULT_BUDGET_RUNS",
           "ESTIMATE_BUDGET_RUNS"]

DEFAULT_BUDGET_RUNS = 2000  # native runs the envelope search and its revisions may take (CHOICE, docs/plan.md)
#: a level whose budget use alone is at most this share of the safety factor meets the target with
#: room to spare: the finer levels of that choice are not measured (CHOICE; the greedy rule would never
#: take them, it takes the cheapest level that fits)
_NEGLIGIBLE_USE = 0.02


def _budget_use(m: dict, acc: AccuracyTarget) -> float:
    return budget_use(m, acc.dte_rel, acc.mesh_force_rel)


#: the costs the budget rule ranks by: deterministic counts (docs/plan.md "Cost model"), never wall times
_COST_KEYS = ("table_work", "table_bytes", "work_per_sim_s")


def _est_cost(levels: Dict[str, int], choices: Dict[str, Choice], base: dict) -> float:
    """Relative cost estimate of a configuration: sum over table work, table size and solver
    work per simulated second (:data:`_COST_KEYS`, counts: the plan is a function of the scene,
    not of the machine's load) of the product of the single-choice ratios to the full model
    (each choice taken as acting independently)."""
    total = 0.0
    for k in _COST_KEYS:
        r = 1.0
        for name, i in levels.items():
            m = choices[name].measured.get(i)
            if m is not None and base.get(k):
                r *= m[k] / base[k]
        total += r
    return total


def cheapest_fit(c: Choice, below: int, room: float, acc: AccuracyTarget, cost_at) -> Optional[tuple]:
    """The greedy rule's candidate of choice ``c``: of its measured levels below ``below`` whose
    budget use fits in ``room``, (estimated cost ``cost_at(i)``, level i, budget use) of the
    lowest cost, the lower level on a tie; None when none fits.  Mostly the first level that
    fits, but levels can trade places in cost with the step (``LEVELS_NOT_COST_ORDERED``)."""
    fits = []
    for i in range(below):
        if i in c.measured:
            u = _budget_use(c.measured[i], acc)
            if math.isfinite(u) and u <= room:
                fits.append((cost_at(i), i, u))
    return min(fits) if fits else None


def plan_scene(scene, *, progress: bool = False, measure_fmu: bool = False,
               fmu_dir: Optional[str] = None, fmu_runtime: Optional[str] = None,
               budget_runs: Optional[int] = None, what_if: bool = False) -> Plan:
    """Plan the fidelity of a scene (docs/plan.md).

    1. Levels of every choice (:func:`choices_of`; pinned ones are fixed, choices the envelope
       cannot need have one level and are listed in ``Plan.skipped``).
    2. Each non-full level is measured alone against the full model (all other
       choices full), cheapest first (:func:`_measure_levels`): TVMS, DTE and mesh-force
       relative RMS errors over the envelope points, table build time, table size and
       native time per simulated second.
    3. Greedy rule: starting from the full model, repeatedly take the level
       change that saves the most estimated cost per unit of added budget use
       (budget use of a level = max(DTE error / DTE target, force error / force
       target)) while the summed budget use of all choices stays <= the safety
       factor (by the triangle inequality the combined error is about at most
       the sum of the single-choice errors).
    4. Verification: the combined chosen model is searched over the envelope against the
       full one and revised while a point is above the target (:func:`verify_and_revise`).
    5. Costs of the chosen and the full model: table build time, table size and
       time per simulated second, and with ``measure_fmu`` both FMUs built (in
       ``fmu_dir`` or a temporary directory; ``fmu_runtime``: "pythonfmu" or
       "standalone", None = the scene's) and driven through the verification
       cases (:func:`gearfmu.plan.confirm.verify_fmus`, stored in ``Plan.fmu_verification``).
    """
    budget_runs = DEFAULT_BUDGET_RUNS if budget_runs is None else int(budget_runs)
    if budget_runs < 1:
        raise PlanError(f"budget_runs: must be a positive number of native runs, got {budget_runs}")
    env, acc = envelope_of(scene), accuracy_of(scene)
    if env.temperature_range_C is not None:
        thermal_options(scene, env)  # the scene's temperature axis must cover the envelope (PlanError)
    log: List[str] = []
    choices = choices_of(scene, env, acc)
    for name in PLAN_CHOICES:
        if name not in choices:
            raise PlanError(f"{name}: no levels (planner bug)")  # pragma: no cover
    ev = Evaluator(scene, env, acc, progress)
    return _plan(scene, env, acc, choices, ev, log, progress=progress, measure_fmu=measure_fmu, fmu_dir=fmu_dir,
                 fmu_runtime=fmu_runtime, budget_runs=budget_runs, what_if=what_if)


def _measure_levels(ev: Evaluator, choices: Dict[str, Choice], full: dict, acc: AccuracyTarget, base: dict,
                    progress: bool, log: List[str], work_budget: float = math.inf) -> None:
    """Step 2 of the budget rule: every non-full level measured alone against the full model,
    cheapest first.  A choice stops at the first level whose budget use is negligible
    (:data:`_NEGLIGIBLE_USE`; not the choices of ``LEVELS_NOT_COST_ORDERED``); a level whose tables are still to be built and would take the
    table work of the levels (:func:`gearfmu.plan.choices.table_work`) above ``work_budget``
    is not measured.  Both are recorded in ``Choice.skipped_levels``."""
    for c in choices.values():
        c.measured[len(c.levels) - 1] = dict(base)
    total = sum(len(c.levels) - 1 for c in choices.values())
    work = 0.0
    with ProgressBar(progress, total, "levels") as bar:
        for name, c in choices.items():
            n = len(c.levels) - 1
            for i, lv in enumerate(c.levels[:-1]):
                cfg = dict(full, **{name: lv})
                if not ev.tables_ready(cfg):
                    if work + table_work(cfg) > work_budget:
                        c.skipped_levels[i] = (
                            f"not measured: plan-time table budget (the full-fidelity {cfg['contact_model']} tables "
                            f"are expensive; the levels may build {PLAN_LEVEL_TABLE_WORK:g} x their table work)")
                        say(progress, f"{name} = {lv}: {c.skipped_levels[i]}", log)
                        bar.update(note=f"{name} = {lv}")
                        continue
                    work += table_work(cfg)
                try:
                    c.measured[i] = ev.measure(cfg, full)
                except (ValueError, ArithmeticError) as exc:  # a level the physics rejects is not offered
                    c.measured[i] = dict({k: math.inf for k in MEASURES}, tvms_rel=math.inf, table_build_s=math.nan,
                                         table_work=math.nan, table_bytes=0, wall_per_sim_s=math.nan,
                                         work_per_sim_s=math.nan, error=str(exc))
                m = c.measured[i]
                bar.update(note=f"{name} = {lv}")
                u = _budget_use(m, acc)
                say(progress, f"{name} = {lv}: TVMS {m['tvms_rel']:.2e}, DTE {m['dte_rel']:.2e}, "
                              f"force {m['mesh_force_rel']:.2e}; budget use {u:.3g} "
                              f"({limiting_measure(m, acc.dte_rel, acc.mesh_force_rel)})", log)
                if u <= _NEGLIGIBLE_USE * acc.safety_factor and i < n - 1 and name not in LEVELS_NOT_COST_ORDERED:
                    why = (f"not measured: the cheaper level {lv} already has a negligible budget use "
                           f"({u:.2g} <= {_NEGLIGIBLE_USE:g} x safety factor)")
                    for j in range(i + 1, n):
                        c.skipped_levels[j] = why
                    bar.update(n - 1 - i)
                    break


def _plan(scene, env, acc: AccuracyTarget, choices: Dict[str, Choice], ev: Evaluator, log: List[str], *,
          progress: bool, measure_fmu: bool, fmu_dir, fmu_runtime, budget_runs: int, what_if: bool) -> Plan:
    """:func:`plan_scene` after its input checks (``ev``: its evaluator)."""
    full = {n: c.full for n, c in choices.items()}
    tb_full, _ = ev.tables(full, progress=progress)
    ev.h0 = h0_of(ev, full, env)
    npts = len(ev.points())
    say(progress, f"{npts} envelope points, full tables {tb_full.slots} slots x {tb_full.n_phi} angles x "
                  f"{tb_full.n_torque} torques, h0 = {ev.h0:.3g} s", log)
    base = ev.measure(full, full)
    budget = PLAN_LEVEL_TABLE_WORK * table_work(full) if reference_is_expensive(scene, full) else math.inf
    _measure_levels(ev, choices, full, acc, base, progress, log, budget)

    what_if_rows = what_if_contact(scene)
    for r in what_if_rows:
        if r["skipped"] is None and not what_if:
            r["skipped"] = (f"not measured: the scene asks for {scene.mesh.contact_model} "
                            f"(plan_scene(..., what_if=True) measures it; film tables take minutes)")
        if r["skipped"] is None:
            try:
                m = ev.measure(dict(full, contact_model=r["contact_model"]), full)
                r.update({k: m[k] for k in ("tvms_rel", "dte_rel", "mesh_force_rel", "table_build_s")})
            except (ValueError, ArithmeticError) as exc:
                r["skipped"] = f"tables failed: {exc}"
        say(progress, f"what-if contact_model = {r['contact_model']}: " +
            (f"skipped ({r['skipped']})" if r["skipped"] else
             f"TVMS {r['tvms_rel']:.2e}, DTE {r['dte_rel']:.2e}, force {r['mesh_force_rel']:.2e}"), log)
    what_if = what_if_rows

    # ---------------------------------------------------------- greedy
    level = {n: len(c.levels) - 1 for n, c in choices.items()}
    use = {n: 0.0 for n in choices}

    def cost_of(lv):
        return _est_cost(lv, choices, base)

    history: List[str] = []
    while True:
        best = None
        cur_cost, total = cost_of(level), sum(use.values())
        for name, c in choices.items():
            fit = cheapest_fit(c, level[name], acc.safety_factor - (total - use[name]), acc,
                                lambda i: cost_of(dict(level, **{name: i})))
            if fit is None:
                continue
            new_cost, i, u = fit
            saved = max(cur_cost - new_cost, 0.0)  # estimated saving
            score = (saved + 1e-6) / max(u - use[name], 1e-6)
            if best is None or score > best[0]:
                best = (score, name, i, u)
        if best is None:
            break
        _, name, i, u = best
        level[name], use[name] = i, u
        history.append(name)
        say(progress, f"take {name} = {choices[name].levels[i]} (budget use {u:.3f}, "
                       f"total {sum(use.values()):.3f})", log)

    # ---------------------------------------------------------- verification
    chosen, ver = verify_and_revise(ev, choices, level, full, acc, budget_runs,
                                     lambda msg: say(progress, msg, log), progress)
    ver["tvms_rel"] = ev.tvms_error(chosen, full)
    ver["points"] = ver["probes"]

    # ---------------------------------------------------------- costs
    cost = {"full": cost_entry(ev, full), "chosen": cost_entry(ev, chosen)}
    plan = Plan(scene_name=scene.name, envelope=env, target=acc, choices=choices, full=full, chosen=chosen,
                h0_s=ev.h0, step_absolute=step_absolute(scene, acc), verification=ver, cost=cost, log=log,
                what_if=what_if, skipped=skipped_choices(choices, what_if))
    plan.verified_envelope = verified_envelope_of(plan, kind="plan verification")

    plan.estimate = {"scene": estimate_build(scene).to_dict(),
                     **{w: estimate_build(planned_scene(scene, plan, w)).to_dict() for w in ("chosen", "full")}}
    if measure_fmu:
        measure_fmus(scene, plan, fmu_dir, progress, fmu_runtime)
        plan.verified_envelope = verified_envelope_of(plan, kind="plan verification")
    g = {}
    for k in ("table_build_s", "table_bytes", "wall_per_sim_s", "fmu_bytes"):
        a, b = cost["full"].get(k), cost["chosen"].get(k)
        if a and b:
            g[k] = a / b
    cost["gain_full_over_chosen"] = g
    return plan


def verify_and_revise(ev: Evaluator, choices: Dict[str, Choice], level: Dict[str, int], full: dict,
                       acc: AccuracyTarget, budget_runs: int, say, progress: bool = False) -> Tuple[dict, dict]:
    """Verify the combined configuration of ``level`` over the envelope
    (:class:`gearfmu.plan.verify.Search`); while the worst point found is above the
    target, find the responsible choice (each reduced choice restored to full alone at
    that point: the one whose restoration lowers the error most), raise it to its
    cheapest level that brings that point within ``safety_factor`` x target (else to
    full) and verify again.  Stops when a search passes, or refuses when the budget of
    native runs is spent.  Returns (chosen configuration, verification dict); a refused
    plan's chosen configuration is the best one reached."""
    def cfg_of(lv):
        return {n: choices[n].levels[i] for n, i in lv.items()}

    search = Search(ev, full, say=say, progress=progress)
    start = ev.native_runs
    attempts: List[dict] = []
    best = None
    refused = None
    while True:
        chosen = cfg_of(level)
        res = search.verify(chosen, budget_runs - (ev.native_runs - start), margin=acc.safety_factor)
        w = res["worst"]
        att = {"chosen": dict(chosen), "worst": {k: v for k, v in w.items()},
               "within_target": res["within_target"], "native_runs": res["native_runs"],
               "probes": len(res["probes"])}
        attempts.append(att)
        say(f"verify ({len(res['probes'])} probes, {res['native_runs']} native runs): worst {w['probe']}: "
            f"DTE {w['dte_rel']:.2e}, force {w['mesh_force_rel']:.2e}, budget use {w['u']:.3g} limited by "
            f"{w['limit']} {w[w['limit']]:.3g} ({'within' if res['within_target'] else 'ABOVE'} target)")
        if not res["exhausted"] and (best is None or w["u"] < best[0]["worst"]["u"]):
            best = (att, res)
        if res["within_target"]:
            break
        if res["exhausted"]:
            refused = (f"the budget of {budget_runs} native runs was spent before a configuration passed the "
                       f"envelope search")
            break
        reduced = [n for n in choices if level[n] < len(choices[n].levels) - 1]
        if not reduced:  # pragma: no cover - the full model against itself has no error
            refused = "the full-fidelity configuration itself fails the search (planner bug)"
            break
        probe = res["worst_probe"]
        trial = {n: search.evaluate(dict(chosen, **{n: full[n]}), probe)["u"] for n in reduced}
        resp = min(trial, key=lambda n: trial[n])
        say("at the worst point, each choice restored to full alone: " +
            ", ".join(f"{n} -> u {trial[n]:.2f}" for n in reduced) + f"; refining {resp}")
        new = len(choices[resp].levels) - 1
        for i in range(level[resp] + 1, len(choices[resp].levels) - 1):
            if search.evaluate(dict(chosen, **{resp: choices[resp].levels[i]}), probe)["u"] <= acc.safety_factor:
                new = i
                break
        level[resp] = new
        say(f"revise: {resp} = {choices[resp].levels[new]}")
    att, res = best if (refused and best is not None) else (attempts[-1], res)
    w = att["worst"]
    ver = dict({k: w[k] for k in MEASURES}, dte_max_rel=w["dte_max_rel"], mesh_force_max_rel=w["mesh_force_max_rel"],
               u=w["u"], limit=w["limit"], worst=w["probe"], worst_at=w["where"],
               within_target=bool(att["within_target"]) and refused is None, refused=refused,
               native_runs=ev.native_runs - start, budget_runs=budget_runs, probes=att["probes"],
               attempts=attempts, error_definition=ERROR_DEFINITION,
               margin=acc.safety_factor, worst_by_measure=res["worst_by_measure"],
               searched_speed_range_rpm=[x * 30 / math.pi for x in search.speed_range_rad_s()],
               probe_errors=[{k: p[k] for k in ("probe", "u", "limit", *MEASURES, "dte_max_rel", "mesh_force_max_rel")}
                             for p in res["probes"]])
    return dict(att["chosen"]), ver


ESTIMATE_BUDGET_RUNS = 80      # native runs of the as-written estimate of `gearfmu build` (CHOICE)
_ESTIMATE_RUN_MESH_PERIODS = 20  # its run length in mesh periods (CHOICE: a cheap estimate)


def estimate_as_written(scene, *, progress: bool = False, budget_runs: int = ESTIMATE_BUDGET_RUNS) -> dict:
    """Cheap estimate of the error of a scene AS WRITTEN against its full-fidelity model
    (the planner's full levels, the scene's own contact model) over the scene's envelope:
    one envelope search (:class:`gearfmu.plan.verify.Search`) with runs of
    ``_ESTIMATE_RUN_MESH_PERIODS`` mesh periods and at most ``budget_runs`` native runs.
    Returns :class:`gearfmu.scene.envelope.VerifiedEnvelope` as a dict with kind
    "as-written estimate" and the default (or the scene's) target."""
    env = envelope_of(scene)
    acc = replace(accuracy_of(scene), pin=(), run_mesh_periods=min(accuracy_of(scene).run_mesh_periods,
                                                                      _ESTIMATE_RUN_MESH_PERIODS))
    log: List[str] = []
    choices = choices_of(scene, env, acc)
    full = {n: c.full for n, c in choices.items()}
    ev = Evaluator(scene, env, acc, progress)
    ev.h0 = h0_of(ev, full, env)
    written = {"contact_model": scene.mesh.contact_model, "thermal": scene_has_thermal(scene),
               "tooth_specific_errors": True, "slices": int(scene.mesh.slices),
               "points_per_mesh": int(scene.tables.points_per_mesh),
               "torque_points": int(scene.tables.torque_points) if full["torque_points"] > 1 else 1,
               "slots": int(scene.tables.slots or min_slots(scene)), "integrator": scene.solver.integrator}
    if scene.solver.max_step_s is not None:
        step_s = float(scene.solver.max_step_s)
    else:
        tb, _ = ev.tables(dict(written, max_step=1.0))
        w_top = max(env.speed_range_rad_s[1], env.nominal_speed_rad_s)
        step_s = (min(choose_max_step_s(tb.at_temperature(float(t)), w_top) for t in tb.temperature_C)
                  if tb.has_temperature_axis else choose_max_step_s(tb, w_top))
    written["max_step"] = step_s / ev.h0
    say(progress, f"as-written estimate: the scene as written against its full-fidelity model "
                   f"(budget {budget_runs} native runs of {acc.run_mesh_periods} mesh periods)", log)
    res = Search(ev, full, say=lambda m: say(progress, m, log), progress=progress).verify(written, budget_runs)
    w = res["worst"]
    ve = VerifiedEnvelope(
        kind="as-written estimate", torque_range_Nm=tuple(env.torque_range_Nm),
        speed_range_rpm=tuple(x * 30 / math.pi for x in env.speed_range_rad_s),
        temperature_range_C=None if env.temperature_range_C is None else tuple(env.temperature_range_C),
        dte_target_rel=acc.dte_rel, mesh_force_target_rel=acc.mesh_force_rel, error_definition=ERROR_DEFINITION,
        within_target=bool(w["u"] <= 1.0),
        worst_dte_rel=float(w["dte_rel"]), worst_mesh_force_rel=float(w["mesh_force_rel"]),
        worst_dte_max_rel=float(w["dte_max_rel"]), worst_mesh_force_max_rel=float(w["mesh_force_max_rel"]),
        worst_at=dict(w["where"]), native_runs=int(res["native_runs"]), probes=len(res["probes"]))
    d = ve.to_dict()
    d["search_complete"] = not res["exhausted"]
    d["worst_measures"] = {k: w[k] for k in MEASURES}
    d["limit"] = w["limit"]
    d["full_fidelity"] = dict(full, max_step_s=full["max_step"] * ev.h0)
    d["as_written"] = dict(written, max_step_s=step_s)
    return d



def resolve(scene, *, progress: bool = False, estimate_accuracy: bool = False,
            allow_large: bool = False) -> Tuple[object, Optional[Plan], Optional[dict]]:
    """(the scene to build, its plan or None, its verified envelope or None): what ``gearfmu build``
    builds for a scene and ``gearfmu validate`` checks (docs/plan.md).

    An oversized scene is refused first (:func:`gearfmu.scene.physics.check_build_cost`,
    ``BuildTooLargeError``, unless ``allow_large``).  A scene with ``[accuracy]`` is built as its
    fidelity plan says (:func:`plan_scene`; :func:`planned_scene`, the plan's verified envelope);
    a plan that is not within its target is refused with :class:`PlanError`.  Without it, the
    scene is built as written, and ``estimate_accuracy`` adds the cheap estimate of its error
    against the full-fidelity model over the envelope (:func:`estimate_as_written`; an estimate
    that fails never stops a build: it says why it is missing)."""
    check_build_cost(scene, allow_large=allow_large)
    if scene.accuracy is not None:
        plan = plan_scene(scene, progress=progress)
        if not plan.within_target:
            v = plan.verification
            raise PlanError(f"accuracy: the fidelity plan of scene {scene.name!r} is not within its target over "
                            f"the envelope ({v.get('refused') or 'worst: ' + str(v.get('worst'))}); "
                            f"see `gearfmu plan`")
        return planned_scene(scene, plan), plan, plan.verified_envelope
    if not estimate_accuracy:
        return scene, None, None
    try:
        verified = estimate_as_written(scene, progress=progress)
    except (ValueError, ArithmeticError) as exc:  # the estimate never stops a build; it says why it is missing
        verified = {"kind": "as-written estimate", "error": f"{type(exc).__name__}: {exc}"}
    return scene, None, verified
