"""The public task contract over every registered task (every version), a user's plugin
task, versioned ids and the old spellings."""
import json
import re
import textwrap

import numpy as np
import pytest

import gpmotion
from gpmotion.check import check_task
from gpmotion.families import make_family
from gpmotion.plugins import load_folder
from gpmotion.task import Term, get_task, task_ids, task_names


@pytest.mark.parametrize("name", task_ids())
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


def lamp_task(label, **attrs):
    """An unregistered short lamp task named ``label`` with one main term "x"
    (``attrs`` override any class attribute, the name too)."""
    return type(label, (gpmotion.Task,), {"name": label, "figure": "lamp", "params": {"seconds": 0.2},
                                          "terms": (Term("x", 1.0, main=True),), **attrs})


def test_a_broken_task_fails_the_contract():
    broken = lamp_task("broken_nan", measure=lambda self, traj: {"x": np.full(traj.n_episodes, np.nan)})
    with pytest.raises(AssertionError, match="not finite"):
        check_task(broken)


def test_a_weight_named_by_a_parameter_is_resolved_per_instance():
    scaled = Term("x", -2.0, main=True, param="w_x")
    cls = lamp_task("weighted", params={"seconds": 0.2, "w_x": 0.5}, terms=(scaled,))
    assert [t.weight for t in cls().terms] == [-1.0]
    assert [t.weight for t in cls(w_x=3.0).terms] == [-6.0]
    assert cls.terms == (scaled,)                   # the class keeps the declaration


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
    from gpmotion.inprocess import InProcessEvaluator
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
    bad = lamp_task("bad_curriculum", curriculum={"height": gpmotion.Ease(1.0, (0.0, 0.5))})
    with pytest.raises(ValueError, match="curriculum names 'height'"):
        bad()


# ---- versioned ids ---------------------------------------------------------------

OLD_RUN = __import__("pathlib").Path(__file__).parent / "data" / "old_run_lamp_hop"

V2 = '''
from gpmotion.tasks.lamp_hop import LampHop
from gpmotion.task import register_task


@register_task
class LampHopV2(LampHop):
    version = 2
    params = {**LampHop.params, "distance": 0.5}
'''


def test_task_ids_are_versioned_and_the_bare_name_is_the_newest(tmp_path):
    from gpmotion import plugins
    from gpmotion.task import task_id, task_ids
    assert get_task("lamp_hop").id == "lamp_hop-v1" == get_task("lamp_hop-v1").id
    assert all(re.fullmatch(r"[a-z][a-z0-9_]*-v[0-9]+", t) for t in task_ids())
    assert {t.rsplit("-v", 1)[0] for t in task_ids()} == set(task_names())
    (tmp_path / "lamp_hop_v2_test.py").write_text(V2)
    (tmp_path / plugins.MANIFEST).write_text('modules = ["lamp_hop_v2_test"]\n')
    plugins.load_folder(tmp_path)
    try:
        assert get_task("lamp_hop").id == "lamp_hop-v2" and get_task("lamp_hop").params["distance"] == 0.5
        assert get_task("lamp_hop-v1").params["distance"] == 0.4      # the published score stays
        assert task_id("lamp_hop", recorded=True) == "lamp_hop-v1"    # a pre-version record
        assert "lamp_hop" in task_names() and "lamp_hop-v2" in task_ids()
    finally:
        from gpmotion import task as task_module
        task_module._TASKS.pop("lamp_hop-v2")
    with pytest.raises(KeyError, match="no version v7; known: lamp_hop-v1"):
        get_task("lamp_hop-v7")
    with pytest.raises(KeyError, match="did you mean 'lamp_hop'"):
        get_task("lamp_hopp")


def test_a_run_records_the_versioned_id(tmp_path):
    out = tmp_path / "run"
    cfg = gpmotion.RunConfig(task="lamp_hop", seed=1, params={"seconds": 0.3},
                             search={"population": 6, "generations": 1})
    gpmotion.run(cfg, out, quiet=True, artifacts=False)
    best = json.loads((out / "best.json").read_text())
    config = json.loads((out / "config.json").read_text())
    assert best["task"] == config["run"]["task"] == config["task_config"]["task"] == "lamp_hop-v1"
    from gpmotion.cli import main
    assert main(["run", "lamp_hop", "--seed", "1", "--param", "seconds=0.3", "--resume",
                 "--out", str(out), "--quiet"]) == 0                  # the bare name resumes it


def test_a_run_recorded_before_versioned_ids_replays_and_resumes(tmp_path, capsys):
    """tests/data/old_run_lamp_hop: made by the code before ids (bare 'lamp_hop' everywhere)."""
    import shutil

    from gpmotion.cli import main
    run = tmp_path / "old"
    shutil.copytree(OLD_RUN, run)
    assert json.loads((run / "best.json").read_text())["task"] == "lamp_hop"
    capsys.readouterr()
    assert main(["replay", str(run), "--json"]) == 0
    replayed = json.loads(capsys.readouterr().out)
    assert replayed["cost"] == json.loads((run / "best.json").read_text())["final_cost"]
    assert main(["resume", str(run), "--extend-generations", "1", "--quiet"]) == 0
    assert json.loads((run / "best.json").read_text())["task"] == "lamp_hop-v1"


def test_old_spellings_warn_and_still_work():
    task = get_task("lamp_hop", seconds=0.3)
    with pytest.warns(DeprecationWarning, match="task.params"):
        assert task.p is task.params
    with pytest.warns(DeprecationWarning, match="task.figure"):
        assert task.fig is task.figure


def test_each_task_owns_its_figure():
    """load_figure copies: one task changing its figure changes no other task's."""
    a, b = get_task("lamp_hop"), get_task("lamp_hop")
    assert a.figure is not b.figure and a.figure.model is not b.figure.model
    a.figure.q_default[:] = 99.0
    assert not np.any(b.figure.q_default == 99.0)
    assert not np.any(gpmotion.load_figure("lamp").q_default == 99.0)


@pytest.mark.parametrize("attrs, message", [
    ({"name": "lamp_x-v2"}, "must be an identifier"),
    ({"version": 0}, "version must be an integer >= 1"),
    ({"version": True}, "version must be an integer"),
    ({"terms": (Term("x", 1.0, main=True, param="w_x"),)}, r"unknown parameter\(s\) \['w_x'\]"),
])
def test_register_task_rejects_bad_declarations(attrs, message):
    from gpmotion.task import register_task
    cls = lamp_task("bad_decl", **attrs)
    with pytest.raises(ValueError, match=message):
        register_task(cls)


@pytest.mark.parametrize("kwargs, message", [
    ({"primitives": "add"}, "primitives: a tuple of names"),
    ({"primitives": ()}, "primitives: name at least one primitive"),
    ({"terminals": ("px", 3)}, "terminals: a tuple of names"),
    ({"targets": "velocity"}, "targets: .*unknown mode 'velocity'"),
    ({"targets": 3}, "targets: GP targets must be a mode"),
    ({"defaults": ["population"]}, "defaults: a dict of search settings"),
])
def test_gp_settings_refuse_bad_declarations_where_the_task_is_defined(kwargs, message):
    with pytest.raises(ValueError, match=message):
        gpmotion.GPSettings(**kwargs)


def test_the_task_layer_holds_nothing_of_gp():
    """GP's function set, terminals, targets and defaults are GP's: a Task has
    none of them, and a task still declaring one the old way is told the new
    spelling when GP reads it (BSR never reads them)."""
    assert not [k for k in ("primitives", "terminals", "gp_targets", "gp_defaults", "paper_terminals",
                            "terminal_names") if hasattr(gpmotion.Task, k)]
    old = lamp_task("old_spelling", gp_defaults={"population": 50},
                    measure=lambda self, traj: {"x": np.zeros(traj.n_episodes)})
    with pytest.raises(ValueError, match=r"gp_defaults belong to GP's settings: declare "
                                         r"gp = GPSettings\(defaults=\.\.\.\)"):
        make_family("gp", old())
    make_family("bsr-time", old())


def test_a_task_naming_an_unknown_primitive_fails_the_contract():
    unknown = lamp_task("unknown_prim", gp=gpmotion.GPSettings(primitives=gpmotion.STANDARD_PRIMITIVES + ("no_such_primitive",)),
                        measure=lambda self, traj: {"x": np.zeros(traj.n_episodes)})
    with pytest.raises(AssertionError, match="unknown primitive 'no_such_primitive'"):
        check_task(unknown)
