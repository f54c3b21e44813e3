"""`gpmotion compose` (also `python -m gpmotion.compose`): exit codes and outputs."""
import json

import pytest

from gpmotion.cli.compose import main
from tests.test_composite import write_controller


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("cli")
    write_controller(d / "a.json")
    write_controller(d / "b.json", family="bsr-time", seed=1)
    (d / "good.motion").write_text("phase one = dcm_x * (dtime ~= 0.5)\nphase two = max_t(cm_z)\n"
                                   "total = (1 + one) * (1 + two)\n")
    (d / "bad.motion").write_text("phase one = dcm_x\ntotal = one +\n")
    return d


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_bad_script_is_one_line_exit_2(files, capsys):
    code, out, err = run(capsys, files / "bad.motion", "--controllers", files / "a.json")
    assert code == 2 and err.count("\n") == 1 and "bad.motion:2:14: unexpected end of line" in err


def test_bad_inputs_exit_2(files, capsys, tmp_path):
    code, _, err = run(capsys, files / "good.motion", "--controllers", files / "a.json")
    assert code == 2 and "script has 2 phase(s) (one, two) but 1 controller(s)" in err
    code, _, err = run(capsys, files / "good.motion", "--controllers", files / "a.json", files / "nope.json")
    assert code == 2 and "nope.json" in err and err.count("\n") == 1
    (tmp_path / "c.json").write_text('{"format": "gpmotion-composite", "version": 1, "phases": 3}')
    code, _, err = run(capsys, files / "good.motion", "--composite", tmp_path / "c.json")
    assert code == 2 and "'phases' must be a list" in err
    code, _, err = run(capsys, files / "good.motion", "--controllers", files / "a.json", files / "b.json",
                       "--transitions", "0.5,x")
    assert code == 2 and "--transitions must be a comma list" in err
    code, _, err = run(capsys, files / "missing.motion", "--controllers", files / "a.json")
    assert code == 2 and "cannot read script" in err


def test_no_search_scores_the_given_switches(files, capsys):
    code, out, _ = run(capsys, files / "good.motion", "--controllers", files / "a.json", files / "b.json",
                       "--transitions", "0.5", "--no-search")
    assert code == 0 and out.startswith("switches [0.5] s: total ") and " one " in out and " two " in out


def test_search_writes_a_run_directory(files, capsys, tmp_path):
    out_dir = tmp_path / "run"
    argv = [files / "good.motion", "--controllers", files / "a.json", files / "b.json", "--arrays", "2",
            "--rounds", "2", "--mutations", "1", "--out", out_dir, "--no-artifacts", "--quiet"]
    code, out, err = run(capsys, *argv)
    assert code == 0, err
    for f in ("config.json", "log.csv", "checkpoint.json", "careless.json", "composite.json", "result.json"):
        assert (out_dir / f).exists(), f
    result = json.loads((out_dir / "result.json").read_text())
    assert result["simulations"] == 1 + 2 * 2 * 1 and result["best"]["total"] >= result["careless"]["total"]
    code, _, err = run(capsys, *argv)
    assert code == 2 and "not empty" in err
    code, out2, _ = run(capsys, *argv, "--resume")
    assert code == 0 and out2 == out
