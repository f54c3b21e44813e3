"""Controller families side by side on one task, one actuation and one
evaluation budget — a study (:mod:`gpmotion.study`) of one configuration per
family, so its searches run through the run loop and its results are a
ledger (``OUT/results.jsonl``); the same command resumes a cut comparison.

Each family runs K seeds (its search's settings for the budget are the
family's ``budget_settings``); every run gets the same evaluation budget (a
serial search's re-scores of its working set when style terms phase in are
evaluations too, and come out of the budget).  The table reports each run's
best controller under the final scoring (every style term at full weight,
progress 1), replayed; the success rate against the task's threshold; the
evaluations needed to first reach it; and wall time.  The plot shows the
same scoring against evaluations: each run's best so far under the final
weights (monotone; median and quartile band per family, like Auslander et
al.'s Figs. 7–8), so it ends at the table's numbers; the progress window in
which style terms phase in is shaded.  Under a curriculum (the scene eases
in), the final scoring is only known for evaluations made in the final
scene, so the curves start there (the figure says so).

Written to the output folder: compare.md / compare.csv (the table),
runs.json (every run, with its curves), curves.csv (the plotted medians and
quartiles), curves.png, and best/FAMILY-seedK.json, each run's best
controller as a ``best.json``-style file (``gpmotion replay`` reads it); the
study's own files: study.json, results.jsonl, controllers/, runs/.
"""
from __future__ import annotations

import csv
import io
import sys
from pathlib import Path

import numpy as np

from .compare_summary import _bands, summarize
from .families import make_family
from .plugins import loaded as loaded_plugins
from .records import atomic_write_json, atomic_write_text, envelope, read_json
from .task import get_task, task_id


def comparison_spec(task, controllers, seeds, budget, actuation, params, population,
                    family_options) -> dict:
    """The study of a comparison: one configuration per family, seeds 0..K-1
    (report seeds: nothing was chosen on them), the family's settings for the budget."""
    configs = {}
    for name in controllers:
        options = dict((family_options or {}).get(name, {}))
        fam = make_family(name, task, **options)
        settings = fam.budget_settings(budget, population if fam.takes_population else None)
        configs[name] = {"task": task.name, "family": name, "params": dict(params or {}),
                         "options": options, "actuation": actuation, "judge": "task",
                         "search": {k: v.item() if hasattr(v, "item") else v
                                    for k, v in settings.items() if v is not None},
                         "label": name}
    return {"study": {"name": "compare", "title": f"{task.name}: {' vs '.join(controllers)}, "
                      f"{budget:,} evaluations per run ({actuation})",
                      "report_seeds": list(range(seeds))},
            "configurations": configs}


def _log_curves(run_dir: Path) -> dict:
    """A run's curves from its log.csv: best so far under the final weights
    (None where unknown), under the generation's weights, progress; and the
    evaluations when the first solver appeared."""
    from .records import read_text
    rows = list(csv.DictReader(io.StringIO(read_text(run_dir / "log.csv", 1 << 30, follow=False))))
    curve, current, progress, first = [], [], [], None
    for r in rows:
        e = int(r["evaluations"])
        curve.append((e, float(r["best_final"]) if r.get("best_final") not in (None, "") else None))
        current.append((e, float(r["best_so_far"])))
        progress.append((e, float(r["progress"])))
        if first is None and int(r.get("solved") or 0) > 0:
            first = e
    return {"curve": curve, "curve_current": current, "progress": progress,
            "first_success": first}


def _run_record(out: Path, row: dict) -> dict:
    """runs.json's record of one ledger row (the run's full curves from its log)."""
    run = {"family": row["config"], "seed": row["seed"], "evaluations": row["evaluations"],
           "final_cost": row["cost"], "success": bool(row["success"]), "wall_s": row["wall_s"],
           **_log_curves(out / "runs" / f"{row['config']}-seed{row['seed']}")}
    return run


def table_markdown(rows) -> str:
    # the best by cost need not be a solver: how many runs met one, and when, is a column of its own
    head = ("| controller | runs | best cost median [q25, q75] | success | "
            "runs that found a solver: evals to the first (median) | wall s (median) |")
    lines = [head, "|---|---|---|---|---|---|"]
    for r in rows:
        n = r["runs_with_solver"]
        ets = f"{n} / {r['runs']}" + ("" if n == 0 else f": {r['evals_to_success_median']:,.0f}")
        lines.append(f"| {r['controller']} | {r['runs']} | {r['cost_median']:.3f} "
                     f"[{r['cost_q25']:.3f}, {r['cost_q75']:.3f}] | {100 * r['success_rate']:.0f}% | "
                     f"{ets} | {r['wall_s_median']:.1f} |")
    return "\n".join(lines) + "\n"


def phase_window(task) -> tuple[float, float] | None:
    """Progress (a, b) from the first style term (or curriculum) starting to
    phase in to the last reaching full weight; None if nothing is phased."""
    spans = [t.phase for t in task.terms if t.weight != 0 and t.phase[1] > t.phase[0]]
    spans += [e.phase for e in task.curriculum.values() if e.phase[1] > e.phase[0]]
    if not spans:
        return None
    return min(a for a, _ in spans), max(b for _, b in spans)


def _evals_at(run, progress: float, strict: bool) -> float:
    """Evaluations made when the run's progress first passed (or reached) ``progress``."""
    for e, p in run["progress"]:
        if p > progress or (not strict and p >= progress):
            return float(e)
    return float(run["evaluations"])


def _window_evals(runs, window):
    """The phase-in window in evaluations: earliest start, latest end over runs."""
    if window is None:
        return None
    a, b = window
    return (min(_evals_at(r, a, True) for r in runs), max(_evals_at(r, b, False) for r in runs))


def _curves_csv(series) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["controller", "evaluations", "q25", "median", "q75"])
    for fam, (x, q25, q50, q75) in series.items():
        for row in zip(x, q25, q50, q75):
            w.writerow([fam, *(repr(float(v)) for v in row)])
    return buf.getvalue()


def plot_curves(path, series, task, window, window_evals, actuation):
    """Best final (log.csv's best_final: the best under the final weights), median
    and quartile band over the seeds, per family."""
    from matplotlib.figure import Figure

    from .render import _save_png
    fig = Figure(figsize=(6.5, 4))
    ax = fig.add_subplot()
    if window_evals is not None:
        lo, hi = window_evals
        ax.axvspan(lo, hi, color="0.5", alpha=0.15, lw=0,
                   label=f"style terms phase in (progress {window[0]:g}–{window[1]:g})")
    for name, (x, q25, q50, q75) in series.items():
        (line,) = ax.plot(x, q50, lw=1.6, drawstyle="steps-post", label=str(name))
        ax.fill_between(x, q25, q75, color=line.get_color(), alpha=0.25, lw=0, step="post")
    ax.set_xlabel("evaluations")
    ys = np.concatenate([np.asarray(v[1:], float).ravel() for v in series.values()])
    ys = ys[np.isfinite(ys)]
    log = ys.size and ys.min() > 0 and ys.max() > 20 * ys.min()   # families far apart
    if log:
        ax.set_yscale("log")
    ax.set_ylabel("best final (final weights): median, 25–75 %\n(lower is better"
                  + (", log scale)" if log else ")"))   # log.csv's best_final, as the progress line
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(f"{task.name}: {' vs '.join(map(str, series))} ({actuation})")
    if task.curriculum:
        ax.text(0.01, 0.01, "curriculum: earlier evaluations ran in an easier scene, so the\n"
                "final-weight cost is known only once the final scene is reached",
                transform=ax.transAxes, fontsize=7, va="bottom")
    fig.set_layout_engine("constrained")
    _save_png(fig, path, 120)


def check_out_dir(out, force: bool, digest: str | None = None) -> Path:
    """The output folder: new, empty, or this comparison's (resumed); another
    comparison's or anything else only with ``force``, which moves it aside."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise ValueError(f"--out {out}: exists and is not a folder")
    if out.is_dir() and any(out.iterdir()):
        same = False
        if digest is not None and (out / "study.json").is_file():
            from .study.ledger import read_study
            try:
                same = read_study(out)["digest"] == digest
            except ValueError:
                same = False
        if force:
            from .rundir import RunDir
            RunDir._move_aside(out)
        elif not same:
            raise ValueError(f"--out {out}: folder exists and is not empty (not this "
                             "comparison); use --force to move it aside")
    out.mkdir(parents=True, exist_ok=True)
    return out


def aggregate_lines(runs) -> list[str]:
    """One line per family over its seeds: median and range, solved, best seed."""
    lines = []
    for fam in dict.fromkeys(r["family"] for r in runs):
        rs = [r for r in runs if r["family"] == fam]
        c = np.array([r["final_cost"] for r in rs])
        best = rs[int(np.argmin(c))]
        lines.append(f"{fam:<10} {len(rs)} seeds: cost median {np.median(c):.3f} "
                     f"(min {c.min():.3f}, max {c.max():.3f}), solved "
                     f"{sum(r['success'] for r in rs)}/{len(rs)}, best seed {best['seed']}")
    return lines


def compare(task_name, controllers, seeds, budget, out, *, actuation="pd", params=None,
            population=None, workers=0, scheduler=None, family_options=None, quiet=False,
            force=False):
    """Run (or resume) the comparison into ``out``; returns (table rows, compare.md)."""
    from .study.driver import run_study
    from .study.spec import parse
    task = get_task(task_name, **(params or {}))
    spec = parse(comparison_spec(task, controllers, seeds, budget, actuation, params,
                                 population, family_options))
    out = check_out_dir(out, force, spec.digest())
    written = {}

    def write(rows):            # under the study's lock: a second compare is refused
        written["table"], written["md"] = _write_outputs(out, task, controllers, rows, seeds,
                                                         budget, actuation, quiet)
    run_study(spec, out, spec.report_seeds, workers=max(1, workers or 0), scheduler=scheduler,
              quiet=quiet, locked=write)
    return written["table"], written["md"]


def _write_outputs(out: Path, task, controllers, rows, seeds, budget, actuation, quiet):
    """best/, compare.csv, compare.md, runs.json and the curves from the ledger's rows
    (each file atomic; the caller holds the folder's lock)."""
    (out / "best").mkdir(exist_ok=True)
    order = {name: i for i, name in enumerate(controllers)}
    rows = sorted(rows, key=lambda r: (order[r["config"]], r["seed"]))
    runs = []
    for r in rows:
        runs.append(_run_record(out, r))
        rec = read_json(out / r["controller"], kind="best")
        rec = {k: v for k, v in rec.items() if k not in ("format", "version")}
        rec.update(cost=r["cost"], plugins=loaded_plugins())
        atomic_write_json(out / "best" / f"{r['config']}-seed{r['seed']}.json",
                          envelope("best", rec))
    if not quiet and seeds > 1:
        print("\n".join(aggregate_lines(runs)), file=sys.stderr, flush=True)
    table = summarize(runs)
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(table[0]), lineterminator="\n")
    w.writeheader()
    w.writerows(table)
    atomic_write_text(out / "compare.csv", buf.getvalue())
    md = (f"{task.name}, actuation {actuation}, {budget:,} evaluations per run, {seeds} seeds; "
          f"cost re-scored at full style weight (lower is better)\n\n" + table_markdown(table))
    atomic_write_text(out / "compare.md", md)
    atomic_write_json(out / "runs.json", {"task": task.id, "params": task.params,
                                          "actuation": actuation, "budget": budget, "runs": runs})
    write_curves(out, task, runs, budget, actuation)
    return table, md


def write_curves(out, task, runs, budget, actuation):
    """curves.csv and curves.png of ``runs`` (as in runs.json)."""
    series = _bands(runs, budget)
    atomic_write_text(Path(out) / "curves.csv", _curves_csv(series))
    window = phase_window(task)
    plot_curves(Path(out) / "curves.png", series, task, window, _window_evals(runs, window),
                actuation)


def replot(out) -> Path:
    """Redraw a compare folder's curves from its runs.json (no search is run)."""
    import json
    from .records import read_text
    d = json.loads(read_text(Path(out) / "runs.json", follow=False))
    task = get_task(task_id(d["task"], recorded=True), **d["params"])    # bare: before ids, v1
    write_curves(out, task, d["runs"], int(d["budget"]), d["actuation"])
    return Path(out) / "curves.png"
