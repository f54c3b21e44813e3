"""The free object and its grip (gpmotion.sim.grip3d): a plain-numpy twin,
analytic results and conservation laws."""
import numpy as np
import pytest

import gpmotion
from gpmotion.controllers import schedule
from gpmotion.sim import grip3d as G
from gpmotion.sim.rollout import rollout
from tests.reference import grip3d_ref as ref

FAR = dict(table_x=(-10.0, 10.0), table_y=(-10.0, 10.0))


def block(mass=2.0, half=0.1):
    """A free rigid capsule along x (mass 2 kg, com at its middle): the gripping body."""
    I = [0.002, mass * (2 * half) ** 2 / 12, mass * (2 * half) ** 2 / 12]
    return {"dimensions": 3, "name": "block", "root": {"type": "free", "body": "b"},
            "bodies": [{"name": "b", "mass": mass, "segment": [[-half, 0, 0], [half, 0, 0]],
                        "com": [0, 0, 0], "radius": 0.02, "inertia": I, "shape": "capsule"}]}


def obj_for(fig, body, position, mass=0.5, radius=0.03, table_z=-5.0, **kw):
    m = fig.model
    i = fig.body_names.index(body)
    return G.object_params(mass=mass, radius=radius, position=position, table_z=table_z,
                           **{**FAR, **kw}, link=int(m.seg_link[i]), a=m.seg_a[i], b=m.seg_b[i],
                           grip_radius=float(m.seg_r[i]))


def run(fig, scene, seconds, dt=1e-3, qd0=None, ctrl=None, every=1):
    ctrl = ctrl or schedule.constant(fig.model.neutral if fig.n_act else np.zeros(1))
    return rollout(fig, scene, ctrl, n_steps=int(round(seconds / dt)), dt=dt, record_every=every,
                   qd0=qd0)


def momentum(fig, tr, obj_mass):
    """Total linear momentum [F, 3] of figure (com velocity × mass) and object."""
    return fig.total_mass * tr.com[0, :, 3:6] + obj_mass * tr.obj[0, :, 3:6]


# ---------------------------------------------------------------- the kernel
def _random_rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.diag(r))


@pytest.mark.parametrize("case", range(12))
def test_object_step_matches_the_numpy_twin(case):
    """Random link frames and object states: free flight, on the table,
    sliding on the ground, the grip closing and a held object."""
    rng = np.random.default_rng(case)
    nl, link = 4, 2
    R = np.stack([_random_rotation(rng) for _ in range(nl)])
    pos, v = rng.normal(size=(nl, 3)), rng.normal(size=(nl, 6))
    a, b = np.array([0.0, 0.0, 0.0]), np.array([0.0, 0.0, -0.2])
    hand = pos[link] + R[link] @ np.array([0.0, 0.04, -0.1])       # 4 cm off the segment
    near = case % 3 == 0
    x = hand if near else pos[link] + rng.normal(size=3)
    obj = G.object_params(mass=0.3, radius=0.03, position=x, table_z=x[2] - 0.028 + 0.01 * (case % 2),
                          table_x=(x[0] - 1, x[0] + 1), table_y=(x[1] - 1, x[1] + 1), link=link,
                          a=a, b=b, grip_radius=0.02)
    ob = np.zeros(G.N_OB)
    ob[G.OB_X:G.OB_X + 3] = x
    ob[G.OB_V:G.OB_V + 3] = rng.normal(size=3)
    if case % 4 == 1:                                             # already held
        ob[G.OB_GRIPPED] = 1.0
        ob[G.OB_ANCHOR:G.OB_ANCHOR + 3] = rng.normal(scale=0.05, size=3)
    fext0 = rng.normal(size=(nl, 6))
    got_ob, got_f = ob.copy(), fext0.copy()
    want_ob, want_f = ob.copy(), fext0.copy()
    ground = case % 2
    G.object_step(obj, 9.81, ground, x[2] - 0.02, R, pos, v, got_f, got_ob, 2e-3)
    ref.object_step(obj, 9.81, ground, x[2] - 0.02, R, pos, v, want_f, want_ob, 2e-3)
    np.testing.assert_allclose(got_ob, want_ob, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(got_f, want_f, rtol=1e-12, atol=1e-12)
    if near:
        assert got_ob[G.OB_GRIPPED] == 1.0                        # touching: the grip closed


def test_object_params_are_checked():
    kw = dict(mass=0.2, radius=0.03, position=(0, 0, 1), table_z=0.5, table_x=(0, 1),
              table_y=(0, 1), link=0, a=(0, 0, 0), b=(0, 0, -1), grip_radius=0.02)
    G.object_params(**kw)
    for bad, msg in ((dict(mass=0.0), "mass"), (dict(table_x=(1, 0)), "footprint"),
                     (dict(link=-1), "link"), (dict(radius=np.nan), "finite")):
        with pytest.raises(ValueError, match=msg):
            G.object_params(**{**kw, **bad})
    with pytest.raises(ValueError, match="obj must be"):
        gpmotion.make_scene(obj=[1.0, 2.0])


def test_an_object_needs_a_3d_figure():
    lamp = gpmotion.load_figure("lamp")
    obj = G.object_params(mass=0.2, radius=0.03, position=(0, 0, 1), table_z=0.5, table_x=(0, 1),
                          table_y=(0, 1), link=0, a=(0, 0, 0), b=(0, 0, -1), grip_radius=0.02)
    with pytest.raises(ValueError, match="3-D figure"):
        run(lamp, gpmotion.make_scene(obj=obj), 0.01)


# ---------------------------------------------------------------- analytic results
def test_object_rests_on_the_table_at_its_spring_sag_and_falls_at_g_off_it():
    """On the table: centre at top + r - m*g/k, at rest, not gripped (the
    block floats far below, falling).  Past the table's edge: free fall,
    z_n = z0 - g*dt^2*n(n+1)/2 (semi-implicit Euler's exact sequence)."""
    fig = gpmotion.load_figure(block())
    table = dict(mass=0.2, table_z=1.0, table_x=(-0.5, 0.5), table_y=(-0.5, 0.5))
    scene = gpmotion.make_scene(ground=False, obj=obj_for(fig, "b", (0.0, 0.0, 1.03), **table))
    tr = run(fig, scene, 2.0)
    assert tr.obj[0, -1, 2] == pytest.approx(1.0 + 0.03 - 0.2 * 9.81 / 2e4, abs=1e-6)
    assert np.abs(tr.obj[0, -200:, 3:6]).max() < 1e-6 and tr.obj[0, -1, 6] == 0.0
    off = scene._replace(obj=obj_for(fig, "b", (0.7, 0.0, 1.03), **table))
    tr = run(fig, off, 0.3)
    n = np.arange(tr.obj.shape[1])
    np.testing.assert_allclose(tr.obj[0, :, 2], 1.03 - 9.81 * 1e-6 * n * (n + 1) / 2, atol=1e-12)


# ---------------------------------------------------------------- conservation laws
def test_the_weld_forming_conserves_momentum_and_ends_as_a_plastic_collision():
    """Zero gravity: a free 2 kg block moving at 1 m/s runs into a floating
    0.5 kg object, straight at the block's centre.  The grip closes on
    contact; the total momentum stays M*v0 at every step, and the two end
    moving together at M*v0/(M + m) (a perfectly plastic collision), the
    block not spinning."""
    fig = gpmotion.load_figure(block())
    m, M, v0 = 0.5, fig.total_mass, 1.0
    scene = gpmotion.make_scene(gravity=0.0, ground=False, obj=obj_for(fig, "b", (0.0, 0.0, 0.2), mass=m))
    tr = run(fig, scene, 1.0, qd0=[0, 0, 0, 0, 0, v0])
    P = momentum(fig, tr, m)
    np.testing.assert_allclose(P, np.broadcast_to([0.0, 0.0, M * v0], P.shape), atol=1e-9)
    assert tr.obj[0, 0, 6] == 0.0 and tr.obj[0, -1, 6] == 1.0
    common = M * v0 / (M + m)
    assert tr.obj[0, -1, 5] == pytest.approx(common, abs=1e-6)
    assert tr.com[0, -1, 5] == pytest.approx(common, abs=1e-6)
    assert np.abs(tr.qd[0, -1, :3]).max() < 1e-9                   # no spin


def test_a_spinning_body_and_the_object_it_holds_fall_together_at_g():
    """Gravity, no ground: the block, spinning, holds the object at one end
    (the grip closes at the first step).  Internal grip forces cancel, so the
    total momentum falls at exactly (M + m)*g, and the grip keeps the object
    within a millimetre of where it was gripped on the block (once the start's
    transient has died away)."""
    fig = gpmotion.load_figure(block())
    m, M, g = 0.5, fig.total_mass, 9.81
    scene = gpmotion.make_scene(ground=False, obj=obj_for(fig, "b", (0.1, 0.0, 0.045), mass=m))
    qd0 = [0.5, 1.0, 4.0, 0.3, 0.0, 0.2]
    tr = run(fig, scene, 1.0, qd0=qd0)
    P = momentum(fig, tr, m)
    t = tr.times[:, None]
    np.testing.assert_allclose(P, P[0] - (M + m) * g * t * np.array([0.0, 0.0, 1.0]), atol=1e-9)
    assert tr.obj[0, 0, 6] == 0.0 and tr.obj[0, 1, 6] == 1.0      # frame 0 is before the first step
    # the gripped point, carried by the block: the object's centre at the start, in block coordinates
    R, P0 = tr.backend.world_frames(fig.model, tr.q[0])
    anchor = R[0, 0].T @ (tr.obj[0, 0, :3] - P0[0, 0])
    held = P0[:, 0] + np.einsum("fij,j->fi", R[:, 0], anchor)
    # the object starts at rest on a moving point: a transient of ~v/ω = 6 mm, gone by 0.3 s
    assert np.linalg.norm(tr.obj[0, 300:, :3] - held[300:], axis=-1).max() < 1e-3
    assert np.abs(tr.qd[0, -1, :3]).max() > 1.0                     # it did spin


def test_herman_holds_an_object_and_its_weight_loads_the_shoulder():
    """Herman with the right arm out in front and a 1 kg object gripped at the
    hand: after settling, the object hangs a fraction of a millimetre
    (m*g/k_grip) below where it was gripped, and the shoulder servo's static
    torque is the arm's own gravity torque plus m*g*(horizontal lever of the
    object from the shoulder)."""
    from tests.test_herman import _gravity_torque, _site
    fig = gpmotion.load_figure("herman")
    mdl = fig.model
    target = mdl.neutral.copy()
    a = fig.actuator_names.index("shoulder_r_y")
    target[a], target[fig.actuator_names.index("elbow_r")] = -np.pi / 2, 0.0
    settle = run(fig, gpmotion.make_scene(ground=False), 4.0, ctrl=schedule.constant(target), every=100)
    q_arm = settle.q[0, -1]
    hand = _site(fig, q_arm, "hand_r")
    scene = gpmotion.make_scene(ground=False, obj=obj_for(fig, "hand_r", hand, mass=1.0))
    tr = rollout(fig, scene, schedule.constant(target), n_steps=4000, dt=1e-3, record_every=100,
                 q0=q_arm)
    q, qd = tr.q[0, -1], tr.qd[0, -1]
    assert tr.obj[0, -1, 6] == 1.0 and np.abs(qd).max() < 1e-4
    servo = mdl.kp[a] * (target[a] - q[mdl.act_q[a]])
    shoulder, held = _site(fig, q, "shoulder_r"), tr.obj[0, -1, :3]
    weight = 1.0 * 9.81 * (held[0] - shoulder[0])                  # m*g*lever, ~5 N*m
    assert weight > 4.0
    assert -servo == pytest.approx(_gravity_torque(fig, q, "shoulder_r_y") + weight, rel=1e-3)
    assert np.linalg.norm(held - _site(fig, q, "hand_r")) < 1e-2
