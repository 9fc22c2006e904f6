"""The planetary drivetrain kernel in C (kernel/plkernel.h, pl_kernel.c, pl_static.c) from Python.

:func:`kernel_data` is the flat data of a :class:`gearfmu.planetary.model.PlanetaryModel` as the C
kernel takes it -- read from the very arrays the numba solver runs on
(:class:`gearfmu.planetary.native._KernelData`), so that the two hold the same numbers: per DOF 1/m and
g, per spring its DOFs, coefficients, k and c, per frame its DOFs, R0 and ratio, per mesh its tables
(k, e, b, contact-zone cuts), the maps of its x and table angle, the damping ratio that gives the
numba solver's per-pair damping c exactly in gk_set_damping, and per planetary stage the load-sharing
group of its sun-planet meshes (Kahraman 1994).  An FMU builder writes it into the FMU; :class:`PlanetaryKernel`
loads it into a compiled kernel library through ctypes (the signatures of
:data:`gearfmu.fmu.runtime.kernel_api.PLANETARY_FUNCTIONS`).

:func:`compile_planetary_kernel` compiles the library (the pair kernel, its FMU layer and the planetary
kernel, with the kernel's flags: no fused multiply-add).
"""
from __future__ import annotations

import ctypes
import math
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Tuple

import numpy as np

from ..common.vocabulary import DAMPING_MODELS, GEARBOX_INTEGRATORS, INTEGRATORS
from ..planetary.kernels import (F_A0, F_AREF, F_C, F_PHI0, F_X0, FF, FI, I_A0, I_NA, I_NX, I_X0, MF, MI, SF, SI, SP)
from ..planetary.model import PlanetaryModel
from ..planetary.native import _KernelData
from .build_steps import CFLAGS, KERNEL_DIR, KERNEL_LIBRARY_SOURCES, FmuBuildError, run_compiler
from .runtime.kernel_api import KernelError, load_kernel

__all__ = ["PLANETARY_SOURCES", "PLANETARY_HEADERS", "MeshData", "KernelData", "kernel_data", "damping_ratio_for",
           "compile_planetary_kernel", "PlanetaryKernel"]

#: the planetary kernel's C files (compiled beside the pair kernel's KERNEL_SOURCES) and headers
PLANETARY_SOURCES = (KERNEL_DIR / "pl_kernel.c", KERNEL_DIR / "pl_static.c")
PLANETARY_HEADERS = (KERNEL_DIR / "plkernel.h", KERNEL_DIR / "pl_internal.h")


@dataclass(frozen=True)
class MeshData:
    """One mesh of :func:`kernel_data`: gk_init's tables and scalars, its zone edges, damping, maps."""

    name: str
    tables: object                      # MeshTables (torque axis, radii, inertias, k_mean, engagement angles)
    torque_Nm: np.ndarray
    k_N_per_m: np.ndarray
    e_m: np.ndarray
    backlash_half_m: np.ndarray
    cuts: Optional[np.ndarray]          # contact-zone cuts (2, P, N) or None (plain lookup)
    damping_ratio: float                # zeta with 2 zeta sqrt(k_mean m_e) == c in gk_set_damping
    damping_model: int                  # GK_DAMPING_*
    c_Ns_per_m: float
    x_dof: Tuple[int, ...]
    x_coef: Tuple[float, ...]
    a_dof: Tuple[int, ...]
    a_coef: Tuple[float, ...]
    a_ref: float
    phase_rad: float
    torque_per_ref: float


@dataclass(frozen=True)
class KernelData:
    """The flat data of a PlanetaryModel for pl_init / pl_add_* (module docstring)."""

    n_dof: int
    inv_m: np.ndarray
    g: np.ndarray
    load_dof: int
    motor_input: bool
    load_input: bool
    springs: Tuple[Tuple[Tuple[int, ...], Tuple[float, ...], float, float], ...]   # (dofs, coefs, k, c)
    frames: Tuple[Tuple[int, int, float, float], ...]                            # (a, b, R0, ratio)
    meshes: Tuple[MeshData, ...]
    groups: Tuple[Tuple[int, ...], ...]                                           # sun-planet meshes of a stage
    drives: Tuple[Tuple[int, np.ndarray], ...] = ()                               # (drive DOF, rigid motion)
    frame_drives: Tuple[Tuple[int, int, float], ...] = ()                         # (frame, drive DOF, its ratio)


def damping_ratio_for(tables, c_Ns_per_m: float) -> float:
    """The damping ratio zeta whose c = 2 zeta sqrt(k_mean m_e) (gk_model.c gk_set_damping, with m_e =
    I1 I2 / (I1 Rb2^2 + I2 Rb1^2) as gk_init evaluates it) is ``c_Ns_per_m`` to the last bit."""
    i1, i2 = float(tables.inertia_pinion_kgm2), float(tables.inertia_gear_kgm2)
    r1, r2 = float(tables.base_radius_pinion_m), float(tables.base_radius_gear_m)
    root = math.sqrt(float(tables.k_mean_N_per_m) * (i1 * i2 / (i1 * r2 * r2 + i2 * r1 * r1)))
    c = float(c_Ns_per_m)
    zeta = c / (2.0 * root)
    for _ in range(64):
        got = 2.0 * zeta * root
        if got == c:
            return zeta
        zeta = math.nextafter(zeta, math.inf if got < c else -math.inf)
    raise FmuBuildError(f"damping: no damping ratio gives the per-pair damping {c!r} N*s/m exactly")


def kernel_data(model: PlanetaryModel) -> KernelData:
    """The flat data of ``model`` for the C kernel, read from the numba solver's own arrays."""
    if not isinstance(model, PlanetaryModel):
        raise FmuBuildError(f"model: expected PlanetaryModel, got {type(model).__name__}")
    kd = _KernelData(model)
    meshes = []
    for m, t in enumerate(model.mesh_tables):
        o, f = m * MI, m * MF
        nx, na = int(kd.mi[o + I_NX]), int(kd.mi[o + I_NA])
        k, e, b, cuts = kd.tables[m]
        c = float(kd.mf[f + F_C])
        meshes.append(MeshData(
            name=model.mesh_names[m], tables=t, torque_Nm=kd.rows[m], k_N_per_m=k, e_m=e, backlash_half_m=b,
            cuts=cuts, damping_ratio=damping_ratio_for(t, c), damping_model=DAMPING_MODELS[model.mesh_damping_model[m]],
            c_Ns_per_m=c, x_dof=tuple(int(d) for d in kd.mi[o + I_X0:o + I_X0 + nx]),
            x_coef=tuple(float(x) for x in kd.mf[f + F_X0:f + F_X0 + nx]),
            a_dof=tuple(int(d) for d in kd.mi[o + I_A0:o + I_A0 + na]),
            a_coef=tuple(float(x) for x in kd.mf[f + F_A0:f + F_A0 + na]),
            a_ref=float(kd.mf[f + F_AREF]), phase_rad=float(kd.mf[f + F_PHI0]),
            torque_per_ref=float(model.mesh_torque_per_ref[m])))
    springs = []
    for s in range(len(model.spring_names)):
        cnt = int(kd.si[s * SI])
        springs.append((tuple(int(d) for d in kd.si[s * SI + 1:s * SI + 1 + cnt]),
                        tuple(float(x) for x in kd.sf[s * SF:s * SF + cnt]), float(kd.sf[s * SF + SP]),
                        float(kd.sf[s * SF + SP + 1])))
    frames = tuple((int(kd.fi[FI * r]), int(kd.fi[FI * r + 1]), float(kd.ff[FF * r]), float(kd.ff[FF * r + 1]))
                   for r in range(kd.fi.shape[0] // FI))
    frame_drives = tuple((r, int(kd.fi[FI * r + 2]), float(kd.ff[FF * r + 2])) for r in range(kd.fi.shape[0] // FI)
                         if kd.fi[FI * r + 2] >= 0)
    groups = tuple(tuple(model.mesh_names.index(f"{st['name']}.sun_planet[{n + 1}]") for n in range(st["planets"]))
                   for st in model.stages)
    n = kd.n
    return KernelData(n_dof=n, inv_m=np.ascontiguousarray(kd.bf[:n]), g=np.ascontiguousarray(kd.bf[n:]),
                      load_dof=int(model.load_dof), motor_input=bool(model.motor_torque_input),
                      load_input=bool(model.load_torque_input), springs=tuple(springs), frames=frames,
                      meshes=tuple(meshes), groups=groups,
                      drives=tuple((int(d["dof"]), np.ascontiguousarray(d["mode"], dtype=np.float64))
                                   for d in model.drives), frame_drives=frame_drives)


def compile_planetary_kernel(dest_dir, *, cc: Optional[str] = None) -> Path:
    """Compile the pair kernel, its FMU layer and the planetary kernel into one shared library in
    ``dest_dir`` (``<cc> -O2 -fPIC -shared -ffp-contract=off -std=c99``); return its path."""
    cc = cc or shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        raise FmuBuildError("compiler: no C compiler (gcc or cc) on the PATH")
    dest = Path(dest_dir)
    dest.mkdir(parents=True, exist_ok=True)
    lib = dest / "libgearplanetary.so"
    run_compiler([cc, *CFLAGS, "-o", str(lib), *(str(p) for p in (*PLANETARY_SOURCES, *KERNEL_LIBRARY_SOURCES)),
                  "-lm"], "planetary kernel")
    return lib


def _buf(nbytes: int) -> np.ndarray:
    return np.zeros(nbytes // 8 + 1)


class PlanetaryKernel:
    """A PlanetaryModel in the C kernel: the pair model of every mesh (gk_init, its contact-zone cuts and
    edges, its damping), the pl_model of :func:`kernel_data`, a state, a work and a Model Exchange mode.
    ``lib``: a library of :func:`compile_planetary_kernel` or its path; ``integrator``: 'rk4', 'rk4_kink'
    or 'rk4_node'.  Every call checks its status (:class:`KernelError`)."""

    def __init__(self, lib, model: PlanetaryModel, integrator: str = "rk4_node"):
        if not isinstance(lib, ctypes.CDLL):
            lib = load_kernel(lib, check=True, planetary=True)
        self.lib, self.model = lib, model
        self.data = data = kernel_data(model)
        self.keep = []
        self.pairs = []
        for md in data.meshes:
            t = md.tables
            pm = _buf(lib.gk_sizeof_model())
            arrs = [np.ascontiguousarray(a, dtype=np.float64) for a in (md.torque_Nm, md.k_N_per_m, md.e_m,
                                                                        md.backlash_half_m)]
            self.keep += arrs
            lib.gk_init(pm.ctypes.data, t.slots, t.n_phi, len(md.torque_Nm), *(a.ctypes.data for a in arrs),
                        t.phi_period_rad, t.base_radius_pinion_m, t.base_radius_gear_m, t.inertia_pinion_kgm2,
                        t.inertia_gear_kgm2, t.k_mean_N_per_m)
            if md.cuts is not None:
                cuts = np.ascontiguousarray(md.cuts, dtype=np.float64)
                self.keep.append(cuts)
                lib.gk_set_zone_cuts(pm.ctypes.data, cuts.ctypes.data)
                lib.gk_set_zone_edges(pm.ctypes.data, t.mesh_period_rad, t.engagement_in_rad, t.engagement_out_rad)
            lib.gk_set_damping(pm.ctypes.data, md.damping_ratio, md.damping_model)
            self.pairs.append(pm)
        self.pl = _buf(lib.pl_sizeof_model())
        self.work = _buf(lib.pl_sizeof_work())
        self.state = _buf(lib.pl_sizeof_state())
        self.me = _buf(lib.pl_sizeof_me())
        P = self.pl.ctypes.data
        lib.pl_init(P, data.n_dof, data.inv_m.ctypes.data, data.g.ctypes.data, data.load_dof, int(data.motor_input),
                    int(data.load_input))
        for dofs, coefs, k, c in data.springs:
            d, cf = np.array(dofs, dtype=np.intc), np.array(coefs, dtype=np.float64)
            lib.pl_add_spring(P, len(dofs), d.ctypes.data, cf.ctypes.data, k, c)
        for a, b, R0, ratio in data.frames:
            lib.pl_add_frame(P, a, b, R0, ratio)
        for md, pm in zip(data.meshes, self.pairs):
            xd, xc = np.array(md.x_dof, dtype=np.intc), np.array(md.x_coef, dtype=np.float64)
            ad, ac = np.array(md.a_dof or (0,), dtype=np.intc), np.array(md.a_coef or (0.0,), dtype=np.float64)
            lib.pl_add_mesh(P, pm.ctypes.data, len(md.x_dof), xd.ctypes.data, xc.ctypes.data, len(md.a_dof),
                            ad.ctypes.data, ac.ctypes.data, md.a_ref, md.phase_rad, md.torque_per_ref)
        for grp in data.groups:
            gi = np.array(grp, dtype=np.intc)
            lib.pl_add_group(P, len(grp), gi.ctypes.data)
        for dof, mode in data.drives:
            self.keep.append(mode)
            lib.pl_add_drive(P, dof, mode.ctypes.data)
        for r, dof, ratio in data.frame_drives:
            lib.pl_set_frame_drive(P, r, dof, ratio)
        self.set_integrator(integrator)
        self.n_out = lib.pl_n_outputs(P)
        self.n = data.n_dof

    # ------------------------------------------------------------ Co-Simulation
    def set_integrator(self, integrator: str) -> None:
        if integrator not in GEARBOX_INTEGRATORS:
            raise FmuBuildError(f"integrator: {integrator!r} unknown for the planetary kernel")
        self.lib.pl_set_integrator(self.pl.ctypes.data, INTEGRATORS[integrator])

    @property
    def y(self) -> np.ndarray:
        """The state (psi, omega, q_1, q_1', ...), a copy."""
        return self.state[:2 * self.n].copy()

    def set_state(self, y) -> None:
        self.state[:2 * self.n] = np.asarray(y, dtype=np.float64)

    def initialize(self, T_ref_Nm: float, speed_rad_s: float, angle_rad: float = 0.0,
                   drive_speeds_rad_s=None) -> np.ndarray:
        """pl_initialize_driven with the drives at ``drive_speeds_rad_s`` (None: the model's): the static
        state into the kernel's state; returns it."""
        bad = ctypes.c_int(-1)
        w = np.ascontiguousarray(self.model.drive_speeds(drive_speeds_rad_s), dtype=np.float64)
        self.lib.pl_initialize_driven(self.pl.ctypes.data, self.work.ctypes.data, self.state.ctypes.data, angle_rad,
                                      speed_rad_s, T_ref_Nm, w.ctypes.data if self.data.drives else None,
                                      ctypes.addressof(bad))
        return self.y

    def set_drive_speeds(self, speeds_rad_s) -> None:
        """pl_set_drive_speeds: every drive's speed (rad/s, in drive order) into the state."""
        w = np.ascontiguousarray(speeds_rad_s, dtype=np.float64).reshape(-1)
        if w.size != len(self.data.drives):
            raise FmuBuildError(f"speeds_rad_s: expected {len(self.data.drives)} drive speeds, got {w.size}")
        self.lib.pl_set_drive_speeds(self.pl.ctypes.data, self.state.ctypes.data, w.ctypes.data if w.size else None)

    def step(self, T_motor_Nm: float, T_load_Nm: float, H_s: float, h_max_s: float) -> np.ndarray:
        """pl_do_step; returns the outputs after the step."""
        out = np.empty(self.n_out)
        self.lib.pl_do_step(self.pl.ctypes.data, self.work.ctypes.data, self.state.ctypes.data, T_motor_Nm,
                            T_load_Nm, H_s, h_max_s, out.ctypes.data)
        return out

    def outputs(self, T_motor_Nm: float, T_load_Nm: float) -> np.ndarray:
        out = np.empty(self.n_out)
        self.lib.pl_outputs(self.pl.ctypes.data, self.work.ctypes.data, self.state.ctypes.data, T_motor_Nm,
                            T_load_Nm, out.ctypes.data)
        return out

    def derivatives(self, y, T_motor_Nm: float, T_load_Nm: float) -> np.ndarray:
        y = np.ascontiguousarray(y, dtype=np.float64)
        dy = np.empty(2 * self.n)
        self.lib.pl_derivatives(self.pl.ctypes.data, self.work.ctypes.data, 0.0, y.ctypes.data, T_motor_Nm,
                                T_load_Nm, dy.ctypes.data)
        return dy

    @property
    def events(self) -> int:
        return int(self.lib.pl_events(self.work.ctypes.data))

    def mesh_offset(self, m: int) -> int:
        return int(self.lib.pl_mesh_offset(self.pl.ctypes.data, m))

    def spring_offset(self) -> int:
        return int(self.lib.pl_spring_offset(self.pl.ctypes.data))

    def group_offset(self, g: int) -> int:
        return int(self.lib.pl_group_offset(self.pl.ctypes.data, g))

    # ---------------------------------------------------------- Model Exchange
    def _me(self, y):
        y = np.ascontiguousarray(y, dtype=np.float64)
        return y, (self.pl.ctypes.data, self.work.ctypes.data, self.me.ctypes.data, y.ctypes.data)

    def n_indicators(self, node_events: int) -> int:
        return int(self.lib.pl_me_n_indicators(self.pl.ctypes.data, node_events))

    def me_init(self, y, T_motor_Nm: float, T_load_Nm: float, node_events: int = 0) -> None:
        y, a = self._me(y)
        self.lib.pl_me_init(*a, T_motor_Nm, T_load_Nm, node_events)

    def me_update(self, y, T_motor_Nm: float, T_load_Nm: float) -> int:
        y, a = self._me(y)
        changed = ctypes.c_int(0)
        self.lib.pl_me_update(*a, T_motor_Nm, T_load_Nm, ctypes.addressof(changed))
        return changed.value

    def me_derivatives(self, y, T_motor_Nm: float, T_load_Nm: float) -> np.ndarray:
        y, a = self._me(y)
        dy = np.empty(2 * self.n)
        self.lib.pl_me_derivatives(*a, T_motor_Nm, T_load_Nm, dy.ctypes.data)
        return dy

    def me_indicators(self, y, T_motor_Nm: float, T_load_Nm: float, node_events: int = 0) -> np.ndarray:
        y, a = self._me(y)
        z = np.empty(max(self.n_indicators(node_events), 1))
        self.lib.pl_me_indicators(*a, T_motor_Nm, T_load_Nm, z.ctypes.data)
        return z[:self.n_indicators(node_events)]

    def me_outputs(self, y, T_motor_Nm: float, T_load_Nm: float) -> np.ndarray:
        y, a = self._me(y)
        out = np.empty(self.n_out)
        self.lib.pl_me_outputs(*a, T_motor_Nm, T_load_Nm, out.ctypes.data)
        return out


__all__ += ["KernelError"]
