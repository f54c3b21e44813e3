"""starman_travel: Mr. Star-Man travels to the right (Auslander et al. §2.2).

Primary: horizontal distance of the centre of mass.  Table 3 secondary terms
with weights as parameters: ``w_contact_distance`` > 0 tends to a shuffle,
``w_rotations`` > 0 to a cartwheel, ``w_max_height`` > 0 to hops.
"""
import numpy as np

from gpmotion.task import Task, register_task
from gpmotion.tasks._travel import TRAVEL_PARAMS, gait, travel_measures, travel_terms


@register_task
class StarmanTravel(Task):
    name = "starman_travel"
    figure = "starman"
    description = "Mr. Star-Man travels right (shuffle, cartwheel...)"
    params = {"seconds": 3.0, "success_distance": 1.0, **TRAVEL_PARAMS}
    terms = travel_terms(TRAVEL_PARAMS)
    actuation = "pd"
    success_threshold = "centre of mass travels ≥ success_distance (1 m) to the right"

    def validate(self):
        self.terms = travel_terms(self.p)

    def measure(self, traj):
        return travel_measures(traj)

    def success(self, traj, m):
        return m["distance"] >= self.p["success_distance"]

    def describe(self, traj, m):
        return gait(traj, m)
