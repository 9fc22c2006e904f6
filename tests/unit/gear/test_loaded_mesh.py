"""Tests of gearfmu.gear.loaded_mesh against closed forms (springs in parallel), a
hand-solved two-pair piecewise-linear balance, seed 000 eq (16) for one crowned
pair, and scipy.optimize.brentq as an independent root finder."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy.optimize import brentq

from gearfmu.gear.loaded_mesh import (LoadedMeshInputError, loaded_static_mesh, pair_force_N,
                                 static_deflection_m)

UM = 1e-6


def test_zero_errors_parallel_springs():
    # closed form: all pairs touch at x = 0, x_s = F / sum k, F_j = k_j F / sum k
    rng = np.random.default_rng(1)
    P, NS, N = 3, 4, 7
    k = rng.uniform(1e7, 1e8, size=(P, NS, N))
    k[2, :, :3] = 0.0  # third pair out of the contact zone at the first angles
    F = 12_345.0
    r = loaded_static_mesh(k, np.zeros((P, N)), np.zeros(NS), F)
    ktot = k.sum(axis=(0, 1))
    np.testing.assert_allclose(r.static_te_m, F / ktot, rtol=1e-13)
    np.testing.assert_allclose(r.pair_load_N, k.sum(axis=1) * F / ktot, rtol=1e-12)
    np.testing.assert_allclose(r.load_sharing, k.sum(axis=1) / ktot, rtol=1e-12)
    # no crowning: per-pair stiffness is the plain sum of the slices, exactly
    assert np.array_equal(r.k_secant_N_per_m, k.sum(axis=1))


def test_two_pairs_known_error_difference_hand_solution():
    # k1 = 2e8, k2 = 3e8 N/m, e1 = 0, e2 = 5 um.  Pair 2 touches when F >= k1*5um = 1000 N.
    # F = 600 N: x = 600/2e8 = 3 um, F1 = 600, F2 = 0.
    # F = 3000 N: x = (3000 + 3e8*5e-6)/5e8 = 9 um, F1 = 1800, F2 = 3e8*4um = 1200.
    k = np.array([[[2e8]], [[3e8]]])
    e = np.array([[0.0], [5 * UM]])
    r = loaded_static_mesh(k, e, np.zeros(1), 600.0)
    np.testing.assert_allclose(r.static_te_m, [3 * UM], rtol=1e-13)
    np.testing.assert_allclose(r.pair_load_N[:, 0], [600.0, 0.0], rtol=1e-12, atol=1e-9)
    r = loaded_static_mesh(k, e, np.zeros(1), 3000.0)
    np.testing.assert_allclose(r.static_te_m, [9 * UM], rtol=1e-13)
    np.testing.assert_allclose(r.pair_load_N[:, 0], [1800.0, 1200.0], rtol=1e-12)
    np.testing.assert_allclose(r.load_sharing[:, 0], [0.6, 0.4], rtol=1e-12)
    # exactly at the threshold 1000 N: x = 5 um, pair 2 just touching
    r = loaded_static_mesh(k, e, np.zeros(1), 1000.0)
    np.testing.assert_allclose(r.static_te_m, [5 * UM], rtol=1e-13)


def test_single_crowned_pair_matches_seed000_eq16():
    # seed 000 eq 16: K = F sum k_n / (F + sum k_n E_pc,n), valid when every slice is in contact,
    # i.e. F >= sum_n k_n (max E - E_n).  5 slices (centre slice E = 0, so the pair's
    # first touch is at its error e), C_b = 8 um over b: E = 8*(0.64, .16, 0, .16, .64) um.
    kn = np.array([1.0e8, 1.2e8, 1.3e8, 1.2e8, 1.0e8])
    E = 8 * UM * np.array([0.64, 0.16, 0.0, 0.16, 0.64])
    F_min = float((kn * (E.max() - E)).sum())  # all slices in contact above this load
    for F in (1.5 * F_min, 4 * F_min, 30 * F_min):
        k = kn[None, :, None]
        r = loaded_static_mesh(k, np.array([[2 * UM]]), E, F)
        K16 = F * kn.sum() / (F + (kn * E).sum())
        np.testing.assert_allclose(r.k_secant_N_per_m[0, 0], K16, rtol=1e-12)
        np.testing.assert_allclose(r.static_te_m[0], 2 * UM + F / K16, rtol=1e-12)
    # below the threshold eq 16 is not valid (outer slices open): the secant is stiffer than
    # eq 16 predicts (eq 16 counts negative slice forces); check against brentq instead
    F = 0.3 * F_min
    x_ref = brentq(lambda x: (kn * np.maximum(0, x - E)).sum() - F, 0, 1e-3, xtol=1e-22, rtol=1e-15)
    r = loaded_static_mesh(kn[None, :, None], np.zeros((1, 1)), E, F)
    np.testing.assert_allclose(r.static_te_m[0], x_ref, rtol=1e-12)
    np.testing.assert_allclose(r.k_secant_N_per_m[0, 0], F / x_ref, rtol=1e-12)
    assert r.k_secant_N_per_m[0, 0] > F * kn.sum() / (F + (kn * E).sum())


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), F=st.floats(0.0, 5e4))
def test_against_brentq_random(seed, F):
    # independent solver: scipy brentq on g(x) = sum k max(0, x - e - E) - F
    rng = np.random.default_rng(seed)
    P, NS = 3, 5
    k = rng.uniform(1e7, 5e7, size=(P, NS, 1)) * (rng.random((P, 1, 1)) < 0.8)
    if k.sum() == 0:
        k[0] = 1e7
    e = rng.uniform(-20 * UM, 20 * UM, size=(P, 1))
    E = np.sort(rng.uniform(0, 10 * UM, NS))
    r = loaded_static_mesh(k, e, E, F)
    gaps = (e[:, None, :] + E[None, :, None]).ravel()
    kk = k.ravel()
    lo = gaps[kk > 0].min()
    g = lambda x: (kk * np.maximum(0, x - gaps)).sum() - F
    if F == 0:
        x_ref = lo
    else:
        x_ref = brentq(g, lo, lo + F / kk[kk > 0].min() + 1e-9, xtol=1e-20, rtol=1e-15, maxiter=500)
    assert abs(r.static_te_m[0] - x_ref) <= 1e-12 * max(abs(x_ref), 1e-6)
    # loads sum to F, and the per-pair (secant k, effective e) springs reproduce F at x_s
    np.testing.assert_allclose(r.pair_load_N.sum(), F, rtol=1e-10, atol=1e-7)
    f_tab = (r.k_secant_N_per_m * np.maximum(0, r.static_te_m - r.e_effective_m)).sum()
    np.testing.assert_allclose(f_tab, F, rtol=1e-10, atol=1e-7)
    # every pair in the contact zone keeps a positive stiffness; pairs outside have zero
    in_zone = k.sum(axis=1) > 0
    assert np.all(r.k_secant_N_per_m[in_zone] > 0) and np.all(r.k_secant_N_per_m[~in_zone] == 0)


def test_static_deflection_vectorised_rows():
    # two rows at once: row 0 one spring 1e8 at gap 1 um, F = 100 N -> x = 2 um;
    # row 1 two springs 1e8 at gaps 0 and 4 um, F = 500 N -> F > 1e8*4um = 400 so both touch:
    # x = (500 + 1e8*4e-6)/2e8 = 4.5 um
    k = np.array([[1e8, 0.0], [1e8, 1e8]])
    g = np.array([[1 * UM, -3 * UM], [0.0, 4 * UM]])
    np.testing.assert_allclose(static_deflection_m(k, g, np.array([100.0, 500.0])), [2 * UM, 4.5 * UM],
                               rtol=1e-13)


def test_pair_force_hand():
    # k = 1e8 per slice, E = [0, 2, 4] um, delta = 3 um -> 1e8*(3 + 1 + 0) um = 400 N
    assert abs(pair_force_N([1e8, 1e8, 1e8], np.array([0, 2, 4]) * UM, 3 * UM) - 400.0) < 1e-9


def test_bad_input():
    k = np.ones((1, 1, 2)) * 1e8
    with pytest.raises(LoadedMeshInputError, match="force_N"):
        loaded_static_mesh(k, np.zeros((1, 2)), np.zeros(1), -1.0)
    with pytest.raises(LoadedMeshInputError, match="e_pair_m"):
        loaded_static_mesh(k, np.zeros((2, 2)), np.zeros(1), 1.0)
    with pytest.raises(LoadedMeshInputError, match="crowning_m"):
        loaded_static_mesh(k, np.zeros((1, 2)), np.array([-1e-6]), 1.0)
    with pytest.raises(LoadedMeshInputError, match="k_N_per_m"):
        loaded_static_mesh(np.zeros((1, 1, 2)), np.zeros((1, 2)), np.zeros(1), 1.0)


def test_even_slices_effective_error_and_unloaded_pair_rule():
    # 4 slices, C_b = 10 um: E = 5.625, 0.625, 0.625, 5.625 um (hand, see test_meshing_errors);
    # the pair first touches at e + min E = e + 0.625 um -> effective error.
    E = np.array([5.625, 0.625, 0.625, 5.625]) * UM
    kn = np.full(4, 5e7)
    k = np.stack([kn, kn])[:, :, None]                 # two identical pairs
    e = np.array([[1 * UM], [500 * UM]])               # pair 2 far away: carries no load
    F = 200.0
    r = loaded_static_mesh(k, e, E, F)
    np.testing.assert_allclose(r.e_effective_m[:, 0], [1.625 * UM, 500.625 * UM], rtol=1e-14)
    # hand: F = 200 N < 2 slices * 5e7 * 5 um = 500 N -> only the 2 centre slices carry:
    # x = 1.625 um + 200/(1e8) = 3.625 um; pair 1 secant = 200 N / 2 um = 1e8 N/m
    np.testing.assert_allclose(r.static_te_m[0], 3.625 * UM, rtol=1e-12)
    np.testing.assert_allclose(r.k_secant_N_per_m[0, 0], 1e8, rtol=1e-10)
    assert r.pair_load_N[1, 0] == 0.0
    # unloaded pair 2 gets the secant at the deflection of pair 1 -> identical pair, same stiffness
    np.testing.assert_allclose(r.k_secant_N_per_m[1, 0], 1e8, rtol=1e-10)
    # at zero load: tangent at first touch = the 2 centre slices = 1e8 N/m for both pairs
    r0 = loaded_static_mesh(k, e, E, 0.0)
    np.testing.assert_allclose(r0.k_secant_N_per_m[:, 0], [1e8, 1e8], rtol=1e-14)
    np.testing.assert_allclose(r0.static_te_m[0], 1.625 * UM, rtol=1e-14)
