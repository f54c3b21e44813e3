"""GP rate targets (``--targets rate``): a tree's output drives its joint
target's rate of change, so a tree that is zero only at the goal settles
there exactly under gravity, where an angle target settles with the PD
servo's offset; the mode is recorded, and a record from before it existed
replays as angles."""
import numpy as np
import pytest

from gpmotion.families import make_family, recorded_options
from gpmotion.replay import replay_genome
from gpmotion.task import get_task

POSE = {"shoulder_r_y": -0.4, "shoulder_r_z": 0.6, "shoulder_r_x": 0.2, "elbow_r": 1.0,
        "wrist_r_y": 0.1, "wrist_r_x": -0.1}     # the arm out to the side, bent: loaded


def final_angles(targets, trees_of):
    task = get_task("herman_touch_nose", seconds=2.0)
    fam = make_family("gp", task, targets=targets)
    names = [task.figure.actuator_names[i] for i in fam.actuators]
    traj, *_ = replay_genome(task, fam, "pd", [trees_of(n) for n in names])
    m = task.figure.model
    return traj.q[0, -1, m.act_q[fam.actuators]], np.array([POSE[n] for n in names]), traj


def test_integral_action_removes_the_steady_state_offset_under_gravity():
    # angle mode: the target is the pose itself; PD under the arm's weight sags
    got, want, _ = final_angles("angle", lambda n: [POSE[n]])
    assert np.abs(got - want).max() > 0.01
    # rate mode: the target moves while the joint is off the pose (tree = pose - angle)
    got, want, traj = final_angles("rate", lambda n: ["sub", POSE[n], f"angle_{n}"])
    assert np.abs(got - want).max() < 1e-3
    assert np.abs(traj.qd[0, -1]).max() < 1e-2               # settled, not passing through
    # pi mode: the same angle targets as the angle mode's, the sag integrated away
    got, want, traj = final_angles("pi", lambda n: [POSE[n]])
    assert np.abs(got - want).max() < 1e-3
    assert np.abs(traj.qd[0, -1]).max() < 1e-2


def test_pi_targets_need_the_joints_angle_senses():
    from gpmotion.families.gp import target_law
    task = get_task("herman_touch_nose")
    law = target_law(task, make_family("gp", task).actuators, "pi")
    names = [task.figure.sense_names[int(a)] for a in law.a]
    assert names == [f"angle_{task.figure.actuator_names[i]}" for i in task.controlled_actuators()]


def test_rate_targets_start_at_neutral_and_hold_within_the_joint_range():
    task = get_task("herman_touch_nose", seconds=1.0)
    fam = make_family("gp", task, targets="rate")
    m = task.figure.model
    traj, *_ = replay_genome(task, fam, "pd", [[5.0]] * len(fam.actuators))   # 50 rad/s up
    acts = list(fam.actuators)
    assert np.allclose(traj.targets[0, 0, acts], m.neutral[acts])
    assert np.allclose(traj.targets[0, -1, acts], np.minimum(m.hi[m.act_dof[acts]], 1e6))
    rest = [a for a in range(m.act_dof.shape[0]) if a not in acts]
    assert np.allclose(traj.targets[0, :, rest], m.neutral[rest][:, None])   # held: neutral


def test_the_mode_is_the_task_default_recorded_and_legacy_records_mean_angles():
    task = get_task("herman_touch_nose")
    assert make_family("gp", task).options["targets"] == task.gp.targets
    assert make_family("gp", task, targets="rate").config()["targets"] == "rate"
    assert recorded_options("gp", {"family": "gp", "tau": 0.1}) == {"targets": "angle"}
    assert recorded_options("gp", {"targets": "rate"}) == {"targets": "rate"}
    assert recorded_options("gp", {}, {"targets": "rate"}) == {"targets": "rate"}
    assert recorded_options("gp", {"targets": "pi"}) == {"targets": "pi"}
    with pytest.raises(ValueError, match="unknown mode 'velocity'"):
        make_family("gp", task, targets="velocity")
    mixed = "rate,elbow_r=angle, wrist_r_y=angle"
    assert make_family("gp", task, targets=mixed).config()["targets"] == mixed


@pytest.mark.parametrize("spec, error", [
    ("rate,knee_l=angle", "GP does not control: knee_l"),
    ("rate,angle", "two modes for every joint"),
    ("rate,elbow_r=angle,elbow_r=pi", "a joint named twice"),
    ("=angle", "needs a joint"),
    ("rate,elbow_r=fast", "unknown mode 'fast'"),
    ("rate,", "unknown mode ''")])
def test_a_bad_targets_spec_is_refused_by_name(spec, error):
    with pytest.raises(ValueError, match=error):
        make_family("gp", get_task("herman_touch_nose"), targets=spec)


def test_per_joint_modes_rate_joints_settle_exactly_angle_joints_take_the_tree():
    """``rate,elbow_r=angle,...``: the shoulder's rate trees (pose - angle)
    settle on the pose under gravity; the elbow's and wrists' targets are
    their trees' constants from the first step on."""
    distal = ("elbow_r", "wrist_r_y", "wrist_r_x")
    spec = "rate," + ",".join(f"{j}=angle" for j in distal)
    got, want, traj = final_angles(spec, lambda n: [POSE[n]] if n in distal
                                   else ["sub", POSE[n], f"angle_{n}"])
    task = get_task("herman_touch_nose")
    fam = make_family("gp", task, targets=spec)
    names = [task.figure.actuator_names[i] for i in fam.actuators]
    rate = [k for k, n in enumerate(names) if n not in distal]
    assert np.abs(got[rate] - want[rate]).max() < 1e-3
    for k, n in enumerate(names):
        if n in distal:
            assert np.allclose(traj.targets[0, :, fam.actuators[k]], POSE[n])
    assert fam.banner_note() == ("trees give target rates, elbow_r: target angles, "
                                 "wrist_r_y: target angles, wrist_r_x: target angles")
