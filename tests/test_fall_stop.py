"""A task that declares falls final (``Task.fall_stop``) ends a fallen episode at
its fall frame: the rollout simulates no step after it, the frames it records
are the full episode's cut there, and a search takes the same decisions as
with full episodes cut afterwards."""
from dataclasses import replace

import numpy as np
import pytest

import gpmotion.inprocess as inprocess
from gpmotion.families import make_family
from gpmotion.figures import load_figure
from gpmotion.inprocess import InProcessEvaluator
from gpmotion.model import make_scene
from gpmotion.controllers import schedule
from gpmotion.sim.rollout import rollout
from gpmotion.task import get_task
from tests.golden_runs import record
from tests.reference.fall_ref import cut_at_fall

CHANNELS = ("q", "qd", "com", "contact_force", "pole_hit", "impact", "energy", "targets",
            "steps_run", "diverged", "diverged_step")


def _random_lamp_batch(n=40, seed=5):
    task = get_task("lamp_hop", falls_final=1)
    fam = make_family("gp", task)
    rng = np.random.default_rng(seed)
    return task, fam, [fam.random(rng) for _ in range(n)]


def test_a_fallen_episode_is_the_full_episode_cut_at_its_fall_frame():
    task, fam, genomes = _random_lamp_batch()
    ev = InProcessEvaluator(task, fam, threads=2)
    stopped = ev.rollout(genomes)
    opts = {**task.rollout_options(), "stop_pitch": None}
    full = rollout(task.figure, ev.scene(), fam.encode(genomes), **opts, actuation=ev.actuation,
                   default_tau=fam.default_tau)
    cut = cut_at_fall(full, task.fall_stop())
    fell = cut["steps_run"] < task.n_steps
    assert 0 < fell.sum() < len(genomes)                     # some fall, some do not
    for name in CHANNELS:
        np.testing.assert_array_equal(getattr(stopped, name), cut[name], err_msg=name)
    assert stopped.steps_run.sum() < full.steps_run.sum() == len(genomes) * task.n_steps
    np.testing.assert_array_equal(task.score(stopped, 1.0)[0], task.score(replace(full, **cut), 1.0)[0])


def _cut_rollout(steps):
    """inprocess.rollout with full episodes cut afterwards, counting the steps it simulates."""
    def full_then_cut(*args, stop_pitch=None, **kw):
        traj = rollout(*args, **kw)
        steps.append(int(traj.steps_run.sum()))
        return replace(traj, **cut_at_fall(traj, stop_pitch)) if stop_pitch else traj
    return full_then_cut


def _stopped_rollout(steps):
    def stopped(*args, **kw):
        traj = rollout(*args, **kw)
        steps.append(int(traj.steps_run.sum()))
        return traj
    return stopped


def _run(tmp_path, name):
    from gpmotion.cli import main
    out = tmp_path / name
    assert main(["run", "lamp_hop", "--param", "falls_final=1", "--seed", "2", "--generations", "3",
                 "--population", "40", "--out", str(out), "--no-artifacts", "--quiet"]) in (0, None)
    return record(out)


def test_a_search_takes_the_same_decisions_with_episodes_stopped_at_a_fall(tmp_path, monkeypatch):
    full_steps, stopped_steps = [], []
    monkeypatch.setattr(inprocess, "rollout", _cut_rollout(full_steps))
    full = _run(tmp_path, "full")
    monkeypatch.setattr(inprocess, "rollout", _stopped_rollout(stopped_steps))
    stopped = _run(tmp_path, "stopped")
    assert stopped == full                                   # best.json and every log row
    assert len(stopped_steps) == len(full_steps)
    assert sum(stopped_steps) < sum(full_steps)


def test_falls_final_is_off_by_default_and_takes_0_or_1():
    assert get_task("lamp_hop").fall_stop() is None
    assert get_task("lamp_limbo").fall_stop() is None
    assert get_task("lamp_limbo", falls_final=1).fall_stop() == 1.0
    for name in ("lamp_hop", "lamp_limbo"):
        with pytest.raises(ValueError, match="falls_final must be 0 or 1"):
            get_task(name, falls_final=0.5)
    with pytest.raises(ValueError, match="unknown parameter"):     # the 3-D lamp has no such option
        get_task("lamp3d_limbo", falls_final=1)


def test_a_stop_pitch_that_cannot_apply_is_refused():
    with pytest.raises(ValueError, match="planar figure whose base is a hinge"):
        simulate_stopped("cujo")
    with pytest.raises(ValueError, match="positive angle"):
        simulate_stopped("lamp", stop_pitch=0.0)


def simulate_stopped(figure, stop_pitch=1.0):
    """Refused before anything is simulated."""
    fig = load_figure(figure)
    return rollout(fig, make_scene(**fig.ground), schedule.constant(fig.model.neutral),
                   n_steps=20, stop_pitch=stop_pitch)


def test_the_contract_check_refuses_a_3d_task_that_declares_falls_final():
    from gpmotion.check import check_task
    from gpmotion.task import task_class

    class Tilted(task_class("lamp3d_hop")):
        name = "tilted_lamp3d"

        def fall_stop(self):
            return 1.0
    with pytest.raises(ValueError, match="planar figure whose base is a hinge"):
        check_task(Tilted())
