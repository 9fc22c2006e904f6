"""Section "Smooth EHL film against Moes' fit" of the validation report (benchmarks/report.py) from
the JSON of ``benchmarks/bench_ehl_moes.py`` (source ``ehl_moes``)."""
from __future__ import annotations

import math


def _f(x, digits=4):
    return "n/a" if x is None or not math.isfinite(float(x)) else f"{float(x):.{digits}g}"


def _p(x, digits=2):
    return "n/a" if x is None or not math.isfinite(float(x)) else f"{100 * float(x):+.{digits}f} %"


def _stat(s):
    return "n/a" if not s or s.get("max") is None else (f"max {100 * s['max']:.2f} %, mean {100 * s['mean']:.2f} % "
                                                       f"({s['n']} points)")


def _grid_part(g, table):
    rows = []
    for r in sorted(g["rows"], key=lambda r: (r["M"], r["L"])):
        rows.append([_f(r["M"], 4), _f(r["L"], 3), r.get("n_intervals", "-"), _f(r.get("H_default"), 5),
                     _f(r.get("H_ref"), 5), _f(r.get("H_reference"), 5), _f(r["fit"], 5),
                     _p(r.get("dev_default_vs_fit")), _p(r.get("dev_fit_vs_ref")), _p(r.get("dev_default_vs_ref")),
                     _p(r.get("dev_reference_vs_solver_same_grid"), 3)])
    return (
        f"{g['points']} points, seed {g['seed']}: M log-uniform on 5..1000, L uniform on 0..20.  "
        "H_ref: the solver on 2x and 4x the default grid (1x and 2x where 4x would exceed 16384 intervals) "
        "at tight tolerances (the default ones where the tight ones stall), Richardson-extrapolated (second "
        "order; n/a where a refined solve stalled); independent: the separate discretisation of "
        "`benchmarks/ehl_reference.py` (piecewise-linear pressure kernel, midpoint ε, dense Newton with an "
        "active set) on the 2x grid where that has at most 2048 intervals (n/a where its Newton did not "
        "converge from the solver's state).\n\n"
        f"* default solve against the fit: {g['within_3pct_default_vs_fit']} of {g['points']} within 3 %, "
        f"{g['within_5pct_default_vs_fit']} within 5 %; {_stat(g['default_vs_fit'])}; failed: {g['failed']}\n"
        f"* **the fit against the converged film H_ref: {_stat(g['fit_vs_ref'])}** (the fit's own accuracy)\n"
        f"* default solve against H_ref: {_stat(g['default_vs_ref'])} (the solver's discretisation error)\n"
        f"* independent discretisation against the solver on the same grid: "
        f"{_stat(g['reference_vs_solver_same_grid'])}; against H_ref: {_stat(g['reference_vs_ref'])}\n\n"
        + table(["M", "L", "default intervals", "H_c default", "H_ref", "H_c independent", "Moes' fit",
                 "default vs fit", "fit vs H_ref", "default vs H_ref", "independent vs solver"], rows) + "\n")


def render(pg, table, source_label):
    """Append the section to ``pg`` (a report Page); ``table`` is the report's table helper."""
    d = pg.data["ehl_moes"]
    parts = ["## Smooth EHL film against Moes' fit\n\n"
             "Moes' (1992) central-film fit (as quoted by Venner & Lubrecht 2000) is a curve fit through "
             "numerical solutions; how close it is to converged solutions of the equations decides what a "
             "comparison with it can show.  References of the fit's own accuracy: Martin's (1916) closed form of "
             "the rigid-isoviscous limit, an independent discretisation of the same equations, and the solver's "
             "own grid convergence.  Barus viscosity, incompressible lubricant (the fit's assumptions); "
             "docs/ehl.md \"Validation\".\n"]
    r = d.get("rigid")
    if r:
        rows = [[_f(q["M"], 3), _f(q.get("x_in_b"), 4), _f(q.get("xi_in"), 4), _f(q.get("HM_solver"), 5),
                 _f(q.get("HM_martin"), 5), _p(q.get("dev_solver_vs_martin")), _f(q.get("HM_fit"), 5),
                 _p(q.get("dev_fit_vs_martin_flooded"))] for q in r["rows"]]
        parts.append(
            "### Rigid-isoviscous limit (L = 0, M -> 0)\n\n"
            "Reference: Martin (1916), rigid cylinder, isoviscous, Reynolds outlet condition, in closed form "
            f"(`gearfmu.ehl.fits.martin_rigid_isoviscous`): H_c M = c/2, c = h0 w/(η0 u_m R) = "
            f"{r['martin_c_flooded']:.4f} fully flooded (the classical h_min/R = 4.9 U/W), "
            f"{r['martin_c_at_xi_in']:.4f} with the inlet at ξ = {r['xi_in']:g} (units of √(2 R h0)).  "
            "The solver with that inlet (in the film found), 4096 intervals; Moes' fit has 3/M as its "
            "rigid-isoviscous asymptote.\n\n"
            + table(["M", "inlet x/b", "inlet ξ", "H_c M solver", "H_c M Martin", "solver vs Martin",
                     "H_c M Moes' fit", "fit vs Martin (flooded)"], rows) + "\n")
    e = d.get("isoviscous_elastic")
    if e:
        rows = [[_f(q["M"], 4), *(_f(h, 6) for h in q.get("H", [None, None])), _f(q.get("H_ref"), 6),
                 _f(q.get("coefficient"), 4), _f(q.get("fit_coefficient"), 4), _p(q.get("dev_fit_vs_ref"))]
                for q in e["rows"]]
        parts.append(
            "### Isoviscous-elastic regime (L = 0, high M)\n\n"
            "The solver on 8192 and 16384 intervals, Richardson value H_ref, and H_ref M^(1/5) against the "
            f"fit's asymptote {e['moes_asymptote_coefficient']} M^(-1/5).\n\n"
            + table(["M", "H_c 8192", "H_c 16384", "H_ref", "H_ref M^(1/5)", "fit M^(1/5)", "fit vs H_ref"], rows)
            + "\n")
    i = d.get("inlet")
    if i:
        rows = [[_f(q["M"], 4), _f(q["L"], 3), _f(q.get("H_x_in_4.5"), 5), _f(q.get("H_x_in_8"), 5),
                 _f(q.get("H_x_in_16"), 5), _f(q["fit"], 5)] for q in i["rows"]]
        parts.append(
            "### Inlet position\n\n"
            "Default grid and options, the inlet at -4.5 b (default), -8 b, -16 b: a longer inlet thickens "
            "the film at low M (less inlet starvation), so it does not close the gap to the fit where the "
            "solver is above it.\n\n"
            + table(["M", "L", "H_c inlet -4.5 b", "-8 b", "-16 b", "Moes' fit"], rows) + "\n")
    g = d.get("grid")
    if g:
        parts.append("### Seeded random (M, L) grid\n\n" + _grid_part(g, table))
    parts.append(f"\nSource: `{source_label}` ({pg.cost('ehl_moes')}).\n")
    pg.parts.append("\n".join(parts))
    if r and r["rows"]:
        last = min(r["rows"], key=lambda q: q["M"])
        pg.summary.append(["smooth film, rigid-isoviscous limit", "Martin (1916) closed form",
                           f"M = {last['M']:g}: {_p(last.get('dev_solver_vs_martin'))}", pg.cost("ehl_moes")])
    if g:
        pg.summary.append(["smooth central film, random (M, L) grid", "Moes (1992) fit; converged films",
                           f"{g['within_3pct_default_vs_fit']} of {g['points']} within 3 % of the fit, max "
                           f"{100 * (g['default_vs_fit']['max'] or float('nan')):.2f} %; the fit itself "
                           f"{100 * (g['fit_vs_ref']['max'] or float('nan')):.2f} % max off the converged "
                           f"films; independent discretisation "
                           f"{100 * (g['reference_vs_solver_same_grid']['max'] or float('nan')):.2f} % max",
                           pg.cost("ehl_moes")])
