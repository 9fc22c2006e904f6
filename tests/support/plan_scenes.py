"""A small planned scene (20/31 teeth, an [accuracy] block): the planner's test scene
(tests/unit/plan/test_plan.py) and the command line's planned-scene check
(tests/integration/test_cli_user_errors.py)."""

SMALL = """
[scene]
name = "plan_small"

[gears]
module_mm = 3.0
face_width_mm = 20.0
backlash_um = 100.0

[gears.pinion]
teeth = 20

[gears.gear]
teeth = 31

[deviations.pinion]
profile_form_um = 5.0
lead_crowning_um = 8.0

[[deviations.pinion.tooth]]
index = 3
profile_form_um = 12.0

[mesh]
slices = 8

[operating]
torque_Nm = 200.0
speed_rpm = 1000.0

[tables]
points_per_mesh = 32

[fmu]
stop_time_s = 0.02
output_interval_s = 1e-4

[envelope]
torque_range_Nm = [80.0, 200.0]
speed_range_rpm = [1000.0, 2000.0]

[accuracy]
dte_rel_error = 0.05
mesh_force_rel_error = 0.05
run_mesh_periods = 12
"""
