"""The planar articulated-body pass over B episodes at once (structure of arrays) against one at a time.

    python benchmarks/aba_soa.py [--lanes 8] [--episodes 8] [--repeats 31]

The ABA of a chain is a chain of dependent operations (a division per link
and pass, each link waiting on its child or parent), so one episode's pass
keeps the core waiting on latency.  With the episodes of a batch side by
side (every quantity an array over B lanes, the lane index last), the
inner loop over lanes is independent work the compiler may vectorise and
the core may overlap.  This measures that lever's ceiling on the pass alone:
the inputs of ``planar.aba`` (transforms, velocities, bias terms, torques,
external forces, prescribed dofs, armatures) are taken from the states the
``gpmotion bench`` lamp workload (sine targets) passes through, every step,
and both forms compute q̈ and the joint forces from them in turn,
``--repeats`` times.

Measured (docs/speed.md): no faster; from 0.6× to 1.1× the one-episode pass
(best runs, 8 and 32 lanes, from one run to the next).  numba/LLVM do not
vectorise these lane loops (a scalar ``vdivsd`` in the machine code, no
``vdivpd``), though a short lane loop over a few arrays does vectorise: the
lanes alone buy nothing, a vectorised pass needs a layout the compiler can
prove free of aliasing.  :func:`aba_soa` is ``planar.aba`` with the lanes added
and its data-dependent branches (a prescribed dof or not) written as selects
of values both ways compute; the outputs must agree bit for bit.
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from numba import njit

from gpmotion.sim.planar import aba, ground_contacts, joint_torques, kinematics

_JIT = dict(cache=False, error_model="numpy", boundscheck=False)


@njit(**_JIT)
def aba_soa(M, X, v, cbias, tau, fext, presc, presc_qdd, arm, gravity, IA, pA, dinv, a, qdd):
    """``planar.aba`` on B lanes: every array [nl, ..., B] (the lane last)."""
    nl = X.shape[0]
    B = X.shape[2]
    for i in range(nl):
        m, cx, cz = M.mass[i], M.com[i, 0], M.com[i, 1]
        i00 = M.icom[i] + m * (cx * cx + cz * cz)
        i01 = -m * cz
        i02 = m * cx
        for b in range(B):
            IA[i, 0, b], IA[i, 1, b], IA[i, 2, b] = i00, i01, i02
            IA[i, 3, b], IA[i, 4, b], IA[i, 5, b] = m, 0.0, m
            v0, v1, v2 = v[i, 0, b], v[i, 1, b], v[i, 2, b]
            h1 = i01 * v0 + m * v1
            h2 = i02 * v0 + m * v2
            pA[i, 0, b] = -v2 * h1 + v1 * h2 - fext[i, 0, b]
            pA[i, 1, b] = -v0 * h2 - fext[i, 1, b]
            pA[i, 2, b] = v0 * h1 - fext[i, 2, b]
    for i in range(nl - 1, -1, -1):
        k = M.jtype[i]
        p = M.parent[i]
        pp = max(p, 0)
        for b in range(B):
            pr = presc[i, b] != 0
            w, ti, ai = presc_qdd[i, b], tau[i, b], arm[i, b]
            a00, a01, a02 = IA[i, 0, b], IA[i, 1, b], IA[i, 2, b]
            a11, a12, a22 = IA[i, 3, b], IA[i, 4, b], IA[i, 5, b]
            e0, e1, e2 = cbias[i, 0, b], cbias[i, 1, b], cbias[i, 2, b]
            pa0, pa1, pa2 = pA[i, 0, b], pA[i, 1, b], pA[i, 2, b]
            if k == 0:
                u0, u1, u2, d, pk = a00, a01, a02, a00, pa0
            elif k == 1:
                u0, u1, u2, d, pk = a01, a11, a12, a11, pa1
            else:
                u0, u1, u2, d, pk = a02, a12, a22, a22, pa2
            # prescribed: e_k += w, no reduction; free: D = d + armature, Ia = IA - U Uᵀ / D
            e0 = e0 + w if pr and k == 0 else e0
            e1 = e1 + w if pr and k == 1 else e1
            e2 = e2 + w if pr and k == 2 else e2
            dfree = 1.0 / (d + ai)
            di = 0.0 if pr else dfree
            ud = 0.0 if pr else (ti - pk) * dfree
            w0, w1, w2 = u0 * dfree, u1 * dfree, u2 * dfree
            a00 = a00 if pr else a00 - u0 * w0
            a01 = a01 if pr else a01 - u0 * w1
            a02 = a02 if pr else a02 - u0 * w2
            a11 = a11 if pr else a11 - u1 * w1
            a12 = a12 if pr else a12 - u1 * w2
            a22 = a22 if pr else a22 - u2 * w2
            dinv[i, b] = di
            pa0 += a00 * e0 + a01 * e1 + a02 * e2 + u0 * ud
            pa1 += a01 * e0 + a11 * e1 + a12 * e2 + u1 * ud
            pa2 += a02 * e0 + a12 * e1 + a22 * e2 + u2 * ud
            if p >= 0:
                c, s, x10, x20 = X[i, 0, b], X[i, 1, b], X[i, 2, b], X[i, 3, b]
                c00 = a00 + a01 * x10 + a02 * x20
                c01 = a01 * c - a02 * s
                c02 = a01 * s + a02 * c
                c10 = a01 + a11 * x10 + a12 * x20
                c11 = a11 * c - a12 * s
                c12 = a11 * s + a12 * c
                c20 = a02 + a12 * x10 + a22 * x20
                c21 = a12 * c - a22 * s
                c22 = a12 * s + a22 * c
                IA[pp, 0, b] += c00 + x10 * c10 + x20 * c20
                IA[pp, 1, b] += c01 + x10 * c11 + x20 * c21
                IA[pp, 2, b] += c02 + x10 * c12 + x20 * c22
                IA[pp, 3, b] += c * c11 - s * c21
                IA[pp, 4, b] += c * c12 - s * c22
                IA[pp, 5, b] += s * c12 + c * c22
                pA[pp, 0, b] += pa0 + x10 * pa1 + x20 * pa2
                pA[pp, 1, b] += c * pa1 - s * pa2
                pA[pp, 2, b] += s * pa1 + c * pa2
    for i in range(nl):
        p = M.parent[i]
        k = M.jtype[i]
        pp = max(p, 0)
        for b in range(B):
            ap0, ap1, ap2 = a[pp, 0, b], a[pp, 1, b], a[pp, 2, b]
            if p < 0:
                ap0, ap1, ap2 = 0.0, 0.0, gravity
            c, s, x10, x20 = X[i, 0, b], X[i, 1, b], X[i, 2, b], X[i, 3, b]
            a0 = ap0 + cbias[i, 0, b]
            a1 = x10 * ap0 + c * ap1 + s * ap2 + cbias[i, 1, b]
            a2 = x20 * ap0 - s * ap1 + c * ap2 + cbias[i, 2, b]
            i00, i01, i02 = IA[i, 0, b], IA[i, 1, b], IA[i, 2, b]
            i11, i12, i22 = IA[i, 3, b], IA[i, 4, b], IA[i, 5, b]
            pr = presc[i, b] != 0
            w, ti, ai, di = presc_qdd[i, b], tau[i, b], arm[i, b], dinv[i, b]
            if k == 0:
                u0, u1, u2, pk = i00, i01, i02, pA[i, 0, b]
            elif k == 1:
                u0, u1, u2, pk = i01, i11, i12, pA[i, 1, b]
            else:
                u0, u1, u2, pk = i02, i12, i22, pA[i, 2, b]
            acc = w if pr else (ti - pk - (u0 * a0 + u1 * a1 + u2 * a2)) * di
            qdd[i, b] = acc
            if k == 0:
                a0 += acc
            elif k == 1:
                a1 += acc
            else:
                a2 += acc
            a[i, 0, b], a[i, 1, b], a[i, 2, b] = a0, a1, a2
            tau[i, b] = u0 * a0 + u1 * a1 + u2 * a2 + pk if pr else ti - ai * acc


@njit(**_JIT)
def _inputs(M, S, Q, QD, TG, TA, dt, X, V, CB, T, FE, PR, PQ, AR):
    """The inputs of the ABA at every state (kinematics, ground contact, joint torques)."""
    nl = Q.shape[1]
    pose, cs = np.zeros((nl, 3)), np.zeros((nl, 2))
    anchor, touching, cforce = np.zeros(M.cp_link.shape[0]), np.zeros(M.cp_link.shape[0]), \
        np.zeros(M.cp_link.shape[0])
    for n in range(Q.shape[0]):
        kinematics(M, Q[n], QD[n], pose, X[n], V[n], CB[n], cs)
        ground_contacts(M, S, pose, cs, V[n], anchor, touching, FE[n], cforce)
        joint_torques(M, Q[n], QD[n], TG[n], TA[n], 0, dt, T[n], PR[n], PQ[n], AR[n])


@njit(**_JIT)
def run_scalar(M, QD, X, V, CB, T, FE, PR, PQ, AR, gravity, IA, pA, dinv, acc, QDD):
    for n in range(X.shape[0]):
        aba(M, QD[n], X[n], V[n], CB[n], T[n], FE[n], PR[n], PQ[n], AR[n], gravity, IA, pA, dinv,
            acc, QDD[n])


@njit(**_JIT)
def run_soa(M, X, V, CB, T, FE, PR, PQ, AR, gravity, IA, pA, dinv, acc, QDD):
    for g in range(X.shape[0]):
        aba_soa(M, X[g], V[g], CB[g], T[g], FE[g], PR[g], PQ[g], AR[g], gravity, IA, pA, dinv, acc,
                QDD[g])


def _lanes(x, B):
    """[N, ...] -> [N / B, ..., B] (the lane last), contiguous."""
    g = x.shape[0] // B
    y = x[:g * B].reshape((g, B) + x.shape[1:])
    return np.ascontiguousarray(np.moveaxis(y, 1, -1))


def main(argv=None) -> int:
    import gpmotion
    from gpmotion.bench import sine_workload
    from gpmotion.controllers import schedule

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--lanes", type=int, default=8)
    p.add_argument("--episodes", type=int, default=8)
    p.add_argument("--repeats", type=int, default=31)
    a = p.parse_args(argv)
    fig = gpmotion.load_figure("lamp")
    scene = gpmotion.make_scene()
    tr = gpmotion.rollout(fig, scene, schedule.sines(*sine_workload(fig, a.episodes, 0)), n_steps=2000,
                          record_every=1, threads=1)
    B = a.lanes
    Q = np.ascontiguousarray(tr.q.reshape(-1, fig.nq))
    N = (len(Q) // B) * B
    Q, QD = Q[:N], np.ascontiguousarray(tr.qd.reshape(-1, fig.nv))[:N]
    TG = np.ascontiguousarray(tr.targets.reshape(-1, fig.n_act))[:N]
    TA = np.full_like(TG, 0.05)
    m = fig.model
    nl = fig.nv
    X, V, CB, T, FE = (np.zeros((N, nl, 4)), np.zeros((N, nl, 3)), np.zeros((N, nl, 3)),
                       np.zeros((N, nl)), np.zeros((N, nl, 3)))
    PR, PQ, AR = np.zeros((N, nl), dtype=np.int64), np.zeros((N, nl)), np.zeros((N, nl))
    _inputs(m, scene, Q, QD, TG, TA, 1e-3, X, V, CB, T, FE, PR, PQ, AR)
    g = scene.gravity
    lanes = [_lanes(x, B) for x in (X, V, CB, T, FE, PR, PQ, AR)]
    sc = (np.zeros((nl, 6)), np.zeros((nl, 3)), np.zeros(nl), np.zeros((nl, 3)))
    sv = (np.zeros((nl, 6, B)), np.zeros((nl, 3, B)), np.zeros((nl, B)), np.zeros((nl, 3, B)))
    qdd_s, qdd_v = np.zeros((N, nl)), np.zeros((N // B, nl, B))
    T_s, T_v = T.copy(), lanes[3].copy()

    def scalar():
        np.copyto(T_s, T)
        t0 = time.perf_counter()
        run_scalar(m, QD, X, V, CB, T_s, FE, PR, PQ, AR, g, *sc, qdd_s)
        return time.perf_counter() - t0

    def soa():
        np.copyto(T_v, lanes[3])
        t0 = time.perf_counter()
        run_soa(m, lanes[0], lanes[1], lanes[2], T_v, *lanes[4:], g, *sv, qdd_v)
        return time.perf_counter() - t0
    scalar()
    soa()
    same = (np.array_equal(_lanes(qdd_s, B).view(np.int64), qdd_v.view(np.int64))
            and np.array_equal(_lanes(T_s, B).view(np.int64), T_v.view(np.int64)))
    times = {"one at a time": [], f"{B} lanes": []}
    for _ in range(a.repeats):
        times["one at a time"].append(scalar() / N * 1e9)
        times[f"{B} lanes"].append(soa() / N * 1e9)
    print(f"lamp ABA: {N} states ({int(PR.any(axis=1).sum())} with a prescribed dof), "
          f"q̈ and joint forces bit for bit the same: {same}")
    for k, v in times.items():
        print(f"  {k:14s} ns per state: median {statistics.median(v):6.1f} ({min(v):6.1f}-{max(v):6.1f}), "
              f"best {min(v):6.1f}")
    one = times["one at a time"]
    for k, v in list(times.items())[1:]:
        r = [x / y for x, y in zip(one, v)]
        print(f"  one at a time / {k} per repeat: median {statistics.median(r):.2f} "
              f"({min(r):.2f}-{max(r):.2f}); bests {min(one) / min(v):.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
