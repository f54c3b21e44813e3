"""Measures and functions of the composite-motion script, over a Trajectory.

Every value is an array ``[E, F, n]``: a *number* per episode is ``[E, 1, 1]``,
a *signal* ``[E, F, 1]`` (one value per recorded frame), *points*
``[E, F, n_points]`` (one per contact point per frame).  A :class:`Window`
holds each episode's first and last frame (inclusive) of the phase being
scored; signals are computed over the whole trajectory once (``Context``) and
reductions over time look only inside the window.

Heights are z (the paper's y: it names 2-D height y, so ``y_i`` is offered).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..bsr import secondary

NUMBER, SIGNAL, POINTS = 0, 1, 2
KIND_NAMES = {NUMBER: "number", SIGNAL: "signal", POINTS: "points"}


@dataclass
class Window:
    """Frames [start[e], end[e]] (inclusive) of each episode, and the scene they ran in."""
    start: np.ndarray          # int64[E]
    end: np.ndarray            # int64[E]
    n_frames: int
    scene: object = None       # the phase's Scene (its goal); None: the trajectory's

    @property
    def mask(self) -> np.ndarray:
        f = np.arange(self.n_frames)[None, :]
        return (f >= self.start[:, None]) & (f <= self.end[:, None])      # [E, F]

    @staticmethod
    def whole(n_episodes: int, n_frames: int) -> "Window":
        return Window(np.zeros(n_episodes, np.int64), np.full(n_episodes, n_frames - 1, np.int64), n_frames)


class Context:
    """A trajectory's per-frame channels, computed once for every window."""

    def __init__(self, traj):
        self.traj = traj
        self.E, self.F = traj.q.shape[:2]
        self._cache: dict = {}

    def memo(self, key, compute):
        if key not in self._cache:
            self._cache[key] = compute()
        return self._cache[key]

    def points(self) -> np.ndarray:
        """Contact-point world positions [E, F, nc, 2 or 3] (last axis: height)."""
        def compute():
            fig, t = self.traj.figure, self.traj
            m = fig.model
            if t.is3d:
                from ..sim import geometry3d
                return geometry3d.points_fast(m, t.q, m.cp_link, m.cp_pos)
            from ..sim import geometry
            return geometry.points_world(m, t.poses(), m.cp_link, m.cp_pos)
        return self.memo("points", compute)

    def signal(self, x) -> np.ndarray:
        return np.broadcast_to(np.asarray(x, np.float64)[..., None], (self.E, self.F, 1))

    def number(self, x) -> np.ndarray:
        return np.broadcast_to(np.asarray(x, np.float64).reshape(-1, 1, 1), (self.E, 1, 1))


# ------------------------------------------------------------------ reductions

def take(x, frames):
    """x[e, frames[e], :] as a number/points-per-episode [E, 1, n]."""
    x = np.broadcast_to(x, (len(frames),) + x.shape[1:])
    return np.take_along_axis(x, frames[:, None, None], axis=1)


def _masked(x, win: Window, fill):
    x = np.broadcast_to(x, (len(win.start), win.n_frames, x.shape[2]))
    return np.where(win.mask[:, :, None], x, fill)


def max_t(x, win):
    return _masked(x, win, -np.inf).max(axis=1, keepdims=True)


def min_t(x, win):
    return _masked(x, win, np.inf).min(axis=1, keepdims=True)


def sum_t(x, win):
    return _masked(x, win, 0.0).sum(axis=1, keepdims=True)


def mean_t(x, win):
    return sum_t(x, win) / (win.end - win.start + 1)[:, None, None]


def close(a, b):
    """The paper's ≟: 1 when a = b, falling linearly to 0 with the relative difference."""
    scale = np.maximum(np.abs(a), np.abs(b))
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(scale > 0, np.abs(a - b) / np.where(scale > 0, scale, 1.0), 0.0)
    return np.clip(1.0 - rel, 0.0, 1.0)


def near(a, b, width):
    """1 when a = b, falling linearly to 0 at |a − b| = width (width > 0)."""
    w = np.where(width > 0, width, np.nan)
    return np.clip(1.0 - np.abs(a - b) / w, 0.0, 1.0)


# --------------------------------------------------------------------- measures

@dataclass(frozen=True)
class Measure:
    kind: int
    doc: str
    fn: Callable        # (ctx, window) -> array [E, F|1, n|1]


def _com_index(traj, axis: str) -> int:
    """Column of the com channel: planar (x, z, vx, vz), 3-D (x, y, z, vx, vy, vz)."""
    cols = ("x", "y", "z", "vx", "vy", "vz") if traj.is3d else ("x", "z", "vx", "vz")
    if axis not in cols:
        raise ValueError(f"cm_{axis} needs a 3-D figure")
    return cols.index(axis)


def _com_axis(axis):
    return lambda c, w: c.signal(c.traj.com[..., _com_index(c.traj, axis)])


def _dcm(axis):
    return lambda c, w: take(_com_axis(axis)(c, w), w.end) - take(_com_axis(axis)(c, w), w.start)


def _pitch(c, w):
    if c.traj.is3d:
        raise ValueError("pitch and rotations are defined for planar figures")
    return c.memo("pitch", lambda: c.signal(np.unwrap(c.traj.base()[..., 0], axis=-1)))


def _rotations(c, w):
    p = _pitch(c, w)
    return np.abs(take(p, w.end) - take(p, w.start)) / (2 * np.pi)


def _touching(c):
    return c.traj.contact_force > 0                                  # [E, F, nc]


def _contact_distance(c, w):
    """Table 3 contact_distance (the BSR secondary term) inside the window: a point
    counts as touching only in the window's frames, so frame pairs leaving it add nothing."""
    force = np.where(w.mask[..., None], c.traj.contact_force, 0.0)
    return c.number(secondary.contact_distance(force, c.points()[..., 0]))


def _speed(c, w):
    v = c.traj.com[..., 3:] if c.traj.is3d else c.traj.com[..., 2:4]
    return c.signal(np.linalg.norm(v, axis=-1))


# the centre of mass per axis: its change over a window (a number) and its value per frame
_COM_CHANGES = {"x": "centre-of-mass x displacement over the window (m) — Δcm_x",
                "y": "centre-of-mass y displacement (m; 3-D figures)",
                "z": "centre-of-mass height change over the window (m)"}
_COM_CHANNELS = {"x": "centre-of-mass x (m)", "y": "centre-of-mass y (m; 3-D figures)",
                 "z": "centre-of-mass height (m)", "vx": "centre-of-mass x velocity (m/s)",
                 "vz": "centre-of-mass vertical velocity (m/s)"}

MEASURES: dict[str, Measure] = {
    # numbers per window
    "dtime": Measure(NUMBER, "duration of the window (s) — the paper's Δtime",
                     lambda c, w: c.number((w.end - w.start) * c.traj.dt * c.traj.record_every)),
    **{f"dcm_{a}": Measure(NUMBER, doc, _dcm(a)) for a, doc in _COM_CHANGES.items()},
    "rotations": Measure(NUMBER, "whole-body turns of the base pitch, fractional (planar; Table 3)", _rotations),
    "contact_distance": Measure(NUMBER, "m slid by contact points touching the ground (Table 3)", _contact_distance),
    "max_height": Measure(NUMBER, "highest centre-of-mass height in the window (m; Table 3)",
                          lambda c, w: max_t(_com_axis("z")(c, w), w)),
    "diverged": Measure(NUMBER, "1 if the simulation diverged (whole episode)",
                        lambda c, w: c.number(c.traj.diverged.astype(float))),
    "goal_x": Measure(NUMBER, "the phase's scene goal x (m)", lambda c, w: c.number(np.full(c.E, _scene(c, w).goal[0]))),
    "goal_z": Measure(NUMBER, "the phase's scene goal height (m)",
                      lambda c, w: c.number(np.full(c.E, _scene(c, w).goal[1]))),
    # signals (one value per frame)
    "t": Measure(SIGNAL, "time since the window began (s)",
                 lambda c, w: c.signal(c.traj.times[None, :] - c.traj.times[w.start][:, None])),
    "time": Measure(SIGNAL, "time since the motion began (s)", lambda c, w: c.signal(c.traj.times[None, :])),
    **{f"cm_{a}": Measure(SIGNAL, doc, _com_axis(a)) for a, doc in _COM_CHANNELS.items()},
    "speed": Measure(SIGNAL, "centre-of-mass speed (m/s)", _speed),
    "pitch": Measure(SIGNAL, "base pitch, unwrapped (rad; planar)", _pitch),
    "airborne": Measure(SIGNAL, "1 when no contact point touches the ground",
                        lambda c, w: c.signal(~_touching(c).any(axis=-1))),
    "contacts": Measure(SIGNAL, "number of contact points touching the ground",
                        lambda c, w: c.signal(_touching(c).sum(axis=-1))),
    "impact": Measure(SIGNAL, "peak total ground normal force since the previous frame (N)",
                      lambda c, w: c.signal(c.traj.impact)),
    "energy": Measure(SIGNAL, "actuator work since the previous frame (J); sum_t(energy) is the window's",
                      lambda c, w: c.signal(c.traj.energy)),
    "pole_hit": Measure(SIGNAL, "deepest penetration into a pole since the previous frame (m)",
                        lambda c, w: c.signal(c.traj.pole_hit)),
    "goal_distance": Measure(SIGNAL, "distance from the centre of mass to the phase's scene goal (m)",
                             lambda c, w: c.signal(_goal_distance(c.traj, None, _scene(c, w)))),
    # points (per frame, per contact point)
    "y_i": Measure(POINTS, "height of each contact point (m) — the paper's y_i(t)",
                   lambda c, w: c.points()[..., -1]),
    "height_i": Measure(POINTS, "height of each contact point (m)", lambda c, w: c.points()[..., -1]),
    "x_i": Measure(POINTS, "x of each contact point (m)", lambda c, w: c.points()[..., 0]),
    "force_i": Measure(POINTS, "ground normal force on each contact point (N)",
                       lambda c, w: np.asarray(c.traj.contact_force, np.float64)),
}


def _scene(c, w):
    """The window's scene (a composite phase's), else the trajectory's."""
    return c.traj.scene if w.scene is None else w.scene


def _goal_distance(traj, site: str | None, scene):
    """Distance [E, F] from the com (or a site) to the scene's goal, in the figure's space."""
    if site is None:
        p = traj.com[..., :3] if traj.is3d else traj.com[..., :2]
    else:
        p = traj.site(site)
    goal = scene.goal3 if traj.is3d else scene.goal
    return np.linalg.norm(p - goal, axis=-1)


def _site_axis(axis):
    def fn(c, w, name):
        i = {"x": 0, "z": -1}[axis]
        return c.signal(c.traj.site(name)[..., i])
    return fn


def _unary(f):
    return lambda c, w, x: f(x)


# ------------------------------------------------------------------- functions

@dataclass(frozen=True)
class Function:
    args: tuple          # per argument: "number"/"any" (expression), "signal", "points", "name" (quoted)
    result: str          # "number", "signal" or "same" (the widest argument kind)
    doc: str
    fn: Callable         # (ctx, window, *values) -> array
    names: str = "site"  # what a quoted name names: a "site" or a "contact" point of the figure


FUNCTIONS: dict[str, Function] = {
    "min_i": Function(("points",), "signal", "lowest value over the contact points", _unary(lambda x: x.min(axis=2, keepdims=True))),
    "max_i": Function(("points",), "signal", "highest value over the contact points", _unary(lambda x: x.max(axis=2, keepdims=True))),
    "sum_i": Function(("points",), "signal", "sum over the contact points", _unary(lambda x: x.sum(axis=2, keepdims=True))),
    "mean_i": Function(("points",), "signal", "mean over the contact points", _unary(lambda x: x.mean(axis=2, keepdims=True))),
    "max_t": Function(("signal",), "number", "maximum over the window's frames", lambda c, w, x: max_t(x, w)),
    "min_t": Function(("signal",), "number", "minimum over the window's frames", lambda c, w, x: min_t(x, w)),
    "mean_t": Function(("signal",), "number", "mean over the window's frames", lambda c, w, x: mean_t(x, w)),
    "sum_t": Function(("signal",), "number", "sum over the window's frames", lambda c, w, x: sum_t(x, w)),
    "first": Function(("signal",), "number", "value at the window's first frame", lambda c, w, x: take(x, w.start)),
    "last": Function(("signal",), "number", "value at the window's last frame", lambda c, w, x: take(x, w.end)),
    "delta": Function(("signal",), "number", "last − first", lambda c, w, x: take(x, w.end) - take(x, w.start)),
    "abs": Function(("any",), "same", "|x|", _unary(np.abs)),
    "sqrt": Function(("any",), "same", "√x (NaN below 0 scores as the worst)", _unary(lambda x: np.sqrt(np.where(x >= 0, x, np.nan)))),
    "exp": Function(("any",), "same", "e^x", _unary(lambda x: np.exp(np.minimum(x, 700.0)))),
    "min": Function(("any", "any"), "same", "the smaller of two values", lambda c, w, a, b: np.minimum(a, b)),
    "max": Function(("any", "any"), "same", "the larger of two values", lambda c, w, a, b: np.maximum(a, b)),
    "clip": Function(("any", "any", "any"), "same", "x limited to [lo, hi]",
                     lambda c, w, x, lo, hi: np.minimum(np.maximum(x, lo), hi)),
    "near": Function(("any", "any", "any"), "same", "1 at a = b, 0 from |a − b| ≥ width", lambda c, w, a, b, d: near(a, b, d)),
    "site_x": Function(("name",), "signal", 'x of a named site, e.g. site_x("base_centre") (m)', _site_axis("x")),
    "site_z": Function(("name",), "signal", "height of a named site (m)", _site_axis("z")),
    "goal_distance_of": Function(("name",), "signal", "distance from a named site to the phase's scene goal (m)",
                                 lambda c, w, name: c.signal(_goal_distance(c.traj, name, _scene(c, w)))),
    "force_of": Function(("name",), "signal", 'ground normal force on a named contact point, e.g. '
                         'force_of("head_tip") (N)', lambda c, w, name: c.signal(
                             np.asarray(c.traj.contact_force, np.float64)[..., c.traj.figure.contact_names.index(name)]),
                         names="contact"),
}
