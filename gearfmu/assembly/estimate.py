"""Cost model of a table build and its FMU, before anything is computed, and the size limits.

:func:`estimate_cost` takes the arguments of the table builder
(:func:`gearfmu.assembly.precompute.precompute_tables`: gear pair, mesh options, points per mesh,
torque axis, nominal torque, slots, contact environment, thermal options) and the FMU's runtime and
experiment, and computes nothing but the pair geometry, so that a build that would take hours or
gigabytes is refused before the first table row (:func:`limits_exceeded`; the scene-level guard
with the scene keys to change is :func:`gearfmu.scene.physics.check_build_cost`, overridden with
``allow_large=True`` in the Python API or ``--allow-large`` on the command line).
docs/tables.md "Cost estimate" describes the model.

The model counts the work the table builder (:mod:`gearfmu.assembly.precompute`) will do
(:func:`work_counts`) and prices each kind with a constant measured once on a reference machine
(benchmarks/bench_estimate.py prints estimate against measurement for every example scene;
the constants are model constants, fixed here, not measurements that follow the machine):

* angles ``n_phi`` = table mesh periods x ``points_per_mesh`` (the hunting-tooth cycle when
  teeth differ, :func:`gearfmu.gear.meshing_errors.pair_table_mesh_count`), ``P`` slots, ``NS``
  face-width slices, ``rows`` torque rows (the torque axis, plus the nominal torque when it is
  not on it; a load-dependent contact model gets :data:`LOAD_DEPENDENT_TORQUE_FACTORS` when the
  axis has fewer than two torques), ``NK`` temperatures;
* stiffness cells P x points_per_mesh (x NS for a helical pair, whose slices differ) per sliced
  stiffness evaluation; meshing-error cells P x n_phi (x NS helical); loaded-mesh cells rows x P x
  NS x n_phi (the loaded static mesh of every row); temperature-stiffness cells torques x
  temperatures x P x points_per_mesh (x NS helical);
* contact requests of a load-dependent contact model: rows x eps_alpha x n_phi positions in
  contact per slice column (one column, or NS when the slices carry different loads: a helical or
  crowned pair), times the passes of the load iteration; the rough EHL model instead solves a film
  grid of ``film_position_nodes`` positions x load columns x (1 + NS) films, shared by all rows;
  worker processes started for the film solves;
* an oil-temperature axis repeats the whole build at each of its NK temperatures;
* bytes: 8 bytes (float64) per table value plus the JSON header; the FMU adds its runtime's
  binaries and sources and the reference result of its validation record (CSV, deflated).

The time is CPU seconds (the build's own process and its worker processes); on a machine with
several cores the film solves share out over them, so the wall time can be lower.
benchmarks/bench_estimate.py checks the model against measurement within a factor 2 both ways.
"""
from __future__ import annotations

import os
from dataclasses import asdict, dataclass

import numpy as np

from .precompute import DEFAULT_TORQUE_FACTORS, LOAD_DEPENDENT_TORQUE_FACTORS
from ..contact.base import DEFAULT_FILM_POSITION_NODES
from ..gear.geometry import pair_geometry
from ..gear.meshing_errors import pair_lead_crowning_m, pair_table_mesh_count
from ..gear.stiffness import required_slots
from ..common.vocabulary import LUBRICATED_CONTACT_MODELS

__all__ = ["BuildEstimate", "BuildTooLargeError", "estimate_cost", "limits_exceeded", "work_counts",
           "FMU_LIMIT_BYTES", "BUILD_TIME_LIMIT_S"]

#: refuse (without ``allow_large``) an FMU or a table file estimated above this size, bytes
FMU_LIMIT_BYTES = 200e6
#: refuse (without ``allow_large``) a table build estimated above this time, s
BUILD_TIME_LIMIT_S = 600.0
#: model constant: bytes of a table file's JSON header (scalars, provenance, scene text)
TABLE_HEADER_BYTES = 8_000
#: model constant: bytes of an FMU besides its tables and reference result, per runtime (the
#: standalone runtime with the binaries of every platform and its C sources; the pythonfmu
#: runtime with the build machine's binaries, the kernel's sources and its Python layer)
FMU_OVERHEAD_BYTES = {"standalone": 490_000, "pythonfmu": 460_000}
#: model constant: deflated bytes per value of the validation record's reference result (CSV)
REFERENCE_BYTES_PER_VALUE = 5.5
#: model constant: deflated / raw bytes of the tables in a standalone FMU (pythonfmu stores them)
TABLE_DEFLATE_RATIO = 0.2
#: model constants, CPU seconds: fixed cost of a table build (first use of the modules in a
#: process); per sliced-stiffness cell; per meshing-error cell; per loaded-mesh cell; per
#: temperature-stiffness cell
SECONDS_FIXED = 0.01
SECONDS_PER_STIFFNESS_CELL = 1.4e-5
SECONDS_PER_ERROR_CELL = 2.4e-7
SECONDS_PER_MESH_CELL = 6.6e-8
SECONDS_PER_THERMAL_CELL = 6.0e-6
#: model constants: passes of the load iteration that solve most requests again; CPU seconds per
#: contact solve of each load-dependent model; per film of the rough film grid; per worker process
#: started for film solves
LOAD_PASSES = 1.5
SECONDS_PER_SOLVE = {"fractal_mixed": 2.3e-3, "smooth_ehl": 2.7e-3, "rough_ehl": 2.7e-3}
SECONDS_PER_GRID_FILM = 0.016
SECONDS_PER_WORKER = 1.3
#: model constant: load columns of the rough film grid that the rows ask for
GRID_LOAD_COLUMNS = 3.6


class BuildTooLargeError(ValueError):
    """The estimated tables / FMU / build time exceed the limits (and no override was given)."""


@dataclass(frozen=True)
class BuildEstimate:
    """Estimated cost of a scene's tables and FMU (see the module docstring for the model).
    ``build_s``: CPU seconds of the table build."""

    n_phi: int
    slots: int
    torque_rows: int
    temperatures: int
    slices: int
    table_cells: int
    table_bytes: float
    fmu_bytes: float
    build_s: float

    def to_dict(self) -> dict:
        return asdict(self)

    def summary(self) -> str:
        """One line: sizes in MB, time in s, and the cells behind them."""
        return (f"estimate: tables {_fmt_bytes(self.table_bytes)}, FMU {_fmt_bytes(self.fmu_bytes)}, "
                f"table build {_fmt_time(self.build_s)} CPU ({self.torque_rows * self.temperatures} rows x "
                f"{self.slots} slots x {self.n_phi} angles x {self.slices} slices)")


def _fmt_bytes(b: float) -> str:
    return f"{b / 1e9:.3g} GB" if b >= 1e9 else f"{b / 1e6:.3g} MB"


def _fmt_time(s: float) -> str:
    if s < 120:
        return f"{s:.2g} s"
    if s < 7200:
        return f"{s / 60:.3g} min"
    return f"{s / 3600:.3g} h"


def _workers() -> int:
    return max(1, os.cpu_count() or 1)


def work_counts(pair, opts, *, points_per_mesh: int, torque_axis_Nm, nominal_torque_Nm: float,
                slots=None, contact_env=None, thermal=None) -> dict:
    """The work of a table build, counted from the table builder's arguments (those of
    :func:`gearfmu.assembly.precompute.precompute_tables`) and the pair geometry (the module
    docstring): table shape, cells of each kind, contact requests, grid films, worker processes.
    ``torque_axis_Nm`` None: the builder's default axis (the nominal torque, with lead crowning
    :data:`gearfmu.assembly.precompute.DEFAULT_TORQUE_FACTORS` x nominal)."""
    geom = pair_geometry(pair)
    helical = geom.helix_angle_rad != 0.0
    slots = int(slots or required_slots(geom))
    ppm = int(points_per_mesh)
    n_phi = pair_table_mesh_count(pair, slots) * ppm
    ns = int(opts.slices)
    model = opts.contact_model
    load_dependent = model in LUBRICATED_CONTACT_MODELS
    nominal = float(nominal_torque_Nm)
    if torque_axis_Nm is None:
        E = pair_lead_crowning_m(pair, ns)
        torque_axis_Nm = [nominal * f for f in DEFAULT_TORQUE_FACTORS] if np.any(E != E[0]) else [nominal]
    torques = [float(t) for t in torque_axis_Nm]
    if len(torques) < 2 and load_dependent:
        torques = [nominal * f for f in LOAD_DEPENDENT_TORQUE_FACTORS]
    nt = len(torques)
    rows = nt + (0 if any(t == nominal for t in torques) else 1)
    th = thermal
    axis = tuple(getattr(th, "temperature_axis_C", ()) or ())
    nk = max(1, len(axis))
    oil_axis = nk > 1 and getattr(th, "axis_quantity", "bulk") in ("oil", "bulk_and_oil")
    states = nk if (nk > 1 and not oil_axis) else (1 if _non_standard(th) else 0)
    calls = nk if oil_axis else 1          # whole table builds (an oil axis rebuilds at each temperature)
    crowned = ns > 1 and bool(np.any(pair_lead_crowning_m(pair, ns) != 0.0))
    columns = ns if (helical or crowned) else 1
    slice_factor = ns if helical else 1
    counts = {
        "n_phi": n_phi, "slots": slots, "slices": ns, "rows": rows, "torques": nt, "temperatures": nk,
        "builds": calls, "helical": helical, "crowned": crowned, "contact_model": model,
        "stiffness_cells": calls * (2 if load_dependent else 1) * slots * ppm * slice_factor,
        "error_cells": calls * slots * n_phi * slice_factor,
        "mesh_cells": calls * rows * slots * ns * n_phi + (nt * states * slots * ns * n_phi if states else 0),
        "thermal_cells": nt * states * slots * ppm * slice_factor,
        "contact_requests": 0.0, "grid_films": 0.0, "workers": 0,
    }
    if load_dependent:
        positions = float(geom.contact_ratio) * n_phi * columns
        if model == "rough_ehl":
            rough = None if contact_env is None else contact_env.roughness
            k = int(getattr(rough, "position_nodes", DEFAULT_FILM_POSITION_NODES))
            if k > 0:
                counts["grid_films"] = calls * k * GRID_LOAD_COLUMNS * (1 + ns)
            else:
                counts["contact_requests"] = calls * rows * LOAD_PASSES * positions * (1 + ns)
        else:
            counts["contact_requests"] = calls * rows * LOAD_PASSES * positions
        if model in ("smooth_ehl", "rough_ehl"):
            counts["workers"] = calls * _workers()
    return counts


def _non_standard(th) -> bool:
    """Thermal options with a state other than the standard one (without an axis)."""
    if th is None:
        return False
    t0 = th.standard_temperature_C
    temps = [t for t in (th.pinion_temperature_C, th.gear_temperature_C) if t is not None]
    return any(t != t0 for t in temps) or bool(th.pinion_profile_C) or bool(th.gear_profile_C)


def estimate_cost(pair, opts, *, points_per_mesh: int, torque_axis_Nm, nominal_torque_Nm: float, slots=None,
                  contact_env=None, thermal=None, runtime: str, stop_time_s: float,
                  output_interval_s: float) -> BuildEstimate:
    """Estimate table size (bytes), FMU size (bytes) and table build time (CPU s) of the tables of
    ``precompute_tables(pair, opts, ...)`` (the arguments of :func:`work_counts`) in an FMU of
    ``runtime`` ("standalone" or "pythonfmu") whose validation record covers ``stop_time_s`` (s) at
    ``output_interval_s`` (s), without computing anything but the pair geometry."""
    c = work_counts(pair, opts, points_per_mesh=points_per_mesh, torque_axis_Nm=torque_axis_Nm,
                    nominal_torque_Nm=nominal_torque_Nm, slots=slots, contact_env=contact_env, thermal=thermal)
    slots, n_phi, nt, nk = c["slots"], c["n_phi"], c["torques"], c["temperatures"]
    cells = nt * nk * slots * n_phi
    table_bytes = 8.0 * (2 * cells + slots * n_phi + 2 * nt * nk * n_phi) + TABLE_HEADER_BYTES
    t = (SECONDS_FIXED + SECONDS_PER_STIFFNESS_CELL * c["stiffness_cells"]
         + SECONDS_PER_ERROR_CELL * c["error_cells"] + SECONDS_PER_MESH_CELL * c["mesh_cells"]
         + SECONDS_PER_THERMAL_CELL * c["thermal_cells"]
         + SECONDS_PER_SOLVE.get(c["contact_model"], 0.0) * c["contact_requests"]
         + SECONDS_PER_GRID_FILM * c["grid_films"] + SECONDS_PER_WORKER * c["workers"])
    runtime = runtime if runtime in FMU_OVERHEAD_BYTES else "standalone"
    samples = int(round(float(stop_time_s) / float(output_interval_s))) + 1
    reference = REFERENCE_BYTES_PER_VALUE * samples * (9 + 2 * slots)
    in_fmu = table_bytes * (TABLE_DEFLATE_RATIO if runtime == "standalone" else 1.0)
    return BuildEstimate(n_phi=n_phi, slots=slots, torque_rows=nt, temperatures=nk, slices=c["slices"],
                         table_cells=cells, table_bytes=table_bytes,
                         fmu_bytes=in_fmu + reference + FMU_OVERHEAD_BYTES[runtime], build_s=t)


def limits_exceeded(est: BuildEstimate) -> list:
    """What of ``est`` exceeds :data:`FMU_LIMIT_BYTES` or :data:`BUILD_TIME_LIMIT_S`, one phrase
    each (empty: within the limits)."""
    over = []
    if est.fmu_bytes > FMU_LIMIT_BYTES:
        over.append(f"FMU {_fmt_bytes(est.fmu_bytes)} > {_fmt_bytes(FMU_LIMIT_BYTES)}")
    if est.build_s > BUILD_TIME_LIMIT_S:
        over.append(f"table build {_fmt_time(est.build_s)} > {_fmt_time(BUILD_TIME_LIMIT_S)}")
    return over
