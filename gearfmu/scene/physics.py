"""What the physics takes from a scene: the table builder's arguments, the contact environment,
the cost estimate and its guard.

The layers below the scene (:mod:`gearfmu.assembly`, :mod:`gearfmu.contact`, :mod:`gearfmu.gear`,
:mod:`gearfmu.ehl`) take specs and settings, never a Scene; this module is where a Scene's
physics options are read off it: the arguments of
:func:`gearfmu.assembly.precompute.precompute_tables` (:func:`table_arguments`), the
:class:`gearfmu.contact.base.ContactEnvironment` of the lubricated contact models
(:func:`environment_from_scene`) and the cost estimate of the scene's tables and FMU
(:func:`estimate_build`, :func:`check_build_cost`; the model is
:mod:`gearfmu.assembly.estimate`).  SI units.
"""
from __future__ import annotations

from ..assembly.estimate import (BUILD_TIME_LIMIT_S, BuildEstimate, BuildTooLargeError, estimate_cost,
                                 limits_exceeded)
from ..assembly.estimate import work_counts as _work_counts
from ..contact.base import ContactEnvironment, RoughnessSpec
from ..gear.geometry import pair_geometry

__all__ = ["environment_from_scene", "table_arguments", "work_counts", "estimate_build", "check_build_cost",
           "BuildEstimate", "BuildTooLargeError"]


def environment_from_scene(scene, geom=None, **kw) -> ContactEnvironment:
    """A :class:`gearfmu.contact.base.ContactEnvironment` from a scene (lubricant at its
    temperature, the scene's pinion speed, slices and ``[roughness]``; the rough-EHL model
    without ``[roughness]`` gets level 1 of Zhao et al. 2022); ``geom``: the pair geometry when already
    computed; ``kw`` overrides fields."""
    geom = pair_geometry(scene.pair) if geom is None else geom
    pair = scene.pair
    ns = int(scene.mesh.slices)
    lub = scene.lubricant
    rough = scene.roughness  # the scene reader builds the RoughnessSpec
    if rough is None and scene.mesh.contact_model == "rough_ehl":
        rough = RoughnessSpec.from_level(1)
    args = dict(pair=pair, geom=geom, omega1_rad_s=float(scene.operating.speed_rad_s), n_slices=ns,
                width_m=min(pair.pinion.face_width_m, pair.gear.face_width_m) / ns,
                eta0_Pas=None if lub is None else lub.dynamic_viscosity_Pas,
                alpha_Pa_inv=None if lub is None else lub.pressure_viscosity_Pa_inv,
                rho0_kg_m3=None if lub is None else lub.density_kg_m3, roughness=rough,
                film_load_anchor_N_per_m=float(scene.operating.torque_Nm) / float(geom.rb1_m)
                / min(pair.pinion.face_width_m, pair.gear.face_width_m))
    args.update(kw)
    return ContactEnvironment(**args)


def table_arguments(scene, *, progress: bool = False) -> dict:
    """The arguments of :func:`gearfmu.assembly.precompute.precompute_tables` for a scene's tables
    (without ``provenance`` and ``progress``): the gear pair and mesh options, points per mesh,
    the torque axis and nominal torque, slots, the thermal options and, for a contact model
    other than Hertz, the contact environment (``progress``: its film solves show progress)."""
    torque_axis = scene.operating.torque_axis_Nm() if hasattr(scene.operating, "torque_axis_Nm") else None
    args = dict(pair=scene.pair, opts=scene.mesh, points_per_mesh=scene.tables.points_per_mesh,
                torque_axis_Nm=torque_axis, nominal_torque_Nm=scene.operating.torque_Nm,
                slots=scene.tables.slots)
    if scene.mesh.contact_model != "hertz":
        args["contact_env"] = environment_from_scene(scene, progress=progress)
    args["thermal"] = scene.thermal
    return args


def work_counts(scene) -> dict:
    """The work of the scene's table build (:func:`gearfmu.assembly.estimate.work_counts`)."""
    return _work_counts(**table_arguments(scene))


def estimate_build(scene) -> BuildEstimate:
    """Estimate table size (bytes), FMU size (bytes) and table build time (CPU s) of ``scene``
    without computing anything but the pair geometry (:func:`gearfmu.assembly.estimate.estimate_cost`
    on :func:`table_arguments`, with the scene's FMU runtime and experiment)."""
    fmu = scene.fmu
    return estimate_cost(**table_arguments(scene), runtime=fmu.runtime, stop_time_s=fmu.stop_time_s,
                         output_interval_s=fmu.output_interval_s)


def check_build_cost(scene, *, allow_large: bool = False) -> BuildEstimate:
    """:func:`estimate_build`, raising :class:`gearfmu.assembly.estimate.BuildTooLargeError` (a
    one-line message with the estimate and the scene keys to change) when the FMU would exceed
    :data:`gearfmu.assembly.estimate.FMU_LIMIT_BYTES` or the build
    :data:`gearfmu.assembly.estimate.BUILD_TIME_LIMIT_S`, unless ``allow_large``."""
    est = estimate_build(scene)
    if allow_large:
        return est
    over = limits_exceeded(est)
    if not over:
        return est
    keys = [f"tables.points_per_mesh ({scene.tables.points_per_mesh})"]
    if est.torque_rows > 1:
        keys.append(f"tables.torque_points ({scene.tables.torque_points})")
    if est.temperatures > 1:
        keys.append(f"thermal.temperature_axis_C ({est.temperatures} values)")
    if est.build_s > BUILD_TIME_LIMIT_S:
        keys.append(f"mesh.slices ({est.slices})")
    raise BuildTooLargeError(
        f"{', '.join(keys)}: the scene is too large to build ({'; '.join(over)}; {est.summary()}); "
        "lower these keys, or pass --allow-large (allow_large=True in the Python API) to build anyway")
