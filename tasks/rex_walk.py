"""rex_walk: Rex walks forward (Auslander et al. §4.1, Fig. 16).

Fitness "the distance traveled by his center of mass ... but it also
included secondary terms that penalized sideways motion and falling down":
cost = −distance + w_sideways·|sideways| + w_fall·(fraction of the episode
fallen), all in the frame Rex starts in.  With ``after`` (the walk's and the
turn's controllers) this is the third stage of walk → turn → walk.
Solved: ≥ 1 m forward without falling.
"""
import numpy as np

from gpmotion.task import Term, register_task
from gpmotion.tasks._creature3d import CreatureTask

FEET = ("heel_l", "toe_l", "toe_in_l", "toe_out_l", "heel_r", "toe_r", "toe_in_r", "toe_out_r")


def walk_terms(p):
    return (Term("distance", -1.0, main=True, doc="com displacement along the start heading (m)"),
            Term("sideways", float(p["w_sideways"]), doc="|com displacement across the start heading| (m)"),
            Term("fall", float(p["w_fall"]), doc="fraction of the episode fallen"))


class RexTask(CreatureTask):
    """What Rex's tasks share: his figure, feet and fall test."""
    figure = "rex"
    feet = FEET
    foot_sites = ("foot_l", "foot_r")
    foot_groups = (FEET[:4], FEET[4:])
    max_tilt = np.radians(30.0)     # Rex's trunk pitched 30° or his com 25 % lower: fallen
    min_height = 0.75               # (at 60°/50 % a search walked by falling slowly forward)
    param_docs = {"seconds": "episode length (s)",
                  "w_sideways": "penalty per m of sideways com motion",
                  "w_fall": "penalty for falling (× fraction of the episode fallen)",
                  "after": "start from the end of these saved controllers (comma-separated files)"}


@register_task
class RexWalk(RexTask):
    name = "rex_walk"
    description = "Rex (15 rods, 10 free angles) walks forward without falling"
    params = {"seconds": 3.0, "success_distance": 1.0, "w_sideways": 0.5, "w_fall": 10.0, "after": ""}
    param_docs = {**RexTask.param_docs,
                  "success_distance": "com travel that counts as solved (m)"}
    terms = walk_terms(params)
    success_threshold = "com ≥ 1 m forward, never fallen"

    @classmethod
    def make_terms(cls, params):
        return walk_terms(params)

    def success(self, traj, m):
        return (m["distance"] >= self.params["success_distance"]) & (m["fall"] == 0)

    def describe(self, traj, m, e=0):
        return [f"forward {m['distance'][e]:.2f} m, sideways {m['sideways'][e]:.2f} m, "
                f"heading change {m['turn'][e] * 57.2958:.0f}°, steps {int(m['steps'][e])}, "
                f"fallen {100 * m['fall'][e]:.0f}% of the time"]
