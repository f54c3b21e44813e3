"""Work to a solved, polished motion: `gpmotion run TASK` on its defaults, beside the old ones.

    python benchmarks/time_to_solution.py [--tasks lamp_hop,lamp_limbo] [--seeds 0,1]
        [--threads 1] [--only new|old] [--search KEY=VALUE ...] [--option KEY=VALUE ...]
        [--artifacts]

Per task and seed, one run on the old defaults (generations 40 run in full:
``OLD``) and one on today's, in this process, printing for each:

* ``steps``: simulated steps (episodes × steps each; an episode a
  divergence or a fall ended counts the steps it ran), the work a run did,
  and ``evals``;
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

``--episodes`` adds where the simulated steps went, to decide which
episodes could stop early (each a count of simulated steps):

* ``div_ran``: steps run by episodes that diverged (the kernel already ends
  an episode at the step its state turns non-finite or beyond 1e4;
  ``div_saved`` is what that stop saves against full episodes);
* ``fell_after``: steps after a planar figure's base first pitched beyond
  1 rad (the lamp's "fell"): what a stop at a final fall would save;
* ``rejected``/``rej_after`` (serial searches): mutants whose cost did not
  beat their parent's (strict replacement rejects them), and their steps
  after the first frame where a lower bound of the cost from the frames so
  far reached the parent's cost.  The bound is the monotone part of the lamp
  terms (late, head_hit, fell, pole; every other term bounded by 0), so
  lamp tasks only.

``--option KEY=VALUE`` sets a family option of the new runs (e.g.
``fast_trig=true``), as ``--search`` sets a search setting, and ``--param
KEY=VALUE`` a task parameter (e.g. ``falls_final=1``).

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
from gpmotion.tasks.lamp_hop import ARRIVED, FELL
from gpmotion.run import RunConfig, run
import gpmotion.sim.rollout as rollout_module

run_module = importlib.import_module("gpmotion.run")   # the module (gpmotion.run is also a function)
BARS = {"lamp_hop": 0.08}          # final cost a polished motion stays within
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
    """Wraps every rollout batch: time inside the kernel, simulated steps, kernels seen."""

    def __init__(self):
        self.seconds, self.steps, self.kernels = 0.0, 0, set()
        self.trace = []            # (episodes, steps) so far, after each batch
        self._run_batch = rollout_module.run_batch
        self._compiles = _Compiles()

    @property
    def compiled(self) -> int:
        return self._compiles.count

    def steps_at(self, episodes: int) -> int:
        """Steps simulated by the batch that took the count of episodes to ``episodes``."""
        return next(s for e, s in self.trace if e >= episodes)

    def __enter__(self):
        event.register("numba:compile", self._compiles)
        meter = self
        run_batch = self._run_batch

        def timed(kernel, args, n, threads=None):
            t0 = time.perf_counter()
            run_batch(kernel, args, n, threads)
            meter.seconds += time.perf_counter() - t0
            out = args[6]                      # args: (M, S, goal, st, start, prog, out)
            meter.steps += int(out.status[:n, 2].sum())      # each episode's steps simulated
            episodes = (meter.trace[-1][0] if meter.trace else 0) + n
            meter.trace.append((episodes, meter.steps))
            meter.kernels.add(kernel.__file__)

        rollout_module.run_batch = timed
        return self

    def __exit__(self, *exc):
        rollout_module.run_batch = self._run_batch
        event.unregister("numba:compile", self._compiles)


EPISODE_COLUMNS = ("div_ran", "div_saved", "fell_after", "mutants", "rejected", "rej_after")


class EpisodeMeter:
    """Wraps Task.score and SerialSearch.tell: where the steps of scored batches went."""

    def __init__(self):
        self.div_ran = self.div_saved = self.fell_after = 0
        self.rejected = self.mutants = self.rej_after = 0
        self._last = None                  # (task, traj, progress) of the last score

    def __enter__(self):
        from gpmotion.search.serial import SerialSearch
        from gpmotion.task import Task
        self._score, self._tell = Task.score, SerialSearch.tell
        meter = self

        def score(task, traj, progress=1.0):
            out = meter._score(task, traj, progress)
            meter._count(task, traj)
            meter._last = (task, traj, progress)
            return out

        def tell(search, ev):
            if search.working is not None and not (search.rescoring or search.restarting):
                meter._serial(np.array(search.scores, float), np.asarray(ev.costs, float))
            return meter._tell(search, ev)
        Task.score, SerialSearch.tell = score, tell
        return self

    def __exit__(self, *exc):
        from gpmotion.search.serial import SerialSearch
        from gpmotion.task import Task
        Task.score, SerialSearch.tell = self._score, self._tell

    @staticmethod
    def _ran(traj):
        """Steps each episode simulated (a divergence or a fall may have ended it), and a full one's."""
        return traj.steps_run, (len(traj.times) - 1) * traj.record_every

    def _count(self, task, traj):
        ran, full = self._ran(traj)
        self.div_ran += int(ran[traj.diverged].sum())
        self.div_saved += int((full - ran[traj.diverged]).sum())
        if traj.is3d:
            return
        fallen = np.abs(traj.base()[..., 0]) > FELL         # [E, F]
        first = np.where(fallen.any(axis=1), fallen.argmax(axis=1), len(traj.times) - 1)
        self.fell_after += int(np.maximum(ran - first * traj.record_every, 0).sum())

    def _serial(self, parents, costs):
        task, traj, progress = self._last
        self.mutants += costs.size
        rejected = ~(costs < parents)
        self.rejected += int(rejected.sum())
        if "distance" not in task.params or traj.is3d:
            return
        bound = lamp_bound(task, traj, progress)               # [E, F]
        reached = bound >= parents[:, None]
        first = np.where(reached.any(axis=1), reached.argmax(axis=1), len(traj.times) - 1)
        ran, _ = self._ran(traj)
        after = np.maximum(ran - first * traj.record_every, 0)
        assert np.all(reached.any(axis=1) <= rejected)          # a true bound never rejects a better one
        self.rej_after += int(after[rejected].sum())


def lamp_bound(task, traj, progress):
    """A lower bound of each lamp episode's cost from frames 0..f, for every f [E, F]."""
    w = {t.name: t.weight * t.factor(progress) for t in task.terms}
    fig = traj.figure
    d = np.linalg.norm(traj.site("base_centre") - np.array([task.params["distance"], 0.0]), axis=-1)
    arrived = np.logical_or.accumulate(d < ARRIVED, axis=1)
    late = np.where(arrived, 0.0, traj.times[None, :] / task.seconds)
    heads = [fig.contact_names.index(c) for c in ("head_tip", "head_rim")]
    force = np.maximum.accumulate(traj.contact_force[..., heads].max(axis=2), axis=1)
    head = (force > 0) + force / (fig.total_mass * 9.81)
    fell = np.maximum.accumulate(np.abs(traj.base()[..., 0]), axis=1) > FELL
    b = w["late"] * late + w["head_hit"] * head + w["fell"] * fell
    if "pole" in w:
        pen = np.maximum.accumulate(traj.pole_hit, axis=1)
        b = b + w["pole"] * ((pen > 0) + 100.0 * pen)
    return np.where(traj.diverged[:, None], -np.inf, b)      # a diverged one costs WORST anyway


def jit_signatures() -> int:
    """Compiled signatures of every numba dispatcher alive in this process."""
    from numba.core.registry import CPUDispatcher
    # type(), not isinstance(): a weak proxy to a dead object raises on __class__
    return sum(len(d.overloads) for d in gc.get_objects() if issubclass(type(d), CPUDispatcher))


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


def one_run(task: str, seed: int, search: dict, threads: int | None, artifacts: bool,
            family: str | None = None, episodes: bool = False, options: dict | None = None,
            params: dict | None = None) -> dict:
    spent: list[float] = []
    orig_finish = run_module._finish
    run_module._finish = _timed_finish(spent)
    extra = (family, options, params)
    try:
        if not episodes:
            return _one_run(task, seed, search, threads, artifacts, spent, *extra)
        with EpisodeMeter() as em:
            r = _one_run(task, seed, search, threads, artifacts, spent, *extra)
        return {**r, **{k: getattr(em, k) for k in EPISODE_COLUMNS}}
    finally:
        run_module._finish = orig_finish


def _one_run(task, seed, search, threads, artifacts, spent, family=None, options=None,
             params=None) -> dict:
    with tempfile.TemporaryDirectory() as d, KernelMeter() as meter:
        out = Path(d) / "run"
        t0 = time.perf_counter()
        fam = {} if family is None else {"family": family}
        if options:
            fam["family_options"] = dict(options)
        run(RunConfig(task=task, seed=seed, search=search, threads=threads, params=dict(params or {}),
                      **fam), out, quiet=True, artifacts=artifacts)
        wall = time.perf_counter() - t0
        best = read_json(out / "best.json", kind="best")
        rows = (out / "log.csv").read_text().splitlines()
    head = rows[0].split(",")
    log = [dict(zip(head, r.split(","))) for r in rows[1:]]
    evals = int(log[-1]["evaluations"])
    bar = BARS.get(task)
    first = next((int(r["evaluations"]) for r in log
                  if r["best_final"] and bar is not None and float(r["best_final"]) <= bar), None)
    ok = best["success"] and (bar is None or best["final_cost"] <= bar)
    return {"task": task, "seed": seed, "generations": len(log), "evals": evals,
            "steps": meter.steps, "to_bar": None if first is None else meter.steps_at(first),
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
    ap.add_argument("--option", action="append", default=[], metavar="KEY=VALUE",
                    help="a family option of the new runs (JSON value), e.g. fast_trig=true")
    ap.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                    help="task parameter of the new runs (e.g. falls_final=1)")
    ap.add_argument("--artifacts", action="store_true", help="draw the pictures, as `gpmotion run`")
    ap.add_argument("--family", default=None, help="controller family (default: gp)")
    ap.add_argument("--episodes", action="store_true",
                    help="also where the steps went (diverged, fallen, rejected mutants)")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    new = {k: _value(v) for k, v in (s.split("=", 1) for s in a.search)}
    options = {k: _value(v) for k, v in (s.split("=", 1) for s in a.option)}
    params = {k: _value(v) for k, v in (s.split("=", 1) for s in a.param)}
    kinds = [k for k in ("old", "new") if a.only in (None, k)]
    rows = []
    print(f"{'task':<22}{'seed':>5} {'':<4}{'gens':>5}{'evals':>7}{'steps':>12}{'to_bar':>12}"
          f"{'cost':>8}{'ok':>4}{'wall_s':>8}{'outside':>8}{'kernels':>8}{'jit':>5}{'finish_s':>9}", file=sys.stderr)
    for task in a.tasks.split(","):
        for seed in (int(s) for s in a.seeds.split(",")):
            for kind in kinds:
                old = {**OLD, **({"generations": OLD_GENERATIONS[task]}
                                 if task in OLD_GENERATIONS else {})}
                r = one_run(task, seed, old if kind == "old" else new, a.threads, a.artifacts,
                            a.family, a.episodes, *((options, params) if kind == "new" else ()))
                r["defaults"] = kind
                rows.append(r)
                print(f"{task:<22}{seed:>5} {kind:<4}{r['generations']:>5}{r['evals']:>7}"
                      f"{r['steps'] / 1e6:>11.2f}M"
                      f"{'-' if r['to_bar'] is None else format(r['to_bar'] / 1e6, '.2f') + 'M':>12}"
                      f"{r['cost']:>8.4f}{'yes' if r['ok'] else 'no':>4}{r['wall_s']:>8.1f}"
                      f"{r['outside']:>8.1%}{r['kernels']:>5} ({r['compiled']}){r['jit']:>5}{r['finish_s']:>9.1f}",
                      file=sys.stderr, flush=True)
                if a.episodes:
                    print("    " + "  ".join(f"{k} {r[k] / 1e6:.2f}M" if k not in ("mutants", "rejected")
                                             else f"{k} {r[k]}" for k in EPISODE_COLUMNS),
                          file=sys.stderr, flush=True)
    if a.json:
        print(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
