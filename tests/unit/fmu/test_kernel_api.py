"""The kernel's C functions are declared once, in gearfmu/fmu/runtime/kernel_api.py.

References (none produced by the table itself): the prototypes of the kernel's public headers
gearkernel.h and gkfmu.h (and the planetary kernel's plkernel.h), read as text, and the compiled
library's own answers (its ABI versions, its sizes, the words gkf_kernel_error gives for a status).
"""
import ctypes
import re
from pathlib import Path

import numpy as np
import pytest

from gearfmu.fmu.pythonfmu_build import compile_kernel
from gearfmu.fmu.runtime import kernel_api
from gearfmu.fmu.runtime.kernel_api import KERNEL_FUNCTIONS, PLANETARY_FUNCTIONS, KernelError, load_kernel

ROOT = Path(__file__).resolve().parents[3]
KERNEL = ROOT / "gearfmu" / "fmu" / "kernel"

#: C type of a prototype -> ctypes type of the table
_C_TYPES = {"int": ctypes.c_int, "long": ctypes.c_long, "double": ctypes.c_double, "void": None,
            "const char *": ctypes.c_char_p}


def _ctype(decl: str):
    """The ctypes type of a C parameter or result declaration (its name dropped)."""
    decl = " ".join(decl.replace("*", " * ").split())
    if decl.startswith("const char *"):
        return ctypes.c_char_p
    if "*" in decl:
        return ctypes.c_void_p
    words = decl.split()
    base = words[0] if words[0] != "const" else words[1]
    return _C_TYPES[base]


def header_prototypes(headers=("gearkernel.h", "gkfmu.h")):
    """{name: (result type, argument types)} of every function declared in the headers (gearkernel.h
    and gkfmu.h)."""
    out = {}
    for h in headers:
        text = re.sub(r"/\*.*?\*/", " ", (KERNEL / h).read_text(), flags=re.S)
        text = "\n".join(ln for ln in text.splitlines() if not ln.lstrip().startswith("#"))
        text = re.sub(r"\bGK_API\s+", "", text)  # the storage class (gearkernel.h): empty in the library
        for m in re.finditer(r"([A-Za-z_][\w \t\*]*?)\b((?:gkf?|pl)_\w+)\s*\(([^)]*)\)\s*;", text):
            params = [p.strip() for p in m.group(3).split(",")]
            args = () if params == ["void"] else tuple(_ctype(re.sub(r"\w+$", "", p).strip() or p) for p in params)
            out[m.group(2)] = (_ctype(m.group(1).strip()), args)
    return out


def test_the_table_is_the_headers():
    protos = header_prototypes()
    assert len(protos) >= 30, sorted(protos)   # the headers were read
    table = {name: (res, args) for name, res, args, _ in KERNEL_FUNCTIONS}
    assert len(table) == len(KERNEL_FUNCTIONS), "a function is declared twice"
    assert set(table) == set(protos), (sorted(set(protos) - set(table)), sorted(set(table) - set(protos)))
    for name, (res, args) in protos.items():
        assert table[name] == (res, args), name


def test_the_planetary_table_is_its_header():
    protos = header_prototypes(("plkernel.h",))
    assert len(protos) >= 25, sorted(protos)
    table = {name: (res, args) for name, res, args, _ in PLANETARY_FUNCTIONS}
    assert len(table) == len(PLANETARY_FUNCTIONS), "a function is declared twice"
    assert set(table) == set(protos), (sorted(set(protos) - set(table)), sorted(set(table) - set(protos)))
    for name, (res, args) in protos.items():
        assert table[name] == (res, args), name
    pl = re.search(r"#define PL_ABI_VERSION (\d+)", (KERNEL / "plkernel.h").read_text())
    assert int(pl.group(1)) == kernel_api.PLANETARY_ABI_VERSION


def test_the_abi_versions_are_the_headers():
    gk = re.search(r"#define GK_ABI_VERSION (\d+)", (KERNEL / "gearkernel.h").read_text())
    gkf = re.search(r"#define GKF_ABI_VERSION (\d+)", (KERNEL / "gkfmu.h").read_text())
    assert int(gk.group(1)) == kernel_api.KERNEL_ABI_VERSION
    assert int(gkf.group(1)) == kernel_api.FMU_LAYER_ABI_VERSION


@pytest.fixture(scope="module")
def lib_path(tmp_path_factory):
    return compile_kernel(tmp_path_factory.mktemp("kernel"))


def test_bind_gives_every_function_its_types(lib_path):
    lib = load_kernel(lib_path)
    for name, res, args, _ in KERNEL_FUNCTIONS:
        f = getattr(lib, name)
        assert f.restype is res and f.argtypes == list(args), name
    assert lib.gk_abi_version() == kernel_api.KERNEL_ABI_VERSION
    assert lib.gkf_abi_version() == kernel_api.FMU_LAYER_ABI_VERSION
    # a double result and double arguments pass as such: ceil(1e-3/3e-4 (1 - 1e-12)) = 4 substeps
    assert lib.gk_substeps(1e-3, 3e-4) == 4.0


def test_a_checked_binding_raises_with_the_kernels_words(lib_path):
    plain, checked = load_kernel(lib_path), load_kernel(lib_path, check=True)
    m = np.zeros(plain.gk_sizeof_model() // 8 + 2)
    tq, k, e, b = np.array([1.0]), np.ones(8), np.zeros(8), np.zeros(8)
    bad = (m.ctypes.data, 1, 8, 1, tq.ctypes.data, k.ctypes.data, e.ctypes.data, b.ctypes.data,
           -1.0, 0.05, 0.05, 1e-3, 1e-3, 1.0)   # a negative table period: GK_ERR_MODEL
    assert plain.gk_init(*bad) == 1
    with pytest.raises(KernelError) as exc:
        checked.gk_init(*bad)
    assert exc.value.status == 1 and exc.value.function == "gk_init"
    assert exc.value.words == plain.gkf_kernel_error(1).decode() == "bad table dimensions or scalars"
    good = bad[:8] + (1.0,) + bad[9:]
    assert checked.gk_init(*good) == 0   # success returns the status, as unchecked
    assert checked.gk_n_outputs(3) == plain.gk_n_outputs(3)


def test_no_other_file_declares_a_kernel_signature():
    # one table: no ctypes argtypes/restype of a gk_/gkf_ function anywhere else in the repository
    pattern = re.compile(r"\b(gkf?|pl)_\w+\.(argtypes|restype)\b")
    found = []
    for p in (*ROOT.glob("gearfmu/**/*.py"), *ROOT.glob("tests/**/*.py"), *ROOT.glob("benchmarks/*.py"),
              *ROOT.glob("examples/**/*.py")):
        if p.name != "kernel_api.py" and pattern.search(p.read_text()):
            found.append(str(p.relative_to(ROOT)))
    assert found == []
