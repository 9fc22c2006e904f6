"""Progress on stderr: no long phase without a word (gearfmu.common.progress).

References: the schedule a test sets itself (a fake clock: the true time left is known), and the
order of the phases of `gearfmu validate` (tables, FMU build with its validation record, fmpy's
check and run, the native run; gearfmu.cli).  Wall times belong to benchmarks/bench_silence.py;
these tests check that each long phase announces itself before it starts, whatever the speed of
the machine.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
import time

import pytest

from gearfmu.common import progress
from gearfmu.common.jit import cache_is_cold
from gearfmu.common.progress import notice, progress_bar, reporting, ticking

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow


def _remaining_s(bar) -> float:
    d = bar.format_dict
    return (d["total"] - d["n"]) / d["rate"] if d["rate"] else float("inf")


@pytest.mark.parametrize("warmup_s", [0.0, 100.0, 300.0])
def test_time_left_is_within_3x_of_the_truth_after_a_slow_first_step(warmup_s, capsys):
    """100 steps of 1 s each in chunks of 10, the first chunk after ``warmup_s`` more (workers
    starting, code compiling).  From 10 % of the work on, the time left shown is unknown or within
    a factor 3 of the true one; after the second chunk it is known.  An average over the warm-up
    (tqdm's own rate) would promise up to 30 times too long."""
    clock = [0.0]
    bar = progress_bar(total=100, desc="films", enabled=True, unit="film")
    bar._time = lambda: clock[0]
    bar.start_t = bar.last_print_t = 0.0
    for k in range(10):
        clock[0] += 10.0 + (warmup_s if k == 0 else 0.0)
        bar.update(10)
        true = float(100 - bar.n)            # 1 s per remaining step
        shown = _remaining_s(bar)
        if k >= 1:
            assert shown != float("inf"), k
        if shown != float("inf") and true > 0:
            assert true / 3 <= shown <= 3 * true, (k, shown, true)
    bar.close()
    assert "films" in capsys.readouterr().err


def test_a_bar_without_time_left_shows_none():
    bar = progress_bar(total=4, desc="rows", enabled=True, eta=False)
    bar.update(1)
    text = bar.format_meter(**bar.format_dict)
    bar.close()
    assert "<" not in text and "?" not in text and "1/4" in text


def test_notices_follow_reporting_and_the_explicit_flag(capsys):
    notice("off by default")
    with reporting(True):
        notice("on in the block")
        notice("off when asked", enabled=False)
        with reporting(False):
            notice("off in -q")
    notice("on when asked", enabled=True)
    err = capsys.readouterr().err
    assert err.splitlines() == ["gearfmu: on in the block", "gearfmu: on when asked"]


def test_ticking_redraws_and_leaves_no_thread_behind(capsys):
    before = threading.active_count()
    with ticking("a long call", enabled=True, interval_s=0.05):
        time.sleep(0.3)
        assert threading.active_count() == before + 1
    assert threading.active_count() == before   # the local process pool may fork again
    err = capsys.readouterr().err
    assert err.count("gearfmu: a long call") >= 3   # redrawn while the call ran
    with ticking("silent", enabled=False):
        assert threading.active_count() == before
    assert capsys.readouterr().err == ""


def test_a_cold_numba_cache_is_told_and_a_warm_one_is_not(tmp_path):
    """Reference: numba itself -- a function compiled in one process is loaded from the cache
    by the next one (a fresh NUMBA_CACHE_DIR starts cold)."""
    mod = tmp_path / "jitmod.py"
    mod.write_text("from numba import njit\n\n@njit(cache=True)\ndef f(x):\n    return x + 1\n")
    code = ("import sys; sys.path.insert(0, %r); import jitmod; from gearfmu.common.jit import cache_is_cold; "
            "cold = cache_is_cold([jitmod.f]); jitmod.f(1); print(cold)" % str(tmp_path))
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "nb"))
    first = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    second = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert first.stdout.split() == ["True"] and second.stdout.split() == ["False"]
    assert cache_is_cold([object()]) is False      # cannot tell: no notice rather than a wrong one


def test_the_native_solver_says_when_it_compiles(monkeypatch, capsys):
    from gearfmu.dynamics import driver
    monkeypatch.setattr(driver, "_COMPILED", set())
    monkeypatch.setattr(driver, "cache_is_cold", lambda ds: True)
    with reporting(True):
        driver._warmup(0)
    assert "compiling the native solver (first run after installing or updating gearfmu" in capsys.readouterr().err
    monkeypatch.setattr(driver, "_COMPILED", set())
    monkeypatch.setattr(driver, "cache_is_cold", lambda ds: False)
    with reporting(True):
        driver._warmup(0)
    assert "compiling" not in capsys.readouterr().err


class _Watch:
    """A command in a fresh process with a reader thread stamping every stderr write."""

    def __init__(self, argv, env, cwd):
        self.chunks = []
        t0 = time.perf_counter()
        p = subprocess.Popen([sys.executable, "-m", "gearfmu.cli", *argv], env=env, cwd=cwd,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE)

        def read():
            while True:
                b = os.read(p.stderr.fileno(), 65536)
                if not b:
                    return
                self.chunks.append((time.perf_counter() - t0, b.decode("utf-8", "replace")))

        th = threading.Thread(target=read, daemon=True)
        th.start()
        self.stdout = p.stdout.read().decode()
        self.returncode = p.wait(timeout=900)
        th.join(10)
        self.err = "".join(b for _, b in self.chunks)

    def first(self, text: str) -> int:
        """Index of the first write that shows ``text`` (-1: none)."""
        return next((i for i, (_, b) in enumerate(self.chunks) if text in b), -1)

    def gaps(self) -> str:
        ts = [0.0] + [t for t, _ in self.chunks]
        return ", ".join(f"{b - a:.2f}" for a, b in zip(ts, ts[1:]) if b - a > 1.0)


def test_validate_announces_every_long_phase_in_order_and_keeps_stdout_json(tmp_path):
    """`gearfmu validate --json` on the default scene with an empty gearfmu cache: every long phase
    is announced on stderr before it runs, in the order it runs; stdout is the JSON report alone."""
    env = dict(os.environ, GEARFMU_CACHE_DIR=str(tmp_path / "cache"))
    env.pop("GEARFMU_NO_TABLE_CACHE", None)
    w = _Watch(["validate", "--json", "--stop-time", "0.005"], env, tmp_path)
    assert w.returncode == 0, w.err[-2000:]
    json.loads(w.stdout)
    phases = ["gearfmu tables", "building the FMU", "FMU binaries", "validation record: native reference run",
              "with fmpy's validation", "through fmpy", "native solver over"]
    at = [w.first(p) for p in phases]
    assert all(i >= 0 for i in at), dict(zip(phases, at))
    assert at == sorted(at), dict(zip(phases, at))
    # a second run reads the tables, the compiled objects and the reference result back, and says so
    w2 = _Watch(["validate", "--json", "--stop-time", "0.005"], env, tmp_path)
    assert w2.returncode == 0 and "tables read from the cache" in w2.err
    assert w2.first("validation record: native reference run") == -1
    # -q: the notices go, the JSON stays
    w3 = _Watch(["validate", "--json", "-q", "--stop-time", "0.005"], env, tmp_path)
    assert w3.returncode == 0 and "gearfmu:" not in w3.err, w3.err
    json.loads(w3.stdout)


def test_a_fresh_film_pool_names_the_compilation(monkeypatch, capsys):
    """The first film batch after installing gearfmu compiles the film solver in every worker;
    it says so before the bar sits at 0."""
    from gearfmu.ehl import mesh_film
    monkeypatch.setattr(mesh_film, "_film_solver_cold", lambda: True)
    mesh_film.map_chunks(lambda env, c: c, None, [[1], [2]], [1, 1], max_workers=1, progress=True)
    assert "compiling the EHL film solver" in capsys.readouterr().err
    assert progress  # the module under test
