"""``gpmotion report``: the interactive HTML report of a run, a comparison, a study or a composite."""
from __future__ import annotations

from pathlib import Path

from .common import _activate_plugins

HELP = ("one self-contained HTML page (no server, no network) of a run, a compare folder, "
        "a folder of runs (a study) or a composite: the motion, the film of every "
        "generation's best, the curves, the terms")


def add_arguments(p) -> None:
    p.add_argument("source", help="run directory, compare folder, study folder, compose folder, "
                                  "composite file, or a shipped study's name (gpmotion study list)")
    p.add_argument("-o", "--output", metavar="FILE",
                   help="the page to write (default SOURCE/report.html; a shipped study's: "
                        "NAME-report.html here, never inside the installed package)")


def cmd_report(args):
    from ..report import write_report
    _activate_plugins(args)
    source, out = args.source, args.output
    if not Path(source).exists():
        from ..study import SHIPPED, shipped_names
        if source in shipped_names():
            source, out = SHIPPED / source, out or f"{source}-report.html"
    path = write_report(source, out)
    print(f"wrote {path}")
