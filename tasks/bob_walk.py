"""bob_walk: Bob the Biped walks forward, facing forward (Auslander et al. §4.2, Fig. 17).

Footnote 10's fitness: forward motion of the centre of mass and of the feet
(rewarded), sideways motion, falling over and net rotation about the
vertical axis (penalized; the last "to encourage more conventional
forward-facing walking").  Solved: ≥ 5 forward steps (a foot touching down
ahead of the other) before falling, facing within 45° of the start heading.
"""
import numpy as np

from gpmotion.task import Term, register_task
from gpmotion.tasks._creature3d import DISTANCE, FACTS, FALL, SIDEWAYS, CreatureTask


@register_task
class BobWalk(CreatureTask):
    name = "bob_walk"
    figure = "bob"
    description = "Bob the Biped (9 rods, point feet) walks forward, facing forward"
    feet = ("foot_l", "foot_r")
    foot_sites = ("foot_l", "foot_r")
    foot_groups = (("foot_l",), ("foot_r",))
    max_tilt = np.radians(45.0)     # Bob's pelvis tilted 45° or his com 30 % lower: fallen
    min_height = 0.7
    params = {"seconds": 4.0, "success_steps": 5.0, "w_feet": 0.5, "w_sideways": 0.5, "w_fall": 2.0,
              "w_rotation": 0.3, "after": ""}
    param_docs = {**CreatureTask.param_docs,
                  "success_steps": "forward steps before falling that count as solved",
                  "w_feet": "reward per m of forward foot motion",
                  "w_rotation": "penalty per rad of net rotation about the vertical"}
    terms = (DISTANCE,
             Term("feet_forward", -1.0, param="w_feet", doc="mean forward displacement of the feet (m)"),
             SIDEWAYS, FALL,
             Term("rotation", 1.0, param="w_rotation", doc="|net rotation about the vertical| (rad)"))
    success_threshold = "≥ 5 forward steps before falling, facing forward"
    facts = ("steps", "forward", "sideways", "rotation", "fallen")

    def success(self, traj, m):
        return m["steps"] >= self.params["success_steps"]


@register_task
class BobWalkV2(BobWalk):
    """v2: walk facing forward, and do not fall for distance.  With v1's
    fitness every search (time- and sense-based, 10,000 evaluations) found
    one of two things that earn distance without steps that count: a lunge
    that falls (sense-based: 1.8-2.1 m, fallen 49-61 % of the episode, since
    a fall cost only 2 × that fraction) or a waddle whose pelvis swings ±50°
    at each step (time-based: 7 alternating steps in 4 s, 1 of them within
    45° of forward), which v1's net-rotation term does not see.  v2 weights
    a fall as rex_walk does (10) and penalizes the mean angle between the
    heading and the start heading over the whole episode (``facing``), the
    footnote's "more conventional forward-facing walking"; success as v1."""
    version = 2
    params = {**BobWalk.params, "w_fall": 10.0, "w_facing": 1.0}
    param_docs = {**BobWalk.param_docs,
                  "w_facing": "penalty per rad of mean |heading − start heading|"}
    terms = (*BobWalk.terms,
             Term("facing", 1.0, param="w_facing", doc="mean |heading − start heading| (rad)"))
    facts = ("steps", "forward", "sideways", "facing", "fallen")


@register_task
class BobWalkV3(BobWalkV2):
    """v3: a step is the feet taking turns, and steps are rewarded.  v1/v2
    count every touchdown of a foot ≥ 5 cm ahead of the other, so a leading
    foot that bounces or chatters in place, or stamps again and again while
    the other foot drags behind, counts many times (``touchdowns``, still
    reported).  v3 counts a touchdown only when the previous counted step
    was the other foot's (``count_steps(..., alternate=True)``): each step
    passes the other foot by ≥ 5 cm.  And where v1/v2 reward only distance
    and foot motion, which a search met with shuffles and lunges that count
    0-3 steps, v3 adds ``w_steps`` per counted step to the reward, the
    success criterion itself; the fall and facing penalties are v2's.
    Success: ≥ 5 such steps before falling, facing within 45°."""
    version = 3
    params = {**BobWalkV2.params, "w_steps": 0.2}
    param_docs = {**BobWalkV2.param_docs,
                  "success_steps": "alternating forward steps before falling that count as solved",
                  "w_steps": "reward per alternating forward step"}
    terms = (*BobWalkV2.terms,
             Term("steps", -1.0, param="w_steps",
                  doc="alternating forward steps (each foot lands ≥ 5 cm ahead of the other, "
                      "the feet taking turns) before falling, facing within 45°"))
    success_threshold = "≥ 5 alternating forward steps before falling, facing forward"
    facts = ("steps", "touchdowns", "forward", "sideways", "facing", "fallen")

    alternate_steps = True          # steps: the feet taking turns; touchdowns: v2's count

    def describe(self, traj, m, e=0):
        facts = {**FACTS, "touchdowns": lambda m, e: f"{int(m['touchdowns'][e])} touchdowns ahead"}
        return [", ".join(facts[f](m, e) for f in self.facts)]

