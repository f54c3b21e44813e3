"""The GP family option fast_trig (off by default): the interpreter's sin and
cos inlined (gpmotion.gp.fast_trig).  Bit for bit its numpy twin, within
1 ulp of libm; off, the interpreter holds none of it; a controller searched
with it replays with it; refused where it cannot apply."""
import json
import math
import random

import numpy as np
import pytest
from deap import gp
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit

from gpmotion.families import make_family
from gpmotion.gp import primitives as registry
from gpmotion.gp.bytecode import STACK_CAP, encode_trees, tokens_to_tree, tree_to_tokens
from gpmotion.gp.interpreter import (interpreter_path, interpreter_source, load_interpreter,
                                     trig_primitives)
from gpmotion.gp.pset import build_pset
from gpmotion.task import get_task
from tests.cli_checks import refused, refused_before_the_directory
from tests.reference import fast_trig_ref
from tests.reference.gp_interpreter_ref import run_tree_ref

SENSES = ["px", "pz", "vx", "t"]
registry.load_builtin()
INFO = build_pset(["px", "vx", "t"], registry.names(), sense_names=SENSES)
FAST = load_interpreter(INFO, fast_trig=True)
ULP_BOUND = 1                  # measured: benchmarks/gp_fast_trig_ab.py --part accuracy
LIMIT = 2.0 ** 20 * (math.pi / 2)
SERIAL_TINY = ["--param", "seconds=0.3", "--generations", "3", "--quiet", "--no-artifacts"]


@njit(cache=False)
def _apply(f, x, out):
    for i in range(x.shape[0]):
        out[i] = f(x[i])


def compiled(f, x):
    x = np.ascontiguousarray(x, dtype=np.float64)
    out = np.empty_like(x)
    _apply(f, x, out)
    return out


def ulps(a, b):
    """Distance in units in the last place (the bit patterns in float order)."""
    def ordered(x):
        u = np.asarray(x, dtype=np.float64).view(np.uint64)
        return np.where(u >> np.uint64(63), ~u, u | np.uint64(1 << 63))
    ua, ub = ordered(a), ordered(b)
    return np.where(ua >= ub, ua - ub, ub - ua)


def arguments(n=20_000):
    """Uniform up to the interpreter's clamp (1e6), doubles next to multiples
    of pi/2 (where the reduction cancels), the kernels' edge and specials."""
    rng = np.random.default_rng(7)
    k = np.arange(1, 1e6 / (math.pi / 2), 97.0)
    near = k * (math.pi / 2)
    return np.concatenate([rng.uniform(-1, 1, n), rng.uniform(-20, 20, n), rng.uniform(-1e6, 1e6, n),
                           near, np.nextafter(near, np.inf), -near,
                           [0.0, -0.0, 5e-324, -1e-300, 7.45e-9, math.pi / 4, -math.pi / 4,
                            np.nextafter(math.pi / 4, 0), 1e6, -1e6, LIMIT, np.nextafter(LIMIT, 0),
                            2e6, 1e300, math.inf, -math.inf, math.nan]])


@pytest.mark.parametrize("name", ["sin", "cos"])
def test_fast_trig_is_bit_for_bit_its_numpy_twin(name):
    x = arguments()
    got = compiled(getattr(FAST, f"_ft_{name}"), x)
    want = getattr(fast_trig_ref, name)(x)
    assert np.array_equal(got, want, equal_nan=True)
    assert np.array_equal(got[~np.isnan(got)].view(np.int64), want[~np.isnan(want)].view(np.int64))


@settings(deadline=None, max_examples=300)
@given(x=st.floats(allow_nan=True, allow_infinity=True, width=64))
def test_fast_trig_twin_agrees_on_any_double(x):
    for name in ("sin", "cos"):
        got = compiled(getattr(FAST, f"_ft_{name}"), np.array([x]))
        want = getattr(fast_trig_ref, name)(np.array([x]))
        assert got.tobytes() == want.tobytes() or (math.isnan(got[0]) and math.isnan(want[0]))


@pytest.mark.parametrize("name", ["sin", "cos"])
def test_fast_trig_is_within_the_stated_ulps_of_libm(name):
    x = arguments()
    x = x[np.isfinite(x)]
    got = compiled(getattr(FAST, f"_ft_{name}"), x)
    want = np.array([getattr(math, name)(v) for v in x])
    assert ulps(got, want).max() <= ULP_BOUND
    assert np.mean(got == want) > 0.9           # most results are libm's own
    beyond = np.abs(x) >= LIMIT
    assert np.array_equal(got[beyond], want[beyond])         # libm past the reduction's range


def test_the_primitives_keep_their_guards():
    """A non-finite argument still gives 0.0 (the primitive's own rule)."""
    for v in (math.inf, -math.inf, math.nan):
        assert FAST.prim_sin(v) == 0.0 and FAST.prim_cos(v) == 0.0
    assert math.copysign(1.0, FAST.prim_sin(-0.0)) == -1.0


def random_tokens(seed, depth):
    saved = random.getstate()
    try:
        random.seed(seed)
        return tree_to_tokens(gp.PrimitiveTree(gp.genHalfAndHalf(INFO.pset, 1, depth)))
    finally:
        random.setstate(saved)


def _twin_scalar(f):
    def call(a):
        return float(f(np.array([a]))[0]) if math.isfinite(a) else 0.0
    return call


@settings(deadline=None, max_examples=100)
@given(seed=st.integers(0, 2**32 - 1), depth=st.integers(1, 6),
       s=st.lists(st.floats(-50, 50), min_size=len(SENSES), max_size=len(SENSES)))
def test_fast_trees_are_the_reference_interpreter_with_the_twin(seed, depth, s):
    tree = tokens_to_tree(random_tokens(seed, depth), INFO)
    ci, cf = encode_trees([tree], INFO, [0])
    funcs = {p.name: p.func for p in INFO.primitives}
    funcs.update(sin=_twin_scalar(fast_trig_ref.sin), cos=_twin_scalar(fast_trig_ref.cos))
    want = run_tree_ref(ci, cf, 0, np.array(s), [funcs[n] for n in INFO.opcode_names],
                        [p.select for p in INFO.primitives])
    got = FAST.run_tree(ci, cf, 0, np.array(s), np.zeros(STACK_CAP))
    assert np.float64(got).tobytes() == np.float64(want).tobytes()


def test_off_the_interpreter_holds_none_of_it():
    """The default module holds no fast trigonometry and the family records no option."""
    assert "_ft_" not in interpreter_source(INFO)
    assert "prim_sin(a):\n    if not math.isfinite(a):\n        return 0.0\n    return _ft_sin(a)" \
        in interpreter_source(INFO, fast_trig=True)
    assert interpreter_path(INFO) != interpreter_path(INFO, fast_trig=True)
    fam = make_family("gp", get_task("lamp_hop"))
    assert "fast_trig" not in fam.config()
    assert fam.encode([fam.random(np.random.default_rng(0))]).module == str(interpreter_path(fam.info))
    assert trig_primitives(INFO.primitives) == ["cos", "sin"]


def test_a_controller_searched_with_fast_trig_replays_with_it(tmp_path):
    from gpmotion.replay import load_controller, replay_genome
    from gpmotion.run import RunConfig, run
    out = tmp_path / "run"
    run(RunConfig(task="lamp_hop", seed=0, params={"seconds": 0.3}, threads=1,
                  search={"population": 6, "generations": 1}, family_options={"fast_trig": True}),
        out, quiet=True, artifacts=False)
    config = json.loads((out / "config.json").read_text())
    assert config["family_config"]["fast_trig"] is True
    assert config["run"]["family_options"] == {"fast_trig": True}       # what a resume rebuilds
    best = json.loads((out / "best.json").read_text())
    assert best["options"]["fast_trig"] is True
    task, family, actuation, genome, _ = load_controller(out)
    assert family.fast_trig
    traj, costs, _, _ = replay_genome(task, family, actuation, genome)
    assert float(costs[0]) == best["final_cost"]
    libm = make_family("gp", task, **{k: v for k, v in family.options.items() if k != "fast_trig"})
    assert family.encode([genome]).module != libm.encode([genome]).module


def test_fast_trig_is_refused_where_it_cannot_apply(tmp_path, capsys):
    out = tmp_path / "o"
    refused_before_the_directory(
        capsys, ["run", "lamp_hop", "--out", str(out), "--controller", "bsr-time", "--fast-trig",
                 *SERIAL_TINY], out, "--fast-trig does not apply to --controller bsr-time")
    refused(capsys, ["run", "lamp_hop", "--out", str(out), "--primitives", "add,sub,mul",
                     "--fast-trig", *SERIAL_TINY], "fast_trig", "calls no math.sin or math.cos")
    with pytest.raises(ValueError, match="fast_trig must be true or false"):
        make_family("gp", get_task("lamp_hop"), fast_trig="yes")
