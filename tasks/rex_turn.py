"""rex_turn: Rex turns (Auslander et al. §4.1, Fig. 16), "given the final
state of that walk" (``after`` = the walk's best.json).

Fitness: the change in heading (|Δ yaw| of the trunk, either direction,
rad), with the walk's penalties for sideways motion and falling.
Solved: heading changed by ≥ 45° without falling.
"""
import numpy as np

from gpmotion.task import Term, register_task
from gpmotion.tasks.rex_walk import RexTask


@register_task
class RexTurn(RexTask):
    name = "rex_turn"
    description = "Rex turns (changes heading) without falling"
    params = {"seconds": 3.0, "success_degrees": 45.0, "w_sideways": 0.2, "w_fall": 10.0, "after": ""}
    param_docs = {**RexTask.param_docs,
                  "success_degrees": "heading change that counts as solved (°)"}
    terms = (Term("turn", -1.0, main=True, doc="|change of heading| (rad)"), *RexTask.penalties)
    success_threshold = "heading changes ≥ 45°, never fallen"
    facts = ("heading", "forward", "fallen")

    def success(self, traj, m):
        return (m["turn"] >= np.radians(self.params["success_degrees"])) & (m["fall"] == 0)


@register_task
class RexTurnV2(RexTurn):
    """v2: the turn must leave Rex upright for 1 s more (``hold``, as
    rex_walk-v2), so the second walk starts from a state he can walk on."""
    version = 2
    params = {**RexTurn.params, "hold": 1.0}
    success_threshold = "heading changes ≥ 45° in 3 s, never fallen in 4 s"
