"""Test-session configuration shared by every test file.

The suite runs in parallel: pytest-xdist with ``-n auto --dist loadfile`` (pyproject's
[tool.pytest.ini_options]).  Many files build something expensive once per module (an FMU,
tables, a compiled host, a pool of film runs) in a module-scoped fixture; ``loadfile`` keeps each
file on one worker, so such a fixture is built once.  Files are handed out longest first, so that
the two workers finish together: the files of :data:`LONGEST_FIRST` in that order, then the other
files whose tests share a module, class or package fixture, then the files of small independent
tests.  xdist would otherwise re-sort the files by their number of tests, which hands the few-test
heavy files (the direct TVMS films, the fresh-process checks) out last; :func:`pytest_configure`
turns that off.  ``-n 0`` runs the same order in one process.

The C kernel of the pythonfmu runtime (:func:`gearfmu.fmu.pythonfmu_build.compile_kernel`: the
system C compiler on gearkernel.c and gkfmu.c) is compiled once per test process and input, not
once per FMU built: :func:`_compile_kernel_once` keys the compiled library by everything the
compiler reads (the compiler file, the flags, the paths and bytes of the kernel folder's sources)
and copies it where the build asks for it.  The compiler is deterministic (the same inputs give
the same bytes), so every FMU and every ctypes library of the suite holds the bytes a fresh
compilation gives; any failure (no compiler, a bad ``cc``, a compile error) is the real
function's, because a key is only stored after the real function succeeded.
"""
import hashlib
import shutil
import tempfile
from pathlib import Path

import pytest

#: the test files with the largest cost, in the order they are handed out (measured per file: the
#: process and child-process CPU time and the wall time, warm numba and object caches; a file that
#: waits on wine, qemu or a Dask cluster holds its worker for the wall time).  First the two files
#: that fill the caches on a fresh install, one family each: test_integrators compiles the native
#: solver and makes the first standalone build (it cross-compiles every platform's objects),
#: test_direct_tvms compiles the numba film kernels.  Then the files that only solve films (no FMU
#: build), so that the other worker does not compile the same platform objects while that first
#: build runs; then the rest, largest first.  Refresh the order when a file's cost changes a lot.
LONGEST_FIRST = (
    "tests/test_integrators.py",
    "tests/test_direct_tvms.py",
    "tests/test_ehl_transient.py",
    "tests/test_ehl_speedpath.py",
    "tests/test_ehl.py",
    "tests/test_direct_tvms_speed_torque.py",
    "tests/test_film_transient.py",
    "tests/test_ehl_determinism.py",
    "tests/test_helical_contact.py",
    "tests/test_standalone.py",
    "tests/test_platforms.py",
    "tests/test_plan_verify.py",
    "tests/test_pyshim.py",
    "tests/test_plan.py",
    "tests/test_fmu.py",
    "tests/test_pipeline.py",
    "tests/test_fuzz.py",
    "tests/test_hard_cases.py",
    "tests/test_fmi3.py",
    "tests/test_sweeps.py",
    "tests/test_temperature_axis.py",
    "tests/test_ehl_mesh.py",
    "tests/test_dask_tables.py",
    "tests/test_cli_user_errors.py",
    "tests/test_subcell.py",
    "tests/test_robustness.py",
    "tests/test_film_transient_tables.py",
    "tests/test_object_cache.py",
    "tests/test_helical.py",
    "tests/test_envelope_fmu.py",
    "tests/test_init_mode.py",
    "tests/test_process_pool.py",
    "tests/test_reference.py",
    "tests/test_state.py",
    "tests/test_fmu_shared_checks.py",
    "tests/test_helical_sawtooth.py",
    "tests/test_ssp.py",
)

_SHARED_SCOPES = ("module", "class", "package")


def _shares_a_fixture(item) -> bool:
    """True when the test uses a fixture built once for its module, class or package."""
    info = getattr(item, "_fixtureinfo", None)
    if info is None:
        return False
    for name in item.fixturenames:
        defs = info.name2fixturedefs.get(name)
        if defs and defs[-1].scope in _SHARED_SCOPES:
            return True
    return False


_KERNELS = {}          # key -> the library compiled for it, in this process's scratch folder
_SCRATCH = []


def _kernel_key(pb, cc):
    """Everything the kernel compile command reads, as one SHA-256; None if ``cc`` is not a file."""
    cc = Path(cc or pb.find_c_compiler())
    if not cc.is_file():
        return None
    st = cc.stat()
    h = hashlib.sha256(repr((str(cc), st.st_size, st.st_mtime_ns, tuple(pb.CFLAGS), str(pb.KERNEL_SOURCE),
                             str(pb.FMU_LAYER_SOURCE), pb._kernel_filename())).encode())
    for f in sorted({*Path(pb.KERNEL_SOURCE).parent.iterdir(), Path(pb.KERNEL_SOURCE), Path(pb.FMU_LAYER_SOURCE)}):
        if f.is_file():
            h.update(str(f).encode() + b"\0" + f.read_bytes())
    return h.hexdigest()


def _compile_kernel_once(real, pb):
    def compile_kernel(dest_dir, *, cc=None):
        key = _kernel_key(pb, cc)
        if key is None:
            return real(dest_dir, cc=cc)
        if key not in _KERNELS:
            if not _SCRATCH:
                _SCRATCH.append(Path(tempfile.mkdtemp(prefix="gearfmu_test_kernels_")))
            _KERNELS[key] = real(_SCRATCH[0] / key[:16], cc=cc)
        dest = Path(dest_dir)
        dest.mkdir(parents=True, exist_ok=True)
        return Path(shutil.copy2(_KERNELS[key], dest / _KERNELS[key].name))
    compile_kernel.__doc__ = real.__doc__
    return compile_kernel


def pytest_configure(config):
    # keep the order below: xdist's loadfile otherwise hands out the files with most tests first
    if hasattr(config.option, "loadscopereorder"):
        config.option.loadscopereorder = False
    if getattr(config.option, "numprocesses", 0) and not hasattr(config, "workerinput"):
        return  # the xdist controller runs no test
    # before the test modules import it (module docstring)
    from gearfmu.fmu import pythonfmu_build as pb
    pb.compile_kernel = _compile_kernel_once(pb.compile_kernel, pb)


def pytest_unconfigure(config):
    for d in _SCRATCH:
        shutil.rmtree(d, ignore_errors=True)


def _file(item) -> str:
    return item.nodeid.split("::", 1)[0]


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    rank = {f: i for i, f in enumerate(LONGEST_FIRST)}
    heavy = {_file(it) for it in items if _shares_a_fixture(it)}
    # stable: every file keeps its tests together and in their written order
    items.sort(key=lambda it: rank.get(_file(it), len(rank) + (0 if _file(it) in heavy else 1)))
