"""Executors for independent work items: in-process, a local process pool, or a Dask cluster.

Shared by the sweeps (:mod:`gearfmu.dynamics.sweeps`), the table precompute and the
film solutions along the mesh (:mod:`gearfmu.ehl.mesh_film`).  Inside a :func:`cluster`
block every local process pool that :func:`make_executor` would open is replaced by the
block's Dask cluster, so a whole command (``gearfmu tables``, ``build``, ``plan`` with
``--scheduler``) runs its parallel work there without passing an executor down every call.
"""
from __future__ import annotations

import argparse
import contextlib
import os
import re
import sys
from concurrent.futures import Executor, ProcessPoolExecutor, Future
from typing import Optional
import multiprocessing as mp
import warnings
import threading

__all__ = ["SweepInputError", "make_executor", "cluster", "add_scheduler_option", "ManagedExecutor"]

#: the Dask client of the innermost active :func:`cluster` block, or None
_cluster_client = None


class SweepInputError(ValueError):
    """Bad sweep argument; the message names the field and the reason."""


class _InProcessExecutor(Executor):
    """Runs each submission at once in the calling process (max_workers = 1)."""

    def submit(self, fn, *args, **kwargs):
        f = Future()
        try:
            f.set_result(fn(*args, **kwargs))
        except BaseException as exc:  # noqa: BLE001 -- handed to the caller via the future
            f.set_exception(exc)
        return f


class ManagedExecutor:
    """Context manager owning an executor (and a Dask client when it made one)."""

    def __init__(self, executor, client=None, own=True):
        self.executor = executor
        self.client = client
        self.own = own

    def __enter__(self):
        return self.executor

    def __exit__(self, *exc):
        if self.own:
            self.executor.shutdown(wait=True)
            if self.client is not None:
                self.client.close()
        return False


def make_executor(*, scheduler: Optional[str] = None, max_workers: Optional[int] = None, client=None):
    """A context manager yielding a ``concurrent.futures``-style executor.

    * ``client``: a ``distributed.Client`` -> its executor (``pure=False``); the
      client is left open.
    * ``scheduler``: a Dask scheduler address such as ``"tcp://127.0.0.1:8786"``
      -> a new Client on it (closed on exit).
    * otherwise ``max_workers`` <= 1 -> in-process (no parallelism); else a
      local process pool of ``max_workers`` (default: the CPU count) with the
      ``spawn`` start method, or 'fork' when the main module is a script without
      an ``if __name__ == "__main__":`` guard (:func:`_start_method`); inside a
      :func:`cluster` block the cluster's executor instead of that pool.
    """
    if client is not None:
        return ManagedExecutor(client.get_executor(pure=False), None, own=False)
    if scheduler is not None:
        cl = _connect(scheduler)
        return ManagedExecutor(cl.get_executor(pure=False), cl, own=True)
    if _cluster_client is not None and (max_workers is None or int(max_workers) > 1):
        # inside cluster(): the cluster instead of a local pool (whatever this machine's CPU count)
        return ManagedExecutor(_cluster_client.get_executor(pure=False), None, own=False)
    n = (os.cpu_count() or 1) if max_workers is None else int(max_workers)
    method = _start_method() if n > 1 else None
    if method is None:
        return ManagedExecutor(_InProcessExecutor(), None, own=True)

    return ManagedExecutor(ProcessPoolExecutor(max_workers=n, mp_context=mp.get_context(method)), None, own=True)


def _scheduler_address(value) -> str:
    """``value`` as a Dask scheduler address (SweepInputError naming the field otherwise)."""
    if not isinstance(value, str) or "://" not in value:
        raise SweepInputError(f"scheduler: expected an address such as 'tcp://127.0.0.1:8786', got {value!r}")
    return value


def _connect(scheduler: str):
    """A new ``distributed.Client`` on ``scheduler``; a bad or unreachable address is a
    SweepInputError naming the address and the reason."""
    _scheduler_address(scheduler)
    try:
        from distributed import Client  # optional: the 'cluster' extra
    except ImportError:  # pragma: no cover - depends on the environment
        raise SweepInputError("scheduler: needs dask.distributed (pip install 'gearfmu[cluster]')") from None
    try:
        return Client(scheduler)
    except (OSError, TimeoutError, ValueError) as exc:
        raise SweepInputError(f"scheduler: cannot connect to {scheduler}: {exc}") from None


@contextlib.contextmanager
def cluster(scheduler: Optional[str] = None, *, client=None):
    """Run the parallel work of the block on a Dask cluster: every :func:`make_executor`
    call that would open a local process pool (film grids, film batches, sweeps) gets the
    executor of one client on ``scheduler`` (an address such as ``"tcp://127.0.0.1:8786"``;
    closed at the end of the block) or of ``client`` (left open).  With neither, the block
    runs as without it.  The workers need gearfmu installed (same version)."""
    global _cluster_client
    if scheduler is None and client is None:
        yield None
        return
    cl = client if client is not None else _connect(scheduler)
    prev, _cluster_client = _cluster_client, cl
    try:
        yield cl
    finally:
        _cluster_client = prev
        if client is None:
            cl.close()


def add_scheduler_option(parser: argparse.ArgumentParser) -> None:
    """The ``--scheduler tcp://HOST:PORT`` option of the commands that can run on a Dask
    cluster (the value for :func:`cluster`)."""
    def address(value):
        try:
            return _scheduler_address(value)
        except SweepInputError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    parser.add_argument("--scheduler", metavar="tcp://HOST:PORT", type=address, default=None,
                        help="run the parallel work (EHL film grids and film solves of the tables, sweeps) on the "
                             "Dask cluster of this scheduler (docs/tables.md 'Progress and a Dask cluster')")


_MAIN_GUARD = re.compile(r"""^\s*if\s+(__name__\s*==\s*['"]__main__['"]|['"]__main__['"]\s*==\s*__name__)""",
                         re.M)
_warned_in_process = False


def _start_method() -> Optional[str]:
    """The start method of the local process pool, or None for in-process work.

    'spawn' (safe in threaded hosts) re-runs the main module in every worker, so it is
    used only when that is harmless: no main script (interactive, notebook, embedded) or
    one with an ``if __name__ == "__main__":`` guard.  A plain script without the guard
    would start the computation again inside each worker; for it the pool forks
    (the workers run pure numpy/numba functions) where 'fork' exists and the process
    runs one Python thread, else the work stays in this process with one warning.
    """
    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    if mp.parent_process() is not None or not path:
        return "spawn" if mp.parent_process() is None else None
    try:
        with open(path, encoding="utf-8", errors="replace") as fh:
            guarded = bool(_MAIN_GUARD.search(fh.read()))
    except OSError:
        guarded = False
    if guarded:
        return "spawn"
    if "fork" in mp.get_all_start_methods() and threading.active_count() == 1:
        return "fork"
    global _warned_in_process
    if not _warned_in_process:
        _warned_in_process = True

        warnings.warn(f"gearfmu: {path} has no 'if __name__ == \"__main__\":' guard, so the work runs in one "
                      "process; put the script's top-level code under that guard to get the worker processes "
                      "back", RuntimeWarning, stacklevel=3)
    return None
