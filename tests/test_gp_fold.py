"""Encode-time constant folding (opt-in) and fused pairs (the default) in
gpmotion.gp.bytecode.compile_tree: a subtree that reads no state becomes one
constant, a primitive whose last argument is a sense reads it itself, and
every tree gives bitwise the value its plain ops give, in the generated
kernel and in the plain reference interpreter."""
import random

import numpy as np
import pytest
from deap import gp
from hypothesis import given, settings
from hypothesis import strategies as st

from gpmotion.gp import primitives as registry
from gpmotion.gp.bytecode import (HEADER, OP_ARG_SENSE0, OP_PUSH_CONST, STACK_CAP, compile_tree, encode_batch,
                                  encode_trees, tokens_to_tree, tree_to_tokens)
from gpmotion.gp.interpreter import load_interpreter
from gpmotion.gp.pset import build_pset
from tests.reference.gp_interpreter_ref import run_tree_ref

SENSES = ["px", "pz", "vx", "t"]
TERMS = ["px", "vx", "t"]
registry.load_builtin()
ALL = registry.names()                   # every shipped primitive: sin, cos, div, conditionals
INFO = build_pset(TERMS, ALL, sense_names=SENSES)
KERNEL = load_interpreter(INFO)


def bits(x: float) -> bytes:
    return np.float64(x).tobytes()


def run(ci, cf, s):
    return KERNEL.run_tree(ci, cf, 0, s, np.zeros(STACK_CAP))


def random_tokens(seed: int, p_const: float, depth: int) -> list:
    """A ramped half-and-half tree with each terminal turned into a constant
    with probability p_const (so constant subtrees of every shape occur)."""
    saved = random.getstate()
    try:
        random.seed(seed)
        tree = gp.PrimitiveTree(gp.genHalfAndHalf(INFO.pset, 1, depth))
        rng = random.Random(seed)
        out = []
        for tok in tree_to_tokens(tree):
            if isinstance(tok, str) and tok in TERMS and rng.random() < p_const:
                tok = rng.choice([0.0, -0.0, 1.0, rng.uniform(-2, 2), rng.uniform(-1e7, 1e7)])
            out.append(tok)
        return out
    finally:
        random.setstate(saved)


senses = st.lists(st.floats(allow_nan=True, allow_infinity=True, width=64),
                  min_size=len(SENSES), max_size=len(SENSES))


@settings(deadline=None, max_examples=150)
@given(seed=st.integers(0, 2**32 - 1), p_const=st.floats(0.0, 1.0), depth=st.integers(1, 6),
       lazy=st.booleans(), s=senses)
def test_folded_tree_gives_bitwise_the_unfolded_value(seed, p_const, depth, lazy, s):
    tree = tokens_to_tree(random_tokens(seed, p_const, depth), INFO)
    s = np.array(s)
    plain = encode_trees([tree], INFO, [0], lazy=lazy, fold=False)
    folded = encode_trees([tree], INFO, [0], lazy=lazy, fold=True)
    assert bits(run(*folded, s)) == bits(run(*plain, s))
    assert folded[0][HEADER + 2] <= plain[0][HEADER + 2]


@settings(deadline=None, max_examples=30)
@given(seed=st.integers(0, 2**32 - 1), p_const=st.floats(0.3, 1.0), s=senses)
def test_folded_batch_drives_bitwise_the_same_targets(seed, p_const, s):
    """Through control(): three trees an individual, four individuals a batch."""
    inds = [[random_tokens(seed + 3 * i + k, p_const, 5) for k in range(3)] for i in range(4)]
    s = np.array(s)
    got = []
    for fold in (False, True):
        b = encode_batch(inds, INFO, [0, 1, 2], fold=fold)
        out = np.zeros((b.n_episodes, 3))
        for r in range(b.n_episodes):
            cstate = np.zeros(b.cstate_size)
            KERNEL.init(b.ci[r], b.cf[r], cstate)
            KERNEL.control(b.ci[r], b.cf[r], s, s, 0.0, cstate, out[r], np.zeros(3))
        got.append(out.tobytes())
    assert got[0] == got[1]


@pytest.mark.parametrize("sub", [["mul", 2.0, "sin", 0.5], ["div", 1.0, 0.0],
                                 ["iflte", 1.0, 2.0, "cos", 3.0, "abs", -4.0],
                                 ["add", 1e300, 1e300]])
def test_a_constant_subtree_becomes_one_constant(sub):
    """px + (constant subtree): three ops folded, its value the kernel's own."""
    tree = tokens_to_tree(["add", "px"] + sub, INFO)
    ops, consts, _ = compile_tree(tree, INFO, fold=True)
    assert len(ops) == 3 and ops[1][0] == OP_PUSH_CONST and len(consts) == 1
    assert len(compile_tree(tree, INFO, fold=False)[0]) == 2 + len(sub) + 2 * ("iflte" in sub)
    alone = encode_trees([tokens_to_tree(sub, INFO)], INFO, [0], fold=False)
    assert bits(consts[0]) == bits(run(*alone, np.zeros(len(SENSES))))


def test_a_constant_tree_folds_to_one_op_and_state_is_never_folded():
    ops, consts, need = compile_tree(tokens_to_tree(["sub", "cos", 1.0, -2.5], INFO), INFO,
                                     fold=True)
    assert len(ops) == 1 and need == 1 and len(consts) == 1
    keep = tokens_to_tree(["add", "t", "mul", "px", 2.0], INFO)
    assert compile_tree(keep, INFO, fold=True) == compile_tree(keep, INFO, fold=False)


def test_folding_admits_no_tree_over_the_stack_cap():
    deep = tokens_to_tree(["add", 1.0] * 64 + [1.0], INFO, max_depth=70)
    with pytest.raises(ValueError, match="stack of 65"):
        compile_tree(deep, INFO, lazy=False, fold=True)


@settings(deadline=None, max_examples=100)
@given(seed=st.integers(0, 2**32 - 1), p_const=st.floats(0.0, 0.6), depth=st.integers(1, 6),
       lazy=st.booleans(), s=senses)
def test_fused_pairs_give_bitwise_the_plain_value(seed, p_const, depth, lazy, s):
    """"Push sense, apply" fused into one op: the kernel and the plain reference
    interpreter each give bitwise what they give on the plain stream."""
    tree = tokens_to_tree(random_tokens(seed, p_const, depth), INFO)
    s = np.array(s)
    plain = encode_trees([tree], INFO, [0], lazy=lazy, fold=False, fuse=False)
    fused = encode_trees([tree], INFO, [0], lazy=lazy, fold=True, fuse=True)
    assert bits(run(*fused, s)) == bits(run(*plain, s))
    funcs = [p.func for p in INFO.primitives]
    selects = [p.select for p in INFO.primitives]
    assert (bits(run_tree_ref(*fused, 0, s, funcs, selects))
            == bits(run_tree_ref(*plain, 0, s, funcs, selects)))


def test_a_primitive_over_a_sense_is_one_op():
    """px, add+vx, sin+t, sub: six plain ops become four."""
    tree = tokens_to_tree(["sub", "add", "px", "vx", "sin", "t"], INFO)
    ops = compile_tree(tree, INFO, fuse=True)[0]
    assert [a >= OP_ARG_SENSE0 for _, a in ops] == [False, True, True, False]
    (px, _), (add, vx), (sin, t), sub = ops
    assert compile_tree(tree, INFO, fuse=False)[0] == [
        (0, px), (0, vx - OP_ARG_SENSE0), (add, 0), (0, t - OP_ARG_SENSE0), (sin, 0), sub]
