"""Sessions 20-21 scratch harness for the reach_standing trials in
docs/notes/herman.md (not a benchmark: trial task versions as subclasses,
run through benchmarks/herman_success.py).

* ``sc/reach``: herman_reach_standing-v3 with SelfContact (session 20's
  trials add ``--targets angle --search polish=20 --param w_rest=3``).
* ``sct/reach``: herman_reach_standing-v4 with the object's travel over run
  progress XEASE (v4: 0,0.7) and the through term at v3's weight
  (``w_through`` 1): the session 21 curriculum trials, which ran the same
  search as a subclass of v3 with the three flags above.
* the v4x/reach row (through x3) is the registered v4 itself:
  ``python benchmarks/herman_success.py --seeds 5 --only reach_standing``.

    XEASE=0,0.5 python docs/notes/herman_s21_trials.py --seeds 5 --only sct/reach --out F
"""
import os
import sys
sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parents[2] / "benchmarks"))
import herman_success as hs
from gpmotion.task import Ease, register_task
from gpmotion.tasks._herman import SelfContact
from gpmotion.tasks.herman_reach_standing import HermanReachStandingV3, HermanReachStandingV4

EASE = tuple(float(v) for v in os.environ.get("XEASE", "0,0.7").split(","))


class SC(SelfContact, HermanReachStandingV3):
    pass


class TR(HermanReachStandingV4):
    params = {**HermanReachStandingV4.params, "w_through": 1.0}

    @property
    def curriculum(self):
        return {"travel": Ease(float(self.params["travel_start"]), EASE, doc="XEASE")}


for cls, name in ((SC, "sc_reach"), (TR, "sct_reach")):
    cls.name, cls.version, cls.__name__ = name, 1, name
    register_task(cls)
hs.EXTRA.update({"sc/reach": ("sc_reach", {}), "sct/reach": ("sct_reach", {})})
sys.exit(hs.main())
