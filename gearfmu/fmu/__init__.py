"""FMUs from tables: model description, one builder per runtime, runtime, C sources.

Imports :mod:`gearfmu.gearbox` (the gearbox FMU), :mod:`gearfmu.tables`, :mod:`gearfmu.dynamics`
(the run settings' automatic values and the validation record) and :mod:`gearfmu.common` (the run
settings); never the scene nor the physics packages (pyproject.toml's contracts).
:mod:`gearfmu.fmu.runtime` imports nothing from gearfmu.

==================  =========================================================
Module              Contents
==================  =========================================================
build_steps         what both builders share: checked arguments and run
                    settings, kernel sources and flags, interface
                    variables, resources, the FMU file
modeldesc           modelDescription.xml from modeldescription/variables.toml
pythonfmu_build     build_fmu: the pythonfmu runtime; compile flags, kernel
standalone_build    build_standalone_fmu: FMI 2.0 or 3.0 in C, no Python
crossbuild          standalone binaries for every desktop platform (zig cc)
envelope            the FMU's envelope record (resources/envelope.json): the
                    range it states and checks, verified or not
validation          the validation record every FMU carries
fmudoc              the documentation page every FMU carries
summary             one line on an FMU file: runtime, FMI version, platforms
integrity           an FMU handed over: intact, and can it run here
compare             an FMU against the native solver (gearfmu validate)
crosscheck          FMI Cross-Check reference results, any FMU against them
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
runtime/            the FMU-side Python (pythonfmu) and the C loader
kernel/, standalone/ the C kernels and the FMI layers in C
==================  =========================================================
"""
