"""What a run prints while it searches: one progress line per generation (at most
one a second), with the log row's numbers under the log's names, and a note
before a kernel compiles for the first time on this machine.

Generations are numbered as log.csv numbers them, from 0 (the first population
or working set) for every controller family.  ``evals/s`` is the recent rate:
evaluations per second over the last ``RATE_WINDOW_S`` seconds of wall time (at
least the last generation), not an average since the start, which the first
generation's compilation would drag down for the whole run.  log.csv records
the same number in its ``recent_evals_per_s`` column (the average since the
start is ``evaluations / elapsed_s``).  A log begun by an older gpmotion has an
``evals_per_s`` column instead, the average since the start: a resume goes on
filling it with that average, so each column keeps one meaning.
"""
from __future__ import annotations

import math
import sys
import threading
import time
from collections import deque

import numpy as np

RATE_WINDOW_S = 5.0          # evals/s is measured over about this much recent time
RATE_COLUMN = "recent_evals_per_s"          # log.csv: the progress line's evals/s
LEGACY_RATE_COLUMN = "evals_per_s"          # older logs: the average since the start


def rate_cell(rate: float, evals_total: int, elapsed: float, legacy: bool) -> dict:
    """log.csv's rate cell: the recent rate, or in a log begun with the legacy
    column, that column's own meaning (the average since the start)."""
    if legacy:
        return {LEGACY_RATE_COLUMN: round(evals_total / elapsed, 1) if elapsed > 0 else ""}
    return {RATE_COLUMN: round(rate, 1)}


class Progress:
    """Progress on stderr: one rewritten line on a terminal, plain lines otherwise,
    at most one every ``every`` seconds (a serial round takes milliseconds).
    ``last``: the number of the last generation (``search.last_generation``)."""

    def __init__(self, last: int, quiet: bool = False, every: float = 1.0):
        self.total, self.quiet, self.every = last, quiet, every
        self.t0 = time.perf_counter()
        self.evals = 0
        self.tty = sys.stderr.isatty()
        self._shown = -math.inf
        self._first = None            # (time, generation) after the first generation: no compile
        self._recent = deque([(self.t0, 0)])     # (time, evaluations so far)
        self._generations_seen = False

    def eta(self, gen: int, now: float) -> str:
        """From the pace since the first generation, once 3 more are done and 2 s passed."""
        if self._first is None:
            self._first = (now, gen)
            return "eta …"
        t1, g1 = self._first
        if gen - g1 < 3 or now - t1 < 2.0:
            return "eta …"
        eta = (now - t1) / (gen - g1) * max(0, self.total - gen)
        return f"eta {eta:,.0f}s"

    def rate(self, now: float) -> float:
        """Evaluations per second over the last ``RATE_WINDOW_S`` (at least the
        last generation), from the samples ``update`` keeps."""
        self._recent.append((now, self.evals))
        while len(self._recent) > 2 and now - self._recent[0][0] > RATE_WINDOW_S:
            self._recent.popleft()
        (t_a, n_a), (t_b, n_b) = self._recent[0], self._recent[-1]
        return (n_b - n_a) / (t_b - t_a) if t_b > t_a else 0.0

    def count(self, n: int, now: float | None = None) -> float:
        """``n`` evaluations just made; the recent rate (the log row's, too)."""
        self.evals += n
        return self.rate(time.perf_counter() if now is None else now)

    def update(self, gen: int, ev, best: float, row: dict | None = None,
               rate: float | None = None):
        """After a generation: ``gen`` its number (the log row's ``generation``);
        ``rate`` what :meth:`count` gave for it (counted here when None)."""
        now = time.perf_counter()
        if rate is None:
            rate = self.count(len(ev.costs), now)
        if not self._generations_seen:
            self._generations_seen = True
            first_generation_done()
        if self.quiet:
            return
        eta = self.eta(gen, now)
        last = gen >= self.total
        if now - self._shown < self.every and not last:
            return
        self._shown = now
        line = (f"gen {gen:>4}/{self.total}  {bests(row, best, ev)}  "
                f"solved {int(ev.success.sum())} of {len(ev.costs)} evaluated  "
                f"failed {int(ev.failed.sum())}  {rate:,.0f} evals/s  {eta}")
        if self.tty:
            print("\r" + line + "\033[K", end="\n" if last else "", file=sys.stderr, flush=True)
        else:
            print(line, file=sys.stderr, flush=True)


def bests(row: dict | None, best: float, ev) -> str:
    """The log row's numbers under its names: ``best so far`` and the median beside
    it under the current weights, ``best final`` under the final weights (– while
    unknown: a curriculum's scene is not final yet)."""
    row = row or {}
    now = row.get("best_so_far", best)
    median = row.get("gen_median", np.median(ev.costs))
    final = row.get("best_final")
    final_s = "–" if final in (None, "") else f"{float(final):.4f}"
    return f"best so far {float(now):.4f} (median {float(median):.4f})  best final {final_s}"


class CompileNote:
    """Says, before the first generation, that kernels are compiling for the first
    time on this machine (numba has no cache index for them yet, here or in a
    worker process), so the wait is minutes, not seconds; a listener of
    :func:`gpmotion.cache.on_cold_compile`.

    The estimate is a measurement, not a guess: how long the first generation of
    this kind of run (``kind``: figure and family) took, compiling included, the
    last time it compiled cold on a CPU of this model (after an upgrade or a
    cleared cache); never measured, the note says so and, for a run on a
    terminal, counts the seconds while it waits (until the first generation's
    end, :meth:`finish`, or the note stops listening).  That end prints how long
    it took and records it for the next time.  ``kind`` None (``check``): no
    count, nothing recorded."""

    TICK_S = 5.0

    def __init__(self, what: str, kind: str | None = None):
        self.what, self.kind = what, kind
        self.t0 = None
        self._done = False
        self._stop = None
        self._ticker = None

    def __call__(self, path) -> None:
        with _NOTE_LOCK:                  # workers' notes arrive on other threads
            if self.t0 is not None:
                return                    # one note for the run's wait
            self.t0 = time.perf_counter()
        from .cache import machine_dir
        from .compile_events import compile_seconds
        last = compile_seconds(self.kind) if self.kind else None
        took = (f"its first generation took {last:,.0f} s here last time, compiling included"
                if last else "minutes, the first time on this machine")
        print(f"compiling the {self.what} kernels ({took}; cached after, in {machine_dir()})",
              file=sys.stderr, flush=True)
        if self.kind and sys.stderr.isatty():
            self._stop = threading.Event()
            self._ticker = threading.Thread(target=self._tick, name="gpmotion-compile-note",
                                            daemon=True)
            self._ticker.start()

    def _tick(self) -> None:
        from .compile_events import cold_listeners
        while not self._stop.wait(self.TICK_S) and self in cold_listeners():
            print(f"\r  compiling… {time.perf_counter() - self.t0:,.0f} s\033[K", end="",
                  file=sys.stderr, flush=True)

    def finish(self, measured: bool = False) -> None:
        """Stop counting; ``measured`` (the first generation is done): say how long
        the wait was and record it for :func:`gpmotion.compile_events.compile_seconds`."""
        if self._ticker is not None:
            self._stop.set()
            self._ticker.join()
            self._ticker = None
            print("\r\033[K", end="", file=sys.stderr, flush=True)
        if measured and self.kind and self.t0 is not None and not self._done:
            self._done = True
            seconds = time.perf_counter() - self.t0
            from .compile_events import record_compile_seconds
            record_compile_seconds(self.kind, seconds)
            print(f"compiled the {self.what} kernels: the first generation took {seconds:,.0f} s;"
                  " cached now", file=sys.stderr, flush=True)


_NOTE_LOCK = threading.Lock()


def first_generation_done() -> None:
    """The first generation came back: its kernels are compiled (notes say so)."""
    from .compile_events import cold_listeners
    for listener in cold_listeners():
        if isinstance(listener, CompileNote):
            listener.finish(measured=True)
