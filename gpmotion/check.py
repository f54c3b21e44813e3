"""Public checks for plugins (as Gymnasium's ``check_env``): the contract tests
run exactly these, so a user's plugin is held to the same standard.

``check_primitive`` compiles the *copy* of the primitive that the generated
interpreter uses (not the original function), so it also catches primitives
that rely on module globals the copy cannot see.
"""
from __future__ import annotations

import inspect
import itertools
import math
import numbers
from pathlib import Path

import numpy as np

from gpmotion.cache import digest, import_file, write_module
from gpmotion.gp import primitives as registry

# Edge inputs: zero, tiny, unit, the clamp and far beyond it (huge/huge, x/0 ...).
EDGE_VALUES = (0.0, 1e-12, -1e-12, 1.0, -1.0, 1e6, -1e6, 1e300, -1e300)


def _resolve(p) -> registry.Primitive:
    if isinstance(p, registry.Primitive):
        return p
    if isinstance(p, str):
        registry.load_builtin()
        return registry.get(p)
    prim = getattr(p, "__gpmotion_primitive__", None)
    if prim is None:
        raise TypeError(f"not a primitive: {p!r} (give a name, a Primitive or a "
                        "function decorated with @primitive)")
    return prim


def _saturate(v: float) -> float:
    """The interpreter's clamp without its NaN safety net: NaN stays NaN."""
    return min(max(float(v), -registry.CLAMP), registry.CLAMP) if v == v else math.nan


def _agree(a: float, b: float) -> bool:
    if a != a or b != b:
        return a != a and b != b
    return a == b or math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-300)


def njit_copy(prim: registry.Primitive):
    """The njit-compiled copy of ``prim`` exactly as the interpreter embeds it."""
    from gpmotion.gp.interpreter import primitive_module_source
    src = primitive_module_source([prim])
    module = import_file(write_module(f"prim_{digest(src)}", src))
    return getattr(module, prim.copy_name)


def check_primitive(name_or_prim, *, plugins=None, n_random: int = 300, seed: int = 0) -> None:
    """Raise AssertionError (clear message) unless the primitive is fit for the interpreter.

    ``name_or_prim``: a registered name, a Primitive or an ``@primitive``
    function.  A plugin's primitive is registered once its folder is loaded:
    pass ``plugins="my_plugins"`` (a folder or a list) or call
    ``gpmotion.load_plugins`` first; an unknown name is a ValueError.

    Checks: declared arity matches the signature; its copy compiles in numba;
    njit and Python agree on random inputs and on every combination of
    EDGE_VALUES; results are never NaN (infinities are fine: the interpreter
    saturates them to +-1e6).
    """
    if plugins is not None:
        from gpmotion.plugins import load_folder
        for folder in [plugins] if isinstance(plugins, (str, Path)) else plugins:
            load_folder(folder)
    p = _resolve(name_or_prim)
    where = f"primitive {p.name!r} ({p.file})"
    params = list(inspect.signature(p.func).parameters.values())
    plain = all(q.kind in (q.POSITIONAL_ONLY, q.POSITIONAL_OR_KEYWORD)
                and q.default is q.empty for q in params)
    if not plain or len(params) != p.arity:
        raise AssertionError(f"{where}: declared arity {p.arity} but signature is "
                             f"{inspect.signature(p.func)} (need {p.arity} plain arguments)")
    try:
        fast = njit_copy(p)
        fast(*([0.5] * p.arity))
    except Exception as exc:          # numba TypingError etc.
        first = str(exc).strip().splitlines()[:6]
        raise AssertionError(f"{where}: does not compile in numba "
                             "(only builtins, math/numpy and names the plugin file imports "
                             "are visible to the copy):\n  " + "\n  ".join(first)) from exc

    rng = np.random.default_rng(seed)
    scales = np.array([1.0, 1e-3, 1e3, 1e6])
    randoms = (rng.uniform(-1, 1, (n_random, p.arity))
               * scales[rng.integers(0, len(scales), (n_random, p.arity))])
    cases = itertools.chain(map(tuple, randoms.tolist()),
                            itertools.product(EDGE_VALUES, repeat=p.arity))
    for args in cases:
        try:
            slow = p.func(*args)
        except Exception as exc:
            raise AssertionError(f"{where}: Python form raised {exc!r} on {args}") from exc
        if not isinstance(slow, numbers.Real):
            raise AssertionError(f"{where}: returned {slow!r} (not a number) on {args}")
        got = fast(*args)
        if not isinstance(got, (float, np.floating)):
            raise AssertionError(f"{where}: njit returned {type(got).__name__}, not float, on {args}")
        a, b = _saturate(slow), _saturate(got)
        if a != a or b != b:
            raise AssertionError(f"{where}: NaN on inputs {args} (Python {slow!r}, njit {got!r}); "
                                 "handle that case explicitly")
        if not _agree(a, b):
            raise AssertionError(f"{where}: njit {got!r} != Python {slow!r} on {args}")
    return None


# --------------------------------------------------------------------------
# check_task: the task contract (builds, rolls out, scores finite, deterministic)
# --------------------------------------------------------------------------

def check_task(task, *, n_controllers: int = 6, seed: int = 0, seconds: float | None = 0.5) -> None:
    """Run the public task contract on a task name, class or instance.

    Builds the task (short episodes by default, to keep it quick) and a GP
    family on it (so its terminals must be senses of its figure and its
    primitive set registered), rolls out random GP controllers, and checks
    every term is a finite number per episode, the total is finite, success is
    a bool per episode, two evaluations of the same genomes agree exactly, the
    phase factors lie in [0, 1], a scene exists at every progress and the
    curriculum ends at the task's parameters.  Raises AssertionError naming
    the problem.
    """
    import random

    from deap import gp as dgp

    from gpmotion.inprocess import InProcessEvaluator
    from gpmotion.families.gp import GPFamily
    from gpmotion.task import Task, get_task

    name = getattr(task, "name", task)
    try:
        if isinstance(task, Task):
            t = task
        elif isinstance(task, type):
            t = task(**({"seconds": seconds} if seconds and "seconds" in task.params else {}))
        else:
            t = get_task(task, **({"seconds": seconds} if seconds else {}))
        fam = GPFamily(t)
    except Exception as e:  # noqa: BLE001 - report any failure as a contract failure
        raise AssertionError(f"task {name}: does not build: {e}") from e
    term_names = [x.name for x in t.terms]
    if len(set(term_names)) != len(term_names):
        raise AssertionError(f"task {name}: repeated term names {term_names}")
    state = random.getstate()
    random.seed(seed)
    try:
        genomes = [[dgp.PrimitiveTree(dgp.genHalfAndHalf(fam.pset, 1, 4)) for _ in fam.actuators]
                   for _ in range(n_controllers)]
    finally:
        random.setstate(state)
    ev = InProcessEvaluator(t, fam)
    a = ev.evaluate(genomes, 1.0)
    b = ev.evaluate(genomes, 1.0)
    for term in term_names:
        v = np.asarray(a.measures.get(term))
        if v.shape != (n_controllers,):
            raise AssertionError(f"task {name}: term {term!r} has shape {v.shape}, want ({n_controllers},)")
        if not np.all(np.isfinite(v)):
            raise AssertionError(f"task {name}: term {term!r} is not finite: {v}")
    if not np.all(np.isfinite(a.costs)):
        raise AssertionError(f"task {name}: non-finite total cost {a.costs}")
    if a.success.dtype != bool or a.success.shape != (n_controllers,):
        raise AssertionError(f"task {name}: success must be a bool per episode")
    if not (np.array_equal(a.costs, b.costs) and np.array_equal(a.success, b.success)):
        raise AssertionError(f"task {name}: two evaluations of the same controllers differ")
    for progress in (0.0, 0.5, 1.0):
        for term in t.terms:
            f = term.factor(progress)
            if not 0.0 <= f <= 1.0:
                raise AssertionError(f"task {name}: phase factor of {term.name} is {f} at {progress}")
        try:
            t.scene_at(progress)
        except Exception as e:  # noqa: BLE001
            raise AssertionError(f"task {name}: no scene at progress {progress}: {e}") from e
    if t.params_at(1.0) != t.params:
        raise AssertionError(f"task {name}: the curriculum does not end at the task's parameters")
    if t.curriculum:
        c = ev.evaluate(genomes[:1], 0.0)
        if not np.all(np.isfinite(c.costs)):
            raise AssertionError(f"task {name}: non-finite cost at the curriculum's start")
    return None


# ------------------------------------------------------------------ families

ROW_COLUMNS = ("generation", "progress", "best_so_far", "best_final", "gen_min", "gen_median",
               "gen_mean", "gen_max", "evaluated", "solved", "failed")


def _family_class(family):
    from gpmotion.families.base import Family, family_class
    cls = family_class(family) if isinstance(family, str) else family
    if not (isinstance(cls, type) and issubclass(cls, Family) and cls.name):
        raise AssertionError(f"{family!r} is not a named Family subclass")
    return cls


def _json_round_trip(fam, genome, what: str):
    import json
    d = fam.to_json(genome)
    try:
        text = json.dumps(d, allow_nan=False)
    except (TypeError, ValueError) as e:
        raise AssertionError(f"{what}: to_json is not plain JSON ({e})") from e
    again = fam.to_json(fam.from_json(json.loads(text)))
    if again != d:
        raise AssertionError(f"{what}: from_json(to_json(genome)) is another genome")
    if fam.to_json(fam.copy(genome)) != d:
        raise AssertionError(f"{what}: copy(genome) is another genome")
    return d


def check_family(family, *, task: str = "lamp_hop", seconds: float = 0.3, seed: int = 0,
                 n_genomes: int = 4) -> None:
    """Run the public contract of a controller family (a name or a Family class).

    Checks its declaration (actuation, search class, CLI options), then on
    ``task``: random genomes are deterministic for a seed, survive safe JSON
    and ``copy`` unchanged, garbage is refused with a ValueError, the batch
    encodes and rolls out to finite costs twice alike, ``mutate`` (where a
    family has one) is deterministic and gives valid genomes; its search under a
    small budget asks, is told, writes a log row, and resumes exactly from
    a JSON round trip of its ``state_dict``.  Raises AssertionError naming
    the problem.
    """
    import json

    from gpmotion import cli_options
    from gpmotion.controllers import ControllerBatch
    from gpmotion.inprocess import InProcessEvaluator
    from gpmotion.search.base import Search
    from gpmotion.task import get_task

    cls = _family_class(family)
    name = f"family {cls.name}"
    if cls.default_actuation not in ("pd", "kinematic"):
        raise AssertionError(f"{name}: default_actuation {cls.default_actuation!r}")
    if not (isinstance(cls.search_class, type) and issubclass(cls.search_class, Search)):
        raise AssertionError(f"{name}: search_class must be a gpmotion.search.base.Search")
    for flag in cls.cli:
        try:
            option = cli_options.get_option(flag)
        except KeyError:
            raise AssertionError(f"{name}: its cli names {flag}, not a registered option") from None
        if cls.name not in option.keys:
            raise AssertionError(f"{name}: {flag} does not apply to it (register_family)")
    t = get_task(task, seconds=seconds)
    fam = cls(t)
    genomes = [fam.random(np.random.default_rng(seed)) for _ in range(2)]
    if fam.to_json(genomes[0]) != fam.to_json(genomes[1]):
        raise AssertionError(f"{name}: random(rng) differs for the same seed")
    rng = np.random.default_rng(seed)
    genomes = [fam.random(rng) for _ in range(n_genomes)]
    for i, g in enumerate(genomes):
        _json_round_trip(fam, g, f"{name}, genome {i}")
    for bad in (None, [], "x", {}, {"kind": "?"}, 1.5):
        try:
            fam.from_json(bad)
        except ValueError:
            continue
        except Exception as e:  # noqa: BLE001 - any other type is the failure reported
            raise AssertionError(f"{name}: from_json({bad!r}) raised {type(e).__name__}, "
                                 "not ValueError") from e
        raise AssertionError(f"{name}: from_json({bad!r}) accepted garbage")
    batch = fam.encode(genomes)
    if not isinstance(batch, ControllerBatch) or batch.n_episodes != n_genomes \
            or not Path(batch.module).is_file():
        raise AssertionError(f"{name}: encode must give a ControllerBatch of one row per genome "
                             "and an existing kernel module")
    ev = InProcessEvaluator(t, fam)
    a, b = ev.evaluate(genomes), ev.evaluate(genomes)
    if not np.all(np.isfinite(a.costs)) or not np.array_equal(a.costs, b.costs):
        raise AssertionError(f"{name}: costs must be finite and repeat exactly: {a.costs} {b.costs}")
    if a.extras is not None and len(a.extras) != n_genomes:
        raise AssertionError(f"{name}: extras must be None or one per genome")
    _check_family_mutate(name, fam, genomes, a.extras, seed)
    _check_family_search(name, fam, ev, seed, json)


def _check_family_mutate(name, fam, genomes, extras, seed) -> None:
    """``mutate`` (optional: what a composite's phase refinement climbs with) is
    deterministic for a seed and gives a valid, different genome (callers
    pass it a copy: it may change its argument)."""
    from gpmotion.families.base import Family
    if type(fam).mutate is Family.mutate:
        return
    g, extra = genomes[0], extras[0] if extras is not None else None
    before = fam.to_json(g)
    m1, m2 = (fam.mutate(fam.copy(g), np.random.default_rng(seed), extra) for _ in range(2))
    if fam.to_json(m1) != fam.to_json(m2):
        raise AssertionError(f"{name}: mutate(genome, rng) differs for the same seed")
    _json_round_trip(fam, m1, f"{name}, mutated genome")
    rng = np.random.default_rng(seed)
    if all(fam.to_json(fam.mutate(fam.copy(g), rng, extra)) == before for _ in range(5)):
        raise AssertionError(f"{name}: five mutations all gave the genome back")


def _check_family_search(name, fam, ev, seed, json) -> None:
    settings = fam.budget_settings(60, 8 if fam.takes_population else None)
    unknown = set(settings) - fam.setting_names()
    if unknown:
        raise AssertionError(f"{name}: budget_settings gives {sorted(unknown)}, not settings "
                             f"of its search ({sorted(fam.setting_names())})")

    def step(search):
        genomes = search.ask()
        for g in genomes[:2]:
            _json_round_trip(fam, g, f"{name}, asked genome")
        search.tell(ev.evaluate(genomes, search.progress))

    s = fam.make_search(seed, **settings)
    step(s)
    row = s.row()
    missing = [c for c in ROW_COLUMNS if c not in row]
    if missing:
        raise AssertionError(f"{name}: its log row lacks {missing}")
    if s.best is None or not np.isfinite(s.best_cost):
        raise AssertionError(f"{name}: no best (or a non-finite cost) after a round")
    try:
        state = json.loads(json.dumps(s.state_dict(), allow_nan=False))
    except (TypeError, ValueError) as e:
        raise AssertionError(f"{name}: state_dict is not plain JSON ({e})") from e
    if s.done:
        raise AssertionError(f"{name}: a budget of 60 evaluations ended after one round")
    resumed = fam.make_search(seed + 1, **settings)
    resumed.load_state_dict(state)
    nxt, again = s.ask(), resumed.ask()
    if [fam.to_json(g) for g in nxt] != [fam.to_json(g) for g in again]:
        raise AssertionError(f"{name}: a search restored from its state_dict asks otherwise")
    step(s)
    step(resumed)
    if s.row() != resumed.row() or s.best_cost != resumed.best_cost:
        raise AssertionError(f"{name}: a restored search is told alike but reports otherwise")
