"""The dynamic model of a gearbox on tables (SI units): bodies, shafts, meshes, ratios, linearisation.

A gearbox is a tree of *bodies* (rigid inertias) joined by elastic *shafts* and gear *meshes*
(docs/gearbox.md "Model").  The parts are named: the end bodies (``motor``, ``load`` by
default; any names in code) and, for every mesh ``m``, ``m.pinion`` and ``m.gear`` (their
inertias are the mesh tables' ``inertia_pinion_kgm2`` and ``inertia_gear_kgm2``).  Rigid shafts
merge parts into one body; a shaft's own inertia is lumped half to each end.

Kinematic reference and deviations (one definition; the native kernels, the reference and
the modes use it): the *reference body* 0 is the motor's body, ``g_0 = 1``; a shaft keeps the
ratio, a mesh multiplies it by ``Rb_p/Rb_q`` (``g`` = body speed / motor speed in steady state,
each angle positive in its body's own driven sense).  The state is

    y = [psi, omega, u_1, du_1, ..., u_{n-1}, du_{n-1}]    (2n values; u_0 = 0 is no state)

with ``psi`` the reference angle, ``omega = psi'``, and ``u_i = theta_i - g_i psi`` the deviation of
body i from its kinematic position.  Mesh m (pinion body p, gear body q) sees the DTE
``x = Rb_p u_p - Rb_q u_q`` (the rigid parts cancel by the definition of g), its rate
``v = Rb_p du_p - Rb_q du_q``, and reads its tables at the pinion angle ``theta_p = g_p psi + u_p``,
speed ``omega_p = g_p omega + du_p``; its force ``F`` (the pair model's per-pair force law,
docs/model.md) acts with ``-Rb_p F`` on p and ``+Rb_q F`` on q.  Shaft s (upstream body a,
downstream b) carries ``T_s = k (u_a - u_b) + c (du_a - du_b)``: ``-T_s`` on a, ``+T_s`` on b.  The
motor torque acts on body 0, the load torque resists on the load's body.  With ``a_i = tau_i/I_i``:
``psi'' = a_0``, ``u_i'' = a_i - g_i a_0``.

:func:`build_gearbox` checks and builds a :class:`GearboxModel`; the orchestration
(:mod:`gearfmu.stages`) builds one from a drivetrain scene and its stages' tables.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Dict, Optional, Sequence, Tuple

import numpy as np

from ..common.checks import finite_number
from ..common.topology import drivetrain_tree
from ..common.vocabulary import DAMPING_MODELS, DEFAULT_DAMPING_MODEL, current_spelling
from ..dynamics.native import NativeInputError, equilibrium_dte_m
from ..tables.mesh_tables import MeshTables
from ..tables.zones import mean_total_stiffness_N_per_m

__all__ = ["GearboxModelError", "Mesh", "Shaft", "GearboxModel", "build_gearbox", "mesh_damping"]


class GearboxModelError(ValueError):
    """Bad gearbox description; the message names the field."""


@dataclass(frozen=True)
class Mesh:
    """A gear mesh (stage) in code: its name (parts ``<name>.pinion``, ``<name>.gear``), its
    tables (no temperature axis), the mesh damping ratio zeta and the per-pair damping law."""

    name: str
    tables: MeshTables
    damping_ratio: float = 0.05
    damping_model: str = DEFAULT_DAMPING_MODEL


@dataclass(frozen=True)
class Shaft:
    """A shaft in code between parts ``a`` and ``b``: torsional stiffness (N*m/rad; None = rigid),
    damping as a ratio or a coefficient (N*m*s/rad; neither = undamped), and its own inertia
    (kg*m^2, lumped half to each end)."""

    name: str
    a: str
    b: str
    stiffness_Nm_per_rad: Optional[float]
    damping_ratio: Optional[float] = None
    damping_Nms_per_rad: Optional[float] = None
    inertia_kgm2: float = 0.0


def mesh_damping(tables: MeshTables, damping_ratio: float) -> Tuple[float, float]:
    """(c, m_e) of a mesh (N*s/m, kg): the pair model's per-pair damping c = 2 zeta sqrt(k_mean m_e)
    with m_e = I1 I2/(I1 Rb2^2 + I2 Rb1^2) of the stage's two gears alone (docs/gearbox.md "Mesh
    damping"), evaluated as docs/model.md pins it: I1*I2/(I1*Rb2*Rb2 + I2*Rb1*Rb1) left to right,
    then 2.0*zeta*sqrt(k_mean*m_e)."""
    i1, i2 = float(tables.inertia_pinion_kgm2), float(tables.inertia_gear_kgm2)
    r1, r2 = float(tables.base_radius_pinion_m), float(tables.base_radius_gear_m)
    me = i1 * i2 / (i1 * r2 * r2 + i2 * r1 * r1)
    return 2.0 * damping_ratio * math.sqrt(float(tables.k_mean_N_per_m) * me), me


def _torque_row(tables: MeshTables, torque_Nm: float) -> np.ndarray:
    """k (P, N) at pinion torque Tq = clamp(torque) by the torque-axis rule of docs/model.md."""
    k = np.asarray(tables.k_N_per_m, dtype=float)
    tq = np.asarray(tables.torque_Nm, dtype=float)
    if tq.size == 1:
        return k[0]
    q = min(max(torque_Nm, tq[0]), tq[-1])
    it = 0
    while it < tq.size - 2 and tq[it + 1] <= q:
        it += 1
    w = (q - tq[it]) / (tq[it + 1] - tq[it])
    return k[it] + w * (k[it + 1] - k[it])


@dataclass(frozen=True)
class GearboxModel:
    """A checked gearbox (SI; module docstring).  Per body: its parts, inertia ``inertia_kgm2``
    and kinematic ratio ``g``; per mesh: the bodies of pinion and gear (``mesh_bodies``), base
    radii, per-pair damping ``mesh_c_Ns_per_m`` and m_e; per elastic shaft: the upstream and
    downstream bodies (``shaft_bodies``), k and c; ``load_body``; which ends are torque
    inputs; ``on_path``: the names of the shafts and meshes on the power path from motor to
    load (the others carry no static torque)."""

    parts: Tuple[str, ...]
    part_body: Dict[str, int]
    bodies: Tuple[Tuple[str, ...], ...]
    inertia_kgm2: np.ndarray
    g: np.ndarray
    meshes: Tuple[Mesh, ...]
    mesh_bodies: np.ndarray
    mesh_rb_m: np.ndarray
    mesh_c_Ns_per_m: np.ndarray
    mesh_me_kg: np.ndarray
    shafts: Tuple[Shaft, ...]
    shaft_bodies: np.ndarray
    shaft_k_Nm_per_rad: np.ndarray
    shaft_c_Nms_per_rad: np.ndarray
    motor: str
    load: str
    load_body: int
    motor_torque_input: bool = True
    load_torque_input: bool = True
    on_path: Tuple[str, ...] = field(default=())
    #: (kind "shaft" or "mesh", index, upstream body, downstream body) of every link, walking order
    tree_edges: Tuple[Tuple[str, int, int, int], ...] = field(default=())

    # ------------------------------------------------------------ sizes and names
    @property
    def n_bodies(self) -> int:
        return int(self.inertia_kgm2.shape[0])

    @property
    def n_state(self) -> int:
        return 2 * self.n_bodies

    def body_name(self, i: int) -> str:
        """A body's name: its parts joined by '+'."""
        return "+".join(self.bodies[i])

    @property
    def load_ratio(self) -> float:
        """Load speed / motor speed (1 / the total ratio)."""
        return float(self.g[self.load_body])

    # ------------------------------------------------------------ static torques
    def reference_torque_Nm(self, motor_torque_Nm: float, load_torque_Nm: float) -> float:
        """The motor-side torque the stages transmit in steady state (N*m): the motor torque when
        it is an input, else the load torque referred to the motor (T_load * g_load)."""
        if self.motor_torque_input:
            return float(motor_torque_Nm)
        return float(load_torque_Nm) * self.load_ratio

    def balancing_load_torque_Nm(self, motor_torque_Nm: float) -> float:
        """The load torque that balances a motor torque in steady state, T_motor / g_load (N*m)."""
        return float(motor_torque_Nm) / self.load_ratio

    def stage_torques_Nm(self, reference_torque_Nm: float) -> np.ndarray:
        """Static pinion torque of every mesh (N*m): T_ref/g_p on the power path, 0 elsewhere; it
        selects each mesh's torque row (docs/model.md "Torque axis")."""
        out = np.zeros(len(self.meshes))
        for m, mesh in enumerate(self.meshes):
            if mesh.name in self.on_path:
                out[m] = reference_torque_Nm / self.g[self.mesh_bodies[m, 0]]
        return out

    def shaft_static_torques_Nm(self, reference_torque_Nm: float) -> np.ndarray:
        """Static torque of every elastic shaft (N*m, positive driving away from the motor)."""
        out = np.zeros(len(self.shafts))
        for s, sh in enumerate(self.shafts):
            if sh.name in self.on_path:
                out[s] = reference_torque_Nm / self.g[self.shaft_bodies[s, 0]]
        return out

    # ------------------------------------------------------------ linearisation
    def mean_mesh_stiffness_N_per_m(self, reference_torque_Nm: float) -> np.ndarray:
        """kbar of every mesh (N/m): the mean over the table period of the total stiffness at the
        mesh's static pinion torque, as the kernels look it up (tables.zones.mean_total_stiffness)."""
        tq = self.stage_torques_Nm(reference_torque_Nm)
        return np.array([mean_total_stiffness_N_per_m(m.tables, _torque_row(m.tables, float(tq[i])))
                         for i, m in enumerate(self.meshes)])

    def mean_pairs_in_contact(self, reference_torque_Nm: float) -> np.ndarray:
        """Mean number of tooth pairs with k > 0 of every mesh over its table grid (at its static
        torque): the factor of the per-pair damping in the linearised mesh damping."""
        tq = self.stage_torques_Nm(reference_torque_Nm)
        return np.array([float((_torque_row(m.tables, float(tq[i])) > 0.0).sum(axis=0).mean())
                         for i, m in enumerate(self.meshes)])

    def linearisation(self, reference_torque_Nm: float, mesh_stiffness_N_per_m=None):
        """(M, K, C) in absolute body angles (n x n): M = diag(I); K = sum_shafts k (e_a - e_b)(e_a -
        e_b)^T + sum_meshes kbar r r^T with r = Rb_p e_p - Rb_q e_q; C likewise with the shaft
        dampers and n_c c per mesh (n_c: :meth:`mean_pairs_in_contact`).  ``mesh_stiffness_N_per_m``
        replaces kbar (e.g. the largest total stiffness for a step bound)."""
        n = self.n_bodies
        M = np.diag(self.inertia_kgm2.astype(float))
        K = np.zeros((n, n))
        C = np.zeros((n, n))
        for s in range(len(self.shafts)):
            a, b = self.shaft_bodies[s]
            d = np.zeros(n)
            d[a] += 1.0
            d[b] -= 1.0
            K += self.shaft_k_Nm_per_rad[s] * np.outer(d, d)
            C += self.shaft_c_Nms_per_rad[s] * np.outer(d, d)
        kbar = (self.mean_mesh_stiffness_N_per_m(reference_torque_Nm) if mesh_stiffness_N_per_m is None
                else np.asarray(mesh_stiffness_N_per_m, dtype=float))
        nc = self.mean_pairs_in_contact(reference_torque_Nm)
        for m in range(len(self.meshes)):
            r = self.mesh_vector(m)
            K += kbar[m] * np.outer(r, r)
            C += nc[m] * self.mesh_c_Ns_per_m[m] * np.outer(r, r)
        return M, K, C

    def mesh_vector(self, m: int) -> np.ndarray:
        """r_m: the DTE of mesh m as a linear function of the absolute body angles, x = r.theta."""
        r = np.zeros(self.n_bodies)
        p, q = self.mesh_bodies[m]
        r[p] += self.mesh_rb_m[m, 0]
        r[q] -= self.mesh_rb_m[m, 1]
        return r

    # ------------------------------------------------------------ initial state
    def static_state(self, reference_torque_Nm: float, speed_rad_s: float, angle_rad: float = 0.0) -> np.ndarray:
        """The quasi-static equilibrium under the reference torque (docs/gearbox.md "Initial
        state"): psi = ``angle_rad``, every body at its kinematic speed (omega = ``speed_rad_s``,
        du = 0), every shaft twisted by its static torque over k, every mesh at the pair model's
        bisection equilibrium at its pinion angle under F = T_p/Rb_p; walked from body 0 along the
        tree.  Raises GearboxModelError naming a mesh with no pair in contact there."""
        n = self.n_bodies
        y = np.zeros(2 * n)
        y[0] = angle_rad
        y[1] = speed_rad_s
        u = np.zeros(n)
        ts = self.shaft_static_torques_Nm(reference_torque_Nm)
        tm = self.stage_torques_Nm(reference_torque_Nm)
        for kind, e, up, down in self.tree_edges:
            if kind == "shaft":
                u[down] = u[up] - ts[e] / self.shaft_k_Nm_per_rad[e]
            else:
                p, q = self.mesh_bodies[e]
                theta_p = self.g[p] * angle_rad + u[p]
                try:
                    x = equilibrium_dte_m(self.meshes[e].tables, float(tm[e]), theta_p)
                except NativeInputError as exc:
                    raise GearboxModelError(f"meshes[{e}] ({self.meshes[e].name}): {exc}") from None
                rb_p, rb_q = self.mesh_rb_m[e]
                u[q] = (rb_p * u[p] - x) / rb_q
        y[2::2] = u[1:]
        return y


def _check_mesh(i: int, m: Mesh) -> Mesh:
    if not isinstance(m, Mesh):
        raise GearboxModelError(f"meshes[{i}]: expected gearfmu.gearbox.model.Mesh, got {type(m).__name__}")
    if not isinstance(m.tables, MeshTables):
        raise GearboxModelError(f"meshes[{i}].tables: expected MeshTables, got {type(m.tables).__name__}")
    if m.tables.has_temperature_axis:
        raise GearboxModelError(f"meshes[{i}].tables: have a temperature axis; select one with "
                                "tables.at_temperature(T)")
    m.tables.validate()
    finite_number(f"meshes[{i}].damping_ratio", m.damping_ratio, nonneg=True, error=GearboxModelError)
    model = current_spelling("damping_model", m.damping_model, where=f"meshes[{i}].damping_model")
    if model not in DAMPING_MODELS:
        raise GearboxModelError(f"meshes[{i}].damping_model: {m.damping_model!r} not one of {sorted(DAMPING_MODELS)}")
    return Mesh(m.name, m.tables, float(m.damping_ratio), model)


def build_gearbox(meshes: Sequence[Mesh], shafts: Sequence[Shaft] = (), parts: Optional[Dict[str, float]] = None, *,
                  motor: str = "motor", load: str = "load", motor_torque_input: bool = True,
                  load_torque_input: bool = True) -> GearboxModel:
    """Check and build a :class:`GearboxModel`.

    ``meshes``: the stages (their parts ``<name>.pinion``, ``<name>.gear`` with the tables'
    inertias); ``shafts``: the links between parts (rigid or elastic); ``parts``: further parts
    and their inertias (kg*m^2), e.g. ``{"motor": 0.02, "load": 1.5}``; ``motor``, ``load``: the
    parts where the motor torque drives and the load torque resists (a single pair in code:
    ``motor="<mesh>.pinion", load="<mesh>.gear"``).  The topology rules are those of
    :mod:`gearfmu.common.topology`; a shaft damping ratio gives c = 2 zeta sqrt(k I_a I_b/(I_a + I_b))
    with the inertias of the two end bodies (after merging and lumping)."""
    meshes = tuple(_check_mesh(i, m) for i, m in enumerate(meshes))
    if not meshes:
        raise GearboxModelError("meshes: a gearbox needs at least one mesh")
    inertia: Dict[str, float] = {}
    for name, val in (parts or {}).items():
        inertia[str(name)] = finite_number(f"parts[{name!r}]", val, positive=True, error=GearboxModelError)
    names = set()
    for i, m in enumerate(meshes):
        if m.name in names:
            raise GearboxModelError(f"meshes[{i}].name: {m.name!r} given twice")
        names.add(m.name)
        for role, val in (("pinion", m.tables.inertia_pinion_kgm2), ("gear", m.tables.inertia_gear_kgm2)):
            p = f"{m.name}.{role}"
            if p in inertia:
                raise GearboxModelError(f"parts: {p!r} is a part of mesh {m.name!r} (its inertia comes from the tables)")
            inertia[p] = float(val)
    for end, what in ((motor, "motor"), (load, "load")):
        if end not in inertia:
            raise GearboxModelError(f"{what}: {end!r} is not a part; parts are {sorted(inertia)}")
    if motor == load:
        raise GearboxModelError(f"load: {load!r} is the motor's part too")
    if not (motor_torque_input or load_torque_input):
        raise GearboxModelError("motor_torque_input, load_torque_input: at least one end must be a torque input")
    for i, s in enumerate(shafts):
        if s.name in names:
            raise GearboxModelError(f"shafts[{i}].name: {s.name!r} is already the name of a mesh or shaft")
        names.add(s.name)
        for end in (s.a, s.b):
            if end not in inertia:
                raise GearboxModelError(f"shafts[{i}] ({s.name}): {end!r} is not a part; parts are {sorted(inertia)}")
        if s.stiffness_Nm_per_rad is not None:
            finite_number(f"shafts[{i}].stiffness_Nm_per_rad", s.stiffness_Nm_per_rad, positive=True,
                          error=GearboxModelError)
        finite_number(f"shafts[{i}].inertia_kgm2", s.inertia_kgm2, nonneg=True, error=GearboxModelError)
        if s.damping_ratio is not None and s.damping_Nms_per_rad is not None:
            raise GearboxModelError(f"shafts[{i}] ({s.name}): give damping_ratio or damping_Nms_per_rad, not both")
    part_names = tuple(inertia)
    nm = len(meshes)
    # meshes first: a loop is then reported at the shaft that closes it
    links = [("mesh", f"{m.name}.pinion", f"{m.name}.gear") for m in meshes]
    links += [("rigid" if s.stiffness_Nm_per_rad is None else "shaft", s.a, s.b) for s in shafts]
    tree = drivetrain_tree(part_names, links, motor)
    if tree.problems:
        li, part, reason = tree.problems[0]
        where = (f"meshes[{li}] ({meshes[li].name})" if li is not None and li < nm
                 else f"shafts[{li - nm}] ({shafts[li - nm].name})" if li is not None else part)
        raise GearboxModelError(f"{where}: {reason}")
    n = len(tree.bodies)
    I = np.zeros(n)
    for p, val in inertia.items():
        I[tree.body_of[p]] += val
    for s in shafts:  # a shaft's own inertia: half to each end
        I[tree.body_of[s.a]] += 0.5 * s.inertia_kgm2
        I[tree.body_of[s.b]] += 0.5 * s.inertia_kgm2
    g = np.ones(n)
    mesh_bodies = np.zeros((len(meshes), 2), dtype=np.int64)
    rb = np.zeros((len(meshes), 2))
    elastic = [i for i, s in enumerate(shafts) if s.stiffness_Nm_per_rad is not None]
    shaft_index = {nm + i: k for k, i in enumerate(elastic)}
    shaft_bodies = np.zeros((len(elastic), 2), dtype=np.int64)
    edges = []
    for li, up, down in tree.edges:
        kind = links[li][0]
        if kind == "mesh":
            m = li
            t = meshes[m].tables
            rb[m] = (float(t.base_radius_pinion_m), float(t.base_radius_gear_m))
            g[down] = g[up] * (rb[m, 0] / rb[m, 1])
            mesh_bodies[m] = (up, down)
            edges.append(("mesh", m, up, down))
        else:
            g[down] = g[up]
            k = shaft_index[li]
            shaft_bodies[k] = (up, down)
            edges.append(("shaft", k, up, down))
    ks = np.array([float(shafts[i].stiffness_Nm_per_rad) for i in elastic])
    cs = np.zeros(len(elastic))
    for k, i in enumerate(elastic):
        s = shafts[i]
        if s.damping_Nms_per_rad is not None:
            cs[k] = finite_number(f"shafts[{i}].damping_Nms_per_rad", s.damping_Nms_per_rad, nonneg=True,
                                  error=GearboxModelError)
        elif s.damping_ratio is not None:
            zeta = finite_number(f"shafts[{i}].damping_ratio", s.damping_ratio, nonneg=True, error=GearboxModelError)
            a, b = shaft_bodies[k]
            ired = I[a] * I[b] / (I[a] + I[b])
            cs[k] = 2.0 * zeta * math.sqrt(ks[k] * ired)
    c_me = [mesh_damping(m.tables, m.damping_ratio) for m in meshes]
    load_body = tree.body_of[load]
    path = tree.path(0, load_body)
    on_path = []
    for e in path:
        li = tree.edges[e][0]
        on_path.append(meshes[li].name if li < nm else shafts[li - nm].name)
    model = GearboxModel(
        parts=part_names, part_body=dict(tree.body_of), bodies=tree.bodies, inertia_kgm2=I, g=g, meshes=meshes,
        mesh_bodies=mesh_bodies, mesh_rb_m=rb, mesh_c_Ns_per_m=np.array([c for c, _ in c_me]),
        mesh_me_kg=np.array([me for _, me in c_me]), shafts=tuple(shafts[i] for i in elastic),
        shaft_bodies=shaft_bodies, shaft_k_Nm_per_rad=ks, shaft_c_Nms_per_rad=cs, motor=motor, load=load,
        load_body=load_body, motor_torque_input=bool(motor_torque_input), load_torque_input=bool(load_torque_input),
        on_path=tuple(on_path), tree_edges=tuple(edges))
    return model
