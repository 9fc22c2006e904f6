"""Is an FMU handed to gearfmu intact, and can it run here?  Checked before fmpy loads it.

A gearfmu FMU records the SHA-256 of most of its members at build time, in four places:
``resources/provenance.json`` (the tables, the scene, every binary, every source file; the
standalone runtime: its configuration file; the pythonfmu runtime: the kernel library; a gearbox
FMU: every stage's tables and scene, ``files_sha256``),
``resources/gearfmu_runtime.json`` (pythonfmu runtime: the files it loads), ``resources/validation/record.json`` (tables.bin, tables.json, the
reference result, the scene) and ``resources/tables.json`` (tables.bin).
:func:`integrity_problem` compares every recorded checksum with the member (a member altered or
replaced after the build, even inside a well-formed zip archive, is found), and the provenance's
GUID and model identifier with modelDescription.xml.  :func:`platform_problem` checks that the
FMU carries a binary fmpy can load on this machine.  Both return one sentence or None.

The checksums catch damage and careless edits, not an attacker who rewrites the records too:
they are not signed.  An FMU from another tool records none of them; only its zip archive (every
member's CRC-32, :func:`gearfmu.common.user_files.read_archive`), its model description and its
binary are checked.
"""
from __future__ import annotations

import json
import re
from typing import Dict, List, Optional, Tuple

__all__ = ["RECORDS", "integrity_problem", "platform_problem"]

PROVENANCE = "resources/provenance.json"
RUNTIME = "resources/gearfmu_runtime.json"
RECORD = "resources/validation/record.json"
TABLES_JSON = "resources/tables.json"
#: the members holding checksums of other members (read_archive keeps their bytes)
RECORDS = (PROVENANCE, RUNTIME, RECORD, TABLES_JSON)

_SHA = re.compile(r"[0-9a-f]{64}")


def _get(d, *keys):
    for k in keys:
        if not isinstance(d, dict):
            return None
        d = d.get(k)
    return d


def _recorded(docs: Dict[str, dict]) -> List[Tuple[str, str, str]]:
    """[(member, sha256, member that records it)] from the parsed record files."""
    out = []

    def add(member, sha, where):
        if isinstance(member, str) and sha is not None:
            out.append((member, sha, where))

    prov = docs.get(PROVENANCE)
    if prov is not None:
        add("resources/tables.bin", prov.get("tables_sha256"), PROVENANCE)
        add("resources/scene.toml", prov.get("scene_sha256"), PROVENANCE)
        add("resources/gearfmu_standalone.txt", prov.get("config_sha256"), PROVENANCE)  # standalone runtime
        for r in (_get(prov, "binary", "platforms") or {}).values():
            if isinstance(r, dict) and "sha256" in r:
                add(f"binaries/{r.get('folder')}/{r.get('file')}", r["sha256"], PROVENANCE)
        for name, sha in (_get(prov, "binary", "sources_sha256") or {}).items():
            add(f"sources/{name}", sha, PROVENANCE)
        for name, sha in (prov.get("files_sha256") or {}).items():  # the gearbox FMU: every stage's tables
            add(name, sha, PROVENANCE)
        kernel = prov.get("kernel")
        if isinstance(kernel, dict):
            add(f"resources/{kernel.get('file')}", kernel.get("sha256"), PROVENANCE)
    for name, sha in (_get(docs.get(RUNTIME), "sha256") or {}).items():
        add(f"resources/{name}", sha, RUNTIME)
    rec = docs.get(RECORD)
    if rec is not None:
        add("resources/tables.bin", _get(rec, "tables", "tables_bin_sha256"), RECORD)
        add(TABLES_JSON, _get(rec, "tables", "tables_json_sha256"), RECORD)
        ref = rec.get("reference")
        if isinstance(ref, dict):
            add(f"resources/validation/{ref.get('file')}", ref.get("sha256"), RECORD)
        add("resources/validation/scene.toml", rec.get("scene_sha256"), RECORD)
    tables = docs.get(TABLES_JSON)
    if tables is not None:
        add("resources/tables.bin", tables.get("bin_sha256"), TABLES_JSON)
    return out


def integrity_problem(archive, model_description) -> Optional[str]:
    """The first problem with the checksums and identity an FMU records (module docstring), as
    a sentence without the file name; None when every recorded checksum matches.  ``archive``:
    :class:`gearfmu.common.user_files.Archive` read with ``keep`` = :data:`RECORDS`."""
    docs, unreadable = {}, []
    for name in RECORDS:
        if name in archive.data:
            try:
                doc = json.loads(archive.data[name].decode("utf-8"))
            except ValueError as exc:  # not UTF-8, not JSON
                unreadable.append(f"altered FMU: {name} is not valid JSON ({exc})")
                continue
            if not isinstance(doc, dict):
                unreadable.append(f"altered FMU: {name} holds a JSON {type(doc).__name__}, not an object")
                continue
            docs[name] = doc
    # the checksums first: a record file that no longer reads is named by the checksum of it
    # that another one holds
    for member, sha, where in _recorded(docs):
        if not isinstance(sha, str) or not _SHA.fullmatch(sha):
            return f"altered FMU: {where} records {sha!r} as the SHA-256 of {member}, not a checksum"
        if member not in archive.sha256:
            return f"damaged FMU: {member} is missing (its checksum is recorded in {where})"
        if archive.sha256[member] != sha:
            return (f"altered FMU: {member} does not match the SHA-256 checksum recorded in {where} "
                    "(changed after the build; rebuild the FMU or use an intact copy)")
    if unreadable:
        return unreadable[0]
    prov = docs.get(PROVENANCE)
    if prov is not None:
        guid = getattr(model_description, "guid", None)
        if prov.get("guid") is not None and guid != prov.get("guid"):
            return (f"altered FMU: modelDescription.xml has guid {guid!r}, its provenance ({PROVENANCE}) "
                    f"{prov.get('guid')!r}")
        ident = _identifier(model_description)
        if prov.get("model_identifier") is not None and ident != prov.get("model_identifier"):
            return (f"altered FMU: modelDescription.xml has modelIdentifier {ident!r}, its provenance "
                    f"({PROVENANCE}) {prov.get('model_identifier')!r}")
    return None


def _identifier(model_description) -> Optional[str]:
    """The modelIdentifier of the FMU's Co-Simulation element, else of its Model Exchange one (the
    standalone runtime uses one binary for both)."""
    for kind in ("coSimulation", "modelExchange"):
        ident = getattr(getattr(model_description, kind, None), "modelIdentifier", None)
        if ident is not None:
            return ident
    return None


def platform_problem(names, model_description) -> Optional[str]:
    """None when the FMU carries the Co-Simulation binary fmpy loads on this machine
    (``binaries/<platform>/<modelIdentifier><extension>``); otherwise which one is missing and
    which platforms the FMU has."""
    import fmpy  # fmpy: the platform names and library extension it loads

    fmi3 = str(getattr(model_description, "fmiVersion", "")).startswith("3")
    folder = fmpy.platform_tuple if fmi3 else fmpy.platform
    ident = _identifier(model_description)
    want = f"binaries/{folder}/{ident}{fmpy.sharedLibraryExtension}"
    if want in names:
        return None
    have = sorted({n.split("/")[1] for n in names if n.startswith("binaries/") and n.count("/") >= 2
                   and not n.endswith("/")})
    src = any(n.startswith("sources/") for n in names)
    return (f"no binary for this platform ({folder}): {want} is missing; the FMU has binaries for "
            f"{', '.join(have) or 'no platform'}" + ("; compile its sources/ for this platform "
                                                     "(docs/standalone.md 'Platforms')" if src else ""))
