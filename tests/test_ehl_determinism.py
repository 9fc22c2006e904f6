"""The EHL film is the same in every process: it does not depend on the heap layout.

Reference: IEEE 754 arithmetic itself -- the same operations on the same numbers give the same
bits.  The elastic deformation (FFT convolution, gearfmu.ehl.deformation.conv_real, called by the
multigrid core's film update) was compiled with reassociating fast-math; the compiled film update
then gave different last bits in different processes for the same inputs (about 4 processes in
10, depending on where the heap put its arrays), and a rough transient film near collapse
collapsed in one run and not in the next.  Fresh processes with different heap layouts must give
bit-identical films.  The processes use numba's ordinary cache (as every user run does): the
heap layout, not the compilation, is what varies between them.
"""
import os
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
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
