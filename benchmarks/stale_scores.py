"""Stale scores in the serial search, measured.

Runs one serial search exactly as ``gpmotion compare`` does (lamp_hop,
bsr-time, ~3,000 evaluations, seed 0), then re-scores the final working set
and the reported best at full style weight (progress 1) and prints the
stored cost next to the re-scored one.  With phase-aware re-scoring the two
columns agree; before the fix the stored costs were those of an earlier
phase (style terms at weight 0).

    python benchmarks/stale_scores.py [--task lamp_hop] [--family bsr-time]
                                      [--budget 3000] [--seed 0]
"""
from __future__ import annotations

import argparse

import numpy as np

from gpmotion.inprocess import InProcessEvaluator
from gpmotion.families import make_family
from gpmotion.task import get_task


def measure(task_name="lamp_hop", family="bsr-time", budget=3000, seed=0, actuation="pd"):
    task = get_task(task_name)
    fam = make_family(family, task)
    s = search = fam.make_search(seed, **fam.budget_settings(budget, 100))
    ev = InProcessEvaluator(task, fam, actuation)
    accepted = {"progress < 0.1": 0, "0.1..0.5": 0, "progress > 0.5": 0}
    while not search.done:
        genomes = search.ask()
        mutants = s.working is not None and not s.rescoring
        p = search.progress
        search.tell(ev.evaluate(genomes, p))
        if mutants:                  # an accepted mutant is the very object handed out
            key = "progress < 0.1" if p < 0.1 else "progress > 0.5" if p > 0.5 else "0.1..0.5"
            accepted[key] += sum(w is g for w, g in zip(s.working, genomes))
    full = ev.evaluate(list(s.working) + [s.best_genome], 1.0).costs
    return {"stored": np.asarray(s.scores, float), "full": full[:-1],
            "best_stored": float(s.best_score), "best_full": float(full[-1]),
            "adapter_best_full": float(ev.evaluate([search.best], 1.0).costs[0]),
            "evaluations": s.evaluations, "accepted": accepted}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--task", default="lamp_hop")
    ap.add_argument("--family", default="bsr-time")
    ap.add_argument("--budget", type=int, default=3000)
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    r = measure(a.task, a.family, a.budget, a.seed)
    print(f"{a.task} {a.family} seed {a.seed}: {r['evaluations']} evaluations")
    print("working set, stored cost  vs  re-scored at progress 1:")
    for st, fu in zip(r["stored"], r["full"]):
        print(f"  {st:8.3f}  {fu:8.3f}")
    print(f"reported best: stored {r['best_stored']:.3f}, at progress 1 {r['best_full']:.3f}; "
          f"working set's best at progress 1 {r['full'].min():.3f}")
    print(f"the search's returned best at progress 1: {r['adapter_best_full']:.3f}")
    print(f"mutants accepted: {r['accepted']}")


if __name__ == "__main__":
    main()
