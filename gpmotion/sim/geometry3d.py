"""Forward kinematics in numpy for 3-D figures over recorded frames.

Shapes: ``q[..., nq]`` → link rotations ``[..., nl, 3, 3]`` (columns = link
axes in world) and origins ``[..., nl, 3]``; ``link_poses`` packs them as
4×4 homogeneous transforms.  Link −1 is the fixed root body.
"""
from __future__ import annotations

import numba as nb
import numpy as np

from ..model import FREE3D, HINGE3D


def quat_to_rot(qv: np.ndarray) -> np.ndarray:
    """Rotation matrices [..., 3, 3] of quaternions (w, x, y, z) [..., 4] (normalized here)."""
    qv = np.asarray(qv, dtype=np.float64)
    qv = qv / np.linalg.norm(qv, axis=-1, keepdims=True)
    w, x, y, z = np.moveaxis(qv, -1, 0)
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1)], -2)


def axis_angle(axis, angle: np.ndarray) -> np.ndarray:
    """Rotation matrices [..., 3, 3] about a unit axis by angles [...] (Rodrigues)."""
    a = np.asarray(axis, dtype=np.float64)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    c, s = np.cos(angle)[..., None, None], np.sin(angle)[..., None, None]
    return c * np.eye(3) + s * K + (1 - c) * np.outer(a, a)


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

    Compiled (numba, parallel over frames) because the scores of a 3-D task
    ask for every recorded frame of every episode, and the numpy loop over
    links cost more than the rollout itself; only the points are stored,
    not every link frame.  ``points_world(model, *link_frames(model, q), ...)``
    is its plain-numpy twin (tests compare them)."""
    q = np.asarray(q, dtype=np.float64)
    flat = np.ascontiguousarray(q.reshape(-1, q.shape[-1]))
    links = np.ascontiguousarray(links, dtype=np.int64)
    local = np.ascontiguousarray(np.asarray(local, dtype=np.float64).reshape(-1, 3))
    out = np.empty((flat.shape[0], len(links), 3))
    _points_kernel(model.jtype, model.parent, model.qadr, model.axis, model.xrot, model.xpos,
                   model.fixed_rot, model.fixed_pos, flat, links, local, out)
    return out.reshape(q.shape[:-1] + (len(links), 3))


@nb.njit(cache=True, parallel=True)
def _points_kernel(jtype, parent, qadr, axis, xrot, xpos, fixed_rot, fixed_pos, q, links, local, out):
    nl = parent.shape[0]
    for s in nb.prange(q.shape[0]):
        R = np.empty((nl + 1, 3, 3))            # index nl: the fixed root body
        P = np.empty((nl + 1, 3))
        R[nl] = fixed_rot
        P[nl] = fixed_pos
        _frames_one(jtype, parent, qadr, axis, xrot, xpos, q[s], R, P)
        for k in range(links.shape[0]):
            li = links[k] if links[k] >= 0 else nl
            for a in range(3):
                out[s, k, a] = P[li, a] + (R[li, a, 0] * local[k, 0] + R[li, a, 1] * local[k, 1]
                                           + R[li, a, 2] * local[k, 2])


@nb.njit(cache=True)
def _frames_one(jtype, parent, qadr, axis, xrot, xpos, q, R, P):
    """World rotation R[i] and origin P[i] of every link i for one configuration."""
    A = np.empty((3, 3))              # the joint's own rotation (identity for a slide)
    Rrel = np.empty((3, 3))
    rrel = np.empty(3)
    for i in range(parent.shape[0]):
        qa, p = qadr[i], parent[i]
        if jtype[i] == FREE3D:
            _quat_rot(q[qa + 3], q[qa + 4], q[qa + 5], q[qa + 6], Rrel)
            for a in range(3):
                rrel[a] = q[qa + a]
        else:
            ax = axis[i]
            if jtype[i] == HINGE3D:
                _rodrigues(ax, q[qa], A)
                for a in range(3):
                    rrel[a] = xpos[i, a]
            else:
                for a in range(3):
                    for b in range(3):
                        A[a, b] = 1.0 if a == b else 0.0
                for a in range(3):
                    rrel[a] = xpos[i, a] + q[qa] * (xrot[i, a, 0] * ax[0] + xrot[i, a, 1] * ax[1]
                                                    + xrot[i, a, 2] * ax[2])
            for a in range(3):
                for b in range(3):
                    Rrel[a, b] = xrot[i, a, 0] * A[0, b] + xrot[i, a, 1] * A[1, b] + xrot[i, a, 2] * A[2, b]
        if p >= 0 and jtype[i] != FREE3D:
            for a in range(3):
                P[i, a] = P[p, a] + R[p, a, 0] * rrel[0] + R[p, a, 1] * rrel[1] + R[p, a, 2] * rrel[2]
                for b in range(3):
                    R[i, a, b] = R[p, a, 0] * Rrel[0, b] + R[p, a, 1] * Rrel[1, b] + R[p, a, 2] * Rrel[2, b]
        else:
            for a in range(3):
                P[i, a] = rrel[a]
                for b in range(3):
                    R[i, a, b] = Rrel[a, b]


@nb.njit(cache=True)
def _quat_rot(w, x, y, z, out):
    n = np.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    out[0, 0] = 1 - 2 * (y * y + z * z)
    out[0, 1] = 2 * (x * y - w * z)
    out[0, 2] = 2 * (x * z + w * y)
    out[1, 0] = 2 * (x * y + w * z)
    out[1, 1] = 1 - 2 * (x * x + z * z)
    out[1, 2] = 2 * (y * z - w * x)
    out[2, 0] = 2 * (x * z - w * y)
    out[2, 1] = 2 * (y * z + w * x)
    out[2, 2] = 1 - 2 * (x * x + y * y)


@nb.njit(cache=True)
def _rodrigues(ax, angle, out):
    c, sn = np.cos(angle), np.sin(angle)
    for a in range(3):
        for b in range(3):
            out[a, b] = (1 - c) * ax[a] * ax[b] + (c if a == b else 0.0)
    out[0, 1] -= sn * ax[2]
    out[0, 2] += sn * ax[1]
    out[1, 0] += sn * ax[2]
    out[1, 2] -= sn * ax[0]
    out[2, 0] -= sn * ax[1]
    out[2, 1] += sn * ax[0]


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
    from ..figures.spec3d import rot_to_quat
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


def euler_angles(Rm: np.ndarray) -> np.ndarray:
    """(roll, pitch, yaw) [..., 3] with R = Rz(yaw)·Ry(−pitch)·Rx(roll) (pitch nose-up,
    the planar CCW convention; the same as the kernel's senses)."""
    roll = np.arctan2(Rm[..., 2, 1], Rm[..., 2, 2])
    pitch = np.arcsin(np.clip(Rm[..., 2, 0], -1, 1))
    yaw = np.arctan2(Rm[..., 1, 0], Rm[..., 0, 0])
    return np.stack([roll, pitch, yaw], -1)
