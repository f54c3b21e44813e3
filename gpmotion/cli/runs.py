"""``gpmotion run`` and ``gpmotion resume``: options to RunConfigs, a series of runs, the summary line."""
from __future__ import annotations

from pathlib import Path

from .common import _activate_plugins, _add_plugins_arg, _add_tls_args, _backend, _params


def _add_run_args(p):
    from ..cli_options import add_arguments
    from ..families import DEFAULT_FAMILY, family_names
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
    p.add_argument("--out", help="run directory (default runs/TASK-CONTROLLER-seedN, "
                   "runs/TASK-CONTROLLER-PRESET-seedN with --preset)")
    p.add_argument("--force", action="store_true", help="move an existing run directory aside")
    p.add_argument("--resume", action="store_true", help="continue an existing run directory")
    p.add_argument("--workers", type=int, default=0, help="process-pool workers (default: in-process)")
    p.add_argument("--scheduler", help="Dask scheduler: 'local' or tcp://HOST:PORT")
    p.add_argument("--threads", type=int,
                   help="rollout threads in this process (default: NUMBA_NUM_THREADS, the cores)")
    _add_plugins_arg(p)
    _add_tls_args(p)
    p.add_argument("--quiet", action="store_true", help="no per-generation progress")
    p.add_argument("--no-artifacts", action="store_true", help="skip the pictures (filmstrip, GIF, curve) and report.html")
    add_arguments(p)
    _add_robust_arguments(p)                                # --robust-starts K, --perturb ...


def _text_param(task: str, key: str) -> bool:
    """A parameter whose default is text (``after``: a comma-separated list of
    files) takes a comma list as its one value, never as a series."""
    from ..task import task_class
    try:
        return isinstance(task_class(task).params.get(key), str)
    except ValueError:                 # an unknown task: reported where the run is built
        return False


def _run_configs(args):
    from ..cli_options import collect
    from ..families import family_class, family_names
    from ..names import unknown
    from ..records import validate_number
    from ..run import RunConfig
    if args.controller not in family_names():
        raise ValueError(unknown("controller", args.controller, family_names()))
    params = _params(args.param)
    plugins = _activate_plugins(args)     # before the options: --primitives may name a plugin's
    series = {k: v.split(",") for k, v in params.items() if "," in v and not _text_param(args.task, k)}
    if len(series) > 1:
        raise ValueError("--param: only one parameter may be a comma list (a series)")
    validate_number("--seeds", args.seeds, lo=1, hi=10_000, integer=True)
    _check_out(args.out)
    validate_number("--workers", args.workers, lo=0, hi=10_000_000, integer=True)
    validate_number("--threads", args.threads, lo=1, hi=10_000_000, integer=True, allow_none=True)
    search, fam = collect(args, args.controller)
    robust = _robust_setting(args)
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


def _check_out(out) -> None:
    """--out, when given, names a folder: '' (or blanks) is refused, never the default."""
    if out is not None and not str(out).strip():
        raise ValueError(f"--out must name a folder, got {out!r}")


def _figure_variant(task_name, path):
    """The variant's spec, resolved (``extends`` merged), as plain data: stored in the
    run's parameters, so the run does not depend on the TOML file staying put."""
    from ..figures import figure_names, load_spec, resolve_spec
    if Path(path).is_file():
        return resolve_spec(load_spec(path))
    if path in figure_names():                       # a registered figure, e.g. herman_standing
        return resolve_spec({"extends": path})
    from ..names import did_you_mean
    raise ValueError(f"--figure: no such file or figure {path!r}{did_you_mean(path, figure_names())}")


def _out_dir(args, seed, key, value) -> Path:
    """--out as given for one run; a folder per seed / series value otherwise."""
    if args.out:
        p = Path(args.out)
        p = p / f"{key}={value}" if key else p
        return p / f"seed{seed}" if args.seeds > 1 else p
    preset = f"-{args.preset}" if args.preset else ""     # a preset's run beside the default's
    p = Path("runs") / f"{args.task}-{args.controller}{preset}-seed{seed}"
    return p / f"{key}={value}" if key else p


def cmd_run(args):
    from ..run import build, run
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

    from ..records import read_json
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
    from ..records import read_json
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
    from ..run import run
    refuse_series(Path(args.run_dir), "resume")
    _activate_plugins(args)
    backend = _backend(args)
    if args.workers is not None or args.scheduler is not None:
        backend.update(workers=args.workers or 0, scheduler=args.scheduler)
    _, _, rd = run(None, args.run_dir, resume=True, quiet=args.quiet, backend=backend,
                   extend_generations=args.extend_generations)
    _summary(rd)


def refuse_series(path: Path, verb: str):
    """A series folder (--seeds K, --param k=a,b) holds runs, not a config or a
    best.json: name them, each with the command ``verb`` (resume, replay...)."""
    if (path / "config.json").exists() or (path / "best.json").exists() or not path.is_dir():
        return
    runs = sorted(str(c.parent) for c in path.glob("**/config.json"))
    if runs:
        more = f" (and {len(runs) - 3} more)" if len(runs) > 3 else ""
        raise ValueError(f"{path} is a series of {len(runs)} runs; {verb} each: "
                         + ", ".join(f"gpmotion {verb} {r}" for r in runs[:3]) + more)


def _add_robust_arguments(p) -> None:
    """``gpmotion run``'s robust-start options (an argument group)."""
    from ..robust import SIZE_KEYS
    g = p.add_argument_group("robust controllers (Auslander et al. §3: perturbed starts)")
    g.add_argument("--robust-starts", type=int, metavar="K",
                   help="score every controller from K randomly perturbed starts (joint angles, "
                        "position, orientation, linear and angular momentum), redrawn every "
                        "generation from the run's seed (default: off, the nominal start)")
    g.add_argument("--robust-aggregate", metavar="mean|worst|qNN",
                   help="fold the K costs into one: mean (default), worst, or qNN, the NN-th "
                        "percentile start's (q80: what 80 %% of the starts do at least as well as)")
    g.add_argument("--robust-confirm", type=int, metavar="M",
                   help="a controller that succeeds from its K starts is run from M more, and "
                        "scored and judged over all K + M (default 0: off)")
    g.add_argument("--robust-require", type=float, metavar="F",
                   help="success = succeeds from at least this fraction of its starts "
                        "(default 1: every one)")
    g.add_argument("--perturb", metavar="PART=SIGMA,...",
                   help="perturbation sizes (σ) overriding the figure's defaults: "
                        + ", ".join(SIZE_KEYS) + " (rad, m, rad, m/s, rad/s); "
                        "defaults per figure in docs/howto/composite.md")


def _robust_setting(args) -> dict:
    """The ``robust`` entry of a RunConfig from parsed ``gpmotion run`` options (only what
    was given; :func:`normalize` fills in the rest once the task is known)."""
    from ..robust import SIZE_KEYS
    from ..records import ConfigError, validate_number
    out = {}
    if getattr(args, "robust_starts", None) is not None:
        out["starts"] = args.robust_starts
    if getattr(args, "robust_aggregate", None) is not None:
        out["aggregate"] = args.robust_aggregate
    for key in ("confirm", "require"):
        if getattr(args, f"robust_{key}", None) is not None:
            out[key] = getattr(args, f"robust_{key}")
    text = getattr(args, "perturb", None)
    if text is not None:
        for part in text.split(","):
            k, eq, v = part.partition("=")
            k = k.strip()
            if not eq or k not in SIZE_KEYS:
                raise ConfigError(f"--perturb expects PART=SIGMA with PART one of "
                                  f"{', '.join(SIZE_KEYS)}, got {part.strip()!r}")
            out[k] = float(validate_number(f"--perturb {k}", v.strip(), lo=0, hi=10.0))
    if out and "starts" not in out:
        raise ConfigError("--robust-aggregate / --robust-confirm / --robust-require / --perturb "
                          "need --robust-starts K")
    return out
