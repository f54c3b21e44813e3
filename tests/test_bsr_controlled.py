"""BSR drives exactly a task's controlled actuators, as GP does."""
import numpy as np
import pytest

from gpmotion.inprocess import InProcessEvaluator
from gpmotion.families import make_family
from gpmotion.search.gp import GPSearch
from gpmotion.task import get_task


@pytest.fixture(scope="module")
def task():
    return get_task("herman_point", seconds=0.1)


def _genomes(task, rng):
    gp_fam = make_family("gp", task)
    gp_genome = GPSearch(gp_fam, population=4, generations=1, migrants=0, seed=0).population[0]
    out = {"gp": (gp_fam, gp_genome)}
    for name in ("bsr-time", "bsr-sense"):
        fam = make_family(name, task)
        out[name] = (fam, fam.random(rng))
    return out


def test_bsr_genome_has_parameters_for_the_driven_joints_only(task):
    driven = task.controlled_actuators()
    assert len(driven) == 6 < task.figure.n_act
    rng = np.random.default_rng(0)
    for name, rules in (("bsr-time", 4), ("bsr-sense", 8)):
        fam = make_family(name, task)
        g = fam.random(rng)
        assert g.theta0.shape == (rules, 6) and g.limits.shape == (6, 2)
        assert np.array_equal(g.limits, task.figure.actuator_limits()[driven])
        assert fam.from_json(fam.to_json(g)).n_act == 6
        ci = fam.encode([g]).ci[0]
        if name == "bsr-time":                   # [R, n_act, variable, actuator map, ...]
            assert list(ci[3:9]) == driven
        else:                                    # 3-D sense kernel: the map ends the program
            assert list(ci[-6:]) == driven       # (gpmotion/bsr/sense3d_kernel.py)


@pytest.mark.parametrize("actuation", ["kinematic", "pd"])
def test_undriven_joints_hold_neutral_alike_under_gp_and_bsr(task, actuation):
    driven = task.controlled_actuators()
    held = [a for a in range(task.figure.n_act) if a not in driven]
    neutral = task.figure.model.neutral[held]
    trajs = {}
    for name, (fam, g) in _genomes(task, np.random.default_rng(1)).items():
        ev = InProcessEvaluator(task, fam, actuation)
        trajs[name] = ev.rollout([g])
        assert np.all(trajs[name].targets[0, :, held] == neutral[:, None])
    bsr = trajs["bsr-time"]
    g = _genomes(task, np.random.default_rng(1))["bsr-time"][1]
    assert np.array_equal(bsr.targets[0, 0, driven], g.theta0[0])     # rule 0 drives the arm
    if actuation == "kinematic":           # prescribed joints: the held ones move identically
        dofs = task.figure.model.act_dof[held]
        for name in ("bsr-time", "bsr-sense"):
            assert np.array_equal(trajs[name].qd[0][:, dofs], trajs["gp"].qd[0][:, dofs])
