"""The 3-D simulator (gpmotion.sim.spatial3d) against the planar kernel,
analytic results, conservation laws and a plain-numpy twin."""
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import gpmotion
from gpmotion.controllers import schedule
from gpmotion.figures import SpecError, compile_spec, load_spec, planar_spec_to_3d
from gpmotion.sim import geometry3d as g3
from gpmotion.sim import spatial3d as K
from tests import physics_checks as B
from tests import figures_for_tests as F
from tests.reference import spatial3d_ref as ref

NO_GROUND = dict(ground=False)
LAMP = Path(gpmotion.__file__).parent / "figures" / "lamp.toml"


# ---------------------------------------------------------------- figures
def rod3(name, length=1.0, mass=1.0, radius=0.01, direction=(1, 0, 0)):
    d = np.asarray(direction, float)
    return {"name": name, "mass": mass, "radius": radius,
            "segment": [[0, 0, 0], list(length * d / np.linalg.norm(d))]}


def box3d(mass=2.0, half=0.2, z0=0.01, inertia=None):
    """A free box (4 bottom contact corners at z = 0 of its frame)."""
    h = half
    I = inertia or [mass * (2 * h) ** 2 / 6] * 3
    return {"dimensions": 3, "name": "box3d",
            "root": {"type": "free", "body": "b", "position": [0.0, 0.0, z0]},
            "bodies": [{"name": "b", "mass": mass, "segment": [[-h, 0, h], [h, 0, h]],
                        "com": [0, 0, h], "radius": 0.02, "inertia": I}],
            "contacts": [{"name": f"c{i}", "body": "b", "position": [sx * h, sy * h, 0.0]}
                         for i, (sx, sy) in enumerate([(-1, -1), (-1, 1), (1, -1), (1, 1)])]}


def top(inertia=(1.0, 2.0, 3.0)):
    """A single free rigid body with principal moments ``inertia`` (no contacts)."""
    return {"dimensions": 3, "name": "top", "root": {"type": "free", "body": "b"},
            "bodies": [{"name": "b", "mass": 1.0, "segment": [[0, 0, 0], [0.1, 0, 0]],
                        "com": [0, 0, 0], "inertia": list(inertia)}]}


def star3d(actuated=True):
    """A free core with two arms on euler / rotated hinge joints (no gravity tests)."""
    g = dict(kp=20.0, kd=0.5, torque_limit=50.0) if actuated else {}
    return {"dimensions": 3, "name": "star3d",
            "root": {"type": "free", "body": "core", "position": [0.3, -0.2, 1.0],
                     "rotation": [0.3, -0.2, 0.5]},
            "bodies": [dict(rod3("core", 0.4, 2.0, 0.05), com=[0.2, 0.01, 0.0]),
                       rod3("a", 0.5, 1.0, direction=(1, 0.2, 0)),
                       dict(rod3("b", 0.3, 0.7, direction=(0, 1, 1)), shape="capsule")],
            "joints": [{"name": "ja", "parent": "core", "child": "a", "offset": [0.4, 0, 0],
                        "type": "euler", "axes": "zy", "limits": [-3.0, 3.0],
                        "actuated": actuated, **g},
                       {"name": "jb", "parent": "core", "child": "b", "offset": [0.0, 0.05, 0.02],
                        "rotation": [0.4, 0.1, -0.3], "type": "hinge", "axis": [1, 0, 0],
                        "limits": [-3.0, 3.0], "actuated": actuated, **g}]}


def chain3d(n_links=3, initial=(0.3, -0.2, 0.25, 0.1, -0.3, 0.2), axes=None):
    """A hanging 3-D chain with non-parallel hinge axes (passive)."""
    axes = axes or [[0, 1, 0], [1, 0, 0], [1, 1, 0], [0, 1, 1], [1, 0, 1], [0, 1, 0]]
    bodies = [rod3("mount", 0.1)] + [rod3(f"l{i}", 0.6, 1.0, 0.03, direction=(0, 0, -1))
                                      for i in range(n_links)]
    joints = [{"name": f"j{i}", "parent": "mount" if i == 0 else f"l{i - 1}", "child": f"l{i}",
               "offset": [0, 0, 0] if i == 0 else [0, 0, -0.6], "type": "hinge", "axis": axes[i],
               "limits": [-10, 10], "actuated": False, "initial": initial[i]}
              for i in range(n_links)]
    return {"dimensions": 3, "name": f"chain3d_{n_links}",
            "root": {"type": "fixed", "body": "mount", "position": [0, 0, 3.0]},
            "bodies": bodies, "joints": joints}


def humanoid3d():
    """A ~20-dof free-floating figure with 4 foot contacts (speed and smoke tests)."""
    g = dict(kp=1000.0, kd=10.0, torque_limit=600.0)
    B = [dict(rod3("pelvis", 0.25, 10.0, 0.08, (0, 1, 0)), segment=[[0, -0.12, 0], [0, 0.12, 0]]),
         rod3("torso", 0.45, 25.0, 0.12, (0, 0, 1)), rod3("head", 0.2, 5.0, 0.1, (0, 0, 1))]
    J = [dict(name="waist", parent="pelvis", child="torso", offset=[0, 0, 0.08], type="euler",
              axes="zyx", limits=[-0.8, 0.8], **g),
         dict(name="neck", parent="torso", child="head", offset=[0, 0, 0.45], type="euler",
              axes="zy", limits=[-0.8, 0.8], **g)]
    C = []
    for side, y in (("l", 0.1), ("r", -0.1)):
        B += [rod3(f"thigh_{side}", 0.42, 7.0, 0.06, (0, 0, -1)),
              rod3(f"shin_{side}", 0.4, 3.5, 0.05, (0, 0, -1)),
              dict(rod3(f"foot_{side}", 0.3, 2.0, 0.03, (1, 0, 0)), segment=[[-0.1, 0, 0], [0.2, 0, 0]],
                   inertia=[0.01, 0.01, 0.01]),
              rod3(f"upper_arm_{side}", 0.3, 2.0, 0.04, (0, 0, -1)),
              rod3(f"fore_arm_{side}", 0.28, 1.5, 0.035, (0, 0, -1))]
        J += [dict(name=f"hip_{side}", parent="pelvis", child=f"thigh_{side}", offset=[0, y, 0],
                   type="euler", axes="zxy", limits=[-1.45, 1.45], **g),
              dict(name=f"knee_{side}", parent=f"thigh_{side}", child=f"shin_{side}",
                   offset=[0, 0, -0.42], axis=[0, 1, 0], limits=[0.0, 2.5], **g),
              dict(name=f"ankle_{side}", parent=f"shin_{side}", child=f"foot_{side}",
                   offset=[0, 0, -0.4], type="euler", axes="yx", limits=[-0.8, 0.8], **g),
              dict(name=f"shoulder_{side}", parent="torso", child=f"upper_arm_{side}",
                   offset=[0, 2 * y + np.sign(y) * 0.05, 0.4], type="euler", axes="yx",
                   limits=[-2.5, 2.5], **g),
              dict(name=f"elbow_{side}", parent=f"upper_arm_{side}", child=f"fore_arm_{side}",
                   offset=[0, 0, -0.3], axis=[0, 1, 0], limits=[-2.5, 0.0], **g)]
        C += [dict(name=f"heel_{side}", body=f"foot_{side}", position=[-0.1, 0, -0.03]),
              dict(name=f"toe_{side}", body=f"foot_{side}", position=[0.2, 0, -0.03])]
    return {"dimensions": 3, "name": "humanoid3d",
            "root": {"type": "free", "body": "pelvis", "position": [0, 0, 0.85]},
            "bodies": B, "joints": J, "contacts": C,
            "sites": [dict(name="head_top", body="head", position=[0, 0, 0.2])]}


def rollout(fig, seconds, scene=None, ctrl=None, dt=1e-3, every=10, **kw):
    fig = gpmotion.load_figure(fig)
    ctrl = ctrl or schedule.constant(fig.model.neutral if fig.n_act else [0.0])
    return fig, gpmotion.rollout(fig, scene or gpmotion.make_scene(**NO_GROUND), ctrl,
                                 n_steps=int(round(seconds / dt)), dt=dt, record_every=every, **kw)


def planar_pitch(R):
    return np.arctan2(R[..., 2, 0], R[..., 0, 0])


# ---------------------------------------------------------------- 1. planar figures
def test_planar_lamp_matches_the_planar_kernel():
    spec = load_spec(LAMP)
    f2, f3 = compile_spec(spec), compile_spec(planar_spec_to_3d(spec))
    assert f3.root == "planar" and f3.nq == f2.nq
    rng = np.random.default_rng(3)
    ctrl = schedule.sines(f2.model.neutral + rng.uniform(-0.3, 0.3, (2, 3)), 0.5,
                          rng.uniform(4, 10, (2, 3)), 0.0)
    scene = gpmotion.make_scene()
    for act in ("pd", "kinematic"):
        a = gpmotion.rollout(f2, scene, ctrl, n_steps=1000, actuation=act, record_senses=True)
        b = gpmotion.rollout(f3, scene, ctrl, n_steps=1000, actuation=act, record_senses=True)
        assert a.contact_force.max() > 1.0 and np.ptp(a.q[..., 0]) > 1e-3    # it moved on the ground
        assert np.abs(a.q - b.q).max() < 1e-6
        assert np.abs(a.contact_force - b.contact_force).max() < 1e-6 * a.contact_force.max()
        upright = np.abs(a.sense("pitch")) < 1.4       # the 3-D pitch lives in [−π/2, π/2]
        assert np.abs(a.sense("pitch") - b.sense("pitch"))[upright].max() < 1e-6
        for n in ("px", "pz", "vx", "vz", "com_z", "com_vz", "angle_elbow", "rate_neck"):
            assert np.abs(a.sense(n) - b.sense(n)).max() < 1e-6
        assert np.abs(a.sites()[..., [0, 1]] - b.sites()[..., [0, 2]]).max() < 1e-6


def test_fixed_root_chain_matches_the_planar_kernel():
    spec = F.pendulum(n_links=3, initial=0.8, actuated=True)
    f2, f3 = compile_spec(spec), compile_spec(planar_spec_to_3d(spec))
    ctrl = schedule.sines([0.2, -0.3, 0.1], 0.6, [5.0, 7.0, 3.0], 0.0)
    a = gpmotion.rollout(f2, gpmotion.make_scene(**NO_GROUND), ctrl, n_steps=1000)
    b = gpmotion.rollout(f3, gpmotion.make_scene(**NO_GROUND), ctrl, n_steps=1000)
    assert np.abs(a.q - b.q).max() < 1e-6 and np.abs(a.qd - b.qd).max() < 1e-6
    assert np.abs(a.segments()[..., [0, 1]] - b.segments()[..., [0, 2]]).max() < 1e-6


def test_free_root_lamp_matches_the_planar_kernel():
    # the free root steps ω_body and the world velocity of its origin; for a
    # motion in the x–z plane that is exactly the planar root's x, z, θ update
    spec = load_spec(LAMP)
    f2, f3 = compile_spec(spec), compile_spec(planar_spec_to_3d(spec, root="free"))
    assert (f3.nq, f3.nv) == (10, 9)
    ctrl = schedule.sines(f2.model.neutral, 0.4, [5.0, 7.0, 9.0], 0.0)
    a = gpmotion.rollout(f2, gpmotion.make_scene(), ctrl, n_steps=1000)
    b = gpmotion.rollout(f3, gpmotion.make_scene(), ctrl, n_steps=1000)
    base = b.base()
    R = g3.quat_to_rot(base[..., 3:])
    assert a.contact_force.max() > 1.0 and np.ptp(a.q[..., 2]) > 1.0     # it tumbles on the ground
    assert np.abs(a.q[..., 3:] - b.q[..., 7:]).max() < 1e-6
    assert np.abs(a.q[..., 0] - base[..., 0]).max() < 1e-6
    assert np.abs(a.q[..., 1] - base[..., 2]).max() < 1e-6
    assert np.abs(np.angle(np.exp(1j * (a.q[..., 2] - planar_pitch(R))))).max() < 1e-6
    assert np.abs(base[..., 1]).max() < 1e-12                            # stays in its plane
    assert np.abs(a.qd[..., 3:] - b.qd[..., 6:]).max() < 1e-6


# ---------------------------------------------------------------- 2. free bodies
def _momentum_drift(dt):
    fig = gpmotion.load_figure(star3d())
    qd0 = np.zeros(fig.nv)
    qd0[:6] = [0.3, -0.2, 0.5, 0.2, 0.1, -0.3]
    ctrl = schedule.sines([0.2, -0.3, 0.4], [0.8, 0.6, 0.5], [7.0, 11.0, 5.0], [0.0, 1.0, 2.0])
    _, tr = rollout(fig, 3.0, gpmotion.make_scene(gravity=0.0, ground=False), ctrl, dt=dt,
                    every=int(round(0.1 / dt)), qd0=qd0)
    assert np.abs(tr.q[0, -1, 7:] - tr.q[0, 0, 7:]).max() > 0.1       # it really moved its joints
    return B.momentum_drift(ref.momentum, fig.model, tr)


def test_free_figure_conserves_momentum_without_gravity():
    B.assert_momentum_drift_is_first_order(_momentum_drift, 0.05)


def test_free_rigid_body_keeps_momentum():
    fig = gpmotion.load_figure(top())
    qd0 = np.array([0.7, 0.4, 3.0, 0.5, -0.2, 0.1])
    _, tr = rollout(fig, 2.0, gpmotion.make_scene(gravity=0.0, ground=False), qd0=qd0)
    mom = [ref.momentum(fig.model, q, qd) for q, qd in zip(tr.q[0], tr.qd[0])]
    P = np.array([p for p, _ in mom])
    L = np.array([l_ for _, l_ in mom])
    assert np.abs(P - P[0]).max() < 1e-12 * np.linalg.norm(P[0])   # ṗ is stepped in world axes
    assert np.abs(L - L[0]).max() < 2e-3 * np.linalg.norm(L[0])
    assert np.abs(np.linalg.norm(tr.q[0, :, 3:7], axis=-1) - 1).max() < 1e-12


@pytest.mark.parametrize("axis, flips", [(0, False), (1, True), (2, False)])
def test_torque_free_top_flips_only_about_the_intermediate_axis(axis, flips):
    # Dzhanibekov: spin about the intermediate principal axis is unstable
    fig = gpmotion.load_figure(top((1.0, 2.0, 3.0)))
    qd0 = np.zeros(6)
    qd0[axis] = 5.0
    qd0[(axis + 1) % 3] = 0.01
    _, tr = rollout(fig, 10.0, gpmotion.make_scene(gravity=0.0, ground=False), qd0=qd0)
    w = tr.qd[0, :, axis]
    if flips:
        assert w.min() < -4.0                  # the spin reversed (in body coordinates)
    else:
        assert w.min() > 4.9
    # energy of rotation is conserved meanwhile
    I = np.array([1.0, 2.0, 3.0])
    e = 0.5 * (I * tr.qd[0, :, :3] ** 2).sum(-1)
    assert np.abs(e - e[0]).max() < 0.02 * e[0]       # explicit in the gyroscopic term


# ---------------------------------------------------------------- 3. energy
def _energy_drift(spec, dt, seconds=10.0):
    fig, tr = rollout(spec, seconds, dt=dt, every=int(round(0.02 / dt)))
    e = np.array([ref.energy(fig.model, 9.81, q, qd) for q, qd in zip(tr.q[0], tr.qd[0])])
    rest = ref.energy(fig.model, 9.81, np.zeros(fig.nq), np.zeros(fig.nv))   # hanging straight
    assert not tr.diverged[0]
    return np.abs(e - e[0]).max() / (e[0] - rest)


@pytest.mark.parametrize("n_links", [1, 2, 3])
def test_passive_3d_chains_conserve_energy_at_the_default_step(n_links):
    assert _energy_drift(chain3d(n_links), 1e-3) < 0.005


def test_energy_error_is_first_order_in_dt():
    spec = chain3d(2, initial=(1.2, 1.0))
    d1, d2 = _energy_drift(spec, 1e-3, 5.0), _energy_drift(spec, 5e-4, 5.0)
    assert 0.4 < d2 / d1 < 0.6


# ---------------------------------------------------------------- 4. contact
def test_box_rests_at_the_height_the_springs_predict():
    fig = gpmotion.load_figure(box3d(mass=2.0))
    _, tr = rollout(fig, 3.0, gpmotion.make_scene(k_ground=5000.0))
    sink = 2.0 * 9.81 / (4 * 5000.0)
    assert tr.q[0, -1, 2] == pytest.approx(-sink, rel=1e-3)
    assert np.abs(tr.q[0, -1, :2]).max() < 1e-9 and np.abs(tr.q[0, -1, 4:7]).max() < 1e-9
    assert np.abs(tr.qd[0, -50:]).max() < 1e-6          # no jitter at rest
    assert tr.contact_force[0, -1].sum() == pytest.approx(2.0 * 9.81, rel=1e-4)
    assert np.allclose(tr.contact_force[0, -1], 2.0 * 9.81 / 4, rtol=1e-4)


def test_sliding_box_decelerates_at_mu_g_in_any_direction():
    mu, v0 = 0.5, 2.0
    fig = gpmotion.load_figure(box3d(mass=2.0, z0=-0.001))
    d = np.array([np.cos(0.6), np.sin(0.6)])
    qd0 = np.zeros(fig.nv)
    qd0[3:5] = v0 * d
    _, tr = rollout(fig, 1.5, gpmotion.make_scene(mu=mu), every=1, qd0=qd0)
    world_v = np.einsum("...ab,...b->...a", g3.quat_to_rot(tr.q[0, :, 3:7]), tr.qd[0, :, 3:])
    speed = world_v[:, :2] @ d
    sliding = (tr.times > 0.1) & (speed > 0.3)
    slope = np.polyfit(tr.times[sliding], speed[sliding], 1)[0]
    assert slope == pytest.approx(-mu * 9.81, rel=0.02)
    stop = v0 ** 2 / (2 * mu * 9.81)
    travel = tr.q[0, -1, :2]
    assert travel @ d == pytest.approx(stop, rel=0.03)
    assert abs(travel @ np.array([-d[1], d[0]])) < 1e-3 * stop     # friction opposes the motion
    assert np.abs(world_v[-1]).max() < 1e-3                         # and then it stays put


def table3d():
    """A free box on four PD-held legs splayed in 3-D, a contact at every foot."""
    g = dict(kp=300.0, kd=3.0, torque_limit=100.0)
    legs = [(0.25, 0.15), (0.25, -0.15), (-0.25, 0.15), (-0.25, -0.15)]
    return {"dimensions": 3, "name": "table3d",
            "root": {"type": "free", "body": "top", "position": [0.0, 0.0, 0.42]},
            "bodies": [dict(rod3("top", 0.5, 5.0, 0.05), segment=[[-0.25, 0, 0], [0.25, 0, 0]],
                            com=[0, 0, 0])] +
                      [rod3(f"leg{k}", 0.4, 0.5, 0.02, direction=(0, 0, -1)) for k in range(4)],
            "joints": [dict(name=f"hip{k}", parent="top", child=f"leg{k}", offset=[x, y, 0],
                            type="euler", axes="xy", neutral=[0.2 * np.sign(y), -0.2 * np.sign(x)],
                            initial=[0.2 * np.sign(y), -0.2 * np.sign(x)], limits=[-1, 1], **g)
                       for k, (x, y) in enumerate(legs)],
            "contacts": [dict(name=f"foot{k}", body=f"leg{k}", position=[0, 0, -0.4]) for k in range(4)]}


def test_standing_figure_stays_still():
    fig = gpmotion.load_figure(table3d())
    _, tr = rollout(fig, 4.0, gpmotion.make_scene())
    assert not tr.diverged[0]
    assert np.abs(tr.qd[0, -30:]).max() < 1e-4                     # no jitter
    assert tr.contact_force[0, -1].sum() == pytest.approx(fig.total_mass * 9.81, rel=1e-3)
    assert np.allclose(tr.contact_force[0, -1], fig.total_mass * 9.81 / 4, rtol=0.02)
    feet = tr.segments()[0, -1, 1:, 1]                               # leg tips
    assert np.abs(feet[:, 2]).max() < 0.01 and np.abs(tr.q[0, -1, :2]).max() < 1e-3
    assert tr.segments().shape == (1, tr.q.shape[1], 5, 2, 3)


# ---------------------------------------------------------------- 5. servo, pendulum
def test_pendulum_period_about_a_tilted_axis():
    L, m, g = 1.0, 1.0, 9.81
    spec = {"dimensions": 3, "name": "pend3d",
            "root": {"type": "fixed", "body": "mount", "position": [0, 0, 2.0]},
            "bodies": [rod3("mount", 0.1), rod3("rod", L, m, direction=(0, 0, -1))],
            "joints": [{"name": "j", "parent": "mount", "child": "rod", "type": "hinge",
                        "axis": [1, 1, 0], "initial": 0.05, "actuated": False}]}
    fig, tr = rollout(spec, 10.0, every=1)
    theta = tr.q[0, :, 0]
    crossings = np.where(np.diff(np.sign(theta)) != 0)[0]
    tc = [tr.times[i] - theta[i] * (tr.times[i + 1] - tr.times[i]) / (theta[i + 1] - theta[i])
          for i in crossings]
    period = 2 * np.mean(np.diff(tc))
    expected = 2 * np.pi * np.sqrt((m * L ** 2 / 3) / (m * g * L / 2))
    assert abs(period - expected) / expected < 0.005


def test_pd_servo_holds_with_the_static_error_gravity_demands():
    m, L, kp = 1.0, 1.0, 50.0
    fig, tr = rollout(planar_spec_to_3d(F.pendulum(actuated=True, angle=0.0)), 6.0,
                      ctrl=schedule.constant([0.0]))
    err = -tr.q[0, -1, 0]
    assert err == pytest.approx(m * 9.81 * L / 2 * np.cos(err) / kp, rel=1e-3)
    assert np.abs(tr.qd[0, -20:]).max() < 1e-6


def test_kinematic_actuation_follows_the_tau_law():
    tau, th0 = 0.1, 0.8
    fig, tr = rollout(star3d(), 1.0, gpmotion.make_scene(gravity=0.0, ground=False),
                      ctrl=schedule.constant([th0, -th0, th0], taus=[tau] * 3),
                      every=1, actuation="kinematic")
    t = tr.times
    exact = th0 * (1 - (1 + t / tau) * np.exp(-t / tau))
    assert np.abs(tr.q[0, :, 7] - exact).max() < 0.01 * th0
    assert np.abs(tr.q[0, :, 8] + exact).max() < 0.01 * th0
    assert not tr.diverged[0]


# ---------------------------------------------------------------- 6. kernels vs numpy twin
def random_figure():
    spec = star3d()
    spec["bodies"].append(rod3("c", 0.3, 0.5, direction=(0, 0, 1)))
    spec["joints"].append({"name": "jc", "parent": "b", "child": "c", "type": "slide",
                           "axis": [0.3, 1, 0.2], "offset": [0, 0.1, 0.2], "limits": [-1, 1],
                           "kp": 5.0, "torque_limit": 5.0})
    spec["bodies"].append(rod3("d", 0.2, 0.4, direction=(1, 1, 1)))
    spec["joints"].append({"name": "jd", "parent": "a", "child": "d", "type": "euler",
                           "axes": [[1, 0, 0], [0, 1, 1], [0, 0, 1]], "offset": [0.5, 0, 0],
                           "rotation_deg": [10, 20, 30], "kp": 5.0, "torque_limit": 5.0})
    spec["contacts"] = [{"name": f"p{k}", "body": b, "position": list(np.random.default_rng(k).normal(0, 0.2, 3))}
                        for k, b in enumerate(["core", "a", "b", "c", "d", "a"])]
    return gpmotion.load_figure(spec)


def random_state(fig, rng):
    q = rng.uniform(-1.5, 1.5, fig.nq)
    quat = rng.normal(size=4)
    q[3:7] = quat / np.linalg.norm(quat)
    return q, rng.normal(0, 1.5, fig.nv)


def scratch(fig):
    nl = len(fig.model.parent)
    return dict(R=np.zeros((nl, 3, 3)), pos=np.zeros((nl, 3)), E=np.zeros((nl, 3, 3)),
                r=np.zeros((nl, 3)), v=np.zeros((nl, 6)), c=np.zeros((nl, 6)))


def test_kinematics_kernel_matches_the_reference():
    fig = random_figure()
    rng = np.random.default_rng(0)
    for _ in range(5):
        q, qd = random_state(fig, rng)
        s = scratch(fig)
        K.kinematics(fig.model, q, qd, s["R"], s["pos"], s["E"], s["r"], s["v"], s["c"])
        R, P, v = ref.frames_and_velocities(fig.model, q, qd)
        assert np.allclose(s["R"], R, atol=1e-12) and np.allclose(s["pos"], P, atol=1e-12)
        assert np.allclose(s["v"], v, atol=1e-12)
        Rn, Pn = g3.link_frames(fig.model, q)
        assert np.allclose(Rn, R, atol=1e-12) and np.allclose(Pn, P, atol=1e-12)


@pytest.mark.parametrize("prescribe", [False, True])
def test_aba_kernel_matches_rnea_crba_reference(prescribe):
    fig = random_figure()
    M = fig.model
    nl, nv = len(M.parent), fig.nv
    rng = np.random.default_rng(1 + prescribe)
    for trial in range(5):
        q, qd = random_state(fig, rng)
        tau = rng.normal(0, 2, nv)
        fext = rng.normal(0, 2, (nl, 6))
        presc = np.zeros(nv, dtype=np.int64)
        presc_qdd = rng.normal(0, 3, nv)
        if prescribe:
            presc[[7, 9, 11]] = 1
        # implicit-PD armature on the joints (not the free root), none on the last trial
        arm = np.zeros(nv)
        if trial < 4:
            arm[6:] = np.where(rng.random(nv - 6) < 0.6, rng.uniform(0.0, 0.5, nv - 6), 0.0)
        s = scratch(fig)
        K.kinematics(M, q, qd, s["R"], s["pos"], s["E"], s["r"], s["v"], s["c"])
        qdd = np.zeros(nv)
        t = tau.copy()
        K.aba(M, qd, s["E"], s["r"], s["v"], s["c"], t, fext, presc, presc_qdd, arm, 9.81,
              np.zeros((nl, 6, 6)), np.zeros((nl, 6)), np.zeros((nl, 6)), np.zeros(nl),
              np.zeros(nl), np.zeros((nl, 6)), qdd, np.zeros((3, 6, 6)), np.zeros((3, 6)))
        qdd_ref, tau_ref = ref.forward_dynamics(M, q, qd, tau, 9.81, fext, presc, presc_qdd, arm)
        assert np.allclose(qdd, qdd_ref, rtol=1e-9, atol=1e-9)
        assert np.allclose(t, tau_ref, rtol=1e-9, atol=1e-9)
        if trial == 0:      # the armature mattered
            assert (arm > 0).any() and not np.allclose(qdd, ref.forward_dynamics(
                M, q, qd, tau, 9.81, fext, presc, presc_qdd)[0], rtol=1e-6, atol=1e-6)


def test_contact_kernel_matches_the_reference():
    fig = random_figure()
    M = fig.model
    nl, nc = len(M.parent), len(M.cp_link)
    rng = np.random.default_rng(5)
    scene = gpmotion.make_scene(mu=0.6, k_ground=3000.0, c_ground=40.0, k_tangent=2000.0,
                                c_tangent=30.0)
    for trial in range(6):
        q, qd = random_state(fig, rng)
        s = scratch(fig)
        K.kinematics(M, q, qd, s["R"], s["pos"], s["E"], s["r"], s["v"], s["c"])
        R, P, v = ref.frames_and_velocities(M, q, qd)
        pts = np.array([P[L] + R[L] @ M.cp_pos[k] for k, L in enumerate(M.cp_link)])
        scene = scene._replace(ground_z=float(np.median(pts[:, 2])))
        anchor = pts[:, :2] + rng.normal(0, 0.01 * trial, (nc, 2))
        touching = rng.integers(0, 2, nc).astype(float)
        fext = np.zeros((nl, 6))
        cforce = np.zeros(nc)
        a_k, t_k = anchor.copy(), touching.copy()
        K.ground_contacts(M, scene, s["R"], s["pos"], s["v"], a_k, t_k, fext, cforce)
        fext_ref = np.zeros((nl, 6))
        for k, L in enumerate(M.cp_link):
            vel = R[L] @ (v[L, 3:] + np.cross(v[L, :3], M.cp_pos[k]))
            F_, an, to = ref.ground_point(scene.k_ground, scene.c_ground, scene.k_tangent,
                                          scene.c_tangent, scene.mu, pts[k], vel, anchor[k],
                                          touching[k], scene.ground_z)
            fext_ref[L] += ref.point_force_to_link(R[L], M.cp_pos[k], F_)
            assert cforce[k] == pytest.approx(F_[2], abs=1e-9)
            assert t_k[k] == to
            if to:
                assert np.allclose(a_k[k], an, atol=1e-12)
        assert np.allclose(fext, fext_ref, atol=1e-9)
        assert 0 < np.count_nonzero(cforce) < nc


def test_energy_kernel_matches_the_reference():
    fig = random_figure()
    q, qd = random_state(fig, np.random.default_rng(9))
    s = scratch(fig)
    K.kinematics(fig.model, q, qd, s["R"], s["pos"], s["E"], s["r"], s["v"], s["c"])
    scene = gpmotion.make_scene()
    assert K.mechanical_energy(fig.model, scene, s["R"], s["pos"], s["v"]) == pytest.approx(
        ref.energy(fig.model, 9.81, q, qd), rel=1e-12)


_NOJIT_SCRIPT = """
import json, sys, numpy as np, gpmotion
from gpmotion.figures import load_spec, planar_spec_to_3d
from gpmotion.controllers import schedule
spec = planar_spec_to_3d(load_spec(sys.argv[1]), root="free")
fig = gpmotion.load_figure(spec)
ctrl = schedule.sines(fig.model.neutral, 0.4, [5.0, 7.0, 9.0], 0.0)
tr = gpmotion.rollout(fig, gpmotion.make_scene(poles=[[0.3, 0.2, 0.05]]), ctrl, n_steps=60,
                      record_every=20, record_senses=True)
print(json.dumps({"q": tr.q.tolist(), "senses": tr.senses.tolist()}))
"""


def test_kernels_run_without_jit_and_agree(tmp_path):
    env = dict(os.environ, NUMBA_DISABLE_JIT="1", GPMOTION_CACHE=str(tmp_path))
    out = subprocess.run([sys.executable, "-c", _NOJIT_SCRIPT, str(LAMP)], env=env,
                         capture_output=True, text=True, timeout=300,
                         cwd=Path(__file__).resolve().parents[1])
    assert out.returncode == 0, out.stderr[-2000:]
    res = json.loads(out.stdout.strip().splitlines()[-1])
    fig = gpmotion.load_figure(planar_spec_to_3d(load_spec(LAMP), root="free"))
    ctrl = schedule.sines(fig.model.neutral, 0.4, [5.0, 7.0, 9.0], 0.0)
    tr = gpmotion.rollout(fig, gpmotion.make_scene(poles=[[0.3, 0.2, 0.05]]), ctrl, n_steps=60,
                          record_every=20, record_senses=True)
    assert np.allclose(tr.q, res["q"], atol=1e-10)
    assert np.allclose(tr.senses, res["senses"], atol=1e-10)


# ---------------------------------------------------------------- 7. batches
def test_a_batch_equals_its_episodes_run_alone():
    B.assert_a_batch_equals_its_episodes_run_alone(
        gpmotion.load_figure(planar_spec_to_3d(load_spec(LAMP), root="free")), 1000)


def test_divergence_flags_one_episode_and_spares_the_rest():
    B.assert_divergence_flags_one_episode_and_spares_the_rest(
        gpmotion.load_figure(planar_spec_to_3d(load_spec(LAMP), root="free")), 3)


# ---------------------------------------------------------------- spec
def test_senses_are_named_and_normalized():
    fig = gpmotion.load_figure(humanoid3d())
    assert fig.n_act == 23 and fig.nv == 29 and fig.nq == 30
    assert fig.sense_names[:3] == ["px", "py", "pz"]
    assert "angle_hip_l_z" in fig.sense_names and "force_toe_r" in fig.sense_names
    _, tr = rollout(fig, 0.2, gpmotion.make_scene(), record_senses=True)
    assert tr.senses.shape[-1] == len(fig.sense_names)
    assert tr.sense("up_z")[0, 0] == pytest.approx(1.0)
    assert tr.sense("pz")[0, 0] == pytest.approx(0.85)


@pytest.mark.parametrize("change, message", [
    (lambda s: s.update(dimensions=4), "dimensions"),
    (lambda s: s["bodies"][1].update(segment=[[0, 0], [1, 0]]), "segment"),
    (lambda s: s["joints"][0].update(axis=[0, 0, 0]), "axis"),
    (lambda s: s["joints"][0].update(type="ball"), "unknown joint type"),
    (lambda s: s["joints"][1].update(axes="zyq"), "axes"),
    (lambda s: s["joints"][1].update(limits=[[-1, 1], [-1, 1]]), "limits"),
    (lambda s: s["joints"][1].update(kp=[1.0, 2.0]), "kp"),
    (lambda s: s["joints"][1].update(limits=[[-1, 1], [-1.6, 1.6], [-1, 1]]), "gimbal lock"),
    (lambda s: s["joints"][1].update(axes=[[0, 0, 1], [0, 1, 0], [0, 0, 1]],
                                       limits=[[-1, 1], [0.05, 0.1], [-1, 1]]),
     "gimbal lock"),
    (lambda s: s["joints"][1].update(axes=[[0, 0, 1], [0, 0.01, 1]], limits=[-1, 1]), "parallel"),
    (lambda s: s["root"].update(type="planet"), "root"),
    (lambda s: s["root"].update(position=[0, 0]), "position"),
    (lambda s: s["bodies"][0].update(inertia=[1, -1, 1]), "inertia"),
])
def test_bad_3d_specs_get_one_clear_line(change, message):
    spec = star3d()
    spec["joints"][1].update(type="euler", axes="zyx", limits=[[-3, 3], [-1.2, 1.2], [-3, 3]])
    spec["joints"][1].pop("axis")
    spec["joints"][0].update(type="hinge", axis=[1, 0, 0])
    spec["joints"][0].pop("axes")
    compile_spec(spec)
    change(spec)
    with pytest.raises(SpecError, match=message):
        compile_spec(spec)


@pytest.mark.parametrize("root", ["free", "fixed"])
def test_sensed_sites_are_their_world_position_minus_the_3d_goal(root):
    spec = humanoid3d()
    spec["root"]["type"] = root
    spec["sites"] = [dict(name="head_top", body="head", position=[0, 0, 0.2], sense=True),
                     dict(name="belly", body="pelvis", position=[0.1, 0.02, 0.05], sense=True),
                     dict(name="hand_l", body="fore_arm_l", position=[0, 0, -0.28])]
    fig = gpmotion.load_figure(spec)
    names = [n for n in fig.sense_names if n.startswith("site_")]
    assert names == [f"site_{s}_{a}" for s in ("head_top", "belly") for a in ("dx", "dy", "dz")]
    k = fig.sense_index("site_head_top_dx")
    assert fig.model.sense_lo[k] == -1.0 and fig.model.sense_hi[k] == 1.0
    goal = np.array([0.3, -0.2, 0.5])
    scene = gpmotion.make_scene(goal=goal)
    assert np.array_equal(scene.goal, [0.3, 0.5]) and np.array_equal(scene.goal3, goal)
    m = fig.model
    T = np.tile(m.neutral, (2, 1))
    T[1] += 0.3
    _, tr = rollout(fig, 0.3, scene, schedule.sines(T, 0.2, 2.0, 0.0), record_senses=True)
    for s in ("head_top", "belly"):
        got = np.stack([tr.sense(f"site_{s}_{a}") for a in ("dx", "dy", "dz")], -1)
        assert np.abs(got - (tr.site(s) - goal)).max() < 1e-9
    base = g3.base_pose(m, tr.q)[..., :3]
    assert np.abs(np.stack([tr.sense(n) for n in ("px", "py", "pz")], -1) - (base - goal)).max() < 1e-9
    if root == "free":
        assert np.ptp(tr.sense("site_belly_dz")) > 1e-3        # the floating base moves


def test_a_planar_goal_is_a_3d_goal_with_y_zero():
    s = gpmotion.make_scene(goal=(1.0, 0.2))
    assert np.array_equal(s.goal, [1.0, 0.2]) and s.goal_y == 0.0
    assert np.array_equal(s.goal3, [1.0, 0.0, 0.2])
    with pytest.raises(ValueError, match="goal"):
        gpmotion.make_scene(goal=(1.0, 2.0, 3.0, 4.0))


@pytest.mark.parametrize("where, value, message", [
    ("sites", "yes", "'sense' must be true or false"),
    ("contacts", True, "only sites of 3-D figures take 'sense'"),
])
def test_site_sense_flag_is_checked(where, value, message):
    spec = humanoid3d()
    spec[where][0]["sense"] = value
    with pytest.raises(SpecError, match=message):
        gpmotion.load_figure(spec)


def _gizmo():
    from tests.test_bvh import gizmo            # a slide joint and rest rotations
    return gizmo()


@pytest.mark.parametrize("make", [humanoid3d, chain3d])
def test_trajectory_sites_and_segments_share_one_pass_and_equal_separate_ones(make):
    """A Trajectory computes sites and capsule ends in one kinematics pass
    (scores ask for both); each equals its own ``points_fast`` call exactly,
    also for a figure without sites (chain3d)."""
    from gpmotion.sim import geometry3d
    fig, tr = rollout(make(), 0.05)
    m = fig.model
    assert np.array_equal(tr.sites(), geometry3d.points_fast(m, tr.q, fig.site_link, fig.site_pos))
    seg = np.stack([geometry3d.points_fast(m, tr.q, m.seg_link, m.seg_a),
                    geometry3d.points_fast(m, tr.q, m.seg_link, m.seg_b)], axis=-2)
    assert np.array_equal(tr.segments(), seg)
    assert tr.sites().shape == tr.q.shape[:2] + (len(fig.site_link), 3)


def test_compiled_points_split_over_threads_are_one_threads(monkeypatch):
    """The frames of ``points_fast`` split over threads (chunks of a nogil kernel)
    give the points of one thread, bit for bit."""
    from gpmotion.sim import geometry3d, threads
    fig, tr = rollout(humanoid3d(), 0.05)
    m = fig.model
    monkeypatch.setattr(threads, "default_threads", lambda: 1)
    one = geometry3d.points_fast(m, tr.q, m.seg_link, m.seg_a)
    monkeypatch.setattr(threads, "default_threads", lambda: 3)     # not capped by this machine
    assert np.array_equal(geometry3d.points_fast(m, tr.q, m.seg_link, m.seg_a), one)


@pytest.mark.parametrize("make", [humanoid3d, star3d, chain3d, _gizmo, lambda: "herman"])
def test_compiled_points_match_the_numpy_kinematics(make):
    """``points_fast`` (numba, what a Trajectory's sites and segments use) is
    the numpy ``link_frames`` + ``points_world`` to rounding, also for the
    fixed root body (link −1), a free root and a slide joint."""
    from gpmotion.sim import geometry3d
    fig = gpmotion.load_figure(make())
    m = fig.model
    rng = np.random.default_rng(1)
    q = np.tile(fig.q_default, (3, 5, 1)) + rng.normal(0, 0.6, (3, 5, fig.nq))
    links = np.concatenate([m.seg_link, [-1]])
    local = np.concatenate([m.seg_a, [[0.1, -0.2, 0.3]]])
    ref = geometry3d.points_world(m, *geometry3d.link_frames(m, q), links, local)
    np.testing.assert_allclose(geometry3d.points_fast(m, q, links, local), ref, atol=1e-12)
    tr_sites = geometry3d.points_fast(m, q, fig.site_link, fig.site_pos)
    np.testing.assert_allclose(tr_sites, geometry3d.sites_world(fig, q), atol=1e-12)
