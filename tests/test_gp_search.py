"""GPSearch (Gritz-Hahn GP, ask/tell) and the DEAP toolbox.

Most tests use a toy objective on the lamp_hop primitive set (no simulator):
cost = |tree 0 evaluated on a fixed sense vector - 0.5|.
"""
import json
import random

import numpy as np
import pytest
from deap import gp

from gpmotion.families import make_family
from gpmotion.gp.bytecode import tokens_to_tree
from gpmotion.gp.pset import compile_reference
from gpmotion.gp.operators import (adjusted_fitness, creep_constants, crossover_same_dof,
                                 make_tree_operators, roulette_indices)
from gpmotion.search.gp import GPSearch
from gpmotion.task import get_task

TAGS = ("px", "pz", "vx")          # lamp has 3 actuators: one tag terminal per DOF


@pytest.fixture(scope="module")
def family():
    return make_family("gp", get_task("lamp_hop", seconds=0.5))


def senses_for(family):
    names = family.task.figure.sense_names
    return np.linspace(-0.9, 1.3, len(names))


def toy_costs(family, genomes):
    s = senses_for(family)
    return [abs(compile_reference(tokens_to_tree(g[0], family.info), family.info)(s) - 0.5)
            for g in genomes]


def run(search, family, until=None, between=None):
    while not search.done and (until is None or search.generation < until):
        genomes = search.ask()
        if between:
            between()
        search.tell(toy_costs(family, genomes))
    return search


def make(family, seed=0, **kw):
    kw = {"population": 30, "generations": 12, "init_depth": (1, 4), **kw}
    return GPSearch(family, seed=seed, **kw)


def tagged_tokens(rng, tag, depth):
    """Random prefix tokens using only the terminal ``tag`` (and no constants)."""
    if depth == 0 or rng.random() < 0.3:
        return [tag]
    op = rng.choice(["add", "sub", "mul", "sin"])
    kids = 1 if op == "sin" else 2
    return [op] + [tok for _ in range(kids) for tok in tagged_tokens(rng, tag, depth - 1)]


def tagged_state(search, family, seed=0):
    """The search's state with a population whose DOF-d trees use only TAGS[d]."""
    rng = random.Random(seed)
    state = search.state_dict()
    state["population"] = [family.to_json([["add"] + tagged_tokens(rng, t, 3) + [t] for t in TAGS])
                           for _ in range(search.population_size)]
    return state


def terminals_of(tokens, family):
    return {t for t in tokens if isinstance(t, float) or t in family.info.terminal_names}


# ---------------------------------------------------------------- variation

def test_crossover_only_mixes_trees_of_the_same_dof(family):
    cx, _ = make_tree_operators(family.pset, 17, 200)
    rng = random.Random(1)
    random.seed(3)
    changed = set()
    for _ in range(200):
        a = [tokens_to_tree(["add"] + tagged_tokens(rng, t, 3) + [t], family.info) for t in TAGS]
        b = [tokens_to_tree(["mul"] + tagged_tokens(rng, t, 3) + [t], family.info) for t in TAGS]
        before = [list(map(str, x)) for x in a + b]
        a, b, d = crossover_same_dof(a, b, cx)
        changed.add(d)
        for dof, tag in enumerate(TAGS):
            for ind in (a, b):
                names = {n.value for n in ind[dof] if isinstance(n, gp.Terminal)}
                assert names == {tag}, (dof, names)
        after = [list(map(str, x)) for x in a + b]
        assert [i % 3 for i in range(6) if before[i] != after[i]] in ([], [d], [d, d])
    assert changed == {0, 1, 2}


def test_creep_moves_only_the_constants_of_one_tree(family):
    ind = [tokens_to_tree(["add", t, 0.5 + d], family.info) for d, t in enumerate(TAGS)]
    ind.append(tokens_to_tree(["px"], family.info))          # a tree without constants
    random.seed(4)
    steps, seen = [], set()
    for _ in range(300):
        out, d = creep_constants(list(ind), sigma=0.1)
        seen.add(d)
        for k, (a, b) in enumerate(zip(ind, out)):
            if k != d:
                assert b is a                                    # other trees untouched
        assert [str(n) for n in out[d]][:2] == [str(n) for n in ind[d]][:2]   # shape kept
        steps.append(out[d][2].value - ind[d][2].value)
    assert seen == {0, 1, 2}
    assert abs(np.mean(steps)) < 0.02 and np.std(steps) == pytest.approx(0.1, rel=0.15)
    assert creep_constants([ind[3]], 0.1) == ([ind[3]], None)


def test_creep_refines_a_constant_that_crossover_cannot(family):
    # cost = |tree 0 - 0.5| is exactly what a constant step helps; without
    # creep the search has only the constants it drew at random
    def best(p_creep):
        return run(make(family, seed=5, population=20, generations=15, p_creep=p_creep,
                        p_crossover=0.6, init_depth=(0, 1)), family).best_cost
    assert best(0.3) < best(0.0)


def test_search_keeps_dof_trees_apart(family):
    s = make(family, p_mutation=0.0, generations=6)
    s.load_state_dict(tagged_state(s, family))
    while not s.done:
        g = s.ask()
        s.tell([len(x[0]) + 0.1 * len(x[1]) for x in g])
        for ind in s.population:
            for dof, tag in enumerate(TAGS):
                assert terminals_of(ind[dof], family) == {tag}


def test_offspring_respect_depth_and_size_limits(family):
    s = make(family, max_depth=5, max_size=25, init_depth=(2, 4), p_crossover=0.7, p_mutation=0.3,
             generations=15)
    while not s.done:
        g = s.ask()
        s.tell([1.0 / (1 + sum(map(len, x))) for x in g])      # pressure to bloat
        for ind in s.population:
            trees = [tokens_to_tree(t, family.info) for t in ind]
            assert all(t.height <= 5 and len(t) <= 25 for t in trees)
    assert max(h["max_tree_depth"] for h in s.history) == 5        # the limit did bind


def test_elitism_keeps_the_best(family):
    s = make(family, elitism=3, generations=8)
    while not s.done:
        before = s.population
        order = np.argsort(toy_costs(family, before), kind="stable")[:3]
        s.tell(toy_costs(family, s.ask()))
        if not s.done:
            assert s.population[:3] == [before[i] for i in order]
    best = [h["best_so_far"] for h in s.history]
    assert all(b2 <= b1 for b1, b2 in zip(best, best[1:]))


def test_roulette_is_fitness_proportionate():
    costs = [0.0, 1.0, 3.0]                     # adjusted fitness 1, 1/2, 1/4
    random.seed(0)
    counts = np.bincount(roulette_indices(costs, 7000), minlength=3) / 7000
    assert np.allclose(counts, adjusted_fitness(costs) / adjusted_fitness(costs).sum(), atol=0.02)


# ------------------------------------------------------------ determinism

def test_same_seed_identical_whatever_global_random_does(family):
    random.seed(123)
    outer = random.getstate()
    a = run(make(family, seed=7), family)
    assert random.getstate() == outer             # the search leaves `random` alone
    b = run(make(family, seed=7), family, between=lambda: random.seed(random.random()))
    c = run(make(family, seed=8), family)
    assert a.history == b.history and a.best == b.best and a.best_cost == b.best_cost
    assert a.population == b.population
    assert a.history != c.history
    assert [h["generation"] for h in a.history] == list(range(12)) and a.generation == 12
    assert a.history[0]["progress"] == 0.0 and a.history[-1]["progress"] == 1.0


@pytest.mark.parametrize("stop_between_ask_and_tell", [False, True])
def test_state_dict_resumes_identically(family, stop_between_ask_and_tell):
    full = run(make(family, seed=5, p_mutation=0.1), family)
    part = run(make(family, seed=5, p_mutation=0.1), family, until=5)
    if stop_between_ask_and_tell:
        asked = part.ask()
    state = json.loads(json.dumps(part.state_dict(), allow_nan=False))
    resumed = make(family, seed=99, population=4, generations=1)   # the state wins
    resumed.load_state_dict(state)
    if stop_between_ask_and_tell:
        assert resumed.ask() == asked
    run(resumed, family)
    assert resumed.history == full.history
    assert resumed.best == full.best and resumed.generation_best == full.generation_best
    assert resumed.population == full.population
    with pytest.raises(ValueError, match="checkpoint"):
        resumed.load_state_dict({"format": "other"})


def test_toy_objective_improves(family):
    s = run(make(family, seed=2, population=40, generations=15,
                 init_depth=(2, 3), p_mutation=0.05), family)
    assert s.best_cost < s.history[0]["min"] and s.best_cost < 0.01
    assert toy_costs(family, [s.best])[0] == pytest.approx(s.best_cost)


# ------------------------------------------------------- caching and phases

def test_costs_reused_only_within_an_unchanged_phase(family):
    # lamp_hop's style ramps end at progress 0.8: generations 8..10 (of 0..10) share a phase
    s = make(family, generations=11, population=20)
    asked, prev = [], set()
    while not s.done:
        g = s.ask()
        assert len(set(map(str, g))) == len(g)                  # no duplicates asked
        asked.append(len(g))
        if s.generation in (9, 10):
            assert not prev & set(map(str, g))                  # known costs reused
        told = s.population
        s.tell(toy_costs(family, g))
        assert s.generation_best[-1]["cost"] == pytest.approx(min(toy_costs(family, told)))
        prev = set(map(str, told))
    assert asked[9] < 20 and asked[10] < 20
    assert s.evaluations == sum(asked) == s.history[-1]["evaluations"]
    # across a phase change every individual is re-scored, and the hall of fame
    # is then the best under the final (full) score
    assert s.phase_of(10) == s.phase_of(8) != s.phase_of(7)
    assert s.best_generation >= 8

    t = make(family, generations=11, population=20, reuse_costs=False)
    run(t, family)
    assert t.history[-1]["evaluated"] == len(set(map(str, t.population)))
    assert t.evaluations > s.evaluations


def test_bad_arguments_raise_one_clear_error(family):
    for kw, msg in [({"population": 1}, "population"), ({"p_crossover": 0.95, "p_mutation": 0.1},
                    "p_crossover"), ({"selection": "rank"}, "selection"),
                    ({"elitism": 50}, "elitism"), ({"max_depth": 30}, "max_depth"),
                    ({"init_depth": (5, 2)}, "init_depth"), ({"seed": None}, "seed"),
                    ({"p_creep": 0.5}, "p_creep"), ({"creep_sigma": 0.0}, "creep_sigma")]:
        with pytest.raises(ValueError, match=msg):
            GPSearch(family, **{"seed": 0, "population": 20, **kw})
    s = make(family, selection="tournament", tournament_size=3, generations=2)
    run(s, family)
    with pytest.raises(RuntimeError):
        s.ask()


# ------------------------------------------------------------ DEAP toolbox

def test_easimple_with_the_toolbox_on_lamp_hop():
    from deap import algorithms, tools

    from gpmotion.toolbox import make_toolbox
    task = get_task("lamp_hop", seconds=0.3)
    tb = make_toolbox(task, generations=2)
    random.seed(0)
    pop = tb.population(n=12)
    assert all(len(ind) == 3 and hasattr(ind, "fitness") for ind in pop)
    hof = tools.HallOfFame(1)
    pop, log = algorithms.eaSimple(pop, tb, cxpb=0.9, mutpb=0.1, ngen=2, halloffame=hof,
                                   verbose=False)
    assert all(ind.fitness.valid and np.isfinite(ind.fitness.values[0]) for ind in pop)
    assert tb.batches == 3 and tb.progress == 1.0
    (cost,) = tb.evaluate(hof[0])
    assert np.isfinite(cost)


def test_islands_breed_apart_and_migrate_around_a_ring(family):
    s = make(family, population=30, islands=3, migrants=2, migrate_every=2, generations=6,
             p_mutation=0.0)
    s.load_state_dict(tagged_state(s, family))
    # island k's DOF-0 trees use only terminal TAGS[k]: without migration they stay apart
    state = s.state_dict()
    state["population"] = [family.to_json([[TAGS[i // 10]]] * 3) for i in range(30)]
    s.load_state_dict(state)
    g = s.ask()
    s.tell([0.0 if x[0] == [TAGS[0]] else 1.0 for x in g])          # generation 0 -> 1: no migration
    assert [ind[0] for ind in s.population] == [[TAGS[i // 10]] for i in range(30)]
    g = s.ask()
    s.tell([0.0 if x[0] == [TAGS[0]] else 1.0 for x in g])          # 1 -> 2: migration
    tags = [ind[0][0] for ind in s.population]
    islands = [set(tags[k * 10:(k + 1) * 10]) for k in range(3)]
    for k in range(3):                         # island k took migrants from island k-1 only
        assert islands[k] <= {TAGS[k], TAGS[k - 1]}
    assert TAGS[0] in islands[1]               # a cost-0 migrant is island 1's elite


def test_one_island_is_the_plain_search(family):
    a = run(make(family, seed=3), family)
    b = run(make(family, seed=3, islands=1, migrants=0), family)
    assert a.population == b.population and a.best == b.best


# ------------------------------------------------- noisy costs (robust starts)

def run_noisy(search, family):
    """Toy costs plus the luck of each generation's starts: easy on even
    generations, hard on odd ones (the same for every individual)."""
    lowest = []
    while not search.done:
        luck = -1.0 if search.generation % 2 == 0 else 1.0
        costs = [c + luck for c in toy_costs(family, search.ask())]
        lowest.append(min(costs))
        search.tell(costs)
    return lowest


def test_fresh_scores_keep_the_last_generations_best_not_the_luckiest(family):
    kw = dict(generations=10, population=20, reuse_costs=False, seed=3)    # the last (9) is hard
    stale, fresh = make(family, **kw), make(family, fresh_scores=True, **kw)
    lowest = run_noisy(stale, family)
    assert run_noisy(fresh, family) == lowest                  # the same search, only the best differs
    last = fresh.generation_best[-1]
    assert fresh.best_cost == last["cost"] == lowest[-1] and fresh.best == last["genome"]
    assert last["cost"] > min(lowest) + 1.0
    assert stale.best_cost == min(lowest)                     # without: the luckiest cost of the run
    assert fresh.config()["fresh_scores"] is True and "fresh_scores" not in stale.config()
    state = json.loads(json.dumps(fresh.state_dict(), allow_nan=False))
    again = make(family, seed=0)
    again.load_state_dict(state)
    assert again.fresh_scores and again.final.per_round and again.best_cost == fresh.best_cost
    with pytest.raises(ValueError, match="reuse_costs"):
        make(family, fresh_scores=True)


def test_polish_tunes_the_best_instead_of_breeding(family):
    # the toy wants tree 0 = 0.5 on fixed senses: an output bias closes any offset
    plain = run(make(family, seed=3, generations=8), family)
    s = make(family, seed=3, generations=8, polish=4)
    run(s, family, until=4)
    assert s.history == plain.history[:4]            # the same GP until the polish starts
    best_before = s.hof_cost
    run(s, family)
    polish_rows = s.history[4:]
    # each polish generation is the previous best plus variations of it: never worse
    assert all(b["min"] <= a["min"] for a, b in zip(s.history[3:], polish_rows))
    assert s.best_cost <= best_before and s.best_cost < plain.best_cost
    assert s.config()["polish"] == 4 and "polish" not in plain.config()
    resumed = make(family, seed=3, generations=8, polish=4)
    run(resumed, family, until=6)
    again = make(family, seed=9, generations=8, polish=4)
    again.load_state_dict(json.loads(json.dumps(resumed.state_dict())))
    run(again, family)
    assert again.history == s.history and again.best == s.best
    with pytest.raises(ValueError, match=r"polish must be an integer in \[0, generations\)"):
        make(family, generations=8, polish=8)


def test_a_tasks_polish_keeps_its_share_of_the_generations():
    fam = make_family("gp", get_task("herman_touch_object"))       # its default: 10 of 50
    assert fam.make_search(0).config()["polish"] == 10
    assert fam.make_search(0, generations=5).config()["polish"] == 1
    assert "polish" not in fam.make_search(0, generations=1).config()    # no room: none
    assert fam.make_search(0, generations=20, polish=3).config()["polish"] == 3   # the user's wins
    with pytest.raises(ValueError, match="polish must be"):
        fam.make_search(0, generations=5, polish=5)


def test_polish_keeps_the_searchs_size_and_depth_limits(family):
    # tight limits: an output bias or a new subtree would pass them (9 nodes, depth 2 without)
    s = run(make(family, seed=4, generations=10, polish=8, max_size=3, max_depth=1,
                 init_depth=(0, 1)), family)
    assert s.generation == 10
    for ind in s._pop:                                # the last polish generation's trees
        for tree in ind:
            assert len(tree) <= 3 and tree.height <= 1
