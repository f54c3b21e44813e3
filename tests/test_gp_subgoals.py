"""Subgoal terminals: flags a task declares, latched in the GP controller's
state (no simulator-kernel change), equal to deap.gp.compile given the same
flag values, and switching a controller's behaviour in a real rollout."""
import importlib.util
import os
import random

import numpy as np
import pytest
from deap import gp

from gpmotion.inprocess import InProcessEvaluator
from gpmotion.families import make_family
from gpmotion.gp import primitives as registry
from gpmotion.gp.bytecode import STACK_CAP, encode_batch, encode_trees, tokens_to_tree
from gpmotion.gp.interpreter import load_interpreter
from gpmotion.gp.pset import build_pset, compile_reference
from gpmotion.gp.subgoals import TESTS, Subgoal
from gpmotion.task import get_task
from gpmotion.tasks.lamp_hop import LampHop

REF = os.path.join(os.path.dirname(os.path.abspath(__file__)), "reference", "gp_interpreter_ref.py")
_spec = importlib.util.spec_from_file_location("gp_interpreter_ref", REF)
_ref = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_ref)

registry.load_builtin()
FLAGS = ["arrived", "passed", "low"]
# arrived: |px| < 0.05; passed: vx > 0.5; low: t < 1.0
TABLE = [(0, TESTS["abs_lt"], 0.05), (1, TESTS["gt"], 0.5), (2, TESTS["lt"], 1.0)]


@pytest.fixture(scope="module")
def info():
    return build_pset(["px", "vx", "t"], registry.names(), flag_names=FLAGS)


def test_flags_latch_once_met(info):
    kernel = load_interpreter(info)
    funcs, selects = [p.func for p in info.primitives], [p.select for p in info.primitives]
    trees = [tokens_to_tree(["ifpos", f, 1.0, -1.0], info) for f in FLAGS]
    batch = encode_batch([trees], info, [0, 1, 2], subgoals=TABLE)
    cstate = np.full(batch.cstate_size, 5.0)
    kernel.init(batch.ci[0], batch.cf[0], cstate)
    ref_flags = [0.0] * 3
    want_rows = [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [1, 1, -1], [1, 1, 1]]
    for (px, vx, t), want in zip([(1.0, 0.0, 2.0), (0.01, 0.0, 2.0), (2.0, 0.6, 2.0),
                                  (2.0, -3.0, 2.0), (2.0, -3.0, 0.5)], want_rows):
        s = np.array([px, vx, t])
        got, plain = np.zeros(3), np.zeros(3)
        kernel.control(batch.ci[0], batch.cf[0], s, s, 0.0, cstate, got, np.zeros(3))
        _ref.control_ref(batch.ci[0], batch.cf[0], s, plain, funcs, selects, ref_flags)
        assert got.tolist() == want and plain.tolist() == want, (px, vx, t)
    assert cstate[STACK_CAP:STACK_CAP + 3].tolist() == [1.0, 1.0, 1.0]
    with pytest.raises(ValueError, match="subgoal tests"):
        encode_trees(trees, info, [0, 1, 2])                  # the table must match the flags


def test_trees_with_flags_agree_with_deap(info):
    kernel = load_interpreter(info)
    funcs, selects = [p.func for p in info.primitives], [p.select for p in info.primitives]
    random.seed(11)
    rng = np.random.default_rng(2)
    used = set()
    for _ in range(150):
        tree = gp.PrimitiveTree(gp.genHalfAndHalf(info.pset, 1, 5))
        used.update(n.value for n in tree if isinstance(n, gp.Terminal) and n.value in FLAGS)
        ci, cf = encode_trees([tree], info, [0], subgoals=TABLE)
        f = compile_reference(tree, info)
        for _k in range(4):
            s, flags = rng.normal(size=3), rng.integers(0, 2, 3).astype(float)
            cstate = np.zeros(STACK_CAP + 8)
            cstate[STACK_CAP:STACK_CAP + 3] = flags
            want = f(s, flags)
            assert kernel.run_tree(ci, cf, 0, s, cstate) == pytest.approx(want, rel=1e-12, abs=0)
            assert _ref.run_tree_ref(ci, cf, 0, s, funcs, selects, flags=list(flags)) == \
                pytest.approx(want, rel=1e-12, abs=0)
    assert used == set(FLAGS)


def test_lamp_tasks_declare_subgoals_and_the_family_adds_them():
    limbo = get_task("lamp_limbo", distance=0.8)
    fam = make_family("gp", limbo, subgoals=True)
    assert fam.info.flag_names == ("passed_pole", "arrived")
    assert fam.info.terminal_names[-2:] == ("passed_pole", "arrived")
    px = limbo.figure.sense_names.index("px")
    assert fam.subgoal_table == [(px, TESTS["gt"], -0.4), (px, TESTS["abs_lt"], 0.05)]
    assert fam.config()["subgoals"] is True
    genome = [["iflte", "passed_pole", "arrived", "px", "vx"]] * 3
    assert fam.from_json(fam.to_json(genome)) == genome
    plain = make_family("gp", limbo)
    assert "arrived" not in plain.info.terminal_names and plain.subgoal_table == []
    with pytest.raises(ValueError, match="unknown token 'passed_pole'"):
        plain.from_json(fam.to_json(genome))
    with pytest.raises(ValueError, match="declares no subgoals"):
        make_family("gp", get_task("herman_wave"), subgoals=True)
    assert Subgoal("a", "px", "gt", 0.0).met(0.1) and not Subgoal("a", "px", "abs_lt", 0.1).met(-0.2)
    with pytest.raises(ValueError, match="test must be one of"):
        Subgoal("a", "px", "ge", 0.0)


class _TimedHop(LampHop):
    """lamp_hop with a subgoal met at t > 0.2 s (unregistered, for this test)."""
    def subgoals(self):
        return (Subgoal("late", "t", "gt", 0.2),)


def test_a_subgoal_switches_behaviour_in_a_rollout():
    task = _TimedHop(seconds=0.5)
    fam = make_family("gp", task, subgoals=True)
    genome = [["iflte", "late", 0.5, -0.3, 0.3]] * 3             # -0.3 until late, then 0.3
    traj = InProcessEvaluator(task, fam).rollout([genome])
    times, targets = traj.times, traj.targets[0]
    assert np.all(targets[(times > 0.05) & (times < 0.19)] == -0.3)
    assert np.all(targets[times > 0.21] == 0.3)
