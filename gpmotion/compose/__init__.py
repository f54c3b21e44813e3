"""Composite motions (Auslander et al. 1995, §3).

* :mod:`.script` — the composite-motion script language (Table 4): ``parse``, ``evaluate``
* :mod:`.composite` — saved controllers in series, state carried across switches; the file
* :mod:`.transitions` — the transition search (Fig. 5) as an ask/tell object
* :mod:`.optimize` — score switch times with a script; run the search on a composite
* :mod:`gpmotion.robust` — evaluation from perturbed starts ("enhanced" controllers; the
  evaluation layer, re-exported here)
"""
from .composite import Composite, CompositeError, from_controllers
from .composite import load as load_composite
from .composite import run as run_composite
from .composite import save as save_composite
from .optimize import score as score_switches
from .optimize import search as search_transitions
from ..robust import Perturbation, perturbed_starts
from .script import Script, ScriptError
from .script import load as load_script
from .script import parse as parse_script
from .transitions import TransitionSearch

__all__ = ["Composite", "CompositeError", "Perturbation", "Script", "ScriptError", "TransitionSearch",
           "from_controllers", "load_composite", "load_script", "parse_script", "perturbed_starts",
           "run_composite", "save_composite", "score_switches", "search_transitions"]
