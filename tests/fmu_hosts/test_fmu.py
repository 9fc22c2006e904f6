"""The FMU built by gearfmu.fmu.pythonfmu_build, driven by fmpy (an independent FMI master).

References: fmpy.validation (the FMI 2.0 schema and rules as fmpy checks
them); the interface contract of README.md "The FMU's variables" (names,
causality, units); the closed-form static balance of a gear pair at rest (mesh force
F = T1/Rb1 = T2/Rb2, speed constant); "the same FMU run alone" for the
isolation tests; exit codes of fresh processes for host crashes.
"""
import json
import subprocess
import sys
import textwrap
import zipfile

import fmpy
import fmpy.validation
import numpy as np
import pytest
from fmpy.fmi2 import FMU2Slave

from gearfmu.fmu.pythonfmu_build import FmuBuildError, build_fmu
from gearfmu.fmu.modeldesc import SpecError, expand_variables, load_spec
from factories import RB1, RB2, make_tables

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    d = tmp_path_factory.mktemp("fmus")
    a = build_fmu(make_tables(), d / "a.fmu", model_name="pairA", stop_time_s=0.01, output_interval_s=1e-4,
                  max_step_s=1e-5, pinion_torque_start_Nm=100.0, damping_ratio=0.02,
                  scene_text='[gear]\nname = "test"\n')
    b = build_fmu(make_tables(P=3, eps=2.4, e_amp=-1e-6, b=0.0), d / "b.fmu", model_name="pairB",
                  stop_time_s=0.01, output_interval_s=1e-4, max_step_s=1e-5, pinion_torque_start_Nm=80.0,
                  damping_model="contact_zone")
    return {"a": a, "b": b, "dir": d}


def run_alone(path, n=60, H=1e-4, start_values=None):
    return fmpy.simulate_fmu(str(path), stop_time=n * H, output_interval=H, start_values=start_values or {})


def test_validate_fmu_passes(fmus):
    for key in ("a", "b"):
        assert fmpy.validation.validate_fmu(str(fmus[key])) == []


def test_interface_matches_design_contract(fmus):
    """Names, causality and units of the interface contract (README "The FMU's variables")."""
    md = fmpy.read_model_description(str(fmus["b"]))
    v = {x.name: x for x in md.modelVariables}
    want = {"pinion_torque": ("input", "N.m"), "gear_torque": ("input", "N.m"),
            "pinion_speed": ("output", "rad/s"), "gear_speed": ("output", "rad/s"),
            "pinion_angle": ("output", "rad"), "gear_angle": ("output", "rad"), "dte": ("output", "m"),
            "mesh_force": ("output", "N"), "mesh_stiffness": ("output", "N/m"),
            "damping_ratio": ("parameter", "1"), "pinion_speed_start": ("parameter", "rad/s")}
    for i in (1, 2, 3):
        want[f"pair_force[{i}]"] = ("output", "N")
        want[f"load_sharing[{i}]"] = ("output", "1")
    for name, (caus, unit) in want.items():
        assert v[name].causality == caus, name
        assert v[name].unit == unit, name
    assert v["damping_ratio"].variability == "tunable"
    assert "pair_force[4]" not in v
    assert v["damping_model"].type == "Integer" and v["damping_model"].start == "1"
    assert md.defaultExperiment.stepSize == "0.0001"
    names = set(zipfile.ZipFile(fmus["a"]).namelist())
    for f in ("resources/tables.json", "resources/tables.bin", "resources/kernel_src/gearkernel.c",
              "resources/kernel_src/gearkernel.h", "resources/kernel_src/gk_internal.h",
              "resources/kernel_src/gk_lookup.h", "resources/kernel_src/gk_model.c", "resources/kernel_src/gk_stops.c",
              "resources/kernel_src/gk_zones.c", "resources/kernel_src/gk_temperature.c",
              "resources/kernel_src/gk_envelope.c", "resources/kernel_src/gkfmu.c", "resources/kernel_src/gkfmu.h",
              "resources/scene.toml", "resources/provenance.json"):
        assert f in names
    prov = json.loads(zipfile.ZipFile(fmus["a"]).read("resources/provenance.json"))
    assert prov["model_name"] == "pairA" and prov["parameters"]["damping_ratio"] == 0.02


def test_static_balance_closed_form(tmp_path):
    """Constant stiffness, no errors, T2 = T1*Rb2/Rb1: the pair stays at its
    static deflection, mesh force = T1/Rb1 exactly and the speed is constant."""
    t = make_tables(P=1, eps=1.0001, e_amp=0.0, b=0.0)
    t.k_N_per_m[:] = 3e8
    t.contact_ratio = 1.0
    p = build_fmu(t, tmp_path / "s.fmu", pinion_torque_start_Nm=150.0, pinion_speed_start_rad_s=80.0,
                  max_step_s=2e-5)
    r = run_alone(p, n=50)
    assert np.allclose(r["mesh_force"], 150.0 / RB1, rtol=1e-9)
    assert np.allclose(r["pinion_speed"], 80.0, rtol=1e-12)
    assert np.allclose(r["gear_speed"], 80.0 * RB1 / RB2, rtol=1e-9)
    assert np.allclose(r["dte"], 150.0 / RB1 / 3e8, rtol=1e-9)
    assert np.allclose(r["pinion_angle"], 80.0 * r["time"], rtol=1e-12, atol=1e-15)
    assert np.allclose(r["mesh_stiffness"], 3e8)


def test_fresh_process_20_runs_exit_zero(fmus):
    """A fresh Python host (fmpy) runs the FMU and exits cleanly, 20 times
    (catches intermittent crashes at interpreter exit; see docs/fmu.md)."""
    code = (f"import fmpy; r = fmpy.simulate_fmu({str(fmus['a'])!r}, stop_time=0.003, output_interval=1e-4); "
            "print(repr(float(r['mesh_force'][-1])))")
    procs, outs = [], []
    for _ in range(20):
        procs.append(subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE,
                                      stderr=subprocess.PIPE, text=True))
        if len(procs) == 4:
            outs += [(p.wait(timeout=120), p.communicate()) for p in procs]
            procs = []
    outs += [(p.wait(timeout=120), p.communicate()) for p in procs]
    codes = [rc for rc, _ in outs]
    assert codes == [0] * 20, [o[1][1][-300:] for o in outs if o[0] != 0]
    values = {o[1][0].strip() for o in outs}
    assert len(values) == 1  # deterministic


def _stepper(path, name):
    md = fmpy.read_model_description(str(path))
    unzip = fmpy.extract(str(path))
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName=name)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    return fmu, vr, unzip


def _interleaved(paths, n=40, H=1e-4):
    """Step instances of ``paths`` interleaved (same step sizes for all), return dte, force, speed."""
    insts = [_stepper(p, f"i{j}") for j, p in enumerate(paths)]
    res = [[] for _ in insts]
    for i in range(n):
        for j, (fmu, vr, _) in enumerate(insts):
            fmu.doStep(currentCommunicationPoint=i * H, communicationStepSize=H)
            res[j].append(fmu.getReal([vr["dte"], vr["mesh_force"], vr["pinion_speed"]]))
    for fmu, _, _ in insts:
        fmu.terminate()
        fmu.freeInstance()
    return [np.array(r) for r in res]


def test_two_fmus_and_two_instances_in_one_process(fmus):
    """Two different gear FMUs and two instances of one FMU, stepped interleaved
    in one process, give bit for bit what each gives alone."""
    (alone_a,) = _interleaved([fmus["a"]])
    (alone_b,) = _interleaved([fmus["b"]])
    a1, b1, a2 = _interleaved([fmus["a"], fmus["b"], fmus["a"]])
    assert np.array_equal(a1, alone_a)
    assert np.array_equal(a2, alone_a)
    assert np.array_equal(b1, alone_b)
    assert not np.allclose(alone_a[:, 1], alone_b[:, 1])
    # and simulate_fmu (its own step-size round-off) agrees to round-off
    r = run_alone(fmus["a"], n=40)
    assert np.allclose(r["dte"][1:], alone_a[:, 0], rtol=1e-9, atol=1e-9 * np.ptp(r["dte"]))


def test_damping_ratio_start_value_changes_result(fmus):
    r1 = run_alone(fmus["a"], n=40)
    r2 = run_alone(fmus["a"], n=40, start_values={"damping_ratio": 0.2})
    r3 = run_alone(fmus["a"], n=40, start_values={"damping_ratio": 0.02})
    assert np.array_equal(r1["dte"], r3["dte"])
    assert np.max(np.abs(r1["dte"] - r2["dte"])) > 1e-3 * np.ptp(r1["dte"])


def test_reset_gives_same_run(fmus):
    fmu, vr, _ = _stepper(fmus["a"], "r")
    H = 1e-4
    runs = []
    for _ in range(2):
        out = []
        for i in range(20):
            fmu.doStep(currentCommunicationPoint=i * H, communicationStepSize=H)
            out.append(fmu.getReal([vr["dte"]])[0])
        runs.append(out)
        fmu.reset()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
    fmu.terminate()
    fmu.freeInstance()
    assert runs[0] == runs[1]


BAD_INPUT_SCRIPT = textwrap.dedent("""
    import sys, fmpy
    from fmpy.fmi2 import FMU2Slave
    from fmpy.fmi1 import FMICallException
    path, value = sys.argv[1], float(sys.argv[2])
    md = fmpy.read_model_description(path)
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=fmpy.extract(path),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bad")
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu.instantiate(loggingOn=True)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=1e-4)
    before = fmu.getReal([vr["dte"], vr["pinion_angle"]])
    fmu.setReal([vr["pinion_torque"]], [value])
    try:
        fmu.doStep(currentCommunicationPoint=1e-4, communicationStepSize=1e-4)
        print("STATUS ok")
    except FMICallException as exc:
        print("STATUS", exc.status)
    after = fmu.getReal([vr["dte"], vr["pinion_angle"]])
    print("UNCHANGED", before == after)
    fmu.setReal([vr["pinion_torque"]], [100.0])
    fmu.doStep(currentCommunicationPoint=1e-4, communicationStepSize=1e-4)
    print("RECOVERED", fmu.getReal([vr["pinion_angle"]])[0] > before[1])
    fmu.terminate()
    fmu.freeInstance()
""")


@pytest.mark.parametrize("value", ["nan", "inf", "-inf"])
def test_non_finite_torque_is_discarded_with_log(fmus, tmp_path, value):
    script = tmp_path / "bad.py"
    script.write_text(BAD_INPUT_SCRIPT)
    p = subprocess.run([sys.executable, str(script), str(fmus["a"]), value], capture_output=True, text=True,
                       timeout=120)
    assert p.returncode == 0, p.stderr[-500:]
    assert "STATUS 2" in p.stdout or "STATUS 3" in p.stdout  # fmi2Discard or fmi2Error
    assert "pinion_torque" in p.stdout and "not finite" in p.stdout  # the log message
    assert "UNCHANGED True" in p.stdout and "RECOVERED True" in p.stdout


def test_tampered_tables_refused(fmus, tmp_path):
    """A changed byte in resources/tables.bin: instantiation is refused and the
    message names the file."""
    bad = tmp_path / "bad.fmu"
    with zipfile.ZipFile(fmus["a"]) as zin, zipfile.ZipFile(bad, "w") as zout:
        for info in zin.infolist():
            data = zin.read(info.filename)
            if info.filename == "resources/tables.bin":
                data = data[:100] + bytes([data[100] ^ 1]) + data[101:]
            zout.writestr(info, data)
    code = (f"import fmpy\ntry:\n    fmpy.simulate_fmu({str(bad)!r}, stop_time=1e-3, output_interval=1e-4, debug_logging=True)\n"
            "    print('RAN')\nexcept Exception as exc:\n    print('REFUSED', exc)\n")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr[-500:]
    assert "REFUSED" in p.stdout
    assert "tables.bin" in p.stdout + p.stderr and "checksum" in p.stdout + p.stderr


def test_build_errors_name_the_field_and_leave_no_file(tmp_path):
    t = make_tables()
    out = tmp_path / "x.fmu"
    for kw, field in (({"damping_ratio": -0.1}, "damping_ratio"), ({"max_step_s": 0.0}, "max_step_s"),
                      ({"damping_model": "viscous"}, "damping_model"),
                      ({"output_interval_s": float("nan")}, "output_interval_s"),
                      ({"pinion_torque_start_Nm": float("inf")}, "pinion_torque_start_Nm")):
        with pytest.raises(FmuBuildError, match=field):
            build_fmu(t, out, **kw)
    with pytest.raises(FmuBuildError, match="compilation failed|C compiler"):
        build_fmu(t, out, cc="false")
    assert list(tmp_path.iterdir()) == []
    out.write_bytes(b"old")
    with pytest.raises(FmuBuildError):
        build_fmu(t, out, cc="false")
    assert out.read_bytes() == b"old" and len(list(tmp_path.iterdir())) == 1


def test_spec_errors(tmp_path):
    spec = load_spec()
    names = [v.name for v in expand_variables(spec, 2)]
    assert names[:2] == ["pinion_torque", "gear_torque"]
    assert "pair_force[2]" in names and "load_sharing[1]" in names
    bad = tmp_path / "v.toml"
    bad.write_text('format = "gearfmu-variables"\nversion = 1\n[units]\n"m" = {m = 1}\n'
                   '[[variable]]\nname = "x"\ntype = "Real"\ncausality = "output"\n'
                   'variability = "continuous"\nunit = "mm"\noutput_index = 0\n')
    with pytest.raises(SpecError, match="unit 'mm'"):
        load_spec(bad)


@pytest.mark.parametrize("damping_model,slots,eps,backlash,torque", [
    ("elastobacklash", 2, 1.5, 1e-5, (100.0,)),
    ("contact_zone", 3, 2.4, 0.0, (100.0,)),
    ("elastobacklash", 2, 1.5, 2e-6, (50.0, 120.0, 300.0)),
])
def test_fmu_agrees_with_native_solver(tmp_path, damping_model, slots, eps, backlash, torque):
    """Two independent implementations of docs/model.md (C kernel in the FMU via
    fmpy, numba native solver): every output agrees to 1e-9 of its range."""
    from gearfmu.dynamics import native

    t = make_tables(P=slots, eps=eps, b=backlash, torque=torque)
    if len(torque) > 1:  # make the torque axis matter
        t.k_N_per_m[1] *= 1.1
        t.k_N_per_m[2] *= 1.3
        t.e_m[2] *= 0.5
    H, hmax, stop = 1e-4, 1e-5, 0.02
    p = build_fmu(t, tmp_path / "n.fmu", pinion_torque_start_Nm=100.0, gear_torque_start_Nm=150.0,
                  max_step_s=hmax, damping_model=damping_model, damping_ratio=0.03, pinion_speed_start_rad_s=120.0)
    r = fmpy.simulate_fmu(str(p), stop_time=stop, output_interval=H)
    n = native.simulate(t, stop_time_s=stop, comm_step_s=H, max_step_s=hmax, pinion_torque_Nm=100.0,
                        gear_torque_Nm=150.0, pinion_speed_start_rad_s=120.0, damping_ratio=0.03,
                        damping_model=damping_model)
    assert len(r) == len(n.time_s) == 201
    cols = n.columns()
    for name in ("pinion_speed", "gear_speed", "pinion_angle", "gear_angle", "dte", "mesh_force",
                 "mesh_stiffness") + tuple(f"pair_force[{i + 1}]" for i in range(slots)) \
            + tuple(f"load_sharing[{i + 1}]" for i in range(slots)):
        ref = cols[name][1]
        scale = max(np.ptp(ref), 1e-12 * np.max(np.abs(ref)), 1e-300)
        assert np.max(np.abs(r[name] - ref)) <= 1e-9 * scale, name
