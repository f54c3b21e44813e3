"""Robust runs: confirmation starts (``confirm``/``require``) and stop_on_success keeping its solver."""
import numpy as np
import pytest

from gpmotion import get_task
from gpmotion import robust as R
from gpmotion.evaluation import Evaluation
from gpmotion.families import make_family


def _lamp(threshold=None):
    task = get_task("lamp_hop", seconds=0.3)
    if threshold is not None:           # success made a plain function of one measure (known by hand)
        task.success = lambda traj, m: m["distance"] < threshold
    return task


def _by_hand(task, fam, genomes, starts_rng, k):
    """Costs [N, k], distances [N, k] of each genome from k starts drawn from ``starts_rng``."""
    q0, qd0 = task.initial_state()
    q, qd = R.perturbed_starts(task.figure, q0, qd0, k, starts_rng, R.FIGURE_SIZES["lamp"])
    tr = R.robust_rollout(task.figure, task.scene_at(1.0), fam.encode(genomes), q, qd, n_steps=task.n_steps,
                          dt=task.dt, record_every=task.record_every, actuation=fam.default_actuation,
                          default_tau=fam.default_tau)
    costs, m, _ = task.score(tr, 1.0)
    return costs.reshape(len(genomes), k), m["distance"].reshape(len(genomes), k)


def test_confirmation_starts_rescore_the_candidates_only():
    from gpmotion.inprocess import InProcessEvaluator
    fam = make_family("gp", _lamp())
    genomes = [fam.random(np.random.default_rng(s)) for s in range(6)]
    k, m, seed, gen = 3, 5, 4, 2
    c_k, d_k = _by_hand(_lamp(), fam, genomes, R.round_rng(seed, gen), k)
    thr = d_k[0].max() + 1e-9                             # genome 0 succeeds from its 3 starts
    cand = d_k.max(axis=1) < thr
    assert cand[0] and not cand.all()
    c_m, d_m = _by_hand(_lamp(), fam, [g for g, c in zip(genomes, cand) if c], R.confirm_rng(seed, gen), m)
    task = _lamp(thr)
    setting = {**R.normalize({"starts": k, "confirm": m, "require": 0.5}, task), "seed": seed}
    ev = InProcessEvaluator(task, make_family("gp", task), robust=setting).evaluate(genomes, 1.0, generation=gen)
    plain = {**R.normalize({"starts": k}, task), "seed": seed}
    ev0 = InProcessEvaluator(task, make_family("gp", task), robust=plain).evaluate(genomes, 1.0, generation=gen)
    np.testing.assert_allclose(ev0.costs, c_k.mean(axis=1))
    np.testing.assert_array_equal(ev0.success, cand)       # require 1: every start
    both = np.concatenate([c_k[cand], c_m], axis=1)
    np.testing.assert_allclose(ev.costs[cand], both.mean(axis=1))       # candidates: over k + m starts
    np.testing.assert_array_equal(ev.costs[~cand], ev0.costs[~cand])    # the others: as without
    rate = np.concatenate([d_k[cand], d_m], axis=1) < thr
    assert list(ev.success[cand]) == list(rate.mean(axis=1) >= 0.5)
    assert not ev.success[~cand].any()
    np.testing.assert_allclose(task.cost(ev.measures, ev.failed), ev.costs)   # measures give the cost


def test_confirm_and_require_are_recorded_only_when_set_and_checked():
    from gpmotion.records import ConfigError
    lamp = get_task("lamp_hop")
    assert "confirm" not in R.normalize({"starts": 4}, lamp)        # older configs read back unchanged
    n = R.normalize({"starts": 4, "confirm": 16, "require": 0.9}, lamp)
    assert n["confirm"] == 16 and n["require"] == 0.9
    for bad in ({"starts": 2, "confirm": -1}, {"starts": 2, "require": 0}, {"starts": 2, "require": 1.5}):
        with pytest.raises(ConfigError):
            R.normalize(bad, lamp)


def test_stop_on_success_keeps_its_solver_over_a_cheaper_earlier_non_solver():
    from gpmotion.search.gp import GPSearch
    task = get_task("lamp_hop")
    fam = make_family("gp", task)
    s = GPSearch(fam, population=6, generations=5, seed=1, stop_on_success=True, elitism=0, task=task)

    def ev(n, distance, success):
        m = {"distance": np.full(n, distance), "late": np.zeros(n), "moving": np.zeros(n),
             "head_hit": np.zeros(n), "fell": np.zeros(n), "neutral": np.zeros(n), "energy": np.zeros(n)}
        return Evaluation(np.full(n, distance), np.array(success, bool), np.zeros(n, bool), m)
    n = len(s.ask())
    s.tell(ev(n, 0.01, [False] * n))                     # cheap, but no solver (e.g. easy starts)
    pending = s.ask()
    s.tell(ev(len(pending), 0.03, [False] * (len(pending) - 1) + [True]))
    assert s.stopped and s.final.cost == pytest.approx(0.01)     # the final scoring saw the cheaper one
    assert s.best == pending[-1] and s.best_cost == pytest.approx(0.03)


def test_a_percentile_aggregate_picks_that_start_and_its_measures():
    c = np.array([[5.0, 1.0, 3.0, 2.0, 4.0, 9.0, 7.0, 8.0]])      # sorted: 1 2 3 4 5 7 8 9
    assert R.aggregate(c.ravel(), 8, "q80")[0] == 8.0                # ceil(0.8·8) = 7th lowest
    assert R.aggregate(c.ravel(), 8, "q50")[0] == 4.0
    assert R.aggregate(c.ravel(), 8, "q99")[0] == 9.0 == R.aggregate(c.ravel(), 8, "worst")[0]
    agg, m = R._fold(c, {"d": c * 10}, "q80")
    assert agg[0] == 8.0 and m["d"][0] == 80.0                       # the measures of that same start
    for bad in ("q0", "q100", "median", "q8"):
        assert not R.is_aggregate(bad)
    assert R.normalize({"starts": 8, "aggregate": "q80"}, get_task("lamp_hop"))["aggregate"] == "q80"
