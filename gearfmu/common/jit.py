"""Whether numba's on-disk cache holds the compiled code of gearfmu's kernels.

gearfmu's numba functions are compiled once and kept in numba's cache (``cache=True``); the
first run after installing or updating gearfmu compiles them, which takes up to a minute per
kernel family.  :func:`cache_is_cold` tells beforehand, so that the command can say so on
stderr instead of sitting silent (:func:`gearfmu.common.progress.notice`).  It reads numba's
index of each function (numba's own cache API, as numba does before loading a function);
when that cannot be told it answers False (no notice rather than a wrong one).
"""
from __future__ import annotations

from types import ModuleType
from typing import Iterable

__all__ = ["cache_is_cold", "module_cache_is_cold"]


def _cold(dispatcher) -> bool:
    try:
        cache = dispatcher._cache
        if not getattr(cache, "_cache_file", None):   # a dispatcher without caching: nothing kept
            return False
        return not cache._cache_file._load_index()     # empty or stale (other source): compiles
    except Exception:  # noqa: BLE001 -- numba internals of another version: cannot tell
        return False


def cache_is_cold(dispatchers: Iterable) -> bool:
    """True when numba's disk cache holds no compiled code of one of ``dispatchers`` (numba
    ``@njit(cache=True)`` functions) for their current source: the next call compiles."""
    return any(_cold(d) for d in dispatchers)


def module_cache_is_cold(*modules: ModuleType) -> bool:
    """:func:`cache_is_cold` of every cached numba function defined in ``modules``."""
    found = []
    for m in modules:
        for v in vars(m).values():
            if hasattr(v, "_cache") and hasattr(v, "py_func") and getattr(v.py_func, "__module__", None) == m.__name__:
                found.append(v)
    return cache_is_cold(found)
