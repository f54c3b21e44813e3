"""The in-process evaluator, and what a worker process runs.

Every evaluator has one interface, ``evaluate(genomes, progress) ->``
:class:`~gpmotion.evaluation.Evaluation`.  In-process evaluation runs the
whole batch in one numba rollout over all threads.  The other backends
(:mod:`gpmotion.evaluators`: process pool, Dask) split genomes into chunks
and call :func:`evaluate_chunk` in their workers with plain data only: a
worker is an in-process evaluator rebuilt from :func:`spec_of`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .evaluation import Evaluation
from .families import Family, make_family
from .sim.rollout import rollout
from .task import Task, get_task


@dataclass
class InProcessEvaluator:
    """Batched numba rollout over all threads of this process."""
    task: Task
    family: Family
    actuation: str | None = None
    threads: int | None = None
    robust: dict | None = None           # perturbed starts (gpmotion.robust), + the run's seed
    evaluations: int = field(default=0, init=False)

    def __post_init__(self):
        self.actuation = self.actuation or self.family.default_actuation
        self._scenes = {}                     # task phase -> scene (a curriculum moves it)
        self._q0, self._qd0 = self.task.initial_state()
        self._contact0 = self.task.initial_contact()

    def scene(self, progress: float = 1.0):
        key = self.task.staged(progress)
        if key not in self._scenes:
            self._scenes[key] = self.task.scene_at(progress)
        return self._scenes[key]

    def rollout(self, genomes, record_senses=False, progress: float = 1.0):
        batch = self.family.encode(genomes)
        return rollout(self.task.figure, self.scene(progress), batch, **self.task.rollout_options(),
                       q0=self._q0, qd0=self._qd0, contact0=self._contact0, actuation=self.actuation,
                       default_tau=self.family.default_tau,
                       record_senses=record_senses or self.family.needs_senses,
                       threads=self.threads)

    def evaluate(self, genomes, progress: float = 1.0, generation: int = 0) -> Evaluation:
        """``generation`` picks the perturbed starts of a robust evaluation (else unused)."""
        genomes = list(genomes)
        if not genomes:
            return Evaluation(np.zeros(0), np.zeros(0, bool), np.zeros(0, bool), {}, [])
        if self.robust:
            from .robust import batch_evaluation
            self.evaluations += len(genomes)
            return batch_evaluation(self, genomes, progress, generation)
        traj = self.rollout(genomes, progress=progress)
        costs, measures, ok = self.task.score(traj, progress)
        extras = self.family.extras(traj)
        self.evaluations += len(genomes)
        return Evaluation(costs, ok, traj.diverged.copy(), measures, extras)

    def close(self):
        pass


def code_digest() -> str:
    """Hash of gpmotion's own sources: workers on other code would give other results."""
    global _CODE
    if _CODE is None:
        from pathlib import Path

        from .cache import file_digest
        root = Path(__file__).resolve().parent
        files = sorted(p for p in root.rglob("*.py") if "__pycache__" not in p.parts)
        import gpmotion.primitives as prims
        import gpmotion.tasks as tasks
        for pkg in (prims, tasks):
            files += sorted(Path(pkg.__path__[0]).glob("*.py"))
        _CODE = file_digest(*files)
    return _CODE


_CODE = None


def spec_of(task: Task, family: Family, actuation: str, plugins=(), robust=None) -> dict:
    """Plain-data description a remote worker rebuilds the evaluator from.

    ``plugins``: requirement records (:mod:`gpmotion.plugins`: name and digest),
    never folder paths.
    """
    from .plugins import for_record
    return {"task": task.id, "params": dict(task.params), "family": family.name,
            "options": dict(family.options), "actuation": actuation,
            "plugins": [{k: v for k, v in r.items() if k != "path"} for r in for_record(plugins)],
            "code": code_digest(), **({"robust": dict(robust)} if robust else {})}


_WORKER_CACHE: dict[str, InProcessEvaluator] = {}


def evaluator_from_spec(spec: dict, threads: int | None = None) -> InProcessEvaluator:
    import json
    key = json.dumps(spec, sort_keys=True)
    ev = _WORKER_CACHE.get(key)
    if ev is None:
        if spec.get("code", code_digest()) != code_digest():
            raise ValueError("this worker runs different gpmotion code than the run's main process; "
                             "install the same version everywhere")
        # Plugin code reaches a worker only as sources shipped by the main process,
        # checked against their digest; the spec's records are requirements.
        from . import plugins
        if any("entry_point" in r for r in spec.get("plugins", ())):
            plugins.load_entry_points()
        plugins.install_sources(spec.get("plugin_sources"))
        plugins.require(spec.get("plugins", []), "this worker")
        task = get_task(spec["task"], **spec["params"])
        fam = make_family(spec["family"], task, **spec["options"])
        ev = _WORKER_CACHE[key] = InProcessEvaluator(task, fam, spec["actuation"], threads,
                                                     spec.get("robust"))
    return ev


def evaluate_chunk(spec: dict, genomes_json: list, progress: float, threads: int | None = 1,
                   generation: int = 0) -> Evaluation:
    """Evaluate a chunk of JSON genomes in this (worker) process."""
    ev = evaluator_from_spec(spec, threads)
    genomes = [ev.family.from_json(g) for g in genomes_json]
    return ev.evaluate(genomes, progress, generation)
