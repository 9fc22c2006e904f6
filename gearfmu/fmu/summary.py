"""What a gearfmu FMU is, in one line: runtime, FMI version and the platforms it carries.

Read from the FMU file itself (modelDescription.xml, ``binaries/``, and the standalone
runtime's ``resources/provenance.json`` for the platforms that could not be built), so the
line printed after ``gearfmu build``, ``gearfmu ssp``, ``gearfmu plan --fmu`` and
``python build_fmu.py`` describes the file that was written, whatever produced it.
"""
from __future__ import annotations

import json
import xml.etree.ElementTree as ET
import zipfile
from typing import Dict, List, Optional

__all__ = ["FmuSummary", "fmu_summary", "read_summary"]

#: what each runtime asks of the importing tool
RUNTIME_NOTES = {
    "standalone": "all C, needs no Python",
    "pythonfmu": "needs Python 3 with numpy in the importing tool, needsExecutionTool=true",
}
#: shared-library suffixes that make a folder of binaries/ a platform
_LIB_SUFFIXES = (".so", ".dll", ".dylib")


class FmuSummary:
    """Runtime, FMI version, platforms carried and platforms not built (with the reason) of an FMU."""

    def __init__(self, runtime: str, fmi_version: str, needs_execution_tool: bool, platforms: List[str],
                 missing: Dict[str, str], darwin_slices: Optional[List[str]] = None,
                 interfaces: str = "Co-Simulation"):
        self.runtime = runtime
        self.interfaces = interfaces
        self.fmi_version = fmi_version
        self.needs_execution_tool = needs_execution_tool
        self.platforms = platforms
        self.missing = missing
        self.darwin_slices = darwin_slices or []

    def line(self) -> str:
        """``runtime standalone (all C, needs no Python), FMI 2.0 Co-Simulation, platforms: linux64,
        aarch64-linux, win64, darwin64 (x86_64 + arm64)``, then the platforms not built and why."""
        plats = []
        fat = "darwin64" in self.platforms and bool(self.darwin_slices)
        for p in self.platforms:
            if p == "aarch64-darwin" and fat and self.fmi_version.startswith("2"):
                continue  # FMI 2: the arm64 slice of darwin64 again, under FMI 3's folder name (said below)
            if p == "darwin64" and self.darwin_slices:
                cpus = sorted(("arm64" if s.startswith("aarch64") else s.split("-")[0] for s in self.darwin_slices),
                              key=lambda c: c != "x86_64")
                p += f" ({' + '.join(cpus)}" + ("; arm64 also as aarch64-darwin" if "aarch64-darwin" in
                                                    self.platforms and self.fmi_version.startswith("2") else "") + ")"
            plats.append(p)
        if self.runtime == "pythonfmu":
            plats = [p + " (the kernel is compiled for the build machine only)" for p in plats]
        note = RUNTIME_NOTES.get(self.runtime, "")
        text = (f"runtime {self.runtime}{f' ({note})' if note else ''}, FMI {self.fmi_version} {self.interfaces}, "
                f"platforms: {', '.join(plats) or 'none'}")
        if self.missing:
            by: Dict[str, List[str]] = {}
            for k, why in self.missing.items():
                by.setdefault(why, []).append(k)
            text += "; NOT built: " + "; ".join(f"{', '.join(ks)} ({why})" for why, ks in by.items())
        return text


def read_summary(fmu_path) -> FmuSummary:
    """The :class:`FmuSummary` of the FMU file at ``fmu_path`` (OSError / zipfile.BadZipFile /
    KeyError for a file that is not an FMU)."""
    with zipfile.ZipFile(fmu_path) as z:  # a path or an open binary file (an FMU inside an SSP)
        names = z.namelist()
        root = ET.fromstring(z.read("modelDescription.xml"))
        prov = {}
        if "resources/provenance.json" in names:
            try:
                prov = json.loads(z.read("resources/provenance.json").decode("utf-8"))
            except ValueError:
                prov = {}
    cs = root.find("CoSimulation")
    needs = (cs.get("needsExecutionTool", "false") if cs is not None else "false") == "true"
    interfaces = " and ".join(n for tag, n in (("CoSimulation", "Co-Simulation"), ("ModelExchange", "Model Exchange"))
                              if root.find(tag) is not None) or "no interface"
    runtime = prov.get("runtime") or ("pythonfmu" if "resources/gearfmu_runtime.json" in names else
                                      "standalone" if "resources/gearfmu_standalone.txt" in names else "unknown")
    folders: List[str] = []
    for n in names:
        parts = n.split("/")
        if len(parts) == 3 and parts[0] == "binaries" and parts[2].endswith(_LIB_SUFFIXES) \
                and parts[1] not in folders:
            folders.append(parts[1])
    report = ((prov.get("binary") or {}).get("platforms") or {}) if isinstance(prov, dict) else {}
    order = [r.get("folder") for r in report.values() if isinstance(r, dict) and r.get("folder")]
    folders.sort(key=lambda f: (order.index(f) if f in order else len(order), f))
    missing = {k: r["missing"] for k, r in report.items() if isinstance(r, dict) and "missing" in r}
    slices = next((r["fat_slices"] for r in report.values() if isinstance(r, dict) and r.get("fat_slices")), None)
    return FmuSummary(runtime, root.get("fmiVersion", "?"), needs, folders, missing, slices, interfaces)


def fmu_summary(fmu_path) -> str:
    """The one-line description of the FMU at ``fmu_path`` (:meth:`FmuSummary.line`)."""
    return read_summary(fmu_path).line()
