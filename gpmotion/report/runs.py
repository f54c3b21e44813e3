"""One run directory as a report panel: the best controller's motion, the
film of every generation's best (``generations.jsonl``, replayed here),
the learning curves (log.csv), the score's terms and the controller's
structure.  A run without ``generations.jsonl`` (written before it existed)
reports without the film, and says so.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from ..records import FormatError
from ..render import phase_windows
from ..rundir import RunDir
from .encode import encode_motion
from .structure import controller_view

FILM_FPS = 25.0                  # the film's frame rate (the best motion keeps every frame)
FILM_BYTES = 800_000             # the film's share of a page: entries are thinned to fit
                                 # (a lamp page stays under 2 MB, a Herman page under 5 MB)


def _num(x):
    try:
        x = float(x)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


def curves(rows: list[dict], task) -> dict | None:
    """log.csv's curves by generation, and each phase-in window in generations."""
    if not rows or "generation" not in rows[0]:
        return None
    gen = [_num(r.get("generation")) for r in rows]
    out = {"x": gen, "xlabel": "generation",
           "series": [{"label": "best so far, current weights",
                       "y": [_num(r.get("best_so_far")) for r in rows], "color": "#1f77b4"},
                      {"label": "best final, final weights",
                       "y": [_num(r.get("best_final")) for r in rows], "color": "#2ca02c"},
                      {"label": "generation median, current weights",
                       "y": [_num(r.get("gen_median")) for r in rows], "color": "#8fb6d8",
                       "dash": True}],
           "windows": []}
    progress = np.array([_num(r.get("progress")) for r in rows], dtype=float)
    x = np.array([g if g is not None else np.nan for g in gen], dtype=float)
    ok = np.isfinite(progress) & np.isfinite(x)
    if task is not None and ok.sum() >= 1:
        for a, b, names in phase_windows(task):
            out["windows"].append({"from": float(np.interp(a, progress[ok], x[ok])),
                                   "to": float(np.interp(b, progress[ok], x[ok])), "label": names})
    out["series"] = [s for s in out["series"] if any(v is not None for v in s["y"])]
    return out


def thin(records: list[dict], keep: int) -> list[dict]:
    """At most ``keep`` records, evenly spread, the first and the last kept."""
    if len(records) <= keep:
        return records
    idx = np.unique(np.round(np.linspace(0, len(records) - 1, keep)).astype(int))
    return [records[i] for i in idx]


def film(records, task, family, actuation, budget: int = FILM_BYTES) -> dict:
    """Every record's controller replayed (one batched rollout) at FILM_FPS."""
    from ..inprocess import InProcessEvaluator
    if not records:
        return {"entries": [], "of": 0}
    genomes = []
    for r in records:
        try:
            genomes.append(family.from_json(r["genome"]))
        except (KeyError, TypeError, ValueError) as e:
            raise FormatError(f"generations.jsonl: generation {r.get('generation')}: "
                              f"not a {family.name} controller ({e})") from None
    ev = InProcessEvaluator(task, family, actuation)
    traj = ev.rollout(genomes)
    costs, _, ok = task.score(traj, 1.0)
    one = encode_motion(traj, 0, task=task, fps=FILM_FPS, details=False)
    per = max(1, len(json.dumps(one)))
    keep = max(2, budget // per)
    chosen = thin(list(range(len(records))), keep)
    entries = []
    for i in chosen:
        r = records[i]
        entries.append({"generation": r["generation"], "evaluations": r.get("evaluations"),
                        "cost": _num(r.get("cost")), "cost_final": _num(costs[i]),
                        "solved": bool(ok[i]),
                        "motion": encode_motion(traj, i, task=task, fps=FILM_FPS, details=False)})
    return {"entries": entries, "of": len(records)}


def run_panel(path, *, title: str | None = None, best=None, with_film: bool = True,
              film_bytes: int = FILM_BYTES) -> dict:
    """The panel of one run directory.  ``best``: (task, family, actuation,
    genome, traj) already replayed (the end of a run), else replayed here."""
    from ..replay import load_controller, replay_genome
    path = Path(path)
    if not (path / RunDir.BEST).is_file():
        raise FormatError(f"{path}: no best.json (an unfinished run? `gpmotion resume {path}`)")
    task, family, actuation, genome, rec = load_controller(path)
    traj = best[4] if best is not None else replay_genome(task, family, actuation, genome)[0]
    costs, measures, ok = task.score(traj, 1.0)
    rd = RunDir(path)
    panel = {"name": title or path.name, "task": task.name, "family": family.name,
             "actuation": actuation, "cost": _num(costs[0]), "solved": bool(ok[0]),
             "diverged": bool(traj.diverged[0]),
             "motion": encode_motion(traj, 0, task=task),
             "curves": curves(rd.read_log(), task),
             "terms": task.breakdown(measures, 0, 1.0), "facts": task.describe(traj, measures),
             "controller": controller_view(family, genome)}
    if with_film:
        records = rd.read_generations()
        if records:
            panel["film"] = film(records, task, family, actuation, film_bytes)
        else:
            panel["film_note"] = ("no generations.jsonl in this run (written by an older "
                                  "gpmotion): no film of the generations")
    return panel
