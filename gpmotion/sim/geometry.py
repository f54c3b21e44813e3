"""Forward kinematics in numpy over recorded frames (poses, sites, segments).

The kernel records joint coordinates only; pictures rebuild world geometry
here, vectorized over episodes and frames.  Scores read the compiled forms
of ``link_poses`` and ``points_world`` (:mod:`gpmotion.sim.geometry_fast`),
which give these values bit for bit.
"""
from __future__ import annotations

import numpy as np

from ..model import REVOLUTE, SLIDE_X


def link_poses(model, q: np.ndarray) -> np.ndarray:
    """World pose (θ, x, z) of every link for q[..., nq] → [..., nq, 3]."""
    q = np.asarray(q, dtype=np.float64)
    out = np.zeros(q.shape + (3,))
    for i, p in enumerate(model.parent):
        a0, rx, rz = model.xtree[i]
        if p >= 0:
            thp, xp, zp = out[..., p, 0], out[..., p, 1], out[..., p, 2]
        else:
            thp = xp = zp = np.zeros(q.shape[:-1])
        c, s = np.cos(thp), np.sin(thp)
        jx, jz = xp + c * rx - s * rz, zp + s * rx + c * rz
        if model.jtype[i] == REVOLUTE:
            out[..., i, 0], out[..., i, 1], out[..., i, 2] = thp + a0 + q[..., i], jx, jz
        else:
            d = q[..., i]
            dx, dz = (d, 0 * d) if model.jtype[i] == SLIDE_X else (0 * d, d)
            th = thp + a0
            cw, sw = np.cos(th), np.sin(th)
            out[..., i, 0], out[..., i, 1], out[..., i, 2] = th, jx + cw * dx - sw * dz, jz + sw * dx + cw * dz
    return out


def points_world(model, poses: np.ndarray, links: np.ndarray, local: np.ndarray) -> np.ndarray:
    """World (x, z) of link-frame points; link −1 is the fixed root body."""
    fixed = np.broadcast_to(model.fixed_pose, poses.shape[:-2] + (1, 3))
    ext = np.concatenate([poses, fixed], axis=-2)       # index −1 → fixed pose
    links = np.asarray(links)
    # cos/sin once per link, then gathered per point (several points share a
    # link: sites and both capsule ends); the same arithmetic, bit for bit
    c, s = np.cos(ext[..., 0])[..., links], np.sin(ext[..., 0])[..., links]
    x, z = ext[..., 1][..., links], ext[..., 2][..., links]
    lx, lz = local[:, 0], local[:, 1]
    out = np.empty(c.shape + (2,))
    out[..., 0] = x + c * lx - s * lz
    out[..., 1] = z + s * lx + c * lz
    return out


def segments_world(model, q: np.ndarray) -> np.ndarray:
    """Capsule end points [..., n_seg, 2 (a/b), 2 (x/z)] for drawing and checks."""
    poses = link_poses(model, q)
    a = points_world(model, poses, model.seg_link, model.seg_a)
    b = points_world(model, poses, model.seg_link, model.seg_b)
    return np.stack([a, b], axis=-2)
