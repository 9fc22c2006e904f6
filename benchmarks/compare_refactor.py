"""Bit-for-bit comparison of two gearfmu checkouts (for refactorings that must not change behaviour).

    python benchmarks/compare_refactor.py CHECKOUT_A CHECKOUT_B [--runtimes pythonfmu,standalone]
                                          [--scenes default,examples,rough_ehl] [--fmi-versions 2,3]
                                          [--bench-full] [--keep DIR [--reuse-a]]

In each checkout (a fresh interpreter with the checkout first on ``sys.path``; the script
checks that the ``gearfmu`` it imported is the checkout's) it computes, for every scene of
``--scenes`` (``default``: the default scene; ``examples``: every gear-pair scene of
``examples/scenes/*.toml`` of checkout A, drivetrain scenes left out; ``rough_ehl``: the default
pair with ``contact_model = "rough_ehl"`` on a small grid, :data:`ROUGH_EHL_SCENE`; or scene file
paths)

* the scene's tables: every array of the MeshTables (built as written: a scene with
  ``[accuracy]`` is not planned); a drivetrain scene (``[drivetrain]``, docs/gearbox.md): every
  stage's tables and the native gearbox run with each gearbox integrator (every output column);
* the native solver on them with the scene's settings, once per integrator at the scene's
  internal step and once more for the event integrators at a coarse step (one internal step per
  output interval): every output array;
* the scene's FMU, built per runtime (and per FMI version for the standalone runtime; the build
  machine's binary only) and run through fmpy over the scene's experiment once per integrator
  (the ``integrator`` parameter): every output column;

and, once, ``gearfmu bench accuracy``'s errors (every error of every row; wall times excluded),
on a shortened run unless ``--bench-full``.  It prints, per array, max |A - B| (NaN in the same
places counts as equal) and whether the two are identical bit for bit.  Exit status 0 when every
array is identical, 1 otherwise.  Only ``.npz`` files (no pickle) cross between the processes;
``--keep DIR`` keeps them (A.npz, B.npz) and ``--reuse-a`` takes A.npz from there instead of
computing it again (record the unchanged tree once, compare every step of a refactoring to it).
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
scenes, fmi_versions = json.loads(sys.argv[5]), [int(v) for v in sys.argv[6].split(",")]
sys.path.insert(0, checkout)
import numpy as np
import gearfmu
from pathlib import Path
assert Path(gearfmu.__file__).resolve().is_relative_to(Path(checkout).resolve()), gearfmu.__file__

def first(*names):
    # the first importable module of names (the flat and the layered package)
    for n in names:
        try:
            return importlib.import_module(n)
        except ImportError:
            pass
    raise ImportError(names)

pipeline = importlib.import_module("gearfmu.pipeline")
compare = first("gearfmu.fmu.compare", "gearfmu.compare")
bench = importlib.import_module("gearfmu.bench")
native = importlib.import_module("gearfmu.dynamics.native")
crossbuild = importlib.import_module("gearfmu.fmu.crossbuild")
arrays = {}

def put(prefix, obj):
    items = obj.items() if isinstance(obj, dict) else vars(obj).items()
    for k, v in items:
        if isinstance(v, np.ndarray) and v.dtype != object:
            arrays[f"{prefix}.{k}"] = v

def with_attr(attr, *names):
    # the first importable module of names that defines attr (the module a name moved to)
    for n in names:
        try:
            m = importlib.import_module(n)
        except ImportError:
            continue
        if hasattr(m, attr):
            return m
    raise ImportError(f"{attr} in none of {names}")

def drivetrain_arrays(label, path):
    # a drivetrain scene: every stage's tables and the native gearbox run with each gearbox integrator
    dt = with_attr("simulate_drivetrain", "gearfmu.drivetrain", "gearfmu.stages", "gearfmu.pipeline")
    _, sc = dt.load_any(path)
    tabs = dt.stage_tables(sc, allow_large=True)
    for i, t in enumerate(tabs):
        put(f"{label}.tables{i}", t)
    model = dt.gearbox_model(sc, tabs)
    vocabulary = importlib.import_module("gearfmu.common.vocabulary")
    for integ in vocabulary.GEARBOX_INTEGRATORS:
        r = dt.simulate_drivetrain(sc, model, integrator=integ)
        put(f"{label}.gearbox_{integ}", {k: np.asarray(v[1]) for k, v in r.columns.items()})
        arrays[f"{label}.gearbox_{integ}.time"] = np.asarray(r.time_s)

host = crossbuild.host_key()
for label, path in scenes:
    print(f"scene {label} ...", file=sys.stderr, flush=True)
    if path is not None and with_attr("is_drivetrain_file", "gearfmu.scene.drivetrain").is_drivetrain_file(path):
        drivetrain_arrays(label, path)
        continue
    scene = pipeline.load(path)
    tables = pipeline.compute_tables(scene, allow_large=True)
    put(f"{label}.tables", tables)
    integrators = list(native.INTEGRATORS)
    t1 = scene.operating.torque_Nm
    kw = dict(stop_time_s=scene.fmu.stop_time_s, comm_step_s=scene.fmu.output_interval_s,
              pinion_torque_Nm=t1, gear_torque_Nm=pipeline.gear_torque_for(tables, t1),
              pinion_speed_start_rad_s=scene.operating.speed_rad_s, damping_ratio=scene.fmu.damping_ratio,
              damping_model=scene.solver.damping_model)
    for integ in integrators:
        put(f"{label}.native_{integ}", native.simulate(tables, max_step_s=pipeline.max_step_for(scene, tables),
                                                       integrator=integ, **kw))
        if integ != "rk4":
            put(f"{label}.native_{integ}_coarse", native.simulate(tables, max_step_s=scene.fmu.output_interval_s,
                                                                  integrator=integ, **kw))
    with tempfile.TemporaryDirectory() as d:
        for rt in runtimes:
            for v in (fmi_versions if rt == "standalone" else [2]):
                extra = dict(platforms=[host], fmi_version=v) if rt == "standalone" else {}
                fmu = Path(d) / f"{rt}{v}.fmu"
                b = pipeline.build(scene, fmu, runtime=rt, tables=tables, **extra)
                for integ in integrators:
                    run = compare.run_fmu(b.fmu_path, stop_time_s=scene.fmu.stop_time_s,
                                          comm_step_s=scene.fmu.output_interval_s,
                                          start_values={"integrator": native.INTEGRATORS[integ]},
                                          names=compare.output_names(tables.slots))
                    key = f"{label}.fmu_{rt}_fmi{v}_{integ}"
                    put(key, {k: np.asarray(val) for k, val in run.columns.items()})
                    arrays[f"{key}.time"] = np.asarray(run.time_s) if hasattr(run, "time_s") else np.asarray(run.time)
print("bench ...", file=sys.stderr, flush=True)
kw = {} if bench_full else dict(substeps=(4, 16, 64), fmu_comm_mesh_periods=(1.0,), rtols=(1e-4,), mesh_periods=40)
rep = bench.accuracy_benchmark("single_sided_impacts", progress=False, **kw)
for r in rep["rows"]:
    key = f"bench.{r['method']}[{r['setting']}]"
    errs = {k: v for k, v in r.items() if k.endswith("_err")}
    arrays[key] = np.array([errs[k] for k in sorted(errs)], dtype=float)
np.savez(out, **arrays)
print(json.dumps({"gearfmu": gearfmu.__file__, "arrays": len(arrays)}))
'''

#: the rough-EHL scene of ``--scenes rough_ehl``: the default pair (its other keys) with the rough
#: EHL contact model on a grid small enough to build in seconds
ROUGH_EHL_SCENE = {"[mesh]": 'contact_model = "rough_ehl"\nslices = 4\nfoundation = true\n',
                   "[tables]": "points_per_mesh = 16\ntorque_points = 1\nslots = \"auto\"\n",
                   "[roughness]": "level = 1\nfilm_position_nodes = 3\n"}


def rough_ehl_scene(default_text: str) -> str:
    """The default scene's text with :data:`ROUGH_EHL_SCENE`'s sections in place of its own."""
    out, skip = [], False
    for line in default_text.splitlines():
        head = line.strip()
        if head.startswith("["):
            skip = head in ROUGH_EHL_SCENE
            if skip:
                out.append(head)
                out.append(ROUGH_EHL_SCENE[head])
                continue
        if not skip:
            out.append(line)
    for head, body in ROUGH_EHL_SCENE.items():
        if head not in default_text:
            out += [head, body]
    text = "\n".join(out) + "\n"
    return text.replace('name = "seed000_table1"', 'name = "rough_ehl_small"', 1)


def _is_drivetrain(path: Path) -> bool:
    """A drivetrain scene (``[drivetrain]``: several stages, gearfmu.stages), not a gear-pair scene."""
    return any(line.strip() == "[drivetrain]" for line in path.read_text().splitlines())


def scene_list(spec: str, checkout_a: Path, tmp: Path):
    """[(label, scene path or None)] of ``--scenes``."""
    out = []
    for item in spec.split(","):
        if item == "default":
            out.append(("default", None))
        elif item == "examples":
            out += [(p.stem, str(p)) for p in sorted((checkout_a / "examples" / "scenes").glob("*.toml"))
                    if not _is_drivetrain(p)]
        elif item == "rough_ehl":
            text = (checkout_a / "gearfmu" / "scene" / "data" / "default_scene.toml").read_text()
            path = tmp / "rough_ehl_small.toml"
            path.write_text(rough_ehl_scene(text))
            out.append(("rough_ehl_small", str(path)))
        else:
            out.append((Path(item).stem, str(Path(item).resolve())))
    return out



def run_checkout(checkout: Path, out: Path, runtimes: str, bench_full: bool, scenes, fmi_versions: str) -> dict:
    res = subprocess.run([sys.executable, "-c", CHILD, str(checkout), str(out), runtimes, "1" if bench_full else "0",
                          json.dumps(scenes), fmi_versions],
                         cwd=tempfile.gettempdir(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
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
    ap.add_argument("--scenes", default="default,examples,rough_ehl",
                    help="comma-separated: default, examples, rough_ehl or scene files")
    ap.add_argument("--fmi-versions", default="2,3", help="FMI versions of the standalone FMU")
    ap.add_argument("--bench-full", action="store_true", help="the benchmark at its own settings (long)")
    ap.add_argument("--keep", type=Path, help="keep the two .npz files in this folder")
    ap.add_argument("--reuse-a", action="store_true", help="with --keep: take A.npz from there when it exists")
    args = ap.parse_args(argv)
    if args.reuse_a and args.keep is None:
        ap.error("--reuse-a needs --keep DIR")
    with tempfile.TemporaryDirectory() as d:
        scenes = scene_list(args.scenes, args.a.resolve(), Path(d))
        d = args.keep or Path(d)
        d.mkdir(parents=True, exist_ok=True)
        info = {}
        for tag, path in (("A", args.a), ("B", args.b)):
            if tag == "A" and args.reuse_a and (d / "A.npz").is_file():
                info[tag] = {"gearfmu": f"{path} (reused {d / 'A.npz'})"}
                continue
            print(f"{tag}: {path} ...", file=sys.stderr, flush=True)
            info[tag] = run_checkout(path.resolve(), d / f"{tag}.npz", args.runtimes, args.bench_full, scenes,
                                     args.fmi_versions)
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
