"""One search interface for every controller family (DESIGN.md point 9).

A search proposes genomes and is told their scores; it never simulates::

    genomes = search.ask()                  # plain-data genomes to evaluate at search.progress
    search.tell(evaluation)                 # an Evaluation of exactly those genomes
    search.row()                            # the log.csv row of the round just told
    search.best, search.best_cost           # what the run reports
    search.state_dict() / load_state_dict() # JSON-safe, exact resume

:class:`Search` writes, once for every search, what the run loop needs
beyond the algorithm: the best under the final scoring, the log row, the
state of both.  A subclass supplies the algorithm (``_ask``, ``_tell``,
``progress_of``, its own best, ``_state`` / ``_load``) and its settings.

Two scorings are in play while style terms phase in: a search compares
controllers under the *current* weights (its own best, the log's
``best_so_far``), but what a run is judged by is the *final* scoring
(progress 1), which ``compare``'s table and ``replay`` use.  So every search
also keeps :class:`FinalBest`, the best controller evaluated so far under the
final scoring (the log's ``best_final``; monotone), and reports it as
``best``.

A cost depends on run progress only through ``task.phase(progress)`` (the
style-term factors and the curriculum); a search without a task has one
phase, and its final costs are the costs it is told.
"""
from __future__ import annotations

import inspect
import math

import numpy as np

from ..evaluation import Evaluation

FINAL_KEY = "final_best"      # the base's own entry in a search's state_dict


class FinalBest:
    """Best controller evaluated so far under the task's final scoring.

    A cost under the final weights is computed from an evaluation's raw
    measures (``Task.cost`` at progress 1), at no extra simulation: exact
    whenever the evaluation ran in the final scene.  Under a curriculum
    (``Task.curriculum``) the scene eases in, and measures taken in an earlier
    scene are not final: such evaluations are skipped, and the value is
    unknown (None) until the curriculum is done.  Bare costs (no measures,
    a toy objective) are final costs when there is no task, else skipped.

    ``per_round``: costs of different rounds are not comparable (robust
    starts redrawn each round), so the best is the best of the latest round
    told (every batch told at that round), not the luckiest of the run.
    """

    def __init__(self, family, task=None, per_round: bool = False):
        self.family, self.task, self.per_round = family, task, per_round
        self._final_scene = None if task is None else task.staged(1.0)
        self.genome, self.cost = None, math.inf
        self.round = None                 # the round the best is of (per_round)

    def known_at(self, progress: float) -> bool:
        return self.task is None or self.task.staged(progress) == self._final_scene

    def _final_costs(self, ev: Evaluation):
        if self.task is None:
            return ev.costs
        if not ev.measures:
            return None
        return self.task.cost(ev.measures, ev.failed, 1.0)

    def update(self, genomes, ev: Evaluation, progress: float, round_: int | None = None) -> None:
        if not len(genomes) or not self.known_at(progress):
            return
        if self.per_round and round_ != self.round:
            self.genome, self.cost, self.round = None, math.inf, round_
        c = self._final_costs(ev)
        if c is None:
            return
        c = np.where(np.isfinite(c), c, math.inf)     # non-finite: never a best
        i = int(np.argmin(c))                     # first of equal minima
        if c[i] < self.cost:
            self.genome, self.cost = self.family.copy(genomes[i]), float(c[i])

    @property
    def value(self):
        return None if self.genome is None else self.cost

    def state_dict(self):
        if self.genome is None:
            return None
        own = {"round": self.round} if self.per_round else {}
        return {"genome": self.family.to_json(self.genome), "cost": self.cost, **own}

    def load_state_dict(self, d) -> None:
        if d is None:
            self.genome, self.cost, self.round = None, math.inf, None
            return
        if not isinstance(d, dict):
            raise ValueError(f"checkpoint {FINAL_KEY} must be an object or null")
        unknown = sorted(map(str, set(d) - {"genome", "cost", "round"}))
        if unknown:
            raise ValueError(f"search.{FINAL_KEY}: unknown key(s) {unknown[:5]}; not a state "
                             "this gpmotion wrote")
        self.genome, self.cost = self.family.from_json(d["genome"]), float(d["cost"])
        self.round = d.get("round")


class Search:
    """The interface the run loop, ``compare`` and users drive (module docstring).

    Subclasses set ``total_key`` (their setting that counts generations) and
    implement the hooks below the line.
    """
    total_key = "generations"
    schedule = None          # generations the style phases span (None: all of them)
    row_extra: dict = {}     # log columns a search adds after the common ones (their blanks)

    def __init__(self, family, task=None):
        self.family, self.task = family, task
        self.final = FinalBest(family, task)
        self.told_progress = 0.0
        self._asked = None
        self._row = None

    # -- the interface -----------------------------------------------------------
    def ask(self) -> list:
        """Genomes to evaluate at ``progress``; asking again before ``tell`` repeats them."""
        self._asked = self._ask()
        return self._asked

    def tell(self, evaluation) -> None:
        """The Evaluation (or bare costs) of the genomes of the last ``ask``, in order."""
        if self._asked is None:
            raise RuntimeError("tell() without a pending ask()")
        ev = evaluation if isinstance(evaluation, Evaluation) else Evaluation.of_costs(evaluation)
        if len(ev.costs) != len(self._asked):
            raise ValueError(f"tell: expected {len(self._asked)} costs, got {len(ev.costs)}")
        self.told_progress, round_ = self.progress, self.generation
        asked, self._asked = self._asked, None
        self._tell(ev)
        self.final.update(asked, ev, self.told_progress, round_)
        self._row = self._make_row(ev)

    @property
    def progress(self) -> float:
        """Run progress in [0, 1] of the round ``ask`` hands out; pass it to the evaluator."""
        return self.progress_of(self.generation)

    def phase_of(self, generation: int) -> tuple:
        """What a cost depends on at ``generation``: ``task.phase`` of its progress."""
        return () if self.task is None else tuple(self.task.phase(self.progress_of(generation)))

    @property
    def best(self):
        """The best under the final scoring once known, else the search's own best."""
        return self.final.genome if self.final.genome is not None else self._own_best()[0]

    @property
    def best_cost(self) -> float:
        """Cost of ``best``: under the final scoring once known, else the search's."""
        return self.final.cost if self.final.genome is not None else float(self._own_best()[1])

    @property
    def best_final(self):
        """Best cost so far under the final scoring; None while unknown (curriculum)."""
        return self.final.value

    @property
    def best_so_far(self) -> float:
        """The log's best_so_far: the best under the weights of the round last told
        (in the final phase these are the final ones, so best_final when lower)."""
        c = float(self._own_best()[1])
        if self.final.value is not None and self.phase_at(self.told_progress) == self.phase_at(1.0):
            c = min(c, self.final.value)
        return c

    # -- noisy costs (robust starts redrawn every round) --------------------------
    fresh_scores = False      # costs are comparable within one round only

    def _set_fresh_scores(self, on: bool) -> None:
        self.fresh_scores = self.final.per_round = bool(on)

    def judged_phase(self, generation: int) -> tuple:
        """What costs must share to be compared: the phase, and with fresh scores the round."""
        return self.phase_of(generation) + ((float(generation),) if self.fresh_scores else ())

    def phase_at(self, progress: float) -> tuple:
        return () if self.task is None else tuple(self.task.phase(progress))

    def row(self) -> dict:
        """The log.csv row of the round last told."""
        if self._row is None:
            raise RuntimeError("row() before the first tell()")
        return dict(self._row)

    def _make_row(self, ev: Evaluation) -> dict:
        generation, costs = self._row_costs(ev)
        return {"generation": generation, "progress": round(self.told_progress, 6),
                "best_so_far": self.best_so_far,
                "best_final": "" if self.final.value is None else self.final.value,
                "gen_min": float(costs.min()), "gen_median": float(np.median(costs)),
                "gen_mean": float(costs.mean()), "gen_max": float(costs.max()),
                "evaluated": len(ev.costs), "solved": int(ev.success.sum()),
                "failed": int(ev.failed.sum()), **self.row_extra, **self._row_columns()}

    def state_dict(self) -> dict:
        """JSON-safe snapshot: the algorithm's state and the final-scoring best."""
        return {**self._state(), FINAL_KEY: self.final.state_dict()}

    def load_state_dict(self, state: dict) -> None:
        if not isinstance(state, dict):
            raise ValueError("checkpoint search state must be an object")
        self.final.load_state_dict(state.get(FINAL_KEY))
        self._load({k: v for k, v in state.items() if k != FINAL_KEY})
        self._asked = None

    @classmethod
    def setting_names(cls) -> set[str]:
        """The settings a run's config may give (the constructor's keywords)."""
        return set(inspect.signature(cls).parameters) - {"family", "seed", "task", "rng"}

    @property
    def progress_span(self) -> int:
        """Generations that progress 0 → 1 spans (``progress ≈ generation / span``)."""
        return max(1, self.schedule or self.total)

    # -- what a subclass supplies --------------------------------------------------
    generation: int          # rounds told so far (the one ``ask`` hands out next)
    evaluations: int         # genomes evaluated so far (re-scores included)

    @property
    def done(self) -> bool:
        raise NotImplementedError

    @property
    def total(self) -> int:
        """The generations (rounds) this search runs."""
        raise NotImplementedError

    @property
    def last_generation(self) -> int:
        """The number log.csv gives the search's last generation."""
        raise NotImplementedError

    def progress_of(self, generation: int) -> float:
        raise NotImplementedError

    def _ask(self) -> list:
        raise NotImplementedError

    def _tell(self, ev: Evaluation) -> None:
        raise NotImplementedError

    def _own_best(self) -> tuple:
        """(genome, cost) of the search's own best under its current phase."""
        raise NotImplementedError

    def _row_costs(self, ev: Evaluation) -> tuple:
        """(generation the row names, the costs its statistics are over)."""
        raise NotImplementedError

    def _row_columns(self) -> dict:
        return {}

    def logged_generation(self) -> int:
        """The ``generation`` of the last log row, given the state (resume checks)."""
        raise NotImplementedError

    def config(self) -> dict:
        """The effective settings, as the checkpoint records them."""
        raise NotImplementedError

    def extend(self, total: int, schedule: int) -> None:
        """Run to ``total`` generations; progress keeps spanning ``schedule``."""
        raise NotImplementedError

    def check_restored(self) -> None:
        """After ``load_state_dict``: raise ValueError if the state contradicts the settings."""

    def _state(self) -> dict:
        raise NotImplementedError

    def _load(self, state: dict) -> None:
        raise NotImplementedError


class GenerationalSearch(Search):
    """A search of ``generations`` generations whose run progress steps evenly
    from 0 at generation 0 to 1 at the last generation of the schedule (GP, CMA-ES)."""
    generations: int

    @property
    def total(self) -> int:
        return self.generations

    @property
    def last_generation(self) -> int:
        return self.generations - 1          # its G generations are 0..G-1

    def progress_of(self, generation: int) -> float:
        n = self.schedule or self.generations
        return 1.0 if n == 1 else min(1.0, generation / (n - 1))

    @property
    def progress_span(self) -> int:
        return max(1, (self.schedule or self.generations) - 1)
