"""The ``gpmotion`` command: list, show, run, resume, replay, render, compare, export,
check, bench, help.

Bad input (unknown task, malformed file, bad value, existing run directory)
prints one line ``gpmotion: error: ...`` and exits with code 2.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

STYLE_HELP = """costs and phased style points:
  A cost is lower-is-better: a main goal (e.g. metres from the target) plus
  style terms (arrive early, don't fall, end neutral...).  As in Gritz & Hahn,
  each style term phases in: its weight ramps from 0 to full over a window of
  run progress (generation / generations), so the search first learns the
  main goal.  While terms phase in, a generation's costs (best, median) are
  under that generation's weights: "best" can rise although no controller got
  worse, and "solved" counts the controllers passing the success test.  The
  final best.json is re-scored with every term at full weight; `gpmotion
  replay` shows each term's value, weight and phase.  `gpmotion show TASK`
  lists a task's terms with their phase-in windows.
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


def _params(items):
    out = {}
    for it in items or []:
        if "=" not in it:
            raise ValueError(f"--param expects KEY=VALUE, got {it!r}")
        k, v = it.split("=", 1)
        if k.strip() == "figure":
            raise ValueError("--param figure=...: use --figure VARIANT.toml (stored with the run)")
        out[k.strip()] = v.strip()
    return out


def _add_run_args(p):
    from .cli_options import add_arguments
    from .families import DEFAULT_FAMILY, family_names
    p.add_argument("task", help="task name (gpmotion list tasks; gpmotion show TASK)")
    p.add_argument("--controller", default=DEFAULT_FAMILY,
                   help=f"controller family: {' | '.join(family_names())} (default {DEFAULT_FAMILY}; "
                        "gpmotion list controllers)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--seeds", type=int, default=1,
                   help="independent runs with seeds seed..seed+K-1; prints an aggregate at the end")
    p.add_argument("--actuation", choices=["pd", "kinematic"],
                   help="pd: targets drive PD servos; kinematic: joints follow targets with a "
                        "time constant τ (default: the family's, gpmotion list controllers)")
    p.add_argument("--preset", help="a family's named configuration, e.g. gp's default | "
                   "gritz-hahn (the paper's terminals, functions and breeding; lamp tasks); "
                   "explicit options win")
    p.add_argument("--figure", metavar="VARIANT.toml",
                   help="run the task on a figure variant, a TOML file or a registered figure "
                        "(it must have the joints, sites, contacts and senses the task uses)")
    p.add_argument("--param", "--set", action="append", metavar="KEY=VALUE",
                   help="task parameter (gpmotion show TASK); a number's VALUE may be a comma list to "
                        "run a series (a text parameter such as after= takes the list as its value)")
    p.add_argument("--out", help="run directory (default runs/TASK-CONTROLLER-seedN)")
    p.add_argument("--force", action="store_true", help="move an existing run directory aside")
    p.add_argument("--resume", action="store_true", help="continue an existing run directory")
    p.add_argument("--workers", type=int, default=0, help="process-pool workers (default: in-process)")
    p.add_argument("--scheduler", help="Dask scheduler: 'local' or tcp://HOST:PORT")
    p.add_argument("--threads", type=int, help="numba threads in this process")
    _add_plugins_arg(p)
    _add_tls_args(p)
    p.add_argument("--quiet", action="store_true", help="no per-generation progress")
    p.add_argument("--no-artifacts", action="store_true", help="skip filmstrip/GIF/curve")
    add_arguments(p)
    from .compose.robust import add_run_arguments        # --robust-starts K, --perturb ...
    add_run_arguments(p)


def _add_plugins_arg(p):
    p.add_argument("--plugins", action="append", default=[], metavar="DIR",
                   help="folder of extra primitives/tasks/figures (repeatable); the only way, "
                        "besides installed entry points, that gpmotion runs code not its own")


def _add_tls_args(p):
    p.add_argument("--tls-ca-file", metavar="PEM", help="Dask TLS: CA certificate (tls:// scheduler)")
    p.add_argument("--tls-cert", metavar="PEM", help="Dask TLS: this client's certificate")
    p.add_argument("--tls-key", metavar="PEM", help="Dask TLS: this client's private key")


def _backend(args) -> dict:
    """This invocation's evaluator settings (TLS files), never recorded in the run."""
    return {k: getattr(args, k) for k in ("tls_ca_file", "tls_cert", "tls_key")
            if getattr(args, k, None)}


def _activate_plugins(args) -> list:
    from .plugins import activate
    return activate(getattr(args, "plugins", []) or [])


def parser() -> argparse.ArgumentParser:
    from .families import family_names
    ap = argparse.ArgumentParser(prog="gpmotion", description="Evolve controllers for physically "
                                 "simulated articulated figures (Gritz-Hahn GP, Auslander BSR).",
                                 epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    from .version import __version__
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
    p.add_argument("--workers", type=int, default=0, help="process-pool workers (default: in-process)")
    p.add_argument("--scheduler", help="Dask scheduler: 'local' or tcp://HOST:PORT")
    p.add_argument("--out", help="output folder (default runs/compare-TASK)")
    _add_plugins_arg(p)
    p.add_argument("--force", action="store_true", help="overwrite a non-empty --out folder")
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
    from .compose.command import HELP as COMPOSE_HELP, add_arguments as add_compose_args
    from .compose.robust_command import HELP as ROBUST_HELP, add_arguments as add_robust_args
    add_compose_args(sub.add_parser("compose", help=COMPOSE_HELP))
    add_robust_args(sub.add_parser("robustness", help=ROBUST_HELP))
    return ap


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["bench"]:
        from .bench import main as bench_main
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
        return getattr(e, "exit_code", 2)     # 3: the Dask scheduler was lost (README)


def _evaluator_lost(e: BaseException) -> bool:
    from .evaluators import SchedulerLost, WorkerLost
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
    from . import plugins
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
        from .bench import main as bench_main
        return bench_main(["--help"]) or 0
    subs = next(a for a in ap._actions if isinstance(a, argparse._SubParsersAction)).choices
    if topic[0] not in subs:
        from .names import unknown
        print(f"gpmotion: error: {unknown('command', topic[0], subs)}", file=sys.stderr)
        return 2
    subs[topic[0]].print_help()
    return 0


def cmd_list(args):
    from . import figure_names
    from .families import family_class, family_names
    from .gp import primitives
    from .task import task_class, task_ids
    _activate_plugins(args)
    primitives.load_builtin()
    if args.what in ("all", "tasks"):
        print("tasks:")
        for tid in task_ids():
            t = task_class(tid)
            print(f"  {tid:<24} {t.figure:<16} {t.description}")
        print("  (a bare name means its newest version; parameters, cost terms, joints and senses "
              "of one task: gpmotion show TASK)")
    if args.what in ("all", "figures"):
        print("figures:", ", ".join(figure_names()))
    if args.what in ("all", "primitives"):
        print("primitives:", ", ".join(f"{n}/{primitives.get(n).arity}" for n in primitives.names()))
    if args.what in ("all", "controllers"):
        print("controllers:")
        for n in family_names():
            c = family_class(n)
            print(f"  {n:<12} {c.description} (default actuation {c.default_actuation})")


def cmd_show(args):
    from .show import describe_task
    _activate_plugins(args)
    print(describe_task(args.task))


def _text_param(task: str, key: str) -> bool:
    """A parameter whose default is text (``after``: a comma-separated list of
    files) takes a comma list as its one value, never as a series."""
    from .task import task_class
    try:
        return isinstance(task_class(task).params.get(key), str)
    except ValueError:                 # an unknown task: reported where the run is built
        return False


def _run_configs(args):
    from .cli_options import collect
    from .families import family_class, family_names
    from .names import unknown
    from .records import validate_number
    from .run import RunConfig
    if args.controller not in family_names():
        raise ValueError(unknown("controller", args.controller, family_names()))
    params = _params(args.param)
    plugins = _activate_plugins(args)     # before the options: --primitives may name a plugin's
    series = {k: v.split(",") for k, v in params.items() if "," in v and not _text_param(args.task, k)}
    if len(series) > 1:
        raise ValueError("--param: only one parameter may be a comma list (a series)")
    validate_number("--seeds", args.seeds, lo=1, hi=10_000, integer=True)
    validate_number("--workers", args.workers, lo=0, hi=10_000_000, integer=True)
    validate_number("--threads", args.threads, lo=1, hi=10_000_000, integer=True, allow_none=True)
    search, fam = collect(args, args.controller)
    from .compose.robust import run_setting
    robust = run_setting(args)
    if args.preset:
        fam, search = family_class(args.controller).apply_preset(args.preset, args.task, fam,
                                                                 search)
    if args.figure:
        params["figure"] = _figure_variant(args.task, args.figure)
    values = next(iter(series.values())) if series else [None]
    key = next(iter(series)) if series else None
    for seed in range(args.seed, args.seed + args.seeds):
        for v in values:
            p = dict(params)
            if key:
                p[key] = v
            name = _out_dir(args, seed, key, v)
            yield RunConfig(task=args.task, family=args.controller, seed=seed, params=p,
                            family_options=dict(fam), search=dict(search),
                            actuation=args.actuation, workers=args.workers,
                            scheduler=args.scheduler, threads=args.threads,
                            plugins=list(plugins), robust=dict(robust)), name


def _figure_variant(task_name, path):
    """The variant's spec, resolved (``extends`` merged), as plain data: stored in the
    run's parameters, so the run does not depend on the TOML file staying put."""
    from .figures import figure_names, load_spec, resolve_spec
    if Path(path).is_file():
        return resolve_spec(load_spec(path))
    if path in figure_names():                       # a registered figure, e.g. herman_standing
        return resolve_spec({"extends": path})
    from .names import did_you_mean
    raise ValueError(f"--figure: no such file or figure {path!r}{did_you_mean(path, figure_names())}")


def _out_dir(args, seed, key, value) -> Path:
    """--out as given for one run; a folder per seed / series value otherwise."""
    if args.out:
        p = Path(args.out)
        p = p / f"{key}={value}" if key else p
        return p / f"seed{seed}" if args.seeds > 1 else p
    p = Path("runs") / f"{args.task}-{args.controller}-seed{seed}"
    return p / f"{key}={value}" if key else p


def cmd_run(args):
    from .run import build, run
    configs = list(_run_configs(args))        # every config validated before the first run
    if not args.resume:                       # (built, too: a series' bad value writes nothing)
        for cfg, _ in configs:
            build(cfg)
    dirs = []
    for cfg, out in configs:
        _, _, rd = run(cfg, out, force=args.force, resume=args.resume, quiet=args.quiet,
                       artifacts=not args.no_artifacts, backend=_backend(args))
        dirs.append(rd.path)
        _summary(rd)
    if len(dirs) > 1:
        print(_aggregate(dirs))
    return 0


def _aggregate(dirs) -> str:
    """One line over the finished runs: median [min, max] final cost, how many solved."""
    import numpy as np

    from .records import read_json
    recs = [read_json(d / "best.json", kind="best") for d in dirs if (d / "best.json").exists()]
    if not recs:
        return f"{len(dirs)} runs: none finished"
    costs = np.array([r["final_cost"] for r in recs])
    solved = sum(bool(r["success"]) for r in recs)
    return (f"{len(recs)} runs: final cost (every term at full weight) median "
            f"{np.median(costs):.4f} [min {costs.min():.4f}, max {costs.max():.4f}]; "
            f"solved {solved}/{len(recs)}"
            + (f"; {len(dirs) - len(recs)} stopped before the end" if len(recs) < len(dirs) else ""))


def _summary(rd):
    from .records import read_json
    p = rd.path / "best.json"
    if not p.exists():
        print(f"{rd.path}: stopped before the end; `gpmotion resume {rd.path}` continues it")
        return
    rec = read_json(p, kind="best")
    robust = (read_json(rd.path / "config.json", kind="config").get("run") or {}).get("robust")
    where = (f" from the nominal start ({rec['cost']:.4f}: the {robust.get('aggregate', 'mean')} "
             f"over its {robust.get('starts')} perturbed starts in the run)") if robust else ""
    print(f"{rd.path}: best cost {rec['final_cost']:.4f}{where}  "
          f"{'SOLVED' if rec['success'] else 'not solved'}  " + "; ".join(rec.get("facts", [])))


def cmd_resume(args):
    from .run import run
    _refuse_series(Path(args.run_dir))
    _activate_plugins(args)
    backend = _backend(args)
    if args.workers is not None or args.scheduler is not None:
        backend.update(workers=args.workers or 0, scheduler=args.scheduler)
    _, _, rd = run(None, args.run_dir, resume=True, quiet=args.quiet, backend=backend,
                   extend_generations=args.extend_generations)
    _summary(rd)


def _refuse_series(path: Path):
    """A series folder (--seeds K, --param k=a,b) holds runs, not a config: name them."""
    if (path / "config.json").exists() or not path.is_dir():
        return
    runs = sorted(str(c.parent) for c in path.glob("**/config.json"))
    if runs:
        more = f" (and {len(runs) - 3} more)" if len(runs) > 3 else ""
        raise ValueError(f"{path} is a series of {len(runs)} runs; resume each: "
                         + ", ".join(f"gpmotion resume {r}" for r in runs[:3]) + more)


def cmd_replay(args):
    from .replay import load_controller, replay_genome
    from .run import render_trajectory
    _activate_plugins(args)
    from .compose import playback                       # a composite file: its phases in series
    if playback.is_composite(args.source):
        return playback.replay(args)
    task, family, actuation, genome, _ = load_controller(args.source)
    traj, costs, measures, ok = replay_genome(task, family, actuation, genome)
    if args.json:
        import json
        print(json.dumps({"task": task.name, "family": family.name, "actuation": actuation,
                          "cost": float(costs[0]), "success": bool(ok[0]),
                          "diverged": bool(traj.diverged[0]),
                          "terms": task.breakdown(measures, 0, 1.0),
                          "facts": task.describe(traj, measures)}))
    else:
        _print_replay(task, family, actuation, traj, costs, measures, ok)
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        render_trajectory(traj, out / "filmstrip.png", out / "motion.gif", title=task.name, task=task)
        print(f"  wrote {out / 'filmstrip.png'} and {out / 'motion.gif'}")
        if family.plot_file:
            family.plot(out / family.plot_file, genome)


def _print_replay(task, family, actuation, traj, costs, measures, ok):
    print(f"{task.name} ({family.name}, {actuation}): cost {costs[0]:.4f}  "
          f"{'SOLVED' if ok[0] else 'not solved'}  [{task.success_threshold}]")
    print(f"  {'term':<16} {'value':>10} {'weight':>8} {'phase':>6} {'contribution':>13}")
    for r in task.breakdown(measures, 0, 1.0):
        print(f"  {r['term']:<16} {r['value']:>10.4f} {r['weight']:>8.3f} {r['phase']:>6.2f} "
              f"{r['contribution']:>13.4f}{'  (main)' if r['main'] else ''}")
    for fact in task.describe(traj, measures):
        print(f"  {fact}")
    if traj.diverged[0]:
        print("  the simulation diverged")


def cmd_render(args):
    from .run import render_trajectory
    if bool(args.source) == bool(args.figure):
        raise ValueError("render: give a run directory/controller file or --figure NAME (one)")
    if args.figure and args.trees:
        raise ValueError("--trees draws a controller's structure, not a --figure's")
    if args.source and args.seconds is not None:
        raise ValueError("--seconds applies to --figure; a controller runs its task's episode "
                         "(the task's 'seconds' parameter)")
    _activate_plugins(args)
    from .compose import playback
    if args.source and playback.is_composite(args.source):
        return playback.render_command(args)
    if args.figure:
        from . import load_figure, simulate
        from .records import validate_number
        seconds = validate_number("--seconds", 2.0 if args.seconds is None else args.seconds,
                                  lo=0.01, hi=120)
        fig = load_figure(args.figure)
        traj = simulate(fig, seconds)
        title, task = f"{fig.name}: holding its neutral pose", None
    else:
        from .replay import load_controller, replay_genome
        task, family, actuation, genome, _ = load_controller(args.source)
        traj = replay_genome(task, family, actuation, genome)[0]
        title = f"{task.name} ({family.name})"
        if args.trees:
            family.plot(args.trees, genome)       # a family with nothing to draw says so
            print(f"wrote {args.trees}")
    render_trajectory(traj, args.output, args.gif, title=title, task=task)
    print(f"wrote {args.output}" + (f" and {args.gif}" if args.gif else ""))


def cmd_compare(args):
    from .compare import compare
    from .families import family_class, family_names
    from .names import unknown
    from .records import validate_number
    ctrls = [c.strip() for c in args.controllers.split(",") if c.strip()]
    for c in ctrls:
        if c not in family_names():
            raise ValueError(f"--controllers: {unknown('controller', c, family_names())}")
    validate_number("--seeds", args.seeds, lo=1, hi=1000, integer=True)
    validate_number("--budget", args.budget, lo=10, hi=10**9, integer=True)
    with_population = [c for c in ctrls if family_class(c).takes_population]
    if args.population is not None and not with_population:
        raise ValueError(f"--population does not apply: no family in --controllers has a "
                         f"population (those with one: "
                         f"{', '.join(n for n in family_names() if family_class(n).takes_population)})")
    population = validate_number("--population", args.population, lo=2, hi=10**6, integer=True,
                                 allow_none=True)
    out = args.out or f"runs/compare-{args.task}"
    _activate_plugins(args)
    _, md = compare(args.task, ctrls, args.seeds, args.budget, out, actuation=args.actuation,
                    params=_params(args.param), population=population,
                    workers=args.workers, scheduler=args.scheduler, quiet=args.quiet,
                    force=args.force)
    print(md)
    print(f"wrote {out}/compare.md, compare.csv, runs.json, curves.png")


def cmd_export(args):
    from .bvh import write_bvh
    from .records import validate_number
    from .replay import load_controller, replay_genome
    validate_number("--scale", args.scale, lo=1e-6, hi=1e6)
    _activate_plugins(args)
    from .compose import playback
    if playback.is_composite(args.source):
        return playback.export_command(args)
    task, family, actuation, genome, _ = load_controller(args.source)
    traj = replay_genome(task, family, actuation, genome)[0]
    n = write_bvh(args.bvh, traj, scale=args.scale)
    print(f"wrote {args.bvh}: {len(traj.figure.body_names)} joints, {n} frames at "
          f"{1 / (traj.dt * traj.record_every):g} fps (y-up, units of 1/{args.scale:g} m)")
    if traj.diverged[0]:
        print("  the simulation diverged: the frames after it are not written")


def cmd_check(args):
    from .check import check_family, check_primitive, check_task
    from .families import family_names
    from .gp import primitives
    from .task import task_ids
    if args.only_plugins and not args.plugins:
        raise ValueError("--only-plugins needs --plugins DIR")
    primitives.load_builtin()
    before = set(primitives.names()) | set(task_ids()) | set(family_names())
    _activate_plugins(args)
    checks = ([("primitive", n, check_primitive) for n in primitives.names()]
              + [("task", n, check_task) for n in task_ids()]       # every version of every task
              + [("family", n, check_family) for n in family_names()])
    if args.only_plugins:
        checks = [c for c in checks if c[1] not in before]
        if not checks:
            raise ValueError(f"{', '.join(args.plugins)}: no primitives, tasks or controller "
                             "families to check")
    bad = sum(_report(f"{kind} {name}", fn, name) for kind, name, fn in checks)
    return 1 if bad else 0


def _report(label, fn, arg):
    try:
        fn(arg)
        print(f"ok    {label}")
        return 0
    except AssertionError as e:
        print(f"FAIL  {label}: {e}")
        return 1


COMMANDS = {"list": cmd_list, "show": cmd_show, "run": cmd_run, "resume": cmd_resume, "replay": cmd_replay,
            "render": cmd_render, "check": cmd_check, "compare": cmd_compare, "export": cmd_export}


def cmd_compose(args):
    from .compose.command import run_command
    return run_command(args)


def cmd_robustness(args):
    from .compose.robust_command import run_command
    return run_command(args)


COMMANDS.update(compose=cmd_compose, robustness=cmd_robustness)

if __name__ == "__main__":
    sys.exit(main())
