"""lamp_hop: the desk lamp hops to a target point (Gritz & Hahn).

Main goal: distance from the base centre to the target at the end.  Style
points, phased in once the lamp has learned to arrive: arrive early, stay
put after arriving, never hit the head or fall over, end at the neutral pose.

``--param falls_final=1`` ends a fallen episode at its fall (Task.fall_stop):
a search then simulates a fifth to two fifths of the steps, but scores a fall
where it happened, which hides the head hit that follows; off by default
(docs/speed.md).
"""
import numpy as np

from gpmotion.gp.settings import GPSettings
from gpmotion.gp.subgoals import Subgoal
from gpmotion.model import make_scene
from gpmotion.task import Task, Term, register_task

ARRIVED = 0.05          # m: "at the target"
FELL = 1.0              # rad: the base pitched beyond this has fallen
FALLS_FINAL_DOC = ("1: a fall ends the episode: it is scored as it stood at the first recorded "
                   "frame with the base pitched beyond 1 rad, and the rest is not simulated")
# Gritz & Hahn's lamp terminals: position relative to the goal, velocity, the
# force the floor puts on the base (its two contact points), time
PAPER_TERMINALS = ("px", "pz", "vx", "vz", "force_base_back", "force_base_front", "t")


def hop_measures(task, traj):
    """The lamp_hop terms (lamp_limbo adds the pole)."""
    fig = traj.figure
    base = traj.site("base_centre")                       # [E, F, 2]
    goal = np.array([task.params["distance"], 0.0])
    d = np.linalg.norm(base - goal, axis=-1)             # [E, F]
    at = d < ARRIVED
    first = np.where(at.any(axis=1), at.argmax(axis=1), d.shape[1] - 1)
    late = traj.times[first] / task.seconds              # 1 when it never arrives
    after = np.arange(d.shape[1])[None, :] >= first[:, None]
    speed = np.linalg.norm(traj.com[..., 2:4], axis=-1)
    moving = np.where(after, speed, 0.0).sum(axis=1) / np.maximum(after.sum(axis=1), 1)
    heads = [fig.contact_names.index(c) for c in ("head_tip", "head_rim")]
    head_force = traj.contact_force[..., heads].max(axis=(1, 2))
    pitch = traj.base()[..., 0]
    fell = np.abs(pitch).max(axis=1) > FELL
    act = fig.model.act_dof
    neutral = np.abs(traj.q[:, -1, act] - fig.model.neutral).mean(axis=1)
    return {"distance": d[:, -1], "late": late, "moving": moving,
            "head_hit": (head_force > 0).astype(float) + head_force / (fig.total_mass * 9.81),
            "fell": fell.astype(float), "neutral": neutral,
            "energy": traj.energy.sum(axis=1)}


HOP_TERMS = (
    Term("distance", 1.0, main=True, doc="m from the base centre to the target at the end"),
    Term("late", 0.1, phase=(0.2, 0.5), doc="arrival time / episode (1: never)"),
    Term("moving", 0.1, phase=(0.3, 0.6), doc="mean speed of the com after arriving (m/s)"),
    Term("head_hit", 0.3, phase=(0.2, 0.5), doc="head touched the ground (+ peak force / weight)"),
    Term("fell", 0.5, phase=(0.1, 0.4), doc="base pitched beyond 1 rad"),
    Term("neutral", 0.05, phase=(0.5, 0.8), doc="mean |joint − neutral| at the end (rad)"),
    Term("energy", 0.0, doc="actuator work (J); weight 0 by default, for reports"),
)


@register_task
class LampHop(Task):
    name = "lamp_hop"
    figure = "lamp"
    goal_label = "target"          # pictures: the scene goal, captioned
    description = "the lamp hops to a target point on the floor"
    params = {"distance": 0.4, "seconds": 3.0, "falls_final": 0.0}
    bounds = {"distance": (-5.0, 5.0), "falls_final": (0, 1)}
    param_docs = {"distance": "target x from the start (m; |distance| ≥ 0.05)",
                  "seconds": "episode length (s)", "falls_final": FALLS_FINAL_DOC}
    terms = HOP_TERMS
    success_threshold = "base within 5 cm of the target at the end, head never touched, not fallen"
    # the style terms phase in over 16 generations; the run stops once they are at full
    # weight and the final-weights best gained < 1 % in 3 generations, at 24 at most
    # (seeds 0-4: 14-15 M simulated steps, cost 0.073-0.077; 40 fixed generations: 35 M);
    # paper_terminals: the gritz-hahn preset's terminal set
    gp = GPSettings(defaults={"generations": 24, "phase_span": 16, "patience": 3},
                    paper_terminals=PAPER_TERMINALS)

    def subgoals(self):
        """Subgoal terminals (GP option ``subgoals``): 1.0 once arrived."""
        return (Subgoal("arrived", "px", "abs_lt", ARRIVED, doc="base within 5 cm of the target"),)

    def validate(self):
        if not 0.05 <= abs(self.params["distance"]) <= 5.0:
            raise ValueError(f"lamp_hop: distance must be within 0.05..5 m, got {self.params['distance']}")
        check_flag(self, "falls_final")

    def fall_stop(self):
        """With ``falls_final=1``: a fall (the base pitched beyond 1 rad) ends the episode."""
        return FELL if self.params["falls_final"] else None

    def scene(self):
        return make_scene(goal=(self.params["distance"], 0.0))

    def measure(self, traj):
        return hop_measures(self, traj)

    def success(self, traj, m):
        return (m["distance"] < ARRIVED) & (m["fell"] == 0) & (m["head_hit"] == 0)

    def describe(self, traj, m):
        return [f"hops: {count_hops(traj)}", f"final distance {m['distance'][0] * 100:.1f} cm"]


def check_flag(task, key):
    """A 0/1 parameter is 0 or 1."""
    if task.params[key] not in (0.0, 1.0):
        raise ValueError(f"{task.name}: {key} must be 0 or 1, got {task.params[key]:g}")


def count_hops(traj, e=0):
    """Hops of episode e: flights of the whole lamp, as the filmstrip marks them."""
    from gpmotion.frames import flights
    return flights(traj, e)
