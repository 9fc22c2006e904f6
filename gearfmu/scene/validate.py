"""The scene's checks: each value against its :class:`~gearfmu.scene.schema.Key`, and the checks across keys.

:class:`Reader` reads the tables of a parsed scene against
:data:`gearfmu.scene.schema.SCHEMA` and collects every problem as ``(key path,
reason)`` instead of stopping at the first, so that one :class:`SceneError` names
them all (unknown keys get the closest valid key as a hint: ``module_m`` suggests
``module_mm``).  :func:`thermal_cross_checks` checks ``[thermal]`` against
``[mesh]`` and ``[lubricant]``; :func:`check_geometry` runs the geometry module's
checks (contact ratio, pointed tip, undercut, interference) and maps its error to
the scene key path.
"""
from __future__ import annotations

import difflib
import math
import re
from dataclasses import replace
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple

from ..common.vocabulary import LUBRICATED_CONTACT_MODELS, current_spelling
from ..gear import geometry
from ..gear.gearpair import GearPairSpec
from .options import Lubricant, ThermalOptions
from .schema import AUTO, SCHEMA, SUBTABLES, Key

__all__ = ["Reader", "sub", "describe", "suggest", "thermal_cross_checks", "check_geometry"]

_UNIT_SUFFIX = re.compile(r"_(mm|m|um|deg|rad|GPa|Pa|Nm|rpm|rad_s|s|kg_m3|kgm2|C|cSt|Pas|GPa_inv|"
                          r"Pa_inv|per_K)$")


def suggest(key: str, valid: Sequence[str], units: Optional[Mapping[str, str]] = None) -> str:
    """Hint for an unknown key: a valid key with the same stem and another
    unit (``module_m`` -> ``module_mm``), else the closest spelling."""
    if not valid:
        return ""
    k = key.lower()
    best = None
    for v in valid:
        m = _UNIT_SUFFIX.search(v)
        if not m:
            continue
        stem = v[:m.start()].lower()
        if (k.startswith(stem + "_") or k == stem) and (best is None or len(stem) > best[1]):
            best = (v, len(stem), m.group(1))
    if best is not None:
        unit = (units or {}).get(best[0], best[2])
        return f"; did you mean {best[0]!r}? (this key is in {unit})"
    close = difflib.get_close_matches(key, list(valid), n=1, cutoff=0.6)
    if not close:
        low = difflib.get_close_matches(k, [v.lower() for v in valid], n=1, cutoff=0.6)
        close = [v for v in valid if low and v.lower() == low[0]]
    return f"; did you mean {close[0]!r}?" if close else ""


def describe(value: Any) -> str:
    if isinstance(value, bool):
        return f"the boolean {str(value).lower()}"
    if isinstance(value, str):
        return f"the string {value!r}"
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, list):
        return "an array"
    if isinstance(value, (int, float)):
        return repr(value)
    return f"a {type(value).__name__}"


def _to_si(v: float, scale: float) -> float:
    """v * scale, computed as a division when scale is 1/integer so that
    decimal inputs give the nearest double (6 mm -> 0.006 m exactly as typed)."""
    if scale != 1.0 and scale < 1.0:
        inv = round(1.0 / scale)
        if abs(1.0 / scale - inv) <= 1e-9 * inv:
            return v / inv
    return v * scale


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


class Reader:
    """Collects problems while reading tables of a parsed scene.  ``schema`` and ``subtables``
    (default :data:`~gearfmu.scene.schema.SCHEMA` and ``SUBTABLES``, the gear-pair scene) are the
    tables and keys it reads against (the drivetrain scene has its own,
    :mod:`gearfmu.scene.drivetrain`)."""

    def __init__(self, schema: Optional[Mapping[str, Tuple[Key, ...]]] = None,
                 subtables: Optional[Mapping[str, Tuple[str, ...]]] = None) -> None:
        self.problems: List[Tuple[str, str]] = []
        self.schema = SCHEMA if schema is None else schema
        self.subtables = SUBTABLES if subtables is None else subtables

    def add(self, path: str, reason: str) -> None:
        self.problems.append((path, reason))

    # ---------------------------------------------------------- values
    def _num(self, path: str, key: Key, v: Any, integer: bool, allow_auto: bool = False):
        """Validate one number against ``key``'s range; return it in SI or None."""
        what = "an integer" if integer else "a number"
        rng = key.range_text()
        expect = f"{what} {rng}".strip() + (' or "auto"' if allow_auto else "")
        if integer:
            ok = isinstance(v, int) and not isinstance(v, bool)
        else:
            ok = _is_number(v)
        if not ok:
            self.add(path, f"must be {expect}, got {describe(v)}")
            return None
        if not integer and not math.isfinite(v):
            self.add(path, f"must be a finite number {rng}".rstrip() + f", got {v!r}")
            return None
        bad = ((key.lo is not None and (v < key.lo or (key.lo_open and v == key.lo)))
               or (key.hi is not None and (v > key.hi or (key.hi_open and v == key.hi))))
        if bad:
            self.add(path, f"must be {expect}, got {v!r}")
            return None
        return int(v) if integer else _to_si(float(v), key.scale)

    def value(self, path: str, key: Key, v: Any):
        """Validate ``v`` for ``key``; return the SI value or None (problem recorded)."""
        k = key.kind
        if k == "float":
            return self._num(path, key, v, integer=False)
        if k == "int":
            return self._num(path, key, v, integer=True)
        if k == "int_or_auto":
            if v == AUTO:
                return None
            return self._num(path, key, v, integer=True, allow_auto=True)
        if k == "float_or_auto":
            if v == AUTO:
                return None
            return self._num(path, key, v, integer=False, allow_auto=True)
        if k == "bool":
            if not isinstance(v, bool):
                self.add(path, f"must be true or false, got {describe(v)}")
                return None
            return v
        if k == "str":
            if not isinstance(v, str):
                self.add(path, f"must be a string, got {describe(v)}")
                return None
            return v
        if k == "identifier":
            if not isinstance(v, str) or not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]{0,63}", v):
                self.add(path, "must be a C identifier (letters, digits, _; not starting with a digit; "
                               f"at most 64 characters), got {describe(v)}")
                return None
            return v
        if k == "enum":
            v = current_spelling(key.name, v, where=path)  # an old spelling: the new one, with a warning
            if not isinstance(v, str) or v not in key.choices:
                hint = ""
                if isinstance(v, str):
                    close = difflib.get_close_matches(v.lower(), key.choices, n=1, cutoff=0.5)
                    hint = f"; did you mean {close[0]!r}?" if close else ""
                self.add(path, f"must be one of {', '.join(repr(c) for c in key.choices)}, "
                               f"got {describe(v)}{hint}")
                return None
            return v
        if k == "str_list":
            if not isinstance(v, list) or not all(isinstance(x, str) for x in v):
                self.add(path, f"must be an array of strings, got {describe(v)}")
                return None
            return tuple(v)
        if k in ("float_list", "float_pair"):
            if not isinstance(v, list):
                self.add(path, f"must be an array of numbers, got {describe(v)}")
                return None
            out, ok = [], True
            for i, item in enumerate(v):
                x = self._num(f"{path}[{i}]", key, item, integer=False)
                ok = ok and x is not None
                out.append(x)
            if not ok:
                return None
            if k == "float_pair":
                if len(out) != 2 or not out[0] < out[1]:
                    self.add(path, f"must be [low, high] with low < high, got {v!r}")
                    return None
                return (out[0], out[1])
            return tuple(out)
        raise AssertionError(f"unknown key kind {k}")  # pragma: no cover - schema bug

    # ---------------------------------------------------------- tables
    def table(self, data: Any, path: str, *, required: bool = False) -> Dict[str, Any]:
        """Read the table at ``path`` (schema ``self.schema[path]``): returns key ->
        SI value (defaults filled in, None where invalid or absent)."""
        keys = self.schema.get(path, ())
        subs = self.subtables.get(path, ())
        out: Dict[str, Any] = {k.name: None for k in keys}
        if data is None:
            if required:
                self.add(path, "missing table (required)")
                return out
            data = {}
        if not isinstance(data, dict):
            self.add(path, f"must be a table, got {describe(data)}")
            return out
        valid = [k.name for k in keys] + list(subs)
        units = {k.name: k.unit for k in keys}
        for name in data:
            if name not in valid:
                where = f"{path}.{name}" if path else name
                self.add(where, "unknown key" + suggest(name, valid, units))
        for k in keys:
            p = f"{path}.{k.name}"
            if k.name in data:
                out[k.name] = self.value(p, k, data[k.name])
            elif k.required:
                self.add(p, "missing (required)")
            elif k.default is None or k.default is AUTO:
                out[k.name] = None
            elif k.kind == "float":
                out[k.name] = _to_si(float(k.default), k.scale)
            elif k.kind == "float_list":
                out[k.name] = tuple(_to_si(x, k.scale) for x in k.default)
            else:
                out[k.name] = k.default
        return out

    def section(self, data: Any, name: str) -> Optional[Tuple[Any, Dict[str, Any]]]:
        """Read the optional top-level table ``name``: ``(raw table, key -> SI value)``, or
        None when the table is absent or any of its keys has a problem (recorded), so that
        the section's own cross-key checks run only on values that passed their checks."""
        raw = sub(data, name)
        if raw is None:
            return None
        n0 = len(self.problems)
        values = self.table(raw, name)
        return None if len(self.problems) > n0 else (raw, values)


def sub(data: Any, name: str) -> Any:
    """``data[name]`` when ``data`` is a table, else None (a missing or mistyped parent table
    is reported by :meth:`Reader.table`)."""
    return data.get(name) if isinstance(data, dict) else None


def thermal_cross_checks(r: Reader, th: Optional[ThermalOptions], contact_model: Optional[str],
                          lub: Optional[Lubricant]) -> Optional[ThermalOptions]:
    """[thermal] against [mesh] and [lubricant] (docs/thermal.md "Oil temperature axis"):
    an axis_quantity other than "bulk" needs an axis, a contact model that uses
    the lubricant and a viscosity-temperature law usable at every axis
    temperature; a bulk temperature axis excludes fixed gear temperatures.
    Returns the options with the lubricant attached when the axis involves the oil."""
    if th is None:
        return None
    q = th.axis_quantity
    fixed = [k for k, v in (("pinion_temperature_C", th.pinion_temperature_C is not None),
                            ("gear_temperature_C", th.gear_temperature_C is not None),
                            ("pinion_profile_C", len(th.pinion_profile_C) > 0),
                            ("gear_profile_C", len(th.gear_profile_C) > 0)) if v]
    if len(th.temperature_axis_C) and q in ("bulk", "bulk_and_oil") and fixed:
        r.add(f"thermal.{fixed[0]}", f"the {q!r} temperature axis sets the temperature of both gears; remove "
                                     f"{', '.join(fixed)} or use axis_quantity = \"oil\"")
    if q == "bulk":
        return th
    if not len(th.temperature_axis_C):
        r.add("thermal.axis_quantity", f"{q!r} needs thermal.temperature_axis_C (the oil temperatures of the "
                                       "tables' axis)")
        return th
    if contact_model not in LUBRICATED_CONTACT_MODELS:
        r.add("thermal.axis_quantity", f"{q!r}: the oil temperature acts through eta0 of a lubricated contact "
                                       f"model, but mesh.contact_model = {contact_model!r} uses no lubricant "
                                       f"(use one of {list(LUBRICATED_CONTACT_MODELS)}, or axis_quantity = \"bulk\")")
        return th
    if lub is None:
        return th  # the missing [lubricant] is reported above
    if lub.kinematic_viscosity_40C_m2_s is None or lub.kinematic_viscosity_100C_m2_s is None:
        r.add("lubricant.eta0_Pas", f"thermal.axis_quantity = {q!r} needs a viscosity-temperature law: give "
                                    "kinematic_viscosity_40C_cSt and kinematic_viscosity_100C_cSt instead")
        return th
    for t in th.temperature_axis_C:
        try:
            eta = lub.density_kg_m3 * lub.kinematic_viscosity_m2_s(float(t))
        except (OverflowError, ValueError):
            eta = float("nan")
        if not (math.isfinite(eta) and eta > 0):
            r.add("thermal.temperature_axis_C", f"the lubricant's viscosity law gives no usable viscosity at "
                                                f"{t:g} degC")
            return th
    return replace(th, lubricant=lub)


#: GearPairSpec / GearSpec field names -> scene key names (for GeometryError)
_FIELD_TO_KEY = {
    "teeth": "teeth", "module_m": "module_mm", "pressure_angle_rad": "pressure_angle_deg",
    "face_width_m": "face_width_mm", "profile_shift": "profile_shift",
    "addendum_coefficient": "addendum_coefficient", "tip_clearance_coefficient": "tip_clearance_coefficient",
    "hub_radius_m": "hub_radius_mm", "inertia_kgm2": "inertia_kgm2", "backlash_m": "backlash_um",
    "center_distance_m": "center_distance_mm", "youngs_modulus_Pa": "youngs_modulus_GPa",
    "poisson_ratio": "poisson_ratio", "density_kg_m3": "density_kg_m3",
    "thermal_expansion_per_K": "thermal_expansion_per_K",
    "helix_angle_rad": "helix_angle_deg", "helix_hand": "hand",
}
_SHARED = ("module_m", "pressure_angle_rad", "face_width_m", "backlash_m", "center_distance_m",
           "helix_angle_rad", "helix_hand")


def _geometry_key_path(field: str) -> str:
    """Map a GeometryError field ('pinion.profile_shift', 'center_distance_m',
    'pair', ...) to the scene key path ('gears.pinion.profile_shift', ...)."""
    parts = [p for p in re.split(r"[.\[\]]+", field.strip()) if p]
    if parts and parts[0] in ("pair", "gears", "spec"):
        parts = parts[1:]
    role = None
    if parts and parts[0] in ("pinion", "gear"):
        role, parts = parts[0], parts[1:]
    if not parts:
        return f"gears.{role}" if role else "gears"
    name = parts[-1]
    key = _FIELD_TO_KEY.get(name)
    if key is None:
        return f"gears.{role}" if role else "gears"
    if name in _SHARED:
        return f"gears.{key}"
    return f"gears.{role}.{key}" if role else f"gears.{key}"


def _geometry_problem(exc: BaseException) -> Tuple[str, str]:
    """``(key_path, reason)`` of a geometry error: :class:`gearfmu.gear.geometry.GeometryError`
    messages start with the field they are about (``pinion.profile_shift: ...``, or several
    joined by ``+``), which is mapped to the scene key."""
    msg = str(exc)
    field = None
    m = re.match(r"\s*([A-Za-z_][\w.\[\]]*)((?:\s*\+\s*[A-Za-z_][\w.\[\]]*)*)\s*:\s*(.*)", msg, re.S)
    if m:
        field, msg = m.group(1), (m.group(1) + m.group(2) + ": " if m.group(2) else "") + m.group(3)
    path = _geometry_key_path(field) if field else "gears"
    return path, f"impossible gear pair: {msg}"


def check_geometry(pair: GearPairSpec) -> Optional[Tuple[str, str]]:
    """Run the geometry module's checks (contact ratio, pointed tip, undercut,
    interference); return ``(key_path, reason)`` or None."""
    try:
        geometry.pair_geometry(pair)
    except (ValueError, ArithmeticError) as exc:  # GeometryError is a ValueError
        return _geometry_problem(exc)
    return None
