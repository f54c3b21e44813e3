"""Herman, the 3-D humanoid (Gritz & Hahn), and its right-arm tasks."""
from dataclasses import replace

import numpy as np
import pytest

import gpmotion
from gpmotion.check import check_task
from gpmotion.figures import load_spec
from gpmotion.gp.settings import terminal_names
from gpmotion.sim import geometry3d
from gpmotion.task import get_task
from gpmotion.tasks._herman import ARM, REST_SPEED, SETTLE, TERMINALS, HermanTask, pose_q, reach
from gpmotion.tasks.herman_touch_object import PRESETS
from gpmotion.tasks.herman_wave import count_passes

HERMAN_TASKS = ("herman_point", "herman_touch", "herman_touch_nose", "herman_touch_object",
                "herman_wave")
SITES = ("nose", "head_top", "chest", "shoulder_r", "shoulder_l", "hand_r", "hand_l",
         "fingertip_r", "fingertip_l", "foot_r", "foot_l")


@pytest.fixture(scope="module")
def herman():
    return gpmotion.load_figure("herman")


def _site(fig, q, name):
    return geometry3d.sites_world(fig, q)[..., fig.site_names.index(name), :]


def _still(fig, q, seconds=1.0, scene=None):
    """A Trajectory that holds configuration q (built from a real rollout's shape)."""
    tr = gpmotion.simulate(fig, seconds, scene=scene)
    return replace(tr, q=np.broadcast_to(q, tr.q.shape).copy(), qd=np.zeros_like(tr.qd),
                   energy=np.zeros_like(tr.energy))


# ---------------------------------------------------------------- the figure
def test_herman_compiles_with_winters_masses_and_its_sites(herman):
    spec = load_spec(gpmotion.figures._REGISTRY["herman"])
    masses = {b["name"]: b["mass"] for b in spec["bodies"]}
    assert sum(masses.values()) == pytest.approx(70.0, abs=1e-6)            # M = 70 kg
    # Winter's fractions (pelvis 0.142, head 0.081, thigh 0.100, hand 0.006)
    assert masses["pelvis"] == pytest.approx(0.142 * 70) and masses["head"] == pytest.approx(0.081 * 70)
    assert masses["thigh_r"] == pytest.approx(0.100 * 70) and masses["hand_l"] == pytest.approx(0.006 * 70)
    assert herman.root == "fixed" and herman.total_mass == pytest.approx(70.0 - masses["pelvis"])
    assert herman.nq == 29 and len(herman.actuator_names) == 29
    assert set(ARM) <= set(herman.actuator_names)
    assert set(SITES) <= set(herman.site_names)
    for name in TERMINALS:
        herman.sense_index(name)
    q = herman.q_default
    assert _site(herman, q, "head_top")[2] == pytest.approx(1.75, abs=1e-6)   # H = 1.75 m
    assert _site(herman, q, "shoulder_r")[2] == pytest.approx(0.818 * 1.75, abs=1e-3)
    assert _site(herman, q, "nose")[0] > 0.05                                 # faces +x
    assert _site(herman, q, "shoulder_l")[1] > 0 > _site(herman, q, "shoulder_r")[1]  # y left
    for foot in ("foot_r", "foot_l"):                                         # just above the floor
        assert 0.0 < _site(herman, q, foot)[2] < 0.01


def test_herman_holds_its_neutral_pose_without_jitter(herman):
    tr = gpmotion.simulate(herman, 2.0, record_every=1)
    assert not tr.diverged[0]
    m = herman.model
    assert np.abs(tr.qd[0, -1]).max() < 1e-3
    assert np.abs(tr.q[0, -1, m.act_q] - m.neutral).max() < 0.02          # sags < 1.2°
    last = tr.qd[0, -500:]
    assert np.abs(np.diff(last, axis=0)).max() / 1e-3 < 0.05              # no step-to-step rattle
    assert tr.contact_force.max() == 0.0                                   # feet clear of the floor


def test_herman_arm_servos_are_stable_over_random_poses(herman):
    """The shoulder's light 'spin' mode is where an explicit PD jitters first."""
    from gpmotion.controllers import schedule
    m, names = herman.model, herman.actuator_names
    rng = np.random.default_rng(1)
    idx = [names.index(n) for n in ARM]
    lo, hi = m.lo[m.act_dof[idx]], m.hi[m.act_dof[idx]]
    T = np.tile(m.neutral, (40, 1))
    T[:, idx] = rng.uniform(lo, hi, (40, len(idx)))
    tr = gpmotion.rollout(herman, gpmotion.make_scene(), schedule.sines(T, 0.0, 1.0, 0.0),
                          n_steps=2000, record_every=10)
    assert not tr.diverged.any()
    assert np.abs(tr.qd[:, -1]).max() < 0.05


def test_herman_standing_stands_for_5_s_at_the_default_step():
    """The free-pelvis variant on its feet, holding neutral with PD at dt = 1 ms.

    It needs the implicit PD servos: the light pelvis (I ≈ 0.04 kg·m²) sits
    between the hip and waist servos (Σkd·dt/I ≈ 7), which an explicit PD
    cannot hold at this step (it jitters and falls within ~1 s)."""
    fig = gpmotion.load_figure("herman_standing")
    assert fig.root == "free" and fig.nv == 35
    # its own ground (the TOML's [ground]): 1e5 N/m per sole point resists
    # tipping with k·Σx² ≈ 7300 N·m/rad, ten times m·g·h ≈ 690 (the default
    # 5000 N/m: 370, it would tip over); 400 N·s/m damps the bounce (~11 /s)
    assert fig.ground == {"k_ground": 1e5, "c_ground": 400.0}
    k = fig.ground["k_ground"]
    tr = gpmotion.simulate(fig, 5.0, record_every=10)             # simulate uses fig.ground
    assert tr.scene.k_ground == k
    assert not tr.diverged[0]
    pelvis = tr.base()[0]                                          # (x, y, z, quaternion)
    assert np.abs(pelvis[:, :2] - pelvis[0, :2]).max() < 0.02      # within 2 cm horizontally
    assert pelvis[:, 2].min() > pelvis[0, 2] - 1e-3                # does not sink (< 1 mm)
    feet = [fig.contact_names.index(n) for n in ("heel_r", "toe_r", "heel_l", "toe_l")]
    soles = [fig.site_names.index(n) for n in ("foot_r", "foot_l")]
    weight = fig.total_mass * 9.81
    # the soles sink only as far as the ground springs must to carry the weight
    assert geometry3d.sites_world(fig, tr.q[0, -1])[soles, 2].min() > -2 * weight / (4 * k)
    assert np.abs(tr.qd[0, -1]).max() < 1e-3                       # at rest at the end
    assert tr.contact_force[0, -1, feet].sum() == pytest.approx(weight, rel=0.01)
    others = np.setdiff1d(np.arange(len(fig.contact_names)), feet)
    assert tr.contact_force[0, :, others].max() == 0.0             # nothing else touches


# ---------------------------------------------------------------- the tasks
@pytest.mark.parametrize("name", HERMAN_TASKS)
def test_herman_task_passes_check_task(name):
    check_task(name)


@pytest.mark.parametrize("name", HERMAN_TASKS)
def test_herman_tasks_drive_only_the_right_arm(name):
    t = get_task(name)
    assert t.figure.name == "herman" and tuple(t.controlled) == ARM
    assert t.success_threshold and 1.0 <= t.seconds <= 3.0


def test_touch_nose_main_term_is_zero_at_the_nose_and_large_at_neutral(herman):
    task = get_task("herman_touch_nose")
    nose = _site(herman, herman.q_default, "nose")
    angles, miss = reach(herman, "fingertip_r", nose, x0=[-1.0, 0.5, 0.0, 2.3, 0.0, 0.0])
    assert miss < 1e-4
    touching = _still(herman, pose_q(herman, **angles))
    neutral = _still(herman, herman.q_default)
    m_touch, m_neutral = task.measure(touching), task.measure(neutral)
    assert m_touch["touch"][0] < 1e-3 and m_touch["touch_end"][0] < 1e-3
    assert m_neutral["touch"][0] > 1.0                 # ~0.95 m away, + half of it again
    assert task.success(touching, m_touch)[0] and not task.success(neutral, m_neutral)[0]
    assert m_touch["through"][0] == 0.0 and m_touch["rest"][0] < 1e-9


def test_the_hand_inside_the_torso_is_penalized(herman):
    task = get_task("herman_touch_nose")
    inside = _site(herman, herman.q_default, "chest") - [0.10, 0.0, 0.0]    # 2 cm off the axis
    angles, miss = reach(herman, "hand_r", inside, x0=[-0.5, 0.5, 0.5, 2.0, 0.0, 0.0])
    assert miss < 0.01
    m = task.measure(_still(herman, pose_q(herman, **angles)))
    assert m["through"][0] > 1.0                      # every frame, and deep
    assert task.measure(_still(herman, herman.q_default))["through"][0] == 0.0


def test_point_main_term_follows_the_arm_direction(herman):
    task = get_task("herman_point", azimuth=-45.0, elevation=0.0)
    shoulder = _site(herman, herman.q_default, "shoulder_r")
    aim = shoulder + 0.7 * task.target_dir
    angles, miss = reach(herman, "fingertip_r", aim, x0=[-1.2, 0.0, -0.5, 0.1, 0.0, 0.0])
    assert miss < 0.01
    m = task.measure(_still(herman, pose_q(herman, **angles)))
    assert m["aim"][0] < np.radians(1.0) and task.success(None, m)[0]
    hanging = task.measure(_still(herman, herman.q_default))["aim"][0]
    assert np.radians(80) < hanging < np.radians(100)   # the arm hangs: ~90° off a horizontal aim
    assert m["bent"][0] < 0.1                            # 0.7 m of the 0.77 m arm
    # the same direction with the hand only 0.3 m out: aimed, but not a point
    angles, miss = reach(herman, "fingertip_r", shoulder + 0.3 * task.target_dir,
                         x0=[-1.2, 0.0, -0.5, 2.0, 0.0, 0.0])
    assert miss < 0.01
    m = task.measure(_still(herman, pose_q(herman, **angles)))
    assert m["aim"][0] < np.radians(1.0) and m["bent"][0] > 0.5 and not task.success(None, m)[0]


@pytest.mark.parametrize("target", [0, 1, 2])
def test_touch_object_presets_are_reachable(herman, target):
    task = get_task("herman_touch_object", target=target)
    obj = task.object_position()
    assert obj == pytest.approx(np.array(PRESETS[target]) + [0.0, 0.0, 0.96])
    angles, miss = reach(herman, "fingertip_r", obj, x0=[-0.8, 0.3, 0.0, 1.5, 0.0, 0.0])
    assert miss < 0.005
    m = task.measure(_still(herman, pose_q(herman, **angles), scene=task.scene()))
    assert m["object"][0] < 0.005 and task.success(None, m)[0]


def test_touch_object_rejects_bad_targets():
    with pytest.raises(ValueError, match="target"):
        get_task("herman_touch_object", target=5)
    with pytest.raises(ValueError, match="reaches"):
        get_task("herman_touch_object", x=1.5)


def test_wave_counts_lateral_swings_only_while_raised():
    t = np.linspace(0.0, 1.5, 151)
    y = np.stack([0.1 * np.sin(2 * np.pi * 1.5 * t),      # 1.5 Hz, ±10 cm: 5 passes
                  0.02 * np.sin(2 * np.pi * 3 * t),       # too small to count
                  0.1 * np.sin(2 * np.pi * 1.5 * t)])
    ok = np.ones_like(y, dtype=bool)
    ok[2] = False                                          # swinging, but the hand is down
    assert count_passes(y, ok).tolist() == [5, 0, 0]


def test_wave_cost_is_bounded_and_worst_when_the_arm_hangs(herman):
    task = get_task("herman_wave")
    m = task.measure(_still(herman, herman.q_default, seconds=task.seconds))
    assert 0.9 < m["wave"][0] <= 1.0 and not task.success(None, m)[0]


@pytest.mark.parametrize("name", HERMAN_TASKS)
def test_herman_tasks_see_the_fingertip_relative_to_their_goal(name, herman):
    task = get_task(name)
    assert {"site_fingertip_r_dx", "site_fingertip_r_dy", "site_fingertip_r_dz"} <= set(terminal_names(task))
    scene = task.scene()
    tr = gpmotion.rollout(herman, scene, schedule_constant(herman), n_steps=50, record_senses=True)
    got = np.stack([tr.sense(f"site_fingertip_r_{a}") for a in ("dx", "dy", "dz")], -1)
    assert np.abs(got - (tr.site("fingertip_r") - scene.goal3)).max() < 1e-9


def schedule_constant(fig):
    from gpmotion.controllers import schedule
    return schedule.constant(fig.model.neutral)


def test_herman_task_goals_are_their_targets(herman):
    nose = _site(herman, herman.q_default, "nose")
    assert np.allclose(get_task("herman_touch_nose").scene().goal3, nose)
    t = get_task("herman_touch_object", target=1)
    assert np.allclose(t.scene().goal3, t.object_position())
    p = get_task("herman_point", azimuth=30.0, elevation=10.0)
    shoulder = _site(herman, herman.q_default, "shoulder_r")
    d = p.scene().goal3 - shoulder
    assert np.linalg.norm(d) == pytest.approx(0.6) and np.allclose(d / 0.6, p.target_dir)
    assert get_task("herman_wave").scene().goal3[2] > shoulder[2] + 0.3


def test_reach_standing_scores_balance_and_falls():
    from gpmotion.controllers import schedule
    task = get_task("herman_reach_standing", seconds=1.0)
    assert task.figure.model.jtype[0] == 2                                # a free pelvis
    hold = schedule.constant(task.figure.model.neutral)
    still = gpmotion.rollout(task.figure, task.scene(), hold, n_steps=task.n_steps, dt=task.dt,
                             record_every=task.record_every)
    _, m, _ = task.score(still)
    assert m["balance"][0] < 0.01                                      # stands where it stood
    q0 = task.figure.q_default.copy()
    q0[3:7] = [np.cos(0.3), 0.0, np.sin(0.3), 0.0]                     # leaning 0.6 rad forward
    q0[2] += 0.2
    fall = gpmotion.rollout(task.figure, task.scene(), hold, n_steps=task.n_steps, q0=q0,
                            dt=task.dt, record_every=task.record_every)
    _, m, ok = task.score(fall)
    assert m["balance"][0] > 1.0 and not ok[0]                         # it fell: +1


def test_standing_herman_at_the_reach_tasks_step_tracks_a_fine_step():
    """herman_reach_standing-v2 steps at 2 ms on the standing figure's stiff
    ground.  Over fast random arm motions (keyframes anywhere in the arm's
    range every 0.3 s) the 2 ms run stays stable and, while the pelvis stays
    within the 5 cm a success allows, its fingertip stays within 1 cm of a
    0.5 ms run (measured 3-6 mm, 11-24 mm at 5 ms; the touch threshold is
    4 cm) and its pelvis within 3 mm (measured 0.6-1.9 mm)."""
    from gpmotion.tasks.herman_reach_standing import STEADY
    task = get_task("herman_reach_standing")
    assert (task.dt, task.record_every) == (2e-3, 5)
    fig = task.figure
    arm = [fig.actuator_names.index(a) for a in ARM]
    lim, rng = fig.actuator_limits(), np.random.default_rng(1)
    times, judged = np.linspace(0.0, 1.5, 6), 0
    for _ in range(4):
        keys = np.tile(fig.model.neutral, (len(times), 1))
        keys[1:, arm] = rng.uniform(lim[arm, 0], lim[arm, 1], (len(times) - 1, len(arm)))
        fine, coarse = (gpmotion.simulate(fig, 2.0, targets=(times, keys), dt=dt,
                                          record_every=round(0.01 / dt)) for dt in (5e-4, 2e-3))
        assert not coarse.diverged.any() and np.isfinite(coarse.q).all()
        pelvis = fine.base()[0, :, :3]
        if np.linalg.norm(pelvis[:, :2] - pelvis[0, :2], axis=-1).max() > STEADY:
            continue                                   # a stumble: not what a success looks like
        judged += 1
        assert np.abs(coarse.site("fingertip_r") - fine.site("fingertip_r")).max() < 0.01
        assert np.abs(coarse.base()[..., :3] - fine.base()[..., :3]).max() < 0.003
    assert judged >= 2


def test_the_limits_term_counts_the_arm_joints_resting_on_a_limit(herman):
    """limits = the fraction of the arm's joints within 0.02 rad of an end of
    their range over the last 0.5 s: 0 at neutral, k/6 with k joints on a limit,
    and only the tail counts."""
    from gpmotion.tasks._herman import on_limits
    lim = herman.actuator_limits()
    q = herman.q_default.copy()
    assert on_limits(_still(herman, q))[0] == 0.0
    for k, a in enumerate(("shoulder_r_z", "wrist_r_y")):
        j = herman.actuator_names.index(a)
        q[herman.model.act_q[j]] = lim[j, k % 2] - 0.01 * (1 if k % 2 else -1)   # 0.01 rad inside
    assert on_limits(_still(herman, q))[0] == pytest.approx(2 / 6)
    tr = _still(herman, q)
    early = tr.times < tr.times[-1] - 0.5 - 1e-9
    tr.q[:, ~early] = herman.q_default                 # on the limits only before the tail
    assert on_limits(tr)[0] == 0.0
    task = get_task("herman_touch_object", target=1, w_limits=2.0)
    assert {t.name: t.weight for t in task.terms}["limits"] == pytest.approx(2.0)
    assert task.measure(_still(herman, q))["limits"][0] == pytest.approx(2 / 6)
    # v2's target 1 charges it by default (its misses rest on the limits) and
    # triples the rest term; the other presets, and every preset of v1, do not
    def weights(tid, t):
        return {x.name: x.weight for x in get_task(tid, target=t).terms}

    for t in (-1, 0, 1, 2):
        assert weights("herman_touch_object-v1", t)["limits"] == 0.0
        assert weights("herman_touch_object-v1", t)["rest"] == pytest.approx(3.0)
    v2 = {t: (weights("herman_touch_object", t)["limits"], weights("herman_touch_object", t)["rest"])
          for t in (-1, 0, 1, 2)}
    assert v2 == {-1: (0.0, 3.0), 0: (0.0, 3.0), 1: (pytest.approx(2.0), pytest.approx(9.0)), 2: (0.0, 3.0)}
    assert get_task("herman_touch_object", target=1, w_limits=0).params["w_limits"] == 0.0
    assert get_task("herman_touch_object", target=1, w_rest=1).params == {
        **get_task("herman_touch_object", target=1).params, "w_rest": 1.0}


# ---------------------------------------------------------------- success at rest
def _passing(fig, q_end, dq, seconds=1.0):
    """A Trajectory moving at constant joint velocity dq that is at q_end on its last frame."""
    tr = gpmotion.simulate(fig, seconds)
    q = q_end + (tr.times - tr.times[-1])[:, None] * dq
    return replace(tr, q=np.broadcast_to(q, tr.q.shape).copy(), qd=np.zeros_like(tr.qd),
                   energy=np.zeros_like(tr.energy))


def test_touch_succeeds_only_once_the_fingertip_has_come_to_rest(herman):
    """A finger swinging through the nose on the last frame is not a touch."""
    task = get_task("herman_touch_nose")
    nose = _site(herman, herman.q_default, "nose")
    angles, miss = reach(herman, "fingertip_r", nose, x0=[-1.0, 0.5, 0.0, 2.3, 0.0, 0.0])
    q_touch = pose_q(herman, **angles)
    dq = np.zeros_like(q_touch)
    dq[herman.model.act_q[herman.actuator_names.index("elbow_r")]] = 1.0      # 1 rad/s
    swinging = _passing(herman, q_touch, dq)
    m = task.measure(swinging)
    assert m["touch_end"][0] < 1e-3                       # on the nose at the last frame ...
    assert m["end_speed"][0] > 5 * REST_SPEED              # ... passing at ~0.3 m/s
    assert not task.success(swinging, m)[0]
    creeping = _passing(herman, q_touch, dq * 0.5 * REST_SPEED / m["end_speed"][0])
    m = task.measure(creeping)
    assert m["end_speed"][0] < REST_SPEED and task.success(creeping, m)[0]


@pytest.mark.parametrize("name", HERMAN_TASKS + ("herman_reach_standing",))
def test_every_herman_task_requires_rest_and_shares_one_attribute_block(name):
    cls = type(get_task(name))
    assert issubclass(cls, HermanTask)
    for attr in ("controlled", "view", "success"):
        assert attr not in vars(cls), f"{name} repeats {attr}: it belongs to HermanTask"
    assert cls.gp.terminals == HermanTask.gp.terminals, f"{name} repeats terminals: they belong to HermanTask"
    # a task may change its budget's generations (longer episodes) and how many of them
    # polish the best (--polish), nothing else of it
    own = ("generations", "polish")
    assert {k: v for k, v in cls.gp.defaults.items() if k not in own} == \
        {k: v for k, v in HermanTask.gp.defaults.items() if k not in own}
    assert f"{REST_SPEED * 100:.0f} cm/s" in cls.success_threshold and f"{SETTLE} s" in cls.success_threshold


# ---------------------------------------------------------------- touching any site
def test_touch_any_site_reaches_the_knee_by_bending_at_the_waist(herman):
    from gpmotion.tasks.herman_touch import WAIST, reach_site
    task = get_task("herman_touch", site="knee_l")
    assert tuple(task.controlled) == WAIST + ARM
    assert {"angle_waist_y", "rate_waist_y"} <= set(terminal_names(task))
    assert np.allclose(task.scene().goal3, _site(herman, herman.q_default, "knee_l"))
    starts = [(-0.3, 0.0, -0.3, 0.3, 0.0, 0.0), (-0.8, 0.3, 0.0, 1.5, 0.0, 0.0)]
    assert reach_site(herman, "knee_l", ARM, starts) > 0.1                # the arm alone: short
    assert reach_site(herman, "knee_l", WAIST + ARM,
                      [(1.0, 0.2, 0.5) + s for s in starts]) < 0.005      # bending: reached
    assert tuple(get_task("herman_touch", site="belly").controlled) == ARM


def test_touch_a_left_arm_site_brings_both_arms_under_gp(herman):
    from gpmotion.tasks.herman_touch import LEFT_ARM, reach_site
    task = get_task("herman_touch", site="hand_l")
    assert tuple(task.controlled) == ARM + LEFT_ARM
    assert {"angle_elbow_l", "rate_shoulder_l_x"} <= set(terminal_names(task))
    right = [(-0.8, 0.3, 0.0, 1.5, 0.0, 0.0)]
    assert reach_site(herman, "hand_l", ARM, right) > 0.02                # the left hand hangs
    assert reach_site(herman, "hand_l", ARM + LEFT_ARM,
                      [r + (-0.8, -0.3, 0.0, 1.5, 0.0, 0.0) for r in right]) < 0.005
    # posture watches only the PD-held joints: moving the left arm costs nothing
    q = pose_q(herman, shoulder_l_y=-0.8, elbow_l=1.5)
    m = task.measure(_still(herman, q))
    assert m["posture"][0] < 1e-3
    assert get_task("herman_touch", site="belly").measure(_still(herman, q))["posture"][0] > 0.1


# right-arm poses on the left elbow: around the front of the trunk, and through it
AROUND = dict(shoulder_r_y=0.4, shoulder_r_z=1.0, shoulder_r_x=0.43, elbow_r=1.34, wrist_r_y=-0.39,
              wrist_r_x=0.07)
ACROSS = dict(shoulder_r_y=0.02, shoulder_r_z=1.4, shoulder_r_x=0.22, elbow_r=1.53, wrist_r_y=0.02,
              wrist_r_x=0.15)


def test_touch_v3_touches_the_left_elbow_with_the_right_arm_alone(herman):
    """v3 keeps the left arm held for a left-arm site the right arm reaches
    (RIGHT_ARM_REACHES: a pose with the forearm clear of the trunk); v2 drove both arms."""
    from gpmotion.tasks.herman_touch import LEFT_ARM, HermanTouchV3
    assert HermanTouchV3.RIGHT_ARM_REACHES == ("elbow_l",)
    assert herman.link_names[herman.site_link[herman.site_names.index("elbow_l")]] in LEFT_ARM
    assert tuple(get_task("herman_touch-v3", site="elbow_l").controlled) == ARM
    assert tuple(get_task("herman_touch-v2", site="elbow_l").controlled) == ARM + LEFT_ARM
    assert tuple(get_task("herman_touch-v3", site="hand_l").controlled) == ARM + LEFT_ARM
    v3 = get_task("herman_touch-v3", site="elbow_l")
    m = v3.measure(_still(herman, pose_q(herman, **AROUND)))
    assert m["touch_end"][0] < 0.005 and m["crossing"][0] < 0.005 and m["through"][0] == 0.0
    # a fixed target on the held body, as the nose: its recipe
    assert (v3.gp.targets, v3.params["w_rest"]) == ("angle", 1.0)
    assert (get_task("herman_touch-v3", site="knee_l").gp.targets,
            get_task("herman_touch-v2", site="elbow_l").gp.targets) == ("rate", "rate")


def test_touch_v3_counts_a_forearm_through_the_trunk(herman):
    """ACROSS touches the left elbow with the right forearm through the trunk:
    v2 judged it a success, v3 charges its through term and fails it."""
    from gpmotion.tasks._herman import CROSSING
    tr = _still(herman, pose_q(herman, **ACROSS))
    v2, v3 = (get_task(v, site="elbow_l") for v in ("herman_touch-v2", "herman_touch-v3"))
    m2, m3 = v2.measure(tr), v3.measure(tr)
    assert m2["touch_end"][0] < 0.005 and v2.success(tr, m2)[0]
    assert m3["crossing"][0] > 0.1 and not v3.success(tr, m3)[0]
    assert m3["through"][0] > m2["through"][0] > 0.0     # whole capsules, not two points
    # v2's value plus the capsules' excess over CROSSING: a motion that never
    # crosses by more than that scores as under v2
    from gpmotion.tasks._herman import limbs_overlap, limbs_through_torso as capsules
    assert m3["through"][0] == pytest.approx(
        m2["through"][0] + capsules(limbs_overlap(tr), herman, CROSSING)[0])
    # resting on the belly (within CROSSING) costs nothing
    overlap = np.full(tr.q.shape[:2], CROSSING * 0.9)
    assert capsules(overlap, herman, CROSSING)[0] == 0.0
    assert capsules(overlap + 0.02, herman, CROSSING)[0] > 1.0


def test_touch_site_measures_the_distance_to_that_site(herman):
    # v2: this IK pose lays the forearm into the trunk, which v3 refuses (its own tests above)
    task = get_task("herman_touch-v2", site="chest")
    chest = _site(herman, herman.q_default, "chest")
    angles, miss = reach(herman, "fingertip_r", chest + [0.02, 0.0, 0.0],
                         x0=[-0.8, 0.3, 0.0, 1.5, 0.0, 0.0])
    assert miss < 1e-3
    m = task.measure(_still(herman, pose_q(herman, **angles)))
    assert m["touch_end"][0] == pytest.approx(0.02, abs=1e-3) and task.success(None, m)[0]
    m = get_task("herman_touch", site="nose").measure(_still(herman, pose_q(herman, **angles)))
    assert m["touch_end"][0] > 0.3 and not get_task("herman_touch").success(None, m)[0]


def test_touch_v2_settles_by_rate_targets_polish_and_a_heavier_rest_term():
    from gpmotion.families import make_family
    v1, v2, nose = (get_task(t, site="knee_l") if t != "herman_touch_nose-v1" else get_task(t)
                    for t in ("herman_touch-v1", "herman_touch-v2", "herman_touch_nose-v1"))
    assert v2.id == "herman_touch-v2" and v1.params == {"site": "knee_l", "seconds": 1.5}
    rest = {t.id: {x.name: x.weight for x in t.terms}["rest"] for t in (v1, v2, nose)}
    assert rest == {"herman_touch-v1": pytest.approx(3.0), "herman_touch-v2": pytest.approx(9.0),
                    "herman_touch_nose-v1": pytest.approx(3.0)}      # nose: v1's scoring
    assert {x.name: x.weight for x in get_task("herman_touch", site="knee_l", w_rest=1).terms}["rest"] == \
        pytest.approx(3.0)
    assert (v1.gp.targets, v2.gp.targets, nose.gp.targets) == ("angle", "rate", "angle")
    assert make_family("gp", v2).make_search(0).config()["polish"] == 10
    assert "polish" not in make_family("gp", v1).make_search(0).config()
    # on the nose v2 is herman_touch_nose-v1 (rate targets fail there; v4 is -v3: tested below)
    v2_nose = get_task("herman_touch-v2")
    assert (v2_nose.site, v2_nose.gp.targets) == ("nose", "angle")
    assert {x.name: x.weight for x in v2_nose.terms} == {x.name: x.weight for x in nose.terms}
    assert make_family("gp", v2_nose).make_search(0).config()["polish"] == 20


@pytest.mark.parametrize("site, why", [("bogus", "unknown site"), ("hand_r", "right arm"),
                                       ("foot_l", "fingertip reaches")])
def test_touch_rejects_sites_it_cannot_touch(site, why):
    with pytest.raises(ValueError, match=why):
        get_task("herman_touch", site=site)


def test_touch_bad_site_on_the_command_line_is_one_line_exit_2(capsys):
    from gpmotion.cli import main
    code = main(["run", "herman_touch", "--param", "site=foot_l", "--generations", "1",
                 "--population", "4", "--quiet", "--no-artifacts", "--out", "/nonexistent/x"])
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "foot_l" in err[0]


def test_reach_standing_force_senses_read_the_soles_ground_forces():
    """--param forces=1: the four sole contact forces are terminals, and what the
    controller reads is the ground's force (standing still: they carry the weight)."""
    from gpmotion.controllers import schedule
    from gpmotion.tasks.herman_reach_standing import FOOT_FORCES
    plain, felt = get_task("herman_reach_standing"), get_task("herman_reach_standing", forces=1)
    assert not set(FOOT_FORCES) & set(terminal_names(plain))
    assert set(FOOT_FORCES) <= set(terminal_names(felt))
    fig = felt.figure
    tr = gpmotion.rollout(fig, felt.scene(), schedule.constant(fig.model.neutral), n_steps=500,
                          record_senses=True)
    total = sum(tr.sense(n)[0, -1] for n in FOOT_FORCES)
    assert total == pytest.approx(fig.total_mass * 9.81, rel=0.02)
    with pytest.raises(ValueError, match="forces"):
        get_task("herman_reach_standing", forces=2)


# ---------------------------------------------------------------- holding an object
def _gravity_torque(fig, q, joint):
    """Torque (N·m) of gravity about a hinge's axis on everything beyond it, at q."""
    m = fig.model
    R, P = geometry3d.link_frames(m, q)
    j = fig.link_names.index(joint)

    def beyond(k):
        while k >= 0:
            if k == j:
                return True
            k = int(m.parent[k])
        return False

    axis = R[j] @ m.axis[j]
    return sum(np.cross(P[k] + R[k] @ m.com[k] - P[j], [0.0, 0.0, -9.81 * m.mass[k]]) @ axis
               for k in range(len(m.parent)) if beyond(k))


def test_a_held_ball_adds_its_weight_times_its_lever_to_the_shoulder_torque():
    """herman_holding: a 1 kg ball welded at the right fingertip.  Holding the
    arm straight out in front, the shoulder servo's static torque balances
    gravity on the arm and ball, and the ball's share is m·g·(horizontal
    lever from the shoulder) -- the welded body joined the hand's link."""
    from gpmotion.controllers import schedule
    plain, holding = gpmotion.load_figure("herman"), gpmotion.load_figure("herman_holding")
    assert holding.total_mass == pytest.approx(plain.total_mass + 1.0)
    m = holding.model
    target = m.neutral.copy()
    a = holding.actuator_names.index("shoulder_r_y")
    target[a], target[holding.actuator_names.index("elbow_r")] = -np.pi / 2, 0.0   # arm out front
    tr = gpmotion.rollout(holding, gpmotion.make_scene(), schedule.constant(target), n_steps=4000)
    q, qd = tr.q[0, -1], tr.qd[0, -1]
    assert np.abs(qd).max() < 1e-4                                          # at rest
    servo = m.kp[a] * (target[a] - q[m.act_q[a]])                           # PD torque at rest
    assert servo + _gravity_torque(holding, q, "shoulder_r_y") == pytest.approx(0.0, abs=1e-3)
    tip = _site(holding, q, "fingertip_r")
    shoulder = _site(holding, q, "shoulder_r")
    ball = 1.0 * 9.81 * (tip[0] - shoulder[0])                              # m·g·lever, ~7.5 N·m
    assert ball > 7.0
    arm = _gravity_torque(plain, q, "shoulder_r_y")                          # same pose, no ball
    assert -servo == pytest.approx(arm + ball, rel=1e-4)


HERMAN_TASKS = ("herman_touch", "herman_touch_nose", "herman_touch_object", "herman_point",
                "herman_wave", "herman_reach_standing", "herman_grasp")


@pytest.mark.parametrize("name", HERMAN_TASKS)
def test_every_herman_task_refuses_a_forearm_through_the_trunk(name, monkeypatch):
    """The newest version of every Herman task carries TrunkCheck (without it
    forearms crossed the trunk on touch_nose, touch_object and reach_standing):
    on the ACROSS pose its ``through`` is the last unchecked version's plus the
    capsules' excess (or, where the check only judges, ``charge = False``,
    the same cost), and it fails a motion that version's own test passes."""
    from gpmotion.task import task_class
    from gpmotion.tasks._herman import CROSSING, TrunkCheck, limbs_overlap, limbs_through_torso
    new = get_task(name)
    old = next(t for t in (get_task(f"{name}-v{v}") for v in range(new.version - 1, 0, -1))
               if not isinstance(t, TrunkCheck))        # the last version without the check
    assert isinstance(new, TrunkCheck) and not isinstance(old, TrunkCheck)
    assert "trunk" in new.success_threshold and "trunk" not in old.success_threshold
    from gpmotion.controllers import schedule
    from gpmotion.sim.rollout import rollout
    fig = new.figure
    # a real rollout of the task's scene (the grasp's ball too), held at ACROSS
    base = rollout(fig, new.scene(), schedule.constant(fig.model.neutral), n_steps=new.n_steps,
                   dt=new.dt, record_every=new.record_every)
    tr = replace(base, q=np.broadcast_to(pose_q(fig, **ACROSS), base.q.shape).copy(),
                 qd=np.zeros_like(base.qd))
    m_new, m_old = new.measure(tr), old.measure(tr)
    assert m_new["crossing"][0] > 0.1
    # charged: the capsules' excess added to through; judged only: the old cost, term for term
    extra = limbs_through_torso(limbs_overlap(tr), fig, CROSSING)[0] if new.charge else 0.0
    assert m_new["through"][0] == pytest.approx(m_old["through"][0] + extra)
    if not new.charge:
        assert [(t.name, t.weight, t.phase) for t in new.terms] == \
            [(t.name, t.weight, t.phase) for t in old.terms]
        assert new.score(tr)[0][0] == old.score(tr)[0][0]
    # with the previous version's own test passed, only the check refuses it
    monkeypatch.setattr(task_class(old.id), "reached", lambda self, traj, m: np.ones(1, bool))
    assert old.reached(tr, m_old)[0] and not new.reached(tr, m_new)[0]


def _assert_same_search_with_self_contact(new, trial):
    """``new`` runs ``trial``'s search with Herman's self-contact pairs added:
    the same terms at the same effective weights and phases, goal, GP
    settings, joints, senses and step."""
    from gpmotion.tasks._herman import SELF_CONTACT

    def weights(task):
        return [(t.name, t.weight * (task.params[t.param] if t.param else 1.0), t.phase, t.doc)
                for t in task.terms]
    assert weights(new) == weights(trial)
    assert len(new.scene().selfc) == len(SELF_CONTACT) and len(trial.scene().selfc) == 0
    assert np.array_equal(new.scene().goal3, trial.scene().goal3)
    assert (new.gp, new.controlled, new.dt, new.n_steps) == (trial.gp, trial.controlled, trial.dt, trial.n_steps)


@pytest.mark.parametrize("site", ["knee_l", "elbow_l", "nose"])
def test_touch_v4_is_the_trial_its_rates_were_measured_on(site):
    """herman_touch-v4 runs the searches its rates were measured with
    (herman_touch-v3 with
    SelfContact, --param w_rest=3): the same terms at the same effective
    weights, scene (with the four contact pairs), GP settings, joints and
    senses; the sites keep v3's recipes (angle on the nose and left elbow,
    rate on the knee)."""
    v4, v3 = get_task("herman_touch", site=site), get_task("herman_touch-v3", site=site, w_rest=3.0)
    assert v4.version == 4
    _assert_same_search_with_self_contact(v4, v3)
    assert v4.gp.targets == ("rate" if site == "knee_l" else "angle")
    assert get_task("herman_touch-v3", site=site).params["w_rest"] == (3.0 if site == "knee_l" else 1.0)


def test_touch_object_v4_is_the_trial_its_target_1_rate_was_measured_on():
    """herman_touch_object-v4 on target 1 is the trial (v3 with
    SelfContact, --targets angle --search polish=20): the same terms and
    weights, the four contact pairs, angle targets, polish 20; targets 0
    and 2 are v3's search unchanged (no contact, rate targets, polish 10)."""
    from gpmotion.tasks._herman import SELF_CONTACT
    for target in (0, 1, 2):
        v4, v3 = (get_task(f"herman_touch_object-v{v}", target=target) for v in (4, 3))
        assert [(t.name, t.weight, t.phase) for t in v4.terms] == [(t.name, t.weight, t.phase) for t in v3.terms]
        assert v4.params == v3.params and np.array_equal(v4.scene().goal3, v3.scene().goal3)
        assert (v4.controlled, v4.gp.terminals, v4.dt, v4.n_steps) == (v3.controlled, v3.gp.terminals, v3.dt, v3.n_steps)
        assert len(v3.scene().selfc) == 0
        if target == 1:
            assert len(v4.scene().selfc) == len(SELF_CONTACT)
            assert (v4.gp.targets, v4.gp.defaults) == ("angle", {**v3.gp.defaults, "polish": 20})
        else:
            assert len(v4.scene().selfc) == 0
            assert (v4.gp.targets, v4.gp.defaults) == (v3.gp.targets, v3.gp.defaults)
    assert get_task("herman_touch_object", target=1).version == 4


def test_touch_nose_v3_is_the_self_contact_trial():
    """herman_touch_nose-v3 runs the search its rate was measured with:
    herman_touch-v3 on the nose with w_rest 3 and Herman's forearm and hand
    colliding with the trunk and the pelvis:
    the same terms at the same effective weights and phases, scene, GP
    settings, joints and senses."""
    new = get_task("herman_touch_nose")
    trial = get_task("herman_touch-v3", site="nose", w_rest=3.0)
    assert new.version == 3
    _assert_same_search_with_self_contact(new, trial)
    assert new.success_threshold == trial.success_threshold


def test_reach_standing_v4_is_v3_with_the_nose_recipe_and_a_travelling_object():
    """herman_reach_standing-v4 = v3 with self-contact, angle targets, polish
    20, the rest and through terms x3 (the search its 4 / 5 was
    measured with), plus the curriculum: the
    object starts at START (pelvis frame) and travels in a line to its place
    over EASE of the run; travel_start=1 keeps it in place."""
    from gpmotion.tasks.herman_reach_standing import EASE, START
    v4 = get_task("herman_reach_standing")
    v3 = get_task("herman_reach_standing-v3", w_rest=3.0)
    v3.terms = tuple(replace(t, weight=t.weight * 3.0) if t.name == "through" else t for t in v3.terms)
    assert v4.version == 4
    _assert_same_search_with_self_contact(v4, _with_recipe(v3, "angle", 20))
    m = v4.figure.model
    start = m.fixed_pos + m.fixed_rot @ np.array(START)
    place = v3.object_position()
    assert np.array_equal(v4.scene_at(0.0).goal3, start)
    assert np.array_equal(v4.scene_at(EASE[1]).goal3, place)
    mid = v4.scene_at(EASE[1] / 2).goal3
    assert np.allclose(mid, (start + place) / 2)
    still = get_task("herman_reach_standing", travel_start=1.0)
    assert np.array_equal(still.scene_at(0.0).goal3, place)


def _with_recipe(task, targets, polish):
    task.gp = replace(task.gp, targets=targets, defaults={**task.gp.defaults, "polish": polish})
    return task


def test_touch_object_measures_the_object_of_the_episodes_scene():
    """Under a curriculum the object moves: a run's distance is measured to
    the object its episode had (the staged scene), not the final place."""
    from gpmotion.controllers import schedule
    task = get_task("herman_reach_standing", seconds=0.2)
    hold = schedule.constant(task.figure.model.neutral)
    for progress in (0.0, 1.0):
        scene = task.scene_at(progress)
        tr = gpmotion.rollout(task.figure, scene, hold, n_steps=task.n_steps, dt=task.dt,
                              record_every=task.record_every)
        d = np.linalg.norm(tr.site("fingertip_r")[0, -1] - scene.goal3)
        assert task.measure(tr)["object_end"][0] == pytest.approx(d, abs=1e-12)
    assert not np.allclose(task.scene_at(0.0).goal3, task.scene_at(1.0).goal3)
