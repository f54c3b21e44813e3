"""Sessions 20-21 scratch harness for the reach_standing trials in
docs/notes/herman.md (not a benchmark: trial task versions as subclasses,
run through benchmarks/herman_success.py).

* ``sc/reach``: herman_reach_standing-v3 with SelfContact (session 20's
  trials add ``--targets angle --search polish=20 --param w_rest=3``).
* ``sct/reach``: the same with the object travelling from XSTART (pelvis
  frame) to its place over run progress XEASE; with XEASE=0,0.7 and the
  three flags above it is the registered herman_reach_standing-v4.
* ``v4x/reach``: v4 with the ``through`` term XTHROUGH times as heavy.

    XEASE=0,0.7 python docs/notes/herman_s21_trials.py --seeds 5 --only sct/reach --targets angle --search polish=20 --param w_rest=3 --out F
    python docs/notes/herman_s21_trials.py --seeds 5 --only v4x/reach --out F
"""
import os, sys
sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parents[2] / "benchmarks"))
import numpy as np
import herman_success as hs
from gpmotion.task import Ease, register_task
from gpmotion.tasks._herman import SelfContact
from gpmotion.tasks.herman_reach_standing import HermanReachStandingV3

START = tuple(float(v) for v in os.environ.get("XSTART", "0.45,-0.15,0.05").split(","))
EASE = tuple(float(v) for v in os.environ.get("XEASE", "0,0.5").split(","))

class SC(SelfContact, HermanReachStandingV3):
    pass
SC.name = "sc_reach"; SC.version = 1; SC.__name__ = "sc_reach"
register_task(SC)

class TR(SC):
    params = {**SC.params, "travel": 1.0}
    bounds = {**SC.bounds, "travel": (0, 1)}
    @property
    def curriculum(self):
        return {"travel": Ease(0.0, EASE, doc="object moves from START")}
    def object_position(self):
        end = super().object_position()
        m = self.figure.model
        start = m.fixed_pos + m.fixed_rot @ np.array(START, float)
        return start + self.params["travel"] * (end - start)
    # (measured against traj.scene.goal3, the episode's own object: HermanTouchObject.measure)
TR.name = "sct_reach"; TR.version = 1; TR.__name__ = "sct_reach"
register_task(TR)
from dataclasses import replace
from gpmotion.tasks.herman_reach_standing import HermanReachStandingV4
XT = float(os.environ.get("XTHROUGH", "3"))
class TH(HermanReachStandingV4):
    terms = tuple(replace(t, weight=t.weight * XT) if t.name == "through" else t
                  for t in HermanReachStandingV4.terms)
TH.name = "v4x_reach"; TH.version = 1; TH.__name__ = "v4x_reach"
register_task(TH)
hs.EXTRA.update({"v4x/reach": ("v4x_reach", {})})
hs.EXTRA.update({"sc/reach": ("sc_reach", {}), "sct/reach": ("sct_reach", {})})
sys.exit(hs.main())
