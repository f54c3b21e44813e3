"""Save a controller found outside the run loop (a DEAP individual from your
own ``eaSimple`` loop, a hand-made BSR genome) as a controller file that
``gpmotion replay / render / export`` and :func:`gpmotion.load_controller` read.
"""
from __future__ import annotations

from pathlib import Path

from .families import DEFAULT_FAMILY, Family, make_family
from .task import Task, get_task


def save_controller(path: str | Path, task: Task | str, genome, *, family: Family | str = DEFAULT_FAMILY,
                    actuation: str | None = None, seed: int = 0, plugins=()) -> dict:
    """Write ``genome`` to ``path`` (the best.json format) and return the record.

    ``genome``: for GP a list of trees, one per controlled joint (a DEAP
    individual: list of ``PrimitiveTree``; token lists also do); for BSR a
    genome.  ``family``: a name or the Family that made the genome (e.g.
    ``toolbox.family`` from :func:`gpmotion.make_toolbox`: its primitive set).
    ``plugins``: the folders its primitives or task come from.  The recorded
    cost is the genome's replayed cost with every style term at full weight.
    """
    from .records import atomic_write_json, envelope
    from .replay import replay_genome
    from .run import RunConfig, controller_record
    task = get_task(task) if isinstance(task, str) else task
    fam = family if isinstance(family, Family) else make_family(family, task)
    if fam.task.id != task.id:
        raise ValueError(f"family was made for task {fam.task.id}, not {task.id}")
    genome = fam.from_json(fam.to_json(genome))      # the checks a file read gets
    actuation = actuation or fam.default_actuation
    traj, costs, measures, ok = replay_genome(task, fam, actuation, genome)
    cfg = RunConfig(task=task.id, family=fam.name, seed=int(seed),
                    plugins=[str(Path(d).resolve()) for d in plugins])
    rec = controller_record(cfg, task, fam, actuation, genome, costs[0])
    rec.update(terms=task.breakdown(measures, 0, 1.0), final_cost=float(costs[0]),
               success=bool(ok[0]), facts=task.describe(traj, measures))
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    atomic_write_json(path, envelope("best", rec))
    return rec
