"""The packaging the multi-mesh FMUs share: the gearbox FMU (:mod:`gearfmu.fmu.gearbox_build`) and the
planetary FMU (:mod:`gearfmu.fmu.planetary_build`).

Both are the standalone C runtime over a multi-mesh model (``standalone/gf_meshes.c``) compiled from one
translation unit for the platforms of :mod:`gearfmu.fmu.crossbuild`; :func:`assemble_fmu` makes the FMU
from what a builder computed (the sources to copy, the resources, the provenance, the validation
record, the documentation page): binaries, build recipe, platforms.txt, resources with their
checksums, provenance.json, the validation record, modelDescription.xml and the documentation, zipped
under a temporary name and renamed at the end (:func:`gearfmu.fmu.build_steps.fmu_zip`).
"""
from __future__ import annotations

import hashlib
import json
import platform
import sys
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Dict, Optional, Sequence

from .. import __version__
from ..common.vocabulary import DEFAULT_FMU_INTERFACE
from . import crossbuild
from .build_steps import (FmuBuildError, check_model_description, compiler_version, find_c_compiler, fmi_header_dir,
                          fmu_zip, model_description, zip_folder)
from .fmudoc import DOC_FILES
from .standalone_build import (INTERFACE_ELEMENTS, STANDALONE_CFLAGS, build_recipe_files, compile_standalone,
                               platforms_text, standalone_model_description)

__all__ = ["FmuPackage", "assemble_fmu", "check_platforms", "interface_options"]


@dataclass
class FmuPackage:
    """What a multi-mesh builder hands to :func:`assemble_fmu`.

    ``kind``: "gearbox" or "planetary" (provenance, generation tool); ``unit``: the one C file to compile;
    ``copy_sources(dest)``: the unit and every file it includes into ``dest``; ``resources``: path under
    resources/ -> bytes; ``provenance``: its fields beside the files, binaries and versions;
    ``record(compiler)``: the validation record as {path in the FMU: bytes} (None: no record);
    ``page(description, record, platforms_text, generation_tool)``: the documentation page (bytes)."""

    kind: str
    out_path: Path
    fmi_version: int
    unit: Path
    copy_sources: Callable[[Path], Path]
    platforms: Sequence[str]
    cc: Optional[str]
    identifier: str
    guid: str
    now: str
    spec: object
    variables: Sequence
    model_name: str
    stop_time_s: float
    step_size_s: float
    interface: str
    resources: Dict[str, bytes]
    provenance: dict
    record: Optional[Callable[[Optional[str]], Dict[str, bytes]]]
    page: Callable[[str, Optional[dict], str, str], bytes]
    #: the model description's variableNamingConvention: "flat" when the names are the native solver's
    #: columns that the structured grammar does not cover (``ps.planet[1]_angle``)
    naming_convention: str = "structured"


def check_platforms(platforms) -> tuple:
    """The platform keys of a build (None: :func:`gearfmu.fmu.crossbuild.parse_platforms`'s default);
    FmuBuildError for an unknown one."""
    keys = crossbuild.parse_platforms(None) if platforms is None else tuple(platforms)
    unknown = [k for k in keys if k not in crossbuild.TARGETS]
    if unknown or not keys:
        raise FmuBuildError(f"platforms: unknown {unknown} (known: {', '.join(crossbuild.TARGETS)})")
    return keys


def interface_options(model_exchange: Optional[dict], fmu_interfaces, node_event_options, default_node_events) -> tuple:
    """(interface, me_node_events) of a builder's ``model_exchange`` mapping (None: {}); FmuBuildError
    naming the key for a value that is not offered."""
    opts = dict(model_exchange or {})
    unknown = sorted(set(opts) - {"interface", "me_node_events"})
    if unknown:
        raise FmuBuildError(f"model_exchange: unknown keys {unknown} (interface, me_node_events)")
    interface = opts.get("interface") or DEFAULT_FMU_INTERFACE
    node_events = opts.get("me_node_events") or default_node_events
    if interface not in fmu_interfaces:
        raise FmuBuildError(f"interface: {interface!r} not one of {fmu_interfaces}")
    if node_events not in node_event_options:
        raise FmuBuildError(f"me_node_events: {node_events!r} not one of {node_event_options}")
    return interface, node_events


def assemble_fmu(p: FmuPackage) -> Path:
    """Build the FMU ``p`` describes at ``p.out_path`` (module docstring); return its path."""
    v = p.fmi_version
    unit = p.unit.name
    with tempfile.TemporaryDirectory(prefix=f"gearfmu_{p.kind}_build_") as tmpd:
        root = Path(tmpd) / "fmu"
        src = p.copy_sources(root / "sources")

        def host_compile(out_lib):
            host = p.cc or find_c_compiler()
            return compile_standalone(src, out_lib, cc=host, fmi_version=v, sources=(unit,)), compiler_version(host)

        try:
            binaries = crossbuild.build_binaries(p.platforms, src, root / "binaries", p.identifier,
                                                 cflags=STANDALONE_CFLAGS, sources=(unit,), host_compile=host_compile,
                                                 host_cc_first=p.cc is not None, fmi_version=v,
                                                 header_dir=fmi_header_dir(v))
        except crossbuild.CrossBuildError as exc:
            raise FmuBuildError(str(exc)) from None
        for name, text in build_recipe_files(p.identifier, v, (unit,)).items():
            (src / name).write_text(text, encoding="utf-8")
        plat_text = platforms_text(binaries, v)
        (root / "documentation").mkdir()
        (root / "documentation" / "platforms.txt").write_text(plat_text, encoding="utf-8")
        built = {k: r for k, r in binaries.items() if "missing" not in r}
        for r in built.values():
            r["sha256"] = hashlib.sha256((root / "binaries" / r["folder"] / r["file"]).read_bytes()).hexdigest()
        res = root / "resources"
        for rel, data in p.resources.items():
            f = res / rel
            f.parent.mkdir(parents=True, exist_ok=True)
            f.write_bytes(data)
        files = {f.relative_to(root).as_posix(): hashlib.sha256(f.read_bytes()).hexdigest()
                 for f in sorted(res.rglob("*")) if f.is_file()}
        compiler = "; ".join(sorted({r["compiler"] for r in built.values()})) or None
        provenance = {
            "gearfmu_version": __version__, "built_utc": p.now, "runtime": "standalone", "model": p.kind,
            "fmi_version": v, "model_name": p.model_name, "model_identifier": p.identifier, "guid": p.guid,
            **p.provenance, "files_sha256": files,
            "binary": {"compiler": compiler, "flags": list(STANDALONE_CFLAGS),
                       "command": "; ".join(sorted({r["command"] for r in built.values()})), "platforms": binaries,
                       "sources_sha256": {f.name: hashlib.sha256(f.read_bytes()).hexdigest()
                                          for f in sorted(src.iterdir())}},
            "python": sys.version.split()[0], "platform": platform.platform(), "spec": Path(p.spec.path).name,
        }
        (res / "provenance.json").write_text(json.dumps(provenance, indent=1, default=str), encoding="utf-8")
        record = None
        if p.record is not None:
            rec_files = p.record(compiler)
            for rel, data in rec_files.items():
                f = root / rel
                f.parent.mkdir(parents=True, exist_ok=True)
                f.write_bytes(data)
            record = json.loads(rec_files["resources/validation/record.json"])
        tool = f"gearfmu {__version__} (standalone runtime, {p.kind})"
        md_args = dict(model_name=p.model_name, model_identifier=p.identifier, guid=p.guid,
                       stop_time_s=p.stop_time_s, step_size_s=p.step_size_s, generation_tool=tool,
                       generation_date=p.now, version=__version__, interfaces=INTERFACE_ELEMENTS[p.interface])
        note = crossbuild.platform_summary(binaries)
        if v == 3:
            md = model_description(p.spec, p.variables, 3, platforms_note=note, **md_args)
        else:
            md = standalone_model_description(model_description(p.spec, p.variables, 2, **md_args), (unit,),
                                              platforms_note=note)
            check_model_description(md, p.variables)
        if p.naming_convention != "structured":
            md = md.replace(b'variableNamingConvention="structured"',
                            f'variableNamingConvention="{p.naming_convention}"'.encode())
        (root / "modelDescription.xml").write_bytes(md)
        page = p.page(ET.fromstring(md).get("description", ""), record, plat_text, tool)
        for rel in DOC_FILES(v):
            (root / rel).write_bytes(page)
        with fmu_zip(p.out_path) as zout:
            zip_folder(zout, root)
    return p.out_path
