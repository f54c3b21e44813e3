"""The ``gpmotion`` command: list, show, run, resume, replay, render, compare, export,
check, compose, robustness, bench, help.

One module per group of commands; this one builds the parser and holds the one
error path: bad input (unknown task, malformed file, bad value, existing run
directory) prints one line ``gpmotion: error: ...`` and exits with code 2.
No module outside this package sees an argparse namespace.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .common import _add_plugins_arg, _add_tls_args
from .comparison import cmd_compare
from .motion import cmd_export, cmd_render, cmd_replay
from .registry import cmd_check, cmd_list, cmd_show
from .runs import _add_run_args, _run_configs, cmd_resume, cmd_run


def cmd_compose(args):
    from .compose import run_command
    return run_command(args)


def cmd_robustness(args):
    from .robustness import run_command
    return run_command(args)


def cmd_report(args):
    from .report import cmd_report as run
    return run(args)


def cmd_study(args):
    from .study import run_command
    return run_command(args)


COMMANDS = {"list": cmd_list, "show": cmd_show, "run": cmd_run, "resume": cmd_resume, "replay": cmd_replay,
            "render": cmd_render, "check": cmd_check, "compare": cmd_compare, "export": cmd_export,
            "compose": cmd_compose, "robustness": cmd_robustness,
            "study": cmd_study, "report": cmd_report}
__all__ = ["COMMANDS", "main", "parser", "_run_configs"]


STYLE_HELP = """costs and phased style points:
  A cost is lower-is-better: a main goal (e.g. metres from the target) plus
  style terms (arrive early, don't fall, end neutral...).  As in Gritz & Hahn,
  each style term phases in: its weight ramps from 0 to full over a window of
  run progress (generation / generations), so the search first learns the
  main goal.  The progress line and log.csv show two bests under one name
  each: "best so far" (column best_so_far) is under that generation's weights,
  with the generation's median under the same weights beside it, and can rise
  although no controller got worse; "best final" (column best_final) is the
  best so far re-scored with every term at full weight, the cost best.json
  keeps ("–" while not yet known).  "solved k of N evaluated" counts the
  controllers evaluated in that generation that pass the success test.
  Generations count from 0, the first population.  `gpmotion replay` shows each term's value, weight and phase;
  `gpmotion show TASK` lists a task's terms with their phase-in windows.
"""


EPILOG = STYLE_HELP + """
examples:
  gpmotion run lamp_hop                         evolve a hopping lamp (GP, defaults)
  gpmotion run lamp_limbo --param pole_height=0.38,0.42,0.46
  gpmotion run starman_travel --controller bsr-time
  gpmotion replay runs/lamp_hop-gp-seed0        why the best controller scored as it did
  gpmotion render --figure lamp --seconds 2     a filmstrip of the lamp settling
  gpmotion list tasks
  gpmotion show lamp_hop                        a task's parameters, terms, figure and senses
  gpmotion help run                             every option of a command
"""


def parser() -> argparse.ArgumentParser:
    from ..families import family_names
    ap = argparse.ArgumentParser(prog="gpmotion", description="Evolve controllers for physically "
                                 "simulated articulated figures (Gritz-Hahn GP, Auslander BSR).",
                                 epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    from ..version import __version__
    ap.add_argument("--version", action="version", version=f"gpmotion {__version__}")
    sub = ap.add_subparsers(dest="cmd", required=True, metavar="COMMAND")
    p = sub.add_parser("help", help="help on a command: gpmotion help run")
    p.add_argument("topic", nargs="?", help="a command name")
    p = sub.add_parser("list", help="registered tasks, figures, primitives, controller families "
                       "(gpmotion show TASK for one task's details)")
    p.add_argument("what", nargs="?", default="all",
                   choices=["all", "tasks", "figures", "primitives", "controllers"])
    _add_plugins_arg(p)
    p = sub.add_parser("show", help="a task's parameters, terms (doc, weight, phase-in), figure, "
                       "controlled joints, sites and senses")
    p.add_argument("task", help="task name (gpmotion list tasks)")
    _add_plugins_arg(p)
    _add_run_args(sub.add_parser("run", help="evolve a controller for a task",
                                 description="Evolve a controller for a task.", epilog=STYLE_HELP,
                                 formatter_class=argparse.RawDescriptionHelpFormatter))
    p = sub.add_parser("resume", help="continue a killed or interrupted run")
    p.add_argument("run_dir", help="a run directory (runs/TASK-CONTROLLER-seedN)")
    p.add_argument("--extend-generations", type=int, metavar="N",
                   help="add N generations (rounds) to the run, finished or not; they run at "
                        "the final weights of the style terms")
    p.add_argument("--quiet", action="store_true", help="no per-generation progress")
    p.add_argument("--workers", type=int, help="resume on a process pool (replaces the recorded backend)")
    p.add_argument("--scheduler", help="resume on Dask: 'local' or tcp://HOST:PORT (replaces it too)")
    _add_tls_args(p)
    _add_plugins_arg(p)
    p = sub.add_parser("replay", help="re-simulate a controller and explain its score")
    p.add_argument("source", help="run directory or controller JSON (best.json)")
    p.add_argument("--out", help="also write filmstrip.png and motion.gif here")
    p.add_argument("--json", action="store_true", help="print the metrics as one JSON object")
    _add_plugins_arg(p)
    p = sub.add_parser("render", help="filmstrip PNG (and GIF) of a controller or a passive figure")
    p.add_argument("source", nargs="?", help="run directory or controller JSON")
    p.add_argument("--figure", help="render a figure holding its neutral pose instead")
    p.add_argument("--seconds", type=float,
                   help="simulated seconds for --figure (default 2; a controller runs its task's episode)")
    p.add_argument("-o", "--output", default="filmstrip.png", help="filmstrip PNG (default filmstrip.png)")
    p.add_argument("--gif", help="also write a GIF")
    p.add_argument("--trees", metavar="PNG", help="also draw a GP controller's trees")
    _add_plugins_arg(p)
    p = sub.add_parser("compare", help="controller families side by side on one task under "
                       "one evaluation budget")
    p.add_argument("task", help="task name (gpmotion list tasks)")
    p.add_argument("--controllers", default=",".join(family_names()),
                   help=f"comma list of controller families (default {','.join(family_names())})")
    p.add_argument("--seeds", type=int, default=5, help="runs per family, seeds 0..K-1 (default 5)")
    p.add_argument("--budget", type=int, default=5000, help="evaluations per run (default 5000)")
    p.add_argument("--actuation", choices=["pd", "kinematic"], default="pd",
                   help="one actuation for every family (default pd)")
    p.add_argument("--population", type=int,
                   help="population of the population-based searches under the budget (default: "
                        "each family's; needs such a family in --controllers)")
    p.add_argument("--param", action="append", metavar="KEY=VALUE",
                   help="task parameter (gpmotion show TASK)")
    p.add_argument("--workers", type=int, default=0,
                   help="searches run at once in spawned processes (default: one, in-process)")
    p.add_argument("--scheduler", help="Dask scheduler: 'local' or tcp://HOST:PORT")
    p.add_argument("--out", help="output folder (default runs/compare-TASK; the same command "
                   "resumes a cut comparison)")
    _add_plugins_arg(p)
    p.add_argument("--force", action="store_true",
                   help="move a non-empty --out folder (of another comparison) aside")
    p.add_argument("--quiet", action="store_true", help="no per-generation progress")
    p = sub.add_parser("export", help="write a controller's motion as BVH (Blender, MotionBuilder)")
    p.add_argument("source", help="run directory or controller JSON (best.json)")
    p.add_argument("--bvh", required=True, metavar="OUT.bvh", help="the BVH file to write")
    p.add_argument("--scale", type=float, default=100.0,
                   help="file units per metre (default 100: centimetres; import in Blender with scale 0.01)")
    _add_plugins_arg(p)
    p = sub.add_parser("check", help="run the public contract checks on every primitive, task "
                       "and controller family")
    _add_plugins_arg(p)
    p.add_argument("--only-plugins", action="store_true",
                   help="check only what the --plugins folders add, not the built-ins")
    sub.add_parser("bench", help="simulator throughput (gpmotion bench --help)", add_help=False)
    from .compose import HELP as COMPOSE_HELP, add_arguments as add_compose_args
    from .robustness import HELP as ROBUST_HELP, add_arguments as add_robust_args
    add_compose_args(sub.add_parser("compose", help=COMPOSE_HELP))
    add_robust_args(sub.add_parser("robustness", help=ROBUST_HELP))
    from .study import HELP as STUDY_HELP, add_arguments as add_study_args
    add_study_args(sub.add_parser("study", help=STUDY_HELP))
    from .report import HELP as REPORT_HELP, add_arguments as add_report_args
    p = sub.add_parser("report", help=REPORT_HELP)
    add_report_args(p)
    _add_plugins_arg(p)
    return ap


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["bench"]:
        from ..bench import main as bench_main
        return bench_main(argv[1:]) or 0
    ap = parser()
    if argv[:1] == ["help"]:
        return _help(ap, argv[1:])
    args = ap.parse_args(argv)
    try:
        return COMMANDS[args.cmd](args) or 0
    except KeyboardInterrupt as e:
        print(f"gpmotion: interrupted{': ' + str(e) if str(e) else ''}", file=sys.stderr)
        return getattr(e, "code", 130)          # 143 after SIGTERM
    except BrokenPipeError:                 # `gpmotion show TASK | head`
        sys.stderr.close()
        return 0
    except Exception as e:
        if not _input_error(e):
            raise                           # a bug: its traceback, not a one-liner
        msg = e.args[0] if isinstance(e, KeyError) and e.args else str(e)
        if _evaluator_lost(e) and "resume" not in msg:
            msg += " (the checkpoint is intact: `gpmotion resume RUN_DIR` continues)"
        print(f"gpmotion: error: {msg}", file=sys.stderr)
        return getattr(e, "exit_code", 2)     # 3: the Dask scheduler was lost (docs/howto/dask.md)


def _evaluator_lost(e: BaseException) -> bool:
    from ..evaluators import SchedulerLost, WorkerLost
    return isinstance(e, (WorkerLost, SchedulerLost))


def _input_error(e: BaseException) -> bool:
    """Errors that are the user's input, not a bug: a ValueError (our bad-input
    convention) or an unknown name (KeyError) raised by gpmotion's own code or
    a plugin, a file the OS refuses, and our error types that carry an
    ``exit_code`` (a lost worker or scheduler, the dask extra missing).  The
    same types raised inside numpy, numba, DEAP or the standard library are
    bugs, and so is every other type (TypeError, RuntimeError...)."""
    if isinstance(e, OSError) or hasattr(type(e), "exit_code"):
        return True
    if not isinstance(e, (ValueError, KeyError)):
        return False
    tb = e.__traceback__
    while tb.tb_next is not None:
        tb = tb.tb_next
    return _ours(tb.tb_frame)


def _ours(frame) -> bool:
    """Code of gpmotion (its package, tasks, primitives) or of a plugin folder."""
    from .. import plugins
    if str(frame.f_globals.get("__name__", "")).startswith("gpmotion"):
        return True
    f = Path(frame.f_code.co_filename).resolve()
    return any(f.is_relative_to(d) for d in getattr(plugins, "_FOLDERS", {}))


def _help(ap, topic):
    """``gpmotion help [COMMAND]``: the same text as ``gpmotion COMMAND --help``."""
    if not topic:
        ap.print_help()
        return 0
    if topic[0] == "bench":
        from ..bench import main as bench_main
        return bench_main(["--help"]) or 0
    subs = next(a for a in ap._actions if isinstance(a, argparse._SubParsersAction)).choices
    if topic[0] not in subs:
        from ..names import unknown
        print(f"gpmotion: error: {unknown('command', topic[0], subs)}", file=sys.stderr)
        return 2
    subs[topic[0]].print_help()
    return 0
