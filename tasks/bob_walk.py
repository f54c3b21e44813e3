"""bob_walk: Bob the Biped walks forward, facing forward (Auslander et al. §4.2, Fig. 17).

Footnote 10's fitness: forward motion of the centre of mass and of the feet
(rewarded), sideways motion, falling over and net rotation about the
vertical axis (penalized; the last "to encourage more conventional
forward-facing walking").  Solved: ≥ 5 forward steps (a foot touching down
ahead of the other) before falling, facing within 45° of the start heading.
"""
import numpy as np

from gpmotion.task import Term, register_task
from gpmotion.tasks._creature3d import CreatureTask


def bob_terms(p):
    return (Term("distance", -1.0, main=True, doc="com displacement along the start heading (m)"),
            Term("feet_forward", -float(p["w_feet"]), doc="mean forward displacement of the feet (m)"),
            Term("sideways", float(p["w_sideways"]), doc="|com displacement across the start heading| (m)"),
            Term("fall", float(p["w_fall"]), doc="fraction of the episode fallen"),
            Term("rotation", float(p["w_rotation"]), doc="|net rotation about the vertical| (rad)"))


@register_task
class BobWalk(CreatureTask):
    name = "bob_walk"
    figure = "bob"
    description = "Bob the Biped (9 rods, point feet) walks forward, facing forward"
    feet = ("foot_l", "foot_r")
    foot_sites = ("foot_l", "foot_r")
    foot_groups = (("foot_l",), ("foot_r",))
    max_tilt = np.radians(45.0)     # Bob's pelvis tilted 45° or his com 30 % lower: fallen
    min_height = 0.7
    params = {"seconds": 4.0, "success_steps": 5.0, "w_feet": 0.5, "w_sideways": 0.5, "w_fall": 2.0,
              "w_rotation": 0.3, "after": ""}
    param_docs = {"seconds": "episode length (s)",
                  "success_steps": "forward steps before falling that count as solved",
                  "w_feet": "reward per m of forward foot motion",
                  "w_sideways": "penalty per m of sideways com motion",
                  "w_fall": "penalty for falling (× fraction of the episode fallen)",
                  "w_rotation": "penalty per rad of net rotation about the vertical",
                  "after": "start from the end of these saved controllers (comma-separated files)"}
    terms = bob_terms(params)
    success_threshold = "≥ 5 forward steps before falling, facing forward"

    @classmethod
    def make_terms(cls, params):
        return bob_terms(params)

    def success(self, traj, m):
        return m["steps"] >= self.params["success_steps"]

    def describe(self, traj, m, e=0):
        return [f"{int(m['steps'][e])} forward steps, forward {m['distance'][e]:.2f} m, "
                f"sideways {m['sideways'][e]:.2f} m, rotation {m['rotation'][e] * 57.2958:.0f}°, "
                f"fallen {100 * m['fall'][e]:.0f}% of the time"]
