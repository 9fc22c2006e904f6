"""The shipped examples build what the README promises, and every build says what it built.

References (none produced by the code under test):
* the README's headline: the default FMU is the all-C standalone one, loadable without Python,
  i.e. modelDescription.xml's ``needsExecutionTool="false"`` (FMI 2.0 section 4.3.1);
* the default scene file gearfmu/scene/data/default_scene.toml: examples/scenes/seed000_table1.toml
  claims to be that scene, so an FMU built from one validates against the other;
* the FMU file itself, read here with zipfile and ElementTree: the FMI version attribute, the
  ``needsExecutionTool`` attribute and the folders under ``binaries/`` -- the one-line summary
  printed by the commands must name exactly those.
"""
import contextlib
import io
import os
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import pytest

from gearfmu.cli import main
from gearfmu.fmu import crossbuild
from gearfmu.fmu.standalone_build import (STANDALONE_CFLAGS, binary_sources, build_standalone_fmu, copy_sources,
                                          fmi_header_dir)
from gearfmu.scene.drivetrain import is_drivetrain_file
from gearfmu.scene.reader import default_scene_path, load_scene

from factories import make_tables

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

REPO = Path(__file__).resolve().parents[2]
#: the example pair scenes (the gearbox example, a drivetrain scene, has its own tests)
SCENES = sorted(p for p in (REPO / "examples" / "scenes").glob("*.toml") if not is_drivetrain_file(p))
FIVE = "platforms: linux64, aarch64-linux, win64, darwin64 (x86_64 + arm64; arm64 also as aarch64-darwin)"


def _cli(*args):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main([str(a) for a in args])
        except SystemExit as exc:  # argparse
            rc = exc.code
    return rc, out.getvalue(), err.getvalue()


def _fmu_facts(fmu):
    """(fmiVersion, needsExecutionTool, sorted binaries/ folders) read from the archive."""
    with zipfile.ZipFile(fmu) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
        folders = sorted({n.split("/")[1] for n in z.namelist() if n.startswith("binaries/") and n.count("/") == 2
                          and n.rsplit(".", 1)[-1] in ("so", "dll", "dylib")})
    cs = root.find("CoSimulation")
    return root.get("fmiVersion"), cs.get("needsExecutionTool"), folders


def _small_scene(tmp_path, **fmu):
    """The default scene with a coarse slicing and grid (cheap tables), as a file."""
    data = tomllib.loads(default_scene_path().read_text())
    text = default_scene_path().read_text().replace("slices = 44 ", "slices = 4 ").replace(
        "points_per_mesh = 64", "points_per_mesh = 32").replace('model_name = "GearPairSeed000"',
                                                                 'model_name = "SmallPair"')
    assert data["mesh"]["slices"] == 44 and "slices = 4 " in text
    p = tmp_path / "small.toml"
    p.write_text(text)
    return p


def test_seed000_example_is_the_default_scene_byte_for_byte():
    """docs/examples.md: `gearfmu validate examples/scenes/seed000_table1.toml --fmu
    build/GearPairSeed000.fmu` checks the FMU of `python build_fmu.py`; the FMU's validation
    record holds the SHA-256 of the scene text, so the two files must be the same bytes."""
    assert (REPO / "examples" / "scenes" / "seed000_table1.toml").read_bytes() == default_scene_path().read_bytes()


@pytest.mark.parametrize("path", SCENES, ids=[p.stem for p in SCENES])
def test_every_example_scene_builds_the_standalone_runtime(path):
    """The runtime `gearfmu build SCENE` uses is the scene's fmu.runtime: standalone for every
    shipped scene (a pythonfmu example would have to say so in its name)."""
    scene = load_scene(path)
    assert scene.fmu.runtime == "standalone" or "pythonfmu" in path.stem, path.name


def test_example_build_prints_runtime_fmi_version_and_platforms(tmp_path):
    """`gearfmu build examples/scenes/seed003_table1.toml` (docs/examples.md): an FMU that needs no
    Python (needsExecutionTool="false"), with the five binaries, and a stdout line saying so."""
    out = tmp_path / "s3.fmu"
    rc, stdout, stderr = _cli("build", REPO / "examples" / "scenes" / "seed003_table1.toml", "-o", out,
                              "--no-estimate", "-q")
    assert rc == 0, stderr
    version, needs, folders = _fmu_facts(out)
    assert (version, needs) == ("2.0", "false")
    assert folders == ["aarch64-darwin", "aarch64-linux", "darwin64", "linux64", "win64"]
    line = next(ln for ln in stdout.splitlines() if ln.startswith("runtime "))
    assert line == f"runtime standalone (all C, needs no Python), FMI 2.0 Co-Simulation and Model Exchange, {FIVE}", line


def test_ssp_takes_runtime_and_fmi_version(tmp_path):
    """`gearfmu ssp --runtime/--fmi-version/--platforms` choose the packaged FMU as they do for
    build, and the last line names what the package carries."""
    scene = _small_scene(tmp_path)
    rc, stdout, stderr = _cli("ssp", scene, "-o", tmp_path / "py.ssp", "--runtime", "pythonfmu", "-q")
    assert rc == 0, stderr
    with zipfile.ZipFile(tmp_path / "py.ssp") as z:
        (tmp_path / "py.fmu").write_bytes(z.read("resources/SmallPair.fmu"))
    assert _fmu_facts(tmp_path / "py.fmu")[:2] == ("2.0", "true")
    assert "its FMU (resources/SmallPair.fmu): runtime pythonfmu (needs Python 3 with numpy" in stdout

    rc, stdout, stderr = _cli("ssp", scene, "-o", tmp_path / "f3.ssp", "--fmi-version", "3",
                              "--platforms", "x86_64-linux", "-q")
    assert rc == 0, stderr
    with zipfile.ZipFile(tmp_path / "f3.ssp") as z:
        (tmp_path / "f3.fmu").write_bytes(z.read("resources/SmallPair.fmu"))
    assert _fmu_facts(tmp_path / "f3.fmu") == ("3.0", "false", ["x86_64-linux"])
    assert stdout.rstrip().endswith("runtime standalone (all C, needs no Python), FMI 3.0 Co-Simulation and Model Exchange, "
                                    "platforms: x86_64-linux")

    rc, _, stderr = _cli("ssp", scene, "-o", tmp_path / "bad.ssp", "--runtime", "pythonfmu", "--fmi-version", "3")
    assert rc == 2 and stderr.startswith("gearfmu: --fmi-version") and stderr.count("\n") == 1


def test_summary_names_platforms_not_built_and_why(monkeypatch, tmp_path):
    """Without a cross compiler the FMU carries the build machine's binary only; the summary line
    says which platforms are missing and why (the FMU's own provenance), on stdout."""
    from gearfmu.fmu.summary import fmu_summary, read_summary

    monkeypatch.setattr(crossbuild, "zig_command", lambda: None)
    p = build_standalone_fmu(make_tables(), tmp_path / "x.fmu", validation=False, max_step_s=1e-5,
                             platforms=("x86_64-linux", "x86_64-windows"))
    s = read_summary(p)
    assert s.platforms == ["linux64"] and set(s.missing) == {"x86_64-windows"}
    line = fmu_summary(p)
    assert line.startswith("runtime standalone (all C, needs no Python), FMI 2.0 Co-Simulation and Model Exchange, platforms: linux64; "
                           "NOT built: x86_64-windows (no cross compiler"), line


# ------------------------------------------------ zig's one-time preparation of a target
@pytest.fixture
def fresh_zig_cache(tmp_path, monkeypatch):
    zig = crossbuild.zig_command()
    if zig is None:
        pytest.fail("zig C compiler missing: pip install . (ziglang is a gearfmu dependency)")
    monkeypatch.setenv("ZIG_GLOBAL_CACHE_DIR", str(tmp_path / "zig-cache"))
    monkeypatch.setenv("GEARFMU_CACHE_DIR", str(tmp_path / "gearfmu-cache"))
    return zig


def test_first_use_of_a_target_is_announced_once(fresh_zig_cache):
    """A zig cache that has never linked for x86_64-linux: the preparation is announced and its end
    reported; the next build (same zig, same cache) says nothing."""
    zig = fresh_zig_cache
    assert crossbuild.zig_global_cache_dir(zig) == Path(os.environ["ZIG_GLOBAL_CACHE_DIR"])
    said = []
    assert crossbuild.prepare_targets(zig, ["x86_64-linux"], STANDALONE_CFLAGS, log=said.append) == {}
    assert said[0].startswith("gearfmu: preparing zig's x86_64-linux C runtime (one time per zig version"), said
    assert said[-1].startswith("gearfmu: zig's x86_64-linux C runtime ready ("), said
    said.clear()
    assert crossbuild.prepare_targets(zig, ["x86_64-linux"], STANDALONE_CFLAGS, log=said.append) == {}
    assert said == []


def test_a_target_zig_cannot_link_is_left_out_with_the_reason(fresh_zig_cache, monkeypatch, tmp_path):
    """One target fails its preparation: the others are built, the failed one is reported missing
    with zig's reason (what the build's summary line prints)."""
    real = crossbuild._probe_link

    def probe(zig, key, cflags):
        if key == "x86_64-windows":
            raise crossbuild.CrossBuildError("zig cannot link for x86_64-windows-gnu (exit status 1: no MinGW)")
        return real(zig, key, cflags)

    monkeypatch.setattr(crossbuild, "_probe_link", probe)
    said = []
    src = copy_sources(tmp_path / "src")
    rep = crossbuild.build_binaries(["x86_64-linux", "x86_64-windows"], src, tmp_path / "bin", "g",
                                    cflags=STANDALONE_CFLAGS, sources=binary_sources(), log=said.append,
                                    header_dir=fmi_header_dir(2))
    assert "missing" not in rep["x86_64-linux"] and (tmp_path / "bin" / "linux64" / "g.so").is_file()
    assert rep["x86_64-windows"] == {"missing": "zig cannot link for x86_64-windows-gnu (exit status 1: no MinGW)"}
    assert any("x86_64-windows: zig cannot link" in s for s in said), said
    assert "not built: x86_64-windows -- zig cannot link" in crossbuild.platform_summary(rep)
