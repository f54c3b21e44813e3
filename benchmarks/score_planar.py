"""Scoring one planar generation: the compiled poses and points against the numpy forms.

    python benchmarks/score_planar.py [--task lamp_hop] [--population 300] [--repeats 9]

Rolls out one generation of random GP controllers, then scores it (``task.score``,
which rebuilds the base pose and the sites of every recorded frame) with the
backend's compiled forms (``gpmotion.sim.geometry_fast``) and with the numpy
forms (``gpmotion.sim.geometry``), in turn, and prints the best time of each
and their ratio.  The two give the same costs bit for bit; the script checks.
"""
from __future__ import annotations

import argparse
import time
from dataclasses import replace

import numpy as np

from gpmotion.families import make_family
from gpmotion.inprocess import InProcessEvaluator
from gpmotion.sim import backend_planar, geometry
from gpmotion.task import get_task

COMPILED = (backend_planar.link_poses, backend_planar.points)


def numpy_forms(on: bool) -> None:
    """Point the planar backend at the numpy forms (on) or back at the compiled ones."""
    if on:
        backend_planar.link_poses = geometry.link_poses
        backend_planar.points = lambda m, q, poses, links, local: geometry.points_world(m, poses(), links, local)
    else:
        backend_planar.link_poses, backend_planar.points = COMPILED


def best_time(task, traj, repeats: int) -> tuple[float, np.ndarray]:
    best, costs = np.inf, None
    for _ in range(repeats):
        fresh = replace(traj)                     # nothing memoized
        t0 = time.perf_counter()
        costs = task.score(fresh, 0.5)[0]
        best = min(best, time.perf_counter() - t0)
    return best, costs


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", default="lamp_hop")
    ap.add_argument("--population", type=int, default=300)
    ap.add_argument("--repeats", type=int, default=9)
    a = ap.parse_args(argv)
    task = get_task(a.task)
    fam = make_family("gp", task)
    rng = np.random.default_rng(0)
    traj = InProcessEvaluator(task, fam).rollout([fam.random(rng) for _ in range(a.population)])
    best_time(task, traj, 1)                      # load the kernels
    times = {}
    for numpy_on in (False, True, False, True):
        numpy_forms(numpy_on)
        t, costs = best_time(task, traj, a.repeats)
        key = "numpy" if numpy_on else "compiled"
        times[key] = min(times.get(key, np.inf), t)
        if key == "compiled":
            want = costs
        elif costs.tobytes() != want.tobytes():
            raise SystemExit("the two forms gave different costs")
    numpy_forms(False)
    frames = traj.q.shape[0] * traj.q.shape[1]
    print(f"{a.task}: scoring {a.population} episodes × {traj.q.shape[1]} frames ({frames:,} frames), "
          f"best of {2 * a.repeats}: compiled {times['compiled'] * 1e3:.1f} ms, "
          f"numpy {times['numpy'] * 1e3:.1f} ms, ×{times['numpy'] / times['compiled']:.2f}; "
          f"the same costs bit for bit")


if __name__ == "__main__":
    main()
