"""What the benchmark scripts share: running independent jobs on one core or many."""
from __future__ import annotations

import multiprocessing as mp


def finished(fn, todo: list, workers: int):
    """``fn(job)`` for every job as each finishes: in this process for one worker
    (so Ctrl-C reaches the job itself), else from a pool of spawned processes
    (``fn`` must be importable by name; results arrive in finishing order)."""
    if workers == 1 or len(todo) <= 1:
        yield from map(fn, todo)
        return
    with mp.get_context("spawn").Pool(min(workers, len(todo))) as pool:
        yield from pool.imap_unordered(fn, todo)
