"""A transition search as a run directory: config, log, checkpoint, result (resumable).

    OUT/config.json       gpmotion-compose-config: the script text, the composite, Q/G/H/seed
    OUT/log.csv           one row per round (TransitionSearch.row())
    OUT/checkpoint.json   gpmotion-compose-checkpoint: the search state after the last round
    OUT/careless.json     the composite as given (gpmotion-composite)
    OUT/composite.json    the composite with the best switch times found (gpmotion-composite)
    OUT/refined_P.json    with ``refine``: phase P's refined controller (gpmotion-best), which
                          composite.json names
    OUT/result.json       gpmotion-compose-result: careless and best scores, per-phase credits

The directory is a :class:`gpmotion.rundir.RunDir` (one writer, no links
followed, regular files only, atomic records, one line ending).
``resume=True`` continues from the checkpoint to exactly the result of an
uninterrupted search (the config must be the same: config.json names the
controllers by absolute path; the composites in OUT name them relative to OUT).
A search killed while refining phases resumes the refinement from its start:
it is deterministic, so the result is the same.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..records import FormatError, envelope
from ..rundir import RunDir
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

    ``out`` is a :class:`~gpmotion.rundir.RunDir`: locked for one writer, its
    records never read through a link or from a FIFO, written atomically.  A
    resume checks config, checkpoint and log before it changes anything; with
    no checkpoint yet (killed before the first round ended) it starts the
    search again.  ``refine``: {"phases": [names], "rounds": R, "mutants": M}
    refines those phases' controllers after the search (gpmotion.compose.refine)."""
    out = Path(out)
    script = S.parse(script_text)
    optimize.check_match(comp, script)
    if refine:
        refine = {"phases": list(refine["phases"]), "rounds": int(refine.get("rounds", 16)),
                  "mutants": int(refine.get("mutants", 16))}
    config = envelope("compose-config", _config(comp, script_text, Q, G, H, seed, perturb, refine))
    if not resume and out.is_dir() and RunDir(out).names():
        raise FormatError(f"{out}: exists and is not empty (resume it, or pick another --out)")
    with RunDir.create(out, resume=resume) as rd:
        state, keep = _resume_point(rd, config) if resume else (None, 0)
        if not resume:
            rd.write_json(CONFIG, "compose-config", config)
        if not resume or state is None:
            C.save(out / "careless.json", comp)
        return _search(rd, out, script, comp, config, state, keep, log, stop_after_rounds, refine)


CONFIG, CHECKPOINT, RESULT = "config.json", "checkpoint.json", "result.json"


def _resume_point(rd: RunDir, config: dict) -> tuple[dict | None, int]:
    """(search state, log rows it was taken after), every record checked, nothing changed."""
    old = rd.read_json(CONFIG, "compose-config")
    if old != config:
        raise FormatError(f"{rd.path}: config.json differs from this search's settings; not resuming")
    rows = rd.read_log()
    if not rd.exists(CHECKPOINT):
        return None, 0                          # killed before its first round: start again
    ck = rd.read_json(CHECKPOINT, "compose-checkpoint")
    unknown = sorted(set(ck) - {"format", "version", "search"})
    if unknown:
        raise FormatError(f"{rd.path / CHECKPOINT}: unknown key(s) {unknown}; refusing it")
    state = ck.get("search")
    last = state.get("round") if isinstance(state, dict) else None
    if type(last) is not int or not 0 <= last <= 10**6:
        raise FormatError(f"{rd.path / CHECKPOINT}: no valid 'search.round'")
    rounds = [r.get("round", "") for r in rows]
    keep = next((i for i, r in enumerate(rounds) if not r.isdigit() or int(r) > last), len(rows))
    if (keep and rounds[keep - 1] != str(last)) or (last and not keep):
        raise FormatError(f"{rd.log_path}: its rows do not end at the checkpoint's round {last}; "
                          "refusing to mix records")
    return state, keep


def _search(rd, out, script, comp, config, state, keep, log, stop_after_rounds, refine):
    rounds = [0]
    trimmed = [False]

    def on_round(ts):
        if not trimmed[0]:                      # the state loaded: now drop rows after it
            rd.trim_log(keep)
            if keep == 0:
                rd.write_text(rd.LOG, ",".join(LOG_FIELDS) + "\n")
            trimmed[0] = True
        row = ts.row()
        rd.log_rows([{k: row[k] if k != "best" else " ".join(f"{x:g}" for x in row[k])
                      for k in LOG_FIELDS}])
        rd.write_json(CHECKPOINT, "compose-checkpoint", {"search": ts.state_dict()})
        log(f"round {ts.round}/{ts.G}: best {row['best_score']} at {row['best']} ({ts.evaluations} simulations)")
        rounds[0] += 1
        if stop_after_rounds is not None and rounds[0] >= stop_after_rounds and not ts.done:
            raise _Stop

    Q, G, H, seed, perturb = (config[k] for k in ("Q", "G", "H", "seed", "perturb"))
    if state is None:
        rd.write_text(rd.LOG, ",".join(LOG_FIELDS) + "\n")
        trimmed[0] = True
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
    rd.write_json(RESULT, "compose-result", result)
    return result


def _refine(out: Path, comp: C.Composite, script, refine: dict, seed: int, log):
    """Refine the phases; write each refined controller as OUT/refined_NAME.json
    and name it in the composite."""
    from . import refine as R
    comp, report = R.refine(comp, script, refine["phases"], rounds=refine["rounds"],
                            mutants=refine["mutants"], seed=seed, log=log)
    return R.save_refined(out, comp, report), report


def _scores(comp: C.Composite, script: S.Script) -> dict:
    totals, credits, traj, _ = optimize.score(comp, script, [comp.switches])
    return {"switches": [float(s) for s in comp.switches], "total": _num(totals[0]),
            "credits": {k: _num(v[0]) for k, v in credits.items() if k != "total"},
            "diverged": bool(traj.diverged[0])}


def _num(x):
    return float(x) if np.isfinite(x) else None


class _Stop(Exception):
    """Raised from the round callback to stop a search early (tests, time limits)."""
