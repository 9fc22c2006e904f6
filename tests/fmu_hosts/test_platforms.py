"""The standalone FMU's binaries for every desktop platform (gearfmu.fmu.crossbuild,
docs/standalone.md "Platforms"), each run here where it can be run.

References (none produced by the code under test):
* the linux64 binary of the same FMU run natively by tests/fmu_hosts/fmi_host.c (that
  binary is itself held to the numba solver in tests/fmu_hosts/test_standalone.py);
* Wine's Windows loader (LoadLibrary in a win64 build of tests/fmu_hosts/fmi_host.c) for
  the win64 DLL, and qemu's aarch64 user-mode emulator with Debian's aarch64
  glibc (libc6-arm64-cross) for the aarch64-linux binary -- both must give the
  native numbers to 1e-9 of each output's range, 10 fresh processes per case,
  exit code 0;
* the Mach-O format as Apple's headers define it (mach-o/fat.h, mach-o/loader.h,
  mach-o/nlist.h), read by a reader written here, separately from gearfmu's
  fat-file writer; the fmi2 function list from the standard's fmi2Functions.h;
* the host gcc and cmake, compiling the FMU's sources/ by its own recipe: the
  result must equal the shipped linux64 binary's bit for bit.

A missing tool (zig, wine, qemu-aarch64, the aarch64 sysroot, cmake) FAILS these
tests (.ci/run installs them).  A developer without root may set
GEARFMU_ALLOW_MISSING_CROSS_TOOLS=1 to skip instead; it is ignored when CI is set.
"""
import re
import shutil
import struct
import subprocess
import zipfile
from pathlib import Path

import fmpy
import numpy as np
import pytest

from gearfmu.fmu import crossbuild
from gearfmu.fmu.compare import output_names
from gearfmu.fmu.standalone_build import (STANDALONE_CFLAGS, build_standalone_fmu, fmi2_header_dir,
                                      read_build_flags)

from support.cross_tools import AARCH64_SYSROOT, compile_host, fat_slices, macho_exports, need, qemu, run_file, wine_env, zig
from support.standalone_cases import cases, max_rel

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

HERE = Path(__file__).resolve().parent
TOL = 1e-9  # of each output's range
RUNS = 10


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    zig()
    d = tmp_path_factory.mktemp("plat")
    out = {}
    for name, c in cases().items():
        kw = dict(damping_ratio=c["zeta"], pinion_speed_start_rad_s=c["w0"], pinion_torque_start_Nm=c["T1"],
                  gear_torque_start_Nm=c["T2"], max_step_s=c["hmax"], damping_model=c["model"],
                  stop_time_s=c["n"] * c["H"], output_interval_s=c["H"], model_name=f"gear_{name}")
        c["fmu"] = build_standalone_fmu(c["tables"], d / f"{name}.fmu", validation=False, **kw)
        c["dir"] = d / name
        with zipfile.ZipFile(c["fmu"]) as z:
            z.extractall(c["dir"])
        md = fmpy.read_model_description(str(c["fmu"]))
        c["md"] = md
        c["id"] = md.coSimulation.modelIdentifier
        vrs = {v.name: v.valueReference for v in md.modelVariables}
        c["names"] = output_names(c["tables"].slots)
        c["vrs"] = [vrs[n] for n in c["names"]]
        out[name] = c
    return out


def _parse(stdout, c):
    lines = stdout.replace("\r\n", "\n").strip().splitlines()
    assert lines[0] == "time," + ",".join(str(v) for v in c["vrs"])
    data = np.array([[float(x) for x in ln.split(",")] for ln in lines[1:]])
    assert data.shape == (c["n"] + 1, len(c["vrs"]) + 1)
    return {n: data[:, i + 1] for i, n in enumerate(c["names"])}


def _host_args(c, fmu_dir):
    return [str(fmu_dir), c["id"], c["md"].guid, repr(c["n"] * c["H"]), repr(c["H"]),
            ",".join(str(v) for v in c["vrs"])]


@pytest.fixture(scope="module")
def native(fmus, tmp_path_factory):
    """Every case run natively (linux64 binary, gcc-built host): the reference of the emulated runs."""
    exe = compile_host(tmp_path_factory.mktemp("host"))
    out = {"exe": exe}
    for name, c in fmus.items():
        p = subprocess.run([str(exe), *_host_args(c, c["dir"])], capture_output=True, text=True, timeout=300)
        assert p.returncode == 0, p.stderr
        out[name] = p.stdout
    return out


def _agree_runs(fmus, native, cmd_for, tmp, env=None):
    """RUNS fresh processes per case; every exit code 0; worst deviation from native (of range).
    Output goes to files, not pipes: Wine's helper processes inherit the standard handles and
    outlive the program, so a pipe would never reach end-of-file."""
    worst = {}
    for name, c in fmus.items():
        ref = _parse(native[name], c)
        procs = []
        for i in range(RUNS):
            fo, fe = open(tmp / f"{name}_{i}.out", "w+"), open(tmp / f"{name}_{i}.err", "w+")
            procs.append((subprocess.Popen(cmd_for(c), stdout=fo, stderr=fe, stdin=subprocess.DEVNULL, env=env),
                          fo, fe))
        outs = set()
        for p, fo, fe in procs:
            rc = p.wait(timeout=600)
            fo.seek(0)
            fe.seek(0)
            out, err = fo.read(), fe.read()
            fo.close()
            fe.close()
            assert rc == 0, (name, rc, err[-2000:])
            outs.add(out.replace("\r\n", "\n"))
        assert len(outs) == 1, f"{name}: the {RUNS} runs differ"
        w = max_rel(ref, _parse(outs.pop(), c), c["names"])
        worst[name] = max(w.values())
        assert worst[name] <= TOL, (name, w)
    return worst


# ------------------------------------------------------------------ contents
def test_every_platform_carried(fmus):
    """One FMU, five targets: ELF x86-64 (linux64), ELF AArch64 (aarch64-linux), PE32+ x86-64 (win64),
    a universal Mach-O x86_64 + arm64 (darwin64) and the arm64 one alone (aarch64-darwin); fmpy sees
    the three FMI 2 platforms and the sources."""
    c = fmus["default"]
    d, ident = c["dir"], c["id"]
    elf = lambda p: (p.read_bytes()[:4], struct.unpack_from("<H", p.read_bytes(), 18)[0])
    assert elf(d / "binaries/linux64" / f"{ident}.so") == (b"\x7fELF", 62)        # EM_X86_64
    assert elf(d / "binaries/aarch64-linux" / f"{ident}.so") == (b"\x7fELF", 183)  # EM_AARCH64
    dll = (d / "binaries/win64" / f"{ident}.dll").read_bytes()
    pe = struct.unpack_from("<I", dll, 0x3C)[0]
    assert dll[:2] == b"MZ" and dll[pe:pe + 4] == b"PE\0\0" and struct.unpack_from("<H", dll, pe + 4)[0] == 0x8664
    fat = (d / "binaries/darwin64" / f"{ident}.dylib").read_bytes()
    assert fat[:4] == b"\xca\xfe\xba\xbe"
    # FMI 2.0.4+ section 2.3: Apple silicon under its FMI 3 tuple too -- the fat file's arm64 slice
    arm = [(off, size) for cpu, _, off, size, _ in fat_slices(fat) if cpu == 0x0100000C]
    assert (d / "binaries/aarch64-darwin" / f"{ident}.dylib").read_bytes() == fat[arm[0][0]:arm[0][0] + arm[0][1]]
    assert {"c-code", "darwin64", "linux64", "win64"} <= set(fmpy.supported_platforms(str(c["fmu"])))
    doc = (d / "documentation" / "platforms.txt").read_text()
    assert "NOT BUILT" not in doc and all(k in doc for k in crossbuild.TARGETS)
    assert "not built" not in c["md"].description


# ----------------------------------------------------------------- Windows
@pytest.fixture(scope="module")
def wine_run(tmp_path_factory):
    """(wine, the win64 build of tests/fmu_hosts/fmi_host.c, the environment of one Wine prefix made for this
    module; cross_tools.wine_env ends its processes and removes it afterwards)."""
    tmp = tmp_path_factory.mktemp("wine")
    exe = compile_host(tmp, "x86_64-windows-gnu")
    with wine_env(tmp) as (w, env):
        # create the prefix once, outside the timed processes
        subprocess.run([w, "cmd", "/c", "exit"], env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL, timeout=600)
        yield w, exe, env


def test_win64_binary_under_wine(fmus, native, wine_run, tmp_path):
    """The win64 DLL, loaded with LoadLibraryW by a win64 build of tests/fmu_hosts/fmi_host.c under Wine,
    gives the native linux64 numbers (10 fresh processes per case, exit code 0)."""
    w, exe, env = wine_run
    worst = _agree_runs(fmus, native, lambda c: [w, str(exe), *_host_args(c, "Z:" + c["dir"].as_posix())],
                        tmp_path, env=env)
    print("win64 under wine: max deviation from native (of range)", worst)


#: folder names of a user's temporary folder on a German (and any other) Windows: letters outside
#: ASCII and the ANSI code page, spaces
UNICODE_FOLDERS = ("dür mit space", "Zahnräder Prüfstand Ölkühlung Übersetzung", "Straße Größe Maß Çédille Ñandú",
                   "ωμέγα Δ 漢字 ß ÄÖÜ äöü", "Messung Zahnradpaar 20 zu 31 Übersetzungsverhältnis Ölsorte",
                   "noch einmal dür mit space")


def test_win64_from_a_long_non_ascii_path_under_wine(fmus, native, wine_run, tmp_path):
    """Windows reads a char path in the ANSI code page, so a C runtime's fopen of the UTF-8 resource
    path fails under a folder named like 'dür mit space' (reference: the fopen/_wfopen contract of
    the Windows C runtime, which Wine implements).  The FMU unzipped under such folders -- non-ASCII
    letters of several scripts, spaces, a folder path over 200 characters and file paths over
    MAX_PATH (260) -- instantiates and runs under Wine, with the resource URI as the host writes it
    (percent-encoded UTF-8), with the drive's colon and the letters escaped in lower-case hex, and
    unescaped UTF-8 after file://localhost/; its output is byte for byte the linux64 binary's from
    the same folder and from a plain one (the same SHA-256)."""
    import hashlib
    import urllib.parse

    w, exe, env = wine_run
    c = fmus["impacts"]
    deep = tmp_path.joinpath(*UNICODE_FOLDERS)
    shutil.copytree(c["dir"], deep)
    win_dir = "Z:" + deep.as_posix()
    dll = f"{win_dir}/binaries/win64/{c['id']}.dll"
    assert len(win_dir) > 200 and len(dll) > 260 and len(f"{win_dir}/resources/tables.bin") > 260
    sha = lambda text: hashlib.sha256(text.encode()).hexdigest()
    reference = sha(native["impacts"])
    rc, out, err = run_file([str(native["exe"]), *_host_args(c, deep)], tmp_path, "linux")
    assert rc == 0, err
    assert sha(out) == reference  # linux64 reads the UTF-8 path as it is

    quoted = urllib.parse.quote(deep.as_posix(), safe="/")
    escaped = "".join(f"%{b:02x}" if b > 127 or chr(b) in " :" else chr(b) for b in deep.as_posix().encode())
    uris = {"host": None,
            "escaped drive colon, lower-case hex": f"file:///Z%3a{escaped}/resources",
            "localhost, unescaped UTF-8": f"file://localhost/Z:{deep.as_posix()}/resources"}
    assert "%C3%BC" in quoted and "%c3%bc" in uris["escaped drive colon, lower-case hex"]
    for name, uri in uris.items():
        extra = [] if uri is None else [f"--resource-uri={uri}"]
        rc, out, err = run_file([w, str(exe), *_host_args(c, win_dir), *extra], tmp_path, f"wine{len(extra)}{name[:4]}",
                                 env=env)
        assert rc == 0, (name, err[-2000:])
        assert sha(out) == reference, name


# ------------------------------------------------------------- aarch64 Linux
def test_aarch64_linux_binary_under_qemu(fmus, native, tmp_path):
    """The aarch64-linux binary, loaded by an aarch64 build of tests/fmu_hosts/fmi_host.c under qemu-aarch64
    (Debian's aarch64 glibc as sysroot), gives the native numbers (10 fresh processes per case)."""
    q = qemu()
    exe = compile_host(tmp_path, "aarch64-linux-gnu")
    worst = _agree_runs(fmus, native, lambda c: [q, "-L", str(AARCH64_SYSROOT), str(exe), *_host_args(c, c["dir"])],
                        tmp_path)
    print("aarch64-linux under qemu: max deviation from native (of range)", worst)


# -------------------------------------------------------------------- macOS
def test_darwin64_universal_binary(fmus):
    """Cannot run here: checked by format. darwin64 holds one fat file with an x86_64 (0x01000007) and
    an arm64 (0x0100000C) dylib (MH_DYLIB = 6), each at an offset aligned to 2**align, each exporting
    every fmi2 function of the standard's header and none of the kernel's (hidden visibility), with the
    install name @rpath/<id>.dylib (no build-machine path)."""
    c = fmus["impacts"]
    data = (c["dir"] / "binaries/darwin64" / f"{c['id']}.dylib").read_bytes()
    header = (fmi2_header_dir() / "fmi2Functions.h").read_text()
    # the header declares the common functions, then the Model Exchange ones, then the Co-Simulation ones;
    # a Co-Simulation FMU exports the common (25) and the Co-Simulation (9) functions
    _, _, common, model_exchange = header.split("Functions for FMI2 for ", 3)
    co_simulation = model_exchange.split("Functions for FMI2 for Co-Simulation", 1)[1]
    decl = lambda text: set(re.findall(r"FMI2_Export\s+fmi2\w+TYPE\s+(fmi2\w+)\s*;", text))
    fmi2 = decl(common) | decl(co_simulation)
    assert len(fmi2) == 34 and {"fmi2DoStep", "fmi2Instantiate", "fmi2GetBooleanStatus"} <= fmi2
    cpus = set()
    for cpu, sub, offset, size, align in fat_slices(data):
        assert offset % (1 << align) == 0 and offset + size <= len(data)
        cpu2, filetype, names, ident = macho_exports(data[offset:offset + size])
        assert cpu2 == cpu and filetype == 6 and ident == f"@rpath/{c['id']}.dylib"
        assert {"_" + f for f in fmi2} <= names, sorted({"_" + f for f in fmi2} - names)
        assert not [n for n in names if n.startswith("_gk_")]
        cpus.add(cpu)
    assert cpus == {0x01000007, 0x0100000C}


# ------------------------------------------------------------ sources recipe
def test_sources_recipe_rebuilds_bit_identical(fmus, native, tmp_path):
    """sources/buildflags.txt names the flags (no contraction, no fast-math, -O2) -- the same as the
    shipped binaries' --, and compiling sources/ by CMakeLists.txt with the host gcc, and by buildflags.txt
    directly, gives a linux64 binary whose results equal the shipped one's bit for bit."""
    cmake = need("cmake", shutil.which("cmake"), "apt-get install cmake")
    gcc = need("gcc", shutil.which("gcc"), "apt-get install gcc")
    c = fmus["impacts"]
    src = c["dir"] / "sources"
    flags = read_build_flags((src / "buildflags.txt").read_text())
    assert flags["cflags"].split() == list(STANDALONE_CFLAGS)
    assert flags["fp_contract"] == "off" and flags["fast_math"] == "off" and flags["optimization"] == "-O2"
    for f in ("-ffp-contract=off", "-fno-fast-math", "-O2"):
        assert f in flags["cflags"].split() and f in (src / "CMakeLists.txt").read_text()
    b = tmp_path / "cmake"
    headers = f"-DFMI_HEADERS_DIR={fmi2_header_dir()}"  # the importer's FMI headers (not in sources/)
    for cmd in ([cmake, "-S", str(src), "-B", str(b), f"-DCMAKE_C_COMPILER={gcc}", headers], [cmake, "--build", str(b)]):
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
        assert p.returncode == 0, p.stdout + p.stderr
    by_flags = tmp_path / "flags" / f"{c['id']}.so"
    by_flags.parent.mkdir()
    p = subprocess.run([gcc, *flags["cflags"].split(), f"-I{src}", f"-I{fmi2_header_dir()}", "-o", str(by_flags),
                        *(str(src / s) for s in flags["sources"].split()), *flags["ldflags"].split()],
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    for lib in (b / f"{c['id']}.so", by_flags):
        d = tmp_path / ("fmu_" + lib.parent.name)
        shutil.copytree(c["dir"], d)
        shutil.copyfile(lib, d / "binaries/linux64" / lib.name)
        p = subprocess.run([str(native["exe"]), *_host_args(c, d)], capture_output=True, text=True, timeout=300)
        assert p.returncode == 0, p.stderr
        assert p.stdout == native["impacts"], f"{lib}: results differ from the shipped binary's"


# ----------------------------------------------------------- without zig
def test_without_zig_the_fmu_says_what_it_lacks(fmus, monkeypatch, tmp_path):
    """No cross compiler: the build still succeeds with the host platform only, and the FMU's
    documentation/platforms.txt and model description name the missing platforms."""
    monkeypatch.setattr(crossbuild, "zig_command", lambda: None)
    c = fmus["impacts"]
    p = build_standalone_fmu(c["tables"], tmp_path / "x.fmu", validation=False, max_step_s=c["hmax"],
                             platforms=("x86_64-linux", "x86_64-windows", "aarch64-darwin"))
    names = zipfile.ZipFile(p).namelist()
    assert [n for n in names if n.startswith("binaries/")] == \
           [f"binaries/linux64/{fmpy.read_model_description(str(p)).coSimulation.modelIdentifier}.so"]
    doc = zipfile.ZipFile(p).read("documentation/platforms.txt").decode()
    assert "x86_64-windows   NOT BUILT" in doc and "aarch64-darwin   NOT BUILT" in doc
    assert "not built: x86_64-windows, aarch64-darwin" in fmpy.read_model_description(str(p)).description


def test_platform_names():
    assert crossbuild.parse_platforms(None) == tuple(crossbuild.TARGETS)
    assert crossbuild.parse_platforms("win64,darwin64") == ("x86_64-windows", "x86_64-darwin", "aarch64-darwin")
    with pytest.raises(ValueError, match="--platforms: unknown platform 'win32'"):
        crossbuild.parse_platforms("linux64,win32")


def test_cli_platforms_errors(capsys):
    """`gearfmu build --platforms`: an unknown name, or a runtime that has no cross build, is a one-line error."""
    from gearfmu.cli import main

    assert main(["build", "--runtime", "standalone", "--platforms", "win32", "-o", "x.fmu"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("gearfmu: --platforms: unknown platform 'win32'") and "\n" not in err
    assert main(["build", "--runtime", "pythonfmu", "--platforms", "win64", "-o", "x.fmu"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("gearfmu: --platforms: only the standalone runtime") and "\n" not in err
