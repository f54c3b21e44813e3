"""The shipped studies: every search of every shipped spec builds (so `gpmotion
study run NAME` can run it), and the creatures ledger's committed controllers
give back the rows that name them (the cost and success each search recorded;
a sequence's composite measures and verdict), so the table printed from the
ledger is what the controllers do."""
import pytest

from gpmotion.replay import load_controller, replay_genome
from gpmotion.study import SHIPPED, load_directory, shipped_names, spec_path
from gpmotion.study.driver import check
from gpmotion.study.judge import get_judge, rex_sequence_measures
from gpmotion.study.spec import load

from tests.replay_checks import same_numbers

CREATURES = SHIPPED / "creatures"
SPEC, ROWS = load_directory(CREATURES)


@pytest.mark.parametrize("name", shipped_names())
def test_every_search_of_a_shipped_study_builds(name):
    check(load(spec_path(name)))          # raises, naming the configuration, if one cannot run


def _replayed(rel: str):
    task, family, actuation, genome, rec = load_controller(CREATURES / rel)
    traj, costs, measures, ok = replay_genome(task, family, actuation, genome)
    return float(costs[0]), bool(ok[0]), rec


def test_the_creatures_ledger_holds_imported_tune_rows_and_report_rows_it_ran():
    tune = [r for r in ROWS if r["seeds"] == "tune"]
    assert {(r["config"], r["seed"]) for r in tune} == {
        (c, s) for c in ("rex-bsr-time", "rex-sequence") for s in SPEC.tune_seeds}
    assert all(r["imported"] for r in tune)
    report = [r for r in ROWS if r["seeds"] == "report"]
    assert report and all(r["seed"] in SPEC.report_seeds and "imported" not in r for r in report)


@pytest.mark.parametrize("row", [r for r in ROWS if "stages" not in r],
                         ids=lambda r: f"{r['config']}-{r['seed']}-{r['start']}")
def test_a_single_search_controller_replays_to_its_row(row):
    """The cost and the task's test (tests/replay_checks.py); a report row's kept measures
    (its gaits3d measures among them) are the replay's, and its judge names
    the recorded label from them."""
    from gpmotion.study.judge import single_measures
    task, family, actuation, genome, rec = load_controller(CREATURES / row["controller"])
    traj, costs, measures, ok = replay_genome(task, family, actuation, genome)
    assert row["cost"] == rec["final_cost"]
    same_numbers(float(costs[0]), row["cost"])
    assert bool(ok[0]) == row["measures"]["task_success"]
    if row["seeds"] == "tune":           # imported: the judge was the task's test
        assert bool(ok[0]) == row["success"]
        return
    same_numbers(single_measures(task, traj, measures, ok), row["measures"])
    conf = SPEC.configurations[row["config"]]
    assert get_judge(conf.judge).decide(row["measures"], conf.expect) == (row["success"], row["label"])


@pytest.mark.parametrize("row", [r for r in ROWS if "stages" in r], ids=lambda r: f"seed{r['seed']}")
def test_a_sequence_gives_its_row_stage_by_stage_and_as_one_composite(row):
    names = [s["name"] for s in row["stages"]]
    for st in row["stages"]:
        cost, ok, _ = _replayed(st["controller"])
        same_numbers((cost, ok), (st["cost"], st["success"]))
        assert min(t["cost"] for t in st["tries"]) == st["cost"]     # the cheapest try goes on
    kept = rex_sequence_measures([CREATURES / s["controller"] for s in row["stages"]], names)
    same_numbers(kept, row["measures"])
    assert get_judge("walk-turn-walk").decide(kept, []) == (row["success"], row["label"])


def test_the_sequences_verdicts_are_the_recorded_ones():
    """Strictly (every stage named by gaits3d) no tune seed completes: seed 0's
    second walk turns 32° (a walk holds its heading within 30°), seed 4's
    walks take one step and none; by distance and heading only (the loose
    judge) seeds 0 and 4 complete and 1-3 miss by one stage's measure."""
    tune = {r["seed"]: r for r in ROWS if r["config"] == "rex-sequence" and r["seeds"] == "tune"}
    assert {s: r["label"] for s, r in tune.items()} == dict.fromkeys(range(5), "incomplete")
    loose = {s: get_judge("walk-turn-walk-loose").decide(r["measures"], [])[1] for s, r in tune.items()}
    assert loose == {0: "completes", 1: "incomplete", 2: "incomplete", 3: "incomplete",
                     4: "completes"}
    m0 = tune[0]["measures"]
    assert m0["walk_gait3d_steps"] >= 2 and 30 < m0["walk2_gait3d_turn_deg"] < 45
    assert tune[1]["measures"]["walk2_distance_m"] < 1.0 <= tune[1]["measures"]["walk_distance_m"]


def test_the_sequences_report_verdicts_strict_and_loose():
    """On report seeds 100-109 no sequence completes strictly; by distance and
    heading only seeds 106 and 109 do (their first walks drift 48° and 61°)."""
    report = {r["seed"]: r for r in ROWS if r["config"] == "rex-sequence" and r["seeds"] == "report"}
    assert sorted(report) == list(range(100, 110))
    assert {r["label"] for r in report.values()} == {"incomplete"}
    loose = get_judge("walk-turn-walk-loose")
    assert {s for s, r in report.items() if loose.decide(r["measures"], [])[0]} == {106, 109}
    assert all(30 < report[s]["measures"]["walk_turn_deg"] for s in (106, 109))
