"""Table precomputation: gear pair -> :class:`gearfmu.tables.mesh_tables.MeshTables` (SI units).

Chain: geometry (:func:`gearfmu.gear.geometry.pair_geometry`) -> per-slot sliced
stiffness (:func:`gearfmu.gear.stiffness.slot_stiffness`) -> per-pair meshing
errors (:mod:`gearfmu.gear.meshing_errors`) -> loaded static mesh with lead
crowning (:mod:`gearfmu.gear.loaded_mesh`, Zhao et al. 2022 eq 16) -> tables.
Choices are documented in docs/physics_errors.md.
"""
from __future__ import annotations

import inspect
import math
from dataclasses import dataclass, replace
import time
from typing import Optional, Sequence

import numpy as np

from ..gear.gearpair import GearPairSpec, GearSpec, MeshModelOptions
from ..gear.loaded_mesh import loaded_static_mesh
from ..gear.meshing_errors import (comprehensive_error_m, pair_lead_crowning_m, pair_table_mesh_count,
                             slot_errors_m, slot_slice_errors_m, stiffness_weighted_pair_error_m)
from .contact_rows import (ContactIteration, PrecomputeInputError, contact_provenance, normal_section_provenance,
                           per_slice_stiffness)
from ..common.vocabulary import TEMPERATURE_INPUTS
from ..tables.mesh_tables import MeshTables, stack_temperatures
from ..tables.zones import mean_total_stiffness_N_per_m
from ..common.progress import progress_bar
from ..contact.models import get_contact_model
from ..ehl.lubricant import roelands_alpha_at_viscosity_Pa_inv
from ..gear.geometry import pair_geometry
from ..gear.stiffness import slot_stiffness, required_slots
from ..gear.thermal import (thermal_state_from_scene, thermal_slot_stiffness, ThermalState, ThermalError,
                            oil_dynamic_viscosity_Pas)

#: default torque axis with lead crowning, as multiples of the nominal torque
DEFAULT_TORQUE_FACTORS = (0.1, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 2.0)


def default_slots(contact_ratio: float) -> int:
    """Slot count P = ceil(contact ratio), at least 1 (eps = 1.0001 -> 2), for a scalar
    contact ratio; the slot count of a gear pair is :func:`gearfmu.gear.stiffness.required_slots`."""
    if not math.isfinite(contact_ratio) or contact_ratio <= 0:
        raise PrecomputeInputError(f"contact_ratio: must be finite and > 0, got {contact_ratio!r}")
    return max(1, int(math.ceil(contact_ratio - 1e-12)))


def disc_inertia_kgm2(gear: GearSpec) -> float:
    """Rotary inertia (kg m^2) of a gear: ``gear.inertia_kgm2`` or, when None, a
    solid disc of the gear's material between the hub bore and the reference
    pitch radius r = m z / 2: I = rho pi b (r^4 - r_hub^4) / 2 (solid cylinder,
    e.g. any statics/dynamics textbook).  For Xu et al. 2022 Table 1 (z = 50,
    m = 3 mm, b = 20 mm, steel 7850 kg/m^3, no bore) this gives 0.00780 kg m^2
    against the table's 0.0074 kg m^2 (+5.5 %)."""
    if gear.inertia_kgm2 is not None:
        if not math.isfinite(gear.inertia_kgm2) or gear.inertia_kgm2 <= 0:
            raise PrecomputeInputError(f"inertia_kgm2: must be finite and > 0, got {gear.inertia_kgm2!r}")
        return float(gear.inertia_kgm2)
    r = 0.5 * gear.module_m * gear.teeth
    rh = 0.0 if gear.hub_radius_m is None else float(gear.hub_radius_m)
    rho = gear.material.density_kg_m3
    if not math.isfinite(rho) or rho <= 0:
        raise PrecomputeInputError(f"density_kg_m3: must be finite and > 0, got {rho!r}")
    if not 0 <= rh < r:
        raise PrecomputeInputError(f"hub_radius_m: must be in [0, pitch radius {r!r}), got {rh!r}")
    return rho * math.pi * gear.face_width_m * (r ** 4 - rh ** 4) / 2.0


def _step(bar, what: str) -> None:
    """One step of a table progress bar, ``what`` shown beside it."""
    bar.set_postfix_str(what, refresh=False)
    bar.update(1)


def _torque_axis(torque_axis_Nm, nominal_torque_Nm: float, crowned: bool) -> np.ndarray:
    if not math.isfinite(nominal_torque_Nm) or nominal_torque_Nm <= 0:
        raise PrecomputeInputError(f"nominal_torque_Nm: must be finite and > 0, got {nominal_torque_Nm!r}")
    if torque_axis_Nm is None:
        if crowned:
            return nominal_torque_Nm * np.asarray(DEFAULT_TORQUE_FACTORS, dtype=float)
        return np.array([float(nominal_torque_Nm)])
    t = np.atleast_1d(np.asarray(torque_axis_Nm, dtype=float))
    if t.ndim != 1 or t.size < 1:
        raise PrecomputeInputError(f"torque_axis_Nm: expected a 1-D sequence, got shape {t.shape}")
    if not np.all(np.isfinite(t)) or np.any(t < 0):
        raise PrecomputeInputError("torque_axis_Nm: values must be finite and >= 0")
    if t.size > 1 and not np.all(np.diff(t) > 0):
        raise PrecomputeInputError("torque_axis_Nm: must be strictly ascending")
    return t


def _slot_stiffness(pair, geom, opts, slots, points_per_mesh, torque_Nm):
    try:
        params = inspect.signature(slot_stiffness).parameters
    except (TypeError, ValueError):
        params = {}
    if "torque_Nm" in params:
        return slot_stiffness(pair, geom, opts, slots, points_per_mesh, torque_Nm=torque_Nm)
    return slot_stiffness(pair, geom, opts, slots, points_per_mesh)


def _stiffness_depends_on_load() -> bool:
    try:
        return "torque_Nm" in inspect.signature(slot_stiffness).parameters
    except (TypeError, ValueError):
        return False


#: torque axis (multiples of the nominal torque) given to the tables of a load-dependent
#: contact model (EHL film) when no axis with at least two torques is asked for
LOAD_DEPENDENT_TORQUE_FACTORS = (0.5, 1.0, 1.5)


@dataclass
class _PairRows:
    """What the torque rows of a pair's tables are computed from (SI): the pair, its model options
    and geometry, the slot count P, the angle points per mesh period, the table's mesh periods
    ``n_mesh``, the pair meshing errors ``e_slot`` (P, n) (stiffness-weighted over the slices of a
    helical pair), the lead crowning per slice ``E`` (NS,) and the slot stiffness when it does not
    depend on the load (``ss_cache``; None: computed per torque)."""

    pair: GearPairSpec
    opts: MeshModelOptions
    geom: object
    slots: int
    points_per_mesh: int
    n_mesh: int
    e_slot: np.ndarray
    E: np.ndarray
    ss_cache: Optional[object] = None

    @property
    def reps(self) -> int:
        """Table mesh periods per slot."""
        return self.n_mesh // self.slots

    @property
    def slices(self) -> int:
        return int(self.opts.slices)

    @property
    def crowned(self) -> bool:
        """Lead crowning: the slices have different crowning (Zhao et al. 2022 eq 16)."""
        return bool(np.any(self.E != self.E[0]))

    @property
    def rb1(self) -> float:
        return float(self.geom.rb1_m)

    def slot_stiffness(self, torque_Nm):
        """The slot stiffness (:func:`gearfmu.gear.stiffness.slot_stiffness`) at a pinion torque
        (N m; the load-independent one where kept)."""
        if self.ss_cache is not None:
            return self.ss_cache
        return _slot_stiffness(self.pair, self.geom, self.opts, self.slots, self.points_per_mesh, torque_Nm)


def _compute_rows(rows, contact_it, pr: _PairRows, torques, nominal_torque_Nm, bar):
    """Stiffness and error rows of the tables, one per torque of ``rows`` (N m): the slice
    stiffness (with a load-dependent contact model, the contact iteration's at the row's slice
    loads) through the loaded static mesh (Zhao et al. 2022 eq 16); with lead crowning the row holds its
    secant stiffness and effective error, else the plain stiffness and the meshing error.
    Returns (k rows, e rows, static TE rows of ``torques``, k of the nominal torque)."""
    k_rows, e_rows, te_rows = [], [], []
    k_nominal = None
    for T in rows:
        if contact_it is not None:
            k_slice = contact_it.k_slice(T, pr.rb1)
            k_tile = k_slice.sum(axis=1)
        else:
            k_tile, k_slice = per_slice_stiffness(pr.slot_stiffness(T), pr.slices, pr.reps)
        lm = loaded_static_mesh(k_slice, pr.e_slot, pr.E, T / pr.rb1)
        if pr.crowned:
            k_row, e_row = lm.k_secant_N_per_m, lm.e_effective_m
        else:
            k_row, e_row = k_tile, pr.e_slot + pr.E[0]
        if T == nominal_torque_Nm:
            k_nominal = k_row
        if len(k_rows) < len(torques):
            k_rows.append(k_row)
            e_rows.append(e_row)
            te_rows.append(lm.static_te_m)
        _step(bar, f"torque {T:g} N m")
    return k_rows, e_rows, te_rows, k_nominal


def precompute_tables(pair: GearPairSpec, opts: MeshModelOptions, *, points_per_mesh: int = 64,
                      torque_axis_Nm: Optional[Sequence[float]] = None, nominal_torque_Nm: float,
                      slots: Optional[int] = None, progress: bool = False,
                      provenance: Optional[dict] = None, contact_env=None, thermal=None) -> MeshTables:
    """Precompute the tooth-pair tables of a gear pair.

    ``points_per_mesh``: angle points per mesh period 2 pi/z1; ``torque_axis_Nm``:
    pinion torques (N m) of the table rows (None: one row at the nominal torque,
    or with lead crowning ``DEFAULT_TORQUE_FACTORS`` x nominal);
    ``nominal_torque_Nm`` (N m, > 0): sets ``k_mean_N_per_m``; ``slots``: P
    (None: ceil(contact ratio)); ``progress``: progress bars on stderr
    (:func:`gearfmu.common.progress.progress_bar`).  Without lead crowning k is
    load-independent and the error tables are the meshing errors; with crowning every torque row holds the
    secant stiffness and effective error of :func:`gearfmu.gear.loaded_mesh.loaded_static_mesh`
    (they reproduce the loaded static TE of that row exactly).  Lead crowning
    only acts with ``opts.slices`` > 1 (one slice sits at the face centre).

    Load-dependent contact models (``opts.contact_model`` 'smooth_ehl',
    'rough_ehl', :mod:`gearfmu.contact.models`) need ``contact_env`` (a
    :class:`gearfmu.contact.models.ContactEnvironment`, e.g. from
    :func:`gearfmu.scene.physics.environment_from_scene`); every torque row
    then holds the slice stiffness with the contact stiffness at that row's
    slice loads, iterated with the loaded mesh (``LOAD_ITERATION_TOL``), and a
    torque axis of fewer than two values becomes ``LOAD_DEPENDENT_TORQUE_FACTORS``
    x nominal (docs/ehl_mesh.md).

    The tables carry the exact engagement of every pair, ``engagement_in_rad`` = 0 (point A)
    and ``engagement_out_rad`` = eps x mesh period, so that both kernels put the stiffness
    steps at meshing-in and meshing-out exactly there (docs/model.md "Contact-zone edges").
    """
    points_per_mesh = _checked_build_inputs(pair, opts, points_per_mesh)
    t_start = time.perf_counter()
    geom = pair_geometry(pair)
    slots = _slot_count(geom, slots)
    E = pair_lead_crowning_m(pair, int(opts.slices))
    torques, load_dep_k, axis_note = _table_torques(opts, torque_axis_Nm, nominal_torque_Nm,
                                                    bool(np.any(E != E[0])), contact_env)
    nominal_in_axis = bool(np.any(torques == nominal_torque_Nm))
    rows = list(torques) + ([] if nominal_in_axis else [float(nominal_torque_Nm)])
    # no time left: with a lubricated contact model the first rows build the film grid the later reuse
    bar = progress_bar(desc="gearfmu tables", enabled=progress, total=1 + len(rows), unit="step",
                       eta=opts.contact_model == "hertz", leave=False)
    pr, contact_it = _pair_rows(pair, opts, geom, slots, points_per_mesh, E, load_dep_k, contact_env,
                                nominal_torque_Nm, rows)
    _step(bar, f"errors + stiffness, {pr.n_mesh} mesh periods x {points_per_mesh} points, P={slots}")
    if contact_it is not None:
        contact_it.__enter__()
    try:
        k_rows, e_rows, te_rows, k_nominal = _compute_rows(rows, contact_it, pr, torques, nominal_torque_Nm, bar)
    finally:
        if contact_it is not None:
            contact_it.__exit__(None, None, None)
    bar.close()
    prov = _provenance(provenance, pr, load_dep_k, t_start, contact_it, axis_note)
    tables = _mesh_tables(pr, torques, (k_rows, e_rows, te_rows), k_nominal, prov)
    if thermal is not None:
        # He & Yang 2023 temperature stiffness / oil temperature (docs/thermal.md, docs/tables.md "Operating axes")
        tables = _apply_thermal(tables, pr, thermal, progress=progress, contact_env=contact_env,
                                nominal_torque_Nm=nominal_torque_Nm)
    return tables.validate()


def _checked_build_inputs(pair: GearPairSpec, opts: MeshModelOptions, points_per_mesh) -> int:
    """The angle points per mesh period (an integer >= 4), the slices and the backlash checked."""
    if int(points_per_mesh) != points_per_mesh or points_per_mesh < 4:
        raise PrecomputeInputError(f"points_per_mesh: must be an integer >= 4, got {points_per_mesh!r}")
    if int(opts.slices) != opts.slices or opts.slices < 1:
        raise PrecomputeInputError(f"slices: must be a positive integer, got {opts.slices!r}")
    if not math.isfinite(pair.backlash_m) or pair.backlash_m < 0:
        raise PrecomputeInputError(f"backlash_m: must be finite and >= 0, got {pair.backlash_m!r}")
    return int(points_per_mesh)


def _slot_count(geom, slots) -> int:
    """The slot count P: at least ceil(contact ratio) (:func:`gearfmu.gear.stiffness.required_slots`;
    spur: eps_alpha, helical: eps_gamma, docs/helical.md), that by default."""
    eps = float(geom.total_contact_ratio)
    p_min = required_slots(geom)
    if slots is None:
        slots = p_min
    if int(slots) != slots or slots < p_min:
        raise PrecomputeInputError(
            f"slots: must be an integer >= ceil(contact ratio {eps:.4f}) = {p_min}, got {slots!r}")
    return int(slots)


def _table_torques(opts: MeshModelOptions, torque_axis_Nm, nominal_torque_Nm: float, crowned: bool, contact_env):
    """(torque axis, stiffness depends on the load, note on an added axis): the axis of
    :func:`_torque_axis`; a load-dependent contact model needs ``contact_env`` and at least two
    torques (:data:`LOAD_DEPENDENT_TORQUE_FACTORS` x nominal otherwise)."""
    torques = _torque_axis(torque_axis_Nm, nominal_torque_Nm, crowned)
    load_dep_k = _stiffness_depends_on_load()
    axis_note = None
    if opts.contact_model != "hertz":
        cm = get_contact_model(opts.contact_model)
        if cm.load_dependent or cm.needs_lubricant:
            if contact_env is None:
                raise PrecomputeInputError(f"contact_env: contact_model {opts.contact_model!r} needs a "
                                           "ContactEnvironment (lubricant, speed, roughness)")
            if cm.load_dependent and torques.size < 2:
                torques = nominal_torque_Nm * np.asarray(LOAD_DEPENDENT_TORQUE_FACTORS, dtype=float)
                axis_note = (f"torque axis {list(LOAD_DEPENDENT_TORQUE_FACTORS)} x nominal added: "
                             f"contact model {opts.contact_model!r} is load-dependent")
            load_dep_k = True
    return torques, load_dep_k, axis_note


def _pair_rows(pair, opts, geom, slots, points_per_mesh, E, load_dep_k, contact_env, nominal_torque_Nm, rows):
    """The :class:`_PairRows` of a build and its contact iteration (None with Hertz contact):
    the meshing errors per pair (:mod:`gearfmu.gear.meshing_errors`), the contact iteration over
    the load range of ``rows`` (a contact model other than Hertz), the load-independent slot
    stiffness, and for a helical pair the stiffness-weighted pair error of its slices (they see
    different roll positions; the contact iteration uses it too)."""
    n_mesh = pair_table_mesh_count(pair, slots)
    reps = n_mesh // slots
    rb1 = float(geom.rb1_m)
    e_slot = slot_errors_m(pair, geom, slots, n_mesh, points_per_mesh)
    contact_it = None
    if opts.contact_model != "hertz":
        contact_it = ContactIteration(pair, geom, opts, contact_env, slots, points_per_mesh, reps, e_slot, E,
                                      nominal_torque_Nm / rb1)
        contact_it.set_load_range(rows, rb1)
    ss_cache = None
    if contact_it is None and not load_dep_k:
        ss_cache = _slot_stiffness(pair, geom, opts, slots, points_per_mesh, None)
    pr = _PairRows(pair, opts, geom, slots, points_per_mesh, n_mesh, e_slot, E, ss_cache)
    if geom.helix_angle_rad != 0.0:
        ss_w = pr.slot_stiffness(float(nominal_torque_Nm))
        pr.e_slot = stiffness_weighted_pair_error_m(
            slot_slice_errors_m(pair, geom, slots, n_mesh, points_per_mesh, pr.slices),
            per_slice_stiffness(ss_w, pr.slices, reps)[1])
        if contact_it is not None:
            contact_it.e = pr.e_slot
    return pr, contact_it


def _provenance(provenance, pr: _PairRows, load_dep_k: bool, t_start: float, contact_it, axis_note) -> dict:
    """The tables' provenance: the caller's, the build's ("precompute") and the contact model's."""
    opts, crowned = pr.opts, pr.crowned
    prov = dict(provenance or {})
    prov.setdefault("precompute", {
        "slots": pr.slots, "points_per_mesh": pr.points_per_mesh, "table_mesh_periods": pr.n_mesh,
        "slices": pr.slices, "lead_crowning_total_m": float(pr.E.max()) if crowned else 0.0,
        "contact_model": opts.contact_model, "foundation": bool(opts.foundation),
        "shared_foundation_correction": bool(opts.shared_foundation_correction),
        "torque_rows": "secant stiffness + effective error (seed 000 eq 16)" if crowned
        else ("load-dependent stiffness" if load_dep_k else "load-independent stiffness"),
        "wall_s": round(time.perf_counter() - t_start, 3),
    })
    if contact_it is not None:
        prov["contact"] = contact_provenance(contact_it, axis_note)
        if contact_it.helical is not None:  # the scene's speed, and the normal-section mapping
            prov["contact"].update(normal_section_provenance(contact_it.helical))
    return prov


def _mesh_tables(pr: _PairRows, torques, rows, k_nominal, prov: dict) -> MeshTables:
    """The single-temperature MeshTables of the rows (k, e, static TE) with the exact engagement
    of every pair, ``engagement_in_rad`` = 0 (point A) and ``engagement_out_rad`` = eps x mesh
    period, and the mean TVMS of the lookup (exact at the contact-zone edges, docs/tables.md;
    the damping) of the nominal torque's stiffness."""
    pair, geom = pr.pair, pr.geom
    k_rows, e_rows, te_rows = rows
    eps = float(geom.total_contact_ratio)  # spur: eps_alpha; helical: eps_gamma (docs/helical.md)
    k_arr = np.ascontiguousarray(np.stack(k_rows))
    e_arr = np.ascontiguousarray(np.stack(e_rows))
    e_comp = np.ascontiguousarray(comprehensive_error_m(e_arr, k_arr > 0))
    tables = MeshTables(
        torque_Nm=np.ascontiguousarray(torques, dtype=float),
        k_N_per_m=k_arr,
        e_m=e_arr,
        backlash_half_m=np.full((pr.slots, pr.n_mesh * pr.points_per_mesh), 0.5 * float(pair.backlash_m)),
        phi_period_rad=pr.n_mesh * float(geom.mesh_period_rad),
        mesh_period_rad=float(geom.mesh_period_rad),
        base_radius_pinion_m=pr.rb1,
        base_radius_gear_m=float(geom.rb2_m),
        inertia_pinion_kgm2=disc_inertia_kgm2(pair.pinion),
        inertia_gear_kgm2=disc_inertia_kgm2(pair.gear),
        teeth_pinion=int(pair.pinion.teeth),
        teeth_gear=int(pair.gear.teeth),
        contact_ratio=eps,
        k_mean_N_per_m=float(k_nominal.sum(axis=0).mean()),
        e_comprehensive_m=e_comp,
        static_te_m=np.ascontiguousarray(np.stack(te_rows)),
        provenance=prov,
        # exact meshing-in / meshing-out angles of every pair (phi = 0 is point A; the pair
        # leaves eps mesh periods later): the sub-cell lookup's zone edges (docs/tables.md)
        engagement_in_rad=0.0,
        engagement_out_rad=eps * float(geom.mesh_period_rad),
    )
    return replace(tables, k_mean_N_per_m=mean_total_stiffness_N_per_m(tables, k_nominal))


def _apply_thermal(tables: MeshTables, pr: _PairRows, thermal, *, progress, contact_env,
                   nominal_torque_Nm) -> MeshTables:
    """The ``[thermal]`` options (:class:`gearfmu.gear.thermal.ThermalOptions`) applied to
    single-temperature tables: a temperature axis whose meaning is
    ``thermal.axis_quantity`` ("bulk": :func:`_add_temperature_axis`; "oil" /
    "bulk_and_oil": :func:`_add_oil_temperature_axis`), else the gears' thermal
    state alone (:func:`_apply_thermal_state`; unchanged at the standard temperature)."""
    quantity = getattr(thermal, "axis_quantity", "bulk")
    has_axis = len(getattr(thermal, "temperature_axis_C", ()) or ()) > 0
    if has_axis and quantity in ("oil", "bulk_and_oil"):
        return _add_oil_temperature_axis(tables, pr.pair, pr.opts, thermal, contact_env=contact_env, slots=pr.slots,
                                         points_per_mesh=pr.points_per_mesh, nominal_torque_Nm=nominal_torque_Nm,
                                         progress=progress)
    if has_axis:
        if quantity != "bulk":
            raise PrecomputeInputError(f"axis_quantity: must be one of ('bulk', 'oil', 'bulk_and_oil'), got {quantity!r}")
        return _add_temperature_axis(tables, pr, thermal, progress=progress)
    state = thermal_state_from_scene(thermal)
    if _is_standard_state(state):
        return tables
    return _apply_thermal_state(tables, pr, state, getattr(thermal, "flank_law", "radial_tangential"),
                                progress=progress)


def _is_standard_state(state) -> bool:
    """Both gears uniformly at the standard temperature (no thermal compliance)."""
    t0 = float(state.standard_temperature_C)
    return all(not hasattr(t, "at_gamma") and float(t) == t0 for t in (state.pinion, state.gear))


def _thermal_rows(tables: MeshTables, pr: _PairRows, states, law, t0, *, progress=False,
                  label="gearfmu temperature axis"):
    """Per torque row T (N m, > 0) and thermal state (:class:`gearfmu.gear.thermal.ThermalState`):
    (k, e, static TE) arrays of shape (NT, NStates, P, n) / (NT, NStates, n).

    The ratio r = k_T/k of :func:`gearfmu.gear.thermal.thermal_slot_stiffness` (He & Yang 2023
    eq 5-28 at the state, load share of CHOICE 4), per slot and angle.  Without
    lead crowning the row's stiffness is r*k and its error unchanged; with
    crowning every slice stiffness is scaled by r (the thermal compliance is a
    series spring of the pair shared by its slices in proportion to their
    stiffness -- CHOICE, docs/tables.md) and the loaded mesh gives the row's
    secant stiffness and effective error.  At the standard state r = 1 exactly
    and the row equals the single-temperature row bit for bit."""
    torques = np.asarray(tables.torque_Nm, dtype=float)
    if np.any(torques <= 0):
        raise PrecomputeInputError(
            f"torque_axis_Nm: a non-standard temperature needs torques > 0 (seed 004 stiffness is a secant "
            f"stiffness under load), got {torques.tolist()!r}")
    rb1, reps = pr.rb1, pr.reps
    bar = progress_bar(desc=label, enabled=progress, total=len(torques), unit="row")
    k4, e4, te4 = [], [], []
    for it, T in enumerate(torques):
        k_tile, k_slice = per_slice_stiffness(pr.slot_stiffness(float(T)), pr.slices, reps)
        th = thermal_slot_stiffness(pr.pair, pr.opts, torque_Nm=float(T), states=states,
                                    standard_temperature_C=t0, slots=pr.slots, n_per_mesh=pr.points_per_mesh,
                                    law=law, geom=pr.geom)
        kstd = np.asarray(th.k_standard_N_per_m, dtype=float)
        if kstd.shape[-1] * reps != tables.n_phi or kstd.shape[0] != tables.slots:
            raise PrecomputeInputError(f"temperature axis: thermal grid {kstd.shape} does not tile the table "
                                       f"grid ({tables.slots}, {tables.n_phi})")
        k_row, e_row, te_row = [], [], []
        for a in range(len(states)):
            kt = np.asarray(th.k_N_per_m[a], dtype=float)
            ratio = np.tile(np.where(kstd > 0, kt / np.where(kstd > 0, kstd, 1.0), 0.0), (1, reps))
            lm = loaded_static_mesh(k_slice * ratio[:, None, :], pr.e_slot, pr.E, float(T) / rb1)
            if pr.crowned:
                k_row.append(lm.k_secant_N_per_m)
                e_row.append(lm.e_effective_m)
            else:
                k_row.append(tables.k_N_per_m[it] * ratio)
                e_row.append(tables.e_m[it])
            te_row.append(lm.static_te_m)
        k4.append(np.stack(k_row))
        e4.append(np.stack(e_row))
        te4.append(np.stack(te_row))
        _step(bar, f"torque {float(T):g} N m, {len(states)} thermal states")
    bar.close()
    return np.ascontiguousarray(np.stack(k4)), np.ascontiguousarray(np.stack(e4)), np.stack(te4)


def _add_temperature_axis(tables: MeshTables, pr: _PairRows, thermal, *, progress=False) -> MeshTables:
    """Tables with the temperature axis ``thermal.temperature_axis_C`` (degC; uniform
    bulk temperature of both gears, the FMU input ``bulk_temperature``;
    docs/tables.md "Operating axes", docs/thermal.md): :func:`_thermal_rows` at
    the states (t, t) of the axis, standard temperature
    ``thermal.standard_temperature_C``, ``thermal.flank_law``.
    Meshing errors and backlash do not depend on temperature (He & Yang 2023 models
    no thermal profile distortion); ``k_mean_N_per_m`` (the damping) stays the
    standard one.
    """
    axis = np.asarray(thermal.temperature_axis_C, dtype=float)
    t0 = float(thermal.standard_temperature_C)
    states = [ThermalState(float(t), float(t), t0) for t in axis]
    k_arr, e_arr, te = _thermal_rows(tables, pr, states, thermal.flank_law, t0, progress=progress)
    e_comp = np.ascontiguousarray(np.stack([comprehensive_error_m(e_arr[:, a], k_arr[:, a] > 0)
                                            for a in range(axis.size)], axis=1))
    prov = dict(tables.provenance)
    prov["thermal"] = {"temperature_axis_C": axis.tolist(), "standard_temperature_C": t0,
                       "flank_law": thermal.flank_law, "axis_quantity": "bulk", "input": "bulk_temperature",
                       "model": "seed 004 eq 5-28 (gearfmu.gear.thermal.thermal_slot_stiffness), k scaled by k_T/k"}
    return replace(tables, k_N_per_m=k_arr, e_m=e_arr, e_comprehensive_m=e_comp,
                   static_te_m=np.ascontiguousarray(te), provenance=prov,
                   temperature_C=np.ascontiguousarray(axis), temperature_reference_C=t0).validate()


def _state_description(state) -> dict:
    def one(t):
        if hasattr(t, "at_gamma"):
            return {"profile_gamma": list(t.gamma), "profile_C": list(t.temperature_C)}
        return float(t)
    return {"pinion_C": one(state.pinion), "gear_C": one(state.gear)}


def _apply_thermal_state(tables: MeshTables, pr: _PairRows, state, law, *, progress=False) -> MeshTables:
    """Single-temperature tables at a non-standard thermal state of the gears
    (``[thermal]`` pinion/gear temperatures or profiles without an axis): He & Yang 2023
    eq 27-28 at that state applied to every torque row by :func:`_thermal_rows`
    (docs/thermal.md "One temperature without an axis")."""
    k_arr, e_arr, te = _thermal_rows(tables, pr, [state], law, float(state.standard_temperature_C),
                                     progress=progress, label="gearfmu thermal state")
    k_arr, e_arr = np.ascontiguousarray(k_arr[:, 0]), np.ascontiguousarray(e_arr[:, 0])
    prov = dict(tables.provenance)
    prov["thermal"] = {"state": _state_description(state),
                       "standard_temperature_C": float(state.standard_temperature_C), "flank_law": law,
                       "model": "seed 004 eq 5-28 (gearfmu.gear.thermal.thermal_slot_stiffness), k scaled by k_T/k"}
    return replace(tables, k_N_per_m=k_arr, e_m=e_arr,
                   e_comprehensive_m=np.ascontiguousarray(comprehensive_error_m(e_arr, k_arr > 0)),
                   static_te_m=np.ascontiguousarray(te[:, 0]), provenance=prov).validate()


def oil_axis_eta0_Pas(lubricant, temperatures_C) -> np.ndarray:
    """eta0 (Pa s) at each oil temperature (degC) of an oil temperature axis: the
    lubricant's Walther / ASTM D341 law times its (constant) density,
    :func:`gearfmu.gear.thermal.oil_dynamic_viscosity_Pas`.  ``lubricant``: a
    :class:`gearfmu.ehl.lubricant.Lubricant` with both kinematic viscosities."""
    if lubricant is None:
        raise PrecomputeInputError("lubricant: an oil temperature axis needs the lubricant's viscosity-temperature "
                                   "law (thermal.lubricant, set by the scene reader from [lubricant])")
    nu40 = getattr(lubricant, "kinematic_viscosity_40C_m2_s", None)
    nu100 = getattr(lubricant, "kinematic_viscosity_100C_m2_s", None)
    if nu40 is None or nu100 is None:
        raise PrecomputeInputError("lubricant.eta0_Pas: an oil temperature axis needs a viscosity-temperature law "
                                   "(kinematic_viscosity_40C_cSt and kinematic_viscosity_100C_cSt)")
    try:
        eta = np.atleast_1d(oil_dynamic_viscosity_Pas(nu40, nu100, lubricant.density_kg_m3, temperatures_C))
    except (ThermalError, ValueError, OverflowError) as exc:
        raise PrecomputeInputError(f"temperature_axis_C: {exc}") from None
    if not np.all(np.isfinite(eta) & (eta > 0)):
        raise PrecomputeInputError(f"temperature_axis_C: the viscosity law gives no usable eta0 at "
                                   f"{list(np.asarray(temperatures_C, float))!r} degC")
    return eta


def _add_oil_temperature_axis(tables: MeshTables, pair, opts, thermal, *, contact_env, slots, points_per_mesh,
                              nominal_torque_Nm, progress=False) -> MeshTables:
    """Tables with an oil temperature axis (``thermal.axis_quantity`` "oil": FMU input
    ``oil_temperature``; "bulk_and_oil": gears and oil at one temperature, input
    ``gearbox_temperature``; docs/thermal.md "Oil temperature axis").

    Each slice t is the whole table build of :func:`precompute_tables` with the
    contact environment's eta0 replaced by eta0(t) of :func:`oil_axis_eta0_Pas`
    (the lubricated contact model's film / contact stiffness rebuilt at that
    viscosity, load sharing iterated again); alpha follows ``thermal.oil_alpha``:
    "roelands" (default) alpha(t) = alpha_ref (ln eta0(t) + 9.67)/(ln eta0_ref + 9.67)
    with Roelands' Z constant (Roelands 1966;
    :func:`gearfmu.ehl.lubricant.roelands_alpha_at_viscosity_Pa_inv`, the scene's
    alpha holding at the lubricant temperature), "constant" the scene's alpha at
    every t; the density is kept (CHOICE, docs/thermal.md).  The gears' state: for "oil" the ``[thermal]``
    pinion/gear temperatures or profiles (standard when absent) at every node;
    for "bulk_and_oil" both gears uniformly at t (He & Yang 2023 eq 27-28).  The
    slice at the lubricant's own temperature is the scene's table bit for bit;
    ``k_mean_N_per_m`` (the damping) is the scene's (``tables``, built at the
    lubricant temperature); the FMU input starts at the lubricant temperature
    clamped into the axis."""
    quantity = thermal.axis_quantity
    if opts.contact_model == "hertz" or contact_env is None:
        raise PrecomputeInputError(
            f"axis_quantity: {quantity!r} acts through eta0 of a lubricated contact model, but contact_model = "
            f"{opts.contact_model!r}" + (" uses no lubricant" if opts.contact_model == "hertz"
                                         else " got no contact_env"))

    if not get_contact_model(opts.contact_model).needs_lubricant:
        raise PrecomputeInputError(f"axis_quantity: {quantity!r} needs a contact model that uses the lubricant; "
                                   f"{opts.contact_model!r} does not")
    lub = getattr(thermal, "lubricant", None)
    axis = np.asarray(thermal.temperature_axis_C, dtype=float)
    eta = oil_axis_eta0_Pas(lub, axis)
    if getattr(thermal, "oil_alpha", "roelands") == "roelands":
        alpha = np.asarray(roelands_alpha_at_viscosity_Pa_inv(contact_env.alpha_Pa_inv, contact_env.eta0_Pas, eta),
                           dtype=float) * np.ones_like(eta)
        alpha[eta == contact_env.eta0_Pas] = contact_env.alpha_Pa_inv   # the lubricant's own temperature: exact
    else:
        alpha = np.full_like(eta, contact_env.alpha_Pa_inv)
    t0 = float(thermal.standard_temperature_C)
    if quantity == "oil":  # the gears keep the scene's state at every oil temperature
        gear_thermal = replace(thermal, temperature_axis_C=(), axis_quantity="bulk", lubricant=None)
    slices, contact = [], []
    for a, t in enumerate(axis):
        if quantity == "bulk_and_oil":
            gear_thermal = replace(thermal, temperature_axis_C=(), axis_quantity="bulk", lubricant=None,
                                   pinion_temperature_C=float(t), gear_temperature_C=float(t),
                                   pinion_profile_gamma=(), pinion_profile_C=(), gear_profile_gamma=(),
                                   gear_profile_C=())
        if float(eta[a]) == contact_env.eta0_Pas and _is_standard_state(thermal_state_from_scene(gear_thermal)):
            tab = tables  # the scene's own oil temperature, gears standard: the table just built
        else:
            tab = precompute_tables(pair, opts, points_per_mesh=points_per_mesh, torque_axis_Nm=tables.torque_Nm,
                                    nominal_torque_Nm=nominal_torque_Nm, slots=slots, progress=progress,
                                    contact_env=replace(contact_env, eta0_Pas=float(eta[a]),
                                                        alpha_Pa_inv=float(alpha[a])),
                                    thermal=gear_thermal)
        if not np.array_equal(tab.torque_Nm, tables.torque_Nm):
            raise PrecomputeInputError(f"temperature axis: the torque axis at {t:g} degC differs")
        c = tab.provenance.get("contact", {})
        contact.append({"temperature_C": float(t), "eta0_Pas": float(eta[a]), "alpha_Pa_inv": float(alpha[a]),
                        "solves": c.get("solves"),
                        "film_failures": c.get("film_failures", 0)})
        slices.append(replace(tab, provenance={}))
    out = stack_temperatures(slices, axis, temperature_reference_C=float(lub.temperature_C))
    prov = dict(tables.provenance)
    prov["thermal"] = {
        "temperature_axis_C": axis.tolist(), "axis_quantity": quantity, "input": TEMPERATURE_INPUTS[quantity],
        "standard_temperature_C": t0, "flank_law": thermal.flank_law,
        "oil": {"law": "Walther (ASTM D341) through kinematic_viscosity_40C/100C, eta0 = rho nu, rho constant",
                "eta0_Pas": eta.tolist(), "alpha_Pa_inv": alpha.tolist(),
                "alpha": ("Roelands 1966, Z constant: alpha_ref (ln eta0 + 9.67)/(ln eta0_ref + 9.67)"
                          if getattr(thermal, "oil_alpha", "roelands") == "roelands"
                          else "constant: the [lubricant] value (CHOICE)"),
                "reference_temperature_C": float(lub.temperature_C), "slices": contact},
        "gears": ("both at the axis temperature (seed 004 eq 5-28)" if quantity == "bulk_and_oil"
                  else _state_description(thermal_state_from_scene(thermal))),
        "model": "each slice rebuilt by precompute_tables with eta0(t); k_mean from the lubricant temperature",
    }
    return replace(out, k_mean_N_per_m=tables.k_mean_N_per_m, provenance=prov).validate()
