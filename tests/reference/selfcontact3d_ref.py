"""Plain-numpy twin of gpmotion.sim.selfcontact3d.self_contacts.

Written from the module's docstring with vectors; the closest points are
found another way than the kernel's (Ericson's clamped solve): the
unconstrained minimum of |p1 + s·d1 − p2 − t·d2|² when it lies inside the
unit square, else the best of the four edges (each a point–segment
projection), so a slip in either shows up as a difference."""
import numpy as np


def _on_segment(p, a, d):
    """Parameter of the point of segment a + u·d nearest to p."""
    dd = d @ d
    return float(np.clip((p - a) @ d / dd, 0.0, 1.0)) if dd > 0 else 0.0


def closest_params(p1, d1, p2, d2):
    cands = []
    A = np.array([[d1 @ d1, -(d1 @ d2)], [-(d1 @ d2), d2 @ d2]])
    rhs = np.array([-(d1 @ (p1 - p2)), d2 @ (p1 - p2)])
    if abs(np.linalg.det(A)) > 1e-12 * max(1e-300, A[0, 0] * A[1, 1]):
        s, t = np.linalg.solve(A, rhs)
        if 0 <= s <= 1 and 0 <= t <= 1:
            cands.append((s, t))
    for s in (0.0, 1.0):
        cands.append((s, _on_segment(p1 + s * d1, p2, d2)))
    for t in (0.0, 1.0):
        cands.append((_on_segment(p2 + t * d2, p1, d1), t))
    return min(cands, key=lambda st: np.linalg.norm(p1 + st[0] * d1 - p2 - st[1] * d2))


def _world(M, R, pos, link, p):
    if link < 0:
        return M.fixed_pos + M.fixed_rot @ p
    return pos[link] + R[link] @ p


def _velocity(R, v, link, p):
    if link < 0:
        return np.zeros(3)
    return R[link] @ (v[link, 3:] + np.cross(v[link, :3], p))


def _push(R, fext, link, p, F):
    if link < 0:
        return
    fl = R[link].T @ F
    fext[link, :3] += np.cross(p, fl)
    fext[link, 3:] += fl


def self_contacts(M, selfc, R, pos, v, fext):
    """Same contract as the kernel: adds to ``fext``, returns the deepest penetration."""
    deepest = 0.0
    for g, h, k, c in selfc:
        g, h = int(g), int(h)
        lg, lh = M.seg_link[g], M.seg_link[h]
        a, b = _world(M, R, pos, lg, M.seg_a[g]), _world(M, R, pos, lg, M.seg_b[g])
        e, f = _world(M, R, pos, lh, M.seg_a[h]), _world(M, R, pos, lh, M.seg_b[h])
        s, t = closest_params(a, b - a, e, f - e)
        gap = a + s * (b - a) - (e + t * (f - e))
        dist = np.linalg.norm(gap)
        pen = M.seg_r[g] + M.seg_r[h] - dist
        if pen <= 0 or dist == 0:
            continue
        deepest = max(deepest, pen)
        n = gap / dist
        pg = M.seg_a[g] + s * (M.seg_b[g] - M.seg_a[g])
        ph = M.seg_a[h] + t * (M.seg_b[h] - M.seg_a[h])
        force = k * pen - c * (_velocity(R, v, lg, pg) - _velocity(R, v, lh, ph)) @ n
        if force > 0:
            _push(R, fext, lg, pg, force * n)
            _push(R, fext, lh, ph, -force * n)
    return deepest

