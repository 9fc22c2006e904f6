"""Every option string the scene, the physics, the solvers and the FMU builders accept.

One definition each; the scene schema, the contact-model registry, the native solver,
the reference integrator, the FMU builders, the planner and the CLI import them from here.
Names that a kernel switches on map to the integer code the numba kernels and the C
kernel (gearkernel.h) use.

Renamed option values keep their old spelling for one release: :data:`DEPRECATED_SPELLINGS`
maps it to the new one and :func:`current_spelling` (called wherever a value enters: the
scene reader, the native and reference solvers, the sweeps, the FMU builders) returns the
new spelling with a :class:`FutureWarning`.  FutureWarning, not DeprecationWarning: the
old spellings are written by end users in scene files (read by the ``gearfmu`` command as
well as by Python code), and Python shows DeprecationWarning by default only for code run
as ``__main__`` (Python docs,
"warnings -- Warning control", section "Warning Categories": FutureWarning is "the base
category for warnings about deprecated features when those warnings are intended for end
users of applications").
"""
import os
import sys
import warnings

__all__ = ["CONTACT_MODELS", "LUBRICATED_CONTACT_MODELS", "FILM_FAILURE_POLICIES", "FILM_TRANSIENT_MODES",
           "THERMAL_AXIS_QUANTITIES", "FLANK_LAWS", "DAMPING_MODELS", "INTEGRATORS", "RUNTIMES",
           "DEFAULT_RUNTIME", "HELIX_HANDS", "OIL_ALPHA_LAWS", "DEPRECATED_SPELLINGS", "current_spelling",
           "DEFAULT_DAMPING_MODEL", "DEFAULT_INTEGRATOR", "TEMPERATURE_INPUTS", "GEARBOX_INTEGRATORS", "FMI3_OUTPUTS",
           "DEFAULT_FMI3_OUTPUTS", "FMU_INTERFACES", "DEFAULT_FMU_INTERFACE", "ME_NODE_EVENTS",
           "DEFAULT_ME_NODE_EVENTS", "SSP_COUPLINGS", "DEFAULT_SSP_COUPLING", "PLANETARY_PORTS", "PLANETARY_MODELS",
           "DEFAULT_PLANETARY_MODEL"]

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
#: [thermal] axis_quantity: what the tables' temperature axis is (docs/thermal.md); the first is the default
THERMAL_AXIS_QUANTITIES = ("bulk", "oil", "bulk_and_oil")
#: axis_quantity -> the FMU input that selects the tables' temperature axis (docs/thermal.md;
#: modeldescription/variables.toml); the FMU runtime template, which imports nothing from
#: gearfmu, keeps its own copy of the input names
TEMPERATURE_INPUTS = {"bulk": "bulk_temperature", "oil": "oil_temperature", "bulk_and_oil": "gearbox_temperature"}
#: free-flank thermal deformation laws (gearfmu.gear.thermal.free_flank_deformation_m); the first is the default
FLANK_LAWS = ("radial_tangential", "homogeneous")
#: [thermal] oil_alpha: the pressure-viscosity coefficient along an oil temperature axis,
#: "roelands" (Roelands 1966, constant Z: alpha(T) from eta0(T); the default) or "constant" (docs/thermal.md)
OIL_ALPHA_LAWS = ("roelands", "constant")
#: helix hand of the pinion (the gear has the opposite hand; docs/helical.md)
HELIX_HANDS = ("right", "left")
#: damping-model names -> kernel code (docs/model.md "Per-pair force"; gearkernel.h GK_DAMPING_*):
#: "elastobacklash" the Modelica ElastoBacklash rule (the damping force never exceeds the
#: spring force and a pair never pulls); "contact_zone" every pair inside its geometric
#: contact zone (k_j > 0) carries spring plus viscous damping force, even while separated
#: by the backlash, and may pull (Xu et al. 2022, Appl. Sci. 12, 4690, eq 3-5)
DAMPING_MODELS = {"elastobacklash": 0, "contact_zone": 1}
#: the damping rule of a scene, solver and FMU builder that names none
DEFAULT_DAMPING_MODEL = "elastobacklash"
#: integrator names -> kernel code (docs/model.md "Integration"; gearkernel.h GK_INTEGRATOR_*);
#: the FMU parameter ``integrator`` takes the code
INTEGRATORS = {"rk4": 0, "rk4_kink": 1, "rk4_node": 2, "rk4_seg": 3}
#: the integrator wherever none is named: rk4_kink with the table nodes reached by one step to
#: their predicted crossing and only where the tables bend (docs/native.md "rk4_node"), faster
#: than rk4_kink down to 1e-9 relative error on the fronts of benchmarks/bench_integrators.py;
#: the default of the native solver, the scene, the FMU builders and the FMU parameter
#: ``integrator`` alike, so a native run and an FMU built with defaults integrate identically
DEFAULT_INTEGRATOR = "rk4_node"
#: the integrators of the gearbox solver (gearfmu.gearbox.native, docs/gearbox.md "Integrators"), a
#: subset of INTEGRATORS with the same codes; the default is DEFAULT_INTEGRATOR
GEARBOX_INTEGRATORS = ("rk4", "rk4_kink", "rk4_node", "rk4_seg")
#: the ports of a planetary stage (parts ``<stage>.sun``, ``<stage>.carrier``, ``<stage>.ring``;
#: docs/planetary.md): one of them is held, the other two join the drivetrain
PLANETARY_PORTS = ("sun", "carrier", "ring")
#: dynamic models of a planetary stage (docs/planetary.md "Model"): Lin & Parker's
#: translational-rotational model or the purely torsional one
PLANETARY_MODELS = ("translational", "torsional")
#: the planetary model of a scene or stage that names none
DEFAULT_PLANETARY_MODEL = "translational"
#: how the stage FMUs of a gearbox SSP are coupled (docs/gearbox.md "The SSP of stage FMUs"):
#: "flange" every elastic shaft inside the stage FMU of the light body it drives, the stage taking
#: the speed of the body at the shaft's far end and returning the shaft's torque (the default);
#: "shaft" the stages take torques at their pinion and gear, shaft FMUs between them integrate the
#: exchanged speeds and return the shaft torque
SSP_COUPLINGS = ("flange", "shaft")
DEFAULT_SSP_COUPLING = "flange"
#: FMU runtimes (docs/fmu.md, docs/standalone.md)
RUNTIMES = ("pythonfmu", "standalone")
#: how an FMI 3 FMU carries the per-slot outputs (docs/standalone.md "FMI 3.0"): "array" (pair_force,
#: load_sharing as arrays of the slot count) or "scalar" (pair_force_1 .. pair_force_P, for hosts
#: without array support)
FMI3_OUTPUTS = ("array", "scalar")
DEFAULT_FMI3_OUTPUTS = "array"
#: the FMI interfaces a standalone FMU offers (docs/standalone.md "Model Exchange"): Co-Simulation,
#: Model Exchange, or both in one FMU (the default: every standalone FMU is usable both ways; the
#: pythonfmu runtime offers Co-Simulation only)
FMU_INTERFACES = ("cs", "me", "both")
DEFAULT_FMU_INTERFACE = "both"
#: Model Exchange's table-node events (docs/model.md "Model Exchange"): none (the host's solver
#: steps over every table node), the big kinks (the default: rk4_seg's stops, a few per mesh
#: period; measured by benchmarks/bench_me.py, docs/validation.md) or every node where the tables
#: bend (rk4_node's)
ME_NODE_EVENTS = ("none", "kinks", "all")
DEFAULT_ME_NODE_EVENTS = "kinks"
#: the FMU runtime when a scene names none: the all-C one (no Python needed in the importing tool)
DEFAULT_RUNTIME = "standalone"

#: old spellings of option values, field -> {old: new}; accepted for one release with a
#: FutureWarning naming the new spelling (:func:`current_spelling`).  "seed003" named the
#: damping rule after the paper that uses it (Xu et al. 2022); "contact_zone" says what it does.
DEPRECATED_SPELLINGS = {"damping_model": {"seed003": "contact_zone"}}


def current_spelling(field: str, value, where: str = ""):
    """``value`` of the option ``field`` (a key of :data:`DEPRECATED_SPELLINGS`), or its new
    spelling with a :class:`FutureWarning` that names it when ``value`` is an old spelling.
    ``where``: the name the warning gives the field (e.g. the scene key path; default ``field``).
    Any other value is returned unchanged (the caller checks it against its vocabulary)."""
    new = DEPRECATED_SPELLINGS.get(field, {}).get(value) if isinstance(value, str) else None
    if new is None:
        return value
    warnings.warn(f"{where or field} = {value!r} is deprecated and will be removed; use {new!r} "
                  "(the same rule)", FutureWarning, stacklevel=_first_frame_outside_package())
    return new


def _first_frame_outside_package() -> int:
    """The ``stacklevel`` of the innermost caller outside the gearfmu package, so that the
    warning points at the user's line, not at the reader that met the value."""
    package = os.path.dirname(os.path.dirname(os.path.abspath(__file__))) + os.sep
    frame, level = sys._getframe(1), 1
    while frame is not None and frame.f_code.co_filename.startswith(package):
        frame, level = frame.f_back, level + 1
    return level
