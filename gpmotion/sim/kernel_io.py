"""The named structures a rollout kernel is called with: settings, start, program, outputs.

Every array is batched over episodes (leading axis E); the episode loop
(:mod:`gpmotion.sim.episode`) reads and writes row ``e``.  NamedTuples of
arrays compile in numba as plain structs: fields by name, no Python objects.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np


class Settings(NamedTuple):
    """Scalars shared by every episode of a rollout."""
    dt: float                  # step (s)
    every: int                 # record a frame every ``every`` steps
    actuation: int             # model.PD / model.KINEMATIC
    default_tau: float         # τ a controller's taus are pre-filled with
    limit: float               # |q| or |q̇| beyond this ends an episode as diverged
    record_senses: bool
    stop_dof: int              # −1 (never), or: a recorded frame with |q[stop_dof] + stop_off|
    stop_off: float            # > stop_abs ends the episode (a task's fall: the base pitch
    stop_abs: float            # beyond a bound, gpmotion.task.Task.fall_stop)


class Start(NamedTuple):
    """Where each episode starts and how long it runs."""
    n_steps: np.ndarray        # int64[E]
    q0: np.ndarray             # float64[E, nq]
    qd0: np.ndarray            # float64[E, nv]
    contact: np.ndarray        # float64[E, nc, backend.CONTACT_WIDTH] friction-anchor state;
                               # the kernel overwrites it with the state at the end


class Program(NamedTuple):
    """The controller's arrays (gpmotion.controllers.ControllerBatch)."""
    ci: np.ndarray             # int64[E, Li]
    cf: np.ndarray             # float64[E, Lf]
    cstate: np.ndarray         # float64[E, max(1, cstate_size)] scratch the controller owns


class Outputs(NamedTuple):
    """Recorded channels (Trajectory's fields) plus the status: divergence and steps simulated."""
    q: np.ndarray              # [E, F, nq]
    qd: np.ndarray             # [E, F, nv]
    com: np.ndarray            # [E, F, backend.COM_WIDTH]
    contact_force: np.ndarray  # [E, F, nc]
    pole_hit: np.ndarray       # [E, F]
    impact: np.ndarray         # [E, F]
    energy: np.ndarray         # [E, F]
    targets: np.ndarray        # [E, F, n_act]
    senses: np.ndarray         # [E, F or 1, n_senses]
    status: np.ndarray         # int64[E, 3]: diverged (0/1), step of divergence or −1, steps simulated
    obj: np.ndarray            # [E, F or 1, grip3d.OB_REC] the scene's object (x, y, z, v, gripped)

    @staticmethod
    def zeros(E: int, F: int, nq: int, nv: int, com: int, nc: int, na: int, ns: int,
              record_senses: bool, record_obj: bool = False) -> "Outputs":
        from .grip3d import OB_REC
        return Outputs(np.zeros((E, F, nq)), np.zeros((E, F, nv)), np.zeros((E, F, com)),
                       np.zeros((E, F, nc)), np.zeros((E, F)), np.zeros((E, F)), np.zeros((E, F)),
                       np.zeros((E, F, na)), np.zeros((E, F if record_senses else 1, ns)),
                       np.zeros((E, 3), dtype=np.int64),
                       np.zeros((E, F if record_obj else 1, OB_REC)))
