"""Name the gait of a planar travelling figure (Star-Man, Beryl), by definitions.

Auslander et al. name the motions their searches found — shuffle (Fig. 9),
cartwheel (Fig. 10), hopping, tumbling (Fig. 11), periodic shuffling
(Fig. 12) — without defining them.  To count them we define them here,
from recorded frames only (contact forces, root pitch, centre of mass,
joint angles), so any trajectory can be classified the same way:

* a contact point is *down* in a frame when it touched the ground at any
  step of that frame's interval (the recorded force is the interval's max);
* a *flight phase* is a run of ≥ ``MIN_FLIGHT`` s (40 ms) with no point down
  after the first touchdown (the drop onto the ground at the start is none);
* fractions of frames (a foot down, airborne) count from the first touchdown;
* *turns* is the net body rotation in the travel direction, in whole turns:
  −Δ(unwrapped root pitch) / 2π, signed by the direction the centre of mass
  travelled (rolling right is clockwise); |turns| counts either direction.

Classes, checked in this order (the first that holds wins):

``cartwheel``  ≥ 1 full rotation in the travel direction with hands and feet
               alternating on the ground: over the frames where only hands or
               only feet are down, support switches between them at least
               twice per whole turn (feet → hands → feet).
``tumble``     ≥ 1 full rotation (either direction) that is not a cartwheel:
               the body rolls over head, back or torso.
``hop``        less than a full rotation and ≥ 2 flight phases.
``periodic shuffle``  a shuffle whose motion repeats: see below.
``shuffle``    less than a full rotation, contact never lost (no flight
               phase) and a foot down in ≥ 90 % of frames (the feet carry
               the figure; they are never both lifted for long).  Posture
               is not checked: a figure that sinks low on its legs still
               shuffles (every Star-Man shuffle on the reproduction
               figures does, centre of mass 0.08-0.12 m at its lowest).
``other``      anything else (a single jump, a crawl on hands or back, a
               fall, or travel under ``MIN_TRAVEL`` = 0.1 m).

*Periodic*: some lag L in [0.1 s, T/3] makes the second half of the
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


def trajectory_features(traj, e: int = 0) -> GaitFeatures:
    """Features of episode ``e`` of a planar Trajectory."""
    fig = traj.figure
    angles = traj.q[e][:, fig.model.act_dof]          # actuated joint angles
    return features(traj.times, traj.contact_force[e], fig.contact_names,
                    traj.base()[e, :, 0], traj.com[e, :, 0], traj.com[e, :, 1], angles)


def gait_of(traj, e: int = 0) -> tuple[str, GaitFeatures]:
    """(gait name, features) of episode ``e``."""
    f = trajectory_features(traj, e)
    return classify(f), f
