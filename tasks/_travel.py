"""Shared by the travel tasks: Auslander's primary term (horizontal distance
of the centre of mass) plus the Table 3 secondary terms, and a gait report."""
from gpmotion import gaits
from gpmotion.bsr import secondary
from gpmotion.sim import geometry
from gpmotion.task import Task, Term


# rewards as negative weights: cost = −(distance + Σ w·secondary); the w are parameters
TRAVEL_TERMS = (Term("distance", -1.0, main=True, doc="com x displacement (m), rewarded"),
                Term("max_height", -1.0, param="w_max_height", doc="highest com z (m)"),
                Term("contact_distance", -1.0, param="w_contact_distance",
                     doc="m travelled right by points in continuous contact (shuffle)"),
                Term("rotations", -1.0, param="w_rotations", doc="whole-body turns (fractional)"),
                Term("grounded_distance", -1.0, param="w_grounded_distance",
                     doc="m the com travels right while some point touches (contact_distance "
                         "read for pinned contacts: a flight earns nothing)"))


def travel_measures(traj):
    fig = traj.figure
    x = traj.com[..., 0]
    poses = traj.poses()
    cx = geometry.points_world(fig.model, poses, fig.model.cp_link, fig.model.cp_pos)[..., 0]
    pitch = traj.base()[..., 0]
    return {"distance": x[:, -1] - x[:, 0],
            "max_height": secondary.max_height(traj.com[..., 1]),
            # signed along +x: forward travel while touching pays, sliding in place does not
            "contact_distance": secondary.contact_distance(traj.contact_force, cx, direction=1.0),
            "rotations": secondary.rotations(pitch, whole=False),
            "grounded_distance": secondary.grounded_distance(traj.contact_force, x)}


def gait(traj, m, e=0):
    """Name the motion found by gpmotion.gaits' definitions, with its evidence."""
    name, f = gaits.gait_of(traj, e)
    contacts = (traj.contact_force[e] > 0).mean(axis=0)
    pattern = ", ".join(f"{n} {100 * c:.0f}%" for n, c in zip(traj.figure.contact_names, contacts))
    return [f"gait: {name}", *f.lines(), f"contact_distance (travel in contact) {m['contact_distance'][e]:.2f} m",
            f"contact time: {pattern}"]


TRAVEL_PARAMS = {"w_max_height": 0.0, "w_contact_distance": 0.0, "w_rotations": 0.0,
                 "w_grounded_distance": 0.0}


class TravelTask(Task):
    """Travel right: cost = −(com distance + Σ w·secondary term)."""
    params = {"seconds": 3.0, "success_distance": 1.0, **TRAVEL_PARAMS}
    param_docs = {"seconds": "episode length (s)",
                  "success_distance": "com travel that counts as solved (m)",
                  "w_max_height": "weight of the max_height reward (Auslander's Table 3)",
                  "w_contact_distance": "weight of the contact_distance reward (shuffle)",
                  "w_rotations": "weight of the rotations reward (cartwheel)",
                  "w_grounded_distance": "weight of the grounded_distance reward (contact_distance "
                                         "read for the paper's pinned contacts: travel without flight)"}
    terms = TRAVEL_TERMS
    success_threshold = "centre of mass travels ≥ success_distance (1 m) to the right"
    record_every = 20           # 50 frames/s resolve every gait event these terms use

    def measure(self, traj):
        return travel_measures(traj)

    def success(self, traj, m):
        return m["distance"] >= self.params["success_distance"]

    def describe(self, traj, m):
        return gait(traj, m)
