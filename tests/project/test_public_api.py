"""The public face: ``import gearfmu`` gives the user's entry points lazily, and every subpackage's
``__init__`` lists its modules and says what it exports (gearfmu/__init__.py, gearfmu/common/exports.py)."""
import doctest
import importlib
import pkgutil
import re
import subprocess
import sys

import pytest

import gearfmu

PACKAGES = sorted(m.name for m in pkgutil.iter_modules(gearfmu.__path__) if m.ispkg)
HEAVY = ("numpy", "numba", "scipy", "fmpy", "matplotlib", "pythonfmu")


def test_entry_points_resolve_to_their_owners():
    assert gearfmu.__all__ == sorted(gearfmu._ENTRY_POINTS)
    listed = dir(gearfmu)
    for name, owner in gearfmu._ENTRY_POINTS.items():
        assert name in listed
        assert getattr(gearfmu, name) is getattr(importlib.import_module(f"gearfmu.{owner}"), name), name
    # the entry points a user calls, one per command (docs/cli.md), with the drivetrain's counterparts
    for name in ("load", "compute_tables", "simulate_native", "build", "validate", "plan_scene", "modes_report",
                 "load_any", "stage_tables", "simulate_drivetrain", "build_drivetrain_fmu", "validate_drivetrain",
                 "ssp_from_scene"):
        assert callable(getattr(gearfmu, name)), name


def test_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'no_such_entry_point'"):
        gearfmu.no_such_entry_point  # noqa: B018
    assert not hasattr(gearfmu, "__wrapped__")  # introspection (doctest, inspect) sees a plain module


def test_every_module_of_the_table_is_an_attribute():
    mods = {m.name for m in pkgutil.iter_modules(gearfmu.__path__)}
    assert set(gearfmu._SUBMODULES) == mods  # the layer table names every module and package
    for name in gearfmu._SUBMODULES:
        assert re.search(rf"^(\w+/?, )*{name}\b", gearfmu.__doc__, re.M), name
        assert getattr(gearfmu, name) is importlib.import_module(f"gearfmu.{name}")


def test_import_gearfmu_loads_no_numerics():
    """The entry points load lazily: a fresh ``import gearfmu`` imports none of the heavy packages."""
    code = ("import sys, gearfmu; "
            f"print(' '.join(sorted(m for m in {HEAVY!r} if m in sys.modules)))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == ""


def test_docstring_examples_run():
    """The examples of gearfmu's docstring (load, tables, a native run whose mean mesh force carries
    the pinion torque, F Rb1 = T1) run as written."""
    res = doctest.testmod(gearfmu, optionflags=doctest.ELLIPSIS)
    assert res.attempted >= 8 and res.failed == 0


@pytest.mark.parametrize("package", PACKAGES)
def test_subpackage_face(package):
    """Every subpackage's __init__: a module table naming each of its modules, a paragraph saying what
    it exports, and ``__all__`` whose names resolve (no exported name shadows a module; a lazily
    exported name is named in that paragraph)."""
    pkg = importlib.import_module(f"gearfmu.{package}")
    doc = pkg.__doc__ or ""
    modules = {m.name for m in pkgutil.iter_modules(pkg.__path__)}
    missing = [m for m in sorted(modules) if not re.search(rf"^{m}/?\b", doc, re.M)]
    assert not missing, f"gearfmu/{package}/__init__.py: module table lacks {missing}"
    assert re.search(r"\bExports\b|\bPublic API\b", doc), \
        f"gearfmu/{package}/__init__.py does not say what it exports"
    assert pkg.__all__, package
    assert not set(pkg.__all__) & modules, f"gearfmu.{package} exports a name that is also one of its modules"
    for name in pkg.__all__:
        assert name in dir(pkg)
        getattr(pkg, name)
        assert name in doc or not hasattr(pkg, "_EXPORTS"), \
            f"gearfmu/{package}/__init__.py: {name} exported but not named in its docstring"
