"""Cases of the planetary tests and benchmark: inputs only (no results here).

* :data:`LIN_PARKER_1999` -- the example system of J. Lin, R. G. Parker, J. Vib. Acoust. 121 (1999)
  316-321, Table 1, entered as published (masses and I/r^2 in kg, mesh, bearing and torsional
  support stiffness in N/m, pressure angle 24.6 deg of both meshes; the sun and carrier have no
  torsional support).  The table gives no tooth counts or radii, which only set the kinematics and
  the mesh frequency here, not the frequencies: sun 24, planet 36, ring 96 teeth (z_r = z_s + 2 z_p
  keeps alpha_r = alpha_s; (z_s + z_r)/N an integer for N = 3, 4, 5) and a sun base radius of
  38.7 mm (CHOICE).
* :func:`lp_stage`, :func:`lp_model`: that system as a stage and as a standalone drivetrain
  (motor on the sun, load on the carrier, the ring held by its published torsional support).
* :func:`planetary_case`: hard cases of the native solver against its reference (``contact_loss``:
  three planets, rectangular-wave stiffness, 15 um backlash and a light load (8 N m on the
  sun): every mesh loses contact now and then; sequential phases;
  ``position_error``: four planets on a floating sun, planet 1's pin 20 um behind its place;
  ``two_stage``: the power entering at the carrier of a planetary stage followed by a parallel stage,
  so the planetary meshes run their tables backwards).
"""
from __future__ import annotations

import math
from dataclasses import replace
from typing import Callable, Dict

import numpy as np

from .assembly.planetary_lumped import LumpedPlanetary, lumped_stage
from .gear.planetary_set import PlanetErrors
from .gearbox.model import Mesh, Shaft
from .planetary.model import build_drivetrain
from .tables.synthetic import rectangular_wave_tables

__all__ = ["LIN_PARKER_1999", "lp_parameters", "lp_stage", "lp_model", "run_kwargs", "PLANETARY_CASES", "planetary_case"]

#: Lin & Parker (1999), Table 1 (see the module docstring for the source of the values)
LIN_PARKER_1999 = dict(
    mass_kg=dict(sun=0.4, ring=2.35, carrier=5.43, planet=0.66),
    inertia_over_r2_kg=dict(sun=0.39, ring=3.0, carrier=6.29, planet=0.61),
    mesh_stiffness_sun_N_per_m=5e8, mesh_stiffness_ring_N_per_m=5e8,
    bearing_N_per_m=dict(sun=1e8, ring=1e8, carrier=1e8, planet=1e8),
    support_N_per_m=1e9,                       # k_ru; k_su = k_cu = 0
    pressure_angle_sun_rad=math.radians(24.6),
)
#: tooth counts and sun base radius chosen here (module docstring)
LP_TEETH = (24, 36, 96)
LP_SUN_BASE_RADIUS_M = 0.0387


def lp_parameters(planets: int, **overrides) -> LumpedPlanetary:
    """Lin & Parker's example system with ``planets`` planets (LumpedPlanetary; ``overrides`` replace
    fields, e.g. contact ratios, teeth, errors)."""
    zs, zp, zr = LP_TEETH
    p = LumpedPlanetary(planets=planets, teeth_sun=zs, teeth_planet=zp, teeth_ring=zr,
                        base_radius_sun_m=LP_SUN_BASE_RADIUS_M, **LIN_PARKER_1999)
    return replace(p, **overrides)


def lp_stage(planets: int, name: str = "lp", **kw):
    """Lin & Parker's system as a :class:`gearfmu.tables.planetary.PlanetaryStage` (ring held)."""
    stage_kw = {k: kw.pop(k) for k in ("held", "model", "mesh_damping_ratio", "damping_model",
                                       "bearing_damping_ratio") if k in kw}
    return lumped_stage(name, lp_parameters(planets, **kw), **stage_kw)


def lp_model(planets: int, **kw):
    """The standalone stage: motor on the sun, load on the carrier."""
    st = lp_stage(planets, **kw)
    return build_drivetrain(planetaries=[st], motor=f"{st.name}.sun", load=f"{st.name}.carrier")


def run_kwargs(model, stage_mesh: str, speed: float, torque, mesh_periods: int, comm_per_mesh: int = 8, **extra):
    """Arguments of gearfmu.planetary.native.simulate: ``mesh_periods`` periods of mesh ``stage_mesh``
    at the motor speed ``speed`` (rad/s), ``comm_per_mesh`` communication steps per period, the motor
    torque ``torque`` (N m), the motor angle 0.013 rad at the start (off the table nodes)."""
    m = model.mesh_names.index(stage_mesh)
    T = float(model.mesh_tables[m].mesh_period_rad) / (abs(float(model.angle_ref[m])) * speed)
    kw = dict(stop_time_s=mesh_periods * T, comm_step_s=T / comm_per_mesh, motor_torque_Nm=torque,
              motor_speed_start_rad_s=speed, motor_angle_start_rad=0.013)
    kw.update(extra)
    return kw


def _contact_loss(mesh_periods):
    st = lp_stage(3, teeth_sun=25, teeth_planet=29, teeth_ring=83, contact_ratio_sun=1.6, contact_ratio_ring=1.7,
                  backlash_half_m=15e-6, gamma_rs=0.3)
    m = build_drivetrain(planetaries=[st], shafts=[Shaft("input_shaft", "motor", "lp.sun", 3e3, 0.02)],
                         parts={"motor": 2e-3}, motor="motor", load="lp.carrier")
    return m, run_kwargs(m, "lp.sun_planet[1]", 400.0, 8.0, mesh_periods)


def _position_error(mesh_periods):
    st = lp_stage(4, teeth_sun=21, teeth_planet=23, teeth_ring=67, contact_ratio_sun=1.6, contact_ratio_ring=1.7,
                  bearing_N_per_m=dict(sun=0.0, ring=1e8, carrier=1e8, planet=1e8),
                  planet_errors=(PlanetErrors(0.0, -20e-6), PlanetErrors(), PlanetErrors(), PlanetErrors()))
    m = build_drivetrain(planetaries=[st], motor="lp.sun", load="lp.carrier")
    return m, run_kwargs(m, "lp.sun_planet[1]", 300.0, 60.0, mesh_periods)


def two_stage_model():
    """Carrier-driven planetary stage (ring held, sun out) followed by a parallel stage."""
    st = lp_stage(3, teeth_sun=24, teeth_planet=36, teeth_ring=96, contact_ratio_sun=1.5, contact_ratio_ring=1.6)
    rs = st.base_radius_sun_m
    par = rectangular_wave_tables(4e8, contact_ratio=1.6, points_per_mesh=32, teeth_pinion=23, teeth_gear=41,
                                  base_radius_pinion_m=0.03, base_radius_gear_m=0.03 * 41 / 23,
                                  inertia_pinion_kgm2=2e-4, inertia_gear_kgm2=2e-3)
    return build_drivetrain([Mesh("par", par, 0.05)], [st],
                            [Shaft("input_shaft", "motor", "lp.carrier", 2e5, 0.02),
                             Shaft("intermediate_shaft", "lp.sun", "par.pinion", 3e3, 0.02),
                             Shaft("output_shaft", "par.gear", "load", 2e4, 0.02)],
                            {"motor": 0.5, "load": 0.02}, motor="motor", load="load")


def _two_stage(mesh_periods):
    m = two_stage_model()
    return m, run_kwargs(m, "lp.sun_planet[1]", 40.0, 200.0, mesh_periods)


PLANETARY_CASES: Dict[str, Callable] = {
    "contact_loss": _contact_loss,
    "position_error": _position_error,
    "two_stage": _two_stage,
}


def planetary_case(name: str, mesh_periods: int = 20):
    """(model, simulate kwargs) of a hard case over ``mesh_periods`` sun-mesh periods."""
    if name not in PLANETARY_CASES:
        raise ValueError(f"case: {name!r} unknown; choose one of {sorted(PLANETARY_CASES)}")
    return PLANETARY_CASES[name](int(mesh_periods))
