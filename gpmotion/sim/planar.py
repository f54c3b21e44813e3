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

Speed notes (the step loop of the rollout runs these millions of times;
measure with ``gpmotion bench`` / ``benchmarks/bench_sim.py``):

* ``kinematics`` also fills ``cs[i] = (cos θ_i, sin θ_i)`` of every link's
  world angle, composed from the parent's and the joint's (one sin/cos pair
  per hinge per step); contacts, centre of mass and senses read ``cs``
  instead of calling the trig functions again;
* the step-loop kernels are ``inline="always"`` (numba IR inlining into the
  generated episode kernel); ``pole_contacts`` is a plain call, made only
  when the scene has poles;
* numba reference counting: a function that receives the ``Model`` tuple
  increfs/decrefs every array in it (atomic operations, ~0.1–0.3 µs per
  call) unless numba's refcount pruning removes the pairs — and pruning
  fails when arrays are read, or array-taking helpers are called, inside an
  ``if``/``else`` or behind an early ``return``.  So: read Model/Scene fields
  up front as scalars or inside plain loop bodies, branch on scalars only;
* articulated inertias are symmetric and kept packed, six numbers per link
  ``(I00, I01, I02, I11, I12, I22)``; the ABA works in scalars, one division
  per link and pass;
* kernels are allocation-free and compiled with ``error_model="numpy"`` (a
  division by zero gives inf/NaN, which the divergence check catches, instead
  of a branch and an exception).  No ``fastmath``: ``integrate`` relies on
  NaN comparisons (and FMA contraction measured no gain).

The plain-numpy twins live in ``tests/reference/planar_ref.py``.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .actuation import apply_servos, limit_torque
from .poles import closest_to_pole

REVOLUTE, SLIDE_X, SLIDE_Z = 0, 1, 2

_JIT = dict(cache=True, error_model="numpy", boundscheck=False)
_INLINE = dict(_JIT, inline="always")


@njit(**_INLINE)
def kinematics(M, q, qd, pose, X, v, cbias, cs):
    """World poses, parent→link transforms, link velocities and velocity-product terms.

    ``cs[i] = (cos θ_i, sin θ_i)`` of the world angle ``θ_i = pose[i, 0]``.
    """
    for i in range(q.shape[0]):
        p = M.parent[i]
        a0, rx, rz = M.xtree[i, 0], M.xtree[i, 1], M.xtree[i, 2]
        if p >= 0:
            thp, xp, zp = pose[p, 0], pose[p, 1], pose[p, 2]
            cp, sp = cs[p, 0], cs[p, 1]
            vp0, vp1, vp2 = v[p, 0], v[p, 1], v[p, 2]
        else:
            thp, xp, zp = 0.0, 0.0, 0.0
            cp, sp = 1.0, 0.0
            vp0, vp1, vp2 = 0.0, 0.0, 0.0
        jx = xp + cp * rx - sp * rz
        jz = zp + sp * rx + cp * rz
        jt = M.jtype[i]
        if jt == REVOLUTE:
            ang = a0 + q[i]
            c, s = np.cos(ang), np.sin(ang)
            pose[i, 0], pose[i, 1], pose[i, 2] = thp + ang, jx, jz
            cw, sw = cp * c - sp * s, sp * c + cp * s
        else:
            if a0 == 0.0:
                c, s = 1.0, 0.0
                cw, sw = cp, sp
            else:
                c, s = np.cos(a0), np.sin(a0)
                cw, sw = cp * c - sp * s, sp * c + cp * s
            dx, dz = (q[i], 0.0) if jt == SLIDE_X else (0.0, q[i])
            rx, rz = rx + c * dx - s * dz, rz + s * dx + c * dz
            pose[i, 0], pose[i, 1], pose[i, 2] = thp + a0, jx + cw * dx - sw * dz, jz + sw * dx + cw * dz
        cs[i, 0], cs[i, 1] = cw, sw
        x10, x20 = s * rx - c * rz, c * rx + s * rz
        X[i, 0], X[i, 1], X[i, 2], X[i, 3] = c, s, x10, x20
        m0 = vp0
        m1 = x10 * vp0 + c * vp1 + s * vp2
        m2 = x20 * vp0 - s * vp1 + c * vp2
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


@njit(**_INLINE)
def link_inertia(M, i, I):
    """Spatial inertia of link i about its origin, in link coordinates (mcI), 3×3."""
    m, cx, cz = M.mass[i], M.com[i, 0], M.com[i, 1]
    I[0, 0] = M.icom[i] + m * (cx * cx + cz * cz)
    I[0, 1] = I[1, 0] = -m * cz
    I[0, 2] = I[2, 0] = m * cx
    I[1, 1] = I[2, 2] = m
    I[1, 2] = I[2, 1] = 0.0


@njit(**_INLINE)
def aba(M, qd, X, v, cbias, tau, fext, presc, presc_qdd, arm, gravity, IA, pA, dinv, a, qdd):
    """Articulated-body forward dynamics with prescribed accelerations (hybrid).

    ``presc[i] != 0`` marks dof i as kinematic: its acceleration is
    ``presc_qdd[i]``; on return ``tau[i]`` holds the torque that realises it.
    ``arm[i]`` is a joint armature (the implicit PD term, ``actuation.py``):
    the joint force is ``tau[i] − arm[i]·q̈[i]``, so ``arm`` adds to the
    joint's ``d = SᵀIᴬS``; on return ``tau[i]`` of a non-prescribed dof
    holds that force.  ``fext[i]`` is the external spatial force on link i
    in link coordinates.
    Scratch: ``IA[nl, 6]`` (packed articulated inertias), ``pA[nl, 3]``
    (bias forces), ``dinv[nl]`` (1/D, so pass 3 multiplies), ``a[nl, 3]``
    (link accelerations).
    """
    nl = qd.shape[0]
    for i in range(nl):
        m, cx, cz = M.mass[i], M.com[i, 0], M.com[i, 1]
        i00 = M.icom[i] + m * (cx * cx + cz * cz)
        i01 = -m * cz
        i02 = m * cx
        IA[i, 0], IA[i, 1], IA[i, 2] = i00, i01, i02
        IA[i, 3], IA[i, 4], IA[i, 5] = m, 0.0, m
        v0, v1, v2 = v[i, 0], v[i, 1], v[i, 2]
        h1 = i01 * v0 + m * v1
        h2 = i02 * v0 + m * v2
        # crf(v) · h  =  (−vz h1 + vx h2, −ω h2, ω h1)
        pA[i, 0] = -v2 * h1 + v1 * h2 - fext[i, 0]
        pA[i, 1] = -v0 * h2 - fext[i, 1]
        pA[i, 2] = v0 * h1 - fext[i, 2]
    # numba: branches below touch scalars only; array reads inside if/else
    # can defeat reference-count pruning (atomic increments every call)
    for i in range(nl - 1, -1, -1):
        k = M.jtype[i]
        p = M.parent[i]
        pr, w, ti, ai = presc[i], presc_qdd[i], tau[i], arm[i]
        a00, a01, a02, a11, a12, a22 = IA[i, 0], IA[i, 1], IA[i, 2], IA[i, 3], IA[i, 4], IA[i, 5]
        e0, e1, e2 = cbias[i, 0], cbias[i, 1], cbias[i, 2]
        pa0, pa1, pa2 = pA[i, 0], pA[i, 1], pA[i, 2]
        # U = IA e_k (column k), d = U_k
        if k == 0:
            u0, u1, u2, d, pk = a00, a01, a02, a00, pa0
        elif k == 1:
            u0, u1, u2, d, pk = a01, a11, a12, a11, pa1
        else:
            u0, u1, u2, d, pk = a02, a12, a22, a22, pa2
        if pr:
            # the joint moves as told: the parent sees the whole articulated inertia
            if k == 0:
                e0 += w
            elif k == 1:
                e1 += w
            else:
                e2 += w
            ud = 0.0
            di = 0.0
        else:
            # Ia = IA − U Uᵀ / D with D = d + armature (U = IA S is unchanged)
            di = 1.0 / (d + ai)
            ud = (ti - pk) * di
            w0, w1, w2 = u0 * di, u1 * di, u2 * di
            a00 -= u0 * w0
            a01 -= u0 * w1
            a02 -= u0 * w2
            a11 -= u1 * w1
            a12 -= u1 * w2
            a22 -= u2 * w2
        dinv[i] = di
        pa0 += a00 * e0 + a01 * e1 + a02 * e2 + u0 * ud
        pa1 += a01 * e0 + a11 * e1 + a12 * e2 + u1 * ud
        pa2 += a02 * e0 + a12 * e1 + a22 * e2 + u2 * ud
        if p >= 0:
            # IA[p] += Xᵀ Ia X and pA[p] += Xᵀ pa, written out (no helper calls in branches)
            c, s, x10, x20 = X[i, 0], X[i, 1], X[i, 2], X[i, 3]
            c00 = a00 + a01 * x10 + a02 * x20    # C = Ia X
            c01 = a01 * c - a02 * s
            c02 = a01 * s + a02 * c
            c10 = a01 + a11 * x10 + a12 * x20
            c11 = a11 * c - a12 * s
            c12 = a11 * s + a12 * c
            c20 = a02 + a12 * x10 + a22 * x20
            c21 = a12 * c - a22 * s
            c22 = a12 * s + a22 * c
            IA[p, 0] += c00 + x10 * c10 + x20 * c20    # Xᵀ C
            IA[p, 1] += c01 + x10 * c11 + x20 * c21
            IA[p, 2] += c02 + x10 * c12 + x20 * c22
            IA[p, 3] += c * c11 - s * c21
            IA[p, 4] += c * c12 - s * c22
            IA[p, 5] += s * c12 + c * c22
            pA[p, 0] += pa0 + x10 * pa1 + x20 * pa2
            pA[p, 1] += c * pa1 - s * pa2
            pA[p, 2] += s * pa1 + c * pa2
    for i in range(nl):
        p = M.parent[i]
        k = M.jtype[i]
        pp = p if p >= 0 else 0
        ap0, ap1, ap2 = a[pp, 0], a[pp, 1], a[pp, 2]
        if p < 0:
            ap0, ap1, ap2 = 0.0, 0.0, gravity  # fictitious base acceleration
        c, s, x10, x20 = X[i, 0], X[i, 1], X[i, 2], X[i, 3]
        a0 = ap0 + cbias[i, 0]
        a1 = x10 * ap0 + c * ap1 + s * ap2 + cbias[i, 1]
        a2 = x20 * ap0 - s * ap1 + c * ap2 + cbias[i, 2]
        i00, i01, i02, i11, i12, i22 = IA[i, 0], IA[i, 1], IA[i, 2], IA[i, 3], IA[i, 4], IA[i, 5]
        pr, w, ti, ai, di = presc[i], presc_qdd[i], tau[i], arm[i], dinv[i]
        if k == 0:
            u0, u1, u2, pk = i00, i01, i02, pA[i, 0]
        elif k == 1:
            u0, u1, u2, pk = i01, i11, i12, pA[i, 1]
        else:
            u0, u1, u2, pk = i02, i12, i22, pA[i, 2]
        if pr:
            acc = w
        else:
            acc = (ti - pk - (u0 * a0 + u1 * a1 + u2 * a2)) * di
        qdd[i] = acc
        if k == 0:
            a0 += acc
        elif k == 1:
            a1 += acc
        else:
            a2 += acc
        a[i, 0], a[i, 1], a[i, 2] = a0, a1, a2
        if pr:
            ti = u0 * a0 + u1 * a1 + u2 * a2 + pk
        else:
            ti -= ai * acc          # the joint force of an implicit servo
        tau[i] = ti


@njit(**_INLINE)
def point_world(pose, cs, link, px, pz):
    """World position of a point given in link coordinates (link >= 0)."""
    c, s = cs[link, 0], cs[link, 1]
    return pose[link, 1] + c * px - s * pz, pose[link, 2] + s * px + c * pz


@njit(**_INLINE)
def fixed_point_world(th, x, z, px, pz):
    """World position of a point on a fixed root body placed at ``(θ, x, z)`` (link −1)."""
    c, s = np.cos(th), np.sin(th)
    return x + c * px - s * pz, z + s * px + c * pz


@njit(**_INLINE)
def point_velocity(cs, v, link, px, pz):
    """World velocity of a point given in link coordinates (zero on a fixed root)."""
    if link < 0:
        return 0.0, 0.0
    w = v[link, 0]
    lx, lz = v[link, 1] - w * pz, v[link, 2] + w * px
    c, s = cs[link, 0], cs[link, 1]
    return c * lx - s * lz, s * lx + c * lz


@njit(**_INLINE)
def apply_point_force(cs, fext, link, px, pz, fx, fz):
    """Add a world force (fx, fz) acting at a link-frame point to ``fext[link]``."""
    if link < 0:
        return
    c, s = cs[link, 0], cs[link, 1]
    lx, lz = c * fx + s * fz, -s * fx + c * fz
    fext[link, 0] += px * lz - pz * lx
    fext[link, 1] += lx
    fext[link, 2] += lz


_CHOSEN = 1e300


@njit(**_INLINE)
def contact_point_world(M, pose, cs, fth, fx, fz, k):
    """Contact point ``k``: its link, link-frame position and world (x, z)
    (``fth, fx, fz``: the model's fixed pose, read by the caller as scalars)."""
    link = M.cp_link[k]
    px, pz = M.cp_pos[k, 0], M.cp_pos[k, 1]
    if link >= 0:
        x, z = point_world(pose, cs, link, px, pz)
    else:
        x, z = fixed_point_world(fth, fx, fz, px, pz)
    return link, px, pz, x, z


@njit(**_INLINE)
def _deepest(M, pose, cs, fth, fx, fz, ground_z, nmax, mark):
    """Mark (``_CHOSEN``) the ``nmax`` most deeply penetrating contact points.

    Auslander et al. §2.1: "only two endpoints can be in contact with the
    ground simultaneously"; the others pass through it this step."""
    nc = M.cp_link.shape[0]
    for k in range(nc):
        mark[k] = ground_z - contact_point_world(M, pose, cs, fth, fx, fz, k)[4]
    for r in range(nmax):
        j, deepest = -1, 0.0
        for k in range(nc):
            if deepest < mark[k] < _CHOSEN:
                j, deepest = k, mark[k]
        if j < 0:
            break
        mark[j] = _CHOSEN


@njit(**_INLINE)
def ground_contacts(M, S, pose, cs, v, anchor, touching, fext, cforce):
    """Penalty ground contact with a stick–slip friction anchor per point.

    Normal: spring-damper on penetration, never pulling.  Tangential: a
    spring to the point where contact began (so a figure at rest does not
    creep), clamped at μ·Fn; when it slips the anchor is dragged along.
    With ``S.max_contacts`` > 0 only the points ``_deepest`` marks in
    ``cforce`` touch.
    """
    # numba: a Model field read inside a branch defeats reference-count
    # pruning (~0.1 µs per call); read such fields up front, as scalars
    fth, fx, fz = M.fixed_pose[0], M.fixed_pose[1], M.fixed_pose[2]
    ground, ground_z, k_ground, c_ground = S.ground, S.ground_z, S.k_ground, S.c_ground
    k_tangent, c_tangent, mu = S.k_tangent, S.c_tangent, S.mu
    nmax = S.max_contacts
    if nmax > 0 and ground != 0:
        _deepest(M, pose, cs, fth, fx, fz, ground_z, nmax, cforce)
    for k in range(M.cp_link.shape[0]):
        chosen = nmax == 0 or cforce[k] == _CHOSEN    # read before cforce[k] is reset
        cforce[k] = 0.0
        if ground == 0:
            continue
        if not chosen:
            touching[k] = 0.0
            continue
        link, px, pz, x, z = contact_point_world(M, pose, cs, fth, fx, fz, k)
        pen = ground_z - z
        if pen <= 0.0:
            touching[k] = 0.0
            continue
        vx, vz = point_velocity(cs, v, link, px, pz)
        fn = k_ground * pen - c_ground * vz
        if fn < 0.0:
            fn = 0.0
        if touching[k] == 0.0:
            anchor[k] = x
            touching[k] = 1.0
        ft = -k_tangent * (x - anchor[k]) - c_tangent * vx
        lim = mu * fn
        if ft > lim or ft < -lim:
            ft = lim if ft > 0 else -lim
            anchor[k] = x + (ft + c_tangent * vx) / k_tangent if k_tangent > 0 else x
        cforce[k] = fn
        apply_point_force(cs, fext, link, px, pz, ft, fn)


@njit(**_JIT)
def pole_contacts(M, S, pose, cs, v, fext):
    """Capsule–pole penalty contact (frictionless); returns the deepest penetration.

    Written branch-free around array accesses (a capsule out of contact adds
    a zero force) so that numba's reference-count pruning succeeds.
    """
    fth, fx, fz = M.fixed_pose[0], M.fixed_pose[1], M.fixed_pose[2]
    fc, fs = np.cos(fth), np.sin(fth)
    k_pole, c_pole = S.k_pole, S.c_pole
    deepest = 0.0
    for j in range(S.poles.shape[0]):
        cx, cz, rp = S.poles[j, 0], S.poles[j, 1], S.poles[j, 2]
        for g in range(M.seg_link.shape[0]):
            link = M.seg_link[g]
            sax, saz, sbx, sbz = M.seg_a[g, 0], M.seg_a[g, 1], M.seg_b[g, 0], M.seg_b[g, 1]
            r = M.seg_r[g]
            li = max(link, 0)
            c, s, ox, oz = cs[li, 0], cs[li, 1], pose[li, 1], pose[li, 2]
            w, v1, v2 = v[li, 0], v[li, 1], v[li, 2]
            moving = link >= 0
            if not moving:                     # a fixed root body
                c, s, ox, oz, w, v1, v2 = fc, fs, fx, fz, 0.0, 0.0, 0.0
            ax, az = ox + c * sax - s * saz, oz + s * sax + c * saz
            bx, bz = ox + c * sbx - s * sbz, oz + s * sbx + c * sbz
            t, ex, ez, dist = closest_to_pole(ax, az, bx, bz, cx, cz)
            pen = r + rp - dist
            hit = pen > 0.0 and dist != 0.0
            if hit:
                deepest = max(deepest, pen)
            inv = 1.0 / dist if hit else 0.0
            nx, nz = ex * inv, ez * inv
            lx = sax + t * (sbx - sax)
            lz = saz + t * (sbz - saz)
            # world velocity of the closest point
            plx, plz = v1 - w * lz, v2 + w * lx
            vx, vz = c * plx - s * plz, s * plx + c * plz
            fn = k_pole * pen - c_pole * (vx * nx + vz * nz)
            if not (hit and moving and fn > 0.0):
                fn = 0.0
            fwx, fwz = fn * nx, fn * nz
            flx, flz = c * fwx + s * fwz, -s * fwx + c * fwz
            fext[li, 0] += lx * flz - lz * flx
            fext[li, 1] += flx
            fext[li, 2] += flz
    return deepest


@njit(**_INLINE)
def joint_torques(M, q, qd, targets, taus, actuation, dt, tau, presc, presc_qdd, arm):
    """Passive damping, joint limits, then PD servos or kinematic responses.

    ``arm[i]``: the armature that makes dof i's PD servo implicit (for :func:`aba`).
    """
    limit_k, limit_c = M.limit_k, M.limit_c
    for i in range(q.shape[0]):
        tau[i] = -M.damping[i] * qd[i]
        presc[i] = 0
        arm[i] = 0.0
        tau[i] += limit_torque(q[i], qd[i], M.lo[i], M.hi[i], limit_k, limit_c)
    apply_servos(M, q, qd, targets, taus, actuation, dt, M.act_dof, tau, presc, presc_qdd, arm)


@njit(**_INLINE)
def centre_of_mass(M, pose, cs, v, com):
    """com = (x, z, vx, vz) of the moving links (a fixed root body is excluded)."""
    mt = sx = sz = svx = svz = 0.0
    for i in range(M.mass.shape[0]):
        m, cx, cz = M.mass[i], M.com[i, 0], M.com[i, 1]
        if m == 0.0:
            continue
        x, z = point_world(pose, cs, i, cx, cz)
        vx, vz = point_velocity(cs, v, i, cx, cz)
        mt += m
        sx += m * x
        sz += m * z
        svx += m * vx
        svz += m * vz
    if mt > 0:
        com[0], com[1], com[2], com[3] = sx / mt, sz / mt, svx / mt, svz / mt


@njit(**_JIT)
def mechanical_energy(M, S, q, qd, pose, cs, v):
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
        x, z = point_world(pose, cs, i, M.com[i, 0], M.com[i, 1])
        pe += M.mass[i] * S.gravity * z
    return ke + pe


@njit(**_INLINE)
def integrate(q, qd, qdd, dt, limit):
    """Semi-implicit Euler; returns False when the state is non-finite or absurd."""
    ok = True
    for i in range(q.shape[0]):
        qd[i] += dt * qdd[i]
        q[i] += dt * qd[i]
        if not (abs(q[i]) < limit and abs(qd[i]) < limit):  # also catches NaN
            ok = False
    return ok
