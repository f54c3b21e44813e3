"""The run loop: search ⇄ evaluator, with log rows and an atomic checkpoint,
so a run killed at any instant resumes to exactly the same result.

Records stay consistent at every instant: log rows are buffered and appended
(one write, one fsync) just before each checkpoint, and a resume trims the
log to the rows the checkpoint counts (to none when no checkpoint exists
yet).  A checkpoint is taken every ``checkpoint_every`` seconds (default 10;
env ``GPMOTION_CHECKPOINT_EVERY``), at the end, on Ctrl-C and on SIGTERM, and
carries the run's identity (run id + config.json's digest), so a checkpoint,
a config and a log from different runs are never mixed.
"""
from __future__ import annotations

import contextlib
import os
import platform
import signal
import sys
import time
from pathlib import Path

import numpy as np

from .inprocess import spec_of
from .progress import LEGACY_RATE_COLUMN, CompileNote, Progress, rate_cell
from .bsr.genome import MAX_RULES
from .version import __version__
from .families import make_family, recorded_options
from .records import ConfigError, FormatError, validate_number
from .rundir import RunDir
from .runconfig import (RunConfig, check_resume_request, config_digest, new_run_id,
                        settings_mismatch)
from .task import Task, get_task, task_id

__all__ = ["RunConfig", "build", "run", "controller_record", "write_best", "Stopped"]

CHECKPOINT_EVERY_S = 10.0


class Stopped(KeyboardInterrupt):
    """Ctrl-C / SIGTERM: the run checkpointed and stopped (``code``: exit status)."""

    def __init__(self, msg: str, code: int = 130):
        super().__init__(msg)
        self.code = code


def build(cfg: RunConfig):
    """Task, family and search (not yet the evaluator) from a config."""
    validate_number("--seed", cfg.seed, lo=0, integer=True)
    validate_number("--rules", cfg.family_options.get("rules"), lo=1, hi=MAX_RULES,
                    integer=True, allow_none=True)        # memory: rules × senses per genome
    from .plugins import require          # records to check, never folders to import
    cfg.plugins = require(cfg.plugins, "the run's plugins (config.json)")
    try:
        task = get_task(cfg.task, **cfg.params)
        family = make_family(cfg.family, task, **cfg.family_options)
        from .robust import normalize
        cfg.robust = normalize(cfg.robust, task)     # the figure's default sizes filled in
        noisy = family.noisy_settings() if cfg.robust else {}   # new starts each generation
        given = {k: v for k, v in cfg.search.items() if v is not None}
        search = family.make_search(cfg.seed, **{**noisy, **given})
    except TypeError as e:           # an option the constructor does not take
        raise ConfigError(f"{cfg.task} ({cfg.family}): {e}") from None
    actuation = cfg.actuation or family.default_actuation
    return task, family, search, actuation


def _evaluator(cfg, task, family, actuation, backend=None):
    from .evaluators import make_evaluator
    robust = {**cfg.robust, "seed": cfg.seed} if cfg.robust else None   # starts: (seed, generation)
    return make_evaluator(task, family, workers=cfg.workers, scheduler=cfg.scheduler,
                          actuation=actuation, threads=cfg.threads, plugins=cfg.plugins,
                          robust=robust, **(backend or {}))


# ------------------------------------------------------------------ progress

def _shown(params: dict) -> dict:
    """Task parameters as the banner shows them: a figure variant (a whole
    spec) by its name."""
    fig = params.get("figure")
    if isinstance(fig, dict):
        return {**params, "figure": f"{fig.get('name', 'variant')} (variant)"}
    return params


def banner(cfg: RunConfig, task: Task, family, search, actuation: str, rd: RunDir,
           verb: str) -> str:
    """What the run is: task, family, seed, actuation, and the style-term schedule."""
    head = (f"{verb} {cfg.task} ({cfg.family}, seed {cfg.seed}"
            f"{', ' + str(_shown(cfg.params)) if cfg.params else ''}) → {rd.path}")
    own = "" if cfg.actuation else f", {family.name}'s default"
    note = family.banner_note()
    act = (f"  actuation: {actuation}{own}{' · ' + note if note else ''} · "
           f"generations 0–{search.last_generation:,}")
    return "\n".join([head, act, "  " + phase_line(task, search)])


def phase_line(task: Task, search) -> str:
    """The style-term phase-in schedule in generations, one short line."""
    sched = search.progress_span                         # progress ≈ generation / sched
    phased = [t for t in task.terms if t.phase[1] > t.phase[0]]
    parts = [f"{t.name} {round(t.phase[0] * sched)}→{round(t.phase[1] * sched)}" for t in phased]
    parts += [f"{k} from {e.start:g} {round(e.phase[0] * sched)}→{round(e.phase[1] * sched)}"
              for k, e in task.curriculum.items()]
    if not parts:
        return "style terms: all at full weight from the first generation"
    return "style terms phase in over generations: " + ", ".join(parts)


# ------------------------------------------------------------------ the loop

def _log_row(search, evals_total: int, elapsed: float, rate: float,
             legacy_rate: bool = False) -> dict:
    row = search.row()
    return {"generation": row.pop("generation"), "evaluations": evals_total, **row,
            **rate_cell(rate, evals_total, elapsed, legacy_rate), "elapsed_s": round(elapsed, 3)}


def _checkpoint_every(value) -> float:
    if value is None:
        value = os.environ.get("GPMOTION_CHECKPOINT_EVERY", CHECKPOINT_EVERY_S)
    return float(validate_number("GPMOTION_CHECKPOINT_EVERY", value, lo=0, hi=86400))


class _Recorder:
    """Buffers log rows; a flush appends them, then replaces the checkpoint."""

    def __init__(self, rd: RunDir, identity: dict, n_rows: int, evals: int, every: float):
        self.rd, self.identity, self.every = rd, identity, every
        self.n_rows, self.evals = n_rows, evals
        self.rows: list[dict] = []
        self.gens: list[dict] = []         # generations.jsonl records, flushed with the rows
        self.film = None                   # a GenerationRecorder
        self.legacy_rate = False           # the log's header has the old evals_per_s column
        self.last = time.monotonic()

    def add(self, row: dict):
        self.rows.append(row)
        self.evals = row["evaluations"]

    def note(self, search, genomes, ev):
        made = self.film.record(search, genomes, ev, self.evals) if self.film else None
        if made:
            self.gens.append(made)

    def due(self) -> bool:
        return time.monotonic() - self.last >= self.every

    def flush(self, search, elapsed: float):
        rows, self.rows = self.rows, []    # never appended twice, even if interrupted here
        gens, self.gens = self.gens, []
        self.rd.append_generations(gens)   # before the checkpoint: a resume trims extras
        self.rd.log_rows(rows)             # before the checkpoint: a resume trims extras
        self.n_rows += len(rows)
        self.rd.save_checkpoint({**self.identity, "search": search.state_dict(),
                                 "evaluations": self.evals, "log_rows": self.n_rows,
                                 "elapsed_s": elapsed})
        self.last = time.monotonic()


class RunResult(tuple):
    """run's (best genome, best cost, run directory); Jupyter shows the run's report."""
    __slots__ = ()

    def _repr_html_(self) -> str:
        from .report import folder_html
        return folder_html(self[2].path)


def run(cfg: RunConfig | None, out: str | Path | None = None, *, force: bool = False,
        resume: bool = False, quiet: bool = False, artifacts: bool = True,
        max_generations: int | None = None, extend_generations: int | None = None,
        checkpoint_every: float | None = None, backend: dict | None = None):
    """Run (or resume) a search into ``out``; returns (best genome, best cost, run dir).

    ``out`` defaults to ``runs/TASK-FAMILY-seedN`` in the current folder (as `gpmotion run`).
    ``backend``: this invocation's evaluator settings (``workers``, ``scheduler``,
    ``security``...); on resume ``workers``/``scheduler`` replace the recorded
    ones -- every backend gives the same result.  On resume ``cfg`` may carry
    the command line's request: it must agree with the recorded run (one-line
    error otherwise); only its backend (workers, scheduler, threads) is taken.
    ``extend_generations`` adds generations to a run (finished or not); they
    run at the final weights.
    """
    if out is None:
        if cfg is None:
            raise ValueError("resume: give the run directory")
        out = Path("runs") / f"{cfg.task}-{cfg.family}-seed{cfg.seed}"
    every = _checkpoint_every(checkpoint_every)
    backend = dict(backend or {})
    given, evaluator, rd = cfg, None, None
    notes = contextlib.ExitStack()        # the cold-compile note, also while workers warm up
    if not resume and extend_generations is not None:
        raise ConfigError("--extend-generations continues an existing run: use resume")
    try:
        if resume:
            rd, cfg, doc = _open_resume(out)
            cfg.task = task_id(cfg.task, recorded=True)      # bare: recorded before ids, its v1
            cfg.family_options = recorded_options(cfg.family, doc.get("family_config"),
                                                  cfg.family_options)
            if given is not None and given.task in (cfg.task, cfg.task.rsplit("-v", 1)[0]):
                given.task = cfg.task                        # the bare name of the recorded task
            _keep_legacy_noisy(rd, cfg)
            task, family, search, actuation = build(cfg)
            if given is not None:
                check_resume_request(given, cfg, doc, search, rd.path)
                cfg.workers, cfg.scheduler, cfg.threads = (given.workers, given.scheduler,
                                                           given.threads)
            if "workers" in backend or "scheduler" in backend:
                cfg.workers, cfg.scheduler = backend.pop("workers", 0), backend.pop("scheduler", None)
            if extend_generations is not None:
                validate_number("--extend-generations", extend_generations, lo=1,
                                hi=10_000_000, integer=True)
            rec = _restore(rd, doc, search)          # everything checked, nothing changed
            notes.enter_context(_compile_note(task, family, quiet))
            evaluator = _evaluator(cfg, task, family, actuation, backend)
            rd.trim_log(rec.trim)                    # now the changes
            if extend_generations is not None:
                doc = _record_extension(rd, doc, search.schedule, extend_generations)
                search.extend(doc["extended_generations"], search.schedule)
        else:       # validate everything (the scheduler too) before touching the disk
            task, family, search, actuation = build(cfg)
            cfg.task = task.id                                # records store the versioned id
            notes.enter_context(_compile_note(task, family, quiet))
            evaluator = _evaluator(cfg, task, family, actuation, backend)
            rd = RunDir.create(out, force=force)
            from .plugins import for_record
            cfg.plugins = for_record(cfg.plugins, rd.path)  # path relative to the run: information
            doc = _write_config(rd, cfg, task, family, actuation)
            rec = _Recorder(rd, _identity(doc), 0, 0, every)
        rec.every = every
        rec.film = _film_recorder(rd, family, task, search, resume)
        if not quiet:
            verb = "resume" if resume else "run"
            print(banner(cfg, task, family, search, actuation, rd, verb), file=sys.stderr)
        if evaluator is None:
            evaluator = _evaluator(cfg, task, family, actuation, backend)
        _loop(evaluator, search, rec, quiet, max_generations)
        if search.done:
            _finish(rd, cfg, task, family, actuation, search, artifacts)
    finally:
        notes.close()
        try:
            if evaluator is not None:
                evaluator.close()
        finally:
            if rd is not None:
                rd.close()
    return RunResult((search.best, search.best_cost, rd))


def _compile_note(task, family, quiet: bool):
    """A note on stderr before kernels compile cold, here or in the workers
    (minutes, once per machine); timed per figure and family."""
    from .cache import on_cold_compile
    if quiet:
        return contextlib.nullcontext()
    return on_cold_compile(CompileNote(task.figure.name, f"{task.figure.name} {family.name}"))


def _keep_legacy_noisy(rd: RunDir, cfg) -> None:
    """A robust run checkpointed before ``fresh_scores`` existed resumes
    as it began: without them (its checkpoint's search settings name none)."""
    if not cfg.robust or "fresh_scores" in cfg.search or not rd.has_checkpoint():
        return
    try:
        settings = rd.load_checkpoint()["search"]["config"]
    except (KeyError, TypeError, ValueError, OSError):
        return                         # a bad checkpoint: _restore says what is wrong
    if isinstance(settings, dict) and "fresh_scores" not in settings:
        cfg.search = {**cfg.search, "fresh_scores": False}


def _film_recorder(rd: RunDir, family, task, search, resume: bool):
    """generations.jsonl's recorder; a resume trims the file to its checkpoint
    and goes on from the last record kept (gpmotion.generations)."""
    from .generations import GenerationRecorder
    kept = []
    if resume:
        kept = rd.trim_generations(search.logged_generation() if rd.has_checkpoint() else -1)
    return GenerationRecorder(family, task, kept[-1] if kept else None)


def _identity(doc: dict) -> dict:
    return {"run_id": doc["run_id"], "config_digest": config_digest(doc)}


def _write_config(rd: RunDir, cfg, task, family, actuation) -> dict:
    rd.write_config({"run_id": new_run_id(), "run": cfg.to_json(), "task_config": task.config(),
                     "family_config": family.config(), "actuation": actuation,
                     "versions": _versions(),
                     "spec": spec_of(task, family, actuation, cfg.plugins)})
    return rd.read_config()           # digest what is on disk


CONFIG_KEYS = {"format", "version", "run_id", "run", "task_config", "family_config",
               "actuation", "versions", "spec", "extended_generations"}


def _check_tables(doc: dict, path) -> None:
    """config.json's recorded task and family settings are tables (or absent):
    a resume merges them, and a list or a number there must be a clear error."""
    unknown = sorted(set(doc) - CONFIG_KEYS)
    if unknown:
        raise ConfigError(f"{path}: unknown key(s) {unknown}; not a config this gpmotion wrote")
    for key in ("task_config", "family_config"):
        if doc.get(key) is not None and not isinstance(doc[key], dict):
            raise ConfigError(f"{path}: '{key}' must be a table, got {type(doc[key]).__name__}")
    params = (doc.get("task_config") or {}).get("params")
    if params is not None and not isinstance(params, dict):
        raise ConfigError(f"{path}: 'task_config.params' must be a table, got {type(params).__name__}")


def _open_resume(out):
    """Lock the run and read its config (checked field by field)."""
    path = Path(out)
    if not (path / RunDir.CONFIG).exists():
        runs = sorted(p.parent for p in path.glob("*/**/config.json")) if path.is_dir() else []
        if runs:
            shown = " ".join(str(p) for p in runs[:4]) + (" …" if len(runs) > 4 else "")
            raise ConfigError(f"{out} is a folder of {len(runs)} runs (a series), not one run; "
                              f"resume each: {shown}")
        raise ConfigError(f"{out}: no config.json to resume from")
    rd = RunDir.create(out, resume=True)
    try:
        doc = rd.read_config()
        _check_tables(doc, rd.path / RunDir.CONFIG)
        cfg = RunConfig.from_json(doc.get("run"), f"{rd.path / RunDir.CONFIG}")
    except BaseException:
        rd.close()
        raise
    return rd, cfg, doc


def _record_extension(rd: RunDir, doc: dict, configured: int, extra: int) -> dict:
    """config.json records the new total (outside the digest): a kill later still
    resumes to it, and the checkpoint stays bound to the same config."""
    extra = validate_number("--extend-generations", extra, lo=1, hi=10_000_000, integer=True)
    now = doc.get("extended_generations", configured)
    now = validate_number(f"{rd.path / RunDir.CONFIG}: extended_generations", now,
                          lo=configured, hi=10**9, integer=True)
    doc = {k: v for k, v in doc.items() if k not in ("format", "version")}
    doc["extended_generations"] = int(now) + int(extra)
    rd.write_config(doc)
    return rd.read_config()


CHECKPOINT_KEYS = {"format", "version", "run_id", "config_digest", "search", "evaluations",
                   "log_rows", "elapsed_s"}


def _restore(rd: RunDir, doc: dict, search) -> _Recorder:
    """Bring the search to the checkpoint (checked against this run) and check the
    log's first rows end at it; none yet: the run starts again.  Changes no file:
    the caller trims the log (``rec.trim``) once everything is checked."""
    ident = _identity(_checked_identity(doc, rd))
    original = search.total
    total = doc.get("extended_generations")
    if total is not None:
        total = int(validate_number("extended_generations", total, lo=original, integer=True,
                                    hi=10**9))
    if not rd.has_checkpoint():
        if rd.exists(RunDir.BEST):          # finished: never silently started again
            raise FormatError(f"{rd.checkpoint_path}: missing, but the run finished (best.json); "
                              "refusing to start it again — `gpmotion run --force` starts a "
                              "new run and moves this one aside")
        rd.read_log()                       # readable (a regular file), not yet trimmed
        search.extend(total or original, original)
        rec = _Recorder(rd, ident, 0, 0, CHECKPOINT_EVERY_S)
        rec.trim = 0
        return rec
    ck = rd.load_checkpoint()
    where = str(rd.checkpoint_path)
    unknown = sorted(set(ck) - CHECKPOINT_KEYS)
    if unknown:
        raise FormatError(f"{where}: unknown key(s) {unknown}; not a checkpoint this "
                          "gpmotion wrote — refusing it")
    for k in ("run_id", "config_digest"):
        if ck.get(k) != ident[k]:
            what = "another run" if k == "run_id" else "a different config.json (edited?)"
            raise FormatError(f"{where}: belongs to {what}: its {k} {_short(ck.get(k))} ≠ "
                              f"{_short(ident[k])}; refusing to mix records")
    evals = validate_number(f"{where}: evaluations", ck.get("evaluations"), lo=0, hi=10**12,
                            integer=True)
    n_rows = validate_number(f"{where}: log_rows", ck.get("log_rows"), lo=0, hi=10**9,
                             integer=True)
    elapsed = validate_number(f"{where}: elapsed_s", ck.get("elapsed_s", 0.0), lo=0, hi=1e9)
    state = ck.get("search")
    cfg_ck = state.get("config") if isinstance(state, dict) else None
    bad = settings_mismatch(search.config(), cfg_ck, search.total_key,
                            {original, total or original})
    if bad:
        raise FormatError(f"{where}: search settings differ from config.json ({bad}); "
                          "config.json is authoritative — refusing the checkpoint")
    try:
        search.load_state_dict(state)
    except (KeyError, TypeError, ValueError, IndexError, AttributeError, OverflowError) as e:
        raise FormatError(f"{where}: not a valid checkpoint ({e!r:.200})") from None
    _check_state(search, evals, where)
    search.extend(total or original, original)
    rows = rd.log_prefix(n_rows)                     # checked; trimmed only after every check
    last = search.logged_generation()
    if (evals > 0) != (n_rows > 0) or (rows and (rows[-1].get("evaluations") != str(evals)
                                                 or rows[-1].get("generation") != str(last))):
        raise FormatError(f"{where}: log_rows {n_rows} does not match {rd.log_path} (its row "
                          f"{n_rows} must end at generation {last}, {evals} evaluations); "
                          "refusing to mix records")
    rd.read_generations()                            # the film's records parse, too
    rec = _Recorder(rd, ident, n_rows, evals, CHECKPOINT_EVERY_S)
    rec.elapsed0 = float(elapsed)
    rec.trim = n_rows
    rec.legacy_rate = bool(rows) and LEGACY_RATE_COLUMN in rows[0]   # keeps its meaning
    return rec


def _check_state(search, evals: int, where: str) -> None:
    """The restored search agrees with the checkpoint's counts and its own settings."""
    if search.evaluations != evals:
        raise FormatError(f"{where}: evaluations {evals} ≠ the search state's "
                          f"{search.evaluations}")
    if search.evaluations > 0 and search.best is None:
        raise FormatError(f"{where}: no best genome after {search.evaluations} evaluations")
    if not 0 <= search.generation <= search.total:
        raise FormatError(f"{where}: generation {search.generation} is outside "
                          f"0..{search.total}")
    try:
        search.check_restored()
    except ValueError as e:
        raise FormatError(f"{where}: {e}") from None


def _checked_identity(doc: dict, rd: RunDir) -> dict:
    rid = doc.get("run_id")
    if not isinstance(rid, str) or not rid:
        raise FormatError(f"{rd.path / RunDir.CONFIG}: no run_id (written by an older gpmotion "
                          "or edited); cannot bind its checkpoint — start a new run")
    return doc


def _short(x) -> str:
    r = repr(x)
    return r if len(r) <= 24 else r[:21] + "..."


def _loop(evaluator, search, rec: _Recorder, quiet, max_generations):
    """ask → evaluate → tell → log row; checkpoint when due, at the end, on a signal."""
    prog = Progress(search.last_generation, quiet)
    t0 = time.perf_counter() - getattr(rec, "elapsed0", 0.0)
    stop = {"sig": None}

    def on_signal(signum, frame):            # finish this generation, checkpoint, exit
        if stop["sig"] is not None:
            raise KeyboardInterrupt("aborted; the last checkpoint is kept")
        stop["sig"] = signum
        name = "interrupt" if signum == signal.SIGINT else "terminate"
        print(f"\n{name}: finishing this generation and checkpointing "
              "(send it again to abort)", file=sys.stderr)

    old = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)} \
        if _main_thread() else {}
    done_now, told = 0, True
    try:
        while not search.done and stop["sig"] is None:
            if max_generations is not None and done_now >= max_generations:
                break
            genomes = search.ask()
            ev = evaluator.evaluate(genomes, search.progress, generation=search.generation)
            told = False
            search.tell(ev)
            rate = prog.count(len(genomes))
            row = _log_row(search, rec.evals + len(genomes), time.perf_counter() - t0, rate,
                           rec.legacy_rate)
            rec.add(row)
            rec.note(search, genomes, ev)
            told = True
            done_now += 1
            if search.done or stop["sig"] is not None or rec.due():
                rec.flush(search, time.perf_counter() - t0)
            prog.update(row["generation"], ev, search.best_cost, row, rate)
    except RuntimeError as e:                 # WorkerLost, SchedulerLost: name the run to resume
        if type(e).__name__ in ("WorkerLost", "SchedulerLost"):
            raise type(e)(f"{e}; the checkpoint is intact: `gpmotion resume {rec.rd.current_path}` "
                          "continues") from None
        raise
    finally:
        for s, h in old.items():
            signal.signal(s, h)
        if told and rec.rows:                # an error or a break: keep what was told
            rec.flush(search, time.perf_counter() - t0)
    if stop["sig"] is not None:
        term = stop["sig"] == signal.SIGTERM
        raise Stopped(f"checkpoint saved after generation {search.logged_generation()}; "
                      f"`gpmotion resume {rec.rd.current_path}` continues", 143 if term else 130)


def _finish(rd, cfg, task, family, actuation, search, artifacts):
    from .replay import replay_genome
    replay = replay_genome(task, family, actuation, search.best)   # once, for both
    write_best(rd, cfg, task, family, actuation, search, replay)
    if artifacts:
        write_artifacts(rd, task, family, search.best, replay[0])
        from .report import write_report                      # the interactive report.html
        write_report(rd.path, rd.artifact("report.html"),
                     best=(task, family, actuation, search.best, replay[0]))


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
    return {"task": task.id, "params": dict(task.params), "family": family.name,
            "options": dict(family.options), "actuation": actuation, "plugins": list(cfg.plugins),
            "genome": family.to_json(genome), "cost": float(cost), "seed": cfg.seed}


def write_best(rd: RunDir, cfg, task, family, actuation, search, replay):
    """best.json from the search's best and its replay (traj, costs, measures, ok)."""
    rec = controller_record(cfg, task, family, actuation, search.best, search.best_cost)
    traj, costs, measures, ok = replay
    rec["terms"] = task.breakdown(measures, 0, 1.0)
    rec["final_cost"] = float(costs[0])
    rec["success"] = bool(ok[0])
    rec["diverged"] = bool(traj.diverged[0])     # its final_cost is then the WORST penalty
    rec["facts"] = task.describe(traj, measures)
    rd.write_best(rec)


def write_artifacts(rd: RunDir, task, family, genome, traj):
    from . import render
    render_trajectory(traj, rd.artifact("filmstrip.png"), rd.artifact("motion.gif"),
                      title=f"{task.name} ({family.name})", task=task)
    if family.plot_file:
        family.plot(rd.artifact(family.plot_file), genome)
    rows = rd.read_log()
    if rows:
        render.run_curve(rd.artifact("curve.png"), rows, task, title=f"{task.name} ({family.name})")


def render_trajectory(traj, filmstrip=None, gif=None, title=None, e: int = 0, task=None):
    """Filmstrip PNG and/or GIF of one episode, planar or 3-D (with the task's view)."""
    from .render3d import render_any
    render_any(traj, filmstrip, gif, title=title, e=e, task=task)
