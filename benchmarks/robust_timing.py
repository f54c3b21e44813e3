"""Cost of a robust evaluation: K perturbed starts per controller against K
nominal evaluations of the same batch, through the run's evaluator
(``InProcessEvaluator`` with ``robust``, as ``gpmotion run --robust-starts K``).

The bar: K starts cost close to K single episodes, not more —
ratio = robust time / (K × one nominal evaluation) ≈ 1 or below.  Best of
``--repeat`` timings of each (the machine is shared).

    python benchmarks/robust_timing.py [--task lamp_hop --controller gp] [-n 32] [-k 8]
"""
import argparse
import time

import numpy as np

from gpmotion.robust import normalize
from gpmotion.inprocess import InProcessEvaluator
from gpmotion.families import make_family
from gpmotion.task import get_task


def best_of(f, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return min(times)


def random_genomes(fam, n):
    """n controllers as each family's search draws them first."""
    if hasattr(fam, "random"):
        rng = np.random.default_rng(0)
        return [fam.random(rng) for _ in range(n)]
    from gpmotion.search.gp import GPSearch
    return GPSearch(fam, seed=0, population=n, generations=1).ask()[:n]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--task", default="lamp_hop")
    ap.add_argument("--controller", default="gp")
    ap.add_argument("-n", type=int, default=32, help="controllers in the batch")
    ap.add_argument("-k", type=int, default=8, help="perturbed starts per controller")
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args(argv)
    task = get_task(a.task)
    fam = make_family(a.controller, task)
    genomes = random_genomes(fam, a.n)
    robust = InProcessEvaluator(task, fam, robust={**normalize({"starts": a.k}, task), "seed": 0})
    nominal = InProcessEvaluator(task, fam)
    robust.evaluate(genomes[:2])              # compile / load the kernels before timing
    nominal.evaluate(genomes[:2])
    t_robust = best_of(lambda: robust.evaluate(genomes, 1.0, generation=1), a.repeat)
    t_one = best_of(lambda: nominal.evaluate(genomes, 1.0), a.repeat)
    print(f"{task.name} ({fam.name}), {a.n} controllers, {task.seconds:g} s episodes: "
          f"{a.k} perturbed starts each {t_robust:.2f} s; one nominal evaluation {t_one:.2f} s; "
          f"ratio robust / ({a.k} × nominal) = {t_robust / (a.k * t_one):.2f}")


if __name__ == "__main__":
    main()
