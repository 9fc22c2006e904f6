"""FMUs from tables: model description, one builder per runtime, runtime, C sources.

Imports :mod:`gearfmu.gearbox` (the gearbox FMU), :mod:`gearfmu.tables`, :mod:`gearfmu.dynamics`
(validation record) and :mod:`gearfmu.common`; :mod:`gearfmu.fmu.runtime` imports nothing from gearfmu.

==================  =========================================================
Module              Contents
==================  =========================================================
modeldesc           modelDescription.xml from modeldescription/variables.toml
pythonfmu_build     build_fmu: the pythonfmu runtime; compile flags, kernel
standalone_build    build_standalone_fmu: FMI 2.0 or 3.0 in C, no Python
crossbuild          standalone binaries for every desktop platform (zig cc)
summary             one line on an FMU file: runtime, FMI version, platforms
validation          the validation record every FMU carries
gearbox_interface   a gearbox FMU's variables from modeldescription/gearbox.toml
gearbox_build       build_gearbox_fmu: one FMU for a whole gearbox, in C
gearbox_validation  the gearbox FMU's validation record (native gearbox solver)
gearbox_compare     a gearbox FMU against the native gearbox solver
gearbox_doc         the gearbox FMU's documentation page
==================  =========================================================
"""
