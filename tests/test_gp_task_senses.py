"""Task senses: terminals a task derives from its figure's senses
by a formula, parsed (never evaluated as Python), computed by the GP
controller before its trees (no simulator-kernel change), equal to the
plain-Python twin, and on the lamp equal to the head tip's position."""
import importlib.util
import math
import os
import random

import numpy as np
import pytest
from deap import gp

from gpmotion.families import make_family
from gpmotion.gp import primitives as registry
from gpmotion.gp.settings import GPSettings
from gpmotion.gp.bytecode import STACK_CAP, encode_batch, encode_trees
from gpmotion.gp.interpreter import load_interpreter
from gpmotion.gp.presets import apply_preset
from gpmotion.gp.pset import build_pset, compile_reference
from gpmotion.gp.subgoals import MAX_SUBGOALS
from gpmotion.gp.task_senses import (MAX_TASK_SENSES, FormulaError, TaskSense, compile_formula,
                                     evaluate, parse, task_senses)
from gpmotion.inprocess import InProcessEvaluator
from gpmotion.task import get_task
from gpmotion.tasks.lamp_hop import LampHop

REF = os.path.join(os.path.dirname(os.path.abspath(__file__)), "reference", "gp_interpreter_ref.py")
_spec = importlib.util.spec_from_file_location("gp_interpreter_ref", REF)
_ref = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_ref)

registry.load_builtin()
PRIMS = registry.names()
SENSES = ["a", "b", "c", "d"]


def _value(formula, **senses):
    return evaluate(parse(formula, SENSES, PRIMS), senses)


@pytest.mark.parametrize("formula, python", [
    ("a - b - c", lambda a, b, c, d: a - b - c),
    ("a - b * c / d", lambda a, b, c, d: a - b * c / d),
    ("-a * b", lambda a, b, c, d: -a * b),
    ("-(a + b) * -c", lambda a, b, c, d: -(a + b) * -c),
    ("2.5e-1 * a + .5 - 3. / d", lambda a, b, c, d: 0.25 * a + 0.5 - 3.0 / d),
    ("sin(a) + cos(b * 2) * abs(c - d)", lambda a, b, c, d: math.sin(a) + math.cos(2 * b) * abs(c - d)),
    ("iflte(a, b, c, d)", lambda a, b, c, d: c if a <= b else d),
    ("  a--b ", lambda a, b, c, d: a + b),
])
def test_formulas_follow_arithmetic_precedence(formula, python):
    rng = np.random.default_rng(0)
    for _ in range(20):
        v = dict(zip(SENSES, rng.normal(size=4) * 2))
        assert _value(formula, **v) == pytest.approx(python(**v), rel=1e-12)


@pytest.mark.parametrize("formula, message", [
    ("a + e", "unknown sense 'e' at column 5"),
    ("a + sqrt(b)", "'sqrt' is not in this run's primitive set"),
    ("sin(a, b)", "sin takes 1 arguments, got 2 at column 1"),
    ("a b", "unexpected 'b' at column 3"),
    ("a + $", "unexpected character '$' at column 5"),
    ("(a + b", "expected ')', found 'the end' at column 7"),
    ("a +", "expected a number, a sense or '(', found 'the end' at column 4"),
    ("__import__(os)", "'__import__' is not in this run's primitive set"),
    ("open('x')", "unexpected character \"'\" at column 6"),
    ("1e999 * a", "constant 1e999 out of range at column 1"),
])
def test_a_bad_formula_says_what_and_where(formula, message):
    with pytest.raises(FormulaError, match="formula: " + message.replace("(", r"\(")
                       .replace(")", r"\)").replace("$", r"\$")):
        parse(formula, SENSES, PRIMS)
    with pytest.raises(FormulaError, match="not in this run's primitive set"):
        parse("a / b", SENSES, ["add", "sub"])


FORMULAS = ["a - b * c", "abs(a) + abs(b) + abs(d)", "cos(a + 0.3) * 2 - c / d", "-d"]


@pytest.fixture(scope="module")
def info():
    return build_pset(["a", "b", "t"], PRIMS, sense_names=SENSES + ["t"],
                      flag_names=["late"], task_sense_names=["u", "v", "w", "x"])


def _programs(info):
    return [compile_formula(parse(f, SENSES, info.primitive_names), SENSES + ["t"],
                            info.opcode_names) for f in FORMULAS]


def test_the_kernel_computes_task_senses_as_the_twin(info):
    kernel = load_interpreter(info)
    funcs, selects = [p.func for p in info.primitives], [p.select for p in info.primitives]
    programs = _programs(info)
    trees = [gp.PrimitiveTree.from_string(n, info.pset) for n in ("u", "v", "w", "x")]
    batch = encode_batch([trees], info, [0, 1, 2, 3], subgoals=[(4, 0, 0.5)], task_programs=programs)
    rng = np.random.default_rng(3)
    cstate = np.zeros(batch.cstate_size)
    kernel.init(batch.ci[0], batch.cf[0], cstate)
    for _ in range(30):
        s = rng.normal(size=5) * 3
        want = [evaluate(parse(f, SENSES, PRIMS), dict(zip(SENSES, s))) for f in FORMULAS]
        got, plain = np.zeros(4), np.zeros(4)
        kernel.control(batch.ci[0], batch.cf[0], s, s, 0.0, cstate, got, np.zeros(4))
        _ref.control_ref(batch.ci[0], batch.cf[0], s, plain, funcs, selects, flags=[0.0])
        assert got == pytest.approx(want, rel=1e-12) and plain == pytest.approx(want, rel=1e-12)
        first = STACK_CAP + MAX_SUBGOALS
        assert cstate[first:first + 4] == pytest.approx(want, rel=1e-12)
    with pytest.raises(ValueError, match="task sense programs"):
        encode_trees(trees, info, [0, 1, 2, 3], subgoals=[(4, 0, 0.5)])


def test_random_trees_over_task_senses_agree_with_deap(info):
    kernel = load_interpreter(info)
    funcs, selects = [p.func for p in info.primitives], [p.select for p in info.primitives]
    programs = _programs(info)
    random.seed(5)
    rng = np.random.default_rng(6)
    used = set()
    for _ in range(120):
        tree = gp.PrimitiveTree(gp.genHalfAndHalf(info.pset, 1, 5))
        used.update(n.value for n in tree if isinstance(n, gp.Terminal))
        batch = encode_batch([[tree]], info, [0], subgoals=[(4, 0, 0.5)], task_programs=programs)
        f = compile_reference(tree, info)
        for _k in range(3):
            s = rng.normal(size=5)
            values = [evaluate(parse(x, SENSES, PRIMS), dict(zip(SENSES, s))) for x in FORMULAS]
            late = [float(s[4] > 0.5)]
            got, plain = np.zeros(1), np.zeros(1)
            cstate = np.zeros(batch.cstate_size)
            kernel.control(batch.ci[0], batch.cf[0], s, s, 0.0, cstate, got, np.zeros(1))
            _ref.control_ref(batch.ci[0], batch.cf[0], s, plain, funcs, selects, flags=[0.0])
            want = f(s, late, values)
            assert got[0] == pytest.approx(want, rel=1e-12, abs=0)
            assert plain[0] == pytest.approx(want, rel=1e-12, abs=0)
    assert {"u", "v", "w", "x", "late"} <= used


def test_lamp_limbo_pole_senses_are_the_head_tip_relative_to_the_pole():
    task = get_task("lamp_limbo", pole_senses=1, distance=0.8, seconds=1.0)
    fam = make_family("gp", task)
    assert fam.info.task_sense_names == ("head_pole_dx", "head_z")
    genome = [["mul", 0.8, "sin", "mul", 7.0, "t"], ["sub", "mul", 1.0, "cos", "mul", 5.0, "t", 1.3],
              ["head_z"]]
    traj = InProcessEvaluator(task, fam).rollout([genome], record_senses=True)
    senses = {n: traj.sense(n)[0] for n in task.figure.sense_names}
    head, pole_x = traj.site("head_tip")[0], task.scene().poles[0][0]
    dx, z = ([evaluate(s.tree, {n: v[i] for n, v in senses.items()}) for i in range(len(head))]
             for s in task_senses(task, fam.info.primitive_names))
    assert np.abs(np.array(dx) - (head[:, 0] - pole_x)).max() < 1e-5     # 1.5708 is not pi/2
    assert np.abs(np.array(z) - head[:, 1]).max() < 1e-5
    assert np.ptp(head[:, 1]) > 0.1                                      # the head did move
    # the neck's tree is head_z itself: its recorded target is the sense of that step
    assert traj.targets[0][1:, 2] == pytest.approx(np.array(z)[1:], abs=2e-3)
    assert "head_z" not in make_family("gp", get_task("lamp_limbo")).info.terminal_names
    fam_gh, _ = apply_preset("gritz-hahn", task)
    assert fam_gh["terminals"][-2:] == ["head_pole_dx", "head_z"]
    with pytest.raises(ValueError, match="pole_senses must be 0 or 1"):
        get_task("lamp_limbo", pole_senses=0.5)


class _Declares(LampHop):
    """lamp_hop declaring task senses (unregistered, for this test)."""
    declared: tuple = ()
    gp = GPSettings(terminals=("px", "t", "speed"))

    def task_senses(self):
        return self.declared


def test_a_task_declaring_bad_senses_gets_one_clear_error():
    def fam(*declared):
        _Declares.declared = declared
        return make_family("gp", _Declares())
    assert fam(TaskSense("speed", "abs(vx) + abs(vz)")).info.terminal_names == ("px", "t", "speed")
    with pytest.raises(ValueError, match="has a figure sense's name"):
        fam(TaskSense("speed", "vx"), TaskSense("px", "vx"))
    with pytest.raises(ValueError, match="repeated task sense names"):
        fam(TaskSense("speed", "vx"), TaskSense("speed", "vz"))
    with pytest.raises(ValueError, match=f"at most {MAX_TASK_SENSES}"):
        fam(*(TaskSense(f"s{k}" if k else "speed", "vx") for k in range(MAX_TASK_SENSES + 1)))
    with pytest.raises(FormulaError, match="task lamp_hop, sense speed = 'vx \\+ nope': unknown sense"):
        fam(TaskSense("speed", "vx + nope"))
    with pytest.raises(ValueError, match="must be an identifier"):
        TaskSense("2fast", "vx")
    with pytest.raises(KeyError, match="has no sense 'speed'"):
        fam()                                                 # 'speed' declared nowhere


def test_a_sense_no_tree_reads_needs_no_function_of_the_runs_set():
    """lamp_limbo declares pole senses written with sin/cos; under the paper's
    function set (no sin) they are not terminals, so the preset's run builds,
    and asking for them as terminals is one clear error."""
    from gpmotion.gp.presets import preset_options
    task = get_task("lamp_limbo")
    fam, _ = preset_options("gritz-hahn", task)
    assert "sin" not in fam["primitives"] and make_family("gp", task, **fam).task_programs == []
    felt = get_task("lamp_limbo", pole_senses=1)
    with pytest.raises(ValueError, match="'sin' is not in this run's primitive set"):
        make_family("gp", felt, **preset_options("gritz-hahn", felt)[0])
