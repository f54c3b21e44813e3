"""Every registered primitive passes the public check_primitive; user plugin
folders register, check and reach the generated interpreter; duplicates fail."""
import math

import numpy as np
import pytest

from gpmotion import plugins
from gpmotion.check import check_primitive, njit_copy
from gpmotion.gp import primitives
from gpmotion.gp.bytecode import HEADER, STACK_CAP, encode_trees, tokens_to_tree
from gpmotion.gp.interpreter import interpreter_source, load_interpreter
from gpmotion.gp.pset import build_pset

primitives.load_builtin()
BUILTIN = primitives.names()

HYPOT = '''\
"""A user primitive: Euclidean length."""
import math

from gpmotion.gp.primitives import primitive


@primitive("hypot", arity=2)
def hypot(a, b):
    return math.hypot(a, b)
'''


@pytest.fixture
def registry(monkeypatch):
    """Isolate registrations made by a test."""
    monkeypatch.setattr(primitives, "_REGISTRY", dict(primitives._REGISTRY))


def load_plugins(folder, modules=None):
    """Load a plugin folder through its manifest (every .py, by default); new primitive names."""
    modules = sorted(p.stem for p in folder.glob("*.py")) if modules is None else modules
    (folder / plugins.MANIFEST).write_text(f"modules = {list(modules)!r}\n")
    before = set(primitives.names())
    plugins.load_folder(folder)
    return sorted(set(primitives.names()) - before)


def test_builtin_set_is_complete():
    assert {"add", "sub", "mul", "div", "iflte", "ifpos", "sin", "cos", "abs"} <= set(BUILTIN)
    assert primitives.get("div").symbol == "%" and primitives.get("iflte").arity == 4
    assert primitives.get("iflte").select == (0, 1) and primitives.get("iflte").branches == (2, 3)
    assert primitives.get("ifpos").select == (0,) and primitives.get("ifpos").arity == 3
    assert "ifpos" not in primitives.STANDARD                 # opt-in: default runs unchanged
    assert primitives.STANDARD == tuple(sorted(set(BUILTIN) - {"ifpos"}))   # the old default set


@pytest.mark.parametrize("name, args, want", [
    ("div", (3.0, 0.0), 1.0), ("div", (3.0, 5e-10), 1.0), ("div", (3.0, -2.0), -1.5),
    ("iflte", (1.0, 1.0, 2.0, 3.0), 2.0), ("iflte", (1.5, 1.0, 2.0, 3.0), 3.0),
    ("ifpos", (1e-9, 2.0, 3.0), 2.0), ("ifpos", (0.0, 2.0, 3.0), 3.0), ("ifpos", (-1.0, 2.0, 3.0), 3.0),
    ("sin", (math.inf,), 0.0), ("cos", (math.nan,), 0.0), ("cos", (0.0,), 1.0),
    ("abs", (-2.5,), 2.5), ("sub", (1.0, 3.0), -2.0),
])
def test_builtin_semantics(name, args, want):
    prim = primitives.get(name)
    assert prim.func(*args) == want
    assert njit_copy(prim)(*args) == want


@pytest.mark.parametrize("name", BUILTIN)
def test_builtin_primitive_contract(name):
    assert check_primitive(name) is None


def test_user_plugin_folder(registry, tmp_path):
    (tmp_path / "hypot.py").write_text(HYPOT)
    assert len(HYPOT.splitlines()) < 15
    assert load_plugins(tmp_path) == ["hypot"]
    assert load_plugins(tmp_path) == []                     # loading again is harmless
    check_primitive("hypot")
    assert "hypot" not in build_pset(["px", "vx"]).primitive_names    # registered: in no set
    info = build_pset(["px", "vx"], primitives.STANDARD + ("hypot",))
    assert info.primitive_names[-1] == "hypot"
    assert "def prim_hypot(a, b)" in interpreter_source(info)
    kernel = load_interpreter(info)
    ci, cf = encode_trees([tokens_to_tree(["hypot", "px", "vx"], info)], info, [0])
    assert kernel.run_tree(ci, cf, 0, np.array([3.0, 4.0]), np.zeros(STACK_CAP)) == 5.0


def test_duplicate_name_names_both_files(registry, tmp_path):
    (tmp_path / "my_add.py").write_text(
        "from gpmotion.gp.primitives import primitive\n"
        "@primitive('add', arity=2)\ndef add(a, b):\n    return b + a\n")
    with pytest.raises(ValueError, match=r"duplicate primitive 'add'.*arithmetic\.py.*my_add\.py"):
        load_plugins(tmp_path)


@pytest.mark.parametrize("body, arity, message", [
    ("def bad(a):\n    return a * 1e300 - a * 1e300\n", 1, "NaN"),
    ("def bad(a, b):\n    return a\n", 1, "arity"),
    ("def bad(a):\n    return SECRET * a\nSECRET = 2.0\n", 1, "compile"),
    ("import math\ndef bad(a):\n    return math.exp(a)\n", 1, "raised"),   # OverflowError in Python
])
def test_check_primitive_rejects_bad(registry, tmp_path, body, arity, message):
    (tmp_path / "bad.py").write_text(
        "from gpmotion.gp.primitives import register\n" + body
        + f"register('bad', bad, arity={arity})\n")
    load_plugins(tmp_path)
    with pytest.raises(AssertionError, match=message):
        check_primitive("bad")


def test_register_rejects_bad_declarations(registry):
    with pytest.raises(ValueError, match="identifier"):
        primitives.register("not a name", lambda a: a, 1)
    with pytest.raises(ValueError, match="arity"):
        primitives.register("zero", lambda: 1.0, 0)
    with pytest.raises(ValueError, match="unknown primitive 'nope'"):
        primitives.get("nope")


# A user conditional whose selector is its LAST argument and that has three branches.
PICK3 = '''
from gpmotion.gp.primitives import primitive


@primitive("pick3", arity=4, select=(3,))
def pick3(a, b, c, s):
    if s < -0.5:
        return a
    if s <= 0.5:
        return b
    return c
'''


def test_user_conditional_is_lazy_and_agrees_with_deap(registry, tmp_path):
    from deap import gp

    from gpmotion.gp.bytecode import OP_JUMP
    from gpmotion.gp.pset import compile_reference
    (tmp_path / "pick3.py").write_text(PICK3)
    assert load_plugins(tmp_path) == ["pick3"]
    check_primitive("pick3")
    p = primitives.get("pick3")
    assert p.select == (3,) and p.branches == (0, 1, 2)
    info = build_pset(["px", "vx"], ["add", "mul", "pick3"])
    kernel = load_interpreter(info)
    tree = tokens_to_tree(["pick3", "add", "px", 1.0, "mul", "px", "vx", "vx", "px"], info)
    ci, cf = encode_trees([tree], info, [0])
    assert OP_JUMP in ci[HEADER + 3::2]
    ref = compile_reference(tree, info)
    for px in (-2.0, -0.5, 0.0, 0.5, 0.7, 3.0):
        s = np.array([px, 1.5])
        for lazy in (True, False):
            ci, cf = encode_trees([tree], info, [0], lazy=lazy)
            assert kernel.run_tree(ci, cf, 0, s, np.zeros(STACK_CAP)) == ref(s)
    import random
    random.seed(5)
    for _ in range(100):
        t = gp.PrimitiveTree(gp.genHalfAndHalf(info.pset, 1, 5))
        f = compile_reference(t, info)
        ci, cf = encode_trees([t], info, [0])
        for s in ([0.3, -0.6], [1.0, 0.0], [-1.0, 2.0]):
            s = np.array(s)
            assert kernel.run_tree(ci, cf, 0, s, np.zeros(STACK_CAP)) == pytest.approx(f(s), rel=1e-12)


@pytest.mark.parametrize("body, select, message", [
    ("def c(a, b, x):\n    return a + b if x > 0 else b\n", 1, "branch arguments unchanged"),
    ("def c(x, b, d):\n    return b if d > x else d\n", 1, "branch arguments unchanged"),  # reads a branch
    ("def c(x, b, d):\n    return b if x > 0 else d\n", 3, "select must name"),
    ("def c(x, b, d):\n    return b if x > 0 else d\n", (0, 0), "select must name"),
    ("def c(x, b, d):\n    return b if x > 0 else d\n", True, "select must be"),
])
def test_bad_conditional_declarations(registry, body, select, message, tmp_path):
    (tmp_path / "c.py").write_text(
        "from gpmotion.gp.primitives import register\n" + body
        + f"register('c', c, arity=3, select={select!r})\n")
    with pytest.raises(ValueError, match=message):
        load_plugins(tmp_path)


def test_registering_a_primitive_changes_no_task_run(registry, tmp_path):
    """Every task names its primitive set: a new primitive (a plugin's, registered
    like any other) leaves each task's set, its hash and its seeded random trees as
    they were, so runs stay bit for bit and checkpoints still resume."""
    import random

    from deap import gp

    from gpmotion.families import make_family
    from gpmotion.task import get_task, task_ids

    def fingerprint(tid):
        fam = make_family("gp", get_task(tid))
        random.seed(11)
        trees = [str(gp.PrimitiveTree(gp.genHalfAndHalf(fam.pset, 1, 5))) for _ in range(20)]
        return fam.info.primitive_names, fam.info.hash, trees

    ids = task_ids()
    before = {t: fingerprint(t) for t in ids}
    (tmp_path / "hypot_run.py").write_text(HYPOT.replace('"hypot"', '"hypot_run"'))
    assert load_plugins(tmp_path) == ["hypot_run"]
    for t in ids:
        assert fingerprint(t) == before[t], t
    assert all(before[t][0] == primitives.STANDARD for t in ids)   # today's default set, in order


def test_default_keyword_is_deprecated(registry):
    def twice(a):
        return 2.0 * a
    with pytest.warns(DeprecationWarning, match="no effect"):
        primitives.register("twice_dep", twice, 1, default=False)
    assert "twice_dep" in primitives.names() and "twice_dep" not in primitives.STANDARD
