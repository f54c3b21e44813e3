"""One face for every search the run loop drives (ask / tell / state).

GP (generational, DEAP) and BSR's serial search differ in vocabulary; the
run loop sees only: ``ask() -> genomes``, ``tell(evaluation)``, ``progress``
(0..1, for phased style terms), ``done``, ``generation``, ``best``,
``best_cost``, ``row()`` (a log.csv row) and a JSON-safe ``state_dict``.
"""
from __future__ import annotations

import numpy as np

from ..evaluate import Evaluation
from .serial import SerialSearch

# Gritz & Hahn: crossover-dominant, little mutation, fitness-proportionate
# selection; we keep one elite so the best is never lost.
GP_DEFAULTS = dict(population=300, generations=40, p_crossover=0.9, p_mutation=0.02,
                   selection="roulette", elitism=1)
SERIAL_DEFAULTS = dict(n_working=10, n_generations=4000, reseed_every=200)


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
        return self.search.ask()

    def state_dict(self):
        return self.search.state_dict()

    def load_state_dict(self, d):
        self.search.load_state_dict(d)

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

    def tell(self, ev: Evaluation):
        self.search.tell(ev.costs, ev)

    @property
    def best(self):
        return self.search.best

    @property
    def best_cost(self):
        return float(self.search.best_cost)

    def row(self, ev: Evaluation) -> dict:
        """log.csv row of the generation just told (whole population, not
        only the genomes evaluated this time: copies reuse their costs)."""
        h = self.search.history[-1]
        return {"generation": h["generation"], "progress": round(h["progress"], 6),
                "best_so_far": h["best_so_far"], "gen_min": h["min"], "gen_median": h["median"],
                "gen_mean": h["mean"], "gen_max": h["max"], "evaluated": h["evaluated"],
                "solved": int(ev.success.sum()), "failed": int(ev.failed.sum()),
                "avg_tree_size": round(h["avg_tree_size"], 2)}


class SerialAdapter(_Adapter):
    """Auslander's serial search minimizing task costs; a 'generation' is one
    round of C mutants (C evaluations)."""
    kind = "serial"

    def __init__(self, family, seed: int, **opts):
        opts = {**SERIAL_DEFAULTS, **opts}
        self.family = family
        self.search = SerialSearch(family.random, family.mutate, rng=np.random.default_rng(seed),
                                   maximize=False, genome_to_json=family.to_json,
                                   genome_from_json=family.from_json, **opts)

    @property
    def progress(self):
        n = self.schedule or self.search.n_generations
        return min(1.0, self.search.generation / max(1, n))

    @property
    def total(self):
        return self.search.n_generations

    total_key = "n_generations"

    def extend(self, total: int, schedule: int):
        """Run to ``total`` rounds; progress keeps spanning ``schedule`` rounds."""
        self.schedule = schedule
        self.search.n_generations = max(self.search.n_generations, total)

    def tell(self, ev: Evaluation):
        self.search.tell(ev.costs, ev.extras)

    @property
    def best(self):
        return self.search.best_genome

    @property
    def best_cost(self):
        return float(self.search.best_score)

    def row(self, ev: Evaluation) -> dict:
        c = ev.costs
        return {"generation": self.search.generation, "progress": round(self.progress, 6),
                "best_so_far": self.best_cost, "gen_min": float(c.min()),
                "gen_median": float(np.median(c)), "gen_mean": float(c.mean()),
                "gen_max": float(c.max()), "evaluated": len(c), "solved": int(ev.success.sum()),
                "failed": int(ev.failed.sum()), "avg_tree_size": ""}


def make_search(family, seed: int, **opts):
    """GP trees evolve with DEAP; BSR rule tables with the serial search."""
    opts = {k: v for k, v in opts.items() if v is not None}
    if family.name == "gp":
        return GPAdapter(family, seed, **opts)
    return SerialAdapter(family, seed, **opts)
