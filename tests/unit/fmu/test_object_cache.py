"""Cross-compiled objects are kept between builds: a second build links, it does not compile.

Reference: the compiler's own invocations.  The first build of a platform must call zig with
``-c`` once per source; a second build from the same sources and flags must not call it with
``-c`` again, and its library must behave as the first one (same bytes: the inputs are the
same).  A changed source must be compiled again (the cache key covers the source text).
"""
import subprocess

import pytest

from gearfmu.fmu import crossbuild
from gearfmu.fmu.standalone_build import STANDALONE_CFLAGS, binary_sources, copy_sources, fmi2_header_dir

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow


@pytest.fixture
def counted_compiles(monkeypatch, tmp_path):
    if crossbuild.zig_command() is None:
        pytest.fail("zig C compiler missing: pip install . (ziglang is a gearfmu dependency)")
    monkeypatch.setenv("GEARFMU_CACHE_DIR", str(tmp_path / "cache"))
    calls = []
    real = subprocess.run

    def run(cmd, *a, **k):
        if "cc" in cmd:
            calls.append(list(cmd))
        return real(cmd, *a, **k)

    monkeypatch.setattr(crossbuild.subprocess, "run", run)
    return calls


def _build(src, out, identifier):
    return crossbuild.build_binaries(["x86_64-linux"], src, out, identifier, cflags=STANDALONE_CFLAGS,
                                     sources=binary_sources(2), header_dir=fmi2_header_dir())


def test_second_build_links_kept_objects(counted_compiles, tmp_path):
    src = copy_sources(tmp_path / "src")
    _build(src, tmp_path / "a", "gear_a")
    compiles = [c for c in counted_compiles if "-c" in c]
    assert len(compiles) == len(binary_sources(2)), compiles  # one per source
    counted_compiles.clear()
    _build(src, tmp_path / "b", "gear_a")
    assert not [c for c in counted_compiles if "-c" in c], "the second build compiled again"
    assert len(counted_compiles) == 1                         # the link
    lib_a = (tmp_path / "a" / "linux64" / "gear_a.so").read_bytes()
    lib_b = (tmp_path / "b" / "linux64" / "gear_a.so").read_bytes()
    assert lib_a == lib_b

    counted_compiles.clear()
    kernel = src / "gearkernel.c"
    kernel.write_text(kernel.read_text() + "\n/* changed */\n")
    _build(src, tmp_path / "c", "gear_a")
    assert len([c for c in counted_compiles if "-c" in c]) == 1   # the translation unit that includes it


def test_pythonfmu_kernel_is_compiled_once_and_kept(monkeypatch, tmp_path):
    # Reference: the compiler's own invocations (build_steps.run_compiler) and a fresh compilation.
    # The first compile_kernel calls the compiler; a second one with the same compiler, flags and
    # sources copies the kept library (no compiler call) with the bytes of a fresh compilation;
    # another flag is another key, so it compiles again.
    from gearfmu.fmu import pythonfmu_build as pb

    monkeypatch.setenv("GEARFMU_CACHE_DIR", str(tmp_path / "cache"))
    calls = []
    real = pb.run_compiler

    def counted(cmd, what, **k):
        calls.append(list(cmd))
        return real(cmd, what, **k)

    monkeypatch.setattr(pb, "run_compiler", counted)
    first = pb.compile_kernel(tmp_path / "a")
    assert len(calls) == 1
    second = pb.compile_kernel(tmp_path / "b")
    assert len(calls) == 1, "the second compile_kernel ran the compiler again"
    assert second.read_bytes() == first.read_bytes()
    monkeypatch.setenv("GEARFMU_CACHE_DIR", str(tmp_path / "other"))
    fresh = pb.compile_kernel(tmp_path / "c")
    assert len(calls) == 2 and fresh.read_bytes() == first.read_bytes()
    monkeypatch.setattr(pb, "CFLAGS", [*pb.CFLAGS, "-DGEARFMU_CACHE_KEY_TEST=1"])
    pb.compile_kernel(tmp_path / "d")
    assert len(calls) == 3, "a changed flag must compile again"
