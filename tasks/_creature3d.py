"""Shared pieces of the 3-D creature tasks (Auslander et al. §4): Cujo, Rex, Bob.

A creature task measures in the frame the episode starts in (heading of the
root body at frame 0), so a stage that starts from another stage's final
state (``after``) is scored along its own start heading.  Terms (raw values;
each task weights them):

* ``distance``      com displacement along the start heading (m)
* ``sideways``      |com displacement across it| at the end (m)
* ``fall``          fraction of the episode spent fallen (gpmotion.bsr.secondary3d)
* ``rotation``      |net rotation about the vertical| (rad)
* ``facing``        mean |heading − start heading| over the motion (rad)
* ``feet_forward``  mean forward displacement of the feet (m)
* ``turn``          |change of heading| (rad)
* ``steps``         forward steps before the first fall (bipeds)

``after``: a comma-separated list of saved controller files (best.json of
earlier stages); the episode starts from the final state of running them in
series from the standing start (gpmotion.compose carries the state across
each switch), as Rex learns to turn "given the final state of that walk".

``hold`` (s, default 0): the controller runs this much longer than
``seconds``; every term but ``fall`` is measured at ``seconds`` and ``fall``
over the whole episode, so a motion that is falling when ``seconds`` end
(a lunge that "walks" 1 m by toppling just after the last frame) fails.  A
stage hands over at the end of its motion (``motion_seconds`` = ``seconds``,
as a phase of a composite too): the next stage starts from a state the
stage's own controller kept upright for ``hold`` seconds more.  (Handed
over at the end of the hold instead, Rex's turn started from a walk about
to fall, and 10,000 evaluations of either BSR kind found no turn that
stayed up; from the walk's 3 s state both did.)

This module starts with ``_``: the plugin loader does not import it as a task.
"""
from __future__ import annotations

import numpy as np

from gpmotion.bsr import secondary3d as s3
from gpmotion.gp.settings import GPSettings
from gpmotion.task import Task, Term

# Bob and Rex are compared at the paper's resolution: 50 frames/s
RECORD_EVERY = 20

# the terms the creatures share; a weight named by a parameter is the user's to set
DISTANCE = Term("distance", -1.0, main=True, doc="com displacement along the start heading (m)")
SIDEWAYS = Term("sideways", 1.0, param="w_sideways", doc="|com displacement across the start heading| (m)")
FALL = Term("fall", 1.0, param="w_fall", doc="fraction of the episode fallen")

# how each fact of an episode reads in a report (``CreatureTask.facts`` picks them)
FACTS = {
    "forward": lambda m, e: f"forward {m['distance'][e]:.2f} m",
    "sideways": lambda m, e: f"sideways {m['sideways'][e]:.2f} m",
    "heading": lambda m, e: f"heading change {np.degrees(m['turn'][e]):.0f}°",
    "rotation": lambda m, e: f"rotation {np.degrees(m['rotation'][e]):.0f}°",
    "facing": lambda m, e: f"facing {np.degrees(m['facing'][e]):.0f}° away on average",
    "steps": lambda m, e: f"{int(m['steps'][e])} forward steps",
    "fallen": lambda m, e: f"fallen {100 * m['fall'][e]:.0f}% of the time",
}


def foot_tracks(traj, xy, foot_groups, yaw, cut=slice(None)):
    """A biped's feet over frames ``cut``: forward position in the start
    heading's frame [..., F, 2] and normal force [..., F, 2] (each foot's
    contact points summed), from the feet's sites ``xy`` [..., F, 2, 2] and
    ``yaw`` [..., F] over the same frames."""
    fig = traj.figure
    fwd = np.stack([s3.in_start_frame(xy[..., k, :], yaw[..., 0])[..., 0] for k in range(2)], -1)
    force = np.stack([traj.contact_force[..., cut, [fig.contact_names.index(n) for n in g]].sum(-1)
                      for g in foot_groups], -1)
    return fwd, force


def creature_measures(traj, feet, foot_sites=(), foot_groups=(), max_tilt=s3.MAX_TILT,
                      min_height=s3.MIN_HEIGHT, frames=None, alternate=False) -> dict[str, np.ndarray]:
    """Every term above for a batch.  ``feet``: the foot contact points' names
    (any other point on the ground means a fall); ``foot_sites``: a site per
    foot; ``foot_groups``: for a biped, the contact points of each foot;
    ``max_tilt`` (rad), ``min_height`` (fraction): the fall thresholds;
    ``frames``: measure all but ``fall`` and ``fell`` over the first
    ``frames`` frames only (``hold``; default all); ``alternate``: ``steps``
    counts only steps of the feet taking turns, and ``touchdowns`` every
    touchdown ahead (``steps`` without it; ``secondary3d.count_steps``)."""
    fig = traj.figure
    base = traj.base()
    quat = base[..., 3:7]
    yaw = s3.heading(quat)
    other = [k for k, n in enumerate(fig.contact_names) if n not in feet]
    fell = s3.fallen(s3.quat_up(quat)[..., 2], traj.com[..., 2], traj.contact_force[..., other],
                     max_tilt, min_height)
    out = {"fall": s3.fall_fraction(fell), "fell": fell[..., -1].astype(np.float64)}
    cut = slice(None, frames)
    yaw, fell = yaw[..., cut], fell[..., cut]
    d = s3.in_start_frame(traj.com[..., cut, :2], yaw[..., 0])
    out.update({"distance": d[..., -1, 0], "sideways": np.abs(d[..., -1, 1]),
                "rotation": s3.net_rotation(yaw), "turn": s3.net_rotation(yaw),
                "facing": s3.facing_away(yaw)})
    if foot_sites:
        xy = traj.sites()[..., cut, [fig.site_names.index(n) for n in foot_sites], :2]
        out["feet_forward"] = s3.feet_forward(xy, yaw[..., 0])
        if len(foot_groups) == 2:
            fwd, force = foot_tracks(traj, xy, foot_groups, yaw, cut)
            out["steps"] = s3.count_steps(force, fwd, fell, yaw).astype(np.float64)
            if alternate:
                out["touchdowns"] = out["steps"]
                out["steps"] = s3.count_steps(force, fwd, fell, yaw, alternate=True).astype(np.float64)
    return out


class CreatureTask(Task):
    """A 3-D creature task; ``after`` chains it onto earlier stages."""
    feet: tuple[str, ...] = ()
    foot_sites: tuple[str, ...] = ()
    foot_groups: tuple[tuple[str, ...], ...] = ()
    max_tilt = s3.MAX_TILT          # fallen: root tilted further (rad) ...
    min_height = s3.MIN_HEIGHT      # ... or com below this fraction of its start height
    facts: tuple[str, ...] = ()     # what describe() reports, in order (FACTS)
    alternate_steps = False         # steps: only the feet taking turns (creature_measures)
    record_every = RECORD_EVERY
    param_docs = {"seconds": "episode length (s)",
                  "w_sideways": "penalty per m of sideways com motion",
                  "w_fall": "penalty for falling (× fraction of the episode fallen)",
                  "after": "start from the end of these saved controllers (comma-separated files)",
                  "hold": "the controller runs this much longer (s); all but the fall term "
                          "are measured at `seconds`, the fall over the whole episode"}
    _start = None

    @property
    def seconds(self) -> float:
        """The episode: the motion's ``seconds`` and the ``hold`` after it."""
        return float(self.params["seconds"]) + float(self.params.get("hold", 0.0))

    @property
    def motion_seconds(self) -> float:
        """The motion, without the hold: where a stage hands over."""
        return float(self.params["seconds"])

    def validate(self):
        after = self.params.get("after", "")
        if not isinstance(after, str):
            raise ValueError(f"task {self.name}: after must be a comma-separated list of controller files")
        hold = self.params.get("hold", 0.0)
        if isinstance(hold, bool) or not isinstance(hold, (int, float)) or not 0 <= hold <= 60:
            raise ValueError(f"task {self.name}: hold must be a number of seconds in [0, 60], got {hold!r}")

    def initial_state(self):
        if not self.params.get("after"):
            return super().initial_state()
        q, qd, _ = self._stage_end()
        return q.copy(), qd.copy()

    def initial_contact(self):
        if not self.params.get("after"):
            return None
        return self._stage_end()[2].copy()

    def _stage_end(self):
        if self._start is None:
            self._start = stage_end([s.strip() for s in self.params["after"].split(",") if s.strip()])
        return self._start

    def measure(self, traj):
        frames = None
        if self.params.get("hold"):
            frames = int(round(self.motion_seconds / (self.dt * self.record_every))) + 1
        return creature_measures(traj, self.feet, self.foot_sites, self.foot_groups,
                                 self.max_tilt, self.min_height, frames, self.alternate_steps)

    def describe(self, traj, m, e=0):
        return [", ".join(FACTS[f](m, e) for f in self.facts)]

    def __init__(self, **overrides):
        super().__init__(**overrides)
        # GP reads the raw senses 3-D BSR is built from (world frame, unfiltered):
        # com height and vertical velocity, the root's velocity, angular velocity
        # and up axis, every contact force, the driven joints' angles, and time
        fig = self.figure
        body = ["com_z", "vx", "vy", "com_vz", "wx", "wy", "wz", "up_x", "up_y", "up_z", "t"]
        self.gp = GPSettings(terminals=tuple(
            body + [f"force_{c}" for c in fig.contact_names]
            + [f"angle_{fig.actuator_names[a]}" for a in self.controlled_actuators()]))


_RESOLVING: list[str] = []        # the stage files being resolved, outermost first


def stage_end(paths) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Final (q, qd, contact anchors) of saved controllers run in series
    (each for its own task's motion_seconds) from the first one's start
    state: the whole physical state a composite would carry on."""
    from gpmotion.compose import composite
    import os
    keys = [os.path.realpath(p) for p in paths]
    loop = [p for p, k in zip(paths, keys) if k in _RESOLVING]
    if loop:              # a stage that starts after itself: a cycle, never a RecursionError
        raise ValueError(f"after: {loop[0]} starts after itself (a cycle through "
                         f"{' -> '.join(_RESOLVING + [os.path.realpath(loop[0])])})")
    _RESOLVING.extend(keys)
    try:
        comp = composite.from_controllers(paths)
        traj, _ = composite.run(comp)          # the stages' own starts: checked the same way
    except (OSError, ValueError) as exc:
        msg = str(exc)
        raise ValueError(msg if msg.startswith("after: ") else f"after: {msg}") from None
    finally:
        del _RESOLVING[-len(keys):]
    if traj.diverged[0]:
        raise ValueError(f"after: the earlier stages {paths} diverge")
    return traj.q[0, -1].copy(), traj.qd[0, -1].copy(), traj.contact_end[0].copy()
