"""Tooth-pair tables: the interface between the physics and the dynamics.

A :class:`MeshTables` holds, per tooth-pair *slot*, the mesh stiffness k and
the meshing error e against the pinion angle (and, where they depend on load,
against pinion torque), plus the few scalars that the dynamic model needs.
Both the native solver (:mod:`gearfmu.dynamics.native`) and the FMU's C kernel read
exactly these arrays; nothing else crosses from physics to dynamics.

Slots
-----
The pinion-angle axis is periodic with period ``phi_period_rad`` (a whole
number of mesh periods 2*pi/z1, a multiple of the slot count ``P``, and the
whole hunting-tooth cycle when teeth differ).  The tooth pair that starts
mesh number n (n = 0, 1, ... counted from phi = 0) lives in slot ``n % P`` for
its whole engagement, so ``pair_force[i]`` is the force history of one tooth
pair from meshing-in to meshing-out; a slot whose pair is outside the
geometric contact zone has k = 0.

Format (versions 1 and 2, documented in docs/tables.md)
-------------------------------------------------------
Version 2 adds a list of operating axes (torque, then an optional
temperature axis selected at run time by the FMU input ``bulk_temperature``);
tables without a temperature axis are still written as version 1.
A ``.gtab`` file is an uncompressed zip archive holding ``tables.json``
(format name, version, axes, scalars, provenance, one entry per array with
dtype, shape, byte offset and SHA-256) and ``tables.bin`` (the arrays as
little-endian float64, C order, concatenated).  The same two files sit
unzipped in an FMU's ``resources/``.  No pickle anywhere.  An optional key
``engagement`` holds the exact meshing-in and meshing-out angles (the sub-cell lookup at
the contact-zone edges, :mod:`gearfmu.tables.zones`); older readers ignore it.
"""
from __future__ import annotations

import hashlib
import math
import io
import json
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, Optional

import numpy as np

from ..common.user_files import ArchiveError, archive_kind, read_archive
from ..common.vocabulary import TEMPERATURE_INPUTS

FORMAT_NAME = "gearfmu-tables"
FORMAT_VERSION = 1
#: written when the tables have a temperature axis (docs/tables.md "Operating axes")
FORMAT_VERSION_AXES = 2
SUPPORTED_VERSIONS = (1, 2)
#: operating axes of version 2, in array order: name -> (unit, FMU input selecting it or None)
OPERATING_AXES = {"torque_Nm": ("N*m", "pinion_torque"), "temperature_C": ("degC", "bulk_temperature")}
# the FMU input of a temperature axis (TEMPERATURE_INPUTS) is recorded in
# provenance["thermal"]["input"] (default bulk_temperature)

#: arrays every table set has, with their axes and units
ARRAY_FIELDS = {
    "torque_Nm": ("(NT,)", "N*m"),
    "k_N_per_m": ("(NT, P, n_phi)", "N/m"),
    "e_m": ("(NT, P, n_phi)", "m"),
    "backlash_half_m": ("(P, n_phi)", "m"),
}
#: optional arrays (derived or for reports and the traditional model)
OPTIONAL_ARRAY_FIELDS = {
    "e_comprehensive_m": ("(NT, n_phi)", "m"),
    "static_te_m": ("(NT, n_phi)", "m"),
}
SCALAR_FIELDS = {
    "phi_period_rad": "rad",
    "mesh_period_rad": "rad",
    "base_radius_pinion_m": "m",
    "base_radius_gear_m": "m",
    "inertia_pinion_kgm2": "kg*m^2",
    "inertia_gear_kgm2": "kg*m^2",
    "teeth_pinion": "1",
    "teeth_gear": "1",
    "contact_ratio": "1",
    "k_mean_N_per_m": "N/m",
}


class TableError(ValueError):
    """A table set is malformed, tampered with, or of an unsupported version."""


class TemperatureRangeError(TableError):
    """A temperature outside the tables' temperature axis (or not finite)."""


def temperature_bracket(axis_C, temperature_C: float, name: str = "bulk_temperature") -> tuple:
    """(ia, w, two) of docs/model.md "Temperature axis": ia is the largest index
    with axis[ia] <= T; at a node (axis[ia] == T, also the last one) one slice
    (two = False, w = 0.0), else slices ia, ia+1 with w = (T - axis[ia])/(axis[ia+1] - axis[ia]).
    No clamping: T outside [axis[0], axis[-1]] or non-finite raises
    :class:`TemperatureRangeError`."""
    ax = np.asarray(axis_C, dtype=float)
    T = float(temperature_C)
    if not np.isfinite(T):
        raise TemperatureRangeError(f"{name} = {T!r} degC: not finite")
    if ax.size == 1:
        if T != ax[0]:
            raise TemperatureRangeError(
                f"{name} = {T!r} degC outside the table range [{ax[0]!r}, {ax[0]!r}] degC")
        return 0, 0.0, False
    if T < ax[0] or T > ax[-1]:
        raise TemperatureRangeError(
            f"{name} = {T!r} degC outside the table range [{float(ax[0])!r}, {float(ax[-1])!r}] degC")
    ia = 0
    while ia < ax.size - 1 and ax[ia + 1] <= T:
        ia += 1
    if ax[ia] == T:
        return ia, 0.0, False
    return ia, (T - float(ax[ia])) / (float(ax[ia + 1]) - float(ax[ia])), True


@dataclass
class MeshTables:
    """Per-slot stiffness and meshing-error tables (SI units).

    Arrays are indexed ``[torque, slot, phi]``; the phi grid is
    ``phi_j = j * phi_period_rad / n_phi`` for j = 0..n_phi-1 and wraps.
    With a temperature axis (``temperature_C`` not None, degC, ascending)
    ``k_N_per_m`` and ``e_m`` are indexed ``[torque, temperature, slot, phi]``
    and ``e_comprehensive_m`` / ``static_te_m`` ``[torque, temperature, phi]``
    (operating axes first); :meth:`at_temperature` gives the single-temperature
    tables of docs/model.md "Temperature axis".  ``temperature_reference_C``:
    the standard temperature t0 of the geometry (degC; sets the FMU input's
    start value, :attr:`default_temperature_C`).

    ``engagement_in_rad``, ``engagement_out_rad`` (optional, both or neither): the exact
    meshing-in and meshing-out pinion angles of every tooth pair, measured from the start
    of its mesh (the pair that starts mesh n is in its contact zone for
    ``n*mesh_period_rad + in <= phi < n*mesh_period_rad + out``, in slot ``n % P``).
    With them the sub-cell lookup (docs/model.md "Contact-zone edges",
    :mod:`gearfmu.tables.zones`) puts the stiffness step exactly at these angles instead
    of a linear ramp over the table cell that holds it.  None: unknown (imported tables,
    files written before the field existed), the lookup is plain linear interpolation.
    """

    torque_Nm: np.ndarray
    k_N_per_m: np.ndarray
    e_m: np.ndarray
    backlash_half_m: np.ndarray
    phi_period_rad: float
    mesh_period_rad: float
    base_radius_pinion_m: float
    base_radius_gear_m: float
    inertia_pinion_kgm2: float
    inertia_gear_kgm2: float
    teeth_pinion: int
    teeth_gear: int
    contact_ratio: float
    k_mean_N_per_m: float
    e_comprehensive_m: Optional[np.ndarray] = None
    static_te_m: Optional[np.ndarray] = None
    provenance: Dict[str, object] = field(default_factory=dict)
    temperature_C: Optional[np.ndarray] = None
    temperature_reference_C: Optional[float] = None
    engagement_in_rad: Optional[float] = None
    engagement_out_rad: Optional[float] = None

    # ------------------------------------------------------------------ shape
    @property
    def n_torque(self) -> int:
        return int(self.k_N_per_m.shape[0])

    @property
    def slots(self) -> int:
        return int(self.k_N_per_m.shape[-2])

    @property
    def n_phi(self) -> int:
        return int(self.k_N_per_m.shape[-1])

    @property
    def has_temperature_axis(self) -> bool:
        return self.temperature_C is not None

    @property
    def n_temperature(self) -> int:
        """Points of the temperature axis (1 without one)."""
        return 1 if self.temperature_C is None else int(np.asarray(self.temperature_C).size)

    @property
    def temperature_range_C(self) -> Optional[tuple]:
        """(lowest, highest) temperature of the axis (degC), None without one."""
        if self.temperature_C is None:
            return None
        return float(self.temperature_C[0]), float(self.temperature_C[-1])

    @property
    def temperature_input(self) -> Optional[str]:
        """Name of the FMU input that selects the temperature axis (one of
        :data:`TEMPERATURE_INPUTS`' values, from ``provenance["thermal"]["input"]``,
        default ``bulk_temperature``); None without a temperature axis."""
        if self.temperature_C is None:
            return None
        th = self.provenance.get("thermal") if isinstance(self.provenance, dict) else None
        name = th.get("input") if isinstance(th, dict) else None
        return name if name in TEMPERATURE_INPUTS.values() else "bulk_temperature"

    @property
    def default_temperature_C(self) -> Optional[float]:
        """Start value of the FMU input ``bulk_temperature`` (degC): the standard
        temperature t0 clamped into the axis (the axis' first point when t0 is
        unknown); None without a temperature axis."""
        if self.temperature_C is None:
            return None
        lo, hi = self.temperature_range_C
        t0 = self.temperature_reference_C
        if t0 is None or not np.isfinite(t0):
            return lo
        return float(min(max(float(t0), lo), hi))

    def at_temperature(self, temperature_C: float) -> "MeshTables":
        """The single-temperature tables at a bulk temperature (degC), by the
        rule of docs/model.md "Temperature axis": with (ia, w, two) =
        :func:`temperature_bracket`, every table node is
        ``A[:, ia] + w*(A[:, ia + 1] - A[:, ia])`` (two slices) or ``A[:, ia]``
        (at a node: the stored slice itself, bit for bit).  Out of range or
        non-finite: :class:`TemperatureRangeError`.  Without a temperature axis
        the tables themselves are returned."""
        if self.temperature_C is None:
            return self
        ia, w, two = temperature_bracket(self.temperature_C, temperature_C, self.temperature_input)

        def blend(a):
            if a is None:
                return None
            if not two:
                return np.ascontiguousarray(a[:, ia])
            lo, hi = a[:, ia], a[:, ia + 1]
            return np.ascontiguousarray(lo + w * (hi - lo))

        return MeshTables(
            torque_Nm=self.torque_Nm.copy(), k_N_per_m=blend(self.k_N_per_m), e_m=blend(self.e_m),
            backlash_half_m=self.backlash_half_m.copy(),
            **{n: getattr(self, n) for n in SCALAR_FIELDS},
            e_comprehensive_m=blend(self.e_comprehensive_m), static_te_m=blend(self.static_te_m),
            provenance=dict(self.provenance, at_bulk_temperature_C=float(temperature_C)),
            engagement_in_rad=self.engagement_in_rad, engagement_out_rad=self.engagement_out_rad,
        )

    @property
    def dphi_rad(self) -> float:
        return self.phi_period_rad / self.n_phi

    @property
    def phi_rad(self) -> np.ndarray:
        return np.arange(self.n_phi) * self.dphi_rad

    @property
    def equivalent_mass_kg(self) -> float:
        """m_e = I1 I2 / (I1 Rb2^2 + I2 Rb1^2) (Xu et al. 2022, below eq 2)."""
        i1, i2 = self.inertia_pinion_kgm2, self.inertia_gear_kgm2
        r1, r2 = self.base_radius_pinion_m, self.base_radius_gear_m
        return i1 * i2 / (i1 * r2 ** 2 + i2 * r1 ** 2)

    def pair_damping_Ns_per_m(self, damping_ratio: float) -> float:
        """Damping of one tooth pair, c = 2 zeta sqrt(k_m m_e) (Xu et al. 2022 eq 7-9:
        every pair has the same constant damping, zeta = c / (2 m_e omega_n),
        omega_n = sqrt(k_m / m_e))."""
        return 2.0 * damping_ratio * np.sqrt(self.k_mean_N_per_m * self.equivalent_mass_kg)

    def k_total_N_per_m(self) -> np.ndarray:
        """Sum over slots: the TVMS of the geometric contact pattern, (NT, n_phi)
        (with a temperature axis (NT, NTemp, n_phi))."""
        return self.k_N_per_m.sum(axis=-2)

    # ------------------------------------------------------------- checking
    def validate(self) -> "MeshTables":
        """Check shapes, finiteness and ranges; raise :class:`TableError` naming the field."""
        for name in ARRAY_FIELDS:
            arr = getattr(self, name)
            if not isinstance(arr, np.ndarray):
                raise TableError(f"{name}: expected a numpy array, got {type(arr).__name__}")
            if not np.all(np.isfinite(arr)):
                raise TableError(f"{name}: contains NaN or infinite values")
        if self.temperature_C is not None:
            tax = self.temperature_C
            if not isinstance(tax, np.ndarray) or tax.ndim != 1 or tax.size < 1:
                raise TableError("temperature_C: expected a 1-D numpy array with at least one point")
            if not np.all(np.isfinite(tax)):
                raise TableError("temperature_C: contains NaN or infinite values")
            if tax.size > 1 and not np.all(np.diff(tax) > 0):
                raise TableError("temperature_C: must be strictly ascending")
            if self.temperature_reference_C is not None and not np.isfinite(self.temperature_reference_C):
                raise TableError(f"temperature_reference_C: must be finite, got {self.temperature_reference_C!r}")
            if self.k_N_per_m.ndim != 4:
                raise TableError(f"k_N_per_m: expected 4 axes (NT, NTemp, P, n_phi) with a temperature axis, "
                                 f"got shape {self.k_N_per_m.shape}")
            nt, ntemp, p, nphi = self.k_N_per_m.shape
            if ntemp != tax.size:
                raise TableError(f"k_N_per_m: temperature axis has {ntemp} points, temperature_C {tax.size}")
            op = (nt, ntemp)
        else:
            if self.k_N_per_m.ndim != 3:
                raise TableError(f"k_N_per_m: expected 3 axes (NT, P, n_phi), got shape {self.k_N_per_m.shape}")
            nt, p, nphi = self.k_N_per_m.shape
            op = (nt,)
        if self.e_m.shape != self.k_N_per_m.shape:
            raise TableError(f"e_m: shape {self.e_m.shape} differs from k_N_per_m {self.k_N_per_m.shape}")
        if self.torque_Nm.shape != (nt,):
            raise TableError(f"torque_Nm: shape {self.torque_Nm.shape}, expected ({nt},)")
        if nt > 1 and not np.all(np.diff(self.torque_Nm) > 0):
            raise TableError("torque_Nm: must be strictly ascending")
        if self.backlash_half_m.shape != (p, nphi):
            raise TableError(f"backlash_half_m: shape {self.backlash_half_m.shape}, expected ({p}, {nphi})")
        if np.any(self.k_N_per_m < 0):
            raise TableError("k_N_per_m: negative stiffness")
        if np.any(self.backlash_half_m < 0):
            raise TableError("backlash_half_m: negative backlash")
        if p < 1 or nphi < 4:
            raise TableError(f"k_N_per_m: need at least 1 slot and 4 angle points, got P={p}, n_phi={nphi}")
        for name, shape in (("e_comprehensive_m", op + (nphi,)), ("static_te_m", op + (nphi,))):
            arr = getattr(self, name)
            if arr is not None and (arr.shape != shape or not np.all(np.isfinite(arr))):
                raise TableError(f"{name}: expected finite array of shape {shape}, got {arr.shape}")
        for name in SCALAR_FIELDS:
            v = float(getattr(self, name))
            if not np.isfinite(v) or v <= 0:
                raise TableError(f"{name}: must be finite and > 0, got {v!r}")
        nmesh = self.phi_period_rad / self.mesh_period_rad
        if abs(nmesh - round(nmesh)) > 1e-9 * max(1.0, nmesh):
            raise TableError(f"phi_period_rad: must be a whole number of mesh periods, got {nmesh:.6g}")
        if (self.engagement_in_rad is None) != (self.engagement_out_rad is None):
            raise TableError("engagement_in_rad, engagement_out_rad: give both or neither")
        if self.engagement_in_rad is not None:
            check_engagement(self)
        return self

    # ------------------------------------------------------------ transforms
    def traditional(self) -> "MeshTables":
        """The traditional single-pair model of Xu et al. 2022 eq (12): one slot whose
        stiffness is the total TVMS and whose error is the comprehensive
        (envelope) meshing error."""
        if self.e_comprehensive_m is None:
            raise TableError("e_comprehensive_m: needed for the traditional model but missing")
        k = self.k_total_N_per_m()[..., None, :]
        e = self.e_comprehensive_m[..., None, :]
        b = self.backlash_half_m.max(axis=0)[None, :]
        return MeshTables(
            torque_Nm=self.torque_Nm.copy(), k_N_per_m=np.ascontiguousarray(k),
            e_m=np.ascontiguousarray(e), backlash_half_m=np.ascontiguousarray(b),
            **{n: getattr(self, n) for n in SCALAR_FIELDS},
            e_comprehensive_m=self.e_comprehensive_m.copy(),
            static_te_m=None if self.static_te_m is None else self.static_te_m.copy(),
            provenance=dict(self.provenance, model="traditional (seed 003 eq 12)"),
            temperature_C=None if self.temperature_C is None else self.temperature_C.copy(),
            temperature_reference_C=self.temperature_reference_C,
        )

    # ------------------------------------------------------------------ I/O
    def _arrays(self) -> Dict[str, np.ndarray]:
        out = {n: getattr(self, n) for n in ARRAY_FIELDS}
        if self.temperature_C is not None:
            out["temperature_C"] = self.temperature_C
        for n in OPTIONAL_ARRAY_FIELDS:
            if getattr(self, n) is not None:
                out[n] = getattr(self, n)
        return out

    def to_bytes(self) -> tuple[bytes, bytes]:
        """Return (tables.json, tables.bin) contents."""
        self.validate()
        buf = io.BytesIO()
        entries = {}
        for name, arr in self._arrays().items():
            a = np.ascontiguousarray(arr, dtype="<f8")
            raw = a.tobytes(order="C")
            entries[name] = {
                "dtype": "<f8", "shape": list(a.shape), "offset": buf.tell(),
                "nbytes": len(raw), "sha256": hashlib.sha256(raw).hexdigest(),
                "unit": {**ARRAY_FIELDS, **OPTIONAL_ARRAY_FIELDS,
                         "temperature_C": ("(NTemp,)", "degC")}[name][1],
            }
            buf.write(raw)
        binary = buf.getvalue()
        meta = {
            "format": FORMAT_NAME,
            "version": FORMAT_VERSION,
            "slots": self.slots,
            "n_phi": self.n_phi,
            "n_torque": self.n_torque,
            "scalars": {n: (int(getattr(self, n)) if n.startswith("teeth") else float(getattr(self, n)))
                        for n in SCALAR_FIELDS},
            "scalar_units": dict(SCALAR_FIELDS),
            "arrays": entries,
            "bin_sha256": hashlib.sha256(binary).hexdigest(),
            "provenance": self.provenance,
        }
        if self.engagement_in_rad is not None:  # optional key, older readers ignore it (docs/tables.md)
            meta["engagement"] = {"in_rad": float(self.engagement_in_rad), "out_rad": float(self.engagement_out_rad),
                                  "unit": "rad"}
        if self.temperature_C is not None:  # version 2: operating axes (docs/tables.md)
            meta["version"] = FORMAT_VERSION_AXES
            meta["n_temperature"] = self.n_temperature
            meta["axes"] = [
                {"name": "torque_Nm", "unit": "N*m", "size": self.n_torque, "input": "pinion_torque",
                 "out_of_range": "clamp"},
                {"name": "temperature_C", "unit": "degC", "size": self.n_temperature, "input": self.temperature_input,
                 "out_of_range": "reject", "reference_C": self.temperature_reference_C,
                 "start_C": self.default_temperature_C},
            ]
        return json.dumps(meta, indent=1, sort_keys=True).encode("utf-8"), binary

    @classmethod
    def from_bytes(cls, meta_bytes: bytes, binary: bytes, source: str = "tables") -> "MeshTables":
        """Tables from the contents of tables.json and tables.bin; TableError naming
        ``source``, the file and the reason for anything that does not read back (not JSON,
        another format or version, a checksum mismatch, missing or malformed entries)."""
        try:
            meta = json.loads(meta_bytes.decode("utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise TableError(f"{source}/tables.json: not valid JSON ({exc})") from None
        if not isinstance(meta, dict):
            raise TableError(f"{source}/tables.json: holds a JSON {type(meta).__name__}, not an object")
        try:
            return cls._from_meta(meta, binary, source)
        except TableError:
            raise
        except (KeyError, TypeError, AttributeError, IndexError, ValueError) as exc:
            what = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
            raise TableError(f"{source}/tables.json: malformed table description ({what})") from None

    @classmethod
    def _from_meta(cls, meta: dict, binary: bytes, source: str) -> "MeshTables":
        if meta.get("format") != FORMAT_NAME:
            raise TableError(f"{source}/tables.json: format is {meta.get('format')!r}, expected {FORMAT_NAME!r}")
        version = meta.get("version")
        if isinstance(version, bool) or version not in SUPPORTED_VERSIONS:
            raise TableError(f"{source}/tables.json: table format version {version!r} found; "
                             f"this gearfmu reads versions {list(SUPPORTED_VERSIONS)}")
        if hashlib.sha256(binary).hexdigest() != meta.get("bin_sha256"):
            raise TableError(f"{source}/tables.bin: checksum mismatch (file corrupted or tampered with)")
        arrays = {}
        for name, ent in meta["arrays"].items():
            raw = binary[ent["offset"]: ent["offset"] + ent["nbytes"]]
            if hashlib.sha256(raw).hexdigest() != ent["sha256"]:
                raise TableError(f"{source}/tables.bin: checksum mismatch in array {name!r}")
            arrays[name] = np.frombuffer(raw, dtype="<f8").reshape(ent["shape"]).astype(np.float64)
        for name in ARRAY_FIELDS:
            if name not in arrays:
                raise TableError(f"{source}/tables.json: required array {name!r} missing")
        extra = {}
        if version == 1:
            if "temperature_C" in arrays:
                raise TableError(f"{source}/tables.json: version 1 tables cannot carry a temperature_C array")
        else:
            axes = meta.get("axes")
            if not isinstance(axes, list) or not axes or not all(isinstance(a, dict) for a in axes):
                raise TableError(f"{source}/tables.json: version 2 needs an 'axes' list of operating axes")
            names = [a.get("name") for a in axes]
            for n in names:
                if n not in OPERATING_AXES:
                    raise TableError(f"{source}/tables.json: operating axis {n!r} unknown; this gearfmu "
                                     f"knows {list(OPERATING_AXES)}")
            if names not in (["torque_Nm"], ["torque_Nm", "temperature_C"]):
                raise TableError(f"{source}/tables.json: operating axes {names!r}; expected ['torque_Nm'] or "
                                 f"['torque_Nm', 'temperature_C'] in this order")
            for a in axes:
                if a["name"] not in arrays or list(arrays[a["name"]].shape) != [a.get("size")]:
                    raise TableError(f"{source}/tables.json: axis {a['name']!r} of size {a.get('size')!r} has "
                                     f"no array of that size in tables.bin")
            if "temperature_C" in names:
                extra["temperature_reference_C"] = axes[1].get("reference_C")
            elif "temperature_C" in arrays:
                raise TableError(f"{source}/tables.json: array 'temperature_C' without a temperature axis")
        scalars = meta["scalars"]
        kw = {n: scalars[n] for n in SCALAR_FIELDS}
        kw["teeth_pinion"] = int(kw["teeth_pinion"])
        kw["teeth_gear"] = int(kw["teeth_gear"])
        eng = meta.get("engagement")
        if eng is not None:
            try:
                extra["engagement_in_rad"] = float(eng["in_rad"])
                extra["engagement_out_rad"] = float(eng["out_rad"])
            except (TypeError, KeyError, ValueError):
                raise TableError(f"{source}/tables.json: 'engagement' needs numbers 'in_rad' and 'out_rad'") from None
        return cls(**arrays, **kw, **extra, provenance=meta.get("provenance", {})).validate()

    def to_gtab(self) -> bytes:
        """The bytes of a ``.gtab`` file: an uncompressed zip of tables.json + tables.bin."""
        meta, binary = self.to_bytes()
        buf = io.BytesIO()
        with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_STORED) as zf:
            zf.writestr("tables.json", meta)
            zf.writestr("tables.bin", binary)
        return buf.getvalue()

    @classmethod
    def from_gtab(cls, payload: bytes, source: str) -> "MeshTables":
        """The tables of ``.gtab`` bytes (:meth:`to_gtab`); ``source`` names them in errors."""
        try:
            with zipfile.ZipFile(io.BytesIO(payload)) as zf:
                return cls.from_bytes(zf.read("tables.json"), zf.read("tables.bin"), source)
        except (zipfile.BadZipFile, KeyError) as exc:
            raise TableError(f"{source}: not a gearfmu table file ({exc})") from None

    def save(self, path) -> Path:
        """Write a ``.gtab`` file (:meth:`to_gtab`)."""
        path = Path(path)
        payload = self.to_gtab()
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(path.suffix + ".part")
        tmp.write_bytes(payload)
        tmp.replace(path)  # never leave a half-written file under the final name
        return path

    def write_dir(self, directory) -> Path:
        """Write ``tables.json`` and ``tables.bin`` into ``directory`` (FMU resources)."""
        d = Path(directory)
        d.mkdir(parents=True, exist_ok=True)
        meta, binary = self.to_bytes()
        (d / "tables.bin").write_bytes(binary)
        (d / "tables.json").write_bytes(meta)
        return d


# ------------------------------------------------ contact-zone edges (docs/tables.md)
def _mesh_count(t: "MeshTables") -> int:
    return int(round(t.phi_period_rad / t.mesh_period_rad))


def zone_edges_nodes(t: "MeshTables") -> np.ndarray:
    """(P, Z, 2) meshing-in and meshing-out positions of every pair in every slot, in node
    units s = phi/dphi (s in [0, n_phi), the grid's node j at s = j); Z = mesh periods / P."""
    n_mesh = _mesh_count(t)
    p, n = t.slots, t.n_phi
    ppm = n / n_mesh                       # nodes per mesh period (an integer for every table built here)
    inv_dphi = n / t.phi_period_rad        # the kernels' N/Phi
    a_in = float(t.engagement_in_rad) * inv_dphi
    a_out = float(t.engagement_out_rad) * inv_dphi
    z = n_mesh // p
    out = np.empty((p, z, 2))
    for m in range(n_mesh):
        start = m * ppm
        out[m % p, m // p] = (np.fmod(start + a_in, n) % n, np.fmod(start + a_out, n) % n)
    return out


def check_engagement(t: "MeshTables") -> None:
    """TableError naming the field unless the engagement angles are finite, the zone is
    shorter than P mesh periods (pairs of one slot do not overlap) and every table node
    strictly outside the zones of its slot has k = 0 in every operating row."""
    a_in, a_out = t.engagement_in_rad, t.engagement_out_rad
    for name, v in (("engagement_in_rad", a_in), ("engagement_out_rad", a_out)):
        if isinstance(v, bool) or not isinstance(v, (int, float, np.floating)) or not math.isfinite(v):
            raise TableError(f"{name}: must be a finite number (rad), got {v!r}")
    span = float(a_out) - float(a_in)
    if not span > 0.0:
        raise TableError(f"engagement_out_rad: must exceed engagement_in_rad ({a_in!r}), got {a_out!r}")
    if span > t.slots * t.mesh_period_rad * (1.0 + 1e-12):
        raise TableError(f"engagement_out_rad: the zone ({span:.6g} rad) is longer than P = {t.slots} mesh "
                         f"periods ({t.slots * t.mesh_period_rad:.6g} rad): pairs of one slot would overlap")
    inside = _inside_closed(t)
    k = t.k_N_per_m.reshape(-1, t.slots, t.n_phi)
    bad = np.any(k != 0.0, axis=0) & ~inside
    if np.any(bad):
        j, i = np.argwhere(bad)[0]
        raise TableError(f"k_N_per_m: slot {j} has k != 0 at node {i} (phi = {i * t.dphi_rad:.9g} rad), outside "
                         f"its contact zone [engagement_in_rad, engagement_out_rad] = [{a_in!r}, {a_out!r}] rad")


def _inside_closed(t: "MeshTables") -> np.ndarray:
    """(P, n_phi) bool: node j lies in a closed zone [in, out] of its slot (periodic)."""
    n = t.n_phi
    nodes = np.arange(n, dtype=float)
    inside = np.zeros((t.slots, n), dtype=bool)
    for j, zones in enumerate(zone_edges_nodes(t)):
        for s_in, s_out in zones:
            if s_in <= s_out:
                inside[j] |= (nodes >= s_in) & (nodes <= s_out)
            else:  # the zone wraps past the period end
                inside[j] |= (nodes >= s_in) | (nodes <= s_out)
    return inside


def stack_temperatures(slices, temperature_C, temperature_reference_C: Optional[float] = None) -> MeshTables:
    """Tables with a temperature axis from single-temperature tables, one per
    temperature (degC, strictly ascending).  The slices must share the torque
    axis, backlash and scalars (taken from the first); k, e and the optional
    arrays are stacked on axis 1 (docs/tables.md "Operating axes")."""
    slices = list(slices)
    ax = np.ascontiguousarray(np.atleast_1d(np.asarray(temperature_C, dtype=float)))
    if ax.ndim != 1 or ax.size != len(slices) or ax.size < 1:
        raise TableError(f"temperature_C: need one temperature per slice ({len(slices)}), got {ax.shape}")
    first = slices[0]
    for i, t in enumerate(slices):
        if not isinstance(t, MeshTables) or t.has_temperature_axis:
            raise TableError(f"slices[{i}]: expected single-temperature MeshTables")
        if t.k_N_per_m.shape != first.k_N_per_m.shape or not np.array_equal(t.torque_Nm, first.torque_Nm):
            raise TableError(f"slices[{i}]: shape or torque axis differs from slices[0]")
        if not np.array_equal(t.backlash_half_m, first.backlash_half_m):
            raise TableError(f"slices[{i}]: backlash differs from slices[0] (backlash has no temperature axis)")

    def stack(name):
        arrs = [getattr(t, name) for t in slices]
        if any(a is None for a in arrs):
            return None
        return np.ascontiguousarray(np.stack(arrs, axis=1))

    return MeshTables(
        torque_Nm=first.torque_Nm.copy(), k_N_per_m=stack("k_N_per_m"), e_m=stack("e_m"),
        backlash_half_m=first.backlash_half_m.copy(), **{n: getattr(first, n) for n in SCALAR_FIELDS},
        e_comprehensive_m=stack("e_comprehensive_m"), static_te_m=stack("static_te_m"),
        provenance=dict(first.provenance), temperature_C=ax,
        temperature_reference_C=None if temperature_reference_C is None else float(temperature_reference_C),
        engagement_in_rad=first.engagement_in_rad, engagement_out_rad=first.engagement_out_rad,
    ).validate()


def load_tables(path) -> MeshTables:
    """Read a ``.gtab`` file or a directory holding tables.json + tables.bin."""
    p = Path(path)
    if p.is_dir():
        try:
            return MeshTables.from_bytes((p / "tables.json").read_bytes(), (p / "tables.bin").read_bytes(), str(p))
        except FileNotFoundError as exc:
            raise TableError(f"{p}: missing {Path(exc.filename).name}") from None
    try:
        arc = read_archive(p, "table file (.gtab)", keep=("tables.json", "tables.bin"))
    except ArchiveError as exc:
        raise TableError(str(exc)) from None
    kind = archive_kind(arc.names)
    if kind in ("an FMU", "an SSP package"):
        raise TableError(f"{p}: {kind}, not a table file (.gtab or .csv)")
    missing = [n for n in ("tables.json", "tables.bin") if n not in arc.data]
    if missing:
        raise TableError(f"{p}: not a gearfmu table file (.gtab): the zip archive lacks {' and '.join(missing)}")
    return MeshTables.from_bytes(arc.data["tables.json"], arc.data["tables.bin"], str(p))
