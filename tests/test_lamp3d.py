"""The 3-D lamp (lamp3d.toml) against the planar lamp and an analytic tipping
angle, and its two tasks through the public contract checks."""
import math

import numpy as np
import pytest

import gpmotion
from gpmotion.check import check_task
from gpmotion.model import make_scene
from gpmotion.tasks.lamp3d_hop import GROUND, HALF_WIDTH, base_tilt

# a hop: crouch, extend, tuck, land at neutral (shoulder, elbow, neck)
HOP = (np.array([0.0, 0.3, 0.5, 0.8, 1.5]),
       np.array([[0.35, -1.32, -1.5], [0.9, -2.4, -1.5], [0.0, -0.3, -1.0],
                 [0.35, -1.32, -1.5], [0.35, -1.32, -1.5]]))


def test_upright_3d_lamp_hops_like_the_planar_lamp():
    """Started upright, the 3-D lamp's base follows the planar lamp's in x and z
    (its corners split each planar base contact in two halves) and never leaves the plane."""
    t2 = gpmotion.simulate("lamp", 0.8, targets=HOP)
    t3 = gpmotion.simulate("lamp3d", 0.8, targets=HOP, scene=make_scene(**GROUND))
    b2, b3 = t2.base()[0], t3.base()[0]
    assert np.abs(b3[:, 0] - b2[:, 1]).max() < 2e-3          # x
    assert np.abs(b3[:, 2] - b2[:, 2]).max() < 2e-3          # z
    assert np.abs(b3[:, 1]).max() < 1e-9                     # y
    assert b2[:, 2].max() > 0.03                             # it did leave the ground


def _rolled(fig, phi):
    """q_default rolled by phi about the base's lower right edge (lamp3d_hop's start)."""
    task = gpmotion.get_task("lamp3d_hop", roll0=phi)
    return task.initial_state()[0]


@pytest.mark.parametrize("factor, tips", [(0.85, False), (1.15, True)])
def test_sideways_tipping_angle_is_the_static_one(factor, tips):
    """A lamp held at neutral and tilted on its edge falls over exactly when its
    centre of mass is beyond the edge: critical roll atan(half width / com height)."""
    fig = gpmotion.load_figure("lamp3d")
    scene = make_scene(**GROUND)
    h = gpmotion.simulate(fig, 0.001, scene=scene).com[0, 0, 2]
    critical = math.atan(HALF_WIDTH / h)
    tr = gpmotion.simulate(fig, 2.0, scene=scene, q0=_rolled(fig, factor * critical))
    assert (base_tilt(tr)[0, -1] > 1.0) == tips


@pytest.mark.parametrize("name", ["lamp3d_hop", "lamp3d_limbo"])
def test_lamp3d_tasks_pass_the_contract(name):
    check_task(name)


def test_tilted_start_rests_on_an_edge():
    """roll0 tilts the base about its right edge: those corners stay put, the others rise."""
    from gpmotion.sim import geometry3d
    task = gpmotion.get_task("lamp3d_hop", roll0=0.1)
    q, _ = task.initial_state()
    m = task.figure.model
    corners = [task.figure.contact_names.index(c) for c in ("base_back_r", "base_front_r",
                                                          "base_back_l", "base_front_l")]
    def corner_z(q):
        return geometry3d.points_fast(m, q[None, None], m.cp_link[corners], m.cp_pos[corners])[0, 0, :, 2]
    z, upright = corner_z(q), corner_z(task.figure.q_default)      # upright: 1.5 mm above the floor
    tr = gpmotion.simulate(task.figure, 0.001, scene=task.scene(), q0=q)
    assert abs(base_tilt(tr)[0, 0] - 0.1) < 1e-9
    assert np.abs(z[:2] - upright[:2]).max() < 1e-9 and (z[2:] - upright[2:]).min() > 0.015


def test_neutral_term_reads_the_joint_angles_not_the_root():
    """The free root has 7 coordinates and 6 velocities: "neutral" must index q by act_q."""
    task = gpmotion.get_task("lamp3d_hop", roll0=0.0)
    q, _ = task.initial_state()
    tr = gpmotion.simulate(task.figure, 0.05, scene=task.scene(), q0=q)
    assert task.measure(tr)["neutral"][0] < 0.01
