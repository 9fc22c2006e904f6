"""The slice sawtooth of the sliced helical TVMS (docs/helical.md, "Slice sawtooth").

References (none produced by gearfmu):
* the engaged face width of a helical pair in closed form: a tooth pair whose leading face end
  passed the start of active profile tau mesh periods ago is in contact where its lag
  u = y tan(beta_b)/p_bt (y along the face, 0 <= u <= eps_beta) satisfies 0 <= tau - u <= eps_alpha,
  so its engaged width is (b/eps_beta) |[0, eps_beta] ∩ [tau - eps_alpha, tau]|, summed over the
  pairs tau = t, t + 1, ... (piecewise linear in t with breakpoints from eps_alpha and eps_beta:
  the classical contact-line length L = engaged width / cos(beta_b); Niemann/Winter,
  Maschinenelemente II, ch. 21);
* the continuous-face-width limit of the real stiffness by slice refinement (the change from
  NS = 240 to 480 is below 1e-5 of the mean), against which the deviation must fall like 1/NS^2.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import gearfmu.gear.stiffness as stf
from gearfmu.gear.geometry import pair_geometry
from gearfmu.scene.reader import load_scene

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

SCENE = Path(__file__).resolve().parents[3] / "examples" / "scenes" / "seed001_table1.toml"


def _engaged_width_m(t, eps_a, eps_b, b, pairs):
    """Closed form: total engaged face width at t mesh periods (array)."""
    total = np.zeros_like(t)
    for m in range(pairs):
        tau = t + m
        total += np.clip(np.minimum(tau, eps_b) - np.maximum(tau - eps_a, 0.0), 0.0, None)
    return total * b / eps_b


@pytest.mark.parametrize("slices", [1, 7, 60])
def test_engaged_width_equals_the_contact_line_closed_form(monkeypatch, slices):
    """A stiffness per unit width that is the same everywhere (stub of the slice components, no
    foundation) makes the total stiffness c x engaged width: it must equal the closed form at
    every angle for any slice count (whole slices entering and leaving miss it by up to w)."""
    c = 1e10  # N/m per m of face width

    def uniform(pair, geom, s_m, width_m):
        s = np.asarray(s_m, dtype=float)
        return np.full(s.shape, c * width_m), np.zeros(s.shape), np.zeros(s.shape)

    monkeypatch.setattr(stf, "_helical_slice_components", uniform)
    sc = load_scene(SCENE)
    g = pair_geometry(sc.pair)
    opts = replace(sc.mesh, slices=slices, foundation=False)
    ppm = 97  # not commensurate with the slice boundaries
    st = stf.helical_slot_stiffness(sc.pair, g, opts, None, ppm)
    t = np.arange(st.k_N_per_m.shape[1])[: ppm] / ppm
    ref = _engaged_width_m(t, g.contact_ratio, g.overlap_ratio, g.face_width_m, st.k_N_per_m.shape[0] + 1)
    got = st.k_N_per_m.sum(axis=0)[: ppm] / c
    assert np.max(np.abs(got - ref)) <= 1e-9 * g.face_width_m


def test_real_stiffness_sawtooth_falls_like_one_over_slices_squared():
    """The seed 001 pair: max |k(NS) - k(limit)| / mean k.  Whole slices left about 1/(NS eps_alpha)
    (1.4e-2 at the scene's 60 slices); partial slices: below 0.05/(NS eps_alpha) and falling at
    least 3.5x per halving of the slice width (second order: 4x)."""
    sc = load_scene(SCENE)
    g = pair_geometry(sc.pair)

    def k(ns):
        return stf.helical_slot_stiffness(sc.pair, g, replace(sc.mesh, slices=ns), None, 64).k_N_per_m.sum(axis=0)

    k_lim = k(480)
    assert np.max(np.abs(k_lim - k(240))) <= 1e-5 * k_lim.mean()  # the limit is converged
    dev = {ns: float(np.max(np.abs(k(ns) - k_lim)) / k_lim.mean()) for ns in (15, 30, 60)}
    for ns, d in dev.items():
        assert d <= 0.05 / (ns * g.contact_ratio), (ns, d)
    assert dev[15] / dev[30] >= 3.5 and dev[30] / dev[60] >= 3.5, dev
