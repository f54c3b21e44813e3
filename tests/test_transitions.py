"""The transition search (Fig. 5): finds a known best, counts, determinism, exact resume."""
import json

import numpy as np
import pytest

from gpmotion.compose import composite as C
from gpmotion.compose import optimize, script
from gpmotion.compose.transitions import TransitionSearch
from tests.test_composite import write_controller


def drive(ts, f, stop=None):
    asked = []
    while not ts.done and (stop is None or ts.evaluations < stop):
        x = ts.ask()
        asked.append(x)
        ts.tell([f(r) for r in x])
    return asked


def bowl(best):
    best = np.asarray(best)
    return lambda s: -float(np.sum((s - best) ** 2))


@pytest.mark.parametrize("best", [[1.24], [0.7, 2.1], [0.3, 0.32, 2.9]])
def test_finds_a_known_best(best):
    ts = TransitionSearch(len(best), 3.0, seed=1, tick=0.02)
    drive(ts, bowl(best))
    np.testing.assert_allclose(ts.best, best, atol=0.021)
    assert ts.evaluations == 1 + 16 * 16 * 4               # Fig. 5: Q × G × H = 1,024 (+ the start)


def test_starts_from_the_guess_or_equally_spaced():
    ts = TransitionSearch(2, 3.0)
    np.testing.assert_allclose(ts.ask(), [[1.0, 2.0]])       # the Q identical start arrays: one simulation
    ts = TransitionSearch(2, 3.0, guess=[2.5, 0.5], Q=4)
    np.testing.assert_allclose(ts.ask(), [[0.5, 2.5]])
    np.testing.assert_allclose(ts.ask(), [[0.5, 2.5]])          # the same until told
    ts.tell([-1.0])
    assert np.all(ts.scores == -1.0) and np.all(ts.pop == [0.5, 2.5])
    assert ts.ask().shape == (4, 2)


def test_mutation_randomizes_a_third_and_perturbs_two_thirds():
    ts = TransitionSearch(3, 10.0, guess=[2.0, 5.0, 8.0], Q=3000, perturb=1e-3, seed=0)
    ts.tell([0.0] * len(ts.ask()))
    x = ts.ask()
    moved = np.abs(np.sort(x, axis=1) - [2.0, 5.0, 8.0])
    assert np.all((moved > 0).sum(axis=1) <= 3)
    big = (moved.max(axis=1) > 0.01).mean()                  # a perturbation moves ~1e-3 s
    assert abs(big - 1 / 3) < 0.03
    assert np.all(np.diff(x, axis=1) >= 0) and x.min() >= 0 and x.max() <= 10.0


def test_keep_if_better_then_bottom_half_becomes_top_half():
    ts = TransitionSearch(1, 1.0, guess=[0.5], Q=4, H=2, seed=3)
    ts.ask()
    ts.tell([-10.0])
    x = ts.ask()
    assert not np.any(x[:, 0] == 0.5)
    ts.tell([-1.0, -20.0, -30.0, -2.0])                      # slots 1 and 2 got worse: kept
    np.testing.assert_allclose(ts.scores, [-1.0, -10.0, -10.0, -2.0])
    np.testing.assert_allclose(ts.pop[:, 0], [x[0, 0], 0.5, 0.5, x[3, 0]])
    y = ts.ask()
    ts.tell([-5.0, -9.0, -11.0, -1.5])                       # slot 1 and 3 improve
    # ranking −1 (slot 0), −1.5 (slot 3), −9 (slot 1), −10 (slot 2): the top two are copied down
    np.testing.assert_allclose(ts.scores, [-1.0, -1.5, -1.0, -1.5])
    np.testing.assert_allclose(ts.pop[:, 0], [x[0, 0], y[3, 0], x[0, 0], y[3, 0]])
    assert ts.round == 1 and ts.step == 0 and ts.best_score == -1.0


def test_same_seed_same_search_other_seed_another():
    runs = [drive(TransitionSearch(2, 3.0, seed=s, G=3), bowl([1.0, 2.0])) for s in (5, 5, 6)]
    assert all(np.array_equal(a, b) for a, b in zip(runs[0], runs[1]))
    assert not all(np.array_equal(a, b) for a, b in zip(runs[0], runs[2]))


@pytest.mark.parametrize("stop, between", [(1, False), (1 + 16 * 5 + 16 * 3, False), (1 + 16 * 9, True)])
def test_resume_is_exact(stop, between):
    f = bowl([0.4, 1.9])
    ref = TransitionSearch(2, 3.0, seed=7, G=6, tick=0.02)
    ref_asks = drive(ref, f)
    ts = TransitionSearch(2, 3.0, seed=7, G=6, tick=0.02)
    first = drive(ts, f, stop=stop)
    pending = ts.ask() if between else None               # checkpoint between ask and tell
    state = json.loads(json.dumps(ts.state_dict(), allow_nan=False))
    back = TransitionSearch(2, 3.0, seed=999, G=6, tick=0.02)  # the seed comes from the state
    back.load_state_dict(state)
    rest = drive(back, f)
    if between:
        np.testing.assert_array_equal(rest[0], pending)
    assert len(first) + len(rest) == len(ref_asks)
    for a, b in zip(ref_asks, first + rest):
        np.testing.assert_array_equal(a, b)
    assert back.best.tolist() == ref.best.tolist() and back.best_score == ref.best_score
    assert back.evaluations == ref.evaluations


def test_bad_state_and_arguments():
    ts = TransitionSearch(2, 3.0)
    other = TransitionSearch(2, 4.0).state_dict()
    with pytest.raises(ValueError, match="another search"):
        ts.load_state_dict(other)
    with pytest.raises(ValueError, match="malformed"):
        ts.load_state_dict({"kind": "transition-search", "version": 1, "config": ts.state_dict()["config"]})
    with pytest.raises(ValueError, match="guess must be 2"):
        TransitionSearch(2, 3.0, guess=[1.0])
    with pytest.raises(ValueError, match="Q must be"):
        TransitionSearch(2, 3.0, Q=0)
    with pytest.raises(RuntimeError, match="without ask"):
        ts.tell([1.0])
    ts.ask()
    with pytest.raises(ValueError, match="expected 1 scores"):
        ts.tell([1.0, 2.0])


def test_nonfinite_scores_are_worst():
    ts = TransitionSearch(1, 1.0, Q=2, H=1)
    ts.ask()
    ts.tell([np.nan])
    assert ts.best_score == -np.inf and ts.row()["best_score"] is None
    ts.ask()
    ts.tell([1.0, np.inf])
    assert ts.best_score == 1.0


def test_search_on_a_composite_finds_the_scripted_switch(tmp_path):
    """Through the simulator: the script pays for phase 1 lasting 0.62 s, so the best switch is 0.62 s."""
    write_controller(tmp_path / "a.json")
    comp = C.from_controllers([tmp_path / "a.json", tmp_path / "a.json"], switches=[0.3], seconds=1.0)
    s = script.parse("phase one = dtime ~= 0.62\nphase two = max_t(cm_z) * 0\n"
                     "total = one + two")
    rows = []
    ts = optimize.search(comp, s, Q=4, G=6, H=2, seed=0, on_round=lambda t: rows.append(t.row()))
    assert ts.best.tolist() == pytest.approx([0.62]) and ts.best_score == pytest.approx(1.0)
    assert len(rows) == 6 and rows[-1]["evaluations"] == 1 + 4 * 6 * 2
    totals, credits, traj, bounds = optimize.score(comp, s, [ts.best])
    assert bounds[0, 1] == 31 and totals[0] == pytest.approx(1.0)
    with pytest.raises(C.CompositeError, match="script has 1 phase"):
        optimize.search(comp, script.parse("phase a = 1\ntotal = a"))


def test_compose_run_directory_resumes_exactly(tmp_path):
    from gpmotion.compose import session
    write_controller(tmp_path / "a.json")
    comp = C.from_controllers([tmp_path / "a.json", tmp_path / "a.json"], switches=[0.3], seconds=1.0)
    text = "phase one = dtime ~= 0.62\nphase two = max_t(cm_z)\ntotal = one + 0.1 * two\n"
    kw = dict(Q=4, G=4, H=1, seed=2, log=lambda m: None)
    full = session.compose_run(tmp_path / "full", text, comp, **kw)
    assert session.compose_run(tmp_path / "part", text, comp, stop_after_rounds=2, **kw) is None
    assert len((tmp_path / "part" / "log.csv").read_text().splitlines()) == 1 + 2
    with pytest.raises(ValueError, match="not empty"):
        session.compose_run(tmp_path / "part", text, comp, **kw)
    with pytest.raises(ValueError, match="differs"):
        session.compose_run(tmp_path / "part", text, comp, resume=True, **dict(kw, seed=3))
    resumed = session.compose_run(tmp_path / "part", text, comp, resume=True, **kw)
    assert resumed == full and full["simulations"] == 1 + 4 * 4 * 1
    assert (tmp_path / "part" / "log.csv").read_text() == (tmp_path / "full" / "log.csv").read_text()
    best = C.load(tmp_path / "full" / "composite.json")
    assert best.switches.tolist() == full["best"]["switches"]
    assert full["best"]["total"] >= full["careless"]["total"]
