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
                     force_threshold: float = 0.0, direction: float | None = None) -> np.ndarray:
    """Table 3 contact_distance: distance traversed by body parts in
    continuous contact with the ground.

    A contact point is *in contact* at a frame when its normal force exceeds
    ``force_threshold``; a *stretch* is a run of consecutive frames in which
    it is.  Each stretch contributes the net horizontal displacement of the
    point over it, x(last) − x(first) — what it *traversed* while touching —
    so sliding to and fro in place adds nothing, and a point that lifts off,
    moves and lands again contributes nothing for that flight.
    ``direction`` +1 (−1) counts each stretch signed along +x (−x), so only
    travel in that direction pays and a backward slide costs (a travel
    task's reading); ``None`` counts |net| per stretch (either direction).
    Summed over points.  Sampling frames finely enough to resolve lift-off
    is the caller's job.
    """
    force = np.asarray(contact_force_frames, dtype=np.float64)
    x = np.asarray(contact_x_frames, dtype=np.float64)
    if force.shape != x.shape or force.ndim < 2:
        raise ValueError(f"contact arrays must share shape [..., n_frames, "
                         f"n_points], got {force.shape} and {x.shape}")
    touching = force > force_threshold
    both = touching[..., 1:, :] & touching[..., :-1, :]          # step f → f+1 in contact
    step = np.where(both, np.diff(x, axis=-2), 0.0)
    if direction is not None:            # Σ over stretches of signed net = Σ of signed steps
        return np.sign(direction) * step.sum(axis=(-2, -1))
    return np.abs(_stretch_sums(step, both)).sum(axis=(-2, -1))


def grounded_distance(contact_force_frames, com_x_frames, force_threshold: float = 0.0,
                      direction: float = 1.0) -> np.ndarray:
    """Table 3's contact_distance read for pinned contacts: the distance the
    centre of mass travels (along ``direction``) while the figure stays in
    contact with the ground — summed over the frame steps at both ends of
    which some point is down, so a flight earns nothing.

    Why a second reading: Auslander et al.'s simulator pins a touching point
    (no slip), so there a point in continuous contact traverses nothing and
    the term can only measure the figure's travel while it keeps contact; a
    shuffle (never airborne) earns its whole distance.  Ours slides under
    Coulomb friction, where :func:`contact_distance` pays limbs for sliding.
    """
    force = np.asarray(contact_force_frames, dtype=np.float64)
    x = np.asarray(com_x_frames, dtype=np.float64)
    if force.ndim < 2 or force.shape[:-1] != x.shape:
        raise ValueError(f"contact forces [..., n_frames, n_points] and com x [..., n_frames] "
                         f"must share their frames, got {force.shape} and {x.shape}")
    down = (force > force_threshold).any(axis=-1)
    both = down[..., 1:] & down[..., :-1]
    return np.sign(direction) * np.where(both, np.diff(x, axis=-1), 0.0).sum(axis=-1)


def _stretch_sums(step, both):
    """Per run of True in ``both`` (axis −2), the sum of ``step`` over it,
    placed at the run's last entry (0 elsewhere)."""
    c = np.cumsum(step, axis=-2)
    n = both.shape[-2]
    idx = np.arange(n).reshape((n, 1))
    prev = np.concatenate([np.zeros_like(both[..., :1, :]), both[..., :-1, :]], axis=-2)
    nxt = np.concatenate([both[..., 1:, :], np.zeros_like(both[..., :1, :])], axis=-2)
    start = np.maximum.accumulate(np.where(both & ~prev, idx, 0), axis=-2)
    before = np.take_along_axis(c, start, axis=-2) - np.take_along_axis(step, start, axis=-2)
    return np.where(both & ~nxt, c - before, 0.0)


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
