"""Gritz & Hahn's genetic programming as an ask/tell object.

An individual is a list of ``gp.PrimitiveTree``, one per actuator.  The
search never simulates: ``ask()`` returns plain-data genomes (one token list
per tree, what ``family.encode``/``to_json`` take and what crosses processes)
to be evaluated at ``progress``; ``tell(evaluation)`` takes their costs
(lower is better) and breeds the next generation (the interface, the
final-scoring best and the log rows are :class:`gpmotion.search.base.Search`'s).
Operators are in :mod:`gpmotion.gp.operators` (crossover between trees of the same DOF only,
one random DOF per mating; ``mutUniform`` on one DOF; static depth/size
limits; roulette on ``1/(1+cost)`` or tournament).  Each new individual is
made by crossover with ``p_crossover``, mutation with ``p_mutation``,
constant creep with ``p_creep`` (Gaussian steps of std ``creep_sigma`` on
one tree's constants), else reproduction (a copy); the best ``elitism``
pass unchanged.  With ``islands`` = K > 1 the population is K demes that
breed apart (elitism per deme) and every ``migrate_every`` generations pass
their ``migrants`` best around a ring (an island model: the demes explore
different solutions, so one stuck deme does not stall the run).  With
``polish`` = P > 0 the last P generations do not breed: each is the previous
generation's best and population − 1 of its variations (``family.mutate``),
a (1 + λ) local search that tunes the best controller's constants and output
offsets (memetic GP).

Decisions, stated once here:

* **Costs and phases.**  A cost depends on ``progress`` only through the
  task's style-term factors (``Term.factor``), so the *phase* of a generation
  is that tuple of factors.  Every individual of every generation gets a cost
  under its own generation's phase: copies (elites, reproduction, crossovers
  that changed nothing) reuse their parent's cost only when the phase is
  unchanged (``reuse_costs=True``; this relies on evaluation being
  deterministic, which the task contract tests check), otherwise they are
  re-evaluated.  Identical genomes within a generation are evaluated once.
  So ``ask()`` returns the *unique, unknown* genomes only, and generation 0
  the whole (deduplicated) population.
* **Hall of fame across phases.**  Costs from different phases are not
  comparable (style terms only add cost as they phase in).  ``hall_of_fame`` is
  replaced by a generation's best when that cost is strictly lower *or* the
  incumbent was scored under another phase; so once the phases stop changing
  (progress past every term's ramp, and always in the last generation,
  progress 1), ``hall_of_fame`` is the best ever under the full score.
  ``generation_best`` keeps each generation's best with the cost it had then.
  With ``fresh_scores`` (robust runs: starts redrawn each generation, so
  costs of two generations are not comparable either) every generation is a
  phase of its own: ``hall_of_fame`` and the final-weights best are the last
  generation's best, not the luckiest cost of the run.
* **Randomness.**  DEAP's operators (and the primitive set's ERC) draw from
  the module-level :mod:`random`.  The search keeps its own state, seeded
  from ``seed``: around each variation step it saves the caller's global
  state, installs its own, and afterwards stores its advanced state and
  puts the caller's back.  A search is therefore deterministic whatever other
  code does with ``random``, and leaves it untouched (not thread-safe: do not
  use ``random`` from another thread while ``tell`` runs).
* ``generations`` = G generations are evaluated, 0..G-1 (generation 0 is
  the random one; G = 1 is random search).  ``generation`` counts the
  generations told so far (= index of the one ``ask`` hands out), and
  ``progress = generation / (G - 1)`` (1 for G = 1), so the last generation
  is scored with every style term fully on (``generation / G`` never reaches
  1, and a term ramping up to progress 1 would never count in full).
* **Stopping.**  A run ends after ``generations``, or earlier on either of
  two stated criteria: ``patience`` = K > 0 stops once every style term is
  at full weight (the phase is the final one) and the best under the final
  weights has improved by less than ``PATIENCE_TOLERANCE`` (relative) over the
  last K generations; ``phase_span`` = S > 0 lays the phases over the first
  S generations instead of all ``generations`` (progress = generation /
  (S - 1), capped at 1), so with patience the run ends when it is done, K
  generations or more after the last term reached full weight, and
  ``generations`` is only a cap; ``stop_on_success`` ends the run in the first
  generation some genome solves the task once the scene is final (``True``)
  or once every style term is at full weight too (``"full-weight"``, Gritz &
  Hahn's criterion with the style points in force).
"""
from __future__ import annotations

import contextlib
import math
import random

import numpy as np
from deap import gp

from ..gp.bytecode import MAX_TREE_DEPTH, MAX_TREE_SIZE, tokens_to_tree, tree_to_tokens
from ..gp.operators import (clean_costs, creep_constants, crossover_same_dof,
                            make_tree_operators, mutate_one_dof, random_tree, roulette_indices,
                            tournament_indices)
from ..records import python_random_state_from_json, python_random_state_to_json
from ..task import WORST
from .base import GenerationalSearch

STATE_FORMAT = "gp-search-v1"
SELECTIONS = ("roulette", "tournament")
STOP_ON_SUCCESS = (False, True, "full-weight")
PATIENCE_TOLERANCE = 0.01     # patience: a relative gain below 1 % over K generations is none


# The keys a gp-search-v1 state may hold, level by level (optional ones included):
# a key this gpmotion did not write is a foreign or edited record, never ignored.
_STATE_KEYS = {"format", "pset", "config", "generation", "evaluations", "stopped", "converged",
               "final_trace", "random", "population", "costs", "parents", "best",
               "generation_best", "history"}
_NESTED_KEYS = {
    "parents": {"phase", "genomes", "costs"},
    "best": {"genome", "cost", "generation", "phase"},
    "generation_best": {"generation", "progress", "cost", "genome"},
    "history": {"generation", "progress", "evaluations", "evaluated", "min", "median", "mean",
                "max", "best_so_far", "avg_tree_size", "max_tree_depth", "n_success",
                "n_failed"},
}


def _check_keys(state: dict) -> None:
    """Refuse a key at any level of the state that :meth:`GPSearch._state` never writes."""
    def refuse(where, obj, known):
        if not isinstance(obj, dict):
            raise ValueError(f"{where} must be an object, got {type(obj).__name__}")
        unknown = sorted(map(str, set(obj) - known))
        if unknown:
            raise ValueError(f"{where}: unknown key(s) {unknown[:5]}; not a state this "
                             "gpmotion wrote")
    refuse("search", state, _STATE_KEYS)
    for name in ("parents", "best"):
        if state.get(name) is not None:
            refuse(f"search.{name}", state[name], _NESTED_KEYS[name])
    for name in ("generation_best", "history"):
        rows = state.get(name)
        if not isinstance(rows, list):
            raise ValueError(f"search.{name} must be a list")
        for i, row in enumerate(rows):
            refuse(f"search.{name}[{i}]", row, _NESTED_KEYS[name])


def _is_int(x) -> bool:
    return isinstance(x, (int, np.integer)) and not isinstance(x, bool)


def genome_key(individual) -> tuple:
    """Hashable identity of an individual: its trees' token tuples."""
    return tuple(tuple(tree_to_tokens(t) if isinstance(t, gp.PrimitiveTree) else t)
                 for t in individual)


class GPSearch(GenerationalSearch):
    """Generational GP over one-tree-per-DOF individuals (Gritz & Hahn)."""
    total_key = "generations"

    def __init__(self, family, population: int = 500, generations: int = 50,
                 p_crossover: float = 0.9, p_mutation: float = 0.02,
                 p_creep: float = 0.0, creep_sigma: float = 0.1,
                 islands: int = 1, migrate_every: int = 5, migrants: int = 2,
                 selection: str = "roulette", tournament_size: int = 7, elitism: int = 1,
                 init_depth: tuple[int, int] = (2, 6), max_depth: int = MAX_TREE_DEPTH,
                 max_size: int = 200, seed: int | None = None, reuse_costs: bool = True,
                 stop_on_success: bool | str = False, fresh_scores: bool = False, polish: int = 0,
                 patience: int = 0, phase_span: int = 0, task=None):
        super().__init__(family, task if task is not None else getattr(family, "task", None))
        self._configure(dict(population=population, generations=generations,
                             p_crossover=p_crossover, p_mutation=p_mutation,
                             p_creep=p_creep, creep_sigma=creep_sigma, islands=islands,
                             migrate_every=migrate_every, migrants=migrants,
                             selection=selection, tournament_size=tournament_size,
                             elitism=elitism, init_depth=init_depth, max_depth=max_depth,
                             max_size=max_size, seed=seed, reuse_costs=reuse_costs,
                             stop_on_success=stop_on_success, fresh_scores=fresh_scores,
                             polish=polish, patience=patience, phase_span=phase_span))
        self.stopped = False                      # stop_on_success fired
        self.converged = False                    # patience fired
        self._final_trace: list[float] = []       # final-weights best after each full-weight generation
        self._rstate = random.Random(self.seed).getstate()
        self.generation = 0
        self.evaluations = 0
        self.costs: np.ndarray | None = None      # costs of the current population, once told
        self._pending: list[tuple] | None = None
        self._parents: dict[tuple, float] = {}    # last told generation: key -> cost
        self._parents_phase: tuple | None = None
        self._best_key, self.hof_cost = None, float("inf")
        self.best_generation, self._best_phase = -1, None
        self.generation_best: list[dict] = []
        self.history: list[dict] = []
        self._height_memo: dict[tuple, int] = {}  # tree tokens -> depth (_heights)
        with self._own_random():
            self._set_population(self._initial_population())

    # -- configuration -------------------------------------------------------
    def _configure(self, c: dict) -> None:
        def bad(what, value):
            raise ValueError(f"GPSearch: {what}, got {value!r}")
        if not _is_int(c["population"]) or c["population"] < 2:
            bad("population must be an integer >= 2", c["population"])
        if not _is_int(c["generations"]) or c["generations"] < 1:
            bad("generations must be an integer >= 1", c["generations"])
        c.setdefault("p_creep", 0.0)            # checkpoints written before creep existed
        c.setdefault("stop_on_success", False)
        c.setdefault("fresh_scores", False)     # absent before robust runs kept a per-round best
        c.setdefault("polish", 0)               # absent before the final local search existed
        c.setdefault("patience", 0)             # absent before the convergence stop existed
        c.setdefault("phase_span", 0)
        c.setdefault("creep_sigma", 0.1)
        for k, v in (("islands", 1), ("migrate_every", 5), ("migrants", 2)):
            c.setdefault(k, v)
        for k in ("p_crossover", "p_mutation", "p_creep"):
            if isinstance(c[k], bool) or not isinstance(c[k], (int, float)) or not 0 <= c[k] <= 1:
                bad(f"{k} must be a number in [0, 1]", c[k])
        total = c["p_crossover"] + c["p_mutation"] + c["p_creep"]
        if total > 1:
            bad("p_crossover + p_mutation + p_creep must be <= 1", total)
        sigma = c["creep_sigma"]
        if isinstance(sigma, bool) or not isinstance(sigma, (int, float)) or not 0 < sigma < 100:
            bad("creep_sigma must be a number in (0, 100)", sigma)
        if c["selection"] not in SELECTIONS:
            bad(f"selection must be one of {SELECTIONS}", c["selection"])
        if not _is_int(c["tournament_size"]) or c["tournament_size"] < 1:
            bad("tournament_size must be an integer >= 1", c["tournament_size"])
        if not _is_int(c["islands"]) or not 1 <= c["islands"] <= c["population"] // 2:
            bad("islands must be an integer in [1, population / 2]", c["islands"])
        island = c["population"] // c["islands"]
        if not _is_int(c["migrate_every"]) or c["migrate_every"] < 1:
            bad("migrate_every must be an integer >= 1", c["migrate_every"])
        if not _is_int(c["migrants"]) or not 0 <= c["migrants"] <= island // 2:
            bad("migrants must be an integer in [0, island size / 2]", c["migrants"])
        if not _is_int(c["elitism"]) or not 0 <= c["elitism"] <= island:
            bad("elitism must be an integer in [0, population / islands]", c["elitism"])
        if not _is_int(c["max_depth"]) or not 1 <= c["max_depth"] <= MAX_TREE_DEPTH:
            bad(f"max_depth must be an integer in [1, {MAX_TREE_DEPTH}]", c["max_depth"])
        if not _is_int(c["max_size"]) or not 1 <= c["max_size"] <= MAX_TREE_SIZE:
            bad(f"max_size must be an integer in [1, {MAX_TREE_SIZE}]", c["max_size"])
        d = c["init_depth"]
        if (not isinstance(d, (tuple, list)) or len(d) != 2 or not all(map(_is_int, d))
                or not 0 <= d[0] <= d[1] <= c["max_depth"]):
            bad("init_depth must be (min, max) integers with 0 <= min <= max <= max_depth", d)
        if not isinstance(c["fresh_scores"], bool):
            bad("fresh_scores must be true or false", c["fresh_scores"])
        if c["fresh_scores"] and c["reuse_costs"]:
            bad("fresh_scores (costs comparable within a generation only) needs reuse_costs "
                "false", c["fresh_scores"])
        if not _is_int(c["polish"]) or not 0 <= c["polish"] < c["generations"]:
            bad("polish must be an integer in [0, generations)", c["polish"])
        if not _is_int(c["patience"]) or not 0 <= c["patience"] <= 10**6:
            bad("patience must be an integer >= 0 (0: run every generation)", c["patience"])
        if not _is_int(c["phase_span"]) or not 0 <= c["phase_span"] <= c["generations"]:
            bad("phase_span must be an integer in [0, generations] (0: all of them)",
                c["phase_span"])
        if not (isinstance(c["stop_on_success"], bool) or c["stop_on_success"] == "full-weight"):
            bad(f"stop_on_success must be one of {STOP_ON_SUCCESS}", c["stop_on_success"])
        if not _is_int(c["seed"]):
            bad("seed must be an integer (randomness is explicit)", c["seed"])
        self.population_size, self.generations = int(c["population"]), int(c["generations"])
        self.p_crossover, self.p_mutation = float(c["p_crossover"]), float(c["p_mutation"])
        self.p_creep, self.creep_sigma = float(c["p_creep"]), float(c["creep_sigma"])
        self.islands, self.migrate_every = int(c["islands"]), int(c["migrate_every"])
        self.migrants = int(c["migrants"])
        self.selection, self.tournament_size = c["selection"], int(c["tournament_size"])
        self.elitism, self.init_depth = int(c["elitism"]), (int(d[0]), int(d[1]))
        self.max_depth, self.max_size = int(c["max_depth"]), int(c["max_size"])
        self.seed, self.reuse_costs = int(c["seed"]), bool(c["reuse_costs"])
        sos = c["stop_on_success"]
        self.stop_on_success = sos if isinstance(sos, str) else bool(sos)
        self.polish, self.patience = int(c["polish"]), int(c["patience"])
        self.phase_span = int(c["phase_span"])
        self._set_fresh_scores(c["fresh_scores"])
        self._cx, self._mut = make_tree_operators(self.family.pset, self.max_depth, self.max_size)

    def config(self) -> dict:
        return {"population": self.population_size, "generations": self.generations,
                "p_crossover": self.p_crossover, "p_mutation": self.p_mutation,
                "p_creep": self.p_creep, "creep_sigma": self.creep_sigma,
                "islands": self.islands, "migrate_every": self.migrate_every,
                "migrants": self.migrants,
                "selection": self.selection, "tournament_size": self.tournament_size,
                "elitism": self.elitism, "init_depth": list(self.init_depth),
                "max_depth": self.max_depth, "max_size": self.max_size, "seed": self.seed,
                "reuse_costs": self.reuse_costs, "stop_on_success": self.stop_on_success,
                **({"fresh_scores": True} if self.fresh_scores else {}),   # absent: as before
                **({"polish": self.polish} if self.polish else {}),
                **({"patience": self.patience} if self.patience else {}),
                **({"phase_span": self.phase_span} if self.phase_span else {})}

    # -- randomness ----------------------------------------------------------
    @contextlib.contextmanager
    def _own_random(self):
        """Run DEAP's operators on this search's ``random`` state (module docstring)."""
        outer = random.getstate()
        random.setstate(self._rstate)
        try:
            yield
        finally:
            self._rstate = random.getstate()
            random.setstate(outer)

    # -- phases --------------------------------------------------------------
    def extend(self, total: int, schedule: int) -> None:
        """Run to ``total`` generations; the phases keep spanning ``schedule``, so
        the added generations run at the final weights.  A finished search
        kept its last population unbred: breed it as tell() would have."""
        self.schedule = schedule
        if total > self.generations and self.converged:
            self.converged, self._final_trace = False, []
        if total > self.generations and self.done and self.costs is not None:
            self.generations = total
            self.generation -= 1
            with self._own_random():
                self._set_population(self._breed())
            self.generation += 1
        self.generations = max(self.generations, total)

    def progress_of(self, generation: int) -> float:
        n = self.phase_span or self.schedule or self.generations
        return 1.0 if n == 1 else min(1.0, generation / (n - 1))

    @property
    def progress_span(self) -> int:
        return max(1, (self.phase_span or self.schedule or self.generations) - 1)

    def _cache_phase(self, generation: int) -> tuple:
        return self.phase_of(generation) if self.reuse_costs else (float(generation),)

    # -- population ----------------------------------------------------------
    def _initial_population(self) -> list:
        """Ramped half-and-half trees; duplicate individuals redrawn (a few tries)."""
        pop, seen = [], set()
        for _ in range(self.population_size):
            for _attempt in range(10):
                ind = [random_tree(self.family.pset, self.init_depth, self.max_depth,
                                   self.max_size) for _ in self.family.actuators]
                if genome_key(ind) not in seen:
                    break
            seen.add(genome_key(ind))
            pop.append(ind)
        return pop

    def _set_population(self, pop: list) -> None:
        self._pop = pop
        self._keys = [genome_key(ind) for ind in pop]
        self.costs = None

    @property
    def population(self) -> list:
        """The current population as plain-data genomes (token lists)."""
        return [[list(t) for t in k] for k in self._keys]

    # -- ask / tell ------------------------------------------------------------
    @property
    def done(self) -> bool:
        return self.stopped or self.converged or self.generation >= self.generations

    def _known(self) -> dict:
        same = self._parents_phase == self._cache_phase(self.generation)
        return self._parents if same else {}

    def _ask(self) -> list:
        """Genomes (lists of token lists) to evaluate at ``progress``; asking
        again before ``tell`` returns the same list."""
        if self.done:
            raise RuntimeError("GP search finished; read best")
        if self._pending is None:
            known, seen, pending = self._known(), set(), []
            for k in self._keys:
                if k not in known and k not in seen:
                    seen.add(k)
                    pending.append(k)
            self._pending = pending
        return [[list(t) for t in k] for k in self._pending]

    def _tell(self, evaluation) -> None:
        """Costs (lower is better) for the genomes of the last ``ask``, in order;
        non-finite costs count as ``WORST``."""
        if self._pending is None:
            raise RuntimeError("tell() without a pending ask()")
        c = clean_costs(evaluation.costs, WORST)
        if c.size != len(self._pending):
            raise ValueError(f"tell: expected {len(self._pending)} costs, got {c.size}")
        table = dict(self._known())
        table.update(zip(self._pending, c.tolist()))
        self.costs = np.array([table[k] for k in self._keys], dtype=np.float64)
        self.evaluations += len(self._pending)
        self._record(len(self._pending), evaluation)
        self._stop_if_solved(evaluation, c)
        self._stop_if_converged(evaluation)
        self._parents = {k: table[k] for k in self._keys}
        self._parents_phase = self._cache_phase(self.generation)
        self._pending = None
        if not self.done and self.generation + 1 < self.generations:   # the last population stays
            with self._own_random():
                self._set_population(self._breed())
        self.generation += 1

    def _record(self, n_evaluated: int, evaluation) -> None:
        c = self._told_costs = self.costs           # the population's costs (breeding resets them)
        i = int(np.argmin(c))                    # first of equal minima
        phase = self.judged_phase(self.generation)    # with fresh scores: this generation's best
        cost = float(c[i])
        self.generation_best.append({"generation": self.generation, "progress": self.progress,
                                     "cost": cost, "genome": [list(t) for t in self._keys[i]]})
        if self._best_key is None or phase != self._best_phase or cost < self.hof_cost:
            self._best_key, self.hof_cost = self._keys[i], cost
            self.best_generation, self._best_phase = self.generation, phase
        sizes = [len(t) for ind in self._pop for t in ind]
        heights = self._heights()
        row = {"generation": self.generation, "progress": self.progress,
               "evaluations": self.evaluations, "evaluated": n_evaluated,
               "min": cost, "median": float(np.median(c)), "mean": float(np.mean(c)),
               "max": float(np.max(c)),
               "best_so_far": self.hof_cost, "avg_tree_size": float(np.mean(sizes)),
               "max_tree_depth": max(heights)}
        row["n_success"] = int(np.sum(evaluation.success))
        row["n_failed"] = int(np.sum(evaluation.failed))
        self.history.append(row)

    def _heights(self) -> list[int]:
        """Every tree's depth, remembered per token tuple across generations
        (DEAP's ``height`` walks the tree in Python; most trees of a
        generation were in the last one).  Only the current trees are kept."""
        old, memo = self._height_memo, {}
        for ind, key in zip(self._pop, self._keys):
            for tree, tokens in zip(ind, key):
                if tokens not in memo:
                    memo[tokens] = old[tokens] if tokens in old else tree.height
        self._height_memo = memo
        return [memo[tokens] for key in self._keys for tokens in key]

    def _stop_if_solved(self, evaluation, costs) -> None:
        """``stop_on_success`` (Gritz & Hahn's termination criterion): once the
        scene is the final one (no curriculum step left), a generation in which
        some genome solves the task ends the run; ``best`` becomes the cheapest
        solving genome of that generation."""
        task = self.task
        if not self.stop_on_success or task is None:
            return
        if (task.staged(self.progress) != task.staged(1.0) if self.stop_on_success is True
                else self.phase_of(self.generation) != self.phase_at(1.0)):
            return
        ok = np.flatnonzero(np.asarray(evaluation.success, dtype=bool))
        if ok.size:
            i = int(ok[np.argmin(costs[ok])])
            self._best_key, self.hof_cost = self._pending[i], float(costs[i])
            self.best_generation, self._best_phase = self.generation, self.judged_phase(self.generation)
            self.stopped = True

    def _stop_if_converged(self, evaluation) -> None:
        """``patience`` = K: in the final phase, stop once the final-weights best
        (with this generation's evaluations) is within ``PATIENCE_TOLERANCE`` of
        what it was K generations ago."""
        if not self.patience or self.phase_of(self.generation) != self.phase_at(1.0):
            return
        ev = evaluation
        c = ev.costs if self.task is None else (
            self.task.cost(ev.measures, ev.failed, 1.0) if ev.measures else None)
        now = math.inf if self.fresh_scores else self.final.cost   # fresh: this round's best
        if c is not None and len(c):
            c = np.where(np.isfinite(c), c, math.inf)
            now = min(now, float(c.min()))
        if not math.isfinite(now):
            return                                  # nothing judged under the final weights yet
        trace = self._final_trace
        trace.append(now)
        k = self.patience
        if len(trace) > k and not trace[-1] < trace[-1 - k] * (1 - PATIENCE_TOLERANCE):
            self.converged = True

    def _island_bounds(self) -> list[tuple[int, int]]:
        """[lo, hi) index range of every island in the flat population."""
        k, n = self.islands, self.population_size
        edges = [i * n // k for i in range(k + 1)]
        return list(zip(edges[:-1], edges[1:]))

    def _migrate(self, pop: list, costs: np.ndarray):
        """Ring migration: each island's ``migrants`` best replace the next
        island's worst (copies, with their costs, before breeding)."""
        pop, costs = list(pop), costs.copy()
        bounds = self._island_bounds()
        best = [lo + np.argsort(costs[lo:hi], kind="stable")[:self.migrants] for lo, hi in bounds]
        for i, (lo, hi) in enumerate(bounds):
            src = best[i - 1]                        # from the previous island of the ring
            worst = lo + np.argsort(costs[lo:hi], kind="stable")[::-1][:len(src)]
            for w, b in zip(worst, src):
                pop[w], costs[w] = pop[b], costs[b]
        return pop, costs

    def _breed(self) -> list:
        """Next population, island by island (one island: the whole population);
        in the last ``polish`` generations a local search around the best."""
        if self.generation + 1 >= self.generations - self.polish:
            return self._polish()
        pop, costs = self._pop, self.costs
        if self.islands > 1 and (self.generation + 1) % self.migrate_every == 0:
            pop, costs = self._migrate(pop, costs)
        new = []
        for lo, hi in self._island_bounds():
            new += self._breed_deme(pop[lo:hi], costs[lo:hi])
        return new

    def _polish(self) -> list:
        """A (1 + λ) step: this generation's best and population − 1 variations
        of it (``family.mutate``: constant creep, an output bias, now and then
        a new subtree), so the final generations tune the best controller
        rather than breed (costs of one generation share its phase, so the
        best is judged like the mutants)."""
        i = int(np.argmin(self.costs))
        rng = np.random.default_rng(random.getrandbits(63))
        new = [list(self._pop[i])]
        for _ in range(self.population_size - 1):
            tokens = self.family.mutate([list(t) for t in self._keys[i]], rng,
                                        max_depth=self.max_depth, max_size=self.max_size)
            new.append([tokens_to_tree(t, self.family.info) for t in tokens])
        return new

    def _breed_deme(self, pop: list, costs: np.ndarray) -> list:
        """Elites, then crossover / mutation / creep / reproduction, within one deme."""
        size = len(pop)
        order = np.argsort(costs, kind="stable")
        costs = costs.tolist()
        new = [list(pop[i]) for i in order[:self.elitism]]   # trees are never modified in place

        def pick(k):
            return (roulette_indices(costs, k) if self.selection == "roulette"
                    else tournament_indices(costs, k, self.tournament_size))
        while len(new) < size:
            r = random.random()
            if r < self.p_crossover:
                i, j = pick(2)
                a, b, _ = crossover_same_dof(list(pop[i]), list(pop[j]), self._cx)
                new.extend([a, b][:size - len(new)])
            elif r < self.p_crossover + self.p_mutation:
                (i,) = pick(1)
                new.append(mutate_one_dof(list(pop[i]), self._mut)[0])
            elif r < self.p_crossover + self.p_mutation + self.p_creep:
                (i,) = pick(1)
                new.append(creep_constants(list(pop[i]), self.creep_sigma)[0])
            else:
                (i,) = pick(1)
                new.append(list(pop[i]))
        return new

    # -- results ---------------------------------------------------------------
    @property
    def best(self):
        """Once ``stop_on_success`` fired: the solver it kept, not a cheaper non-solver the
        final scoring saw earlier (with robust starts: one whose starts were easy)."""
        return self.hall_of_fame if self.stopped else super().best

    @property
    def best_cost(self) -> float:
        return float(self.hof_cost) if self.stopped else super().best_cost

    @property
    def hall_of_fame(self):
        """Hall-of-fame genome (token lists), or None before the first ``tell``."""
        return None if self._best_key is None else [list(t) for t in self._best_key]

    def _own_best(self) -> tuple:
        return self.hall_of_fame, self.hof_cost

    def _row_costs(self, ev) -> tuple:
        """A row names the generation told and is over the whole population
        (copies reuse their costs), not only the genomes evaluated this time."""
        return self.generation - 1, self._told_costs

    def _row_columns(self) -> dict:
        return {"avg_tree_size": round(self.history[-1]["avg_tree_size"], 2)}

    def logged_generation(self) -> int:
        return self.generation - 1

    def check_restored(self) -> None:
        if len(self.population) != self.population_size:
            raise ValueError(f"its population has {len(self.population)} entries, the settings "
                             f"say {self.population_size}")
        # a phase tells which costs compare: a mangled one must not pass as "another phase"
        for what, got, want in (
                ("parents.phase", self._parents_phase, self._cache_phase(self.generation)),
                ("best.phase", self._best_phase, self.judged_phase(max(self.best_generation, 0)))):
            if got is not None and (len(got) != len(want) or not all(
                    isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
                    for x in got)):
                raise ValueError(f"{what} must be {len(want)} finite numbers, got {got!r:.60}")

    # -- checkpoints -------------------------------------------------------------
    def _state(self) -> dict:
        """JSON-safe snapshot; a pending ``ask`` is recomputed on resume."""
        enc = self.family.to_json
        dec_key = lambda k: enc([list(t) for t in k])  # noqa: E731
        return {
            "format": STATE_FORMAT, "pset": self.family.info.hash, "config": self.config(),
            "generation": self.generation, "evaluations": self.evaluations, "stopped": self.stopped,
            **({"converged": True} if self.converged else {}),
            **({"final_trace": list(self._final_trace)} if self._final_trace else {}),
            "random": python_random_state_to_json(self._rstate),
            "population": [dec_key(k) for k in self._keys],
            "costs": None if self.costs is None else self.costs.tolist(),
            "parents": None if self._parents_phase is None else {
                "phase": list(self._parents_phase),
                "genomes": [dec_key(k) for k in self._parents],
                "costs": list(self._parents.values())},
            "best": None if self._best_key is None else {
                "genome": dec_key(self._best_key), "cost": self.hof_cost,
                "generation": self.best_generation, "phase": list(self._best_phase)},
            "generation_best": [dict(g, genome=enc(g["genome"])) for g in self.generation_best],
            "history": [dict(h) for h in self.history],
        }

    def _load(self, state: dict) -> None:
        """Restore a :meth:`state_dict` snapshot (its config wins)."""
        if not isinstance(state, dict) or state.get("format") != STATE_FORMAT:
            raise ValueError(f"not a {STATE_FORMAT} checkpoint")
        if state.get("pset") != self.family.info.hash:
            raise ValueError(f"checkpoint primitive set {state.get('pset')} differs from "
                             f"this family's {self.family.info.hash}")
        _check_keys(state)
        info = self.family.info

        def key(d):
            return genome_key(tokens_to_tree(t, info) for t in self.family.from_json(d))

        def trees(k):
            return [tokens_to_tree(list(t), info) for t in k]
        self._configure({**state["config"], "init_depth": tuple(state["config"]["init_depth"])})
        self.generation, self.evaluations = int(state["generation"]), int(state["evaluations"])
        self.stopped = bool(state.get("stopped", False))
        self.converged = bool(state.get("converged", False))
        self._final_trace = [float(x) for x in state.get("final_trace", [])]
        self._rstate = python_random_state_from_json(state["random"])
        self._set_population([trees(key(d)) for d in state["population"]])
        if state["costs"] is not None:
            self.costs = np.array(state["costs"], dtype=np.float64)
        par = state["parents"]
        self._parents = {} if par is None else {
            key(d): float(c) for d, c in zip(par["genomes"], par["costs"])}
        self._parents_phase = None if par is None else tuple(par["phase"])
        b = state["best"]
        self._best_key = None if b is None else key(b["genome"])
        self.hof_cost = float("inf") if b is None else float(b["cost"])
        self.best_generation = -1 if b is None else int(b["generation"])
        self._best_phase = None if b is None else tuple(b["phase"])
        self.generation_best = [dict(g, genome=[list(t) for t in key(g["genome"])])
                                for g in state["generation_best"]]
        self.history = [dict(h) for h in state["history"]]
        self._pending = None
