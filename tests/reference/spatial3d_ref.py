"""Plain-numpy twin of gpmotion.sim.spatial3d, written the textbook way.

Full 6×6 Plücker matrices (spatial_v2: ``plux``, ``crm``, ``crf``, ``mcI``),
RNEA for the bias forces and CRBA for the joint-space inertia, then a dense
solve — a different algorithm from the kernel's ABA, so agreement means
something.  A free root is a 6-dof joint with S = 1₆ (body coordinates).
"""
import numpy as np

from .hybrid import hybrid_dynamics

HINGE, SLIDE, FREE = 0, 1, 2


def skew(r):
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def plux(E, r):
    """Plücker transform of a frame rotated by E (parent→child coords) at r (parent coords)."""
    X = np.zeros((6, 6))
    X[:3, :3] = E
    X[3:, 3:] = E
    X[3:, :3] = -E @ skew(r)
    return X


def crm(v):
    X = np.zeros((6, 6))
    X[:3, :3] = skew(v[:3])
    X[3:, 3:] = skew(v[:3])
    X[3:, :3] = skew(v[3:])
    return X


def crf(v):
    return -crm(v).T


def mci(m, c, Ic):
    C = skew(c)
    I = np.zeros((6, 6))
    I[:3, :3] = Ic + m * C @ C.T
    I[:3, 3:] = m * C
    I[3:, :3] = m * C.T
    I[3:, 3:] = m * np.eye(3)
    return I


def rot_axis(a, q):
    a = np.asarray(a, float)
    K = skew(a)
    return np.eye(3) + np.sin(q) * K + (1 - np.cos(q)) * K @ K


def quat_rot(qv):
    w, x, y, z = qv / np.linalg.norm(qv)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def jcalc(M, i, q):
    """Joint transform XJ and motion subspace S (6×k) of link i."""
    qa, jt, a = M.qadr[i], M.jtype[i], M.axis[i]
    if jt == FREE:
        R = quat_rot(q[qa + 3:qa + 7])
        return plux(R.T, q[qa:qa + 3]), np.eye(6)
    if jt == HINGE:
        return plux(rot_axis(a, q[qa]).T, np.zeros(3)), np.concatenate([a, np.zeros(3)])[:, None]
    return plux(np.eye(3), a * q[qa]), np.concatenate([np.zeros(3), a])[:, None]


def transforms(M, q):
    """Per link: (X parent→link, S, dof slice)."""
    out = []
    for i in range(len(M.parent)):
        XJ, S = jcalc(M, i, q)
        Xtree = plux(M.xrot[i].T, M.xpos[i])
        d = M.dadr[i]
        out.append((XJ @ Xtree, S, slice(d, d + S.shape[1])))
    return out


def link_inertia(M, i):
    return mci(M.mass[i], M.com[i], M.icom[i])


def rnea(M, q, qd, qdd, gravity, fext):
    """Inverse dynamics (fext[nl, 6] in link coordinates)."""
    nl = len(M.parent)
    tr = transforms(M, q)
    v, a, f = np.zeros((nl, 6)), np.zeros((nl, 6)), np.zeros((nl, 6))
    ag = np.array([0, 0, 0, 0, 0, gravity], float)
    for i in range(nl):
        X, S, sl = tr[i]
        p = M.parent[i]
        vJ = S @ qd[sl]
        v[i] = (X @ v[p] if p >= 0 else 0) + vJ
        a[i] = X @ (a[p] if p >= 0 else ag) + S @ qdd[sl] + crm(v[i]) @ vJ
        I = link_inertia(M, i)
        f[i] = I @ a[i] + crf(v[i]) @ I @ v[i] - fext[i]
    tau = np.zeros(len(qd))
    for i in range(nl - 1, -1, -1):
        X, S, sl = tr[i]
        tau[sl] = S.T @ f[i]
        if M.parent[i] >= 0:
            f[M.parent[i]] += X.T @ f[i]
    return tau


def crba(M, q):
    nl = len(M.parent)
    nv = int(M.nv)
    tr = transforms(M, q)
    IC = [link_inertia(M, i) for i in range(nl)]
    for i in range(nl - 1, -1, -1):
        if M.parent[i] >= 0:
            X = tr[i][0]
            IC[M.parent[i]] = IC[M.parent[i]] + X.T @ IC[i] @ X
    H = np.zeros((nv, nv))
    for i in range(nl):
        X, S, si = tr[i]
        F = IC[i] @ S
        H[si, si] = S.T @ F
        j = i
        while M.parent[j] >= 0:
            F = tr[j][0].T @ F
            j = M.parent[j]
            Sj, sj = tr[j][1], tr[j][2]
            H[si, sj] = F.T @ Sj
            H[sj, si] = H[si, sj].T
    return H


def forward_dynamics(M, q, qd, tau, gravity, fext, presc=None, presc_qdd=None, arm=None):
    """qdd (and the forces of prescribed dofs) by dense hybrid dynamics.

    ``arm`` (per dof, default 0): the implicit-PD armature — a free dof's
    joint force is ``tau − arm·qdd``, so the system matrix is H + diag(arm);
    the returned forces of free dofs are those joint forces.
    """
    C = rnea(M, q, qd, np.zeros(len(qd)), gravity, fext)
    return hybrid_dynamics(crba(M, q), C, np.asarray(tau, dtype=float), presc, presc_qdd, arm)


def frames_and_velocities(M, q, qd):
    """World rotation R[nl,3,3], origin P[nl,3] and link velocity v[nl,6] (link coords)."""
    nl = len(M.parent)
    tr = transforms(M, q)
    X0 = [None] * nl                   # world → link
    v = np.zeros((nl, 6))
    for i in range(nl):
        X, S, sl = tr[i]
        p = M.parent[i]
        X0[i] = X @ X0[p] if p >= 0 else X
        v[i] = (X @ v[p] if p >= 0 else 0) + S @ qd[sl]
    R = np.array([X[:3, :3].T for X in X0])
    P = np.array([-(X[:3, :3].T @ X[3:, :3]) for X in X0])
    P = np.array([[Pm[2, 1], Pm[0, 2], Pm[1, 0]] for Pm in P])   # r from r×
    return R, P, v


def energy(M, gravity, q, qd):
    R, P, v = frames_and_velocities(M, q, qd)
    ke = pe = 0.0
    for i in range(len(M.parent)):
        if M.mass[i] == 0:
            continue
        ke += 0.5 * v[i] @ link_inertia(M, i) @ v[i]
        pe += M.mass[i] * gravity * (P[i] + R[i] @ M.com[i])[2]
    return ke + pe


def momentum(M, q, qd):
    """World linear momentum and angular momentum about the world origin."""
    R, P, v = frames_and_velocities(M, q, qd)
    lin, ang = np.zeros(3), np.zeros(3)
    for i in range(len(M.parent)):
        m = M.mass[i]
        if m == 0:
            continue
        c = M.com[i]
        vc = R[i] @ (v[i, 3:] + np.cross(v[i, :3], c))
        x = P[i] + R[i] @ c
        lin += m * vc
        ang += R[i] @ M.icom[i] @ v[i, :3] + m * np.cross(x, vc)
    return lin, ang


def ground_point(k, c, kt, ct, mu, x, vel, anchor, touching, ground_z=0.0):
    """One penalty contact: world force (3) and the updated (anchor, touching)."""
    pen = ground_z - x[2]
    if pen <= 0:
        return np.zeros(3), anchor, 0.0
    fn = max(0.0, k * pen - c * vel[2])
    if not touching:
        anchor = x[:2].copy()
    ft = -kt * (x[:2] - anchor) - ct * vel[:2]
    if np.linalg.norm(ft) > mu * fn:
        ft = ft / np.linalg.norm(ft) * mu * fn
        anchor = x[:2] + (ft + ct * vel[:2]) / kt
    return np.array([ft[0], ft[1], fn]), anchor, 1.0


def point_force_to_link(R, p_local, F):
    """Spatial force (link coords) of a world force F applied at a link-frame point."""
    fl = R.T @ F
    return np.concatenate([np.cross(p_local, fl), fl])
