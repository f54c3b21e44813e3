"""generations.jsonl (the report's film record): what it holds, that a killed
and resumed run writes the same file as an uninterrupted one, and that a run
without it still reports (without the film)."""
import json
import shutil
from pathlib import Path

import pytest

from gpmotion.records import FormatError
from gpmotion.run import RunConfig, run
from gpmotion.rundir import RunDir

DATA = Path(__file__).parent / "data"


def _cfg(family="gp", **search):
    return RunConfig(task="lamp_hop", family=family, seed=3,
                     search=search or {"population": 12, "generations": 5})


def _records(path):
    return [json.loads(line) for line in (Path(path) / "generations.jsonl").read_text().splitlines()]


@pytest.mark.parametrize("family,search", [
    ("gp", {"population": 12, "generations": 5}),
    ("bsr-sense", {"n_working": 4, "n_generations": 12}),
])
def test_resume_writes_the_same_record(tmp_path, family, search):
    whole = tmp_path / "whole"
    run(_cfg(family, **search), whole, quiet=True, artifacts=False, checkpoint_every=0)
    part = tmp_path / "part"
    run(_cfg(family, **search), part, quiet=True, artifacts=False, checkpoint_every=0,
        max_generations=2)
    with open(part / "generations.jsonl", "a") as f:     # a record written after the checkpoint
        f.write('{"generation": 999, "genome": {}}\n{"generation": 1000, "torn')
    run(None, part, resume=True, quiet=True, artifacts=False, checkpoint_every=0)
    assert (part / "generations.jsonl").read_bytes() == (whole / "generations.jsonl").read_bytes()
    recs = _records(whole)
    assert recs and recs[0]["generation"] == 0
    gens = [r["generation"] for r in recs]
    assert gens == sorted(set(gens))
    genomes = [json.dumps(r["genome"], sort_keys=True) for r in recs]
    assert all(a != b for a, b in zip(genomes, genomes[1:]))      # only changes are recorded
    assert all({"evaluations", "cost", "cost_final", "genome"} <= set(r) for r in recs)
    evals = [r["evaluations"] for r in recs]
    assert evals == sorted(set(evals))


def test_the_final_cost_is_the_final_scoring(tmp_path):
    """cost_final is the task's final scoring of that controller: a replay agrees."""
    from gpmotion.report.runs import film
    from gpmotion.replay import load_controller
    out = tmp_path / "r"
    run(_cfg(), out, quiet=True, artifacts=False, checkpoint_every=0)
    task, family, actuation, _, _ = load_controller(out)
    recs = [r for r in _records(out) if r["cost_final"] is not None]
    f = film(recs, task, family, actuation)
    assert [e["cost_final"] for e in f["entries"]] == pytest.approx([r["cost_final"] for r in recs])


def test_an_old_run_reports_without_the_film(tmp_path):
    from gpmotion.report.runs import run_panel
    old = tmp_path / "old"
    shutil.copytree(DATA / "old_run_lamp_hop", old)
    p = run_panel(old)
    assert "film" not in p and "generations.jsonl" in p["film_note"]
    assert p["motion"]["n"] > 10 and p["curves"]["series"]


def test_a_bad_record_is_a_format_error(tmp_path):
    (tmp_path / "generations.jsonl").write_text('{"generation": 0}\n[1, 2]\n')
    with pytest.raises(FormatError, match="not a generation record"):
        RunDir(tmp_path).read_generations()
