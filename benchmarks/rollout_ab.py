"""Simulator speed of two checkouts of gpmotion, measured alternately in one run.

    python benchmarks/rollout_ab.py BASE_DIR NEW_DIR [--rounds 3] [--only lamp_gp]

runs ``gpmotion bench --json --no-gp --no-warm-start`` for the three
workloads of ``gpmotion bench`` — lamp (sines), lamp driven by GP trees
(``--controller gp``) and herman (3-D, GP arm) — with ``PYTHONPATH`` set to
each checkout in turn (base, new, base, new, ...), so both see the same
machine load; a first untimed pass per checkout compiles the kernels.
Prints one JSON object: per workload the median and the best single-thread
``steps_per_s`` of each checkout and new/base of each.  Read the best: on the
shared 2-core machine one process running one kernel swings between two
speeds (1.06 and 1.76 M steps/s for the sine lamp, back and forth within a
minute: noise from outside the process), so a median of a few runs depends
on how many landed in the slow mode, while the best of each side says what
its code can do.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys

WORKLOADS = {"lamp": [], "lamp_gp": ["--controller", "gp"], "herman": ["--figure", "herman"]}


def bench(checkout: str, args: list[str]) -> dict:
    env = dict(os.environ, PYTHONPATH=os.path.abspath(checkout))
    out = subprocess.run([sys.executable, "-m", "gpmotion", "bench", "--json", "--no-gp",
                          "--no-warm-start", *args], env=env, check=True, capture_output=True,
                         text=True, cwd=os.path.abspath(checkout)).stdout
    return json.loads(out)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("base")
    p.add_argument("new")
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--only", choices=sorted(WORKLOADS), action="append",
                   help="measure only this workload (repeatable; default: all three)")
    a = p.parse_args(argv)
    workloads = {w: WORKLOADS[w] for w in (a.only or WORKLOADS)}
    sides = {"base": a.base, "new": a.new}
    for side in sides.values():                        # compile (untimed)
        for args in workloads.values():
            bench(side, args + ["--quick"])
    runs = {w: {s: [] for s in sides} for w in workloads}
    for _ in range(a.rounds):
        for w, args in workloads.items():
            for s, path in sides.items():
                runs[w][s].append(bench(path, args)["steps_per_s"])
    result = {}
    for w, r in runs.items():
        med = {s: statistics.median(v) for s, v in r.items()}
        top = {s: max(v) for s, v in r.items()}
        result[w] = {"steps_per_s_base": med["base"], "steps_per_s_new": med["new"],
                     "new_over_base": med["new"] / med["base"],
                     "best_base": top["base"], "best_new": top["new"],
                     "best_new_over_base": top["new"] / top["base"], "runs": r}
    print(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
