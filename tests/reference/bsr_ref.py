"""Plain-numpy twins of the BSR kernels, written straight from the paper.

They work on genome arrays (μ, λ, θ₀, τ), not on the packed program, so a
mismatch also catches an encoding bug.
"""
import math

import numpy as np

LAMBDA_MIN = 0.5


def rule_scores(mu, lam, s):
    """W_j (1 − max_k [λ_jk (S_k − μ_jk)]²), W_j = Σ_k log(λ_jk / λ_min)."""
    w = np.log(lam / LAMBDA_MIN).sum(axis=1)
    return w * (1.0 - np.max((lam * (s[None, :] - mu)) ** 2, axis=1))


def select_rule(mu, lam, s, previous):
    """Highest positive score wins (first on ties); none positive: keep."""
    scores = rule_scores(mu, lam, s)
    j = int(np.argmax(scores))
    return j if scores[j] > 0.0 else previous


def sense_controller_run(mu, lam, theta0, tau, sense_rows):
    """Targets, taus and active rule for consecutive control calls; rule 0
    is active at the first call (Fig. 2), later calls score the senses."""
    active, out = 0, []
    for step, s in enumerate(sense_rows):
        if step > 0:
            active = select_rule(mu, lam, s, active)
        out.append((theta0[active].copy(), np.full(theta0.shape[1], tau[active]), active))
    return out


def time_segment(t, t_per, n_rules):
    return min(int(math.floor((t % t_per) / (t_per / n_rules))), n_rules - 1)
