"""3-D articulated-body dynamics (Featherstone's ABA, 6-vector spatial algebra).

Conventions are spatial_v2's: a motion vector is ``(ω; v)``, a force vector
``(n; f)``, both in link coordinates; ``crm``, ``crf`` and ``mcI`` as in the
book.  World z is up; gravity acts along −z.

Representation (per link i, filled by :func:`kinematics`):

* ``R[i]`` (3×3) and ``pos[i]`` (3): the link frame's world orientation
  (columns = link axes in world coordinates) and origin;
* ``E[i]`` (3×3) and ``r[i]`` (3): the parent→link Plücker transform
  ``X = [[E, 0], [−E r×, E]]`` kept as its rotation ``E`` (parent → link
  coordinates) and translation ``r`` (link origin in parent coordinates).
  No 6×6 transform is ever formed: ``X v``, ``Xᵀ f`` and ``Xᵀ I X`` are
  written out over the 3×3 blocks (``Xᵀ I X`` costs ~270 multiply-adds).

Links and dofs: every link carries one dof — ``HINGE`` (rotation about the
unit ``axis`` of its joint frame) or ``SLIDE`` (translation along it),
motion subspace ``S = (axis; 0)`` or ``(0; axis)`` — except a ``FREE`` root
(link 0 only): 6 dofs, ``S = 1₆`` in body coordinates.  A free root stores
``q[0:3]`` = world position of the body origin and ``q[3:7]`` = unit
quaternion (w, x, y, z) of its orientation; ``qd[0:6]`` = its spatial
velocity in body coordinates (ω_body; v_body), so ``nq = nv + 1``.  The
link's first configuration / velocity index is ``M.qadr[i]`` / ``M.dadr[i]``.
The joint frame of link i sits at ``xpos[i]`` in its parent with orientation
``xrot[i]`` (joint→parent coordinates); the link frame is the joint frame
moved by the joint.  Parent ``−1`` is the world (or a fixed root body
folded into ``xrot``/``xpos``).

Speed notes as in ``planar.py``: allocation-free, ``inline="always"``
step kernels, ``error_model="numpy"``; articulated inertias are full 6×6
(``IA[nl, 6, 6]``).  The plain-numpy twins (RNEA + CRBA + dense solve) are
in ``tests/reference/spatial3d_ref.py``.
"""
from __future__ import annotations

import numpy as np
from numba import njit

HINGE, SLIDE, FREE = 0, 1, 2

_JIT = dict(cache=True, error_model="numpy", boundscheck=False)
_INLINE = dict(_JIT, inline="always")

# ---------------------------------------------------------------- senses
BODY_SENSES3D = ("px", "py", "pz", "vx", "vy", "vz", "roll", "pitch", "yaw",
                 "wx", "wy", "wz", "up_x", "up_y", "up_z", "com_z", "com_vz", "t")
N_BODY3D = len(BODY_SENSES3D)
DEFAULT_RANGES3D = {"px": (-2.0, 2.0), "py": (-2.0, 2.0), "pz": (-1.0, 1.0),
                    "vx": (-3.0, 3.0), "vy": (-3.0, 3.0), "vz": (-3.0, 3.0),
                    "roll": (-np.pi, np.pi), "pitch": (-np.pi / 2, np.pi / 2),
                    "yaw": (-np.pi, np.pi), "wx": (-10.0, 10.0), "wy": (-10.0, 10.0),
                    "wz": (-10.0, 10.0), "up_x": (-1.0, 1.0), "up_y": (-1.0, 1.0),
                    "up_z": (-1.0, 1.0), "com_z": (0.0, 2.0), "com_vz": (-3.0, 3.0),
                    "t": (0.0, 5.0), "rate": (-10.0, 10.0)}


def sense_layout3d(actuators, contacts, lo, hi, total_mass, overrides):
    """Names and (lo, hi) ranges of the sense vector of a 3-D figure.

    Layout: the body senses ``BODY_SENSES3D`` (base position relative to
    the goal, base world velocity, roll/pitch/yaw, world angular velocity,
    the base's up vector (its z axis in world), com height and vertical
    velocity, time), then ``angle_<dof>``, ``rate_<dof>`` per actuated dof
    and ``force_<contact>`` per contact point.
    """
    r = dict(DEFAULT_RANGES3D)
    r["force"] = (0.0, 2.0 * max(total_mass, 1e-3) * 9.81)
    r.update(overrides)
    names, los, his = [], [], []

    def add(name, rng):
        names.append(name)
        los.append(float(rng[0]))
        his.append(float(rng[1]))

    for n in BODY_SENSES3D:
        add(n, r[n])
    for a, l_, h in zip(actuators, lo, hi):
        lo_, hi_ = (l_, h) if np.isfinite(l_) and np.isfinite(h) else (-np.pi, np.pi)
        add(f"angle_{a}", r.get(f"angle_{a}", (lo_, hi_)))
    for a in actuators:
        add(f"rate_{a}", r.get(f"rate_{a}", r["rate"]))
    for c in contacts:
        add(f"force_{c}", r.get(f"force_{c}", r["force"]))
    return names, np.array(los), np.array(his)


# ---------------------------------------------------------------- kinematics
@njit(**_INLINE)
def quat_to_rot(w, x, y, z, R, i):
    """R[i] = rotation matrix of the unit quaternion (w, x, y, z)."""
    R[i, 0, 0] = 1.0 - 2.0 * (y * y + z * z)
    R[i, 0, 1] = 2.0 * (x * y - w * z)
    R[i, 0, 2] = 2.0 * (x * z + w * y)
    R[i, 1, 0] = 2.0 * (x * y + w * z)
    R[i, 1, 1] = 1.0 - 2.0 * (x * x + z * z)
    R[i, 1, 2] = 2.0 * (y * z - w * x)
    R[i, 2, 0] = 2.0 * (x * z - w * y)
    R[i, 2, 1] = 2.0 * (y * z + w * x)
    R[i, 2, 2] = 1.0 - 2.0 * (x * x + y * y)


@njit(**_INLINE)
def kinematics(M, q, qd, R, pos, E, r, v, cbias):
    """World frames, parent→link transforms, link velocities and c = crm(v)·S·q̇."""
    nl = M.parent.shape[0]
    for i in range(nl):
        p = M.parent[i]
        jt = M.jtype[i]
        qa = M.qadr[i]
        da = M.dadr[i]
        if jt == FREE:
            w, x, y, z = q[qa + 3], q[qa + 4], q[qa + 5], q[qa + 6]
            quat_to_rot(w, x, y, z, R, i)
            for a in range(3):
                pos[i, a] = q[qa + a]
                r[i, a] = q[qa + a]
                for b in range(3):
                    E[i, a, b] = R[i, b, a]
            for a in range(6):
                v[i, a] = qd[da + a]
                cbias[i, a] = 0.0
            continue
        ax, ay, az = M.axis[i, 0], M.axis[i, 1], M.axis[i, 2]
        qi = q[qa]
        wq = qd[da]
        # joint motion: RJ (joint→link rotation), dj (translation in joint coords)
        if jt == HINGE:
            c, s = np.cos(qi), np.sin(qi)
            t = 1.0 - c
            j00, j01, j02 = c + t * ax * ax, t * ax * ay - s * az, t * ax * az + s * ay
            j10, j11, j12 = t * ax * ay + s * az, c + t * ay * ay, t * ay * az - s * ax
            j20, j21, j22 = t * ax * az - s * ay, t * ay * az + s * ax, c + t * az * az
            dx, dy, dz = 0.0, 0.0, 0.0
        else:
            j00, j01, j02 = 1.0, 0.0, 0.0
            j10, j11, j12 = 0.0, 1.0, 0.0
            j20, j21, j22 = 0.0, 0.0, 1.0
            dx, dy, dz = ax * qi, ay * qi, az * qi
        # Rrel = xrot · RJ  (link→parent); E = Rrelᵀ
        for a in range(3):
            x0, x1, x2 = M.xrot[i, a, 0], M.xrot[i, a, 1], M.xrot[i, a, 2]
            E[i, 0, a] = x0 * j00 + x1 * j10 + x2 * j20
            E[i, 1, a] = x0 * j01 + x1 * j11 + x2 * j21
            E[i, 2, a] = x0 * j02 + x1 * j12 + x2 * j22
            r[i, a] = M.xpos[i, a] + x0 * dx + x1 * dy + x2 * dz
        r0, r1, r2 = r[i, 0], r[i, 1], r[i, 2]
        pp = max(p, 0)
        if p >= 0:
            # R = R_p · Rrel,  pos = pos_p + R_p · r
            for a in range(3):
                p0, p1, p2 = R[pp, a, 0], R[pp, a, 1], R[pp, a, 2]
                for b in range(3):
                    R[i, a, b] = p0 * E[i, b, 0] + p1 * E[i, b, 1] + p2 * E[i, b, 2]
                pos[i, a] = pos[pp, a] + p0 * r0 + p1 * r1 + p2 * r2
            w0, w1, w2 = v[pp, 0], v[pp, 1], v[pp, 2]
            u0, u1, u2 = v[pp, 3], v[pp, 4], v[pp, 5]
        else:
            for a in range(3):
                for b in range(3):
                    R[i, a, b] = E[i, b, a]
                pos[i, a] = r[i, a]
            w0, w1, w2 = 0.0, 0.0, 0.0
            u0, u1, u2 = 0.0, 0.0, 0.0
        # v = X v_p :  ω = E ω_p,  v = E (v_p − r × ω_p)
        l0 = u0 - (r1 * w2 - r2 * w1)
        l1 = u1 - (r2 * w0 - r0 * w2)
        l2 = u2 - (r0 * w1 - r1 * w0)
        for a in range(3):
            e0, e1, e2 = E[i, a, 0], E[i, a, 1], E[i, a, 2]
            v[i, a] = e0 * w0 + e1 * w1 + e2 * w2
            v[i, 3 + a] = e0 * l0 + e1 * l1 + e2 * l2
        om0, om1, om2 = v[i, 0], v[i, 1], v[i, 2]
        vl0, vl1, vl2 = v[i, 3], v[i, 4], v[i, 5]
        s0, s1, s2 = ax * wq, ay * wq, az * wq
        if jt == HINGE:
            # crm(v)·(s; 0) = (ω × s; v × s)
            cbias[i, 0] = om1 * s2 - om2 * s1
            cbias[i, 1] = om2 * s0 - om0 * s2
            cbias[i, 2] = om0 * s1 - om1 * s0
            cbias[i, 3] = vl1 * s2 - vl2 * s1
            cbias[i, 4] = vl2 * s0 - vl0 * s2
            cbias[i, 5] = vl0 * s1 - vl1 * s0
            v[i, 0] = om0 + s0
            v[i, 1] = om1 + s1
            v[i, 2] = om2 + s2
        else:
            # crm(v)·(0; s) = (0; ω × s)
            cbias[i, 0] = 0.0
            cbias[i, 1] = 0.0
            cbias[i, 2] = 0.0
            cbias[i, 3] = om1 * s2 - om2 * s1
            cbias[i, 4] = om2 * s0 - om0 * s2
            cbias[i, 5] = om0 * s1 - om1 * s0
            v[i, 3] = vl0 + s0
            v[i, 4] = vl1 + s1
            v[i, 5] = vl2 + s2


# ---------------------------------------------------------------- dynamics
@njit(**_INLINE)
def link_inertia(M, i, I):
    """Spatial inertia of link i about its origin in link coordinates (mcI) → ``I[i]`` (6×6)."""
    m = M.mass[i]
    cx, cy, cz = M.com[i, 0], M.com[i, 1], M.com[i, 2]
    cc = cx * cx + cy * cy + cz * cz
    for a in range(3):
        for b in range(3):
            I[i, a, b] = M.icom[i, a, b]
            I[i, 3 + a, 3 + b] = 0.0
        I[i, 3 + a, 3 + a] = m
    # Ic + m (c·c 1 − c cᵀ)
    I[i, 0, 0] += m * (cc - cx * cx)
    I[i, 1, 1] += m * (cc - cy * cy)
    I[i, 2, 2] += m * (cc - cz * cz)
    I[i, 0, 1] -= m * cx * cy
    I[i, 1, 0] -= m * cx * cy
    I[i, 0, 2] -= m * cx * cz
    I[i, 2, 0] -= m * cx * cz
    I[i, 1, 2] -= m * cy * cz
    I[i, 2, 1] -= m * cy * cz
    # m c× (upper right) and its transpose −m c× (lower left)
    I[i, 0, 3], I[i, 0, 4], I[i, 0, 5] = 0.0, -m * cz, m * cy
    I[i, 1, 3], I[i, 1, 4], I[i, 1, 5] = m * cz, 0.0, -m * cx
    I[i, 2, 3], I[i, 2, 4], I[i, 2, 5] = -m * cy, m * cx, 0.0
    I[i, 3, 0], I[i, 3, 1], I[i, 3, 2] = 0.0, m * cz, -m * cy
    I[i, 4, 0], I[i, 4, 1], I[i, 4, 2] = -m * cz, 0.0, m * cx
    I[i, 5, 0], I[i, 5, 1], I[i, 5, 2] = m * cy, -m * cx, 0.0


@njit(**_INLINE)
def _solve6(A, i, b, L, x):
    """x = A[i]⁻¹ b by Cholesky (A[i] symmetric positive definite), L scratch 6×6."""
    for j in range(6):
        s = A[i, j, j]
        for k in range(j):
            s -= L[j, k] * L[j, k]
        ljj = np.sqrt(s)
        L[j, j] = ljj
        for m in range(j + 1, 6):
            t = A[i, m, j]
            for k in range(j):
                t -= L[m, k] * L[j, k]
            L[m, j] = t / ljj
    for j in range(6):
        t = b[j]
        for k in range(j):
            t -= L[j, k] * x[k]
        x[j] = t / L[j, j]
    for j in range(5, -1, -1):
        t = x[j]
        for k in range(j + 1, 6):
            t -= L[k, j] * x[k]
        x[j] = t / L[j, j]


@njit(**_INLINE)
def aba(M, qd, E, r, v, cbias, tau, fext, presc, presc_qdd, gravity, IA, pA, U, dinv, uu, a,
        qdd, work, vec):
    """Articulated-body forward dynamics with prescribed accelerations (hybrid).

    ``presc[d] != 0`` marks dof d (of a 1-dof link) as kinematic: its
    acceleration is ``presc_qdd[d]``; on return ``tau[d]`` holds the force
    that realises it.  ``fext[i]`` is the external spatial force on link i
    in link coordinates.  Scratch: ``IA[nl, 6, 6]``, ``pA[nl, 6]``,
    ``U[nl, 6]``, ``dinv[nl]``, ``uu[nl]``, ``a[nl, 6]``, ``work[3, 6, 6]``,
    ``vec[3, 6]``.
    """
    nl = M.parent.shape[0]
    for i in range(nl):
        link_inertia(M, i, IA)
        w0, w1, w2, l0, l1, l2 = v[i, 0], v[i, 1], v[i, 2], v[i, 3], v[i, 4], v[i, 5]
        for k in range(6):
            vec[0, k] = (IA[i, k, 0] * w0 + IA[i, k, 1] * w1 + IA[i, k, 2] * w2 +
                         IA[i, k, 3] * l0 + IA[i, k, 4] * l1 + IA[i, k, 5] * l2)
        h0, h1, h2, f0, f1, f2 = vec[0, 0], vec[0, 1], vec[0, 2], vec[0, 3], vec[0, 4], vec[0, 5]
        # crf(v)·h = (ω × hn + v × hf; ω × hf)
        pA[i, 0] = w1 * h2 - w2 * h1 + l1 * f2 - l2 * f1 - fext[i, 0]
        pA[i, 1] = w2 * h0 - w0 * h2 + l2 * f0 - l0 * f2 - fext[i, 1]
        pA[i, 2] = w0 * h1 - w1 * h0 + l0 * f1 - l1 * f0 - fext[i, 2]
        pA[i, 3] = w1 * f2 - w2 * f1 - fext[i, 3]
        pA[i, 4] = w2 * f0 - w0 * f2 - fext[i, 4]
        pA[i, 5] = w0 * f1 - w1 * f0 - fext[i, 5]
    for i in range(nl - 1, -1, -1):
        jt = M.jtype[i]
        if jt == FREE:
            continue                   # the root: solved in the forward pass
        p = M.parent[i]
        da = M.dadr[i]
        ax, ay, az = M.axis[i, 0], M.axis[i, 1], M.axis[i, 2]
        off = 0 if jt == HINGE else 3
        pr, w, ti = presc[da], presc_qdd[da], tau[da]
        for k in range(6):
            U[i, k] = IA[i, k, off] * ax + IA[i, k, off + 1] * ay + IA[i, k, off + 2] * az
        d = U[i, off] * ax + U[i, off + 1] * ay + U[i, off + 2] * az
        sp = pA[i, off] * ax + pA[i, off + 1] * ay + pA[i, off + 2] * az
        for k in range(6):
            vec[1, k] = cbias[i, k]
        if pr:
            # the joint moves as told: the parent sees the whole articulated inertia
            vec[1, off] += ax * w
            vec[1, off + 1] += ay * w
            vec[1, off + 2] += az * w
            di = 0.0
            ud = 0.0
            for k in range(6):
                for m in range(6):
                    work[0, k, m] = IA[i, k, m]
        else:
            di = 1.0 / d
            ud = (ti - sp) * di
            for k in range(6):
                uk = U[i, k] * di
                for m in range(6):
                    work[0, k, m] = IA[i, k, m] - uk * U[i, m]
        dinv[i] = di
        uu[i] = ti - sp
        # pa = pA + Ia c + U u/d
        for k in range(6):
            s = pA[i, k] + U[i, k] * ud
            for m in range(6):
                s += work[0, k, m] * vec[1, m]
            vec[2, k] = s
        if p >= 0:
            r0, r1, r2 = r[i, 0], r[i, 1], r[i, 2]
            # F = −E r×: row b of F is r × (row b of E)
            for b in range(3):
                e0, e1, e2 = E[i, b, 0], E[i, b, 1], E[i, b, 2]
                work[2, b, 0] = r1 * e2 - r2 * e1
                work[2, b, 1] = r2 * e0 - r0 * e2
                work[2, b, 2] = r0 * e1 - r1 * e0
            # W = Ia X,  X = [[E, 0], [F, E]]
            for k in range(6):
                for b in range(3):
                    s0 = 0.0
                    s1 = 0.0
                    for m in range(3):
                        s0 += work[0, k, m] * E[i, m, b] + work[0, k, 3 + m] * work[2, m, b]
                        s1 += work[0, k, 3 + m] * E[i, m, b]
                    work[1, k, b] = s0
                    work[1, k, 3 + b] = s1
            # IA[p] += Xᵀ W,  Xᵀ = [[Eᵀ, Fᵀ], [0, Eᵀ]]
            for b in range(3):
                for k in range(6):
                    s0 = 0.0
                    s1 = 0.0
                    for m in range(3):
                        s0 += E[i, m, b] * work[1, m, k] + work[2, m, b] * work[1, 3 + m, k]
                        s1 += E[i, m, b] * work[1, 3 + m, k]
                    IA[p, b, k] += s0
                    IA[p, 3 + b, k] += s1
            for b in range(3):
                s0 = 0.0
                s1 = 0.0
                for m in range(3):
                    s0 += E[i, m, b] * vec[2, m] + work[2, m, b] * vec[2, 3 + m]
                    s1 += E[i, m, b] * vec[2, 3 + m]
                pA[p, b] += s0
                pA[p, 3 + b] += s1
    for i in range(nl):
        p = M.parent[i]
        jt = M.jtype[i]
        da = M.dadr[i]
        pp = max(p, 0)
        if p >= 0:
            b0, b1, b2, b3, b4, b5 = a[pp, 0], a[pp, 1], a[pp, 2], a[pp, 3], a[pp, 4], a[pp, 5]
        else:
            b0, b1, b2, b3, b4, b5 = 0.0, 0.0, 0.0, 0.0, 0.0, gravity  # fictitious base acceleration
        r0, r1, r2 = r[i, 0], r[i, 1], r[i, 2]
        l0 = b3 - (r1 * b2 - r2 * b1)
        l1 = b4 - (r2 * b0 - r0 * b2)
        l2 = b5 - (r0 * b1 - r1 * b0)
        for k in range(3):
            e0, e1, e2 = E[i, k, 0], E[i, k, 1], E[i, k, 2]
            a[i, k] = e0 * b0 + e1 * b1 + e2 * b2 + cbias[i, k]
            a[i, 3 + k] = e0 * l0 + e1 * l1 + e2 * l2 + cbias[i, 3 + k]
        if jt == FREE:
            for k in range(6):
                s = tau[da + k] - pA[i, k]
                for m in range(6):
                    s -= IA[i, k, m] * a[i, m]
                vec[0, k] = s
            _solve6(IA, i, vec[0], work[0], vec[1])
            for k in range(6):
                qdd[da + k] = vec[1, k]
                a[i, k] += vec[1, k]
            continue
        ax, ay, az = M.axis[i, 0], M.axis[i, 1], M.axis[i, 2]
        off = 0 if jt == HINGE else 3
        pr, w = presc[da], presc_qdd[da]
        ua = 0.0
        for k in range(6):
            ua += U[i, k] * a[i, k]
        if pr:
            acc = w
        else:
            acc = (uu[i] - ua) * dinv[i]
        qdd[da] = acc
        a[i, off] += ax * acc
        a[i, off + 1] += ay * acc
        a[i, off + 2] += az * acc
        if pr:
            s = pA[i, off] * ax + pA[i, off + 1] * ay + pA[i, off + 2] * az
            for k in range(6):
                s += U[i, k] * a[i, k]
            tau[da] = s


# ---------------------------------------------------------------- contacts
@njit(**_INLINE)
def point_world(R, pos, link, px, py, pz):
    """World position of a point given in link coordinates (link >= 0)."""
    return (pos[link, 0] + R[link, 0, 0] * px + R[link, 0, 1] * py + R[link, 0, 2] * pz,
            pos[link, 1] + R[link, 1, 0] * px + R[link, 1, 1] * py + R[link, 1, 2] * pz,
            pos[link, 2] + R[link, 2, 0] * px + R[link, 2, 1] * py + R[link, 2, 2] * pz)


@njit(**_INLINE)
def fixed_point_world(FR, Fp, px, py, pz):
    """World position of a point on a fixed root body (link −1)."""
    return (Fp[0] + FR[0, 0] * px + FR[0, 1] * py + FR[0, 2] * pz,
            Fp[1] + FR[1, 0] * px + FR[1, 1] * py + FR[1, 2] * pz,
            Fp[2] + FR[2, 0] * px + FR[2, 1] * py + FR[2, 2] * pz)


@njit(**_INLINE)
def point_velocity(R, v, link, px, py, pz):
    """World velocity of a link-frame point: R (v + ω × p) (zero on a fixed root)."""
    if link < 0:
        return 0.0, 0.0, 0.0
    w0, w1, w2 = v[link, 0], v[link, 1], v[link, 2]
    l0 = v[link, 3] + w1 * pz - w2 * py
    l1 = v[link, 4] + w2 * px - w0 * pz
    l2 = v[link, 5] + w0 * py - w1 * px
    return (R[link, 0, 0] * l0 + R[link, 0, 1] * l1 + R[link, 0, 2] * l2,
            R[link, 1, 0] * l0 + R[link, 1, 1] * l1 + R[link, 1, 2] * l2,
            R[link, 2, 0] * l0 + R[link, 2, 1] * l1 + R[link, 2, 2] * l2)


@njit(**_INLINE)
def apply_point_force(R, fext, link, px, py, pz, fx, fy, fz):
    """Add a world force acting at a link-frame point to ``fext[link]`` (link coords)."""
    if link < 0:
        return
    l0 = R[link, 0, 0] * fx + R[link, 1, 0] * fy + R[link, 2, 0] * fz
    l1 = R[link, 0, 1] * fx + R[link, 1, 1] * fy + R[link, 2, 1] * fz
    l2 = R[link, 0, 2] * fx + R[link, 1, 2] * fy + R[link, 2, 2] * fz
    fext[link, 0] += py * l2 - pz * l1
    fext[link, 1] += pz * l0 - px * l2
    fext[link, 2] += px * l1 - py * l0
    fext[link, 3] += l0
    fext[link, 4] += l1
    fext[link, 5] += l2


@njit(**_INLINE)
def ground_contacts(M, S, R, pos, v, anchor, touching, fext, cforce):
    """Penalty ground contact with a 2-D stick–slip friction anchor per point.

    Normal: spring-damper on penetration, never pulling.  Tangential: a
    spring in the ground plane to the point where contact began, clamped
    at μ·Fn (the force's magnitude); when it slips the anchor is dragged.
    """
    ground, ground_z, k_ground, c_ground = S.ground, S.ground_z, S.k_ground, S.c_ground
    k_tangent, c_tangent, mu = S.k_tangent, S.c_tangent, S.mu
    FR, Fp = M.fixed_rot, M.fixed_pos
    for k in range(M.cp_link.shape[0]):
        cforce[k] = 0.0
        if ground == 0:
            continue
        link = M.cp_link[k]
        px, py, pz = M.cp_pos[k, 0], M.cp_pos[k, 1], M.cp_pos[k, 2]
        if link >= 0:
            x, y, z = point_world(R, pos, link, px, py, pz)
        else:
            x, y, z = fixed_point_world(FR, Fp, px, py, pz)
        pen = ground_z - z
        if pen <= 0.0:
            touching[k] = 0.0
            continue
        vx, vy, vz = point_velocity(R, v, link, px, py, pz)
        fn = k_ground * pen - c_ground * vz
        if fn < 0.0:
            fn = 0.0
        if touching[k] == 0.0:
            anchor[k, 0] = x
            anchor[k, 1] = y
            touching[k] = 1.0
        fx = -k_tangent * (x - anchor[k, 0]) - c_tangent * vx
        fy = -k_tangent * (y - anchor[k, 1]) - c_tangent * vy
        lim = mu * fn
        ft2 = fx * fx + fy * fy
        if ft2 > lim * lim:
            sc = lim / np.sqrt(ft2)
            fx *= sc
            fy *= sc
            if k_tangent > 0:
                anchor[k, 0] = x + (fx + c_tangent * vx) / k_tangent
                anchor[k, 1] = y + (fy + c_tangent * vy) / k_tangent
            else:
                anchor[k, 0] = x
                anchor[k, 1] = y
        cforce[k] = fn
        apply_point_force(R, fext, link, px, py, pz, fx, fy, fn)


@njit(**_JIT)
def pole_contacts(M, S, R, pos, v, fext):
    """Capsule–pole penalty contact (frictionless); returns the deepest penetration.

    Poles are the planar scene's horizontal poles: infinite cylinders along
    y through (x, z), so the distance is taken in the x–z projection.
    """
    k_pole, c_pole = S.k_pole, S.c_pole
    FR, Fp = M.fixed_rot, M.fixed_pos
    deepest = 0.0
    for j in range(S.poles.shape[0]):
        cx, cz, rp = S.poles[j, 0], S.poles[j, 1], S.poles[j, 2]
        for g in range(M.seg_link.shape[0]):
            link = M.seg_link[g]
            sa0, sa1, sa2 = M.seg_a[g, 0], M.seg_a[g, 1], M.seg_a[g, 2]
            sb0, sb1, sb2 = M.seg_b[g, 0], M.seg_b[g, 1], M.seg_b[g, 2]
            rr = M.seg_r[g]
            if link >= 0:
                ax, ay, az = point_world(R, pos, link, sa0, sa1, sa2)
                bx, by, bz = point_world(R, pos, link, sb0, sb1, sb2)
            else:
                ax, ay, az = fixed_point_world(FR, Fp, sa0, sa1, sa2)
                bx, by, bz = fixed_point_world(FR, Fp, sb0, sb1, sb2)
            dx, dz = bx - ax, bz - az
            L2 = dx * dx + dz * dz
            t = ((cx - ax) * dx + (cz - az) * dz) / L2 if L2 > 0 else 0.0
            t = min(1.0, max(0.0, t))
            qx, qz = ax + t * dx, az + t * dz
            ex, ez = qx - cx, qz - cz
            dist = np.sqrt(ex * ex + ez * ez)
            pen = rr + rp - dist
            if pen <= 0.0 or dist == 0.0:
                continue
            deepest = max(deepest, pen)
            nx, nz = ex / dist, ez / dist
            lx = sa0 + t * (sb0 - sa0)
            ly = sa1 + t * (sb1 - sa1)
            lz = sa2 + t * (sb2 - sa2)
            vx, vy, vz = point_velocity(R, v, link, lx, ly, lz)
            fn = k_pole * pen - c_pole * (vx * nx + vz * nz)
            if fn > 0.0:
                apply_point_force(R, fext, link, lx, ly, lz, fn * nx, 0.0, fn * nz)
    return deepest


# ---------------------------------------------------------------- actuation
@njit(**_INLINE)
def joint_torques(M, q, qd, targets, taus, actuation, dt, tau, presc, presc_qdd):
    """Passive damping, joint limits, then PD servos or kinematic responses (per dof)."""
    limit_k, limit_c = M.limit_k, M.limit_c
    for d in range(qd.shape[0]):
        tau[d] = -M.damping[d] * qd[d]
        presc[d] = 0
    for i in range(M.parent.shape[0]):
        if M.jtype[i] == FREE:
            continue
        d = M.dadr[i]
        x = q[M.qadr[i]]
        lo, hi, w = M.lo[d], M.hi[d], qd[d]
        # a limit is a unilateral spring-damper: it pushes back, never pulls
        if x < lo:
            tau[d] += max(0.0, limit_k * (lo - x) - limit_c * w)
        elif x > hi:
            tau[d] += min(0.0, limit_k * (hi - x) - limit_c * w)
    for a in range(M.act_dof.shape[0]):
        d = M.act_dof[a]
        x = q[M.act_q[a]]
        target, neutral, lo, hi = targets[a], M.neutral[a], M.lo[d], M.hi[d]
        kp, kd, tau_max = M.kp[a], M.kd[a], M.tau_max[a]
        if not np.isfinite(target):  # a controller's NaN must not poison the physics
            target = neutral
        target = min(hi, max(lo, target))
        if actuation == 0:
            u = kp * (target - x) - kd * qd[d]
            tau[d] += min(tau_max, max(-tau_max, u))
        else:
            tc = max(taus[a], 2.0 * dt)
            presc[d] = 1
            presc_qdd[d] = (target - x - 2.0 * tc * qd[d]) / (tc * tc)


# ---------------------------------------------------------------- body measures
@njit(**_INLINE)
def centre_of_mass(M, R, pos, v, com):
    """com = (x, y, z, vx, vy, vz) of the moving links (a fixed root body is excluded)."""
    mt = sx = sy = sz = svx = svy = svz = 0.0
    for i in range(M.mass.shape[0]):
        m = M.mass[i]
        if m == 0.0:
            continue
        cx, cy, cz = M.com[i, 0], M.com[i, 1], M.com[i, 2]
        x, y, z = point_world(R, pos, i, cx, cy, cz)
        vx, vy, vz = point_velocity(R, v, i, cx, cy, cz)
        mt += m
        sx += m * x
        sy += m * y
        sz += m * z
        svx += m * vx
        svy += m * vy
        svz += m * vz
    if mt > 0:
        com[0], com[1], com[2] = sx / mt, sy / mt, sz / mt
        com[3], com[4], com[5] = svx / mt, svy / mt, svz / mt


@njit(**_JIT)
def mechanical_energy(M, S, R, pos, v):
    """Kinetic + gravitational potential energy (for conservation tests and logs)."""
    nl = M.parent.shape[0]
    I = np.empty((nl, 6, 6))
    ke = 0.0
    pe = 0.0
    for i in range(nl):
        if M.mass[i] == 0.0:
            continue
        link_inertia(M, i, I)
        for a in range(6):
            for b in range(6):
                ke += 0.5 * v[i, a] * I[i, a, b] * v[i, b]
        x, y, z = point_world(R, pos, i, M.com[i, 0], M.com[i, 1], M.com[i, 2])
        pe += M.mass[i] * S.gravity * z
    return ke + pe


@njit(**_INLINE)
def integrate(M, q, qd, qdd, dt, limit):
    """Semi-implicit Euler.  A free root: ω_body += dt·ω̇; the quaternion turns
    by exp(dt·ω_body) (exact for the step, then renormalized); the origin's
    world velocity ṗ += dt·R(a_lin + ω × v) and p += dt·ṗ; then
    v_body = R(new)ᵀ ṗ.  Returns False when the state is non-finite or absurd."""
    ok = True
    for i in range(M.parent.shape[0]):
        qa = M.qadr[i]
        da = M.dadr[i]
        if M.jtype[i] == FREE:
            a0, a1, a2, a3 = q[qa + 3], q[qa + 4], q[qa + 5], q[qa + 6]
            w0, w1, w2 = qd[da], qd[da + 1], qd[da + 2]
            u0, u1, u2 = qd[da + 3], qd[da + 4], qd[da + 5]
            # the origin's classical acceleration (body coords): a_lin + ω × v;
            # its world velocity ṗ is stepped in world coordinates, so a body
            # in free flight keeps its momentum exactly
            g0 = u0 + dt * (qdd[da + 3] + w1 * u2 - w2 * u1)
            g1 = u1 + dt * (qdd[da + 4] + w2 * u0 - w0 * u2)
            g2 = u2 + dt * (qdd[da + 5] + w0 * u1 - w1 * u0)
            p0 = (1.0 - 2.0 * (a2 * a2 + a3 * a3)) * g0 + 2.0 * (a1 * a2 - a0 * a3) * g1 \
                + 2.0 * (a1 * a3 + a0 * a2) * g2
            p1 = 2.0 * (a1 * a2 + a0 * a3) * g0 + (1.0 - 2.0 * (a1 * a1 + a3 * a3)) * g1 \
                + 2.0 * (a2 * a3 - a0 * a1) * g2
            p2 = 2.0 * (a1 * a3 - a0 * a2) * g0 + 2.0 * (a2 * a3 + a0 * a1) * g1 \
                + (1.0 - 2.0 * (a1 * a1 + a2 * a2)) * g2
            w0 += dt * qdd[da]
            w1 += dt * qdd[da + 1]
            w2 += dt * qdd[da + 2]
            qd[da], qd[da + 1], qd[da + 2] = w0, w1, w2
            wn = np.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
            h = 0.5 * wn * dt
            if wn > 0.0:
                sc = np.sin(h) / wn
            else:
                sc = 0.5 * dt
            c0, c1, c2, c3 = np.cos(h), sc * w0, sc * w1, sc * w2
            n0 = a0 * c0 - a1 * c1 - a2 * c2 - a3 * c3
            n1 = a0 * c1 + a1 * c0 + a2 * c3 - a3 * c2
            n2 = a0 * c2 - a1 * c3 + a2 * c0 + a3 * c1
            n3 = a0 * c3 + a1 * c2 - a2 * c1 + a3 * c0
            nn = 1.0 / np.sqrt(n0 * n0 + n1 * n1 + n2 * n2 + n3 * n3)
            n0, n1, n2, n3 = n0 * nn, n1 * nn, n2 * nn, n3 * nn
            q[qa + 3], q[qa + 4], q[qa + 5], q[qa + 6] = n0, n1, n2, n3
            q[qa] += dt * p0
            q[qa + 1] += dt * p1
            q[qa + 2] += dt * p2
            # v_body = R(new)ᵀ ṗ
            qd[da + 3] = (1.0 - 2.0 * (n2 * n2 + n3 * n3)) * p0 + 2.0 * (n1 * n2 + n0 * n3) * p1 \
                + 2.0 * (n1 * n3 - n0 * n2) * p2
            qd[da + 4] = 2.0 * (n1 * n2 - n0 * n3) * p0 + (1.0 - 2.0 * (n1 * n1 + n3 * n3)) * p1 \
                + 2.0 * (n2 * n3 + n0 * n1) * p2
            qd[da + 5] = 2.0 * (n1 * n3 + n0 * n2) * p0 + 2.0 * (n2 * n3 - n0 * n1) * p1 \
                + (1.0 - 2.0 * (n1 * n1 + n2 * n2)) * p2
        else:
            qd[da] += dt * qdd[da]
            q[qa] += dt * qd[da]
    for k in range(q.shape[0]):
        if not abs(q[k]) < limit:  # also catches NaN
            ok = False
    for k in range(qd.shape[0]):
        if not abs(qd[k]) < limit:
            ok = False
    return ok


@njit(**_INLINE)
def compute_senses3d(M, goal, q, qd, R, pos, v, com, cforce, t, senses, senses_norm):
    """Fill ``senses`` / ``senses_norm`` (layout: :func:`sense_layout3d`).

    Orientation: ``R_base = Rz(yaw) · Ry(−pitch) · Rx(roll)`` — pitch is
    positive nose-up (a rotation about −y), the planar kernel's convention,
    so a planar figure run in 3-D reports the planar pitch.
    """
    b = M.base_link
    bb = max(b, 0)
    FR, Fp = M.fixed_rot, M.fixed_pos
    r00, r01, r02 = R[bb, 0, 0], R[bb, 0, 1], R[bb, 0, 2]
    r10, r11, r12 = R[bb, 1, 0], R[bb, 1, 1], R[bb, 1, 2]
    r20, r21, r22 = R[bb, 2, 0], R[bb, 2, 1], R[bb, 2, 2]
    x, y, z = pos[bb, 0], pos[bb, 1], pos[bb, 2]
    w0, w1, w2, l0, l1, l2 = v[bb, 0], v[bb, 1], v[bb, 2], v[bb, 3], v[bb, 4], v[bb, 5]
    f00, f01, f02 = FR[0, 0], FR[0, 1], FR[0, 2]
    f10, f11, f12 = FR[1, 0], FR[1, 1], FR[1, 2]
    f20, f21, f22 = FR[2, 0], FR[2, 1], FR[2, 2]
    fx, fy, fz = Fp[0], Fp[1], Fp[2]
    if b < 0:                       # a fixed root: the base does not move
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = f00, f01, f02, f10, f11, f12, f20, f21, f22
        x, y, z = fx, fy, fz
        w0, w1, w2, l0, l1, l2 = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    senses[0] = x - goal[0]
    senses[1] = y - goal[1]
    senses[2] = z - goal[2]
    senses[3] = r00 * l0 + r01 * l1 + r02 * l2
    senses[4] = r10 * l0 + r11 * l1 + r12 * l2
    senses[5] = r20 * l0 + r21 * l1 + r22 * l2
    senses[6] = np.arctan2(r21, r22)
    senses[7] = np.arcsin(min(1.0, max(-1.0, r20)))
    senses[8] = np.arctan2(r10, r00)
    senses[9] = r00 * w0 + r01 * w1 + r02 * w2
    senses[10] = r10 * w0 + r11 * w1 + r12 * w2
    senses[11] = r20 * w0 + r21 * w1 + r22 * w2
    senses[12] = r02
    senses[13] = r12
    senses[14] = r22
    senses[15] = com[2]
    senses[16] = com[5]
    senses[17] = t
    nb = 18
    na = M.act_dof.shape[0]
    for a in range(na):
        senses[nb + a] = q[M.act_q[a]]
        senses[nb + na + a] = qd[M.act_dof[a]]
    for k in range(cforce.shape[0]):
        senses[nb + 2 * na + k] = cforce[k]
    for k in range(senses.shape[0]):
        lo, hi = M.sense_lo[k], M.sense_hi[k]
        span = hi - lo
        yk = (senses[k] - lo) / span if span > 0 else 0.5
        senses_norm[k] = min(1.0, max(0.0, yk))
