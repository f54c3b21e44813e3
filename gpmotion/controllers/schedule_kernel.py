"""Kernel module of the `schedule` family: open-loop targets over time.
(Rollouts import it under its package name: gpmotion.cache.import_file.)

Used by ``gpmotion.simulate``, the benchmark and tests.  ``ci = [mode, n_keys]``:

* mode 0 — keyframes, linearly interpolated and held after the last key:
  ``cf = [t_0..t_{K-1}, targets (K × n_act, row-major), taus (n_act)]``
* mode 1 — sines per actuator: ``cf = [offset, amplitude, omega, phase, taus]``
  (each n_act long): target = offset + amplitude·sin(omega·t + phase)
"""
import numpy as np
from numba import njit

from gpmotion.controllers import KERNEL_JIT


@njit(**KERNEL_JIT)
def init(ci, cf, cstate):
    pass


@njit(**KERNEL_JIT)
def control(ci, cf, senses, senses_norm, t, cstate, targets, taus):
    na = targets.shape[0]
    if ci[0] == 1:
        for a in range(na):
            targets[a] = cf[a] + cf[na + a] * np.sin(cf[2 * na + a] * t + cf[3 * na + a])
            taus[a] = cf[4 * na + a]
        return
    nk = ci[1]
    k = 0
    while k + 1 < nk and cf[k + 1] <= t:
        k += 1
    base = nk
    if k + 1 < nk and t > cf[k]:
        w = (t - cf[k]) / (cf[k + 1] - cf[k])
        for a in range(na):
            targets[a] = (1 - w) * cf[base + k * na + a] + w * cf[base + (k + 1) * na + a]
    else:
        for a in range(na):
            targets[a] = cf[base + k * na + a]
    for a in range(na):
        taus[a] = cf[base + nk * na + a]
