"""Bitwise comparison of EHL solver outputs between two source trees.

``python benchmarks/compare_ehl_outputs.py run TREE OUT.npz`` runs a fixed set
of EHL solves (smooth steady solves at several Moes M, L; one rough steady
solve; one transient solve) with the package found in TREE and stores every
output array; ``python benchmarks/compare_ehl_outputs.py diff A.npz B.npz``
reports whether the two files are equal bit for bit (exit status 1 if not).
Used to check that a refactoring of gearfmu/ehl changes no result.
"""
import json
import sys

import numpy as np

STEADY = [(5.0, 0.0), (20.0, 5.0), (100.0, 10.0), (500.0, 10.0), (50.0, 20.0), (1000.0, 5.0)]


def run(tree, out):
    sys.path.insert(0, tree)
    import gearfmu.ehl as ehl
    assert ehl.__file__.startswith(tree), ehl.__file__
    from gearfmu.ehl import HarmonicWaviness, solve_line_contact, solve_line_contact_transient
    arrays = {}
    for M, L in STEADY:
        for visc in ("roelands", "barus"):
            key = f"steady_M{M:g}_L{L:g}_{visc}"
            try:
                r = solve_line_contact(M=M, L=L, viscosity=visc)
                arrays[key + "_P"] = r.P
                arrays[key + "_H"] = r.H
                arrays[key + "_it"] = np.array([r.iterations])
            except ehl.EHLError as e:
                arrays[key + "_error"] = np.array([str(e).split(" in ")[0]])
    rough = lambda x: 2e-8 * np.cos(2 * np.pi * x / 2e-4)
    r = solve_line_contact(M=20.0, L=10.0, roughness_m=rough)
    arrays["rough_P"], arrays["rough_H"] = r.P, r.H
    wav = HarmonicWaviness(amplitude_m=0.1 * r.h_central_m, wavelength_m=0.5 * r.b_m)
    t = solve_line_contact_transient(M=20.0, L=10.0, n_nodes=257, roughness=wav, srr=0.5,
                                     n_steps=20)
    for k, v in vars(t).items():
        if isinstance(v, np.ndarray) and v.dtype.kind in "fi":
            arrays["transient_" + k] = v
    np.savez(out, **arrays)
    print(json.dumps({"stored": len(arrays), "file": out}))


def diff(a, b):
    A, B = np.load(a), np.load(b)
    bad = sorted(set(A.files) ^ set(B.files))
    rel = {}
    for k in sorted(set(A.files) & set(B.files)):
        x, y = A[k], B[k]
        if x.shape != y.shape or x.tobytes() != y.tobytes():
            bad.append(k)
            if x.shape == y.shape and x.dtype.kind == "f" and k.endswith("_H"):
                rel[k] = float(np.max(np.abs(x - y)) / np.max(np.abs(x)))
    print(json.dumps({"compared": len(A.files), "different": bad, "bitwise_equal": not bad,
                      "max_rel_film_change": rel}))
    return 0 if not bad else 1


if __name__ == "__main__":
    if sys.argv[1] == "run":
        run(sys.argv[2], sys.argv[3])
    else:
        sys.exit(diff(sys.argv[2], sys.argv[3]))
