"""The C of the package has no cycle: between its files, calls run one way (gearfmu/fmu/kernel,
gearfmu/fmu/standalone, gearfmu/fmu/runtime/pyshim.c).

Reference: the sources themselves, read as text.  Every function defined in a C file or
(inline) in a header is found with the file that defines it; a file that calls a function of
another file depends on it; the graph of those dependencies (Tarjan's strongly connected
components) must have no component of more than one file.  The standalone runtime's model
contract (gf_model.h, in the shape of the Modelica Reference-FMUs' include/model.h) is checked
besides: the plumbing reaches the gear model through it only, and the model includes nothing
of the plumbing.
"""
import re
from pathlib import Path

import pytest

FMU = Path(__file__).resolve().parents[2] / "gearfmu" / "fmu"
C_FOLDERS = (FMU / "kernel", FMU / "standalone", FMU / "runtime")

#: a comment or a string/character literal, matched in one pass from left to right (a "//" inside a
#: string is no comment, a quote inside a comment no string)
_COMMENT_OR_STRING = re.compile(r'(/\*.*?\*/|//[^\n]*)|("(?:\\.|[^"\\\n])*"|\'(?:\\.|[^\'\\\n])*\')', re.S)
_CALL = re.compile(r"\b([A-Za-z_]\w*)\s*\(")
_KEYWORDS = {"if", "for", "while", "switch", "return", "sizeof", "defined"}


def _code(text: str):
    """(the code without comments, strings, C++ guards and preprocessor lines, the macro bodies):
    a call written in a macro is a call of the file that defines the macro."""
    text = _COMMENT_OR_STRING.sub(lambda m: " " if m.group(1) else '""', text).replace("\\\n", " ")
    text = re.sub(r"#ifdef __cplusplus.*?#endif", "", text, flags=re.S)
    lines = text.splitlines()
    macros = " ".join(m.group(1) for ln in lines for m in [re.match(r"\s*#\s*define\s+\w+(?:\([^)]*\))?(.*)", ln)] if m)
    return "\n".join("" if ln.lstrip().startswith("#") else ln for ln in lines), macros


def _definitions_and_calls(text: str):
    """(functions defined at file level, names called inside function bodies and macros)."""
    code, macros = _code(text)
    defined, called = set(), {m.group(1) for m in _CALL.finditer(macros)}
    depth, start = 0, 0
    for i, ch in enumerate(code):
        if ch == "{":
            if depth == 0:  # a body at file level: a function if its head ends with "name(...)"
                head = code[max(code.rfind(";", 0, i), code.rfind("}", 0, i)) + 1:i]
                m = re.search(r"\b([A-Za-z_]\w*)\s*\([^()]*(?:\([^()]*\)[^()]*)*\)\s*$", head)
                if m and m.group(1) not in _KEYWORDS and "=" not in head:
                    defined.add(m.group(1))
                start = i
            depth += 1
        elif ch == "}":
            depth -= 1
            if depth == 0:
                called.update(m.group(1) for m in _CALL.finditer(code, start, i))
    return defined, called - _KEYWORDS


def call_graph(folders):
    """{file: set of files it calls a function of} over the C files and headers in ``folders``."""
    files = sorted(p for d in folders for p in d.glob("*.[ch]"))
    defs, calls = {}, {}
    for p in files:
        defs[p], calls[p] = _definitions_and_calls(p.read_text())
    owner = {}
    for p in files:
        for name in defs[p]:
            owner.setdefault(name, set()).add(p)
    return {p: {q for name in calls[p] - defs[p] for q in owner.get(name, ())} for p in files}


def cycles(graph):
    """The strongly connected components of more than one node (Tarjan)."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(x.name for x in comp))

    for v in graph:
        if v not in index:
            visit(v)
    return out


def test_the_c_files_call_each_other_one_way():
    graph = call_graph(C_FOLDERS)
    assert cycles(graph) == []
    names = {p.name for p in graph}
    assert {"gearkernel.c", "gk_stops.c", "gkfmu.c", "fmi_common.c", "gear_model.c", "fmi2_gear.c"} <= names
    # the graph sees the calls it should: the layers call the plumbing and the model, the model the kernel
    edges = {(p.name, q.name) for p, qs in graph.items() for q in qs}
    assert {("fmi2_gear.c", "fmi_common.c"), ("fmi_common.c", "gear_model.c"), ("fmi_common.c", "pyshim.c"),
            ("gear_model.c", "gkfmu.c"),
            ("gkfmu.c", "gearkernel.c"), ("gearkernel.c", "gk_stops.c"), ("gk_stops.c", "gk_zones.c")} <= edges


def test_a_call_back_from_the_model_into_the_plumbing_is_a_cycle(tmp_path):
    # the check itself: the model calling a function of the plumbing closes a cycle
    for d in C_FOLDERS:
        (tmp_path / d.name).mkdir()
        for p in d.glob("*.[ch]"):
            (tmp_path / d.name / p.name).write_text(p.read_text())
    model = tmp_path / "standalone" / "gear_model.c"
    model.write_text(model.read_text() + "\nstatic void call_back(gf_inst *c) { gf_enter_init(c); }\n")
    found = cycles(call_graph([tmp_path / d.name for d in C_FOLDERS]))
    assert found and {"fmi_common.c", "gear_model.c"} <= set(found[0]), found


@pytest.mark.parametrize("name", ["standalone/gear_model.c", "standalone/gear_model.h", "runtime/pyshim.c",
                                  "standalone/gearbox_model.c", "standalone/gearbox_model.h",
                                  "standalone/stage_model.c", "standalone/stage_model.h",
                                  "standalone/element_model.c", "standalone/element_model.h",
                                  "standalone/planetary_model.c", "standalone/planetary_model.h"])
def test_the_model_includes_the_contract_not_the_plumbing(name):
    """The models of the contract: the gear model (standalone runtime), the Python slave's
    (pythonfmu runtime, docs/fmu.md "The binary"), the gearbox model (docs/gearbox.md), and the stage and
    element models of an SSP of stage FMUs (docs/gearbox.md "The SSP of stage FMUs")."""
    text = (FMU / name).read_text()
    includes = set(re.findall(r'#include "([^"]+)"', text))
    assert "fmi_common.h" not in includes and "fmi_common.c" not in includes
    assert includes & {"gf_model.h", "gear_model.h", "gearbox_model.h", "stage_model.h", "element_model.h",
                       "planetary_model.h"}


def test_the_plumbing_reaches_the_model_through_the_contract_only():
    text = (FMU / "standalone" / "fmi_common.c").read_text() + (FMU / "standalone" / "fmi_common.h").read_text()
    includes = set(re.findall(r'#include "([^"]+)"', text))
    assert includes <= {"fmi_common.h", "gf_model.h"}, includes
    contract = (FMU / "standalone" / "gf_model.h").read_text()
    declared = set(re.findall(r"\b(gm_\w+)\s*\(", contract))
    used = _definitions_and_calls((FMU / "standalone" / "fmi_common.c").read_text())[1]
    used = {u for u in used if u.startswith("gm_")}
    assert used and used <= declared, used - declared


@pytest.mark.parametrize("v", [2, 3])
def test_the_translation_unit_includes_every_c_file_once(v):
    """fmi2_all.c / fmi3_all.c, the one file an FMU's build compiles, includes every C file of the
    binary once, in the order of a file-by-file build (gearfmu.fmu.standalone_build.file_sources)."""
    from gearfmu.fmu.standalone_build import file_sources

    text = (FMU / "standalone" / f"fmi{v}_all.c").read_text()
    assert re.findall(r'#include "(\w+\.c)"', text) == list(file_sources(v))
    assert "#define GF_API GF_UNIT_STATIC" in text and "#define GK_API GF_UNIT_STATIC" in text


@pytest.mark.parametrize("v", [2, 3])
def test_the_gearbox_unit_includes_every_c_file_once(v):
    """fmi2_gearbox_all.c / fmi3_gearbox_all.c include the pair FMU's FMI layer and plumbing unchanged, the
    gearbox model and kernel and the pair kernel's files, once each, in the order of
    gearfmu.fmu.gearbox_build.gearbox_file_sources; not the gear model or its FMU layer."""
    from gearfmu.fmu.gearbox_build import gearbox_file_sources

    text = (FMU / "standalone" / f"fmi{v}_gearbox_all.c").read_text()
    included = re.findall(r'#include "(\w+\.c)"', text)
    assert included == list(gearbox_file_sources(v))
    assert f"fmi{v}_gear.c" in included and "fmi_common.c" in included and "gb_kernel.c" in included
    assert "gear_model.c" not in included and "gkfmu.c" not in included
    assert "#define GF_API GF_UNIT_STATIC" in text and "#define GK_API GF_UNIT_STATIC" in text
    edges = {(p.name, q.name) for p, qs in call_graph(C_FOLDERS).items() for q in qs}
    assert {("gearbox_model.c", "gb_kernel.c"), ("gb_kernel.c", "gk_pair.h"), ("gearkernel.c", "gk_pair.h"),
            ("gearbox_model.c", "gf_resources.c"), ("gear_model.c", "gf_resources.c")} <= edges


@pytest.mark.parametrize("v", [2, 3])
def test_the_stage_and_element_units_include_every_c_file_once(v):
    """fmi2/3_stage_all.c: the FMI layer, the plumbing, the stage model (which includes the gearbox model, the
    one model it wraps), the reading of resources, the gearbox and pair kernel; fmi2/3_element_all.c: the FMI
    layer, the plumbing, the element model, the reading of resources -- each once; the files each build copies
    into sources/ are the ones they include."""
    from gearfmu.fmu.element_build import ELEMENT_SOURCES, ELEMENT_UNITS
    from gearfmu.fmu.gearbox_build import gearbox_file_sources
    from gearfmu.fmu.stage_build import STAGE_UNITS

    stage = re.findall(r'#include "(\w+\.c)"', STAGE_UNITS[v].read_text())
    gearbox = list(gearbox_file_sources(v))
    assert stage == [name if name != "gearbox_model.c" else "stage_model.c" for name in gearbox]
    inner = re.findall(r'#include "(\w+\.c)"', (FMU / "standalone" / "stage_model.c").read_text())
    assert inner == ["gearbox_model.c"]
    element = re.findall(r'#include "(\w+\.c)"', ELEMENT_UNITS[v].read_text())
    assert element == [f"fmi{v}_gear.c"] + [p.name for p in ELEMENT_SOURCES]
    for unit in (STAGE_UNITS[v], ELEMENT_UNITS[v]):
        text = unit.read_text()
        assert "#define GF_API GF_UNIT_STATIC" in text


@pytest.mark.parametrize("v", [2, 3])
def test_the_planetary_unit_includes_every_c_file_once(v):
    """fmi2_planetary_all.c / fmi3_planetary_all.c: the pair FMU's FMI layer and plumbing, the planetary model,
    the reading of resources, the multi-mesh behaviour it shares with the gearbox model (gf_meshes.c), the
    planetary and pair kernel files -- once each, in the order of
    gearfmu.fmu.planetary_build.planetary_file_sources; the two multi-mesh models reach their kernels only
    through gf_meshes.c's function table (no call from gf_meshes.c into a model file)."""
    from gearfmu.fmu.planetary_build import planetary_file_sources

    text = (FMU / "standalone" / f"fmi{v}_planetary_all.c").read_text()
    assert re.findall(r'#include "(\w+\.c)"', text) == list(planetary_file_sources(v))
    assert "#define GF_API GF_UNIT_STATIC" in text and "#define GK_API GF_UNIT_STATIC" in text
    edges = {(p.name, q.name) for p, qs in call_graph(C_FOLDERS).items() for q in qs}
    assert {("planetary_model.c", "pl_kernel.c"), ("planetary_model.c", "gf_meshes.c"),
            ("gearbox_model.c", "gf_meshes.c"), ("gf_meshes.c", "gf_resources.c")} <= edges
    assert not {e for e in edges if e[0] == "gf_meshes.c" and e[1] in ("planetary_model.c", "gearbox_model.c")}
