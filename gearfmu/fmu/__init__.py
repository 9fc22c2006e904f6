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
summary             one line on an FMU file: runtime, FMI version, platforms
validation          the validation record every FMU carries
compare             FMU against the native solver (fmpy)
runtime/            gearfmu_slave.py (slave template), kernel_api.py (the kernel's C functions,
                    declared once), pyshim.c (C loader)
kernel/             the C kernel of both runtimes: gearkernel.h (contract), gearkernel.c (hot
                    path), gk_lookup.h, gk_model.c, gk_stops.c, gk_zones.c, gk_temperature.c,
                    gk_envelope.c; gkfmu.c/.h (the FMU behaviour both runtimes share)
standalone/         fmi2_gear.c / fmi3_gear.c: the FMI 2.0 / 3.0 layers in C over the plumbing
                    fmi_common.c and the gear model gear_model.c, their contract gf_model.h
==================  =========================================================
"""
