"""Plain-numpy twin of gpmotion.sim.grip3d.object_step (the free object and its grip).

Written from the module's docstring with vectors instead of scalars, so a
slip in the kernel's unrolled arithmetic shows up as a difference."""
import numpy as np

from gpmotion.sim import grip3d as G


def support(obj, ground, ground_z, x, vz):
    r = obj[G.O_RADIUS]
    over = (obj[G.O_TABLE_X0] <= x[0] <= obj[G.O_TABLE_X1]
            and obj[G.O_TABLE_Y0] <= x[1] <= obj[G.O_TABLE_Y1] and x[2] >= obj[G.O_TABLE_Z] - r)
    pens = ([obj[G.O_TABLE_Z] - (x[2] - r)] if over else []) + ([ground_z - (x[2] - r)] if ground else [])
    pen = max(pens, default=0.0)
    return max(0.0, obj[G.O_K] * pen - obj[G.O_C] * vz) if pen > 0 else 0.0


def segment_distance(p, a, b):
    d = b - a
    t = np.clip((p - a) @ d / (d @ d), 0.0, 1.0) if d @ d > 0 else 0.0
    return np.linalg.norm(p - (a + t * d))


def object_step(obj, gravity, ground, ground_z, R, pos, v, fext, ob, dt):
    """Same contract as the kernel: updates ``ob`` and ``fext`` in place."""
    m, link = obj[G.O_MASS], int(obj[G.O_LINK])
    x, vel = ob[G.OB_X:G.OB_X + 3].copy(), ob[G.OB_V:G.OB_V + 3].copy()
    fn = support(obj, ground, ground_z, x, vel[2])
    slip = np.array([vel[0], vel[1], 0.0])
    vt = np.linalg.norm(slip)
    f = -min(obj[G.O_MU] * fn / vt, m / dt) * slip if vt > 0 else np.zeros(3)
    f[2] += fn - m * gravity
    Rl, pl = R[link], pos[link]
    if ob[G.OB_GRIPPED] == 0:
        a, b = pl + Rl @ obj[G.O_A:G.O_A + 3], pl + Rl @ obj[G.O_B:G.O_B + 3]
        if segment_distance(x, a, b) < obj[G.O_RADIUS] + obj[G.O_GRIP_R]:
            ob[G.OB_GRIPPED] = 1.0
            ob[G.OB_ANCHOR:G.OB_ANCHOR + 3] = Rl.T @ (x - pl)
    if ob[G.OB_GRIPPED] != 0:
        k, c = obj[G.O_K_GRIP], obj[G.O_C_GRIP]
        p = ob[G.OB_ANCHOR:G.OB_ANCHOR + 3]
        w = pl + Rl @ p                                         # anchor, world
        u = Rl @ (v[link, 3:] + np.cross(v[link, :3], p))       # its velocity, world
        F = k * (w - x) + c * (u - vel)                         # on the object; −F on the link
        new_v = vel + dt * (f + F) / m
        fl = Rl.T @ -F                                          # in link coordinates, at p
        fext[link, :3] += np.cross(p, fl)
        fext[link, 3:] += fl
    else:
        new_v = vel + dt * f / m
    ob[G.OB_V:G.OB_V + 3] = new_v
    ob[G.OB_X:G.OB_X + 3] = x + dt * new_v
