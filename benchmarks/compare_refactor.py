"""Bit-for-bit comparison of two gearfmu checkouts (for refactorings that must not change behaviour).

    python benchmarks/compare_refactor.py CHECKOUT_A CHECKOUT_B [--runtimes pythonfmu,standalone]
                                          [--bench-full] [--keep DIR]

In each checkout (a fresh interpreter with the checkout first on ``sys.path``; the script
checks that the ``gearfmu`` it imported is the checkout's) it computes

* the default scene's tables: every array of the MeshTables;
* the native solver on them with the scene's settings (``pipeline.simulate_native``): every
  output array;
* the default scene's FMU, built per runtime and run through fmpy over the scene's
  experiment: every output column;
* ``gearfmu bench accuracy``'s errors (every error of every row; wall times excluded), on
  a shortened run unless ``--bench-full``.

and prints, per array, max |A - B| (NaN in the same places counts as equal) and whether the
two are identical bit for bit.  Exit status 0 when every array is identical, 1 otherwise.
Only ``.npz`` files (no pickle) cross between the processes.
"""
from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

CHILD = r'''
import sys, json, tempfile, importlib
checkout, out, runtimes, bench_full = sys.argv[1], sys.argv[2], sys.argv[3].split(","), sys.argv[4] == "1"
sys.path.insert(0, checkout)
import numpy as np
import gearfmu
from pathlib import Path
assert Path(gearfmu.__file__).resolve().is_relative_to(Path(checkout).resolve()), gearfmu.__file__

def first(*names):
    """The first importable module of ``names`` (the flat and the layered package)."""
    for n in names:
        try:
            return importlib.import_module(n)
        except ImportError:
            pass
    raise ImportError(names)

pipeline = importlib.import_module("gearfmu.pipeline")
compare = first("gearfmu.fmu.compare", "gearfmu.compare")
bench = importlib.import_module("gearfmu.bench")
arrays = {}

def put(prefix, obj):
    items = obj.items() if isinstance(obj, dict) else vars(obj).items()
    for k, v in items:
        if isinstance(v, np.ndarray) and v.dtype != object:
            arrays[f"{prefix}.{k}"] = v

scene = pipeline.load(None)
tables = pipeline.compute_tables(scene)
put("tables", tables)
res = pipeline.simulate_native(scene, tables)
put("native", res)
with tempfile.TemporaryDirectory() as d:
    for rt in runtimes:
        b = pipeline.build(scene, Path(d) / f"{rt}.fmu", runtime=rt, tables=tables)
        run = compare.run_fmu(b.fmu_path, stop_time_s=scene.fmu.stop_time_s, comm_step_s=scene.fmu.output_interval_s,
                              names=compare.output_names(tables.slots))
        put(f"fmu_{rt}", {k: np.asarray(v) for k, v in run.columns.items()})
        arrays[f"fmu_{rt}.time"] = np.asarray(run.time_s) if hasattr(run, "time_s") else np.asarray(run.time)
kw = {} if bench_full else dict(substeps=(4, 16, 64), fmu_comm_mesh_periods=(1.0,), rtols=(1e-4,), mesh_periods=40)
rep = bench.accuracy_benchmark("single_sided_impacts", progress=False, **kw)
for r in rep["rows"]:
    key = f"bench.{r['method']}[{r['setting']}]"
    errs = {k: v for k, v in r.items() if k.endswith("_err")}
    arrays[key] = np.array([errs[k] for k in sorted(errs)], dtype=float)
np.savez(out, **arrays)
print(json.dumps({"gearfmu": gearfmu.__file__, "arrays": len(arrays)}))
'''


def run_checkout(checkout: Path, out: Path, runtimes: str, bench_full: bool) -> dict:
    res = subprocess.run([sys.executable, "-c", CHILD, str(checkout), str(out), runtimes, "1" if bench_full else "0"],
                         cwd=tempfile.gettempdir(), capture_output=True, text=True)
    if res.returncode != 0:
        raise SystemExit(f"{checkout}: the child run failed:\n{res.stderr[-4000:]}")
    return json.loads(res.stdout.strip().splitlines()[-1])


def compare_npz(a_path: Path, b_path: Path):
    a, b = np.load(a_path, allow_pickle=False), np.load(b_path, allow_pickle=False)
    rows, identical = [], True
    for k in sorted(set(a.files) | set(b.files)):
        if k not in a.files or k not in b.files:
            rows.append((k, "only in " + ("A" if k in a.files else "B"), False))
            identical = False
            continue
        x, y = a[k], b[k]
        if x.shape != y.shape:
            rows.append((k, f"shape {x.shape} vs {y.shape}", False))
            identical = False
            continue
        same = x.dtype == y.dtype and x.tobytes() == y.tobytes()
        if x.size == 0:
            d = 0.0
        elif np.issubdtype(x.dtype, np.number):
            xf, yf = x.astype(float), y.astype(float)
            nan_same = np.array_equal(np.isnan(xf), np.isnan(yf))
            fin = ~np.isnan(xf) & ~np.isnan(yf)
            with np.errstate(invalid="ignore"):
                diff = np.abs(xf[fin] - yf[fin])
            d = float(np.max(diff)) if diff.size else 0.0
            if not nan_same:
                d = math.inf
        else:
            d = 0.0 if np.array_equal(x, y) else math.inf
        identical &= same
        rows.append((k, f"{d:.3g}", same))
    return rows, identical


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("a", type=Path)
    ap.add_argument("b", type=Path)
    ap.add_argument("--runtimes", default="pythonfmu,standalone")
    ap.add_argument("--bench-full", action="store_true", help="the benchmark at its own settings (long)")
    ap.add_argument("--keep", type=Path, help="keep the two .npz files in this folder")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as d:
        d = args.keep or Path(d)
        d.mkdir(parents=True, exist_ok=True)
        info = {}
        for tag, path in (("A", args.a), ("B", args.b)):
            info[tag] = run_checkout(path.resolve(), d / f"{tag}.npz", args.runtimes, args.bench_full)
        rows, identical = compare_npz(d / "A.npz", d / "B.npz")
    print(f"A: {info['A']['gearfmu']}\nB: {info['B']['gearfmu']}")
    w = max(len(r[0]) for r in rows)
    print(f"{'array':<{w}}  {'max|A-B|':>9}  bit-identical")
    for k, d_, same in rows:
        print(f"{k:<{w}}  {d_:>9}  {'yes' if same else 'NO'}")
    print(f"{len(rows)} arrays, {sum(r[2] for r in rows)} bit-identical: "
          + ("IDENTICAL" if identical else "DIFFERENT"))
    return 0 if identical else 1


if __name__ == "__main__":
    sys.exit(main())
