"""Amplitude reduction of a harmonic waviness in a transient EHL line contact.

Scan of A_d/A_i (deformed amplitude of the film at the contact centre over the
undeformed waviness amplitude) against Venner, Couhier, Lubrecht & Greenwood's
(1997) wavelength parameter nabla = (lambda/b) M^(3/4)/L^(1/2) for a few Moes
(M, L) pairs, pure rolling, waviness on one surface, A_i = 0.1 H_c
(gearfmu.ehl.transient.waviness_amplitude_ratio; docs/ehl_transient.md).  Per
Venner et al. the points of all (M, L) pairs should fall on one curve F(nabla).

    python examples/ehl_waviness.py [--json] [--quick] [--pairs 20,10 10,10] [--nabla 1 3 10]
                                    [--points-per-wavelength 32] [--max-intervals 1024] [--out DIR]
    python examples/ehl_waviness.py --seed000 [--levels 1 2] [--slices 4] [--intervals 256] [--json]
    python examples/ehl_waviness.py --sliding [--json]

``--sliding``: the kinematic check of Hooke (2006) (docs/ehl_transient.md section 4): with
sliding, a waviness on the surface moving at v makes a "complementary" film wave that travels
at the entrainment speed u with wavelength lambda u/v.  M = 20, L = 10, 512 intervals,
lambda = b, A_i = 0.1 H_c, SRR = +-0.5 with the waviness on either surface; the film deviation
from the smooth film on |X| <= 0.9 at the last step is fitted by least squares with a wave of
the surface wavelength plus one of a scanned wavelength (0.3-3 b, step 0.005 b).

``--seed000``: instead of the scan, the seed 000 Table 1 pair at the pitch point
(nominal load, ``--intervals`` 256 by default): smooth film, and for each roughness level and
slice the transient film (option A of docs/ehl_transient.md: only the flank
roughness moves, at U_i = u_i/u_s) against quasi-static steady films of the
same moving roughness (8 frozen snapshots in the averaging window), with the
film stiffness reductions (a) <k(t)> and (b) eq 8 on the time means, each as a
ratio to the smooth film; also the averaging-window check (window T_avg = 4
against 8 after the wash-out).  JSON only (stdout with --json, else a file).

Grid per point: the smallest power-of-2 number of intervals (>= 256) with at
least ``--points-per-wavelength`` (20) nodes per wavelength on the 6 b domain,
capped at ``--max-intervals``.  Default time scheme: the characteristic one
(dT = dX, the wavelength rounded to whole steps per period; the rows give the
nabla used), which does not damp the wave numerically (docs/ehl_transient.md 6.7).
--json prints one JSON object; PNG and CSV go to examples/output/ehl_waviness/.
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

PAIRS = ((10.0, 10.0), (20.0, 10.0), (20.0, 5.0))
NABLA = (1.0, 2.0, 3.0, 5.0, 8.0, 12.0, 20.0)


def intervals_for(wavelength_b: float, ppw: float, max_int: int, length: float = 6.0) -> int:
    n = 256
    while n < ppw * length / wavelength_b and n < max_int:
        n *= 2
    return n


def run(pairs, nablas, ppw, max_int, log=print) -> dict:
    from gearfmu.ehl.transient import waviness_amplitude_ratio

    rows = []
    for M, L in pairs:
        for nab in nablas:
            lam = nab * math.sqrt(L) / M ** 0.75
            n = intervals_for(lam, ppw, max_int)
            t0 = time.perf_counter()
            try:
                d = waviness_amplitude_ratio(M, L, lam, 0.1, n_nodes=n + 1)
                status = "ok"
            except Exception as exc:  # report, do not hide: the row carries the error
                d, status = {}, f"{type(exc).__name__}: {str(exc)[:160]}"
            lam = d.get("wavelength_b", lam)      # rounded to whole steps per period
            row = dict(M=M, L=L, nabla=d.get("nabla", nab), nabla_requested=nab, wavelength_b=lam,
                       intervals=n, points_per_wavelength=lam * n / 6.0, status=status,
                       ratio=d.get("ratio", float("nan")),
                       periodicity_defect=d.get("periodicity_defect", float("nan")),
                       n_steps=d.get("n_steps", 0), cycles_per_step=d.get("cycles_per_step", float("nan")),
                       cycles_per_step_max=d.get("cycles_per_step_max", 0),
                       cpu_time_s=d.get("cpu_time_s", float("nan")),
                       cpu_per_step_ms=d.get("cpu_per_step_ms", float("nan")),
                       wall_s=time.perf_counter() - t0)
            rows.append(row)
            log(f"M={M:g} L={L:g} nabla={nab:g} lambda/b={lam:.3f} n={n}: A_d/A_i={row['ratio']:.4f} "
                f"({row['cycles_per_step']:.2f} cycles/step, {row['cpu_per_step_ms']:.2f} ms CPU/step) {status}")
    return dict(reference="Venner, Couhier, Lubrecht & Greenwood 1997, Tribology Series 32, 103-112: "
                          "A_d/A_i = F(nabla), nabla = (lambda/b) M^0.75 / L^0.5",
                amplitude_Hc=0.1, surfaces=[1], srr=0.0, rows=rows)


def seed000_pitch_study(levels=(1, 2), slices=4, n_snap=8, log=print, intervals=256) -> dict:
    """See the module doc (--seed000)."""
    import numpy as np
    from gearfmu.contact.models import RoughnessSpec
    from gearfmu.scene.physics import environment_from_scene
    from gearfmu.ehl import EHLError, solve_line_contact
    from gearfmu.ehl.film_stiffness import film_stiffness_N_per_m, slice_film_stiffness_N_per_m
    from gearfmu.ehl.transient import T_AVERAGE, flank_slice_case, solve_line_contact_transient
    from gearfmu.gear.geometry import pair_geometry
    from gearfmu.scene.reader import load_scene

    sc = load_scene(ROOT / "examples" / "scenes" / "seed000_table1.toml")
    g = pair_geometry(sc.pair)
    s_m = g.s_pitch_m
    w = sc.operating.torque_Nm / g.rb1_m / sc.pair.pinion.face_width_m
    n_nodes = int(intervals) + 1
    env0 = environment_from_scene(sc, roughness=RoughnessSpec.from_level(1), max_workers=1)
    kw0 = flank_slice_case(env0, s_m, w, None)
    t0 = time.process_time()
    sm = solve_line_contact(*(kw0[k] for k in ("R_m", "E_Pa", "w_N_per_m", "u_m_s", "eta0_Pas",
                                               "alpha_Pa_inv", "rho0_kg_m3")), n_nodes=n_nodes)
    k_s = slice_film_stiffness_N_per_m(sm, kw0["width_m"], "seed", kw0["B0_Pa"], kw0["B0_prime"])
    band = np.abs(sm.X) <= 1.0
    out = dict(scene="examples/scenes/seed000_table1.toml", s_m=s_m, w_N_per_m=w, n_nodes=n_nodes,
               R_m=kw0["R_m"], u_s_m_s=kw0["u_m_s"], srr=kw0["srr"], b_m=sm.b_m,
               smooth=dict(k_N_per_m=k_s, h_mean_m=float(sm.h_m[band].mean()),
                           h_central_m=sm.h_central_m), levels={})
    for level in levels:
        env = environment_from_scene(sc, roughness=RoughnessSpec.from_level(level), max_workers=1)
        rows = []
        for j in range(slices):
            kw = flank_slice_case(env, s_m, w, j)
            row = dict(slice=j)
            try:
                tc = time.process_time()
                # run to T_wash + 2 T_AVERAGE: windows [T_wash, +T_AVERAGE] and [T_wash, +2 T_AVERAGE]
                T_wash = 6.0 / min(1 + kw["srr"] / 2, 1 - kw["srr"] / 2)
                dX = 6.0 / (n_nodes - 1)
                r = solve_line_contact_transient(n_nodes=n_nodes, n_steps=int(math.ceil(
                    (1.0 + T_wash + 2 * T_AVERAGE) / dX)), start="auto", ramp_T=1.0, **kw)
                T0 = r.T_settled
                a4 = r.film_stiffness_reductions(T0, T0 + T_AVERAGE)
                a8 = r.film_stiffness_reductions(T0, T0 + 2 * T_AVERAGE)
                row.update(transient_cpu_s=time.process_time() - tc, n_steps=int(r.T.size - 1),
                           start=r.start,
                           cycles_per_step=float(r.cycles[1:].mean()),
                           cycles_per_step_max=int(r.cycles.max()),
                           k_start_ratio=float(r.k_film_N_per_m[0] / k_s),
                           k_a_ratio=a8["k_mean_of_k_N_per_m"] / k_s,
                           k_b_ratio=a8["k_of_means_N_per_m"] / k_s,
                           h_mean_ratio=a8["h_mean_m"] / out["smooth"]["h_mean_m"],
                           window_hm_change=abs(a8["h_mean_m"] / a4["h_mean_m"] - 1.0),
                           h_min_over_smooth=float(r.h_min_m[r.window()].min() / sm.h_min_m))
                # quasi-static: steady films of the same moving roughness frozen at n_snap instants
                Ts = np.linspace(T0, T0 + 2 * T_AVERAGE, n_snap)
                ks, hs, ps = [], [], []
                rough = kw["roughness"]
                U1, U2 = r.U1, r.U2
                for T in Ts:
                    sh = T * r.b_m   # u_s t = T b

                    def wm(x, sh=sh):
                        x = np.asarray(x, float)
                        return rough.surface_height_m(1, x - U1 * sh) + rough.surface_height_m(2, x - U2 * sh)
                    try:
                        st = solve_line_contact(*(kw[k] for k in ("R_m", "E_Pa", "w_N_per_m", "u_m_s",
                                                                  "eta0_Pas", "alpha_Pa_inv", "rho0_kg_m3")),
                                                roughness_m=wm, n_nodes=n_nodes, initial=sm,
                                                roughness_min_wavelength_dX=0.0)
                    except EHLError:
                        row["steady_snapshots_failed"] = row.get("steady_snapshots_failed", 0) + 1
                        continue
                    bd = np.abs(st.X) <= 1.0
                    hs.append(float(st.h_m[bd].mean()))
                    ps.append(float(st.p_Pa[bd].mean()))
                    ks.append(film_stiffness_N_per_m(2 * st.b_m * kw["width_m"], hs[-1], ps[-1],
                                                     kw["B0_Pa"], kw["B0_prime"]))
                row["status"] = "ok"
                if not ks:
                    raise EHLError("every steady snapshot failed")
                kb = film_stiffness_N_per_m(2 * sm.b_m * kw["width_m"], float(np.mean(hs)),
                                            float(np.mean(ps)), kw["B0_Pa"], kw["B0_prime"])
                row.update(steady_k_a_ratio=float(np.mean(ks)) / k_s, steady_k_b_ratio=kb / k_s,
                           steady_h_mean_ratio=float(np.mean(hs)) / out["smooth"]["h_mean_m"],
                           status="ok")
            except EHLError as exc:
                if row.get("status") == "ok":      # transient fine, steady snapshots failed
                    row["steady_status"] = f"{type(exc).__name__}: {str(exc)[:200]}"
                else:
                    row.update(status=f"{type(exc).__name__}: {str(exc)[:200]}")
            rows.append(row)
            log(json.dumps(row))
        ok = [r for r in rows if r["status"] == "ok"]
        summ = {}
        for k in ("k_a_ratio", "k_b_ratio", "steady_k_a_ratio", "steady_k_b_ratio", "h_mean_ratio",
                  "steady_h_mean_ratio", "cycles_per_step", "window_hm_change"):
            v = [r[k] for r in ok if k in r]
            if v:
                summ[k] = float(np.mean(v))
                summ[k + "_n"] = len(v)
        out["levels"][str(level)] = dict(rows=rows, mean=summ, failed=len(rows) - len(ok))
    out["cpu_time_s"] = time.process_time() - t0
    return out


def sliding_check(log=print) -> dict:
    """See the module doc (--sliding)."""
    import numpy as np
    from gearfmu.ehl import solve_line_contact
    from gearfmu.ehl.transient import HarmonicWaviness, solve_line_contact_transient

    M, L, n, lam = 20.0, 10.0, 513, 1.0
    s = solve_line_contact(M=M, L=L, n_nodes=n)
    rows = []
    for srr, surf in ((0.5, 1), (0.5, 2), (-0.5, 1)):
        U = (1 + srr / 2) if surf == 1 else (1 - srr / 2)
        wav = HarmonicWaviness(0.1 * s.h_central_m, lam * s.b_m, (surf,))
        T_wash = 6.0 / min(1 + srr / 2, 1 - srr / 2)
        r = solve_line_contact_transient(M=M, L=L, n_nodes=n, roughness=wav, srr=srr,
                                         n_steps=int(math.ceil((T_wash + 2.0) / (6.0 / (n - 1)))))
        m = np.abs(r.X) <= 0.9
        x, y = r.X[m], ((r.h_m - s.h_m) / s.h_central_m)[m]
        best = None
        for lam2 in np.arange(0.3, 3.0 + 1e-9, 0.005):
            A = np.stack([np.ones_like(x), x, np.cos(2 * np.pi * x / lam), np.sin(2 * np.pi * x / lam),
                          np.cos(2 * np.pi * x / lam2), np.sin(2 * np.pi * x / lam2)], 1)
            c = np.linalg.lstsq(A, y, rcond=None)[0]
            rr = float(np.sum((A @ c - y) ** 2))
            if best is None or rr < best[0]:
                best = (rr, float(lam2), math.hypot(c[2], c[3]), math.hypot(c[4], c[5]))
        row = dict(srr=srr, surface=surf, U_wavy=U, wavelength_b=lam,
                   hooke_complementary_wavelength_b=lam / U, fitted_wavelength_b=best[1],
                   relative_error=best[1] * U / lam - 1.0, surface_wave_amplitude_Hc=best[2],
                   complementary_amplitude_Hc=best[3], cycles_per_step=float(r.cycles[1:].mean()),
                   cpu_time_s=r.cpu_time_s)
        rows.append(row)
        log(json.dumps(row))
    return dict(reference="Hooke 2006, Proc. IMechE Part J, doi:10.1243/13506501JET146: complementary "
                          "wave at the entrainment speed, wavelength lambda u/v", rows=rows)


def write_outputs(result: dict, out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    rows = result["rows"]
    with open(out / "ehl_waviness.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return
    fig, ax = plt.subplots(figsize=(6, 4))
    for M, L in sorted({(r["M"], r["L"]) for r in rows}):
        rr = [r for r in rows if (r["M"], r["L"]) == (M, L) and r["status"] == "ok"]
        ax.plot([r["nabla"] for r in rr], [r["ratio"] for r in rr], "o-", label=f"M={M:g}, L={L:g}")
    ax.set_xscale("log")
    ax.set_xlabel(r"$\nabla = (\lambda/b)\,M^{3/4}/L^{1/2}$")
    ax.set_ylabel(r"$A_d/A_i$ (film amplitude at X = 0)")
    ax.set_title("Waviness amplitude reduction, pure rolling (transient EHL)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "ehl_waviness.png", dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--json", action="store_true", help="print one JSON object to stdout")
    ap.add_argument("--quick", action="store_true", help="two pairs, nabla 1, 3, 10; 512 intervals at most")
    ap.add_argument("--pairs", nargs="*", default=None, help="M,L pairs, e.g. 20,10 10,10")
    ap.add_argument("--nabla", nargs="*", type=float, default=None)
    ap.add_argument("--points-per-wavelength", type=float, default=20.0)
    ap.add_argument("--max-intervals", type=int, default=1024)
    ap.add_argument("--seed000", action="store_true", help="seed 000 pitch-point study (module doc)")
    ap.add_argument("--sliding", action="store_true", help="Hooke (2006) complementary-wave check")
    ap.add_argument("--levels", nargs="*", type=int, default=[1, 2])
    ap.add_argument("--slices", type=int, default=4)
    ap.add_argument("--intervals", type=int, default=256, help="--seed000 grid intervals (256)")
    ap.add_argument("--out", type=Path, default=ROOT / "examples" / "output" / "ehl_waviness")
    a = ap.parse_args(argv)
    pairs = PAIRS if a.pairs is None else []
    for p in a.pairs or []:
        try:
            M, L = (float(v) for v in p.split(","))
        except ValueError:
            ap.error(f"--pairs: {p!r} is not M,L")
        pairs.append((M, L))
    nablas = NABLA if a.nabla is None else a.nabla
    max_int = a.max_intervals
    if a.quick:
        pairs, nablas, max_int = PAIRS[:2], (1.0, 3.0, 10.0), min(max_int, 512)
    log = (lambda *s: print(*s, file=sys.stderr)) if a.json else print
    if a.sliding:
        res = sliding_check(log=log)
        a.out.mkdir(parents=True, exist_ok=True)
        (a.out / "sliding.json").write_text(json.dumps(res, indent=1))
        if a.json:
            print(json.dumps(res))
        return 0
    if a.seed000:
        res = seed000_pitch_study(tuple(a.levels), a.slices, log=log, intervals=a.intervals)
        a.out.mkdir(parents=True, exist_ok=True)
        (a.out / f"seed000_pitch_{a.intervals}.json").write_text(json.dumps(res, indent=1))
        if a.json:
            print(json.dumps(res))
        return 0
    t0 = time.perf_counter()
    result = run(pairs, nablas, a.points_per_wavelength, max_int, log)
    result["wall_time_s"] = time.perf_counter() - t0
    write_outputs(result, a.out)
    if a.json:
        print(json.dumps(result))
    else:
        print(f"wrote {a.out}/ehl_waviness.csv and .png ({result['wall_time_s']:.1f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
