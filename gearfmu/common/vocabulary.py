"""Every option string the scene, the physics, the solvers and the FMU builders accept.

One definition each; the scene schema, the contact-model registry, the native solver,
the reference integrator, the FMU builders, the planner and the CLI import them from here.
Names that a kernel switches on map to the integer code the numba kernels and the C
kernel (gearkernel.h) use.
"""

__all__ = ["CONTACT_MODELS", "LUBRICATED_CONTACT_MODELS", "FILM_FAILURE_POLICIES", "FILM_TRANSIENT_MODES",
           "THERMAL_AXIS_QUANTITIES", "FLANK_LAWS", "DAMPING_MODELS", "INTEGRATORS", "RUNTIMES",
           "DEFAULT_RUNTIME"]

#: contact models a scene may name (implemented by the registry of gearfmu.contact.models)
CONTACT_MODELS = ("hertz", "smooth_ehl", "rough_ehl", "fractal_mixed")
#: contact models that need a [lubricant] section
LUBRICATED_CONTACT_MODELS = ("smooth_ehl", "rough_ehl", "fractal_mixed")
#: what a rough-EHL request uses where the full film does not hold (RoughnessSpec.on_failure)
FILM_FAILURE_POLICIES = ("fractal_mixed", "hertz", "error", "load_sharing")
#: ``RoughnessSpec.film_transient`` values: "off" (steady frozen-roughness films only),
#: "correction" (docs/ehl_transient.md section 3 "last row": per film-grid node, transient
#: runs with the roughness moving with the flanks on :data:`gearfmu.contact.models.FILM_TRANSIENT_SLICES` slices give
#: c = <k_transient>/k_steady, which multiplies every slice's steady rough/smooth ratio) or
#: "film" (the rough film IS the transient film: per node, ratio = mean over those slices of
#: k_transient/k_smooth, the same for every slice, no steady rough solve; start 'auto';
#: docs/ehl_mesh.md "Transient films in the tables")
FILM_TRANSIENT_MODES = ("off", "correction", "film")
#: [thermal] axis_quantity: what the tables' temperature axis is (docs/thermal.md)
THERMAL_AXIS_QUANTITIES = ("bulk", "oil", "bulk_and_oil")
#: free-flank thermal deformation laws (gearfmu.gear.thermal.free_flank_deformation_m)
FLANK_LAWS = ("radial_tangential", "homogeneous")
#: damping-model names -> kernel code (docs/model.md "Per-pair force"; gearkernel.h)
DAMPING_MODELS = {"elastobacklash": 0, "seed003": 1}
#: integrator names -> kernel code (docs/model.md "Integration"; gearkernel.h GK_INTEGRATOR_*);
#: the FMU parameter ``integrator`` takes the code
INTEGRATORS = {"rk4": 0, "rk4_kink": 1, "rk4_node": 2}
#: FMU runtimes (docs/fmu.md, docs/standalone.md)
RUNTIMES = ("pythonfmu", "standalone")
#: the FMU runtime when a scene names none: the all-C one (no Python needed in the importing tool)
DEFAULT_RUNTIME = "standalone"
