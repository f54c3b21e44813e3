"""Evaluators beyond one process: a process pool and a Dask cluster.

Every evaluator exposes the same small interface as
:class:`gpmotion.evaluate.InProcessEvaluator`::

    ev = make_evaluator(task, family, workers=4)          # or scheduler="local"
    result = ev.evaluate(genomes, progress=0.5)           # -> Evaluation, in genome order
    ev.evaluations                                        # genomes evaluated so far
    ev.close()                                            # or use ``with``

Genomes leave this process as JSON-safe plain data (``family.to_json``);
workers rebuild the evaluator from :func:`gpmotion.evaluate.spec_of` (cached
per process) and run the same numba rollout with one thread each.  Each
episode is simulated independently and deterministically, so the chunked,
reassembled result is bitwise identical to the in-process one, on any
backend and any chunk size.

Fault tolerance: a worker that dies mid-evaluation (OOM killer, SIGKILL, a
lost machine) does not change the result.  The process pool is rebuilt and
the unfinished chunks resubmitted; on Dask the scheduler reschedules a dead
worker's tasks on other workers and we resubmit a chunk that still ends up
``KilledWorker``.  Exceptions raised *by* the evaluation (a malformed genome)
are deterministic and propagate at once, without retries.
"""
from __future__ import annotations

import math
import os
import re
import statistics
import threading
import time
import uuid
from concurrent.futures import FIRST_EXCEPTION, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool

import numpy as np

from .evaluate import Evaluation, InProcessEvaluator, evaluate_chunk, spec_of

__all__ = ["ProcessPoolEvaluator", "DaskEvaluator", "make_evaluator", "check_scheduler",
           "chunk_bounds", "plan_chunk_size", "WorkerLost", "DASK_MISSING"]

DASK_MISSING = "the dask backend needs `pip install gpmotion[dask]`"

# Chunking targets: each task carries at least this much work, and a batch is
# split into about this many chunks per worker (load balance, fault granularity).
TARGET_TASK_SECONDS = 0.03
CHUNKS_PER_WORKER = 4
# A-priori cost of one simulation step of one episode on one core (measured on
# the planar lamp; refined from real chunk timings after the first batch).
PRIOR_SECONDS_PER_STEP = 1.5e-6

_WORKER_ENV = {"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1",
               "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}

_ADDRESS = re.compile(r"^(tcp|tls|ws|wss)://(\[[0-9a-fA-F:.]+\]|[A-Za-z0-9_.\-]+):(\d{1,5})$")


class WorkerLost(RuntimeError):
    """Workers kept dying: the batch could not be finished within the retry budget."""


# ---- chunking ----------------------------------------------------------------

def chunk_bounds(n: int, size: int) -> list[tuple[int, int]]:
    """Contiguous ``[start, stop)`` ranges of at most ``size`` covering ``range(n)`` in order."""
    if n < 0:
        raise ValueError(f"n must be >= 0, got {n}")
    if size < 1:
        raise ValueError(f"chunk size must be >= 1, got {size}")
    return [(s, min(s + size, n)) for s in range(0, n, size)]


def plan_chunk_size(n: int, workers: int, seconds_per_evaluation: float,
                    target_seconds: float = TARGET_TASK_SECONDS,
                    chunks_per_worker: int = CHUNKS_PER_WORKER) -> int:
    """Evaluations per task for a batch of ``n`` on ``workers`` workers.

    Aim for ``chunks_per_worker`` chunks per worker (load balance), but never
    less than ``target_seconds`` of work per task (so per-task overhead stays
    small); and never so large that a worker is left without a chunk.
    """
    if n <= 0:
        return 1
    workers = max(1, workers)
    balance = math.ceil(n / (chunks_per_worker * workers))
    overhead = math.ceil(target_seconds / max(seconds_per_evaluation, 1e-9))
    return max(1, min(max(balance, overhead), math.ceil(n / workers)))


def _check_chunk_size(chunk_size):
    if chunk_size is None:
        return None
    if isinstance(chunk_size, bool) or not isinstance(chunk_size, (int, np.integer)) or chunk_size < 1:
        raise ValueError(f"chunk_size must be a positive integer or None, got {chunk_size!r}")
    return int(chunk_size)


def _check_workers(workers, minimum=1):
    if isinstance(workers, bool) or not isinstance(workers, (int, np.integer)):
        raise ValueError(f"workers must be an integer, got {workers!r}")
    if workers < minimum:
        raise ValueError(f"workers must be >= {minimum}, got {workers}")
    return int(workers)


# ---- worker side -----------------------------------------------------------------

_CHUNK_LOCK = threading.Lock()


def _limit_threads():
    """One compute thread per worker process: the parallelism is the processes.

    The spawned child imported numba (through gpmotion) before any initializer
    ran, so the environment alone is too late for numba's pool size: reload the
    config and, if the thread pool is not launched yet, shrink it to one thread.
    ``threads=1`` on every chunk is the backstop if the pool was launched.
    """
    os.environ.update(_WORKER_ENV)
    try:
        import numba
        numba.config.reload_config()
        from numba.np.ufunc import parallel
        if not getattr(parallel, "_is_initialized", True):
            parallel.NUM_THREADS = 1
    except Exception:              # pragma: no cover - numba internals moved; threads=1 still applies
        pass


def _init_worker(spec: dict):
    """Process-pool initializer: threads, imports, evaluator built (no simulation)."""
    _limit_threads()
    from .evaluate import evaluator_from_spec
    evaluator_from_spec(spec, threads=1)


def _run_chunk(spec: dict, genomes_json: list, progress: float):
    """Evaluate one chunk in a worker; returns (Evaluation, seconds of work)."""
    with _CHUNK_LOCK:          # numba's threading layers are not re-entrant across threads
        t0 = time.perf_counter()
        result = evaluate_chunk(spec, genomes_json, progress, threads=1)
        return result, time.perf_counter() - t0


def _warm_worker(spec: dict) -> int:
    """Dask: limit threads, build the evaluator and compile/load the kernels once."""
    _limit_threads()
    from .evaluate import evaluator_from_spec
    evaluator_from_spec(spec, threads=1)
    return os.getpid()


def _noop(x=None):
    return x


# ---- shared client side ---------------------------------------------------------

class _ChunkedEvaluator:
    """Common bookkeeping: spec, JSON encoding, chunk planning, reassembly."""

    target_task_seconds = TARGET_TASK_SECONDS     # least work per task for this backend's overhead

    def __init__(self, task, family, workers, actuation, chunk_size, plugins, max_retries):
        self.task = task
        self.family = family
        self.workers = workers
        self.actuation = actuation or family.default_actuation
        self.chunk_size = _check_chunk_size(chunk_size)
        self.plugins = [os.path.abspath(os.fspath(p)) for p in plugins]
        if isinstance(max_retries, bool) or not isinstance(max_retries, int) or max_retries < 0:
            raise ValueError(f"max_retries must be an integer >= 0, got {max_retries!r}")
        self.max_retries = max_retries
        self.spec = spec_of(task, family, self.actuation, self.plugins)
        self.evaluations = 0
        self.restarts = 0                     # worker losses recovered from
        self.seconds_per_evaluation = PRIOR_SECONDS_PER_STEP * task.n_steps
        self.last_chunk_size = None
        self._hook_after_submit = None        # test hook: called with self after a batch is submitted

    def _plan(self, n: int) -> list[tuple[int, int]]:
        size = self.chunk_size or plan_chunk_size(n, self.workers, self.seconds_per_evaluation,
                                                  self.target_task_seconds)
        self.last_chunk_size = size
        return chunk_bounds(n, size)

    def _learn(self, timings):
        """Refine the per-evaluation cost from chunk timings (median: robust to a cold first chunk)."""
        rates = [sec / k for sec, k in timings if k > 0 and sec > 0]
        if rates:
            self.seconds_per_evaluation = statistics.median(rates)

    def evaluate(self, genomes, progress: float = 1.0) -> Evaluation:
        genomes = list(genomes)
        if not genomes:
            return Evaluation(np.zeros(0), np.zeros(0, bool), np.zeros(0, bool), {}, [])
        payload = [self.family.to_json(g) for g in genomes]
        bounds = self._plan(len(payload))
        chunks = [payload[a:b] for a, b in bounds]
        parts = self._run(chunks, float(progress))
        self._learn([(sec, len(c)) for (_, sec), c in zip(parts, chunks)])
        result = Evaluation.concat([p for p, _ in parts])
        if len(result.costs) != len(genomes):          # never hand back a misaligned result
            raise RuntimeError(f"evaluator returned {len(result.costs)} scores for {len(genomes)} genomes")
        self.evaluations += len(genomes)
        return result

    def _run(self, chunks, progress):
        raise NotImplementedError

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


# ---- process pool ------------------------------------------------------------------

class ProcessPoolEvaluator(_ChunkedEvaluator):
    """Chunks of a batch on a pool of spawned worker processes, one numba thread each.

    The pool is started lazily on the first :meth:`evaluate` and kept for the
    following ones.  If a worker dies, the pool is rebuilt and the chunks that
    had not come back are resubmitted (up to ``max_retries`` rebuilds per batch).
    """

    def __init__(self, task, family, workers: int, actuation=None, chunk_size=None, plugins=(),
                 max_retries: int = 3):
        super().__init__(task, family, _check_workers(workers), actuation, chunk_size, plugins,
                         max_retries)
        self._executor = None
        self._chunk_function = _run_chunk
        self._executor_factory = self._spawn_pool

    def _spawn_pool(self):
        import multiprocessing
        return ProcessPoolExecutor(max_workers=self.workers,
                                   mp_context=multiprocessing.get_context("spawn"),
                                   initializer=_init_worker, initargs=(self.spec,))

    def worker_pids(self) -> list[int]:
        """Process ids of the live pool's workers (empty before the first batch)."""
        procs = getattr(self._executor, "_processes", None) or {}
        return [p.pid for p in list(procs.values()) if p.pid is not None]

    def _run(self, chunks, progress):
        results: list = [None] * len(chunks)
        todo = list(range(len(chunks)))
        losses = 0
        while todo:
            if self._executor is None:
                self._executor = self._executor_factory()
            futures = {}
            try:
                for i in todo:
                    futures[self._executor.submit(self._chunk_function, self.spec, chunks[i], progress)] = i
            except BrokenProcessPool:
                pass                                   # handled below like a loss during the run
            if self._hook_after_submit is not None:
                self._hook_after_submit(self)
            broken = len(futures) < len(todo)
            pending = set(futures)
            while pending:
                done, pending = wait(pending, return_when=FIRST_EXCEPTION)
                for f in done:
                    exc = f.exception()
                    if exc is None:
                        results[futures[f]] = f.result()
                    elif isinstance(exc, BrokenProcessPool):
                        broken = True
                    else:                              # deterministic failure of the evaluation
                        for g in pending:
                            g.cancel()
                        raise exc
                if broken:
                    # Collect what already finished; the rest fails fast once broken.
                    wait(pending)
                    for f in pending:
                        if f.exception() is None:
                            results[futures[f]] = f.result()
                    pending = set()
            todo = [i for i in range(len(chunks)) if results[i] is None]
            if todo:
                losses += 1
                self.restarts += 1
                self._discard_pool()
                if losses > self.max_retries:
                    raise WorkerLost(f"process-pool workers died {losses} times in one batch; "
                                     f"{len(todo)} of {len(chunks)} chunks unfinished")
        return results

    def _discard_pool(self):
        ex, self._executor = self._executor, None
        if ex is not None:
            ex.shutdown(wait=True, cancel_futures=True)

    def close(self):
        self._discard_pool()

    def __del__(self):
        try:
            self._discard_pool()
        except Exception:
            pass


# ---- Dask --------------------------------------------------------------------------

def _import_distributed():
    try:
        import distributed
    except ImportError as e:                       # pragma: no cover - depends on the install
        raise ImportError(DASK_MISSING) from e
    return distributed


def check_scheduler(scheduler) -> str:
    """``'local'`` or a scheduler address ``scheme://host:port`` (tcp, tls, ws, wss)."""
    if not isinstance(scheduler, str) or not scheduler.strip():
        raise ValueError(f"scheduler must be 'local' or an address like tcp://host:8786, got {scheduler!r}")
    scheduler = scheduler.strip()
    if scheduler == "local":
        return scheduler
    m = _ADDRESS.match(scheduler)
    if not m or not 0 < int(m.group(3)) < 65536:
        raise ValueError(f"bad scheduler address {scheduler!r}: expected 'local' or "
                         f"tcp://host:port (also tls://, ws://, wss://), e.g. tcp://10.0.0.5:8786")
    return scheduler


class DaskEvaluator(_ChunkedEvaluator):
    """Chunks of a batch as Dask tasks on a local or remote cluster.

    ``scheduler="local"`` starts a :class:`distributed.LocalCluster` of
    ``workers`` single-threaded worker processes bound to 127.0.0.1 (no
    dashboard); an address connects a :class:`distributed.Client` to an existing
    scheduler (start its workers with ``--nthreads 1`` and
    ``NUMBA_NUM_THREADS=1``; workers with more threads still evaluate one chunk
    at a time per process).  Workers are warmed once (imports, evaluator, numba
    kernels).  A task whose worker dies is rescheduled by Dask; a chunk that
    still fails with ``KilledWorker`` is resubmitted up to ``max_retries`` times.
    """

    # A Dask task costs ~2 ms of scheduler time and ~10 ms round trip (benchmarks/evaluators.py):
    # give each task >= 0.1 s of work.
    target_task_seconds = 0.1

    def __init__(self, task, family, scheduler: str = "local", workers: int = 2, actuation=None,
                 chunk_size=None, plugins=(), max_retries: int = 3, timeout: float = 60.0):
        scheduler = check_scheduler(scheduler)
        workers = _check_workers(workers)
        super().__init__(task, family, workers, actuation, chunk_size, plugins, max_retries)
        distributed = _import_distributed()
        self.scheduler = scheduler
        self._cluster = None
        self._client = None
        self._token = uuid.uuid4().hex[:12]
        self._batch = 0
        try:
            if scheduler == "local":
                self._cluster = distributed.LocalCluster(
                    n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                    dashboard_address=None, env=dict(_WORKER_ENV),
                    # no dashboard; its bare HTTP endpoints on a free loopback port, not :8787
                    scheduler_kwargs={"dashboard": False, "dashboard_address": "127.0.0.1:0"})
                self._client = distributed.Client(self._cluster, timeout=timeout)
            else:
                self._client = distributed.Client(scheduler, timeout=timeout)
            self._client.run(_warm_worker, self.spec)
            self.workers = max(1, len(self._client.scheduler_info().get("workers", {})) or workers)
        except Exception:
            self.close()
            raise

    @property
    def client(self):
        return self._client

    def worker_pids(self) -> dict[str, int]:
        return self._client.run(os.getpid)

    def _run(self, chunks, progress):
        distributed = _import_distributed()
        from distributed import KilledWorker
        client = self._client
        self._batch += 1
        results: list = [None] * len(chunks)
        attempts = [0] * len(chunks)

        def submit(i):
            key = f"gpmotion-eval-{self._token}-{self._batch}-{i}-{attempts[i]}"
            return client.submit(_run_chunk, self.spec, chunks[i], progress, key=key, pure=False)

        futures = {i: submit(i) for i in range(len(chunks))}
        if self._hook_after_submit is not None:
            self._hook_after_submit(self)
        try:
            while futures:
                done = distributed.wait(list(futures.values()), return_when="FIRST_COMPLETED").done
                for i, f in list(futures.items()):
                    if f not in done:
                        continue
                    if f.status == "finished":
                        results[i] = f.result()
                        del futures[i]
                        continue
                    exc = f.exception() if f.status == "error" else None
                    if exc is not None and not isinstance(exc, KilledWorker):
                        raise exc                      # deterministic failure of the evaluation
                    attempts[i] += 1                   # killed worker or cancelled: resubmit
                    self.restarts += 1
                    if attempts[i] > self.max_retries:
                        raise WorkerLost(f"chunk {i} lost its worker {attempts[i]} times") from exc
                    f.release()
                    futures[i] = submit(i)
        finally:
            for f in futures.values():
                f.cancel()
        return results

    def close(self):
        client, self._client = getattr(self, "_client", None), None
        cluster, self._cluster = getattr(self, "_cluster", None), None
        if client is not None:
            try:
                client.close()
            except Exception:
                pass
        if cluster is not None:
            try:
                cluster.close()
            except Exception:
                pass


# ---- choice ------------------------------------------------------------------------

def make_evaluator(task, family, *, workers: int = 0, scheduler: str | None = None, actuation=None,
                   threads: int | None = None, plugins=(), chunk_size=None):
    """The evaluator for ``--workers`` / ``--scheduler``.

    ``scheduler`` given → :class:`DaskEvaluator` (``workers`` = local cluster
    size, default 2); else ``workers > 1`` → :class:`ProcessPoolEvaluator`;
    else the in-process evaluator (numba threads; ``threads`` caps them).
    """
    workers = _check_workers(workers, minimum=0)
    if threads is not None and (isinstance(threads, bool) or not isinstance(threads, int) or threads < 1):
        raise ValueError(f"threads must be a positive integer or None, got {threads!r}")
    if scheduler is not None:
        return DaskEvaluator(task, family, scheduler=scheduler, workers=workers or 2,
                             actuation=actuation, chunk_size=chunk_size, plugins=plugins)
    if workers > 1:
        return ProcessPoolEvaluator(task, family, workers, actuation=actuation, chunk_size=chunk_size,
                                    plugins=plugins)
    return InProcessEvaluator(task, family, actuation, threads)
