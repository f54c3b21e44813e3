"""Rotations in numpy: quaternions (w, x, y, z), axis–angle, matrices (columns = axes)."""
from __future__ import annotations

import numpy as np


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


def rot_to_quat(R) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a rotation matrix, w >= 0."""
    R = np.asarray(R, dtype=np.float64)
    K = np.array([
        [R[0, 0] - R[1, 1] - R[2, 2], R[1, 0] + R[0, 1], R[2, 0] + R[0, 2], R[2, 1] - R[1, 2]],
        [R[1, 0] + R[0, 1], R[1, 1] - R[0, 0] - R[2, 2], R[2, 1] + R[1, 2], R[0, 2] - R[2, 0]],
        [R[2, 0] + R[0, 2], R[2, 1] + R[1, 2], R[2, 2] - R[0, 0] - R[1, 1], R[1, 0] - R[0, 1]],
        [R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1], R[0, 0] + R[1, 1] + R[2, 2]]]) / 3.0
    w, V = np.linalg.eigh(K)
    x, y, z, qw = V[:, np.argmax(w)]
    qv = np.array([qw, x, y, z])
    return qv if qv[0] >= 0 else -qv
