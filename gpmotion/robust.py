"""Robust ("enhanced") controllers: evaluation from perturbed starts (Auslander et al. §3).

The evaluation layer: the in-process and remote evaluators run a robust batch
through here, so it imports nothing of compose, run or the CLI.

"By randomly perturbing the initial physical configuration of the
articulated figure during each iteration of the original motion-synthesis
process, the resulting sense-based motion controller can be made more robust."

* :func:`perturbed_starts` draws K initial states around the nominal one —
  joint angles, position, orientation, and linear and angular momentum (as
  velocities) — from a generator seeded by (run seed, round) only, so every
  evaluator backend and a resumed run draw the same starts, and a new round
  draws new ones.  A start whose contact points would sink below the nominal
  start's lowest point is lifted by the difference (no start inside the floor).
* :func:`robust_rollout` runs N controllers × K starts as one batched rollout
  (episode ``n·K + k`` is controller n from start k), so K starts cost K
  episodes of batch, not K separate rollouts.
* :func:`aggregate` folds the K costs of each controller into one: the mean,
  or the worst.
* :func:`normalize` / :func:`batch_evaluation`: the ``robust`` setting of a
  run (``gpmotion run --robust-starts K``): every generation's batch is scored
  from K starts drawn from (run seed, generation), on every evaluator backend.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from .controllers import ControllerBatch
from .sim.backend import backend_of
from .sim.rollout import rollout
from .task import WORST

AGGREGATES = ("mean", "worst")       # and "qNN": the NN-th percentile start (q80, q90, ...)


def is_aggregate(how) -> bool:
    return how in AGGREGATES or (isinstance(how, str) and len(how) == 3 and how[0] == "q"
                                 and how[1:].isdigit() and 1 <= int(how[1:]) <= 99)


def _order_index(n_starts: int, how: str) -> int:
    """The start an aggregate "qNN" picks among n sorted costs: the NN-th percentile (inverted CDF,
    so q80 of 8 costs is the 7th lowest — the cost that 80 % of starts do at least as well as)."""
    q = int(how[1:]) / 100.0
    return min(n_starts - 1, max(0, int(np.ceil(q * n_starts - 1e-9)) - 1))


@dataclass(frozen=True)
class Perturbation:
    """Standard deviations of the normal perturbations (defaults suit Star-Man-sized figures)."""
    joint: float = 0.15            # rad, every non-root joint angle (then clipped to its limits)
    position: float = 0.02         # m, root position (each axis; height only lifts, see module doc)
    orientation: float = 0.1       # rad, root pitch (3-D: a rotation about a random axis)
    velocity: float = 0.1          # m/s, root linear velocity (each axis) — linear momentum
    angular: float = 0.3           # rad/s, root and joint angular rates — angular momentum

    def __post_init__(self):
        for k, v in asdict(self).items():
            if not (np.isfinite(v) and v >= 0):
                raise ValueError(f"perturbation {k} must be a finite number >= 0, got {v!r}")


# Per-figure defaults (σ of each part): about the same *relative* push for each
# figure — the lamp (1.65 kg, 0.4 m) gets a few degrees and millimetres,
# Star-Man / Beryl (5–8 kg, ~1 m) the class defaults, a standing human less
# (balance on two feet).  A figure not listed gets ``Perturbation()``.
FIGURE_SIZES = {
    "lamp": Perturbation(joint=0.05, position=0.005, orientation=0.03, velocity=0.03, angular=0.1),
    "starman": Perturbation(),
    "beryl": Perturbation(),
    "herman": Perturbation(joint=0.05, position=0.01, orientation=0.03, velocity=0.05, angular=0.1),
    "herman_standing": Perturbation(joint=0.05, position=0.01, orientation=0.03, velocity=0.05,
                                    angular=0.1),
}


def sizes_for(figure: str) -> Perturbation:
    """The default perturbation sizes of a figure (by its registered name)."""
    return FIGURE_SIZES.get(figure, Perturbation())


def round_rng(seed: int, round_: int) -> np.random.Generator:
    """The generator of one round's starts: a function of (seed, round) only."""
    return np.random.default_rng([int(seed), int(round_), 0x0B5A])


def confirm_rng(seed: int, round_: int) -> np.random.Generator:
    """The generator of one round's confirmation starts (``confirm``): neither a
    training round's nor the robustness judge's."""
    return np.random.default_rng([int(seed), int(round_), 0xC0F1])


def trial_rng(seed: int) -> np.random.Generator:
    """The generator of ``gpmotion robustness``'s trials: never a training round's."""
    return np.random.default_rng([int(seed), 0x7E57])


def perturbed_starts(figure, q0, qd0, k: int, rng: np.random.Generator,
                     sizes: Perturbation = Perturbation()) -> tuple[np.ndarray, np.ndarray]:
    """K perturbed initial states (q [K, nq], qd [K, nv]) around (q0, qd0)."""
    if k < 1:
        raise ValueError(f"need at least one start, got {k}")
    q = np.tile(np.asarray(q0, dtype=np.float64), (k, 1))
    qd = np.tile(np.asarray(qd0, dtype=np.float64), (k, 1))
    m = figure.model
    backend_of(m).perturb(m, q, qd, rng, sizes)
    _lift(figure, q, np.asarray(q0, dtype=np.float64))
    return q, qd


def lowest_contact(figure, q) -> np.ndarray:
    """Height [K] of the lowest contact point of each configuration q [K, nq]."""
    m = figure.model
    if len(m.cp_link) == 0:
        return np.full(len(q), np.inf)
    b = backend_of(m)
    pts = b.points(m, q, lambda: b.link_poses(m, q), m.cp_link, m.cp_pos)
    return pts[..., b.UP].min(axis=-1)


def _lift(figure, q, q_nominal) -> None:
    """Raise starts whose lowest contact point is below the nominal start's (if the root can rise)."""
    zi = backend_of(figure.model).height_coordinate(figure.model)
    if zi is None:
        return
    floor = lowest_contact(figure, q_nominal[None])[0]
    q[:, zi] += np.maximum(0.0, floor - lowest_contact(figure, q))


# ---------------------------------------------------------------- batching

def tile_controllers(batch: ControllerBatch, k: int) -> ControllerBatch:
    """Each controller row repeated k times (controller-major)."""
    return batch._replace(ci=np.repeat(batch.ci, k, axis=0), cf=np.repeat(batch.cf, k, axis=0))


def robust_rollout(figure, scene, batch: ControllerBatch, q0s, qd0s, **rollout_kw):
    """N controllers × K starts in one rollout; episode n·K + k = controller n from start k."""
    q0s, qd0s = np.atleast_2d(q0s), np.atleast_2d(qd0s)
    k, n = len(q0s), batch.n_episodes
    if len(qd0s) != k:
        raise ValueError(f"{k} start configurations but {len(qd0s)} start velocities")
    return rollout(figure, scene, tile_controllers(batch, k), q0=np.tile(q0s, (n, 1)),
                   qd0=np.tile(qd0s, (n, 1)), **rollout_kw)


def aggregate(costs, k: int, how: str = "mean") -> np.ndarray:
    """Fold costs [N·K] (lower is better) into one per controller [N]; a non-finite cost counts as WORST."""
    if not is_aggregate(how):
        raise ValueError(f"aggregate must be one of {', '.join(AGGREGATES)} or qNN, got {how!r}")
    c = np.asarray(costs, dtype=np.float64).reshape(-1, k)
    c = np.where(np.isfinite(c), c, WORST)
    if how in AGGREGATES:
        return c.mean(axis=1) if how == "mean" else c.max(axis=1)
    return np.sort(c, axis=1)[:, _order_index(k, how)]


def evaluate(task, family, genomes, *, k: int, seed: int, round_: int, how: str = "mean",
             sizes: Perturbation = Perturbation(), actuation: str | None = None, progress: float = 1.0,
             threads: int | None = None):
    """Costs [N] aggregated over K perturbed starts, the success rate [N] and the trajectory [N·K].

    The starts depend on (seed, round_) only: the same for every backend and after a resume.
    """
    q0, qd0 = task.initial_state()
    q0s, qd0s = perturbed_starts(task.figure, q0, qd0, k, round_rng(seed, round_), sizes)
    traj = robust_rollout(task.figure, task.scene_at(progress), family.encode(list(genomes)), q0s, qd0s,
                          **task.rollout_options(),
                          actuation=actuation or family.default_actuation, default_tau=family.default_tau,
                          record_senses=family.needs_senses, threads=threads)
    costs, _, ok = task.score(traj, progress)
    return aggregate(costs, k, how), np.asarray(ok, float).reshape(-1, k).mean(axis=1), traj


def robustness(task, family, actuation, genome, *, trials: int = 100, seed: int = 0,
               sizes: Perturbation | None = None, threads: int | None = None) -> dict:
    """Success rate and cost spread of one controller over ``trials`` perturbed starts.

    Trial 0 is the nominal start (so the table also says how the controller
    does as evolved); the other trials are drawn from ``trial_rng(seed)``, a
    stream no run's training starts come from.  ``sizes`` default: the figure's.
    """
    sizes = sizes_for(type(task).figure) if sizes is None else sizes
    if not 1 <= trials <= 100_000:
        raise ValueError(f"trials must be in 1..100000, got {trials}")
    q0, qd0 = task.initial_state()
    q0s, qd0s = perturbed_starts(task.figure, q0, qd0, trials, trial_rng(seed), sizes)
    q0s[0], qd0s[0] = q0, qd0
    traj = robust_rollout(task.figure, task.scene_at(1.0), family.encode([genome]), q0s, qd0s,
                          **task.rollout_options(),
                          actuation=actuation, default_tau=family.default_tau,
                          record_senses=family.needs_senses, threads=threads)
    costs, _, ok = task.score(traj, 1.0)
    costs, ok = np.asarray(costs, float), np.asarray(ok, bool)
    q = np.percentile(costs, [0, 25, 50, 75, 100])
    return {"trials": trials, "seed": seed, "success_rate": float(ok.mean()), "nominal_success": bool(ok[0]),
            "nominal_cost": float(costs[0]), "cost_min": q[0], "cost_q25": q[1], "cost_median": q[2],
            "cost_q75": q[3], "cost_max": q[4], "diverged": int(traj.diverged.sum()),
            "sizes": asdict(sizes), "costs": costs.tolist(), "success": ok.tolist()}


# ---------------------------------------------------------------- a run's robust setting

SIZE_KEYS = tuple(Perturbation.__dataclass_fields__)
SETTING_KEYS = ("starts", "aggregate", *SIZE_KEYS, "confirm", "require")
MAX_STARTS = 1000


def normalize(robust: dict | None, task) -> dict:
    """A run's ``robust`` setting checked and completed (the figure's default
    sizes filled in), as config.json records it; {} when off.  Bad values: one
    ConfigError line."""
    if not robust:
        return {}
    from .records import ConfigError, validate_number
    unknown = sorted(set(robust) - set(SETTING_KEYS))
    if unknown:
        raise ConfigError(f"robust: unknown setting(s) {unknown}; known: {list(SETTING_KEYS)}")
    out = {"starts": int(validate_number("--robust-starts", robust.get("starts", 1), lo=1,
                                         hi=MAX_STARTS, integer=True)),
           "aggregate": robust.get("aggregate", "mean")}
    if not is_aggregate(out["aggregate"]):
        raise ConfigError(f"--robust-aggregate must be one of {', '.join(AGGREGATES)} or qNN (q80: the "
                          f"80th-percentile start), "
                         f"got {out['aggregate']!r}")
    default = asdict(sizes_for(type(task).figure))
    for k in SIZE_KEYS:
        v = robust.get(k, default[k])
        out[k] = float(validate_number(f"--perturb {k}", v, lo=0, hi=10.0))
    # written only when set, so configs from before these options read back unchanged
    if robust.get("confirm", 0):
        out["confirm"] = int(validate_number("--robust-confirm", robust["confirm"], lo=0,
                                             hi=MAX_STARTS, integer=True))
    if robust.get("require", 1.0) != 1.0:
        out["require"] = float(validate_number("--robust-require", robust["require"], lo=0.01, hi=1.0))
    return out


def sizes_of(robust: dict) -> Perturbation:
    return Perturbation(**{k: robust[k] for k in SIZE_KEYS})


def batch_evaluation(ev, genomes, progress: float, generation: int):
    """One generation's batch scored from ``ev.robust['starts']`` perturbed starts.

    ``ev`` is an :class:`gpmotion.inprocess.InProcessEvaluator` whose ``robust``
    holds a normalized setting plus the run's ``seed``.  The starts depend on
    (seed, generation) only, so chunks on any backend and a resumed run see
    the same ones.  Per controller: cost = the aggregate of its K costs;
    success = it succeeds from at least ``require`` (default: every one) of
    its starts; failed = some start diverged; measures = those of the mean
    (``mean``: the mean over starts), of the worst start (``worst``) or of the
    NN-th percentile start (``qNN``: the cost 80 % of starts match, for q80), so a
    cost recomputed from them (the final-weights column) agrees with the
    aggregate; extras (BSR senses) from its first start.

    ``confirm`` = M > 0: a controller that succeeds from ``require`` of its K
    starts is run from M more (``confirm_rng(seed, generation)``), and its
    cost, measures and success are over all K + M.  Why: "succeeds from all
    K = 8 starts" is passed by luck — a controller that succeeds from 70 % of
    starts does so 6 % of the time, and a population of 300 has many — so
    ``stop_on_success`` and the best-ever cost picked lucky controllers.
    """
    from .evaluation import Evaluation
    r, task, fam = ev.robust, ev.task, ev.family
    k, n = r["starts"], len(genomes)
    traj = _batch_rollout(ev, genomes, progress, k, round_rng(r["seed"], generation))
    costs, measures, ok = task.score(traj, progress)
    costs = np.where(np.isfinite(costs), costs, WORST).reshape(n, k)
    measures = {m: np.asarray(v).reshape(n, k) for m, v in measures.items()}
    ok, bad = np.asarray(ok, bool).reshape(n, k), traj.diverged.reshape(n, k)
    agg, folded = _fold(costs, measures, r["aggregate"])
    require = r.get("require", 1.0)
    success = ok.mean(axis=1) >= require - 1e-12
    failed = bad.any(axis=1)
    m_more = r.get("confirm", 0)
    cand = np.flatnonzero(success) if m_more else np.zeros(0, int)
    if cand.size:                                   # run the candidates from M more starts
        t2 = _batch_rollout(ev, [genomes[i] for i in cand], progress, m_more,
                            confirm_rng(r["seed"], generation))
        c2, m2, ok2 = task.score(t2, progress)
        c2 = np.where(np.isfinite(c2), c2, WORST).reshape(len(cand), m_more)
        both = {m: np.concatenate([measures[m][cand], np.asarray(v).reshape(len(cand), m_more)], axis=1)
                for m, v in m2.items()}
        a2, f2 = _fold(np.concatenate([costs[cand], c2], axis=1), both, r["aggregate"])
        agg[cand] = a2
        for m in folded:
            folded[m][cand] = f2[m]
        ok_all = np.concatenate([ok[cand], np.asarray(ok2, bool).reshape(len(cand), m_more)], axis=1)
        success[cand] = ok_all.mean(axis=1) >= require - 1e-12
        failed[cand] |= t2.diverged.reshape(len(cand), m_more).any(axis=1)
    extras = fam.extras(traj)                                   # per episode; a genome's first start
    extras = None if extras is None else extras[::k]
    return Evaluation(agg, success, failed, folded, extras)


def _batch_rollout(ev, genomes, progress, k, rng):
    """Genomes × K starts drawn from ``rng`` (one batched rollout, controller-major)."""
    task, fam = ev.task, ev.family
    q0s, qd0s = perturbed_starts(task.figure, ev._q0, ev._qd0, k, rng, sizes_of(ev.robust))
    return robust_rollout(task.figure, ev.scene(progress), fam.encode(genomes), q0s, qd0s,
                          **task.rollout_options(),
                          actuation=ev.actuation, default_tau=fam.default_tau,
                          record_senses=fam.needs_senses, threads=ev.threads)


def _fold(costs, measures: dict, how: str):
    """Per controller (rows of costs [N, S]): the aggregate cost and the measures that give it
    (the mean over starts, or the worst start's)."""
    n = len(costs)
    if how == "mean":
        return costs.mean(axis=1), {m: np.asarray(v, float).mean(axis=1) for m, v in measures.items()}
    if how == "worst":
        pick = np.argmax(costs, axis=1)                         # first of equal worsts
    else:                                                       # qNN: that percentile's start
        pick = np.argsort(costs, axis=1, kind="stable")[:, _order_index(costs.shape[1], how)]
    return costs[np.arange(n), pick], {m: np.asarray(v)[np.arange(n), pick] for m, v in measures.items()}

