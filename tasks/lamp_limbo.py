"""lamp_limbo: hop to the target under a horizontal pole (Gritz & Hahn).

As lamp_hop, with a pole halfway between start and target and a large
penalty for touching it.  Pole height (of its lowest point) is a parameter;
``gpmotion run lamp_limbo --param pole_height=0.36,0.40,0.44`` runs a series.

``--param pole_senses=1`` adds two task senses (gpmotion.gp.task_senses) to
the GP terminals, Gritz & Hahn's "the pole's position relative to the head":
``head_pole_dx``, the head tip forward of the pole (m; < 0 before it), and
``head_z``, the head tip's height above the floor (m), both by forward
kinematics over the lamp's senses.  Off by default: the measured success
rates are for the default terminal set.
"""
from dataclasses import replace

import numpy as np

from gpmotion.gp.subgoals import Subgoal
from gpmotion.gp.task_senses import TaskSense, planar_site_formulas
from gpmotion.task import Ease, Term, register_task
from gpmotion.tasks.lamp_hop import ARRIVED, FALLS_FINAL_DOC, HOP_TERMS, LampHop, check_flag

POLE_RADIUS = 0.01
POLE_SENSES = ("head_pole_dx", "head_z")    # task senses (pole_senses=1)


class Limbo:
    """What a limbo task adds to its hop task (``class X(Limbo, Hop)``): a pole
    halfway to the target, lowered over the first half of a run, and a large
    penalty for touching it."""
    terms = HOP_TERMS + (
        Term("pole", 2.0, doc="touched the pole (+ 100 × deepest penetration in m)"),
    )

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

    def validate(self):
        if not 0.1 <= self.params["distance"] <= 5.0:
            raise ValueError(f"{self.name}: distance must be within 0.1..5 m, got {self.params['distance']}")
        for k in ("pole_height", "pole_start"):
            if not 0.1 <= self.params[k] <= 1.0:
                raise ValueError(f"{self.name}: {k} must be within 0.1..1 m, got {self.params[k]}")

    def scene(self):
        """The hop's scene with the pole (x, z of its axis, radius)."""
        pole = (self.params["distance"] / 2, self.params["pole_height"] + POLE_RADIUS, POLE_RADIUS)
        return super().scene()._replace(poles=np.array([pole], dtype=np.float64))

    def measure(self, traj):
        """The hop's measures plus "pole": touched it (+ 100 × deepest penetration in m)."""
        m = super().measure(traj)
        pen = traj.pole_hit.max(axis=1)
        m["pole"] = (pen > 0).astype(float) + 100.0 * pen
        return m

    def success(self, traj, m):
        return super().success(traj, m) & (m["pole"] == 0)

    def describe(self, traj, m):
        facts = super().describe(traj, m)
        facts.insert(1, f"pole {'touched' if m['pole'][0] else 'clear'}")     # after the hops
        return facts


@register_task
class LampLimbo(Limbo, LampHop):
    name = "lamp_limbo"
    # 40 generations in full: shorter schedules solve the limbo less often (docs/speed.md)
    gp = replace(LampHop.gp, defaults={})
    description = "the lamp hops to a target, passing under a limbo pole"
    params = {"distance": 0.6, "seconds": 4.0, "pole_height": 0.42,   # standing, the lamp is 0.50 m tall
              "pole_start": 0.60, "pole_senses": 0.0, "falls_final": 0.0}
    bounds = {"distance": (0.1, 5.0), "pole_height": (0.1, 1.0), "pole_start": (0.1, 1.0),
              "pole_senses": (0, 1), "falls_final": (0, 1)}
    param_docs = {"distance": "target x (m); the pole stands halfway",
                  "pole_height": "height of the pole's underside (m)", "seconds": "episode length (s)",
                  "pole_start": "the pole's height at the start of a run, lowered to pole_height over "
                                "the first half (m); = pole_height: no curriculum",
                  "pole_senses": "1: the head tip relative to the pole (head_pole_dx, head_z) "
                                 "are GP terminals too",
                  "falls_final": FALLS_FINAL_DOC}
    success_threshold = "base within 5 cm of the target, pole and head untouched, not fallen"

    def __init__(self, **overrides):
        super().__init__(**overrides)
        check_flag(self, "pole_senses")
        check_flag(self, "falls_final")
        if self.params["pole_senses"]:
            self.gp = replace(self.gp, terminals=tuple(self.figure.sense_names) + POLE_SENSES)

    def task_senses(self):
        """The head tip relative to the pole (the formulas give it relative to
        the scene goal, the target; the floor is at z = 0)."""
        x, z = planar_site_formulas(self.figure, "head_tip")
        (gx, gz), pole_x = self.scene().goal, self.params["distance"] / 2
        return (TaskSense("head_pole_dx", f"{x} + {float(gx - pole_x)!r}",
                          "head tip forward of the pole, m"),
                TaskSense("head_z", f"{z} + {float(gz)!r}" if gz else z, "head tip above the floor, m"))

    def subgoals(self):
        """Subgoal terminals (GP option ``subgoals``): passed the pole, arrived."""
        return (Subgoal("passed_pole", "px", "gt", -self.params["distance"] / 2,
                        doc="base beyond the pole (px is relative to the target)"),
                Subgoal("arrived", "px", "abs_lt", ARRIVED, doc="base within 5 cm of the target"))
