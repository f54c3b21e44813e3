"""Simulator backends by name, as Brax picks its pipeline: ``planar`` and ``3d``.

A backend is a module (:mod:`gpmotion.sim.backend_planar`,
:mod:`gpmotion.sim.backend_3d`) with one interface:

* sizes: ``NAME``, ``CONTACT_WIDTH`` (friction state per
  contact point), ``COM_WIDTH`` (the com channel), ``JIT`` (the flags of the
  episode loop), ``STEP`` (observe/advance: inlined);
* kernel steps (numba), called by the one episode loop of
  :mod:`gpmotion.sim.episode` through the generic functions below;
  every step is inlined into the loop (``observe``/``advance`` as their
  own Python function's IR: see the note above ``_observe``):

  - ``workspace(M, S, nv, contact) -> Work``: per-episode scratch (a NamedTuple),
    friction anchors taken from ``contact``, the scene's object (if any) at its start;
  - ``observe(M, S, goal, q, qd, work, cforce, com, t, senses, senses_norm)
    -> deepest pole penetration``: kinematics, contact forces, com, senses;
  - ``advance(M, S, q, qd, targets, taus, actuation, dt, limit, work,
    energy) -> (finite?, energy)``: torques, dynamics, one integration step;
  - ``save_contact(work, contact)``: the friction state at the end;
  - ``store_object(work, row)``: the scene's object into a recorded frame
    (3-D only: gpmotion.sim.grip3d);
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
# (numba) or at the call (JIT disabled, as the no-JIT tests run)
def workspace(M, S, nv, contact):
    return backend_of(M).workspace(M, S, nv, contact)


def observe(M, S, goal, q, qd, w, cforce, com, t, senses, senses_norm):
    return backend_of(M).observe(M, S, goal, q, qd, w, cforce, com, t, senses, senses_norm)


def advance(M, S, q, qd, targets, taus, actuation, dt, limit, w, energy):
    return backend_of(M).advance(M, S, q, qd, targets, taus, actuation, dt, limit, w, energy)


def save_contact(M, work, contact):
    return backend_of(M).save_contact(work, contact)


def store_object(M, work, row):
    return backend_of(M).store_object(work, row)


@overload(workspace, inline="always")
def _workspace(M, S, nv, contact):
    f = _kernels(M).workspace
    return lambda M, S, nv, contact: f(M, S, nv, contact)


# observe/advance: the backend's own Python function, its IR inlined into the loop
# as a direct call would be.  Through a jitted wrapper (a lambda calling the
# dispatcher) numba deep-copies the whole physics IR once more per level: the
# herman kernel then compiled for > 17 min; as separate calls (not inlined) the
# loop passed ~60 arrays per call and the lamp ran 3.5x slower.
@overload(observe, inline="always")
def _observe(M, S, goal, q, qd, w, cforce, com, t, senses, senses_norm):
    return _kernels(M).observe.py_func


@overload(advance, inline="always")
def _advance(M, S, q, qd, targets, taus, actuation, dt, limit, w, energy):
    return _kernels(M).advance.py_func


@overload(save_contact, inline="always")
def _save_contact(M, work, contact):
    f = _kernels(M).save_contact
    return lambda M, work, contact: f(work, contact)


@overload(store_object, inline="always")
def _store_object(M, work, row):
    f = _kernels(M).store_object
    return lambda M, work, row: f(work, row)
