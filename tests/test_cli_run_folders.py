"""Where runs go and how they are read back: a preset's run has its own default
folder; a series folder is listed (replay, render, export as resume); a record
whose task is unknown says how to load it."""
import json

from gpmotion.cli import main

SMALL = ["--param", "seconds=0.2", "--population", "4", "--generations", "1", "--no-artifacts"]


def test_a_presets_run_does_not_collide_with_the_default_run(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["run", "lamp_hop", *SMALL]) == 0
    assert main(["run", "lamp_hop", "--preset", "gritz-hahn", *SMALL]) == 0
    assert (tmp_path / "runs" / "lamp_hop-gp-seed0" / "best.json").exists()
    assert (tmp_path / "runs" / "lamp_hop-gp-gritz-hahn-seed0" / "best.json").exists()


def test_commands_that_read_a_run_list_the_runs_of_a_series(tmp_path, capsys):
    series = tmp_path / "s"
    assert main(["run", "lamp_hop", "--seeds", "2", "--out", str(series), *SMALL]) == 0
    capsys.readouterr()
    for verb, extra in (("replay", []), ("render", ["-o", str(tmp_path / "x.png")]),
                        ("export", ["--bvh", str(tmp_path / "x.bvh")])):
        assert main([verb, str(series), *extra]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith(f"gpmotion: error: {series} is a series of 2 runs; {verb} each: ")
        assert f"gpmotion {verb} {series / 'seed0'}" in err and "cannot read" not in err
    assert not (tmp_path / "x.png").exists() and not (tmp_path / "x.bvh").exists()


def test_an_unknown_task_says_to_pass_the_plugin_folder(tmp_path, capsys):
    run = tmp_path / "r"
    assert main(["run", "lamp_hop", "--out", str(run), *SMALL]) == 0
    rec = json.loads((run / "best.json").read_text())
    rec["task"] = "lamp_reach-v1"                 # as a task a script registered
    (run / "best.json").write_text(json.dumps(rec))
    capsys.readouterr()
    assert main(["replay", str(run)]) == 2
    err = capsys.readouterr().err
    assert "unknown task 'lamp_reach-v1'" in err and "pass --plugins DIR" in err
    assert "not a controller record" not in err
