"""`gpmotion bench`: the benchmark runs and reports what it promises (no timing assertions)."""
import json

import pytest

from gpmotion import bench

KEYS = ("steps_per_s", "steps_per_s_all_threads", "threads", "warm_start_s", "episodes", "steps",
        "cpu_count", "gp_evals_per_s", "gp_steps_per_s")


@pytest.fixture(scope="module")
def quick():
    return bench.run_bench("lamp", quick=True)


def test_quick_bench_reports_positive_numbers(quick):
    for k in KEYS:
        assert isinstance(quick[k], (int, float)) and quick[k] > 0, k
    assert quick["figure"] == "lamp" and quick["numba"] and quick["numpy"]
    assert quick["steps"] == quick["episodes"] * quick["steps_per_episode"]
    assert quick["diverged"] == 0
    assert 0 < quick["contact_frames"] <= 1      # the lamp really touches the ground


def test_report_and_cli(quick, capsys):
    text = bench.format_report(quick)
    assert "steps/s" in text and "lamp" in text
    assert bench.main(["--quick", "--json", "--no-gp", "--no-warm-start", "--figure", "starman"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["figure"] == "starman" and out["steps_per_s"] > 0


def test_cli_rejects_bad_input(capsys):
    assert bench.main(["--figure", "nope"]) == 2
    assert bench.main(["--episodes", "0"]) == 2
    err = capsys.readouterr().err
    assert "unknown figure" in err and "--episodes" in err
