"""Memory of a long FMU run: 10^7 internal (RK4) steps keep the resident set flat.

Runs the pythonfmu gear FMU through fmpy's low-level API: communication step
H = 1e-3 s with max_step 1e-5 s (100 internal steps per call), 10^5 calls =
10^7 internal steps; every 100 calls it also takes, serializes and frees an
FMU state and reads every output.  Samples the resident set size (Linux
/proc/self/statm) and prints JSON:

    {"internal_steps", "calls", "rss_MB_after_warmup", "rss_MB_end", "rss_MB_max",
     "growth_MB", "growth_per_million_calls_MB", "wall_s", "samples": [[calls, rss_MB], ...]}

and writes benchmarks/output/memory_flat.{json,png}.  "Flat" = growth after
warm-up below 2 MB (a leak of one 8-byte object per call would be 0.8 MB,
one state blob (~300 B) per state call ~0.3 MB).

    python benchmarks/memory_flat.py [--calls 100000] [--substeps 100]
"""
import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def rss_MB() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 1e6


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--calls", type=int, default=100_000)
    ap.add_argument("--substeps", type=int, default=100)
    ap.add_argument("--out", default=str(HERE / "output"))
    a = ap.parse_args(argv)

    import fmpy
    from fmpy.fmi2 import FMU2Slave

    from gearfmu.fmu.pythonfmu_build import build_fmu
    from gearfmu.tables.synthetic import rectangular_wave_tables

    hmax = 1e-5
    H = hmax * a.substeps
    with tempfile.TemporaryDirectory() as d:
        t = rectangular_wave_tables(2e8, contact_ratio=1.6, points_per_mesh=64, backlash_half_m=1e-5)
        path = str(build_fmu(t, Path(d) / "mem.fmu", max_step_s=hmax, pinion_speed_start_rad_s=100.0))
        md = fmpy.read_model_description(path)
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=fmpy.extract(path, os.path.join(d, "x")),
                        modelIdentifier=md.coSimulation.modelIdentifier, instanceName="mem")
        outs = [v.valueReference for v in md.modelVariables if v.causality == "output"]
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        samples = []
        warm = max(1, a.calls // 20)
        t0 = time.perf_counter()
        for i in range(a.calls):
            fmu.doStep(i * H, H)
            if i % 100 == 0:
                fmu.getReal(outs)
                s = fmu.getFMUstate()
                fmu.serializeFMUstate(s)
                fmu.freeFMUstate(s)
            if i % max(1, a.calls // 200) == 0 or i == a.calls - 1:
                samples.append([i + 1, round(rss_MB(), 3)])
                if i % max(1, a.calls // 10) == 0:
                    print(f"memory_flat: {i + 1}/{a.calls} calls, RSS {samples[-1][1]:.1f} MB",
                          file=sys.stderr, flush=True)
        wall = time.perf_counter() - t0
        final = fmu.getReal(outs)
        fmu.terminate()
        fmu.freeInstance()
    arr = np.array(samples)
    after = arr[arr[:, 0] >= warm]
    res = {"internal_steps": a.calls * a.substeps, "calls": a.calls, "H_s": H, "max_step_s": hmax,
           "rss_MB_after_warmup": float(after[0, 1]), "rss_MB_end": float(arr[-1, 1]),
           "rss_MB_max": float(arr[:, 1].max()), "growth_MB": float(arr[-1, 1] - after[0, 1]),
           "growth_per_million_calls_MB": float(np.polyfit(after[:, 0], after[:, 1], 1)[0] * 1e6),
           "wall_s": round(wall, 2), "final_outputs_finite": bool(np.all(np.isfinite(final))),
           "flat": bool(arr[-1, 1] - after[0, 1] < 2.0), "samples": samples}
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "memory_flat.json").write_text(json.dumps(res, indent=1))
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(6, 3.5))
        ax.plot(arr[:, 0] * a.substeps, arr[:, 1], ".-")
        ax.set_xlabel("internal steps")
        ax.set_ylabel("resident set (MB)")
        ax.set_title("gear FMU, fmpy low-level loop")
        fig.tight_layout()
        fig.savefig(out / "memory_flat.png", dpi=120)
    except Exception as exc:  # noqa: BLE001 - the JSON is the result
        print(f"memory_flat: no plot ({exc})", file=sys.stderr)
    print(json.dumps({k: v for k, v in res.items() if k != "samples"}))
    return 0 if res["flat"] else 1


if __name__ == "__main__":
    sys.exit(main())
