"""Simulator backends by name, as Brax picks its pipeline: ``planar`` and ``3d``.

A backend is a module (:mod:`gpmotion.sim.backend_planar`,
:mod:`gpmotion.sim.backend_3d`) with one interface:

* sizes: ``NAME``, ``CONTACT_WIDTH`` (friction state per
  contact point), ``COM_WIDTH`` (the com channel), ``JIT`` (the flags of the
  episode loop), ``STEP`` (those of observe/advance);
* kernel steps (numba), called by the one episode loop of
  :mod:`gpmotion.sim.episode` through the generic functions below;
  ``observe`` and ``advance`` (the physics) are compiled once per backend
  with the ``STEP`` flags and cached on disk, so a new controller's kernel
  compiles its loop, not the physics again (inlined into every loop, the
  herman kernel compiled for > 17 min cold where it now takes 6.4 min, at
  load 9 on 2 cores); ``workspace`` and ``save_contact`` are inlined:

  - ``workspace(M, nv, contact) -> Work``: per-episode scratch (a NamedTuple),
    friction anchors taken from ``contact``;
  - ``observe(M, S, goal, q, qd, work, cforce, com, t, senses, senses_norm)
    -> deepest pole penetration``: kinematics, contact forces, com, senses;
  - ``advance(M, S, q, qd, targets, taus, actuation, dt, limit, work,
    energy) -> (finite?, energy)``: torques, dynamics, one integration step;
  - ``save_contact(work, contact)``: the friction state at the end;
* recorded frames (numpy): ``goal(scene)``, ``link_poses(model, q)``,
  ``base_pose(model, q, poses)``, ``points(model, q, poses, links, local)``,
  ``world_frames(model, q)`` (3-D rotations and origins; planar lifted),
  ``reference_q(model)``, ``slides(model, link)``.

A compiled model names its backend (``Model.BACKEND``, a class constant, as
is ``DIMENSIONS``); the harness asks
:func:`backend_of`, never the model's type.  Adding a backend: write the
module, add it to ``BACKENDS``, give its Model class ``BACKEND = name``.
"""
from __future__ import annotations

from numba.extending import overload

from . import backend_3d, backend_planar

BACKENDS = {b.NAME: b for b in (backend_planar, backend_3d)}


def backend_of(model):
    """The backend module that simulates ``model`` (a Model or a Figure)."""
    model = getattr(model, "model", model)
    return BACKENDS[model.BACKEND]


def _kernels(M):
    """The backend of a Model's numba type (a NamedTuple type of its class)."""
    return BACKENDS[M.instance_class.BACKEND]


# ---- generic kernel steps: each resolves to the Model's backend at compile time
def workspace(M, nv, contact):
    raise NotImplementedError("numba only")


def observe(M, S, goal, q, qd, work, cforce, com, t, senses, senses_norm):
    raise NotImplementedError("numba only")


def advance(M, S, q, qd, targets, taus, actuation, dt, limit, work, energy):
    raise NotImplementedError("numba only")


def save_contact(M, work, contact):
    raise NotImplementedError("numba only")


@overload(workspace, inline="always")
def _workspace(M, nv, contact):
    f = _kernels(M).workspace
    return lambda M, nv, contact: f(M, nv, contact)


@overload(observe, inline="always")
def _observe(M, S, goal, q, qd, work, cforce, com, t, senses, senses_norm):
    f = _kernels(M).observe
    return lambda M, S, goal, q, qd, work, cforce, com, t, senses, senses_norm: f(
        M, S, goal, q, qd, work, cforce, com, t, senses, senses_norm)


@overload(advance, inline="always")
def _advance(M, S, q, qd, targets, taus, actuation, dt, limit, work, energy):
    f = _kernels(M).advance
    return lambda M, S, q, qd, targets, taus, actuation, dt, limit, work, energy: f(
        M, S, q, qd, targets, taus, actuation, dt, limit, work, energy)


@overload(save_contact, inline="always")
def _save_contact(M, work, contact):
    f = _kernels(M).save_contact
    return lambda M, work, contact: f(work, contact)
