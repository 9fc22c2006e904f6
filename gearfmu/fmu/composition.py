"""Cut a gearbox into stage FMUs and torsional elements: the system of an SSP of stage FMUs.

docs/gearbox.md "The SSP of stage FMUs".  A gearbox (:class:`gearfmu.gearbox.model.GearboxModel`, a
chain motor -> shaft -> stage -> shaft -> ... -> load) becomes components joined at its elastic
shafts:

* one **stage** component per mesh (:class:`gearfmu.fmu.stage_build.StageSpec`): the stage's pinion and
  gear bodies with the inertias they have in the whole gearbox (gear, the halves of the shafts lumped
  there, the parts joined rigidly) on the stage's own tables;
* a **body** component for the motor and for the load when they are not joined rigidly to a stage
  (:class:`gearfmu.fmu.element_build.BodyElement`);
* per elastic shaft, by the coupling (:data:`gearfmu.common.vocabulary.SSP_COUPLINGS`):

  - ``"flange"``: the shaft goes into the stage FMU of the body it drives, the light pinion (the
    output shaft, which drives the load, into the last stage); its far end is a flange of that stage,
    which takes the speed of the body there and returns the torque the shaft transmits.  The stiff
    shaft is integrated with the light inertia it drives; the heavy body at its far end (the motor,
    the previous stage's gear, the load) holds the returned torque over a communication step.
  - ``"shaft"``: the stages take torques at their pinion and gear bodies (the gear-pair FMU's
    interface); a **shaft** component (:class:`gearfmu.fmu.element_build.ShaftElement`) between the
    two bodies integrates the exchanged speeds and returns the shaft torque.

Every joint is a power bond of two ports, each a torque and an angular velocity (the Open Simulation
Platform's AngularMechanicalPort): one side holds the torque it receives and returns its speed, the
other takes the speed and returns the torque.  Port torques are the shaft torque, positive driving
away from the motor, so that torque x speed is the power through the joint on both sides.

A rigid shaft between two stages cannot be cut (a kinematic constraint between two FMUs): refused.
The start values are the gearbox's quasi-static initial state (docs/gearbox.md "Initial state"), so
every component starts where the monolithic model starts.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from ..common.vocabulary import DEFAULT_INTEGRATOR, DEFAULT_SSP_COUPLING, SSP_COUPLINGS
from ..gearbox.model import GearboxModel, Shaft, build_gearbox
from .build_steps import FmuBuildError
from .element_build import BodyElement, ShaftElement, TorqueInput
from .stage_build import StageSpec

__all__ = ["Link", "Port", "Bond", "Component", "Composition", "compose", "CompositionError"]


class CompositionError(FmuBuildError):
    """The gearbox cannot be cut into an SSP of stage FMUs; the message names the shaft or stage."""


@dataclass(frozen=True)
class Link:
    """A connection: ``source``'s output ``source_var`` drives ``target``'s input ``target_var``."""

    source: str
    source_var: str
    target: str
    target_var: str


@dataclass(frozen=True)
class Port:
    """One side of a power bond: the component, its torque and angular-velocity variables and whether
    it takes the torque (``torque_is_input``) or returns it."""

    component: str
    torque: str
    speed: str
    torque_is_input: bool


@dataclass(frozen=True)
class Bond:
    """A power bond between two ports (the body side, which takes the torque, first)."""

    name: str
    a: Port
    b: Port


@dataclass(frozen=True)
class Component:
    """A component of the system: its name (the FMU's model name), kind ("stage", "body", "shaft") and
    the spec its FMU is built from."""

    name: str
    kind: str
    spec: Union[StageSpec, BodyElement, ShaftElement]


@dataclass(frozen=True)
class Composition:
    """The system: components, links, power bonds, the coupling, the gearbox it was cut from and where
    each output of the monolithic gearbox is found (``outputs``: monolithic column -> (component,
    variable))."""

    coupling: str
    model: GearboxModel
    components: Tuple[Component, ...]
    links: Tuple[Link, ...]
    bonds: Tuple[Bond, ...]
    outputs: Dict[str, Tuple[str, str]] = field(default_factory=dict)

    def component(self, name: str) -> Component:
        return next(c for c in self.components if c.name == name)


def _rigid_links(parts: Sequence[str], tag: str) -> List[Shaft]:
    """Rigid shafts joining ``parts`` into one body (as the gearbox joined them)."""
    return [Shaft(f"{tag}~{i}", parts[i], parts[i + 1], None) for i in range(len(parts) - 1)]


def _owners(model: GearboxModel) -> Dict[int, str]:
    """The component that holds each body of ``model``: its stage's name, "motor" or "load";
    CompositionError where a body is joined rigidly to two stages or belongs to none."""
    n = model.n_bodies
    owner: Dict[int, str] = {}
    for m, mesh in enumerate(model.meshes):
        for b in model.mesh_bodies[m]:
            if int(b) in owner:
                other = owner[int(b)]
                raise CompositionError(
                    f"stage {mesh.name}: its body {model.body_name(int(b))} is joined rigidly to stage {other}: an SSP "
                    "of stage FMUs cuts the gearbox at its elastic shafts; give that shaft a stiffness (or build the "
                    "gearbox as one FMU)")
            owner[int(b)] = mesh.name
    owner.setdefault(0, "motor")
    owner.setdefault(model.load_body, "load")
    if len(owner) != n:
        raise CompositionError(f"bodies: {n} bodies but only motor, load and the stages' bodies can be cut into "
                               "components")
    return owner


def _end_bodies(model: GearboxModel, owner: Dict[int, str], tm: float, tl: float, ts, theta0, omega0
                ) -> List[Component]:
    """The body components of the motor and the load where no stage holds them: their inertia, start
    angle (rad) and speed (rad/s), and the torques on them (motor torque tm, load torque tl in N*m,
    the shafts' static torques ts as port inputs)."""
    components: List[Component] = []
    for end, body in (("motor", 0), ("load", model.load_body)):
        if owner[body] != end:
            continue
        torques = []
        if end == "motor" and model.motor_torque_input:
            torques.append(TorqueInput("motor_torque", 1, tm, "Motor torque"))
        for s in range(len(model.shafts)):
            a, b = (int(x) for x in model.shaft_bodies[s])
            if body in (a, b):
                torques.append(TorqueInput(f"{model.shafts[s].name}.torque", -1 if body == a else 1, float(ts[s]),
                                           f"Torque of {model.shafts[s].name} (positive driving away from the motor)",
                                           port=True))
        if end == "load" and model.load_torque_input:
            torques.append(TorqueInput("load_torque", -1, tl, "Load torque"))
        components.append(Component(end, "body", BodyElement(end, float(model.inertia_kgm2[body]), float(theta0[body]),
                                                             float(omega0[body]), tuple(torques))))
    return components


def compose(model: GearboxModel, *, coupling: str = DEFAULT_SSP_COUPLING, motor_torque_Nm: float,
            load_torque_Nm: Optional[float] = None, motor_speed_rad_s: float, motor_angle_rad: float = 0.0,
            max_step_s: float, integrator: str = DEFAULT_INTEGRATOR, flange_order: int = 2) -> Composition:
    """Cut ``model`` into its stage and element components for ``coupling`` (module docstring), every
    component starting from the gearbox's quasi-static state under the start torques (N*m) at the motor
    speed (rad/s) and angle (rad); ``load_torque_Nm`` None: the balancing one.  Every stage integrates
    with ``integrator`` and the largest internal step ``max_step_s`` (s) of the monolithic gearbox;
    ``flange_order``: how a flange moves over a step (:class:`gearfmu.fmu.stage_build.StageSpec`).
    CompositionError naming the shaft or stage that cannot be cut."""
    if coupling not in SSP_COUPLINGS:
        raise CompositionError(f"coupling: {coupling!r} not one of {SSP_COUPLINGS}")
    tl = model.balancing_load_torque_Nm(motor_torque_Nm) if load_torque_Nm is None else float(load_torque_Nm)
    tm = float(motor_torque_Nm) if model.motor_torque_input else 0.0
    tl = tl if model.load_torque_input else 0.0
    t_ref = model.reference_torque_Nm(tm, tl)
    y0 = model.static_state(t_ref, motor_speed_rad_s, motor_angle_rad)
    n = model.n_bodies
    theta0 = np.array([y0[0]] + [model.g[i] * y0[0] + y0[2 * i] for i in range(1, n)])
    omega0 = np.array([y0[1]] + [model.g[i] * y0[1] + y0[2 * i + 1] for i in range(1, n)])
    ts = model.shaft_static_torques_Nm(t_ref)

    owner = _owners(model)
    stages = {mesh.name: m for m, mesh in enumerate(model.meshes)}

    # which stage holds which shaft (flange coupling): the stage of the body the shaft drives, else its driver
    assigned: Dict[str, List[int]] = {name: [] for name in stages}
    for s, (a, b) in enumerate(model.shaft_bodies):
        if coupling == "flange":
            inner = owner[int(b)] if owner[int(b)] in stages else owner[int(a)]
            if inner not in stages:
                raise CompositionError(f"shafts: {model.shafts[s].name} joins the motor and the load directly")
            assigned[inner].append(s)

    def speed_var(body: int) -> str:
        o = owner[body]
        return f"{model.bodies[body][0]}_speed" if o in stages else "speed"

    def angle_var(body: int) -> str:
        o = owner[body]
        return f"{model.bodies[body][0]}_angle" if o in stages else "angle"

    components: List[Component] = []
    links: List[Link] = []
    bonds: List[Bond] = []
    outputs: Dict[str, Tuple[str, str]] = {}
    # ------------------------------------------------------------------ stages
    for name, m in stages.items():
        p, q = (int(x) for x in model.mesh_bodies[m])
        own = assigned[name]
        far = {s: int(model.shaft_bodies[s, 0]) if int(model.shaft_bodies[s, 1]) == p else int(model.shaft_bodies[s, 1])
               for s in own}
        up = [s for s in own if far[s] != q and int(model.shaft_bodies[s, 1]) == p]
        down = [s for s in own if int(model.shaft_bodies[s, 0]) == q]
        flanges = up + down
        bodies = [p, q] + [far[s] for s in flanges]
        extra = {pt: 1.0 for b in bodies for pt in model.bodies[b] if not pt.startswith(f"{name}.")}
        sub_shafts: List[Shaft] = []
        for b in bodies:
            sub_shafts += _rigid_links(model.bodies[b], f"{name}~{b}")
        for s in flanges:
            sh = model.shafts[s]
            sub_shafts.append(Shaft(sh.name, sh.a, sh.b, float(model.shaft_k_Nm_per_rad[s]),
                                    damping_Nms_per_rad=float(model.shaft_c_Nms_per_rad[s])))
        motor_part = model.shafts[up[0]].a if up else ("motor" if "motor" in model.bodies[p] else model.bodies[p][0])
        load_part = model.shafts[down[0]].b if down else ("load" if "load" in model.bodies[q] else model.bodies[q][0])
        out_ports = [s for s in range(len(model.shafts)) if int(model.shaft_bodies[s, 0]) == q and s not in own]
        in_ports = [s for s in range(len(model.shafts)) if int(model.shaft_bodies[s, 1]) == p and s not in own]
        load_is_input = not down and (bool(out_ports) or ("load" in model.bodies[q] and model.load_torque_input))
        sub = build_gearbox([model.meshes[m]], sub_shafts, extra, motor=motor_part, load=load_part,
                            motor_torque_input=True, load_torque_input=load_is_input)
        mono = [model.part_body[sub.bodies[i][0]] for i in range(sub.n_bodies)]
        sub = replace(sub, inertia_kgm2=np.array([model.inertia_kgm2[b] for b in mono]))
        if not np.allclose(sub.g * model.g[mono[0]], model.g[mono], rtol=1e-12, atol=0.0):
            raise CompositionError(f"stage {name}: its kinematic ratios differ from the gearbox's")
        b0 = mono[0]
        if up:
            motor_input, t_in = "reference_torque", t_ref / float(model.g[b0])
        elif "motor" in model.bodies[p] and model.motor_torque_input:
            motor_input, t_in = "motor_torque", tm
        elif in_ports:
            motor_input, t_in = f"{model.shafts[in_ports[0]].name}.torque", float(ts[in_ports[0]])
        else:
            motor_input, t_in = "reference_torque", t_ref / float(model.g[b0])
        if down or not load_is_input:
            load_input, t_out = None, 0.0
        elif out_ports:
            load_input, t_out = f"{model.shafts[out_ports[0]].name}.torque", float(ts[out_ports[0]])
        else:
            load_input, t_out = "load_torque", tl
        spec = StageSpec(name=name, model=sub, flanges=tuple(model.shafts[s].name for s in flanges),
                         motor_input=motor_input, load_input=load_input, reference_torque_Nm=t_in,
                         reference_speed_rad_s=float(omega0[b0]), reference_angle_rad=float(theta0[b0]),
                         load_torque_Nm=t_out, max_step_s=float(max_step_s), integrator=integrator,
                         flange_order=flange_order)
        components.append(Component(name, "stage", spec))
        for col in ("dte", "dte_rate", "mesh_force", "mesh_stiffness"):
            outputs[f"{name}.{col}"] = (name, f"{name}.{col}")
        for i in range(model.meshes[m].tables.slots):
            for col in ("pair_force", "load_sharing"):
                outputs[f"{name}.{col}[{i + 1}]"] = (name, f"{name}.{col}[{i + 1}]")
        for s in flanges:
            outputs[f"{model.shafts[s].name}.torque"] = (name, f"{model.shafts[s].name}.torque")
    components += _end_bodies(model, owner, tm, tl, ts, theta0, omega0)
    # ------------------------------------------------------------------ shafts, links, bonds
    for s, (a, b) in enumerate(model.shaft_bodies):
        a, b = int(a), int(b)
        sh = model.shafts[s].name
        if coupling == "flange":
            inner = next(n for n, own in assigned.items() if s in own)
            fb = a if owner[b] == inner else b
            y = owner[fb]
            links += [Link(inner, f"{sh}.port_torque", y, f"{sh}.torque"),
                      Link(y, speed_var(fb), inner, f"{sh}.flange_speed")]
            bonds.append(Bond(sh, Port(y, f"{sh}.torque", speed_var(fb), True),
                              Port(inner, f"{sh}.port_torque", f"{sh}.flange_speed", False)))
        else:
            k, c = float(model.shaft_k_Nm_per_rad[s]), float(model.shaft_c_Nms_per_rad[s])
            components.append(Component(sh, "shaft", ShaftElement(sh, k, c, float(ts[s]) / k, float(omega0[a]))))
            for end, body, inp in (("upstream", a, "upstream_speed"), ("downstream", b, "downstream_speed")):
                links += [Link(sh, "torque", owner[body], f"{sh}.torque"), Link(owner[body], speed_var(body), sh, inp)]
                bonds.append(Bond(f"{sh}.{end}", Port(owner[body], f"{sh}.torque", speed_var(body), True),
                                  Port(sh, "torque", inp, False)))
    for part in model.parts:
        body = model.part_body[part]
        outputs[f"{part}_speed"] = (owner[body], speed_var(body) if owner[body] not in stages else f"{part}_speed")
        outputs[f"{part}_angle"] = (owner[body], angle_var(body) if owner[body] not in stages else f"{part}_angle")
    return Composition(coupling, model, tuple(components), tuple(links), tuple(bonds), outputs)
