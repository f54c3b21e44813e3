"""Forward kinematics in numpy for 3-D figures over recorded frames.

Shapes: ``q[..., nq]`` → link rotations ``[..., nl, 3, 3]`` (columns = link
axes in world) and origins ``[..., nl, 3]``; ``link_poses`` packs them as
4×4 homogeneous transforms.  Link −1 is the fixed root body.
"""
from __future__ import annotations

import numba as nb
import numpy as np

from ..model import FREE3D, HINGE3D
from .rotations import axis_angle, quat_to_rot, rot_to_quat  # noqa: F401 (quat_to_rot: re-exported)
from .spatial3d import fixed_point_world, kinematics, point_world
from .threads import run_chunks


def link_frames(model, q: np.ndarray):
    """World rotation [..., nl, 3, 3] and origin [..., nl, 3] of every link."""
    q = np.asarray(q, dtype=np.float64)
    lead = q.shape[:-1]
    nl = len(model.parent)
    R = np.zeros(lead + (nl, 3, 3))
    P = np.zeros(lead + (nl, 3))
    for i in range(nl):
        qa, p, jt = int(model.qadr[i]), int(model.parent[i]), int(model.jtype[i])
        if jt == FREE3D:
            R[..., i, :, :] = quat_to_rot(q[..., qa + 3:qa + 7])
            P[..., i, :] = q[..., qa:qa + 3]
            continue
        ax = model.axis[i]
        if jt == HINGE3D:
            Rrel = model.xrot[i] @ axis_angle(ax, q[..., qa])
            rrel = np.broadcast_to(model.xpos[i], lead + (3,))
        else:
            Rrel = np.broadcast_to(model.xrot[i], lead + (3, 3))
            rrel = model.xpos[i] + q[..., qa, None] * (model.xrot[i] @ ax)
        if p >= 0:
            R[..., i, :, :] = R[..., p, :, :] @ Rrel
            P[..., i, :] = P[..., p, :] + np.einsum("...ab,...b->...a", R[..., p, :, :], rrel)
        else:
            R[..., i, :, :] = Rrel
            P[..., i, :] = rrel
    return R, P


def points_fast(model, q: np.ndarray, links, local) -> np.ndarray:
    """World (x, y, z) [..., n, 3] of link-frame points ``local[n, 3]`` on
    ``links[n]`` (−1: the fixed root body) for configurations ``q[..., nq]``.

    Compiled (numba, frames split over threads) because the scores of a 3-D task
    ask for every recorded frame of every episode, and the numpy loop over
    links cost more than the rollout itself; it runs the simulator's own
    ``kinematics`` pass and stores only the points, not every link frame.
    ``points_world(model, *link_frames(model, q), ...)`` is its plain-numpy
    twin (tests compare them)."""
    q = np.asarray(q, dtype=np.float64)
    flat = np.array(q.reshape(-1, q.shape[-1]))            # a copy: quaternions are normalized
    for qa in model.qadr[model.jtype == FREE3D]:           # (as quat_to_rot does; kinematics
        quat = flat[:, qa + 3:qa + 7]                      # assumes unit quaternions)
        quat /= np.linalg.norm(quat, axis=1, keepdims=True)
    links = np.ascontiguousarray(links, dtype=np.int64)
    local = np.ascontiguousarray(np.asarray(local, dtype=np.float64).reshape(-1, 3))
    out = np.empty((flat.shape[0], len(links), 3))
    run_chunks(_points_kernel, (model, flat, links, local, out), flat.shape[0])
    return out.reshape(q.shape[:-1] + (len(links), 3))


@nb.njit(cache=True, nogil=True)
def _points_kernel(M, q, links, local, out, lo, hi):
    nl, nv = M.parent.shape[0], M.lo.shape[0]
    R, pos, E = np.empty((nl, 3, 3)), np.empty((nl, 3)), np.empty((nl, 3, 3))
    r, v, cbias = np.empty((nl, 3)), np.empty((nl, 6)), np.empty((nl, 6))
    qd = np.zeros(nv)
    for s in range(lo, hi):          # scratch reused across frames, as the rollout reuses it across steps
        kinematics(M, q[s], qd, R, pos, E, r, v, cbias)
        for k in range(links.shape[0]):
            px, py, pz = local[k, 0], local[k, 1], local[k, 2]
            if links[k] >= 0:
                out[s, k, 0], out[s, k, 1], out[s, k, 2] = point_world(R, pos, links[k], px, py, pz)
            else:
                out[s, k, 0], out[s, k, 1], out[s, k, 2] = fixed_point_world(
                    M.fixed_rot, M.fixed_pos, px, py, pz)


def link_poses(model, q: np.ndarray) -> np.ndarray:
    """World transforms [..., nl, 4, 4] of every link."""
    R, P = link_frames(model, q)
    T = np.zeros(R.shape[:-2] + (4, 4))
    T[..., :3, :3] = R
    T[..., :3, 3] = P
    T[..., 3, 3] = 1.0
    return T


def points_world(model, R, P, links, local) -> np.ndarray:
    """World (x, y, z) [..., n, 3] of link-frame points ``local[n, 3]`` on ``links[n]``."""
    links = np.asarray(links, dtype=np.int64)
    local = np.asarray(local, dtype=np.float64).reshape(-1, 3)
    lead = R.shape[:-3]
    Rf = np.broadcast_to(model.fixed_rot, lead + (1, 3, 3))
    Pf = np.broadcast_to(model.fixed_pos, lead + (1, 3))
    Re = np.concatenate([R, Rf], axis=-3)   # index −1 → the fixed root body
    Pe = np.concatenate([P, Pf], axis=-2)
    return Pe[..., links, :] + np.einsum("...nab,nb->...na", Re[..., links, :, :], local)


def sites_world(figure, q) -> np.ndarray:
    R, P = link_frames(figure.model, q)
    return points_world(figure.model, R, P, figure.site_link, figure.site_pos)


def segments_world(model, q: np.ndarray) -> np.ndarray:
    """Capsule end points [..., n_seg, 2 (a/b), 3 (x/y/z)] for drawing and checks."""
    R, P = link_frames(model, q)
    a = points_world(model, R, P, model.seg_link, model.seg_a)
    b = points_world(model, R, P, model.seg_link, model.seg_b)
    return np.stack([a, b], axis=-2)


def base_pose(model, q: np.ndarray) -> np.ndarray:
    """Base (root body) pose [..., 7] = (x, y, z, qw, qx, qy, qz)."""
    q = np.asarray(q, dtype=np.float64)
    b = model.base_link
    if b < 0:
        pose = np.concatenate([model.fixed_pos, rot_to_quat(model.fixed_rot)])
        return np.broadcast_to(pose, q.shape[:-1] + (7,)).copy()
    if model.jtype[b] == FREE3D:
        qa = int(model.qadr[b])
        return q[..., qa:qa + 7].copy()
    R, P = link_frames(model, q)
    Rb = R[..., b, :, :].reshape(-1, 3, 3)
    quats = np.array([rot_to_quat(r) for r in Rb]).reshape(q.shape[:-1] + (4,))
    return np.concatenate([P[..., b, :], quats], axis=-1)

