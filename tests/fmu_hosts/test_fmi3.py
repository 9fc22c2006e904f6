"""The standalone FMU as FMI 3.0 Co-Simulation (gearfmu/fmu/standalone/fmi3_gear.c over the same
gear glue as the FMI 2.0 layer, docs/standalone.md "FMI 3.0").

References (none produced by the code under test):
* fmpy.validation.validate_fmu -- fmpy's checks of the FMI 3.0 schema and rules (and of FMI 2.0
  for the FMI 2 FMU of the same tables);
* the FMI 2.0 FMU of the same tables and settings, run by fmpy's FMI 2 master: the FMI 3 FMU run
  by fmpy's FMI 3 master must give the same numbers bit for bit (that FMU is itself held to the
  numba solver and two other masters in tests/fmu_hosts/test_standalone.py), on the default scene and on
  a case with contact loss and back-flank impacts;
* tests/fmu_hosts/fmi3_host.c, a plain C FMI 3 master (no Python in the process), for the FMU state round
  trip (get, serialize, deserialize, set: the continuation equal bit for bit), for random call
  orders (fresh processes, exit code 0, every refusal logged) and, built for aarch64-linux and
  x86_64-windows, under qemu-aarch64 and Wine (same numbers as the native run, text equal);
* Apple's Mach-O format (read by tests/fmu_hosts/test_platforms.py's reader) for the two macOS binaries;
* the host gcc compiling sources/ by sources/buildDescription.xml (the standard's build
  description): the binary must reproduce the shipped one's results bit for bit;
* pyssp-standard's SSP 1.0 XSD for the SSP package of an FMI 3 FMU.
"""
import re
import shutil
import subprocess
import zipfile
from pathlib import Path

import fmpy
import fmpy.validation
import numpy as np
import pytest

from gearfmu.fmu.standalone_build import build_description_flags, build_standalone_fmu, fmi3_header_dir
from gearfmu.ssp import build_ssp, validate_ssp_dir

from support.cross_tools import AARCH64_SYSROOT, macho_exports, need, qemu, wine_env, zig
from support.standalone_cases import cases

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

HERE = Path(__file__).resolve().parent
FMI3_TUPLES = ("x86_64-linux", "aarch64-linux", "x86_64-windows", "x86_64-darwin", "aarch64-darwin")


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """Per case (default scene, impacts) one FMI 2 and one FMI 3 FMU from the same tables and
    settings; the impacts FMI 3 FMU carries every platform."""
    d = tmp_path_factory.mktemp("fmi3")
    out = cases()
    for name, c in out.items():
        kw = dict(damping_ratio=c["zeta"], pinion_speed_start_rad_s=c["w0"], pinion_torque_start_Nm=c["T1"],
                  gear_torque_start_Nm=c["T2"], max_step_s=c["hmax"], damping_model=c["model"],
                  stop_time_s=c["n"] * c["H"], output_interval_s=c["H"], model_name=f"gear_{name}")
        c["fmi2"] = build_standalone_fmu(c["tables"], d / f"{name}2.fmu", validation=False,
                                         platforms=("x86_64-linux",), **kw)
        c["fmi3"] = build_standalone_fmu(c["tables"], d / f"{name}3.fmu", validation=name == "default",
                                         platforms=FMI3_TUPLES if name == "impacts" else ("x86_64-linux",),
                                         fmi_version=3, **kw)
        c["dir"] = d / f"{name}3"
        zipfile.ZipFile(c["fmi3"]).extractall(c["dir"])
        c["md"] = fmpy.read_model_description(str(c["fmi3"]))
        c["id"] = c["md"].coSimulation.modelIdentifier
    return out


@pytest.fixture(scope="module")
def host(tmp_path_factory):
    return _compile_host(tmp_path_factory.mktemp("host3"))


def _compile_host(tmp, target=None):
    """tests/fmu_hosts/fmi3_host.c for this machine (gcc) or for a zig target."""
    src, inc = str(HERE / "fmi3_host.c"), f"-I{fmi3_header_dir()}"
    if target is None:
        exe = tmp / "fmi3_host"
        cmd = [shutil.which("gcc") or "cc", "-std=c99", "-O1", "-Wall", inc, "-o", str(exe), src, "-ldl", "-lm"]
    else:
        exe = tmp / ("fmi3_host.exe" if "windows" in target else "fmi3_host_" + target.split("-")[0])
        cmd = [*zig(), "cc", "-target", target, "-std=c99", "-O1", "-Wall", inc, "-o", str(exe), src] + \
              ([] if "windows" in target else ["-ldl", "-lm"])
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=tmp, timeout=1800)
    assert p.returncode == 0, p.stderr
    return exe


def _outputs(c):
    """(value references, number of values) of every output of the FMI 3 FMU, arrays whole."""
    outs = [v for v in c["md"].modelVariables if v.causality == "output"]
    return [v.valueReference for v in outs], sum(int(np.prod(v.shape)) if v.shape else 1 for v in outs)


def _run_args(c, fmu_dir, n=None):
    vrs, nval = _outputs(c)
    n = c["n"] if n is None else n
    return ["run", str(fmu_dir), c["id"], c["md"].instantiationToken, repr(n * c["H"]), repr(c["H"]),
            ",".join(map(str, vrs)), str(nval)]


# --------------------------------------------------------------- interface
def test_fmpy_validates_both_versions(built):
    for c in built.values():
        assert fmpy.validation.validate_fmu(str(c["fmi3"])) == []
        assert fmpy.validation.validate_fmu(str(c["fmi2"])) == []


def test_fmi3_interface_same_names_arrays_and_resources(built):
    """The FMI 2 names and value references; pair_force[i] / load_sharing[i] are the arrays pair_force /
    load_sharing (<Dimension start=P>, reference of element 1); FMU state offered; the validation and
    envelope records, the buildDescription.xml with the reproducibility flags; binaries under the FMI 3
    platform tuples."""
    c = built["default"]
    md3, md2 = c["md"], fmpy.read_model_description(str(c["fmi2"]))
    P = c["tables"].slots
    assert md3.fmiVersion == "3.0" and re.fullmatch(r"\{[0-9a-f-]{36}\}", md3.instantiationToken)
    cs = md3.coSimulation
    assert cs.canGetAndSetFMUstate and cs.canSerializeFMUstate and not cs.needsExecutionTool  # fmpy's spelling
    xml = zipfile.ZipFile(c["fmi3"]).read("modelDescription.xml").decode()
    assert 'canGetAndSetFMUState="true"' in xml and 'canSerializeFMUState="true"' in xml
    v3 = {v.name: v for v in md3.modelVariables}
    want = {}
    for v in md2.modelVariables:
        base = re.sub(r"\[\d+\]$", "", v.name)
        if base not in want:
            want[base] = (v.valueReference, v.causality, {"Real": "Float64", "Integer": "Int32"}[v.type])
    assert {n: (v.valueReference, v.causality, v.type) for n, v in v3.items() if n != "time"} == want
    assert v3["time"].causality == "independent"
    for arr in ("pair_force", "load_sharing"):
        assert v3[arr].shape == (P,) and int(v3[arr].dimensions[0].start) == P
    names = set(zipfile.ZipFile(c["fmi3"]).namelist())
    assert {"resources/validation/record.json", "resources/envelope.json", "sources/buildDescription.xml",
            f"binaries/x86_64-linux/{c['id']}.so"} <= names
    bd = build_description_flags(zipfile.ZipFile(c["fmi3"]).read("sources/buildDescription.xml").decode())
    assert "-ffp-contract=off" in bd["cflags"] and "-fno-fast-math" in bd["cflags"]
    assert not [f for f in bd["cflags"] if "fast-math" in f and f != "-fno-fast-math"]
    assert bd["sources"] == ["fmi3_all.c"]  # the one translation unit (docs/standalone.md "Source code")
    imp = set(zipfile.ZipFile(built["impacts"]["fmi3"]).namelist())
    ext = {"x86_64-windows": ".dll", "x86_64-darwin": ".dylib", "aarch64-darwin": ".dylib"}
    for t in FMI3_TUPLES:
        assert f"binaries/{t}/{built['impacts']['id']}{ext.get(t, '.so')}" in imp


# ------------------------------------------------------ same numbers as FMI 2
@pytest.mark.parametrize("case", ["default", "impacts"])
def test_fmi3_equals_fmi2_bit_for_bit(built, case):
    """fmpy's FMI 3 master on the FMI 3 FMU and its FMI 2 master on the FMI 2 FMU: every output at
    every communication point identical (difference 0), arrays element by element."""
    c = built[case]
    r2 = fmpy.simulate_fmu(str(c["fmi2"]))
    r3 = fmpy.simulate_fmu(str(c["fmi3"]))
    assert len(r2) == len(r3) == c["n"] + 1
    assert np.array_equal(r2["time"], r3["time"])
    compared = 0
    for name in r2.dtype.names:
        m = re.fullmatch(r"(\w+)\[(\d+)\]", name)
        b = r3[m.group(1)][:, int(m.group(2)) - 1] if m else r3[name]
        assert np.array_equal(r2[name], b), (name, np.max(np.abs(r2[name] - b)))
        compared += 1
    assert compared == 7 + 2 * c["tables"].slots + 1
    if case == "impacts":  # the case does what its name says: some pair loses contact
        assert np.min(r3["pair_force"]) <= 0.0


# --------------------------------------------------------------- FMU state
def test_state_serialize_round_trip_continues_identically(built, host):
    """tests/fmu_hosts/fmi3_host.c: at the middle of the run fmi3GetFMUState, fmi3SerializeFMUState,
    fmi3DeserializeFMUState; run to the end, fmi3SetFMUState, run the second half again: equal bit for
    bit ("state-check ok"); and the run with these state calls prints what a run without them prints."""
    c = built["impacts"]
    p = subprocess.run([str(host), *_run_args(c, c["dir"]), "--state-check"], capture_output=True, text=True,
                       timeout=300)
    assert p.returncode == 0, p.stderr[-2000:]
    lines = p.stdout.strip().splitlines()
    assert lines[-1] == "state-check ok"
    assert "\n".join(lines[:-1]) + "\n" == _native(c, host)


def test_fmpy_state_round_trip(built):
    """The same through fmpy's FMI 3 API: a state got at t1, serialized and deserialized, set after
    running on, continues with the numbers of the first continuation."""
    from fmpy.fmi3 import FMU3Slave

    c = built["default"]
    fmu = FMU3Slave(guid=c["md"].instantiationToken, unzipDirectory=str(c["dir"]), modelIdentifier=c["id"],
                    instanceName="g")
    fmu.instantiate()
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    vrs, nval = _outputs(c)
    h, t = c["H"], 0.0
    for _ in range(20):
        fmu.doStep(t, h)
        t += h
    blob = fmu.serializeFMUState(fmu.getFMUState())
    first = []
    for k in range(30):
        fmu.doStep(t + k * h, h)
        first.append(fmu.getFloat64(vrs, nval))
    fmu.setFMUState(fmu.deserializeFMUState(blob))
    again = []
    for k in range(30):
        fmu.doStep(t + k * h, h)
        again.append(fmu.getFloat64(vrs, nval))
    fmu.terminate()
    fmu.freeInstance()
    assert np.array_equal(np.array(first), np.array(again))
    assert not np.array_equal(np.array(first[0]), np.array(first[-1]))


# --------------------------------------------------------- illegal call order
def test_random_call_orders_never_crash(built, host):
    """tests/fmu_hosts/fmi3_host.c fuzz: 10 fresh processes x 200 sequences of random FMI 3 calls (each starting
    with a call the Instantiated state forbids): exit code 0, every status valid, every refusal
    logged, the forbidden first call refused, and steps taken (deep states reached)."""
    c = built["default"]
    for run in range(10):
        p = subprocess.run([str(host), "fuzz", str(c["dir"]), c["id"], c["md"].instantiationToken,
                            str(20261125 + 1000 * run), "200"], capture_output=True, text=True, timeout=600)
        assert p.returncode == 0, (run, p.returncode, p.stderr[-2000:])
        res = {k: int(v) for k, v in (kv.split("=") for kv in p.stdout.split())}
        assert res["sequences"] == 200 and res["bad_status"] == 0 and res["unlogged"] == 0, res
        assert res["illegal_first"] >= 150 and res["steps_ok"] > 50 and res["calls"] > 200 * 5, res


# ---------------------------------------------------------------- platforms
def _native(c, host):
    p = subprocess.run([str(host), *_run_args(c, c["dir"])], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-2000:]
    return p.stdout


def test_aarch64_linux_under_qemu_equals_native(built, host, tmp_path):
    """binaries/aarch64-linux, loaded by an aarch64 build of tests/fmu_hosts/fmi3_host.c under qemu-aarch64:
    the native x86_64-linux numbers, every value equal (IEEE ==; the sign of a zero may differ), exit
    code 0."""
    q = qemu()
    c = built["impacts"]
    exe = _compile_host(tmp_path, "aarch64-linux-gnu")
    p = subprocess.run([q, "-L", str(AARCH64_SYSROOT), str(exe), *_run_args(c, c["dir"])], capture_output=True,
                       text=True, timeout=600)
    assert p.returncode == 0, p.stderr[-2000:]
    assert _equal(p.stdout, _native(c, host))


def _equal(a, b):
    """Two host outputs hold the same numbers (IEEE ==, so 0.0 equals -0.0), row by row."""
    pa, pb = a.replace("\r\n", "\n").strip().splitlines(), b.strip().splitlines()
    num = lambda lines: np.array([[float(x) for x in ln.split(",")] for ln in lines[1:]])
    return pa[0] == pb[0] and len(pa) == len(pb) and np.array_equal(num(pa), num(pb))


def test_x86_64_windows_under_wine_equals_native(built, host, tmp_path):
    """binaries/x86_64-windows, loaded with LoadLibrary by a Windows build of tests/fmu_hosts/fmi3_host.c under
    Wine: the native numbers (IEEE ==), exit code 0 (output to a file: Wine's helpers keep pipes open)."""
    c = built["impacts"]
    exe = _compile_host(tmp_path, "x86_64-windows-gnu")
    out = tmp_path / "wine.out"
    with wine_env(tmp_path) as (w, env), open(out, "w") as fo:
        rc = subprocess.run([w, str(exe), *_run_args(c, "Z:" + c["dir"].as_posix())], stdout=fo,
                            stderr=subprocess.DEVNULL, stdin=subprocess.DEVNULL, env=env, timeout=900).returncode
    assert rc == 0
    assert _equal(out.read_text(), _native(c, host))


def test_darwin_binaries_thin_per_tuple(built):
    """Cannot run here: checked by format. x86_64-darwin and aarch64-darwin each hold one thin Mach-O
    dylib (MH_DYLIB) of that CPU (0x01000007, 0x0100000C), exporting every fmi3 function of the
    standard's fmi3Functions.h and none of the glue's or kernel's (hidden visibility)."""
    c = built["impacts"]
    header = (fmi3_header_dir() / "fmi3Functions.h").read_text()
    fmi3 = set(re.findall(r"FMI3_Export\s+fmi3\w+TYPE\s+(fmi3\w+)\s*;", header))
    assert len(fmi3) == 75 and {"fmi3DoStep", "fmi3InstantiateCoSimulation"} <= fmi3
    for t, cpu in (("x86_64-darwin", 0x01000007), ("aarch64-darwin", 0x0100000C)):
        data = (c["dir"] / "binaries" / t / f"{c['id']}.dylib").read_bytes()
        cpu2, filetype, names, ident = macho_exports(data)
        assert cpu2 == cpu and filetype == 6 and ident == f"@rpath/{c['id']}.dylib"
        assert {"_" + f for f in fmi3} <= names
        assert not [n for n in names if n.startswith(("_gk_", "_gm_", "_gf_"))]


# ------------------------------------------------------------ build recipe
def test_build_description_rebuilds_bit_identical(built, host, tmp_path):
    """Compiling sources/ with the host gcc by sources/buildDescription.xml (its sources, include
    directory, compilerOptions and libraries; -shared to link) gives a binary whose results equal
    the shipped x86_64-linux binary's bit for bit."""
    gcc = need("gcc", shutil.which("gcc"), "apt-get install gcc")
    c = built["impacts"]
    d = tmp_path / "fmu"
    shutil.copytree(c["dir"], d)
    src = d / "sources"
    bd = build_description_flags((src / "buildDescription.xml").read_text())
    lib = d / "binaries" / "x86_64-linux" / f"{c['id']}.so"
    lib.unlink()
    p = subprocess.run([gcc, *bd["cflags"], "-shared", *(f"-I{src / i}" for i in bd["include_dirs"]),
                        f"-I{fmi3_header_dir()}", "-o", str(lib),  # the importer's FMI headers
                        *(str(src / s) for s in bd["sources"]), *(f"-l{x}" for x in bd["libraries"])],
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    p = subprocess.run([str(host), *_run_args(c, d)], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-2000:]
    assert p.stdout == _native(c, host)


# ---------------------------------------------------------------------- SSP
def test_ssp_of_an_fmi3_fmu_is_schema_valid(built, tmp_path):
    """gearfmu.ssp packages the FMI 3 FMU: every .ssd/.ssv valid against the SSP 1.0 XSD, one
    connector per FMI 3 output (the arrays by their name), Int32 parameters as Integer.
    fmpy's SSP master runs FMI 2 components only, so the package is not simulated here."""
    c = built["default"]
    out = build_ssp(c["fmi3"], tmp_path / "g3.ssp", {"nominal": {"damping_ratio": 0.05},
                                                     "seed": {"damping_model": 1}})
    d = tmp_path / "unpacked"
    zipfile.ZipFile(out).extractall(d)
    validate_ssp_dir(d)
    ssd = (d / "SystemStructure.ssd").read_text()
    assert 'name="pair_force"' in ssd and 'name="load_sharing"' in ssd and 'name="time"' not in ssd
    assert "<ssv:Integer value=\"1\"" in (d / "resources" / "seed.ssv").read_text()


def test_cli_fmi_version_errors():
    """--fmi-version 3 with the pythonfmu runtime: a one-line error, exit 2."""
    from gearfmu.cli import main

    with pytest.raises(SystemExit) as e:
        main(["build", "--fmi-version", "4"])
    assert e.value.code == 2
    assert main(["build", "--runtime", "pythonfmu", "--fmi-version", "3", "-o", "/tmp/x.fmu", "-q"]) == 2


def test_compare_reads_fmi3_arrays_by_fmi2_names(built):
    """gearfmu.fmu.compare (gearfmu validate, build_fmu.py) takes the FMI 3 FMU: its variables match
    the tables' (the arrays as their FMI 2 elements), and run_fmu gives the FMI 2 columns with the
    FMI 2 FMU's values, difference 0."""
    from gearfmu.fmu.compare import check_fmu_matches, open_fmu, output_names, run_fmu

    c = built["impacts"]
    check_fmu_matches(open_fmu(c["fmi3"]), tables=c["tables"])
    names = output_names(c["tables"].slots)
    kw = dict(stop_time_s=c["n"] * c["H"], comm_step_s=c["H"], names=names)
    r2, r3 = run_fmu(c["fmi2"], **kw), run_fmu(c["fmi3"], **kw)
    assert set(r3.columns) == set(r2.columns) == set(names)
    for n in names:
        assert np.array_equal(r2.columns[n], r3.columns[n]), n
