"""The public task contract over every registered task, and a user's plugin task."""
import textwrap

import numpy as np
import pytest

import gpmotion
from gpmotion.check import check_task
from gpmotion.plugins import load_folder
from gpmotion.task import Term, get_task, task_names


@pytest.mark.parametrize("name", task_names())
def test_every_registered_task_passes_check_task(name):
    check_task(name)


def test_a_user_task_in_one_small_file_registers_and_passes(tmp_path):
    (tmp_path / "lamp_stand_tall.py").write_text(textwrap.dedent('''
        from gpmotion.task import Task, Term, register_task

        @register_task
        class LampStandTall(Task):
            name = "lamp_stand_tall"
            figure = "lamp"
            params = {"seconds": 1.0}
            terms = (Term("low", 1.0, main=True),)

            def measure(self, traj):
                return {"low": 1.0 - traj.site("head_tip")[:, -1, 1]}
    '''))
    load_folder(tmp_path)
    assert "lamp_stand_tall" in task_names()
    check_task("lamp_stand_tall")


def test_a_broken_task_fails_the_contract():
    class Broken(gpmotion.Task):
        name = "broken_nan"
        figure = "lamp"
        params = {"seconds": 0.2}
        terms = (Term("x", 1.0, main=True),)

        def measure(self, traj):
            return {"x": np.full(traj.n_episodes, np.nan)}

    with pytest.raises(AssertionError, match="not finite"):
        check_task(Broken)


def test_phase_in_ramps_style_terms():
    t = Term("late", 0.5, phase=(0.2, 0.6))
    assert [t.factor(p) for p in (0.0, 0.2, 0.4, 0.6, 1.0)] == pytest.approx([0, 0, 0.5, 1, 1])
    task = get_task("lamp_hop", seconds=0.3)
    from gpmotion.controllers import schedule
    ctrl = schedule.constant(task.figure.model.neutral)
    tr = gpmotion.rollout(task.figure, task.scene(), ctrl, n_steps=task.n_steps)
    early, m, _ = task.score(tr, progress=0.0)
    late, _, _ = task.score(tr, progress=1.0)
    assert early[0] == pytest.approx(m["distance"][0])       # only the main goal at the start
    assert late[0] > early[0]                                 # style points arrive later


def test_limbo_pole_hits_are_penalized():
    task = get_task("lamp_limbo", seconds=0.5, pole_height=0.38, distance=0.38)
    # the pole crosses x = 0.19 at 38 cm: right through the neutral lamp's shade
    from gpmotion.controllers import schedule
    tr = gpmotion.rollout(task.figure, task.scene(), schedule.constant(task.figure.model.neutral),
                          n_steps=task.n_steps)
    cost, m, ok = task.score(tr)
    assert m["pole"][0] >= 1.0 and not ok[0]


def test_limbo_pole_comes_down_over_the_curriculum():
    from gpmotion.evaluate import InProcessEvaluator
    from gpmotion.families import make_family
    from gpmotion.search.gp import GPSearch
    task = get_task("lamp_limbo", pole_height=0.40)
    ease = task.curriculum["pole_height"]
    a, b = ease.phase
    assert task.params_at(0.0)["pole_height"] == ease.start > 0.5      # above the standing lamp
    assert task.params_at((a + b) / 2)["pole_height"] == pytest.approx((ease.start + 0.40) / 2)
    assert task.params_at(1.0) == task.params
    ev = InProcessEvaluator(task, make_family("gp", task))
    assert ev.scene(0.0).poles[0, 1] == pytest.approx(ease.start + 0.01)
    assert ev.scene(1.0).poles[0, 1] == pytest.approx(0.41)
    np.testing.assert_array_equal(ev.scene(1.0).poles, task.scene().poles)
    # a cost is reused only within one phase: the pole height is part of it
    s = GPSearch(make_family("gp", task), seed=0, population=4, generations=11)
    phases = [s.phase_of(g) for g in range(11)]
    assert phases[0] != phases[3] and phases[-1] == task.phase(1.0)
    assert len(task.phase(0.3)) == len(task.terms) + 1


def test_a_curriculum_must_name_a_numeric_parameter():
    class Bad(gpmotion.Task):
        name = "bad_curriculum"
        figure = "lamp"
        params = {"seconds": 0.2}
        terms = (Term("x", 1.0, main=True),)
        curriculum = {"height": gpmotion.Ease(1.0, (0.0, 0.5))}
    with pytest.raises(ValueError, match="curriculum names 'height'"):
        Bad()
