"""rex_turn: Rex turns (Auslander et al. §4.1, Fig. 16), "given the final
state of that walk" (``after`` = the walk's best.json).

Fitness: the change in heading (|Δ yaw| of the trunk, either direction,
rad), with the walk's penalties for sideways motion and falling.
Solved: heading changed by ≥ 45° without falling.

v3 (the default) is a turn that stops: v2's turns spun 122-471° in 3 s and
handed over still spinning (230°/s), and no second walk searched from them
reached 1 m (docs/reproduction/auslander.md).
"""
import numpy as np

from gpmotion.bsr import secondary3d as s3
from gpmotion.task import Term, register_task
from gpmotion.tasks._creature3d import FACTS
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


@register_task
class RexTurnV3(RexTurnV2):
    """v3: the heading change pays up to ``target_degrees``, each radian past
    it costs ``w_over`` and the yaw rate over the motion's last 0.25 s costs
    ``w_spin`` per rad/s, so the second walk starts from a settled turn.
    Success is v2's.  With it the walk → turn → walk sequence completes on
    2 of 5 seeds."""
    version = 3
    description = "Rex turns by about 90° and stops turning, without falling"
    params = {**RexTurnV2.params, "target_degrees": 90.0, "w_over": 1.0, "w_spin": 0.5}
    param_docs = {**RexTurn.param_docs,
                  "target_degrees": "heading change that earns full credit (°)",
                  "w_over": "penalty per rad turned past the target",
                  "w_spin": "penalty per rad/s of yaw rate over the motion's last 0.25 s"}
    terms = (Term("turn_credit", -1.0, main=True, doc="min(|change of heading|, target) (rad)"),
             Term("overshoot", 1.0, param="w_over", doc="|change of heading| past the target (rad)"),
             Term("spin", 1.0, param="w_spin", doc="|yaw rate| over the motion's last 0.25 s (rad/s)"),
             *RexTask.penalties)
    success_threshold = "heading changes ≥ 45° in 3 s, never fallen in 4 s (credit up to 90°)"
    facts = ("heading", "spin", "forward", "fallen")
    SETTLE_S = 0.25

    def validate(self):
        super().validate()
        for key in ("target_degrees", "w_over", "w_spin"):
            v = self.params[key]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v) or v < 0:
                raise ValueError(f"task {self.name}: {key} must be a number >= 0, got {v!r}")

    def measure(self, traj):
        m = super().measure(traj)
        target = np.radians(float(self.params["target_degrees"]))
        m["turn_credit"] = np.minimum(m["turn"], target)
        m["overshoot"] = np.maximum(m["turn"] - target, 0.0)
        frame_s = self.dt * self.record_every
        end = int(round(self.motion_seconds / frame_s))
        k = max(1, int(round(self.SETTLE_S / frame_s)))
        yaw = s3.heading(traj.base()[..., 3:7])
        m["spin"] = np.abs(yaw[..., end] - yaw[..., end - k]) / (k * frame_s)
        return m

    def describe(self, traj, m, e=0):
        facts = {"spin": f"spinning {np.degrees(m['spin'][e]):.0f}°/s at the handover"}
        return [", ".join(facts[f] if f in facts else FACTS[f](m, e) for f in self.facts)]
