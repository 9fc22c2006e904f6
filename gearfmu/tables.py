"""Tooth-pair tables: the interface between the physics and the dynamics.

A :class:`MeshTables` holds, per tooth-pair *slot*, the mesh stiffness k and
the meshing error e against the pinion angle (and, where they depend on load,
against pinion torque), plus the few scalars that the dynamic model needs.
Both the native solver (:mod:`gearfmu.native`) and the FMU's C kernel read
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

Format (version 1, documented in docs/tables.md)
------------------------------------------------
A ``.gtab`` file is an uncompressed zip archive holding ``tables.json``
(format name, version, axes, scalars, provenance, one entry per array with
dtype, shape, byte offset and SHA-256) and ``tables.bin`` (the arrays as
little-endian float64, C order, concatenated).  The same two files sit
unzipped in an FMU's ``resources/``.  No pickle anywhere.
"""
from __future__ import annotations

import hashlib
import io
import json
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, Optional

import numpy as np

FORMAT_NAME = "gearfmu-tables"
FORMAT_VERSION = 1
SUPPORTED_VERSIONS = (1,)

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


@dataclass
class MeshTables:
    """Per-slot stiffness and meshing-error tables (SI units).

    Arrays are indexed ``[torque, slot, phi]``; the phi grid is
    ``phi_j = j * phi_period_rad / n_phi`` for j = 0..n_phi-1 and wraps.
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

    # ------------------------------------------------------------------ shape
    @property
    def n_torque(self) -> int:
        return int(self.k_N_per_m.shape[0])

    @property
    def slots(self) -> int:
        return int(self.k_N_per_m.shape[1])

    @property
    def n_phi(self) -> int:
        return int(self.k_N_per_m.shape[2])

    @property
    def dphi_rad(self) -> float:
        return self.phi_period_rad / self.n_phi

    @property
    def phi_rad(self) -> np.ndarray:
        return np.arange(self.n_phi) * self.dphi_rad

    @property
    def equivalent_mass_kg(self) -> float:
        """m_e = I1 I2 / (I1 Rb2^2 + I2 Rb1^2) (seed 003, below eq 2)."""
        i1, i2 = self.inertia_pinion_kgm2, self.inertia_gear_kgm2
        r1, r2 = self.base_radius_pinion_m, self.base_radius_gear_m
        return i1 * i2 / (i1 * r2 ** 2 + i2 * r1 ** 2)

    def pair_damping_Ns_per_m(self, damping_ratio: float) -> float:
        """Damping of one tooth pair, c = 2 zeta sqrt(k_m m_e) (seed 003 eq 7-9:
        every pair has the same constant damping, zeta = c / (2 m_e omega_n),
        omega_n = sqrt(k_m / m_e))."""
        return 2.0 * damping_ratio * np.sqrt(self.k_mean_N_per_m * self.equivalent_mass_kg)

    def k_total_N_per_m(self) -> np.ndarray:
        """Sum over slots: the TVMS of the geometric contact pattern, (NT, n_phi)."""
        return self.k_N_per_m.sum(axis=1)

    # ------------------------------------------------------------- checking
    def validate(self) -> "MeshTables":
        """Check shapes, finiteness and ranges; raise :class:`TableError` naming the field."""
        for name in ARRAY_FIELDS:
            arr = getattr(self, name)
            if not isinstance(arr, np.ndarray):
                raise TableError(f"{name}: expected a numpy array, got {type(arr).__name__}")
            if not np.all(np.isfinite(arr)):
                raise TableError(f"{name}: contains NaN or infinite values")
        if self.k_N_per_m.ndim != 3:
            raise TableError(f"k_N_per_m: expected 3 axes (NT, P, n_phi), got shape {self.k_N_per_m.shape}")
        nt, p, nphi = self.k_N_per_m.shape
        if self.e_m.shape != (nt, p, nphi):
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
        for name, shape in (("e_comprehensive_m", (nt, nphi)), ("static_te_m", (nt, nphi))):
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
        return self

    # ------------------------------------------------------------ transforms
    def traditional(self) -> "MeshTables":
        """The traditional single-pair model of seed 003 eq (12): one slot whose
        stiffness is the total TVMS and whose error is the comprehensive
        (envelope) meshing error."""
        if self.e_comprehensive_m is None:
            raise TableError("e_comprehensive_m: needed for the traditional model but missing")
        k = self.k_total_N_per_m()[:, None, :]
        e = self.e_comprehensive_m[:, None, :]
        b = self.backlash_half_m.max(axis=0)[None, :]
        return MeshTables(
            torque_Nm=self.torque_Nm.copy(), k_N_per_m=np.ascontiguousarray(k),
            e_m=np.ascontiguousarray(e), backlash_half_m=np.ascontiguousarray(b),
            **{n: getattr(self, n) for n in SCALAR_FIELDS},
            e_comprehensive_m=self.e_comprehensive_m.copy(),
            static_te_m=None if self.static_te_m is None else self.static_te_m.copy(),
            provenance=dict(self.provenance, model="traditional (seed 003 eq 12)"),
        )

    # ------------------------------------------------------------------ I/O
    def _arrays(self) -> Dict[str, np.ndarray]:
        out = {n: getattr(self, n) for n in ARRAY_FIELDS}
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
                "unit": {**ARRAY_FIELDS, **OPTIONAL_ARRAY_FIELDS}[name][1],
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
        return json.dumps(meta, indent=1, sort_keys=True).encode("utf-8"), binary

    @classmethod
    def from_bytes(cls, meta_bytes: bytes, binary: bytes, source: str = "tables") -> "MeshTables":
        try:
            meta = json.loads(meta_bytes.decode("utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise TableError(f"{source}/tables.json: not valid JSON ({exc})") from None
        if meta.get("format") != FORMAT_NAME:
            raise TableError(f"{source}/tables.json: format is {meta.get('format')!r}, expected {FORMAT_NAME!r}")
        version = meta.get("version")
        if version not in SUPPORTED_VERSIONS:
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
        scalars = meta["scalars"]
        kw = {n: scalars[n] for n in SCALAR_FIELDS}
        kw["teeth_pinion"] = int(kw["teeth_pinion"])
        kw["teeth_gear"] = int(kw["teeth_gear"])
        return cls(**arrays, **kw, provenance=meta.get("provenance", {})).validate()

    def save(self, path) -> Path:
        """Write a ``.gtab`` file (zip of tables.json + tables.bin)."""
        path = Path(path)
        meta, binary = self.to_bytes()
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(path.suffix + ".part")
        with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_STORED) as zf:
            zf.writestr("tables.json", meta)
            zf.writestr("tables.bin", binary)
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


def load_tables(path) -> MeshTables:
    """Read a ``.gtab`` file or a directory holding tables.json + tables.bin."""
    p = Path(path)
    if p.is_dir():
        try:
            return MeshTables.from_bytes((p / "tables.json").read_bytes(), (p / "tables.bin").read_bytes(), str(p))
        except FileNotFoundError as exc:
            raise TableError(f"{p}: missing {Path(exc.filename).name}") from None
    try:
        with zipfile.ZipFile(p) as zf:
            return MeshTables.from_bytes(zf.read("tables.json"), zf.read("tables.bin"), str(p))
    except zipfile.BadZipFile:
        raise TableError(f"{p}: not a gearfmu table file (.gtab zip archive)") from None
    except KeyError as exc:
        raise TableError(f"{p}: archive lacks {exc.args[0]}") from None
