"""Bind a study directory to an amended spec without running anything.

A study directory is bound to the spec it was run from (study.json's digest),
so a changed spec is refused by ``study run``.  Some changes leave every row
true: a new configuration, a new label, a spec comment, a judge or an
``expect`` that re-judges the kept measures.  :func:`amend` checks that the
amendment is one of those, and only then rewrites study.json (and, when a
judge changed, each affected row's verdict, from its kept measures):

* every configuration with rows is in the new spec with the same searches
  (stages, tasks, parameters, options, search settings, budget, actuation,
  starts) — only its label, judge and ``expect`` may differ;
* every row's seed is still in the same seed set (tune or report);
* both specs are full or both ``--quick``.

Anything else would mix rows of two experiments in one table: it is refused
with one line, and nothing on disk changes.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

from ..records import atomic_write_text
from ..rundir import LOCK, RunDir
from .judge import rejudge
from .ledger import RESULTS, STUDY, read_rows, read_study, row_line, study_text
from .spec import Spec, SpecError, parse


@dataclass
class Amendment:
    added: list = field(default_factory=list)        # configurations new to the directory
    rejudged: dict = field(default_factory=dict)     # configuration -> (old judge, new judge)
    changed: int = 0                                 # rows whose verdict changed
    same: bool = False                               # the digest was already the new spec's


def _searches(conf) -> tuple:
    return (conf.staged, conf.starts, conf.stages)


def check(old: Spec, new: Spec, rows: list[dict]) -> Amendment:
    """What binding ``rows`` (run under ``old``) to ``new`` changes; raises
    SpecError naming the first thing that would make a row untrue."""
    if old.quick != new.quick:
        raise SpecError("one spec is --quick and the other is not")
    out = Amendment()
    with_rows = sorted({r["config"] for r in rows})
    for name in with_rows:
        if name not in new.configurations:
            raise SpecError(f"configuration {name!r} has rows but is not in the new spec")
        a, b = old.configurations[name], new.configurations[name]
        if _searches(a) != _searches(b):
            raise SpecError(f"configurations.{name}: its searches differ from the ones its rows "
                            "ran (stages, task, options, search, budget, actuation or starts); "
                            "a changed search needs a new --out")
        if (a.judge, a.expect) != (b.judge, b.expect):
            out.rejudged[name] = (a.judge, b.judge)
    for r in rows:
        if r["seed"] not in new.seeds or new.seed_set(r["seed"]) != r.get("seeds"):
            raise SpecError(f"row {r['config']} seed {r['seed']}: not a {r.get('seeds')} seed "
                            "of the new spec")
    out.added = [n for n in new.configurations if n not in old.configurations]
    return out


def _rejudged(rows: list[dict], new: Spec, amendment: Amendment) -> list[dict]:
    out = []
    for r in rows:
        if r["config"] in amendment.rejudged:
            conf = new.configurations[r["config"]]
            try:
                ok, label = rejudge(r, conf.judge, conf.expect)
            except ValueError as e:
                raise SpecError(str(e)) from None
            amendment.changed += (ok, label) != (r["success"], r["label"])
            r = {**r, "judge": conf.judge, "success": ok, "label": label}
        out.append(r)
    return out


def amend(directory: str | Path, new: Spec) -> Amendment:
    """Bind ``directory`` to ``new`` (module doc).  Checked before anything is
    written; written under the directory's lock (a running study refuses)."""
    directory = Path(directory)
    amendment, _ = _checked(directory, new)
    if amendment.same:
        return amendment
    had_lock = (directory / LOCK).exists()
    rd = RunDir.create(directory, resume=True)          # one writer: refuses a running study
    try:
        amendment, rows = _checked(directory, new)        # what is there now, under the lock
        if amendment.rejudged:                            # rows first: a rerun redoes both
            atomic_write_text(rd.file(RESULTS), "".join(map(row_line, rows)))
        atomic_write_text(rd.file(STUDY), study_text(new.digest(), new.source, new.quick))
        if not had_lock:                                  # it only names the holder
            os.unlink(rd.file(LOCK))
    finally:
        rd.close()
    return amendment


def _checked(directory: Path, new: Spec) -> tuple[Amendment, list[dict]]:
    """The amendment and the rows it leaves (re-judged), or SpecError."""
    have = read_study(directory)
    old = parse(have["spec"], quick=have["quick"])
    rows = read_rows(directory)
    amendment = check(old, new, rows)
    amendment.same = have["digest"] == new.digest()
    return amendment, _rejudged(rows, new, amendment)
