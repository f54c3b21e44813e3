"""lamp3d_limbo: the 3-D lamp hops to a target under a limbo pole.

lamp_limbo on the ``lamp3d`` figure (free base, starts tilted sideways by
``roll0``; see lamp3d_hop): the pole is a horizontal cylinder across the
travel direction, lowered over the first half of a run as in lamp_limbo.
"""
from gpmotion.model import make_scene
from gpmotion.task import Term, register_task
from gpmotion.tasks.lamp3d_hop import (GROUND, LAMP3D_DOCS, LAMP3D_PARAMS, Lamp3DHop,
                                       count_hops3d, hop3d_measures)
from gpmotion.tasks.lamp_hop import HOP_TERMS
from gpmotion.tasks.lamp_limbo import POLE_RADIUS, LampLimbo, limbo_success, with_pole


@register_task
class Lamp3DLimbo(Lamp3DHop):
    name = "lamp3d_limbo"
    description = "the 3-D lamp hops to a target, passing under a limbo pole"
    params = {**LampLimbo.params, **LAMP3D_PARAMS}
    bounds = {**LampLimbo.bounds, "roll0": (0.0, 1.0)}
    param_docs = {**LampLimbo.param_docs, **LAMP3D_DOCS}
    terms = HOP_TERMS + (
        Term("pole", 2.0, doc="touched the pole (+ 100 × deepest penetration in m)"),
    )
    success_threshold = ("base within 5 cm of the target in the floor plane, pole and head "
                         "untouched, base never tilted beyond 1 rad")
    curriculum = LampLimbo.curriculum

    def validate(self):
        LampLimbo.validate(self)

    def scene(self):
        pole = (self.params["distance"] / 2, self.params["pole_height"] + POLE_RADIUS, POLE_RADIUS)
        return make_scene(goal=(self.params["distance"], 0.0, 0.0), poles=[pole], **GROUND)

    def measure(self, traj):
        return with_pole(hop3d_measures(self, traj), traj)

    def success(self, traj, m):
        return limbo_success(m)

    def describe(self, traj, m):
        return [f"hops: {count_hops3d(traj)}", f"pole {'touched' if m['pole'][0] else 'clear'}",
                f"final distance {m['distance'][0] * 100:.1f} cm",
                f"sideways {m['sideways'][0] * 100:.1f} cm"]
