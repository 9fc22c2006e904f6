"""Build the *standalone* gearfmu FMU: FMI 2.0 (or 3.0) Co-Simulation in C, no Python.

The FMI layer ``gearfmu/fmu/standalone/fmi2_gear.c`` (FMI 3: ``fmi3_gear.c``) with the
generic FMI plumbing and the gear model both layers share (``fmi_common.c``, ``gear_model.c``,
the contract between them ``gf_model.h``), the FMU behaviour the pythonfmu runtime shares
(``gearfmu/fmu/kernel/gkfmu.c``) and the C kernel (``gearfmu/fmu/kernel/``: ``gearkernel.c`` and
the files beside it, docs/model.md) are compiled at build time
into ``binaries/<platform>/<modelIdentifier>.so`` from one translation unit
(``fmi2_all.c`` / ``fmi3_all.c``, every internal function static); the FMU also carries all
sources (``sources/``, the unit listed in ``<SourceFiles>``), without the FMI headers, which the
standard has the importer supply (the build uses the standard's FMI 2.0.5 headers,
``standalone/fmi2_headers``, and fmpy's FMI 3.0.1 ones), so any other platform can compile it
and several FMUs link into one program (docs/standalone.md "Source code").  The tables sit in ``resources/`` as in the pythonfmu FMU; because
C has no JSON parser the builder also writes ``resources/gearfmu_standalone.txt``
(key=value lines: GUID, table dimensions and byte offsets, scalars as C99
hexadecimal floats -- exact --, the SHA-256 of tables.bin, and the variable
table with the value references of modeldescription/variables.toml).

FMU layout (docs/standalone.md)::

    modelDescription.xml                 from the spec (gearfmu.fmu.modeldesc), CoSimulation
                                         needsExecutionTool=false, FMU state supported, SourceFiles
    binaries/<folder>/<id>.<so|dll|dylib>  the C files for linux64, aarch64-linux, win64 and
                                         darwin64 (universal x86_64 + arm64), gearfmu.fmu.crossbuild
    sources/                             fmi2_all.c fmi2_gear.c fmi_common.[ch] gf_model.h gear_model.[ch] gf_resources.[ch]
                                         gkfmu.[ch] gearkernel.[ch] gk_*.[ch]
                                         BUILD.txt
                                         CMakeLists.txt (FMI 3: fmi3_all.c, fmi3_gear.c, buildDescription.xml)
                                         buildflags.txt
    documentation/index.html             the FMU's documentation (gearfmu.fmu.fmudoc; FMI 2 also _main.html)
    documentation/platforms.txt          which platforms carry a binary, which not and why
    resources/tables.json, tables.bin    the tables (gearfmu/tables/mesh_tables.py format)
    resources/gearfmu_standalone.txt     what the C layer reads at instantiation
    resources/provenance.json            who/what/when built this FMU
    resources/scene.toml                 the scene (when given)
    resources/validation/                the validation record (:func:`validation_record`)
    resources/envelope.json              the verified envelope (gearfmu.fmu.envelope.fmu_envelope_record)

:func:`validation_record` is shared with the pythonfmu builder
(:func:`gearfmu.fmu.pythonfmu_build.build_fmu`): every FMU carries its scene, package and
dependency versions, table checksums and a reference result CSV of the native
solver over the FMU's DefaultExperiment -- the way the Modelica Reference-FMUs
carry their reference results.
"""
from __future__ import annotations

import datetime
import hashlib
import json
import math
import platform
import re
import shutil
import sys
import tempfile
import uuid
import xml.etree.ElementTree as ET
from dataclasses import replace
from pathlib import Path
from typing import Dict, Optional, Sequence, Union

import numpy as np

from .. import __version__
from ..common.settings import RunSettings
from ..common.vocabulary import (DEFAULT_FMI3_OUTPUTS, DEFAULT_FMU_INTERFACE, DEFAULT_ME_NODE_EVENTS, FMI3_OUTPUTS,
                                 FMU_INTERFACES, ME_NODE_EVENTS)
from . import crossbuild
from .build_steps import (CFLAGS, FMI2_HEADERS, FMI3_HEADERS, FMU_LAYER_HEADER, FMU_LAYER_SOURCE,  # noqa: F401
                          KERNEL_HEADERS, KERNEL_SOURCES, CompilerNotFoundError,
                          FmuBuildError, check_arguments, check_model_description, compiler_version,
                          find_c_compiler, fmi2_header_dir, fmi3_header_dir, fmi_header_dir, fmu_digest, fmu_zip,
                          interface_variables, model_description, record_parameters, run_compiler, scene_sha256,
                          start_values, variable_table_lines, write_scene, write_tables, zip_folder)
from .envelope import ENVELOPE_FILE, envelope_json, envelope_note, fmu_envelope_record, runtime_envelope
from .modeldesc import load_spec
from ..tables.mesh_tables import MeshTables
from ..tables.zones import zone_cuts
from .fmudoc import DOC_FILES, documentation_html
from .validation import VALIDATION_DIR, validation_record

HERE = Path(__file__).resolve().parent
LAYER_SOURCE = HERE / "standalone" / "fmi2_gear.c"
FMI3_LAYER_SOURCE = HERE / "standalone" / "fmi3_gear.c"
#: the generic FMI plumbing and the gear model both FMI layers share, and the FMU behaviour over the
#: kernel the pythonfmu runtime calls too (gkfmu.h)
SHARED_SOURCES = (HERE / "standalone" / "fmi_common.c", HERE / "standalone" / "gear_model.c",
                  HERE / "standalone" / "gf_resources.c", FMU_LAYER_SOURCE)
#: their headers: the model contract (gf_model.h, as the Reference-FMUs' model.h), the plumbing's API,
#: the gear model's data, the reading of the resources, the FMU layer's API
SHARED_HEADERS = (HERE / "standalone" / "gf_model.h", HERE / "standalone" / "fmi_common.h",
                  HERE / "standalone" / "gear_model.h", HERE / "standalone" / "gf_resources.h", FMU_LAYER_HEADER)
#: the C files of the FMI 2 binary besides the kernel, in compile order
LAYER_SOURCES = (LAYER_SOURCE.name, *(p.name for p in SHARED_SOURCES))
FMI3_LAYER_SOURCES = (FMI3_LAYER_SOURCE.name, *(p.name for p in SHARED_SOURCES))
#: the kernel's C files (build_steps.KERNEL_SOURCES), compiled after the layer's
KERNEL_SOURCE_NAMES = tuple(p.name for p in KERNEL_SOURCES)
#: the one file a build of FMI 2 / FMI 3 compiles: it includes the layer's and the kernel's C files, so
#: that every function but the fmi2* / fmi3* ones is static (docs/standalone.md "Source code")
UNIT_SOURCES = {2: HERE / "standalone" / "fmi2_all.c", 3: HERE / "standalone" / "fmi3_all.c"}
FMI_VERSIONS = (2, 3)
CONFIG_FILE = "gearfmu_standalone.txt"
CONFIG_FORMAT = "gearfmu-standalone"
CONFIG_VERSION = 1
#: compile flags of the standalone binary, the same for every platform: the kernel's
#: (-O2, no FMA contraction), no fast-math spelled out, plus hidden visibility so
#: only the fmi2* functions are exported (two gear FMUs in one process never
#: interpose each other's kernel symbols)
STANDALONE_CFLAGS = (*CFLAGS, "-fno-fast-math", "-fvisibility=hidden")
#: the machine-readable build recipe in the FMU's sources/ (key=value lines)
BUILDFLAGS_FILE = "buildflags.txt"


def layer_sources(fmi_version: int = 2) -> tuple:
    """The C files of the binary besides the kernel: the FMI layer of ``fmi_version``, the plumbing, the model."""
    return FMI3_LAYER_SOURCES if fmi_version == 3 else LAYER_SOURCES


def file_sources(fmi_version: int = 2) -> tuple:
    """Every C file of the binary in compile order, for a build that compiles them one by one
    (the benchmarks look inside the instance that way): :func:`layer_sources`, then the kernel's."""
    return (*layer_sources(fmi_version), *KERNEL_SOURCE_NAMES)


def binary_sources(fmi_version: int = 2) -> tuple:
    """The C files a build of the binary compiles: the one translation unit ``fmi2_all.c`` /
    ``fmi3_all.c``, which includes :func:`file_sources` (docs/standalone.md "Source code")."""
    return (UNIT_SOURCES[3 if fmi_version == 3 else 2].name,)


def copy_sources(dest_dir, fmi_version: int = 2) -> Path:
    """Copy every source the standalone binary of ``fmi_version`` needs into ``dest_dir``: the
    translation unit, the files it includes and their headers.  Not the FMI headers: the standard
    has the importer supply them (FMI 2.0.5 section 2.3, FMI 3.0 section 2.5.1.3); the build
    takes them from :func:`fmi_header_dir`."""
    dest = Path(dest_dir)
    dest.mkdir(parents=True, exist_ok=True)
    layer = FMI3_LAYER_SOURCE if fmi_version == 3 else LAYER_SOURCE
    unit = UNIT_SOURCES[3 if fmi_version == 3 else 2]
    for src in (unit, layer, *SHARED_SOURCES, *SHARED_HEADERS, *KERNEL_SOURCES, *KERNEL_HEADERS):
        shutil.copy2(src, dest / src.name)
    return dest


def compile_standalone(sources_dir, out_lib, *, cc: Optional[str] = None, fmi_version: int = 2,
                       sources: Optional[Sequence[str]] = None) -> list:
    """Compile the FMU binary from ``sources_dir``; return the command used.

    ``<cc> -O2 -fPIC -shared -ffp-contract=off -std=c99 -fno-fast-math -fvisibility=hidden -I<src>
    -I<FMI headers> -o <lib> fmi2_all.c -lm`` (:func:`binary_sources`; FMI 3: fmi3_all.c; ``sources``:
    another unit, e.g. the gearbox FMU's)
    """
    cc = cc or find_c_compiler()
    src = Path(sources_dir)
    out_lib = Path(out_lib)
    out_lib.parent.mkdir(parents=True, exist_ok=True)
    cmd = [cc, *STANDALONE_CFLAGS, f"-I{src}", f"-I{fmi_header_dir(fmi_version)}", "-o", str(out_lib),
           *(str(src / n) for n in (sources or binary_sources(fmi_version))), "-lm"]
    run_compiler(cmd, "standalone binary", timeout=300)
    return cmd


def build_recipe_files(identifier: str, fmi_version: int = 2, sources: Optional[Sequence[str]] = None
                       ) -> Dict[str, str]:
    """``sources/`` build files: BUILD.txt (prose), buildflags.txt (key=value, what a tool
    reads) and CMakeLists.txt (``cmake -S sources -B b -DFMI_HEADERS_DIR=<dir> && cmake --build b``),
    all with the flags of :data:`STANDALONE_CFLAGS`; FMI 3 also buildDescription.xml
    (:func:`build_description_xml`).  The FMI headers are the importer's (the standard's rule).
    ``sources``: the unit to compile (default :func:`binary_sources`; the gearbox FMU's is another)."""
    flags = " ".join(STANDALONE_CFLAGS)
    v = 3 if fmi_version == 3 else 2
    sources = tuple(sources or binary_sources(fmi_version))
    srcs = " ".join(sources)
    headers = ", ".join(FMI3_HEADERS if v == 3 else FMI2_HEADERS)
    section = "FMI 3.0 section 2.5.1.3" if v == 3 else "FMI 2.0.5 section 2.3"
    prefix_section = "FMI 3.0 section 2.2.2" if v == 3 else "FMI 2.0.5 section 2.1.1"
    build_txt = (
        f"Build the binary of this FMU from these sources (C99; FMI {v}.0):\n"
        f"  cc {flags} -I. -I<FMI headers> -o {identifier}.so {srcs} -lm\n"
        f"and place it as binaries/<platform>/{identifier}.so (Windows: .dll, macOS: .dylib; the fmi{v}*\n"
        "functions are exported unprefixed), or:\n"
        "  cmake -S sources -B build -DFMI_HEADERS_DIR=<FMI headers> && cmake --build build\n"
        "(CMakeLists.txt, same flags). buildflags.txt lists the flags as key=value lines.\n"
        f"<FMI headers> is the folder of the standard's {headers}: the importer's\n"
        f"own, which the standard has it supply ({section}); they are not part of sources/.\n"
        f"{srcs} is the one file to compile: it includes the other C files, and every function in it\n"
        f"but the fmi{v}* ones is static.\n"
        "\n"
        "Source code import / static linking (several FMUs in one program):\n"
        f"  cc -c -O2 -ffp-contract=off -std=c99 -fno-fast-math -DFMI{v}_FUNCTION_PREFIX={identifier}_ \\\n"
        f"     -I. -I<FMI headers> -o {identifier}.o {srcs}\n"
        f"gives {identifier}_fmi{v}DoStep, ... ({prefix_section}: the prefix is the modelIdentifier and '_';\n"
        "use the standard's unmodified headers, which honour the prefix). No other symbol is external.\n"
        "\n"
        "The numbers are the same on every platform by construction: -ffp-contract=off (no fused\n"
        "multiply-add), no fast-math, IEEE double arithmetic in source order; the kernel calls only\n"
        "sqrt, floor, ceil and fabs, which IEEE 754 defines exactly.\n")
    kv = [
        "# gearfmu standalone FMU build recipe (key=value; written by gearfmu.fmu.standalone_build)",
        "format=gearfmu-buildflags", "version=1", f"model_identifier={identifier}",
        "language=C99", f"sources={srcs}", "include_dirs=.", f"cflags={flags}", "ldflags=-lm",
        "optimization=-O2", "fp_contract=off", "fast_math=off", "visibility=hidden",
        f"# the standard's {headers}: supplied by the importer ({section})",
        f"fmi_headers={' '.join(FMI3_HEADERS if v == 3 else FMI2_HEADERS)}",
        f"# static linking: -DFMI{v}_FUNCTION_PREFIX=<model_identifier>_ ({prefix_section})",
        f"function_prefix_macro=FMI{v}_FUNCTION_PREFIX",
        "# MSVC (CMakeLists.txt): /fp:strict never contracts into FMA (/fp:precise does in MSVC before 2022)",
        "msvc_cflags=/O2 /fp:strict",
    ]
    cmake = (
        "# Build the FMU binary from these sources with the flags of buildflags.txt:\n"
        "#   cmake -S sources -B build -DFMI_HEADERS_DIR=<folder of the FMI headers>\n"
        "#   cmake --build build --config Release\n"
        "cmake_minimum_required(VERSION 3.10)\n"
        f"project({identifier} C)\n"
        f"set(FMI_HEADERS_DIR \"\" CACHE PATH \"folder of the standard's {headers} (the importer's, {section})\")\n"
        f"if(NOT EXISTS \"${{FMI_HEADERS_DIR}}/fmi{v}Functions.h\")\n"
        f"  message(FATAL_ERROR \"FMI_HEADERS_DIR: give the folder of the FMI {v}.0 headers ({headers}); \"\n"
        f"                      \"the standard has the importer supply them ({section})\")\n"
        "endif()\n"
        f"add_library({identifier} SHARED {srcs})\n"
        f"set_target_properties({identifier} PROPERTIES PREFIX \"\" C_STANDARD 99 C_STANDARD_REQUIRED ON\n"
        "                      C_EXTENSIONS OFF C_VISIBILITY_PRESET hidden POSITION_INDEPENDENT_CODE ON)\n"
        f"target_include_directories({identifier} PRIVATE ${{CMAKE_CURRENT_SOURCE_DIR}} ${{FMI_HEADERS_DIR}})\n"
        "if(MSVC)\n"
        f"  target_compile_options({identifier} PRIVATE /O2 /fp:strict)\n"
        "else()\n"
        f"  target_compile_options({identifier} PRIVATE -O2 -ffp-contract=off -fno-fast-math)\n"
        f"  target_link_libraries({identifier} m)\n"
        "endif()\n")
    files = {"BUILD.txt": build_txt, BUILDFLAGS_FILE: "\n".join(kv) + "\n", "CMakeLists.txt": cmake}
    if fmi_version == 3:
        files[BUILD_DESCRIPTION_FILE] = build_description_xml(identifier, sources)
    return files


#: the FMI 3.0 build description in an FMI 3 FMU's sources/ (FMI 3.0 section 2.5.1.2)
BUILD_DESCRIPTION_FILE = "buildDescription.xml"


def build_description_xml(identifier: str, sources: Optional[Sequence[str]] = None) -> str:
    """``sources/buildDescription.xml`` of an FMI 3 FMU (the standard's fmi3BuildDescription
    format): one C99 source file set (the FMI 3 layer, plumbing, model, kernel), include directory
    ``.``, the reproducibility flags of :data:`STANDALONE_CFLAGS` as ``compilerOptions``
    (``-ffp-contract=off``, ``-fno-fast-math``) and the C math library."""
    root = ET.Element("fmiBuildDescription", {"fmiVersion": "3.0"})
    bc = ET.SubElement(root, "BuildConfiguration", {
        "modelIdentifier": identifier,
        "description": "every platform: the same flags; no fused multiply-add (-ffp-contract=off) and no "
                       "fast-math, so every platform computes the same numbers (MSVC: /O2 /fp:strict). "
                       f"{(sources or binary_sources(3))[0]} includes the other C files; every function in it "
                       "but the fmi3* ones is "
                       f"static. Static linking: define FMI3_FUNCTION_PREFIX={identifier}_ (FMI 3.0 section "
                       "2.2.2); a shared library leaves it undefined. The FMI headers are the importer's."})
    sfs = ET.SubElement(bc, "SourceFileSet", {"language": "C99", "compilerOptions": " ".join(
        f for f in STANDALONE_CFLAGS if f not in ("-shared",))})
    for name in (sources or binary_sources(3)):
        ET.SubElement(sfs, "SourceFile", {"name": name})
    ET.SubElement(sfs, "IncludeDirectory", {"name": "."})
    ET.SubElement(bc, "Library", {"name": "m", "external": "true", "description": "C math library (-lm)"})
    ET.indent(root, space="  ")
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def build_description_flags(xml_text: str) -> Dict[str, object]:
    """What a tool reads from a ``buildDescription.xml``: sources, include dirs, compiler options, libraries."""
    root = ET.fromstring(xml_text)
    bc = root.find("BuildConfiguration")
    sfs = bc.find("SourceFileSet")
    return {"model_identifier": bc.get("modelIdentifier"), "language": sfs.get("language"),
            "sources": [e.get("name") for e in sfs.findall("SourceFile")],
            "include_dirs": [e.get("name") for e in sfs.findall("IncludeDirectory")],
            "cflags": (sfs.get("compilerOptions") or "").split(),
            "libraries": [e.get("name") for e in bc.findall("Library")]}


def read_build_flags(text: str) -> Dict[str, str]:
    """Parse a ``buildflags.txt`` (key=value lines, '#' comments)."""
    out = {}
    for line in text.splitlines():
        if line.strip() and not line.startswith("#") and "=" in line:
            k, v = line.split("=", 1)
            out[k.strip()] = v.strip()
    return out


def platforms_text(report: Dict[str, dict], fmi_version: int = 2) -> str:
    """``documentation/platforms.txt``: the binaries this FMU carries and the ones it lacks."""
    lines = [f"Platforms of this FMU (FMI {fmi_version}.0 Co-Simulation, standalone gearfmu runtime)", ""]
    for key, r in report.items():
        if "missing" in r:
            lines.append(f"{key:16s} NOT BUILT: {r['missing']}; compile sources/ (sources/BUILD.txt)")
        else:
            fat = f" (universal Mach-O with {' + '.join(r['fat_slices'])})" if r.get("fat_slices") else ""
            also = f" and binaries/{r['also_in']}/{r['file']}" if r.get("also_in") else ""
            lines.append(f"{key:16s} binaries/{r['folder']}/{r['file']}{fat}{also}; {r['compiler']}")
    lines += ["", f"Compile flags (every platform): {' '.join(STANDALONE_CFLAGS)} (sources/buildflags.txt)."]
    return "\n".join(lines) + "\n"


def scalar_names(variables):
    """The variables with every per-slot element ``name[i]`` renamed ``name_i`` (the FMI 3 FMU with
    scalar outputs: no name ends in ``[1]``, so neither the model description
    (:func:`gearfmu.fmu.modeldesc.fmi3_variables`) nor the C layer (gf_resources.c gfr_mark_arrays) makes
    arrays of them).  Value references, order and everything else stay."""
    return [replace(v, name=re.sub(r"\[(\d+)\]$", r"_\1", v.name)) for v in variables]


def _hexf(v) -> str:
    """A float as a C99 hexadecimal literal (exact; strtod reads it)."""
    return float(v).hex()


#: the model description's elements of each ``interface`` value (gearfmu.common.vocabulary.FMU_INTERFACES)
INTERFACE_ELEMENTS = {"cs": ("cs",), "me": ("me",), "both": ("me", "cs")}


def me_features(tables: MeshTables, interface: str, node_events: str) -> tuple:
    """The spec features (:data:`gearfmu.fmu.modeldesc.ME_FEATURES`) of an FMU offering ``interface``:
    none without Model Exchange; else its states and contact indicators, the zone indicators when the
    tables have contact-zone edges (the lookup's cuts, :func:`gearfmu.tables.zones.zone_cuts`) and the
    segment indicators with ``node_events`` other than "none"."""
    if "me" not in INTERFACE_ELEMENTS[interface]:
        return ()
    return (("model_exchange",) + (("zone_events",) if zone_cuts(tables) is not None else ())
            + (("node_events",) if node_events != "none" else ()))


def me_nominals(tables: MeshTables, pinion_speed_rad_s: float, pinion_torque_Nm: float) -> tuple:
    """Nominal values of the Model Exchange states [theta1, omega1, x, v] (rad, rad/s, m, m/s), the
    scales of the event-located reference (gearfmu.dynamics.reference): one mesh period; the start
    speed (at least 1 rad/s); the largest of the static deflection, the backlash and the meshing
    error range (at least 1e-9 m); that times omega_n = sqrt(k_mean/m_e).  A host's absolute
    tolerance is its relative tolerance times these (fmpy's CVode)."""
    e = np.asarray(tables.e_m, float)
    x = max(abs(pinion_torque_Nm) / (tables.base_radius_pinion_m * tables.k_mean_N_per_m),
            float(np.max(np.abs(tables.backlash_half_m))), float(np.max(e) - np.min(e)), 1e-9)
    wn = math.sqrt(tables.k_mean_N_per_m / tables.equivalent_mass_kg)
    return (float(tables.mesh_period_rad), max(abs(pinion_speed_rad_s), 1.0), x, x * wn)


def config_text(tables: MeshTables, variables, *, guid: str, model_identifier: str,
                meta_bytes: bytes, bin_bytes: bytes, envelope: Optional[dict] = None,
                interface: str = "cs", node_events: str = "none", nominals: Optional[tuple] = None) -> str:
    """The ``gearfmu_standalone.txt`` the C layer reads (format version 1, docs/standalone.md).
    ``envelope``: :func:`gearfmu.fmu.envelope.runtime_envelope` (``envelope.kind`` and
    ``envelope.<quantity>=low|high`` lines; none: nothing is checked).  ``interface``, ``node_events``,
    ``nominals``: Model Exchange (``interfaces``, ``me.*`` lines; docs/standalone.md "Model Exchange")."""
    meta = json.loads(meta_bytes.decode("utf-8"))
    sc = meta["scalars"]
    lines = [
        "# gearfmu standalone runtime configuration (written by gearfmu.fmu.standalone_build; read by gear_model.c)",
        "# floats are C99 hexadecimal literals (exact); var = vr|causality|variability|type|output_index|start|min|max|name",
        f"format={CONFIG_FORMAT}", f"version={CONFIG_VERSION}",
        f"model_identifier={model_identifier}", f"guid={guid}",
        f"slots={int(meta['slots'])}", f"n_phi={int(meta['n_phi'])}", f"n_torque={int(meta['n_torque'])}",
        f"tables_bytes={len(bin_bytes)}", f"tables_sha256={hashlib.sha256(bin_bytes).hexdigest()}",
    ]
    for name in ("torque_Nm", "k_N_per_m", "e_m", "backlash_half_m"):
        lines.append(f"offset.{name}={int(meta['arrays'][name]['offset'])}")
    if "temperature_C" in meta["arrays"]:  # version 2 temperature axis (docs/tables.md)
        lines.append(f"n_temperature={int(meta['n_temperature'])}")
        lines.append(f"offset.temperature_C={int(meta['arrays']['temperature_C']['offset'])}")
    for name in ("phi_period_rad", "base_radius_pinion_m", "base_radius_gear_m", "inertia_pinion_kgm2",
                 "inertia_gear_kgm2", "k_mean_N_per_m"):
        lines.append(f"{name}={_hexf(sc[name])}")
    if meta.get("engagement") is not None:  # contact-zone edges (docs/model.md "Contact-zone edges")
        lines.append(f"mesh_period_rad={_hexf(sc['mesh_period_rad'])}")
        lines.append(f"engagement_in_rad={_hexf(meta['engagement']['in_rad'])}")
        lines.append(f"engagement_out_rad={_hexf(meta['engagement']['out_rad'])}")
    if envelope is not None:  # docs/fmu.md "Verified envelope"
        lines.append(f"envelope.kind={int(envelope['kind'])}")
        for q in ("pinion_torque_Nm", "pinion_speed_rad_s", "temperature_C"):
            if envelope.get(q) is not None:
                lines.append(f"envelope.{q}={_hexf(envelope[q][0])}|{_hexf(envelope[q][1])}")
    elements = INTERFACE_ELEMENTS[interface]
    lines.append("interfaces=" + ",".join(e for e in ("cs", "me") if e in elements))
    if "me" in elements:  # docs/standalone.md "Model Exchange"
        lines.append(f"me.node_events={ME_NODE_EVENTS.index(node_events)}")
        lines.append(f"me.event_indicators={sum(v.event_indicator for v in variables)}")
        lines.append("me.nominals=" + "|".join(_hexf(v) for v in nominals))
    lines += variable_table_lines(variables)
    return "\n".join(lines) + "\n"


def standalone_model_description(xml: bytes, source_files, platforms_note: Optional[str] = None) -> bytes:
    """Turn the spec's model description into the standalone one: no execution
    tool needed, FMU state get/set/serialize offered, ``<SourceFiles>`` listed,
    ``platforms_note`` (which binaries the FMU carries) appended to the description."""
    root = ET.fromstring(xml)
    if platforms_note:
        root.set("description", (root.get("description", "").rstrip() + " [" + platforms_note + "]").lstrip())
    elements = [el for el in (root.find("ModelExchange"), root.find("CoSimulation")) if el is not None]
    if not elements:
        raise FmuBuildError("modelDescription.xml: no ModelExchange or CoSimulation element")
    for el in elements:
        el.set("needsExecutionTool", "false")
        el.set("canGetAndSetFMUstate", "true")
        el.set("canSerializeFMUstate", "true")
        for child in list(el):
            el.remove(child)
        sf = ET.SubElement(el, "SourceFiles")
        for name in source_files:
            ET.SubElement(sf, "File", {"name": name})
    ET.indent(root, space="  ")
    return b'<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="utf-8") + b"\n"


def write_documentation(root: Path, *, fmi_version: int, **kw) -> None:
    """``documentation/index.html`` (FMI 2 also ``_main.html``, the same page) into the FMU folder
    ``root`` (:func:`gearfmu.fmu.fmudoc.documentation_html`; the validation record read from
    ``root/resources/validation/record.json`` when the FMU has one)."""
    rec = root / VALIDATION_DIR / "record.json"
    page = documentation_html(fmi_version=fmi_version, validation_record=json.loads(rec.read_text())
                              if rec.is_file() else None, **kw)
    for rel in DOC_FILES(fmi_version):
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_bytes(page)


# --------------------------------------------------------------------- build
def build_standalone_fmu(tables: MeshTables, out_path, settings: Optional[RunSettings] = None, *,
                         model_name: str = "gearpair", scene_text: Optional[str] = None, spec_path=None,
                         cc: Optional[str] = None, validation: bool = True,
                         platforms: Optional[Sequence[str]] = None, envelope: Optional[dict] = None,
                         fmi_version: int = 2, fmi3_outputs: str = DEFAULT_FMI3_OUTPUTS,
                         damping_ratio: Optional[float] = None, pinion_speed_start_rad_s: Optional[float] = None,
                         pinion_torque_start_Nm: Optional[float] = None, gear_torque_start_Nm: Optional[float] = None,
                         max_step_s: Optional[float] = None, damping_model: Union[int, str, None] = None,
                         stop_time_s: Optional[float] = None, output_interval_s: Optional[float] = None,
                         pinion_angle_start_rad: Optional[float] = None, integrator: Union[int, str, None] = None,
                         interface: str = DEFAULT_FMU_INTERFACE, me_node_events: str = DEFAULT_ME_NODE_EVENTS) -> Path:
    """Build the standalone FMI 2.0 (``fmi_version`` 3: FMI 3.0) CS FMU of ``tables``; return its path.

    Same settings, arguments and units as :func:`gearfmu.fmu.pythonfmu_build.build_fmu`
    (``settings``: the :class:`gearfmu.common.settings.RunSettings` of the FMU's start values and
    DefaultExperiment, its fields replaced by the keyword arguments given; damping ratio 1, speeds
    rad/s, torques N*m, times s, angles rad; ``integrator`` "rk4" (0), "rk4_kink" (1),
    "rk4_node" (2, default) or "rk4_seg" (3), the FMU parameter ``integrator``); ``validation``
    False skips the validation record (and its native run).  ``platforms``:
    keys of :data:`gearfmu.fmu.crossbuild.TARGETS` (default: all); without the zig
    compiler only the build machine's platform is compiled (with ``cc`` or the
    host C compiler), and documentation/platforms.txt and the model description
    say which platforms are missing.  ``cc`` given: the build machine's platform
    is compiled with it.  ``envelope``: :func:`gearfmu.fmu.envelope.fmu_envelope_record` (None: the
    tables' own range, "not verified").  ``fmi_version`` 3: the same C glue behind the FMI 3.0
    layer (fmi3_gear.c), ``pair_force``/``load_sharing`` as arrays, binaries under the FMI 3
    platform tuples, sources/buildDescription.xml (docs/standalone.md "FMI 3.0"); ``fmi3_outputs``
    "scalar" makes them scalars ``pair_force_1 .. pair_force_P`` (:func:`scalar_names`), for hosts
    without array support.  ``interface``: "cs" (Co-Simulation), "me" (Model Exchange) or "both"
    (default: one FMU usable both ways); ``me_node_events``: Model Exchange's table-node events,
    "none" (default), "kinks" or "all" (docs/standalone.md "Model Exchange").  Written under a
    temporary name beside ``out_path`` and renamed at the end.
    """
    if interface not in FMU_INTERFACES:
        raise FmuBuildError(f"interface: {interface!r} not one of {FMU_INTERFACES}")
    if me_node_events not in ME_NODE_EVENTS:
        raise FmuBuildError(f"me_node_events: {me_node_events!r} not one of {ME_NODE_EVENTS}")
    if fmi_version not in FMI_VERSIONS:
        raise FmuBuildError(f"fmi_version: {fmi_version!r} not one of {FMI_VERSIONS}")
    if fmi3_outputs not in FMI3_OUTPUTS or (fmi3_outputs != DEFAULT_FMI3_OUTPUTS and fmi_version != 3):
        raise FmuBuildError(f"fmi3_outputs: {fmi3_outputs!r} must be one of {FMI3_OUTPUTS}, and other than "
                            f"{DEFAULT_FMI3_OUTPUTS!r} only with fmi_version 3")
    s, out_path = check_arguments(tables, out_path, settings, scene_text=scene_text, model_name=model_name,
                                  damping_ratio=damping_ratio, pinion_speed_start_rad_s=pinion_speed_start_rad_s,
                                  pinion_angle_start_rad=pinion_angle_start_rad,
                                  pinion_torque_start_Nm=pinion_torque_start_Nm, gear_torque_start_Nm=gear_torque_start_Nm,
                                  max_step_s=max_step_s, stop_time_s=stop_time_s, output_interval_s=output_interval_s,
                                  damping_model=damping_model, integrator=integrator)
    tstop, dt = s.stop_time_s, s.output_interval_s
    keys = crossbuild.parse_platforms(None) if platforms is None else tuple(platforms)
    unknown = [k for k in keys if k not in crossbuild.TARGETS]
    if unknown or not keys:
        raise FmuBuildError(f"platforms: unknown {unknown} (known: {', '.join(crossbuild.TARGETS)})")

    spec = load_spec(spec_path)
    variables, temp0 = interface_variables(spec, tables, start_values(s), integrator_optional=True,
                                           features=me_features(tables, interface, me_node_events))
    if fmi3_outputs == "scalar":
        variables = scalar_names(variables)
    env_rec = envelope if envelope is not None else fmu_envelope_record(tables)
    meta_bytes, bin_bytes = tables.to_bytes()
    identifier = f"gearfmu_sa_{fmu_digest(meta_bytes, bin_bytes, model_name, s)[:12]}_{uuid.uuid4().hex[:8]}"
    guid = "{" + str(uuid.uuid4()) + "}"
    cc_given = cc is not None
    now = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    params = record_parameters(s, temp0)

    with tempfile.TemporaryDirectory(prefix="gearfmu_sa_build_") as tmpd:
        root = Path(tmpd) / "fmu"
        src = copy_sources(root / "sources", fmi_version)
        host_cc = {}

        def host_compile(out_lib):
            host_cc["cc"] = cc or find_c_compiler()
            return (compile_standalone(src, out_lib, cc=host_cc["cc"], fmi_version=fmi_version),
                    compiler_version(host_cc["cc"]))

        try:
            binaries = crossbuild.build_binaries(keys, src, root / "binaries", identifier,
                                                 cflags=STANDALONE_CFLAGS, sources=binary_sources(fmi_version),
                                                 host_compile=host_compile, host_cc_first=cc_given,
                                                 fmi_version=fmi_version, header_dir=fmi_header_dir(fmi_version))
        except crossbuild.CrossBuildError as exc:
            raise FmuBuildError(str(exc)) from None
        for name, text in build_recipe_files(identifier, fmi_version).items():
            (src / name).write_text(text, encoding="utf-8")
        (root / "documentation").mkdir()
        (root / "documentation" / "platforms.txt").write_text(platforms_text(binaries, fmi_version),
                                                              encoding="utf-8")
        built = {k: r for k, r in binaries.items() if "missing" not in r}
        for r in built.values():
            r["sha256"] = hashlib.sha256((root / "binaries" / r["folder"] / r["file"]).read_bytes()).hexdigest()
        build_line = "; ".join(sorted({r["command"] for r in built.values()}))
        res = root / "resources"
        res.mkdir()
        write_tables(res, meta_bytes, bin_bytes)
        (res / CONFIG_FILE).write_text(config_text(tables, variables, guid=guid, model_identifier=identifier,
                                                   meta_bytes=meta_bytes, bin_bytes=bin_bytes,
                                                   envelope=runtime_envelope(env_rec), interface=interface,
                                                   node_events=me_node_events,
                                                   nominals=me_nominals(tables, s.pinion_speed_start_rad_s,
                                                                        s.pinion_torque_start_Nm)),
                                       encoding="utf-8")
        (root / ENVELOPE_FILE).write_text(envelope_json(env_rec), encoding="utf-8")
        write_scene(res, scene_text)
        compiler = "; ".join(sorted({r["compiler"] for r in built.values()})) or None
        provenance = {
            "gearfmu_version": __version__, "built_utc": now, "runtime": "standalone", "fmi_version": fmi_version,
            "model_name": model_name, "model_identifier": identifier, "guid": guid,
            "parameters": dict(params, stop_time_s=tstop, output_interval_s=dt),
            "tables_sha256": hashlib.sha256(bin_bytes).hexdigest(), "tables_provenance": tables.provenance,
            "binary": {"compiler": compiler, "flags": list(STANDALONE_CFLAGS), "command": build_line,
                       "platforms": binaries,
                       "sources_sha256": {p.name: hashlib.sha256(p.read_bytes()).hexdigest()
                                          for p in sorted(src.iterdir())}},
            "scene_sha256": scene_sha256(scene_text),
            # the file the C layer reads at instantiation (gearfmu.fmu.integrity checks it before loading)
            "config_sha256": hashlib.sha256((res / CONFIG_FILE).read_bytes()).hexdigest(),
            "python": sys.version.split()[0], "platform": platform.platform(), "spec": Path(spec.path).name,
        }
        (res / "provenance.json").write_text(json.dumps(provenance, indent=1, default=str), encoding="utf-8")
        if validation:
            for rel, data in validation_record(tables, s, runtime="standalone", model_identifier=identifier,
                                               temperature_start_C=temp0, scene_text=scene_text, compiler=compiler,
                                               envelope=env_rec).items():
                p = root / rel
                p.parent.mkdir(parents=True, exist_ok=True)
                p.write_bytes(data)
        md_args = dict(model_name=model_name, model_identifier=identifier, guid=guid, stop_time_s=tstop,
                       step_size_s=dt, generation_tool=f"gearfmu {__version__} (standalone runtime)",
                       generation_date=now, version=__version__, description_note=envelope_note(env_rec),
                       interfaces=INTERFACE_ELEMENTS[interface])
        note = crossbuild.platform_summary(binaries)
        if fmi_version == 3:
            xml = model_description(spec, variables, 3, platforms_note=note, **md_args)
        else:
            xml = standalone_model_description(model_description(spec, variables, 2, **md_args),
                                               binary_sources(2), platforms_note=note)
            check_model_description(xml, variables)
        (root / "modelDescription.xml").write_bytes(xml)
        write_documentation(root, fmi_version=fmi_version, model_name=model_name, model_identifier=identifier,
                            runtime="standalone", generation_tool=md_args["generation_tool"], variables=variables,
                            description=ET.fromstring(xml).get("description", ""), tables=tables,
                            parameters=params, envelope=env_rec, scene_text=scene_text,
                            platforms_text=platforms_text(binaries, fmi_version),
                            experiment={"start": 0.0, "stop": tstop, "step": dt},
                            interfaces=INTERFACE_ELEMENTS[interface])
        with fmu_zip(out_path) as zout:
            zip_folder(zout, root)
    return out_path
