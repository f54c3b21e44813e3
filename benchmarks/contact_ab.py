"""Planar ground contact, branching against branch-free, timed in turn in one process.

    python benchmarks/contact_ab.py [--workload lamp|lamp_gp] [--episodes 8] [--repeats 31]

Replays the states a workload's episodes pass through (every step; the
workloads of benchmarks/kernel_profile.py) through three drivers: kinematics
alone, kinematics + ``planar.ground_contacts`` and kinematics +
``planar.ground_contacts_branchfree``, in turn, ``--repeats`` times.  Prints
per contact form the ns per step of the contact stage (driver minus
kinematics alone): median over the repeats with its min-max, and from the
best run of each driver; and whether both forms left the same forces,
anchors and flags, bit for bit, after every state and on random states of
the shipped planar figures (:func:`check_random_states`).

The branch-free form computes every contact point's force, anchor and flag
and then selects (penetrating or not, sticking or slipping), the form a
structure-of-arrays kernel over episodes would need; in the scalar kernel the
branches it removes are well predicted (a foot stays on the ground or in the
air for many steps), so it does more work for nothing.
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from numba import njit

from gpmotion.sim.planar import _CHOSEN, contact_point_world, ground_contacts, kinematics

_BF = dict(error_model="numpy", boundscheck=False, inline="always")   # planar.py's flags, uncached


@njit(**_BF)
def _deepest_branchfree(M, pose, cs, fth, fx, fz, ground_z, nmax, mark):
    """:func:`_deepest` with selects in place of the data-dependent branches."""
    nc = M.cp_link.shape[0]
    for k in range(nc):
        mark[k] = ground_z - contact_point_world(M, pose, cs, fth, fx, fz, k)[4]
    for r in range(nmax):
        j, deepest = -1, 0.0
        for k in range(nc):
            mk = mark[k]
            better = deepest < mk < _CHOSEN
            j = k if better else j
            deepest = mk if better else deepest
        jj = max(j, 0)
        mark[jj] = _CHOSEN if j >= 0 else mark[jj]


@njit(**_BF)
def ground_contacts_branchfree(M, S, pose, cs, v, anchor, touching, fext, cforce):
    """:func:`ground_contacts` without data-dependent branches: every contact
    point's force, anchor and touching flag are computed and then selected
    (penetrating or not, sticking or slipping), so the same operations run
    whatever the state — bitwise the same results (a force that does not
    apply leaves ``fext`` as it was, a select of the stored value rather
    than an added zero, so even the sign of a zero is kept).  The branches
    left depend on the model and scene only (a point on the fixed root body,
    ``max_contacts``)."""
    fth, fx, fz = M.fixed_pose[0], M.fixed_pose[1], M.fixed_pose[2]
    ground, ground_z, k_ground, c_ground = S.ground, S.ground_z, S.k_ground, S.c_ground
    k_tangent, c_tangent, mu = S.k_tangent, S.c_tangent, S.mu
    nmax = S.max_contacts
    if nmax > 0 and ground != 0:
        _deepest_branchfree(M, pose, cs, fth, fx, fz, ground_z, nmax, cforce)
    for k in range(M.cp_link.shape[0]):
        chosen = nmax == 0 or cforce[k] == _CHOSEN    # read before cforce[k] is written
        link, px, pz, x, z = contact_point_world(M, pose, cs, fth, fx, fz, k)
        moving = link >= 0
        li = max(link, 0)
        c, s = cs[li, 0], cs[li, 1]
        w = v[li, 0]
        lx, lz = v[li, 1] - w * pz, v[li, 2] + w * px
        vx, vz = c * lx - s * lz, s * lx + c * lz
        vx = vx if moving else 0.0
        vz = vz if moving else 0.0
        pen = ground_z - z
        on = ground != 0 and chosen and not (pen <= 0.0)
        fn = k_ground * pen - c_ground * vz
        fn = 0.0 if fn < 0.0 else fn
        tk, ak = touching[k], anchor[k]
        a1 = x if tk == 0.0 else ak
        ft = -k_tangent * (x - a1) - c_tangent * vx
        lim = mu * fn
        slip = ft > lim or ft < -lim
        fts = lim if ft > 0 else -lim
        a2 = x + (fts + c_tangent * vx) / k_tangent if k_tangent > 0 else x
        ft = fts if slip else ft
        a1 = a2 if slip else a1
        anchor[k] = a1 if on else ak
        touching[k] = 1.0 if on else (tk if ground == 0 else 0.0)
        cforce[k] = fn if on else 0.0
        flx, flz = c * ft + s * fn, -s * ft + c * fn
        add = on and moving
        f0, f1, f2 = fext[li, 0], fext[li, 1], fext[li, 2]
        fext[li, 0] = f0 + (px * flz - pz * flx) if add else f0
        fext[li, 1] = f1 + flx if add else f1
        fext[li, 2] = f2 + flz if add else f2


def check_random_states(seed: int = 21, trials: int = 60) -> int:
    """Both forms on random states of the shipped planar figures, the ground near a
    contact point, random friction state and ``fext`` (signed zeros included),
    every scene switch; returns the number of cases, raises on a difference."""
    import gpmotion
    from gpmotion.sim.planar import fixed_point_world, point_world
    rng = np.random.default_rng(seed)
    scenes = [dict(mu=0.6, k_tangent=4000.0), dict(mu=0.0, k_tangent=4000.0),
              dict(mu=0.6, k_tangent=0.0), dict(mu=0.6, k_tangent=4000.0, max_contacts=1),
              dict(mu=0.3, k_tangent=2000.0, max_contacts=2), dict(mu=0.6, ground=False)]
    cases = 0
    for name in ("lamp", "starman", "beryl"):
        M = gpmotion.load_figure(name).model
        n, nc = len(M.parent), len(M.cp_link)
        for kw in scenes:
            scene = gpmotion.make_scene(**kw)
            for _ in range(trials):
                q, qd = rng.uniform(-1.5, 1.5, n), rng.uniform(-3.0, 3.0, n)
                pose, X, v, cbias, cs = (np.zeros((n, 3)), np.zeros((n, 4)), np.zeros((n, 3)),
                                         np.zeros((n, 3)), np.zeros((n, 2)))
                kinematics(M, q, qd, pose, X, v, cbias, cs)
                heights = [point_world(pose, cs, lk, *pt)[1] if lk >= 0 else
                           fixed_point_world(*M.fixed_pose, *pt)[1] for lk, pt in zip(M.cp_link, M.cp_pos)]
                sc = scene._replace(ground_z=float(rng.choice(heights) + rng.uniform(-0.03, 0.08)))
                state = (rng.uniform(-1, 1, nc), (rng.random(nc) < 0.5).astype(float),
                         rng.choice([0.0, -0.0, 1.5, -2.0], size=(n, 3)), rng.uniform(0, 5, nc))
                outs = []
                for f in (ground_contacts, ground_contacts_branchfree):
                    a, t, fe, c = (x.copy() for x in state)
                    f(M, sc, pose, cs, v, a, t, fe, c)
                    outs.append((a, t, fe, c))
                for old, new in zip(*outs):
                    if not np.array_equal(old.view(np.int64), new.view(np.int64)):
                        raise AssertionError(f"{name} {kw}: the forms differ")
                cases += 1
    return cases


def _driver(contact):
    @njit(cache=False, error_model="numpy", boundscheck=False)
    def drive(M, S, Q, QD, w, q, qd, cforce, F, A):
        for n in range(Q.shape[0]):
            for i in range(q.shape[0]):
                q[i] = Q[n, i]
                qd[i] = QD[n, i]
            kinematics(M, q, qd, w.pose, w.X, w.v, w.cbias, w.cs)
            fext = w.fext
            for i in range(fext.shape[0]):
                fext[i, 0] = 0.0
                fext[i, 1] = 0.0
                fext[i, 2] = 0.0
            if contact == 1:
                ground_contacts(M, S, w.pose, w.cs, w.v, w.anchor, w.touching, fext, cforce)
            elif contact == 2:
                ground_contacts_branchfree(M, S, w.pose, w.cs, w.v, w.anchor, w.touching, fext,
                                           cforce)
            if F.shape[0] > 0:
                F[n] = fext[0, 1] + fext[fext.shape[0] - 1, 2] + cforce[0]
                A[n] = w.anchor[0] + w.touching[0]
        return 0
    return drive


def main(argv=None) -> int:
    import gpmotion
    from gpmotion.sim.backend import backend_of

    from kernel_profile import workload

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--workload", choices=("lamp", "lamp_gp"), default="lamp")
    p.add_argument("--episodes", type=int, default=8)
    p.add_argument("--repeats", type=int, default=31)
    a = p.parse_args(argv)
    fig, scene, ctrl, n_steps, q0, qd0, dt = workload(a.workload, a.episodes)
    tr = gpmotion.rollout(fig, scene, ctrl, n_steps=n_steps, q0=q0, qd0=qd0, dt=dt,
                          record_every=1, threads=1)
    E, F = tr.q.shape[:2]
    Q = np.ascontiguousarray(tr.q.reshape(E * F, -1))
    QD = np.ascontiguousarray(tr.qd.reshape(E * F, -1))
    m = fig.model
    backend = backend_of(m)
    nc = len(m.cp_link)

    def args(check):
        w = backend.workspace(m, scene, fig.nv, np.zeros((nc, backend.CONTACT_WIDTH)))
        k = len(Q) if check else 0
        return (m, scene, Q, QD, w, np.zeros(fig.nq), np.zeros(fig.nv), np.zeros(nc),
                np.zeros(k), np.zeros(k))
    names = ("kinematics", "branching", "branch-free")
    drivers = [_driver(c) for c in range(3)]
    checks = []
    for d in drivers:
        x = args(True)
        d(*x)
        checks.append((x[8], x[9]))
    cases = check_random_states()
    same = all(np.array_equal(c.view(np.int64), checks[1][i].view(np.int64))
               for i, c in enumerate(checks[2]))
    raw = {n: [] for n in names}
    for _ in range(a.repeats):
        for n, d in zip(names, drivers):
            x = args(False)
            t0 = time.perf_counter()
            d(*x)
            raw[n].append((time.perf_counter() - t0) / len(Q) * 1e9)
    print(f"{a.workload}: {len(Q)} states (max_contacts {scene.max_contacts}), {a.repeats} repeats; "
          f"same forces/anchors bit for bit: {same} (replay), and on {cases} random states")
    print(f"  kinematics alone: median {statistics.median(raw['kinematics']):.1f} ns, "
          f"best {min(raw['kinematics']):.1f} ns")
    for n in names[1:]:
        diff = [x - k for x, k in zip(raw[n], raw["kinematics"])]
        print(f"  {n:12s} contact stage: median {statistics.median(diff):6.1f} ns "
              f"({min(diff):6.1f}-{max(diff):6.1f}), from the bests "
              f"{min(raw[n]) - min(raw['kinematics']):6.1f} ns")
    ratio = [b / f for b, f in zip(raw["branching"], raw["branch-free"])]
    print(f"  kinematics+contact, branching/branch-free per repeat: median {statistics.median(ratio):.3f} "
          f"({min(ratio):.3f}-{max(ratio):.3f}); bests {min(raw['branching']) / min(raw['branch-free']):.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
