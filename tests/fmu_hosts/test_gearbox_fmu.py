"""The gearbox FMU (gearfmu/fmu/gearbox_build.py, docs/gearbox.md "The gearbox FMU") against
references its C code did not produce.

* The native gearbox solver (numba, gearfmu/gearbox/kernels.py), an implementation of the same
  equations in another language: on the example reducer and on a hard case (contact loss and
  impacts in stage 1 while stage 2 carries load), all three integrators, the FMU stepped
  at exactly the native communication step: every output within 1e-9 of its range.
* The linear limit (constant mesh stiffness, no errors, no backlash, contact_zone force law): the
  response to a torque step from the static state is the matrix exponential of the first-order
  system with M, K, C assembled element by element in tests/unit/gearbox/test_gearbox_modes.py and
  tests/unit/gearbox/test_gearbox_native.py, the static state worked out by hand here: within 1e-6 of each
  signal's range.
* The kernel's right-hand side gb_derivatives (the form a Model Exchange host integrates) in the
  linear limit: the accelerations -M^-1 (K theta + C omega - f) with the hand-assembled M, K, C,
  mapped to the deviation state.
* The pair FMU (gear_model.c over gearkernel.c, another C model in other state variables): one stage
  without shafts reproduces it on the pair hard cases of gearfmu.bench to 1e-9 of the range.
* The FMI 2 FMU of the same gearbox for its FMI 3 twin (bit for bit); the linux64 binary run by
  tests/fmu_hosts/fmi_host.c for the win64 binary under Wine and the aarch64 binary under qemu (the SHA-256
  of the output); fmpy's validate_fmu; tests/fmu_hosts/fmi_fuzz.c's contract (no crash, every refusal
  logged); hashlib's SHA-256 for the tables checksums.
"""
import hashlib
import json
import subprocess
import sys
import zipfile
from pathlib import Path

import fmpy
import fmpy.validation
import numpy as np
import pytest
import scipy.linalg
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave

import fuzz_fmu
from gearfmu.bench import hard_case
from gearfmu.fmu.gearbox_build import build_gearbox_fmu, gearbox_settings, variables_of_fmu
from gearfmu.fmu.gearbox_validation import native_outputs_by_vr, native_run
from gearfmu.fmu.standalone_build import build_standalone_fmu
from gearfmu.gearbox.cases import gearbox_case
from gearfmu.gearbox.model import Mesh, build_gearbox
from gearfmu.gearbox.native import choose_max_step_s

from support.cross_tools import AARCH64_SYSROOT, compile_host, qemu, run_file, wine_env
from support.fmpy_host import slave, status
from support.gearbox_cases import (K_IN, K_MID, K_OUT, S1, S2, c_mesh, hand_damping, hand_damping_of_mid, hand_matrices,
                                   kernel_library, linear_gearbox)

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
EXAMPLE = REPO / "examples" / "scenes" / "gearbox_two_stage.toml"
TOL = 1e-9  # of each output's range
HOST = ("x86_64-linux",)


def _settings(model, *, torque, speed, angle=0.0, load=None, integrator="rk4_node", stop, H, hmax=None):
    if hmax is None:
        hmax = choose_max_step_s(model, max(1.5 * abs(speed), 1.0), reference_torque_Nm=torque)
    return gearbox_settings(model, motor_torque_start_Nm=torque, load_torque_start_Nm=load,
                            motor_speed_start_rad_s=speed, motor_angle_start_rad=angle, max_step_s=hmax,
                            integrator=integrator, stop_time_s=stop, output_interval_s=H)


def _build(model, settings, path, **kw):
    kw.setdefault("platforms", HOST)
    kw.setdefault("validation", False)
    return build_gearbox_fmu(model, path, settings=settings, model_name=path.stem, **kw)


def run_fmu(path, names, stop, H, inputs=None, unzip=None):
    """Step the FMU (FMI 2 or 3) with fmpy's low-level API at exactly H from t_k = k*H and read the outputs
    ``names`` after initialisation and after every step.  ``inputs``: {name: value} set after the
    initialisation (a step of the inputs at t = 0)."""
    md = fmpy.read_model_description(str(path))
    fmi3 = md.fmiVersion.startswith("3")
    d = fmpy.extract(str(path), unzipdir=None if unzip is None else str(unzip))
    s = (FMU3Slave if fmi3 else FMU2Slave)(guid=md.guid, unzipDirectory=d,
                                          modelIdentifier=md.coSimulation.modelIdentifier, instanceName="t")
    var = {v.name: v for v in md.modelVariables}
    refs = []
    for n in names:
        if n in var:
            refs.append((var[n].valueReference, 0, 1))
        else:   # FMI 3 array element
            base, i = n[:-1].split("[")
            refs.append((var[base].valueReference, int(i) - 1, int(var[base].shape[0])))
    s.instantiate()
    if fmi3:
        s.enterInitializationMode(startTime=0.0)
    else:
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
    s.exitInitializationMode()
    for n, v in (inputs or {}).items():
        (s.setFloat64 if fmi3 else s.setReal)([var[n].valueReference], [float(v)])

    def read():
        row = []
        for vr, i, size in refs:
            vals = s.getFloat64([vr], nValues=size) if fmi3 else s.getReal([vr])
            row.append(vals[i])
        return row

    rows = [read()]
    n = int(round(stop / H))
    for k in range(n):
        s.doStep(k * H, H)
        rows.append(read())
    s.terminate()
    s.freeInstance()
    a = np.array(rows)
    return {name: a[:, i] for i, name in enumerate(names)}


def _rel(ref, got):
    rng = np.ptp(ref) if np.ptp(ref) > 0 else max(float(np.max(np.abs(ref))), 1e-300)
    return float(np.max(np.abs(np.asarray(got) - np.asarray(ref))) / rng)


def _against_native(path, model, settings):
    """Worst |FMU - native| / range over every output, and the two runs."""
    variables = variables_of_fmu(model, settings)
    outs = [v for v in variables if v.causality == "output"]
    fmu = run_fmu(path, [v.name for v in outs], settings.stop_time_s, settings.output_interval_s)
    nat = native_run(model, settings)
    by = native_outputs_by_vr(model, variables)
    worst = {v.name: _rel(nat[by[v.value_reference]], fmu[v.name]) for v in outs}
    return worst, fmu, nat


# ------------------------------------------------------------- the example
@pytest.fixture(scope="module")
def example(tmp_path_factory):
    """The example reducer's FMU, FMI 2 and FMI 3, five platforms, from the drivetrain scene."""
    from gearfmu import pipeline
    from gearfmu.scene.drivetrain import load_drivetrain

    d = tmp_path_factory.mktemp("gbfmu")
    scene = load_drivetrain(EXAMPLE)
    out = {"scene": scene, "dir": d}
    for v in (2, 3):
        res = pipeline.build_drivetrain_fmu(scene, d / f"example{v}.fmu", fmi_version=v)
        out[v] = res.fmu_path
        out["model"], out["settings"] = res.model, res.settings
    return out


def test_example_fmu_equals_native_gearbox_solver(example):
    worst, fmu, nat = _against_native(example[2], example["model"], example["settings"])
    print("example: worst |FMU - native| / range", max(worst.values()))
    assert max(worst.values()) <= TOL, sorted(worst.items(), key=lambda kv: -kv[1])[:3]
    assert np.ptp(fmu["stage2.mesh_force"]) > 100.0 and len(fmu["motor_speed"]) == 1001


def test_example_validation_record_reproduced(example, tmp_path):
    """The FMU's own record: stepped at exactly stepSize it reproduces reference_result.csv (the native
    gearbox solver) to 1e-9 of each column's range; the record names every stage's table checksums."""
    with zipfile.ZipFile(example[2]) as z:
        rec = json.loads(z.read("resources/validation/record.json"))
        ref = z.read("resources/validation/reference_result.csv").decode().splitlines()
        for name, st in rec["stages"].items():
            assert hashlib.sha256(z.read(f"resources/{name}/tables.bin")).hexdigest() == st["tables_bin_sha256"]
    assert rec["model"] == "gearbox" and rec["reference"]["sha256"] == hashlib.sha256(
        ("\n".join(ref) + "\n").encode()).hexdigest()
    names = ref[0].split(",")[1:]
    data = np.array([[float(x) for x in ln.split(",")] for ln in ref[1:]])
    got = run_fmu(example[2], names, rec["reference"]["stop_time_s"], rec["reference"]["output_interval_s"])
    worst = max(_rel(data[:, i + 1], got[n]) for i, n in enumerate(names))
    assert worst <= TOL


def test_fmi3_equals_fmi2_bit_for_bit(example):
    variables = variables_of_fmu(example["model"], example["settings"])
    names = [v.name for v in variables if v.causality == "output"]
    s = example["settings"]
    a = run_fmu(example[2], names, 0.01, s.output_interval_s)
    b = run_fmu(example[3], names, 0.01, s.output_interval_s)
    assert all(np.array_equal(a[n], b[n]) for n in names)
    md = fmpy.read_model_description(str(example[3]))
    arrays = {v.name: int(v.shape[0]) for v in md.modelVariables if getattr(v, "shape", None) and v.causality == "output"}
    assert arrays == {"stage1.pair_force": 3, "stage1.load_sharing": 3, "stage2.pair_force": 3,
                      "stage2.load_sharing": 3}


def test_fmpy_validates_both_versions_and_the_interface(example):
    for v in (2, 3):
        assert fmpy.validation.validate_fmu(str(example[v])) == []
    md = fmpy.read_model_description(str(example[2]))
    assert md.variableNamingConvention == "structured" and md.coSimulation.needsExecutionTool is False
    var = {x.name: x for x in md.modelVariables}
    for name, caus, unit in (("motor_torque", "input", "N.m"), ("load_torque", "input", "N.m"),
                             ("motor_speed", "output", "rad/s"), ("load_angle", "output", "rad"),
                             ("stage1.pinion_speed", "output", "rad/s"), ("stage2.gear_angle", "output", "rad"),
                             ("stage1.dte", "output", "m"), ("stage2.mesh_force", "output", "N"),
                             ("stage1.pair_force[3]", "output", "N"), ("stage2.load_sharing[1]", "output", None),
                             ("stage2.mesh_stiffness", "output", "N/m"), ("intermediate_shaft.torque", "output", "N.m"),
                             ("stage1.damping_ratio", "parameter", "1"), ("max_step", "parameter", "s")):
        assert var[name].causality == caus, name
        assert unit is None or var[name].unit == unit, name
    assert var["stage1.damping_ratio"].variability == "tunable"
    assert var["integrator"].max == "3" and var["integrator"].start == "2"
    with zipfile.ZipFile(example[2]) as z:
        names = set(z.namelist())
        page = z.read("documentation/index.html").decode()
    for f in ("resources/stage1/tables.bin", "resources/stage2/tables.json", "resources/gearfmu_gearbox.txt",
              "resources/stage1/scene.toml", "resources/scene.toml", "sources/fmi2_gearbox_all.c",
              "sources/gb_kernel.c", "sources/gk_pair.h", "documentation/_main.html"):
        assert f in names, f
    assert not [n for n in names if n.startswith("sources/") and n.startswith("sources/fmi2F")]
    for word in ("stage1", "stage2", "intermediate_shaft", "output_shaft", "Validation record"):
        assert word in page
    # no file of the FMU holds a path of the build machine (tests/fmu_hosts/test_fmu_strict.py for the pair FMU)
    from gearfmu.fmu.fmudoc import build_machine_paths

    d = example["dir"] / "unzipped"
    with zipfile.ZipFile(example[2]) as z:
        z.extractall(d)
    assert build_machine_paths(d) == []


def test_tampered_stage_tables_refused(example, tmp_path):
    """One flipped byte in a stage's tables.bin: instantiation is refused by the C model (its SHA-256)
    with a message naming the file, and gearfmu refuses the FMU before loading it (the provenance)."""
    from gearfmu.fmu.compare import FmuMismatchError, open_fmu

    bad = tmp_path / "bad.fmu"
    with zipfile.ZipFile(example[2]) as zin, zipfile.ZipFile(bad, "w") as zout:
        for item in zin.namelist():
            data = zin.read(item)
            if item == "resources/stage2/tables.bin":
                data = data[:100] + bytes([data[100] ^ 1]) + data[101:]
            zout.writestr(item, data)
    with pytest.raises(FmuMismatchError, match="resources/stage2/tables.bin does not match"):
        open_fmu(bad)
    sl, _, msgs = slave(bad, tmp_path, "bad", instantiate=False)
    with pytest.raises(Exception):
        sl.instantiate(loggingOn=True, callbacks=sl._test_callbacks)
    assert any("resources/stage2/tables.bin: SHA-256 checksum mismatch" in m for _, m in msgs), msgs


@pytest.mark.parametrize("integrator", [2, 3])
def test_state_save_restore_and_bad_inputs(example, tmp_path, integrator):
    """Saving the FMU state, stepping, restoring and stepping again gives the same outputs bit for bit (with
    rk4_node and with rk4_seg: the restore derives the integrator from the restored parameter); a NaN motor
    torque and a negative step are discarded with a message and leave the state unchanged."""
    s, var, msgs = slave(example[2], tmp_path)
    out = [var[n] for n in ("stage1.dte", "stage2.mesh_force", "load_speed", "intermediate_shaft.torque")]
    s.setInteger([var["integrator"]], [integrator])
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    H = example["settings"].output_interval_s
    for k in range(10):
        s.doStep(k * H, H)
    st = s.getFMUstate()
    blob = s.serializeFMUstate(st)
    first = []
    for k in range(10, 20):
        s.doStep(k * H, H)
        first.append(s.getReal(out))
    s.setFMUstate(s.deSerializeFMUstate(blob))
    s.setReal([var["motor_torque"]], [float("nan")])
    assert status(s.fmi2DoStep, s.component, 10 * H, H, 1) == 2   # fmi2Discard
    s.setReal([var["motor_torque"]], [example["settings"].motor_torque_start_Nm])
    assert status(s.fmi2DoStep, s.component, 10 * H, -H, 1) == 2
    second = []
    for k in range(10, 20):
        s.doStep(k * H, H)
        second.append(s.getReal(out))
    assert first == second
    text = " ".join(m for _, m in msgs)
    assert "motor_torque = nan: not finite; step rejected, state unchanged" in text
    assert "must be finite and > 0" in text
    s.terminate()
    s.freeInstance()


def test_c_fuzz_of_the_gearbox_fmu(example):
    """tests/fmu_hosts/fmi_fuzz.c's random call sequences (the checks of tests/fmu_hosts/test_fuzz.py, which the gearbox FMU
    shares through the pair's FMI layer and plumbing): no host crash, every refusal logged, out-of-order
    calls refused as such."""
    res = fuzz_fmu.run_c_fuzz(example[2], 600, first_seed=20261201, batch=300, jobs=2)
    assert res["sequences"] == 600 and res["host_crashes"] == 0, res["crashes"]
    assert res["unlogged_refusals"] == 0, res["unlogged_examples"]
    assert res["bad_status"] == 0 and res["fatals"] == 0
    assert res["sequences_breaking_order"] == res["sequences"] - res["instantiate_refused"]
    assert res["illegal_sequence_refusals"] > 600 and res["discards"] > 100


# -------------------------------------------------------------- hard case
@pytest.fixture(scope="module")
def contact_loss(tmp_path_factory):
    d = tmp_path_factory.mktemp("gbcl")
    model, kw = gearbox_case("contact_loss", 60)
    out = {}
    for integ in ("rk4", "rk4_kink", "rk4_node", "rk4_seg"):
        s = _settings(model, torque=kw["motor_torque_Nm"], speed=kw["motor_speed_start_rad_s"],
                      angle=kw["motor_angle_start_rad"], integrator=integ, stop=kw["stop_time_s"],
                      H=kw["comm_step_s"])
        out[integ] = (_build(model, s, d / f"cl_{integ}.fmu"), s)
    return model, out


@pytest.mark.parametrize("integrator", ["rk4", "rk4_kink", "rk4_node", "rk4_seg"])
def test_contact_loss_in_one_stage_equals_native(contact_loss, integrator):
    """Stage 1 loses contact (no pair in contact, then impacts) while stage 2 keeps carrying load; the FMU follows the native solver to 1e-9 of every output's range."""
    model, fmus = contact_loss
    path, s = fmus[integrator]
    worst, fmu, nat = _against_native(path, model, s)
    print(integrator, "contact loss: worst |FMU - native| / range", max(worst.values()), "events", nat.info["events"])
    assert max(worst.values()) <= TOL, sorted(worst.items(), key=lambda kv: -kv[1])[:3]
    lost = (fmu["stage1.mesh_force"] == 0.0) & (fmu["stage1.mesh_stiffness"] == 0.0)
    assert 5 <= np.count_nonzero(lost) < len(lost) // 2          # stage 1 loses contact again and again ...
    assert np.min(fmu["stage2.mesh_force"]) > 0.0                # ... while stage 2 carries load throughout


# --------------------------------------------------------- the linear limit
def test_linear_limit_torque_step_against_matrix_exponential(tmp_path):
    """Constant mesh stiffness, no error, no backlash, contact_zone (F = k x + c v): from the static state
    under 150 N*m at 300 rad/s the motor torque steps to 250 N*m against a load of 1000 N*m.  Reference:
    expm of the first-order system with the hand-assembled M, K, C; the static state by hand (every shaft
    twisted by its torque over k, every mesh deflected by F = T_p/Rb_p over k)."""
    model = linear_gearbox()
    H, n, T0, w0 = 1e-4, 200, 150.0, 300.0
    s = _settings(model, torque=T0, load=1000.0, speed=w0, stop=n * H, H=H)
    path = _build(model, s, tmp_path / "linear.fmu")
    names = ["s1.dte", "s2.dte", "load_speed", "intermediate_shaft.torque", "s1.mesh_force", "motor_speed"]
    got = run_fmu(path, names, n * H, H, inputs={"motor_torque": 250.0, "load_torque": 1000.0})
    # the static state by hand, chain [motor, p1, g1, p2, g2, load], motor angle 0
    g1 = S1["rb1"] / S1["rb2"]
    g2 = g1 * S2["rb1"] / S2["rb2"]
    th = np.zeros(6)
    th[1] = th[0] - T0 / K_IN
    th[2] = (S1["rb1"] * th[1] - (T0 / S1["rb1"]) / S1["k"]) / S1["rb2"]
    th[3] = th[2] - (T0 / g1) / K_MID
    th[4] = (S2["rb1"] * th[3] - (T0 / g1 / S2["rb1"]) / S2["k"]) / S2["rb2"]
    th[5] = th[4] - (T0 / g2) / K_OUT
    w = w0 * np.array([1.0, 1.0, g1, g1, g2, g2])
    M, K = hand_matrices()
    C = hand_damping()
    f = np.zeros(6)
    f[0], f[5] = 250.0, -1000.0
    A = np.zeros((13, 13))
    Mi = np.linalg.inv(M)
    A[:6, 6:12] = np.eye(6)
    A[6:12, :6] = -Mi @ K
    A[6:12, 6:12] = -Mi @ C
    A[6:12, 12] = Mi @ f
    Z = np.array([scipy.linalg.expm(A * (i * H)) @ np.concatenate([th, w, [1.0]]) for i in range(n + 1)])
    x1 = S1["rb1"] * Z[:, 1] - S1["rb2"] * Z[:, 2]
    x2 = S2["rb1"] * Z[:, 3] - S2["rb2"] * Z[:, 4]
    refs = {"s1.dte": x1, "s2.dte": x2, "load_speed": Z[:, 11], "motor_speed": Z[:, 6],
            "intermediate_shaft.torque": K_MID * (Z[:, 2] - Z[:, 3]) + hand_damping_of_mid(Z),
            "s1.mesh_force": S1["k"] * x1 + c_mesh(S1) * (S1["rb1"] * Z[:, 7] - S1["rb2"] * Z[:, 8])}
    # the static state first (the FMU's outputs at t = 0), then the response
    assert abs(got["s1.mesh_force"][0] - T0 / S1["rb1"]) <= 1e-9 * T0 / S1["rb1"]
    assert abs(got["intermediate_shaft.torque"][0] - T0 / g1) <= 1e-9 * T0 / g1
    worst = {name: _rel(ref, got[name]) for name, ref in refs.items()}
    print("linear limit: |FMU - expm| / range", worst)
    assert max(worst.values()) <= 1e-6, worst
    # the response does ring at the gearbox's modes: a real test of the dynamics
    assert np.ptp(x1) > 1e-7 and np.ptp(refs["intermediate_shaft.torque"]) > 10.0


# ------------------------------------------------- one stage is the pair FMU
@pytest.mark.parametrize("case", ["single_sided_impacts", "double_sided_impacts", "high_contact_ratio"])
def test_one_stage_without_shafts_equals_the_pair_fmu(case, tmp_path):
    """The gearbox FMU of a single mesh (motor = pinion, load = gear) and the pair's standalone FMU on the
    same tables and inputs (other state variables: the gear deviation against the DTE) agree to 1e-9 of
    every output's range."""
    t, kw = hard_case(case)
    h = kw["comm_step_s"] / 32
    t2 = kw["pinion_torque_Nm"] * t.base_radius_gear_m / t.base_radius_pinion_m   # the static balance
    model = build_gearbox([Mesh("pair", t, kw["damping_ratio"], kw.get("damping_model", "elastobacklash"))],
                          motor="pair.pinion", load="pair.gear")
    s = _settings(model, torque=kw["pinion_torque_Nm"], load=t2, speed=kw["pinion_speed_start_rad_s"],
                  angle=kw["pinion_angle_start_rad"], stop=kw["stop_time_s"], H=kw["comm_step_s"], hmax=h)
    gb = _build(model, s, tmp_path / "gb.fmu")
    pair = build_standalone_fmu(t, tmp_path / "pair.fmu", damping_ratio=kw["damping_ratio"],
                                pinion_speed_start_rad_s=kw["pinion_speed_start_rad_s"],
                                pinion_angle_start_rad=kw["pinion_angle_start_rad"],
                                pinion_torque_start_Nm=kw["pinion_torque_Nm"], gear_torque_start_Nm=t2,
                                max_step_s=h, damping_model=kw.get("damping_model", "elastobacklash"),
                                stop_time_s=kw["stop_time_s"], output_interval_s=kw["comm_step_s"], validation=False,
                                platforms=HOST)
    names = {"pinion_speed": "pair.pinion_speed", "gear_speed": "pair.gear_speed", "pinion_angle": "pair.pinion_angle",
             "gear_angle": "pair.gear_angle", "dte": "pair.dte", "mesh_force": "pair.mesh_force",
             "mesh_stiffness": "pair.mesh_stiffness"}
    for i in range(t.slots):
        names[f"pair_force[{i + 1}]"] = f"pair.pair_force[{i + 1}]"
        names[f"load_sharing[{i + 1}]"] = f"pair.load_sharing[{i + 1}]"
    a = run_fmu(pair, list(names), kw["stop_time_s"], kw["comm_step_s"])
    b = run_fmu(gb, list(names.values()), kw["stop_time_s"], kw["comm_step_s"])
    worst = {n: _rel(a[n], b[names[n]]) for n in names}
    print(case, "pair FMU against the one-stage gearbox FMU:", max(worst.values()))
    assert max(worst.values()) <= TOL, sorted(worst.items(), key=lambda kv: -kv[1])[:3]


# --------------------------------------------------------------- platforms
@pytest.fixture(scope="module")
def host_exe(tmp_path_factory):

    return compile_host(tmp_path_factory.mktemp("gbhost"))


def _host_args(example, fmu_dir, n):
    md = fmpy.read_model_description(str(example[2]))
    vrs = [v.valueReference for v in md.modelVariables if v.causality == "output"]
    H = example["settings"].output_interval_s
    return [str(fmu_dir), md.coSimulation.modelIdentifier, md.guid, repr(n * H), repr(H), ",".join(map(str, vrs))]


def _unzipped(example, tmp_path):
    d = tmp_path / "example"
    with zipfile.ZipFile(example[2]) as z:
        z.extractall(d)
    return d


def test_win64_under_wine_and_aarch64_under_qemu_equal_linux64(example, host_exe, tmp_path):
    """The example gearbox FMU's win64 DLL (under Wine, a win64 build of tests/fmu_hosts/fmi_host.c) and its
    aarch64-linux binary (under qemu-aarch64) give output files with the SHA-256 of the linux64 binary's."""

    d = _unzipped(example, tmp_path)
    args = _host_args(example, d, 200)
    rc, ref, err = run_file([str(host_exe), *args], tmp_path, "linux")
    assert rc == 0, err
    assert len(ref.splitlines()) == 202
    sha = lambda text: hashlib.sha256(text.encode()).hexdigest()
    q = qemu()
    exe = compile_host(tmp_path, "aarch64-linux-gnu")
    rc, out, err = run_file([q, "-L", str(AARCH64_SYSROOT), str(exe), *args], tmp_path, "qemu")
    assert rc == 0, err[-2000:]
    assert sha(out) == sha(ref)
    exe = compile_host(tmp_path, "x86_64-windows-gnu")
    wargs = _host_args(example, "Z:" + d.as_posix(), 200)
    with wine_env(tmp_path) as (w, env):
        rc, out, err = run_file([w, str(exe), *wargs], tmp_path, "wine", env=env)
    assert rc == 0, err[-2000:]
    assert sha(out) == sha(ref)
    with zipfile.ZipFile(example[2]) as z:
        plats = {n.split("/")[1] for n in z.namelist() if n.startswith("binaries/") and n.count("/") == 2}
    assert plats == {"linux64", "aarch64-linux", "win64", "darwin64", "aarch64-darwin"}


# --------------------------------------------------------------------- CLI
def test_cli_build_validate_and_refusals(tmp_path):
    """gearfmu build DRIVETRAIN.toml says what it built (runtime, FMI version, both interfaces by default
    as the pair FMU, platforms); --runtime pythonfmu, --tables and --me-node-events with --interface cs
    are refused with one line and status 2; gearfmu validate passes."""
    def gearfmu(*args):
        return subprocess.run([sys.executable, "-m", "gearfmu.cli", *args], capture_output=True, text=True,
                              timeout=900, cwd=REPO)

    out = tmp_path / "g.fmu"
    p = gearfmu("build", str(EXAMPLE), "-o", str(out), "--platforms", "x86_64-linux", "-q")
    assert p.returncode == 0, p.stderr
    assert "gearbox of 2 stages, 3 elastic shafts, 6 bodies" in p.stdout
    assert ("runtime standalone (all C, needs no Python), FMI 2.0 Co-Simulation and Model Exchange, platforms: "
            "linux64") in p.stdout
    for bad, words in ((["--runtime", "pythonfmu"], "built with the standalone C runtime only"),
                       (["--tables", "x.csv"], "--tables: not offered for a drivetrain scene"),
                       (["--interface", "cs", "--me-node-events", "all"],
                        "--me-node-events all: only with Model Exchange")):
        p = gearfmu("build", str(EXAMPLE), "-o", str(tmp_path / "x.fmu"), *bad)
        assert p.returncode == 2 and words in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr
    p = gearfmu("validate", str(EXAMPLE), "--fmu", str(out), "--stop-time", "0.01", "-q")
    assert p.returncode == 0, p.stdout + p.stderr
    assert "PASSED: every output within 1e-09 of its range" in p.stdout and "intermediate_shaft.torque" in p.stdout
    # a gear-pair FMU is refused for a drivetrain scene, and the gearbox FMU for a pair scene, each in one line
    t, kw = hard_case("single_sided_impacts")
    pair = build_standalone_fmu(t, tmp_path / "pair.fmu", validation=False, platforms=HOST)
    p = gearfmu("validate", str(EXAMPLE), "--fmu", str(pair), "-q")
    assert p.returncode == 2 and "is a gear-pair FMU, not a gearbox FMU" in p.stderr, p.stderr
    p = gearfmu("validate", str(REPO / "examples" / "scenes" / "seed000_table1.toml"), "--fmu", str(out), "-q")
    assert p.returncode == 2 and "was built from scene 'gearbox_two_stage'" in p.stderr, p.stderr


# ------------------------------------------- the right-hand side of the kernel
def test_kernel_right_hand_side_in_the_linear_limit(tmp_path):
    """gb_derivatives(t, y) of the linear gearbox (constant mesh stiffness, no error, no backlash,
    contact_zone: F = k x + c v) at a state far from equilibrium equals the accelerations of the
    hand-assembled M, K, C (tests/unit/gearbox/test_gearbox_modes.py, tests/unit/gearbox/test_gearbox_native.py) mapped to the
    deviation state: psi'' = alpha_0, u_i'' = alpha_i - g_i alpha_0, to 1e-9 of the largest."""
    L = kernel_library(tmp_path)
    model = linear_gearbox()
    keep = []
    pairs = []
    for mesh in model.meshes:
        t = mesh.tables
        arrs = [np.ascontiguousarray(a, dtype=float) for a in (t.torque_Nm, t.k_N_per_m, t.e_m, t.backlash_half_m)]
        pm = np.zeros(L.gk_sizeof_model() // 8 + 1)
        keep += arrs + [pm]
        assert L.gk_init(pm.ctypes.data, t.slots, t.n_phi, t.n_torque, *(a.ctypes.data for a in arrs),
                         t.phi_period_rad, t.base_radius_pinion_m, t.base_radius_gear_m, t.inertia_pinion_kgm2,
                         t.inertia_gear_kgm2, t.k_mean_N_per_m) == 0
        assert L.gk_set_damping(pm.ctypes.data, mesh.damping_ratio, 1) == 0
        pairs.append(pm)
    gb = np.zeros(L.gb_sizeof_model() // 8 + 1)
    work = np.zeros(L.gb_sizeof_work() // 8 + 1)
    inv_i = 1.0 / model.inertia_kgm2
    g = np.ascontiguousarray(model.g)
    assert L.gb_init(gb.ctypes.data, model.n_bodies, inv_i.ctypes.data, g.ctypes.data, int(model.load_body), 1, 1) == 0
    for m, pm in enumerate(pairs):
        p, q = model.mesh_bodies[m]
        assert L.gb_add_mesh(gb.ctypes.data, pm.ctypes.data, int(p), int(q), 1) == 0
    for s, (a, b) in enumerate(model.shaft_bodies):
        assert L.gb_add_shaft(gb.ctypes.data, int(a), int(b), model.shaft_k_Nm_per_rad[s],
                              model.shaft_c_Nms_per_rad[s], 1) == 0
    # the output layout the interface spec's indices are relative to: Python's and C's the same
    from gearfmu.fmu.gearbox_interface import mesh_offset, n_outputs, shaft_offset

    assert [L.gb_mesh_offset(gb.ctypes.data, m) for m in range(2)] == [mesh_offset(model, m) for m in range(2)]
    assert L.gb_shaft_offset(gb.ctypes.data) == shaft_offset(model) and L.gb_n_outputs(gb.ctypes.data) == n_outputs(model)
    rng = np.random.default_rng(31)
    n = model.n_bodies
    y = np.zeros(2 * n)
    y[0], y[1] = 0.37, 280.0
    y[2::2] = rng.normal(0.0, 1e-4, n - 1)     # deviations of a few 1e-4 rad
    y[3::2] = rng.normal(0.0, 0.5, n - 1)      # and their rates
    dy = np.zeros(2 * n)
    T_in, T_out = 230.0, 900.0
    assert L.gb_derivatives(gb.ctypes.data, work.ctypes.data, 0.0, y.ctypes.data, T_in, T_out, dy.ctypes.data) == 0
    # the reference in absolute angles, chain [motor, p1, g1, p2, g2, load]
    order = [model.part_body[x] for x in ("motor", "s1.pinion", "s1.gear", "s2.pinion", "s2.gear", "load")]
    u = np.concatenate([[0.0], y[2::2]])
    du = np.concatenate([[0.0], y[3::2]])
    th = (model.g * y[0] + u)[order]
    om = (model.g * y[1] + du)[order]
    M, K = hand_matrices()
    C = hand_damping()
    f = np.zeros(6)
    f[0], f[5] = T_in, -T_out
    alpha = np.linalg.solve(M, f - K @ th - C @ om)
    a_body = np.zeros(n)
    a_body[order] = alpha
    want = np.zeros(2 * n)
    want[0], want[1] = y[1], a_body[0]
    want[2::2] = y[3::2]
    want[3::2] = a_body[1:] - model.g[1:] * a_body[0]
    scale = np.max(np.abs(want[1::2]))
    assert np.max(np.abs(dy[1::2] - want[1::2])) <= 1e-9 * scale, (dy, want)
    assert np.array_equal(dy[0::2], want[0::2])


def test_the_builder_takes_the_gearbox_run_settings_and_names_a_bad_one(example):
    """The gearbox FMU's settings are the native gearbox solver's GearboxRunSettings: what is left
    automatic is resolved on the model (the balancing load torque T_motor/g_load, the native
    solver's step rule at 1.5 x the start speed linearised at the start torques), and a bad value
    raises FmuBuildError naming the field (the one check of gearfmu.common.settings)."""
    from gearfmu.common.settings import GearboxRunSettings
    from gearfmu.fmu.build_steps import FmuBuildError

    model = example["model"]
    s = gearbox_settings(model, GearboxRunSettings(motor_torque_start_Nm=143.0, motor_speed_start_rad_s=154.0,
                                                   output_interval_s=1e-4))
    assert s.load_torque_start_Nm == model.balancing_load_torque_Nm(143.0)
    assert s.max_step_s == choose_max_step_s(model, 1.5 * 154.0,
                                             reference_torque_Nm=model.reference_torque_Nm(143.0, s.load_torque_start_Nm))
    assert gearbox_settings(model, s) == s
    with pytest.raises(FmuBuildError, match=r"^integrator: 'euler' unknown for gearboxes"):
        gearbox_settings(model, s, integrator="euler")
    with pytest.raises(FmuBuildError, match=r"^stop_time_s: "):
        gearbox_settings(model, s, stop_time_s=-1.0)
    with pytest.raises(FmuBuildError, match=r"^settings: expected GearboxRunSettings, got object"):
        build_gearbox_fmu(model, example["dir"] / "x.fmu", settings=object())
