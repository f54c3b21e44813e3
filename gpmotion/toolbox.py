"""A ready DEAP toolbox for Gritz-Hahn individuals, wired to gpmotion's
evaluator, for DEAP users who prefer their own loop
(``deap.algorithms.eaSimple`` works out of the box, see
``examples/deap_easimple.py``).  The operators are :mod:`gpmotion.gp.operators`.
"""
from __future__ import annotations

import math
from typing import Sequence

from deap import base, creator, gp, tools

from .families.gp import GPFamily
from .gp.bytecode import MAX_TREE_DEPTH
from .gp.operators import (crossover_same_dof, make_tree_operators, mutate_one_dof, random_tree,
                            roulette_indices, tournament_indices)
from .inprocess import InProcessEvaluator
from .task import WORST

FITNESS_CLASS = "GPMotionFitnessMin"
INDIVIDUAL_CLASS = "GPMotionIndividual"


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
    if selection not in ("roulette", "tournament"):
        raise ValueError(f"selection must be 'roulette' or 'tournament', got {selection!r}")
    family = family or GPFamily(task)
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
