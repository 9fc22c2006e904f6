"""Progress bars: the one progress reporter of gearfmu (tqdm on stderr).

Every long computation that reports progress (table rows, film grids, film batches, sweeps,
plan searches) goes through :func:`progress_bar`, so that all bars look alike, go to stderr
(stdout stays free for results such as ``--json``) and cost nothing when not asked for.
"""
from __future__ import annotations

import sys
from typing import Iterable, Optional

from tqdm import tqdm

__all__ = ["progress_bar"]


class _Bar(tqdm):
    """tqdm without its monitor thread: every tqdm instance, even a disabled one, would
    otherwise start that thread, and a second thread in the process stops the local process
    pool from forking (gearfmu.common.executors._start_method)."""

    monitor_interval = 0


def progress_bar(iterable: Optional[Iterable] = None, desc: str = "", enabled: bool = True, *,
                 total: Optional[int] = None, unit: str = "it", leave: bool = True) -> tqdm:
    """A tqdm bar on stderr over ``iterable`` (or, with ``iterable`` None, a bar of ``total``
    steps advanced by ``update(n)``); ``desc`` names the work; ``enabled`` False gives a bar
    that prints nothing (it still iterates, counts and closes)."""
    return _Bar(iterable, desc=desc, total=total, unit=unit, leave=leave, file=sys.stderr,
                disable=not enabled, dynamic_ncols=True)
