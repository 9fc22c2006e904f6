"""What a short command loads and computes: the CLI's imports and the cached reference result of
the validation record (gearfmu.fmu.validation, gearfmu.common.cache).

References: the SSP 1.0 XSD (through xmlschema, as pyssp-standard applies it); the native solver itself (a cached reference result must be byte for byte the file a
fresh run of :func:`gearfmu.dynamics.native.simulate` writes) and Python's ``sys.modules`` (what
an import really loaded).  Speed itself is measured in benchmarks/bench_startup.py, not here.
"""
from __future__ import annotations

import dataclasses
import pathlib
import shutil
import json
import subprocess
import sys
import zipfile

import pytest

import gearfmu.fmu.validation as validation
from gearfmu.common.cache import CacheWarning, cache_dir
from gearfmu.fmu.crossbuild import host_key
from gearfmu.fmu.standalone_build import build_standalone_fmu
from gearfmu.pipeline import compute_tables, load, run_settings
from gearfmu.ssp import SspError, build_ssp, validate_ssp_dir

RECORD = f"{validation.VALIDATION_DIR}/record.json"
REFERENCE = f"{validation.VALIDATION_DIR}/reference_result.csv"

#: heavy modules that building, simulating, validating or packaging the default scene never needs
NOT_AT_STARTUP = ("scipy.optimize", "scipy.integrate", "scipy.special", "scipy.interpolate", "scipy.fft",
                  "scipy.signal", "matplotlib", "gearfmu.plan", "gearfmu.bench", "gearfmu.plots")


@pytest.mark.slow
def test_importing_the_cli_loads_no_planner_plots_or_heavy_scipy():
    code = ("import json, sys, gearfmu.cli; "
            f"print(json.dumps([m for m in {NOT_AT_STARTUP!r} if m in sys.modules]))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    assert json.loads(res.stdout) == []


@pytest.fixture(scope="module")
def default_case():
    scene = load(None)
    tables = compute_tables(scene)
    settings = dataclasses.replace(run_settings(scene, tables), integrator="rk4_kink")
    return scene, tables, settings


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("GEARFMU_CACHE_DIR", str(tmp_path / "cache"))
    return tmp_path / "cache"


@pytest.fixture
def native_runs(monkeypatch):
    """The native runs the validation record makes (a list of their keyword arguments)."""
    calls = []
    real = validation.simulate

    def counted(tables, settings=None, **kw):
        calls.append(dict(kw, settings=settings))
        return real(tables, settings, **kw)

    monkeypatch.setattr(validation, "simulate", counted)
    return calls


def _record(case, *, tables=None, stop_time_s=0.002, **changes):
    scene, t, settings = case
    return validation.validation_record(tables if tables is not None else t,
                                        dataclasses.replace(settings, stop_time_s=stop_time_s, **changes),
                                        runtime="standalone", model_identifier="gearfmu_sa_test",
                                        scene_text=scene.text, compiler="test", envelope=None)


def _without_creation_time(rec: dict) -> dict:
    out = dict(rec)
    r = json.loads(out.pop(RECORD))
    r.pop("created_utc")
    out[RECORD] = json.dumps(r, indent=1).encode()
    return out


def test_a_cache_hit_runs_no_solver_and_gives_the_same_record(default_case, cache, native_runs, tmp_path,
                                                               monkeypatch):
    first = _record(default_case)
    assert len(native_runs) == 1
    assert sorted(p.suffix for p in (cache / validation.REFERENCE_CACHE).iterdir()) == [".csv", ".json"]
    again = _record(default_case)
    assert len(native_runs) == 1  # read from the cache
    assert set(again) == set(first)
    assert again[REFERENCE] == first[REFERENCE]
    assert _without_creation_time(again) == _without_creation_time(first)  # every byte but the creation time
    # the cached file is what a fresh run of the solver writes (an empty cache elsewhere)
    monkeypatch.setenv("GEARFMU_CACHE_DIR", str(tmp_path / "other"))
    fresh = _record(default_case)
    assert len(native_runs) == 2
    assert fresh[REFERENCE] == first[REFERENCE]
    rec = json.loads(first[RECORD])
    assert rec["reference"]["rows"] == first[REFERENCE].count(b"\n") - 1 > 10


@pytest.mark.parametrize("change", ["tables", "damping_ratio", "max_step_s", "integrator", "stop_time_s",
                                    "gearfmu_version", "gearfmu_sources"])
def test_any_change_in_the_key_runs_the_solver_again(default_case, cache, native_runs, monkeypatch, change):
    scene, tables, settings = default_case
    base = _record(default_case)
    assert len(native_runs) == 1
    kw = {}
    if change == "tables":  # one stiffness value changed by one part in 1e6
        k = tables.k_N_per_m.copy()
        k.flat[k.argmax()] *= 1.000001
        kw["tables"] = dataclasses.replace(tables, k_N_per_m=k)
    elif change == "damping_ratio":
        kw["damping_ratio"] = settings.damping_ratio * 1.5
    elif change == "max_step_s":
        kw["max_step_s"] = settings.max_step_s / 2
    elif change == "integrator":
        kw["integrator"] = 0
    elif change == "stop_time_s":
        kw["stop_time_s"] = 0.003
    elif change == "gearfmu_sources":  # the solver's code changed, the version string did not
        monkeypatch.setattr(validation, "_sources_sha256", lambda: "0" * 64)
    else:
        monkeypatch.setattr(validation, "__version__", validation.__version__ + ".post1")
    changed = _record(default_case, **kw)
    assert len(native_runs) == 2, change
    if change in ("tables", "damping_ratio", "max_step_s", "stop_time_s"):  # another run, another file
        assert changed[REFERENCE] != base[REFERENCE]
    assert len(list((cache / validation.REFERENCE_CACHE).glob("*.csv"))) == 2


def test_the_sources_checksum_follows_any_change_of_a_package_source(tmp_path):
    """Reference: the definition in the docstring (path and bytes of every .py file); a copy of
    the package with one byte of the native solver changed must give another checksum, a copy
    left alone the same one."""
    pkg = pathlib.Path(validation.__file__).resolve().parents[1]
    copy = tmp_path / "gearfmu"
    shutil.copytree(pkg, copy, ignore=shutil.ignore_patterns("__pycache__"))
    same = validation.package_sources_sha256(copy)
    assert same == validation.package_sources_sha256(pkg)
    f = copy / "dynamics" / "integrators.py"
    f.write_bytes(f.read_bytes() + b"\n")
    assert validation.package_sources_sha256(copy) != same


def _corrupt(folder, how):
    head = next(folder.glob("*.json"))
    body = head.with_suffix(".csv")
    if how == "not json":
        head.write_text("{ not json")
    elif how == "other key":
        e = json.loads(head.read_text())
        e["key"]["simulate"]["damping_ratio"] = "0.5"
        head.write_text(json.dumps(e))
    elif how == "missing metadata":
        e = json.loads(head.read_text())
        del e["meta"]["rows"]
        head.write_text(json.dumps(e))
    elif how == "changed csv":
        body.write_bytes(body.read_bytes().replace(b"e-", b"e+", 1))
    elif how == "csv missing":
        body.unlink()
    elif how == "binary garbage":
        head.write_bytes(b"\xff\xfe\x00garbage")


@pytest.mark.parametrize("how", ["not json", "other key", "missing metadata", "changed csv", "csv missing",
                                 "binary garbage"])
def test_an_unusable_entry_is_ignored_with_a_warning_and_replaced(default_case, cache, native_runs, how):
    first = _record(default_case)
    _corrupt(cache / validation.REFERENCE_CACHE, how)
    with pytest.warns(CacheWarning, match="ignoring the unusable entry"):
        again = _record(default_case)
    assert len(native_runs) == 2  # computed again
    assert again[REFERENCE] == first[REFERENCE]
    third = _record(default_case)  # the entry was replaced: a hit, no warning
    assert len(native_runs) == 2
    assert third[REFERENCE] == first[REFERENCE]


def test_an_unwritable_cache_costs_only_the_computation(default_case, tmp_path, monkeypatch, native_runs):
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("GEARFMU_CACHE_DIR", str(blocker))
    assert cache_dir(validation.REFERENCE_CACHE) == blocker / validation.REFERENCE_CACHE
    a = _record(default_case)
    b = _record(default_case)
    assert len(native_runs) == 2 and a[REFERENCE] == b[REFERENCE]


@pytest.mark.slow
def test_the_ssp_schema_check_parses_each_schema_once_and_still_refuses_invalid_files(default_case, tmp_path):
    """Every .ssd and .ssv is still checked against its SSP 1.0 XSD when the parsed schema is
    reused: an attribute the XSD does not allow, in the last file of each kind, is refused."""
    scene, tables, settings = default_case
    fmu = build_standalone_fmu(tables, tmp_path / "g.fmu", platforms=(host_key(),), validation=False,
                               model_name="sspcheck", max_step_s=settings.max_step_s)
    ssp = build_ssp(fmu, tmp_path / "g.ssp", {"nominal": {"damping_ratio": 0.05}, "soft": {"damping_ratio": 0.02}})
    d = tmp_path / "unpacked"
    with zipfile.ZipFile(ssp) as z:
        z.extractall(d)
    validate_ssp_dir(d)  # as written: valid
    for rel, tag in (("resources/soft.ssv", b"<ssv:ParameterSet "), ("soft.ssd", b"<ssd:SystemStructureDescription ")):
        f = d / rel
        good = f.read_bytes()
        assert good.count(tag) == 1
        f.write_bytes(good.replace(tag, tag + b'bogus="1" '))
        with pytest.raises(SspError, match=f"^{rel}: not valid SSP 1.0"):
            validate_ssp_dir(d)
        f.write_bytes(good)
