"""Named outcome judges: how a study's result is labelled and whether it succeeded.

A judge has two halves, so a table can be re-judged without re-running a
search (``gpmotion study table DIR --judge NAME``):

* ``measure`` sees the replayed best controller (or, for a composite judge,
  the stages' controllers run as one composite) and returns the *kept
  measures*: plain numbers the ledger stores;
* ``decide`` turns kept measures (and the configuration's ``expect``) into
  ``(success, label)``; success is None when the judge has no test for the
  configuration (a gait judge without expected gaits).

Judges measuring the same things share kept measures: every single-search
row keeps the task's measures *and* the gait features where the figure is a
planar traveller (a 3-D creature: its :mod:`gpmotion.gaits3d` measures), so
``task`` and ``gait`` (``gait3d``) re-judge each other's ledgers.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np


@dataclass(frozen=True)
class Judge:
    name: str
    doc: str
    labels: tuple
    decide: Callable            # (kept: dict, expect: list) -> (success | None, label)
    composite: bool = False     # judges a staged configuration's composite
    needs: tuple = ()           # kept measures ``decide`` reads
    extra: Callable | None = None   # (task, family, actuation, genome) -> more kept measures


_JUDGES: dict[str, Judge] = {}


def register_judge(judge: Judge) -> Judge:
    if judge.name in _JUDGES and _JUDGES[judge.name] is not judge:
        raise ValueError(f"judge {judge.name!r} is already registered")
    _JUDGES[judge.name] = judge
    return judge


def get_judge(name: str) -> Judge:
    if name not in _JUDGES:
        from ..names import unknown
        raise KeyError(unknown("judge", name, _JUDGES))
    return _JUDGES[name]


def judge_names() -> list[str]:
    return sorted(_JUDGES)


def rejudge(row: dict, name: str, expect: list) -> tuple:
    """(success, label) of a ledger row under judge ``name``, from its kept measures."""
    j = get_judge(name)
    kept = row.get("measures") or {}
    missing = [k for k in j.needs if k not in kept]
    if missing:
        raise ValueError(f"judge {name!r} needs measures {missing} the ledger's "
                         f"{row.get('config')} rows do not keep")
    return j.decide(kept, expect)


# ------------------------------------------------------------------ measuring

def single_measures(task, traj, measures: dict, ok) -> dict:
    """What a single search's row keeps: the task's measures of the best
    controller, its success test, and the gait features of a planar traveller
    or of a 3-D creature (a task naming its ``feet``)."""
    kept = {"task_success": bool(ok[0])}
    for k, v in measures.items():
        x = float(np.asarray(v).reshape(-1)[0])
        kept[k] = x if np.isfinite(x) else None
    fig = traj.figure
    if fig.dimensions == 2 and any(n.startswith("foot") for n in fig.contact_names):
        from .. import gaits
        _, m = gaits.judge(traj)            # the strict measures hold the loose features too
        kept.update({f"gait_{k}": v for k, v in m.items()})
    elif fig.dimensions == 3 and getattr(task, "feet", ()):
        from .. import gaits3d
        _, m = gaits3d.judge(traj, task)
        kept.update({f"gait3d_{k}": v for k, v in m.items()})
    return kept


# ------------------------------------------------------------------ the judges

def _task_decide(kept: dict, expect: list):
    ok = bool(kept["task_success"])
    return ok, "solved" if ok else "not solved"


register_judge(Judge(
    "task", "the task's own success test (its threshold)", ("solved", "not solved"),
    _task_decide, needs=("task_success",)))


def _gait_decide(kept: dict, expect: list):
    from ..gaits import GaitFeatures, classify
    f = GaitFeatures(**{k[5:]: kept[k] for k in _GAIT_KEYS})
    label = classify(f)
    return (label in expect) if expect else None, label


_GAIT_KEYS = ("gait_distance", "gait_turns", "gait_flights", "gait_airborne",
              "gait_feet_down", "gait_switches", "gait_period")


def _gait_labels():
    from ..gaits import GAITS
    return tuple(GAITS)


register_judge(Judge(
    "gait", "the planar gait classifier (gpmotion.gaits); success: an expected gait",
    ("cartwheel", "tumble", "hop", "periodic shuffle", "shuffle", "other"),
    _gait_decide, needs=_GAIT_KEYS))


def _strict_gait_decide(kept: dict, expect: list):
    from ..gaits import relabel
    label = relabel({k[5:]: v for k, v in kept.items() if k.startswith("gait_")}, "strict")
    return (label in expect) if expect else None, label


_STRICT_GAIT_KEYS = _GAIT_KEYS + tuple(f"gait_{k}" for k in (
    "standing_height", "upright", "min_height", "max_tilt_deg", "feet_share", "hands_share",
    "other_share", "hands_down", "landings", "landed_on_feet"))

register_judge(Judge(
    "gait-strict", "the planar gait classifier's strict definitions (posture, which limbs carry "
    "the weight, landings on the feet: gpmotion.gaits); success: an expected gait",
    ("cartwheel", "tumble", "hop", "periodic shuffle", "shuffle", "other"),
    _strict_gait_decide, needs=_STRICT_GAIT_KEYS))


_GAIT3D_LABELS = ("fallen", "bound", "walk", "turn", "other")     # gpmotion.gaits3d.LABELS
_GAIT3D_MEASURES = ("forward", "turn_deg", "facing_deg", "fell", "flights", "landed_on_feet",
                    "steps", "paired", "pair_support")
_GAIT3D_KEYS = tuple(f"gait3d_{k}" for k in _GAIT3D_MEASURES)


def _gait3d_label(kept: dict) -> str:
    from ..gaits3d import relabel
    return relabel({k[7:]: v for k, v in kept.items() if k.startswith("gait3d_")})


def _gait3d_decide(kept: dict, expect: list):
    label = _gait3d_label(kept)
    return (label in expect) if expect else None, label


register_judge(Judge(
    "gait3d", "the 3-D creature classifier (gpmotion.gaits3d: fallen, bound, walk, turn); "
    "success: an expected label", _GAIT3D_LABELS, _gait3d_decide, needs=_GAIT3D_KEYS))

# Auslander et al. §4.3: Bob's time-based walks fail "after two or three steps"
LONG_WALK_STEPS = 5
LONG_WALK = f"walk of ≥ {LONG_WALK_STEPS} steps"


def _long_walk_decide(kept: dict, expect: list):
    label = _gait3d_label(kept)
    if label == "walk" and (kept["gait3d_steps"] or 0) >= LONG_WALK_STEPS:
        label = LONG_WALK
    return (label in expect) if expect else None, label


register_judge(Judge(
    "long-walk", f"a 3-D biped's walk (gpmotion.gaits3d) of ≥ {LONG_WALK_STEPS} forward-facing "
    "steps, the feet taking turns; success: an expected label",
    (LONG_WALK, *_GAIT3D_LABELS), _long_walk_decide, needs=_GAIT3D_KEYS))


# Rex's walk → turn → walk: every stage judged on its own frames of the composite
SEQUENCE_WALK_M, SEQUENCE_TURN_DEG = 1.0, 45.0


def rex_sequence_measures(paths, names) -> dict:
    """The stages' controllers run as one composite (state carried across each
    switch), each stage measured on its own frames by Rex's measures."""
    from dataclasses import replace

    from ..compose import composite
    from ..gaits3d import measures as gait3d_measures
    from ..tasks._creature3d import creature_measures
    from ..tasks.rex_walk import RexTask
    comp = composite.from_controllers([str(p) for p in paths], names=list(names))
    traj, bounds = composite.run(comp)
    whole, kept = traj.episode(0), {}
    for k, name in enumerate(names):
        sl = slice(int(bounds[0, k]), int(bounds[0, k + 1]) + 1)
        piece = replace(whole, q=whole.q[:, sl], qd=whole.qd[:, sl], com=whole.com[:, sl],
                        contact_force=whole.contact_force[:, sl], times=whole.times[sl])
        p = creature_measures(piece, RexTask.feet, max_tilt=RexTask.max_tilt,
                              min_height=RexTask.min_height)
        kept[f"{name}_distance_m"] = float(p["distance"][0])
        kept[f"{name}_turn_deg"] = float(np.degrees(p["turn"][0]))
        kept[f"{name}_fell"] = bool(p["fall"][0] > 0)
        g = gait3d_measures(piece, RexTask.feet, RexTask.foot_sites, RexTask.foot_groups)
        kept.update({f"{name}_gait3d_{m}": g[m] for m in _GAIT3D_MEASURES})
    kept["stages"] = list(names)
    return kept


def _three_stages(kept: dict, judge: str) -> list:
    names = kept["stages"]
    if len(names) != 3:
        raise ValueError(f"judge {judge!r} needs three stages, got {names}")
    return names


def _sequence_decide(kept: dict, expect: list):
    """Each stage named by gaits3d on its own frames: walk, turn, walk."""
    names = _three_stages(kept, "walk-turn-walk")
    labels = [_gait3d_label({k[len(n) + 1:]: v for k, v in kept.items() if k.startswith(f"{n}_gait3d_")})
              for n in names]
    ok = labels == ["walk", "turn", "walk"]
    return ok, "completes" if ok else "incomplete"


def _sequence_loose_decide(kept: dict, expect: list):
    """walk ≥ 1 m, turn ≥ 45°, walk ≥ 1 m (stages in order), never fallen."""
    w1, t, w2 = _three_stages(kept, "walk-turn-walk-loose")
    ok = (kept[f"{w1}_distance_m"] >= SEQUENCE_WALK_M and kept[f"{t}_turn_deg"] >= SEQUENCE_TURN_DEG
          and kept[f"{w2}_distance_m"] >= SEQUENCE_WALK_M
          and not any(kept[f"{n}_fell"] for n in (w1, t, w2)))
    return ok, "completes" if ok else "incomplete"


register_judge(Judge(
    "walk-turn-walk", "a 3-D biped's walk, turn, walk as one composite, each stage named on its "
    "own frames by gpmotion.gaits3d: a walk (≥ 2 forward-facing steps, the feet taking turns, "
    "≥ 1 m forward), a turn (heading ≥ 45°, not fallen), a walk",
    ("completes", "incomplete"), _sequence_decide, composite=True, needs=("stages",)))

register_judge(Judge(
    "walk-turn-walk-loose", "a 3-D creature's walk, turn, walk as one composite by distance "
    "and heading only: walk ≥ 1 m, turn ≥ 45°, walk ≥ 1 m, never fallen",
    ("completes", "incomplete"), _sequence_loose_decide, composite=True, needs=("stages",)))

ROBUST_TRIALS, ROBUST_REQUIRE = 100, 0.9


def robust_measures(task, family, actuation, genome) -> dict:
    """The best controller from ROBUST_TRIALS perturbed starts (trial 0 nominal;
    the figure's default sizes; a stream no search trains on)."""
    from ..robust import robustness
    r = robustness(task, family, actuation, genome, trials=ROBUST_TRIALS, seed=0)
    return {"robust_success_rate": r["success_rate"], "robust_trials": r["trials"],
            "robust_nominal_success": r["nominal_success"], "robust_cost_median": r["cost_median"]}


def _robust_decide(kept: dict, expect: list):
    ok = kept["robust_success_rate"] >= ROBUST_REQUIRE
    return ok, "robust" if ok else "fragile"


register_judge(Judge(
    "robust", f"succeeds from ≥ {ROBUST_REQUIRE:.0%} of {ROBUST_TRIALS} perturbed starts "
    "(gpmotion robustness)", ("robust", "fragile"), _robust_decide,
    needs=("robust_success_rate",), extra=robust_measures))

COMPOSITE_MEASURES = {"walk-turn-walk": rex_sequence_measures,
                      "walk-turn-walk-loose": rex_sequence_measures}
