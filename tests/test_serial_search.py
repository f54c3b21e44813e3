"""Serial search (Fig. 3) on toy objectives: no simulator involved.
A search minimizes costs; the toy costs are squared distances to a target."""
import json
from types import SimpleNamespace

import numpy as np
import pytest

from gpmotion.bsr import genome as G
from gpmotion.bsr import mutation as M
from gpmotion.evaluation import Evaluation
from gpmotion.search.serial import SerialSearch

LIMITS = np.array([[-1.0, 1.0], [-1.0, 1.0], [0.0, 2.0]])
TARGET = np.array([0.3, -0.7, 1.5])


class ToyFamily:
    """What the serial search asks of a family: random, mutate, copy, JSON."""

    def __init__(self, init, mutate, to_json=lambda g: g.to_dict(), from_json=G.genome_from_dict):
        self.random, self.mutate, self.to_json, self.from_json = init, mutate, to_json, from_json

    def copy(self, g):
        return g.copy()


def init_fn(rng):
    return G.random_time_genome(rng, 4, LIMITS, 0.01, 2.0, 1.0)


def toy_cost(g):
    return float(np.sum((g.theta0 - TARGET) ** 2))


def make(seed, task=None, **kw):
    kw = {"n_working": 6, "n_generations": 120, "reseed_every": 20, **kw}
    return SerialSearch(ToyFamily(init_fn, M.make_mutate_fn()), seed=seed, task=task, **kw)


def run(search, until=None):
    while not search.done and (until is None or search.generation < until):
        cands = search.ask()
        search.tell([toy_cost(g) for g in cands])
    return search


def test_improves_monotonically():
    s = run(make(0))
    best = [b for _, b in s.history]
    assert all(b2 <= b1 for b1, b2 in zip(best, best[1:]))
    assert best[-1] < best[0] - 1.0 and best[-1] < 0.5
    assert [e for e, _ in s.history] == [6 * (i + 1) for i in range(121)]
    assert s.evaluations == 6 * 121 and s.best_score == best[-1]
    assert toy_cost(s.best_genome) == s.best_score
    assert s.best_cost == s.best_score and s.best.to_dict() == s.best_genome.to_dict()
    with pytest.raises(RuntimeError):
        s.ask()


def test_same_seed_identical_other_seed_differs():
    a, b, c = run(make(42)), run(make(42)), run(make(43))
    assert a.history == b.history and a.best_genome.to_dict() == b.best_genome.to_dict()
    assert a.history != c.history


def restored(part, fresh, stop_between_ask_and_tell):
    """``fresh`` given ``part``'s state through JSON (taken after an ask when asked to)."""
    if stop_between_ask_and_tell:
        part.ask()
    fresh.load_state_dict(json.loads(json.dumps(part.state_dict(), allow_nan=False)))
    return fresh


@pytest.mark.parametrize("stop_between_ask_and_tell", [False, True])
def test_state_dict_resumes_identically(stop_between_ask_and_tell):
    full = run(make(5))
    part = run(make(5), until=37)
    resumed = restored(part, make(999, n_generations=1),     # wrong seed and config: the state wins
                       stop_between_ask_and_tell)
    assert resumed.n_generations == 120
    if stop_between_ask_and_tell:
        assert resumed.pending is not None
    run(resumed)
    assert resumed.history == full.history
    assert resumed.best_genome.to_dict() == full.best_genome.to_dict()
    assert [g.to_dict() for g in resumed.working] == [g.to_dict() for g in full.working]
    with pytest.raises(ValueError, match="checkpoint"):
        resumed.load_state_dict({"format": "other"})


def _marker_search(**kw):
    """Genomes are plain dicts {'id': n}; mutants count up, so we see who survives."""
    counter = iter(range(10_000))
    fam = ToyFamily(lambda rng: {"id": next(counter)},
                    lambda g, rng, extra: {"id": next(counter), "parent_extra": extra},
                    to_json=dict, from_json=dict)
    return SerialSearch(fam, seed=0, **kw)


def _tell(s, costs, extras=None):
    s.tell(Evaluation.of_costs(costs, extras))


def test_replacement_is_strict_unless_ties_accepted():
    for ties, expect in [(False, [0, 1]), (True, [2, 3])]:
        s = _marker_search(n_working=2, n_generations=5, reseed_every=100, accept_ties=ties)
        s.ask(); s.tell([-1.0, -2.0])
        s.ask(); s.tell([-1.0, -2.0])                    # equal costs
        assert [g["id"] for g in s.working] == expect
        s.ask(); s.tell([-0.5, -3.0])                    # worse, better
        assert s.working[1]["id"] == 5 and s.working[0]["id"] == expect[0]


def test_nonfinite_costs_are_worst():
    s = _marker_search(n_working=2, n_generations=5, reseed_every=100)
    s.ask(); s.tell([float("nan"), -1.0])
    s.ask(); s.tell([1e9, -float("inf")])
    assert [g["id"] for g in s.working] == [2, 1] and s.best_score == -1.0
    json.dumps(s.state_dict(), allow_nan=False)


def test_reseed_copies_top_half_over_bottom_half():
    s = _marker_search(n_working=4, n_generations=5, reseed_every=1)
    s.ask(); s.tell([0.0, 0.0, 0.0, 0.0])
    s.ask(); _tell(s, [-1.0, -4.0, -2.0, -3.0], extras=[[1.0], [4.0], [2.0], [3.0]])
    # ranks: 1 (-4.0), 3 (-3.0), 2, 0 -> slot 2 <- slot 1, slot 0 <- slot 3
    assert list(s.scores) == [-3.0, -4.0, -4.0, -3.0]
    assert [g["id"] for g in s.working] == [7, 5, 5, 7]
    assert s.working[2] is not s.working[1]
    assert [float(e[0]) for e in s.extras] == [3.0, 4.0, 4.0, 3.0]
    # the next mutants see their parent's trajectory (relevance heuristic input)
    assert [c["parent_extra"][0] for c in s.ask()] == [3.0, 4.0, 4.0, 3.0]


def test_sense_genomes_with_relevance_trajectories():
    """Sense-based genomes + trajectories through ask/tell and a JSON checkpoint."""
    V = 3

    def init(rng):
        return G.random_sense_genome(rng, 5, V, LIMITS, 0.01, 2.0)

    def trajectory(g):       # stand-in for a rollout: deterministic sense path
        return np.clip(np.linspace(0, 1, 20)[:, None] * (g.theta0[0] + 1.5) / 3.5, 0, 1)

    s = SerialSearch(ToyFamily(init, M.make_mutate_fn(p_reinit=0.5)), n_working=4,
                     n_generations=30, reseed_every=10, seed=1)
    while not s.done:
        c = s.ask()
        _tell(s, [toy_cost(g) for g in c], extras=[trajectory(g) for g in c])
        if s.generation == 15:
            state = json.loads(json.dumps(s.state_dict()))
            s2 = SerialSearch(ToyFamily(init, M.make_mutate_fn(p_reinit=0.5)), seed=7)
            s2.load_state_dict(state)
            assert all(np.array_equal(a, b) for a, b in zip(s.extras, s2.extras))
    assert s.history[-1][1] < s.history[0][1]


# -- phases: scores under phased-in terms go stale -------------------------

STYLE = np.array([1.0, 0.0, 0.0])


def phased_cost(g, phase):
    """Phase 0: toy_cost; phase 1 adds a style penalty that most controllers pay."""
    return toy_cost(g) + phase[0] * 20.0 * float(np.sum((g.theta0[:, :1] - STYLE[0]) ** 2))


def run_phased(search, until=None):
    while not search.done and (until is None or search.generation < until):
        phase = search.current_phase()        # the round the candidates are scored in
        cands = search.ask()
        search.tell([phased_cost(g, phase) for g in cands])
    return search


# progress moves in 3 stages over 120 rounds (0, 0.5 from round 40, 1 from round 80);
# the style term is on from progress 0.5
TOY_TASK = SimpleNamespace(phase=lambda p: (0.0 if p < 0.5 else 1.0,), staged=lambda p: ())


def make_phased(seed, **kw):
    return make(seed, task=TOY_TASK, phase_steps=3, **kw)


def test_phase_change_rescores_working_set_and_best():
    s = run_phased(make_phased(3))
    final = (1.0,)
    # every stored score, and the best, is a score of the final phase
    assert [phased_cost(g, final) for g in s.working] == list(s.scores)
    assert phased_cost(s.best_genome, final) == s.best_score
    assert s.best_score <= min(s.scores)
    # one re-score of C + 1 candidates, counted as evaluations
    assert s.evaluations == 6 * 121 + 7
    assert [e for e, _ in s.history][40:42] == [6 * 41, 6 * 41 + 7]
    # no re-score without a phase change, none without a task
    assert run(make(3)).evaluations == 6 * 121


def test_rescore_draws_no_random_numbers_and_keeps_best_when_not_beaten():
    s = make_phased(3)
    run_phased(s, until=40)
    rng_state = s.rng.bit_generator.state
    best = s.best_genome.to_dict()
    cands = s.ask()
    assert s.rescoring and len(cands) == 7 and s.rng.bit_generator.state == rng_state
    s.tell([1e3] * 6 + [5.0])                        # the incumbent stays the best
    assert s.best_genome.to_dict() == best and s.best_score == 5.0
    assert not s.rescoring and list(s.scores) == [1e3] * 6


@pytest.mark.parametrize("stop_between_ask_and_tell", [False, True])
def test_resume_across_a_rescore_is_exact(stop_between_ask_and_tell):
    full = run_phased(make_phased(5))
    part = run_phased(make_phased(5), until=40)
    resumed = restored(part, make_phased(6), stop_between_ask_and_tell)
    assert part.rescoring or not stop_between_ask_and_tell     # the ask began a re-score
    run_phased(resumed)
    assert resumed.history == full.history
    assert resumed.best_genome.to_dict() == full.best_genome.to_dict()


# -- noisy costs (robust starts redrawn every round) ------------------------------

def noisy_cost(g, generation):
    """toy_cost plus the luck of round g's starts, the same for every controller of
    the round: easy starts on even rounds, hard ones on odd rounds."""
    return toy_cost(g) + (3.0 if generation % 2 else -3.0)


def run_noisy(search, until=None, log=None):
    while not search.done and (until is None or search.generation < until):
        gen, rescoring = search.generation, search.working is not None and search._stale()
        cands = search.ask()
        costs = [noisy_cost(g, gen) for g in cands]      # the evaluator's (seed, round) starts
        if log is not None:
            log.append((gen, rescoring, len(cands), min(costs)))
        search.tell(costs)
    return search


def test_fresh_scores_judge_a_mutant_and_its_parent_on_the_same_starts():
    s = make(2, fresh_scores=True, n_generations=40)
    log = []
    run_noisy(s, log=log)
    # round 0's mutants meet the initial scores (round 0's starts); each later round:
    # a re-score of C + 1 at round g, then C mutants at round g
    assert [r[:3] for r in log[:2]] == [(0, False, 6), (0, False, 6)]
    rounds = log[2:]
    assert [(r[1], r[2]) for r in rounds] == [(True, 7), (False, 6)] * 39
    assert all(a[0] == b[0] for a, b in zip(rounds[::2], rounds[1::2]))
    assert s.evaluations == 6 + 6 + 39 * (7 + 6)
    # every stored score is that controller's cost on the last round's starts
    last = s.generation - 1
    assert list(s.scores) == [noisy_cost(g, last) for g in s.working]
    # the best is the last round's (re-scored incumbent or a winner on the same starts),
    # not the luckiest cost of the run
    assert s.best_cost == noisy_cost(s.best, last) == s.best_score <= min(s.scores)
    assert s.row()["best_final"] == s.best_cost
    assert min(r[3] for r in log) < s.best_cost - 1.0     # the luckiest cost told, never the best


def test_stale_scores_let_lucky_parents_block_better_mutants():
    """Without fresh scores a parent keeps the cost of its luckiest round, so
    mutants drawn under worse luck are refused even when they are better."""
    stale, fresh = make(4, n_generations=60), make(4, fresh_scores=True, n_generations=60)
    run_noisy(stale), run_noisy(fresh)
    truth = lambda s: min(toy_cost(g) for g in s.working)   # noqa: E731
    # the stale search's stored scores are far below what its controllers cost on average
    gap = np.mean([sc - toy_cost(g) for g, sc in zip(stale.working, stale.scores)])
    assert gap < -1.0
    assert truth(fresh) < truth(stale)


def test_fresh_scores_resume_exactly_and_are_in_the_checkpoint():
    full = run_noisy(make(5, fresh_scores=True, n_generations=30))
    part = run_noisy(make(5, fresh_scores=True, n_generations=30), until=12)
    assert part.config()["fresh_scores"] is True and "fresh_scores" not in make(5).config()
    resumed = restored(part, make(6, fresh_scores=True, n_generations=30), False)
    run_noisy(resumed)
    assert resumed.history == full.history
    assert resumed.best_cost == full.best_cost and resumed.final.round == full.final.round
    with pytest.raises(ValueError, match="fresh_scores"):
        make(0, fresh_scores="yes")


# -- restarts (restart_after / restart_delta) ----------------------------------------

def _fresh_marker_search(**kw):
    """Marker genomes that say whether they are fresh (random) or mutants."""
    counter = iter(range(10_000))
    fam = ToyFamily(lambda rng: {"id": next(counter), "fresh": True},
                    lambda g, rng, extra: {"id": next(counter), "fresh": False},
                    to_json=dict, from_json=dict)
    return SerialSearch(fam, seed=0, **kw)


def test_restart_replaces_a_stagnant_working_set_and_keeps_the_best():
    s = _fresh_marker_search(n_working=2, n_generations=20, reseed_every=100, restart_after=3)
    s.ask(); s.tell([-1.0, -2.0])                    # initial: mark (0, best -2)
    for _ in range(3):                               # three rounds, no improvement
        assert not any(g["fresh"] for g in s.ask())
        s.tell([0.0, 0.0])
    assert s.generation == 3 and s.restarts == 0
    cands = s.ask()                                  # round 4 is the restart
    assert [g["fresh"] for g in cands] == [True, True] and s.restarting
    s.tell([5.0, 4.0])                               # worse than before: replaces anyway
    assert [g["id"] for g in s.working] == [g["id"] for g in cands]
    assert list(s.scores) == [5.0, 4.0] and s.restarts == 1 and s.generation == 4
    assert s.evaluations == 2 * 5 and s.best_score == -2.0     # best-so-far survives
    assert not any(g["fresh"] for g in s.ask())      # mutants of the new set next


def test_strict_improvement_puts_off_a_restart_and_delta_sets_its_size():
    for delta, restarted in [(0.0, False), (0.5, True)]:
        s = _fresh_marker_search(n_working=1, n_generations=20, reseed_every=100,
                                 restart_after=2, restart_delta=delta)
        s.ask(); s.tell([0.0])
        for cost in (-0.1, -0.2):                    # small steps, each an improvement
            s.ask(); s.tell([cost])
        assert s.ask()[0]["fresh"] is restarted, delta
        assert s.restarting is restarted


def test_restarts_are_off_by_default_and_leave_the_checkpoint_as_before():
    a, b = run(make(3)), run(make(3, restart_after=0))
    assert a.history == b.history and a.restarts == 0
    st = a.state_dict()
    assert "restart" not in st and "restart_after" not in st["config"]
    on = run(make(3, restart_after=5))
    assert on.state_dict()["config"]["restart_after"] == 5 and "restart" in on.state_dict()


def test_restarts_happen_on_the_toy_and_are_deterministic_per_seed():
    a, b, c = (run(make(seed, restart_after=4, restart_delta=0.05)) for seed in (8, 8, 9))
    assert a.restarts > 0
    assert a.history == b.history and a.best_genome.to_dict() == b.best_genome.to_dict()
    assert a.history != c.history
    assert a.evaluations == 6 * 121                  # a restart round costs C, like any round
    best = [x for _, x in a.history]
    assert all(y <= x for x, y in zip(best, best[1:]))


@pytest.mark.parametrize("stop_between_ask_and_tell", [False, True])
def test_restarts_resume_identically(stop_between_ask_and_tell):
    kw = dict(restart_after=4, restart_delta=0.05)
    full = run(make(8, **kw))
    assert full.restarts > 0
    for until in range(1, 120, 7):                  # stops before, in and after restarts
        part = run(make(8, **kw), until=until)
        resumed = restored(part, make(999, n_generations=1), stop_between_ask_and_tell)
        assert resumed.restart_after == 4 and resumed.restart_delta == 0.05
        run(resumed)
        assert resumed.history == full.history and resumed.restarts == full.restarts
        assert resumed.best_genome.to_dict() == full.best_genome.to_dict()


def test_a_phase_rescore_comes_first_and_restarts_the_count():
    """A phase change re-scores before any restart; the re-scored set counts from there."""
    s = make_phased(1, restart_after=1)
    s.ask(); s.tell([phased_cost(g, s.current_phase()) for g in s.pending])
    while not s.done:
        cands = s.ask()
        if s.rescoring:
            assert len(cands) == 7 and not s.restarting
            s.tell([phased_cost(g, s.current_phase()) for g in cands])
            assert s.mark == (s.generation, s._working_best())
        else:
            s.tell([phased_cost(g, s.current_phase()) for g in cands])
    assert s.restarts > 0


@pytest.mark.parametrize("kw, needle", [
    (dict(restart_after=-1), "restart_after"), (dict(restart_after=1.5), "restart_after"),
    (dict(restart_after=2, restart_delta=-0.1), "restart_delta"),
    (dict(restart_after=2, restart_delta=float("nan")), "restart_delta"),
    (dict(restart_delta=0.1), "needs restart_after")])
def test_restart_settings_are_checked(kw, needle):
    with pytest.raises(ValueError, match=needle):
        make(0, **kw)


def test_restart_options_reach_the_serial_search():
    from gpmotion.cli import _run_configs, parser
    args = parser().parse_args(["run", "starman_travel", "--controller", "bsr-time",
                                "--restart-after", "30", "--restart-delta", "0.01",
                                "--generations", "7"])
    (cfg, _), = list(_run_configs(args))
    assert cfg.search == {"restart_after": 30, "restart_delta": 0.01, "n_generations": 7}
    from gpmotion.families import make_family
    from gpmotion.task import get_task
    fam = make_family("bsr-time", get_task("starman_travel"))
    s = fam.make_search(0, **cfg.search)
    assert (s.restart_after, s.restart_delta, s.n_generations) == (30, 0.01, 7)


@pytest.mark.slow
def test_a_run_with_restarts_resumes_to_the_uninterrupted_run(tmp_path):
    """Through the CLI on a tiny Rex walk: restarts happen, and 6 + 6 rounds
    (run, then resume --extend-generations) log what 12 rounds do."""
    import csv
    from gpmotion.cli import main
    args = ["rex_walk", "--controller", "bsr-time", "--segments", "variable", "--t-per", "0.2",
            "--param", "seconds=0.2", "--param", "hold=0.1", "--working", "4", "--quiet",
            "--no-artifacts", "--restart-after", "2", "--threads", "1"]
    a, b = tmp_path / "a", tmp_path / "b"
    assert main(["run", *args, "--generations", "12", "--out", str(a)]) == 0
    assert main(["run", *args, "--generations", "6", "--out", str(b)]) == 0
    assert main(["resume", str(b), "--extend-generations", "6", "--quiet"]) == 0
    keep = ("generation", "evaluations", "best_so_far", "gen_min", "gen_median", "gen_max")
    rows = [[{k: r[k] for k in keep} for r in csv.DictReader(open(d / "log.csv"))] for d in (a, b)]
    assert rows[0] == rows[1] and len(rows[0]) == 13
    state = json.loads((a / "checkpoint.json").read_text())["search"]
    assert state["config"]["restart_after"] == 2 and state["restart"]["restarts"] > 0
