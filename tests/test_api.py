"""The Python API: short reprs, real signatures, top-level exports, saving a
DEAP individual as a controller file, run() without a directory."""
import ast
import inspect
import json
import random
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


def test_check_primitive_of_a_plugin(tmp_path):
    with pytest.raises(ValueError, match=r"unknown primitive 'hypot_api'.*load_plugins"):
        gpmotion.check_primitive("hypot_api")
    (tmp_path / "hyp.py").write_text(PLUGIN)
    (tmp_path / "gpmotion-plugin.toml").write_text('modules = ["hyp"]\n')
    gpmotion.check_primitive("hypot_api", plugins=tmp_path)
    gpmotion.check_primitive("hypot_api")            # loaded now


def test_top_level_exports_what_the_examples_use():
    for name in ("primitive", "RunConfig", "run", "load_controller", "replay_genome",
                 "make_family", "make_evaluator", "Evaluation", "make_toolbox",
                 "evaluate_population", "save_controller", "load_plugins", "read_json",
                 "get_task", "Task", "Term", "register_task", "check_primitive", "task_ids",
                 "STANDARD_PRIMITIVES"):
        assert name in gpmotion.__all__ and hasattr(gpmotion, name), name
    assert callable(gpmotion.run) and "out" in inspect.signature(gpmotion.run).parameters


def _gpmotion_uses(tree):
    """(line, what) for every import of gpmotion and every ``gpmotion.<name>`` reached."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            yield from ((node.lineno, f"import {a.name}") for a in node.names
                        if a.name.split(".")[0] == "gpmotion")
        elif isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "gpmotion":
            yield node.lineno, f"from {node.module} import " + ", ".join(a.name for a in node.names)
            if node.module == "gpmotion":
                yield from ((node.lineno, f"gpmotion.{a.name}") for a in node.names)
        elif (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
              and node.value.id == "gpmotion"):
            yield node.lineno, f"gpmotion.{node.attr}"


@pytest.mark.parametrize("path", sorted((ROOT / "examples").glob("*.py")), ids=lambda p: p.name)
def test_examples_use_only_the_top_level_api(path):
    """No ``gpmotion.<sub>`` import or attribute: what an example needs, gpmotion exports."""
    bad = []
    for line, what in _gpmotion_uses(ast.parse(path.read_text(), str(path))):
        deep = what.startswith(("import gpmotion.", "from gpmotion."))
        missing = what.startswith("gpmotion.") and what.split(".", 1)[1] not in gpmotion.__all__
        if deep or missing:
            bad.append(f"{path.name}:{line}: {what}")
    assert not bad, bad


def test_the_deep_import_check_catches_deep_imports():
    tree = ast.parse("import gpmotion.sim\nfrom gpmotion.task import Task\n"
                     "from gpmotion import (get_task,\n    run)\nimport gpmotion\ngpmotion.families.X\n")
    found = [w for _, w in _gpmotion_uses(tree)]
    assert "import gpmotion.sim" in found and "from gpmotion.task import Task" in found
    assert "gpmotion.families" in found and "gpmotion.get_task" in found


def test_the_wheel_ships_py_typed_and_every_package():
    """pyproject lists every package under gpmotion/ (a new one would not be installed)
    and ships py.typed, the shipped figures, tasks and primitives."""
    try:
        import tomllib
    except ModuleNotFoundError:
        import tomli as tomllib
    conf = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert "py.typed" in conf["package-data"]["gpmotion"] and (ROOT / "gpmotion" / "py.typed").exists()
    assert conf["package-data"]["gpmotion.figures"] == ["*.toml"]
    on_disk = {".".join(p.parent.relative_to(ROOT).parts)
               for p in (ROOT / "gpmotion").rglob("__init__.py")}
    on_disk |= {"gpmotion.primitives", "gpmotion.tasks"}
    assert on_disk <= set(conf["packages"]), sorted(on_disk - set(conf["packages"]))
    assert conf["package-dir"] == {"gpmotion": "gpmotion", "gpmotion.primitives": "primitives",
                                   "gpmotion.tasks": "tasks"}


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
