"""Secondary fitness terms for 3-D figures (Auslander et al. §4).

The paper's 3-D tasks needed terms beyond Table 3: Rex's walk "penalized
sideways motion and falling down", his turn "measured the change in
heading", and Bob's walk rewarded "forward motion by both the centre of mass
and the feet" and penalized "sideways motion and falling over" and "a net
rotation about the vertical axis" (footnote 10).  The paper gives no
formulas; ours, each over batched frames (episodes first, frames on the
next axis), numpy only:

* heading       yaw of the root body's forward (x) axis, unwrapped (rad)
* forward / sideways   displacement along / across the heading the episode
                starts with (so a stage that starts turned is measured in
                its own frame)
* fallen        per frame: the root's up axis tilted past ``max_tilt`` from
                vertical, or the centre of mass below ``min_height`` × its
                start height, or a non-foot contact point on the ground; a
                figure that fell stays fallen (frames after the first fall)
* fall_fraction fraction of the episode spent fallen (0: never fell)
* net_rotation  |heading(end) − heading(start)| (rad)
* feet_forward  mean forward displacement of the feet (m)
* count_steps   touchdowns of a foot ahead of the other foot, before the
                first fall, while facing within ``max_yaw`` of the start
                heading; with ``alternate`` (bob_walk-v3) only when the
                feet take turns
"""
from __future__ import annotations

import numpy as np

MAX_TILT = np.radians(60.0)     # a root tilted further than this has fallen over
MIN_HEIGHT = 0.5                # ... or a com lower than this fraction of its start


def quat_forward(quat) -> np.ndarray:
    """World x axis of unit quaternions (w, x, y, z) [..., 4] → [..., 3]."""
    w, x, y, z = (quat[..., k] for k in range(4))
    return np.stack([1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)], axis=-1)


def quat_up(quat) -> np.ndarray:
    """World z axis of unit quaternions (w, x, y, z) [..., 4] → [..., 3]."""
    w, x, y, z = (quat[..., k] for k in range(4))
    return np.stack([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)], axis=-1)


def heading(quat) -> np.ndarray:
    """Unwrapped yaw [..., F] of the forward axis projected on the ground."""
    f = quat_forward(np.asarray(quat, dtype=np.float64))
    return np.unwrap(np.arctan2(f[..., 1], f[..., 0]), axis=-1)


def in_start_frame(xy, yaw0) -> np.ndarray:
    """Displacements [..., F, 2] from frame 0, rotated into the start heading:
    [..., F, 0] forward, [..., F, 1] to the left."""
    d = np.asarray(xy, dtype=np.float64) - np.asarray(xy)[..., :1, :]
    c, s = np.cos(yaw0)[..., None], np.sin(yaw0)[..., None]
    return np.stack([c * d[..., 0] + s * d[..., 1], -s * d[..., 0] + c * d[..., 1]], axis=-1)


def fallen(up_z, com_z, other_force, max_tilt=MAX_TILT, min_height=MIN_HEIGHT) -> np.ndarray:
    """Bool [..., F]: fallen at or before each frame (see the module doc).
    ``other_force`` [..., F, k]: normal forces of the contact points that are
    not feet (k may be 0)."""
    up_z, com_z = np.asarray(up_z, np.float64), np.asarray(com_z, np.float64)
    down = (up_z < np.cos(max_tilt)) | (com_z < min_height * com_z[..., :1])
    other = np.asarray(other_force, np.float64)
    if other.shape[-1]:
        down |= (other > 0).any(axis=-1)
    return np.maximum.accumulate(down, axis=-1)


def fall_fraction(fell) -> np.ndarray:
    """Fraction of frames spent fallen [...]."""
    return np.asarray(fell, dtype=np.float64).mean(axis=-1)


def net_rotation(yaw) -> np.ndarray:
    """|Δ heading| over the episode (rad), from an unwrapped yaw [..., F]."""
    yaw = np.asarray(yaw, dtype=np.float64)
    return np.abs(yaw[..., -1] - yaw[..., 0])


def facing_away(yaw) -> np.ndarray:
    """Mean |heading − start heading| over the episode (rad) [...]: a figure
    that waddles, swinging ±50° about a net heading of 0, scores 0 on
    ``net_rotation`` but not here."""
    yaw = np.asarray(yaw, dtype=np.float64)
    return np.abs(yaw - yaw[..., :1]).mean(axis=-1)


def feet_forward(feet_xy, yaw0) -> np.ndarray:
    """Mean forward displacement [...] of the feet [..., F, n_feet, 2]."""
    feet = np.moveaxis(np.asarray(feet_xy, np.float64), -2, -3)      # [..., n_feet, F, 2]
    fwd = in_start_frame(feet, np.asarray(yaw0)[..., None])[..., -1, 0]
    return fwd.mean(axis=-1)


def count_steps(foot_force, foot_fwd, fell, yaw, max_yaw=np.radians(45.0),
                ahead=0.05, alternate=False) -> np.ndarray:
    """Steps [...]: touchdowns (normal force 0 → > 0) of one of two feet
    landing at least ``ahead`` m in front of the other foot (forward = the
    start heading; ``foot_fwd`` [..., F, 2]), before the first fall and
    while the heading is within ``max_yaw`` of the start (forward-facing).

    ``alternate``: a touchdown counts only if the previous counted step was
    the other foot's (the first counted step may be either foot's), so the
    feet must pass each other: a leading foot that bounces or chatters in
    place, or steps again and again while the other foot drags behind, is
    one step, not many.  (Without it, bob_walk-v1/v2's count, every such
    touchdown counts.)"""
    force = np.asarray(foot_force, np.float64)
    fwd = np.asarray(foot_fwd, np.float64)
    down = force > 0
    touch = down[..., 1:, :] & ~down[..., :-1, :]                   # [..., F-1, 2]
    lead = fwd[..., 1:, :] - fwd[..., 1:, ::-1] >= ahead
    yaw = np.asarray(yaw, np.float64)
    ok = ~np.asarray(fell)[..., 1:] & (np.abs(yaw[..., 1:] - yaw[..., :1]) <= max_yaw)
    step = touch & lead & ok[..., None]                              # [..., F-1, 2]
    if not alternate:
        return step.sum(axis=(-2, -1))
    return _alternating(step.reshape(-1, *step.shape[-2:])).reshape(step.shape[:-2])


def _alternating(step) -> np.ndarray:
    """Counted steps [E] of candidate touchdowns [E, F, 2] taken only when the
    foot differs from the last counted one's (with ``ahead`` > 0 the two
    feet never qualify in the same frame)."""
    n = np.zeros(step.shape[0], np.int64)
    last = np.full(step.shape[0], -1)
    for f in range(step.shape[1]):
        for k in (0, 1):
            take = step[:, f, k] & (last != k)
            n += take
            last = np.where(take, k, last)
    return n
