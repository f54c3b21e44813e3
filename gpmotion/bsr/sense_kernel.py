"""Kernel for the *sense-based* BSR controller (Auslander et al. §2.1.2).
(Rollouts import it under its package name: gpmotion.cache.import_file.)

A controller is a bank of R stimulus-response rules.  Rule j has a stimulus
hyperrectangle (centre μ_j, sharpness λ_j, one value per sense, side length
2/λ) and a response (target pose θ₀_j for every actuated joint and one time
constant τ_j).  Each step every rule is scored

    score_j = W_j · (1 − max_k [λ_jk (S[k] − μ_jk)]²),
    W_j     = Σ_k log(λ_jk / λ_min),

and the rule with the highest *positive* score becomes active; if no score
is positive the previously active rule stays active.  Ties go to the lower
rule index.  λ_min = 2 / 4 = 0.5 is the smallest allowable λ (Table 2 bounds
the side length 2/λ to [0.4, 4]); W_j is computed once, in
:func:`gpmotion.bsr.genome.encode_batch`, and stored in the program.

Parameter count — the paper's (5N+4)R for an N-rod planar figure:
  senses V = 2N+2 (Table 1): N−1 joint angles, N+1 rod-endpoint contact
  forces, y_cm, ẏ_cm; joints n_act = N−1.  Per rule: μ (V) + λ (V) + θ₀
  (N−1) + τ (1) = 2(2N+2) + (N−1) + 1 = 5N+4.  So the paper has ONE τ per
  rule (Fig. 2: "time constant τ_i_active"), which we write to every entry
  of ``taus``.  In general a rule has 2V + n_act + 1 parameters; V is
  whatever subset of ``senses_norm`` the caller selects via sense indices.

Initial rule: rule 0 (Fig. 2 "Set i_active to 1").  Fig. 2 measures the
senses only *after* the first step, so the first ``control`` call of an
episode keeps rule 0 without scoring; every later call scores the senses it
is given (the senses at the end of the previous step, as in Fig. 2).

Program layout (see ``encode_batch``)
  ci = [R, V, n_act, sense_index_0 .. sense_index_{V-1},
        actuator_0 .. actuator_{n_act-1}]   (figure actuator of θ₀ column i;
        the figure's other actuators keep the rollout's neutral target and τ)
  cf = R blocks of [W, τ, μ_0..μ_{V-1}, λ_0..λ_{V-1}, θ₀_0..θ₀_{n_act-1}]
  cstate = [active rule, steps taken]        (CSTATE_SIZE = 2)
``control`` allocates nothing: it runs every simulation step.
"""
from __future__ import annotations

from numba import njit

from gpmotion.controllers import KERNEL_JIT

CI_HEADER = 3          # R, V, n_act
CF_RULE_HEADER = 2     # W, τ
CSTATE_SIZE = 2


@njit(**KERNEL_JIT)
def init(ci, cf, cstate):
    cstate[0] = 0.0    # active rule: rule 0, as Fig. 2 "Set i_active to 1"
    cstate[1] = 0.0    # number of control calls so far


@njit(**KERNEL_JIT)
def select_rule(ci, cf, senses_norm, previous):
    """Index of the rule with the highest positive score, else ``previous``."""
    n_rules = ci[0]
    n_senses = ci[1]
    n_act = ci[2]
    stride = CF_RULE_HEADER + 2 * n_senses + n_act
    best = previous
    best_score = 0.0
    for j in range(n_rules):
        base = j * stride
        weight = cf[base]
        worst = 0.0                       # max_k [λ (S − μ)]²
        for k in range(n_senses):
            s = senses_norm[ci[CI_HEADER + k]]
            d = cf[base + CF_RULE_HEADER + n_senses + k] * (
                s - cf[base + CF_RULE_HEADER + k])
            d2 = d * d
            if d2 > worst:
                worst = d2
        score = weight * (1.0 - worst)
        if score > best_score:
            best_score = score
            best = j
    return best


@njit(**KERNEL_JIT)
def control(ci, cf, senses, senses_norm, t, cstate, targets, taus):
    n_senses = ci[1]
    n_act = ci[2]
    active = int(cstate[0])
    if cstate[1] > 0.0:
        active = select_rule(ci, cf, senses_norm, active)
        cstate[0] = active
    cstate[1] += 1.0
    stride = CF_RULE_HEADER + 2 * n_senses + n_act
    base = active * stride
    tau = cf[base + 1]
    pose = base + CF_RULE_HEADER + 2 * n_senses
    amap = CI_HEADER + n_senses
    for i in range(n_act):
        a = ci[amap + i]
        targets[a] = cf[pose + i]
        taus[a] = tau
