"""The standalone FMU is strict where the FMI standard is, and documents itself.

References (none produced by the code under test):
* FMI 2.0.5 section 4.2.2 / FMI 3.0 section 4.2.1: a step starts at the time the FMU has reached
  (tc_i+1 = tc_i + hc_i); after fmi2Error the instance can only be restored, reset or freed
  (FMI 2.0.5 section 2.1.3);
* FMI 2.0.5 section 2.2.7: "On a fixed or tunable parameter fmi2Status = fmi2Discard is returned"
  when a set violates min/max;
* FMI 3.0 section 2.2.6 (arrays serialized row-major, nValues counts every element) and the
  scalar variables of an FMU built with scalar outputs: the same value references and values;
* FMI 3.0 section 2.4.5: the standard log categories logStatusWarning .. logStatusFatal, here
  described with FMI 3's status names;
* FMI 2.0 section 2.3 (documentation/_main.html), FMI 2.0.1+ and FMI 3.0 section 2.5.1.1
  (documentation/index.html); Python's html.parser reading the page.
"""
import ctypes
import html.parser
import zipfile

import fmpy
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave

from gearfmu.fmu.fmudoc import build_machine_paths
from gearfmu.fmu.standalone_build import build_standalone_fmu

from factories import make_tables
from support.fmpy_host import callbacks

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

H = 1e-4
SCENE = '# a scene with text to escape: <script>alert("x")</script> & "quotes"\n[fmu]\nmodel_name = "g"\n'


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    d = tmp_path_factory.mktemp("strict")
    t = make_tables()
    kw = dict(stop_time_s=20 * H, output_interval_s=H, max_step_s=1e-5, platforms=["x86_64-linux"],
              scene_text=SCENE)
    out = {}
    for key, v, outs in (("fmi2", 2, "array"), ("fmi3", 3, "array"), ("fmi3s", 3, "scalar")):
        p = build_standalone_fmu(t, d / f"{key}.fmu", fmi_version=v, fmi3_outputs=outs, **kw)
        z = d / key
        zipfile.ZipFile(p).extractall(z)
        md = fmpy.read_model_description(str(p))
        out[key] = {"fmu": p, "dir": z, "md": md, "vr": {v.name: v.valueReference for v in md.modelVariables}}
    return out


def _fmi2(c, log):
    fmu = FMU2Slave(guid=c["md"].guid, unzipDirectory=str(c["dir"]),
                    modelIdentifier=c["md"].coSimulation.modelIdentifier, instanceName="strict")
    fmu.instantiate(callbacks=callbacks(log), loggingOn=False)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    return fmu


def _fmi3(c, log):
    def logger(env, status, category, message):
        log.append((status, category.decode(), message.decode()))

    fmu = FMU3Slave(guid=c["md"].instantiationToken, unzipDirectory=str(c["dir"]),
                    modelIdentifier=c["md"].coSimulation.modelIdentifier, instanceName="strict")
    fmu.instantiate(logMessage=logger)
    fmu.enterInitializationMode(startTime=0.0)
    return fmu


def _status(fn, *args):
    try:
        fn(*args)
        return 0
    except FMICallException as exc:
        return exc.status


# -------------------------------------------------------------------- doStep time
def test_fmi2_step_must_start_where_the_fmu_is(fmus):
    """0.5 s reached, then a step from 0.0 s: fmi2Error with a message naming both times; the
    instance is in the error state (a further step is refused), getters still work, and restoring a
    saved FMU state continues the run as if nothing happened."""
    log = []
    fmu = _fmi2(fmus["fmi2"], log)
    fmu.exitInitializationMode()
    t = 0.0
    for _ in range(5):  # the master's own time arithmetic, t += H: round-off is the same time
        assert _status(fmu.doStep, t, H) == 0
        t += H
    saved = fmu.getFMUstate()
    after = _status(fmu.doStep, t, H), fmu.getReal([fmus["fmi2"]["vr"]["dte"]])[0]
    assert _status(fmu.doStep, 0.0, H) == 3   # fmi2Error: backwards
    assert any("currentCommunicationPoint = 0 s is not the time this FMU has reached" in m for _, m in log), log
    assert _status(fmu.doStep, t + H, H) == 3  # state error: only restore, reset, free
    assert "not allowed in state error" in log[-1][1]
    fmu.setFMUstate(saved)
    assert (_status(fmu.doStep, t, H), fmu.getReal([fmus["fmi2"]["vr"]["dte"]])[0]) == after
    assert _status(fmu.doStep, t + H + 0.5 * H, H) == 3  # ahead of the FMU's time: refused as well
    fmu.freeFMUstate(saved)
    fmu.freeInstance()


def test_fmi3_step_must_start_where_the_fmu_is(fmus):
    log = []
    fmu = _fmi3(fmus["fmi3"], log)
    fmu.exitInitializationMode()
    for k in range(5):
        fmu.doStep(k * H, H)  # the master's t = k*H: round-off against the FMU's t + H
    assert _status(fmu.doStep, 0.0, H) == 3
    assert any("fmi3DoStep: currentCommunicationPoint = 0 s" in m for _, _, m in log), log
    fmu.freeInstance()


# ------------------------------------------------------------ parameters when set
@pytest.mark.parametrize("name,value", [("damping_ratio", -0.5), ("damping_ratio", float("nan")),
                                        ("damping_model", 3), ("integrator", 4)])
def test_a_parameter_outside_its_range_is_discarded_when_set(fmus, name, value):
    """FMI 2.0.5 section 2.2.7: fmi2Discard at the set (not at the next step), a message naming the
    variable, the value and the range, and the value is not taken: a get returns the old one and
    the run goes on.  Set in initialization mode (fixed parameters can only be set there); the
    tunable damping_ratio also after it."""
    c = fmus["fmi2"]
    log = []
    fmu = _fmi2(c, log)
    vr = c["vr"][name]
    integer = name in ("damping_model", "integrator")
    get, set_ = (fmu.getInteger, fmu.setInteger) if integer else (fmu.getReal, fmu.setReal)
    before = get([vr])[0]
    assert _status(set_, [vr], [value]) == 2
    assert any(m.startswith(f"fmi2Set{'Integer' if integer else 'Real'}: {name} = ") and "is outside its range" in m
               for _, m in log), log
    assert get([vr])[0] == before
    fmu.exitInitializationMode()
    assert _status(fmu.doStep, 0.0, H) == 0
    if name == "damping_ratio":
        log.clear()
        assert _status(set_, [vr], [value]) == 2 and "is outside its range" in log[-1][1]
        assert get([vr])[0] == before and _status(fmu.doStep, H, H) == 0
    fmu.freeInstance()


def test_fmi3_parameter_outside_its_range_is_discarded_when_set(fmus):
    c = fmus["fmi3"]
    log = []
    fmu = _fmi3(c, log)
    fmu.exitInitializationMode()
    assert _status(fmu.setFloat64, [c["vr"]["damping_ratio"]], [-0.5]) == 2
    assert any("fmi3SetFloat64: damping_ratio = -0.5 is outside its range [0, inf]" in m for _, _, m in log), log
    fmu.freeInstance()


# -------------------------------------------------------------- FMI 3 outputs
def test_fmi3_scalar_outputs_for_hosts_without_arrays(fmus):
    """--fmi3-outputs scalar: pair_force_1 .. P and load_sharing_1 .. P are scalar Float64 variables
    (no Dimension) at the value references of the array FMU's elements; one get with nValues = nvr
    brings every output, equal bit for bit to the array FMU's values after the same steps."""
    a, s = fmus["fmi3"], fmus["fmi3s"]
    P = make_tables().slots
    names = [f"pair_force_{i}" for i in range(1, P + 1)] + [f"load_sharing_{i}" for i in range(1, P + 1)]
    sv = {v.name: v for v in s["md"].modelVariables}
    assert all(n in sv and not sv[n].dimensions for n in names)
    assert [sv[f"pair_force_{i}"].valueReference for i in range(1, P + 1)] == \
           [a["vr"]["pair_force"] + i for i in range(P)]
    outs = [v.valueReference for v in s["md"].modelVariables if v.causality == "output"]
    fa, fs = _fmi3(a, []), _fmi3(s, [])
    for f in (fa, fs):
        f.exitInitializationMode()
        for k in range(10):
            f.doStep(k * H, H)
    scalars = fs.getFloat64(outs, nValues=len(outs))
    arr_vrs = [v.valueReference for v in a["md"].modelVariables if v.causality == "output"]
    arrays = fa.getFloat64(arr_vrs, nValues=len(outs))
    assert np.array_equal(np.array(scalars), np.array(arrays))
    fa.freeInstance()
    fs.freeInstance()


def test_fmi3_array_read_with_the_wrong_count_is_explained_at_warning_level(fmus):
    """A host without array support asks for every output reference with one value each: the get
    fails (fmi3Error) and a warning-level message names the array, its reference and its length and
    points to the scalar build."""
    c = fmus["fmi3"]
    log = []
    fmu = _fmi3(c, log)
    fmu.exitInitializationMode()
    outs = [v.valueReference for v in c["md"].modelVariables if v.causality == "output"]
    vrs = (ctypes.c_uint32 * len(outs))(*outs)
    vals = (ctypes.c_double * len(outs))()
    st = fmu.dll.fmi3GetFloat64(fmu.component, vrs, len(outs), vals, len(outs))
    assert st == 3
    warnings = [m for s, cat, m in log if s == 1 and cat == "logStatusWarning"]
    assert any(f"pair_force (value reference {c['vr']['pair_force']}) is an array of" in m and
               "--fmi3-outputs scalar" in m for m in warnings), log
    fmu.freeInstance()


def test_log_categories_name_the_fmi_version(fmus):
    for key, v in (("fmi2", 2), ("fmi3", 3)):
        cats = {c.name: c.description for c in fmus[key]["md"].logCategories}
        assert {"logStatusWarning", "logStatusDiscard", "logStatusError", "logStatusFatal"} <= set(cats)
        assert cats["logStatusWarning"] == f"Log messages with fmi{v}Warning status."
        assert not [d for d in cats.values() if f"fmi{5 - v}" in d]


# ----------------------------------------------------------------- documentation
class _Page(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.ids, self.hrefs, self.srcs, self.tags, self.text = set(), [], [], set(), []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self.tags.add(tag)
        if "id" in a:
            self.ids.add(a["id"])
        if "href" in a:
            self.hrefs.append(a["href"])
        if "src" in a:
            self.srcs.append(a["src"])

    def handle_data(self, data):
        self.text.append(data)


@pytest.mark.parametrize("key", ["fmi2", "fmi3", "fmi3s"])
def test_every_fmu_documents_itself(fmus, key):
    """documentation/index.html (FMI 2 also _main.html, the same page): every variable with its unit
    and meaning, every in-page link resolving to an anchor (the equations), no script, no external
    resource or link, the scene's text escaped, the tables' provenance, the envelope and the
    validation record; and no file of the FMU holds a path of the build machine."""
    c = fmus[key]
    doc = c["dir"] / "documentation"
    page = (doc / "index.html").read_text(encoding="utf-8")
    if key == "fmi2":
        assert (doc / "_main.html").read_text(encoding="utf-8") == page
    else:
        assert not (doc / "_main.html").exists()
    p = _Page()
    p.feed(page)
    text = "".join(p.text)
    assert "script" not in p.tags and not p.srcs and "<script>" not in page
    assert p.hrefs and all(h.startswith("#") and h[1:] in p.ids for h in p.hrefs), p.hrefs
    assert {"eq-motion", "eq-pair", "variables", "envelope", "validation"} <= p.ids
    for v in c["md"].modelVariables:
        if v.name == "time":
            continue
        assert v.name in text and (v.description or "") in text
        if v.unit:
            assert v.unit in text
    assert '<script>alert("x")</script> & "quotes"' in text   # the scene, as text
    assert "Provenance of the tables" in text and "reference_result.csv" in text and "status" in text
    assert build_machine_paths(c["dir"]) == []


def test_the_page_of_a_documented_fmu_is_the_page_of_its_fields():
    """documentation_html takes what the page documents as one DocumentedFmu or as its fields by
    keyword (the builders' call): the same bytes; both at once, or a field missing, is a
    TypeError.  The page is read back by Python's html.parser: the written names are escaped
    text, the FMI 3 page has the independent variable ``time``."""
    import dataclasses

    from gearfmu.fmu.fmudoc import DocumentedFmu, documentation_html
    from gearfmu.fmu.modeldesc import Variable

    variables = [Variable("pinion_torque", 0, "Real", "input", "continuous", None, "N.m", "pinion <torque>", 1.0,
                          None, None, None)]
    fields = dict(model_name="a<b>", model_identifier="ab", fmi_version=3, runtime="standalone",
                  generation_tool="gearfmu", variables=variables, description="d & e", tables=make_tables(),
                  parameters={"damping_ratio": 0.02}, envelope=None, scene_text=None, validation_record=None,
                  platforms_text="x86_64-linux", experiment={"start": 0.0, "stop": 0.1, "step": 1e-3})
    page = documentation_html(DocumentedFmu(**fields))
    assert page == documentation_html(**fields)
    p = _Page()
    p.feed(page.decode("utf-8"))
    text = "".join(p.text)
    assert "a<b>" in text and "pinion <torque>" in text and "Simulation time" in text and "d & e" in text
    assert page != documentation_html(dataclasses.replace(DocumentedFmu(**fields), fmi_version=2))
    with pytest.raises(TypeError):
        documentation_html(DocumentedFmu(**fields), model_name="x")
    with pytest.raises(TypeError):
        documentation_html(**{k: v for k, v in fields.items() if k != "tables"})
