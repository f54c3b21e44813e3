"""Staged study configurations: each stage searched from the end of the earlier
stages' controllers, a stage's starts (the cheapest of K), and the composite
judged as one motion (Rex's walk → turn → walk)."""
import json
from pathlib import Path

from gpmotion.cli import main
from gpmotion.study.judge import get_judge, rex_sequence_measures
from gpmotion.study.ledger import read_rows

ROOT = Path(__file__).resolve().parents[1]

SPEC = """
[study]
name = "rex"
tune_seeds = [1]

[defaults]
judge = "walk-turn-walk"
family = "bsr-time"
actuation = "kinematic"
options = { rules = 4, segments = "variable" }
search = { n_working = 10, n_generations = 1 }

[configurations.seq]
[[configurations.seq.stages]]
name = "walk"
task = "rex_walk"
options = { t_per = 0.4 }
starts = 2
[[configurations.seq.stages]]
name = "turn"
task = "rex_turn"
options = { t_per = 0.5 }
[[configurations.seq.stages]]
name = "walk2"
task = "rex_walk"
options = { t_per = 0.3 }
search = { n_generations = 2 }
"""


def test_the_walk_turn_walk_judges_name_each_stage_on_its_own_frames():
    """The creatures study's tune seed 0, judged from its controllers: by
    distance and heading it completes (walk 1.58 m, turn 90°, walk 1.06 m);
    by gaits3d its first walk is a walk (3 steps, heading within 30°) and its
    turn a turn, but its second walk turns 32°, so strictly it does not."""
    d = ROOT / "gpmotion" / "studies" / "creatures" / "controllers"
    kept = rex_sequence_measures([d / f"rex-sequence-seed0-{s}.json" for s in ("walk", "turn", "walk2")],
                                 ["walk", "turn", "walk2"])
    assert get_judge("walk-turn-walk-loose").decide(kept, []) == (True, "completes")
    assert not any(kept[f"{n}_fell"] for n in ("walk", "turn", "walk2"))
    assert round(kept["walk_distance_m"], 2) == 1.58 and round(kept["turn_turn_deg"]) == 90
    assert round(kept["walk2_distance_m"], 2) == 1.06
    shorter = dict(kept, walk2_distance_m=0.9)
    assert get_judge("walk-turn-walk-loose").decide(shorter, []) == (False, "incomplete")
    assert kept["walk_gait3d_steps"] == 3 and round(kept["walk2_gait3d_turn_deg"]) == 32
    assert get_judge("walk-turn-walk").decide(kept, []) == (False, "incomplete")
    held = dict(kept, walk2_gait3d_turn_deg=29.0)            # the second walk holding its heading
    assert get_judge("walk-turn-walk").decide(held, []) == (True, "completes")
    fell = dict(held, turn_gait3d_fell=True)
    assert get_judge("walk-turn-walk").decide(fell, []) == (False, "incomplete")


def test_stages_run_from_the_earlier_stages_with_their_own_settings(tmp_path):
    spec = tmp_path / "rex.toml"
    spec.write_text(SPEC)
    out = tmp_path / "out"
    assert main(["study", "run", str(spec), "--out", str(out), "--quiet"]) == 0
    row, = read_rows(out)
    walk, turn, walk2 = row["stages"]
    assert [t["search_seed"] for t in walk["tries"]] == [2, 3]           # seed 1, 2 starts
    assert walk["cost"] == min(t["cost"] for t in walk["tries"])
    assert [s["task"] for s in row["stages"]] == ["rex_walk-v2", "rex_turn-v3", "rex_walk-v2"]
    assert row["evaluations"] == 2 * 20 + 20 + 30
    assert row["cost"] == walk["cost"] + turn["cost"] + walk2["cost"]
    assert row["label"] in ("completes", "incomplete") and row["measures"]["stages"] == \
        ["walk", "turn", "walk2"]
    rec = {s["name"]: json.loads((out / s["controller"]).read_text()) for s in row["stages"]}
    assert [rec[n]["options"]["t_per"] for n in ("walk", "turn", "walk2")] == [0.4, 0.5, 0.3]
    assert rec["walk"]["seed"] == walk["search_seed"]
    assert rec["walk2"]["params"]["after"] == "seq-seed1-walk.json,seq-seed1-turn.json"
    # the turn started where the chosen walk ended: its run records that walk
    cfg = json.loads((out / "runs" / "seq-seed1-turn" / "config.json").read_text())
    chosen = "try0" if walk["search_seed"] == 2 else "try1"
    assert cfg["run"]["params"]["after"].endswith(f"seq-seed1-walk-{chosen}/best.json")
