"""The gritz-hahn preset (the paper's terminals, functions and breeding), the
GP search's stop-on-success, and the limbo curriculum switch."""
import json

import numpy as np
import pytest

from gpmotion.cli import main
from gpmotion.evaluation import Evaluation
from gpmotion.families import make_family
from gpmotion.gp.presets import PAPER_PRIMITIVES, apply_preset
from gpmotion.search.gp import GPSearch
from gpmotion.task import get_task

PAPER_TERMS = ["px", "pz", "vx", "vz", "force_base_back", "force_base_front", "t"]
TINY = ["--param", "seconds=0.3", "--population", "8", "--generations", "2", "--quiet",
        "--no-artifacts"]


def test_preset_expands_to_the_papers_configuration():
    fam, search = apply_preset("gritz-hahn", get_task("lamp_limbo"))
    assert fam == {"primitives": list(PAPER_PRIMITIVES), "terminals": PAPER_TERMS}
    assert "ifpos" in fam["primitives"] and "iflte" not in fam["primitives"]
    assert search == {"selection": "roulette", "p_crossover": 0.9, "p_mutation": 0.0,
                      "p_creep": 0.0, "elitism": 0, "islands": 1, "stop_on_success": True}
    fam, search = apply_preset("gritz-hahn", get_task("lamp_hop"), {"primitives": ["add"]},
                               {"elitism": 2, "population": None})
    assert fam["primitives"] == ["add"] and search["elitism"] == 2     # given options win
    assert "population" not in search
    assert apply_preset(None, get_task("lamp_hop"), {"x": None}, {"elitism": 1}) == ({}, {"elitism": 1})


@pytest.mark.parametrize("name, task, family, message", [
    ("nope", "lamp_hop", "gp", "unknown GP preset 'nope'"),
    ("gritz-hahn", "herman_wave", "gp", "paper's terminal set"),
    ("gritz-hahn", "lamp_hop", "bsr-sense", "applies to --controller gp"),
])
def test_bad_presets(name, task, family, message):
    from gpmotion.families import family_class
    with pytest.raises(ValueError, match=message):
        family_class(family).apply_preset(name, task, {}, {})


def test_family_terminals_option():
    task = get_task("lamp_hop")
    fam = make_family("gp", task, **apply_preset("gritz-hahn", task)[0])
    assert list(fam.info.terminal_names) == PAPER_TERMS
    assert fam.info.primitive_names == tuple(sorted(PAPER_PRIMITIVES)) or \
        set(fam.info.primitive_names) == set(PAPER_PRIMITIVES)
    assert fam.config()["terminals"] == PAPER_TERMS
    default = make_family("gp", task)
    assert "terminals" not in default.config() and len(default.info.terminal_names) == 19
    with pytest.raises(ValueError, match="not senses"):
        make_family("gp", task, terminals=["px", "angle_knee"])


def _evaluation(success, costs):
    n = len(costs)
    return Evaluation(np.array(costs, float), np.array(success, bool), np.zeros(n, bool), {})


def test_stop_on_success_waits_for_the_final_scene_and_keeps_a_solver():
    task = get_task("lamp_limbo")                         # the pole comes down until progress 0.5
    fam = make_family("gp", task)
    s = GPSearch(fam, population=6, generations=5, seed=1, stop_on_success=True, elitism=0)
    n = len(s.ask())
    s.tell(evaluation=_evaluation([True] * n, list(range(n))))    # progress 0: the pole is high
    assert not s.done and s.generation == 1
    while s.progress < 0.5:
        n = len(s.ask())
        s.tell(evaluation=_evaluation([False] * n, [5.0] * n))
    assert task.staged(s.progress) == task.staged(1.0)
    pending = s.ask()
    costs = [1.0] * len(pending)
    costs[-1] = 3.0                                        # the solver is not the cheapest
    s.tell(evaluation=_evaluation([False] * (len(pending) - 1) + [True], costs))
    assert s.done and s.stopped and s.generation < s.generations
    assert s.best == pending[-1] and s.best_cost == 3.0
    again = GPSearch(fam, population=6, generations=5, seed=1)
    again.load_state_dict(json.loads(json.dumps(s.state_dict())))
    assert again.done and again.best == s.best and again.stop_on_success
    off = GPSearch(fam, population=6, generations=5, seed=1)          # default: never stops
    for _ in range(5):
        n = len(off.ask())
        off.tell(evaluation=_evaluation([True] * n, [1.0] * n))
    assert off.generation == 5 and not off.stopped


def test_cli_preset_expands_into_the_run_config(tmp_path, capsys):
    from gpmotion import cli
    args = cli.parser().parse_args(["run", "lamp_limbo", "--preset", "gritz-hahn", "--elitism", "2",
                                    "--param", "pole_height=0.38,0.34", "--seeds", "2"])
    cfgs = [c for c, _ in cli._run_configs(args)]
    assert len(cfgs) == 4
    for c in cfgs:
        assert c.family_options == {"primitives": list(PAPER_PRIMITIVES), "terminals": PAPER_TERMS}
        assert c.search["elitism"] == 2 and c.search["p_mutation"] == 0.0
        assert c.search["stop_on_success"] is True
    plain = cli.parser().parse_args(["run", "lamp_hop"])
    (c, _), = cli._run_configs(plain)
    assert c.family_options == {} and "stop_on_success" not in c.search
    for argv, needle in ((["--preset", "nope", *TINY], "unknown GP preset"),
                         (["--preset", "gritz-hahn", "--controller", "bsr-time", "--quiet"],
                          "controller gp")):
        capsys.readouterr()
        assert main(["run", "lamp_hop", "--out", str(tmp_path / "x"), *argv]) == 2
        assert needle in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


@pytest.mark.slow          # compiles a rollout kernel for the paper's primitive set
def test_cli_preset_runs_and_records_its_expansion(tmp_path, capsys):
    out = tmp_path / "gh"
    assert main(["run", "lamp_hop", "--preset", "gritz-hahn", "--elitism", "1", "--out", str(out),
                 *TINY]) == 0
    cfg = json.loads((out / "config.json").read_text())["run"]
    assert cfg["family_options"]["terminals"] == PAPER_TERMS
    assert cfg["search"]["p_mutation"] == 0.0 and cfg["search"]["stop_on_success"] is True
    assert cfg["search"]["elitism"] == 1                   # the explicit flag won
    best = json.loads((out / "best.json").read_text())
    used = {tok for tree in best["genome"]["trees"] for tok in tree if isinstance(tok, str)}
    assert used <= set(PAPER_TERMS) | set(PAPER_PRIMITIVES)


def test_limbo_without_curriculum_has_the_pole_at_its_height_from_the_start():
    from gpmotion.inprocess import InProcessEvaluator
    fixed = get_task("lamp_limbo", pole_height=0.38, pole_start=0.38)
    assert fixed.curriculum == {} and fixed.params_at(0.0)["pole_height"] == 0.38
    ev = InProcessEvaluator(fixed, make_family("gp", fixed))
    assert ev.scene(0.0).poles[0, 1] == pytest.approx(0.39)
    eased = get_task("lamp_limbo", pole_height=0.38)
    assert eased.params_at(0.0)["pole_height"] == 0.60 and eased.params_at(1.0)["pole_height"] == 0.38
    assert get_task("lamp_limbo", pole_start=0.7).params_at(0.0)["pole_height"] == 0.7
    with pytest.raises(ValueError, match="pole_start must be within"):
        get_task("lamp_limbo", pole_start=2.0)
