"""Robust evaluation: perturbed starts (deterministic, sized, never in the floor), batching, aggregates."""
import numpy as np
import pytest

from gpmotion import get_task, load_figure, make_scene, rollout
from gpmotion.compose import robust as R
from gpmotion.controllers import schedule
from gpmotion.families import make_family
from gpmotion.task import WORST


def starts(name="starman", k=8, seed=1, round_=0, **sizes):
    fig = load_figure(name)
    return fig, *R.perturbed_starts(fig, fig.q_default, np.zeros(fig.nv), k, R.round_rng(seed, round_),
                                    R.Perturbation(**sizes))


def test_starts_depend_on_seed_and_round_only():
    a, b, c = starts()[1], starts()[1], starts(round_=1)[1]
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)
    assert not np.allclose(a, starts(seed=2)[1])


def test_zero_sizes_give_the_nominal_start():
    fig, q, qd = starts(joint=0, position=0, orientation=0, velocity=0, angular=0)
    np.testing.assert_array_equal(q, np.tile(fig.q_default, (8, 1)))
    assert not qd.any()


def test_each_part_of_the_state_moves_by_its_own_size():
    # starman: q = [x, z, pitch, 4 joints]; only the named part of the state moves
    fig, q, qd = starts(k=4000, joint=0, position=0, velocity=0, angular=0, orientation=0.1)
    d = q - fig.q_default
    assert np.std(d[:, 2]) == pytest.approx(0.1, rel=0.05)
    assert not d[:, 3:].any() and not d[:, 0].any() and not qd.any()
    fig, q, qd = starts(k=4000, joint=0, position=0, orientation=0, velocity=0.2, angular=0.5)
    assert np.std(qd[:, :2], axis=0) == pytest.approx([0.2, 0.2], rel=0.05)
    assert np.std(qd[:, 2:], axis=0) == pytest.approx([0.5] * 5, rel=0.05)
    fig, q, qd = starts(k=4000, position=0, orientation=0, velocity=0, angular=0, joint=0.05)
    d = q - fig.q_default
    assert np.std(d[:, 3:], axis=0) == pytest.approx([0.05] * 4, rel=0.06)


def test_starts_never_sink_into_the_floor_and_respect_limits():
    fig, q, qd = starts(k=500, joint=0.8, orientation=0.5, position=0.05)
    m = fig.model
    floor = R.lowest_contact(fig, fig.q_default[None])[0]
    assert np.all(R.lowest_contact(fig, q) >= floor - 1e-12)
    joints = np.arange(3, fig.nq)
    assert np.all(q[:, joints] >= m.lo[joints]) and np.all(q[:, joints] <= m.hi[joints])


def test_3d_starts_keep_unit_quaternions_and_the_floor():
    fig, q, qd = starts("herman_standing", k=50, orientation=0.3)
    np.testing.assert_allclose(np.linalg.norm(q[:, 3:7], axis=1), 1.0)
    floor = R.lowest_contact(fig, fig.q_default[None])[0]
    assert np.all(R.lowest_contact(fig, q) >= floor - 1e-9)
    assert np.std(q[:, 4:7]) > 0.05                         # the orientation moved


def test_robust_rollout_is_controller_major_and_equals_single_runs():
    fig = load_figure("starman")
    rng = np.random.default_rng(0)
    ctrls = [schedule.constant(fig.model.neutral + 0.4 * rng.standard_normal(fig.n_act)) for _ in range(2)]
    q0s, qd0s = R.perturbed_starts(fig, fig.q_default, np.zeros(fig.nv), 3, R.round_rng(0, 0))
    tr = R.robust_rollout(fig, make_scene(), schedule.stack(ctrls), q0s, qd0s, n_steps=300)
    for n in range(2):
        for k in range(3):
            one = rollout(fig, make_scene(), ctrls[n], n_steps=300, q0=q0s[k], qd0=qd0s[k])
            np.testing.assert_array_equal(tr.q[n * 3 + k], one.q[0])


def test_aggregate_mean_and_worst():
    c = [1.0, 2.0, 6.0, 0.0, np.nan, 1.0]
    np.testing.assert_allclose(R.aggregate(c, 3, "mean"), [3.0, (WORST + 1.0) / 3])
    np.testing.assert_allclose(R.aggregate(c, 3, "worst"), [6.0, WORST])
    np.testing.assert_allclose(R.aggregate(c, 2, "worst"), [2.0, 6.0, WORST])
    with pytest.raises(ValueError, match="aggregate must be"):
        R.aggregate(c, 3, "median")
    with pytest.raises(ValueError, match="perturbation joint"):
        R.Perturbation(joint=-1)


def test_evaluate_is_deterministic_and_aggregates_k_starts():
    task = get_task("starman_travel", seconds=0.5)
    fam = make_family("bsr-time", task)
    genomes = [fam.random(np.random.default_rng(s)) for s in range(2)]
    a = R.evaluate(task, fam, genomes, k=4, seed=3, round_=5)
    b = R.evaluate(task, fam, genomes, k=4, seed=3, round_=5)
    np.testing.assert_array_equal(a[0], b[0])
    costs, *_ = task.score(a[2])
    np.testing.assert_allclose(a[0], costs.reshape(2, 4).mean(axis=1))
    worst, *_ = R.evaluate(task, fam, genomes, k=4, seed=3, round_=5, how="worst")
    np.testing.assert_allclose(worst, costs.reshape(2, 4).max(axis=1))
    assert a[2].n_episodes == 8 and np.all((a[1] >= 0) & (a[1] <= 1))


def test_robustness_table_nominal_first_and_deterministic(tmp_path, capsys):
    import json as _json

    from gpmotion.compose import robust_command
    from gpmotion.replay import load_controller, replay_genome
    from tests.test_composite import write_controller
    path = write_controller(tmp_path / "c.json", family="bsr-time", seconds=0.5, seed=4)
    task, fam, act, genome, _ = load_controller(path)
    r = R.robustness(task, fam, act, genome, trials=6, seed=1)
    _, costs, _, ok = replay_genome(task, fam, act, genome)
    assert r["nominal_cost"] == pytest.approx(float(costs[0])) and r["nominal_success"] == bool(ok[0])
    assert r["success_rate"] == np.mean(r["success"]) and len(r["costs"]) == 6
    assert r["cost_min"] <= r["cost_median"] <= r["cost_max"]
    assert R.robustness(task, fam, act, genome, trials=6, seed=1)["costs"] == r["costs"]
    assert robust_command.main([str(path), "--trials", "6", "--seed", "1", "--json",
                                "--plot", str(tmp_path / "r.png")]) == 0
    assert _json.loads(capsys.readouterr().out)["costs"] == r["costs"]
    assert (tmp_path / "r.png").stat().st_size > 1000
    assert robust_command.main([str(tmp_path / "missing.json")]) == 2
    assert robust_command.main([str(path), "--joint", "-1"]) == 2
    err = capsys.readouterr().err
    assert "perturbation joint must be" in err
