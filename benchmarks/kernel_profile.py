"""Where a rollout step's time goes: the kernel's stages timed one by one on recorded states.

    python benchmarks/kernel_profile.py [--workload lamp|lamp_gp|herman] [--episodes 8] [--repeats 5]

The episode loop inlines every stage into one machine-code function, so a
sampling profiler sees one symbol.  This script records the states a
workload's episodes pass through (every step) and replays them through
drivers compiled with the first k stages of a step, for k = 0 (copy the
state only) up to the whole step:

    copy → kinematics → ground contact → centre of mass + senses
         → joint torques → articulated-body dynamics → integrate

A stage's time is the difference between consecutive drivers (the friction
anchors carry over from state to state, as in an episode).  The controller
(sines or the GP interpreter) is timed alone on the recorded senses.  All
drivers run in turn in one process, ``--repeats`` times, one thread; the
median per stage and the spread (min-max) across the repeats are printed in
ns per step, beside the rollout's own time per step (which adds the
recording of frames and the loop's bookkeeping).

On a loaded machine a timed run longer than the scheduler's time slice is
cut by preemptions (the same code then seems to run at two speeds, about
2x apart): keep the runs short (``--episodes 2``, or 1 for herman) so that
some of them run whole, and read the bests.

Workloads are those of ``benchmarks/compare_mujoco.py`` / ``gpmotion bench``:
``lamp`` (sines), ``lamp_gp`` (three random ~35-node trees, lamp_hop),
``herman`` (3-D, GP right arm, herman_touch_nose).
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from numba import njit

STAGES = ("copy", "kinematics", "contact", "com+senses", "torques", "aba", "integrate")


def _planar_driver(k):
    from gpmotion.sim.planar import (aba, centre_of_mass, ground_contacts, integrate,
                                     joint_torques, kinematics)
    from gpmotion.sim.senses import compute_senses

    @njit(cache=False, error_model="numpy", boundscheck=False)
    def drive(M, S, goal, Q, QD, TG, TA, w, q, qd, cforce, com, senses, senses_norm, dt, limit):
        acc = 0.0
        for n in range(Q.shape[0]):
            for i in range(q.shape[0]):
                q[i] = Q[n, i]
                qd[i] = QD[n, i]
            if k >= 1:
                kinematics(M, q, qd, w.pose, w.X, w.v, w.cbias, w.cs)
            if k >= 2:
                fext = w.fext
                for i in range(fext.shape[0]):
                    fext[i, 0] = 0.0
                    fext[i, 1] = 0.0
                    fext[i, 2] = 0.0
                ground_contacts(M, S, w.pose, w.cs, w.v, w.anchor, w.touching, fext, cforce)
            if k >= 3:
                centre_of_mass(M, w.pose, w.cs, w.v, com)
                compute_senses(M, goal, q, qd, w.pose, w.cs, w.v, com, cforce, 0.0, senses,
                               senses_norm)
            if k >= 4:
                joint_torques(M, q, qd, TG[n], TA[n], 0, dt, w.tau, w.presc, w.presc_qdd, w.arm)
            if k >= 5:
                aba(M, qd, w.X, w.v, w.cbias, w.tau, w.fext, w.presc, w.presc_qdd, w.arm,
                    S.gravity, w.IA, w.pA, w.dinv, w.acc, w.qdd)
            if k >= 6:
                integrate(q, qd, w.qdd, dt, limit)
            acc += q[0]
        return acc
    return drive


def _spatial_driver(k):
    from gpmotion.sim.spatial3d import (aba_packed, centre_of_mass, compute_senses3d,
                                        ground_contacts, integrate, joint_torques, kinematics)

    @njit(cache=False, error_model="numpy", boundscheck=False, fastmath={"contract"})
    def drive(M, S, goal, Q, QD, TG, TA, w, q, qd, cforce, com, senses, senses_norm, dt, limit):
        acc = 0.0
        for n in range(Q.shape[0]):
            for i in range(q.shape[0]):
                q[i] = Q[n, i]
            for i in range(qd.shape[0]):
                qd[i] = QD[n, i]
            if k >= 1:
                kinematics(M, q, qd, w.R, w.pos, w.E, w.r, w.v, w.cbias)
            if k >= 2:
                fext = w.fext
                for i in range(fext.shape[0]):
                    for j in range(6):
                        fext[i, j] = 0.0
                ground_contacts(M, S, w.R, w.pos, w.v, w.anchor, w.touching, fext, cforce)
            if k >= 3:
                centre_of_mass(M, w.R, w.pos, w.v, com)
                compute_senses3d(M, goal, q, qd, w.R, w.pos, w.v, com, cforce, 0.0, senses,
                                 senses_norm)
            if k >= 4:
                joint_torques(M, q, qd, TG[n], TA[n], 0, dt, w.tau, w.presc, w.presc_qdd, w.arm)
            if k >= 5:
                aba_packed(M, qd, w.E, w.r, w.v, w.cbias, w.tau, w.fext, w.presc, w.presc_qdd,
                           w.arm, S.gravity, w.Ib, w.IA, w.pA, w.U, w.Ut, w.dinv, w.uu, w.acc,
                           w.qdd, w.L6, w.b6, w.x6)
            if k >= 6:
                integrate(M, q, qd, w.qdd, dt, limit)
            acc += q[0]
        return acc
    return drive


@njit(cache=False)
def _drive_control(control, ci, cf, SN, SNN, cstate, targets, taus, dt):
    acc = 0.0
    for n in range(SN.shape[0]):
        control(ci, cf, SN[n], SNN[n], n * dt, cstate, targets, taus)
        acc += targets[0]
    return acc


def workload(name: str, episodes: int):
    """(figure, scene, controller batch, n_steps, q0, qd0, dt) of a benchmark workload."""
    import gpmotion
    from gpmotion.bench import bench_gp_trees, sine_workload
    from gpmotion.controllers import schedule
    if name == "lamp":
        fig = gpmotion.load_figure("lamp")
        return (fig, gpmotion.make_scene(), schedule.sines(*sine_workload(fig, episodes, 0)),
                2000, None, None, 1e-3)
    task, fam, trees = bench_gp_trees(0, figure="herman" if name == "herman" else "lamp")
    q0, qd0 = task.initial_state()
    return (task.figure, task.scene(), fam.encode([trees] * episodes), task.n_steps, q0, qd0,
            task.dt)


def main(argv=None) -> int:
    import gpmotion
    from gpmotion.cache import import_file
    from gpmotion.sim.backend import backend_of
    from gpmotion.sim.rollout import DIVERGE_LIMIT

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--workload", choices=("lamp", "lamp_gp", "herman"), default="lamp")
    p.add_argument("--episodes", type=int, default=8)
    p.add_argument("--repeats", type=int, default=5)
    a = p.parse_args(argv)
    fig, scene, ctrl, n_steps, q0, qd0, dt = workload(a.workload, a.episodes)
    run = lambda: gpmotion.rollout(fig, scene, ctrl, n_steps=n_steps, q0=q0, qd0=qd0, dt=dt,  # noqa: E731
                                   record_every=1, record_senses=True, threads=1)
    tr = run()
    E, F = tr.q.shape[:2]
    Q = np.ascontiguousarray(tr.q.reshape(E * F, -1))
    QD = np.ascontiguousarray(tr.qd.reshape(E * F, -1))
    TG = np.ascontiguousarray(tr.targets.reshape(E * F, -1))
    TA = np.full_like(TG, 0.05)
    SN = np.ascontiguousarray(tr.senses.reshape(E * F, -1))
    m = fig.model
    backend = backend_of(m)
    w = backend.workspace(m, scene, fig.nv, np.zeros((len(m.cp_link), backend.CONTACT_WIDTH)))
    goal = backend.goal(scene)
    ns = len(m.sense_lo)
    make = _planar_driver if backend.NAME == "planar" else _spatial_driver
    drivers = [make(k) for k in range(len(STAGES))]
    args = lambda: (m, scene, goal, Q, QD, TG, TA, w, np.zeros(fig.nq), np.zeros(fig.nv),  # noqa: E731
                    np.zeros(len(m.cp_link)), np.zeros(backend.COM_WIDTH), np.zeros(ns + 1),
                    np.zeros(ns), dt, DIVERGE_LIMIT)
    t0 = time.perf_counter()
    for d in drivers:
        d(*args())
    ctl = import_file(ctrl.module)
    SNN = np.zeros_like(SN)
    cst = np.zeros(max(1, ctrl.cstate_size))
    targets, taus = np.zeros(fig.n_act), np.zeros(fig.n_act)
    cargs = (ctl.control, np.ascontiguousarray(ctrl.ci[0]), np.ascontiguousarray(ctrl.cf[0]),
             SN, SNN, cst, targets, taus, dt)
    _drive_control(*cargs)
    print(f"compiled the drivers in {time.perf_counter() - t0:.0f} s; {E * F} states")
    times = {s: [] for s in STAGES + ("control", "rollout")}
    raw = {s: [] for s in STAGES}
    for _ in range(a.repeats):                  # in turn: the machine's load hits every stage
        prev = 0.0
        for s, d in zip(STAGES, drivers):
            t0 = time.perf_counter()
            d(*args())
            t = (time.perf_counter() - t0) / len(Q) * 1e9
            raw[s].append(t)
            times[s].append(t - prev)
            prev = t
        t0 = time.perf_counter()
        _drive_control(*cargs)
        times["control"].append((time.perf_counter() - t0) / len(Q) * 1e9)
        t0 = time.perf_counter()
        gpmotion.rollout(fig, scene, ctrl, n_steps=n_steps, q0=q0, qd0=qd0, dt=dt, threads=1)
        times["rollout"].append((time.perf_counter() - t0) / (E * n_steps) * 1e9)
    whole = statistics.median(times["rollout"])
    best = {s: min(v) for s, v in raw.items()}
    best_diff = {s: best[s] - (best[STAGES[i - 1]] if i else 0.0) for i, s in enumerate(STAGES)}
    best_diff.update(control=min(times["control"]), rollout=min(times["rollout"]))
    print(f"{a.workload}: ns per step: median of {a.repeats} per-repeat differences (min-max), "
          f"its share of the rollout's median step; difference of the bests, its share of the best step")
    for s, v in times.items():
        med = statistics.median(v)
        print(f"  {s:12s} {med:8.1f}  ({min(v):7.1f}-{max(v):7.1f})  {100 * med / whole:5.1f} %"
              f"   best {best_diff[s]:7.1f}  {100 * best_diff[s] / best_diff['rollout']:5.1f} %")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
