"""Kernel for the *time-based* BSR controller (Auslander et al. §2.3, Fig. 4).

The sole "sense" is elapsed time.  A user-chosen period t_per is split into
R equal segments; rule r is active while

    r = floor((t mod t_per) / (t_per / R)),

so the script of responses repeats when t_per < T and is aperiodic when
t_per ≥ T.  A rule is only a response: θ₀ for every actuated joint and one τ,
i.e. n_act + 1 parameters per rule, (n_act + 1)R in all.

Reconciling with the paper: footnote 6 says N+1 parameters per rule for an
N-rod figure, which has N−1 joints; θ₀ + τ is only N.  The paper's 3-D count
(§4.1: "R−1 independent variables to divide up each period", total 2NR − 1)
shows the extra per-rule parameter is the segment's *duration*.  We follow
the brief and use equal segments, so a rule has (N−1) + 1 = N parameters in
the paper's rod count = n_act + 1 in ours.  Variable durations would add R−1
parameters and a boundary search here.

Program layout (see ``encode_batch``)
  ci = [R, n_act, actuator_0 .. actuator_{n_act-1}]   (figure actuator of θ₀
        column i; the figure's other actuators keep the rollout's neutral
        target and τ)
  cf = [t_per, then R blocks of [τ, θ₀_0 .. θ₀_{n_act-1}]]
  cstate = [active rule]                      (CSTATE_SIZE = 1)
"""
from __future__ import annotations

import math

from numba import njit

CSTATE_SIZE = 1


@njit(cache=True)
def init(ci, cf, cstate):
    cstate[0] = 0.0


@njit(cache=True)
def segment(t, t_per, n_rules):
    """Active rule at time t; clamped so rounding never leaves [0, R−1]."""
    phase = t - t_per * math.floor(t / t_per)      # t mod t_per, in [0, t_per)
    r = int(math.floor(phase / (t_per / n_rules)))
    if r < 0:
        r = 0
    if r > n_rules - 1:
        r = n_rules - 1
    return r


@njit(cache=True)
def control(ci, cf, senses, senses_norm, t, cstate, targets, taus):
    n_rules = ci[0]
    n_act = ci[1]
    r = segment(t, cf[0], n_rules)
    cstate[0] = r
    base = 1 + r * (n_act + 1)
    tau = cf[base]
    for i in range(n_act):
        a = ci[2 + i]
        targets[a] = cf[base + 1 + i]
        taus[a] = tau
