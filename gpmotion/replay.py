"""Replay a controller: from a run directory or a controller JSON file."""
from __future__ import annotations

from pathlib import Path

from .inprocess import InProcessEvaluator
from .families import make_family, recorded_options
from .records import FormatError, read_json
from .task import get_task, task_id


def replay_genome(task, family, actuation, genome):
    """One episode of ``genome``: (trajectory, costs, measures, success)."""
    ev = InProcessEvaluator(task, family, actuation)
    traj = ev.rollout([genome], record_senses=True)
    costs, measures, ok = task.score(traj, 1.0)
    return traj, costs, measures, ok


def _after_from(params: dict, folder: Path) -> dict:
    """A record's ``after`` (earlier stages' controller files) resolved against the
    record's own folder, not the current one; a record that named its stages from
    the folder it was run in (and has none beside it) keeps that meaning."""
    after = params.get("after")
    if not isinstance(after, str) or not after.strip():
        return params
    out = []
    for p in (s.strip() for s in after.split(",") if s.strip()):
        beside = folder / p
        out.append(p if Path(p).is_absolute() or not (beside.exists() or not Path(p).exists())
                   else str(beside))
    return {**params, "after": ",".join(out)}


def _check_record_tables(rec: dict, path: Path) -> None:
    """A record's params and options are tables and its actuation one of the
    known modes (null or absent: the family's default), never a falsy stand-in
    such as 0 or {} read as "absent"."""
    from .sim.rollout import ACTUATION
    for key in ("params", "options"):
        if rec.get(key) is not None and not isinstance(rec[key], dict):
            raise FormatError(f"{path}: '{key}' must be a table, got {type(rec[key]).__name__}")
    act = rec.get("actuation")
    if act is not None and (not isinstance(act, str) or act not in ACTUATION):
        raise FormatError(f"{path}: 'actuation' must be one of {', '.join(ACTUATION)}, "
                          f"got {str(act)[:40]!r}")


def load_controller(path: str | Path):
    """(task, family, actuation, genome, record) from best.json or a run dir.

    Parsed with a whitelist (primitive and terminal names, size caps).  The
    file's ``plugins`` are requirements checked against the plugins the user
    loaded (``--plugins``, entry points): nothing the file names is imported,
    though the replay runs the code of the task it names (loaded already).
    A bare task name (a record from before versioned ids) means its v1.
    """
    path = Path(path)
    if path.is_dir():
        path = path / "best.json"
    rec = read_json(path, kind="best")
    from .plugins import require
    require(rec.get("plugins"), str(path))
    _check_record_tables(rec, path)
    try:
        params = _after_from(dict(rec.get("params", {})), path.parent)
        task = _recorded_task(rec, params)
        options = recorded_options(str(rec["family"]), rec.get("options"), rec.get("options"))
        family = make_family(str(rec["family"]), task, **options)
        genome = family.from_json(rec["genome"])
        actuation = str(rec.get("actuation") or family.default_actuation)
    except (KeyError, TypeError) as e:
        raise FormatError(f"{path}: not a controller record ({e})") from None
    except ValueError as e:
        raise FormatError(f"{path}: {e}") from None
    return task, family, actuation, genome, rec


def _recorded_task(rec: dict, params: dict):
    """The record's task; an unknown one says where a task comes from."""
    name = str(rec["task"])
    try:
        return get_task(task_id(name, recorded=True), **params)
    except KeyError as e:
        hint = ("; the record names no plugin folder: the task was registered by the program "
                "that made it -- pass --plugins DIR with a folder whose gpmotion-plugin.toml "
                "names the task's file (examples/ holds one for examples/custom_task.py)"
                if not rec.get("plugins") else "")
        raise FormatError(f"{e.args[0] if e.args else name}{hint}") from None   # the caller names path
