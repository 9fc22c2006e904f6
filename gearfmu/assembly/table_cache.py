"""The table cache: a scene's tooth-pair tables computed once, read back by every later command.

:func:`cached_tables` wraps :func:`gearfmu.assembly.precompute.precompute_tables` (the scene-level
call of :func:`gearfmu.stages.compute_tables`, so ``gearfmu tables``, ``build``, ``simulate``,
``validate``, ``ssp`` and the FMUs of ``plan --fmu``).  The tables are kept in gearfmu's file
cache (:mod:`gearfmu.common.cache`, folder :data:`TABLE_CACHE`) under a key made of exactly
what the tables depend on:

* the arguments of ``precompute_tables`` as canonical JSON (:func:`canonical`): the gear pair
  (gears, material, deviations), the mesh options (contact model, slices, foundation), points
  per mesh, torque axis, nominal torque, slots, the thermal options and, for a lubricated
  contact model, the contact environment (speed, lubricant, roughness, slice width).  The
  executor, worker count and progress flag are left out (they do not change a number), and so
  is everything of the scene that precompute does not read: the FMU and solver settings
  (damping ratio, stop time, model name, runtime, integrator), comments and key order;
* gearfmu's version and a checksum of its physics sources (:data:`PHYSICS_PARTS`;
  :func:`gearfmu.common.cache.package_sources_sha256`), so that a code change in a development
  checkout computes again;
* the Python, numpy, scipy and numba versions.

The payload is the tables' ``.gtab`` file (zip of tables.json and tables.bin, docs/tables.md; no
pickle), so a cache entry is itself a table file.  Read back, the tables are the computed
ones bit for bit; their provenance is that of the computation (its ``created_utc`` and
``precompute.wall_s``) with the current call's scene name, scene text and versions and a
``table_cache`` note (entry, time read).  An entry that cannot be used is ignored with a
:class:`gearfmu.common.cache.CacheWarning` and computed again; a cache folder that cannot be
written costs only the next run the computation.  The folder is kept below
``$GEARFMU_TABLE_CACHE_MAX_MB`` (default :data:`DEFAULT_MAX_MB`) by removing the entries used
longest ago.  ``--no-cache`` on the command line (:func:`bypassed`) or
``GEARFMU_NO_TABLE_CACHE=1`` computes without reading or writing it.
"""
from __future__ import annotations

import contextlib
import contextvars
import dataclasses
import importlib.metadata
import math
import os
import sys
import time
import warnings
from pathlib import Path
from typing import Callable, Optional

import numpy as np

from .. import __version__
from ..common.cache import (CacheWarning, cache_dir, entry_digest, entry_path, load_entry, sources_sha256,
                            store_entry)
from ..common.progress import notice
from ..tables.mesh_tables import MeshTables, TableError

__all__ = ["TABLE_CACHE", "NO_CACHE_ENV", "MAX_MB_ENV", "DEFAULT_MAX_MB", "PHYSICS_PARTS", "bypassed",
           "cache_enabled", "canonical", "table_key", "cached_tables"]

#: folder of gearfmu's file cache holding the tables
TABLE_CACHE = "tables"
#: environment variable: "1" computes every table without the cache (as ``--no-cache``)
NO_CACHE_ENV = "GEARFMU_NO_TABLE_CACHE"
#: environment variable: largest size of the table cache folder, MB
MAX_MB_ENV = "GEARFMU_TABLE_CACHE_MAX_MB"
#: default largest size of the table cache folder, MB (the entries used longest ago go first)
DEFAULT_MAX_MB = 2000.0
#: gearfmu's sub-packages whose sources compute the tables (their checksum is part of the key)
PHYSICS_PARTS = ("assembly", "common", "contact", "ehl", "gear", "tables")
#: packages whose versions are part of the key (the numbers depend on them)
KEY_PACKAGES = ("numpy", "scipy", "numba")
#: dataclass fields that never change a table (how the work is run, not what is computed)
_RUN_FIELDS = frozenset({"executor", "max_workers", "progress"})
_PAYLOAD = ".gtab"

_bypass: contextvars.ContextVar = contextvars.ContextVar("gearfmu_table_cache_bypass", default=False)


@contextlib.contextmanager
def bypassed(on: bool = True):
    """Within the block (``on`` True) tables are computed without reading or writing the cache
    (the command line's ``--no-cache``)."""
    token = _bypass.set(bool(on) or _bypass.get())
    try:
        yield
    finally:
        _bypass.reset(token)


def cache_enabled() -> bool:
    """False inside :func:`bypassed` or with ``GEARFMU_NO_TABLE_CACHE`` set to anything but
    "" or "0"."""
    return not _bypass.get() and os.environ.get(NO_CACHE_ENV, "").strip() in ("", "0")


def canonical(obj):
    """``obj`` as plain JSON data that is equal for equal physics: dataclasses as
    ``{"__type__": module.Class, field: value, ...}`` without private fields (``_...``) and the
    run settings :data:`_RUN_FIELDS`; tuples and arrays as lists; non-finite floats as their
    repr.  Anything else raises TypeError (then the tables are computed without the cache)."""
    if obj is None or isinstance(obj, (bool, str)):
        return obj
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        f = float(obj)
        return f if math.isfinite(f) else repr(f)
    if isinstance(obj, np.ndarray):
        return {"__ndarray__": str(obj.dtype), "shape": list(obj.shape), "values": canonical(obj.tolist())}
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        out = {"__type__": f"{type(obj).__module__}.{type(obj).__qualname__}"}
        for f in dataclasses.fields(obj):
            if not f.name.startswith("_") and f.name not in _RUN_FIELDS:
                out[f.name] = canonical(getattr(obj, f.name))
        return out
    if isinstance(obj, (list, tuple)):
        return [canonical(v) for v in obj]
    if isinstance(obj, dict):
        return {str(k): canonical(v) for k, v in sorted(obj.items(), key=lambda kv: str(kv[0]))}
    raise TypeError(f"no canonical form for a {type(obj).__name__}")


def _versions() -> dict:
    out = {"gearfmu": __version__, "python": sys.version.split()[0]}
    for pkg in KEY_PACKAGES:
        try:
            out[pkg] = importlib.metadata.version(pkg)
        except importlib.metadata.PackageNotFoundError:
            out[pkg] = None
    return out


def table_key(args: dict) -> Optional[dict]:
    """The cache key of the tables of ``precompute_tables(**args)`` (module doc); None when an
    argument has no canonical form (such tables are not cached)."""
    try:
        physics = canonical(dict(args))
    except TypeError:
        return None
    return {"what": "gearfmu tooth-pair tables", "precompute": physics, "versions": _versions(),
            "gearfmu_physics_sha256": sources_sha256(PHYSICS_PARTS)}


def _max_bytes() -> float:
    try:
        return float(os.environ.get(MAX_MB_ENV, DEFAULT_MAX_MB)) * 1e6
    except ValueError:
        return DEFAULT_MAX_MB * 1e6


def _trim(folder: Path, keep: str) -> None:
    """Remove the entries used longest ago (the mtime of their head) until the folder is below
    :func:`_max_bytes`; the entry ``keep`` (a digest) stays.  Errors are ignored (another
    process may trim at the same time)."""
    try:
        heads = [(h.stat().st_mtime, h) for h in folder.glob("*.json")]
        sizes = {h: sum(f.stat().st_size for f in folder.glob(h.stem + "*")) for _, h in heads}
        total, limit = sum(sizes.values()), _max_bytes()
        for _, h in sorted(heads, key=lambda x: x[0]):
            if total <= limit:
                break
            if h.stem == keep:
                continue
            h.unlink(missing_ok=True)   # the head first: a reader then never finds a head without payload
            (folder / f"{h.stem}{_PAYLOAD}").unlink(missing_ok=True)
            total -= sizes[h]
    except OSError:
        pass


def cached_tables(compute: Callable[..., MeshTables], args: dict, provenance: dict, *, progress: bool = False,
                  use_cache: Optional[bool] = None) -> MeshTables:
    """``compute(**args, provenance=provenance, progress=progress)`` (e.g.
    :func:`gearfmu.assembly.precompute.precompute_tables`), or the same tables read from the cache
    (module doc).  ``use_cache``: None follows :func:`cache_enabled`; False computes without the
    cache; True uses it even where the environment turns it off.  ``progress``: one line on
    stderr when the tables come from the cache."""
    if use_cache is None:
        use_cache = cache_enabled()
    key = table_key(args) if use_cache else None
    if key is None:
        return compute(**args, provenance=provenance, progress=progress)
    folder = cache_dir(TABLE_CACHE)
    digest = entry_digest(key)
    hit = load_entry(folder, key, _PAYLOAD, fields={"created_utc": str, "wall_s": float})
    if hit is not None:
        meta, payload = hit
        try:
            tables = MeshTables.from_gtab(payload, str(folder / f"{digest}{_PAYLOAD}"))
        except TableError as exc:
            warnings.warn(f"gearfmu cache: ignoring the unusable entry {entry_path(folder, key)} ({exc}); "
                          "computing again", CacheWarning, stacklevel=2)
        else:
            with contextlib.suppress(OSError):
                os.utime(entry_path(folder, key))  # last use, for the trimming
            prov = dict(tables.provenance)
            prov.update(provenance)             # this call's scene (name, text) and versions
            prov["created_utc"] = meta["created_utc"]   # when the tables were computed
            prov["table_cache"] = {
                "entry": digest, "read_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
                "note": f"read from gearfmu's table cache; computed at created_utc in "
                        f"{meta['wall_s']:.3g} s"}
            notice(f"tables read from the cache (computed {meta['created_utc']} in {meta['wall_s']:.3g} s; "
                   f"--no-cache computes them again)", enabled=progress or None)
            return dataclasses.replace(tables, provenance=prov)
    t0 = time.perf_counter()
    tables = compute(**args, provenance=provenance, progress=progress)
    wall = time.perf_counter() - t0
    try:
        payload = tables.to_gtab()
    except (TypeError, ValueError):  # provenance that JSON cannot hold: keep the tables, skip the cache
        return tables
    created = tables.provenance.get("created_utc") if isinstance(tables.provenance, dict) else None
    store_entry(folder, key, {"created_utc": str(created or time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())),
                              "wall_s": round(wall, 3)}, payload, _PAYLOAD)
    _trim(folder, digest)
    return tables
