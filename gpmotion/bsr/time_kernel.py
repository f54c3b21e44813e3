"""Kernel for the *time-based* BSR controller (Auslander et al. §2.3, Fig. 4).
(Rollouts import it under its package name: gpmotion.cache.import_file.)

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
equal segments by default, so a rule has (N−1) + 1 = N parameters in the
paper's rod count = n_act + 1 in ours.  With variable segments
(``TimeGenome.durations``, an option) each rule also has a relative
duration, the paper's R − 1 dividers per period; rule r is then active
while the phase fraction (t mod t_per)/t_per lies in [b_{r−1}, b_r) with
b_{−1} = 0, b_{R−1} = 1.

Program layout (see ``encode_batch``)
  ci = [R, n_act, variable (0/1), actuator_0 .. actuator_{n_act-1}]
        (actuator_i: the figure actuator of θ₀ column i; the figure's other
        actuators keep the rollout's neutral target and τ)
  cf = [t_per, then R blocks of [τ, θ₀_0 .. θ₀_{n_act-1}],
        then (variable) the R − 1 inner boundaries b_0 < .. < b_{R−2}]
  cstate = [active rule]                      (CSTATE_SIZE = 1)
"""
from __future__ import annotations

import math

from numba import njit

from gpmotion.controllers import KERNEL_JIT

CSTATE_SIZE = 1


@njit(**KERNEL_JIT)
def init(ci, cf, cstate):
    cstate[0] = 0.0


@njit(**KERNEL_JIT)
def segment(t, t_per, n_rules):
    """Active rule at time t; clamped so rounding never leaves [0, R−1]."""
    phase = t - t_per * math.floor(t / t_per)      # t mod t_per, in [0, t_per)
    r = int(math.floor(phase / (t_per / n_rules)))
    if r < 0:
        r = 0
    if r > n_rules - 1:
        r = n_rules - 1
    return r


@njit(**KERNEL_JIT)
def variable_segment(t, t_per, cf, first, n_rules):
    """Active rule with boundaries cf[first : first + R − 1] (fractions of t_per)."""
    frac = (t - t_per * math.floor(t / t_per)) / t_per
    r = 0
    while r < n_rules - 1 and frac >= cf[first + r]:
        r += 1
    return r


@njit(**KERNEL_JIT)
def control(ci, cf, senses, senses_norm, t, cstate, targets, taus):
    n_rules = ci[0]
    n_act = ci[1]
    if ci[2] != 0:
        r = variable_segment(t, cf[0], cf, 1 + n_rules * (n_act + 1), n_rules)
    else:
        r = segment(t, cf[0], n_rules)
    cstate[0] = r
    base = 1 + r * (n_act + 1)
    tau = cf[base]
    for i in range(n_act):
        a = ci[3 + i]
        targets[a] = cf[base + 1 + i]
        taus[a] = tau
