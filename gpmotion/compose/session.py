"""A transition search as a run directory: config, log, checkpoint, result (resumable).

    OUT/config.json       gpmotion-compose-config: the script text, the composite, Q/G/H/seed
    OUT/log.csv           one row per round (TransitionSearch.row())
    OUT/checkpoint.json   gpmotion-compose-checkpoint: the search state after the last round
    OUT/careless.json     the composite as given (gpmotion-composite)
    OUT/composite.json    the composite with the best switch times found (gpmotion-composite)
    OUT/refined_P.json    with ``refine``: phase P's refined controller (gpmotion-best), which
                          composite.json names
    OUT/result.json       gpmotion-compose-result: careless and best scores, per-phase credits

``resume=True`` continues from the checkpoint to exactly the result of an
uninterrupted search (the config must be the same: config.json names the
controllers by absolute path; the composites in OUT name them relative to OUT).
A search killed while refining phases resumes the refinement from its start:
it is deterministic, so the result is the same.
"""
from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from ..records import FormatError, atomic_write_json, atomic_write_text, envelope, read_json
from . import composite as C
from . import optimize
from . import script as S

LOG_FIELDS = ("round", "step", "evaluations", "best_score", "median_score", "best")


def _config(comp: C.Composite, script_text: str, Q: int, G: int, H: int, seed: int, perturb,
            refine: dict | None) -> dict:
    return {"script": script_text, "composite": C.to_obj(comp), "Q": Q, "G": G, "H": H, "seed": seed,
            "perturb": perturb, **({"refine": refine} if refine else {})}   # absent: as before


def compose_run(out, script_text: str, comp: C.Composite, *, Q: int = 16, G: int = 16, H: int = 4,
                seed: int = 0, perturb: float | None = None, resume: bool = False,
                log=print, stop_after_rounds: int | None = None, refine: dict | None = None
                ) -> dict | None:
    """Run (or resume) the search into ``out``; return the result dict (None if stopped early).

    ``refine``: {"phases": [names], "rounds": R, "mutants": M} refines those
    phases' controllers after the search (gpmotion.compose.refine)."""
    out = Path(out)
    script = S.parse(script_text)
    optimize.check_match(comp, script)
    if refine:
        refine = {"phases": list(refine["phases"]), "rounds": int(refine.get("rounds", 16)),
                  "mutants": int(refine.get("mutants", 16))}
    config = envelope("compose-config", _config(comp, script_text, Q, G, H, seed, perturb, refine))
    state = None
    if resume:
        old = read_json(out / "config.json", kind="compose-config")
        if old != config:
            raise FormatError(f"{out}: config.json differs from this search's settings; not resuming")
        state = read_json(out / "checkpoint.json", kind="compose-checkpoint")["search"]
        _trim_log(out / "log.csv", int(state["round"]))
    else:
        if out.exists() and any(out.iterdir()):
            raise FormatError(f"{out}: exists and is not empty (resume it, or pick another --out)")
        out.mkdir(parents=True, exist_ok=True)
        atomic_write_json(out / "config.json", config)
        atomic_write_text(out / "log.csv", ",".join(LOG_FIELDS) + "\n")
        C.save(out / "careless.json", comp)
    rounds = [0]

    def on_round(ts):
        row = ts.row()
        buf = io.StringIO()
        csv.writer(buf).writerow([row[k] if k != "best" else " ".join(f"{x:g}" for x in row[k])
                                  for k in LOG_FIELDS])
        with open(out / "log.csv", "a", encoding="utf-8") as f:
            f.write(buf.getvalue())
        atomic_write_json(out / "checkpoint.json", envelope("compose-checkpoint", {"search": ts.state_dict()}))
        log(f"round {ts.round}/{ts.G}: best {row['best_score']} at {row['best']} ({ts.evaluations} simulations)")
        rounds[0] += 1
        if stop_after_rounds is not None and rounds[0] >= stop_after_rounds and not ts.done:
            raise _Stop

    try:
        ts = optimize.search(comp, script, Q=Q, G=G, H=H, seed=seed, perturb=perturb, state=state,
                             on_round=on_round)
    except _Stop:
        return None
    best = optimize.repaired(comp, ts)
    result = {"careless": _scores(comp, script)}
    if refine:
        result["searched"] = _scores(best, script)
        best, result["refined"] = _refine(out, best, script, refine, seed, log)
    C.save(out / "composite.json", best)
    result.update(best=_scores(best, script), simulations=ts.evaluations
                  + sum(r["evaluations"] for r in result.get("refined", {}).values()))
    atomic_write_json(out / "result.json", envelope("compose-result", result))
    return result


def _refine(out: Path, comp: C.Composite, script, refine: dict, seed: int, log):
    """Refine the phases; write each refined controller as OUT/refined_NAME.json
    and name it in the composite."""
    from . import refine as R
    comp, report = R.refine(comp, script, refine["phases"], rounds=refine["rounds"],
                            mutants=refine["mutants"], seed=seed, log=log)
    return R.save_refined(out, comp, report), report


def _trim_log(path: Path, last_round: int) -> None:
    """Drop log rows written after the checkpoint (a crash between the two writes)."""
    lines = path.read_text(encoding="utf-8").splitlines(keepends=True)
    keep = lines[:1] + [ln for ln in lines[1:] if ln.split(",", 1)[0].isdigit() and int(ln.split(",", 1)[0]) <= last_round]
    if keep != lines:
        atomic_write_text(path, "".join(keep))


def _scores(comp: C.Composite, script: S.Script) -> dict:
    totals, credits, traj, _ = optimize.score(comp, script, [comp.switches])
    return {"switches": [float(s) for s in comp.switches], "total": _num(totals[0]),
            "credits": {k: _num(v[0]) for k, v in credits.items() if k != "total"},
            "diverged": bool(traj.diverged[0])}


def _num(x):
    return float(x) if np.isfinite(x) else None


class _Stop(Exception):
    """Raised from the round callback to stop a search early (tests, time limits)."""
