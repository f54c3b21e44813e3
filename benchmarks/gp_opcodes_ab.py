"""The GP interpreter dispatching the installed primitives against only the function set's.

    python benchmarks/gp_opcodes_ab.py [--trees 300] [--repeats 7]

The kernel dispatches every installed primitive (``PsetInfo.opcode_names``),
so that every function set drawn from them shares one compiled kernel.  The
default set's primitives come first, so its bytecode is the same either way
and only the kernel differs by its extra dispatch arms.  This times both
kernels on the same bytecode: 300 ramped half-and-half trees of the default
set (depth 2..6, fixed seed), each on 2,000 random sense vectors, the two
forms alternately, best of ``--repeats``.  Both give the same values
(checked here).
"""
import argparse
import dataclasses
import random
import sys
import time
from pathlib import Path

import numpy as np
from deap import gp

from gpmotion.gp.bytecode import STACK_CAP, encode_trees
from gpmotion.gp.interpreter import interpreter_path, load_interpreter
from gpmotion.gp.pset import build_pset

sys.path.insert(0, str(Path(__file__).resolve().parent))
from gp_lazy_branches import drive  # noqa: E402  (benchmarks/gp_lazy_branches.py: one tree on every sense vector)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trees", type=int, default=300)
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args(argv)
    info = build_pset(["a", "b", "c", "d", "t"])
    own = dataclasses.replace(info, opcode_names=info.primitive_names)   # the set's only
    kernels = {"installed": load_interpreter(info), "function set": load_interpreter(own)}
    assert interpreter_path(info) != interpreter_path(own)
    saved = random.getstate()
    random.seed(0)
    trees = [gp.PrimitiveTree(gp.genHalfAndHalf(info.pset, 2, 6)) for _ in range(args.trees)]
    random.setstate(saved)
    enc = [encode_trees([t], info, [0]) for t in trees]
    for t, e in zip(trees, enc):
        same = encode_trees([t], own, [0])
        assert all(np.array_equal(a, b) for a, b in zip(e, same)), "bytecode differs"
    senses = np.random.default_rng(0).normal(size=(2000, 5))
    stack = np.zeros(STACK_CAP)
    values = {k: [drive(m.run_tree, *e, senses, stack) for e in enc] for k, m in kernels.items()}
    assert values["installed"] == values["function set"], "values differ"
    best = dict.fromkeys(kernels, np.inf)
    for _ in range(args.repeats):
        for k, m in kernels.items():
            t0 = time.perf_counter()
            for e in enc:
                drive(m.run_tree, *e, senses, stack)
            best[k] = min(best[k], time.perf_counter() - t0)
    evals = len(trees) * len(senses)
    for k, s in best.items():
        print(f"{k:13} {evals / s / 1e6:7.2f} M tree evaluations/s ({s * 1e3:.1f} ms)")
    print(f"installed / function set: {best['function set'] / best['installed']:.3f}× the speed")


if __name__ == "__main__":
    main()
