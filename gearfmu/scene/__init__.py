"""The scene: the single user input (TOML), read and checked.

It builds the gear-pair specs and runs the geometry checks, so it sits above
:mod:`gearfmu.gear` and :mod:`gearfmu.contact`.

==========  =================================================================
Module      Contents
==========  =================================================================
reader      load_scene, Scene, the schema of every key, dumps_toml
envelope    [envelope] and [accuracy]: operating envelope and accuracy target
data/       default_scene.toml
==========  =================================================================
"""
