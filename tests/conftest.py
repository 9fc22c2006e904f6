"""Test-session configuration shared by every test file.

The suite runs in parallel: pytest-xdist with ``-n auto --dist loadfile`` (pyproject's
[tool.pytest.ini_options]).  Before the workers start, the controller fills gearfmu's compile
caches -- numba's (the native solvers, the EHL film kernels) and the cross-compiled C objects -- in
one process per family (:func:`_warm_caches`, tests/support/warm_caches.py), so that on a fresh
clone no worker, command-line run or process pool compiles the same code again.  Many files build
something expensive once per module (an FMU, tables, a compiled host, a pool of film runs) in a
module-scoped fixture; ``loadfile`` keeps each file on one worker, so such a fixture is built once.
Files are handed out longest first, so that the two workers finish together: the files of
:data:`LONGEST_FIRST` in that order, then the other files whose tests share a module, class or
package fixture, then the files of small independent tests.  xdist would otherwise re-sort the
files by their number of tests, which hands the few-test heavy files (the direct TVMS films, the
fresh-process checks) out last; :func:`pytest_configure` turns that off.  ``-n 0`` runs the same
order in one process (and compiles what it meets as it goes).
"""
import importlib.util
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

# The suite computes every table afresh: a test that replaces or counts the table builder, or
# that reads its progress, must not get tables that another test kept in gearfmu's table cache
# (gearfmu.assembly.table_cache).  Set here, so the command-line processes the tests start inherit
# it; tests/unit/assembly/test_table_cache.py turns the cache on in a folder of its own.
os.environ["GEARFMU_NO_TABLE_CACHE"] = "1"

#: the test files with the largest cost, in the order they are handed out (measured per file: the
#: process and child-process CPU time and the wall time, warm numba and object caches; a file that
#: waits on wine, qemu or a Dask cluster holds its worker for the wall time), largest first.
#: Refresh the order when a file's cost changes a lot.
LONGEST_FIRST = (
    "tests/unit/dynamics/test_integrators.py",
    "tests/unit/assembly/test_direct_tvms.py",
    "tests/unit/ehl/test_ehl_transient.py",
    "tests/unit/ehl/test_ehl_speedpath.py",
    "tests/unit/ehl/test_ehl.py",
    "tests/unit/assembly/test_direct_tvms_speed_torque.py",
    "tests/unit/contact/test_film_transient.py",
    "tests/unit/ehl/test_ehl_determinism.py",
    "tests/unit/contact/test_helical_contact.py",
    "tests/fmu_hosts/test_standalone.py",
    "tests/fmu_hosts/test_platforms.py",
    "tests/unit/plan/test_plan_verify.py",
    "tests/fmu_hosts/test_pyshim.py",
    "tests/unit/plan/test_plan.py",
    "tests/fmu_hosts/test_fmu.py",
    "tests/integration/test_pipeline.py",
    "tests/fmu_hosts/test_fuzz.py",
    "tests/unit/dynamics/test_hard_cases.py",
    "tests/fmu_hosts/test_fmi3.py",
    "tests/unit/dynamics/test_sweeps.py",
    "tests/unit/tables/test_temperature_axis.py",
    "tests/unit/contact/test_ehl_mesh.py",
    "tests/integration/test_dask_tables.py",
    "tests/integration/test_cli_user_errors.py",
    "tests/unit/dynamics/test_subcell.py",
    "tests/fmu_hosts/test_robustness.py",
    "tests/unit/assembly/test_film_transient_tables.py",
    "tests/unit/fmu/test_object_cache.py",
    "tests/unit/gear/test_helical.py",
    "tests/fmu_hosts/test_envelope_fmu.py",
    "tests/fmu_hosts/test_init_mode.py",
    "tests/unit/common/test_process_pool.py",
    "tests/unit/dynamics/test_reference.py",
    "tests/fmu_hosts/test_state.py",
    "tests/fmu_hosts/test_fmu_shared_checks.py",
    "tests/unit/gear/test_helical_sawtooth.py",
    "tests/fmu_hosts/test_ssp.py",
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


def pytest_configure(config):
    # keep the order below: xdist's loadfile otherwise hands out the files with most tests first
    if hasattr(config.option, "loadscopereorder"):
        config.option.loadscopereorder = False
    if _is_parallel_controller(config):
        _warm_caches()


def _is_parallel_controller(config) -> bool:
    """True in the process that hands the files to xdist workers (not in a worker, not with -n 0,
    not when only collecting)."""
    n = getattr(config.option, "numprocesses", None)
    return bool(n) and not hasattr(config, "workerinput") and not config.option.collectonly


def _warm_caches() -> None:
    """Fill gearfmu's compile caches before the workers start (tests/support/warm_caches.py): the
    families side by side, each in its own process, with the gearfmu the tests import -- and, when
    gearfmu is also installed as a copy (``pip install .``, as CI does), the numba families of that
    copy too: the command-line runs, fresh processes and pools the tests start outside the
    repository import it, and numba keeps one cache per copy.  With warm caches this takes a few
    seconds.  A family that fails is named on stderr and left to the tests that need it."""
    import tempfile

    from support.warm_caches import FAMILIES, NUMBA_FAMILIES

    here = Path(__file__).resolve().parent
    script = str(here / "support" / "warm_caches.py")
    package = Path(importlib.util.find_spec("gearfmu").origin).resolve().parents[1]
    path = [os.environ["PYTHONPATH"]] if os.environ.get("PYTHONPATH") else []
    runs = [(f, package, dict(os.environ, PYTHONPATH=os.pathsep.join([str(package), str(here), *path])))
            for f in FAMILIES]
    with tempfile.TemporaryDirectory() as cwd:  # the gearfmu a process started outside the repository imports
        p = subprocess.run([sys.executable, "-c", "import importlib.util; print(importlib.util.find_spec('gearfmu').origin)"],
                           cwd=cwd, capture_output=True, text=True)
    installed = Path(p.stdout.strip()).resolve().parents[1] if p.returncode == 0 and p.stdout.strip() else package
    if installed != package:
        runs += [(f, installed, dict(os.environ, PYTHONPATH=os.pathsep.join([str(here), *path])))
                 for f in NUMBA_FAMILIES]
    print(f"tests/conftest.py: filling the compile caches ({', '.join(FAMILIES)}) before the workers start",
          file=sys.stderr, flush=True)
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as cwd:  # outside the repository: a copy imports itself
        procs = [(f, where, subprocess.Popen([sys.executable, script, f], env=env, cwd=cwd, stdout=subprocess.DEVNULL,
                                             stderr=subprocess.PIPE, text=True))
                 for f, where, env in runs]
        for family, where, p in procs:
            _, err = p.communicate()
            if p.returncode != 0:
                last = (err.strip().splitlines() or ["(no message)"])[-1]
                print(f"tests/conftest.py: warming the {family} cache of {where} failed (the tests compile it): "
                      f"{last}", file=sys.stderr, flush=True)
    print(f"tests/conftest.py: compile caches ready ({time.perf_counter() - t0:.0f} s)", file=sys.stderr, flush=True)


def _file(item) -> str:
    return item.nodeid.split("::", 1)[0]


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    rank = {f: i for i, f in enumerate(LONGEST_FIRST)}
    heavy = {_file(it) for it in items if _shares_a_fixture(it)}
    # stable: every file keeps its tests together and in their written order
    items.sort(key=lambda it: rank.get(_file(it), len(rank) + (0 if _file(it) in heavy else 1)))
