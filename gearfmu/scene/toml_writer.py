"""Writing a scene back as TOML: :func:`dumps_toml`.

Scenes built in code (:func:`gearfmu.scene.reader.load_scene` with a mapping) are
written to TOML text first, so that every scene has a TOML source for provenance
(TOML 1.0: https://toml.io/en/v1.0.0; read back with :mod:`tomllib`).
"""
from __future__ import annotations

import math
import re
from typing import Any, List, Mapping

__all__ = ["dumps_toml"]

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def _toml_str(s: str) -> str:
    out = ['"']
    for ch in s:
        o = ord(ch)
        if ch == '"':
            out.append('\\"')
        elif ch == "\\":
            out.append("\\\\")
        elif ch == "\n":
            out.append("\\n")
        elif ch == "\t":
            out.append("\\t")
        elif o < 0x20 or o == 0x7F:
            out.append(f"\\u{o:04X}")
        elif 0xD800 <= o <= 0xDFFF:
            raise ValueError("dumps_toml: lone surrogate characters cannot be written to TOML")
        else:
            out.append(ch)
    out.append('"')
    return "".join(out)


def _toml_key(k: str) -> str:
    return k if _BARE_KEY.fullmatch(k) else _toml_str(k)


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return _toml_str(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, Mapping):
        return "{" + ", ".join(f"{_toml_key(str(k))} = {_toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"dumps_toml: cannot write a {type(v).__name__}")


def _is_table_array(v: Any) -> bool:
    return isinstance(v, (list, tuple)) and len(v) > 0 and all(isinstance(x, Mapping) for x in v)


def _dump_table(data: Mapping, prefix: List[str], lines: List[str]) -> None:
    scalars = [(k, v) for k, v in data.items() if not isinstance(v, Mapping) and not _is_table_array(v)]
    tables = [(k, v) for k, v in data.items() if isinstance(v, Mapping)]
    arrays = [(k, v) for k, v in data.items() if _is_table_array(v)]
    for k, v in scalars:
        lines.append(f"{_toml_key(str(k))} = {_toml_value(v)}")
    for k, v in tables:
        path = prefix + [str(k)]
        lines.append("")
        lines.append("[" + ".".join(_toml_key(p) for p in path) + "]")
        _dump_table(v, path, lines)
    for k, v in arrays:
        path = prefix + [str(k)]
        for item in v:
            lines.append("")
            lines.append("[[" + ".".join(_toml_key(p) for p in path) + "]]")
            _dump_table(item, path, lines)


def dumps_toml(data: Mapping) -> str:
    """Write a nested mapping (tables, arrays of tables, strings, numbers,
    booleans, arrays) as TOML text that :mod:`tomllib` reads back to the same
    data.  Used for scenes built in code (:func:`load_scene` with a mapping)
    so that every scene has a TOML source for provenance."""
    if not isinstance(data, Mapping):
        raise TypeError("dumps_toml: expected a mapping")
    lines: List[str] = []
    _dump_table(data, [], lines)
    return "\n".join(lines).lstrip("\n") + "\n"
