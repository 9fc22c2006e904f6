"""The table cache (gearfmu.assembly.table_cache): a scene's tables computed once, read back after.

References: the table builder itself (gearfmu.assembly.precompute.precompute_tables) -- a table
read from the cache must equal a fresh computation bit for bit, and the number of its calls
tells a hit from a miss; the scene text (the FMU's validation record names the scene by its
SHA-256, gearfmu.fmu.compare.check_fmu_matches).  The key must follow exactly what changes the
tables: a physics key of the scene computes again, an FMU or solver setting, a comment or the
order of keys reads the kept tables.
"""
from __future__ import annotations

import json
import pickle
import zipfile

import numpy as np
import pytest

from gearfmu import pipeline
from gearfmu.cli import main
from gearfmu.common.cache import CacheWarning
from gearfmu.scene.reader import default_scene_path, load_scene
from gearfmu.assembly import precompute, table_cache
from gearfmu.tables.mesh_tables import load_tables

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

DEFAULT = default_scene_path().read_text()
ARRAYS = ("torque_Nm", "k_N_per_m", "e_m", "backlash_half_m", "e_comprehensive_m", "static_te_m")


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """An empty table cache of this test (the suite runs with the table cache off, conftest)."""
    monkeypatch.setenv("GEARFMU_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.delenv(table_cache.NO_CACHE_ENV, raising=False)
    return tmp_path / "cache" / table_cache.TABLE_CACHE


@pytest.fixture
def computed(monkeypatch):
    """The calls of the table builder (the real one runs)."""
    calls = []
    real = precompute.precompute_tables

    def counted(*a, **k):
        calls.append(k)
        return real(*a, **k)

    monkeypatch.setattr(precompute, "precompute_tables", counted)
    return calls


@pytest.fixture
def stub_builder(monkeypatch):
    """The table builder replaced by one that returns the default scene's tables (computed once)
    and counts its calls: for the key tests, where only hit or miss matters."""
    base = precompute.precompute_tables(**_args(load_scene(DEFAULT)))
    calls = []

    def stub(*a, provenance=None, progress=False, **k):
        calls.append(k)
        return pipeline_replace(base, provenance)

    monkeypatch.setattr(precompute, "precompute_tables", stub)
    return calls


def pipeline_replace(tables, provenance):
    import dataclasses
    return dataclasses.replace(tables, provenance=dict(provenance or {}, precompute={"wall_s": 0.0}))


def _args(scene):
    return dict(pair=scene.pair, opts=scene.mesh, points_per_mesh=scene.tables.points_per_mesh,
                torque_axis_Nm=scene.operating.torque_axis_Nm(), nominal_torque_Nm=scene.operating.torque_Nm,
                slots=scene.tables.slots, thermal=scene.thermal)


def _same_arrays(a, b) -> bool:
    return all(np.array_equal(getattr(a, n), getattr(b, n)) for n in ARRAYS) and a.k_mean_N_per_m == b.k_mean_N_per_m


def test_second_computation_reads_the_kept_tables_bit_for_bit(cache, computed):
    scene = load_scene(DEFAULT)
    first = pipeline.compute_tables(scene)
    assert len(computed) == 1 and "table_cache" not in first.provenance
    second = pipeline.compute_tables(scene)
    assert len(computed) == 1, "the second call computed the tables again"
    assert _same_arrays(first, second)
    # the provenance of the computation: its creation time and wall time, plus a note
    assert second.provenance["created_utc"] == first.provenance["created_utc"]
    assert second.provenance["precompute"] == first.provenance["precompute"]
    assert "table cache" in second.provenance["table_cache"]["note"]
    # a fresh computation elsewhere gives the same numbers
    fresh = pipeline.compute_tables(scene, cache=False)
    assert len(computed) == 2 and _same_arrays(fresh, second)


def _variant(change: str) -> str:
    s = DEFAULT
    edits = {
        # physics: every one of these changes the tables' arguments
        "points_per_mesh": ("points_per_mesh = 64", "points_per_mesh = 32"),
        "torque": ("torque_Nm = 2000.0 ", "torque_Nm = 1500.0 "),
        "module": ("module_mm = 6.0", "module_mm = 6.5"),
        "deviation": ("profile_form_um = 15.0", "profile_form_um = 14.0"),
        "slices": ("slices = 44 ", "slices = 22 "),
        "youngs_modulus": ("youngs_modulus_GPa = 207.0", "youngs_modulus_GPa = 206.0"),
        "backlash": ("backlash_um = 240.0", "backlash_um = 200.0"),
        "foundation": ("foundation = true", "foundation = false"),
        "torque_points": ("torque_points = 1", "torque_points = 3\n"),
        # not the tables': FMU and solver settings, text that is no key
        "damping_ratio": ("damping_ratio = 0.05", "damping_ratio = 0.08"),
        "stop_time": ("stop_time_s = 0.05 ", "stop_time_s = 0.02 "),
        "model_name": ('model_name = "GearPairSeed000"', 'model_name = "Other"'),
        "runtime": ("# runtime: not set", 'runtime = "pythonfmu"\n#'),
        "integrator": ('integrator = "rk4_node"', 'integrator = "rk4"'),
        "comment": ("# gearfmu default scene", "# another comment\n# gearfmu default scene"),
        "scene_name": ('name = "seed000_table1"', 'name = "renamed"'),
        "hertz_speed": ("speed_rpm = 2000.0 ", "speed_rpm = 1000.0 "),   # the Hertz tables do not use it
    }
    old, new = edits[change]
    assert old in s, change
    out = s.replace(old, new)
    if change == "torque_points":
        out = out.replace("speed_rpm = 2000.0 ", "torque_range_Nm = [1000.0, 3000.0]\nspeed_rpm = 2000.0 ")
    return out


PHYSICS = ["points_per_mesh", "torque", "module", "deviation", "slices", "youngs_modulus", "backlash",
           "foundation", "torque_points"]
NOT_PHYSICS = ["damping_ratio", "stop_time", "model_name", "runtime", "integrator", "comment", "scene_name",
               "hertz_speed"]


@pytest.mark.parametrize("change", PHYSICS + NOT_PHYSICS)
def test_the_key_follows_exactly_what_changes_the_tables(cache, stub_builder, change):
    pipeline.compute_tables(load_scene(DEFAULT))
    assert len(stub_builder) == 1
    other = load_scene(_variant(change))
    tables = pipeline.compute_tables(other)
    if change in PHYSICS:
        assert len(stub_builder) == 2, f"{change}: the changed physics read the kept tables"
    else:
        assert len(stub_builder) == 1, f"{change}: a setting the tables do not depend on computed them again"
        # the tables name the scene that asked for them, not the one that computed them
        assert tables.provenance["scene_toml"] == other.text and tables.provenance["scene_name"] == other.name


def test_key_order_does_not_matter(cache, stub_builder):
    a = DEFAULT.replace("teeth = 45\nprofile_shift = 0.37", "profile_shift = 0.37\nteeth = 45")
    assert a != DEFAULT
    pipeline.compute_tables(load_scene(DEFAULT))
    pipeline.compute_tables(load_scene(a))
    assert len(stub_builder) == 1


LUBRICATED = DEFAULT.replace('contact_model = "hertz"', 'contact_model = "smooth_ehl"')


@pytest.mark.parametrize("old,new", [("speed_rpm = 2000.0 ", "speed_rpm = 1000.0 "),
                                     ("pressure_viscosity_GPa_inv = 20.0", "pressure_viscosity_GPa_inv = 18.0"),
                                     ("temperature_C = 60.0", "temperature_C = 70.0")])
def test_a_lubricated_scene_keys_its_speed_and_oil(cache, stub_builder, old, new):
    """The film stiffness depends on the entrainment speed and the oil (the contact environment)."""
    pipeline.compute_tables(load_scene(LUBRICATED))
    pipeline.compute_tables(load_scene(LUBRICATED))
    assert len(stub_builder) == 1
    pipeline.compute_tables(load_scene(LUBRICATED.replace(old, new)))
    assert len(stub_builder) == 2


def test_a_code_or_version_change_computes_again(cache, stub_builder, monkeypatch):
    pipeline.compute_tables(load_scene(DEFAULT))
    monkeypatch.setattr(table_cache, "sources_sha256", lambda parts=None: "0" * 64)
    pipeline.compute_tables(load_scene(DEFAULT))
    assert len(stub_builder) == 2
    monkeypatch.setattr(table_cache, "__version__", "0.0.0+other")
    pipeline.compute_tables(load_scene(DEFAULT))
    assert len(stub_builder) == 3


def test_the_source_checksum_covers_every_package_the_table_builder_runs():
    """The key's checksum (table_cache.PHYSICS_PARTS) covers the sources of every gearfmu package
    the table builder and the argument types it is keyed on load: a code change in any of them
    computes the tables again.  Reference: the modules a fresh interpreter has loaded after
    importing the builder, the cache and the scene's physics options (sys.modules)."""
    import subprocess
    import sys
    code = ("import sys, gearfmu.assembly.precompute, gearfmu.assembly.table_cache, gearfmu.scene.physics; "
            "print(' '.join(sorted({m.split('.')[1] for m in sys.modules if m.startswith('gearfmu.')})))")
    loaded = set(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
                 .stdout.split())
    loaded -= {"scene"}  # the scene reads the arguments; their values are in the key (canonical)
    assert {"assembly", "tables", "gear", "contact", "ehl", "common"} <= loaded
    assert loaded <= set(table_cache.PHYSICS_PARTS), loaded - set(table_cache.PHYSICS_PARTS)


def _corrupt(folder, how):
    head = next(folder.glob("*.json"))
    body = head.with_suffix(".gtab")
    if how == "not json":
        head.write_text("{ not json")
    elif how == "changed payload":
        b = bytearray(body.read_bytes())
        b[len(b) // 2] ^= 0xFF
        body.write_bytes(bytes(b))
    elif how == "payload missing":
        body.unlink()
    elif how == "other key":
        e = json.loads(head.read_text())
        e["key"]["precompute"]["points_per_mesh"] = 32
        head.write_text(json.dumps(e))
    elif how == "valid checksum, not a table file":
        import hashlib
        body.write_bytes(b"not a zip archive")
        e = json.loads(head.read_text())
        e["payload_sha256"] = hashlib.sha256(b"not a zip archive").hexdigest()
        head.write_text(json.dumps(e))


@pytest.mark.parametrize("how", ["not json", "changed payload", "payload missing", "other key",
                                 "valid checksum, not a table file"])
def test_an_unusable_entry_is_computed_again_with_a_warning(cache, computed, how):
    scene = load_scene(DEFAULT)
    first = pipeline.compute_tables(scene)
    _corrupt(cache, how)
    with pytest.warns(CacheWarning, match="ignoring the unusable entry"):
        again = pipeline.compute_tables(scene)
    assert len(computed) == 2 and _same_arrays(first, again)
    third = pipeline.compute_tables(scene)   # the entry was replaced: a hit
    assert len(computed) == 2 and _same_arrays(first, third)


def test_an_unwritable_cache_costs_only_the_computation(tmp_path, monkeypatch, computed):
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("GEARFMU_CACHE_DIR", str(blocker))
    monkeypatch.delenv(table_cache.NO_CACHE_ENV, raising=False)
    scene = load_scene(DEFAULT)
    a = pipeline.compute_tables(scene)
    b = pipeline.compute_tables(scene)
    assert len(computed) == 2 and _same_arrays(a, b)


def test_no_cache_option_and_variable_bypass_it(cache, computed, tmp_path, monkeypatch):
    scene_file = tmp_path / "s.toml"
    scene_file.write_text(DEFAULT)
    out = str(tmp_path / "t.gtab")
    assert main(["tables", str(scene_file), "-q", "-o", out, "--no-cache"]) == 0
    assert len(computed) == 1 and not cache.exists()  # nothing read, nothing written
    assert main(["tables", str(scene_file), "-q", "-o", out]) == 0
    assert len(computed) == 2 and len(list(cache.glob("*.gtab"))) == 1
    assert main(["tables", str(scene_file), "-q", "-o", out]) == 0
    assert len(computed) == 2                               # read back
    assert main(["tables", str(scene_file), "-q", "-o", out, "--no-cache"]) == 0
    assert len(computed) == 3                               # not read
    monkeypatch.setenv(table_cache.NO_CACHE_ENV, "1")
    pipeline.compute_tables(load_scene(DEFAULT))
    assert len(computed) == 4
    assert table_cache.cache_enabled() is False
    with table_cache.bypassed():
        assert pipeline.compute_tables(load_scene(DEFAULT), cache=True) is not None  # explicit True wins
    assert len(computed) == 4


def test_every_table_command_has_no_cache():
    from gearfmu.cli import make_parser
    for cmd in ("build", "tables", "simulate", "validate", "plan", "ssp"):
        args = make_parser().parse_args([cmd, "--no-cache"])
        assert args.no_cache is True, cmd


def test_entries_are_json_and_a_table_file_and_are_read_without_pickle(cache, computed, monkeypatch):
    scene = load_scene(DEFAULT)
    first = pipeline.compute_tables(scene)
    head = next(cache.glob("*.json"))
    json.loads(head.read_text())                          # plain JSON
    with zipfile.ZipFile(head.with_suffix(".gtab")) as z:  # a .gtab table file (docs/tables.md)
        assert sorted(z.namelist()) == ["tables.bin", "tables.json"]
    assert _same_arrays(load_tables(head.with_suffix(".gtab")), first)

    def refuse(*a, **k):
        raise AssertionError("pickle used")

    monkeypatch.setattr(pickle, "load", refuse)
    monkeypatch.setattr(pickle, "loads", refuse)
    monkeypatch.setattr(np, "load", refuse)
    again = pipeline.compute_tables(scene)
    assert len(computed) == 1 and _same_arrays(first, again)


def test_the_cache_is_kept_below_its_size_limit(cache, stub_builder, monkeypatch):
    """The entries used longest ago go first; the one just written stays."""
    size = None
    for i, ppm in enumerate((16, 24, 32)):
        pipeline.compute_tables(load_scene(DEFAULT.replace("points_per_mesh = 64", f"points_per_mesh = {ppm}")))
        if size is None:
            size = sum(f.stat().st_size for f in cache.iterdir())
            monkeypatch.setenv(table_cache.MAX_MB_ENV, str(2.5 * size / 1e6))  # room for two entries
    assert len(list(cache.glob("*.json"))) == 2
    pipeline.compute_tables(load_scene(DEFAULT.replace("points_per_mesh = 64", "points_per_mesh = 32")))
    assert len(stub_builder) == 3     # the newest entry was kept
    pipeline.compute_tables(load_scene(DEFAULT.replace("points_per_mesh = 64", "points_per_mesh = 16")))
    assert len(stub_builder) == 4     # the oldest one was removed


def test_an_fmu_built_from_kept_tables_names_its_own_scene(cache, computed, tmp_path):
    """Scene B differs from scene A only in the damping ratio: B's tables come from A's entry,
    but B's FMU must name B (its scene text and SHA-256) so that `validate --fmu` matches it with
    B and refuses it with A; its tables are those of A bit for bit."""
    from gearfmu.fmu.compare import FmuMismatchError, check_fmu_matches, open_fmu

    a = load_scene(DEFAULT)
    b = load_scene(DEFAULT.replace("damping_ratio = 0.05", "damping_ratio = 0.07"))
    ta = pipeline.compute_tables(a)
    res = pipeline.build(b, tmp_path / "b.fmu", runtime="pythonfmu")
    assert len(computed) == 1, "B's tables were computed again"
    assert res.tables.provenance["scene_toml"] == b.text
    fmu = open_fmu(res.fmu_path)
    check_fmu_matches(fmu, scene_text=b.text, tables=ta)
    with pytest.raises(FmuMismatchError, match="the scene changed since the build"):
        check_fmu_matches(fmu, scene_text=a.text)
    with zipfile.ZipFile(res.fmu_path) as z:
        prov = json.loads(z.read("resources/tables.json"))["provenance"]
    assert prov["scene_toml"] == b.text and "table_cache" in prov
    assert main(["validate", "-q", "--fmu", str(res.fmu_path), "--stop-time", "0.002", "--json"]
                + ["--tolerance", "1e-9"] + [_write(tmp_path / "b.toml", b.text)]) == 0


def _write(path, text) -> str:
    path.write_text(text)
    return str(path)


def test_the_planner_reads_its_configurations_tables_back(cache, monkeypatch):
    """A second plan of the same scene reads the tables of its configurations from the cache; the
    cost it records for them stays the computation's time (the planner compares costs)."""
    from gearfmu.plan import evaluator as plan_evaluator
    from gearfmu.plan.choices import choices_of
    from gearfmu.scene.envelope import accuracy_of, envelope_of

    calls = []
    real = plan_evaluator.precompute_tables

    def counted(*a, **k):
        calls.append(k)
        return real(*a, **k)

    monkeypatch.setattr(plan_evaluator, "precompute_tables", counted)
    scene = load_scene(DEFAULT)
    env, acc = envelope_of(scene), accuracy_of(scene)
    full = {n: c.full for n, c in choices_of(scene, env, acc).items()}
    tb1, dt1 = plan_evaluator.Evaluator(scene, env, acc, False).tables(full)
    tb2, dt2 = plan_evaluator.Evaluator(scene, env, acc, False).tables(full)
    assert len(calls) == 1 and _same_arrays(tb1, tb2)
    assert dt2 == tb1.provenance["precompute"]["wall_s"] and "table_cache" in tb2.provenance


def test_a_build_from_kept_tables_reports_the_computation_time(cache, tmp_path):
    """BuildResult.tables_compute_s (what `plan --fmu` compares between the planned and the full
    model) is the computation's time also when the tables were read back; tables_wall_s is the
    time this build spent on them."""
    scene = load_scene(DEFAULT)
    first = pipeline.build(scene, tmp_path / "a.fmu", runtime="pythonfmu")
    second = pipeline.build(scene, tmp_path / "b.fmu", runtime="pythonfmu")
    assert "table_cache" not in first.tables.provenance and "table_cache" in second.tables.provenance
    assert first.tables_compute_s == first.tables_wall_s
    assert second.tables_compute_s == first.tables.provenance["precompute"]["wall_s"]


def test_an_fmu_from_kept_tables_holds_no_path_of_the_build_machine(cache, computed, tmp_path):
    """An FMU is sent to other teams: no file in it may name a folder of the machine that built
    it.  The second build reads its tables from the cache; neither the cache folder nor the build
    folder may appear in any member of the FMU (before: the provenance note named the cache
    folder)."""
    scene = load_scene(DEFAULT)
    pipeline.compute_tables(scene)
    res = pipeline.build(scene, tmp_path / "kept.fmu")
    assert len(computed) == 1, "the build computed the tables again instead of reading the cache"
    machine_paths = {str(cache), str(cache.parent), str(tmp_path)}
    with zipfile.ZipFile(res.fmu_path) as z:
        for member in z.namelist():
            data = z.read(member)
            for p in machine_paths:
                assert p.encode() not in data, f"{member} names the build machine's folder {p}"
