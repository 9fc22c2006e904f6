"""Lin & Parker's example planetary system as published, and its matrices assembled by hand (tests only).

J. Lin, R. G. Parker, *Analytical characterization of the unique properties of planetary gear free
vibration*, J. Vib. Acoust. 121 (1999) 316-321, Table 1: the parameters below as published; the
model of its eq (1)-(4) written out here in Lin & Parker's own coordinates (x, y in the carrier
frame, u = r theta for rotations, the planets' radial and tangential zeta, eta; masses m and I/r^2):
K is the Hessian of the potential energy of the mesh deflections delta_sn, delta_rn, the planet
bearing deflections and the supports.  None of it is computed by gearfmu.planetary; the tests
compare the model's frequencies and static loads with these matrices.
"""
import math

import numpy as np
import scipy.linalg

#: Lin & Parker (1999) Table 1, as published
PUBLISHED = dict(
    m=dict(s=0.4, r=2.35, c=5.43, p=0.66),              # kg
    I_r2=dict(s=0.39, r=3.00, c=6.29, p=0.61),           # I/r^2, kg
    k_sp=5e8, k_rp=5e8,                                   # mesh stiffness, N/m
    k_bearing=dict(s=1e8, r=1e8, c=1e8, p=1e8),          # N/m
    k_u=dict(s=0.0, r=1e9, c=0.0),                        # torsional support along u = r theta, N/m
    alpha_deg=24.6,                                       # both meshes
)
#: the kinematics (they do not enter the frequencies): teeth (chosen; the table gives none) and the sun's base
#: radius (half the 77.4 mm base diameter the table lists; its planet and ring diameters, 100.3 and 275.0 mm,
#: do not fit 24.6 deg on both meshes and are not used)
TEETH = (24, 36, 96)
RS = 0.0387


def lin_parker_matrices(N, angles=None, pin_errors=None, k_bearing=None):
    """M, K of Lin & Parker's translational model in their coordinates, [c, r, s, p1..pN] x (x|zeta,
    y|eta, u), from the published table: K = sum k a a^T over every deflection a . q; and the load
    vector f of pin position errors: planet n's pin displaced by (e_r, e_t) (radially out, tangentially
    counter-clockwise) pre-deflects its bearing, delta_zeta + e_r, delta_eta + e_t, so that the bearing
    energy k/2 (a . q + e)^2 adds -k e a to f.  ``k_bearing`` overrides the published bearing
    stiffness of sun, ring, carrier or planet (dict)."""
    P = PUBLISHED
    kb = dict(P["k_bearing"], **(k_bearing or {}))
    a = math.radians(P["alpha_deg"])
    psi = [2 * math.pi * n / N for n in range(N)] if angles is None else list(angles)
    n = 3 * (3 + N)
    idx = {"c": 0, "r": 3, "s": 6}
    M = np.zeros((n, n))
    for b, o in idx.items():
        M[o, o] = M[o + 1, o + 1] = P["m"][b]
        M[o + 2, o + 2] = P["I_r2"][b]
    for k in range(N):
        o = 9 + 3 * k
        M[o, o] = M[o + 1, o + 1] = P["m"]["p"]
        M[o + 2, o + 2] = P["I_r2"]["p"]
    K = np.zeros((n, n))
    f = np.zeros(n)

    def spring(k, entries, pre=0.0):
        v = np.zeros(n)
        for i, c in entries:
            v[i] += c
        K[:] += k * np.outer(v, v)
        f[:] -= k * pre * v

    for b, o in idx.items():              # central members: bearings and torsional supports
        spring(kb[b], [(o, 1.0)])
        spring(kb[b], [(o + 1, 1.0)])
        spring(P["k_u"][b], [(o + 2, 1.0)])
    c, r, s = idx["c"], idx["r"], idx["s"]
    for k in range(N):
        o = 9 + 3 * k
        zeta, eta, un = o, o + 1, o + 2
        psn, prn = psi[k] - a, psi[k] + a
        # delta_sn = y_s cos psi_sn - x_s sin psi_sn - zeta_n sin a_s - eta_n cos a_s + u_s + u_n
        spring(P["k_sp"], [(s + 1, math.cos(psn)), (s, -math.sin(psn)), (zeta, -math.sin(a)), (eta, -math.cos(a)),
                           (s + 2, 1.0), (un, 1.0)])
        # delta_rn = y_r cos psi_rn - x_r sin psi_rn + zeta_n sin a_r - eta_n cos a_r + u_r - u_n
        spring(P["k_rp"], [(r + 1, math.cos(prn)), (r, -math.sin(prn)), (zeta, math.sin(a)), (eta, -math.cos(a)),
                           (r + 2, 1.0), (un, -1.0)])
        # planet bearing: x_c cos psi + y_c sin psi - zeta_n, -x_c sin psi + y_c cos psi - eta_n + u_c
        er, et = (0.0, 0.0) if pin_errors is None else pin_errors[k]
        spring(kb["p"], [(c, math.cos(psi[k])), (c + 1, math.sin(psi[k])), (zeta, -1.0)], er)
        spring(kb["p"], [(c, -math.sin(psi[k])), (c + 1, math.cos(psi[k])), (eta, -1.0), (c + 2, 1.0)], et)
    return M, K, f


def sun_mesh_vector(N, n, angles=None):
    """The row a of delta_sn = a . q (planet n, 0-based) in the coordinates of lin_parker_matrices."""
    a = math.radians(PUBLISHED["alpha_deg"])
    psi = (2 * math.pi * n / N) if angles is None else angles[n]
    v = np.zeros(3 * (3 + N))
    o = 9 + 3 * n
    v[7], v[6], v[o], v[o + 1], v[8], v[o + 2] = (math.cos(psi - a), -math.sin(psi - a), -math.sin(a), -math.cos(a),
                                                  1.0, 1.0)
    return v


def torsional_matrices(N):
    """M, K of the purely rotational model in u = r theta: [c, r, s, p1..pN]; the planets ride on the
    carrier (their mass adds N m_p to the carrier's I/r^2); delta_sn = u_s + u_n - u_c cos a,
    delta_rn = u_r - u_n - u_c cos a."""
    P = PUBLISHED
    a = math.radians(P["alpha_deg"])
    n = 3 + N
    M = np.diag([P["I_r2"]["c"] + N * P["m"]["p"], P["I_r2"]["r"], P["I_r2"]["s"]] + [P["I_r2"]["p"]] * N)
    K = np.zeros((n, n))
    K[1, 1] += P["k_u"]["r"]
    for k in range(N):
        v = np.zeros(n); v[2] = 1.0; v[3 + k] = 1.0; v[0] = -math.cos(a)
        K += P["k_sp"] * np.outer(v, v)
        v = np.zeros(n); v[1] = 1.0; v[3 + k] = -1.0; v[0] = -math.cos(a)
        K += P["k_rp"] * np.outer(v, v)
    return M, K


def hz(M, K, *_):
    w2 = scipy.linalg.eigh(K, M, eigvals_only=True)
    return np.sqrt(np.clip(w2, 0.0, None)) / (2 * math.pi)


