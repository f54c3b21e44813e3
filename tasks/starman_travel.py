"""starman_travel: Mr. Star-Man travels to the right (Auslander et al. §2.2).

Primary: horizontal distance of the centre of mass.  Table 3 secondary terms
with weights as parameters: ``w_contact_distance`` > 0 tends to a shuffle,
``w_rotations`` > 0 to a cartwheel, ``w_max_height`` > 0 to hops.
"""
from gpmotion.task import register_task
from gpmotion.tasks._travel import TravelTask


@register_task
class StarmanTravel(TravelTask):
    name = "starman_travel"
    figure = "starman"
    description = "Mr. Star-Man travels right (shuffle, cartwheel...)"
