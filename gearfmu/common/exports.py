"""A package's public names, loaded with their module on first use (PEP 562).

A package's ``__init__`` lists what it exports -- each name and the module of the package that
defines it -- without importing those modules, so that importing one module of a package does not
load the whole package, and the public names still read ``gearfmu.scene.load_scene``::

    __getattr__, __dir__ = lazy_exports(__name__, {"load_scene": "reader", "Scene": "options"})
    __all__ = [...]

No exported name may be the name of a module of the package (importing that module would
replace the attribute).  Imports nothing beyond the standard library's import machinery (``typing``
alone would double the time ``import gearfmu`` takes).
"""
from __future__ import annotations

import importlib
import sys


def lazy_exports(package: str, exports: dict[str, str], submodules: tuple[str, ...] = ()) -> tuple:
    """(``__getattr__``, ``__dir__``) of the package named ``package``: ``exports`` maps each public
    name to the module (relative to the package, "reader" or "tables.mesh_tables") that defines it;
    ``submodules`` are modules of the package that are attributes too, imported on first use."""
    exports = dict(exports)
    submodules = frozenset(submodules)

    def __getattr__(name: str):
        owner = exports.get(name)
        if owner is not None:
            value = getattr(importlib.import_module(f"{package}.{owner}"), name)
            setattr(sys.modules[package], name, value)  # later lookups find it without this function
            return value
        if name in submodules:
            return importlib.import_module(f"{package}.{name}")
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__():
        return sorted(set(vars(sys.modules[package])) | set(exports) | submodules)

    return __getattr__, __dir__
