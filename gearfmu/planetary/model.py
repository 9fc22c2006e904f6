"""The dynamic model of a drivetrain with planetary stages (SI units): degrees of freedom, springs,
meshes, kinematic ratios, the linearisation and the quasi-static state (docs/planetary.md "Model").

A drivetrain here is the gearbox of gearfmu.gearbox.model (end bodies, parallel-axis meshes,
shafts) plus planetary stages.  A :class:`PlanetaryStage` has three ports, the parts
``<name>.sun``, ``<name>.carrier`` and ``<name>.ring``; one of them is *held* (grounded through its
torsional support), the other two join the drivetrain tree like the two gears of a mesh (link kind
``planetary`` of gearfmu.common.topology), their kinematic ratio by the Willis equation.

Degrees of freedom (DOF 0 is the motor body's rotation psi, the reference; every other DOF i is a
deviation q_i from its kinematic motion; the state is y = [psi, omega, q_1, q_1', ...]):

* one rotation per torsional body of the tree (absolute angle g_i psi + q_i, each positive in its
  body's own sense as in the gearbox), and one per held member (g = 0);
* per planetary stage, rotation of every planet (absolute spin g_p psi + q, counter-clockwise);
* translational model (Lin & Parker 1999): the translations x, y of sun, ring and carrier, and the
  radial and tangential displacements zeta_n, eta_n of every planet, all in the frame that turns
  with the carrier's kinematic angle g_c psi (planet n's axes along and across its carrier radius
  at psi_n); torsional model (Kahraman 1994): no translations, the planets ride rigidly on the
  carrier (their mass adds m_p r_c^2 to the carrier's inertia).

Stage angles follow Lin & Parker: counter-clockwise, the carrier, sun, ring and planets.  With
the sun as the stage's reference sense: the carrier's, sun's and ring's body angles are the
stage's angles.

Mesh deflections (Lin & Parker 1999, J. Vib. Acoust. 121, eq 1-2; base radii r_s, r_p, r_r,
carrier radius r_c, operating pressure angles alpha_s, alpha_r, psi_sn = psi_n - alpha_s,
psi_rn = psi_n + alpha_r):

    delta_sn = -x_s sin psi_sn + y_s cos psi_sn - zeta_n sin alpha_s - eta_n cos alpha_s + r_s q_s + r_p q_n
    delta_rn = -x_r sin psi_rn + y_r cos psi_rn + zeta_n sin alpha_r - eta_n cos alpha_r + r_r q_r - r_p q_n
    torsional: delta_sn = r_s q_s + r_p q_n - r_c cos(alpha_s) q_c,  delta_rn = r_r q_r - r_p q_n - r_c cos(alpha_r) q_c

and the planet bearing deflections delta_zeta = x_c cos psi_n + y_c sin psi_n - zeta_n,
delta_eta = -x_c sin psi_n + y_c cos psi_n + r_c q_c - eta_n.  The rigid parts cancel by the Willis
equation (r_s (g_s - g_c) + r_p (g_p - g_c) = 0, r_r (g_r - g_c) - r_p (g_p - g_c) = 0).  The pair model
of every mesh (per-pair stiffness, damping, meshing error, backlash on its own tables) sees
x_sn = sigma delta_sn, x_rn = -sigma' delta_rn, sigma' = -sigma, and reads its tables at
sigma (theta_s - theta_c) + phi_sn (the sun the pinion) and sigma' (theta_p - theta_c) + phi_rn (the
planet the pinion), phi the mesh phases of gearfmu.gear.phasing; sigma is the sign of the sun's static
torque in the stage's sense (the tables' drive flank is the flank the static load presses: x > 0;
the tables run forwards when the sun drives the planets, backwards when it is driven); the planets'
position errors shift the meshing errors (gearfmu.gear.planetary_set).

Every element is linear in the DOFs: a spring (shaft, bearing, support) carries f = k (r.q) +
c (r.q'), a mesh the pair model's force F(theta, omega, x, v) with x = a.q; both act on DOF i with
-r_i f, -a_i F.  Translational DOFs in a rotating frame get the frame's inertial terms (frame rate
Omega = g_c omega, Omega' = g_c psi''): q_a'' += 2 Omega q_b' + Omega' q_b + Omega^2 (R0 + q_a),
q_b'' += -2 Omega q_a' - Omega' (R0 + q_a) + Omega^2 q_b (R0 = r_c for planets, 0 for the centres);
every DOF: q_i'' = Q_i/m_i - g_i psi'', psi'' = Q_0/m_0.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from ..common.checks import finite_number
from ..common.topology import drivetrain_tree, planetary_sun_torque, willis_ratio
from ..common.vocabulary import DAMPING_MODELS, PLANETARY_MODELS, PLANETARY_PORTS, current_spelling
from ..dynamics.reference import TableRows
from ..gearbox.model import GearboxModelError, Mesh, Shaft, _check_mesh, mesh_damping
from ..tables.mesh_tables import MeshTables
from ..tables.planetary import PlanetaryStage, shift_meshing_error
from ..tables.zones import mean_total_stiffness_N_per_m
from .drives import drive_modes

__all__ = ["PlanetaryModelError", "PlanetaryModel", "build_drivetrain", "MESH_MAP_DOFS", "SPRING_DOFS"]

#: most DOFs of a mesh's x map (a translational stage's mesh: 6, and the drive that turns its carrier)
MESH_MAP_DOFS = 7
#: most DOFs of a spring (a planet bearing's tangential spring: 4, and the drive that turns its carrier)
SPRING_DOFS = 5

class PlanetaryModelError(GearboxModelError):
    """Bad planetary drivetrain description; the message names the field."""


def _check_stage(i: int, s: PlanetaryStage) -> PlanetaryStage:
    w = f"planetary[{i}] ({s.name})"
    if s.held not in PLANETARY_PORTS:
        raise PlanetaryModelError(f"{w}.held: {s.held!r} not one of {PLANETARY_PORTS}")
    if s.model not in PLANETARY_MODELS:
        raise PlanetaryModelError(f"{w}.model: {s.model!r} not one of {PLANETARY_MODELS}")
    n = s.planets
    if n < 1 or len(s.sun_tables) != n or len(s.ring_tables) != n:
        raise PlanetaryModelError(f"{w}: need one sun and one ring table set per planet ({n} planets)")
    for nm in ("base_radius_sun_m", "base_radius_planet_m", "base_radius_ring_m", "carrier_radius_m"):
        finite_number(f"{w}.{nm}", getattr(s, nm), positive=True, error=PlanetaryModelError)
    for key in ("sun", "ring", "carrier", "planet"):
        finite_number(f"{w}.inertia_kgm2[{key}]", s.inertia_kgm2.get(key), positive=True, error=PlanetaryModelError)
        if s.model == "translational" or key == "planet":
            finite_number(f"{w}.mass_kg[{key}]", s.mass_kg.get(key), positive=True, error=PlanetaryModelError)
        if s.model == "translational":
            finite_number(f"{w}.bearing_N_per_m[{key}]", s.bearing_N_per_m.get(key), nonneg=True,
                          error=PlanetaryModelError)
    if s.model == "translational" and not s.bearing_N_per_m.get("planet", 0.0) > 0.0:
        raise PlanetaryModelError(f"{w}.bearing_N_per_m[planet]: the planet bearings need a stiffness > 0")
    finite_number(f"{w}.support_Nm_per_rad", s.support_Nm_per_rad, positive=True, error=PlanetaryModelError)
    if s.driven_speed_rad_s is not None:
        finite_number(f"{w}.driven_speed_rad_s", s.driven_speed_rad_s, error=PlanetaryModelError)
    # geometric consistency the rigid-body motion needs
    rs, rp, rr, rc = s.base_radius_sun_m, s.base_radius_planet_m, s.base_radius_ring_m, s.carrier_radius_m
    if abs(rc * math.cos(s.pressure_angle_sun_rad) - (rs + rp)) > 1e-9 * rc:
        raise PlanetaryModelError(f"{w}.pressure_angle_sun_rad: r_c cos(alpha_s) must equal r_s + r_p "
                                  f"({rc * math.cos(s.pressure_angle_sun_rad)!r} != {rs + rp!r})")
    if abs(rc * math.cos(s.pressure_angle_ring_rad) - (rr - rp)) > 1e-9 * rc:
        raise PlanetaryModelError(f"{w}.pressure_angle_ring_rad: r_c cos(alpha_r) must equal r_r - r_p "
                                  f"({rc * math.cos(s.pressure_angle_ring_rad)!r} != {rr - rp!r})")
    if abs(rs / s.teeth_sun - rp / s.teeth_planet) > 1e-9 * rp / s.teeth_planet or \
            abs(rr / s.teeth_ring - rp / s.teeth_planet) > 1e-9 * rp / s.teeth_planet:
        raise PlanetaryModelError(f"{w}: base radii must be in the ratio of the tooth counts (one base pitch)")
    for n_, t in enumerate(list(s.sun_tables) + list(s.ring_tables)):
        if not isinstance(t, MeshTables):
            raise PlanetaryModelError(f"{w}: tables must be MeshTables, got {type(t).__name__}")
        if t.has_temperature_axis:
            raise PlanetaryModelError(f"{w}: tables with a temperature axis; select one with at_temperature")
        t.validate()
    model = current_spelling("damping_model", s.damping_model, where=f"{w}.damping_model")
    if model not in DAMPING_MODELS:
        raise PlanetaryModelError(f"{w}.damping_model: {s.damping_model!r} not one of {sorted(DAMPING_MODELS)}")
    if s.position_deflections_m and len(s.position_deflections_m) != n:
        raise PlanetaryModelError(f"{w}.position_deflections_m: one (sun, ring) pair per planet")
    return replace(s, damping_model=model)


@dataclass
class _Builder:
    names: List[str] = field(default_factory=list)
    kind: List[str] = field(default_factory=list)
    mass: List[float] = field(default_factory=list)
    g: List[float] = field(default_factory=list)

    def add(self, name, kind, mass, g):
        self.names.append(name)
        self.kind.append(kind)
        self.mass.append(float(mass))
        self.g.append(float(g))
        return len(self.names) - 1


@dataclass(frozen=True)
class PlanetaryModel:
    """A checked drivetrain with planetary stages (SI; module docstring).  Per DOF: name, kind ('rot'
    or 'trans'), mass or inertia, kinematic ratio g.  Per spring: name, kind, up to SPRING_DOFS (DOF, coefficient)
    entries, k, c, frame ratio.  Per mesh: name, tables, up to MESH_MAP_DOFS (DOF, coefficient) entries of x, up to
    2 of the table angle, its psi coefficient and phase, per-pair damping c and m_e, the static pinion
    torque per unit reference torque (table rows).  Inertial frames: (DOF a, DOF b, R0, frame ratio).
    ``part_dof``: part name -> its rotation DOF; ``stages``: the planetary stages with their DOFs."""

    dof_names: Tuple[str, ...]
    dof_kind: Tuple[str, ...]
    mass: np.ndarray
    g: np.ndarray
    part_dof: Dict[str, int]
    spring_names: Tuple[str, ...]
    spring_kind: Tuple[str, ...]
    spring_idx: np.ndarray
    spring_coef: np.ndarray
    spring_k: np.ndarray
    spring_c: np.ndarray
    mesh_names: Tuple[str, ...]
    mesh_tables: Tuple[MeshTables, ...]
    mesh_idx: np.ndarray
    mesh_coef: np.ndarray
    angle_idx: np.ndarray
    angle_coef: np.ndarray
    angle_ref: np.ndarray
    angle_phase: np.ndarray
    mesh_c: np.ndarray
    mesh_me: np.ndarray
    mesh_damping_model: Tuple[str, ...]
    mesh_torque_per_ref: np.ndarray
    frame_idx: np.ndarray
    frame_par: np.ndarray
    motor: str
    load: str
    load_dof: int
    motor_torque_input: bool
    load_torque_input: bool
    stages: Tuple[dict, ...] = ()
    gearbox_meshes: Tuple[str, ...] = ()
    parts: Tuple[str, ...] = ()
    #: the drives of the driven members (docs/planetary.md "Driven members"): per drive its port (part
    #: name), its DOF (infinite inertia, g = 0), its stage, its default speed (rad/s) and ``mode``, the
    #: rigid motion of every DOF per unit drive speed with the motor DOF at rest (rad/s per rad/s)
    drives: Tuple[dict, ...] = ()
    #: per rotating frame the drive DOF that turns it too (-1: none) and its ratio h_c: the frame turns
    #: at g_f omega + h_c q_d' (None: no frame is turned by a drive)
    frame_drive: Optional[np.ndarray] = None
    frame_drive_ratio: Optional[np.ndarray] = None

    def frame_drives(self) -> Tuple[np.ndarray, np.ndarray]:
        """(drive DOF or -1, drive ratio) of every rotating frame."""
        nf = self.frame_idx.shape[0]
        if self.frame_drive is None:
            return -np.ones(nf, dtype=np.int64), np.zeros(nf)
        return self.frame_drive, self.frame_drive_ratio

    # ------------------------------------------------------------ drives
    @property
    def drive_dofs(self) -> Tuple[int, ...]:
        return tuple(int(d["dof"]) for d in self.drives)

    def drive_speeds(self, speeds_rad_s=None) -> np.ndarray:
        """The drives' speeds (rad/s): ``speeds_rad_s`` (a sequence in drive order, or a dict port ->
        speed for some) over the model's defaults."""
        w = np.array([float(d["speed_rad_s"]) for d in self.drives], dtype=float)
        if isinstance(speeds_rad_s, dict):
            ports = [d["port"] for d in self.drives]
            for k, v in speeds_rad_s.items():
                if k not in ports:
                    raise PlanetaryModelError(f"drive_speeds_rad_s[{k!r}]: not a driven member; driven are {ports}")
                w[ports.index(k)] = finite_number(f"drive_speeds_rad_s[{k!r}]", v, error=PlanetaryModelError)
        elif speeds_rad_s is not None:
            v = np.asarray(speeds_rad_s, dtype=float).reshape(-1)
            if v.shape != w.shape or not np.all(np.isfinite(v)):
                raise PlanetaryModelError(f"drive_speeds_rad_s: expected {w.size} finite speeds (rad/s)")
            w = v
        return w

    def kinematic_speeds(self, omega_rad_s: float, drive_speeds_rad_s=None) -> np.ndarray:
        """Every DOF's rigid speed (rad/s, or m/s for a translation): g omega plus the drives' rigid
        motions."""
        v = self.g * float(omega_rad_s)
        for d, w in zip(self.drives, self.drive_speeds(drive_speeds_rad_s)):
            v = v + d["mode"] * w
        return v

    def table_speeds(self, omega_rad_s: float, drive_speeds_rad_s=None) -> np.ndarray:
        """Every mesh's table-angle speed (rad/s) in the rigid motion."""
        v = self.kinematic_speeds(omega_rad_s, drive_speeds_rad_s)
        return np.array([self.angle_ref[m] * float(omega_rad_s) + sum(c * (v[i] - self.g[i] * float(omega_rad_s))
                                                                         for i, c in zip(self.angle_idx[m],
                                                                                         self.angle_coef[m]) if i >= 0)
                         for m in range(len(self.mesh_names))])

    # ------------------------------------------------------------ sizes
    @property
    def n_dof(self) -> int:
        return int(self.mass.shape[0])

    @property
    def n_state(self) -> int:
        return 2 * self.n_dof

    @property
    def load_ratio(self) -> float:
        return float(self.g[self.load_dof])

    def reference_torque_Nm(self, motor_torque_Nm: float, load_torque_Nm: float) -> float:
        """The motor-side torque in steady state: the motor torque when it is an input, else the load
        torque referred to the motor."""
        return float(motor_torque_Nm) if self.motor_torque_input else float(load_torque_Nm) * self.load_ratio

    def mesh_torques_Nm(self, reference_torque_Nm: float) -> np.ndarray:
        """Static pinion torque of every mesh (N m): it selects the torque rows of its tables."""
        return np.abs(self.mesh_torque_per_ref * reference_torque_Nm)

    # ------------------------------------------------------------ linearisation
    def _rows(self, m: int, torque: float) -> np.ndarray:
        t = self.mesh_tables[m]
        k = np.asarray(t.k_N_per_m, dtype=float)
        tq = np.asarray(t.torque_Nm, dtype=float)
        if tq.size == 1:
            return k[0]
        q = min(max(torque, tq[0]), tq[-1])
        i = min(max(int(np.searchsorted(tq, q, side="right") - 1), 0), tq.size - 2)
        w = (q - tq[i]) / (tq[i + 1] - tq[i])
        return k[i] + w * (k[i + 1] - k[i])

    def mean_mesh_stiffness_N_per_m(self, reference_torque_Nm: float) -> np.ndarray:
        tq = self.mesh_torques_Nm(reference_torque_Nm)
        return np.array([mean_total_stiffness_N_per_m(t, self._rows(m, float(tq[m])))
                         for m, t in enumerate(self.mesh_tables)])

    def mean_pairs_in_contact(self, reference_torque_Nm: float) -> np.ndarray:
        tq = self.mesh_torques_Nm(reference_torque_Nm)
        return np.array([float((self._rows(m, float(tq[m])) > 0.0).sum(axis=0).mean())
                         for m in range(len(self.mesh_tables))])

    def vector(self, idx_row, coef_row) -> np.ndarray:
        v = np.zeros(self.n_dof)
        for i, c in zip(idx_row, coef_row):
            if i >= 0:
                v[i] += c
        return v

    def mesh_vector(self, m: int) -> np.ndarray:
        return self.vector(self.mesh_idx[m], self.mesh_coef[m])

    def spring_vector(self, s: int) -> np.ndarray:
        return self.vector(self.spring_idx[s], self.spring_coef[s])

    def linearisation(self, reference_torque_Nm: float, mesh_stiffness_N_per_m=None):
        """(M, K, C) in absolute coordinates at rest (docs/planetary.md "Modes"): M = diag(m), K = sum
        springs k r r^T + sum meshes kbar a a^T, C likewise with the spring dampers and n_c c per mesh."""
        n = self.n_dof
        M = np.diag(self.mass.astype(float))
        K = np.zeros((n, n))
        C = np.zeros((n, n))
        for s in range(len(self.spring_names)):
            r = self.spring_vector(s)
            K += self.spring_k[s] * np.outer(r, r)
            C += self.spring_c[s] * np.outer(r, r)
        kbar = (self.mean_mesh_stiffness_N_per_m(reference_torque_Nm) if mesh_stiffness_N_per_m is None
                else np.asarray(mesh_stiffness_N_per_m, dtype=float))
        nc = self.mean_pairs_in_contact(reference_torque_Nm)
        for m in range(len(self.mesh_names)):
            a = self.mesh_vector(m)
            K += kbar[m] * np.outer(a, a)
            C += nc[m] * self.mesh_c[m] * np.outer(a, a)
        return M, K, C

    def rigid_mode(self) -> np.ndarray:
        """The rigid rotation in absolute coordinates: rotations g, planet tangential displacements
        r_c g_c (the planets ride on the turning carrier), other translations 0."""
        v = np.where(np.array(self.dof_kind) == "rot", self.g, 0.0).astype(float)
        for st in self.stages:
            if st["model"] == "translational":
                gc = self.g[st["dofs"]["carrier"]]
                for n in range(st["planets"]):
                    v[st["dofs"]["planet_eta"][n]] = st["carrier_radius_m"] * gc
        return v

    # ------------------------------------------------------------ static state
    def static_state(self, reference_torque_Nm: float, speed_rad_s: float, angle_rad: float = 0.0,
                     iterations: int = 60, drive_speeds_rad_s=None) -> np.ndarray:
        """The quasi-static equilibrium (docs/planetary.md "Initial state"): psi = ``angle_rad``, omega =
        ``speed_rad_s``, q' = 0 and q solving sum of the static forces = 0 (the motor torque and the
        balancing load torque, springs, the meshes' static force laws at their table angles, the
        frames' centripetal terms at the start speed), by Newton's method on the piecewise-linear mesh
        laws from the state with every pair in its contact zone on its drive flank (an active-set
        iteration, to a residual of 1e-13 of the largest term summed into it: the torques, the mesh
        forces and the springs' k q).  Raises
        PlanetaryModelError naming a mesh with no pair in its contact zone, or when no equilibrium is
        found.  A drive DOF (a driven member's, infinite inertia) stays at q = 0, every DOF's q' is its
        part of the drives' rigid motion at ``drive_speeds_rad_s`` (:meth:`drive_speeds`; None: the
        model's)."""
        n = self.n_dof
        T_in = float(reference_torque_Nm)
        f_ext = np.zeros(n)
        f_ext[0] += T_in
        f_ext[self.load_dof] -= T_in / self.load_ratio
        tq = self.mesh_torques_Nm(reference_torque_Nm)
        rows = [TableRows(t, float(tq[m])) for m, t in enumerate(self.mesh_tables)]
        Kspr = np.zeros((n, n))
        for s in range(len(self.spring_names)):
            r = self.spring_vector(s)
            Kspr += self.spring_k[s] * np.outer(r, r)
        # centripetal terms of the frames at the start speed: force m Omega^2 (R0 + q_a) on q_a
        cen = np.zeros(n)
        Kcen = np.zeros((n, n))
        wd = self.drive_speeds(drive_speeds_rad_s) if self.drives else np.zeros(0)
        for (ia, ib), (R0, gf), fd, fh in zip(self.frame_idx, self.frame_par, *self.frame_drives()):
            Om = gf * speed_rad_s
            if fd >= 0:   # a drive turns the frame too
                Om += fh * wd[self.drive_dofs.index(int(fd))]
            W2 = Om ** 2
            cen[ia] += self.mass[ia] * W2 * R0
            Kcen[ia, ia] += self.mass[ia] * W2       # the force m Omega^2 q grows with q: a negative stiffness
            Kcen[ib, ib] += self.mass[ib] * W2
        free = np.array([i for i in range(1, n) if i not in self.drive_dofs], dtype=np.int64)
        meshvec = [self.mesh_vector(m) for m in range(len(self.mesh_names))]
        anglevec = [self.vector(self.angle_idx[m], self.angle_coef[m]) for m in range(len(self.mesh_names))]

        def mesh_law(m, q):
            th = self.angle_ref[m] * angle_rad + anglevec[m] @ q + self.angle_phase[m]
            Kk, Ee, Bb = _lookup(rows[m], th)
            x = meshvec[m] @ q
            d = x - Ee
            act = Kk > 0.0
            drive = act & (d > Bb)
            back = act & (d < -Bb)
            F = float(np.sum(Kk[drive] * (d[drive] - Bb[drive])) + np.sum(Kk[back] * (d[back] + Bb[back])))
            kt = float(np.sum(Kk[drive | back]))
            if not np.any(act):
                raise PlanetaryModelError(f"meshes[{m}] ({self.mesh_names[m]}): no tooth pair in the contact "
                                          f"zone at the start angle")
            return F, kt, Kk, Ee, Bb

        nm = len(self.mesh_names)
        # start: every pair in its contact zone pressed on its drive flank (the static load's flank), the
        # linear problem of that contact state; then Newton's method on the piecewise-linear laws, which
        # ends when the contact state repeats (exact on its piece)
        q = np.zeros(n)
        J = Kspr - Kcen
        rhs = f_ext + cen
        for m in range(nm):
            _, _, Kk, Ee, Bb = mesh_law(m, q)
            J = J + float(Kk.sum()) * np.outer(meshvec[m], meshvec[m])
            rhs = rhs + float(np.sum(Kk * (Ee + Bb))) * meshvec[m]
        q[free] = np.linalg.solve(J[np.ix_(free, free)], rhs[free])
        for it in range(iterations):
            R = f_ext + cen + Kcen @ q - Kspr @ q
            J = Kspr - Kcen
            # the residual's round-off grows with the largest term summed into it, the springs' k q too
            # (supports of 1e13 N/m and more: a rigid part written as a stiff spring)
            scale = abs(T_in) + float(np.max(np.abs(Kspr) @ np.abs(q), initial=0.0))
            for m in range(nm):
                F, kt, Kk, _, _ = mesh_law(m, q)
                R -= meshvec[m] * F
                scale += abs(F) * float(np.max(np.abs(meshvec[m])))
                J = J + max(kt, 1e-6 * float(Kk.sum())) * np.outer(meshvec[m], meshvec[m])
            if float(np.max(np.abs(R[free]))) <= 1e-13 * max(scale, 1e-300):
                break
            q[free] += np.linalg.solve(J[np.ix_(free, free)], R[free])
        else:
            raise PlanetaryModelError(f"static state: no equilibrium found in {iterations} Newton steps at the "
                                      f"reference torque {T_in!r} N*m (largest residual "
                                      f"{float(np.max(np.abs(R[free]))):.3g})")
        y = np.zeros(2 * n)
        y[0], y[1] = angle_rad, speed_rad_s
        y[2::2] = q[1:]
        for d, w in zip(self.drives, self.drive_speeds(drive_speeds_rad_s)):
            y[3::2] += d["mode"][1:] * w
        return y


def _lookup(rows: TableRows, theta: float):
    """k, e, b of every slot at table angle theta (the reference's pieces: plain or zone lines)."""
    s = theta / rows.dphi
    K = np.empty(rows.P)
    E = np.empty(rows.P)
    B = np.empty(rows.P)
    for j in range(rows.P):
        (k0, k1), (e0, e1), (b0, b1), base, inz = rows.coeffs(j, s)
        w = s - base
        K[j] = (k0 + w * (k1 - k0)) if inz else 0.0
        E[j] = e0 + w * (e1 - e0)
        B[j] = b0 + w * (b1 - b0)
    return K, E, B


def _sign(v: float) -> int:
    return 1 if v >= 0.0 else -1


def build_drivetrain(meshes: Sequence[Mesh] = (), planetaries: Sequence[PlanetaryStage] = (),
                     shafts: Sequence[Shaft] = (), parts: Optional[Dict[str, float]] = None, *,
                     motor: str = "motor", load: str = "load", motor_torque_input: bool = True,
                     load_torque_input: bool = True) -> PlanetaryModel:
    """Check and build a :class:`PlanetaryModel` (module docstring): parallel-axis ``meshes``
    (gearfmu.gearbox.model.Mesh), planetary stages, ``shafts`` (gearfmu.gearbox.model.Shaft, rigid or
    elastic), further ``parts`` with their inertias (kg m^2), the motor and load parts and which ends
    are torque inputs.  The topology rules of gearfmu.common.topology apply; a planetary stage joins
    its two free ports.  Steps: the parts and their inertias (:func:`_parts`), the tree and the
    kinematic ratios (:func:`_kinematics`), the DOFs and elements (:func:`_add_stage` per stage), the
    check that every element's rigid deflection vanishes, the flat arrays of the model."""
    meshes = tuple(_check_mesh(i, m) for i, m in enumerate(meshes))
    planetaries = tuple(_check_stage(i, s) for i, s in enumerate(planetaries))
    if not meshes and not planetaries:
        raise PlanetaryModelError("meshes, planetaries: a drivetrain needs at least one stage")
    if not (motor_torque_input or load_torque_input):
        raise PlanetaryModelError("motor_torque_input, load_torque_input: at least one end must be a torque input")
    inertia, held_parts = _parts(meshes, planetaries, shafts, parts, motor, load)
    tree, I_body, g_body, up_port = _kinematics(meshes, planetaries, shafts, inertia, motor)
    B = _Builder()
    for b in range(len(tree.bodies)):
        B.add("+".join(tree.bodies[b]), "rot", I_body[b], g_body[b])
    part_dof = dict(tree.body_of)
    for p, (i, I) in held_parts.items():
        part_dof[p] = B.add(p, "rot", I, 0.0)
    springs = _shaft_springs(shafts, tree, B, part_dof)   # (name, kind, [(dof, coef)], k, c, frame ratio)
    mesh_rows: List[dict] = []
    frames: List[tuple] = []
    for m in meshes:
        t = m.tables
        p, q = part_dof[f"{m.name}.pinion"], part_dof[f"{m.name}.gear"]
        c, me = mesh_damping(t, m.damping_ratio)
        mesh_rows.append(dict(name=m.name, tables=t, x=[(p, float(t.base_radius_pinion_m)),
                                                        (q, -float(t.base_radius_gear_m))],
                              a=[(p, 1.0)], phase=0.0, c=c, me=me, model=m.damping_model, torque=1.0 / B.g[p]))
    stage_info = [_add_stage(st, up_port[st.name], B, part_dof, springs, mesh_rows, frames) for st in planetaries]
    _check_rigid_parts(B, springs, mesh_rows)
    tq_ref = np.array([r["torque"] for r in mesh_rows])
    # stages off the motor-load path carry no static torque
    on = {tree.edges[e][0] for e in tree.path(0, tree.body_of[load])}
    for mi in range(len(meshes)):
        if mi not in on:
            tq_ref[mi] = 0.0
    for i, si in enumerate(stage_info):
        if len(meshes) + i not in on:
            tq_ref[si["meshes"]] = 0.0
    drives, frame_drive = drive_modes(planetaries, stage_info, B.names, B.kind, springs, mesh_rows, frames,
                                      error=PlanetaryModelError)
    model = _packed(B, part_dof, springs, mesh_rows, frames, tq_ref, motor=motor, load=load,
                    inputs=(bool(motor_torque_input), bool(load_torque_input)), stages=tuple(stage_info),
                    gearbox_meshes=tuple(m.name for m in meshes), parts=tuple(inertia) + tuple(held_parts))
    if not drives:
        return model
    return replace(model, drives=tuple(drives), frame_drive=np.array([d for d, _ in frame_drive], dtype=np.int64),
                   frame_drive_ratio=np.array([h for _, h in frame_drive], dtype=float))


def _parts(meshes, planetaries, shafts, parts, motor: str, load: str):
    """(part name -> inertia, held port name -> (stage index, inertia)), every name and end checked."""
    inertia: Dict[str, float] = {}
    for name, val in (parts or {}).items():
        inertia[str(name)] = finite_number(f"parts[{name!r}]", val, positive=True, error=PlanetaryModelError)
    names = set()
    for i, m in enumerate(meshes):
        if m.name in names:
            raise PlanetaryModelError(f"meshes[{i}].name: {m.name!r} given twice")
        names.add(m.name)
        inertia[f"{m.name}.pinion"] = float(m.tables.inertia_pinion_kgm2)
        inertia[f"{m.name}.gear"] = float(m.tables.inertia_gear_kgm2)
    held_parts = {}
    for i, s in enumerate(planetaries):
        if s.name in names:
            raise PlanetaryModelError(f"planetaries[{i}].name: {s.name!r} given twice")
        names.add(s.name)
        for p in PLANETARY_PORTS:
            I = s.inertia_kgm2[p]
            if p == "carrier" and s.model == "torsional":
                I = I + s.planets * s.mass_kg["planet"] * s.carrier_radius_m ** 2
            if p == s.held:
                held_parts[s.port(p)] = (i, I)
            else:
                inertia[s.port(p)] = float(I)
    for end, what in ((motor, "motor"), (load, "load")):
        if end not in inertia:
            raise PlanetaryModelError(f"{what}: {end!r} is not a part; parts are {sorted(inertia)}")
    if motor == load:
        raise PlanetaryModelError(f"load: {load!r} is the motor's part too")
    for i, s in enumerate(shafts):
        if s.name in names:
            raise PlanetaryModelError(f"shafts[{i}].name: {s.name!r} is already a name in this drivetrain")
        names.add(s.name)
        for end in (s.a, s.b):
            if end in held_parts:
                raise PlanetaryModelError(f"shafts[{i}] ({s.name}): {end!r} is a held member (grounded, or driven, "
                                          "through its torsional support); no shaft may join it")
            if end not in inertia:
                raise PlanetaryModelError(f"shafts[{i}] ({s.name}): {end!r} is not a part; parts are "
                                          f"{sorted(inertia)}")
        if s.stiffness_Nm_per_rad is not None:
            finite_number(f"shafts[{i}].stiffness_Nm_per_rad", s.stiffness_Nm_per_rad, positive=True,
                          error=PlanetaryModelError)
        finite_number(f"shafts[{i}].inertia_kgm2", s.inertia_kgm2, nonneg=True, error=PlanetaryModelError)
    return inertia, held_parts


def _kinematics(meshes, planetaries, shafts, inertia, motor: str):
    """(tree, inertia per body, kinematic ratio per body, stage name -> its port nearer the motor):
    the drivetrain tree (gearfmu.common.topology), each shaft's inertia half to each end, the ratios
    along the tree (a mesh by its base radii, a planetary stage by Willis' equation)."""
    nm_, npl = len(meshes), len(planetaries)
    links = [("mesh", f"{m.name}.pinion", f"{m.name}.gear") for m in meshes]
    links += [("planetary",) + tuple(s.port(p) for p in s.free_ports) for s in planetaries]
    links += [("rigid" if s.stiffness_Nm_per_rad is None else "shaft", s.a, s.b) for s in shafts]
    tree = drivetrain_tree(tuple(inertia), links, motor)
    if tree.problems:
        li, part, reason = tree.problems[0]
        where = (f"meshes[{li}] ({meshes[li].name})" if li is not None and li < nm_
                 else f"planetaries[{li - nm_}] ({planetaries[li - nm_].name})" if li is not None and li < nm_ + npl
                 else f"shafts[{li - nm_ - npl}] ({shafts[li - nm_ - npl].name})" if li is not None else part)
        raise PlanetaryModelError(f"{where}: {reason}")
    nb = len(tree.bodies)
    I_body = np.zeros(nb)
    for p, val in inertia.items():
        I_body[tree.body_of[p]] += val
    for s in shafts:
        I_body[tree.body_of[s.a]] += 0.5 * s.inertia_kgm2
        I_body[tree.body_of[s.b]] += 0.5 * s.inertia_kgm2
    g_body = np.ones(nb)
    up_port = {}
    for li, up, down in tree.edges:
        kind = links[li][0]
        if kind == "mesh":
            t = meshes[li].tables
            g_body[down] = g_body[up] * float(t.base_radius_pinion_m) / float(t.base_radius_gear_m)
        elif kind == "planetary":
            st = planetaries[li - nm_]
            a, b = links[li][1], links[li][2]
            pu, pd = ((a, b) if tree.body_of[a] == up else (b, a))
            pu, pd = pu.split(".")[-1], pd.split(".")[-1]
            g_body[down] = g_body[up] * willis_ratio(st.held, pu, pd, st.base_radius_sun_m, st.base_radius_ring_m)
            up_port[st.name] = pu
        else:
            g_body[down] = g_body[up]
    return tree, I_body, g_body, up_port


def _shaft_springs(shafts, tree, B: "_Builder", part_dof) -> List[tuple]:
    """The elastic shafts as springs (name, "shaft", [(upstream DOF, 1), (downstream DOF, -1)], k, c,
    0); a damping ratio with the two-inertia reduced inertia of its end bodies."""
    springs = []
    for s in shafts:
        if s.stiffness_Nm_per_rad is None:
            continue
        a, b = part_dof[s.a], part_dof[s.b]
        up, down = (a, b) if _depth(tree, a) <= _depth(tree, b) else (b, a)
        k = float(s.stiffness_Nm_per_rad)
        if s.damping_Nms_per_rad is not None:
            c = float(s.damping_Nms_per_rad)
        elif s.damping_ratio is not None:
            ired = B.mass[up] * B.mass[down] / (B.mass[up] + B.mass[down])
            c = 2.0 * float(s.damping_ratio) * math.sqrt(k * ired)
        else:
            c = 0.0
        springs.append((s.name, "shaft", [(up, 1.0), (down, -1.0)], k, c, 0.0))
    return springs


def _check_rigid_parts(B: "_Builder", springs, mesh_rows) -> None:
    """The rigid parts of every element cancel (the translations of a stage are measured in the frame
    that turns with its carrier, so its elements' rotations count relative to that frame)."""
    g = np.array(B.g)
    checks = [(name, ent, gf) for name, kind, ent, k, c, gf in springs]
    checks += [(r["name"], r["x"], r.get("frame", 0.0)) for r in mesh_rows]
    for name, ent, gf in checks:
        rigid = sum(cf * (g[d] - gf) for d, cf in ent if B.kind[d] == "rot")
        if abs(rigid) > 1e-9 * max(1.0, max(abs(cf * g[d]) for d, cf in ent)):
            raise PlanetaryModelError(f"{name}: its rigid deflection does not vanish ({rigid!r}); the kinematic ratios "
                                      "and the element's radii disagree")


def _packed(B: "_Builder", part_dof, springs, mesh_rows, frames, tq_ref, *, motor, load, inputs, stages,
            gearbox_meshes, parts) -> PlanetaryModel:
    """The :class:`PlanetaryModel` of the built DOFs and elements, as flat arrays."""
    g = np.array(B.g)
    ns = len(springs)
    spring_idx = -np.ones((ns, SPRING_DOFS), dtype=np.int64)
    spring_coef = np.zeros((ns, SPRING_DOFS))
    for s_, (_, _, ent, _, _, _) in enumerate(springs):
        for j, (d, cf) in enumerate(ent):
            spring_idx[s_, j], spring_coef[s_, j] = d, cf
    nmesh = len(mesh_rows)
    mesh_idx = -np.ones((nmesh, MESH_MAP_DOFS), dtype=np.int64)
    mesh_coef = np.zeros((nmesh, MESH_MAP_DOFS))
    angle_idx = -np.ones((nmesh, 2), dtype=np.int64)
    angle_coef = np.zeros((nmesh, 2))
    for m_, r in enumerate(mesh_rows):
        for j, (d, cf) in enumerate(r["x"]):
            mesh_idx[m_, j], mesh_coef[m_, j] = d, cf
        for j, (d, cf) in enumerate(r["a"]):
            angle_idx[m_, j], angle_coef[m_, j] = d, cf
    angle_ref = np.array([sum(cf * g[d] for d, cf in r["a"]) for r in mesh_rows])
    return PlanetaryModel(
        dof_names=tuple(B.names), dof_kind=tuple(B.kind), mass=np.array(B.mass), g=g, part_dof=part_dof,
        spring_names=tuple(s[0] for s in springs), spring_kind=tuple(s[1] for s in springs), spring_idx=spring_idx,
        spring_coef=spring_coef, spring_k=np.array([s[3] for s in springs], dtype=float),
        spring_c=np.array([s[4] for s in springs], dtype=float), mesh_names=tuple(r["name"] for r in mesh_rows),
        mesh_tables=tuple(r["tables"] for r in mesh_rows), mesh_idx=mesh_idx, mesh_coef=mesh_coef,
        angle_idx=angle_idx, angle_coef=angle_coef, angle_ref=angle_ref,
        angle_phase=np.array([r["phase"] for r in mesh_rows]), mesh_c=np.array([r["c"] for r in mesh_rows]),
        mesh_me=np.array([r["me"] for r in mesh_rows]), mesh_damping_model=tuple(r["model"] for r in mesh_rows),
        mesh_torque_per_ref=tq_ref, frame_idx=np.array([f[:2] for f in frames], dtype=np.int64).reshape(-1, 2),
        frame_par=np.array([f[2:] for f in frames], dtype=float).reshape(-1, 2), motor=motor, load=load,
        load_dof=part_dof[load], motor_torque_input=inputs[0], load_torque_input=inputs[1],
        stages=stages, gearbox_meshes=gearbox_meshes, parts=parts)


def _depth(tree, body: int) -> int:
    d = 0
    while body != 0 and body < len(tree.parent):
        body = tree.edges[tree.parent[body]][1]
        d += 1
    return d


def _add_stage(st: PlanetaryStage, up: str, B: _Builder, part_dof, springs, mesh_rows, frames) -> dict:
    """The DOFs, springs, meshes and frames of one planetary stage (module docstring); ``up`` the port
    nearer the motor."""
    nm = st.name
    dS, dC, dR = part_dof[st.port("sun")], part_dof[st.port("carrier")], part_dof[st.port("ring")]
    gS, gC, gR = B.g[dS], B.g[dC], B.g[dR]
    rs, rp, rr, rc = st.base_radius_sun_m, st.base_radius_planet_m, st.base_radius_ring_m, st.carrier_radius_m
    a_s, a_r = st.pressure_angle_sun_rad, st.pressure_angle_ring_rad
    gP = gC - rs * (gS - gC) / rp
    # statics (equal load sharing): the external torques on sun, ring, carrier are in the ratio
    # r_s : r_r : -(r_s + r_r); the upstream port takes T_ref/g_up.  The sun's torque per unit reference
    # torque sets the tables' sense: the flank its static load presses is the tables' drive flank
    # (x > 0); the tables run backwards when the sun is driven (docs/planetary.md "Mesh sense").
    t_sun = planetary_sun_torque(up, 1.0 / B.g[part_dof[st.port(up)]], rs, rr)
    sig = _sign(t_sun)
    sig_p = -sig
    N = st.planets
    trans = st.model == "translational"
    zeta = st.bearing_damping_ratio
    dofs = {"sun": dS, "carrier": dC, "ring": dR, "planet": [], "planet_zeta": [], "planet_eta": []}
    # held member's torsional support (a driven member's: to its drive, a DOF of infinite inertia whose
    # speed is prescribed; docs/planetary.md "Driven members")
    dH = part_dof[st.port(st.held)]
    kH = float(st.support_Nm_per_rad)
    ends = [(dH, 1.0)]
    if st.driven_speed_rad_s is not None:
        dofs["drive"] = B.add(f"{nm}.{st.held}_drive", "rot", math.inf, 0.0)
        ends.append((dofs["drive"], -1.0))
    springs.append((f"{nm}.{st.held}_support", "support", ends, kH,
                    2.0 * zeta * math.sqrt(kH * B.mass[dH]), 0.0))
    if trans:
        for p in ("sun", "ring", "carrier"):
            ix = B.add(f"{nm}.{p}_x", "trans", st.mass_kg[p], 0.0)
            iy = B.add(f"{nm}.{p}_y", "trans", st.mass_kg[p], 0.0)
            dofs[p + "_xy"] = (ix, iy)
            frames.append((ix, iy, 0.0, gC))
            kb = float(st.bearing_N_per_m[p])
            if kb > 0.0:
                cb = 2.0 * zeta * math.sqrt(kb * st.mass_kg[p])
                springs.append((f"{nm}.{p}_bearing_x", "bearing", [(ix, 1.0)], kb, cb, gC))
                springs.append((f"{nm}.{p}_bearing_y", "bearing", [(iy, 1.0)], kb, cb, gC))
    mesh_ids = []
    for n in range(N):
        psi = st.planet_angles_rad[n]
        ip = B.add(f"{nm}.planet[{n + 1}]", "rot", st.inertia_kgm2["planet"], gP)
        dofs["planet"].append(ip)
        if trans:
            iz = B.add(f"{nm}.planet[{n + 1}]_radial", "trans", st.mass_kg["planet"], 0.0)
            ie = B.add(f"{nm}.planet[{n + 1}]_tangential", "trans", st.mass_kg["planet"], 0.0)
            dofs["planet_zeta"].append(iz)
            dofs["planet_eta"].append(ie)
            frames.append((iz, ie, rc, gC))
            kp = float(st.bearing_N_per_m["planet"])
            cp = 2.0 * zeta * math.sqrt(kp * st.mass_kg["planet"])
            xc, yc = dofs["carrier_xy"]
            springs.append((f"{nm}.planet[{n + 1}]_bearing_radial", "bearing",
                            [(xc, math.cos(psi)), (yc, math.sin(psi)), (iz, -1.0)], kp, cp, gC))
            springs.append((f"{nm}.planet[{n + 1}]_bearing_tangential", "bearing",
                            [(xc, -math.sin(psi)), (yc, math.cos(psi)), (dC, rc), (ie, -1.0)], kp, cp, gC))
            xs, ys = dofs["sun_xy"]
            xr, yr = dofs["ring_xy"]
            d_sun = [(xs, -math.sin(psi - a_s)), (ys, math.cos(psi - a_s)), (iz, -math.sin(a_s)),
                     (ie, -math.cos(a_s)), (dS, rs), (ip, rp)]
            d_ring = [(xr, -math.sin(psi + a_r)), (yr, math.cos(psi + a_r)), (iz, math.sin(a_r)),
                      (ie, -math.cos(a_r)), (dR, rr), (ip, -rp)]
        else:
            d_sun = [(dS, rs), (ip, rp), (dC, -rc * math.cos(a_s))]
            d_ring = [(dR, rr), (ip, -rp), (dC, -rc * math.cos(a_r))]
        # the pin position error as a meshing error: x = sigma delta + sigma dsun -> e - sigma dsun
        e_s, e_r = (st.position_deflections_m[n] if st.position_deflections_m else (0.0, 0.0))
        ts = shift_meshing_error(st.sun_tables[n], sig * e_s)
        tr = shift_meshing_error(st.ring_tables[n], -sig_p * e_r)
        cs, mes = mesh_damping(ts, st.mesh_damping_ratio)
        cr, mer = mesh_damping(tr, st.mesh_damping_ratio)
        tq_sun = 1.0 / N            # times the sun torque (set below from the port torque)
        mesh_ids.append(len(mesh_rows))
        mesh_rows.append(dict(name=f"{nm}.sun_planet[{n + 1}]", tables=ts, x=[(d, sig * c) for d, c in d_sun],
                              a=[(dS, float(sig)), (dC, -float(sig))], phase=-sig * psi, c=cs, me=mes,
                              model=st.damping_model, torque=tq_sun, frame=gC))
        mesh_ids.append(len(mesh_rows))
        mesh_rows.append(dict(name=f"{nm}.ring_planet[{n + 1}]", tables=tr, x=[(d, -sig_p * c) for d, c in d_ring],
                              a=[(ip, float(sig_p)), (dC, -float(sig_p))],
                              phase=st.ring_sun_phase_rad + sig * (st.teeth_ring / st.teeth_planet) * psi,
                              c=cr, me=mer, model=st.damping_model, torque=tq_sun * rp / rs, frame=gC))
    for k in mesh_ids:
        mesh_rows[k]["torque"] *= abs(t_sun)
    return {"name": nm, "planets": N, "model": st.model, "held": st.held, "driven": st.driven_speed_rad_s is not None,
            "dofs": dofs, "meshes": mesh_ids,
            "carrier_radius_m": rc, "sigma": sig, "teeth": (st.teeth_sun, st.teeth_planet, st.teeth_ring),
            "planet_angles_rad": tuple(st.planet_angles_rad), "g_planet": gP}
