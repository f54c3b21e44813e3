"""The Python API: short reprs, real signatures, top-level exports, saving a
DEAP individual as a controller file, run() without a directory."""
import inspect
import json
import random
import re
from pathlib import Path

import pytest

import gpmotion
from gpmotion.cli import main

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("name", ["lamp", "herman"])
def test_figure_model_and_trajectory_reprs_are_short(name):
    fig = gpmotion.load_figure(name)
    traj = gpmotion.simulate(fig, 0.1)
    for obj, needle in ((fig, f"Figure('{name}'"), (fig.model, "actuators"),
                        (traj, f"Trajectory('{name}'")):
        text = repr(obj)
        assert len(text) < 200 and needle in text, text
    assert "21 actuated" not in repr(fig) and f"{fig.n_act} actuated joints" in repr(fig)


def test_check_primitive_has_a_real_signature():
    params = inspect.signature(gpmotion.check_primitive).parameters
    assert "name_or_prim" in params and "plugins" in params and "args" not in params
    assert "task" in inspect.signature(gpmotion.check_task).parameters


PLUGIN = '''import math
from gpmotion import primitive


@primitive("hypot_api", arity=2)
def hypot_api(a, b):
    return math.sqrt(a * a + b * b)
'''


def test_check_primitive_of_a_plugin(tmp_path, forget_plugins):
    with pytest.raises(ValueError, match=r"unknown primitive 'hypot_api'.*load_plugins"):
        gpmotion.check_primitive("hypot_api")
    (tmp_path / "hyp.py").write_text(PLUGIN)
    gpmotion.check_primitive("hypot_api", plugins=tmp_path)
    gpmotion.check_primitive("hypot_api")            # loaded now


def test_top_level_exports_what_the_examples_use():
    for name in ("primitive", "RunConfig", "run", "load_controller", "replay_genome",
                 "make_family", "make_evaluator", "Evaluation", "make_toolbox",
                 "evaluate_population", "save_controller", "load_plugins", "read_json",
                 "get_task", "Task", "Term", "register_task", "check_primitive"):
        assert name in gpmotion.__all__ and hasattr(gpmotion, name), name
    assert callable(gpmotion.run) and "out" in inspect.signature(gpmotion.run).parameters
    for path in sorted((ROOT / "examples").glob("*.py")):
        for line in path.read_text().splitlines():
            m = re.match(r"\s*(from|import)\s+(gpmotion[\w.]*)", line)
            assert not m or m.group(2) == "gpmotion", f"{path.name}: {line.strip()}"
    assert (ROOT / "gpmotion" / "py.typed").exists()
    assert '"py.typed"' in (ROOT / "pyproject.toml").read_text()


def test_a_deap_individual_saved_as_a_controller_replays(tmp_path, capsys):
    task = gpmotion.get_task("lamp_hop", seconds=0.3)
    toolbox = gpmotion.make_toolbox(task)
    random.seed(3)
    ind = toolbox.individual()
    cost = gpmotion.evaluate_population(toolbox, [ind], progress=1.0).costs[0]
    path = tmp_path / "mine.json"
    rec = gpmotion.save_controller(path, task, ind, family=toolbox.family)
    assert rec["final_cost"] == pytest.approx(cost, abs=0, rel=0)
    capsys.readouterr()
    assert main(["replay", str(path), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["cost"] == float(cost)
    t2, fam, act, genome, _ = gpmotion.load_controller(path)
    assert len(genome) == len(ind) and act == "pd"
    with pytest.raises(ValueError, match="trees"):
        gpmotion.save_controller(tmp_path / "bad.json", task, ind[:2], family=toolbox.family)


def test_run_without_a_directory_uses_runs_task_family_seed(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    cfg = gpmotion.RunConfig(task="lamp_hop", seed=4, params={"seconds": 0.3},
                             search={"population": 8, "generations": 1})
    best, cost, rd = gpmotion.run(cfg, quiet=True, artifacts=False)
    assert rd.path.resolve() == (tmp_path / "runs" / "lamp_hop-gp-seed4").resolve()
    assert (rd.path / "best.json").exists()
