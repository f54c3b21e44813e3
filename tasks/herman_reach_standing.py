"""herman_reach_standing: Herman, standing free on his feet, touches an object
with his right fingertip and keeps his balance.

As ``herman_touch_object`` (same targets, in the frame of the pelvis at the
start), on ``herman_standing``: the pelvis is a free root, so the arm's
swing pushes the body, and the PD-held legs and trunk must absorb it.  One
extra term, on from the start: ``balance``, the largest horizontal excursion
of the pelvis from where it stood (m), plus 1 if it drops by more than
20 cm (a fall).  The ground is the figure's own (stiff: see its TOML).
"""
import numpy as np

from gpmotion.model import make_scene
from gpmotion.task import Term, register_task
from gpmotion.tasks._herman import MAIN_WEIGHT
from gpmotion.tasks.herman_touch_object import HermanTouchObject

FELL = 0.20            # m: the pelvis dropped this much
STEADY = 0.05          # m: largest pelvis excursion of a success


@register_task
class HermanReachStanding(HermanTouchObject):
    name = "herman_reach_standing"
    figure = "herman_standing"
    description = "Herman, standing free on his feet, touches an object and keeps his balance"
    terms = HermanTouchObject.terms + (
        Term("balance", MAIN_WEIGHT, doc="largest horizontal pelvis excursion (m), +1 if it fell"),)
    success_threshold = (f"{HermanTouchObject.success_threshold}, pelvis within "
                         f"{STEADY * 100:.0f} cm of where it stood")

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

    def success(self, traj, m):
        return super().success(traj, m) & (m["balance"] < STEADY)

    def describe(self, traj, m):
        return super().describe(traj, m) + [f"pelvis moved {m['balance'][0] * 100:.1f} cm at most"]
