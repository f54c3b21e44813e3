"""Self-contact of a 3-D figure (gpmotion.sim.selfcontact3d): a plain-numpy
twin, conservation laws, and Herman's forearm kept out of his trunk."""
import numpy as np
import pytest

import gpmotion
from gpmotion.controllers import schedule
from gpmotion.sim import selfcontact3d as C
from gpmotion.sim.rollout import rollout
from tests import physics_checks as B
from tests.reference import selfcontact3d_ref as ref
from tests.reference import spatial3d_ref as sref


def _random_rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.diag(r))


def scissors():
    """A free core with two passive arms hinged beside each other about x: swung
    towards each other they meet (their capsules, 5 cm radius, 10 cm apart)."""
    arm = {"mass": 1.0, "radius": 0.05, "segment": [[0, 0, 0], [0, 0, -0.5]], "shape": "capsule"}
    hinge = {"type": "hinge", "axis": [1, 0, 0], "limits": [-3, 3], "actuated": False}
    return {"dimensions": 3, "name": "scissors",
            "root": {"type": "free", "body": "core", "position": [0, 0, 1.0]},
            "bodies": [{"name": "core", "mass": 2.0, "radius": 0.03, "segment": [[0, -0.15, 0], [0, 0.15, 0]]},
                       {"name": "a", **arm}, {"name": "b", **arm}],
            "joints": [{"name": "ja", "parent": "core", "child": "a", "offset": [0, 0.1, 0], **hinge},
                       {"name": "jb", "parent": "core", "child": "b", "offset": [0, -0.1, 0], **hinge}]}


# ---------------------------------------------------------------- the kernel
@pytest.mark.parametrize("case", range(40))
def test_closest_points_of_two_segments_match_the_twin(case):
    rng = np.random.default_rng(case)
    p1, d1, p2, d2 = rng.normal(size=(4, 3))
    if case % 5 == 1:
        d2 = -0.7 * d1                      # parallel
    if case % 5 == 2:
        d1 = np.zeros(3)                    # a point (a sphere)
    if case % 10 == 3:
        d1 = d2 = np.zeros(3)
    s, t = C.closest_params(*p1, *d1, *p2, *d2)
    s_ref, t_ref = ref.closest_params(p1, d1, p2, d2)
    dist = np.linalg.norm(p1 + s * d1 - p2 - t * d2)
    assert 0 <= s <= 1 and 0 <= t <= 1
    # parallel segments have many closest pairs: the distance is what must agree
    assert dist == pytest.approx(np.linalg.norm(p1 + s_ref * d1 - p2 - t_ref * d2), abs=1e-12)
    grid = np.linspace(0, 1, 201)
    brute = np.linalg.norm(p1 + grid[:, None, None] * d1 - p2 - grid[None, :, None] * d2, axis=-1).min()
    assert dist <= brute + 1e-12


@pytest.mark.parametrize("case", range(12))
def test_self_contact_forces_match_the_numpy_twin(case):
    """Random link frames and velocities of Herman's model, with the forearm
    and hand placed against the trunk or the fixed pelvis (link -1)."""
    rng = np.random.default_rng(case)
    fig = gpmotion.load_figure("herman")
    m = fig.model
    nl = len(m.parent)
    R = np.stack([_random_rotation(rng) for _ in range(nl)])
    pos, v = rng.normal(size=(nl, 3)), rng.normal(size=(nl, 6))
    pairs = [("forearm_r", "torso"), ("hand_r", "torso"), ("forearm_r", "pelvis"), ("hand_r", "pelvis")]
    selfc = C.self_contact_pairs(fig, pairs, k=2e4, c=40.0)
    torso = m.seg_link[fig.body_names.index("torso")]
    for body in ("forearm_r", "hand_r"):
        link = m.seg_link[fig.body_names.index(body)]
        near = m.fixed_pos if case % 2 else pos[torso]
        pos[link] = near + rng.normal(scale=0.08, size=3)
    got, want = np.zeros((nl, 6)), np.zeros((nl, 6))
    d_got = C.self_contacts(m, selfc, R, pos, v, got)
    d_want = ref.self_contacts(m, selfc, R, pos, v, want)
    assert d_got == pytest.approx(d_want, abs=1e-12)
    np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-9)
    if case < 4:
        assert d_got > 0                     # these cases really touch


def test_self_contact_pairs_and_scenes_are_checked():
    herman = gpmotion.load_figure("herman")
    with pytest.raises(ValueError, match="no body"):
        C.self_contact_pairs(herman, [("forearm_r", "belly")])
    with pytest.raises(ValueError, match="itself"):
        C.self_contact_pairs(herman, [("torso", "torso")])
    with pytest.raises(ValueError, match="planar"):
        C.self_contact_pairs(gpmotion.load_figure("lamp"), [("base", "link1")])
    with pytest.raises(ValueError, match="selfc"):
        gpmotion.make_scene(selfc=[(0.5, 1, 1e4, 10)])
    scene = gpmotion.make_scene(selfc=[(0, 99, 1e4, 10)])
    with pytest.raises(ValueError, match="segments"):
        rollout(herman, scene, schedule.constant(herman.model.neutral), n_steps=2)


# ---------------------------------------------------------------- conservation
def _scissors_run(dt, c=0.0, contact=True, seconds=0.6, k=2e4):
    fig = gpmotion.load_figure(scissors())
    qd0 = np.zeros(fig.nv)
    qd0[:6] = [0.2, -0.1, 0.3, 0.1, 0.2, -0.1]
    qd0[6:] = [-3.0, 1.0]                          # a swings towards b
    selfc = C.self_contact_pairs(fig, [("a", "b")], k=k, c=c) if contact else ()
    scene = gpmotion.make_scene(gravity=0.0, ground=False, selfc=selfc)
    tr = rollout(fig, scene, schedule.constant(np.zeros(1)), n_steps=int(round(seconds / dt)), dt=dt,
                 record_every=int(round(0.01 / dt)), qd0=qd0)
    return fig, tr


def test_the_arms_pass_through_each_other_without_self_contact_and_bounce_with_it():
    _, free = _scissors_run(1e-3, contact=False)
    _, hit = _scissors_run(1e-3)
    assert free.q[0, -1, 7] < -1.0 and free.q[0, -1, 8] > 1.0      # crossed over
    assert hit.qd[0, -1, 6] > 0 > hit.qd[0, -1, 7]                  # each swung back


def test_self_contact_conserves_momentum_to_first_order():
    def drift(dt):
        fig, tr = _scissors_run(dt, c=40.0)
        return B.momentum_drift(sref.momentum, fig.model, tr)
    B.assert_momentum_drift_is_first_order(drift, 0.01)


def test_an_undamped_self_contact_is_elastic():
    """With c = 0 the spring gives back what it stored: mechanical energy
    after the bounce is within 1 % of before at 1 ms (k = 2e4; the 4e4
    default: 2 %), and the error shrinks with the step; damping takes
    energy out."""
    def energy_change(dt, c=0.0):
        fig, tr = _scissors_run(dt, c=c)
        e = np.array([sref.energy(fig.model, 0.0, q, qd) for q, qd in zip(tr.q[0], tr.qd[0])])
        return abs(e[-1] - e[0]) / e[0]
    e1, e2 = energy_change(1e-3), energy_change(5e-4)
    assert e1 < 0.01 and e2 < 0.5 * e1
    assert energy_change(1e-3, c=40.0) > 0.2


# ---------------------------------------------------------------- Herman
ACROSS = dict(shoulder_r_y=0.02, shoulder_r_z=1.4, shoulder_r_x=0.22, elbow_r=1.53, wrist_r_y=0.02,
              wrist_r_x=0.15)          # tests/test_herman.py: the forearm through the trunk


def test_herman_servoing_his_forearm_into_the_trunk_is_stopped_at_its_surface():
    """_herman.SelfContact's pairs (the right forearm and hand against the
    trunk and the pelvis) hold a forearm servoed through the trunk outside,
    within the forearm check's 1 cm."""
    from gpmotion.tasks._herman import CROSSING, SELF_CONTACT, SelfContact, limbs_overlap, pose_q
    from gpmotion.tasks.herman_touch_object import HermanTouchObjectV3

    class Touching(SelfContact, HermanTouchObjectV3):
        pass
    assert len(Touching().scene().selfc) == len(SELF_CONTACT)
    fig = gpmotion.load_figure("herman")
    target = fig.model.neutral.copy()
    q = pose_q(fig, **ACROSS)
    for name in ACROSS:
        target[fig.actuator_names.index(name)] = q[fig.model.act_q[fig.actuator_names.index(name)]]
    pairs = C.self_contact_pairs(fig, SELF_CONTACT)
    runs = {}
    for label, selfc in (("through", ()), ("stopped", pairs)):
        runs[label] = rollout(fig, gpmotion.make_scene(selfc=selfc), schedule.constant(target),
                              n_steps=1000, dt=2e-3, record_every=5)
    assert limbs_overlap(runs["through"]).max() > 0.1
    assert limbs_overlap(runs["stopped"]).max() <= CROSSING
    assert np.isfinite(runs["stopped"].q).all()
