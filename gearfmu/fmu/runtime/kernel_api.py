"""The C functions of the kernel library, declared once (gearfmu/fmu/kernel: gearkernel.h, gkfmu.h,
and the planetary kernel's plkernel.h).

:data:`KERNEL_FUNCTIONS` has one row per exported function: its name, result type, argument
types (the C prototype of the header, pointers as ``void *``) and what its result means
(:data:`STATUS`: a ``GK_*`` status code, ``GK_OK`` = 0 on success; :data:`FLAG`: 1 on success,
0 with the reasons queued for ``gkf_message``; :data:`VALUE`: a plain value).  :func:`bind`
gives a loaded library every signature of the table, the way FMPy's ``fmi2.py`` binds each FMI
function once with its types; with ``check=True`` a :data:`STATUS` function that returns an
error raises :class:`KernelError` with the kernel's own words for it (``gkf_kernel_error``).
:func:`load_kernel` loads a library and binds it.  The pythonfmu runtime, the tests and the
benchmarks all bind the kernel here; tests/unit/fmu/test_kernel_api.py checks the table against the
headers.

This module runs inside the pythonfmu FMU too (the builder copies it beside the slave under
the FMU's own name), so it imports nothing but the standard library.
"""
import ctypes

#: the C types of the table (every pointer, const or not, is ``void *``; text is ``const char *``)
INT, DOUBLE, PTR, TEXT, VOID = ctypes.c_int, ctypes.c_double, ctypes.c_void_p, ctypes.c_char_p, None
#: what a result means
STATUS, FLAG, VALUE = "status", "flag", "value"

#: the ABI versions the table declares (gearkernel.h GK_ABI_VERSION, gkfmu.h GKF_ABI_VERSION)
KERNEL_ABI_VERSION = 6  # 2: temperature axis, 3: verified envelope check, 4: node kink flags,
#                         5: contact-zone cuts from the tables' engagement angles, 6: Model Exchange
FMU_LAYER_ABI_VERSION = 2  # 2: Model Exchange (gkf_me_inputs, gkf_me_speed)

_D6 = (DOUBLE,) * 6
#: (name, result type, argument types, what the result means), in the order of the headers
KERNEL_FUNCTIONS = (
    # gearkernel.h: the model, its state and the step
    ("gk_abi_version", INT, (), VALUE),
    ("gk_sizeof_model", INT, (), VALUE),
    ("gk_sizeof_state", INT, (), VALUE),
    ("gk_n_outputs", INT, (INT,), VALUE),
    ("gk_init", INT, (PTR, INT, INT, INT, PTR, PTR, PTR, PTR) + _D6, STATUS),
    ("gk_zone_cuts", INT, (INT, INT, DOUBLE, DOUBLE, DOUBLE, DOUBLE, PTR), STATUS),
    ("gk_set_zone_cuts", INT, (PTR, PTR), STATUS),
    ("gk_set_zone_edges", INT, (PTR, DOUBLE, DOUBLE, DOUBLE), STATUS),
    ("gk_set_temperature_axis", INT, (PTR, INT, PTR), STATUS),
    ("gk_set_temperature", INT, (PTR, DOUBLE), STATUS),
    ("gk_set_damping", INT, (PTR, DOUBLE, INT), STATUS),
    ("gk_set_integrator", INT, (PTR, INT), STATUS),
    ("gk_initialize", INT, (PTR, PTR, DOUBLE, DOUBLE, DOUBLE), STATUS),
    ("gk_do_step", INT, (PTR, PTR, DOUBLE, DOUBLE, DOUBLE, DOUBLE, PTR), STATUS),
    ("gk_outputs", INT, (PTR, PTR, DOUBLE, PTR), STATUS),
    ("gk_substeps", DOUBLE, (DOUBLE, DOUBLE), VALUE),
    # gearkernel.h: Model Exchange
    ("gk_sizeof_me", INT, (), VALUE),
    ("gk_me_n_outputs", INT, (INT,), VALUE),
    ("gk_me_n_indicators", INT, (PTR, INT), VALUE),
    ("gk_me_init", INT, (PTR, PTR, PTR, DOUBLE, DOUBLE, INT), STATUS),
    ("gk_me_update", INT, (PTR, PTR, PTR, DOUBLE, DOUBLE, PTR), STATUS),
    ("gk_me_derivatives", INT, (PTR, PTR, PTR, DOUBLE, DOUBLE, PTR), STATUS),
    ("gk_me_indicators", INT, (PTR, PTR, PTR, DOUBLE, PTR), STATUS),
    ("gk_me_outputs", INT, (PTR, PTR, PTR, DOUBLE, DOUBLE, PTR, PTR), STATUS),
    # gearkernel.h: the verified envelope
    ("gk_sizeof_envelope", INT, (), VALUE),
    ("gk_envelope_init", INT, (PTR, INT), STATUS),
    ("gk_envelope_set", INT, (PTR, INT, DOUBLE, DOUBLE), STATUS),
    ("gk_envelope_rearm", VOID, (PTR,), VALUE),
    ("gk_envelope_check", INT, (PTR, INT, TEXT, DOUBLE, DOUBLE, PTR, INT), VALUE),
    # gkfmu.h: the FMU behaviour both runtimes share
    ("gkf_abi_version", INT, (), VALUE),
    ("gkf_sizeof", INT, (), VALUE),
    ("gkf_kernel_error", TEXT, (INT,), VALUE),
    ("gkf_init", INT, (PTR, PTR, PTR), STATUS),
    ("gkf_declare", INT, (PTR, INT, TEXT, INT, DOUBLE, INT, DOUBLE), STATUS),
    ("gkf_set_values", INT, (PTR, PTR), STATUS),
    ("gkf_reset", VOID, (PTR,), VALUE),
    ("gkf_initialize", INT, (PTR, PTR, DOUBLE, PTR), FLAG),
    ("gkf_do_step", INT, (PTR, PTR, DOUBLE, DOUBLE, PTR), FLAG),
    ("gkf_me_inputs", INT, (PTR, DOUBLE), FLAG),
    ("gkf_me_speed", VOID, (PTR, PTR, DOUBLE), VALUE),
    ("gkf_restore", INT, (PTR, INT, INT, DOUBLE, INT), STATUS),
    ("gkf_zeta_valid", INT, (PTR,), VALUE),
    ("gkf_zeta_applied", DOUBLE, (PTR,), VALUE),
    ("gkf_warned_range", INT, (PTR,), VALUE),
    ("gkf_n_messages", INT, (PTR,), VALUE),
    ("gkf_message_level", INT, (PTR, INT), VALUE),
    ("gkf_message", TEXT, (PTR, INT), VALUE),
)


#: the planetary drivetrain kernel (plkernel.h; pl_kernel.c and pl_static.c compiled beside the kernel)
PLANETARY_ABI_VERSION = 2
PLANETARY_FUNCTIONS = (
    ("pl_abi_version", INT, (), VALUE),
    ("pl_sizeof_model", INT, (), VALUE),
    ("pl_sizeof_work", INT, (), VALUE),
    ("pl_sizeof_state", INT, (), VALUE),
    ("pl_events", ctypes.c_long, (PTR,), VALUE),
    ("pl_init", INT, (PTR, INT, PTR, PTR, INT, INT, INT), STATUS),
    ("pl_add_spring", INT, (PTR, INT, PTR, PTR, DOUBLE, DOUBLE), STATUS),
    ("pl_add_frame", INT, (PTR, INT, INT, DOUBLE, DOUBLE), STATUS),
    ("pl_add_mesh", INT, (PTR, PTR, INT, PTR, PTR, INT, PTR, PTR, DOUBLE, DOUBLE, DOUBLE), STATUS),
    ("pl_add_group", INT, (PTR, INT, PTR), STATUS),
    ("pl_set_integrator", INT, (PTR, INT), STATUS),
    ("pl_add_drive", INT, (PTR, INT, PTR), STATUS),
    ("pl_set_drive_speeds", INT, (PTR, PTR, PTR), STATUS),
    ("pl_start_drives", INT, (PTR, PTR, PTR), STATUS),
    ("pl_set_frame_drive", INT, (PTR, INT, INT, DOUBLE), STATUS),
    ("pl_initialize_driven", INT, (PTR, PTR, PTR, DOUBLE, DOUBLE, DOUBLE, PTR, PTR), STATUS),
    ("pl_reference_torque", DOUBLE, (PTR, DOUBLE, DOUBLE), VALUE),
    ("pl_mesh_torque", DOUBLE, (PTR, INT, DOUBLE), VALUE),
    ("pl_initialize", INT, (PTR, PTR, PTR, DOUBLE, DOUBLE, DOUBLE, PTR), STATUS),
    ("pl_derivatives", INT, (PTR, PTR, DOUBLE, PTR, DOUBLE, DOUBLE, PTR), STATUS),
    ("pl_do_step", INT, (PTR, PTR, PTR, DOUBLE, DOUBLE, DOUBLE, DOUBLE, PTR), STATUS),
    ("pl_outputs", INT, (PTR, PTR, PTR, DOUBLE, DOUBLE, PTR), STATUS),
    ("pl_sizeof_me", INT, (), VALUE),
    ("pl_me_n_indicators", INT, (PTR, INT), VALUE),
    ("pl_me_init", INT, (PTR, PTR, PTR, PTR, DOUBLE, DOUBLE, INT), STATUS),
    ("pl_me_update", INT, (PTR, PTR, PTR, PTR, DOUBLE, DOUBLE, PTR), STATUS),
    ("pl_me_derivatives", INT, (PTR, PTR, PTR, PTR, DOUBLE, DOUBLE, PTR), STATUS),
    ("pl_me_indicators", INT, (PTR, PTR, PTR, PTR, DOUBLE, DOUBLE, PTR), STATUS),
    ("pl_me_outputs", INT, (PTR, PTR, PTR, PTR, DOUBLE, DOUBLE, PTR), STATUS),
    ("pl_mesh_offset", INT, (PTR, INT), VALUE),
    ("pl_spring_offset", INT, (PTR,), VALUE),
    ("pl_group_offset", INT, (PTR, INT), VALUE),
    ("pl_n_outputs", INT, (PTR,), VALUE),
)


class KernelError(RuntimeError):
    """A kernel function of a checked binding returned an error status (``status``: the ``GK_*``
    code; ``words``: the kernel's own words for it)."""

    def __init__(self, function: str, status: int, words: str):
        super().__init__(f"{function}: status {status} ({words})")
        self.function, self.status, self.words = function, status, words


def _status_check(lib, name):
    def check(result, func, args):
        if result != 0:
            raise KernelError(name, int(result), lib.gkf_kernel_error(int(result)).decode("utf-8", "replace"))
        return result
    return check


def bind(lib, *, check: bool = False, functions=KERNEL_FUNCTIONS):
    """Give the ctypes library ``lib`` (the kernel library) the signature of every function of
    ``functions`` (:data:`KERNEL_FUNCTIONS`; a library with the planetary kernel also
    :data:`PLANETARY_FUNCTIONS`); with ``check`` a :data:`STATUS` function raises
    :class:`KernelError` on an error status instead of returning it.  Returns ``lib``."""
    for name, result, args, meaning in functions:
        f = getattr(lib, name)
        f.restype = result
        f.argtypes = list(args)
        if check and meaning == STATUS:
            f.errcheck = _status_check(lib, name)
    return lib


def load_kernel(path, *, check: bool = False, planetary: bool = False):
    """Load the kernel library at ``path`` (str or path-like) and :func:`bind` it (with ``planetary``
    also the planetary kernel's functions)."""
    functions = KERNEL_FUNCTIONS + PLANETARY_FUNCTIONS if planetary else KERNEL_FUNCTIONS
    return bind(ctypes.CDLL(str(path)), check=check, functions=functions)
