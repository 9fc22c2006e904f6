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

#: the folder of the gearfmu the tests import (the repository with ``python -m pytest``)
PACKAGE_ROOT = Path(importlib.util.find_spec("gearfmu").origin).resolve().parents[1]
# Every process the tests start (command-line runs, fresh processes, process pools, user scripts) runs
# that same gearfmu, also where a copy is installed (``pip install .``, as CI does) and the process
# starts outside the repository: the code under test is one, and so is numba's cache of it, which
# numba keeps next to the source.
os.environ["PYTHONPATH"] = os.pathsep.join([str(PACKAGE_ROOT)] + ([os.environ["PYTHONPATH"]]
                                                                  if os.environ.get("PYTHONPATH") else []))

#: the test files with the largest cost, in the order they are handed out: largest first, by the sum
#: of their tests' durations (setup, call and teardown, as pytest's --junitxml reports them) in a run
#: of the whole suite after the cache warm-up; a file that waits on wine, qemu or a Dask cluster
#: holds its worker for the wall time.  Refresh the order when a file's cost changes a lot.
LONGEST_FIRST = (
    "tests/unit/planetary/test_planetary_native.py",
    "tests/unit/contact/test_helical_contact.py",
    "tests/fmu_hosts/test_pyshim.py",
    "tests/unit/ehl/test_ehl_transient.py",
    "tests/unit/assembly/test_table_cache.py",
    "tests/fmu_hosts/test_platforms.py",
    "tests/unit/gearbox/test_gearbox_me_kernel.py",
    "tests/fmu_hosts/test_source_fmus.py",
    "tests/fmu_hosts/test_gearbox_fmu.py",
    "tests/project/test_architecture.py",
    "tests/integration/test_examples_runtime.py",
    "tests/integration/test_pipeline.py",
    "tests/fmu_hosts/test_fuzz.py",
    "tests/unit/ehl/test_ehl_determinism.py",
    "tests/unit/assembly/test_direct_tvms.py",
    "tests/integration/test_progress.py",
    "tests/unit/gearbox/test_gearbox_reference.py",
    "tests/unit/fmu/test_object_cache.py",
    "tests/unit/dynamics/test_integrators.py",
    "tests/unit/ehl/test_ehl.py",
    "tests/unit/plan/test_plan.py",
    "tests/unit/plan/test_plan_verify.py",
    "tests/unit/ehl/test_ehl_speedpath.py",
    "tests/fmu_hosts/test_fmi3.py",
    "tests/fmu_hosts/test_gearbox_ssp.py",
    "tests/fmu_hosts/test_fmu.py",
    "tests/integration/test_cli_user_errors.py",
    "tests/fmu_hosts/test_standalone.py",
    "tests/fmu_hosts/test_model_exchange.py",
    "tests/integration/test_dask_tables.py",
    "tests/unit/ehl/test_ehl_moes.py",
    "tests/unit/contact/test_film_transient.py",
    "tests/unit/assembly/test_direct_tvms_speed_torque.py",
    "tests/fmu_hosts/test_gearbox_me.py",
    "tests/unit/tables/test_temperature_axis.py",
    "tests/unit/dynamics/test_sweeps.py",
    "tests/integration/test_damaged_inputs.py",
    "tests/fmu_hosts/test_robustness.py",
    "tests/unit/assembly/test_film_transient_tables.py",
    "tests/unit/dynamics/test_hard_cases.py",
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
    families side by side, each in its own process, with the gearfmu the tests import.  With warm
    caches this takes a few seconds.  A family that fails is named on stderr and left to the tests
    that need it."""
    from support.warm_caches import FAMILIES

    here = Path(__file__).resolve().parent
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([os.environ["PYTHONPATH"], str(here)]))
    print(f"tests/conftest.py: filling the compile caches ({', '.join(FAMILIES)}) before the workers start",
          file=sys.stderr, flush=True)
    t0 = time.perf_counter()
    procs = {f: subprocess.Popen([sys.executable, str(here / "support" / "warm_caches.py"), f], env=env,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
             for f in FAMILIES}
    for family, p in procs.items():
        _, err = p.communicate()
        if p.returncode != 0:
            last = (err.strip().splitlines() or ["(no message)"])[-1]
            print(f"tests/conftest.py: warming the {family} cache failed (the tests compile it): {last}",
                  file=sys.stderr, flush=True)
    print(f"tests/conftest.py: compile caches ready ({time.perf_counter() - t0:.0f} s)", file=sys.stderr, flush=True)


def _file(item) -> str:
    return item.nodeid.split("::", 1)[0]


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    rank = {f: i for i, f in enumerate(LONGEST_FIRST)}
    heavy = {_file(it) for it in items if _shares_a_fixture(it)}
    # stable: every file keeps its tests together and in their written order
    items.sort(key=lambda it: rank.get(_file(it), len(rank) + (0 if _file(it) in heavy else 1)))
