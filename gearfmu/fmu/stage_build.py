"""Build a stage FMU of an SSP of stage FMUs: one stage of a gearbox with the shafts assigned to it, in C.

A stage FMU is a gearbox of its own (:class:`gearfmu.gearbox.model.GearboxModel` of the stage's pinion
and gear bodies, the elastic shafts assigned to the stage and, at the far end of each, a *flange*), run
by the stage model (``standalone/stage_model.c``: the gearbox model ``gearbox_model.c`` with flanges)
over the gearbox kernel, from one translation unit (``fmi2_stage_all.c`` / ``fmi3_stage_all.c``).
docs/gearbox.md "The SSP of stage FMUs" describes the coupling; :mod:`gearfmu.fmu.composition` cuts a
gearbox into stages and elements.

The interface is the gearbox FMU's (``modeldescription/gearbox.toml``, expanded for the stage's model
by :mod:`gearfmu.fmu.gearbox_interface`) with these changes:

* the outputs of the flange bodies are left out (the flange is the neighbour's body);
* the gearbox's ``motor_torque`` is ``reference_torque`` when the stage's reference body is a flange
  (it then selects the tables' torque rows only, as the drivetrain's motor torque does in the gearbox
  FMU), else the name of the torque that drives the pinion body (``motor_torque``, or the torque
  ``<shaft>.torque`` of the shaft that drives it); ``load_torque`` likewise (``<shaft>.torque``, or
  ``load_torque``, or absent when the stage ends at a flange);
* ``motor_speed_start`` / ``motor_angle_start`` are ``reference_speed_start`` / ``reference_angle_start``
  (the motion of the stage's reference body at the start);
* for every flange, ``<shaft>.flange_speed`` (input, rad/s: the speed of the flange body) and
  ``<shaft>.port_torque`` (output, N.m: the torque the shaft transmits, positive driving away from
  the motor, predicted for the next communication step).
"""
from __future__ import annotations

import hashlib
import uuid
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

from .. import __version__
from ..common.vocabulary import DEFAULT_INTEGRATOR, GEARBOX_INTEGRATORS, INTEGRATORS
from ..gearbox.model import GearboxModel
from .build_steps import KERNEL_HEADERS, KERNEL_SOURCES, FmuBuildError, variable_table_lines
from .element_build import UnitFmu, build_unit_fmu
from .gearbox_build import (GEARBOX_HEADERS, GEARBOX_SOURCES, STANDALONE_DIR, config_text, stage_folder,
                            start_values, gearbox_settings)
from .gearbox_interface import apply_starts, gearbox_variables, load_gearbox_spec, n_outputs
from .modeldesc import SpecError, Variable

__all__ = ["StageSpec", "stage_variables", "stage_config_text", "build_stage_fmu", "STAGE_UNITS"]

#: the one file a build of a stage FMU of FMI 2 / FMI 3 compiles
STAGE_UNITS = {2: STANDALONE_DIR / "fmi2_stage_all.c", 3: STANDALONE_DIR / "fmi3_stage_all.c"}
LAYERS = {2: STANDALONE_DIR / "fmi2_gear.c", 3: STANDALONE_DIR / "fmi3_gear.c"}
STAGE_FILES = (STANDALONE_DIR / "stage_model.c", STANDALONE_DIR / "stage_model.h")


@dataclass(frozen=True)
class StageSpec:
    """One stage FMU: its component name, its gearbox (the stage's mesh, its bodies with the inertias
    of the whole gearbox's, the shafts assigned to it, flange parts at their far ends), the shafts
    whose far end is a flange (in the order of ``model.shafts``), the FMU names of its torque inputs
    (``motor_input`` on the reference body, ``load_input`` on the load body; None: none), the start
    values (the reference torque, N*m; the reference body's speed, rad/s, and angle, rad; the load
    torque, N*m), the integrator and its largest internal step (s)."""

    name: str
    model: GearboxModel
    flanges: Tuple[str, ...]
    motor_input: str
    load_input: Optional[str]
    reference_torque_Nm: float
    reference_speed_rad_s: float
    reference_angle_rad: float
    load_torque_Nm: float
    max_step_s: float
    integrator: str = DEFAULT_INTEGRATOR
    description: str = ""
    flange_order: int = 2

    @property
    def flange_parts(self) -> Tuple[str, ...]:
        """The part at the flange end of each flange shaft."""
        out = []
        for name in self.flanges:
            s = next(i for i, sh in enumerate(self.model.shafts) if sh.name == name)
            a, b = self.model.shaft_bodies[s]
            body = b if a in self._inner_bodies else a
            out.append(self.model.bodies[body][0])
        return tuple(out)

    @property
    def _inner_bodies(self) -> Tuple[int, ...]:
        m = self.model.mesh_bodies[0]
        return int(m[0]), int(m[1])


RENAMED = {"motor_speed_start": "reference_speed_start", "motor_angle_start": "reference_angle_start"}
#: the torque inputs that are no port (they do not come from a neighbouring FMU)
OWN_INPUTS = ("reference_torque", "motor_torque", "load_torque")
FIRST_STEP_DESCRIPTION = (
    "1: in the first communication step the flanges move as the initial state says and the torques from "
    "neighbouring FMUs hold their start values (the neighbours' initial outputs), as a master that transfers the "
    "initial outputs gives them; for masters that start every connection at 0 (fmpy's SSP master). 0: the values set")

FLANGE_ORDER_DESCRIPTION = (
    "How a flange moves over a communication step: 1 at the speed received; 2 (default) with the acceleration of "
    "the last two speeds received as well (the step cut into the integrator's substeps, the flange on the "
    "parabola)")


def port_inputs(spec) -> Tuple[str, ...]:
    """The stage's torque inputs that come from neighbouring FMUs."""
    return tuple(n for n in (spec.motor_input, spec.load_input) if n is not None and n not in OWN_INPUTS)


def stage_variables(spec: StageSpec) -> List[Variable]:
    """The variables of the stage FMU (module docstring), numbered in order, with the start values."""
    model = spec.model
    if spec.integrator not in GEARBOX_INTEGRATORS:
        raise FmuBuildError(f"{spec.name}.integrator: {spec.integrator!r} not one of {GEARBOX_INTEGRATORS}")
    settings = gearbox_settings(model, None, motor_torque_start_Nm=spec.reference_torque_Nm,
                                load_torque_start_Nm=spec.load_torque_Nm,
                                motor_speed_start_rad_s=spec.reference_speed_rad_s,
                                motor_angle_start_rad=spec.reference_angle_rad, max_step_s=spec.max_step_s,
                                integrator=spec.integrator, stop_time_s=1.0, output_interval_s=1.0)
    try:
        base = apply_starts(gearbox_variables(load_gearbox_spec(), model), start_values(model, settings))
    except SpecError as exc:
        raise FmuBuildError(str(exc)) from None
    rename = dict(RENAMED, motor_torque=spec.motor_input)
    if spec.load_input is not None:
        rename["load_torque"] = spec.load_input
    hidden = {f"{p}_{q}" for p in _flange_part_names(spec) for q in ("speed", "angle")}
    out: List[Variable] = []
    for v in base:
        if v.name in hidden:
            continue
        deps = None if v.initial_dependencies is None else tuple(rename.get(d, d) for d in v.initial_dependencies)
        desc = v.description
        if v.name == "motor_torque" and spec.motor_input == "reference_torque":
            desc = ("Reference torque of the stage (N.m at its reference body, the upstream flange): selects the "
                    "tables' torque rows as the drivetrain's motor torque does in the gearbox FMU")
        out.append(replace(v, name=rename.get(v.name, v.name), value_reference=len(out), initial_dependencies=deps,
                           description=desc))
    out.append(Variable(name="first_step_start_values", value_reference=len(out), type="Integer",
                        causality="parameter", variability="fixed", initial="exact", unit=None,
                        description=FIRST_STEP_DESCRIPTION, start=1, min=0, max=1, output_index=None))
    if spec.flanges:
        if spec.flange_order not in (1, 2):
            raise FmuBuildError(f"{spec.name}.flange_order: must be 1 or 2, got {spec.flange_order!r}")
        out.append(Variable(name="flange_order", value_reference=len(out), type="Integer", causality="parameter",
                            variability="fixed", initial="exact", unit=None, description=FLANGE_ORDER_DESCRIPTION,
                            start=int(spec.flange_order), min=1, max=2, output_index=None))
    k0 = n_outputs(model)
    for k, (shaft, part) in enumerate(zip(spec.flanges, spec.flange_parts)):
        speed0 = _part_speed(spec, part)
        out.append(Variable(name=f"{shaft}.flange_speed", value_reference=len(out), type="Real", causality="input",
                            variability="continuous", initial=None, unit="rad/s",
                            description=f"Speed of the flange at the far end of {shaft} (the body {part} of the "
                                        "neighbouring FMU)", start=speed0, min=None, max=None, output_index=None))
        out.append(Variable(name=f"{shaft}.port_torque", value_reference=len(out), type="Real", causality="output",
                            variability="continuous", initial="calculated", unit="N.m",
                            description=f"Torque {shaft} transmits (positive driving away from the motor), "
                                        "predicted for the middle of the next communication step",
                            start=None, min=None, max=None, output_index=k0 + k,
                            initial_dependencies=None))
    return out


def _flange_part_names(spec: StageSpec) -> Tuple[str, ...]:
    """Every part of the flange bodies."""
    out = []
    for part in spec.flange_parts:
        out += list(spec.model.bodies[spec.model.part_body[part]])
    return tuple(out)


def _part_speed(spec: StageSpec, part: str) -> float:
    """The start speed of a part: its kinematic speed in the stage's model (rad/s)."""
    return float(spec.model.g[spec.model.part_body[part]]) * spec.reference_speed_rad_s


def stage_config_text(spec: StageSpec, variables: Sequence[Variable], stage_bytes, *, guid: str,
                      model_identifier: str) -> str:
    """The gearbox model's configuration (:func:`gearfmu.fmu.gearbox_build.config_text`, with the value
    references of the gearbox's own names) followed by ``extra_outputs`` and the ``flange=`` lines
    (body|shaft|speed input|torque output index) that stage_model.c reads, and the variable table."""
    back = {new: old for old, new in dict(RENAMED, motor_torque=spec.motor_input,
                                          **({"load_torque": spec.load_input} if spec.load_input else {})).items()}
    canonical = [replace(v, name=back.get(v.name, v.name)) for v in variables]
    text = config_text(spec.model, canonical, stage_bytes, guid=guid, model_identifier=model_identifier)
    head = text[:text.index("\nn_vars=") + 1]
    vr = {v.name: v.value_reference for v in variables}
    lines = [f"extra_outputs={len(spec.flanges)}", f"vr.first_step_start_values={vr['first_step_start_values']}"]
    lines += [f"port_torque={vr[name]}" for name in port_inputs(spec)]
    if spec.flanges:
        lines.append(f"vr.flange_order={vr['flange_order']}")
    k0 = n_outputs(spec.model)
    for k, (shaft, part) in enumerate(zip(spec.flanges, spec.flange_parts)):
        s = next(i for i, sh in enumerate(spec.model.shafts) if sh.name == shaft)
        lines.append(f"flange={spec.model.part_body[part]}|{s}|{vr[f'{shaft}.flange_speed']}|{k0 + k}")
    return head + "\n".join(lines + variable_table_lines(variables)) + "\n"


def build_stage_fmu(spec: StageSpec, out_path, *, fmi_version: int = 2, platforms: Optional[Sequence[str]] = None,
                    stop_time_s: float = 0.1, step_size_s: float = 1e-5, cc: Optional[str] = None) -> Path:
    """Build the stage FMU of ``spec`` at ``out_path`` (FMI ``fmi_version`` 2 or 3 Co-Simulation, the
    standalone C runtime); return its path."""
    if len(spec.model.meshes) != 1:
        raise FmuBuildError(f"{spec.name}: a stage FMU holds one mesh, got {len(spec.model.meshes)}")
    variables = stage_variables(spec)
    stage_bytes = [m.tables.to_bytes() for m in spec.model.meshes]
    h = hashlib.sha256()
    for meta, data in stage_bytes:
        h.update(meta)
        h.update(data)
    h.update(repr(spec).encode())
    identifier = f"gearfmu_st_{h.hexdigest()[:12]}_{uuid.uuid4().hex[:8]}"
    guid = "{" + str(uuid.uuid4()) + "}"
    config = stage_config_text(spec, variables, stage_bytes, guid=guid, model_identifier=identifier)
    mesh = spec.model.meshes[0]
    resources: Dict[str, bytes] = {f"{stage_folder(mesh.name)}/tables.json": stage_bytes[0][0],
                                   f"{stage_folder(mesh.name)}/tables.bin": stage_bytes[0][1],
                                   "gearfmu_gearbox.txt": config.encode("utf-8")}
    v = fmi_version if fmi_version in STAGE_UNITS else 2
    files = (LAYERS[v], *GEARBOX_SOURCES, *GEARBOX_HEADERS, *STAGE_FILES, *KERNEL_SOURCES, *KERNEL_HEADERS)
    description = spec.description or (
        f"Stage {mesh.name} of a gearbox for an SSP of stage FMUs: the multi-pair mesh model of seed 003 eq 1-6 on "
        f"the stage's tables with {len(spec.model.shafts)} shaft(s) to {len(spec.flanges)} flange(s) "
        "(docs/gearbox.md), FMI Co-Simulation")
    fmu = UnitFmu(
        unit=STAGE_UNITS[v], files=files, spec=load_gearbox_spec(), variables=variables,
        description=description, model_name=spec.name, identifier=identifier, guid=guid, resources=resources,
        generation_tool=f"gearfmu {__version__} (standalone runtime, stage of a gearbox SSP)",
        provenance={"model": "stage", "stage": mesh.name, "flanges": list(spec.flanges),
                    "integrator": INTEGRATORS[spec.integrator], "max_step_s": spec.max_step_s})
    return build_unit_fmu(out_path, fmu, fmi_version=fmi_version, platforms=platforms, stop_time_s=stop_time_s,
                          step_size_s=step_size_s, cc=cc)
