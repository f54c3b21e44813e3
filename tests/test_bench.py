"""`gpmotion bench`: the benchmark runs and reports what it promises (no timing assertions)."""
import json

import pytest

from gpmotion import bench

KEYS = ("steps_per_s", "steps_per_s_all_threads", "threads", "warm_start_s", "episodes", "steps",
        "cpu_count", "gp_evals_per_s", "gp_steps_per_s")


@pytest.fixture(scope="module")
def quick():
    return bench.run_bench("lamp", quick=True)


def test_quick_bench_reports_positive_numbers(quick):
    for k in KEYS:
        assert isinstance(quick[k], (int, float)) and quick[k] > 0, k
    assert quick["figure"] == "lamp" and quick["numba"] and quick["numpy"]
    assert quick["steps"] == quick["episodes"] * quick["steps_per_episode"]
    assert quick["diverged"] == 0
    assert 0 < quick["contact_frames"] <= 1      # the lamp really touches the ground
    assert quick["controller"] == "sine" and quick["tree_nodes"] is None


def test_report_and_cli(quick, capsys):
    text = bench.format_report(quick)
    assert "steps/s" in text and "lamp" in text
    assert bench.main(["--quick", "--json", "--no-gp", "--no-warm-start", "--figure", "starman"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["figure"] == "starman" and out["steps_per_s"] > 0


def test_cli_rejects_bad_input(capsys):
    assert bench.main(["--figure", "nope"]) == 2
    assert bench.main(["--episodes", "0"]) == 2
    err = capsys.readouterr().err
    assert "unknown figure" in err and "--episodes" in err


def test_gp_controller_bench(capsys):
    r = bench.run_bench("lamp", quick=True, episodes=2, seconds=0.2, repeats=1, gp=False,
                        warm_start=False, controller="gp")
    assert r["controller"] == "gp" and len(r["tree_nodes"]) == 3
    assert all(30 <= n <= 40 for n in r["tree_nodes"])
    assert r["steps_per_s"] > 0 and r["steps_per_s_all_threads"] > 0
    assert r["steps_per_episode"] == 200 and r["diverged"] == 0
    assert "GP trees in-kernel" in bench.format_report(r)
    lb = r["lazy_branches"]                                      # the same trees, lazy vs eager
    assert lb["same_targets"] and lb["steps_per_s_lazy"] > 0 and lb["steps_per_s_eager"] > 0
    assert lb["tree_evals_per_s_lazy"] > 0 and lb["tree_evals_per_s_eager"] > 0
    assert lb["conditionals"] > 0 and lb["ops_per_eval_lazy"] < lb["ops_per_eval_eager"]
    assert "lazy branches" in bench.format_report(r)
    # the same trees every time (fixed seed), and DEAP's global random state is left alone
    import random
    state = random.getstate()
    task, fam, trees = bench.bench_gp_trees()
    assert random.getstate() == state
    assert [len(t) for t in trees] == r["tree_nodes"] and bench.bench_gp_trees()[2] == trees
    for t in trees:
        fam.encode([[t] * 3])                                    # valid lamp_hop trees
    # CLI: lamp_hop-length episodes by default; other figures are refused
    assert bench.main(["--controller", "gp", "--quick", "--json", "--no-gp", "--no-warm-start",
                       "--episodes", "2"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["controller"] == "gp" and out["steps_per_episode"] == 3000
    assert bench.main(["--controller", "gp", "--figure", "starman"]) == 2
    assert "needs --figure lamp" in capsys.readouterr().err


HERMAN_KEYS = ("steps_per_s", "steps_per_s_all_threads", "threads", "episodes", "steps",
               "steps_per_episode", "tree_nodes", "gp_controlled", "gp_controller_task",
               "contact_frames", "diverged", "links", "dofs", "contacts")


def _need_herman():
    from gpmotion.figures import figure_names
    if "herman" not in figure_names():
        pytest.skip("the herman figure is not registered")


def test_herman_bench_runs_the_gp_arm(capsys):
    """``gpmotion bench --figure herman``: GP trees on the right arm by default (no timing asserts)."""
    _need_herman()
    assert bench.main(["--figure", "herman", "--quick", "--json", "--no-gp", "--no-warm-start",
                       "--episodes", "2", "--seconds", "0.05"]) == 0
    out = json.loads(capsys.readouterr().out)
    for k in HERMAN_KEYS:
        assert k in out, k
    assert out["figure"] == "herman" and out["controller"] == "gp" and out["dimensions"] == 3
    assert out["gp_controller_task"] == "herman_touch_nose"
    assert out["steps_per_s"] > 0 and out["steps_per_s_all_threads"] > 0
    assert out["steps_per_episode"] == round(0.05 / out["dt"]) and out["diverged"] == 0
    assert len(out["tree_nodes"]) == len(out["gp_controlled"]) > 0
    assert all(20 <= n <= 30 for n in out["tree_nodes"])
    assert all("_r" in a for a in out["gp_controlled"])          # the right arm only
    assert "herman_touch_nose" in bench.format_report(out)
    # the same trees every time; sines remain available for herman
    assert bench.bench_gp_trees(figure="herman")[2] == bench.bench_gp_trees(figure="herman")[2]
    r = bench.run_bench("herman", quick=True, episodes=2, seconds=0.05, repeats=1, gp=False,
                        warm_start=False, controller="sine")
    assert r["controller"] == "sine" and r["tree_nodes"] is None and r["steps_per_s"] > 0


def compare_mujoco():
    """benchmarks/compare_mujoco.py as a module (skips the test without MuJoCo)."""
    pytest.importorskip("mujoco")
    import importlib.util
    from pathlib import Path
    path = Path(__file__).resolve().parents[1] / "benchmarks" / "compare_mujoco.py"
    spec = importlib.util.spec_from_file_location("compare_mujoco_under_test", path)
    cm = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(cm)
    return cm


def test_compare_mujoco_humanoid_smoke():
    """benchmarks/compare_mujoco.py's humanoid workload and 3-D cross-check run (no timing asserts)."""
    cm = compare_mujoco()
    h = cm.compare_humanoid(episodes=2, seconds=0.05, repeats=1, threads=1)
    w = h["workload"]
    assert w["mujoco_nq"] == w["dofs"] and w["mujoco_nu"] == w["actuators"]
    assert h["ours_steps_per_s"] > 0 and h["mujoco_steps_per_s"] > 0 and h["ratio_one_thread"] > 0
    assert h["ours_diverged"] == 0
    c = cm.pendulum3d_crosscheck(seconds=0.5)
    assert c["max_angle_diff_Euler"] < 1e-9 and c["swing_amplitude"] > 0.1


def test_compare_mujoco_gp_smoke():
    """benchmarks/compare_mujoco.py's GP workload runs (tiny; no timing assertions)."""
    cm = compare_mujoco()
    g = cm.compare_lamp_gp(episodes=2, repeats=1, threads=1, py_episodes=1, seconds=0.05)
    assert g["ours_gp_steps_per_s"] > 0 and g["mujoco_gp_compile_steps_per_s"] > 0
    assert g["ratio_one_thread"] > 0 and g["workload"]["steps_per_episode"] == 50
    assert g["trees_agree_max_abs_diff"] < 1e-9        # same trees, same values in both
    assert g["senses_initial_max_abs_diff"] < 1e-9     # the loop's senses are ours
    assert g["mujoco_finite"]


def test_the_op_count_walks_fused_bytecode_as_the_kernel_runs_it():
    """Eager bytecode runs every op once, fused ops included: the Python walk
    that counts ops per evaluation must count each tree's whole length."""
    import numpy as np

    from gpmotion.gp.bytecode import HEADER, OP_ARG_SENSE0, OP_PRIM0, encode_batch
    task, fam, trees = bench.bench_gp_trees()
    b = encode_batch([trees], fam.info, fam.actuators, lazy=False)
    ci, cf = b.ci[0], b.cf[0]
    assert any(ci[p] >= OP_PRIM0 and ci[p + 1] >= OP_ARG_SENSE0
               for p in range(HEADER + 3 * len(trees), len(ci) - 1, 2)), "no fused op to count"
    senses = np.random.default_rng(0).uniform(-1, 1, 64)
    for k in range(len(trees)):
        n_ops = int(ci[HEADER + 3 * k + 2])
        assert bench._count_ops(ci, cf, k, senses, fam.info.primitives) == n_ops
