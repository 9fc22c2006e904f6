"""The test suite's disk use stays bounded: a CI machine's disk can be small.

A Wine prefix holds copies of Wine's DLLs (about 0.7 GB); the tests that ran Windows binaries once
each kept their own in their tmp_path, and with the other tests' folders that filled a CI
machine's disk mid-run.  Every Wine prefix now comes from ``support.cross_tools.wine_env``, which
removes it afterwards, and pytest removes a passing test's tmp_path when the test ends.
"""
import re
import tomllib
from pathlib import Path

import support.cross_tools as cross_tools

TESTS = Path(__file__).resolve().parents[1]
ROOT = TESTS.parent


def test_no_test_makes_its_own_wine_prefix():
    """WINEPREFIX is set only in support/cross_tools.py (wine_env), never by a test file itself."""
    own = [str(p.relative_to(ROOT)) for p in TESTS.rglob("*.py")
           if p.name != "cross_tools.py" and re.search(r"WINEPREFIX\s*=", p.read_text(encoding="utf-8"))]
    assert own == []


def test_wine_env_removes_its_prefix(tmp_path, monkeypatch):
    """The prefix folder (filled here as Wine fills it) is gone after the block, also when the block fails."""
    monkeypatch.setattr(cross_tools, "wine", lambda: "wine")
    monkeypatch.setattr(cross_tools, "wineserver", lambda: None)
    for fail in (False, True):
        try:
            with cross_tools.wine_env(tmp_path) as (w, env):
                prefix = Path(env["WINEPREFIX"])
                assert w == "wine" and prefix.parent == tmp_path
                (prefix / "drive_c" / "windows" / "system32").mkdir(parents=True)
                (prefix / "drive_c" / "windows" / "system32" / "kernel32.dll").write_bytes(b"\0" * 4096)
                if fail:
                    raise RuntimeError("the run failed")
        except RuntimeError:
            assert fail
        assert not prefix.exists()


def test_passing_tests_tmp_paths_are_removed():
    """pytest's tmp_path_retention_policy is 'failed': only a failing test's folder is kept."""
    opts = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]
    assert opts.get("tmp_path_retention_policy") == "failed"
