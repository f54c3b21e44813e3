"""herman_grasp: the ball on the table, the grip, and the task's score."""
import numpy as np
import pytest

from gpmotion.check import check_task
from gpmotion.controllers import schedule
from gpmotion.sim.rollout import rollout
from gpmotion.task import get_task
from gpmotion.tasks._herman import ARM, reach


def _run(task, ctrl):
    return rollout(task.figure, task.scene(), ctrl, n_steps=task.n_steps, dt=task.dt,
                   record_every=task.record_every)


def _pick_and_lift(task, lift):
    """Keyframes: hand down onto the ball (0.6 s), then up by ``lift`` (1.2 s), hold."""
    f, m = task.figure, task.figure.model
    ball = task.ball_start
    down, _ = reach(f, "fingertip_r", ball + (0.0, 0.0, 0.02))
    up, _ = reach(f, "fingertip_r", ball + (0.0, 0.0, 0.02 + lift), x0=[down[a] for a in ARM])
    T = np.tile(m.neutral, (4, 1))
    for k, sol in ((1, down), (2, up), (3, up)):
        for a, v in sol.items():
            T[k, f.actuator_names.index(a)] = v
    return schedule.keyframes(np.array([0.0, 0.6, 1.2, task.seconds]), T)


def test_herman_grasp_passes_check_task():
    check_task("herman_grasp")


def test_a_scripted_pick_and_lift_succeeds_and_a_still_arm_does_not():
    """Bring the fingertip onto the ball and raise it 14 cm: the grip closes,
    the ball rises with the hand and the task counts a success.  Holding
    still: the ball stays on the table, ungripped, and the main term is the
    hand's gap to the ball plus the lift still to do."""
    task = get_task("herman_grasp")
    tr = _run(task, _pick_and_lift(task, 0.14))
    cost, m, ok = task.score(tr)
    assert tr.obj[0, -1, 6] == 1.0 and not tr.diverged[0]
    assert 0.10 <= m["lift"][0] < 0.3            # the ball sits in the hand as gripped, not at the fingertip
    assert ok[0]
    still = _run(task, schedule.constant(task.figure.model.neutral))
    _, m, ok = task.score(still)
    assert not ok[0] and still.obj[0, -1, 6] == 0.0
    assert abs(m["lift"][0]) < 1e-3                                    # on the table
    gap = m["grasp"][0] - (task.params["lift"] + 0.02)
    assert 0.1 < gap < 0.4                                             # the hanging hand's gap


def test_a_ball_lifted_too_little_is_not_a_success():
    task = get_task("herman_grasp")
    tr = _run(task, _pick_and_lift(task, 0.0))          # down onto the ball, and stay
    _, m, ok = task.score(tr)
    assert tr.obj[0, -1, 6] == 1.0 and m["lift"][0] < 0.08 and not ok[0]


def test_grasp_lift_is_checked():
    with pytest.raises(ValueError, match="lift"):
        get_task("herman_grasp", lift=0.5)
