"""The auslander-2d ledgers' report-seed rows hold what their controllers do.

The report rows of ``auslander-2d`` are imported from a run script's records
(``"imported"``: a run of the same configuration and seed), those of
``auslander-2d-variants`` were written by ``gpmotion study run``.  Each is
checked the way the import checked it: the saved controller replays to its
recorded cost bit for bit, its kept measures (the strict gait measures among
them) are the replay's, and its loose label is the recorded one; the strict
table a page shows is re-judged from those measures.
"""
from __future__ import annotations

import json
from functools import lru_cache

import pytest

from gpmotion.study import SHIPPED, load_directory
from tests.replay_checks import same_numbers

STUDY = SHIPPED / "auslander-2d"
STUDIES = ("auslander-2d", "auslander-2d-variants")


@lru_cache(maxsize=None)
def report_rows(name: str = "auslander-2d") -> list[dict]:
    spec, rows = load_directory(SHIPPED / name)
    return [r for r in rows if r["seeds"] == "report"]


def test_every_imported_report_row_names_a_report_seed_run_of_its_configuration():
    spec, _ = load_directory(STUDY)
    imported = [r for r in report_rows() if "imported" in r]
    assert imported
    for r in imported:
        assert r["imported"].startswith("benchmarks/auslander_2d.py --first-seed 100")
        assert r["seed"] in spec.report_seeds and r["search_seed"] == r["seed"]
        assert r["evaluations"] == 40000


@pytest.mark.parametrize("name,row", [(n, r) for n in STUDIES for r in report_rows(n)],
                         ids=lambda x: x if isinstance(x, str) else f"{x['config']}-{x['seed']}")
def test_a_report_row_replays_to_its_cost_label_and_measures(name, row):
    from gpmotion.families import make_family
    from gpmotion.replay import replay_genome
    from gpmotion.study.judge import get_judge, single_measures
    from gpmotion.task import get_task
    spec, _ = load_directory(SHIPPED / name)
    rec = json.loads((SHIPPED / name / row["controller"]).read_text())
    task = get_task(rec["task"], **rec["params"])
    fam = make_family(rec["family"], task, **rec["options"])
    traj, costs, measures, ok = replay_genome(task, fam, rec["actuation"], fam.from_json(rec["genome"]))
    assert row["cost"] == rec["cost"]
    same_numbers(float(costs[0]), row["cost"])
    kept = single_measures(task, traj, measures, ok)
    same_numbers(kept, row["measures"])
    conf = spec.configurations[row["config"]]
    assert get_judge("gait").decide(kept, conf.expect) == (row["success"], row["label"])


@pytest.mark.parametrize("name", STUDIES)
def test_the_strict_report_table_is_rejudged_from_the_kept_measures(name):
    from gpmotion.study.judge import rejudge
    from gpmotion.study.table import summarize
    spec, rows = load_directory(SHIPPED / name)
    table = {t["configuration"]: t for t in summarize(spec, rows, "report", "gait-strict")["rows"]}
    for conf, t in table.items():
        mine = [r for r in report_rows(name) if r["config"] == conf]
        expect = spec.configurations[conf].expect
        assert t["runs"] == len(mine)
        verdicts = [rejudge(r, "gait-strict", expect)[0] for r in mine]
        tested = [v for v in verdicts if v is not None]      # no expected gait: no test
        assert t["success"] == (sum(map(bool, tested)) if tested else None)
