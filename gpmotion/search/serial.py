"""The serial search of Auslander et al., Fig. 3, as an ask/tell object.

C hill climbers run side by side on a working set of controllers: each
generation every working controller is mutated once and the mutant replaces
it "if the new controller is better than the old one"; every R generations
the set is rank-ordered and its bottom 50 % replaced by copies of the top
50 %.  The object never simulates anything: ``ask()`` returns the genomes to
evaluate (the C initial controllers first, then one mutant per working
controller), ``tell(scores, extras)`` takes their scores and optional
per-candidate extras — for BSR the normalized sense trajectory of that
candidate's rollout, which the relevance heuristic needs when the candidate,
having become a working controller, is mutated later.

Decisions, all stated once here:
* replacement is strict ("better", Fig. 3) unless ``accept_ties=True``;
* non-finite scores count as the worst possible;
* reseeding, with h = C // 2 and a stable rank order (ties by position):
  the k-th best (k < h) is copied over the k-th of the bottom h, score and
  extras included; with odd C the middle controller stays;
* the best-so-far is updated on strict improvement only;
* phases: a score may depend on the round it was made in (style terms
  phased in over the run).  ``phase_fn(generation)`` names that phase (any
  JSON-able tuple; None: scores never go stale).  When the phase of the
  next round differs from the one the working set was scored in, ``ask()``
  first hands out the working set and the best-so-far for re-scoring (C + 1
  candidates, counted in ``evaluations`` like any other: a budget buys
  re-scores too); ``tell`` replaces their scores, and the best-so-far becomes
  the re-scored incumbent, or a working controller if strictly better.  So
  mutants are only ever compared with scores of their own phase, and at the
  end ``best_genome`` is the best under the last phase's scoring.  A
  re-score draws no random numbers.
``state_dict()`` is JSON-safe (rng state from ``rng.bit_generator.state``),
so a run resumes bit-for-bit from a checkpoint taken between any two calls.
"""
from __future__ import annotations

import copy
import math

import numpy as np

STATE_FORMAT = "serial-search-v2"
OLD_FORMATS = ("serial-search-v1",)       # kept no phase: re-scored on the next ask


def _default_to_json(genome):
    return genome.to_dict()


def _default_from_json(d):
    from gpmotion.bsr.genome import genome_from_dict
    return genome_from_dict(d)


def _copy(genome):
    return genome.copy() if hasattr(genome, "copy") else copy.deepcopy(genome)


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


class SerialSearch:
    """Fig. 3 hill climbers with reseeding.  ``init_fn(rng) -> genome``,
    ``mutate_fn(genome, rng, extra) -> genome`` (must not modify its input).
    """

    def __init__(self, init_fn, mutate_fn, n_working: int = 10,
                 n_generations: int = 4000, reseed_every: int = 200, rng=None,
                 maximize: bool = True, accept_ties: bool = False,
                 genome_to_json=_default_to_json,
                 genome_from_json=_default_from_json, phase_fn=None):
        if rng is None:
            raise ValueError("SerialSearch needs rng (a numpy Generator or a seed)")
        if n_working < 1 or n_generations < 0 or reseed_every < 1:
            raise ValueError("need n_working >= 1, n_generations >= 0, "
                             "reseed_every >= 1")
        self.rng = rng if isinstance(rng, np.random.Generator) \
            else np.random.default_rng(rng)
        self.init_fn, self.mutate_fn = init_fn, mutate_fn
        self.n_working, self.n_generations = int(n_working), int(n_generations)
        self.reseed_every = int(reseed_every)
        self.maximize, self.accept_ties = bool(maximize), bool(accept_ties)
        self.genome_to_json, self.genome_from_json = genome_to_json, genome_from_json
        self.phase_fn = phase_fn
        self.phase = None              # phase the working scores and best_score are of
        self.rescoring = False         # pending = working set + best, to re-score
        self.generation = 0            # completed mutation rounds
        self.evaluations = 0
        self.working = None            # list of genomes once initialized
        self.scores = None             # float64[C], as told
        self.extras = None
        self.pending = None            # candidates handed out by ask()
        self.best_genome, self.best_score = None, -math.inf if maximize else math.inf
        self.history: list[tuple[int, float]] = []

    # -- ordering -----------------------------------------------------------
    def _key(self, score):
        """Larger is better; NaN/inf-nonsense becomes the worst."""
        s = float(score)
        if math.isnan(s):
            return -math.inf
        s = s if self.maximize else -s
        return s if s != math.inf else -math.inf

    def _better(self, new, old, ties=False):
        a, b = self._key(new), self._key(old)
        return a > b or (ties and a == b)

    # -- ask / tell -----------------------------------------------------------
    @property
    def done(self) -> bool:
        return self.working is not None and self.generation >= self.n_generations

    def ask(self) -> list:
        """Candidates to evaluate; asking again before ``tell`` repeats them."""
        if self.done:
            raise RuntimeError("serial search finished; read best_genome")
        if self.pending is None:
            if self.working is None:
                self.pending = [self.init_fn(self.rng) for _ in range(self.n_working)]
            elif self._stale():
                self.pending = [_copy(g) for g in self.working] + [_copy(self.best_genome)]
                self.rescoring = True
            else:
                self.pending = [self.mutate_fn(g, self.rng, e)
                                for g, e in zip(self.working, self.extras)]
        return list(self.pending)

    def current_phase(self):
        """Phase of the round ``ask`` hands out next (None without ``phase_fn``)."""
        return None if self.phase_fn is None else tuple(self.phase_fn(self.generation))

    def _stale(self) -> bool:
        return self.phase_fn is not None and self.current_phase() != self.phase

    def tell(self, scores, extras=None) -> None:
        """Scores (and optional extras) for the candidates of the last ask."""
        if self.pending is None:
            raise RuntimeError("tell() without a pending ask()")
        scores = np.array(scores, dtype=np.float64).ravel()
        n = len(self.pending)
        extras = [None] * n if extras is None else list(extras)
        if scores.size != n or len(extras) != n:
            raise ValueError(f"tell: expected {n} scores and extras, got "
                             f"{scores.size} and {len(extras)}")
        if self.rescoring:
            self._tell_rescored(scores, extras)
            return
        if self.working is None:
            self.working, self.scores, self.extras = list(self.pending), scores, extras
            self.phase = self.current_phase()
        else:
            for i in range(n):
                if self._better(scores[i], self.scores[i], self.accept_ties):
                    self.working[i], self.scores[i] = self.pending[i], scores[i]
                    self.extras[i] = extras[i]
            self.generation += 1
        self.pending = None
        self.evaluations += n
        i = max(range(n), key=lambda k: (self._key(self.scores[k]), -k))
        if self.best_genome is None or self._better(self.scores[i], self.best_score):
            self.best_genome, self.best_score = _copy(self.working[i]), float(self.scores[i])
        if self.generation > 0 and self.generation % self.reseed_every == 0:
            self._reseed()
        self.history.append((self.evaluations, self.best_score))

    def _tell_rescored(self, scores, extras) -> None:
        """Scores of the working set and the incumbent under the new phase."""
        c = self.n_working
        self.scores, self.extras = scores[:c].copy(), extras[:c]
        self.best_score = float(scores[c])
        i = max(range(c), key=lambda k: (self._key(self.scores[k]), -k))
        if self._better(self.scores[i], self.best_score):
            self.best_genome, self.best_score = _copy(self.working[i]), float(self.scores[i])
        self.phase, self.rescoring, self.pending = self.current_phase(), False, None
        self.evaluations += c + 1
        self.history.append((self.evaluations, self.best_score))

    def _reseed(self):
        """Replace the bottom 50 % of the working set by copies of the top 50 %."""
        keys = np.array([self._key(s) for s in self.scores])
        order = np.argsort(-keys, kind="stable")
        half = self.n_working // 2
        for k in range(half):
            dst, src = order[self.n_working - half + k], order[k]
            self.working[dst] = _copy(self.working[src])
            self.scores[dst] = self.scores[src]
            self.extras[dst] = self.extras[src]

    # -- checkpoints ---------------------------------------------------------
    def state_dict(self) -> dict:
        """JSON-safe snapshot: config, working set, pending, rng, history."""
        enc = self.genome_to_json
        return {
            "format": STATE_FORMAT,
            "config": {"n_working": self.n_working, "n_generations": self.n_generations,
                       "reseed_every": self.reseed_every, "maximize": self.maximize,
                       "accept_ties": self.accept_ties},
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
        }

    def load_state_dict(self, state: dict) -> None:
        """Restore a :meth:`state_dict` snapshot (config included)."""
        if not isinstance(state, dict) or state.get("format") not in (STATE_FORMAT, *OLD_FORMATS):
            raise ValueError(f"not a {STATE_FORMAT} checkpoint")
        name = state["rng"].get("bit_generator")
        if name != self.rng.bit_generator.state["bit_generator"]:
            raise ValueError(f"checkpoint rng is {name}, search uses "
                             f"{self.rng.bit_generator.state['bit_generator']}")
        worst = -math.inf if state["config"]["maximize"] else math.inf
        num = lambda x: worst if x is None else float(x)  # noqa: E731
        dec = self.genome_from_json
        cfg = state["config"]
        self.n_working, self.n_generations = int(cfg["n_working"]), int(cfg["n_generations"])
        self.reseed_every = int(cfg["reseed_every"])
        self.maximize, self.accept_ties = bool(cfg["maximize"]), bool(cfg["accept_ties"])
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
