"""Cost estimate of a scene's tables and FMU before anything is computed, and the size guard.

:func:`estimate_build` reads only the scene and the pair geometry (no physics), so a scene
that would take hours or gigabytes is refused before the first table row
(:func:`check_build_cost`; override with ``allow_large=True`` in the Python API or
``--allow-large`` on the command line).  docs/tables.md "Cost estimate" describes the model.

Model (cheap on purpose; the constants are model constants, fixed here, not measurements
that follow the machine):

* table cells: ``n_phi = table mesh periods x points_per_mesh`` pinion angles (the hunting-tooth
  cycle when teeth differ, gearfmu.gear.meshing_errors.pair_table_mesh_count), ``P`` slots, ``NT``
  torque rows (the scene's torque axis, or the axis precompute adds for a load-dependent
  contact model) and ``NK`` temperatures;
* table bytes: 8 bytes (float64) x (k and e: 2 NT NK P n_phi; backlash: P n_phi; comprehensive
  error and static TE: 2 NT NK n_phi) plus :data:`TABLE_HEADER_BYTES` for the JSON header;
* FMU bytes: the table bytes (float64 tables hardly deflate) plus :data:`FMU_OVERHEAD_BYTES`
  (kernel, runtime, model description of the pythonfmu runtime);
* build time: :data:`SECONDS_PER_SLICE_CELL` x (1 + NT NK) x n_phi x P x slices for the
  sliced stiffness (one set-up pass and one pass per row), plus for a lubricated contact
  model :data:`FILM_SECONDS_PER_CELL` x NT NK x n_phi x P (the film solves of the load
  iteration scale with the angle-slot cells, not with the slices).

The estimate is meant to be right within a factor of about 3 (tables) and 10 (time); the limits
below leave that much room.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

from .precompute import LOAD_DEPENDENT_TORQUE_FACTORS
from ..gear.geometry import pair_geometry
from ..gear.meshing_errors import pair_table_mesh_count
from ..gear.stiffness import required_slots
from ..common.vocabulary import LUBRICATED_CONTACT_MODELS

__all__ = ["BuildEstimate", "BuildTooLargeError", "estimate_build", "check_build_cost",
           "FMU_LIMIT_BYTES", "BUILD_TIME_LIMIT_S"]

#: refuse (without ``allow_large``) an FMU or a table file estimated above this size, bytes
FMU_LIMIT_BYTES = 200e6
#: refuse (without ``allow_large``) a table build estimated above this time, s
BUILD_TIME_LIMIT_S = 600.0
#: model constant: bytes of a table file's JSON header (scalars, provenance, scene text)
TABLE_HEADER_BYTES = 8_000
#: model constant: bytes of an FMU besides its tables (pythonfmu runtime, C kernel, XML)
FMU_OVERHEAD_BYTES = 700_000
#: model constant: seconds per (angle x slot x slice) and pass of the sliced Hertz stiffness
SECONDS_PER_SLICE_CELL = 3e-6
#: model constant: seconds per (angle x slot) and torque row of a lubricated contact model's
#: film solves (the smooth_ehl value; rough_ehl and fractal_mixed use it too, so their
#: estimate is a lower bound)
FILM_SECONDS_PER_CELL = 0.15


class BuildTooLargeError(ValueError):
    """The estimated tables / FMU / build time exceed the limits (and no override was given)."""


@dataclass(frozen=True)
class BuildEstimate:
    """Estimated cost of a scene's tables and FMU (see the module docstring for the model)."""

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
                f"table build {_fmt_time(self.build_s)} ({self.torque_rows * self.temperatures} rows x "
                f"{self.slots} slots x {self.n_phi} angles x {self.slices} slices)")


def _fmt_bytes(b: float) -> str:
    return f"{b / 1e9:.3g} GB" if b >= 1e9 else f"{b / 1e6:.3g} MB"


def _fmt_time(s: float) -> str:
    if s < 120:
        return f"{s:.2g} s"
    if s < 7200:
        return f"{s / 60:.3g} min"
    return f"{s / 3600:.3g} h"


def estimate_build(scene) -> BuildEstimate:
    """Estimate table size (bytes), FMU size (bytes) and table build time (s) of ``scene``
    without computing anything but the pair geometry."""
    pair, mesh = scene.pair, scene.mesh
    slots = scene.tables.slots or required_slots(pair_geometry(pair))
    n_phi = pair_table_mesh_count(pair, slots) * int(scene.tables.points_per_mesh)
    ns = int(mesh.slices)
    torques = list(scene.operating.torque_axis_Nm())
    lubricated = mesh.contact_model in LUBRICATED_CONTACT_MODELS
    if len(torques) < 2 and lubricated:
        torques = list(LOAD_DEPENDENT_TORQUE_FACTORS)
    nt = len(torques)
    nk = max(1, len(getattr(getattr(scene, "thermal", None), "temperature_axis_C", ()) or ()))
    cells = nt * nk * slots * n_phi
    table_bytes = 8.0 * (2 * cells + slots * n_phi + 2 * nt * nk * n_phi) + TABLE_HEADER_BYTES
    t = SECONDS_PER_SLICE_CELL * (1 + nt * nk) * n_phi * slots * ns
    if lubricated:
        t += FILM_SECONDS_PER_CELL * cells
    return BuildEstimate(n_phi=n_phi, slots=slots, torque_rows=nt, temperatures=nk, slices=ns,
                         table_cells=cells, table_bytes=table_bytes,
                         fmu_bytes=table_bytes + FMU_OVERHEAD_BYTES, build_s=t)


def check_build_cost(scene, *, allow_large: bool = False) -> BuildEstimate:
    """:func:`estimate_build`, raising :class:`BuildTooLargeError` (a one-line message with
    the estimate and the scene keys to change) when the FMU would exceed
    :data:`FMU_LIMIT_BYTES` or the build :data:`BUILD_TIME_LIMIT_S`, unless ``allow_large``."""
    est = estimate_build(scene)
    if allow_large:
        return est
    over = []
    if est.fmu_bytes > FMU_LIMIT_BYTES:
        over.append(f"FMU {_fmt_bytes(est.fmu_bytes)} > {_fmt_bytes(FMU_LIMIT_BYTES)}")
    if est.build_s > BUILD_TIME_LIMIT_S:
        over.append(f"table build {_fmt_time(est.build_s)} > {_fmt_time(BUILD_TIME_LIMIT_S)}")
    if not over:
        return est
    keys = [f"tables.points_per_mesh ({scene.tables.points_per_mesh})"]
    if est.torque_rows > 1:
        keys.append(f"tables.torque_points ({scene.tables.torque_points})")
    if est.temperatures > 1:
        keys.append(f"thermal.temperature_axis_C ({est.temperatures} values)")
    if est.build_s > BUILD_TIME_LIMIT_S:
        keys.append(f"mesh.slices ({est.slices})")
    raise BuildTooLargeError(
        f"{', '.join(keys)}: the scene is too large to build ({'; '.join(over)}; {est.summary()}); "
        "lower these keys, or pass --allow-large (allow_large=True in the Python API) to build anyway")
