"""Planar poses and points of recorded frames, compiled: what scores read.

A planar score asks for the base pose and a site over every recorded frame
of a generation's episodes (a lamp generation: 300 × 301 frames), and the
numpy forms in :mod:`gpmotion.sim.geometry` spend about an eighth of a
lamp_hop run allocating temporaries.  These kernels do the same arithmetic
in the same order, without fused multiply-adds, so they give the numpy
forms' values bit for bit (``tests/test_geometry_fast.py``); the frames are
split over the rollout's threads.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..model import REVOLUTE, SLIDE_X
from .threads import run_chunks


def link_poses(model, q: np.ndarray) -> np.ndarray:
    """World pose (θ, x, z) of every link for q[..., nq] → [..., nq, 3]."""
    q = np.asarray(q, dtype=np.float64)
    flat = np.ascontiguousarray(q.reshape(-1, q.shape[-1]))
    out = np.empty(flat.shape + (3,))
    args = (model.parent, model.jtype, model.xtree, flat, out)
    run_chunks(_poses_kernel, args, flat.shape[0])
    return out.reshape(q.shape + (3,))


def points_world(model, poses: np.ndarray, links, local) -> np.ndarray:
    """World (x, z) [..., n, 2] of link-frame points; link −1 is the fixed root body."""
    nl = poses.shape[-2]
    flat = np.ascontiguousarray(poses.reshape(-1, nl, 3))
    links = np.ascontiguousarray(links, dtype=np.int64)
    local = np.ascontiguousarray(np.asarray(local, dtype=np.float64).reshape(-1, 2))
    fixed = np.ascontiguousarray(model.fixed_pose, dtype=np.float64)
    out = np.empty((flat.shape[0], len(links), 2))
    run_chunks(_points_kernel, (flat, fixed, links, local, out), flat.shape[0])
    return out.reshape(poses.shape[:-2] + (len(links), 2))


@njit(cache=True, nogil=True, error_model="numpy")
def _poses_kernel(parent, jtype, xtree, q, out, lo, hi):
    for s in range(lo, hi):
        for i in range(parent.shape[0]):
            p = parent[i]
            a0, rx, rz = xtree[i, 0], xtree[i, 1], xtree[i, 2]
            thp, xp, zp = (out[s, p, 0], out[s, p, 1], out[s, p, 2]) if p >= 0 else (0.0, 0.0, 0.0)
            c, sn = math.cos(thp), math.sin(thp)
            jx, jz = xp + c * rx - sn * rz, zp + sn * rx + c * rz
            if jtype[i] == REVOLUTE:
                out[s, i, 0], out[s, i, 1], out[s, i, 2] = thp + a0 + q[s, i], jx, jz
            else:
                d = q[s, i]
                dx, dz = (d, 0 * d) if jtype[i] == SLIDE_X else (0 * d, d)
                th = thp + a0
                cw, sw = math.cos(th), math.sin(th)
                out[s, i, 0], out[s, i, 1], out[s, i, 2] = th, jx + cw * dx - sw * dz, jz + sw * dx + cw * dz


@njit(cache=True, nogil=True, error_model="numpy")
def _points_kernel(poses, fixed, links, local, out, lo, hi):
    for s in range(lo, hi):
        for k in range(links.shape[0]):
            th, x, z = (poses[s, links[k], 0], poses[s, links[k], 1], poses[s, links[k], 2]) \
                if links[k] >= 0 else (fixed[0], fixed[1], fixed[2])
            c, sn = math.cos(th), math.sin(th)
            lx, lz = local[k, 0], local[k, 1]
            out[s, k, 0] = x + c * lx - sn * lz
            out[s, k, 1] = z + sn * lx + c * lz
