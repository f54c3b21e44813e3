"""Every registered primitive passes the public check_primitive; user plugin
folders register, check and reach the generated interpreter; duplicates fail."""
import math

import numpy as np
import pytest

from gpmotion.check import check_primitive, njit_copy
from gpmotion.gp import primitives
from gpmotion.gp.bytecode import STACK_CAP, encode_trees, tokens_to_tree
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


def test_builtin_set_is_complete():
    assert {"add", "sub", "mul", "div", "iflte", "sin", "cos", "abs"} <= set(BUILTIN)
    assert primitives.get("div").symbol == "%" and primitives.get("iflte").arity == 4
    import gpmotion.primitives as builtin_package           # the folder form is the same set
    assert primitives.load_plugins(builtin_package.__path__[0]) == []


@pytest.mark.parametrize("name, args, want", [
    ("div", (3.0, 0.0), 1.0), ("div", (3.0, 5e-10), 1.0), ("div", (3.0, -2.0), -1.5),
    ("iflte", (1.0, 1.0, 2.0, 3.0), 2.0), ("iflte", (1.5, 1.0, 2.0, 3.0), 3.0),
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
    assert primitives.load_plugins(tmp_path) == ["hypot"]
    assert primitives.load_plugins(tmp_path) == []          # loading again is harmless
    check_primitive("hypot")
    info = build_pset(["px", "vx"])
    assert "hypot" in info.primitive_names
    assert "def prim_hypot(a, b)" in interpreter_source(info)
    kernel = load_interpreter(info)
    ci, cf = encode_trees([tokens_to_tree(["hypot", "px", "vx"], info)], info, [0])
    assert kernel.run_tree(ci, cf, 0, np.array([3.0, 4.0]), np.zeros(STACK_CAP)) == 5.0


def test_duplicate_name_names_both_files(registry, tmp_path):
    (tmp_path / "my_add.py").write_text(
        "from gpmotion.gp.primitives import primitive\n"
        "@primitive('add', arity=2)\ndef add(a, b):\n    return b + a\n")
    with pytest.raises(ValueError, match=r"duplicate primitive 'add'.*arithmetic\.py.*my_add\.py"):
        primitives.load_plugins(tmp_path)


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
    primitives.load_plugins(tmp_path)
    with pytest.raises(AssertionError, match=message):
        check_primitive("bad")


def test_register_rejects_bad_declarations(registry):
    with pytest.raises(ValueError, match="identifier"):
        primitives.register("not a name", lambda a: a, 1)
    with pytest.raises(ValueError, match="arity"):
        primitives.register("zero", lambda: 1.0, 0)
    with pytest.raises(ValueError, match="unknown primitive 'nope'"):
        primitives.get("nope")
