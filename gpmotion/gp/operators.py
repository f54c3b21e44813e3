"""DEAP operators on Gritz-Hahn individuals (the representation's variation
and selection; nothing here runs a simulation).

An individual is a list of trees, one per controlled DOF (actuator).  The
operators here are shared by :class:`gpmotion.search.gp.GPSearch` and by
:func:`gpmotion.toolbox.make_toolbox`, for DEAP users who prefer their
own loop (``deap.algorithms.eaSimple`` works out of the box, see
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
import operator
import random

import numpy as np
from deap import gp

from .bytecode import MAX_TREE_DEPTH, is_erc


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
