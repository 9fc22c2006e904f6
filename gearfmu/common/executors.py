"""Executors for independent work items: in-process, a local process pool, or a Dask cluster.

Shared by the sweeps (:mod:`gearfmu.dynamics.sweeps`), the table precompute and the
film solutions along the mesh (:mod:`gearfmu.ehl.mesh_film`).
"""
from __future__ import annotations

import os
from concurrent.futures import Executor, ProcessPoolExecutor, Future
from typing import Optional
import multiprocessing as mp

__all__ = ["SweepInputError", "make_executor"]


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


class _ManagedExecutor:
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
      ``spawn`` start method.
    """
    if client is not None:
        return _ManagedExecutor(client.get_executor(pure=False), None, own=False)
    if scheduler is not None:
        if not isinstance(scheduler, str) or "://" not in scheduler:
            raise SweepInputError(f"scheduler: expected an address such as 'tcp://127.0.0.1:8786', got {scheduler!r}")
        try:
            from distributed import Client  # optional: the 'cluster' extra
        except ImportError:  # pragma: no cover - depends on the environment
            raise SweepInputError("scheduler: needs dask.distributed (pip install 'gearfmu[cluster]')") from None
        cl = Client(scheduler)
        return _ManagedExecutor(cl.get_executor(pure=False), cl, own=True)
    n = (os.cpu_count() or 1) if max_workers is None else int(max_workers)
    if n <= 1:
        return _ManagedExecutor(_InProcessExecutor(), None, own=True)

    return _ManagedExecutor(ProcessPoolExecutor(max_workers=n, mp_context=mp.get_context("spawn")), None, own=True)
