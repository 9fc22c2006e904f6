"""gearfmu FMU runtime: a thin pythonfmu Fmi2Slave over the compiled C kernel.

TEMPLATE.  gearfmu.fmu.pythonfmu_build copies this file into every FMU under a unique
module name and replaces the class name ``GearFmuSlave`` by a unique one
(pythonfmu FMUs in one process share one interpreter and module cache).

This file must import neither gearfmu nor numba: the host needs Python with
numpy and the pythonfmu wrapper only.  Everything it needs sits in the FMU's
``resources/``:

* ``gearfmu_runtime.json`` -- variables (names, value references, start
  values, kernel output positions; produced from modeldescription/variables.toml),
  the kernel file name and the SHA-256 of every resource file;
* ``tables.json`` + ``tables.bin`` -- the tooth-pair tables (format:
  gearfmu/tables/mesh_tables.py, docs/tables.md), checked against their SHA-256 sums;
* the kernel shared library (gearfmu/fmu/kernel/: gearkernel.c and the files beside it, with
  gkfmu.c), loaded with ctypes and bound by the function table of ``kernel_api.py`` (this FMU's
  copy beside this file, under the FMU's own module name).

The parameter and input checks, the damping and temperature applied, the initial state, the
communication step, the outputs and the torque-axis and verified-envelope warnings (``envelope``
in ``gearfmu_runtime.json``), with their messages, are the kernel's FMU layer (gkfmu.c): the
functions the standalone runtime calls too.  This file hands the values over and passes the
messages to the host's logger.

The model is docs/model.md; the FMU behaviour is docs/fmu.md.
"""
import hashlib
import json
import math
import os
import struct

import numpy as np
from pythonfmu import Fmi2Slave
from pythonfmu.enums import Fmi2Causality, Fmi2Initial, Fmi2Status, Fmi2Variability
from pythonfmu.variables import Integer, Real

if __package__:  # the package's template (gearfmu.fmu.runtime)
    from .kernel_api import load_kernel
else:  # inside the FMU: the copy beside this file (the builder names the module after the FMU)
    from gearfmu_kernel_api import load_kernel

RUNTIME_FILE = "gearfmu_runtime.json"
TABLE_VERSIONS = (1, 2)  # docs/tables.md (2: operating axes with a temperature axis)
TEMPERATURE_INPUT = "bulk_temperature"  # the input that selects a bulk temperature axis (docs/model.md)
#: inputs that may select the temperature axis, by what the axis is (docs/thermal.md); the
#: variable table holds exactly one of them when the tables have a temperature axis.  A copy of
#: gearfmu.common.vocabulary.TEMPERATURE_INPUTS' values (this template imports nothing from
#: gearfmu; tests/unit/scene/test_scene.py checks that the two agree)
TEMPERATURE_INPUT_NAMES = ("bulk_temperature", "oil_temperature", "gearbox_temperature")

# Serialized FMU state (docs/robustness.md "FMU state"): a fixed little-endian
# header, the raw bytes of the kernel's gk_state, the output vector, the values
# of all non-output variables, a few runtime scalars, then the SHA-256 of all
# that.  No pickle: plain bytes of POD data.
STATE_MAGIC = b"GEARFMUS"
STATE_VERSION = 1
_STATE_HEAD = struct.Struct("<8sHHI32sIII")  # magic, version, flags, reserved, fingerprint, n_state, n_out, n_values
_STATE_TAIL = struct.Struct("<ddQ")          # zeta applied (NaN = none), start time, accepted steps
_FLAG_INITIALIZED, _FLAG_WARNED_RANGE, _FLAG_TERMINATED, _FLAG_INIT_MODE = 1, 2, 4, 8

#: the variable of each gkfmu.h GKF_* slot (the temperature slot: the one temperature input)
FMU_LAYER_SLOTS = ("damping_ratio", "pinion_speed_start", "pinion_angle_start", "max_step", "damping_model",
                   "integrator", "pinion_torque", "gear_torque", None)
_GKF_TEMPERATURE = 8


class GearFmuResourceError(ValueError):
    """A resource file of the FMU is missing, corrupted or inconsistent."""


def _sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _read_config(res):
    cfg_path = os.path.join(res, RUNTIME_FILE)
    try:
        with open(cfg_path, "rb") as f:
            return json.loads(f.read().decode("utf-8"))
    except (OSError, ValueError) as exc:
        raise GearFmuResourceError(f"resources/{RUNTIME_FILE}: cannot read ({exc})") from None


def _load_resources(res, cfg):
    """Verify every resource against its SHA-256; return (tables meta, arrays)."""
    for fname, digest in cfg["sha256"].items():
        p = os.path.join(res, fname)
        if not os.path.isfile(p):
            raise GearFmuResourceError(f"resources/{fname}: missing from the FMU")
        if _sha256(p) != digest:
            raise GearFmuResourceError(
                f"resources/{fname}: SHA-256 checksum mismatch (file corrupted or tampered with); refusing to run")
    with open(os.path.join(res, "tables.json"), "rb") as f:
        meta = json.loads(f.read().decode("utf-8"))
    if meta.get("version") not in TABLE_VERSIONS:
        raise GearFmuResourceError(f"resources/tables.json: table format version {meta.get('version')!r} found; "
                                   f"this runtime reads versions {list(TABLE_VERSIONS)}")
    with open(os.path.join(res, "tables.bin"), "rb") as f:
        binary = f.read()
    if hashlib.sha256(binary).hexdigest() != meta.get("bin_sha256"):
        raise GearFmuResourceError("resources/tables.bin: checksum differs from tables.json bin_sha256; refusing to run")
    arrays = {}
    for name, ent in meta["arrays"].items():
        raw = binary[ent["offset"]: ent["offset"] + ent["nbytes"]]
        if hashlib.sha256(raw).hexdigest() != ent["sha256"]:
            raise GearFmuResourceError(f"resources/tables.bin: checksum mismatch in array {name!r}; refusing to run")
        arrays[name] = np.ascontiguousarray(np.frombuffer(raw, dtype="<f8").reshape(ent["shape"]), dtype=np.float64)
    return meta, arrays


class GearFmuSlave(Fmi2Slave):
    """Two-inertia spur or helical gear pair (docs/model.md) over the C kernel."""

    author = "gearfmu"
    description = "Spur or helical gear pair, per-tooth-pair dynamic model (seed 003 eq 1-6)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        res = self.resources
        if res is None:
            raise GearFmuResourceError("resources: the host gave no resource location")
        cfg = _read_config(res)
        try:
            meta, arr = _load_resources(res, cfg)
        except GearFmuResourceError as exc:
            self.log(str(exc), Fmi2Status.fatal)
            raise
        self.modelName = cfg["model_identifier"]
        self._cfg = cfg
        self._lib = load_kernel(os.path.join(res, cfg["kernel_file"]))
        lib = self._lib
        if (lib.gk_abi_version() != cfg["kernel_abi_version"]
                or lib.gkf_abi_version() != cfg.get("fmu_layer_abi_version")):
            raise GearFmuResourceError(f"resources/{cfg['kernel_file']}: kernel ABI version mismatch")
        P, n_phi, nt = int(meta["slots"]), int(meta["n_phi"]), int(meta["n_torque"])
        sc = meta["scalars"]
        # keep every array referenced by self: the kernel borrows their memory
        self._torque = arr["torque_Nm"]
        self._k = arr["k_N_per_m"]
        self._e = arr["e_m"]
        self._b = arr["backlash_half_m"]
        self._model = np.zeros(lib.gk_sizeof_model() // 8 + 2)
        self._state = np.zeros(lib.gk_sizeof_state() // 8 + 1)
        self._out = np.zeros(lib.gk_n_outputs(P))
        self._pm = self._model.ctypes.data
        self._ps = self._state.ctypes.data
        self._po = self._out.ctypes.data
        st = lib.gk_init(self._pm, P, n_phi, nt, self._torque.ctypes.data, self._k.ctypes.data,
                         self._e.ctypes.data, self._b.ctypes.data, sc["phi_period_rad"],
                         sc["base_radius_pinion_m"], sc["base_radius_gear_m"], sc["inertia_pinion_kgm2"],
                         sc["inertia_gear_kgm2"], sc["k_mean_N_per_m"])
        if st != 0:
            msg = f"resources/tables.json: kernel rejects the tables ({self._kernel_error(st)})"
            self.log(msg, Fmi2Status.fatal)
            raise GearFmuResourceError(msg)
        self._temp_name = None
        if "temperature_C" in arr:  # version 2 tables with a temperature axis (docs/tables.md)
            self._tax = arr["temperature_C"]
            st = lib.gk_set_temperature_axis(self._pm, int(self._tax.size), self._tax.ctypes.data)
            names = [n for n in TEMPERATURE_INPUT_NAMES if n in [v["name"] for v in cfg["variables"]]]
            self._temp_name = names[0] if len(names) == 1 else TEMPERATURE_INPUT
            if st != 0 or len(names) != 1:
                msg = (f"resources/tables.json: temperature axis rejected by the kernel or not exactly one "
                       f"of {list(TEMPERATURE_INPUT_NAMES)} inputs in the variable table")
                self.log(msg, Fmi2Status.fatal)
                raise GearFmuResourceError(msg)
        eng = meta.get("engagement")  # contact-zone edges (docs/model.md "Contact-zone edges")
        if eng is not None:
            self._cuts = np.zeros(2 * P * n_phi)
            if lib.gk_zone_cuts(P, n_phi, sc["phi_period_rad"], sc["mesh_period_rad"], float(eng["in_rad"]),
                                float(eng["out_rad"]), self._cuts.ctypes.data) == 0:
                lib.gk_set_zone_cuts(self._pm, self._cuts.ctypes.data)
        self._init_envelope(cfg.get("envelope"))
        self._slots = P
        self._initialized = False
        self._in_init = False  # between fmi2EnterInitializationMode and fmi2ExitInitializationMode
        self._dirty = True     # a value was set since the outputs were last computed
        self._terminated = False
        self._n_steps = 0  # accepted communication steps (part of the FMU state)
        self._t0 = 0.0
        self._fingerprint = hashlib.sha256(json.dumps(
            [cfg["sha256"], lib.gk_abi_version(), lib.gk_sizeof_model(), lib.gk_sizeof_state(),
             [v["name"] for v in cfg["variables"]]]).encode("utf-8")).digest()
        self._v = {}
        self._limits = {}
        self._output_vrs = {int(ent["vr"]) for ent in cfg["variables"] if ent["causality"] == "output"}
        for ent in cfg["variables"]:
            self._register(ent)
        self._init_fmu_layer()

    # ------------------------------------------------------------ variables
    def _register(self, ent):
        name = ent["name"]
        causality = getattr(Fmi2Causality, ent["causality"])
        variability = getattr(Fmi2Variability, ent["variability"])
        initial = getattr(Fmi2Initial, ent["initial"]) if ent.get("initial") else None
        cls = Integer if ent["type"] == "Integer" else Real
        if ent["causality"] == "output":
            idx = int(ent["output_index"])
            out = self._out
            getter = (lambda i=idx: out[i])
            setter = None
        else:
            self._v[name] = ent["start"]
            self._limits[name] = (ent.get("min"), ent.get("max"))
            values = self._v
            getter = (lambda n=name: values[n])
            setter = (lambda x, n=name: values.__setitem__(n, x))
        var = cls(name, causality=causality, variability=variability, initial=initial,
                  description=ent.get("description"), getter=getter, setter=setter)
        self.register_variable(var, nested=False)
        if var.value_reference != ent["vr"]:
            raise GearFmuResourceError(f"resources/{RUNTIME_FILE}: {name} registered with value reference "
                                       f"{var.value_reference}, expected {ent['vr']}")

    # ------------------------------------------- the kernel's FMU layer (gkfmu.c)
    _ENV_QUANTITIES = ("pinion_torque_Nm", "pinion_speed_rad_s", "temperature_C")  # GK_ENV_* order

    def _kernel_error(self, st):
        return self._lib.gkf_kernel_error(int(st)).decode("utf-8", "replace")

    def _init_envelope(self, env):
        """The kernel's envelope (docs/fmu.md "Verified envelope"); kept by self, checked by gkfmu.c."""
        self._env = np.zeros(self._lib.gk_sizeof_envelope() // 8 + 1)
        self._pe = self._env.ctypes.data
        env = env or {}
        self._lib.gk_envelope_init(self._pe, int(env.get("kind", 2)))
        for q, key in enumerate(self._ENV_QUANTITIES):
            if env.get(key) is not None:
                self._lib.gk_envelope_set(self._pe, q, float(env[key][0]), float(env[key][1]))

    def _init_fmu_layer(self):
        """Declare the variables gkfmu.c checks and drives, with their min/max (the standalone
        runtime declares the same ones from its variable table)."""
        lib = self._lib
        self._fmu = np.zeros(lib.gkf_sizeof() // 8 + 1)
        self._pf = self._fmu.ctypes.data
        self._vals = np.zeros(len(FMU_LAYER_SLOTS))
        self._pv = self._vals.ctypes.data
        lib.gkf_init(self._pf, self._pm, self._pe)
        self._slot_names = []
        for slot, name in enumerate(FMU_LAYER_SLOTS):
            name = self._temp_name if slot == _GKF_TEMPERATURE else name
            if name is None or name not in self._v:
                continue
            lo, hi = self._limits[name]
            if lib.gkf_declare(self._pf, slot, name.encode(), lo is not None, 0.0 if lo is None else float(lo),
                               hi is not None, 0.0 if hi is None else float(hi)) != 0:
                raise GearFmuResourceError(f"resources/{RUNTIME_FILE}: variable {name!r} refused by the kernel")
            self._slot_names.append((slot, name))

    def _hand_over(self, values=None):
        """The current values (or ``values``, a name -> value mapping) to gkfmu.c."""
        values = self._v if values is None else values
        for slot, name in self._slot_names:
            self._vals[slot] = float(values[name])
        self._lib.gkf_set_values(self._pf, self._pv)

    def _log_fmu_messages(self):
        lib = self._lib
        for i in range(lib.gkf_n_messages(self._pf)):
            self.log(lib.gkf_message(self._pf, i).decode("utf-8", "replace"),
                     Fmi2Status(lib.gkf_message_level(self._pf, i)))

    # ---------------------------------------------------------------- FMI
    def _init_state(self, t):
        self._hand_over()
        ok = self._lib.gkf_initialize(self._pf, self._ps, float(t), self._po)
        self._log_fmu_messages()
        self._initialized = bool(ok)
        return self._initialized

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._t0 = start_time

    # Initialization Mode (FMI 2.0 section 4.2.4): from enter on, every output is
    # the initial one computed from the values set so far, by the same _init_state
    # that exit uses; a value set in this mode marks the outputs dirty and the next
    # get of an output recomputes them.
    def enter_initialization_mode(self):
        self._in_init = True
        self._dirty = True

    def _refresh_initial_outputs(self, vrs):
        if not (self._in_init and self._dirty) or not any(int(vr) in self._output_vrs for vr in vrs):
            return
        try:
            ok = self._init_state(self._t0)
        except Exception as exc:  # noqa: BLE001 - an FMU must not crash its host
            self.log(f"initialisation failed: {exc!r}", Fmi2Status.error)
            ok = False
        if ok:
            self._dirty = False
        else:  # the reasons are logged (status error); the FMI layer refuses the get (docs/fmu.md)
            self._out[:] = float("nan")

    def exit_initialization_mode(self):
        # never raise here (pythonfmu 0.7.0 would turn it into fmi2Fatal and free the slave):
        # a failure is logged and reported by the first do_step
        self._in_init = False
        if not self._dirty and self._initialized:
            return
        try:
            if self._init_state(self._t0):
                self._dirty = False
        except Exception as exc:  # noqa: BLE001 - an FMU must not crash its host
            self.log(f"initialisation failed: {exc!r}", Fmi2Status.error)
            self._initialized = False

    def terminate(self):
        self._terminated = True

    def do_step(self, current_time, step_size):
        try:
            if self._terminated:
                self.log(f"do_step at t = {current_time!r} s after fmi2Terminate: refused (only fmi2Reset or "
                         f"fmi2FreeInstance may follow); state unchanged", Fmi2Status.error)
                return False
            if not self._initialized and not self._init_state(current_time):
                return False
            self._hand_over()
            ok = self._lib.gkf_do_step(self._pf, self._ps, float(current_time), float(step_size), self._po)
            self._log_fmu_messages()
            if not ok:
                return False
            self._n_steps += 1
            return True
        except Exception as exc:  # noqa: BLE001 - an FMU must not crash its host
            self.log(f"do_step failed: {exc!r}", Fmi2Status.error)
            return False

    # ------------------------------------------------- get/set, never raising
    # pythonfmu 0.7.0's wrapper turns any Python exception into fmi2Fatal and
    # then releases the slave object while keeping the dangling pointer (a
    # later call or fmi2FreeInstance touches freed memory).  So nothing below
    # raises: a bad call is logged with its reason (status error) and ignored;
    # a getter returns NaN / 0 for value references it cannot serve.
    def _guarded_get(self, kind, vrs, fill):
        try:
            self._refresh_initial_outputs(vrs)
            return getattr(super(), "get_" + kind)(vrs)
        except Exception as exc:  # noqa: BLE001
            self.log(f"fmi2Get{kind.capitalize()}({list(vrs)!r}) refused: {exc}; returned {fill!r}",
                     Fmi2Status.error)
            return [fill] * len(vrs)

    def _guarded_set(self, kind, vrs, values):
        try:
            if self._terminated:
                self.log(f"fmi2Set{kind.capitalize()}({list(vrs)!r}) after fmi2Terminate: ignored",
                         Fmi2Status.error)
                return
            getattr(super(), "set_" + kind)(vrs, values)
            self._dirty = True
        except Exception as exc:  # noqa: BLE001
            self.log(f"fmi2Set{kind.capitalize()}({list(vrs)!r}) refused: {exc}", Fmi2Status.error)

    def get_real(self, vrs):
        return self._guarded_get("real", vrs, float("nan"))

    def get_integer(self, vrs):
        return self._guarded_get("integer", vrs, 0)

    def get_boolean(self, vrs):
        return self._guarded_get("boolean", vrs, False)

    def get_string(self, vrs):
        return self._guarded_get("string", vrs, "")

    def set_real(self, vrs, values):
        self._guarded_set("real", vrs, values)

    def set_integer(self, vrs, values):
        self._guarded_set("integer", vrs, values)

    def set_boolean(self, vrs, values):
        self._guarded_set("boolean", vrs, values)

    def set_string(self, vrs, values):
        self._guarded_set("string", vrs, values)

    # ------------------------------------------------------------ FMU state
    # The wrapper keeps whatever _get_fmu_state returns as the fmi2FMUstate and
    # hands it to _set_fmu_state and to the static _fmu_state_to_bytes.  Our
    # state object is already the serialized bytes (immutable, so a stored
    # state can be set any number of times).
    def _state_values(self):
        return [ent["name"] for ent in self._cfg["variables"] if ent["causality"] != "output"]

    def _get_fmu_state(self):
        try:
            names = self._state_values()
            lib, pf = self._lib, self._pf
            flags = ((_FLAG_INITIALIZED if self._initialized else 0)
                     | (_FLAG_WARNED_RANGE if lib.gkf_warned_range(pf) else 0)
                     | (_FLAG_TERMINATED if self._terminated else 0) | (_FLAG_INIT_MODE if self._in_init else 0))
            state = self._state.tobytes()
            body = b"".join([
                _STATE_HEAD.pack(STATE_MAGIC, STATE_VERSION, flags, 0, self._fingerprint, len(state),
                                 self._out.size, len(names)),
                state, self._out.astype("<f8").tobytes(),
                np.array([float(self._v[n]) for n in names], dtype="<f8").tobytes(),
                _STATE_TAIL.pack(lib.gkf_zeta_applied(pf) if lib.gkf_zeta_valid(pf) else float("nan"),
                                 float(self._t0), int(self._n_steps)),
            ])
            return body + hashlib.sha256(body).digest()
        except Exception as exc:  # noqa: BLE001
            self.log(f"fmi2GetFMUstate failed: {exc!r}; the state returned cannot be set", Fmi2Status.error)
            return b""

    def _set_fmu_state(self, state):
        try:
            msg = self._restore(state)
        except Exception as exc:  # noqa: BLE001
            msg = repr(exc)
        if msg:
            self.log(f"fmi2SetFMUstate refused: {msg}; instance state unchanged", Fmi2Status.error)

    def _restore(self, state):
        if not isinstance(state, (bytes, bytearray)):
            return f"not a gearfmu state (a {type(state).__name__})"
        state = bytes(state)
        hs, ts = _STATE_HEAD.size, _STATE_TAIL.size
        if len(state) < hs + ts + 32 or state[:8] != STATE_MAGIC:
            return "not a gearfmu state (bad magic or too short)"
        magic, version, flags, _, fp, n_state, n_out, n_values = _STATE_HEAD.unpack_from(state, 0)
        if version != STATE_VERSION:
            return f"state format version {version} found; this runtime reads version {STATE_VERSION}"
        if hashlib.sha256(state[:-32]).digest() != state[-32:]:
            return "state checksum mismatch (bytes corrupted)"
        if fp != self._fingerprint:
            return "the state belongs to a different FMU (tables, kernel or variables differ)"
        names = self._state_values()
        if (n_state != self._state.nbytes or n_out != self._out.size or n_values != len(names)
                or len(state) != hs + n_state + 8 * (n_out + n_values) + ts + 32):
            return "state sizes do not match this FMU"
        o = hs
        kernel_state = np.frombuffer(state, dtype=np.float64, count=n_state // 8, offset=o)
        o += n_state
        out = np.frombuffer(state, dtype="<f8", count=n_out, offset=o)
        o += 8 * n_out
        values = np.frombuffer(state, dtype="<f8", count=n_values, offset=o)
        o += 8 * n_values
        zeta, t0, n_steps = _STATE_TAIL.unpack_from(state, o)
        # the integrator (a model setting applied at initialisation) and the damping applied
        self._hand_over(dict(zip(names, values.tolist())))
        st = self._lib.gkf_restore(self._pf, int(bool(flags & _FLAG_INITIALIZED)), int(math.isfinite(zeta)),
                                   zeta if math.isfinite(zeta) else 0.0, int(bool(flags & _FLAG_WARNED_RANGE)))
        if st != 0:
            return f"integrator or damping_ratio in the state: {self._kernel_error(st)}"
        # from here on nothing can fail: copy everything in place
        self._state[:] = kernel_state
        self._out[:] = out
        types = {ent["name"]: ent["type"] for ent in self._cfg["variables"]}
        for n, val in zip(names, values.tolist()):
            self._v[n] = int(val) if types[n] == "Integer" else val
        self._initialized = bool(flags & _FLAG_INITIALIZED)
        self._terminated = bool(flags & _FLAG_TERMINATED)
        self._in_init = bool(flags & _FLAG_INIT_MODE)
        self._dirty = self._in_init or not self._initialized
        self._t0 = t0
        self._n_steps = n_steps
        return None

    @staticmethod
    def _fmu_state_to_bytes(state):
        return state if isinstance(state, bytes) else b""

    @staticmethod
    def _fmu_state_from_bytes(state):
        return bytes(state)  # checked by _set_fmu_state
