"""Studies: grids of searches (configurations × seeds × starts × stages) run
through the run loop, one ledger, tables and plots from it (docs/studies.md).

* :mod:`.spec` parses and checks a spec (TOML);
* :mod:`.driver` runs it into a study directory, resumably;
* :mod:`.ledger` is that directory: study.json, results.jsonl, controllers/;
* :mod:`.judge` names how a result is judged (task success, gait, composite);
* :mod:`.table` and :mod:`.plot` read the ledger.

The shipped studies (``gpmotion study list``) live in ``gpmotion/studies/NAME``:
``spec.toml`` and, where published, their ledger and controllers.
"""
from __future__ import annotations

from pathlib import Path

SHIPPED = Path(__file__).resolve().parent.parent / "studies"


def shipped_names() -> list[str]:
    return sorted(p.parent.name for p in SHIPPED.glob("*/spec.toml"))


def spec_path(name_or_path: str) -> Path:
    """A spec file: a path, or a shipped study's name."""
    p = Path(name_or_path)
    if p.suffix == ".toml" or p.exists():
        return p
    if name_or_path in shipped_names():
        return SHIPPED / name_or_path / "spec.toml"
    from ..names import unknown
    raise ValueError(f"no spec file {name_or_path!r} and "
                     + unknown("shipped study", name_or_path, shipped_names()))


def study_dir(name_or_dir: str) -> Path:
    """A study directory: a path, or a shipped study's name (its committed ledger)."""
    p = Path(name_or_dir)
    if p.is_dir():
        return p
    if name_or_dir in shipped_names():
        return SHIPPED / name_or_dir
    from ..names import unknown
    raise ValueError(f"no study directory {name_or_dir!r} and "
                     + unknown("shipped study", name_or_dir, shipped_names()))


def load_directory(directory: str | Path):
    """(spec, rows) of a study directory: the spec it was run from (study.json)
    and its ledger."""
    from .ledger import read_rows, read_study
    from .spec import SpecError, parse
    doc = read_study(directory)
    try:
        spec = parse(doc["spec"], quick=bool(doc["quick"]))
    except SpecError as e:
        raise SpecError(f"{Path(directory) / 'study.json'}: {e}") from None
    if spec.digest() != doc["digest"]:
        raise SpecError(f"{Path(directory) / 'study.json'}: its spec does not match its digest "
                        "(edited?)")
    return spec, read_rows(directory)
