"""The two-stage reducer the gearbox tests hold the model to (tests/unit/gearbox/, the gearbox FMU and
SSP host tests): constant-stiffness stages, shafts and end inertias; the mass, stiffness and damping
matrices of its linear limit written out element by element here, not by gearfmu.gearbox; and the
gearbox kernel compiled as a library for ctypes.

References: the chain motor - shaft - stage 1 - shaft - stage 2 - shaft - load in absolute angles;
shaft damping c = 2 zeta sqrt(k Ia Ib/(Ia + Ib)) of its end inertias, mesh damping
c = 2 zeta sqrt(k m_e), m_e = I1 I2/(I1 Rb2^2 + I2 Rb1^2), on x = Rb1 th1 - Rb2 th2.
"""
import math
import subprocess

import numpy as np

from gearfmu.gearbox.model import Mesh, Shaft, build_gearbox
from gearfmu.tables.synthetic import tables_from_arrays


def const_tables(k, z1, z2, rb1, rb2, i1, i2, n=16):
    """Constant mesh stiffness k (one slot, no error, no backlash)."""
    return tables_from_arrays(k_N_per_m=np.full((1, n), k), base_radius_pinion_m=rb1, base_radius_gear_m=rb2,
                              inertia_pinion_kgm2=i1, inertia_gear_kgm2=i2, teeth_pinion=z1, teeth_gear=z2)


# stage 1: 23/67 teeth, stage 2: 19/73 (an e-axle-like reducer, total 11.19)
S1 = dict(k=4.0e8, z1=23, z2=67, rb1=0.0270, rb2=0.0270 * 67 / 23, i1=2.0e-4, i2=1.2e-2)


S2 = dict(k=6.0e8, z1=19, z2=73, rb1=0.0312, rb2=0.0312 * 73 / 19, i1=8.0e-4, i2=8.0e-2)


K_IN, K_MID, K_OUT = 4.0e4, 1.6e5, 5.0e5


I_MOTOR, I_LOAD = 0.03, 2.0


def hand_matrices():
    """M, K of the chain [motor, p1, g1, p2, g2, load] in absolute angles, element by element."""
    M = np.diag([I_MOTOR, S1["i1"], S1["i2"], S2["i1"], S2["i2"], I_LOAD])
    K = np.zeros((6, 6))
    # input shaft motor(0) - p1(1)
    K[0, 0] += K_IN; K[1, 1] += K_IN; K[0, 1] -= K_IN; K[1, 0] -= K_IN
    # mesh 1: x = rb1 th1 - rb2 th2 on p1(1), g1(2)
    a, b, k = S1["rb1"], S1["rb2"], S1["k"]
    K[1, 1] += k * a * a; K[2, 2] += k * b * b; K[1, 2] -= k * a * b; K[2, 1] -= k * a * b
    # intermediate shaft g1(2) - p2(3)
    K[2, 2] += K_MID; K[3, 3] += K_MID; K[2, 3] -= K_MID; K[3, 2] -= K_MID
    # mesh 2 on p2(3), g2(4)
    a, b, k = S2["rb1"], S2["rb2"], S2["k"]
    K[3, 3] += k * a * a; K[4, 4] += k * b * b; K[3, 4] -= k * a * b; K[4, 3] -= k * a * b
    # output shaft g2(4) - load(5)
    K[4, 4] += K_OUT; K[5, 5] += K_OUT; K[4, 5] -= K_OUT; K[5, 4] -= K_OUT
    return M, K


ZETA_MESH, ZETA_SHAFT = 0.05, 0.02


def linear_gearbox():
    meshes = [Mesh("s1", const_tables(**S1), ZETA_MESH, "contact_zone"),
              Mesh("s2", const_tables(**S2), ZETA_MESH, "contact_zone")]
    shafts = [Shaft("input_shaft", "motor", "s1.pinion", K_IN, ZETA_SHAFT),
              Shaft("intermediate_shaft", "s1.gear", "s2.pinion", K_MID, ZETA_SHAFT),
              Shaft("output_shaft", "s2.gear", "load", K_OUT, ZETA_SHAFT)]
    return build_gearbox(meshes, shafts, {"motor": I_MOTOR, "load": I_LOAD})


def hand_damping():
    """C of the chain [motor, p1, g1, p2, g2, load]: shaft c = 2 zeta sqrt(k Ia Ib/(Ia + Ib)) of
    its end inertias, mesh c = 2 zeta sqrt(k m_e), m_e = I1 I2/(I1 Rb2^2 + I2 Rb1^2), on x = Rb1 th1 - Rb2 th2."""
    I = [I_MOTOR, S1["i1"], S1["i2"], S2["i1"], S2["i2"], I_LOAD]
    C = np.zeros((6, 6))
    for (a, b), k in (((0, 1), K_IN), ((2, 3), K_MID), ((4, 5), K_OUT)):
        c = 2 * ZETA_SHAFT * math.sqrt(k * I[a] * I[b] / (I[a] + I[b]))
        C[a, a] += c; C[b, b] += c; C[a, b] -= c; C[b, a] -= c
    for (a, b), s in (((1, 2), S1), ((3, 4), S2)):
        me = s["i1"] * s["i2"] / (s["i1"] * s["rb2"] ** 2 + s["i2"] * s["rb1"] ** 2)
        c = 2 * ZETA_MESH * math.sqrt(s["k"] * me)
        r = np.zeros(6); r[a] = s["rb1"]; r[b] = -s["rb2"]
        C += c * np.outer(r, r)
    return C


def c_mesh(s):
    me = s["i1"] * s["i2"] / (s["i1"] * s["rb2"] ** 2 + s["i2"] * s["rb1"] ** 2)
    return 2 * ZETA_MESH * math.sqrt(s["k"] * me)


def hand_damping_of_mid(Z):
    c = 2 * ZETA_SHAFT * math.sqrt(K_MID * S1["i2"] * S2["i1"] / (S1["i2"] + S2["i1"]))
    return c * (Z[:, 8] - Z[:, 9])


def kernel_library(tmp):
    """gb_kernel.c and the pair kernel's library (every function exported); the pair kernel's functions
    bound by gearfmu.fmu.runtime.kernel_api (their one declaration), the gearbox kernel's here."""
    import ctypes
    import shutil

    from gearfmu.fmu.build_steps import CFLAGS, KERNEL_DIR, KERNEL_LIBRARY_SOURCES
    from gearfmu.fmu.runtime.kernel_api import load_kernel

    lib = tmp / "libgb.so"
    subprocess.run([shutil.which("gcc") or "cc", *CFLAGS, "-o", str(lib), str(KERNEL_DIR / "gb_kernel.c"),
                    *map(str, KERNEL_LIBRARY_SOURCES), "-lm"], check=True, capture_output=True, text=True)
    L = load_kernel(lib)
    D, P, I = ctypes.c_double, ctypes.c_void_p, ctypes.c_int
    for name, args in (("gb_sizeof_model", []), ("gb_sizeof_work", []), ("gb_init", [P, I, P, P, I, I, I]),
                       ("gb_add_mesh", [P, P, I, I, I]), ("gb_add_shaft", [P, I, I, D, D, I]),
                       ("gb_derivatives", [P, P, D, P, D, D, P]), ("gb_mesh_offset", [P, I]),
                       ("gb_shaft_offset", [P]), ("gb_n_outputs", [P])):
        getattr(L, name).restype = I
        getattr(L, name).argtypes = args
    return L
