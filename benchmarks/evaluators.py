"""Evaluator throughput and per-task overhead; chunk size for a 100-worker cluster.

    python benchmarks/evaluators.py                 # lamp_hop 3 s episodes, 1,000 GP individuals
    python benchmarks/evaluators.py --quick         # smaller, for a smoke run
    python benchmarks/evaluators.py --json out.json

Measures on this machine:
  * evaluations/s: in-process (rollout threads; and one thread), process pool
    (``--workers``), Dask LocalCluster (``--workers``), same genomes, results
    checked bitwise equal;
  * per-task overhead of each backend (Dask: the TLS local cluster gpmotion
    starts, and the same over plain tcp): throughput of N no-op tasks submitted
    at once (the serialized, central cost per task: client + scheduler, or the
    pool's feeder thread) and the round-trip latency of one task at a time;
  * a paper estimate of the chunk size for ``--target-workers`` workers.

Model (stated in the output too).  A chunk of c evaluations costs c·t_e of
work on one worker (t_e: one evaluation on one core) plus a round-trip
latency l.  A central scheduler handles tasks one after another at s seconds
each, so keeping W workers busy costs W·s per "round" in which every worker
finishes one chunk.  A round therefore lasts max(c·t_e + l, W·s) and

    efficiency E(c) = c·t_e / max(c·t_e + l, W·s)

E ≥ E* needs c ≥ max(E*/(1−E*) · l, E*·W·s) / t_e.  A generation of n
genomes also needs n ≥ W·c (better 2–4·W·c) for every worker to get work.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import platform
import random
import sys
import time


def _population(family, n, seed):
    from deap import gp
    random.seed(seed)
    return [[gp.PrimitiveTree(gp.genHalfAndHalf(family.pset, 2, 5)) for _ in family.actuators]
            for _ in range(n)]


def _best_time(fn, repeats):
    best, out = math.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def _same(a, b):
    return all(getattr(a, k).tobytes() == getattr(b, k).tobytes() for k in ("costs", "success", "failed"))


def pool_overhead(workers, n_tasks, n_latency):
    """Per-task cost of the process pool with a no-op task (throughput and latency)."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, wait

    from gpmotion.evaluators import _noop
    with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn")) as ex:
        wait([ex.submit(_noop, i) for i in range(4 * workers)])            # start every worker
        t0 = time.perf_counter()
        wait([ex.submit(_noop, i) for i in range(n_tasks)])
        throughput = (time.perf_counter() - t0) / n_tasks
        t0 = time.perf_counter()
        for i in range(n_latency):
            ex.submit(_noop, i).result()
        latency = (time.perf_counter() - t0) / n_latency
    return throughput, latency


def dask_overhead(client, n_tasks, n_latency):
    """Per-task cost of Dask with a no-op task (throughput and latency)."""
    from gpmotion.evaluators import _noop
    client.gather([client.submit(_noop, i, pure=False) for i in range(20)])
    t0 = time.perf_counter()
    client.gather([client.submit(_noop, i, pure=False) for i in range(n_tasks)])
    throughput = (time.perf_counter() - t0) / n_tasks
    t0 = time.perf_counter()
    for i in range(n_latency):
        client.submit(_noop, i, pure=False).result()
    latency = (time.perf_counter() - t0) / n_latency
    return throughput, latency


def chunk_for(efficiency, workers, t_eval, latency, serial):
    """Smallest chunk size with E(c) >= efficiency under the model above."""
    need = max(efficiency / (1 - efficiency) * latency, efficiency * workers * serial)
    c = max(1, math.ceil(need / t_eval))
    e = c * t_eval / max(c * t_eval + latency, workers * serial)
    return c, e


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--task", default="lamp_hop")
    ap.add_argument("--seconds", type=float, default=3.0, help="episode length (task default 3 s)")
    ap.add_argument("--population", type=int, default=1000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--tasks", type=int, default=1000, help="no-op tasks for the overhead throughput")
    ap.add_argument("--latency-tasks", type=int, default=200)
    ap.add_argument("--target-workers", type=int, default=100)
    ap.add_argument("--efficiency", type=float, default=0.8)
    ap.add_argument("--no-dask", action="store_true")
    ap.add_argument("--quick", action="store_true", help="population 200, 1 s episodes, fewer tasks")
    ap.add_argument("--json", help="also write the result here")
    args = ap.parse_args(argv)
    if args.quick:
        args.population, args.seconds, args.repeats, args.tasks, args.latency_tasks = 200, 1.0, 2, 300, 50

    from gpmotion.inprocess import InProcessEvaluator
    from gpmotion.evaluators import DaskEvaluator, ProcessPoolEvaluator
    from gpmotion.families import make_family
    from gpmotion.task import get_task

    task = get_task(args.task, seconds=args.seconds)
    fam = make_family("gp", task)
    pop = _population(fam, args.population, seed=1)
    n = len(pop)
    res = {"task": args.task, "seconds": args.seconds, "population": n, "workers": args.workers,
           "cpus": os.cpu_count(), "load_average": list(os.getloadavg()), "python": platform.python_version(),
           "backends": {}}

    # in-process: all rollout threads, and one thread (t_e for the model)
    ev = InProcessEvaluator(task, fam)
    ev.evaluate(pop[:8])                                            # compile / load the cache
    sec, ref = _best_time(lambda: ev.evaluate(pop), args.repeats)
    res["backends"]["in_process"] = {"seconds": sec, "evals_per_s": n / sec}
    ev1 = InProcessEvaluator(task, fam, threads=1)
    sec1, r1 = _best_time(lambda: ev1.evaluate(pop), args.repeats)
    t_eval = sec1 / n
    res["backends"]["in_process_1_thread"] = {"seconds": sec1, "evals_per_s": n / sec1, "identical": _same(r1, ref)}
    res["seconds_per_evaluation_1_core"] = t_eval

    # process pool
    t0 = time.perf_counter()
    with ProcessPoolEvaluator(task, fam, args.workers) as pev:
        pev.evaluate(pop[: 4 * args.workers])                       # start + warm the workers
        start = time.perf_counter() - t0
        sec, r = _best_time(lambda: pev.evaluate(pop), args.repeats)
        res["backends"]["process_pool"] = {"seconds": sec, "evals_per_s": n / sec, "identical": _same(r, ref),
                                           "chunk_size": pev.last_chunk_size, "startup_s": start}
    thr, lat = pool_overhead(args.workers, args.tasks, args.latency_tasks)
    res["overhead"] = {"process_pool": {"per_task_throughput_s": thr, "per_task_latency_s": lat}}

    # dask LocalCluster
    if not args.no_dask:
        t0 = time.perf_counter()
        with DaskEvaluator(task, fam, "local", workers=args.workers) as dev:
            dev.evaluate(pop[: 4 * args.workers])
            start = time.perf_counter() - t0
            sec, r = _best_time(lambda: dev.evaluate(pop), args.repeats)
            res["backends"]["dask_local"] = {"seconds": sec, "evals_per_s": n / sec, "identical": _same(r, ref),
                                             "chunk_size": dev.last_chunk_size, "startup_s": start}
            thr, lat = dask_overhead(dev.client, args.tasks, args.latency_tasks)
            res["overhead"]["dask"] = {"per_task_throughput_s": thr, "per_task_latency_s": lat}
        # the same without TLS: what the local cluster's throwaway certificate costs per task
        with DaskEvaluator(task, fam, "local", workers=args.workers, local_tls=False) as dev:
            thr, lat = dask_overhead(dev.client, args.tasks, args.latency_tasks)
            res["overhead"]["dask_tcp"] = {"per_task_throughput_s": thr, "per_task_latency_s": lat}

    # paper estimate
    W, E = args.target_workers, args.efficiency
    est = {"model": "E(c) = c*t_e / max(c*t_e + latency, W*serial); serial = no-op throughput cost per "
                    "task (central scheduler/feeder handles tasks one after another), latency = one task's "
                    "round trip, t_e = one evaluation on one core",
           "target_workers": W, "target_efficiency": E}
    for name, o in res["overhead"].items():
        c, e = chunk_for(E, W, t_eval, o["per_task_latency_s"], o["per_task_throughput_s"])
        est[name] = {"chunk_size": c, "efficiency_at_chunk": e,
                     "min_population_all_busy": W * c,
                     "bound_by": "scheduler" if W * o["per_task_throughput_s"] > c * t_eval + o["per_task_latency_s"] - 1e-12
                     else "latency",
                     "evals_per_s_estimate": W * e / t_eval}
    res["estimate"] = est

    print(json.dumps(res, indent=2))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(res, fh, indent=2)

    b, o = res["backends"], res["overhead"]
    print(f"\n{args.task} {args.seconds:g} s episodes, {n} GP individuals, {os.cpu_count()} CPUs "
          f"(load {res['load_average'][0]:.2f}):")
    for name, r in b.items():
        extra = f", chunk {r['chunk_size']}" if "chunk_size" in r else ""
        same = "" if r.get("identical", True) else "  RESULTS DIFFER"
        print(f"  {name:22s} {r['evals_per_s']:9.0f} evals/s{extra}{same}")
    print(f"  one evaluation on one core: {t_eval * 1e3:.2f} ms")
    for name, r in o.items():
        print(f"  {name:12s} per-task overhead: {r['per_task_throughput_s'] * 1e3:.3f} ms serialized (throughput), "
              f"{r['per_task_latency_s'] * 1e3:.3f} ms round trip")
    for name in o:
        r = est[name]
        print(f"  {W} workers via {name}: chunk >= {r['chunk_size']} evaluations/task for {E:.0%} "
              f"(E={r['efficiency_at_chunk']:.2f}, {r['bound_by']}-bound); a generation needs >= "
              f"{r['min_population_all_busy']} genomes to keep all workers busy")
    return 0


if __name__ == "__main__":
    sys.exit(main())
