"""GP bytecode + generated interpreter agree with deap.gp.compile and a plain
Python stack machine (tests/reference/gp_interpreter_ref.py).

Semantics are made identical, not approximately equal: the DEAP pset's
functions are the clamped primitives (gpmotion.gp.pset), compile_reference
clamps the senses, and both interpreters clamp every push and result.
"""
import importlib.util
import json
import math
import os
import random
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from deap import gp

from gpmotion.gp import primitives as registry
from gpmotion.gp.bytecode import (HEADER, MAX_TREE_DEPTH, OP_JUMP, OP_PRIM0, RATE_STATE,
                                  STACK_CAP, TargetLaw, compile_tree, encode_batch, encode_trees,
                                  tokens_to_tree, tree_to_tokens)
from gpmotion.gp.interpreter import interpreter_path, interpreter_source, load_interpreter
from gpmotion.gp.primitives import STANDARD
from gpmotion.gp.pset import build_pset, compile_reference
from gpmotion.gp.subgoals import MAX_SUBGOALS
from gpmotion.gp.task_senses import MAX_TASK_SENSES

REF = os.path.join(os.path.dirname(os.path.abspath(__file__)), "reference", "gp_interpreter_ref.py")
_spec = importlib.util.spec_from_file_location("gp_interpreter_ref", REF)
_ref = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_ref)
control_ref, run_tree_ref = _ref.control_ref, _ref.run_tree_ref

SENSES = ["px", "pz", "vx", "angle_shoulder", "force_head_tip", "t", "unused"]
TERMS = ["px", "vx", "angle_shoulder", "force_head_tip", "t"]


registry.load_builtin()
ALL = registry.names()          # the default set plus the opt-in ones (ifpos)


@pytest.fixture(scope="module")
def info():
    return build_pset(TERMS, ALL, sense_names=SENSES)


def funcs_selects(info):
    return [p.func for p in info.primitives], [p.select for p in info.primitives]


@pytest.fixture(scope="module")
def kernel(info):
    return load_interpreter(info)


@pytest.fixture(scope="module")
def trees(info):
    random.seed(1234)
    return [gp.PrimitiveTree(gp.genHalfAndHalf(info.pset, 1, 6)) for _ in range(200)]


def sense_vectors(rng):
    """Random, zero (division by zero), equal (iflte ties), huge and non-finite senses."""
    n = len(SENSES)
    tie = rng.normal(size=n)
    tie[[0, 2, 3]] = tie[0]
    return [rng.normal(size=n), np.zeros(n), tie, rng.normal(size=n) * 1e5,
            np.array([1e300, -1e300, 0.0, 1e-12, 3e6, -2.0, 5.0]),
            np.array([np.nan, np.inf, -np.inf, 0.5, np.nan, 1.0, 0.0])]


def close(a, b):
    return abs(a - b) <= 1e-9 * max(abs(a), abs(b)) + 1e-300


def agree_on(trees, info, kernel, rng):
    """Lazy and eager bytecode, kernel and plain reference, all equal deap.gp.compile."""
    funcs, selects = funcs_selects(info)
    stack = np.zeros(STACK_CAP)
    for tree in trees:
        ref = compile_reference(tree, info)
        streams = [encode_trees([tree], info, [0], lazy=lz) for lz in (True, False)]
        for s in sense_vectors(rng):
            want = ref(s)
            for ci, cf in streams:
                got = kernel.run_tree(ci, cf, 0, s, stack)
                plain = run_tree_ref(ci, cf, 0, s, funcs, selects)
                assert math.isfinite(got) and abs(got) <= 1e6
                assert close(got, want), (str(tree), s, got, want)
                assert close(plain, want), (str(tree), s, plain, want)


def test_interpreter_agrees_with_deap_compile_and_reference(info, kernel, trees):
    agree_on(trees, info, kernel, np.random.default_rng(0))
    kinds = {n.name for t in trees for n in t if isinstance(n, gp.Primitive)}
    assert kinds == set(info.primitive_names)     # every primitive exercised


def deep_tree(pset, depth, rng, p_cond=0.7):
    """A random tree of height exactly ``depth``: a spine of mostly conditionals
    (the deep child in a random argument slot: selector or branch), the other
    arguments small random subtrees, so conditionals nest in every position."""
    prims = [p for ps in pset.primitives.values() for p in ps]
    conds = [p for p in prims if registry.get(p.name).conditional]
    nodes = []

    def grow(d, spine):
        if d == 0:
            nodes.append(pset.terminals[pset.ret][rng.randrange(len(pset.terminals[pset.ret]))])
            if isinstance(nodes[-1], type):           # the ERC class: draw a constant
                nodes[-1] = nodes[-1]()
            return
        if not spine and rng.random() < 0.5:
            return grow(0, False)
        p = rng.choice(conds if spine and rng.random() < p_cond else prims)
        nodes.append(p)
        deep = rng.randrange(p.arity) if spine else -1
        for i in range(p.arity):
            grow(d - 1 if i == deep else min(d - 1, 2), i == deep)

    grow(depth, True)
    return gp.PrimitiveTree(nodes)


def test_nested_conditionals_at_max_depth_agree(info, kernel):
    rng = random.Random(7)
    trees = [deep_tree(info.pset, MAX_TREE_DEPTH, rng) for _ in range(60)]
    assert all(t.height == MAX_TREE_DEPTH for t in trees)
    assert max(sum(registry.get(n.name).conditional for n in t if isinstance(n, gp.Primitive))
               for t in trees) >= 12
    for t in trees:                         # they round-trip through the token parser's caps
        tokens_to_tree(tree_to_tokens(t), info)
    agree_on(trees, info, kernel, np.random.default_rng(3))


def test_untaken_branch_is_never_executed(info, kernel):
    """Poison the ops of one branch: the lazy kernel returns the other branch's
    value when that branch is taken, and 0.0 (malformed) when the poisoned one is."""
    tree = tokens_to_tree(["ifpos", "px", "add", "vx", 1.0, "mul", "t", 2.0], info)
    ci, cf = encode_trees([tree], info, [0])
    ops = ci[HEADER + 3:].reshape(-1, 2)  # after the header and the tree's row
    # px SELECT J | vx 1 add J | t 2 mul
    assert len(ops) == 10 and ops[2, 0] == ops[6, 0] == OP_JUMP
    s = np.zeros(len(SENSES))
    s[SENSES.index("vx")], s[SENSES.index("t")] = 2.0, 5.0
    for poisoned, rows in (("then", slice(3, 6)), ("else", slice(7, 10))):
        bad = ci.copy()
        bad[HEADER + 3:].reshape(-1, 2)[rows, 0] = 999
        for px, taken in ((1.0, "then"), (-1.0, "else")):
            s[0] = px
            got = kernel.run_tree(bad, cf, 0, s, np.zeros(STACK_CAP))
            want = 0.0 if taken == poisoned else (3.0 if taken == "then" else 10.0)
            assert got == want, (poisoned, px, got)
            assert run_tree_ref(bad, cf, 0, s, *funcs_selects(info)) == want
    eager, _ = encode_trees([tree], info, [0], lazy=False)   # eager: every op, no jumps
    assert len(eager[HEADER + 3:]) // 2 == 8 and OP_JUMP not in eager[HEADER + 3::2]


def test_batch_control_writes_only_its_actuators(info, kernel, trees):
    acts = [0, 2, 3]
    inds = [trees[i:i + 3] for i in range(0, 30, 3)] + [trees[:1] * 3]
    batch = encode_batch(inds, info, acts)
    assert batch.module == str(interpreter_path(info))
    assert batch.ci.shape[0] == len(inds) and batch.cstate_size == STACK_CAP + MAX_SUBGOALS + MAX_TASK_SENSES + RATE_STATE + 3
    funcs, selects = funcs_selects(info)
    s = np.random.default_rng(1).normal(size=len(SENSES))
    for r in range(batch.n_episodes):
        cstate = np.full(batch.cstate_size, 7.0)
        kernel.init(batch.ci[r], batch.cf[r], cstate)
        assert not cstate.any()
        targets = np.full(5, -9.0)
        taus = np.full(5, 0.1)
        kernel.control(batch.ci[r], batch.cf[r], s, s, 0.0, cstate, targets, taus)
        want = np.full(5, -9.0)
        control_ref(batch.ci[r], batch.cf[r], s, want, funcs, selects)
        assert np.allclose(targets, want, rtol=1e-9, atol=0)
        assert targets[1] == -9.0 and targets[4] == -9.0 and (taus == 0.1).all()
        for k, a in enumerate(acts):
            assert close(targets[a], compile_reference(inds[r][k], info)(s))
    padded = np.zeros_like(batch.ci[0])       # a padding row drives nothing
    targets = np.full(5, -9.0)
    kernel.control(padded, batch.cf[0], s, s, 0.0, np.zeros(STACK_CAP), targets, targets)
    assert (targets == -9.0).all()


def run_law(kernel, info, ind, acts, law, rng, steps=60, dt=0.002):
    """Step the kernel and the plain-Python twin side by side; yield each step's
    (step, targets, senses)."""
    funcs, selects = funcs_selects(info)
    batch = encode_batch([ind], info, acts, law=law)
    ci, cf = batch.ci[0], batch.cf[0]
    assert ci[3] == 1 and list(cf[ci[4]: ci[4] + 4 * len(acts)]) == law.block()
    cstate = np.full(batch.cstate_size, 3.0)
    kernel.init(ci, cf, cstate)
    state = {}
    for step in range(steps):
        s = rng.normal(size=len(SENSES))
        got, want = np.full(5, 0.1), np.full(5, 0.1)     # the caller's start: 0.1
        kernel.control(ci, cf, s, s, step * dt, cstate, got, np.zeros(5))
        control_ref(ci, cf, s, want, funcs, selects, t=step * dt, rate=state)
        assert np.allclose(got, want, rtol=1e-12, atol=1e-12), step
        assert got[1] == got[4] == 0.1                      # others untouched
        yield step, got, s


def test_rate_targets_integrate_and_hold_within_the_joint_range(info, kernel, trees):
    """Rate mode: target_k(t) = start + gain * integral of tree k's output, held
    within [lo, hi]; the kernel agrees with the plain-Python twin step by step,
    and constant trees give the analytic ramp."""
    acts = [0, 2, 3]
    law = TargetLaw(("rate",) * 3, (10.0,) * 3, (-0.3, -1e6, -2.0), (0.3, 1e6, 2.0))   # tree 0's ramp: 0.3
    consts = [tokens_to_tree([c], info) for c in (0.3, -0.7, 0.05)]
    rng = np.random.default_rng(4)
    for ind in (consts, trees[3:6], trees[9:12]):
        for step, got, _ in run_law(kernel, info, ind, acts, law, rng):
            if ind is consts:                                   # the analytic ramp, clamped
                ramp = [min(max(0.1 + 10.0 * c * step * 0.002, lo), hi)
                        for c, lo, hi in zip((0.3, -0.7, 0.05), law.a, law.b)]
                assert np.allclose(got[acts], ramp, rtol=0, atol=1e-12), step
        assert abs(got[0]) <= 0.3 and abs(got[3]) <= 2.0
    with pytest.raises(ValueError, match="joint entries"):
        encode_trees(consts, info, acts, law=TargetLaw(("rate",), (1.0,), (0.0,), (1.0,)))


def test_pi_targets_add_the_bounded_integral_of_the_angle_error(info, kernel, trees):
    """Pi mode: target_k = tree_k + I_k, I_k the integral of gain * (tree_k -
    its angle sense), |I_k| <= bound; kernel and twin agree step by step, and
    a constant tree against a constant angle gives the analytic ramp."""
    acts = [0, 2, 3]
    angle = SENSES.index("angle_shoulder")
    law = TargetLaw(("pi",) * 3, (5.0,) * 3, (float(angle),) * 3, (0.05, 0.5, 0.5))
    rng = np.random.default_rng(5)
    for ind in (trees[3:6], trees[12:15]):
        for _, got, _ in run_law(kernel, info, ind, acts, law, rng):
            pass
    consts = [tokens_to_tree([c], info) for c in (0.3, -0.7, 0.05)]
    funcs, selects = funcs_selects(info)
    batch = encode_batch([consts], info, acts, law=law)
    cstate = np.zeros(batch.cstate_size)
    s = np.zeros(len(SENSES))
    s[angle] = 0.2                                        # the joint sits at 0.2 rad
    for step in range(40):
        got = np.zeros(5)
        kernel.control(batch.ci[0], batch.cf[0], s, s, step * 0.01, cstate, got, np.zeros(5))
        want = [c + min(max(5.0 * (c - 0.2) * step * 0.01, -b), b)
                for c, b in zip((0.3, -0.7, 0.05), law.b)]
        assert np.allclose(got[acts], want, rtol=0, atol=1e-12), step


def test_each_tree_follows_its_own_mode(info, kernel, trees):
    """Mixed modes (``rate,JOINT=angle,...``): one tree's target ramps, one is
    its tree's output, one is PI-corrected, in one row; kernel and twin agree."""
    acts = [0, 2, 3]
    angle = SENSES.index("angle_shoulder")
    law = TargetLaw(("rate", "angle", "pi"), (10.0, 0.0, 5.0), (-0.3, 0.0, float(angle)),
                    (0.3, 0.0, 0.5))
    rng = np.random.default_rng(6)
    for ind in (trees[3:6], trees[6:9]):
        for _, got, _ in run_law(kernel, info, ind, acts, law, rng):
            assert abs(got[0]) <= 0.3
    consts = [tokens_to_tree([c], info) for c in (0.3, -0.7, 0.05)]
    for step, got, s in run_law(kernel, info, consts, acts, law, rng):
        assert got[0] == pytest.approx(min(0.1 + 10.0 * 0.3 * step * 0.002, 0.3), abs=1e-12)
        assert got[2] == -0.7                                    # the angle tree, as it is


@pytest.mark.parametrize("tokens, senses, want", [
    (["div", "px", "vx"], {"px": 3.0, "vx": 0.0}, 1.0),              # protected division
    (["div", "px", "vx"], {"px": 3.0, "vx": 2.0}, 1.5),
    (["iflte", "px", "vx", 1.0, -1.0], {"px": 2.0, "vx": 2.0}, 1.0),  # tie takes "then"
    (["iflte", "px", "vx", 1.0, -1.0], {"px": 2.5, "vx": 2.0}, -1.0),
    (["mul", "px", "px"], {"px": 1e300}, 1e6),                       # saturates, no inf
    (["sub", 0.0, "px"], {"px": np.inf}, -1e6),
    (["sin", "px"], {"px": np.nan}, 0.0),                            # NaN sense -> 0
    (["div", "px", 0.0], {"px": 1e300}, 1.0),
    (["t"], {"t": 1e300}, 1e6),
    (["ifpos", "px", 1.0, -1.0], {"px": 0.0}, -1.0),                 # zero is not positive
    (["ifpos", "px", 1.0, -1.0], {"px": 1e-12}, 1.0),
    (["ifpos", "px", 1.0, -1.0], {"px": np.nan}, -1.0),              # NaN sense reads 0
    (["ifpos", "px", "vx", "div", "px", 0.0], {"px": -2.0, "vx": 4.0}, 1.0),
])
def test_semantics_cases(info, kernel, tokens, senses, want):
    s = np.zeros(len(SENSES))
    for name, v in senses.items():
        s[SENSES.index(name)] = v
    tree = tokens_to_tree(tokens, info)
    for lazy in (True, False):
        ci, cf = encode_trees([tree], info, [0], lazy=lazy)
        assert kernel.run_tree(ci, cf, 0, s, np.zeros(STACK_CAP)) == want
    assert compile_reference(tree, info)(s) == want


def test_token_round_trip(info, trees):
    for tree in trees:
        tokens = json.loads(json.dumps(tree_to_tokens(tree)))
        back = tokens_to_tree(tokens, info)
        assert str(back) == str(tree)
        assert tree_to_tokens(back) == tokens
        a, b = encode_trees([tree], info, [1]), encode_trees([back], info, [1])
        assert (a[0] == b[0]).all() and (a[1] == b[1]).all()
    # token lists are accepted directly by the encoder
    batch = encode_batch([[tree_to_tokens(trees[0])]], info, [0])
    assert (batch.ci[0] == encode_trees([trees[0]], info, [0])[0]).all()


@pytest.mark.parametrize("tokens, message", [
    (["add", "px", "__import__('os').system('x')"], "unknown token"),
    (["exp", "px"], "unknown token 'exp'"),
    (["ARG0"], "unknown token"),
    (["add", "px"], "incomplete"),
    (["px", "vx"], "extra tokens"),
    ([], "empty"),
    ("add(px, vx)", "list of tokens"),
    (["add", True, "px"], "bad token"),
    (["add", None, "px"], "bad token"),
    (["add", float("nan"), "px"], "non-finite"),
    (["add"] * 600 + ["px"] * 601, "size cap"),
    (["sin"] * 30 + ["px"], "depth cap"),
])
def test_bad_tokens_rejected(info, tokens, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(")):
        tokens_to_tree(tokens, info)


def test_stack_cap_enforced(info):
    tokens = ["iflte", "px", "px", "px"] * 22 + ["px"]   # nested in the last branch
    tree = tokens_to_tree(tokens, info, max_depth=30)
    with pytest.raises(ValueError, match="stack"):       # eager: 3*22+1 slots
        encode_trees([tree], info, [0], lazy=False)
    ci, _ = encode_trees([tree], info, [0])              # lazy: a branch starts where
    assert ci[1] == 2                                    # its selectors were popped
    ok = tokens_to_tree(["iflte", "px", "px", "px"] * 20 + ["px"], info, max_depth=30)
    ci, _ = encode_trees([ok], info, [0], lazy=False)
    assert ci[1] == 61
    # nested in a selector, the lazy form needs a slot per level too
    deep = tokens_to_tree(["iflte", "px"] * 64 + ["px"] + ["px", "px"] * 64, info, max_depth=70)
    with pytest.raises(ValueError, match="stack of 65"):
        encode_trees([deep], info, [0])
    within = tokens_to_tree(["iflte", "px"] * 63 + ["px"] + ["px", "px"] * 63, info, max_depth=70)
    assert encode_trees([within], info, [0])[0][1] == 64


def test_malformed_jumps_and_selects_give_zero(info, kernel):
    tree = tokens_to_tree(["iflte", "px", "vx", 1.0, 2.0], info)
    ci, cf = encode_trees([tree], info, [0])
    s = np.zeros(len(SENSES))
    assert kernel.run_tree(ci, cf, 0, s, np.zeros(STACK_CAP)) == 1.0
    start = int(ci[HEADER + 1])
    jumps = [start + 2 * k for k in range(int(ci[HEADER + 2])) if ci[start + 2 * k] == OP_JUMP]
    for bad_arg in (-1, 99):                              # backwards / out of the tree
        bad = ci.copy()
        bad[jumps[-1] + 1] = bad_arg                      # the jump after branch 0
        assert kernel.run_tree(bad, cf, 0, s, np.zeros(STACK_CAP)) == 0.0
        assert run_tree_ref(bad, cf, 0, s, *funcs_selects(info)) == 0.0
    add = tokens_to_tree(["add", "px", "vx"], info)       # "select" on a non-conditional
    ci, cf = encode_trees([add], info, [0])
    ci[-1] = 1
    assert kernel.run_tree(ci, cf, 0, s, np.zeros(STACK_CAP)) == 0.0


def test_terminals_must_be_senses():
    with pytest.raises(ValueError, match="not senses"):
        build_pset(["px", "bogus"], sense_names=SENSES)


def test_pset_rebuild_in_one_process(info):
    again = build_pset(TERMS, ALL, sense_names=SENSES)
    assert again.hash == info.hash and again.erc_name == info.erc_name
    other = build_pset(["px"], ["add", "sin"], sense_names=SENSES)
    assert other.hash != info.hash and other.erc_name != info.erc_name
    default = build_pset(TERMS, sense_names=SENSES)       # opt-in primitives stay out
    assert "ifpos" not in default.primitive_names and "iflte" in default.primitive_names


def test_function_sets_drawn_from_the_installed_primitives_share_one_kernel():
    """One GP kernel per install, not per task or preset: a set's opcodes are the
    installed primitives' (the default set's first, so its bytecode is unchanged)."""
    default = build_pset(TERMS, sense_names=SENSES)
    small = build_pset(["px"], ["sub", "add"], sense_names=SENSES)
    paper = build_pset(TERMS, ["add", "sub", "mul", "div", "ifpos"], sense_names=SENSES)
    assert interpreter_path(small) == interpreter_path(default) == interpreter_path(paper)
    assert default.opcode_names[:len(STANDARD)] == STANDARD
    assert small.opcode_names == default.opcode_names
    tree = gp.PrimitiveTree.from_string("sub(px, add(px, px))", small.pset)
    ops = compile_tree(tree, small)[0]
    assert [op for op, _ in ops if op >= OP_PRIM0] == [OP_PRIM0 + STANDARD.index("add"),
                                                        OP_PRIM0 + STANDARD.index("sub")]
    with pytest.raises(ValueError, match="not in this primitive set"):
        compile_tree(gp.PrimitiveTree.from_string("mul(px, px)", default.pset), small)


def test_kernels_run_without_jit(info, trees, tmp_path):
    """Run the generated kernel functions as plain Python (coverage sees them)."""
    progs = [(tree_to_tokens(t)) for t in trees[:40]]
    (tmp_path / "progs.json").write_text(json.dumps(progs))
    script = textwrap.dedent(f"""
        import importlib.util, json, numpy as np
        from gpmotion.gp.pset import build_pset, compile_reference
        from gpmotion.gp.bytecode import encode_batch, tokens_to_tree
        from gpmotion.gp.interpreter import load_interpreter
        spec = importlib.util.spec_from_file_location("gp_interpreter_ref", {REF!r})
        ref = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(ref)
        control_ref = ref.control_ref
        info = build_pset({TERMS!r}, {ALL!r}, sense_names={SENSES!r})
        k = load_interpreter(info)
        assert not hasattr(k.run_tree, "py_func"), "JIT not disabled"
        progs = json.load(open({str(tmp_path / "progs.json")!r}))
        batch = encode_batch([progs[i:i + 2] for i in range(0, 40, 2)], info, [0, 1])
        funcs = [p.func for p in info.primitives]
        selects = [p.select for p in info.primitives]
        s = np.array([0.5, -1.0, 0.0, 2.0, 1e300, np.nan, 3.0])
        cstate = np.zeros(batch.cstate_size)
        for r in range(batch.n_episodes):
            got, want = np.zeros(2), np.zeros(2)
            k.init(batch.ci[r], batch.cf[r], cstate)
            k.control(batch.ci[r], batch.cf[r], s, s, 0.0, cstate, got, got.copy())
            control_ref(batch.ci[r], batch.cf[r], s, want, funcs, selects)
            assert np.allclose(got, want, rtol=1e-12, atol=0), (r, got, want)
        print("ok")
    """)
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    out = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr[-2000:]


def test_token_lists_encode_as_their_trees_once_remembered(info, trees, monkeypatch):
    """encode_trees remembers compiled trees by their tokens (most trees of
    a GP generation are unchanged copies): a remembered list encodes exactly
    as its tree does, lazy and eager apart, and -0.0 apart from 0.0; a tree
    or list seen before, in either form, is not compiled again."""
    from gpmotion.gp import bytecode
    monkeypatch.setattr(bytecode, "_COMPILED", {})
    toks = [tree_to_tokens(t) for t in trees[:40]]
    calls = []
    real = bytecode.compile_tree
    monkeypatch.setattr(bytecode, "compile_tree", lambda *a, **k: calls.append(1) or real(*a, **k))
    for lazy in (True, False):
        for tree, tk in zip(trees[:40], toks):
            want = encode_trees([tree], info, [0], lazy=lazy)
            for _ in range(2):
                got = encode_trees([tk], info, [0], lazy=lazy)
                assert all(np.array_equal(g, w) for g, w in zip(got, want))
    assert len(calls) == 2 * len({repr(t) for t in toks})            # once per tree and mode
    for tree in trees[:40]:
        encode_trees([tree], info, [0])
    assert len(calls) == 2 * len({repr(t) for t in toks})
    zero, negzero = ["add", "t", 0.0], ["add", "t", -0.0]
    cf0, cf1 = encode_trees([zero], info, [0])[1], encode_trees([negzero], info, [0])[1]
    assert np.copysign(1.0, cf0[-1]) == 1.0 and np.copysign(1.0, cf1[-1]) == -1.0
