"""lamp3d_limbo: the 3-D lamp hops to a target under a limbo pole.

lamp_limbo on the ``lamp3d`` figure (free base, starts tilted sideways by
``roll0``; see lamp3d_hop): the pole is a horizontal cylinder across the
travel direction, lowered over the first half of a run as in lamp_limbo.
"""
from gpmotion.task import register_task
from gpmotion.tasks.lamp3d_hop import LAMP3D_DOCS, LAMP3D_PARAMS, Lamp3DHop
from gpmotion.tasks.lamp_limbo import LampLimbo, Limbo


@register_task
class Lamp3DLimbo(Limbo, Lamp3DHop):
    name = "lamp3d_limbo"
    description = "the 3-D lamp hops to a target, passing under a limbo pole"
    # falls_final is the planar lamp's: the 3-D lamp runs every episode to its end
    params = {**{k: v for k, v in LampLimbo.params.items() if k != "falls_final"}, **LAMP3D_PARAMS}
    bounds = {**{k: v for k, v in LampLimbo.bounds.items() if k != "falls_final"}, "roll0": (0.0, 1.0)}
    param_docs = {**{k: v for k, v in LampLimbo.param_docs.items() if k != "falls_final"}, **LAMP3D_DOCS}
    success_threshold = ("base within 5 cm of the target in the floor plane, pole and head "
                         "untouched, base never tilted beyond 1 rad")
