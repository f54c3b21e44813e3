"""Name a 3-D creature's motion (Rex, Bob, Cujo) by what a viewer would check.

Auslander et al. §4 report walks (Rex, Bob), a turn (Rex) and bounding (Cujo)
without defining them.  The definitions here look at the recorded frames
only, in the frame the episode starts in (its start heading), with the
helpers of :mod:`gpmotion.bsr.secondary3d`:

* *upright*: the root's up axis within ``UPRIGHT_TILT`` (45°) of vertical
  and the centre of mass at least ``UPRIGHT_HEIGHT`` (0.6) of its start
  height; *fallen*: a frame not upright, or a point that is not a foot on
  the ground (a figure that fell stays fallen);
* *forward-facing*: the heading within ``FACING`` (30°) of the start
  heading on average over the motion and at the end;
* a *step*: a touchdown of one foot at least 5 cm ahead of the other while
  forward-facing and not fallen, counted only when the feet take turns
  (``secondary3d.count_steps(alternate=True)``);
* a *flight*: ≥ ``MIN_FLIGHT`` (40 ms) with no foot down after the first
  touchdown; it *lands on the feet* when the frame it ends has only feet
  down and the root upright;
* a quadruped's feet form a front and a rear *pair* (names that differ only
  in their last letter: ``foot_fl``/``foot_fr``, ``foot_hl``/``foot_hr``); a
  *footfall* is a foot's touchdown after ≥ ``MIN_FLIGHT`` off the ground,
  and it is *paired* when the other foot of its pair touches down within
  ``PAIR_SYNC`` (60 ms) of it (the pair lands together, as in a bound, not
  one after the other, as in a walk or gallop); each pair's *support* is its
  share of the normal force on the feet over the motion.

Labels, the first that holds:

``fallen``  fallen at any frame.
``bound``   a quadruped's ≥ 2 flights, ≥ 2 of them landing on the feet; ≥
            ``BOUND_PAIRED`` (60 %) of footfalls paired; each pair carrying
            ≥ ``BOUND_SUPPORT`` (20 %) of the weight (front and rear legs
            both work); ≥ ``BOUND_DISTANCE`` (0.6 m, Cujo's trunk) forward,
            forward-facing.
``walk``    a biped's ≥ ``WALK_STEPS`` (2) steps, ≥ ``WALK_DISTANCE`` (1 m)
            forward, forward-facing, heading changed by < ``TURN`` (45°).
``turn``    heading changed by ≥ ``TURN`` (45°).
``other``   anything else (shuffling in place, a slide, a lunge forward).

:func:`judge` returns (label, measures); :func:`relabel` names the label
again from kept measures.  A walk of ``n`` steps is ``measures["steps"]``.
"""
from __future__ import annotations

import numpy as np

from .bsr import secondary3d as s3

UPRIGHT_TILT = np.radians(45.0)
UPRIGHT_HEIGHT = 0.6
FACING = np.radians(30.0)
MIN_FLIGHT = 0.04
BOUND_DISTANCE = 0.6
PAIR_SYNC = 0.06
BOUND_PAIRED = 0.6
BOUND_SUPPORT = 0.2
WALK_DISTANCE = 1.0
WALK_STEPS = 2
TURN = np.radians(45.0)
LABELS = ("fallen", "bound", "walk", "turn", "other")


def _runs(mask) -> list[tuple[int, int]]:
    m = np.concatenate([[False], np.asarray(mask, bool), [False]]).astype(np.int8)
    d = np.diff(m)
    return list(zip(np.flatnonzero(d == 1).tolist(), np.flatnonzero(d == -1).tolist()))


def foot_pairs(feet) -> list[tuple[str, str]]:
    """A quadruped's front and rear pairs: feet whose names differ only in the
    last letter (empty unless the four feet make two such pairs)."""
    groups: dict[str, list[str]] = {}
    for f in feet:
        groups.setdefault(f[:-1], []).append(f)
    pairs = [tuple(g) for g in groups.values()]
    return pairs if len(feet) == 4 and len(pairs) == 2 and all(len(p) == 2 for p in pairs) else []


def _pair_measures(force, names, pairs, frame_dt) -> dict:
    """Share of footfalls paired with the partner's, and the lesser pair's
    share of the support (module doc)."""
    gap = max(1, round(MIN_FLIGHT / frame_dt))
    sync = max(1, round(PAIR_SYNC / frame_dt))
    falls = {}
    for pair in pairs:
        for f in pair:
            down = force[:, names.index(f)] > 0
            falls[f] = [b for a, b in _runs(~down) if a > 0 and b - a >= gap and b < len(down)]
    total = paired = 0
    for x, y in pairs:
        for f, g in ((x, y), (y, x)):
            for t in falls[f]:
                total += 1
                paired += any(abs(t - u) <= sync for u in falls[g])
    load = np.array([force[:, [names.index(f) for f in p]].sum() for p in pairs])
    return {"footfalls": total, "paired": paired / total if total else 0.0,
            "pair_support": float(load.min() / load.sum()) if load.sum() > 0 else 0.0}


def measures(traj, feet, foot_sites=(), foot_groups=(), e: int = 0) -> dict:
    """The measures the labels judge by, for episode ``e``: ``feet`` are the
    foot contact points' names; ``foot_sites`` a site per foot and
    ``foot_groups`` each foot's contact points (a biped: two), for steps."""
    fig = traj.figure
    quat = traj.base()[e, :, 3:7]
    com = traj.com[e]
    force = traj.contact_force[e]
    names = list(fig.contact_names)
    is_foot = np.array([n in feet for n in names])
    if not is_foot.any():
        raise ValueError(f"gaits3d: none of the feet {list(feet)} is a contact point of {fig.name}")
    up_z = s3.quat_up(quat)[:, 2]
    upright = (up_z >= np.cos(UPRIGHT_TILT)) & (com[:, 2] >= UPRIGHT_HEIGHT * com[0, 2])
    fell = np.maximum.accumulate(~upright | (force[:, ~is_foot] > 0).any(axis=1))
    yaw = s3.heading(quat)
    d = s3.in_start_frame(com[:, :2], yaw[0])
    feet_down = (force[:, is_foot] > 0).any(axis=1)
    landed = np.maximum.accumulate(feet_down)
    frame_dt = float(np.median(np.diff(traj.times)))
    flights = on_feet = 0
    for a, b in _runs(~feet_down & landed):
        if b - a < max(1, round(MIN_FLIGHT / frame_dt)) or b >= len(traj.times):
            continue
        flights += 1
        on_feet += bool(not (force[b, ~is_foot] > 0).any() and upright[b])
    pairs = foot_pairs(list(feet))
    out = {"forward": float(d[-1, 0]), "sideways": float(abs(d[-1, 1])),
           "turn_deg": float(np.degrees(abs(yaw[-1] - yaw[0]))),
           "facing_deg": float(np.degrees(s3.facing_away(yaw))),
           "upright": float(upright.mean()), "fell": bool(fell[-1]),
           "fallen": float(fell.mean()), "flights": flights, "landed_on_feet": on_feet,
           "steps": None, "footfalls": None, "paired": None, "pair_support": None}
    if pairs:
        out.update(_pair_measures(force, names, pairs, frame_dt))
    if len(foot_groups) == 2 and len(foot_sites) == 2:
        xy = traj.sites()[e][:, [fig.site_names.index(n) for n in foot_sites], :2]
        fwd = np.stack([s3.in_start_frame(xy[:, k], yaw[0])[:, 0] for k in range(2)], -1)
        grp = np.stack([force[:, [names.index(n) for n in g]].sum(-1) for g in foot_groups], -1)
        out["steps"] = int(s3.count_steps(grp[None], fwd[None], fell[None], yaw[None],
                                          max_yaw=FACING, alternate=True)[0])
    return out


def relabel(m: dict) -> str:
    """The label of kept :func:`measures` (module doc)."""
    facing = m["facing_deg"] <= np.degrees(FACING) and m["turn_deg"] <= np.degrees(FACING)
    if m["fell"]:
        return "fallen"
    if (m.get("paired") is not None and m["flights"] >= 2 and m["landed_on_feet"] >= 2
            and m["paired"] >= BOUND_PAIRED and m["pair_support"] >= BOUND_SUPPORT
            and m["forward"] >= BOUND_DISTANCE and facing):
        return "bound"
    if (m["steps"] is not None and m["steps"] >= WALK_STEPS and m["forward"] >= WALK_DISTANCE
            and facing):
        return "walk"
    if m["turn_deg"] >= np.degrees(TURN):
        return "turn"
    return "other"


def judge(traj, task, e: int = 0) -> tuple[str, dict]:
    """(label, measures) of episode ``e`` of a creature task's trajectory (the
    task names the feet: ``feet``, ``foot_sites``, ``foot_groups``)."""
    m = measures(traj, task.feet, getattr(task, "foot_sites", ()),
                 getattr(task, "foot_groups", ()), e)
    return relabel(m), m
