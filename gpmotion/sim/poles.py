"""The limbo pole's contact geometry, shared by the planar and 3-D kernels.

A pole is an infinite cylinder along y through (cx, cz); a body segment meets
it where the segment's closest point in the x–z plane is nearer than the sum
of their radii.
"""
from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy", boundscheck=False, inline="always")
def closest_to_pole(ax, az, bx, bz, cx, cz):
    """(t, ex, ez, dist): the point a + t (b − a), t ∈ [0, 1], of segment a–b nearest to
    the pole's axis (cx, cz) in the x–z plane, its offset from the axis and its distance."""
    dx, dz = bx - ax, bz - az
    L2 = dx * dx + dz * dz
    t = ((cx - ax) * dx + (cz - az) * dz) / L2 if L2 > 0 else 0.0
    t = min(1.0, max(0.0, t))
    qx, qz = ax + t * dx, az + t * dz
    ex, ez = qx - cx, qz - cz
    return t, ex, ez, np.sqrt(ex * ex + ez * ez)
