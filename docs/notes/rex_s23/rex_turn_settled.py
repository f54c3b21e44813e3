"""rex_turn_settled: a Rex turn that stops at about 90° (session 23's
experiment, a plugin: ``--plugins docs/notes/rex_s23``; not a shipped task).

rex_turn-v2's turns (session 15, seeds 0-4) spun 122-471° in 3 s and handed
over still spinning (seed 1: 230°/s), and no second walk started from them
reached 1 m.  Here the heading change pays up to ``target_degrees``, each
radian past it costs ``w_over``, and the yaw rate over the motion's last
0.25 s costs ``w_spin`` per rad/s.  Solved as v2 (≥ 45°, never fallen in 4 s).
"""
import numpy as np

from gpmotion.bsr import secondary3d as s3
from gpmotion.task import Term, register_task
from gpmotion.tasks._creature3d import FACTS
from gpmotion.tasks.rex_turn import RexTurn, RexTurnV2
from gpmotion.tasks.rex_walk import RexTask


@register_task
class RexTurnSettled(RexTurnV2):
    name = "rex_turn_settled"
    version = 1
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
