"""Refining a phase's controller inside its composite (Auslander et al. §3's
future work: "also refine the controllers of a phase"; off by default).

After the transition search has fixed the switch times, a phase's controller
is climbed from where it stands, in the state the earlier phases hand it:
each round asks ``mutants`` variations of the incumbent (the family's own
``mutate``: GP creeps a tree's constants or grows a new subtree, BSR creeps
or re-draws a rule, keyframes step a value), runs the *whole* composite with
each of them in the phase, scores it with the script, and keeps the best
mutant if its total is strictly higher (a (1 + λ) hill climb: the composite
never gets worse).  Phases are refined one after another in composite order,
so a later phase is refined in the state the refined earlier ones hand it.

The climb draws from its own generator (seeded by the run's seed and the
phase's index), so a refinement is deterministic; ``state_dict()`` is plain
JSON.  A family without ``mutate`` cannot be refined (a clear error).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..families.base import Family
from . import composite as C
from .transitions import checked_scores

STATE_FORMAT = "phase-refinement-v1"


class PhaseRefinement:
    """(1 + λ) climb of one genome, scores maximized; ask/tell."""

    def __init__(self, family, genome, *, rounds: int = 16, mutants: int = 16, seed: int = 0):
        for what, v in (("rounds", rounds), ("mutants", mutants)):
            if not (isinstance(v, (int, np.integer)) and 1 <= v <= 10_000):
                raise ValueError(f"refinement {what} must be an integer in 1..10000, got {v!r}")
        self.family, self.rounds, self.mutants = family, int(rounds), int(mutants)
        self.rng = np.random.default_rng(seed)
        self.best, self.best_score = family.copy(genome), -np.inf
        self.start_score = -np.inf                                 # the incumbent's, as given
        self.round, self.evaluations, self.accepted = -1, 0, 0     # round -1: score the incumbent
        self.pending = None

    @property
    def done(self) -> bool:
        return self.round >= self.rounds

    def ask(self) -> list:
        if self.done:
            raise RuntimeError("the refinement is finished")
        if self.pending is None:
            self.pending = ([self.family.copy(self.best)] if self.round < 0 else
                            [self.family.mutate(self.family.copy(self.best), self.rng)
                             for _ in range(self.mutants)])
        return list(self.pending)

    def tell(self, scores) -> None:
        scores = checked_scores(self.pending, scores)
        j = int(np.argmax(scores))
        if self.round < 0:
            self.start_score = self.best_score = float(scores[0])
        elif scores[j] > self.best_score:
            self.best, self.best_score = self.pending[j], float(scores[j])
            self.accepted += 1
        self.evaluations += len(scores)
        self.round += 1
        self.pending = None

    def state_dict(self) -> dict:
        return {"format": STATE_FORMAT, "round": self.round, "evaluations": self.evaluations,
                "accepted": self.accepted, "best": self.family.to_json(self.best),
                "best_score": self.best_score if np.isfinite(self.best_score) else None,
                "start_score": self.start_score if np.isfinite(self.start_score) else None,
                "rng": self.rng.bit_generator.state}

    def load_state_dict(self, state: dict) -> None:
        if state.get("format") != STATE_FORMAT:
            raise ValueError(f"not a phase refinement state (format {state.get('format')!r})")
        self.round, self.evaluations = int(state["round"]), int(state["evaluations"])
        self.accepted, self.best = int(state["accepted"]), self.family.from_json(state["best"])
        self.best_score = -np.inf if state["best_score"] is None else float(state["best_score"])
        self.start_score = -np.inf if state["start_score"] is None else float(state["start_score"])
        self.rng.bit_generator.state = state["rng"]
        self.pending = None


def refine(comp: C.Composite, script, phases, *, rounds: int = 16, mutants: int = 16, seed: int = 0,
           threads: int | None = None, log=None) -> tuple[C.Composite, dict]:
    """Refine the named phases of ``comp`` in composite order (switch times fixed).

    Returns the composite with the refined controllers and, per phase, what the
    climb did: {name: {"before", "after", "accepted", "evaluations"}} (totals of
    the script)."""
    from . import script as S
    names = [p.name for p in comp.parts]
    unknown = [p for p in phases if p not in names]
    if unknown:
        raise C.CompositeError(f"--refine names {unknown}, not phases of the script ({', '.join(names)})")
    report = {}
    for k, part in enumerate(comp.parts):
        if part.name not in phases:
            continue
        if type(part.family).mutate is Family.mutate:
            raise C.CompositeError(f"phase {part.name!r}: the {part.family.name} family has no mutate; "
                                   "it cannot be refined")
        climb = PhaseRefinement(part.family, part.genome, rounds=rounds, mutants=mutants,
                                seed=int(np.random.SeedSequence([seed, k]).generate_state(1)[0]))
        while not climb.done:
            traj, bounds = C.run(comp, threads=threads, variants=(k, climb.ask()))
            climb.tell(S.evaluate(script, traj, bounds, comp.scenes)["total"])
            if log is not None and climb.round > 0:
                log(f"refine {part.name}: round {climb.round}/{rounds}, total {climb.best_score:.6g} "
                    f"({climb.accepted} accepted)")
        comp = _with_genome(comp, k, climb.best)
        report[part.name] = {"before": _num(climb.start_score), "after": _num(climb.best_score),
                             "accepted": climb.accepted, "evaluations": climb.evaluations}
    return comp, report


def _num(x: float):
    return float(x) if np.isfinite(x) else None


def controller_record(part: C.Part, genome, refined: dict) -> dict:
    """A controller file (``gpmotion-best``) for a refined phase: the phase's own
    record with the refined genome and what refined it; the single-run results
    of the original (cost, success, facts) are left out, as they are not this
    controller's."""
    from pathlib import Path

    from ..records import read_json
    src = Path(part.source)
    rec = read_json(src / "best.json" if src.is_dir() else src, kind="best")
    keep = ("task", "params", "family", "options", "actuation", "plugins", "seed")
    return {**{k: rec[k] for k in keep if k in rec}, "genome": part.family.to_json(genome),
            "refined": {"from": str(src), **refined}}


def _with_genome(comp: C.Composite, k: int, genome) -> C.Composite:
    parts = list(comp.parts)
    parts[k] = replace(parts[k], genome=genome)
    return replace(comp, parts=parts, switches=comp.switches.copy())


def save_refined(folder, comp: C.Composite, report: dict) -> C.Composite:
    """Write each refined phase's controller as FOLDER/refined_NAME.json; the
    composite naming those files (a composite file names its controllers by
    path, so a refined genome must have a file of its own)."""
    from pathlib import Path

    from ..records import atomic_write_json, envelope
    parts = list(comp.parts)
    for k, part in enumerate(parts):
        if part.name in report:
            path = Path(folder) / f"refined_{part.name}.json"
            atomic_write_json(path, envelope("best", controller_record(part, part.genome, report[part.name])))
            parts[k] = replace(part, source=str(path.resolve()))
    return replace(comp, parts=parts, switches=comp.switches.copy())
