"""Simulator backends by name, as Brax picks its pipeline: ``planar`` and ``3d``.

A backend is a module (:mod:`gpmotion.sim.backend_planar`,
:mod:`gpmotion.sim.backend_3d`) with one interface:

* sizes: ``NAME``, ``CONTACT_WIDTH`` (friction state per
  contact point), ``COM_WIDTH`` (the com channel), ``JIT`` (the flags of the
  episode loop), ``STEP`` (observe/advance: inlined);
* kernel steps (numba, ``inline="always"``), imported by name into the one
  episode loop of :mod:`gpmotion.sim.episode` by :mod:`gpmotion.sim.kernels`
  (the generic functions below serve the loop imported as it is, JIT disabled):

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

from . import backend_3d, backend_planar

BACKENDS = {b.NAME: b for b in (backend_planar, backend_3d)}


def backend_of(model):
    """The backend module that simulates ``model`` (a Model or a Figure)."""
    model = getattr(model, "model", model)
    return BACKENDS[model.BACKEND]


# ---- generic kernel steps, for gpmotion.sim.episode imported as it is (JIT
# disabled, as the no-JIT tests run): each dispatches on the Model's backend.
# A compiled kernel imports its backend's own steps instead (gpmotion.sim.kernels).
JIT: dict = {}


def workspace(M, S, nv, contact):
    return backend_of(M).workspace(M, S, nv, contact)


def observe(M, S, goal, q, qd, w, cforce, com, t, senses, senses_norm):
    return backend_of(M).observe(M, S, goal, q, qd, w, cforce, com, t, senses, senses_norm)


def advance(M, S, q, qd, targets, taus, actuation, dt, limit, w, energy):
    return backend_of(M).advance(M, S, q, qd, targets, taus, actuation, dt, limit, w, energy)


def save_contact(work, contact):
    return _backend_of_work(work).save_contact(work, contact)


def store_object(work, row):
    return _backend_of_work(work).store_object(work, row)


def _backend_of_work(work):
    return next(b for b in BACKENDS.values() if isinstance(work, b.Work))
