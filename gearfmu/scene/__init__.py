"""The scene: the single user input (TOML), read and checked.

It builds the gear-pair specs and runs the geometry checks, and reads the physics options
off a scene for the layers below (:mod:`gearfmu.scene.physics`), so it sits above
:mod:`gearfmu.assembly`, :mod:`gearfmu.contact`, :mod:`gearfmu.gear` and :mod:`gearfmu.ehl`,
none of which imports it.

Exports (loaded with their module on first use): ``load_scene``, ``default_scene_path``;
``Scene``, ``SceneError`` and the option dataclasses ``OperatingPoint``, ``TableOptions``,
``SolverOptions``, ``FmuOptions``; the drivetrain scene ``DrivetrainScene``, ``load_drivetrain``,
``is_drivetrain_file``; ``Envelope``, ``AccuracyTarget``, ``VerifiedEnvelope``, ``EnvelopeError``;
``environment_from_scene``, ``estimate_build``; ``SCHEMA``; ``dumps_toml``.

============  ===================================================================
Module        Contents
============  ===================================================================
reader        load_scene, default_scene_path: parse, check and build a Scene
options       Scene, SceneError and the SI option dataclasses (OperatingPoint,
              TableOptions, SolverOptions, FmuOptions; Lubricant and ThermalOptions
              are the physics' own, gearfmu.ehl.lubricant and gearfmu.gear.thermal)
physics       what the physics takes from a scene: the contact environment, the
              table builder's arguments, the cost estimate and its guard
schema        SCHEMA: every table and key (type, unit, default, range, SI scale)
validate      Reader (key-by-key checks collecting every problem), the checks
              across sections and the geometry check
sections      per-section readers: gears, deviations, lubricant, thermal, roughness
              (the roughness is gearfmu.contact.base.RoughnessSpec)
envelope      [envelope] and [accuracy]: operating envelope and accuracy target
toml_writer   dumps_toml: a mapping written as TOML (scenes built in code)
drivetrain    DrivetrainScene, load_drivetrain: gear-pair stages joined by shafts,
              motor and load
planetary     [[planetary]] stages of a drivetrain scene: a geometric planetary set or
              published lumped parameters, and the checks of an impossible set
data/         default_scene.toml
============  ===================================================================
"""
from ..common.exports import lazy_exports

_EXPORTS = {
    "load_scene": "reader", "default_scene_path": "reader",
    **dict.fromkeys(("Scene", "SceneError", "OperatingPoint", "TableOptions", "SolverOptions", "FmuOptions"),
                    "options"),
    **dict.fromkeys(("DrivetrainScene", "load_drivetrain", "is_drivetrain_file"), "drivetrain"),
    **dict.fromkeys(("Envelope", "AccuracyTarget", "VerifiedEnvelope", "EnvelopeError"), "envelope"),
    "environment_from_scene": "physics", "estimate_build": "physics",
    "SCHEMA": "schema",
    "dumps_toml": "toml_writer",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
