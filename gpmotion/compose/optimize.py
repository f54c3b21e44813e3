"""Score transition times with a script, and run the transition search on a composite."""
from __future__ import annotations

from typing import Callable

import numpy as np

from . import composite as C
from . import script as S
from .transitions import TransitionSearch


def check_match(comp: C.Composite, script: S.Script) -> None:
    """One phase of the script per controller, and the script's sites exist on the figure."""
    if script.n_phases != len(comp.parts):
        raise C.CompositeError(f"the script has {script.n_phases} phase(s) ({', '.join(script.phases)}) "
                               f"but the composite {len(comp.parts)} controller(s)")
    S.bind(script, comp.figure)


def score(comp: C.Composite, script: S.Script, switches, threads: int | None = None):
    """(totals [E], per-phase credits {name: [E]}, trajectory, bounds) for switch times [E, P − 1]."""
    traj, bounds = C.run(comp, switches, threads=threads)
    values = S.evaluate(script, traj, bounds, comp.scenes)
    return values["total"], values, traj, bounds


def search(comp: C.Composite, script: S.Script, *, Q: int = 16, G: int = 16, H: int = 4, seed: int = 0,
           guess=None, perturb: float | None = None, state: dict | None = None,
           on_round: Callable[[TransitionSearch], None] | None = None,
           threads: int | None = None) -> TransitionSearch:
    """Fig. 5 on a composite, from ``guess`` (default: the composite's own switch times).

    ``state``: a ``state_dict()`` to resume from; ``on_round`` is called after
    every completed round (log a row, write a checkpoint).
    """
    check_match(comp, script)
    ts = TransitionSearch(len(comp.parts) - 1, comp.seconds, comp.switches if guess is None else guess,
                          Q=Q, G=G, H=H, seed=seed, perturb=perturb, tick=comp.frame_seconds)
    if state is not None:
        ts.load_state_dict(state)
    while not ts.done:
        before = ts.round
        totals, *_ = score(comp, script, ts.ask(), threads=threads)
        ts.tell(totals)
        if on_round is not None and ts.round != before:
            on_round(ts)
    return ts


def repaired(comp: C.Composite, ts: TransitionSearch) -> C.Composite:
    """The composite with the search's best switch times."""
    return C.Composite(comp.parts, np.asarray(ts.best, dtype=np.float64).copy(), comp.seconds,
                       comp.scene, comp.scene_settings, comp.scenes, comp.phase_scene_settings)
