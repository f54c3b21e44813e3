"""What a fall hides: random controllers scored on full episodes and on episodes a fall ends.

    python benchmarks/fall_hides.py [--task lamp_hop] [--n 600] [--seed 1]

Rolls out ``n`` random GP controllers of the task twice, with ``falls_final``
off (every episode to its end) and on (a fallen episode ends at its fall
frame), and prints, over the episodes that fall, each term's mean and the
share that is non-zero under either, and the median cost at full weights of
the fallen and of the others.  It says why a search under the falls-final
score keeps more lamps that fall (docs/speed.md).
"""
from __future__ import annotations

import argparse

import numpy as np

from gpmotion.families import make_family
from gpmotion.inprocess import InProcessEvaluator
from gpmotion.task import get_task


def scored(task_name: str, falls_final: int, genomes_seed: int, n: int):
    """(measures, costs at full weights, steps simulated) of n random controllers."""
    task = get_task(task_name, falls_final=falls_final)
    fam = make_family("gp", task)
    rng = np.random.default_rng(genomes_seed)
    traj = InProcessEvaluator(task, fam).rollout([fam.random(rng) for _ in range(n)])
    m = task.measure(traj)
    cost = sum(t.weight * m[t.name] for t in task.terms)
    return m, cost, traj.steps_run


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", default="lamp_hop", help="a task with the falls_final parameter")
    ap.add_argument("--n", type=int, default=600, help="random controllers")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args(argv)
    full, cost_full, steps_full = scored(a.task, 0, a.seed, a.n)
    cut, cost_cut, steps_cut = scored(a.task, 1, a.seed, a.n)
    fell = full["fell"] > 0
    print(f"{a.task}: {a.n} random controllers, {fell.mean():.0%} fall; steps simulated "
          f"{steps_cut.sum() / 1e6:.2f} M with falls final, {steps_full.sum() / 1e6:.2f} M without")
    print(f"{'term (fallen episodes)':<24}{'full mean':>10}{'cut mean':>10}{'full > 0':>10}{'cut > 0':>10}")
    for name in full:
        f, c = full[name][fell], cut[name][fell]
        print(f"{name:<24}{f.mean():>10.3f}{c.mean():>10.3f}{(f > 0).mean():>10.0%}{(c > 0).mean():>10.0%}")
    print(f"median cost at full weights: fallen {np.median(cost_full[fell]):.2f} in full, "
          f"{np.median(cost_cut[fell]):.2f} cut at the fall; not fallen {np.median(cost_full[~fell]):.2f}")


if __name__ == "__main__":
    main()
