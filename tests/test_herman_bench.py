"""benchmarks/herman_success.py: resumes per run, tabulates from its file."""
import importlib.util
import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture()
def bench():
    spec = importlib.util.spec_from_file_location("herman_success", ROOT / "benchmarks" / "herman_success.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_benchmark_runs_only_what_its_file_lacks_and_tables_the_file(bench, tmp_path, monkeypatch, capsys):
    out = tmp_path / "runs.jsonl"
    out.write_text(json.dumps({"config": "touch_nose", "seed": 0, "success": True, "wall_s": 80.0,
                               "cpu_s": 150.0, "load": 1.5, "final_cost": 0.1, "facts": []}) + "\n")   # no main_cpu_s: an older row
    calls = []

    def fake(name, seed, tmp=None, targets=None, search=None, family=None, params=None):
        calls.append((name, seed))
        assert (targets, search, family, params) == (None, {}, {}, {})      # no overrides given
        first = 30.0 + 10 * seed if seed != 2 else None
        return {"config": name, "seed": seed, "success": seed != 2, "wall_s": 70.0 + seed, "cpu_s": 100.0,
                "main_cpu_s": 50.0 + 25 * seed, "load": 2.0, "final_cost": 0.2,
                "first_solved_gen": None if first is None else 9, "first_solved_main_cpu_s": first,
                "facts": ["x"]}

    monkeypatch.setattr(bench, "run_one", fake)
    assert bench.main(["--seeds", "3", "--only", "touch_nose,point", "--out", str(out)]) == 0
    assert calls == [("point", 0), ("touch_nose", 1), ("point", 1), ("touch_nose", 2), ("point", 2)]
    table = capsys.readouterr().out
    # wall: medians of 80, 71, 72; main-thread CPU 75, 100 (the old row has none): one over 90 s
    # first solver: the old row has no such field (-); point's seeds 0, 1 at 30, 40 s, seed 2 none
    assert "| touch_nose | 2 / 3 | 72 | 80 | 88 [75, 100] | 1 | - | 1.5–2.0 |" in table
    assert "| point | 2 / 3 | 71 | 72 | 75 [50, 100] | 1 | 2 / 3: 35 [40] | 2.0–2.0 |" in table
    assert len(out.read_text().splitlines()) == 6
    calls.clear()
    bench.main(["--seeds", "3", "--only", "touch_nose,point", "--out", str(out)])
    assert calls == []                                       # all there: nothing re-run


def test_first_solver_is_the_first_log_row_with_a_solving_genome(bench, tmp_path):
    log = tmp_path / "log.csv"
    log.write_text("generation,solved,elapsed_s\n0,0,10.0\n1,0,20.0\n2,3,40.0\n3,0,50.0\n")
    # main-thread CPU scaled by the row's share of the run's wall time: 50 * 40 / 100
    assert bench.first_solver(log, wall=100.0, main=50.0) == {
        "first_solved_gen": 2, "first_solved_wall_s": 40.0, "first_solved_main_cpu_s": 20.0}
    log.write_text("generation,solved,elapsed_s\n0,0,10.0\n1,0,20.0\n")
    assert bench.first_solver(log, wall=100.0, main=50.0)["first_solved_gen"] is None


def test_first_solver_counts_no_genome_that_solved_a_curriculums_easier_scene(bench, tmp_path):
    """herman_reach_standing-v4 moves its object over the first 70 % of a run:
    a solver at progress 0.2 solved a scene the task does not ask for."""
    from gpmotion.task import get_task
    task = get_task("herman_reach_standing")
    assert task.curriculum
    log = tmp_path / "log.csv"
    log.write_text("generation,progress,solved,elapsed_s\n0,0.0,0,10.0\n1,0.2,4,20.0\n"
                   "2,0.6,0,40.0\n3,0.8,1,50.0\n")
    assert bench.first_solver(log, wall=100.0, main=50.0)["first_solved_gen"] == 1     # no task
    assert bench.first_solver(log, wall=100.0, main=50.0, task=task)["first_solved_gen"] == 3


def test_benchmark_names_every_task_and_preset_of_the_bar_and_refuses_unknown(bench, tmp_path, capsys):
    from gpmotion.task import get_task
    assert set(bench.CONFIGS) == {"touch_nose", "touch_object/0", "touch_object/1", "touch_object/2",
                                  "point", "wave", "reach_standing"}
    for task, params in {**bench.CONFIGS, **bench.EXTRA}.values():
        get_task(task, **params)                             # each builds
    assert bench.main(["--only", "bogus", "--out", str(tmp_path / "x.jsonl")]) == 2
    assert "bogus" in capsys.readouterr().err


def test_benchmark_measures_how_far_a_saved_controller_crosses_the_trunk(bench, tmp_path):
    """crossing_cm replays best.json and takes limbs_overlap's deepest frame."""
    from gpmotion.replay import load_controller, replay_genome
    from gpmotion.run import RunConfig, run
    from gpmotion.tasks._herman import limbs_overlap
    out = tmp_path / "run"
    run(RunConfig(task="herman_touch", seed=0, params={"seconds": 0.3},
                  search={"population": 8, "generations": 1}), out, quiet=True, artifacts=False)
    task, fam, act, genome, _ = load_controller(out / "best.json")
    traj = replay_genome(task, fam, act, genome)[0]
    assert bench._crossing(out / "best.json") == float(limbs_overlap(traj).max()) >= 0.0
