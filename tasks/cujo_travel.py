"""cujo_travel: Cujo the dog-like creature travels forward (Auslander et al. §4.1, Fig. 15).

"The fitness function for Cujo was simply the distance traveled by his
center of mass": cost = −(com displacement along the start heading), plus an
optional fall penalty (``w_fall``, 0 as in the paper).  Solved: at least one
body length (the 0.6 m trunk) forward and on his feet at the end.  The
report counts bounds: flights with all four feet off the ground.
"""
import numpy as np

from gpmotion.task import Term, register_task
from gpmotion.tasks._creature3d import CreatureTask

BODY_LENGTH = 0.6          # m: Cujo's trunk, shoulder to hip (figures/cujo.toml)
FEET = ("foot_fl", "foot_fr", "foot_hl", "foot_hr")


def bounds(traj, feet=FEET):
    """Flights per episode: runs of frames with all feet off the ground (after touching it)."""
    idx = [traj.figure.contact_names.index(n) for n in feet]
    air = (traj.contact_force[..., idx] <= 0).all(axis=-1)
    return (air[..., 1:] & ~air[..., :-1]).sum(axis=-1)


@register_task
class CujoTravel(CreatureTask):
    name = "cujo_travel"
    figure = "cujo"
    description = "Cujo (7 rods) travels forward, e.g. by bounding"
    feet = FEET
    params = {"seconds": 3.0, "success_distance": BODY_LENGTH, "w_fall": 0.0, "after": ""}
    param_docs = {"seconds": "episode length (s)",
                  "success_distance": "com travel that counts as solved (m; 0.6 = one body length)",
                  "w_fall": "weight of the fall penalty (fraction of the episode fallen)",
                  "after": "start from the end of these saved controllers (comma-separated files)"}
    terms = (Term("distance", -1.0, main=True, doc="com displacement along the start heading (m)"),
             Term("fall", 0.0, doc="fraction of the episode fallen"))
    success_threshold = "com ≥ one body length (0.6 m) forward, upright at the end"

    @classmethod
    def make_terms(cls, params):
        return (cls.terms[0], Term("fall", float(params["w_fall"]), doc=cls.terms[1].doc))

    def measure(self, traj):
        m = super().measure(traj)
        m["bounds"] = bounds(traj).astype(np.float64)
        return m

    def success(self, traj, m):
        return (m["distance"] >= self.params["success_distance"]) & (m["fell"] == 0)

    def describe(self, traj, m, e=0):
        return [f"forward {m['distance'][e]:.2f} m ({m['distance'][e] / BODY_LENGTH:.1f} body lengths), "
                f"sideways {m['sideways'][e]:.2f} m, {int(m['bounds'][e])} bounds, "
                f"{'fell' if m['fell'][e] else 'upright'}"]
