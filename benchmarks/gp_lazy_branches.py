"""Lazy vs eager conditional branches, interpreter alone, on many random trees.

``gpmotion bench --controller gp`` times its three fixed trees; this script
averages over 300 ramped half-and-half trees (depth 2..6, fixed seed) of a
primitive set, each evaluated on 2000 random sense vectors, lazy and eager
bytecode timed alternately (best of 5).  Both forms give identical values
(tests/test_gp_bytecode.py); only the time differs.  ``--bench-trees``
instead rolls out the lamp driven by ``compare_mujoco.py``'s three GP trees
(8 episodes of 3,000 steps, one thread), lazy and eager in turn, best of
``--repeats``, and checks that both give the same states.

    python benchmarks/gp_lazy_branches.py [--primitives add,sub,mul,div,ifpos]
    python benchmarks/gp_lazy_branches.py --bench-trees [--repeats 11]
"""
import argparse
import random
import time

import numpy as np
from deap import gp
from numba import njit

from gpmotion.gp.bytecode import STACK_CAP, encode_trees
from gpmotion.gp.interpreter import load_interpreter
from gpmotion.gp.pset import build_pset


@njit
def drive(run_tree, ci, cf, senses, stack):
    acc = 0.0
    for s in range(senses.shape[0]):
        acc += run_tree(ci, cf, 0, senses[s], stack)
    return acc


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--primitives", default=None, help="comma list (default: the default set)")
    ap.add_argument("--trees", type=int, default=300)
    ap.add_argument("--bench-trees", action="store_true",
                    help="the lamp rollout driven by compare_mujoco.py's GP trees")
    ap.add_argument("--repeats", type=int, default=11)
    args = ap.parse_args(argv)
    if args.bench_trees:
        return bench_trees(args.repeats)
    info = build_pset(["a", "b", "c", "d", "t"],
                      args.primitives.split(",") if args.primitives else None)
    kernel = load_interpreter(info)
    saved = random.getstate()
    random.seed(0)
    trees = [gp.PrimitiveTree(gp.genHalfAndHalf(info.pset, 2, 6)) for _ in range(args.trees)]
    random.setstate(saved)
    senses = np.random.default_rng(0).normal(size=(2000, 5))
    stack = np.zeros(STACK_CAP)
    enc = {lz: [encode_trees([t], info, [0], lazy=lz) for t in trees] for lz in (True, False)}
    for lz in enc:                                     # compile before timing
        drive(kernel.run_tree, *enc[lz][0], senses, stack)
    best = {True: np.inf, False: np.inf}
    for _ in range(5):
        for lz in (True, False):
            t0 = time.perf_counter()
            for ci, cf in enc[lz]:
                drive(kernel.run_tree, ci, cf, senses, stack)
            best[lz] = min(best[lz], time.perf_counter() - t0)
    n = len(trees) * len(senses)
    print(f"primitives {','.join(info.primitive_names)}; {len(trees)} trees, "
          f"mean {np.mean([len(t) for t in trees]):.1f} nodes")
    print(f"lazy {n / best[True] / 1e6:.2f} M tree evals/s, eager {n / best[False] / 1e6:.2f} M; "
          f"lazy is x{best[False] / best[True]:.2f} as fast")


def bench_trees(repeats: int, episodes: int = 8, n_steps: int = 3000) -> None:
    """Lazy vs eager on the rollout of compare_mujoco.py's GP lamp workload."""
    import gpmotion
    from compare_mujoco import bench_gp_trees
    from gpmotion.gp.bytecode import encode_batch
    task, fam, tokens = bench_gp_trees(0)
    q0, qd0 = task.initial_state()
    best, states = {True: np.inf, False: np.inf}, {}
    for round_ in range(repeats + 1):                  # round 0 compiles: not timed
        for lz in (True, False):
            batch = encode_batch([tokens] * episodes, fam.info, fam.actuators, lazy=lz,
                                 subgoals=fam.subgoal_table, law=fam.law,
                                 task_programs=fam.task_programs)
            t0 = time.perf_counter()
            traj = gpmotion.rollout(task.figure, task.scene(), batch, n_steps=n_steps,
                                    q0=q0, qd0=qd0, threads=1)
            if round_:
                best[lz] = min(best[lz], time.perf_counter() - t0)
            states[lz] = traj.q
    steps = episodes * n_steps
    print(f"bench trees ({', '.join(str(len(t)) for t in tokens)} nodes), {episodes} x {n_steps} steps, "
          f"same states: {np.array_equal(states[True], states[False])}")
    print(f"lazy {steps / best[True] / 1e6:.3f} M steps/s, eager {steps / best[False] / 1e6:.3f} M; "
          f"lazy is x{best[False] / best[True]:.2f} as fast")


if __name__ == "__main__":
    main()
