"""The EHL film is the same in every process: it depends neither on the heap layout nor on the
solves run before it.

Reference: IEEE 754 arithmetic itself -- the same operations on the same numbers give the same
bits.  The elastic deformation (FFT convolution, gearfmu.ehl.deformation.conv_real, called by the
multigrid core's film update) was compiled with reassociating fast-math; the compiled film update
then gave different last bits in different processes for the same inputs (about 4 processes in
10, depending on where the heap put its arrays), and a rough transient film near collapse
collapsed in one run and not in the next.  Fresh processes with different heap layouts must give
bit-identical films.  The processes use numba's ordinary cache (as every user run does): the
heap layout, not the compilation, is what varies between them.  Within a process the solves share
read-only grid constants and cycle schedules and nothing else (tests below).
"""
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[3]
CHILD = textwrap.dedent("""
    import hashlib, sys
    import numpy as np
    junk = [np.ones(int(sys.argv[1]) + k) for k in range(5)]   # a different heap layout per run
    from gearfmu.ehl import multigrid
    from gearfmu.ehl.multigrid import EHLParams
    prm = EHLParams(lam=0.17, A=7.5, z=0.52, php0=4.7, c1=0.64, compressible=True, x_in=-4.5, x_out=1.5)
    fm = multigrid.FlatMultigrid(prm, 4, 32)          # finest level 257 nodes: FFT deformation
    fm.hertz_start(0.78)
    print(hashlib.sha256(fm.level_H().tobytes()).hexdigest())
""")


def test_film_is_bitwise_identical_in_fresh_processes():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    digests = []
    for run in range(8):
        out = subprocess.run([sys.executable, "-c", CHILD, str(5 * run + 1)], capture_output=True,
                             text=True, timeout=300, env=env)
        assert out.returncode == 0, out.stderr[-2000:]
        digests.append(out.stdout.split()[-1])
    assert len(set(digests)) == 1, f"{len(set(digests))} different films in {len(digests)} processes"


# ------------------------------------------------------------------ history independence
# A solve must not depend on the solves before it in the same process: the multigrid core
# shares grid constants (node positions, kernel coefficients and spectra, FFT twiddles, the
# X^2/2 base, the level index table) and the cycle schedules between solves on the same grid
# (gearfmu.ehl.multigrid._GRID_CACHE / _LAYOUT_CACHE, gearfmu.ehl.mgcycle.cached_schedule).
# Reference: the same solves in a fresh process, in the other order and after others -- the
# same bits (IEEE 754: the same operations on the same numbers).
HISTORY_CHILD = textwrap.dedent("""
    import hashlib, json, math, sys
    import numpy as np
    from gearfmu.ehl import solve_line_contact

    def digest(r):
        return hashlib.sha256(r.P.tobytes() + r.H.tobytes()
                              + repr((r.iterations, r.residuals.get("attempt"))).encode()).hexdigest()

    # the targets: the fast path (Roelands), the relaxation settings with the frozen switch
    # (Barus, L beyond Moes' range), the settings path at high L, a rough film (coupled Newton)
    TARGETS = [dict(M=5.75, L=22.3), dict(M=5.75, L=22.3, viscosity="barus", compressible=False),
               dict(M=20.0, L=15.0, viscosity="barus", compressible=False),
               dict(M=20.0, L=10.0, n_nodes=257,
                    roughness_m=lambda x: 0.05e-6 * np.cos(2 * np.pi * x / 0.2e-3))]
    rng = np.random.default_rng(2024)
    OTHERS = [dict(M=float(M), L=float(L), viscosity="barus", compressible=False)
              for M, L in zip(10 ** rng.uniform(math.log10(5.0), 3.0, 10), rng.uniform(0.0, 20.0, 10))]
    OTHERS += [dict(M=20.0, L=10.0, n_nodes=513), dict(M=100.0, L=10.0, x_in=-8.0),
               dict(M=20.0, L=10.0, n_nodes=257, roughness_m=lambda x: 0.03e-6 * np.sin(x / 2e-5))]
    order = sys.argv[1]
    out = {}
    if order == "targets_first":
        out["first"] = [digest(solve_line_contact(**t)) for t in TARGETS]
    for o in OTHERS:
        solve_line_contact(**o)
    out["after_others"] = [digest(solve_line_contact(**t)) for t in reversed(TARGETS)][::-1]
    print(json.dumps(out))
""")


def test_solves_do_not_depend_on_the_solves_before_them():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    runs = {}
    for order in ("targets_first", "others_first"):
        out = subprocess.run([sys.executable, "-c", HISTORY_CHILD, order], capture_output=True, text=True,
                             timeout=600, env=env)
        assert out.returncode == 0, out.stderr[-2000:]
        runs[order] = json.loads(out.stdout.strip().splitlines()[-1])
    fresh = runs["targets_first"]["first"]
    assert runs["targets_first"]["after_others"] == fresh, "a solve changed after other solves in its process"
    assert runs["others_first"]["after_others"] == fresh, "a solve differs between processes with other histories"


def test_shared_grid_constants_and_schedules_are_read_only():
    # The arrays every solver on a grid shares cannot be written: a solve that changed one
    # would change every later solve on that grid (numpy raises; a compiled kernel writing
    # one does not compile).
    from gearfmu.ehl import multigrid
    from gearfmu.ehl.mgcycle import cached_schedule
    from gearfmu.ehl.multigrid import EHLParams
    prm = EHLParams(lam=0.17, A=7.5, z=0.52, php0=4.7, c1=0.64, compressible=True, x_in=-4.5, x_out=1.5)
    fm = multigrid.FlatMultigrid(prm, 4, 32)
    shared = [*fm.X, fm.dx, fm.K, fm.khr, fm.khi, fm.twr, fm.twi, fm.sched, cached_schedule(4, "F")]
    for a in shared:
        with pytest.raises(ValueError, match="read-only"):
            a[0] = a[0]
    # the per-solver state is the solver's own
    fm.hertz_start(0.78)
    fm2 = multigrid.FlatMultigrid(prm, 4, 32)
    assert fm2.P is not fm.P and not np.shares_memory(fm2.base, fm.base)
    assert not np.shares_memory(fm2.iarr, fm.iarr)
