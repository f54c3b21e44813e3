"""What a report folder holds, as the page's data: a run directory, a
``gpmotion compare`` folder, a folder of run directories (a study: its
``results.jsonl`` as the table when present), or a composite (a
``gpmotion compose`` folder or a composite file)."""
from __future__ import annotations

import json
from pathlib import Path

from ..records import FormatError
from .runs import FILM_BYTES, _num, run_panel

MAX_PANELS = 12


def build(src: Path, best=None) -> tuple[dict, str]:
    from ..compose import playback
    if src.is_file() and playback.is_composite(src):
        return composite(src)
    if not src.is_dir():
        raise FormatError(f"{src}: not a run, comparison, study folder or composite file")
    if (src / "best.json").is_file() and (src / "config.json").is_file():
        p = run_panel(src, best=best)
        return ({"kind": "run", "subtitle": _subtitle(p), "panels": [p]},
                f"{p['task']} ({p['family']}) — {src.name}")
    if (src / "runs.json").is_file():
        return comparison(src)
    if (src / "composite.json").is_file():
        return composite(src / "composite.json")
    if (src / "study.json").is_file() and (src / "results.jsonl").is_file():
        return ledger_study(src)
    runs = sorted(p.parent for p in src.glob("**/best.json") if (p.parent / "config.json").is_file())
    if runs:
        return study(src, runs)
    raise FormatError(f"{src}: holds no run (best.json + config.json), comparison (runs.json), "
                      "study (run folders) or composite (composite.json)")


def _subtitle(p: dict) -> str:
    film = p.get("film")
    return (f"{p['task']} · controller {p['family']} · actuation {p['actuation']} · "
            + (f"film of {film['of']} generations whose best changed" if film else
               p.get("film_note", "")))


def comparison(src: Path) -> tuple[dict, str]:
    """Every family's best run (lowest final cost) side by side; the table and the
    families' median curves of the best under the final weights."""
    from ..compare_summary import _bands, summarize
    from ..task import get_task
    d = json.loads((src / "runs.json").read_text(encoding="utf-8"))
    runs = d["runs"]
    task = get_task(d["task"], **dict(d.get("params") or {}))
    panels = []
    families = list(dict.fromkeys(r["family"] for r in runs))
    for fam in families:
        mine = [r for r in runs if r["family"] == fam]
        r = min(mine, key=lambda r: r["final_cost"])
        run_dir = src / "runs" / f"{fam}-seed{r['seed']}"
        if (run_dir / "best.json").is_file() and (run_dir / "config.json").is_file():
            p = run_panel(run_dir, film_bytes=FILM_BYTES // len(families))
        else:                       # an older comparison kept only the controllers
            p = _controller_panel(src / "best" / f"{fam}-seed{r['seed']}.json", task)
            p["film_note"] = "this comparison kept no run folders: no film of the generations"
        p["name"] = f"{fam}: its best of {len(mine)} seeds (seed {r['seed']})"
        panels.append(p)
    series = []
    colors = ["#1f77b4", "#2ca02c", "#d62728", "#9467bd", "#ff7f0e", "#8c564b"]
    grid = None
    for k, (fam, (g, q25, med, q75)) in enumerate(_bands(runs, int(d["budget"])).items()):
        grid = g
        c = colors[k % len(colors)]
        series += [{"label": f"{fam} median", "y": [_num(v) for v in med], "color": c},
                   {"label": f"{fam} q25", "y": [_num(v) for v in q25], "color": c, "dash": True},
                   {"label": f"{fam} q75", "y": [_num(v) for v in q75], "color": c, "dash": True}]
    rows = summarize(runs)
    table = {"caption": "the table (cost re-scored at full style weight; lower is better)",
             "head": ["controller", "runs", "cost median [q25, q75]", "success",
                      "runs with a solver", "wall s (median)"],
             "rows": [[r["controller"], r["runs"],
                       f"{r['cost_median']:.3f} [{r['cost_q25']:.3f}, {r['cost_q75']:.3f}]",
                       f"{100 * r['success_rate']:.0f}%", r["runs_with_solver"],
                       f"{r['wall_s_median']:.1f}"] for r in rows]}
    data = {"kind": "comparison", "panels": panels, "table": table,
            "subtitle": f"{task.name}, actuation {d['actuation']}, {int(d['budget']):,} evaluations per run",
            "curves": {"title": "best final: the best under the final weights (median and quartiles of the seeds)",
                       "x": [float(v) for v in grid], "xlabel": "evaluations", "series": series,
                       "windows": []}}
    return data, f"comparison: {task.name}"


def _controller_panel(path: Path, task=None) -> dict:
    from ..replay import load_controller, replay_genome
    from .encode import encode_motion
    from .structure import controller_view
    task, family, actuation, genome, _ = load_controller(path)
    traj, costs, measures, ok = replay_genome(task, family, actuation, genome)
    return {"name": path.stem, "task": task.name, "family": family.name, "actuation": actuation,
            "cost": _num(costs[0]), "solved": bool(ok[0]), "motion": encode_motion(traj, 0, task=task),
            "terms": task.breakdown(measures, 0, 1.0), "facts": task.describe(traj, measures),
            "controller": controller_view(family, genome)}


def study(src: Path, runs: list[Path]) -> tuple[dict, str]:
    """One panel per run folder (at most MAX_PANELS: the cheapest), the table
    from results.jsonl when the folder has one."""
    notes = []
    costs = []
    for r in runs:
        try:
            costs.append(float(json.loads((r / "best.json").read_text())["best"]["final_cost"]))
        except (KeyError, TypeError, ValueError, OSError):
            costs.append(float("inf"))
    shown = runs
    if len(runs) > MAX_PANELS:
        order = sorted(range(len(runs)), key=lambda i: costs[i])[:MAX_PANELS]
        shown = [runs[i] for i in sorted(order)]
        notes.append(f"{MAX_PANELS} of the {len(runs)} runs shown: the lowest final costs")
    panels = []
    for r in shown:
        p = run_panel(r, title=str(r.relative_to(src)), film_bytes=FILM_BYTES // len(shown))
        panels.append(p)
    data = {"kind": "study", "panels": panels, "notes": notes,
            "subtitle": f"{len(runs)} runs in {src}"}
    table = _results_table(src / "results.jsonl")
    data["table"] = table or {"caption": "the runs", "head": ["run", "task", "controller", "cost", "solved"],
                              "rows": [[p["name"], p["task"], p["family"], f"{p['cost']:.4f}",
                                        "yes" if p["solved"] else "no"] for p in panels]}
    return data, f"study: {src.name}"


def ledger_study(src: Path) -> tuple[dict, str]:
    """A study directory (study.json and its ledger): the table ``gpmotion study
    table`` prints (report seeds; tune seeds when it has no report rows) and one
    panel per configuration, its cheapest run of those seeds: the run folder,
    with its film, when the study kept it, else the ledger's controller."""
    from ..study import load_directory
    from ..study.table import _evals, _success, chosen, summarize
    spec, rows = load_directory(src)
    seed_set = "report" if any(r["seed"] in spec.report_seeds for r in rows) else "tune"
    seeds = spec.report_seeds if seed_set == "report" else spec.tune_seeds
    picked = chosen(rows, seeds)
    summary = summarize(spec, rows, seed_set)
    configs = [c for c in spec.configurations.values()
               if any(k[0] == c.name for k in picked)][:MAX_PANELS]
    notes, panels = [], []
    if len(configs) < len(spec.configurations):
        notes.append(f"{len(configs)} of the {len(spec.configurations)} configurations shown "
                     f"(those with {seed_set}-seed runs, at most {MAX_PANELS})")
    for conf in configs:
        mine = [r for k, r in picked.items() if k[0] == conf.name]
        best = min(mine, key=lambda r: r["cost"])
        panels.append(_ledger_panel(src, conf, best, len(configs)))
        panels[-1]["name"] = (f"{conf.label}: its best of {len(mine)} {seed_set} seeds "
                              f"(seed {best['seed']})")
    head = ["configuration", "runs", "evaluations per run", "success", "cost median [q25, q75]"]
    table = {"caption": f"the study's table ({seed_set} seeds; cost lower is better)", "head": head,
             "rows": [[r["label"], r["runs"], _evals(r["evaluations"]), _success(r),
                       f"{r['cost_median']:.3f} [{r['cost_q25']:.3f}, {r['cost_q75']:.3f}]"]
                      for r in summary["rows"] if r["runs"]]}
    return ({"kind": "study", "panels": panels, "notes": notes, "table": table,
             "subtitle": spec.title or spec.name}, f"study: {spec.name}")


def _ledger_panel(src: Path, conf, row: dict, n_panels: int) -> dict:
    stem = f"{conf.name}-seed{row['seed']}" + (f"-start{row['start']}" if conf.starts > 1 else "")
    run_dir = src / "runs" / stem
    if (run_dir / "best.json").is_file() and (run_dir / "config.json").is_file():
        return run_panel(run_dir, film_bytes=FILM_BYTES // n_panels)
    ctl = (src / str(row.get("controller", ""))).resolve()
    if src.resolve() not in ctl.parents or not ctl.is_file():
        raise FormatError(f"{src / 'results.jsonl'}: {conf.name} seed {row['seed']}: its "
                          f"controller {row.get('controller')!r} is not a file of the study")
    p = _controller_panel(ctl)
    p["film_note"] = "the study kept no run folder for this run: no film of the generations"
    return p


def _results_table(path: Path) -> dict | None:
    if not path.is_file():
        return None
    rows = []
    for line in path.read_text(encoding="utf-8").splitlines():
        try:
            obj = json.loads(line)
        except ValueError:
            continue
        if isinstance(obj, dict):
            rows.append({k: v for k, v in obj.items() if isinstance(v, (str, int, float, bool)) or v is None})
    if not rows:
        return None
    head = list(dict.fromkeys(k for r in rows for k in r))
    return {"caption": f"{path.name}", "head": head,
            "rows": [["" if r.get(k) is None else (f"{r[k]:.4g}" if isinstance(r[k], float) else str(r[k]))
                      for k in head] for r in rows]}


def composite(path: Path) -> tuple[dict, str]:
    """The composite's motion with its phases on the timeline (each phase's poles
    drawn while it runs) and a table of what the figure did in each phase."""
    from ..compose import playback
    from .encode import encode_motion
    comp, traj, bounds = playback.simulate(path)
    motion = encode_motion(traj, 0)
    motion["poles"] = []
    t = traj.times
    motion["phases"] = [{"name": part.name, "from": float(t[int(bounds[k])]),
                         "to": float(t[int(bounds[k + 1])]),
                         "poles": [list(map(float, p)) for p in comp.scenes[k].poles]}
                        for k, part in enumerate(comp.parts)]
    rows = playback.phase_rows(comp, traj, bounds)
    head = list(rows[0]) if rows else []
    table = {"caption": "phases", "head": head,
             "rows": [[f"{v:.3f}" if isinstance(v, float) else str(v) for v in r.values()] for r in rows]}
    name = path.parent.name if path.name == "composite.json" else path.name
    panel = {"name": name, "task": " → ".join(p.name for p in comp.parts),
             "motion": motion, "table": table}
    return ({"kind": "composite", "panels": [panel],
             "subtitle": f"a composite of {len(comp.parts)} phases"}, f"composite: {name}")
