"""Hard cases of the gearbox model: inputs for the tests and the benchmark (no results here).

``gearbox_case(name)`` returns ``(model, kwargs)`` for :func:`gearfmu.gearbox.native.simulate`
and :func:`gearfmu.gearbox.reference.simulate_reference` (which take the same arguments).  The
gearbox is a two-stage reducer, motor - input shaft - stage 1 (23/67 teeth) - intermediate
shaft - stage 2 (19/73) - output shaft - load, total ratio 11.2, on rectangular-wave mesh
stiffness (gearfmu.tables.synthetic.rectangular_wave_tables: the textbook TVMS, Xu et al. 2022 Fig. 2)
with tent-shaped meshing errors and backlash:

* ``contact_loss``: stage 1 with a large meshing error at a light load loses contact
  (impacts, back-flank contacts) while stage 2, four times more loaded, keeps it;
* ``intermediate_shaft_resonance``: the stage-1 mesh frequency on the natural frequency of the
  mode whose strain energy lies mostly in the intermediate shaft (from gearfmu.gearbox.modes);
* ``torque_step``: tables with a torque axis; the motor torque steps from 60 to 200 N*m a third
  into the run against the load torque that balances 60 N*m, so the gearbox accelerates and
  every mesh changes its torque row at the step;
* ``accessory_drive``: one stage-1 pinion drives the load's gear at 150 N*m and, beside the power
  path, an unloaded accessory gear (a pump drive, an anti-backlash gear: no backlash, 1 um tent
  error) on tables of the same angle grid: the two meshes read one pinion angle, so every table
  node of one is a node of the other at the same instant (simultaneous events).
"""
from __future__ import annotations

import math
from dataclasses import replace
from typing import Callable, Dict

import numpy as np

from ..tables.synthetic import rectangular_wave_tables
from .model import Mesh, Shaft, build_gearbox
from .modes import modes

__all__ = ["GEARBOX_CASES", "gearbox_case", "reducer"]

#: stage data of the test reducer: teeth, base radii (m; in the ratio of the teeth), gear inertias
STAGE1 = dict(teeth_pinion=23, teeth_gear=67, base_radius_pinion_m=0.0270, base_radius_gear_m=0.0270 * 67 / 23,
              inertia_pinion_kgm2=2.0e-4, inertia_gear_kgm2=1.2e-2)
STAGE2 = dict(teeth_pinion=19, teeth_gear=73, base_radius_pinion_m=0.0312, base_radius_gear_m=0.0312 * 73 / 19,
              inertia_pinion_kgm2=8.0e-4, inertia_gear_kgm2=8.0e-2)


def _tent(amplitude_m: float):
    """A pair's meshing error over its engagement u in [0, 1): amplitude*(1 - |2u - 1|)."""
    return lambda slot, u: amplitude_m * (1.0 - np.abs(2.0 * u - 1.0))


def _stage(k_single, stage, backlash_half_m, error_m, torque_axis=None):
    t = rectangular_wave_tables(k_single, backlash_half_m=backlash_half_m, pair_error_m=_tent(error_m),
                                points_per_mesh=32, **stage)
    if torque_axis is None:
        return t
    # a torque axis: the stiffness 8 % lower at the low end, 8 % higher at the high end
    k = np.stack([t.k_N_per_m[0] * f for f in (0.92, 1.08)])
    e = np.repeat(t.e_m, 2, axis=0)
    return replace(t, torque_Nm=np.asarray(torque_axis, dtype=float), k_N_per_m=k, e_m=e,
                   e_comprehensive_m=np.repeat(t.e_comprehensive_m, 2, axis=0)).validate()


def reducer(error1_m=5e-6, error2_m=2e-6, backlash1_m=20e-6, backlash2_m=30e-6, torque_axis=None,
            mesh_damping=0.05, shaft_damping=0.02):
    """The two-stage test reducer (module docstring) as a GearboxModel."""
    t1 = _stage(3.0e8, STAGE1, backlash1_m, error1_m, torque_axis)
    t2 = _stage(5.0e8, STAGE2, backlash2_m, error2_m,
                None if torque_axis is None else [q * 67 / 23 for q in torque_axis])
    return build_gearbox([Mesh("stage1", t1, mesh_damping), Mesh("stage2", t2, mesh_damping)],
                         [Shaft("input_shaft", "motor", "stage1.pinion", 4.0e4, shaft_damping),
                          Shaft("intermediate_shaft", "stage1.gear", "stage2.pinion", 1.6e5, shaft_damping),
                          Shaft("output_shaft", "stage2.gear", "load", 5.0e5, shaft_damping)],
                         {"motor": 0.03, "load": 2.0})


def _kw(speed, torque, mesh_periods, comm_per_mesh=4, **extra):
    """Run arguments: ``mesh_periods`` stage-1 mesh periods at ``comm_per_mesh`` communication
    steps each; the start angle 0.31 of a table step past a node (as gearfmu.bench's cases)."""
    H = 2.0 * math.pi / STAGE1["teeth_pinion"] / speed / comm_per_mesh
    kw = dict(stop_time_s=mesh_periods * comm_per_mesh * H, comm_step_s=H, motor_torque_Nm=torque,
              motor_speed_start_rad_s=speed, motor_angle_start_rad=0.31 * 2.0 * math.pi / 23 / 32)
    kw.update(extra)
    return kw


def _contact_loss(mesh_periods):
    m = reducer(error1_m=10e-6, error2_m=1e-6, backlash1_m=15e-6)
    return m, _kw(300.0, 30.0, mesh_periods)


def _resonance(mesh_periods):
    m = reducer()
    res = modes(m, 60.0)
    mode = max((md for md in res.modes if not md.rigid), key=lambda md: md.energy["intermediate_shaft"])
    speed = 2.0 * math.pi * mode.frequency_Hz / STAGE1["teeth_pinion"]   # stage-1 mesh frequency on the mode
    return m, _kw(speed, 60.0, mesh_periods)


def _torque_step(mesh_periods):
    m = reducer(torque_axis=[40.0, 220.0])
    kw = _kw(300.0, 60.0, mesh_periods)
    n = int(round(kw["stop_time_s"] / kw["comm_step_s"]))
    kw["motor_torque_Nm"] = np.where(np.arange(n) < n // 3, 60.0, 200.0)
    kw["load_torque_Nm"] = 60.0 / m.load_ratio
    return m, kw


def _accessory_drive(mesh_periods):
    main = _stage(3.0e8, STAGE1, 20e-6, 5e-6)
    pump = _stage(3.0e8, STAGE1, 0.0, 1e-6)
    m = build_gearbox([Mesh("main", main, 0.05), Mesh("pump", pump, 0.05)],
                      [Shaft("input_shaft", "motor", "main.pinion", None),
                       Shaft("pump_drive", "main.pinion", "pump.pinion", None),
                       Shaft("output_shaft", "main.gear", "load", 5.0e5, 0.02)],
                      {"motor": 0.03, "load": 2.0})
    return m, _kw(300.0, 150.0, mesh_periods)


GEARBOX_CASES: Dict[str, Callable] = {
    "contact_loss": _contact_loss,
    "intermediate_shaft_resonance": _resonance,
    "torque_step": _torque_step,
    "accessory_drive": _accessory_drive,
}


def gearbox_case(name: str, mesh_periods: int = 60):
    """(model, simulate kwargs) of a hard case over ``mesh_periods`` stage-1 mesh periods;
    ValueError naming unknown cases."""
    if name not in GEARBOX_CASES:
        raise ValueError(f"case: {name!r} unknown; choose one of {sorted(GEARBOX_CASES)}")
    return GEARBOX_CASES[name](int(mesh_periods))
