"""SSP package (gearfmu.ssp): schema, system connectors, variants, and runs in fmpy and libcosim.

References: the SSP 1.0 XSD (shipped with pyssp-standard, an independent
reader/validator); fmpy's SSP master (fmpy.ssp.simulation.simulate_ssp) and
libcosim (Open Simulation Platform, through libcosimpy) as independent SSP
loaders and co-simulation masters; the same FMU run alone (no SSP) with the
variant's values as start values and the same input sequence -- each master's
result must equal it to round-off, and a variant must change ``mesh_force``
by far more than round-off.  The FMU is built by the runtime the scene names
(``[fmu] runtime``), here the standalone one.
"""
import json
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile

import fmpy
import numpy as np
import pytest
from fmpy.fmi2 import FMU2Slave
from fmpy.ssp.simulation import simulate_ssp
from fmpy.ssp.ssd import read_ssv
from pyssp_standard import SSP, SSV

from gearfmu.scene.reader import default_scene_path, load_scene
from gearfmu.ssp import COMPONENT, NS, SspError, build_ssp, check_variants, parse_variant, ssp_from_scene

from test_fmu import make_tables

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

ZETA = 0.05  # the scene's damping ratio = the nominal variant (the FMU's start value)
VARIANTS = {"nominal": {"damping_ratio": ZETA}, "damping_low": {"damping_ratio": 0.01},
            "damping_high": {"damping_ratio": 0.3, "damping_model": 1}}
H_NS = 100_000  # 1e-4 s in integer nanoseconds (libcosimpy's CosimExecution.from_step_size takes integer ns)
STOP_NS = 3_000_000
H, STOP = H_NS * 1e-9, STOP_NS * 1e-9


@pytest.fixture(scope="module")
def ssp(tmp_path_factory):
    d = tmp_path_factory.mktemp("ssp")
    data = tomllib.loads(default_scene_path().read_text())
    data["fmu"].update(runtime="standalone", model_name="sspgear", damping_ratio=ZETA, stop_time_s=STOP)
    data["operating"]["torque_Nm"] = 100.0
    data["solver"]["max_step_s"] = 1e-5
    scene = load_scene(data)
    path = ssp_from_scene(scene, d / "gear.ssp", variants=VARIANTS, tables=make_tables())
    unpacked = d / "unpacked"
    zipfile.ZipFile(path).extractall(unpacked)
    return {"ssp": path, "dir": unpacked, "fmu": unpacked / "resources" / "sspgear.fmu", "scene": scene}


def _fmu_vars(fmu):
    return {v.name: v for v in fmpy.read_model_description(str(fmu)).modelVariables}


def test_archive_contents_and_schema(ssp):
    names = set(zipfile.ZipFile(ssp["ssp"]).namelist())
    ssds = {"SystemStructure", *VARIANTS, *(f"{v}_closed" for v in VARIANTS)}
    assert {f"{n}.ssd" for n in ssds} | {"resources/sspgear.fmu"} | {f"resources/{v}.ssv" for v in VARIANTS} <= names
    # the packaged FMU is the runtime the scene names
    rec = json.loads(zipfile.ZipFile(ssp["fmu"]).read("resources/validation/record.json"))
    assert rec["runtime"] == ssp["scene"].fmu.runtime == "standalone"
    with SSP(ssp["ssp"], mode="r") as s:  # pyssp-standard reads it back
        s.system_structure.__check_compliance__()  # SSP 1.0 XSD
        assert sorted(s.variants) == sorted(ssds)
        for v in s.variants:
            s.variants[v].__check_compliance__()
        ssvs = {}
        for f in (s.unpacked_path / "resources").glob("*.ssv"):
            x = SSV(f, mode="r")
            x.__check_compliance__()
            ssvs[f.stem] = {p["name"]: p for p in x.parameters}
    assert set(ssvs) == set(VARIANTS)
    # the .ssv names target the component by name (system-level hierarchical names)
    assert ssvs["damping_high"]["gear.damping_ratio"]["type_value"].parameter["value"] == "0.3"
    assert ssvs["damping_high"]["gear.damping_model"]["type_value"].parameter["value"] == "1"
    # the default (open) system binds the first parameter set at the system level
    root = ET.parse(ssp["dir"] / "SystemStructure.ssd").getroot()
    system = root.find("ssd:System", NS)
    sources = [b.get("source") for b in system.findall("ssd:ParameterBindings/ssd:ParameterBinding", NS)]
    assert "resources/nominal.ssv" in sources
    assert system.find("ssd:Elements/ssd:Component", NS).get("source") == "resources/sspgear.fmu"


def test_every_fmu_scalar_is_a_system_connector_by_its_full_name(ssp):
    """Every FMU input and output (also pair_force[i], load_sharing[i]) is a system connector of
    the same full name, wired to the component's connector of that name; inputs carry the FMU's
    start values by the system's parameter binding."""
    fv = _fmu_vars(ssp["fmu"])
    io = {n: v for n, v in fv.items() if v.causality in ("input", "output")}
    assert {"pair_force[1]", "pair_force[2]", "load_sharing[1]", "load_sharing[2]"} <= set(io)
    for ssd in ["SystemStructure", *VARIANTS]:
        system = ET.parse(ssp["dir"] / f"{ssd}.ssd").getroot().find("ssd:System", NS)
        conns = {c.get("name"): c.get("kind") for c in system.findall("ssd:Connectors/ssd:Connector", NS)}
        assert conns == {n: v.causality for n, v in io.items()}, ssd
        wires = [c.attrib for c in system.findall("ssd:Connections/ssd:Connection", NS)]
        for n, v in io.items():
            want = ({"startConnector": n, "endElement": COMPONENT, "endConnector": n} if v.causality == "input"
                    else {"startElement": COMPONENT, "startConnector": n, "endConnector": n})
            assert wires.count(want) == 1, (ssd, n)
        starts = {p.get("name"): float(p.find("ssv:Real", NS).get("value")) for p in
                  system.findall("ssd:ParameterBindings/ssd:ParameterBinding/ssd:ParameterValues/ssv:ParameterSet/"
                                 "ssv:Parameters/ssv:Parameter", NS)}
        assert starts == {n: float(v.start) for n, v in io.items() if v.causality == "input"}, ssd


def run_alone(fmu, n, params, inputs_at):
    """The FMU alone (no SSP) in a plain FMI 2 loop: ``params`` as start values, then
    ``n`` steps of H with ``inputs_at(k)`` set before step k; outputs after each step."""
    md = fmpy.read_model_description(str(fmu))
    var = {v.name: v for v in md.modelVariables}
    outs = [v.name for v in md.modelVariables if v.causality == "output"]
    unzip = fmpy.extract(str(fmu))
    s = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName="alone")
    try:
        s.instantiate()
        s.setupExperiment(startTime=0.0)
        for k, x in params.items():
            if var[k].type == "Integer":
                s.setInteger([var[k].valueReference], [int(x)])
            else:
                s.setReal([var[k].valueReference], [float(x)])
        s.enterInitializationMode()
        s.exitInitializationMode()
        rows, t = [], 0.0
        for k in range(n):
            for name, x in inputs_at(k).items():
                s.setReal([var[name].valueReference], [x])
            s.doStep(t, H)
            t += H
            rows.append(s.getReal([var[o].valueReference for o in outs]))
        s.terminate()
        s.freeInstance()
    finally:
        shutil.rmtree(unzip, ignore_errors=True)
    return {o: np.array([r[i] for r in rows]) for i, o in enumerate(outs)}


def test_fmpy_runs_the_package_and_its_variants(ssp):
    """fmpy's SSP master reads SystemStructure.ssd only; a variant is its .ssv passed as
    parameter_set, the inputs come through the system's input connectors (input=).  fmpy's
    master starts every connector at 0 and hands a connection's value on after a step, so the
    FMU sees 0 N m over the first step: the reference is the FMU alone with that input sequence."""
    fv = _fmu_vars(ssp["fmu"])
    torques = {n: float(fv[n].start) for n in ("pinion_torque", "gear_torque")}
    inputs = {n: (lambda t, x=x: x) for n, x in torques.items()}
    got = {v: simulate_ssp(str(ssp["ssp"]), stop_time=STOP, step_size=H, input=inputs,
                           parameter_set=read_ssv(str(ssp["ssp"]), resource=f"resources/{v}.ssv")) for v in VARIANTS}
    got["default"] = simulate_ssp(str(ssp["ssp"]), stop_time=STOP, step_size=H, input=inputs)
    for v, res in got.items():
        n = len(res)
        assert n >= 30
        ref = run_alone(ssp["fmu"], n, VARIANTS["nominal" if v == "default" else v],
                        lambda k: {name: (0.0 if k == 0 else x) for name, x in torques.items()})
        for name in ("mesh_force", "dte", "pinion_speed", "pair_force[1]", "load_sharing[2]"):
            scale = np.ptp(ref[name]) or 1.0
            np.testing.assert_allclose(res[name], ref[name], rtol=0, atol=1e-9 * scale, err_msg=f"{v} {name}")
            np.testing.assert_array_equal(res[name], res[f"{COMPONENT}.{name}"])  # system = component connector
        # every slot is reachable by its full name: the slots add up to the mesh force
        np.testing.assert_allclose(res["pair_force[1]"] + res["pair_force[2]"], res["mesh_force"],
                                   rtol=1e-12, atol=1e-9)
    np.testing.assert_array_equal(got["default"]["mesh_force"], got["nominal"]["mesh_force"])
    # choosing a variant changes the result (far beyond round-off)
    for v in ("damping_low", "damping_high"):
        d = np.max(np.abs(got[v]["mesh_force"] - got["nominal"]["mesh_force"]))
        assert d > 0.01 * np.ptp(got["nominal"]["mesh_force"]), (v, d)


LIBCOSIM_RUN = """
import json, sys
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
from libcosimpy.CosimObserver import CosimObserver
log_output_level(CosimLogLevel.ERROR)
res = {}
names = ["dte", "mesh_force", "pinion_speed", "damping_ratio", "pair_force[1]", "pair_force[2]"]
for ssd in sys.argv[2:]:
    ex = CosimExecution.from_ssp_file(sys.argv[1] + "/" + ssd + ".ssd", step_size=%d)
    obs = CosimObserver.create_last_value()
    ex.add_observer(obs)
    idx = ex.slave_index_from_instance_name("gear")
    vr = {v.name.decode(): v.reference for v in ex.slave_variables(idx)}
    rows = []
    for k in range(1, %d + 1):  # one row per communication point
        ex.simulate_until(k * %d)
        rows.append(obs.last_real_values(idx, [vr[n] for n in names]))
    res[ssd] = {n: [r[i] for r in rows] for i, n in enumerate(names)}
    res[ssd]["damping_model"] = obs.last_integer_values(idx, [vr["damping_model"]])[0]
print("RESULT " + json.dumps(res))
""" % (H_NS, STOP_NS // H_NS, H_NS)


def test_every_variant_runs_in_libcosim_like_the_fmu_alone(ssp, tmp_path):
    """libcosim loads each variant's closed system (<variant>_closed.ssd: it rejects connections
    to system connectors) and applies its parameter set; its outputs after 3 ms equal the FMU
    alone (fmpy.simulate_fmu, the variant's values as start values) to 1e-9 of the range."""
    script = tmp_path / "run.py"
    script.write_text(LIBCOSIM_RUN)
    ssds = [f"{v}_closed" for v in VARIANTS]
    p = subprocess.run([sys.executable, str(script), str(ssp["dir"]), *ssds], capture_output=True, text=True,
                       timeout=300)
    assert p.returncode == 0, p.stderr[-800:]
    got = json.loads(next(line for line in p.stdout.splitlines() if line.startswith("RESULT "))[7:])
    force = {}
    for v, params in VARIANTS.items():
        g = {n: np.array(x) for n, x in got[f"{v}_closed"].items()}
        ref = fmpy.simulate_fmu(str(ssp["fmu"]), stop_time=STOP, output_interval=H, start_values=params,
                                output=["dte", "mesh_force", "pinion_speed", "pair_force[1]", "pair_force[2]"])
        assert len(ref) == len(g["dte"]) + 1  # fmpy's rows start at t = 0
        assert np.all(g["damping_ratio"] == params["damping_ratio"])
        assert g["damping_model"] == params.get("damping_model", 0)
        for n in ("dte", "mesh_force", "pinion_speed", "pair_force[1]", "pair_force[2]"):
            np.testing.assert_allclose(g[n], ref[n][1:], rtol=0, atol=1e-9 * np.ptp(ref[n]), err_msg=f"{v} {n}")
        np.testing.assert_allclose(g["pair_force[1]"] + g["pair_force[2]"], g["mesh_force"], rtol=1e-12)
        force[v] = g["mesh_force"]
    # the variants really differ (the parameter sets were applied)
    for v in ("damping_low", "damping_high"):
        d = np.max(np.abs(force[v] - force["nominal"]))
        assert d > 0.01 * np.ptp(force["nominal"]), (v, d)


def test_fmu_outputs_reachable_by_full_name(ssp):
    """In the FMU itself each pair_force[i] / load_sharing[i] is a scalar with its own value
    reference, reachable by its full name (fmpy); the slots add up to mesh_force and the
    sharing ratios to 1 while a pair carries load (reference: the definitions, docs/fmu.md)."""
    fv = _fmu_vars(ssp["fmu"])
    slots = [n for n in fv if n.startswith(("pair_force[", "load_sharing["))]
    assert len({fv[n].valueReference for n in slots}) == len(slots) == 4
    r = fmpy.simulate_fmu(str(ssp["fmu"]), stop_time=STOP, output_interval=H, output=slots + ["mesh_force"])
    np.testing.assert_allclose(r["pair_force[1]"] + r["pair_force[2]"], r["mesh_force"], rtol=1e-12)
    loaded = r["mesh_force"] > 0
    assert loaded.any()
    np.testing.assert_allclose((r["load_sharing[1]"] + r["load_sharing[2]"])[loaded], 1.0, rtol=1e-12)


def test_bad_variants_are_rejected_naming_them(ssp, tmp_path):
    md = fmpy.read_model_description(str(ssp["fmu"]))
    cases = [({"x": {"no_such": 1.0}}, "variants.x.no_such"),
             ({"x": {"damping_ratio": -0.1}}, "variants.x.damping_ratio"),
             ({"x": {"damping_ratio": float("nan")}}, "variants.x.damping_ratio"),
             ({"x": {"damping_model": 0.5}}, "variants.x.damping_model"),
             ({"x": {"dte": 1.0}}, "variants.x.dte"),  # an output, not a parameter
             ({"1bad": {"damping_ratio": 0.1}}, "'1bad'"),
             ({"x": {}}, "variants.x"),
             ({"x_closed": {"damping_ratio": 0.1}}, "x_closed"),
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
