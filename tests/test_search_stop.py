"""A GP schedule that ends when it is done: ``patience`` (no gain at full
weight for K generations) and ``stop_on_success="full-weight"``."""
import json

import numpy as np
import pytest

from gpmotion.evaluation import Evaluation
from gpmotion.families import make_family
from gpmotion.search.gp import GPSearch
from gpmotion.task import get_task


def _evaluation(task, distances, success=None):
    """An Evaluation whose measures are all 0 but the main goal (distance)."""
    n = len(distances)
    m = {t.name: np.zeros(n) for t in task.terms}
    m["distance"] = np.asarray(distances, float)
    failed = np.zeros(n, bool)
    ok = np.zeros(n, bool) if success is None else np.asarray(success, bool)
    return Evaluation(task.cost(m, failed, 1.0), ok, failed, m)


def _generation(search, task, best):
    n = len(search.ask())              # copies of known genomes are not asked again
    search.tell(_evaluation(task, ([best] + [best + 1.0] * (n - 1))[:n]))


@pytest.fixture(scope="module")
def hop():
    task = get_task("lamp_hop")
    return task, make_family("gp", task)


def test_patience_stops_k_full_weight_generations_after_the_last_gain(hop):
    task, fam = hop
    s = GPSearch(fam, population=6, generations=40, seed=1, patience=3, task=task)
    full = next(g for g in range(40) if s.phase_of(g) == s.phase_at(1.0))     # 32 of 40
    for g in range(full + 2):
        _generation(s, task, 0.95 ** g)                # 5 % better every generation
    assert not s.done
    _generation(s, task, s.best_cost * 0.995)          # below the 1 % tolerance: no gain
    _generation(s, task, s.best_cost)
    assert not s.done
    mid = json.loads(json.dumps(s.state_dict()))
    _generation(s, task, s.best_cost)                  # third generation without a gain
    assert s.done and s.converged and not s.stopped and s.generation == full + 5 < 40
    again = GPSearch(fam, population=6, generations=40, seed=1, patience=3, task=task)
    again.load_state_dict(mid)                         # a resume takes the same decision
    _generation(again, task, again.best_cost)
    assert again.done and again.generation == s.generation and again.best == s.best
    s.extend(45, 40)                                    # more generations: it runs on
    assert not s.done
    _generation(s, task, s.best_cost)


def test_patience_does_not_count_before_full_weight(hop):
    task, fam = hop
    s = GPSearch(fam, population=6, generations=12, seed=2, patience=1, task=task)
    for _ in range(12):
        _generation(s, task, 0.5)                      # never a gain
        if s.done:
            break
    assert s.converged and s.phase_of(s.generation - 2) == s.phase_at(1.0)
    off = GPSearch(fam, population=6, generations=6, seed=2, task=task)     # default: off
    for _ in range(6):
        _generation(off, task, 0.5)
    assert off.generation == 6 and not off.converged and "patience" not in off.config()


def test_stop_on_success_full_weight_waits_for_every_style_term(hop):
    task, fam = hop
    s = GPSearch(fam, population=6, generations=10, seed=1, stop_on_success="full-weight",
                 elitism=0, task=task)
    while s.phase_of(s.generation) != s.phase_at(1.0):
        n = len(s.ask())
        s.tell(_evaluation(task, [0.01] * n, [True] * n))        # solvers: not yet final weights
        assert not s.done
    pending = s.ask()
    n = len(pending)
    s.tell(_evaluation(task, [0.2] * (n - 1) + [0.3], [False] * (n - 1) + [True]))
    assert s.done and s.stopped and s.best == pending[-1]
    assert s.config()["stop_on_success"] == "full-weight"
    scene_only = GPSearch(fam, population=6, generations=10, seed=1, stop_on_success=True,
                          task=task)                              # no curriculum: gen 0 stops
    n = len(scene_only.ask())
    scene_only.tell(_evaluation(task, [0.01] * n, [True] * n))
    assert scene_only.stopped and scene_only.generation == 1


@pytest.mark.parametrize("kw, message", [
    (dict(patience=-1), "patience"), (dict(patience=1.5), "patience"),
    (dict(stop_on_success="always"), "stop_on_success"),
])
def test_bad_stop_settings(hop, kw, message):
    task, fam = hop
    with pytest.raises(ValueError, match=message):
        GPSearch(fam, population=6, generations=5, seed=0, task=task, **kw)
