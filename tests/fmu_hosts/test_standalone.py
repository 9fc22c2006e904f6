"""The standalone FMU (FMI layer in C, gearfmu/fmu/standalone/fmi2_gear.c) against
independent references and masters.

References (none produced by gearfmu code paths under test):
* fmpy.validation.validate_fmu -- fmpy's checks of the FMI 2.0 schema and rules;
* three independent implementations of docs/model.md must agree to
  round-off (<= 1e-9 of each signal's range) when their internal steps match:
  the numba native solver, the pythonfmu FMU (Python FMI layer) and the
  standalone FMU (C FMI layer) -- for the default scene and for a hard case
  with contact loss and back-flank impacts;
* independent FMI masters: fmpy, libcosimpy (Open Simulation Platform's
  libcosim, FMI Library loader) and tests/fmu_hosts/fmi_host.c (a plain C host, no
  Python in the process);
* hashlib's SHA-256 (Python standard library) for the C layer's own SHA-256;
* the closed-form static balance at standstill (F = T1/Rb1 = T2/Rb2, the
  speed stays 0);
* exit codes of fresh processes for host crashes.
"""
import csv
import hashlib
import io
import json
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import fmpy
import fmpy.validation
import numpy as np
import pytest
from fmpy.fmi2 import FMU2Slave

from gearfmu.fmu.compare import native_columns, output_names
from gearfmu.fmu.pythonfmu_build import build_fmu
from gearfmu.dynamics.native import simulate
from gearfmu.fmu.build_steps import FmuBuildError
from gearfmu.fmu.standalone_build import (StandaloneOptions, build_standalone_fmu, fmi2_header_dir,
                                           standalone_options)
from gearfmu.tables.synthetic import rectangular_wave_tables

from support.fmpy_host import slave, status
from support.standalone_cases import cases, impact_tables, max_rel

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

HERE = Path(__file__).resolve().parent
TOL = 1e-9  # of each signal's range


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    d = tmp_path_factory.mktemp("sa")
    out = {}
    for name, c in cases().items():
        kw = dict(damping_ratio=c["zeta"], pinion_speed_start_rad_s=c["w0"], pinion_torque_start_Nm=c["T1"],
                  gear_torque_start_Nm=c["T2"], max_step_s=c["hmax"], damping_model=c["model"],
                  stop_time_s=c["n"] * c["H"], output_interval_s=c["H"], model_name=f"gear_{name}")
        c["sa"] = build_standalone_fmu(c["tables"], d / f"{name}_sa.fmu", **kw)
        c["py"] = build_fmu(c["tables"], d / f"{name}_py.fmu", **kw)
        nat = simulate(c["tables"], stop_time_s=c["n"] * c["H"], comm_step_s=c["H"], max_step_s=c["hmax"],
                       pinion_torque_Nm=c["T1"], gear_torque_Nm=c["T2"], pinion_speed_start_rad_s=c["w0"],
                       damping_ratio=c["zeta"], damping_model=c["model"])
        c["native"] = native_columns(nat, c["tables"].slots)
        out[name] = c
    out["dir"] = d
    return out


def _fmpy_cols(path, c, tmp, stop=None, H=None):
    """Step the FMU with fmpy's FMU2Slave at exactly H from t_k = k*H (the
    native solver's steps; fmpy.simulate_fmu computes H as a difference of
    times, which differs by ulps and, where impacts amplify it, by more than
    round-off)."""
    H = c["H"] if H is None else H
    n = c["n"] if stop is None else int(round(stop / H))
    md = fmpy.read_model_description(str(path))
    d = fmpy.extract(str(path), unzipdir=str(tmp))
    s = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName="x")
    s.instantiate()
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    names = output_names(c["tables"].slots)
    vrs = {v.name: v.valueReference for v in md.modelVariables}
    out = [vrs[x] for x in names]
    rows = [s.getReal(out)]
    for k in range(n):
        s.doStep(k * H, H)
        rows.append(s.getReal(out))
    s.terminate()
    s.freeInstance()
    a = np.array(rows)
    return {x: a[:, i] for i, x in enumerate(names)}


def _unzip(fmu, dest):
    with zipfile.ZipFile(fmu) as z:
        z.extractall(dest)
    md = fmpy.read_model_description(str(fmu))
    return md


# --------------------------------------------------------------- validation
def test_validate_fmu_and_interface(built):
    for name in ("default", "impacts"):
        sa = built[name]["sa"]
        assert fmpy.validation.validate_fmu(str(sa)) == []
        md = fmpy.read_model_description(str(sa))
        cs = md.coSimulation
        assert cs.needsExecutionTool is False
        assert cs.canGetAndSetFMUstate and cs.canSerializeFMUstate
        bc = md.buildConfigurations[0]
        assert bc.modelIdentifier == cs.modelIdentifier
        # the one translation unit (docs/standalone.md "Source code"), which includes the others
        assert bc.sourceFileSets[0].sourceFiles == ["fmi2_all.c"]
        names = set(zipfile.ZipFile(sa).namelist())
        for f in ("sources/fmi2_all.c", "sources/fmi2_gear.c", "sources/fmi_common.c", "sources/fmi_common.h", "sources/gf_model.h",
                  "sources/gear_model.c", "sources/gear_model.h", "sources/gearkernel.c", "sources/gearkernel.h",
                  "sources/gk_internal.h", "sources/gk_lookup.h", "sources/gk_model.c", "sources/gk_stops.c",
                  "sources/gk_zones.c", "sources/gk_temperature.c", "sources/gk_envelope.c",
                  "sources/gkfmu.c", "sources/gkfmu.h",
                  f"binaries/linux64/{cs.modelIdentifier}.so", "resources/tables.bin",
                  "resources/gearfmu_standalone.txt"):
            assert f in names, f
        # the FMI headers are the importer's (FMI 2.0.5 section 2.3)
        assert not [n for n in names if n.startswith("sources/fmi2") and n.endswith(".h")]
        # same value references as the pythonfmu FMU built from the same spec; the standalone FMU offers
        # Model Exchange too (the default), whose locals come after them (docs/standalone.md "Model Exchange")
        mp = fmpy.read_model_description(str(built[name]["py"]))
        common = [(v.name, v.valueReference, v.causality) for v in mp.modelVariables]
        assert [(v.name, v.valueReference, v.causality) for v in md.modelVariables][:len(common)] == common
        extra = md.modelVariables[len(common):]
        assert extra and {v.causality for v in extra} == {"local"}
        assert [v.name for v in extra if v.derivative is not None] == \
            ["der(pinion_angle)", "der(pinion_speed)", "der(dte)", "der(dte_rate)"]
        assert md.modelExchange.modelIdentifier == cs.modelIdentifier and mp.modelExchange is None


def test_validation_record_in_both_runtimes(built, tmp_path):
    """resources/validation/ holds versions, checksums and a native reference CSV;
    the checksums equal hashlib's of the FMU's own tables.bin, and the FMU run
    at its DefaultExperiment by fmpy reproduces the CSV to 1e-9 of each range."""
    c = built["impacts"]
    for key in ("sa", "py"):
        z = zipfile.ZipFile(c[key])
        rec = json.loads(z.read("resources/validation/record.json"))
        assert rec["runtime"] == {"sa": "standalone", "py": "pythonfmu"}[key]
        for pkg in ("gearfmu", "python", "numpy", "numba", "fmpy"):
            assert rec["versions"][pkg]
        assert rec["tables"]["tables_bin_sha256"] == hashlib.sha256(z.read("resources/tables.bin")).hexdigest()
        ref_bytes = z.read("resources/validation/reference_result.csv")
        assert rec["reference"]["sha256"] == hashlib.sha256(ref_bytes).hexdigest()
        rows = list(csv.reader(io.StringIO(ref_bytes.decode())))
        ref = {n: np.array([float(r[i]) for r in rows[1:]]) for i, n in enumerate(rows[0])}
        de = fmpy.read_model_description(str(c[key])).defaultExperiment
        got = _fmpy_cols(c[key], c, tmp_path / key, stop=float(de.stopTime), H=float(de.stepSize))
        worst = max_rel(ref, got, output_names(c["tables"].slots))
        assert max(worst.values()) <= TOL, worst


# ----------------------------------------------------------- agreement
@pytest.mark.parametrize("case", ["default", "impacts"])
def test_native_pythonfmu_standalone_agree(built, case, tmp_path):
    c = built[case]
    names = output_names(c["tables"].slots)
    sa = _fmpy_cols(c["sa"], c, tmp_path / "sa")
    py = _fmpy_cols(c["py"], c, tmp_path / "py")
    w_sa = max_rel(c["native"], sa, names)
    w_py = max_rel(c["native"], py, names)
    w_pair = max_rel(py, sa, names)
    print(case, "standalone vs native", max(w_sa.values()), "pythonfmu vs native", max(w_py.values()),
          "standalone vs pythonfmu", max(w_pair.values()))
    assert max(w_sa.values()) <= TOL, w_sa
    assert max(w_py.values()) <= TOL, w_py
    assert max(w_pair.values()) <= TOL, w_pair
    if case == "impacts":  # the case is hard: contact loss and back-flank impacts happen
        pf = np.stack([sa[f"pair_force[{i + 1}]"] for i in range(c["tables"].slots)])
        assert np.any(sa["mesh_force"] == 0.0) and np.any(pf < 0.0)


# -------------------------------------------------------------- masters
@pytest.fixture(scope="module")
def host(tmp_path_factory):
    gcc = shutil.which("gcc") or shutil.which("cc")
    exe = tmp_path_factory.mktemp("host") / "fmi_host"
    subprocess.run([gcc, "-std=c99", "-O1", "-Wall", f"-I{fmi2_header_dir()}", "-o", str(exe),
                    str(HERE / "fmi_host.c"), "-ldl"], check=True, capture_output=True, text=True)
    return exe


def _host_run(host, d, md, c, outs, extra=()):
    cmd = [str(host), str(d), md.coSimulation.modelIdentifier, md.guid, repr(c["n"] * c["H"]), repr(c["H"]),
           ",".join(str(v) for v in outs), *extra]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=120)


def test_c_host_no_python(built, host, tmp_path):
    """tests/fmu_hosts/fmi_host.c (dlopen + FMI C API, no Python) runs the standalone FMU;
    its outputs equal the native solver's to 1e-9 of range, and saving,
    serializing, de-serializing and restoring the FMU state mid-run reproduces
    the second half bit for bit."""
    for case in ("default", "impacts"):
        c = built[case]
        d = tmp_path / case
        md = _unzip(c["sa"], d)
        names = output_names(c["tables"].slots)
        vrs = {v.name: v.valueReference for v in md.modelVariables}
        p = _host_run(host, d, md, c, [vrs[n] for n in names], ["--state-check"])
        assert p.returncode == 0, p.stderr
        lines = p.stdout.strip().splitlines()
        assert lines[-1] == "state-check ok"
        data = np.array([[float(x) for x in ln.split(",")] for ln in lines[1:-1]])
        got = {n: data[:, i + 1] for i, n in enumerate(names)}
        worst = max_rel(c["native"], got, names)
        assert max(worst.values()) <= TOL, worst


def test_fresh_processes_exit_zero(built, host, tmp_path):
    """Both FMUs in fresh fmpy processes (10 each) and the standalone FMU in
    fresh C-host processes (30): every exit code 0, identical final values."""
    c = built["impacts"]
    procs = []
    for key in ("sa", "py"):
        code = (f"import fmpy; r = fmpy.simulate_fmu({str(c[key])!r}, stop_time=0.005, output_interval=1e-4); "
                "print(repr(float(r['mesh_force'][-1])))")
        procs += [(key, subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE,
                                         stderr=subprocess.PIPE, text=True)) for _ in range(10)]
    finals = {"sa": set(), "py": set()}
    for key, p in procs:
        out, err = p.communicate(timeout=300)
        assert p.returncode == 0, (key, p.returncode, err[-2000:])
        finals[key].add(out.strip().splitlines()[-1])  # after fmpy's printed warnings (docs/fmu.md "Verified envelope")
    assert len(finals["sa"]) == 1 and finals["sa"] == finals["py"]
    d = tmp_path / "u"
    md = _unzip(c["sa"], d)
    hp = [subprocess.Popen([str(host), str(d), md.coSimulation.modelIdentifier, md.guid, "0.005", "1e-4", "7"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for _ in range(30)]
    outs = set()
    for p in hp:
        out, err = p.communicate(timeout=120)
        assert p.returncode == 0, err
        outs.add(out)
    assert len(outs) == 1


LIBCOSIM_SCRIPT = r"""
import json, sys
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
from libcosimpy.CosimObserver import CosimObserver
from libcosimpy.CosimSlave import CosimLocalSlave
log_output_level(CosimLogLevel.ERROR)
path, step_ns, n, vrs = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), json.loads(sys.argv[4])
ex = CosimExecution.from_step_size(step_ns)
i = ex.add_local_slave(CosimLocalSlave(fmu_path=path, instance_name="gear"))
obs = CosimObserver.create_last_value()
ex.add_observer(obs)
rows = []
for k in range(n):
    assert ex.step()
    rows.append(obs.last_real_values(i, vrs))
print(json.dumps(rows))
"""


@pytest.mark.parametrize("key", ["sa", "py"])
def test_libcosimpy_master(built, key):
    """libcosimpy (libcosim; integer-nanosecond time) runs each runtime on the
    impact case; the outputs after each step equal the native solver's to 1e-9
    of range.  The step is H = 1/512 s = 1953125 ns: dyadic, so every time
    point and their differences are exact in double and the FMU gets exactly
    the native solver's H (with H = 1e-4 s libcosim's time-point differences
    are off by ulps, which the impacts amplify to ~2e-6 of range)."""
    import libcosimpy  # noqa: F401 - a test dependency (pyproject 'test' extra)
    c = built["impacts"]
    H, n = 1.0 / 512.0, 12
    nat = simulate(c["tables"], stop_time_s=n * H, comm_step_s=H, max_step_s=c["hmax"], pinion_torque_Nm=c["T1"],
                   gear_torque_Nm=c["T2"], pinion_speed_start_rad_s=c["w0"], damping_ratio=c["zeta"],
                   damping_model=c["model"])
    names = output_names(c["tables"].slots)
    ref = {k: v[1:] for k, v in native_columns(nat, c["tables"].slots).items()}
    md = fmpy.read_model_description(str(c[key]))
    vrs = {v.name: v.valueReference for v in md.modelVariables}
    p = subprocess.run([sys.executable, "-c", LIBCOSIM_SCRIPT, str(c[key]), "1953125", str(n),
                        json.dumps([vrs[x] for x in names])], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-3000:]
    rows = np.array(json.loads(p.stdout.strip().splitlines()[-1]))
    got = {x: rows[:, i] for i, x in enumerate(names)}
    worst = max_rel(ref, got, names)
    assert max(worst.values()) <= TOL, worst
    assert np.any(ref["mesh_force"] == 0.0)  # contact loss within these steps


def test_fmu_state_get_set_serialize(built, tmp_path):
    """Saving the state, stepping, restoring and stepping again gives the same
    outputs bit for bit; a serialized state restores into a fresh instance."""
    c = built["impacts"]
    s, vrs, _ = slave(c["sa"], tmp_path)
    out = [vrs[n] for n in output_names(c["tables"].slots)]
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    H = c["H"]
    for k in range(20):
        s.doStep(k * H, H)
    st = s.getFMUstate()
    blob = s.serializeFMUstate(st)
    first = []
    for k in range(20, 40):
        s.doStep(k * H, H)
        first.append(s.getReal(out))
    s.setFMUstate(st)
    second = []
    for k in range(20, 40):
        s.doStep(k * H, H)
        second.append(s.getReal(out))
    assert first == second
    s.freeFMUstate(st)
    s2, _, _ = slave(c["sa"], tmp_path, "s2")
    s2.setupExperiment(startTime=0.0)
    s2.enterInitializationMode()
    s2.exitInitializationMode()
    st2 = s2.deSerializeFMUstate(blob)
    s2.setFMUstate(st2)
    third = []
    for k in range(20, 40):
        s2.doStep(k * H, H)
        third.append(s2.getReal(out))
    assert third == first
    s2.freeFMUstate(st2)
    for x in (s, s2):
        x.terminate()
        x.freeInstance()
    # a state of another FMU (different tables) is refused
    o, _, _ = slave(built["default"]["sa"], tmp_path, "other")
    with pytest.raises(Exception):
        o.deSerializeFMUstate(blob)
    o.freeInstance()


def test_bad_inputs_discard_state_unchanged(built, tmp_path):
    """NaN / inf torque and a negative step give fmi2Discard and a log message;
    the state is unchanged (the next good step equals an undisturbed run)."""
    c = built["impacts"]
    H = c["H"]
    results = []
    for disturb in (False, True):
        s, vrs, msgs = slave(c["sa"], tmp_path, f"b{disturb}")
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        s.exitInitializationMode()
        for k in range(5):
            s.doStep(k * H, H)
        if disturb:
            for bad in (float("nan"), float("inf")):
                s.setReal([vrs["pinion_torque"]], [bad])
                assert status(s.fmi2DoStep, s.component, 5 * H, H, 1) == 2  # fmi2Discard
            s.setReal([vrs["pinion_torque"]], [c["T1"]])
            assert status(s.fmi2DoStep, s.component, 5 * H, -H, 1) == 2
            text = " ".join(m for _, m in msgs)
            assert "pinion_torque = nan" in text and "not finite" in text and "must be finite and > 0" in text
        s.doStep(5 * H, H)
        results.append(s.getReal([vrs["dte"], vrs["pinion_speed"], vrs["mesh_force"]]))
        s.terminate()
        s.freeInstance()
    assert results[0] == results[1]


def test_getters_read_each_value_and_refuse_bad_references(built, tmp_path):
    """fmi2GetReal / fmi2GetInteger of several references in one call give the values of the
    same references read one by one (outputs, an input, a parameter, in any order), in
    initialization mode after a set too (the outputs recomputed); a reference past the last
    variable, a variable of the other type or NULL arrays give fmi2Error and a message naming
    the function and the reason (the FMI 2.0 standard, section 2.1.7, leaves no other answer)."""
    from ctypes import POINTER, c_double, c_uint, cast

    from fmpy.fmi2 import fmi2Integer, fmi2Real, fmi2ValueReference

    c = built["impacts"]
    s, vrs, msgs = slave(c["sa"], tmp_path)
    names = ["mesh_force", "pinion_torque", "dte", "max_step", "pinion_speed", "dte"]
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    force_before = s.getReal([vrs["mesh_force"]])[0]
    s.setReal([vrs["pinion_torque"]], [2 * c["T1"]])
    init_all = s.getReal([vrs[n] for n in names])
    s.exitInitializationMode()
    s.doStep(0.0, c["H"])
    one_by_one = [s.getReal([vrs[n]])[0] for n in names]
    assert s.getReal([vrs[n] for n in names]) == one_by_one
    assert init_all[1] == 2 * c["T1"] and init_all[0] != force_before  # recomputed after the set
    assert s.getInteger([vrs["damping_model"], vrs["integrator"]]) == [s.getInteger([vrs["damping_model"]])[0],
                                                                      s.getInteger([vrs["integrator"]])[0]]
    n_vars = len(vrs)
    bad = [([vrs["dte"], n_vars], "fmi2GetReal: no variable with value reference"),
           ([vrs["integrator"], vrs["dte"]], "fmi2GetReal: integrator is not of type Real")]
    for refs, words in bad:
        del msgs[:]
        arr, vals = (fmi2ValueReference * len(refs))(*refs), (fmi2Real * len(refs))()
        assert status(s.fmi2GetReal, s.component, arr, len(refs), vals) == 3
        assert any(words in m for _, m in msgs), (words, msgs)
    del msgs[:]
    arr, ints = (fmi2ValueReference * 1)(vrs["dte"]), (fmi2Integer * 1)()
    assert status(s.fmi2GetInteger, s.component, arr, 1, ints) == 3
    assert any("fmi2GetInteger: dte is not of type Integer" in m for _, m in msgs), msgs
    del msgs[:]
    assert status(s.fmi2GetReal, s.component, arr, 1, cast(None, POINTER(c_double))) == 3
    assert status(s.fmi2GetReal, s.component, cast(None, POINTER(c_uint)), 1, (fmi2Real * 1)()) == 3
    assert sum("vr[] or value[] is NULL with nvr = 1" in m for _, m in msgs) == 2, msgs
    s.terminate()
    s.freeInstance()


def test_tampered_tables_refused(built, tmp_path):
    """One flipped byte in resources/tables.bin: the C layer's SHA-256 differs
    from the recorded one (hashlib's at build time) and instantiation is
    refused with a message naming the file and the checksum."""
    c = built["impacts"]
    s, _, msgs = slave(c["sa"], tmp_path, "t", instantiate=False)
    p = Path(s.unzipDirectory) / "resources" / "tables.bin"
    raw = bytearray(p.read_bytes())
    raw[len(raw) // 2] ^= 0x01
    p.write_bytes(bytes(raw))
    with pytest.raises(Exception, match="Failed to instantiate"):
        s.instantiate(loggingOn=True, callbacks=s._test_callbacks)
    assert any("tables.bin" in m and "SHA-256" in m for _, m in msgs), msgs


def test_standstill_static_balance(tmp_path):
    """Start at omega = 0 with balanced torques T2 = T1*Rb2/Rb1 and constant
    stiffness without errors: the pair stays at rest, mesh force = T1/Rb1 and
    dte = F/k exactly (closed form), through the substep bound at zero speed."""
    t = rectangular_wave_tables(2e8, contact_ratio=2.0)  # two pairs always engaged: constant total k
    T1 = 40.0
    T2 = T1 * t.base_radius_gear_m / t.base_radius_pinion_m
    p = build_standalone_fmu(t, tmp_path / "still.fmu", pinion_speed_start_rad_s=0.0, pinion_torque_start_Nm=T1,
                             gear_torque_start_Nm=T2, max_step_s=1e-5, stop_time_s=0.002, output_interval_s=1e-4,
                             validation=False)
    r = fmpy.simulate_fmu(str(p), stop_time=0.002, output_interval=1e-4)
    F = T1 / t.base_radius_pinion_m
    k_total = 4e8  # two pairs engaged everywhere: k_double = 2*k_single (rectangular_wave_tables)
    assert np.allclose(r["mesh_force"], F, rtol=1e-9)
    assert np.allclose(r["dte"], F / k_total, rtol=1e-9)
    assert np.max(np.abs(r["pinion_speed"])) < 1e-9 and np.max(np.abs(r["gear_speed"])) < 1e-9
    assert np.allclose(r["mesh_stiffness"], k_total, rtol=1e-12)


def test_sources_in_fmu_compile_to_same_results(built, host, tmp_path):
    """The FMU's sources/ (the files its buildflags.txt names), with the standard's FMI headers
    (the importer's), compile into a binary that reproduces the shipped binary's outputs bit for bit."""
    c = built["impacts"]
    d = tmp_path / "src"
    md = _unzip(c["sa"], d)
    ident = md.coSimulation.modelIdentifier
    so = d / "binaries" / "linux64" / f"{ident}.so"
    ref = _host_run(host, d, md, c, [2, 3, 4, 5, 6, 7, 8])
    so.unlink()
    gcc = shutil.which("gcc") or shutil.which("cc")
    recipe = dict(line.split("=", 1) for line in (d / "sources" / "buildflags.txt").read_text().splitlines()
                  if "=" in line and not line.startswith("#"))
    subprocess.run([gcc, "-O2", "-fPIC", "-shared", "-ffp-contract=off", "-std=c99", "-fvisibility=hidden",
                    f"-I{d / 'sources'}", f"-I{fmi2_header_dir()}", "-o", str(so),
                    *(str(d / "sources" / n) for n in recipe["sources"].split()), "-lm"], check=True,
                   capture_output=True)
    again = _host_run(host, d, md, c, [2, 3, 4, 5, 6, 7, 8])
    assert ref.returncode == 0 and again.returncode == 0
    assert ref.stdout == again.stdout


def test_cli_default_runtime_is_standalone(tmp_path):
    """`gearfmu build` (no --runtime) writes the all-C FMU of the default scene."""
    from gearfmu.cli import main

    out = tmp_path / "cli.fmu"
    assert main(["build", "-o", str(out), "-q"]) == 0
    md = fmpy.read_model_description(str(out))
    assert md.coSimulation.needsExecutionTool is False and md.buildConfigurations
    assert fmpy.validation.validate_fmu(str(out)) == []


def test_options_as_object_or_keywords_are_checked_alike(tmp_path):
    """The kind of FMU comes as :class:`StandaloneOptions` or as its fields given as keywords
    (beside the run settings' fields): a bad value is refused the same way both ways, by one
    line naming the field, before anything is compiled and without leaving a file; a keyword
    that is neither an option nor a run setting is a TypeError naming it."""
    t = impact_tables()
    out = tmp_path / "x.fmu"
    for kw, field in (({"fmi_version": 4}, "fmi_version"), ({"interface": "co-sim"}, "interface"),
                      ({"me_node_events": "every"}, "me_node_events"),
                      ({"fmi3_outputs": "scalar"}, "fmi3_outputs"),    # scalars need FMI 3
                      ({"platforms": ("x86_64-plan9",)}, "platforms")):
        with pytest.raises(FmuBuildError, match=f"^{field}: "):
            build_standalone_fmu(t, out, **kw)
        with pytest.raises(FmuBuildError, match=f"^{field}: "):
            build_standalone_fmu(t, out, None, StandaloneOptions(**kw))
    with pytest.raises(FmuBuildError, match="^damping_ratio: "):   # a run setting beside an option
        build_standalone_fmu(t, out, None, StandaloneOptions(fmi_version=3), damping_ratio=-1.0, interface="cs")
    with pytest.raises(FmuBuildError, match="^options: expected StandaloneOptions"):
        build_standalone_fmu(t, out, None, {"fmi_version": 3})
    with pytest.raises(TypeError, match="fmi_verison"):
        build_standalone_fmu(t, out, fmi_verison=3)
    assert list(tmp_path.iterdir()) == []
    o = StandaloneOptions(fmi_version=3, fmi3_outputs="scalar", platforms=["x86_64-linux"])
    assert o.platform_keys() == ("x86_64-linux",)
    assert standalone_options(o, interface="cs") == StandaloneOptions(
        fmi_version=3, fmi3_outputs="scalar", platforms=["x86_64-linux"], interface="cs")
