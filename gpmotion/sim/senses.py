"""The sense vector every controller reads (DESIGN §3): the one source of its layout.

A figure's sense vector is its backend's body senses (``BODY[backend]``, in
that order), then one block per kind, in ``BLOCKS`` order: ``angle_<joint>``
and ``rate_<joint>`` per actuated joint, ``force_<contact>`` (ground normal
force) per contact point and, 3-D only, ``site_<name>_dx/_dy/_dz`` per
sensed site.  Positions are relative to the scene's goal point.

No kernel writes at a literal offset.  A backend's kernel writes the *slots*
of ``SLOTS[backend]`` — body quantities and block starts, named by the
constants below — at ``senses[M.sense_at[slot]]``; :func:`sense_layout`
compiles the layout into ``sense_at``.  A body slot the layout leaves out
(``com_x``, ``com_vx``: computed, not in the default layout) is written to
a scratch entry just past the vector.  Adding a body sense is one entry in
``BODY`` (name and range) — plus, if no kernel computes it yet, its slot in
``SLOTS`` and its one write in the backend's senses kernel.
"""
from __future__ import annotations

import numpy as np
from numba import njit

# body senses in layout order, with the range of their normalized [0, 1] view
# (BSR's Table 1; a figure may override any range)
BODY = {
    "planar": (("px", (-2.0, 2.0)), ("pz", (-1.0, 1.0)), ("vx", (-3.0, 3.0)), ("vz", (-3.0, 3.0)),
               ("pitch", (-np.pi, np.pi)), ("pitch_rate", (-10.0, 10.0)), ("com_z", (0.0, 1.0)),
               ("com_vz", (-3.0, 3.0)), ("t", (0.0, 5.0))),
    "3d": (("px", (-2.0, 2.0)), ("py", (-2.0, 2.0)), ("pz", (-1.0, 1.0)),
           ("vx", (-3.0, 3.0)), ("vy", (-3.0, 3.0)), ("vz", (-3.0, 3.0)),
           ("roll", (-np.pi, np.pi)), ("pitch", (-np.pi / 2, np.pi / 2)), ("yaw", (-np.pi, np.pi)),
           ("wx", (-10.0, 10.0)), ("wy", (-10.0, 10.0)), ("wz", (-10.0, 10.0)),
           ("up_x", (-1.0, 1.0)), ("up_y", (-1.0, 1.0)), ("up_z", (-1.0, 1.0)),
           ("com_z", (0.0, 2.0)), ("com_vz", (-3.0, 3.0)), ("t", (0.0, 5.0))),
}
OPTIONAL_RANGES = {"com_x": (-2.0, 2.0), "com_y": (-2.0, 2.0), "com_vx": (-3.0, 3.0),
                   "com_vy": (-3.0, 3.0)}
BLOCKS = ("angle", "rate", "force", "site")
# ranges of the block entries: angle: the joint's limits; force: twice the figure's weight
BLOCK_RANGES = {"rate": (-10.0, 10.0), "site": (-1.0, 1.0)}

# the slots each backend's kernel writes: M.sense_at[slot] is where
SLOTS = {
    "planar": ("px", "pz", "vx", "vz", "pitch", "pitch_rate", "com_z", "com_vz", "t",
               "com_x", "com_vx", "angle", "rate", "force"),
    "3d": ("px", "py", "pz", "vx", "vy", "vz", "roll", "pitch", "yaw", "wx", "wy", "wz",
           "up_x", "up_y", "up_z", "com_z", "com_vz", "t", "com_x", "com_y", "com_vx", "com_vy",
           "angle", "rate", "force", "site"),
}
# planar slot constants, in SLOTS["planar"] order (tests check the pairing by name)
(PX, PZ, VX, VZ, PITCH, PITCH_RATE, COM_Z, COM_VZ, T, COM_X, COM_VX,
 ANGLE, RATE, FORCE) = range(len(SLOTS["planar"]))


def sense_layout(backend, actuators, contacts, lo, hi, total_mass, overrides, sites=()):
    """Names, (lo, hi) ranges and the kernel's write offsets (``sense_at``, int64
    per slot of ``SLOTS[backend]``) of a figure's sense vector.

    ``lo``/``hi``: the actuated joints' limits; ``overrides``: {sense name or
    range key: (lo, hi)} from the figure; ``sites``: sensed sites (3-D).
    """
    r = dict(BODY[backend]) | OPTIONAL_RANGES | BLOCK_RANGES
    r["force"] = (0.0, 2.0 * max(total_mass, 1e-3) * 9.81)
    r.update(overrides)
    names, los, his, start = [], [], [], {}

    def add(name, rng):
        names.append(name)
        los.append(float(rng[0]))
        his.append(float(rng[1]))

    for name, _ in BODY[backend]:
        start[name] = len(names)
        add(name, r[name])
    start["angle"] = len(names)
    for a, l_, h in zip(actuators, lo, hi):
        span = (l_, h) if np.isfinite(l_) and np.isfinite(h) else (-np.pi, np.pi)
        add(f"angle_{a}", r.get(f"angle_{a}", span))
    start["rate"] = len(names)
    for a in actuators:
        add(f"rate_{a}", r.get(f"rate_{a}", r["rate"]))
    start["force"] = len(names)
    for c in contacts:
        add(f"force_{c}", r.get(f"force_{c}", r["force"]))
    if "site" in SLOTS[backend]:
        start["site"] = len(names)
    elif sites:
        raise ValueError(f"the {backend} kernel senses no sites")
    for s_ in sites:
        for ax in ("dx", "dy", "dz"):
            add(f"site_{s_}_{ax}", r.get(f"site_{s_}_{ax}", r["site"]))
    unknown = set(start) - set(SLOTS[backend])
    if unknown:          # a body sense no kernel computes would read 0 forever
        raise ValueError(f"no {backend} kernel computes the senses {sorted(unknown)}")
    scratch = len(names)
    at = np.array([start.get(slot, scratch) for slot in SLOTS[backend]], dtype=np.int64)
    return names, np.array(los), np.array(his), at


@njit(cache=True, error_model="numpy", boundscheck=False, inline="always")
def compute_senses(M, goal, q, qd, pose, cs, v, com, cforce, t, senses, senses_norm):
    """Fill ``senses`` (n_senses + 1 entries: the last is scratch) and
    ``senses_norm`` from the current kinematic state, at ``M.sense_at``.

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
    at = M.sense_at
    senses[at[PX]] = x - goal[0]
    senses[at[PZ]] = z - goal[1]
    senses[at[VX]] = vx
    senses[at[VZ]] = vz
    senses[at[PITCH]] = th
    senses[at[PITCH_RATE]] = w
    senses[at[COM_Z]] = com[1]
    senses[at[COM_VZ]] = com[3]
    senses[at[T]] = t
    senses[at[COM_X]] = com[0]
    senses[at[COM_VX]] = com[2]
    joint_senses(senses, at[ANGLE], at[RATE], at[FORCE], q, qd, M.act_dof, M.act_dof, cforce)
    normalize_senses(M, senses, senses_norm)


@njit(cache=True, error_model="numpy", boundscheck=False, inline="always")
def joint_senses(senses, a0, r0, f0, q, qd, act_q, act_dof, cforce):
    """Actuated joint angles and rates, then contact forces, from their blocks' offsets."""
    for a in range(act_dof.shape[0]):
        senses[a0 + a] = q[act_q[a]]
        senses[r0 + a] = qd[act_dof[a]]
    for k in range(cforce.shape[0]):
        senses[f0 + k] = cforce[k]


@njit(cache=True, error_model="numpy", boundscheck=False, inline="always")
def normalize_senses(M, senses, senses_norm):
    """Every sense mapped to [0, 1] over its range (a zero-width range: 0.5)."""
    for k in range(M.sense_lo.shape[0]):
        lo, hi = M.sense_lo[k], M.sense_hi[k]
        span = hi - lo
        y = (senses[k] - lo) / span if span > 0 else 0.5
        senses_norm[k] = min(1.0, max(0.0, y))
