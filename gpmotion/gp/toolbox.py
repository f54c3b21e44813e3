"""DEAP operators on Gritz-Hahn individuals, and a ready DEAP toolbox.

An individual is a list of trees, one per controlled DOF (actuator).  The
operators here are shared by :class:`gpmotion.search.gp.GPSearch` and by
:func:`make_toolbox`, for DEAP users who prefer their own loop
(``deap.algorithms.eaSimple`` works out of the box, see
``examples/deap_easimple.py``).

Why these choices:

* **Crossover only between trees of the same DOF** (Gritz & Hahn: the list
  structure is never disturbed).  One mating = one crossover point, as in
  Koza: pick one DOF uniformly among those where both parents' trees have a
  non-root node, and ``gp.cxOnePoint`` those two trees; the other DOFs are
  inherited unchanged.  Uniform over DOFs (not weighted by tree size) so a
  small tree still gets varied.
* **Mutation**: ``gp.mutUniform`` with a ``genFull`` depth 0-2 subtree on one
  random DOF.
* **Constant creep** (not in Gritz & Hahn; the BSR serial search's "creep"
  step, applied to GP): the random constants of one random DOF's tree move
  by Gaussian steps.  Crossover and mutation only recombine or redraw
  constants, so a controller that is 3 cm off a target has no fine step
  towards it; creep gives one.  Off by default (``p_creep = 0``).
* **Bloat control**: both operators are wrapped in ``gp.staticLimit`` on
  depth and size; an over-limit child tree is replaced by one of its parent
  trees (of the same DOF).
* **Selection on costs** (lower is better): roulette on Koza's adjusted
  fitness ``1 / (1 + cost)``, or tournament.  DEAP's ``selRoulette`` assumes
  maximisation, hence our own.

All of these draw from the module-level :mod:`random`, as DEAP's operators
do; ``GPSearch`` swaps its own state in and out around them.
"""
from __future__ import annotations

import bisect
import functools
import math
import operator
import random
from typing import Sequence

import numpy as np
from deap import base, creator, gp, tools

from gpmotion.gp.bytecode import MAX_TREE_DEPTH, is_erc
from gpmotion.task import WORST

FITNESS_CLASS = "GPMotionFitnessMin"
INDIVIDUAL_CLASS = "GPMotionIndividual"


# ------------------------------------------------------------- tree operators

def limited(func, max_depth: int, max_size: int):
    """``func`` (trees in, trees out) under Koza's static depth and size limits."""
    func = gp.staticLimit(operator.attrgetter("height"), max_depth)(func)
    return gp.staticLimit(len, max_size)(func)


def make_tree_operators(pset, max_depth: int = MAX_TREE_DEPTH, max_size: int = 200):
    """(crossover of two same-DOF trees, mutation of one tree), both limited."""
    cx = limited(gp.cxOnePoint, max_depth, max_size)
    mut = limited(functools.partial(gp.mutUniform, pset=pset,
                                    expr=functools.partial(gp.genFull, min_=0, max_=2)),
                  max_depth, max_size)
    return cx, mut


def crossover_same_dof(ind1, ind2, tree_cx):
    """Swap subtrees between the trees of ONE random DOF, in place; returns
    ``(ind1, ind2, dof)`` (dof None when no DOF has a non-root node in both)."""
    dofs = [d for d in range(len(ind1)) if len(ind1[d]) > 1 and len(ind2[d]) > 1]
    if not dofs:
        return ind1, ind2, None
    d = random.choice(dofs)
    a, b = tree_cx(gp.PrimitiveTree(ind1[d]), gp.PrimitiveTree(ind2[d]))
    ind1[d], ind2[d] = a, b
    return ind1, ind2, d


def mutate_one_dof(ind, tree_mut):
    """``mutUniform`` on one random DOF's tree, in place; returns ``(ind, dof)``."""
    d = random.randrange(len(ind))
    (ind[d],) = tree_mut(gp.PrimitiveTree(ind[d]))
    return ind, d


def creep_constants(ind, sigma: float):
    """Gaussian step (std ``sigma``) on every constant of one random DOF's tree
    that has constants, in place; returns ``(ind, dof)`` (None: no constants)."""
    dofs = [d for d, t in enumerate(ind) if any(is_erc(n) for n in t)]
    if not dofs:
        return ind, None
    d = random.choice(dofs)
    nodes = []
    for n in ind[d]:
        if is_erc(n):
            c = type(n).__new__(type(n))
            c.value = float(n.value + random.gauss(0.0, sigma))
            n = c
        nodes.append(n)
    ind[d] = gp.PrimitiveTree(nodes)
    return ind, d


def random_tree(pset, depth: tuple[int, int], max_depth: int, max_size: int,
                tries: int = 50) -> gp.PrimitiveTree:
    """Ramped half-and-half tree within the limits (redrawn when too big:
    arity-4 primitives make a full depth-6 tree far larger than the size cap)."""
    lo, hi = depth
    for k in range(tries):
        t = gp.PrimitiveTree(gp.genHalfAndHalf(pset, min_=lo, max_=hi if k < tries // 2 else lo))
        if len(t) <= max_size and t.height <= max_depth:
            return t
    return gp.PrimitiveTree(gp.genFull(pset, min_=0, max_=0))      # a single terminal


# ------------------------------------------------------------------ selection

def clean_costs(costs, worst: float) -> np.ndarray:
    """float64 costs with NaN/inf (either sign) replaced by ``worst``."""
    c = np.array(costs, dtype=np.float64).ravel()
    c[~np.isfinite(c)] = worst
    return c


def adjusted_fitness(costs) -> np.ndarray:
    """Koza's ``1 / (1 + cost)``; costs below 0 are shifted so the minimum is 0."""
    c = np.asarray(costs, dtype=np.float64)
    shift = min(0.0, float(c.min())) if c.size else 0.0
    return 1.0 / (1.0 + (c - shift))


def roulette_indices(costs, k: int) -> list[int]:
    """k indices drawn with probability proportional to adjusted fitness."""
    cum = np.cumsum(adjusted_fitness(costs)).tolist()
    total = cum[-1]
    return [min(bisect.bisect_right(cum, random.random() * total), len(cum) - 1)
            for _ in range(k)]


def tournament_indices(costs, k: int, size: int) -> list[int]:
    """k winners of ``size``-way tournaments (lowest cost; first drawn wins ties)."""
    n = len(costs)
    out = []
    for _ in range(k):
        entrants = [random.randrange(n) for _ in range(size)]
        out.append(min(entrants, key=lambda i: costs[i]))
    return out


# --------------------------------------------------------------- DEAP toolbox

def _creator_classes():
    """Create the creator classes once per process (DEAP warns on re-creation)."""
    if not hasattr(creator, FITNESS_CLASS):
        creator.create(FITNESS_CLASS, base.Fitness, weights=(-1.0,))
    if not hasattr(creator, INDIVIDUAL_CLASS):
        creator.create(INDIVIDUAL_CLASS, list, fitness=getattr(creator, FITNESS_CLASS))
    return getattr(creator, FITNESS_CLASS), getattr(creator, INDIVIDUAL_CLASS)


def _select(individuals, k, method="roulette", tournament_size=7):
    costs = [ind.fitness.values[0] for ind in individuals]
    idx = (roulette_indices(costs, k) if method == "roulette"
           else tournament_indices(costs, k, tournament_size))
    return [individuals[i] for i in idx]


def make_toolbox(task, family=None, *, evaluator=None, init_depth=(2, 6),
                 max_depth: int = MAX_TREE_DEPTH, max_size: int = 200,
                 selection: str = "roulette", tournament_size: int = 7,
                 generations: int | None = None, progress: float = 1.0) -> base.Toolbox:
    """A DEAP toolbox over lists of trees (one per actuator) for ``task``.

    Registers ``expr``, ``tree``, ``individual``, ``population``, ``mate``,
    ``mutate``, ``select``, ``evaluate`` (ONE individual -> ``(cost,)``) and a
    ``map`` that batches ``evaluate`` into one rollout (so ``eaSimple``'s
    ``toolbox.map(toolbox.evaluate, invalid)`` is one batched simulation);
    any other function is mapped plainly.

    Style phase-in: with ``generations`` given, every batched evaluation
    counts as one generation and ``progress = min(1, batch / generations)``
    (``eaSimple`` evaluates once per generation); otherwise ``progress`` stays
    fixed.  Note ``eaSimple`` does not re-score unchanged copies, so their
    costs may date from an earlier phase; ``GPSearch`` handles that.
    """
    from gpmotion.evaluate import InProcessEvaluator
    from gpmotion.families import make_family
    if selection not in ("roulette", "tournament"):
        raise ValueError(f"selection must be 'roulette' or 'tournament', got {selection!r}")
    family = family or make_family("gp", task)
    evaluator = evaluator or InProcessEvaluator(task, family)
    _, Individual = _creator_classes()
    pset = family.pset
    n_trees = len(family.actuators)
    tree_cx, tree_mut = make_tree_operators(pset, max_depth, max_size)

    tb = base.Toolbox()
    tb.family, tb.evaluator = family, evaluator
    tb.generations, tb.progress, tb.batches = generations, float(progress), 0
    tb.register("expr", gp.genHalfAndHalf, pset=pset, min_=init_depth[0], max_=init_depth[1])
    tb.register("tree", random_tree, pset, tuple(init_depth), max_depth, max_size)
    tb.register("individual", tools.initRepeat, Individual, tb.tree, n=n_trees)
    tb.register("population", tools.initRepeat, list, tb.individual)
    tb.register("mate", lambda a, b: crossover_same_dof(a, b, tree_cx)[:2])
    tb.register("mutate", lambda ind: (mutate_one_dof(ind, tree_mut)[0],))
    tb.register("select", _select, method=selection, tournament_size=tournament_size)
    tb.register("compile", gp.compile, pset=pset)

    def evaluate_one(individual):
        return (float(evaluate_population(tb, [individual], tb.progress, assign=False).costs[0]),)

    def batched_map(func, *iterables):
        if getattr(func, "func", func) is evaluate_one:       # our evaluate: one rollout
            inds = list(iterables[0])
            if tb.generations:
                tb.progress = min(1.0, tb.batches / tb.generations)
            tb.batches += 1
            costs = evaluate_population(tb, inds, tb.progress, assign=False).costs
            return [(float(c),) for c in costs]
        return list(map(func, *iterables))

    tb.register("evaluate", evaluate_one)
    tb.register("map", batched_map)
    return tb


def evaluate_population(toolbox_or_family, individuals: Sequence, progress: float = 1.0,
                        assign: bool = True):
    """Evaluate many individuals in one batched rollout; returns the ``Evaluation``.

    With ``assign`` each individual that has a ``fitness`` gets ``(cost,)``.
    Accepts a toolbox from :func:`make_toolbox` (its evaluator) or a family
    (an in-process evaluator is built for ``family.task``).
    """
    from gpmotion.evaluate import InProcessEvaluator
    ev = getattr(toolbox_or_family, "evaluator", None)
    if ev is None:
        fam = toolbox_or_family
        ev = InProcessEvaluator(fam.task, fam)
    individuals = list(individuals)
    result = ev.evaluate(individuals, progress)
    if assign:
        for ind, c in zip(individuals, result.costs):
            if hasattr(ind, "fitness"):
                ind.fitness.values = (float(c) if math.isfinite(c) else WORST,)
    return result
