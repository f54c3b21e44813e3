"""Name the gait of a planar travelling figure (Star-Man, Beryl), by definitions.

Auslander et al. name the motions their searches found — shuffle (Fig. 9),
cartwheel (Fig. 10), hopping, tumbling (Fig. 11), periodic shuffling
(Fig. 12) — without defining them.  To count them we define them here,
from recorded frames only (contact forces, root pitch, centre of mass,
joint angles), so any trajectory can be classified the same way.  Two
definitions are kept: ``strict`` (the default of :func:`judge`), which checks
what a person watching would check, and ``loose`` (:func:`classify`, the
earlier counting rules), so old labels can be compared with new ones.  Each
judge returns the label and the measures behind it (a dict of plain numbers):
:func:`relabel` names a label again from kept measures, without a replay.

Shared measures:

* a contact point is *down* in a frame when it touched the ground at any
  step of that frame's interval (the recorded force is the interval's max);
* a *flight phase* is a run of ≥ ``MIN_FLIGHT`` s (40 ms) with no point down
  after the first touchdown (the drop onto the ground at the start is none);
* fractions of frames (a foot down, airborne) count from the first touchdown;
* *turns* is the net body rotation in the travel direction, in whole turns:
  −Δ(unwrapped root pitch) / 2π, signed by the direction the centre of mass
  travelled (rolling right is clockwise); |turns| counts either direction.

Strict definitions (:func:`strict_measures`, :func:`classify_strict`).  The
root body is the torso (Star-Man's head rod, Beryl's torso), pointing up when
standing; a frame is *upright* when the torso is within ``UPRIGHT_TILT``
(45°) of vertical and the centre of mass is at least ``UPRIGHT_HEIGHT`` (0.6)
of its standing height (frame 0, the standing start pose).  *Support shares*
split the summed normal force over the episode between the feet (``foot*``),
the hands (``hand*``) and every other point (head, hub, hip, knees).  A
flight *lands on the feet* when the frame it ends has a foot down, no other
point but feet down, and the torso upright (tilt within 45°).  Checked in
this order:

``cartwheel``  ≥ 1 full rotation in the travel direction, hands and feet
               alternating (≥ 2 hand/foot support switches per whole turn),
               hands and feet carrying ≥ 90 % of the support (not rolled
               over the head or back) and airborne in ≤ 30 % of the frames
               (a wheel turns on the ground, it is no somersault).
``tumble``     ≥ 1 full rotation (either direction) that is not a cartwheel.
``hop``        less than a quarter turn net, ≥ 2 flight phases, ≥ 2 of them
               and ≥ 2/3 of all landing on the feet, upright ≥ 60 % of frames.
``periodic shuffle``  a shuffle whose motion repeats (the period below).
``shuffle``    less than a quarter turn net, no flight phase, the feet
               carrying ≥ 90 % of the support, and upright ≥ 80 % of frames.
``other``      anything else (a crawl on the hands or knees, a fall, a single
               jump, lying pitched over, travel under ``MIN_TRAVEL`` = 0.1 m).

Loose definitions (:func:`features`, :func:`classify`), the first that holds:

``cartwheel``  ≥ 1 full rotation in the travel direction with hands and feet
               alternating on the ground: over the frames where only hands or
               only feet are down, support switches between them at least
               twice per whole turn (feet → hands → feet).
``tumble``     ≥ 1 full rotation (either direction) that is not a cartwheel:
               the body rolls over head, back or torso.
``hop``        less than a full rotation and ≥ 2 flight phases.
``periodic shuffle``  a shuffle whose motion repeats: see below.
``shuffle``    less than a full rotation, contact never lost (no flight
               phase) and a foot down in ≥ 90 % of frames.  Posture and
               which limbs carry the weight are not checked.
``other``      anything else (a single jump, a crawl on hands or back, a
               fall, or travel under ``MIN_TRAVEL`` = 0.1 m).

*Periodic* (both): some lag L in [0.1 s, T/3] makes the second half of the
episode repeat itself: the root-mean-square difference between the state
at t and at t + L is ≤ 0.15 rad in every joint angle and in the unwrapped
root pitch (so net rotation is never periodic) and ≤ 0.03 m in centre-of-mass
height, and the set of points down agrees in ≥ 80 % of the frame pairs;
and it is a motion, not a still pose: some joint angle sweeps ≥ 0.2 rad in
the second half.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MIN_FLIGHT = 0.04           # s without any contact: a flight phase
MIN_TRAVEL = 0.1            # m: less is no gait at all
FEET_DOWN = 0.9             # shuffle: a foot down in this fraction of frames
PERIOD_RANGE = (0.1, 1.0 / 3.0)   # lag: seconds (lower), fraction of T (upper)
PERIOD_ANGLE_RMS = 0.15     # rad
PERIOD_HEIGHT_RMS = 0.03    # m
PERIOD_CONTACT_AGREE = 0.8
PERIOD_MIN_SWEEP = 0.2      # rad: a still pose repeats at every lag
# strict definitions (module doc)
UPRIGHT_TILT = np.radians(45.0)   # torso within this of vertical ...
UPRIGHT_HEIGHT = 0.6              # ... and com ≥ this × standing height: upright
SUPPORT_SHARE = 0.9               # shuffle: feet; cartwheel: hands and feet
SHUFFLE_UPRIGHT = 0.8             # shuffle: upright in this fraction of frames
HOP_UPRIGHT = 0.6                 # hop: upright in this fraction of frames
HOP_LANDED = 2.0 / 3.0            # hop: this fraction of landings on the feet
CARTWHEEL_AIRBORNE = 0.3          # cartwheel: airborne in at most this fraction
NO_TURN = 0.25                    # shuffle, hop: |net turns| under this
DEFINITIONS = ("strict", "loose")

GAITS = ("cartwheel", "tumble", "hop", "periodic shuffle", "shuffle", "other")


@dataclass(frozen=True)
class GaitFeatures:
    distance: float          # m the centre of mass travelled (signed, +x)
    turns: float             # net rotations in the travel direction
    flights: int             # flight phases of ≥ MIN_FLIGHT
    airborne: float          # fraction of frames (after touchdown) with no point down
    feet_down: float         # fraction of frames with a foot down
    switches: int            # hands-only ↔ feet-only support changes
    period: float | None     # s, the shortest repeat lag, or None

    def lines(self) -> list[str]:
        per = "none" if self.period is None else f"{self.period:.2f} s"
        return [f"distance {self.distance:.2f} m", f"turns {self.turns:+.2f}",
                f"flight phases {self.flights} (airborne {100 * self.airborne:.0f}% of frames)",
                f"a foot down {100 * self.feet_down:.0f}% of frames",
                f"hand/foot support switches {self.switches}", f"period {per}"]


def _runs(mask: np.ndarray) -> list[int]:
    """Lengths of the runs of True in a 1-D bool array."""
    m = np.concatenate([[False], np.asarray(mask, bool), [False]]).astype(np.int8)
    d = np.diff(m)
    return list(np.flatnonzero(d == -1) - np.flatnonzero(d == 1))


def _switches(hands: np.ndarray, feet: np.ndarray) -> int:
    """Changes of support between hands-only and feet-only frames."""
    labels = np.where(hands & ~feet, 1, np.where(feet & ~hands, 2, 0))
    seq = labels[labels > 0]
    return int(np.count_nonzero(np.diff(seq))) if seq.size else 0


def _period(frame_dt, angles, pitch, height, down) -> float | None:
    """Shortest lag at which the second half of the episode repeats itself."""
    n = angles.shape[0]
    if np.ptp(angles[n // 2:], axis=0).max() < PERIOD_MIN_SWEEP:
        return None
    state = np.column_stack([angles, pitch])
    lo = max(1, int(np.ceil(PERIOD_RANGE[0] / frame_dt - 1e-9)))
    hi = int(n * PERIOD_RANGE[1])
    start = n // 2
    for lag in range(lo, hi + 1):
        a, b = slice(start - lag, n - lag), slice(start, n)
        if b.stop - b.start < 2:
            break
        d_ang = np.sqrt(np.mean((state[a] - state[b]) ** 2, axis=0)).max()
        d_h = np.sqrt(np.mean((height[a] - height[b]) ** 2))
        agree = np.mean(np.all(down[a] == down[b], axis=1))
        if d_ang <= PERIOD_ANGLE_RMS and d_h <= PERIOD_HEIGHT_RMS \
                and agree >= PERIOD_CONTACT_AGREE:
            return lag * frame_dt
    return None


def features(times, contact_force, contact_names, pitch, com_x, com_z,
             angles) -> GaitFeatures:
    """Gait features of one episode from its recorded frames.

    ``contact_force`` [F, nc] (names: ``hand*`` and ``foot*`` points are
    hands and feet), ``pitch`` [F] root angle (rad), ``com_x``/``com_z`` [F],
    ``angles`` [F, n_joints].
    """
    times = np.asarray(times, float)
    force = np.asarray(contact_force, float)
    if force.ndim != 2 or force.shape != (times.size, len(contact_names)) or times.size < 3:
        raise ValueError(f"gait features: contact_force must be [F, {len(contact_names)}] "
                         f"with F = {times.size} ≥ 3 frames, got {force.shape}")
    frame_dt = float(np.median(np.diff(times)))
    down = force > 0.0
    names = list(contact_names)
    hands = down[:, [i for i, n in enumerate(names) if n.startswith("hand")]].any(axis=1)
    feet = down[:, [i for i, n in enumerate(names) if n.startswith("foot")]].any(axis=1)
    airborne = ~down.any(axis=1)
    min_run = max(1, int(round(MIN_FLIGHT / frame_dt)))
    landed = np.maximum.accumulate(~airborne)          # after the first touchdown
    if not landed.any():                               # never touched: all of it counts
        landed[:] = True
    flights = sum(1 for r in _runs(airborne & landed) if r >= min_run)
    distance = float(com_x[-1] - com_x[0])
    pitch = np.unwrap(np.asarray(pitch, float))
    direction = 1.0 if distance >= 0 else -1.0
    turns = float(-(pitch[-1] - pitch[0]) / (2 * np.pi) * direction)
    period = _period(frame_dt, np.asarray(angles, float).reshape(times.size, -1), pitch,
                     np.asarray(com_z, float), down)
    return GaitFeatures(distance, turns, flights, float(airborne[landed].mean()),
                        float(feet[landed].mean()),
                        _switches(hands, feet), period)


def classify(f: GaitFeatures) -> str:
    """The gait named by the module's definitions (first match in GAITS order)."""
    whole = np.floor(abs(f.turns) + 1e-9)
    if abs(f.distance) < MIN_TRAVEL:
        return "other"
    if f.turns >= 1.0 and f.switches >= 2 * whole:
        return "cartwheel"
    if whole >= 1:
        return "tumble"
    if f.flights >= 2:
        return "hop"
    if f.flights == 0 and f.feet_down >= FEET_DOWN:
        return "periodic shuffle" if f.period is not None else "shuffle"
    return "other"


def _run_bounds(mask: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) of each run of True in a 1-D bool array."""
    m = np.concatenate([[False], np.asarray(mask, bool), [False]]).astype(np.int8)
    d = np.diff(m)
    return list(zip(np.flatnonzero(d == 1).tolist(), np.flatnonzero(d == -1).tolist()))


def strict_measures(times, contact_force, contact_names, pitch, com_x, com_z, angles) -> dict:
    """The measures the strict definitions judge by (module doc), as plain
    numbers: the loose features plus posture (``upright``: fraction of frames
    upright; ``min_height``: lowest com / standing; ``max_tilt_deg``), support
    shares (``feet_share``, ``hands_share``, ``other_share``; ``hands_down``:
    fraction of frames with a hand down) and landings (``landings``,
    ``landed_on_feet``)."""
    f = features(times, contact_force, contact_names, pitch, com_x, com_z, angles)
    force = np.asarray(contact_force, float)
    names = list(contact_names)
    frame_dt = float(np.median(np.diff(np.asarray(times, float))))
    down = force > 0.0
    is_foot = np.array([n.startswith("foot") for n in names])
    is_hand = np.array([n.startswith("hand") for n in names])
    airborne = ~down.any(axis=1)
    landed = np.maximum.accumulate(~airborne)
    if not landed.any():
        landed[:] = True
    com_z = np.asarray(com_z, float)
    standing = float(com_z[0])
    tilt = np.abs(np.angle(np.exp(1j * (np.asarray(pitch, float) - np.pi / 2))))
    upright = (tilt <= UPRIGHT_TILT) & (com_z >= UPRIGHT_HEIGHT * standing)
    total = force[landed].sum()
    share = (lambda sel: float(force[landed][:, sel].sum() / total)) if total > 0 else (lambda sel: 0.0)
    min_run = max(1, int(round(MIN_FLIGHT / frame_dt)))
    landings = on_feet = 0
    for start, stop in _run_bounds(airborne & landed):
        if stop - start < min_run or stop >= len(times):
            continue                                   # too short, or still flying at the end
        landings += 1
        pts = down[stop]
        on_feet += bool(pts[is_foot].any() and not pts[~is_foot].any() and tilt[stop] <= UPRIGHT_TILT)
    hands = down[:, is_hand].any(axis=1) if is_hand.any() else np.zeros(len(times), bool)
    return {**{k: v for k, v in f.__dict__.items()},
            "standing_height": standing, "upright": float(upright[landed].mean()),
            "min_height": float(com_z[landed].min() / standing) if standing > 0 else 0.0,
            "max_tilt_deg": float(np.degrees(tilt[landed].max())),
            "feet_share": share(is_foot), "hands_share": share(is_hand),
            "other_share": share(~is_foot & ~is_hand), "hands_down": float(hands[landed].mean()),
            "landings": landings, "landed_on_feet": on_feet}


def classify_strict(m: dict) -> str:
    """The gait the strict definitions name, from :func:`strict_measures`' dict."""
    whole = np.floor(abs(m["turns"]) + 1e-9)
    if abs(m["distance"]) < MIN_TRAVEL:
        return "other"
    if (m["turns"] >= 1.0 and m["switches"] >= 2 * whole
            and m["feet_share"] + m["hands_share"] >= SUPPORT_SHARE
            and m["airborne"] <= CARTWHEEL_AIRBORNE):
        return "cartwheel"
    if whole >= 1:
        return "tumble"
    if abs(m["turns"]) >= NO_TURN:
        return "other"
    if (m["flights"] >= 2 and m["landed_on_feet"] >= 2
            and m["landed_on_feet"] >= HOP_LANDED * m["landings"] and m["upright"] >= HOP_UPRIGHT):
        return "hop"
    if m["flights"] == 0 and m["feet_share"] >= SUPPORT_SHARE and m["upright"] >= SHUFFLE_UPRIGHT:
        return "periodic shuffle" if m["period"] is not None else "shuffle"
    return "other"


def relabel(m: dict, definition: str = "strict") -> str:
    """A label named again from kept measures (a strict measures dict holds the
    loose features too, so either definition can judge it)."""
    if definition == "strict":
        return classify_strict(m)
    if definition == "loose":
        return classify(GaitFeatures(**{k: m[k] for k in GaitFeatures.__dataclass_fields__}))
    raise ValueError(f"gait definition must be one of {', '.join(DEFINITIONS)}, got {definition!r}")


def _frames(traj, e: int):
    fig = traj.figure
    return (traj.times, traj.contact_force[e], fig.contact_names, traj.base()[e, :, 0],
            traj.com[e, :, 0], traj.com[e, :, 1], traj.q[e][:, fig.model.act_dof])


def trajectory_features(traj, e: int = 0) -> GaitFeatures:
    """Loose features of episode ``e`` of a planar Trajectory."""
    return features(*_frames(traj, e))


def judge(traj, e: int = 0, definition: str = "strict") -> tuple[str, dict]:
    """(gait name, measures) of episode ``e`` under ``definition`` ("strict" or
    "loose"); the measures are the strict ones either way (they hold the loose
    features), so :func:`relabel` can name it under the other definition."""
    if definition not in DEFINITIONS:
        raise ValueError(f"gait definition must be one of {', '.join(DEFINITIONS)}, got {definition!r}")
    m = strict_measures(*_frames(traj, e))
    return relabel(m, definition), m


def gait_of(traj, e: int = 0) -> tuple[str, GaitFeatures]:
    """(gait name, features) of episode ``e`` under the loose definitions."""
    f = trajectory_features(traj, e)
    return classify(f), f
