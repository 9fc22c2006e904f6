"""SSP package (gearfmu.ssp): schema, content, and runs in fmpy, libcosim and ecos.

References: the SSP 1.0 XSD (shipped with pyssp-standard, an independent
reader/validator) and the standard's rule for ParameterBindings (all bindings of an
element apply, in order, a later one over an earlier one: the XSD's documentation);
three independent SSP loaders and co-simulation masters -- fmpy's SSP master
(fmpy.ssp.simulation.simulate_ssp), libcosim (Open Simulation Platform, through
libcosimpy) and ecos (through ecospy) -- each opening the package as it is written;
the same FMU run alone (a plain FMI 2 loop, no SSP) with the variant's values as start
values.  Each master's result must equal the FMU alone to round-off, for the default
system and for every variant chosen the way that master chooses one, and a variant must
change ``mesh_force`` by far more than round-off.  The FMU is built by the runtime the
scene names (``[fmu] runtime``), here the standalone one.
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
from pyssp_standard import SSP, SSV

from gearfmu.scene.reader import default_scene_path, load_scene
from gearfmu.ssp import (COMPONENT, NS, SspError, build_ssp, check_variants, fmpy_parameter_set, parse_variant,
                         ssp_from_scene)

from factories import make_tables

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

ZETA = 0.05  # the scene's damping ratio = the nominal variant (the FMU's start value)
VARIANTS = {"nominal": {"damping_ratio": ZETA}, "damping_low": {"damping_ratio": 0.01},
            "damping_high": {"damping_ratio": 0.3, "damping_model": 1},
            "loaded": {"pinion_torque": 150.0, "gear_torque": 225.0}}  # input start values (balance: x Rb2/Rb1)
#: every variant's values with the variables another variant names (gearfmu.ssp.complete_variants)
COMPLETE = {v: {"damping_ratio": ZETA, "damping_model": 0, "pinion_torque": 100.0, "gear_torque": 150.0, **x}
            for v, x in VARIANTS.items()}
H_NS = 100_000  # 1e-4 s in integer nanoseconds (libcosimpy's step size is integer ns)
N = 30  # communication steps
H = H_NS * 1e-9
OUTS = ("mesh_force", "dte", "pinion_speed", "pair_force[1]", "pair_force[2]", "load_sharing[2]")


@pytest.fixture(scope="module")
def ssp(tmp_path_factory):
    d = tmp_path_factory.mktemp("ssp")
    data = tomllib.loads(default_scene_path().read_text())
    data["fmu"].update(runtime="standalone", model_name="sspgear", damping_ratio=ZETA, stop_time_s=N * H)
    data["operating"]["torque_Nm"] = 100.0
    data["solver"]["max_step_s"] = 1e-5
    scene = load_scene(data)
    tables = make_tables()
    path = ssp_from_scene(scene, d / "gear.ssp", variants=VARIANTS, tables=tables)
    unpacked = d / "unpacked"
    zipfile.ZipFile(path).extractall(unpacked)
    fmu = unpacked / "resources" / "sspgear.fmu"
    fv = _fmu_vars(fmu)
    # the FMU's start torques: the scene's 100 N m and its static balance (Rb2/Rb1 = 1.5)
    assert (float(fv["pinion_torque"].start), float(fv["gear_torque"].start)) == (100.0, 150.0)
    assert tables.base_radius_gear_m / tables.base_radius_pinion_m == pytest.approx(1.5)
    alone = {v: run_alone(fmu, N + 1, COMPLETE[v]) for v in VARIANTS}
    return {"ssp": path, "dir": unpacked, "fmu": fmu, "scene": scene, "alone": alone}


def _fmu_vars(fmu):
    return {v.name: v for v in fmpy.read_model_description(str(fmu)).modelVariables}


def run_alone(fmu, n, start_values):
    """The FMU alone (no SSP) in a plain FMI 2 loop: ``start_values`` set before initialization,
    then ``n`` steps of H; the outputs after each step."""
    md = fmpy.read_model_description(str(fmu))
    var = {v.name: v for v in md.modelVariables}
    outs = [v.name for v in md.modelVariables if v.causality == "output"]
    unzip = fmpy.extract(str(fmu))
    s = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName="alone")
    try:
        s.instantiate()
        s.setupExperiment(startTime=0.0)
        for k, x in start_values.items():
            if var[k].type == "Integer":
                s.setInteger([var[k].valueReference], [int(x)])
            else:
                s.setReal([var[k].valueReference], [float(x)])
        s.enterInitializationMode()
        s.exitInitializationMode()
        rows, t = [], 0.0
        for _ in range(n):
            s.doStep(t, H)
            t += H
            rows.append(s.getReal([var[o].valueReference for o in outs]))
        s.terminate()
        s.freeInstance()
    finally:
        shutil.rmtree(unzip, ignore_errors=True)
    return {o: np.array([r[i] for r in rows]) for i, o in enumerate(outs)}


def _equal_to_alone(ssp, variant, got, what, rel=0.0):
    """``got`` ({output: values after step 1, 2, ...}) equals the FMU alone with the variant's
    values, to ``rel`` of each signal's range (0: bit for bit); the slots add up to the mesh force."""
    ref = ssp["alone"][variant]
    for name in OUTS:
        g = np.asarray(got[name])
        scale = np.ptp(ref[name][:len(g)]) or 1.0
        np.testing.assert_allclose(g, ref[name][:len(g)], rtol=0, atol=rel * scale, err_msg=f"{what} {variant} {name}")
    np.testing.assert_allclose(np.asarray(got["pair_force[1]"]) + np.asarray(got["pair_force[2]"]),
                               got["mesh_force"], rtol=1e-12, atol=1e-9)


def _variants_differ(force):
    """Choosing a variant changes the result far beyond round-off."""
    for v in ("damping_low", "damping_high", "loaded"):
        d = np.max(np.abs(np.asarray(force[v]) - np.asarray(force["nominal"])))
        assert d > 0.01 * np.ptp(force["nominal"]), (v, d)


def test_archive_contents_and_schema(ssp):
    names = set(zipfile.ZipFile(ssp["ssp"]).namelist())
    ssds = {"SystemStructure", *VARIANTS}
    assert names == {f"{n}.ssd" for n in ssds} | {"resources/sspgear.fmu"} | {f"resources/{v}.ssv" for v in VARIANTS}
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
            ssvs[f.stem] = x
    # one parameter set per variant, named after it, with the FMU's variable names; every set names
    # every variable a variant sets, so that any set applied over another gives that set
    assert set(ssvs) == set(VARIANTS)
    for v, x in ssvs.items():
        root = ET.parse(ssp["dir"] / "resources" / f"{v}.ssv").getroot()
        assert root.get("name") == v
        got = {p["name"]: float(p["type_value"].parameter["value"]) for p in x.parameters}
        assert got == COMPLETE[v], v


def _bindings(ssd):
    root = ET.parse(ssd).getroot()
    system = root.find("ssd:System", NS)
    comps = system.findall("ssd:Elements/ssd:Component", NS)
    assert len(comps) == 1 and comps[0].get("name") == COMPONENT
    assert comps[0].get("source") == "resources/sspgear.fmu"
    # the form every engine opens: nothing connects to the system, no binding on it
    assert system.find("ssd:Connectors", NS) is None and system.find("ssd:Connections", NS) is None
    assert system.find("ssd:ParameterBindings", NS) is None
    return comps[0], [b.get("source") for b in comps[0].findall("ssd:ParameterBindings/ssd:ParameterBinding", NS)]


def test_every_ssd_binds_its_sets_on_the_component_and_the_default_ends_with_the_first(ssp):
    """<variant>.ssd binds the variant's set alone; SystemStructure.ssd binds every set, the first
    one first (the set an engine that reads the first binding takes) and again last: applied in
    order, as SSP 1.0 prescribes, its bindings give the first variant's values."""
    order = list(VARIANTS)
    for v in order:
        assert _bindings(ssp["dir"] / f"{v}.ssd")[1] == [f"resources/{v}.ssv"]
    comp, sources = _bindings(ssp["dir"] / "SystemStructure.ssd")
    assert sources == [f"resources/{v}.ssv" for v in [order[0], *order[1:], order[0]]]
    applied = {}
    for src in sources:  # the standard's rule, read from the files
        for par in ET.parse(ssp["dir"] / src).getroot().findall("ssv:Parameters/ssv:Parameter", NS):
            applied[par.get("name")] = float(next(iter(par)).get("value"))
    assert applied == COMPLETE[order[0]]
    # every FMU output is a connector of the component by its full name (pair_force[1], ...)
    fv = _fmu_vars(ssp["fmu"])
    conns = {c.get("name"): c.get("kind") for c in comp.findall("ssd:Connectors/ssd:Connector", NS)}
    assert conns == {n: "output" for n, v in fv.items() if v.causality == "output"}
    assert {"pair_force[1]", "pair_force[2]", "load_sharing[1]", "load_sharing[2]"} <= set(conns)


def test_fmpy_runs_the_package_as_is_and_every_variant(ssp):
    """fmpy's SSP master reads SystemStructure.ssd and applies no binding: as is it runs the FMU
    with its start values (the nominal variant); a variant is its parameter set passed as
    parameter_set (gearfmu.ssp.fmpy_parameter_set: the .ssv with the system's names gear.<v>).
    fmpy's row k holds the outputs after step k + 1."""
    got = {v: simulate_ssp(str(ssp["ssp"]), stop_time=N * H, step_size=H,
                           parameter_set=fmpy_parameter_set(ssp["ssp"], v)) for v in VARIANTS}
    default = simulate_ssp(str(ssp["ssp"]), stop_time=N * H, step_size=H)
    for v, res in [("nominal", default), *got.items()]:
        assert len(res) >= N
        _equal_to_alone(ssp, v, {n: res[f"{COMPONENT}.{n}"] for n in OUTS}, "fmpy")
    _variants_differ({v: res[f"{COMPONENT}.mesh_force"] for v, res in got.items()})
    with pytest.raises(SspError, match="variant"):
        fmpy_parameter_set(ssp["ssp"], "no_such")


ENGINE_RUN = """
import ctypes, json, os, sys
engine, where, jobs = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
names = %r
H_NS, N = %d, %d
res = {}
if engine == "libcosim":
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    log_output_level(CosimLogLevel.ERROR)
    for key, path in jobs.items():
        ex = CosimExecution.from_ssp_file(os.path.join(where, path), step_size=H_NS)
        obs = CosimObserver.create_last_value()
        ex.add_observer(obs)
        idx = ex.slave_index_from_instance_name("gear")
        vr = {v.name.decode(): v.reference for v in ex.slave_variables(idx)}
        rows = []
        for k in range(1, N + 1):  # one row per communication point
            ex.simulate_until(k * H_NS)
            rows.append(obs.last_real_values(idx, [vr[n] for n in names]))
        res[key] = {n: [r[i] for r in rows] for i, n in enumerate(names)}
else:  # ecos: libtbb comes from the tbb package (the test extra), loaded before ecospy's library
    ctypes.CDLL(os.path.join(sys.prefix, "lib", "libtbb.so.12"), mode=ctypes.RTLD_GLOBAL)
    from ecospy import EcosLib, EcosSimulation
    EcosLib.set_log_level("err")
    for key, parameter_set in jobs.items():
        with EcosSimulation(ssp_path=where, step_size=H_NS * 1e-9) as sim:
            sim.init(parameter_set=parameter_set)
            rows = []
            for k in range(N):
                sim.step()
                rows.append([sim.get_real("gear::" + n) for n in names])
            sim.terminate()
        res[key] = {n: [r[i] for r in rows] for i, n in enumerate(names)}
print("RESULT " + json.dumps(res))
""" % (list(OUTS), H_NS, N)


def _engine(engine, where, jobs, tmp_path):
    """Run ``jobs`` ({key: .ssd path for libcosim, or parameter-set name (None: none) for ecos})
    in a fresh process of ``engine``; {key: {output: values after each step}}."""
    script = tmp_path / "engine.py"
    script.write_text(ENGINE_RUN)
    p = subprocess.run([sys.executable, str(script), engine, str(where), json.dumps(jobs)], capture_output=True,
                       text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-800:]
    return json.loads(next(line for line in p.stdout.splitlines() if line.startswith("RESULT "))[7:])


def test_libcosim_runs_the_archive_as_is_and_every_variant(ssp, tmp_path):
    """libcosim opens the .ssp archive as is (SystemStructure.ssd: the component's first
    parameter set, nominal) and a variant as its .ssd (libcosimpy's from_ssp_file takes the .ssd
    file); each run equals the FMU alone with the variant's values to 1e-12 of the range (libcosim
    counts time in integer nanoseconds: measured 2.2e-13; fmpy and ecos agree bit for bit)."""
    jobs = {"archive": str(ssp["ssp"]), "SystemStructure": "SystemStructure.ssd",
            **{v: f"{v}.ssd" for v in VARIANTS}}
    got = _engine("libcosim", ssp["dir"], jobs, tmp_path)
    for key in ("archive", "SystemStructure"):
        _equal_to_alone(ssp, "nominal", got[key], f"libcosim {key}", rel=1e-12)
    for v in VARIANTS:
        _equal_to_alone(ssp, v, got[v], "libcosim", rel=1e-12)
    _variants_differ({v: got[v]["mesh_force"] for v in VARIANTS})


def test_ecos_runs_the_archive_as_is_and_every_variant(ssp, tmp_path):
    """ecos (ecospy) opens the .ssp archive as is; it applies a parameter set when initialization
    names it (EcosSimulation.init(parameter_set=<variant>)), and the FMU's start values (the
    nominal variant) without one; each run equals the FMU alone with the variant's values."""
    got = _engine("ecos", ssp["ssp"], {"none": None, **{v: v for v in VARIANTS}}, tmp_path)
    _equal_to_alone(ssp, "nominal", got["none"], "ecos without a parameter set")
    for v in VARIANTS:
        _equal_to_alone(ssp, v, got[v], "ecos")
    _variants_differ({v: got[v]["mesh_force"] for v in VARIANTS})


def test_fmu_outputs_reachable_by_full_name(ssp):
    """In the FMU itself each pair_force[i] / load_sharing[i] is a scalar with its own value
    reference, reachable by its full name (fmpy); the slots add up to mesh_force and the
    sharing ratios to 1 while a pair carries load (reference: the definitions, docs/fmu.md)."""
    fv = _fmu_vars(ssp["fmu"])
    slots = [n for n in fv if n.startswith(("pair_force[", "load_sharing["))]
    assert len({fv[n].valueReference for n in slots}) == len(slots) == 4
    r = fmpy.simulate_fmu(str(ssp["fmu"]), stop_time=N * H, output_interval=H, output=slots + ["mesh_force"])
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
             ({"x": {"dte": 1.0}}, "variants.x.dte"),  # an output, not a parameter or input
             ({"1bad": {"damping_ratio": 0.1}}, "'1bad'"),
             ({"SystemStructure": {"damping_ratio": 0.1}}, "SystemStructure"),
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
