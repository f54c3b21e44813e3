"""The run's film record, ``generations.jsonl``: the best controller the search
holds after each generation (GP) or serial round (BSR) in which it changed.

One JSON object a line::

    {"generation": 12, "evaluations": 6500, "progress": 0.24,
     "cost": 3.9,            # under the weights of that generation
     "cost_final": 4.1,      # under the final weights (null: not known then)
     "genome": {...}}        # the family's JSON form (best.json's "genome")

The controller, not its motion: the report replays it.  A generation whose
best is the previous record's controller is not repeated.  ``cost_final``
is exact (the task's final scoring of that evaluation's measures, no extra
simulation) when the controller was evaluated in that generation in the
final scene, else null.

Records are buffered by the run loop and appended just before each
checkpoint, like log rows; a resume trims the file to the checkpoint's
generation (:meth:`gpmotion.rundir.RunDir.trim_generations`) and takes the
last record as where it left off, so a killed-and-resumed run writes the
same file as an uninterrupted one.
"""
from __future__ import annotations

import json
import math

import numpy as np


def _jsonable(x):
    """A genome's JSON form with numpy scalars and arrays as plain numbers."""
    return json.loads(json.dumps(x, default=lambda v: v.tolist() if hasattr(v, "tolist") else str(v)))


class GenerationRecorder:
    """Makes a record when the search's held best changes (see the module docstring)."""

    def __init__(self, family, task, last: dict | None = None):
        self.family, self.task = family, task
        self.last_genome = None if last is None else last.get("genome")

    def record(self, search, genomes, ev, evaluations: int) -> dict | None:
        genome, cost = search._own_best()       # the best under this generation's weights
        if genome is None:
            return None
        data = _jsonable(self.family.to_json(genome))
        if data == self.last_genome:
            return None
        self.last_genome = data
        return {"generation": int(search.logged_generation()), "evaluations": int(evaluations),
                "progress": round(float(search.told_progress), 6),
                "cost": _num(cost), "cost_final": self._final_cost(data, genomes, ev, search),
                "genome": data}

    def _final_cost(self, data, genomes, ev, search):
        """Its cost under the final weights from this generation's measures, if it was
        evaluated here in the final scene; None otherwise."""
        task = self.task
        if task is None or not ev.measures or task.staged(search.told_progress) != task.staged(1.0):
            return None
        for i in np.argsort(np.asarray(ev.costs), kind="stable"):
            if _jsonable(self.family.to_json(genomes[i])) == data:
                one = {k: np.asarray(v)[[i]] for k, v in ev.measures.items()}
                return _num(task.cost(one, np.asarray(ev.failed)[[i]], 1.0)[0])
        return None


def _num(x):
    x = float(x)
    return x if math.isfinite(x) else None
