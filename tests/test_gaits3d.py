"""The 3-D gait classifier (gpmotion.gaits3d) against motions labelled by eye
(tests/data/labelled_motions_3d.json).

Each motion is a Rex, Bob or Cujo controller: a saved controller file
(``controller``, a path in the repository) or a controller record held in
the data file (``record``: task, parameters, family, options, actuation,
genome).  Its filmstrip (``render_any(traj, filmstrip, title=id, task=task)``)
was looked at and labelled before the classifier's answer was computed.
The test replays every motion, judges it, prints the confusion matrix and
checks the agreement measured when the set was made, as a floor; the docs
page (docs/reproduction/classifiers.md) must hold the printed report.

    python tests/test_gaits3d.py                  # the report (Markdown) for the docs page
    python tests/test_gaits3d.py --filmstrips DIR # the filmstrips that were labelled
"""
from __future__ import annotations

import json
import sys
from functools import lru_cache
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_classifiers import confusion as _confusion  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data" / "labelled_motions_3d.json"
DOCS = ROOT / "docs" / "reproduction" / "classifiers.md"
# agreement with the eye as measured when the set was labelled
AGREE_FLOOR = 32


def load_set() -> dict:
    return json.loads(DATA.read_text())


def load_motion(m: dict):
    """(task, family, actuation, genome) of a labelled motion."""
    from gpmotion.families import make_family
    from gpmotion.families.base import recorded_options
    from gpmotion.replay import load_controller
    from gpmotion.task import get_task, task_id
    if "controller" in m:
        task, fam, act, genome, _ = load_controller(ROOT / m["controller"])
        return task, fam, act, genome
    r = m["record"]
    task = get_task(task_id(r["task"], recorded=True), **r["params"])
    fam = make_family(r["family"], task, **recorded_options(r["family"], r["options"], r["options"]))
    return task, fam, r["actuation"], fam.from_json(r["genome"])


def replay(m: dict):
    from gpmotion.replay import replay_genome
    task, fam, act, genome = load_motion(m)
    return task, replay_genome(task, fam, act, genome)[0]


@lru_cache(maxsize=1)
def judged() -> list[dict]:
    """Every labelled motion replayed and judged."""
    from gpmotion import gaits3d
    out = []
    for m in load_set()["motions"]:
        task, traj = replay(m)
        label, measures = gaits3d.judge(traj, task)
        out.append({**m, "got": label, "measures": measures})
    return out


def confusion(rows, labels) -> str:
    return _confusion(rows, "got", labels, name="gaits3d")


def agree(rows) -> int:
    return sum(r["eye"] == r["got"] for r in rows)


def creature(m: dict) -> str:
    task = m["record"]["task"] if "record" in m else Path(m["controller"]).name
    return "Cujo" if "cujo" in task else "Bob" if "bob" in task else "Rex"


def report() -> str:
    rows, labels = judged(), load_set()["labels"]
    sure = [r for r in rows if r["sure"]]
    parts = [f"**gaits3d** agrees with the eye on {agree(rows)} / {len(rows)} motions "
             f"({100 * agree(rows) / len(rows):.0f} %), on {agree(sure)} / {len(sure)} of those "
             "labelled without doubt", "", confusion(rows, labels), ""]
    for who in ("Rex", "Bob", "Cujo"):
        sub = [r for r in rows if creature(r) == who]
        parts += [f"{who}: {agree(sub)} / {len(sub)}", "", confusion(sub, labels), ""]
    wrong = [f"* {r['id']}: eye {r['eye']}, gaits3d {r['got']} — {r['reason']}"
             for r in rows if r["eye"] != r["got"]]
    return "\n".join(parts + ["Disagreements with the eye:", ""] + (wrong or ["* none"]))


def test_the_set_is_well_formed():
    doc = load_set()
    ids = [m["id"] for m in doc["motions"]]
    assert len(ids) == len(set(ids)) >= 40
    assert all(m["eye"] in doc["labels"] and m["reason"] and m["source"] for m in doc["motions"])
    assert all(("controller" in m) != ("record" in m) for m in doc["motions"])
    keys = {json.dumps([m.get("controller"), m.get("record")], sort_keys=True) for m in doc["motions"]}
    assert len(keys) == len(ids)
    assert {creature(m) for m in doc["motions"]} == {"Rex", "Bob", "Cujo"}


def test_the_classifier_agrees_with_the_eye_as_measured(capsys):
    rows = judged()
    with capsys.disabled():
        print("\n" + report())
    assert agree(rows) >= AGREE_FLOOR


def test_the_docs_page_holds_the_report():
    assert report() in DOCS.read_text()


def test_every_label_is_named_again_from_kept_measures():
    from gpmotion import gaits3d
    for r in judged():
        assert gaits3d.relabel(json.loads(json.dumps(r["measures"]))) == r["got"]


def test_a_bound_needs_the_pairs_to_land_together():
    """No motion of the set bounds by eye, so the bound rule is checked here on
    footfalls made by hand: pairs landing together (a bound) against feet
    landing one at a time (a walk or gallop)."""
    import numpy as np
    from gpmotion import gaits3d
    feet = ["foot_fl", "foot_fr", "foot_hl", "foot_hr"]
    assert gaits3d.foot_pairs(feet) == [("foot_fl", "foot_fr"), ("foot_hl", "foot_hr")]
    assert gaits3d.foot_pairs(["foot_l", "foot_r"]) == []
    frames, dt = 150, 0.02

    def force(offsets):             # every 0.4 s each foot lifts for 0.1 s, shifted by its offset (frames)
        f = np.ones((frames, 4))
        for k, off in enumerate(offsets):
            for start in range(10 + off, frames - 10, 20):
                f[start:start + 5, k] = 0.0
        return f
    paired = gaits3d._pair_measures(force([0, 1, 10, 11]), feet, gaits3d.foot_pairs(feet), dt)
    apart = gaits3d._pair_measures(force([0, 5, 10, 15]), feet, gaits3d.foot_pairs(feet), dt)
    assert paired["paired"] == 1.0 and apart["paired"] == 0.0
    assert paired["footfalls"] == apart["footfalls"] > 0
    bound = {"forward": 1.2, "sideways": 0.0, "turn_deg": 5.0, "facing_deg": 5.0, "upright": 1.0,
             "fell": False, "fallen": 0.0, "flights": 3, "landed_on_feet": 3, "steps": None,
             "footfalls": 12, "paired": 0.75, "pair_support": 0.4}
    assert gaits3d.relabel(bound) == "bound"
    assert gaits3d.relabel({**bound, "paired": 0.5}) == "other"          # feet land one at a time
    assert gaits3d.relabel({**bound, "pair_support": 0.1}) == "other"    # a wheelbarrow on the front legs
    assert gaits3d.relabel({**bound, "landed_on_feet": 1}) == "other"
    assert gaits3d.relabel({**bound, "paired": None, "steps": 0}) == "other"   # a biped does not bound


def test_the_study_judges_name_what_gaits3d_names_from_a_rows_kept_measures():
    """A study row of a creature keeps ``gait3d_*`` measures; ``gait3d`` and
    ``long-walk`` re-judge them as the classifier labels the motion."""
    from gpmotion.study.judge import LONG_WALK, LONG_WALK_STEPS, get_judge, rejudge, single_measures
    for r in judged()[:6] + [r for r in judged() if creature(r) == "Bob"][:3]:
        task, traj = replay(r)
        m = task.measure(traj)
        kept = json.loads(json.dumps(single_measures(task, traj, m, task.success(traj, m))))
        assert rejudge({"measures": kept}, "gait3d", ["bound"]) == (r["got"] == "bound", r["got"])
        walk5 = r["got"] == "walk" and (r["measures"]["steps"] or 0) >= LONG_WALK_STEPS
        assert rejudge({"measures": kept}, "long-walk", [LONG_WALK])[0] == walk5
    kept = {f"gait3d_{k}": v for k, v in {"forward": 2.0, "turn_deg": 5.0, "facing_deg": 5.0,
                                           "fell": False, "flights": 0, "landed_on_feet": 0,
                                           "steps": 4, "paired": None, "pair_support": None}.items()}
    from gpmotion.gaits3d import LABELS
    assert get_judge("gait3d").labels == LABELS
    j = get_judge("long-walk")
    assert set(j.labels) == {LONG_WALK, *LABELS}
    assert j.decide(kept, [LONG_WALK]) == (False, "walk")
    assert j.decide({**kept, "gait3d_steps": 5}, [LONG_WALK]) == (True, LONG_WALK)
    assert j.decide({**kept, "gait3d_fell": True, "gait3d_steps": 7}, [LONG_WALK]) == (False, "fallen")


def filmstrips(folder: Path) -> None:
    from gpmotion.render3d import render_any
    folder.mkdir(parents=True, exist_ok=True)
    for m in load_set()["motions"]:
        task, traj = replay(m)
        render_any(traj, filmstrip=str(folder / f"{m['id']}.png"), title=m["id"], task=task)


if __name__ == "__main__":
    if sys.argv[1:2] == ["--filmstrips"] and len(sys.argv) == 3:
        filmstrips(Path(sys.argv[2]))
    else:
        print(report())
