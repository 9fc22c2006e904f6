"""Planetary stages on tables: sun, carrier, ring and N planets, every mesh the multi-pair model.

The solver layer of planetary stages, beside :mod:`gearfmu.gearbox`: it reads a stage's tables
(:class:`gearfmu.tables.planetary.PlanetaryStage`, built by :mod:`gearfmu.assembly.planetary` from
the geometry of a planetary set or by :mod:`gearfmu.assembly.planetary_lumped` from published lumped
parameters) and imports :mod:`gearfmu.gearbox` (parallel-axis meshes, shafts, the pair kernels'
pointer helpers), :mod:`gearfmu.dynamics`, :mod:`gearfmu.tables` and :mod:`gearfmu.common`; never the
scene, the assembly or the physics.  docs/planetary.md describes the model, the integrators, the
modes and what is verified.

Exports (loaded with their module on first use): ``PlanetaryModel``, ``build_drivetrain``,
``PlanetaryModelError``; the native solver ``simulate``, ``PlanetaryResult``,
``PlanetaryInputError``; ``PlanetaryModes``, ``PlanetaryMode``, ``campbell`` (the modes
themselves: ``gearfmu.planetary.modes.modes``); the reference ``simulate_reference``.

===========  =========================================================
Module       Contents
===========  =========================================================
model        PlanetaryModel, build_drivetrain: the DOFs (rotations;
             Lin & Parker translations in the carrier frame), springs,
             meshes, Willis kinematics, linearisation, static state
drives       the drives of driven members: their rigid motion, a
             translational frame that turns with a drive
modes        modes classified as rotational, translational, planet or
             mixed; multiplicities; Campbell data
kernels      numba kernels: right-hand side, 'rk4', the event-aware
             'rk4_kink' / 'rk4_node' substep, the loop over steps
native       public API of the numba solver (simulate, PlanetaryResult)
reference    event-located scipy reference of the same equations
===========  =========================================================
"""
from ..common.exports import lazy_exports

_EXPORTS = {
    **dict.fromkeys(("PlanetaryModel", "build_drivetrain", "PlanetaryModelError"), "model"),
    **dict.fromkeys(("simulate", "PlanetaryResult", "PlanetaryInputError"), "native"),
    **dict.fromkeys(("PlanetaryModes", "PlanetaryMode", "campbell"), "modes"),
    "simulate_reference": "reference",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
