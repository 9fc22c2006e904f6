"""CSV import of tooth-pair tables (gearfmu.tables.table_import, docs/tables.md 'CSV import').

References: the computed table itself (a CSV export must read back to identical
arrays, bit for bit); the rectangular-wave TVMS of a single pair of constant
stiffness expanded by the slot rule (pair n engaged for phi - n*T in
[0, eps*T), seed 003 Fig. 2) -- the same wave gearfmu.tables.synthetic builds from its
definition; hand-made bad files for the error messages.
"""
import subprocess
import sys

import numpy as np
import pytest

from gearfmu.pipeline import compute_tables, load
from gearfmu.tables.synthetic import KB_BASE_RADIUS_M, rectangular_wave_tables
from gearfmu.tables.table_import import TableImportError, load_tables_csv, load_tables_file, tables_to_csv

META = dict(teeth_pinion=50, teeth_gear=50, base_radius_pinion_m=KB_BASE_RADIUS_M,
            base_radius_gear_m=KB_BASE_RADIUS_M, inertia_pinion_kgm2=0.0074, inertia_gear_kgm2=0.0074)


@pytest.fixture(scope="module")
def computed():
    return compute_tables(load(None))


def test_computed_table_round_trips_identically(computed, tmp_path):
    csv, meta = tables_to_csv(computed, tmp_path / "t.csv")
    back = load_tables_csv(csv, meta)
    for name in ("k_N_per_m", "e_m", "backlash_half_m", "torque_Nm", "e_comprehensive_m", "static_te_m"):
        assert np.array_equal(getattr(back, name), getattr(computed, name)), name
    for name in ("phi_period_rad", "mesh_period_rad", "k_mean_N_per_m", "contact_ratio", "teeth_pinion",
                 "base_radius_gear_m", "inertia_pinion_kgm2"):
        assert getattr(back, name) == getattr(computed, name), name
    # and the same through the .gtab dispatcher
    computed.save(tmp_path / "t.gtab")
    assert np.array_equal(load_tables_file(tmp_path / "t.gtab").k_N_per_m, computed.k_N_per_m)


def test_torque_axis_round_trips(tmp_path):
    k = np.stack([np.full((2, 16), 1e8), np.full((2, 16), 1.2e8)])
    from gearfmu.tables.synthetic import tables_from_arrays

    t = tables_from_arrays(k_N_per_m=k, e_m=np.random.default_rng(1).normal(0, 1e-6, k.shape), backlash_half_m=3e-5,
                           torque_Nm=[100.0, 500.0], teeth_pinion=20, teeth_gear=31)
    back = load_tables_csv(*tables_to_csv(t, tmp_path / "tq.csv"))
    assert np.array_equal(back.k_N_per_m, t.k_N_per_m) and np.array_equal(back.e_m, t.e_m)
    assert np.array_equal(back.torque_Nm, t.torque_Nm)


def test_csv_with_degrees_and_k_total_reads_back(computed, tmp_path):
    """A slots-form CSV in degrees with a k_total column (one torque row) is accepted too."""
    t = computed
    cols = [np.degrees(t.phi_rad)] + [t.k_N_per_m[0, j] for j in range(t.slots)]
    cols += [t.e_m[0, j] for j in range(t.slots)] + [t.k_total_N_per_m()[0]]
    head = (["pinion_angle_deg"] + [f"k_slot{j + 1}_N_per_m" for j in range(t.slots)]
            + [f"e_slot{j + 1}_m" for j in range(t.slots)] + ["k_total_N_per_m"])
    np.savetxt(tmp_path / "cli.csv", np.column_stack(cols), delimiter=",", header=",".join(head), comments="")
    _, meta = tables_to_csv(computed, tmp_path / "x.csv")
    back = load_tables_csv(tmp_path / "cli.csv", meta)
    assert np.array_equal(back.k_N_per_m, computed.k_N_per_m) and np.array_equal(back.e_m, computed.e_m)


def test_single_pair_expands_to_the_rectangular_wave(tmp_path):
    """One pair of constant stiffness over eps = 1.7547 mesh periods, expanded into slots,
    is the rectangular wave of the same pair stiffness (k_double = 2 k_single)."""
    want = rectangular_wave_tables(2.5e8, points_per_mesh=64, zone_edges=True)   # the pair's own edges
    span = want.contact_ratio * want.mesh_period_rad
    a = np.linspace(0.0, np.degrees(span), 41)
    (tmp_path / "pair.csv").write_text("pinion_angle_deg,k_pair_N_per_m,e_pair_um\n"
                                       + "".join(f"{float(x)!r},2.5e8,0\n" for x in a))
    (tmp_path / "pair.toml").write_text(
        "[gear]\nteeth_pinion = 50\nteeth_gear = 50\nbase_radius_pinion_m = 0.070475\n"
        "base_radius_gear_m = 0.070475\ninertia_pinion_kgm2 = 0.0074\ninertia_gear_kgm2 = 0.0074\n"
        "[tables]\ncontact_ratio = 1.7547\npoints_per_mesh = 64\n")
    got = load_tables_csv(tmp_path / "pair.csv", tmp_path / "pair.toml")
    assert got.slots == 2 and got.n_phi == want.n_phi
    assert np.array_equal(got.k_N_per_m, want.k_N_per_m)
    assert got.engagement_in_rad == 0.0 and got.engagement_out_rad == pytest.approx(span, rel=1e-14)
    assert got.k_mean_N_per_m == pytest.approx(want.k_mean_N_per_m, rel=1e-12)
    # meshing error of the pair follows it into each slot
    (tmp_path / "pair2.csv").write_text("pinion_angle_rad,k_pair_N_per_m,e_pair_m\n0,2e8,1e-6\n"
                                        f"{float(span)!r},2e8,3e-6\n")
    got2 = load_tables_csv(tmp_path / "pair2.csv", tmp_path / "pair.toml")
    phi0 = got2.phi_rad[10]
    assert got2.e_m[0, 0, 10] == pytest.approx(1e-6 + 2e-6 * phi0 / span, rel=1e-12)
    j = 64 + 5  # slot 1's pair starts one mesh period later
    assert got2.e_m[0, 1, j] == pytest.approx(1e-6 + 2e-6 * (got2.phi_rad[j] - got2.mesh_period_rad) / span, rel=1e-12)


@pytest.mark.parametrize("text, words", [
    ("pinion_angle_deg,k_slot1_N_per_m\n0,1e8\n1,x\n", ["k_slot1_N_per_m", "line 3"]),
    ("pinion_angle_deg,k_slot1_N_per_m,foo\n0,1,2\n", ["foo"]),
    ("k_slot1_N_per_m\n1e8\n", ["pinion_angle"]),
    ("pinion_angle_deg,k_slot1_N_per_m\n0,1e8\n1.2,1e8\n2.4,1e8\n3.9,1e8\n4.8,1e8\n6.0,1e8\n", ["uniform", "line 5"]),
    ("pinion_angle_deg,k_slot1_N_per_m\n0,1e8\n1.8,-1e8\n3.6,1e8\n5.4,1e8\n7.2,1e8\n", ["negative", "line 3"]),
    ("pinion_angle_deg,k_slot1_N_per_m\n0,1e8\n1,1e8,3\n", ["line 3", "fields"]),
])
def test_bad_csv_names_column_or_row(tmp_path, text, words):
    p = tmp_path / "bad.csv"
    p.write_text(text)
    with pytest.raises(TableImportError) as exc:
        load_tables_csv(p, teeth_pinion=50, teeth_gear=50, base_radius_pinion_m=0.07, base_radius_gear_m=0.07,
                        inertia_pinion_kgm2=0.01, inertia_gear_kgm2=0.01)
    for w in words:
        assert w in str(exc.value)


def test_missing_scalar_is_named(tmp_path):
    p = tmp_path / "a.csv"
    p.write_text("pinion_angle_deg,k_slot1_N_per_m\n0,1\n")
    with pytest.raises(TableImportError, match="inertia_gear_kgm2"):
        load_tables_csv(p, **{k: v for k, v in META.items() if k != "inertia_gear_kgm2"})
    (tmp_path / "m.toml").write_text("teeth = 3\n")
    with pytest.raises(TableImportError, match="unknown key 'teeth'"):
        load_tables_csv(p, tmp_path / "m.toml")


@pytest.mark.slow
def test_cli_build_from_csv_tables(tmp_path):
    """`gearfmu build --tables F.csv --tables-meta M.toml` builds an FMU from imported tables."""
    t = rectangular_wave_tables(2.5e8, points_per_mesh=16)
    csv, meta = tables_to_csv(t, tmp_path / "rect.csv")
    out = tmp_path / "rect.fmu"
    p = subprocess.run([sys.executable, "-m", "gearfmu.cli", "build", "--tables", str(csv), "--tables-meta", str(meta),
                        "-o", str(out), "-q"], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    import fmpy

    md = fmpy.read_model_description(str(out))
    assert sum(1 for v in md.modelVariables if v.name.startswith("pair_force[")) == 2
    bad = subprocess.run([sys.executable, "-m", "gearfmu.cli", "build", "--tables", str(tmp_path / "nope.csv"),
                          "--tables-meta", str(meta), "-o", str(out)], capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "nope.csv" in bad.stderr
