"""herman_reach_standing: Herman, standing free on his feet, touches an object
with his right fingertip and keeps his balance.

As ``herman_touch_object`` (same targets, in the frame of the pelvis at the
start), on ``herman_standing``: the pelvis is a free root, so the arm's
swing pushes the body, and the PD-held legs and trunk must absorb it.  One
extra term, on from the start: ``balance``, the largest horizontal excursion
of the pelvis from where it stood (m), plus 1 if it drops by more than
20 cm (a fall).  The ground is the figure's own (stiff: see its TOML).

``--param forces=1`` adds Gritz & Hahn's force sensors to the terminal set:
the ground's normal force on each sole point (``force_heel_r``,
``force_toe_r``, ``force_heel_l``, ``force_toe_l``; N, ~170 each standing
still), whose shifts tell a controller how the body's weight moves over its
feet.  Off by default: the measured success rates (docs/reproduction/gritz_hahn.md) are
for the default terminal set.
"""
from dataclasses import replace

import numpy as np

from gpmotion.model import make_scene
from gpmotion.task import Ease, Term, register_task
from gpmotion.tasks._herman import (GP_DEFAULTS, MAIN_WEIGHT, NOSE_SEARCH, TERMINALS, SelfContact,
                                    TrunkCheck)
from gpmotion.tasks.herman_touch_object import HermanTouchObject

FELL = 0.20            # m: the pelvis dropped this much
STEADY = 0.05          # m: largest pelvis excursion of a success
FOOT_FORCES = ("force_heel_r", "force_toe_r", "force_heel_l", "force_toe_l")
START = (0.45, -0.15, 0.05)    # pelvis frame (m): v4's object at the run's start, low in front
EASE = (0.0, 0.7)              # run progress over which v4's object travels to its place


@register_task
class HermanReachStanding(HermanTouchObject):
    name = "herman_reach_standing"
    figure = "herman_standing"
    # v1: 1 ms, not the arm tasks' 2 ms (v2 steps at 2 ms, below)
    dt = 1e-3
    record_every = 10
    description = "Herman, standing free on his feet, touches an object and keeps his balance"
    # Rate targets, as herman_touch_object (inherited), and 35 generations: a
    # generation of the standing body costs ~3 s of main-thread CPU, so 50 took
    # 121-148 s; 5 seeds: 3 / 5 solved in 104-112 s (angle, 50: 0 / 5)
    gp = replace(HermanTouchObject.gp, defaults={**GP_DEFAULTS, "generations": 35})
    terms = HermanTouchObject.terms + (
        Term("balance", MAIN_WEIGHT, doc="largest horizontal pelvis excursion (m), +1 if it fell"),)
    success_threshold = (f"{HermanTouchObject.success_threshold}, pelvis within "
                         f"{STEADY * 100:.0f} cm of where it stood")
    params = {**HermanTouchObject.params, "forces": 0.0}
    bounds = {**HermanTouchObject.bounds, "forces": (0, 1)}
    param_docs = {**HermanTouchObject.param_docs,
                  "forces": "1: the soles' contact forces are terminals too (the paper's force sensors)"}

    def __init__(self, **overrides):
        super().__init__(**overrides)
        if self.params["forces"]:
            self.gp = replace(self.gp, terminals=TERMINALS + FOOT_FORCES)

    def scene(self):
        # herman_standing's own ground (its TOML's [ground]): stiff enough for 70 kg
        goal = self.object_position()
        return make_scene(goal=tuple(float(v) for v in goal), **self.figure.ground)

    def measure(self, traj):
        out = super().measure(traj)
        pelvis = traj.base()[..., :3]                          # [E, F, 3]
        start = pelvis[:, :1]
        drift = np.linalg.norm((pelvis - start)[..., :2], axis=-1).max(axis=1)
        fell = (start[..., 2] - pelvis[..., 2]).max(axis=1) > FELL
        out["balance"] = drift + fell
        return out

    def reached(self, traj, m):
        return super().reached(traj, m) & (m["balance"] < STEADY)

    def describe(self, traj, m):
        return super().describe(traj, m) + [f"pelvis moved {m['balance'][0] * 100:.1f} cm at most"]


@register_task
class HermanReachStandingV2(HermanReachStanding):
    """v2: a 2 ms step (v1: 1 ms) and herman_touch_object's budget, 50
    generations of which the last 10 polish.  The 1 ms step was a guess the
    figure's own stability bounds do not need (herman_standing.toml: still
    < 2 at 2 ms), and over random arm motions with the pelvis within 5 cm
    the fingertip stays within 8 mm of a 0.5 ms run (test_herman); at 1 ms a
    run could afford 35 generations (3 / 5 in 104-112 s), at 2 ms
    50 with polish: 5 seeds, 4 / 5 in 62-67 s."""
    version = 2
    dt = 2e-3
    record_every = 5
    gp = replace(HermanReachStanding.gp, defaults=HermanTouchObject.gp.defaults)


@register_task
class HermanReachStandingV3(TrunkCheck, HermanReachStandingV2):
    """v3: the right forearm may not cross the trunk (``_herman.TrunkCheck``;
    the forearm check found v2's seed 0 with the forearm 8.3 cm
    into the trunk)."""
    version = 3


@register_task
class HermanReachStandingV4(SelfContact, HermanReachStandingV3):
    """v4: the nose's recipe (the right forearm and hand collide with the
    trunk, angle targets, the last 20 of the 50 generations polish, the rest
    term x3), a curriculum on the object's place and the through term x3.
    The object starts low in front (``START``, where the arm swung forward
    from hanging meets it first) and travels in a straight line to its place
    over the first 70 % of the run (``EASE``).  The recipe alone left seeds
    settled 9-10 cm short with the arm folded, a pose no search left
    (3 / 5, the misses never touching); with the
    curriculum every seed touched at rest but two struck the trunk hard
    enough at the start to sink the forearm 1.0-1.2 cm into it for an instant
    (3 / 5), which the heavier through term charges.  5 seeds:
    4 / 5 in 78-100 s of main-thread CPU."""
    version = 4
    gp = replace(HermanReachStandingV3.gp, **NOSE_SEARCH)
    terms = tuple(replace(t, param="w_through") if t.name == "through" else t
                  for t in HermanReachStandingV3.terms)
    params = {**HermanReachStandingV3.params, "w_rest": 3.0, "w_through": 3.0, "travel": 1.0,
              "travel_start": 0.0}
    bounds = {**HermanReachStandingV3.bounds, "travel": (0, 1), "travel_start": (0, 1)}
    param_docs = {**HermanReachStandingV3.param_docs,
                  "w_through": "multiplier on the through term's weight (v3: 1)",
                  "travel": f"the object's place as a fraction of the way from {START} (pelvis "
                            "frame, m) to its target (x, y, z or the preset); 1: at the target",
                  "travel_start": "where on that way the object starts the run (the "
                                  "curriculum's start); 1: no curriculum"}

    @property
    def curriculum(self):
        return {"travel": Ease(float(self.params["travel_start"]), EASE,
                               doc="the object travels from low in front to its place")}

    def object_position(self) -> np.ndarray:
        end, start = super().object_position(), self.pelvis_point(START)
        return start + self.params["travel"] * (end - start)
