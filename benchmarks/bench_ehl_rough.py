"""Benchmark: rough and wavy EHL films against convergence, grids and the literature.  Prints
one JSON object (sections below; docs/ehl.md "Rough films" records what it measured).

    python benchmarks/bench_ehl_rough.py [--sections solves grid waviness] [--levels 1 2 3]
                                         [--slice-step 4]

* ``solves``: the rough films of the default scene's film grid (seed 000 Table 1 pair, its oil,
  2000 rpm; 9 positions over the path of contact x loads 0.25, 0.5, 1, 2 x the nominal line
  load -- the range of the rough load columns of the default tables -- x every
  ``--slice-step``-th slice), each warm-started from its smooth film with the table path's
  relaxation (:data:`gearfmu.ehl.mesh_film.ROUGH_WARM_SETTINGS`): converged or failed with the
  multigrid cycles alone (``newton_after_cycles=0``, the path before the coupled Newton) and
  with the default path, split by the film parameter Lambda = h_min/sigma (>= 3: full film),
  CPU per rough solve; and the residual history of the first node whose cycles fail: per cycle
  the pressure change, load error, scaled residual, and where the largest scaled residual sits.
* ``grid``: one rough film per level (pitch point, nominal load, slice 0) on 256, 512 and 1024
  intervals (the same band-limited roughness on all three): central and minimum film, film
  stiffness (seed 000 eq 8, per 1 mm slice) and the pressure peak; observed order
  p = log2(|f_256 - f_512| / |f_512 - f_1024|), Richardson value f_inf = f_1024 + (f_1024 -
  f_512)/(2^p - 1), error of the default grid (256) (f_256 - f_inf)/f_inf (where the changes
  do not fall monotonically, p is not an order and only (f_256 - f_1024)/f_1024 is given).
* ``waviness``: a stationary sinusoidal waviness (amplitude 0.05 h_c, frozen in the contact,
  i.e. on a surface that does not move while the entrainment speed is u) at the seed 000 pitch
  point on 1024 intervals: the film amplitude over |X| <= 0.5 (least-squares sinusoid) over the
  undeformed amplitude, against Hooke's (2006) parallel-film result a/A = (1 - iCQ)/(1 - iQ -
  iCQ), Q = (12/pi^2) eta (v - u)/(E' h) (lambda/h)^2 with v = 0, C = (pi/2)(E'/B)(h/lambda),
  with eta, B (Dowson-Higginson tangent bulk modulus) and h the means of the smooth film over
  |X| <= 0.5 (Hooke, C.J., 2006, "Roughness in rolling-sliding elastohydrodynamic lubricated
  contacts", Proc. IMechE Part J, doi:10.1243/13506501JET146, eqs 11-14).
(The smooth film against Moes' fit: benchmarks/bench_ehl_moes.py.)
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

LOAD_FACTORS = (0.25, 0.5, 1.0, 2.0)
GRIDS = (257, 513, 1025)
WAVELENGTHS_B = (0.06, 0.08, 0.1, 0.15, 0.25, 0.4, 0.7)


def _env(level):
    from gearfmu.contact.models import RoughnessSpec
    from gearfmu.scene.physics import environment_from_scene
    from gearfmu.scene.reader import load_scene

    sc = load_scene(None)
    sc = dataclasses.replace(sc, mesh=dataclasses.replace(sc.mesh, contact_model="rough_ehl", slices=44))
    return sc, environment_from_scene(sc, roughness=RoughnessSpec.from_level(level), max_workers=1)


def _nominal_w(sc, env):
    return sc.operating.torque_Nm / env.geom.rb1_m / sc.pair.pinion.face_width_m


def _args(fenv, R, u, w):
    return (R, fenv.E_prime_Pa, w, u, fenv.eta0_Pas, fenv.alpha_Pa_inv, fenv.rho0_kg_m3)


def section_solves(levels, slice_step, log):
    from gearfmu.contact.models import rough_profile, film_parameter
    from gearfmu.contact.rough_ehl import RoughFilmGrid
    from gearfmu.ehl.errors import EHLConvergenceError, FilmCollapseError
    from gearfmu.ehl.mesh_film import ROUGH_WARM_SETTINGS, contact_kinematics
    from gearfmu.ehl.solver import solve_line_contact

    out = []
    history = None
    for level in levels:
        sc, env = _env(level)
        fenv, fl = env.film_environment(), env.flanks()
        s_nodes = RoughFilmGrid(env, 9).s_nodes
        R, u, _ = contact_kinematics(env.geom, s_nodes, env.omega1_rad_s)
        wn = _nominal_w(sc, env)
        row = {"level": level, "nodes": 0, "full_film_nodes": 0,
               "cycles_alone": {"failed_full_film": 0, "failed_mixed": 0, "cpu_s": 0.0},
               "default": {"failed_full_film": 0, "failed_mixed": 0, "cpu_s": 0.0, "newton_nodes": 0,
                           "ramp_nodes": 0, "newton_steps_mean": 0.0}, "lambda_range": None}
        lams, steps = [], []
        for f in LOAD_FACTORS:
            w = f * wn
            for k in range(s_nodes.size):
                lam = float(film_parameter(env, np.array([s_nodes[k]]), np.array([w]))[0])
                a = _args(fenv, float(R[k]), float(u[k]), w)
                sm = solve_line_contact(*a)
                for n in range(0, env.n_slices, slice_step):
                    prof = rough_profile(env, fenv, fl, float(s_nodes[k]), n, w, float(R[k]))
                    row["nodes"] += 1
                    row["full_film_nodes"] += lam >= 3.0
                    lams.append(lam)
                    for key, nac in (("cycles_alone", 0), ("default", None)):
                        t0 = time.process_time()
                        try:
                            r = solve_line_contact(*a, roughness_m=prof, initial=sm, newton_after_cycles=nac,
                                                   **ROUGH_WARM_SETTINGS)
                            ok = True
                        except (EHLConvergenceError, FilmCollapseError) as exc:
                            ok = False
                            if key == "cycles_alone" and history is None and isinstance(exc, EHLConvergenceError):
                                history = _history(a, prof, sm, level, k, n, w, lam)
                        row[key]["cpu_s"] += time.process_time() - t0
                        if not ok:
                            row[key]["failed_full_film" if lam >= 3.0 else "failed_mixed"] += 1
                        elif key == "default":
                            if "coupled_newton_steps" in r.residuals:
                                row[key]["newton_nodes"] += 1
                                steps.append(r.residuals["coupled_newton_steps"][0])
                            row[key]["ramp_nodes"] += "roughness_ramp_retry" in r.residuals
        for key in ("cycles_alone", "default"):
            row[key]["cpu_ms_per_rough_solve"] = 1e3 * row[key]["cpu_s"] / max(row["nodes"], 1)
        row["default"]["newton_steps_mean"] = float(np.mean(steps)) if steps else None
        row["lambda_range"] = [min(lams), max(lams)]
        log(f"solves level {level}: {row}")
        out.append(row)
    return {"load_factors": list(LOAD_FACTORS), "slice_step": slice_step, "levels": out,
            "residual_history": history}


def _history(a, prof, sm, level, k, n, w, lam):
    """History of a node whose cycles fail (the path without the Newton): per cycle the pressure
    change, load error and scaled residual of the first 24 cycles, the place of the largest
    scaled residuals after them, then the coupled Newton's steps from that state."""
    import gearfmu.ehl.iterate as it
    from gearfmu.ehl.errors import EHLConvergenceError
    from gearfmu.ehl.mesh_film import ROUGH_WARM_SETTINGS
    from gearfmu.ehl.solver import solve_line_contact

    seen = []
    orig = it.coupled_newton

    def spy(solver, *args, **kw):
        res = orig(solver, *args, **kw)
        seen.append(res)
        return res
    it.coupled_newton = spy
    try:
        r = solve_line_contact(*a, roughness_m=prof, initial=sm, newton_after_cycles=24, **ROUGH_WARM_SETTINGS)
        h = r.residuals
    except EHLConvergenceError as exc:
        h = exc.history
    finally:
        it.coupled_newton = orig
    n_cyc = int(h.get("coupled_newton_from_cycle", [min(24, len(h["reynolds_residual"]))])[0])
    out = {"level": level, "position_node": k, "slice": n, "w_N_per_m": w, "film_parameter": lam,
           "M": sm.M, "L": sm.L,
           "cycles": {k_: h[k_][:n_cyc] for k_ in ("pressure_change", "load_balance", "reynolds_residual")},
           "spikes_after_cycles": _spikes(a, prof, sm)}
    if seen:
        ok, steps, hn = seen[0]
        out["newton"] = {"converged": bool(ok), "steps": int(steps),
                         "reynolds_residual": hn["reynolds_residual"], "load_balance": hn["load_balance"]}
    return out


def _spikes(a, prof, sm, n_cycles=24):
    """After ``n_cycles`` cycles alone: the five nodes of largest scaled residual (X, P, eps/dX^2)."""
    import gearfmu.ehl.attempts as attempts
    from gearfmu.ehl.film_newton import _terms
    from gearfmu.ehl.mesh_film import ROUGH_WARM_SETTINGS
    from gearfmu.ehl.solver import solve_line_contact

    keep = []
    orig = attempts.iterate_setting

    def spy(*args, **kw):
        res = orig(*args, **kw)
        keep.append(res[0])
        return res
    attempts.iterate_setting = spy
    try:
        solve_line_contact(*a, roughness_m=prof, initial=sm, newton_after_cycles=0, max_cycles=n_cycles,
                           **ROUGH_WARM_SETTINGS)
    except Exception:  # noqa: BLE001 -- the failing state is what is looked at
        pass
    finally:
        attempts.iterate_setting = orig
    if not keep:
        return None
    s = keep[0]
    t = s.top
    sl = s._sl(t)
    r, eps, dle, rho, drho = _terms(s)
    P, X, dX = s.P[sl], s.X[t], float(s.dx[t])
    K = s.K[s.iarr[2, t]:]
    J = -(0.5 * (eps[:-2] + eps[1:-1]) + 0.5 * (eps[1:-1] + eps[2:])) / dX ** 2 \
        + rho[1:-1] * (K[0] - K[1]) / (math.pi * dX)
    sc = np.zeros_like(P)
    sc[1:-1] = np.abs(r[1:-1] / J)
    sc[P <= 0] = 0.0
    top = np.argsort(-sc)[:5]
    return [{"X": float(X[i]), "P": float(P[i]), "eps_over_dX2": float(eps[i] / dX ** 2),
             "scaled_residual": float(sc[i])} for i in sorted(top)]


def section_grid(levels, log):
    from gearfmu.contact.models import rough_profile, film_parameter
    from gearfmu.ehl.film_stiffness import slice_film_stiffness_N_per_m
    from gearfmu.ehl.mesh_film import contact_kinematics
    from gearfmu.ehl.solver import solve_line_contact

    out = []
    for level in levels:
        sc, env = _env(level)
        fenv, fl = env.film_environment(), env.flanks()
        s = float(env.geom.s_pitch_m)
        w = _nominal_w(sc, env)
        R, u, _ = (float(np.ravel(v)[0]) for v in contact_kinematics(env.geom, np.array([s]), env.omega1_rad_s))
        prof = rough_profile(env, fenv, fl, s, 0, w, R)
        lam = float(film_parameter(env, np.array([s]), np.array([w]))[0])
        rows = []
        for n in GRIDS:
            a = _args(fenv, R, u, w)
            t0 = time.process_time()
            sm = solve_line_contact(*a, n_nodes=n)
            r = solve_line_contact(*a, n_nodes=n, roughness_m=prof, initial=sm)
            rows.append({"n_intervals": n - 1, "cpu_s": time.process_time() - t0,
                         "h_central_m": r.h_central_m, "h_min_m": r.h_min_m,
                         "k_film_N_per_m": slice_film_stiffness_N_per_m(r, env.width_m, "seed", fenv.B0_Pa,
                                                                        fenv.B0_prime),
                         "p_max_Pa": float(np.max(r.p_Pa))})
        est = {}
        for q in ("h_central_m", "h_min_m", "k_film_N_per_m", "p_max_Pa"):
            f1, f2, f3 = (row[q] for row in rows)
            d1, d2 = abs(f1 - f2), abs(f2 - f3)
            p = math.log2(d1 / d2) if d1 > 0 and d2 > 0 else float("nan")
            f_inf = f3 + (f3 - f2) / (2 ** p - 1) if math.isfinite(p) and p > 0 else float("nan")
            est[q] = {"observed_order": p, "richardson_value": f_inf,
                      "default_grid_error": (f1 - f_inf) / f_inf if math.isfinite(f_inf) else float("nan"),
                      "change_512_to_1024": (f3 - f2) / f3, "default_grid_diff_to_1024": (f1 - f3) / f3}
        out.append({"level": level, "s_m": s, "w_N_per_m": w, "slice": 0, "film_parameter": lam,
                    "rows": rows, "estimates": est})
        log(f"grid level {level}: {est}")
    return {"grids_intervals": [n - 1 for n in GRIDS], "levels": out}


def section_waviness(log):
    from gearfmu.ehl.lubricant import ROELANDS_LN_ETA_INF, ROELANDS_P0_PA
    from gearfmu.ehl.mesh_film import contact_kinematics
    from gearfmu.ehl.solver import solve_line_contact

    sc, env = _env(1)
    fenv = env.film_environment()
    s = float(env.geom.s_pitch_m)
    w = _nominal_w(sc, env)
    R, u, _ = (float(np.ravel(v)[0]) for v in contact_kinematics(env.geom, np.array([s]), env.omega1_rad_s))
    a = _args(fenv, R, u, w)
    n = 1025
    sm = solve_line_contact(*a, n_nodes=n)
    m = np.abs(sm.X) <= 0.5
    p = float(np.mean(sm.p_Pa[m]))
    h = float(np.mean(sm.h_m[m]))
    c1 = 0.59e9
    B = (c1 + 1.34 * p) * (c1 + p) / (0.34 * c1)                 # rho / (d rho/dp), Dowson-Higginson
    A_r = math.log(fenv.eta0_Pas) - ROELANDS_LN_ETA_INF
    z = fenv.alpha_Pa_inv * ROELANDS_P0_PA / A_r
    eta = float(np.mean(fenv.eta0_Pas * np.exp(A_r * ((1 + sm.p_Pa[m] / ROELANDS_P0_PA) ** z - 1))))
    Ep = fenv.E_prime_Pa
    rows = []
    for lb in WAVELENGTHS_B:
        lam = lb * sm.b_m
        A = 0.05 * sm.h_central_m
        r = solve_line_contact(*a, n_nodes=n, roughness_m=lambda x, lam=lam, A=A: A * np.cos(2 * np.pi * x / lam),
                               initial=sm)
        x = r.x_m[m]
        dh = (r.h_m - sm.h_m)[m]
        G = np.stack([np.cos(2 * np.pi * x / lam), np.sin(2 * np.pi * x / lam), np.ones_like(x), x], 1)
        c = np.linalg.lstsq(G, dh, rcond=None)[0]
        ratio = math.hypot(c[0], c[1]) / A
        C = 0.5 * math.pi * Ep / B * h / lam
        Q = 12.0 / math.pi ** 2 * eta * (0.0 - u) / (Ep * h) * (lam / h) ** 2
        ref = abs((1 - 1j * C * Q) / (1 - 1j * Q - 1j * C * Q))
        rows.append({"wavelength_over_b": lb, "wavelength_m": lam, "ratio": ratio, "hooke": ref,
                     "rel_diff": ratio / ref - 1.0, "C": C, "Q": Q,
                     "newton_steps": (r.residuals.get("coupled_newton_steps") or [0])[0]})
        log(f"waviness lambda/b={lb}: {ratio:.4f} vs {ref:.4f}")
    return {"M": sm.M, "L": sm.L, "n_intervals": n - 1, "b_m": sm.b_m, "h_central_m": sm.h_central_m,
            "p_mean_Pa": p, "h_mean_m": h, "eta_mean_Pas": eta, "B_Pa": B, "amplitude_over_hc": 0.05,
            "rows": rows}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sections", nargs="+", default=["solves", "grid", "waviness"],
                    choices=["solves", "grid", "waviness"])
    ap.add_argument("--levels", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--slice-step", type=int, default=4)
    a = ap.parse_args(argv)

    def log(msg):
        print(msg, file=sys.stderr, flush=True)
    out = {"benchmark": "rough and wavy EHL films"}
    t0 = time.perf_counter()
    if "solves" in a.sections:
        out["solves"] = section_solves(a.levels, a.slice_step, log)
    if "grid" in a.sections:
        out["grid"] = section_grid(a.levels, log)
    if "waviness" in a.sections:
        out["waviness"] = section_waviness(log)
    out["wall_s"] = time.perf_counter() - t0
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
