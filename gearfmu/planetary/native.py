"""Native (numba) solver of drivetrains with planetary stages (SI units; docs/planetary.md).

One monolithic system: every mesh -- parallel-axis stages and every sun-planet and ring-planet
mesh of every planetary stage -- is the multi-pair model on its own tables (per-pair stiffness,
damping, meshing error, backlash; docs/model.md), the springs (shafts, bearings, supports) couple
the DOFs, and the event-aware integrators stop at the events of every mesh.  The compiled loop is
:func:`gearfmu.planetary.kernels.run`; this module checks the arguments, lays out the kernel data
and wraps the outputs.

Public API: :func:`simulate` (settings: :class:`gearfmu.common.settings.GearboxRunSettings`, as the
gearbox solver's), :func:`choose_max_step_s`, :func:`resolve_settings`, :class:`PlanetaryResult` (output columns
by name: ``sun_speed`` style part speeds ``<part>_speed``, ``<stage>.sun_planet[n].dte``,
``<stage>.load_sharing_factor[n]`` ...; ``to_csv``).
"""
from __future__ import annotations

import dataclasses
import time as _time
from dataclasses import dataclass, field
from typing import Dict, Optional, Tuple

import numpy as np

from ..common.checks import finite_number
from ..common.progress import progress_bar
from ..common.settings import SOLVER_ARGUMENTS, GearboxRunSettings, checked, default_output_interval_s
from ..common.vocabulary import INTEGRATORS
from ..dynamics.native import (InputLike, choose_max_step_s as pair_max_step_s, input_series, substeps, write_columns_csv)
from ..gearbox._pair import KINK_MAX_SLOTS
from ..gearbox.kernels import stop_flags
from ..gearbox.native import _NO_CUTS, _torque_rows, drivetrain_inputs
from ..tables.zones import zone_cuts
from .kernels import (F_A0, F_AREF, F_C, F_DPHI, F_INV, F_PHI0, F_X0, FF, FI, I_A0, I_B, I_CUTS, I_E, I_FLAGS, I_K,
                      I_MD, I_MODEL, I_N, I_NA, I_NP, I_NX, I_ROWS2, I_WK, I_X0, I_ZONED, MF, MI, SF, SI, SP, WK, run)
from .model import PlanetaryModel
from .modes import modes

__all__ = ["PlanetaryInputError", "PlanetaryResult", "simulate", "choose_max_step_s", "output_units",
           "resolve_settings", "default_output_interval", "checked_settings", "run_inputs", "columns", "drive_inputs"]


class PlanetaryInputError(ValueError):
    """Bad argument to the planetary solver; the message names the argument."""


@dataclass
class PlanetaryResult:
    """Result of :func:`simulate` (SI).  Row 0 is the initial state with the inputs of step 0, then one
    row per communication step.  ``columns``: output name -> (unit, array); ``result["name"]`` reads
    one.  ``state``: the solver state after the last step."""

    time_s: np.ndarray
    columns: Dict[str, Tuple[str, np.ndarray]]
    step_s: float
    substeps: int
    integrator: str
    wall_s: float
    state: np.ndarray
    info: dict = field(default_factory=dict)

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name][1]

    def names(self):
        return list(self.columns)

    def to_csv(self, path) -> None:
        write_columns_csv(path, {"time": ("s", self.time_s), **self.columns})


def output_units(model: PlanetaryModel) -> Dict[str, str]:
    """Every output name and its unit (docs/planetary.md "Outputs")."""
    out = {}
    for i, nm in enumerate(model.dof_names):
        if model.dof_kind[i] == "rot":
            out[f"{nm}_angle"], out[f"{nm}_speed"] = "rad", "rad/s"
        else:
            out[f"{nm}"], out[f"{nm}_rate"] = "m", "m/s"
    for p in model.parts:
        d = model.part_dof[p]
        if model.dof_names[d] != p:
            out[f"{p}_angle"], out[f"{p}_speed"] = "rad", "rad/s"
    for m, nm in enumerate(model.mesh_names):
        t = model.mesh_tables[m]
        out[f"{nm}.dte"], out[f"{nm}.dte_rate"], out[f"{nm}.mesh_force"] = "m", "m/s", "N"
        for i in range(t.slots):
            out[f"{nm}.pair_force[{i + 1}]"] = "N"
        for i in range(t.slots):
            out[f"{nm}.load_sharing[{i + 1}]"] = "1"
        out[f"{nm}.mesh_stiffness"] = "N/m"
    for st in model.stages:
        for n in range(st["planets"]):
            out[f"{st['name']}.load_sharing_factor[{n + 1}]"] = "1"
    for nm in model.spring_names:
        out[f"{nm}.force"] = "N*m" if _torsional(model, nm) else "N"
    out["motor_torque"] = "N*m"
    out["load_torque"] = "N*m"
    return out


def _torsional(model: PlanetaryModel, spring: str) -> bool:
    s = model.spring_names.index(spring)
    return all(model.dof_kind[i] == "rot" for i in model.spring_idx[s] if i >= 0) and \
        model.spring_kind[s] in ("shaft", "support")


def choose_max_step_s(model: PlanetaryModel, motor_speed_rad_s: float, points_per_period: int = 64,
                      reference_torque_Nm: float = 0.0) -> float:
    """Default largest internal step (s): the pair rule of every mesh at its table speed
    (gearfmu.dynamics.native.choose_max_step_s) and the period of the highest natural frequency of
    the linearisation over ``points_per_period``."""
    w = abs(finite_number("motor_speed_rad_s", motor_speed_rad_s, error=PlanetaryInputError))
    ts = np.abs(model.table_speeds(w)) if model.drives else None   # the drives at their default speeds
    h = min(pair_max_step_s(t, w * abs(float(model.angle_ref[m])) if ts is None else max(w * abs(float(
        model.angle_ref[m])), float(ts[m])), points_per_period) for m, t in enumerate(model.mesh_tables))
    f_max = max(md.frequency_Hz for md in modes(model, reference_torque_Nm).modes)
    if f_max > 0.0:
        h = min(h, 1.0 / f_max / points_per_period)
    return h


class _KernelData:
    """The flat data of gearfmu.planetary.kernels (its module docstring) and the arrays whose
    addresses it holds (kept alive here while a run uses them)."""

    def __init__(self, model: PlanetaryModel, icode: int = INTEGRATORS["rk4_node"]):
        nm = len(model.mesh_names)
        self.keep = []
        self.mi = np.zeros(nm * MI, dtype=np.int64)
        self.mf = np.zeros(nm * MF)
        self.pair_off = np.zeros(nm + 1, dtype=np.int64)
        self.rows = []
        self.tables = []     # per mesh (k, e, b, contact-zone cuts or None): the arrays mi addresses
        for m, t in enumerate(model.mesh_tables):
            k = np.ascontiguousarray(t.k_N_per_m, dtype=np.float64)
            e = np.ascontiguousarray(t.e_m, dtype=np.float64)
            b = np.ascontiguousarray(t.backlash_half_m, dtype=np.float64)
            cuts = zone_cuts(t)
            zoned = cuts is not None
            cuts = np.ascontiguousarray(cuts) if zoned else _NO_CUTS
            flags = stop_flags(k, e, b, cuts, zoned, icode)
            md = np.zeros(4 * t.slots + 2, dtype=np.int64)
            wk = np.zeros(WK)
            self.keep += [k, e, b, cuts, flags, md, wk]
            self.tables.append((k, e, b, cuts if zoned else None))
            o, f = m * MI, m * MF
            xs = [(int(d), float(c)) for d, c in zip(model.mesh_idx[m], model.mesh_coef[m]) if d >= 0]
            ans = [(int(d), float(c)) for d, c in zip(model.angle_idx[m], model.angle_coef[m]) if d >= 0]
            self.mi[o + I_NX] = len(xs)
            for j, (d, c) in enumerate(xs):
                self.mi[o + I_X0 + j], self.mf[f + F_X0 + j] = d, c
            self.mi[o + I_NA] = len(ans)
            for j, (d, c) in enumerate(ans):
                self.mi[o + I_A0 + j], self.mf[f + F_A0 + j] = d, c
            self.mi[o + I_N], self.mi[o + I_NP] = t.n_phi, t.slots
            self.mi[o + I_MODEL] = {"elastobacklash": 0, "contact_zone": 1}[model.mesh_damping_model[m]]
            self.mi[o + I_ZONED] = 1 if zoned else 0
            for slot, arr in ((I_K, k), (I_E, e), (I_B, b), (I_FLAGS, flags), (I_CUTS, cuts), (I_MD, md), (I_WK, wk)):
                self.mi[o + slot] = arr.ctypes.data
            self.mi[o + I_ROWS2] = 1 if k.shape[0] > 1 else 0
            phi = float(t.phi_period_rad)
            self.mf[f + F_AREF] = model.angle_ref[m]
            self.mf[f + F_PHI0] = model.angle_phase[m]
            self.mf[f + F_DPHI] = phi / t.n_phi
            self.mf[f + F_INV] = t.n_phi / phi
            self.mf[f + F_C] = model.mesh_c[m]
            self.pair_off[m + 1] = self.pair_off[m] + t.slots
            self.rows.append(np.ascontiguousarray(t.torque_Nm, dtype=np.float64))
        self.bf = np.concatenate([1.0 / model.mass, model.g]).astype(np.float64)
        ns = len(model.spring_names)
        self.si = np.zeros(ns * SI, dtype=np.int64)
        self.sf = np.zeros(ns * SF)
        for s in range(ns):
            ent = [(int(d), float(c)) for d, c in zip(model.spring_idx[s], model.spring_coef[s]) if d >= 0]
            self.si[s * SI] = len(ent)
            for j, (d, c) in enumerate(ent):
                self.si[s * SI + 1 + j], self.sf[s * SF + j] = d, c
            self.sf[s * SF + SP], self.sf[s * SF + SP + 1] = model.spring_k[s], model.spring_c[s]
        nf = model.frame_idx.shape[0]
        fd, fh = model.frame_drives()
        self.fi = np.zeros(nf * FI, dtype=np.int64)
        self.ff = np.zeros(nf * FF)
        for r in range(nf):
            self.fi[FI * r:FI * r + 3] = (model.frame_idx[r, 0], model.frame_idx[r, 1], fd[r])
            self.ff[FF * r:FF * r + 3] = (model.frame_par[r, 0], model.frame_par[r, 1], fh[r])
        self.n = model.n_dof


def _integrator_code(integrator, model) -> int:
    """The code of a (checked) gearbox integrator name; the event-locating integrators handle at most
    KINK_MAX_SLOTS slots per mesh."""
    if integrator != "rk4":
        for m, t in enumerate(model.mesh_tables):
            if t.slots > KINK_MAX_SLOTS:
                raise PlanetaryInputError(f"integrator: {integrator!r} handles at most {KINK_MAX_SLOTS} slots, mesh "
                                          f"{model.mesh_names[m]!r} has {t.slots}")
    return INTEGRATORS[integrator]


def default_output_interval(model: PlanetaryModel, settings: GearboxRunSettings) -> float:
    """The output interval of a run that gives none: the shortest over the meshes of
    :func:`gearfmu.common.settings.default_output_interval_s` at the speed of the mesh's table angle
    (the motor's start speed times its ratio) and its pinion's teeth, at most the stop time."""
    w = settings.motor_speed_start_rad_s
    ws = (np.abs(model.table_speeds(w)) if model.drives else np.abs(w * model.angle_ref.astype(float)))
    return min(min(default_output_interval_s(float(ws[m]), t.teeth_pinion)
                   for m, t in enumerate(model.mesh_tables)), settings.stop_time_s)


def checked_settings(model, settings, error=PlanetaryInputError, **changes) -> GearboxRunSettings:
    """The run's checked settings (``settings`` with the changes given), the output interval set."""
    s = checked(settings, error, GearboxRunSettings, SOLVER_ARGUMENTS, **changes)
    if s.output_interval_s is None and isinstance(model, PlanetaryModel):
        s = dataclasses.replace(s, output_interval_s=default_output_interval(model, s))
    return s


def resolve_settings(model: PlanetaryModel, settings: GearboxRunSettings,
                     reference_torque_Nm: Optional[float] = None) -> GearboxRunSettings:
    """``settings`` with its automatic values resolved on the model: the output interval
    (:func:`default_output_interval`) and the step bound (:func:`choose_max_step_s` at 1.5 x the
    motor's start speed, at least 1 rad/s, linearised at ``reference_torque_Nm``)."""
    s = settings
    if s.output_interval_s is None:
        s = dataclasses.replace(s, output_interval_s=default_output_interval(model, s))
    if s.max_step_s is None:
        s = dataclasses.replace(s, max_step_s=choose_max_step_s(model, max(1.5 * abs(s.motor_speed_start_rad_s), 1.0),
                                                                 reference_torque_Nm=reference_torque_Nm or 0.0))
    return s


def run_inputs(model, s: GearboxRunSettings, motor_torque_Nm, load_torque_Nm, initial_state,
               error=PlanetaryInputError):
    """(n_steps, motor torque, load torque, reference torque, initial state or None) of a run with
    checked settings ``s`` whose output interval is set, by the rules of
    :func:`gearfmu.gearbox.native.run_inputs` (``motor_torque_Nm`` None: the settings' start torque
    held; ``load_torque_Nm`` None: the balancing load, else the settings' start torque; an end that is
    no torque input takes 0)."""
    if not isinstance(model, PlanetaryModel):
        raise error(f"model: expected PlanetaryModel, got {type(model).__name__}")
    return drivetrain_inputs(model, s, motor_torque_Nm, load_torque_Nm, initial_state, error, "psi, omega, q_i, q_i'")


#: the keyword arguments of :func:`simulate` that replace a field of its settings
SETTING_ARGUMENTS = ("stop_time_s", "comm_step_s", "motor_speed_start_rad_s", "max_step_s", "integrator",
                     "motor_angle_start_rad")


def simulate(model: PlanetaryModel, settings: Optional[GearboxRunSettings] = None, *,
             motor_torque_Nm: Optional[InputLike] = None, load_torque_Nm: Optional[InputLike] = None,
             initial_state=None, drive_speeds_rad_s: Optional[Dict[str, InputLike]] = None, progress: bool = False,
             **setting_changes) -> PlanetaryResult:
    """Run the model (docs/planetary.md); settings and arguments as gearfmu.gearbox.native.simulate:
    ``settings`` a :class:`gearfmu.common.settings.GearboxRunSettings` (None: its defaults), the keyword
    arguments of the same meaning (:data:`SETTING_ARGUMENTS`: ``stop_time_s``, ``comm_step_s``,
    ``motor_speed_start_rad_s``, ``max_step_s``, ``integrator``, ``motor_angle_start_rad``) replace its
    fields; inputs a number, an array of one value per communication step or a callable of t_k;
    ``load_torque_Nm`` None = the balancing load torque; ``max_step_s`` None: :func:`choose_max_step_s`
    at 1.5 x the start speed; initial state: ``initial_state`` or the quasi-static equilibrium
    (:meth:`gearfmu.planetary.model.PlanetaryModel.static_state`); ``integrator`` 'rk4_node' (default),
    'rk4_kink' or 'rk4'.  ``drive_speeds_rad_s``: per driven member (its port, e.g. ``"ps.ring"``) the
    speed of its drive (rad/s; a number, an array per communication step or a callable of t_k), set at
    the start of every step (None: the model's, docs/planetary.md "Driven members")."""
    unknown = sorted(set(setting_changes) - set(SETTING_ARGUMENTS))
    if unknown:
        raise TypeError(f"simulate() got unexpected keyword arguments {unknown}")
    ch = {k: setting_changes.get(k) for k in SETTING_ARGUMENTS}
    ch["output_interval_s"] = ch.pop("comm_step_s")
    s = checked_settings(model, settings, **ch)
    n_steps, t_in, t_out, t_ref, y_given = run_inputs(model, s, motor_torque_Nm, load_torque_Nm, initial_state)
    icode = _integrator_code(s.integrator, model)
    s = resolve_settings(model, s, reference_torque_Nm=float(t_ref[0]))
    H, w0 = s.output_interval_s, s.motor_speed_start_rad_s
    n_sub = substeps(H, s.max_step_s)
    h = H / n_sub
    kd = _KernelData(model, icode)
    nm = len(model.mesh_names)
    it_rows = np.zeros((n_steps + 1, nm), dtype=np.int64)
    wt_rows = np.zeros((n_steps + 1, nm))
    for m in range(nm):
        it_rows[:, m], wt_rows[:, m] = _torque_rows(kd.rows[m], np.abs(t_ref * model.mesh_torque_per_ref[m]))
    drv_dof, drv_w = drive_inputs(model, drive_speeds_rad_s, n_steps, H)
    y = (model.static_state(float(t_ref[0]), w0, s.motor_angle_start_rad, drive_speeds_rad_s=drv_w[0])
         if y_given is None else y_given)
    y = np.ascontiguousarray(y, dtype=np.float64)
    n = model.n_dof
    rows = n_steps + 1
    out_dof = np.full((rows, 2 * n), np.nan)
    out_mesh = np.full((rows, 4 * nm), np.nan)
    out_pair = np.full((rows, int(kd.pair_off[-1])), np.nan)
    out_spring = np.full((rows, len(model.spring_names)), np.nan)
    events = np.zeros(rows, dtype=np.int64)
    args = (H, n_sub, h, kd.mi, kd.mf, kd.bf, kd.si, kd.sf, kd.fi, kd.ff, n, int(model.load_dof), out_dof, out_mesh,
            out_pair, kd.pair_off, out_spring, events, drv_dof, drv_w)
    run(icode, y.copy(), t_in, t_out, it_rows, wt_rows, 0, 0, *args)   # compile (or load) before timing
    chunk = n_steps if not progress else max(1, n_steps // 100)
    wall = 0.0
    done = 0
    with progress_bar(None, "planetary", progress, total=n_steps, unit="step") as bar:
        while done < n_steps:
            k = min(chunk, n_steps - done)
            t0 = _time.perf_counter()
            got = run(icode, y, t_in, t_out, it_rows, wt_rows, done, k, *args)
            wall += _time.perf_counter() - t0
            done += got
            bar.update(got)
            if got < k:
                break
    info = {"events": int(events.sum()), "completed_steps": int(done), "reference_torque_Nm": t_ref,
            "settings": s}
    if model.drives:
        info["drive_speeds_rad_s"] = drv_w   # (steps + 1, drives): the speed each drive held over each step
    if done < n_steps:
        info["diverged_at_step"] = int(done)
    cols = columns(model, kd.pair_off, out_dof, out_mesh, out_pair, out_spring, t_in, t_out)
    return PlanetaryResult(time_s=np.arange(rows) * H, columns=cols, step_s=h, substeps=n_sub, integrator=s.integrator,
                           wall_s=wall, state=y, info=info)


def drive_inputs(model: PlanetaryModel, drive_speeds_rad_s, n_steps: int, H: float, error=PlanetaryInputError):
    """(drive DOFs, speeds (n_steps + 1, drives) in rad/s) of a run: per driven member the speed given
    for its port (a number, an array per step or a callable of t_k), else the model's."""
    dofs = np.array(model.drive_dofs, dtype=np.int64)
    w = np.zeros((n_steps + 1, len(model.drives)))
    given = dict(drive_speeds_rad_s or {})
    ports = [d["port"] for d in model.drives]
    for k in given:
        if k not in ports:
            raise error(f"drive_speeds_rad_s[{k!r}]: not a driven member; driven are {ports}")
    for j, d in enumerate(model.drives):
        v = given.get(d["port"], d["speed_rad_s"])
        w[:, j] = input_series(f"drive_speeds_rad_s[{d['port']!r}]", v, n_steps, H, error=error)
    return dofs, w


def columns(model, pair_off, out_dof, out_mesh, out_pair, out_spring, t_in, t_out):
    """Output name -> (unit, array) from the kernel rows; load sharing per pair as the pair model
    defines it; the load-sharing factor of planet n, L_n = N F_sn / sum_k F_sk (its sun-mesh force
    over the mean of the stage's sun-mesh forces; Kahraman 1994)."""
    units = output_units(model)
    cols = {}
    for i, nm in enumerate(model.dof_names):
        if model.dof_kind[i] == "rot":
            cols[f"{nm}_angle"], cols[f"{nm}_speed"] = out_dof[:, 2 * i], out_dof[:, 2 * i + 1]
        else:
            cols[nm], cols[f"{nm}_rate"] = out_dof[:, 2 * i], out_dof[:, 2 * i + 1]
    for p in model.parts:
        d = model.part_dof[p]
        if model.dof_names[d] != p:
            cols[f"{p}_angle"], cols[f"{p}_speed"] = out_dof[:, 2 * d], out_dof[:, 2 * d + 1]
    force = {}
    for m, nm in enumerate(model.mesh_names):
        cols[f"{nm}.dte"] = out_mesh[:, 4 * m]
        cols[f"{nm}.dte_rate"] = out_mesh[:, 4 * m + 1]
        f = out_mesh[:, 4 * m + 2]
        force[nm] = f
        cols[f"{nm}.mesh_force"] = f
        pf = out_pair[:, pair_off[m]:pair_off[m + 1]]
        for i in range(pf.shape[1]):
            cols[f"{nm}.pair_force[{i + 1}]"] = pf[:, i]
        ls = np.zeros(pf.shape)
        with np.errstate(invalid="ignore", divide="ignore"):
            np.divide(pf, f[:, None], out=ls, where=f[:, None] != 0.0)
        ls[np.isnan(f)] = np.nan
        for i in range(pf.shape[1]):
            cols[f"{nm}.load_sharing[{i + 1}]"] = ls[:, i]
        cols[f"{nm}.mesh_stiffness"] = out_mesh[:, 4 * m + 3]
    for st in model.stages:
        N = st["planets"]
        fs = np.stack([force[f"{st['name']}.sun_planet[{n + 1}]"] for n in range(N)])
        tot = fs.sum(axis=0)
        with np.errstate(invalid="ignore", divide="ignore"):
            lsf = np.where(tot != 0.0, N * fs / np.where(tot != 0.0, tot, 1.0), np.nan)
        for n in range(N):
            cols[f"{st['name']}.load_sharing_factor[{n + 1}]"] = lsf[n]
    for s, nm in enumerate(model.spring_names):
        cols[f"{nm}.force"] = out_spring[:, s]
    cols["motor_torque"] = t_in
    cols["load_torque"] = t_out
    return {name: (units[name], np.ascontiguousarray(a)) for name, a in cols.items()}
