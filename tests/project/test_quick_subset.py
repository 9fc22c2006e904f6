"""The quick subset, ``python -m pytest -m "not slow" -q -n 2``, stays documented and still touches
every layer.

The ``slow`` marker (pyproject.toml) takes the long tests out of the quick subset; they still run in
the full suite (README's second command, CI).  Read statically (no test is run or collected here):
a test is quick when neither it, its class nor its module (``pytestmark``) carries ``slow``.  The
quick subset must keep at least one quick test file per layer, a file counting for a layer when it
imports a module of it (the docs layer: a file that reads the pages under docs/).
"""
import ast
import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parents[2]
QUICK = 'python -m pytest -m "not slow" -q -n 2'

#: layer -> the gearfmu modules whose import makes a test file count for it
LAYERS = {
    "scene": ("gearfmu.scene",),
    "physics": ("gearfmu.gear", "gearfmu.contact", "gearfmu.ehl"),
    "tables": ("gearfmu.tables", "gearfmu.assembly"),
    "dynamics": ("gearfmu.dynamics", "gearfmu.gearbox"),
    "fmu C runtime": ("gearfmu.fmu.standalone_build", "gearfmu.fmu.gearbox_build"),
    "cli": ("gearfmu.cli",),
}


def _marked_slow(decorators) -> bool:
    for d in decorators:
        for node in ast.walk(d):
            if isinstance(node, ast.Attribute) and node.attr == "slow":
                return True
    return False


def quick_tests(path: pathlib.Path, tree=None):
    """Names of the tests of ``path`` (parsed: ``tree``) that the quick subset runs."""
    tree = tree or ast.parse(path.read_text(encoding="utf-8"))
    for node in tree.body:  # pytestmark = pytest.mark.slow (or a list holding it): the whole module
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "pytestmark" for t in node.targets) \
                and _marked_slow([node.value]):
            return []
    out = []
    for node in tree.body:
        if isinstance(node, ast.ClassDef) and node.name.startswith("Test") and not _marked_slow(node.decorator_list):
            out += [f"{node.name}.{f.name}" for f in node.body
                    if isinstance(f, ast.FunctionDef) and f.name.startswith("test") and not _marked_slow(f.decorator_list)]
        elif isinstance(node, ast.FunctionDef) and node.name.startswith("test") and not _marked_slow(node.decorator_list):
            out.append(node.name)
    return out


def imports(tree):
    """Every module the parsed file ``tree`` imports (dotted names, ``from a import b`` also as ``a.b``)."""
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            names.add(node.module)
            names.update(f"{node.module}.{a.name}" for a in node.names)
    return names


def _test_files():
    return sorted(p for p in (ROOT / "tests").rglob("test_*.py"))


def test_the_reader_finds_marks(tmp_path):
    p = tmp_path / "test_x.py"
    p.write_text("import pytest\n@pytest.mark.slow\ndef test_a(): pass\ndef test_b(): pass\n"
                 "@pytest.mark.slow\nclass TestC:\n    def test_c(self): pass\n"
                 "class TestD:\n    @pytest.mark.slow\n    def test_d(self): pass\n    def test_e(self): pass\n")
    assert quick_tests(p) == ["test_b", "TestD.test_e"]
    p.write_text("import pytest\npytestmark = [pytest.mark.slow]\ndef test_a(): pass\n")
    assert quick_tests(p) == []


def test_the_quick_subset_is_documented():
    assert re.search(r'^markers = \["slow: ', (ROOT / "pyproject.toml").read_text(), re.M)
    for page in ("README.md", "tests/README.md"):
        assert QUICK in (ROOT / page).read_text(encoding="utf-8"), page


def test_the_marker_is_used_and_every_layer_stays_in_the_quick_subset():
    text = {p: p.read_text(encoding="utf-8") for p in _test_files()}
    trees = {p: ast.parse(t) for p, t in text.items()}
    quick = {p: quick_tests(p, trees[p]) for p in text}
    assert any(not q for q in quick.values()), "no test file is marked slow"
    quick_files = [p for p in text if quick[p]]
    used = {p: imports(trees[p]) for p in quick_files}
    missing = [layer for layer, mods in LAYERS.items()
               if not any(any(m == x or m.startswith(x + ".") for m in used[p] for x in mods) for p in quick_files)]
    docs = [p for p in quick_files if p.name != pathlib.Path(__file__).name
            and re.search(r'/ "docs"|"docs" /', text[p])]
    assert docs, "no quick test file reads the pages under docs/"
    assert not missing, f"the quick subset lost the layers {missing}: keep one quick test file for each"
