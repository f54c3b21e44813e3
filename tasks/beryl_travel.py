"""beryl_travel: Beryl Biped travels to the right (Auslander et al. §2.3).

Made for time-based BSR: ``--t-per`` equal to the episode gives an aperiodic
tumble, ``--t-per`` much shorter a periodic shuffle.  Table 3 weights as in
starman_travel.
"""
from gpmotion.task import Task, register_task
from gpmotion.tasks._travel import TRAVEL_PARAMS, gait, travel_measures, travel_terms


@register_task
class BerylTravel(Task):
    name = "beryl_travel"
    figure = "beryl"
    description = "Beryl Biped travels right (tumble, shuffle...)"
    params = {"seconds": 3.0, "success_distance": 1.0, **TRAVEL_PARAMS}
    terms = travel_terms(TRAVEL_PARAMS)
    success_threshold = "centre of mass travels ≥ success_distance (1 m) to the right"

    def validate(self):
        self.terms = travel_terms(self.p)

    def measure(self, traj):
        return travel_measures(traj)

    def success(self, traj, m):
        return m["distance"] >= self.p["success_distance"]

    def describe(self, traj, m):
        return gait(traj, m)
