"""The native gearbox solver against the independent event-located scipy reference on hard cases.

Reference: gearfmu.gearbox.reference.simulate_reference -- the same equations written again in
plain Python over the pair reference's table pieces and force law, integrated by solve_ivp DOP853
at rtol 1e-10 with every table node and contact change of every mesh located as an event (no
numba code shared).  The cases (gearfmu.gearbox.cases, a two-stage reducer on rectangular-wave
mesh stiffness with tent errors and backlash):

* contact loss in stage 1 (its mesh force drops to zero) while stage 2 carries load throughout;
* the stage-1 mesh frequency on the mode whose strain energy lies mostly in the intermediate
  shaft (its torque swings more than twice as much as a quarter below that speed);
* a motor torque step with torque-axis tables (every mesh changes its torque row);
* an accessory drive: one pinion drives the load's gear and an unloaded pump gear on tables of the
  same angle grid, so the two meshes reach their table nodes at the same instant (the reference
  located one event and left the other mesh on a stale piece before it crossed every mesh standing
  on its piece end together: 0.75 to 0.99 of the range off).

The event-aware integrators (rk4_node, rk4_kink, rk4_seg) meet the reference within 1e-5 of each signal's range at the default
step and converge at fourth order: within 5e-8 at a quarter of it.  Classical RK4 steps across the
kinks of the force law and converges at about first order (within 1e-3 at a quarter step).
"""
import numpy as np
import pytest

from gearfmu.gearbox.cases import gearbox_case
from gearfmu.gearbox.native import simulate
from gearfmu.gearbox.reference import simulate_reference

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

SIGNALS = ("stage1.dte", "stage2.dte", "stage1.mesh_force", "stage2.mesh_force", "intermediate_shaft.torque",
           "load_speed")
_REF = {}


def reference(case):
    if case not in _REF:
        model, kw = gearbox_case(case, mesh_periods=24)
        _REF[case] = (model, kw, simulate_reference(model, **kw))
    return _REF[case]


def worst(res, ref):
    return max(float(np.max(np.abs(res[n] - ref[n])) / np.ptp(ref[n])) for n in SIGNALS)


@pytest.mark.parametrize("case", ["contact_loss", "intermediate_shaft_resonance", "torque_step"])
def test_native_against_reference(case):
    model, kw, ref = reference(case)
    for integrator in ("rk4_node", "rk4_kink", "rk4_seg"):
        r = simulate(model, **kw, integrator=integrator)
        assert worst(r, ref) <= 1e-5, integrator
        fine = simulate(model, **kw, integrator=integrator, max_step_s=r.step_s / 4)
        assert worst(fine, ref) <= 5e-8, integrator
    r4 = simulate(model, **kw, integrator="rk4", max_step_s=r.step_s / 4)
    assert worst(r4, ref) <= 1e-3


ACCESSORY_SIGNALS = ("main.dte", "pump.dte", "main.mesh_force", "pump.mesh_force", "load_speed")


def test_simultaneous_table_nodes_of_two_meshes():
    model, kw = gearbox_case("accessory_drive", mesh_periods=24)
    ref = simulate_reference(model, **kw)
    worst_of = lambda r: max(float(np.max(np.abs(r[n] - ref[n])) / np.ptp(ref[n])) for n in ACCESSORY_SIGNALS)
    r = simulate(model, **kw)
    assert worst_of(r) <= 1e-5
    assert worst_of(simulate(model, **kw, max_step_s=r.step_s / 4)) <= 5e-8
    # the case is what it says: the pump gear is off the power path, its mesh still carries force
    assert ref["pump.mesh_force"].min() < 0.0 < ref["pump.mesh_force"].max()


def test_the_cases_are_what_they_say():
    model, kw, ref = reference("contact_loss")
    f1, f2 = ref["stage1.mesh_force"], ref["stage2.mesh_force"]
    assert np.sum(f1 == 0.0) >= 1                      # stage 1 loses contact ...
    assert f2.min() > 0.25 * f2.mean()                 # ... while stage 2 carries load
    model, kw, ref = reference("torque_step")
    assert ref["motor_torque"][0] == 60.0 and ref["motor_torque"][-1] == 200.0
    assert ref["load_speed"][-1] > 1.01 * ref["load_speed"][0]
    # resonance: the intermediate shaft swings more than twice as much as a quarter below the speed
    model, kw = gearbox_case("intermediate_shaft_resonance", mesh_periods=60)
    swing = lambda r: np.ptp(r["intermediate_shaft.torque"][len(r.time_s) // 2:])
    on = swing(simulate(model, **kw))
    w = kw["motor_speed_start_rad_s"] * 0.75
    off = swing(simulate(model, **dict(kw, motor_speed_start_rad_s=w, comm_step_s=kw["comm_step_s"] / 0.75,
                                       stop_time_s=kw["stop_time_s"] / 0.75)))
    assert on > 2.0 * off
