"""FMUs from tables: model description, one builder per runtime, runtime, C sources.

Imports :mod:`gearfmu.gearbox` (the gearbox FMU), :mod:`gearfmu.planetary` (the planetary kernel's
data and the planetary FMU), :mod:`gearfmu.tables`, :mod:`gearfmu.dynamics`
(the run settings' automatic values and the validation record) and :mod:`gearfmu.common` (the run
settings); never the scene nor the physics packages (pyproject.toml's contracts).
:mod:`gearfmu.fmu.runtime` imports nothing from gearfmu.

Exports (loaded with their module on first use): the builders ``build_standalone_fmu``,
``build_fmu`` (pythonfmu), ``build_gearbox_fmu``, ``build_planetary_fmu``, ``FmuBuildError``; an FMU against the native
solver ``validate_fmu_against_native``, ``validate_gearbox_fmu``, ``open_fmu``, ``run_fmu``,
``FmuMismatchError``; ``fmu_summary``; ``fmu_envelope_record``; the FMI Cross-Check sets
``write_reference_results``, ``check_reference_results``.

==================  =========================================================
Module              Contents
==================  =========================================================
build_steps         what both builders share: checked arguments and run
                    settings, kernel sources and flags, interface
                    variables, resources, the FMU file, BuildInputs
                    (what one build knows before it writes a file)
modeldesc           modelDescription.xml from modeldescription/variables.toml
pythonfmu_build     build_fmu: the pythonfmu runtime; compile flags, kernel
standalone_build    build_standalone_fmu: FMI 2.0 or 3.0 in C, no Python;
                    StandaloneOptions (FMI version, interfaces, platforms)
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
multimesh_build     the packaging the gearbox and planetary FMUs share
planetary_interface a planetary FMU's variables from modeldescription/planetary.toml
planetary_build     build_planetary_fmu: one FMU for a drivetrain with
                    planetary stages, in C
planetary_doc       the planetary FMU's documentation page
planetary_compare   a planetary FMU against the native planetary solver
composition         a gearbox cut into stage FMUs and torsional elements
                    (an SSP of stage FMUs: components, links, power bonds)
stage_build         build_stage_fmu: one stage with its shafts and flanges, in C
element_build       build_element_fmu: a rigid body or an elastic shaft, in C
planetary_kernel    the planetary drivetrain kernel in C from Python: a
                    PlanetaryModel's flat data, the library, its ctypes model
gearbox_ssp         the files of an SSP of stage FMUs (system structure, OSP
                    angular mechanical ports, libcosim's OspSystemStructure)
ssp_engines         run such an SSP in fmpy and libcosim (fixed step, ECCO);
                    the energy residual at its power bonds
runtime/            the FMU-side Python (pythonfmu) and the C loader
kernel/, standalone/ the C kernels and the FMI layers in C
==================  =========================================================
"""
from ..common.exports import lazy_exports

_EXPORTS = {
    "build_standalone_fmu": "standalone_build", "build_fmu": "pythonfmu_build",
    "build_gearbox_fmu": "gearbox_build", "build_planetary_fmu": "planetary_build", "FmuBuildError": "build_steps",
    **dict.fromkeys(("validate_fmu_against_native", "open_fmu", "run_fmu", "FmuMismatchError"), "compare"),
    "validate_gearbox_fmu": "gearbox_compare",
    "fmu_summary": "summary",
    "fmu_envelope_record": "envelope",
    "write_reference_results": "crosscheck", "check_reference_results": "crosscheck",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
