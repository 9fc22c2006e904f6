"""Run settings (gearfmu.common.settings): one type, one check, one place for the defaults.

References: the default output interval by hand (mesh period 2 pi / (z1 w1), 20 samples, rounded
down to 1, 2 or 5 x 10^n s); the balancing gear torque T2 = T1 Rb2/Rb1 (seed 003: F_m = T1/Rb1 =
T2/Rb2); the automatic step min(2 pi/omega_n, mesh period at 1.5 w1)/64 (docs/native.md).
"""
import dataclasses
import math

import pytest

from gearfmu.common.settings import (GearboxRunSettings, RunSettings, RunSettingsError, checked,
                                     default_output_interval_s)
from gearfmu.dynamics.native import NativeInputError, resolve_settings, simulate
from gearfmu.dynamics.reference import ReferenceInputError, simulate_reference
from gearfmu.fmu.build_steps import FmuBuildError, check_arguments, record_parameters, start_values
from gearfmu.tables.synthetic import rectangular_wave_tables

BAD = [("stop_time_s", 0.0, "must be > 0"), ("stop_time_s", math.inf, "must be finite"),
       ("output_interval_s", -1e-4, "must be > 0"), ("max_step_s", 0.0, "must be > 0"),
       ("integrator", "euler", "unknown"), ("integrator", 7, "must be one of"),
       ("damping_ratio", -0.01, "must be >= 0"), ("damping_ratio", "x", "expected a number"),
       ("damping_model", "viscous", "unknown"), ("damping_model", True, "must be one of"),
       ("pinion_speed_start_rad_s", math.nan, "must be finite"), ("pinion_angle_start_rad", None, "expected a number"),
       ("pinion_torque_start_Nm", -math.inf, "must be finite"), ("gear_torque_start_Nm", math.nan, "must be finite")]


@pytest.mark.parametrize("field,value,reason", BAD)
def test_every_setting_is_checked_when_made_and_the_message_names_it(field, value, reason):
    with pytest.raises(RunSettingsError, match=f"^{field}: .*{reason}"):
        RunSettings(**{field: value})
    with pytest.raises(RunSettingsError, match=f"^{field}: "):  # a changed copy is checked by the same rule
        dataclasses.replace(RunSettings(), **{field: value})


def test_the_one_check_speaks_in_each_callers_error_class():
    """The solver, the reference and both builders report the same message, raised as their own
    error (they all call the one check)."""
    t = rectangular_wave_tables(2.5e8)
    run = dict(stop_time_s=1e-3, comm_step_s=1e-4, pinion_torque_Nm=1.0, pinion_speed_start_rad_s=10.0)
    msgs = []
    for call, err in ((lambda: simulate(t, damping_ratio=-1.0, **run), NativeInputError),
                      (lambda: simulate_reference(t, damping_ratio=-1.0, **run), ReferenceInputError),
                      (lambda: check_arguments(t, "x.fmu", None, scene_text=None, model_name="m", damping_ratio=-1.0),
                       FmuBuildError),
                      (lambda: checked(RunSettings(), ValueError, damping_ratio=-1.0), ValueError)):
        with pytest.raises(err) as exc:
            call()
        msgs.append(str(exc.value))
    assert len(set(msgs)) == 1 and msgs[0] == "damping_ratio: must be >= 0, got -1.0"


def test_codes_and_older_spellings_are_stored_as_the_names():
    s = RunSettings(integrator=1, damping_model=1)
    assert (s.integrator, s.damping_model, s.integrator_code, s.damping_model_code) == ("rk4_kink", "contact_zone", 1, 1)
    assert RunSettings(integrator="rk4_seg").integrator == "rk4_seg"
    assert GearboxRunSettings(integrator="rk4_seg").integrator_code == 3
    with pytest.raises(RunSettingsError, match="integrator: 'euler' unknown for gearboxes"):
        GearboxRunSettings(integrator="euler")
    assert GearboxRunSettings().stop_time_s == RunSettings().stop_time_s  # the shared part, the same defaults


def test_default_output_interval_by_hand():
    # z1 = 20 at 100 rad/s: mesh period 2 pi/2000 = 3.14e-3 s, / 20 = 1.57e-4 s -> 1e-4 s
    assert default_output_interval_s(100.0, 20) == 1e-4
    # z1 = 25 at 157.08 rad/s (1500 rpm): 1.6e-3 s / 20 = 8.0e-5 -> 5e-5 s
    assert default_output_interval_s(1500 * math.pi / 30, 25) == 5e-5
    # a stop time below the default caps it
    assert RunSettings(stop_time_s=2e-5).output_interval_for(100.0, 20) == 2e-5


def test_automatic_values_resolved_once_for_the_solver_and_the_builders():
    """resolve_settings is the rule of the native solver and of both builders: the FMU's
    start values and the native run's settings are the same numbers."""
    t = rectangular_wave_tables(2.5e8)
    s = RunSettings(pinion_speed_start_rad_s=80.0, pinion_torque_start_Nm=150.0)
    r = resolve_settings(t, s)
    assert r.gear_torque_start_Nm == 150.0 * t.base_radius_gear_m / t.base_radius_pinion_m
    wn = math.sqrt(t.k_mean_N_per_m / t.equivalent_mass_kg)
    assert r.max_step_s == pytest.approx(min(2 * math.pi / wn, t.mesh_period_rad / (1.5 * 80.0)) / 64, rel=1e-15)
    assert r.output_interval_s == default_output_interval_s(80.0, t.teeth_pinion)
    built, _ = check_arguments(t, "x.fmu", s, scene_text=None, model_name="m")
    assert built == r
    assert start_values(built)["max_step"] == r.max_step_s and record_parameters(built)["integrator"] == 2
    res = simulate(t, s, stop_time_s=10 * r.output_interval_s)
    assert res.step_s * res.substeps == pytest.approx(r.output_interval_s, rel=1e-15)
    assert res.substeps == math.ceil(r.output_interval_s / r.max_step_s * (1 - 1e-12))
    assert res.gear_torque[0] == r.gear_torque_start_Nm


def test_a_bad_setting_is_named_by_the_argument_the_caller_gave():
    """The solvers' keyword ``comm_step_s`` sets ``output_interval_s``, ``omega1_rad_s`` the start
    speed of the SDOF form: the message names the argument given, not the field behind it."""
    from gearfmu.dynamics.native import simulate_sdof

    t = rectangular_wave_tables(2.5e8)
    run = dict(stop_time_s=1e-3, pinion_torque_Nm=1.0, damping_ratio=0.02)
    with pytest.raises(NativeInputError, match=r"^comm_step_s: must be > 0"):
        simulate(t, comm_step_s=-1e-4, pinion_speed_start_rad_s=10.0, **run)
    with pytest.raises(NativeInputError, match=r"^omega1_rad_s: must be finite"):
        simulate_sdof(t, comm_step_s=1e-4, omega1_rad_s=math.nan, **run)
    with pytest.raises(RunSettingsError, match=r"^output_interval_s: must be > 0"):
        RunSettings(output_interval_s=-1e-4)
