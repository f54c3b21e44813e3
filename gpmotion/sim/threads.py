"""Threads for the compiled loops: a batch split into chunks of a ``nogil`` kernel.

Each kernel here takes ``lo, hi`` as its last two arguments and works on rows
``lo`` to ``hi - 1`` of its outputs only, so chunks run on any thread in any
order and give the results of one thread.  Python threads rather than numba's
``parallel=True``: a parallel loop compiles a wrapper of its own around the
body, which adds a sixth to a rollout kernel's cold compile
(docs/speed.md, "Compilation").
"""
from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import numba

CHUNKS_PER_THREAD = 4      # chunks handed to threads as they free up: an early end idles none

_POOL: dict = {}


def default_threads() -> int:
    """Threads a batch uses unless told: ``NUMBA_NUM_THREADS`` (the cores; 1 in a worker process)."""
    return max(1, int(numba.config.NUMBA_NUM_THREADS))


def run_chunks(kernel, args: tuple, n: int, threads: int | None = None) -> None:
    """``kernel(*args, lo, hi)`` over rows 0..n-1, on ``threads`` threads (capped
    at :func:`default_threads`); returns once every chunk has, raising the first
    chunk's error."""
    threads = min(threads or default_threads(), default_threads(), n)
    if threads <= 1:
        kernel(*args, 0, n)
        return
    size = -(-n // (threads * CHUNKS_PER_THREAD))
    pool = _thread_pool(threads)
    jobs = [pool.submit(kernel, *args, lo, min(n, lo + size)) for lo in range(0, n, size)]
    for job in jobs:           # every chunk finished before the outputs are read
        job.exception()
    for job in jobs:
        job.result()


def _thread_pool(threads: int) -> ThreadPoolExecutor:
    """One pool per thread count and process (a forked child starts its own)."""
    key = (os.getpid(), threads)
    if key not in _POOL:
        _POOL[key] = ThreadPoolExecutor(threads, thread_name_prefix="gpmotion-batch")
    return _POOL[key]
