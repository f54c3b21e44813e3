"""Plain-numpy twin of gpmotion.sim.planar, written the textbook way.

Full 3×3 matrices (spatial_v2's planar conventions), RNEA for the bias
forces and CRBA for the joint-space inertia, then a dense solve — a
different algorithm from the kernel's ABA, so agreement is meaningful.
"""
import numpy as np

from .hybrid import hybrid_dynamics

REVOLUTE, SLIDE_X, SLIDE_Z = 0, 1, 2


def xpln(theta, r):
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[1.0, 0.0, 0.0],
                     [s * r[0] - c * r[1], c, s],
                     [c * r[0] + s * r[1], -s, c]])


def crm(v):
    w, vx, vz = v
    return np.array([[0.0, 0.0, 0.0], [vz, 0.0, -w], [-vx, w, 0.0]])


def crf(v):
    return -crm(v).T


def mci(m, c, ic):
    cx, cz = c
    return np.array([[ic + m * (cx * cx + cz * cz), -m * cz, m * cx],
                     [-m * cz, m, 0.0],
                     [m * cx, 0.0, m]])


def jcalc(jtype, q):
    if jtype == REVOLUTE:
        return xpln(q, (0.0, 0.0)), np.array([1.0, 0.0, 0.0])
    if jtype == SLIDE_X:
        return xpln(0.0, (q, 0.0)), np.array([0.0, 1.0, 0.0])
    return xpln(0.0, (0.0, q)), np.array([0.0, 0.0, 1.0])


def transforms(M, q):
    out = []
    for i in range(len(q)):
        XJ, S = jcalc(M.jtype[i], q[i])
        a0, rx, rz = M.xtree[i]
        out.append((XJ @ xpln(a0, (rx, rz)), S))
    return out


def rnea(M, q, qd, qdd, gravity, fext):
    """Inverse dynamics: joint forces for accelerations qdd (fext in link coords)."""
    n = len(q)
    tr = transforms(M, q)
    v, a, f = np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3))
    for i in range(n):
        X, S = tr[i]
        p = M.parent[i]
        vp = v[p] if p >= 0 else np.zeros(3)
        ap = a[p] if p >= 0 else np.array([0.0, 0.0, gravity])
        vJ = S * qd[i]
        v[i] = X @ vp + vJ
        a[i] = X @ ap + S * qdd[i] + crm(v[i]) @ vJ
        I = mci(M.mass[i], M.com[i], M.icom[i])
        f[i] = I @ a[i] + crf(v[i]) @ I @ v[i] - fext[i]
    tau = np.zeros(n)
    for i in range(n - 1, -1, -1):
        X, S = tr[i]
        tau[i] = S @ f[i]
        if M.parent[i] >= 0:
            f[M.parent[i]] += X.T @ f[i]
    return tau


def crba(M, q):
    """Joint-space inertia matrix H(q)."""
    n = len(q)
    tr = transforms(M, q)
    IC = [mci(M.mass[i], M.com[i], M.icom[i]) for i in range(n)]
    for i in range(n - 1, -1, -1):
        if M.parent[i] >= 0:
            X = tr[i][0]
            IC[M.parent[i]] = IC[M.parent[i]] + X.T @ IC[i] @ X
    H = np.zeros((n, n))
    for i in range(n):
        fh = IC[i] @ tr[i][1]
        H[i, i] = tr[i][1] @ fh
        j = i
        while M.parent[j] >= 0:
            fh = tr[j][0].T @ fh
            j = M.parent[j]
            H[i, j] = H[j, i] = tr[j][1] @ fh
    return H


def forward_dynamics(M, q, qd, tau, gravity, fext, presc=None, presc_qdd=None, arm=None):
    """qdd (and the torques of prescribed dofs) by dense hybrid dynamics.

    ``arm`` (per dof, default 0): the implicit-PD armature — a free dof's
    joint force is ``tau − arm·qdd``, so the system matrix is H + diag(arm);
    the returned torques of free dofs are those joint forces.
    """
    C = rnea(M, q, qd, np.zeros(len(qd)), gravity, fext)
    return hybrid_dynamics(crba(M, q), C, np.asarray(tau, dtype=float), presc, presc_qdd, arm)


def poses_and_velocities(M, q, qd):
    """World pose (θ, x, z) and spatial velocity (link coords) of every link."""
    n = len(q)
    tr = transforms(M, q)
    pose, v = np.zeros((n, 3)), np.zeros((n, 3))
    for i in range(n):
        X, S = tr[i]
        p = M.parent[i]
        v[i] = (X @ v[p] if p >= 0 else 0) + S * qd[i]
        th_p, xp, zp = pose[p] if p >= 0 else (0.0, 0.0, 0.0)
        a0, rx, rz = M.xtree[i]
        c, s = np.cos(th_p), np.sin(th_p)
        jx, jz = xp + c * rx - s * rz, zp + s * rx + c * rz
        if M.jtype[i] == REVOLUTE:
            pose[i] = (th_p + a0 + q[i], jx, jz)
        else:
            d = np.array([q[i], 0.0]) if M.jtype[i] == SLIDE_X else np.array([0.0, q[i]])
            th = th_p + a0
            R = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
            pose[i] = (th, *(np.array([jx, jz]) + R @ d))
    return pose, v


def energy(M, gravity, q, qd):
    pose, v = poses_and_velocities(M, q, qd)
    ke = pe = 0.0
    for i in range(len(q)):
        if M.mass[i] == 0:
            continue
        ke += 0.5 * v[i] @ mci(M.mass[i], M.com[i], M.icom[i]) @ v[i]
        th, x, z = pose[i]
        pe += M.mass[i] * gravity * (z + np.sin(th) * M.com[i, 0] + np.cos(th) * M.com[i, 1])
    return ke + pe


def momentum(M, q, qd):
    """Linear momentum (px, pz) and angular momentum about the world origin."""
    pose, v = poses_and_velocities(M, q, qd)
    P = np.zeros(2)
    L = 0.0
    for i in range(len(q)):
        m = M.mass[i]
        if m == 0:
            continue
        th, x, z = pose[i]
        c, s = np.cos(th), np.sin(th)
        cx, cz = M.com[i]
        gx, gz = x + c * cx - s * cz, z + s * cx + c * cz
        w = v[i, 0]
        lx, lz = v[i, 1] - w * cz, v[i, 2] + w * cx
        vx, vz = c * lx - s * lz, s * lx + c * lz
        P += m * np.array([vx, vz])
        L += M.icom[i] * w + m * (gx * vz - gz * vx)
    return P, L


def ground_force(k, c, mu, pen, vz):
    """Normal force of one penalty contact (never pulls)."""
    return max(0.0, k * pen - c * vz) if pen > 0 else 0.0


def rot(th):
    c, s = np.cos(th), np.sin(th)
    return np.array([[c, -s], [s, c]])


def _deepest_points(M, S, pose):
    """Indices of the points allowed to touch: all, or the ``S.max_contacts``
    most deeply penetrating ones (ties: the lower index)."""
    if not S.max_contacts:
        return set(range(len(M.cp_link)))
    pens = []
    for k, (link, p) in enumerate(zip(M.cp_link, M.cp_pos)):
        th, x, z = pose[link] if link >= 0 else M.fixed_pose
        pens.append(S.ground_z - (z + (rot(th) @ p)[1]))
    order = sorted((k for k in range(len(pens)) if pens[k] > 0), key=lambda k: (-pens[k], k))
    return set(order[:S.max_contacts])


def ground_contacts(M, S, q, qd, anchor, touching):
    """Penalty ground contact with a stick–slip friction anchor, the plain way.

    Returns ``(fext [nl, 3] spatial forces in link coordinates, cforce [nc],
    anchor, touching)``; ``anchor`` and ``touching`` are updated copies.
    """
    pose, v = poses_and_velocities(M, q, qd)
    anchor, touching = np.array(anchor, float), np.array(touching, float)
    fext, cforce = np.zeros((len(q), 3)), np.zeros(len(M.cp_link))
    allowed = _deepest_points(M, S, pose)
    for k, (link, p) in enumerate(zip(M.cp_link, M.cp_pos)):
        if not S.ground:
            continue
        th, x, z = pose[link] if link >= 0 else M.fixed_pose
        R = rot(th)
        x, z = np.array([x, z]) + R @ p
        pen = S.ground_z - z
        if pen <= 0 or k not in allowed:
            touching[k] = 0.0
            continue
        if link >= 0:       # v = (ω, v_origin) in link coordinates; point velocity ω × p
            w = v[link, 0]
            vx, vz = R @ (v[link, 1:] + w * np.array([-p[1], p[0]]))
        else:
            vx = vz = 0.0
        fn = max(0.0, S.k_ground * pen - S.c_ground * vz)
        if touching[k] == 0.0:
            anchor[k], touching[k] = x, 1.0
        ft = -S.k_tangent * (x - anchor[k]) - S.c_tangent * vx
        if abs(ft) > S.mu * fn:
            ft = np.sign(ft) * S.mu * fn
            anchor[k] = x + (ft + S.c_tangent * vx) / S.k_tangent if S.k_tangent > 0 else x
        cforce[k] = fn
        if link >= 0:
            f = R.T @ np.array([ft, fn])                     # force in link coordinates
            fext[link] += (p[0] * f[1] - p[1] * f[0], f[0], f[1])   # moment about the origin
    return fext, cforce, anchor, touching
