"""What a scene reads into: the validated, SI option dataclasses and :class:`Scene`.

:func:`gearfmu.scene.reader.load_scene` builds these from the TOML tables (the keys,
units and ranges are in :mod:`gearfmu.scene.schema`, their documentation in
``docs/scene.md``).  The sections the physics takes are the physics' own specs, defined
where they are used and importable from here: the gear pair
:class:`gearfmu.gear.gearpair.GearPairSpec`, the ``[roughness]`` table
:class:`gearfmu.contact.base.RoughnessSpec`, the ``[lubricant]`` table
:class:`gearfmu.ehl.lubricant.Lubricant` and the ``[thermal]`` table
:class:`gearfmu.gear.thermal.ThermalOptions`.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass
from typing import Any, List, Optional, Sequence, Tuple

from ..common.settings import OUTPUT_SAMPLES_PER_MESH, default_output_interval_s  # noqa: F401 (re-exported)
from ..common.units import RPM_TO_RAD_S  # noqa: F401 (re-exported)
from ..common.vocabulary import DEFAULT_DAMPING_MODEL, DEFAULT_INTEGRATOR, DEFAULT_RUNTIME
from ..contact.base import RoughnessSpec
from ..ehl.lubricant import Lubricant
from ..gear.gearpair import GearPairSpec, MeshModelOptions
from ..gear.thermal import ThermalOptions

__all__ = ["SceneError", "Scene", "OperatingPoint", "TableOptions", "SolverOptions", "FmuOptions", "Lubricant",
           "ThermalOptions", "default_output_interval_s", "OUTPUT_SAMPLES_PER_MESH", "RPM_TO_RAD_S"]


# ============================================================== errors
class SceneError(ValueError):
    """A scene is invalid.  ``problems`` lists ``(key_path, reason)`` pairs;
    the message names every key path and reason, one per line."""

    def __init__(self, problems: Sequence[Tuple[str, str]], source: str = ""):
        self.problems: List[Tuple[str, str]] = list(problems)
        self.source = source
        lines = [f"{path}: {reason}" for path, reason in self.problems]
        where = f" in scene {source!r}" if source else ""
        if len(lines) == 1:
            msg = lines[0] + (f" ({where.strip()})" if where else "")
        else:
            msg = f"{len(lines)} problems{where}:\n" + "\n".join("  - " + s for s in lines)
        super().__init__(msg)


# ============================================================== result dataclasses
@dataclass(frozen=True)
class OperatingPoint:
    """Operating envelope (SI).

    ``torque_Nm`` is the nominal pinion torque (N*m, positive drives),
    ``speed_rad_s`` the nominal pinion speed (rad/s).  The optional ranges
    (N*m and rad/s, ``(low, high)``) span the torque axis of the tables
    (see :meth:`torque_axis_Nm`) and the envelope the FMU accepts.
    """

    torque_Nm: float
    speed_rad_s: float
    torque_range_Nm: Optional[Tuple[float, float]] = None
    speed_range_rad_s: Optional[Tuple[float, float]] = None
    torque_points: int = 1

    @property
    def speed_rpm(self) -> float:
        """Nominal pinion speed in rev/min."""
        return self.speed_rad_s / RPM_TO_RAD_S

    def torque_axis_Nm(self, points: Optional[int] = None) -> Tuple[float, ...]:
        """Torque axis of the tables (N*m): the nominal torque alone when
        ``points == 1`` or no range is given, else ``points`` equally spaced
        values over ``torque_range_Nm`` (both ends included).  ``points``
        None = ``torque_points`` (the scene's ``tables.torque_points``)."""
        if points is None:
            points = self.torque_points
        if points <= 1 or self.torque_range_Nm is None:
            return (float(self.torque_Nm),)
        lo, hi = self.torque_range_Nm
        return tuple(lo + (hi - lo) * i / (points - 1) for i in range(points))


@dataclass(frozen=True)
class TableOptions:
    """Resolution of the tooth-pair tables.

    ``points_per_mesh``: pinion-angle samples per mesh period 2*pi/z1;
    ``torque_points``: samples of the torque axis (1 = no torque axis);
    ``slots``: tooth-pair slot count P, ``None`` = automatic (from the contact ratio).
    """

    points_per_mesh: int = 64
    torque_points: int = 1
    slots: Optional[int] = None


@dataclass(frozen=True)
class SolverOptions:
    """Dynamic solver settings (docs/model.md).

    ``integrator``: :data:`~gearfmu.common.vocabulary.INTEGRATORS`, default 'rk4_node'
    (:data:`~gearfmu.common.vocabulary.DEFAULT_INTEGRATOR`, docs/native.md "rk4_node"), 'rk4_kink' or 'rk4'; ``max_step_s``: largest internal step in s
    (``None`` = automatic, chosen by the builder from the mesh frequency and
    the contact natural frequency); ``damping_model``: 'elastobacklash' or
    'contact_zone' (docs/model.md, "Per-pair force").
    """

    integrator: str = DEFAULT_INTEGRATOR
    max_step_s: Optional[float] = None
    damping_model: str = DEFAULT_DAMPING_MODEL


@dataclass(frozen=True)
class FmuOptions:
    """FMU options.

    ``model_name``: the FMU's model name / identifier (a C identifier);
    ``damping_ratio``: mesh damping ratio zeta (dimensionless, default 0.05,
    see docs/scene.md for why); ``runtime``: 'standalone' (default, all-C) or 'pythonfmu';
    ``stop_time_s`` and ``output_interval_s``: the DefaultExperiment (s);
    ``output_interval_auto``: True when the scene left ``output_interval_s`` unset (or
    "auto") and it was resolved by :func:`default_output_interval_s`.
    """

    model_name: str
    damping_ratio: float = 0.05
    runtime: str = DEFAULT_RUNTIME
    stop_time_s: float = 0.05
    output_interval_s: float = 1e-4
    output_interval_auto: bool = False


@dataclass(frozen=True)
class Scene:
    """A validated scene, in SI.

    ``text`` is the TOML source (provenance; hash it with :attr:`sha256`),
    ``source_path`` the file it came from (``None`` for text).  Built only by
    :func:`gearfmu.scene.reader.load_scene`.
    """

    #: ``[scene] name`` (also the default FMU model name) and ``description``
    name: str
    description: str
    #: the TOML source as read (provenance)
    text: str
    #: ``[gears]``, ``[gears.pinion]``, ``[gears.gear]``, ``[material]``, ``[deviations]``
    pair: GearPairSpec
    #: ``[mesh]``: contact model, slices, foundation
    mesh: MeshModelOptions
    #: ``[operating]``: nominal torque and speed, their ranges
    operating: OperatingPoint
    #: ``[tables]``: resolution of the tooth-pair tables
    tables: TableOptions
    #: ``[solver]``: integrator, largest step, damping rule
    solver: SolverOptions
    #: ``[fmu]``: model name, damping ratio, runtime, DefaultExperiment
    fmu: FmuOptions
    #: ``[lubricant]``, None when absent
    lubricant: Optional[Lubricant] = None
    #: the scene file, None for a scene given as text or a mapping
    source_path: Optional[str] = None
    #: ``[thermal]``, None when absent
    thermal: Optional[ThermalOptions] = None
    #: ``[envelope]``: gearfmu.scene.envelope.Envelope (docs/plan.md), None when absent
    envelope: Optional[Any] = None
    #: ``[accuracy]``: gearfmu.scene.envelope.AccuracyTarget (docs/plan.md), None when absent
    accuracy: Optional[Any] = None
    #: ``[roughness]`` (SI), None when absent; the contact models take it as it is
    roughness: Optional[RoughnessSpec] = None

    @property
    def sha256(self) -> str:
        """SHA-256 of the TOML source (hex)."""
        return hashlib.sha256(self.text.encode("utf-8")).hexdigest()

    @property
    def torque_axis_Nm(self) -> Tuple[float, ...]:
        """The tables' torque axis (N*m), see :meth:`OperatingPoint.torque_axis_Nm`."""
        return self.operating.torque_axis_Nm(self.tables.torque_points)

