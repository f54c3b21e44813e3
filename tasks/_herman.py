"""Shared pieces of the Herman upper-body tasks (Gritz & Hahn's humanoid).

The GP drives the right arm only (shoulder y/z/x, elbow, wrist y/x); every
other joint holds Herman's neutral pose with its PD servo, so the style
terms watch what the arm's motion does to the rest of the body:

* ``energy``    actuator work over the episode (J)
* ``posture``   mean RMS deviation of the PD-held joints from neutral (rad):
                torso sway, the other arm swinging, the head nodding
* ``through``   the hand or fingertip inside the torso's cylinder (a penalty
                standing in for self-collision, which only a SelfContact
                version has): fraction of frames inside + deepest
                penetration / radius
* ``rest``      mean fingertip speed over the last 0.3 s (m/s)

This module starts with ``_``: the plugin loader does not import it as a task.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from gpmotion.gp.settings import GPSettings
from gpmotion.task import Task, Term

FIGURE = "herman"
ARM = ("shoulder_r_y", "shoulder_r_z", "shoulder_r_x", "elbow_r", "wrist_r_y", "wrist_r_x")
# The fingertip relative to the task's goal point (the scene goal, world
# (x, y, z); each task puts it on its target), so a controller can see how
# far it still has to go, as in Gritz & Hahn's "effector position relative
# to the goal" senses.
FINGERTIP = ("site_fingertip_r_dx", "site_fingertip_r_dy", "site_fingertip_r_dz")
TERMINALS = (tuple(f"angle_{a}" for a in ARM) + tuple(f"rate_{a}" for a in ARM) + ("t",)
             + FINGERTIP)
REST_WINDOW = 0.3          # s: the style term "rest" looks at the fingertip over this tail
# Success is judged on a motion that has come to rest: every Herman task
# requires the fingertip's speed to stay below REST_SPEED over the last
# SETTLE seconds (its largest speed there), so a finger swinging through
# the target at the last frame does not count.  5 cm/s moves the fingertip
# 5 mm over that window.
REST_SPEED = 0.05          # m/s
SETTLE = 0.1               # s


# Cost scale: the GP's default roulette selects on 1/(1 + cost), so a cost
# that only spans 0..1.5 barely separates good from bad controllers.  The
# touch tasks weight their main distance by MAIN_WEIGHT (a cost of 1 per
# 10 cm); the style weights below are on the same scale.
MAIN_WEIGHT = 10.0

# A herman arm run evaluates ~240 rollouts of 1.5 s per second on two cores;
# 400 × 50 takes ~1.5 minutes.  Constant creep (Gaussian steps on a tree's
# constants) does the last few centimetres: with it touch_nose went from
# 2/5 to 4/5 seeds at 250 × 40, and seed 0 (3.6 cm at 250 × 40) reaches the
# nose at 400 × 50.
GP_DEFAULTS = {"population": 400, "generations": 50, "p_crossover": 0.85, "p_creep": 0.1}
# The nose's search (herman_touch_nose): angle targets, and the last
# 20 of the 50 generations polish the best; the versions that take it name it.
NOSE_SEARCH = {"targets": "angle", "defaults": {**GP_DEFAULTS, "polish": 20}}   # GPSettings fields


# Pictures of an arm task: the upper body, seen from the front right (mostly its
# right side: the right arm towards the camera), without the floor grid.
VIEW = {"elev": 10, "azim": -80, "ground": False,
        "bodies": ["pelvis", "torso", "head", "upper_arm_r", "forearm_r", "hand_r",
                   "upper_arm_l", "forearm_l", "hand_l"]}


class HermanTask(Task):
    """What every Herman task shares (one block, not one copy per
    task): the figure, the joints under GP and their senses, the GP budget,
    the time step, the picture view, and success = the task's own ``reached``
    test AND a motion that has come to rest (``at_rest``).  A task overrides
    any of these class attributes where it needs more of the body (its file
    says so).  Not registered: a base, not a task."""
    figure = FIGURE
    # A 2 ms step: the fixed-pelvis arm touches nothing and its PD servos are
    # implicit, so the step is limited by accuracy alone: over fast random arm
    # motions the fingertip is within 1.9-4.4 mm of a 0.5 ms run (1 ms: 0.6-1.5
    # mm), a tenth of the touch thresholds, at half the cost per rollout.
    # Frames stay 10 ms apart.  A task with stiff contacts sets its own.
    dt = 2e-3
    record_every = 5
    params = {"seconds": 1.5}
    controlled = ARM
    gp = GPSettings(terminals=TERMINALS, defaults=GP_DEFAULTS)
    view = VIEW

    def reached(self, traj, m) -> np.ndarray:
        """The task's own goal test per episode (without the rest rule)."""
        raise NotImplementedError

    def success(self, traj, m):
        return self.reached(traj, m) & at_rest(m)


def goal_scene(point):
    """The default scene with the goal (senses' reference) at a world point (x, y, z)."""
    from gpmotion.model import make_scene
    return make_scene(goal=tuple(float(v) for v in point))


def site_at_rest(fig, name) -> np.ndarray:
    """World position of a site in Herman's default (neutral) pose."""
    from gpmotion.sim import geometry3d
    return geometry3d.sites_world(fig, fig.q_default)[fig.site_names.index(name)]


def style_terms(rest: bool = True, scale: float = MAIN_WEIGHT,
                rest_weight: float | None = None) -> tuple[Term, ...]:
    """The style points every Herman arm task shares, phased in after the main goal.

    Weights are for a main term worth ``scale`` per unit; at scale 10 (1 per
    10 cm): a hand inside the torso for the whole episode costs 15-30 cm of
    miss, 1° RMS of sway of the held joints 1.7 mm, 100 J of actuator work 2 cm
    (a plain PD step to the nose spends ~110 J), a fingertip still moving at
    10 cm/s over the last 0.3 s 3 cm (success needs it below REST_SPEED, so
    the rest term weighs as much as a miss of the touch threshold; a task whose
    threshold costs more gives its own ``rest_weight``, per m/s)."""
    terms = [
        Term("through", 0.15 * scale, phase=(0.1, 0.4),
             doc="hand/fingertip inside the torso: fraction of frames + depth/radius"),
        Term("posture", 0.1 * scale, phase=(0.3, 0.7),
             doc="mean RMS deviation of the PD-held joints from neutral (rad)"),
        Term("energy", 0.0002 * scale, phase=(0.5, 0.9), doc="actuator work over the episode (J)"),
    ]
    if rest:
        terms.append(Term("rest", 0.3 * scale if rest_weight is None else rest_weight,
                          phase=(0.2, 0.6),
                          doc=f"mean fingertip speed over the last {REST_WINDOW} s (m/s)"))
    return tuple(terms)


def rest_scaled(terms) -> tuple[Term, ...]:
    """The style terms with the rest term's weight scaled by the task parameter
    ``w_rest`` (a task using this declares it)."""
    return tuple(replace(t, param="w_rest") if t.name == "rest" else t for t in terms)


def _segment(fig, body):
    """(index into segments(), radius) of a body's capsule."""
    i = fig.body_names.index(body)
    m = fig.model
    return i, float(m.seg_r[i])


def point_axis_distance(p, a, b):
    """Distance [...] from points p [..., 3] to the line a-b [..., 3] and the
    position t [...] of the foot of the perpendicular (0 at a, 1 at b)."""
    ab = b - a
    t = np.einsum("...k,...k->...", p - a, ab) / np.maximum(np.einsum("...k,...k->...", ab, ab), 1e-12)
    return np.linalg.norm(p - (a + t[..., None] * ab), axis=-1), t


def through_torso(traj, points=("hand_r", "fingertip_r")):
    """Per episode: fraction of frames with a point inside the torso capsule plus
    the deepest penetration as a fraction of the radius (0 when never inside)."""
    fig = traj.figure
    i, r = _segment(fig, "torso")
    # the torso's axis: the capsules come from the sites' kinematics pass
    seg = traj.segments()[..., i, :, :]
    a, b = seg[..., 0, :], seg[..., 1, :]
    sites = traj.sites()
    worst = np.zeros(traj.q.shape[:2])
    for name in points:
        p = sites[..., fig.site_names.index(name), :]
        d, t = point_axis_distance(p, a, b)
        # the trunk's cylinder only: the capsule's end caps would reach the chin
        inside = np.where((t > 0.0) & (t < 1.0), np.clip((r - d) / r, 0.0, 1.0), 0.0)
        worst = np.maximum(worst, inside)
    return (worst > 0).mean(axis=1) + worst.max(axis=1)


def limbs_overlap(traj, bodies=("forearm_r", "hand_r"), samples=9) -> np.ndarray:
    """[E, F] the deepest overlap (m) of ``bodies``' capsules with the torso's
    cylinder in each frame (0 apart), sampled at ``samples`` points along
    each capsule's axis.  A forearm can cross the trunk with both its end
    points outside, which ``through_torso`` does not see."""
    fig = traj.figure
    i, r = _segment(fig, "torso")
    seg = traj.segments()
    a, b = seg[..., i, 0, :], seg[..., i, 1, :]
    worst = np.zeros(traj.q.shape[:2])
    for body in bodies:
        j, rj = _segment(fig, body)
        for s in np.linspace(0.0, 1.0, samples):
            p = seg[..., j, 0, :] * (1.0 - s) + seg[..., j, 1, :] * s
            d, t = point_axis_distance(p, a, b)
            worst = np.maximum(worst, np.where((t > 0.0) & (t < 1.0), np.maximum(r + rj - d, 0.0), 0.0))
    return worst


def limbs_through_torso(overlap, fig, allow: float) -> np.ndarray:
    """``through_torso``'s value for ``limbs_overlap``: the fraction of frames
    overlapping by more than ``allow`` (m: a forearm resting on the belly)
    plus the deepest overlap beyond it as a fraction of the torso's radius."""
    r = _segment(fig, "torso")[1]
    excess = np.maximum(overlap - allow, 0.0)
    return (excess > 0).mean(axis=1) + np.minimum(excess.max(axis=1) / r, 1.0)


# A forearm resting on the belly overlaps the trunk's cylinder a little
# (capsules are rounder than a body); beyond this it has gone through.
CROSSING = 0.01            # m


class TrunkCheck:
    """Mixin for a task version whose right forearm may not cross the trunk
    (list it before the task's class: ``class V(TrunkCheck, HermanX)``).

    Herman has no self-collision, and v1's ``through`` watched the hand and
    fingertip sites alone, so a forearm could pass through the trunk with
    both outside (3 of touch_nose's 4 successes did).  The
    checked version adds ``limbs_through_torso`` of the forearm's and hand's
    capsules to ``through`` (so a population that never crosses is scored as
    before), measures ``crossing`` (the deepest overlap, m) and requires it
    ≤ CROSSING for success.  The version listing TrunkCheck gets its
    ``success_threshold`` and ``through`` doc derived (``__init_subclass__``).

    ``charge = False`` judges the crossing without charging it: the cost,
    and so the search, stay the previous version's.  For tasks whose
    searches do not cross anyway and which charging made worse (point
    4 / 5 -> 2 / 5, wave 5 / 5 -> 1 / 5, grasp 5 / 5 -> 4 / 5; their
    v1 best controllers crossed at most 0.7 cm in 5 seeds)."""
    charge = True

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if TrunkCheck in cls.__bases__:        # the version that adds the check, once
            cls.success_threshold = checked_threshold(cls.success_threshold)
            if cls.charge:
                cls.terms = checked_terms(cls.terms)

    def measure(self, traj):
        overlap = limbs_overlap(traj)
        m = super().measure(traj)
        extra = limbs_through_torso(overlap, traj.figure, CROSSING) if self.charge else 0.0
        return {**m, "through": m["through"] + extra, "crossing": overlap.max(axis=1)}

    def reached(self, traj, m):
        return super().reached(traj, m) & (m["crossing"] <= CROSSING)

    def describe(self, traj, m):
        return [*super().describe(traj, m),
                f"forearm and hand at most {m['crossing'][0] * 100:.1f} cm into the trunk"]


# The bodies Herman's right forearm and hand collide with in a SelfContact
# version: the trunk (torso) and the pelvis below it.  Not the head (a
# fingertip touching the nose would be held off it by the hand's capsule)
# nor the upper arm and shoulder rotors (adjacent: they overlap at the joint).
SELF_CONTACT = (("forearm_r", "torso"), ("hand_r", "torso"),
                ("forearm_r", "pelvis"), ("hand_r", "pelvis"))


class SelfContact:
    """Mixin for a task version in which Herman's right forearm and hand
    collide with his trunk and pelvis (``SELF_CONTACT``): capsule-capsule
    penalty contact in the 3-D kernel (``gpmotion.sim.selfcontact3d``), so
    a forearm cannot pass through the body in the first place, where
    TrunkCheck only charges and judges it.  List it before the task's class
    (``class V(SelfContact, HermanXV3)``); TrunkCheck's judgement stays (the
    contact's springs let in a few millimetres)."""

    def scene(self):
        return with_self_contact(super().scene(), self.figure)


def with_self_contact(scene, figure):
    """``scene`` with Herman's self-contact pairs (``SelfContact``'s scene; a
    version that collides on some presets only calls it itself)."""
    from gpmotion.sim.selfcontact3d import self_contact_pairs
    return scene._replace(selfc=self_contact_pairs(figure, SELF_CONTACT))


def checked_terms(terms) -> tuple[Term, ...]:
    """``terms`` with the ``through`` term's doc saying what TrunkCheck adds."""
    return tuple(replace(t, doc=f"{t.doc}; + the same for the right forearm's and hand's capsules "
                                f"overlapping it by more than {CROSSING * 100:.0f} cm")
                 if t.name == "through" else t for t in terms)


def checked_threshold(threshold: str) -> str:
    return (f"{threshold}; forearm and hand never more than {CROSSING * 100:.0f} cm into the "
            f"trunk's cylinder")


def posture(traj, controlled=ARM):
    """Mean over frames of the RMS deviation of the PD-held joints from neutral (rad)."""
    fig = traj.figure
    m = fig.model
    held = [a for a, n in enumerate(fig.actuator_names) if n not in controlled]
    dev = traj.q[..., m.act_q[held]] - m.neutral[held]
    return np.sqrt((dev ** 2).mean(axis=-1)).mean(axis=1)


LIMIT_EPS = 0.02           # rad: a joint this close to an end of its range is on its limit


def on_limits(traj, controlled=ARM, seconds=0.5):
    """Per episode: the fraction of the joints under GP that sit on a limit of
    their range (within LIMIT_EPS), averaged over the last ``seconds``.  Under
    rate targets any constant tree drives its joint to a limit, so a pose of
    joints on their limits is the easy near-solution of a reach."""
    fig = traj.figure
    m = fig.model
    idx = [fig.actuator_names.index(a) for a in controlled]
    lim = fig.actuator_limits()[idx]
    q = traj.q[:, tail(traj, seconds)][..., m.act_q[idx]]
    on = (q <= lim[:, 0] + LIMIT_EPS) | (q >= lim[:, 1] - LIMIT_EPS)
    return on.mean(axis=(1, 2))


def site_speed(traj, name):
    """Speed [E, F] of a site by central differences over the recorded frames (m/s)."""
    p = traj.site(name)
    return np.linalg.norm(np.gradient(p, traj.times, axis=1), axis=-1)


def tail(traj, seconds):
    """Boolean mask [F] of the frames in the last ``seconds`` of the episode."""
    return traj.times >= traj.times[-1] - seconds - 1e-9


def style_measures(traj, rest: bool = True, controlled=ARM) -> dict[str, np.ndarray]:
    """The style terms' raw values, and ``end_speed``: the fingertip's largest
    speed over the last SETTLE s (m/s), which success compares with REST_SPEED.
    ``controlled``: the joints under GP (posture watches the others)."""
    speed = site_speed(traj, "fingertip_r")
    out = {"through": through_torso(traj), "posture": posture(traj, controlled),
           "energy": traj.energy.sum(axis=1),
           "end_speed": speed[:, tail(traj, SETTLE)].max(axis=1)}
    if rest:
        out["rest"] = speed[:, tail(traj, REST_WINDOW)].mean(axis=1)
    return out


def at_rest(m) -> np.ndarray:
    """Per episode: has the motion come to rest (fingertip slower than REST_SPEED
    throughout the last SETTLE s)?  Part of every Herman task's success."""
    return m["end_speed"] < REST_SPEED


REST_RULE = f"fingertip slower than {REST_SPEED * 100:.0f} cm/s over the last {SETTLE} s"


# ---- posing Herman by hand (tests, examples): numpy forward kinematics -------
def pose_q(fig, **angles) -> np.ndarray:
    """Herman's default configuration with some actuated joints set (radians)."""
    q = fig.q_default.copy()
    for name, v in angles.items():
        q[fig.model.act_q[fig.actuator_names.index(name)]] = v
    return q


def reach(fig, site, target, joints=ARM, x0=None):
    """Joint angles of ``joints`` (within their limits) that bring ``site`` closest
    to the world point ``target``: least squares on the numpy forward kinematics."""
    from scipy.optimize import least_squares

    from gpmotion.sim import geometry3d

    m = fig.model
    idx = [fig.actuator_names.index(n) for n in joints]
    lo, hi = m.lo[m.act_dof[idx]], m.hi[m.act_dof[idx]]
    k = fig.site_names.index(site)
    target = np.asarray(target, dtype=np.float64)

    def residual(x):
        q = fig.q_default.copy()
        q[m.act_q[idx]] = x
        return geometry3d.sites_world(fig, q)[k] - target

    start = np.clip(m.neutral[idx] if x0 is None else np.asarray(x0, float), lo, hi)
    sol = least_squares(residual, start, bounds=(lo, hi))
    return dict(zip(joints, sol.x)), float(np.linalg.norm(sol.fun))
