"""BSR mutation: creep one rule, or reinitialize one rule (§2.1.3).

"For each mutation, local optimization is facilitated by subjecting one rule
to *creep* (each free parameter in the rule is perturbed slightly), and
global optimization by reinitializing one rule from scratch", where the new
stimulus box is placed by the **relevance heuristic**: one of its corners
lies on the sense trajectory S(t) of the *unmutated* controller, so the new
rule is likely to become active at some point (a random box in a
2N+2-dimensional space almost never would).

Choices the paper leaves open (documented, overridable):
* probability of reinitialization ``P_REINIT = 1/3`` — the only ratio the
  paper states is Fig. 5's "randomize 1/3 of the time, perturb 2/3";
* creep sizes (``CREEP``): μ += N(0, 0.05); side 2/λ and τ are multiplied
  by exp(N(0, 0.1)) (they are log-distributed in Table 2); θ₀ += N(0, 5% of
  the joint range); everything is clipped back into its valid range.
* the trajectory is ``float64[n_frames, V]``: the V normalized senses the
  controller reads (``senses_norm[sense_indices]``) at every recorded frame.
  Non-finite frames are skipped; with no usable trajectory the stimulus is
  drawn from Table 2 instead.
Time-based genomes mutate the same way, minus the stimulus; with variable
segments the rule's relative duration creeps like τ (× exp(N(0, 0.1))) and
is redrawn from DURATION_INIT on reinitialization, so the R − 1 dividers
move with the search.
"""
from __future__ import annotations

import numpy as np

from gpmotion.bsr.genome import (DURATION_BOUNDS, DURATION_INIT, LAMBDA_MAX, LAMBDA_MIN,
                                 MU_BOUNDS, SenseGenome, exp, log_uniform, random_stimulus,
                                 random_theta0)

P_REINIT = 1.0 / 3.0
CREEP = {"mu": 0.05, "log_side": 0.1, "theta_frac": 0.05, "log_tau": 0.1}


def normalized_sense_trajectory(raw, sense_lo, sense_hi, sense_indices) -> np.ndarray:
    """Relevance-heuristic input from *raw* recorded senses ``[..., F, n_senses]``.

    Same mapping as the rollout's ``senses_norm`` (clip((s − lo)/(hi − lo), 0,
    1), 0.5 for an empty range), then the columns the controller reads.
    """
    raw = np.asarray(raw, dtype=np.float64)
    lo, hi = np.asarray(sense_lo, np.float64), np.asarray(sense_hi, np.float64)
    span = hi - lo
    with np.errstate(divide="ignore", invalid="ignore"):
        y = np.where(span > 0, (raw - lo) / np.where(span > 0, span, 1.0), 0.5)
    return np.clip(y, 0.0, 1.0)[..., np.asarray(sense_indices, dtype=np.int64)]


def usable_frame(trajectory, rng):
    """(frame, point) of a random frame of ``trajectory`` [F, V] whose senses are all
    finite, the point clipped to [0, 1] (senses_norm's range); None if there is none."""
    traj = np.asarray(trajectory, dtype=np.float64)
    if traj.ndim != 2 or traj.shape[0] == 0:
        return None
    usable = np.flatnonzero(np.all(np.isfinite(traj), axis=1))
    if usable.size == 0:
        return None
    frame = int(usable[rng.integers(usable.size)])
    return frame, np.clip(traj[frame], 0.0, 1.0)


def relevant_stimulus(rng: np.random.Generator, trajectory) -> tuple | None:
    """A Table-2-sized box with a corner on a random trajectory point.

    Returns (μ, λ, point, frame) or None if no frame is usable.  Each side
    2/λ_k is log-uniform in [0.4, 4]; the box extends from the point away
    in a random direction per sense, μ_k = p_k ± 1/λ_k, so p is exactly one
    of its 2^V corners.
    """
    picked = usable_frame(trajectory, rng)
    if picked is None:
        return None
    frame, point = picked
    lam = np.clip(2.0 / log_uniform(rng, 0.4, 4.0, point.size),
                  LAMBDA_MIN, LAMBDA_MAX)
    sign = rng.choice(np.array([-1.0, 1.0]), point.size)
    mu = point + sign / lam
    return mu, lam, point, frame


def creep_rule(genome, rng: np.random.Generator, rule: int | None = None,
               scale: float = 1.0):
    """Copy of ``genome`` with every parameter of one rule perturbed slightly."""
    g = genome.copy()
    r = int(rng.integers(g.n_rules)) if rule is None else rule
    lo, hi = g.limits[:, 0], g.limits[:, 1]
    g.theta0[r] = np.clip(g.theta0[r] + rng.normal(0.0, 1.0, g.n_act)
                          * CREEP["theta_frac"] * scale * (hi - lo), lo, hi)
    g.tau[r] = np.clip(g.tau[r] * exp(rng.normal(0.0, CREEP["log_tau"] * scale)),
                       g.tau_range[0], g.tau_range[1])
    if getattr(g, "durations", None) is not None:
        g.durations[r] = np.clip(g.durations[r] * exp(
            rng.normal(0.0, CREEP["log_tau"] * scale)), *DURATION_BOUNDS)
    if isinstance(g, SenseGenome):
        g.mu[r] = np.clip(g.mu[r] + rng.normal(0.0, CREEP["mu"] * scale, g.n_senses),
                          *MU_BOUNDS)
        side = 2.0 / g.lam[r] * exp(rng.normal(0.0, CREEP["log_side"] * scale,
                                                  g.n_senses))
        g.lam[r] = np.clip(2.0 / side, LAMBDA_MIN, LAMBDA_MAX)
    return g


def reinit_rule(genome, rng: np.random.Generator, rule: int | None = None,
                trajectory=None):
    """Copy of ``genome`` with one rule redrawn (relevance heuristic for μ, λ)."""
    g = genome.copy()
    r = int(rng.integers(g.n_rules)) if rule is None else rule
    g.theta0[r] = random_theta0(rng, g.limits, 1)[0]
    g.tau[r] = log_uniform(rng, g.tau_range[0], g.tau_range[1])
    if getattr(g, "durations", None) is not None:
        g.durations[r] = log_uniform(rng, *DURATION_INIT)
    if isinstance(g, SenseGenome):
        box = None if trajectory is None else relevant_stimulus(rng, trajectory)
        if box is not None and box[0].size != g.n_senses:
            raise ValueError(f"trajectory has {box[0].size} senses per frame, "
                             f"genome reads {g.n_senses}")
        if box is None:
            mu, lam = random_stimulus(rng, 1, g.n_senses)
            box = (mu[0], lam[0])
        g.mu[r], g.lam[r] = box[0], box[1]
    return g


def mutate(genome, rng: np.random.Generator, trajectory=None,
           p_reinit: float = P_REINIT, scale: float = 1.0):
    """One mutation: reinitialize a rule with probability p_reinit, else creep."""
    if rng.random() < p_reinit:
        return reinit_rule(genome, rng, trajectory=trajectory)
    return creep_rule(genome, rng, scale=scale)


def make_mutate_fn(p_reinit: float = P_REINIT, scale: float = 1.0):
    """``mutate_fn(genome, rng, extra)`` for :class:`SerialSearch`.

    ``extra`` is the unmutated controller's sense trajectory (or None).
    """
    def mutate_fn(genome, rng, extra=None):
        return mutate(genome, rng, extra, p_reinit=p_reinit, scale=scale)
    return mutate_fn
