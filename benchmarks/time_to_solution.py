"""Work to a solved, polished motion: `gpmotion run TASK` on its defaults, beside the old ones.

    python benchmarks/time_to_solution.py [--tasks lamp_hop,lamp_limbo] [--seeds 0,1]
        [--threads 1] [--only new|old] [--search KEY=VALUE ...] [--artifacts]

Per task and seed, one run on the old defaults (generations 40 run in full:
``OLD``) and one on today's, in this process, printing for each:

* ``steps``: simulated steps (episodes × steps each; a diverged episode
  counts the steps it ran), the work a run did, and ``evals``;
* ``to_bar``: steps until the final-weights best first reached the bar
  (a run that stops there would have done this much work);
* ``cost`` and ``solved``: best.json's final cost (every term at full
  weight) and success; ``ok``: solved with cost ≤ the task's bar;
* ``wall_s`` and ``outside``: wall time of the run (search, best.json and,
  with ``--artifacts``, the pictures) and the fraction of it spent outside
  the rollout kernel (encoding, scoring, breeding, logging, pictures);
* ``kernels``: distinct rollout kernels the run called, and how many
  numba compiled cold (0 on a warm cache); ``jit``: numba-compiled functions
  of gpmotion the process holds after the run, counted per signature
  (compiled or loaded from the cache; a run in a fresh process);
* ``finish_s``: of the wall time, what the end of the run took (replay of
  the best, best.json and, with ``--artifacts``, the pictures and report).

Seconds depend on the machine and its load; steps and the ratios do not.
"""
from __future__ import annotations

import argparse
import gc
import importlib
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from numba.core import event

from gpmotion.records import read_json
from gpmotion.run import RunConfig, run
import gpmotion.sim.rollout as rollout_module

run_module = importlib.import_module("gpmotion.run")   # the module (gpmotion.run is also a function)
BARS = {"lamp_hop": 0.08}          # final cost a polished motion stays within (issue 50)
# the defaults before the stop criteria: every generation run, phases over all of them
OLD = {"patience": 0, "phase_span": 0}
OLD_GENERATIONS = {"lamp_hop": 40, "lamp_limbo": 40}


class _Compiles(event.Listener):
    """Counts numba's compile events of rollout kernels (fired on a cache miss only)."""

    def __init__(self):
        self.count = 0

    def on_start(self, ev):
        if getattr(ev.data.get("dispatcher"), "__name__", "") == "rollout_batch":
            self.count += 1

    def on_end(self, ev):
        pass


class KernelMeter:
    """Wraps every rollout kernel: time inside it, simulated steps, kernels seen."""

    def __init__(self):
        self.seconds, self.steps, self.kernels = 0.0, 0, set()
        self._orig = rollout_module.kernel_for
        self._compiles = _Compiles()

    @property
    def compiled(self) -> int:
        return self._compiles.count

    def __enter__(self):
        event.register("numba:compile", self._compiles)
        meter = self

        class Timed:
            def __init__(self, kernel):
                self.kernel = kernel

            def rollout_batch(self, M, S, goal, st, start, prog, out):
                t0 = time.perf_counter()
                self.kernel.rollout_batch(M, S, goal, st, start, prog, out)
                meter.seconds += time.perf_counter() - t0
                div = out.status[:, 0] == 1
                meter.steps += int(np.where(div, out.status[:, 1] + 1, start.n_steps).sum())
                meter.kernels.add(self.kernel.__file__)

        rollout_module.kernel_for = lambda module, backend: Timed(self._orig(module, backend))
        return self

    def __exit__(self, *exc):
        rollout_module.kernel_for = self._orig
        event.unregister("numba:compile", self._compiles)


def jit_signatures() -> int:
    """Compiled signatures of every numba dispatcher alive in this process."""
    from numba.core.registry import CPUDispatcher
    return sum(len(d.overloads) for d in gc.get_objects() if isinstance(d, CPUDispatcher))


def _timed_finish(spent: list):
    """run._finish wrapped to add its wall time to ``spent``."""
    inner = run_module._finish

    def finish(*args, **kw):
        t0 = time.perf_counter()
        try:
            return inner(*args, **kw)
        finally:
            spent.append(time.perf_counter() - t0)
    return finish


def one_run(task: str, seed: int, search: dict, threads: int | None, artifacts: bool) -> dict:
    spent: list[float] = []
    orig_finish = run_module._finish
    run_module._finish = _timed_finish(spent)
    try:
        return _one_run(task, seed, search, threads, artifacts, spent)
    finally:
        run_module._finish = orig_finish


def _one_run(task, seed, search, threads, artifacts, spent) -> dict:
    with tempfile.TemporaryDirectory() as d, KernelMeter() as meter:
        out = Path(d) / "run"
        t0 = time.perf_counter()
        run(RunConfig(task=task, seed=seed, search=search, threads=threads), out, quiet=True,
            artifacts=artifacts)
        wall = time.perf_counter() - t0
        best = read_json(out / "best.json", kind="best")
        rows = (out / "log.csv").read_text().splitlines()
    head = rows[0].split(",")
    log = [dict(zip(head, r.split(","))) for r in rows[1:]]
    evals = int(log[-1]["evaluations"])
    per_eval = meter.steps / max(1, evals + 1)            # + the replay of the best
    bar = BARS.get(task)
    first = next((int(r["evaluations"]) for r in log
                  if r["best_final"] and bar is not None and float(r["best_final"]) <= bar), None)
    ok = best["success"] and (bar is None or best["final_cost"] <= bar)
    return {"task": task, "seed": seed, "generations": len(log), "evals": evals,
            "steps": meter.steps, "to_bar": None if first is None else round(first * per_eval),
            "cost": round(best["final_cost"], 4), "solved": best["success"], "ok": bool(ok),
            "wall_s": round(wall, 1), "outside": round(1 - meter.seconds / wall, 3),
            "kernels": len(meter.kernels), "compiled": meter.compiled, "jit": jit_signatures(),
            "finish_s": round(sum(spent), 1)}


def _value(text: str):
    try:
        return json.loads(text)
    except ValueError:
        return text


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", default="lamp_hop")
    ap.add_argument("--seeds", default="0", help="comma list")
    ap.add_argument("--threads", type=int, default=None)
    ap.add_argument("--only", choices=["old", "new"], default=None)
    ap.add_argument("--search", action="append", default=[], metavar="KEY=VALUE",
                    help="a search setting of the new runs (JSON value)")
    ap.add_argument("--artifacts", action="store_true", help="draw the pictures, as `gpmotion run`")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    new = {k: _value(v) for k, v in (s.split("=", 1) for s in a.search)}
    kinds = [k for k in ("old", "new") if a.only in (None, k)]
    rows = []
    print(f"{'task':<22}{'seed':>5} {'':<4}{'gens':>5}{'evals':>7}{'steps':>12}{'to_bar':>12}"
          f"{'cost':>8}{'ok':>4}{'wall_s':>8}{'outside':>8}{'kernels':>8}{'jit':>5}{'finish_s':>9}", file=sys.stderr)
    for task in a.tasks.split(","):
        for seed in (int(s) for s in a.seeds.split(",")):
            for kind in kinds:
                old = {**OLD, **({"generations": OLD_GENERATIONS[task]}
                                 if task in OLD_GENERATIONS else {})}
                r = one_run(task, seed, old if kind == "old" else new, a.threads, a.artifacts)
                r["defaults"] = kind
                rows.append(r)
                print(f"{task:<22}{seed:>5} {kind:<4}{r['generations']:>5}{r['evals']:>7}"
                      f"{r['steps'] / 1e6:>11.2f}M"
                      f"{'-' if r['to_bar'] is None else format(r['to_bar'] / 1e6, '.2f') + 'M':>12}"
                      f"{r['cost']:>8.4f}{'yes' if r['ok'] else 'no':>4}{r['wall_s']:>8.1f}"
                      f"{r['outside']:>8.1%}{r['kernels']:>5} ({r['compiled']}){r['jit']:>5}{r['finish_s']:>9.1f}",
                      file=sys.stderr, flush=True)
    if a.json:
        print(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
