"""The package's architecture (README "Architecture"), checked with import-linter.

The contracts live in pyproject.toml ``[tool.importlinter]``: the layers (each stage imports
only the stages below it, every top-level module or package placed), no import cycles
between sibling modules or packages, the table format, the assembly and the physics never
importing the scene, the table format never importing the physics, the FMU runtime template
importing nothing from gearfmu, and the FMU and the solvers (dynamics, gearbox, planetary)
importing neither the scene nor the physics packages (forbidden contracts: direct and indirect
imports).
import-linter builds the import graph with grimp, which also sees imports inside functions.
Each check is shown to fail on a copy of the package with a violation (an upward import, a
cycle or a forbidden import) written into it.
"""
from __future__ import annotations

import ast
import importlib.util
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from gearfmu.common import vocabulary
from gearfmu.contact.models import CONTACT_MODELS as REGISTRY

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

REPO = Path(__file__).resolve().parents[2]
PACKAGE = REPO / "gearfmu"

#: packages that may be imported inside a function (heavy and needed only by some calls);
#: gearfmu.plots loads matplotlib, gearfmu.bench scipy.integrate; gearfmu.plan is loaded by the commands that build or plan;
#: the scipy subpackages are needed only by the contact models and solvers that call them
LAZY_OK = {"fmpy", "matplotlib", "distributed", "dask", "tqdm", "pythonfmu", "pyssp_standard", "libcosimpy",
           "plots", "gearfmu.plots", "bench", "plan", "xmlschema", "scipy.optimize", "scipy.special", "scipy.integrate",
           "scipy.interpolate", "scipy.fft"}
#: the FMU runtime template runs inside the FMU, not as part of the package
NOT_PACKAGE_CODE = {PACKAGE / "fmu" / "runtime" / "gearfmu_slave.py"}

_LINT = ("import sys; sys.path.insert(0, sys.argv[1]); "
         "from importlinter.cli import lint_imports; "
         "sys.exit(lint_imports(config_filename=sys.argv[2], no_cache=True, no_logo=True))")


def _lint(root: Path):
    """Run import-linter on the gearfmu package under ``root`` (a fresh interpreter, so the
    graph is built from that copy); returns (exit code, report)."""
    res = subprocess.run([sys.executable, "-c", _LINT, str(root), str(REPO / "pyproject.toml")],
                         cwd=root, capture_output=True, text=True, timeout=300)
    return res.returncode, res.stdout + res.stderr


def _copy(tmp_path: Path) -> Path:
    shutil.copytree(PACKAGE, tmp_path / "gearfmu", ignore=shutil.ignore_patterns("__pycache__"))
    return tmp_path


def test_import_contracts_hold():
    code, report = _lint(REPO)
    assert code == 0, report
    contracts = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["importlinter"]["contracts"]
    assert f"{len(contracts)} kept, 0 broken" in report, report


def test_contracts_fail_on_an_upward_import_and_on_a_cycle(tmp_path):
    root = _copy(tmp_path)
    code, report = _lint(root)
    assert code == 0, report  # the copy itself is clean
    assert str(root) in _graph_origin(root)  # and it is the copy that is analysed

    # upward: the EHL numerics importing the native solver
    (root / "gearfmu" / "ehl" / "_offender.py").write_text("from gearfmu.dynamics import native\n")
    code, report = _lint(root)
    assert code == 1, report
    assert "Layers: every stage imports only the stages below it BROKEN" in report, report
    assert "gearfmu.ehl._offender -> gearfmu.dynamics.native" in report, report
    (root / "gearfmu" / "ehl" / "_offender.py").unlink()

    # a cycle inside one layer: hertz <- stiffness already; hertz -> stiffness closes it
    hertz = root / "gearfmu" / "gear" / "hertz.py"
    hertz.write_text(hertz.read_text() + "\n\ndef _late():\n    from gearfmu.gear import stiffness\n"
                     "    return stiffness\n")
    code, report = _lint(root)
    assert code == 1, report
    assert "No import cycles between sibling modules or packages BROKEN" in report, report
    assert "Layers: every stage imports only the stages below it KEPT" in report, report
    assert "No cycles are allowed in gearfmu.gear." in report, report


def test_contracts_fail_when_a_lower_layer_imports_the_scene_or_the_format_the_physics(tmp_path):
    root = _copy(tmp_path)
    offenders = {pkg: "from gearfmu.scene import options  # offender\n"
                 for pkg in ("tables", "assembly", "contact", "gear", "ehl")}
    for pkg, line in offenders.items():
        (root / "gearfmu" / pkg / "_offender.py").write_text(line)
    code, report = _lint(root)
    assert code == 1, report
    assert "The table format, the assembly and the physics never import the scene BROKEN" in report, report
    for pkg in offenders:
        assert f"gearfmu.{pkg}._offender -> gearfmu.scene.options" in report, report
    for pkg in offenders:
        (root / "gearfmu" / pkg / "_offender.py").unlink()

    # the format importing the physics: allowed by the layers (tables sits above contact, gear
    # and ehl), refused by its own contract
    for pkg in ("contact", "gear", "ehl"):
        (root / "gearfmu" / "tables" / f"_offender_{pkg}.py").write_text(f"from gearfmu.{pkg} import __doc__\n")
    code, report = _lint(root)
    assert code == 1, report
    assert "The table format never imports the physics BROKEN" in report, report
    assert "Layers: every stage imports only the stages below it KEPT" in report, report
    assert "The table format, the assembly and the physics never import the scene KEPT" in report, report
    for pkg in ("contact", "gear", "ehl"):
        assert f"gearfmu.tables._offender_{pkg} -> gearfmu.{pkg}" in report, report


@pytest.mark.slow
def test_following_a_scene_to_its_tables_goes_back_up_a_layer_at_most_ten_times():
    """benchmarks/layer_walk.py's measurement (a call trace; its module doc) over the table
    builder's paths (default, rough EHL, helical EHL with a temperature axis, oil-temperature
    axis), from the scene through the cost guard to the tables: at most 10 moves back up a
    layer, and none of them a lower layer reading the scene or the assembly reaching up."""
    spec = importlib.util.spec_from_file_location("gearfmu_layer_walk", REPO / "benchmarks" / "layer_walk.py")
    layer_walk = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(layer_walk)
    out = layer_walk.walk(REPO, tables_only=True)
    up = out["back_up"]
    assert out["total"]["moves_back_up_a_layer"] == len(up) <= 10, up
    assert not [u for u in up if u["from"].startswith("gearfmu.scene") or u["at"].startswith(("assembly/", "tables/"))
                or u["from"].startswith(("assembly/", "tables/"))], up
    assert out["total"]["files_entered"] > 10  # the trace followed the scene into the physics


def test_contracts_fail_when_the_fmu_runtime_imports_the_package(tmp_path):
    root = _copy(tmp_path)
    slave = root / "gearfmu" / "fmu" / "runtime" / "gearfmu_slave.py"
    slave.write_text(slave.read_text() + "\nfrom gearfmu.tables.mesh_tables import MeshTables  # noqa\n")
    code, report = _lint(root)
    assert code == 1, report
    assert "The FMU runtime imports nothing from gearfmu BROKEN" in report, report


SOLVERS = ("fmu", "dynamics", "gearbox", "planetary")


def test_the_solvers_and_the_fmu_never_import_the_scene(tmp_path):
    """Each of fmu, dynamics, gearbox and planetary made to read the scene: only the forbidden contract breaks
    (the layers allow it: the scene is below them), naming each offending import."""
    root = _copy(tmp_path)
    for pkg in SOLVERS:
        (root / "gearfmu" / pkg / "_offender.py").write_text("from gearfmu.scene import reader\n")
    code, report = _lint(root)
    assert code == 1, report
    assert "The FMU and the solvers never import the scene BROKEN" in report, report
    assert "Layers: every stage imports only the stages below it KEPT" in report, report
    for pkg in SOLVERS:
        assert f"gearfmu.{pkg}._offender -> gearfmu.scene.reader" in report, report


def test_the_solvers_and_the_fmu_never_import_the_physics(tmp_path):
    """fmu, dynamics, gearbox and planetary made to import gear, contact, ehl and gear, one each, and the
    dynamics the table assembly; and once indirectly (through a module of the tables that
    imports the gear pair): the forbidden contract breaks, naming the imports, the layers hold."""
    root = _copy(tmp_path)
    for pkg, physics in zip(SOLVERS, ("gear.geometry", "contact.models", "ehl.lubricant", "gear.planetary_set")):
        package, module = physics.split(".")
        (root / "gearfmu" / pkg / "_offender.py").write_text(f"from gearfmu.{package} import {module}\n")
    (root / "gearfmu" / "dynamics" / "_offender_assembly.py").write_text("from gearfmu.assembly import estimate\n")
    code, report = _lint(root)
    assert code == 1, report
    assert "The FMU and the solvers never import the physics packages BROKEN" in report, report
    assert "Layers: every stage imports only the stages below it KEPT" in report, report
    for pkg, physics in zip(SOLVERS, ("gear.geometry", "contact.models", "ehl.lubricant", "gear.planetary_set")):
        assert f"gearfmu.{pkg}._offender -> gearfmu.{physics}" in report, report
    assert "gearfmu.dynamics._offender_assembly -> gearfmu.assembly.estimate" in report, report
    for pkg in SOLVERS:
        (root / "gearfmu" / pkg / "_offender.py").unlink()
    (root / "gearfmu" / "dynamics" / "_offender_assembly.py").unlink()
    (root / "gearfmu" / "tables" / "_bridge.py").write_text("from gearfmu.gear import geometry\n")
    (root / "gearfmu" / "dynamics" / "_offender.py").write_text("from gearfmu.tables import _bridge\n")
    code, report = _lint(root)
    assert code == 1, report
    assert "The FMU and the solvers never import the physics packages BROKEN" in report, report
    assert "gearfmu.dynamics._offender -> gearfmu.tables._bridge" in report, report


def test_the_top_level_holds_at_most_eight_modules():
    """The top level is the front ends and the entry points; everything else lives in a package."""
    modules = sorted(p.stem for p in PACKAGE.glob("*.py") if p.stem != "__init__")
    assert len(modules) <= 8, modules
    assert modules == ["bench", "cli", "pipeline", "plots", "ssp", "stages"], modules


def test_a_new_top_level_module_must_be_placed_in_a_layer(tmp_path):
    root = _copy(tmp_path)
    (root / "gearfmu" / "unplaced.py").write_text('"""A module no layer names."""\n')
    code, report = _lint(root)
    assert code == 1, report
    assert "gearfmu.unplaced" in report, report


def _graph_origin(root: Path) -> str:
    res = subprocess.run([sys.executable, "-c", "import sys; sys.path.insert(0, sys.argv[1]); import gearfmu; "
                          "print(gearfmu.__file__)", str(root)], capture_output=True, text=True, timeout=120)
    return res.stdout


def _function_level_imports(path: Path):
    tree = ast.parse(path.read_text())
    for fn in ast.walk(tree):
        if isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
            for node in ast.walk(fn):
                if isinstance(node, ast.ImportFrom):
                    yield node, (node.module or "") if not node.level else (node.module or ".")
                elif isinstance(node, ast.Import):
                    for a in node.names:
                        yield node, a.name


def test_imports_inside_functions_only_for_heavy_optional_packages_with_a_reason():
    bad = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if path in NOT_PACKAGE_CODE:
            continue
        lines = path.read_text().splitlines()
        for node, module in _function_level_imports(path):
            root = module if module in LAZY_OK else module.split(".")[0]
            where = f"{path.relative_to(REPO)}:{node.lineno}"
            if root not in LAZY_OK:
                bad.append(f"{where}: import of {module!r} inside a function")
            elif "#" not in lines[node.lineno - 1]:
                bad.append(f"{where}: function-level import of {module!r} without its reason in a comment")
    assert not bad, "\n".join(bad)


def test_the_contact_model_registry_implements_exactly_the_vocabulary():
    assert tuple(REGISTRY) == vocabulary.CONTACT_MODELS
    lubricated = tuple(name for name, m in REGISTRY.items() if m.needs_lubricant)
    assert lubricated == vocabulary.LUBRICATED_CONTACT_MODELS


def test_every_vocabulary_is_defined_once():
    """No module but common/vocabulary.py assigns a vocabulary name at module level."""
    names = set(vocabulary.__all__)
    bad = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if path == PACKAGE / "common" / "vocabulary.py":
            continue
        for node in ast.parse(path.read_text()).body:
            targets = node.targets if isinstance(node, ast.Assign) else (
                [node.target] if isinstance(node, ast.AnnAssign) else [])
            for t in targets:
                registry = getattr(t, "id", None) == "CONTACT_MODELS" and path == PACKAGE / "contact" / "models.py"  # the implementations
                if isinstance(t, ast.Name) and t.id in names and not registry:
                    bad.append(f"{path.relative_to(REPO)}:{node.lineno}: {t.id}")
    assert not bad, "\n".join(bad)
