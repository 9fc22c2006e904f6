"""Modes of a drivetrain with planetary stages, classified by Lin & Parker's structure (docs/planetary.md "Modes").

The mean-stiffness linearisation of :meth:`gearfmu.planetary.model.PlanetaryModel.linearisation` at
rest (CHOICE, as Lin & Parker 1999: no gyroscopic or centripetal terms of the turning carrier),
in absolute coordinates: ``K phi = omega^2 M phi`` (scipy.linalg.eigh).  Every mode gets the
fractions of its kinetic energy ``phi^T M phi`` in

* the rotations of the drivetrain's torsional bodies (motor, load, parallel gears, and every
  stage's sun, carrier and ring),
* the translations of every stage's sun, ring and carrier,
* every stage's planets (their rotations and translations),

and a type per planetary stage after J. Lin, R. G. Parker, *Analytical characterization of the unique
properties of planetary gear free vibration*, J. Vib. Acoust. 121 (1999) 316-321: **rotational**
(the central members only rotate), **translational** (the central members only translate, nothing
rotates), **planet** (the central members do not move: only the planets), or **mixed** (none of
these, e.g. unequally spaced planets or a mode of the rest of the drivetrain that moves the stage in
several ways); "rigid" for the rigid rotation.  A fraction below ``tol`` (1e-9 of the mode's
kinetic energy) counts as zero.  For equally spaced, identical planets Lin & Parker prove every mode
is one of the three, rotational modes simple, translational modes in pairs and planet modes of
multiplicity N - 3; :func:`multiplicities` groups the frequencies to show it.

The strain energy per element (spring or mesh) and the damped frequencies follow
:mod:`gearfmu.gearbox.modes`; the Campbell diagram's orders are the mesh harmonics of every stage
(the sun mesh frequency z_s |g_s - g_c| f_motor for a planetary stage) and the rotation of every
distinct shaft speed.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np
import scipy.linalg

from ..gearbox.modes import MESH_HARMONICS
from .model import PlanetaryModel

__all__ = ["PlanetaryMode", "PlanetaryModes", "modes", "multiplicities", "campbell", "MODE_TYPES"]

MODE_TYPES = ("rigid", "rotational", "translational", "planet", "mixed")


@dataclass(frozen=True)
class PlanetaryMode:
    """One mode: frequency (Hz), shape (absolute coordinates, largest |component| 1), strain-energy
    fraction per element, kinetic-energy fractions per group, its type per planetary stage, and the
    damped frequency and damping ratio."""

    index: int
    frequency_Hz: float
    shape: np.ndarray
    energy: Dict[str, float]
    kinetic: Dict[str, float]
    types: Dict[str, str]
    damped_frequency_Hz: float
    damping_ratio: float
    rigid: bool = False

    def to_dict(self, dof_names: Sequence[str]) -> dict:
        return {"index": self.index, "rigid": self.rigid, "frequency_Hz": self.frequency_Hz,
                "damped_frequency_Hz": self.damped_frequency_Hz, "damping_ratio": self.damping_ratio,
                "type": dict(self.types), "kinetic_energy_fraction": dict(self.kinetic),
                "shape": {b: float(v) for b, v in zip(dof_names, self.shape)},
                "strain_energy_fraction": dict(self.energy)}


@dataclass(frozen=True)
class PlanetaryModes:
    modes: Tuple[PlanetaryMode, ...]
    M: np.ndarray
    K: np.ndarray
    C: np.ndarray
    dof_names: Tuple[str, ...]
    mesh_stiffness_N_per_m: Dict[str, float]
    reference_torque_Nm: float
    extra: Dict[str, object] = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {"reference_torque_Nm": self.reference_torque_Nm, "dofs": list(self.dof_names),
                "mean_mesh_stiffness_N_per_m": dict(self.mesh_stiffness_N_per_m),
                "modes": [m.to_dict(self.dof_names) for m in self.modes], **self.extra}


def _groups(model: PlanetaryModel):
    """Index sets: torsional bodies' rotations, per stage its central translations and its planets."""
    rot_central = [i for i, k in enumerate(model.dof_kind) if k == "rot"]
    stage_trans, stage_planets = {}, {}
    planet_dofs = set()
    for st in model.stages:
        d = st["dofs"]
        pl = list(d["planet"]) + list(d["planet_zeta"]) + list(d["planet_eta"])
        stage_planets[st["name"]] = pl
        planet_dofs.update(pl)
        tr = []
        for p in ("sun", "ring", "carrier"):
            tr += list(d.get(p + "_xy", ()))
        stage_trans[st["name"]] = tr
    rot_central = [i for i in rot_central if i not in planet_dofs]
    return rot_central, stage_trans, stage_planets


def modes(model: PlanetaryModel, reference_torque_Nm: float, tol: float = 1e-9) -> PlanetaryModes:
    """Modes of the linearisation at the motor-side torque ``reference_torque_Nm`` (N m; it selects
    the torque rows and the mean stiffness), sorted by frequency; the rigid rotation is mode 0."""
    M, K, C = model.linearisation(reference_torque_Nm)
    kbar = model.mean_mesh_stiffness_N_per_m(reference_torque_Nm)
    # a driven member's drive (infinite inertia, prescribed speed) is ground for the modes: its DOF
    # is left out and stands still in every shape
    keep = np.array([i for i in range(M.shape[0]) if i not in model.drive_dofs], dtype=np.int64)
    M, K, C = (X[np.ix_(keep, keep)] for X in (M, K, C))
    w2, phi_k = scipy.linalg.eigh(K, M)
    phi = np.zeros((model.n_dof, phi_k.shape[1]))
    phi[keep] = phi_k
    n = M.shape[0]
    scale = max(float(np.max(np.abs(w2))), 1e-300)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-K / np.diag(M)[:, None], -C / np.diag(M)[:, None]]])
    lam = scipy.linalg.eigvals(A)
    upper = lam[lam.imag > 0.0]
    rot, trans, planets = _groups(model)
    mvec = np.zeros(model.n_dof)
    mvec[keep] = np.diag(M)
    out: List[PlanetaryMode] = []
    for i in range(n):
        v = phi[:, i]
        v = v / v[int(np.argmax(np.abs(v)))]
        rigid = abs(float(w2[i])) <= 1e-10 * scale
        ke = mvec * v * v
        tot = float(ke.sum())
        kin = {"rotation": float(ke[rot].sum() / tot)}
        types = {}
        for st in model.stages:
            nm = st["name"]
            kt = float(ke[trans[nm]].sum() / tot) if trans[nm] else 0.0
            kp = float(ke[planets[nm]].sum() / tot)
            kin[f"{nm}.translation"] = kt
            kin[f"{nm}.planets"] = kp
            kr = kin["rotation"]
            if rigid:
                types[nm] = "rigid"
            elif kt <= tol and kr <= tol:
                types[nm] = "planet"
            elif kt <= tol:
                types[nm] = "rotational"
            elif kr <= tol:
                types[nm] = "translational"
            else:
                types[nm] = "mixed"
        if rigid:
            out.append(PlanetaryMode(i, 0.0, v, {}, kin, types, 0.0, 0.0, True))
            continue
        wi = math.sqrt(max(float(w2[i]), 0.0))
        total = float(v[keep] @ K @ v[keep])
        energy = {}
        for s, nm in enumerate(model.spring_names):
            r = model.spring_vector(s)
            energy[nm] = float(model.spring_k[s] * (r @ v) ** 2 / total)
        for m, nm in enumerate(model.mesh_names):
            a = model.mesh_vector(m)
            energy[nm] = float(kbar[m] * (a @ v) ** 2 / total)
        if upper.size:
            lj = upper[int(np.argmin(np.abs(np.abs(upper) - wi)))]
            fd, zeta = float(lj.imag) / (2.0 * math.pi), float(-lj.real / abs(lj))
        else:
            fd, zeta = 0.0, 1.0
        out.append(PlanetaryMode(i, wi / (2.0 * math.pi), v, energy, kin, types, fd, zeta, False))
    return PlanetaryModes(modes=tuple(out), M=M, K=K, C=C, dof_names=tuple(model.dof_names),
                          mesh_stiffness_N_per_m={nm: float(kbar[i]) for i, nm in enumerate(model.mesh_names)},
                          reference_torque_Nm=float(reference_torque_Nm))


def multiplicities(result: PlanetaryModes, stage: str, rel_tol: float = 1e-7) -> List[Tuple[str, float, int]]:
    """(type, frequency Hz, multiplicity) of the elastic modes of ``stage``, frequencies within
    ``rel_tol`` of each other counted as one."""
    groups: List[List] = []
    for md in result.modes:
        if md.rigid:
            continue
        t = md.types.get(stage, "mixed")
        if groups and groups[-1][0] == t and abs(md.frequency_Hz - groups[-1][1]) <= rel_tol * md.frequency_Hz:
            groups[-1][2] += 1
        else:
            groups.append([t, md.frequency_Hz, 1])
    return [tuple(g) for g in groups]


def campbell(model: PlanetaryModel, result: PlanetaryModes, max_speed_rpm: float,
             operating_speed_rpm: Optional[float] = None, harmonics: Sequence[int] = MESH_HARMONICS) -> dict:
    """Campbell (interference) diagram data over the motor speed (rpm), as gearfmu.gearbox.modes.campbell:
    mesh orders of every parallel mesh and planetary stage, rotation orders of every distinct speed."""
    orders = []
    for m, nm in enumerate(model.mesh_names):
        if nm not in model.gearbox_meshes:
            continue
        t = model.mesh_tables[m]
        for h in harmonics:
            orders.append({"name": f"{nm} mesh {h}x", "kind": "mesh", "harmonic": int(h),
                           "hz_per_rpm": h * int(t.teeth_pinion) * abs(float(model.angle_ref[m])) / 60.0})
    for st in model.stages:
        m0 = st["meshes"][0]
        zs = st["teeth"][0]
        for h in harmonics:
            orders.append({"name": f"{st['name']} mesh {h}x", "kind": "mesh", "harmonic": int(h),
                           "hz_per_rpm": h * zs * abs(float(model.angle_ref[m0])) / 60.0})
    seen = []
    for i, k in enumerate(model.dof_kind):
        if k != "rot":
            continue
        gi = abs(float(model.g[i]))
        if gi == 0.0 or any(abs(gi - s) <= 1e-12 * max(gi, s) for s in seen):
            continue
        seen.append(gi)
        orders.append({"name": f"{model.dof_names[i]} 1x", "kind": "shaft", "harmonic": 1, "hz_per_rpm": gi / 60.0})
    points = []
    for o in orders:
        for md in result.modes:
            if md.rigid or o["hz_per_rpm"] <= 0.0:
                continue
            n = md.frequency_Hz / o["hz_per_rpm"]
            if 0.0 < n <= max_speed_rpm:
                points.append({"order": o["name"], "mode": md.index, "speed_rpm": n, "frequency_Hz": md.frequency_Hz})
    points.sort(key=lambda p: p["speed_rpm"])
    return {"speed_axis_rpm": [0.0, float(max_speed_rpm)], "operating_speed_rpm": operating_speed_rpm,
            "orders": orders, "modes_Hz": [m.frequency_Hz for m in result.modes if not m.rigid],
            "interferences": points}
