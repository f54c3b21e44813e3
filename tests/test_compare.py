"""Phase-aware scores on a real task, and compare's figure agreeing with its table."""
import csv
import json

import numpy as np
import pytest

from gpmotion.compare import compare, phase_window, replot
from gpmotion.inprocess import InProcessEvaluator
from gpmotion.families import make_family
from gpmotion.replay import load_controller, replay_genome
from gpmotion.search.serial import serial_generations, serial_rescores
from gpmotion.task import get_task

SHORT = {"seconds": 0.3}


def _drive(search, ev):
    rows = []
    while not search.done:
        result = ev.evaluate(search.ask(), search.progress)
        search.tell(result)
        rows.append(search.row())
    return rows


def test_serial_working_set_holds_final_weight_scores():
    """lamp_hop's style terms phase in: at the end every stored cost is the
    controller's cost at full weight, and the returned best is the best ever
    evaluated under it (the old search kept costs from progress 0)."""
    task = get_task("lamp_hop", **SHORT)
    fam = make_family("bsr-time", task)
    s = search = fam.make_search(0, n_working=4, n_generations=30, phase_steps=6)
    ev = InProcessEvaluator(task, fam, "pd")
    rows = _drive(search, ev)
    full = ev.evaluate(list(s.working) + [s.best_genome, search.best], 1.0).costs
    assert np.array_equal(full[:4], s.scores)
    assert full[4] == s.best_score == min(s.scores.min(), full[4])
    assert full[5] == search.best_cost == search.best_final <= s.best_score
    finals = [r["best_final"] for r in rows]
    assert all(b <= a for a, b in zip(finals, finals[1:])) and finals[-1] == search.best_final
    assert rows[-1]["best_so_far"] == search.best_final      # final phase: the same weights
    assert s.evaluations == 4 * 31 + 5 * (len(set(task.phase(k / 5) for k in range(6))) - 1)


def test_gp_rows_carry_current_and_final_best():
    task = get_task("lamp_hop", **SHORT)
    fam = make_family("gp", task)
    search = fam.make_search(1, population=12, generations=8)
    ev = InProcessEvaluator(task, fam, "pd")
    rows = _drive(search, ev)
    finals = [r["best_final"] for r in rows]
    assert all(b <= a for a, b in zip(finals, finals[1:]))
    assert all(r["best_final"] <= r["best_so_far"] + 1e-12 or r["progress"] < 1 for r in rows)
    _, costs, _, _ = replay_genome(task, fam, "pd", search.best)
    assert costs[0] == finals[-1] == search.best_cost


def test_curriculum_final_best_unknown_until_final_scene():
    task = get_task("lamp_limbo", seconds=0.3)
    fam = make_family("bsr-time", task)
    search = fam.make_search(0, n_working=3, n_generations=20, phase_steps=5)
    ev = InProcessEvaluator(task, fam, "pd")
    rows = _drive(search, ev)
    unknown = [r for r in rows if r["best_final"] == ""]
    assert unknown and all(task.staged(r["progress"]) != task.staged(1.0) for r in unknown)
    _, costs, _, _ = replay_genome(task, fam, "pd", search.best)
    assert costs[0] == rows[-1]["best_final"] == search.best_cost


def test_serial_budget_counts_rescores():
    task = get_task("lamp_hop")
    g = serial_generations(task, 3000, 10)
    used = 10 * (1 + g) + 11 * serial_rescores(task, g, 20)
    assert used <= 3000 < used + 10 + 11


@pytest.mark.slow
def test_compare_curves_end_at_the_table(tmp_path):
    _check_compare(tmp_path, budget=240)


def test_compare_curves_end_at_the_table_small(tmp_path):
    _check_compare(tmp_path, budget=60)


def _check_compare(tmp_path, budget):
    out = tmp_path / "c"
    rows, _ = compare("lamp_hop", ["gp", "bsr-time"], 2, budget, out, params=SHORT,
                      population=10, quiet=True)
    table = {r["controller"]: r for r in csv.DictReader(open(out / "compare.csv"))}
    curves = list(csv.DictReader(open(out / "curves.csv")))
    runs = json.loads((out / "runs.json").read_text())["runs"]
    for fam in ("gp", "bsr-time"):
        mine = [r for r in curves if r["controller"] == fam]
        last = mine[-1]
        for q in ("q25", "median", "q75"):
            assert float(last[q]) == float(table[fam][f"cost_{q}" if q != "median" else "cost_median"])
        med = [float(r["median"]) for r in mine if r["median"] != "nan"]
        assert all(b <= a for a, b in zip(med, med[1:]))
        for r in (r for r in runs if r["family"] == fam):
            assert r["curve"][-1][1] == r["final_cost"] and r["evaluations"] <= budget
            task, family, act, genome, rec = load_controller(out / "best" / f"{fam}-seed{r['seed']}.json")
            _, costs, _, _ = replay_genome(task, family, act, genome)
            assert costs[0] == rec["cost"] == r["final_cost"]
    assert (out / "curves.png").stat().st_size > 1000
    plotted = (out / "curves.csv").read_text()
    replot(out)                                   # the same curves from runs.json alone
    assert (out / "curves.csv").read_text() == plotted
    with pytest.raises(ValueError, match="--force"):
        compare("lamp_hop", ["gp"], 1, budget, out, params=SHORT, quiet=True)
    compare("lamp_hop", ["gp"], 1, 30, out, params=SHORT, population=10, quiet=True, force=True)


def test_phase_window():
    assert phase_window(get_task("lamp_hop")) == (0.1, 0.8)
    assert phase_window(get_task("lamp_limbo"))[0] == 0.1


def test_the_table_says_how_many_runs_found_a_solver_beside_the_best_controllers_success():
    """A run can meet a solver its best by cost is not (Cujo's GP): the
    table must not show a median of first solvers under a 0 % success without the count."""
    from gpmotion.compare import summarize, table_markdown
    runs = [{"family": "gp", "seed": s, "final_cost": -1.0, "success": False, "wall_s": 1.0,
             "first_success": f} for s, f in enumerate([None, 8444, None, 5764, None])]
    row, = summarize(runs)
    assert row["success_rate"] == 0.0 and row["runs_with_solver"] == 2
    line = table_markdown([row]).splitlines()[2]
    assert "| 0% | 2 / 5: 7,104 |" in line
    none = [dict(r, first_success=None) for r in runs]
    assert "| 0% | 0 / 5 |" in table_markdown(summarize(none)).splitlines()[2]
