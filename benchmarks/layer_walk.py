#!/usr/bin/env python3
"""Measurement: following a scene through ``gearfmu.pipeline.build``, how often does the code go
back up a layer?

The layers are those of the import-linter "layers" contract in ``pyproject.toml``
(``[tool.importlinter]``, README "Architecture"): a module's layer is that of its top-level
module or package.  import-linter checks the imports; this script checks what the imports
cannot show, by a call trace (``sys.setprofile``) of ``pipeline.build(scene, ...)`` with the
table cache off (so that the tables are computed):

* **files entered**: the gearfmu source files in which a Python function ran;
* **moves between files**: the distinct (calling file, called file) pairs of the trace;
* **moves back up a layer**: the distinct places where running code reaches a layer it may not
  import -- a higher layer, or another package of its own independent layer (``a | b``):

  - a call from a file into a file of such a layer (a callback, or a method of an object that
    a higher layer handed down), counted per (called function, calling function);
  - a call that hands a function an object defined in such a layer (an instance of one of its
    classes, or one of its functions; looked for in the arguments and one level into tuples,
    lists and dicts): the function reads back up through it (e.g. a physics function reading a
    Scene's fields), counted per (function, parameter, the object's class).

Returning from a call is not a move.  The scenes cover the table builder's paths: ``default``
(the default scene: spur, Hertz, crowning-free), ``rough_ehl`` (rough EHL film grid),
``helical_ehl`` (a helical pair with the smooth EHL model on the normal section and a bulk
temperature axis) and ``oil_axis`` (smooth EHL with an oil-temperature axis, a non-standard gear
temperature); the last three are the default scene with the sections of :data:`SCENES` in place
of its own, on small grids.

Prints one JSON object: per scene and in total (union over the scenes) the three numbers, and the
list of moves back up a layer.  ``--checkout DIR`` measures another checkout of gearfmu (its
``pyproject.toml`` and package; e.g. the unchanged tree before a refactoring);
``--fresh-cache`` runs with an empty gearfmu cache folder (compiled objects and kernels built
again: slower, but the files entered and moves do not depend on what an earlier run left);
``--tables-only`` follows the scene through ``pipeline.compute_tables`` (the cost guard and the
tables: where a scene's physics options are read) instead of the whole build.

    python benchmarks/layer_walk.py [--checkout DIR] [--scenes default,rough_ehl,helical_ehl,oil_axis]
                                    [--fresh-cache] [--tables-only]
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import tomllib
import types
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: scenes besides the default: the default scene's text with these sections in place of its own
SCENES = {
    "rough_ehl": {"[mesh]": 'contact_model = "rough_ehl"\nslices = 4\nfoundation = true\n',
                  "[tables]": 'points_per_mesh = 16\ntorque_points = 1\nslots = "auto"\n',
                  "[roughness]": "level = 1\nfilm_position_nodes = 3\n"},
    "helical_ehl": {"[gears]": "module_mm = 6.0\npressure_angle_deg = 20.0\nface_width_mm = 44.0\n"
                               "backlash_um = 240.0\nhelix_angle_deg = 15.0\n",
                    "[mesh]": 'contact_model = "smooth_ehl"\nslices = 3\nfoundation = true\n',
                    "[operating]": "torque_Nm = 2000.0\nspeed_rpm = 2000.0\ntorque_range_Nm = [1000.0, 3000.0]\n",
                    "[tables]": 'points_per_mesh = 16\ntorque_points = 2\nslots = "auto"\n',
                    "[thermal]": "temperature_axis_C = [20.0, 60.0]\n"},
    "oil_axis": {"[mesh]": 'contact_model = "smooth_ehl"\nslices = 2\nfoundation = true\n',
                 "[tables]": 'points_per_mesh = 16\ntorque_points = 1\nslots = "auto"\n',
                 "[thermal]": 'temperature_axis_C = [40.0, 60.0, 80.0]\naxis_quantity = "oil"\n'
                              "pinion_temperature_C = 50.0\n"},
}


def with_sections(text: str, sections: dict) -> str:
    """``text`` (a scene) with each section of ``sections`` (header -> body) in place of its own
    (added when absent)."""
    out, skip = [], False
    for line in text.splitlines():
        head = line.strip()
        if head.startswith("["):
            skip = head in sections
            if skip:
                out += [head, sections[head]]
                continue
        if not skip:
            out.append(line)
    for head, body in sections.items():
        if head not in text:
            out += [head, body]
    return "\n".join(out) + "\n"


class Layers:
    """The layers contract of a checkout's pyproject.toml: which top-level name may import which."""

    def __init__(self, pyproject: Path):
        cfg = tomllib.loads(pyproject.read_text())
        contract = next(c for c in cfg["tool"]["importlinter"]["contracts"] if c["type"] == "layers")
        self.rank, self.group = {}, {}
        for i, layer in enumerate(contract["layers"]):
            independent = "|" in layer
            for name in layer.replace(":", "|").split("|"):
                self.rank[name.strip()] = len(contract["layers"]) - i      # higher number: higher layer
                self.group[name.strip()] = i if independent else None

    def may_not_import(self, low: str, high: str) -> bool:
        """True when top-level name ``low`` may not import ``high`` by the contract."""
        if low == high or low not in self.rank or high not in self.rank:
            return False
        if self.rank[high] > self.rank[low]:
            return True
        return self.rank[high] == self.rank[low] and self.group[low] is not None


def walk(checkout: Path = ROOT, scenes=("default", "rough_ehl", "helical_ehl", "oil_axis"),
         fresh_cache: bool = False, tables_only: bool = False) -> dict:
    """The measurement (module doc) of ``checkout``; its gearfmu must be the one imported.  The
    environment variables it sets (table cache off, cache folder) are restored after."""
    saved = {k: os.environ.get(k) for k in ("GEARFMU_NO_TABLE_CACHE", "GEARFMU_CACHE_DIR")}
    os.environ["GEARFMU_NO_TABLE_CACHE"] = "1"
    if fresh_cache:
        os.environ["GEARFMU_CACHE_DIR"] = tempfile.mkdtemp(prefix="gearfmu_layer_walk_")
    try:
        return _walk(Path(checkout).resolve(), scenes, tables_only)
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def _walk(checkout: Path, scenes, tables_only: bool) -> dict:
    if str(checkout) not in sys.path[:1]:
        sys.path.insert(0, str(checkout))
    import gearfmu
    from gearfmu import pipeline
    pkg = Path(gearfmu.__file__).resolve().parent
    if not pkg.is_relative_to(checkout):
        raise SystemExit(f"{checkout}: imported gearfmu is {pkg}")
    layers = Layers(checkout / "pyproject.toml")
    prefix = str(pkg) + os.sep

    def top_of_file(f: str) -> str:
        return Path(f).relative_to(pkg).parts[0].removesuffix(".py")

    def top_of_module(m) -> str:
        parts = (m or "").split(".")
        return parts[1] if parts[0] == "gearfmu" and len(parts) > 1 else ""

    def origins(v):
        if isinstance(v, (types.FunctionType, types.MethodType)):
            yield getattr(v, "__module__", ""), "function " + getattr(v, "__qualname__", "?")
            return
        yield type(v).__module__, type(v).__qualname__
        if isinstance(v, (tuple, list)):
            for x in v[:8]:
                yield type(x).__module__, type(x).__qualname__
        elif isinstance(v, dict):
            for x in list(v.values())[:16]:
                yield type(x).__module__, type(x).__qualname__

    def rel(f: str) -> str:
        return Path(f).relative_to(pkg).as_posix()

    default_text = (pkg / "scene" / "data" / "default_scene.toml").read_text()
    out = {"checkout": str(checkout), "followed": "pipeline.compute_tables" if tables_only else "pipeline.build",
           "scenes": {}}
    all_files, all_moves, all_up = set(), set(), set()
    for name in scenes:
        files, moves, up = set(), set(), set()

        def profile(frame, event, arg):
            if event != "call":
                return
            f = frame.f_code.co_filename
            if not f.startswith(prefix):
                return
            code = frame.f_code
            here = top_of_file(f)
            where = f"{rel(f)}:{code.co_qualname}"
            files.add(rel(f))
            caller = frame.f_back
            while caller is not None and not caller.f_code.co_filename.startswith(prefix):
                caller = caller.f_back
            if caller is not None and caller.f_code.co_filename != f:
                moves.add((rel(caller.f_code.co_filename), rel(f)))
                if layers.may_not_import(top_of_file(caller.f_code.co_filename), here):
                    up.add(("call", where, f"{rel(caller.f_code.co_filename)}:{caller.f_code.co_qualname}"))
            names = code.co_varnames[:code.co_argcount + code.co_kwonlyargcount
                                     + bool(code.co_flags & 0x04) + bool(code.co_flags & 0x08)]
            for i, a in enumerate(names):
                if i == 0 and a in ("self", "cls"):
                    continue
                v = frame.f_locals.get(a)
                for mod, qual in origins(v):
                    if layers.may_not_import(here, top_of_module(mod)):
                        up.add(("argument", f"{where}({a})", f"{mod}.{qual}"))

        if name == "default":
            path = None
        else:
            tmp = Path(tempfile.mkdtemp(prefix="gearfmu_layer_walk_"))
            path = tmp / f"{name}.toml"
            path.write_text(with_sections(default_text, SCENES[name]).replace(
                'name = "seed000_table1"', f'name = "layer_walk_{name}"', 1))
        scene = pipeline.load(None if path is None else str(path))
        with tempfile.TemporaryDirectory() as d:
            print(f"layer walk: {name} ...", file=sys.stderr, flush=True)
            sys.setprofile(profile)
            try:
                if tables_only:
                    pipeline.compute_tables(scene)
                else:
                    pipeline.build(scene, Path(d) / f"{name}.fmu", allow_large=True)
            finally:
                sys.setprofile(None)
        out["scenes"][name] = {"files_entered": len(files), "moves_between_files": len(moves),
                               "moves_back_up_a_layer": len(up)}
        all_files |= files
        all_moves |= moves
        all_up |= up
    out["total"] = {"files_entered": len(all_files), "moves_between_files": len(all_moves),
                    "moves_back_up_a_layer": len(all_up)}
    out["back_up"] = [{"kind": k, "at": a, "from": b} for k, a, b in sorted(all_up)]
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--checkout", type=Path, default=ROOT, help="the gearfmu checkout to measure")
    ap.add_argument("--scenes", default="default,rough_ehl,helical_ehl,oil_axis")
    ap.add_argument("--fresh-cache", action="store_true", help="an empty gearfmu cache folder")
    ap.add_argument("--tables-only", action="store_true", help="follow the scene through compute_tables only")
    args = ap.parse_args(argv)
    scenes = args.scenes.split(",")
    bad = [s for s in scenes if s != "default" and s not in SCENES]
    if bad:
        ap.error(f"--scenes: unknown {', '.join(bad)} (default, {', '.join(SCENES)})")
    print(json.dumps(walk(args.checkout, scenes, args.fresh_cache, args.tables_only), indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
