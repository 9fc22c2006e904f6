"""The interface of a planetary FMU from the spec ``modeldescription/planetary.toml`` (docs/planetary.md
"The planetary FMU").

The spec is the single source of the inputs' and parameters' names, causality, variability, units,
start values and descriptions, and of the description of every kind of output; it is read by the
gearbox spec's reader (:func:`gearfmu.fmu.gearbox_interface.load_gearbox_spec` with this spec's item
kinds).  This module expands it for a :class:`gearfmu.planetary.model.PlanetaryModel`
(:func:`planetary_variables`): the outputs are the native planetary solver's columns
(:func:`gearfmu.planetary.native.output_units`), in its order and with its names, each with its
absolute position in the planetary kernel's output vector (plkernel.h: :func:`mesh_offset`,
:func:`spring_offset`, :func:`group_offset`); the damping parameters are per stage (a planetary
stage's apply to all its meshes, :func:`damping_items`).  With Model Exchange the continuous states
(the kernel's state vector), their derivatives and every mesh's event indicators follow, as the gearbox
FMU has them (gearfmu.fmu.gearbox_interface).
"""
from __future__ import annotations

import hashlib
import math
import re
from typing import Dict, List, Tuple

from ..planetary.model import PlanetaryModel
from ..planetary.native import output_units
from ..tables.zones import zone_cuts
from .gearbox_interface import DEFAULT_GEARBOX_SPEC_PATH, FEATURES, _relative_index, load_gearbox_spec
from .modeldesc import Spec, SpecError, Variable
from .planetary_kernel import damping_ratio_for

__all__ = ["PLANETARY_SPEC_FORMAT", "DEFAULT_PLANETARY_SPEC_PATH", "load_planetary_spec", "planetary_variables",
           "damping_items", "tables_folders", "mesh_offset", "spring_offset", "group_offset", "n_outputs", "me_indicator_counts"]

PLANETARY_SPEC_FORMAT = "gearfmu-planetary-variables"
#: the item kinds an entry of the spec is repeated for
PER = {"rotation": "{item}_{name}", "translation": "{item}_{name}", "mesh": "{item}.{name}",
       "stage": "{item}.{name}", "spring": "{item}.{name}", "damping": "{item}.{name}", "drive": "{item}_{name}"}
#: the gearbox kernel's output block of a mesh before its pair forces (plkernel.h PL_OUT_PAIR_FORCE)
MESH_SCALARS = 4
DEFAULT_PLANETARY_SPEC_PATH = DEFAULT_GEARBOX_SPEC_PATH.with_name("planetary.toml")


def load_planetary_spec(path=None) -> Spec:
    """Read and check the planetary spec (default ``modeldescription/planetary.toml``); SpecError naming
    the entry and field."""
    return load_gearbox_spec(DEFAULT_PLANETARY_SPEC_PATH if path is None else path,
                             spec_format=PLANETARY_SPEC_FORMAT, per=PER, features=FEATURES)


# ------------------------------------------------------------ output layout
def mesh_offset(model: PlanetaryModel, m: int) -> int:
    """Position of mesh m's block in the planetary kernel's output vector (plkernel.h pl_mesh_offset)."""
    return 2 * model.n_dof + sum(MESH_SCALARS + 2 * t.slots for t in model.mesh_tables[:m])


def spring_offset(model: PlanetaryModel) -> int:
    """Position of the spring forces (plkernel.h pl_spring_offset)."""
    return mesh_offset(model, len(model.mesh_names))


def group_offset(model: PlanetaryModel, g: int) -> int:
    """Position of planetary stage g's load-sharing factors (plkernel.h pl_group_offset)."""
    return spring_offset(model) + len(model.spring_names) + sum(st["planets"] for st in model.stages[:g])


def n_outputs(model: PlanetaryModel) -> int:
    """Length of the planetary kernel's output vector (plkernel.h pl_n_outputs)."""
    return group_offset(model, len(model.stages))


def tables_folders(model: PlanetaryModel) -> List[str]:
    """The resources/ folder of every mesh's tables: meshes with identical tables files (the sun-planet
    meshes of a stage without planet position errors) share the folder of the first of them; a folder
    is named after its first mesh (letters, digits, '.', '_')."""
    first: Dict[str, str] = {}
    out = []
    for nm, t in zip(model.mesh_names, model.mesh_tables):
        key = hashlib.sha256(t.to_bytes()[1]).hexdigest()
        first.setdefault(key, re.sub(r"[^A-Za-z0-9_.]", "_", nm.replace("]", "")))
        out.append(first[key])
    return out


def damping_items(model: PlanetaryModel) -> List[Tuple[str, List[int], float, str]]:
    """(stage name, its mesh indices, damping ratio, damping law) of every stage: the parallel stages,
    then the planetary stages (every sun-planet and ring-planet mesh of the stage)."""
    out = []
    staged = set()
    for st in model.stages:
        staged.update(st["meshes"])
    for m, nm in enumerate(model.mesh_names):
        if m not in staged:
            out.append((nm, [m]))
    out += [(st["name"], list(st["meshes"])) for st in model.stages]
    return [(nm, ms, _stage_zeta(model, nm, ms), model.mesh_damping_model[ms[0]]) for nm, ms in out]


def _stage_zeta(model: PlanetaryModel, name: str, meshes: List[int]) -> float:
    """The one damping ratio that gives every mesh of a stage its per-pair damping exactly in the pair
    kernel's gk_set_damping (:func:`gearfmu.fmu.planetary_kernel.damping_ratio_for`); SpecError if none."""
    for z in dict.fromkeys(damping_ratio_for(model.mesh_tables[m], model.mesh_c[m]) for m in meshes):
        if all(_c_of(model, m, z) == float(model.mesh_c[m]) for m in meshes):
            return z
    raise SpecError(f"stage {name}: its meshes' damping is not one damping ratio's")


def _c_of(model: PlanetaryModel, m: int, zeta: float) -> float:
    """c = 2 zeta sqrt(k_mean m_e) as gk_set_damping evaluates it."""
    t = model.mesh_tables[m]
    i1, i2 = float(t.inertia_pinion_kgm2), float(t.inertia_gear_kgm2)
    r1, r2 = float(t.base_radius_pinion_m), float(t.base_radius_gear_m)
    return 2.0 * zeta * math.sqrt(float(t.k_mean_N_per_m) * (i1 * i2 / (i1 * r2 * r2 + i2 * r1 * r1)))


def me_indicator_counts(model: PlanetaryModel, node_events: bool) -> List[int]:
    """The number of event indicators of every mesh (gk_me_n_indicators): 3 P, P more when its tables
    have contact-zone edges, 2 more with table-node events."""
    return [3 * t.slots + (t.slots if zone_cuts(t) is not None else 0) + (2 if node_events else 0)
            for t in model.mesh_tables]


# ------------------------------------------------------------ expansion
def _outputs(model: PlanetaryModel, by_name: Dict[str, dict]) -> List[Tuple[str, dict, int, str]]:
    """(name, spec entry, output index, unit) of every output, in the native solver's column order."""
    out = []
    for i, nm in enumerate(model.dof_names):
        if model.dof_kind[i] == "rot":
            out += [(f"{nm}_angle", by_name["angle"], 2 * i, None), (f"{nm}_speed", by_name["speed"], 2 * i + 1, None)]
        else:
            out += [(nm, by_name["position"], 2 * i, None), (f"{nm}_rate", by_name["rate"], 2 * i + 1, None)]
    for p in model.parts:
        d = model.part_dof[p]
        if model.dof_names[d] != p:
            out += [(f"{p}_angle", by_name["angle"], 2 * d, None), (f"{p}_speed", by_name["speed"], 2 * d + 1, None)]
    for m, nm in enumerate(model.mesh_names):
        P = model.mesh_tables[m].slots
        base = mesh_offset(model, m)
        for key in ("dte", "dte_rate", "mesh_force", "pair_force", "load_sharing", "mesh_stiffness"):
            ent = by_name[key]
            rel = _relative_index(ent["output_index"], P, key)
            if ent.get("per_slot"):
                out += [(f"{nm}.{key}[{i + 1}]", ent, base + rel + i, None) for i in range(P)]
            else:
                out.append((f"{nm}.{key}", ent, base + rel, None))
    for g, st in enumerate(model.stages):
        out += [(f"{st['name']}.load_sharing_factor[{n + 1}]", by_name["load_sharing_factor"], group_offset(model, g) + n,
                 None) for n in range(st["planets"])]
    units = output_units(model)
    out += [(f"{nm}.force", by_name["force"], spring_offset(model) + s, "N.m" if units[f"{nm}.force"] == "N*m" else "N")
            for s, nm in enumerate(model.spring_names)]
    return out


def _variable(n: int, name: str, ent: dict, *, output_index=None, unit=None, desc=None, start=None,
              derivative_of=None, event_indicator=False, causality=None) -> Variable:
    st = ent.get("start") if start is None else start
    if st is not None:
        st = int(st) if ent["type"] == "Integer" else float(st)
    return Variable(name=name, value_reference=n, type=ent["type"], causality=causality or ent["causality"],
                    variability=ent["variability"], initial=ent.get("initial"), unit=unit or ent.get("unit"),
                    description=desc if desc is not None else ent.get("description", ""), start=st,
                    min=ent.get("min"), max=ent.get("max"), output_index=output_index,
                    build_override=bool(ent.get("build_override", False)), derivative_of=derivative_of,
                    event_indicator=event_indicator)


def planetary_variables(spec: Spec, model: PlanetaryModel, *, model_exchange: bool = False,
                        node_events: bool = False) -> List[Variable]:
    """The spec expanded for ``model`` (module docstring), numbered in order (value reference =
    position): the torque inputs of the ends that are inputs, the speed input of every driven member's
    drive, the outputs (the native solver's
    columns), the parameters (the damping ones per stage), then with ``model_exchange`` the states,
    derivatives and event indicators (``node_events``: the table-node indicators too), their
    indices in the Model Exchange block after the kernel's outputs."""
    by_name = {e["name"]: e for e in spec.entries}
    feats = {"motor_torque_input": model.motor_torque_input, "load_torque_input": model.load_torque_input}
    out: List[Variable] = []
    for e in spec.entries:
        if e["causality"] == "input" and e.get("per") == "drive":   # a driven member's speed input
            for d in model.drives:
                out.append(_variable(len(out), f"{d['port']}_{e['name']}", e,
                                     desc=f"{e.get('description', '')} ({d['port']})"))
        elif e["causality"] == "input" and feats.get(e.get("requires"), True):
            desc = e.get("description", "") + f" ({model.motor if e['name'] == 'motor_torque' else model.load})"
            out.append(_variable(len(out), e["name"], e, desc=desc))
    names = set()
    for name, ent, idx, unit in _outputs(model, by_name):
        item = name.rsplit(".", 1)[0] if "." in name else name
        out.append(_variable(len(out), name, ent, output_index=idx, unit=unit,
                             desc=f"{ent.get('description', '')} ({item})"))
        names.add(name)
    missing = set(output_units(model)) - names - {"motor_torque", "load_torque"}
    if missing:
        raise SpecError(f"the planetary interface lacks native outputs {sorted(missing)}")
    damping = damping_items(model)
    for e in spec.entries:
        if e["causality"] != "parameter":
            continue
        if e.get("per") == "damping":
            for nm, _, _, _ in damping:
                out.append(_variable(len(out), f"{nm}.{e['name']}", e, desc=f"{e.get('description', '')} (stage {nm})"))
        else:
            out.append(_variable(len(out), e["name"], e))
    return out + _me_variables(model, len(out), node_events, model_exchange)


def _me_variables(model: PlanetaryModel, n0: int, node_events: bool, model_exchange: bool) -> List[Variable]:
    """The kernel state [psi, omega, q_i, q_i'] as locals (every planetary FMU shows it: a validation
    starts the native solver there) and, with ``model_exchange``, their derivatives and every mesh's event
    indicators, at their positions in the block after the kernel's outputs (gf_meshes.c)."""
    n2 = 2 * model.n_dof
    base = n_outputs(model)
    real = {"type": "Real", "causality": "local", "variability": "continuous", "initial": "calculated"}
    out: List[Variable] = []
    states = ["reference_angle", "reference_speed"]
    units = ["rad", "rad/s"]
    for i in range(1, model.n_dof):
        nm = model.dof_names[i]
        rot = model.dof_kind[i] == "rot"
        states += [f"{nm}_deviation", f"{nm}_deviation_rate"]
        units += ["rad", "rad/s"] if rot else ["m", "m/s"]
    for k, (s, u) in enumerate(zip(states, units)):
        out.append(_variable(n0 + len(out), s, dict(real, unit=u), output_index=base + k,
                             desc="continuous state %d of the planetary kernel (plkernel.h pl_state)" % k))
    if not model_exchange:
        return out
    for k, (s, u) in enumerate(zip(states, units)):
        du = {"rad": "rad/s", "rad/s": "rad/s2", "m": "m/s", "m/s": "m/s2"}[u]
        out.append(_variable(n0 + len(out), f"der({s})", dict(real, unit=du), output_index=base + n2 + k,
                             derivative_of=s, desc=f"d({s})/dt"))
    ind = base + 2 * n2
    for m, nm in enumerate(model.mesh_names):
        t = model.mesh_tables[m]
        kinds = ["contact_indicator_a", "contact_indicator_b", "contact_indicator_c"]
        if zone_cuts(t) is not None:
            kinds.append("zone_indicator")
        for kind in kinds:
            for i in range(t.slots):
                out.append(_variable(n0 + len(out), f"{nm}.{kind}[{i + 1}]", dict(real, unit="m"), output_index=ind,
                                     event_indicator=True,
                                     desc=f"event indicator of slot {i + 1} of mesh {nm} (docs/model.md)"))
                ind += 1
        if node_events:
            for kind in ("segment_indicator_low", "segment_indicator_high"):
                out.append(_variable(n0 + len(out), f"{nm}.{kind}", dict(real, unit="m"), output_index=ind,
                                     event_indicator=True, desc=f"table-segment event indicator of mesh {nm}"))
                ind += 1
    return out
