"""The run loop: search ⇄ evaluator, with a log row and an atomic checkpoint
after every generation, so a killed run resumes to exactly the same result.
"""
from __future__ import annotations

import platform
import signal
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import __version__
from .evaluate import Evaluation, spec_of
from .families import make_family
from .records import RunDir, validate_number
from .search.adapters import make_search
from .task import Task, get_task


@dataclass
class RunConfig:
    """Everything that fixes a run (written to config.json)."""
    task: str
    family: str = "gp"
    seed: int = 0
    params: dict = field(default_factory=dict)          # task parameters
    family_options: dict = field(default_factory=dict)  # rules, t_per, primitives...
    search: dict = field(default_factory=dict)          # population, generations...
    actuation: str | None = None
    workers: int = 0
    scheduler: str | None = None
    threads: int | None = None
    plugins: list = field(default_factory=list)

    def to_json(self) -> dict:
        return dict(task=self.task, family=self.family, seed=self.seed, params=self.params,
                    family_options=self.family_options, search=self.search,
                    actuation=self.actuation, workers=self.workers, scheduler=self.scheduler,
                    threads=self.threads, plugins=self.plugins)

    @classmethod
    def from_json(cls, d: dict) -> "RunConfig":
        keys = cls.__dataclass_fields__
        if not isinstance(d, dict):
            raise ValueError("config.json: no 'run' settings" if d is None else
                             f"config.json: 'run' must be an object, got {type(d).__name__}")
        missing = [k for k in ("task", "family", "seed") if k not in d]
        if missing:
            raise ValueError(f"config.json lacks {missing}")
        for k, types in _FIELD_TYPES.items():     # a hand-edited file: one line, not a TypeError
            if k in d and not (isinstance(d[k], types) and not isinstance(d[k], bool) or
                               d[k] is None and k in _OPTIONAL):
                raise ValueError(f"config.json: run.{k} must be {types[0].__name__}, "
                                 f"got {type(d[k]).__name__}")
        return cls(**{k: d[k] for k in keys if k in d})


_FIELD_TYPES = {"task": (str,), "family": (str,), "seed": (int,), "params": (dict,),
                "family_options": (dict,), "search": (dict,), "actuation": (str,), "workers": (int,),
                "scheduler": (str,), "threads": (int,), "plugins": (list,)}
_OPTIONAL = {"actuation", "scheduler", "threads", "plugins"}


def build(cfg: RunConfig):
    """Task, family and search (not yet the evaluator) from a config."""
    validate_number("--seed", cfg.seed, lo=0, integer=True)
    from .plugins import require          # records to check, never folders to import
    cfg.plugins = require(cfg.plugins, "the run's plugins (config.json)")
    try:
        task = get_task(cfg.task, **cfg.params)
        family = make_family(cfg.family, task, **cfg.family_options)
        search = make_search(family, cfg.seed, **cfg.search)
    except TypeError as e:               # a hand-edited config.json: a value of the wrong type
        raise ValueError(f"bad run settings ({e})") from None
    actuation = cfg.actuation or family.default_actuation
    return task, family, search, actuation


def _evaluator(cfg, task, family, actuation, backend=None):
    from .evaluators import make_evaluator
    return make_evaluator(task, family, workers=cfg.workers, scheduler=cfg.scheduler,
                          actuation=actuation, threads=cfg.threads, plugins=cfg.plugins,
                          **(backend or {}))


class Progress:
    """Per-generation progress on stderr: one rewritten line on a terminal,
    plain lines otherwise (logs, CI)."""

    def __init__(self, total: int, quiet: bool = False):
        self.total, self.quiet, self.t0 = total, quiet, time.perf_counter()
        self.evals = 0
        self.tty = sys.stderr.isatty()

    def update(self, gen: int, ev: Evaluation, best: float):
        self.evals += len(ev.costs)
        if self.quiet:
            return
        el = time.perf_counter() - self.t0
        rate = self.evals / el if el > 0 else 0.0
        eta = el / max(gen, 1) * (self.total - gen)
        line = (f"gen {gen:>4}/{self.total}  best {best:.4f}  median {np.median(ev.costs):.4f}  "
                f"solved {int(ev.success.sum())}/{len(ev.costs)}  failed {int(ev.failed.sum())}  "
                f"{rate:,.0f} evals/s  eta {eta:,.0f}s")
        if self.tty:
            end = "\n" if gen >= self.total else ""
            print("\r" + line + "\033[K", end=end, file=sys.stderr, flush=True)
        else:
            print(line, file=sys.stderr, flush=True)


def _log_row(search, ev: Evaluation, evals_total: int, elapsed: float) -> dict:
    row = search.row(ev)
    return {"generation": row.pop("generation"), "evaluations": evals_total, **row,
            "evals_per_s": round(evals_total / elapsed, 1) if elapsed > 0 else "",
            "elapsed_s": round(elapsed, 3)}


def _trim_log(run: RunDir, evaluations: int):
    """On resume, drop log rows written after the checkpoint was taken
    (rows count evaluations, which only grow)."""
    rows = run.read_log()
    keep = [r for r in rows if int(r["evaluations"]) <= evaluations]
    if len(keep) != len(rows) or (run.log_path.exists() and not rows):
        from .records import atomic_write_text
        import csv
        import io
        buf = io.StringIO()
        if rows:
            w = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
            w.writeheader()
            w.writerows(keep)
        atomic_write_text(run.log_path, buf.getvalue())


def run(cfg: RunConfig | None, out: str | Path | None = None, *, force: bool = False,
        resume: bool = False, quiet: bool = False, artifacts: bool = True,
        max_generations: int | None = None, backend: dict | None = None):
    """Run (or resume) a search into ``out``; returns (best genome, best cost, run dir).

    ``out`` defaults to ``runs/TASK-FAMILY-seedN`` in the current folder (as `gpmotion run`).
    ``backend``: this invocation's evaluator settings (``workers``, ``scheduler``,
    ``security``...); on resume ``workers``/``scheduler`` replace the recorded
    ones -- every backend gives the same result.
    """
    if out is None:
        if cfg is None:
            raise ValueError("resume: give the run directory")
        out = Path("runs") / f"{cfg.task}-{cfg.family}-seed{cfg.seed}"
    backend = dict(backend or {})
    if resume:
        if not (Path(out) / RunDir.CONFIG).exists():
            raise ValueError(f"{out}: no config.json to resume from")
        rd = RunDir.create(out, resume=True)
        cfg = RunConfig.from_json(rd.read_config().get("run"))
        if "workers" in backend or "scheduler" in backend:
            cfg.workers, cfg.scheduler = backend.pop("workers", 0), backend.pop("scheduler", None)
        task, family, search, actuation = build(cfg)
        evaluator = None                                    # made once the checkpoint is read
    else:       # validate everything (the scheduler too) before touching the disk
        task, family, search, actuation = build(cfg)
        evaluator = _evaluator(cfg, task, family, actuation, backend)
        try:
            rd = RunDir.create(out, force=force)
        except BaseException:
            evaluator.close()
            raise
        from .plugins import for_record
        cfg.plugins = for_record(cfg.plugins, rd.path)      # path relative to the run: information
    evals = 0
    elapsed0 = 0.0
    if resume and rd.checkpoint_path.exists():
        ck = rd.load_checkpoint()
        try:
            search.load_state_dict(ck["search"])
            evals, elapsed0 = int(ck["evaluations"]), float(ck.get("elapsed_s", 0.0))
            if evals > 0 and search.best is None:
                raise ValueError("no best genome after evaluations")
        except (KeyError, TypeError, ValueError, IndexError, AttributeError, OverflowError) as e:
            from .records import FormatError
            raise FormatError(f"{rd.checkpoint_path}: not a valid checkpoint ({e!r:.200})") from None
        _trim_log(rd, evals)
    elif not resume:
        rd.write_config({"run": cfg.to_json(), "task_config": task.config(),
                         "family_config": family.config(), "actuation": actuation,
                         "versions": _versions(), "spec": spec_of(task, family, actuation, cfg.plugins)})
    if not quiet:
        print(f"{'resume' if resume else 'run'} {cfg.task} ({cfg.family}, seed {cfg.seed}"
              f"{', ' + str(cfg.params) if cfg.params else ''}) → {rd.path}", file=sys.stderr)
    if evaluator is None:
        evaluator = _evaluator(cfg, task, family, actuation, backend)
    prog = Progress(search.total, quiet)
    t0 = time.perf_counter() - elapsed0
    stop = {"flag": False}

    def on_sigint(signum, frame):            # finish this generation, checkpoint, exit
        if stop["flag"]:
            raise KeyboardInterrupt
        stop["flag"] = True
        print("\ninterrupt: finishing this generation and checkpointing (Ctrl-C again to abort)",
              file=sys.stderr)

    old = signal.signal(signal.SIGINT, on_sigint) if _main_thread() else None
    done_now = 0
    try:
        while not search.done and not stop["flag"]:
            if max_generations is not None and done_now >= max_generations:
                break
            genomes = search.ask()
            ev = evaluator.evaluate(genomes, search.progress)
            search.tell(ev)
            evals += len(genomes)
            done_now += 1
            el = time.perf_counter() - t0
            rd.log_row(_log_row(search, ev, evals, el))
            rd.save_checkpoint({"search": search.state_dict(), "evaluations": evals,
                                "elapsed_s": el})
            prog.update(search.generation, ev, search.best_cost)
    except RuntimeError as e:                 # WorkerLost, SchedulerLost: name the run to resume
        if type(e).__name__ in ("WorkerLost", "SchedulerLost"):
            raise type(e)(f"{e}; the checkpoint is intact: `gpmotion resume {rd.path}` "
                          "continues") from None
        raise
    finally:
        if old is not None:
            signal.signal(signal.SIGINT, old)
        evaluator.close()
    if stop["flag"]:
        raise KeyboardInterrupt(f"checkpoint saved after generation {search.generation}; "
                                f"`gpmotion resume {rd.path}` continues")
    if search.done:
        from .replay import replay_genome
        replay = replay_genome(task, family, actuation, search.best)   # once, for both
        write_best(rd, cfg, task, family, actuation, search, replay)
        if artifacts:
            write_artifacts(rd, task, family, search.best, replay[0])
    return search.best, search.best_cost, rd


def _main_thread():
    import threading
    return threading.current_thread() is threading.main_thread()


def _versions():
    import deap
    import numba
    return {"gpmotion": __version__, "python": platform.python_version(), "numpy": np.__version__,
            "numba": numba.__version__, "deap": deap.__version__}


def controller_record(cfg: RunConfig, task: Task, family, actuation, genome, cost) -> dict:
    """The safe-JSON controller file (best.json, or a user's controller)."""
    return {"task": task.name, "params": dict(task.p), "family": family.name,
            "options": dict(family.options), "actuation": actuation, "plugins": list(cfg.plugins),
            "genome": family.to_json(genome), "cost": float(cost), "seed": cfg.seed}


def write_best(rd: RunDir, cfg, task, family, actuation, search, replay):
    """best.json from the search's best and its replay (traj, costs, measures, ok)."""
    rec = controller_record(cfg, task, family, actuation, search.best, search.best_cost)
    traj, costs, measures, ok = replay
    rec["terms"] = task.breakdown(measures, 0, 1.0)
    rec["final_cost"] = float(costs[0])
    rec["success"] = bool(ok[0])
    rec["facts"] = task.describe(traj, measures)
    rd.write_best(rec)


def write_artifacts(rd: RunDir, task, family, genome, traj):
    from . import render
    render_trajectory(traj, rd.artifact("filmstrip.png"), rd.artifact("motion.gif"),
                      title=f"{task.name} ({family.name})", task=task)
    if family.name == "gp":
        plot_gp_trees(rd.artifact("trees.png"), task, family, genome)
    rows = rd.read_log()
    if rows:
        render.run_curve(rd.artifact("curve.png"), rows, task, title=f"{task.name} ({family.name})")


def plot_gp_trees(path, task, family, genome):
    from .treeplot import plot_trees
    names = [task.fig.actuator_names[i] for i in family.actuators]
    plot_trees(path, family.to_json(genome)["trees"], titles=names, suptitle=f"{task.name} (gp)")


def render_trajectory(traj, filmstrip=None, gif=None, title=None, e: int = 0, task=None):
    """Filmstrip PNG and/or GIF of one episode, planar or 3-D (with the task's view)."""
    from .render3d import render_any
    render_any(traj, filmstrip, gif, title=title, e=e, task=task)
