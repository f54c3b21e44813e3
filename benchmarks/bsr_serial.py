"""Auslander's serial search speed: 40,000 time-based BSR evaluations of
Mr. Star-Man (the paper: 3–6 minutes on a DEC 3000/400 AXP).

C = 10 working controllers, 4,000 rounds, reseeding every 200: each round
evaluates its 10 mutants in one batched rollout.  Reports wall time,
evaluations/s and simulation steps/s.  The issue's bar: under 20 s on a
2-core machine; goal: under 5 s.

    python benchmarks/bsr_serial.py [--evaluations 40000] [--seconds 2] [--json]
"""
import argparse
import json
import time

import numpy as np

from gpmotion.inprocess import InProcessEvaluator
from gpmotion.families import make_family
from gpmotion.task import get_task


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--evaluations", type=int, default=40_000)
    ap.add_argument("--seconds", type=float, default=2.0, help="episode length T (s)")
    ap.add_argument("--working", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    task = get_task("starman_travel", seconds=args.seconds)
    fam = make_family("bsr-time", task)
    rounds = args.evaluations // args.working - 1
    search = fam.make_search(args.seed, n_working=args.working, n_generations=rounds)
    ev = InProcessEvaluator(task, fam)
    ev.evaluate([fam.random(np.random.default_rng(1))])          # compile / load the cache
    t0, c0 = time.perf_counter(), time.process_time()
    evals = 0
    while not search.done:
        genomes = search.ask()
        search.tell(ev.evaluate(genomes, search.progress))
        evals += len(genomes)
    wall = time.perf_counter() - t0
    cpu = time.process_time() - c0     # all threads: a load-independent cost figure
    out = {"benchmark": "bsr_serial", "task": task.name, "episode_s": task.seconds, "dt": task.dt,
           "evaluations": evals, "wall_s": round(wall, 2), "cpu_s": round(cpu, 2), "evals_per_s": round(evals / wall, 1),
           "steps_per_s": round(evals * task.n_steps / wall), "best_distance_m": -search.best_cost}
    print(json.dumps(out) if args.json else
          f"{evals:,} time-based BSR evaluations of Star-Man ({task.seconds:g} s episodes) in "
          f"{wall:.1f} s ({cpu:.1f} s of CPU): {out['evals_per_s']:,.0f} evals/s, {out['steps_per_s']:,.0f} steps/s; "
          f"best travel {out['best_distance_m']:.2f} m")


if __name__ == "__main__":
    main()
