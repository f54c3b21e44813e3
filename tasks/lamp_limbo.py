"""lamp_limbo: hop to the target under a horizontal pole (Gritz & Hahn).

As lamp_hop, with a pole halfway between start and target and a large
penalty for touching it.  Pole height (of its lowest point) is a parameter;
``gpmotion run lamp_limbo --param pole_height=0.36,0.40,0.44`` runs a series.
"""
import numpy as np

from gpmotion.model import make_scene
from gpmotion.task import Ease, Task, Term, register_task
from gpmotion.tasks.lamp_hop import ARRIVED, HOP_TERMS, count_hops, hop_measures

POLE_RADIUS = 0.01


@register_task
class LampLimbo(Task):
    name = "lamp_limbo"
    figure = "lamp"
    goal_label = "target"          # pictures: the scene goal, captioned
    description = "the lamp hops to a target, passing under a limbo pole"
    params = {"distance": 0.6, "seconds": 4.0, "pole_height": 0.42}   # standing, the lamp is 0.50 m tall
    bounds = {"distance": (0.1, 5.0), "pole_height": (0.1, 1.0)}
    param_docs = {"distance": "target x (m); the pole stands halfway",
                  "pole_height": "height of the pole's underside (m)", "seconds": "episode length (s)"}
    terms = HOP_TERMS + (
        Term("pole", 2.0, doc="touched the pole (+ 100 × deepest penetration in m)"),
    )
    # The pole comes down over the first half of the run: from above the
    # standing lamp (0.60 m) to pole_height.  With the full-height pole from
    # the start most runs settle on standing in front of it (2/5 seeds
    # solved); lowered gradually, the lamp first learns to hop, then to duck.
    curriculum = {"pole_height": Ease(0.60, (0.1, 0.5), doc="pole lowered from 0.60 m")}
    success_threshold = "base within 5 cm of the target, pole and head untouched, not fallen"

    def validate(self):
        if not 0.1 <= self.p["distance"] <= 5.0:
            raise ValueError(f"lamp_limbo: distance must be within 0.1..5 m, got {self.p['distance']}")
        if not 0.1 <= self.p["pole_height"] <= 1.0:
            raise ValueError(f"lamp_limbo: pole_height must be within 0.1..1 m, got {self.p['pole_height']}")

    def scene(self):
        pole = (self.p["distance"] / 2, self.p["pole_height"] + POLE_RADIUS, POLE_RADIUS)
        return make_scene(goal=(self.p["distance"], 0.0), poles=[pole])

    def measure(self, traj):
        m = hop_measures(self, traj)
        pen = traj.pole_hit.max(axis=1)
        m["pole"] = (pen > 0).astype(float) + 100.0 * pen
        return m

    def success(self, traj, m):
        return (m["distance"] < ARRIVED) & (m["fell"] == 0) & (m["pole"] == 0) & (m["head_hit"] == 0)

    def describe(self, traj, m):
        return [f"hops: {count_hops(traj)}", f"pole {'touched' if m['pole'][0] else 'clear'}",
                f"final distance {m['distance'][0] * 100:.1f} cm"]
