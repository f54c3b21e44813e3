"""starman_travel_feet: starman_travel with contact_distance read on the feet
only (session 24's experiment, a plugin: ``--plugins docs/notes/auslander_feet``;
not a shipped task).

Table 3's contact_distance is the "distance traversed by body parts in
continuous contact with ground"; ours counts every contact point, so on the
reproduction figures 7 of 10 contact_distance searches slide on hands and
feet, which earns more of the term than a two-footed shuffle.  Here only
foot_l and foot_r count.
"""
import numpy as np

from gpmotion.bsr import secondary
from gpmotion.sim import geometry
from gpmotion.task import register_task
from gpmotion.tasks.starman_travel import StarmanTravel


@register_task
class StarmanTravelFeet(StarmanTravel):
    name = "starman_travel_feet"
    version = 1
    description = "Mr. Star-Man travels right; contact_distance counts the feet only"
    FEET = ("foot_l", "foot_r")

    def measure(self, traj):
        m = super().measure(traj)
        fig = traj.figure
        feet = np.array([fig.contact_names.index(n) for n in self.FEET])
        cx = geometry.points_world(fig.model, traj.poses(), fig.model.cp_link[feet],
                                   fig.model.cp_pos[feet])[..., 0]
        m["contact_distance"] = secondary.contact_distance(traj.contact_force[..., feet], cx, direction=1.0)
        return m
