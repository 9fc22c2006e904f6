"""gearfmu.dynamics.harmonics: A_r and A_rms of seed 003 eq 10-11.

References: closed forms of the DFT of sums of sinusoids over whole periods
(a sinusoid of amplitude a has RMS a/sqrt(2)), Parseval's theorem, and
scipy.signal.periodogram (an independent one-sided power-spectrum routine).
"""
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy.signal import periodogram

from gearfmu.dynamics.harmonics import HarmonicsInputError, autopower_one_sided, mesh_harmonics

N_TEETH = 50


def _signal(spr, revs, comps, mean=0.0, rng=None):
    """comps: [(shaft order, amplitude, phase)]; spr samples per revolution."""
    n = int(round(spr * revs))
    s = np.arange(n) / spr  # revolutions
    x = np.full(n, mean)
    for order, a, ph in comps:
        x += a * np.sin(2 * np.pi * order * s + ph)
    return x


def test_sinusoids_at_mesh_orders_give_their_rms_amplitudes():
    # closed form: over whole periods a sinusoid a*sin(...) has one-sided power a^2/2 in one bin
    a = [3.0e-6, 1.2e-6, 0.4e-6]
    comps = [(N_TEETH * (r + 1), a[r], 0.3 + r) for r in range(3)]
    comps.append((7.0, 5e-6, 1.0))           # shaft-order content far from the mesh bands
    comps.append((N_TEETH * 4, 2e-6, 0.0))    # 4th mesh harmonic: not in A_rms (3 harmonics)
    x = _signal(1024, 3, comps, mean=40e-6)
    h = mesh_harmonics(x, samples_per_revolution=1024, teeth=N_TEETH)
    expect = np.array(a) / math.sqrt(2.0)
    assert np.allclose(h.A_r, expect, rtol=1e-12, atol=1e-20)
    assert h.A_rms == pytest.approx(math.sqrt(sum(v * v for v in a) / 2.0), rel=1e-12)
    assert h.mean == pytest.approx(40e-6, rel=1e-12)
    amp = mesh_harmonics(x, samples_per_revolution=1024, teeth=N_TEETH, normalization="amplitude")
    assert np.allclose(amp.A_r, a, rtol=1e-12)


def test_band_collects_sidebands_within_bw():
    # BW = 2 shaft orders: orders N-1, N, N+1 are summed (closed form: powers add)
    a, s = 2.0, 0.5
    x = _signal(512, 4, [(N_TEETH, a, 0.0), (N_TEETH + 1, s, 0.2), (N_TEETH + 2, 7.0, 0.1)])
    h = mesh_harmonics(x, samples_per_revolution=512, teeth=N_TEETH, harmonics=1, bandwidth_orders=2.0)
    assert h.A_r[0] == pytest.approx(math.sqrt((a * a + s * s) / 2.0), rel=1e-12)
    h0 = mesh_harmonics(x, samples_per_revolution=512, teeth=N_TEETH, harmonics=1, bandwidth_orders=0.0)
    assert h0.A_r[0] == pytest.approx(a / math.sqrt(2.0), rel=1e-12)
    h4 = mesh_harmonics(x, samples_per_revolution=512, teeth=N_TEETH, harmonics=1, bandwidth_orders=4.0)
    assert h4.A_r[0] == pytest.approx(math.sqrt((a * a + s * s + 49.0) / 2.0), rel=1e-12)


def test_whole_mesh_periods_are_enough_for_mesh_harmonics():
    # 7 mesh periods (not whole revolutions): mesh orders still fall on bins (order spacing N/7)
    spr = 64 * N_TEETH
    x = _signal(spr, 7 / N_TEETH, [(N_TEETH, 1.0, 0.0), (2 * N_TEETH, 0.25, 1.0)])
    h = mesh_harmonics(x, samples_per_revolution=spr, teeth=N_TEETH)
    assert np.allclose(h.A_r, [1 / math.sqrt(2), 0.25 / math.sqrt(2), 0.0], rtol=1e-12, atol=1e-14)


def test_autopower_matches_scipy_periodogram_and_parseval():
    rng = np.random.default_rng(3)
    for n in (1000, 1001):
        x = rng.normal(size=n) + 0.7
        W = autopower_one_sided(x)
        f, P = periodogram(x, fs=1.0, window="boxcar", detrend=False, scaling="spectrum")
        assert np.allclose(W, P, rtol=1e-12, atol=1e-15)
        assert W[1:].sum() == pytest.approx(np.var(x), rel=1e-12)


@settings(max_examples=30, deadline=None)
@given(amps=st.lists(st.floats(0.0, 10.0), min_size=3, max_size=3),
       phases=st.lists(st.floats(0.0, 6.3), min_size=3, max_size=3),
       revs=st.integers(1, 4))
def test_property_rms_of_mesh_sinusoids(amps, phases, revs):
    comps = [(N_TEETH * (r + 1), amps[r], phases[r]) for r in range(3)]
    x = _signal(400, revs, comps)
    h = mesh_harmonics(x, samples_per_revolution=400, teeth=N_TEETH)
    assert np.allclose(h.A_r, np.array(amps) / math.sqrt(2.0), rtol=1e-9, atol=1e-9)


def test_bad_input_is_rejected_with_the_field_named():
    x = _signal(512, 1, [(N_TEETH, 1.0, 0.0)])
    with pytest.raises(HarmonicsInputError, match="signal"):
        mesh_harmonics(x[:-3], samples_per_revolution=512, teeth=N_TEETH)   # not whole mesh periods
    with pytest.raises(HarmonicsInputError, match="samples_per_revolution"):
        mesh_harmonics(x, samples_per_revolution=200, teeth=N_TEETH)        # Nyquist below 3rd harmonic
    with pytest.raises(HarmonicsInputError, match="normalization"):
        mesh_harmonics(x, samples_per_revolution=512, teeth=N_TEETH, normalization="peak")
    with pytest.raises(HarmonicsInputError, match="teeth"):
        mesh_harmonics(x, samples_per_revolution=512, teeth=0)
    with pytest.raises(HarmonicsInputError, match="bandwidth_orders"):
        mesh_harmonics(x, samples_per_revolution=512, teeth=N_TEETH, bandwidth_orders=-1)
    bad = x.copy()
    bad[3] = np.nan
    with pytest.raises(HarmonicsInputError, match="NaN"):
        mesh_harmonics(bad, samples_per_revolution=512, teeth=N_TEETH)
    assert issubclass(HarmonicsInputError, ValueError)


def test_mesh_order_amplitudes_closed_form_at_constant_and_varying_speed():
    """Closed form: c + sum_k a_k cos(2 pi k phi + p_k) over whole mesh periods has mean c and
    mesh-order peak amplitudes a_k.  At constant speed the samples are used as they are (exact to
    round-off); on a run-up (phi = 10 t + 8 t^2, samples uniform in time) the record is resampled
    uniformly in phi (cubic spline) before the DFT."""
    from gearfmu.dynamics.harmonics import mesh_order_amplitudes

    a = [2.0e-6, 0.5e-6, 0.1e-6]

    def sig(ph):
        return 7e-6 + sum(ak * np.cos(2 * np.pi * (k + 1) * ph + 0.7 * k) for k, ak in enumerate(a))
    ph = np.arange(16 * 30 + 1) / 16
    r = mesh_order_amplitudes(sig(ph), ph)
    assert r.periods == 30 and r.samples_per_period == 16
    assert np.allclose(r.amplitudes, a, rtol=1e-10, atol=0.0) and r.mean == pytest.approx(7e-6, rel=1e-12)
    t = np.linspace(0.0, 1.0, 1201)
    ph = 10 * t + 8 * t ** 2
    r = mesh_order_amplitudes(sig(ph), ph)
    assert r.periods == 18
    assert np.allclose(r.amplitudes, a, rtol=1e-4, atol=0.0) and r.mean == pytest.approx(7e-6, rel=1e-6)
    with pytest.raises(HarmonicsInputError, match="mesh_phase"):
        mesh_order_amplitudes(sig(ph), ph[::-1])
    with pytest.raises(HarmonicsInputError, match="at least one"):
        mesh_order_amplitudes(sig(ph[:10]), ph[:10] * 0.01)
