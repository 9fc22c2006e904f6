"""FMU state of the pythonfmu runtime: fmi2GetFMUstate / SetFMUstate /
SerializeFMUstate / DeSerializeFMUstate, through fmpy (an independent FMI master).

Reference: the FMU's own uninterrupted run.  FMI 2.0 (section 2.1.8) defines a
restored state as "the FMU is exactly in the state it was in when the state was
taken", so "step, save, step, restore, step again" must reproduce the outputs
of the first pass bit for bit, and so must a fresh instance given the
serialized state.  Also the capability flags in modelDescription.xml, and the
refusal of foreign or corrupted states (logged, state unchanged).
"""
import numpy as np
import fmpy
import pytest
from fmpy.fmi1 import FMICallException

from gearfmu.fmu.pythonfmu_build import build_fmu

from factories import make_tables
from support.fmpy_host import H, Inst

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    d = tmp_path_factory.mktemp("state")
    # a two-row torque axis so that the once-per-excursion warning flag is state too
    a = build_fmu(make_tables(torque=(50.0, 150.0)), d / "a.fmu", model_name="stateA", max_step_s=1e-5,
                  pinion_torque_start_Nm=100.0, damping_ratio=0.03)
    b = build_fmu(make_tables(P=3, eps=2.4, b=0.0), d / "b.fmu", model_name="stateB", max_step_s=1e-5)
    return {"a": a, "b": b}


def torque(i):
    """Pinion torque schedule that leaves the torque axis [50, 150] and comes back."""
    return 100.0 + 80.0 * np.sin(i / 5.0)


def test_capability_flags_in_model_description(fmus):
    cs = fmpy.read_model_description(str(fmus["a"])).coSimulation
    assert cs.canGetAndSetFMUstate and cs.canSerializeFMUstate


def test_step_save_step_restore_step_is_bit_identical(fmus):
    """Inputs, a tunable parameter changed before saving, the integrator state,
    outputs: all restored.  The second pass differs from the first unless the
    state is restored (checked by stepping on without restoring)."""
    x = Inst(fmus["a"], "s1")
    x.steps(0, 15, torque)
    x.set(damping_ratio=0.1, gear_torque=140.0)  # changed before the save: must come back
    x.fmu.doStep(15 * H, H)
    saved_out = x.out()
    s = x.fmu.getFMUstate()
    first = x.steps(16, 20, torque)
    x.set(damping_ratio=0.5, gear_torque=0.0, pinion_torque=-30.0)  # disturb everything
    x.steps(36, 5)
    x.fmu.setFMUstate(s)
    assert x.out() == saved_out  # outputs right after the restore
    second = x.steps(16, 20, torque)
    x.fmu.setFMUstate(s)  # the same state can be set again
    third = x.steps(16, 20, torque)
    x.fmu.freeFMUstate(s)
    on = x.steps(36, 20, torque)
    x.close()
    assert np.array_equal(first, second) and np.array_equal(first, third)
    assert not np.allclose(first[:, 0], on[:, 0])
    assert not any(st >= 3 for st, _ in x.log), x.log


def test_serialized_state_into_fresh_instance(fmus):
    """Serialize in one instance, deserialize into a fresh instance of the same
    FMU (never stepped): it continues exactly like the original.  Includes the
    damping ratio (tunable) and the torque-range warning flag."""
    x = Inst(fmus["a"], "s2")
    x.set(damping_ratio=0.07)
    x.steps(0, 12, torque)
    s = x.fmu.getFMUstate()
    blob = x.fmu.serializeFMUstate(s)
    x.fmu.freeFMUstate(s)
    x.log.clear()
    ref = np.vstack([x.steps(12, 1), x.steps(13, 24, torque)])  # first step: the input held from before
    warn_ref = sum(1 for st, m in x.log if st == 1 and "outside the tables' torque axis" in m)
    x.close()

    y = Inst(fmus["a"], "s3")  # start values differ: pinion_torque 100 != torque(11), damping 0.03
    s2 = y.fmu.deSerializeFMUstate(blob)
    y.fmu.setFMUstate(s2)
    y.fmu.freeFMUstate(s2)
    y.log.clear()
    got = np.vstack([y.steps(12, 1), y.steps(13, 24, torque)])
    warn_got = sum(1 for st, m in y.log if st == 1 and "outside the tables' torque axis" in m)
    y.close()
    assert np.array_equal(ref, got)
    assert warn_ref > 0 and warn_got == warn_ref  # the once-per-excursion flag is state too
    assert abs(torque(11) - 100.0) > 10.0  # so the held input really had to come from the state


def test_state_before_initialisation_and_after_terminate(fmus):
    """A state taken before the first step restores the un-stepped instance;
    one taken after terminate restores 'terminated' (steps refused, logged)."""
    x = Inst(fmus["a"], "s5")
    s0 = x.fmu.getFMUstate()
    a = x.steps(0, 10)
    x.fmu.setFMUstate(s0)
    b = x.steps(0, 10)
    assert np.array_equal(a, b)
    x.fmu.terminate()
    st = x.fmu.getFMUstate()
    x.fmu.setFMUstate(s0)
    assert np.array_equal(x.steps(0, 10), a)  # un-terminated by the restore
    x.fmu.setFMUstate(st)
    with pytest.raises(Exception):
        x.fmu.doStep(10 * H, H)
    assert x.log[-1] == (3, "fmi2DoStep: illegal call sequence: not allowed in state terminated "
                            "(allowed in: stepComplete)")
    for s in (s0, st):
        x.fmu.freeFMUstate(s)
    x.fmu.freeInstance()


def _status(call, *args):
    try:
        return 0, call(*args)
    except FMICallException as exc:
        return exc.status, None


def _reseal(blob: bytes) -> bytes:
    """The state with the FMI layer's checksum computed again (FNV-1a 64 over the whole state with
    its checksum field, bytes 32-40 of the header, read as 0; gearfmu/fmu/runtime/pyshim.c)."""
    b = bytearray(blob)
    b[32:40] = bytes(8)
    h = 14695981039346656037
    for x in b:
        h = ((h ^ x) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    b[32:40] = h.to_bytes(8, "little")
    return bytes(b)


def test_foreign_and_corrupted_states_are_refused_with_log(fmus):
    """A state of a different FMU, a one-bit-flipped state, a truncated state and garbage: each
    refused by fmi2DeSerializeFMUstate (fmi2Error) with the reason logged; a state whose checksum
    of the FMI layer is right but whose slave part is corrupted is refused by fmi2SetFMUstate
    (fmi2Error, the slave's reason); the instance continues unchanged."""
    a = Inst(fmus["a"], "s6")
    b = Inst(fmus["b"], "s7")
    b.steps(0, 5)
    sb = b.fmu.getFMUstate()
    blob_b = b.fmu.serializeFMUstate(sb)
    a.steps(0, 5)
    sa = a.fmu.getFMUstate()
    blob_a = a.fmu.serializeFMUstate(sa)
    ref = a.steps(5, 10)
    a.fmu.setFMUstate(sa)
    flipped = bytearray(blob_a)
    flipped[len(flipped) // 2] ^= 4
    not_ours = "fmi2DeSerializeFMUstate: not a state of this FMU"
    size = f"this FMU's state has {len(blob_a)}"
    assert len(blob_b) != len(blob_a)  # three pair slots against two
    cases = {"different FMU": (blob_b, f"fmi2DeSerializeFMUstate: {len(blob_b)} bytes, {size}"),
             "one bit flipped": (bytes(flipped), not_ours),
             "too short": (blob_a[:20], f"fmi2DeSerializeFMUstate: 20 bytes, {size}"),
             "garbage": (b"x" * len(blob_a), not_ours)}
    for reason, (blob, words) in cases.items():
        a.log.clear()
        assert _status(a.fmu.deSerializeFMUstate, blob) == (3, None), reason
        assert a.log == [(3, words)], (reason, a.log)
    slave_flipped = bytearray(blob_a)
    slave_flipped[-40] ^= 1  # in the slave's part, before its SHA-256
    a.log.clear()
    st, s = _status(a.fmu.deSerializeFMUstate, _reseal(bytes(slave_flipped)))
    assert st == 0
    assert _status(a.fmu.setFMUstate, s)[0] == 3
    assert a.log == [(3, "fmi2SetFMUstate refused: state checksum mismatch (bytes corrupted); instance state unchanged")]
    a.fmu.freeFMUstate(s)
    assert np.array_equal(a.steps(5, 10), ref)
    for inst, s in ((a, sa), (b, sb)):
        inst.fmu.freeFMUstate(s)
        inst.close()


def test_isolation_with_interleaved_state_save_restore(fmus):
    """Two instances of one FMU and one of another, stepped interleaved in one
    process, with save/restore on one of them in the middle: each gives bit for
    bit what it gives alone."""
    def alone(key):
        x = Inst(fmus[key], f"alone{key}")
        r = x.steps(0, 30, torque if key == "a" else None)
        x.close()
        return r

    ref_a, ref_b = alone("a"), alone("b")
    a1, b1, a2 = Inst(fmus["a"], "ia1"), Inst(fmus["b"], "ib"), Inst(fmus["a"], "ia2")
    ra, rb, r2 = [], [], []

    def step_all(i, with_a2=True):
        for x, r, sched in ((a1, ra, torque), (b1, rb, None), (a2, r2, torque)):
            if x is a2 and not with_a2:
                continue
            if sched is not None:
                x.set(pinion_torque=sched(i))
            x.fmu.doStep(i * H, H)
            r.append(x.out())

    for i in range(0, 11):
        step_all(i)
    saved = a2.fmu.getFMUstate()
    for i in range(11, 20):
        step_all(i)
    a2.fmu.setFMUstate(saved)  # rewind a2 to after step 10 while the others go on
    a2.fmu.freeFMUstate(saved)
    del r2[11:]
    for i in range(11, 20):
        a2.set(pinion_torque=torque(i))
        a2.fmu.doStep(i * H, H)
        r2.append(a2.out())
        step_all(i + 9, with_a2=False)  # a1, b1 go on with steps 20..28 in between
    for i in range(len(ra), 30):
        step_all(i, with_a2=False)
    for i in range(len(r2), 30):
        a2.set(pinion_torque=torque(i))
        a2.fmu.doStep(i * H, H)
        r2.append(a2.out())
    for x in (a1, b1, a2):
        x.close()
    assert np.array_equal(np.array(ra), ref_a)
    assert np.array_equal(np.array(r2), ref_a)
    assert np.array_equal(np.array(rb), ref_b)
