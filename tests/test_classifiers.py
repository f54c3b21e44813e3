"""The gait classifiers against motions labelled by eye (tests/data/labelled_motions.json).

Each motion is a saved controller (task, parameters, family, genome) whose
filmstrip was looked at and labelled before any classifier's answer was
seen.  The test replays every motion, names it under the strict and the
loose definitions (gpmotion.gaits), prints both confusion matrices and
checks the agreement measured when the set was made, as a floor: a change
that makes the strict classifier disagree with the eye more fails here.

    python tests/test_classifiers.py     # prints the matrices (Markdown) for the docs page
"""
from __future__ import annotations

import json
from collections import Counter
from functools import lru_cache
from pathlib import Path

import pytest

DATA = Path(__file__).resolve().parent / "data" / "labelled_motions.json"
# agreement with the eye as measured when the set was labelled (docs/reproduction/classifiers.md)
STRICT_FLOOR = 34 / 55


def load_set() -> dict:
    return json.loads(DATA.read_text())


@lru_cache(maxsize=1)
def judged() -> list[dict]:
    """Every labelled motion replayed and named under both definitions."""
    from gpmotion import gaits
    from gpmotion.families import make_family
    from gpmotion.replay import replay_genome
    from gpmotion.task import get_task
    out = []
    for m in load_set()["motions"]:
        task = get_task(m["task"], **m["params"])
        fam = make_family(m["family"], task, **m["options"])
        traj = replay_genome(task, fam, fam.default_actuation, fam.from_json(m["genome"]))[0]
        strict, measures = gaits.judge(traj, definition="strict")
        out.append({**m, "strict": strict, "loose": gaits.relabel(measures, "loose"),
                    "measures": measures})
    return out


def confusion(rows, key: str, labels, name: str | None = None) -> str:
    """Markdown confusion matrix: rows the eye's label, columns the classifier's
    (``r[key]``, headed ``name``, default ``key``)."""
    count = Counter((r["eye"], r[key]) for r in rows)
    head = "| eye \\ " + (name or key) + " | " + " | ".join(labels) + " | agree |"
    lines = [head, "|" + "---|" * (len(labels) + 2)]
    for eye in labels:
        n = sum(count[(eye, c)] for c in labels)
        if n:
            lines.append(f"| {eye} | " + " | ".join(str(count[(eye, c)]) for c in labels)
                         + f" | {count[(eye, eye)]} / {n} |")
    return "\n".join(lines)


def agreement(rows, key: str) -> float:
    return sum(r["eye"] == r[key] for r in rows) / len(rows)


def report() -> str:
    rows, labels = judged(), load_set()["labels"]
    sure = [r for r in rows if r["sure"]]
    parts = []
    for key in ("strict", "loose"):
        parts += [f"**{key}** definitions: agree with the eye on "
                  f"{sum(r['eye'] == r[key] for r in rows)} / {len(rows)} motions "
                  f"({100 * agreement(rows, key):.0f} %), on {sum(r['eye'] == r[key] for r in sure)}"
                  f" / {len(sure)} of those labelled without doubt", "", confusion(rows, key, labels), ""]
    wrong = [f"* {r['id']} ({r['source']}): eye {r['eye']}, strict {r['strict']}, loose {r['loose']}"
             f" — {r['reason']}" for r in rows if r["eye"] != r["strict"]]
    return "\n".join(parts + ["Disagreements of the strict classifier with the eye:", ""] + wrong)


def test_the_set_is_well_formed():
    doc = load_set()
    ids = [m["id"] for m in doc["motions"]]
    assert len(ids) == len(set(ids)) >= 40
    assert all(m["eye"] in doc["labels"] and m["reason"] for m in doc["motions"])
    # no two motions are the same controller on the same figure
    keys = {json.dumps([m["task"], m["params"], m["options"], m["genome"]], sort_keys=True)
            for m in doc["motions"]}
    assert len(keys) == len(ids)


def test_strict_classifier_agrees_with_the_eye_as_measured(capsys):
    rows = judged()
    with capsys.disabled():
        print("\n" + report())
    assert agreement(rows, "strict") >= STRICT_FLOOR


def test_strict_definitions_agree_with_the_eye_more_than_the_loose_ones():
    rows = judged()
    assert agreement(rows, "strict") > agreement(rows, "loose")


def test_every_label_is_named_again_from_kept_measures():
    """A ledger keeps the measures; re-judging them gives the same labels, under
    either definition, and the measures survive a JSON round trip."""
    from gpmotion import gaits
    for r in judged():
        kept = json.loads(json.dumps(r["measures"]))
        assert gaits.relabel(kept, "strict") == r["strict"]
        assert gaits.relabel(kept, "loose") == r["loose"]
    with pytest.raises(ValueError, match="definition"):
        gaits.relabel(judged()[0]["measures"], "lenient")


if __name__ == "__main__":
    print(report())


def test_the_study_engine_keeps_the_strict_measures_and_judges_by_them():
    """A study row keeps every strict measure (gpmotion.study.judge.single_measures),
    and the 'gait-strict' judge names the label the strict classifier names."""
    from gpmotion.families import make_family
    from gpmotion.replay import replay_genome
    from gpmotion.study.judge import get_judge, single_measures
    from gpmotion.task import get_task
    judge = get_judge("gait-strict")
    for r in judged():
        kept = {f"gait_{k}": v for k, v in r["measures"].items()}
        assert judge.decide(kept, ["cartwheel"]) == (r["strict"] == "cartwheel", r["strict"])
    m = load_set()["motions"][0]
    task = get_task(m["task"], **m["params"])
    fam = make_family(m["family"], task, **m["options"])
    traj, _, measures, ok = replay_genome(task, fam, fam.default_actuation, fam.from_json(m["genome"]))
    kept = single_measures(task, traj, measures, ok)
    assert set(judge.needs) <= set(kept)
    assert judge.decide(kept, [])[1] == judged()[0]["strict"]


@pytest.mark.parametrize("path, label, steps", [
    ("bob_walk_v1_waddle.json", "fallen", 0),        # tips past the fall test in its last frames
    ("bob_walk_v2_limp.json", "other", 1),           # 0.8 m, one step with the feet taking turns
    ("rex_walk_v1_lunge.json", "other", 1),          # 1.07 m by a lunge, one alternating step
    ("rex_turn_v3/walk.json", "turn", 3),            # 2.3 m, 3 steps, but the heading swings 48°
    ("rex_turn_v3/turn.json", "turn", 1),            # 101° of heading change
])
def test_3d_labels_of_the_saved_creature_controllers(path, label, steps):
    """gpmotion.gaits3d on the saved Bob and Rex controllers (not eye-validated:
    these pin the strict 3-D definitions' answers; docs/reproduction/classifiers.md)."""
    from gpmotion import gaits3d
    from gpmotion.replay import load_controller, replay_genome
    task, fam, act, genome, _ = load_controller(DATA.parent / path)
    traj, _, measures, _ = replay_genome(task, fam, act, genome)
    got, m = gaits3d.judge(traj, task)
    assert (got, m["steps"]) == (label, steps)
    assert m["steps"] <= measures["steps"][0]       # alternating, forward-facing: never more
    assert gaits3d.relabel(json.loads(json.dumps(m))) == got
