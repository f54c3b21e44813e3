"""Cold compiles across processes, and how long they took.

:func:`gpmotion.cache.announce_compile` tells the listeners of
:func:`gpmotion.cache.on_cold_compile` in the process that compiles.  A run
whose workers compile (a process pool, Dask) hears of it through its
evaluator: the worker forwards each cold compile (:func:`forward_cold_compiles`)
and the run's process tells its own listeners (:func:`tell_cold_compile`).

How long the first generation took, compiling included, is kept per CPU model
and kind of run in ``compile-seconds.json`` in the cache root (across
versions: a new version compiles again), so the next cold compile's note
quotes a measured time, not a guess.  This module is apart from
:mod:`gpmotion.cache` on purpose: every rollout kernel's key hashes that
module's source, and the note's machinery must not recompile every kernel.
"""
from __future__ import annotations

import contextlib
import json
import os
from pathlib import Path

try:
    import fcntl
except ImportError:            # pragma: no cover - not POSIX: processes compile side by side
    fcntl = None

from . import cache

COMPILE_SECONDS = "compile-seconds.json"
_SEND: list = []           # in a worker process: the channel to the process it works for


def _forward(path) -> None:
    for send in list(_SEND):
        try:
            send(path)
        except Exception:          # a closed channel: the note is lost, never the compile
            pass


def forward_cold_compiles(send) -> None:
    """In a worker process: ``send(path)`` for each cold compile from now on
    (replaces an earlier channel; one listener however often it is called)."""
    _SEND[:] = [send]
    if _forward not in cache._COLD:
        cache._COLD.append(_forward)


def tell_cold_compile(path) -> None:
    """A worker's cold compile of ``path`` reached this process: tell its listeners."""
    for listener in cold_listeners():
        listener(path)


def cold_listeners() -> list:
    """This process's listeners (:func:`gpmotion.cache.on_cold_compile`), less the
    forwarder of a worker."""
    return [x for x in cache._COLD if x is not _forward]


def timings_path() -> Path:
    return cache.cache_root() / COMPILE_SECONDS


def _key(kind: str) -> str:
    return f"{cache._compile_target()[0].strip()} | {kind}"


def _read() -> dict:
    """{CPU | kind: seconds}; an unreadable or foreign file counts as empty (a cache)."""
    try:
        data = json.loads(timings_path().read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    if not isinstance(data, dict):
        return {}
    return {k: float(v) for k, v in data.items() if isinstance(k, str)
            and isinstance(v, (int, float)) and not isinstance(v, bool) and 0 < v < 1e6}


def compile_seconds(kind: str) -> float | None:
    """How long the first generation of ``kind`` took, compiling included, the last
    time its kernels compiled cold on a CPU of this model (None: never measured)."""
    return _read().get(_key(kind))


def record_compile_seconds(kind: str, seconds: float) -> None:
    """Remember ``seconds`` for :func:`compile_seconds` (atomically; a cache that
    cannot be written is no error)."""
    data = _read()
    data[_key(kind)] = round(float(seconds), 1)
    path = timings_path()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        tmp.write_text(json.dumps(data, indent=1, sort_keys=True) + "\n", encoding="utf-8")
        os.replace(tmp, path)
    except OSError:
        pass


@contextlib.contextmanager
def compile_lock(module_path):
    """One process at a time compiles or loads the kernel module at ``module_path``.

    Processes that start together on a cold cache (a process pool's workers, a
    study's) would each compile the same kernel, a minute of CPU and half a
    gigabyte each; with the lock one compiles and the others wait, then load
    what it cached.  An exclusive ``flock`` on ``<module>.lock`` beside it,
    released when its holder ends, however it ends; a folder where it cannot
    be taken only loses the wait, never the compile."""
    fd = None
    if fcntl is not None:
        try:
            fd = os.open(Path(module_path).with_suffix(".lock"), os.O_RDWR | os.O_CREAT, 0o666)
            fcntl.flock(fd, fcntl.LOCK_EX)
        except OSError:
            if fd is not None:
                os.close(fd)
            fd = None
    try:
        yield
    finally:
        if fd is not None:
            os.close(fd)
