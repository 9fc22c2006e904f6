"""The dynamics of a gearbox (several gear-pair stages joined by shafts) on tables.

Imports :mod:`gearfmu.dynamics` (the pair model's lookup and force law, per mesh),
:mod:`gearfmu.tables` and :mod:`gearfmu.common`; never the scene (the orchestration,
:mod:`gearfmu.stages`, builds a model from a drivetrain scene).  docs/gearbox.md
describes the model, the integrators, the modes and what is verified.

Exports (loaded with their module on first use): ``GearboxModel``, ``Mesh``, ``Shaft``,
``build_gearbox``, ``GearboxModelError``; the native gearbox solver ``simulate``,
``GearboxResult``, ``GearboxInputError``; ``ModesResult``, ``campbell`` (the modes themselves:
``gearfmu.gearbox.modes.modes``); the reference ``simulate_reference``.

===========  =========================================================
Module       Contents
===========  =========================================================
model        GearboxModel, build_gearbox: bodies, shafts, meshes, the
             kinematic ratios, the state layout, the mean-stiffness
             linearisation, the quasi-static initial state
modes        natural frequencies, mode shapes, modal strain energy per
             mesh and shaft, Campbell / interference diagram data
native       public API of the numba gearbox solver (simulate,
             GearboxResult), argument checks, step choice
kernels      the numba kernels: right-hand side, 'rk4', the event-aware
             'rk4_kink' / 'rk4_node' substep, the loop over steps
reference    event-located scipy reference of the same equations
             (tests and benchmarks)
cases        the hard cases of the tests and the benchmark (inputs only)
_pair        the pair model's numba kernels used per mesh (the one place
             that names them)
===========  =========================================================
"""
from ..common.exports import lazy_exports

_EXPORTS = {
    **dict.fromkeys(("GearboxModel", "Mesh", "Shaft", "build_gearbox", "GearboxModelError"), "model"),
    **dict.fromkeys(("simulate", "GearboxResult", "GearboxInputError"), "native"),
    "ModesResult": "modes", "campbell": "modes",
    "simulate_reference": "reference",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
