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

Speed notes (measure with ``gpmotion bench --figure herman`` and
``benchmarks/compare_mujoco.py --only humanoid``; the rules of ``planar.py``
apply — allocation-free, ``inline="always"`` step kernels, Model fields read
into locals up front, branches on scalars, ``error_model="numpy"``):

* everything is 3×3 rotations and 3-vectors held in scalars; no 6×6 matrix
  is formed in the step loop;
* articulated inertias are symmetric and kept packed, 21 numbers per link
  ``[[A, B], [Bᵀ, C]]`` → ``(A upper 6, B 9, C upper 6)``; the body
  inertias are packed once per episode (:func:`body_inertias`);
* every non-root link has one dof with a unit axis s, so ``U = IA·S`` is a
  combination of three columns and ``Sᵀ·`` a 3-term dot product;
* ``Xᵀ Ia X`` is a block rotation (``Eᵀ·E``) plus a shift by r, skipped
  when r = 0 (inside an Euler-joint chain), and it is applied to IA
  *before* the rank-1 update (``Xᵀ IA X − Ũ Ũᵀ/d`` with ``Ũ = Xᵀ U``), so the
  transform does not wait for the division; pass 3 uses ``Ũ·a_parent``.
  The backward pass is latency-bound along limbs, not flop-bound;
* the generated episode kernel allows FMA contraction
  (``fastmath={"contract"}``: no other fast-math flag, the NaN checks stay),
  ~10 % on the humanoid;
* what is left per step on a 24-link humanoid: ~0.75 µs kinematics (mostly
  one ``sincos`` per hinge), ~1.9 µs ABA, ~0.6 µs contacts, senses,
  controller, integration.

The plain-numpy twins (RNEA + CRBA + dense solve) are in
``tests/reference/spatial3d_ref.py``; :func:`aba` keeps the first version's
signature (6×6 scratch, plus ``arm``) for scripts and tests and runs :func:`aba_packed`.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .actuation import apply_servos, limit_torque
from .poles import closest_to_pole
from .senses import SLOTS, joint_senses, normalize_senses

HINGE, SLIDE, FREE = 0, 1, 2

_JIT = dict(cache=True, error_model="numpy", boundscheck=False)
_INLINE = dict(_JIT, inline="always")

# ---------------------------------------------------------------- senses
# slot constants of the 3-D sense kernel, in SLOTS["3d"] order (gpmotion.sim.senses;
# tests check the pairing by name)
(S_PX, S_PY, S_PZ, S_VX, S_VY, S_VZ, S_ROLL, S_PITCH, S_YAW, S_WX, S_WY, S_WZ,
 S_UP_X, S_UP_Y, S_UP_Z, S_COM_Z, S_COM_VZ, S_T, S_COM_X, S_COM_Y, S_COM_VX, S_COM_VY,
 S_ANGLE, S_RATE, S_FORCE, S_SITE) = range(len(SLOTS["3d"]))


# ---------------------------------------------------------------- kinematics
@njit(**_INLINE)
def quat_to_rot(w, x, y, z, R, i):
    """R[i] = rotation matrix of the unit quaternion (w, x, y, z)."""
    m = _quat_mat(w, x, y, z)
    R[i, 0, 0], R[i, 0, 1], R[i, 0, 2] = m[0], m[1], m[2]
    R[i, 1, 0], R[i, 1, 1], R[i, 1, 2] = m[3], m[4], m[5]
    R[i, 2, 0], R[i, 2, 1], R[i, 2, 2] = m[6], m[7], m[8]


@njit(**_INLINE)
def _quat_mat(w, x, y, z):
    """The rotation matrix of a unit quaternion, row-major, as 9 scalars."""
    return (1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y),
            2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x),
            2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y))


@njit(**_INLINE)
def kinematics(M, q, qd, R, pos, E, r, v, cbias):
    """World frames, parent→link transforms, link velocities and c = crm(v)·S·q̇.

    One pass in scalars: the joint's rotation J (Rodrigues for a hinge, the
    quaternion for a free root) and translation d, then ``E = (xrot·J)ᵀ``,
    ``r = xpos + xrot·d``, ``R = R_p·Eᵀ``, ``pos = pos_p + R_p·r`` and
    ``v = X v_p + S q̇``.  A free root is the same formulas with
    ``S q̇ = q̇[0:6]`` (its xrot is the identity, xpos zero, parent the world).
    """
    parent, jtype, qadr, dadr = M.parent, M.jtype, M.qadr, M.dadr
    axis, xrot, xpos = M.axis, M.xrot, M.xpos
    for i in range(parent.shape[0]):
        p = parent[i]
        jt = jtype[i]
        qa = qadr[i]
        da = dadr[i]
        ax, ay, az = axis[i, 0], axis[i, 1], axis[i, 2]
        x00, x01, x02 = xrot[i, 0, 0], xrot[i, 0, 1], xrot[i, 0, 2]
        x10, x11, x12 = xrot[i, 1, 0], xrot[i, 1, 1], xrot[i, 1, 2]
        x20, x21, x22 = xrot[i, 2, 0], xrot[i, 2, 1], xrot[i, 2, 2]
        t0, t1, t2 = xpos[i, 0], xpos[i, 1], xpos[i, 2]
        qi = q[qa]
        wq = qd[da]
        # joint motion: J (joint→link rotation), d (translation, joint coords),
        # S q̇ = (sw; sv)
        if jt == HINGE:
            c, s = np.cos(qi), np.sin(qi)
            k = 1.0 - c
            j00, j01, j02 = c + k * ax * ax, k * ax * ay - s * az, k * ax * az + s * ay
            j10, j11, j12 = k * ax * ay + s * az, c + k * ay * ay, k * ay * az - s * ax
            j20, j21, j22 = k * ax * az - s * ay, k * ay * az + s * ax, c + k * az * az
            dx, dy, dz = 0.0, 0.0, 0.0
            sw0, sw1, sw2 = ax * wq, ay * wq, az * wq
            sv0, sv1, sv2 = 0.0, 0.0, 0.0
        elif jt == SLIDE:
            j00, j01, j02 = 1.0, 0.0, 0.0
            j10, j11, j12 = 0.0, 1.0, 0.0
            j20, j21, j22 = 0.0, 0.0, 1.0
            dx, dy, dz = ax * qi, ay * qi, az * qi
            sw0, sw1, sw2 = 0.0, 0.0, 0.0
            sv0, sv1, sv2 = ax * wq, ay * wq, az * wq
        else:                                   # FREE
            j00, j01, j02, j10, j11, j12, j20, j21, j22 = _quat_mat(
                q[qa + 3], q[qa + 4], q[qa + 5], q[qa + 6])
            dx, dy, dz = qi, q[qa + 1], q[qa + 2]
            sw0, sw1, sw2 = wq, qd[da + 1], qd[da + 2]
            sv0, sv1, sv2 = qd[da + 3], qd[da + 4], qd[da + 5]
        # Rrel = xrot · J (link → parent);  E = Rrelᵀ
        e00 = x00 * j00 + x01 * j10 + x02 * j20
        e10 = x00 * j01 + x01 * j11 + x02 * j21
        e20 = x00 * j02 + x01 * j12 + x02 * j22
        e01 = x10 * j00 + x11 * j10 + x12 * j20
        e11 = x10 * j01 + x11 * j11 + x12 * j21
        e21 = x10 * j02 + x11 * j12 + x12 * j22
        e02 = x20 * j00 + x21 * j10 + x22 * j20
        e12 = x20 * j01 + x21 * j11 + x22 * j21
        e22 = x20 * j02 + x21 * j12 + x22 * j22
        r0 = t0 + x00 * dx + x01 * dy + x02 * dz
        r1 = t1 + x10 * dx + x11 * dy + x12 * dz
        r2 = t2 + x20 * dx + x21 * dy + x22 * dz
        # the parent's frame and velocity (the world: identity, at rest)
        pp = max(p, 0)
        p00, p01, p02 = R[pp, 0, 0], R[pp, 0, 1], R[pp, 0, 2]
        p10, p11, p12 = R[pp, 1, 0], R[pp, 1, 1], R[pp, 1, 2]
        p20, p21, p22 = R[pp, 2, 0], R[pp, 2, 1], R[pp, 2, 2]
        o0, o1, o2 = pos[pp, 0], pos[pp, 1], pos[pp, 2]
        w0, w1, w2 = v[pp, 0], v[pp, 1], v[pp, 2]
        u0, u1, u2 = v[pp, 3], v[pp, 4], v[pp, 5]
        if p < 0:
            p00, p01, p02, p10, p11, p12, p20, p21, p22 = 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0
            o0, o1, o2 = 0.0, 0.0, 0.0
            w0, w1, w2, u0, u1, u2 = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        E[i, 0, 0], E[i, 0, 1], E[i, 0, 2] = e00, e01, e02
        E[i, 1, 0], E[i, 1, 1], E[i, 1, 2] = e10, e11, e12
        E[i, 2, 0], E[i, 2, 1], E[i, 2, 2] = e20, e21, e22
        r[i, 0], r[i, 1], r[i, 2] = r0, r1, r2
        # R = R_p · Eᵀ,  pos = pos_p + R_p · r
        R[i, 0, 0] = p00 * e00 + p01 * e01 + p02 * e02
        R[i, 0, 1] = p00 * e10 + p01 * e11 + p02 * e12
        R[i, 0, 2] = p00 * e20 + p01 * e21 + p02 * e22
        R[i, 1, 0] = p10 * e00 + p11 * e01 + p12 * e02
        R[i, 1, 1] = p10 * e10 + p11 * e11 + p12 * e12
        R[i, 1, 2] = p10 * e20 + p11 * e21 + p12 * e22
        R[i, 2, 0] = p20 * e00 + p21 * e01 + p22 * e02
        R[i, 2, 1] = p20 * e10 + p21 * e11 + p22 * e12
        R[i, 2, 2] = p20 * e20 + p21 * e21 + p22 * e22
        pos[i, 0] = o0 + p00 * r0 + p01 * r1 + p02 * r2
        pos[i, 1] = o1 + p10 * r0 + p11 * r1 + p12 * r2
        pos[i, 2] = o2 + p20 * r0 + p21 * r1 + p22 * r2
        # X v_p:  ω = E ω_p,  v = E (v_p − r × ω_p)
        l0 = u0 - (r1 * w2 - r2 * w1)
        l1 = u1 - (r2 * w0 - r0 * w2)
        l2 = u2 - (r0 * w1 - r1 * w0)
        om0 = e00 * w0 + e01 * w1 + e02 * w2
        om1 = e10 * w0 + e11 * w1 + e12 * w2
        om2 = e20 * w0 + e21 * w1 + e22 * w2
        vl0 = e00 * l0 + e01 * l1 + e02 * l2
        vl1 = e10 * l0 + e11 * l1 + e12 * l2
        vl2 = e20 * l0 + e21 * l1 + e22 * l2
        # crm(v)·(sw; sv) = (ω × sw; v × sw + ω × sv)
        cbias[i, 0] = om1 * sw2 - om2 * sw1
        cbias[i, 1] = om2 * sw0 - om0 * sw2
        cbias[i, 2] = om0 * sw1 - om1 * sw0
        cbias[i, 3] = vl1 * sw2 - vl2 * sw1 + (om1 * sv2 - om2 * sv1)
        cbias[i, 4] = vl2 * sw0 - vl0 * sw2 + (om2 * sv0 - om0 * sv2)
        cbias[i, 5] = vl0 * sw1 - vl1 * sw0 + (om0 * sv1 - om1 * sv0)
        v[i, 0], v[i, 1], v[i, 2] = om0 + sw0, om1 + sw1, om2 + sw2
        v[i, 3], v[i, 4], v[i, 5] = vl0 + sv0, vl1 + sv1, vl2 + sv2


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


N_IB = 10      # body inertia, packed: (A00, A01, A02, A11, A12, A22, m cx, m cy, m cz, m)
N_IA = 21      # articulated inertia [[A, B], [Bᵀ, C]], packed: A (6), B (9, row-major), C (6)


@njit(**_INLINE)
def body_inertias(M, Ib):
    """``Ib[i]`` = link i's spatial inertia about its origin (link coordinates), packed:
    the rotational block ``A = Ic + m (c·c 1 − c cᵀ)`` (upper triangle), ``m c``
    and ``m`` (the coupling block is ``(m c)×``, the linear one ``m·1``).
    Constant per model: filled once per episode."""
    mass, com, icom = M.mass, M.com, M.icom
    for i in range(mass.shape[0]):
        m = mass[i]
        cx, cy, cz = com[i, 0], com[i, 1], com[i, 2]
        cc = cx * cx + cy * cy + cz * cz
        Ib[i, 0] = icom[i, 0, 0] + m * (cc - cx * cx)
        Ib[i, 1] = icom[i, 0, 1] - m * cx * cy
        Ib[i, 2] = icom[i, 0, 2] - m * cx * cz
        Ib[i, 3] = icom[i, 1, 1] + m * (cc - cy * cy)
        Ib[i, 4] = icom[i, 1, 2] - m * cy * cz
        Ib[i, 5] = icom[i, 2, 2] + m * (cc - cz * cz)
        Ib[i, 6], Ib[i, 7], Ib[i, 8], Ib[i, 9] = m * cx, m * cy, m * cz, m


@njit(**_INLINE)
def _sym_congruence(a00, a01, a02, a11, a12, a22,
                    e00, e01, e02, e10, e11, e12, e20, e21, e22):
    """Eᵀ A E for a symmetric A (upper triangles in and out)."""
    r = _congruence(a00, a01, a02, a01, a11, a12, a02, a12, a22,
                    e00, e01, e02, e10, e11, e12, e20, e21, e22)
    return r[0], r[1], r[2], r[4], r[5], r[8]


@njit(**_INLINE)
def _force_to_parent(n0, n1, n2, f0, f1, f2, e00, e01, e02, e10, e11, e12, e20, e21, e22,
                     r0, r1, r2):
    """A spatial force (n, f) in parent coordinates: f' = Eᵀ f, n' = Eᵀ n + r × f'."""
    g0 = e00 * f0 + e10 * f1 + e20 * f2
    g1 = e01 * f0 + e11 * f1 + e21 * f2
    g2 = e02 * f0 + e12 * f1 + e22 * f2
    m0 = e00 * n0 + e10 * n1 + e20 * n2 + (r1 * g2 - r2 * g1)
    m1 = e01 * n0 + e11 * n1 + e21 * n2 + (r2 * g0 - r0 * g2)
    m2 = e02 * n0 + e12 * n1 + e22 * n2 + (r0 * g1 - r1 * g0)
    return m0, m1, m2, g0, g1, g2


@njit(**_INLINE)
def _congruence(b00, b01, b02, b10, b11, b12, b20, b21, b22,
                e00, e01, e02, e10, e11, e12, e20, e21, e22):
    """Eᵀ B E for a general 3×3 B (row-major in and out)."""
    t00 = b00 * e00 + b01 * e10 + b02 * e20
    t01 = b00 * e01 + b01 * e11 + b02 * e21
    t02 = b00 * e02 + b01 * e12 + b02 * e22
    t10 = b10 * e00 + b11 * e10 + b12 * e20
    t11 = b10 * e01 + b11 * e11 + b12 * e21
    t12 = b10 * e02 + b11 * e12 + b12 * e22
    t20 = b20 * e00 + b21 * e10 + b22 * e20
    t21 = b20 * e01 + b21 * e11 + b22 * e21
    t22 = b20 * e02 + b21 * e12 + b22 * e22
    return (e00 * t00 + e10 * t10 + e20 * t20,
            e00 * t01 + e10 * t11 + e20 * t21,
            e00 * t02 + e10 * t12 + e20 * t22,
            e01 * t00 + e11 * t10 + e21 * t20,
            e01 * t01 + e11 * t11 + e21 * t21,
            e01 * t02 + e11 * t12 + e21 * t22,
            e02 * t00 + e12 * t10 + e22 * t20,
            e02 * t01 + e12 * t11 + e22 * t21,
            e02 * t02 + e12 * t12 + e22 * t22)


@njit(**_INLINE)
def _solve_packed6(IA, i, b, L, x):
    """x = I⁻¹ b for the packed symmetric positive definite ``IA[i]`` (Cholesky in L, 6×6)."""
    L[0, 0], L[1, 0], L[2, 0], L[1, 1], L[2, 1], L[2, 2] = (IA[i, 0], IA[i, 1], IA[i, 2],
                                                            IA[i, 3], IA[i, 4], IA[i, 5])
    L[3, 3], L[4, 3], L[5, 3], L[4, 4], L[5, 4], L[5, 5] = (IA[i, 15], IA[i, 16], IA[i, 17],
                                                            IA[i, 18], IA[i, 19], IA[i, 20])
    for j in range(3):
        for k in range(3):
            L[3 + k, j] = IA[i, 6 + 3 * j + k]           # Bᵀ
    for j in range(6):
        s = L[j, j]
        for k in range(j):
            s -= L[j, k] * L[j, k]
        ljj = np.sqrt(s)
        L[j, j] = ljj
        for m in range(j + 1, 6):
            t = L[m, j]
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
def aba_packed(M, qd, E, r, v, cbias, tau, fext, presc, presc_qdd, arm, gravity, Ib, IA, pA,
               U, Ut, dinv, uu, a, qdd, L, b6, x6):
    """Articulated-body forward dynamics with prescribed accelerations (hybrid).

    ``presc[d] != 0`` marks dof d (of a 1-dof link) as kinematic: its
    acceleration is ``presc_qdd[d]``; on return ``tau[d]`` holds the force
    that realises it.  ``arm[d]`` is a joint armature (the implicit PD term,
    ``actuation.py``; 0 on a free root): the joint force is
    ``tau[d] − arm[d]·q̈[d]``, so ``arm`` adds to the joint's ``d = SᵀIᴬS``;
    on return ``tau[d]`` of a non-prescribed joint holds that force.  ``fext[i]``
    is the external spatial force on link i in link coordinates.
    ``Ib[nl, 10]``: :func:`body_inertias`.  Scratch: ``IA[nl, 21]`` (packed
    articulated inertias), ``pA[nl, 6]``, ``U[nl, 6]``
    (``IA·S``), ``Ut[nl, 6]`` (``Xᵀ U``, parent coordinates), ``dinv[nl]``,
    ``uu[nl]`` (``τ − Sᵀ pA − Uᵀ c``), ``a[nl, 6]``, ``L[6, 6]``, ``b6[6]``, ``x6[6]``.

    The transform to the parent, ``Xᵀ Ia X`` with ``X = diag(E, E)·[[1, 0],
    [−r×, 1]]``, is a rotation of the three 3×3 blocks (``Eᵀ·E``) followed by
    a shift by r: ``A'' = A' + Z + Zᵀ − r× C' r×``, ``B'' = B' + r× C'``,
    ``C'' = C'`` with ``Z = r× B'ᵀ`` (skipped when r = 0, as inside an
    Euler-joint chain).
    """
    parent, jtype, dadr, axis = M.parent, M.jtype, M.dadr, M.axis
    nl = parent.shape[0]
    # pass 1: IA = I, pA = v ×* I v − fext
    for i in range(nl):
        a00, a01, a02, a11, a12, a22 = Ib[i, 0], Ib[i, 1], Ib[i, 2], Ib[i, 3], Ib[i, 4], Ib[i, 5]
        mx, my, mz, m = Ib[i, 6], Ib[i, 7], Ib[i, 8], Ib[i, 9]
        w0, w1, w2, l0, l1, l2 = v[i, 0], v[i, 1], v[i, 2], v[i, 3], v[i, 4], v[i, 5]
        h0 = a00 * w0 + a01 * w1 + a02 * w2 + (my * l2 - mz * l1)
        h1 = a01 * w0 + a11 * w1 + a12 * w2 + (mz * l0 - mx * l2)
        h2 = a02 * w0 + a12 * w1 + a22 * w2 + (mx * l1 - my * l0)
        f0 = m * l0 - (my * w2 - mz * w1)
        f1 = m * l1 - (mz * w0 - mx * w2)
        f2 = m * l2 - (mx * w1 - my * w0)
        # crf(v)·h = (ω × hn + v × hf; ω × hf)
        pA[i, 0] = w1 * h2 - w2 * h1 + l1 * f2 - l2 * f1 - fext[i, 0]
        pA[i, 1] = w2 * h0 - w0 * h2 + l2 * f0 - l0 * f2 - fext[i, 1]
        pA[i, 2] = w0 * h1 - w1 * h0 + l0 * f1 - l1 * f0 - fext[i, 2]
        pA[i, 3] = w1 * f2 - w2 * f1 - fext[i, 3]
        pA[i, 4] = w2 * f0 - w0 * f2 - fext[i, 4]
        pA[i, 5] = w0 * f1 - w1 * f0 - fext[i, 5]
        IA[i, 0], IA[i, 1], IA[i, 2], IA[i, 3], IA[i, 4], IA[i, 5] = a00, a01, a02, a11, a12, a22
        IA[i, 6], IA[i, 7], IA[i, 8] = 0.0, -mz, my            # B = (m c)×
        IA[i, 9], IA[i, 10], IA[i, 11] = mz, 0.0, -mx
        IA[i, 12], IA[i, 13], IA[i, 14] = -my, mx, 0.0
        IA[i, 15], IA[i, 16], IA[i, 17], IA[i, 18], IA[i, 19], IA[i, 20] = m, 0.0, 0.0, m, 0.0, m
    # pass 2 (leaves first): Ia, pa of each 1-dof link, folded into its parent.
    # numba: branches below touch scalars only (reference-count pruning)
    for i in range(nl - 1, -1, -1):
        jt = jtype[i]
        if jt == FREE:
            continue                   # the root: solved in pass 3
        p = parent[i]
        da = dadr[i]
        sx, sy, sz = axis[i, 0], axis[i, 1], axis[i, 2]
        pr, w, ti, ai = presc[da], presc_qdd[da], tau[da], arm[da]
        a00, a01, a02, a11, a12, a22 = IA[i, 0], IA[i, 1], IA[i, 2], IA[i, 3], IA[i, 4], IA[i, 5]
        b00, b01, b02 = IA[i, 6], IA[i, 7], IA[i, 8]
        b10, b11, b12 = IA[i, 9], IA[i, 10], IA[i, 11]
        b20, b21, b22 = IA[i, 12], IA[i, 13], IA[i, 14]
        c00, c01, c02, c11, c12, c22 = (IA[i, 15], IA[i, 16], IA[i, 17], IA[i, 18], IA[i, 19],
                                        IA[i, 20])
        pn0, pn1, pn2, pf0, pf1, pf2 = pA[i, 0], pA[i, 1], pA[i, 2], pA[i, 3], pA[i, 4], pA[i, 5]
        g0, g1, g2, g3, g4, g5 = (cbias[i, 0], cbias[i, 1], cbias[i, 2], cbias[i, 3], cbias[i, 4],
                                  cbias[i, 5])
        e00, e01, e02 = E[i, 0, 0], E[i, 0, 1], E[i, 0, 2]
        e10, e11, e12 = E[i, 1, 0], E[i, 1, 1], E[i, 1, 2]
        e20, e21, e22 = E[i, 2, 0], E[i, 2, 1], E[i, 2, 2]
        r0, r1, r2 = r[i, 0], r[i, 1], r[i, 2]
        wp = w if pr else 0.0
        # U = IA S (S a unit axis: a combination of three columns), d = Sᵀ U
        if jt == HINGE:
            un0 = a00 * sx + a01 * sy + a02 * sz
            un1 = a01 * sx + a11 * sy + a12 * sz
            un2 = a02 * sx + a12 * sy + a22 * sz
            uf0 = b00 * sx + b10 * sy + b20 * sz
            uf1 = b01 * sx + b11 * sy + b21 * sz
            uf2 = b02 * sx + b12 * sy + b22 * sz
            d = un0 * sx + un1 * sy + un2 * sz
            sp = pn0 * sx + pn1 * sy + pn2 * sz
            g0 += sx * wp                  # prescribed: c + S q̈
            g1 += sy * wp
            g2 += sz * wp
        else:
            un0 = b00 * sx + b01 * sy + b02 * sz
            un1 = b10 * sx + b11 * sy + b12 * sz
            un2 = b20 * sx + b21 * sy + b22 * sz
            uf0 = c00 * sx + c01 * sy + c02 * sz
            uf1 = c01 * sx + c11 * sy + c12 * sz
            uf2 = c02 * sx + c12 * sy + c22 * sz
            d = uf0 * sx + uf1 * sy + uf2 * sz
            sp = pf0 * sx + pf1 * sy + pf2 * sz
            g3 += sx * wp
            g4 += sy * wp
            g5 += sz * wp
        # a prescribed joint moves as told: the parent sees the whole IA (gain 0);
        # D = d + armature (U = IA S is unchanged)
        di = 0.0 if pr else 1.0 / (d + ai)
        u = ti - sp
        # U in parent coordinates, Ũ = Xᵀ U (Ũ·a_p = U·X a_p: pass 3's dot product)
        tn0, tn1, tn2, tf0, tf1, tf2 = _force_to_parent(
            un0, un1, un2, uf0, uf1, uf2, e00, e01, e02, e10, e11, e12, e20, e21, e22, r0, r1, r2)
        uc = (un0 * g0 + un1 * g1) + (un2 * g2 + uf0 * g3) + (uf1 * g4 + uf2 * g5)
        k = (u - uc) * di
        U[i, 0], U[i, 1], U[i, 2], U[i, 3], U[i, 4], U[i, 5] = un0, un1, un2, uf0, uf1, uf2
        Ut[i, 0], Ut[i, 1], Ut[i, 2], Ut[i, 3], Ut[i, 4], Ut[i, 5] = tn0, tn1, tn2, tf0, tf1, tf2
        dinv[i] = di
        uu[i] = u - uc
        # pa = pA + Ia c + U u/d = pA + IA c + U (u − Uᵀc)/d
        qn0 = pn0 + (a00 * g0 + a01 * g1 + a02 * g2) + (b00 * g3 + b01 * g4 + b02 * g5)
        qn1 = pn1 + (a01 * g0 + a11 * g1 + a12 * g2) + (b10 * g3 + b11 * g4 + b12 * g5)
        qn2 = pn2 + (a02 * g0 + a12 * g1 + a22 * g2) + (b20 * g3 + b21 * g4 + b22 * g5)
        qf0 = pf0 + (b00 * g0 + b10 * g1 + b20 * g2) + (c00 * g3 + c01 * g4 + c02 * g5)
        qf1 = pf1 + (b01 * g0 + b11 * g1 + b21 * g2) + (c01 * g3 + c11 * g4 + c12 * g5)
        qf2 = pf2 + (b02 * g0 + b12 * g1 + b22 * g2) + (c02 * g3 + c12 * g4 + c22 * g5)
        if p >= 0:
            # Xᵀ Ia X = Xᵀ IA X − Ũ Ũᵀ/d: the transform of IA overlaps the division.
            # Rotate the blocks (Eᵀ · E) ...
            a00, a01, a02, a11, a12, a22 = _sym_congruence(
                a00, a01, a02, a11, a12, a22, e00, e01, e02, e10, e11, e12, e20, e21, e22)
            c00, c01, c02, c11, c12, c22 = _sym_congruence(
                c00, c01, c02, c11, c12, c22, e00, e01, e02, e10, e11, e12, e20, e21, e22)
            b00, b01, b02, b10, b11, b12, b20, b21, b22 = _congruence(
                b00, b01, b02, b10, b11, b12, b20, b21, b22,
                e00, e01, e02, e10, e11, e12, e20, e21, e22)
            # forces: f' = Eᵀ f,  n' = Eᵀ n + r × f'
            n0, n1, n2, f0, f1, f2 = _force_to_parent(
                qn0, qn1, qn2, qf0, qf1, qf2, e00, e01, e02, e10, e11, e12, e20, e21, e22,
                r0, r1, r2)
            if r0 != 0.0 or r1 != 0.0 or r2 != 0.0:
                # ... then shift them by r: P = r× C', Z = r× B'ᵀ, W = P r×
                p00, p01, p02 = r1 * c02 - r2 * c01, r1 * c12 - r2 * c11, r1 * c22 - r2 * c12
                p10, p11, p12 = r2 * c00 - r0 * c02, r2 * c01 - r0 * c12, r2 * c02 - r0 * c22
                p20, p21, p22 = r0 * c01 - r1 * c00, r0 * c11 - r1 * c01, r0 * c12 - r1 * c02
                # Z[:, k] = r × (row k of B')
                z00, z10, z20 = r1 * b02 - r2 * b01, r2 * b00 - r0 * b02, r0 * b01 - r1 * b00
                z01, z11, z21 = r1 * b12 - r2 * b11, r2 * b10 - r0 * b12, r0 * b11 - r1 * b10
                z02, z12, z22 = r1 * b22 - r2 * b21, r2 * b20 - r0 * b22, r0 * b21 - r1 * b20
                # W row j = (row j of P) × r  (symmetric)
                a00 += 2.0 * z00 - (p01 * r2 - p02 * r1)
                a01 += (z01 + z10) - (p02 * r0 - p00 * r2)
                a02 += (z02 + z20) - (p00 * r1 - p01 * r0)
                a11 += 2.0 * z11 - (p12 * r0 - p10 * r2)
                a12 += (z12 + z21) - (p10 * r1 - p11 * r0)
                a22 += 2.0 * z22 - (p20 * r1 - p21 * r0)
                b00 += p00
                b01 += p01
                b02 += p02
                b10 += p10
                b11 += p11
                b12 += p12
                b20 += p20
                b21 += p21
                b22 += p22
            v0, v1, v2, v3, v4, v5 = tn0 * di, tn1 * di, tn2 * di, tf0 * di, tf1 * di, tf2 * di
            IA[p, 0] += a00 - tn0 * v0
            IA[p, 1] += a01 - tn0 * v1
            IA[p, 2] += a02 - tn0 * v2
            IA[p, 3] += a11 - tn1 * v1
            IA[p, 4] += a12 - tn1 * v2
            IA[p, 5] += a22 - tn2 * v2
            IA[p, 6] += b00 - tn0 * v3
            IA[p, 7] += b01 - tn0 * v4
            IA[p, 8] += b02 - tn0 * v5
            IA[p, 9] += b10 - tn1 * v3
            IA[p, 10] += b11 - tn1 * v4
            IA[p, 11] += b12 - tn1 * v5
            IA[p, 12] += b20 - tn2 * v3
            IA[p, 13] += b21 - tn2 * v4
            IA[p, 14] += b22 - tn2 * v5
            IA[p, 15] += c00 - tf0 * v3
            IA[p, 16] += c01 - tf0 * v4
            IA[p, 17] += c02 - tf0 * v5
            IA[p, 18] += c11 - tf1 * v4
            IA[p, 19] += c12 - tf1 * v5
            IA[p, 20] += c22 - tf2 * v5
            pA[p, 0] += n0 + tn0 * k
            pA[p, 1] += n1 + tn1 * k
            pA[p, 2] += n2 + tn2 * k
            pA[p, 3] += f0 + tf0 * k
            pA[p, 4] += f1 + tf1 * k
            pA[p, 5] += f2 + tf2 * k
    # pass 3 (root first): accelerations.  q̈ = (u − Uᵀc − Ũ·a_p)/d needs only
    # the parent's acceleration; a = X a_p + c + S q̈ runs beside it
    for i in range(nl):
        p = parent[i]
        jt = jtype[i]
        da = dadr[i]
        sx, sy, sz = axis[i, 0], axis[i, 1], axis[i, 2]
        pp = max(p, 0)
        b0, b1, b2, b3, b4, b5 = a[pp, 0], a[pp, 1], a[pp, 2], a[pp, 3], a[pp, 4], a[pp, 5]
        if p < 0:
            b0, b1, b2, b3, b4, b5 = 0.0, 0.0, 0.0, 0.0, 0.0, gravity  # fictitious base acceleration
        e00, e01, e02 = E[i, 0, 0], E[i, 0, 1], E[i, 0, 2]
        e10, e11, e12 = E[i, 1, 0], E[i, 1, 1], E[i, 1, 2]
        e20, e21, e22 = E[i, 2, 0], E[i, 2, 1], E[i, 2, 2]
        r0, r1, r2 = r[i, 0], r[i, 1], r[i, 2]
        un0, un1, un2, uf0, uf1, uf2 = U[i, 0], U[i, 1], U[i, 2], U[i, 3], U[i, 4], U[i, 5]
        tn0, tn1, tn2, tf0, tf1, tf2 = Ut[i, 0], Ut[i, 1], Ut[i, 2], Ut[i, 3], Ut[i, 4], Ut[i, 5]
        pn0, pn1, pn2, pf0, pf1, pf2 = pA[i, 0], pA[i, 1], pA[i, 2], pA[i, 3], pA[i, 4], pA[i, 5]
        di, u, pr, w, ti, ai = dinv[i], uu[i], presc[da], presc_qdd[da], tau[da], arm[da]
        ua = (tn0 * b0 + tn1 * b1) + (tn2 * b2 + tf0 * b3) + (tf1 * b4 + tf2 * b5)
        acc = w if pr else (u - ua) * di
        l0 = b3 - (r1 * b2 - r2 * b1)
        l1 = b4 - (r2 * b0 - r0 * b2)
        l2 = b5 - (r0 * b1 - r1 * b0)
        a0 = e00 * b0 + e01 * b1 + e02 * b2 + cbias[i, 0]
        a1 = e10 * b0 + e11 * b1 + e12 * b2 + cbias[i, 1]
        a2 = e20 * b0 + e21 * b1 + e22 * b2 + cbias[i, 2]
        a3 = e00 * l0 + e01 * l1 + e02 * l2 + cbias[i, 3]
        a4 = e10 * l0 + e11 * l1 + e12 * l2 + cbias[i, 4]
        a5 = e20 * l0 + e21 * l1 + e22 * l2 + cbias[i, 5]
        if jt == FREE:
            _free_root_solve(IA, i, tau, da, pA, a0, a1, a2, a3, a4, a5, L, b6, x6)
            qdd[da], qdd[da + 1], qdd[da + 2] = x6[0], x6[1], x6[2]
            qdd[da + 3], qdd[da + 4], qdd[da + 5] = x6[3], x6[4], x6[5]
            a[i, 0], a[i, 1], a[i, 2] = a0 + x6[0], a1 + x6[1], a2 + x6[2]
            a[i, 3], a[i, 4], a[i, 5] = a3 + x6[3], a4 + x6[4], a5 + x6[5]
            continue
        qdd[da] = acc
        if jt == HINGE:
            a0 += sx * acc
            a1 += sy * acc
            a2 += sz * acc
            sp = pn0 * sx + pn1 * sy + pn2 * sz
        else:
            a3 += sx * acc
            a4 += sy * acc
            a5 += sz * acc
            sp = pf0 * sx + pf1 * sy + pf2 * sz
        a[i, 0], a[i, 1], a[i, 2], a[i, 3], a[i, 4], a[i, 5] = a0, a1, a2, a3, a4, a5
        if pr:
            tau[da] = sp + un0 * a0 + un1 * a1 + un2 * a2 + uf0 * a3 + uf1 * a4 + uf2 * a5
        else:
            tau[da] = ti - ai * acc         # the joint force of an implicit servo


@njit(**_INLINE)
def _free_root_solve(IA, i, tau, da, pA, a0, a1, a2, a3, a4, a5, L, b6, x6):
    """x6 = IA[i]⁻¹ (τ − pA − IA a) for a free root with bias acceleration a."""
    a00, a01, a02, a11, a12, a22 = IA[i, 0], IA[i, 1], IA[i, 2], IA[i, 3], IA[i, 4], IA[i, 5]
    b00, b01, b02 = IA[i, 6], IA[i, 7], IA[i, 8]
    b10, b11, b12 = IA[i, 9], IA[i, 10], IA[i, 11]
    b20, b21, b22 = IA[i, 12], IA[i, 13], IA[i, 14]
    c00, c01, c02, c11, c12, c22 = IA[i, 15], IA[i, 16], IA[i, 17], IA[i, 18], IA[i, 19], IA[i, 20]
    b6[0] = tau[da] - pA[i, 0] - (a00 * a0 + a01 * a1 + a02 * a2 + b00 * a3 + b01 * a4 + b02 * a5)
    b6[1] = tau[da + 1] - pA[i, 1] - (a01 * a0 + a11 * a1 + a12 * a2 + b10 * a3 + b11 * a4 + b12 * a5)
    b6[2] = tau[da + 2] - pA[i, 2] - (a02 * a0 + a12 * a1 + a22 * a2 + b20 * a3 + b21 * a4 + b22 * a5)
    b6[3] = tau[da + 3] - pA[i, 3] - (b00 * a0 + b10 * a1 + b20 * a2 + c00 * a3 + c01 * a4 + c02 * a5)
    b6[4] = tau[da + 4] - pA[i, 4] - (b01 * a0 + b11 * a1 + b21 * a2 + c01 * a3 + c11 * a4 + c12 * a5)
    b6[5] = tau[da + 5] - pA[i, 5] - (b02 * a0 + b12 * a1 + b22 * a2 + c02 * a3 + c12 * a4 + c22 * a5)
    _solve_packed6(IA, i, b6, L, x6)


@njit(**_JIT)
def aba(M, qd, E, r, v, cbias, tau, fext, presc, presc_qdd, arm, gravity, IA, pA, U, dinv, uu,
        a, qdd, work, vec):
    """:func:`aba_packed` behind the first version's signature (for scripts and tests).

    ``IA[nl, 6, 6]``, ``work[3, 6, 6]`` and ``vec[3, 6]`` are unused (the packed
    scratch is allocated here); ``pA``, ``U``, ``dinv``, ``uu``, ``a`` and
    ``qdd`` are filled as :func:`aba_packed` fills them.  The step loop calls
    :func:`aba_packed` with scratch allocated once per episode.
    """
    nl = M.parent.shape[0]
    Ib = np.empty((nl, N_IB))
    body_inertias(M, Ib)
    aba_packed(M, qd, E, r, v, cbias, tau, fext, presc, presc_qdd, arm, gravity, Ib,
               np.empty((nl, N_IA)), pA, U, np.empty((nl, 6)), dinv, uu, a, qdd, np.zeros((6, 6)), np.zeros(6),
               np.zeros(6))


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
def segment_world(M, R, pos, g):
    """World end points (a, b) of segment g, on a link or on the fixed root."""
    link = M.seg_link[g]
    a0, a1, a2 = M.seg_a[g, 0], M.seg_a[g, 1], M.seg_a[g, 2]
    b0, b1, b2 = M.seg_b[g, 0], M.seg_b[g, 1], M.seg_b[g, 2]
    if link >= 0:
        ax, ay, az = point_world(R, pos, link, a0, a1, a2)
        bx, by, bz = point_world(R, pos, link, b0, b1, b2)
    else:
        ax, ay, az = fixed_point_world(M.fixed_rot, M.fixed_pos, a0, a1, a2)
        bx, by, bz = fixed_point_world(M.fixed_rot, M.fixed_pos, b0, b1, b2)
    return ax, ay, az, bx, by, bz


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
    deepest = 0.0
    for j in range(S.poles.shape[0]):
        cx, cz, rp = S.poles[j, 0], S.poles[j, 1], S.poles[j, 2]
        for g in range(M.seg_link.shape[0]):
            link = M.seg_link[g]
            sa0, sa1, sa2 = M.seg_a[g, 0], M.seg_a[g, 1], M.seg_a[g, 2]
            sb0, sb1, sb2 = M.seg_b[g, 0], M.seg_b[g, 1], M.seg_b[g, 2]
            rr = M.seg_r[g]
            ax, ay, az, bx, by, bz = segment_world(M, R, pos, g)
            t, ex, ez, dist = closest_to_pole(ax, az, bx, bz, cx, cz)
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
def joint_torques(M, q, qd, targets, taus, actuation, dt, tau, presc, presc_qdd, arm):
    """Passive damping, joint limits, then PD servos or kinematic responses (per dof).

    ``arm[d]``: the armature that makes dof d's PD servo implicit (for :func:`aba_packed`).
    """
    limit_k, limit_c = M.limit_k, M.limit_c
    for d in range(qd.shape[0]):
        tau[d] = -M.damping[d] * qd[d]
        presc[d] = 0
        arm[d] = 0.0
    for i in range(M.parent.shape[0]):
        if M.jtype[i] == FREE:
            continue
        d = M.dadr[i]
        x = q[M.qadr[i]]
        tau[d] += limit_torque(x, qd[d], M.lo[d], M.hi[d], limit_k, limit_c)
    apply_servos(M, q, qd, targets, taus, actuation, dt, M.act_q, tau, presc, presc_qdd, arm)


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
    """Fill ``senses`` (n_senses + 1 entries: the last is scratch) / ``senses_norm``
    at ``M.sense_at`` (layout: gpmotion.sim.senses).

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
    at = M.sense_at
    senses[at[S_PX]] = x - goal[0]
    senses[at[S_PY]] = y - goal[1]
    senses[at[S_PZ]] = z - goal[2]
    senses[at[S_VX]] = r00 * l0 + r01 * l1 + r02 * l2
    senses[at[S_VY]] = r10 * l0 + r11 * l1 + r12 * l2
    senses[at[S_VZ]] = r20 * l0 + r21 * l1 + r22 * l2
    senses[at[S_ROLL]] = np.arctan2(r21, r22)
    senses[at[S_PITCH]] = np.arcsin(min(1.0, max(-1.0, r20)))
    senses[at[S_YAW]] = np.arctan2(r10, r00)
    senses[at[S_WX]] = r00 * w0 + r01 * w1 + r02 * w2
    senses[at[S_WY]] = r10 * w0 + r11 * w1 + r12 * w2
    senses[at[S_WZ]] = r20 * w0 + r21 * w1 + r22 * w2
    senses[at[S_UP_X]] = r02
    senses[at[S_UP_Y]] = r12
    senses[at[S_UP_Z]] = r22
    senses[at[S_COM_Z]] = com[2]
    senses[at[S_COM_VZ]] = com[5]
    senses[at[S_T]] = t
    senses[at[S_COM_X]] = com[0]
    senses[at[S_COM_Y]] = com[1]
    senses[at[S_COM_VX]] = com[3]
    senses[at[S_COM_VY]] = com[4]
    a0, r0, f0, site0 = at[S_ANGLE], at[S_RATE], at[S_FORCE], at[S_SITE]
    joint_senses(senses, a0, r0, f0, q, qd, M.act_q, M.act_dof, cforce)
    g0, g1, g2 = goal[0], goal[1], goal[2]
    for k in range(M.ss_link.shape[0]):     # sensed sites: world position − goal
        i = M.ss_link[k]
        s0, s1, s2 = M.ss_pos[k, 0], M.ss_pos[k, 1], M.ss_pos[k, 2]
        if i < 0:
            px = fx + f00 * s0 + f01 * s1 + f02 * s2
            py = fy + f10 * s0 + f11 * s1 + f12 * s2
            pz = fz + f20 * s0 + f21 * s1 + f22 * s2
        else:
            px = pos[i, 0] + R[i, 0, 0] * s0 + R[i, 0, 1] * s1 + R[i, 0, 2] * s2
            py = pos[i, 1] + R[i, 1, 0] * s0 + R[i, 1, 1] * s1 + R[i, 1, 2] * s2
            pz = pos[i, 2] + R[i, 2, 0] * s0 + R[i, 2, 1] * s1 + R[i, 2, 2] * s2
        senses[site0 + 3 * k] = px - g0
        senses[site0 + 3 * k + 1] = py - g1
        senses[site0 + 3 * k + 2] = pz - g2
    normalize_senses(M, senses, senses_norm)
