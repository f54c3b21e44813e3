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

from gpmotion.gp.bytecode import (STACK_CAP, encode_batch, encode_trees, tokens_to_tree,
                                  tree_to_tokens)
from gpmotion.gp.interpreter import interpreter_path, interpreter_source, load_interpreter
from gpmotion.gp.pset import build_pset, compile_reference

REF = os.path.join(os.path.dirname(os.path.abspath(__file__)), "reference", "gp_interpreter_ref.py")
_spec = importlib.util.spec_from_file_location("gp_interpreter_ref", REF)
_ref = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_ref)
control_ref, run_tree_ref = _ref.control_ref, _ref.run_tree_ref

SENSES = ["px", "pz", "vx", "angle_shoulder", "force_head_tip", "t", "unused"]
TERMS = ["px", "vx", "angle_shoulder", "force_head_tip", "t"]


@pytest.fixture(scope="module")
def info():
    return build_pset(TERMS, sense_names=SENSES)


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


def test_interpreter_agrees_with_deap_compile_and_reference(info, kernel, trees):
    rng = np.random.default_rng(0)
    funcs = [p.func for p in info.primitives]
    stack = np.zeros(STACK_CAP)
    kinds = set()
    for tree in trees:
        kinds.update(n.name for n in tree if isinstance(n, gp.Primitive))
        ci, cf = encode_trees([tree], info, [0])
        ref = compile_reference(tree, info)
        for s in sense_vectors(rng):
            want = ref(s)
            got = kernel.run_tree(ci, cf, 0, s, stack)
            plain = run_tree_ref(ci, cf, 0, s, funcs)
            assert math.isfinite(got) and abs(got) <= 1e6
            assert close(got, want), (str(tree), s, got, want)
            assert close(plain, want), (str(tree), s, plain, want)
    assert kinds == set(info.primitive_names)     # every primitive exercised


def test_batch_control_writes_only_its_actuators(info, kernel, trees):
    acts = [0, 2, 3]
    inds = [trees[i:i + 3] for i in range(0, 30, 3)] + [trees[:1] * 3]
    batch = encode_batch(inds, info, acts)
    assert batch.module == str(interpreter_path(info))
    assert batch.ci.shape[0] == len(inds) and batch.cstate_size == STACK_CAP
    funcs = [p.func for p in info.primitives]
    s = np.random.default_rng(1).normal(size=len(SENSES))
    for r in range(batch.n_episodes):
        cstate = np.full(batch.cstate_size, 7.0)
        kernel.init(batch.ci[r], batch.cf[r], cstate)
        assert not cstate.any()
        targets = np.full(5, -9.0)
        taus = np.full(5, 0.1)
        kernel.control(batch.ci[r], batch.cf[r], s, s, 0.0, cstate, targets, taus)
        want = np.full(5, -9.0)
        control_ref(batch.ci[r], batch.cf[r], s, want, funcs)
        assert np.allclose(targets, want, rtol=1e-9, atol=0)
        assert targets[1] == -9.0 and targets[4] == -9.0 and (taus == 0.1).all()
        for k, a in enumerate(acts):
            assert close(targets[a], compile_reference(inds[r][k], info)(s))
    padded = np.zeros_like(batch.ci[0])       # a padding row drives nothing
    targets = np.full(5, -9.0)
    kernel.control(padded, batch.cf[0], s, s, 0.0, np.zeros(STACK_CAP), targets, targets)
    assert (targets == -9.0).all()


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
])
def test_semantics_cases(info, kernel, tokens, senses, want):
    s = np.zeros(len(SENSES))
    for name, v in senses.items():
        s[SENSES.index(name)] = v
    tree = tokens_to_tree(tokens, info)
    ci, cf = encode_trees([tree], info, [0])
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
    tokens = ["iflte", "px", "px", "px"] * 22 + ["px"]   # right-nested: needs 3*22+1 slots
    tree = tokens_to_tree(tokens, info, max_depth=30)
    with pytest.raises(ValueError, match="stack"):
        encode_trees([tree], info, [0])
    ok = tokens_to_tree(["iflte", "px", "px", "px"] * 20 + ["px"], info, max_depth=30)
    ci, _ = encode_trees([ok], info, [0])
    assert ci[1] == 61


def test_terminals_must_be_senses():
    with pytest.raises(ValueError, match="not senses"):
        build_pset(["px", "bogus"], sense_names=SENSES)


def test_pset_rebuild_in_one_process(info):
    again = build_pset(TERMS, sense_names=SENSES)
    assert again.hash == info.hash and again.erc_name == info.erc_name
    other = build_pset(["px"], ["add", "sin"], sense_names=SENSES)
    assert other.hash != info.hash and other.erc_name != info.erc_name
    assert "prim_iflte" not in interpreter_source(other)


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
        info = build_pset({TERMS!r}, sense_names={SENSES!r})
        k = load_interpreter(info)
        assert not hasattr(k.run_tree, "py_func"), "JIT not disabled"
        progs = json.load(open({str(tmp_path / "progs.json")!r}))
        batch = encode_batch([progs[i:i + 2] for i in range(0, 40, 2)], info, [0, 1])
        funcs = [p.func for p in info.primitives]
        s = np.array([0.5, -1.0, 0.0, 2.0, 1e300, np.nan, 3.0])
        cstate = np.zeros(batch.cstate_size)
        for r in range(batch.n_episodes):
            got, want = np.zeros(2), np.zeros(2)
            k.init(batch.ci[r], batch.cf[r], cstate)
            k.control(batch.ci[r], batch.cf[r], s, s, 0.0, cstate, got, got.copy())
            control_ref(batch.ci[r], batch.cf[r], s, want, funcs)
            assert np.allclose(got, want, rtol=1e-12, atol=0), (r, got, want)
        print("ok")
    """)
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    out = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr[-2000:]
