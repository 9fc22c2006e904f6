"""Files a user hands over: zip archives (FMUs, SSP packages, .gtab tables) and text files
(scenes, CSV tables, sidecars); read them and say in one sentence what is wrong, with which file.

:func:`read_archive` reads every member to its end, so that the CRC-32 and the sizes the zip
headers record are checked (PKWARE APPNOTE 4.3.7); it keeps the SHA-256 of every member and the
bytes of the few members the caller asks for.  A file that is missing, a directory, empty, not a
zip archive, cut short, or whose member fails its CRC, is cut short, cannot be decompressed, is
encrypted, appears twice or has a name that leaves the archive's folder raises
:class:`ArchiveError` (a ValueError) naming the file, the member and the reason.
:func:`archive_kind` tells an FMU, an SSP package and a gearfmu table file apart by their
members, so that a file of the wrong kind is called by its name.  :func:`read_text` reads a
text file as UTF-8 and calls a zip archive, a binary file or bytes that are not UTF-8 by name.
"""
from __future__ import annotations

import hashlib
import zipfile
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath
from typing import Dict, Iterable, List, Optional

__all__ = ["ArchiveError", "Archive", "read_archive", "archive_kind", "read_text"]

_CHUNK = 1 << 20
_ZIP_MAGIC = b"PK\x03\x04"
_EMPTY_ZIP = b"PK\x05\x06"


class ArchiveError(ValueError):
    """A zip archive that cannot be used; the message names the file and the reason."""


@dataclass
class Archive:
    """A zip archive whose every member was read and checked: member names in archive order,
    the SHA-256 (hex) of every member and the bytes of the members asked for."""
    path: Path
    names: List[str]
    sha256: Dict[str, str] = field(default_factory=dict)
    data: Dict[str, bytes] = field(default_factory=dict)


def archive_kind(names: Iterable[str]) -> Optional[str]:
    """'an FMU', 'an SSP package' or 'a gearfmu table file (.gtab)' from an archive's member
    names; None for anything else."""
    s = set(names)
    if "SystemStructure.ssd" in s:
        return "an SSP package"
    if "modelDescription.xml" in s:
        return "an FMU"
    if {"tables.json", "tables.bin"} <= s:
        return "a gearfmu table file (.gtab)"
    return None


def read_text(path, expected: str, error=ValueError) -> str:
    """The text of the file ``path`` (UTF-8).  ``error`` naming the file when it is not text:
    a zip archive (an FMU, an SSP package or a table file called by name), a binary file (NUL
    bytes) or bytes that are not UTF-8 (line and column of the first); ``expected`` names what
    it should be ("a TOML scene").  OSError (missing, unreadable) passes through."""
    p = Path(path)
    raw = p.read_bytes()
    if raw.startswith((_ZIP_MAGIC, _EMPTY_ZIP)):
        kind = None
        try:
            with zipfile.ZipFile(p) as z:
                kind = archive_kind(z.namelist())
        except Exception:  # noqa: BLE001 - a damaged archive is still an archive
            pass
        raise error(f"{p}: not a text file but {kind + ' (a zip archive)' if kind else 'a zip archive'}; "
                    f"expected {expected}")
    if b"\0" in raw:
        raise error(f"{p}: not a text file (it holds NUL bytes); expected {expected}")
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        col = exc.start - (raw.rfind(b"\n", 0, exc.start) + 1) + 1
        raise error(f"{p}: not UTF-8 text (byte 0x{raw[exc.start]:02x} at line {line}, column {col}); "
                    f"expected {expected}") from None


def _unsafe(name: str) -> bool:
    p = PurePosixPath(name.replace("\\", "/"))
    return p.is_absolute() or ".." in p.parts or (len(name) > 1 and name[1] == ":")


def read_archive(path, kind: str, keep: Iterable[str] = ()) -> Archive:
    """Open ``path`` as a zip archive of ``kind`` (a noun for messages, e.g. "FMU") and read
    every member to its end; return the :class:`Archive` with the bytes of the members named in
    ``keep`` that exist.  ArchiveError naming the file and the reason otherwise (module docstring)."""
    p = Path(path)
    if not p.exists():
        raise ArchiveError(f"{p}: file not found")
    if not p.is_file():
        raise ArchiveError(f"{p}: not {_a(kind)} (a directory, not a file)")
    with open(p, "rb") as f:
        head = f.read(4)
    if not head:
        raise ArchiveError(f"{p}: not {_a(kind)} (an empty file)")
    if not zipfile.is_zipfile(p):
        if head == _ZIP_MAGIC:
            raise ArchiveError(f"{p}: damaged {kind}: the zip archive is truncated (its central directory "
                               "is missing; was the copy cut short?)")
        raise ArchiveError(f"{p}: not {_a(kind)} (not a zip archive)")
    keep = set(keep)
    try:
        z = zipfile.ZipFile(p)
    except Exception as exc:  # noqa: BLE001 - zipfile raises many kinds on a damaged directory
        raise ArchiveError(f"{p}: damaged {kind}: the zip directory cannot be read ({_reason(exc)})") from None
    with z:
        infos = z.infolist()
        names = [i.filename for i in infos]
        twice = sorted({n for n in names if names.count(n) > 1})
        if twice:
            raise ArchiveError(f"{p}: damaged {kind}: member {twice[0]} appears twice in the archive")
        bad = next((n for n in names if _unsafe(n)), None)
        if bad is not None:
            raise ArchiveError(f"{p}: refused {kind}: member name {bad!r} points outside the archive's folder")
        out = Archive(p, names)
        for info in infos:
            h, buf = hashlib.sha256(), [] if info.filename in keep else None
            try:
                with z.open(info) as m:
                    while True:
                        chunk = m.read(_CHUNK)
                        if not chunk:
                            break
                        h.update(chunk)
                        if buf is not None:
                            buf.append(chunk)
            except Exception as exc:  # noqa: BLE001 - BadZipFile, EOFError, zlib.error, ... on damage
                raise ArchiveError(f"{p}: damaged {kind}: member {info.filename} {_member_reason(exc)}") from None
            out.sha256[info.filename] = h.hexdigest()
            if buf is not None:
                out.data[info.filename] = b"".join(buf)
    return out


def _a(kind: str) -> str:
    """``kind`` with its article: "an FMU", "an SSP package", "a table file"."""
    word = kind.split()[0]
    vowel = word[0] in "AEFHILMNORSX" if word.isupper() else word[0].lower() in "aeio"
    return ("an " if vowel else "a ") + kind


def _reason(exc: BaseException) -> str:
    text = str(exc).splitlines()[0] if str(exc) else ""
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _member_reason(exc: BaseException) -> str:
    """What reading a member to its end says about it."""
    text = str(exc)
    if isinstance(exc, zipfile.BadZipFile) and "CRC" in text:
        return "fails its CRC-32 check (the file was corrupted in transfer or on disk)"
    if isinstance(exc, EOFError):
        return "is truncated (fewer bytes than its header records)"
    if isinstance(exc, RuntimeError) and "encrypted" in text:
        return "is encrypted"
    if isinstance(exc, NotImplementedError):
        return f"cannot be read ({text or 'unsupported compression'})"
    name = type(exc).__module__ + "." + type(exc).__name__
    if name == "zlib.error":
        return f"cannot be decompressed ({text}; the file was corrupted or truncated)"
    return f"cannot be read ({_reason(exc)})"
