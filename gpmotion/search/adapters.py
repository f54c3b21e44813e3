"""One face for every search the run loop drives (ask / tell / state).

GP (generational, DEAP) and BSR's serial search differ in vocabulary; the
run loop sees only: ``ask() -> genomes``, ``tell(evaluation)``, ``progress``
(0..1, for phased style terms), ``done``, ``generation``, ``best``,
``best_cost``, ``best_final``, ``row()`` (a log.csv row) and a JSON-safe
``state_dict``.

Two scorings are in play while style terms phase in: a search compares
controllers under the *current* weights (its own best-so-far, the log's
``best_so_far``), but what a run is judged by is the *final* scoring
(progress 1), which ``compare``'s table and ``replay`` use.  Every adapter
therefore also keeps :class:`FinalBest`, the best controller evaluated so far
under the final scoring (the log's ``best_final``; monotone), and returns it
as ``best``.
"""
from __future__ import annotations

import math

import numpy as np

from ..evaluate import Evaluation
from .serial import SerialSearch

# Gritz & Hahn: crossover-dominant, little mutation, fitness-proportionate
# selection; we keep one elite so the best is never lost.
GP_DEFAULTS = dict(population=300, generations=40, p_crossover=0.9, p_mutation=0.02,
                   selection="roulette", elitism=1)
SERIAL_DEFAULTS = dict(n_working=10, n_generations=4000, reseed_every=200, phase_steps=20)
ADAPTER_KEY = "final_best"      # the adapter's own entry in a search's state_dict


class FinalBest:
    """Best controller evaluated so far under the task's final scoring.

    A cost under the final weights is computed from an evaluation's raw
    measures (``Task.cost`` at progress 1), at no extra simulation: exact
    whenever the evaluation ran in the final scene.  Under a curriculum
    (``Task.curriculum``) the scene eases in, and measures taken in an earlier
    scene are not final: such evaluations are skipped, and the value is
    unknown (None) until the curriculum is done.
    """

    def __init__(self, family):
        self.family, self.task = family, family.task
        self._final_scene = self.task.staged(1.0)
        self.genome, self.cost = None, math.inf

    def known_at(self, progress: float) -> bool:
        return self.task.staged(progress) == self._final_scene

    def update(self, genomes, ev, progress: float) -> None:
        if not len(genomes) or not self.known_at(progress):
            return
        c = self.task.cost(ev.measures, ev.failed, 1.0)
        i = int(np.argmin(c))                     # first of equal minima
        if self.genome is None or c[i] < self.cost:
            g = genomes[i]
            self.genome = g.copy() if hasattr(g, "copy") else [list(t) for t in g]
            self.cost = float(c[i])

    @property
    def value(self):
        return None if self.genome is None else self.cost

    def state_dict(self):
        return None if self.genome is None else {"genome": self.family.to_json(self.genome),
                                                 "cost": self.cost}

    def load_state_dict(self, d) -> None:
        if d is None:
            self.genome, self.cost = None, math.inf
            return
        if not isinstance(d, dict):
            raise ValueError(f"checkpoint {ADAPTER_KEY} must be an object or null")
        self.genome, self.cost = self.family.from_json(d["genome"]), float(d["cost"])


class _Adapter:
    """What both searches share: the run loop's vocabulary over ``self.search``."""
    kind = ""

    @property
    def done(self):
        return self.search.done

    @property
    def generation(self):
        return self.search.generation

    def ask(self):
        self._asked = self.search.ask()
        return self._asked

    def tell(self, ev: Evaluation):
        """Scores of the last ``ask``, evaluated at ``progress``."""
        self.told_progress = self.progress
        self.final.update(self._asked, ev, self.told_progress)
        self._tell(ev)

    @property
    def best(self):
        """The best under the final scoring once known, else the search's own best."""
        return self.final.genome if self.final.genome is not None else self._search_best

    @property
    def best_cost(self):
        """Cost of ``best``: under the final scoring once known, else the search's."""
        return self.final.cost if self.final.genome is not None else self._search_best_cost

    @property
    def best_final(self):
        """Best cost so far under the final scoring; None while unknown (curriculum)."""
        return self.final.value

    @property
    def best_so_far(self) -> float:
        """Best cost so far under the weights of the round last told."""
        return self._best_so_far()

    def _best_so_far(self) -> float:
        """The log's best_so_far, under the current weights (in the final phase
        these are the final ones, so it is best_final when that is lower)."""
        c, task = self._search_best_cost, self.family.task
        if self.final.value is not None and task.phase(self.told_progress) == task.phase(1.0):
            c = min(c, self.final.value)
        return c

    def _final_column(self):
        return "" if self.final.value is None else self.final.value

    def state_dict(self):
        return {**self.search.state_dict(), ADAPTER_KEY: self.final.state_dict()}

    def load_state_dict(self, d):
        if not isinstance(d, dict):
            raise ValueError("checkpoint search state must be an object")
        self.final.load_state_dict(d.get(ADAPTER_KEY))
        self.search.load_state_dict({k: v for k, v in d.items() if k != ADAPTER_KEY})

    @property
    def evaluations(self):
        return self.search.evaluations

    schedule = None        # generations the style phases span (None: all of them)


class GPAdapter(_Adapter):
    kind = "gp"

    def __init__(self, family, seed: int, **opts):
        from .gp import GPSearch
        self.family = family
        self.search = GPSearch(family, seed=seed,
                               **{**GP_DEFAULTS, **family.task.gp_defaults, **opts})
        self.final = FinalBest(family)

    @property
    def progress(self):
        return self.search.progress

    @property
    def total(self):
        return self.search.generations

    total_key = "generations"

    def extend(self, total: int, schedule: int):
        """Run to ``total`` generations; the phases keep spanning ``schedule``, so
        the added generations run at the final weights.  A finished search
        kept its last population unbred: breed it as tell() would have."""
        s = self.search
        self.schedule = s.schedule = schedule
        if total > s.generations and s.done and s.costs is not None:
            s.generations = total
            s.generation -= 1
            with s._own_random():
                s._set_population(s._breed())
            s.generation += 1
        s.generations = max(s.generations, total)

    def _tell(self, ev: Evaluation):
        self.search.tell(ev.costs, ev)

    @property
    def _search_best(self):
        return self.search.best

    @property
    def _search_best_cost(self):
        return float(self.search.best_cost)

    def row(self, ev: Evaluation) -> dict:
        """log.csv row of the generation just told (whole population, not
        only the genomes evaluated this time: copies reuse their costs)."""
        h = self.search.history[-1]
        return {"generation": h["generation"], "progress": round(h["progress"], 6),
                "best_so_far": self._best_so_far(), "best_final": self._final_column(),
                "gen_min": h["min"], "gen_median": h["median"],
                "gen_mean": h["mean"], "gen_max": h["max"], "evaluated": h["evaluated"],
                "solved": int(ev.success.sum()), "failed": int(ev.failed.sum()),
                "avg_tree_size": round(h["avg_tree_size"], 2)}


def serial_progress(generation: int, n_generations: int, phase_steps: int) -> float:
    """Run progress of serial round ``generation``: held constant over
    ``phase_steps`` equal stages, 0 in the first and 1 in the last, so style
    terms reach full weight and the working set is re-scored at most
    phase_steps − 1 times (not before every round of a ramp)."""
    steps = max(1, min(phase_steps, n_generations))
    if steps == 1:
        return 1.0
    stage = min(steps - 1, generation * steps // max(1, n_generations))
    return stage / (steps - 1)


def serial_rescores(task, n_generations: int, phase_steps: int) -> int:
    """How many times a serial run re-scores its working set (phase changes)."""
    steps = max(1, min(phase_steps, n_generations))
    phases = [task.phase(k / (steps - 1) if steps > 1 else 1.0) for k in range(steps)]
    return sum(a != b for a, b in zip(phases, phases[1:]))


def serial_generations(task, budget: int, n_working: int = 10,
                       phase_steps: int = SERIAL_DEFAULTS["phase_steps"]) -> int:
    """Most rounds whose evaluations (C initial + C per round + C + 1 per
    re-score) fit in ``budget``; at least 1."""
    g = max(1, (budget - n_working) // n_working)
    while g > 1 and n_working * (1 + g) + (n_working + 1) * serial_rescores(
            task, g, phase_steps) > budget:
        g -= 1
    return g


class SerialAdapter(_Adapter):
    """Auslander's serial search minimizing task costs; a 'generation' is one
    round of C mutants (C evaluations).  Run progress moves in ``phase_steps``
    stages (:func:`serial_progress`); when the task's phase changes, the search
    re-scores its working set and best first (C + 1 evaluations, counted)."""
    kind = "serial"

    def __init__(self, family, seed: int, **opts):
        opts = {**SERIAL_DEFAULTS, **opts}
        self.phase_steps = opts.pop("phase_steps")
        if isinstance(self.phase_steps, bool) or not isinstance(self.phase_steps, (int, np.integer)) \
                or self.phase_steps < 1:
            raise ValueError(f"phase_steps must be an integer >= 1, got {self.phase_steps!r}")
        self.family = family
        task = family.task
        search = getattr(family, "serial_search", SerialSearch)    # 3-D bsr-sense: enriched start
        self.search = search(family.random, family.mutate, rng=np.random.default_rng(seed),
                                   maximize=False, genome_to_json=family.to_json,
                                   genome_from_json=family.from_json,
                                   phase_fn=lambda g: task.phase(self.progress_of(g)), **opts)
        self.final = FinalBest(family)

    def progress_of(self, generation: int) -> float:
        n = self.schedule or self.search.n_generations     # an extension keeps the schedule
        return serial_progress(generation, n, int(self.phase_steps))

    @property
    def progress(self):
        return self.progress_of(self.search.generation)

    @property
    def total(self):
        return self.search.n_generations

    total_key = "n_generations"

    def extend(self, total: int, schedule: int):
        """Run to ``total`` rounds; progress keeps spanning ``schedule`` rounds."""
        self.schedule = schedule
        self.search.n_generations = max(self.search.n_generations, total)

    def _tell(self, ev: Evaluation):
        self.search.tell(ev.costs, ev.extras)

    @property
    def _search_best(self):
        return self.search.best_genome

    @property
    def _search_best_cost(self):
        return float(self.search.best_score)

    def row(self, ev: Evaluation) -> dict:
        c = ev.costs
        return {"generation": self.search.generation, "progress": round(self.told_progress, 6),
                "best_so_far": self._best_so_far(), "best_final": self._final_column(),
                "gen_min": float(c.min()),
                "gen_median": float(np.median(c)), "gen_mean": float(c.mean()),
                "gen_max": float(c.max()), "evaluated": len(c), "solved": int(ev.success.sum()),
                "failed": int(ev.failed.sum()), "avg_tree_size": ""}


def make_search(family, seed: int, **opts):
    """GP trees evolve with DEAP; BSR rule tables with the serial search."""
    opts = {k: v for k, v in opts.items() if v is not None}
    if family.name == "gp":
        return GPAdapter(family, seed, **opts)
    return SerialAdapter(family, seed, **opts)
