"""The interactive report: one self-contained HTML page of a run, a
comparison (``gpmotion compare`` folder), a folder of runs (a study) or a
composite (``gpmotion compose`` folder or file).

:func:`write_report` picks the kind from what the folder holds;
:func:`report_data` gives the page's data; :func:`player_html` is the
Jupyter view of a Trajectory.
"""
from __future__ import annotations

from pathlib import Path

from ..records import FormatError, atomic_write_text
from .page import page

__all__ = ["write_report", "report_data", "player_html"]


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


def player_html(traj, task=None, title: str = "motion") -> str:
    """A Trajectory's player as an iframe (Jupyter's ``_repr_html_``)."""
    import html as _html
    from .encode import encode_motion
    panel = {"name": title, "motion": encode_motion(traj, 0, task=task)}
    doc = page({"kind": "motion", "panels": [panel]}, title)
    return (f'<iframe style="width:100%;height:560px;border:0" '
            f'srcdoc="{_html.escape(doc, quote=True)}"></iframe>')
