"""Encoding a GP population to bytecode: the compile cache for DEAP trees.

A GP generation re-encodes every individual, but most of its trees were
compiled in an earlier generation (reproduction copies them; crossover and
mutation change one tree of an individual).  ``encode_batch`` caches each
tree's compiled form by its tokens, for token lists and DEAP trees alike.
This prints, for ``--pop`` first-generation individuals of a task's GP
family (ramped half-and-half, seed 0), the seconds per encode of the whole
population:

* ``uncached``: every tree compiled (``compile_tree``), as a cold cache does;
* ``trees``: DEAP trees, every tree seen before (a warm cache);
* ``tokens``: the same trees as token lists, warm;

and checks that the three give the same arrays.

    python benchmarks/gp_encode_cache.py --task lamp_hop --pop 300
"""
import argparse
import random
import time

import numpy as np
from deap import gp

from gpmotion.families import make_family
from gpmotion.gp import bytecode
from gpmotion.task import get_task


def population(fam, n, seed=0):
    random.seed(seed)
    return [[gp.PrimitiveTree(gp.genHalfAndHalf(fam.pset, 2, 6)) for _ in fam.actuators]
            for _ in range(n)]


def seconds(fn, repeats):
    best = float("inf")
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", default="lamp_hop")
    ap.add_argument("--pop", type=int, default=300)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args(argv)
    fam = make_family("gp", get_task(args.task))
    trees = population(fam, args.pop)
    tokens = [[bytecode.tree_to_tokens(t) for t in ind] for ind in trees]

    def uncached():
        bytecode._COMPILED.clear()
        return fam.encode(trees)

    ref = uncached()
    times = {"uncached": seconds(uncached, args.repeats)}
    for name, genomes in (("trees", trees), ("tokens", tokens)):
        got = fam.encode(genomes)
        assert np.array_equal(got.ci, ref.ci) and np.array_equal(got.cf, ref.cf), name
        times[name] = seconds(lambda: fam.encode(genomes), args.repeats)
    print(f"{args.task}: {args.pop} individuals x {len(fam.actuators)} trees, best of {args.repeats}")
    for name, s in times.items():
        print(f"  {name:>9}: {s * 1e3:7.1f} ms per encode ({times['uncached'] / s:4.1f}x uncached)")


if __name__ == "__main__":
    main()
