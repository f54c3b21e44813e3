"""Kernel for the 3-D *sense-based* BSR controller (Auslander et al. §4.2).
(Rollouts import it under its package name: gpmotion.cache.import_file.)

Same rules as ``sense_kernel`` (score_j = W_j · (1 − max_k [λ_jk (S_k − μ_jk)]²),
the highest positive score wins, else the active rule stays), but the
stimulus S is the paper's 3-D sense vector, built here from the figure's raw
senses and low-pass filtered (``gpmotion.bsr.senses3d`` documents the senses,
the figure-centric frame and the filter; its numpy twin computes the same
numbers from recorded frames).

The controller samples its senses every ``every`` simulation steps (the
task's frame interval, so the samples are exactly the recorded frames):
at each sample it rotates the root's velocity, angular velocity and up axis
into the heading frame, updates the filter y ← y + α (x − y) (y = x at the
first sample), normalizes y to [0, 1] and selects a rule; the first sample
keeps rule 0 (Fig. 2: senses are measured only after the first step).

Program layout (``senses3d.encode_batch``)
  ci = [R, V, n_act, every, n_contacts, n_angles,
        i_vx, i_vy, i_com_vz, i_wx, i_wy, i_wz, i_up_x, i_up_y, i_up_z, i_com_z, i_yaw,
        contact sense indices (n_contacts), angle sense indices (n_angles),
        actuator of θ₀ column 0 .. n_act−1]
  cf = [α, lo_0..lo_{V−1}, hi_0..hi_{V−1},
        then R blocks of [W, τ, μ_0..μ_{V−1}, λ_0..λ_{V−1}, θ₀_0..θ₀_{n_act−1}]]
  cstate = [active rule, steps taken, y_0 .. y_{V−1} (filtered, raw units),
            s_0 .. s_{V−1} (scratch: normalized)]         (2 + 2V)
"""
from __future__ import annotations

import math

from numba import njit

from gpmotion.controllers import KERNEL_JIT_3D

CI_HEADER = 6
N_BODY = 10            # com_z, v (3), ω (3), up (3)
N_SOURCES = 11         # the raw senses the body part is built from (+ yaw)


@njit(**KERNEL_JIT_3D)
def init(ci, cf, cstate):
    cstate[0] = 0.0
    cstate[1] = 0.0


@njit(**KERNEL_JIT_3D)
def sample(ci, senses, x):
    """The 3-D sense vector (raw units) from the figure's raw senses."""
    src = CI_HEADER
    yaw = senses[ci[src + 10]]
    c, s = math.cos(yaw), math.sin(yaw)
    x[0] = senses[ci[src + 9]]                                   # com height
    for k in range(3):                                           # v, ω, up: heading frame
        a = senses[ci[src + 3 * k]]
        b = senses[ci[src + 3 * k + 1]]
        x[1 + 3 * k] = c * a + s * b
        x[2 + 3 * k] = -s * a + c * b
        x[3 + 3 * k] = senses[ci[src + 3 * k + 2]]
    n_c, n_a = ci[4], ci[5]
    base = CI_HEADER + N_SOURCES
    for k in range(n_c + n_a):
        x[N_BODY + k] = senses[ci[base + k]]


@njit(**KERNEL_JIT_3D)
def select(ci, cf, cstate, previous):
    """Rule with the highest positive score on the normalized senses in cstate."""
    n_rules, V, n_act = ci[0], ci[1], ci[2]
    stride = 2 + 2 * V + n_act
    first = 1 + 2 * V
    norm = 2 + V
    best, best_score = previous, 0.0
    for j in range(n_rules):
        base = first + j * stride
        worst = 0.0
        for k in range(V):
            d = cf[base + 2 + V + k] * (cstate[norm + k] - cf[base + 2 + k])
            if d * d > worst:
                worst = d * d
        score = cf[base] * (1.0 - worst)
        if score > best_score:
            best_score, best = score, j
    return best


@njit(**KERNEL_JIT_3D)
def control(ci, cf, senses, senses_norm, t, cstate, targets, taus):
    V, n_act, every = ci[1], ci[2], ci[3]
    step = int(cstate[1])
    cstate[1] += 1.0
    if step % every == 0:
        y = cstate[2:2 + V]
        x = cstate[2 + V:2 + 2 * V]         # scratch: the new sample, then normalized
        sample(ci, senses, x)
        alpha = cf[0]
        for k in range(V):
            yk = x[k] if step == 0 else y[k] + alpha * (x[k] - y[k])
            y[k] = yk
            lo, hi = cf[1 + k], cf[1 + V + k]
            v = (yk - lo) / (hi - lo) if hi > lo else 0.5
            x[k] = min(1.0, max(0.0, v))
        if step > 0:
            cstate[0] = select(ci, cf, cstate, int(cstate[0]))
    active = int(cstate[0])
    stride = 2 + 2 * V + n_act
    base = 1 + 2 * V + active * stride
    tau = cf[base + 1]
    pose = base + 2 + 2 * V
    amap = CI_HEADER + N_SOURCES + ci[4] + ci[5]
    for i in range(n_act):
        a = ci[amap + i]
        targets[a] = cf[pose + i]
        taus[a] = tau
