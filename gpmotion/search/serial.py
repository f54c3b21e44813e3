"""The serial search of Auslander et al., Fig. 3, as an ask/tell object.

C hill climbers run side by side on a working set of controllers: each
generation every working controller is mutated once and the mutant replaces
it "if the new controller is better than the old one"; every R generations
the set is rank-ordered and its bottom 50 % replaced by copies of the top
50 %.  The object never simulates anything (the interface is
:class:`gpmotion.search.base.Search`'s): ``ask()`` returns the genomes to
evaluate (the C initial controllers first, then one mutant per working
controller), ``tell(evaluation)`` takes their costs (lower is better) and
the evaluation's per-candidate ``extras`` — for BSR the normalized sense
trajectory of that candidate's rollout, which the relevance heuristic needs
when the candidate, having become a working controller, is mutated later.
The family supplies ``random(rng)``, ``mutate(genome, rng, extra)`` (must
not modify its input), ``copy``, ``to_json`` and ``from_json``.

Decisions, all stated once here:
* replacement is strict ("better", Fig. 3) unless ``accept_ties=True``;
* non-finite costs count as the worst possible;
* reseeding, with h = C // 2 and a stable rank order (ties by position):
  the k-th best (k < h) is copied over the k-th of the bottom h, score and
  extras included; with odd C the middle controller stays;
* the best-so-far is updated on strict improvement only;
* progress: run progress moves in ``phase_steps`` equal stages
  (:func:`serial_progress`), 0 in the first and 1 in the last;
* phases: a cost may depend on the round it was made in (style terms
  phased in over the run): ``phase_of(generation)`` names that phase (the
  task's; without a task, costs never go stale).  When the phase of the
  next round differs from the one the working set was scored in, ``ask()``
  first hands out the working set and the best-so-far for re-scoring (C + 1
  candidates, counted in ``evaluations`` like any other: a budget buys
  re-scores too); ``tell`` replaces their scores, and the best-so-far becomes
  the re-scored incumbent, or a working controller if strictly better.  So
  mutants are only ever compared with scores of their own phase, and at the
  end ``best_genome`` is the best under the last phase's scoring.  A
  re-score draws no random numbers.  (A re-score is its own row of the log:
  a generation number repeated, C + 1 evaluations.)
* noisy costs: with ``fresh_scores=True`` every round is a phase of its own,
  so the working set and the incumbent are re-scored before each round's
  mutants.  Robust runs set it (``Family.noisy_settings``): their starts are
  drawn anew each round from (seed, round), and the re-score asks at the
  same round as the mutants that follow, so a mutant and its parent are
  judged from the same starts — not a mutant's fresh starts against its
  parent's luckiest earlier ones.  A round then costs 2C + 1 evaluations,
  and the best under the final weights is the latest round's best (the
  incumbent re-scored, or a controller that beat it on the same starts).
* restarts (``restart_after`` = N > 0; 0, the default, never restarts):
  when the working set's best cost has not improved by more than
  ``restart_delta`` for N rounds (counted from the round it last did, or
  from the last restart or re-score), the next round hands out C fresh
  random controllers instead of mutants and they replace the whole working
  set (scores and extras too).  A restart round costs C evaluations and
  counts as a round like any other, so a budget of rounds buys the same
  evaluations with or without restarts; the best-so-far is kept across
  restarts (a restart only ever loses the working set).  Fresh controllers
  come from the family's ``random``, as the first ones do (an enriched
  start is not repeated).
``state_dict()`` is JSON-safe (rng state from ``rng.bit_generator.state``),
so a run resumes bit-for-bit from a checkpoint taken between any two calls.
"""
from __future__ import annotations

import math

import numpy as np

from .base import Search

STATE_FORMAT = "serial-search-v2"
OLD_FORMATS = ("serial-search-v1",)       # kept no phase: re-scored on the next ask
PHASE_STEPS = 20


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
                       phase_steps: int = PHASE_STEPS) -> int:
    """Most rounds whose evaluations (C initial + C per round + C + 1 per
    re-score) fit in ``budget``; at least 1."""
    g = max(1, (budget - n_working) // n_working)
    while g > 1 and n_working * (1 + g) + (n_working + 1) * serial_rescores(
            task, g, phase_steps) > budget:
        g -= 1
    return g


def _extra_to_json(extra):
    if extra is None:
        return None
    a = np.asarray(extra, dtype=np.float64)
    return {"shape": list(a.shape), "data": a.ravel().tolist()}


def _extra_from_json(d):
    if d is None:
        return None
    return np.asarray(d["data"], dtype=np.float64).reshape(d["shape"])


def _score_to_json(x):
    return float(x) if math.isfinite(x) else None


class SerialSearch(Search):
    """Fig. 3 hill climbers with reseeding, minimizing costs (module docstring)."""
    total_key = "n_generations"
    row_extra = {"avg_tree_size": ""}     # the log's columns are GP's too

    def __init__(self, family, seed: int | None = None, n_working: int = 10,
                 n_generations: int = 4000, reseed_every: int = 200,
                 accept_ties: bool = False, phase_steps: int = PHASE_STEPS,
                 fresh_scores: bool = False, restart_after: int = 0,
                 restart_delta: float = 0.0, task=None, rng=None):
        super().__init__(family, task)
        if rng is None and seed is None:
            raise ValueError("SerialSearch needs a seed (randomness is explicit)")
        if n_working < 1 or n_generations < 0 or reseed_every < 1:
            raise ValueError("need n_working >= 1, n_generations >= 0, "
                             "reseed_every >= 1")
        if isinstance(phase_steps, bool) or not isinstance(phase_steps, (int, np.integer)) \
                or phase_steps < 1:
            raise ValueError(f"phase_steps must be an integer >= 1, got {phase_steps!r}")
        self.rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(seed)
        self.n_working, self.n_generations = int(n_working), int(n_generations)
        self.reseed_every = int(reseed_every)
        self.accept_ties = bool(accept_ties)
        self.phase_steps = int(phase_steps)
        if not isinstance(fresh_scores, (bool, np.bool_)):
            raise ValueError(f"fresh_scores must be true or false, got {fresh_scores!r}")
        self._set_fresh_scores(fresh_scores)         # no best picked by the luck of its starts
        if isinstance(restart_after, bool) or not isinstance(restart_after, (int, np.integer)) \
                or restart_after < 0:
            raise ValueError(f"restart_after must be an integer >= 0 (0: never), got {restart_after!r}")
        if isinstance(restart_delta, bool) or not isinstance(restart_delta, (int, float, np.floating)) \
                or not math.isfinite(restart_delta) or restart_delta < 0:
            raise ValueError(f"restart_delta must be a finite number >= 0, got {restart_delta!r}")
        if restart_delta and not restart_after:
            raise ValueError("restart_delta needs restart_after > 0 (without it nothing restarts)")
        self.restart_after, self.restart_delta = int(restart_after), float(restart_delta)
        self.restarting = False        # pending = fresh random controllers (a restart)
        self.restarts = 0              # restarts so far
        self.mark = None               # (round, working-set best) of the last improvement
        self.phase = None              # phase the working scores and best_score are of
        self.rescoring = False         # pending = working set + best, to re-score
        self.generation = 0            # completed mutation rounds
        self.evaluations = 0
        self.working = None            # list of genomes once initialized
        self.scores = None             # float64[C], as told
        self.extras = None
        self.pending = None            # candidates handed out by ask()
        self.best_genome, self.best_score = None, math.inf
        self.history: list[tuple[int, float]] = []

    # -- progress ------------------------------------------------------------
    def progress_of(self, generation: int) -> float:
        n = self.schedule or self.n_generations     # an extension keeps the schedule
        return serial_progress(generation, n, self.phase_steps)

    @property
    def total(self) -> int:
        return self.n_generations

    @property
    def last_generation(self) -> int:
        return self.n_generations            # its rounds follow the initial set (generation 0)

    def extend(self, total: int, schedule: int) -> None:
        """Run to ``total`` rounds; progress keeps spanning ``schedule`` rounds."""
        self.schedule = schedule
        self.n_generations = max(self.n_generations, total)

    # -- ordering -----------------------------------------------------------
    def _key(self, cost):
        """Larger is better (a negated cost); NaN and ±inf become the worst."""
        s = -float(cost)
        if math.isnan(s):
            return -math.inf
        return s if s != math.inf else -math.inf

    def _better(self, new, old, ties=False):
        a, b = self._key(new), self._key(old)
        return a > b or (ties and a == b)

    # -- ask / tell -----------------------------------------------------------
    @property
    def done(self) -> bool:
        return self.working is not None and self.generation >= self.n_generations

    def _ask(self) -> list:
        """Candidates to evaluate; asking again before ``tell`` repeats them."""
        if self.done:
            raise RuntimeError("serial search finished; read best")
        if self.pending is None:
            copy = self.family.copy
            if self.working is None:
                self.pending = [self.family.random(self.rng) for _ in range(self.n_working)]
            elif self._stale():
                self.pending = [copy(g) for g in self.working] + [copy(self.best_genome)]
                self.rescoring = True
            elif self._restart_due():
                self.pending = [self.family.random(self.rng) for _ in range(self.n_working)]
                self.restarting = True
            else:
                self.pending = [self.family.mutate(g, self.rng, e)
                                for g, e in zip(self.working, self.extras)]
        return list(self.pending)

    def current_phase(self) -> tuple:
        """Phase of the round ``ask`` hands out next (with fresh scores, the round too)."""
        return self.judged_phase(self.generation)

    def _stale(self) -> bool:
        return self.current_phase() != self.phase

    # -- restarts ---------------------------------------------------------------
    def _working_best(self) -> float:
        return max(self._key(c) for c in self.scores)       # larger is better

    def _set_mark(self) -> None:
        self.mark = (self.generation, self._working_best())

    def _update_mark(self) -> None:
        """Move the mark when the working set's best improved by more than
        restart_delta since it was set (only with restarts on)."""
        if not self.restart_after:
            return
        if self.mark is None or self._working_best() > self.mark[1] + self.restart_delta:
            self._set_mark()

    def _restart_due(self) -> bool:
        return bool(self.restart_after) and self.mark is not None \
            and self.generation - self.mark[0] >= self.restart_after

    def _told(self, ev) -> tuple[np.ndarray, list]:
        """The costs and extras of the last ask's candidates, checked."""
        if self.pending is None:
            raise RuntimeError("tell() without a pending ask()")
        scores = np.array(ev.costs, dtype=np.float64).ravel()
        n = len(self.pending)
        extras = [None] * n if ev.extras is None else list(ev.extras)
        if scores.size != n or len(extras) != n:
            raise ValueError(f"tell: expected {n} costs and extras, got {scores.size} and {len(extras)}")
        return scores, extras

    def _keep_best(self, genomes, scores) -> None:
        """The best of these (the first on ties) becomes the best so far if it beats it."""
        i = max(range(len(genomes)), key=lambda k: (self._key(scores[k]), -k))
        if self.best_genome is None or self._better(scores[i], self.best_score):
            self.best_genome, self.best_score = self.family.copy(genomes[i]), float(scores[i])

    def _tell(self, ev) -> None:
        """Costs (and extras) for the candidates of the last ask."""
        scores, extras = self._told(ev)
        n = len(extras)
        if self.rescoring:
            self._tell_rescored(scores, extras)
            return
        if self.working is None:
            self.working, self.scores, self.extras = list(self.pending), scores, extras
            self.phase = self.current_phase()
        elif self.restarting:
            self.working, self.scores, self.extras = list(self.pending), scores, extras
            self.generation += 1
            self.restarting, self.mark = False, None
            self.restarts += 1
        else:
            for i in range(n):
                if self._better(scores[i], self.scores[i], self.accept_ties):
                    self.working[i], self.scores[i] = self.pending[i], scores[i]
                    self.extras[i] = extras[i]
            self.generation += 1
        self.pending = None
        self.evaluations += n
        self._keep_best(self.working, self.scores)
        if self.generation > 0 and self.generation % self.reseed_every == 0:
            self._reseed()
        self._update_mark()
        self.history.append((self.evaluations, self.best_score))

    def _tell_rescored(self, scores, extras) -> None:
        """Scores of the working set and the incumbent under the new phase."""
        c = self.n_working
        self.scores, self.extras = scores[:c].copy(), extras[:c]
        self.best_score = float(scores[c])
        self._keep_best(self.working, self.scores)
        self.phase, self.rescoring, self.pending = self.current_phase(), False, None
        if self.restart_after:
            self._set_mark()                 # scores of a new phase: count from here
        self.evaluations += c + 1
        self.history.append((self.evaluations, self.best_score))

    def _reseed(self):
        """Replace the bottom 50 % of the working set by copies of the top 50 %."""
        keys = np.array([self._key(s) for s in self.scores])
        order = np.argsort(-keys, kind="stable")
        half = self.n_working // 2
        for k in range(half):
            dst, src = order[self.n_working - half + k], order[k]
            self.working[dst] = self.family.copy(self.working[src])
            self.scores[dst] = self.scores[src]
            self.extras[dst] = self.extras[src]

    # -- what the run loop reads ----------------------------------------------
    def _own_best(self) -> tuple:
        return self.best_genome, self.best_score

    def _row_costs(self, ev) -> tuple:
        return self.generation, np.asarray(ev.costs, dtype=np.float64)

    def logged_generation(self) -> int:
        return self.generation

    def check_restored(self) -> None:
        n = None if self.working is None else len(self.working)
        sizes = [("working set", n, self.n_working if n is not None else None),
                 ("scores", None if self.scores is None else len(self.scores), n)]
        for what, have, want in sizes:
            if have != want:
                raise ValueError(f"its {what} has {have} entries, the settings say {want}")

    def config(self) -> dict:
        """The settings a checkpoint records (phase_steps is config.json's alone;
        ``maximize`` is always false: kept for the checkpoint format)."""
        return {"n_working": self.n_working, "n_generations": self.n_generations,
                "reseed_every": self.reseed_every, "maximize": False,
                "accept_ties": self.accept_ties,
                **({"fresh_scores": True} if self.fresh_scores else {}),   # absent: as before
                **({"restart_after": self.restart_after, "restart_delta": self.restart_delta}
                   if self.restart_after else {})}

    # -- checkpoints ---------------------------------------------------------
    def _state(self) -> dict:
        """JSON-safe snapshot: config, working set, pending, rng, history."""
        enc = self.family.to_json
        return {
            "format": STATE_FORMAT,
            "config": self.config(),
            "generation": self.generation, "evaluations": self.evaluations,
            "rng": self.rng.bit_generator.state,
            "working": None if self.working is None else [enc(g) for g in self.working],
            "scores": None if self.scores is None else [_score_to_json(s) for s in self.scores],
            "extras": None if self.extras is None else [_extra_to_json(e) for e in self.extras],
            "pending": None if self.pending is None else [enc(g) for g in self.pending],
            "rescoring": self.rescoring,
            "phase": None if self.phase is None else list(self.phase),
            "best_genome": None if self.best_genome is None else enc(self.best_genome),
            "best_score": _score_to_json(self.best_score),
            "history": [[int(e), _score_to_json(b)] for e, b in self.history],
            **({"restart": {"restarting": self.restarting, "restarts": self.restarts,
                            "mark": None if self.mark is None
                            else [self.mark[0], _score_to_json(-self.mark[1])]}}
               if self.restart_after else {}),           # absent without restarts: as before
        }

    def _load(self, state: dict) -> None:
        """Restore a :meth:`state_dict` snapshot (config included)."""
        if not isinstance(state, dict) or state.get("format") not in (STATE_FORMAT, *OLD_FORMATS):
            raise ValueError(f"not a {STATE_FORMAT} checkpoint")
        name = state["rng"].get("bit_generator")
        if name != self.rng.bit_generator.state["bit_generator"]:
            raise ValueError(f"checkpoint rng is {name}, search uses "
                             f"{self.rng.bit_generator.state['bit_generator']}")
        cfg = state["config"]
        if cfg.get("maximize"):
            raise ValueError("checkpoint of a maximizing serial search; this one minimizes costs")
        num = lambda x: math.inf if x is None else float(x)  # noqa: E731
        dec = self.family.from_json
        self.n_working, self.n_generations = int(cfg["n_working"]), int(cfg["n_generations"])
        self.reseed_every = int(cfg["reseed_every"])
        self.accept_ties = bool(cfg["accept_ties"])
        self._set_fresh_scores(cfg.get("fresh_scores", False))   # absent before robust re-scores
        self.restart_after = int(cfg.get("restart_after", 0))
        self.restart_delta = float(cfg.get("restart_delta", 0.0))
        rs = state.get("restart") or {}
        self.restarting, self.restarts = bool(rs.get("restarting", False)), int(rs.get("restarts", 0))
        mark = rs.get("mark")
        self.mark = None if mark is None else (int(mark[0]), self._key(num(mark[1])))
        self.generation, self.evaluations = int(state["generation"]), int(state["evaluations"])
        self.rng.bit_generator.state = state["rng"]
        opt = lambda xs, f: None if xs is None else [f(x) for x in xs]  # noqa: E731
        self.working = opt(state["working"], dec)
        self.scores = None if state["scores"] is None else \
            np.array([num(s) for s in state["scores"]], dtype=np.float64)
        self.extras = opt(state["extras"], _extra_from_json)
        self.pending = opt(state["pending"], dec)
        self.rescoring = bool(state.get("rescoring", False))
        phase = state.get("phase")
        self.phase = None if phase is None else tuple(phase)
        self.best_genome = None if state["best_genome"] is None else dec(state["best_genome"])
        self.best_score = num(state["best_score"])
        self.history = [(int(e), num(b)) for e, b in state["history"]]
