"""Evaluators beyond one process: a process pool and a Dask cluster.

Every evaluator exposes the same small interface as
:class:`gpmotion.inprocess.InProcessEvaluator`::

    ev = make_evaluator(task, family, workers=4)          # or scheduler="local"
    result = ev.evaluate(genomes, progress=0.5)           # -> Evaluation, in genome order
    ev.evaluations                                        # genomes evaluated so far
    ev.close()                                            # or use ``with``

Genomes leave this process as JSON-safe plain data (``family.to_json``);
workers rebuild the evaluator from :func:`gpmotion.inprocess.spec_of` (cached
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

Losing the Dask scheduler: the client waits ``reconnect_grace`` seconds for
it to come back (a restarted scheduler at the same address), then re-warms the
workers and resubmits the unfinished chunks; otherwise :class:`SchedulerLost`
(the command exits with code 3; the checkpoint of the last generation is
intact).  With no worker connected the evaluator says that it is waiting.

Pool workers die with the run: on Linux the kernel sends them SIGKILL when
the process that started them dies (``PR_SET_PDEATHSIG``), and everywhere a
watchdog thread exits a worker whose parent has gone; they ignore Ctrl-C
(SIGINT goes to the whole terminal's process group), so only the main process
reacts to it.
"""
from __future__ import annotations

import math
import os
import re
import signal
import statistics
import sys
import threading
import time
import uuid
from concurrent.futures import FIRST_EXCEPTION, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool

import numpy as np

from .evaluation import Evaluation
from .inprocess import InProcessEvaluator, evaluate_chunk, spec_of

__all__ = ["ProcessPoolEvaluator", "DaskEvaluator", "make_evaluator", "check_scheduler",
           "chunk_bounds", "plan_chunk_size", "usable_workers", "WorkerLost", "SchedulerLost",
           "DaskMissing", "DASK_MISSING", "EXIT_SCHEDULER_LOST"]

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


# Exit code of a command whose Dask scheduler went away for good (README, "Clusters").
EXIT_SCHEDULER_LOST = 3
# Seconds a lost scheduler has to come back; seconds to reach it at the start.
# (GPMOTION_RECONNECT_GRACE overrides the grace: a batch job may rather fail fast.)
RECONNECT_GRACE = 30.0
CONNECT_TIMEOUT = 10.0
# Seconds between checks that any worker is connected while a batch waits.
IDLE_POLL = 5.0


class WorkerLost(RuntimeError):
    """Workers kept dying: the batch could not be finished within the retry budget."""
    exit_code = 2


class DaskMissing(ImportError):
    """The dask backend is not installed (a setup problem: one line, exit 2)."""
    exit_code = 2


class SchedulerLost(RuntimeError):
    """The Dask scheduler went away and did not come back within the grace period."""
    exit_code = EXIT_SCHEDULER_LOST


def _say(msg: str) -> None:
    print(f"gpmotion: {msg}", file=sys.stderr, flush=True)


def usable_workers(requested: int, n: int | None = None) -> int:
    """Worker processes worth starting: no more than the CPUs this process may
    use (each worker runs one thread) nor than the genomes of a batch."""
    try:
        cpus = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        cpus = os.cpu_count() or 1
    return max(1, min(requested, cpus, n if n else requested))


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

COMPILE_TOPIC = "gpmotion-cold-compile"      # Dask event: a worker compiles a kernel cold

_CHUNK_LOCK = threading.Lock()


def _limit_threads():
    """One compute thread per worker process: the parallelism is the processes.

    The spawned child imported numba (through gpmotion) before any initializer
    ran, so the environment alone is too late: reload numba's config, which
    :func:`gpmotion.sim.threads.default_threads` reads, and shrink numba's own
    pool if it is not launched yet.  ``threads=1`` on every chunk is the backstop.
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


def _die_with_parent(parent_pid: int, kernel_signal: bool) -> None:
    """Make this pool worker exit when the run's process dies (even by SIGKILL).

    Linux: PR_SET_PDEATHSIG (only when the pool was started from the main
    thread: the signal fires when the *thread* that started us ends).  Everywhere:
    a daemon thread that exits once our parent is gone (we are re-parented).
    """
    if kernel_signal and sys.platform.startswith("linux"):
        try:
            import ctypes
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)            # 1 = PR_SET_PDEATHSIG
        except (OSError, AttributeError):                          # pragma: no cover - no libc
            pass
    if os.getppid() != parent_pid:                                  # died before we got here
        os._exit(1)

    def watch():
        while os.getppid() == parent_pid:
            time.sleep(0.5)
        os._exit(1)
    threading.Thread(target=watch, name="gpmotion-parent-watch", daemon=True).start()


def _init_worker(spec: dict, parent_pid: int | None = None, kernel_signal: bool = True,
                 notes=None):
    """Process-pool initializer: die with the parent, ignore Ctrl-C, threads,
    imports, evaluator built (no simulation); a cold compile is told to the
    parent on ``notes`` (a queue), which says so while it waits."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)   # the main process checkpoints and stops us
    if parent_pid is not None:
        _die_with_parent(parent_pid, kernel_signal)
    if notes is not None:
        from .compile_events import forward_cold_compiles
        forward_cold_compiles(lambda path: notes.put(str(path)))
    _limit_threads()
    from .inprocess import evaluator_from_spec
    evaluator_from_spec(spec, threads=1)


def _run_chunk(spec: dict, genomes_json: list, progress: float, generation: int = 0):
    """Evaluate one chunk in a worker; returns (Evaluation, seconds of work)."""
    with _CHUNK_LOCK:          # one chunk at a time per worker: its one compute thread
        t0 = time.perf_counter()
        result = evaluate_chunk(spec, genomes_json, progress, threads=1, generation=generation)
        return result, time.perf_counter() - t0


def _warm_worker(spec: dict, dask_worker=None) -> int:
    """Dask: limit threads, build the evaluator and compile/load the kernels once;
    a cold compile is told to the client as a ``COMPILE_TOPIC`` event
    (``dask_worker``: the worker, as ``Client.run`` passes it)."""
    _limit_threads()
    if dask_worker is not None:
        from .compile_events import forward_cold_compiles
        forward_cold_compiles(lambda path: dask_worker.log_event(COMPILE_TOPIC, str(path)))
    from .inprocess import evaluator_from_spec
    evaluator_from_spec(spec, threads=1)
    return os.getpid()


def _noop(x=None):
    return x


# ---- shared client side ---------------------------------------------------------

class _ChunkedEvaluator:
    """Common bookkeeping: spec, JSON encoding, chunk planning, reassembly."""

    target_task_seconds = TARGET_TASK_SECONDS     # least work per task for this backend's overhead

    def __init__(self, task, family, workers, actuation, chunk_size, plugins, max_retries,
                 robust=None):
        from .plugins import loaded, require, sources_of
        plugins = loaded() if plugins is None else plugins     # default: all the user loaded
        self.task = task
        self.family = family
        self.workers = workers
        self.actuation = actuation or family.default_actuation
        self.chunk_size = _check_chunk_size(chunk_size)
        self.plugins = require(list(plugins), "the evaluator's plugins")   # records, loaded already
        if isinstance(max_retries, bool) or not isinstance(max_retries, int) or max_retries < 0:
            raise ValueError(f"max_retries must be an integer >= 0, got {max_retries!r}")
        self.max_retries = max_retries
        self.spec = spec_of(task, family, self.actuation, self.plugins, robust)
        self.spec["plugin_sources"] = sources_of(self.plugins)     # workers need no shared disk
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

    def evaluate(self, genomes, progress: float = 1.0, generation: int = 0) -> Evaluation:
        genomes = list(genomes)
        if not genomes:
            return Evaluation(np.zeros(0), np.zeros(0, bool), np.zeros(0, bool), {}, [])
        payload = [self.family.to_json(g) for g in genomes]
        bounds = self._plan(len(payload))
        chunks = [payload[a:b] for a, b in bounds]
        self._generation = int(generation)       # the chunks' perturbed starts (robust runs)
        parts = self._run(chunks, float(progress))
        self._learn([(sec, len(c)) for (_, sec), c in zip(parts, chunks)])
        result = Evaluation.concat([p for p, _ in parts])
        if len(result.costs) != len(genomes):          # never hand back a misaligned result
            raise RuntimeError(f"evaluator returned {len(result.costs)} scores for {len(genomes)} genomes")
        self.evaluations += len(genomes)
        return result

    def _chunk_args(self, chunk, progress) -> tuple:
        """_run_chunk's arguments; a robust run's chunks also need the generation (its starts)."""
        robust = "robust" in self.spec
        return (self.spec, chunk, progress) + ((self._generation,) if robust else ())

    def _run(self, chunks, progress):
        raise NotImplementedError

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


# ---- process pool ------------------------------------------------------------------

class ProcessPoolEvaluator(_ChunkedEvaluator):
    """Chunks of a batch on a pool of spawned worker processes, one compute thread each.

    The pool is started lazily on the first :meth:`evaluate` and kept for the
    following ones.  If a worker dies, the pool is rebuilt and the chunks that
    had not come back are resubmitted (up to ``max_retries`` rebuilds per batch).
    """

    def __init__(self, task, family, workers: int, actuation=None, chunk_size=None, plugins=None,
                 max_retries: int = 3, quiet: bool = False, robust=None):
        requested = _check_workers(workers)
        super().__init__(task, family, usable_workers(requested), actuation, chunk_size, plugins,
                         max_retries, robust)
        self.requested_workers = requested
        self.quiet = quiet
        if self.workers < requested and not quiet:
            _say(f"--workers {requested}: using {self.workers}, the CPUs this process may use "
                 "(each worker runs one thread)")
        self._executor = None
        self._chunk_function = _run_chunk
        self._executor_factory = self._spawn_pool

    def _spawn_pool(self):
        import multiprocessing
        main = threading.current_thread() is threading.main_thread()
        ctx = multiprocessing.get_context("spawn")
        if getattr(self, "_notes", None) is None:        # workers' cold compiles, relayed
            self._notes = ctx.Queue()
            threading.Thread(target=_relay_notes, args=(self._notes,), daemon=True,
                             name="gpmotion-compile-notes").start()
        return ProcessPoolExecutor(max_workers=self.workers, mp_context=ctx,
                                   initializer=_init_worker,
                                   initargs=(self.spec, os.getpid(), main, self._notes))
        # Processes start on demand, one per waiting chunk: never more than a batch's chunks.

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
                    futures[self._executor.submit(self._chunk_function,
                                                  *self._chunk_args(chunks[i], progress))] = i
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
        notes, self._notes = getattr(self, "_notes", None), None
        if notes is not None:
            notes.put(None)                              # ends the relay thread

    def __del__(self):
        try:
            self._discard_pool()
        except Exception:
            pass


def _relay_notes(notes) -> None:
    """The parent's side of the workers' cold-compile notes (None ends it)."""
    from .compile_events import tell_cold_compile
    while True:
        try:
            path = notes.get()
        except (EOFError, OSError, ValueError):
            return
        if path is None:
            return
        tell_cold_compile(path)


# ---- Dask --------------------------------------------------------------------------

def _import_distributed():
    try:
        import distributed
    except ImportError as e:                       # pragma: no cover - depends on the install
        raise DaskMissing(DASK_MISSING) from e
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


def make_security(scheduler: str, tls_ca_file=None, tls_cert=None, tls_key=None):
    """distributed ``Security`` for this client, or None for plain tcp://.

    ``local``: a throwaway self-signed certificate (``Security.temporary``) when
    ``cryptography`` is installed, so no other user of the machine can submit
    code to the local cluster's workers.  ``tls://``: the given PEM files, or
    distributed's own config (``distributed.comm.tls.*``) for those not given.
    """
    files = {"tls_ca_file": tls_ca_file, "tls_client_cert": tls_cert, "tls_client_key": tls_key}
    given = {k: v for k, v in files.items() if v}
    for k, v in given.items():
        if not os.path.isfile(v):
            raise ValueError(f"--{k.replace('_client', '').replace('_', '-')}: no such file: {v}")
    if scheduler == "local":
        if given:
            raise ValueError("--tls-* files are for a tls:// scheduler; a local cluster makes its own")
        try:
            from distributed.security import Security
            return Security.temporary()
        except ImportError:                         # no cryptography: loopback-only tcp
            return None
    if not scheduler.startswith(("tls://", "wss://")):
        if given:
            raise ValueError(f"--tls-* files given but the scheduler address {scheduler} is not "
                             "tls://: use tls://HOST:PORT")
        return None
    from distributed.security import Security
    sec = Security(require_encryption=True, **given)
    if not sec.tls_ca_file:
        raise ValueError(f"{scheduler}: TLS needs a CA certificate: --tls-ca-file PEM "
                         "(or distributed.comm.tls.ca-file in the Dask config)")
    return sec


class DaskEvaluator(_ChunkedEvaluator):
    """Chunks of a batch as Dask tasks on a local or remote cluster.

    ``scheduler="local"`` starts a :class:`distributed.LocalCluster` of
    ``workers`` single-threaded worker processes bound to 127.0.0.1 (no
    dashboard; TLS with a throwaway certificate when ``cryptography`` is
    installed); an address connects a :class:`distributed.Client` to an
    existing scheduler (start its workers with ``--nthreads 1`` and
    ``NUMBA_NUM_THREADS=1``; workers with more threads still evaluate one chunk
    at a time per process).  ``tls://`` addresses take ``tls_ca_file``,
    ``tls_cert`` and ``tls_key`` (PEM files); ``local_tls=False`` makes a local
    cluster plain tcp on loopback (benchmarks).  Workers are warmed once
    (imports, evaluator, numba kernels).  A task whose worker dies is
    rescheduled by Dask; a chunk that still fails with ``KilledWorker`` is
    resubmitted up to ``max_retries`` times.  A lost scheduler has
    ``reconnect_grace`` seconds to come back (see the module docstring).
    """

    # A Dask task costs ~2 ms of scheduler time and ~10 ms round trip (benchmarks/evaluators.py):
    # give each task >= 0.1 s of work.
    target_task_seconds = 0.1

    def __init__(self, task, family, scheduler: str = "local", workers: int = 2, actuation=None,
                 chunk_size=None, plugins=None, max_retries: int = 3,
                 timeout: float = CONNECT_TIMEOUT, reconnect_grace: float | None = None,
                 tls_ca_file=None, tls_cert=None, tls_key=None, quiet: bool = False,
                 local_tls: bool = True, robust=None):
        scheduler = check_scheduler(scheduler)
        workers = _check_workers(workers)
        if scheduler == "local":
            capped = usable_workers(workers)
            if capped < workers and not quiet:
                _say(f"--workers {workers}: using {capped}, the CPUs this process may use "
                     "(each worker runs one thread)")
            workers = capped
        super().__init__(task, family, workers, actuation, chunk_size, plugins, max_retries, robust)
        distributed = _import_distributed()
        import logging      # our one line (SchedulerLost) replaces the client's reconnect errors
        logging.getLogger("distributed.client").setLevel(logging.CRITICAL)
        self.security = (make_security(scheduler, tls_ca_file, tls_cert, tls_key)
                         if scheduler != "local" or local_tls else None)
        self.scheduler = scheduler
        self.reconnect_grace = _grace(reconnect_grace)
        self.quiet = quiet
        self._cluster = None
        self._client = None
        self._token = uuid.uuid4().hex[:12]
        self._batch = 0
        try:
            if scheduler == "local":
                tls = self.security is not None
                self._cluster = distributed.LocalCluster(
                    n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                    dashboard_address=None, env=dict(_WORKER_ENV),
                    protocol="tls://" if tls else "tcp://", security=self.security,
                    # no dashboard; its bare HTTP endpoints on a free loopback port, not :8787
                    scheduler_kwargs={"dashboard": False, "dashboard_address": "127.0.0.1:0"})
                self._client = distributed.Client(self._cluster, timeout=timeout,
                                                  security=self.security)
                # the cluster returns once its workers have started, not registered:
                # without the wait, a loaded machine warmed (and counted) none of them
                self._client.wait_for_workers(workers, timeout=timeout)
            else:
                self._client = self._connect(scheduler, timeout)
            self._client._timeout = self.reconnect_grace     # how long the client itself retries
            from .compile_events import tell_cold_compile
            self._client.subscribe_topic(COMPILE_TOPIC, lambda event: tell_cold_compile(event[1]))
            self._client.run(_warm_worker, self.spec)
            self.workers = max(1, len(self._client.scheduler_info().get("workers", {})) or workers)
        except Exception:
            self.close()
            raise

    def _connect(self, address: str, timeout: float):
        """A client on ``address``, or one ValueError line saying why not."""
        distributed = _import_distributed()
        try:
            return distributed.Client(address, timeout=timeout, security=self.security)
        except (OSError, TimeoutError) as e:
            why = str(e).splitlines()[0] if str(e) else type(e).__name__
            raise ValueError(f"cannot reach the Dask scheduler at {address} "
                             f"(within {timeout:g} s): {why[:200]}") from None

    @property
    def client(self):
        return self._client

    def worker_pids(self) -> dict[str, int]:
        return self._client.run(os.getpid)

    # ---- one batch ----

    def _run(self, chunks, progress):
        results: list = [None] * len(chunks)
        attempts = [0] * len(chunks)
        futures: dict = {}
        self._batch += 1
        self._idle_said = False
        try:
            while any(r is None for r in results):
                lost = False
                try:
                    for i in range(len(chunks)):
                        if results[i] is None and i not in futures:
                            futures[i] = self._submit(i, attempts[i], chunks[i], progress)
                    if self._hook_after_submit is not None:
                        self._hook_after_submit(self)
                    lost = self._collect(futures, results, attempts)
                except TimeoutError:
                    self._report_idle()
                except _connection_errors():
                    lost = True
                if lost or self._client is None or self._client.status != "running":
                    futures.clear()
                    self._await_scheduler()
        finally:
            for f in futures.values():
                try:
                    f.cancel()
                except Exception:                   # the client may be gone: nothing to cancel
                    pass
        return results

    def _submit(self, i, attempt, chunk, progress):
        key = f"gpmotion-eval-{self._token}-{self._batch}-{i}-{attempt}"
        return self._client.submit(_run_chunk, *self._chunk_args(chunk, progress), key=key, pure=False)

    def _collect(self, futures, results, attempts) -> bool:
        """Wait for some futures; store results, resubmit killed ones.  True if the scheduler was lost."""
        distributed = _import_distributed()
        from distributed import KilledWorker
        done = distributed.wait(list(futures.values()), timeout=IDLE_POLL,
                                return_when="FIRST_COMPLETED").done
        for i, f in list(futures.items()):
            if f not in done:
                continue
            if f.status == "finished":
                results[i] = f.result()
                del futures[i]
                self._idle_said = False
            elif f.status == "cancelled":          # the client cancels all when the scheduler goes
                return True
            else:
                exc = f.exception()
                if not isinstance(exc, KilledWorker):
                    raise exc                      # deterministic failure of the evaluation
                attempts[i] += 1
                self.restarts += 1
                if attempts[i] > self.max_retries:
                    raise WorkerLost(f"chunk {i} lost its worker {attempts[i]} times") from exc
                f.release()
                del futures[i]                     # resubmitted by the caller
        return False

    def _report_idle(self):
        """Say once per batch that no worker is connected (instead of silence); not
        while the scheduler itself is gone (its stale info lists no workers)."""
        if getattr(self._client, "status", None) != "running":
            return
        try:
            n = len(self._client.scheduler_info().get("workers", {}))
        except Exception:
            return
        if n == 0 and not self._idle_said:
            self._idle_said = True
            _say(f"no Dask workers connected to {self.scheduler}; waiting for workers "
                 "(Ctrl-C stops; the checkpoint of the last generation is kept)")

    def _await_scheduler(self):
        """The scheduler is gone: wait ``reconnect_grace`` s for it, re-warm, or raise SchedulerLost."""
        deadline = time.monotonic() + self.reconnect_grace
        _say(f"lost the Dask scheduler at {self.scheduler}; waiting up to "
             f"{self.reconnect_grace:g} s for it to come back")
        while time.monotonic() < deadline:
            client = self._client
            if client is not None and client.status == "running":
                try:
                    client.run(_warm_worker, self.spec)
                    _say(f"reconnected to {self.scheduler}; resubmitting the unfinished chunks")
                    return
                except _connection_errors():
                    pass
            elif client is None or client.status in ("closed", "closing"):
                self._reopen(deadline)
            time.sleep(0.2)
        raise SchedulerLost(f"lost the Dask scheduler at {self.scheduler} and it did not come back "
                            f"within {self.reconnect_grace:g} s")

    def _reopen(self, deadline):
        """The client gave up reconnecting: try a fresh one until the deadline."""
        if self.scheduler == "local":
            return
        old, self._client = self._client, None
        if old is not None:
            try:
                old.close(timeout=1)
            except Exception:
                pass
        try:
            self._client = self._connect(self.scheduler, max(0.5, min(2.0, deadline - time.monotonic())))
            self._client._timeout = self.reconnect_grace
        except ValueError:
            self._client = None

    def close(self):
        client, self._client = getattr(self, "_client", None), None
        cluster, self._cluster = getattr(self, "_cluster", None), None
        if client is not None:
            try:
                client.close(timeout=2)
            except Exception:
                pass
        if cluster is not None:
            try:
                cluster.close()
            except Exception:
                pass


def _grace(value) -> float:
    """Seconds a lost scheduler may take to come back: the argument, $GPMOTION_RECONNECT_GRACE
    or RECONNECT_GRACE."""
    name = "reconnect_grace"
    if value is None:
        value, name = os.environ.get("GPMOTION_RECONNECT_GRACE", RECONNECT_GRACE), "GPMOTION_RECONNECT_GRACE"
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number of seconds, got {value!r}") from None
    if not 0 <= value <= 86400:
        raise ValueError(f"{name} must be between 0 and 86400 seconds, got {value!r}")
    return value


def _connection_errors():
    """Exceptions that mean 'the scheduler connection is gone', not 'the evaluation failed'."""
    from concurrent.futures import CancelledError

    from distributed.client import FutureCancelledError
    from distributed.comm import CommClosedError
    try:
        from distributed.client import ClosedClientError
    except ImportError:                              # pragma: no cover - older distributed
        ClosedClientError = CommClosedError
    return (CancelledError, FutureCancelledError, CommClosedError, ClosedClientError, OSError)


# ---- choice ------------------------------------------------------------------------

def make_evaluator(task, family, *, workers: int = 0, scheduler: str | None = None, actuation=None,
                   threads: int | None = None, plugins=None, chunk_size=None, robust=None,
                   **dask_options):
    """The evaluator for ``--workers`` / ``--scheduler``.

    ``scheduler`` given → :class:`DaskEvaluator` (``workers`` = local cluster
    size, default 2; ``dask_options``: ``tls_ca_file``, ``tls_cert``,
    ``tls_key``, ``reconnect_grace``, ``timeout``); else ``workers > 1`` →
    :class:`ProcessPoolEvaluator`; else the in-process evaluator (numba
    threads; ``threads`` caps them).  ``plugins``: requirement records
    (default: every plugin loaded in this process).  ``robust``: a run's
    perturbed-start setting plus its ``seed`` (gpmotion.robust).
    """
    workers = _check_workers(workers, minimum=0)
    if threads is not None and (isinstance(threads, bool) or not isinstance(threads, int) or threads < 1):
        raise ValueError(f"threads must be a positive integer or None, got {threads!r}")
    if scheduler is not None:
        return DaskEvaluator(task, family, scheduler=scheduler, workers=workers or 2,
                             actuation=actuation, chunk_size=chunk_size, plugins=plugins,
                             robust=robust, **dask_options)
    if any(dask_options.get(k) for k in ("tls_ca_file", "tls_cert", "tls_key")):
        raise ValueError("--tls-* options need a tls:// --scheduler")
    if workers > 1:
        return ProcessPoolEvaluator(task, family, workers, actuation=actuation, chunk_size=chunk_size,
                                    plugins=plugins, robust=robust)
    return InProcessEvaluator(task, family, actuation, threads, robust)
