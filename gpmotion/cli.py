"""The ``gpmotion`` command: list, run, resume, replay, render, check, bench.

Bad input (unknown task, malformed file, bad value, existing run directory)
prints one line ``gpmotion: error: ...`` and exits with code 2.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

EPILOG = """examples:
  gpmotion run lamp_hop                         evolve a hopping lamp (GP, defaults)
  gpmotion run lamp_limbo --param pole_height=0.38,0.42,0.46
  gpmotion run starman_travel --controller bsr-time
  gpmotion replay runs/lamp_hop-gp-seed0        why the best controller scored as it did
  gpmotion render --figure lamp --seconds 2     a filmstrip of the lamp settling
  gpmotion list tasks
"""


def _params(items):
    out = {}
    for it in items or []:
        if "=" not in it:
            raise ValueError(f"--param expects KEY=VALUE, got {it!r}")
        k, v = it.split("=", 1)
        out[k.strip()] = v.strip()
    return out


def _add_run_args(p):
    p.add_argument("task", help="task name (gpmotion list tasks)")
    p.add_argument("--controller", default="gp", help="gp | bsr-sense | bsr-time (default gp)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--seeds", type=int, default=1, help="independent runs with seeds seed..seed+K-1")
    p.add_argument("--generations", type=int, help="GP generations / serial-search rounds")
    p.add_argument("--population", type=int, help="GP population size")
    p.add_argument("--selection", choices=["roulette", "tournament"],
                   help="GP selection (default roulette, fitness-proportionate)")
    p.add_argument("--p-crossover", type=float, help="GP crossover probability (default 0.9)")
    p.add_argument("--p-mutation", type=float, help="GP mutation probability (default 0.02)")
    p.add_argument("--p-creep", type=float,
                   help="GP constant-creep probability: Gaussian steps on one tree's constants "
                        "(default 0, herman tasks 0.1)")
    p.add_argument("--islands", type=int,
                   help="GP island model: demes that breed apart and pass their best around a "
                        "ring every 5 generations (default 1)")
    p.add_argument("--elitism", type=int, help="GP elites copied unchanged (default 1)")
    p.add_argument("--max-size", type=int, help="GP nodes per tree cap (default 200)")
    p.add_argument("--working", type=int, help="serial search: working controllers C (default 10)")
    p.add_argument("--reseed-every", type=int, help="serial search: reseeding interval (default 200)")
    p.add_argument("--rules", type=int, help="BSR rules per controller")
    p.add_argument("--t-per", type=float, help="time-based BSR period (s; default: episode length)")
    p.add_argument("--actuation", choices=["pd", "kinematic"], help="default: the family's own")
    p.add_argument("--param", "--set", action="append", metavar="KEY=VALUE",
                   help="task parameter; VALUE may be a comma list to run a series")
    p.add_argument("--out", help="run directory (default runs/TASK-CONTROLLER-seedN)")
    p.add_argument("--force", action="store_true", help="move an existing run directory aside")
    p.add_argument("--resume", action="store_true", help="continue an existing run directory")
    p.add_argument("--workers", type=int, default=0, help="process-pool workers (default: in-process)")
    p.add_argument("--scheduler", help="Dask scheduler: 'local' or tcp://HOST:PORT")
    p.add_argument("--threads", type=int, help="numba threads in this process")
    p.add_argument("--plugins", action="append", default=[], metavar="DIR",
                   help="folder of extra primitives/tasks (repeatable)")
    p.add_argument("--quiet", action="store_true", help="no per-generation progress")
    p.add_argument("--no-artifacts", action="store_true", help="skip filmstrip/GIF/curve")


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="gpmotion", description="Evolve controllers for physically "
                                 "simulated articulated figures (Gritz-Hahn GP, Auslander BSR).",
                                 epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("list", help="registered tasks, figures, primitives, controller families")
    p.add_argument("what", nargs="?", default="all",
                   choices=["all", "tasks", "figures", "primitives", "controllers"])
    p.add_argument("--plugins", action="append", default=[], metavar="DIR")
    _add_run_args(sub.add_parser("run", help="evolve a controller for a task"))
    p = sub.add_parser("resume", help="continue a killed or interrupted run")
    p.add_argument("run_dir")
    p.add_argument("--quiet", action="store_true")
    p = sub.add_parser("replay", help="re-simulate a controller and explain its score")
    p.add_argument("source", help="run directory or controller JSON (best.json)")
    p.add_argument("--out", help="also write filmstrip.png and motion.gif here")
    p.add_argument("--json", action="store_true", help="print the metrics as one JSON object")
    p = sub.add_parser("render", help="filmstrip PNG (and GIF) of a controller or a passive figure")
    p.add_argument("source", nargs="?", help="run directory or controller JSON")
    p.add_argument("--figure", help="render a figure holding its neutral pose instead")
    p.add_argument("--seconds", type=float, default=2.0)
    p.add_argument("-o", "--output", default="filmstrip.png")
    p.add_argument("--gif", help="also write a GIF")
    p.add_argument("--trees", metavar="PNG", help="also draw a GP controller's trees")
    p = sub.add_parser("compare", help="GP vs BSR on one task under one evaluation budget")
    p.add_argument("task")
    p.add_argument("--controllers", default="gp,bsr-sense,bsr-time")
    p.add_argument("--seeds", type=int, default=5)
    p.add_argument("--budget", type=int, default=5000, help="evaluations per run (default 5000)")
    p.add_argument("--actuation", choices=["pd", "kinematic"], default="pd",
                   help="one actuation for every family (default pd)")
    p.add_argument("--population", type=int, default=100, help="GP population (default 100)")
    p.add_argument("--param", action="append", metavar="KEY=VALUE")
    p.add_argument("--workers", type=int, default=0)
    p.add_argument("--scheduler")
    p.add_argument("--out", help="output folder (default runs/compare-TASK)")
    p.add_argument("--force", action="store_true", help="overwrite a non-empty --out folder")
    p.add_argument("--quiet", action="store_true")
    p = sub.add_parser("export", help="write a controller's motion as BVH (Blender, MotionBuilder)")
    p.add_argument("source", help="run directory or controller JSON (best.json)")
    p.add_argument("--bvh", required=True, metavar="OUT.bvh")
    p.add_argument("--scale", type=float, default=100.0,
                   help="file units per metre (default 100: centimetres; import in Blender with scale 0.01)")
    p = sub.add_parser("check", help="run the public contract checks on every primitive and task")
    p.add_argument("--plugins", action="append", default=[], metavar="DIR")
    sub.add_parser("bench", help="simulator throughput (gpmotion bench --help)", add_help=False)
    return ap


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["bench"]:
        from .bench import main as bench_main
        return bench_main(argv[1:]) or 0
    args = parser().parse_args(argv)
    try:
        return COMMANDS[args.cmd](args) or 0
    except KeyboardInterrupt as e:
        print(f"gpmotion: interrupted{': ' + str(e) if str(e) else ''}", file=sys.stderr)
        return 130
    except (ValueError, KeyError, OSError, ImportError, RuntimeError) as e:
        msg = e.args[0] if isinstance(e, KeyError) and e.args else str(e)
        if type(e).__name__ == "WorkerLost":
            msg += " (the checkpoint is intact: `gpmotion resume RUN_DIR` continues)"
        print(f"gpmotion: error: {msg}", file=sys.stderr)
        return 2


def cmd_list(args):
    from . import figure_names
    from .families import FAMILIES
    from .gp import primitives
    from .plugins import load_folder
    from .task import get_task, task_names
    for d in args.plugins:
        load_folder(d)
    primitives.load_builtin()
    if args.what in ("all", "tasks"):
        print("tasks:")
        for n in task_names():
            t = get_task(n)
            print(f"  {n:<18} {t.figure:<9} {t.description}")
    if args.what in ("all", "figures"):
        print("figures:", ", ".join(figure_names()))
    if args.what in ("all", "primitives"):
        print("primitives:", ", ".join(f"{n}/{primitives.get(n).arity}" for n in primitives.names()))
    if args.what in ("all", "controllers"):
        print("controllers:", ", ".join(FAMILIES))


def _run_configs(args):
    from .records import validate_number
    from .run import RunConfig
    params = _params(args.param)
    series = {k: v.split(",") for k, v in params.items() if "," in v}
    if len(series) > 1:
        raise ValueError("--param: only one parameter may be a comma list (a series)")
    validate_number("--seeds", args.seeds, lo=1, hi=10_000, integer=True)
    for name, v, lo in (("--generations", args.generations, 1), ("--population", args.population, 2),
                        ("--rules", args.rules, 1), ("--working", args.working, 2),
                        ("--reseed-every", args.reseed_every, 1), ("--workers", args.workers, 0),
                        ("--threads", args.threads, 1)):
        validate_number(name, v, lo=lo, hi=10_000_000, integer=True, allow_none=True)
    validate_number("--t-per", args.t_per, lo=1e-3, hi=1e3, allow_none=True)
    validate_number("--p-crossover", args.p_crossover, lo=0, hi=1, allow_none=True)
    validate_number("--p-mutation", args.p_mutation, lo=0, hi=1, allow_none=True)
    validate_number("--p-creep", args.p_creep, lo=0, hi=1, allow_none=True)
    validate_number("--islands", args.islands, lo=1, hi=10_000, integer=True, allow_none=True)
    validate_number("--elitism", args.elitism, lo=0, hi=10**6, integer=True, allow_none=True)
    validate_number("--max-size", args.max_size, lo=1, hi=512, integer=True, allow_none=True)
    gp = args.controller == "gp"
    search = ({"population": args.population, "generations": args.generations,
               "selection": args.selection, "p_crossover": args.p_crossover,
               "p_mutation": args.p_mutation, "p_creep": args.p_creep, "islands": args.islands,
               "elitism": args.elitism,
               "max_size": args.max_size} if gp else
              {"n_working": args.working, "n_generations": args.generations,
               "reseed_every": args.reseed_every})
    fam = {} if gp else {"rules": args.rules, "t_per": args.t_per}
    values = next(iter(series.values())) if series else [None]
    key = next(iter(series)) if series else None
    for seed in range(args.seed, args.seed + args.seeds):
        for v in values:
            p = dict(params)
            if key:
                p[key] = v
            name = _out_dir(args, seed, key, v)
            yield RunConfig(task=args.task, family=args.controller, seed=seed, params=p,
                            family_options={k: v_ for k, v_ in fam.items() if v_ is not None},
                            search={k: v_ for k, v_ in search.items() if v_ is not None},
                            actuation=args.actuation, workers=args.workers,
                            scheduler=args.scheduler, threads=args.threads,
                            plugins=[str(Path(d).resolve()) for d in args.plugins]), name


def _out_dir(args, seed, key, value) -> Path:
    """--out as given for one run; a folder per seed / series value otherwise."""
    if args.out:
        p = Path(args.out)
        p = p / f"{key}={value}" if key else p
        return p / f"seed{seed}" if args.seeds > 1 else p
    p = Path("runs") / f"{args.task}-{args.controller}-seed{seed}"
    return p / f"{key}={value}" if key else p


def cmd_run(args):
    from .run import run
    results = []
    for cfg, out in _run_configs(args):
        best, cost, rd = run(cfg, out, force=args.force, resume=args.resume, quiet=args.quiet,
                             artifacts=not args.no_artifacts)
        results.append((out, cost, rd))
        _summary(rd)
    return 0


def _summary(rd):
    from .records import read_json
    p = rd.path / "best.json"
    if not p.exists():
        print(f"{rd.path}: stopped before the end; `gpmotion resume {rd.path}` continues it")
        return
    rec = read_json(p, kind="best")
    print(f"{rd.path}: best cost {rec['final_cost']:.4f}  "
          f"{'SOLVED' if rec['success'] else 'not solved'}  " + "; ".join(rec.get("facts", [])))


def cmd_resume(args):
    from .run import run
    best, cost, rd = run(None, args.run_dir, resume=True, quiet=args.quiet)
    _summary(rd)


def cmd_replay(args):
    from .replay import load_controller, replay_genome
    from .run import render_trajectory
    task, family, actuation, genome, rec = load_controller(args.source)
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
        if family.name == "gp":
            from .run import plot_gp_trees
            plot_gp_trees(out / "trees.png", task, family, genome)


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
        raise ValueError("--trees needs a GP controller, not --figure")
    if args.figure:
        from . import load_figure, simulate
        from .records import validate_number
        validate_number("--seconds", args.seconds, lo=0.01, hi=120)
        fig = load_figure(args.figure)
        traj = simulate(fig, args.seconds)
        title, task = f"{fig.name}: holding its neutral pose", None
    else:
        from .replay import load_controller, replay_genome
        task, family, actuation, genome, rec = load_controller(args.source)
        traj = replay_genome(task, family, actuation, genome)[0]
        title = f"{task.name} ({family.name})"
        if args.trees:
            if family.name != "gp":
                raise ValueError("--trees needs a GP controller")
            from .run import plot_gp_trees
            plot_gp_trees(args.trees, task, family, genome)
            print(f"wrote {args.trees}")
    render_trajectory(traj, args.output, args.gif, title=title, task=task)
    print(f"wrote {args.output}" + (f" and {args.gif}" if args.gif else ""))


def cmd_compare(args):
    from .compare import compare
    from .families import FAMILIES
    from .records import validate_number
    ctrls = [c.strip() for c in args.controllers.split(",") if c.strip()]
    for c in ctrls:
        if c not in FAMILIES:
            raise ValueError(f"--controllers: unknown {c!r}; known: {', '.join(FAMILIES)}")
    validate_number("--seeds", args.seeds, lo=1, hi=1000, integer=True)
    validate_number("--budget", args.budget, lo=10, hi=10**9, integer=True)
    validate_number("--population", args.population, lo=2, hi=10**6, integer=True)
    out = args.out or f"runs/compare-{args.task}"
    rows, md = compare(args.task, ctrls, args.seeds, args.budget, out, actuation=args.actuation,
                       params=_params(args.param), population=args.population,
                       workers=args.workers, scheduler=args.scheduler, quiet=args.quiet,
                       force=args.force)
    print(md)
    print(f"wrote {out}/compare.md, compare.csv, runs.json, curves.png")


def cmd_export(args):
    from .bvh import write_bvh
    from .records import validate_number
    from .replay import load_controller, replay_genome
    validate_number("--scale", args.scale, lo=1e-6, hi=1e6)
    task, family, actuation, genome, rec = load_controller(args.source)
    traj = replay_genome(task, family, actuation, genome)[0]
    n = write_bvh(args.bvh, traj, scale=args.scale)
    print(f"wrote {args.bvh}: {len(traj.figure.body_names)} joints, {n} frames at "
          f"{1 / (traj.dt * traj.record_every):g} fps (y-up, units of 1/{args.scale:g} m)")
    if traj.diverged[0]:
        print("  the simulation diverged: the frames after it are not written")


def cmd_check(args):
    from .check import check_primitive, check_task
    from .gp import primitives
    from .plugins import load_folder
    from .task import task_names
    for d in args.plugins:
        load_folder(d)
    primitives.load_builtin()
    bad = 0
    for name in primitives.names():
        bad += _report(f"primitive {name}", check_primitive, name)
    for name in task_names():
        bad += _report(f"task {name}", check_task, name)
    return 1 if bad else 0


def _report(label, fn, arg):
    try:
        fn(arg)
        print(f"ok    {label}")
        return 0
    except AssertionError as e:
        print(f"FAIL  {label}: {e}")
        return 1


COMMANDS = {"list": cmd_list, "run": cmd_run, "resume": cmd_resume, "replay": cmd_replay,
            "render": cmd_render, "check": cmd_check, "compare": cmd_compare, "export": cmd_export}

if __name__ == "__main__":
    sys.exit(main())
