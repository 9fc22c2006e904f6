"""The native solver's compiled code is cached on disk, so a second process does not compile again.

Reference: numba's own dispatcher statistics (``Dispatcher.stats.cache_hits`` /
``cache_misses``): a process that runs the default scene after another process already ran it
must load every compiled driver from the cache (hits, no misses), whatever the wall time.

Both processes use numba's ordinary cache location (the one every user run uses): on a fresh
install the first process compiles and fills it, on a warm one it loads it; either way the second
process must find every driver there.  Another test process may compile the same functions at the
same time: numba writes each index and data file under a temporary name and renames it into place
(``numba.core.caching.IndexDataCacheFile``), so a reader never sees a half-written file; and
these drivers are compiled for one signature each (the argument types ``simulate`` passes), so
every writer writes the same key under the same data file name with the same bytes: a concurrent
writer can only replace an entry with an equal one.  The first process has exited (its entries
are on disk) before the second starts.
"""
import json
import subprocess
import sys
import textwrap
import pytest

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

CHILD = textwrap.dedent("""
    import json, gearfmu.dynamics.native as nat
    import gearfmu.dynamics.driver as driver
    from gearfmu.pipeline import compute_tables
    from gearfmu.scene.reader import load_scene
    tables = compute_tables(load_scene())
    kw = dict(stop_time_s=2e-3, comm_step_s=1e-4, pinion_torque_Nm=2000.0,
              pinion_speed_start_rad_s=209.4, damping_ratio=0.05)
    nat.simulate(tables, **kw)
    nat.simulate(tables, integrator="rk4", **kw)
    stats = {}
    for name in ("_run", "_equilibrium"):
        st = getattr(driver, name).stats
        stats[name] = [sum(st.cache_hits.values()), sum(st.cache_misses.values())]
    print(json.dumps(stats))
""")


def _run():
    out = subprocess.run([sys.executable, "-c", CHILD], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_second_process_loads_the_native_solver_from_the_cache():
    first = _run()
    second = _run()
    for name, (hits, misses) in second.items():
        assert misses == 0 and hits >= 1, f"{name}: second process {hits} cache hits, {misses} misses (first: {first[name]})"
