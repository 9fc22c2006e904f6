"""Native (numba) solver of the gearbox model (SI units; docs/gearbox.md).

One monolithic system: every mesh is the multi-pair model of its stage (per-pair stiffness,
damping, meshing error, backlash; the pair model's lookup and force law, docs/model.md), the
shafts couple the bodies, and the event-aware integrators stop at the events of every mesh.
The compiled loop is :func:`gearfmu.gearbox.kernels.run`; this module checks the inputs (the
settings are a :class:`gearfmu.common.settings.GearboxRunSettings`, checked where they are made),
lays out the kernel data, and wraps the outputs.

Public API
----------
* :func:`simulate` -- run a :class:`gearfmu.gearbox.model.GearboxModel`.
* :func:`choose_max_step_s` -- the default internal step; :func:`resolve_settings` -- a run's
  automatic values (output interval, step bound) resolved on the model.
* :class:`GearboxResult` -- output columns by name (``motor_speed``, ``s1.dte``,
  ``input_shaft.torque`` ...), ``to_csv``.
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
from ..dynamics.native import (InputLike, choose_max_step_s as pair_max_step_s, input_series, substeps, whole_steps,
                               write_columns_csv)
from ..tables.zones import zone_cuts
from ._pair import KINK_MAX_SLOTS
from .kernels import F_C, F_DPHI, F_G, F_INV, F_RBP, F_RBQ, I_B, I_CUTS, I_E, I_FLAGS, I_K, I_MD, I_MODEL, I_N, \
    I_NP, I_P, I_Q, I_ROWS2, I_WK, I_ZONED, MF, MI, WK, run, stop_flags
from .model import GearboxModel
from .modes import modes

__all__ = ["GearboxInputError", "GearboxResult", "simulate", "choose_max_step_s", "output_units", "resolve_settings",
           "default_output_interval", "checked_settings", "run_inputs", "columns"]

_NO_CUTS = np.full((2, 1, 1), -1.0)


class GearboxInputError(ValueError):
    """Bad argument to the gearbox solver; the message names the argument."""


@dataclass
class GearboxResult:
    """Result of :func:`simulate` (SI units).  Row 0 is the initial state with the inputs of step
    0, then one row per communication step.  ``columns``: output name -> (unit, array), in the
    order of docs/gearbox.md "Outputs"; ``result["s1.dte"]`` reads one.  ``state``: the solver state
    y (psi, omega, u_i, du_i) after the last step (for continuing a run)."""

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
        """The CSV layout of the pair solver's results (gearfmu.dynamics.native.write_columns_csv): a
        '# units:' line, a row of output names (``time`` first), the data with 17 significant digits."""
        write_columns_csv(path, {"time": ("s", self.time_s), **self.columns})


def output_units(model: GearboxModel) -> Dict[str, str]:
    """Every output name of a model's runs and its unit (docs/gearbox.md "Outputs")."""
    out = {}
    for p in model.parts:
        out[f"{p}_angle"] = "rad"
        out[f"{p}_speed"] = "rad/s"
    for m in model.meshes:
        out[f"{m.name}.dte"] = "m"
        out[f"{m.name}.dte_rate"] = "m/s"
        out[f"{m.name}.mesh_force"] = "N"
        for i in range(m.tables.slots):
            out[f"{m.name}.pair_force[{i + 1}]"] = "N"
        for i in range(m.tables.slots):
            out[f"{m.name}.load_sharing[{i + 1}]"] = "1"
        out[f"{m.name}.mesh_stiffness"] = "N/m"
    for s in model.shafts:
        out[f"{s.name}.torque"] = "N*m"
    out["motor_torque"] = "N*m"
    out["load_torque"] = "N*m"
    return out


def choose_max_step_s(model: GearboxModel, motor_speed_rad_s: float, points_per_period: int = 64,
                      reference_torque_Nm: Optional[float] = None) -> float:
    """Default largest internal step (s): the pair rule of every stage at its pinion speed
    (gearfmu.dynamics.native.choose_max_step_s: the stage's mesh period and its own two-inertia
    period over ``points_per_period``) and the period of the highest natural frequency of the
    gearbox's mean-stiffness linearisation (shafts and meshes coupled) over the same number."""
    w = abs(finite_number("motor_speed_rad_s", motor_speed_rad_s, error=GearboxInputError))
    h = min(pair_max_step_s(m.tables, w * float(model.g[model.mesh_bodies[i, 0]]), points_per_period)
            for i, m in enumerate(model.meshes))
    t_ref = 0.0 if reference_torque_Nm is None else reference_torque_Nm
    f_max = max(md.frequency_Hz for md in modes(model, t_ref).modes)
    if f_max > 0.0:
        h = min(h, 1.0 / f_max / points_per_period)
    return h


def _torque_rows(tq: np.ndarray, torque: np.ndarray):
    """(it, wt) per value of ``torque`` by docs/model.md "Torque axis": Tq = clamp(T), it the
    largest index in [0, NT-2] with tq[it] <= Tq, wt = (Tq - tq[it])/(tq[it+1] - tq[it])."""
    if tq.size == 1:
        return np.zeros(torque.shape, dtype=np.int64), np.zeros(torque.shape)
    q = np.clip(torque, tq[0], tq[-1])
    it = np.clip(np.searchsorted(tq, q, side="right") - 1, 0, tq.size - 2).astype(np.int64)
    return it, (q - tq[it]) / (tq[it + 1] - tq[it])


class _KernelData:
    """The flat per-mesh data of gearfmu.gearbox.kernels (its module docstring) and the arrays
    whose addresses it holds (kept alive here while a run uses them)."""

    def __init__(self, model: GearboxModel, icode: int = INTEGRATORS["rk4_node"]):
        nm = len(model.meshes)
        self.keep = []
        self.mi = np.zeros(nm * MI, dtype=np.int64)
        self.mf = np.zeros(nm * MF)
        self.pair_off = np.zeros(nm + 1, dtype=np.int64)
        self.rows = []
        for m, mesh in enumerate(model.meshes):
            t = mesh.tables
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
            o, f = m * MI, m * MF
            p, q = model.mesh_bodies[m]
            self.mi[o + I_P], self.mi[o + I_Q] = p, q
            self.mi[o + I_N], self.mi[o + I_NP] = t.n_phi, t.slots
            self.mi[o + I_MODEL] = {"elastobacklash": 0, "contact_zone": 1}[mesh.damping_model]
            self.mi[o + I_ZONED] = 1 if zoned else 0
            for slot, arr in ((I_K, k), (I_E, e), (I_B, b), (I_FLAGS, flags), (I_CUTS, cuts), (I_MD, md),
                              (I_WK, wk)):
                self.mi[o + slot] = arr.ctypes.data
            self.mi[o + I_ROWS2] = 1 if k.shape[0] > 1 else 0
            phi = float(t.phi_period_rad)
            self.mf[f + F_RBP], self.mf[f + F_RBQ] = model.mesh_rb_m[m]
            self.mf[f + F_DPHI] = phi / t.n_phi
            self.mf[f + F_INV] = t.n_phi / phi   # docs/model.md "Table lookup": N/Phi, one rounding
            self.mf[f + F_C] = model.mesh_c_Ns_per_m[m]
            self.mf[f + F_G] = model.g[p]
            self.pair_off[m + 1] = self.pair_off[m] + t.slots
            self.rows.append(np.ascontiguousarray(t.torque_Nm, dtype=np.float64))
        n = model.n_bodies
        self.bf = np.concatenate([1.0 / model.inertia_kgm2, model.g]).astype(np.float64)
        self.si = np.ascontiguousarray(model.shaft_bodies.reshape(-1), dtype=np.int64)
        self.sf = np.ascontiguousarray(np.column_stack([model.shaft_k_Nm_per_rad, model.shaft_c_Nms_per_rad])
                                       .reshape(-1), dtype=np.float64)
        self.n = n


def _integrator_code(integrator, model) -> int:
    """The code of a (checked) gearbox integrator name; the event-locating integrators handle at most
    KINK_MAX_SLOTS slots per mesh."""
    if integrator != "rk4":
        for i, m in enumerate(model.meshes):
            if m.tables.slots > KINK_MAX_SLOTS:
                raise GearboxInputError(f"integrator: {integrator!r} handles at most {KINK_MAX_SLOTS} slots, the "
                                        f"tables of mesh {m.name!r} have {m.tables.slots}")
    return INTEGRATORS[integrator]


def default_output_interval(model: GearboxModel, settings: GearboxRunSettings) -> float:
    """The output interval of a run that gives none: the shortest over the meshes of
    :func:`gearfmu.common.settings.default_output_interval_s` at the mesh pinion's speed (the
    motor's start speed times its ratio) and teeth, at most the stop time (the rule of a
    drivetrain scene's ``run.output_interval_s = "auto"``, docs/gearbox.md)."""
    w = settings.motor_speed_start_rad_s
    return min(min(default_output_interval_s(w * float(model.g[model.mesh_bodies[i, 0]]), m.tables.teeth_pinion)
                   for i, m in enumerate(model.meshes)), settings.stop_time_s)


def resolve_settings(model: GearboxModel, settings: GearboxRunSettings,
                     reference_torque_Nm: Optional[float] = None) -> GearboxRunSettings:
    """``settings`` with its automatic values resolved on the model: the output interval
    (:func:`default_output_interval`) and the step bound (:func:`choose_max_step_s` at 1.5 x the
    motor's start speed, at least 1 rad/s, linearised at ``reference_torque_Nm``)."""
    s = settings
    if s.output_interval_s is None:
        s = dataclasses.replace(s, output_interval_s=default_output_interval(model, s))
    if s.max_step_s is None:
        s = dataclasses.replace(s, max_step_s=choose_max_step_s(model, max(1.5 * abs(s.motor_speed_start_rad_s), 1.0),
                                                                 reference_torque_Nm=reference_torque_Nm))
    return s


def run_inputs(model, s: GearboxRunSettings, motor_torque_Nm, load_torque_Nm, initial_state, error=GearboxInputError):
    """(n_steps, motor torque, load torque, reference torque, initial state or None) of a run with
    checked settings ``s`` whose output interval is set: the inputs one value per communication step
    (n_steps + 1; ``motor_torque_Nm`` None: the settings' start torque held; ``load_torque_Nm``
    None: the balancing load T_motor/g_load of the motor input given, else the settings' start
    torque held, else the balance), the motor-side reference torque that selects the torque rows
    (:meth:`GearboxModel.reference_torque_Nm` per step) and a given initial state (None: the
    quasi-static one).  ``error`` names the first bad one."""
    if not isinstance(model, GearboxModel):
        raise error(f"model: expected GearboxModel, got {type(model).__name__}")
    return drivetrain_inputs(model, s, motor_torque_Nm, load_torque_Nm, initial_state, error, "psi, omega, u_i, du_i")


def drivetrain_inputs(model, s: GearboxRunSettings, motor_torque_Nm, load_torque_Nm, initial_state, error, state: str):
    """:func:`run_inputs` of any drivetrain model with ``motor_torque_input``, ``load_torque_input``,
    ``load_ratio`` and ``n_state`` (a gearbox, a planetary drivetrain); ``state`` names the state's
    entries in the message on a bad initial state."""
    H = s.output_interval_s
    n_steps = whole_steps(s.stop_time_s, H, error=error)
    t_in = input_series("motor_torque_Nm", s.motor_torque_start_Nm if motor_torque_Nm is None else motor_torque_Nm,
                        n_steps, H, error=error)
    if load_torque_Nm is None and motor_torque_Nm is None:
        load_torque_Nm = s.load_torque_start_Nm
    if load_torque_Nm is None:
        if not model.motor_torque_input:
            raise error("load_torque_Nm: required when the motor is no torque input")
        t_out = t_in / model.load_ratio
    else:
        t_out = input_series("load_torque_Nm", load_torque_Nm, n_steps, H, error=error)
    if not model.motor_torque_input:
        t_in = np.zeros_like(t_in)
    if not model.load_torque_input:
        t_out = np.zeros_like(t_out)
    t_ref = t_in if model.motor_torque_input else t_out * model.load_ratio
    y = None
    if initial_state is not None:
        y = np.array(initial_state, dtype=np.float64)
        if y.shape != (model.n_state,) or not np.all(np.isfinite(y)):
            raise error(f"initial_state: expected {model.n_state} finite values ({state})")
    return n_steps, t_in, t_out, t_ref, y


def checked_settings(model, settings, error=GearboxInputError, **changes) -> GearboxRunSettings:
    """The run's checked settings (``settings`` with the changes given), the output interval set."""
    s = checked(settings, error, GearboxRunSettings, SOLVER_ARGUMENTS, **changes)
    if s.output_interval_s is None and isinstance(model, GearboxModel):
        s = dataclasses.replace(s, output_interval_s=default_output_interval(model, s))
    return s


def simulate(model: GearboxModel, settings: Optional[GearboxRunSettings] = None, *,
             stop_time_s: Optional[float] = None, comm_step_s: Optional[float] = None,
             motor_torque_Nm: Optional[InputLike] = None, load_torque_Nm: Optional[InputLike] = None,
             motor_speed_start_rad_s: Optional[float] = None, max_step_s: Optional[float] = None,
             integrator: Optional[str] = None, motor_angle_start_rad: Optional[float] = None, initial_state=None,
             progress: bool = False) -> GearboxResult:
    """Run the gearbox model (docs/gearbox.md).

    ``settings``: the run's :class:`gearfmu.common.settings.GearboxRunSettings` (None: its
    defaults); the keyword arguments of the same meaning, when given, replace its fields:
    ``stop_time_s``, ``comm_step_s`` (the communication step = ``output_interval_s``; None:
    :func:`default_output_interval`), ``motor_speed_start_rad_s``, ``motor_angle_start_rad``,
    ``max_step_s`` (None: :func:`choose_max_step_s` at 1.5 x the start speed), ``integrator``
    ('rk4_node' (default), 'rk4_kink' or 'rk4', docs/gearbox.md "Integrators").
    Inputs (N*m): a number, an array of one value per communication step (n or n + 1 values;
    value k is held over [t_k, t_k + H)) or a callable of t_k; ``motor_torque_Nm`` None: the
    settings' start torque held; ``load_torque_Nm`` None = the balancing load torque
    T_motor/g_load (without a motor input: the settings' load start torque, when set).  An end
    that is no torque input (``model.motor_torque_input`` / ``load_torque_input`` False) takes 0.
    Initial state: ``initial_state`` (the ``state`` of an earlier result) or the quasi-static
    equilibrium under the start torques at the motor angle (:meth:`GearboxModel.static_state`).
    If the state turns non-finite the run stops there; the remaining rows are NaN and
    ``info['diverged_at_step']`` says where.  ``progress``: a bar on stderr (the run goes in chunks
    of steps; results unchanged)."""
    s = checked_settings(model, settings, stop_time_s=stop_time_s, output_interval_s=comm_step_s,
                         max_step_s=max_step_s, integrator=integrator, motor_speed_start_rad_s=motor_speed_start_rad_s,
                         motor_angle_start_rad=motor_angle_start_rad)
    n_steps, t_in, t_out, t_ref, y_given = run_inputs(model, s, motor_torque_Nm, load_torque_Nm, initial_state)
    icode = _integrator_code(s.integrator, model)
    s = resolve_settings(model, s, reference_torque_Nm=float(t_ref[0]))
    H, w0 = s.output_interval_s, s.motor_speed_start_rad_s
    n_sub = substeps(H, s.max_step_s)
    h = H / n_sub
    kd = _KernelData(model, icode)
    nm = len(model.meshes)
    it_rows = np.zeros((n_steps + 1, nm), dtype=np.int64)
    wt_rows = np.zeros((n_steps + 1, nm))
    for m in range(nm):
        if model.meshes[m].name in model.on_path:
            it_rows[:, m], wt_rows[:, m] = _torque_rows(kd.rows[m], t_ref / model.g[model.mesh_bodies[m, 0]])
        else:
            it_rows[:, m], wt_rows[:, m] = _torque_rows(kd.rows[m], np.zeros(n_steps + 1))
    y = model.static_state(float(t_ref[0]), w0, s.motor_angle_start_rad) if y_given is None else y_given
    y = np.ascontiguousarray(y, dtype=np.float64)
    n = model.n_bodies
    rows = n_steps + 1
    out_body = np.full((rows, 2 * n), np.nan)
    out_mesh = np.full((rows, 4 * nm), np.nan)
    out_pair = np.full((rows, int(kd.pair_off[-1])), np.nan)
    out_shaft = np.full((rows, len(model.shafts)), np.nan)
    events = np.zeros(rows, dtype=np.int64)
    args = (H, n_sub, h, kd.mi, kd.mf, kd.bf, kd.si, kd.sf, n, int(model.load_body), out_body, out_mesh, out_pair,
            kd.pair_off, out_shaft, events)
    run(icode, y.copy(), t_in, t_out, it_rows, wt_rows, 0, 0, *args)   # compile (or load) before timing
    chunk = n_steps if not progress else max(1, n_steps // 100)
    wall = 0.0
    done = 0
    with progress_bar(None, "gearbox", progress, total=n_steps, unit="step") as bar:
        while done < n_steps:
            k = min(chunk, n_steps - done)
            t0 = _time.perf_counter()
            got = run(icode, y, t_in, t_out, it_rows, wt_rows, done, k, *args)
            wall += _time.perf_counter() - t0
            done += got
            bar.update(got)
            if got < k:
                break
    info = {"events": int(events.sum()), "completed_steps": int(done), "reference_torque_Nm": t_ref}
    if done < n_steps:
        info["diverged_at_step"] = int(done)
    cols = columns(model, kd.pair_off, out_body, out_mesh, out_pair, out_shaft, t_in, t_out)
    return GearboxResult(time_s=np.arange(rows) * H, columns=cols, step_s=h, substeps=n_sub, integrator=s.integrator,
                         wall_s=wall, state=y, info=info)


def columns(model, pair_off, out_body, out_mesh, out_pair, out_shaft, t_in, t_out):
    """Output name -> (unit, array) from the rows the kernels write (per body angle and speed,
    per mesh x, v, force, stiffness, the pair forces at columns pair_off[m]..pair_off[m+1], per
    shaft torque) and the inputs; the load sharing derived as docs/model.md defines it."""
    units = output_units(model)
    cols = {}
    for p in model.parts:
        b = model.part_body[p]
        cols[f"{p}_angle"] = out_body[:, 2 * b]
        cols[f"{p}_speed"] = out_body[:, 2 * b + 1]
    for m, mesh in enumerate(model.meshes):
        nm = mesh.name
        cols[f"{nm}.dte"] = out_mesh[:, 4 * m]
        cols[f"{nm}.dte_rate"] = out_mesh[:, 4 * m + 1]
        f = out_mesh[:, 4 * m + 2]
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
    for s, sh in enumerate(model.shafts):
        cols[f"{sh.name}.torque"] = out_shaft[:, s]
    cols["motor_torque"] = t_in
    cols["load_torque"] = t_out
    return {name: (units[name], np.ascontiguousarray(a)) for name, a in cols.items()}
