"""``gpmotion report``: the interactive HTML report of a run, a comparison, a study or a composite."""
from __future__ import annotations

from .common import _activate_plugins

HELP = ("one self-contained HTML page (no server, no network) of a run, a compare folder, "
        "a folder of runs (a study) or a composite: the motion, the film of every "
        "generation's best, the curves, the terms")


def add_arguments(p) -> None:
    p.add_argument("source", help="run directory, compare folder, study folder, compose folder "
                                  "or composite file")
    p.add_argument("-o", "--output", metavar="FILE",
                   help="the page to write (default SOURCE/report.html)")


def cmd_report(args):
    from ..report import write_report
    _activate_plugins(args)
    path = write_report(args.source, args.output)
    print(f"wrote {path}")
