"""benchmarks/creatures_3d.py: a bad run path is one line and exit 2, not a traceback."""
import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _bench():
    spec = importlib.util.spec_from_file_location("creatures_3d", ROOT / "benchmarks" / "creatures_3d.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_steps_of_a_missing_run_is_one_line_and_exit_2(tmp_path, capsys):
    missing = tmp_path / "nowhere" / "best.json"
    assert _bench().main(["steps", "--task", "bob_walk-v3", str(missing)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(missing) in err[0] and "Traceback" not in err[0]


def test_steps_of_a_file_that_is_not_a_record_is_one_line_and_exit_2(tmp_path, capsys):
    bad = tmp_path / "best.json"
    bad.write_text("{not json")
    assert _bench().main(["steps", "--task", "bob_walk-v3", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(bad) in err[0]


def test_multistart_chooses_each_seeds_best_search_by_cost_and_resumes(tmp_path, capsys):
    bench, out = _bench(), tmp_path / "ms"
    argv = ["multistart", "rex_walk", "--starts", "2", "--seeds", "1", "--first-seed", "1",
            "--budget", "20", "--t-per", "0.4", "--workers", "1", "--out", str(out)]
    assert bench.main(argv) == 0
    text = capsys.readouterr().out
    import json
    runs = [json.loads(line) for line in (out / "starts.jsonl").read_text().splitlines()]
    assert sorted(r["seed"] for r in runs) == [2, 3]                 # seed 1 of 2 starts: 2 and 3
    best = min(runs, key=lambda r: r["cost"])
    assert f"| 1 | " in text and f"| {best['seed']} | {'yes' if best['success'] else 'no'} |" in text
    assert all(r["options"]["t_per"] == 0.4 and r["evaluations"] == 20 for r in runs)
    assert bench.main(argv) == 0                                       # nothing left to run
    assert "search seed" not in capsys.readouterr().out
    assert len((out / "starts.jsonl").read_text().splitlines()) == 2


def test_multistart_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    bench = _bench()
    assert bench.main(["multistart", "no_such_task", "--out", str(tmp_path)]) == 2
    assert bench.main(["multistart", "rex_walk", "--starts", "0", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and all(line.startswith("creatures_3d.py: ") for line in err)


SEQ = ROOT / "gpmotion" / "studies" / "creatures" / "controllers" / "rex-sequence-seed0-{}.json"


def test_judge_gives_the_recorded_sequence_its_verdict(capsys):
    """A completed walk → turn → walk of the creatures study, judged from its controllers."""
    import json
    assert _bench().main(["judge", *(str(SEQ).format(s) for s in ("walk", "turn", "walk2"))]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["completes"] and got["fell"] == [False, False, False]
    assert round(got["walk_m"], 2) == 1.58 and round(got["turn_deg"]) == 90 and round(got["walk2_m"], 2) == 1.06


def test_judge_of_a_missing_controller_is_one_line_and_exit_2(tmp_path, capsys):
    walk, walk2 = str(SEQ).format("walk"), str(SEQ).format("walk2")
    assert _bench().main(["judge", walk, str(tmp_path / "no.json"), walk2]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no.json" in err[0]


def test_sequence_runs_the_three_stages_with_their_own_settings(tmp_path, capsys):
    """The walk is the cheapest of --starts searches, each stage gets its own
    t_per and the second walk its own budget; the turn is rex_turn-v3."""
    import json
    out = tmp_path / "seq"
    argv = ["sequence", "--seed", "1", "--starts", "2", "--budget", "20", "--budget-walk2", "30",
            "--t-per", "0.4,0.5,0.3", "--out", str(out)]
    assert _bench().main(argv) == 0
    rep = json.loads((out / "sequence.json").read_text())
    walk = rep["walk"]
    assert [s["seed"] for s in walk["starts"]] == [2, 3]
    assert walk["cost"] == min(s["cost"] for s in walk["starts"]) and walk["seed"] in (2, 3)
    assert [rep[k]["task"] for k in ("walk", "turn", "walk2")] == ["rex_walk-v2", "rex_turn-v3", "rex_walk-v2"]
    assert [rep[k]["evaluations"] for k in ("walk", "turn", "walk2")] == [20, 20, 30]
    assert rep["composite"]["t_per"] == [0.4, 0.5, 0.3] and rep["turn"]["seed"] == 1
    assert json.loads((out / "walk.json").read_text())["seed"] == walk["seed"]


def test_sequence_bad_t_per_is_one_line_and_exit_2(tmp_path, capsys):
    import pytest
    with pytest.raises(SystemExit) as e:
        _bench().main(["sequence", "--t-per", "0.4,0.5", "--out", str(tmp_path)])
    assert e.value.code == 2
    assert "three" in capsys.readouterr().err


def test_steps_replays_a_controller_on_the_figure_variant_it_was_searched_on(tmp_path, capsys):
    """A Bob whose waist also twists has 11 driven joints: replayed on the plain
    Bob (as before) its controller was a traceback, now it is its own row."""
    import numpy as np

    import gpmotion
    from gpmotion.controller_file import save_controller
    from gpmotion.families import make_family
    spec = tmp_path / "bob_twist.toml"
    spec.write_text('extends = "bob"\nname = "bob_twist"\n[[joints]]\nname = "waist"\naxes = "zyx"\n'
                    'limits = [[-0.35, 0.35], [-0.17, 0.17], [-0.1, 0.1]]\n')
    task = gpmotion.get_task("bob_walk-v3", figure=str(spec), seconds=0.5)
    fam = make_family("bsr-time", task, segments="variable", t_per=0.5)
    assert len(task.controlled_actuators()) == 11
    save_controller(tmp_path / "best.json", task, fam.random(np.random.default_rng(0)), family=fam)
    assert _bench().main(["steps", "--task", "bob_walk-v3", str(tmp_path / "best.json")]) == 0
    assert "| bob_walk-v3 |" in capsys.readouterr().out


def test_speed_reports_the_period_it_searched_with(capsys):
    assert _bench().main(["speed", "--budget", "20", "--t-per", "0.5"]) == 0
    assert "t_per 0.5 s" in capsys.readouterr().out
    assert _bench().FAMILY_OPTIONS["rex_walk"]["bsr-time"]["t_per"] == 0.4     # the best measured
