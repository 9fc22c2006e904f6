"""Section "Rough EHL films" of the validation report (benchmarks/report.py) from the JSON of
``benchmarks/bench_ehl_rough.py`` (source ``ehl_rough``) and ``benchmarks/bench_ehl_tables.py
--levels 1 2 3 --models hertz smooth_ehl`` (source ``ehl_rough_tables``)."""
from __future__ import annotations

import math


def _f(x, digits=4):
    return "n/a" if x is None or not math.isfinite(float(x)) else f"{float(x):.{digits}g}"


def _p(x, digits=2):
    return "n/a" if x is None or not math.isfinite(float(x)) else f"{100 * float(x):+.{digits}f} %"


def _tables_part(t, table, cost):
    """Default pair's rough-EHL tables per level: what each flagged point is, and the TVMS order."""
    rows = []
    for r in t.get("levels", []):
        mx = r.get("film_mixed_lubrication") or {}
        bad = r.get("film_solver_failures") or {}
        lr = mx.get("lambda_range")
        rows.append([r["roughness_level"], r.get("rough_film_solves"), r.get("failed_rough_nodes"),
                     r.get("stalled_rough_nodes_interpolated"),
                     f"{mx.get('points', 0)}" + (f" (Λ {lr[0]:.3g}..{lr[1]:.3g})" if lr else ""),
                     bad.get("points", 0), ", ".join(f"{k} {v}" for k, v in (r.get("film_failures_by_use") or {}).items())
                     or "-", f"{r['workers_cpu_s']:.1f}", f"{r['wall_s']:.1f}"])
    out = ("Default pair (seed 000 Table 1, 44 slices, 64 points per mesh period, torque rows 0.5/1/1.5 x "
           "nominal), `contact_model = \"rough_ehl\"`, the seed's oil (60 °C), roughness levels of seed 000 "
           "Table 2, 2 worker processes.  Points in mixed lubrication by Λ are expected; points where a "
           "full-film solve failed are a defect (must be 0).\n\n"
           + table(["level", "rough film solves", "failed grid nodes", "stalled nodes interpolated",
                    "mixed-lubrication points (Λ < 3)", "full-film solver failures", "replaced by",
                    "worker CPU s", "wall s"], rows))
    lines = [r.get("build_line") for r in t.get("levels", []) if r.get("build_line")]
    if lines:
        out += "\n\nBuild lines:\n\n" + "\n".join(f"* level {r['roughness_level']}: `{r['build_line']}`"
                                                 for r in t["levels"] if r.get("build_line"))
    models = {m["model"]: m for m in t.get("models", [])}
    lv = {r["roughness_level"]: r for r in t.get("levels", [])}
    if models and lv:
        def mean(v):
            return sum(v) / len(v)
        order = [("Hertz", models.get("hertz")), ("rough level 1", lv.get(1)), ("rough level 2", lv.get(2)),
                 ("smooth film", models.get("smooth_ehl"))]
        order = [(n, mean(r["mean_tvms_N_per_m"])) for n, r in order if r is not None]
        nom = [(n, r["mean_tvms_N_per_m"][len(r["mean_tvms_N_per_m"]) // 2]) for n, r in
               [("Hertz", models.get("hertz")), ("rough level 1", lv.get(1)), ("rough level 2", lv.get(2)),
                ("smooth film", models.get("smooth_ehl"))] if r is not None]
        def held(v):   # Hertz below both rough levels, both rough levels below the smooth film
            return len(v) == 4 and v[0][1] < min(v[1][1], v[2][1]) and max(v[1][1], v[2][1]) < v[3][1]
        ok, ok2 = held(order), held(nom)
        out += ("\n\nMean TVMS of the tables (N/m; mean over the torque rows / the nominal row), seed 000 Figs. "
                "12-13 order Hertz < rough (levels 1, 2) < smooth:\n\n"
                + table(["tables", "mean over rows", "nominal row"],
                        [[n, f"{v:.5e}", f"{w:.5e}"] for (n, v), (_, w) in zip(order, nom)])
                + f"\n\nOrder held: {'yes' if ok else 'no'} (mean over rows), {'yes' if ok2 else 'no'} (nominal row).")
    return out + f"\n\nSource: `python benchmarks/bench_ehl_tables.py --levels 1 2 3 --models hertz smooth_ehl` ({cost}).\n"


def render(pg, table, source_label):
    """Append the section to ``pg`` (a report Page); ``table`` is the report's table helper."""
    parts = ["## Rough EHL films\n\n"
             "Rough films of seed 000 eq 2-7 with the W-M roughness of seed 000 Table 2 (docs/ehl.md "
             "\"Rough films\"): do they converge where the film is full, how large is the default grid's "
             "error, and does a wavy film deform as the literature says.\n"]
    if "ehl_rough_tables" in pg.data:
        parts.append("### Rough-EHL tables of the default pair\n\n"
                     + _tables_part(pg.data["ehl_rough_tables"], table, pg.cost("ehl_rough_tables")))
    d = pg.data.get("ehl_rough")
    if d is None:
        parts.append("Source `ehl_rough` not run (`python benchmarks/report.py --only ehl_rough`).\n")
        pg.parts.append("\n".join(parts))
        return
    s = d.get("solves")
    if s:
        rows = []
        for r in s["levels"]:
            c, n = r["cycles_alone"], r["default"]
            rows.append([r["level"], r["nodes"], f"{r['lambda_range'][0]:.3g}..{r['lambda_range'][1]:.3g}",
                         r["full_film_nodes"], c["failed_full_film"], c["failed_mixed"], n["failed_full_film"],
                         n["failed_mixed"], n["newton_nodes"], n["ramp_nodes"], _f(n["newton_steps_mean"], 3),
                         _f(c["cpu_ms_per_rough_solve"], 3), _f(n["cpu_ms_per_rough_solve"], 3)])
        parts.append(
            "### Convergence of the film grid's rough films\n\n"
            f"Every film-grid node of the default scene (9 positions over the path of contact x loads "
            f"{', '.join(f'{x:g}' for x in s['load_factors'])} x the nominal line load x every "
            f"{s['slice_step']}th of the 44 slices), warm-started from its smooth film: failed rough films "
            "with the multigrid cycles alone (the path before the coupled Newton) and with the default "
            "path, split by the film parameter Λ = h_min/σ.\n\n"
            + table(["level", "nodes", "Λ", "nodes Λ ≥ 3", "cycles alone: failed Λ ≥ 3", "failed Λ < 3",
                     "default: failed Λ ≥ 3", "failed Λ < 3", "Newton used", "amplitude steps used",
                     "Newton steps (mean)", "CPU ms per rough solve, cycles alone", "default"], rows) + "\n")
        h = s.get("residual_history")
        if h:
            cy = h.get("cycles", {})
            k = list(range(0, len(cy.get("reynolds_residual", [])), 3))
            hist_rows = [[i + 1, f"{cy['pressure_change'][i]:.1e}", f"{cy['load_balance'][i]:.1e}",
                          f"{cy['reynolds_residual'][i]:.1e}"] for i in k]
            sp = h.get("spikes_after_cycles") or []
            nw = h.get("newton") or {}
            parts.append(
                f"\nResidual history of the first node whose cycles fail (level {h['level']}, position node "
                f"{h['position_node']}, slice {h['slice']}, w = {h['w_N_per_m']:.4g} N/m, Λ = "
                f"{h['film_parameter']:.3g}, M = {h['M']:.3g}, L = {h['L']:.3g}): every third cycle\n\n"
                + table(["cycle", "pressure change", "load error", "scaled residual"], hist_rows)
                + "\n\nThe five largest scaled residuals after 24 cycles sit on one pressure spike:\n\n"
                + table(["X = x/b", "P = p/p_h", "eps/dX²", "scaled residual"],
                        [[f"{q['X']:.3f}", f"{q['P']:.3g}", f"{q['eps_over_dX2']:.2e}",
                          f"{q['scaled_residual']:.2e}"] for q in sp])
                + (f"\n\nThe coupled Newton from that state: scaled residual per step "
                   f"{', '.join(f'{x:.1e}' for x in nw.get('reynolds_residual', []))} "
                   f"({'converged' if nw.get('converged') else 'not converged'} in {nw.get('steps')} steps)."
                   if nw else "") + "\n")
    g = d.get("grid")
    if g:
        rows = []
        names = {"h_central_m": ("central film", 1e6, "µm"), "h_min_m": ("minimum film", 1e6, "µm"),
                 "k_film_N_per_m": ("film stiffness (1 mm slice)", 1e-9, "GN/m"),
                 "p_max_Pa": ("pressure peak", 1e-9, "GPa")}
        for lv in g["levels"]:
            for q, (name, sc, unit) in names.items():
                e = lv["estimates"][q]
                rows.append([lv["level"], f"{name} ({unit})"] + [_f(r[q] * sc, 5) for r in lv["rows"]]
                            + [_f(e["observed_order"], 3), _p(e["default_grid_error"]),
                               _p(e.get("default_grid_diff_to_1024"))])
        parts.append(
            "### Grid convergence of a rough film\n\n"
            "Pitch point, nominal line load, slice 0, the same band-limited roughness on each grid.  "
            "Observed order p = log2(|f_256 - f_512|/|f_512 - f_1024|); default-grid error (256 "
            "intervals) against the Richardson value f_1024 + (f_1024 - f_512)/(2^p - 1) where the "
            "changes fall monotonically (else n/a), and against the 1024-interval value.\n\n"
            + table(["level", "quantity"] + [f"{n} intervals" for n in g["grids_intervals"]]
                    + ["observed order", "default grid error (Richardson)", "default grid vs 1024"], rows) + "\n")
    w = d.get("waviness")
    if w:
        rows = [[_f(r["wavelength_over_b"], 3), _f(r["ratio"], 4), _f(r["hooke"], 4), _p(r["rel_diff"], 1),
                 _f(r["C"], 3), _f(r["Q"], 3)] for r in w["rows"]]
        worst = max(abs(r["rel_diff"]) for r in w["rows"])
        parts.append(
            "### Amplitude reduction of a stationary waviness\n\n"
            "Reference: Hooke's (2006) parallel-film theory of a low-amplitude waviness in an EHL line "
            "contact (Proc. IMechE Part J 220, doi:10.1243/13506501JET146, eqs 11-14): a/A = (1 - iCQ)/"
            "(1 - iQ - iCQ), Q = (12/π²) η (v - u)/(E'h) (λ/h)², C = (π/2)(E'/B)(h/λ), for a waviness "
            "moving at v (here v = 0: frozen in the contact) and the entrainment speed u; η, B (the "
            "Dowson-Higginson tangent bulk modulus) and h the means of the smooth film over |X| <= 0.5.  "
            f"Seed 000 pitch point (M = {w['M']:.3g}, L = {w['L']:.3g}), {w['n_intervals']} intervals, "
            f"amplitude {w['amplitude_over_hc']:g} h_c; ours: the film amplitude over |X| <= 0.5 "
            "(least-squares sinusoid of the waviness' wavelength) over the undeformed amplitude.\n\n"
            + table(["λ/b", "A_d/A_i ours", "Hooke (2006)", "difference", "C", "Q"], rows)
            + f"\n\nLargest difference {100 * worst:.1f} % over {len(rows)} wavelengths.\n")
    parts.append(f"\nSource: `{source_label}` ({pg.cost('ehl_rough')}).\n")
    pg.parts.append("\n".join(parts))
    if g:
        ks = ", ".join(f"level {lv['level']}: {_p(lv['estimates']['k_film_N_per_m'].get('default_grid_diff_to_1024'))}"
                       for lv in g["levels"])
        pg.summary.append(["rough film stiffness, default grid (256 intervals)", "same film on 1024 intervals",
                           ks, pg.cost("ehl_rough")])
    if w:
        pg.summary.append(["stationary waviness amplitude reduction", "Hooke (2006) parallel-film theory",
                           f"max {100 * max(abs(r['rel_diff']) for r in w['rows']):.1f} % over "
                           f"{len(w['rows'])} wavelengths", pg.cost("ehl_rough")])
