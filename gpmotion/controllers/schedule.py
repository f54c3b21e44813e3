"""The `schedule` controller family: keyframed or sinusoidal targets (open loop)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from . import ControllerBatch

KERNEL = str((Path(__file__).parent / "schedule_kernel.py").resolve())


def keyframes(times, targets, taus=None, n_act=None) -> ControllerBatch:
    """One episode whose targets interpolate keyframes ``targets[K, n_act]`` at ``times[K]``."""
    targets = np.atleast_2d(np.asarray(targets, dtype=np.float64))
    times = np.asarray(times, dtype=np.float64).reshape(-1)
    if targets.shape[0] != times.shape[0]:
        raise ValueError("keyframes: one row of targets per time")
    if np.any(np.diff(times) <= 0):
        raise ValueError("keyframes: times must increase")
    na = targets.shape[1] if n_act is None else n_act
    taus = np.full(na, 0.05) if taus is None else np.broadcast_to(np.asarray(taus, float), (na,))
    cf = np.concatenate([times, targets.reshape(-1), taus])[None, :]
    return ControllerBatch(KERNEL, np.array([[0, len(times)]], dtype=np.int64), cf, 0)


def constant(targets, taus=None) -> ControllerBatch:
    targets = np.asarray(targets, dtype=np.float64).reshape(1, -1)
    return keyframes([0.0], targets, taus)


def sines(offset, amplitude, omega, phase, taus=0.05) -> ControllerBatch:
    """A batch of sinusoidal controllers; each argument is [n_episodes, n_act] (broadcast)."""
    arrs = np.broadcast_arrays(*(np.atleast_2d(np.asarray(x, dtype=np.float64))
                                 for x in (offset, amplitude, omega, phase, taus)))
    cf = np.concatenate(arrs, axis=1)
    ci = np.tile(np.array([[1, 0]], dtype=np.int64), (cf.shape[0], 1))
    return ControllerBatch(KERNEL, ci, np.ascontiguousarray(cf), 0)


def stack(batches) -> ControllerBatch:
    """Concatenate batches of the same module into one (rows zero-padded)."""
    mods = {b.module for b in batches}
    if len(mods) != 1:
        raise ValueError("stack: batches use different kernel modules")
    li = max(b.ci.shape[1] for b in batches)
    lf = max(b.cf.shape[1] for b in batches)
    ci = np.concatenate([np.pad(b.ci, ((0, 0), (0, li - b.ci.shape[1]))) for b in batches])
    cf = np.concatenate([np.pad(b.cf, ((0, 0), (0, lf - b.cf.shape[1]))) for b in batches])
    return ControllerBatch(mods.pop(), ci, cf, max(b.cstate_size for b in batches))
