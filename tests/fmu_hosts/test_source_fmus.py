"""Source-code FMUs that combine, and a rebuilt library that exports the FMI functions only
(docs/standalone.md "Source code").

References (none produced by the code under test):
* the FMI standard's headers, unmodified: the FMI 2.0.5 headers the project carries
  (gearfmu/fmu/standalone/fmi2_headers) and fmpy's FMI 3.0.1 headers, each compared byte for byte
  with the SHA-256 of the blob of the modelica/fmi-standard release tag (headers/ folder);
* the standard's naming rule for source-code FMUs: every fmi2/fmi3 function prefixed by
  ``<modelIdentifier>_`` through FMI2_FUNCTION_PREFIX / FMI3_FUNCTION_PREFIX (FMI 2.0.5 section
  2.1.1, FMI 3.0 section 2.2.2), and the system linker, which refuses a symbol defined twice;
* the shipped binary of each FMU run by fmpy with the same calls: the program linking both FMUs'
  sources must reproduce both runs bit for bit;
* fmpy's own CMake project (``fmpy.build.build_platform_binary``, fmpy's headers) rebuilding the
  library from sources/, and binutils' ``nm -D --defined-only`` listing what it exports.
"""
import hashlib
import re
import shutil
import subprocess
import zipfile
from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave

from gearfmu.fmu.standalone_build import build_standalone_fmu, fmi2_header_dir, fmi3_header_dir

from factories import make_tables

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

HERE = Path(__file__).resolve().parent
H = 1e-4
N = 40
SCALARS = ("pinion_speed", "gear_speed", "dte", "mesh_force", "mesh_stiffness")
#: SHA-256 of headers/<file> at modelica/fmi-standard tags v2.0.5 and v3.0.1
STANDARD_HEADERS = {
    "fmi2Functions.h": "718e970643d69a7f368519eefd1cab3adbf71ccb373b77761da89898de93b30b",
    "fmi2FunctionTypes.h": "1100ef3a1b50d500887106c88dc126ab064da78884f3b1ca73bbacfebc069d68",
    "fmi2TypesPlatform.h": "2771621d6384562ff9de617fcb83c12bb4d4906645768d02779d1f66b31b315b",
    "fmi3Functions.h": "6367e9f7895848ed8d06c8a9b7f77e72d9f3eae102f64c313d51c10049b720ee",
    "fmi3FunctionTypes.h": "77bb086dbf9b9123f75edc2a90a0f27fb5c32f913ab3f9b69fe2e2cbc2448b24",
    "fmi3PlatformTypes.h": "19ea19ae07cdab582931fc1a545d9aeef3d5066da131ee96a7e393e72164fa30",
}
#: what a linker defines in every shared library besides the code's own symbols
LINKER_SYMBOLS = {"_init", "_fini", "_edata", "_end", "__bss_start"}


def _gcc():
    gcc = shutil.which("gcc")
    if gcc is None:
        pytest.fail("gcc not found: apt-get install gcc")
    return gcc


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    """Two different gear FMUs (other tables, other damping) per FMI version, unzipped."""
    d = tmp_path_factory.mktemp("source_fmus")
    stiff = make_tables()
    soft = make_tables()
    soft.k_N_per_m[:] *= 0.7
    out = {}
    for v in (2, 3):
        for name, tables, zeta in (("A", stiff, 0.02), ("B", soft, 0.05)):
            p = build_standalone_fmu(tables, d / f"{name}{v}.fmu", validation=False, damping_ratio=zeta,
                                     stop_time_s=N * H, output_interval_s=H, max_step_s=1e-5,
                                     platforms=["x86_64-linux"], fmi_version=v, model_name=f"gear{name}")
            z = d / f"{name}{v}"
            with zipfile.ZipFile(p) as f:
                f.extractall(z)
            md = fmpy.read_model_description(str(p))
            out[(v, name)] = {"fmu": p, "dir": z, "md": md, "id": md.coSimulation.modelIdentifier,
                              "token": md.guid}
    return out


def _vrs(md):
    by_name = {v.name: v.valueReference for v in md.modelVariables}
    return [by_name[n] for n in SCALARS]


def _fmpy_run(c, v):
    """The shipped binary, stepped by fmpy with the calls of tests/fmu_hosts/fmi_static_host.c."""
    Slave = FMU3Slave if v == 3 else FMU2Slave
    fmu = Slave(guid=c["token"], unzipDirectory=str(c["dir"]), modelIdentifier=c["id"], instanceName="ref")
    vrs = _vrs(c["md"])
    fmu.instantiate()
    if v == 3:
        fmu.enterInitializationMode(startTime=0.0, stopTime=N * H)
        get = fmu.getFloat64
    else:
        fmu.setupExperiment(startTime=0.0, stopTime=N * H)
        fmu.enterInitializationMode()
        get = fmu.getReal
    fmu.exitInitializationMode()
    rows = [get(vrs)]
    for k in range(1, N + 1):
        fmu.doStep((k - 1) * H, H)
        rows.append(get(vrs))
    fmu.terminate()
    fmu.freeInstance()
    return np.array(rows)


def _declared(v, model_exchange: bool = False):
    """The functions the standard's fmi{v}Functions.h declares for the FMU's interfaces (FMI 2: the
    common and the Co-Simulation ones, and Model Exchange's when the FMU offers it; FMI 3: all, as
    FMI 3.0 section 2.5 requires every function of the header)."""
    text = ((fmi3_header_dir() if v == 3 else fmi2_header_dir()) / f"fmi{v}Functions.h").read_text()
    decl = lambda part: set(re.findall(rf"FMI{v}_Export\s+fmi{v}\w+TYPE\s+(fmi{v}\w+)\s*;", part))
    if v == 3 or model_exchange:
        return decl(text)
    # the declarations come after the #defines, in the order common, Model Exchange, Co-Simulation
    model_exchange = text.rsplit("Functions for FMI2 for Model Exchange", 1)[1].split("Functions for FMI2 for", 1)[0]
    return decl(text) - decl(model_exchange)


def test_the_fmi_headers_are_the_standards():
    for name, want in STANDARD_HEADERS.items():
        d = fmi3_header_dir() if name.startswith("fmi3") else fmi2_header_dir()
        assert hashlib.sha256((d / name).read_bytes()).hexdigest() == want, name


@pytest.mark.parametrize("v", [2, 3])
def test_sources_hold_no_fmi_header(fmus, v):
    """The standard has the importer supply the FMI headers (FMI 2.0.5 section 2.3, FMI 3.0 section
    2.5.1.3): sources/ carries none, and the one file to compile is the translation unit."""
    c = fmus[(v, "A")]
    names = sorted(p.name for p in (c["dir"] / "sources").iterdir())
    assert not [n for n in names if re.match(r"fmi[23]\w*\.h$", n)], names
    if v == 2:
        assert [f for f in c["md"].buildConfigurations[0].sourceFileSets[0].sourceFiles] == ["fmi2_all.c"]
    else:
        assert "fmi3_all.c" in (c["dir"] / "sources" / "buildDescription.xml").read_text()


@pytest.mark.parametrize("v", [2, 3])
def test_two_fmus_sources_link_into_one_program(fmus, v, tmp_path):
    """Both FMUs' sources/fmi{v}_all.c compiled with FMI{v}_FUNCTION_PREFIX=<id>_ and the standard's
    headers, linked into one executable (no symbol defined twice, no unresolved one), run side by
    side: each gives the results of its own shipped binary bit for bit."""
    gcc = _gcc()
    a, b = fmus[(v, "A")], fmus[(v, "B")]
    assert a["id"] != b["id"]
    headers = fmi3_header_dir() if v == 3 else fmi2_header_dir()
    objects = []
    for c in (a, b):
        obj = tmp_path / f"{c['id']}.o"
        src = c["dir"] / "sources"
        p = subprocess.run([gcc, "-c", "-O2", "-std=c99", "-ffp-contract=off", "-fno-fast-math",
                            f"-DFMI{v}_FUNCTION_PREFIX={c['id']}_", f"-I{src}", f"-I{headers}", "-o", str(obj),
                            str(src / f"fmi{v}_all.c")], capture_output=True, text=True, timeout=600)
        assert p.returncode == 0, p.stderr
        defined = subprocess.run(["nm", "--defined-only", "-g", str(obj)], capture_output=True, text=True,
                                 check=True).stdout.split()[2::3]
        assert defined and all(s.startswith(f"{c['id']}_fmi{v}") for s in defined), defined
        objects.append(str(obj))
    exe = tmp_path / "two_fmus"
    p = subprocess.run([gcc, "-std=c99", "-O1", "-Wall", f"-DFMI_VERSION={v}", f"-DFMU_A={a['id']}",
                        f"-DFMU_B={b['id']}", f"-I{headers}", "-o", str(exe), str(HERE / "fmi_static_host.c"),
                        *objects, "-lm"], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    vrs = _vrs(a["md"])
    assert vrs == _vrs(b["md"])
    p = subprocess.run([str(exe), str(a["dir"]), a["token"], str(b["dir"]), b["token"], repr(N * H), repr(H),
                        ",".join(map(str, vrs))], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    parts = p.stdout.split("fmu ")[1:]
    got = {part[0]: np.array([[float(x) for x in ln.split(",")[1:]] for ln in part.splitlines()[2:]])
           for part in parts}
    for name, c in (("A", a), ("B", b)):
        ref = _fmpy_run(c, v)
        assert got[name].shape == ref.shape == (N + 1, len(SCALARS))
        assert np.array_equal(got[name], ref), name
    assert not np.array_equal(got["A"], got["B"])  # two different models


@pytest.mark.parametrize("v", [2, 3])
def test_library_rebuilt_by_fmpy_exports_only_fmi_functions(fmus, v, tmp_path):
    """fmpy's CMake project compiles sources/ (its own headers and flags, no -fvisibility=hidden):
    the library exports the fmi{v}* functions and nothing else of the FMU (no gk_, gkf_, gf_,
    gm_ or other internal symbol), and it runs."""
    from fmpy.build import build_platform_binary

    c = fmus[(v, "A")]
    d = tmp_path / "fmu"
    shutil.copytree(c["dir"], d)
    shutil.rmtree(d / "binaries")
    (tmp_path / "build").mkdir()
    build_platform_binary(d, build_dir=tmp_path / "build")
    lib = next((d / "binaries").rglob(f"{c['id']}.so"))
    names = set(subprocess.run(["nm", "-D", "--defined-only", str(lib)], capture_output=True, text=True,
                               check=True).stdout.split()[2::3])
    fmi = {n for n in names if n.startswith(f"fmi{v}")}
    assert names - fmi <= LINKER_SYMBOLS, sorted(names - fmi - LINKER_SYMBOLS)
    me = "<ModelExchange" in (d / "modelDescription.xml").read_text(encoding="utf-8")
    assert fmi == _declared(v, me), sorted(fmi ^ _declared(v, me))
    res = fmpy.simulate_fmu(str(d), stop_time=10 * H, output_interval=H, output=["mesh_force"])
    assert len(res) == 11 and np.all(np.isfinite(res["mesh_force"]))
