"""Tooth-pair tables from CSV files (TVMS and meshing error from any tool), and back.

Two CSV forms (documented in docs/tables.md, section "CSV import"):

* **slots form** -- one row per pinion angle (and torque), one column per
  slot: ``pinion_angle_deg`` or ``pinion_angle_rad``; ``k_slot1_N_per_m`` ..
  ``k_slotP_N_per_m``; optional ``e_slot1_m`` .. (or ``e_slot1_um``), optional
  ``b_slot1_m`` .. (half backlash per slot), optional ``torque_Nm``, optional
  ``e_comprehensive_m``, ``static_te_m``; ``k_total_N_per_m`` (written by
  ``gearfmu tables``) is checked against the sum of the slots and dropped.
  The angles form the uniform grid ``phi_i = i*Phi/n_phi`` of docs/tables.md
  starting at 0; a closing row at ``Phi`` equal to the first row may be given.
* **single-pair form** -- one tooth pair over its engagement, as an FE or
  LTCA tool gives it: ``pinion_angle_deg``/``_rad`` from the start of
  contact (0) to its end, ``k_pair_N_per_m``, optional ``e_pair_m`` (or
  ``e_pair_um``), ``b_pair_m``, ``torque_Nm``.  The pair is repeated every
  mesh period and expanded into ``P = ceil(contact ratio)`` slots with the slot
  rule of docs/tables.md (pair n in slot n % P), linear interpolation onto a
  grid of ``points_per_mesh`` points per mesh period.

The scalars (teeth, base radii, inertias, half backlash, optional period,
contact ratio, mean stiffness) come from a small TOML sidecar and/or keyword
arguments (keywords win).  Every problem raises :class:`TableImportError`
(a ValueError) naming the file, the column or the row.

SI units everywhere except the ``_deg`` / ``_um`` column variants, converted on read.
"""
from __future__ import annotations

import csv
import math
from pathlib import Path
import numpy as np

from ..common.user_files import read_text
from .mesh_tables import MeshTables, TableError, load_tables
from .synthetic import tables_from_arrays

try:  # Python 3.11+
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - 3.10
    import tomli as tomllib

__all__ = ["TableImportError", "META_KEYS", "read_meta", "load_tables_csv", "load_tables_file",
           "tables_to_csv", "sidecar_path"]


class TableImportError(TableError):
    """A CSV table or its TOML sidecar is malformed; the message names file, column or row."""


#: sidecar keys -> (type, unit/meaning)
META_KEYS = {
    "teeth_pinion": (int, "1, required"),
    "teeth_gear": (int, "1, required"),
    "base_radius_pinion_m": (float, "m, required"),
    "base_radius_gear_m": (float, "m, required"),
    "inertia_pinion_kgm2": (float, "kg*m^2, required"),
    "inertia_gear_kgm2": (float, "kg*m^2, required"),
    "backlash_half_m": (float, "m, half backlash b when the CSV has no b columns (default 0)"),
    "phi_period_rad": (float, "rad, table period (default: from the angle column)"),
    "mesh_period_rad": (float, "rad, default 2*pi/teeth_pinion"),
    "contact_ratio": (float, "1, default: slots form mean number of slots with k > 0; "
                             "single-pair form engagement span / mesh period"),
    "k_mean_N_per_m": (float, "N/m, default mean total stiffness over the grid"),
    "slots": (int, "single-pair form: number of slots P (default ceil(contact ratio))"),
    "points_per_mesh": (int, "single-pair form: grid points per mesh period (default 64)"),
    "form": (str, '"slots" or "single_pair" (default: from the columns)'),
    "engagement_in_rad": (float, "rad, meshing-in angle of every pair from the start of its mesh (with "
                                 "engagement_out_rad; single-pair form default 0; slots form default none)"),
    "engagement_out_rad": (float, "rad, meshing-out angle (single-pair form default: the engagement span)"),
    "name": (str, "free text, kept in the provenance"),
}
REQUIRED = ("teeth_pinion", "teeth_gear", "base_radius_pinion_m", "base_radius_gear_m",
            "inertia_pinion_kgm2", "inertia_gear_kgm2")


def sidecar_path(csv_path) -> Path:
    """The sidecar that belongs to a CSV by name: ``T.csv`` -> ``T.meta.toml`` (what
    :func:`tables_to_csv` and ``gearfmu tables`` write, and ``build --tables`` looks for)."""
    p = Path(csv_path)
    return p.with_name(p.stem + ".meta.toml")


def read_meta(path) -> dict:
    """Read a TOML sidecar (flat keys of :data:`META_KEYS`; a ``[gear]`` or
    ``[tables]`` table is flattened too)."""
    p = Path(path)
    if not p.exists():
        raise TableImportError(f"{p}: file not found")
    try:
        data = tomllib.loads(read_text(p, "a TOML sidecar", TableImportError))
    except tomllib.TOMLDecodeError as exc:
        raise TableImportError(f"{p}: not valid TOML ({exc})") from None
    flat = {}
    for k, v in data.items():
        if isinstance(v, dict):
            flat.update(v)
        else:
            flat[k] = v
    for k in flat:
        if k not in META_KEYS:
            raise TableImportError(f"{p}: unknown key {k!r}; known keys: {', '.join(META_KEYS)}")
    return flat


def _meta_value(meta, key, src):
    typ = META_KEYS[key][0]
    v = meta[key]
    if typ is str:
        if not isinstance(v, str):
            raise TableImportError(f"{src}: {key} must be a string, got {v!r}")
        return v
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise TableImportError(f"{src}: {key} must be a number, got {v!r}")
    if typ is int:
        if int(v) != v or v < 1:
            raise TableImportError(f"{src}: {key} must be a positive integer, got {v!r}")
        return int(v)
    v = float(v)
    if key.startswith("engagement_"):
        if not math.isfinite(v):
            raise TableImportError(f"{src}: {key} must be finite, got {v!r}")
        return v
    if not math.isfinite(v) or v < 0 or (v == 0 and key != "backlash_half_m"):
        raise TableImportError(f"{src}: {key} must be finite and > 0 (>= 0 for backlash), got {v!r}")
    return v


def _read_csv(path):
    """(header list, data (n, m) float array, file line number of each row)."""
    p = Path(path)
    try:
        text = read_text(p, "a CSV table", TableImportError)
    except FileNotFoundError:
        raise TableImportError(f"{p}: file not found") from None
    header, rows, lines = None, [], []
    for lineno, rec in enumerate(csv.reader(text.splitlines()), start=1):
        if not rec or (rec[0].lstrip().startswith("#")) or all(not c.strip() for c in rec):
            continue
        if header is None:
            header = [c.strip() for c in rec]
            if len(set(header)) != len(header):
                dup = [c for c in header if header.count(c) > 1][0]
                raise TableImportError(f"{p}: column {dup!r} appears twice in the header (line {lineno})")
            continue
        if len(rec) != len(header):
            raise TableImportError(f"{p}: row at line {lineno} has {len(rec)} fields, the header has {len(header)}")
        vals = []
        for name, cell in zip(header, rec):
            try:
                v = float(cell)
            except ValueError:
                raise TableImportError(f"{p}: column {name!r}, line {lineno}: not a number: {cell.strip()!r}") from None
            if not math.isfinite(v):
                raise TableImportError(f"{p}: column {name!r}, line {lineno}: not finite: {cell.strip()!r}")
            vals.append(v)
        rows.append(vals)
        lines.append(lineno)
    if header is None or not rows:
        raise TableImportError(f"{p}: no header and data rows found")
    return header, np.array(rows, dtype=float), lines


def _angle_column(header, data, src):
    has_deg, has_rad = "pinion_angle_deg" in header, "pinion_angle_rad" in header
    if has_deg == has_rad:
        raise TableImportError(f"{src}: need exactly one angle column, pinion_angle_deg or pinion_angle_rad")
    if has_rad:
        return data[:, header.index("pinion_angle_rad")], "pinion_angle_rad"
    return np.radians(data[:, header.index("pinion_angle_deg")]), "pinion_angle_deg"


def _slot_columns(header, prefix, suffixes, src, required=False):
    """Columns prefix1.., e.g. k_slot1_N_per_m; returns (list of (index, factor)) in slot order."""
    out = []
    j = 1
    while True:
        found = [(header.index(f"{prefix}{j}{s}"), f) for s, f in suffixes if f"{prefix}{j}{s}" in header]
        if len(found) > 1:
            raise TableImportError(f"{src}: slot {j} of {prefix!r} is given in more than one unit")
        if not found:
            break
        out.append(found[0])
        j += 1
    if required and not out:
        names = " or ".join(f"{prefix}1{s}" for s, _ in suffixes)
        raise TableImportError(f"{src}: missing column {names}")
    return out


def _collect_meta(meta_path, kwargs):
    meta = {}
    src = "keyword arguments"
    if meta_path is not None:
        meta.update(read_meta(meta_path))
        src = str(meta_path)
    for k, v in kwargs.items():
        if k not in META_KEYS:
            raise TableImportError(f"{k}: unknown keyword; known: {', '.join(META_KEYS)}")
        if v is not None:
            meta[k] = v
    clean = {k: _meta_value(meta, k, src) for k in meta}
    for k in REQUIRED:
        if k not in clean:
            raise TableImportError(f"{src}: {k} missing ({META_KEYS[k][1]})")
    return clean, src


def load_tables_csv(csv_path, meta_path=None, **meta_kwargs) -> MeshTables:
    """Read tables from a CSV file (slots or single-pair form) and its TOML sidecar.

    ``meta_kwargs`` are the sidecar keys (:data:`META_KEYS`), overriding the file.
    Returns validated :class:`MeshTables`.
    """
    src = str(csv_path)
    meta, msrc = _collect_meta(meta_path, meta_kwargs)
    header, data, lines = _read_csv(csv_path)
    form = meta.get("form") or ("single_pair" if "k_pair_N_per_m" in header else "slots")
    if form not in ("slots", "single_pair"):
        raise TableImportError(f"{msrc}: form must be 'slots' or 'single_pair', got {form!r}")
    z1 = meta["teeth_pinion"]
    mp = meta.get("mesh_period_rad", 2.0 * math.pi / z1)
    prov = {"source": "gearfmu.tables.table_import", "csv": Path(csv_path).name, "form": form,
            "meta": {k: v for k, v in meta.items()}}
    if form == "slots":
        return _load_slots(header, data, lines, src, meta, mp, prov)
    return _load_single_pair(header, data, lines, src, meta, mp, prov)


def _torque_groups(header, data, lines, src):
    """Row indices per torque value (ascending), or one group when there is no torque column."""
    if "torque_Nm" not in header:
        return np.zeros(1), [np.arange(len(data))]
    tq = data[:, header.index("torque_Nm")]
    values = np.unique(tq)
    groups = [np.nonzero(tq == v)[0] for v in values]
    return values, groups


def _load_slots(header, data, lines, src, meta, mp, prov):
    ang, ang_name = _angle_column(header, data, src)
    kcols = _slot_columns(header, "k_slot", [("_N_per_m", 1.0)], src, required=True)
    P = len(kcols)
    ecols = _slot_columns(header, "e_slot", [("_m", 1.0), ("_um", 1e-6)], src)
    bcols = _slot_columns(header, "b_slot", [("_m", 1.0), ("_um", 1e-6)], src)
    for name, cols in (("e_slot", ecols), ("b_slot", bcols)):
        if cols and len(cols) != P:
            raise TableImportError(f"{src}: {P} k_slot columns but {len(cols)} {name} columns")
    used = {ang_name, "torque_Nm", "k_total_N_per_m", "e_comprehensive_m", "static_te_m"}
    used |= {header[i] for i, _ in kcols + ecols + bcols}
    for c in header:
        if c not in used:
            raise TableImportError(f"{src}: unknown column {c!r} (docs/tables.md, 'CSV import')")
    tq, groups = _torque_groups(header, data, lines, src)
    n = len(groups[0])
    for g, v in zip(groups, tq):
        if len(g) != n:
            raise TableImportError(f"{src}: torque_Nm = {v:g} has {len(g)} rows, torque {tq[0]:g} has {n}")
    a0 = ang[groups[0]]
    if n < 5:
        raise TableImportError(f"{src}: {ang_name}: need at least 5 angle rows, got {n}")
    order_ok = np.all(np.diff(a0) > 0)
    if not order_ok:
        i = int(np.argmin(np.diff(a0) > 0)) + 1
        raise TableImportError(f"{src}: {ang_name}: angles must increase; line {lines[groups[0][i]]}")
    if abs(a0[0]) > 1e-9 * max(1.0, abs(a0[1])):
        raise TableImportError(f"{src}: {ang_name}: the first angle must be 0 (point A, start of "
                               f"active contact), got {a0[0]!r} at line {lines[groups[0][0]]}")
    # uniform grid; the period from the sidecar or the angle column
    if "phi_period_rad" in meta:
        period = meta["phi_period_rad"]
    else:
        step = (a0[-1] - a0[0]) / (n - 1)
        cand = [n * step, (n - 1) * step]  # without / with a closing row at Phi
        whole = [c for c in cand if abs(c / mp - round(c / mp)) < 1e-6 * max(1.0, c / mp) and round(c / mp) >= 1]
        if not whole:
            raise TableImportError(f"{src}: {ang_name}: the rows span neither {cand[0] / mp:.6g} nor "
                                   f"{cand[1] / mp:.6g} mesh periods; give phi_period_rad in the sidecar")
        period = round(whole[0] / mp) * mp
    closing = abs(a0[-1] - period) < 1e-6 * period / n
    nphi = n - 1 if closing else n
    dphi = period / nphi
    dev = np.abs(a0[:nphi] - np.arange(nphi) * dphi)
    if np.any(dev > 1e-6 * dphi):
        i = int(np.argmax(dev > 1e-6 * dphi))
        raise TableImportError(
            f"{src}: {ang_name}: the grid must be uniform, phi_i = i*{period:.9g}/{nphi} rad; line "
            f"{lines[groups[0][i]]} is off by {dev[i]:.3g} rad (resample the data or give phi_period_rad)")
    for g, v in zip(groups[1:], tq[1:]):
        if np.any(np.abs(ang[g] - a0) > 1e-9 * period):
            raise TableImportError(f"{src}: torque_Nm = {v:g}: its angles differ from those of torque {tq[0]:g}")

    def grab(cols, default):
        out = np.empty((len(tq), P, nphi))
        for it, g in enumerate(groups):
            rows = data[g]
            for j in range(P):
                if cols:
                    idx, fac = cols[j]
                    col = rows[:, idx] * fac
                    if closing and abs(col[-1] - col[0]) > 1e-9 * max(np.max(np.abs(col)), 1e-300):
                        raise TableImportError(
                            f"{src}: column {header[idx]!r}: the closing row at phi = period (line "
                            f"{lines[g[-1]]}) differs from the first row; the tables are periodic")
                    out[it, j] = col[:nphi]
                else:
                    out[it, j] = default
        return out

    k = grab(kcols, 0.0)
    if np.any(k < 0):
        it, j, i = np.argwhere(k < 0)[0]
        raise TableImportError(f"{src}: column {header[kcols[j][0]]!r}, line {lines[groups[it][i]]}: negative stiffness")
    e = grab(ecols, 0.0)
    b = grab(bcols, meta.get("backlash_half_m", 0.0))
    if bcols and len(tq) > 1 and np.any(np.abs(b - b[0]) > 0):
        raise TableImportError(f"{src}: b_slot columns must not depend on torque_Nm (docs/tables.md)")
    if np.any(b < 0):
        raise TableImportError(f"{src}: b_slot columns: negative half backlash")
    b = b[0]
    if "k_total_N_per_m" in header:
        kt = np.stack([data[g][:nphi, header.index("k_total_N_per_m")] for g in groups])
        if np.any(np.abs(kt - k.sum(axis=1)) > 1e-9 * max(float(np.max(np.abs(kt))), 1.0)):
            raise TableImportError(f"{src}: column 'k_total_N_per_m' is not the sum of the k_slot columns")
    opt = {}
    for name in ("e_comprehensive_m", "static_te_m"):
        if name in header:
            opt[name] = np.stack([data[g][:nphi, header.index(name)] for g in groups])
    return _make(k, e, b, tq, period, mp, meta, prov, **opt)


def _make(k, e, b, tq, period, mp, meta, prov, **opt):
    return tables_from_arrays(
        phi_period_rad=period, mesh_period_rad=mp, k_N_per_m=k, e_m=e, backlash_half_m=b,
        base_radius_pinion_m=meta["base_radius_pinion_m"], base_radius_gear_m=meta["base_radius_gear_m"],
        inertia_pinion_kgm2=meta["inertia_pinion_kgm2"], inertia_gear_kgm2=meta["inertia_gear_kgm2"],
        teeth_pinion=meta["teeth_pinion"], teeth_gear=meta["teeth_gear"],
        torque_Nm=tq, contact_ratio=meta.get("contact_ratio"),
        k_mean_N_per_m=meta.get("k_mean_N_per_m"), provenance=prov,
        engagement_in_rad=meta.get("engagement_in_rad"), engagement_out_rad=meta.get("engagement_out_rad"), **opt)


def _load_single_pair(header, data, lines, src, meta, mp, prov):
    ang, ang_name = _angle_column(header, data, src)
    if "k_pair_N_per_m" not in header:
        raise TableImportError(f"{src}: missing column k_pair_N_per_m (single-pair form)")
    known = {ang_name, "torque_Nm", "k_pair_N_per_m", "e_pair_m", "e_pair_um", "b_pair_m"}
    for c in header:
        if c not in known:
            raise TableImportError(f"{src}: unknown column {c!r} in the single-pair form (docs/tables.md)")
    if "e_pair_m" in header and "e_pair_um" in header:
        raise TableImportError(f"{src}: give e_pair_m or e_pair_um, not both")
    tq, groups = _torque_groups(header, data, lines, src)
    spans = []
    for g, v in zip(groups, tq):
        a = ang[g]
        if len(a) < 2:
            raise TableImportError(f"{src}: {ang_name}: need at least 2 rows per torque")
        if abs(a[0]) > 1e-12:
            raise TableImportError(f"{src}: {ang_name}: must start at 0 (start of the pair's contact); "
                                   f"line {lines[g[0]]} has {a[0]!r}")
        bad = np.nonzero(np.diff(a) <= 0)[0]
        if len(bad):
            raise TableImportError(f"{src}: {ang_name}: angles must increase; line {lines[g[bad[0] + 1]]}")
        spans.append(a[-1])
    span = max(spans)
    if any(abs(s - span) > 1e-9 * span for s in spans):
        raise TableImportError(f"{src}: {ang_name}: every torque must cover the same engagement span")
    eps_span = span / mp
    eps = meta.get("contact_ratio", eps_span)
    if abs(eps - eps_span) > 0.01 * eps:
        raise TableImportError(f"{src}: contact_ratio {eps:g} of the sidecar differs by more than 1 % from "
                               f"the CSV's engagement span {eps_span:.6g} mesh periods")
    if eps < 1.0:
        raise TableImportError(f"{src}: the engagement spans {eps:.4g} < 1 mesh period (contact ratio < 1)")
    need = int(math.ceil(eps_span - 1e-9))
    P = meta.get("slots", need)
    if P < need:
        raise TableImportError(f"slots: {P} is fewer than the {need} pairs the engagement span needs")
    npm = meta.get("points_per_mesh", 64)
    if npm < 4:
        raise TableImportError(f"points_per_mesh: must be >= 4, got {npm}")
    nphi = P * npm
    period = P * mp
    phi = np.arange(nphi) * (period / nphi)
    k = np.zeros((len(tq), P, nphi))
    e = np.zeros_like(k)
    b = np.full((P, nphi), float(meta.get("backlash_half_m", 0.0)))
    efac = 1e-6 if "e_pair_um" in header else 1.0
    ecol = "e_pair_um" if "e_pair_um" in header else ("e_pair_m" if "e_pair_m" in header else None)
    kneg = np.nonzero(data[:, header.index("k_pair_N_per_m")] < 0)[0]
    if len(kneg):
        raise TableImportError(f"{src}: column 'k_pair_N_per_m', line {lines[kneg[0]]}: negative stiffness")
    tol = 1e-9 * span
    for j in range(P):  # pair n = j starts at j*T; one pair per slot per period P*T
        local = np.mod(phi - j * mp, period)
        local = np.where(local > period - tol, local - period, local)  # a node just below the start is 0
        on = (local >= -tol) & (local <= span + tol)
        u = np.clip(local, 0.0, span)
        for it, g in enumerate(groups):
            a = ang[g]
            k[it, j] = np.where(on, np.interp(u, a, data[g, header.index("k_pair_N_per_m")]), 0.0)
            if ecol:
                e[it, j] = np.where(on, np.interp(u, a, data[g, header.index(ecol)] * efac), 0.0)
            if "b_pair_m" in header and it == 0:
                b[j] = np.where(on, np.interp(u, a, data[g, header.index("b_pair_m")]), b[j])
    # the pair is in contact from 0 to the span (docs/tables.md "Contact-zone edges")
    meta = dict(meta, contact_ratio=eps, engagement_in_rad=meta.get("engagement_in_rad", 0.0),
                engagement_out_rad=meta.get("engagement_out_rad", span))
    return _make(k, e, b, tq, period, mp, meta, prov)


def load_tables_file(path, meta_path=None, **meta_kwargs) -> MeshTables:
    """A ``.gtab`` (or FMU-resources directory) or a ``.csv`` with its sidecar."""
    p = Path(path)
    if p.suffix.lower() == ".csv":
        return load_tables_csv(p, meta_path, **meta_kwargs)
    if meta_path is not None or meta_kwargs:
        raise TableImportError(f"{p}: a sidecar / scalars are only used with CSV tables")
    if not p.exists():
        raise TableImportError(f"{p}: file not found")
    return load_tables(p)


def _toml_value(v) -> str:
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    return repr(float(v))


def tables_to_csv(tables: MeshTables, csv_path, meta_path=None):
    """Write ``tables`` in the slots form (every torque row, every slot; angles in rad,
    17 significant digits, so a read gives identical arrays) and its TOML sidecar
    (default: :func:`sidecar_path`, ``T.meta.toml`` beside ``T.csv``).  Returns (csv path, sidecar path)."""
    tables.validate()
    csv_path = Path(csv_path)
    meta_path = Path(meta_path) if meta_path is not None else sidecar_path(csv_path)
    P, N, NT = tables.slots, tables.n_phi, tables.n_torque
    head = ["pinion_angle_rad", "torque_Nm"]
    head += [f"k_slot{j + 1}_N_per_m" for j in range(P)] + [f"e_slot{j + 1}_m" for j in range(P)]
    head += [f"b_slot{j + 1}_m" for j in range(P)]
    if tables.e_comprehensive_m is not None:
        head.append("e_comprehensive_m")
    if tables.static_te_m is not None:
        head.append("static_te_m")
    blocks = []
    for it in range(NT):
        cols = [tables.phi_rad, np.full(N, tables.torque_Nm[it])]
        cols += [tables.k_N_per_m[it, j] for j in range(P)] + [tables.e_m[it, j] for j in range(P)]
        cols += [tables.backlash_half_m[j] for j in range(P)]
        if tables.e_comprehensive_m is not None:
            cols.append(tables.e_comprehensive_m[it])
        if tables.static_te_m is not None:
            cols.append(tables.static_te_m[it])
        blocks.append(np.column_stack(cols))
    csv_path.parent.mkdir(parents=True, exist_ok=True)
    with open(csv_path, "w", encoding="utf-8") as fh:
        fh.write("# gearfmu tooth-pair tables, slots form (docs/tables.md 'CSV import'); SI units\n")
        fh.write(",".join(head) + "\n")
        np.savetxt(fh, np.vstack(blocks), delimiter=",", fmt="%.17g")
    scal = {n: getattr(tables, n) for n in ("teeth_pinion", "teeth_gear", "base_radius_pinion_m",
                                            "base_radius_gear_m", "inertia_pinion_kgm2", "inertia_gear_kgm2",
                                            "phi_period_rad", "mesh_period_rad", "contact_ratio",
                                            "k_mean_N_per_m")}
    if tables.engagement_in_rad is not None:
        scal["engagement_in_rad"] = tables.engagement_in_rad
        scal["engagement_out_rad"] = tables.engagement_out_rad
    lines = ["# sidecar of " + csv_path.name + " (docs/tables.md 'CSV import')"]
    lines += [f"{k} = {_toml_value(v)}" for k, v in scal.items()]
    meta_path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return csv_path, meta_path
