"""Every FMU states and checks the envelope over which its accuracy was verified
(docs/fmu.md "Verified envelope").

References: the envelope numbers are the builder's own inputs (hand-written ranges of a
:class:`gearfmu.scene.envelope.VerifiedEnvelope`, the tables' torque row and temperature axis); the
rule is docs/fmu.md: one fmi2Warning per input the first time it leaves its range, naming the
input, its value and the range, and the step still returns fmi2OK.  The speed run-up is the
rigid-body closed form w(t) = w0 + T1 t / (I1 + I2 (Rb1/Rb2)^2) with the gear torque 0.
Both runtimes are driven the same way and must log the same messages.
"""
import json

import pytest

from gearfmu.fmu.crossbuild import host_key
from gearfmu.fmu.envelope import fmu_envelope_record
from gearfmu.scene.envelope import VerifiedEnvelope
from gearfmu.fmu.pythonfmu_build import build_fmu
from gearfmu.fmu.standalone_build import build_standalone_fmu

from factories import RB1, RB2, make_tables
from support.envelope_checks import H, both_runtimes_warn, record
from support.fmpy_host import KEPT_CALLBACKS
from factories import temp_tables

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

RPM = 30 / 3.141592653589793


def _verified(torque, speed_rad_s, temperature=None):
    """A hand-written plan record (plain data, as gearfmu.plan.verified_envelope_of makes it)."""
    return VerifiedEnvelope(
        kind="plan verification", torque_range_Nm=torque, speed_range_rpm=tuple(w * RPM for w in speed_rad_s),
        temperature_range_C=temperature, dte_target_rel=0.02, mesh_force_target_rel=0.03,
        error_definition="rms(y - y_full) / rms(y_full)", within_target=True, worst_dte_rel=0.011,
        worst_mesh_force_rel=0.017, worst_dte_max_rel=0.02, worst_mesh_force_max_rel=0.03,
        worst_at={"case": "steady", "torque_Nm": torque[1]}, native_runs=12, probes=9).to_dict()


def _build(tables, d, name, verified=None, **kw):
    """The same FMU in both runtimes (standalone: this machine's binary only)."""
    env = fmu_envelope_record(tables, verified) if verified is not None else None
    kw = dict(max_step_s=1e-5, pinion_torque_start_Nm=100.0, pinion_speed_start_rad_s=100.0, stop_time_s=0.01,
              output_interval_s=H, model_name=name, envelope=env, **kw)
    return {"standalone": build_standalone_fmu(tables, d / f"{name}_sa.fmu", validation=True,
                                               platforms=(host_key(),), **kw),
            "pythonfmu": build_fmu(tables, d / f"{name}_py.fmu", **kw)}


@pytest.fixture(scope="module")
def single_row(tmp_path_factory):
    d = tmp_path_factory.mktemp("env1")
    t = make_tables()  # one torque row, 100 N.m
    return {"plain": _build(t, d, "plain"),
            "verified": _build(t, d, "ver", _verified((80.0, 150.0), (90.0, 110.0)))}


def test_single_row_fmu_without_record_warns_once_at_another_torque(single_row):
    """No envelope record: the envelope is the tables' own range, here the one row at 100 N.m,
    and the record says "not verified".  Before, a one-row FMU never looked at the torque."""
    fmus = single_row["plain"]
    sched = [{"pinion_torque": T} for T in (100.0, 100.0, 120.0, 130.0, 100.0, 90.0, 125.0)]
    warns = both_runtimes_warn(fmus, sched)
    assert len(warns) == 1, warns
    assert "pinion_torque = 120 N.m" in warns[0] and "[100, 100] N.m" in warns[0]
    assert "accuracy not verified" in warns[0]
    for p in fmus.values():
        env, rec, desc = record(p)
        assert env["status"] == "not verified" and env["pinion_torque_range_Nm"] == [100.0, 100.0]
        assert env["pinion_speed_range_rad_s"] is None and env["verified_envelope"] is None
        assert rec["envelope"] == env
        assert "Accuracy NOT verified" in desc and "[100, 100] N.m" in desc


def test_verified_torque_envelope_inside_silent_outside_one_warning(single_row):
    """A verified record [80, 150] N.m on a one-row table: the applied torque is compared with
    the verified range, not with the row -- 140 N.m is silent, 160 N.m warns once (170 and 60
    after it do not warn again)."""
    fmus = single_row["verified"]
    assert both_runtimes_warn(fmus, [{"pinion_torque": T} for T in (100.0, 140.0, 80.0, 150.0)]) == []
    warns = both_runtimes_warn(fmus, [{"pinion_torque": T} for T in (100.0, 160.0, 170.0, 60.0, 100.0)])
    assert len(warns) == 1, warns
    w = warns[0]
    assert w.startswith("pinion_torque = 160 N.m at t = 0.0001 s is outside the envelope over which this "
                        "FMU's accuracy was verified (fidelity plan): pinion torque [80, 150] N.m"), w
    for p in fmus.values():
        env, rec, desc = record(p)
        assert env["status"] == "verified" and env["source"] == "plan verification"
        assert env["pinion_torque_range_Nm"] == [80.0, 150.0]
        assert env["pinion_speed_range_rad_s"] == pytest.approx([90.0, 110.0], rel=1e-12)
        assert env["worst_mesh_force_rel"] == 0.017 and env["mesh_force_target_rel"] == 0.03
        assert rec["envelope"]["verified_envelope"]["worst_at"] == {"case": "steady", "torque_Nm": 150.0}
        assert "Accuracy verified by the fidelity plan over pinion torque [80, 150] N.m" in desc
        assert "worst mesh-force error 0.017 (target 0.03)" in desc


def test_speed_leaving_the_envelope_warns_once(single_row):
    """Gear torque 0, pinion torque 100 N.m: the pair runs up at a = T1 / (I1 + I2 (Rb1/Rb2)^2)
    from 100 rad/s; the verified range [90, 110] rad/s, compared with its 10 percent margin, is left
    above 121 rad/s, i.e. after (121 - 100) / a."""
    fmus = single_row["verified"]
    a = 100.0 / (0.002 + 0.006 * (RB1 / RB2) ** 2)
    n_out = int(21.0 / a / H) + 1
    warns = both_runtimes_warn(fmus, [{"pinion_torque": 100.0, "gear_torque": 0.0}] * (n_out + 15))
    assert len(warns) == 1, warns
    w = warns[0]
    assert w.startswith("pinion_speed = 12") and "[90, 110] rad/s" in w and "10 percent margin" in w, w
    t_warn = float(w.split(" at t = ")[1].split(" s ")[0])
    assert abs(t_warn - 21.0 / a) <= 2 * H, (t_warn, 21.0 / a)


def test_temperature_input_leaving_the_envelope_warns_once(tmp_path):
    """Tables with a temperature axis 10-70 degC, verified over 20-50 degC: 60 degC (inside the
    axis, so the step is taken) warns once, naming bulk_temperature."""
    tt, _ = temp_tables()
    fmus = _build(tt, tmp_path, "temp", _verified((50.0, 150.0), (90.0, 110.0), (20.0, 50.0)))
    warns = both_runtimes_warn(fmus, [{"bulk_temperature": T} for T in (30.0, 45.0, 60.0, 65.0, 40.0, 60.0)])
    assert len(warns) == 1, warns
    assert warns[0].startswith("bulk_temperature = 60 degC at t = 0.0002 s is outside the envelope") and \
        "temperature [20, 50] degC" in warns[0], warns
    env, _, _ = record(fmus["standalone"])
    assert env["temperature_range_C"] == [20.0, 50.0]


def test_record_without_a_usable_plan_is_the_tables_range():
    """A failed estimate (``error``) or no record: "not verified", the tables' torque rows and the
    scene's speed range (rad/s and rpm, 2 pi / 60); a plan record: its own ranges."""
    t = make_tables(torque=(50.0, 100.0, 150.0))
    failed = {"kind": "as-written estimate", "error": "ValueError: no contact"}
    for v in (None, failed):
        rec = fmu_envelope_record(t, v, speed_range_rad_s=(50.0, 200.0))
        assert rec["status"] == "not verified" and rec["pinion_torque_range_Nm"] == [50.0, 150.0]
        assert rec["pinion_speed_range_rpm"] == pytest.approx([50.0 * RPM, 200.0 * RPM], rel=1e-12)
        assert rec["temperature_range_C"] is None and "worst_dte_rel" not in rec
    rec = fmu_envelope_record(t, _verified((60.0, 90.0), (10.0, 20.0)), speed_range_rad_s=(50.0, 200.0))
    assert rec["status"] == "verified" and rec["pinion_torque_range_Nm"] == [60.0, 90.0]
    assert rec["pinion_speed_range_rad_s"] == pytest.approx([10.0, 20.0], rel=1e-12)


def test_validate_json_stays_json_when_the_fmu_warns(tmp_path, capsys):
    """`gearfmu validate --json` of an FMU run outside its envelope (the default scene's tables,
    verified only over 1-2 N.m): fmpy prints the FMU's warning, on stderr, and stdout is the JSON
    report alone."""
    from ctypes import byref

    from fmpy.fmi1 import printLogMessage
    from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
    from fmpy.logging import addLoggerProxy

    from gearfmu.cli import main
    from gearfmu.pipeline import compute_tables, load

    # fmpy's default logger prints (what a fresh process does; earlier tests re-pointed its one slot)
    cb = fmi2CallbackFunctions()
    cb.logger = fmi2CallbackLoggerTYPE(printLogMessage)
    addLoggerProxy(byref(cb))
    KEPT_CALLBACKS.append(cb)
    scene = load(None)
    t = compute_tables(scene)
    from gearfmu.pipeline import gear_torque_for, max_step_for

    # the scene's own settings (validate compares with the native run of the scene, to 1e-9 of range)
    t1 = scene.operating.torque_Nm
    p = build_standalone_fmu(t, tmp_path / "v.fmu", platforms=(host_key(),), validation=False,
                             model_name=scene.fmu.model_name, damping_ratio=scene.fmu.damping_ratio,
                             pinion_speed_start_rad_s=scene.operating.speed_rad_s, pinion_torque_start_Nm=t1,
                             gear_torque_start_Nm=gear_torque_for(t, t1), max_step_s=max_step_for(scene, t),
                             damping_model=scene.solver.damping_model, scene_text=scene.text,
                             envelope=fmu_envelope_record(t, _verified((1.0, 2.0), (1.0, 2.0))))
    assert main(["validate", "--fmu", str(p), "--stop-time", "0.001", "--json"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["fmpy_problems"] == []
    assert "pinion_torque = " in err and "[1, 2] N.m" in err
