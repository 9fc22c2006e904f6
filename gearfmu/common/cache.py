"""gearfmu's file cache: results kept between runs, each under a content address.

The root is ``$GEARFMU_CACHE_DIR``, else ``$XDG_CACHE_HOME/gearfmu``, else
``~/.cache/gearfmu``; each user of the cache has a folder there (``objects``: compiled C
objects, :mod:`gearfmu.fmu.crossbuild`; ``kernels``: the pythonfmu runtime's compiled kernel,
:func:`gearfmu.fmu.pythonfmu_build.compile_kernel`; ``validation``: the native reference results of
the validation record, :mod:`gearfmu.fmu.validation`; ``tables``: the tooth-pair tables of a scene,
:mod:`gearfmu.assembly.table_cache`; ``pythons``: where the Pythons that pythonfmu FMUs were built
with are, read by those FMUs' loader, :func:`gearfmu.fmu.pythonfmu_build.record_build_python`).

An entry is two plain files named by the SHA-256 of its key (a JSON-able dict): ``<digest>.json``
(the key itself, the caller's metadata and the payload's SHA-256) and ``<digest><suffix>`` (the
payload bytes).  Both are published atomically (written beside, then renamed).  A read checks
that the stored key equals the asked one and that the payload matches its checksum; an entry
that fails a check is ignored with a :class:`CacheWarning` (the caller computes again and
overwrites it).  A cache folder that cannot be written only costs the next run the computation.
No pickle: keys and metadata are JSON.
"""
from __future__ import annotations

import functools
import hashlib
import json
import os
import warnings
from pathlib import Path
from typing import Dict, Optional, Sequence, Tuple

__all__ = ["CacheWarning", "cache_root", "cache_dir", "entry_digest", "load_entry", "store_entry",
           "package_sources_sha256", "sources_sha256", "entry_path"]

#: gearfmu's package folder (the root of :func:`package_sources_sha256`)
PACKAGE_ROOT = Path(__file__).resolve().parents[1]

ENTRY_FORMAT = "gearfmu-cache-entry"
ENTRY_VERSION = 1


class CacheWarning(UserWarning):
    """A cache entry that could not be used (it is ignored; nothing is lost)."""


def cache_root() -> Path:
    """``$GEARFMU_CACHE_DIR``, else ``$XDG_CACHE_HOME/gearfmu``, else ``~/.cache/gearfmu``."""
    root = os.environ.get("GEARFMU_CACHE_DIR")
    if root:
        return Path(root)
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "gearfmu"


def cache_dir(name: str) -> Path:
    """The folder of one user of the cache (not created here)."""
    return cache_root() / name


def package_sources_sha256(root: Path = PACKAGE_ROOT, parts: Optional[Sequence[str]] = None) -> str:
    """SHA-256 over the path and bytes of every ``.py`` file under ``root`` (default: the
    installed gearfmu package), in sorted path order; ``parts``: only the files under these
    sub-folders of ``root`` (None: all).  Part of the keys of cached results: in a development
    checkout the version string stays the same while the code changes, and a result of other
    code must not be read back."""
    h = hashlib.sha256()
    root = Path(root)
    files = sorted(root.rglob("*.py")) if parts is None else sorted(
        f for part in parts for f in (root / part).rglob("*.py"))
    for f in files:
        h.update(f.relative_to(root).as_posix().encode("utf-8") + b"\0")
        h.update(f.read_bytes() + b"\0")
    return h.hexdigest()


@functools.lru_cache(maxsize=None)
def sources_sha256(parts: Optional[Tuple[str, ...]] = None) -> str:
    """:func:`package_sources_sha256` of the installed package (computed once per process)."""
    return package_sources_sha256(PACKAGE_ROOT, parts)


def _canonical(key: dict) -> bytes:
    return json.dumps(key, sort_keys=True, separators=(",", ":"), allow_nan=True).encode("utf-8")


def entry_digest(key: dict) -> str:
    """The SHA-256 (hex) that names the entry of ``key``."""
    return hashlib.sha256(_canonical(key)).hexdigest()


def entry_path(folder: Path, key: dict) -> Path:
    """The head file (``<digest>.json``) of the entry of ``key`` in ``folder``."""
    return Path(folder) / f"{entry_digest(key)}.json"


def load_entry(folder: Path, key: dict, suffix: str, fields: Optional[Dict[str, type]] = None
               ) -> Optional[Tuple[dict, bytes]]:
    """(metadata, payload) of the entry of ``key`` in ``folder``; None when there is none or when
    it is unusable (then with a :class:`CacheWarning` naming the file and the reason).
    ``fields``: metadata the entry must have, name -> type (an int is accepted for a float)."""
    digest = entry_digest(key)
    head = Path(folder) / f"{digest}.json"
    if not head.exists():
        return None
    try:
        entry = json.loads(head.read_text(encoding="utf-8"))
        if not isinstance(entry, dict) or entry.get("format") != ENTRY_FORMAT \
                or entry.get("version") != ENTRY_VERSION:
            raise ValueError("not a gearfmu cache entry of this version")
        if _canonical(entry.get("key")) != _canonical(key):
            raise ValueError("its key differs from the one its name stands for")
        payload = (Path(folder) / f"{digest}{suffix}").read_bytes()
        if hashlib.sha256(payload).hexdigest() != entry.get("payload_sha256"):
            raise ValueError(f"{digest}{suffix} does not match its checksum")
        meta = entry.get("meta")
        if not isinstance(meta, dict):
            raise ValueError("no metadata")
        for name, kind in (fields or {}).items():
            if type(meta.get(name)) is not kind and not (kind is float and type(meta.get(name)) is int):
                raise ValueError(f"metadata {name!r} is not a {kind.__name__}")
    except (OSError, ValueError, TypeError) as exc:  # JSONDecodeError and UnicodeDecodeError are ValueErrors
        warnings.warn(f"gearfmu cache: ignoring the unusable entry {head} ({exc}); computing again",
                      CacheWarning, stacklevel=2)
        return None
    return meta, payload


def _publish(path: Path, data: bytes) -> None:
    part = path.with_name(f"{path.name}.{os.getpid()}.part")
    try:
        part.write_bytes(data)
        os.replace(part, path)
    finally:
        if part.exists():
            part.unlink()


def store_entry(folder: Path, key: dict, meta: dict, payload: bytes, suffix: str) -> None:
    """Keep ``payload`` and ``meta`` under ``key`` (the payload first, so that a reader never
    sees a head without its payload).  An unwritable folder is not an error."""
    digest = entry_digest(key)
    folder = Path(folder)
    head = {"format": ENTRY_FORMAT, "version": ENTRY_VERSION, "key": key, "meta": meta,
            "payload_sha256": hashlib.sha256(payload).hexdigest()}
    try:
        folder.mkdir(parents=True, exist_ok=True)
        _publish(folder / f"{digest}{suffix}", payload)
        _publish(folder / f"{digest}.json", json.dumps(head, indent=1, sort_keys=True).encode("utf-8"))
    except OSError:
        pass  # an unwritable cache only costs the next run the computation
