"""Damaged, truncated, wrong-kind and tampered files handed to every command: one line, status 2.

The contract (gearfmu/cli.py, docs/cli.md "Exit status and errors"): a file a user hands over
(the SCENE and the files it names, ``--fmu``, ``--tables``, ``--tables-meta``) that cannot be
used is answered with exactly one line on stderr, starting ``gearfmu: `` and naming the file,
exit status 2, and no traceback.  References for "damaged": the zip format (PKWARE APPNOTE
4.3.7: every member carries the CRC-32 of its bytes and its sizes; the end-of-central-directory
record closes the archive), UTF-8 (RFC 3629: a byte 0x80-0xFF after an ASCII byte never decodes,
so flipping the top bit of any byte of an ASCII scene makes it invalid UTF-8) and SHA-256 (FIPS
180-4) of the members a gearfmu FMU records in its provenance and validation record.

One tiny scene (1 slice, 8 points per mesh period) gives one FMU, one .gtab, one CSV table pair
and one SSP (module fixtures); the damage is done byte by byte on copies of them, chosen by
hypothesis (derandomized: the same examples every run) and by hand for each kind.
"""
import contextlib
import io
import struct
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gearfmu.cli import main

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

TINY = """\
[scene]
name = "tiny"

[gears]
module_mm = 3.0
face_width_mm = 20.0

[gears.pinion]
teeth = 20

[gears.gear]
teeth = 31

[mesh]
slices = 1

[operating]
torque_Nm = 200.0
speed_rpm = 1000.0

[tables]
points_per_mesh = 8

[fmu]
stop_time_s = 0.002
output_interval_s = 1e-4
"""

FAST = ["-q", "--no-estimate", "--platforms", "x86_64-linux"]  # build options: one binary, no estimate
PROPERTY = settings(max_examples=12, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])


def _cli(*args):
    """``gearfmu ARGS`` in this process: (status, stdout + stderr, stderr).  An exception that
    escapes main() fails the test with its traceback."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main([str(a) for a in args])
        except SystemExit as exc:  # argparse
            rc = exc.code
    return rc, out.getvalue() + err.getvalue(), err.getvalue()


def refused(args, named: Path, *words):
    """Run ``gearfmu ARGS``; assert status 2, no traceback and exactly one stderr line, starting
    ``gearfmu: `` and naming ``named`` and every word of ``words`` (case-insensitive)."""
    rc, both, err = _cli(*args)
    assert "Traceback" not in both, both
    assert rc == 2, (rc, both[-2000:])
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("gearfmu: "), err
    assert named.name in lines[0], (named.name, lines[0])
    for w in words:
        assert w.lower() in lines[0].lower(), (w, lines[0])
    return lines[0]


def same_content(path: Path, intact: Path) -> bool:
    """Every member of ``path`` reads back byte for byte as in ``intact`` (zipfile accepts a few
    flips that change no content, e.g. the final-block bit of a deflate stream that ends anyway,
    or a date field)."""
    try:
        with zipfile.ZipFile(path) as za, zipfile.ZipFile(intact) as zb:
            return (sorted(za.namelist()) == sorted(zb.namelist())
                    and all(za.read(n) == zb.read(n) for n in zb.namelist()))
    except Exception:  # noqa: BLE001 - any failure to read is damage
        return False


def refused_unless_intact(args, bad: Path, intact: Path):
    """``refused`` when the damage changed what the archive holds; otherwise the command runs
    like on the intact file (status 0)."""
    if not same_content(bad, intact):
        return refused(args, bad)
    rc, both, _ = _cli(*args)
    assert rc == 0 and "Traceback" not in both, both


# ------------------------------------------------------------------ the intact files
@pytest.fixture(scope="module")
def good(tmp_path_factory):
    """tiny.toml, tiny.fmu (standalone, this platform), tiny.gtab, tiny.csv + tiny.meta.toml,
    tiny.ssp; each checked to work before it is damaged."""
    from gearfmu.ssp import build_ssp

    d = tmp_path_factory.mktemp("good")
    (d / "tiny.toml").write_text(TINY, encoding="utf-8")
    rc, both, _ = _cli("build", d / "tiny.toml", "-o", d / "tiny.fmu", *FAST)
    assert rc == 0, both
    rc, both, _ = _cli("tables", d / "tiny.toml", "-o", d / "tiny.gtab", "-q")
    assert rc == 0, both
    build_ssp(d / "tiny.fmu", d / "tiny.ssp", {"nominal": {"damping_ratio": 0.05}}, system_name="tiny")
    # the intact files pass: the damage below is what gets refused
    rc, both, _ = _cli("validate", d / "tiny.toml", "--fmu", d / "tiny.fmu")
    assert rc == 0 and "PASSED" in both, both
    rc, both, _ = _cli("build", d / "tiny.toml", "--tables", d / "tiny.gtab", "-o", d / "g.fmu", *FAST)
    assert rc == 0, both
    rc, both, _ = _cli("build", d / "tiny.toml", "--tables", d / "tiny.csv", "-o", d / "c.fmu", *FAST)
    assert rc == 0, both
    return d


def fmu_commands(scene, fmu, out):
    return [["validate", scene, "--fmu", fmu],
            ["simulate", scene, "--backend", "fmu", "--fmu", fmu, "-o", out / "s.csv", "-q"]]


def scene_commands(scene, good, out):
    return [["build", scene, "-o", out / "x.fmu", *FAST],
            ["tables", scene, "-o", out / "t.gtab", "-q"],
            ["simulate", scene, "-o", out / "s.csv", "-q"],
            ["validate", scene, "--fmu", good / "tiny.fmu"],
            ["plan", scene, "-q"],
            ["ssp", scene, "-o", out / "x.ssp", "-q"]]


def tables_command(good, tables, out, meta=None):
    return ["build", good / "tiny.toml", "--tables", tables, *(["--tables-meta", meta] if meta else []),
            "-o", out / "x.fmu", *FAST]


# ------------------------------------------------------------------ zip surgery
def _members(raw: bytes):
    """[(ZipInfo, start of its data in ``raw``)] in archive order (no data descriptors here)."""
    with zipfile.ZipFile(io.BytesIO(raw)) as z:
        infos = sorted(z.infolist(), key=lambda i: i.header_offset)
    out = []
    for i in infos:
        assert not i.flag_bits & 0x08  # sizes in the headers, as zipfile writes to a file
        n, e = struct.unpack("<HH", raw[i.header_offset + 26:i.header_offset + 30])
        out.append((i, i.header_offset + 30 + n + e))
    return out


def names(path: Path):
    return [i.filename for i, _ in _members(path.read_bytes()) if i.compress_size > 0]


def flip_in_member(path: Path, dst: Path, member: str, where: float, bit: int = 4) -> Path:
    """One bit of ``member``'s stored bytes flipped in place: its CRC-32 no longer matches."""
    raw = bytearray(path.read_bytes())
    i, start = next((i, s) for i, s in _members(bytes(raw)) if i.filename == member)
    raw[start + min(int(where * i.compress_size), i.compress_size - 1)] ^= 1 << bit
    dst.write_bytes(bytes(raw))
    return dst


def cut_member(path: Path, dst: Path, member: str, keep: float) -> Path:
    """``member``'s stored bytes cut to the fraction ``keep``, its compressed size in both headers
    set to the cut length (CRC and uncompressed size left as they were), every later offset moved:
    a well-formed archive with one member truncated."""
    raw = path.read_bytes()
    body, moved, new_len = bytearray(), {}, None
    for i, start in _members(raw):
        hdr, data = bytearray(raw[i.header_offset:start]), raw[start:start + i.compress_size]
        if i.filename == member:
            data = data[:int(keep * len(data))]
            new_len = len(data)
            hdr[18:22] = struct.pack("<I", new_len)
        moved[i.header_offset] = len(body)
        body += hdr + data
    eocd = raw.rfind(b"PK\x05\x06")
    cd_size, cd_off = struct.unpack("<II", raw[eocd + 12:eocd + 20])
    cd, pos = bytearray(raw[cd_off:cd_off + cd_size]), 0
    while pos < len(cd):
        n, e, c = struct.unpack("<HHH", cd[pos + 28:pos + 34])
        cd[pos + 42:pos + 46] = struct.pack("<I", moved[struct.unpack("<I", cd[pos + 42:pos + 46])[0]])
        if cd[pos + 46:pos + 46 + n].decode() == member:
            cd[pos + 20:pos + 24] = struct.pack("<I", new_len)
        pos += 46 + n + e + c
    end = bytearray(raw[eocd:])
    end[16:20] = struct.pack("<I", len(body))
    dst.write_bytes(bytes(body + cd + end))
    return dst


def rezip(path: Path, dst: Path, change=None, rename=None) -> Path:
    """A new archive with valid CRCs: ``change(name, data) -> data`` and ``rename {old: new}``."""
    with zipfile.ZipFile(path) as zin, zipfile.ZipFile(dst, "w", zipfile.ZIP_DEFLATED) as zout:
        for i in zin.infolist():
            data = zin.read(i.filename)
            if change is not None:
                data = change(i.filename, data)
            zout.writestr((rename or {}).get(i.filename, i.filename), data)
    return dst


def flip_byte(data: bytes, where: float, bit: int = 4) -> bytes:
    b = bytearray(data)
    b[min(int(where * len(b)), len(b) - 1)] ^= 1 << bit
    return bytes(b)


def binary_member(fmu: Path) -> str:
    return next(n for n in names(fmu) if n.startswith("binaries/linux64/"))


# ------------------------------------------------------------------ FMU: properties
@PROPERTY
@given(data=st.data(), where=st.floats(0, 1), bit=st.integers(0, 7))
def test_any_member_of_the_fmu_with_a_flipped_bit_is_refused(good, tmp_path_factory, data, where, bit):
    member = data.draw(st.sampled_from(names(good / "tiny.fmu")), label="member")
    d = tmp_path_factory.mktemp("flip")
    bad = flip_in_member(good / "tiny.fmu", d / "flipped.fmu", member, where, bit)
    for args in fmu_commands(good / "tiny.toml", bad, d):
        refused_unless_intact(args, bad, good / "tiny.fmu")


@PROPERTY
@given(data=st.data(), keep=st.floats(0, 0.99))
def test_any_truncated_member_of_the_fmu_is_refused(good, tmp_path_factory, data, keep):
    member = data.draw(st.sampled_from(names(good / "tiny.fmu")), label="member")
    d = tmp_path_factory.mktemp("cut")
    bad = cut_member(good / "tiny.fmu", d / "cut.fmu", member, keep)
    for args in fmu_commands(good / "tiny.toml", bad, d):
        refused_unless_intact(args, bad, good / "tiny.fmu")


@PROPERTY
@given(keep=st.floats(0, 0.9999))
def test_an_fmu_cut_short_anywhere_is_refused(good, tmp_path_factory, keep):
    d = tmp_path_factory.mktemp("short")
    raw = (good / "tiny.fmu").read_bytes()
    bad = d / "short.fmu"
    bad.write_bytes(raw[:int(keep * len(raw))])
    for args in fmu_commands(good / "tiny.toml", bad, d):
        refused(args, bad)


@PROPERTY
@given(data=st.data(), where=st.floats(0, 1), bit=st.integers(0, 7))
def test_a_recorded_member_altered_with_a_valid_crc_is_refused(good, tmp_path_factory, data, where, bit):
    """Re-zipped after the change (every CRC valid): the SHA-256 the FMU records of its binary,
    tables, sources, scene and reference result no longer match."""
    recorded = [n for n in names(good / "tiny.fmu")
                if n.startswith(("binaries/", "sources/gear", "sources/gk")) or n in (
                    "resources/tables.bin", "resources/tables.json", "resources/scene.toml",
                    "resources/validation/reference_result.csv", "resources/validation/scene.toml")]
    member = data.draw(st.sampled_from(recorded), label="member")
    d = tmp_path_factory.mktemp("tamper")
    bad = rezip(good / "tiny.fmu", d / "tampered.fmu",
                change=lambda n, b: flip_byte(b, where, bit) if n == member else b)
    for args in fmu_commands(good / "tiny.toml", bad, d):
        refused(args, bad, member.rsplit("/", 1)[-1], "checksum")


@settings(max_examples=15, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(where=st.floats(0, 1), bit=st.integers(0, 7))
def test_any_bit_of_the_fmu_file_flipped_runs_or_is_refused_never_a_traceback(good, tmp_path_factory, where, bit):
    """Anywhere in the file, headers included (a flip in a date field changes nothing that
    matters): the FMU either still runs like the intact one or is refused in one line."""
    d = tmp_path_factory.mktemp("anybit")
    bad = d / "anybit.fmu"
    bad.write_bytes(flip_byte((good / "tiny.fmu").read_bytes(), where, bit))
    refused_unless_intact(fmu_commands(good / "tiny.toml", bad, d)[1], bad, good / "tiny.fmu")


# ------------------------------------------------------------------ FMU: each kind by hand
def test_fmu_with_a_bad_crc_is_refused_naming_the_member(good, tmp_path):
    member = binary_member(good / "tiny.fmu")
    bad = flip_in_member(good / "tiny.fmu", tmp_path / "crc.fmu", member, 0.5)
    for args in fmu_commands(good / "tiny.toml", bad, tmp_path):
        refused(args, bad, "damaged", member, "CRC-32")


def test_fmu_with_a_truncated_member_is_refused(good, tmp_path):
    bad = cut_member(good / "tiny.fmu", tmp_path / "trunc.fmu", "resources/tables.bin", 0.5)
    for args in fmu_commands(good / "tiny.toml", bad, tmp_path):
        refused(args, bad, "damaged", "resources/tables.bin")


def test_fmu_cut_short_is_called_truncated(good, tmp_path):
    bad = tmp_path / "half.fmu"
    bad.write_bytes((good / "tiny.fmu").read_bytes()[:40000])
    for args in fmu_commands(good / "tiny.toml", bad, tmp_path):
        refused(args, bad, "truncated")


@pytest.mark.parametrize("old,new,words", [
    ("modelDescription.xml", "modeldescription.xml", ["no modelDescription.xml"]),
    ("binary", "binaries/linux64/other.so", ["binaries/linux64/", "missing"]),
    ("resources/tables.bin", "resources/tables.bin.old", ["resources/tables.bin", "missing"]),
    ("resources/gearfmu_standalone.txt", "resources/config.txt", ["resources/gearfmu_standalone.txt", "missing"]),
], ids=["modelDescription", "binary", "tables.bin", "config"])
def test_fmu_with_a_renamed_member_is_refused(good, tmp_path, old, new, words):
    old = binary_member(good / "tiny.fmu") if old == "binary" else old
    bad = rezip(good / "tiny.fmu", tmp_path / "renamed.fmu", rename={old: new})
    for args in fmu_commands(good / "tiny.toml", bad, tmp_path):
        refused(args, bad, *words)


def test_fmu_whose_model_description_was_edited_is_refused(good, tmp_path):
    """A GUID that is not the one the FMU was built with, and a modelDescription.xml that is
    not XML."""
    guid = rezip(good / "tiny.fmu", tmp_path / "guid.fmu", change=lambda n, b: (
        b.replace(b'guid="{', b'guid="{0') if n == "modelDescription.xml" else b))
    junk = rezip(good / "tiny.fmu", tmp_path / "junk.fmu", change=lambda n, b: (
        b[:len(b) // 2] if n == "modelDescription.xml" else b))
    for args in fmu_commands(good / "tiny.toml", guid, tmp_path):
        refused(args, guid, "guid", "provenance")
    for args in fmu_commands(good / "tiny.toml", junk, tmp_path):
        refused(args, junk, "modelDescription.xml")


def test_fmu_without_a_binary_for_this_platform_is_refused(good, tmp_path):
    """Built for Windows only (the provenance agrees: nothing is missing that it lists)."""
    win = tmp_path / "win.fmu"
    rc, both, _ = _cli("build", good / "tiny.toml", "-o", win, "-q", "--no-estimate", "--platforms", "x86_64-windows")
    assert rc == 0, both
    for args in fmu_commands(good / "tiny.toml", win, tmp_path):
        refused(args, win, "no binary for this platform", "linux64", "win64")


@pytest.mark.parametrize("kind,words", [("ssp", ["SSP", "resources/tiny.fmu"]), ("gtab", ["table file"]),
                                        ("toml", ["not a zip archive"])])
def test_another_kind_of_file_given_as_fmu_is_named(good, tmp_path, kind, words):
    for args in fmu_commands(good / "tiny.toml", good / f"tiny.{kind}", tmp_path):
        refused(args, good / f"tiny.{kind}", *words)


def test_no_traceback_reaches_the_terminal(good, tmp_path):
    """The command as a user runs it, in a fresh process: the line, status 2, nothing else."""
    bad = flip_in_member(good / "tiny.fmu", tmp_path / "crc.fmu", binary_member(good / "tiny.fmu"), 0.5)
    for args in fmu_commands(good / "tiny.toml", bad, tmp_path):
        p = subprocess.run([sys.executable, "-m", "gearfmu.cli", *map(str, args)], capture_output=True,
                           text=True, timeout=300)
        assert p.returncode == 2, p.stderr
        assert "Traceback" not in p.stderr + p.stdout
        lines = p.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("gearfmu: ") and "crc.fmu" in lines[0], p.stderr


def test_done_when_every_command_refuses_a_bad_crc_a_truncated_fmu_and_an_ssp(good, tmp_path):
    """The acceptance case: a damaged FMU (bad CRC), a truncated one and an SSP, in every place a
    command takes a file (--fmu, --tables, SCENE): one line, status 2, no traceback."""
    crc = flip_in_member(good / "tiny.fmu", tmp_path / "crc.fmu", binary_member(good / "tiny.fmu"), 0.3)
    short = tmp_path / "short.fmu"
    short.write_bytes((good / "tiny.fmu").read_bytes()[:-100])
    for f in (crc, short, good / "tiny.ssp"):
        for args in (fmu_commands(good / "tiny.toml", f, tmp_path) + [tables_command(good, f, tmp_path)]
                     + scene_commands(f, good, tmp_path)):
            refused(args, f)


# ------------------------------------------------------------------ tables: .gtab and CSV
@PROPERTY
@given(member=st.sampled_from(["tables.json", "tables.bin"]), how=st.sampled_from(["flip", "cut", "rezip"]),
       where=st.floats(0, 0.99), bit=st.integers(0, 7))
def test_a_damaged_gtab_is_refused(good, tmp_path_factory, member, how, where, bit):
    """A bit flipped (bad CRC), a member cut short, or tables.bin altered and re-zipped (its
    SHA-256 in tables.json no longer matches)."""
    d = tmp_path_factory.mktemp("gtab")
    src, bad = good / "tiny.gtab", d / "bad.gtab"
    if how == "flip":
        flip_in_member(src, bad, member, where, bit)
    elif how == "cut":
        cut_member(src, bad, member, where)
    else:
        rezip(src, bad, change=lambda n, b: flip_byte(b, where, bit) if n == "tables.bin" else b)
    refused_unless_intact(tables_command(good, bad, d), bad, src)


@pytest.mark.parametrize("case,words", [
    ("short", ["truncated"]),
    ("renamed", ["tables.json"]),
    ("arrays", ["tables.json"]),
    ("list", ["tables.json"]),
    ("shape", ["tables.json"]),
], ids=lambda v: v if isinstance(v, str) else None)
def test_a_malformed_gtab_is_refused_naming_it(good, tmp_path, case, words):
    src, bad = good / "tiny.gtab", tmp_path / "bad.gtab"
    if case == "short":
        bad.write_bytes(src.read_bytes()[:-30])
    elif case == "renamed":
        rezip(src, bad, rename={"tables.json": "Tables.json"})
    else:
        edit = {"arrays": lambda b: b.replace(b'"arrays"', b'"arrayz"'),
                "list": lambda b: b"[" + b + b"]",
                "shape": lambda b: b.replace(b'"shape": [\n', b'"shape": [\n   7,\n', 1)}[case]
        rezip(src, bad, change=lambda n, b: edit(b) if n == "tables.json" else b)
    refused(tables_command(good, bad, tmp_path), bad, *words)


def test_other_files_given_as_tables_are_named(good, tmp_path):
    (tmp_path / "fmu.csv").write_bytes((good / "tiny.fmu").read_bytes())
    text = (good / "tiny.csv").read_bytes()
    (tmp_path / "latin.csv").write_bytes(text[:200] + b"\xe9" + text[200:])
    (tmp_path / "nul.csv").write_bytes(text[:200] + b"\x00" + text[200:])
    cases = [
        (good / "tiny.fmu", None, ["an FMU", "not a table file"]),
        (good / "tiny.ssp", None, ["SSP", "not a table file"]),
        (tmp_path / "fmu.csv", good / "tiny.meta.toml", ["not a text file"]),
        (tmp_path / "latin.csv", good / "tiny.meta.toml", ["UTF-8"]),
        (tmp_path / "nul.csv", good / "tiny.meta.toml", []),
    ]
    for tables, meta, words in cases:
        refused(tables_command(good, tables, tmp_path, meta), tables, *words)
    refused(tables_command(good, good / "tiny.csv", tmp_path, good / "tiny.fmu"), good / "tiny.fmu", "not a text file")


# ------------------------------------------------------------------ scenes
@PROPERTY
@given(where=st.floats(0, 1))
def test_a_scene_with_invalid_utf8_is_refused_by_every_command(good, tmp_path_factory, where):
    """The top bit of one byte flipped: never valid UTF-8 (module docstring)."""
    d = tmp_path_factory.mktemp("utf8")
    bad = d / "bad.toml"
    bad.write_bytes(flip_byte(TINY.encode(), where, bit=7))
    for args in scene_commands(bad, good, d):
        refused(args, bad, "UTF-8")


@pytest.mark.parametrize("kind,words", [("fmu", ["zip archive", "FMU"]), ("ssp", ["zip archive", "SSP"]),
                                        ("gtab", ["zip archive", "table file"]), ("png", ["not a text file"])])
def test_a_binary_file_as_scene_is_named_by_every_command(good, tmp_path, kind, words):
    for args in scene_commands(good / f"tiny.{kind}", good, tmp_path):
        refused(args, good / f"tiny.{kind}", *words)


def test_a_scene_whose_duty_cycle_is_binary_is_refused(good, tmp_path):
    scene = tmp_path / "duty.toml"
    scene.write_text(TINY + f'\n[envelope]\nduty_cycle_csv = "{good / "tiny.fmu"}"\n', encoding="utf-8")
    for args in scene_commands(scene, good, tmp_path):
        line = refused(args, scene, "duty_cycle_csv", "tiny.fmu")
        assert "not a text file" in line, line


# ------------------------------------------------------------------ policy: user file against bug
def test_a_reader_failure_nobody_foresaw_is_one_line_with_a_hint(good, tmp_path, monkeypatch):
    """The last-resort guard around reading a handed-over file (gearfmu/cli.py ``_reading``):
    an exception no reader foresaw still gives one line naming the file, with the hint;
    GEARFMU_DEBUG=1 adds the traceback behind the same line and status."""
    import gearfmu.cli as cli

    def unforeseen(*args, **kwargs):
        raise KeyError("arrays")

    monkeypatch.setattr(cli, "load_tables_file", unforeseen)
    args = tables_command(good, good / "tiny.gtab", tmp_path)
    line = refused(args, good / "tiny.gtab", "--tables", "KeyError", "GEARFMU_DEBUG=1")
    monkeypatch.setenv("GEARFMU_DEBUG", "1")
    rc, _, err = _cli(*args)
    assert rc == 2 and "Traceback" in err and "unforeseen" in err, err
    assert err.strip().splitlines()[-1] == line


def test_an_internal_error_keeps_its_traceback(good, tmp_path, monkeypatch):
    """A failure that is not about a handed-over file is a bug: main() does not hide it."""
    import gearfmu.pipeline as pipeline

    def bug(*args, **kwargs):
        raise RuntimeError("a bug in the table stage")

    monkeypatch.setattr(pipeline, "compute_tables", bug)
    with pytest.raises(RuntimeError, match="a bug in the table stage"):
        main(["tables", str(good / "tiny.toml"), "-o", str(tmp_path / "t.gtab"), "-q"])
