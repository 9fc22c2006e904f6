"""Natural frequencies, mode shapes, modal strain energy and the Campbell diagram of a gearbox.

The mean-stiffness linearisation of :meth:`gearfmu.gearbox.model.GearboxModel.linearisation`
at the operating torque (docs/gearbox.md "Modes and Campbell diagram"):

* undamped modes: the generalized symmetric eigenproblem ``K phi = omega^2 M phi``
  (scipy.linalg.eigh) in absolute body angles; the gearbox is free at both ends (both ends are
  torque inputs), so mode 0 is the rigid rotation (omega = 0, shape = the kinematic ratios g),
  reported as such;
* per mode: frequency (Hz), shape (per body, the largest |component| = 1, positive), and the
  fraction of the modal strain energy ``phi^T K phi / 2`` in every shaft, ``k_s (phi_a - phi_b)^2 / 2``,
  and every mesh, ``kbar (r . phi)^2 / 2``;
* damped modes: the eigenvalues ``lambda`` of the first-order system with the shaft dampers and the
  mesh dampers (n_c pairs in contact times the per-pair c); each undamped mode gets the
  eigenvalue with Im > 0 nearest to its omega: damped frequency Im(lambda)/(2 pi), damping ratio
  -Re(lambda)/|lambda|;
* Campbell (interference) diagram over the motor speed: the mesh orders (h x the mesh frequency
  z_p n_p, h = 1..3, of every stage) and the shaft orders (1 x the rotation frequency of every
  distinct shaft speed) as lines through the origin, the modes as horizontal lines, and every
  speed where an order line meets a mode within the speed range (an interference point).

Pure numpy/scipy; the PNG is drawn by :mod:`gearfmu.plots_gearbox`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np
import scipy.linalg

from .model import GearboxModel

__all__ = ["Mode", "ModesResult", "modes", "campbell", "MESH_HARMONICS"]

#: mesh-frequency harmonics drawn in the Campbell diagram
MESH_HARMONICS = (1, 2, 3)


@dataclass(frozen=True)
class Mode:
    """One mode of the linearisation: ``frequency_Hz`` (undamped), ``shape`` (per body),
    ``energy`` (element name -> fraction of the modal strain energy), ``damped_frequency_Hz`` and
    ``damping_ratio`` (from the damped eigenproblem), ``rigid`` (the rigid rotation)."""

    index: int
    frequency_Hz: float
    shape: np.ndarray
    energy: Dict[str, float]
    damped_frequency_Hz: float
    damping_ratio: float
    rigid: bool = False

    def to_dict(self, body_names: Sequence[str]) -> dict:
        return {"index": self.index, "rigid": self.rigid, "frequency_Hz": self.frequency_Hz,
                "damped_frequency_Hz": self.damped_frequency_Hz, "damping_ratio": self.damping_ratio,
                "shape": {b: float(v) for b, v in zip(body_names, self.shape)},
                "strain_energy_fraction": dict(self.energy)}


@dataclass(frozen=True)
class ModesResult:
    """The modes of a gearbox at one operating torque, with the matrices they come from (SI)."""

    modes: Tuple[Mode, ...]
    M: np.ndarray
    K: np.ndarray
    C: np.ndarray
    body_names: Tuple[str, ...]
    mesh_stiffness_N_per_m: Dict[str, float]
    reference_torque_Nm: float
    extra: Dict[str, object] = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {"reference_torque_Nm": self.reference_torque_Nm, "bodies": list(self.body_names),
                "mean_mesh_stiffness_N_per_m": dict(self.mesh_stiffness_N_per_m),
                "modes": [m.to_dict(self.body_names) for m in self.modes], **self.extra}


def _normalise(v: np.ndarray) -> np.ndarray:
    i = int(np.argmax(np.abs(v)))
    return v / v[i]


def modes(model: GearboxModel, reference_torque_Nm: float) -> ModesResult:
    """Modes of the mean-stiffness linearisation at the motor-side torque ``reference_torque_Nm``
    (N*m; it selects each mesh's torque row and kbar).  Sorted by frequency; mode 0 is rigid."""
    M, K, C = model.linearisation(reference_torque_Nm)
    kbar = model.mean_mesh_stiffness_N_per_m(reference_torque_Nm)
    w2, phi = scipy.linalg.eigh(K, M)
    n = M.shape[0]
    scale = max(float(np.max(np.abs(w2))), 1e-300)
    # damped: x' = A x, A = [[0, I], [-M^-1 K, -M^-1 C]]
    Minv = np.diag(1.0 / np.diag(M))
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ C]])
    lam = scipy.linalg.eigvals(A)
    upper = lam[lam.imag > 0.0]
    out: List[Mode] = []
    names = [model.body_name(i) for i in range(n)]
    for i in range(n):
        w2i = max(float(w2[i]), 0.0)
        rigid = abs(float(w2[i])) <= 1e-10 * scale
        shape = _normalise(phi[:, i])
        if rigid:
            out.append(Mode(i, 0.0, shape, {}, 0.0, 0.0, True))
            continue
        wi = math.sqrt(w2i)
        total = float(shape @ K @ shape)
        energy = {}
        for s, sh in enumerate(model.shafts):
            a, b = model.shaft_bodies[s]
            energy[sh.name] = float(model.shaft_k_Nm_per_rad[s] * (shape[a] - shape[b]) ** 2 / total)
        for m, mesh in enumerate(model.meshes):
            r = model.mesh_vector(m)
            energy[mesh.name] = float(kbar[m] * (r @ shape) ** 2 / total)
        if upper.size:
            j = int(np.argmin(np.abs(np.abs(upper) - wi)))
            lj = upper[j]
            fd, zeta = float(lj.imag) / (2.0 * math.pi), float(-lj.real / abs(lj))
        else:  # overdamped: no oscillating eigenvalue
            fd, zeta = 0.0, 1.0
        out.append(Mode(i, wi / (2.0 * math.pi), shape, energy, fd, zeta, False))
    return ModesResult(modes=tuple(out), M=M, K=K, C=C, body_names=tuple(names),
                       mesh_stiffness_N_per_m={m.name: float(kbar[i]) for i, m in enumerate(model.meshes)},
                       reference_torque_Nm=float(reference_torque_Nm))


def campbell(model: GearboxModel, result: ModesResult, max_speed_rpm: float,
             operating_speed_rpm: Optional[float] = None, harmonics: Sequence[int] = MESH_HARMONICS) -> dict:
    """Campbell (interference) diagram data over the motor speed 0..``max_speed_rpm``: every
    order as ``{"name", "kind", "hz_per_rpm"}`` (frequency = hz_per_rpm x motor speed in rpm),
    the modes' frequencies, and every interference ``{"order", "mode", "speed_rpm",
    "frequency_Hz"}`` where an order meets a mode at a motor speed in (0, max_speed_rpm]."""
    orders = []
    for m, mesh in enumerate(model.meshes):
        p = model.mesh_bodies[m, 0]
        z = int(mesh.tables.teeth_pinion)
        for h in harmonics:
            orders.append({"name": f"{mesh.name} mesh {h}x", "kind": "mesh", "harmonic": int(h),
                           "hz_per_rpm": h * z * float(model.g[p]) / 60.0})
    seen = []
    for i in range(model.n_bodies):
        gi = float(model.g[i])
        if any(abs(gi - s) <= 1e-12 * max(gi, s) for s in seen):
            continue
        seen.append(gi)
        bodies = [model.body_name(j) for j in range(model.n_bodies) if abs(float(model.g[j]) - gi) <= 1e-12 * gi]
        orders.append({"name": f"{' / '.join(bodies)} 1x", "kind": "shaft", "harmonic": 1, "hz_per_rpm": gi / 60.0})
    points = []
    for o in orders:
        for md in result.modes:
            if md.rigid:
                continue
            n = md.frequency_Hz / o["hz_per_rpm"]
            if 0.0 < n <= max_speed_rpm:
                points.append({"order": o["name"], "mode": md.index, "speed_rpm": n, "frequency_Hz": md.frequency_Hz})
    points.sort(key=lambda p: p["speed_rpm"])
    return {"speed_axis_rpm": [0.0, float(max_speed_rpm)], "operating_speed_rpm": operating_speed_rpm,
            "orders": orders,
            "modes_Hz": [m.frequency_Hz for m in result.modes if not m.rigid],
            "interferences": points}
