"""A free object in the 3-D scene and a grip that welds it to a link on contact.

The object is a sphere (mass m, radius r) that rests on a table (a
horizontal rectangle of the scene) or on the ground, and is simulated as a
particle beside the figure: gravity, penalty contact with the table top
and the ground (a normal spring-damper that never pulls, friction that
opposes sliding up to μ·Fn), and the grip.

The grip is one link's capsule (segment a-b, radius r_g, in link
coordinates).  It closes the first time the object touches it (the
sphere's centre within r + r_g of the segment): the object's centre, as it
is at that moment, becomes an anchor point fixed in the link, and from then
on a stiff spring-damper holds the centre there (a weld at the centre: the
object goes where the hand goes; its spin about its own centre is left
free, which for a small sphere drops only 2/5·m·r² of inertia).  The grip
force F acts on the object and −F on the link at the anchor, so momentum
passes between them and the sum is conserved (tests: a weld forming between
two free bodies in zero gravity, a figure swinging a held object while
falling, the shoulder torque of a held object against m·g·lever).

The grip's spring-damper is explicit, like every contact force (an
implicit step for the object alone would lag the anchor's own acceleration
and leave a spurious force on a freely falling pair): stable while
√(k/μ)·dt and c·dt/μ stay below ~1, μ the reduced mass of the object and
the gripping point (the defaults suit objects of 0.1 kg and more in
Herman's hand at dt = 2 ms: μ ≥ 0.05 kg gives 0.49 and 0.8).

Layout of the scene's object parameters (``Scene.obj``, float64; empty: no
object) and of the per-episode object state (``OB_*``), both as index
constants below.  Plain-numpy twin: ``tests/reference/grip3d_ref.py``.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .spatial3d import apply_point_force, point_velocity, point_world

# ---- Scene.obj: the object, its table and the grip (float64[N_OBJ])
O_MASS, O_RADIUS, O_X, O_Y, O_Z = 0, 1, 2, 3, 4          # start position of the centre
O_TABLE_Z, O_TABLE_X0, O_TABLE_X1, O_TABLE_Y0, O_TABLE_Y1 = 5, 6, 7, 8, 9   # top and footprint
O_K, O_C, O_MU = 10, 11, 12                             # table/ground contact, friction
O_LINK, O_A, O_B, O_GRIP_R = 13, 14, 17, 20              # gripping link, its segment a, b, radius
O_K_GRIP, O_C_GRIP = 21, 22
N_OBJ = 23
# ---- the object's state per episode (float64[N_OB]); recorded frames keep the first OB_REC
OB_X, OB_V, OB_GRIPPED, OB_ANCHOR = 0, 3, 6, 7           # centre, velocity, 1 once gripped, anchor (link coords)
OB_REC = 7                                               # x, y, z, vx, vy, vz, gripped
N_OB = 10

_INLINE = dict(cache=True, error_model="numpy", boundscheck=False, inline="always")
_JIT = dict(cache=True, error_model="numpy", boundscheck=False)


def object_params(*, mass, radius, position, table_z, table_x, table_y, link, a, b, grip_radius,
                  k=2e4, c=60.0, mu=0.8, k_grip=3000.0, c_grip=20.0) -> np.ndarray:
    """The ``Scene.obj`` vector (see make_scene's ``obj``), checked.

    Defaults are stable at dt = 2 ms for a 0.1-1 kg object: the table's
    spring gives √(k/m)·dt ≤ 0.9 for m ≥ 0.1 kg and sinks m·g/k (0.1 mm for
    0.2 kg); the grip holds 0.2 kg with a 0.65 mm sag (m·g/k_grip)."""
    v = np.zeros(N_OBJ)
    v[O_MASS], v[O_RADIUS] = mass, radius
    v[O_X:O_X + 3] = position
    v[O_TABLE_Z] = table_z
    v[O_TABLE_X0], v[O_TABLE_X1] = table_x
    v[O_TABLE_Y0], v[O_TABLE_Y1] = table_y
    v[O_K], v[O_C], v[O_MU] = k, c, mu
    v[O_LINK] = link
    v[O_A:O_A + 3], v[O_B:O_B + 3] = a, b
    v[O_GRIP_R], v[O_K_GRIP], v[O_C_GRIP] = grip_radius, k_grip, c_grip
    if not np.all(np.isfinite(v)):
        raise ValueError("object: every parameter must be a finite number")
    if mass <= 0 or radius <= 0 or grip_radius < 0 or min(k, c, mu, k_grip, c_grip) < 0:
        raise ValueError("object: mass and radius must be > 0; stiffnesses, dampings, mu >= 0")
    if table_x[0] > table_x[1] or table_y[0] > table_y[1]:
        raise ValueError("object: the table's footprint needs x0 <= x1 and y0 <= y1")
    if int(link) != link or link < 0:
        raise ValueError(f"object: the gripping link must be a link index >= 0, got {link}")
    return v


@njit(**_JIT)
def object_start(obj, ob):
    """The object's state at the start of an episode: at rest at its start position.
    (A call, not inlined: inlined into the episode loop, numba stored only the
    first of a tuple assignment's three elements here.)"""
    for k in range(N_OB):
        ob[k] = 0.0
    if obj.shape[0] > 0:
        for k in range(3):
            ob[OB_X + k] = obj[O_X + k]


@njit(**_INLINE)
def _support(obj, ground, ground_z, x, y, z, vz):
    """Normal force of the table top or the ground on the sphere (never pulling)."""
    r = obj[O_RADIUS]
    pen = 0.0
    if (obj[O_TABLE_X0] <= x <= obj[O_TABLE_X1] and obj[O_TABLE_Y0] <= y <= obj[O_TABLE_Y1]
            and z >= obj[O_TABLE_Z] - r):            # over the table, not below its top
        pen = obj[O_TABLE_Z] - (z - r)
    if ground != 0:
        pen = max(pen, ground_z - (z - r))
    if pen <= 0.0:
        return 0.0
    return max(0.0, obj[O_K] * pen - obj[O_C] * vz)


@njit(**_INLINE)
def _segment_distance(px, py, pz, ax, ay, az, bx, by, bz):
    dx, dy, dz = bx - ax, by - ay, bz - az
    L2 = dx * dx + dy * dy + dz * dz
    t = ((px - ax) * dx + (py - ay) * dy + (pz - az) * dz) / L2 if L2 > 0.0 else 0.0
    t = min(1.0, max(0.0, t))
    ex, ey, ez = px - (ax + t * dx), py - (ay + t * dy), pz - (az + t * dz)
    return np.sqrt(ex * ex + ey * ey + ez * ez)


@njit(**_JIT)
def object_step(obj, gravity, ground, ground_z, R, pos, v, fext, ob, dt):
    """Advance the object by dt from the figure's observed state (R, pos, v of
    every link); add the grip's reaction to ``fext``.  Closes the grip on
    contact.  A call, not inlined: only scenes with an object make it."""
    m = obj[O_MASS]
    link = int(obj[O_LINK])
    x, y, z = ob[OB_X], ob[OB_X + 1], ob[OB_X + 2]
    vx, vy, vz = ob[OB_V], ob[OB_V + 1], ob[OB_V + 2]
    fn = _support(obj, ground, ground_z, x, y, z, vz)
    # friction opposes sliding: Coulomb μ·Fn, but at most what stops the
    # slide within this step (explicit friction must not reverse it)
    vt = np.sqrt(vx * vx + vy * vy)
    g = min(obj[O_MU] * fn / vt, m / dt) if vt > 0.0 else 0.0
    fx, fy, fz = -g * vx, -g * vy, fn - m * gravity
    if ob[OB_GRIPPED] == 0.0:
        ax, ay, az = point_world(R, pos, link, obj[O_A], obj[O_A + 1], obj[O_A + 2])
        bx, by, bz = point_world(R, pos, link, obj[O_B], obj[O_B + 1], obj[O_B + 2])
        if _segment_distance(x, y, z, ax, ay, az, bx, by, bz) < obj[O_RADIUS] + obj[O_GRIP_R]:
            ob[OB_GRIPPED] = 1.0          # the anchor: the centre, in link coordinates, now
            dx, dy, dz = x - pos[link, 0], y - pos[link, 1], z - pos[link, 2]
            for i in range(3):
                ob[OB_ANCHOR + i] = R[link, 0, i] * dx + R[link, 1, i] * dy + R[link, 2, i] * dz
    if ob[OB_GRIPPED] != 0.0:
        k, c = obj[O_K_GRIP], obj[O_C_GRIP]
        px, py, pz = ob[OB_ANCHOR], ob[OB_ANCHOR + 1], ob[OB_ANCHOR + 2]
        wx, wy, wz = point_world(R, pos, link, px, py, pz)
        ux, uy, uz = point_velocity(R, v, link, px, py, pz)
        # a spring-damper from the anchor to the centre, explicit like every contact
        # force: in free fall (w = x, u = v) it is zero, as a weld's force must be
        gx = k * (wx - x) + c * (ux - vx)
        gy = k * (wy - y) + c * (uy - vy)
        gz = k * (wz - z) + c * (uz - vz)
        nvx, nvy, nvz = vx + dt * (fx + gx) / m, vy + dt * (fy + gy) / m, vz + dt * (fz + gz) / m
        apply_point_force(R, fext, link, px, py, pz, -gx, -gy, -gz)
    else:
        nvx, nvy, nvz = vx + dt * fx / m, vy + dt * fy / m, vz + dt * fz / m
    ob[OB_V], ob[OB_V + 1], ob[OB_V + 2] = nvx, nvy, nvz
    ob[OB_X], ob[OB_X + 1], ob[OB_X + 2] = x + dt * nvx, y + dt * nvy, z + dt * nvz
