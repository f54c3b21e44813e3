"""Planar articulated-body dynamics (Featherstone's ABA, 3-vector spatial algebra).

Spatial motion vectors are ``(ω, vx, vz)``; the plane is x–z with angles
counter-clockwise (x right, z up).  A link-to-link transform Xpln(θ, r)
(frame rotated by θ, origin at r in the parent frame) is stored as the four
numbers ``(c, s, X10, X20)`` of its matrix

    [[1,   0, 0],
     [X10, c, s],      X10 = s·rx − c·rz
     [X20, −s, c]]     X20 = c·rx + s·rz

Every link has one degree of freedom with motion subspace S = e_k
(k = 0 hinge, 1 slide-x, 2 slide-z), so products with S are indexing.
Kernels are small and allocation-free; the plain-numpy twins live in
``tests/reference/planar_ref.py``.
"""
from __future__ import annotations

import numpy as np
from numba import njit

REVOLUTE, SLIDE_X, SLIDE_Z = 0, 1, 2


@njit(cache=True, inline="always")
def _xm(X, m0, m1, m2):
    """X · m for a motion vector."""
    c, s = X[0], X[1]
    return m0, X[2] * m0 + c * m1 + s * m2, X[3] * m0 - s * m1 + c * m2


@njit(cache=True, inline="always")
def _xtf(X, f0, f1, f2):
    """Xᵀ · f: a force from the child frame to the parent frame."""
    c, s = X[0], X[1]
    return f0 + X[2] * f1 + X[3] * f2, c * f1 - s * f2, s * f1 + c * f2


@njit(cache=True)
def _add_xtix(X, A, B):
    """B += Xᵀ A X  (A symmetric 3×3), in scalars: no allocation per step."""
    c, s, x10, x20 = X[0], X[1], X[2], X[3]
    for r in range(3):  # row r of C = A X, then the three rows of Xᵀ C
        c0 = A[r, 0] + A[r, 1] * x10 + A[r, 2] * x20
        c1 = A[r, 1] * c - A[r, 2] * s
        c2 = A[r, 1] * s + A[r, 2] * c
        # (Xᵀ C)[k, j] = Σ_r X[r, k] C[r, j]; X[:, 0] = (1, x10, x20), X[:, 1] = (0, c, −s), X[:, 2] = (0, s, c)
        xr0 = 1.0 if r == 0 else (x10 if r == 1 else x20)
        xr1 = 0.0 if r == 0 else (c if r == 1 else -s)
        xr2 = 0.0 if r == 0 else (s if r == 1 else c)
        B[0, 0] += xr0 * c0
        B[0, 1] += xr0 * c1
        B[0, 2] += xr0 * c2
        B[1, 0] += xr1 * c0
        B[1, 1] += xr1 * c1
        B[1, 2] += xr1 * c2
        B[2, 0] += xr2 * c0
        B[2, 1] += xr2 * c1
        B[2, 2] += xr2 * c2


@njit(cache=True)
def kinematics(M, q, qd, pose, X, v, cbias):
    """World poses, parent→link transforms, link velocities and velocity-product terms."""
    for i in range(q.shape[0]):
        p = M.parent[i]
        a0, rx, rz = M.xtree[i, 0], M.xtree[i, 1], M.xtree[i, 2]
        if p >= 0:
            thp, xp, zp = pose[p, 0], pose[p, 1], pose[p, 2]
            vp0, vp1, vp2 = v[p, 0], v[p, 1], v[p, 2]
        else:
            thp, xp, zp = 0.0, 0.0, 0.0
            vp0, vp1, vp2 = 0.0, 0.0, 0.0
        cp, sp = np.cos(thp), np.sin(thp)
        jx = xp + cp * rx - sp * rz
        jz = zp + sp * rx + cp * rz
        jt = M.jtype[i]
        if jt == REVOLUTE:
            ang = a0 + q[i]
            pose[i, 0], pose[i, 1], pose[i, 2] = thp + ang, jx, jz
        else:
            ang = a0
            dx, dz = (q[i], 0.0) if jt == SLIDE_X else (0.0, q[i])
            ca, sa = np.cos(a0), np.sin(a0)
            rx, rz = rx + ca * dx - sa * dz, rz + sa * dx + ca * dz
            cw, sw = np.cos(thp + a0), np.sin(thp + a0)
            pose[i, 0], pose[i, 1], pose[i, 2] = thp + a0, jx + cw * dx - sw * dz, jz + sw * dx + cw * dz
        c, s = np.cos(ang), np.sin(ang)
        X[i, 0], X[i, 1], X[i, 2], X[i, 3] = c, s, s * rx - c * rz, c * rx + s * rz
        m0, m1, m2 = _xm(X[i], vp0, vp1, vp2)
        w = qd[i]
        if jt == REVOLUTE:
            m0 += w
            # crm(v) · S w with S = e0
            cbias[i, 0], cbias[i, 1], cbias[i, 2] = 0.0, m2 * w, -m1 * w
        elif jt == SLIDE_X:
            m1 += w
            cbias[i, 0], cbias[i, 1], cbias[i, 2] = 0.0, 0.0, m0 * w
        else:
            m2 += w
            cbias[i, 0], cbias[i, 1], cbias[i, 2] = 0.0, -m0 * w, 0.0
        v[i, 0], v[i, 1], v[i, 2] = m0, m1, m2


@njit(cache=True, inline="always")
def link_inertia(M, i, I):
    """Spatial inertia of link i about its origin, in link coordinates (mcI)."""
    m, cx, cz = M.mass[i], M.com[i, 0], M.com[i, 1]
    I[0, 0] = M.icom[i] + m * (cx * cx + cz * cz)
    I[0, 1] = I[1, 0] = -m * cz
    I[0, 2] = I[2, 0] = m * cx
    I[1, 1] = I[2, 2] = m
    I[1, 2] = I[2, 1] = 0.0


@njit(cache=True)
def aba(M, qd, X, v, cbias, tau, fext, presc, presc_qdd, gravity, IA, pA, a, qdd, Ia):
    """Articulated-body forward dynamics with prescribed accelerations (hybrid).

    ``presc[i] != 0`` marks dof i as kinematic: its acceleration is
    ``presc_qdd[i]``; on return ``tau[i]`` holds the torque that realises it.
    ``fext[i]`` is the external spatial force on link i in link coordinates;
    ``Ia`` is a 3×3 scratch.
    """
    nl = qd.shape[0]
    for i in range(nl):
        link_inertia(M, i, IA[i])
        h0 = IA[i, 0, 0] * v[i, 0] + IA[i, 0, 1] * v[i, 1] + IA[i, 0, 2] * v[i, 2]
        h1 = IA[i, 1, 0] * v[i, 0] + IA[i, 1, 1] * v[i, 1]
        h2 = IA[i, 2, 0] * v[i, 0] + IA[i, 2, 2] * v[i, 2]
        # crf(v) · h  =  (−vz h1 + vx h2, −ω h2, ω h1)
        pA[i, 0] = -v[i, 2] * h1 + v[i, 1] * h2 - fext[i, 0]
        pA[i, 1] = -v[i, 0] * h2 - fext[i, 1]
        pA[i, 2] = v[i, 0] * h1 - fext[i, 2]
    for i in range(nl - 1, -1, -1):
        k = M.jtype[i]
        p = M.parent[i]
        if presc[i]:
            # the joint moves as told: the parent sees the whole articulated inertia
            w = presc_qdd[i]
            for r in range(3):
                for col in range(3):
                    Ia[r, col] = IA[i, r, col]
            e0 = cbias[i, 0] + (w if k == 0 else 0.0)
            e1 = cbias[i, 1] + (w if k == 1 else 0.0)
            e2 = cbias[i, 2] + (w if k == 2 else 0.0)
            pa0 = pA[i, 0] + Ia[0, 0] * e0 + Ia[0, 1] * e1 + Ia[0, 2] * e2
            pa1 = pA[i, 1] + Ia[1, 0] * e0 + Ia[1, 1] * e1 + Ia[1, 2] * e2
            pa2 = pA[i, 2] + Ia[2, 0] * e0 + Ia[2, 1] * e1 + Ia[2, 2] * e2
        else:
            d = IA[i, k, k]
            u = tau[i] - pA[i, k]
            for r in range(3):
                for col in range(3):
                    Ia[r, col] = IA[i, r, col] - IA[i, r, k] * IA[i, col, k] / d
            e0, e1, e2 = cbias[i, 0], cbias[i, 1], cbias[i, 2]
            ud = u / d
            pa0 = pA[i, 0] + Ia[0, 0] * e0 + Ia[0, 1] * e1 + Ia[0, 2] * e2 + IA[i, 0, k] * ud
            pa1 = pA[i, 1] + Ia[1, 0] * e0 + Ia[1, 1] * e1 + Ia[1, 2] * e2 + IA[i, 1, k] * ud
            pa2 = pA[i, 2] + Ia[2, 0] * e0 + Ia[2, 1] * e1 + Ia[2, 2] * e2 + IA[i, 2, k] * ud
        if p >= 0:
            _add_xtix(X[i], Ia, IA[p])
            f0, f1, f2 = _xtf(X[i], pa0, pa1, pa2)
            pA[p, 0] += f0
            pA[p, 1] += f1
            pA[p, 2] += f2
    for i in range(nl):
        p = M.parent[i]
        if p >= 0:
            ap0, ap1, ap2 = a[p, 0], a[p, 1], a[p, 2]
        else:
            ap0, ap1, ap2 = 0.0, 0.0, gravity  # fictitious base acceleration
        a0, a1, a2 = _xm(X[i], ap0, ap1, ap2)
        a0 += cbias[i, 0]
        a1 += cbias[i, 1]
        a2 += cbias[i, 2]
        k = M.jtype[i]
        if presc[i]:
            acc = presc_qdd[i]
        else:
            acc = (tau[i] - pA[i, k] - (IA[i, 0, k] * a0 + IA[i, 1, k] * a1 + IA[i, 2, k] * a2)) / IA[i, k, k]
        qdd[i] = acc
        if k == 0:
            a0 += acc
        elif k == 1:
            a1 += acc
        else:
            a2 += acc
        a[i, 0], a[i, 1], a[i, 2] = a0, a1, a2
        if presc[i]:
            tau[i] = IA[i, 0, k] * a0 + IA[i, 1, k] * a1 + IA[i, 2, k] * a2 + pA[i, k]


@njit(cache=True, inline="always")
def point_world(M, pose, link, px, pz):
    """World position of a point given in link coordinates (link −1: fixed root)."""
    if link >= 0:
        th, x, z = pose[link, 0], pose[link, 1], pose[link, 2]
    else:
        th, x, z = M.fixed_pose[0], M.fixed_pose[1], M.fixed_pose[2]
    c, s = np.cos(th), np.sin(th)
    return x + c * px - s * pz, z + s * px + c * pz


@njit(cache=True, inline="always")
def point_velocity(pose, v, link, px, pz):
    """World velocity of a point given in link coordinates."""
    if link < 0:
        return 0.0, 0.0
    w = v[link, 0]
    lx, lz = v[link, 1] - w * pz, v[link, 2] + w * px
    c, s = np.cos(pose[link, 0]), np.sin(pose[link, 0])
    return c * lx - s * lz, s * lx + c * lz


@njit(cache=True, inline="always")
def apply_point_force(pose, fext, link, px, pz, fx, fz):
    """Add a world force (fx, fz) acting at a link-frame point to ``fext[link]``."""
    if link < 0:
        return
    c, s = np.cos(pose[link, 0]), np.sin(pose[link, 0])
    lx, lz = c * fx + s * fz, -s * fx + c * fz
    fext[link, 0] += px * lz - pz * lx
    fext[link, 1] += lx
    fext[link, 2] += lz


@njit(cache=True)
def ground_contacts(M, S, pose, v, anchor, touching, fext, cforce):
    """Penalty ground contact with a stick–slip friction anchor per point.

    Normal: spring-damper on penetration, never pulling.  Tangential: a
    spring to the point where contact began (so a figure at rest does not
    creep), clamped at μ·Fn; when it slips the anchor is dragged along.
    """
    for k in range(M.cp_link.shape[0]):
        cforce[k] = 0.0
        if S.ground == 0:
            continue
        link = M.cp_link[k]
        px, pz = M.cp_pos[k, 0], M.cp_pos[k, 1]
        x, z = point_world(M, pose, link, px, pz)
        pen = S.ground_z - z
        if pen <= 0.0:
            touching[k] = 0.0
            continue
        vx, vz = point_velocity(pose, v, link, px, pz)
        fn = S.k_ground * pen - S.c_ground * vz
        if fn < 0.0:
            fn = 0.0
        if touching[k] == 0.0:
            anchor[k] = x
            touching[k] = 1.0
        ft = -S.k_tangent * (x - anchor[k]) - S.c_tangent * vx
        lim = S.mu * fn
        if ft > lim or ft < -lim:
            ft = lim if ft > 0 else -lim
            anchor[k] = x + (ft + S.c_tangent * vx) / S.k_tangent if S.k_tangent > 0 else x
        cforce[k] = fn
        apply_point_force(pose, fext, link, px, pz, ft, fn)


@njit(cache=True)
def pole_contacts(M, S, pose, v, fext):
    """Capsule–pole penalty contact (frictionless); returns the deepest penetration."""
    deepest = 0.0
    for j in range(S.poles.shape[0]):
        cx, cz, rp = S.poles[j, 0], S.poles[j, 1], S.poles[j, 2]
        for g in range(M.seg_link.shape[0]):
            link = M.seg_link[g]
            ax, az = point_world(M, pose, link, M.seg_a[g, 0], M.seg_a[g, 1])
            bx, bz = point_world(M, pose, link, M.seg_b[g, 0], M.seg_b[g, 1])
            dx, dz = bx - ax, bz - az
            L2 = dx * dx + dz * dz
            t = ((cx - ax) * dx + (cz - az) * dz) / L2 if L2 > 0 else 0.0
            t = min(1.0, max(0.0, t))
            qx, qz = ax + t * dx, az + t * dz
            ex, ez = qx - cx, qz - cz
            dist = np.sqrt(ex * ex + ez * ez)
            pen = M.seg_r[g] + rp - dist
            if pen <= 0.0 or dist == 0.0:
                continue
            deepest = max(deepest, pen)
            nx, nz = ex / dist, ez / dist
            lx = M.seg_a[g, 0] + t * (M.seg_b[g, 0] - M.seg_a[g, 0])
            lz = M.seg_a[g, 1] + t * (M.seg_b[g, 1] - M.seg_a[g, 1])
            vx, vz = point_velocity(pose, v, link, lx, lz)
            fn = S.k_pole * pen - S.c_pole * (vx * nx + vz * nz)
            if fn > 0.0:
                apply_point_force(pose, fext, link, lx, lz, fn * nx, fn * nz)
    return deepest


@njit(cache=True)
def joint_torques(M, q, qd, targets, taus, actuation, dt, tau, presc, presc_qdd):
    """Passive damping, joint limits, then PD servos or kinematic responses."""
    for i in range(q.shape[0]):
        tau[i] = -M.damping[i] * qd[i]
        presc[i] = 0
        # a limit is a unilateral spring-damper: it pushes back, never pulls
        if q[i] < M.lo[i]:
            tau[i] += max(0.0, M.limit_k * (M.lo[i] - q[i]) - M.limit_c * qd[i])
        elif q[i] > M.hi[i]:
            tau[i] += min(0.0, M.limit_k * (M.hi[i] - q[i]) - M.limit_c * qd[i])
    for a in range(M.act_dof.shape[0]):
        i = M.act_dof[a]
        target = targets[a]
        if not np.isfinite(target):  # a controller's NaN must not poison the physics
            target = M.neutral[a]
        target = min(M.hi[i], max(M.lo[i], target))
        if actuation == 0:
            u = M.kp[a] * (target - q[i]) - M.kd[a] * qd[i]
            tau[i] += min(M.tau_max[a], max(-M.tau_max[a], u))
        else:
            tc = max(taus[a], 2.0 * dt)
            presc[i] = 1
            presc_qdd[i] = (target - q[i] - 2.0 * tc * qd[i]) / (tc * tc)


@njit(cache=True)
def centre_of_mass(M, pose, v, com):
    """com = (x, z, vx, vz) of the moving links (a fixed root body is excluded)."""
    mt = sx = sz = svx = svz = 0.0
    for i in range(M.mass.shape[0]):
        m = M.mass[i]
        if m == 0.0:
            continue
        cx, cz = M.com[i, 0], M.com[i, 1]
        x, z = point_world(M, pose, i, cx, cz)
        vx, vz = point_velocity(pose, v, i, cx, cz)
        mt += m
        sx += m * x
        sz += m * z
        svx += m * vx
        svz += m * vz
    if mt > 0:
        com[0], com[1], com[2], com[3] = sx / mt, sz / mt, svx / mt, svz / mt


@njit(cache=True)
def mechanical_energy(M, S, q, qd, pose, v):
    """Kinetic + gravitational potential energy (for conservation tests and logs)."""
    ke = 0.0
    pe = 0.0
    I = np.empty((3, 3))
    for i in range(q.shape[0]):
        if M.mass[i] == 0.0:
            continue
        link_inertia(M, i, I)
        for r in range(3):
            for c in range(3):
                ke += 0.5 * v[i, r] * I[r, c] * v[i, c]
        x, z = point_world(M, pose, i, M.com[i, 0], M.com[i, 1])
        pe += M.mass[i] * S.gravity * z
    return ke + pe


@njit(cache=True)
def integrate(q, qd, qdd, dt, limit):
    """Semi-implicit Euler; returns False when the state is non-finite or absurd."""
    ok = True
    for i in range(q.shape[0]):
        qd[i] += dt * qdd[i]
        q[i] += dt * qd[i]
        if not (abs(q[i]) < limit and abs(qd[i]) < limit):  # also catches NaN
            ok = False
    return ok
