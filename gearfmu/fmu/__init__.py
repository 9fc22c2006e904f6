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
composition         a gearbox cut into stage FMUs and torsional elements
                    (an SSP of stage FMUs: components, links, power bonds)
stage_build         build_stage_fmu: one stage with its shafts and flanges, in C
element_build       build_element_fmu: a rigid body or an elastic shaft, in C
gearbox_ssp         the files of an SSP of stage FMUs (system structure, OSP
                    angular mechanical ports, libcosim's OspSystemStructure)
ssp_engines         run such an SSP in fmpy and libcosim (fixed step, ECCO);
                    the energy residual at its power bonds
==================  =========================================================
"""
