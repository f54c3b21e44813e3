"""Encode-time constant folding and fused "sense, apply" pairs on GP lamp
populations: evaluations per second of each bytecode form, in one process.

Two populations of the lamp's GP controllers:

* ``evolved``: every planar GP controller record under the given folders
  (default: the lamp studies' controllers), each as a batch of ``--copies``
  episodes of its own task;
* ``random``: ``--pop`` first-generation individuals of ``lamp_hop``'s GP
  family (ramped half-and-half, seed 0), the population a search starts from.

Each population is encoded in four forms -- plain, folded, fused (the
default), folded and fused -- and rolled out on one thread, the forms in turn (best of
``--repeats``); the targets and states they give are checked bitwise equal.
Also printed: ops per tree, and the interpreter alone (``run_tree`` over
20,000 random sense vectors a tree).

    python benchmarks/gp_fold_fuse.py
"""
import argparse
import time
from pathlib import Path

import numpy as np
from numba import njit

import gpmotion
from gpmotion.gp import bytecode
from gpmotion.gp.interpreter import load_interpreter
from gpmotion.replay import load_controller
from gpmotion.task import get_task

FOLDERS = ["gpmotion/studies/gritz-hahn-lamp/controllers",
           "gpmotion/studies/limbo-series/controllers"]


FORMS = {"plain": dict(fold=False, fuse=False), "fold": dict(fold=True, fuse=False),
         "fuse": dict(fold=False, fuse=True), "fold+fuse": dict(fold=True, fuse=True)}


def encode(fam, genomes, form):
    return bytecode.encode_batch(list(genomes), fam.info, fam.actuators, subgoals=fam.subgoal_table,
                                 law=fam.law, task_programs=fam.task_programs, **FORMS[form])


def populations(folders, copies, pop):
    """[(label, task, family, genomes)]"""
    out = []
    for folder in folders:
        for path in sorted(Path(folder).glob("*.json")):
            task, fam, _, genome, _ = load_controller(path)
            if fam.name == "gp" and task.figure.dimensions == 2:
                out.append(("evolved", task, fam, [genome] * copies))
    from gpmotion.families.gp import GPFamily
    task = get_task("lamp_hop")
    fam = GPFamily(task)
    rng = np.random.default_rng(0)
    out.append(("random", task, fam, [fam.random(rng) for _ in range(pop)]))
    return out


def rollout(task, batch):
    q0, qd0 = task.initial_state()
    return gpmotion.rollout(task.figure, task.scene(), batch, n_steps=int(round(task.seconds / task.dt)),
                            q0=q0, qd0=qd0, dt=task.dt, threads=1, record_every=25)


@njit
def drive(run_tree, ci, cf, n_trees, senses, stack):
    acc = 0.0
    for s in range(senses.shape[0]):
        for k in range(n_trees):
            acc += run_tree(ci, cf, k, senses[s], stack)
    return acc


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", nargs="*", default=FOLDERS)
    ap.add_argument("--copies", type=int, default=20, help="episodes a controller record")
    ap.add_argument("--pop", type=int, default=300, help="random individuals")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    pops = populations(args.folders, args.copies, args.pop)
    for label in ("evolved", "random"):
        rows = [p for p in pops if p[0] == label]
        step = args.copies if label == "evolved" else 1        # distinct rows, for the interpreter
        batches = {f: [(task, encode(fam, g, f)) for _, task, fam, g in rows] for f in FORMS}
        n_ops = {f: sum(int(b.ci[r, bytecode.HEADER + 3 * k + 2]) for _, b in batches[f]
                        for r in range(b.n_episodes) for k in range(int(b.ci[r, 0])))
                 for f in FORMS}
        outs = {f: [rollout(t, b) for t, b in batches[f]] for f in FORMS}     # warm + check
        same = all(np.array_equal(a.targets.view(np.int64), b.targets.view(np.int64))
                   and np.array_equal(a.q.view(np.int64), b.q.view(np.int64))
                   for f in FORMS for a, b in zip(outs["plain"], outs[f]))
        kernel = load_interpreter(rows[0][2].info)
        senses = np.random.default_rng(0).normal(size=(20000, 64))
        stack = np.zeros(bytecode.STACK_CAP)
        _, b0 = batches["plain"][0]
        drive(kernel.run_tree, b0.ci[0], b0.cf[0], int(b0.ci[0, 0]), senses, stack)   # compile
        best = {f: np.inf for f in FORMS}
        interp = {f: np.inf for f in FORMS}
        for _ in range(args.repeats):
            for f in FORMS:
                t0 = time.perf_counter()
                for t, b in batches[f]:
                    rollout(t, b)
                best[f] = min(best[f], time.perf_counter() - t0)
                t0 = time.perf_counter()
                for _, b in batches[f]:
                    for r in range(0, b.n_episodes, step):
                        drive(kernel.run_tree, b.ci[r], b.cf[r], int(b.ci[r, 0]), senses, stack)
                interp[f] = min(interp[f], time.perf_counter() - t0)
        episodes = sum(b.n_episodes for _, b in batches["plain"])
        per_eval = interp["plain"] / (len(senses) * sum(
            int(b.ci[r, 0]) for _, b in batches["plain"] for r in range(0, b.n_episodes, step)))
        tree_evals = sum(int(b.ci[r, 0]) * round(t.seconds / t.dt) for t, b in batches["plain"]
                         for r in range(b.n_episodes))
        print(f"{label}: {episodes} episodes; same targets and states in every form: {same}; "
              f"the trees' share of a plain rollout ~{min(per_eval * tree_evals / best['plain'], 1):.0%}")
        for f in FORMS:
            print(f"  {f:>9}: ops {n_ops[f]:6d} ({n_ops[f] / n_ops['plain']:.3f}), "
                  f"rollout {episodes / best[f]:7.1f} evals/s (x{best['plain'] / best[f]:.3f}), "
                  f"interpreter alone x{interp['plain'] / interp[f]:.3f}")

if __name__ == "__main__":
    main()
