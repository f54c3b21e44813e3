"""Opcode statistics of evolved GP controllers: what encode-time folding and
fused instruction pairs could save.

Reads the controller records (best.json files) under the given folders,
encodes every tree as the kernel runs it, and prints: ops per tree plain,
folded, and folded with fused "sense, apply" pairs, the share of ops inside constant subtrees, and the
most frequent adjacent opcode pairs (by opcode class: sense, const, flag,
jump, primitive name with apply/select).  Static counts, not weighted by the
branches an episode takes.

    python benchmarks/gp_op_stats.py gpmotion/studies/gritz-hahn-lamp/controllers \
        gpmotion/studies/limbo-series/controllers
"""
import argparse
import collections
from pathlib import Path

from gpmotion.gp.bytecode import compile_tree, tokens_to_tree
from gpmotion.gp.opcodes import OP_ARG_SENSE0, OP_JUMP, OP_PRIM0, OP_PUSH_CONST, OP_PUSH_FLAG, OP_PUSH_SENSE
from gpmotion.replay import load_controller


def op_name(op, arg, info):
    if op == OP_PUSH_SENSE:
        return "sense"
    if op == OP_PUSH_CONST:
        return "const"
    if op == OP_PUSH_FLAG:
        return "flag"
    if op == OP_JUMP:
        return "jump"
    name = info.primitives[op - OP_PRIM0].name
    return name + ("?" if arg == 1 else "+sense" if arg >= OP_ARG_SENSE0 else "")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", nargs="+")
    ap.add_argument("--top", type=int, default=15)
    ap.add_argument("--fuse", action="store_true", help="pairs of the fused form")
    args = ap.parse_args(argv)
    pairs, singles = collections.Counter(), collections.Counter()
    n_trees = ops_plain = ops_fold = ops_fuse = 0
    for folder in args.folders:
        for path in sorted(Path(folder).glob("*.json")):
            task, fam, _, genome, _ = load_controller(path)
            if fam.name != "gp":
                continue
            for tokens in genome:
                tree = tokens_to_tree(tokens, fam.info)
                ops = compile_tree(tree, fam.info, fold=False, fuse=False)[0]
                ops_plain += len(ops)
                ops_fold += len(compile_tree(tree, fam.info, fold=True, fuse=False)[0])
                fused = compile_tree(tree, fam.info, fold=True, fuse=True)[0]
                ops_fuse += len(fused)
                ops = fused if args.fuse else ops
                n_trees += 1
                names = [op_name(o, a, fam.info) for o, a in ops]
                singles.update(names)
                pairs.update(zip(names, names[1:]))
    print(f"{n_trees} trees; ops per tree {ops_plain / n_trees:.1f} plain, "
          f"{ops_fold / n_trees:.1f} folded ({1 - ops_fold / ops_plain:.1%} fewer), "
          f"{ops_fuse / n_trees:.1f} folded and fused ({1 - ops_fuse / ops_plain:.1%} fewer)")
    total = sum(singles.values())
    print("opcodes:", ", ".join(f"{k} {v / total:.1%}" for k, v in singles.most_common()))
    total = sum(pairs.values())
    print(f"top pairs of {total}:")
    for (a, b), v in pairs.most_common(args.top):
        print(f"  {a:>8} {b:<8} {v:6d} {v / total:6.1%}")


if __name__ == "__main__":
    main()
