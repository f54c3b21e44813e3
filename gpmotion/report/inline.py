"""The report's player inline in Jupyter (``_repr_html_``): an iframe holding
the same self-contained page ``gpmotion report`` writes (srcdoc: nothing
fetched, nothing written).  This module needs only the frames and the page
(not the runs or the harness): the simulator's Trajectory shows itself with it."""
from __future__ import annotations

import html

from .encode import encode_motion
from .page import page

HEIGHT = 560     # pixels: the player and its controls; the page scrolls inside


def iframe(doc: str, height: int = HEIGHT) -> str:
    return (f'<iframe style="width:100%;height:{height}px;border:0" '
            f'srcdoc="{html.escape(doc, quote=True)}"></iframe>')


def player_html(traj, task=None, title: str = "motion", e: int = 0) -> str:
    """Episode ``e`` of a Trajectory in the report's player."""
    n = traj.n_episodes
    name = title if n == 1 else f"{title}: episode {e + 1} of {n}"
    panel = {"name": name, "motion": encode_motion(traj, e, task=task)}
    return iframe(page({"kind": "motion", "panels": [panel]}, title))
