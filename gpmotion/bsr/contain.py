"""The 3-D relevance heuristic, "contain" (Auslander et al. §4.2), and the
enrichment of the first controllers.

2-D: a new rule's stimulus box shares a *corner* with the unmutated
controller's sense trajectory (``mutation.relevant_stimulus``).  "With 3D
figures, it was necessary to change this relevance heuristic to require
that the hyperrectangle *contain* some point on the trajectory": here a
random frame's point p, box sides 2/λ_k log-uniform in [0.4, 4] (Table 2)
and centre μ_k = p_k + u_k / λ_k with u_k uniform in (−1, 1), so
|λ_k (p_k − μ_k)| < 1 for every sense: the rule scores W (1 − max²) > 0 at
p and is a candidate there.

"Applying three rounds of this mutation operation to the first set of 100
motion controllers was also found to be a useful strategy for enriching the
initial population": :class:`EnrichedSerialSearch` draws ``n_initial``
(100) random controllers, gives each ``rounds`` (3) new rules by contain,
re-evaluating between rounds so each new rule contains a point of its
controller's current trajectory (kept unconditionally: enrichment, not
selection), and starts the serial search (Fig. 3) from the best
``n_working`` of the enriched controllers.
"""
from __future__ import annotations

import numpy as np

from gpmotion.bsr.genome import LAMBDA_MAX, LAMBDA_MIN, SenseGenome, log_uniform, random_theta0
from gpmotion.bsr.mutation import P_REINIT, creep_rule, usable_frame
from gpmotion.search.serial import SerialSearch, _extra_from_json, _extra_to_json, _score_to_json

ENRICH_INITIAL = 100
ENRICH_ROUNDS = 3


def containing_stimulus(rng: np.random.Generator, trajectory):
    """(μ, λ, point, frame): a Table-2-sized box containing a random usable
    frame of ``trajectory`` [F, V] (normalized senses); None if none is usable."""
    picked = usable_frame(trajectory, rng)
    if picked is None:
        return None
    frame, point = picked
    lam = np.clip(2.0 / log_uniform(rng, 0.4, 4.0, point.size), LAMBDA_MIN, LAMBDA_MAX)
    mu = point + rng.uniform(-1.0, 1.0, point.size) / lam
    return mu, lam, point, frame


def contain_rule(genome: SenseGenome, rng, trajectory, rule: int | None = None) -> SenseGenome:
    """Copy of ``genome`` with one rule redrawn, its box containing a trajectory point
    (Table 2's box when there is no usable trajectory)."""
    from gpmotion.bsr.genome import random_stimulus
    g = genome.copy()
    r = int(rng.integers(g.n_rules)) if rule is None else rule
    g.theta0[r] = random_theta0(rng, g.limits, 1)[0]
    g.tau[r] = log_uniform(rng, g.tau_range[0], g.tau_range[1])
    box = None if trajectory is None else containing_stimulus(rng, trajectory)
    if box is None:
        mu, lam = random_stimulus(rng, 1, g.n_senses)
        box = (mu[0], lam[0])
    elif box[0].size != g.n_senses:
        raise ValueError(f"trajectory has {box[0].size} senses per frame, genome reads {g.n_senses}")
    g.mu[r], g.lam[r] = box[0], box[1]
    return g


def mutate(genome, rng, trajectory=None, p_reinit: float = P_REINIT, scale: float = 1.0):
    """One 3-D mutation: a new rule by contain with probability p_reinit, else creep."""
    if rng.random() < p_reinit:
        return contain_rule(genome, rng, trajectory)
    return creep_rule(genome, rng, scale=scale)


class EnrichedSerialSearch(SerialSearch):
    """Fig. 3's serial search started from enriched controllers (module doc).

    Before the search proper, ``ask`` hands out the ``n_initial`` random
    controllers, then ``rounds`` times their contain-mutants; the costs of
    the last round pick the working set.  All of these count as evaluations.
    """

    def __init__(self, family, seed=None, n_initial: int = ENRICH_INITIAL,
                 rounds: int = ENRICH_ROUNDS, **kw):
        super().__init__(family, seed, **kw)
        if n_initial < self.n_working or rounds < 0:
            raise ValueError(f"enrichment needs n_initial >= n_working ({self.n_working}) and rounds >= 0")
        self.n_initial, self.rounds = int(n_initial), int(rounds)
        self.pool = None               # [genomes, costs, extras] while enriching
        self.round = 0

    def _ask(self) -> list:
        if self.working is not None:
            return super()._ask()
        if self.pending is None:
            if self.pool is None:
                self.pending = [self.family.random(self.rng) for _ in range(self.n_initial)]
            else:
                self.pending = [contain_rule(g, self.rng, e) for g, e in zip(self.pool[0], self.pool[2])]
        return list(self.pending)

    def _tell(self, ev) -> None:
        if self.working is not None:
            return super()._tell(ev)
        if self.pending is None:
            raise RuntimeError("tell() without a pending ask()")
        costs = np.array(ev.costs, dtype=np.float64).ravel()
        n = len(self.pending)
        extras = [None] * n if ev.extras is None else list(ev.extras)
        if costs.size != n or len(extras) != n:
            raise ValueError(f"tell: expected {n} costs and extras, got {costs.size} and {len(extras)}")
        self.evaluations += n
        if self.pool is not None:
            self.round += 1
        self.pool, self.pending = [list(self.pending), costs, extras], None
        i = max(range(n), key=lambda k: (self._key(costs[k]), -k))
        if self.best_genome is None or self._better(costs[i], self.best_score):
            self.best_genome, self.best_score = self.family.copy(self.pool[0][i]), float(costs[i])
        if self.round >= self.rounds:
            keys = np.array([self._key(c) for c in costs])
            top = np.argsort(-keys, kind="stable")[:self.n_working]
            self.working = [self.pool[0][k] for k in top]
            self.scores = costs[top].copy()
            self.extras = [extras[k] for k in top]
            self.phase = self.current_phase()
            self.pool = None
        self.history.append((self.evaluations, self.best_score))

    def _state(self) -> dict:
        state = super()._state()
        enc = self.family.to_json
        state["enrich"] = {"n_initial": self.n_initial, "rounds": self.rounds, "round": self.round,
                           "pool": None if self.pool is None else
                           [[enc(g) for g in self.pool[0]], [_score_to_json(c) for c in self.pool[1]],
                            [_extra_to_json(e) for e in self.pool[2]]]}
        return state

    def _load(self, state: dict) -> None:
        super()._load(state)
        e = state.get("enrich")
        if not isinstance(e, dict):
            raise ValueError("not an enriched serial-search checkpoint (no 'enrich' entry)")
        self.n_initial, self.rounds, self.round = int(e["n_initial"]), int(e["rounds"]), int(e["round"])
        pool = e["pool"]
        self.pool = None if pool is None else [
            [self.family.from_json(g) for g in pool[0]],
            np.array([np.inf if c is None else float(c) for c in pool[1]]),
            [_extra_from_json(x) for x in pool[2]]]
