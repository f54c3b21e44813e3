"""The sense vector every controller reads (DESIGN §3), named and normalized.

Layout: the 9 body senses below, then ``angle_<joint>`` and ``rate_<joint>``
for every actuated joint, then ``force_<contact>`` (ground normal force) for
every contact point.  Positions are relative to the scene's goal point.
"""
from __future__ import annotations

import numpy as np
from numba import njit

BODY_SENSES = ("px", "pz", "vx", "vz", "pitch", "pitch_rate", "com_z", "com_vz", "t")
N_BODY = len(BODY_SENSES)

# ranges of the normalized [0, 1] view (BSR's Table 1); overridable per figure
DEFAULT_RANGES = {"px": (-2.0, 2.0), "pz": (-1.0, 1.0), "vx": (-3.0, 3.0), "vz": (-3.0, 3.0),
                  "pitch": (-np.pi, np.pi), "pitch_rate": (-10.0, 10.0), "com_z": (0.0, 1.0),
                  "com_vz": (-3.0, 3.0), "t": (0.0, 5.0), "rate": (-10.0, 10.0)}


def sense_layout(actuators, contacts, lo, hi, total_mass, overrides, *,
                 body=BODY_SENSES, ranges=DEFAULT_RANGES, sites=()):
    """Names and (lo, hi) ranges of the sense vector of a figure.

    ``body``/``ranges`` are the planar body senses by default; the 3-D
    kernel passes its own and the sensed sites (``site_<name>_dx/dy/dz``).
    """
    r = dict(ranges)
    r["force"] = (0.0, 2.0 * max(total_mass, 1e-3) * 9.81)
    r.update(overrides)
    names, los, his = [], [], []

    def add(name, rng):
        names.append(name)
        los.append(float(rng[0]))
        his.append(float(rng[1]))

    for n in body:
        add(n, r[n])
    for a, l_, h in zip(actuators, lo, hi):
        span = (l_, h) if np.isfinite(l_) and np.isfinite(h) else (-np.pi, np.pi)
        add(f"angle_{a}", r.get(f"angle_{a}", span))
    for a in actuators:
        add(f"rate_{a}", r.get(f"rate_{a}", r["rate"]))
    for c in contacts:
        add(f"force_{c}", r.get(f"force_{c}", r["force"]))
    for s_ in sites:
        for ax in ("dx", "dy", "dz"):
            add(f"site_{s_}_{ax}", r.get(f"site_{s_}_{ax}", r["site"]))
    return names, np.array(los), np.array(his)


@njit(cache=True, error_model="numpy", boundscheck=False, inline="always")
def compute_senses(M, goal, q, qd, pose, cs, v, com, cforce, t, senses, senses_norm):
    """Fill ``senses`` and ``senses_norm`` from the current kinematic state.

    ``pose[i] = (θ, x, z)`` world pose of link i, ``cs[i] = (cos θ, sin θ)``,
    ``v[i]`` its spatial velocity in link coordinates, ``com = (x, z, vx, vz)``.
    """
    # numba: an array read inside an if/else here defeats reference-count
    # pruning (~0.3 µs per call): read unconditionally, branch on scalars only
    b = M.base_link
    fth, fx, fz = M.fixed_pose[0], M.fixed_pose[1], M.fixed_pose[2]
    bb = max(b, 0)
    th, x, z = pose[bb, 0], pose[bb, 1], pose[bb, 2]
    c, s = cs[bb, 0], cs[bb, 1]
    w, v1, v2 = v[bb, 0], v[bb, 1], v[bb, 2]
    vx = c * v1 - s * v2
    vz = s * v1 + c * v2
    if b < 0:                       # a fixed root: the base does not move
        th, x, z, vx, vz, w = fth, fx, fz, 0.0, 0.0, 0.0
    senses[0] = x - goal[0]
    senses[1] = z - goal[1]
    senses[2] = vx
    senses[3] = vz
    senses[4] = th
    senses[5] = w
    senses[6] = com[1]
    senses[7] = com[3]
    senses[8] = t
    na = M.act_dof.shape[0]
    for a in range(na):
        i = M.act_dof[a]
        senses[9 + a] = q[i]
        senses[9 + na + a] = qd[i]
    for k in range(cforce.shape[0]):
        senses[9 + 2 * na + k] = cforce[k]
    for k in range(senses.shape[0]):
        lo, hi = M.sense_lo[k], M.sense_hi[k]
        span = hi - lo
        y = (senses[k] - lo) / span if span > 0 else 0.5
        senses_norm[k] = min(1.0, max(0.0, y))
