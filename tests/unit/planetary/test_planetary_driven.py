"""A planetary stage whose third member is DRIVEN at a prescribed speed (docs/planetary.md "Driven
members"): its support's outer end turns at the drive's speed instead of standing still.

References (none produced by gearfmu.planetary):

* Willis' equation z_s (w_s - w_c) + z_r (w_r - w_c) = 0 (H. W. Mueller, *Epicyclic Drive Trains*,
  1982): with one member driven at a prescribed speed and another by the motor, in steady state with
  time-varying mesh stiffness, the angles turned over the last 100 whole mesh periods satisfy it to
  1e-12 (the periodic mesh deflections cancel over whole periods), the driven member turns at exactly
  the drive's speed and the third member at the closed form of the other two;
* the torque balance of a lossless planetary stage, T_s : T_r : T_c = 1 : z_r/z_s : -(1 + z_r/z_s),
  independent of the speeds: with constant mesh stiffness (contact ratio 1) the run starts in its
  steady state, and the driven member's support carries the closed-form torque from the motor torque
  over the whole run to 1e-8 (torsional; translational 2e-4: the planets' centripetal preload at speed) (the static start is exact to 1e-13 of the forces; the support's twist,
  about 1e-5 rad, is the difference of the member's and the drive's absolute angles, which grow with
  time, so its round-off is some 1e-16 rad of angle: 1e-11 of the twist, and RK4 on a state that
  does not accelerate adds nothing);
* the modes: a drive is ground, so a driven stage's modes are the held stage's (same support);
* the translational model with a drive that turns the carrier: its frame turns with the drive too, so
  the translations stay at their static values over a run at constant mesh stiffness.

Bad input: each new refusal names its field.
"""
import dataclasses

import numpy as np
import pytest

from gearfmu.bench import lp_stage
from gearfmu.planetary.model import PlanetaryModelError, build_drivetrain
from gearfmu.planetary.modes import modes
from gearfmu.planetary.native import PlanetaryInputError, simulate
from gearfmu.planetary.reference import simulate_reference

ZS, ZP, ZR = 24, 36, 96
PORT_RATIO = {"sun": 1.0, "ring": ZR / ZS, "carrier": -(1.0 + ZR / ZS)}   # T_s : T_r : T_c


def driven_model(driven, motor, load, speed, model="torsional", contact_ratio=1.6):
    st = lp_stage(4, contact_ratio_sun=contact_ratio, contact_ratio_ring=contact_ratio + 0.1 if contact_ratio > 1
                  else 1.0, held=driven, bearing_damping_ratio=0.05, model=model)
    st = dataclasses.replace(st, driven_speed_rad_s=speed)
    return build_drivetrain(planetaries=[st], motor=f"lp.{motor}", load=f"lp.{load}")


def run_kw(m, w, torque, periods, per=8):
    """``periods`` whole periods of the sun mesh at its table speed with the drive turning (rad/s)."""
    k = m.mesh_names.index("lp.sun_planet[1]")
    T = float(m.mesh_tables[k].mesh_period_rad) / abs(float(m.table_speeds(w)[k]))
    return dict(stop_time_s=periods * T, comm_step_s=T / per, motor_torque_Nm=torque, motor_speed_start_rad_s=w,
                motor_angle_start_rad=0.013)


CASES = [("ring", "sun", "carrier", -40.0), ("ring", "carrier", "sun", 25.0), ("carrier", "sun", "ring", 30.0),
         ("carrier", "ring", "sun", -20.0), ("sun", "ring", "carrier", 200.0), ("sun", "carrier", "ring", -150.0)]


@pytest.mark.parametrize("driven,motor,load,speed,model", [c + ("torsional",) for c in CASES] +
                         [c + ("translational",) for c in CASES[:4]])
def test_willis_equation_with_a_driven_member(driven, motor, load, speed, model):
    m = driven_model(driven, motor, load, speed, model=model)
    r = simulate(m, **run_kw(m, 300.0, 50.0, 400))
    last = slice(len(r.time_s) - 1 - 8 * 100, None)     # the last 100 whole mesh periods
    t = r.time_s[last][-1] - r.time_s[last][0]
    d = {p: r[f"lp.{p}_angle"][last][-1] - r[f"lp.{p}_angle"][last][0] for p in ("sun", "carrier", "ring")}
    scale = max(abs(v) for v in d.values()) * ZR
    assert abs(ZS * (d["sun"] - d["carrier"]) + ZR * (d["ring"] - d["carrier"])) <= 1e-12 * scale
    # the driven member turns with its drive (the support's twist is periodic); the drive at its speed, its
    # angle summed over some 1e5 RK4 substeps, each rounding at 1e-16 of the angle
    drive = r[f"lp.{driven}_drive_angle"][last]
    assert abs(d[driven] - (drive[-1] - drive[0])) <= 1e-12 * scale
    assert abs((drive[-1] - drive[0]) / t - speed) <= 1e-10 * abs(speed)
    assert np.all(r[f"lp.{driven}_drive_speed"] == speed)
    free = load
    w_free = {"sun": lambda s, c, rg: c + ZR * (c - rg) / ZS, "ring": lambda s, c, rg: c + ZS * (c - s) / ZR,
              "carrier": lambda s, c, rg: (ZS * s + ZR * rg) / (ZS + ZR)}[free]
    mean = {p: d[p] / t for p in d}
    assert abs(mean[free] - w_free(mean["sun"], mean["carrier"], mean["ring"])) <= 1e-12 * scale / t


@pytest.mark.parametrize("driven,motor,load,speed,model", [c + (m,) for m in ("torsional", "translational")
                                                           for c in CASES])
def test_the_driven_member_carries_the_closed_form_torque(driven, motor, load, speed, model):
    m = driven_model(driven, motor, load, speed, model=model, contact_ratio=1.0)
    T_m = 50.0
    r = simulate(m, **run_kw(m, 300.0, T_m, 40))
    # the torque the drive applies to the member: minus the support spring's force k (q_member - q_drive);
    # constant over the run to 1e-8 (the start is the steady state)
    want = T_m * PORT_RATIO[driven] / PORT_RATIO[motor]
    got = -r[f"lp.{driven}_support.force"]
    assert np.ptp(got) <= 1e-8 * abs(want)
    # torsional: the closed form to 1e-8; translational at speed: to 2e-4, the planets' centripetal preload
    # m_p Omega^2 r_c that the linear model carries without its moment (docs/planetary.md "Initial state"):
    # 1.25e-4 of the smallest torque with the carrier at 280 rad/s, as the held stage's 9.2e-5 at 240 rad/s
    # times (280/240)^2
    assert np.max(np.abs(got - want)) <= (1e-8 if model == "torsional" else 2e-4) * abs(want), (got[:3], want)
    if model == "translational":    # the frame turns with the carrier: the translations stay at their static values
        assert np.ptp(r["lp.planet[1]_tangential"]) <= 1e-6 * np.max(np.abs(r["lp.planet[1]_tangential"]))
    want_load = -T_m * PORT_RATIO[load] / PORT_RATIO[motor]                  # positive resists
    assert r["load_torque"][0] == pytest.approx(want_load, rel=1e-14)


def test_a_held_member_is_unchanged_by_the_new_key():
    """driven_speed_rad_s None is the held stage: the same DOFs and springs, no drive."""
    held = build_drivetrain(planetaries=[lp_stage(4, model="torsional")], motor="lp.sun", load="lp.carrier")
    assert held.drives == () and "lp.ring_drive" not in held.dof_names
    assert [d for d in held.spring_idx[held.spring_names.index("lp.ring_support")] if d >= 0] == [held.part_dof["lp.ring"]]


def test_a_drive_is_ground_for_the_modes():
    held = build_drivetrain(planetaries=[lp_stage(4, held="ring")], motor="lp.sun", load="lp.carrier")
    driven = build_drivetrain(planetaries=[dataclasses.replace(lp_stage(4, held="ring"), driven_speed_rad_s=0.0)],
                              motor="lp.carrier", load="lp.sun")
    held2 = build_drivetrain(planetaries=[lp_stage(4, held="ring")], motor="lp.carrier", load="lp.sun")
    a = np.array([md.frequency_Hz for md in modes(held2, 50.0).modes])
    b = modes(driven, 50.0)
    f = np.array([md.frequency_Hz for md in b.modes])
    np.testing.assert_allclose(f, a, rtol=1e-10, atol=1e-9)
    d = driven.drive_dofs[0]
    assert all(md.shape[d] == 0.0 for md in b.modes)
    assert held.n_dof + 1 == driven.n_dof


def test_the_rigid_motion_of_the_drive():
    """Willis with the motor at rest: driving the ring at 1 rad/s turns the carrier at z_r/(z_s + z_r) and
    the planets at the carrier's speed minus r_s (w_s - w_c)/r_p (model docstring)."""
    m = driven_model("ring", "sun", "carrier", -40.0)
    h = m.drives[0]["mode"]
    assert h[m.part_dof["lp.sun"]] == 0.0 and h[m.part_dof["lp.ring"]] == pytest.approx(1.0, rel=1e-14)
    assert h[m.part_dof["lp.carrier"]] == pytest.approx(ZR / (ZS + ZR), rel=1e-13)
    hc = ZR / (ZS + ZR)
    assert h[m.stages[0]["dofs"]["planet"][0]] == pytest.approx(hc + ZS * hc / ZP, rel=1e-13)


# ------------------------------------------------------------------ bad input
def test_a_non_finite_drive_speed_is_refused():
    st = dataclasses.replace(lp_stage(3, model="torsional"), driven_speed_rad_s=float("nan"))
    with pytest.raises(PlanetaryModelError, match=r"^planetary\[0\] \(lp\)\.driven_speed_rad_s: "):
        build_drivetrain(planetaries=[st], motor="lp.sun", load="lp.carrier")


def test_a_translational_carrier_turned_by_two_drives_is_refused():
    """Stage b (translational) takes stage a's carrier on its sun and has its ring driven: its carrier turns
    with both drives, its frame can follow one."""
    from gearfmu.gearbox.model import Shaft
    a, b = (dataclasses.replace(lp_stage(3, name=n, model=mdl), driven_speed_rad_s=w)
            for n, mdl, w in (("a", "torsional", -30.0), ("b", "translational", 10.0)))
    with pytest.raises(PlanetaryModelError, match=r"^planetary\[0\] \(a\)\.driven_speed_rad_s: the carrier of the "
                                                  r"translational stage 'b' is turned by two drives|^planetary\[1\] "
                                                  r"\(b\)\.driven_speed_rad_s: the carrier of the translational stage 'b'"):
        build_drivetrain(planetaries=[a, b], shafts=[Shaft("s", "a.carrier", "b.sun", 1e5, 0.02)], motor="a.sun",
                         load="b.carrier")


def test_run_inputs_of_the_drive_are_checked():
    m = driven_model("ring", "sun", "carrier", -40.0)
    kw = run_kw(m, 300.0, 50.0, 2)
    with pytest.raises(PlanetaryInputError, match=r"drive_speeds_rad_s\['lp\.sun'\]: not a driven member; driven are "
                                                  r"\['lp\.ring'\]"):
        simulate(m, drive_speeds_rad_s={"lp.sun": 3.0}, **kw)
    with pytest.raises(PlanetaryInputError, match=r"drive_speeds_rad_s\['lp\.ring'\]: contains NaN"):
        simulate(m, drive_speeds_rad_s={"lp.ring": float("inf")}, **kw)
    with pytest.raises(PlanetaryModelError, match=r"drive_speeds_rad_s: expected 1 finite speeds"):
        m.static_state(50.0, 300.0, drive_speeds_rad_s=[1.0, 2.0])


def test_the_reference_refuses_a_driven_member():
    m = driven_model("ring", "sun", "carrier", -40.0)
    with pytest.raises(PlanetaryInputError, match=r"^model: the reference does not take driven members \(lp\.ring\)"):
        simulate_reference(m, **run_kw(m, 300.0, 50.0, 2))


def test_two_driven_stages_in_series():
    """Two stages (21/23/67, constant mesh stiffness), each ring driven, the first stage's carrier on the
    second's sun through an elastic shaft: each drive's rigid motion moves the stages after it; the start
    is the steady state, the torques the chained closed form T_s2 = (1 + z_r/z_s) T_s1, T_r = (z_r/z_s) T_s
    of each stage, the speeds Willis' of each stage from its sun's and its drive's."""
    from gearfmu.gearbox.model import Shaft
    zs, zr = 21, 67
    a, b = (dataclasses.replace(lp_stage(3, name=n, model="torsional", teeth_sun=zs, teeth_planet=23, teeth_ring=zr),
                                driven_speed_rad_s=w) for n, w in (("a", -30.0), ("b", 10.0)))
    m = build_drivetrain(planetaries=[a, b], shafts=[Shaft("s", "a.carrier", "b.sun", 1e5, 0.02)], motor="a.sun",
                         load="b.carrier")
    k = m.mesh_names.index("a.sun_planet[1]")
    T = float(m.mesh_tables[k].mesh_period_rad) / abs(float(m.table_speeds(300.0)[k]))
    r = simulate(m, stop_time_s=20 * T, comm_step_s=T / 8, motor_torque_Nm=50.0, motor_speed_start_rad_s=300.0)
    t_sb = (1 + zr / zs) * 50.0
    for name, want in (("s.force", t_sb), ("a.ring_support.force", -zr / zs * 50.0),
                       ("b.ring_support.force", -zr / zs * t_sb)):
        assert np.max(np.abs(r[name] - want)) <= 1e-8 * abs(want), name
    for st, w_d in (("a", -30.0), ("b", 10.0)):
        ws, wc = r[f"{st}.sun_speed"][0], r[f"{st}.carrier_speed"][0]
        assert wc == pytest.approx((zs * ws + zr * w_d) / (zs + zr), rel=1e-13)
