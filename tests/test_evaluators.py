"""Process-pool and Dask evaluators: same result as in-process, bitwise, even when workers die."""
from __future__ import annotations

import os
import random
import signal
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from concurrent.futures.process import BrokenProcessPool

import numpy as np
import pytest
from deap import gp
from hypothesis import given, settings
from hypothesis import strategies as st

from gpmotion.evaluation import Evaluation
from gpmotion.inprocess import InProcessEvaluator
from gpmotion.evaluators import (DASK_MISSING, PRIOR_SECONDS_PER_STEP, DaskEvaluator, ProcessPoolEvaluator, WorkerLost,
                                 check_scheduler, chunk_bounds, make_evaluator, plan_chunk_size)
from gpmotion.families import make_family
from gpmotion.task import get_task

SECONDS = 0.3
N = 40


# ---- fixtures ---------------------------------------------------------------------

@pytest.fixture(scope="module")
def task():
    return get_task("lamp_hop", seconds=SECONDS)


def _gp_population(family, n, seed=0):
    random.seed(seed)
    return [[gp.PrimitiveTree(gp.genHalfAndHalf(family.pset, 1, 4)) for _ in family.actuators]
            for _ in range(n)]


def _bsr_population(family, n, seed=0):
    rng = np.random.default_rng(seed)
    return [family.random(rng) for _ in range(n)]


@pytest.fixture(scope="module", params=["gp", "bsr-time"])
def case(request, task):
    """(family, genomes, in-process reference Evaluation) for each family."""
    fam = make_family(request.param, task)
    pop = _gp_population(fam, N) if request.param == "gp" else _bsr_population(fam, N)
    ref = InProcessEvaluator(task, fam).evaluate(pop, progress=0.7)
    return fam, pop, ref


def assert_identical(got: Evaluation, ref: Evaluation):
    for name in ("costs", "success", "failed"):
        a, b = getattr(got, name), getattr(ref, name)
        assert a.dtype == b.dtype and a.shape == b.shape, name
        assert a.tobytes() == b.tobytes(), f"{name} differs"            # bitwise, NaN-safe
    assert sorted(got.measures) == sorted(ref.measures)
    for k in ref.measures:
        assert np.asarray(got.measures[k]).tobytes() == np.asarray(ref.measures[k]).tobytes(), k
    assert (got.extras is None) == (ref.extras is None)


# ---- process pool -------------------------------------------------------------------

def test_process_pool_matches_in_process(task, case):
    fam, pop, ref = case
    with ProcessPoolEvaluator(task, fam, workers=2, chunk_size=7) as ev:
        got = ev.evaluate(pop, progress=0.7)
        assert_identical(got, ref)
        again = ev.evaluate(pop, progress=0.7)                 # warm pool, default chunking
        assert_identical(again, ref)
        assert ev.evaluations == 2 * N and ev.restarts == 0


def test_process_pool_survives_killed_worker(task):
    fam = make_family("gp", task)
    pop = _gp_population(fam, 200, seed=3)
    ref = InProcessEvaluator(task, fam).evaluate(pop)
    killed = []

    def kill_one(ev):                                          # once; the hook runs every round
        if killed:
            return
        pid = ev.worker_pids()[0]
        os.kill(pid, signal.SIGKILL)
        killed.append(pid)

    with ProcessPoolEvaluator(task, fam, workers=2, chunk_size=10) as ev:
        ev.evaluate(pop[:4])                                   # warm: the kill lands mid-batch
        ev._hook_after_submit = kill_one
        got = ev.evaluate(pop)
        ev._hook_after_submit = None
        assert killed
        assert_identical(got, ref)
        assert_identical(ev.evaluate(pop), ref)                # the rebuilt pool keeps working
        # (on a heavily loaded machine the kill may land after the batch: then the next batch
        # finds the pool broken and recovers; either way exactly one loss is recovered from)
        assert ev.restarts == 1, ev.restarts
        assert killed[0] not in ev.worker_pids()


def test_worker_error_propagates_without_retry(task):
    fam = make_family("gp", task)
    bad = [[["no_such_primitive"]] * len(fam.actuators)]
    with ProcessPoolEvaluator(task, fam, workers=2) as ev:
        with pytest.raises(ValueError):
            ev.evaluate(bad)
        assert ev.restarts == 0


# ---- chunking and reassembly (cheap fake path: threads, fake family) -----------------------

class _FakeTask:
    name, id, params, n_steps = "fake", "fake-v1", {}, 300


class _FakeFamily:
    name, options, default_actuation = "fake", {}, "pd"

    def to_json(self, g):
        return int(g)


def _fake_chunk(spec, genomes_json, progress):
    x = np.asarray(genomes_json, dtype=np.float64)
    return Evaluation(x * 2.0, x % 2 == 0, x % 3 == 0, {"x": x}, None), 1e-4 * len(x)


def _fake_evaluator(chunk_size, fail_first=frozenset(), workers=3, max_retries=3):
    ev = ProcessPoolEvaluator(_FakeTask(), _FakeFamily(), workers=workers, chunk_size=chunk_size,
                              max_retries=max_retries)
    ev._executor_factory = lambda: ThreadPoolExecutor(max_workers=workers)
    ev.workers = workers                 # threads here: not capped at this machine's CPUs
    seen = set()

    def flaky(spec, genomes_json, progress):
        first = genomes_json[0]
        if first in fail_first and first not in seen:          # this chunk's worker "dies" once
            seen.add(first)
            time.sleep(0.001)
            raise BrokenProcessPool("worker died")
        return _fake_chunk(spec, genomes_json, progress)

    ev._chunk_function = flaky
    return ev


@settings(max_examples=60, deadline=None)
@given(n=st.integers(0, 300), size=st.integers(1, 64))
def test_chunk_bounds_cover_in_order(n, size):
    bounds = chunk_bounds(n, size)
    flat = [i for a, b in bounds for i in range(a, b)]
    assert flat == list(range(n))
    assert all(0 < b - a <= size for a, b in bounds)


@settings(max_examples=60, deadline=None)
@given(n=st.integers(1, 5000), workers=st.integers(1, 200), sec=st.floats(1e-6, 1.0))
def test_planned_chunk_size_is_sane(n, workers, sec):
    size = plan_chunk_size(n, workers, sec)
    assert 1 <= size <= max(1, -(-n // workers))               # every worker can get a chunk


@settings(max_examples=40, deadline=None)
@given(n=st.integers(1, 120), size=st.one_of(st.none(), st.integers(1, 40)), data=st.data())
def test_reassembly_in_order_with_lost_chunks(n, size, data):
    planned = size or plan_chunk_size(n, 3, PRIOR_SECONDS_PER_STEP * _FakeTask.n_steps)
    starts = [a for a, _ in chunk_bounds(n, planned)]
    fail = frozenset(data.draw(st.sets(st.sampled_from(starts), max_size=3)))
    ev = _fake_evaluator(size, fail_first=fail)
    try:
        got = ev.evaluate(range(n), progress=0.5)
    finally:
        ev.close()
    x = np.arange(n, dtype=np.float64)
    assert got.costs.tobytes() == (x * 2.0).tobytes()
    assert np.array_equal(got.measures["x"], x)
    assert ev.evaluations == n and ev.last_chunk_size == planned
    assert (ev.restarts >= 1) == bool(fail)


def test_gives_up_after_max_retries():
    ev = _fake_evaluator(4, max_retries=0)
    ev._chunk_function = lambda *a: (_ for _ in ()).throw(BrokenProcessPool("dead"))
    with pytest.raises(WorkerLost):
        ev.evaluate(range(10))
    ev.close()


# ---- argument checks ----------------------------------------------------------------------

@pytest.mark.parametrize("workers", [-1, -8, 1.5, "2", True])
def test_bad_workers(task, workers):
    fam = make_family("gp", task)
    with pytest.raises(ValueError, match="workers"):
        make_evaluator(task, fam, workers=workers)


@pytest.mark.parametrize("address", ["localhost:8786", "tcp://", "tcp://host", "tcp://host:0",
                                     "tcp://host:99999", "http://host:8786", "tcp://a b:1", "", " ", 8786])
def test_bad_scheduler_address(task, address):
    fam = make_family("gp", task)
    with pytest.raises(ValueError, match="scheduler"):
        make_evaluator(task, fam, scheduler=address)


@pytest.mark.parametrize("address", ["local", "tcp://127.0.0.1:8786", "tls://sched.example.org:8786",
                                     "tcp://[::1]:8786", "ws://node-3:8786"])
def test_good_scheduler_address(address):
    assert check_scheduler(address) == address


def test_no_scheduler_is_not_an_address():
    with pytest.raises(ValueError, match="scheduler"):
        check_scheduler(None)


def test_bad_chunk_size(task):
    fam = make_family("gp", task)
    for bad in (0, -3, 2.0, True):
        with pytest.raises(ValueError, match="chunk_size"):
            ProcessPoolEvaluator(task, fam, workers=2, chunk_size=bad)


def test_make_evaluator_choice(task):
    fam = make_family("gp", task)
    for w in (0, 1):
        assert isinstance(make_evaluator(task, fam, workers=w), InProcessEvaluator)
    ev = make_evaluator(task, fam, workers=2)
    assert isinstance(ev, ProcessPoolEvaluator) and ev.workers == 2
    ev.close()                                                  # never started: nothing to stop


def test_dask_missing_gives_clear_error(task, monkeypatch):
    fam = make_family("gp", task)
    monkeypatch.setitem(sys.modules, "distributed", None)        # import distributed -> ImportError
    with pytest.raises(ImportError, match=r"pip install gpmotion\[dask\]"):
        make_evaluator(task, fam, scheduler="local")
    assert "gpmotion[dask]" in DASK_MISSING


# ---- Dask --------------------------------------------------------------------------------

@pytest.mark.dask
def test_dask_local_cluster_matches_in_process(task, case):
    pytest.importorskip("distributed")
    fam, pop, ref = case
    with make_evaluator(task, fam, scheduler="local", workers=2, chunk_size=7) as ev:
        assert isinstance(ev, DaskEvaluator)
        addresses = ev.client.scheduler_info()["workers"]
        # loopback only, and TLS with a throwaway certificate: no other local user can submit code
        assert len(addresses) == 2 and all(a.startswith("tls://127.0.0.1:") for a in addresses)
        assert_identical(ev.evaluate(pop, progress=0.7), ref)
        assert ev.evaluations == N


@pytest.mark.dask
def test_dask_survives_killed_worker(task):
    pytest.importorskip("distributed")
    fam = make_family("gp", task)
    pop = _gp_population(fam, 200, seed=5)
    ref = InProcessEvaluator(task, fam).evaluate(pop)
    killed = []

    with DaskEvaluator(task, fam, scheduler="local", workers=2, chunk_size=10) as ev:
        pids = ev.worker_pids()

        def kill_one(ev):
            if killed:
                return
            pid = sorted(pids.values())[0]
            os.kill(pid, signal.SIGKILL)
            killed.append(pid)

        ev._hook_after_submit = kill_one
        got = ev.evaluate(pop)
        assert killed
        assert_identical(got, ref)
        assert killed[0] not in ev.worker_pids().values()     # its tasks really ran elsewhere
        assert_identical(ev.evaluate(pop), ref)
