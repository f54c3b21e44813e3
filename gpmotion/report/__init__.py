"""The interactive report: one self-contained HTML page of a run, a
comparison (``gpmotion compare`` folder), a folder of runs (a study) or a
composite (``gpmotion compose`` folder or file).

:func:`write_report` picks the kind from what the folder holds;
:func:`report_data` gives the page's data; :func:`player_html` and
:func:`folder_html` are the Jupyter views (``_repr_html_``) of a Trajectory
and of a run's or a study's result.
"""
from __future__ import annotations

from pathlib import Path

from ..records import FormatError, atomic_write_text
from .page import page

__all__ = ["write_report", "report_data", "player_html", "folder_html"]


def report_data(source, best=None) -> tuple[dict, str]:
    """(the page's data, its title) for a run, compare, study folder or composite."""
    from . import sources
    return sources.build(Path(source), best=best)


def write_report(source, out=None, best=None) -> Path:
    """Write ``report.html`` (default: inside ``source``; a composite file: beside it)."""
    source = Path(source)
    if not source.exists():
        raise FormatError(f"{source}: no such run, comparison, study or composite")
    data, title = report_data(source, best=best)
    if out is None:
        out = (source if source.is_dir() else source.parent) / "report.html"
    atomic_write_text(out, page(data, title))
    return Path(out)


def player_html(traj, task=None, title: str = "motion", e: int = 0) -> str:
    """Episode ``e`` of a Trajectory in the report's player, as an iframe (Jupyter)."""
    from .inline import player_html as inline
    return inline(traj, task=task, title=title, e=e)


def folder_html(source, height: int = 900) -> str:
    """A run, comparison or study folder's report as an iframe (Jupyter): the
    page ``gpmotion report`` writes, nothing written to disk."""
    from .inline import iframe
    data, title = report_data(source)
    return iframe(page(data, title), height)
