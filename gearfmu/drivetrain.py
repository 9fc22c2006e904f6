"""The main job on a drivetrain scene: scene -> every stage's tables -> gearbox model; its run and modes.

Wiring only (docs/gearbox.md): :func:`load_any` tells a drivetrain file (top-level
``[drivetrain]``) from a gear-pair scene; :func:`stage_tables` checks the estimated cost of
every stage (before computing any) and computes each stage's tables with
:func:`gearfmu.pipeline.compute_tables` at the stage's operating point (the drivetrain's,
:mod:`gearfmu.scene.drivetrain`); :func:`gearbox_model` builds the
:class:`gearfmu.gearbox.model.GearboxModel`; :func:`pair_model` makes the two-body gearbox of a
single pair scene (for ``gearfmu modes``); :func:`simulate_drivetrain` runs the native gearbox
solver with the scene's settings; :func:`modes_report` gives the modes and the Campbell data;
:func:`fmu_settings` and :func:`build_drivetrain_fmu` build the gearbox FMU of a drivetrain scene
(gearfmu.fmu.gearbox_build; docs/gearbox.md "The gearbox FMU").  A drivetrain with ``[[planetary]]``
stages builds every planetary stage's tables (:func:`planetary_stages`: gearfmu.assembly.planetary from
the geometry, gearfmu.assembly.planetary_lumped from published lumped parameters) and runs on the
planetary solver (:func:`drivetrain_model`, gearfmu.planetary; docs/planetary.md); it has no FMU yet.
"""
from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import List, Optional, Sequence, Tuple, Union

from .assembly.planetary import planetary_stage
from .assembly.planetary_lumped import lumped_stage
from .gear.phasing import parker_harmonic_excitation
from .gearbox.model import GearboxModel, Mesh, Shaft, build_gearbox
from .gearbox.modes import ModesResult, campbell, modes
from .planetary import modes as planetary_modes
from .planetary.model import PlanetaryModel, build_drivetrain as build_planetary_drivetrain
from .planetary.native import simulate as simulate_planetary
from .common.vocabulary import DEFAULT_FMI3_OUTPUTS
from .fmu.build_steps import FmuBuildError
from .fmu.gearbox_build import GearboxFmuSettings, build_gearbox_fmu, gearbox_settings
from .gearbox.native import GearboxResult, choose_max_step_s, simulate as simulate_gearbox
from .pipeline import compute_tables, load
from .scene.drivetrain import DrivetrainScene, is_drivetrain_file, load_drivetrain
from .scene.options import RPM_TO_RAD_S, Scene
from .assembly.estimate import BuildTooLargeError
from .scene.physics import check_build_cost

__all__ = ["load_any", "is_drivetrain_file", "stage_tables", "gearbox_model", "pair_model", "simulate_drivetrain", "modes_report",
           "PAIR_MESH_NAME", "fmu_settings", "build_drivetrain_fmu", "DrivetrainBuild", "check_fmu_runtime",
           "planetary_stages", "drivetrain_model", "describe_model", "modes_lines", "check_fmu_supported"]

#: the mesh name of a single pair scene seen as a gearbox (parts ``pair.pinion``, ``pair.gear``)
PAIR_MESH_NAME = "pair"


def load_any(path) -> Tuple[str, Union[DrivetrainScene, Scene]]:
    """("drivetrain", DrivetrainScene) for a file with a top-level [drivetrain] table, else
    ("pair", Scene) (None: the default pair scene)."""
    if path is not None and is_drivetrain_file(path):
        return "drivetrain", load_drivetrain(path)
    return "pair", load(path)


def _flat(tables):
    """Tables without a temperature axis: a stage with one runs at its default temperature."""
    if tables.has_temperature_axis:
        return tables.at_temperature(tables.default_temperature_C)
    return tables


def stage_tables(scene: DrivetrainScene, *, progress: bool = False, allow_large: bool = False) -> List:
    """Every stage's MeshTables (in stage order), each at its drivetrain operating point.  The
    cost estimate of every stage is checked first (gearfmu.assembly.estimate): a stage over the
    limits raises BuildTooLargeError naming the stage before any table is computed."""
    for s in scene.stages:
        try:
            check_build_cost(s.scene, allow_large=allow_large)
        except BuildTooLargeError as exc:
            raise BuildTooLargeError(f"stage {s.name!r} ({s.source}): {exc}") from None
    out = []
    for s in scene.stages:
        if progress:
            print(f"gearfmu: tables of stage {s.name} ({s.pinion_torque_Nm:.6g} N*m, "
                  f"{s.scene.operating.speed_rad_s / RPM_TO_RAD_S:.6g} rpm)", file=sys.stderr, flush=True)
        out.append(_flat(compute_tables(s.scene, progress=progress, allow_large=allow_large)))
    return out


def planetary_stages(scene: DrivetrainScene, *, progress: bool = False) -> List:
    """Every [[planetary]] stage of the scene as a gearfmu.tables.planetary.PlanetaryStage: its tables
    at the sun torque the drivetrain's motor torque sets (geometry), or the published lumped parameters'."""
    out = []
    for p in scene.planetaries:
        common = dict(mesh_damping_ratio=p.mesh_damping_ratio, damping_model=p.damping_model,
                      bearing_damping_ratio=p.bearing_damping_ratio)
        if p.form == "geometry":
            if progress:
                print(f"gearfmu: tables of planetary stage {p.name} (sun torque {p.sun_torque_Nm:.6g} N*m, "
                      f"{p.planets} planets)", file=sys.stderr, flush=True)
            st = planetary_stage(p.name, p.planetary_set, p.mechanics, points_per_mesh=p.points_per_mesh,
                                 sun_torque_Nm=p.sun_torque_Nm, progress=progress)
        else:
            st = lumped_stage(p.name, p.lumped, held=p.held, model=p.model, **common)
        out.append(replace(st, source=p.source))
    return out


def drivetrain_model(scene: DrivetrainScene, tables, *, damping_ratio: Optional[float] = None,
                     progress: bool = False):
    """The model of a drivetrain scene on its stages' tables: the GearboxModel (:func:`gearbox_model`)
    or, with planetary stages, the gearfmu.planetary.model.PlanetaryModel; ``damping_ratio`` replaces
    every mesh damping ratio."""
    if not scene.planetaries:
        return gearbox_model(scene, tables, damping_ratio=damping_ratio)
    meshes = [Mesh(s.name, t, s.damping_ratio if damping_ratio is None else damping_ratio, s.damping_model)
              for s, t in zip(scene.stages, tables)]
    stages = planetary_stages(scene, progress=progress)
    if damping_ratio is not None:
        stages = [replace(st, mesh_damping_ratio=damping_ratio) for st in stages]
    return build_planetary_drivetrain(meshes, stages, _shafts(scene),
                                      {"motor": scene.motor.inertia_kgm2, "load": scene.load.inertia_kgm2},
                                      motor_torque_input=scene.motor.torque_input,
                                      load_torque_input=scene.load.torque_input)


def _shafts(scene: DrivetrainScene) -> List[Shaft]:
    return [Shaft(sh.name, sh.a, sh.b, sh.stiffness_Nm_per_rad, sh.damping_ratio, sh.damping_Nms_per_rad,
                  sh.inertia_kgm2) for sh in scene.shafts]


def check_fmu_supported(scene: DrivetrainScene) -> None:
    """FmuBuildError for a drivetrain with planetary stages: they run on the native planetary solver
    (``gearfmu simulate``, ``gearfmu modes``), not yet as an FMU."""
    if scene.planetaries:
        p = scene.planetaries[0]
        raise FmuBuildError(f"planetary[0] ({p.name}): a drivetrain with planetary stages has no FMU yet; "
                            "`gearfmu simulate` and `gearfmu modes` run it (docs/planetary.md)")


def gearbox_model(scene: DrivetrainScene, tables, *, damping_ratio: Optional[float] = None) -> GearboxModel:
    """The GearboxModel of a drivetrain scene on its stages' tables (``tables`` in stage order);
    ``damping_ratio`` replaces every stage's mesh damping ratio."""
    check_fmu_supported(scene)
    meshes = [Mesh(s.name, t, s.damping_ratio if damping_ratio is None else damping_ratio, s.damping_model)
              for s, t in zip(scene.stages, tables)]
    return build_gearbox(meshes, _shafts(scene), {"motor": scene.motor.inertia_kgm2, "load": scene.load.inertia_kgm2},
                         motor_torque_input=scene.motor.torque_input, load_torque_input=scene.load.torque_input)


def pair_model(scene: Scene, tables, *, damping_ratio: Optional[float] = None) -> GearboxModel:
    """A pair scene as the two-body gearbox (pinion = motor end, gear = load end)."""
    mesh = Mesh(PAIR_MESH_NAME, _flat(tables), scene.fmu.damping_ratio if damping_ratio is None else damping_ratio,
                scene.solver.damping_model)
    return build_gearbox([mesh], motor=f"{PAIR_MESH_NAME}.pinion", load=f"{PAIR_MESH_NAME}.gear")


def simulate_drivetrain(scene: DrivetrainScene, model: GearboxModel, *, stop_time_s: Optional[float] = None,
                        comm_step_s: Optional[float] = None, max_step_s: Optional[float] = None,
                        motor_torque_Nm=None, load_torque_Nm=None, integrator: Optional[str] = None,
                        progress: bool = False) -> GearboxResult:
    """Run the native gearbox solver with the scene's settings (each overridable).  Without a load
    torque (argument or ``load.torque_Nm``) the load balances the motor torque at every step."""
    tm = scene.motor.torque_Nm if motor_torque_Nm is None else motor_torque_Nm
    if load_torque_Nm is None and scene.load.torque_Nm is not None:
        load_torque_Nm = scene.load.torque_Nm
    if load_torque_Nm is None and not scene.motor.torque_input:
        load_torque_Nm = scene.load_torque_Nm
    run = simulate_planetary if isinstance(model, PlanetaryModel) else simulate_gearbox
    return run(
        model, stop_time_s=scene.stop_time_s if stop_time_s is None else stop_time_s,
        comm_step_s=scene.output_interval_s if comm_step_s is None else comm_step_s,
        max_step_s=scene.max_step_s if max_step_s is None else max_step_s,
        motor_torque_Nm=tm if scene.motor.torque_input else 0.0,
        load_torque_Nm=load_torque_Nm if scene.load.torque_input else 0.0,
        motor_speed_start_rad_s=scene.motor.speed_rad_s,
        integrator=scene.integrator if integrator is None else integrator, progress=progress)


def modes_report(kind: str, scene, model: GearboxModel, *,
                 max_speed_rpm: Optional[float] = None) -> Tuple[ModesResult, dict]:
    """(modes, Campbell data) of a drivetrain or pair scene at its operating point: the motor (pinion)
    torque sets the linearisation; the speed axis runs to ``max_speed_rpm`` (None: 1.25 x the
    highest speed of the operating point and, for a pair scene, of its speed range)."""
    if kind == "drivetrain":
        t_ref = model.reference_torque_Nm(scene.motor.torque_Nm, scene.load_torque_Nm)
        w = scene.motor.speed_rad_s
        w_max = w
    else:
        t_ref = scene.operating.torque_Nm
        w = scene.operating.speed_rad_s
        rng = scene.operating.speed_range_rad_s
        w_max = max([w] + (list(rng) if rng else []))
    top = 1.25 * w_max / RPM_TO_RAD_S if max_speed_rpm is None else float(max_speed_rpm)
    if isinstance(model, PlanetaryModel):
        res = planetary_modes.modes(model, t_ref)
        cb = planetary_modes.campbell(model, res, top, operating_speed_rpm=w / RPM_TO_RAD_S)
        _phasing_rule(model, res, cb)
        return res, cb
    res = modes(model, t_ref)
    cb = campbell(model, res, top, operating_speed_rpm=w / RPM_TO_RAD_S)
    return res, cb


def _phasing_rule(model: PlanetaryModel, res, cb: dict) -> None:
    """Mark every interference of a planetary stage's mesh order with one of its modes by Parker's (2000)
    rule for equally spaced planets (gearfmu.gear.phasing.parker_harmonic_excitation): ``"excited"``
    true when the harmonic reaches the mode's type, false when the mesh phasing cancels it, None for
    mixed modes or unequally spaced planets."""
    for st in model.stages:
        N = st["planets"]
        equal = all(abs(a - 2.0 * math.pi * k / N) < 1e-9 for k, a in enumerate(st["planet_angles_rad"]))
        for o in cb["orders"]:
            if o["kind"] == "mesh" and o["name"].startswith(f"{st['name']} mesh ") and equal:
                o["phasing"] = parker_harmonic_excitation(o["harmonic"], st["teeth"][0], N)
        for p in cb["interferences"]:
            if not p["order"].startswith(f"{st['name']} mesh "):
                continue
            h = int(p["order"].rsplit(" ", 1)[1].rstrip("x"))
            kind = res.modes[p["mode"]].types.get(st["name"])
            p["excited"] = (parker_harmonic_excitation(h, st["teeth"][0], N) == kind
                            if equal and kind in ("rotational", "translational", "planet") else None)


def describe_model(model) -> str:
    """One line: what a gearbox or planetary drivetrain model holds."""
    if isinstance(model, PlanetaryModel):
        st = ", ".join(f"{s['name']} ({s['model']}, {s['planets']} planets, {s['held']} held)" for s in model.stages)
        return (f"{model.n_dof} DOFs, {len(model.mesh_names)} meshes, {len(model.spring_names)} springs; planetary "
                f"stage(s) {st}")
    return f"{model.n_bodies} bodies, {len(model.meshes)} mesh(es), {len(model.shafts)} elastic shaft(s)"


def modes_lines(name: str, model, res, cb) -> List[str]:
    """The text report of ``gearfmu modes``: the model, every mode (frequency, damped frequency, damping
    ratio, the largest strain-energy shares; for planetary stages the mode type of each stage), the
    mode structure of every planetary stage and the Campbell interferences."""
    planetary = isinstance(model, PlanetaryModel)
    out = [f"{name}: {describe_model(model)}; linearised at the mean mesh stiffness, motor torque "
           f"{res.reference_torque_Nm:.6g} N*m", f"{'mode':>4} {'f [Hz]':>10} {'f_d [Hz]':>10} {'zeta':>8}  "
           + ("type  " if planetary else "") + "strain energy (largest shares)"]
    for m in res.modes:
        if m.rigid:
            out.append(f"{m.index:>4} {'rigid':>10}")
            continue
        top = sorted(m.energy.items(), key=lambda kv: -kv[1])[:3]
        shares = ", ".join(f"{k} {100 * v:.0f}%" for k, v in top if v >= 0.005)
        kind = (" ".join(f"{t}" if len(m.types) == 1 else f"{s}:{t}" for s, t in m.types.items()) + "  "
                if planetary else "")
        out.append(f"{m.index:>4} {m.frequency_Hz:>10.5g} {m.damped_frequency_Hz:>10.5g} {m.damping_ratio:>8.4f}  "
                   f"{kind}{shares}")
    for st in (model.stages if planetary else ()):
        groups = planetary_modes.multiplicities(res, st["name"])
        out.append(f"{st['name']}: " + ", ".join(f"{t} {f:.5g} Hz" + (f" x{k}" if k > 1 else "")
                                                  for t, f, k in groups))
    pts = cb["interferences"]
    out.append(f"interferences of mesh and shaft orders with the modes, motor speed 0 .. {cb['speed_axis_rpm'][1]:.5g} "
               f"rpm (operating {cb['operating_speed_rpm']:.5g} rpm): {len(pts)}")
    out += [f"  {p['speed_rpm']:>9.5g} rpm  {p['order']} on mode {p['mode']} ({p['frequency_Hz']:.5g} Hz)"
            + ("  (cancelled by the planets' mesh phasing)" if p.get("excited") is False else "") for p in pts]
    return out


def fmu_settings(scene: DrivetrainScene, model: GearboxModel) -> GearboxFmuSettings:
    """The start values and DefaultExperiment of a drivetrain scene's gearbox FMU: the scene's motor
    torque and load torque (an end that is no torque input takes 0), motor speed, the integrator and
    largest internal step (``"auto"``: :func:`gearfmu.gearbox.native.choose_max_step_s` at 1.5 x the
    motor speed, as the native solver chooses it), the run's stop time and output interval."""
    check_fmu_supported(scene)
    t_in = scene.motor.torque_Nm if scene.motor.torque_input else 0.0
    t_out = scene.load_torque_Nm if scene.load.torque_input else 0.0
    w0 = scene.motor.speed_rad_s
    h = scene.max_step_s
    if h is None:
        h = choose_max_step_s(model, max(1.5 * abs(w0), 1.0),
                              reference_torque_Nm=model.reference_torque_Nm(t_in, t_out))
    return gearbox_settings(model, motor_torque_Nm=t_in, load_torque_Nm=t_out, motor_speed_start_rad_s=w0,
                            max_step_s=h, integrator=scene.integrator, stop_time_s=scene.stop_time_s,
                            output_interval_s=scene.output_interval_s)


def check_fmu_runtime(runtime: Optional[str]) -> None:
    """A gearbox FMU has the standalone C runtime only: FmuBuildError for any other ``runtime`` (None: the default)."""
    if runtime not in (None, "standalone"):
        raise FmuBuildError(f"--runtime {runtime}: a gearbox FMU (drivetrain scene) is built with the standalone "
                            "C runtime only (docs/gearbox.md \"The gearbox FMU\"); leave --runtime out or give "
                            "--runtime standalone")


@dataclass
class DrivetrainBuild:
    """What :func:`build_drivetrain_fmu` built: the FMU, the gearbox model and the FMU's settings, the
    wall times of the tables and of the FMU (s)."""

    fmu_path: Path
    model: GearboxModel
    settings: GearboxFmuSettings
    tables_wall_s: float
    build_wall_s: float


def build_drivetrain_fmu(scene: DrivetrainScene, out_path, *, progress: bool = False, runtime: Optional[str] = None,
                         platforms: Optional[Sequence[str]] = None, fmi_version: int = 2,
                         fmi3_outputs: str = DEFAULT_FMI3_OUTPUTS, allow_large: bool = False,
                         validation: bool = True) -> DrivetrainBuild:
    """Drivetrain scene -> every stage's tables -> the gearbox FMU at ``out_path`` (the standalone C
    runtime, FMI ``fmi_version`` 2 or 3).  ``runtime`` "pythonfmu" is refused (FmuBuildError): a
    gearbox FMU is C only.  The stages' notes go to stderr with ``progress``."""
    check_fmu_runtime(runtime)
    check_fmu_supported(scene)
    t0 = time.perf_counter()
    tables = stage_tables(scene, progress=progress, allow_large=allow_large)
    model = gearbox_model(scene, tables)
    t1 = time.perf_counter()
    settings = fmu_settings(scene, model)
    stage_texts = {s.name: s.scene.text for s in scene.stages if getattr(s.scene, "text", None)}
    path = build_gearbox_fmu(model, out_path, settings=settings, model_name=scene.model_name, scene_text=scene.text,
                             stage_scene_texts=stage_texts, platforms=platforms, fmi_version=fmi_version,
                             fmi3_outputs=fmi3_outputs, validation=validation)
    return DrivetrainBuild(Path(path), model, settings, t1 - t0, time.perf_counter() - t1)
