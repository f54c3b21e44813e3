"""rex_walk: Rex walks forward (Auslander et al. §4.1, Fig. 16).

Fitness "the distance traveled by his center of mass ... but it also
included secondary terms that penalized sideways motion and falling down":
cost = −distance + w_sideways·|sideways| + w_fall·(fraction of the episode
fallen), all in the frame Rex starts in.  With ``after`` (the walk's and the
turn's controllers) this is the third stage of walk → turn → walk.
Solved: ≥ 1 m forward without falling.
"""
import numpy as np

from gpmotion.task import register_task
from gpmotion.tasks._creature3d import DISTANCE, FALL, SIDEWAYS, CreatureTask

FEET = ("heel_l", "toe_l", "toe_in_l", "toe_out_l", "heel_r", "toe_r", "toe_in_r", "toe_out_r")


class RexTask(CreatureTask):
    """What Rex's tasks share: his figure, feet and fall test, and the walk's
    penalties for sideways motion and falling."""
    figure = "rex"
    feet = FEET
    foot_sites = ("foot_l", "foot_r")
    foot_groups = (FEET[:4], FEET[4:])
    max_tilt = np.radians(30.0)     # Rex's trunk pitched 30° or his com 25 % lower: fallen
    min_height = 0.75               # (at 60°/50 % a search walked by falling slowly forward)
    penalties = (SIDEWAYS, FALL)


@register_task
class RexWalk(RexTask):
    name = "rex_walk"
    description = "Rex (15 rods, 10 free angles) walks forward without falling"
    params = {"seconds": 3.0, "success_distance": 1.0, "w_sideways": 0.5, "w_fall": 10.0, "after": ""}
    param_docs = {**RexTask.param_docs, "success_distance": "com travel that counts as solved (m)"}
    terms = (DISTANCE, *RexTask.penalties)
    success_threshold = "com ≥ 1 m forward, never fallen"
    facts = ("forward", "sideways", "heading", "steps", "fallen")

    def success(self, traj, m):
        return (m["distance"] >= self.params["success_distance"]) & (m["fall"] == 0)


@register_task
class RexWalkV2(RexWalk):
    """v2: the walk must leave Rex upright.  Every v1 walk we evolved (4 of 5
    seeds "solved" at 10,000 evaluations) toppled within 0.1-0.2 s after its
    last frame: a lunge that covers 1 m and falls, and a turn started from it
    could only fall.  Here the controller runs 1 s past the 3 s (``hold``),
    a fall then counts, and the distance is still taken at 3 s."""
    version = 2
    params = {**RexWalk.params, "hold": 1.0}
    success_threshold = "com ≥ 1 m forward in 3 s, never fallen in 4 s"
