"""Robustness of the FMU and the build: table format versions, integrity of
every resource file, out-of-range torque policy, non-finite substeps, and
"no valid scene crashes the build".

References: docs/tables.md (supported versions); SHA-256 (hashlib, FIPS
180-4) of the resource files; docs/model.md / docs/robustness.md for the
clamping policy, checked against the FMU run with the torque held at the end
of the axis (the tables are constant beyond the axis ends, so the two runs must
be bit-identical); the exit code of a fresh process for host crashes; scene
validity from gearfmu.scene.reader's own schema (the accepted half of the
property-based scene tests in tests/unit/scene/test_scene.py).
"""
import json
import subprocess
import sys
import textwrap
import tomllib
import zipfile

import fmpy
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gearfmu.fmu.compare import FmuMismatchError, open_fmu
from gearfmu.fmu.pythonfmu_build import build_fmu
from gearfmu.scene.reader import default_scene_path, load_scene
from gearfmu.tables.mesh_tables import TableError, load_tables

from factories import make_tables
from support.fmpy_host import Inst

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

H = 1e-4


@pytest.fixture(scope="module")
def fmu2(tmp_path_factory):
    """P = 2, torque axis [50, 150] N.m (different stiffness per row)."""
    d = tmp_path_factory.mktemp("rob")
    t = make_tables(torque=(50.0, 150.0))
    t.k_N_per_m[1] *= 1.2
    return build_fmu(t, d / "r.fmu", model_name="rob", max_step_s=1e-5, pinion_torque_start_Nm=100.0)


# ------------------------------------------------------------ table versions
@pytest.mark.parametrize("version", [0, 3, 99, "1", None, True])
def test_table_versions_other_than_1_and_2_are_rejected_naming_found_and_supported(tmp_path, version):
    meta, binary = make_tables().to_bytes()
    m = json.loads(meta)
    m["version"] = version
    d = tmp_path / "t"
    d.mkdir()
    (d / "tables.json").write_text(json.dumps(m))
    (d / "tables.bin").write_bytes(binary)
    with pytest.raises(TableError) as info:
        load_tables(d)
    msg = str(info.value)
    assert f"version {version!r} found" in msg and "[1, 2]" in msg and "tables.json" in msg


def test_table_version_1_round_trips(tmp_path):
    t = make_tables()
    back = load_tables(t.save(tmp_path / "t.gtab"))
    assert np.array_equal(back.k_N_per_m, t.k_N_per_m) and np.array_equal(back.e_m, t.e_m)


# ------------------------------------------------------------------ integrity
TAMPER_RUN = textwrap.dedent("""
    import sys, fmpy
    try:
        fmpy.simulate_fmu(sys.argv[1], stop_time=1e-3, output_interval=1e-4, debug_logging=True)
        print("RAN")
    except Exception as exc:
        print("REFUSED", exc)
""")


def _tampered(src, dst, member, change):
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w") as zout:
        names = zin.namelist()
        assert member in names, names
        for info in zin.infolist():
            data = zin.read(info.filename)
            if info.filename == member:
                data = change(data)
            zout.writestr(info, data)


TAMPERS = pytest.mark.parametrize("member,change", [
    ("resources/tables.json", lambda b: b.replace(b'"slots": 2', b'"slots":  2')),   # one byte more
    ("resources/tables.json", lambda b: b[:-5] + bytes([b[-5] ^ 1]) + b[-4:]),
    ("resources/gearkernel.so", lambda b: b[:200] + bytes([b[200] ^ 0x10]) + b[201:]),
    ("resources/gearfmu_runtime.json", lambda b: b.replace(b'"sha256": {', b'"sha256": {"extra.bin": "00", ')),
], ids=["tables.json-space", "tables.json-bitflip", "kernel-bitflip", "runtime-extra-file"])


@TAMPERS
def test_tampered_resource_refused_naming_the_file(fmu2, tmp_path, member, change):
    bad = tmp_path / "bad.fmu"
    _tampered(fmu2, bad, member, change)
    script = tmp_path / "run.py"
    script.write_text(TAMPER_RUN)
    p = subprocess.run([sys.executable, str(script), str(bad)], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr[-500:]  # the host survives
    out = p.stdout + p.stderr
    assert "REFUSED" in p.stdout
    named = "extra.bin" if "runtime" in member else member.split("/")[-1]
    assert named in out and ("checksum" in out or "missing" in out), out[-800:]


@TAMPERS
def test_tampered_resource_refused_by_gearfmu_before_fmpy_loads_it(fmu2, tmp_path, member, change):
    """gearfmu's own reader of a handed-over FMU (``open_fmu``: validate, simulate --backend fmu)
    compares every member with the SHA-256 the pythonfmu FMU records (gearfmu_runtime.json,
    provenance.json, the validation record) before fmpy extracts or loads anything."""
    bad = tmp_path / "bad.fmu"
    _tampered(fmu2, bad, member, change)
    with pytest.raises(FmuMismatchError) as info:
        open_fmu(bad)
    msg = str(info.value)
    named = "extra.bin" if "runtime" in member else member.split("/")[-1]
    assert str(bad) in msg and named in msg and ("checksum" in msg or "missing" in msg), msg
    open_fmu(fmu2)  # the intact FMU opens


# --------------------------------------------------- out-of-range torque policy
def test_torque_outside_axis_is_clamped_and_warned_once_per_excursion(fmu2):
    """Policy (docs/robustness.md): a pinion torque outside the torque axis uses
    the tables at the nearest end and logs one warning per excursion (the
    numbers are checked in the next test)."""
    sched = [100.0] * 5 + [170.0] * 5 + [100.0] * 5 + [20.0] * 5 + [200.0] * 5
    x = Inst(fmu2, "clamp")
    for i, T in enumerate(sched):
        x.set(pinion_torque=T)
        x.fmu.doStep(i * H, H)
    x.close()
    warns = [m for st_, m in x.log if st_ == 1 and "outside the tables' torque axis" in m]
    # excursions: 170 (above), 20 (below), then 200 right after 20 (still outside: no new warning)
    assert len(warns) == 2, warns
    assert "170.0" in warns[0] and "20.0" in warns[1] and "[50.0, 150.0]" in warns[0]


def test_clamped_torque_equals_end_row_tables(tmp_path):
    """Tables constant in torque beyond the end: an FMU with axis [50, 150] driven
    at 200 N.m gives bit for bit the FMU whose axis is extended to [50, 150, 250]
    with the 150 row repeated (both interpolate the same numbers; independent of
    how the kernel clamps internally, the contract is 'nearest end row')."""
    t = make_tables(torque=(50.0, 150.0))
    t.k_N_per_m[1] *= 1.2
    t3 = make_tables(torque=(50.0, 150.0, 250.0))
    t3.k_N_per_m[1] *= 1.2
    t3.k_N_per_m[2] *= 1.2
    a = build_fmu(t, tmp_path / "a.fmu", max_step_s=1e-5, pinion_torque_start_Nm=200.0)
    b = build_fmu(t3, tmp_path / "b.fmu", max_step_s=1e-5, pinion_torque_start_Nm=200.0)
    ra = fmpy.simulate_fmu(str(a), stop_time=3e-3, output_interval=H)
    rb = fmpy.simulate_fmu(str(b), stop_time=3e-3, output_interval=H)
    for n in ("dte", "mesh_force", "pinion_speed", "mesh_stiffness"):
        assert np.array_equal(ra[n], rb[n]), n
    # and the axis end really matters: at 100 N.m (inside) the stiffness differs from the 150 row
    assert np.max(ra["mesh_stiffness"]) == pytest.approx(1.2 * 2e8 * 2, rel=1e-12)


NAN_SUBSTEP = textwrap.dedent("""
    import sys, fmpy
    from fmpy.fmi2 import FMU2Slave
    path = sys.argv[1]
    md = fmpy.read_model_description(path)
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=fmpy.extract(path),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="nan")
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu.instantiate(loggingOn=True)
    fmu.setReal([vr["pinion_speed_start"]], [1e308])   # finite, but the first substep overflows
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    for H in (3.3e-4, 1e-4):
        try:
            fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=H)
            print("STEP ok")
        except Exception as exc:
            print("STEP refused", exc)
    fmu.terminate()
    fmu.freeInstance()
    print("END")
""")


def test_overflowing_substep_is_refused_not_a_segfault(fmu2, tmp_path):
    """Found by tests/fmu_hosts/fuzz_fmu.py: a finite but huge initial speed made a substep
    non-finite, and the kernel indexed its table with (int)NaN (host SIGSEGV).
    Now: fmi2Discard with the kernel's reason, host alive."""
    script = tmp_path / "nan.py"
    script.write_text(NAN_SUBSTEP)
    p = subprocess.run([sys.executable, str(script), str(fmu2)], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, (p.returncode, p.stderr[-500:])
    assert p.stdout.count("STEP refused") == 2 and "END" in p.stdout
    assert "non-finite" in p.stdout


# ------------------------------------------- no valid scene crashes the build
_BASE = tomllib.loads(default_scene_path().read_text())


@settings(max_examples=5, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(z1=st.integers(17, 40), z2=st.integers(17, 60), x1=st.floats(-0.2, 0.5), x2=st.floats(-0.2, 0.5),
       torque=st.floats(10.0, 3000.0), backlash=st.floats(0.0, 300.0), zeta=st.floats(0.0, 1.0),
       slices=st.integers(1, 4), model=st.sampled_from(["elastobacklash", "contact_zone"]))
def test_valid_scene_perturbations_build_or_fail_naming_a_key(tmp_path_factory, z1, z2, x1, x2, torque, backlash,
                                                              zeta, slices, model):
    import copy

    from gearfmu.pipeline import build

    data = copy.deepcopy(_BASE)
    g = data["gears"]
    g["pinion"]["teeth"], g["gear"]["teeth"] = z1, z2
    g["pinion"]["profile_shift"], g["gear"]["profile_shift"] = x1, x2
    for k in ("hub_radius_mm",):  # keep hubs inside the smaller roots
        g["pinion"].pop(k, None)
        g["gear"].pop(k, None)
    g["backlash_um"] = backlash
    data.setdefault("mesh", {})["slices"] = slices
    data["operating"]["torque_Nm"] = torque
    data.setdefault("tables", {})["points_per_mesh"] = 16
    data.setdefault("fmu", {})["damping_ratio"] = zeta
    data.setdefault("solver", {})["damping_model"] = model
    data["deviations"] = {}
    from gearfmu.scene.reader import SceneError, dumps_toml
    try:
        scene = load_scene(dumps_toml(data))
    except SceneError as exc:  # invalid gear pair (undercut, pointed tip, ...): rejected with key paths
        assert exc.problems and all(k for k, _ in exc.problems)
        return
    out = tmp_path_factory.mktemp("scene") / "s.fmu"
    try:
        res = build(scene, out)
    except ValueError as exc:
        text = str(exc)
        assert ":" in text and text.split(":")[0].strip(), text  # names the key / field first
        assert not out.exists()
        return
    assert res.fmu_path.is_file() and zipfile.is_zipfile(res.fmu_path)
