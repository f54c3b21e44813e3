"""The 3-D backend: free-floating and fixed figures in space (gpmotion.sim.spatial3d).

Same interface as :mod:`gpmotion.sim.backend_planar` (see there).  The goal
the senses refer to is the scene's 3-D goal (x, y, z).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from ..model import FREE3D, HINGE3D, SLIDE3D
from . import geometry3d
from .grip3d import N_OB, OB_REC, object_start, object_step
from .selfcontact3d import self_contacts
from .spatial3d import (N_IA, N_IB, aba_packed, body_inertias, centre_of_mass, compute_senses3d,
                        ground_contacts, integrate, joint_torques, kinematics, pole_contacts)

NAME = "3d"
CONTACT_WIDTH = 3          # friction state per contact point: anchor x, y, touching (0/1)
COM_WIDTH = 6              # com channel: x, y, z, vx, vy, vz
UP = 2                     # the vertical axis of a point (x, y, z)
# flags of the episode loop the steps are inlined into: FMA contraction only
# (no other fast-math: the NaN checks stay), ~10 % on the humanoid
JIT = dict(cache=True, error_model="numpy", boundscheck=False, fastmath={"contract"})
_INLINE = dict(cache=True, error_model="numpy", boundscheck=False, inline="always")
STEP = _INLINE             # observe/advance: inlined into the episode loop (kernels.py)


class Work(NamedTuple):
    """Per-episode scratch (allocated once, reused every step)."""
    R: np.ndarray          # [nl, 3, 3] link orientations (world)
    pos: np.ndarray        # [nl, 3] link origins (world)
    E: np.ndarray          # [nl, 3, 3] parent→link rotations
    r: np.ndarray          # [nl, 3] link origins in the parent
    v: np.ndarray          # [nl, 6] link velocities
    cbias: np.ndarray      # [nl, 6]
    Ib: np.ndarray         # [nl, N_IB] packed body inertias (constant)
    IA: np.ndarray         # [nl, N_IA] packed articulated inertias
    pA: np.ndarray         # [nl, 6]
    U: np.ndarray          # [nl, 6]
    Ut: np.ndarray         # [nl, 6]
    dinv: np.ndarray       # [nl]
    uu: np.ndarray         # [nl]
    acc: np.ndarray        # [nl, 6]
    L6: np.ndarray         # [6, 6] free-root solve
    b6: np.ndarray         # [6]
    x6: np.ndarray         # [6]
    qdd: np.ndarray        # [nv]
    tau: np.ndarray        # [nv]
    fext: np.ndarray       # [nl, 6]
    presc: np.ndarray      # int64[nv]
    presc_qdd: np.ndarray  # [nv]
    arm: np.ndarray        # [nv] implicit-PD armature (joint_torques → aba_packed)
    anchor: np.ndarray     # [nc, 2] friction anchors, carried in and out (composites)
    touching: np.ndarray   # [nc]
    ob: np.ndarray         # [grip3d.N_OB] the scene's object: centre, velocity, grip


@njit(**_INLINE)
def workspace(M, S, nv, contact):
    nl = M.parent.shape[0]
    Ib = np.zeros((nl, N_IB))
    body_inertias(M, Ib)           # constant: once per episode
    w = Work(np.zeros((nl, 3, 3)), np.zeros((nl, 3)), np.zeros((nl, 3, 3)), np.zeros((nl, 3)),
             np.zeros((nl, 6)), np.zeros((nl, 6)), Ib, np.zeros((nl, N_IA)), np.zeros((nl, 6)),
             np.zeros((nl, 6)), np.zeros((nl, 6)), np.zeros(nl), np.zeros(nl), np.zeros((nl, 6)),
             np.zeros((6, 6)), np.zeros(6), np.zeros(6), np.zeros(nv), np.zeros(nv),
             np.zeros((nl, 6)), np.zeros(nv, dtype=np.int64), np.zeros(nv), np.zeros(nv),
             contact[:, 0:2].copy(), contact[:, 2].copy(), np.zeros(N_OB))
    object_start(S.obj, w.ob)
    return w


@njit(**STEP)
def observe(M, S, goal, q, qd, w, cforce, com, t, senses, senses_norm):
    """Kinematics, contact forces (into w.fext), com and senses of the current state;
    returns the deepest pole penetration."""
    kinematics(M, q, qd, w.R, w.pos, w.E, w.r, w.v, w.cbias)
    fext = w.fext
    for i in range(fext.shape[0]):
        for k in range(6):
            fext[i, k] = 0.0
    ground_contacts(M, S, w.R, w.pos, w.v, w.anchor, w.touching, fext, cforce)
    pen = 0.0
    if S.poles.shape[0] > 0:       # a call, not inlined: most scenes have no poles
        pen = pole_contacts(M, S, w.R, w.pos, w.v, fext)
    if S.selfc.shape[0] > 0:       # the pairs of bodies the task lets collide
        self_contacts(M, S.selfc, w.R, w.pos, w.v, fext)
    centre_of_mass(M, w.R, w.pos, w.v, com)
    compute_senses3d(M, goal, q, qd, w.R, w.pos, w.v, com, cforce, t, senses, senses_norm)
    return pen


@njit(**STEP)
def advance(M, S, q, qd, targets, taus, actuation, dt, limit, w, energy):
    """One step of dt from the observed state: (finite?, energy + actuator work)."""
    tau = w.tau
    joint_torques(M, q, qd, targets, taus, actuation, dt, tau, w.presc, w.presc_qdd, w.arm)
    if S.obj.shape[0] > 0:         # the object moves; a grip's reaction joins w.fext
        object_step(S.obj, S.gravity, S.ground, S.ground_z, w.R, w.pos, w.v, w.fext, w.ob, dt)
    aba_packed(M, qd, w.E, w.r, w.v, w.cbias, tau, w.fext, w.presc, w.presc_qdd, w.arm, S.gravity,
               w.Ib, w.IA, w.pA, w.U, w.Ut, w.dinv, w.uu, w.acc, w.qdd, w.L6, w.b6, w.x6)
    act_dof = M.act_dof
    for a in range(act_dof.shape[0]):
        d = act_dof[a]
        energy += abs(tau[d] * qd[d]) * dt
    return integrate(M, q, qd, w.qdd, dt, limit), energy


@njit(**_INLINE)
def save_contact(w, contact):
    contact[:, 0:2] = w.anchor
    contact[:, 2] = w.touching


@njit(**_INLINE)
def store_object(w, row):
    for k in range(OB_REC):
        row[k] = w.ob[k]


# ---- recorded frames (numpy) ----------------------------------------------
def goal(scene) -> np.ndarray:
    """The goal point the senses refer to: (x, y, z)."""
    return scene.goal3


def link_poses(model, q):
    """[..., nl, 4, 4] world transforms of every link."""
    return geometry3d.link_poses(model, q)


def base_pose(model, q, poses):
    """[..., 7] (x, y, z, qw, qx, qy, qz) of the root body (``poses`` not needed)."""
    return geometry3d.base_pose(model, q)


def points(model, q, poses, links, local):
    """World (x, y, z) [..., n, 3] of link-frame points ``local`` on ``links`` (−1: fixed root)."""
    return geometry3d.points_fast(model, q, links, local)



def world_frames(model, q):
    """World rotation [..., nl + 1, 3, 3] and origin [..., nl + 1, 3] of every link,
    the fixed root body last (index −1)."""
    R, P = geometry3d.link_frames(model, q)
    lead = R.shape[:-3]
    R = np.concatenate([R, np.broadcast_to(model.fixed_rot, lead + (1, 3, 3))], axis=-3)
    P = np.concatenate([P, np.broadcast_to(model.fixed_pos, lead + (1, 3))], axis=-2)
    return R, P


def reference_q(model):
    """Every joint coordinate zero; a free root at the origin, unrotated."""
    q = np.zeros(model.nq)
    q[model.qadr[model.jtype == FREE3D] + 3] = 1.0
    return q


def slides(model, link) -> bool:
    """Does ``link``'s joint translate the body it carries?"""
    return int(model.jtype[link]) == SLIDE3D


def height_coordinate(model):
    """The q index of the figure's height (a free root's z), or None when it has none."""
    free = np.flatnonzero(model.jtype == FREE3D)
    return int(model.qadr[0] + 2) if free.size and free[0] == 0 else None


def perturb(model, q, qd, rng, s) -> None:
    """Perturb K states q [K, nq], qd [K, nv] in place by normal steps of the sizes ``s``
    (a free root: position, orientation, velocity, angular; hinges: joint/angular;
    slides: position/velocity)."""
    m = model
    k = q.shape[0]
    zq, zv = rng.standard_normal((k, m.nq)), rng.standard_normal((k, m.nv))
    for link in range(len(m.parent)):
        a, d = m.qadr[link], m.dadr[link]
        if m.jtype[link] == FREE3D:
            q[:, a:a + 3] += s.position * zq[:, a:a + 3]
            q[:, a + 3:a + 7] = _rotate(q[:, a + 3:a + 7], s.orientation * zq[:, a + 3:a + 6])
            qd[:, d:d + 3] += s.angular * zv[:, d:d + 3]       # q̇ = (ω_body, v_body)
            qd[:, d + 3:d + 6] += s.velocity * zv[:, d + 3:d + 6]
        else:
            size = s.joint if m.jtype[link] == HINGE3D else s.position
            q[:, a] = np.clip(q[:, a] + size * zq[:, a], m.lo[d], m.hi[d])
            qd[:, d] += (s.angular if m.jtype[link] == HINGE3D else s.velocity) * zv[:, d]


def _rotate(quat, rotvec):
    """quat ⊗ exp(rotvec / 2): a body-frame rotation by |rotvec| rad, renormalized."""
    angle = np.linalg.norm(rotvec, axis=1, keepdims=True)
    axis = np.where(angle > 0, rotvec / np.where(angle > 0, angle, 1.0), 0.0)
    w2, v2 = np.cos(angle / 2), axis * np.sin(angle / 2)
    w1, v1 = quat[:, :1], quat[:, 1:]
    w = w1 * w2 - np.sum(v1 * v2, axis=1, keepdims=True)
    v = w1 * v2 + w2 * v1 + np.cross(v1, v2)
    out = np.concatenate([w, v], axis=1)
    return out / np.linalg.norm(out, axis=1, keepdims=True)
