"""GP vs BSR on one task, one actuation and one evaluation budget.

Each family runs K seeds; every run gets the same number of evaluations.
The table reports the final best controller re-scored with every style term
at full weight (progress 1), the success rate against the task's threshold,
the evaluations needed to first reach it, and wall time; the plot shows
best-so-far against evaluations (median and quartile band per family), like
Auslander et al.'s Figs. 7–8.
"""
from __future__ import annotations

import csv
import io
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from .evaluators import make_evaluator
from .families import make_family
from .records import atomic_write_json, atomic_write_text
from .replay import replay_genome
from .search.adapters import make_search
from .task import get_task


def _search_opts(family: str, budget: int, population: int):
    if family == "gp":
        pop = min(population, budget)
        return {"population": pop, "generations": max(1, budget // pop - 1)}
    return {"n_working": 10, "n_generations": max(1, budget // 10 - 1)}


def run_one(task, family_name, seed, budget, actuation, population, workers=0, scheduler=None,
            family_options=None):
    """One search; returns a dict with the curve and the final numbers."""
    fam = make_family(family_name, task, **(family_options or {}).get(family_name, {}))
    search = make_search(fam, seed, **_search_opts(family_name, budget, population))
    ev = make_evaluator(task, fam, workers=workers, scheduler=scheduler, actuation=actuation)
    evals, curve, first_success = 0, [], None
    t0 = time.perf_counter()
    try:
        while not search.done and evals < budget:
            genomes = search.ask()
            result = ev.evaluate(genomes, search.progress)
            search.tell(result)
            evals += len(genomes)
            curve.append((evals, search.best_cost))
            if first_success is None and result.success.any():
                first_success = evals
    finally:
        ev.close()
    wall = time.perf_counter() - t0
    _, costs, _, ok = replay_genome(task, fam, actuation, search.best)
    return {"family": family_name, "seed": seed, "evaluations": evals, "final_cost": float(costs[0]),
            "success": bool(ok[0]), "first_success": first_success, "wall_s": wall,
            "curve": curve}


def summarize(runs: list[dict]) -> list[dict]:
    rows = []
    for fam in dict.fromkeys(r["family"] for r in runs):
        rs = [r for r in runs if r["family"] == fam]
        c = np.array([r["final_cost"] for r in rs])
        firsts = [r["first_success"] for r in rs if r["first_success"] is not None]
        rows.append({"controller": fam, "runs": len(rs),
                     "cost_q25": float(np.percentile(c, 25)), "cost_median": float(np.median(c)),
                     "cost_q75": float(np.percentile(c, 75)),
                     "success_rate": float(np.mean([r["success"] for r in rs])),
                     "evals_to_success_median": float(np.median(firsts)) if firsts else None,
                     "wall_s_median": float(np.median([r["wall_s"] for r in rs]))})
    return rows


def table_markdown(rows) -> str:
    head = "| controller | runs | best cost median [q25, q75] | success | evals to success (median) | wall s (median) |"
    lines = [head, "|---|---|---|---|---|---|"]
    for r in rows:
        ets = "—" if r["evals_to_success_median"] is None else f"{r['evals_to_success_median']:,.0f}"
        lines.append(f"| {r['controller']} | {r['runs']} | {r['cost_median']:.3f} "
                     f"[{r['cost_q25']:.3f}, {r['cost_q75']:.3f}] | {100 * r['success_rate']:.0f}% | "
                     f"{ets} | {r['wall_s_median']:.1f} |")
    return "\n".join(lines) + "\n"


def _bands(runs, budget):
    grid = np.linspace(0, budget, 60)[1:]
    series = {}
    for fam in dict.fromkeys(r["family"] for r in runs):
        ys = []
        for r in (r for r in runs if r["family"] == fam):
            e = np.array([p[0] for p in r["curve"]])
            b = np.array([p[1] for p in r["curve"]])
            idx = np.searchsorted(e, grid, side="right") - 1
            ys.append(np.where(idx >= 0, b[np.clip(idx, 0, None)], np.nan))
        y = np.array(ys)
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)   # before a run's first point
            series[fam] = (grid, *np.nanpercentile(y, [25, 50, 75], axis=0))
    return series


def compare(task_name, controllers, seeds, budget, out, *, actuation="pd", params=None,
            population=100, workers=0, scheduler=None, family_options=None, quiet=False):
    from . import render
    task = get_task(task_name, **(params or {}))
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    runs = []
    for fam in controllers:
        for seed in range(seeds):
            r = run_one(task, fam, seed, budget, actuation, population, workers, scheduler,
                        family_options)
            runs.append(r)
            if not quiet:
                print(f"{fam:<10} seed {seed}: cost {r['final_cost']:.3f} "
                      f"{'solved' if r['success'] else 'not solved'} in {r['wall_s']:.1f}s",
                      file=sys.stderr, flush=True)
    rows = summarize(runs)
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    atomic_write_text(out / "compare.csv", buf.getvalue())
    md = (f"{task.name}, actuation {actuation}, {budget:,} evaluations per run, {seeds} seeds; "
          f"cost re-scored at full style weight (lower is better)\n\n" + table_markdown(rows))
    atomic_write_text(out / "compare.md", md)
    atomic_write_json(out / "runs.json", {"task": task.name, "params": task.p, "actuation": actuation,
                                          "budget": budget, "runs": runs})
    render.curves_band(out / "curves.png", _bands(runs, budget), xlabel="evaluations",
                       ylabel="best cost so far (lower is better)",
                       title=f"{task.name}: GP vs BSR ({actuation})")
    return rows, md
