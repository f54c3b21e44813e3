"""Keyframes: splines of PD targets searched by CMA-ES (the animator's baseline).

A genome is K keyframe values per controlled actuator, ``float64[K, n]``
(radians, within the joint's limits).  The keys sit at fixed times, evenly
spaced over the episode, ``t_k = k · T / (K − 1)``; between keys the target is
interpolated **linearly** (a piecewise-linear spline) and held after the last
key.  Actuators the task does not control hold the neutral pose.  The
targets run inside the rollout kernel of the open-loop ``schedule``
controllers (:mod:`gpmotion.controllers.schedule`, keyframe mode): no new
kernel, no Python call per step.

The search is CMA-ES (Hansen's ``cma`` package) on the keys scaled to
[0, 1] per joint range (``bounds`` [0, 1]), starting from the neutral pose
with step size ``sigma0``; λ = ``population`` (default cma's 4 + ⌊3 ln N⌋).
Its samples come from its own ``numpy`` Generator (cma's ``randn`` option),
never the global ``numpy.random``, so a seed fixes the run.

Checkpoints are plain JSON and exact: CMA-ES's state is a deterministic
function of its seed, settings and the costs it was told, so the state is
those costs (one list per generation) plus the resulting mean and σ as a
check; loading replays the ask/tell sequence (milliseconds) and refuses a
state whose replay does not reproduce the recorded mean and σ (another
``cma`` version).  Nothing is pickled.

Phases: a generation's costs are all of one phase (CMA-ES keeps no old
costs), so only the search's own best follows the GP rule: replaced by a
generation's best when that is lower or the incumbent is of another phase.
"""
from __future__ import annotations

import math

import numpy as np

from .. import cli_options
from ..cli_options import Option, number
from ..controllers import schedule
from ..search.base import GenerationalSearch
from ..task import WORST
from .base import Family, register_family

STATE_FORMAT = "cmaes-keyframes-v1"
MAX_KEYS = 64

cli_options.register_option(Option(
    "--keys", "family", {}, "keyframes per joint, evenly spaced over the episode (default 6)",
    "the number of keyframes", dict(type=int), number(2, MAX_KEYS, True)))
cli_options.register_option(Option(
    "--sigma0", "search", {}, "CMA-ES initial step, as a fraction of each joint's range "
    "(default 0.25)", "the CMA-ES step size", dict(type=float), number(1e-6, 1.0)))


def _cma_options(seed: int, popsize: int | None) -> dict:
    """cma options for a silent, fixed-length run drawing from its own Generator."""
    rng = np.random.default_rng(seed)
    opts = {"bounds": [0.0, 1.0], "randn": lambda *shape: rng.standard_normal(shape),
            "seed": np.nan, "verbose": -9, "verb_log": 0, "verb_disp": 0,
            "maxiter": np.inf, "tolfun": 0, "tolx": 0, "tolfunhist": 0,
            "tolstagnation": np.inf, "tolflatfitness": np.inf}
    if popsize is not None:
        opts["popsize"] = popsize
    return opts


class CMAESSearch(GenerationalSearch):
    """CMA-ES over a keyframes family's normalized keys (module docstring)."""
    total_key = "generations"

    def __init__(self, family, seed: int | None = None, population: int | None = None,
                 generations: int = 100, sigma0: float = 0.25, fresh_scores: bool = False,
                 task=None):
        super().__init__(family, task)
        if not isinstance(fresh_scores, bool):
            raise ValueError(f"CMAESSearch: fresh_scores must be true or false, got {fresh_scores!r}")
        # robust starts: costs of two generations are not comparable, the best is the latest's
        self._set_fresh_scores(fresh_scores)
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
            raise ValueError(f"CMAESSearch: seed must be an integer, got {seed!r}")
        if population is not None and (isinstance(population, bool)
                                       or not isinstance(population, (int, np.integer))
                                       or population < 2):
            raise ValueError(f"CMAESSearch: population must be an integer >= 2, got {population!r}")
        if isinstance(generations, bool) or not isinstance(generations, (int, np.integer)) \
                or generations < 1:
            raise ValueError(f"CMAESSearch: generations must be an integer >= 1, got {generations!r}")
        if isinstance(sigma0, bool) or not isinstance(sigma0, (int, float)) or not 0 < sigma0 <= 1:
            raise ValueError(f"CMAESSearch: sigma0 must be a number in (0, 1], got {sigma0!r}")
        self.seed, self.generations, self.sigma0 = int(seed), int(generations), float(sigma0)
        self._start(population)

    def _start(self, population):
        import cma
        self.es = cma.CMAEvolutionStrategy(self.family.normalize(self.family.neutral_genome()),
                                           self.sigma0, _cma_options(self.seed, population))
        self.population = int(self.es.popsize)
        self.generation, self.evaluations = 0, 0
        self.told: list[list[float]] = []        # every generation's costs: the state (replay)
        self._x = None                           # the pending samples (normalized)
        self._best, self._best_cost, self._best_phase = None, math.inf, None

    # -- the algorithm -------------------------------------------------------------
    @property
    def done(self) -> bool:
        return self.generation >= self.generations

    def extend(self, total: int, schedule: int) -> None:
        self.schedule = schedule
        self.generations = max(self.generations, total)

    def _ask(self) -> list:
        if self.done:
            raise RuntimeError("CMA-ES search finished; read best")
        if self._x is None:
            self._x = self.es.ask()
        return [self.family.denormalize(x) for x in self._x]

    def _tell(self, ev) -> None:
        if self._x is None:
            raise RuntimeError("tell() without a pending ask()")
        x, self._x = self._x, None
        c = np.array(ev.costs, dtype=np.float64).ravel()
        c[~np.isfinite(c)] = WORST
        self.es.tell(x, c.tolist())
        self.told.append(c.tolist())
        self._told_costs = c
        i = int(np.argmin(c))                    # first of equal minima
        phase = self.judged_phase(self.generation)
        if self._best is None or phase != self._best_phase or c[i] < self._best_cost:
            self._best = self.family.denormalize(x[i])
            self._best_cost, self._best_phase = float(c[i]), phase
        self.generation += 1
        self.evaluations += len(c)

    # -- what the run loop reads ---------------------------------------------------
    def _own_best(self) -> tuple:
        return self._best, self._best_cost

    def _row_costs(self, ev) -> tuple:
        return self.generation - 1, self._told_costs

    def _row_columns(self) -> dict:
        return {"avg_tree_size": "", "sigma": float(self.es.sigma)}

    def logged_generation(self) -> int:
        return self.generation - 1

    def config(self) -> dict:
        return {"population": self.population, "generations": self.generations,
                "sigma0": self.sigma0, "seed": self.seed,
                **({"fresh_scores": True} if self.fresh_scores else {})}    # absent: as before

    def check_restored(self) -> None:
        if len(self.told) != self.generation or any(len(c) != self.population for c in self.told):
            raise ValueError(f"its costs are {len(self.told)} generations, the state says "
                             f"{self.generation} of {self.population}")

    # -- checkpoints: the told costs, replayed ---------------------------------------------
    def _state(self) -> dict:
        enc = self.family.to_json
        return {"format": STATE_FORMAT, "config": self.config(),
                "generation": self.generation, "evaluations": self.evaluations,
                "told": [list(c) for c in self.told],
                "check": {"mean": self.es.mean.tolist(), "sigma": float(self.es.sigma)},
                "best": None if self._best is None else {
                    "genome": enc(self._best), "cost": self._best_cost,
                    "phase": list(self._best_phase)}}

    def _load(self, state: dict) -> None:
        if not isinstance(state, dict) or state.get("format") != STATE_FORMAT:
            raise ValueError(f"not a {STATE_FORMAT} checkpoint")
        cfg = state["config"]
        self.seed, self.sigma0 = int(cfg["seed"]), float(cfg["sigma0"])
        self.generations = int(cfg["generations"])
        self._set_fresh_scores(cfg.get("fresh_scores", False))
        self._start(int(cfg["population"]))
        told = state["told"]
        if not isinstance(told, list) or len(told) > 10**7:
            raise ValueError("checkpoint 'told' must be a list of cost lists")
        for costs in told:
            c = np.array(costs, dtype=np.float64)
            if c.shape != (self.population,) or not np.all(np.isfinite(c)):
                raise ValueError(f"checkpoint costs must be {self.population} finite numbers "
                                 "per generation")
            self.es.tell(self.es.ask(), c.tolist())
            self.told.append(c.tolist())
        check = state["check"]
        if (self.es.mean.tolist() != [float(x) for x in check["mean"]]
                or float(self.es.sigma) != float(check["sigma"])):
            raise ValueError("the CMA-ES state does not replay to the recorded one "
                             "(another version of the cma package?)")
        self.generation, self.evaluations = int(state["generation"]), int(state["evaluations"])
        b = state["best"]
        if b is not None:
            self._best, self._best_cost = self.family.from_json(b["genome"]), float(b["cost"])
            self._best_phase = tuple(b["phase"])


@register_family
class KeyframesFamily(Family):
    """K keyframes per controlled joint, linearly interpolated PD targets; CMA-ES."""
    name = "keyframes"
    description = ("keyframed PD targets (linear between evenly spaced keys), searched by "
                   "CMA-ES")
    search_class = CMAESSearch
    cli = {"--generations": "generations", "--population": "population", "--keys": "keys",
           "--sigma0": "sigma0"}
    takes_population = True

    def __init__(self, task, keys: int = 6, **options):
        if isinstance(keys, bool) or not isinstance(keys, (int, np.integer)) \
                or not 2 <= keys <= MAX_KEYS:
            raise ValueError(f"keys must be an integer in 2..{MAX_KEYS}, got {keys!r}")
        super().__init__(task, keys=int(keys), **options)
        self.actuators = task.controlled_actuators()
        fig = task.figure
        neutral = np.asarray(fig.model.neutral, dtype=np.float64)
        lim = fig.actuator_limits()[self.actuators]
        mid = neutral[self.actuators]
        # a joint without limits gets a range of ±π about its neutral angle
        self.lo = np.where(np.isfinite(lim[:, 0]), lim[:, 0], mid - math.pi)
        self.hi = np.where(np.isfinite(lim[:, 1]), lim[:, 1], mid + math.pi)
        self.neutral = neutral
        self.times = np.linspace(0.0, task.seconds, self.options["keys"])

    @property
    def shape(self) -> tuple:
        return self.options["keys"], len(self.actuators)

    # -- genomes -------------------------------------------------------------------
    def neutral_genome(self) -> np.ndarray:
        return np.clip(np.tile(self.neutral[self.actuators], (self.shape[0], 1)), self.lo, self.hi)

    def random(self, rng) -> np.ndarray:
        return self.lo + rng.random(self.shape) * (self.hi - self.lo)

    def mutate(self, genome, rng, extra=None) -> np.ndarray:
        """One variation (for searches that climb from a given controller; CMA-ES
        samples its own): a normal step of σ = 0.1 of its range on one keyframe
        value in three, clipped to the range."""
        x = self.normalize(genome)
        pick = rng.random(x.size) < 1 / 3
        pick[rng.integers(x.size)] = True                   # at least one value moves
        return self.denormalize(np.where(pick, x + 0.1 * rng.standard_normal(x.size), x))

    def normalize(self, genome) -> np.ndarray:
        return ((np.asarray(genome) - self.lo) / (self.hi - self.lo)).ravel()

    def denormalize(self, x) -> np.ndarray:
        x = np.clip(np.asarray(x, dtype=np.float64).reshape(self.shape), 0.0, 1.0)
        return self.lo + x * (self.hi - self.lo)

    def encode(self, genomes):
        """The schedule kernel's keyframe mode: every actuator keyed (neutral
        where the task does not control it), τ the family's default."""
        batches = []
        for g in genomes:
            targets = np.tile(self.neutral, (self.shape[0], 1))
            targets[:, self.actuators] = np.asarray(g, dtype=np.float64).reshape(self.shape)
            batches.append(schedule.keyframes(self.times, targets,
                                              np.full(len(self.neutral), self.default_tau)))
        return schedule.stack(batches)

    def to_json(self, genome) -> dict:
        return {"kind": "keyframes", "times": self.times.tolist(),
                "values": np.asarray(genome, dtype=np.float64).reshape(self.shape).tolist()}

    def from_json(self, data) -> np.ndarray:
        if not isinstance(data, dict) or data.get("kind") != "keyframes":
            raise ValueError("not a keyframes controller (expected kind 'keyframes')")
        v = data.get("values")
        k, n = self.shape
        ok = (isinstance(v, list) and len(v) == k
              and all(isinstance(r, list) and len(r) == n for r in v)
              and all(isinstance(x, (int, float)) and not isinstance(x, bool) for r in v for x in r))
        if not ok:
            raise ValueError(f"keyframes 'values' must be {k} rows of {n} numbers "
                             f"(keys × the joints {self.task.name} drives)")
        g = np.array(v, dtype=np.float64)
        if not np.all(np.isfinite(g)) or np.any(g < self.lo - 1e-9) or np.any(g > self.hi + 1e-9):
            raise ValueError("keyframe values must be finite angles within the joints' limits")
        return g

    # -- search --------------------------------------------------------------------
    def noisy_settings(self) -> dict:
        return {"fresh_scores": True}          # robust starts: the best is the latest generation's

    def budget_settings(self, budget: int, population: int | None = None) -> dict:
        lam = population or 4 + int(3 * math.log(self.shape[0] * self.shape[1]))
        lam = max(2, min(lam, budget))
        return {"population": lam, "generations": max(1, budget // lam)}
