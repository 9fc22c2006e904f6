"""The gearfmu command line: spur and helical gear pairs to FMI 2.0/3.0 Co-Simulation and Model Exchange FMUs.

  gearfmu build    [SCENE] [-o OUT.fmu] [--runtime standalone|pythonfmu] [--platforms LIST] [--fmi-version 2|3]
                   [--fmi3-outputs array|scalar] [--interface both|cs|me] [--me-node-events E] [--reference-results DIR]
                                             scene -> tables -> FMU (DIR: its FMI Cross-Check set)
  gearfmu build    [SCENE] --tables T.csv [--tables-meta M.toml]           imported tables -> FMU
  gearfmu tables   [SCENE] [-o OUT.gtab]     compute, save (.gtab, .csv + .meta.toml) and plot tables
  gearfmu simulate [SCENE] [--backend native|fmu --fmu F] [--stop-time S] [--output-interval S]
                                             native solver (default) or an FMU; CSV + PNG
  gearfmu validate [SCENE] [--fmu F] [--stop-time S] [--output-interval S] [--tolerance R] [--json]
                                             an FMU against the native solver
  gearfmu bench accuracy [--case NAME] [--json] [--png P]   speed against error
  gearfmu ssp      [SCENE] [-o OUT.ssp] [--variant NAME:PARAM=VALUE] [--runtime R] [--platforms LIST]
                   [--fmi-version 2|3] [--coupling flange|shaft] [--comm-step S]
                                             SSP package with variants (a drivetrain scene: stage FMUs)
  gearfmu plan     [SCENE] [--json] [--fmu]  fidelity plan: what the scene needs (docs/plan.md)
  gearfmu modes    [SCENE] [-o OUT.json] [--json] [--max-speed-rpm N]
                                             natural frequencies, strain energy, Campbell diagram (PNG + JSON)
  gearfmu crosscheck FMU DIR [--model NAME] [--rel-tol X]
                                             any FMU against an FMI Cross-Check set (docs/fmu_import.md)

A SCENE with a top-level [drivetrain] table is a gearbox (docs/gearbox.md): build makes its gearbox
FMU (standalone C runtime), validate compares that FMU with the native gearbox solver, simulate runs
the native gearbox solver on it, modes gives its modes, ssp makes an SSP of stage FMUs.

SCENE defaults to the default scene (the Zhao et al. 2022 Table 1 pair).  Every
command exits with status 2 and a one-line message naming the problem on
bad input (an invalid scene, a missing, damaged or wrong kind of file, a bad
option value, an output path that cannot be written).  GEARFMU_DEBUG=1 adds
the traceback behind that line.
"""
from __future__ import annotations

import argparse
import io
import json
import os
import sys
import tempfile
import time
import traceback
import zipfile
from pathlib import Path
import contextlib

import numpy as np

from .common.executors import add_scheduler_option, cluster
from .common.progress import notice, reporting, ticking
from .common.vocabulary import (DEFAULT_FMI3_OUTPUTS, DEFAULT_SSP_COUPLING, FMI3_OUTPUTS, FMU_INTERFACES,
                                ME_NODE_EVENTS, RUNTIMES, SSP_COUPLINGS)
from .contact.base import FLAG_MEANINGS
from .dynamics.native import write_columns_csv
from .fmu.compare import (native_columns, output_names, output_units, run_fmu, FmuMismatchError, open_fmu,
                          DEFAULT_TOLERANCE)
from .fmu.crosscheck import main as crosscheck_main, write_reference_results
from . import pipeline
from .pipeline import load, build, simulate_native
from .ssp import parse_variant, ssp_fmu_bytes, ssp_fmu_name, ssp_from_drivetrain, ssp_from_scene
from .assembly import table_cache
from .tables.table_import import load_tables_file, REQUIRED, sidecar_path, tables_to_csv
from .fmu.crossbuild import parse_platforms
from .fmu.summary import fmu_summary


class CliError(Exception):
    pass


def _input_file(path, what: str) -> Path:
    """``path`` as an existing regular file (CliError naming ``what`` and the file otherwise)."""
    p = Path(path)
    if not p.exists():
        raise CliError(f"{what}: file not found: {p}")
    if not p.is_file():
        raise CliError(f"{what}: {p} is a directory, not a file")
    return p


def _output_file(path, what: str) -> Path:
    """``path`` as a file that can be written: its folder is created when missing; CliError
    naming ``what`` and the path when it is a directory or its folder cannot be written.
    Checked before any work, so a bad output path never costs a computation."""
    p = Path(path)
    if p.is_dir():
        raise CliError(f"{what}: {p} is a directory; give a file path")
    for a in p.parents:
        if a.exists():
            if not a.is_dir():
                raise CliError(f"{what}: cannot write {p}: {a} is a file, not a folder")
            break
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=p.parent):
            pass
    except OSError as exc:
        raise CliError(f"{what}: cannot write {p}: folder {p.parent}: {exc.strerror or exc}") from None
    return p


def _debug() -> bool:
    """GEARFMU_DEBUG set (and not 0): show the traceback behind a one-line error."""
    return os.environ.get("GEARFMU_DEBUG", "") not in ("", "0")


@contextlib.contextmanager
def _reading(what: str, path):
    """Around the reading of a file the user handed over (``what``: the argument).  The readers
    name the file and the reason; this makes sure of it: a ValueError or OSError whose message
    does not name the file gets ``what`` and the file in front, and an exception no reader
    foresaw becomes one line naming the file with a hint (GEARFMU_DEBUG=1: the traceback)."""
    try:
        yield
    except CliError:
        raise
    except (ValueError, OSError) as exc:
        text = _one_line(exc)
        if path is None or Path(path).name in text:
            raise
        raise CliError(f"{what} {path}: {text}") from exc
    except Exception as exc:  # noqa: BLE001 - last resort for a file a reader did not foresee
        first = (str(exc).strip().splitlines() or [""])[0]
        raise CliError(f"{what} {path}: cannot be read ({type(exc).__name__}{': ' + first if first else ''}); "
                       "is it the right kind of file, and intact? (GEARFMU_DEBUG=1 shows where it failed)") from exc


def _scene(path):
    with _reading("SCENE", path):
        if path is not None:
            _scene_file(path)
        return load(path)


def _positive(name):
    """argparse type: a positive finite float.  The messages leave out ``name``: argparse
    already starts them with "argument <option>:"."""
    def conv(text):
        try:
            v = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number: {text!r}")
        if not (v > 0 and v < float("inf")):
            raise argparse.ArgumentTypeError(f"must be a positive finite number, got {text}")
        return v
    return conv


def _tolerance(text):
    """argparse type of ``--tolerance``: a finite float >= 0."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}")
    if not (v >= 0 and v < float("inf")):
        raise argparse.ArgumentTypeError(f"must be a finite number >= 0, got {text}")
    return v


def _fmu(path):
    """The FMU of ``--fmu``, opened (CliError naming the file and what is wrong otherwise)."""
    try:
        with _reading("--fmu", path):
            return open_fmu(path)
    except FmuMismatchError as exc:
        raise CliError(f"--fmu: {exc}") from None


def _build_drivetrain(args) -> int:
    """gearfmu build DRIVETRAIN.toml: the gearbox FMU (docs/gearbox.md "The gearbox FMU")."""
    me = pipeline.check_gearbox_fmu_runtime(args.runtime, args.interface, args.me_node_events)
    _, scene = _any_scene(args.scene)
    for given, option in ((args.tables, "--tables"), (args.tables_meta, "--tables-meta"),
                          (args.reference_results, "--reference-results")):
        if given:
            raise CliError(f"{option}: not offered for a drivetrain scene (its stages compute their own tables; "
                           "the gearbox FMU carries its reference result in resources/validation/)")
    out = _output_file(args.output or f"build/{scene.model_name}.fmu", "--output")
    platforms = parse_platforms(args.platforms) if args.platforms is not None else None
    if not args.quiet:
        for note in scene.notes:
            print(f"gearfmu: {note}", file=sys.stderr)
    res = pipeline.build_drivetrain_fmu(scene, out, progress=not args.quiet, runtime=args.runtime,
                                        platforms=platforms, fmi_version=args.fmi_version,
                                        fmi3_outputs=args.fmi3_outputs, allow_large=args.allow_large, model_exchange=me)
    m = res.model
    what = (f"gearbox of {len(m.meshes)} stages, {len(m.shafts)} elastic shafts, {m.n_bodies} bodies"
            if not scene.planetaries else f"planetary drivetrain of {pipeline.describe_model(m)}")
    print(f"built {res.fmu_path} (tables {res.tables_wall_s:.2f} s, FMU {res.build_wall_s:.2f} s, {what}, "
          f"{res.settings.integrator}, max internal step {res.settings.max_step_s:.3g} s)")
    print(fmu_summary(res.fmu_path))
    return 0


def cmd_build(args) -> int:
    if args.scene is not None and pipeline.is_drivetrain_file(args.scene):
        return _build_drivetrain(args)
    scene = _scene(args.scene)
    out = _output_file(args.output or f"build/{scene.fmu.model_name}.fmu", "--output")
    tables = None
    if args.tables:  # imported tables instead of the scene's physics
        paths = _tables_args(args.tables, args.tables_meta)
        with _reading("--tables", paths[0]):
            tables = load_tables_file(*paths)
    platforms = None
    if args.platforms is not None:
        platforms = parse_platforms(args.platforms)
    res = build(scene, out, progress=not args.quiet, runtime=args.runtime, tables=tables, platforms=platforms,
                estimate_accuracy=not args.no_estimate, allow_large=args.allow_large, fmi_version=args.fmi_version,
                fmi3_outputs=args.fmi3_outputs, interface=args.interface, me_node_events=args.me_node_events)
    cached = _from_cache(res.tables) if not args.tables else ""
    print(f"built {res.fmu_path} (tables {res.tables_wall_s:.2f} s{cached}, "
          f"FMU {res.build_wall_s:.2f} s, "
          f"{res.tables.slots} pair slots, max internal step {res.max_step_s:.3g} s)")
    if res.estimate is not None:
        print(f"{res.estimate.summary()}; actual FMU {res.fmu_path.stat().st_size / 1e6:.3g} MB")
    print(fmu_summary(res.fmu_path))
    _print_accuracy(res.verified_envelope)
    _print_contact(res.tables)
    if args.reference_results:
        paths = write_reference_results(res.fmu_path, args.reference_results)
        print(f"reference results (FMI Cross-Check set): {', '.join(p.name for p in paths.values())} in "
              f"{Path(args.reference_results)}")
    return 0


def _from_cache(tables) -> str:
    """' from the table cache' when the tables were read back (gearfmu.assembly.table_cache)."""
    return " from the table cache" if "table_cache" in (tables.provenance or {}) else ""


def cmd_crosscheck(args) -> int:
    argv = [args.fmu, args.set_dir] + (["--model", args.model] if args.model else []) + \
        (["--rel-tol", repr(args.rel_tol)] if args.rel_tol is not None else [])
    return crosscheck_main(argv)


def _print_accuracy(ve) -> None:
    """One line on the built model's error against full fidelity over the envelope (docs/plan.md)."""
    if not ve:
        return
    if ve.get("error"):
        print(f"accuracy: no estimate of the error against full fidelity ({ve['error']})")
        return
    w = ve.get("worst_at") or {}
    label = ("ESTIMATE (cheap search) of the scene as written" if ve["kind"] == "as-written estimate"
             else "fidelity plan, verified")
    print(f"accuracy, {label} against full fidelity over the envelope: worst DTE {ve['worst_dte_rel']:.3g}, "
          f"mesh force {ve['worst_mesh_force_rel']:.3g} (rms(diff)/rms(full); max/range "
          f"{ve['worst_dte_max_rel']:.3g} / {ve['worst_mesh_force_max_rel']:.3g}) at {w.get('case')}, "
          f"{w.get('torque_Nm', float('nan')):.4g} N*m, {w.get('speed_rpm', float('nan')):.5g} rpm; "
          f"{'within' if ve['within_target'] else 'ABOVE'} the target {ve['dte_target_rel']:g} / "
          f"{ve['mesh_force_target_rel']:g}" + ("" if ve["kind"] != "as-written estimate" else
                                                 " (add [accuracy] to build the planned model instead)"))


def _tables_args(tables, meta):
    """(tables path, sidecar path or None) of ``build --tables T [--tables-meta M]``: a CSV's
    sidecar defaults to the one ``gearfmu tables`` writes beside it (T.meta.toml)."""
    t = Path(tables)
    if not t.exists():
        raise CliError(f"--tables: file not found: {t}")
    if t.suffix.lower() != ".csv":
        return t, meta
    _input_file(t, "--tables")
    if meta is not None:
        return t, _input_file(meta, "--tables-meta")
    found = sidecar_path(t)
    if not found.is_file():
        raise CliError(f"--tables {t}: no sidecar {found.name} beside it; give --tables-meta M.toml, a TOML "
                       f"file with {', '.join(REQUIRED)} (docs/tables.md 'CSV import')")
    return t, found


def _print_contact(tables) -> None:
    """One line on the contact model the tables were computed with, from their provenance: the
    environment the scene passed (lubricant eta0, pinion speed) for every load-dependent model,
    and the flagged contact requests, counted per reason with what the tables hold there."""
    c = tables.provenance.get("contact")
    if not c:
        return
    rows = c.get("load_iteration", {}).get("rows", [])
    fails = sum(r.get("failures", 0) for r in rows)
    by = {}
    for r in rows:
        for st, n in (r.get("failures_by_status") or {}).items():
            by[st] = by.get(st, 0) + n
    eta = c.get("eta0_Pas")
    flagged = ""
    if fails:
        why = "; ".join(f"{n} {st}: {FLAG_MEANINGS.get(st, st)}" for st, n in by.items()) or \
            "contact requests the model could not answer as asked"
        flagged = (f", {fails} flagged points (flagged = (position, slice load) requests of the load-sharing "
                   f"iteration, summed over the torque rows: {why}; tables' provenance 'contact.load_iteration')")
    print(f"contact model {c.get('model')}: eta0 {eta if eta is None else format(eta, '.4g')} Pa s, "
          f"pinion speed {c.get('speed_rad_s', float('nan')):.4g} rad/s, {c.get('solves', 0)} contact solves"
          + flagged + (", helical: normal-section requests per slice" if "helical_normal_section" in c else ""))


def cmd_tables(args) -> int:
    from .plots import plot_tables  # matplotlib: loaded only by the plotting commands


    scene = _scene(args.scene)
    out = _output_file(args.output or f"build/{scene.fmu.model_name}.gtab", "--output")
    for extra in (".png", ".csv"):
        _output_file(out.with_suffix(extra), "--output")
    t0 = time.perf_counter()
    tables = pipeline.compute_tables(scene, progress=not args.quiet, allow_large=args.allow_large)
    wall = time.perf_counter() - t0
    with ticking(f"writing {out}, its plot and its CSV form"):
        tables.save(out)
        flat, note = tables, ""
        if tables.has_temperature_axis:  # the plot and the CSV form have no temperature axis
            flat = tables.at_temperature(tables.default_temperature_C)
            note = f" at {tables.default_temperature_C:g} degC (the .gtab keeps the temperature axis)"
        png = plot_tables(flat, out.with_suffix(".png"))
        csv, meta = tables_to_csv(flat, out.with_suffix(".csv"), sidecar_path(out.with_suffix(".csv")))
    print(f"tables {out} ({tables.slots} slots x {tables.n_phi} angles x {tables.n_torque} torques, "
          f"{wall:.2f} s{_from_cache(tables)}); plot {png}; csv {csv} with sidecar {meta}{note} (build --tables {csv})")
    print(f"mean mesh stiffness {tables.k_mean_N_per_m:.4e} N/m, contact ratio {tables.contact_ratio:.4f}")
    _print_contact(tables)
    return 0


def _any_scene(path):
    """("drivetrain", DrivetrainScene) or ("pair", Scene) of SCENE (docs/gearbox.md)."""
    with _reading("SCENE", path):
        if path is not None:
            _scene_file(path)
        return pipeline.load_any(path)


def _scene_file(path) -> Path:
    p = _input_file(path, "SCENE")
    if not p.read_bytes().strip():
        raise CliError(f"SCENE: {p} is empty (a scene needs [scene], [gears] and [operating]; docs/scene.md)")
    return p


def _gearbox(kind, scene, args):
    """The gearbox model of a drivetrain or pair scene (its tables computed; the notes of a drivetrain
    -- replaced operating points, torque-axis warnings -- on stderr)."""
    if kind == "drivetrain":
        for note in scene.notes:
            print(f"gearfmu: {note}", file=sys.stderr)
        tables = pipeline.stage_tables(scene, progress=not args.quiet, allow_large=args.allow_large)
        return pipeline.drivetrain_model(scene, tables, damping_ratio=getattr(args, "damping_ratio", None),
                                         progress=not args.quiet)
    tables = pipeline.compute_tables(scene, progress=not args.quiet, allow_large=args.allow_large)
    return pipeline.pair_model(scene, tables)


def _simulate_drivetrain(args, scene) -> int:
    from .plots import plot_gearbox_simulation, plot_planetary_simulation  # matplotlib: the plotting commands only

    if args.backend != "native" or args.fmu:
        raise CliError("--backend: a drivetrain scene runs with the native gearbox solver only (--backend native)")
    out = _output_file(args.output or f"out/{scene.model_name}_native.csv", "--output")
    _output_file(out.with_suffix(".png"), "--output")
    model = _gearbox("drivetrain", scene, args)
    res = pipeline.simulate_drivetrain(scene, model, stop_time_s=args.stop_time, comm_step_s=args.output_interval,
                                         progress=not args.quiet)
    res.to_csv(out)
    plot = plot_planetary_simulation if scene.planetaries else plot_gearbox_simulation
    png = plot(res, model, out.with_suffix(".png"), title=f"{scene.name} (native solver)")
    if "diverged_at_step" in res.info:
        print(f"gearfmu: the state turned non-finite at step {res.info['diverged_at_step']}; the rows after it are "
              "NaN", file=sys.stderr)
    print(f"simulated {res.time_s[-1]:.6g} s of {scene.name} ({pipeline.describe_model(model)}; "
          f"{res.integrator}, step {res.step_s:.3g} s, {res.info['events']} events) in {res.wall_s:.3f} s -> "
          f"{out}, {png}")
    return 0


def cmd_modes(args) -> int:
    from .plots import plot_campbell  # matplotlib: loaded only by the plotting commands

    kind, scene = _any_scene(args.scene)
    name = scene.model_name if kind == "drivetrain" else scene.fmu.model_name
    out = _output_file(args.output or f"out/{name}_modes.json", "--output")
    png = _output_file(out.with_suffix(".png"), "--output")
    with _logs_to_stderr(args.json):
        model = _gearbox(kind, scene, args)
    res, cb = pipeline.modes_report(kind, scene, model, max_speed_rpm=args.max_speed_rpm)
    report = {"scene": scene.name, "kind": kind, **res.to_dict(), "campbell": cb}
    out.write_text(json.dumps(report, indent=1), encoding="utf-8")
    plot_campbell(cb, png, title=f"{scene.name}: Campbell diagram (modes at {res.reference_torque_Nm:.4g} N*m)")
    if args.json:
        print(json.dumps(report, indent=1))
        return 0
    print("\n".join(pipeline.modes_lines(scene.name, model, res, cb)))
    print(f"wrote {out}, {png}")
    return 0


def cmd_simulate(args) -> int:
    from .plots import plot_simulation  # matplotlib: loaded only by the plotting commands

    if args.scene is not None and pipeline.is_drivetrain_file(args.scene):
        return _simulate_drivetrain(args, _any_scene(args.scene)[1])
    scene = _scene(args.scene)
    stop = args.stop_time or scene.fmu.stop_time_s
    step = args.output_interval or scene.fmu.output_interval_s
    if args.backend == "fmu":
        if not args.fmu:
            raise CliError("--fmu: required with --backend fmu")
        fmu = _fmu(args.fmu)
    out = _output_file(args.output or f"out/{scene.fmu.model_name}_{args.backend}.csv", "--output")
    _output_file(out.with_suffix(".png"), "--output")
    if args.backend == "native":
        tables = pipeline.compute_tables(scene, progress=not args.quiet, allow_large=args.allow_large)
        notice(f"simulating {stop:g} s with the native solver")
        res = simulate_native(scene, tables, stop_time_s=stop, comm_step_s=step,
                              damping_ratio=args.damping_ratio)
        time_s, cols, slots, wall = res.time_s, native_columns(res, tables.slots), tables.slots, res.wall_s
    else:
        slots = sum(1 for n in fmu.variable_names if n.startswith("pair_force["))
        missing = [n for n in output_names(slots) if n not in fmu.variable_names]
        if not slots or missing:
            raise CliError(f"--fmu: {args.fmu}: not a gearfmu FMU (no outputs {', '.join(missing[:3]) or 'pair_force[1]'})")
        sv = {} if args.damping_ratio is None else {"damping_ratio": args.damping_ratio}
        run = run_fmu(args.fmu, stop_time_s=stop, comm_step_s=step, start_values=sv,
                      names=output_names(slots))
        time_s, cols, wall = run.time_s, run.columns, run.wall_s
    units = output_units(slots)  # the CSV layout of docs/native.md and docs/cli.md

    class _R:  # the plot wants attributes
        pass

    r = _R()
    r.time_s, r.dte, r.mesh_force = time_s, cols["dte"], cols["mesh_force"]
    r.pair_force = np.column_stack([cols[f"pair_force[{i + 1}]"] for i in range(slots)])
    r.load_sharing = np.column_stack([cols[f"load_sharing[{i + 1}]"] for i in range(slots)])
    with ticking(f"writing {out} and its plot"):
        write_columns_csv(out, {"time": ("s", time_s), **{n: (u, cols[n]) for n, u in units.items()}})
        png = plot_simulation(r, out.with_suffix(".png"), title=f"{scene.name} ({args.backend})")
    print(f"simulated {stop} s with {args.backend} in {wall:.3f} s -> {out}, {png}")
    return 0


def _logs_to_stderr(json_mode: bool):
    """With --json, whatever fmpy prints while running FMUs (their log messages, e.g. the one
    warning per input outside the verified envelope, docs/fmu.md) goes to stderr, so that stdout
    is the JSON report alone."""
    return contextlib.redirect_stdout(sys.stderr) if json_mode else contextlib.nullcontext()


def cmd_validate(args) -> int:
    with _logs_to_stderr(args.json):
        rep = _validate(args)
    if args.json:
        print(json.dumps(rep, indent=1))
    else:
        print_report(rep)
    for name, rel in rep["failed"].items():
        v = rep["outputs"][name]
        print(f"gearfmu: validate: {name} differs by {v['max_abs_diff']:.3e} = {rel:.3e} of its range "
              f"{v['range']:.4g} (tolerance {rep['tolerance']:g})", file=sys.stderr)
    return 0 if not rep["fmpy_problems"] and not rep["failed"] else 1


def _validate(args) -> dict:
    """gearfmu validate: the FMU (--fmu, else built) against the native solver (:func:`gearfmu.pipeline.validate`;
    a drivetrain scene: its gearbox FMU against the native gearbox solver, :func:`gearfmu.pipeline.validate_drivetrain`)."""
    drivetrain = args.scene is not None and pipeline.is_drivetrain_file(args.scene)
    scene = _any_scene(args.scene)[1] if drivetrain else _scene(args.scene)
    fmu = _fmu(args.fmu) if args.fmu else None
    name = scene.model_name if drivetrain else scene.fmu.model_name
    out = None if fmu is not None else _output_file(f"build/{name}.fmu", "validate")
    run = pipeline.validate_drivetrain if drivetrain else pipeline.validate
    return run(scene, fmu, out_path=out, tolerance=args.tolerance, stop_time_s=args.stop_time,
               comm_step_s=args.output_interval, progress=not args.quiet, allow_large=args.allow_large)


def print_report(rep: dict) -> None:
    print(f"FMU {rep['fmu']} (scene {rep.get('scene', '?')})")
    probs = rep["fmpy_problems"]
    print(f"fmpy validation problems: {len(probs)}" + "".join(f"\n  - {p}" for p in probs))
    print(f"{rep['samples']} samples, communication step {rep['comm_step_s']:.3g} s, "
          f"internal step <= {rep['max_step_s']:.3g} s, stop time {rep['stop_time_s']:.3g} s")
    units = rep.get("units") or output_units(sum(1 for n in rep["outputs"] if n.startswith("pair_force[")))
    w = max([18] + [len(n) + 2 for n in rep["outputs"]])
    print(f"{'output':<{w}}{'unit':<7}{'max |FMU-native|':>18}{'RMS diff':>14}{'range':>14}{'max/range':>12}")
    for name, v in rep["outputs"].items():
        print(f"{name:<{w}}{units.get(name, '?'):<7}{v['max_abs_diff']:>18.3e}{v['rms_diff']:>14.3e}"
              f"{v['range']:>14.4g}{v['rel_max_diff']:>12.2e}")
    print("differences and range in the output's unit; range = max - min of the native solver's output over "
          "the run (its largest |value| when it is constant); max/range = max |FMU-native| / range, the "
          "quantity the tolerance applies to")
    print(f"wall time: native {rep['native_wall_s']:.4f} s, FMU (fmpy) {rep['fmu_wall_s']:.4f} s")
    if "failed" in rep:
        tol = rep.get("tolerance")
        print(f"FAILED: {len(rep['failed'])} output(s) beyond {tol:g} of their range: "
              + ", ".join(f"{k} {v:.3e}" for k, v in rep["failed"].items()) if rep["failed"]
              else f"PASSED: every output within {tol:g} of its range")


def _ssp_drivetrain(args) -> int:
    """gearfmu ssp DRIVETRAIN.toml: an SSP of stage FMUs (docs/gearbox.md "The SSP of stage FMUs")."""
    if args.variant:
        raise CliError("--variant: for a gear-pair scene's SSP; a drivetrain scene's SSP holds one FMU per stage")
    pipeline.check_gearbox_fmu_runtime(args.runtime)
    _, scene = _any_scene(args.scene)
    out = _output_file(args.output or f"build/{scene.model_name}.ssp", "--output")
    platforms = parse_platforms(args.platforms) if args.platforms is not None else None
    path = ssp_from_drivetrain(scene, out, coupling=args.coupling, comm_step_s=args.comm_step,
                               fmi_version=args.fmi_version, platforms=platforms, progress=not args.quiet,
                               allow_large=args.allow_large)
    with zipfile.ZipFile(path) as z:
        fmus = sorted(n[10:-4] for n in z.namelist() if n.startswith("resources/") and n.endswith(".fmu"))
    print(f"wrote {path}: {len(fmus)} FMUs ({', '.join(fmus)}), {args.coupling or DEFAULT_SSP_COUPLING} coupling, "
          f"communication step {args.comm_step or scene.output_interval_s:g} s; OSP angular mechanical ports in "
          "resources/*_OspModelDescription.xml and OspSystemStructure.xml")
    return 0


def cmd_ssp(args) -> int:
    if args.scene is not None and pipeline.is_drivetrain_file(args.scene):
        return _ssp_drivetrain(args)
    for opt, val in (("--coupling", args.coupling), ("--comm-step", args.comm_step)):
        if val is not None:
            raise CliError(f"{opt}: only for a drivetrain scene (an SSP of stage FMUs, docs/gearbox.md)")
    scene = _scene(args.scene)
    out = _output_file(args.output or f"build/{scene.fmu.model_name}.ssp", "--output")
    variants = dict(parse_variant(v) for v in args.variant) if args.variant else None
    platforms = parse_platforms(args.platforms) if args.platforms is not None else None
    path = ssp_from_scene(scene, out, variants=variants, progress=not args.quiet, fmi_version=args.fmi_version,
                          runtime=args.runtime, platforms=platforms)
    print(f"wrote {path}")
    print(f"its FMU ({ssp_fmu_name(path)}): {fmu_summary(io.BytesIO(ssp_fmu_bytes(path)))}")
    return 0


def cmd_plan(args) -> int:
    from .plan import format_report, plan_scene  # the planner: loaded only by the commands that plan
    scene = _scene(args.scene)
    if args.output is not None:
        d = Path(args.output)
        if d.exists() and not d.is_dir():
            raise CliError(f"--output: {d} is a file; give a folder for the FMUs of --fmu")
        _output_file(d / "probe", "--output")
    with _logs_to_stderr(args.json):
        plan = plan_scene(scene, progress=not args.quiet, measure_fmu=args.fmu, fmu_dir=args.output,
                          budget_runs=args.budget_runs, what_if=args.what_if)
    print(json.dumps(plan.to_dict(), indent=1) if args.json else format_report(plan))
    if not plan.within_target:  # a refused plan or a failed FMU confirmation is not a success
        print(f"gearfmu: plan of {scene.name} is not within its accuracy target over the envelope "
              f"(worst: {plan.verification.get('worst')}); see the report", file=sys.stderr)
        return 1
    return 0


def _fmu_options(parser) -> None:
    """--runtime, --platforms, --fmi-version: the FMU options of build and ssp."""
    parser.add_argument("--runtime", choices=RUNTIMES,
                        help="FMU runtime (default: the scene's fmu.runtime, standalone unless set); "
                             "standalone = FMI layer in C, no Python; pythonfmu = Python layer over the same C kernel")
    parser.add_argument("--platforms", metavar="LIST",
                        help="standalone runtime: binaries to build, comma-separated (x86_64-linux, aarch64-linux, "
                             "x86_64-windows, x86_64-darwin, aarch64-darwin, or linux64/win64/darwin64; default: "
                             "all five; docs/standalone.md 'Platforms')")
    parser.add_argument("--fmi-version", type=int, choices=(2, 3), default=2,
                        help="FMI version of the FMU (default 2; 3: FMI 3.0 Co-Simulation, standalone runtime)")


def _no_cache(parser) -> None:
    parser.add_argument("--no-cache", action="store_true",
                        help="compute the tables without reading or writing gearfmu's table cache "
                             "(docs/cli.md 'Table cache')")


def _allow_large(parser) -> None:
    parser.add_argument("--allow-large", action="store_true",
                        help="compute even when the estimated tables/FMU/build time exceed the limits (gearfmu.assembly.estimate)")


def cmd_bench(args) -> int:
    if args.png:
        _output_file(args.png, "--png")
    from .bench import main_accuracy  # bench: loads scipy.integrate (the reference solver), only for bench
    return main_accuracy(args)


def make_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="gearfmu", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True)

    b = sub.add_parser("build", help="build an FMU from a scene")
    b.add_argument("scene", nargs="?", help="scene TOML (default: the default scene)")
    b.add_argument("-o", "--output", help="FMU path (default build/<model_name>.fmu)")
    b.add_argument("-q", "--quiet", action="store_true")
    _fmu_options(b)
    b.add_argument("--fmi3-outputs", choices=FMI3_OUTPUTS, default=DEFAULT_FMI3_OUTPUTS,
                   help="FMI 3 FMU: pair_force and load_sharing as arrays (default) or as scalars pair_force_1 .. "
                        "(for hosts without array support; docs/standalone.md 'FMI 3.0')")
    b.add_argument("--interface", choices=FMU_INTERFACES, help="standalone runtime: the FMI interfaces: both "
                   "(default; Co-Simulation and Model Exchange), cs or me (docs/standalone.md 'Model Exchange')")
    b.add_argument("--me-node-events", choices=ME_NODE_EVENTS, help="Model Exchange's node events (docs/model.md)")
    b.add_argument("--reference-results", metavar="DIR",
                   help="also write the FMU's FMI Cross-Check set into DIR: <model>.fmu, _ref.csv, _in.csv, "
                        "_ref.opt (docs/fmu_import.md 'Reference results')")
    b.add_argument("--tables", help="tables .csv or .gtab instead of the scene's physics (docs/tables.md 'CSV import')")
    b.add_argument("--tables-meta", help="TOML sidecar with the scalars of a --tables CSV "
                                         "(default: T.meta.toml beside T.csv, as gearfmu tables writes it)")
    b.add_argument("--no-estimate", action="store_true",
                   help="skip the estimate of the as-written scene's error against full fidelity (scenes "
                        "without [accuracy]; docs/plan.md)")
    _allow_large(b)
    _no_cache(b)
    add_scheduler_option(b)
    b.set_defaults(func=cmd_build)

    cc = sub.add_parser("crosscheck", help="run an FMU against an FMI Cross-Check set (<model>_ref.csv, _in.csv, "
                                           "_ref.opt) and compare; exit 0 passed, 1 failed")
    cc.add_argument("fmu")
    cc.add_argument("set_dir")
    cc.add_argument("--model", help="the set's file prefix (default: the one *_ref.csv in the folder)")
    cc.add_argument("--rel-tol", type=_tolerance, help="agreement per column, fraction of its range "
                                                       "(default: the set's RelTol)")
    cc.set_defaults(func=cmd_crosscheck)

    be = sub.add_parser("bench", help="benchmarks: 'bench accuracy' = speed against error (gearfmu.bench)")
    be.add_argument("what", choices=("accuracy",))
    be.add_argument("--case", default="single_sided_impacts", help="hard case (gearfmu.bench.HARD_CASES)")
    be.add_argument("--json", action="store_true", help="print the report as JSON")
    be.add_argument("--png", help="write the Pareto plot (wall time against error) here")
    be.set_defaults(func=cmd_bench)

    t = sub.add_parser("tables", help="compute, save (.gtab; .csv + .meta.toml for build --tables) and plot "
                                      "(.png) the tooth-pair tables")
    t.add_argument("scene", nargs="?", help="scene TOML (default: the default scene)")
    t.add_argument("-o", "--output", help="table path (default build/<model_name>.gtab)")
    t.add_argument("-q", "--quiet", action="store_true")
    _allow_large(t)
    _no_cache(t)
    add_scheduler_option(t)
    t.set_defaults(func=cmd_tables)

    s = sub.add_parser("simulate", help="simulate with the native solver or an FMU; CSV and PNG out")
    s.add_argument("scene", nargs="?", help="scene TOML (default: the default scene)")
    s.add_argument("--backend", choices=("native", "fmu"), default="native")
    s.add_argument("--fmu", help="FMU to run with --backend fmu")
    s.add_argument("--stop-time", type=_positive("--stop-time"), help="s")
    s.add_argument("--output-interval", type=_positive("--output-interval"), help="communication step, s")
    s.add_argument("--damping-ratio", type=_positive("--damping-ratio"), help="1")
    s.add_argument("-o", "--output", help="CSV path")
    s.add_argument("-q", "--quiet", action="store_true")
    _allow_large(s)
    _no_cache(s)
    s.set_defaults(func=cmd_simulate)

    v = sub.add_parser("validate", help="run an FMU and the native solver on the same inputs and compare")
    v.add_argument("scene", nargs="?", help="scene TOML (default: the default scene)")
    v.add_argument("--fmu", help="an FMU built from SCENE (default: build one)")
    v.add_argument("--stop-time", type=_positive("--stop-time"))
    v.add_argument("--output-interval", type=_positive("--output-interval"))
    v.add_argument("--tolerance", type=_tolerance, default=DEFAULT_TOLERANCE,
                   help=f"largest |FMU - native| allowed, relative to each output's range (default "
                        f"{DEFAULT_TOLERANCE:g}); exit status 1 beyond it")
    v.add_argument("--json", action="store_true", help="print a machine-readable report")
    v.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
    _allow_large(v)
    _no_cache(v)
    v.set_defaults(func=cmd_validate)

    x = sub.add_parser("ssp", help="SSP package: the FMU, a system structure and .ssv parameter sets (variants)")
    x.add_argument("scene", nargs="?", help="scene TOML (default: the default scene)")
    _fmu_options(x)
    x.add_argument("-o", "--output", help="SSP path (default build/<model_name>.ssp)")
    x.add_argument("--variant", action="append", metavar="NAME:PARAM=VALUE[,...]",
                   help="a named parameter set (repeat; default nominal/damping_low/damping_high)")
    x.add_argument("--coupling", choices=SSP_COUPLINGS,
                   help=f"drivetrain scene: how the stage FMUs are coupled (default {DEFAULT_SSP_COUPLING}; "
                        "docs/gearbox.md 'The SSP of stage FMUs')")
    x.add_argument("--comm-step", type=_positive("--comm-step"),
                   help="drivetrain scene: the communication step the SSP is annotated with (s; default the "
                        "scene's run.output_interval_s)")
    x.add_argument("-q", "--quiet", action="store_true")
    _allow_large(x)
    _no_cache(x)
    x.set_defaults(func=cmd_ssp)

    pl = sub.add_parser("plan", help="fidelity plan: each modelling choice's error over the envelope, "
                                     "kept/dropped, cost (docs/plan.md)")
    pl.add_argument("scene", nargs="?", help="scene TOML (default: the default scene)")
    pl.add_argument("--json", action="store_true", help="print the report as JSON")
    pl.add_argument("--fmu", action="store_true",
                    help="also build the planned and the full-fidelity FMU (sizes, build times) and confirm the "
                         "plan through them with fmpy: steady, run-up, run-down, the search's worst point, "
                         "warm-up, duty cycle; a case above the target fails the plan (exit 1)")
    pl.add_argument("--budget-runs", type=int, default=None,
                    help="native runs the envelope search and its revisions may take (default "
                         "gearfmu.plan.DEFAULT_BUDGET_RUNS); when spent before a plan passes, the plan is refused")
    pl.add_argument("--what-if", action="store_true",
                    help="also measure the other contact models the scene allows (what-if rows; film tables are slow)")
    pl.add_argument("-o", "--output", help="directory for the FMUs of --fmu (default: a temporary one)")
    pl.add_argument("-q", "--quiet", action="store_true")
    _no_cache(pl)
    add_scheduler_option(pl)
    pl.set_defaults(func=cmd_plan)

    mo = sub.add_parser("modes", help="natural frequencies, mode shapes, strain energy per mesh and shaft, and "
                                      "the Campbell diagram (PNG + JSON) of a pair or drivetrain scene")
    mo.add_argument("scene", nargs="?", help="pair or drivetrain scene TOML (default: the default scene)")
    mo.add_argument("-o", "--output", help="JSON path (default out/<model_name>_modes.json; the PNG beside it)")
    mo.add_argument("--json", action="store_true", help="print the report as JSON")
    mo.add_argument("--max-speed-rpm", type=_positive("--max-speed-rpm"),
                    help="top of the Campbell diagram's motor speed axis (default 1.25 x the highest speed)")
    mo.add_argument("-q", "--quiet", action="store_true")
    _allow_large(mo)
    _no_cache(mo)
    mo.set_defaults(func=cmd_modes)
    return p


def _one_line(exc: BaseException) -> str:
    """The message of a user-facing error: CliError and the project's ValueErrors (SceneError,
    TableError, FmuMismatchError, ...) name the field or file; an OSError names its file."""
    if isinstance(exc, OSError) and exc.filename:
        return f"{exc.filename}: {exc.strerror or exc}"
    return str(exc)


def main(argv=None) -> int:
    args = make_parser().parse_args(argv)
    try:
        # --scheduler: the parallel work on that Dask cluster; --no-cache: tables computed afresh;
        # notices of the long phases on stderr unless -q (the bars follow each command's progress flag)
        with cluster(getattr(args, "scheduler", None)), table_cache.bypassed(getattr(args, "no_cache", False)), \
                reporting(not getattr(args, "quiet", False)):
            return args.func(args)
    except (CliError, ValueError, OSError) as exc:  # user-facing: one line, status 2
        if _debug():
            traceback.print_exc()
        print(f"gearfmu: {_one_line(exc)}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
