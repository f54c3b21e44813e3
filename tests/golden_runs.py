"""Golden runs: small fixed-seed runs whose records must not change.

They catch a refactor that changes a single bit of a result.  Regenerate only
for a deliberate change of results, and say in the commit which fix changed
them and why:

    python -m tests.golden_runs          # rewrites tests/golden/*.json
"""
from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

GOLDEN = Path(__file__).parent / "golden"

# name -> CLI arguments after `gpmotion run`; budgets are tiny on purpose
RUNS = {
    "lamp_hop-gp": ["lamp_hop", "--seed", "3", "--generations", "3", "--population", "30"],
    "lamp_limbo-gp": ["lamp_limbo", "--seed", "1", "--generations", "2", "--population", "30"],
    "starman_travel-bsr-time": ["starman_travel", "--controller", "bsr-time", "--seed", "2",
                                "--generations", "60", "--param", "seconds=1"],
    "starman_travel-bsr-sense": ["starman_travel", "--controller", "bsr-sense", "--seed", "4",
                                 "--generations", "60", "--param", "seconds=1"],
    "herman_touch_nose-gp": ["herman_touch_nose-v1", "--seed", "0", "--generations", "2",
                             "--population", "20"],
}

# timing and environment columns/keys: not results
LOG_SKIP = {"evals_per_s", "recent_evals_per_s", "elapsed_s"}
BEST_SKIP = {"version", "plugins"}


def record(run_dir: Path) -> dict:
    """The result-bearing part of a run directory, as plain JSON data."""
    best = json.loads((run_dir / "best.json").read_text())
    with open(run_dir / "log.csv", newline="") as f:
        rows = [{k: v for k, v in row.items() if k not in LOG_SKIP} for row in csv.DictReader(f)]
    return {"best": {k: v for k, v in best.items() if k not in BEST_SKIP}, "log": rows}


def run_golden(name: str, out: Path, *extra: str) -> dict:
    from gpmotion.cli import main
    code = main(["run", *RUNS[name], "--out", str(out), "--no-artifacts", "--quiet", *extra])
    assert code in (0, None), f"{name}: exit {code}"
    return record(out)


if __name__ == "__main__":
    import tempfile
    GOLDEN.mkdir(exist_ok=True)
    names = sys.argv[1:] or list(RUNS)
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            data = run_golden(name, Path(tmp) / name)
            (GOLDEN / f"{name}.json").write_text(json.dumps(data, indent=1, sort_keys=True) + "\n")
            print("wrote", GOLDEN / f"{name}.json")
