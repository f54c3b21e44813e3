"""Self-contact of a 3-D figure: capsule–capsule penalty contact between named pairs.

A figure's bodies are capsules (segment a-b, radius r, in link coordinates;
``Model3D.seg_*``).  For each pair the scene lists (``Scene.selfc``, rows of
``S_G, S_H, S_K, S_C``: two segment indices, a stiffness and a damping), the
step finds the closest points of the two segments (Ericson, *Real-Time
Collision Detection* §5.1.9); when they are nearer than r_g + r_h a normal
spring-damper pushes them apart:

    pen = r_g + r_h − |p_g − p_h|,  n = (p_g − p_h) / |p_g − p_h|
    f   = max(0, k·pen − c·(v_g − v_h)·n)

acting as +f·n on g at p_g and −f·n on h at p_h.  The pair of forces lies on
one line, so it carries neither net force nor net torque: self-contact
conserves the figure's momentum and angular momentum (tests).  Frictionless:
the arm slides over the trunk.  A body on the fixed root (link −1, e.g. a
fixed pelvis) takes no force.

Which pairs collide is a task's choice (its scene), not the figure's: a
figure's older task versions keep their results, and adjacent bodies, which
overlap at their shared joint, are never listed.  Plain-numpy twin:
``tests/reference/selfcontact3d_ref.py``.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .spatial3d import apply_point_force, point_velocity, segment_world

S_G, S_H, S_K, S_C = 0, 1, 2, 3       # columns of Scene.selfc
N_SELFC = 4

_INLINE = dict(cache=True, error_model="numpy", boundscheck=False, inline="always")


def self_contact_pairs(figure, pairs, k=4e4, c=40.0) -> np.ndarray:
    """The ``Scene.selfc`` rows for ``pairs`` of body names, checked.

    Defaults: 1 cm of penetration pushes back with 400 N, four times what
    Herman's shoulder servo (50 N·m) presses with at half a metre, so a
    forearm held against the trunk sinks in ~3-6 mm; at dt = 2 ms
    √(k/m)·dt = 0.38 and 0.62, c·dt/m = 0.07 and 0.19 for his forearm
    (1.12 kg) and hand (0.42 kg): explicit, like every contact force here,
    and stable while both stay well below 1 (at k = 2e4 a GP
    controller pressed its forearm 1.1 cm into the belly; random arm
    motions at dt = 2 ms went 1.9 cm in at 2e4, 1.15 cm at 4e4)."""
    if figure.dimensions != 3:
        raise ValueError(f"self-contact: {figure.name!r} is planar; self-contact needs a 3-D figure")
    if not (np.isfinite(k) and np.isfinite(c) and k >= 0 and c >= 0):
        raise ValueError("self-contact: k and c must be finite numbers >= 0")
    rows = []
    for g, h in pairs:
        for b in (g, h):
            if b not in figure.body_names:
                raise ValueError(f"self-contact: {figure.name!r} has no body {b!r}")
        i, j = figure.body_names.index(g), figure.body_names.index(h)
        if i == j:
            raise ValueError(f"self-contact: a body cannot collide with itself ({g!r})")
        rows.append((i, j, k, c))
    return np.array(rows, dtype=np.float64).reshape(-1, N_SELFC)


@njit(**_INLINE)
def _clamp01(x):
    return 0.0 if x < 0.0 else (1.0 if x > 1.0 else x)


@njit(**_INLINE)
def closest_params(p1x, p1y, p1z, d1x, d1y, d1z, p2x, p2y, p2z, d2x, d2y, d2z):
    """Parameters (s, t) in [0, 1] of the closest points p1 + s·d1, p2 + t·d2."""
    rx, ry, rz = p1x - p2x, p1y - p2y, p1z - p2z
    a = d1x * d1x + d1y * d1y + d1z * d1z
    e = d2x * d2x + d2y * d2y + d2z * d2z
    f = d2x * rx + d2y * ry + d2z * rz
    eps = 1e-18
    if a <= eps and e <= eps:
        return 0.0, 0.0
    if a <= eps:
        return 0.0, _clamp01(f / e)
    c = d1x * rx + d1y * ry + d1z * rz
    if e <= eps:
        return _clamp01(-c / a), 0.0
    b = d1x * d2x + d1y * d2y + d1z * d2z
    denom = a * e - b * b
    s = _clamp01((b * f - c * e) / denom) if denom > eps * a * e else 0.0
    t = (b * s + f) / e
    if t < 0.0:
        return _clamp01(-c / a), 0.0
    if t > 1.0:
        return _clamp01((b - c) / a), 1.0
    return s, t


@njit(**_INLINE)
def self_contacts(M, selfc, R, pos, v, fext):
    """Add the self-contact forces of the pairs ``selfc`` to ``fext``; returns
    the deepest penetration (m, 0 when no pair touches)."""
    deepest = 0.0
    for k in range(selfc.shape[0]):
        g, h = int(selfc[k, S_G]), int(selfc[k, S_H])
        ax, ay, az, bx, by, bz = segment_world(M, R, pos, g)
        cx, cy, cz, dx, dy, dz = segment_world(M, R, pos, h)
        s, t = closest_params(ax, ay, az, bx - ax, by - ay, bz - az,
                              cx, cy, cz, dx - cx, dy - cy, dz - cz)
        ex = ax + s * (bx - ax) - (cx + t * (dx - cx))
        ey = ay + s * (by - ay) - (cy + t * (dy - cy))
        ez = az + s * (bz - az) - (cz + t * (dz - cz))
        dist = np.sqrt(ex * ex + ey * ey + ez * ez)
        pen = M.seg_r[g] + M.seg_r[h] - dist
        if pen <= 0.0 or dist == 0.0:
            continue
        deepest = max(deepest, pen)
        nx, ny, nz = ex / dist, ey / dist, ez / dist
        # the closest points in each link's own coordinates
        gx = M.seg_a[g, 0] + s * (M.seg_b[g, 0] - M.seg_a[g, 0])
        gy = M.seg_a[g, 1] + s * (M.seg_b[g, 1] - M.seg_a[g, 1])
        gz = M.seg_a[g, 2] + s * (M.seg_b[g, 2] - M.seg_a[g, 2])
        hx = M.seg_a[h, 0] + t * (M.seg_b[h, 0] - M.seg_a[h, 0])
        hy = M.seg_a[h, 1] + t * (M.seg_b[h, 1] - M.seg_a[h, 1])
        hz = M.seg_a[h, 2] + t * (M.seg_b[h, 2] - M.seg_a[h, 2])
        lg, lh = M.seg_link[g], M.seg_link[h]
        ugx, ugy, ugz = point_velocity(R, v, lg, gx, gy, gz)
        uhx, uhy, uhz = point_velocity(R, v, lh, hx, hy, hz)
        vn = (ugx - uhx) * nx + (ugy - uhy) * ny + (ugz - uhz) * nz
        f = selfc[k, S_K] * pen - selfc[k, S_C] * vn
        if f > 0.0:
            apply_point_force(R, fext, lg, gx, gy, gz, f * nx, f * ny, f * nz)
            apply_point_force(R, fext, lh, hx, hy, hz, -f * nx, -f * ny, -f * nz)
    return deepest
