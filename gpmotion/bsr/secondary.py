"""Table 3 secondary fitness terms (Auslander et al. §2.2), over trajectories.

Added with small weights to a task's primary term to steer style: positive
``max_height`` favours hops and jumps, ``contact_distance`` sliding and
shuffling, ``rotations`` gyrations such as cartwheels.  Frames are on axis
−1 for scalar channels (``com_z[..., n_frames]``) and on axis −2 for
per-contact-point channels (``[..., n_frames, n_points]``), so each term
works on one episode or a batch.
"""
from __future__ import annotations

import numpy as np


def max_height(com_z) -> np.ndarray:
    """Table 3 max_height: maximum height of the centre of mass during motion."""
    return np.max(np.asarray(com_z, dtype=np.float64), axis=-1)


def contact_distance(contact_force_frames, contact_x_frames,
                     force_threshold: float = 0.0) -> np.ndarray:
    """Table 3 contact_distance: distance traversed by body parts in
    continuous contact with the ground.

    A contact point is *in contact* at a frame when its normal force exceeds
    ``force_threshold``.  For each point we add |x(f+1) − x(f)| over every pair
    of consecutive frames in which it is in contact at both ends (so a point
    that lifts off, moves and lands again contributes nothing for that
    flight), then sum over the points.  Sampling frames finely enough to
    resolve lift-off is the caller's job.
    """
    force = np.asarray(contact_force_frames, dtype=np.float64)
    x = np.asarray(contact_x_frames, dtype=np.float64)
    if force.shape != x.shape or force.ndim < 2:
        raise ValueError(f"contact arrays must share shape [..., n_frames, "
                         f"n_points], got {force.shape} and {x.shape}")
    touching = force > force_threshold
    both = touching[..., 1:, :] & touching[..., :-1, :]
    step = np.abs(np.diff(x, axis=-2))
    return np.where(both, step, 0.0).sum(axis=(-2, -1))


def rotations(pitch_frames, whole: bool = True) -> np.ndarray:
    """Table 3 rotations: number of full-body rotations during the motion.

    Net rotation = |unwrapped pitch at the end − at the start| / 2π, in either
    direction (a cartwheel left counts as one right).  ``whole=True`` returns
    completed rotations (floored), as the paper's "number of full-body
    rotations"; ``whole=False`` the fractional count, a smoother search
    signal.  Unwrapping needs |Δpitch| < π between frames.
    """
    pitch = np.unwrap(np.asarray(pitch_frames, dtype=np.float64), axis=-1)
    turns = np.abs(pitch[..., -1] - pitch[..., 0]) / (2.0 * np.pi)
    return np.floor(turns + 1e-9) if whole else turns
