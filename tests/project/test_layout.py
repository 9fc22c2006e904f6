"""The tests are grouped by layer (tests/README.md "Layout"), and every group is on the import path.

Reference: the layout tests/README.md describes -- unit/<package> for each package of gearfmu,
integration, fmu_hosts, docs, project, and the support package of shared helpers -- and
pyproject.toml's ``pythonpath``, which must name tests/ (the shared factories and the support
package) and every other folder holding Python files (pytest's default import mode imports a test
file by its module name, which must be unique).  A test file imports support modules, never another
test file.
"""
import ast
import pathlib
import re
from collections import Counter

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

ROOT = pathlib.Path(__file__).resolve().parents[2]
TESTS = ROOT / "tests"
GROUPS = ("integration", "fmu_hosts", "docs", "project")


def test_every_test_file_is_in_a_layer_folder():
    packages = {p.name for p in (ROOT / "gearfmu").iterdir() if (p / "__init__.py").is_file()}
    for p in TESTS.rglob("test_*.py"):
        parts = p.relative_to(TESTS).parts[:-1]
        assert parts and (parts[0] in GROUPS and len(parts) == 1
                          or parts[0] == "unit" and len(parts) == 2 and parts[1] in packages), \
            f"{p.relative_to(ROOT)}: not in unit/<package>/ or one of {GROUPS} (tests/README.md)"


def test_every_test_folder_is_on_the_path_and_module_names_are_unique():
    conf = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]
    folders = {p.parent.relative_to(ROOT).as_posix() for p in TESTS.rglob("*.py")
               if p.name != "conftest.py" and not (p.parent / "__init__.py").is_file()}  # a package: from tests/
    assert set(conf["pythonpath"]) == folders | {"tests"}
    names = Counter(p.name for p in TESTS.rglob("*.py"))
    assert [n for n, c in names.items() if c > 1] == []


def test_the_readme_describes_every_folder():
    text = (TESTS / "README.md").read_text(encoding="utf-8")
    for d in sorted({p.parent for p in TESTS.rglob("test_*.py")}):
        rel = d.relative_to(TESTS).as_posix()
        assert re.search(rf"`{re.escape(rel)}/`|`unit/<package>/`", text), rel


def _imported_modules(path: pathlib.Path):
    """(line, top-level module name) of every import in a file, at any depth (function bodies too)."""
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name.split(".")[0]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            yield node.lineno, node.module.split(".")[0]


def test_no_test_file_imports_another_test_file():
    """A helper two test files share lives in a support module (tests/support/, tests/factories.py),
    never in a test file: importing a test file runs its module code and its imports in the other
    file's worker and ties the two files' fate together (tests/README.md "Layout")."""
    test_modules = {p.stem for p in TESTS.rglob("test_*.py")}
    found = [f"{p.relative_to(ROOT)}:{line} imports {name}"
             for p in sorted(TESTS.rglob("*.py")) for line, name in _imported_modules(p) if name in test_modules]
    assert not found, "test files import other test files:\n" + "\n".join(found)
