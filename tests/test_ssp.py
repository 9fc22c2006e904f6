"""SSP package (gearfmu.ssp): schema, contents, and a run of every variant in libcosim.

References: the SSP 1.0 XSD (shipped with pyssp-standard, an independent
reader/validator); libcosim (Open Simulation Platform, through libcosimpy) as
an independent SSP loader and co-simulation master; fmpy running the same FMU
with the variant's parameter values as start values -- libcosim's result of
each variant must equal fmpy's to round-off (1e-9 of the signal range; the
communication grids differ only in floating-point round-off: libcosim steps in
integer nanoseconds).
"""
import subprocess
import sys
import zipfile

import fmpy
import numpy as np
import pytest
from pyssp_standard import SSP, SSV

from gearfmu.fmu.pythonfmu_build import build_fmu
from gearfmu.ssp import SspError, build_ssp, check_variants, parse_variant

from test_fmu import make_tables

VARIANTS = {"nominal": {"damping_ratio": 0.05}, "damping_low": {"damping_ratio": 0.01},
            "damping_high": {"damping_ratio": 0.3, "damping_model": 1}}
H_NS = 100_000  # 1e-4 s in integer nanoseconds (libcosimpy's CosimExecution.from_step_size takes integer ns)
STOP_NS = 3_000_000


@pytest.fixture(scope="module")
def ssp(tmp_path_factory):
    d = tmp_path_factory.mktemp("ssp")
    fmu = build_fmu(make_tables(), d / "gear.fmu", model_name="sspgear", damping_ratio=0.02, max_step_s=1e-5,
                    stop_time_s=0.003)
    return {"fmu": fmu, "ssp": build_ssp(fmu, d / "gear.ssp", VARIANTS), "dir": d}


def test_archive_contents_and_schema(ssp):
    names = set(zipfile.ZipFile(ssp["ssp"]).namelist())
    assert {"SystemStructure.ssd", "nominal.ssd", "damping_low.ssd", "damping_high.ssd", "resources/gear.fmu",
            "resources/nominal.ssv", "resources/damping_low.ssv", "resources/damping_high.ssv"} <= names
    with SSP(ssp["ssp"], mode="r") as s:  # pyssp-standard reads it back
        sd = s.system_structure
        sd.__check_compliance__()  # SSP 1.0 XSD
        assert sorted(s.variants) == ["SystemStructure", "damping_high", "damping_low", "nominal"]
        for v in s.variants:
            s.variants[v].__check_compliance__()
        ssvs = {}
        for f in (s.unpacked_path / "resources").glob("*.ssv"):
            x = SSV(f, mode="r")
            x.__check_compliance__()
            ssvs[f.stem] = {p["name"]: p for p in x.parameters}
    assert set(ssvs) == set(VARIANTS)
    assert ssvs["damping_high"]["damping_ratio"]["type_value"].parameter["value"] == "0.3"
    assert ssvs["damping_high"]["damping_model"]["type_value"].parameter["value"] == "1"
    # the default variant binds the first parameter set
    ssd = zipfile.ZipFile(ssp["ssp"]).read("SystemStructure.ssd").decode()
    assert 'source="resources/nominal.ssv"' in ssd and 'source="resources/gear.fmu"' in ssd


LIBCOSIM_RUN = """
import json, sys
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
from libcosimpy.CosimObserver import CosimObserver
log_output_level(CosimLogLevel.ERROR)
res = {}
for ssd in sys.argv[2:]:
    ex = CosimExecution.from_ssp_file(sys.argv[1] + "/" + ssd + ".ssd", step_size=%d)
    obs = CosimObserver.create_last_value()
    ex.add_observer(obs)
    idx = ex.slave_index_from_instance_name("gear")
    vr = {v.name.decode(): v.reference for v in ex.slave_variables(idx)}
    ex.simulate_until(%d)
    names = ["dte", "mesh_force", "pinion_speed", "damping_ratio"]
    res[ssd] = dict(zip(names, obs.last_real_values(idx, [vr[n] for n in names])))
    res[ssd]["damping_model"] = obs.last_integer_values(idx, [vr["damping_model"]])[0]
print("RESULT " + json.dumps(res))
""" % (H_NS, STOP_NS)


def test_every_variant_runs_in_libcosim_like_fmpy(ssp, tmp_path):
    d = tmp_path / "unpacked"
    zipfile.ZipFile(ssp["ssp"]).extractall(d)
    script = tmp_path / "run.py"
    script.write_text(LIBCOSIM_RUN)
    variants = ["SystemStructure", *VARIANTS]
    p = subprocess.run([sys.executable, str(script), str(d), *variants], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-800:]
    import json
    got = json.loads(next(line for line in p.stdout.splitlines() if line.startswith("RESULT "))[7:])
    dtes = {}
    for v in variants:
        params = VARIANTS["nominal" if v == "SystemStructure" else v]
        ref = fmpy.simulate_fmu(str(ssp["fmu"]), stop_time=STOP_NS * 1e-9, output_interval=H_NS * 1e-9,
                                start_values=params)
        assert got[v]["damping_ratio"] == params["damping_ratio"]
        assert got[v]["damping_model"] == params.get("damping_model", 0)
        for n in ("dte", "mesh_force", "pinion_speed"):
            rng = np.ptp(ref[n]) or abs(ref[n][-1])
            assert abs(got[v][n] - ref[n][-1]) <= 1e-9 * rng, (v, n, got[v][n], ref[n][-1])
        dtes[v] = got[v]["dte"]
    assert dtes["SystemStructure"] == dtes["nominal"]
    # the variants really differ (the parameter sets were applied)
    assert len({dtes["nominal"], dtes["damping_low"], dtes["damping_high"]}) == 3


def test_bad_variants_are_rejected_naming_them(ssp, tmp_path):
    md = fmpy.read_model_description(str(ssp["fmu"]))
    cases = [({"x": {"no_such": 1.0}}, "variants.x.no_such"),
             ({"x": {"damping_ratio": -0.1}}, "variants.x.damping_ratio"),
             ({"x": {"damping_ratio": float("nan")}}, "variants.x.damping_ratio"),
             ({"x": {"damping_model": 0.5}}, "variants.x.damping_model"),
             ({"x": {"dte": 1.0}}, "variants.x.dte"),  # an output, not a parameter
             ({"1bad": {"damping_ratio": 0.1}}, "'1bad'"),
             ({"x": {}}, "variants.x"),
             ({}, "variants")]
    for variants, needle in cases:
        with pytest.raises(SspError, match=needle.replace(".", r"\.").replace("'", "'")):
            check_variants(md, variants)
    with pytest.raises(SspError, match="out_path"):
        build_ssp(ssp["fmu"], tmp_path / "x.zip", VARIANTS)
    assert not (tmp_path / "x.zip").exists()
    assert parse_variant("hot:damping_ratio=0.1,damping_model=1") == ("hot", {"damping_ratio": 0.1, "damping_model": 1.0})
    with pytest.raises(SspError, match="--variant"):
        parse_variant("hot")


def test_cli_ssp_bad_variant_exits_2(tmp_path):
    p = subprocess.run([sys.executable, "-m", "gearfmu.cli", "ssp", str(tmp_path / "missing.toml"), "-o",
                        str(tmp_path / "x.ssp")], capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and "SCENE" in p.stderr
