"""Binaries of the standalone FMU for every desktop platform (docs/standalone.md "Platforms").

One compiler for all targets: zig's bundled clang (the ``ziglang`` package, a
dependency of gearfmu, ``python -m ziglang cc``), with the same flags for every
target (:data:`gearfmu.fmu.standalone_build.STANDALONE_CFLAGS`: ``-O2``,
``-ffp-contract=off``, ``-fno-fast-math``, C99, hidden visibility).  Without zig
(a Python where the ``ziglang`` package cannot be installed) only the build
machine's own platform is compiled, with the host C compiler; the FMU then says
which platforms it lacks and why, and so does the build's output.

The first link for a target makes zig build that target's C runtime (libc stubs,
compiler-rt; for Windows the whole MinGW runtime) into zig's global cache, once per
zig version.  :func:`prepare_targets` does that up front with a line per target on
stderr (and a note in zig's cache that it is done), so a first build is never a
silent minute; a target whose runtime cannot be built is left out of the FMU with
the reason.

Platform keys are the FMI 3 platform tuples; the folder is FMI 2's name where
FMI 2 has one:

==============  ===================  =============================  ========
key             zig target           FMU folder (FMI 2)             file
==============  ===================  =============================  ========
x86_64-linux    x86_64-linux-gnu.2.17  binaries/linux64             .so
aarch64-linux   aarch64-linux-gnu.2.17 binaries/aarch64-linux       .so
x86_64-windows  x86_64-windows-gnu   binaries/win64                 .dll
x86_64-darwin   x86_64-macos.11.0    binaries/darwin64 (fat)        .dylib
aarch64-darwin  aarch64-macos.11.0   binaries/darwin64 (fat)        .dylib
==============  ===================  =============================  ========

FMI 2.0 names no folder for 64-bit ARM Linux (its platform names are
win32/win64/linux32/linux64/darwin32/darwin64); ``aarch64-linux`` is the FMI 3
tuple, which fmpy's ``supported_platforms`` and the FMI 3 loaders read.  The two
macOS binaries are joined into one universal ("fat") Mach-O in darwin64, so an
importer on either Mac loads the same file (:func:`write_fat_macho`).  An FMI 3
FMU puts every binary under its platform tuple, ``binaries/<key>/`` (FMI 3.0
section 2.5.1.1), one thin Mach-O per Mac CPU, no universal file.  glibc
2.17 is the oldest glibc the Linux binaries need (the manylinux2014 baseline).
"""
from __future__ import annotations

import functools
import hashlib
import importlib.util
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

import platform as _platform

from ..common.cache import cache_dir
from ..common.progress import progress_bar, reporting_enabled, wait_refreshing


@dataclass(frozen=True)
class Target:
    key: str          # FMI 3 platform tuple
    zig: str          # zig -target
    folder: str       # binaries/<folder> in an FMI 2 FMU
    ext: str          # shared library suffix


TARGETS: Dict[str, Target] = {t.key: t for t in (
    Target("x86_64-linux", "x86_64-linux-gnu.2.17", "linux64", ".so"),
    Target("aarch64-linux", "aarch64-linux-gnu.2.17", "aarch64-linux", ".so"),
    Target("x86_64-windows", "x86_64-windows-gnu", "win64", ".dll"),
    Target("x86_64-darwin", "x86_64-macos.11.0", "darwin64", ".dylib"),
    Target("aarch64-darwin", "aarch64-macos.11.0", "darwin64", ".dylib"),
)}
#: Mach-O CPU types (mach/machine.h) of the darwin64 slices
MACHO_CPU = {"x86_64-darwin": 0x01000007, "aarch64-darwin": 0x0100000C}
#: alignment (log2) of each slice inside a fat file: the page size of that CPU (4 KiB x86_64, 16 KiB arm64)
MACHO_ALIGN = {0x01000007: 12, 0x0100000C: 14}


class CrossBuildError(ValueError):
    """A platform could not be compiled; the message names it."""


#: rough size of each target's one-time C-runtime preparation by zig, for the message that
#: announces it (the Windows target builds the whole MinGW C runtime, the others link stubs)
PREPARE_ESTIMATE = {"x86_64-windows": "a minute or more"}
PREPARE_ESTIMATE_DEFAULT = "a few seconds"
#: how often a preparation still under way is reported (s)
PREPARE_HEARTBEAT_S = 20.0
#: the library a preparation links: one exported function (a Mach-O library that exports
#: nothing makes zig's linker fail)
PROBE_SOURCE = '__attribute__((visibility("default"))) int gearfmu_probe(void) { return 0; }\n'


def parse_platforms(text: Optional[str]) -> Tuple[str, ...]:
    """``"all"``/None -> every key; else a comma-separated list of keys (or FMI 2 folder names:
    linux64, win64, darwin64 = both Mac CPUs).  Unknown names raise a one-line ValueError."""
    if text is None or text.strip() in ("", "all"):
        return tuple(TARGETS)
    out: List[str] = []
    for name in (s.strip() for s in text.split(",")):
        keys = [name] if name in TARGETS else [k for k, t in TARGETS.items() if t.folder == name]
        if not keys:
            raise ValueError(f"--platforms: unknown platform {name!r} (known: all, {', '.join(TARGETS)}, "
                             "linux64, win64, darwin64)")
        out += [k for k in keys if k not in out]
    return tuple(out)


def host_key() -> Optional[str]:
    """This machine's platform key (None if not one of :data:`TARGETS`)."""
    sysname = {"Linux": "linux", "Windows": "windows", "Darwin": "darwin"}.get(_platform.system())
    mach = {"amd64": "x86_64", "x86_64": "x86_64", "arm64": "aarch64", "aarch64": "aarch64"}.get(
        _platform.machine().lower())
    key = f"{mach}-{sysname}"
    return key if key in TARGETS and sys.maxsize > 2 ** 32 else None


def zig_command() -> Optional[List[str]]:
    """The zig C compiler driver: the ``ziglang`` package's binary when the package is installed
    (called directly: ``python -m ziglang`` would start one more Python process per compiler
    run, only to exec that binary), else a ``zig`` on PATH."""
    spec = importlib.util.find_spec("ziglang")
    if spec is not None:
        for folder in spec.submodule_search_locations or ():
            binary = os.path.join(folder, "zig.exe" if os.name == "nt" else "zig")
            if os.path.isfile(binary) and os.access(binary, os.X_OK):
                return [binary]
        return [sys.executable, "-m", "ziglang"]
    z = shutil.which("zig")
    return [z] if z else None


def zig_version(zig: Sequence[str]) -> str:
    """``zig <version>`` of the compiler command (asked once per process)."""
    return _zig_version(tuple(zig))


@functools.lru_cache(maxsize=None)
def _zig_version(zig: Tuple[str, ...]) -> str:
    try:
        return "zig " + subprocess.run([*zig, "version"], capture_output=True, text=True,
                                       timeout=120).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "zig (version unknown)"


def zig_global_cache_dir(zig: Sequence[str]) -> Optional[Path]:
    """zig's global cache folder (``zig env``: JSON in older zig, ZON in newer; both give
    ``global_cache_dir`` as a quoted string), None when zig does not say."""
    env = tuple(os.environ.get(k) for k in ("ZIG_GLOBAL_CACHE_DIR", "XDG_CACHE_HOME", "LOCALAPPDATA", "HOME"))
    return _zig_global_cache_dir(tuple(zig), env)


@functools.lru_cache(maxsize=None)
def _zig_global_cache_dir(zig: Tuple[str, ...], _env: tuple) -> Optional[Path]:
    """(``_env``: the variables zig's choice depends on, so that the answer is asked again
    when one of them changes)"""
    try:
        out = subprocess.run([*zig, "env"], capture_output=True, text=True, timeout=120).stdout
    except (OSError, subprocess.SubprocessError):
        return None
    m = re.search(r'global_cache_dir"?\s*[:=]\s*"((?:[^"\\]|\\.)*)"', out)
    return Path(m.group(1).replace("\\\\", "\\")) if m else None


def object_cache_dir() -> Path:
    """Where compiled object files are kept between builds: ``$GEARFMU_CACHE_DIR/objects``, else
    ``$XDG_CACHE_HOME/gearfmu/objects``, else ``~/.cache/gearfmu/objects``."""
    return cache_dir("objects")  # gearfmu.common.cache: the root shared with the other cached results


def _compile_flags(cflags: Sequence[str]) -> List[str]:
    """The flags of a compile-only step: the link-only ``-shared`` dropped."""
    return [f for f in cflags if f != "-shared"]


def _object(zig: Sequence[str], key: str, cflags: Sequence[str], source: Path, include: Path, tmp: Path) -> Path:
    """The object file of ``source`` for target ``key``, compiled once and kept in
    :func:`object_cache_dir` under a name that hashes everything the object depends on (zig's
    version, target, flags, the source and every header of ``include``); a later build with the
    same inputs links the kept object instead of compiling again."""
    t = TARGETS[key]
    h = hashlib.sha256()
    for part in (zig_version(zig), t.zig, " ".join(_compile_flags(cflags)), source.name):
        h.update(part.encode() + b"\0")
    h.update(source.read_bytes())
    for hdr in sorted(Path(include).glob("*.h")):
        h.update(hdr.name.encode() + b"\0" + hdr.read_bytes())
    cache = object_cache_dir()
    obj = cache / f"{source.stem}-{key}-{h.hexdigest()[:24]}.o"
    if obj.is_file():
        return obj
    out = tmp / obj.name
    cmd = [*zig, "cc", "-target", t.zig, *_compile_flags(cflags), "-g0", f"-I{include}", "-c", "-o", str(out),
           str(source)]
    _run(cmd, key, "compilation", tmp)
    try:  # atomic publish: a concurrent build sees either no file or the whole object
        cache.mkdir(parents=True, exist_ok=True)
        part = cache / (obj.name + f".{os.getpid()}.part")
        shutil.copyfile(out, part)
        os.replace(part, obj)
    except OSError:
        return out  # an unwritable cache only costs the next build a compilation
    return obj


def _run(cmd: Sequence[str], key: str, what: str, cwd: Path) -> None:
    try:
        p = subprocess.run(list(cmd), capture_output=True, text=True, timeout=1800, cwd=cwd)
    except (OSError, subprocess.SubprocessError) as exc:
        raise CrossBuildError(f"platform {key}: zig cc cannot run ({exc})") from None
    if p.returncode != 0:
        raise CrossBuildError(f"platform {key}: {what} failed ({' '.join(cmd)}):\n{p.stderr[-4000:]}")


def zig_compile(zig: Sequence[str], key: str, cflags: Sequence[str], sources: Sequence[Path], include: Path,
                out_lib: Path) -> List[str]:
    """Build ``out_lib`` for target ``key``: each source compiled to an object
    (:func:`_object`, kept between builds), then linked with ``zig cc -target <t> <cflags> -g0
    -o <lib> <objects> -lm`` (macOS: plus ``-Wl,-install_name,@rpath/<lib>``, a link option).
    Returns the equivalent one-step command ``zig cc -target <t> <cflags> -g0 -I<include> -o <lib>
    <sources> -lm`` (what the FMU's build recipe records).  Runs in a scratch folder (the Windows
    linker writes an import library and a .pdb beside its output)."""
    t = TARGETS[key]
    out_lib = Path(out_lib)
    out_lib.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="gearfmu_zig_") as tmp:
        tmp = Path(tmp)
        tmp_out = tmp / out_lib.name  # the library's own name (ELF soname, Mach-O id, DLL name)
        link = [f"-Wl,-install_name,@rpath/{out_lib.name}"] if key.endswith("-darwin") else []
        objects = [_object(zig, key, cflags, Path(s), include, tmp) for s in sources]
        _run([*zig, "cc", "-target", t.zig, *cflags, "-g0", "-o", str(tmp_out), *(str(o) for o in objects),
              "-lm", *link], key, "link", tmp)
        shutil.copyfile(tmp_out, out_lib)
    return [*zig, "cc", "-target", t.zig, *cflags, "-g0", f"-I{include}", "-o", str(tmp_out),
            *(str(s) for s in sources), "-lm", *link]


# ------------------------------------------- one-time preparation of the targets
def _prepared_stamp(zig: Sequence[str], key: str, cflags: Sequence[str]) -> Optional[Path]:
    """The note that zig's C runtime of target ``key`` is built, kept in zig's own global cache
    (so that it goes when that cache is cleared); None when zig names no cache folder."""
    root = zig_global_cache_dir(zig)
    if root is None:
        return None
    h = hashlib.sha256("\0".join((zig_version(zig), TARGETS[key].zig, *cflags)).encode()).hexdigest()[:24]
    return root / "gearfmu-prepared" / f"{key}-{h}"


def _probe_link(zig: Sequence[str], key: str, cflags: Sequence[str]) -> None:
    """Link a one-function library for ``key`` with the flags of the real link (zig builds the
    target's C runtime on the way); CrossBuildError with zig's last error line when it fails."""
    t = TARGETS[key]
    with tempfile.TemporaryDirectory(prefix="gearfmu_zigprep_") as tmp:
        src = Path(tmp) / "gearfmu_probe.c"
        src.write_text(PROBE_SOURCE)
        link = ["-Wl,-install_name,@rpath/gearfmu_probe" + t.ext] if key.endswith("-darwin") else []
        cmd = [*zig, "cc", "-target", t.zig, *cflags, "-g0", "-o", str(Path(tmp) / ("gearfmu_probe" + t.ext)),
               str(src), "-lm", *link]
        try:
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=3600, cwd=tmp)
        except (OSError, subprocess.SubprocessError) as exc:
            raise CrossBuildError(f"zig cannot run ({exc})") from None
        if p.returncode != 0:
            lines = [ln.strip() for ln in p.stderr.splitlines() if ln.strip()]
            raise CrossBuildError(f"zig cannot link for {t.zig} (exit status {p.returncode}"
                                  + (f": {lines[-1]}" if lines else "") + ")")


def prepare_targets(zig: Sequence[str], keys: Sequence[str], cflags: Sequence[str], *, log=None) -> Dict[str, str]:
    """Have zig build the C runtime of every target in ``keys`` that it has not built yet (once
    per zig version and cache), one target at a time (zig builds a runtime on all cores), each
    announced on ``log`` (default: stderr) with its rough duration, reported every
    :data:`PREPARE_HEARTBEAT_S` s while it runs and when it is ready.  Returns ``{key: reason}``
    for the targets zig cannot link for (they cannot be built; the rest can)."""
    log = log or (lambda msg: print(msg, file=sys.stderr, flush=True))
    stamps = {k: _prepared_stamp(zig, k, cflags) for k in keys}
    todo = [k for k in keys if stamps[k] is None or not stamps[k].is_file()]
    todo.sort(key=lambda k: k in PREPARE_ESTIMATE)  # the quick ones first
    failed: Dict[str, str] = {}
    with ThreadPoolExecutor(max_workers=1) as pool:
        for key in todo:
            log(f"gearfmu: preparing zig's {key} C runtime (one time per zig version, "
                f"{PREPARE_ESTIMATE.get(key, PREPARE_ESTIMATE_DEFAULT)}) ...")
            t0 = time.perf_counter()
            job = pool.submit(_probe_link, zig, key, cflags)
            while not wait([job], timeout=PREPARE_HEARTBEAT_S).done:
                log(f"gearfmu: still preparing zig's {key} C runtime ({time.perf_counter() - t0:.0f} s) ...")
            try:
                job.result()
            except CrossBuildError as exc:
                failed[key] = str(exc)
                log(f"gearfmu: {key}: {exc}; the FMU will not carry {key}")
                continue
            log(f"gearfmu: zig's {key} C runtime ready ({time.perf_counter() - t0:.0f} s)")
            try:
                stamps[key].parent.mkdir(parents=True, exist_ok=True)
                stamps[key].write_text(f"{zig_version(zig)} {TARGETS[key].zig} {' '.join(cflags)}\n")
            except (OSError, AttributeError):
                pass  # no or an unwritable zig cache: the next build checks again (quickly, zig has it)
    return failed


# ------------------------------------------------------------- Mach-O fat files
def macho_cpu(data: bytes) -> Tuple[int, int]:
    """(cputype, cpusubtype) of a thin 64-bit little-endian Mach-O (magic 0xFEEDFACF)."""
    if len(data) < 12 or struct.unpack_from("<I", data, 0)[0] != 0xFEEDFACF:
        raise CrossBuildError("not a 64-bit little-endian Mach-O file")
    return struct.unpack_from("<ii", data, 4)


def write_fat_macho(slices: Sequence[bytes], out_path) -> Path:
    """Join thin Mach-O files into one universal file (the format ``lipo -create`` writes).

    Format (mach-o/fat.h; all fields big-endian uint32): ``fat_header`` =
    magic 0xCAFEBABE, nfat_arch; then one ``fat_arch`` per slice = cputype,
    cpusubtype (copied from the slice's own header), offset, size, align
    (log2); then the slices, each at an offset that is a multiple of
    2**align (4 KiB for x86_64, 16 KiB for arm64)."""
    heads, body, offset = [], [], 8 + 20 * len(slices)
    for data in slices:
        cpu, sub = macho_cpu(data)
        align = MACHO_ALIGN.get(cpu, 14)
        offset = -(-offset // (1 << align)) * (1 << align)
        heads.append(struct.pack(">iiIII", cpu, sub, offset, len(data), align))
        body.append((offset, data))
        offset += len(data)
    buf = bytearray(offset)
    buf[0:8] = struct.pack(">II", 0xCAFEBABE, len(slices))
    for i, h in enumerate(heads):
        buf[8 + 20 * i:28 + 20 * i] = h
    for off, data in body:
        buf[off:off + len(data)] = data
    out_path = Path(out_path)
    out_path.parent.mkdir(parents=True, exist_ok=True)
    out_path.write_bytes(bytes(buf))
    return out_path


# ------------------------------------------------------------------ the build
def folder(key: str, fmi_version: int = 2) -> str:
    """The binaries/ folder of platform ``key``: FMI 2's name, or FMI 3's tuple (the key itself)."""
    return key if fmi_version == 3 else TARGETS[key].folder


def build_binaries(keys: Sequence[str], sources_dir: Path, binaries_dir: Path, identifier: str, *,
                   cflags: Sequence[str], sources: Sequence[str],
                   host_compile=None, host_cc_first: bool = False, fmi_version: int = 2,
                   log=None) -> Dict[str, dict]:
    """Compile every platform in ``keys`` into ``binaries_dir/<folder>/<identifier><ext>``
    (:func:`folder`; ``sources``: the names of the binary's C files in ``sources_dir``, in compile
    order).

    Returns ``{key: {"folder", "file", "compiler", "command"}}`` for each built
    platform and ``{key: {"missing": reason}}`` for each that could not be built
    (no zig; zig cannot link for the target; the compilation failed: the reason
    says which).  ``host_compile(out_lib) -> (command, compiler)`` compiles the
    build machine's platform when zig is absent, or always with ``host_cc_first``
    (the caller named its own C compiler).  The targets zig has not prepared yet
    are prepared first (:func:`prepare_targets`, messages on ``log``, default stderr).
    CrossBuildError only when no platform at all could be built."""
    zig = zig_command()
    src = Path(sources_dir)
    sources = [src / n for n in sources]
    fat_mac = fmi_version != 3
    report: Dict[str, dict] = {}
    hk = host_key()
    zver = zig_version(zig) if zig else None
    darwin: Dict[str, bytes] = {}
    use_host = {k for k in keys if k == hk and host_compile is not None and (zig is None or host_cc_first)}
    unprepared: Dict[str, str] = {}
    if zig is not None:
        unprepared = prepare_targets(zig, [k for k in keys if k not in use_host], cflags, log=log)
    errors: Dict[str, str] = {}
    with tempfile.TemporaryDirectory(prefix="gearfmu_xbuild_") as tmp:
        outs, jobs = {}, {}
        bar = progress_bar(desc="gearfmu: FMU binaries", enabled=reporting_enabled(), total=len(keys),
                           unit="platform", leave=False)
        with bar, ThreadPoolExecutor(max_workers=max(1, min(len(keys), os.cpu_count() or 1))) as pool:
            for key in keys:  # the zig compilations run side by side (one process each)
                t = TARGETS[key]
                outs[key] = out = (Path(tmp) / key if key.endswith("-darwin") and fat_mac else
                                   Path(binaries_dir) / folder(key, fmi_version)) / (identifier + t.ext)
                if key in use_host:
                    cmd, compiler = host_compile(out)
                    report[key] = {"folder": folder(key, fmi_version), "file": identifier + t.ext,
                                   "compiler": compiler,
                                   "command": _portable(cmd, src, None)}
                elif key in unprepared:
                    report[key] = {"missing": unprepared[key]}
                elif zig is not None:
                    jobs[key] = pool.submit(zig_compile, zig, key, cflags, sources, src, out)
                    report[key] = {}
                else:
                    report[key] = {"missing": "no cross compiler: the ziglang package (a gearfmu dependency) is "
                                              "not installed in this Python"}
                if key not in jobs:
                    bar.update(1)
            names = {job: key for key, job in jobs.items()}
            for job in wait_refreshing(list(jobs.values()), bar):  # the elapsed time moves while zig runs
                bar.set_postfix_str(names[job], refresh=False)
                bar.update(1)
            for key, job in jobs.items():
                t = TARGETS[key]
                try:
                    cmd = job.result()
                except CrossBuildError as exc:
                    errors[key] = str(exc)
                    report[key] = {"missing": str(exc).splitlines()[0] + " (details: the build's stderr)"}
                    continue
                report[key] = {"folder": folder(key, fmi_version), "file": identifier + t.ext, "compiler": zver,
                               "command": _portable(cmd, src, zig)}
        for key, msg in errors.items():  # the compiler's own words, for whoever has to fix it
            (log or (lambda m: print(m, file=sys.stderr, flush=True)))(f"gearfmu: {msg}")
        if all("missing" in r for r in report.values()):
            raise CrossBuildError("no platform could be built: " + "; ".join(
                f"{k}: {r['missing']}" for k, r in report.items()))
        for key in keys:
            if fat_mac and key.endswith("-darwin") and "missing" not in report[key]:
                darwin[key] = outs[key].read_bytes()
        if darwin:
            fat = Path(binaries_dir) / "darwin64" / (identifier + ".dylib")
            write_fat_macho([darwin[k] for k in sorted(darwin)], fat)
            for k in darwin:
                report[k]["fat_slices"] = sorted(darwin)
    return report


def _portable(cmd: Sequence[str], src: Path, zig) -> str:
    """The command with the scratch paths replaced by names relative to sources/."""
    out = []
    skip = len(zig) if zig else 0
    words = (["zig"] if zig else []) + list(cmd[skip:])
    for i, w in enumerate(words):
        if i > 0 and words[i - 1] == "-o":
            w = "<lib>"
        elif w.startswith("-I"):
            w = "-I."
        elif w.startswith(str(src)):
            w = Path(w).name
        elif i == 0 and not zig:
            w = Path(w).name
        out.append(w)
    return " ".join(out)


def platform_summary(report: Dict[str, dict]) -> str:
    """One line: which platforms the FMU carries and which it lacks, each with its reason."""
    have = [k for k, r in report.items() if "missing" not in r]
    line = "binaries: " + (", ".join(f"{k} (binaries/{report[k]['folder']})" for k in have) or "none")
    lacks = missing_platforms(report)
    if lacks:
        reasons = _by_reason(lacks)
        line += "; not built: " + ", ".join(lacks) + " -- " + (next(iter(reasons)) if len(reasons) == 1 else "; ".join(
            f"{', '.join(ks)}: {why}" for why, ks in reasons.items())) + \
            "; those platforms compile sources/ (sources/BUILD.txt)"
    return line


def missing_platforms(report: Dict[str, dict]) -> Dict[str, str]:
    """``{key: reason}`` of the platforms a build report lacks."""
    return {k: r["missing"] for k, r in report.items() if "missing" in r}


def _by_reason(lacks: Dict[str, str]) -> Dict[str, List[str]]:
    out: Dict[str, List[str]] = {}
    for k, why in lacks.items():
        out.setdefault(why, []).append(k)
    return out
