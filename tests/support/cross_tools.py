"""The tools the cross-platform host tests run other platforms' binaries with (zig, Wine, qemu
with Debian's aarch64 glibc), the plain C host tests/fmu_hosts/fmi_host.c compiled for this machine or
a zig target, and a reader of Apple's Mach-O headers (mach-o/fat.h, loader.h, nlist.h) written here,
separately from gearfmu's fat-file writer.

A missing tool FAILS the test that needs it (.ci/run installs them), unless a developer (not CI)
sets GEARFMU_ALLOW_MISSING_CROSS_TOOLS=1.
"""
import contextlib
import os
import shutil
import struct
import subprocess
from pathlib import Path

import pytest

from gearfmu.fmu import crossbuild
from gearfmu.fmu.standalone_build import fmi2_header_dir

FMU_HOSTS = Path(__file__).resolve().parents[1] / "fmu_hosts"

AARCH64_SYSROOT = Path("/usr/aarch64-linux-gnu")  # Debian libc6-arm64-cross


def need(what, found, install):
    """A missing tool fails the test, unless a developer (not CI) explicitly allows skipping."""
    if found:
        return found
    msg = f"{what} not found: {install} (.ci/run installs it)"
    if os.environ.get("GEARFMU_ALLOW_MISSING_CROSS_TOOLS") == "1" and not os.environ.get("CI"):
        pytest.skip(msg)
    pytest.fail(msg)


def zig():
    return need("zig C compiler", crossbuild.zig_command(), "pip install . (ziglang is a gearfmu dependency)")


def wine():
    return need("wine", shutil.which("wine") or shutil.which("wine64") or
                (Path("/usr/lib/wine/wine64").is_file() and "/usr/lib/wine/wine64"),
                "apt-get install wine wine64")


def wineserver():
    """The wineserver of the installed Wine (Debian keeps it out of PATH), or None."""
    return shutil.which("wineserver") or next((str(p) for p in (Path("/usr/lib/wine/wineserver64"),
                                                              Path("/usr/lib/wine/wineserver")) if p.is_file()), None)


@contextlib.contextmanager
def wine_env(tmp):
    """(wine, environment) of a new Wine prefix in the folder ``tmp``; afterwards the prefix's Wine
    processes (the services its runs started) are ended and the prefix removed.  A prefix holds
    copies of Wine's DLLs, about 0.7 GB: kept, one per test, they alone filled a CI machine's disk.
    The UTF-8 locale makes Wine read the Unix side's file names and arguments as UTF-8."""
    w = wine()
    prefix = Path(tmp) / "wineprefix"
    env = dict(os.environ, WINEPREFIX=str(prefix), WINEDEBUG="-all", WINEDLLOVERRIDES="mscoree,mshtml=",
               LANG="C.UTF-8", LC_ALL="C.UTF-8")
    try:
        yield w, env
    finally:
        server = wineserver()
        if server:
            subprocess.run([server, "-k"], env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                           stderr=subprocess.DEVNULL, timeout=120)
        shutil.rmtree(prefix, ignore_errors=True)


def qemu():
    q = need("qemu-aarch64", shutil.which("qemu-aarch64") or shutil.which("qemu-aarch64-static"),
             "apt-get install qemu-user")
    need("aarch64 glibc sysroot", (AARCH64_SYSROOT / "lib" / "ld-linux-aarch64.so.1").is_file() and AARCH64_SYSROOT,
         "apt-get install libc6-arm64-cross")
    return q


def compile_host(tmp, target=None):
    """tests/fmu_hosts/fmi_host.c for this machine (gcc) or for a zig target."""
    src = str(FMU_HOSTS / "fmi_host.c")
    if target is None:
        exe = tmp / "fmi_host"
        cmd = [shutil.which("gcc") or "cc", "-std=c99", "-O1", "-Wall", f"-I{fmi2_header_dir()}", "-o", str(exe),
               src, "-ldl"]
    else:
        exe = tmp / ("fmi_host.exe" if "windows" in target else "fmi_host_" + target.split("-")[0])
        cmd = [*zig(), "cc", "-target", target, "-std=c99", "-O1", "-Wall", f"-I{fmi2_header_dir()}",
               "-o", str(exe), src] + (["-lshell32"] if "windows" in target else ["-ldl"])
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=tmp, timeout=1800)
    assert p.returncode == 0, p.stderr
    return exe


def run_file(cmd, tmp, name, env=None):
    """Run cmd with its output in files (Wine's helper processes keep pipes open); (exit code,
    stdout, stderr)."""
    with open(tmp / f"{name}.out", "w+", encoding="utf-8") as fo, open(tmp / f"{name}.err", "w+") as fe:
        rc = subprocess.Popen(cmd, stdout=fo, stderr=fe, stdin=subprocess.DEVNULL, env=env).wait(timeout=600)
        fo.seek(0)
        fe.seek(0)
        return rc, fo.read().replace("\r\n", "\n"), fe.read()


def fat_slices(data):
    """mach-o/fat.h: big-endian fat_header {magic 0xCAFEBABE, nfat_arch} + fat_arch {cputype, cpusubtype,
    offset, size, align}."""
    magic, n = struct.unpack_from(">II", data, 0)
    assert magic == 0xCAFEBABE
    return [struct.unpack_from(">iiIII", data, 8 + 20 * i) for i in range(n)]


def macho_exports(m):
    """mach-o/loader.h + nlist.h: 64-bit header (magic 0xFEEDFACF, cputype, cpusubtype, filetype, ncmds,
    sizeofcmds, flags, reserved), LC_SYMTAB (0x2) -> nlist_64 {n_strx, n_type, n_sect, n_desc, n_value};
    exported = N_EXT (0x01) with type N_SECT (0x0e); LC_ID_DYLIB (0xd) -> the library's install name."""
    magic, cpu, _, filetype, ncmds = struct.unpack_from("<IiiII", m, 0)
    assert magic == 0xFEEDFACF
    off, names, ident = 32, set(), None
    for _ in range(ncmds):
        cmd, size = struct.unpack_from("<II", m, off)
        if cmd == 0xD:
            name_at = off + struct.unpack_from("<I", m, off + 8)[0]
            ident = m[name_at:m.index(b"\0", name_at)].decode()
        if cmd == 0x2:
            symoff, nsyms, stroff, _ = struct.unpack_from("<IIII", m, off + 8)
            for i in range(nsyms):
                strx, ntype = struct.unpack_from("<IB", m, symoff + 16 * i)
                if ntype & 0x01 and ntype & 0x0E == 0x0E:
                    names.add(m[stroff + strx:m.index(b"\0", stroff + strx)].decode())
        off += size
    return cpu, filetype, names, ident
