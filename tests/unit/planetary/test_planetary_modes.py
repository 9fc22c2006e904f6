"""Planetary modes: Lin & Parker's example system, entered as published, against references assembled here.

References (none produced by gearfmu.planetary):

* J. Lin, R. G. Parker, *Analytical characterization of the unique properties of planetary gear
  free vibration*, J. Vib. Acoust. 121 (1999) 316-321: the example system of its Table 1 (below, as
  published: masses and I/r^2 in kg, stiffnesses in N/m, the pressure angle of both meshes); the
  structure its analysis proves for equally spaced planets: rotational modes simple, translational
  modes in pairs, planet modes of multiplicity N - 3 whose frequencies do not depend on N; in the
  purely rotational model the planet modes have multiplicity N - 1.
* the frequencies: the eigenproblem of the mass and stiffness matrices written out in
  tests/unit/planetary/lin_parker.py in Lin & Parker's own coordinates (x, y in the carrier frame, u = r theta for
  rotations, the planets' radial and tangential zeta, eta; masses m and I/r^2), with K the Hessian of
  their potential energy (mesh deflections delta_sn, delta_rn, planet bearing deflections, supports),
  solved with scipy.linalg.eigh.  The model builds angles and radii instead (the teeth and sun radius
  of tests/unit/planetary/lin_parker.py are a choice: the frequencies do not depend on them).
"""
import math

import numpy as np
import pytest

pytestmark = pytest.mark.slow  # builds or long runs: the full suite, not the quick subset

from gearfmu.assembly.planetary_lumped import LumpedPlanetary, lumped_stage
from gearfmu.planetary.model import build_drivetrain
from gearfmu.planetary.modes import campbell, modes, multiplicities
from gearfmu.bench import LIN_PARKER_1999, lp_model
from lin_parker import PUBLISHED, RS, TEETH, hz, lin_parker_matrices, torsional_matrices


def stage(N, model="translational", **kw):
    P = PUBLISHED
    p = LumpedPlanetary(
        planets=N, mass_kg={"sun": P["m"]["s"], "ring": P["m"]["r"], "carrier": P["m"]["c"], "planet": P["m"]["p"]},
        inertia_over_r2_kg={"sun": P["I_r2"]["s"], "ring": P["I_r2"]["r"], "carrier": P["I_r2"]["c"],
                            "planet": P["I_r2"]["p"]},
        mesh_stiffness_sun_N_per_m=P["k_sp"], mesh_stiffness_ring_N_per_m=P["k_rp"],
        bearing_N_per_m={"sun": P["k_bearing"]["s"], "ring": P["k_bearing"]["r"], "carrier": P["k_bearing"]["c"],
                         "planet": P["k_bearing"]["p"]},
        support_N_per_m=P["k_u"]["r"], pressure_angle_sun_rad=math.radians(P["alpha_deg"]),
        teeth_sun=TEETH[0], teeth_planet=TEETH[1], teeth_ring=TEETH[2], base_radius_sun_m=RS, **kw)
    return lumped_stage("lp", p, model=model)


def model_of(N, model="translational", **kw):
    st = stage(N, model, **kw)
    return build_drivetrain(planetaries=[st], motor="lp.sun", load="lp.carrier")


def test_the_cases_module_holds_the_published_table():
    P = PUBLISHED
    assert LIN_PARKER_1999["mass_kg"] == {"sun": P["m"]["s"], "ring": P["m"]["r"], "carrier": P["m"]["c"],
                                          "planet": P["m"]["p"]}
    assert LIN_PARKER_1999["inertia_over_r2_kg"] == {"sun": P["I_r2"]["s"], "ring": P["I_r2"]["r"],
                                                     "carrier": P["I_r2"]["c"], "planet": P["I_r2"]["p"]}
    assert LIN_PARKER_1999["support_N_per_m"] == P["k_u"]["r"]
    assert LIN_PARKER_1999["pressure_angle_sun_rad"] == math.radians(P["alpha_deg"])
    ref = hz(*lin_parker_matrices(4))
    got = np.array([m.frequency_Hz for m in modes(lp_model(4), 50.0).modes])
    np.testing.assert_allclose(got, ref, rtol=1e-9, atol=1e-3)


@pytest.mark.parametrize("N", [3, 4, 5])
def test_translational_frequencies_match_lin_parkers_matrices(N):
    res = modes(model_of(N), 50.0)
    got = np.array([m.frequency_Hz for m in res.modes])
    ref = hz(*lin_parker_matrices(N))
    assert len(got) == 3 * (N + 3)
    np.testing.assert_allclose(got, ref, rtol=1e-9, atol=1e-3)
    # k_su = k_cu = 0: one rigid rotation (sun, carrier and planets turning against the held ring)
    assert ref[0] < 1e-3 and res.modes[0].rigid and not res.modes[1].rigid


@pytest.mark.parametrize("N", [3, 4, 5])
def test_translational_structure_of_lin_parker(N):
    groups = multiplicities(modes(model_of(N), 50.0), "lp")
    rot = [f for t, f, k in groups if t == "rotational"]
    trans = [(f, k) for t, f, k in groups if t == "translational"]
    planet = [(f, k) for t, f, k in groups if t == "planet"]
    assert {t for t, _, _ in groups} <= {"rotational", "translational", "planet"}   # no mixed mode
    assert all(k == 1 for t, _, k in groups if t == "rotational")
    assert len(rot) == 5                              # 6 rotational modes with the rigid one
    assert [k for _, k in trans] == [2] * 6           # 6 pairs of translational modes
    if N == 3:
        assert planet == []
    else:
        assert [k for _, k in planet] == [N - 3] * 3  # 3 planet modes of multiplicity N - 3


def test_planet_mode_frequencies_do_not_depend_on_the_number_of_planets():
    f = {}
    for N in (4, 5, 6):
        f[N] = [fr for t, fr, k in multiplicities(modes(model_of(N), 50.0), "lp") if t == "planet"]
    np.testing.assert_allclose(f[5], f[4], rtol=1e-10)
    np.testing.assert_allclose(f[6], f[4], rtol=1e-10)
    # and the rotational ones do (the planets load the central members)
    r4 = [fr for t, fr, k in multiplicities(modes(model_of(4), 50.0), "lp") if t == "rotational"]
    r5 = [fr for t, fr, k in multiplicities(modes(model_of(5), 50.0), "lp") if t == "rotational"]
    assert max(abs(a / b - 1.0) for a, b in zip(r4, r5)) > 1e-3


@pytest.mark.parametrize("N", [3, 4, 5])
def test_torsional_model_frequencies_and_structure(N):
    res = modes(model_of(N, model="torsional"), 50.0)
    got = np.array([m.frequency_Hz for m in res.modes])
    np.testing.assert_allclose(got, hz(*torsional_matrices(N)), rtol=1e-9, atol=1e-3)
    groups = multiplicities(res, "lp")
    assert [k for t, _, k in groups if t == "planet"] == [N - 1]
    assert [t for t, _, _ in groups].count("rotational") == 3      # 4 with the rigid one


def test_unequally_spaced_planets_mix_the_mode_types():
    """Lin & Parker's structure needs equal spacing: planets at 0, 99, 219 deg (assembly allows
    multiples of 3 deg with 24 + 96 teeth) couple rotation and translation; the frequencies still
    match the published matrices."""
    angles = tuple(math.radians(d) for d in (0.0, 99.0, 219.0))
    res = modes(model_of(3, planet_angles_rad=angles), 50.0)
    np.testing.assert_allclose([m.frequency_Hz for m in res.modes], hz(*lin_parker_matrices(3, angles)),
                               rtol=1e-9, atol=1e-3)
    assert sum(1 for m in res.modes if m.types["lp"] == "mixed") >= 10


def test_strain_energy_fractions_and_campbell():
    m = model_of(4)
    res = modes(m, 50.0)
    for md in res.modes[1:]:
        assert sum(md.energy.values()) == pytest.approx(1.0, rel=1e-9)
    # a planet mode strains no central-member support
    pm = next(md for md in res.modes if md.types["lp"] == "planet")
    assert all(v < 1e-12 for k, v in pm.energy.items() if k.startswith(("lp.sun_", "lp.ring_", "lp.carrier_"))
               and ("bearing" in k or "support" in k))
    c = campbell(m, res, max_speed_rpm=6000.0)
    mesh = [o for o in c["orders"] if o["kind"] == "mesh" and o["harmonic"] == 1]
    # the mesh frequency per motor (sun) rpm: z_s (1 - g_c/g_s) / 60, g_c/g_s = z_s/(z_s + z_r) (Willis)
    zs, zp, zr = TEETH
    assert mesh[0]["hz_per_rpm"] == pytest.approx(zs * (1 - zs / (zs + zr)) / 60.0, rel=1e-12)
    for pt in c["interferences"]:
        assert 0.0 < pt["speed_rpm"] <= 6000.0
