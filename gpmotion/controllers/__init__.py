"""Controller families: how a controller becomes arrays the rollout kernel runs.

Contract (every family, GP and BSR alike)
-----------------------------------------
A family provides a *kernel module*: a Python source file with two njit
functions, imported by the generated rollout kernel (gpmotion.sim.rollout):

    init(ci, cf, cstate)                       # once per episode
    control(ci, cf, senses, senses_norm, t, cstate, targets, taus)   # every step

* ``ci``  int64[:]    this episode's integer program (opcodes, rule counts, ...)
* ``cf``  float64[:]  this episode's float program (constants, rule tables, ...)
* ``cstate`` float64[:] per-episode scratch the family owns (active rule, stack...)
* ``senses`` float64[:] raw senses (names: Figure.sense_names)
* ``senses_norm`` float64[:] the same, mapped to [0, 1] (BSR's Table 1 view)
* ``t`` float, seconds since the episode started
* ``targets`` float64[n_act] out: desired joint angles (clamped later to limits);
  pre-filled every step with the figure's neutral pose, so a family that
  controls only some actuators leaves the others holding neutral
* ``taus``   float64[n_act] out: time constants for ``kinematic`` actuation
  (pre-filled with the rollout's default τ; a family may overwrite them)

Decorate a kernel module's functions with every numba option set
(``@njit(**KERNEL_JIT)``, below): see the comment there.

Batches are rectangular: ``ci[n_episodes, Li]``, ``cf[n_episodes, Lf]``
(zero-padded), plus ``cstate_size``.  Python-side, a family's ``encode``
turns plain-data genomes into a :class:`ControllerBatch`.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np


# numba options of a kernel module's functions, all set: an option left unset is
# inherited from the first kernel that compiles the function (numba's target-option
# inheritance), and the on-disk cache keeps that one version, so a module shared by
# the planar loop and the 3-D loop (which contracts multiply-adds) gave results
# that hung in their last bits on which loop ran first on a machine.  These are
# the planar loop's; a module only the 3-D loop calls may take ``KERNEL_JIT_3D``.
# numba's cache of a module that imports them is keyed by that module's file only:
# after editing them, clear the __pycache__ of gpmotion/bsr and gpmotion/controllers.
KERNEL_JIT = dict(cache=True, fastmath=False, error_model="numpy", boundscheck=False)
KERNEL_JIT_3D = dict(cache=True, fastmath={"contract"}, error_model="numpy", boundscheck=False)


class ControllerBatch(NamedTuple):
    """Arrays for one batched rollout; ``module`` is the kernel module file."""
    module: str            # absolute path of the kernel module source file
    ci: np.ndarray         # int64[n_episodes, Li]
    cf: np.ndarray         # float64[n_episodes, Lf]
    cstate_size: int

    @property
    def n_episodes(self) -> int:
        return self.ci.shape[0]
