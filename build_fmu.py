#!/usr/bin/env python3
"""Build a gear FMU from a scene, run it through fmpy and the native solver, report.

    python build_fmu.py                      # the default scene -> build/<model>.fmu (all-C runtime,
                                             # binaries for linux64, aarch64-linux, win64, darwin64)
    python build_fmu.py SCENE.toml -o OUT.fmu
    python build_fmu.py --runtime pythonfmu  # the Python runtime over the same C kernel
    python build_fmu.py examples/scenes/gearbox_two_stage.toml   # a drivetrain scene: the gearbox FMU,
                                             # against the native gearbox solver (docs/gearbox.md)

The report: the FMU's runtime, FMI version and platforms (and any platform that
could not be built, with the reason), fmpy validation problems, the largest and RMS difference per
output between the FMU and the native solver on the same inputs and steps,
and the wall time of each.  Add --json for a machine-readable report.
"""
import argparse
import json
import sys
from pathlib import Path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scene", nargs="?", help="scene TOML (default: gearfmu's default scene)")
    ap.add_argument("-o", "--output", help="FMU path (default build/<model_name>.fmu)")
    ap.add_argument("--runtime", choices=("standalone", "pythonfmu"),
                    help="FMU runtime (default: the scene's fmu.runtime, standalone unless set)")
    ap.add_argument("--fmi-version", type=int, choices=(2, 3), default=2,
                    help="FMI version of the FMU (default 2; 3: FMI 3.0 Co-Simulation, standalone runtime)")
    ap.add_argument("--json", action="store_true", help="print the report as JSON")
    args = ap.parse_args(argv)

    from gearfmu.fmu.compare import validate_fmu_against_native
    from gearfmu.fmu.summary import read_summary
    from gearfmu.pipeline import build, gear_torque_for, is_drivetrain_file, load

    if args.scene is not None and is_drivetrain_file(args.scene):
        return _gearbox(args)
    try:
        if args.scene is not None and not Path(args.scene).exists():
            raise ValueError(f"SCENE: file not found: {args.scene}")
        scene = load(args.scene)
        out = Path(args.output or f"build/{scene.fmu.model_name}.fmu")
        res = build(scene, out, progress=not args.json, runtime=args.runtime, fmi_version=args.fmi_version)
    except ValueError as exc:
        print(f"build_fmu: {exc}", file=sys.stderr)
        return 2
    summary = read_summary(res.fmu_path)
    if not args.json:
        print(f"built {res.fmu_path}: tables {res.tables_wall_s:.2f} s, FMU packaging {res.build_wall_s:.2f} s")
        print(summary.line())
    t1 = scene.operating.torque_Nm
    native_kwargs = dict(
        max_step_s=res.max_step_s, pinion_torque_Nm=t1, gear_torque_Nm=gear_torque_for(res.tables, t1),
        pinion_speed_start_rad_s=scene.operating.speed_rad_s, damping_ratio=scene.fmu.damping_ratio,
        damping_model=scene.solver.damping_model)
    rep = validate_fmu_against_native(res.fmu_path, res.tables, native_kwargs=native_kwargs,
                                      stop_time_s=scene.fmu.stop_time_s,
                                      comm_step_s=scene.fmu.output_interval_s)
    rep["scene"] = scene.name
    return _report(rep, res, summary, args.json)


def _gearbox(args) -> int:
    """A drivetrain scene: its gearbox FMU against the native gearbox solver."""
    from gearfmu.fmu.gearbox_build import variables_of_fmu
    from gearfmu.fmu.gearbox_compare import validate_gearbox_fmu
    from gearfmu.fmu.summary import read_summary
    from gearfmu.pipeline import build_drivetrain_fmu
    from gearfmu.scene.drivetrain import load_drivetrain

    try:
        scene = load_drivetrain(args.scene)
        out = Path(args.output or f"build/{scene.model_name}.fmu")
        res = build_drivetrain_fmu(scene, out, progress=not args.json, runtime=args.runtime,
                                   fmi_version=args.fmi_version)
    except ValueError as exc:
        print(f"build_fmu: {exc}", file=sys.stderr)
        return 2
    summary = read_summary(res.fmu_path)
    if not args.json:
        print(f"built {res.fmu_path}: tables {res.tables_wall_s:.2f} s, FMU packaging {res.build_wall_s:.2f} s")
        print(summary.line())
    rep = validate_gearbox_fmu(res.fmu_path, res.model, res.settings, variables_of_fmu(res.model, res.settings),
                               scene_text=scene.text)
    rep["scene"] = scene.name
    return _report(rep, res, summary, args.json)


def _report(rep, res, summary, as_json) -> int:
    from gearfmu.cli import print_report

    rep["tables_wall_s"] = res.tables_wall_s
    rep["fmu_build_wall_s"] = res.build_wall_s
    rep["fmu_contents"] = {"summary": summary.line(), "runtime": summary.runtime, "fmi_version": summary.fmi_version,
                  "needs_execution_tool": summary.needs_execution_tool, "platforms": summary.platforms,
                  "not_built": summary.missing}
    if as_json:
        print(json.dumps(rep, indent=1))
    else:
        print_report(rep)
    return 0 if not rep["fmpy_problems"] and not rep["failed"] else 1


if __name__ == "__main__":
    sys.exit(main())
