"""lamp_limbo: hop to the target under a horizontal pole (Gritz & Hahn).

As lamp_hop, with a pole halfway between start and target and a large
penalty for touching it.  Pole height (of its lowest point) is a parameter;
``gpmotion run lamp_limbo --param pole_height=0.36,0.40,0.44`` runs a series.
"""

from gpmotion.gp.subgoals import Subgoal
from gpmotion.model import make_scene
from gpmotion.task import Ease, Task, Term, register_task
from gpmotion.tasks.lamp_hop import (ARRIVED, HOP_TERMS, PAPER_TERMINALS, count_hops,
                                     hop_measures)

POLE_RADIUS = 0.01


def with_pole(m, traj):
    """The measures plus "pole": touched it (+ 100 × deepest penetration in m)."""
    pen = traj.pole_hit.max(axis=1)
    m["pole"] = (pen > 0).astype(float) + 100.0 * pen
    return m


def limbo_success(m):
    return (m["distance"] < ARRIVED) & (m["fell"] == 0) & (m["pole"] == 0) & (m["head_hit"] == 0)


@register_task
class LampLimbo(Task):
    name = "lamp_limbo"
    figure = "lamp"
    goal_label = "target"          # pictures: the scene goal, captioned
    description = "the lamp hops to a target, passing under a limbo pole"
    params = {"distance": 0.6, "seconds": 4.0, "pole_height": 0.42,   # standing, the lamp is 0.50 m tall
              "pole_start": 0.60}
    bounds = {"distance": (0.1, 5.0), "pole_height": (0.1, 1.0), "pole_start": (0.1, 1.0)}
    param_docs = {"distance": "target x (m); the pole stands halfway",
                  "pole_height": "height of the pole's underside (m)", "seconds": "episode length (s)",
                  "pole_start": "the pole's height at the start of a run, lowered to pole_height over "
                                "the first half (m); = pole_height: no curriculum"}
    terms = HOP_TERMS + (
        Term("pole", 2.0, doc="touched the pole (+ 100 × deepest penetration in m)"),
    )
    success_threshold = "base within 5 cm of the target, pole and head untouched, not fallen"
    paper_terminals = PAPER_TERMINALS           # the gritz-hahn preset's terminal set

    @property
    def curriculum(self):
        """The pole comes down over the first half of the run: from pole_start
        (0.60 m, above the standing lamp) to pole_height.  With the full-height
        pole from the start most runs settle on standing in front of it (2/5
        seeds solved); lowered gradually, the lamp first learns to hop, then to
        duck.  ``pole_start=pole_height`` turns the curriculum off."""
        start = self.params["pole_start"]
        if start == self.params["pole_height"]:
            return {}
        return {"pole_height": Ease(start, (0.1, 0.5), doc=f"pole lowered from {start:g} m")}

    def subgoals(self):
        """Subgoal terminals (GP option ``subgoals``): passed the pole, arrived."""
        return (Subgoal("passed_pole", "px", "gt", -self.params["distance"] / 2,
                        doc="base beyond the pole (px is relative to the target)"),
                Subgoal("arrived", "px", "abs_lt", ARRIVED, doc="base within 5 cm of the target"))

    def validate(self):
        if not 0.1 <= self.params["distance"] <= 5.0:
            raise ValueError(f"lamp_limbo: distance must be within 0.1..5 m, got {self.params['distance']}")
        for k in ("pole_height", "pole_start"):
            if not 0.1 <= self.params[k] <= 1.0:
                raise ValueError(f"lamp_limbo: {k} must be within 0.1..1 m, got {self.params[k]}")

    def scene(self):
        pole = (self.params["distance"] / 2, self.params["pole_height"] + POLE_RADIUS, POLE_RADIUS)
        return make_scene(goal=(self.params["distance"], 0.0), poles=[pole])

    def measure(self, traj):
        return with_pole(hop_measures(self, traj), traj)

    def success(self, traj, m):
        return limbo_success(m)

    def describe(self, traj, m):
        return [f"hops: {count_hops(traj)}", f"pole {'touched' if m['pole'][0] else 'clear'}",
                f"final distance {m['distance'][0] * 100:.1f} cm"]
