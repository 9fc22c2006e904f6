"""The stages of a scene, without the planner: what each stage takes from the scene, wired to
the package that does it (scene, tables, fmu, dynamics, gearbox).

A gear-pair scene: :func:`load`, its tables (:func:`compute_tables`), its run settings
(:func:`run_settings`: the one :class:`gearfmu.common.settings.RunSettings` of the FMU and the
native run), its FMU (:func:`build_fmu_from_scene`, the scene as it is) and its native run
(:func:`simulate_native`).  A drivetrain scene (docs/gearbox.md): :func:`load_any` tells it from
a pair scene, :func:`stage_tables` computes every stage's tables at its operating point,
:func:`gearbox_model` builds the gearbox, :func:`gearbox_run_settings` and
:func:`simulate_drivetrain` run it, :func:`modes_report` gives its modes and Campbell data
(:func:`pair_model`: a pair scene as the two-body gearbox), :func:`gearbox_fmu_settings` and
:func:`build_drivetrain_fmu` build its gearbox FMU (:mod:`gearfmu.fmu.gearbox_build`;
docs/gearbox.md "The gearbox FMU").  A drivetrain with ``[[planetary]]`` stages builds every
planetary stage's tables (:func:`planetary_stages`: gearfmu.assembly.planetary from the geometry,
gearfmu.assembly.planetary_lumped from published lumped parameters) and runs on the planetary solver
(:func:`drivetrain_model`, gearfmu.planetary; docs/planetary.md); :func:`build_drivetrain_fmu` makes it
one planetary FMU (:func:`build_planetary_drivetrain_fmu`, :mod:`gearfmu.fmu.planetary_build`;
docs/planetary.md "The planetary FMU"), never a gearbox of stages (:func:`check_fmu_supported`).

The planner (:mod:`gearfmu.plan`) builds its planned scenes with these stages, so they never
plan; :mod:`gearfmu.pipeline` puts the planner in front of them (``gearfmu build``).
"""
from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import List, Optional, Sequence, Tuple, Union

import numpy as np

from . import __version__
from .common.progress import notice
from .common.settings import GearboxRunSettings, RunSettings
from .common.vocabulary import DEFAULT_FMI3_OUTPUTS, DEFAULT_FMU_INTERFACE, FMI3_OUTPUTS, FMU_INTERFACES, ME_NODE_EVENTS, RUNTIMES
from .scene.physics import environment_from_scene
from .dynamics.native import choose_max_step_s, simulate
from .fmu.build_steps import FmuBuildError
from .fmu.gearbox_build import build_gearbox_fmu, gearbox_settings
from .fmu.planetary_build import build_planetary_fmu, planetary_settings
from .fmu.pythonfmu_build import build_fmu
from .fmu.standalone_build import build_standalone_fmu
from .fmu.envelope import fmu_envelope_record
from .gearbox.model import GearboxModel, Mesh, Shaft, build_gearbox
from .gearbox.modes import ModesResult, campbell, modes
from .gearbox.native import simulate as simulate_gearbox
from .gear.phasing import parker_harmonic_excitation
from .planetary import modes as planetary_modes
from .planetary.model import PlanetaryModel, build_drivetrain as build_planetary_drivetrain
from .planetary.native import simulate as simulate_planetary
from .assembly.planetary import planetary_stage
from .assembly.planetary_lumped import lumped_stage
from .scene.drivetrain import DrivetrainScene, is_drivetrain_file, load_drivetrain
from .scene.options import RPM_TO_RAD_S, Scene
from .scene.reader import default_scene_path, load_scene
from .scene.physics import check_build_cost, estimate_build
from .assembly import precompute, table_cache
from .assembly.estimate import BuildTooLargeError


def load(scene_path: Optional[str] = None):
    """Load a scene file (None: the default scene)."""
    return load_scene(scene_path if scene_path is not None else default_scene_path())


def gear_torque_for(tables, pinion_torque_Nm: float) -> float:
    """Load torque on the gear that balances a pinion torque in steady state,
    T2 = T1 * Rb2 / Rb1 (Xu et al. 2022: F_m = T1/Rb1 = T2/Rb2)."""
    return pinion_torque_Nm * tables.base_radius_gear_m / tables.base_radius_pinion_m


def compute_tables(scene, *, progress: bool = False, allow_large: bool = False, cache: Optional[bool] = None):
    """Precompute the tooth-pair tables of a scene (timed).  Refuses with a
    :class:`gearfmu.assembly.estimate.BuildTooLargeError` naming the scene keys when the estimated
    tables, FMU or build time exceed the limits of :mod:`gearfmu.assembly.estimate`, unless
    ``allow_large``.  The tables are kept in gearfmu's table cache and read back when the same
    physics is asked again (:mod:`gearfmu.assembly.table_cache`); ``cache`` False computes without
    it, None follows ``--no-cache`` / ``GEARFMU_NO_TABLE_CACHE``."""
    check_build_cost(scene, allow_large=allow_large)
    torque_axis = scene.operating.torque_axis_Nm() if hasattr(scene.operating, "torque_axis_Nm") else None
    prov = {
        "scene_name": scene.name,
        "scene_toml": scene.text,
        "gearfmu_version": __version__,
        "numpy_version": np.__version__,
        "created_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "contact_model": scene.mesh.contact_model,
    }
    args = dict(pair=scene.pair, opts=scene.mesh, points_per_mesh=scene.tables.points_per_mesh,
                torque_axis_Nm=torque_axis, nominal_torque_Nm=scene.operating.torque_Nm,
                slots=scene.tables.slots, **_contact_kw(scene, progress), thermal=scene.thermal)
    # looked up at call time, so a substitute set on the module is used
    return table_cache.cached_tables(precompute.precompute_tables, args, prov, progress=progress, use_cache=cache)


def _contact_kw(scene, progress: bool) -> dict:
    """``contact_env`` for the EHL contact models (gearfmu/contact/models.py); {} for Hertz."""
    if scene.mesh.contact_model == "hertz":
        return {}
    return {"contact_env": environment_from_scene(scene, progress=progress)}


def run_settings(scene, tables=None) -> RunSettings:
    """The run settings of a scene on its tables (:class:`gearfmu.common.settings.RunSettings`),
    built once for the FMU, the native run and the validation: ``[fmu]`` stop time, output
    interval and damping ratio, ``[solver]`` integrator, step bound (:func:`max_step_for`) and
    damping model, ``[operating]`` start speed and pinion torque, the balancing gear torque
    (:func:`gear_torque_for`).  Without ``tables``: the scene's own step bound (None when
    "auto") and no gear torque (the balance on the tables the run takes)."""
    t1_Nm = scene.operating.torque_Nm
    return RunSettings(stop_time_s=scene.fmu.stop_time_s, output_interval_s=scene.fmu.output_interval_s,
                       max_step_s=scene.solver.max_step_s if tables is None else max_step_for(scene, tables),
                       integrator=scene.solver.integrator, damping_ratio=scene.fmu.damping_ratio,
                       damping_model=scene.solver.damping_model, pinion_speed_start_rad_s=scene.operating.speed_rad_s,
                       pinion_torque_start_Nm=t1_Nm,
                       gear_torque_start_Nm=None if tables is None else gear_torque_for(tables, t1_Nm))


def max_step_for(scene, tables) -> float:
    """The internal step bound: the scene's ``solver.max_step_s`` or the automatic choice."""
    if scene.solver.max_step_s is not None:
        return float(scene.solver.max_step_s)
    vmax = scene.operating.speed_rad_s
    rng = scene.operating.speed_range_rad_s
    if rng:
        vmax = max(abs(v) for v in rng)
    if tables.has_temperature_axis:  # the bound of the stiffest temperature slice
        return min(choose_max_step_s(tables.at_temperature(float(t)), abs(vmax)) for t in tables.temperature_C)
    return choose_max_step_s(tables, abs(vmax))


@dataclass
class BuildResult:
    fmu_path: Path
    tables: object
    tables_wall_s: float
    build_wall_s: float
    max_step_s: float
    plan: object = None  # gearfmu.plan.Plan when the scene's [accuracy] made build follow a plan
    #: gearfmu.scene.envelope.VerifiedEnvelope as a dict: the plan's verified envelope, or the as-written
    #: estimate (estimate_accuracy=True, no [accuracy]); None otherwise (docs/plan.md "Verified envelope")
    verified_envelope: Optional[dict] = None
    estimate: object = None  # gearfmu.assembly.estimate.BuildEstimate of the scene that was built
    #: s, the time the tables' computation took: ``tables_wall_s`` when they were computed here, the
    #: original computation's when they were read from the table cache (gearfmu.assembly.table_cache)
    tables_compute_s: Optional[float] = None
    #: the run settings the FMU was built with (:func:`run_settings`; its start values and DefaultExperiment)
    settings: Optional[RunSettings] = None


def fmu_builder(runtime: str):
    """The FMU builder of a runtime: "standalone" (FMI layer in C, docs/standalone.md) or
    "pythonfmu"; both take the same arguments."""
    if runtime == "standalone":
        return build_standalone_fmu
    if runtime != "pythonfmu":
        raise ValueError(f"runtime: {runtime!r} not one of {RUNTIMES}")
    return build_fmu


def platform_kw(runtime: str, platforms, fmi_version: int = 2,
                fmi3_outputs: str = DEFAULT_FMI3_OUTPUTS, interface: Optional[str] = None,
                me_node_events: Optional[str] = None) -> dict:
    """``platforms`` for the builder: binaries of a standalone FMU (gearfmu.fmu.crossbuild keys;
    None: all available); ``fmi_version`` 3: the standalone FMI 3.0 FMU, with ``fmi3_outputs``
    "array" or "scalar" (:data:`gearfmu.common.vocabulary.FMI3_OUTPUTS`); ``interface`` and
    ``me_node_events`` (None: the builder's defaults): a standalone FMU's interfaces and Model
    Exchange's node events (:data:`gearfmu.common.vocabulary.FMU_INTERFACES`, ``ME_NODE_EVENTS``)."""
    me = {k: v for k, v in (("interface", interface), ("me_node_events", me_node_events)) if v is not None}
    if interface is not None and interface not in FMU_INTERFACES:
        raise ValueError(f"--interface: {interface!r} not one of {', '.join(FMU_INTERFACES)}")
    if me_node_events is not None and me_node_events not in ME_NODE_EVENTS:
        raise ValueError(f"--me-node-events: {me_node_events!r} not one of {', '.join(ME_NODE_EVENTS)}")
    if runtime != "standalone" and me and interface != "cs":
        raise ValueError("--interface/--me-node-events: the pythonfmu runtime offers Co-Simulation only; Model "
                         "Exchange needs --runtime standalone")
    if runtime != "standalone":
        me = {}
    if fmi_version not in (2, 3) or (fmi_version == 3 and runtime != "standalone"):
        raise ValueError(f"--fmi-version: {fmi_version} needs 2, or 3 with the standalone runtime")
    if fmi3_outputs not in FMI3_OUTPUTS:
        raise ValueError(f"--fmi3-outputs: {fmi3_outputs!r} not one of {', '.join(FMI3_OUTPUTS)}")
    if fmi3_outputs != DEFAULT_FMI3_OUTPUTS and fmi_version != 3:
        raise ValueError(f"--fmi3-outputs: {fmi3_outputs} needs --fmi-version 3 (an FMI 2 FMU has scalars only)")
    version = dict({"fmi_version": 3, "fmi3_outputs": fmi3_outputs} if fmi_version == 3 else {}, **me)
    if platforms is None:
        return version
    if runtime != "standalone":
        raise ValueError("--platforms: only the standalone runtime builds binaries for other platforms "
                         "(use --runtime standalone)")
    return {"platforms": tuple(platforms), **version}


def build_fmu_from_scene(scene, out_path, *, progress: bool = False, runtime: Optional[str] = None,
                         tables=None, plan=None, verified_envelope: Optional[dict] = None, platforms=None,
                         allow_large: bool = False, fmi_version: int = 2, fmi3_outputs: str = DEFAULT_FMI3_OUTPUTS,
                         model_exchange: Optional[dict] = None) -> BuildResult:
    """Scene -> tables -> FMU at ``out_path``, the scene as it is (no planning: see
    :func:`gearfmu.pipeline.build`).  ``runtime``: "standalone" or "pythonfmu"; None: the
    scene's ``fmu.runtime``.  ``tables``: MeshTables to use instead of the scene's physics
    (e.g. imported from CSV, gearfmu.tables.table_import); the scene then only gives the FMU
    and operating settings.  ``plan``, ``verified_envelope``: kept in the result.
    ``platforms``: binaries of a standalone FMU.  ``allow_large``: build even when the
    estimate (gearfmu.assembly.estimate) exceeds the limits.  ``model_exchange``: the
    ``interface`` and ``me_node_events`` of a standalone FMU (:func:`platform_kw`; None or a
    value None: the builder's defaults)."""
    runtime = runtime or scene.fmu.runtime
    builder = fmu_builder(runtime)
    extra = platform_kw(runtime, platforms, fmi_version, fmi3_outputs, **(model_exchange or {}))
    est = estimate_build(scene) if tables is None else None
    t0 = time.perf_counter()
    if tables is None:
        tables = compute_tables(scene, progress=progress, allow_large=allow_large)
    t1 = time.perf_counter()
    settings = run_settings(scene, tables)
    notice(f"building the FMU {out_path} ({runtime} runtime, FMI {fmi_version})", enabled=progress or None)
    path = builder(tables, out_path, settings, model_name=scene.fmu.model_name, scene_text=scene.text,
                   envelope=fmu_envelope_record(tables, verified_envelope,
                                                speed_range_rad_s=scene.operating.speed_range_rad_s), **extra)
    t2 = time.perf_counter()
    computed = t1 - t0
    if isinstance(tables.provenance, dict) and "table_cache" in tables.provenance:
        computed = float((tables.provenance.get("precompute") or {}).get("wall_s", computed))
    return BuildResult(Path(path), tables, t1 - t0, t2 - t1, settings.max_step_s, plan, verified_envelope, est,
                       computed, settings)


def simulate_native(scene, tables, *, stop_time_s=None, comm_step_s=None, max_step_s=None,
                    damping_ratio=None, pinion_torque_Nm=None, gear_torque_Nm=None):
    """Run the native (numba) solver on a scene's tables with the scene's settings
    (:func:`run_settings`); the keyword arguments given replace them (a pinion torque given
    without a gear torque: its balancing load)."""
    return simulate(tables, run_settings(scene, tables), stop_time_s=stop_time_s, comm_step_s=comm_step_s,
                    max_step_s=max_step_s, damping_ratio=damping_ratio, pinion_torque_Nm=pinion_torque_Nm,
                    gear_torque_Nm=gear_torque_Nm)


# ================================================================ a drivetrain scene
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
        out.append(replace(st, source=p.source, driven_speed_rad_s=p.driven_speed_rad_s))
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
    """FmuBuildError for a drivetrain with planetary stages where a gearbox model is asked for (a gearbox
    FMU, an SSP of stage FMUs): such a drivetrain is one planetary model and builds as one planetary FMU
    (:func:`build_drivetrain_fmu`; docs/planetary.md "The planetary FMU")."""
    if scene.planetaries:
        p = scene.planetaries[0]
        raise FmuBuildError(f"planetary[0] ({p.name}): a drivetrain with planetary stages is one system, not a "
                            "gearbox of stages; `gearfmu build` makes its planetary FMU (docs/planetary.md)")


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


def gearbox_run_settings(scene: DrivetrainScene) -> GearboxRunSettings:
    """The run settings of a drivetrain scene (:class:`gearfmu.common.settings.GearboxRunSettings`):
    ``[run]`` stop time and output interval, ``[solver]`` integrator and step bound (None: "auto"),
    the motor's start speed and torque, the load's torque (given, else -- when the motor is no torque
    input -- the balancing torque, else None: the balance of the motor's at every step); an end
    that is no torque input takes 0."""
    m, ld = scene.motor, scene.load
    load = ld.torque_Nm if ld.torque_Nm is not None else (None if m.torque_input else scene.load_torque_Nm)
    return GearboxRunSettings(stop_time_s=scene.stop_time_s, output_interval_s=scene.output_interval_s,
                              max_step_s=scene.max_step_s, integrator=scene.integrator,
                              motor_speed_start_rad_s=m.speed_rad_s,
                              motor_torque_start_Nm=m.torque_Nm if m.torque_input else 0.0,
                              load_torque_start_Nm=load if ld.torque_input else 0.0)


def simulate_drivetrain(scene: DrivetrainScene, model, *, stop_time_s: Optional[float] = None,
                        comm_step_s: Optional[float] = None, max_step_s: Optional[float] = None,
                        motor_torque_Nm=None, load_torque_Nm=None, integrator: Optional[str] = None,
                        progress: bool = False):
    """Run the native gearbox solver (the planetary solver for a drivetrain with planetary stages) with the scene's settings (:func:`gearbox_run_settings`; each
    overridable).  Without a load torque (argument or ``load.torque_Nm``) the load balances the
    motor torque at every step."""
    s = gearbox_run_settings(scene)
    inputs = {}
    if motor_torque_Nm is not None:
        inputs["motor_torque_Nm"] = motor_torque_Nm if scene.motor.torque_input else 0.0
    if load_torque_Nm is not None:
        inputs["load_torque_Nm"] = load_torque_Nm if scene.load.torque_input else 0.0
    elif motor_torque_Nm is not None:  # a motor input alone: the load as the scene says (None: its balance)
        inputs["load_torque_Nm"] = s.load_torque_start_Nm
    run = simulate_planetary if isinstance(model, PlanetaryModel) else simulate_gearbox
    return run(model, s, stop_time_s=stop_time_s, comm_step_s=comm_step_s, max_step_s=max_step_s,
               integrator=integrator, progress=progress, **inputs)


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
        st = ", ".join(f"{s['name']} ({s['model']}, {s['planets']} planets, {s['held']} "
                       f"{'driven' if s.get('driven') else 'held'})" for s in model.stages)
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


def gearbox_fmu_settings(scene: DrivetrainScene, model: GearboxModel) -> GearboxRunSettings:
    """The run settings of a drivetrain scene's gearbox FMU (its start values and DefaultExperiment):
    :func:`gearbox_run_settings` with the load's start torque a number (the given one, else the
    balancing torque; 0 for an end that is no torque input) and the automatic values resolved by
    :func:`gearfmu.fmu.gearbox_build.gearbox_settings` (``"auto"`` step: the native solver's choice
    at 1.5 x the motor speed, linearised at the start torques)."""
    check_fmu_supported(scene)
    return gearbox_settings(model, gearbox_run_settings(scene),
                            load_torque_start_Nm=scene.load_torque_Nm if scene.load.torque_input else 0.0)


def check_gearbox_fmu_runtime(runtime: Optional[str], interface: Optional[str] = None,
                              me_node_events: Optional[str] = None) -> dict:
    """A gearbox FMU has the standalone C runtime only: FmuBuildError for any other ``runtime`` (None: the
    default) and for ``me_node_events`` without Model Exchange (``interface`` "cs"; None, the default,
    offers both interfaces).  Returns the ``model_exchange`` mapping of :func:`build_drivetrain_fmu`."""
    if runtime not in (None, "standalone"):
        raise FmuBuildError(f"--runtime {runtime}: a gearbox FMU (drivetrain scene) is built with the standalone "
                            "C runtime only (docs/gearbox.md \"The gearbox FMU\"); leave --runtime out or give "
                            "--runtime standalone")
    if interface == "cs" and me_node_events is not None:
        raise FmuBuildError(f"--me-node-events {me_node_events}: only with Model Exchange (--interface me or both, "
                            "the default; docs/gearbox.md 'Model Exchange')")
    return {"interface": interface, "me_node_events": me_node_events}


@dataclass
class DrivetrainBuild:
    """What :func:`build_drivetrain_fmu` built: the FMU, the gearbox (or planetary) model and the FMU's
    settings, the wall times of the tables and of the FMU (s)."""

    fmu_path: Path
    model: Union[GearboxModel, PlanetaryModel]
    settings: GearboxRunSettings
    tables_wall_s: float
    build_wall_s: float


def build_drivetrain_fmu(scene: DrivetrainScene, out_path, *, progress: bool = False, runtime: Optional[str] = None,
                         platforms: Optional[Sequence[str]] = None, fmi_version: int = 2,
                         fmi3_outputs: str = DEFAULT_FMI3_OUTPUTS, allow_large: bool = False,
                         validation: bool = True, model_exchange: Optional[dict] = None) -> DrivetrainBuild:
    """Drivetrain scene -> every stage's tables -> the gearbox FMU at ``out_path`` (the standalone C
    runtime, FMI ``fmi_version`` 2 or 3); a drivetrain with planetary stages: its planetary FMU
    (:func:`build_planetary_drivetrain_fmu`).  ``runtime`` "pythonfmu" is refused (FmuBuildError): a
    gearbox FMU is C only.  The stages' notes go to stderr with ``progress``.  ``model_exchange``: the
    interfaces and node events (:func:`gearfmu.fmu.gearbox_build.build_gearbox_fmu`)."""
    if scene.planetaries:
        return build_planetary_drivetrain_fmu(scene, out_path, progress=progress, runtime=runtime, platforms=platforms,
                                              fmi_version=fmi_version, fmi3_outputs=fmi3_outputs,
                                              allow_large=allow_large, validation=validation,
                                              model_exchange=model_exchange)
    check_gearbox_fmu_runtime(runtime, *((model_exchange or {}).get(k) for k in ("interface", "me_node_events")))
    check_fmu_supported(scene)
    t0 = time.perf_counter()
    tables = stage_tables(scene, progress=progress, allow_large=allow_large)
    model = gearbox_model(scene, tables)
    t1 = time.perf_counter()
    settings = gearbox_fmu_settings(scene, model)
    stage_texts = {s.name: s.scene.text for s in scene.stages if getattr(s.scene, "text", None)}
    path = build_gearbox_fmu(model, out_path, settings=settings, model_name=scene.model_name, scene_text=scene.text,
                             stage_scene_texts=stage_texts, platforms=platforms, fmi_version=fmi_version,
                             fmi3_outputs=fmi3_outputs, validation=validation, model_exchange=model_exchange)
    return DrivetrainBuild(Path(path), model, settings, t1 - t0, time.perf_counter() - t1)


def planetary_fmu_settings(scene: DrivetrainScene, model: PlanetaryModel) -> GearboxRunSettings:
    """The run settings of a drivetrain scene's planetary FMU, as :func:`gearbox_fmu_settings` for a
    gearbox (:func:`gearfmu.fmu.planetary_build.planetary_settings`)."""
    return planetary_settings(model, gearbox_run_settings(scene),
                              load_torque_start_Nm=scene.load_torque_Nm if scene.load.torque_input else 0.0)


def build_planetary_drivetrain_fmu(scene: DrivetrainScene, out_path, *, progress: bool = False,
                                   runtime: Optional[str] = None, platforms: Optional[Sequence[str]] = None,
                                   fmi_version: int = 2, fmi3_outputs: str = DEFAULT_FMI3_OUTPUTS,
                                   allow_large: bool = False, validation: bool = True,
                                   model_exchange: Optional[dict] = None) -> DrivetrainBuild:
    """A drivetrain scene with planetary stages -> its tables -> the planetary FMU at ``out_path``
    (docs/planetary.md "The planetary FMU"; :func:`gearfmu.fmu.planetary_build.build_planetary_fmu`):
    Co-Simulation and Model Exchange unless ``model_exchange`` names the interface."""
    me = dict(model_exchange or {})
    me["interface"] = me.get("interface") or DEFAULT_FMU_INTERFACE
    check_gearbox_fmu_runtime(runtime, me["interface"], me.get("me_node_events"))
    t0 = time.perf_counter()
    tables = stage_tables(scene, progress=progress, allow_large=allow_large)
    model = drivetrain_model(scene, tables, progress=progress)
    t1 = time.perf_counter()
    settings = planetary_fmu_settings(scene, model)
    stage_texts = {s.name: s.scene.text for s in scene.stages if getattr(s.scene, "text", None)}
    path = build_planetary_fmu(model, out_path, settings=settings, model_name=scene.model_name, scene_text=scene.text,
                               stage_scene_texts=stage_texts, platforms=platforms, fmi_version=fmi_version,
                               fmi3_outputs=fmi3_outputs, validation=validation, model_exchange=me)
    return DrivetrainBuild(Path(path), model, settings, t1 - t0, time.perf_counter() - t1)
