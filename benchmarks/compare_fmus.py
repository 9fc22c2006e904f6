"""Member-by-member comparison of the FMUs two gearfmu checkouts build (for refactorings of the builders).

    python benchmarks/compare_fmus.py CHECKOUT_A CHECKOUT_B [--platforms KEYS] [--keep DIR]

In each checkout (a fresh interpreter with the checkout first on ``sys.path``; the script
checks that the ``gearfmu`` it imported is the checkout's) it builds, from the same small
synthetic tables (``rectangular_wave_tables``) with a scene text and the same arguments:

* the pythonfmu FMU (FMI 2.0), :func:`gearfmu.fmu.pythonfmu_build.build_fmu`;
* the standalone FMU for FMI 2.0 and for FMI 3.0, :func:`gearfmu.fmu.standalone_build.build_standalone_fmu`
  (``--platforms``: crossbuild keys, default the build machine's own).

What a build draws from the clock or from chance is made the same in both runs: ``uuid.uuid4``
returns 1, 2, 3, ... and ``datetime.datetime.now`` a fixed instant.  The one timing an FMU
records, ``native_wall_s`` of ``resources/validation/record.json`` (the native solver's wall
time), is blanked before the comparison, and the zip entries' own timestamps are not compared.

Printed per FMU: whether the two files are byte-identical, and whether every member (the same
names in the same order, the same compression, the same bytes) is.  Exit status 0 when every
FMU is identical member by member, 1 otherwise.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

CHILD = r'''
import datetime, sys, uuid
checkout, out, platforms = sys.argv[1], sys.argv[2], sys.argv[3]
sys.path.insert(0, checkout)


class _FixedNow(datetime.datetime):
    @classmethod
    def now(cls, tz=None):
        return cls(2000, 1, 1, tzinfo=tz)


datetime.datetime = _FixedNow
_count = [0]


def _uuid4():
    _count[0] += 1
    return uuid.UUID(int=_count[0])


uuid.uuid4 = _uuid4
from pathlib import Path
import gearfmu
assert Path(gearfmu.__file__).resolve().is_relative_to(Path(checkout).resolve()), gearfmu.__file__
import numpy as np
from gearfmu.fmu import crossbuild
from gearfmu.fmu.pythonfmu_build import build_fmu
from gearfmu.fmu.standalone_build import build_standalone_fmu
from gearfmu.tables.synthetic import rectangular_wave_tables

tables = rectangular_wave_tables(1e8, contact_ratio=1.6, backlash_half_m=20e-6,
                                 pair_error_m=lambda j, u: 10e-6 * np.sin(np.pi * u) * (1 + 0.5 * j))
kw = dict(model_name="cmp", damping_ratio=0.03, pinion_speed_start_rad_s=80.0, pinion_torque_start_Nm=20.0,
          max_step_s=4e-6, stop_time_s=2e-3, output_interval_s=1e-4, damping_model="contact_zone",
          scene_text="# compare_fmus\n")
keys = crossbuild.parse_platforms(None if platforms == "all" else platforms)
o = Path(out)
_count[0] = 0
build_fmu(tables, o / "pythonfmu_fmi2.fmu", **kw)
for v in (2, 3):
    _count[0] = 0
    build_standalone_fmu(tables, o / f"standalone_fmi{v}.fmu", fmi_version=v, platforms=keys, **kw)
print(gearfmu.__file__)
'''

TIMINGS = {"resources/validation/record.json": ("reference", "native_wall_s")}


def build(checkout: Path, out: Path, platforms: str) -> str:
    out.mkdir(parents=True, exist_ok=True)
    res = subprocess.run([sys.executable, "-c", CHILD, str(checkout), str(out), platforms],
                         cwd=tempfile.gettempdir(), capture_output=True, text=True)
    if res.returncode != 0:
        raise SystemExit(f"{checkout}: the child build failed:\n{res.stderr[-4000:]}")
    return res.stdout.strip().splitlines()[-1]


def members(path: Path):
    """[(name, compress_type, bytes)] in the zip's order, timings blanked (:data:`TIMINGS`)."""
    out = []
    with zipfile.ZipFile(path) as z:
        for info in z.infolist():
            data = z.read(info)
            if info.filename in TIMINGS:
                rec = json.loads(data)
                outer, key = TIMINGS[info.filename]
                rec[outer][key] = None
                data = json.dumps(rec, indent=1).encode("utf-8")
            out.append((info.filename, info.compress_type, data))
    return out


def compare(a: Path, b: Path):
    """(byte-identical files, identical member by member, differing member names)."""
    ma, mb = members(a), members(b)
    names_a, names_b = [m[0] for m in ma], [m[0] for m in mb]
    if names_a != names_b:
        diff = sorted(set(names_a) ^ set(names_b)) or ["(member order differs)"]
        return a.read_bytes() == b.read_bytes(), False, diff
    diff = [x[0] for x, y in zip(ma, mb) if x != y]
    return a.read_bytes() == b.read_bytes(), not diff, diff


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("a", type=Path)
    ap.add_argument("b", type=Path)
    ap.add_argument("--platforms", default="host", help="crossbuild keys (comma-separated), 'all', or 'host'")
    ap.add_argument("--keep", type=Path, help="keep the built FMUs in this folder")
    args = ap.parse_args(argv)
    platforms = args.platforms
    if platforms == "host":
        sys.path.insert(0, str(args.a.resolve()))
        from gearfmu.fmu.crossbuild import host_key
        platforms = host_key() or "all"
    with tempfile.TemporaryDirectory() as d:
        root = args.keep or Path(d)
        where = {tag: build(p.resolve(), root / tag, platforms) for tag, p in (("A", args.a), ("B", args.b))}
        print(f"A: {where['A']}\nB: {where['B']}\nplatforms: {platforms}")
        ok = True
        for fmu in sorted(p.name for p in (root / "A").glob("*.fmu")):
            same_file, same_members, diff = compare(root / "A" / fmu, root / "B" / fmu)
            n = len(members(root / "A" / fmu))
            ok &= same_members
            print(f"{fmu:24s} {n:3d} members  file bytes {'identical' if same_file else 'differ'}  "
                  f"members {'identical' if same_members else 'DIFFER: ' + ', '.join(diff)}")
    print("identical member by member" if ok else "DIFFERENT")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
