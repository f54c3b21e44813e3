"""Running a study: configurations × seeds × starts (× stages), every search
through the run loop ``gpmotion run`` uses (:func:`gpmotion.run.run`: its
checkpoints, lock and signals), one ledger row per finished search.

Each search has its own run directory ``RUNS/CONFIG-seedS[-startK][-STAGE]``
(RUNS: ``DIR/runs`` unless given), checkpointed by the run loop.  A job is
done when its row is in the ledger; rerunning the same command after a kill
at any instant skips done jobs, resumes cut searches where their checkpoint
stopped and re-finishes searches that ended before their row was written,
so the rows are those of an uninterrupted run (the timing fields aside).

Search seeds: a configuration with ``starts = K`` runs K independent
searches per seed S, with search seeds S·K … S·K + K − 1 (K = 1: seed S);
the table takes the cheapest of them (by cost, as a user would).  A stage
with ``starts = K`` continues from the cheapest of its K searches.
"""
from __future__ import annotations

import csv
import hashlib
import io
import json
import os
import signal
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from ..records import ConfigError
from .spec import Configuration, Spec, SpecError, Stage

CURVE_POINTS = 40


@dataclass
class Job:
    """One ledger row to make (picklable: it travels to a spawned worker)."""
    study: str
    config: Configuration
    seed: int
    start: int
    seed_set: str
    runs: str
    scheduler: str | None = None
    quiet: bool = True

    @property
    def key(self) -> tuple:
        return (self.config.name, self.seed, self.start)

    @property
    def stem(self) -> str:
        k = self.config.starts
        return f"{self.config.name}-seed{self.seed}" + (f"-start{self.start}" if k > 1 else "")

    @property
    def search_seed(self) -> int:
        k = self.config.starts
        return self.seed * k + self.start if k > 1 else self.seed


def jobs(spec: Spec, seeds: list[int], runs: Path, scheduler=None, quiet=True) -> list[Job]:
    """Seed-major: every configuration's first seed before any second seed, so
    a study cut short still has the first seeds of every configuration."""
    return [Job(spec.name, c, s, k, spec.seed_set(s), str(runs), scheduler, quiet)
            for s in seeds for c in spec.configurations.values() for k in range(c.starts)]


# ------------------------------------------------------------------ one search

def run_config(stage: Stage, search_seed: int, after: list[str], scheduler):
    """The RunConfig of one search of ``stage`` (budget → the family's settings,
    the stage's own search settings over them)."""
    from ..families import make_family
    from ..runconfig import RunConfig
    from ..task import get_task
    params = dict(stage.params)
    if after:
        params["after"] = ",".join(after)
    search = {}
    if stage.budget is not None:
        task = get_task(stage.task, **params)
        fam = make_family(stage.family, task, **stage.options)
        search = {k: v for k, v in fam.budget_settings(stage.budget).items() if v is not None}
    search.update(stage.search)
    return RunConfig(task=stage.task, family=stage.family, seed=search_seed, params=params,
                     family_options=dict(stage.options), search=search,
                     actuation=stage.actuation, threads=1, scheduler=scheduler,
                     robust=dict(stage.robust))


def search_once(stage: Stage, search_seed: int, run_dir: Path, after: list[str],
                scheduler=None, quiet=True) -> dict:
    """One search (resumed if its run directory holds one) and its best, replayed."""
    from ..families import make_family
    from ..records import read_json
    from ..replay import replay_genome
    from ..run import run
    from ..task import get_task
    cfg = run_config(stage, search_seed, after, scheduler)
    resumed = (run_dir / "config.json").exists()
    c0 = time.process_time()
    # a run killed before its config.json was whole is no run yet: begun again, anything
    # more than the lock and a killed write's temp file moved aside first
    from ..rundir import RunDir
    begun = run_dir.is_dir() and not resumed and bool(RunDir(run_dir).names())
    run(cfg, run_dir, resume=resumed, force=begun, quiet=quiet, artifacts=False)
    cpu = time.process_time() - c0
    best = read_json(run_dir / "best.json", kind="best")
    log = list(csv.DictReader(io.StringIO((run_dir / "log.csv").read_text())))
    task = get_task(best["task"], **best["params"])
    fam = make_family(best["family"], task, **best["options"])
    replay = replay_genome(task, fam, best["actuation"], fam.from_json(best["genome"]))
    return {"best": best, "task": task, "family": fam, "replay": replay,
            "evaluations": int(log[-1]["evaluations"]) if log else 0,
            "wall_s": float(log[-1]["elapsed_s"]) if log else 0.0, "cpu_s": cpu,
            "curve": _curve(log), "search_seed": search_seed, "run_dir": str(run_dir)}


def _curve(log: list[dict]) -> list:
    """[evaluations, best cost under the final weights] at ≤ CURVE_POINTS rows."""
    pts = []
    for r in log:
        v = r.get("best_final") or r.get("best")
        if v not in (None, ""):
            pts.append([int(r["evaluations"]), float(v)])
    if len(pts) <= CURVE_POINTS:
        return pts
    step = (len(pts) - 1) / (CURVE_POINTS - 1)
    return [pts[round(i * step)] for i in range(CURVE_POINTS)]


def _stage_best(stage: Stage, job: Job, after: list[str]) -> tuple[dict, list]:
    """A stage's search, or the cheapest of its ``starts`` searches."""
    k = stage.starts
    tag = "" if not job.config.staged else f"-{stage.name}"
    tries = []
    for i in range(k):
        seed = job.search_seed * k + i if k > 1 else job.search_seed
        run_dir = Path(job.runs) / f"{job.stem}{tag}" if k == 1 else \
            Path(job.runs) / f"{job.stem}{tag}-try{i}"
        tries.append(search_once(stage, seed, run_dir, after, job.scheduler, job.quiet))
    best = min(tries, key=lambda r: (r["best"]["final_cost"], tries.index(r)))
    return best, tries


# ------------------------------------------------------------------ one row

def run_job(job: Job) -> tuple[dict, dict]:
    """Run one job: (its ledger row, {controller name: controller record})."""
    from ..version import __version__
    from .judge import COMPOSITE_MEASURES, get_judge, single_measures
    conf = job.config
    judge = get_judge(conf.judge)
    stages, after, controllers, names, stage_paths = [], [], {}, {}, []
    for stage in conf.stages:
        best, tries = _stage_best(stage, job, after)
        name = job.stem + (f"-{stage.name}" if conf.staged else "")
        rec = dict(best["best"])
        if after:     # the earlier stages, as the study's controller files beside it
            rec["params"] = {**rec["params"], "after": ",".join(
                f"{names[p]}.json" for p in list(names))}
        controllers[name] = rec
        names[stage.name] = name
        stage_paths.append(str(Path(best["run_dir"]) / "best.json"))
        after = list(stage_paths)
        stages.append((stage, best, tries))
    if judge.composite:
        kept = COMPOSITE_MEASURES[conf.judge](stage_paths, [s.name for s in conf.stages])
    else:
        _, best, _ = stages[0]
        traj, costs, measures, ok = best["replay"]
        kept = single_measures(best["task"], traj, measures, ok)
        if judge.extra is not None:
            b = best["best"]
            kept.update(judge.extra(best["task"], best["family"], b["actuation"],
                                    best["family"].from_json(b["genome"])))
    success, label = judge.decide(kept, conf.expect)
    last = stages[-1][1]
    row = {"study": job.study, "config": conf.name, "seed": job.seed, "start": job.start,
           "seeds": job.seed_set, "search_seed": job.search_seed,
           "cost": sum(float(b["best"]["final_cost"]) for _, b, _ in stages),
           "success": success, "label": label, "judge": conf.judge, "measures": kept,
           "evaluations": sum(t["evaluations"] for _, _, ts in stages for t in ts),
           "wall_s": round(sum(t["wall_s"] for _, _, ts in stages for t in ts), 2),
           "cpu_s": round(sum(t["cpu_s"] for _, _, ts in stages for t in ts), 2),
           "controller": f"controllers/{names[conf.stages[-1].name]}.json",
           "curve": last["curve"],
           "versions": {"gpmotion": __version__, "task": last["task"].id,
                        "figure": figure_version(last["task"]),
                        "family": f"{last['family'].name}"}}
    if conf.staged:
        row["stages"] = [{"name": s.name, "task": b["task"].id, "search_seed": b["search_seed"],
                          "cost": float(b["best"]["final_cost"]),
                          "success": bool(b["best"]["success"]),
                          "controller": f"controllers/{names[s.name]}.json",
                          "tries": [{"search_seed": t["search_seed"],
                                     "cost": float(t["best"]["final_cost"]),
                                     "success": bool(t["best"]["success"])} for t in ts]}
                         for s, b, ts in stages]
    elif conf.stages[0].starts > 1:
        row["tries"] = [{"search_seed": t["search_seed"], "cost": float(t["best"]["final_cost"])}
                        for t in stages[0][2]]
    return row, controllers


def figure_version(task) -> str:
    """The figure's name and the digest of its spec (a variant's or the file's)."""
    spec = task.params.get("figure")
    if isinstance(spec, dict):
        text = json.dumps(spec, sort_keys=True, separators=(",", ":"))
    else:
        from ..figures import _REGISTRY
        src = _REGISTRY.get(task.figure.name)
        text = src.read_text() if isinstance(src, Path) else json.dumps(src, sort_keys=True)
    return f"{task.figure.name}@{hashlib.sha256(text.encode()).hexdigest()[:12]}"


# ------------------------------------------------------------------ the study

def check(spec: Spec) -> None:
    """Build every search's task, family and search before touching the disk:
    a bad parameter or option is one line naming the configuration."""
    from ..run import build
    for conf in spec.configurations.values():
        for stage in conf.stages:
            where = f"configurations.{conf.name}" + (f".stages.{stage.name}" if conf.staged else "")
            if stage.params.get("after") is not None:
                raise ConfigError(f"{where}.params.after: stages chain searches; "
                                  "give stages instead")
            try:
                build(run_config(stage, 0, [], None))
            except (ValueError, KeyError) as e:
                msg = e.args[0] if isinstance(e, KeyError) and e.args else str(e)
                raise ConfigError(f"{where}: {msg}") from None


class StudyRows(list):
    """run_study's rows (a list) with the study folder; Jupyter shows its report."""

    def __init__(self, rows, path: Path):
        super().__init__(rows)
        self.path = Path(path)

    def _repr_html_(self) -> str:
        from ..report import folder_html
        return folder_html(self.path)


def run_study(spec: Spec, out: str | Path, seeds: list[int], *, workers: int = 1,
              scheduler: str | None = None, runs: str | Path | None = None,
              quiet: bool = False, progress=None, configs: list[str] | None = None,
              locked=None) -> list[dict]:
    """Run every job of ``seeds`` (of the configurations named in ``configs``,
    default all) not yet in ``out``'s ledger; returns all rows.  ``locked(rows)``,
    when given, runs while ``out`` is still locked (a writer of files from the rows)."""
    from .ledger import StudyDir, row_key
    check(spec)
    unknown = sorted(set(configs or ()) - set(spec.configurations))
    if unknown:
        raise SpecError(f"--configs: no configuration {', '.join(unknown)} in {spec.name}; "
                        f"it has {', '.join(spec.configurations)}")
    out = Path(out)
    with StudyDir(out, spec.digest(), spec.source, spec.quick) as sd:
        runs = Path(runs) if runs is not None else out / "runs"
        done = {row_key(r) for r in sd.rows()}
        todo = [j for j in jobs(spec, seeds, runs.resolve(), scheduler, quiet=quiet or workers > 1)
                if j.key not in done and (configs is None or j.config.name in configs)]
        progress = progress or StudyProgress(len(todo), len(done), quiet)
        try:
            for row, controllers in _finished(todo, workers):
                for name, rec in controllers.items():
                    sd.write_controller(name, rec)
                sd.append(row)
                progress.done(row, workers)
        except (KeyboardInterrupt, WorkerStopped) as e:  # the run loop checkpointed (Ctrl-C, SIGTERM)
            from ..run import Stopped
            what = str(e).split(";")[0] or "stopped"
            raise Stopped(f"{what}; the same `gpmotion study run` continues the study",
                          getattr(e, "code", 130)) from None
        rows = StudyRows(sd.rows(), out)
        if locked is not None:
            locked(rows)
        return rows


class WorkerStopped(Exception):
    """A worker's search was stopped by a signal (it checkpointed): an
    Exception, so the pool hands it back instead of printing a traceback."""

    def __init__(self, msg: str, code: int = 130):
        super().__init__(msg)
        self.code = code


def _job(job: Job):
    try:
        return run_job(job)
    except KeyboardInterrupt as e:
        raise WorkerStopped(str(e), getattr(e, "code", 130)) from None


def _finished(todo: list[Job], workers: int):
    """Rows as each job finishes: in this process for one worker (so Ctrl-C and
    SIGTERM reach the run loop, which checkpoints), else from spawned processes
    with one compute thread each."""
    if workers <= 1 or len(todo) <= 1:
        yield from map(_job, todo)
        return
    import multiprocessing as mp
    old = os.environ.get("NUMBA_NUM_THREADS")
    os.environ["NUMBA_NUM_THREADS"] = "1"          # read by the children as they start
    try:
        pool = mp.get_context("spawn").Pool(min(workers, len(todo)))
    finally:
        if old is None:
            os.environ.pop("NUMBA_NUM_THREADS", None)
        else:
            os.environ["NUMBA_NUM_THREADS"] = old
    with pool:
        yield from _pool_rows(pool, todo, min(workers, len(todo)), mp)


def _pool_rows(pool, todo: list[Job], n: int, mp):
    """At most ``n`` jobs in flight.  On SIGTERM or Ctrl-C: no new job starts,
    each worker's run loop checkpoints (SIGTERM is passed on; Ctrl-C reaches
    the whole process group), rows finished meanwhile are still yielded, then
    WorkerStopped; leaving the pool ends the idle workers."""
    stop: dict = {}

    def on_signal(signum, frame):
        if not stop and signum == signal.SIGTERM:
            for child in mp.active_children():
                os.kill(child.pid, signal.SIGTERM)
        stop.setdefault("code", 128 + signum)

    old = {s: signal.signal(s, on_signal) for s in (signal.SIGTERM, signal.SIGINT)}
    pending, running = list(todo), []
    try:
        while running or (pending and not stop):
            while pending and len(running) < n and not stop:
                running.append(pool.apply_async(_job, (pending.pop(0),)))
            ready = [r for r in running if r.ready()]
            if not ready:
                time.sleep(0.05)
                continue
            for r in ready:
                running.remove(r)
                try:
                    yield r.get()
                except WorkerStopped as e:
                    stop.setdefault("code", e.code)
        if stop:
            raise WorkerStopped("stopped", stop["code"])
    finally:
        for s, h in old.items():
            signal.signal(s, h)


class StudyProgress:
    """A line on stderr per finished run: runs done of the study, and its ETA."""

    def __init__(self, todo: int, done: int, quiet: bool = False):
        self.todo, self.done0, self.quiet = todo, done, quiet
        self.n, self.t0 = 0, time.perf_counter()

    def done(self, row: dict, workers: int = 1) -> None:
        self.n += 1
        if self.quiet:
            return
        el = time.perf_counter() - self.t0
        left = self.todo - self.n
        eta = f"eta {el / self.n * left:,.0f}s" if left else "done"
        what = row["label"] + ("" if row["success"] is None else
                               (" ✓" if row["success"] else " ✗"))
        print(f"[{self.done0 + self.n}/{self.done0 + self.todo}] {row['config']} seed "
              f"{row['seed']}" + (f" start {row['start']}" if row["start"] else "") +
              f": {what}, cost {row['cost']:.4f}, {row['evaluations']:,} evaluations, "
              f"{row['wall_s']:.0f} s  ({eta})", file=sys.stderr, flush=True)
