"""Fixed-seed runs reproduce their recorded best.json and log.csv bit for bit
(tests/golden_runs.py says how they were made and when to regenerate)."""
import json

import pytest

from tests.golden_runs import GOLDEN, RUNS, run_golden


def _check(name, tmp_path, *extra):
    want = json.loads((GOLDEN / f"{name}.json").read_text())
    got = json.loads(json.dumps(run_golden(name, tmp_path / name, *extra)))   # same float text
    assert got["best"] == want["best"]
    assert len(got["log"]) == len(want["log"])
    for i, (g, w) in enumerate(zip(got["log"], want["log"])):
        assert g == w, f"log row {i} differs"


@pytest.mark.parametrize("name", sorted(RUNS))
def test_golden_run_unchanged(name, tmp_path):
    _check(name, tmp_path)


@pytest.mark.parametrize("name", ["lamp_hop-gp", "starman_travel-bsr-time"])
def test_golden_run_same_with_a_process_pool(name, tmp_path):
    _check(name, tmp_path, "--workers", "2")
