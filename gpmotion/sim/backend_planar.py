"""The planar backend: figures in the x–z plane (gpmotion.sim.planar's 3-vector ABA).

A backend is a module with one interface (gpmotion.sim.backend lists it):
kernel steps the shared episode loop (gpmotion.sim.episode) calls —
``workspace``, ``observe``, ``advance``, ``save_contact`` — and the numpy
geometry of recorded frames a Trajectory asks for — ``link_poses``,
``base_pose``, ``points`` — plus its sizes and jit flags.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from ..model import REVOLUTE, SLIDE_X, SLIDE_Z
from . import geometry_fast
from .planar import (aba, centre_of_mass, ground_contacts, integrate, joint_torques, kinematics,
                     pole_contacts)
from .senses import compute_senses

NAME = "planar"
CONTACT_WIDTH = 2          # friction state per contact point: anchor x, touching (0/1)
COM_WIDTH = 4              # com channel: x, z, vx, vz
UP = 1                     # the vertical axis of a point (x, z)
# flags of the episode loop the steps are inlined into (no FMA contraction:
# it measured no gain here, and results stay those of the first kernels)
JIT = dict(cache=True, error_model="numpy", boundscheck=False)
_INLINE = dict(JIT, inline="always")
STEP = _INLINE             # observe/advance: inlined into the episode loop (kernels.py)


class Work(NamedTuple):
    """Per-episode scratch (allocated once, reused every step)."""
    pose: np.ndarray       # [nl, 3] world (θ, x, z)
    X: np.ndarray          # [nl, 4] parent→link transforms
    v: np.ndarray          # [nl, 3] link velocities
    cbias: np.ndarray      # [nl, 3]
    cs: np.ndarray         # [nl, 2] (cos θ, sin θ)
    IA: np.ndarray         # [nl, 6] packed articulated inertias
    pA: np.ndarray         # [nl, 3]
    dinv: np.ndarray       # [nl]
    acc: np.ndarray        # [nl, 3]
    qdd: np.ndarray        # [nl]
    tau: np.ndarray        # [nl]
    fext: np.ndarray       # [nl, 3]
    presc: np.ndarray      # int64[nl] prescribed (kinematic) dofs
    presc_qdd: np.ndarray  # [nl]
    arm: np.ndarray        # [nl] implicit-PD armature (joint_torques → aba)
    anchor: np.ndarray     # [nc] friction anchors, carried in and out (composites)
    touching: np.ndarray   # [nc]


@njit(**_INLINE)
def workspace(M, S, nv, contact):
    nl = nv
    return Work(np.zeros((nl, 3)), np.zeros((nl, 4)), np.zeros((nl, 3)), np.zeros((nl, 3)),
                np.zeros((nl, 2)), np.zeros((nl, 6)), np.zeros((nl, 3)), np.zeros(nl),
                np.zeros((nl, 3)), np.zeros(nl), np.zeros(nl), np.zeros((nl, 3)),
                np.zeros(nl, dtype=np.int64), np.zeros(nl), np.zeros(nl),
                contact[:, 0].copy(), contact[:, 1].copy())


@njit(**STEP)
def observe(M, S, goal, q, qd, w, cforce, com, t, senses, senses_norm):
    """Kinematics, contact forces (into w.fext), com and senses of the current state;
    returns the deepest pole penetration."""
    kinematics(M, q, qd, w.pose, w.X, w.v, w.cbias, w.cs)
    fext = w.fext
    for i in range(fext.shape[0]):
        fext[i, 0] = 0.0
        fext[i, 1] = 0.0
        fext[i, 2] = 0.0
    ground_contacts(M, S, w.pose, w.cs, w.v, w.anchor, w.touching, fext, cforce)
    pen = 0.0
    if S.poles.shape[0] > 0:       # a call, not inlined: most scenes have no poles
        pen = pole_contacts(M, S, w.pose, w.cs, w.v, fext)
    centre_of_mass(M, w.pose, w.cs, w.v, com)
    compute_senses(M, goal, q, qd, w.pose, w.cs, w.v, com, cforce, t, senses, senses_norm)
    return pen


@njit(**STEP)
def advance(M, S, q, qd, targets, taus, actuation, dt, limit, w, energy):
    """One step of dt from the observed state: (finite?, energy + actuator work)."""
    tau = w.tau
    joint_torques(M, q, qd, targets, taus, actuation, dt, tau, w.presc, w.presc_qdd, w.arm)
    aba(M, qd, w.X, w.v, w.cbias, tau, w.fext, w.presc, w.presc_qdd, w.arm, S.gravity, w.IA,
        w.pA, w.dinv, w.acc, w.qdd)
    act_dof = M.act_dof
    for a in range(act_dof.shape[0]):
        i = act_dof[a]
        energy += abs(tau[i] * qd[i]) * dt
    return integrate(q, qd, w.qdd, dt, limit), energy


@njit(**_INLINE)
def save_contact(w, contact):
    contact[:, 0] = w.anchor
    contact[:, 1] = w.touching


@njit(**_INLINE)
def store_object(w, row):
    """No free objects in the plane (rollout refuses a scene with one)."""


# ---- recorded frames (numpy) ----------------------------------------------
def goal(scene) -> np.ndarray:
    """The goal point the senses refer to: (x, z)."""
    return scene.goal


def link_poses(model, q):
    """[..., nl, 3] world (θ, x, z) of every link (compiled; ``geometry.link_poses``
    is the numpy form)."""
    return geometry_fast.link_poses(model, q)


def base_pose(model, q, poses):
    """[..., 3] (pitch, x, z) of the root body.

    ``poses()`` gives link_poses(model, q) (the caller memoizes it).
    """
    if model.base_link < 0:
        return np.broadcast_to(model.fixed_pose, np.shape(q)[:-1] + (3,)).copy()
    return poses()[..., model.base_link, :]


def points(model, q, poses, links, local):
    """World (x, z) [..., n, 2] of link-frame points ``local`` on ``links`` (−1: fixed root)."""
    return geometry_fast.points_world(model, poses(), links, local)



def world_frames(model, q):
    """World rotation [..., nl + 1, 3, 3] and origin [..., nl + 1, 3] of every link,
    the fixed root body last (index −1): the plane lifted to (x, 0, z), an angle
    θ a rotation about −y (a planar figure seen as a 3-D one, as the BVH export needs)."""
    poses = link_poses(model, q)
    poses = np.concatenate([poses, np.broadcast_to(model.fixed_pose, poses.shape[:-2] + (1, 3))], axis=-2)
    c, s = np.cos(poses[..., 0]), np.sin(poses[..., 0])
    z, o = np.zeros_like(c), np.ones_like(c)
    R = np.stack([np.stack([c, z, -s], -1), np.stack([z, o, z], -1), np.stack([s, z, c], -1)], -2)
    return R, np.stack([poses[..., 1], z, poses[..., 2]], -1)


def reference_q(model):
    """Every joint coordinate zero."""
    return np.zeros(model.nq)


def slides(model, link) -> bool:
    """Does ``link``'s joint translate the body it carries?  Between bodies never:
    the only planar slides are a planar root's x and z (the figure's position)."""
    return False


def height_coordinate(model):
    """The q index of the figure's height (its root z slide), or None when it has none."""
    zs = np.flatnonzero(model.jtype == SLIDE_Z)
    return int(zs[0]) if zs.size else None


def perturb(model, q, qd, rng, s) -> None:
    """Perturb K states q [K, nq], qd [K, nv] in place by normal steps of the sizes ``s``
    (root slides: position/velocity; root pitch: orientation/angular; joints: joint/angular)."""
    m = model
    k, n = q.shape
    z = rng.standard_normal((2, k, n))                         # drawn whole: same stream for any sizes
    slide = (m.jtype == SLIDE_X) | (m.jtype == SLIDE_Z)
    root_pitch = (m.jtype == REVOLUTE) & np.isin(m.parent, np.flatnonzero(slide))
    joint = (m.jtype == REVOLUTE) & ~root_pitch
    q += z[0] * np.where(slide, s.position, np.where(root_pitch, s.orientation, s.joint))
    qd += z[1] * np.where(slide, s.velocity, s.angular)
    q[:, joint] = np.clip(q[:, joint], m.lo[joint], m.hi[joint])
