"""Session 17 scratch harness for the Herman trials in docs/notes/herman.md
(not a benchmark: trial task versions as subclasses, run through
benchmarks/herman_success.py).  XW: weight of the from-generation-0 forearm
charge; XEASE: the ease-in phase.  sc_* use self_contact_pairs' default k
(2e4 for the runs of this session before the default became 4e4).

    python docs/notes/herman_s17_trials.py --seeds 5 --only sc/obj1 --out F
    python docs/notes/herman_s17_trials.py --seeds 5 --only sc/obj1 --targets angle --search polish=20 --out F
"""
import sys
sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parents[2] / "benchmarks"))
import numpy as np
import herman_success as hs
from gpmotion.task import Term, register_task
from gpmotion.tasks._herman import limbs_overlap, limbs_through_torso, CROSSING, MAIN_WEIGHT
from gpmotion.tasks.herman_touch_object import HermanTouchObjectV3
from gpmotion.tasks.herman_reach_standing import HermanReachStandingV3
from gpmotion.tasks.herman_touch import HermanTouchV3
import os
W = float(os.environ.get("XW", "1.5"))

def early(base, name):
    class T(base):
        charge = False
        terms = base.terms + (Term("cross", W, doc="forearm crossing, on from gen 0"),)
        def measure(self, traj):
            m = super().measure(traj)
            m["cross"] = limbs_through_torso(limbs_overlap(traj), traj.figure, CROSSING)
            return m
    T.name = name; T.version = 1; T.__name__ = name
    return register_task(T)

early(HermanTouchObjectV3, "trial_obj")
early(HermanReachStandingV3, "trial_reach")
early(HermanTouchV3, "trial_touch")
from gpmotion.tasks._herman import SelfContact
def contact(base, name):
    class T(SelfContact, base):
        pass
    T.name = name; T.version = 1; T.__name__ = name
    return register_task(T)
contact(HermanTouchObjectV3, "sc_obj")
contact(HermanReachStandingV3, "sc_reach")
contact(HermanTouchV3, "sc_touch")
from gpmotion.task import Ease
from gpmotion.tasks.herman_touch_object import PRESETS
EASE = tuple(float(v) for v in os.environ.get("XEASE", "0,0.5").split(","))
def travel(base, name):
    class T(base):
        params = {**base.params, "travel": 1.0}
        bounds = {**base.bounds, "travel": (0, 1)}
        @property
        def curriculum(self):
            return {"travel": Ease(0.0, EASE, doc="object moves from preset 0")}
        def object_position(self):
            end = super().object_position()
            m = self.figure.model
            start = m.fixed_pos + m.fixed_rot @ np.array(PRESETS[0], float)
            return start + self.params["travel"] * (end - start)
        def measure(self, traj):
            self.object_position = lambda: traj.scene.goal3
            try:
                return super().measure(traj)
            finally:
                del self.object_position
    T.name = name; T.version = 1; T.__name__ = name
    return register_task(T)
SCObj = contact(HermanTouchObjectV3, "sc_obj_base")
travel(SCObj, "sct_obj")
hs.EXTRA.update({"sct/obj1": ("sct_obj", {"target": 1})})
hs.EXTRA.update({"sc/obj0": ("sc_obj", {"target": 0}), "sc/obj2": ("sc_obj", {"target": 2})})
hs.EXTRA.update({"sc/obj1": ("sc_obj", {"target": 1}), "sc/reach": ("sc_reach", {}),
                 "sc/nose": ("sc_touch", {"site": "nose"}), "sc/knee_l": ("sc_touch", {"site": "knee_l"}),
                 "sc/elbow_l": ("sc_touch", {"site": "elbow_l"})})
hs.EXTRA.update({"x/obj1": ("trial_obj", {"target": 1}), "x/reach": ("trial_reach", {}),
                 "x/nose": ("trial_touch", {"site": "nose"})})
sys.exit(hs.main())
