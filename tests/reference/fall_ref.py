"""Plain-numpy twin of the rollout's fall stop (``rollout(..., stop_pitch=...)``).

A full episode, cut as the kernel cuts it: from the first recorded frame whose
base pitch is beyond the bound, every later frame holds that frame's pose,
com and targets, with zero velocity and no events.  An episode cut there never
diverges: a divergence ends a full episode, so it comes after any recorded fall.
"""
import numpy as np

HELD = ("q", "com", "targets", "senses", "obj")          # copied from the fall frame
ZEROED = ("qd", "contact_force", "pole_hit", "impact", "energy")


def fall_frames(traj, bound: float) -> np.ndarray:
    """[E] each episode's first recorded frame with |base pitch| > bound, or −1."""
    fallen = np.abs(traj.base()[..., 0]) > bound
    return np.where(fallen.any(axis=1), fallen.argmax(axis=1), -1)


def cut_at_fall(traj, bound: float) -> dict:
    """The channels of ``traj`` as the stopped rollout records them, and ``steps_run``."""
    first = fall_frames(traj, bound)
    out = {}
    for name in HELD + ZEROED:
        x = getattr(traj, name)
        if x is None or (name in ("senses", "obj") and x.shape[1] == 1):
            continue
        x = x.copy()
        for e, f in enumerate(first):
            if f >= 0:
                x[e, f + 1:] = x[e, f] if name in HELD else 0.0
        out[name] = x
    out["steps_run"] = np.where(first >= 0, first * traj.record_every, traj.steps_run)
    out["diverged"] = traj.diverged & (first < 0)
    out["diverged_step"] = np.where(first >= 0, -1, traj.diverged_step)
    return out
