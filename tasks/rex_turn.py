"""rex_turn: Rex turns (Auslander et al. §4.1, Fig. 16), "given the final
state of that walk" (``after`` = the walk's best.json).

Fitness: the change in heading (|Δ yaw| of the trunk, either direction,
rad), with the walk's penalties for sideways motion and falling.
Solved: heading changed by ≥ 45° without falling.
"""
import numpy as np

from gpmotion.task import Term, register_task
from gpmotion.tasks.rex_walk import RexTask


def turn_terms(p):
    return (Term("turn", -1.0, main=True, doc="|change of heading| (rad)"),
            Term("sideways", float(p["w_sideways"]), doc="|com displacement across the start heading| (m)"),
            Term("fall", float(p["w_fall"]), doc="fraction of the episode fallen"))


@register_task
class RexTurn(RexTask):
    name = "rex_turn"
    description = "Rex turns (changes heading) without falling"
    params = {"seconds": 3.0, "success_degrees": 45.0, "w_sideways": 0.2, "w_fall": 10.0, "after": ""}
    param_docs = {**RexTask.param_docs,
                  "success_degrees": "heading change that counts as solved (°)"}
    terms = turn_terms(params)
    success_threshold = "heading changes ≥ 45°, never fallen"

    @classmethod
    def make_terms(cls, params):
        return turn_terms(params)

    def success(self, traj, m):
        return (m["turn"] >= np.radians(self.params["success_degrees"])) & (m["fall"] == 0)

    def describe(self, traj, m, e=0):
        return [f"heading change {np.degrees(m['turn'][e]):.0f}°, forward {m['distance'][e]:.2f} m, "
                f"fallen {100 * m['fall'][e]:.0f}% of the time"]
