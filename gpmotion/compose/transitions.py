"""The transition search (Auslander et al. 1995, Fig. 5) as an ask/tell object.

    Q identical transition-point arrays (the user's guess, or equally spaced)
    evaluate them
    for G rounds:
        for each array, H times: mutate one randomly chosen transition point
            (randomize it 1/3 of the time, perturb it 2/3), evaluate,
            keep the new array if it scores better
        rank the arrays; replace the bottom half with the top half
    return the best array

Within a round the arrays never interact, so the H mutations of all Q arrays
are asked in H batches of Q (mutation j of every array at once): the same
algorithm as the paper's loop, evaluated Q at a time.  The Q identical start
arrays are evaluated once (one simulation, not Q).  Defaults Q = G = 16,
H = 4: 1 + 1,024 simulations.

Scores are maximized (a script's ``total``); a non-finite score is the worst.
Transition points stay in [0, seconds], sorted, and on the frame grid
(``tick``) when one is given, so every asked array is one the simulator can run.
``state_dict()`` is plain JSON (the generator's state included): a search
restored with ``load_state_dict`` continues exactly as the original would.
"""
from __future__ import annotations

import numpy as np

RANDOMIZE = 1.0 / 3.0          # Fig. 5: randomize 1/3 of the time, perturb 2/3


def checked_scores(pending, scores) -> np.ndarray:
    """Scores told for the ``pending`` asks (higher is better): one each, a
    non-finite score the worst."""
    if pending is None:
        raise RuntimeError("tell() without ask()")
    scores = np.asarray(scores, dtype=np.float64).reshape(-1)
    if scores.shape != (len(pending),):
        raise ValueError(f"expected {len(pending)} scores, got {scores.shape[0]}")
    return np.where(np.isfinite(scores), scores, -np.inf)


class TransitionSearch:
    def __init__(self, n_switches: int, seconds: float, guess=None, *, Q: int = 16, G: int = 16,
                 H: int = 4, seed: int = 0, perturb: float | None = None, tick: float | None = None):
        if n_switches < 1:
            raise ValueError("a transition search needs at least one switch (two phases)")
        for name, v in (("Q", Q), ("G", G), ("H", H)):
            if not (isinstance(v, (int, np.integer)) and 1 <= v <= 10_000):
                raise ValueError(f"{name} must be an integer in 1..10000, got {v!r}")
        if not (np.isfinite(seconds) and seconds > 0):
            raise ValueError(f"seconds must be > 0, got {seconds}")
        self.P1, self.seconds, self.Q, self.G, self.H = int(n_switches), float(seconds), int(Q), int(G), int(H)
        self.tick = None if tick is None else float(tick)
        # perturbation: a normal step of σ = 5 % of the motion by default (≈ 0.17 s of a 3.5 s motion)
        self.perturb = 0.05 * self.seconds if perturb is None else float(perturb)
        if not (np.isfinite(self.perturb) and self.perturb > 0):
            raise ValueError(f"perturb must be > 0 s, got {perturb}")
        if guess is None:
            guess = np.arange(1, self.P1 + 1) * self.seconds / (self.P1 + 1)    # equally spaced
        guess = np.asarray(guess, dtype=np.float64).reshape(-1)
        if guess.shape != (self.P1,) or not np.all(np.isfinite(guess)):
            raise ValueError(f"the guess must be {self.P1} finite switch time(s), got {guess.tolist()}")
        self.rng = np.random.default_rng(seed)
        self.pop = np.tile(self._legal(guess), (self.Q, 1))      # [Q, P − 1]
        self.scores = np.full(self.Q, -np.inf)
        self.round, self.step = 0, -1                             # step −1: the start arrays
        self.pending: np.ndarray | None = None
        self.best, self.best_score = self.pop[0].copy(), -np.inf
        self.evaluations = 0

    # ------------------------------------------------------------ ask / tell
    @property
    def done(self) -> bool:
        return self.round >= self.G

    def ask(self) -> np.ndarray:
        """Transition-point arrays [n, P − 1] to evaluate next (the same until told)."""
        if self.done:
            raise RuntimeError("the transition search is finished")
        if self.pending is None:
            self.pending = self.pop[:1].copy() if self.step < 0 else self._mutate(self.pop)
        return self.pending.copy()

    def tell(self, scores) -> None:
        """Scores (higher is better) of the arrays from the last ask()."""
        scores = checked_scores(self.pending, scores)
        self.evaluations += len(scores)
        i = int(np.argmax(scores))
        if scores[i] > self.best_score:
            self.best, self.best_score = self.pending[i].copy(), float(scores[i])
        if self.step < 0:                                          # Q identical start arrays
            self.scores[:] = scores[0]
        else:
            better = scores > self.scores                          # keep if better
            self.pop[better], self.scores[better] = self.pending[better], scores[better]
        self.pending = None
        self.step += 1
        if self.step == self.H:
            self._select()
            self.round, self.step = self.round + 1, 0

    def _select(self) -> None:
        """Rank; the bottom half becomes a copy of the top half (stable: ties keep their order)."""
        order = np.argsort(-self.scores, kind="stable")
        half = self.Q // 2
        keep = np.concatenate([order[:self.Q - half], order[:half]])
        self.pop, self.scores = self.pop[keep].copy(), self.scores[keep].copy()

    def _mutate(self, pop: np.ndarray) -> np.ndarray:
        """One randomly chosen transition point of every array: randomized or perturbed."""
        out = pop.copy()
        n = len(out)
        which = self.rng.integers(0, self.P1, size=n)
        randomize = self.rng.random(n) < RANDOMIZE
        fresh = self.rng.uniform(0.0, self.seconds, size=n)
        step = self.rng.normal(0.0, self.perturb, size=n)
        rows = np.arange(n)
        out[rows, which] = np.where(randomize, fresh, out[rows, which] + step)
        return np.stack([self._legal(r) for r in out])

    def _legal(self, s: np.ndarray) -> np.ndarray:
        s = np.sort(np.clip(s, 0.0, self.seconds))
        if self.tick:
            s = np.minimum(np.rint(s / self.tick) * self.tick, self.seconds)
        return s

    # ------------------------------------------------------------- records
    def row(self) -> dict:
        """One log row: where the search is and how good it is."""
        finite = self.scores[np.isfinite(self.scores)]
        return {"round": self.round, "step": self.step, "evaluations": self.evaluations,
                "best_score": _num(self.best_score), "best": self.best.tolist(),
                "median_score": _num(np.median(finite)) if finite.size else None}

    def state_dict(self) -> dict:
        return {"kind": "transition-search", "version": 1,
                "config": {"n_switches": self.P1, "seconds": self.seconds, "Q": self.Q, "G": self.G,
                           "H": self.H, "perturb": self.perturb, "tick": self.tick},
                "rng": self.rng.bit_generator.state, "pop": self.pop.tolist(),
                "scores": [_num(s) for s in self.scores], "round": self.round, "step": self.step,
                "pending": None if self.pending is None else self.pending.tolist(),
                "best": self.best.tolist(), "best_score": _num(self.best_score),
                "evaluations": self.evaluations}

    def load_state_dict(self, state: dict) -> None:
        """Restore a state_dict() (checked: a mismatched or malformed state is a ValueError)."""
        try:
            if state.get("kind") != "transition-search" or state.get("version") != 1:
                raise ValueError("not a transition-search state (version 1)")
            mine = self.state_dict()["config"]
            if state["config"] != mine:
                raise ValueError(f"state is for another search ({state['config']} vs {mine})")
            pop = np.asarray(state["pop"], dtype=np.float64)
            scores = np.asarray([-np.inf if s is None else s for s in state["scores"]], dtype=np.float64)
            if pop.shape != (self.Q, self.P1) or scores.shape != (self.Q,) or not np.all(np.isfinite(pop)):
                raise ValueError("population has the wrong shape")
            pending = None if state["pending"] is None else np.asarray(state["pending"], dtype=np.float64)
            if pending is not None and (pending.ndim != 2 or pending.shape[1] != self.P1):
                raise ValueError("pending arrays have the wrong shape")
            rng = np.random.default_rng()
            rng.bit_generator.state = state["rng"]
            round_, step, evals = int(state["round"]), int(state["step"]), int(state["evaluations"])
            best = np.asarray(state["best"], dtype=np.float64)
            best_score = -np.inf if state["best_score"] is None else float(state["best_score"])
        except (KeyError, TypeError, AttributeError) as e:
            raise ValueError(f"malformed transition-search state ({e})") from None
        if best.shape != (self.P1,) or not np.all(np.isfinite(best)):
            raise ValueError(f"best must be {self.P1} finite switch times")
        if min(round_, step, evals) < 0:
            raise ValueError("round, step and evaluations must be ≥ 0")
        self.pop, self.scores, self.pending, self.rng = pop, scores, pending, rng
        self.round, self.step, self.evaluations = round_, step, evals
        self.best, self.best_score = best, best_score


def _num(x):
    """A JSON-safe float: −inf (never scored / worst) as None."""
    x = float(x)
    return x if np.isfinite(x) else None
