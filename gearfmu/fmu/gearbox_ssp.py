"""The files of an SSP of stage FMUs: every component's FMU, the system structure, the OSP port annotations.

:func:`write_composition` writes into a folder (which :func:`gearfmu.ssp.gearbox_ssp` checks against the
SSP 1.0 schema and zips)::

    SystemStructure.ssd                  the system "gearbox": one component per FMU, the connectors
                                         (every output, every input a connection drives), the connections;
                                         DefaultExperiment with libcosim's fixed-step annotation
    OspSystemStructure.xml               the same system for the Open Simulation Platform (libcosim):
                                         simulators, every power bond a connection of two ports
    resources/<component>.fmu           the stage, body and shaft FMUs
    resources/<component>_OspModelDescription.xml
                                         the component's mechanical ports, each an OSP
                                         AngularMechanicalPort (Torque + AngularVelocity)

Inputs that no connection drives (the motor and load torques, a stage's reference torque) are no
connectors: they keep the start values the FMUs were built with, which every engine tried applies
(fmpy writes 0 into an input connector nothing drives; libcosim and ecos refuse a connection to a
system connector; docs/fmu_import.md "SSP packages").  The system has no connectors of its own.
"""
from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Dict, Optional, Sequence

from .composition import Composition
from .element_build import build_element_fmu
from .stage_build import build_stage_fmu

__all__ = ["build_component_fmus", "write_composition", "ssd_xml", "osp_system_xml", "osp_model_description_xml",
           "SYSTEM_NAME", "OSP_MD_NS", "OSP_SS_NS", "fmu_variables"]

NS = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
      "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
      "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
      "osp": "http://opensimulationplatform.com/SSP/OSPAnnotations"}
for _p, _u in NS.items():
    ET.register_namespace(_p, _u)
#: namespaces of the OSP interface specification's model description and of libcosim's system structure
OSP_MD_NS = "http://opensimulationplatform.com/MSMI/OSPModelDescription"
OSP_SS_NS = "http://opensimulationplatform.com/MSMI/OSPSystemStructure"
SYSTEM_NAME = "gearbox"
_BASE = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")


def _q(prefix: str, tag: str) -> str:
    return f"{{{NS[prefix]}}}{tag}"


def build_component_fmus(comp: Composition, folder, *, fmi_version: int = 2, platforms: Optional[Sequence[str]] = None,
                         stop_time_s: float = 0.1, step_size_s: float = 1e-5) -> Dict[str, Path]:
    """Build every component's FMU into ``folder`` as ``<component>.fmu``; {component: path}."""
    folder = Path(folder)
    out = {}
    for c in comp.components:
        path = folder / f"{c.name}.fmu"
        kw = dict(fmi_version=fmi_version, platforms=platforms, stop_time_s=stop_time_s, step_size_s=step_size_s)
        out[c.name] = build_stage_fmu(c.spec, path, **kw) if c.kind == "stage" else build_element_fmu(c.spec, path, **kw)
    return out


def fmu_variables(fmu_path) -> Dict[str, dict]:
    """{name: {"causality", "unit", "type", "vr"}} of an FMU, and its units {name: base exponents}."""
    import fmpy  # fmpy: heavy, only to read the FMU

    md = fmpy.read_model_description(str(fmu_path))
    units = {}
    for u in md.unitDefinitions:
        bu = u.baseUnit
        units[u.name] = {} if bu is None else {k: getattr(bu, k) for k in _BASE if getattr(bu, k, 0)}
    variables = {v.name: {"causality": v.causality, "unit": v.unit if v.unit is not None else
                          (v.declaredType.unit if getattr(v, "declaredType", None) is not None else None),
                          "type": v.type, "vr": v.valueReference} for v in md.modelVariables}
    return {"variables": variables, "units": units, "model_name": md.modelName}


def ssd_xml(comp: Composition, interfaces: Dict[str, dict], *, stop_time_s: float, step_size_s: float,
            name: str, description: str) -> bytes:
    """``SystemStructure.ssd``: the system of ``comp`` (``interfaces``: :func:`fmu_variables` of every
    component's FMU)."""
    root = ET.Element(_q("ssd", "SystemStructureDescription"),
                      {"version": "1.0", "name": name, "generationTool": "gearfmu", "description": description})
    system = ET.SubElement(root, _q("ssd", "System"), {"name": SYSTEM_NAME, "description": description})
    elements = ET.SubElement(system, _q("ssd", "Elements"))
    driven = {(ln.target, ln.target_var) for ln in comp.links}
    units: Dict[str, dict] = {}
    for c in comp.components:
        itf = interfaces[c.name]
        el = ET.SubElement(elements, _q("ssd", "Component"), {"name": c.name, "type": "application/x-fmu-sharedlibrary",
                                                            "source": f"resources/{c.name}.fmu"})
        conns = ET.SubElement(el, _q("ssd", "Connectors"))
        for vname, v in itf["variables"].items():
            if v["causality"] == "output" or (v["causality"] == "input" and (c.name, vname) in driven):
                ce = ET.SubElement(conns, _q("ssd", "Connector"), {"name": vname, "kind": v["causality"]})
                if v["type"] == "Integer":
                    ET.SubElement(ce, _q("ssc", "Integer"))
                else:
                    ET.SubElement(ce, _q("ssc", "Real"), {"unit": v["unit"]} if v["unit"] else {})
                    if v["unit"]:
                        units[v["unit"]] = itf["units"].get(v["unit"], {})
    connections = ET.SubElement(system, _q("ssd", "Connections"))
    for ln in comp.links:
        ET.SubElement(connections, _q("ssd", "Connection"), {"startElement": ln.source, "startConnector": ln.source_var,
                                                          "endElement": ln.target, "endConnector": ln.target_var})
    if units:
        ue = ET.SubElement(root, _q("ssd", "Units"))
        for u in sorted(units):
            un = ET.SubElement(ue, _q("ssc", "Unit"), {"name": u})
            ET.SubElement(un, _q("ssc", "BaseUnit"), {k: str(e) for k, e in units[u].items()})
    de = ET.SubElement(root, _q("ssd", "DefaultExperiment"), {"startTime": "0.0", "stopTime": repr(float(stop_time_s))})
    ann = ET.SubElement(ET.SubElement(de, _q("ssd", "Annotations")), _q("ssc", "Annotation"),
                        {"type": "com.opensimulationplatform"})
    ET.SubElement(ET.SubElement(ann, _q("osp", "Algorithm")), _q("osp", "FixedStepAlgorithm"),
                  {"baseStepSize": repr(float(step_size_s))})
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="utf-8", xml_declaration=True)


def osp_model_description_xml(comp: Composition, component: str, units: Dict[str, dict]) -> bytes:
    """``<component>_OspModelDescription.xml``: the component's ports as OSP AngularMechanicalPorts."""
    root = ET.Element(f"{{{OSP_MD_NS}}}OspModelDescription", {"version": "0.1"})
    ud = ET.SubElement(root, f"{{{OSP_MD_NS}}}UnitDefinitions")
    for u in ("N.m", "rad/s"):
        ET.SubElement(ET.SubElement(ud, f"{{{OSP_MD_NS}}}Unit", {"name": u}), f"{{{OSP_MD_NS}}}BaseUnit",
                      {k: str(e) for k, e in units.get(u, {}).items()})
    groups = ET.SubElement(root, f"{{{OSP_MD_NS}}}VariableGroups")
    for b in comp.bonds:
        for port in (b.a, b.b):
            if port.component != component:
                continue
            g = ET.SubElement(groups, f"{{{OSP_MD_NS}}}AngularMechanicalPort", {"name": b.name})
            ET.SubElement(ET.SubElement(g, f"{{{OSP_MD_NS}}}Torque", {"name": f"{b.name}.torque"}),
                          f"{{{OSP_MD_NS}}}Variable", {"ref": port.torque, "unit": "N.m"})
            ET.SubElement(ET.SubElement(g, f"{{{OSP_MD_NS}}}AngularVelocity", {"name": f"{b.name}.angular_velocity"}),
                          f"{{{OSP_MD_NS}}}Variable", {"ref": port.speed, "unit": "rad/s"})
    ET.indent(root, space="  ")
    ET.register_namespace("", OSP_MD_NS)
    return ET.tostring(root, encoding="utf-8", xml_declaration=True)


def osp_system_xml(comp: Composition, *, step_size_s: float, stop_time_s: Optional[float] = None) -> bytes:
    """``OspSystemStructure.xml`` (libcosim's format): the simulators (the FMUs in resources/), the fixed-step
    algorithm at ``step_size_s``, every power bond as a VariableGroupConnection of the two ports'
    AngularMechanicalPort groups (the components' OspModelDescription files), every other link as a
    VariableConnection.  The bonds carry no ``powerBond`` attribute: libcosim refuses a configuration
    with more than one (its check of the bond names runs after the first bond); its ECCO algorithm takes
    the bonds from :func:`gearfmu.fmu.ssp_engines.run_libcosim` instead."""
    ns = f"{{{OSP_SS_NS}}}"
    root = ET.Element(f"{ns}OspSystemStructure", {"version": "0.1"})
    ET.SubElement(root, f"{ns}StartTime").text = "0.0"
    if stop_time_s is not None:
        ET.SubElement(root, f"{ns}EndTime").text = repr(float(stop_time_s))
    ET.SubElement(root, f"{ns}BaseStepSize").text = repr(float(step_size_s))
    ET.SubElement(root, f"{ns}Algorithm").text = "fixedStep"
    sims = ET.SubElement(root, f"{ns}Simulators")
    for c in comp.components:
        ET.SubElement(sims, f"{ns}Simulator", {"name": c.name, "source": f"resources/{c.name}.fmu"})
    conns = ET.SubElement(root, f"{ns}Connections")
    in_bond = set()
    for b in comp.bonds:
        tin, tout = (b.a, b.b) if b.a.torque_is_input else (b.b, b.a)
        in_bond |= {(tout.component, tout.torque, tin.component, tin.torque),
                    (tin.component, tin.speed, tout.component, tout.speed)}
    for ln in comp.links:
        if (ln.source, ln.source_var, ln.target, ln.target_var) not in in_bond:
            vc = ET.SubElement(conns, f"{ns}VariableConnection")
            ET.SubElement(vc, f"{ns}Variable", {"simulator": ln.target, "name": ln.target_var})
            ET.SubElement(vc, f"{ns}Variable", {"simulator": ln.source, "name": ln.source_var})
    for b in comp.bonds:
        gc = ET.SubElement(conns, f"{ns}VariableGroupConnection")
        for port in (b.a, b.b):
            ET.SubElement(gc, f"{ns}VariableGroup", {"simulator": port.component, "name": b.name})
    ET.indent(root, space="  ")
    ET.register_namespace("", OSP_SS_NS)
    return ET.tostring(root, encoding="utf-8", xml_declaration=True)


def write_composition(comp: Composition, folder, *, stop_time_s: float, step_size_s: float, name: str,
                      description: str, fmi_version: int = 2, platforms: Optional[Sequence[str]] = None,
                      fmus: Optional[Dict[str, Path]] = None) -> Path:
    """Write the SSP's files for ``comp`` into ``folder`` (module docstring); ``fmus``: FMUs already built
    ({component: path}; None: build them).  Returns ``folder``."""
    folder = Path(folder)
    res = folder / "resources"
    res.mkdir(parents=True, exist_ok=True)
    if fmus is None:
        fmus = build_component_fmus(comp, res, fmi_version=fmi_version, platforms=platforms, stop_time_s=stop_time_s,
                                    step_size_s=step_size_s)
    else:
        for cname, p in fmus.items():
            if Path(p).resolve() != (res / f"{cname}.fmu").resolve():
                (res / f"{cname}.fmu").write_bytes(Path(p).read_bytes())
    interfaces = {c.name: fmu_variables(res / f"{c.name}.fmu") for c in comp.components}
    for c in comp.components:
        itf = interfaces[c.name]
        (res / f"{itf['model_name']}_OspModelDescription.xml").write_bytes(
            osp_model_description_xml(comp, c.name, itf["units"]))
    (folder / "SystemStructure.ssd").write_bytes(ssd_xml(comp, interfaces, stop_time_s=stop_time_s,
                                                         step_size_s=step_size_s, name=name, description=description))
    (folder / "OspSystemStructure.xml").write_bytes(osp_system_xml(comp, step_size_s=step_size_s,
                                                                   stop_time_s=stop_time_s))
    return folder
