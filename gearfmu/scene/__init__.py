"""The scene: the single user input (TOML), read and checked.

It builds the gear-pair specs and runs the geometry checks, and reads the physics options
off a scene for the layers below (:mod:`gearfmu.scene.physics`), so it sits above
:mod:`gearfmu.assembly`, :mod:`gearfmu.contact`, :mod:`gearfmu.gear` and :mod:`gearfmu.ehl`,
none of which imports it.  The public names (``load_scene``,
``Scene``, ``SceneError``, the option dataclasses, ``SCHEMA``, ``dumps_toml`` ...) are
importable from :mod:`gearfmu.scene.reader`.

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
data/         default_scene.toml
============  ===================================================================
"""
