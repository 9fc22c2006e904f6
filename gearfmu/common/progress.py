"""Progress on stderr: the one progress reporter of gearfmu (tqdm bars and one-line notices).

Every long computation that reports progress (table rows, film grids, film batches, sweeps,
plan searches) goes through :func:`progress_bar`, so that all bars look alike, go to stderr
(stdout stays free for results such as ``--json``) and cost nothing when not asked for.  A
phase without countable steps (a compilation, an FMU build, a run through fmpy) announces itself
with :func:`notice` before it starts; the command line turns the notices of the layers below on
with :func:`reporting` (off with ``-q``), a library call gets them only where it asks for
progress.

The time left that a bar shows is measured from its first step on: the first step of a batch
often carries a one-off cost (worker processes starting, numba loading or compiling its code),
and an average over it would promise many times the real remainder.  Until a second step has
finished the bar shows no time left ("?").
"""
from __future__ import annotations

import contextlib
import contextvars
import sys
import threading
import time
from concurrent.futures import FIRST_COMPLETED, wait
from typing import Iterable, Optional

from tqdm import tqdm

__all__ = ["progress_bar", "notice", "reporting", "reporting_enabled", "ticking", "wait_refreshing"]

_reporting: contextvars.ContextVar = contextvars.ContextVar("gearfmu_reporting", default=False)


@contextlib.contextmanager
def reporting(on: bool = True):
    """Within the block :func:`notice` prints by default (``on`` True; the command line's
    commands without ``-q``) or not (``on`` False)."""
    token = _reporting.set(bool(on))
    try:
        yield
    finally:
        _reporting.reset(token)


def reporting_enabled() -> bool:
    """True inside ``reporting(True)``."""
    return bool(_reporting.get())


def notice(message: str, enabled: Optional[bool] = None) -> None:
    """One line ``gearfmu: message`` on stderr (beside any open bar) when ``enabled``; None:
    when inside ``reporting(True)`` (outside any block: not)."""
    if not (_reporting.get() if enabled is None else enabled):
        return
    _Bar.write(f"gearfmu: {message}", file=sys.stderr)
    sys.stderr.flush()


class _Bar(tqdm):
    """tqdm without its monitor thread: every tqdm instance, even a disabled one, would
    otherwise start that thread, and a second thread in the process stops the local process
    pool from forking (gearfmu.common.executors._start_method).  Its rate (and so the time
    left) counts from the first finished step (module doc)."""

    monitor_interval = 0
    _first: Optional[tuple] = None

    @property
    def format_dict(self):
        d = super().format_dict
        if self.disable or not hasattr(self, "start_t"):
            return d
        now = self._time()
        if self._first is None:
            if self.n > self.initial:
                self._first = (now, self.n)
            d["rate"] = 0.0  # no time left until a step after the first has finished
            return d
        t1, n1 = self._first
        d["rate"] = (self.n - n1) / (now - t1) if self.n > n1 and now > t1 else 0.0
        return d


#: a bar without time left and rate: for steps of very unequal cost
_NO_ETA_FORMAT = "{l_bar}{bar}| {n_fmt}/{total_fmt} [{elapsed}{postfix}]"


def progress_bar(iterable: Optional[Iterable] = None, desc: str = "", enabled: bool = True, *,
                 total: Optional[int] = None, unit: str = "it", leave: bool = True, eta: bool = True) -> tqdm:
    """A tqdm bar on stderr over ``iterable`` (or, with ``iterable`` None, a bar of ``total``
    steps advanced by ``update(n)``); ``desc`` names the work; ``enabled`` False gives a bar
    that prints nothing (it still iterates, counts and closes).  ``eta`` False: no time left
    (steps of very unequal cost, e.g. table rows of which the first builds a film grid that
    the later ones reuse; the bars inside them show theirs).  ``refresh()`` redraws it
    (elapsed time) while a step runs."""
    return _Bar(iterable, desc=desc, total=total, unit=unit, leave=leave, file=sys.stderr,
                disable=not enabled, dynamic_ncols=True, bar_format=None if eta else _NO_ETA_FORMAT)


def wait_refreshing(futures, bar, interval_s: float = 1.0):
    """Yield the futures as they complete (as ``concurrent.futures.as_completed``), redrawing
    ``bar`` at least every ``interval_s`` seconds while none completes, so that a long first
    step (worker start, compilation) still shows the elapsed time move."""
    pending = set(futures)
    last = time.monotonic()
    while pending:
        done, pending = wait(pending, timeout=interval_s, return_when=FIRST_COMPLETED)
        for f in done:
            yield f
        if not done or time.monotonic() - last >= interval_s:
            if not bar.disable:
                bar.refresh()
            last = time.monotonic()


@contextlib.contextmanager
def ticking(desc: str, enabled: Optional[bool] = None, interval_s: float = 1.0):
    """A phase without countable steps (a compilation, a single long call): the line
    ``gearfmu: desc 00:12`` on stderr, its elapsed time redrawn every ``interval_s`` by a helper
    thread that ends with the block (so that no thread outlives it: a local process pool forks
    only in a one-thread process, gearfmu.common.executors; start no process pool inside).
    ``enabled``: as for :func:`notice`."""
    if not (_reporting.get() if enabled is None else enabled):
        yield
        return
    bar = _Bar(total=None, desc=f"gearfmu: {desc}", bar_format="{desc} {elapsed}", file=sys.stderr, leave=True,
               dynamic_ncols=True)
    stop = threading.Event()

    def tick():
        while not stop.wait(interval_s):
            bar.refresh()

    th = threading.Thread(target=tick, name="gearfmu-ticking", daemon=True)
    th.start()
    try:
        yield
    finally:
        stop.set()
        th.join()
        bar.close()
