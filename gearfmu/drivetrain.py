"""The main job on a drivetrain scene: scene -> every stage's tables -> gearbox model; its run and modes.

Wiring only (docs/gearbox.md): :func:`load_any` tells a drivetrain file (top-level
``[drivetrain]``) from a gear-pair scene; :func:`stage_tables` checks the estimated cost of
every stage (before computing any) and computes each stage's tables with
:func:`gearfmu.pipeline.compute_tables` at the stage's operating point (the drivetrain's,
:mod:`gearfmu.scene.drivetrain`); :func:`gearbox_model` builds the
:class:`gearfmu.gearbox.model.GearboxModel`; :func:`pair_model` makes the two-body gearbox of a
single pair scene (for ``gearfmu modes``); :func:`simulate_drivetrain` runs the native gearbox
solver with the scene's settings; :func:`modes_report` gives the modes and the Campbell data.
"""
from __future__ import annotations

import sys
from typing import List, Optional, Tuple, Union

from .common.settings import GearboxRunSettings
from .gearbox.model import GearboxModel, Mesh, Shaft, build_gearbox
from .gearbox.modes import ModesResult, campbell, modes
from .gearbox.native import GearboxResult, simulate as simulate_gearbox
from .pipeline import compute_tables, load
from .scene.drivetrain import DrivetrainScene, is_drivetrain_file, load_drivetrain
from .scene.options import RPM_TO_RAD_S, Scene
from .tables.estimate import BuildTooLargeError, check_build_cost

__all__ = ["load_any", "is_drivetrain_file", "stage_tables", "gearbox_model", "pair_model", "gearbox_run_settings",
           "simulate_drivetrain", "modes_report", "PAIR_MESH_NAME"]

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
    cost estimate of every stage is checked first (gearfmu.tables.estimate): a stage over the
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


def gearbox_model(scene: DrivetrainScene, tables, *, damping_ratio: Optional[float] = None) -> GearboxModel:
    """The GearboxModel of a drivetrain scene on its stages' tables (``tables`` in stage order);
    ``damping_ratio`` replaces every stage's mesh damping ratio."""
    meshes = [Mesh(s.name, t, s.damping_ratio if damping_ratio is None else damping_ratio, s.damping_model)
              for s, t in zip(scene.stages, tables)]
    shafts = [Shaft(sh.name, sh.a, sh.b, sh.stiffness_Nm_per_rad, sh.damping_ratio, sh.damping_Nms_per_rad,
                    sh.inertia_kgm2) for sh in scene.shafts]
    return build_gearbox(meshes, shafts, {"motor": scene.motor.inertia_kgm2, "load": scene.load.inertia_kgm2},
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


def simulate_drivetrain(scene: DrivetrainScene, model: GearboxModel, *, stop_time_s: Optional[float] = None,
                        comm_step_s: Optional[float] = None, max_step_s: Optional[float] = None,
                        motor_torque_Nm=None, load_torque_Nm=None, integrator: Optional[str] = None,
                        progress: bool = False) -> GearboxResult:
    """Run the native gearbox solver with the scene's settings (:func:`gearbox_run_settings`; each
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
    return simulate_gearbox(model, s, stop_time_s=stop_time_s, comm_step_s=comm_step_s, max_step_s=max_step_s,
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
    res = modes(model, t_ref)
    top = 1.25 * w_max / RPM_TO_RAD_S if max_speed_rpm is None else float(max_speed_rpm)
    cb = campbell(model, res, top, operating_speed_rpm=w / RPM_TO_RAD_S)
    return res, cb
