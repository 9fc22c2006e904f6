"""FMUs from tables: model description, one builder per runtime, runtime, C sources.

Imports :mod:`gearfmu.tables`, :mod:`gearfmu.dynamics` (validation record) and
:mod:`gearfmu.common`; :mod:`gearfmu.fmu.runtime` imports nothing from gearfmu.

==================  =========================================================
Module              Contents
==================  =========================================================
modeldesc           modelDescription.xml from modeldescription/variables.toml
pythonfmu_build     build_fmu: the pythonfmu runtime; compile flags, kernel
standalone_build    build_standalone_fmu: FMI 2.0 or 3.0 in C, no Python
crossbuild          standalone binaries for every desktop platform (zig cc)
validation          the validation record every FMU carries
compare             FMU against the native solver (fmpy); open_fmu: a handed-over FMU, checked
integrity           an FMU's recorded checksums, GUID and binary for this platform
runtime/            gearfmu_slave.py (slave template), pyshim.c (C loader)
kernel/             gearkernel.c/.h: the C kernel of both runtimes
standalone/         fmi2_gear.c / fmi3_gear.c: the FMI 2.0 / 3.0 layers in C over fmi_common.c + gear_model.c
==================  =========================================================
"""
