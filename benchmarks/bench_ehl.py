"""Benchmark of the line-contact EHL solver (prints JSON; not a test).

Wall and CPU time per smooth solve (median of repeats, numba compilation
excluded; the machine's load average is recorded because other jobs inflate
wall time) for
several grid sizes at fixed operating points, the number of W-cycles, the
time per W-cycle per node, and the central film (Moes scaling) so that the
cost can be read against the discretisation error.

    python benchmarks/bench_ehl.py [--repeats 3]
"""
from __future__ import annotations

import argparse
import json
import math
import os
import platform
import time

import numpy as np

from gearfmu.ehl import solve_line_contact
from gearfmu.ehl.fits import moes_central_film


def bench(M, L, sizes, repeats, **kw):
    rows = []
    for n in sizes:
        times, cpu = [], []
        r = None
        for _ in range(repeats):
            t = time.perf_counter()
            c = time.process_time()
            r = solve_line_contact(M=M, L=L, n_nodes=n + 1, **kw)
            times.append(time.perf_counter() - t)
            cpu.append(time.process_time() - c)
        t_med = float(np.median(times))
        rows.append(dict(n_intervals=n, solver=kw.get('solver', 'compiled'), levels=r.grid_levels, w_cycles=r.iterations,
                         attempt=r.residuals["attempt"], time_s=t_med,
                         cpu_time_s=float(np.median(cpu)),
                         time_per_cycle_ms=1e3 * t_med / r.iterations,
                         us_per_cycle_per_node_over_log2n=1e6 * t_med / r.iterations / (n * math.log2(n)),
                         H_central_moes=r.H_central_moes,
                         rel_dev_from_moes=r.H_central_moes / moes_central_film(M, L) - 1.0))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    solve_line_contact(M=20.0, L=5.0, n_nodes=257)  # numba compilation
    out = dict(python=platform.python_version(), machine=platform.machine(),
               load_average_1min=os.getloadavg()[0], cpu_count=os.cpu_count(), cases=[])
    solve_line_contact(M=20.0, L=5.0, n_nodes=257, solver="python")
    for M, L, kw in [(20.0, 5.0, dict(viscosity="barus", compressible=False, n_coarse=32)),
                     (100.0, 10.0, dict(viscosity="barus", compressible=False, n_coarse=64)),
                     (100.0, 10.0, dict(viscosity="roelands", compressible=True, n_coarse=64)),
                     (100.0, 10.0, dict(viscosity="roelands", compressible=True, n_coarse=64,
                                        solver="python"))]:
        out["cases"].append(dict(M=M, L=L, options={k: v for k, v in kw.items()},
                                 rows=bench(M, L, [256, 512, 1024, 2048, 4096], args.repeats,
                                            **kw)))
    # warm start along 8 neighbouring loads (a meshing-position sweep)
    kw = dict(R_m=0.02, E_Pa=2.26e11, u_m_s=5.0, eta0_Pas=0.04, alpha_Pa_inv=2.2e-8,
              )
    loads = np.linspace(3.0e5, 3.35e5, 8)
    t = time.perf_counter()
    cold = [solve_line_contact(w_N_per_m=w, **kw) for w in loads]
    t_cold = time.perf_counter() - t
    t = time.perf_counter()
    prev, warm = None, []
    for w in loads:
        prev = solve_line_contact(w_N_per_m=w, initial=prev, **kw)
        warm.append(prev)
    t_warm = time.perf_counter() - t
    out["warm_start"] = dict(n_solves=len(loads), cold_s=t_cold, warm_s=t_warm,
                             cold_cycles=[r.iterations for r in cold],
                             warm_cycles=[r.iterations for r in warm],
                             max_rel_diff_h_central=max(abs(a.h_central_m / b.h_central_m - 1)
                                                        for a, b in zip(warm, cold)))
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
